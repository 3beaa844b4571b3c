#!/usr/bin/env bash
# End-to-end: issue 7's heal reproductions (docs/reliability.md). --force over
# a previous run is whole or not at all (kill -9, full disk); a killed new run
# is never taken for finished nor run into again without --force, and resumes
# exactly; a checkpoint of another run (scenario, grid) is exit 2 with nothing
# of the run touched; two runs into one folder; disk estimates before work.
# The full-disk part needs root (a small tmpfs) and is left out otherwise.
set -u
CLI="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
T=$(mktemp -d /tmp/skinsim-e2e-sheal-XXXXXX)   # outputs only
W=$(mktemp -d /tmp/skinsim-e2e-sheal-w-XXXXXX) # the test's scratch files
MNT=""
cleanup() {
  [ -n "$MNT" ] && umount "$MNT" 2>/dev/null
  rm -rf "$T" "$W"
}
trap cleanup EXIT
export SKINSIM_THREADS=1
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
expect2() {
  local words="$1"; shift
  timeout 60 "$CLI" "$@" >/dev/null 2>"$W/err.txt"
  local rc=$?
  if [ $rc -ne 2 ]; then bad "expected exit 2, got $rc: $* ($(cat "$W/err.txt"))"; return; fi
  if ! grep -qi -- "$words" "$W/err.txt"; then bad "message lacks '$words': $(cat "$W/err.txt")"; return; fi
  ok
}
# wait (up to 20 s) until the glob $1 matches
await() { for _ in $(seq 1 2000); do compgen -G "$1" >/dev/null && return 0; sleep 0.01; done; return 1; }
SMALL="--grid 20x20x6 --size-mm 10,10,3 --quiet"

# ---- a previous run, replaced with --force: whole or not at all ------------
"$CLI" heal $SMALL --days 1 --out "$T/h"
check '[ -f "$T/h/.skinsim-complete" ] && [ -f "$T/h/run.json" ]' "first heal run"
sums "$T/h" >"$W/h.sums"
expect2 "previous run" heal $SMALL --days 1 --out "$T/h"
"$CLI" heal $SMALL --days 40 --snapshot-every 0.5 --force --out "$T/h" & pid=$!
await "$T/h.skinsim-staging.*/fields/fields_0003.vti" || bad "the --force run never wrote"
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
check '[ "$(sums "$T/h")" = "$(cat "$W/h.sums")" ]' "kill -9 of heal --force changed the previous run"
"$CLI" heal $SMALL --days 2 --force --out "$T/h"
rc=$?
check '[ $rc -eq 0 ] && [ "$(ls -A "$T")" = h ]' "heal --force after a killed one: rc $rc, left $(ls -A "$T")"
check 'grep -q "\"days\":	2" "$T/h/summary.json" && [ ! -e "$T/h/fields/fields_0003.vti" ]' "the replaced run is not whole"

# ---- a killed new run: unfinished, refused without --force, resumed exactly ----
"$CLI" heal $SMALL --days 3 --checkpoint-every 0.5 --out "$T/u" & pid=$!
await "$T/u/checkpoints/ckpt_*.sshc" || bad "the run never checkpointed"
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
if [ -f "$T/u/.skinsim-complete" ]; then
  echo "note: the run finished before the kill"
else
  check '[ -f "$T/u/.skinsim-unfinished" ] && [ ! -e "$T/u/summary.json" ]' "a killed run does not look unfinished"
  expect2 "unfinished run" heal $SMALL --days 3 --out "$T/u"
fi
"$CLI" heal --resume "$T/u" --quiet
rc=$?
check '[ $rc -eq 0 ] && [ -f "$T/u/.skinsim-complete" ] && [ ! -e "$T/u/.skinsim-unfinished" ]' "resume of the killed run: rc $rc"
"$CLI" heal $SMALL --days 3 --checkpoint-every 0.5 --out "$T/ref"
check 'cmp -s "$T/u/area.csv" "$T/ref/area.csv"' "resumed run differs from an uninterrupted one"

# ---- resume refuses checkpoints of another run, touching nothing ----------------
"$CLI" heal $SMALL --scenario keloid --days 4 --checkpoint-every 0.5 --out "$T/k"
"$CLI" heal --grid 24x24x6 --size-mm 12,12,3 --quiet --days 2 --checkpoint-every 0.5 --out "$T/g"
newest=$(ls "$T/k/checkpoints" | tail -1)
cp "$T/k/checkpoints/$newest" "$T/ref/checkpoints/"
sums "$T/ref" >"$W/ref.sums"
expect2 "another run" heal --resume "$T/ref" --days 5
check '[ "$(sums "$T/ref")" = "$(cat "$W/ref.sums")" ]' "a foreign (keloid) checkpoint: the run was touched"
rm "$T/ref/checkpoints/$newest"
cp "$T/g/checkpoints/$(ls "$T/g/checkpoints" | head -1)" "$T/ref/checkpoints/ckpt_000000000001.sshc"
sums "$T/ref" >"$W/ref.sums"
expect2 "another run" heal --resume "$T/ref" --days 5
check '[ "$(sums "$T/ref")" = "$(cat "$W/ref.sums")" ]' "a foreign (grid) checkpoint: the run was touched"
rm "$T/ref/checkpoints/ckpt_000000000001.sshc"
"$CLI" heal --resume "$T/ref" --days 4 --quiet
check '[ $? -eq 0 ] && grep -q "\"scenario\":	\"clean\"" "$T/ref/summary.json"' "resume with its own checkpoints"

# ---- a resumed run's summary.json is the uninterrupted one's, byte for byte --------
# (but the wall time, the thread count and the resume's record); t50 and t95
# interpolate the area rows restored from the checkpoint, which must read
# back bit for bit (issue 21: t50 5.334857047685207 against ...208)
nosum() { grep -v '"wall_time_s"\|"resumed_from_step"\|"threads"' "$1"; }
"$CLI" heal $SMALL --days 6 --checkpoint-every 0.5 --out "$T/r6"
"$CLI" heal $SMALL --days 3 --checkpoint-every 0.5 --out "$T/s6"
"$CLI" heal --resume "$T/s6" --days 6 --quiet
check 'grep -q "time_to_50pct_closure_days\":	[0-9]" "$T/r6/summary.json" && cmp -s <(nosum "$T/r6/summary.json") <(nosum "$T/s6/summary.json")' "resumed summary.json differs: $(diff <(nosum "$T/r6/summary.json") <(nosum "$T/s6/summary.json") | head -4)"
rm -rf "$T/r6" "$T/s6"

# ---- issue 21: a resume proves every checkpoint is the run's (run id + identity) ----
# run.json gone and another grid's checkpoints copied in: refused, nothing changed
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --out "$T/i"
cp -r "$T/i" "$T/i2"
rm "$T/i/run.json"; cp "$T/g/checkpoints/"* "$T/i/checkpoints/"
sums "$T/i" >"$W/i.sums"
expect2 "run.json is missing" heal --resume "$T/i" --days 3
check '[ "$(sums "$T/i")" = "$(cat "$W/i.sums")" ] && [ ! -e "$T/i/fields/fields_0002.vti" ]' "run.json gone: the run was touched"
# keloid checkpoints into a clean run (its run.json there): refused, named
cp "$T/k/checkpoints/"* "$T/i2/checkpoints/"
sums "$T/i2" >"$W/i.sums"
expect2 "belongs to another run" heal --resume "$T/i2" --days 3
check '[ "$(sums "$T/i2")" = "$(cat "$W/i.sums")" ]' "keloid checkpoints: the run was touched"
# a checkpoint of an identical set-up but another run (same grid, scenario, parameters)
rm -rf "$T/i2"; cp -r "$T/ref" "$T/i2"; rm -f "$T/i2/checkpoints/"*
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --out "$T/twin"
cp "$T/twin/checkpoints/$(ls "$T/twin/checkpoints" | head -1)" "$T/i2/checkpoints/"
cp "$T/ref/checkpoints/"* "$T/i2/checkpoints/" 2>/dev/null
sums "$T/i2" >"$W/i.sums"
expect2 "run id" heal --resume "$T/i2" --days 5
check '[ "$(sums "$T/i2")" = "$(cat "$W/i.sums")" ]' "a twin run's checkpoint: the run was touched"
# a run folder from before run ids: refused with what to do
rm -rf "$T/i2"; cp -r "$T/ref" "$T/i2"
sed -i -e '/"run_id"/d' -e '/"identity"/d' "$T/i2/run.json"
sums "$T/i2" >"$W/i.sums"
expect2 "before run ids.*--force" heal --resume "$T/i2" --days 5
check '[ "$(sums "$T/i2")" = "$(cat "$W/i.sums")" ]' "an old run folder was touched"
rm -rf "$T/i" "$T/i2" "$T/twin"

# ---- a checkpoint piece that is a named pipe: exit 2 at once, not a hang ----------
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --checkpoint-pieces 2x1x1 --out "$T/p"
for piece in "$T"/p/checkpoints/ckpt_*_p000001.sshp; do rm "$piece"; mkfifo "$piece"; done
timeout 20 "$CLI" heal --resume "$T/p" --days 2 --quiet 2>"$W/err.txt"
rc=$?
check '[ $rc -eq 2 ] && grep -q "named pipe" "$W/err.txt"' "a pipe as checkpoint piece: rc $rc ($(cat "$W/err.txt"))"
rm -rf "$T/p"

# ---- wound --heal: its folder checked before work, never written into (issue 21) ----
"$CLI" heal $SMALL --days 2 --out "$T/wh"
sums "$T/wh" >"$W/wh.sums"
expect2 "inside the input folder" wound --heal "$T/wh" --days 0,2 --size 32 --out "$T/wh/new" --quiet
check '[ "$(sums "$T/wh")" = "$(cat "$W/wh.sums")" ] && [ ! -e "$T/wh/new" ]' "wound --out inside --heal: written into"
"$CLI" heal --grid 24x24x6 --size-mm 12,12,3 --quiet --days 2 --out "$T/wg"
snap="$T/wc/fields/fields_0002.vti"
for how in truncated garbage extent grid; do
  rm -rf "$T/wc"; cp -r "$T/wh" "$T/wc"
  case $how in
    truncated) head -c 3000 "$T/wh/fields/fields_0002.vti" >"$snap" ;;
    garbage) head -c 3000 /dev/urandom >"$snap" ;;
    extent) sed -i '0,/WholeExtent="0 20 0 20/s//WholeExtent="0 2000000 0 2000000/' "$snap" ;;
    grid) cp "$T/wg/fields/fields_0002.vti" "$snap" ;;
  esac
  expect2 "fields_0002.vti" wound --heal "$T/wc" --days 0,1,2 --size 32 --out "$T/wout" --quiet
  check '[ ! -e "$T/wout" ]' "a $how snapshot: wound wrote $T/wout"
done
rm -rf "$T/wh" "$T/wg" "$T/wc"
expect2 "out of range" heal $SMALL --days 1 --threads 0 --out "$T/t0"
check '[ ! -e "$T/t0" ]' "heal --threads 0 wrote"

# ---- two runs into one new folder at once ---------------------------------------
"$CLI" heal $SMALL --days 40 --out "$T/two" & pid=$!
await "$T/two.skinsim-lock" || bad "no lock file"
expect2 "process $pid" heal $SMALL --days 1 --out "$T/two"
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null

# ---- bad outputs and disk estimates: exit 2 before any work ----------------------
expect2 "empty" heal --days 1 --out ""
mkfifo "$T/pipe"
expect2 "named pipe" heal --days 1 --out "$T/pipe"
expect2 "of disk" heal --days 1000000 --out "$T/big"
check '[ ! -e "$T/big" ] && [ -p "$T/pipe" ]' "refused heal runs left output"

# ---- full disk (root: a small tmpfs) ------------------------------------------------
if [ "$(id -u)" = 0 ] && mkdir -p "$T/disk" && mount -t tmpfs -o size=8m tmpfs "$T/disk" 2>/dev/null; then
  MNT="$T/disk"
  "$CLI" heal $SMALL --days 1 --out "$T/disk/h"
  sums "$T/disk/h" >"$W/disk.sums"
  expect2 "free" heal $SMALL --days 200 --snapshot-every 0.1 --force --out "$T/disk/h"
  check '[ "$(sums "$T/disk/h")" = "$(cat "$W/disk.sums")" ]' "full disk (estimate) touched the previous run"
  # the estimate fits, the disk fills during the run (another writer)
  "$CLI" heal $SMALL --days 8 --force --out "$T/disk/h" 2>"$W/err.txt" & pid=$!
  await "$T/disk/h.skinsim-staging.*/fields/fields_0001.vti"
  head -c 20000000 /dev/zero >"$T/disk/filler" 2>/dev/null
  wait $pid; rc=$?
  echo "heal --force on a disk filling up: exit $rc ($(head -c 200 "$W/err.txt"))"
  if [ $rc -ne 0 ]; then
    check '[ $rc -eq 1 ] && [ "$(sums "$T/disk/h")" = "$(cat "$W/disk.sums")" ]' "full disk mid-run: the previous run changed"
    check '[ "$(ls -A "$T/disk" | tr "\n" " ")" = "filler h " ]' "full disk mid-run left: $(ls -A "$T/disk")"
  else
    check '[ -f "$T/disk/h/.skinsim-complete" ]' "full disk: exit 0 but not whole"
  fi
fi

echo "e2e_safety_heal: $pass checks passed, $fail failed"
[ $fail -eq 0 ]
