#!/usr/bin/env bash
# End-to-end test of `skinsim heal --mesh` (seed 001 §5.1, §5.4): the hand of
# data/meshes with a wound painted as UV strokes on
# the back of the hand runs with the mechanics on a coarse patch, writes the
# fields mapped onto the mesh (surface/skin_*.vtu + skin.pvd) and the
# skin_mesh block of summary.json; a checkpointed run resumed on another thread
# count is byte-identical; a wound given as a closed mesh runs; bad input (an
# open mesh, a self-intersecting mesh, strokes outside the UV islands, a
# stroke across two islands, a wound mesh away from the skin, a wound wrapping
# around a finger, --wound-uv without --mesh) exits 2 naming the input and
# writes nothing; an OBJ in metres is read as metres with a note, one whose
# size leaves mm or cm open is refused naming --mesh-units-mm.
# usage: e2e_heal_mesh.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2
HAND="$SRC/data/meshes/generic-hand-left.glb" # shipped with the repository
[ -f "$HAND" ] || fail "$HAND is missing"

# an ellipse of strokes on the back of the hand (UV island lower left)
python3 "$SRC/tests/strokes_ellipse.py" 0.2 0.62 0.02 0.014 >"$T/cut.csv"
# sanitizer runs (SKINSIM_TEST_QUICK): half the time
D=1; H=0.5
[ -n "${SKINSIM_TEST_QUICK:-}" ] && { D=0.5; H=0.25; }
# the myofibroblasts pull at once (kinetics off, docs/mech.md), so a day
# deforms the skin enough to check the mapping onto the mesh
printf '{"mechanics": {"tau_myo": {"value": 0, "unit": "day", "source": "e2e"}, "tau_remodel": {"value": 0, "unit": "day", "source": "e2e"}}}\n' >"$T/pull.json"
RUN="--mesh $HAND --wound-uv $T/cut.csv --voxel-mm 1 --mechanics --params $T/pull.json --snapshot-every $H --quiet"

# --- the hand, 1 day (0.5 quick), 2 threads
"$CLI" heal $RUN --days $D --threads 2 --out "$T/a" --json >"$T/a.json" || fail "hand run failed"
for f in surface/skin.pvd surface/skin_0000.vtu surface/skin_0002.vtu fields/mesh_0002.vtu \
         surface/velocity_0002.png summary.json; do
    [ -s "$T/a/$f" ] || fail "missing $f"
done
for a in displacement epithelium scar open_wound; do
    grep -q "Name=\"$a\"" "$T/a/surface/skin_0002.vtu" || fail "skin .vtu lacks $a"
done
python3 - "$T/a.json" "$T/a/surface/skin_0000.vtu" "$T/a/surface/skin_0002.vtu" <<'PY' || fail "summary/skin values"
import json, re, sys
s = json.load(open(sys.argv[1]))
m, k = s["mechanics"], s["skin_mesh"]
assert k["triangles"] == 2314 and k["units_mm"] == 1000, k
# the surface the fields map onto: the mesh refined around the wound
assert k["surface_triangles"] > 2314 and k["surface_vertices"] > 1360, k
assert abs(sum(x * x for x in k["patch_normal"]) - 1) < 1e-9
assert m["tets"] > 500 and 0 < m["contraction_percent"] < 90, m
def arr(path, name):
    t = open(path).read()
    return [float(x) for x in re.search(r'Name="%s"[^>]*>(.*?)</DataArray>' % name, t, re.S).group(1).split()]
o0, o2 = arr(sys.argv[2], "open_wound"), arr(sys.argv[3], "open_wound")
assert sum(o0) > 0, "no vertex on the open wound at day 0"
d = arr(sys.argv[3], "displacement")
assert max(abs(x) for x in d) > 0.01, "no deformation mapped onto the mesh"
PY

# --- the same snapshots as binary glTF: valid (tests/gltf_check.py, the glTF
# 2.0 rules a viewer relies on; gltfpack's reader, cgltf_validate, where
# installed), the fields as _ attributes equal to the .vtu's, the open wound in
# COLOR_0, the displacement as a morph target
for f in surface/skin_0000.glb surface/skin_0002.glb; do
    [ -s "$T/a/$f" ] || fail "missing $f"
done
if command -v gltfpack >/dev/null; then
    for i in 0000 0002; do
        gltfpack -i "$T/a/surface/skin_$i.glb" -o "$T/repacked.glb" >/dev/null 2>"$T/gp.txt" \
            || fail "gltfpack rejects skin_$i.glb: $(cat "$T/gp.txt")"
    done
fi
PY=/usr/bin/python3
[ -x "$PY" ] || PY=$(command -v python3)
if "$PY" -c "import numpy" 2>/dev/null; then
    PYTHONPATH="$SRC/tests" "$PY" - "$T/a/surface" <<'PY' || fail "glb contents"
import re, sys
import numpy as np
import gltf_check
d = sys.argv[1]
def vtu(path, name):
    t = open(path).read()
    return np.array(re.search(r'Name="%s"[^>]*>(.*?)</DataArray>' % name, t, re.S).group(1).split(), float)
for i in ("0000", "0002"):
    doc, a = gltf_check.load("%s/skin_%s.glb" % (d, i))
    for f in ("oxygen", "mdgf", "capillary", "fibroblast", "eschar", "epithelium", "scar", "plasma",
              "open_wound"):
        x = a["_" + f.upper()]
        assert x.dtype == np.float32 and x.ndim == 1, f
        np.testing.assert_allclose(x, vtu("%s/skin_%s.vtu" % (d, i), f), rtol=1e-5, atol=1e-6)  # the .vtu has 6 digits
    n = len(a["POSITION"])
    assert doc["meshes"][0]["extras"]["targetNames"] == ["displacement"]
    assert doc["meshes"][0]["weights"] == [1]
    disp = a["target0/POSITION"] * 1000  # m -> mm
    np.testing.assert_allclose(disp.ravel(), vtu("%s/skin_%s.vtu" % (d, i), "displacement"), atol=1e-4)
    t = doc["nodes"][0]["extras"]["t_days"]
    assert (t == 0) == (i == "0000"), t
    c = a["COLOR_0"]
    op = a["_OPEN_WOUND"] > 0.5
    skin = np.all(np.abs(c - [0.70, 0.42, 0.32]) < 1e-6, axis=1)
    if i == "0000":
        assert op.any() and (a["_PLASMA"][op] > 0.5).all()
        assert np.all(c[op][:, 0] > 2 * c[op][:, 1]), "open wound not red"
        assert skin[~op].all(), "intact skin is not skin-coloured at day 0"
        assert np.abs(disp).max() == 0
    else:
        assert np.abs(disp).max() > 0.01, "no deformation in the morph target"
PY
fi

# --- checkpoint half way on 1 thread, resume to the end: the same bytes
"$CLI" heal $RUN --days $H --threads 1 --checkpoint-every $H --out "$T/b" || fail "checkpointed run failed"
"$CLI" heal --resume "$T/b" --days $D --threads 1 --quiet || fail "resume failed"
for f in fields/fields_0002.vti surface/skin_0002.vtu area.csv; do
    cmp -s "$T/a/$f" "$T/b/$f" || fail "resumed $f differs from the uninterrupted run"
done

# --- a closed wound mesh (an octahedron, in metres like the hand) on the back of the hand
python3 - "$T/a.json" >"$T/wound.obj" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["skin_mesh"]["wound_centre_mm"]
c = [x / 1000 for x in c]; r = 0.004
v = [(c[0]+r,c[1],c[2]),(c[0]-r,c[1],c[2]),(c[0],c[1]+r,c[2]),(c[0],c[1]-r,c[2]),(c[0],c[1],c[2]+r),(c[0],c[1],c[2]-r)]
for p in v: print("v %.7f %.7f %.7f" % p)
for f in ((1,3,5),(3,2,5),(2,4,5),(4,1,5),(3,1,6),(2,3,6),(4,2,6),(1,4,6)): print("f %d %d %d" % f)
PY
"$CLI" heal --mesh "$HAND" --wound-mesh "$T/wound.obj" --mesh-units-mm 1000 --voxel-mm 1 --days 0.2 \
    --quiet --out "$T/w" || fail "wound-mesh run failed"

# --- the shipped example abrasion (README, docs/wound.md): four strokes, concave hulls
"$CLI" heal --mesh "$HAND" --wound-uv "$SRC/data/heal/hand_abrasion_uv.csv" --concave-k 6 \
    --voxel-mm 1 --days 0.1 --snapshot-every 0 --quiet --out "$T/ex" --json >"$T/ex.json" \
    || fail "the example abrasion does not run"
python3 -c "
import json, sys
w = json.load(open(sys.argv[1]))['wound']
assert w['voxels'] > 100, w
" "$T/ex.json" || fail "the example abrasion cuts too little"

# --- bad input: exit 2 naming the input, nothing written
bad() {
    local what=$1
    shift
    rm -rf "$T/bad"
    "$CLI" heal --days 0.1 --quiet --out "$T/bad" "$@" 2>"$T/err.txt"
    [ $? -eq 2 ] || fail "exit code for: $*"
    [ ! -e "$T/bad" ] || fail "output written for: $*"
    grep -q -- "$what" "$T/err.txt" || fail "message does not name $what: $(cat "$T/err.txt")"
}
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n' >"$T/open.obj"
bad open.obj --mesh "$T/open.obj" --wound-uv "$T/cut.csv"
python3 - >"$T/twice.obj" <<'PY'
# two overlapping tetrahedra: closed, but their surfaces cross
for o in (0, 0.3):
    for p in ((0,0,0),(1,0,0),(0,1,0),(0,0,1)): print("v %g %g %g" % (p[0]+o, p[1]+o, p[2]+o))
for b in (0, 4):
    for f in ((1,3,2),(1,2,4),(1,4,3),(2,3,4)): print("f %d %d %d" % tuple(b + i for i in f))
PY
bad twice.obj --mesh "$T/twice.obj" --wound-mesh "$T/wound.obj"
printf 'u,v\n0.9,0.9\n0.95,0.9\n0.95,0.95\n' >"$T/off.csv"
bad off.csv --mesh "$HAND" --wound-uv "$T/off.csv"
printf 'u,v\n0.2,0.62\n0.22,0.62\n0.6,0.4\n' >"$T/seam.csv"
bad seam.csv --mesh "$HAND" --wound-uv "$T/seam.csv"
python3 -c "
for p in ((1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1)): print('v %g %g %g' % (p[0]+5, p[1]+5, p[2]+5))
for f in ((1,3,5),(3,2,5),(2,4,5),(4,1,5),(3,1,6),(2,3,6),(4,2,6),(1,4,6)): print('f %d %d %d' % f)
" >"$T/far.obj"
bad far.obj --mesh "$HAND" --wound-mesh "$T/far.obj"
# a wound wrapping around the index finger (the back of the finger's UV
# island reaches round to its side), as strokes and as a closed wound mesh
# around the finger: refused, not cut off at the steep sides
python3 "$SRC/tests/strokes_ellipse.py" 0.512 0.51 0.03 0.035 >"$T/wrap.csv"
bad "wrap.csv: the wound wraps around" --mesh "$HAND" --wound-uv "$T/wrap.csv"
grep -q "more than the 60 degrees" "$T/err.txt" || fail "the wrap message names no limit"
python3 -c "
c = (-0.0238, -0.0974, -0.0152); r = 0.010
for p in ((1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1)): print('v %.6f %.6f %.6f' % tuple(c[i] + r * p[i] for i in range(3)))
for f in ((1,3,5),(3,2,5),(2,4,5),(4,1,5),(3,1,6),(2,3,6),(4,2,6),(1,4,6)): print('f %d %d %d' % f)
" >"$T/ring.obj"
bad "ring.obj: the wound wraps around" --mesh "$HAND" --wound-mesh "$T/ring.obj" --mesh-units-mm 1000
bad "need --mesh" --wound-uv "$T/cut.csv"

# --- OBJ units from the mesh's size (docs/mesh.md "Units"): a forearm-sized
# ellipsoid (0.24 x 0.08 x 0.06 m) with an octahedral wound on its top,
# written in metres, mm and cm. Metres (diagonal 0.26) is read as metres with
# a note and cuts the same voxels as mm (to float rounding) (diagonal 260, the default); cm
# (diagonal 26) is ambiguous: refused naming --mesh-units-mm, and with
# --mesh-units-mm 10 it cuts the same voxels again.
for u in m mm cm; do
    python3 - "$u" "$T/arm_$u.obj" "$T/cut_$u.obj" <<'PY'
import math, sys
s = {"m": 1.0, "mm": 1000.0, "cm": 100.0}[sys.argv[1]]
a, b, c, nu, nv = 0.12, 0.04, 0.03, 48, 24
with open(sys.argv[2], "w") as o:
    for j in range(nv + 1):
        th = math.pi * j / nv
        for i in range(nu + 1):
            ph = 2 * math.pi * i / nu
            p = (a * math.sin(th) * math.cos(ph), b * math.sin(th) * math.sin(ph), c * math.cos(th))
            o.write("v %.9g %.9g %.9g\nvt %.6f %.6f\n" % (p[0] * s, p[1] * s, p[2] * s, i / nu, j / nv))
    k = lambda i, j: j * (nu + 1) + i + 1
    for j in range(nv):
        for i in range(nu):
            q = (k(i, j), k(i, j + 1), k(i + 1, j + 1), k(i + 1, j))
            if j < nv - 1: o.write("f %d/%d %d/%d %d/%d\n" % (q[0], q[0], q[1], q[1], q[2], q[2]))
            if j > 0: o.write("f %d/%d %d/%d %d/%d\n" % (q[0], q[0], q[2], q[2], q[3], q[3]))
r, z = 0.004, c - 0.0015
with open(sys.argv[3], "w") as o:
    for p in ((r,0,z),(-r,0,z),(0,r,z),(0,-r,z),(0,0,z+r),(0,0,z-r)):
        o.write("v %.9g %.9g %.9g\n" % tuple(x * s for x in p))
    for f in ((1,3,5),(3,2,5),(2,4,5),(4,1,5),(3,1,6),(2,3,6),(4,2,6),(1,4,6)):
        o.write("f %d %d %d\n" % f)
PY
done
units_run() { # name, then the options
    local n=$1
    shift
    "$CLI" heal --voxel-mm 1 --days 0.1 --snapshot-every 0 --out "$T/u_$n" --json "$@" \
        >"$T/u_$n.json" 2>"$T/u_$n.err" || fail "units run $n: $(cat "$T/u_$n.err")"
}
units_run mm --mesh "$T/arm_mm.obj" --wound-mesh "$T/cut_mm.obj"
units_run m --mesh "$T/arm_m.obj" --wound-mesh "$T/cut_m.obj"
grep -q "arm_m.obj: read in metres" "$T/u_m.err" || fail "no metre note: $(cat "$T/u_m.err")"
! grep -q "metres" "$T/u_mm.err" || fail "a mm OBJ got a metre note"
bad "arm_cm.obj: .*--mesh-units-mm" --mesh "$T/arm_cm.obj" --wound-mesh "$T/cut_cm.obj"
units_run cm --mesh "$T/arm_cm.obj" --wound-mesh "$T/cut_cm.obj" --mesh-units-mm 10
python3 - "$T" <<'PY' || fail "the unit readings disagree"
import json, sys
w = {u: json.load(open("%s/u_%s.json" % (sys.argv[1], u)))["wound"] for u in ("mm", "m", "cm")}
s = json.load(open(sys.argv[1] + "/u_m/summary.json"))["skin_mesh"]
assert s["units_mm"] == 1000, s
assert w["mm"]["voxels"] > 20, w
for u in ("m", "cm"):
    # the same cut up to a voxel or two on its boundary (float rounding of the scaled positions)
    assert abs(w[u]["voxels"] - w["mm"]["voxels"]) <= 0.05 * w["mm"]["voxels"], w
    assert abs(w[u]["radius_mm"] - w["mm"]["radius_mm"]) < 1e-6 * w["mm"]["radius_mm"], w
PY
echo "e2e_heal_mesh: OK"
