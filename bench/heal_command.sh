#!/bin/sh
# The whole `skinsim heal` command on the seed's 160x124x159 grid (seed 001
# Table 1's largest but one; DESIGN.md's target: 28 simulated days, whole
# command with its default outputs, <= 120 CPU-s), and the same run without
# the per-row statistics (--area-every at its coarsest) and without snapshots,
# so the profile's parts show: CPU seconds (user + system of the command and
# its threads), wall seconds, area.csv rows, snapshot files.
# Usage: bench/heal_command.sh BUILD_DIR [DAYS] [GRID] [THREADS]
# Runs niced. Figures only; nothing is asserted.
set -eu
S=${1:-build}/skinsim
days=${2:-28}
grid=${3:-160x124x159}
thr=${4:-2}
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
cmd = ["nice", "-n", "5", s, "heal", "--grid", grid, "--days", days, "--threads", thr,
       "--quiet", "--out", out] + extra
t0 = time.time()
subprocess.run(cmd, check=True)
wall = time.time() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
rows = sum(1 for _ in open(os.path.join(out, "area.csv"))) - 1
snaps = len([f for f in os.listdir(os.path.join(out, "fields")) if f.endswith(".vti")]) \
    if os.path.isdir(os.path.join(out, "fields")) else 0
print("| %s | %s | %s | %.1f | %.1f | %d | %d |" % (label, grid, days, ru.ru_utime + ru.ru_stime,
      wall, rows, snaps))
PY
}
echo "| run | grid | days | CPU-s | wall s | area.csv rows | snapshots |"
echo "|---|---|---|---|---|---|---|"
one default
one no-stats --area-every "$days"
one no-snapshots --area-every "$days" --snapshot-every 0
