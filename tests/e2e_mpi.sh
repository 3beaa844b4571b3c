#!/usr/bin/env bash
# End-to-end test of skinsim on MPI (docs/scaling.md): `skinsim heal` on 1, 2,
# 3 and 4 ranks (mpirun --oversubscribe on this 2-core machine) writes the same
# bytes as the single-process run: area.csv, run.json, the surface maps and
# summary.json (less its wall time and thread count); its snapshots are per-rank
# pieces joined by fields_NNNN.pvti (no whole-grid .vti), which assembled
# (tests/pvti_same.py) equal the single-process fields_NNNN.vti array by array,
# and fields.pvd lists them; every rank builds its own box from the wound (the
# built-in square, strokes, a mesh voxelised per box);
# on a grid that divides by the rank counts and one that does not, and
# with boxes stacked in z (SKINSIM_MPI_DIMS=1x1x2 and 2x1x2); a run
# checkpointed on a 2x1x2 process grid resumes on 3 ranks to the uninterrupted
# single-process result; the contraction mechanics (on rank 0) on 1, 2, 3 and
# 2x1x2 ranks and resumed across rank counts, and with the split scheme (its
# convection on the y slabs) on 2 and 3 ranks and resumed 2 -> 3; a run on a skin mesh (--mesh,
# with mechanics) on 3 and 2x1x2 ranks and resumed 2 -> 3; bad input (too many ranks for
# the grid with either scheme, z boxes too thin, a bad SKINSIM_MPI_DIMS, a
# missing skin mesh, a missing
# or damaged checkpoint) exits 2 on every rank with
# nothing written; `optics table` on 2 and 4 ranks writes the bytes of the
# single-process table. Skips (77) without mpirun or without an MPI build.
# usage: e2e_mpi.sh <skinsim> <source dir>
set -u
CLI=$1
SRC=${2:-$(dirname "$0")/..}
command -v mpirun >/dev/null || { echo "skip: no mpirun"; exit 77; }
"$CLI" --version | grep -q "with MPI" || { echo "skip: skinsim built without MPI"; exit 77; }
T=$(mktemp -d /tmp/skinsim-e2e-mpi-XXXXXX)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# these machines run as root (DESIGN.md: OpenMPI refuses root without these)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# OpenMPI keeps allocations until exit: leak reports under ASan are its own
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
# (waiting ranks yield the core: this machine has 2 and other jobs)
MPIRUN="mpirun --oversubscribe --allow-run-as-root --mca btl self,vader --mca mpi_yield_when_idle 1"
run_np() { local n=$1; shift; $MPIRUN -np "$n" "$CLI" "$@"; }

# compares every output of run dir $1 with $2 (an MPI run: pieces + .pvti)
same_run() {
    for f in area.csv run.json; do
        cmp -s "$1/$f" "$2/$f" || fail "$2/$f differs from the single-process run"
    done
    cmp -s "$1/fields/fields.pvd" <(sed 's/\.pvti"/.vti"/' "$2/fields/fields.pvd") ||
        fail "$2/fields/fields.pvd does not list the snapshots of the single-process run as .pvti"
    for f in "$1"/surface/*.png; do
        cmp -s "$f" "$2/${f#$1/}" || fail "$2/${f#$1/} differs from the single-process run"
    done
    python3 "$SRC/tests/pvti_same.py" "$1" "$2" ||
        fail "$2: the assembled pieces differ from the single-process snapshots"
    diff <(grep -v -e wall_time_s -e '"threads"' "$1/summary.json") \
        <(grep -v -e wall_time_s -e '"threads"' "$2/summary.json") >/dev/null ||
        fail "$2/summary.json differs from the single-process run"
}

# runs heal with options $3.. without mpirun into $T/$1, then on the rank
# counts $2 into $T/$1-N, and compares every output
equal_on_ranks() {
    local name=$1 counts=$2; shift 2
    "$CLI" heal "$@" --out "$T/$name" || fail "single-process run ($name)"
    for n in $counts; do
        run_np $n heal "$@" --out "$T/$name-$n" || fail "run on $n ranks ($name)"
        same_run "$T/$name" "$T/$name-$n"
    done
    echo "ok: heal $name bit-identical on $counts ranks"
}
# 1-4 ranks on a grid no rank count divides; 2 and 4 on one they divide
# (SKINSIM_TEST_QUICK, the sanitizer suite: the uneven grid only, a shorter adaptive run)
adapt_days=40
EXPL="--scheme explicit --scenario scab --days 0.6 --snapshot-every 0.3 --area-every 0.05 --quiet --threads 1"
[ -n "${SKINSIM_TEST_QUICK:-}" ] && adapt_days=30 ||
    equal_on_ranks explicit-24x20x8 "2 4" --grid 24x20x8 $EXPL
equal_on_ranks explicit-23x17x9 "1 2 3 4" --grid 23x17x9 $EXPL

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

# --- the contraction mechanics (--mechanics, the explicit scheme) on rank 0:
# the fields they read gathered from the boxes each step, their velocity
# handed back to every box + halo; every output (pieces with velocity and
# displacement, mesh .vtu, velocity views, area.csv columns, summary block)
# the single-process run's; on 1, 2 and 3 ranks and with z split (2x1x2); and a
# run checkpointed mid-way resumed on another rank count (pieces 2 -> 3
# ranks, a single-process checkpoint -> 2x1x2, pieces -> one process)
MECH="--grid 23x17x9 --scheme explicit --mechanics --snapshot-every 0.5 --area-every 0.25 --quiet --threads 1"
mech_same() { # single-process run $1, MPI run $2: the mechanics' own outputs
    for f in "$1"/fields/mesh_*.vtu "$1"/fields/mesh.pvd "$1"/surface/velocity_*.png; do
        cmp -s "$f" "$2/${f#$1/}" || fail "$2/${f#$1/} differs from the single-process run"
    done
}
# (SKINSIM_TEST_QUICK, the sanitizer suite: 2 ranks and the z split only)
mech_counts="1 2 3"
[ -n "${SKINSIM_TEST_QUICK:-}" ] && mech_counts="2"
equal_on_ranks mech "$mech_counts" $MECH --days 1.5
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $MECH --days 1.5 --out "$T/mech-z" || fail "mechanics run on 2x1x2"
same_run "$T/mech" "$T/mech-z"
for n in $mech_counts z; do mech_same "$T/mech" "$T/mech-$n"; done
grep -q 'Name="displacement"' "$T/mech-2/fields/fields_0003_p0001.vti" || fail "a piece lacks the displacement"
vel_nonzero() { # $1: a single-process snapshot whose velocity must not be zero
    python3 - "$1" <<'PY' || fail "$1: the mechanics' velocity is zero: the test would not see the coupling"
import re, struct, sys
b = open(sys.argv[1], 'rb').read()
head, raw = b.split(b'<AppendedData encoding="raw">', 1)
raw = raw[raw.index(b'_') + 1:]
off = int(re.search(rb'Name="velocity"[^>]*offset="(\d+)"', head).group(1))
n = struct.unpack('<Q', raw[off:off + 8])[0]
v = struct.unpack('<%df' % (n // 4), raw[off + 8:off + 8 + n])
assert max(abs(x) for x in v) > 1e-4, max(abs(x) for x in v)
PY
}
vel_nonzero "$T/mech/fields/fields_0003.vti"
run_np 2 heal $MECH --days 1 --checkpoint-every 0.5 --out "$T/mech-ck" || fail "mechanics run with checkpoints on 2 ranks"
cp -r "$T/mech-ck" "$T/mech-ck1"
run_np 3 heal --resume "$T/mech-ck" --days 1.5 --quiet || fail "mechanics resume on 3 ranks"
cmp -s "$T/mech/area.csv" "$T/mech-ck/area.csv" || fail "mechanics resumed (2 -> 3 ranks) area.csv differs"
python3 "$SRC/tests/pvti_same.py" "$T/mech" "$T/mech-ck" last || fail "mechanics resumed (2 -> 3 ranks) fields differ"
mech_same "$T/mech" "$T/mech-ck"
"$CLI" heal --resume "$T/mech-ck1" --days 1.5 --quiet || fail "mechanics pieces resumed in one process"
cmp -s "$T/mech/area.csv" "$T/mech-ck1/area.csv" || fail "mechanics resumed (2 ranks -> 1 process) area.csv differs"
cmp -s "$T/mech/fields/fields_0003.vti" "$T/mech-ck1/fields/fields_0003.vti" ||
    fail "mechanics resumed (2 ranks -> 1 process) final fields differ"
"$CLI" heal $MECH --days 1 --checkpoint-every 0.5 --out "$T/mech-w" || fail "single-process mechanics run with checkpoints"
SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal --resume "$T/mech-w" --days 1.5 --quiet || fail "mechanics resume on 2x1x2"
cmp -s "$T/mech/area.csv" "$T/mech-w/area.csv" || fail "mechanics resumed (1 process -> 2x1x2) area.csv differs"
mkdir -p "$T/mech-wp/fields"
cp "$T"/mech-w/fields/*.pvti "$T"/mech-w/fields/*_p0*.vti "$T/mech-wp/fields/"
python3 "$SRC/tests/pvti_same.py" "$T/mech" "$T/mech-wp" last || fail "mechanics resumed (1 process -> 2x1x2) fields differ"
mech_same "$T/mech" "$T/mech-w"
echo "ok: --mechanics bit-identical on 1, 2, 3 and 2x1x2 ranks; checkpoints resume across rank counts"

# --- the mechanics with the default split scheme: the y slabs convect with
# the mechanics' velocity (donor cell, the y halo exchanged per subcycle, the
# subcycles from the largest speed of any slab) as one process does
# (the myofibroblasts at once and no remodelling: velocities of 0.01-0.02 mm/day)
printf '{"mechanics": {"tau_myo": {"value": 0, "unit": "day", "source": "e2e"}, "tau_remodel": {"value": 0, "unit": "day", "source": "e2e"}}}\n' >"$T/pull-split.json"
MSPLIT="--grid 23x17x9 --mechanics --params $T/pull-split.json --snapshot-every 0.5 --area-every 0.25 --quiet --threads 1 --days 1"
msplit_counts="2 3"
[ -n "${SKINSIM_TEST_QUICK:-}" ] && msplit_counts="3"
equal_on_ranks mech-split "$msplit_counts" $MSPLIT
for n in $msplit_counts; do mech_same "$T/mech-split" "$T/mech-split-$n"; done
vel_nonzero "$T/mech-split/fields/fields_0001.vti"
run_np 2 heal ${MSPLIT/--days 1/--days 0.5} --checkpoint-every 0.5 --out "$T/mech-split-ck" ||
    fail "split mechanics run with checkpoints on 2 ranks"
run_np 3 heal --resume "$T/mech-split-ck" --days 1 --quiet || fail "split mechanics resume on 3 ranks"
cmp -s "$T/mech-split/area.csv" "$T/mech-split-ck/area.csv" || fail "split mechanics resumed (2 -> 3 ranks) area.csv differs"
python3 "$SRC/tests/pvti_same.py" "$T/mech-split" "$T/mech-split-ck" last ||
    fail "split mechanics resumed (2 -> 3 ranks) fields differ"
echo "ok: --mechanics with the split scheme bit-identical on $msplit_counts ranks and resumed 2 -> 3"

# --- a patch of skin on a mesh (--mesh, the hand) with the mechanics: rank 0
# builds the patch's grid once and hands out the boxes; the skin surface
# outputs (skin_NNNN.vtu / .glb) take the fields at each column's top tissue
# cell from the box that owns it; on 3 ranks and 2x1x2, and checkpointed on 2
# ranks, resumed on 3 (skipped without the hand mesh)
HAND=""
for h in "$SRC/data/meshes/generic-hand-left.glb" "$SRC/../shared/data/meshes/generic-hand-left.glb" \
         "$SRC/../../shared/data/meshes/generic-hand-left.glb" /work/shared/data/meshes/generic-hand-left.glb; do
    [ -f "$h" ] && { HAND=$h; break; }
done
if [ -n "$HAND" ]; then
    python3 "$SRC/tests/strokes_ellipse.py" 0.2 0.62 0.02 0.014 >"$T/cut.csv"
    printf '{"mechanics": {"tau_myo": {"value": 0, "unit": "day", "source": "e2e"}, "tau_remodel": {"value": 0, "unit": "day", "source": "e2e"}}}\n' >"$T/pull.json"
    SKIN="--mesh $HAND --wound-uv $T/cut.csv --voxel-mm 1 --scheme explicit --mechanics --params $T/pull.json --snapshot-every 0.5 --area-every 0.25 --quiet --threads 1"
    equal_on_ranks skin "3" $SKIN --days 1
    skin_runs="skin-3"
    if [ -z "${SKINSIM_TEST_QUICK:-}" ]; then
        SKINSIM_MPI_DIMS=2x1x2 run_np 4 heal $SKIN --days 1 --out "$T/skin-z" || fail "skin-mesh run on 2x1x2"
        same_run "$T/skin" "$T/skin-z"
        skin_runs="skin-3 skin-z"
    fi
    for d in $skin_runs; do
        mech_same "$T/skin" "$T/$d"
        for f in "$T"/skin/surface/skin_*.glb "$T"/skin/surface/skin_*.vtu "$T"/skin/surface/skin.pvd; do
            cmp -s "$f" "$T/$d/surface/${f##*/}" || fail "$T/$d/surface/${f##*/} differs from the single-process run"
        done
    done
    run_np 2 heal $SKIN --days 0.5 --checkpoint-every 0.5 --out "$T/skin-ck" || fail "skin-mesh run with checkpoints on 2 ranks"
    run_np 3 heal --resume "$T/skin-ck" --days 1 --quiet || fail "skin-mesh resume on 3 ranks"
    cmp -s "$T/skin/area.csv" "$T/skin-ck/area.csv" || fail "skin-mesh resumed (2 -> 3 ranks) area.csv differs"
    python3 "$SRC/tests/pvti_same.py" "$T/skin" "$T/skin-ck" last || fail "skin-mesh resumed (2 -> 3 ranks) fields differ"
    cmp -s "$T/skin/surface/skin_0002.glb" "$T/skin-ck/surface/skin_0002.glb" ||
        fail "skin-mesh resumed (2 -> 3 ranks) skin_0002.glb differs"
    echo "ok: --mesh with --mechanics bit-identical on 3 ranks and 2x1x2, resumed 2 -> 3 ranks"
else
    echo "no hand mesh: the --mesh case on MPI skipped"
fi

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
