#!/usr/bin/env bash
# Builds the Pinocchio peer benchmark (bench/peers/pinocchio_bench.cpp) against the PyPI wheels
# of Pinocchio 4.1.0. Idempotent: pip is skipped when the pinned versions are already installed,
# and the compile is skipped when the binary is newer than the source and this script.
#
# Usage: bench/peers/build_pinocchio.sh [--force]
# Stdout is exactly three KEY=VALUE lines (everything else goes to stderr), so a script can
# `eval "$(bench/peers/build_pinocchio.sh)"`:
#   PINOCCHIO_BENCH=<path of the binary>        (target/peers/pinocchio_bench)
#   PINOCCHIO_PARALLEL=<path of the binary>     (target/peers/pinocchio_parallel: abaInParallel, OpenMP)
#   ERD_ROBOTS=<example-robot-data's robots folder>
#
# Env: PYTHON (default python3), CXX (default g++).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
src="$here/pinocchio_bench.cpp"
out_dir="$root/target/peers"
bin="$out_dir/pinocchio_bench"
PYTHON="${PYTHON:-python3}"
CXX="${CXX:-g++}"
force=0
[[ "${1:-}" == "--force" ]] && force=1

PIN_VERSION=4.1.0
ERD_VERSION=6.0.0

# 1. Python wheels (Pinocchio's headers need Eigen and urdfdom headers, which `pin` does not pull).
have_versions() {
  "$PYTHON" - "$PIN_VERSION" "$ERD_VERSION" <<'EOF' 2>/dev/null
import sys
from importlib.metadata import version, PackageNotFoundError
want_pin, want_erd = sys.argv[1], sys.argv[2]
try:
    ok = (version("pin") == want_pin and version("example-robot-data") == want_erd
          and version("cmeel-eigen") and version("cmeel-urdfdom-headers"))
    import pinocchio  # noqa: F401  (importable, not just listed)
    sys.exit(0 if ok and pinocchio.__version__ == want_pin else 1)
except (PackageNotFoundError, ImportError):
    sys.exit(1)
EOF
}
if have_versions; then
  echo "pin==$PIN_VERSION and example-robot-data==$ERD_VERSION already installed" >&2
else
  echo "installing pin==$PIN_VERSION example-robot-data==$ERD_VERSION cmeel-eigen cmeel-urdfdom-headers" >&2
  "$PYTHON" -m pip install --quiet --disable-pip-version-check \
    "pin==$PIN_VERSION" "example-robot-data==$ERD_VERSION" cmeel-eigen cmeel-urdfdom-headers >&2
  have_versions || { echo "error: pip install did not give the pinned versions" >&2; exit 1; }
fi

# 2. Locate the cmeel prefix (site-packages/cmeel.prefix).
prefix="$("$PYTHON" -c 'import cmeel, os; print(os.path.join(os.path.dirname(os.path.dirname(cmeel.__file__)), "cmeel.prefix"))')"
[[ -d "$prefix/include/pinocchio" ]] || { echo "error: no Pinocchio headers under $prefix" >&2; exit 1; }
robots="$prefix/share/example-robot-data/robots"
[[ -d "$robots" ]] || { echo "error: no example-robot-data robots under $prefix" >&2; exit 1; }

# 3. Compile. The defines are those of the pinocchio::pinocchio_headers CMake target in
# $prefix/lib/cmake/pinocchio/pinocchioTargets.cmake (BOOST_FUSION_INVOKE_MAX_ARITY=12 is needed by
# 4.1's 7-argument joint visitors; without it rnea fails to compile). PINOCCHIO_ENABLE_TEMPLATE_
# INSTANTIATION is deliberately NOT defined: the algorithms are compiled here, header-only, with
# these flags, rather than called in the wheel's prebuilt libpinocchio_default. No -march=native: the prebuilt URDF parser in the wheel is compiled for generic
# x86-64 and Eigen's alignment must match it, or buildModel corrupts the model.
mkdir -p "$out_dir"
# compile SOURCE BINARY [EXTRA FLAGS...]: skipped when the binary is newer than its source and this script.
compile() {
  local source="$1" binary="$2"
  shift 2
  if (( force == 0 )) && [[ -x "$binary" && "$binary" -nt "$source" && "$binary" -nt "${BASH_SOURCE[0]}" ]] \
     && [[ "$(cat "$binary.prefix" 2>/dev/null)" == "$prefix" ]]; then
    echo "up to date: $binary" >&2
    return
  fi
  local cmd=("$CXX" -std=c++17 -O3 -DNDEBUG "$@"
    -I"$prefix/include" -I"$prefix/include/eigen3" -I"$prefix/include/urdfdom_headers"
    -DPINOCCHIO_WITH_URDFDOM
    -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS
    -DBOOST_FUSION_INVOKE_MAX_ARITY=12
    "$source" -o "$binary"
    -L"$prefix/lib" -Wl,-rpath,"$prefix/lib"
    -lpinocchio_parsers -lpinocchio_default -lurdfdom_model -lboost_serialization)
  echo "${cmd[*]}" >&2
  "${cmd[@]}"
  echo "$prefix" > "$binary.prefix"
}
compile "$src" "$bin"
# abaInParallel is OpenMP (gcc's libgomp).
compile "$here/pinocchio_parallel.cpp" "$out_dir/pinocchio_parallel" -fopenmp

echo "PINOCCHIO_BENCH=$bin"
echo "PINOCCHIO_PARALLEL=$out_dir/pinocchio_parallel"
echo "ERD_ROBOTS=$robots"
