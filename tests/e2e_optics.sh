#!/usr/bin/env bash
# End-to-end: `skinsim optics` subcommands, help texts, JSON shape, output
# files, bad input (exit 2, nothing written), thread-count determinism.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"

"$CLI" optics --help >/dev/null || fail "optics --help"
for s in spectrum brdf mci swatch; do
  "$CLI" optics $s --help >"$T/h.txt" || fail "$s --help"
  grep -q "usage: skinsim optics $s" "$T/h.txt" || fail "$s help text"
done
grep -q -- "--melanin F" "$T/h.txt" || fail "common options in help"

# spectrum --json: keys, sane numbers
"$CLI" optics spectrum --json --photons 2000 --wl-step 40 --threads 2 >"$T/s.json" || fail "spectrum"
for k in srgb_linear wavelength_nm reflectance specular std_error; do
  grep -q "\"$k\"" "$T/s.json" || fail "spectrum json lacks $k"
done
# same seed, 1 vs 2 threads: identical output
"$CLI" optics spectrum --json --photons 2000 --wl-step 40 --threads 1 >"$T/s1.json" || fail "spectrum t1"
cmp -s "$T/s.json" "$T/s1.json" || fail "spectrum differs between 1 and 2 threads"
"$CLI" optics spectrum --json --photons 2000 --wl-step 40 --seed 9 >"$T/s9.json" || fail "spectrum seed"
cmp -s "$T/s.json" "$T/s9.json" && fail "a different seed gave identical output"

# spectrum CSV
"$CLI" optics spectrum --photons 1000 --wl-step 100 --out "$T/s.csv" >/dev/null || fail "spectrum csv"
[ "$(head -1 "$T/s.csv")" = "wavelength_nm,reflectance,std_error" ] || fail "csv header"
[ "$(wc -l <"$T/s.csv")" -eq 6 ] || fail "csv rows"

# radial profile per colour channel
"$CLI" optics spectrum --photons 1000 --wl-step 100 --radial-out "$T/r.csv" --radial-bins 10 \
  --radial-max-cm 0.2 >/dev/null || fail "radial"
[ "$(head -1 "$T/r.csv")" = "r_min_cm,r_max_cm,rd_r,rd_g,rd_b" ] || fail "radial header"
[ "$(wc -l <"$T/r.csv")" -eq 11 ] || fail "radial rows"
# the seed's subsurface distance D (summed horizontal path) as an option
"$CLI" optics spectrum --photons 1000 --wl-step 100 --radial-out "$T/rp.csv" --radial-bins 10 \
  --radial-max-cm 0.2 --radial-distance path >/dev/null || fail "radial path"
[ "$(wc -l <"$T/rp.csv")" -eq 11 ] || fail "radial path rows"
cmp -s "$T/r.csv" "$T/rp.csv" && fail "--radial-distance path changed nothing"

# brdf
"$CLI" optics brdf --out "$T/b.csv" --photons 500 --wl-step 200 --theta-i 2 --theta-r 3 --phi 4 \
  || fail "brdf"
[ "$(wc -l <"$T/b.csv")" -eq 25 ] || fail "brdf rows"

# swatch
"$CLI" optics swatch --out "$T/sw.png" --photons 1000 --wl-step 40 --melanin-list 0.02,0.3 \
  --blood-list 0.005 --cell 32 --quiet || fail "swatch"
[ -s "$T/sw.png" ] || fail "swatch png"
head -c 8 "$T/sw.png" | od -An -tx1 | grep -q "89 50 4e 47" || fail "swatch is not a PNG"

# mci: output named in the file, relative to the current directory
cat >"$T/in.mci" <<'MCI'
1.0    # version
1      # runs
out1.mco A
20000
0.002 0.01
10 50 10
1
1.0
1.0 10 90 0.75 0.02
1.0
MCI
(cd "$T" && "$CLI" optics mci in.mci --json >mci.json) || fail "mci"
[ -s "$T/out1.mco" ] || fail "mci output missing"
grep -q "^RAT" "$T/out1.mco" || fail "mci RAT"
grep -q "Rd_r #" "$T/out1.mco" || fail "mci Rd_r"
grep -q '"diffuse"' "$T/mci.json" || fail "mci json"
# --scalar: the one-photon loop runs (other samplers: a different file) and
# agrees with the packet path within Monte Carlo error (van de Hulst: 0.09739)
cp "$T/out1.mco" "$T/packet.mco"
(cd "$T" && "$CLI" optics mci in.mci --scalar) || fail "mci --scalar"
cmp -s "$T/out1.mco" "$T/packet.mco" && fail "mci --scalar gave the packet path's output"
rd() { awk '/#Diffuse reflectance/ {print $1}' "$1"; }
awk -v a="$(rd "$T/out1.mco")" -v b="$(rd "$T/packet.mco")" \
  'BEGIN { d = a - b; if (d < 0) d = -d; e = a - 0.09739; if (e < 0) e = -e;
           exit !(d < 0.012 && e < 0.009) }' || fail "mci --scalar Rd $(rd "$T/out1.mco") vs $(rd "$T/packet.mco")"
"$CLI" optics spectrum --json --photons 2000 --wl-step 40 --scalar >"$T/ss.json" || fail "spectrum --scalar"
grep -q '"srgb_linear"' "$T/ss.json" || fail "spectrum --scalar json"

# bad input: exit 2, nothing written
expect2() {
  local out="$1"; shift
  "$@" >/dev/null 2>"$T/err.txt"
  local rc=$?
  [ $rc -eq 2 ] || fail "expected exit 2 (got $rc): $*"
  [ -e "$out" ] && fail "output written despite bad input: $*"
  grep -q "error" "$T/err.txt" || fail "no error message: $*"
  return 0
}
expect2 "$T/x.png" "$CLI" optics swatch --out "$T/x.png" --melanin-list 0.1,-1
expect2 "$T/x.csv" "$CLI" optics spectrum --out "$T/x.csv" --melanin -0.1
expect2 "$T/x.csv" "$CLI" optics spectrum --out "$T/x.csv" --blood 1.5
expect2 "$T/x.csv" "$CLI" optics spectrum --out "$T/x.csv" --radial-distance far
expect2 "$T/x.csv" "$CLI" optics spectrum --out "$T/x.csv" --oxygenation nan
expect2 "$T/x.csv" "$CLI" optics spectrum --out "$T/x.csv" --epidermis-thickness-cm 0
expect2 "$T/x.csv" "$CLI" optics brdf --out "$T/x.csv" --theta-i 0
expect2 "$T/s.csv/x.png" "$CLI" optics swatch --out "$T/s.csv/x.png" --photons 10
expect2 "$T/x.csv" "$CLI" optics spectrum --bogus
expect2 "$T/none.mco" "$CLI" optics mci "$T/does-not-exist.mci"
sed 's/1.0 10 90 0.75 0.02/1.0 10 90 1.75 0.02/; s/out1.mco/bad.mco/' "$T/in.mci" >"$T/bad.mci"
(cd "$T" && expect2 "$T/bad.mco" "$CLI" optics mci bad.mci)
"$CLI" optics nosuch >/dev/null 2>&1; [ $? -eq 2 ] || fail "unknown subcommand exit code"
echo "e2e_optics: OK"
