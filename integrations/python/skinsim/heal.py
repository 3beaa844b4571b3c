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
from typing import Any, Dict, Optional, Sequence, Union

import numpy as np

from . import _lib as L

#: the eight species fields, by name, in the library's order
FIELDS = [L.lib.ss_heal_field_name(i).decode() for i in range(L.SS_HEAL_NFIELDS)]
#: cell state codes of Run.cells
CELL_STATES = {"air": 0, "epidermis": 1, "dermis": 2, "wound": 3, "bound": 4}
_SURFACE_MODES = {"top": 0, "max": 1, "layer": 2}
_SCHEMES = {"explicit": 0, "split": 1}
# the library names settings by their `skinsim heal` options; these differ
# from the keyword arguments by more than - and _ (python_terms)
_RENAME = {"mesh": "skin_mesh", "dt": "dt_days", "out": "out_dir", "resume": "resume_dir",
           "params": "params_path", "mask": "wound_mask", "stroke": "wound_stroke"}

PathLike = Union[str, bytes, "os.PathLike[str]"]


def _field_index(name):
    if name not in FIELDS:
        raise L.InputError("field: %r is not one of %s" % (name, ", ".join(FIELDS)),
                           L.SS_ERR_INPUT)
    return FIELDS.index(name)


def _triple(name, v, conv):
    if v is None:
        return None
    t = tuple(v)
    if len(t) != 3:
        raise L.InputError("%s: want three values (x, y, z), got %r" % (name, v), L.SS_ERR_INPUT)
    return tuple(conv("%s[%d]" % (name, i), x) for i, x in enumerate(t))


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
    Numbers are checked before they reach the library (a whole number where
    one is needed, finite, in range: InputError naming the keyword). Bad
    input raises InputError with the library's message, in which settings
    are named by these keywords (`days=-1: ...`). out_dir is checked here,
    at construction: a folder that cannot be made, or one holding something
    else than a heal run, raises before any work.
    """

    def __init__(self, scenario: Optional[str] = None, days: Optional[float] = None,
                 grid: Optional[Sequence[int]] = None, size_mm: Optional[Sequence[float]] = None,
                 wound_mask: Any = None, wound_stroke: Optional[PathLike] = None,
                 wound_mesh: Optional[PathLike] = None, wound_depth_mm: Optional[float] = None,
                 scheme: Optional[str] = None, dt_days: Optional[float] = None,
                 area_every: Optional[float] = None, snapshot_every: Optional[float] = None,
                 checkpoint_every: Optional[float] = None, params_path: Optional[PathLike] = None,
                 no_scab: bool = False, static_region: bool = False,
                 out_dir: Optional[PathLike] = None, force: bool = False,
                 resume_dir: Optional[PathLike] = None, seed: Optional[int] = None,
                 concave_k: Optional[int] = None, skin_top_mm: Optional[float] = None,
                 epidermis_mm: Optional[float] = None, mechanics: bool = False,
                 skin_mesh: Optional[PathLike] = None, wound_uv: Optional[PathLike] = None,
                 voxel_mm: Optional[float] = None, skin_thickness_mm: Optional[float] = None,
                 mesh_units_mm: Optional[float] = None) -> None:
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
        g = _triple("grid", grid, lambda n, v: L.as_int(n, v, lo=1))
        if g:
            c.grid[:] = g
        sz = _triple("size_mm", size_mm, L.as_float)
        if sz:
            c.size_mm[:] = sz
        for name, v in (("skin_top_mm", skin_top_mm), ("epidermis_mm", epidermis_mm),
                        ("wound_depth_mm", wound_depth_mm), ("days", days),
                        ("dt_days", dt_days), ("area_every", area_every),
                        ("snapshot_every", snapshot_every),
                        ("checkpoint_every", checkpoint_every)):
            if v is not None:
                setattr(c, name, L.as_float(name, v))
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
                setattr(c, name, L.as_float(name, v))
        c.wound_mesh = text(wound_mesh)
        if concave_k is not None:
            c.concave_k = L.as_int("concave_k", concave_k, lo=0)
        if scheme is not None:
            if scheme not in _SCHEMES:
                raise L.InputError("scheme: %r is not split or explicit" % (scheme,),
                                   L.SS_ERR_INPUT)
            c.scheme = _SCHEMES[scheme]
        c.out_dir = text(out_dir)
        c.force = 1 if force else 0
        c.resume_dir = text(resume_dir)
        if seed is not None:
            c.seed = L.as_u64("seed", seed)
        r = L.P_RUN()
        L.check(L.lib.ss_heal_run_create, ctypes.byref(c), ctypes.byref(r), rename=_RENAME)
        self._h = L.Handle()
        self._r = self._h.own(L.lib.ss_heal_run_free, r)
        self.out_dir = out_dir

    def _run(self) -> Any:
        if self._h is None:
            raise L.SkinsimError("this Run was closed", L.SS_ERR_INPUT)
        return self._r

    def close(self) -> None:
        """Drops this object's hold on the run (memory goes with the last view)."""
        self._h = None

    def __enter__(self) -> "Run":
        """The run itself (closed on leaving the with block)."""
        return self

    def __exit__(self, *exc: Any) -> None:
        """Closes the run."""
        self.close()

    # ---- time ----
    @property
    def day(self) -> float:
        """The run's current time, days."""
        return L.lib.ss_heal_run_day(self._run())

    @property
    def dt(self) -> float:
        """The solver's time step, days."""
        return L.lib.ss_heal_run_dt(self._run())

    @property
    def end_day(self) -> float:
        """The day the run ends (steps_total x dt)."""
        return L.lib.ss_heal_run_end_day(self._run())

    @property
    def step_index(self) -> int:
        """Steps taken so far."""
        return L.lib.ss_heal_run_step_index(self._run())

    @property
    def steps_total(self) -> int:
        """Steps from day 0 to the end."""
        return L.lib.ss_heal_run_steps_total(self._run())

    @property
    def done(self) -> bool:
        """True once the run has reached its end."""
        return bool(L.lib.ss_heal_run_done(self._run()))

    @property
    def scenario(self) -> str:
        """The scenario's name ("clean", "scab", "keloid")."""
        return L.lib.ss_heal_run_scenario(self._run()).decode()

    def step(self, n: int = 1) -> "Run":
        """n solver steps with the run's bookkeeping (area rows, snapshots,
        checkpoints). Stepping past the end raises InputError."""
        r = self._run()
        for _ in range(L.as_int("n", n, lo=0)):
            L.check(L.lib.ss_heal_run_step, r, rename=_RENAME)
        return self

    def advance_to(self, day: float, progress: L.ProgressArg = None) -> "Run":
        """Steps until the run reaches `day` (rounded to whole steps).
        progress: True for a bar on stderr, or a callable(fraction 0..1)
        called after every step. Ctrl-C stops after the current step with
        KeyboardInterrupt; the run stays valid there, and advance_to(day)
        again goes on as if it had not stopped."""
        r = self._run()
        day = L.as_float("day", day, lo=0.0)
        with L.Poll(progress, "heal", span=(self.day, day)) as poll:
            L.lib.ss_heal_run_set_progress(r, poll.day, None)
            try:
                poll.check(L.lib.ss_heal_run_advance_to, r, day, rename=_RENAME)
            finally:
                L.lib.ss_heal_run_set_progress(r, L.DAY_FN(), None)
        return self

    def finish(self) -> Dict[str, Any]:
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
    def _grid(self) -> L.ss_heal_grid:
        return L.lib.ss_heal_run_grid(self._run()).contents

    @property
    def shape(self) -> tuple:
        """(nz, ny, nx): the axis order of every field array."""
        g = self._grid()
        return (g.nz, g.ny, g.nx)

    @property
    def dx_mm(self) -> float:
        """Voxel edge, mm."""
        return self._grid().dx_mm

    def field(self, name: str, copy: bool = False) -> np.ndarray:
        """A species field (see FIELDS) as a (nz, ny, nx) float32 array: a
        view of the grid (valid until the next step) or, with copy=True, a
        copy. Writing into the view changes the simulation's state, as the
        library allows between steps."""
        g = self._grid()
        f = _field_index(name)
        v = L.float_view(g.field[f], g.nx * g.ny * g.nz, self._h, (g.nz, g.ny, g.nx))
        return v.copy() if copy else v

    def fields(self, copy: bool = False) -> Dict[str, np.ndarray]:
        """Every species field by name (views, or copies with copy=True)."""
        return {n: self.field(n, copy) for n in FIELDS}

    @property
    def cells(self) -> np.ndarray:
        """Cell states (CELL_STATES codes) as a read-only (nz, ny, nx) uint8 view."""
        g = self._grid()
        n = g.nx * g.ny * g.nz
        buf = (ctypes.c_uint8 * n).from_address(ctypes.cast(g.cell, ctypes.c_void_p).value)
        buf._owner = self._h
        a = np.frombuffer(buf, dtype=np.uint8).reshape(g.nz, g.ny, g.nx)
        a.flags.writeable = False
        return a

    def surface(self, name: str, mode: str = "layer") -> np.ndarray:
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

    def area(self) -> Dict[str, np.ndarray]:
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

    def time_to_closure(self, level: float = 0.05) -> Optional[float]:
        """First day the normalised open area drops to <= level (None if not yet)."""
        n = ctypes.c_int()
        rows = L.lib.ss_heal_run_area(self._run(), ctypes.byref(n))
        t = L.lib.ss_heal_time_to_closure(rows, n.value, L.as_float("level", level, 0.0, 1.0))
        return None if t < 0 else t
