#!/usr/bin/env bash
# End-to-end test of the keloid's height in `skinsim wound` (docs/wound.md,
# height; docs/heal-model.md [D16]): the height map follows the healing
# model's own surface elevation, unsaturated and unclipped. On one problem
# (a stroke, so heal and wound draw the same wound):
# - `skinsim wound` in memory: the day-60 and day-365 height maxima (the
#   frames' height_max_mm) are heal's elevation_max_mm of those days (area.csv)
#   within 3 % + 0.05 mm (the base skin's relief), and the keloid rises by more
#   than 1 mm from day 60 to day 365 (before: the recipe's 4 mm saturation gave
#   2.8 mm for heal's 4.8 at a year);
# - `skinsim wound --heal DIR` of that heal run: its frames are the in-memory
#   frames byte for byte (before: the snapshots did not hold the keloid's
#   added volume, so the elevation stopped at 1.79 mm);
# - the height PNG decodes (the frame's height_min_mm..height_max_mm) to that
#   maximum, with the wound's texels not piled at one value.
# usage: e2e_wound_keloid.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"

printf 'u,v\n0.3,0.35\n0.65,0.3\n0.7,0.62\n0.4,0.7\n' >"$T/stroke.csv"
PROB="--scenario keloid --size-mm 16,16,4 --grid 32x32x8 --skin-top-mm 3 --stroke $T/stroke.csv
      --adapt-tol 0"
# shellcheck disable=SC2086
"$CLI" heal $PROB --days 365 --snapshot-every 5 --area-every 1 --quiet --out "$T/h" ||
    fail "heal run failed"
# shellcheck disable=SC2086
"$CLI" wound $PROB --days 60,365 --size 96 --no-compare --quiet --out "$T/a" ||
    fail "wound (in memory) failed"
"$CLI" wound --heal "$T/h" --days 60,365 --size 96 --no-compare --quiet --out "$T/b" ||
    fail "wound --heal failed"

for d in 60 365; do
    for m in base_color roughness height normal; do
        cmp -s "$T/a/frames/t${d}_$m.png" "$T/b/frames/t${d}_$m.png" ||
            fail "day $d $m differs between --heal and the in-memory run"
    done
done

/usr/bin/python3 - "$T/h" "$T/a" <<'PY' || fail "the keloid's height does not follow heal's elevation"
import csv, json, struct, sys, zlib

def png16_gray(path):
    """The 16-bit grey values of a PNG (the five filter types)."""
    d = open(path, "rb").read()
    assert d[:8] == b"\x89PNG\r\n\x1a\n"
    i, idat = 8, b""
    while i < len(d):
        (n,) = struct.unpack(">I", d[i:i + 4])
        t, c = d[i + 4:i + 8], d[i + 8:i + 8 + n]
        if t == b"IHDR":
            w, h, bd, ct = struct.unpack(">IIBB", c[:10])
        elif t == b"IDAT":
            idat += c
        i += 12 + n
    assert bd == 16 and ct == 0, (bd, ct)
    stride, bpp = 2 * w, 2
    raw, out, prev, p = zlib.decompress(idat), bytearray(), bytearray(2 * w), 0
    for _ in range(h):
        f, line = raw[p], bytearray(raw[p + 1:p + 1 + stride])
        p += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    return [v for (v,) in struct.iter_unpack(">H", bytes(out))]

heal, wound = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(heal + "/area.csv")))
def elev_max(day):
    r = min(rows, key=lambda r: abs(float(r["t_days"]) - day))
    assert abs(float(r["t_days"]) - day) < 1e-6, r["t_days"]
    return float(r["elevation_max_mm"])
summary = json.load(open(heal + "/summary.json"))
assert abs(summary["surface_elevation_max_mm"] - elev_max(365)) < 1e-6
frames = {f["day"]: f for f in json.load(open(wound + "/timeline.json"))["frames"]}
hmax = {}
for day in (60, 365):
    f, e = frames[day], elev_max(day)
    hmax[day] = f["height_max_mm"]
    print("day %g: wound height max %.3f mm, heal elevation max %.3f mm" % (day, hmax[day], e))
    assert abs(hmax[day] - e) <= 0.03 * e + 0.05, (day, hmax[day], e)
    # the PNG holds that range: decoded, its top texels are the maximum
    lo, hi = f["height_min_mm"], f["height_max_mm"]
    v = png16_gray(wound + "/frames/t%g_height.png" % day)
    mm = [lo + x / 65535.0 * (hi - lo) for x in v]
    assert abs(max(mm) - hmax[day]) < 1e-3, (max(mm), hmax[day])
    # a keloid plateau, not a cap: fewer than a quarter of the texels within
    # 1 % of the range of the top (the old PNG encoding put 82 % at 65535)
    top = sum(1 for x in v if x >= 65535 * 0.99) / len(v)
    print("day %g: %.1f %% of the texels in the top 1 %% of the range" % (day, 100 * top))
    assert top < 0.25, top
assert hmax[365] > hmax[60] + 1.0, hmax
PY
echo "e2e_wound_keloid: ok"
