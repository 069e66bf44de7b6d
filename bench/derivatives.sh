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
if ! cargo bench --bench derivatives --no-run --message-format=json > target/cargo_bench_derivatives.json 2> target/cargo_bench_derivatives.log; then
  tail -20 target/cargo_bench_derivatives.log >&2
  echo "cargo bench failed (log: target/cargo_bench_derivatives.log); BENCHMARKS.md not updated" >&2
  exit 1
fi
bin=$(python3 -c 'import json,sys
for line in open(sys.argv[1]):
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("target", {}).get("name") == "derivatives" and m.get("executable"):
        print(m["executable"])' target/cargo_bench_derivatives.json)
python3 bench/placement.py criterion "$bin" "$copies" bench/results/derivatives_copies.json
# The larger robots: TALOS reduced beside Pinocchio, GRBDA's robots against their own aba.
python3 bench/placement.py command "$copies" bench/results/pinocchio_derivatives_talos.jsonl "$PINOCCHIO_BENCH" \
  --floating --derivatives tests/data/erd/talos_reduced.urdf
if ! cargo bench --features large-benches --bench derivatives_large --no-run --message-format=json \
    > target/cargo_bench_derivatives_large.json 2> target/cargo_bench_derivatives_large.log; then
  tail -20 target/cargo_bench_derivatives_large.log >&2
  echo "cargo bench failed (log: target/cargo_bench_derivatives_large.log); BENCHMARKS.md not updated" >&2
  exit 1
fi
large=$(python3 -c 'import json,sys
for line in open(sys.argv[1]):
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("target", {}).get("name") == "derivatives_large" and m.get("executable"):
        print(m["executable"])' target/cargo_bench_derivatives_large.json)
python3 bench/placement.py criterion "$large" "$copies" bench/results/derivatives_large_copies.json
python3 bench/derivatives_table.py
