"""Headless test of the skinsim Blender add-on (run by tests/e2e_blender.sh):

    blender -b --factory-startup --python-exit-code 1 --python test_addon.py -- SRC CLI OUT MESH

Registers the add-on, imports the hand mesh, checks that bad input is
refused with skinsim's own message and leaves no material, builds the
material (abrasion timeline, days 0, 3, 20 at one frame per day), checks its
nodes, colour spaces, keyframes and drivers, renders frames 1 (day 0), 4 (day 3)
and 21 (day 20) with Cycles on the CPU, and checks that the later renders
differ from the first where the wound is and nowhere else; then builds the
static skin-texture material, an abrasion over procedural skin, and the
simulated healing (skinsim wound in a 20 mm block) whose frames 1 and 11
differ on the wound and nowhere outside the block. Writes
OUT/frame_NNN.png and OUT/compare.png (the three frames, the difference of
the first and last, the skin material, and day 3 over that skin; below, the
simulated healing at frames 1, 4, 11 and its difference) to look at."""
import math
import os
import time
import sys

import bpy
import numpy as np
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

argv = sys.argv[sys.argv.index("--") + 1:]
SRC, CLI, OUT, MESH = argv[0], argv[1], argv[2], argv[3]
os.makedirs(OUT, exist_ok=True)
os.environ["SKINSIM_CLI"] = CLI


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print("ok:", what)


bpy.ops.wm.read_factory_settings(use_empty=True)
sys.path.insert(0, os.path.join(SRC, "integrations", "blender"))
import skinsim_blender  # noqa: E402

skinsim_blender.register()
check(hasattr(bpy.ops.skinsim, "build_material") and hasattr(bpy.types.Object, "skinsim"),
      "add-on registers its operator and per-object settings")

# Debian 12's Blender 3.4 glTF importer needs SMOOTH shading (DESIGN.md pitfalls)
bpy.ops.import_scene.gltf(filepath=MESH, import_shading="SMOOTH")
obj = next(o for o in bpy.data.objects if o.type == "MESH")
for o in bpy.context.view_layer.objects:
    o.select_set(o == obj)
bpy.context.view_layer.objects.active = obj
scene = bpy.context.scene
st = obj.skinsim
# settings are per object: another object keeps its own
other = bpy.data.objects.new("other_settings", obj.data.copy())
scene.collection.objects.link(other)
other.skinsim.wound_u = 0.75
check(st.wound_u != 0.75 and other.skinsim.wound_u == 0.75, "each object has its own settings")
bpy.data.objects.remove(other)  # not in the renders below
st.size = 256
st.days = "0,3,20"
st.frames_per_day = 1.0
st.start_frame = 1
st.out_dir = os.path.join(OUT, "textures")
mats_before = len(bpy.data.materials)

# ---- bad input: refused with a message, nothing built ----
st.days = "0,abc"
try:
    bpy.ops.skinsim.build_material()
    check(False, "bad day list is refused")
except RuntimeError as e:
    check("abc" in str(e) and "abc" in st.last_error, "bad day list: message names it (%s)" % e)
st.days = "0,3,20"
bad_csv = os.path.join(OUT, "bad_strokes.csv")
with open(bad_csv, "w") as f:
    f.write("u,v\n0.2,0.2\n1.5,0.3\n0.3,0.5\n")
st.stroke_csv = bad_csv
try:
    bpy.ops.skinsim.build_material()
    check(False, "bad stroke file is refused")
except RuntimeError:
    check("bad_strokes.csv:3" in st.last_error and "outside [0,1]" in st.last_error,
          "bad stroke file: skinsim's message names file and line (%s)" % st.last_error)
check(len(bpy.data.materials) == mats_before, "a failed run builds no material")
st.stroke_csv = ""
# an output folder that cannot be made: report(), no traceback, nothing built
st.out_dir = "/proc/skinsim_cannot_be_here"
try:
    bpy.ops.skinsim.build_material()
    check(False, "an output folder that cannot be made is refused")
except RuntimeError as e:
    check("cannot be made" in st.last_error and "Traceback" not in str(e),
          "output folder that cannot be made: reported (%s)" % st.last_error)
check(len(bpy.data.materials) == mats_before, "a refused folder builds no material")
st.out_dir = os.path.join(OUT, "textures")
# the job the modal operator runs: cancel stops the running command and
# leaves the scene and the output as they were
job = skinsim_blender.Job(obj, st, CLI)
job.start()
check(job.proc is not None and job.proc.poll() is None, "a job's command runs as a child process")
job.cancel()
check(job.proc is None and not os.path.exists(job.tmp), "cancel stops it and cleans up")
check(len(bpy.data.materials) == mats_before, "a cancelled job builds no material")
check(not os.path.exists(os.path.join(st.out_dir, "abrasion", "frames")),
      "a cancelled job leaves no frames")

# ---- the material ----
res = bpy.ops.skinsim.build_material()
check(res == {"FINISHED"}, "build_material finished")
mat = obj.active_material
check(mat is not None and mat.name.startswith("skinsim_"), "the mesh wears the skinsim material")
nt = mat.node_tree
bsdf = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
for name in ("Base Color", "Roughness", "Normal"):
    check(bsdf.inputs[name].is_linked, "Principled %s is wired" % name)
spec = bsdf.inputs["Specular"] if "Specular" in bsdf.inputs else bsdf.inputs["Specular IOR Level"]
check(spec.is_linked, "Principled specular is wired")
nmap = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeNormalMap")
check(nmap.space == "TANGENT" and nmap.outputs["Normal"].is_linked, "normal map node, tangent space")
out = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
check(out.inputs["Displacement"].is_linked, "height drives displacement")
imgs = [n.image for n in nt.nodes if n.bl_idname == "ShaderNodeTexImage"]
check(len(imgs) == 12, "4 maps x 3 days of images")
for im in imgs:
    want = "sRGB" if "_color" in im.filepath else "Non-Color"
    check(im.colorspace_settings.name == want, "%s is %s" % (os.path.basename(im.filepath), want))
fcs = [fc for fc in mat.animation_data.action.fcurves if fc.data_path == '["skinsim_day"]']
check(len(fcs) == 1 and len(fcs[0].keyframe_points) == 2, "skinsim_day is keyframed")
check([tuple(k.co) for k in fcs[0].keyframe_points] == [(1.0, 0.0), (21.0, 20.0)],
      "day 0 at frame 1, day 20 at frame 21")
drivers = nt.animation_data.drivers
check(len(drivers) == 8, "two blends per map, each driven by the day")
check(all(d.driver.is_valid and d.driver.is_simple_expression for d in drivers),
      "blend drivers are simple expressions (no Python auto-run needed)")
scene.frame_set(11)  # day 10: between the day-3 and day-20 sets
dg = bpy.context.evaluated_depsgraph_get()
me = mat.evaluated_get(dg)
check(abs(me["skinsim_day"] - 10.0) < 1e-6, "frame 11 is day 10")
facs = sorted(round(n.inputs["Fac"].default_value, 4)
              for n in me.node_tree.nodes if n.bl_idname == "ShaderNodeMixRGB")
check(facs == [0.4118] * 4 + [1.0] * 4, "blend weights at day 10: %s" % facs)

# ---- render frame 1 and frame 21, looking at the wound ----
dg = bpy.context.evaluated_depsgraph_get()
ev = obj.evaluated_get(dg)
mesh = ev.to_mesh()
uvl = mesh.uv_layers.active.data
centre = Vector((st.wound_u, st.wound_v))
wound_pts, best, faces = [], None, []
for p in mesh.polygons:
    c = sum((uvl[i].uv for i in p.loop_indices), Vector((0, 0))) / len(p.loop_indices)
    d = (c - centre).length
    w = obj.matrix_world @ p.center
    faces.append(([tuple(uvl[i].uv) for i in p.loop_indices] + [tuple(c)], w))
    if d < st.wound_radius * 0.9:
        wound_pts.append(w)
    if best is None or d < best[0]:
        best = (d, w, (obj.matrix_world.to_3x3() @ p.normal).normalized())
ev.to_mesh_clear()
check(len(wound_pts) >= 5, "the wound covers %d faces of the hand" % len(wound_pts))
_, pos, normal = best
cam_data = bpy.data.cameras.new("cam")
cam_data.lens = 50
cam_data.clip_start = 0.001  # the hand is 20 cm long; the default 10 cm would cut it
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
cam.location = pos + normal * 0.10
cam.rotation_euler = (pos - cam.location).to_track_quat("-Z", "Y").to_euler()
scene.camera = cam
sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = 3.0
sun = bpy.data.objects.new("sun", sun_data)
sun.rotation_euler = ((cam.location + Vector((0.03, 0.02, 0.05))) - pos).to_track_quat(
    "Z", "Y").to_euler()
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("w")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.3, 0.3, 0.3, 1)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
scene.render.resolution_x = scene.render.resolution_y = 200
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"


def render(frame):
    scene.frame_set(frame)
    path = os.path.join(OUT, "frame_%03d.png" % frame)
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    w, h = img.size
    a = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1, :, :3]  # rows top-down
    return a


a, b, c = render(1), render(4), render(21)  # days 0, 3 (scab), 20 (maturation)
H, W = a.shape[:2]
yy, xx = np.mgrid[0:H, 0:W]


def pixel_distance(points):
    """Per render pixel, the distance (pixels) to the nearest of the world
    points as the camera sees them."""
    dist = np.full((H, W), np.inf)
    for p in points:
        x, y, z = world_to_camera_view(scene, cam, p)
        if z > 0 and -0.2 <= x < 1.2 and -0.2 <= y < 1.2:
            dist = np.minimum(dist, np.hypot(yy - (1 - y) * H, xx - x * W))
    return dist


def texture(day, m):
    im = bpy.data.images.load(os.path.join(st.out_dir, "abrasion", "frames",
                                           "t%g_%s.png" % (day, m)))
    w, h = im.size
    return np.array(im.pixels[:], dtype=np.float32).reshape(h, w, 4)  # row 0 = v 0, as UV


def changed_faces(day):
    """World centres of the faces whose texels change between day 0 and day:
    the wound and whatever of the skin around it the timeline touches."""
    ch = None
    for m in ("color", "normal", "height"):
        t = np.abs(texture(0, m) - texture(day, m))[..., :3].max(axis=2) > 2.0 / 255
        ch = t if ch is None else ch | t
    n = ch.shape[0]
    out = []
    for uvs, w in faces:
        if any(ch[min(int(v * n), n - 1), min(int(u * n), n - 1)] for u, v in uvs):
            out.append(w)
    return out


core = pixel_distance(wound_pts)
check((core <= 3).sum() >= 20, "the wound is in view")
check(np.abs(b - c).mean(axis=2)[core <= 3].mean() > 0.05, "frames 4 and 21 differ on the wound")
for later, frame, day in ((b, 4, 3.0), (c, 21, 20.0)):
    diff = np.abs(a - later).mean(axis=2)
    region = pixel_distance(changed_faces(day))
    away = region > 20  # beyond a face's size from every face whose texels changed
    print("mean |frame %d - frame 1|: on the wound %.4f, away from it %.5f (max %.5f, %d%% of "
          "the picture)" % (frame, diff[core <= 3].mean(), diff[away].mean(), diff[away].max(),
                            100 * away.mean()))
    # day 20 is pink new epithelium, day 0 a pale speckled scrape: close in
    # mean colour (0.03), so the day-20 frame must also differ from day 3's crust
    check(diff[core <= 3].mean() > (0.05 if day < 10 else 0.02),
          "frames 1 and %d differ on the wound" % frame)
    check(away.mean() > 0.15 and diff[away].max() < 0.01,
          "frames 1 and %d agree away from the wound" % frame)

# ---- skin textures (static material) and skin under the abrasion ----
st.source = "SKIN"
check(bpy.ops.skinsim.build_material() == {"FINISHED"}, "skin source: build_material finished")
skin_mat = obj.active_material
snt = skin_mat.node_tree
sbsdf = next(n for n in snt.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
spec = sbsdf.inputs["Specular"] if "Specular" in sbsdf.inputs else sbsdf.inputs["Specular IOR Level"]
linked = {l.to_socket.name: os.path.basename(l.from_node.image.filepath)
          for l in snt.links if l.from_node.bl_idname == "ShaderNodeTexImage"
          and l.to_node == sbsdf}
check(linked.get("Base Color") == "base_color.png" and linked.get("Roughness") == "roughness.png"
      and spec.is_linked, "skin maps wired: %s" % linked)
check(skin_mat.animation_data is None, "skin textures are static")
d = render(1)
skin_render = d
check(np.abs(d - a).mean() > 0.005, "the skin material looks different from the abrasion's")
st.source = "ABRASION"
st.skin_under_abrasion = True
plain = texture(0, "color")
st.out_dir = os.path.join(OUT, "textures_on_skin")
check(bpy.ops.skinsim.build_material() == {"FINISHED"}, "abrasion over procedural skin")
im = bpy.data.images.load(os.path.join(st.out_dir, "abrasion", "frames", "t0_color.png"))
on_skin = np.array(im.pixels[:], dtype=np.float32).reshape(im.size[1], im.size[0], 4)
check(np.abs(on_skin - plain)[..., :3].mean() > 0.01, "the abrasion's healthy skin is skinsim skin's")
scab_on_skin = render(4)

# ---- the simulated healing (skinsim wound) in a block around the wound ----
st.skin_under_abrasion = False
st.source = "HEAL"
st.heal_days = "0,3,10"
st.block_mm = 20.0
st.wound_radius = 0.03
st.out_dir = os.path.join(OUT, "textures_heal")
# run as the modal operator runs it (poll() on a timer), recording the
# progress it would show: it moves within the healing simulation's step
# (the command's own progress lines), never backwards, and ends at 1
hjob = skinsim_blender.Job(obj, st, CLI)
seen = []
while not hjob.poll():
    seen.append(hjob.fraction())
    time.sleep(0.05)
seen.append(hjob.fraction())
nsteps = len(hjob.steps)
inside = [f for f in seen if abs(f * nsteps - round(f * nsteps)) > 1e-3]
print("healing job: %d polls, %d with a fraction inside a step, e.g. %s"
      % (len(seen), len(inside), ["%.3f" % f for f in inside[:5]]))
check(len(inside) >= 2 and seen == sorted(seen) and seen[-1] == 1.0,
      "the healing job reports progress within its command (%d of %d polls)"
      % (len(inside), len(seen)))
check(hjob.finish() is obj.active_material, "healing source: the job builds the material")
hmat = obj.active_material
check(hmat.name.startswith("skinsim_heal_"), "the mesh wears the healing material")
himgs = [n.image for n in hmat.node_tree.nodes if n.bl_idname == "ShaderNodeTexImage"]
check(sum("wound" in im.filepath for im in himgs) == 12, "4 wound maps x 3 days")
check(len(hmat.node_tree.animation_data.drivers) == 8, "wound blends driven by the day")
side = st.block_mm / (10 * st.world_size_cm)
block_pts = [w for uvs, w in faces
             if all(abs(u - st.wound_u) < side / 2 + 0.01 and abs(v - st.wound_v) < side / 2 + 0.01
                    for u, v in uvs[-1:])]
heal_core = [w for uvs, w in faces
             if math.hypot(uvs[-1][0] - st.wound_u, uvs[-1][1] - st.wound_v) < 0.02]
h1, h4, h11 = render(1), render(4), render(11)
hcore = pixel_distance(heal_core)
haway = pixel_distance(block_pts) > 20
hdiff = np.abs(h1 - h11).mean(axis=2)
print("healing: |frame 11 - frame 1| on the wound %.4f, away from the block max %.5f (%d%%)"
      % (hdiff[hcore <= 3].mean(), hdiff[haway].max(), 100 * haway.mean()))
check(hdiff[hcore <= 3].mean() > 0.03, "the simulated wound heals between frames 1 and 11")
check(haway.mean() > 0.15 and hdiff[haway].max() < 0.01,
      "the healing changes nothing outside its block")

# a picture to look at: frames 1 | 4 | 21 | difference 1-21 (x4) | skin textures | day 3 on
# them; below, the simulated healing: frames 1 | 4 | 11 | difference 1-11 (x4)
diff = np.abs(a - c).mean(axis=2)
grey = lambda d: np.repeat(np.clip(d * 4, 0, 1)[..., None], 3, axis=2)  # noqa: E731
blank = np.zeros_like(a)
sheet = np.concatenate([
    np.concatenate([a, b, c, grey(diff), skin_render, scab_on_skin], axis=1),
    np.concatenate([h1, h4, h11, grey(hdiff), blank, blank], axis=1)], axis=0)
img = bpy.data.images.new("compare", sheet.shape[1], sheet.shape[0])
rgba = np.concatenate([sheet, np.ones(sheet.shape[:2] + (1,), np.float32)], axis=2)[::-1]
img.pixels[:] = rgba.ravel()
img.filepath_raw = os.path.join(OUT, "compare.png")
img.file_format = "PNG"
img.save()
print("PASS: renders in", OUT)
