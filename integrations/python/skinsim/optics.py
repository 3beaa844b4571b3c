"""Skin optics (seed 003): biological parameters -> reflectance spectrum,
colour, sampled BRDF, fitted render parameters, ModelMatch table lookups.

Biological parameters are keyword arguments everywhere, with the names and
units of ss_bio_params (include/skinsim/optics.h); unnamed ones keep the
library's default light skin:

    melanin                 epidermal melanosome volume fraction 0..1
    pheomelanin_ratio       pheomelanin / total melanin 0..1
    blood                   dermal blood volume fraction 0..1
    oxygenation             HbO2 / total haemoglobin 0..1
    sc_thickness_cm         stratum corneum thickness (cm)
    epidermis_thickness_cm  epidermis thickness (cm)
    bilirubin_g_per_l, betacarotene_g_per_l

The library validates them (NaN, negative, fraction > 1 -> InputError with
its message). Transport is Monte Carlo: `photons` and `seed` choose the
noise; results are bit-identical for the same seed at any thread count.
"""

import ctypes
import os

import numpy as np

from . import _lib as L

BIO_NAMES = [f[0] for f in L.ss_bio_params._fields_]
MODELS = {"ggx": 0, "ashikhmin-shirley": 1}
AXES = ["melanin", "pheomelanin_ratio", "blood", "oxygenation", "sc_thickness_cm",
        "epidermis_thickness_cm"]


def bio_params(**kw):
    """The default skin with the given parameters changed, as a dict."""
    p = L.ss_bio_params()
    L.lib.ss_bio_params_default(ctypes.byref(p))
    out = {k: getattr(p, k) for k in BIO_NAMES}
    for k, v in kw.items():
        if k not in out:
            raise TypeError("unknown biological parameter %r (known: %s)" % (k, ", ".join(BIO_NAMES)))
        out[k] = float(v)
    return out


def _bio(kw):
    b = bio_params(**kw)
    p = L.ss_bio_params(**b)
    L.check(L.lib.ss_bio_params_validate, ctypes.byref(p))
    return p


def _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm):
    o = L.ss_spectrum_options()
    L.lib.ss_spectrum_options_default(ctypes.byref(o))
    if photons is not None:
        if int(photons) < 1:
            raise L.InputError("photons: must be at least 1, got %r" % photons, L.SS_ERR_INPUT)
        o.mc.photons = int(photons)
    if seed is not None:
        o.mc.seed = int(seed)
    for name, val in (("wl_min_nm", wl_min_nm), ("wl_max_nm", wl_max_nm),
                      ("wl_step_nm", wl_step_nm)):
        if val is not None:
            setattr(o, name, float(val))
    return o


class Spectrum:
    """A diffuse reflectance spectrum (no surface specular, which is
    `specular`). Arrays are views of the library's result, not copies."""

    def __init__(self, res):
        self._res = res
        n = res.n
        self.wavelength_nm = L.double_view(res.wavelength_nm, n, self)
        self.reflectance = L.double_view(res.reflectance, n, self)
        self.std_error = L.double_view(res.std_error, n, self)
        self.specular = res.specular

    def __del__(self):
        if getattr(self, "_res", None) is not None and L.lib:
            L.lib.ss_reflectance_spectrum_free(ctypes.byref(self._res))
            self._res = None

    def colour(self):
        """Linear sRGB albedo under D65 (a white reflector gives 1, 1, 1)."""
        return colour(self.wavelength_nm, self.reflectance)

    def __repr__(self):
        return "Spectrum(%d wavelengths %g..%g nm, specular %.4f)" % (
            len(self.wavelength_nm), self.wavelength_nm[0], self.wavelength_nm[-1], self.specular)


def spectrum(photons=None, seed=None, wl_min_nm=None, wl_max_nm=None, wl_step_nm=None, **bio):
    """Diffuse reflectance spectrum of a skin by Monte Carlo transport
    (default 380..780 nm every 10 nm, 20,000 photons per wavelength)."""
    p = _bio(bio)
    o = _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm)
    res = L.ss_reflectance_spectrum()
    L.check(L.lib.ss_optics_reflectance_spectrum, ctypes.byref(p), ctypes.byref(o),
            ctypes.byref(res))
    return Spectrum(res)


def colour(wavelength_nm, reflectance):
    """Spectrum -> CIE 1931 XYZ under D65 -> linear sRGB albedo (3 floats).
    Any wavelength grid inside the CIE tables works; arrays are read in place
    when they are contiguous float64."""
    wl = np.ascontiguousarray(wavelength_nm, dtype=np.float64)
    r = np.ascontiguousarray(reflectance, dtype=np.float64)
    if wl.ndim != 1 or wl.shape != r.shape:
        raise L.InputError("colour: wavelength_nm and reflectance must be 1-D arrays of one "
                           "length, got shapes %s and %s" % (wl.shape, r.shape), L.SS_ERR_INPUT)
    rgb = (ctypes.c_double * 3)()
    L.check(L.lib.ss_spectrum_to_srgb_linear, wl.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            r.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(wl), rgb)
    return np.array(rgb[:])


def _rows3(name, a):
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.shape[-1:] != (3,):
        raise L.InputError("%s: want values (..., 3), got shape %s" % (name, a.shape),
                           L.SS_ERR_INPUT)
    return a


def lab(rgb):
    """Linear sRGB albedo (..., 3) -> CIELAB (D65 white), same shape."""
    a = _rows3("rgb", rgb)
    out = np.empty_like(a)
    P = ctypes.POINTER(ctypes.c_double)
    src, dst = a.reshape(-1, 3), out.reshape(-1, 3)
    for i in range(src.shape[0]):
        L.lib.ss_srgb_linear_to_lab(src[i].ctypes.data_as(P), dst[i].ctypes.data_as(P))
    return out


def describe_lab(lab_value):
    """(chroma C*ab, hue angle h_ab in degrees, individual typology angle ITA
    in degrees) of one CIELAB colour: ITA > 55 very light ... < -30 dark."""
    a = _rows3("lab", lab_value)
    if a.shape != (3,):
        raise L.InputError("lab: one colour (3 values), got shape %s" % (a.shape,),
                           L.SS_ERR_INPUT)
    c, h, ita = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
    L.lib.ss_lab_describe(a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), ctypes.byref(c),
                          ctypes.byref(h), ctypes.byref(ita))
    return c.value, h.value, ita.value


def ciede2000(lab1, lab2):
    """CIEDE2000 colour difference of two CIELAB colours."""
    a, b = _rows3("lab1", lab1), _rows3("lab2", lab2)
    if a.shape != (3,) or b.shape != (3,):
        raise L.InputError("ciede2000: two colours of 3 values each", L.SS_ERR_INPUT)
    P = ctypes.POINTER(ctypes.c_double)
    return L.lib.ss_ciede2000(a.ctypes.data_as(P), b.ctypes.data_as(P))


def srgb_encode(linear):
    """Linear values -> sRGB-encoded 0..1 (the library's table, float32)."""
    a = np.ascontiguousarray(np.clip(linear, 0.0, 1.0), dtype=np.float32)
    out = np.empty_like(a)
    P = ctypes.POINTER(ctypes.c_float)
    L.lib.ss_srgb_encode_array(a.ctypes.data_as(P), out.ctypes.data_as(P), a.size)
    return out


def _brdf_array(b, owner):
    n = b.n_theta_i * b.n_theta_r * b.n_phi * 3
    return L.double_view(b.f_rgb, n, owner, (b.n_theta_i, b.n_theta_r, b.n_phi, 3))


class _BRDFOwner:
    def __init__(self, b):
        self.b = b

    def __del__(self):
        if L.lib:
            L.lib.ss_brdf_sampled_free(ctypes.byref(self.b))


def brdf(n_theta_i=8, n_theta_r=8, n_phi=8, photons=None, seed=None, wl_min_nm=400.0,
         wl_max_nm=700.0, wl_step_nm=20.0, **bio):
    """Sampled BRDF of a skin per linear-sRGB channel, f_r in 1/sr, as an
    array [theta_i, theta_r, dphi, channel] (bin conventions in
    include/skinsim/optics.h). A view of the library's result."""
    p = _bio(bio)
    o = _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm)
    b = L.ss_brdf_sampled()
    L.check(L.lib.ss_optics_brdf_sample, ctypes.byref(p), ctypes.byref(o), int(n_theta_i),
            int(n_theta_r), int(n_phi), ctypes.byref(b))
    return _brdf_array(b, _BRDFOwner(b))


def render_brdf(model="ggx", base_rgb=(0.5, 0.5, 0.5), specular=0.5, roughness=0.5,
                n_theta_i=8, n_theta_r=8, n_phi=8, subsamples=3):
    """Sampled BRDF of a render model in the layout `brdf` returns (each
    exit bin averaged the way the photon tally does it): what `fit`
    compares against."""
    rp = L.ss_render_params((ctypes.c_double * 3)(*[float(c) for c in base_rgb]),
                            float(specular), float(roughness))
    b = L.ss_brdf_sampled()
    L.check(L.lib.ss_render_brdf_sample, _model_id(model), ctypes.byref(rp), int(n_theta_i),
            int(n_theta_r), int(n_phi), int(subsamples), ctypes.byref(b))
    return _brdf_array(b, _BRDFOwner(b))


def _params_dict(rp):
    return {"base_rgb": np.array(rp.base_rgb[:]), "specular": rp.specular,
            "roughness": rp.roughness}


def _model_id(model):
    if model not in MODELS:
        raise L.InputError("model: %r is not one of %s" % (model, ", ".join(MODELS)),
                           L.SS_ERR_INPUT)
    return MODELS[model]


def fit(brdf_rgb, model="ggx", weighting=None, max_theta_deg=None):
    """Least-squares fit of a render BRDF ("ggx": glTF metallic-roughness
    with metallic 0; "ashikhmin-shirley") to a sampled BRDF array
    [theta_i, theta_r, dphi, 3] (as `brdf` returns; read in place when it is
    C-contiguous float64). Returns base_rgb, specular, roughness and the
    residuals (docs/modelmatch.md)."""
    a = np.ascontiguousarray(brdf_rgb, dtype=np.float64)
    if a.ndim != 4 or a.shape[3] != 3 or min(a.shape) < 1:
        raise L.InputError("fit: want a BRDF array [theta_i, theta_r, dphi, 3], got shape %s"
                           % (a.shape,), L.SS_ERR_INPUT)
    if not np.all(np.isfinite(a)):
        raise L.InputError("fit: the BRDF array holds NaN or infinite values", L.SS_ERR_INPUT)
    b = L.ss_brdf_sampled(a.shape[0], a.shape[1], a.shape[2],
                          a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    fo = L.ss_fit_options()
    L.lib.ss_fit_options_default(ctypes.byref(fo))
    if weighting is not None:
        names = {"solid-angle": 0, "uniform": 1, "projected": 2}
        if weighting not in names:
            raise L.InputError("weighting: %r is not one of %s" % (weighting, ", ".join(names)),
                               L.SS_ERR_INPUT)
        fo.weighting = names[weighting]
    if max_theta_deg is not None:
        fo.max_theta_rad = np.radians(float(max_theta_deg))
    r = L.ss_fit_result()
    L.check(L.lib.ss_render_fit, _model_id(model), ctypes.byref(b), ctypes.byref(fo),
            ctypes.byref(r))
    out = _params_dict(r.params)
    out.update(model=model, residual_rel=r.residual_rel, residual_rms=r.residual_rms,
               evaluations=r.evaluations)
    return out


def _entry_dict(e):
    out = {}
    for name, m in MODELS.items():
        d = _params_dict(e.fit[m])
        d["residual_rel"] = e.residual_rel[m]
        out[name] = d
    out["sss_radius_cm"] = np.array(e.sss_radius_cm[:])
    out["albedo_rgb"] = np.array(e.albedo_rgb[:])
    return out


def match(photons=None, seed=None, n_theta_i=None, n_theta_r=None, n_phi=None, wl_step_nm=None,
          **bio):
    """ModelMatch for one skin (seed 003 §4.8.6): what a table entry holds,
    computed by transport (the table builder's fast path): both render
    models' fitted parameters, the subsurface radius per channel (cm) and
    the normal-incidence albedo."""
    p = _bio(bio)
    o = L.ss_mm_build_options()
    L.lib.ss_mm_build_options_default(ctypes.byref(o))
    if photons is not None:
        o.spectrum.mc.photons = int(photons)
    if seed is not None:
        o.spectrum.mc.seed = int(seed)
    for name, val in (("n_theta_i", n_theta_i), ("n_theta_r", n_theta_r), ("n_phi", n_phi)):
        if val is not None:
            setattr(o, name, int(val))
    if wl_step_nm is not None:
        o.spectrum.wl_step_nm = float(wl_step_nm)
    b = L.ss_brdf_sampled()
    e = L.ss_mm_entry()
    L.check(L.lib.ss_mm_sample_fast, ctypes.byref(p), ctypes.byref(o), ctypes.byref(b),
            e.sss_radius_cm, e.albedo_rgb)
    owner = _BRDFOwner(b)
    fo = o.fit
    for name, m in MODELS.items():
        r = L.ss_fit_result()
        L.check(L.lib.ss_render_fit, m, ctypes.byref(b), ctypes.byref(fo), ctypes.byref(r))
        e.fit[m] = r.params
        e.residual_rel[m] = r.residual_rel
    del owner
    return _entry_dict(e)


def default_table_path():
    return os.path.join(L.lib.ss_data_dir().decode(), "modelmatch_default.sstab")


class Table:
    """A ModelMatch table (render parameters over the six optical
    biological parameters, multilinear lookup). Table() opens the shipped
    default table; Table(path) any table `skinsim optics table` wrote."""

    def __init__(self, path=None):
        self.path = path or default_table_path()
        self._t = L.check_ptr(L.lib.ss_mm_table_read, os.fsencode(self.path))
        t = self._t.contents
        self.axes = {AXES[a]: L.double_view(t.axis[a], t.nsamples[a], self).copy()
                     for a in range(L.SS_MM_NAXES)}
        #: all entries [axis0, ..., axis5, field] as a read-only view
        self.entries = L.double_view(t.entries, t.nentries * L.SS_MM_NFIELDS, self,
                                     tuple(t.nsamples) + (L.SS_MM_NFIELDS,))
        self.entries.flags.writeable = False

    def __del__(self):
        if getattr(self, "_t", None) and L.lib:
            L.lib.ss_mm_table_free(self._t)
            self._t = None

    def lookup(self, **bio):
        """Render parameters for one skin (validated; outside the table's
        range each axis is clamped)."""
        p = _bio(bio)
        e = L.ss_mm_entry()
        L.check(L.lib.ss_mm_table_lookup_bio, self._t, ctypes.byref(p), ctypes.byref(e))
        return _entry_dict(e)

    def lookup_maps(self, **maps):
        """Per-pixel lookup: each axis parameter may be an array (all of one
        shape) or a scalar. Returns arrays base_rgb (..., 3), specular,
        roughness for the GGX model and albedo_rgb (..., 3)."""
        shape = None
        for k, v in maps.items():
            if k not in AXES:
                raise TypeError("lookup_maps: %r is not a table axis (%s)" % (k, ", ".join(AXES)))
            a = np.asarray(v, dtype=np.float64)
            if a.ndim:
                if shape is not None and a.shape != shape:
                    raise L.InputError("lookup_maps: %s has shape %s, others %s"
                                       % (k, a.shape, shape), L.SS_ERR_INPUT)
                shape = a.shape
            if not np.all(np.isfinite(a)):
                raise L.InputError("lookup_maps: %s holds NaN or infinite values" % k,
                                   L.SS_ERR_INPUT)
        shape = shape or ()
        base = bio_params()
        x = np.empty(shape + (L.SS_MM_NAXES,), dtype=np.float64)
        for a, name in enumerate(AXES):
            x[..., a] = maps.get(name, base[name])
        x = x.reshape(-1, L.SS_MM_NAXES)
        out = np.empty((x.shape[0], L.SS_MM_NFIELDS), dtype=np.float64)
        P = ctypes.POINTER(ctypes.c_double)
        xp, op = x.ctypes.data, out.ctypes.data
        step_x, step_o = 8 * L.SS_MM_NAXES, 8 * L.SS_MM_NFIELDS
        look = L.lib.ss_mm_table_lookup
        for i in range(x.shape[0]):
            look(self._t, ctypes.cast(xp + i * step_x, P), ctypes.cast(op + i * step_o, P))
        # entry layout (docs/modelmatch.md): per model base r g b, specular, roughness
        out = out.reshape(shape + (L.SS_MM_NFIELDS,))
        e = L.ss_mm_entry()
        L.lib.ss_mm_entry_unpack((ctypes.c_double * L.SS_MM_NFIELDS)(*range(L.SS_MM_NFIELDS)),
                                 ctypes.byref(e))
        ggx = e.fit[0]
        idx = lambda v: int(round(v))  # noqa: E731  field index of each unpacked value
        return {
            "base_rgb": out[..., [idx(c) for c in ggx.base_rgb]],
            "specular": out[..., idx(ggx.specular)],
            "roughness": out[..., idx(ggx.roughness)],
            "albedo_rgb": out[..., [idx(c) for c in e.albedo_rgb]],
        }
