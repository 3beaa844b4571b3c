#!/usr/bin/env bash
# Start-up and Generate times of `skinsim view` (issue targets: the window's
# first frame <= 3 s, Generate <= 5 s at 2048^2, on 2 cores). Prints, per run:
# the wall time of a batch frame through EGL, the window's first frame under
# the caller's display (or a private Xvfb), Generate's own breakdown at
# --texture-size (default 2048) and its upload, with the load average, since
# on a shared machine wall time measures the queue as much as the program.
#   bench/view_startup.sh build/skinsim [runs] [texture-size]
# OMP_WAIT_POLICY is left to the viewer unless set: export
# OMP_WAIT_POLICY=active to see the spinning default's times; likewise
# GLIBC_TUNABLES=glibc.malloc.hugetlb=0 for the times without huge pages.
set -u
CLI=${1:-build/skinsim}
RUNS=${2:-3}
TS=${3:-2048}
T=$(mktemp -d /tmp/skinsim-bench-view-XXXXXX)
XPID=""
trap 'rm -rf "$T"; [ -n "$XPID" ] && kill "$XPID" 2>/dev/null' EXIT
export GTK_A11Y=none NO_AT_BRIDGE=1
if [ -z "${DISPLAY:-}" ] && command -v Xvfb >/dev/null; then
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$T/dpy" 2>/dev/null &
  XPID=$!
  for _ in $(seq 100); do [ -s "$T/dpy" ] && break; sleep 0.1; done
  [ -s "$T/dpy" ] && export DISPLAY=":$(head -1 "$T/dpy")"
fi
now() { date +%s.%N; }
printf 'key Escape\n' >"$T/esc.txt"
for r in $(seq "$RUNS"); do
  load=$(cut -d' ' -f1 /proc/loadavg)
  t0=$(now)
  "$CLI" view --egl --size 1280x720 --screenshot "$T/a.png" --quiet
  t1=$(now)
  egl=$(echo "$t1 - $t0" | bc)
  first="-"
  if [ -n "${DISPLAY:-}" ]; then
    t0=$(now)
    timeout 120 "$CLI" view --size 1280x720 --script "$T/esc.txt" 2>"$T/win.err"
    t1=$(now)
    first=$(sed -n 's/.*first frame \([0-9.]*\) s after start.*/\1/p' "$T/win.err")
    win=$(echo "$t1 - $t0" | bc)
  fi
  t0=$(now)
  "$CLI" view --egl --size 1280x720 --generate --texture-size "$TS" --time 5 \
    --screenshot "$T/g.png" 2>"$T/gen.err"
  t1=$(now)
  gen=$(sed -n 's/.*day 30 (\(.*\))$/\1/p' "$T/gen.err")
  up=$(sed -n 's/.*uploaded in \([0-9]*\) ms.*/\1/p' "$T/gen.err")
  printf 'run %d (load %s): EGL frame %.2f s; window first frame %s s (open to closed %.2f s); ' \
    "$r" "$load" "$egl" "$first" "${win:-0}"
  printf 'Generate %d^2 %s, upload %s ms, whole command %.2f s\n' "$TS" "$gen" "$up" \
    "$(echo "$t1 - $t0" | bc)"
done
