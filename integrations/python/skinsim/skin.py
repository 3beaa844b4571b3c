"""Procedural skin textures (seed 003 §4.8, §5): features scattered by
probability fields -> biological parameter maps -> render maps through the
ModelMatch table. The same library calls `skinsim skin` makes.

    t = skinsim.skin.textures(size=512)              # forearm preset, 5 cm
    t["base_color"]   # (512, 512, 3) linear RGB      t["bio"]  (512, 512, 11)
    t["roughness"], t["specular"], t["height_mm"]  # (512, 512)
    t["normal"]       # (512, 512, 3) tangent space, OpenGL (+Y up)
    t["features"]     # dict of arrays: type, x, y, r, ... (one entry per feature)

Maps are numpy views of the library's images (no copies), kept alive by the
arrays themselves. Lengths in mm, positions in texture units (x right, y
down); see docs/skin.md.
"""

import ctypes
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _lib as L
from . import optics

if not L.HAVE_SKIN:
    raise ImportError("skinsim.skin: the loaded library %s has no skin module" % L.library_path)

#: feature type names (moles, freckles, ...), in the library's order
FEATURE_TYPES = [L.lib.ss_feature_type_name(i).decode() for i in range(L.SS_FEAT_NTYPES)]
#: channels of the bio map (t["bio"][..., k]), in order
BIO_CHANNELS = [L.lib.ss_bio_channel_name(i).decode() for i in range(L.SS_BIO_NCHANNELS)]
#: base-skin parameters settable with base={...}
BASE_NAMES = ["melanin", "pheomelanin", "blood", "oxygenation", "sc", "epidermis"]


def param_names() -> List[str]:
    """Names of the distribution constants (`--param` of the CLI)."""
    p = L.lib.ss_skin_dist_names()
    out, i = [], 0
    while p[i]:
        out.append(p[i].decode())
        i += 1
    return out


def settings(size: int = 512, preset: str = "forearm", world_size_cm: Optional[float] = None,
             seed: int = 1, counts: Optional[Mapping[str, int]] = None,
             params: Optional[Mapping[str, float]] = None,
             base: Optional[Mapping[str, float]] = None, wrap: bool = True,
             sampler: str = "alias") -> L.ss_skin_settings:
    """The ss_skin_settings `skinsim skin` would use for these options,
    validated (numbers first in Python: size a whole number, values finite;
    then by the library)."""
    s = L.ss_skin_settings()
    L.check(L.lib.ss_skin_settings_preset, ctypes.byref(s), str(preset).encode(),
            L.as_int("size", size, lo=1))
    s.seed = L.as_u64("seed", seed)
    s.wrap = 1 if wrap else 0
    if sampler not in ("alias", "rejection"):
        raise L.InputError("sampler: %r is not alias or rejection" % (sampler,), L.SS_ERR_INPUT)
    s.sampler = 0 if sampler == "alias" else 1
    if world_size_cm is not None:
        s.world_size_cm = L.as_float("world_size_cm", world_size_cm, lo=0.0, lo_open=True)
        if preset == "forearm":  # counts follow the area, as on the command line
            L.lib.ss_skin_forearm_counts(s.world_size_cm, s.count)
    for name, n in (counts or {}).items():
        t = L.lib.ss_feature_type_from_name(str(name).encode())
        if t < 0:
            raise L.InputError("counts: unknown feature %r (%s)" % (name, ", ".join(FEATURE_TYPES)),
                               L.SS_ERR_INPUT)
        s.count[t] = L.as_int("counts[%s]" % name, n, lo=0, hi=2**62, c_max=2**63 - 1)
    for name, v in (params or {}).items():
        L.check(L.lib.ss_skin_dist_set, ctypes.byref(s.dist), str(name).encode(),
                L.as_float("params[%s]" % name, v))
    for name, v in (base or {}).items():
        if name not in BASE_NAMES:
            raise L.InputError("base: unknown parameter %r (%s)" % (name, ", ".join(BASE_NAMES)),
                               L.SS_ERR_INPUT)
        a = BASE_NAMES.index(name)
        s.base_lo[a] = L.as_float("base[%s]" % name, v, 0.0, s.base_hi[a])
    L.check(L.lib.ss_skin_settings_validate, ctypes.byref(s), rename=_RENAME)
    return s


_RENAME = {"size": "size", "param": "params", "count": "counts"}


def _features_dict(lst):
    n = lst.n
    out = {k: np.empty(n) for k in ("x", "y", "r", "r2", "h", "m", "p", "w")}
    types = np.empty(n, dtype=object)
    curves = np.zeros((n, 4, 2))
    for i in range(n):
        f = lst.f[i]
        types[i] = FEATURE_TYPES[f.type]
        for k in out:
            out[k][i] = getattr(f, k)
        curves[i, :, 0] = f.curve.x[:]
        curves[i, :, 1] = f.curve.y[:]
    out["type"] = types
    out["curve"] = curves
    return out


def textures(size: int = 512, preset: str = "forearm", world_size_cm: Optional[float] = None,
             seed: int = 1, counts: Optional[Mapping[str, int]] = None,
             params: Optional[Mapping[str, float]] = None,
             base: Optional[Mapping[str, float]] = None, wrap: bool = True,
             sampler: str = "alias", fields: Optional[Mapping[str, Any]] = None,
             table: Union[None, str, "optics.Table"] = None,
             normal_directx: bool = False, progress: L.ProgressArg = None) -> Dict[str, Any]:
    """Skin textures. fields: optional arrays by name -- a feature type
    ("moles", ...) for its probability field (h, w) 0..1, "lips" (h, w) lip
    weight, "vectors" (h, w, 3) wrinkle vector field. table: an
    optics.Table or a path (default: the shipped table, opened once per
    process: optics.default_table()). progress: True for a bar on stderr, or
    a callable(fraction 0..1) called between bands of texel rows; Ctrl-C (or
    an exception from the callable) stops the call at the next band, frees
    what it made and raises KeyboardInterrupt (or that exception)."""
    s = settings(size, preset, world_size_cm, seed, counts, params, base, wrap, sampler)
    fl = L.ss_skin_fields()
    keep = []
    for name, arr in (fields or {}).items():
        if name == "vectors":
            a = L.as_image_input(arr, "fields[vectors]", channels=(3,))
            hdr = L.image_header(a)
            fl.wrinkle_vectors = ctypes.pointer(hdr)
        else:
            a = L.as_image_input(arr, "fields[%s]" % name, channels=(1,))
            if a.ndim == 3:
                a = np.ascontiguousarray(a[..., 0])
            hdr = L.image_header(a)
            if name == "lips":
                fl.lips = ctypes.pointer(hdr)
            else:
                t = L.lib.ss_feature_type_from_name(str(name).encode())
                if t < 0:
                    raise L.InputError("fields: unknown field %r (%s, lips, vectors)"
                                       % (name, ", ".join(FEATURE_TYPES)), L.SS_ERR_INPUT)
                fl.density[t] = ctypes.pointer(hdr)
        keep.append((a, hdr))
    if table is None:
        table = optics.default_table()
    elif not isinstance(table, optics.Table):
        table = optics.Table(table)
    h = L.Handle()
    lst = L.ss_skin_feature_list()
    notes = ctypes.create_string_buffer(512)
    with L.Poll(progress, "skin") as poll:
        poll.call(L.lib.ss_skin_generate_poll, ctypes.byref(s), ctypes.byref(fl),
                  ctypes.byref(lst), notes, 512, poll.stage(0.0, 0.05), None)
        try:
            poll.raise_pending()  # Ctrl-C at the features' last poll
            features = _features_dict(lst)
            bio = poll.call(L.lib.ss_skin_bio_maps_poll, ctypes.byref(s), ctypes.byref(fl),
                            ctypes.byref(lst), poll.stage(0.05, 0.6), None, pointer=True)
        finally:
            L.lib.ss_skin_feature_list_free(ctypes.byref(lst))
        h.own(L.lib.ss_image_free, bio)
        poll.raise_pending()
        maps = L.ss_skin_maps()
        poll.call(L.lib.ss_skin_render_maps_poll, bio, table._skin_lut(), s.world_size_cm,
                  1 if normal_directx else 0, ctypes.byref(maps), poll.stage(0.6, 1.0), None)
        h.own(L.lib.ss_skin_maps_free, ctypes.pointer(maps))
        poll.raise_pending()
    out = {m: L.image_view(getattr(maps, m), h)
           for m in ("base_color", "roughness", "specular", "height_mm", "normal")}
    out["bio"] = L.image_view(bio, h)
    out["height_min_mm"] = maps.height_min_mm
    out["height_max_mm"] = maps.height_max_mm
    out["world_size_cm"] = s.world_size_cm
    out["features"] = features
    out["notes"] = notes.value.decode()
    return out
