#!/usr/bin/env bash
# End-to-end test of skinsim on MPI (docs/scaling.md), the solver itself:
# `skinsim heal` on 1, 2, 3 and 4 ranks (mpirun --oversubscribe on this
# 2-core machine) writes the same bytes as the single-process run: area.csv,
# run.json, the surface maps and summary.json (less its wall time and thread
# count); its snapshots are per-rank pieces joined by fields_NNNN.pvti (no
# whole-grid .vti), which assembled (tests/pvti_same.py) equal the
# single-process fields_NNNN.vti array by array, and fields.pvd lists them;
# every rank builds its own box from the wound (the built-in square,
# strokes, a mesh voxelised per box); on the default wound and grid, on a
# grid that divides by the rank counts and one that does not, and with boxes stacked in z
# (SKINSIM_MPI_DIMS=1x1x2 and 2x1x2); adaptive steps with rejected steps; a
# run checkpointed on a 2x1x2 process grid resumes on 3 ranks and in one
# process to the uninterrupted single-process result; bad input (too many
# ranks for the grid with either scheme, z boxes too thin, a bad
# SKINSIM_MPI_DIMS, a missing skin mesh, a missing or damaged checkpoint)
# exits 2 on every rank with nothing written; `optics table` on 2 and 4
# ranks writes the bytes of the single-process table. The mechanics and skin
# meshes on MPI: tests/e2e_mpi_mech.sh. Skips (77) without mpirun or without
# an MPI build. 1 mm voxels (a sub-voxel crust, [D14]) on 3 ranks and 2x1x2.
# usage: e2e_mpi.sh <skinsim> <source dir>
set -u
CLI=$1
SRC=${2:-$(dirname "$0")/..}
. "$SRC/tests/mpi_common.sh"

# 1-4 ranks on a grid no rank count divides; 2 and 4 on one they divide
# (SKINSIM_TEST_QUICK, the sanitizer suite: the uneven grid only, a shorter adaptive run)
adapt_days=40
EXPL="--scheme explicit --scenario scab --days 0.6 --snapshot-every 0.3 --area-every 0.05 --quiet --threads 1"
[ -n "${SKINSIM_TEST_QUICK:-}" ] && adapt_days=30 ||
    equal_on_ranks explicit-24x20x8 "2 4" --grid 24x20x8 $EXPL
equal_on_ranks explicit-23x17x9 "1 2 3 4" --grid 23x17x9 $EXPL
# the default wound on the default grid (60 x 60 x 8), both schemes
equal_on_ranks default "1 2 3 4" --days 1 --snapshot-every 0.5 --area-every 0.05 --quiet --threads 1
equal_on_ranks default-explicit "2 4" --scheme explicit --days 0.3 --snapshot-every 0.15 --quiet --threads 1

# --- z split too (SKINSIM_MPI_DIMS; the explicit scheme): boxes stacked in z,
# the column values of the epithelium handed down the stack; 9 levels in 2
# boxes of 4 and 5, 23 and 17 columns over 2 and 1
for dims in 1x1x2 2x1x2; do
    np=$(echo "$dims" | awk -Fx '{print $1 * $2 * $3}')
    SKINSIM_MPI_DIMS=$dims run_np "$np" heal --grid 23x17x9 $EXPL --out "$T/zsplit-$dims" ||
        fail "run on the process grid $dims"
    same_run "$T/explicit-23x17x9" "$T/zsplit-$dims"
done
echo "ok: heal bit-identical with z split (process grids 1x1x2, 2x1x2)"

# --- every rank builds its box from the wound: strokes (per-column ranges,
# with z split too) and a closed mesh voxelised per box
printf 'u,v,stroke_id\n0.3,0.3,0\n0.7,0.35,0\n0.6,0.7,0\n0.35,0.6,0\n' >"$T/s.csv"
printf 'v 3 3 1.6\nv 8 3 1.6\nv 8 7 1.6\nv 3 7 1.6\nv 3 3 3.4\nv 8 3 3.4\nv 8 7 3.4\nv 3 7 3.4\n%s\n' \
    'f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8' >"$T/cube.obj"
SHORT="--grid 23x17x9 --scheme explicit --scenario scab --days 0.3 --snapshot-every 0.3 --area-every 0.05 --quiet --threads 1"
"$CLI" heal $SHORT --stroke "$T/s.csv" --out "$T/stroke" || fail "single-process stroke run"
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $SHORT --stroke "$T/s.csv" --out "$T/stroke-4" ||
    fail "stroke run on 2x1x2"
same_run "$T/stroke" "$T/stroke-4"
"$CLI" heal $SHORT --wound-mesh "$T/cube.obj" --out "$T/mesh" || fail "single-process mesh run"
SKINSIM_MPI_DIMS=1x2x2 run_np 4 heal $SHORT --wound-mesh "$T/cube.obj" --out "$T/mesh-4" ||
    fail "mesh run on 1x2x2"
same_run "$T/mesh" "$T/mesh-4"
echo "ok: boxes built per rank from strokes and a mesh, bit-identical (2x1x2, 1x2x2)"

# --- the split scheme (the default): y sweeps on x slabs, reached by transposes
equal_on_ranks split-23x17x9 "1 2 3 4" --grid 23x17x9 --scenario scab --days 1 --snapshot-every 0.5 \
    --area-every 0.05 --quiet --threads 1

# --- 1 mm voxels: the crust layer's floor cuts the surface voxel, whose
# tissue share has its own faces and volume (docs/heal-model.md [D14]);
# both schemes, and boxes stacked in z (the neighbours' shares in the halo)
SUB="--size-mm 23,17,9 --grid 23x17x9 --scenario scab --days 1 --snapshot-every 0.5 --area-every 0.05 --quiet --threads 1"
equal_on_ranks subvoxel-split "3" $SUB
equal_on_ranks subvoxel-explicit "3" $SUB --scheme explicit
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $SUB --scheme explicit --out "$T/subvoxel-explicit-z" ||
    fail "1 mm voxel run on 2x1x2"
same_run "$T/subvoxel-explicit" "$T/subvoxel-explicit-z"
echo "ok: heal with sub-voxel crusts (1 mm voxels) bit-identical, 2x1x2 too"

# --- adaptive steps (the split scheme's default) with rejected, undone steps
OPTS="--grid 23x17x9 --scenario keloid --days $adapt_days --snapshot-every 10 --adapt-tol 0.05 --quiet --threads 1"
"$CLI" heal $OPTS --out "$T/adapt" || fail "single-process adaptive run"
grep -q '"retried":[[:space:]]*[1-9]' "$T/adapt/summary.json" || fail "the adaptive case retries no step"
run_np 3 heal $OPTS --out "$T/adapt-3" || fail "adaptive run on 3 ranks"
same_run "$T/adapt" "$T/adapt-3"
# checkpointed (in pieces, y slabs) on 2 ranks mid-way, resumed on 3
run_np 2 heal $OPTS --days $((adapt_days / 2)) --checkpoint-every 5 --out "$T/adapt-ck" ||
    fail "adaptive run with checkpoints on 2 ranks"
run_np 3 heal --resume "$T/adapt-ck" --days $adapt_days --quiet || fail "adaptive resume on 3 ranks"
# the reference has the same checkpoint days: long adaptive steps never jump over a
# checkpoint, so the cadence is part of the step sequence (docs/heal-model.md §4)
"$CLI" heal $OPTS --checkpoint-every 5 --out "$T/adapt-ckref" || fail "adaptive run with checkpoints"
cmp -s "$T/adapt-ckref/area.csv" "$T/adapt-ck/area.csv" || fail "adaptive resumed (2 -> 3 ranks) area.csv differs"
python3 "$SRC/tests/pvti_same.py" "$T/adapt-ckref" "$T/adapt-ck" last || fail "adaptive resumed (2 -> 3 ranks) fields differ"
echo "ok: adaptive steps (with retries) bit-identical on 3 ranks, and checkpointed on 2, resumed on 3"

# --- checkpoint on 4 ranks, resume on 3: the uninterrupted single-process result
OPTS="--scheme explicit --grid 23x17x9 --scenario scab --snapshot-every 0.3 --area-every 0.05 --quiet --threads 1"
"$CLI" heal $OPTS --days 0.9 --out "$T/full" || fail "single-process 0.9-day run"
# (written on a 2x1x2 process grid: boxes stacked in z too)
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $OPTS --days 0.6 --checkpoint-every 0.3 --out "$T/cut" ||
    fail "4-rank run with checkpoints"
# (in pieces: one per rank and a header, two checkpoints kept; no whole-grid file)
ls "$T"/cut/checkpoints/ckpt_*.sshh >/dev/null 2>&1 || fail "no checkpoint header written on 4 ranks"
[ "$(ls "$T"/cut/checkpoints/ckpt_*_p*.sshp | wc -l)" = 8 ] || fail "not 4 pieces per checkpoint"
ls "$T"/cut/checkpoints/*.sshc >/dev/null 2>&1 && fail "a whole-grid checkpoint written on 4 ranks"
cp -r "$T/cut" "$T/cut1"
run_np 3 heal --resume "$T/cut" --days 0.9 --quiet || fail "resume on 3 ranks"
cmp -s "$T/full/area.csv" "$T/cut/area.csv" || fail "resumed (4 -> 3 ranks) area.csv differs"
# (the cut run's own last snapshot shifts the numbering: compare the newest of each)
python3 "$SRC/tests/pvti_same.py" "$T/full" "$T/cut" last || fail "resumed (4 -> 3 ranks) final fields differ"
# the same pieces resumed by one process (no mpirun)
"$CLI" heal --resume "$T/cut1" --days 0.9 --quiet || fail "resume of the pieces in one process"
cmp -s "$T/full/area.csv" "$T/cut1/area.csv" || fail "resumed (4 ranks -> 1 process) area.csv differs"
cmp -s "$(ls "$T"/full/fields/fields_????.vti | tail -1)" "$(ls "$T"/cut1/fields/fields_????.vti | tail -1)" ||
    fail "resumed (4 ranks -> 1 process) final fields differ"
echo "ok: checkpoint in pieces on 4 ranks (2x1x2) resumes on 3 ranks and in one process bit-identically"

# --- the ModelMatch table: geometries shared out by rank 0, the same bytes
TAB="--samples 2 --photons 400 --wl-min 450 --wl-max 650 --wl-step 100 --theta-i 2 --theta-r 3 --phi 3 --quiet --threads 1"
"$CLI" optics table $TAB --out "$T/t1.sstab" || fail "single-process table"
for n in 2 4; do
    run_np $n optics table $TAB --out "$T/t$n.sstab" || fail "table on $n ranks"
    cmp -s "$T/t1.sstab" "$T/t$n.sstab" || fail "table on $n ranks differs from the single-process one"
done
echo "ok: optics table bit-identical on 2 and 4 ranks"

# --- bad input: exit 2 on every rank, a message naming the input, nothing written
bad() { # name, expected message part, ranks, args...
    local name=$1 msg=$2 n=$3; shift 3
    run_np "$n" "$@" >"$T/$name.out" 2>"$T/$name.err"
    local rc=$?
    [ $rc -eq 2 ] || { cat "$T/$name.err"; fail "$name: exit $rc, expected 2"; }
    grep -q -- "$msg" "$T/$name.err" || { cat "$T/$name.err"; fail "$name: no message naming $msg"; }
}
bad ranks "too many" 5 heal --scheme explicit --grid 4x40x8 --days 0.1 --out "$T/bad1"
[ -e "$T/bad1" ] && fail "too many ranks: output written"
bad split "--scheme split" 5 heal --grid 40x4x8 --days 0.1 --out "$T/bad2"
[ -e "$T/bad2" ] && fail "split on too many ranks: output written"
SKINSIM_MPI_DIMS=1x1x4 bad zthin "fewer than 3 levels" 4 heal --scheme explicit --grid 23x17x9 \
    --days 0.1 --out "$T/bad5"
[ -e "$T/bad5" ] && fail "z boxes too thin: output written"
SKINSIM_MPI_DIMS=1x1x2 bad zsplit "split scheme" 2 heal --grid 23x17x9 --days 0.1 --out "$T/bad6"
SKINSIM_MPI_DIMS=2x2 bad dims "SKINSIM_MPI_DIMS" 4 heal --scheme explicit --grid 23x17x9 \
    --days 0.1 --out "$T/bad7"
[ -e "$T/bad6" ] || [ -e "$T/bad7" ] && fail "bad process grid: output written"
printf 'v 0 0 20\nv 1 0 20\nv 0 1 20\nv 0 0 21\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n' >"$T/above.obj"
bad meshout "above.obj" 3 heal --scheme explicit --grid 23x17x9 --wound-mesh "$T/above.obj" --days 0.1 \
    --out "$T/bad8"
[ -e "$T/bad8" ] && fail "mesh outside the block on 3 ranks: output written"
bad skinmesh "none.glb" 2 heal --mesh "$T/none.glb" --wound-uv "$T/s.csv" --days 0.1 --out "$T/bad9"
[ -e "$T/bad9" ] && fail "a run on a missing skin mesh on 2 ranks: output written"
bad missing "resume" 3 heal --resume "$T/nowhere" --quiet
rm -rf "$T/dmg" "$T/nopiece"
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $OPTS --days 0.6 --checkpoint-every 0.3 --out "$T/dmg" ||
    fail "4-rank run with checkpoints (for damage)"
cp -r "$T/dmg" "$T/nopiece"
for f in "$T"/dmg/checkpoints/*_p000002.sshp; do printf 'garbage' >"$f"; done
before=$(cd "$T/dmg" && find . -type f -exec md5sum {} + | sort | md5sum)
bad damaged "checkpoint" 2 heal --resume "$T/dmg" --days 1.2 --quiet
after=$(cd "$T/dmg" && find . -type f -exec md5sum {} + | sort | md5sum)
[ "$before" = "$after" ] || fail "a refused resume changed the run directory"
rm -f "$T"/nopiece/checkpoints/*_p000001.sshp
before=$(cd "$T/nopiece" && find . -type f -exec md5sum {} + | sort | md5sum)
bad nopiece "p000001" 3 heal --resume "$T/nopiece" --days 1.2 --quiet
after=$(cd "$T/nopiece" && find . -type f -exec md5sum {} + | sort | md5sum)
[ "$before" = "$after" ] || fail "a resume with a missing piece changed the run directory"
bad other "does not run on" 2 skin --size 64 --out "$T/bad4"
[ -e "$T/bad4" ] && fail "skin on 2 ranks: output written"
mkdir -p "$T/adir"
bad tabdir "--out" 3 optics table $TAB --out "$T/adir"
bad tabsamples "--samples" 2 optics table --samples 0 --out "$T/t0.sstab"
[ -e "$T/t0.sstab" ] && fail "bad table: output written"
echo "ok: bad input exits 2 on every rank, nothing written"
echo "e2e_mpi: all passed"
