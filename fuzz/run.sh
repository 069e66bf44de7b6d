#!/usr/bin/env bash
# One fuzzing run of one target, the way fuzz/README.md documents it:
#   fuzz/run.sh TARGET SECONDS
# Nice'd, one process (-workers=1), no sanitizer (safe Rust: panics, aborts, timeouts and out-of-memory
# are what is looked for; debug assertions and overflow checks stay on). New inputs go to work/TARGET,
# seeded from the committed corpus; crashes to artifacts/TARGET. Afterwards `cargo +nightly fuzz cmin`
# (README.md) merges what is new into corpus/TARGET.
set -euo pipefail
cd "$(dirname "$0")"
target=${1:?target: urdf or eval_input}
seconds=${2:-3600}
case $target in
  urdf) dict=urdf.dict; max_len=32768 ;;
  eval_input) dict=eval.dict; max_len=8192 ;;
  *) echo "unknown target $target" >&2; exit 2 ;;
esac
mkdir -p "work/$target"
exec nice -n 10 cargo +nightly fuzz run --sanitizer none "$target" "work/$target" "corpus/$target" -- \
  -dict="$dict" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 -workers=1 \
  -max_total_time="$seconds" -print_final_stats=1
