# Renders a `skinsim wound --mesh` day's glTF as docs/images/wound_hand.png (docs/wound.md):
# Cycles on the CPU, 48 samples, no denoiser (Debian's Blender 3.4 has none), a sun and a
# grey world, the camera 14 cm along the skin's normal at the wound (the UV centroid of
# stroke 0 of the strokes file, found on the mesh's triangles). Usage:
#   blender -b -P docs/images/render_wound_hand.py -- DAY.gltf STROKES.csv OUT.png SIZE
import bpy, sys, csv, mathutils
argv = sys.argv[sys.argv.index("--") + 1:]
gltf, strokes, out, size = argv[0], argv[1], argv[2], int(argv[3])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=gltf, import_shading="SMOOTH")  # Blender 3.4 + numpy: np.bool
obj = [o for o in bpy.context.scene.objects if o.type == "MESH"][0]
us, vs = [], []
with open(strokes) as f:
    for row in csv.DictReader(f):
        if int(row.get("stroke", 0)) == 0:
            us.append(float(row["u"])); vs.append(float(row["v"]))
tu, tv = sum(us) / len(us), 1.0 - sum(vs) / len(vs)  # glTF v down -> Blender v up
me = obj.data
me.calc_loop_triangles()
uv = me.uv_layers.active.data
hit = None
for tri in me.loop_triangles:
    a, b, c = (uv[l].uv for l in tri.loops)
    d = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)
    if abs(d) < 1e-14: continue
    w1 = ((tu - a.x) * (c.y - a.y) - (c.x - a.x) * (tv - a.y)) / d
    w2 = ((b.x - a.x) * (tv - a.y) - (tu - a.x) * (b.y - a.y)) / d
    w0 = 1 - w1 - w2
    if min(w0, w1, w2) >= -1e-6:
        hit = (tri, (w0, w1, w2)); break
if hit is None: raise SystemExit("stroke centroid is on no triangle")
tri, w = hit
M = obj.matrix_world
p = sum((M @ me.vertices[v].co * wi for v, wi in zip(tri.vertices, w)), mathutils.Vector())
n = (M.to_3x3() @ tri.normal).normalized()
cam_data = bpy.data.cameras.new("cam")
cam = bpy.data.objects.new("cam", cam_data)
bpy.context.scene.collection.objects.link(cam)
cam.location = p + 0.14 * n
cam.rotation_euler = (p - cam.location).to_track_quat("-Z", "Y").to_euler()
cam_data.clip_start = 0.001
bpy.context.scene.camera = cam
sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = 3.0
sun = bpy.data.objects.new("sun", sun_data)
bpy.context.scene.collection.objects.link(sun)
sun.rotation_euler = (n + mathutils.Vector((0.3, 0.2, 0.0))).to_track_quat("Z", "Y").to_euler()
world = bpy.data.worlds.new("grey")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (0.3, 0.3, 0.3, 1)
bpy.context.scene.world = world
sc = bpy.context.scene
sc.render.engine = "CYCLES"
sc.cycles.samples = 48
sc.cycles.use_denoising = False
sc.cycles.device = "CPU"
sc.render.threads_mode = "FIXED"
sc.render.threads = 2
sc.render.resolution_x = sc.render.resolution_y = size
sc.render.resolution_percentage = 100
sc.render.filepath = out
sc.render.image_settings.file_format = "PNG"
bpy.ops.render.render(write_still=True)
