#!/usr/bin/env bash
# End-to-end: `skinsim optics match` as an artist would use it: the two skin
# patches of the ColorChecker (commonly published sRGB values) matched with
# the shipped table and transport refinement within Delta-E00 <= 3 (colour
# with the surface reflectance included, --geometry sce without), JSON
# shape, the same answer for 1 and 2 threads, --lab input, and bad input
# (exit 2 with an error naming it).
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$2"
[ -f "$SRC/data/modelmatch_default.sstab" ] || fail "data/modelmatch_default.sstab is missing"

"$CLI" optics match --help >"$T/h.txt" || fail "match --help"
grep -q "usage: skinsim optics match" "$T/h.txt" || fail "match help text"

PH=20000
[ -n "${SKINSIM_TEST_QUICK:-}" ] && PH=8000
check() { # name, srgb, maximum Delta-E00
  "$CLI" optics match --srgb "$2" --photons $PH --json --threads 2 >"$T/$1.json" \
    || fail "match $1"
  python3 - "$T/$1.json" "$1" "$3" <<'PY' || fail "match $1 result"
import json, sys
d = json.load(open(sys.argv[1]))
for k in ("target_lab", "bio", "albedo_rgb", "lab", "delta_e00", "table_delta_e00", "refined",
          "prior_penalty", "unique", "alternative"):
    assert k in d, k
b = d["bio"]
print("%s: melanin %.4f pheomelanin %.3f blood %.4f oxygenation %.3f SC %.4f epi %.4f -> "
      "Lab %.2f %.2f %.2f, dE00 %.3f (table %.3f)" % (sys.argv[2], b["melanin"],
      b["pheomelanin_ratio"], b["blood"], b["oxygenation"], b["sc_thickness_cm"],
      b["epidermis_thickness_cm"], *d["lab"], d["delta_e00"], d["table_delta_e00"]))
assert d["refined"] is True
assert d["delta_e00"] <= float(sys.argv[3]), d["delta_e00"]
PY
}
# both patches: the issue's target, Delta-E00 <= 3, in the default geometry
# (SCI: albedo + surface reflectance, as measured colours are; the albedo
# alone, SCE, reaches the dark patch only at the ends of three axes,
# docs/validation.md).
check light-skin 194,150,130 3
check dark-skin 115,82,68 3
python3 -c "
import json; d=json.load(open('$T/dark-skin.json'))
assert d['geometry'] == 'sci' and 0.02 < d['surface'] < 0.03, d" || fail "SCI surface reflectance"
"$CLI" optics match --srgb 115,82,68 --geometry sce --table-only --json >"$T/sce.json" \
  || fail "match --geometry sce"
python3 -c "
import json; d=json.load(open('$T/sce.json'))
assert d['geometry'] == 'sce' and d['surface'] == 0.0, d" || fail "SCE has no surface term"
# plausible biology among fits (issue: with --geometry sce the light-skin
# patch came back as pheomelanin 1): the population prior keeps the
# pheomelanin share near its measured 0.26, reports its penalty and whether
# another biology far away also fits
"$CLI" optics match --srgb 194,150,130 --geometry sce --photons $PH --json --threads 2 \
  >"$T/sce-light.json" || fail "match light-skin --geometry sce"
python3 -c "
import json; d=json.load(open('$T/sce-light.json'))
assert d['delta_e00'] <= 1.0, d
assert d['bio']['pheomelanin_ratio'] < 0.45 and d['bio']['melanin'] < 0.05, d['bio']
assert 0.0 <= d['prior_penalty'] < 1.0, d
a = d['alternative']
assert isinstance(d['unique'], bool) and d['unique'] == (a['distance'] <= 0.25), d
assert a['delta_e00_table'] <= d['delta_e00'] + 1.0 + 1e-4, a" \
  || fail "light-skin --geometry sce: implausible biology or no prior report"
# the dark patch needs more melanin than the light one
python3 -c "
import json; a=json.load(open('$T/light-skin.json')); b=json.load(open('$T/dark-skin.json'))
assert b['bio']['melanin'] > a['bio']['melanin']" || fail "dark patch not darker in melanin"

# same answer on one thread
"$CLI" optics match --srgb 115,82,68 --photons $PH --json --threads 1 >"$T/d1.json" || fail "1 thread"
cmp -s "$T/d1.json" "$T/dark-skin.json" || fail "match differs between 1 and 2 threads"

# L*a*b* input and the table-only stage
"$CLI" optics match --lab 60,12,18 --table-only >"$T/l.txt" || fail "match --lab"
grep -q "Delta-E00" "$T/l.txt" || fail "match text output"

exits2 "$CLI" optics match
exits2 "$CLI" optics match --srgb 1,2
exits2 "$CLI" optics match --srgb 300,2,3
exits2 "$CLI" optics match --srgb 1,2,nan
exits2 "$CLI" optics match --lab 120,0,0
exits2 "$CLI" optics match --srgb 1,2,3 --lab 50,0,0
exits2 "$CLI" optics match --srgb 1,2,3 --table "$T/none.sstab"
echo "garbage" >"$T/bad.sstab"
exits2 "$CLI" optics match --srgb 1,2,3 --table "$T/bad.sstab"
exits2 "$CLI" optics match --srgb 1,2,3 --photons 5
exits2 "$CLI" optics match --srgb 1,2,3 --geometry 45/0
exits2 "$CLI" optics match --srgb 1,2,3 --geometry
echo "e2e_optics_match: ok"
