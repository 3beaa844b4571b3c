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

import numpy as np

from . import _lib as L
from . import optics

if not L.HAVE_SKIN:
    raise ImportError("skinsim.skin: the loaded library %s has no skin module" % L.library_path)

FEATURE_TYPES = [L.lib.ss_feature_type_name(i).decode() for i in range(L.SS_FEAT_NTYPES)]
BIO_CHANNELS = [L.lib.ss_bio_channel_name(i).decode() for i in range(L.SS_BIO_NCHANNELS)]
BASE_NAMES = ["melanin", "pheomelanin", "blood", "oxygenation", "sc", "epidermis"]


def param_names():
    """Names of the distribution constants (`--param` of the CLI)."""
    p = L.lib.ss_skin_dist_names()
    out, i = [], 0
    while p[i]:
        out.append(p[i].decode())
        i += 1
    return out


def settings(size=512, preset="forearm", world_size_cm=None, seed=1, counts=None, params=None,
             base=None, wrap=True, sampler="alias"):
    """The ss_skin_settings `skinsim skin` would use for these options,
    validated by the library."""
    s = L.ss_skin_settings()
    L.check(L.lib.ss_skin_settings_preset, ctypes.byref(s), str(preset).encode(), int(size))
    s.seed = int(seed)
    s.wrap = 1 if wrap else 0
    if sampler not in ("alias", "rejection"):
        raise L.InputError("sampler: %r is not alias or rejection" % (sampler,), L.SS_ERR_INPUT)
    s.sampler = 0 if sampler == "alias" else 1
    if world_size_cm is not None:
        s.world_size_cm = float(world_size_cm)
        if preset == "forearm":  # counts follow the area, as on the command line
            L.lib.ss_skin_forearm_counts(s.world_size_cm, s.count)
    for name, n in (counts or {}).items():
        t = L.lib.ss_feature_type_from_name(str(name).encode())
        if t < 0:
            raise L.InputError("counts: unknown feature %r (%s)" % (name, ", ".join(FEATURE_TYPES)),
                               L.SS_ERR_INPUT)
        if int(n) < 0:
            raise L.InputError("counts: %s=%r must be >= 0" % (name, n), L.SS_ERR_INPUT)
        s.count[t] = int(n)
    for name, v in (params or {}).items():
        L.check(L.lib.ss_skin_dist_set, ctypes.byref(s.dist), str(name).encode(), float(v))
    for name, v in (base or {}).items():
        if name not in BASE_NAMES:
            raise L.InputError("base: unknown parameter %r (%s)" % (name, ", ".join(BASE_NAMES)),
                               L.SS_ERR_INPUT)
        a = BASE_NAMES.index(name)
        if not 0 <= float(v) <= s.base_hi[a]:
            raise L.InputError("base: %s=%r outside [0, %g]" % (name, v, s.base_hi[a]),
                               L.SS_ERR_INPUT)
        s.base_lo[a] = float(v)
    L.check(L.lib.ss_skin_settings_validate, ctypes.byref(s))
    return s


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


def textures(size=512, preset="forearm", world_size_cm=None, seed=1, counts=None, params=None,
             base=None, wrap=True, sampler="alias", fields=None, table=None,
             normal_directx=False):
    """Skin textures. fields: optional arrays by name -- a feature type
    ("moles", ...) for its probability field (h, w) 0..1, "lips" (h, w) lip
    weight, "vectors" (h, w, 3) wrinkle vector field. table: an
    optics.Table or a path (default: the shipped table)."""
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
    if table is None or not isinstance(table, optics.Table):
        table = optics.Table(table)
    h = L.Handle()
    lst = L.ss_skin_feature_list()
    notes = ctypes.create_string_buffer(512)
    L.check(L.lib.ss_skin_generate, ctypes.byref(s), ctypes.byref(fl), ctypes.byref(lst), notes,
            512)
    try:
        features = _features_dict(lst)
        bio = L.check_ptr(L.lib.ss_skin_bio_maps, ctypes.byref(s), ctypes.byref(fl),
                          ctypes.byref(lst))
    finally:
        L.lib.ss_skin_feature_list_free(ctypes.byref(lst))
    h.own(L.lib.ss_image_free, bio)
    lut = L.check_ptr(L.lib.ss_skin_lut_create, table._t)
    try:
        maps = L.ss_skin_maps()
        L.check(L.lib.ss_skin_render_maps, bio, lut, s.world_size_cm, 1 if normal_directx else 0,
                ctypes.byref(maps))
    finally:
        L.lib.ss_skin_lut_free(lut)
    h.own(L.lib.ss_skin_maps_free, ctypes.pointer(maps))
    out = {m: L.image_view(getattr(maps, m), h)
           for m in ("base_color", "roughness", "specular", "height_mm", "normal")}
    out["bio"] = L.image_view(bio, h)
    out["height_min_mm"] = maps.height_min_mm
    out["height_max_mm"] = maps.height_max_mm
    out["world_size_cm"] = s.world_size_cm
    out["features"] = features
    out["notes"] = notes.value.decode()
    return out
