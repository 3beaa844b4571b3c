#!/bin/bash
# End-to-end test of the hyperelastic path's contraction course (docs/mech.md,
# "The GOH path in the heal run"): the 13 mm wound on a 20 x 20 x 3 mm block
# (`skinsim heal --grid 40x40x8 --mechanics --mech-model goh --days 14`)
# gapes at day 0, then its edges move at most about 0.6-0.75 mm/day (the
# test: the fastest day between 0.3 and 0.8 mm/day, the outline side taken
# from the square root of its area, halved), the outline ends at least 15 %
# below the cut by day 14, the course is smooth (no day on which the outline
# grows back by more than 0.5 % after the myofibroblasts appear) and runs
# after day 3 (most of the contraction from the gape after day 4).
# usage: e2e_mech_goh_course.sh <skinsim> <source dir>
set -u
CLI=$1
T=$(mktemp -d /tmp/skinsim-e2e-gohc-XXXXXX)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$CLI" heal --grid 40x40x8 --mechanics --mech-model goh --days 14 --quiet --threads 2 \
    --out "$T/run" >"$T/log" 2>&1 || { cat "$T/log" >&2; fail "heal --mech-model goh"; }
python3 - "$T/run/area.csv" <<'PY' || fail "contraction course"
import csv, math, sys
r = list(csv.DictReader(open(sys.argv[1])))
t = [float(x["t_days"]) for x in r]
A = [float(x["outline_area_mm2"]) for x in r]
cut = 169.0  # the 13 x 13 mm wound (2/3 of the 20 mm block, 0.5 mm voxels)
def at(d):
    return A[min(range(len(t)), key=lambda i: abs(t[i] - d))]
day = [(math.sqrt(at(d - 1)) - math.sqrt(at(d))) / 2 for d in range(1, 15)]
vmax = max(day)
print("outline/cut: day 0 %.3f, 4 %.3f, 8 %.3f, 14 %.3f; fastest day %.3f mm/day (day %d)" % (
    at(0) / cut, at(4) / cut, at(8) / cut, at(14) / cut, vmax, 1 + day.index(vmax)))
assert at(0) > 1.1 * cut, "the cut gapes at day 0"
assert 0.3 <= vmax <= 0.8, vmax
assert at(14) <= 0.85 * cut, at(14) / cut
for d in range(4, 15):
    assert at(d) <= 1.005 * at(d - 1), ("grows back", d)
assert at(4) - at(14) > 0.5 * (at(0) - at(14)), "most of the contraction after day 4"
PY
echo "e2e_mech_goh_course: ok"
