#!/usr/bin/env bash
# Issue 12's speed targets in one session: Pinocchio 4.1's computeABADerivatives and computeRNEADerivatives
# (bench/peers/pinocchio_bench.cpp --derivatives) and embedyn's generated aba_derivatives and rnea_derivatives
# (benches/derivatives.rs) on the Z1 arm and the floating ANYmal B (and benches/derivatives_large.rs: the floating
# TALOS reduced beside Pinocchio, GRBDA's Mini Cheetah, MIT humanoid leg and six-bar against their own aba), each side from COPIES fresh copies of its
# binary (bench/placement.py), then the table "Derivatives" in BENCHMARKS.md (bench/derivatives_table.py).
# Usage: bench/derivatives.sh [COPIES]
set -euo pipefail
cd "$(dirname "$0")/.."
copies="${1:-5}"
mkdir -p bench/results target
eval "$(bench/peers/build_pinocchio.sh)"
python3 bench/placement.py command "$copies" bench/results/pinocchio_derivatives_z1.jsonl "$PINOCCHIO_BENCH" \
  --derivatives models/peers/z1.urdf
python3 bench/placement.py command "$copies" bench/results/pinocchio_derivatives_anymal.jsonl "$PINOCCHIO_BENCH" \
  --floating --derivatives models/peers/anymal_b.urdf
bin=$(bench/bench_binary.sh derivatives)
python3 bench/placement.py criterion "$bin" "$copies" bench/results/derivatives_copies.json
# The larger robots: TALOS reduced beside Pinocchio, GRBDA's robots against their own aba.
python3 bench/placement.py command "$copies" bench/results/pinocchio_derivatives_talos.jsonl "$PINOCCHIO_BENCH" \
  --floating --derivatives tests/data/erd/talos_reduced.urdf
large=$(bench/bench_binary.sh derivatives_large --features large-benches)
python3 bench/placement.py criterion "$large" "$copies" bench/results/derivatives_large_copies.json
python3 bench/derivatives_table.py
