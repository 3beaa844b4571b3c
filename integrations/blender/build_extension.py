"""Builds the Blender 4.2+ extension zip of the skinsim add-on.

    python3 integrations/blender/build_extension.py OUT.zip

Checks blender_manifest.toml first (the keys Blender's extension validator
requires, an id that is a Python identifier, a tagline of at most 64
characters without a final full stop, a version equal to bl_info's and to
the CMake project's), then writes __init__.py and blender_manifest.toml at
the root of the zip, which is the layout `blender --command extension
build` makes. Written with zipfile, so neither Blender nor zip is needed to
build it; the zip is staged and renamed into place whole.
"""
import ast
import os
import re
import sys
import tomllib
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
PKG = os.path.join(HERE, "skinsim_blender")
SRC = os.path.dirname(os.path.dirname(HERE))
REQUIRED = ("schema_version", "id", "version", "name", "tagline", "maintainer", "type",
            "blender_version_min", "license")


def fail(msg):
    sys.exit("build_extension: " + msg)


def bl_info_version():
    tree = ast.parse(open(os.path.join(PKG, "__init__.py"), encoding="utf-8").read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "bl_info"
                                                for t in node.targets):
            info = ast.literal_eval(node.value)
            return ".".join(str(v) for v in info["version"])
    fail("no bl_info in skinsim_blender/__init__.py")


def check(m):
    missing = [k for k in REQUIRED if k not in m]
    if missing:
        fail("blender_manifest.toml lacks %s" % ", ".join(missing))
    if m["type"] != "add-on":
        fail("type must be add-on, not %r" % m["type"])
    if not m["id"].isidentifier():
        fail("id %r is not a Python identifier" % m["id"])
    if len(m["tagline"]) > 64 or m["tagline"].endswith((".", "!", "?")):
        fail("tagline: at most 64 characters, no final punctuation")
    if not re.fullmatch(r"\d+\.\d+\.\d+", m["version"]):
        fail("version %r is not MAJOR.MINOR.PATCH" % m["version"])
    if m["version"] != bl_info_version():
        fail("version %s differs from bl_info's %s" % (m["version"], bl_info_version()))
    cm = open(os.path.join(SRC, "CMakeLists.txt"), encoding="utf-8").read()
    v = re.search(r"project\(\s*skinsim\s+VERSION\s+([0-9.]+)", cm)
    if v and v.group(1) != m["version"]:
        fail("version %s differs from CMakeLists.txt's %s" % (m["version"], v.group(1)))
    if tuple(int(x) for x in m["blender_version_min"].split(".")) < (4, 2, 0):
        fail("blender_version_min must be 4.2.0 or later for an extension")
    if not all(str(lic).startswith("SPDX:") for lic in m["license"]):
        fail("license entries are SPDX:<id>")


def main():
    if len(sys.argv) != 2:
        fail("usage: build_extension.py OUT.zip")
    out = sys.argv[1]
    with open(os.path.join(PKG, "blender_manifest.toml"), "rb") as f:
        m = tomllib.load(f)
    check(m)
    tmp = out + ".tmp.%d" % os.getpid()
    try:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
            for name in ("__init__.py", "blender_manifest.toml"):
                z.write(os.path.join(PKG, name), name)
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    print("%s: extension %s %s" % (out, m["id"], m["version"]))


if __name__ == "__main__":
    main()
