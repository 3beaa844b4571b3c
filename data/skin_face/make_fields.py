#!/usr/bin/env python3
"""Writes the face-like example fields of data/skin_face/ (seed 003 §5.1, Fig. 6):
greyscale probability fields for follicles, moles, freckles, cysts, wrinkle
starts and lips, and the RGB wrinkle vector field, for a front view of a face
unwrapped onto the texture (u to the right, v down; forehead at the top, chin
at the bottom). Standard library only (zlib + struct PNG writer).

usage: python3 data/skin_face/make_fields.py [OUT_DIR (default: this folder)] [SIZE (256)]
"""
import math
import os
import struct
import sys
import zlib


def write_png(path, w, h, channels, pixels):
    """pixels: list of rows, each a list of w tuples (or ints for grey), 0..255."""
    raw = bytearray()
    for row in pixels:
        raw.append(0)
        for p in row:
            if channels == 1:
                raw.append(p)
            else:
                raw.extend(p)
    colour = {1: 0, 3: 2}[channels]
    chunks = [
        (b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)),
        (b"IDAT", zlib.compress(bytes(raw), 9)),
        (b"IEND", b""),
    ]
    with open(path + ".tmp", "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        for tag, data in chunks:
            f.write(struct.pack(">I", len(data)) + tag + data)
            f.write(struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))
    os.replace(path + ".tmp", path)


def smooth(e0, e1, x):
    t = min(1.0, max(0.0, (x - e0) / (e1 - e0)))
    return t * t * (3 - 2 * t)


def ellipse(u, v, cu, cv, ru, rv, soft=0.25):
    """1 inside the ellipse, smooth fall to 0 over `soft` of its radius."""
    d = math.hypot((u - cu) / ru, (v - cv) / rv)
    return 1.0 - smooth(1.0 - soft, 1.0 + soft, d)


def gauss(u, v, cu, cv, s):
    return math.exp(-((u - cu) ** 2 + (v - cv) ** 2) / (2 * s * s))


EYES = ((0.33, 0.41), (0.67, 0.41))


def lips(u, v):
    return ellipse(u, v, 0.5, 0.765, 0.125, 0.042, 0.35)


def eyes(u, v):
    return max(ellipse(u, v, cu, cv, 0.085, 0.035, 0.3) for cu, cv in EYES)


def follicles(u, v):
    scalp = 1.0 - smooth(0.06, 0.13, v)
    brows = max(ellipse(u, v, cu, 0.335, 0.085, 0.022, 0.4) for cu, _ in EYES)
    beard = smooth(0.62, 0.70, v) * 0.55
    vellus = 0.05
    f = max(scalp, brows, beard, vellus)
    return f * (1.0 - lips(u, v)) * (1.0 - eyes(u, v))


def moles(u, v):
    return 0.35 * (1.0 - lips(u, v)) * (1.0 - eyes(u, v))


def freckles(u, v):
    f = max(gauss(u, v, 0.29, 0.53, 0.09), gauss(u, v, 0.71, 0.53, 0.09), gauss(u, v, 0.5, 0.5, 0.06))
    return f * (1.0 - eyes(u, v)) * (1.0 - lips(u, v))


def cysts(u, v):
    return 0.3 + 0.7 * max(gauss(u, v, 0.5, 0.9, 0.12), gauss(u, v, 0.5, 0.2, 0.15))


def nasolabial(u, v):
    """distance-based band along both folds (from beside the nose to beside the mouth)."""
    best = 1.0
    for side in (-1, 1):
        ax, ay, bx, by = 0.5 + side * 0.09, 0.58, 0.5 + side * 0.15, 0.76
        dx, dy = bx - ax, by - ay
        t = max(0.0, min(1.0, ((u - ax) * dx + (v - ay) * dy) / (dx * dx + dy * dy)))
        best = min(best, math.hypot(u - ax - t * dx, v - ay - t * dy))
    return 1.0 - smooth(0.0, 0.035, best)


def wrinkle_starts(u, v):
    forehead = smooth(0.12, 0.16, v) * (1.0 - smooth(0.26, 0.30, v)) * (1.0 - smooth(0.3, 0.4, abs(u - 0.5)))
    crows = max(gauss(u, v, 0.17, 0.42, 0.04), gauss(u, v, 0.83, 0.42, 0.04))
    under_eye = max(ellipse(u, v, cu, 0.465, 0.07, 0.02, 0.5) for cu, _ in EYES) * 0.6
    return max(forehead, crows, under_eye, nasolabial(u, v), 0.02)


def wrinkle_vector(u, v):
    """(dx, dy, length 0..1): horizontal on the forehead, radial from the
    outer eye corners, along the nasolabial folds, short elsewhere."""
    for cu, side in ((0.17, -1), (0.83, 1)):
        if gauss(u, v, cu, 0.42, 0.05) > 0.3:
            cx = cu - side * 0.06
            dx, dy = u - cx, v - 0.42
            n = math.hypot(dx, dy) or 1.0
            return dx / n, dy / n, 0.35
    if nasolabial(u, v) > 0.2:
        side = -1 if u < 0.5 else 1
        dx, dy = side * 0.06, 0.18
        n = math.hypot(dx, dy)
        return dx / n, dy / n, 0.9
    if 0.12 < v < 0.30:
        return 1.0, 0.04 * math.sin(6 * u), 1.0
    return 1.0, 0.2, 0.25


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    os.makedirs(out, exist_ok=True)
    grey = {
        "follicles": follicles,
        "moles": moles,
        "freckles": freckles,
        "cysts": cysts,
        "wrinkles": wrinkle_starts,
        "lips": lips,
    }
    for name, fn in grey.items():
        rows = [[int(round(255 * max(0.0, min(1.0, fn((x + 0.5) / n, (y + 0.5) / n))))) for x in range(n)]
                for y in range(n)]
        write_png(os.path.join(out, name + ".png"), n, n, 1, rows)
    rows = []
    for y in range(n):
        row = []
        for x in range(n):
            dx, dy, ln = wrinkle_vector((x + 0.5) / n, (y + 0.5) / n)
            row.append((int(round(127.5 + 127.5 * dx)), int(round(127.5 + 127.5 * dy)), int(round(255 * ln))))
        rows.append(row)
    write_png(os.path.join(out, "wrinkle_vectors.png"), n, n, 3, rows)
    print("wrote", ", ".join(list(grey) + ["wrinkle_vectors"]), "to", out)


if __name__ == "__main__":
    main()
