#!/usr/bin/env bash
# Minimizes each target's corpus for committing: corpus/TARGET and work/TARGET (new inputs of run.sh) are
# merged by `cargo fuzz cmin` into a fresh corpus/TARGET with only inputs that add coverage. Inputs named
# finding-* (crash reproducers, fixed) are kept whatever cmin thinks of them.
set -euo pipefail
cd "$(dirname "$0")"
for target in "${@:-urdf eval_input}"; do
  for t in $target; do
    case $t in urdf) max_len=32768 ;; eval_input) max_len=8192 ;; esac
    all="work/all-$t"
    rm -rf "$all" && mkdir -p "$all" "work/$t"
    cp corpus/"$t"/* "$all"/
    cp work/"$t"/* "$all"/ 2>/dev/null || true
    mkdir -p work/findings-"$t" && cp corpus/"$t"/finding-* work/findings-"$t"/ 2>/dev/null || true
    nice -n 10 cargo +nightly fuzz cmin --sanitizer none "$t" "$all" -- -max_len="$max_len" -rss_limit_mb=2048 -timeout=10
    rm -rf corpus/"$t" && mkdir -p corpus/"$t"
    cp "$all"/* corpus/"$t"/
    cp work/findings-"$t"/* corpus/"$t"/ 2>/dev/null || true
    echo "$t: $(ls corpus/"$t" | wc -l) files, $(du -sh corpus/"$t" | cut -f1)"
  done
done
