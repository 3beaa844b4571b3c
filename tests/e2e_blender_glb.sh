#!/usr/bin/env bash
# End-to-end: the skin-surface .glb of `skinsim heal --mesh` (a wound on the
# hand, with the mechanics) imported by the distribution's Blender, headless
# (tests/blender_glb_check.py): vertex colours, the displacement shape key,
# the extras, and on Blender >= 3.5 the _ field attributes. Runs with `make
# test-blender` (SKINSIM_TEST_BLENDER=1); skipped (77) in the ordinary suite,
# where Blender may be missing, or without the hand mesh.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$(cd "$2" && pwd)"
[ "${SKINSIM_TEST_BLENDER:-0}" = 1 ] || { echo "SKIP: run with make test-blender"; exit 77; }
command -v blender >/dev/null || { echo "SKIP: blender is not installed"; exit 77; }
HAND="$SRC/data/meshes/generic-hand-left.glb"
[ -f "$HAND" ] || { echo "SKIP: no hand mesh"; exit 77; }
python3 "$SRC/tests/strokes_ellipse.py" 0.2 0.62 0.02 0.014 >"$T/cut.csv"
# myofibroblasts pull at once (no differentiation delay), so day 0.2 is deformed
printf '{"mechanics": {"tau_myo": {"value": 0, "unit": "day", "source": "e2e"}, "tau_remodel": {"value": 0, "unit": "day", "source": "e2e"}}}\n' >"$T/pull.json"
"$CLI" heal --mesh "$HAND" --wound-uv "$T/cut.csv" --voxel-mm 1 --mechanics --days 0.2 \
    --params "$T/pull.json" --snapshot-every 0 --quiet --out "$T/run" || { echo "FAIL: heal run"; exit 1; }
unset LD_PRELOAD
for snap in "0000 0" "0001 0.2"; do
    set -- $snap
    blender -b --factory-startup --python-exit-code 1 --python "$SRC/tests/blender_glb_check.py" \
        -- "$T/run/surface/skin_$1.glb" "$2" >"$T/bl.txt" 2>&1
    rc=$?
    grep -E "blender|shape key|drops|Error|assert" "$T/bl.txt"
    [ $rc -eq 0 ] || { echo "FAIL: blender check of skin_$1.glb"; tail -20 "$T/bl.txt"; exit 1; }
done
echo "e2e_blender_glb: OK"
