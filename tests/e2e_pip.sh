#!/usr/bin/env bash
# End-to-end: `pip install .` as a Python user does it, into a fresh venv,
# without a network and without PYTHONPATH: the package (pyproject.toml +
# setup.py) bundles this build's libskinsim.so.0 and the shipped data, and
# the installed package imports, finds its data next to the bundled library
# and does real work (a spectrum by Monte Carlo transport, a ModelMatch table
# lookup). The source files pip reads are copied to a scratch folder first, so
# the test writes nothing into the source tree. Needs python3-venv,
# python3-setuptools, python3-wheel and python3-numpy (Makefile DEPS).
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC="$(cd "$2" && pwd)"
BUILD="$(dirname "$CLI")"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=$(command -v python3)
for m in ensurepip:python3-venv setuptools:python3-setuptools wheel:python3-wheel numpy:python3-numpy; do
  "$PY" -c "import ${m%%:*}" 2>/dev/null || { echo "SKIP: $PY has no ${m%%:*} (apt-get install ${m#*:})"; exit 77; }
done
[ -e "$BUILD/libskinsim.so.0" ] || fail "no $BUILD/libskinsim.so.0"

# what a clone holds that the package is built from
mkdir -p "$T/src/integrations/python"
cp "$SRC/pyproject.toml" "$SRC/setup.py" "$SRC/CMakeLists.txt" "$SRC/LICENSE" "$T/src/" || fail "copy"
cp -r "$SRC/data" "$T/src/data" || fail "copy data"
cp -r "$SRC/integrations/python/skinsim" "$T/src/integrations/python/" || fail "copy package"
find "$T/src" -name __pycache__ -prune -exec rm -rf {} +

unset PYTHONPATH PYTHONHOME LD_LIBRARY_PATH SKINSIM_DATA
export PYTHONDONTWRITEBYTECODE=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
"$PY" -m venv --system-site-packages "$T/venv" >"$T/venv.log" 2>&1 || { cat "$T/venv.log"; fail "python3 -m venv"; }
V="$T/venv/bin/python"
# --no-index: nothing from a network; --no-build-isolation: Debian's setuptools
SKINSIM_LIB="$BUILD/libskinsim.so.0" "$V" -m pip install --no-build-isolation --no-index "$T/src" \
  >"$T/pip.log" 2>&1 || { cat "$T/pip.log"; fail "pip install"; }
grep -q "Successfully installed skinsim" "$T/pip.log" || { cat "$T/pip.log"; fail "pip did not install skinsim"; }
[ ! -e "$T/src/build" ] || fail "pip wrote setuptools' build folder into build/ (the CMake folder's name)"

# a sanitizer build of the library needs its runtime loaded first
PRELOAD=""
if readelf -d "$BUILD/libskinsim.so.0" | grep -q 'libasan'; then
  PRELOAD="$(cc -print-file-name=libasan.so) $(cc -print-file-name=libubsan.so)"
  export ASAN_OPTIONS="detect_leaks=0"
fi
mkdir -p "$T/elsewhere"
# the venv's python3, first on PATH as after `source venv/bin/activate`
(cd "$T/elsewhere" && PATH="$T/venv/bin:$PATH" LD_PRELOAD="$PRELOAD" SKINSIM_THREADS=2 python3 - "$T/venv" <<'EOF'
import os, sys
venv = os.path.realpath(sys.argv[1])
import skinsim
from skinsim import optics
pkg = os.path.realpath(os.path.dirname(skinsim.__file__))
assert pkg.startswith(venv), "skinsim imported from %s, not the venv" % pkg
lib = os.path.realpath(skinsim.library_path)
assert lib.startswith(pkg), "library %s is not the bundled one" % lib
data = os.path.realpath(skinsim.data_dir())
assert data.startswith(pkg), "data from %s, not the package" % data
assert os.path.isfile(os.path.join(pkg, "py.typed")), "py.typed not installed"
s = optics.spectrum(photons=3000, seed=3, wl_step_nm=40.0, melanin=0.05, blood=0.02)
rgb = s.colour()
assert len(s.wavelength_nm) == 11 and all(0.05 < c < 1.0 for c in rgb), rgb
assert rgb[0] > rgb[2], "skin is redder than it is blue: %s" % (rgb,)
e = optics.Table().lookup(melanin=0.05, blood=0.02)
assert 0.0 < e["ggx"]["roughness"] <= 1.0, e
print("OK", skinsim.version(), lib, "rgb", [round(float(c), 3) for c in rgb])
EOF
) || fail "the installed package"
"$V" -m pip uninstall -y skinsim >"$T/un.log" 2>&1 || { cat "$T/un.log"; fail "pip uninstall"; }
left=$(find "$T/venv/lib" -path '*site-packages/skinsim*' | head -3)
[ -z "$left" ] || fail "pip uninstall left $left"
echo "PASS: pip install into a fresh venv, import, spectrum and table lookup, uninstall"
