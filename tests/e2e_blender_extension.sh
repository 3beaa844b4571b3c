#!/usr/bin/env bash
# End-to-end: the Blender 4.2+ extension package of the add-on, as
# `make blender-extension` builds it (integrations/blender/build_extension.py):
# the zip holds __init__.py and blender_manifest.toml at its root, the
# manifest has the keys Blender's validator requires and the add-on's
# version, and a manifest whose version disagrees with bl_info is refused
# (nothing written). Needs no Blender (Debian's is 3.4, older than
# extensions).
set -u
SRC="$(cd "$2" && pwd)"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
PY=/usr/bin/python3
[ -x "$PY" ] || PY=$(command -v python3)
"$PY" -c "import tomllib" 2>/dev/null || { echo "SKIP: $PY has no tomllib (Python < 3.11)"; exit 77; }
"$PY" "$SRC/integrations/blender/build_extension.py" "$T/ext.zip" || fail "build_extension.py"
"$PY" - "$T/ext.zip" "$SRC" <<'PYEOF' || fail "the zip"
import ast, sys, tomllib, zipfile
z = zipfile.ZipFile(sys.argv[1])
names = sorted(z.namelist())
assert names == ["__init__.py", "blender_manifest.toml"], names
m = tomllib.loads(z.read("blender_manifest.toml").decode())
for k in ("schema_version", "id", "version", "name", "tagline", "maintainer", "type",
          "blender_version_min", "license"):
    assert k in m, k
assert m["type"] == "add-on" and m["id"] == "skinsim", m
src = z.read("__init__.py").decode()
ast.parse(src)  # the add-on module compiles
assert "def register()" in src and "bpy.types.Object.skinsim" in src
assert src == open(sys.argv[2] + "/integrations/blender/skinsim_blender/__init__.py").read()
print("zip:", names, m["id"], m["version"], "for Blender >=", m["blender_version_min"])
PYEOF
# a manifest out of step with bl_info is refused
mkdir -p "$T/src/integrations"
cp -r "$SRC/integrations/blender" "$T/src/integrations/" && cp "$SRC/CMakeLists.txt" "$T/src/"
sed -i 's/^version = .*/version = "9.9.9"/' "$T/src/integrations/blender/skinsim_blender/blender_manifest.toml"
if "$PY" "$T/src/integrations/blender/build_extension.py" "$T/bad.zip" 2>"$T/err"; then
  fail "a manifest version different from bl_info's was accepted"
fi
grep -q "differs from bl_info" "$T/err" || { cat "$T/err"; fail "message"; }
[ ! -e "$T/bad.zip" ] || fail "a refused build wrote $T/bad.zip"
echo "PASS: extension zip built and checked"
