"""What a Python user relies on beyond the physics: objects freed when
dropped, Ctrl-C and progress on long calls, numbers checked before they
reach C (messages naming the keyword, not a command-line flag), the output
folder checked at construction, colour only inside the CIE tables, the
vectorised table lookup equal to single lookups, any layer stack through
run_layers, and a docstring on every public member."""
import gc
import inspect
import os
import signal
import tempfile
import threading
import time
import unittest
import weakref

import numpy as np

import skinsim
from skinsim import _lib as L
from skinsim import heal, optics

try:
    from skinsim import skin
except ImportError:  # a library built without the skin module
    skin = None


def _sigint_after(seconds):
    t = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    t.start()
    return t


class Freed(unittest.TestCase):
    def setUp(self):
        gc.collect()
        gc.disable()  # freed by reference counting alone: no cycle left for the collector

    def tearDown(self):
        gc.enable()

    def test_table_is_freed_when_dropped(self):
        t = optics.Table()
        owner = weakref.ref(t._h)
        table = weakref.ref(t)
        del t
        self.assertIsNone(table())
        self.assertIsNone(owner(), "the C table outlived its Table")

    def test_a_view_keeps_the_table_memory_until_it_goes(self):
        t = optics.Table()
        owner = weakref.ref(t._h)
        e = t.entries
        first = float(e.flat[0])
        del t
        self.assertIsNotNone(owner())
        self.assertEqual(float(e.flat[0]), first)
        del e
        self.assertIsNone(owner())

    def test_spectrum_is_freed_when_dropped(self):
        s = optics.spectrum(photons=200, wl_step_nm=200)
        owner = weakref.ref(s._h)
        del s
        self.assertIsNone(owner())

    def test_fifty_tables_do_not_pile_up(self):
        owners = []
        for _ in range(50):
            owners.append(weakref.ref(optics.Table()._h))
        self.assertEqual(sum(o() is not None for o in owners), 0)

    @unittest.skipIf(skin is None, "no skin module")
    def test_textures_without_table_reuse_one_default_table(self):
        opened = []
        real = optics.Table.__init__

        def counting(self, path=None):
            opened.append(path)
            real(self, path)

        optics.default_table()  # whatever opened it before
        optics.Table.__init__ = counting
        try:
            skin.textures(size=32, counts={"moles": 1})
            skin.textures(size=32, counts={"moles": 1})
        finally:
            optics.Table.__init__ = real
        self.assertEqual(opened, [])
        self.assertIs(optics.default_table(), optics.default_table())


class Interrupt(unittest.TestCase):
    def test_ctrl_c_stops_a_long_transport(self):
        slab = [dict(n=1.4, mua_per_cm=0.1, mus_per_cm=100, g=0.9, d_cm=1.0)]
        t = _sigint_after(0.5)
        t0 = time.monotonic()
        with self.assertRaises(KeyboardInterrupt):
            optics.run_layers(slab, photons=10**10)  # hours if not stopped
        t.join()
        self.assertLess(time.monotonic() - t0, 120)
        self.assertIs(signal.getsignal(signal.SIGINT), signal.default_int_handler)
        r = optics.run_layers(slab, photons=2000)  # the library goes on working
        self.assertGreater(r["diffuse"], 0)

    def test_ctrl_c_stops_a_spectrum(self):
        t = _sigint_after(0.5)
        with self.assertRaises(KeyboardInterrupt):
            optics.spectrum(photons=10**9, wl_step_nm=10)
        t.join()

    def test_ctrl_c_stops_a_heal_run_between_steps(self):
        run = heal.Run(days=2000, grid=(40, 40, 16), dt_days=0.05)
        t = _sigint_after(0.5)
        with self.assertRaises(KeyboardInterrupt):
            run.advance_to(2000)
        t.join()
        day = run.day
        self.assertGreater(day, 0)
        self.assertLess(day, 2000)
        run.step()  # still a valid run
        self.assertGreater(run.day, day)

    # Ctrl-C in the texture calls: a real SIGINT sent from the first
    # progress callback (so small, fast sizes still interrupt mid-call) must
    # stop the call at its next poll -- no further callbacks -- raise
    # KeyboardInterrupt, restore the handler and free what the call made;
    # the next call, with a progress callable, equals one without.
    @staticmethod
    def _sigint_at_first(seen):
        def progress(fraction):
            seen.append(fraction)
            if len(seen) == 1:
                os.kill(os.getpid(), signal.SIGINT)
        return progress

    def _assert_stopped_at_first_poll(self, seen):
        self.assertEqual(len(seen), 1, "the call went on after Ctrl-C: %r" % seen)
        self.assertLess(seen[0], 1.0)
        self.assertIs(signal.getsignal(signal.SIGINT), signal.default_int_handler)

    def _assert_progress_rises_to_one(self, seen):
        self.assertGreater(len(seen), 2)
        self.assertEqual(seen, sorted(seen))
        self.assertAlmostEqual(seen[-1], 1.0)

    @unittest.skipIf(skin is None, "no skin module")
    def test_ctrl_c_stops_skin_textures(self):
        handles = []
        real = L.Handle.__init__

        def tracked(h):
            real(h)
            handles.append(weakref.ref(h))

        optics.default_table()
        for stop_at in (1, 6, 11):  # in the features; the bio maps; the render maps
            seen = []

            def progress(f, seen=seen, stop_at=stop_at):
                seen.append(f)
                if len(seen) == stop_at:
                    os.kill(os.getpid(), signal.SIGINT)

            L.Handle.__init__ = tracked
            try:
                with self.assertRaises(KeyboardInterrupt) as cm:
                    skin.textures(size=128, progress=progress)
            finally:
                L.Handle.__init__ = real
            del cm
            self.assertEqual(len(seen), stop_at, "went on after Ctrl-C: %r" % seen)
            self.assertLess(seen[-1], 1.0)
            self.assertIs(signal.getsignal(signal.SIGINT), signal.default_int_handler)
            self.assertEqual(len(handles), 1)
            self.assertIsNone(handles.pop()(), "a cancelled call kept its C memory")
        plain = skin.textures(size=128)
        seen = []
        t = skin.textures(size=128, progress=seen.append)
        self._assert_progress_rises_to_one(seen)
        for m in ("base_color", "roughness", "specular", "height_mm", "normal", "bio"):
            np.testing.assert_array_equal(t[m], plain[m])

    def test_ctrl_c_stops_an_abrasion_frame(self):
        from skinsim import abrasion

        ab = abrasion.Abrasion(size=64)
        keys, end = ab.timeline
        blend = 0.5 * (keys[3][1] + keys[4][1])  # vasodilation -> scab forming
        for day in (blend, keys[-1][1] + 0.5 * (end - keys[-1][1])):  # a blend; maturation
            seen = []
            with self.assertRaises(KeyboardInterrupt):
                ab.frame(day, progress=self._sigint_at_first(seen))
            self._assert_stopped_at_first_poll(seen)
            plain = ab.frame(day)
            seen = []
            f = ab.frame(day, progress=seen.append)
            self.assertGreaterEqual(len(seen), 2)
            self.assertEqual(seen, sorted(seen))
            self.assertAlmostEqual(seen[-1], 1.0)
            for m in plain:
                np.testing.assert_array_equal(f[m], plain[m])

    def test_ctrl_c_stops_a_wound_render(self):
        try:
            from skinsim import wound
        except ImportError:
            self.skipTest("no wound module")
        run = heal.Run(days=1, grid=(16, 16, 6), size_mm=(8, 8, 3))
        tex = wound.Textures(run, size=256)
        seen = []
        with self.assertRaises(KeyboardInterrupt):
            tex.render(progress=self._sigint_at_first(seen))
        self._assert_stopped_at_first_poll(seen)
        plain = tex.render()
        seen = []
        maps = tex.render(progress=seen.append)
        self._assert_progress_rises_to_one(seen)
        for m in plain:
            np.testing.assert_array_equal(maps[m], plain[m])

    def test_progress_callable_and_bar(self):
        seen = []
        optics.spectrum(photons=300, wl_step_nm=100, progress=seen.append)
        self.assertEqual(len(seen), 5)
        self.assertEqual(seen, sorted(seen))
        self.assertAlmostEqual(seen[-1], 1.0)
        run = heal.Run(days=0.5, grid=(12, 12, 6))
        days = []
        run.advance_to(0.5, progress=days.append)
        self.assertEqual(len(days), run.steps_total)
        self.assertAlmostEqual(days[-1], 1.0)
        buf = _Buffer()
        optics.spectrum(photons=300, wl_step_nm=100, progress=L.ProgressBar("spec", buf))
        self.assertIn("100%", buf.text)

    def test_an_exception_from_progress_stops_the_call(self):
        def boom(f):
            raise RuntimeError("stop here")

        with self.assertRaisesRegex(RuntimeError, "stop here"):
            optics.spectrum(photons=300, wl_step_nm=50, progress=boom)


class _Buffer:
    def __init__(self):
        self.text = ""

    def write(self, s):
        self.text += s

    def flush(self):
        pass


class Values(unittest.TestCase):
    def assertRefused(self, exc, pattern, fn, *a, **kw):
        with self.assertRaisesRegex(exc, pattern):
            fn(*a, **kw)

    @unittest.skipIf(skin is None, "no skin module")
    def test_sizes_are_checked_before_conversion(self):
        self.assertRefused(ValueError, r"^size: 1099511627776 is outside", skin.textures,
                           size=2**40)
        self.assertRefused(ValueError, r"^size: want a whole number, got 3.7", skin.textures,
                           size=3.7)
        self.assertRefused(ValueError, r"^size: want a whole number, got nan", skin.textures,
                           size=float("nan"))
        self.assertRefused(TypeError, r"^size: want a whole number", skin.textures, size="64")
        self.assertRefused(ValueError, r"^world_size_cm: want a finite number",
                           skin.textures, size=32, world_size_cm=float("inf"))

    def test_numbers_name_the_keyword(self):
        self.assertRefused(ValueError, r"^melanin: want a finite number, got nan",
                           optics.spectrum, melanin=float("nan"))
        self.assertRefused(ValueError, r"^photons: want a whole number, got 3.7",
                           optics.spectrum, photons=3.7)
        self.assertRefused(ValueError, r"^seed: -1 is outside", optics.spectrum, seed=-1)
        self.assertRefused(ValueError, r"^grid\[0\]: 1099511627776 is outside", heal.Run,
                           grid=(2**40, 8, 8))
        self.assertRefused(ValueError, r"^days: want a finite number, got nan", heal.Run,
                           days=float("nan"))
        self.assertEqual(optics.brdf(n_theta_i=2.0, n_theta_r=2, n_phi=2, photons=100,
                                     wl_step_nm=150).shape, (2, 2, 2, 3))

    def test_library_messages_in_python_terms(self):
        for kw, want in ((dict(days=-1), r"^days=-1: "),
                         (dict(area_every=-1), r"^area_every=-1: "),
                         (dict(skin_mesh="x.obj"), r"^skin_mesh needs the wound as wound_uv")):
            with self.assertRaises(ValueError) as cm:
                heal.Run(**kw)
            self.assertRegex(str(cm.exception), want)
            self.assertNotIn("--", str(cm.exception))

    def test_out_dir_checked_at_construction(self):
        with tempfile.TemporaryDirectory() as d:
            afile = os.path.join(d, "a-file")
            open(afile, "w").close()
            self.assertRefused(ValueError, r"^out_dir=.*a-file: exists and is a file",
                               heal.Run, out_dir=afile)
            other = os.path.join(d, "other")
            os.mkdir(other)
            open(os.path.join(other, "notes.txt"), "w").close()
            self.assertRefused(ValueError, r"not a 'skinsim heal' run folder", heal.Run,
                               out_dir=other)
            self.assertTrue(os.path.exists(os.path.join(other, "notes.txt")))
            if os.path.isdir("/proc/self"):
                self.assertRefused(ValueError, r"^out_dir=/proc/skinsim-x: cannot be created",
                                   heal.Run, out_dir="/proc/skinsim-x")
            ok = heal.Run(out_dir=os.path.join(d, "run"), days=0.1, grid=(8, 8, 12))
            self.assertFalse(os.path.exists(os.path.join(d, "run")))  # nothing before work
            ok.close()

    def test_colour_outside_the_cie_tables_raises(self):
        for wl in ([300.0, 500.0], [600.0, 900.0], [850.0, 900.0]):
            self.assertRefused(ValueError, r"outside the CIE 1931", optics.colour, wl,
                               [0.5, 0.5])
        np.testing.assert_allclose(optics.colour([380.0, 780.0], [0.25, 0.25]), [0.25] * 3,
                                   atol=1e-3)


class TableMaps(unittest.TestCase):
    def test_lookup_maps_equals_lookup_per_pixel(self):
        t = optics.default_table()
        rng = np.random.default_rng(3)
        mel = rng.uniform(0.0, 0.5, (7, 9))
        blood = rng.uniform(0.0, 0.08, (7, 9))
        m = t.lookup_maps(melanin=mel, blood=blood, oxygenation=0.6)
        self.assertEqual(m["base_rgb"].shape, (7, 9, 3))
        for (i, j) in ((0, 0), (3, 4), (6, 8)):
            e = t.lookup(melanin=mel[i, j], blood=blood[i, j], oxygenation=0.6)
            np.testing.assert_array_equal(m["base_rgb"][i, j], e["ggx"]["base_rgb"])
            self.assertEqual(m["roughness"][i, j], e["ggx"]["roughness"])
            np.testing.assert_array_equal(m["albedo_rgb"][i, j], e["albedo_rgb"])

    def test_lookup_maps_is_one_call_not_a_pixel_loop(self):
        t = optics.default_table()
        calls = []
        real = L.lib.ss_mm_table_lookup

        class Spy:
            def __call__(self, *a):
                calls.append(1)
                return real(*a)

        L.lib.ss_mm_table_lookup = Spy()
        try:
            m = t.lookup_maps(melanin=np.full((64, 64), 0.1))
        finally:
            L.lib.ss_mm_table_lookup = real
        self.assertEqual(calls, [])
        self.assertEqual(m["specular"].shape, (64, 64))


class Layers(unittest.TestCase):
    def test_van_de_hulst_slab(self):
        # n=1, mua=10/cm, mus=90/cm, g=0.75, d=0.02 cm: Rd 0.09739, Tt 0.66096
        r = optics.run_layers([dict(n=1.0, mua_per_cm=10, mus_per_cm=90, g=0.75, d_cm=0.02)],
                              photons=40000, seed=7)
        self.assertLess(abs(r["diffuse"] - 0.09739), 3 * r["diffuse_se"])
        self.assertLess(abs(r["transmit"] - 0.66096), 3 * r["transmit_se"])
        total = r["specular"] + r["diffuse"] + r["transmit"] + r["absorbed"] - r["roulette_net"]
        self.assertAlmostEqual(total, 1.0, places=9)
        self.assertEqual(r["absorbed_per_layer"].shape, (1,))

    def test_two_layers_brdf_radial_and_determinism(self):
        layers = [(1.4, 1.0, 200.0, 0.8, 0.01), (1.4, 0.5, 100.0, 0.9, 0.2)]
        a = optics.run_layers(layers, photons=6000, seed=2, brdf_bins=(4, 3), radial_bins=8,
                              radial_max_cm=0.4, bottom_albedo=0.5)
        skinsim.set_threads(1)
        b = optics.run_layers(layers, photons=6000, seed=2, brdf_bins=(4, 3), radial_bins=8,
                              radial_max_cm=0.4, bottom_albedo=0.5)
        skinsim.set_threads(0)
        self.assertEqual(a["diffuse"], b["diffuse"])
        self.assertEqual(a["brdf_exit"].shape, (4, 3))
        self.assertEqual(a["radial"].shape, (8,))
        self.assertEqual(a["absorbed_per_layer"].shape, (2,))
        self.assertGreater(a["specular"], 0.0)  # index step at the top

    def test_bad_layers(self):
        with self.assertRaisesRegex(ValueError, r"layers\[0\]\.g: want a finite"):
            optics.run_layers([dict(n=1.0, mua_per_cm=1, mus_per_cm=1, g=float("nan"), d_cm=1)])
        with self.assertRaisesRegex(ValueError, r"layers: want 1\.\.16"):
            optics.run_layers([])
        with self.assertRaisesRegex(ValueError, r"layers\[0\]: want keys"):
            optics.run_layers([dict(n=1.0)])


def _public_members(module):
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", module.__name__) != module.__name__:
            continue
        if inspect.isfunction(obj):
            yield "%s.%s" % (module.__name__, name), obj
        elif inspect.isclass(obj):
            yield "%s.%s" % (module.__name__, name), obj
            for mname, m in vars(obj).items():
                if mname.startswith("_") and mname not in ("__init__", "__enter__", "__exit__"):
                    continue
                if mname == "__init__":
                    continue  # the class docstring describes construction
                if inspect.isfunction(m) or isinstance(m, property):
                    yield "%s.%s.%s" % (module.__name__, name, mname), m


class Documented(unittest.TestCase):
    def test_every_public_member_has_a_docstring(self):
        mods = [skinsim, skinsim.optics, skinsim.heal, skinsim.abrasion]
        for opt in ("skin", "wound"):
            if hasattr(skinsim, opt):
                mods.append(getattr(skinsim, opt))
        missing = [name for m in mods for name, obj in _public_members(m)
                   if not (inspect.getdoc(obj) or "").strip()]
        self.assertEqual(missing, [])
        self.assertGreater(sum(1 for m in mods for _ in _public_members(m)), 60)

    def test_typed_package(self):
        pkg = os.path.dirname(skinsim.__file__)
        self.assertTrue(os.path.isfile(os.path.join(pkg, "py.typed")))
        hints = inspect.signature(optics.run_layers).return_annotation
        self.assertIsNot(hints, inspect.Signature.empty)


if __name__ == "__main__":
    unittest.main()
