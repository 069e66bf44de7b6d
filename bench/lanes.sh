#!/usr/bin/env bash
# Issue 13's many-states-per-call targets in one session: Pinocchio 4.1's single-state aba, rnea and crba
# (bench/peers/pinocchio_bench.cpp), its OpenMP abaInParallel over a batch (bench/peers/pinocchio_parallel.cpp)
# and embedyn's generated scalar and lane functions (benches/lanes.rs),
# built twice: for the baseline x86-64 target (timed as it runs, with the twins the CPU allows, with its AVX
# twins instead of the AVX-512 ones, and with its SSE2 copies alone) and with -C target-cpu=native (the host's widest SIMD). Each binary runs from COPIES fresh copies (bench/placement.py); then the table "Many states per
# call" in BENCHMARKS.md (bench/lanes_table.py).
# Usage: bench/lanes.sh [COPIES]
set -euo pipefail
cd "$(dirname "$0")/.."
copies="${1:-3}"
mkdir -p bench/results target
eval "$(bench/peers/build_pinocchio.sh)"
python3 bench/placement.py command "$copies" bench/results/pinocchio_lanes_z1.jsonl "$PINOCCHIO_BENCH" \
  --derivatives models/peers/z1.urdf
python3 bench/placement.py command "$copies" bench/results/pinocchio_lanes_anymal.jsonl "$PINOCCHIO_BENCH" \
  --floating --derivatives models/peers/anymal_b.urdf
# Pinocchio's OpenMP abaInParallel over 1024 states, 1 and 2 threads.
python3 bench/placement.py command "$copies" bench/results/pinocchio_parallel_z1.jsonl "$PINOCCHIO_PARALLEL" \
  --states 1024 models/peers/z1.urdf
python3 bench/placement.py command "$copies" bench/results/pinocchio_parallel_anymal.jsonl "$PINOCCHIO_PARALLEL" \
  --states 1024 --floating models/peers/anymal_b.urdf
# The bench binary of one build: `lanes_binary TARGET_DIR RUSTFLAGS`.
lanes_binary() {
  CARGO_TARGET_DIR="$1" RUSTFLAGS="$2" bench/bench_binary.sh lanes
}
baseline=$(lanes_binary target "")
python3 bench/placement.py criterion "$baseline" "$copies" bench/results/lanes_baseline.json
# The same binary with its AVX twins instead of the AVX-512 ones: `use_avx512(false)`.
EMBEDYN_AVX_TWINS_ONLY=1 python3 bench/placement.py criterion "$baseline" "$copies" \
  bench/results/lanes_avx_twins.json
# The same binary with its baseline (SSE2) copies alone: `use_avx(false)`.
EMBEDYN_BASELINE_COPIES=1 python3 bench/placement.py criterion "$baseline" "$copies" \
  bench/results/lanes_baseline_copies.json
native=$(lanes_binary target/native "-C target-cpu=native")
python3 bench/placement.py criterion "$native" "$copies" bench/results/lanes_native.json
python3 bench/lanes_table.py
