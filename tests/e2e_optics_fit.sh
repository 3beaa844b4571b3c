#!/usr/bin/env bash
# End-to-end: `skinsim optics fit` and `skinsim optics table` (build, lookup),
# help texts, JSON shape, thread-count determinism of the table file, bad input
# (exit 2, nothing written), corrupt / truncated / other-version tables, and
# the shipped default table.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$2"

for s in fit table; do
  "$CLI" optics $s --help >"$T/h.txt" || fail "$s --help"
  grep -q "usage: skinsim optics $s" "$T/h.txt" || fail "$s help text"
  grep -q -- "--photons N" "$T/h.txt" || fail "$s help lists --photons"
done
grep -q "epidermis" "$T/h.txt" || fail "table help lists the axes"

SMALL="--photons 400 --wl-min 450 --wl-max 650 --wl-step 100 --theta-i 2 --theta-r 3 --phi 3"

# fit: JSON keys and both models
"$CLI" optics fit $SMALL --json --threads 2 >"$T/f.json" || fail "fit"
for k in base_color_linear specular roughness residual_rel subsurface_radius_cm ggx \
         ashikhmin-shirley albedo_linear; do
  grep -q "\"$k\"" "$T/f.json" || fail "fit json lacks $k"
done
"$CLI" optics fit $SMALL --fast --weighting projected >"$T/f.txt" || fail "fit --fast"
grep -q "^ggx " "$T/f.txt" || fail "fit text output"
# default (--base albedo): the GGX base colour is the albedo (within 10 % per
# channel) and the lobe stays inside its bounds; --base free runs the seed's fit
"$CLI" optics fit --photons 3000 --wl-min 450 --wl-max 650 --wl-step 100 --theta-i 6 \
  --theta-r 6 --phi 6 --fast --json --threads 2 >"$T/fb.json" || fail "fit 6x6x6"
python3 - "$T/fb.json" <<'PY' || fail "fit --base albedo: base colour vs albedo"
import json, sys
d = json.load(open(sys.argv[1]))
g, a = d["models"]["ggx"], d["albedo_linear"]
for b, x in zip(g["base_color_linear"], a):
    assert abs(b - x) <= 0.1 * x, (g, a)
assert 0.0 < g["specular"] < 1.0 and 0.0 < g["roughness"] < 1.0, g
PY
"$CLI" optics fit $SMALL --fast --base free >"$T/ff.txt" || fail "fit --base free"
grep -q "^ggx " "$T/ff.txt" || fail "fit --base free output"

# table build: 1 vs 2 threads give identical files
"$CLI" optics table --samples 2 $SMALL --out "$T/t1.sstab" --threads 1 --quiet || fail "table t1"
"$CLI" optics table --samples 2 $SMALL --out "$T/t2.sstab" --threads 2 --quiet --json \
  >"$T/t.json" || fail "table t2"
cmp -s "$T/t1.sstab" "$T/t2.sstab" || fail "table differs between 1 and 2 threads"
grep -q '"entries": 64' "$T/t.json" || fail "table json entries"
head -c 7 "$T/t1.sstab" | grep -q "SSMMTAB" || fail "table magic"

# lookup
"$CLI" optics table --lookup "$T/t1.sstab" --melanin 0.2 --blood 0.01 --json >"$T/l.json" \
  || fail "lookup"
grep -q '"ggx"' "$T/l.json" || fail "lookup json"

# bad input: exit 2, nothing written
exits2 "$CLI" optics fit --melanin 2
exits2 "$CLI" optics fit --photons abc
exits2 "$CLI" optics fit --weighting foo
exits2 "$CLI" optics fit --base none
exits2 "$CLI" optics fit --base
exits2 "$CLI" optics fit --bogus
exits2 "$CLI" optics fit --max-theta-deg 5
exits2 "$CLI" optics fit --max-theta-deg 91
exits2 "$CLI" optics table --samples 0 --out "$T/bad.sstab"
exits2 "$CLI" optics table --samples 2 --photons 10 --out "$T/bad.sstab"
exits2 "$CLI" optics table $SMALL --samples 2 --out "$T/nodir/x/bad.sstab" --wl-min 700 \
  --wl-max 400
exits2 "$CLI" optics table --samples 2
exits2 "$CLI" optics table --lookup "$T/t1.sstab" --out "$T/bad.sstab"
exits2 "$CLI" optics table --samples 1 $SMALL --out /proc/none/bad.sstab
[ ! -e "$T/bad.sstab" ] || fail "a failed run wrote its output"
[ -z "$(ls "$T" | grep -v -e '^t1.sstab$' -e '^t2.sstab$' -e '\.json$' -e '\.txt$')" ] \
  || fail "stray files: $(ls "$T")"

# corrupt, truncated, other-version and missing tables: exit 2
head -c 100 "$T/t1.sstab" >"$T/trunc.sstab"
exits2 "$CLI" optics table --lookup "$T/trunc.sstab"
cp "$T/t1.sstab" "$T/corrupt.sstab"
printf '\x55' | dd of="$T/corrupt.sstab" bs=1 seek=200 conv=notrunc 2>/dev/null
exits2 "$CLI" optics table --lookup "$T/corrupt.sstab"
cp "$T/t1.sstab" "$T/v2.sstab"  # version 7: not readable
printf '\x07' | dd of="$T/v2.sstab" bs=1 seek=8 conv=notrunc 2>/dev/null
exits2 "$CLI" optics table --lookup "$T/v2.sstab"
grep -q "version" "$T/e.txt" || fail "version error names the version"
exits2 "$CLI" optics table --lookup "$T/missing.sstab"

# explicit axis values: two melanin samples, the rest single
"$CLI" optics table --axis melanin=0.01,0.2 --samples 1 $SMALL --out "$T/ax.sstab" --quiet \
  || fail "table --axis"
"$CLI" optics table --lookup "$T/ax.sstab" --melanin 0.1 --json >"$T/ax.json" || fail "lookup --axis table"
grep -q '"entries": 2' "$T/ax.json" || fail "--axis table has 2 entries"
exits2 "$CLI" optics table --axis melanin=0.2,0.1 --out "$T/bad.sstab"
exits2 "$CLI" optics table --axis skin=0.1 --out "$T/bad.sstab"
[ ! -e "$T/bad.sstab" ] || fail "bad --axis wrote a table"

# the shipped default table reads and interpolates
if [ -f "$SRC/data/modelmatch_default.sstab" ]; then
  "$CLI" optics table --lookup "$SRC/data/modelmatch_default.sstab" --melanin 0.1 --json \
    >"$T/d.json" || fail "default table lookup"
  grep -q '"entries": 4320' "$T/d.json" || fail "default table has 8 x 5 x 4 x 3 x 3 x 3 entries"
  grep -q '"surface_curve": true' "$T/d.json" || fail "default table has a surface curve"
  # the lobe follows the surface's roughness
  r1=$("$CLI" optics table --lookup "$SRC/data/modelmatch_default.sstab" --surface-sigma 0.3 --json \
       | python3 -c "import json,sys; print(json.load(sys.stdin)['models']['ggx']['roughness'])")
  r2=$("$CLI" optics table --lookup "$SRC/data/modelmatch_default.sstab" --surface-sigma 0.7 --json \
       | python3 -c "import json,sys; print(json.load(sys.stdin)['models']['ggx']['roughness'])")
  python3 -c "import sys; assert float(sys.argv[1]) + 0.15 < float(sys.argv[2])" "$r1" "$r2" \
    || fail "--surface-sigma 0.3 / 0.7 give roughness $r1 / $r2"
else
  fail "data/modelmatch_default.sstab is missing"
fi
echo "ok"
