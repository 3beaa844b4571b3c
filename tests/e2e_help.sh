#!/usr/bin/env bash
# Every subcommand's --help ends with a working example: the text after its
# last "Example" line is one command (backslash continuations joined), which
# is run from a scratch folder holding the repository's data/ (as a user in a
# fresh clone would) and must exit 0. `view` opens a window: its example is
# only checked to be there. Also: a misspelt option gets a "did you mean"
# naming the right one, the one default per option of optics swatch, and
# `heal --help` listing --wound-mesh once.
# SKINSIM_TEST_QUICK (the sanitizer build) runs the fast examples only.
# usage: e2e_help.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2
ln -s "$SRC/data" "$T/data"
for c in abrasion heal wound skin view "optics" "optics spectrum" "optics brdf" "optics mci" \
         "optics swatch" "optics fit" "optics table" "optics match"; do
    # shellcheck disable=SC2086
    help=$("$CLI" $c --help 2>&1)
    rc=$?
    if [ "$c" = view ] && [ $rc -ne 0 ]; then echo "skip view: no viewer in this build"; continue; fi
    [ $rc -eq 0 ] || { bad "$c --help exits $rc"; continue; }
    ex=$(printf '%s\n' "$help" | awk '/^Example/{buf=""; on=1; next} on{buf=buf $0 "\n"} END{printf "%s", buf}' |
         sed -e ':a' -e '/\\$/N; s/\\\n//; ta' | sed 's/^ *//' | grep -v '^$')
    [ -n "$ex" ] || { bad "$c --help does not end with an example"; continue; }
    [ "$(printf '%s\n' "$ex" | wc -l)" -eq 1 ] || { bad "$c: more than one line after Example: $ex"; continue; }
    case "$ex" in "skinsim $c "*|"cp "*"&& skinsim $c "*) ;; *) bad "$c: the example is not a '$c' command: $ex"; continue;; esac
    [ "$c" = view ] && { echo "ok   view (example present, not run: it opens a window)"; continue; }
    if [ -n "${SKINSIM_TEST_QUICK:-}" ] && case "$c" in heal|wound|skin|"optics brdf"|"optics fit") true;; *) false;; esac; then
        echo "skip running the $c example under SKINSIM_TEST_QUICK"; continue
    fi
    run=${ex//skinsim /\"\$CLI\" }
    if (cd "$T" && CLI=$CLI bash -c "$run" >"$T/out.txt" 2>&1); then
        echo "ok   $c: $ex"
    else
        bad "$c: its --help example fails: $ex"; tail -5 "$T/out.txt"
    fi
done

# "did you mean": the nearest option of the command's own help
for c in "heal --dayz 3" "abrasion --sizee 64" "optics swatch --photon 10" "skin --feature-in x" \
         "optics table --sampels 2" "wound --heall x"; do
    # shellcheck disable=SC2086
    "$CLI" $c >/dev/null 2>"$T/err.txt"
    rc=$?
    want=$(case "$c" in heal*) echo --days;; abrasion*) echo --size;; "optics swatch"*) echo --photons;;
           skin*) echo --features-in;; "optics table"*) echo --samples;; wound*) echo --heal;; esac)
    [ $rc -eq 2 ] && grep -q "did you mean '$want'?" "$T/err.txt" ||
        bad "$c: exit $rc, no 'did you mean $want': $(cat "$T/err.txt")"
done
"$CLI" abrasion --xyzzy >/dev/null 2>"$T/err.txt"
grep -q "did you mean" "$T/err.txt" && bad "a far-off option got a suggestion: $(cat "$T/err.txt")"
# --times must be increasing: refused, nothing written
"$CLI" abrasion --times 5,1 --size 16 --out "$T/unsorted" >/dev/null 2>"$T/err.txt"
rc=$?
[ $rc -eq 2 ] && grep -q "increasing order (1 after 5)" "$T/err.txt" && [ ! -e "$T/unsorted" ] ||
    bad "--times 5,1: exit $rc: $(cat "$T/err.txt")"
# one default per option: swatch prints its own --photons and --wl-step, once
h=$("$CLI" optics swatch --help)
[ "$(printf '%s\n' "$h" | grep -c -- '--photons')" -eq 1 ] &&
    printf '%s\n' "$h" | grep -q -- '--photons N .*(10000)' &&
    printf '%s\n' "$h" | grep -q -- '--wl-step NM .*(380, 780, 20)' || bad "optics swatch --help: two defaults"
[ "$("$CLI" heal --help | grep -c -- '^  --wound-mesh')" -eq 1 ] || bad "heal --help lists --wound-mesh twice"
"$CLI" wound --help | grep -q -- '--skin FILE.exr|FOLDER' || bad "wound --help: --skin FILE.exr|FOLDER"
[ $fail -eq 0 ] || exit 1
echo "e2e_help: all passed"
