#!/usr/bin/env bash
# Writes the seed corpora (corpus/*/seed-*) from the repository's models: every small URDF as it is, and for
# each bundled model of the `eval_input` target a consistent state (`embedyn complete` solves the loops)
# under every selector. Needs the `embedyn` binary (cargo build -p embedyn-codegen) and jq. Rerun after
# adding models; `cargo fuzz cmin` then keeps what adds coverage.
set -euo pipefail
cd "$(dirname "$0")/.."
EMBEDYN=${EMBEDYN:-target/debug/embedyn}
mkdir -p fuzz/corpus/urdf fuzz/corpus/eval_input

# URDF seeds: the repository's models up to 32 KB (the fuzzing runs use -max_len=32768).
find models tests/data -name '*.urdf' -size -32k | sort | while read -r f; do
  cp "$f" "fuzz/corpus/urdf/seed-$(echo "$f" | tr '/' '_')"
done

# eval_input seeds: selector byte = model + 6·command + 42·floating (fuzz/harness.rs, eval_selection).
models=(models/arm7.urdf models/quadruped.urdf models/loops/four_bar_internal.urdf
        models/loops/geared_motor.urdf models/loops/differential_wrist.urdf
        tests/data/scenes/two_free_bodies.urdf)
sample_for() { # model floating -> one sample with q, v, tau, qdd (loops solved by `complete`)
  local model=$1 floating=$2 flag=()
  [ "$floating" = 1 ] && flag=(--floating)
  local info; info=$("$EMBEDYN" info "$model" "${flag[@]}" 2>/dev/null) || return 1
  local guess; guess=$(jq -c '
    def vals(n; s): [range(n)] | map(((. * 0.37 + s) | sin) * 0.5);
    {q: ([.joints[] | if .type == "floating" then [0.1, -0.2, 0.3, 0, 0, 0, 1]
                      else [0.2] end] | add),
     v: vals(.nv; 1.3)}' <<<"$info")
  local done
  done=$("$EMBEDYN" complete "$model" "${flag[@]}" <<<"{\"samples\": [$guess]}" 2>/dev/null \
         | jq -c '.samples[0] | {q, v}') || done=$guess
  jq -c --argjson nv "$(jq .nv <<<"$info")" \
    '. + {tau: [range($nv)] | map(. * 0.5 - 1), qdd: [range($nv)] | map(. * 0.25)}' <<<"$done"
}
for m in "${!models[@]}"; do
  for floating in 0 1; do
    sample=$(sample_for "${models[$m]}" "$floating") || continue
    for c in 0 1 2 3 4 5 6; do
      selector=$((m + 6 * c + 42 * floating))
      out="fuzz/corpus/eval_input/seed-m${m}-c${c}-f${floating}"
      { printf "\\x$(printf %02x "$selector")"; printf '{"samples": [%s]}' "$sample"; } >"$out"
    done
  done
done
