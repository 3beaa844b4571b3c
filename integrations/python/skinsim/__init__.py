"""skinsim: skin optics, wound healing and skin/wound textures from Python.

A thin ctypes layer over the shared C library libskinsim (see _lib.py for
how the library is found and how arrays cross without copies). Modules:

    skinsim.optics    spectra, colour, sampled BRDF, render-BRDF fit, ModelMatch
    skinsim.abrasion  the abrasion-healing texture timeline (seed 000)
    skinsim.heal      the wound-healing simulation (seed 001): run, step, fields, area curve
    skinsim.skin      procedural skin textures (seed 003 §4.8): bio maps and render maps
    skinsim.wound     a heal run's wound as render textures over a base skin (seeds joined)

Errors raise skinsim.SkinsimError (InputError for bad input, also a
ValueError) with the library's own message.
"""

from . import _lib
from ._lib import InputError, OutOfMemoryError, SkinsimError
from . import optics, abrasion, heal  # noqa: E402

# libraries built without these modules leave them out
try:
    from . import skin  # noqa: F401
except ImportError:
    pass
try:
    from . import wound  # noqa: F401
except ImportError:
    pass

__all__ = ["optics", "abrasion", "heal", "SkinsimError", "InputError", "OutOfMemoryError",
           "version", "data_dir", "set_threads", "library_path", "read_image", "write_png"]

library_path = _lib.library_path


def version():
    """The loaded library's version ("0.1.0")."""
    return _lib.lib.ss_version().decode()


def data_dir():
    """Where the library reads its data (spectra, default table)."""
    return _lib.lib.ss_data_dir().decode()


def read_image(path, srgb=True):
    """A PNG or EXR file as a float32 array (h, w[, c]), linear light (PNG
    colour channels are sRGB-decoded unless srgb=False)."""
    import os
    p = _lib.check_ptr(_lib.lib.ss_image_read, os.fsencode(os.fspath(path)), 1 if srgb else 0)
    try:
        return _lib.image_view(p, None).copy()
    finally:
        _lib.lib.ss_image_free(p)


def write_png(path, image, bits=8, srgb=None):
    """Writes a float image (h, w[, c], 1-4 channels, linear) as PNG; colour
    (3-4 channels) is sRGB-encoded unless srgb=False. Atomic."""
    import os
    a = _lib.as_image_input(image, str(path))
    if srgb is None:
        srgb = a.ndim == 3 and a.shape[2] >= 3
    hdr = _lib.image_header(a)
    _lib.check(_lib.lib.ss_png_write, os.fsencode(os.fspath(path)), hdr, _lib.as_int("bits", bits, lo=8, hi=16),
               1 if srgb else 0)


def set_threads(n=0):
    """Worker threads for parallel work (0: $SKINSIM_THREADS, else all
    cores). Results are identical for any count. Returns the count in force."""
    n = _lib.as_int("n", n, lo=0, hi=4096)
    return _lib.lib.ss_threads_set(n)
