#!/usr/bin/env bash
# (needs python3 for the JSON and PNG checks: in the Makefile DEPS)
# End-to-end: `skinsim abrasion` as a user runs it: default shape, strokes,
# masks, several wounds, timeline JSON; and every bad input exits 2 with a
# message naming the input and leaves no output directory behind.
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2

# 1. Defaults (built-in stroke) at a small size.
"$CLI" abrasion --size 128 --out "$T/def" --quiet --times 0,0.02,1,5,12,30 >"$T/out.txt" 2>"$T/err.txt"
check '[ $? -eq 0 ]' "default run exit code ($(cat "$T/err.txt"))"
for ph in vasoconstriction vasodilation scab_forming scab maturation; do
  for m in color reflection height normal; do
    check '[ -s "$T/def/keys/${ph}_${m}.png" ]' "missing keys/${ph}_${m}.png"
  done
done
for t in 0 0.02 1 5 12 30; do
  check '[ -s "$T/def/frames/t${t}_color.png" ]' "missing frames/t${t}_color.png"
  check '[ -s "$T/def/frames/t${t}_normal.png" ]' "missing frames/t${t}_normal.png"
done
check '[ -s "$T/def/contact_sheet.png" ]' "missing contact sheet"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert len(d[\"frames\"])==6 and d[\"frames\"][5][\"phase\"]==\"maturation\" and len(d[\"keys\"])>=5" "$T/def/timeline.json"' "timeline.json content"
check '[ -z "$(ls "$T" | grep partial)" ]' "staging directory left behind"

# 2. Determinism: same seed, same bytes.
"$CLI" abrasion --size 128 --out "$T/def2" --quiet --times 0,0.02,1,5,12,30 --threads 1
check 'cmp -s "$T/def/frames/t5_color.png" "$T/def2/frames/t5_color.png"' "same seed gives different output"

# 3. Strokes with two wounds and a concave hull; --json summary.
printf 'u,v,stroke\n0.1,0.1,0\n0.4,0.1,0\n0.4,0.2,0\n0.2,0.2,0\n0.2,0.4,0\n0.1,0.4,0\n0.6,0.6,1\n0.9,0.6,1\n0.75,0.9,1\n' >"$T/s.csv"
"$CLI" abrasion --stroke "$T/s.csv" --hull concave --size 96 --times 0.5,20 --out "$T/str" --json --quiet >"$T/j.json"
check '[ $? -eq 0 ]' "strokes run"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"wounds\"]==2" "$T/j.json"' "--json says 2 wounds"

# 3b. glTF frames: valid JSON, every image and the buffer present, accessor
# counts consistent (checked with the Khronos validator by hand: 0 issues).
"$CLI" abrasion --size 64 --times 5 --gltf --out "$T/gl" --quiet
check '[ $? -eq 0 ]' "--gltf run"
check 'python3 - "$T/gl/frames/t5.gltf" <<PY
import json, os, sys, base64
g = json.load(open(sys.argv[1])); d = os.path.dirname(sys.argv[1])
assert g["asset"]["version"] == "2.0"
for im in g["images"]: assert os.path.getsize(os.path.join(d, im["uri"])) > 0, im
b = g["buffers"][0]; data = base64.b64decode(b["uri"].split(",", 1)[1]); assert len(data) == b["byteLength"]
for a in g["accessors"]:
    v = g["bufferViews"][a["bufferView"]]; assert v["byteOffset"] + v["byteLength"] <= len(data)
m = g["materials"][0]; assert "baseColorTexture" in m["pbrMetallicRoughness"] and "normalTexture" in m
PY' "glTF frame content"

# 3c. --exr: each map also as OpenEXR (magic 76 2f 31 01).
"$CLI" abrasion --size 64 --times 1 --exr --out "$T/ex" --quiet
check '[ $? -eq 0 ] && [ "$(head -c 4 "$T/ex/frames/t1_height.exr" | od -An -tx1 | tr -d " ")" = "762f3101" ]' "--exr output"

# 4. Mask input (a PNG written by the tool itself: the key colour of vasoconstriction is not a mask, so make one with python's zlib).
python3 - "$T/mask.png" <<'PY'
import struct, zlib, sys
w = h = 40
rows = b''.join(b'\x00' + bytes(255 if 10 <= x < 30 and 12 <= y < 28 else 0 for x in range(w)) for y in range(h))
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open(sys.argv[1], 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(rows)) + chunk(b'IEND', b''))
PY
"$CLI" abrasion --mask "$T/mask.png" --size 64 --times 1 --out "$T/mask" --quiet
check '[ $? -eq 0 ] && [ -s "$T/mask/frames/t1_color.png" ]' "mask run"

# 5. Bad inputs: exit 2, message names the input, nothing written.
expect2() { # name, expected text, args...
  local name=$1 text=$2; shift 2
  "$CLI" abrasion --quiet --size 64 --out "$T/bad" "$@" >/dev/null 2>"$T/e.txt"
  local rc=$?
  if [ $rc -ne 2 ]; then bad "$name: exit $rc, want 2"; return; fi
  if ! grep -q -- "$text" "$T/e.txt"; then bad "$name: message lacks '$text': $(cat "$T/e.txt")"; return; fi
  if [ -e "$T/bad" ] || ls "$T" | grep -q partial; then bad "$name: output left behind"; return; fi
  ok
}
printf 'not a png' >"$T/text.png"
python3 -c "import sys; open(sys.argv[1],'wb').write(open(sys.argv[2],'rb').read()[:60])" "$T/cut.png" "$T/mask.png"
python3 - "$T/empty.png" <<'PY'
import struct, zlib, sys
w = h = 8
rows = b''.join(b'\x00' + bytes(w) for y in range(h))
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open(sys.argv[1], 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(rows)) + chunk(b'IEND', b''))
PY
printf '0.1,0.1\n0.2,0.2\n' >"$T/two.csv"
printf '0.1,0.1\n0.2,0.2\n0.3,0.3\n' >"$T/line.csv"
printf '0.1,0.1\n1.2,0.2\n0.3,0.5\n' >"$T/out.csv"
printf '0.1,0.1\nnan,0.2\n0.3,0.5\n' >"$T/nan.csv"
printf '{"keys":[{"phase":"scab","day":5},{"phase":"scab","day":1}]}' >"$T/tl.json"
touch "$T/afile"
expect2 "missing mask" "nope.png" --mask "$T/nope.png"
expect2 "non-PNG mask" "text.png" --mask "$T/text.png"
expect2 "truncated mask" "cut.png" --mask "$T/cut.png"
expect2 "empty mask" "empty" --mask "$T/empty.png"
expect2 "two points" "two.csv" --stroke "$T/two.csv"
expect2 "collinear points" "line.csv" --stroke "$T/line.csv"
expect2 "point outside 0..1" "out.csv" --stroke "$T/out.csv"
expect2 "NaN point" "nan.csv" --stroke "$T/nan.csv"
expect2 "missing stroke file" "missing.csv" --stroke "$T/missing.csv"
expect2 "size 0" "--size" --size 0
expect2 "size too big" "--size" --size 20000
# 16384 px needs about 65 GB: refused up front on machines with less.
if [ "$(awk '/MemTotal/ {print $2}' /proc/meminfo)" -lt 60000000 ]; then
  expect2 "size too big for memory" "GB" --size 16384
fi
expect2 "negative time" "--times" --times 1,-2
expect2 "NaN time" "--times" --times nan
expect2 "bad hull" "--hull" --hull round
expect2 "bad timeline" "tl.json" --timeline "$T/tl.json"
expect2 "unknown option" "--bogus" --bogus
expect2 "stroke and mask" "not both" --stroke "$T/s.csv" --mask "$T/mask.png"
"$CLI" abrasion --quiet --size 64 --out "$T/afile/sub" >/dev/null 2>"$T/e.txt"
rc=$?
check '[ $rc -eq 2 ] && grep -q afile "$T/e.txt"' "unwritable out dir (exit $rc)"
"$CLI" abrasion --help >"$T/h.txt"
check '[ $? -eq 0 ] && grep -q -- "--stroke" "$T/h.txt" && grep -q -- "--times" "$T/h.txt"' "--help"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
