#!/bin/bash
# End-to-end test of the hyperelastic path's contraction course (docs/mech.md,
# "The GOH path in the heal run"): the 13 mm wound on a 20 x 20 x 3 mm block
# (`skinsim heal --grid 40x40x8 --mechanics --mech-model goh --days 14`)
# gapes at day 0, then its edges move at most about 0.75 mm/day (the
# fastest day between 0.15 and 0.75 mm/day, the outline side taken from the
# square root of its area, halved) and no earlier than day 6 (the active
# tension lags the myofibroblasts by tau_contract_goh); the outline ends at
# least 15 % below the cut by day 14, the course is smooth (no day on which
# the outline grows back by more than 0.5 % after the myofibroblasts
# appear), most of it comes after day 5 and it is still going after day 10
# (clinically maximal at 5-15 days). A run checkpointed at day 5 and resumed
# (the lagged tension in the mechanics state) follows the same course.
# usage: e2e_mech_goh_course.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
H="--grid 40x40x8 --mechanics --mech-model goh --quiet --threads 2"
"$CLI" heal $H --days 14 --out "$T/run" >"$T/log" 2>&1 || { cat "$T/log" >&2; fail "heal --mech-model goh"; }
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
peak = 1 + day.index(vmax)  # the day that ends the fastest day
print("outline/cut: day 0 %.3f, 5 %.3f, 8 %.3f, 10 %.3f, 14 %.3f; fastest day %.3f mm/day "
      "(days %d-%d)" % (at(0) / cut, at(5) / cut, at(8) / cut, at(10) / cut, at(14) / cut, vmax,
                        peak - 1, peak))
assert at(0) > 1.1 * cut, "the cut gapes at day 0"
assert 0.15 <= vmax <= 0.75, vmax
assert peak >= 7, ("fastest day before day 6", peak)
assert at(14) <= 0.85 * cut, at(14) / cut
for d in range(4, 15):
    assert at(d) <= 1.005 * at(d - 1), ("grows back", d)
total = at(0) - at(14)
assert at(5) - at(14) > 0.75 * total, "most of the contraction after day 5"
assert at(10) - at(14) > 0.15 * total, "still contracting after day 10"
PY
# checkpoint at day 5 (the lagged tension is half built), resume to day 8:
# the course goes on as in the uninterrupted run. To the solver's tolerance,
# not bit for bit: the Newton solve keeps its tangent from frame to frame
# (src/mech/hyper.c), which the checkpoint does not hold; a resume that lost
# the lagged tension would stall the contraction for days instead.
"$CLI" heal $H --days 5 --checkpoint-every 5 --out "$T/ck" >"$T/log" 2>&1 ||
    { cat "$T/log" >&2; fail "checkpointed run"; }
"$CLI" heal --resume "$T/ck" --days 8 --threads 2 --quiet >"$T/log" 2>&1 ||
    { cat "$T/log" >&2; fail "resume"; }
python3 - "$T/run/area.csv" "$T/ck/area.csv" <<'PY' || fail "resumed course"
import csv, sys
a, b = ([(float(x["t_days"]), float(x["outline_area_mm2"])) for x in csv.DictReader(open(f))]
        for f in sys.argv[1:3])
assert len(b) > 100 and abs(b[-1][0] - 8) < 1e-9, b[-1]
worst = max(abs(q[1] - p[1]) / p[1] for p, q in zip(a, b))
assert all(p[0] == q[0] for p, q in zip(a, b))
print("resumed at day 5: outline at day 8 %.4f mm2 (uninterrupted %.4f), largest difference %.1e" % (
    b[-1][1], a[len(b) - 1][1], worst))
assert worst < 1e-4, worst
PY
echo "e2e_mech_goh_course: ok"
