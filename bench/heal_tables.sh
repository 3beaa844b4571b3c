#!/bin/sh
# Regenerates the grid-convergence and sensitivity tables of docs/heal-model.md
# from bench_heal_course (the same ss_heal_course_run the tests use).
# Usage: bench/heal_tables.sh BUILD_DIR [convergence|sensitivity|all] [FINEST_DX]
# Runs niced, one OpenMP thread per run, two runs at a time. Figures only.
set -eu
B=${1:-build}/bench_heal_course
what=${2:-all}
finest=${3:-0.25}
[ -x "$B" ] || { echo "heal_tables.sh: $B not built (make build)" >&2; exit 2; }
export OMP_NUM_THREADS=1
run() { nice -n 19 "$B" "$@"; }
field() { python3 -c "import json,sys; j=json.loads(sys.argv[1]); print(j['$2'])" "$1"; }
pct() { python3 -c "import sys; a,b=float(sys.argv[1]),float(sys.argv[2]); print('%.1f' % (100*abs(a-b)/b) if a>0 and b>0 else 'n/a')" "$1" "$2"; }

if [ "$what" = convergence ] || [ "$what" = all ]; then
    echo "| scenario | voxel (mm) | t50 (days) | t95 (days) | vs next finer: t50, t95 | run time (s) |"
    echo "|---|---|---|---|---|---|"
    for sc in clean scab; do
        days=13; [ $sc = scab ] && days=23
        dxs="0.5 0.25"; [ "$finest" = 0.125 ] && dxs="0.5 0.25 0.125"
        tmp=$(mktemp -d)
        for dx in $dxs; do
            (run --scenario $sc --dx $dx --days $days > "$tmp/$dx.json") &
        done
        wait
        prev=""
        for dx in $dxs; do
            j=$(cat "$tmp/$dx.json")
            eval "t50_$(echo $dx | tr . _)=$(field "$j" t50)"
            eval "t95_$(echo $dx | tr . _)=$(field "$j" t95)"
        done
        set -- $dxs
        while [ $# -gt 0 ]; do
            dx=$1; shift
            k=$(echo $dx | tr . _)
            a50=$(eval echo \$t50_$k); a95=$(eval echo \$t95_$k)
            cmp="-"
            if [ $# -gt 0 ]; then
                kn=$(echo $1 | tr . _)
                cmp="$(pct $a50 $(eval echo \$t50_$kn)) %, $(pct $a95 $(eval echo \$t95_$kn)) %"
            fi
            echo "| $sc | $dx | $a50 | $a95 | $cmp | $(field "$(cat $tmp/$dx.json)" wall_s) |"
        done
        rm -rf "$tmp"
    done
    echo
fi

if [ "$what" = sensitivity ] || [ "$what" = all ]; then
    keys="D1 lam11 lam31 D2 lam12 lam22 u1_beta2 D3 lam33 lam32 Dn rn lamnn De lamge gamma1 lamnrho rho_open lamrhop bed_mm"
    skeys="Ds Rs lames kscab kang scab_mm"
    base=$(run --scenario clean --days 25)
    sbase=$(run --scenario scab --days 40)
    echo "| parameter | scenario | value | t95 x0.5 / x1 / x2 (days) | peak scar x0.5 / x1 / x2 |"
    echo "|---|---|---|---|---|"
    line() {
        sc=$1 key=$2 b=$3 days=$4
        t=$(mktemp -d)
        (run --scenario $sc --days $days --scale $key=0.5 > $t/lo) &
        (run --scenario $sc --days $days --scale $key=2 > $t/hi) &
        wait
        lo=$(cat $t/lo) hi=$(cat $t/hi)
        rm -rf $t
        echo "| $key | $sc | $("$B" --scenario $sc --get $key) | $(field "$lo" t95) / $(field "$b" t95) / $(field "$hi" t95) | $(field "$lo" scar_max_peak) / $(field "$b" scar_max_peak) / $(field "$hi" scar_max_peak) |"
    }
    for k in $keys; do line clean $k "$base" 25; done
    for k in $skeys; do line scab $k "$sbase" 40; done
    echo "(t95 -1: not closed within the run: 25 days clean, 40 days scab)"
fi
