#!/usr/bin/env python3
"""Checks for tests/e2e_view.sh, standard library only (no numpy, no PIL).

  view_check.py skin SHOT.png
      the hand at day 0 shows skin: enough non-background pixels, skin-like
      (R > G > B, not grey, not saturated red).
  view_check.py redder WOUND.png PLAIN.png
      pixels that changed between a wounded and an unwounded frame (same
      camera) are redder (R - G) on average than the unchanged hand pixels.
  view_check.py strokes MESH.glb STROKES.csv SUMMARY.json
      every stroke's points lie in one UV island of the mesh (found by this
      script's own UV-triangle lookup and island labelling), that island is
      the one under the cursor where the stroke was painted (the picks in the
      viewer's JSON summary), a gesture across a seam was split, and each
      pick lies inside the convex hull of its stroke (the hull covers the
      painted spot; at a seam, on its outline).
  view_check.py changed A.png B.png X Y R
      the frames differ inside the disc of radius R around pixel (X, Y).
  view_check.py help WINDOW.png
      a window shot shows the F1 help: a dark box with light text over the
      middle of the 3D view.
"""
import json
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path + ": not a PNG"
    pos, idat, w, h, ch = 8, b"", 0, 0, 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and ctype in (2, 6), path + ": expected 8-bit RGB(A)"
            ch = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    stride = w * ch
    out = bytearray(h * stride)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if f == 1:
            for i in range(ch, stride):
                line[i] = (line[i] + line[i - ch]) & 255
        elif f == 2:
            for i in range(stride):
                line[i] = (line[i] + prev[i]) & 255
        elif f == 3:
            for i in range(stride):
                left = line[i - ch] if i >= ch else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 255
        elif f == 4:
            for i in range(stride):
                a = line[i - ch] if i >= ch else 0
                b = prev[i]
                c = prev[i - ch] if i >= ch else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pr) & 255
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return w, h, ch, out


def pixels(path):
    w, h, ch, buf = read_png(path)
    return w, h, [tuple(buf[i:i + 3]) for i in range(0, len(buf), ch)]


def is_background(p, bg):
    return abs(p[0] - bg[0]) + abs(p[1] - bg[1]) + abs(p[2] - bg[2]) < 12


def check_skin(path):
    w, h, px = pixels(path)
    bg = px[0]
    hand = [p for p in px if not is_background(p, bg)]
    frac = len(hand) / len(px)
    assert frac > 0.05, "%s: only %.1f%% of the frame shows the mesh" % (path, 100 * frac)
    r = sum(p[0] for p in hand) / len(hand)
    g = sum(p[1] for p in hand) / len(hand)
    b = sum(p[2] for p in hand) / len(hand)
    assert r > g > b, "%s: mean colour %.0f,%.0f,%.0f is not skin-like (R > G > B)" % (path, r, g, b)
    assert r - b > 15 and r > 80, "%s: mean colour %.0f,%.0f,%.0f is too grey or dark" % (path, r, g, b)
    assert g > 0.45 * r, "%s: mean colour %.0f,%.0f,%.0f is too red for healthy skin" % (path, r, g, b)
    print("skin: %.1f%% of the frame, mean sRGB %.0f,%.0f,%.0f" % (100 * frac, r, g, b))


def check_redder(wound, plain):
    w1, h1, a = pixels(wound)
    w2, h2, b = pixels(plain)
    assert (w1, h1) == (w2, h2), "frames differ in size"
    bg = b[0]
    changed, same = [], []
    for p, q in zip(a, b):
        if is_background(q, bg):
            continue
        if abs(p[0] - q[0]) + abs(p[1] - q[1]) + abs(p[2] - q[2]) > 30:
            changed.append(p)
        else:
            same.append(p)
    assert len(changed) > 200, "only %d pixels changed: no wound visible" % len(changed)
    red_w = sum(p[0] - p[1] for p in changed) / len(changed)
    red_s = sum(p[0] - p[1] for p in same) / len(same)
    assert red_w > red_s + 10, "wound R-G %.1f not redder than skin %.1f" % (red_w, red_s)
    print("redder: %d wound pixels with R-G %.1f, %d skin pixels with R-G %.1f" %
          (len(changed), red_w, len(same), red_s))


def read_glb_uvs(path):
    data = open(path, "rb").read()
    jlen = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + jlen])
    blen = struct.unpack("<I", data[20 + jlen:24 + jlen])[0]
    binary = data[28 + jlen:28 + jlen + blen]
    prim = doc["meshes"][0]["primitives"][0]

    def accessor(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        off = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[a["type"]]
        fmt = {5126: "f", 5123: "H", 5125: "I"}[a["componentType"]]
        size = struct.calcsize(fmt)
        stride = v.get("byteStride", n * size)
        return [struct.unpack_from("<%d%s" % (n, fmt), binary, off + k * stride) for k in range(a["count"])]

    uv = accessor(prim["attributes"]["TEXCOORD_0"])
    idx = [t[0] for t in accessor(prim["indices"])]
    return uv, [idx[i:i + 3] for i in range(0, len(idx), 3)]


def islands(uv, tris):
    parent = {}

    def find(x):
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for t in tris:
        keys = [uv[v] for v in t]
        for k in keys[1:]:
            ra, rb = find(keys[0]), find(k)
            if ra != rb:
                parent[ra] = rb
    return [find(uv[t[0]]) for t in tris]


def locate(uv, tris, p):
    found = []
    for i, t in enumerate(tris):
        (ax, ay), (bx, by), (cx, cy) = uv[t[0]], uv[t[1]], uv[t[2]]
        d = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay)
        if d == 0:
            continue
        l1 = ((p[0] - ax) * (cy - ay) - (cx - ax) * (p[1] - ay)) / d
        l2 = ((bx - ax) * (p[1] - ay) - (p[0] - ax) * (by - ay)) / d
        if l1 >= -1e-6 and l2 >= -1e-6 and 1 - l1 - l2 >= -1e-6:
            found.append(i)
    return found


def hull(points):
    pts = sorted(set(points))
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def inside(poly, p, strict):
    """Inside the counter-clockwise hull; strict: not on its outline."""
    n = len(poly)
    for i in range(n):
        a, b = poly[i], poly[(i + 1) % n]
        c = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        if c < (1e-12 if strict else -1e-9):
            return False
    return True


def check_strokes(mesh, csv, summary):
    uv, tris = read_glb_uvs(mesh)
    isl = islands(uv, tris)
    strokes = {}
    for line in open(csv).read().splitlines()[1:]:
        u, v, s = line.split(",")
        strokes.setdefault(int(s), []).append((float(u), float(v)))
    assert strokes, "no strokes saved"
    stroke_island = {}
    for s, pts in strokes.items():
        assert len(pts) >= 3, "stroke %d has %d points" % (s, len(pts))
        seen = set()
        for p in pts:
            found = locate(uv, tris, p)
            assert found, "stroke %d point %s lies in no UV triangle" % (s, p)
            seen.add(frozenset(isl[t] for t in found))
        common = frozenset.intersection(*seen)
        assert len(common) >= 1, "stroke %d spans UV islands" % s
        stroke_island[s] = common
    picks = json.load(open(summary))["picks"]
    assert picks, "no picks in the summary"
    # Stroke ids in the file are renumbered in order of first appearance, as
    # the picks' ids are allocated: map them by order.
    pick_ids = []
    for p in picks:
        if p["stroke"] >= 0 and p["stroke"] not in pick_ids:
            pick_ids.append(p["stroke"])
    assert len(pick_ids) == len(strokes), "%d painted strokes, %d saved" % (len(pick_ids), len(strokes))
    file_id = {pid: k for k, pid in enumerate(pick_ids)}
    hulls = {s: hull(pts) for s, pts in strokes.items()}
    interior = 0
    for p in picks:
        if p["stroke"] < 0:
            continue
        s = file_id[p["stroke"]]
        under = frozenset(isl[t] for t in locate(uv, tris, (p["u"], p["v"])))
        assert under & stroke_island[s], "stroke %d is not in the island under the cursor at %s" % (s, p)
        # A pick at a seam has brush samples on one side only (the other side
        # is another island): it may lie on the hull's outline, never outside.
        assert inside(hulls[s], (p["u"], p["v"]), False), "pick %s outside its stroke's hull" % p
        interior += inside(hulls[s], (p["u"], p["v"]), True)
    assert interior >= 0.5 * len(picks), "only %d of %d picks inside their hull: no brush footprint" % (
        interior, len(picks))
    islands_used = set().union(*stroke_island.values())
    print("strokes: %d strokes in %d UV islands, %d picks all inside their island and hull" %
          (len(strokes), len(islands_used), len(picks)))
    return len(strokes), len(islands_used)


def check_changed(a_path, b_path, x, y, r):
    w, h, a = pixels(a_path)
    _, _, b = pixels(b_path)
    n = diff = 0
    for yy in range(max(0, y - r), min(h, y + r + 1)):
        for xx in range(max(0, x - r), min(w, x + r + 1)):
            if (xx - x) ** 2 + (yy - y) ** 2 > r * r:
                continue
            p, q = a[yy * w + xx], b[yy * w + xx]
            n += 1
            diff += abs(p[0] - q[0]) + abs(p[1] - q[1]) + abs(p[2] - q[2]) > 30
    assert diff > 0.3 * n, "only %d of %d pixels around (%d,%d) changed" % (diff, n, x, y)
    print("changed: %d of %d pixels around (%d,%d)" % (diff, n, x, y))


def check_help(path):
    w, h, px = pixels(path)
    box = [px[y * w + x] for y in range(h * 3 // 8, h * 5 // 8) for x in range(w * 3 // 8, w * 5 // 8)]
    dark = sum(1 for p in box if sum(p) < 3 * 30)
    light = sum(1 for p in box if min(p) > 190)
    assert dark > 0.4 * len(box) and light > 0.01 * len(box), \
        "no help box in the middle: %d dark, %d light of %d" % (dark, light, len(box))
    print("help: %d dark, %d light of %d pixels in the middle" % (dark, light, len(box)))


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "skin":
        check_skin(sys.argv[2])
    elif cmd == "redder":
        check_redder(sys.argv[2], sys.argv[3])
    elif cmd == "strokes":
        n, k = check_strokes(sys.argv[2], sys.argv[3], sys.argv[4])
        if len(sys.argv) > 5 and k < int(sys.argv[5]):
            sys.exit("expected strokes in at least %s islands, got %d" % (sys.argv[5], k))
    elif cmd == "changed":
        check_changed(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]))
    elif cmd == "help":
        check_help(sys.argv[2])
    else:
        sys.exit("unknown check " + cmd)
