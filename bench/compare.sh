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
  # The floating-base humanoid, read from the pip package (its licence keeps it out of the repo).
  TALOS="$ERD_ROBOTS/talos_data/robots/talos_reduced.urdf"
  if [[ -f "$TALOS" ]]; then
    "$PINOCCHIO_BENCH" --floating "$TALOS" | sed 's/"model": "talos_reduced"/"model": "talos_reduced_floating"/' >> bench/results/pinocchio.jsonl
    cargo run --release -q -p embedyn-cli --bin embedyn -- bench "$TALOS" --floating --json > bench/results/talos_embedyn.json 2>/dev/null || true
  fi
fi
# Generated code on GRBDA's own URDF+ files (the models of the constraint-embedding table), through the CLI.
: > bench/results/loops_embedyn.jsonl
for m in four_bar six_bar revolute_rotor_chain mini_cheetah mit_humanoid jvrc1_humanoid; do
  out=$(cargo run --release -q -p embedyn-cli --bin embedyn -- bench "tests/data/grbda/$m.urdf" --json 2>/dev/null)
  echo "{\"model\": \"$m\", \"bench\": $out}" >> bench/results/loops_embedyn.jsonl
done
# The whole log is kept: a benchmark that panics must stop the script, not leave stale rows in the table.
mkdir -p target
if ! cargo bench --bench dynamics > target/cargo_bench.log 2>&1; then
  tail -20 target/cargo_bench.log >&2
  echo "cargo bench failed (log: target/cargo_bench.log); BENCHMARKS.md not updated" >&2
  exit 1
fi
grep -E "^(aba|rnea|crba|minv)|time:" target/cargo_bench.log >&2 || true
python3 bench/make_table.py
