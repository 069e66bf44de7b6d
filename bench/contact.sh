#!/usr/bin/env bash
# Issue 11's speed targets in one session: Pinocchio 4.1 (frame Jacobian + classical acceleration, centre of
# mass Jacobian, ccrba, dccrba, aba with four foot wrenches) and embedyn's generated code (benches/contact.rs)
# on the floating ANYmal B, then the table "Contacts, frames and momentum" in BENCHMARKS.md
# (bench/contact_table.py). Usage: bench/contact.sh
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p bench/results target
eval "$(bench/peers/build_pinocchio.sh)"
"$PINOCCHIO_BENCH" --floating --frame LF_FOOT --wrenches LF_FOOT,RF_FOOT,LH_FOOT,RH_FOOT models/peers/anymal_b.urdf \
  | sed 's/"model": "anymal_b"/"model": "anymal_b_floating"/' > bench/results/pinocchio_contact.jsonl
if ! cargo bench --bench contact > target/cargo_bench_contact.log 2>&1; then
  tail -20 target/cargo_bench_contact.log >&2
  echo "cargo bench failed (log: target/cargo_bench_contact.log); BENCHMARKS.md not updated" >&2
  exit 1
fi
grep -E "^gen|time:" target/cargo_bench_contact.log >&2 || true
python3 bench/contact_table.py
