#!/bin/bash
# End-to-end test of the hyperelastic tissue (docs/mech.md, "The GOH solver"):
# `skinsim mech stretch` against the closed-form GOH stress (fibres along,
# across and at 30 and 60 degrees to the axis, mu and k2 change it, the
# springs model is far from it, bad input exits 2), and `skinsim heal
# --mechanics --mech-model goh`: a slit across the fibres gapes from
# area.csv's first row, one along them less, stitches across the slit hold
# it, and the springs model shows no gape.
# usage: e2e_mech_goh.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"

st() { # out-file, options...
    local o=$1; shift
    "$CLI" mech stretch --json --threads 2 "$@" >"$T/$o.json" || fail "mech stretch $* failed"
}
st along --stretch 1.1 --axis x --fibres x
st across --stretch 1.1 --axis x --fibres y
st deg30 --stretch 1.1 --axis x --fibres 30
st deg60 --stretch 1.1 --axis x --fibres 60
st mu --stretch 1.1 --axis x --fibres y --param mu=30
st k2 --stretch 1.1 --axis x --fibres x --param k2=10
st zz --stretch 1.1 --axis z --fibres z --tet-size-mm 2
st springs --stretch 1.1 --axis x --fibres x --mech-model springs
st rest --stretch 1 --axis x --fibres 30
python3 - "$T" <<'PY' || fail "stretch figures"
import json, sys
names = ["along", "across", "deg30", "deg60", "mu", "k2", "zz", "springs"]
d = {k: json.load(open(f"{sys.argv[1]}/{k}.json")) for k in names}
for k in ["along", "across", "deg30", "deg60", "mu", "k2", "zz"]:
    s, a = d[k]["stress_kpa"], d[k]["analytic_stress_kpa"]
    assert abs(s - a) <= 1e-6 * abs(a), (k, s, a)
    assert d[k]["converged"] is True, k
assert d["along"]["stress_kpa"] > 5 * d["across"]["stress_kpa"]
# at rest: converged, no stress
r = json.load(open(f"{sys.argv[1]}/rest.json"))
assert r["converged"] is True and abs(r["stress_kpa"]) < 1e-9, r
# oblique fibres: softer as they turn away from the axis, and the block shears (free ends)
s0, s30, s60, s90 = (d[k]["stress_kpa"] for k in ["along", "deg30", "deg60", "across"])
assert s0 > s30 > s60 > s90, (s0, s30, s60, s90)
for k in ["deg30", "deg60"]:
    g, ga = d[k]["shear"][0], d[k]["analytic_shear"][0]
    assert g < -1e-3 and abs(g - ga) < 1e-6, (k, g, ga)
assert d["mu"]["stress_kpa"] > 1.5 * d["across"]["stress_kpa"]
assert d["k2"]["stress_kpa"] > 1.2 * d["along"]["stress_kpa"]
assert abs(d["zz"]["stress_kpa"] - d["along"]["stress_kpa"]) < 1e-6 * d["along"]["stress_kpa"]
assert d["springs"]["stress_kpa"] < 0.5 * d["springs"]["analytic_stress_kpa"]
print("stretch 1.1: along %.3f kPa, 30 deg %.3f, 60 deg %.3f, across %.3f, mu 30 %.3f, "
      "k2 10 %.3f, springs %.3f (GOH %.3f)" % (
    s0, s30, s60, s90, d["mu"]["stress_kpa"], d["k2"]["stress_kpa"],
    d["springs"]["stress_kpa"], d["springs"]["analytic_stress_kpa"]))
PY
bad() {
    "$CLI" mech stretch "$@" >/dev/null 2>"$T/err.txt"
    [ $? -eq 2 ] || fail "mech stretch $* did not exit 2"
}
bad --stretch 1.1 --axis w
bad --axis x
bad --stretch 1.1 --param k1=5
bad --stretch 1.1 --param nope=5
bad --stretch 1.1 --param mu=abc
bad --stretch 1.1 --fibres q
grep -q "k1_goh" <(("$CLI" mech stretch --stretch 1.1 --param k1=5 2>&1)) || fail "k1 error does not name k1_goh"

# slits 2 x 12 mm in a 20 x 20 mm block, 1 mm deep (fibres along x)
printf "0.45,0.2\n0.55,0.2\n0.55,0.8\n0.45,0.8\n" >"$T/across.csv"
printf "0.2,0.45\n0.2,0.55\n0.8,0.55\n0.8,0.45\n" >"$T/along.csv"
printf "x1,y1,z1,x2,y2,z2,remove_day\n" >"$T/sut.csv"
for y in 6.5 8.8 11.1 13.4; do echo "8,$y,2.5,12,$y,2.5,0.08" >>"$T/sut.csv"; done
H="--grid 40x40x8 --mechanics --days 0.1 --threads 2 --quiet"
"$CLI" heal $H --mech-model goh --stroke "$T/across.csv" --out "$T/a" || fail "goh heal across"
"$CLI" heal $H --mech-model goh --stroke "$T/along.csv" --out "$T/b" || fail "goh heal along"
"$CLI" heal $H --mech-model goh --stroke "$T/across.csv" --sutures "$T/sut.csv" --out "$T/s" ||
    fail "goh heal sutured"
"$CLI" heal $H --stroke "$T/across.csv" --out "$T/p" || fail "springs heal across"
python3 - "$T" <<'PY' || fail "gape figures"
import csv, sys
def rows(d):
    r = list(csv.DictReader(open(f"{sys.argv[1]}/{d}/area.csv")))
    return [(float(x["t_days"]), float(x["outline_area_mm2"])) for x in r]
a, b, s, p = rows("a"), rows("b"), rows("s"), rows("p")
cut = 0.1 * 20 * 0.6 * 20  # 2 x 12 mm
ga, gb, gs, gp = a[0][1] / cut, b[0][1] / cut, s[0][1] / cut, p[0][1] / cut
print("day 0 outline / cut: across %.3f, along %.3f, across stitched %.3f, springs %.3f; "
      "stitches out at 0.08: %.3f at day %.2f" % (ga, gb, gs, gp, s[-1][1] / cut, s[-1][0]))
assert ga > 1.2, ga
assert ga - 1 > 2 * (gb - 1), (ga, gb)
assert gs - 1 < 0.5 * (ga - 1), (gs, ga)
assert abs(gp - 1) < 0.02, gp
# the stitches come out at day 0.08: the slit gapes again
assert s[-1][1] / cut > gs + 0.5 * (ga - gs), s[-1]
PY
echo "e2e_mech_goh: ok"
