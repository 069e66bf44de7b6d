#!/usr/bin/env bash
# Runs the interpreted-solver benchmark (criterion) and Pinocchio 4.1 on the same URDFs in one session,
# then writes the comparison table into BENCHMARKS.md. Usage: bench/compare.sh [--skip-pinocchio]
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p bench/results
echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores" >&2

if [[ "${1:-}" != "--skip-pinocchio" ]]; then
  eval "$(bench/peers/build_pinocchio.sh)"
  # Same URDFs as benches/dynamics.rs (MODELS); solo12 is made free with --floating in both.
  "$PINOCCHIO_BENCH" tests/data/pinocchio/ur5.urdf models/peers/z1.urdf models/arm7.urdf \
    tests/data/pinocchio/panda.urdf models/peers/anymal_b.urdf models/quadruped.urdf models/humanoid34.urdf \
    > bench/results/pinocchio.jsonl
  "$PINOCCHIO_BENCH" --floating tests/data/pinocchio/solo12.urdf \
    | sed 's/"model": "solo12"/"model": "solo12_floating"/' >> bench/results/pinocchio.jsonl
fi
cargo bench --bench dynamics 2>&1 | grep -E "^(aba|rnea|crba|minv)|time:" >&2 || true
python3 bench/make_table.py
