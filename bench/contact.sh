#!/usr/bin/env bash
# Issue 11's speed targets in one session: Pinocchio 4.1 (frame Jacobian + classical acceleration, centre of
# mass Jacobian, ccrba, dccrba, aba with four foot wrenches) and embedyn's generated code (benches/contact.rs)
# on the floating ANYmal B, then the table "Contacts, frames and momentum" in BENCHMARKS.md
# (bench/contact_table.py). Each side runs from COPIES fresh copies of its binary (default 5), interleaved
# (one of Pinocchio's, then one of ours), and the table gives the medians and the median of the pairs' ratios:
# see bench/placement.py for why. Usage: bench/contact.sh [COPIES]
set -euo pipefail
cd "$(dirname "$0")/.."
copies="${1:-5}"
mkdir -p bench/results target
eval "$(bench/peers/build_pinocchio.sh)"
bin=$(bench/bench_binary.sh contact)
# Interleaved: a copy of Pinocchio's binary, then a copy of ours, COPIES times (bench/placement.py pairs).
python3 bench/placement.py pairs "$copies" bench/results/pinocchio_contact.jsonl bench/results/contact_copies.json \
  "$bin" -- "$PINOCCHIO_BENCH" \
  --floating --frame LF_FOOT --wrenches LF_FOOT,RF_FOOT,LH_FOOT,RH_FOOT models/peers/anymal_b.urdf
sed -i 's/"model": "anymal_b"/"model": "anymal_b_floating"/g' bench/results/pinocchio_contact.jsonl
python3 bench/contact_table.py
