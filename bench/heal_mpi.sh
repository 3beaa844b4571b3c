#!/bin/sh
# The healing solver on MPI (docs/scaling.md): strong scaling on the seed's
# 160x124x159 grid over 1, 2 and 4 ranks, weak scaling with an 80x62x159 block
# per rank, SCHEME explicit (default; halo exchange) or split (transposes), each
# rank on THREADS OpenMP threads (default 1).
# Prints one Markdown row per run with the slowest rank's kernel time and halo
# exchange time per step, separated, and the halo bytes each rank sends per
# step. Runs each case REPEAT times (default 3) and keeps the best. The
# explicit scheme also runs the strong cases without the overlap of the halo
# exchange and the interior kernel (SKINSIM_DIST_OVERLAP=0: the exchange
# completes before the kernel, as before the overlap) and with boxes stacked in
# z (SKINSIM_MPI_DIMS=1x1x2 and 2x1x2).
# Then the peak memory (getrusage ru_maxrss) of every rank on the strong grid,
# with a snapshot (pieces, surface maps) and a checkpoint (pieces) written, next
# to the single process: rank 0 holds its box only, not the whole grid.
# MEM_ONLY=1 runs just that table.
# Usage: bench/heal_mpi.sh [BUILD_DIR] [STEPS] [REPEAT] [THREADS] [SCHEME]
# mpirun runs as root here only with --allow-run-as-root (DESIGN.md).
set -eu
B=${1:-build}/skinsim
steps=${2:-20}
repeat=${3:-3}
threads=${4:-1}
scheme=${5:-explicit}
[ -x "$B" ] || { echo "heal_mpi.sh: $B not built (make build)" >&2; exit 2; }
"$B" --version | grep -q "with MPI" || { echo "heal_mpi.sh: $B built without MPI" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
dt=0.0155 # the explicit limit of the 0.5 mm grid is 0.0172 days
[ "$scheme" = split ] && dt=0.05
days=$(python3 -c "print($steps * $dt)")

# one run: prints "compute_per_step halo_per_step stats_s gather_s bytes" (best of repeat)
run() { # np grid
    best=""
    for i in $(seq "$repeat"); do
        rm -rf "$tmp/out"
        mpirun --oversubscribe --allow-run-as-root -np "$1" "$B" heal --scheme "$scheme" \
            --grid "$2" --dt $dt --days "$days" --snapshot-every 0 --area-every 1000 \
            --threads "$threads" --out "$tmp/out" 2>"$tmp/err" >/dev/null ||
            { cat "$tmp/err" >&2; exit 1; }
        line=$(grep "MPI .* ranks" "$tmp/err")
        r=$(echo "$line" | python3 -c "
import re, sys
l = sys.stdin.read()
n = int(re.search(r'(\d+) steps', l).group(1))
g = lambda k: float(re.search(k + r' ([0-9.]+) s', l).group(1))
b = float(re.search(r'halo ([0-9.]+) bytes', l).group(1))
print('%.4f %.4f %.3f %.3f %.0f' % (g('compute') / n, g('halo exchange') / n, g('statistics'), g('gathers'), b))")
        if [ -z "$best" ] || [ "$(echo "$r $best" | awk '{print ($1 + $2 < $6 + $7)}')" = 1 ]; then
            best=$r
        fi
    done
    echo "$best"
}

row() { # kind np grid base_step
    set -- "$1" "$2" "$3" "$4" $(run "$2" "$3")
    cells=$(echo "$3" | tr x ' ' | awk '{print $1 * $2 * $3}')
    step=$(echo "$5 $6" | awk '{print $1 + $2}')
    [ "$4" = 0 ] && set -- "$1" "$2" "$3" "$step" "$5" "$6" "$7" "$8" "$9"
    eff=$(echo "$4 $step $2 $1" | awk '{ if ($4 ~ /^strong/) printf "%.0f%%", 100 * $1 / ($2 * $3); else printf "%.0f%%", 100 * $1 / $2 }')
    rate=$(echo "$cells $step" | awk '{printf "%.2e", 8 * $1 / $2}')
    echo "| $1 | $2 | $3 | $5 | $6 | $step | $rate | $eff | $9 |"
}

# peak memory: one process (no mpirun), then 1, 2 and 4 ranks (MB per rank)
mem() {
    rm -rf "$tmp/mem"
    python3 - "$B" "$scheme" "$dt" "$tmp/mem" "$threads" <<'PY'
import resource, subprocess, sys
b, scheme, dt, out, th = sys.argv[1:]
subprocess.run([b, 'heal', '--scheme', scheme, '--grid', '160x124x159', '--dt', dt, '--days',
                str(3 * float(dt)), '--snapshot-every', '0', '--checkpoint-every', dt,
                '--threads', th, '--quiet', '--out', out], check=True)
print('%.1f' % (resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024))
PY
}
memrow() { # np
    rm -rf "$tmp/mem"
    mpirun --oversubscribe --allow-run-as-root -np "$1" "$B" heal --scheme "$scheme" \
        --grid 160x124x159 --dt $dt --days "$(python3 -c "print(3 * $dt)")" --snapshot-every 0 \
        --checkpoint-every $dt --threads "$threads" --out "$tmp/mem" 2>"$tmp/err" >/dev/null ||
        { cat "$tmp/err" >&2; exit 1; }
    grep "peak memory per rank" "$tmp/err" | sed 's/.*(MB): //'
}
memtable() {
    echo "peak memory (MB), scheme $scheme, 160x124x159 (3.15e6 voxels), a snapshot and a checkpoint written"
    echo "| run | rank 0 | other ranks |"
    echo "|---|---|---|"
    echo "| one process (no mpirun) | $(mem) | - |"
    for np in 1 2 4; do
        set -- $(memrow $np)
        r0=$1
        shift
        echo "| $np rank(s) | $r0 | $* |"
    done
}
if [ -n "${MEM_ONLY:-}" ]; then
    echo "load before: $(uptime)"
    memtable
    echo "load after: $(uptime)"
    exit 0
fi

echo "load before: $(uptime)"
echo "scheme $scheme, $steps steps, $threads thread(s) per rank, best of $repeat"
echo "| scaling | ranks | grid | kernel s/step | halo s/step | step s | species-cell updates/s | efficiency | halo (transpose) bytes/rank/step |"
echo "|---|---|---|---|---|---|---|---|---|"
# the 1-rank row of each kind is its own base (efficiency 100 %)
row strong 1 160x124x159 0 >"$tmp/base" && cat "$tmp/base"
base=$(awk -F'|' '{print $7}' "$tmp/base")
row strong 2 160x124x159 "$base"
row strong 4 160x124x159 "$base"
if [ "$scheme" = explicit ]; then
    (export SKINSIM_DIST_OVERLAP=0; row strong-no-overlap 2 160x124x159 "$base")
    (export SKINSIM_DIST_OVERLAP=0; row strong-no-overlap 4 160x124x159 "$base")
    (export SKINSIM_MPI_DIMS=1x1x2; row strong-1x1x2 2 160x124x159 "$base")
    (export SKINSIM_MPI_DIMS=2x1x2; row strong-2x1x2 4 160x124x159 "$base")
fi
row weak 1 80x62x159 0 >"$tmp/base" && cat "$tmp/base"
wbase=$(awk -F'|' '{print $7}' "$tmp/base")
row weak 2 160x62x159 "$wbase"
row weak 4 160x124x159 "$wbase"
memtable
echo "load after: $(uptime)"
