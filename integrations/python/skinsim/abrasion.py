"""The abrasion-healing texture timeline (seed 000): a wound shape (painted
UV strokes or a mask) -> five key positions -> a texture set for any day.

    ab = skinsim.abrasion.Abrasion(size=512)            # built-in stroke
    tex = ab.frame(3.0)                                 # day 3
    tex["color"]       # (512, 512, 3) float32, linear RGB
    tex["reflection"]  # (512, 512) specular strength 0..1
    tex["height"]      # (512, 512) 0.5 = skin surface, 1 = thickest scab
    tex["normal"]      # (512, 512, 3) tangent space, OpenGL (+Y up), 0..1 encoded

Frames are rendered by the library straight into numpy arrays (no copies);
pass `out=` to reuse the arrays of an earlier frame, as a time slider would.
"""

import ctypes
import os
from typing import Any, List, Tuple

import numpy as np

from . import _lib as L

MAPS = ("color", "reflection", "height", "normal")
_CHANNELS = {"color": 3, "reflection": 1, "height": 1, "normal": 3}


def phases() -> List[str]:
    """The five abrasion phases' names, in order (seed 000 §4)."""
    return [L.lib.ss_phase_name(i).decode() for i in range(L.SS_PHASE_COUNT)]


def default_timeline():
    """The default key positions as [(phase, day), ...] and the end day."""
    t = L.ss_timeline()
    L.lib.ss_timeline_default(ctypes.byref(t))
    keys = [(L.lib.ss_phase_name(t.key[i].phase).decode(), t.key[i].day) for i in range(t.nkeys)]
    return keys, t.end_day


def _strokes_text(strokes):
    """Stroke points (n x 2: u, v; or n x 3: u, v, stroke id) as the CSV the
    library parses, so the library checks them with its own messages."""
    a = np.asarray(strokes, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        raise L.InputError("strokes: want an array of (u, v) or (u, v, stroke_id) rows, got "
                           "shape %s" % (a.shape,), L.SS_ERR_INPUT)
    rows = []
    for r in a:
        if len(r) == 2:
            rows.append("%.17g,%.17g" % (r[0], r[1]))
        else:
            rows.append("%.17g,%.17g,%.17g" % (r[0], r[1], r[2]))
    return ("\n".join(rows) + "\n").encode()


class Abrasion:
    """Key textures of one wound. Arguments:

    size          texture side in pixels
    strokes       (n, 2|3) array of u, v[, stroke id] in 0..1 (v down); one hull per stroke
    stroke_csv    or a stroke CSV file (the `skinsim abrasion --stroke` format)
    mask          or a wound mask array (h, w), > 0.5 = wound
    hull          "convex" or "concave" (k-nearest, concave_k)
    timeline      [(phase, day), ...] and end_day, default the library's
    seed, world_size_cm
    Neither strokes, stroke_csv nor mask: the built-in example stroke.
    """

    def __init__(self, size=512, strokes=None, stroke_csv=None, mask=None, hull="convex",
                 concave_k=8, timeline=None, end_day=None, seed=None, world_size_cm=None):
        self._h = None
        if sum(x is not None for x in (strokes, stroke_csv, mask)) > 1:
            raise L.InputError("give one of strokes, stroke_csv and mask", L.SS_ERR_INPUT)
        if hull not in ("convex", "concave"):
            raise L.InputError("hull: %r is not convex or concave" % (hull,), L.SS_ERR_INPUT)
        s = L.ss_abrasion_settings()
        L.lib.ss_abrasion_settings_default(ctypes.byref(s))
        s.size = L.as_int("size", size, lo=1)
        if seed is not None:
            s.seed = L.as_u64("seed", seed)
        if world_size_cm is not None:
            s.world_size_cm = L.as_float("world_size_cm", world_size_cm, lo=0.0, lo_open=True)
        self.size = s.size
        t = L.ss_timeline()
        L.lib.ss_timeline_default(ctypes.byref(t))
        if timeline is not None:
            keys = list(timeline)
            if not 1 <= len(keys) <= L.SS_TIMELINE_MAX_KEYS:
                raise L.InputError("timeline: 1 to %d keys" % L.SS_TIMELINE_MAX_KEYS,
                                   L.SS_ERR_INPUT)
            t.nkeys = len(keys)
            for i, (ph, day) in enumerate(keys):
                pid = L.lib.ss_phase_from_name(str(ph).encode())
                if pid < 0:
                    raise L.InputError("timeline: unknown phase %r (known: %s)"
                                       % (ph, ", ".join(phases())), L.SS_ERR_INPUT)
                t.key[i].phase = pid
                t.key[i].day = L.as_float("timeline[%d] day" % i, day)
        if end_day is not None:
            t.end_day = L.as_float("end_day", end_day)
        L.check(L.lib.ss_timeline_validate, ctypes.byref(t))
        self._timeline = t

        h = L.Handle()  # frees shape, skin and key textures after the last view
        shape = L.P_SHAPE()
        if mask is not None:
            m = L.as_image_input(mask, "mask", channels=(1,))
            hdr = L.image_header(m if m.ndim == 2 else np.ascontiguousarray(m[..., 0]))
            L.check(L.lib.ss_wound_shape_from_mask, ctypes.byref(hdr), s.size, s.seed,
                    ctypes.byref(shape))
        else:
            ss = L.ss_stroke_set()
            try:
                if strokes is not None:
                    L.check(L.lib.ss_stroke_csv_parse, _strokes_text(strokes), b"strokes",
                            ctypes.byref(ss))
                elif stroke_csv is not None:
                    path = os.fspath(stroke_csv)
                    try:
                        with open(path, "rb") as f:
                            text = f.read()
                    except OSError as e:
                        raise L.InputError("%s: %s" % (path, e.strerror), L.SS_ERR_INPUT)
                    L.check(L.lib.ss_stroke_csv_parse, text, os.fsencode(path), ctypes.byref(ss))
                else:
                    L.check(L.lib.ss_abrasion_example_strokes, ctypes.byref(ss))
                try:
                    L.check(L.lib.ss_wound_shape_from_strokes, ctypes.byref(ss),
                            1 if hull == "concave" else 0,
                            L.as_int("concave_k", concave_k, lo=0) if hull == "concave" else 0, s.size, s.seed,
                            ctypes.byref(shape))
                except L.SkinsimError as e:
                    # name the input, as the command line does
                    if strokes is None and stroke_csv is None:
                        raise
                    name = "strokes" if strokes is not None else os.fspath(stroke_csv)
                    L.raise_for(e.code, "%s: %s" % (name, e))
            finally:
                L.lib.ss_stroke_set_free(ctypes.byref(ss))
        self._shape = h.own(L.lib.ss_wound_shape_free, shape)
        skin = L.ss_base_skin()
        L.check(L.lib.ss_base_skin_create, None, None, s.size, s.seed, ctypes.byref(skin))
        h.own(L.lib.ss_base_skin_free, ctypes.pointer(skin))
        ab = L.P_ABR()
        L.check(L.lib.ss_abrasion_create, ctypes.byref(s), ctypes.byref(t), shape,
                ctypes.byref(skin), ctypes.byref(ab))
        self._ab = h.own(L.lib.ss_abrasion_free, ab)
        self._h = h

    def close(self):
        """Drops this object's hold on the library's memory; it is freed when
        no view of a key texture or the mask is left either."""
        self._h = None

    def __enter__(self) -> "Abrasion":
        """The object itself (closed on leaving the with block)."""
        return self

    def __exit__(self, *exc: Any) -> None:
        """Closes it."""
        self.close()

    def _need_open(self):
        if self._h is None:
            raise L.SkinsimError("this Abrasion was closed", L.SS_ERR_INPUT)

    @property
    def mask(self):
        """The wound shape (size, size), 1 inside a wound: a read-only view."""
        self._need_open()
        v = L.image_view(self._shape.contents.mask, self._h)
        v.flags.writeable = False
        return v

    @property
    def nwounds(self) -> int:
        """How many separate wounds the shape holds."""
        self._need_open()
        return self._shape.contents.nwounds

    @property
    def timeline(self) -> Tuple[List[Tuple[str, float]], float]:
        """The timeline as ([(phase, day), ...], end_day)."""
        t = self._timeline
        keys = [(L.lib.ss_phase_name(t.key[i].phase).decode(), t.key[i].day)
                for i in range(t.nkeys)]
        return keys, t.end_day

    def key(self, phase):
        """The key texture set of a phase (read-only views of the library's
        textures, valid while this object lives)."""
        self._need_open()
        pid = L.lib.ss_phase_from_name(str(phase).encode())
        if pid < 0 or not self._ab.contents.rendered[pid]:
            raise L.InputError("key: %r is not a phase of this timeline (%s)"
                               % (phase, ", ".join(k for k, _ in self.timeline[0])),
                               L.SS_ERR_INPUT)
        ts = self._ab.contents.phase[pid]
        out = {}
        for m in MAPS:
            v = L.image_view(getattr(ts, m), self._h)
            v.flags.writeable = False
            out[m] = v
        return out

    def new_frame(self, maps=MAPS):
        """Zeroed arrays for a frame with the given maps."""
        n = self.size
        return {m: np.zeros((n, n, 3) if _CHANNELS[m] == 3 else (n, n), dtype=np.float32)
                for m in maps}

    def frame(self, day, out=None, maps=MAPS, progress=None):
        """The texture set at `day` (days since the injury) as numpy arrays
        the library renders into. out: arrays of an earlier frame to reuse
        (only the maps present in it are rendered). progress: True for a bar
        on stderr, or a callable(fraction 0..1) called between maps and bands
        of rows; Ctrl-C stops the frame there and raises KeyboardInterrupt
        (arrays passed as out= are then partly written)."""
        self._need_open()
        day = L.as_float("day", day, lo=0.0)
        if out is None:
            out = self.new_frame(maps)
        ts = L.ss_texture_set()
        hdrs = []
        for m, arr in out.items():
            if m not in _CHANNELS:
                raise L.InputError("frame: unknown map %r (maps: %s)" % (m, ", ".join(MAPS)),
                                   L.SS_ERR_INPUT)
            want = (self.size, self.size) + ((3,) if _CHANNELS[m] == 3 else ())
            L.set_out_image(ts, m, arr, want, "frame: out[%r]" % m, hdrs)
        if "color" not in out:
            raise L.InputError("frame: the colour map is always rendered; include 'color'",
                               L.SS_ERR_INPUT)
        with L.Poll(progress, "abrasion frame") as poll:
            poll.check(L.lib.ss_abrasion_frame_poll, self._ab, day, ctypes.byref(ts),
                       poll.stage(), None)
        return out
