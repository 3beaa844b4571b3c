#!/usr/bin/env bash
# End-to-end: the skinsim Python package (integrations/python) over the
# shared library of this build, with Debian's python3 and python3-numpy:
# the unit tests in integrations/python/tests, including the check that the
# ctypes struct mirrors have the C compiler's sizes and offsets.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$(cd "$2" && pwd)"
BUILD="$(dirname "$CLI")"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=$(command -v python3)
"$PY" -c "import numpy" 2>/dev/null || { echo "SKIP: $PY has no numpy (apt-get install python3-numpy)"; exit 77; }
[ -e "$BUILD/libskinsim.so.0" ] || { echo "FAIL: no $BUILD/libskinsim.so.0"; exit 1; }
cc -std=c17 -I"$SRC/include" "$SRC/integrations/python/tests/abi_layout.c" -o "$T/abi_layout" \
  || { echo "FAIL: abi_layout.c"; exit 1; }
"$T/abi_layout" >"$T/layout.txt" || exit 1
export SKINSIM_ABI_LAYOUT="$T/layout.txt" SKINSIM_LIB="$BUILD/libskinsim.so.0" SKINSIM_CLI="$CLI"
export PYTHONPATH="$SRC/integrations/python" PYTHONDONTWRITEBYTECODE=1 SKINSIM_THREADS="${SKINSIM_THREADS:-2}"
# a sanitizer build of the library needs its runtime loaded first
if readelf -d "$BUILD/libskinsim.so.0" | grep -q 'libasan'; then
  export LD_PRELOAD="$(cc -print-file-name=libasan.so) $(cc -print-file-name=libubsan.so)"
  export ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
  ASAN_OPTIONS="${ASAN_OPTIONS//detect_leaks=1/detect_leaks=0}"
fi
cd "$T" && "$PY" -m unittest discover -s "$SRC/integrations/python/tests" -p 'test_*.py' -v 2>&1
