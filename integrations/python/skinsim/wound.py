"""The three seeds joined (skinsim wound): a heal run's tissue at the skin
surface -> biological parameters -> render textures over a base skin.

    run = skinsim.heal.Run(scenario="scab", days=14, grid=(60, 60, 8))
    tex = skinsim.wound.Textures(run, size=512)   # before stepping: exact closure days
    tex.advance_to(7)                             # steps the run, observing every step
    maps = tex.render()   # base_color (512, 512, 3) linear, roughness, height_mm, normal

The texture covers the heal block (square in x, y). The same library calls
`skinsim wound` makes, so a day rendered here equals its frames/t<day>_*.png.
render() writes straight into numpy arrays (pass out= to reuse them).
"""

import ctypes
import os

import numpy as np

from . import _lib as L
from . import heal, optics

if not L.HAVE_WOUND:
    raise ImportError("skinsim.wound: the loaded library %s has no wound module" % L.library_path)

MAPS = ("base_color", "roughness", "height_mm", "normal")


class Textures:
    """Textures of a heal.Run's wound. skin: the base skin as a bio map
    (h, w, 11) in skinsim.skin.BIO_CHANNELS order (e.g.
    skin.textures()["bio"]) or a path to `skinsim skin`'s output folder or
    bio.exr; default the built-in forearm skin at the block's size; table: an
    optics.Table or path; recipe: a recipe JSON path (docs/wound.md)."""

    def __init__(self, run, size=512, skin=None, table=None, recipe=None, seed=1,
                 scab_photons=None):
        if not isinstance(run, heal.Run):
            raise TypeError("run: a skinsim.heal.Run")
        self.run = run
        r = run._run()
        g = L.lib.ss_heal_run_grid(r).contents
        self.side_mm = g.nx * g.dx_mm
        if abs(g.ny * g.dx_mm - self.side_mm) > 1e-9 * self.side_mm:
            raise L.InputError("the heal block is %g x %g mm; the texture needs a square block"
                               % (self.side_mm, g.ny * g.dx_mm), L.SS_ERR_INPUT)
        self.size = L.as_int("size", size, lo=16, hi=16384)
        self.exact = run.step_index == 0
        rec = L.ss_wound_recipe()
        L.lib.ss_wound_recipe_default(ctypes.byref(rec))
        if recipe is not None:
            L.check(L.lib.ss_wound_recipe_load, os.fsencode(os.fspath(recipe)), ctypes.byref(rec))
        h = L.Handle()
        h.own(lambda _: None, run._h)  # the tissue reads the run's grid: keep it alive
        if skin is None:
            sk = L.check_ptr(L.lib.ss_skin_bio_default, self.size, self.side_mm / 10.0,
                             L.as_u64("seed", seed))
            h.own(L.lib.ss_image_free, sk)
            skin_hdr = sk
        elif isinstance(skin, (str, bytes, os.PathLike)):
            sk = L.check_ptr(L.lib.ss_wound_skin_read, os.fsencode(os.fspath(skin)))
            h.own(L.lib.ss_image_free, sk)
            skin_hdr = sk
        else:
            a = L.as_image_input(skin, "skin")
            if a.ndim != 3 or a.shape[2] != L.SS_BIO_NCHANNELS:
                raise L.InputError("skin: a bio map has %d channels (%s), got shape %s"
                                   % (L.SS_BIO_NCHANNELS, "melanin, pheomelanin, blood, "
                                      "oxygenation, sc_cm, epidermis_cm, height_mm, extra RGBA",
                                      a.shape), L.SS_ERR_INPUT)
            hdr = L.image_header(a)
            L.check(L.lib.ss_wound_skin_validate, ctypes.byref(hdr), b"skin")
            self._skin = (a, hdr)
            skin_hdr = ctypes.pointer(hdr)
        if table is None:
            table = optics.default_table()
        elif not isinstance(table, optics.Table):
            table = optics.Table(table)
        self._table = table
        o = L.ss_wound_render_options()
        L.lib.ss_wound_render_options_default(ctypes.byref(o))
        o.size = self.size
        o.side_mm = self.side_mm
        o.skin = skin_hdr
        o.table = table._t
        o.recipe = rec
        o.seed = L.as_u64("seed", seed)
        if scab_photons is not None:
            o.scab_photons = L.as_u64("scab_photons", scab_photons, lo=1)
        rd = ctypes.c_void_p()
        L.check(L.lib.ss_wound_renderer_create, ctypes.byref(o), ctypes.byref(rd))
        self._renderer = h.own(L.lib.ss_wound_renderer_free, rd)
        t = L.check_ptr(L.lib.ss_wound_tissue_create, L.lib.ss_heal_run_grid(r),
                        L.lib.ss_heal_run_params(r), ctypes.byref(rec))
        self._tissue = h.own(L.lib.ss_wound_tissue_free, ctypes.c_void_p(t))
        self._h = h

    def observe(self):
        """Samples the run's current state (closure days are exact when this
        runs after every step, as advance_to does)."""
        L.lib.ss_wound_tissue_observe(self._tissue, L.lib.ss_heal_run_grid(self.run._run()))

    def advance_to(self, day):
        """Steps the run to `day`, observing the tissue after every step."""
        r = self.run._run()
        target = int(round(L.as_float("day", day, lo=0.0) / L.lib.ss_heal_run_dt(r)))
        if target > L.lib.ss_heal_run_steps_total(r) or target < L.lib.ss_heal_run_step_index(r):
            raise L.InputError("day: %g is before the run's current day %g or after its end %g"
                               % (day, self.run.day, self.run.end_day), L.SS_ERR_INPUT)
        while L.lib.ss_heal_run_step_index(r) < target:
            L.check(L.lib.ss_heal_run_step, r)
            self.observe()
        return self

    def render(self, out=None, progress=None):
        """The textures of the current day: base_color (size, size, 3)
        linear RGB, roughness, height_mm (0 = skin surface) and normal
        (tangent space, OpenGL +Y up). progress: True for a bar on stderr, or
        a callable(fraction 0..1) called between bands of texture rows;
        Ctrl-C stops the render at the next band and raises
        KeyboardInterrupt (arrays passed as out= are then partly written)."""
        n = self.size
        if out is None:
            out = {"base_color": np.zeros((n, n, 3), np.float32),
                   "roughness": np.zeros((n, n), np.float32),
                   "height_mm": np.zeros((n, n), np.float32),
                   "normal": np.zeros((n, n, 3), np.float32)}
        ts = L.ss_wound_textures()
        hdrs = []
        for m, field in zip(MAPS, ("base_color", "roughness", "height", "normal")):
            want = (n, n, 3) if m in ("base_color", "normal") else (n, n)
            L.set_out_image(ts, field, out.get(m), want, "render: out[%r]" % m, hdrs)
        with L.Poll(progress, "wound render") as poll:
            poll.check(L.lib.ss_wound_render_poll, self._renderer, self._tissue, None,
                       ctypes.byref(ts), poll.stage(), None)
        return out
