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
import functools
import os
from typing import Any, Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _lib as L

#: the biological parameters, in ss_bio_params order
BIO_NAMES = [f[0] for f in L.ss_bio_params._fields_]
#: the render models `fit` and the table know, by name
MODELS = {"ggx": 0, "ashikhmin-shirley": 1}
#: the ModelMatch table's axes, in order
AXES = ["melanin", "pheomelanin_ratio", "blood", "oxygenation", "sc_thickness_cm",
        "epidermis_thickness_cm"]
#: the wavelengths (nm) the CIE 1931 observer and D65 tables cover; `colour`
#: integrates over them and refuses samples outside
CIE_RANGE_NM = (380.0, 780.0)

PathLike = Union[str, bytes, "os.PathLike[str]"]
Progress = L.ProgressArg


def bio_params(**kw: float) -> Dict[str, float]:
    """The default skin with the given parameters changed, as a dict
    (each value a finite number; InputError naming the parameter otherwise)."""
    p = L.ss_bio_params()
    L.lib.ss_bio_params_default(ctypes.byref(p))
    out = {k: getattr(p, k) for k in BIO_NAMES}
    for k, v in kw.items():
        if k not in out:
            raise TypeError("unknown biological parameter %r (known: %s)" % (k, ", ".join(BIO_NAMES)))
        out[k] = L.as_float(k, v)
    return out


def _bio(kw):
    b = bio_params(**kw)
    p = L.ss_bio_params(**b)
    L.check(L.lib.ss_bio_params_validate, ctypes.byref(p))
    return p


def _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm, poll=None):
    o = L.ss_spectrum_options()
    L.lib.ss_spectrum_options_default(ctypes.byref(o))
    if photons is not None:
        o.mc.photons = L.as_u64("photons", photons, lo=1)
    if seed is not None:
        o.mc.seed = L.as_u64("seed", seed)
    for name, val in (("wl_min_nm", wl_min_nm), ("wl_max_nm", wl_max_nm),
                      ("wl_step_nm", wl_step_nm)):
        if val is not None:
            setattr(o, name, L.as_float(name, val))
    if poll is not None:
        o.mc.cancel = poll.cancel
        o.progress = poll.fraction
    return o


class Spectrum:
    """A diffuse reflectance spectrum (no surface specular, which is
    `specular`). Arrays are views of the library's result, not copies; the
    result is freed when the Spectrum and every view of it are gone."""

    #: wavelengths (nm), a read-only-by-convention view
    wavelength_nm: np.ndarray
    #: diffuse reflectance per wavelength (0..1)
    reflectance: np.ndarray
    #: Monte Carlo standard error of each reflectance
    std_error: np.ndarray
    #: surface (Fresnel) reflectance, averaged over the wavelengths
    specular: float

    def __init__(self, res: L.ss_reflectance_spectrum) -> None:
        # the views hold the Handle, not this object: no reference cycle, so
        # the C result goes as soon as the last of them is dropped
        self._h = L.Handle()
        self._h.own(L.lib.ss_reflectance_spectrum_free, ctypes.pointer(res))
        n = res.n
        self.wavelength_nm = L.double_view(res.wavelength_nm, n, self._h)
        self.reflectance = L.double_view(res.reflectance, n, self._h)
        self.std_error = L.double_view(res.std_error, n, self._h)
        self.specular = res.specular

    def colour(self) -> np.ndarray:
        """Linear sRGB albedo under D65 (a white reflector gives 1, 1, 1)."""
        return colour(self.wavelength_nm, self.reflectance)

    def __repr__(self) -> str:
        return "Spectrum(%d wavelengths %g..%g nm, specular %.4f)" % (
            len(self.wavelength_nm), self.wavelength_nm[0], self.wavelength_nm[-1], self.specular)


def spectrum(photons: Optional[int] = None, seed: Optional[int] = None,
             wl_min_nm: Optional[float] = None, wl_max_nm: Optional[float] = None,
             wl_step_nm: Optional[float] = None, progress: Progress = None,
             **bio: float) -> Spectrum:
    """Diffuse reflectance spectrum of a skin by Monte Carlo transport
    (default 380..780 nm every 10 nm, 20,000 photons per wavelength).
    progress: True for a bar on stderr, or a callable(fraction 0..1) called
    after each wavelength. Ctrl-C stops the transport within a photon block
    and raises KeyboardInterrupt."""
    p = _bio(bio)
    with L.Poll(progress, "spectrum") as poll:
        o = _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm, poll)
        res = L.ss_reflectance_spectrum()
        poll.check(L.lib.ss_optics_reflectance_spectrum, ctypes.byref(p), ctypes.byref(o),
                   ctypes.byref(res))
    return Spectrum(res)


def colour(wavelength_nm: Any, reflectance: Any) -> np.ndarray:
    """Spectrum -> CIE 1931 XYZ under D65 -> linear sRGB albedo (3 floats).
    Any increasing wavelength grid inside the CIE tables (CIE_RANGE_NM,
    380..780 nm) works; a sample outside them raises InputError (the colour
    would be made up). Between the first and last samples reflectance is
    interpolated linearly, beyond them held constant. Arrays are read in
    place when they are contiguous float64."""
    wl = np.ascontiguousarray(wavelength_nm, dtype=np.float64)
    r = np.ascontiguousarray(reflectance, dtype=np.float64)
    if wl.ndim != 1 or wl.shape != r.shape:
        raise L.InputError("colour: wavelength_nm and reflectance must be 1-D arrays of one "
                           "length, got shapes %s and %s" % (wl.shape, r.shape), L.SS_ERR_INPUT)
    if wl.size and np.all(np.isfinite(wl)):
        lo, hi = CIE_RANGE_NM
        if wl.min() < lo or wl.max() > hi:
            raise L.InputError(
                "colour: wavelength_nm spans %g..%g nm, outside the CIE 1931 / D65 tables "
                "(%g..%g nm)" % (wl.min(), wl.max(), lo, hi), L.SS_ERR_INPUT)
    rgb = (ctypes.c_double * 3)()
    L.check(L.lib.ss_spectrum_to_srgb_linear, wl.ctypes.data_as(ctypes.POINTER(ctypes.c_double)),
            r.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(wl), rgb)
    return np.array(rgb[:])


def _rows3(name: str, a: Any) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.shape[-1:] != (3,):
        raise L.InputError("%s: want values (..., 3), got shape %s" % (name, a.shape),
                           L.SS_ERR_INPUT)
    return a


def lab(rgb: Any) -> np.ndarray:
    """Linear sRGB albedo (..., 3) -> CIELAB (D65 white), same shape."""
    a = _rows3("rgb", rgb)
    out = np.empty_like(a)
    P = ctypes.POINTER(ctypes.c_double)
    src, dst = a.reshape(-1, 3), out.reshape(-1, 3)
    for i in range(src.shape[0]):
        L.lib.ss_srgb_linear_to_lab(src[i].ctypes.data_as(P), dst[i].ctypes.data_as(P))
    return out


def describe_lab(lab_value: Any) -> Tuple[float, float, float]:
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


def ciede2000(lab1: Any, lab2: Any) -> float:
    """CIEDE2000 colour difference of two CIELAB colours."""
    a, b = _rows3("lab1", lab1), _rows3("lab2", lab2)
    if a.shape != (3,) or b.shape != (3,):
        raise L.InputError("ciede2000: two colours of 3 values each", L.SS_ERR_INPUT)
    P = ctypes.POINTER(ctypes.c_double)
    return L.lib.ss_ciede2000(a.ctypes.data_as(P), b.ctypes.data_as(P))


def srgb_encode(linear: Any) -> np.ndarray:
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
    """Frees a sampled BRDF when the last array view of it goes."""

    def __init__(self, b):
        self.b = b

    def __del__(self):
        if L.lib:
            L.lib.ss_brdf_sampled_free(ctypes.byref(self.b))


def _bins(name, v):
    return L.as_int(name, v, lo=1, hi=4096)


def brdf(n_theta_i: int = 8, n_theta_r: int = 8, n_phi: int = 8, photons: Optional[int] = None,
         seed: Optional[int] = None, wl_min_nm: float = 400.0, wl_max_nm: float = 700.0,
         wl_step_nm: float = 20.0, progress: Progress = None, **bio: float) -> np.ndarray:
    """Sampled BRDF of a skin per linear-sRGB channel, f_r in 1/sr, as an
    array [theta_i, theta_r, dphi, channel] (bin conventions in
    include/skinsim/optics.h). A view of the library's result. progress and
    Ctrl-C as in `spectrum`."""
    p = _bio(bio)
    ni, nr, nphi = _bins("n_theta_i", n_theta_i), _bins("n_theta_r", n_theta_r), \
        _bins("n_phi", n_phi)
    with L.Poll(progress, "brdf") as poll:
        o = _spectrum_options(photons, seed, wl_min_nm, wl_max_nm, wl_step_nm, poll)
        b = L.ss_brdf_sampled()
        poll.check(L.lib.ss_optics_brdf_sample, ctypes.byref(p), ctypes.byref(o), ni, nr, nphi,
                   ctypes.byref(b))
    return _brdf_array(b, _BRDFOwner(b))


def render_brdf(model: str = "ggx", base_rgb: Sequence[float] = (0.5, 0.5, 0.5),
                specular: float = 0.5, roughness: float = 0.5, n_theta_i: int = 8,
                n_theta_r: int = 8, n_phi: int = 8, subsamples: int = 3) -> np.ndarray:
    """Sampled BRDF of a render model in the layout `brdf` returns (each
    exit bin averaged the way the photon tally does it): what `fit`
    compares against."""
    rgb = [L.as_float("base_rgb", c) for c in base_rgb]
    if len(rgb) != 3:
        raise L.InputError("base_rgb: want 3 values, got %d" % len(rgb), L.SS_ERR_INPUT)
    rp = L.ss_render_params((ctypes.c_double * 3)(*rgb), L.as_float("specular", specular),
                            L.as_float("roughness", roughness))
    b = L.ss_brdf_sampled()
    L.check(L.lib.ss_render_brdf_sample, _model_id(model), ctypes.byref(rp),
            _bins("n_theta_i", n_theta_i), _bins("n_theta_r", n_theta_r), _bins("n_phi", n_phi),
            L.as_int("subsamples", subsamples, lo=1, hi=64), ctypes.byref(b))
    return _brdf_array(b, _BRDFOwner(b))


def _params_dict(rp):
    return {"base_rgb": np.array(rp.base_rgb[:]), "specular": rp.specular,
            "roughness": rp.roughness}


def _model_id(model):
    if model not in MODELS:
        raise L.InputError("model: %r is not one of %s" % (model, ", ".join(MODELS)),
                           L.SS_ERR_INPUT)
    return MODELS[model]


def fit(brdf_rgb: Any, model: str = "ggx", weighting: Optional[str] = None,
        max_theta_deg: Optional[float] = None) -> Dict[str, Any]:
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
        fo.max_theta_rad = np.radians(L.as_float("max_theta_deg", max_theta_deg, 0.0, 90.0))
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


def match(photons: Optional[int] = None, seed: Optional[int] = None,
          n_theta_i: Optional[int] = None, n_theta_r: Optional[int] = None,
          n_phi: Optional[int] = None, wl_step_nm: Optional[float] = None,
          progress: Progress = None, **bio: float) -> Dict[str, Any]:
    """ModelMatch for one skin (seed 003 §4.8.6): what a table entry holds,
    computed by transport (the table builder's fast path): both render
    models' fitted parameters, the subsurface radius per channel (cm) and
    the normal-incidence albedo. progress and Ctrl-C as in `spectrum`."""
    p = _bio(bio)
    o = L.ss_mm_build_options()
    L.lib.ss_mm_build_options_default(ctypes.byref(o))
    if photons is not None:
        o.spectrum.mc.photons = L.as_u64("photons", photons, lo=1)
    if seed is not None:
        o.spectrum.mc.seed = L.as_u64("seed", seed)
    for name, val in (("n_theta_i", n_theta_i), ("n_theta_r", n_theta_r), ("n_phi", n_phi)):
        if val is not None:
            setattr(o, name, _bins(name, val))
    if wl_step_nm is not None:
        o.spectrum.wl_step_nm = L.as_float("wl_step_nm", wl_step_nm)
    b = L.ss_brdf_sampled()
    e = L.ss_mm_entry()
    with L.Poll(progress, "match") as poll:
        o.spectrum.mc.cancel = poll.cancel
        o.spectrum.progress = poll.fraction
        poll.check(L.lib.ss_mm_sample_fast, ctypes.byref(p), ctypes.byref(o), ctypes.byref(b),
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


def default_table_path() -> str:
    """Path of the shipped default ModelMatch table (in data_dir())."""
    return os.path.join(L.lib.ss_data_dir().decode(), "modelmatch_default.sstab")


class Table:
    """A ModelMatch table (render parameters over the six optical
    biological parameters, multilinear lookup). Table() opens the shipped
    default table (default_table() shares one open copy); Table(path) any
    table `skinsim optics table` wrote. Freed when the Table and every view
    of its entries are gone."""

    #: the file it was read from
    path: str
    #: sample positions per axis (name -> array, copies)
    axes: Dict[str, np.ndarray]
    #: all entries [axis0, ..., axis5, field], a read-only view
    entries: np.ndarray

    def __init__(self, path: Optional[PathLike] = None) -> None:
        self.path = os.fsdecode(os.fspath(path)) if path is not None else default_table_path()
        # the C table belongs to a Handle that the views reference, not to
        # this object, so dropping the Table frees it (no reference cycle)
        self._h = L.Handle()
        self._t = self._h.own(L.lib.ss_mm_table_free,
                              L.check_ptr(L.lib.ss_mm_table_read, os.fsencode(self.path)))
        self._lut = None
        t = self._t.contents
        self.axes = {AXES[a]: L.double_view(t.axis[a], t.nsamples[a], self._h).copy()
                     for a in range(L.SS_MM_NAXES)}
        self.entries = L.double_view(t.entries, t.nentries * L.SS_MM_NFIELDS, self._h,
                                     tuple(t.nsamples) + (L.SS_MM_NFIELDS,))
        self.entries.flags.writeable = False

    def _skin_lut(self) -> int:
        """The skin module's lookup structure for this table (made once)."""
        if self._lut is None:
            self._lut = self._h.own(L.lib.ss_skin_lut_free,
                                    L.check_ptr(L.lib.ss_skin_lut_create, self._t))
        return self._lut

    def lookup(self, **bio: float) -> Dict[str, Any]:
        """Render parameters for one skin (validated; outside the table's
        range each axis is clamped)."""
        p = _bio(bio)
        e = L.ss_mm_entry()
        L.check(L.lib.ss_mm_table_lookup_bio, self._t, ctypes.byref(p), ctypes.byref(e))
        return _entry_dict(e)

    def lookup_maps(self, **maps: Any) -> Dict[str, np.ndarray]:
        """Per-pixel lookup: each axis parameter may be an array (all of one
        shape) or a scalar; the others keep the default skin. Returns arrays
        base_rgb (..., 3), specular, roughness for the GGX model and
        albedo_rgb (..., 3). One library call over all pixels (in parallel);
        each pixel equals `lookup` of its values, clamped to the table."""
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
        L.lib.ss_mm_table_lookup_many(self._t, x.ctypes.data_as(P), x.shape[0],
                                      out.ctypes.data_as(P))
        # entry layout (docs/modelmatch.md): per model base r g b, specular, roughness
        out = out.reshape(shape + (L.SS_MM_NFIELDS,))
        ggx, albedo = _FIELDS
        return {
            "base_rgb": out[..., list(ggx[0])],
            "specular": out[..., ggx[1]],
            "roughness": out[..., ggx[2]],
            "albedo_rgb": out[..., list(albedo)],
        }

    def __repr__(self) -> str:
        return "Table(%r, %d entries)" % (self.path, self.entries.size // L.SS_MM_NFIELDS)


def _field_indices():
    # where each unpacked value sits in a packed entry: unpack 0, 1, 2, ...
    e = L.ss_mm_entry()
    L.lib.ss_mm_entry_unpack((ctypes.c_double * L.SS_MM_NFIELDS)(*range(L.SS_MM_NFIELDS)),
                             ctypes.byref(e))
    g = e.fit[0]
    idx = lambda v: int(round(v))  # noqa: E731
    return ((tuple(idx(c) for c in g.base_rgb), idx(g.specular), idx(g.roughness)),
            tuple(idx(c) for c in e.albedo_rgb))


_FIELDS = _field_indices()


@functools.lru_cache(maxsize=None)
def _default_table(path: str) -> Table:
    return Table(path)


def default_table() -> Table:
    """The shipped default table, opened once per process and shared (what
    skin.textures() and wound.Textures use without table=)."""
    return _default_table(default_table_path())


# ---- any layer stack (ss_mc_run) -----------------------------------------------

_LAYER_KEYS = ("n", "mua_per_cm", "mus_per_cm", "g", "d_cm")
_RADIAL = {"net": 0, "path": 1}


def run_layers(layers: Iterable[Union[Mapping[str, float], Sequence[float]]],
               photons: int = 100000, seed: int = 1, n_above: float = 1.0,
               n_below: float = 1.0, bottom_albedo: Optional[float] = None,
               theta_i_deg: float = 0.0, roughness: float = 0.0,
               stochastic_absorb: bool = False, brdf_bins: Optional[Tuple[int, int]] = None,
               radial_bins: int = 0, radial_max_cm: float = 0.0,
               radial_distance: str = "net") -> Dict[str, Any]:
    """Monte Carlo photon transport through any stack of layers (ss_mc_run,
    MCML-style packets; lengths in cm, coefficients in 1/cm).

    layers: top first, each a mapping with n, mua_per_cm, mus_per_cm, g,
    d_cm (or a 5-sequence in that order), at most 16. Below the last layer
    the light leaves into n_below (as MCML), or with bottom_albedo >= 0 a
    Lambertian reflector sends it back. theta_i_deg: incidence; roughness:
    Trowbridge-Reitz sigma of the top surface (0 smooth). brdf_bins=(n_theta,
    n_phi) tallies the exit BRDF, radial_bins/radial_max_cm the radial
    profile Rd(r) ("net" entry-exit distance or the "path" projection).

    Returns specular, diffuse, transmit, absorbed (fractions of the incident
    weight), diffuse_se, transmit_se, roulette_net, absorbed_per_layer
    (array), and brdf_exit [theta_r, dphi] (1/sr) and radial (1/cm^2 per
    bin) with radial_dr_cm when asked for. Bit-identical for the same seed
    at any thread count; Ctrl-C stops it within a photon block
    (KeyboardInterrupt)."""
    slab = L.ss_optics_slab()
    rows = list(layers)
    if not 1 <= len(rows) <= L.SS_OPTICS_MAX_LAYERS:
        raise L.InputError("layers: want 1..%d layers, got %d"
                           % (L.SS_OPTICS_MAX_LAYERS, len(rows)), L.SS_ERR_INPUT)
    slab.nlayers = len(rows)
    for i, row in enumerate(rows):
        if isinstance(row, Mapping):
            unknown = set(row) - set(_LAYER_KEYS)
            missing = [k for k in _LAYER_KEYS if k not in row]
            if unknown or missing:
                raise L.InputError("layers[%d]: want keys %s (missing %s, unknown %s)"
                                   % (i, ", ".join(_LAYER_KEYS), missing or "none",
                                      sorted(unknown) or "none"), L.SS_ERR_INPUT)
            vals = [row[k] for k in _LAYER_KEYS]
        else:
            vals = list(row)
            if len(vals) != 5:
                raise L.InputError("layers[%d]: want 5 values (%s), got %d"
                                   % (i, ", ".join(_LAYER_KEYS), len(vals)), L.SS_ERR_INPUT)
        lay = slab.layer[i]
        for k, v in zip(_LAYER_KEYS, vals):
            setattr(lay, k, L.as_float("layers[%d].%s" % (i, k), v))
    slab.n_above = L.as_float("n_above", n_above, lo=1.0)
    slab.n_below = L.as_float("n_below", n_below, lo=1.0)
    slab.bottom_albedo = -1.0 if bottom_albedo is None else L.as_float(
        "bottom_albedo", bottom_albedo, 0.0, 1.0)
    L.check(L.lib.ss_optics_slab_validate, ctypes.byref(slab))
    o = L.ss_mc_options()
    L.lib.ss_mc_options_default(ctypes.byref(o))
    o.photons = L.as_u64("photons", photons, lo=1)
    o.seed = L.as_u64("seed", seed)
    o.theta_i_rad = np.radians(L.as_float("theta_i_deg", theta_i_deg, 0.0, 89.999))
    o.roughness_sigma = L.as_float("roughness", roughness, 0.0)
    o.stochastic_absorb = 1 if stochastic_absorb else 0
    if brdf_bins is not None:
        nt, nphi = brdf_bins
        o.brdf_n_theta, o.brdf_n_phi = _bins("brdf_bins[0]", nt), _bins("brdf_bins[1]", nphi)
    o.radial_bins = L.as_int("radial_bins", radial_bins, lo=0, hi=1 << 20)
    o.radial_max_cm = L.as_float("radial_max_cm", radial_max_cm, 0.0)
    if (o.radial_bins > 0) != (o.radial_max_cm > 0):
        raise L.InputError("radial_bins and radial_max_cm: give both (> 0) or neither",
                           L.SS_ERR_INPUT)
    if radial_distance not in _RADIAL:
        raise L.InputError("radial_distance: %r is not net or path" % (radial_distance,),
                           L.SS_ERR_INPUT)
    o.radial_distance = _RADIAL[radial_distance]
    r = L.ss_mc_result()
    with L.Poll(None, "transport") as poll:
        o.cancel = poll.cancel
        poll.check(L.lib.ss_mc_run, ctypes.byref(slab), ctypes.byref(o), ctypes.byref(r))
    try:
        out: Dict[str, Any] = {k: getattr(r, k) for k in (
            "specular", "diffuse", "transmit", "absorbed", "diffuse_se", "transmit_se",
            "roulette_net")}
        out["absorbed_per_layer"] = np.array(r.absorbed_per_layer[:r.nlayers])
        if r.brdf_exit:
            out["brdf_exit"] = np.array(r.brdf_exit[:r.brdf_n_theta * r.brdf_n_phi]).reshape(
                r.brdf_n_theta, r.brdf_n_phi)
        if r.radial:
            out["radial"] = np.array(r.radial[:r.radial_bins])
            out["radial_dr_cm"] = r.radial_dr_cm
        return out
    finally:
        L.lib.ss_mc_result_free(ctypes.byref(r))
