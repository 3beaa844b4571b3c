"""Wound healing (seed 001): the library's heal run object from Python.

    run = skinsim.heal.Run(scenario="clean", days=21)   # in memory, nothing written
    run.advance_to(7.0)                                 # day 7
    e = run.field("epithelium")                         # (nz, ny, nx) float32 view
    top = run.surface("epithelium")                     # (ny, nx) top view
    curve = run.area()                                  # t_days, normalised_area, ...
    run.advance_to(run.end_day); summary = run.finish()

All stepping, bookkeeping and outputs are the library's (ss_heal_run in
include/skinsim/heal_run.h, the same object `skinsim heal` runs), so a run
here gives the numbers the command line gives. With out_dir the run also
writes what `skinsim heal --out` writes (snapshots, area.csv/png,
summary.json on finish).

Fields come as numpy views of the grid (axis order z, y, x; z up, z = nz-1
the top): no copy, and they show the state of the moment you took them
until the next step -- the solver may swap buffers while stepping, so
take a view again (or .copy()) after stepping. Views keep the run's memory
alive. Units: mm and days.
"""

import ctypes
import json
import os

import numpy as np

from . import _lib as L

FIELDS = [L.lib.ss_heal_field_name(i).decode() for i in range(L.SS_HEAL_NFIELDS)]
CELL_STATES = {"air": 0, "epidermis": 1, "dermis": 2, "wound": 3, "bound": 4}
_SURFACE_MODES = {"top": 0, "max": 1, "layer": 2}
_SCHEMES = {"explicit": 0, "split": 1}


def _field_index(name):
    if name not in FIELDS:
        raise L.InputError("field: %r is not one of %s" % (name, ", ".join(FIELDS)),
                           L.SS_ERR_INPUT)
    return FIELDS.index(name)


def _triple(name, v, kind):
    if v is None:
        return None
    t = tuple(v)
    if len(t) != 3:
        raise L.InputError("%s: want three values (x, y, z), got %r" % (name, v), L.SS_ERR_INPUT)
    return tuple(kind(x) for x in t)


class Run:
    """One healing simulation. Keyword arguments are the fields of
    ss_heal_run_config, named like the `skinsim heal` options:

    scenario       "clean" | "scab" | "keloid"
    days           end of the run (default 10)
    grid           (nx, ny, nz) voxels;  size_mm  (x, y, z) block size in mm
    wound_mask     footprint: a PNG/EXR path, or an array (ny, nx) > 0.5 = wound
                   (row 0 at the far y edge, as a mask image)
    wound_stroke   painted strokes CSV;  wound_mesh  closed OBJ (mm, grid frame)
    wound_depth_mm, scheme ("split" | "explicit"), dt_days, area_every,
    snapshot_every, checkpoint_every, params_path, no_scab, static_region,
    out_dir (None: in memory), force, resume_dir, seed
    mechanics      True: wound contraction (mass-spring mechanics, docs/mech.md)
    skin_mesh      closed OBJ/glTF/GLB body surface: the grid becomes a patch of
                   skin around the wound on it (docs/mech.md, "Real geometry"),
                   with the wound as wound_uv (strokes CSV in the mesh's UV
                   space) or wound_mesh (closed mesh in the mesh's units);
                   voxel_mm, skin_thickness_mm, mesh_units_mm as the options
    Bad input raises InputError with the library's message, which names the
    setting by its command-line option.
    """

    def __init__(self, scenario=None, days=None, grid=None, size_mm=None, wound_mask=None,
                 wound_stroke=None, wound_mesh=None, wound_depth_mm=None, scheme=None,
                 dt_days=None, area_every=None, snapshot_every=None, checkpoint_every=None,
                 params_path=None, no_scab=False, static_region=False, out_dir=None,
                 force=False, resume_dir=None, seed=None, concave_k=None, skin_top_mm=None,
                 epidermis_mm=None, mechanics=False, skin_mesh=None, wound_uv=None,
                 voxel_mm=None, skin_thickness_mm=None, mesh_units_mm=None):
        self._h = None
        c = L.ss_heal_run_config()
        L.lib.ss_heal_run_config_default(ctypes.byref(c))
        keep = []  # bytes and arrays the config points into, alive during create

        def text(v):
            if v is None:
                return None
            b = os.fsencode(os.fspath(v)) if not isinstance(v, bytes) else v
            keep.append(b)
            return b

        c.scenario = text(scenario)
        c.params_path = text(params_path)
        c.no_scab = 1 if no_scab else 0
        c.static_region = 1 if static_region else 0
        g = _triple("grid", grid, int)
        if g:
            c.grid[:] = g
        sz = _triple("size_mm", size_mm, float)
        if sz:
            c.size_mm[:] = sz
        for name, v in (("skin_top_mm", skin_top_mm), ("epidermis_mm", epidermis_mm),
                        ("wound_depth_mm", wound_depth_mm), ("days", days),
                        ("dt_days", dt_days), ("area_every", area_every),
                        ("snapshot_every", snapshot_every),
                        ("checkpoint_every", checkpoint_every)):
            if v is not None:
                setattr(c, name, float(v))
        if wound_mask is not None and not isinstance(wound_mask, (str, bytes, os.PathLike)):
            m = L.as_image_input(wound_mask, "wound_mask", channels=(1,))
            if m.ndim == 3:
                m = np.ascontiguousarray(m[..., 0])
            hdr = L.image_header(m)
            keep.append(hdr)
            c.wound_footprint = ctypes.pointer(hdr)
        else:
            c.wound_mask = text(wound_mask)
        c.wound_stroke = text(wound_stroke)
        c.mechanics = 1 if mechanics else 0
        c.skin_mesh = text(skin_mesh)
        c.wound_uv = text(wound_uv)
        for name, v in (("voxel_mm", voxel_mm), ("skin_thickness_mm", skin_thickness_mm),
                        ("mesh_units_mm", mesh_units_mm)):
            if v is not None:
                setattr(c, name, float(v))
        c.wound_mesh = text(wound_mesh)
        if concave_k is not None:
            c.concave_k = int(concave_k)
        if scheme is not None:
            if scheme not in _SCHEMES:
                raise L.InputError("scheme: %r is not split or explicit" % (scheme,),
                                   L.SS_ERR_INPUT)
            c.scheme = _SCHEMES[scheme]
        c.out_dir = text(out_dir)
        c.force = 1 if force else 0
        c.resume_dir = text(resume_dir)
        if seed is not None:
            c.seed = int(seed)
        r = L.P_RUN()
        L.check(L.lib.ss_heal_run_create, ctypes.byref(c), ctypes.byref(r))
        self._h = L.Handle()
        self._r = self._h.own(L.lib.ss_heal_run_free, r)
        self.out_dir = out_dir

    def _run(self):
        if self._h is None:
            raise L.SkinsimError("this Run was closed", L.SS_ERR_INPUT)
        return self._r

    def close(self):
        """Drops this object's hold on the run (memory goes with the last view)."""
        self._h = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- time ----
    @property
    def day(self):
        return L.lib.ss_heal_run_day(self._run())

    @property
    def dt(self):
        return L.lib.ss_heal_run_dt(self._run())

    @property
    def end_day(self):
        return L.lib.ss_heal_run_end_day(self._run())

    @property
    def step_index(self):
        return L.lib.ss_heal_run_step_index(self._run())

    @property
    def steps_total(self):
        return L.lib.ss_heal_run_steps_total(self._run())

    @property
    def done(self):
        return bool(L.lib.ss_heal_run_done(self._run()))

    @property
    def scenario(self):
        return L.lib.ss_heal_run_scenario(self._run()).decode()

    def step(self, n=1):
        """n solver steps with the run's bookkeeping (area rows, snapshots,
        checkpoints). Stepping past the end raises InputError."""
        r = self._run()
        for _ in range(int(n)):
            L.check(L.lib.ss_heal_run_step, r)
        return self

    def advance_to(self, day):
        """Steps until the run reaches `day` (rounded to whole steps)."""
        L.check(L.lib.ss_heal_run_advance_to, self._run(), float(day))
        return self

    def finish(self):
        """Closing tables (area.csv, area.png and summary.json when the run
        has an out_dir); returns the summary as a dict."""
        p = ctypes.c_void_p()
        L.check(L.lib.ss_heal_run_finish, self._run(), ctypes.byref(p))
        try:
            return json.loads(ctypes.string_at(p.value).decode()) if p.value else {}
        finally:
            if p.value:
                L.libc_free(p)

    # ---- state ----
    def _grid(self):
        return L.lib.ss_heal_run_grid(self._run()).contents

    @property
    def shape(self):
        """(nz, ny, nx): the axis order of every field array."""
        g = self._grid()
        return (g.nz, g.ny, g.nx)

    @property
    def dx_mm(self):
        return self._grid().dx_mm

    def field(self, name, copy=False):
        """A species field (see FIELDS) as a (nz, ny, nx) float32 array: a
        view of the grid (valid until the next step) or, with copy=True, a
        copy. Writing into the view changes the simulation's state, as the
        library allows between steps."""
        g = self._grid()
        f = _field_index(name)
        v = L.float_view(g.field[f], g.nx * g.ny * g.nz, self._h, (g.nz, g.ny, g.nx))
        return v.copy() if copy else v

    def fields(self, copy=False):
        return {n: self.field(n, copy) for n in FIELDS}

    @property
    def cells(self):
        """Cell states (CELL_STATES codes) as a read-only (nz, ny, nx) uint8 view."""
        g = self._grid()
        n = g.nx * g.ny * g.nz
        buf = (ctypes.c_uint8 * n).from_address(ctypes.cast(g.cell, ctypes.c_void_p).value)
        buf._owner = self._h
        a = np.frombuffer(buf, dtype=np.uint8).reshape(g.nz, g.ny, g.nx)
        a.flags.writeable = False
        return a

    def surface(self, name, mode="layer"):
        """Top view of a field, (ny, nx), oriented like a footprint image
        (row 0 = the far y edge): "layer" the epithelial layer the open area
        is measured on, "top" the topmost tissue cell, "max" the column
        maximum."""
        if mode not in _SURFACE_MODES:
            raise L.InputError("mode: %r is not one of %s" % (mode, ", ".join(_SURFACE_MODES)),
                               L.SS_ERR_INPUT)
        p = L.check_ptr(L.lib.ss_heal_surface_map, L.lib.ss_heal_run_grid(self._run()),
                        _field_index(name), _SURFACE_MODES[mode])
        try:
            return L.image_view(p, None).copy()
        finally:
            L.lib.ss_image_free(p)

    def area(self):
        """The wound-area curve so far (seed 001 Fig. 4), one row per
        area_every: arrays t_days, open_area_mm2, normalised_area,
        wound_region_area_mm2 and mean_<field> per field (copies)."""
        n = ctypes.c_int()
        rows = L.lib.ss_heal_run_area(self._run(), ctypes.byref(n))
        n = n.value
        out = {"t_days": np.empty(n), "open_area_mm2": np.empty(n),
               "normalised_area": np.empty(n), "wound_region_area_mm2": np.empty(n)}
        means = np.empty((n, L.SS_HEAL_NFIELDS))
        for i in range(n):
            r = rows[i]
            out["t_days"][i] = r.t_days
            out["open_area_mm2"][i] = r.st.open_area_mm2
            out["normalised_area"][i] = L.lib.ss_heal_area_normalised(ctypes.byref(r.st))
            out["wound_region_area_mm2"][i] = r.st.wound_region_area_mm2
            means[i] = r.st.field_mean[:]
        for k, name in enumerate(FIELDS):
            out["mean_" + name] = means[:, k].copy()
        return out

    def time_to_closure(self, level=0.05):
        """First day the normalised open area drops to <= level (None if not yet)."""
        n = ctypes.c_int()
        rows = L.lib.ss_heal_run_area(self._run(), ctypes.byref(n))
        t = L.lib.ss_heal_time_to_closure(rows, n.value, float(level))
        return None if t < 0 else t
