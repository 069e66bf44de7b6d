#!/usr/bin/env bash
# Issue 13's third item: source size and release compile time of the standalone crate `embedyn generate`
# writes with the default functions (kinematics, aba, rnea, crba; f64 and f32), against the robot's DoF.
# Robots: the bundled z1 and the floating ANYmal B, and from example-robot-data (the pip package that
# bench/peers/build_pinocchio.sh installs) go2, solo12, g1_29dof and talos_reduced, all floating but z1.
# Each crate is built from scratch (its own target folder, dependencies built first and not timed: only the
# crate's own `cargo build --release` after `cargo build --release` of an empty twin is the time of the
# generated code), wall and user seconds from GNU time, on this machine's cores.
# Writes bench/results/compile_time.jsonl and the table "Compile time against model size" in BENCHMARKS.md
# (bench/compile_time_table.py). Usage: bench/compile_time.sh
set -euo pipefail
cd "$(dirname "$0")/.."
eval "$(bench/peers/build_pinocchio.sh)"
cargo build --release -p embedyn-cli >&2
embedyn=target/release/embedyn
work=target/compile-time
rm -rf "$work"
mkdir -p "$work" bench/results
out=bench/results/compile_time.jsonl
: > "$out"
robots=(
  "z1 models/peers/z1.urdf"
  "anymal_b --floating models/peers/anymal_b.urdf"
  "go2 --floating $ERD_ROBOTS/go2_description/urdf/go2.urdf"
  "solo12 --floating $ERD_ROBOTS/solo_description/robots/solo12.urdf"
  "g1_29dof --floating $ERD_ROBOTS/g1_description/urdf/g1_29dof_rev_1_0.urdf"
  "talos_reduced --floating $ERD_ROBOTS/talos_data/robots/talos_reduced.urdf"
)
for entry in "${robots[@]}"; do
  read -r name rest <<< "$entry"
  dir="$work/$name"
  # shellcheck disable=SC2086
  "$embedyn" generate $rest --out "$dir" > "$dir.json" 2> "$dir.log"
  # Dependencies (libm) first, so that the timed build is the generated crate alone.
  (cd "$dir" && cargo fetch -q && cargo build --release -q -p libm 2> /dev/null || true)
  /usr/bin/time -f "%e %U %M" -o "$dir.time" bash -c "cd '$dir' && cargo build --release -q"
  read -r wall user rss < "$dir.time"
  bytes=$(stat -c %s "$dir/src/lib.rs")
  # shellcheck disable=SC2086
  info=$("$embedyn" info $rest 2> /dev/null)
  python3 - "$name" "$wall" "$user" "$rss" "$bytes" "$info" >> "$out" <<'PY'
import json, sys
name, wall, user, rss, size, info = sys.argv[1:7]
info = json.loads(info)
print(json.dumps({"model": name, "nq": info.get("nq"), "nv": info.get("nv"), "source_bytes": int(size),
                  "wall_s": float(wall), "user_s": float(user), "rustc_peak_mb": int(rss) // 1024}))
PY
  tail -1 "$out" >&2
done
python3 bench/compile_time_table.py
