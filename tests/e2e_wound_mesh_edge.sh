#!/usr/bin/env bash
# End-to-end test of a wound's edge on a mesh (`skinsim wound --mesh M
# --wound-uv CSV`, docs/wound.md "Edges on a mesh"): a four-point stroke on
# the back of the hand, day 0, rendered at 512 and 1024 texels. Per texel the
# wound weight w is the bed's coverage: its green in linear light scaled from
# the skin around (0) to the open bed (1); a dark brown mole's texels count
# as skin (dark in the base skin, from a run with a tiny stroke far away, and
# brown here). Checks: (1) along the rim no neighbouring texels at 1024
# differ by more than 0.6 in w (a stepped, aliased edge jumps ~1 in a texel;
# pairs next to a base-skin mole are left out);
# (2) the edge's width in mm (the texels with 0.1 < w < 0.9, their area over
# the outline's length) is the same at 512 and 1024 within 35 %; (3) no
# isolated rim texels (w off the median of its 8 neighbours by > 0.5, and
# its redness (R - G) / R by > 0.15 the same way),
# all within 3 mm of the quadrilateral; (4)
# the corners are rounded: the wound (w > 0.5) covers less than 97 % of the
# strokes' quadrilateral but more than 75 %. Skipped (77) without the hand mesh.
# usage: e2e_wound_mesh_edge.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2
MESH="$SRC/data/meshes/generic-hand-left.glb"
[ -f "$MESH" ] || { echo "SKIP: no $MESH"; exit 77; }
PY=/usr/bin/python3
[ -x "$PY" ] || PY=$(command -v python3)

printf 'u,v\n0.22,0.70\n0.30,0.68\n0.31,0.76\n0.23,0.78\n' >"$T/quad.csv"
# the base skin around the quadrilateral: a tiny stroke far from it
printf 'u,v\n0.22,0.55\n0.23,0.55\n0.23,0.56\n0.22,0.56\n' >"$T/far.csv"
for n in 512 1024; do
    "$CLI" wound --mesh "$MESH" --wound-uv "$T/quad.csv" --voxel-mm 1 --days 0 --size $n \
        --quiet --no-compare --out "$T/w$n" || fail "wound --mesh --size $n failed"
    "$CLI" wound --mesh "$MESH" --wound-uv "$T/far.csv" --voxel-mm 1 --days 0 --size $n \
        --quiet --no-compare --out "$T/b$n" || fail "wound --mesh --size $n (base skin) failed"
done
"$PY" - "$T" <<'PY' || fail "edge checks"
import json, math, struct, sys, zlib
import numpy as np

def png_rgb(path):
    """8-bit RGB PNG (skinsim's writer: no interlace) -> h x w x 3 int array."""
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(d):
        n, kind = struct.unpack(">I4s", d[pos:pos + 8])
        body = d[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype == 2, (depth, ctype)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(h, 3 * w + 1)
    out = np.zeros((h, 3 * w), dtype=np.int64)
    prev = np.zeros(3 * w, dtype=np.int64)
    for y in range(h):
        f, line = raw[y, 0], raw[y, 1:].astype(np.int64)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        elif f == 1:  # Sub: a running sum per channel
            cur = line.reshape(w, 3).cumsum(axis=0).reshape(-1) & 255
        else:  # Average, Paeth: sequential
            cur = line.copy()
            for i in range(3 * w):
                a = cur[i - 3] if i >= 3 else 0
                b = prev[i]
                if f == 3:
                    cur[i] = (cur[i] + (a + b) // 2) & 255
                else:
                    c = prev[i - 3] if i >= 3 else 0
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    cur[i] = (cur[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out[y] = cur
        prev = cur
    return out.reshape(h, w, 3)

quad = [(0.22, 0.70), (0.30, 0.68), (0.31, 0.76), (0.23, 0.78)]

def outside_mm(n, mm_per_uv):
    """Per texel: mm outside the strokes' quadrilateral (0 inside)."""
    ys, xs = np.mgrid[0:n, 0:n]
    u, v = (xs + 0.5) / n, (ys + 0.5) / n
    d = np.full((n, n), np.inf)
    for k in range(4):
        (ax, ay), (bx, by) = quad[k], quad[(k + 1) % 4]
        t = np.clip(((u - ax) * (bx - ax) + (v - ay) * (by - ay)) / ((bx - ax) ** 2 + (by - ay) ** 2), 0, 1)
        d = np.minimum(d, np.hypot(u - ax - t * (bx - ax), v - ay - t * (by - ay)))
    return np.where(inside_quad(n), 0, d * mm_per_uv)

def inside_quad(n):
    ys, xs = np.mgrid[0:n, 0:n]
    u, v = (xs + 0.5) / n, (ys + 0.5) / n
    ok = np.ones((n, n), bool)
    for k in range(4):
        (ax, ay), (bx, by) = quad[k], quad[(k + 1) % 4]
        ok &= (bx - ax) * (v - ay) - (by - ay) * (u - ax) >= 0
    return ok

res = {}
for n in (512, 1024):
    d = "%s/w%d" % (sys.argv[1], n)
    mm_per_uv = json.load(open(d + "/timeline.json"))["mm_per_uv"]
    rgb = png_rgb(d + "/frames/t0_base_color.png").astype(float) / 255
    x0, x1, y0, y1 = int(0.19 * n), int(0.34 * n), int(0.65 * n), int(0.81 * n)
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    # coverage of the bed: its green in linear light (the bed has almost
    # none); a dark mole or hair of the base skin (the run with the far
    # stroke: its texels here are the base skin's) is skin. A colour rule
    # alone (red low, blue under green) took the dark red bed's rim mixtures,
    # (162, 103, 82), for a mole.
    base = png_rgb("%s/b%d/frames/t0_base_color.png" % (sys.argv[1], n)).astype(float) / 255
    bl = np.where(base <= 0.04045, base / 12.92, ((base + 0.055) / 1.055) ** 2.4)[..., 1]
    dark = bl < 0.7 * np.median(bl[int(0.65 * n):int(0.81 * n), int(0.19 * n):int(0.34 * n)])
    mole = dark.copy()
    # and looking like one here, brown (the dark red bed over a mole is bed)
    mole &= ((rgb[..., 0] < 0.65) & (rgb[..., 2] < 0.8 * rgb[..., 1]) & (rgb[..., 1] > 0.12) &
             (rgb[..., 1] > 0.4 * rgb[..., 0]))
    red = np.where(mole, -1e9, -lin[..., 1])
    r = red[y0:y1, x0:x1]
    q = inside_quad(n)[y0:y1, x0:x1]
    core = np.zeros_like(q)
    c = (slice(int(0.72 * n) - y0, int(0.74 * n) - y0), slice(int(0.25 * n) - x0, int(0.28 * n) - x0))
    core[c] = True
    skin = -np.median(lin[y0:y0 + 4, x0:x1, 1]), np.median(r[core])
    w = np.clip((r - skin[0]) / (skin[1] - skin[0]), 0, 1)
    # the rim: texels inside the quadrilateral or within 3 mm of it (moles
    # and hairs further out are the skin's own)
    near = outside_mm(n, mm_per_uv)[y0:y1, x0:x1] < 3
    w = np.where(near, w, 0)
    tex_mm = mm_per_uv / n
    band = (w > 0.1) & (w < 0.9)
    area = (w > 0.5).sum() * tex_mm ** 2
    # the outline's length: edge texels of the w > 0.5 region
    m = w > 0.5
    edge = (m[1:-1, 1:-1] & ~(m[:-2, 1:-1] & m[2:, 1:-1] & m[1:-1, :-2] & m[1:-1, 2:])).sum()
    length = edge * tex_mm * 0.9  # a digital outline's texel count ~ length / 1.1 texels
    width = band.sum() * tex_mm ** 2 / length
    # steps between neighbours, except next to a mole of the base skin (its
    # texels half under the bed's rim are neither skin nor bed)
    mb = dark[y0:y1, x0:x1]
    mb = mb | np.roll(mb, 1, 0) | np.roll(mb, -1, 0) | np.roll(mb, 1, 1) | np.roll(mb, -1, 1)
    jump = max(np.where(mb[1:] | mb[:-1], 0, np.abs(np.diff(w, axis=0))).max(),
               np.where(mb[:, 1:] | mb[:, :-1], 0, np.abs(np.diff(w, axis=1))).max())
    nb = np.stack([w[1 + dy:w.shape[0] - 1 + dy, 1 + dx:w.shape[1] - 1 + dx]
                   for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx])
    # a tab is wound among skin or skin among wound: off in coverage and in
    # redness (a skin's dark follicle dot is off in green only)
    rd = ((rgb[..., 0] - rgb[..., 1]) / np.maximum(rgb[..., 0], 1e-3))[y0:y1, x0:x1]
    nr = np.stack([rd[1 + dy:rd.shape[0] - 1 + dy, 1 + dx:rd.shape[1] - 1 + dx]
                   for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx])
    off_w = w[1:-1, 1:-1] - np.median(nb, axis=0)
    off_r = rd[1:-1, 1:-1] - np.median(nr, axis=0)
    iso = ((np.abs(off_w) > 0.5) & (np.abs(off_r) > 0.15) & (off_w * off_r > 0)).sum()
    cover = (m & q).sum() / q.sum()
    res[n] = dict(width=width, jump=jump, iso=int(iso), cover=cover)
    print("size %d: texel %.3f mm, edge width %.3f mm, largest jump %.2f, isolated %d, "
          "quad covered %.3f" % (n, tex_mm, width, jump, iso, cover))
a, b = res[512], res[1024]
assert b["jump"] <= 0.6, "stepped edge at 1024: a jump of %.2f" % b["jump"]
ratio = a["width"] / b["width"]
assert 1 / 1.35 <= ratio <= 1.35, "edge width %.3f mm at 512, %.3f at 1024" % (a["width"], b["width"])
for n in res:
    assert res[n]["iso"] == 0, "%d isolated rim texels at %d" % (res[n]["iso"], n)
    assert 0.75 < res[n]["cover"] < 0.97, "quad covered %.3f at %d" % (res[n]["cover"], n)
PY
echo "e2e_wound_mesh_edge: all checks passed"
