#!/usr/bin/env bash
# End-to-end test of `skinsim wound --mesh M --wound-uv CSV`: the healing
# runs on a patch of the hand mesh's skin (skinsim/shell.h) and the textures
# land in the mesh's UV layout: the texels inside the UV strokes change from
# day 0 to day 1 and are the red of an open wound, the texels away from them
# are the same skin on both days, the glTF is the mesh itself, timeline.json
# states the UV scale; --mechanics on a mesh exits 2 and writes nothing.
# Skipped (77) without the hand mesh.
# usage: e2e_wound_mesh.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2
MESH="$SRC/data/meshes/generic-hand-left.glb"
[ -f "$MESH" ] || { echo "SKIP: no $MESH"; exit 77; }

# a wound on the back of the hand (its UV island, lower left)
printf 'u,v\n0.22,0.70\n0.30,0.68\n0.31,0.76\n0.23,0.78\n' >"$T/cut.csv"
ARGS="--mesh $MESH --wound-uv $T/cut.csv --voxel-mm 1 --size 128 --quiet"
"$CLI" wound $ARGS --days 0,1 --out "$T/a" || fail "wound --mesh failed"
/usr/bin/python3 - "$T/a" <<'PY' || fail "textures in UV space"
import json, struct, sys, zlib

def png_rgb(path):
    """8-bit RGB PNG (skinsim's writer: no interlace) -> rows of (r, g, b)."""
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, w = 8, b"", 0
    while pos < len(d):
        n, kind = struct.unpack(">I4s", d[pos:pos + 8])
        body = d[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype == 2, (depth, ctype)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, bpp, stride = zlib.decompress(idat), 3, 3 * w
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[3 * x:3 * x + 3]) for x in range(w)])
        prev = line
    return rows

d = sys.argv[1]
t = json.load(open(d + "/timeline.json"))
assert t["texture_space"] == "the mesh's UV layout" and 50 < t["mm_per_uv"] < 2000, t
day0, day1 = png_rgb(d + "/frames/t0_base_color.png"), png_rgb(d + "/frames/t1_base_color.png")
n = len(day0)
# inside the strokes' quadrilateral (its centre region): an open red bed
red = [day1[y][x] for y in range(int(0.71 * n), int(0.75 * n)) for x in range(int(0.24 * n), int(0.29 * n))]
assert all(r > 1.8 * g and r > 60 for r, g, b in red), red[:4]
# away from it (upper half of the layout: palm, fingers): the same skin on both days
far = [(x, y) for y in range(0, n // 2) for x in range(n) if day0[y][x] != day1[y][x]]
assert not far, far[:5]
# the glTF is the mesh with its own UVs, not a square
g = json.load(open(d + "/frames/t1.gltf"))
assert g["accessors"][0]["count"] > 1000, g["accessors"][0]
PY

# --- bad input: no mechanics on a UV layout (yet): exit 2, nothing written
"$CLI" wound $ARGS --days 0,1 --mechanics --out "$T/bad" 2>"$T/err.txt"
rc=$?
[ $rc -eq 2 ] || fail "--mesh --mechanics exited $rc, expected 2"
grep -q -- "--mechanics" "$T/err.txt" || fail "message does not name --mechanics"
[ ! -e "$T/bad" ] || fail "--mesh --mechanics left $T/bad behind"
echo "e2e_wound_mesh: all checks passed"
