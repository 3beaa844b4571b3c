"""skinsim.skin from Python: procedural skin textures as numpy arrays, equal
to `skinsim skin`'s maps, deterministic, with the library's messages for bad
settings."""
import os
import subprocess
import tempfile
import unittest

import numpy as np

import skinsim

from skinsim import _lib

# a library with the module must give a working Python module: only a
# library built without it skips these tests
if hasattr(_lib.lib, "ss_skin_generate"):
    from skinsim import skin
else:
    skin = None

N = 64 if os.environ.get("SKINSIM_TEST_QUICK") else 128


@unittest.skipIf(skin is None, "library without the skin module")
class Textures(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.t = skin.textures(size=N, seed=3)

    def test_maps(self):
        t = self.t
        self.assertEqual(t["base_color"].shape, (N, N, 3))
        self.assertEqual(t["bio"].shape, (N, N, len(skin.BIO_CHANNELS)))
        self.assertEqual(t["roughness"].shape, (N, N))
        self.assertFalse(t["base_color"].flags.owndata)  # a view of the library's image
        for m in ("base_color", "roughness", "specular", "normal"):
            self.assertTrue(np.all((t[m] >= 0) & (t[m] <= 1)), m)
        self.assertAlmostEqual(float(t["height_mm"].min()), t["height_min_mm"], places=5)
        # skin: red above blue; melanin in its biological range
        self.assertGreater(t["base_color"][..., 0].mean(), t["base_color"][..., 2].mean())
        mel = t["bio"][..., skin.BIO_CHANNELS.index("melanin")]
        self.assertTrue(0 < mel.mean() < 0.5)
        self.assertGreater(len(t["features"]["x"]), 0)

    def test_deterministic_and_seeded(self):
        again = skin.textures(size=N, seed=3)
        np.testing.assert_array_equal(again["bio"], self.t["bio"])
        other = skin.textures(size=N, seed=4)
        self.assertFalse(np.array_equal(other["bio"], self.t["bio"]))

    def test_counts_and_fields(self):
        t = skin.textures(size=N, counts={"moles": 7, "cysts": 0, "freckles": 0,
                                          "wrinkles": 0, "follicles": 0})
        types = list(t["features"]["type"])
        self.assertEqual(types.count("moles"), 7)
        self.assertEqual(len(types), 7)
        # moles only where the field allows: the left half
        field = np.zeros((32, 32), np.float32)
        field[:, :16] = 1
        t = skin.textures(size=N, counts={"moles": 20, "cysts": 0, "freckles": 0,
                                          "wrinkles": 0, "follicles": 0}, fields={"moles": field})
        self.assertTrue(np.all(t["features"]["x"] <= 0.5 + 1e-9))

    def test_equal_to_the_command_line(self):
        cli = os.environ.get("SKINSIM_CLI")
        if not cli:
            self.skipTest("SKINSIM_CLI not set")
        with tempfile.TemporaryDirectory() as d:
            subprocess.run([cli, "skin", "--size", str(N), "--seed", "3", "--quiet", "--out",
                            os.path.join(d, "s")], check=True)
            png = skinsim.read_image(os.path.join(d, "s", "base_color.png"), srgb=False)
            rough = skinsim.read_image(os.path.join(d, "s", "roughness.png"), srgb=False)
        ours = skinsim.optics.srgb_encode(self.t["base_color"])
        self.assertLessEqual(np.abs(png - ours).max(), 1.0 / 255 + 1e-6)
        self.assertLessEqual(np.abs(rough - self.t["roughness"]).max(), 1.0 / 255 + 1e-6)

    def test_bad_settings_raise_the_library_message(self):
        with self.assertRaises(skinsim.InputError) as cm:
            skin.textures(size=N, preset="elbow")
        self.assertIn("elbow", str(cm.exception))
        with self.assertRaises(skinsim.InputError) as cm:
            skin.textures(size=N, params={"moles.nonsense": 1})
        self.assertIn("moles.nonsense", str(cm.exception))
        with self.assertRaises(skinsim.InputError):
            skin.textures(size=N, counts={"tattoos": 3})
        with self.assertRaises(skinsim.InputError):
            skin.textures(size=N, fields={"moles": np.zeros((8, 8, 3))})
        with self.assertRaises(skinsim.InputError):
            skin.textures(size=-1)


if __name__ == "__main__":
    unittest.main()
