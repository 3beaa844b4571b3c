#!/usr/bin/env bash
# End-to-end test of `skinsim heal`: a small run writes every output (area.csv,
# area.png, fields/*.vti + fields.pvd, surface PNGs, summary.json); a run cut
# short with checkpoints, whose newest checkpoint is then damaged, resumes to a
# bit-identical final state; stroke and mesh wounds run; bad inputs exit 2 and
# leave no output directory.
# usage: e2e_heal.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
count() { ls "$@" 2>/dev/null | wc -l; }

# one thread keeps these tiny runs fast on a loaded machine; run a uses 2 threads,
# so every comparison with it also checks thread-count independence
SMALL="--grid 24x20x8 --scenario scab --snapshot-every 1 --quiet --threads 1"

# --- help answers units, defaults and outputs
"$CLI" heal --help >"$T/help.txt" || fail "--help exit code"
for w in "mm" "days" "area.csv" "fields.pvd" "summary.json" "--checkpoint-every" "default"; do
    grep -q -- "$w" "$T/help.txt" || fail "--help does not mention $w"
done

# --- full run: every output exists and is consistent
"$CLI" heal $SMALL --days 2 --threads 2 --out "$T/a" --json >"$T/a.json" || fail "small run failed"
grep -q '"scenario":[[:space:]]*"scab"' "$T/a.json" || fail "--json summary lacks the scenario"
for f in area.csv area.png summary.json fields/fields.pvd; do
    [ -s "$T/a/$f" ] || fail "missing $f"
done
png_ok "$T/a/area.png"
# dt 0.05 days (split default), an area row every step: header + 41 rows
rows=$(wc -l <"$T/a/area.csv")
[ "$rows" -eq 42 ] || fail "area.csv has $rows lines, expected 42"
head -1 "$T/a/area.csv" | grep -q '^t_days,open_area_mm2,normalised_area,wound_region_area_mm2,mean_oxygen' ||
    fail "area.csv header"
sed -n 2p "$T/a/area.csv" | grep -q '^0,[0-9.]*,1,' || fail "first area row is not t=0 with normalised area 1"
[ "$(count "$T"/a/fields/*.vti)" -eq 3 ] || fail "expected 3 VTI snapshots (days 0, 1, 2)"
[ "$(grep -c '<DataSet timestep=' "$T/a/fields/fields.pvd")" -eq 3 ] || fail "pvd does not list 3 snapshots"
grep -q 'timestep="2" .*file="fields_0002.vti"' "$T/a/fields/fields.pvd" || fail "pvd time of the last snapshot"
head -c 400 "$T/a/fields/fields_0002.vti" | grep -q 'WholeExtent="0 24 0 20 0 8"' || fail "VTI extent"
for fld in epithelium capillary eschar scar; do
    [ "$(count "$T"/a/surface/${fld}_*.png)" -eq 3 ] || fail "expected 3 $fld surface maps"
    png_ok "$T/a/surface/${fld}_0002.png"
done
for k in '"dt_days"' '"scheme"' '"time_to_50pct_closure_days"' '"time_to_95pct_closure_days"' \
    '"wall_time_s"' '"params"' '"nx":[[:space:]]*24'; do
    grep -q "$k" "$T/a/summary.json" || fail "summary.json lacks $k"
done
# one thread gives the same bytes as two
"$CLI" heal $SMALL --days 2 --threads 1 --out "$T/a1" || fail "1-thread run failed"
cmp -s "$T/a/fields/fields_0002.vti" "$T/a1/fields/fields_0002.vti" || fail "1 vs 2 threads differ"
# the same DIR again is refused (a previous run), --force overwrites
"$CLI" heal $SMALL --days 2 --out "$T/a" 2>/dev/null
[ $? -eq 2 ] || fail "re-running into a previous run's DIR should exit 2"

# --- checkpoints: stop at day 1, damage the newest checkpoint, resume to day 2
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --out "$T/b" || fail "checkpointed run failed"
[ "$(count "$T"/b/checkpoints/ckpt_*.sshc)" -eq 2 ] || fail "expected the 2 newest checkpoints"
newest=$(ls "$T"/b/checkpoints/ckpt_*.sshc | tail -1)
head -c 1000 "$newest" >"$newest.part" && mv "$newest.part" "$newest"  # truncated
head -c 500 "$newest" >"$newest.tmp.XXXXXX"                            # an interrupted write
"$CLI" heal --resume "$T/b" --days 2 --quiet || fail "resume failed"
cmp -s "$T/a/fields/fields_0002.vti" "$T/b/fields/fields_0002.vti" ||
    fail "resumed final state differs from the uninterrupted run"
cmp -s "$T/a/area.csv" "$T/b/area.csv" || fail "resumed area.csv differs"
# summary.json byte for byte but the wall time and the resume's own record
# (t50/t95 interpolate restored area rows: they must read back bit for bit)
same_summary() { cmp -s <(grep -v '"wall_time_s"\|"resumed_from_step"\|"threads"' "$1") \
                        <(grep -v '"wall_time_s"\|"resumed_from_step"\|"threads"' "$2"); }
same_summary "$T/a/summary.json" "$T/b/summary.json" || fail "resumed summary.json differs"
grep -q '"resumed_from_step"' "$T/b/summary.json" || fail "summary.json does not record the resume"

# --- a run killed (SIGKILL) once it has a checkpoint resumes to the same final state
"$CLI" heal $SMALL --days 2 --checkpoint-every 0.1 --area-every 0.05 --out "$T/c" &
pid=$!
for _ in $(seq 200); do
    ls "$T"/c/checkpoints/ckpt_*.sshc >/dev/null 2>&1 && break
    sleep 0.05
done
kill -9 $pid 2>/dev/null
wait $pid 2>/dev/null
[ -e "$T/c/summary.json" ] && echo "note: the run finished before the kill; resume is a no-op"
"$CLI" heal --resume "$T/c" --quiet || fail "resume after kill failed"
cmp -s "$T/a/fields/fields_0002.vti" "$T/c/fields/fields_0002.vti" ||
    fail "state after kill + resume differs from the uninterrupted run"

# --- stroke and mesh wounds
printf 'u,v,stroke_id\n# one quadrilateral stroke\n0.3,0.3,0\n0.7,0.35,0\n0.6,0.7,0\n0.35,0.6,0\n' >"$T/s.csv"
"$CLI" heal $SMALL --days 0.2 --stroke "$T/s.csv" --out "$T/s" || fail "stroke run failed"
grep -q '"stroke"' "$T/s/summary.json" || fail "stroke wound not recorded"
cat >"$T/cube.obj" <<'EOF'
# closed cube in mm, grid frame (quads, v//n forms)
v 3 3 1.6
v 8 3 1.6
v 8 7 1.6
v 3 7 1.6
v 3 3 3.4
v 8 3 3.4
v 8 7 3.4
v 3 7 3.4
vn 0 0 1
f 1//1 4//1 3//1 2//1
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
EOF
"$CLI" heal $SMALL --days 0.2 --wound-mesh "$T/cube.obj" --out "$T/m" || fail "mesh run failed"
# 10 x 8 columns; voxel centres 1.75 .. 3.25 (4 layers) inside, 2.75 and up is air
grep -q '"voxels":[[:space:]]*320' "$T/m/summary.json" || fail "mesh voxel count"
grep -q '"initial_area_mm2":[[:space:]]*20' "$T/m/summary.json" || fail "mesh wound area (80 columns x 0.25 mm^2)"

# --- bad inputs: exit 2, nothing written
echo '{"params": {"D1": {"value": 1.0}}}' >"$T/nounit.json"
echo '{"params": ' >"$T/bad.json"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 2 3 4\n' >"$T/open.obj"
printf '0.1,0.1\n0.2,nan\n0.3,0.3\n' >"$T/nan.csv"
printf '0.1,0.1\n0.2,0.2\n' >"$T/two.csv"
# a closed tetrahedron in the air above the skin surface (3 mm)
printf 'v 1 1 3.5\nv 5 1 3.5\nv 1 5 3.5\nv 1 1 3.9\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n' >"$T/above.obj"
bad_cases=(
    "--scenario bogus"
    "--params $T/bad.json"
    "--params $T/nounit.json"
    "--params $T/missing.json"
    "--size-mm -1,2,3"
    "--grid 0x10x10"
    "--grid 4000x4000x400"
    "--days nan"
    "--days -1"
    "--dt 100 --scheme explicit"
    "--scheme rk4"
    "--wound-mask $T/missing.png"
    "--wound-mesh $T/open.obj"
    "--stroke $T/nan.csv"
    "--stroke $T/two.csv"
    "--wound-depth-mm 9"
    "--wound-depth-mm 0.1 --scenario keloid"
    "--wound-depth-mm 0.1 --mechanics"
    "--wound-mesh $T/above.obj"
    "--stroke $T/s.csv --wound-mesh $T/cube.obj"
    "--threads -3"
    "--no-such-option"
    "--adapt-tol 2"
    "--adapt-tol nan"
    "--scheme explicit --adapt-tol 0.01"
    "--mechanics --adapt-tol 0.01"
)
for args in "${bad_cases[@]}"; do
    "$CLI" heal $args --out "$T/bad" --quiet 2>"$T/err.txt"
    rc=$?
    [ $rc -eq 2 ] || fail "'$args' exited $rc, expected 2"
    [ -s "$T/err.txt" ] || fail "'$args' printed no error message"
    [ ! -e "$T/bad" ] || fail "'$args' left $T/bad behind"
done
# a wound shallower than one voxel is a partial cell ([D15]); the keloid and
# --mechanics keep whole voxels and refuse it (above)
"$CLI" heal --size-mm 10,10,4 --wound-depth-mm 0.1 --days 0.2 --snapshot-every 0 --quiet \
    --out "$T/shallow" || fail "a 0.1 mm wound on 0.5 mm voxels was refused"
# --- adaptive steps (the default with the split scheme): a long run takes far
# fewer solver steps than days / dt, and lands on every snapshot day
"$CLI" heal --grid 24x20x8 --days 60 --snapshot-every 20 --quiet --out "$T/long" ||
    fail "60-day adaptive run failed"
n=$(python3 -c "import json; print(json.load(open('$T/long/summary.json'))['adaptive_steps']['solver_steps'])")
[ "$n" -lt 400 ] || fail "60 days took $n solver steps (1200 fixed steps of 0.05 days)"
[ "$(count "$T"/long/fields/*.vti)" -eq 4 ] || fail "expected 4 VTI snapshots (days 0, 20, 40, 60)"
grep -q 'fields_0003.vti' "$T/long/fields/fields.pvd" || fail "fields.pvd lacks the day-60 snapshot"
grep -q 'timestep="60"' "$T/long/fields/fields.pvd" || fail "the last snapshot is not at day 60"

"$CLI" heal --resume "$T/nothing" --quiet 2>/dev/null
[ $? -eq 2 ] || fail "--resume of a directory without checkpoints should exit 2"
[ ! -e "$T/nothing" ] || fail "--resume created a directory"
echo "e2e_heal: all checks passed"
