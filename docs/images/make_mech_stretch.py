#!/usr/bin/env python3
# Writes docs/images/mech_stretch.svg (docs/mech.md, "Stress-stretch: the solver against the
# analytic GOH"): `skinsim mech stretch --axis x --fibres DEG --json` at stretches 1.0..1.3
# for fibres at 0, 30, 60 and 90 degrees from the axis, the tet solver's `stress_kpa` as open
# markers and the closed-form `analytic_stress_kpa` as lines, in two stacked panels (the full
# range, and 0..25 kPa where the off-axis curves sit), with the initial slope of excised human
# back skin (Ni Annaidh et al. 2012, J Mech Behav Biomed Mater 5:139: 1.18 +- 0.88 MPa, mean
# +- SD of 56 samples) as a grey wedge up to 5 % strain, where engineering and Cauchy stress
# differ by under 5 %. Plain SVG written by hand: standard library only, no matplotlib.
# It also prints the docs' table at 1.1 and 1.2 (solver, analytic, relative difference).
# Usage: python3 docs/images/make_mech_stretch.py [--skinsim build/skinsim]
#        [--out docs/images/mech_stretch.svg] [--points 13] [--threads 2]
import argparse, json, subprocess, sys

ANGLES = [0, 30, 60, 90]
COLOURS = {0: "#1f4e9c", 30: "#2e7d32", 60: "#d07000", 90: "#b3261e"}
MARKERS = {0: "circle", 30: "square", 60: "triangle", 90: "diamond"}
SLOPE_MPA, SLOPE_SD_MPA, WEDGE_END = 1.18, 0.88, 1.05  # Ni Annaidh et al. 2012 (abstract)
W, H = 700, 640
LEFT, RIGHT = 70, 545  # plot area x range; the legend sits right of it
PANELS = [(40, 300), (360, 580)]  # (top, bottom) of each panel's plot area


def run(skinsim, stretch, angle, threads):
    cmd = [skinsim, "mech", "stretch", "--stretch", "%.6g" % stretch, "--axis", "x",
           "--fibres", str(angle), "--tet-size-mm", "1", "--increments", "5",
           "--threads", str(threads), "--json"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("%s failed (exit %d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()))
    d = json.loads(p.stdout)
    if d.get("converged") is not True:
        sys.exit("%s did not converge" % " ".join(cmd))
    return d["stress_kpa"], d["analytic_stress_kpa"]


def ticks(lo, hi, n=6):
    raw = (hi - lo) / n
    step = min((s * 10 ** e for e in range(-3, 6) for s in (1, 2, 5) if s * 10 ** e >= raw))
    t, k = [], int(-(-lo // step))
    while k * step <= hi + 1e-9 * step:
        t.append(k * step)
        k += 1
    return t


def fmt(v):
    return ("%.3f" % v).rstrip("0").rstrip(".") if abs(v) < 1e4 else "%g" % v


def clip_polyline(pts, ymin):
    """Pieces of the polyline pts (SVG y, down) that lie below ymin (the plot's top edge)."""
    pieces, cur = [], []
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if y0 >= ymin and y1 >= ymin:
            cur = cur or [(x0, y0)]
            cur.append((x1, y1))
        elif y0 >= ymin:  # leaves through the top
            xc = x0 + (ymin - y0) / (y1 - y0) * (x1 - x0)
            pieces.append((cur or [(x0, y0)]) + [(xc, ymin)])
            cur = []
        elif y1 >= ymin:  # comes back in
            xc = x0 + (ymin - y0) / (y1 - y0) * (x1 - x0)
            cur = [(xc, ymin), (x1, y1)]
    if len(cur) > 1:
        pieces.append(cur)
    return pieces


def clip_polygon(pts, ymin):
    """Sutherland-Hodgman: the polygon pts cut to y >= ymin (SVG y, down)."""
    out = []
    for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1]):
        if y0 >= ymin:
            out.append((x0, y0))
        if (y0 >= ymin) != (y1 >= ymin):
            out.append((x0 + (ymin - y0) / (y1 - y0) * (x1 - x0), ymin))
    return out


def path(pts):
    return " ".join("%.1f,%.1f" % p for p in pts)


def marker(kind, x, y, colour):
    s = 'fill="white" stroke="%s" stroke-width="1.6"' % colour
    if kind == "circle":
        return '<circle cx="%.1f" cy="%.1f" r="4.2" %s/>' % (x, y, s)
    if kind == "square":
        return '<rect x="%.1f" y="%.1f" width="7.6" height="7.6" %s/>' % (x - 3.8, y - 3.8, s)
    if kind == "triangle":
        return '<polygon points="%.1f,%.1f %.1f,%.1f %.1f,%.1f" %s/>' % (
            x, y - 5, x - 4.6, y + 3.6, x + 4.6, y + 3.6, s)
    return '<polygon points="%.1f,%.1f %.1f,%.1f %.1f,%.1f %.1f,%.1f" %s/>' % (
        x, y - 5.2, x + 4.4, y, x, y + 5.2, x - 4.4, y, s)


def panel(out, top, bottom, ymax, data, stretches, title, title_low_right):
    xlo, xhi = stretches[0], stretches[-1]
    X = lambda v: LEFT + (v - xlo) / (xhi - xlo) * (RIGHT - LEFT)
    Y = lambda v: bottom - v / ymax * (bottom - top)
    for t in ticks(0, ymax):
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#e4e4e4"/>' % (
            LEFT, Y(t), RIGHT, Y(t)))
        out.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="black"/>' % (
            LEFT - 5, Y(t), LEFT, Y(t)))
        out.append('<text x="%d" y="%.1f" text-anchor="end">%s</text>' % (LEFT - 8, Y(t) + 4, fmt(t)))
    for t in ticks(xlo, xhi):
        out.append('<line x1="%.1f" y1="%d" x2="%.1f" y2="%d" stroke="black"/>' % (
            X(t), bottom, X(t), bottom + 5))
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%.2f</text>' % (X(t), bottom + 19, t))
    # the excised-skin initial slope: stress = slope * (lambda - 1), mean and mean +- SD
    lo, hi = SLOPE_MPA - SLOPE_SD_MPA, SLOPE_MPA + SLOPE_SD_MPA
    e = WEDGE_END - 1
    # lines and the wedge are cut at the panel's top by hand (not every renderer clips)
    wedge = [(X(1), Y(0)), (X(WEDGE_END), Y(1000 * lo * e)), (X(WEDGE_END), Y(1000 * hi * e))]
    out.append('<polygon points="%s" fill="#bdbdbd" fill-opacity="0.45"/>' % path(clip_polygon(wedge, top)))
    for piece in clip_polyline([(X(1), Y(0)), (X(WEDGE_END), Y(1000 * SLOPE_MPA * e))], top):
        out.append('<polyline points="%s" fill="none" stroke="#707070" stroke-width="1.4" '
                   'stroke-dasharray="4,3"/>' % path(piece))
    for a in ANGLES:
        for piece in clip_polyline([(X(s), Y(d[1])) for s, d in zip(stretches, data[a])], top):
            out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (
                path(piece), COLOURS[a]))
    for a in ANGLES:
        for s, d in zip(stretches, data[a]):
            if Y(d[0]) >= top:
                out.append(marker(MARKERS[a], X(s), Y(d[0]), COLOURS[a]))
    out.append('<rect x="%d" y="%d" width="%d" height="%d" fill="none" stroke="black"/>' % (
        LEFT, top, RIGHT - LEFT, bottom - top))
    if title_low_right:  # where the zoomed panel is empty
        out.append('<text x="%d" y="%d" font-weight="bold" text-anchor="end">%s</text>' % (
            RIGHT - 8, bottom - 10, title))
    else:
        out.append('<text x="%d" y="%d" font-weight="bold">%s</text>' % (LEFT + 8, top + 17, title))
    out.append('<text x="18" y="%.1f" text-anchor="middle" transform="rotate(-90 18 %.1f)">'
               'Cauchy stress along x, kPa</text>' % ((top + bottom) / 2, (top + bottom) / 2))


def legend(out, x, y):
    out.append('<text x="%d" y="%d" font-weight="bold">fibre angle</text>' % (x, y))
    out.append('<text x="%d" y="%d">from the axis</text>' % (x, y + 15))
    y += 38
    for a in ANGLES:
        out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (
            x, y, x + 30, y, COLOURS[a]))
        out.append(marker(MARKERS[a], x + 15, y, COLOURS[a]))
        out.append('<text x="%d" y="%d">%d&#176;</text>' % (x + 40, y + 4, a))
        y += 24
    y += 8
    out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="#555" stroke-width="2"/>' % (x, y, x + 30, y))
    out.append('<text x="%d" y="%d">analytic GOH</text>' % (x + 40, y + 4))
    y += 24
    out.append(marker("circle", x + 15, y, "#555"))
    out.append('<text x="%d" y="%d">tet solver</text>' % (x + 40, y + 4))
    y += 30
    out.append('<polygon points="%d,%d %d,%d %d,%d" fill="#bdbdbd" fill-opacity="0.6"/>' % (
        x, y + 8, x + 30, y - 6, x + 30, y + 4))
    out.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="#707070" stroke-width="1.4" '
               'stroke-dasharray="4,3"/>' % (x, y + 8, x + 30, y - 1))
    out.append('<text x="%d" y="%d">excised</text>' % (x + 40, y + 4))
    for i, t in enumerate(["human back skin,", "initial slope", "1.18 \u00b1 0.88 MPa",
                           "(N\u00ed Annaidh et al.", "2012), to 5 %"]):
        out.append('<text x="%d" y="%d" font-size="12">%s</text>' % (x, y + 24 + 15 * i, t))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--skinsim", default="build/skinsim")
    ap.add_argument("--out", default="docs/images/mech_stretch.svg")
    ap.add_argument("--points", type=int, default=13)
    ap.add_argument("--threads", type=int, default=2)
    o = ap.parse_args()
    if o.points < 2:
        sys.exit("--points: at least 2")
    stretches = [1.0 + 0.3 * i / (o.points - 1) for i in range(o.points)]
    for want in (1.1, 1.2):  # the table's stretches must be on the grid
        if min(abs(s - want) for s in stretches) > 1e-9:
            stretches = sorted(stretches + [want])
    data = {a: [run(o.skinsim, s, a, o.threads) for s in stretches] for a in ANGLES}
    ymax = max(d[1] for d in data[0]) * 1.08
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
           'font-family="DejaVu Sans, sans-serif" font-size="13">' % (W, H, W, H),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="24" font-size="15" font-weight="bold">Uniaxial stretch along x, GOH '
           'defaults, 384 tets (h = 1 mm)</text>' % LEFT]
    panel(out, PANELS[0][0], PANELS[0][1], ymax, data, stretches, "full range", False)
    panel(out, PANELS[1][0], PANELS[1][1], 25.0, data, stretches, "0 to 25 kPa", True)
    out.append('<text x="%d" y="%d" text-anchor="middle">stretch &#955; along x</text>' % (
        (LEFT + RIGHT) / 2, PANELS[1][1] + 42))
    legend(out, RIGHT + 16, PANELS[0][0] + 14)
    out.append('</svg>')
    with open(o.out, "w") as f:
        f.write("\n".join(out) + "\n")
    print("| fibres | stretch | solver, kPa | analytic, kPa | relative difference |")
    print("|---|---|---|---|---|")
    for a in ANGLES:
        for want in (1.1, 1.2):
            i = min(range(len(stretches)), key=lambda k: abs(stretches[k] - want))
            s, an = data[a][i]
            print("| %d | %.1f | %.9g | %.9g | %.1e |" % (a, want, s, an, abs(s - an) / abs(an)))
    print("wrote %s (%d stretches x %d angles)" % (o.out, len(stretches), len(ANGLES)), file=sys.stderr)


if __name__ == "__main__":
    main()
