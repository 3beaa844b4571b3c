#!/usr/bin/env bash
# End-to-end test of `skinsim heal --mechanics` (seed 001 §4.2-5.3): a small
# run writes the mechanics outputs (deformed tet mesh .vtu + .pvd, displacement
# in the grid .vti, velocity top views, area.csv outline and closure shares,
# summary.json "mechanics"); a checkpointed run on one thread resumed to the
# end is byte-identical to an uninterrupted run on two; sutures run; bad
# mechanics inputs exit 2 and leave no output directory.
# usage: e2e_heal_mech.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
count() { ls "$@" 2>/dev/null | wc -l; }

# a 20 x 20 x 4 mm block, 13 mm wound, 1 mm tets
SMALL="--grid 40x40x8 --mechanics --snapshot-every 0.5 --quiet"

"$CLI" heal --help | grep -q -- "--mechanics" || fail "--help does not mention --mechanics"

# --- full run on 2 threads
"$CLI" heal $SMALL --days 1 --threads 2 --out "$T/a" --json >"$T/a.json" || fail "mechanics run failed"
for f in fields/mesh.pvd fields/mesh_0000.vtu fields/mesh_0002.vtu surface/velocity_0002.png; do
    [ -s "$T/a/$f" ] || fail "missing $f"
done
png_ok "$T/a/surface/velocity_0002.png"
[ "$(grep -c '<DataSet timestep=' "$T/a/fields/mesh.pvd")" -eq 3 ] || fail "mesh.pvd does not list 3 meshes"
for a in displacement velocity stress; do
    grep -q "Name=\"$a\"" "$T/a/fields/mesh_0002.vtu" || fail "mesh .vtu lacks $a"
done
grep -q 'Name="displacement"' "$T/a/fields/fields_0002.vti" || fail ".vti lacks the displacement"
grep -q 'Name="velocity"' "$T/a/fields/fields_0002.vti" || fail ".vti lacks the velocity"
head -1 "$T/a/area.csv" | grep -q ',outline_area_mm2,contraction,closure_share_contraction,closure_share_epithelialisation,myofibroblast_fraction$' ||
    fail "area.csv lacks the mechanics columns"
python3 - "$T/a.json" "$T/a/area.csv" <<'PY' || fail "summary/area values"
import csv, json, sys
s = json.load(open(sys.argv[1]))["mechanics"]
for k in ("contraction_percent", "aspect_ratio_y_over_x", "principal_direction", "closure_share_contraction", "tets"):
    assert k in s, k
assert s["tets"] > 1000
rows = list(csv.DictReader(open(sys.argv[2])))
o = [float(r["outline_area_mm2"]) for r in rows]
assert o[-1] < o[0], "the outline did not shrink"
assert 0 < s["contraction_percent"] < 90
PY

# --- checkpoint at day 0.5 on 1 thread, resume to day 1: same bytes as run a
"$CLI" heal $SMALL --days 0.5 --threads 1 --checkpoint-every 0.5 --out "$T/b" || fail "checkpointed run failed"
"$CLI" heal --resume "$T/b" --days 1 --threads 1 --quiet || fail "resume failed"
for f in fields/fields_0002.vti fields/mesh_0002.vtu area.csv; do
    cmp -s "$T/a/$f" "$T/b/$f" || fail "resumed $f differs from the uninterrupted run"
done

# --- the explicit scheme: the grid velocity is capped at its CFL limit
# (left out of sanitizer runs, SKINSIM_TEST_QUICK, for time)
if [ -z "${SKINSIM_TEST_QUICK:-}" ]; then
    "$CLI" heal $SMALL --scheme explicit --days 0.3 --threads 2 --out "$T/x" || fail "explicit run failed"
fi

# --- sutures: one stitch across the wound, taken out at day 0.5
printf 'x1,y1,z1,x2,y2,z2,remove_day\n6,10,3,14,10,3,0.5\n' >"$T/s.csv"
"$CLI" heal $SMALL --days 0.2 --threads 2 --sutures "$T/s.csv" --out "$T/s" --json >"$T/s.json" ||
    fail "sutured run failed"
grep -q '"sutures":[[:space:]]*1' "$T/s.json" || fail "summary does not count the stitch"

# --- bad input: exit 2, nothing written
bad() {
    rm -rf "$T/bad"
    "$CLI" heal --grid 40x40x8 --days 0.1 --quiet --out "$T/bad" "$@" 2>"$T/err.txt"
    [ $? -eq 2 ] || fail "exit code for: $*"
    [ ! -e "$T/bad" ] || fail "output written for: $*"
    [ -s "$T/err.txt" ] || fail "no message for: $*"
}
bad --mechanics --fibres 0,0,0
bad --mechanics --fibres 1,0,0:-3,0,0
bad --mechanics --fibres 1,0
bad --mechanics --kappa 0.5
bad --fibres 1,0,0
bad --mechanics --tet-size-mm -1
printf '1,1,1,100,100,100\n' >"$T/far.csv"
bad --mechanics --sutures "$T/far.csv"
grep -q "outside" "$T/err.txt" || fail "suture message does not say outside"
bad --mechanics --sutures "$T/missing.csv"
printf 'garbage\n' >"$T/m.msh"
bad --mechanics --tet-mesh "$T/m.msh"
printf '{"mechanics": {"K_act": {"value": 1}}}\n' >"$T/p.json"
bad --mechanics --params "$T/p.json"
grep -q "unit" "$T/err.txt" || fail "parameter message does not ask for the unit"
echo "e2e_heal_mech: ok"
