"""skinsim.heal from Python: the library's run object (the one `skinsim
heal` runs), fields as numpy views, the area curve, errors as exceptions."""
import csv
import json
import os
import subprocess
import tempfile
import unittest

import numpy as np

import skinsim
from skinsim import heal

SMALL = dict(grid=(24, 24, 8), size_mm=(12, 12, 4), area_every=0.5)


class Run(unittest.TestCase):
    def test_in_memory_run_closes_the_wound(self):
        r = heal.Run(days=4, **SMALL)
        self.assertEqual(r.shape, (8, 24, 24))
        self.assertEqual(r.scenario, "clean")
        self.assertAlmostEqual(r.dx_mm, 0.5)
        e0 = r.field("epithelium", copy=True)
        r.advance_to(4.0)
        self.assertTrue(r.done)
        self.assertAlmostEqual(r.day, 4.0, places=9)
        e = r.field("epithelium")
        self.assertEqual(e.dtype, np.float32)
        self.assertFalse(e.flags.owndata)  # a view of the grid
        # the epithelium grows in from the wound edge
        self.assertGreater(float(e.sum()), float(e0.sum()))
        a = r.area()
        self.assertEqual(a["t_days"][0], 0.0)
        self.assertAlmostEqual(a["normalised_area"][0], 1.0)
        self.assertLess(a["normalised_area"][-1], a["normalised_area"][0])
        self.assertTrue(np.all(np.diff(a["normalised_area"]) <= 1e-12))
        top = r.surface("epithelium")
        self.assertEqual(top.shape, (24, 24))
        self.assertTrue(np.all((top >= 0) & (top <= 1.0001)))
        cells = r.cells
        self.assertIn(heal.CELL_STATES["wound"], np.unique(cells))
        self.assertFalse(cells.flags.writeable)
        s = r.finish()
        self.assertIsInstance(s, dict)
        self.assertTrue(s)

    def test_views_outlive_the_run_object(self):
        r = heal.Run(days=0.5, **SMALL)
        v = r.field("oxygen")
        r.close()
        del r
        self.assertTrue(np.isfinite(v).all())  # the view keeps the memory
        x = heal.Run(days=0.5, **SMALL)
        x.close()
        with self.assertRaises(skinsim.SkinsimError):
            x.step()

    def test_same_curve_as_the_command_line(self):
        cli = os.environ.get("SKINSIM_CLI")
        if not cli:
            self.skipTest("SKINSIM_CLI not set")
        with tempfile.TemporaryDirectory() as d:
            subprocess.run([cli, "heal", "--grid", "24x24x8", "--size-mm", "12,12,4", "--days",
                            "3", "--area-every", "0.5", "--snapshot-every", "0", "--quiet",
                            "--out", os.path.join(d, "h")], check=True)
            with open(os.path.join(d, "h", "area.csv")) as f:
                rows = list(csv.DictReader(f))
        r = heal.Run(days=3, **SMALL)
        r.advance_to(3)
        a = r.area()
        self.assertEqual(len(rows), len(a["t_days"]))
        for k in ("t_days", "open_area_mm2", "normalised_area"):
            np.testing.assert_allclose([float(x[k]) for x in rows], a[k], rtol=1e-5, atol=1e-9)

    def test_footprint_array_and_outputs(self):
        mask = np.zeros((24, 24), np.float32)
        mask[8:16, 6:18] = 1  # 8 x 12 voxels of 0.5 mm
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "run")
            r = heal.Run(days=1, wound_mask=mask, out_dir=out, snapshot_every=0, **SMALL)
            a = r.area()
            self.assertAlmostEqual(a["open_area_mm2"][0], 8 * 12 * 0.25)
            r.step(r.steps_total)
            summary = r.finish()
            for f in ("area.csv", "area.png", "summary.json"):
                self.assertTrue(os.path.isfile(os.path.join(out, f)), f)
            with open(os.path.join(out, "summary.json")) as f:
                self.assertEqual(json.load(f), summary)

    def test_bad_input_raises_the_library_message(self):
        with self.assertRaises(skinsim.InputError) as cm:
            heal.Run(scenario="bogus")
        self.assertIn("clean", str(cm.exception))
        with self.assertRaises(skinsim.InputError) as cm:
            heal.Run(grid=(-4, 10, 8))
        self.assertIn("grid", str(cm.exception))
        with self.assertRaises(skinsim.InputError) as cm:
            heal.Run(wound_mask="/nonexistent/mask.png", **SMALL)
        self.assertIn("/nonexistent/mask.png", str(cm.exception))
        with self.assertRaises(skinsim.InputError):
            heal.Run(wound_mask=np.zeros((10, 10)), **SMALL)
        r = heal.Run(days=0.5, **SMALL)
        with self.assertRaises(skinsim.InputError):
            r.advance_to(5)
        with self.assertRaises(skinsim.InputError):
            r.field("collagen")
        with self.assertRaises(skinsim.InputError):
            heal.Run(scheme="implicit")


if __name__ == "__main__":
    unittest.main()
