#!/usr/bin/env bash
# End-to-end test of `skinsim wound`: a small run writes the frames of every
# day (base colour, roughness, height, normal, metal-rough, glTF), the contact
# sheet, compare_abrasion.png and timeline.json in the abrasion timeline
# format; the same run on 1 and 2 threads gives the same bytes; --mechanics
# runs; bad inputs
# (days, recipe, skin, table, heal options) exit 2 and write nothing.
# usage: e2e_wound.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"

SMALL="--grid 24x24x8 --size 64 --quiet"

"$CLI" wound --help >"$T/help.txt" || fail "--help exit code"
for w in "--days" "--skin" "--recipe" "base_color" "timeline.json" "compare_abrasion.png" "mm"; do
    grep -q -- "$w" "$T/help.txt" || fail "--help does not mention $w"
done

# --- a small run: every output exists
"$CLI" wound $SMALL --scenario scab --days 0,1,3 --threads 2 --out "$T/a" --json >"$T/a.json" ||
    fail "small run failed"
for d in 0 1 3; do
    for m in base_color roughness height normal metal_rough; do
        png_ok "$T/a/frames/t${d}_$m.png"
    done
    [ -s "$T/a/frames/t$d.gltf" ] || fail "missing t$d.gltf"
done
png_ok "$T/a/contact_sheet.png"
png_ok "$T/a/compare_abrasion.png"
/usr/bin/python3 - "$T/a/timeline.json" "$T/a.json" <<'PY' || fail "timeline.json"
import json, sys
t = json.load(open(sys.argv[1]))
assert t["command"] == "wound" and t["scenario"] == "scab", t
assert [f["day"] for f in t["frames"]] == [0, 1, 3]
for f in t["frames"]:
    for k in ("color", "base_color", "roughness", "height", "normal", "gltf"):
        assert k in f["files"], (k, f)
assert t["height_range_mm"] > 0 and "recipe" in t and "keys" in t
s = json.load(open(sys.argv[2]))
assert s["frames"] == t["frames"]
PY
# the height PNG's range is in each frame's entry and covers the frame (no clipping)
/usr/bin/python3 - "$T/a/timeline.json" <<'PY' || fail "height range"
import json, sys
for f in json.load(open(sys.argv[1]))["frames"]:
    lo, hi = f["height_min_mm"], f["height_max_mm"]
    assert lo <= -2 and hi >= 2 and hi > lo, f
PY
# a skin of another world size than the block is matched, with a warning
"$CLI" skin --size 64 --world-size-cm 5 --quiet --out "$T/skin5" || fail "skin run failed"
"$CLI" wound $SMALL --scenario scab --days 0 --skin "$T/skin5" --no-compare --out "$T/w5" \
    2>"$T/w5.err" || fail "wound on a 5 cm skin failed"
grep -q "warning: --skin .* covers 5 cm but the texture covers" "$T/w5.err" ||
    fail "no warning for a 5 cm skin under the block: $(cat "$T/w5.err")"
grep -q '"warnings":[[:space:]]*\[[[:space:]]*"--skin' "$T/w5/timeline.json" ||
    fail "timeline.json lacks the skin-size warning"
# the glTF references files that exist
grep -q '"t3_base_color.png"' "$T/a/frames/t3.gltf" || fail "glTF does not reference the base colour"
# one thread gives the same pictures as two
"$CLI" wound $SMALL --scenario scab --days 0,1,3 --threads 1 --out "$T/b" || fail "1-thread run failed"
for f in frames/t3_base_color.png frames/t3_height.png frames/t3_normal.png frames/t3_roughness.png contact_sheet.png; do
    cmp -s "$T/a/$f" "$T/b/$f" || fail "$f differs between 1 and 2 threads"
done

# --- with the contraction mechanics coupled
"$CLI" wound --grid 24x24x8 --size 32 --quiet --days 0,2 --mechanics --no-compare --out "$T/m" ||
    fail "--mechanics run failed"
grep -q '"mechanics":[[:space:]]*true' "$T/m/timeline.json" || fail "timeline.json lacks mechanics"
png_ok "$T/m/frames/t2_base_color.png"
[ ! -e "$T/m/compare_abrasion.png" ] || fail "--no-compare wrote compare_abrasion.png"

# --- bad inputs: exit 2, nothing written
echo '{"recipe": {"no_such_key": {"value": 1, "unit": "1"}}}' >"$T/unknown.json"
echo '{"recipe": {"bed_blood": {"value": 0.04}}}' >"$T/nounit.json"
echo 'not a table' >"$T/bad.sstab"
bad_cases=(
    "--days 3,1"
    "--days -1"
    "--days 0.03"
    "--days 1,nan"
    "--size 5"
    "--recipe $T/unknown.json"
    "--recipe $T/nounit.json"
    "--recipe $T/missing.json"
    "--skin $T/missing.exr"
    "--table $T/bad.sstab"
    "--scenario bogus"
    "--size-mm 30,20,4"
    "--stroke $T/missing.csv"
    "--no-such-option"
)
for args in "${bad_cases[@]}"; do
    "$CLI" wound $SMALL $args --out "$T/bad" 2>"$T/err.txt"
    rc=$?
    [ $rc -eq 2 ] || fail "'$args' exited $rc, expected 2"
    [ -s "$T/err.txt" ] || fail "'$args' printed no error message"
    [ ! -e "$T/bad" ] || fail "'$args' left $T/bad behind"
done
echo "e2e_wound: all checks passed"
