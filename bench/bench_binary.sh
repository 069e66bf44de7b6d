#!/usr/bin/env bash
# Builds one criterion bench without running it and prints its executable's path (the bench/*.sh scripts
# then run it from fresh copies, bench/placement.py). The build's environment (CARGO_TARGET_DIR,
# RUSTFLAGS) is the caller's. On a failed build: the log's tail on stderr, exit 1.
# Usage: bench/bench_binary.sh NAME [CARGO BENCH ARGS...]   e.g. bench/bench_binary.sh derivatives_large --features large-benches
set -euo pipefail
cd "$(dirname "$0")/.."
name="$1"
shift
mkdir -p target
json="target/cargo_bench_$name.json"
log="target/cargo_bench_$name.log"
if ! cargo bench "$@" --bench "$name" --no-run --message-format=json > "$json" 2> "$log"; then
  tail -20 "$log" >&2
  echo "cargo bench --bench $name failed (log: $log); BENCHMARKS.md not updated" >&2
  exit 1
fi
python3 - "$json" "$name" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("target", {}).get("name") == sys.argv[2] and m.get("executable"):
        print(m["executable"])
PY
