"""Run by tests/e2e_blender_glb.sh inside Blender (blender -b --python ...
-- FILE.glb DAY): imports a heal run's skin-surface .glb with Blender's own
glTF importer and checks what a Blender user sees: the mesh, the wound-state
vertex colours (red on the open wound), the morph target as the shape key
"displacement" (non-zero after day 0), the node's extras (t_days) as a custom
property and, on Blender 3.5 and later (glTF-Blender-IO pull request 1781),
the _ field attributes. Exits 1 on a failed check."""
import sys

import bpy
import numpy as np

path, day = sys.argv[sys.argv.index("--") + 1], float(sys.argv[sys.argv.index("--") + 2])
bpy.ops.wm.read_factory_settings(use_empty=True)
# Debian 12's Blender 3.4 needs SMOOTH shading to import at all (np.bool, see DESIGN.md)
bpy.ops.import_scene.gltf(filepath=path, import_shading="SMOOTH")
objs = [o for o in bpy.data.objects if o.type == "MESH"]
assert len(objs) == 1, objs
obj, me = objs[0], objs[0].data
print("blender %s: %d vertices, attributes %s" % (bpy.app.version_string, len(me.vertices),
                                                  sorted(a.name for a in me.attributes)))
assert len(me.vertices) > 100
assert abs(obj.get("t_days", -1) - day) < 1e-6, obj.get("t_days")
cols = me.color_attributes
assert len(cols) >= 1, "no vertex colours"
c = np.array([tuple(d.color)[:3] for d in cols[0].data])
skin = np.all(np.abs(c - [0.70, 0.42, 0.32]) < 0.01, axis=1)
red = (c[:, 0] > 0.3) & (c[:, 1] < 0.1)
assert skin.mean() > 0.9, "most of the hand is not skin-coloured"
if day == 0:
    assert red.any(), "no open-wound (red) vertex colour"
keys = me.shape_keys.key_blocks if me.shape_keys else {}
assert "displacement" in keys, "no shape key 'displacement'"
kb = keys["displacement"]
d = np.array([tuple(kb.data[i].co) for i in range(len(me.vertices))]) - \
    np.array([tuple(v.co) for v in me.vertices])
print("shape key displacement: max %.3g m, value %g" % (np.abs(d).max(), kb.value))
assert (np.abs(d).max() > 1e-6) == (day > 0), "shape key displacement"
if bpy.app.version >= (3, 5, 0):
    names = [a.name.upper().lstrip("_") for a in me.attributes]
    for f in ("EPITHELIUM", "SCAR", "ESCHAR", "OPEN_WOUND"):
        assert f in names, "attribute _%s not imported" % f
else:
    print("Blender %s drops glTF _ attributes (imported from 3.5 on)" % bpy.app.version_string)
print("blender_glb_check: OK")
