#!/usr/bin/env bash
# Issue 13's floating-base targets in one session: generated `aba`, `rnea`, `crba` (f64, through
# `embedyn bench --floating --json`, which builds and times the generated code in-process) against
# Pinocchio 4.1 (`pinocchio_bench --floating`) on ANYmal B, TALOS reduced and the 29-joint G1, each with a
# free-flyer root; then the table "Floating bases" in BENCHMARKS.md (bench/floating_table.py). The two sides
# alternate ROUNDS times (default 3), so that each round sees one state of the shared machine; the table
# gives the medians over rounds and the median of the rounds' ratios. TALOS and the G1 are read from the
# example-robot-data pip package that build_pinocchio.sh installs (their licences keep them out of the repo).
# Usage: bench/floating.sh [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-3}"
mkdir -p bench/results
eval "$(bench/peers/build_pinocchio.sh)"
cargo build --release -q -p embedyn-cli --bin embedyn
models=(
  "anymal_b models/peers/anymal_b.urdf"
  "talos_reduced $ERD_ROBOTS/talos_data/robots/talos_reduced.urdf"
  "g1_29dof $ERD_ROBOTS/g1_description/urdf/g1_29dof_rev_1_0.urdf"
)
out=bench/results/floating.jsonl
: > "$out"
for r in $(seq 1 "$rounds"); do
  for entry in "${models[@]}"; do
    read -r name path <<< "$entry"
    echo "round $r: $name" >&2
    pin=$("$PINOCCHIO_BENCH" --floating "$path" 2>/dev/null)
    ours=$(target/release/embedyn bench "$path" --floating --json 2>/dev/null)
    echo "{\"round\": $r, \"model\": \"$name\", \"pinocchio\": $pin, \"embedyn\": $ours}" >> "$out"
  done
done
python3 bench/floating_table.py
