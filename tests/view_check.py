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
  view_check.py ring RING.png PLAIN.png X Y
      the brush ring: the pixels that differ are white (red with --eraser)
      and lie on a circle around the cursor (X, Y) (their distances to it
      spread by less than a third of the mean), the cursor itself unchanged;
      prints the radius.
  view_check.py confined A.png B.png X Y R
      the frames differ (by more than 12 in the sum of R, G, B, on the mesh
      in both), 95 % of those pixels within R pixels of (X, Y).
  view_check.py mirrored STROKES.csv
      the stroke points are symmetric in u: each (u, v) has a (1 - u, v)
      within 1e-3, and there are points on both sides of u = 0.5.
  view_check.py mask MASK.png STROKES.csv
      a UV mask of the strokes: grey 8-bit, white in 0.1 %..50 % of it and
      white at the centroid of each stroke's points, black at the corners.
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
            assert depth == 8 and ctype in (0, 2, 6), path + ": expected 8-bit grey or RGB(A)"
            ch = {0: 1, 2: 3, 6: 4}[ctype]
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


def changed_pixels(a_path, b_path, tol=0):
    w, h, a = pixels(a_path)
    w2, h2, b = pixels(b_path)
    assert (w, h) == (w2, h2), "frames differ in size"
    out = []
    for i, (p, q) in enumerate(zip(a, b)):
        if abs(p[0] - q[0]) + abs(p[1] - q[1]) + abs(p[2] - q[2]) > tol:
            out.append((i % w, i // w, p, q))
    return out


def check_ring(ring, plain, x, y, eraser=False):
    ch = changed_pixels(ring, plain)
    assert len(ch) >= 12, "only %d pixels changed: no brush ring" % len(ch)
    for px, py, p, _ in ch:
        if eraser:
            assert p[0] > 200 and p[1] < 120 and p[2] < 120, "ring pixel %s at %d,%d not red" % (p, px, py)
        else:
            assert min(p) > 200, "ring pixel %s at %d,%d not white" % (p, px, py)
    d = [((px - x) ** 2 + (py - y) ** 2) ** 0.5 for px, py, _, _ in ch]
    mean = sum(d) / len(d)
    assert mean >= 2, "ring of radius %.1f px: a dot, not a ring" % mean
    assert max(d) - min(d) < mean / 3 + 1.5, "changed pixels %.1f..%.1f px from the cursor: not a ring" % (min(d), max(d))
    print("ring: %d pixels, radius %.2f px" % (len(ch), mean))
    return mean


def check_confined(a_path, b_path, x, y, r):
    # a few 8-bit steps of shading elsewhere are not the wound (the height
    # range of the loaded maps differs from the plain skin's), nor is the
    # silhouette (displaced by the same difference); a pixel seen at a
    # grazing angle samples a coarse mipmap level, which averages the block
    # in: 95 % of the changed pixels must be within R
    ch = changed_pixels(a_path, b_path, 12)
    bg = pixels(b_path)[2][0]
    ch = [c for c in ch if not is_background(c[2], bg) and not is_background(c[3], bg)]
    assert len(ch) >= 20, "only %d pixels changed" % len(ch)
    far = [c for c in ch if (c[0] - x) ** 2 + (c[1] - y) ** 2 > r * r]
    assert len(far) <= 0.05 * len(ch), "%d of %d changed pixels lie more than %d px from (%d,%d), e.g. %s" % (
        len(far), len(ch), r, x, y, far[0][:2])
    print("confined: %d of %d changed pixels within %d px of (%d,%d)" % (len(ch) - len(far), len(ch), r, x, y))


def read_csv_points(path):
    rows = [l.strip().split(",") for l in open(path) if l.strip()]
    head = rows[0]
    iu, iv = head.index("u"), head.index("v")
    ist = head.index("stroke") if "stroke" in head else None
    return [(float(r[iu]), float(r[iv]), int(r[ist]) if ist is not None else 0) for r in rows[1:]]


def check_mirrored(csv):
    pts = read_csv_points(csv)
    assert pts, csv + ": no points"
    left = sum(1 for u, v, _ in pts if u < 0.5)
    right = sum(1 for u, v, _ in pts if u > 0.5)
    assert left and right, "points only on one side of u = 0.5 (%d left, %d right)" % (left, right)
    for u, v, _ in pts:
        assert any(abs(1 - u - u2) < 1e-3 and abs(v - v2) < 1e-3 for u2, v2, _ in pts), \
            "point (%.4f, %.4f) has no mirror image" % (u, v)
    print("mirrored: %d points, %d left and %d right of u = 0.5" % (len(pts), left, right))


def check_mask(mask, csv):
    w, h, ch, buf = read_png(mask)
    assert ch == 1, mask + ": not a grey mask"
    white = sum(1 for b in buf if b > 127)
    assert 0.001 * w * h < white < 0.5 * w * h, "%d of %d mask pixels white" % (white, w * h)
    for x, y in ((0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)):
        assert buf[y * w + x] < 128, "mask corner %d,%d is white" % (x, y)
    pts = read_csv_points(csv)
    for s in sorted(set(p[2] for p in pts)):
        sp = [p for p in pts if p[2] == s]
        u = sum(p[0] for p in sp) / len(sp)
        v = sum(p[1] for p in sp) / len(sp)
        x, y = min(w - 1, int(u * w)), min(h - 1, int(v * h))
        assert buf[y * w + x] > 127, "stroke %d: centroid (%.3f, %.3f) is black in the mask" % (s, u, v)
    print("mask: %d of %d pixels white, every stroke's centroid inside" % (white, w * h))


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
    elif cmd in ("ring", "eraser-ring"):
        check_ring(sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5]), cmd != "ring")
    elif cmd == "ring-ratio":  # ring SMALL.png BIG.png PLAIN.png X Y: BIG's radius ~2x SMALL's
        r1 = check_ring(sys.argv[2], sys.argv[4], float(sys.argv[5]), float(sys.argv[6]))
        r2 = check_ring(sys.argv[3], sys.argv[4], float(sys.argv[5]), float(sys.argv[6]))
        assert 1.6 < r2 / r1 < 2.5, "brush x2 gave a ring %.2f times as wide" % (r2 / r1)
        print("ring-ratio: %.2f" % (r2 / r1))
    elif cmd == "confined":
        check_confined(sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6]))
    elif cmd == "mirrored":
        check_mirrored(sys.argv[2])
    elif cmd == "mask":
        check_mask(sys.argv[2], sys.argv[3])
    else:
        sys.exit("unknown check " + cmd)
