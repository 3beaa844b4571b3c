#!/usr/bin/env bash
# End-to-end: `skinsim skin` as a user runs it: defaults, the seed preset with
# fields, features.csv round trip, determinism across thread counts, --gltf,
# --normal-convention; every bad input exits 2 naming the input and leaves no
# output folder behind. (python3 for the JSON checks: in the Makefile DEPS.)
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2

# 1. Defaults at a small size.
"$CLI" skin --size 256 --out "$T/def" --quiet >"$T/o" 2>"$T/e"
check '[ $? -eq 0 ]' "default run ($(cat "$T/e"))"
for f in base_color.png roughness.png specular.png height.png normal.png bio.exr features.csv \
         skin.json contact_sheet.png translucency.png cavity.png; do
  check '[ -s "$T/def/$f" ]' "missing $f"
done
check 'python3 - "$T/def/skin.json" "$T/def/features.csv" <<PY
import json, sys, csv
d = json.load(open(sys.argv[1]))
rows = list(csv.reader(open(sys.argv[2])))
assert rows[0][0] == "type" and len(rows) - 1 == sum(d["counts"].values()), (len(rows), d["counts"])
for k in ("cysts", "moles", "freckles", "wrinkles", "follicles"): assert k in d["counts"]
assert d["length_unit"] == "mm" and d["height_max_mm"] > d["height_min_mm"]
assert d["wrap"] is True and len(d["bio_channels"]) == 12 and d["bio_channels"][11] == "surface_roughness"
PY' "skin.json / features.csv content"
check '[ -z "$(ls "$T" | grep partial)" ]' "staging folder left behind"

# 2. Round trip: render the written features.csv again: same maps, same csv.
"$CLI" skin --size 256 --features-in "$T/def/features.csv" --out "$T/rt" --quiet --threads 1
check '[ $? -eq 0 ]' "--features-in run"
for f in base_color.png height.png normal.png features.csv bio.exr; do
  check 'cmp -s "$T/def/$f" "$T/rt/$f"' "round trip differs: $f"
done
# edit a feature (a big mole in the middle): the maps change
python3 - "$T/def/features.csv" "$T/edit.csv" <<PY
import sys
rows = open(sys.argv[1]).read().splitlines()
rows.append("moles,0.5,0.5,2,0,0.3,0.3,0,0,0,0,0,0,0,0")
open(sys.argv[2], "w").write("\n".join(rows) + "\n")
PY
"$CLI" skin --size 256 --features-in "$T/edit.csv" --out "$T/ed" --quiet
check '! cmp -s "$T/def/base_color.png" "$T/ed/base_color.png"' "edited mole does not show"

# 3. Threads: bit-identical.
"$CLI" skin --size 256 --out "$T/t2" --quiet --threads 2
check 'cmp -s "$T/def/base_color.png" "$T/t2/base_color.png" && cmp -s "$T/def/bio.exr" "$T/t2/bio.exr"' "thread count changes output"

# 4. The seed preset with the face fields (colour field read as luminance),
#    rejection sampler, glTF, DirectX normals.
FACE="$SRC/data/skin_face"
if [ -f "$FACE/follicles.png" ]; then
  "$CLI" skin --preset seed --size 256 --count follicles=20000 --field follicles="$FACE/follicles.png" \
    --field freckles="$FACE/freckles.png" --field lips="$FACE/lips.png" --field moles="$FACE/moles.png" \
    --field vectors="$FACE/wrinkle_vectors.png" --field wrinkles="$FACE/wrinkles.png" \
    --sampler rejection --gltf --normal-convention directx --out "$T/face" --json --quiet >"$T/face.json" 2>"$T/e"
  check '[ $? -eq 0 ]' "face run ($(cat "$T/e"))"
  check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"counts\"][\"follicles\"]==20000 and d[\"normal_convention\"]==\"directx\" and d[\"sampler\"]==\"rejection\"" "$T/face.json"' "face --json"
  check 'python3 - "$T/face/skin.gltf" <<PY
import json, os, sys
g = json.load(open(sys.argv[1])); d = os.path.dirname(sys.argv[1])
assert g["asset"]["version"] == "2.0"
for im in g["images"]: assert os.path.getsize(os.path.join(d, im["uri"])) > 0, im
# glTF requires +Y normals: with --normal-convention directx it points at normal_gl.png
n = g["materials"][0]["normalTexture"]["index"]
assert g["images"][g["textures"][n]["source"]]["uri"] == "normal_gl.png", g["images"]
PY' "glTF and its images"
  # normal_gl.png is normal.png (DirectX) with green flipped back
  check 'cmp -s "$T/face/normal_gl.png" "$T/face/normal.png"; [ $? -eq 1 ]' "normal_gl.png differs from the DirectX map"
  "$CLI" skin --preset seed --size 256 --count follicles=20000 --field follicles="$FACE/follicles.png" \
    --field freckles="$FACE/freckles.png" --field lips="$FACE/lips.png" --field moles="$FACE/moles.png" \
    --field vectors="$FACE/wrinkle_vectors.png" --field wrinkles="$FACE/wrinkles.png" \
    --sampler rejection --out "$T/face_gl" --quiet 2>"$T/e"
  check 'cmp -s "$T/face/normal_gl.png" "$T/face_gl/normal.png"' "normal_gl.png equals the OpenGL run's normal.png"
fi

# 4a. --no-bio: every map but bio.exr; the surface maps vary over the patch.
"$CLI" skin --size 128 --no-bio --out "$T/nobio" --json --quiet >"$T/nobio.json" 2>"$T/e"
check '[ $? -eq 0 ] && [ ! -e "$T/nobio/bio.exr" ] && [ -s "$T/nobio/translucency.png" ] && [ -s "$T/nobio/cavity.png" ]' "--no-bio run ($(cat "$T/e"))"
check 'python3 -c "import json,sys; assert json.load(open(sys.argv[1]))[\"bio_exr\"] is False" "$T/nobio.json"' "--no-bio in the summary"

# 4b. The material on the hand mesh's UVs.
HAND="$SRC/data/meshes/generic-hand-left.glb"
if [ -f "$HAND" ]; then
  "$CLI" skin --size 64 --gltf --mesh "$HAND" --no-wrap --out "$T/hand" --quiet 2>"$T/e"
  check '[ $? -eq 0 ]' "--mesh run ($(cat "$T/e"))"
  check 'python3 - "$T/hand/skin.gltf" <<PY
import json, sys
g = json.load(open(sys.argv[1]))
acc = g["accessors"][g["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"]]
assert acc["count"] > 1000, acc
assert g["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] == 0
PY' "glTF on the hand"
  # --pad: the same maps with a gutter around the UV islands (the values
  # themselves: test_mesh's test_uv_pad)
  "$CLI" skin --size 64 --gltf --mesh "$HAND" --no-wrap --pad 4 --out "$T/handpad" --quiet 2>"$T/e"
  check '[ $? -eq 0 ]' "--pad run ($(cat "$T/e"))"
  check '! cmp -s "$T/hand/base_color.png" "$T/handpad/base_color.png" && ! cmp -s "$T/hand/normal.png" "$T/handpad/normal.png"' "--pad changed nothing"
fi

# 5. Fixtures: an all-black field, an RGB field, a zero vector field, a truncated PNG.
python3 - "$SRC/data/skin_face" "$T" <<PY
import sys
sys.path.insert(0, sys.argv[1])
from make_fields import write_png
t = sys.argv[2]
write_png(t + "/black.png", 8, 8, 1, [[0] * 8 for _ in range(8)])
write_png(t + "/rgb.png", 8, 8, 3, [[(255, 0, 0) if x > 3 else (0, 0, 0) for x in range(8)] for _ in range(8)])
write_png(t + "/zero_vectors.png", 8, 8, 3, [[(128, 128, 255)] * 8 for _ in range(8)])
PY
head -c 60 "$T/rgb.png" >"$T/trunc.png"
"$CLI" skin --size 64 --out "$T/bl" --field moles="$T/black.png" --field cysts="$T/rgb.png" --quiet --json >"$T/bl.json" 2>"$T/e"
check '[ $? -eq 0 ]' "black/rgb field run ($(cat "$T/e"))"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); n=\" \".join(d[\"notes\"]); assert d[\"counts\"][\"moles\"]==0 and \"all black\" in n and \"luminance\" in n, n" "$T/bl.json"' "all-black and luminance notes"
check 'python3 - "$T/bl/features.csv" <<PY
import sys, csv
for r in list(csv.reader(open(sys.argv[1])))[1:]:
    if r[0] == "cysts": assert float(r[1]) >= 0.5, r
PY' "cysts only where the red (luminance > 0) half is"

# 6. Bad input: exit 2, names the input, nothing written.
expect2() { # name, args...
  local name=$1; shift
  rm -rf "$T/bad"
  "$CLI" skin --size 32 --out "$T/bad" --quiet "$@" >"$T/o" 2>"$T/e"
  local rc=$?
  check "[ $rc -eq 2 ]" "$name: exit $rc, expected 2 ($(cat "$T/e"))"
  check '[ ! -e "$T/bad" ]' "$name: output written"
  check '[ -s "$T/e" ]' "$name: no message"
}
expect2 "unknown feature" --count warts=3
check 'grep -q warts "$T/e"' "unknown feature not named"
expect2 "negative count" --count moles=-1
expect2 "NaN param" --param moles.r_sigma=nan
expect2 "unknown param" --param moles.colour=1
expect2 "missing field" --field moles="$T/nope.png"
check 'grep -q nope.png "$T/e"' "missing field not named"
expect2 "truncated field" --field cysts="$T/trunc.png"
expect2 "unknown field" --field hair="$T/trunc.png"
expect2 "missing table" --table "$T/nope.sstab"
printf 'not a table' >"$T/bad.sstab"
expect2 "bad table" --table "$T/bad.sstab"
expect2 "bad features csv" --features-in "$T/trunc.png"
printf 'type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3\nmoles,0.5,0.5,1e300,0,0,0,0,0,0,0,0,0,0,0\n' >"$T/big.csv"
expect2 "huge radius in features csv" --features-in "$T/big.csv"
check 'grep -q "big.csv:2" "$T/e"' "huge radius: file and line not named"
expect2 "bad size" --size -4
expect2 "bad convention" --normal-convention vulkan
expect2 "bad preset" --preset elbow
expect2 "zero vector field" --field vectors="$T/zero_vectors.png"
check 'grep -q "zero" "$T/e"' "zero vector field message"
expect2 "grey vector field" --field vectors="$T/black.png"
expect2 "NaN world size" --world-size-cm nan
expect2 "mesh without gltf" --mesh "$T/nope.glb"
expect2 "missing mesh" --gltf --mesh "$T/nope.glb"
expect2 "pad without mesh" --pad 4
expect2 "negative pad" --gltf --mesh "$SRC/data/meshes/generic-hand-left.glb" --pad -1

echo "e2e_skin: $pass passed, $fail failed"
[ $fail -eq 0 ]
