#!/usr/bin/env bash
# End-to-end: `skinsim view` as a user drives it, through GTK 4 on a display
# (a private Xvfb when there is none) and through EGL surfaceless: the hand at
# day 0 shows skin; the built-in wound at day 1 is redder than the skin
# around it (generated in the viewer and loaded from `skinsim abrasion`, a
# single texture set or a `skinsim wound` sequence); a
# scripted paint session writes strokes that stay in the UV island under the
# cursor (split at seams) and whose hulls cover the picks, which `skinsim
# abrasion` reads; paint + Generate + slider puts a wound where the paint
# was; --bench-frames prints its figures; bad input exits 2 naming the input
# and writes nothing; the window and EGL paths render the same frame, and
# Generate equals `skinsim abrasion` (also on a loaded skin, as --upper); a
# heal run folder renders as `skinsim wound --heal`; a wound block sits at
# its world size; the brush ring, eraser, undo/redo, mirror symmetry and
# the mask export do what they say; Generate's fast path makes the same
# bytes as its reference path (layers_hash). Skips (77) only when skinsim-view was not built or no
# display and no EGL can be made. Checks use tests/view_check.py (python3).
set -u
CLI=$1
SRC=$2
CHECK="python3 $SRC/tests/view_check.py"
HAND="$SRC/data/meshes/generic-hand-left.glb"
T=$(mktemp -d /tmp/skinsim-e2e-view-XXXXXX)
XPID=""
trap 'rm -rf "$T"; [ -n "$XPID" ] && kill "$XPID" 2>/dev/null' EXIT
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"

if [ ! -x "$(dirname "$CLI")/skinsim-view" ]; then
  echo "skip: skinsim-view not built (GTK 4 or libepoxy missing at build time)"; exit 77
fi
# GTK, Mesa and fontconfig keep allocations to exit: leak reports from them
# are noise here (the library's own leaks are caught by test_mesh/test_paint).
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
export GTK_A11Y=none NO_AT_BRIDGE=1

# A display: the caller's, else a private Xvfb.
if [ -z "${DISPLAY:-}" ] && command -v Xvfb >/dev/null; then
  Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>"$T/dpy" 2>"$T/xvfb.log" &
  XPID=$!
  for _ in $(seq 100); do [ -s "$T/dpy" ] && break; sleep 0.1; done
  [ -s "$T/dpy" ] && export DISPLAY=":$(head -1 "$T/dpy")"
fi
V() { "$CLI" view --size 480x270 --texture-size 256 "$@"; }
GTK=1
if [ -z "${DISPLAY:-}" ] || ! V --screenshot "$T/probe.png" --quiet 2>"$T/probe.err"; then
  GTK=0
  echo "no usable display ($(cat "$T/probe.err" 2>/dev/null)); testing through EGL only"
  if ! V --egl --screenshot "$T/probe.png" --quiet 2>"$T/probe.err"; then
    echo "skip: no display and no EGL: $(cat "$T/probe.err")"; exit 77
  fi
fi
G=""; [ $GTK -eq 0 ] && G="--egl"

# 1. The hand at day 0, no wound: skin.
V $G --screenshot "$T/day0.png" --quiet
check '[ $? -eq 0 ] && $CHECK skin "$T/day0.png"' "day 0 is not skin"
# The same frame through EGL surfaceless (no display involved).
V --egl --screenshot "$T/day0_egl.png" --quiet
check '[ $? -eq 0 ] && $CHECK skin "$T/day0_egl.png"' "EGL day 0 is not skin"
[ $GTK -eq 1 ] && check 'cmp -s "$T/day0.png" "$T/day0_egl.png"' "the window and EGL paths render different frames"

# 2. The built-in wound at day 1 is redder than the skin around it:
#    generated in the viewer, and loaded from `skinsim abrasion`.
V $G --generate --time 1 --screenshot "$T/gen1.png" --quiet
check '[ $? -eq 0 ] && $CHECK redder "$T/gen1.png" "$T/day0.png"' "generated wound at day 1 not redder"
"$CLI" abrasion --size 256 --out "$T/ab" --quiet --times 1,20,30
V $G --load "$T/ab" --time 1 --screenshot "$T/load1.png" --json --quiet >"$T/load1.json"
check '[ $? -eq 0 ] && $CHECK redder "$T/load1.png" "$T/day0.png"' "loaded wound at day 1 not redder"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"layers\"]>=7 and d[\"end_day\"]==30" "$T/load1.json"' "loaded stack: keys and maturation frames"
# Generate in the viewer makes the same key textures as `skinsim abrasion`:
# at day 5 (the scab key held) the two frames are the same bytes.
V $G --generate --time 5 --screenshot "$T/gen5k.png" --quiet
V $G --load "$T/ab" --time 5 --screenshot "$T/load5k.png" --quiet
check 'cmp -s "$T/gen5k.png" "$T/load5k.png"' "Generate differs from skinsim abrasion at day 5"

# A single texture set (`skinsim skin` names: base_color, roughness, normal,
# height) loads as one layer.
mkdir -p "$T/set"
cp "$T/ab/frames/t1_color.png" "$T/set/base_color.png"
cp "$T/ab/frames/t1_normal.png" "$T/set/normal.png"
cp "$T/ab/frames/t1_height.png" "$T/set/height.png"
V $G --load "$T/set" --screenshot "$T/set1.png" --json --quiet >"$T/set1.json"
check '[ $? -eq 0 ] && $CHECK redder "$T/set1.png" "$T/day0.png"' "single texture set not shown"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"layers\"]==1" "$T/set1.json"' "single set: one layer"

# A healing sequence in the `skinsim wound` layout (no keys, frames with
# base_color/roughness/height/normal, height_range_mm): every frame is a stop.
mkdir -p "$T/seq/frames"
for d in 1 30; do
  cp "$T/ab/frames/t${d}_color.png" "$T/seq/frames/t${d}_base_color.png"
  cp "$T/ab/frames/t${d}_normal.png" "$T/seq/frames/t${d}_normal.png"
done
cat >"$T/seq/timeline.json" <<'EOF'
{"command":"wound","keys":[],"end_day":30,"height_range_mm":2,"frames":[
 {"day":1,"phase":"simulated","files":{"base_color":"frames/t1_base_color.png","color":"frames/t1_base_color.png","normal":"frames/t1_normal.png"}},
 {"day":30,"phase":"simulated","files":{"color":"frames/t30_base_color.png","normal":"frames/t30_normal.png"}}]}
EOF
V $G --load "$T/seq" --time 1 --screenshot "$T/seq1.png" --json --quiet >"$T/seq1.json"
check '[ $? -eq 0 ] && $CHECK redder "$T/seq1.png" "$T/day0.png"' "healing sequence not shown"
check 'python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"layers\"]==2 and d[\"end_day\"]==30" "$T/seq1.json"' "healing sequence: two layers to day 30"

# 3. Paint across the hand from the side (seams in view) and save strokes.
cat >"$T/paint.txt" <<'EOF'
# turn the hand to show its side, then paint three bands across it
drag 200 150 340 150 10
key p
drag 150 90 345 90 30
drag 150 128 345 128 30
drag 150 165 345 165 30
key p
EOF
V $G --script "$T/paint.txt" --save-strokes "$T/strokes.csv" --screenshot "$T/paint.png" --json --quiet >"$T/paint.json"
check '[ $? -eq 0 ] && [ -s "$T/strokes.csv" ]' "scripted paint session wrote no strokes"
check '$CHECK strokes "$HAND" "$T/strokes.csv" "$T/paint.json" 2' "painted strokes leave their UV island or hull"
"$CLI" abrasion --stroke "$T/strokes.csv" --size 64 --times 1 --out "$T/ab_painted" --quiet
check '[ $? -eq 0 ]' "skinsim abrasion cannot read the painted strokes"

# 4. Paint a cross on the back of the hand, Generate, slide to day 5: the
#    wound is where the paint was; the strokes load back.
cat >"$T/gen.txt" <<'EOF'
key p
drag 235 80 280 110 15
drag 280 80 235 110 15
key p
key h
key g
wait
slider 5
EOF
V $G --script "$T/gen.txt" --screenshot "$T/gen5.png" --save-strokes "$T/cross.csv" --quiet
check '[ $? -eq 0 ] && $CHECK changed "$T/gen5.png" "$T/day0.png" 257 95 8' "no wound where the cross was painted"
V $G --strokes "$T/cross.csv" --screenshot "$T/cross.png" --quiet
check '[ $? -eq 0 ] && $CHECK changed "$T/cross.png" "$T/day0.png" 257 95 8' "loaded strokes not shown"

# 5. --bench-frames prints median and 95th percentile with the resolution.
V $G --load "$T/ab" --bench-frames 8 --quiet >"$T/bench.txt"
check '[ $? -eq 0 ] && grep -q "median .* ms/frame, 95th percentile .* ms" "$T/bench.txt" && grep -q "480x270" "$T/bench.txt"' "bench output: $(cat "$T/bench.txt")"
cat "$T/bench.txt"

# 6. Bad input: exit 2, message names the input, nothing written.
expect2() { # name, grep pattern, args...
  local name=$1 pat=$2; shift 2
  rm -f "$T/bad.png"
  V $G --screenshot "$T/bad.png" --quiet "$@" >"$T/bad.out" 2>"$T/bad.err"
  local rc=$?
  if [ $rc -eq 2 ] && grep -q -- "$pat" "$T/bad.err" && [ ! -e "$T/bad.png" ]; then ok
  else bad "$name: rc=$rc, $(cat "$T/bad.err")"; fi
}
expect2 "missing mesh" "nope.glb" --mesh "$T/nope.glb"
head -c 5000 "$HAND" >"$T/cut.glb"
expect2 "truncated glb" "cut.glb" --mesh "$T/cut.glb"
printf '{"asset":{"version":"2.0"},"meshes":[' >"$T/broken.gltf"
expect2 "broken gltf" "broken.gltf" --mesh "$T/broken.gltf"
expect2 "missing texture folder" "nofolder" --load "$T/nofolder"
mkdir -p "$T/abbad" && cp "$T/ab/timeline.json" "$T/abbad/"
expect2 "folder without its textures" "abbad" --load "$T/abbad"
printf 'u,v\n0.5,0.5\n1.5,0.5\n0.5,0.6\n' >"$T/out01.csv"
expect2 "stroke UVs outside 0..1" "out01.csv" --strokes "$T/out01.csv"
printf 'u,v\n0.001,0.001\n0.003,0.001\n0.001,0.003\n' >"$T/other.csv"
expect2 "strokes for another mesh" "another mesh" --strokes "$T/other.csv"
printf 'move 1 2\nfly 3 4\n' >"$T/bad.txt"
expect2 "bad script line" "bad.txt:2" --script "$T/bad.txt"
expect2 "bad size" "--size" --size 12x-3
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$T/nouv.obj"
expect2 "strokes on a mesh without UVs" "no UVs" --mesh "$T/nouv.obj" --strokes "$T/cross.csv"
# A mesh without UVs still shows (untextured) and says so.
V $G --mesh "$T/nouv.obj" --screenshot "$T/nouv.png" 2>"$T/nouv.err" >/dev/null
check '[ $? -eq 0 ] && grep -q "no texture coordinates" "$T/nouv.err"' "mesh without UVs: $(cat "$T/nouv.err")"
"$CLI" view --help >/dev/null
check '[ $? -eq 0 ]' "view --help"

# The window itself (GTK path only): Escape quits (without it the window
# stays open and timeout ends it with 124); F1 shows the help over the 3D
# view; a mesh without UVs refuses Generate at once, in the window's status
# line. (Where the keyboard focus starts cannot be seen in a shot: Xvfb has
# no window manager, so GTK draws every window unfocused.)
if [ $GTK -eq 1 ]; then
  printf 'key Escape\n' >"$T/esc.txt"
  timeout 300 "$CLI" view --size 480x270 --texture-size 256 --script "$T/esc.txt" --quiet \
    >/dev/null 2>"$T/esc.err"
  check '[ $? -eq 0 ]' "Escape does not close the window ($(cat "$T/esc.err"))"
  printf 'key g\nkey F1\n' >"$T/f1.txt"
  timeout 300 "$CLI" view --size 480x270 --texture-size 256 --mesh "$T/nouv.obj" \
    --script "$T/f1.txt" --window-shot "$T/help.png" >/dev/null 2>"$T/f1.err"
  check '[ $? -eq 0 ] && $CHECK help "$T/help.png"' "F1 help ($(tail -2 "$T/f1.err"))"
  check 'grep -q "Generate: the mesh has no texture coordinates" "$T/f1.err"' \
    "Generate on a mesh without UVs is not refused: $(cat "$T/f1.err")"
fi

# 7. Generate on loaded skin textures: a `skinsim skin` set loaded, then
#    Generate, gives the same frame as `skinsim abrasion --upper` with that
#    skin's colour (not the default skin's).
"$CLI" skin --size 256 --base melanin=0.25 --out "$T/skin" --quiet
"$CLI" abrasion --upper "$T/skin/base_color.png" --size 256 --times 1,20,30 --out "$T/abskin" --quiet
V $G --load "$T/skin" --generate --time 5 --screenshot "$T/genskin5.png" --json --quiet >"$T/genskin.json"
check '[ $? -eq 0 ] && grep -q "on the loaded skin" "$T/genskin.json"' "Generate does not use the loaded skin"
V $G --load "$T/abskin" --time 5 --screenshot "$T/abskin5.png" --quiet
check 'cmp -s "$T/genskin5.png" "$T/abskin5.png"' "Generate on the loaded skin differs from skinsim abrasion --upper"
check '! cmp -s "$T/genskin5.png" "$T/gen5k.png"' "Generate on the loaded skin looks like the default skin"

# 7b. Generate's fast path (shape and skin at once, maturation in its own
#    thread, layers packed only in the changed region) gives the same bytes
#    as the reference path (SKINSIM_VIEW_REFERENCE=1: each step in turn, every
#    layer packed whole): the same layers_hash for the built-in wound and for
#    the painted bands (several islands) on the loaded skin; the two differ.
hash_of() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['layers_hash'])" "$1"; }
for c in ex:"" bands:"--strokes $T/strokes.csv --load $T/skin"; do
  n=${c%%:*}; args=${c#*:}
  for ref in 0 1; do
    SKINSIM_VIEW_REFERENCE=$ref "$CLI" view --egl --size 160x90 --texture-size 512 --generate \
      $args --json --quiet >"$T/hash_${n}_$ref.json" 2>"$T/hash_${n}_$ref.err"
    check '[ $? -eq 0 ]' "Generate $n (reference $ref) failed: $(cat "$T/hash_${n}_$ref.err")"
  done
  check '[ "$(hash_of "$T/hash_${n}_0.json")" = "$(hash_of "$T/hash_${n}_1.json")" ]' \
    "Generate $n: fast path $(hash_of "$T/hash_${n}_0.json") != reference $(hash_of "$T/hash_${n}_1.json")"
done
check '[ "$(hash_of "$T/hash_ex_0.json")" != "$(hash_of "$T/hash_bands_0.json")" ]' \
  "layers_hash does not tell two different wounds apart"

# 8. A heal run folder (`skinsim heal --out`) loads through `skinsim wound
#    --heal`: every snapshot a stop, the same frame as loading the folder
#    `skinsim wound --heal` writes.
"$CLI" heal --grid 20x20x8 --scenario scab --days 4 --adapt-tol 0 --quiet --threads 1 --out "$T/heal"
V $G --load "$T/heal" --time 2 --screenshot "$T/heal2.png" --json --quiet >"$T/heal.json"
check '[ $? -eq 0 ] && python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d[\"layers\"]==5 and d[\"end_day\"]==4 and \"heal run\" in d[\"textures\"]" "$T/heal.json"' "heal run folder: $(head -c 300 "$T/heal.json")"
"$CLI" wound --heal "$T/heal" --days 0,1,2,3,4 --size 256 --no-compare --quiet --out "$T/woundheal"
V $G --load "$T/woundheal" --time 2 --screenshot "$T/woundheal2.png" --quiet
check 'cmp -s "$T/heal2.png" "$T/woundheal2.png"' "a heal run renders unlike skinsim wound --heal of it"
check '$CHECK changed "$T/heal2.png" "$T/day0.png" 240 135 2' "no wound in the middle of the heal run's frame"

# 9. The `skinsim wound` block of that run (1 cm of skin) sits on the mesh
#    at its world size, centred in the start view: it is there, and nothing
#    changes farther than 20 px from the centre (before, the block was
#    stretched over the whole UV layout of the hand).
V $G --load "$T/woundheal" --time 2 --json --quiet --screenshot "$T/blk.png" >"$T/blk.json"
check '[ $? -eq 0 ] && python3 -c "import json,sys; b=json.load(open(sys.argv[1]))[\"block\"]; assert b[\"side_mm\"]==10 and 200<b[\"mm_per_uv\"]<500 and abs(b[\"side_uv\"]*b[\"mm_per_uv\"]-10)<1e-6 and abs(b[\"x\"]-240)<1 and abs(b[\"y\"]-135)<1" "$T/blk.json"' "block placement: $(grep -A8 block "$T/blk.json")"
check '$CHECK confined "$T/woundheal2.png" "$T/day0.png" 240 135 20' "the wound block is not confined to 1 cm around the view's centre"

# 10. Paint tools. The brush ring follows the cursor in paint mode at the
#     brush's size (twice the brush, twice the ring), red for the eraser.
printf 'key p\nmove 250 100\n' >"$T/ring.txt"
V $G --script "$T/ring.txt" --screenshot "$T/ring4.png" --quiet
V $G --script "$T/ring.txt" --brush-mm 8 --screenshot "$T/ring8.png" --quiet
check '$CHECK ring-ratio "$T/ring4.png" "$T/ring8.png" "$T/day0.png" 250 100' "brush ring"
printf 'key p\nkey e\nmove 250 100\n' >"$T/ringe.txt"
V $G --script "$T/ringe.txt" --screenshot "$T/ringe.png" --quiet
check '$CHECK eraser-ring "$T/ringe.png" "$T/day0.png" 250 100' "eraser ring"
# Eraser, undo, redo: paint a band, erase its middle, undo, redo.
printf 'key p\ndrag 220 100 280 100 20\n' >"$T/t1.txt"
{ cat "$T/t1.txt"; printf 'key e\ndrag 240 100 260 100 10\n'; } >"$T/t2.txt"
{ cat "$T/t2.txt"; printf 'key z\n'; } >"$T/t3.txt"
{ cat "$T/t3.txt"; printf 'key y\n'; } >"$T/t4.txt"
{ cat "$T/t4.txt"; printf 'key z\nkey z\nkey y\nkey y\n'; } >"$T/t5.txt"
pts() { V $G --script "$1" --save-strokes "$2" --json --quiet | python3 -c "import json,sys; print(json.load(sys.stdin)['stroke_points'])"; }
n1=$(pts "$T/t1.txt" "$T/t1.csv"); n2=$(pts "$T/t2.txt" "$T/t2.csv"); n3=$(pts "$T/t3.txt" "$T/t3.csv")
n4=$(pts "$T/t4.txt" "$T/t4.csv"); n5=$(pts "$T/t5.txt" "$T/t5.csv")
check '[ "$n1" -gt 50 ] && [ "$n2" -gt 0 ] && [ "$n2" -lt "$n1" ]' "eraser: $n1 points painted, $n2 after erasing"
check 'cmp -s "$T/t1.csv" "$T/t3.csv" && cmp -s "$T/t2.csv" "$T/t4.csv" && cmp -s "$T/t4.csv" "$T/t5.csv"' "undo/redo of an erase: $n1 $n2 $n3 $n4 $n5"
# Mirror symmetry on a flat square (u = x): a stroke painted left of the
# middle is also painted at u -> 1 - u; without --mirror only on one side.
python3 -c '
import sys
n, L = 8, 0.1
with open(sys.argv[1], "w") as f:
    for j in range(n + 1):
        for i in range(n + 1):
            f.write("v %g %g 0\nvt %g %g\n" % (L * i / n - L / 2, L * j / n - L / 2, i / n, j / n))
    f.write("vn 0 0 1\n")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            b, c, d = a + 1, a + n + 2, a + n + 1
            f.write("f %d/%d/1 %d/%d/1 %d/%d/1\nf %d/%d/1 %d/%d/1 %d/%d/1\n" % (a, a, b, b, c, c, a, a, c, c, d, d))
' "$T/plane.obj"
printf 'key p\ndrag 150 100 190 160 20\n' >"$T/mir.txt"
V $G --mesh "$T/plane.obj" --mirror --script "$T/mir.txt" --save-strokes "$T/mir.csv" --save-mask "$T/mask.png" --quiet
check '[ $? -eq 0 ] && $CHECK mirrored "$T/mir.csv"' "mirror symmetry"
V $G --mesh "$T/plane.obj" --script "$T/mir.txt" --save-strokes "$T/nomir.csv" --quiet
check '! $CHECK mirrored "$T/nomir.csv" >/dev/null 2>&1' "strokes mirrored without --mirror"
printf 'key p\nkey m\ndrag 150 100 190 160 20\n' >"$T/mirkey.txt"
V $G --mesh "$T/plane.obj" --script "$T/mirkey.txt" --save-strokes "$T/mirkey.csv" --quiet
check 'cmp -s "$T/mir.csv" "$T/mirkey.csv"' "the M key does not mirror as --mirror does"
# The painted mask: white inside the strokes' hulls, what skinsim abrasion --mask reads.
check '$CHECK mask "$T/mask.png" "$T/mir.csv"' "painted mask"
"$CLI" abrasion --mask "$T/mask.png" --size 64 --times 1 --out "$T/ab_mask" --quiet
check '[ $? -eq 0 ]' "skinsim abrasion cannot read the exported mask"
rm -f "$T/empty_mask.png"
V $G --save-mask "$T/empty_mask.png" --quiet 2>"$T/em.err"
rc=$?
check '[ $rc -eq 2 ] && [ ! -e "$T/empty_mask.png" ] && grep -q "no stroke" "$T/em.err"' "--save-mask with nothing painted: rc $rc, $(cat "$T/em.err")"

# Keep the pictures for a person to look at when asked.
[ -n "${SKINSIM_VIEW_KEEP:-}" ] && cp "$T"/*.png "$SKINSIM_VIEW_KEEP"/
echo "e2e_view: $pass passed, $fail failed (GTK path: $GTK)"
[ $fail -eq 0 ]
