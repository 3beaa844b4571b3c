#!/usr/bin/env bash
# End-to-end: the installed library as a user gets it. Installs the build into
# a temporary prefix, moves the prefix (an install must be relocatable), builds
# examples/ against it with pkg-config (shared and static) and with CMake's
# find_package, runs them, and checks that the installed copy reads its data
# from its own prefix (shared and static, the static program kept outside
# the prefix and the source tree's data never used), that SKINSIM_DATA still
# overrides it, that bad input gets the library's message and exit 2, that
# every installed header's functions link from both libraries, and that
# pkg-config --cflags emits only the include folder.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$(cd "$2" && pwd)"
BUILD="$(dirname "$CLI")"
for tool in cc pkg-config cmake readelf; do
  command -v $tool >/dev/null || { echo "SKIP: $tool not installed"; exit 77; }
done

cmake --install "$BUILD" --prefix "$T/prefix" >"$T/install.log" 2>&1 || { cat "$T/install.log"; fail "cmake --install"; }
mv "$T/prefix" "$T/moved"
P="$T/moved"
LIBDIR=$(dirname "$(find "$P" -name 'libskinsim.so' | head -1)")
[ -n "$LIBDIR" ] || fail "no libskinsim.so installed"
for f in include/skinsim/core.h include/skinsim/optics.h include/skinsim/abrasion.h \
         share/skinsim/spectra/d65.csv share/skinsim/modelmatch_default.sstab bin/skinsim; do
  [ -f "$P/$f" ] || fail "not installed: $f"
done
for f in libskinsim.a libskinsim.so.0 pkgconfig/skinsim.pc cmake/skinsim/skinsimConfig.cmake \
         cmake/skinsim/skinsimConfigVersion.cmake; do
  [ -e "$LIBDIR/$f" ] || fail "not installed: $LIBDIR/$f"
done
readelf -d "$LIBDIR/libskinsim.so" | grep -q 'SONAME.*\[libskinsim\.so\.0\]' || fail "soname is not libskinsim.so.0"
# only the ss_* API is exported
bad=$(nm -D --defined-only "$LIBDIR/libskinsim.so" | awk '$2 ~ /[TDBR]/ && $3 !~ /^ss_/' | head -3)
[ -z "$bad" ] || fail "non-API symbols exported: $bad"

[ -e "$P/include/skinsim/dist.h" ] && fail "dist.h installed, but its ss_dist_* functions are in no installed library"

export PKG_CONFIG_PATH="$LIBDIR/pkgconfig"
# the public headers include only libc's: no cairo, glib, libpng folders
cf=$(pkg-config --cflags skinsim | sed 's/-fsanitize=[^ ]*//; s/ *$//')
case "$cf" in -I*" "*|"") false ;; -I*) [ "$(realpath "${cf#-I}")" = "$(realpath "$P/include")" ] ;; *) false ;; esac \
  || fail "pkg-config --cflags: '$(pkg-config --cflags skinsim)', want only -I$P/include"
# every function declared in an installed header is in the installed
# libraries: a program taking the address of each links (shared and static)
{
  echo '#include <stdio.h>'
  for h in "$P"/include/skinsim/*.h; do echo "#include <skinsim/$(basename "$h")>"; done
  echo 'typedef void (*fn)(void);'
  echo 'int main(void) { static const fn all[] = {'
  for h in "$P"/include/skinsim/*.h; do
    cc -std=c17 -I"$P/include" -E -P "$h" 2>/dev/null | tr '\n' ' ' | grep -oE '[ *](ss_[a-z0-9_]+) *\([^*]' \
      | grep -oE 'ss_[a-z0-9_]+'
  done | sort -u | sed 's/.*/(fn)\&&,/'
  echo '}; printf("%zu functions\n", sizeof all / sizeof *all); return all[0] == 0; }'
} >"$T/all_api.c"
nfn=$(grep -c '^(fn)' "$T/all_api.c")
[ "$nfn" -gt 100 ] || fail "found only $nfn functions in the installed headers"
cc -std=c17 -Wno-cast-function-type "$T/all_api.c" $(pkg-config --cflags --libs skinsim) -o "$T/all_api" 2>"$T/all_api.log" \
  || { grep -oE "(undefined reference to .[a-z0-9_]*|error: .*)" "$T/all_api.log" | sort -u | head; fail "an installed header declares functions the shared library lacks"; }
LD_LIBRARY_PATH="$LIBDIR" "$T/all_api" | grep -q "^$nfn functions" || fail "all_api did not run"
cc -std=c17 -Wno-cast-function-type "$T/all_api.c" $(pkg-config --cflags skinsim) \
  $(pkg-config --static --libs skinsim | sed 's/-lskinsim/-l:libskinsim.a/') -o "$T/all_api_static" 2>"$T/all_api.log" \
  || { grep -oE "(undefined reference to .[a-z0-9_]*|error: .*)" "$T/all_api.log" | sort -u | head; fail "an installed header declares functions the static library lacks"; }
[ "$(pkg-config --modversion skinsim)" = "$("$CLI" --version | awk '{print $2}')" ] || fail "pkg-config version"
CFLAGS_SS=$(pkg-config --cflags skinsim)
LIBS_SS=$(pkg-config --libs skinsim)
for ex in skin_colour abrasion_frame; do
  cc -std=c17 -Wall -Wextra -Werror "$SRC/examples/$ex.c" $CFLAGS_SS $LIBS_SS -o "$T/$ex" || fail "build $ex (shared)"
  readelf -d "$T/$ex" | grep -q 'NEEDED.*libskinsim\.so\.0' || fail "$ex does not use the shared library"
done
# The static link and the CMake package are build checks, not sanitizer
# checks: the sanitizer suite (SKINSIM_TEST_QUICK) skips them to save time.
QUICK="${SKINSIM_TEST_QUICK:-}"
STATIC_LIBS=$(pkg-config --static --libs skinsim | sed 's/-lskinsim/-l:libskinsim.a/')
if [ -z "$QUICK" ]; then
cc -std=c17 -Wall -Wextra -Werror "$SRC/examples/skin_colour.c" $CFLAGS_SS $STATIC_LIBS -o "$T/skin_colour_static" \
  || fail "build skin_colour (static)"
readelf -d "$T/skin_colour_static" | grep -q 'libskinsim' && fail "static build still needs libskinsim.so"
fi

export LD_LIBRARY_PATH="$LIBDIR"
unset SKINSIM_DATA
# fewer photons under the sanitizers (SKINSIM_TEST_QUICK): the checks hold at any count
PH=2000
[ -n "${SKINSIM_TEST_QUICK:-}" ] && PH=500
"$T/skin_colour" 0.08 0.02 $PH >"$T/sc.txt" || { cat "$T/sc.txt"; fail "skin_colour"; }
grep -q "data in $P/share/skinsim\$" "$T/sc.txt" || { cat "$T/sc.txt"; fail "installed library does not read its prefix's data"; }
# a darker, bloodier skin is red > green > blue and not white
read -r r g b < <(awk '/linear sRGB albedo/ {print $4, $5, $6}' "$T/sc.txt")
awk -v r="$r" -v g="$g" -v b="$b" 'BEGIN { exit !(r > g && g > b && r < 0.6 && b > 0.01) }' || fail "implausible skin colour $r $g $b"
if [ -z "$QUICK" ]; then
"$T/skin_colour_static" 0.08 0.02 $PH >"$T/scs.txt" || fail "static skin_colour"
# the static program, kept outside the prefix, reads the prefix's data (from
# the lib folder pkg-config gave it), not the source tree's or the configured one
grep -q "data in $P/share/skinsim\$" "$T/scs.txt" || { cat "$T/scs.txt"; fail "static program does not read its prefix's data"; }
# the same result through both libraries
[ "$(grep albedo "$T/sc.txt")" = "$(grep albedo "$T/scs.txt")" ] || fail "static and shared results differ"
fi
# SKINSIM_DATA overrides the installed data
SKINSIM_DATA="$T/nowhere" "$T/skin_colour" >"$T/o.txt" 2>"$T/e.txt"
rc=$?
[ $rc -eq 2 ] || fail "SKINSIM_DATA=missing: exit $rc, want 2"
grep -q "$T/nowhere" "$T/e.txt" || { cat "$T/e.txt"; fail "message does not name the SKINSIM_DATA folder"; }
# bad input: the library's message, exit 2
"$T/skin_colour" -0.5 >"$T/o.txt" 2>"$T/e.txt"
rc=$?
[ $rc -eq 2 ] || fail "negative melanin: exit $rc, want 2"
grep -qi "melanin" "$T/e.txt" || { cat "$T/e.txt"; fail "message does not name melanin"; }
# an argument that is not a number: refused, exit 2, naming it
for bad in "abc" "0.1x" ""; do
  "$T/skin_colour" 0.05 "$bad" >"$T/o.txt" 2>"$T/e.txt"
  rc=$?
  [ $rc -eq 2 ] || fail "skin_colour blood '$bad': exit $rc, want 2"
  grep -q "blood '$bad' is not a number" "$T/e.txt" || { cat "$T/e.txt"; fail "message does not name blood '$bad'"; }
done
"$T/skin_colour" 0.05 0.02 3.5 >"$T/o.txt" 2>"$T/e.txt"
[ $? -eq 2 ] && grep -q "photons" "$T/e.txt" || fail "skin_colour photons 3.5 not refused"
"$T/abrasion_frame" abc "$T/nf" >"$T/o.txt" 2>"$T/e.txt"
[ $? -eq 2 ] && grep -q "day 'abc'" "$T/e.txt" || fail "abrasion_frame day abc not refused"
# ss_data_path: the shipped default table through the public call
cat >"$T/dp.c" <<'CEOF'
#include <stdio.h>
#include <skinsim/core.h>
int main(void) {
    char path[4096];
    ss_error err = {0};
    if (ss_data_path(SS_DATA_DEFAULT_TABLE, path, sizeof path, &err)) return 3;
    printf("%s\n", path);
    if (ss_data_path("no/such.file", path, sizeof path, &err) != SS_ERR_INPUT) return 4;
    fprintf(stderr, "%s\n", err.msg);
    return 0;
}
CEOF
cc -std=c17 -Wall -Wextra -Werror "$T/dp.c" $CFLAGS_SS $LIBS_SS -o "$T/dp" || fail "build ss_data_path program"
[ "$("$T/dp" 2>"$T/e.txt")" = "$P/share/skinsim/modelmatch_default.sstab" ] || fail "ss_data_path(SS_DATA_DEFAULT_TABLE)"
grep -q "no/such.file" "$T/e.txt" || fail "ss_data_path message does not name the file"

"$T/abrasion_frame" 3 "$T/frame" >"$T/af.txt" || { cat "$T/af.txt"; fail "abrasion_frame"; }
for f in frame_color.png frame_normal.png; do [ -s "$T/frame/$f" ] || fail "abrasion_frame did not write $f"; done
# the wound (day 3: scab forming) is darker than the skin around it
read -r win wout < <(awk '/inside/ {i=$7+$8+$9} /outside/ {o=$7+$8+$9} END {print i, o}' "$T/af.txt")
awk -v i="$win" -v o="$wout" 'BEGIN { exit !(i < 0.7 * o) }' || { cat "$T/af.txt"; fail "wound not darker than skin"; }

# CMake: find_package(skinsim) from the moved prefix
if [ -z "$QUICK" ]; then
cmake -S "$SRC/examples" -B "$T/cm" -DCMAKE_PREFIX_PATH="$P" -DCMAKE_C_FLAGS="$(pkg-config --cflags-only-other skinsim)" \
  -DCMAKE_EXE_LINKER_FLAGS="$(pkg-config --libs-only-other skinsim)" >"$T/cm.log" 2>&1 || { cat "$T/cm.log"; fail "find_package configure"; }
cmake --build "$T/cm" >>"$T/cm.log" 2>&1 || { cat "$T/cm.log"; fail "find_package build"; }
"$T/cm/abrasion_frame" 1 "$T/frame2" >/dev/null || fail "find_package abrasion_frame"
[ -s "$T/frame2/frame_color.png" ] || fail "find_package abrasion_frame wrote nothing"
fi
# the installed Python package loads the installed library (not a sanitizer build's:
# python would need the sanitizer runtime preloaded, which e2e_python.sh covers)
PY=/usr/bin/python3
PYDIR=$(dirname "$(find "$P" -path '*/skinsim/__init__.py' | head -1)")
[ -n "$PYDIR" ] && [ "$PYDIR" != . ] || fail "Python package not installed"
if "$PY" -c "import numpy" 2>/dev/null && ! pkg-config --libs skinsim | grep -q sanitize; then
  (unset SKINSIM_LIB LD_LIBRARY_PATH; cd "$T" && PYTHONPATH="$(dirname "$PYDIR")" "$PY" -c "
import skinsim
assert skinsim.library_path == '$LIBDIR/libskinsim.so.0', skinsim.library_path
assert skinsim.data_dir() == '$P/share/skinsim', skinsim.data_dir()
s = skinsim.optics.spectrum(photons=300, wl_step_nm=100)
assert 0 < s.reflectance.min() < 1
") || fail "installed Python package"
fi
echo "PASS"
