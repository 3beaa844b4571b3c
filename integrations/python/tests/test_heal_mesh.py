"""skinsim.heal on real geometry from Python: a wound painted as UV strokes on
the shipped hand (data/meshes), healed with the mechanics on a coarse patch
through the library's run object, gives the numbers and files `skinsim heal
--mesh` gives (the summary's skin_mesh block, the .vtu and .glb of the skin
surface); bad strokes raise InputError naming the file."""
import json
import math
import os
import struct
import tempfile
import unittest

import numpy as np

import skinsim
from skinsim import heal

HERE = os.path.dirname(os.path.abspath(__file__))
HAND = os.path.join(HERE, "..", "..", "..", "data", "meshes", "generic-hand-left.glb")
DAYS = 0.1  # about 1 s with the mechanics


def strokes(path, u=0.2, v=0.62, ru=0.02, rv=0.014):
    """An ellipse of stroke points on the back of the hand (UV island lower left)."""
    with open(path, "w") as f:
        f.write("u,v,stroke\n")
        for k in range(12):
            a = 2 * math.pi * k / 12
            f.write("%.4f,%.4f,0\n" % (u + ru * math.cos(a), v + rv * math.sin(a)))


def glb_json(path):
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert magic == 0x46546C67 and version == 2 and length == len(data) and jtype == 0x4E4F534A
    return json.loads(data[20:20 + jlen])


@unittest.skipUnless(os.path.exists(HAND), "no hand mesh in data/meshes")
class HandMesh(unittest.TestCase):
    def test_wound_on_the_hand_heals_and_maps_back(self):
        with tempfile.TemporaryDirectory() as d:
            cut = os.path.join(d, "cut.csv")
            strokes(cut)
            # the myofibroblast kinetics make day 0.1 nearly still: pull at once,
            # so the mechanics visibly acts within this short run
            pull = os.path.join(d, "pull.json")
            with open(pull, "w") as f:
                json.dump({"mechanics": {k: {"value": 0, "unit": "day", "source": "test"}
                                         for k in ("tau_myo", "tau_remodel")}}, f)
            out = os.path.join(d, "run")
            r = heal.Run(skin_mesh=HAND, wound_uv=cut, voxel_mm=1, mechanics=True, days=DAYS,
                         snapshot_every=0, params_path=pull, out_dir=out)
            nz, ny, nx = r.shape
            self.assertAlmostEqual(r.dx_mm, 1.0)
            cells = r.cells
            self.assertEqual(cells.shape, (nz, ny, nx))
            nwound = int((cells == heal.CELL_STATES["wound"]).sum())
            self.assertGreater(nwound, 0)
            self.assertGreater(int((cells == heal.CELL_STATES["air"]).sum()), 0)
            e0 = r.field("epithelium", copy=True)
            r.advance_to(DAYS)
            self.assertTrue(r.done)
            self.assertGreater(float(r.field("epithelium").sum()), float(e0.sum()))
            s = r.finish()
            k = s["skin_mesh"]
            self.assertEqual((k["vertices"], k["triangles"]), (1360, 2314))
            self.assertEqual(k["units_mm"], 1000)
            self.assertEqual(s["wound"]["voxels"], nwound)
            self.assertGreater(s["mechanics"]["tets"], 100)
            self.assertGreater(s["mechanics"]["contraction_percent"], 1)
            # the skin surface of the last snapshot, as .vtu and as .glb
            surf = os.path.join(out, "surface")
            self.assertTrue(os.path.exists(os.path.join(surf, "skin.pvd")))
            doc = glb_json(os.path.join(surf, "skin_0001.glb"))
            attrs = doc["meshes"][0]["primitives"][0]["attributes"]
            for a in ("POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0", "_EPITHELIUM", "_SCAR",
                      "_ESCHAR", "_OPEN_WOUND"):
                self.assertIn(a, attrs)
            # the skin refined around the wound (surface_vertices > the mesh's 1360)
            self.assertGreater(k["surface_vertices"], 1360)
            self.assertEqual(doc["accessors"][attrs["_EPITHELIUM"]]["count"], k["surface_vertices"])
            self.assertAlmostEqual(doc["nodes"][0]["extras"]["t_days"], DAYS, places=9)

    def test_strokes_off_the_mesh_raise_input_error(self):
        with tempfile.TemporaryDirectory() as d:
            off = os.path.join(d, "off.csv")
            strokes(off, u=0.92, v=0.92, ru=0.02, rv=0.02)
            out = os.path.join(d, "run")
            with self.assertRaises(skinsim.InputError) as cm:
                heal.Run(skin_mesh=HAND, wound_uv=off, voxel_mm=1, days=0.1, out_dir=out)
            self.assertIn("off.csv", str(cm.exception))
            self.assertFalse(os.path.exists(out))


if __name__ == "__main__":
    unittest.main()
