#!/usr/bin/env bash
# End-to-end: the Blender add-on (integrations/blender) headless with the
# distribution's Blender: registers, builds the time-driven material on the
# hand mesh, renders frames with Cycles on the CPU and compares them
# (integrations/blender/tests/test_addon.py). Runs with `make test-blender`
# (SKINSIM_TEST_BLENDER=1), which installs Blender first; skipped (77) in
# the ordinary suite, where Blender cannot start, or without the hand mesh.
# Renders stay in <build>/blender-test/ to look at (compare.png).
set -u
CLI="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
SRC="$(cd "$2" && pwd)"
BUILD="$(dirname "$CLI")"
[ "${SKINSIM_TEST_BLENDER:-0}" = 1 ] || { echo "SKIP: run with make test-blender"; exit 77; }
command -v blender >/dev/null || { echo "SKIP: blender is not installed"; exit 77; }
blender -b --factory-startup --python-expr "import bpy" >/dev/null 2>&1 \
  || { echo "SKIP: blender cannot start here"; exit 77; }
MESH="${SKINSIM_TEST_MESH:-}"
for m in "$SRC/data/meshes/generic-hand-left.glb"; do
  [ -z "$MESH" ] && [ -f "$m" ] && MESH="$m"
done
[ -n "$MESH" ] && [ -f "$MESH" ] || { echo "SKIP: hand mesh not found (set SKINSIM_TEST_MESH)"; exit 77; }
OUT="$BUILD/blender-test"
rm -rf "$OUT"
mkdir -p "$OUT"
# a sanitizer build's command needs no special care (it runs as a child
# process); Blender itself must not inherit a preload
unset LD_PRELOAD
blender -b --factory-startup --python-exit-code 1 \
  --python "$SRC/integrations/blender/tests/test_addon.py" -- "$SRC" "$CLI" "$OUT" "$MESH" 2>&1 \
  | grep -v '^Fra:' | grep -v '^$'
rc=${PIPESTATUS[0]}
[ $rc -eq 0 ] || { echo "FAIL: blender exited $rc"; exit 1; }
[ -s "$OUT/compare.png" ] || { echo "FAIL: no $OUT/compare.png"; exit 1; }
echo "PASS: look at $OUT/compare.png"
