#!/usr/bin/env bash
# End-to-end: the input reproductions of issue 21 against the built command.
# Files named inside a file stay in its folder (glTF buffer URIs); a PNG
# chunk cannot claim more than the file holds; 1-bit PNG masks and textures
# are read; whole-file inputs are refused by size before they are read; .mci
# run lines need a name and a type; three messages name their file; a
# self-intersecting --wound-mesh is refused; heal --mesh checks its options
# before the mesh. Each refusal is exit 2 with nothing written.
# usage: e2e_inputs.sh <skinsim> [source dir]
set -u
export SKINSIM_THREADS=1
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
# exit 2, a message containing $1 (grep -E), nothing at output $2; the rest is the command
expect2() {
  local words="$1" out="$2"; shift 2
  (cd "$T" && timeout 60 "$CLI" "$@" >/dev/null 2>"$T/err.txt")
  local rc=$?
  if [ $rc -ne 2 ]; then bad "expected exit 2, got $rc: $* ($(cat "$T/err.txt"))"; return; fi
  if ! grep -qiE -- "$words" "$T/err.txt"; then bad "message lacks '$words': $(cat "$T/err.txt")"; return; fi
  if [ -n "$out" ] && [ -e "$T/$out" ]; then bad "$out written by: $*"; return; fi
  ok
}

# ---- glTF buffers outside the .gltf's folder ---------------------------------
mkdir -p "$T/secret" "$T/a/b"
python3 - "$T" <<'EOF'
import struct, json, sys, base64
T = sys.argv[1]
data = struct.pack('<9f', 0,0,0, 1,0,0, 0,1,0) + struct.pack('<6f', 0,0, 1,0, 0,1) + struct.pack('<3H', 0,1,2) + b'\0\0'
open(T + '/secret/secret.bin', 'wb').write(data)
open(T + '/a/b/own.bin', 'wb').write(data)
def scene(uri):
    return {"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
     "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"indices":2}]}],
     "buffers":[{"uri":uri,"byteLength":len(data)}],
     "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24},
                    {"buffer":0,"byteOffset":60,"byteLength":6}],
     "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
      {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"},
      {"bufferView":2,"componentType":5123,"count":3,"type":"SCALAR"}]}
for name, uri in [("up", "../../secret/secret.bin"), ("enc", "..%2F..%2Fsecret%2Fsecret.bin"),
                  ("abs", T + "/secret/secret.bin"), ("link", "link.bin"), ("own", "own.bin"),
                  ("data", "data:application/octet-stream;base64," + base64.b64encode(data).decode())]:
    json.dump(scene(uri), open(T + '/a/b/%s.gltf' % name, 'w'))
EOF
ln -s "$T/secret/secret.bin" "$T/a/b/link.bin"
expect2 "secret.bin.*outside its folder" sk1 skin --gltf --mesh a/b/up.gltf --size 64 --out sk1 --quiet
expect2 "outside its folder" sk2 skin --gltf --mesh a/b/enc.gltf --size 64 --out sk2 --quiet
expect2 "absolute path" sk3 skin --gltf --mesh a/b/abs.gltf --size 64 --out sk3 --quiet
expect2 "link.bin.*resolves to" sk4 skin --gltf --mesh a/b/link.gltf --size 64 --out sk4 --quiet
for ok_scene in own data; do
  (cd "$T" && timeout 120 "$CLI" skin --gltf --mesh a/b/$ok_scene.gltf --size 64 --out ok_$ok_scene --quiet)
  check '[ $? -eq 0 ] && [ -s "$T/ok_$ok_scene/skin.gltf" ]' "a glTF with a $ok_scene buffer was refused"
done

# ---- PNG: a chunk claiming 2 GB in a 44-byte file; 1-bit masks and textures ---
python3 - "$T" <<'EOF'
import struct, zlib, sys
T = sys.argv[1]
def chunk(t, d, n=None):
    return struct.pack('>I', len(d) if n is None else n) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
sig = b'\x89PNG\r\n\x1a\n'
bomb = sig + chunk(b'IHDR', struct.pack('>IIBBBBB', 1, 1, 8, 0, 0, 0, 0)) + struct.pack('>I', 0x7fffffff) + b'tEXtabc'
assert len(bomb) == 44
open(T + '/bomb.png', 'wb').write(bomb)
def png(path, w, h, depth, ctype, pix, palette=None):
    rows = bytearray()
    for y in range(h):
        rows.append(0); acc = 0; nb = 0
        for x in range(w):
            acc = (acc << depth) | pix(x, y); nb += depth
            if nb == 8: rows.append(acc); acc = 0; nb = 0
        if nb: rows.append(acc << (8 - nb))
    out = sig + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, depth, ctype, 0, 0, 0))
    if palette: out += chunk(b'PLTE', b''.join(bytes(c) for c in palette))
    out += chunk(b'IDAT', zlib.compress(bytes(rows), 9)) + chunk(b'IEND', b'')
    open(path, 'wb').write(out)
n = 2048; r = 76
png(T + '/m.png', n, n, 1, 0, lambda x, y: 1 if (x - n // 2) ** 2 + (y - n // 2) ** 2 < r * r else 0)
png(T + '/empty.png', 64, 64, 1, 0, lambda x, y: 0)
png(T + '/lower.png', 1024, 1024, 1, 3, lambda x, y: (x // 64 + y // 64) & 1, [(120, 30, 40), (200, 90, 80)])
EOF
expect2 "chunk tEXt.*2147483647" o_bomb abrasion --mask bomb.png --size 64 --out o_bomb --quiet
(cd "$T" && timeout 120 "$CLI" abrasion --mask m.png --size 128 --times 0,5 --out o_mask --quiet 2>"$T/err.txt")
check '[ $? -eq 0 ] && [ -s "$T/o_mask/frames/t5_color.png" ]' "a 1-bit mask was refused: $(cat "$T/err.txt")"
(cd "$T" && timeout 120 "$CLI" abrasion --mask m.png --lower lower.png --size 128 --times 0 --out o_low --quiet 2>"$T/err.txt")
check '[ $? -eq 0 ]' "a 1-bit palette --lower was refused: $(cat "$T/err.txt")"
expect2 "empty.png: .*empty" o_empty abrasion --mask empty.png --size 64 --out o_empty --quiet

# ---- whole-file inputs: a 2 GB sparse file is refused by its size ----------------
for f in big.csv big.json big.obj big.glb big.mci big.sstab; do truncate -s 2G "$T/$f"; done
expect2 "big.csv: .*64 MB limit" o1 abrasion --stroke big.csv --size 64 --out o1 --quiet
printf '0.4,0.4\n0.6,0.4\n0.5,0.6\n' >"$T/st.csv"
expect2 "big.json: .*16 MB limit" o2 abrasion --stroke st.csv --timeline big.json --size 64 --out o2 --quiet
expect2 "big.json: .*16 MB limit" o3 heal --params big.json --grid 8x8x4 --days 0.1 --out o3 --quiet
expect2 "big.obj: .*1024 MB limit" o4 heal --wound-mesh big.obj --grid 20x20x8 --days 0.1 --out o4 --quiet
expect2 "big.glb: .*1024 MB limit" o5 skin --gltf --mesh big.glb --size 64 --out o5 --quiet
expect2 "big.csv: .*64 MB limit" o6 skin --features-in big.csv --size 64 --out o6 --quiet
expect2 "big.sstab: .*512 MB limit" o7 skin --table big.sstab --size 64 --out o7 --quiet
expect2 "big.mci: .*16 MB limit" "" optics mci big.mci
rm -f "$T"/big.*

# ---- .mci: a run line without its type is refused, nothing written -----------------
printf '1.0\n1\nA\n2000\n0.01 0.01\n10 10 10\n1\n1.0\n1.0 10 90 0.75 0.02\n1.0\n' >"$T/bare.mci"
expect2 "name and type" A optics mci bare.mci

# ---- .mci: a 20000 x 20000 x 10 grid is refused before anything is allocated -----------
printf '1.0\n1\nbig.mco A\n2000\n0.01 0.01\n10 20000 20000\n1\n1.0\n1.0 10 90 0.75 0.02\n1.0\n' >"$T/grid.mci"
expect2 "grid.mci: line 6: run 1: grid .* above the limit of 10000000" big.mco optics mci grid.mci

# ---- messages that name their file ----------------------------------------------
printf '{"scenario": "burn"}\n' >"$T/p.json"
expect2 "p.json: .*scenario 'burn' unknown" o8 heal --params p.json --grid 8x8x4 --days 0.1 --out o8 --quiet
printf 'x1,y1,z1,x2,y2,z2\n10,10,3,10,10,3\n' >"$T/self.csv"
expect2 "self.csv: stitch 1 .*joins a node to itself" o9 heal --grid 40x40x8 --mechanics --sutures self.csv --days 0.1 --out o9 --quiet
python3 -c "print('x1,y1,z1,x2,y2,z2'); [print('6,10,3,14,10,3') for _ in range(10001)]" >"$T/many.csv"
expect2 "more than 10000 sutures" o10 heal --grid 40x40x8 --mechanics --sutures many.csv --days 0.1 --out o10 --quiet

# ---- --wound-mesh: a self-intersecting closed mesh is refused like --mesh's --------
python3 - "$T" <<'EOF'
import sys
T = sys.argv[1]
def box(o, s, base):
    x, y, z = o
    v = [(x+i*s, y+j*s, z+k*s) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    f = [(0,2,3),(0,3,1),(4,5,7),(4,7,6),(0,1,5),(0,5,4),(2,6,7),(2,7,3),(0,4,6),(0,6,2),(1,3,7),(1,7,5)]
    return v, [(a+base, b+base, c+base) for a, b, c in f]
v1, f1 = box((3, 3, 1), 3, 1)
v2, f2 = box((4.5, 4.5, 1.5), 3, 9)   # overlaps the first box: the surface crosses itself
with open(T + '/cross.obj', 'w') as o:
    for p in v1 + v2: o.write('v %g %g %g\n' % p)
    for t in f1 + f2: o.write('f %d %d %d\n' % t)
with open(T + '/one.obj', 'w') as o:
    for p in v1: o.write('v %g %g %g\n' % p)
    for t in f1: o.write('f %d %d %d\n' % t)
EOF
expect2 "cross.obj:[0-9]+: the mesh intersects itself" o11 heal --wound-mesh cross.obj --grid 20x20x8 --days 0.1 --out o11 --quiet
(cd "$T" && timeout 120 "$CLI" heal --wound-mesh one.obj --grid 20x20x8 --days 0.1 --out o12 --quiet 2>"$T/err.txt")
check '[ $? -eq 0 ]' "a closed box --wound-mesh was refused: $(cat "$T/err.txt")"

# ---- heal --mesh: options checked before the mesh --------------------------------
# an open mesh would be refused by the mesh check; the option error must come first
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$T/open.obj"
printf '0.5,0.5\n0.6,0.5\n0.5,0.6\n' >"$T/uv.csv"
expect2 "need --mechanics" o13 heal --mesh open.obj --wound-uv uv.csv --fibres 1,0,0 --out o13 --quiet
expect2 "--kappa" o14 heal --mesh open.obj --wound-uv uv.csv --mechanics --kappa 0.9 --out o14 --quiet
mkdir -p "$T/prev" && echo x >"$T/prev/mine.txt"
expect2 "is not a .skinsim heal. run folder" "" heal --mesh open.obj --wound-uv uv.csv --out prev --quiet
check '[ "$(cat "$T/prev/mine.txt")" = x ]' "a refused heal --mesh touched the --out folder"
expect2 "not a closed surface|too few triangles" o15 heal --mesh open.obj --wound-uv uv.csv --out o15 --quiet

echo "e2e_inputs: $pass checks passed, $fail failed"
[ $fail -eq 0 ]
