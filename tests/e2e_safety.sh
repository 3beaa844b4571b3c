#!/usr/bin/env bash
# End-to-end: the reproductions of issue 7 against the built command, each
# ending with the old output intact, the new output whole, or exit 2 before
# any work (docs/reliability.md). Full-disk and device-node cases need root
# (a small tmpfs, mknod) and are left out otherwise; the rest runs anywhere.
# Every command that could hang runs under `timeout`, so a hang is a failure.
set -u
# one thread: the runs are tiny, and spinning OpenMP barriers crawl on a loaded machine
export SKINSIM_THREADS=1
CLI="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
T=$(mktemp -d /tmp/skinsim-e2e-safety-XXXXXX)   # outputs only: listed by the checks
W=$(mktemp -d /tmp/skinsim-e2e-safety-w-XXXXXX) # the test's own scratch files
MNT=""
cleanup() {
  [ -n "$MNT" ] && umount "$MNT" 2>/dev/null
  rm -rf "$T" "$W"
}
trap cleanup EXIT
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
sk() { timeout 120 "$CLI" "$@"; }
# background runs call the command directly, so $! is its pid (kill -9, lock)
# exit 2 with a message containing $1; the rest is the command
expect2() {
  local words="$1"; shift
  timeout 20 "$CLI" "$@" >/dev/null 2>"$W/err.txt"
  local rc=$?
  if [ $rc -ne 2 ]; then bad "expected exit 2, got $rc: $* ($(cat "$W/err.txt"))"; return; fi
  if ! grep -qi -- "$words" "$W/err.txt"; then bad "message lacks '$words': $(cat "$W/err.txt")"; return; fi
  ok
}
only() { # the folder $1 holds exactly the names $2..
  local d="$1"; shift
  [ "$(ls -A "$d" | LC_ALL=C sort | tr '\n' ' ')" = "$* " ]
}

# ---- 1. re-running into an existing folder: whole or not at all ----------
sk abrasion --size 64 --times 0,1 --out "$T/a" --quiet
rc=$?
check '[ $rc -eq 0 ] && [ -f "$T/a/.skinsim-complete" ]' "first run"
sums "$T/a" >"$W/a.sums"
# killed mid-write (kill -9 as soon as the first new file appears)
"$CLI" abrasion --size 768 --times 0,1,5,12,20,30 --out "$T/a" --quiet & pid=$!
for _ in $(seq 1 2000); do
  ls "$T"/a.skinsim-staging.*/keys/*.png >/dev/null 2>&1 && break
  sleep 0.01
done
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
check '[ "$(sums "$T/a")" = "$(cat "$W/a.sums")" ]' "kill -9 during a re-run changed the old folder"
check 'ls -d "$T"/a.skinsim-staging.* >/dev/null 2>&1' "the killed run's staging should be there (test did not kill mid-write)"
# the next run recognises and removes the leftovers, and replaces the folder whole
sk abrasion --size 64 --times 0,5,20 --out "$T/a" --quiet
rc=$?
check '[ $rc -eq 0 ]' "run after a killed run"
check 'only "$T" a' "leftovers after the next run: $(ls -A "$T")"
check '[ -f "$T/a/frames/t20_color.png" ] && [ ! -e "$T/a/frames/t1_color.png" ]' "the new folder is not whole, or mixed with the old"
# a killed run into a new folder leaves nothing under the final name
"$CLI" abrasion --size 768 --times 0,1,5,12,20,30 --out "$T/n" --quiet & pid=$!
for _ in $(seq 1 2000); do
  ls "$T"/n.skinsim-staging.*/keys/*.png >/dev/null 2>&1 && break
  sleep 0.01
done
kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
check '[ ! -e "$T/n" ]' "a killed run left its folder under the final name"
sk abrasion --size 32 --times 1 --out "$T/n" --quiet
rc=$?
check '[ $rc -eq 0 ] && only "$T" a n' "leftovers of the killed new run: $(ls -A "$T")"
# ---- what only looks like a leftover is the user's: never touched (issue 21) ----
# the cleaner removes only what names a skinsim marker and a process that is
# gone, and (a folder) holds a skinsim marker; these have neither
L="$T/look"; mkdir -p "$L"
echo mine >"$L/s.csv.tmp.2024Q1"
mkdir "$L/run.partial-backup" "$L/res.skinsim-staging.mine" "$L/res.skinsim-backup.x"
echo mine >"$L/run.partial-backup/f"; echo mine >"$L/res.skinsim-staging.mine/f"
echo mine >"$L/res.skinsim-backup.x/f"
echo mine >"$L/X.skinsim-lock"
dead=$(sh -c 'echo $$')   # a process that is gone; a folder with its id but no marker stays too
mkdir "$L/run.skinsim-staging.$dead.AbC123"; echo mine >"$L/run.skinsim-staging.$dead.AbC123/f"
echo mine >"$L/s.csv.skinsim-lock" # the user's file at the lock's name: refused, kept
sums "$L" >"$W/look.sums"
expect2 "not a skinsim lock file" optics spectrum --photons 100 --wl-step 100 --out "$L/s.csv"
check '[ "$(sums "$L")" = "$(cat "$W/look.sums")" ] && [ ! -e "$L/s.csv" ]' "a user's s.csv.skinsim-lock was touched"
rm "$L/s.csv.skinsim-lock"; sums "$L" >"$W/look.sums"
sk optics spectrum --photons 100 --wl-step 100 --out "$L/s.csv" >/dev/null
rc1=$?
sk abrasion --size 32 --times 1 --out "$L/run" --quiet
rc2=$?
sk abrasion --size 32 --times 1 --out "$L/res" --quiet # res missing: the backup look-alike stays
rc3=$?
check '[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ] && [ $rc3 -eq 0 ]' "runs beside look-alikes: rc $rc1 $rc2 $rc3"
check '[ "$(sums "$L" | grep -v " ./s.csv$" | grep -v " ./run/" | grep -v " ./res/")" = "$(cat "$W/look.sums")" ]' "a user's look-alike was changed: $(ls -A "$L")"
check 'only "$L" X.skinsim-lock res res.skinsim-backup.x res.skinsim-staging.mine run run.partial-backup run.skinsim-staging.$dead.AbC123 s.csv s.csv.tmp.2024Q1' "look-alikes: $(ls -A "$L")"
check '[ -f "$L/res/.skinsim-complete" ] && [ ! -e "$L/res/f" ] && [ ! -e "$L/res/.skinsim-staging" ]' "res is not the new run's"
rm -rf "$L"

# ---- concurrent runs into one output: the second is refused -----------------
"$CLI" abrasion --size 256 --times 0,1,5 --out "$T/c" --quiet & pid=$!
for _ in $(seq 1 2000); do [ -e "$T/c.skinsim-lock" ] && break; sleep 0.01; done
expect2 "process $pid" abrasion --size 32 --times 1 --out "$T/c" --quiet
wait $pid
rc=$?
check '[ $rc -eq 0 ] && [ -f "$T/c/frames/t5_color.png" ] && [ -f "$T/c/.skinsim-complete" ]' "the first of two concurrent runs"
rm -rf "$T/c"

# ---- a folder that is not this command's finished output is never replaced
mkdir -p "$T/mine"; echo precious >"$T/mine/notes.txt"
expect2 "not a finished" abrasion --size 32 --times 1 --out "$T/mine"
check '[ "$(cat "$T/mine/notes.txt")" = precious ]' "a foreign folder was touched"
# heal into it: not a heal run, so neither --resume nor --force is offered
expect2 "not a 'skinsim heal' run folder" heal --days 0.1 --grid 10x10x6 --out "$T/mine"
check '! grep -q -- "--force" "$W/err.txt"' "heal suggests --force for a folder it then refuses"
# the finished output of another command: the message names whose it is
"$CLI" abrasion --size 32 --times 1 --out "$T/abr" --quiet || bad "abrasion into a new folder"
expect2 "is a finished 'skinsim abrasion' output folder, not a 'skinsim skin' one" \
    skin --size 16 --out "$T/abr"
rm -rf "$T/abr"
# an input inside the output folder would be lost with the old folder
printf '0.2,0.2\n0.5,0.2\n0.4,0.6\n' >"$T/a/strokes.csv"
expect2 "overwrite the input" abrasion --stroke "$T/a/strokes.csv" --size 32 --times 1 --out "$T/a"
rm -f "$T/a/strokes.csv"

# ---- 3. outputs that are not regular files: refused, never replaced --------
mkfifo "$T/pipe"
expect2 "named pipe" optics spectrum --photons 100 --wl-step 100 --out "$T/pipe"
expect2 "named pipe" optics swatch --photons 100 --out "$T/pipe"
expect2 "not a folder" abrasion --size 32 --out "$T/pipe"
check '[ -p "$T/pipe" ]' "the named pipe was replaced"
if [ "$(id -u)" = 0 ] && mknod "$T/null" c 1 3 2>/dev/null; then
  expect2 "character device" optics spectrum --photons 100 --wl-step 100 --out "$T/null"
  expect2 "character device" optics brdf --photons 100 --out "$T/null"
  expect2 "character device" optics swatch --photons 100 --out "$T/null"
  check '[ -c "$T/null" ]' "the device node was replaced"
fi
expect2 "same place" optics spectrum --photons 100 --wl-step 100 --out "$T/s.csv" --radial-out "$T/s.csv"
expect2 "same place" optics spectrum --photons 100 --wl-step 100 --out "$T/s.csv" --radial-out "$T/x/../s.csv"
check '[ ! -e "$T/s.csv" ]' "a refused spectrum wrote its output"

# .mci outputs: relative to the .mci's folder, never outside it, never the .mci
mkdir -p "$T/m/sub"
mci() { # name of the output
  printf '1.0\n1\n%s A\n2000\n0.01 0.01\n10 10 10\n1\n1.0\n1.0 10 90 0.75 0.02\n1.0\n' "$1"
}
mci out.mco >"$T/m/sub/in.mci"
(cd "$T" && sk optics mci m/sub/in.mci --quiet 2>/dev/null)
rc=$?
check '[ $rc -eq 0 ] && [ -s "$T/m/sub/out.mco" ] && [ ! -e "$T/out.mco" ]' ".mci output not in the .mci's folder"
mci in.mci >"$T/m/sub/self.mci"; sed -i 's/^in.mci/self.mci/' "$T/m/sub/self.mci"
cp "$T/m/sub/self.mci" "$W/self.copy"
expect2 "overwrite the input" optics mci "$T/m/sub/self.mci"
check 'cmp -s "$T/m/sub/self.mci" "$W/self.copy"' "an .mci naming itself was overwritten"
mci ../up.mco >"$T/m/sub/up.mci"
expect2 "allow-outside-paths" optics mci "$T/m/sub/up.mci"
check '[ ! -e "$T/m/up.mco" ]' "an .mci wrote outside its folder"
sk optics mci "$T/m/sub/up.mci" --allow-outside-paths --quiet 2>/dev/null
rc=$?
check '[ $rc -eq 0 ] && [ -s "$T/m/up.mco" ]' "--allow-outside-paths"
mci /etc/skinsim-e2e-test.mco >"$T/m/sub/etc.mci"
expect2 "leaves the folder" optics mci "$T/m/sub/etc.mci"
check '[ ! -e /etc/skinsim-e2e-test.mco ]' "an .mci wrote to /etc"
if [ -c "$T/null" ]; then
  mci "$T/null" >"$T/m/sub/dev.mci"
  expect2 "character device" optics mci "$T/m/sub/dev.mci" --allow-outside-paths
  check '[ -c "$T/null" ]' "an .mci replaced a device node"
fi

# ---- 4. bad outputs are exit 2 before any work ------------------------------
# (a billion photons would take hours: returning at all means before the work)
HUGE="--photons 1000000000"
expect2 "empty" optics spectrum $HUGE --out ""
expect2 "is a folder" optics spectrum $HUGE --out "$T"
expect2 "names a folder" optics brdf $HUGE --out "$T/m/"
long=$(printf 'x%.0s' $(seq 1 5000))
expect2 "too long" optics spectrum $HUGE --out "$T/$long.csv"
ln -s "$T/nowhere/x.csv" "$T/broken.csv"
expect2 "broken symbolic link" optics spectrum $HUGE --out "$T/broken.csv"
expect2 "empty" abrasion --size 16384 --out ""
check '[ ! -e /area.csv ] && [ ! -e /contact_sheet.png ]' "something was written into /"

# ---- 5. inputs that would hang or blow memory --------------------------------
mkfifo "$T/in.csv" "$T/in.png" "$T/in.json" "$T/in.mci" "$T/in.sstab"
expect2 "named pipe" abrasion --stroke "$T/in.csv" --size 32 --out "$T/x1"
expect2 "named pipe" abrasion --mask "$T/in.png" --size 32 --out "$T/x2"
expect2 "named pipe" abrasion --timeline "$T/in.json" --size 32 --out "$T/x3"
expect2 "named pipe" abrasion --upper "$T/in.png" --size 32 --out "$T/x4"
expect2 "named pipe" abrasion --lower "$T/in.png" --size 32 --out "$T/x5"
expect2 "named pipe" optics mci "$T/in.mci"
expect2 "named pipe" optics table --lookup "$T/in.sstab"
expect2 "named pipe" heal --wound-mask "$T/in.png" --days 1 --out "$T/x6"
expect2 "named pipe" heal --stroke "$T/in.csv" --days 1 --out "$T/x7"
expect2 "named pipe" heal --params "$T/in.json" --days 1 --out "$T/x8"
expect2 "named pipe" heal --wound-mesh "$T/in.csv" --days 1 --out "$T/x9"
check 'only "$T" a broken.csv in.csv in.json in.mci in.png in.sstab m mine n null pipe || only "$T" a broken.csv in.csv in.json in.mci in.png in.sstab m mine n pipe' "outputs of refused runs: $(ls -A "$T")"
# a 68-byte PNG whose header claims 30000 x 30000 pixels
python3 - "$T/bomb.png" <<'PY'
import struct, sys, zlib
def chunk(t, d): return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 30000, 30000, 8, 2, 0, 0, 0))
png += chunk(b"IDAT", zlib.compress(b"\0" * 4)) + chunk(b"IEND", b"")
open(sys.argv[1], "wb").write(png)
PY
check '[ "$(stat -c %s "$T/bomb.png")" -lt 100 ]' "the PNG bomb is not small"
expect2 "30000 x 30000" abrasion --mask "$T/bomb.png" --size 32 --out "$T/x10"
expect2 "30000 x 30000" abrasion --upper "$T/bomb.png" --size 32 --out "$T/x11"
# the same under a memory limit (ulimit -v): still exit 2, not 1 (not with
# AddressSanitizer, whose shadow memory cannot start under such a limit)
if ! ldd "$CLI" 2>/dev/null | grep -q libasan; then
  ( ulimit -v 2000000; exec timeout 20 "$CLI" abrasion --mask "$T/bomb.png" --size 32 --out "$T/x12" ) 2>"$W/err.txt"
  rc=$?
  check '[ $rc -eq 2 ] && grep -q "30000 x 30000" "$W/err.txt"' "PNG bomb under ulimit -v: $(cat "$W/err.txt")"
fi

# ---- 6. smaller gaps ---------------------------------------------------------
for v in abc 0 -1 2x 4096; do
  SKINSIM_THREADS=$v expect2 "SKINSIM_THREADS" abrasion --size 32 --times 1 --out "$T/x13"
done
expect2 "both name the frame" abrasion --size 32 --times 1,1.0000001 --out "$T/x14"
printf '0.2,0.2,2147483647\n0.5,0.2,2147483647\n0.4,0.6,2147483647\n' >"$T/id.csv"
expect2 "out of range" abrasion --stroke "$T/id.csv" --size 32 --out "$T/x15"
check '[ ! -e "$T/x13" ] && [ ! -e "$T/x14" ] && [ ! -e "$T/x15" ]' "refused runs wrote output"

# ---- a full disk (a small tmpfs; root only) ------------------------------------
if [ "$(id -u)" = 0 ] && mkdir -p "$T/disk" && mount -t tmpfs -o size=3m tmpfs "$T/disk" 2>/dev/null; then
  MNT="$T/disk"
  sk abrasion --size 64 --times 0,1 --out "$T/disk/a" --quiet
  sums "$T/disk/a" >"$W/disk.sums"
  # the estimate does not fit: exit 2 before any work, old folder as it was
  expect2 "MB are free" abrasion --size 512 --times 0,1,5 --out "$T/disk/a" --quiet
  check '[ "$(sums "$T/disk/a")" = "$(cat "$W/disk.sums")" ] && only "$T/disk" a' "full disk (estimate) touched the old folder"
  # the estimate fits but the disk fills during the run (another writer)
  "$CLI" abrasion --size 256 --times 0,1,5 --out "$T/disk/a" --quiet 2>"$W/err.txt" & pid=$!
  for _ in $(seq 1 2000); do ls -d "$T"/disk/a.skinsim-staging.* >/dev/null 2>&1 && break; sleep 0.005; done
  head -c 10000000 /dev/zero >"$T/disk/filler" 2>/dev/null
  wait $pid; rc=$?
  echo "full disk during the run: exit $rc ($(head -c 300 "$W/err.txt"))"
  if [ $rc -eq 0 ]; then
    check '[ -f "$T/disk/a/.skinsim-complete" ] && [ -f "$T/disk/a/frames/t5_color.png" ]' "full disk: exit 0 but not whole"
  else
    check '[ $rc -eq 1 ] && [ "$(sums "$T/disk/a")" = "$(cat "$W/disk.sums")" ]' "full disk mid-run: rc $rc, old folder changed"
    check 'only "$T/disk" a filler' "full disk mid-run left: $(ls -A "$T/disk")"
  fi
  rm -f "$T/disk/filler"
  sk abrasion --size 64 --times 0,5 --out "$T/disk/a" --quiet
  rc=$?
  check '[ $rc -eq 0 ] && only "$T/disk" a && [ -f "$T/disk/a/frames/t5_color.png" ]' "run after a full disk"
fi

echo "e2e_safety: $pass checks passed, $fail failed"
[ $fail -eq 0 ]
