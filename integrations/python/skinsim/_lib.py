"""Loading libskinsim and the C declarations the package uses (ctypes).

Design: the package is a thin layer over the shared library. Every struct
the bindings touch is declared here once, field by field as in
include/skinsim/*.h; tests/test_layout.py compares sizes and offsets with
what the C compiler says (integrations/python/tests/abi_layout.c), so a
header change that is not mirrored here fails a test instead of corrupting
memory. Every library call goes through `check`, which turns a non-zero
ss_status into a Python exception carrying the library's own message.

Arrays cross the boundary without copies where the layout allows: results
the library allocates are wrapped as numpy views that keep their owner (and
so the C memory) alive; images the caller passes or receives are numpy
float32 arrays whose buffers the library reads or writes directly through an
ss_image header that points into them.

Which library: $SKINSIM_LIB (a path) if set; else the one bundled into the
package by `pip install .` (_native/lib/libskinsim.so.0, with its data in
_native/share/skinsim); else the one an installed copy
of this package was installed with (_installed.py, written by cmake
--install); else build/libskinsim.so.0 of the source tree this file is in;
else the system's (ldconfig).
"""

import ctypes
import ctypes.util
import math
import numbers
import os
import re
import signal
import sys
import threading
from typing import Any, Callable, Dict, Optional, Union

import numpy as np

c_int = ctypes.c_int
c_double = ctypes.c_double
c_float = ctypes.c_float
c_uint64 = ctypes.c_uint64
c_size_t = ctypes.c_size_t
c_char_p = ctypes.c_char_p
c_void_p = ctypes.c_void_p
POINTER = ctypes.POINTER
byref = ctypes.byref


def _candidates():
    env = os.environ.get("SKINSIM_LIB")
    if env:
        return [env]
    out = []
    here = os.path.dirname(os.path.abspath(__file__))
    bundled = os.path.join(here, "_native", "lib", "libskinsim.so.0")
    if os.path.isfile(bundled):
        out.append(bundled)
    try:
        from . import _installed  # written by cmake --install

        out.append(os.path.normpath(_installed.LIBRARY))
    except ImportError:
        pass
    src = os.path.normpath(os.path.join(here, "..", "..", ".."))
    out.append(os.path.join(src, "build", "libskinsim.so.0"))
    found = ctypes.util.find_library("skinsim")
    out.append(found or "libskinsim.so.0")
    return out


def _load():
    tried = []
    for path in _candidates():
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError(
        "skinsim: cannot load libskinsim; set SKINSIM_LIB to the library's path. Tried: "
        + "; ".join(tried)
    )


lib, library_path = _load()

# ---- errors ------------------------------------------------------------------

SS_OK, SS_ERR_RUNTIME, SS_ERR_INPUT, SS_ERR_NOMEM = 0, 1, 2, 3


class ss_error(ctypes.Structure):
    _fields_ = [("code", c_int), ("msg", ctypes.c_char * 1024)]


class SkinsimError(Exception):
    """A failure reported by libskinsim; `code` is the library's ss_status
    (1 runtime, 2 input, 3 memory) and the text is the library's message."""

    def __init__(self, message, code=SS_ERR_RUNTIME):
        super().__init__(message)
        self.code = code


class InputError(SkinsimError, ValueError):
    """Bad argument, malformed or missing file, bad value (ss_status 2: the
    command-line tool exits 2 for these)."""


class OutOfMemoryError(SkinsimError, MemoryError):
    """The library could not allocate what the job needs."""


def raise_for(code, message):
    if code == SS_ERR_INPUT:
        raise InputError(message, code)
    if code == SS_ERR_NOMEM:
        raise OutOfMemoryError(message, code)
    raise SkinsimError(message, code)


def check(fn, *args, rename=None):
    """Calls fn(*args, &err) and raises on a non-zero status, with the
    library's message in Python terms (python_terms)."""
    err = ss_error()
    st = fn(*args, byref(err))
    if st != SS_OK:
        raise_for(st, python_terms(err.msg.decode("utf-8", "replace"), rename))
    return st


def check_ptr(fn, *args, rename=None):
    """Calls fn(*args, &err) for a function returning a pointer; raises when NULL."""
    err = ss_error()
    p = fn(*args, byref(err))
    if not p:
        raise_for(err.code or SS_ERR_RUNTIME,
                  python_terms(err.msg.decode("utf-8", "replace"), rename))
    return p


# ---- Python values -> C values, checked before conversion --------------------
#
# ctypes wraps a too-large int and truncates a float without a word (size
# 2**40 -> 0, 3.7 -> 3), so every number a caller passes goes through one of
# these first: the error names the Python parameter and says what was wrong.

INT_MIN, INT_MAX = -(2**31), 2**31 - 1
U64_MAX = 2**64 - 1


def _bad(name, what, v):
    raise InputError("%s: %s, got %r" % (name, what, v), SS_ERR_INPUT)


def as_int(name: str, v: Any, lo: Optional[int] = None, hi: Optional[int] = None,
           c_max: int = INT_MAX) -> int:
    """v as a whole number in [lo, hi] (and in the C type's range): an
    integral float such as 4.0 is accepted, 3.7, NaN, a string or a bool
    are not (TypeError for non-numbers, InputError otherwise)."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        raise TypeError("%s: want a whole number, got %r" % (name, v))
    if isinstance(v, numbers.Integral):
        n = int(v)
    else:
        f = float(v)
        if not math.isfinite(f) or not f.is_integer():
            _bad(name, "want a whole number", v)
        n = int(f)
    lo = (INT_MIN if c_max == INT_MAX else 0) if lo is None else lo
    hi = c_max if hi is None else min(hi, c_max)
    if not lo <= n <= hi:
        raise InputError("%s: %d is outside %d..%d" % (name, n, lo, hi), SS_ERR_INPUT)
    return n


def as_u64(name: str, v: Any, lo: int = 0) -> int:
    """v as a whole number for a uint64_t (seeds, photon counts)."""
    return as_int(name, v, lo, U64_MAX, c_max=U64_MAX)


def as_float(name: str, v: Any, lo: Optional[float] = None, hi: Optional[float] = None,
             lo_open: bool = False) -> float:
    """v as a finite float in [lo, hi] ((lo, hi] with lo_open): NaN and
    infinities are refused (InputError), non-numbers are a TypeError."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        raise TypeError("%s: want a number, got %r" % (name, v))
    f = float(v)
    if not math.isfinite(f):
        _bad(name, "want a finite number", v)
    if lo is not None and (f <= lo if lo_open else f < lo):
        _bad(name, "want a value %s %g" % (">" if lo_open else ">=", lo), v)
    if hi is not None and f > hi:
        _bad(name, "want a value <= %g" % hi, v)
    return f


def python_terms(message: str, rename: Optional[Dict[str, str]] = None) -> str:
    """A library message in Python terms: command-line options become the
    keyword arguments they correspond to ("--days -1: need ..." ->
    "days=-1: need ...", "--mesh" -> "skin_mesh" with rename)."""
    rename = rename or {}

    def name(opt):
        return rename.get(opt, opt.replace("-", "_"))

    message = re.sub(r"--([a-z][a-z0-9-]*) ([^\s:]+):",
                     lambda m: "%s=%s:" % (name(m.group(1)), m.group(2)), message)
    return re.sub(r"--([a-z][a-z0-9-]*)", lambda m: name(m.group(1)), message)


# ---- long calls: progress, and Ctrl-C between blocks of work ---------------------
#
# A long call (Monte Carlo transport, a heal run's steps) runs inside the C
# library, where Python cannot deliver KeyboardInterrupt. The library polls a
# callback from the calling thread (ss_mc_options.cancel after each photon
# block, ss_heal_run_set_progress after each step, the spectrum progress after
# each wavelength, the ss_progress_fn of the *_poll calls -- skin maps,
# abrasion frames, wound renders -- between bands of rows). While such a call runs on the main thread, SIGINT only
# sets a flag (a Python handler that does not raise, so it cannot fire in the
# middle of a callback); the next poll sees it and tells the library to stop,
# and the call raises KeyboardInterrupt once the library has cleaned up.

PROGRESS_FN = ctypes.CFUNCTYPE(None, c_void_p, c_double)
CANCEL_FN = ctypes.CFUNCTYPE(c_int, c_void_p)
DAY_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_double)
PROGRESS_POLL_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_double)  # core.h ss_progress_fn
_check_signals = ctypes.pythonapi.PyErr_CheckSignals
_check_signals.restype = c_int
_check_signals.argtypes = []

ProgressArg = Union[None, bool, Callable[[float], Any]]


class ProgressBar:
    """A text progress bar on stderr: what progress=True draws."""

    def __init__(self, label: str = "skinsim", stream: Any = None) -> None:
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self._last = -1

    def __call__(self, fraction: float) -> None:
        pct = int(max(0.0, min(1.0, fraction)) * 100)
        if pct == self._last:
            return
        self._last = pct
        bar = "#" * (pct // 4) + "." * (25 - pct // 4)
        self.stream.write("\r%s [%s] %3d%%%s" % (self.label, bar, pct, "\n" if pct == 100 else ""))
        self.stream.flush()


def progress_callable(progress: ProgressArg, label: str) -> Optional[Callable[[float], Any]]:
    """None/False: none; True: a ProgressBar; else a callable(fraction 0..1)."""
    if progress is None or progress is False:
        return None
    if progress is True:
        return ProgressBar(label)
    if not callable(progress):
        raise TypeError("progress: want None, True or a callable(fraction), got %r" % (progress,))
    return progress


class Poll:
    """The callbacks one long library call polls, and what they saw: use as
    `with Poll(progress) as p: p.check(fn, ...)`. A KeyboardInterrupt (or an
    exception from the progress callable) stops the library at its next poll
    and is raised when the call returns."""

    def __init__(self, progress: ProgressArg = None, label: str = "skinsim",
                 span: Optional[tuple] = None) -> None:
        self.progress = progress_callable(progress, label)
        self.span = span  # (first, last) day for the heal callback's fraction
        self.error: Optional[BaseException] = None
        self.interrupted = False
        self._prev = None
        self.cancel = CANCEL_FN(self._cancel)
        self.fraction = PROGRESS_FN(self._fraction)
        self.day = DAY_FN(self._day)
        self._stages: list = []

    def __enter__(self) -> "Poll":
        if threading.current_thread() is threading.main_thread():
            try:
                if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
                    self._prev = signal.signal(signal.SIGINT, self._on_sigint)
            except (ValueError, OSError):
                self._prev = None
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._prev is not None:
            signal.signal(signal.SIGINT, self._prev)
            self._prev = None

    def _on_sigint(self, signum: int, frame: Any) -> None:
        self.interrupted = True

    def _stop(self) -> int:
        try:
            _check_signals()  # runs the SIGINT handler above if a signal is pending
        except BaseException as e:  # another handler raised: stop and re-raise it later
            if self.error is None:
                self.error = e
        return 1 if (self.interrupted or self.error is not None) else 0

    def _report(self, fraction: float) -> None:
        if self.progress is not None and self.error is None:
            try:
                self.progress(fraction)
            except BaseException as e:
                self.error = e

    def _cancel(self, user: Any) -> int:
        try:
            return self._stop()
        except BaseException:
            return 1

    def _fraction(self, user: Any, fraction: float) -> None:
        try:
            self._report(fraction)
        except BaseException:
            pass

    def _day(self, user: Any, day: float) -> int:
        try:
            if self.span is not None:
                a, b = self.span
                self._report(1.0 if b <= a else (day - a) / (b - a))
            return self._stop()
        except BaseException:
            return 1

    def stage(self, lo: float = 0.0, hi: float = 1.0) -> Any:
        """An ss_progress_fn for one stage of the call: the library's
        fraction 0..1 is reported as lo..hi of the whole, and a pending
        Ctrl-C (or an exception of the progress callable) stops it. The Poll
        keeps the callback alive."""

        def fn(user: Any, fraction: float) -> int:
            try:
                self._report(lo + (hi - lo) * fraction)
                return self._stop()
            except BaseException:
                return 1

        cb = PROGRESS_POLL_FN(fn)
        self._stages.append(cb)
        return cb

    def raise_pending(self) -> None:
        """Raises what stopped the call (KeyboardInterrupt on Ctrl-C)."""
        if self.error is not None:
            e, self.error = self.error, None
            raise e
        if self.interrupted:
            self.interrupted = False
            raise KeyboardInterrupt

    def check(self, fn: Any, *args: Any, rename: Optional[Dict[str, str]] = None) -> int:
        """check(fn, *args) that raises KeyboardInterrupt (or the progress
        callable's exception) instead of the library's "cancelled"."""
        try:
            st = check(fn, *args, rename=rename)
        except SkinsimError:
            self.raise_pending()
            raise
        self.raise_pending()
        return st

    def call(self, fn: Any, *args: Any, pointer: bool = False,
             rename: Optional[Dict[str, str]] = None) -> Any:
        """check(fn, *args) (check_ptr with pointer=True) that raises as
        `check` does when the call fails, but on success returns even if a
        Ctrl-C came in at the call's last poll: the caller first takes
        ownership of what the call made, then calls raise_pending()."""
        try:
            return (check_ptr if pointer else check)(fn, *args, rename=rename)
        except SkinsimError:
            self.raise_pending()
            raise


class Handle:
    """Owns library objects: calls each free function on its pointer when the
    last reference goes. Python objects hold a Handle and the numpy views of
    library memory reference it too, so memory is never freed under a view
    (closing an object only drops its own reference)."""

    def __init__(self):
        self._frees = []

    def own(self, free_fn, ptr):
        self._frees.append((free_fn, ptr))
        return ptr

    def __del__(self):
        while self._frees and lib:
            fn, ptr = self._frees.pop()
            fn(ptr)


def _fn(name, restype, *argtypes):
    f = getattr(lib, name)
    f.restype = restype
    f.argtypes = list(argtypes)
    return f


# ---- core: images --------------------------------------------------------------


class ss_image(ctypes.Structure):
    _fields_ = [
        ("width", c_int),
        ("height", c_int),
        ("channels", c_int),
        ("data", POINTER(c_float)),
    ]


P_IMAGE = POINTER(ss_image)


def image_header(arr):
    """An ss_image that points into the float32 C-contiguous array arr of
    shape (h, w) or (h, w, c). The caller keeps arr alive while it is used."""
    if arr.dtype != np.float32 or not arr.flags.c_contiguous:
        raise TypeError("image arrays must be C-contiguous float32")
    if arr.ndim == 2:
        h, w, c = arr.shape[0], arr.shape[1], 1
    elif arr.ndim == 3:
        h, w, c = arr.shape
    else:
        raise ValueError("an image is a (height, width) or (height, width, channels) array")
    img = ss_image(w, h, c, arr.ctypes.data_as(POINTER(c_float)))
    img._keep = arr
    return img


def set_out_image(struct, field, arr, shape, what, keep):
    """Points struct.field (an ss_image *) at the caller's output array arr,
    which must be C-contiguous float32 of the given shape; keep collects the
    headers, which must live until the call that writes through them."""
    if (not isinstance(arr, np.ndarray) or arr.shape != tuple(shape)
            or arr.dtype != np.float32 or not arr.flags.c_contiguous):
        raise InputError("%s must be C-contiguous float32 of shape %s" % (what, tuple(shape)),
                         SS_ERR_INPUT)
    h = image_header(arr)
    keep.append(h)
    setattr(struct, field, ctypes.pointer(h))


def as_image_input(arr, name, channels=None):
    """Validates and converts an image argument to C-contiguous float32
    (copied only when its dtype or layout requires it)."""
    a = np.asarray(arr)
    if a.ndim not in (2, 3) or a.shape[0] < 1 or a.shape[1] < 1:
        raise InputError("%s: want an image array (height, width[, channels]), got shape %s"
                         % (name, a.shape), SS_ERR_INPUT)
    if a.ndim == 3 and not 1 <= a.shape[2] <= 4:
        raise InputError("%s: 1 to 4 channels, got %d" % (name, a.shape[2]), SS_ERR_INPUT)
    if channels is not None and (a.shape[2] if a.ndim == 3 else 1) not in channels:
        raise InputError("%s: want %s channel(s), got %d" % (
            name, " or ".join(str(c) for c in channels), a.shape[2] if a.ndim == 3 else 1),
            SS_ERR_INPUT)
    a = np.ascontiguousarray(a, dtype=np.float32)
    if not np.all(np.isfinite(a)):
        raise InputError("%s: contains NaN or infinite values" % name, SS_ERR_INPUT)
    return a


def image_view(p_img, owner):
    """A numpy view (h, w) or (h, w, c) of a library-owned ss_image*; the view
    keeps owner alive."""
    img = p_img.contents
    n = img.width * img.height * img.channels
    buf = (c_float * n).from_address(ctypes.addressof(img.data.contents))
    buf._owner = owner
    a = np.frombuffer(buf, dtype=np.float32)
    if img.channels == 1:
        return a.reshape(img.height, img.width)
    return a.reshape(img.height, img.width, img.channels)


def double_view(ptr, n, owner, shape=None):
    """A numpy float64 view of n doubles the library allocated."""
    if n == 0:
        return np.zeros(0 if shape is None else shape)
    buf = (c_double * n).from_address(ctypes.cast(ptr, c_void_p).value)
    buf._owner = owner
    a = np.frombuffer(buf, dtype=np.float64)
    return a if shape is None else a.reshape(shape)


def float_view(ptr, n, owner, shape=None):
    buf = (c_float * n).from_address(ctypes.cast(ptr, c_void_p).value)
    buf._owner = owner
    a = np.frombuffer(buf, dtype=np.float32)
    return a if shape is None else a.reshape(shape)


_fn("ss_image_create", P_IMAGE, c_int, c_int, c_int, POINTER(ss_error))
_fn("ss_image_free", None, P_IMAGE)
_fn("ss_png_write", c_int, c_char_p, P_IMAGE, c_int, c_int, POINTER(ss_error))
_fn("ss_image_read", P_IMAGE, c_char_p, c_int, POINTER(ss_error))
_fn("ss_version", c_char_p)
_fn("ss_data_dir", c_char_p)
_fn("ss_threads_set", c_int, c_int)
_fn("ss_threads_get", c_int)
_fn("ss_srgb_encode", c_float, c_float)
_fn("ss_srgb_decode", c_float, c_float)
_fn("ss_srgb_encode_array", None, POINTER(c_float), POINTER(c_float), c_size_t)

# ---- optics -------------------------------------------------------------------


class ss_bio_params(ctypes.Structure):
    _fields_ = [
        ("melanin", c_double),
        ("pheomelanin_ratio", c_double),
        ("blood", c_double),
        ("oxygenation", c_double),
        ("sc_thickness_cm", c_double),
        ("epidermis_thickness_cm", c_double),
        ("bilirubin_g_per_l", c_double),
        ("betacarotene_g_per_l", c_double),
    ]


class ss_mc_options(ctypes.Structure):
    _fields_ = [
        ("photons", c_uint64),
        ("seed", c_uint64),
        ("theta_i_rad", c_double),
        ("roughness_sigma", c_double),
        ("stochastic_absorb", c_int),
        ("brdf_n_theta", c_int),
        ("brdf_n_phi", c_int),
        ("radial_bins", c_int),
        ("radial_max_cm", c_double),
        ("radial_distance", c_int),
        ("kernel", c_int),
        ("cancel", ctypes.CFUNCTYPE(c_int, c_void_p)),
        ("cancel_user", c_void_p),
    ]


class ss_spectrum_options(ctypes.Structure):
    _fields_ = [
        ("wl_min_nm", c_double),
        ("wl_max_nm", c_double),
        ("wl_step_nm", c_double),
        ("mc", ss_mc_options),
        ("progress", PROGRESS_FN),
        ("progress_user", c_void_p),
    ]


class ss_reflectance_spectrum(ctypes.Structure):
    _fields_ = [
        ("n", c_int),
        ("wavelength_nm", POINTER(c_double)),
        ("reflectance", POINTER(c_double)),
        ("std_error", POINTER(c_double)),
        ("specular", c_double),
    ]


class ss_brdf_sampled(ctypes.Structure):
    _fields_ = [
        ("n_theta_i", c_int),
        ("n_theta_r", c_int),
        ("n_phi", c_int),
        ("f_rgb", POINTER(c_double)),
    ]


class ss_render_params(ctypes.Structure):
    _fields_ = [("base_rgb", c_double * 3), ("specular", c_double), ("roughness", c_double)]


class ss_fit_options(ctypes.Structure):
    _fields_ = [
        ("subsamples", c_int),
        ("max_iter", c_int),
        ("tol", c_double),
        ("weighting", c_int),
        ("max_theta_rad", c_double),
        ("base_mode", c_int),
        ("albedo_rgb", c_double * 3),
        ("surface", POINTER(ss_brdf_sampled)),
    ]


class ss_fit_result(ctypes.Structure):
    _fields_ = [
        ("model", c_int),
        ("params", ss_render_params),
        ("distance", c_double),
        ("residual_rms", c_double),
        ("residual_rel", c_double),
        ("evaluations", c_int),
    ]


SS_RENDER_NMODELS = 2
SS_MM_NAXES = 6
SS_MM_NFIELDS = 18


class ss_mm_entry(ctypes.Structure):
    _fields_ = [
        ("fit", ss_render_params * SS_RENDER_NMODELS),
        ("residual_rel", c_double * SS_RENDER_NMODELS),
        ("sss_radius_cm", c_double * 3),
        ("albedo_rgb", c_double * 3),
    ]


SS_MM_MAX_SURFACE = 32

SS_OPTICS_MAX_LAYERS = 16
SS_OPTICS_PHASE_MAX = 65


class ss_optics_layer(ctypes.Structure):
    _fields_ = [
        ("n", c_double),
        ("mua_per_cm", c_double),
        ("mus_per_cm", c_double),
        ("g", c_double),
        ("d_cm", c_double),
        ("phase_n", c_int),
        ("phase_theta", c_double * SS_OPTICS_PHASE_MAX),
    ]


class ss_optics_slab(ctypes.Structure):
    _fields_ = [
        ("nlayers", c_int),
        ("layer", ss_optics_layer * SS_OPTICS_MAX_LAYERS),
        ("n_above", c_double),
        ("n_below", c_double),
        ("bottom_albedo", c_double),
    ]


class ss_mc_result(ctypes.Structure):
    _fields_ = [
        ("specular", c_double),
        ("diffuse", c_double),
        ("transmit", c_double),
        ("absorbed", c_double),
        ("diffuse_se", c_double),
        ("transmit_se", c_double),
        ("brdf_exit", POINTER(c_double)),
        ("radial", POINTER(c_double)),
        ("absorbed_per_layer", POINTER(c_double)),
        ("roulette_net", c_double),
        ("nlayers", c_int),
        ("brdf_n_theta", c_int),
        ("brdf_n_phi", c_int),
        ("radial_bins", c_int),
        ("radial_dr_cm", c_double),
    ]


class ss_mm_table(ctypes.Structure):
    _fields_ = [
        ("nsamples", c_int * SS_MM_NAXES),
        ("axis", POINTER(c_double) * SS_MM_NAXES),
        ("nentries", c_size_t),
        ("entries", POINTER(c_double)),
        ("photons", c_uint64),
        ("seed", c_uint64),
        ("n_theta_i", c_int),
        ("n_theta_r", c_int),
        ("n_phi", c_int),
        ("wl_min_nm", c_double),
        ("wl_max_nm", c_double),
        ("wl_step_nm", c_double),
        ("surface_sigma", c_double),
        ("nsurface", c_int),
        ("surf_sigma", c_double * SS_MM_MAX_SURFACE),
        ("surf_specular", c_double * SS_MM_MAX_SURFACE),
        ("surf_roughness", c_double * SS_MM_MAX_SURFACE),
    ]


class ss_mm_build_options(ctypes.Structure):
    _fields_ = [
        ("spectrum", ss_spectrum_options),
        ("n_theta_i", c_int),
        ("n_theta_r", c_int),
        ("n_phi", c_int),
        ("fit", ss_fit_options),
        ("base", ss_bio_params),
        ("quiet", c_int),
    ]


P_ERR = POINTER(ss_error)
P_BIO = POINTER(ss_bio_params)
P_TABLE = POINTER(ss_mm_table)
_fn("ss_bio_params_default", None, P_BIO)
_fn("ss_bio_params_validate", c_int, P_BIO, P_ERR)
_fn("ss_spectrum_options_default", None, POINTER(ss_spectrum_options))
_fn("ss_optics_reflectance_spectrum", c_int, P_BIO, POINTER(ss_spectrum_options),
    POINTER(ss_reflectance_spectrum), P_ERR)
_fn("ss_reflectance_spectrum_free", None, POINTER(ss_reflectance_spectrum))
_fn("ss_spectrum_to_srgb_linear", c_int, POINTER(c_double), POINTER(c_double), c_int,
    POINTER(c_double), P_ERR)
_fn("ss_optics_brdf_sample", c_int, P_BIO, POINTER(ss_spectrum_options), c_int, c_int, c_int,
    POINTER(ss_brdf_sampled), P_ERR)
_fn("ss_brdf_sampled_free", None, POINTER(ss_brdf_sampled))
_fn("ss_fit_options_default", None, POINTER(ss_fit_options))
_fn("ss_render_fit", c_int, c_int, POINTER(ss_brdf_sampled), POINTER(ss_fit_options),
    POINTER(ss_fit_result), P_ERR)
_fn("ss_render_model_name", c_char_p, c_int)
_fn("ss_render_brdf_eval", None, c_int, POINTER(ss_render_params), c_double, c_double, c_double,
    POINTER(c_double))
_fn("ss_render_brdf_sample", c_int, c_int, POINTER(ss_render_params), c_int, c_int, c_int, c_int,
    POINTER(ss_brdf_sampled), P_ERR)
_fn("ss_srgb_linear_to_lab", None, POINTER(c_double), POINTER(c_double))
_fn("ss_lab_to_srgb_linear", None, POINTER(c_double), POINTER(c_double))
_fn("ss_lab_describe", None, POINTER(c_double), POINTER(c_double), POINTER(c_double),
    POINTER(c_double))
_fn("ss_ciede2000", c_double, POINTER(c_double), POINTER(c_double))
_fn("ss_mm_build_options_default", None, POINTER(ss_mm_build_options))
_fn("ss_mm_sample_fast", c_int, P_BIO, POINTER(ss_mm_build_options), POINTER(ss_brdf_sampled),
    POINTER(c_double), POINTER(c_double), P_ERR)
_fn("ss_mm_table_read", P_TABLE, c_char_p, P_ERR)
_fn("ss_mm_table_free", None, P_TABLE)
_fn("ss_mm_table_lookup", None, P_TABLE, POINTER(c_double), POINTER(c_double))
_fn("ss_mm_table_lookup_many", None, P_TABLE, POINTER(c_double), c_size_t, POINTER(c_double))
_fn("ss_mc_options_default", None, POINTER(ss_mc_options))
_fn("ss_optics_slab_validate", c_int, POINTER(ss_optics_slab), P_ERR)
_fn("ss_mc_run", c_int, POINTER(ss_optics_slab), POINTER(ss_mc_options), POINTER(ss_mc_result),
    P_ERR)
_fn("ss_mc_result_free", None, POINTER(ss_mc_result))
_fn("ss_mm_table_lookup_bio", c_int, P_TABLE, P_BIO, POINTER(ss_mm_entry), P_ERR)
_fn("ss_mm_entry_unpack", None, POINTER(c_double), POINTER(ss_mm_entry))
_fn("ss_mm_axis_name", c_char_p, c_int)

# ---- geom + abrasion ------------------------------------------------------------


class ss_stroke_set(ctypes.Structure):
    _fields_ = [
        ("npoints", c_int),
        ("u", POINTER(c_double)),
        ("v", POINTER(c_double)),
        ("stroke", POINTER(c_int)),
        ("nstrokes", c_int),
        ("stroke_ids", POINTER(c_int)),
    ]


class ss_wound_shape(ctypes.Structure):
    _fields_ = [
        ("size", c_int),
        ("mask", P_IMAGE),
        ("dist", P_IMAGE),
        ("label", POINTER(c_int)),
        ("nwounds", c_int),
        ("closing_px", POINTER(c_double)),
        ("inner_ratio", POINTER(c_double)),
        ("box_x", c_int),
        ("box_y", c_int),
        ("box_w", c_int),
        ("box_h", c_int),
        ("npolys", c_int),
        ("polys", c_void_p),
        ("smooth", P_IMAGE),
    ]


class ss_base_skin(ctypes.Structure):
    _fields_ = [("upper", P_IMAGE), ("lower", P_IMAGE), ("upper_srgb", P_IMAGE),
                ("lower_srgb", P_IMAGE), ("palette", c_void_p)]


class ss_texture_set(ctypes.Structure):
    _fields_ = [("color", P_IMAGE), ("reflection", P_IMAGE), ("height", P_IMAGE),
                ("normal", P_IMAGE)]


class ss_abrasion_settings(ctypes.Structure):
    _fields_ = [
        ("size", c_int),
        ("world_size_cm", c_double),
        ("reference_px", c_double),
        ("scab_height_mm", c_double),
        ("seed", c_uint64),
    ]


SS_TIMELINE_MAX_KEYS = 32
SS_PHASE_COUNT = 5


class ss_timeline_key(ctypes.Structure):
    _fields_ = [("phase", c_int), ("day", c_double)]


class ss_timeline(ctypes.Structure):
    _fields_ = [
        ("nkeys", c_int),
        ("key", ss_timeline_key * SS_TIMELINE_MAX_KEYS),
        ("end_day", c_double),
    ]


class ss_abrasion(ctypes.Structure):
    _fields_ = [
        ("settings", ss_abrasion_settings),
        ("timeline", ss_timeline),
        ("shape", POINTER(ss_wound_shape)),
        ("skin", POINTER(ss_base_skin)),
        ("phase", ss_texture_set * SS_PHASE_COUNT),
        ("rendered", c_int * SS_PHASE_COUNT),
    ]


P_SHAPE = POINTER(ss_wound_shape)
P_ABR = POINTER(ss_abrasion)
_fn("ss_stroke_csv_parse", c_int, c_char_p, c_char_p, POINTER(ss_stroke_set), P_ERR)
_fn("ss_stroke_set_free", None, POINTER(ss_stroke_set))
_fn("ss_abrasion_example_strokes", c_int, POINTER(ss_stroke_set), P_ERR)
_fn("ss_wound_shape_from_strokes", c_int, POINTER(ss_stroke_set), c_int, c_int, c_int, c_uint64,
    POINTER(P_SHAPE), P_ERR)
_fn("ss_wound_shape_from_mask", c_int, P_IMAGE, c_int, c_uint64, POINTER(P_SHAPE), P_ERR)
_fn("ss_wound_shape_free", None, P_SHAPE)
_fn("ss_base_skin_create", c_int, P_IMAGE, P_IMAGE, c_int, c_uint64, POINTER(ss_base_skin), P_ERR)
_fn("ss_base_skin_free", None, POINTER(ss_base_skin))
_fn("ss_abrasion_settings_default", None, POINTER(ss_abrasion_settings))
_fn("ss_timeline_default", None, POINTER(ss_timeline))
_fn("ss_timeline_validate", c_int, POINTER(ss_timeline), P_ERR)
_fn("ss_phase_name", c_char_p, c_int)
_fn("ss_phase_from_name", c_int, c_char_p)
_fn("ss_abrasion_create", c_int, POINTER(ss_abrasion_settings), POINTER(ss_timeline), P_SHAPE,
    POINTER(ss_base_skin), POINTER(P_ABR), P_ERR)
_fn("ss_abrasion_free", None, P_ABR)
_fn("ss_abrasion_frame", c_int, P_ABR, c_double, POINTER(ss_texture_set), P_ERR)
_fn("ss_abrasion_frame_poll", c_int, P_ABR, c_double, POINTER(ss_texture_set),
    PROGRESS_POLL_FN, c_void_p, P_ERR)

# ---- heal ------------------------------------------------------------------------

SS_HEAL_NFIELDS = 8


class ss_heal_stats(ctypes.Structure):
    _fields_ = [
        ("open_area_mm2", c_double),
        ("wound_region_area_mm2", c_double),
        ("initial_area_mm2", c_double),
        ("field_mean", c_double * SS_HEAL_NFIELDS),
        ("eschar_wound_mean", c_double),
        ("scar_volume_mm3", c_double),
        ("scar_max", c_double),
        ("open_columns_mm2", c_double),
        ("elevation_mean_mm", c_double),
        ("elevation_max_mm", c_double),
    ]


class ss_heal_area_row(ctypes.Structure):
    _fields_ = [("t_days", c_double), ("st", ss_heal_stats)]


class ss_heal_grid(ctypes.Structure):
    _fields_ = [
        ("nx", c_int),
        ("ny", c_int),
        ("nz", c_int),
        ("dx_mm", c_double),
        ("skin_top_mm", c_double),
        ("cell", POINTER(ctypes.c_uint8)),
        ("field", POINTER(c_float) * SS_HEAL_NFIELDS),
        ("velocity", POINTER(c_float) * 3),
        ("t_days", c_double),
        ("step", c_uint64),
        ("added", POINTER(c_float)),
    ]


class ss_heal_run_config(ctypes.Structure):
    _fields_ = [
        ("scenario", c_char_p),
        ("params_path", c_char_p),
        ("no_scab", c_int),
        ("static_region", c_int),
        ("grid", c_int * 3),
        ("size_mm", c_double * 3),
        ("skin_top_mm", c_double),
        ("epidermis_mm", c_double),
        ("wound_mask", c_char_p),
        ("wound_stroke", c_char_p),
        ("concave_k", c_int),
        ("wound_mesh", c_char_p),
        ("wound_footprint", P_IMAGE),
        ("wound_depth_mm", c_double),
        ("wound_depth_image", c_char_p),
        ("days", c_double),
        ("scheme", c_int),
        ("dt_days", c_double),
        ("snapshot_every", c_double),
        ("area_every", c_double),
        ("checkpoint_every", c_double),
        ("out_dir", c_char_p),
        ("force", c_int),
        ("resume_dir", c_char_p),
        ("seed", c_uint64),
        ("checkpoint_pieces", c_int * 3),
        ("mechanics", c_int),
        ("fibres", c_char_p),
        ("kappa", c_double),
        ("tet_size_mm", c_double),
        ("sutures", c_char_p),
        ("tet_mesh", c_char_p),
        ("mech_model", c_char_p),
        ("adapt_tol", c_double),
        ("skin_mesh", c_char_p),
        ("wound_uv", c_char_p),
        ("skin_thickness_mm", c_double),
        ("voxel_mm", c_double),
        ("mesh_units_mm", c_double),
        ("distributed", c_int),  # the MPI driver's rank 0 only (src/mpi)
    ]


P_RUN = c_void_p  # opaque ss_heal_run *
P_GRID = POINTER(ss_heal_grid)
_fn("ss_heal_field_name", c_char_p, c_int)
_fn("ss_heal_run_config_default", None, POINTER(ss_heal_run_config))
_fn("ss_heal_run_create", c_int, POINTER(ss_heal_run_config), POINTER(P_RUN), P_ERR)
_fn("ss_heal_run_free", None, P_RUN)
_fn("ss_heal_run_step", c_int, P_RUN, P_ERR)
_fn("ss_heal_run_advance_to", c_int, P_RUN, c_double, P_ERR)
_fn("ss_heal_run_set_progress", None, P_RUN, DAY_FN, c_void_p)
_fn("ss_heal_run_finish", c_int, P_RUN, POINTER(c_void_p), P_ERR)
_fn("ss_heal_run_grid", P_GRID, P_RUN)
_fn("ss_heal_run_scenario", c_char_p, P_RUN)
_fn("ss_heal_run_day", c_double, P_RUN)
_fn("ss_heal_run_dt", c_double, P_RUN)
_fn("ss_heal_run_end_day", c_double, P_RUN)
_fn("ss_heal_run_step_index", ctypes.c_longlong, P_RUN)
_fn("ss_heal_run_steps_total", ctypes.c_longlong, P_RUN)
_fn("ss_heal_run_done", c_int, P_RUN)
_fn("ss_heal_run_area", POINTER(ss_heal_area_row), P_RUN, POINTER(c_int))
_fn("ss_heal_area_normalised", c_double, POINTER(ss_heal_stats))
_fn("ss_heal_open_threshold", c_double)
_fn("ss_heal_surface_map", P_IMAGE, P_GRID, c_int, c_int, P_ERR)
_fn("ss_heal_time_to_closure", c_double, POINTER(ss_heal_area_row), c_int, c_double)
libc_free = ctypes.CDLL(None).free
libc_free.argtypes = [c_void_p]
libc_free.restype = None

# ---- skin ------------------------------------------------------------------------

SS_FEAT_NTYPES = 5
SS_BIO_NCHANNELS = 12


NDIST = 45  # doubles in ss_skin_dist


class ss_skin_dist(ctypes.Structure):
    # the distribution constants, set and read by name (ss_skin_dist_set/get)
    _fields_ = [("v", c_double * NDIST)]


class ss_skin_settings(ctypes.Structure):
    _fields_ = [
        ("size", c_int),
        ("world_size_cm", c_double),
        ("seed", c_uint64),
        ("wrap", c_int),
        ("sampler", c_int),
        ("count", ctypes.c_long * SS_FEAT_NTYPES),
        ("dist", ss_skin_dist),
        ("base_lo", c_double * 6),
        ("base_hi", c_double * 6),
        ("phi", c_double),
    ]


class ss_skin_fields(ctypes.Structure):
    _fields_ = [("density", P_IMAGE * SS_FEAT_NTYPES), ("lips", P_IMAGE),
                ("wrinkle_vectors", P_IMAGE), ("hydration", P_IMAGE), ("sebum", P_IMAGE),
                ("scar", P_IMAGE)]


class ss_bezier3(ctypes.Structure):
    _fields_ = [("x", c_double * 4), ("y", c_double * 4)]


class ss_skin_feature(ctypes.Structure):
    _fields_ = [
        ("type", c_int),
        ("x", c_double),
        ("y", c_double),
        ("r", c_double),
        ("r2", c_double),
        ("h", c_double),
        ("m", c_double),
        ("p", c_double),
        ("w", c_double),
        ("curve", ss_bezier3),
    ]


class ss_skin_feature_list(ctypes.Structure):
    _fields_ = [("n", c_size_t), ("f", POINTER(ss_skin_feature))]


class ss_skin_maps(ctypes.Structure):
    _fields_ = [
        ("base_color", P_IMAGE),
        ("roughness", P_IMAGE),
        ("specular", P_IMAGE),
        ("translucency", P_IMAGE),
        ("cavity", P_IMAGE),
        ("height_mm", P_IMAGE),
        ("normal", P_IMAGE),
        ("height_min_mm", c_double),
        ("height_max_mm", c_double),
    ]


# a library built without this module (or with another version of its API)
# leaves the module out instead of failing the import of the package
try:
    P_SKINSET = POINTER(ss_skin_settings)
    _fn("ss_skin_settings_preset", c_int, P_SKINSET, c_char_p, c_int, P_ERR)
    _fn("ss_skin_forearm_counts", None, c_double, POINTER(ctypes.c_long))
    _fn("ss_skin_settings_validate", c_int, P_SKINSET, P_ERR)
    _fn("ss_skin_dist_set", c_int, POINTER(ss_skin_dist), c_char_p, c_double, P_ERR)
    _fn("ss_skin_dist_get", c_double, POINTER(ss_skin_dist), c_char_p)
    _fn("ss_skin_dist_names", POINTER(c_char_p))
    _fn("ss_feature_type_name", c_char_p, c_int)
    _fn("ss_feature_type_from_name", c_int, c_char_p)
    _fn("ss_bio_channel_name", c_char_p, c_int)
    _fn("ss_skin_generate", c_int, P_SKINSET, POINTER(ss_skin_fields),
        POINTER(ss_skin_feature_list), c_char_p, c_size_t, P_ERR)
    _fn("ss_skin_generate_poll", c_int, P_SKINSET, POINTER(ss_skin_fields),
        POINTER(ss_skin_feature_list), c_char_p, c_size_t, PROGRESS_POLL_FN, c_void_p, P_ERR)
    _fn("ss_skin_feature_list_free", None, POINTER(ss_skin_feature_list))
    _fn("ss_skin_bio_maps", P_IMAGE, P_SKINSET, POINTER(ss_skin_fields),
        POINTER(ss_skin_feature_list), P_ERR)
    _fn("ss_skin_lut_create", c_void_p, P_TABLE, P_ERR)
    _fn("ss_skin_lut_free", None, c_void_p)
    _fn("ss_skin_render_maps", c_int, P_IMAGE, c_void_p, c_double, c_int, POINTER(ss_skin_maps),
        P_ERR)
    _fn("ss_skin_bio_maps_poll", P_IMAGE, P_SKINSET, POINTER(ss_skin_fields),
        POINTER(ss_skin_feature_list), PROGRESS_POLL_FN, c_void_p, P_ERR)
    _fn("ss_skin_render_maps_poll", c_int, P_IMAGE, c_void_p, c_double, c_int,
        POINTER(ss_skin_maps), PROGRESS_POLL_FN, c_void_p, P_ERR)
    _fn("ss_skin_maps_free", None, POINTER(ss_skin_maps))
    HAVE_SKIN = True
except AttributeError:
    HAVE_SKIN = False

# ---- wound ------------------------------------------------------------------------

SS_WR_NKEYS = 53


class ss_wound_recipe(ctypes.Structure):
    _fields_ = [("v", c_double * SS_WR_NKEYS)]


class ss_wound_render_options(ctypes.Structure):
    _fields_ = [
        ("size", c_int),
        ("side_mm", c_double),
        ("skin", P_IMAGE),
        ("table", P_TABLE),
        ("recipe", ss_wound_recipe),
        ("scab_photons", c_uint64),
        ("seed", c_uint64),
    ]


class ss_wound_textures(ctypes.Structure):
    _fields_ = [("base_color", P_IMAGE), ("roughness", P_IMAGE), ("height", P_IMAGE),
                ("normal", P_IMAGE)]


# a library built without this module (or with another version of its API)
# leaves the module out instead of failing the import of the package
try:
    _fn("ss_heal_run_params", c_void_p, P_RUN)
    _fn("ss_wound_recipe_default", None, POINTER(ss_wound_recipe))
    _fn("ss_wound_recipe_key", c_char_p, c_int)
    _fn("ss_wound_recipe_load", c_int, c_char_p, POINTER(ss_wound_recipe), P_ERR)
    _fn("ss_skin_bio_default", P_IMAGE, c_int, c_double, c_uint64, P_ERR)
    _fn("ss_wound_skin_read", P_IMAGE, c_char_p, P_ERR)
    _fn("ss_wound_skin_validate", c_int, P_IMAGE, c_char_p, P_ERR)
    _fn("ss_wound_render_options_default", None, POINTER(ss_wound_render_options))
    _fn("ss_wound_renderer_create", c_int, POINTER(ss_wound_render_options), POINTER(c_void_p),
        P_ERR)
    _fn("ss_wound_renderer_free", None, c_void_p)
    _fn("ss_wound_tissue_create", c_void_p, P_GRID, c_void_p, POINTER(ss_wound_recipe), P_ERR)
    _fn("ss_wound_tissue_observe", None, c_void_p, P_GRID)
    _fn("ss_wound_tissue_free", None, c_void_p)
    _fn("ss_wound_render", c_int, c_void_p, c_void_p, P_IMAGE, POINTER(ss_wound_textures), P_ERR)
    _fn("ss_wound_render_poll", c_int, c_void_p, c_void_p, P_IMAGE, POINTER(ss_wound_textures),
        PROGRESS_POLL_FN, c_void_p, P_ERR)
    HAVE_WOUND = True
except AttributeError:
    HAVE_WOUND = False
