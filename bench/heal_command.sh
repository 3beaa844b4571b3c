#!/bin/sh
# The whole `skinsim heal` command on the seed's 160x124x159 grid (seed 001
# Table 1's largest but one; DESIGN.md's target: 28 simulated days, whole
# command with its default outputs, <= 120 CPU-s), and the same run without
# the per-row statistics (--area-every at its coarsest) and without snapshots,
# so the profile's parts show: CPU seconds (user + system of the command and
# its threads, and each apart: the machine is shared, so wall seconds say
# little), wall seconds, area.csv rows, snapshot files. The last row runs the
# default command with the OpenMP default wait policy (threads spin at each
# barrier before they sleep; the command itself asks for passive waits).
# Usage: bench/heal_command.sh BUILD_DIR [DAYS] [GRID] [THREADS] [RUNS]
# RUNS (default "default no-stats no-snapshots spin") picks the rows.
# Runs niced. Figures only; nothing is asserted.
set -eu
S=${1:-build}/skinsim
days=${2:-28}
grid=${3:-160x124x159}
thr=${4:-2}
runs=${5:-default no-stats no-snapshots spin}
[ -x "$S" ] || { echo "heal_command.sh: $S not built (make build)" >&2; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
one() { # label, extra options
    label=$1
    shift
    python3 - "$S" "$T/$label" "$days" "$grid" "$thr" "$label" "$@" <<'PY'
import os, resource, subprocess, sys, time
s, out, days, grid, thr, label = sys.argv[1:7]
extra = sys.argv[7:]
env = dict(os.environ)
if label == "spin":
    env["OMP_WAIT_POLICY"] = "ACTIVE"
cmd = ["nice", "-n", "5", s, "heal", "--grid", grid, "--days", days, "--threads", thr,
       "--quiet", "--out", out] + extra
t0 = time.time()
subprocess.run(cmd, check=True, env=env)
wall = time.time() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
rows = sum(1 for _ in open(os.path.join(out, "area.csv"))) - 1
snaps = len([f for f in os.listdir(os.path.join(out, "fields")) if f.endswith(".vti")]) \
    if os.path.isdir(os.path.join(out, "fields")) else 0
print("| %s | %s | %s | %.1f | %.1f | %.1f | %.1f | %d | %d |" % (label, grid, days,
      ru.ru_utime + ru.ru_stime, ru.ru_utime, ru.ru_stime, wall, rows, snaps))
PY
}
echo "| run | grid | days | CPU-s | user s | sys s | wall s | area.csv rows | snapshots |"
echo "|---|---|---|---|---|---|---|---|---|"
for r in $runs; do
    case $r in
    default) one default ;;
    no-stats) one no-stats --area-every "$days" ;;
    no-snapshots) one no-snapshots --area-every "$days" --snapshot-every 0 ;;
    spin) one spin ;;
    *) echo "heal_command.sh: unknown run '$r'" >&2; exit 2 ;;
    esac
done
