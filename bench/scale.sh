#!/usr/bin/env bash
# Generation at scale: for chains of N revolute bodies (codegen/examples/chain_urdf.rs), the source size,
# time and peak memory of `embedyn generate CHAIN --only aba`, and the time and peak rustc memory of
# `cargo build --release` of the generated crate (GNU time's maximum resident set size, which for cargo is
# that of its largest child, rustc). Prints the Markdown rows of BENCHMARKS.md's scale table.
#
# Usage: bench/scale.sh [N ...]            (default: 10 100 1000)
#        ONLY=crba,minv EXTRA="--scalar f64" bench/scale.sh 100
set -euo pipefail
cd "$(dirname "$0")/.."
only="${ONLY:-aba}"
extra="${EXTRA:-}"
sizes=("$@")
[[ ${#sizes[@]} -gt 0 ]] || sizes=(10 100 1000)
cargo build --release -q -p embedyn-cli --bin embedyn
cargo build --release -q -p embedyn-codegen --example chain_urdf
work=target/scale
mkdir -p "$work"
# Seconds from GNU time's "Elapsed (wall clock)" (h:mm:ss or m:ss), MB from its kilobytes.
elapsed() { sed -n 's/.*Elapsed (wall clock).*: //p' "$1" | awk -F: '{s=0; for(i=1;i<=NF;i++) s=s*60+$i; printf "%.1f", s}'; }
user() { sed -n 's/.*User time (seconds): //p' "$1"; }
peak() { sed -n 's/.*Maximum resident set size (kbytes): //p' "$1" | awk '{printf "%.0f", $1/1024}'; }
echo "machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores, $(rustc --version)" >&2
echo "| N | functions | source bytes per body | generate s | generate MB | cargo build s (user s) | rustc peak MB |"
echo "|---:|---|---:|---:|---:|---:|---:|"
for n in "${sizes[@]}"; do
  target/release/examples/chain_urdf "$n" > "$work/chain$n.urdf"
  out="$work/chain$n"
  rm -rf "$out"
  # shellcheck disable=SC2086
  if ! /usr/bin/time -v target/release/embedyn generate "$work/chain$n.urdf" --out "$out" --only "$only" $extra \
      > /dev/null 2> "$work/generate$n.log"; then
    echo "| $n | $only $extra | refused: $(grep -o 'estimated [0-9.]* [GM]B' "$work/generate$n.log") | | | | |"
    continue
  fi
  bytes=$(wc -c < "$out/src/lib.rs")
  (cd "$out" && /usr/bin/time -v nice -n 10 cargo build --release -q) 2> "$work/build$n.log"
  printf "| %s | %s | %s | %s | %s | %s (%s) | %s |\n" "$n" "$only $extra" "$((bytes / n))" \
    "$(elapsed "$work/generate$n.log")" "$(peak "$work/generate$n.log")" \
    "$(elapsed "$work/build$n.log")" "$(user "$work/build$n.log")" "$(peak "$work/build$n.log")"
done
