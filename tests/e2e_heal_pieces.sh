#!/usr/bin/env bash
# End-to-end test of the healing grid in pieces (docs/heal-outputs.md
# "Checkpoints in pieces", docs/scaling.md): `skinsim heal --checkpoint-pieces`
# writes each checkpoint as per-box pieces under a header; --resume from them
# (and from a folder mixing both kinds, and after the newest is damaged) ends
# bit-identical to the uninterrupted run; bad input (no usable piece
# checkpoint, a malformed or impossible split) exits 2 naming the input with
# nothing written. Under mpirun (when built with MPI) `skinsim wound --heal`
# reads a run folder with only .pvti + pieces: equal frames to the gathered
# .vti when the pieces carry closure days, else exit 2 naming the snapshot.
# usage: e2e_heal_pieces.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
count() { ls "$@" 2>/dev/null | wc -l; }
tree_sum() { (cd "$1" && find . -type f | sort | xargs md5sum) | md5sum; }
SMALL="--grid 24x20x8 --scenario scab --snapshot-every 1 --quiet --threads 1"

"$CLI" heal $SMALL --days 2 --out "$T/a" || fail "reference run failed"

# --- checkpoints in 2x2x1 pieces, resumed to the end: the same bytes
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --checkpoint-pieces 2x2x1 --out "$T/b" ||
    fail "run with checkpoint pieces failed"
[ "$(count "$T"/b/checkpoints/ckpt_*.sshh)" -eq 2 ] || fail "expected the 2 newest piece headers"
[ "$(count "$T"/b/checkpoints/ckpt_*_p*.sshp)" -eq 8 ] || fail "expected 2 x 4 pieces"
[ "$(count "$T"/b/checkpoints/ckpt_*.sshc)" -eq 0 ] || fail "a whole-grid checkpoint was written"
cp -r "$T/b" "$T/b2"
cp -r "$T/b" "$T/b3"
"$CLI" heal --resume "$T/b" --days 2 --quiet || fail "resume from pieces failed"
for f in fields/fields_0002.vti area.csv; do
    cmp -s "$T/a/$f" "$T/b/$f" || fail "resumed from pieces: $f differs from the uninterrupted run"
done

# --- the newest piece checkpoint damaged (a flipped byte): the older one is used
newest=$(ls "$T"/b2/checkpoints/ckpt_*_p000001.sshp | tail -1)
printf '\x55' | dd of="$newest" bs=1 seek=600 conv=notrunc status=none
"$CLI" heal --resume "$T/b2" --days 2 >/dev/null 2>"$T/b2.err" || fail "resume past a damaged piece failed"
grep -q "$(basename "$newest")" "$T/b2.err" || fail "the skipped piece is not named: $(cat "$T/b2.err")"
cmp -s "$T/a/fields/fields_0002.vti" "$T/b2/fields/fields_0002.vti" ||
    fail "resumed past a damaged piece: final state differs"

# --- a folder with both kinds: a whole-grid checkpoint at day 0.5, then (the
# run resumed with --checkpoint-pieces) pieces at day 1, all of the run's own
# (a copy of another run's would be refused: docs/reliability.md): the newest
# (the pieces) is used; the resumed run writes whole-grid checkpoints (no
# --checkpoint-pieces) and pruning keeps the newest two of either kind
"$CLI" heal $SMALL --days 0.5 --checkpoint-every 0.5 --out "$T/c" || fail "whole-checkpoint run failed"
"$CLI" heal --resume "$T/c" --days 1 --checkpoint-pieces 2x2x1 --quiet || fail "piece-checkpoint resume failed"
[ "$(count "$T"/c/checkpoints/*.sshh)" -eq 1 ] || fail "no piece checkpoint at day 1: $(ls "$T"/c/checkpoints)"
cp -r "$T/c" "$T/c2"
"$CLI" heal --resume "$T/c" --days 2 --quiet || fail "resume of the mixed folder failed"
# (its state is not compared with run a's: the stop at day 0.5 lands the
# adaptive steps differently)
[ "$(count "$T"/c/checkpoints/*)" -eq 2 ] && [ "$(count "$T"/c/checkpoints/*.sshc)" -eq 2 ] ||
    fail "pruning should leave the newest 2 (whole-grid) checkpoints: $(ls "$T"/c/checkpoints)"
# its pieces truncated: the whole-grid one of day 0.5 is used
p=$(ls "$T"/c2/checkpoints/*_p000003.sshp)
head -c 700 "$p" >"$p.cut" && mv "$p.cut" "$p"
"$CLI" heal --resume "$T/c2" --days 2 >/dev/null 2>"$T/c2.err" || fail "resume past truncated pieces failed"
grep -q "$(basename "$p")" "$T/c2.err" || fail "the truncated piece is not named: $(cat "$T/c2.err")"
[ -f "$T/c2/fields/fields_0002.vti" ] || fail "resumed past truncated pieces: no final state"

# --- bad input: exit 2, the file named, nothing written
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --checkpoint-pieces 3x1x1 --out "$T/d" ||
    fail "3x1x1 run failed"
for h in "$T"/d/checkpoints/ckpt_*.sshh; do rm -f "${h%.sshh}_p000002.sshp"; done
before=$(tree_sum "$T/d")
"$CLI" heal --resume "$T/d" --days 2 --quiet 2>"$T/d.err"
[ $? -eq 2 ] || fail "resume with a piece missing from every checkpoint should exit 2"
grep -q "_p000002.sshp" "$T/d.err" || fail "the missing piece is not named: $(cat "$T/d.err")"
grep -q "missing" "$T/d.err" || fail "the error does not say the piece is missing"
[ "$before" = "$(tree_sum "$T/d")" ] || fail "a refused resume changed the folder"
"$CLI" heal $SMALL --days 1 --checkpoint-pieces 0x1x1 --out "$T/e" 2>"$T/e.err"
[ $? -eq 2 ] || fail "--checkpoint-pieces 0x1x1 should exit 2"
grep -q -- "--checkpoint-pieces" "$T/e.err" || fail "the option is not named"
"$CLI" heal $SMALL --days 1 --checkpoint-every 0.5 --checkpoint-pieces 25x1x1 --out "$T/e" 2>"$T/e.err"
[ $? -eq 2 ] || fail "more pieces than the grid has cells should exit 2"
grep -q "25x1x1" "$T/e.err" || fail "the impossible split is not named: $(cat "$T/e.err")"
[ ! -e "$T/e" ] || fail "a refused run left its folder"

# --- wound --heal on a run folder with only .pvti + pieces (made on 2 MPI ranks):
# the frames equal those from the single-process run's gathered .vti
if command -v mpirun >/dev/null && "$CLI" --version | grep -q "with MPI"; then
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
    SQ="--grid 20x20x8 --scenario scab --days 2 --adapt-tol 0 --quiet --threads 1"
    W="--days 0,1,2 --size 32 --quiet --threads 1"
    "$CLI" heal $SQ --out "$T/s" || fail "single-process heal failed"
    "$CLI" wound --heal "$T/s" $W --out "$T/ws" || fail "wound --heal on the single-process run failed"
    mpirun --oversubscribe --allow-run-as-root --mca btl self,vader --mca mpi_yield_when_idle 1 \
        -np 2 "$CLI" heal $SQ --out "$T/m" || fail "heal on 2 ranks failed"
    [ "$(count "$T"/m/fields/fields_????.pvti)" -eq 3 ] || fail "expected 3 .pvti on 2 ranks"
    cp -r "$T/m" "$T/mp"
    rm -f "$T"/mp/fields/fields_????.vti # the gathered snapshots, where the driver writes them
    if grep -laq 'Name="closed_day"' "$T"/mp/fields/fields_0000_p*.vti; then
        "$CLI" wound --heal "$T/mp" $W --out "$T/wp" || fail "wound --heal on .pvti pieces failed"
        for f in "$T"/ws/frames/*; do
            cmp -s "$f" "$T/wp/frames/$(basename "$f")" ||
                fail "wound --heal on pieces: $(basename "$f") differs from the single-process run's"
        done
    else # pieces without closure days: refused before anything is written
        "$CLI" wound --heal "$T/mp" $W --out "$T/wp" 2>"$T/wp.err"
        [ $? -eq 2 ] || fail "wound --heal on pieces without closure days should exit 2"
        grep -q "fields_0000.pvti" "$T/wp.err" || fail "the snapshot is not named: $(cat "$T/wp.err")"
        [ ! -e "$T/wp" ] || fail "a refused wound --heal left its folder"
        echo "note: the MPI driver's pieces carry no closed_day; wound --heal on pieces refused (exit 2)"
    fi
    # a piece of day 1 missing: exit 2 naming it, nothing written
    src=$(grep -o 'Source="[^"]*"' "$T/mp/fields/fields_0001.pvti" | tail -1 | cut -d'"' -f2)
    [ -n "$src" ] && rm "$T/mp/fields/$src" || fail "fields_0001.pvti names no piece"
    "$CLI" wound --heal "$T/mp" $W --out "$T/wq" 2>"$T/wq.err"
    [ $? -eq 2 ] || fail "wound --heal with a missing piece should exit 2"
    grep -q "$src" "$T/wq.err" || fail "the missing piece is not named: $(cat "$T/wq.err")"
    [ ! -e "$T/wq" ] || fail "a refused wound --heal left its folder"
else
    echo "note: no mpirun or no MPI build: the MPI part is skipped (test_heal_pieces covers .pvti)"
fi
echo "ok"
