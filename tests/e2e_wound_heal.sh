#!/usr/bin/env bash
# End-to-end test of `skinsim wound --heal DIR`: a finished `skinsim heal` run
# folder is rendered instead of simulating again. Its snapshots hold the full
# state and the closure day of every column (which no field holds), so the
# frames equal those of `skinsim wound` running the same problem itself, byte
# for byte, on every day, also after margin columns have closed. Bad input: a folder of another version,
# an unfinished one, a folder that is not a heal run, days outside the run or
# between its snapshots, heal options next to --heal, --mechanics on a run
# without it, a damaged snapshot: exit 2 naming the input, nothing written.
# usage: e2e_wound_heal.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"

printf 'u,v\n0.25,0.3\n0.7,0.22\n0.78,0.6\n0.45,0.8\n0.2,0.62\n' >"$T/stroke.csv"
PROB="--scenario scab --grid 24x24x8 --stroke $T/stroke.csv"
"$CLI" heal $PROB --adapt-tol 0 --days 4 --quiet --out "$T/h" || fail "heal run failed"
grep -q '"format":[[:space:]]*1' "$T/h/run.json" || fail "run.json has no format stamp"

# --- the frames equal an in-memory run of the same problem (margins close from day 3)
"$CLI" wound --heal "$T/h" --days 0,1,3,4 --size 48 --quiet --out "$T/a" --json >"$T/a.json" ||
    fail "wound --heal failed"
"$CLI" wound $PROB --adapt-tol 0 --days 0,1,3,4 --size 48 --quiet --out "$T/b" || fail "wound (in memory) failed"
for d in 0 1 3 4; do
    for m in base_color roughness height normal; do
        cmp -s "$T/a/frames/t${d}_$m.png" "$T/b/frames/t${d}_$m.png" ||
            fail "day $d $m differs between --heal and the in-memory run"
    done
done
cmp -s "$T/a/contact_sheet.png" "$T/b/contact_sheet.png" || fail "contact sheets differ"
/usr/bin/python3 - "$T/a/timeline.json" "$T/h" <<'PY' || fail "timeline.json"
import json, sys
t = json.load(open(sys.argv[1]))
assert t["scenario"] == "scab" and t["heal_dir"] == sys.argv[2], t
assert [f["day"] for f in t["frames"]] == [0, 1, 3, 4]
PY
# the last day alone (no earlier snapshot read) gives the same frame; the heal folder is untouched
before=$(cd "$T/h" && find . -type f -exec md5sum {} + | sort)
"$CLI" wound --heal "$T/h" --days 4 --size 48 --quiet --no-compare --out "$T/c" ||
    fail "wound --heal at the last day failed"
cmp -s "$T/c/frames/t4_base_color.png" "$T/a/frames/t4_base_color.png" ||
    fail "day 4 alone differs from day 4 in a sequence"
after=$(cd "$T/h" && find . -type f -exec md5sum {} + | sort)
[ "$before" = "$after" ] || fail "wound --heal changed the heal folder"

# --- bad inputs: exit 2, a message naming the input, nothing written
cp -r "$T/h" "$T/old"
sed -i '/"format"/d' "$T/old/run.json"          # a folder of an earlier version
cp -r "$T/h" "$T/unfinished"
rm "$T/unfinished/.skinsim-complete"
touch "$T/unfinished/.skinsim-unfinished"
cp -r "$T/h" "$T/nomarker"
rm "$T/nomarker/.skinsim-complete"
cp -r "$T/h" "$T/damaged"
head -c 2000 "$T/h/fields/fields_0000.vti" >"$T/damaged/fields/fields_0000.vti"
cp -r "$T/h" "$T/nosummary"
rm "$T/nosummary/summary.json"
mkdir -p "$T/empty"
bad_cases=(
    "--heal $T/old --days 0|$T/old"
    "--heal $T/unfinished --days 0|incomplete"
    "--heal $T/nomarker --days 0|$T/nomarker"
    "--heal $T/damaged --days 0|fields_0000.vti"
    "--heal $T/nosummary --days 0|summary.json"
    "--heal $T/empty --days 0|$T/empty"
    "--heal $T/missing --days 0|$T/missing"
    "--heal $T/h --days 0,9|day 9"
    "--heal $T/h --days 0,1.5|1.5"
    "--heal $T/h --days 0 --scenario clean|--heal"
    "--heal $T/h --days 0 --adapt-tol 0.01|--heal"
    "--heal $T/h --days 0 --mechanics|--mechanics"
)
for case in "${bad_cases[@]}"; do
    args=${case%|*}
    want=${case##*|}
    "$CLI" wound --size 32 --quiet $args --out "$T/bad" 2>"$T/err.txt"
    rc=$?
    [ $rc -eq 2 ] || fail "'$args' exited $rc, expected 2"
    grep -qF -- "$want" "$T/err.txt" || fail "'$args': message does not name '$want': $(cat "$T/err.txt")"
    [ ! -e "$T/bad" ] || fail "'$args' left $T/bad behind"
done
echo "e2e_wound_heal: all checks passed"
