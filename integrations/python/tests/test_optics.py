"""skinsim.optics from Python: spectra, colour, BRDF, fit, ModelMatch; the
library's physics and its error messages come through unchanged."""
import os
import tempfile
import unittest

import numpy as np

import skinsim
from skinsim import optics


class Spectrum(unittest.TestCase):
    def test_reflectance_is_physical_and_melanin_darkens_blue(self):
        light = optics.spectrum(melanin=0.02, photons=3000, wl_step_nm=40)
        dark = optics.spectrum(melanin=0.3, photons=3000, wl_step_nm=40)
        self.assertEqual(list(light.wavelength_nm), list(range(380, 781, 40)))
        self.assertTrue(np.all((light.reflectance > 0) & (light.reflectance < 1)))
        self.assertTrue(np.all(light.std_error > 0))
        blue = light.wavelength_nm.tolist().index(460)
        self.assertLess(dark.reflectance[blue], 0.6 * light.reflectance[blue])
        # skin is redder than it is blue
        self.assertGreater(light.reflectance[-1], light.reflectance[blue])
        self.assertGreater(light.specular, 0.01)

    def test_same_seed_same_numbers_any_thread_count(self):
        skinsim.set_threads(1)
        a = optics.spectrum(photons=2000, wl_step_nm=100, seed=5).reflectance.copy()
        skinsim.set_threads(2)
        b = optics.spectrum(photons=2000, wl_step_nm=100, seed=5).reflectance
        c = optics.spectrum(photons=2000, wl_step_nm=100, seed=6).reflectance
        skinsim.set_threads(0)
        self.assertTrue(np.array_equal(a, b))
        self.assertFalse(np.array_equal(a, c))

    def test_arrays_are_views_of_the_library_result(self):
        s = optics.spectrum(photons=500, wl_step_nm=200)
        self.assertFalse(s.reflectance.flags.owndata)
        self.assertEqual(s.reflectance.dtype, np.float64)
        r = s.reflectance
        del s  # the view keeps the C result alive
        self.assertTrue(np.all(np.isfinite(r)))

    def test_colour_of_a_white_reflector_is_white(self):
        wl = np.arange(380.0, 781.0, 5.0)
        np.testing.assert_allclose(optics.colour(wl, np.ones_like(wl)), [1, 1, 1], atol=2e-3)
        grey = optics.colour(wl, np.full_like(wl, 0.18))
        np.testing.assert_allclose(grey, [0.18] * 3, atol=1e-3)

    def test_lab_and_colour_difference(self):
        np.testing.assert_allclose(optics.lab([1.0, 1.0, 1.0]), [100, 0, 0], atol=1e-6)
        grey = optics.lab([[0.18, 0.18, 0.18], [0.5, 0.5, 0.5]])
        self.assertEqual(grey.shape, (2, 3))
        self.assertLess(grey[0, 0], grey[1, 0])
        # Sharma, Wu & Dalal (2005) Table 1, pair 1: dE00 = 2.0425
        self.assertAlmostEqual(optics.ciede2000([50, 2.6772, -79.7751], [50, 0, -82.7485]),
                               2.0425, places=4)
        light = optics.lab(optics.spectrum(melanin=0.02, photons=1500, wl_step_nm=20).colour())
        dark = optics.lab(optics.spectrum(melanin=0.3, photons=1500, wl_step_nm=20).colour())
        self.assertGreater(optics.describe_lab(light)[2], optics.describe_lab(dark)[2])  # ITA
        with self.assertRaises(skinsim.InputError):
            optics.lab([1, 2])

    def test_skin_colour_matches_the_cli(self):
        import json
        import subprocess
        cli = os.environ.get("SKINSIM_CLI")
        if not cli:
            self.skipTest("SKINSIM_CLI not set")
        out = subprocess.run([cli, "optics", "spectrum", "--json", "--photons", "1000",
                              "--wl-step", "20", "--melanin", "0.1", "--threads", "2"],
                             check=True, capture_output=True, text=True).stdout
        ref = json.loads(out)
        s = optics.spectrum(melanin=0.1, photons=1000, wl_step_nm=20)
        # the JSON carries 6 significant digits
        np.testing.assert_allclose(s.reflectance, ref["reflectance"], rtol=2e-5)
        np.testing.assert_allclose(s.colour(), ref["srgb_linear"], rtol=2e-5)

    def test_bad_input_raises_with_the_library_message(self):
        with self.assertRaises(skinsim.InputError) as cm:
            optics.spectrum(melanin=float("nan"))
        self.assertIn("melanin", str(cm.exception))
        self.assertEqual(cm.exception.code, 2)
        with self.assertRaises(ValueError):  # InputError is a ValueError
            optics.spectrum(blood=1.5)
        with self.assertRaises(skinsim.InputError) as cm:
            optics.spectrum(wl_min_nm=100, wl_max_nm=200, photons=10)
        self.assertIn("nm", str(cm.exception))
        with self.assertRaises(TypeError):
            optics.spectrum(melanine=0.1)
        with self.assertRaises(skinsim.InputError):
            optics.colour([400, 500], [0.5])


class BRDFAndFit(unittest.TestCase):
    def test_fit_recovers_a_render_model(self):
        for model in ("ggx", "ashikhmin-shirley"):
            data = optics.render_brdf(model, base_rgb=(0.6, 0.35, 0.25), specular=0.7,
                                      roughness=0.4, n_theta_i=6, n_theta_r=6, n_phi=6)
            self.assertEqual(data.shape, (6, 6, 6, 3))
            r = optics.fit(data, model)
            np.testing.assert_allclose(r["base_rgb"], [0.6, 0.35, 0.25], atol=2e-3)
            self.assertAlmostEqual(r["specular"], 0.7, delta=5e-3)
            self.assertAlmostEqual(r["roughness"], 0.4, delta=5e-3)
            self.assertLess(r["residual_rel"], 1e-3)

    def test_skin_brdf_fits_with_plausible_parameters(self):
        b = optics.brdf(n_theta_i=4, n_theta_r=4, n_phi=4, photons=1500, wl_step_nm=50,
                        melanin=0.05)
        self.assertEqual(b.shape, (4, 4, 4, 3))
        self.assertTrue(np.all(b >= 0))
        r = optics.fit(b, "ggx")
        self.assertTrue(np.all((r["base_rgb"] > 0) & (r["base_rgb"] <= 1)))
        self.assertGreater(r["base_rgb"][0], r["base_rgb"][2])  # red above blue
        self.assertTrue(0.05 <= r["roughness"] <= 1)

    def test_fit_rejects_bad_arrays(self):
        with self.assertRaises(skinsim.InputError):
            optics.fit(np.zeros((4, 4, 3)))
        bad = np.ones((2, 2, 2, 3))
        bad[0, 0, 0, 0] = np.nan
        with self.assertRaises(skinsim.InputError):
            optics.fit(bad)
        with self.assertRaises(skinsim.InputError) as cm:
            optics.fit(np.ones((2, 2, 2, 3)), "phong")
        self.assertIn("phong", str(cm.exception))

    def test_match_gives_an_entry(self):
        e = optics.match(photons=400, n_theta_i=3, n_theta_r=3, n_phi=3, wl_step_nm=60,
                         melanin=0.05)
        for m in ("ggx", "ashikhmin-shirley"):
            self.assertEqual(e[m]["base_rgb"].shape, (3,))
        self.assertTrue(np.all(e["sss_radius_cm"] > 0))
        self.assertGreater(e["albedo_rgb"][0], e["albedo_rgb"][2])


class Table(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.t = optics.Table()

    def test_lookup_is_exact_at_nodes(self):
        ax = self.t.axes
        idx = (2, 1, 1, 0, 2, 1)
        point = {name: ax[name][i] for name, i in zip(optics.AXES, idx)}
        e = self.t.lookup(**point)
        node = self.t.entries[idx]
        np.testing.assert_allclose(e["ggx"]["base_rgb"], node[0:3], rtol=1e-12)
        self.assertAlmostEqual(e["ggx"]["specular"], node[3], places=12)
        self.assertAlmostEqual(e["ggx"]["roughness"], node[4], places=12)

    def test_lookup_maps_equals_pointwise_lookup(self):
        mel = np.linspace(0.01, 0.4, 12).reshape(3, 4).astype(np.float32)
        blood = np.full((3, 4), 0.02)
        m = self.t.lookup_maps(melanin=mel, blood=blood)
        self.assertEqual(m["base_rgb"].shape, (3, 4, 3))
        for (i, j) in [(0, 0), (1, 2), (2, 3)]:
            e = self.t.lookup(melanin=float(mel[i, j]), blood=0.02)
            np.testing.assert_allclose(m["base_rgb"][i, j], e["ggx"]["base_rgb"], rtol=1e-12)
            self.assertAlmostEqual(m["roughness"][i, j], e["ggx"]["roughness"], places=12)
            np.testing.assert_allclose(m["albedo_rgb"][i, j], e["albedo_rgb"], rtol=1e-12)
        # more melanin, darker
        self.assertTrue(np.all(np.diff(m["base_rgb"][..., 2].ravel()) < 0))

    def test_missing_and_corrupt_tables(self):
        with self.assertRaises(skinsim.InputError) as cm:
            optics.Table("/nonexistent/x.sstab")
        self.assertIn("/nonexistent/x.sstab", str(cm.exception))
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "bad.sstab")
            with open(optics.default_table_path(), "rb") as f:
                data = bytearray(f.read())
            data[200] ^= 0xFF
            with open(p, "wb") as f:
                f.write(data)
            with self.assertRaises(skinsim.InputError) as cm:
                optics.Table(p)
            self.assertIn("bad.sstab", str(cm.exception))


if __name__ == "__main__":
    unittest.main()
