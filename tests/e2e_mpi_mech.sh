#!/usr/bin/env bash
# End-to-end test of skinsim on MPI (docs/scaling.md), the contraction
# mechanics and skin meshes: `skinsim heal --mechanics` (the mechanics on
# rank 0, the fields gathered from the boxes and the velocity handed back
# each step) on 1, 2, 3 ranks and 2x1x2 with the explicit scheme and on 2
# and 3 with the split scheme writes the single-process bytes (pieces,
# area.csv, mesh .vtu, velocity maps, summary) and resumes across rank
# counts; a run on a skin mesh (--mesh, the hand, with mechanics) on 3
# ranks and 2x1x2, and checkpointed on 2, resumed on 3. Skips (77) without
# mpirun or without an MPI build.
# usage: e2e_mpi_mech.sh <skinsim> <source dir>
set -u
CLI=$1
SRC=${2:-$(dirname "$0")/..}
. "$SRC/tests/mpi_common.sh"

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
HAND="$SRC/data/meshes/generic-hand-left.glb" # shipped with the repository
[ -f "$HAND" ] || HAND=""
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

echo "e2e_mpi_mech: all passed"
