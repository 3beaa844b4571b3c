"""skinsim.abrasion from Python: frames rendered straight into numpy arrays,
equal to the command line's output, and the library's errors for bad
wounds."""
import os
import subprocess
import tempfile
import unittest

import numpy as np

import skinsim
from skinsim import abrasion, optics

# the sanitizer suite sets SKINSIM_TEST_QUICK: smaller textures, same checks
N = 64 if os.environ.get("SKINSIM_TEST_QUICK") else 128


class Frames(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.ab = abrasion.Abrasion(size=N)

    def test_maps_shapes_and_ranges(self):
        f = self.ab.frame(3.0)
        self.assertEqual(f["color"].shape, (N, N, 3))
        self.assertEqual(f["normal"].shape, (N, N, 3))
        self.assertEqual(f["height"].shape, (N, N))
        self.assertEqual(f["reflection"].dtype, np.float32)
        for m in f.values():
            self.assertTrue(np.all((m >= 0) & (m <= 1)))
        self.assertEqual(self.ab.nwounds, 1)
        inside = self.ab.mask > 0.5
        self.assertGreater(inside.sum(), 100)
        # the fresh wound is darker than the skin around it
        self.assertLess(f["color"][inside].mean(), 0.7 * f["color"][~inside].mean())

    def test_frames_render_into_given_arrays(self):
        out = self.ab.new_frame(maps=("color",))
        buf = out["color"]
        r = self.ab.frame(1.0, out=out)
        self.assertIs(r["color"], buf)
        np.testing.assert_array_equal(buf, self.ab.frame(1.0)["color"])

    def test_time_changes_only_around_the_wound(self):
        a = self.ab.frame(0.0)["color"]
        b = self.ab.frame(20.0)["color"]
        diff = np.abs(a - b).max(axis=2)
        inside = self.ab.mask > 0.5
        self.assertGreater(diff[inside].mean(), 0.05)
        # far from the wound (beyond the widest gradient), nothing changes
        ys, xs = np.nonzero(inside)
        far = np.ones_like(inside)
        pad = N * 20 // 128
        far[max(ys.min() - pad, 0):ys.max() + pad, max(xs.min() - pad, 0):xs.max() + pad] = False
        self.assertLess(diff[far].max(), 1e-6)

    def test_key_positions_are_views(self):
        k = self.ab.key("scab")
        self.assertEqual(k["color"].shape, (N, N, 3))
        self.assertFalse(k["color"].flags.writeable)
        keys, end = self.ab.timeline
        self.assertEqual(keys[0][0], "vasoconstriction")
        self.assertGreater(end, keys[-1][1])
        with self.assertRaises(skinsim.InputError):
            self.ab.key("bruise")

    def test_equal_to_the_command_line(self):
        cli = os.environ.get("SKINSIM_CLI")
        if not cli:
            self.skipTest("SKINSIM_CLI not set")
        with tempfile.TemporaryDirectory() as d:
            subprocess.run([cli, "abrasion", "--size", str(N), "--times", "3", "--out",
                            os.path.join(d, "o"), "--quiet"], check=True)
            png = skinsim.read_image(os.path.join(d, "o", "frames", "t3_color.png"), srgb=False)
        ours = optics.srgb_encode(self.ab.frame(3.0)["color"])
        self.assertEqual(png.shape, ours.shape)
        self.assertLessEqual(np.abs(png - ours).max(), 1.0 / 255 + 1e-6)

    def test_strokes_and_mask_inputs(self):
        t = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        pts = np.stack([0.3 + 0.1 * np.cos(t), 0.6 + 0.08 * np.sin(t)], axis=1)
        two = np.concatenate([np.c_[pts, np.zeros(16)], np.c_[pts + [0.35, -0.3], np.ones(16)]])
        with abrasion.Abrasion(size=96, strokes=two) as ab:
            self.assertEqual(ab.nwounds, 2)
            m = ab.mask
        mask = np.zeros((64, 64), np.float32)
        mask[20:40, 10:30] = 1
        with abrasion.Abrasion(size=64, mask=mask) as ab:
            self.assertEqual(ab.nwounds, 1)
            np.testing.assert_array_equal(ab.mask > 0.5, mask > 0.5)
        self.assertEqual(m.shape, (96, 96))

    def test_bad_wounds_raise_the_library_message(self):
        with self.assertRaises(skinsim.InputError) as cm:
            abrasion.Abrasion(size=64, strokes=[[0.1, 0.1], [0.2, 0.2], [0.3, 0.3]])
        self.assertIn("strokes", str(cm.exception))
        with self.assertRaises(skinsim.InputError) as cm:
            abrasion.Abrasion(size=64, strokes=[[0.1, 0.1], [1.5, 0.2], [0.3, 0.5]])
        self.assertIn("strokes", str(cm.exception))
        with self.assertRaises(skinsim.InputError):
            abrasion.Abrasion(size=64, mask=np.zeros((8, 8)))
        with self.assertRaises(skinsim.InputError):
            abrasion.Abrasion(size=-5)
        with self.assertRaises(skinsim.InputError) as cm:
            abrasion.Abrasion(size=64, stroke_csv="/nonexistent/strokes.csv")
        self.assertIn("/nonexistent/strokes.csv", str(cm.exception))
        with self.assertRaises(skinsim.InputError):
            abrasion.Abrasion(size=64, timeline=[("scab", 2), ("blister", 3)])
        with self.assertRaises(skinsim.InputError):
            self.ab.frame(float("nan"))


if __name__ == "__main__":
    unittest.main()
