#!/usr/bin/env bash
# Shared by the MPI end-to-end tests (tests/e2e_mpi*.sh), sourced, never run
# alone: the skip checks (no mpirun, no MPI build: exit 77), a scratch
# directory, run_np (mpirun --oversubscribe: these machines have 2 cores)
# and the comparisons of a run on ranks with the single-process run.
# Callers set CLI and SRC first.
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
    cmp -s "$1/area.csv" "$2/area.csv" || fail "$2/area.csv differs from the single-process run"
    # run.json: all but the run id (made anew by every run)
    cmp -s <(grep -v '"run_id"' "$1/run.json") <(grep -v '"run_id"' "$2/run.json") ||
        fail "$2/run.json differs from the single-process run"
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
