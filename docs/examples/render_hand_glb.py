"""Renders the skin-surface snapshots of a `skinsim heal --mesh` run the way
docs/images/mech_hand_glb.png shows them: each surface/skin_NNNN.glb imported
with Blender's own glTF importer (the displacement shape key at its weight,
1), drawn by the Workbench engine in the file's vertex colours (COLOR_0, the
wound state), seen down the patch normal from DIST_CM centimetres with the
patch's x axis to the right (both from the run's summary.json).

usage: blender -b --python docs/examples/render_hand_glb.py -- RUN_DIR OUT_PREFIX [DIST_CM [PX]]
writes OUT_PREFIX_NNNN.png (PX x PX, default 300) per snapshot; put them side
by side with labels, for instance with ImageMagick:
  montage -label 'day 0' OUT_0000.png -label 'day 5' OUT_0001.png ... \
      -tile 4x1 -geometry +2+2 -pointsize 18 docs/images/mech_hand_glb.png
"""
import glob
import json
import os
import sys

import bpy
from mathutils import Matrix, Vector

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if len(argv) < 2:
    sys.exit(__doc__)
run, prefix = argv[0], argv[1]
dist = float(argv[2]) / 100 if len(argv) > 2 else 0.07
px = int(argv[3]) if len(argv) > 3 else 300

with open(os.path.join(run, "summary.json")) as f:
    sm = json.load(f)["skin_mesh"]
to_m = 1e-3  # summary.json is in mm; glTF (and Blender after import) in metres


def gl2bl(v):
    """glTF is y-up, Blender z-up: the importer maps (x, y, z) to (x, -z, y)."""
    return Vector((v[0], -v[2], v[1]))


centre = gl2bl([c * to_m for c in sm["wound_centre_mm"]])
normal = gl2bl(sm["patch_normal"]).normalized()
xaxis = gl2bl(sm["patch_x_axis"]).normalized()
yaxis = normal.cross(xaxis).normalized()

scene = bpy.context.scene
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob, do_unlink=True)


def set_up_render():
    """Workbench in vertex colours (set after each import: the glTF importer
    switches the scene to Eevee)."""
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.color_type = "VERTEX"
    scene.display.shading.show_specular_highlight = True
    scene.render.resolution_x = scene.render.resolution_y = px
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"  # the vertex colours as they are
    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    scene.world.color = (0, 0, 0)


cam_data = bpy.data.cameras.new("cam")
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
scene.camera = cam
# the camera looks down its -z with +x to the right and +y up
rot = Matrix((xaxis, yaxis, normal)).transposed()
cam.matrix_world = Matrix.Translation(centre + dist * normal) @ rot.to_4x4()
cam_data.clip_start = 0.001

for path in sorted(glob.glob(os.path.join(run, "surface", "skin_*.glb"))):
    before = set(bpy.data.objects)
    # Debian 12's Blender 3.4 needs SMOOTH shading to import at all (DESIGN.md)
    bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
    new = [o for o in bpy.data.objects if o not in before]
    n = os.path.splitext(os.path.basename(path))[0].split("_")[-1]
    scene.render.filepath = "%s_%s.png" % (prefix, n)
    set_up_render()
    bpy.ops.render.render(write_still=True)
    print("rendered", path, "->", scene.render.filepath)
    for o in new:
        bpy.data.objects.remove(o, do_unlink=True)
