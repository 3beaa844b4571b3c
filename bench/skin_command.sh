#!/bin/sh
# The whole `skinsim skin` command at 2048^2 (DESIGN.md's target: every map
# written, <= 6 CPU-s and <= 3 s wall on 2 cores): the default (bio.exr in
# half floats included) and --no-bio, each RUNS times, printing CPU seconds
# (user + system of the command and its threads: the machine is shared, so
# wall seconds say little), wall seconds, peak RSS and the machine's load.
# Usage: bench/skin_command.sh BUILD_DIR [SIZE] [THREADS] [RUNS] [PRESET]
# Runs niced. Figures only; nothing is asserted.
set -eu
S=${1:-build}/skinsim
size=${2:-2048}
thr=${3:-2}
runs=${4:-2}
preset=${5:-forearm}
[ -x "$S" ] || { echo "skin_command.sh: $S not built (make build)" >&2; exit 2; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
one() { # label, extra options
    label=$1
    shift
    python3 - "$S" "$T/$label" "$size" "$thr" "$preset" "$label" "$@" <<'PY'
import os, resource, subprocess, sys, time
s, out, size, thr, preset, label = sys.argv[1:7]
extra = sys.argv[7:]
cmd = ["nice", "-n", "5", s, "skin", "--size", size, "--threads", thr, "--preset", preset,
       "--quiet", "--out", out] + extra
before = resource.getrusage(resource.RUSAGE_CHILDREN)
t0 = time.time()
subprocess.run(cmd, check=True)
wall = time.time() - t0
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
user, sys_ = ru.ru_utime - before.ru_utime, ru.ru_stime - before.ru_stime
print("| %s | %s | %s | %.2f | %.2f | %.2f | %.2f | %.0f | %.1f |" % (label, size, thr,
      user + sys_, user, sys_, wall, ru.ru_maxrss / 1024.0, os.getloadavg()[0]))
PY
    rm -rf "$T/$label"
}
echo "| run | size | threads | CPU-s | user s | sys s | wall s | peak RSS MB | load |"
echo "|---|---|---|---|---|---|---|---|---|"
i=0
while [ $i -lt "$runs" ]; do
    one default
    one no-bio --no-bio
    i=$((i + 1))
done
