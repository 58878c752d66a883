"""vibcam: vision-based vibration and modal measurement, from numpy.

The library behind the ``host-harness`` command line, as Python functions: the same code
(firmware-core's centroid, Lucas-Kanade tracker, Welch H1 and Fourier upsampler; host-harness's
frame readers, multi-target tracking, output-only modal analysis and Monte Carlo studies), numpy
arrays in and out. See docs/python.md.

Errors are exceptions carrying the command line's messages: :class:`InputError` (a
``ValueError``) when the input is refused, :class:`VibcamError` (a ``RuntimeError``) otherwise.
Every function releases the GIL while it works.
"""

from __future__ import annotations

import csv as _csv
import inspect as _inspect
import io as _io
import math as _math
import numbers as _numbers
import os as _os
import tempfile as _tempfile
from dataclasses import dataclass as _dataclass, field as _field, fields as _fields
from typing import Any as _Any, Optional as _Optional, Sequence as _Sequence, Union as _Union

import numpy as _np

from . import _vibcam
from ._vibcam import InputError, VibcamError, FrameReader

#: The package's version (the workspace's).
__version__ = _vibcam.__version__

# the future import's name is no part of the package (its effect on this module stays)
del annotations

__all__ = [
    "InputError",
    "VibcamError",
    "FrameReader",
    "Centroid",
    "Tracks",
    "AnalysisResult",
    "EmaResult",
    "StudyResult",
    "FLAGS",
    "MODEL_REVISION",
    "centroid",
    "track",
    "frf",
    "upsample",
    "analyze",
    "ema",
    "modal",
    "study",
    "open_frames",
    "region_points",
]

#: ``(bit, name)`` of the firmware's result flags (``Tracks.flags``, ``Centroid.flags``).
FLAGS = tuple(_vibcam.FLAGS)
#: The revision of the simulation models (a study's numbers belong to it).
MODEL_REVISION = _vibcam.MODEL_REVISION

_PathLike = _Union[str, "_os.PathLike[str]"]


def _frames(frames: _Any) -> _Any:
    """A path as a ``str`` (what the native module takes); arrays pass through."""
    if isinstance(frames, (str, _os.PathLike)):
        return _os.fspath(frames)
    if isinstance(frames, _np.ndarray):
        return frames
    if isinstance(frames, (list, tuple)):
        return _np.stack([_np.asarray(f) for f in frames])
    return _np.asarray(frames)


# Every argument is checked here, before the native module sees it: a refused value raises
# InputError naming the argument (never Python's OverflowError or TypeError from the
# conversion), and nothing is truncated (a threshold of 1.7 is refused, not taken as 1).


def _whole(name: str, v: _Any, lo: int, hi: int, optional: bool = False) -> _Optional[int]:
    """``v`` as a whole number in ``lo..=hi``."""
    if v is None and optional:
        return None
    ok = isinstance(v, _numbers.Integral) and not isinstance(v, bool)
    if isinstance(v, _numbers.Real) and not isinstance(v, bool) and not ok:
        ok = _math.isfinite(float(v)) and float(v) == int(v)
    if not ok:
        raise InputError(f"{name} = {v!r}: a whole number from {lo} to {hi} is needed")
    i = int(v)
    if not lo <= i <= hi:
        raise InputError(f"{name} = {i}: a whole number from {lo} to {hi} is needed")
    return i


def _number(name: str, v: _Any, positive: bool = False, optional: bool = False) -> _Optional[float]:
    """``v`` as a finite number (``> 0`` with ``positive``)."""
    if v is None and optional:
        return None
    if isinstance(v, bool) or not isinstance(v, _numbers.Real) or not _math.isfinite(float(v)):
        raise InputError(f"{name} = {v!r}: a finite number is needed")
    if positive and not float(v) > 0:
        raise InputError(f"{name} = {v!r}: a positive number is needed")
    return float(v)


_SETTINGS = _vibcam.SETTINGS


def _setting(command: str, name: str, v: _Any, optional: bool = False) -> _Any:
    """``v`` checked against ``command``'s row of ``name`` in the settings table (the one the
    command line's flags are declared by): its range, its words (``auto``), its choices."""
    row = next(r for r in _SETTINGS if r["key"] == name and command in r["commands"])
    if v is None and optional:
        return None
    if isinstance(v, str) and v in row["words"]:
        return v
    if row["kind"] == "choice":
        if v not in row["choices"]:
            raise InputError(f"{name} = {v!r}: {row['range']}")
        return v
    if row["kind"] == "whole":
        return _whole(name, v, int(row["min"]), int(row["max"]))
    x = _number(name, v)
    lo, hi = row["min"], row["max"]
    below = lo is not None and (x <= lo if row["min_open"] else x < lo)
    above = hi is not None and (x >= hi if row["max_open"] else x > hi)
    if below or above:
        raise InputError(f"{name} = {v!r}: {row['range']} is needed")
    return x


def _vector(name: str, x: _Any) -> _np.ndarray:
    """``x`` as a 1-D array of finite float64 values."""
    try:
        a = _np.asarray(x, dtype=_np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(f"{name}: not an array of numbers ({e})") from None
    if a.ndim != 1:
        raise InputError(f"{name}: a 1-D array is needed, got shape {a.shape}")
    bad = _np.flatnonzero(~_np.isfinite(a))
    if bad.size:
        v = a[bad[0]]
        raise InputError(f"{name}[{bad[0]}] is {'NaN' if _np.isnan(v) else v}: every value must be finite")
    return _np.ascontiguousarray(a)


def _shown(v: _Any) -> str:
    """A value as a report's header shows it: an array by its shape and type, a path as a
    string, anything else by ``repr`` (cut at 200 characters)."""
    if hasattr(v, "shape") and hasattr(v, "dtype"):
        return f"array{tuple(v.shape)} {v.dtype}"
    if isinstance(v, _os.PathLike):
        v = _os.fspath(v)
    text = repr(v)
    return text if len(text) <= 200 else text[:197] + "..."


def _same(a: _Any, b: _Any) -> bool:
    """Whether a value is its parameter's default (an array never is)."""
    if hasattr(a, "shape"):
        return False
    try:
        return bool(a == b) and type(a) is type(b)
    except Exception:
        return False


def _call(fn: _Any, given: dict) -> tuple:
    """How ``fn`` was called, for the report's header: the call as written (the arguments
    not left at their default) and every parameter ``(name, value shown, default?)``."""
    settings, written = [], []
    for name, p in _inspect.signature(fn).parameters.items():
        v = given.get(name, p.default)
        default = p.default is not _inspect.Parameter.empty and _same(v, p.default)
        settings.append((name, _shown(v), default))
        if not default:
            written.append(_shown(v) if p.default is _inspect.Parameter.empty
                           else f"{name}={_shown(v)}")
    return (f"vibcam.{fn.__name__}({', '.join(written)})", settings)


def _roi(roi: _Any) -> _Optional[tuple]:
    if roi is None:
        return None
    r = tuple(roi) if isinstance(roi, (list, tuple, _np.ndarray)) else None
    if r is None or len(r) != 4:
        raise InputError(f"roi = {roi!r}: (x, y, w, h) is needed")
    x, y = (_whole(f"roi[{i}]", v, 0, 65535) for i, v in enumerate(r[:2]))
    w, h = (_whole(f"roi[{i + 2}]", v, 1, 65535) for i, v in enumerate(r[2:]))
    return (x, y, w, h)


def _threshold(threshold: _Union[int, str, None]) -> tuple:
    if threshold is None:
        return None, False
    if isinstance(threshold, str):
        if threshold.strip().lower() == "auto":
            return None, True
        raise InputError(f"threshold `{threshold}`: a grey level 0-65535, or 'auto' (with points)")
    return _setting("track", "threshold", threshold), False


def _points(points: _Any) -> tuple:
    """``(points, points_file)`` for the native module."""
    if points is None:
        return None, None
    if isinstance(points, (str, _os.PathLike)):
        return None, _os.fspath(points)
    out = []
    for i, p in enumerate(points):
        if isinstance(p, dict):
            get = p.get
            row = (get("x"), get("y"), get("w"), get("h"), get("threshold"), get("group"))
        else:
            p = tuple(p)
            if not 4 <= len(p) <= 6:
                raise InputError(
                    f"points[{i}]: (x, y, w, h[, threshold[, group]]) expected, got {len(p)} values"
                )
            row = p + (None,) * (6 - len(p))
        if any(v is None for v in row[:4]):
            raise InputError(f"points[{i}]: x, y, w and h are needed")
        x, y, w, h, thr, group = row
        out.append(
            (
                _number(f"points[{i}].x", x),
                _number(f"points[{i}].y", y),
                _whole(f"points[{i}].w", w, 3, 65536),
                _whole(f"points[{i}].h", h, 3, 65536),
                _whole(f"points[{i}].threshold", thr, 0, 65535, optional=True),
                _whole(f"points[{i}].group", group, 0, 2**32 - 1, optional=True),
            )
        )
    return out, None


def _tracking(points, targets, tracker, threshold, fps, retime, search_px, gate_px, roi) -> dict:
    """The targets and how to follow them, as the native ``track`` and ``analyze`` take them."""
    t, auto = _threshold(threshold)
    pts, pfile = _points(points)
    if not isinstance(tracker, str):
        raise InputError(
            f"tracker = {tracker!r}: one of 'auto', 'binary' (alias 'blob'), 'weighted', 'lk'"
        )
    return {
        "fps": _setting("track", "fps", fps, optional=True),
        "retime": bool(retime),
        "points": pts,
        "points_file": pfile,
        "targets": _setting("track", "targets", targets, optional=True),
        "gate_px": _setting("track", "gate_px", gate_px, optional=True),
        "threshold": t,
        "auto_threshold": auto,
        "tracker": tracker,
        "search_px": _setting("track", "search_px", search_px, optional=True),
        "roi": _roi(roi),
    }


def _view(reference, camera_model, scale, target_size_mm, world) -> _Optional[dict]:
    """The camera's view (static references, the scale from the scene) for the native ``track``
    and ``analyze``; ``None`` when nothing of it was asked."""
    if reference is None and camera_model is None and scale is None and target_size_mm is None \
            and world is None:
        return None
    ref, rfile = _points(reference)
    if camera_model is not None and camera_model not in ("translation", "similarity", "homography"):
        raise InputError(
            f"camera_model {camera_model!r}: 'translation', 'similarity' or 'homography'"
        )
    sc = None
    if scale is not None:
        try:
            a, b, mm = scale
        except (TypeError, ValueError):
            raise InputError(f"scale = {scale!r}: (A, B, mm) expected, A and B a target (3) or "
                             "a reference ('r2')") from None
        sc = (str(a), str(b), _number("scale[2]", mm, positive=True))
    w, wfile = None, None
    if world is not None:
        if isinstance(world, (str, _os.PathLike)):
            wfile = _os.fspath(world)
        else:
            w = []
            for i, p in enumerate(world):
                p = tuple(p)
                if len(p) not in (4, 5):
                    raise InputError(f"world[{i}]: (x, y, x_mm, y_mm[, u_px]) expected")
                u = p[4] if len(p) == 5 else 0.5
                w.append(tuple(_number(f"world[{i}][{j}]", v) for j, v in enumerate(p[:4]))
                         + (_number(f"world[{i}].u_px", u),))
    return {
        "reference": ref,
        "reference_file": rfile,
        "camera_model": camera_model,
        "scale": sc,
        "target_size_mm": _setting("track", "target_size_mm", target_size_mm, optional=True),
        "world": w,
        "world_file": wfile,
    }


@_dataclass(frozen=True)
class Centroid:
    """One frame's centroid: position (px; NaN when no pixel passed the threshold), the pixels
    above it, and the firmware's flags by name (``EMPTY``, ``SATURATED``, ``BORDER``, ...)."""

    x: float
    y: float
    pixels: int
    flags: tuple

    @property
    def found(self) -> bool:
        """Whether there is a position."""
        return not (_np.isnan(self.x) or _np.isnan(self.y))


def centroid(
    frame: _np.ndarray,
    threshold: int,
    mode: str = "auto",
    roi: _Optional[_Sequence[int]] = None,
) -> Centroid:
    """The centroid of one frame by firmware-core (as ``host-harness centroid``).

    ``frame``: ``uint8``/``uint16`` array ``(H, W)`` (or ``(H, W, 3|4)`` colour: its BT.601
    luma); ``threshold``: grey level (pixels above it count); ``mode``: ``"binary"`` (alias
    ``"blob"``: every pixel above weighs 1; ``"auto"``, the default, is binary for one frame) or
    ``"weighted"`` (weights ``pixel - threshold``);
    ``roi``: ``(x, y, w, h)``.
    """
    a = _np.asarray(frame)
    if a.ndim == 3 and a.shape[-1] in (3, 4):
        a = a[_np.newaxis]  # one colour frame
    if not isinstance(mode, str):
        raise InputError(f"mode = {mode!r}: 'binary' (alias 'blob') or 'weighted'")
    level = _setting("centroid", "threshold", threshold)
    if isinstance(level, str):
        raise InputError("threshold 'auto' is Otsu's of each window (track with points); "
                         "centroid needs a grey level")
    x, y, pixels, flags = _vibcam.centroid(a, level, mode, _roi(roi))
    return Centroid(x, y, pixels, tuple(flags))


@_dataclass(frozen=True)
class Tracks:
    """Each target's position per frame.

    ``positions``: ``(N, K, 2)`` pixels ``(x, y)``, NaN where the target was lost;
    ``flags``: ``(N, K)`` bits of :data:`FLAGS` (why a frame was lost, or a warning);
    ``fps``: the frame rate used (1.0 when none was known nor needed); with ``reference``:
    ``raw_positions`` (as measured; ``positions`` has the camera's motion removed) and
    ``camera_motion`` ``(N, 4)`` (the image centre's shift x, y in px, the roll in degrees, the
    scale; NaN where no reference was seen); with a scale: ``displacement_mm`` ``(N, K)`` along
    ``axis`` (positive up for ``y``); ``view_report``: what the references and the scale gave
    (references left out and why, each target's scale and its uncertainty); ``report``: the
    report ``track`` prints (report.txt after its header), and the page of its ``report.html``
    (its header naming this call, the inputs' SHA-256 and the settings) shown inline by
    notebooks. Each position's evidence, ``(N, K)`` (Lucas-Kanade; NaN and ``""`` for the
    centroids): ``score``, its match against the first frame's template (ZNCC); ``fb_px``, the
    forward-backward disagreement in px; ``check``, the check that took the position away
    (``"forward-backward"``, ``"score"``, ``"group"``; ``""``: none), as ``displacement.csv``.
    """

    positions: _np.ndarray
    flags: _np.ndarray
    fps: float
    raw_positions: _Optional[_np.ndarray] = None
    camera_motion: _Optional[_np.ndarray] = None
    displacement_mm: _Optional[_np.ndarray] = None
    view_report: str = ""
    report: str = _field(default="", repr=False)
    html: str = _field(default="", repr=False)
    score: _Optional[_np.ndarray] = _field(default=None, repr=False)
    fb_px: _Optional[_np.ndarray] = _field(default=None, repr=False)
    check: _Optional[_np.ndarray] = _field(default=None, repr=False)

    def _repr_html_(self) -> str:
        """The page of ``track``'s ``report.html`` (the first frame with the windows, the
        tracks' figure, the report), shown inline by notebooks."""
        return self.html

    @property
    def lost(self) -> _np.ndarray:
        """``(N, K)``: frames without a position."""
        return _np.isnan(self.positions[..., 0])


def track(
    frames: _Any,
    points: _Any = None,
    *,
    targets: _Optional[int] = None,
    tracker: str = "auto",
    threshold: _Union[int, str, None] = None,
    fps: _Optional[float] = None,
    retime: bool = False,
    search_px: _Optional[int] = None,
    gate_px: _Optional[float] = None,
    roi: _Optional[_Sequence[int]] = None,
    return_flags: bool = False,
    reference: _Any = None,
    camera_model: _Optional[str] = None,
    scale: _Optional[_Sequence] = None,
    target_size_mm: _Optional[float] = None,
    world: _Any = None,
    axis: str = "y",
) -> _Union[_np.ndarray, Tracks]:
    """Each target's position in every frame, ``(N, K, 2)`` pixels (NaN where lost), as
    ``host-harness track`` follows them.

    ``frames``: a path as ``--frames`` takes it (directory, pattern, multi-page TIFF, Photron
    ``.cih``/``.cihx``, Phantom ``.cine``, video) or an ``uint8``/``uint16`` array ``(N, H, W)``
    (``(N, H, W, 3|4)``: colour). Targets: ``points`` (a list of ``(x, y, w, h[, threshold[,
    group]])`` windows, or a points CSV file ``target,x,y,w,h[,threshold][,group]``), or
    ``targets=K`` (the K blobs of the first frame, numbered left to right), or neither (the one
    target of the frame or ``roi``). ``tracker``: ``"auto"`` (the default: with points, per target
    the blob centroid where a threshold separates it, Lucas-Kanade otherwise, said in
    ``Tracks.report``; without points the binary centroid), ``"binary"``/``"blob"``,
    ``"weighted"``, or ``"lk"`` (Lucas-Kanade; with points, no threshold). ``threshold``: a grey level, or
    ``"auto"`` with points (Otsu's of each window). ``search_px``: with ``lk``, the largest
    motion between frames to catch. With ``return_flags``: a :class:`Tracks`.

    The camera's view (as ``host-harness track``): ``reference``, windows on parts of the scene
    that do not move (as ``points``), from which the camera's own motion is estimated (model
    ``camera_model``: ``"translation"``, ``"similarity"`` (the default with two or more) or
    ``"homography"``) and removed from ``positions``; a reference that moves or is lost is left
    out and named in ``view_report``. A scale: ``scale=(A, B, mm)`` (the distance between two
    tracked points, ``A`` a target number or ``"rK"`` a reference), ``target_size_mm`` (each
    target's diameter; a centroid tracker) or ``world`` (four or more ``(x, y, x_mm, y_mm[,
    u_px])`` points of the structure's plane, or a CSV file ``x,y,x_mm,y_mm[,u_px]``): each
    target's ``displacement_mm`` along ``axis``.
    """
    call = _call(track, locals())
    if axis not in ("x", "y"):
        raise InputError(f"axis {axis!r}: 'x' or 'y'")
    d = _vibcam.track(
        _frames(frames),
        _tracking(points, targets, tracker, threshold, fps, retime, search_px, gate_px, roi),
        _view(reference, camera_model, scale, target_size_mm, world),
        axis,
        call=call,
    )
    if return_flags:
        return Tracks(
            d["positions"],
            d["flags"],
            d["fps"],
            d["raw_positions"],
            d["camera_motion"] if d["raw_positions"] is not None else None,
            d["displacement_mm"],
            d["view_report"],
            d["report"],
            d["html"],
            d["score"],
            d["fb_px"],
            _np.array(d["check"], dtype=str).reshape(d["score"].shape),
        )
    return d["positions"]


def frf(
    x: _Any,
    y: _Any,
    fs: float,
    window: str = "hann",
    nperseg: _Optional[int] = None,
    noverlap: _Optional[int] = None,
    nfft: _Optional[int] = None,
    detrend: _Union[str, bool] = "constant",
) -> tuple:
    """H1 = Pxy / Pxx and coherence by firmware-core's streaming Welch estimator (f32 inside,
    as on the MCU), with scipy.signal.csd's conventions and defaults (``nperseg`` 256 or the
    record, ``noverlap`` half of it, ``nfft`` = ``nperseg``); only whole segments are used.

    Returns ``(freq_hz, h1, coherence)``: ``freq_hz`` the bins ``0 .. nfft/2`` at
    ``k fs / nfft``, ``h1`` complex (y units per x unit; 0 where x has no energy), coherence in
    ``[0, 1]``.
    """
    if detrend is False:
        detrend = "none"
    f, h, c, _segments = _vibcam.frf(
        _vector("x", x),
        _vector("y", y),
        _setting("frf", "fs", fs),
        window=window,
        nperseg=_setting("frf", "nperseg", nperseg, optional=True),
        noverlap=_setting("frf", "noverlap", noverlap, optional=True),
        nfft=_setting("frf", "nfft", nfft, optional=True),
        detrend=str(detrend),
    )
    return f, h, c


def upsample(x: _Any, from_hz: float, to_hz: float) -> _np.ndarray:
    """``x`` sampled at ``from_hz`` Fourier-upsampled to ``to_hz`` by firmware-core (``len(x) *
    to_hz / from_hz`` samples, which must be whole; the record is taken as periodic, as
    ``scipy.signal.resample``)."""
    return _vibcam.upsample(
        _vector("x", x), _number("from_hz", from_hz, positive=True), _number("to_hz", to_hz, positive=True)
    )


_INTERVAL_COLUMNS = [
    f"{q}_{p}" for q in ("f_hz", "damping", "amplitude") for p in ("u", "lo", "hi")
]
_MODES_COLUMNS = (
    "system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr,method".split(",")
    + _INTERVAL_COLUMNS
)
_SHAPES_COLUMNS = "mode,target,x_px,y_px,re,im,abs,method,abs_u".split(",")


@_dataclass
class AnalysisResult:
    """What an output-only analysis found (``host-harness analyze`` without ``--accel``).

    ``modes``: dict of arrays, one entry per mode and method (``method``: ``fdd``, ``efdd``,
    ``ssi``, and ``decay`` when the record holds free decays; ``mode``, ``band_lo_hz``, ``band_hi_hz``, ``f_hz``, ``amplitude``, ``damping``,
    NaN where a method gives none; and each estimate's standard uncertainty and 95 % interval,
    ``f_hz_u``, ``f_hz_lo``, ``f_hz_hi`` and the same of ``damping`` and ``amplitude``, NaN
    where not estimated); ``shapes``: complex ``(modes, K)``, the row of each mode,
    normalised (largest component 1); ``shapes_abs_u``: the standard uncertainty of each
    component's magnitude; ``targets``: the target numbers of the columns (targets
    left out are named in ``left_out``); ``first_xy``: each target's position in the first
    frame; ``svd_freq_hz``, ``svd``: the singular values of the cross-spectral matrix per line;
    ``displacement``: ``(N, all targets)`` in ``unit`` (mm with ``mm_per_px``, else px; lost
    frames filled, NaN for a target left out); ``lost``: which frames were filled; ``report``:
    the text of ``report.txt`` after its header (the page's header names the call, the inputs'
    SHA-256 and the settings); ``evidence``: per mode (the rows of ``modes``), how it was
    found (a peak's prominence and bell, an SSI cluster's size, spread, MPC and MPD);
    ``rejected``: the peaks and SSI clusters not taken for modes, each with its reason (without
    bands). From :func:`modal`: ``lost`` is ``None`` and ``filled`` counts each column's
    filled samples (a displacement file says how many, not which); ``first_xy`` is NaN where
    the file gives no position; ``fps`` is the sample rate; with several setups the columns
    are the global points and ``setups`` holds each setup's part in each mode PoSER merged
    (dicts: ``method``, ``mode``, ``setup``, ``f_hz``, ``damping``, ``scale`` (complex: its
    shape's factor onto setup 1's at the references), ``reference_mac``). ``videos``: the
    paths of each mode's magnified video (:func:`analyze` with ``magnify_dir``).
    """

    modes: dict
    shapes: _np.ndarray
    targets: _np.ndarray
    first_xy: _np.ndarray
    svd_freq_hz: _np.ndarray
    svd: _np.ndarray
    displacement: _np.ndarray
    lost: _np.ndarray
    unit: str
    fps: float
    report: str
    left_out: list = _field(default_factory=list)
    notes: list = _field(default_factory=list)
    shapes_abs_u: _Optional[_np.ndarray] = None
    evidence: list = _field(default_factory=list)
    rejected: list = _field(default_factory=list)
    html: str = _field(default="", repr=False)
    camera_motion: _Optional[_np.ndarray] = None
    filled: _Optional[list] = None
    setups: list = _field(default_factory=list)
    videos: list = _field(default_factory=list)

    def _repr_html_(self) -> str:
        """The page of ``analyze``'s ``report.html`` (the frame with the targets, the modes,
        the MAC, the shapes animated), shown inline by a notebook."""
        return self.html

    def modes_rows(self) -> list:
        """The rows of ``modes.csv`` (dicts; ``None`` for an empty cell)."""
        rows = []
        m = self.modes
        for i in range(len(m["method"])):
            def opt(v: float) -> _Optional[float]:
                return None if _np.isnan(v) else float(v)

            rows.append(
                {
                    "system": "vision",
                    "target": None,
                    "mode": int(m["mode"][i]),
                    "band_lo_hz": opt(m["band_lo_hz"][i]),
                    "band_hi_hz": opt(m["band_hi_hz"][i]),
                    "f_hz": float(m["f_hz"][i]),
                    "amplitude": opt(m["amplitude"][i]),
                    "damping": opt(m["damping"][i]),
                    "e2pr": None,
                    "method": m["method"][i],
                    **{c: opt(m[c][i]) for c in _INTERVAL_COLUMNS},
                }
            )
        return rows

    def shapes_rows(self) -> list:
        """The rows of ``shapes.csv`` (dicts)."""
        rows = []
        for i, method in enumerate(self.modes["method"]):
            for j, t in enumerate(self.targets):
                c = self.shapes[i, j]
                x, y = self.first_xy[j]
                rows.append(
                    {
                        "mode": int(self.modes["mode"][i]),
                        "target": int(t),
                        "x_px": None if _np.isnan(x) else float(x),
                        "y_px": None if _np.isnan(y) else float(y),
                        "re": float(c.real),
                        "im": float(c.imag),
                        "abs": float(abs(c)),
                        "method": method,
                        "abs_u": None if _np.isnan(self.shapes_abs_u[i, j])
                        else float(self.shapes_abs_u[i, j]),
                    }
                )
        return rows

    def to_pandas(self) -> tuple:
        """``(modes, shapes)`` as pandas DataFrames with the columns of ``modes.csv`` and
        ``shapes.csv`` (pandas must be installed)."""
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("to_pandas needs pandas: pip install pandas") from e
        return (
            pd.DataFrame(self.modes_rows(), columns=_MODES_COLUMNS),
            pd.DataFrame(self.shapes_rows(), columns=_SHAPES_COLUMNS),
        )

    def shape(self, mode: int, method: str = "ssi") -> _np.ndarray:
        """The complex shape of mode ``mode`` (1-based) by ``method``."""
        for i, (m, n) in enumerate(zip(self.modes["method"], self.modes["mode"])):
            if m == method and n == mode:
                return self.shapes[i]
        raise KeyError(f"no mode {mode} by {method}")


def analyze(
    frames: _Any,
    points: _Any = None,
    *,
    targets: _Optional[int] = None,
    fps: _Optional[float] = None,
    tracker: str = "auto",
    threshold: _Union[int, str, None] = None,
    retime: bool = False,
    search_px: _Optional[int] = None,
    gate_px: _Optional[float] = None,
    roi: _Optional[_Sequence[int]] = None,
    mm_per_px: _Optional[float] = None,
    axis: str = "y",
    invert: bool = False,
    lost_frames: str = "interpolate",
    window: str = "hann",
    nperseg: _Optional[int] = None,
    noverlap: _Optional[int] = None,
    nfft: _Optional[int] = None,
    detrend: str = "constant",
    bands: _Optional[_Sequence[_Sequence[float]]] = None,
    reference: _Any = None,
    camera_model: _Optional[str] = None,
    scale: _Optional[_Sequence] = None,
    target_size_mm: _Optional[float] = None,
    world: _Any = None,
    geometry: _Optional[_PathLike] = None,
    magnify_dir: _Optional[_PathLike] = None,
    magnify_px: float = 4.0,
) -> AnalysisResult:
    """Output-only modal analysis of the targets in ``frames`` (FDD, EFDD and SSI-cov on their
    displacements), exactly as ``host-harness analyze`` without ``--accel`` (the same numbers as
    its ``modes.csv`` and ``shapes.csv``).

    Frames and targets as :func:`track`; ``fps`` is needed unless a camera file states it.
    ``mm_per_px`` scales the displacement (else pixels); ``axis`` ``"y"`` (positive up) or
    ``"x"``; ``invert`` flips the sign; ``lost_frames`` ``"interpolate"`` or ``"hold"``; the
    Welch settings of the cross-spectral matrix as :func:`frf` (default: the command line's);
    ``bands``: ``[(lo, hi), ...]`` Hz, one mode per band (default: peaks picked).
    ``reference``, ``camera_model``, ``scale``, ``target_size_mm``, ``world``: the camera's
    motion removed and the scale from the scene, as :func:`track` (``camera_motion`` in the
    result; a scale other than ``mm_per_px`` makes the values mm). ``geometry``: a CSV of the structure's nodes (``node,x_mm,y_mm`` or ``node,x_px,y_px``)
    and lines (``from,to``) on which the page draws the shapes (docs/cli.md, "Geometry").
    ``magnify_dir``: a folder (created) for each mode's magnified video as ``analyze
    --magnify-px`` writes it (``magnified_<method>_<mode>.webm``, through the ``ffmpeg``
    program; the point moving most moves ``magnify_px`` pixels); their paths in ``videos``, the
    videos and each mode's displacement field on the page. More than 48 targets (a dense field,
    :func:`region_points`) are identified on 12 reference channels, each shape carried to
    every target.
    """
    call = _call(analyze, locals())
    d = _vibcam.analyze(
        _frames(frames),
        _tracking(points, targets, tracker, threshold, fps, retime, search_px, gate_px, roi),
        mm_per_px=_setting("analyze", "mm_per_px", mm_per_px, optional=True),
        axis=axis,
        invert=invert,
        lost_frames=lost_frames,
        window=window,
        nperseg=_setting("analyze", "nperseg", nperseg, optional=True),
        noverlap=_setting("analyze", "noverlap", noverlap, optional=True),
        nfft=_setting("analyze", "nfft", nfft, optional=True),
        detrend=detrend,
        bands=None if bands is None else _bands(bands),
        view=_view(reference, camera_model, scale, target_size_mm, world),
        geometry=None if geometry is None else _os.fspath(geometry),
        magnify=None if magnify_dir is None else (
            _os.fspath(magnify_dir), _setting("analyze", "magnify_px", magnify_px)),
        call=call,
    )
    motion = d["camera_motion"] if reference is not None else None
    return _result(AnalysisResult, d, camera_motion=motion)


@_dataclass
class EmaResult:
    """What an experimental modal analysis found (``host-harness ema``).

    ``modes``: dict of arrays, one entry per mode (``mode``, ``f_hz``, ``damping`` (the
    exponential window's damping removed), ``band_lo_hz``, ``band_hi_hz`` (NaN without bands),
    and the standard uncertainty and 95 % interval of each, ``f_hz_u``, ``f_hz_lo``,
    ``f_hz_hi``, ``damping_u``, ``damping_lo``, ``damping_hi``, NaN where not estimated);
    ``shapes``: complex ``(modes, responses)``, the LSFD residues normalised (largest
    component 1); ``shapes_abs_u``: the standard uncertainty of each component's magnitude;
    ``responses``: the responses' names; ``shape_points``: the point each shape column stands at
    (the responses' numbers, or a roving hammer's hit points when they outnumber the
    responses); ``freq_hz``, ``h1``, ``h2``, ``coherence``: the FRFs per response and line (a
    roving hammer's: per hit point, then per response); ``hits_left_out``: each hit of an impact test
    not used, with the reason (a double hit, a clipped force); ``notes``; ``report``: the text
    of ``report.txt`` after its header (the page's header names the call, the inputs' SHA-256
    and the settings).
    """

    modes: dict
    shapes: _np.ndarray
    shapes_abs_u: _np.ndarray
    responses: list
    freq_hz: _np.ndarray
    h1: _np.ndarray
    h2: _np.ndarray
    coherence: _np.ndarray
    report: str
    notes: list = _field(default_factory=list)
    hits_left_out: list = _field(default_factory=list)
    shape_points: list = _field(default_factory=list)
    html: str = _field(default="", repr=False)

    def _repr_html_(self) -> str:
        """The page of ``ema``'s ``report.html`` (modes, MAC, animated shapes), shown inline by
        a notebook."""
        return self.html


def ema(
    response: _Optional[_PathLike] = None,
    excitation: _Optional[_PathLike] = None,
    *,
    roving: _Optional[_Sequence[_Sequence[_Any]]] = None,
    response_cols: _Optional[_Sequence[str]] = None,
    response_fs: _Optional[float] = None,
    excitation_col: _Optional[_Union[str, _Sequence[str]]] = None,
    excitation_fs: _Optional[float] = None,
    impact: bool = False,
    exp_window: _Union[str, float] = "auto",
    block_s: _Optional[float] = None,
    delay_s: _Optional[float] = None,
    response_quantity: str = "displacement",
    bands: _Optional[_Sequence[_Sequence[float]]] = None,
    f_min_hz: _Optional[float] = None,
    f_max_hz: _Optional[float] = None,
    max_order: int = 48,
    nperseg: _Optional[int] = None,
    out: _Optional[_PathLike] = None,
    force: bool = False,
    poles: _Optional[_PathLike] = None,
    pdf: bool = False,
    geometry: _Optional[_PathLike] = None,
) -> EmaResult:
    """Experimental modal analysis of responses over a measured force, exactly as
    ``host-harness ema`` (the same numbers as its ``modes.csv`` and ``shapes.csv``).

    ``response``: ``displacement.csv`` of ``track``/``analyze``, a wide CSV, a pyidi ``.npy``
    or a DAQ file (``.lvm``, ``.tdms``, ``.uff``); ``response_cols`` picks channels by name.
    ``excitation``: the file with the force, ``excitation_col`` its channel (a list of channels:
    several forces at once, shakers, the FRF matrix by the multiple-input H1). Rates come from the
    files, else ``response_fs``/``excitation_fs``; the slower record is upsampled to the
    faster's rate. ``impact``: hits of a hammer (``exp_window`` ``"off"``, ``"auto"`` or the
    window's value at the block's end; ``block_s`` the longest block); else a continuous force
    (Welch segments of ``nperseg``). ``delay_s``: the responses' first sample after the force's (None: as the files state, else estimated from an impact's onset).
    ``poles``: a CSV with ``f_hz`` and ``damping`` columns (an earlier ``modes.csv``, edited, or
    poles picked on the stabilisation diagram): exactly these modes, their shapes by LSFD.
    ``response_quantity``: ``"displacement"``, ``"velocity"`` or ``"acceleration"``. ``bands``:
    ``[(lo, hi), ...]`` Hz, one mode per band (default: every mode the stabilisation diagram
    shows between ``f_min_hz`` and ``f_max_hz``). ``out``: also write the command's files there
    (``force`` replaces an earlier ``ema`` output; ``pdf`` prints ``report.pdf`` too, through a
    headless Chromium). ``geometry``: a CSV of the structure's nodes (``node,x_mm,y_mm`` or ``node,x_px,y_px``, a node per response)
    and lines (``from,to``) on which the page draws the shapes (docs/cli.md, "Geometry").
    ``roving``: a roving-hammer test instead of ``response`` and ``excitation``, one record per
    point hit: ``[(point, file), ...]`` (the file holding its force and responses) or
    ``[(point, responses_file, force_file), ...]``; with ``impact=True`` (docs/cli.md, ema).
    """
    call = _call(ema, locals())
    records = [] if roving is None else [_roving_record(r) for r in roving]
    if records and (response is not None or excitation is not None):
        raise ValueError("roving: instead of response and excitation, not beside them")
    if not records and (response is None or excitation is None):
        raise ValueError("response and excitation are needed (or roving, one record per hit point)")
    exp_window = _setting("ema", "exp_window", exp_window)
    if not isinstance(exp_window, str):
        exp_window = repr(exp_window)
    _setting("ema", "response_quantity", response_quantity)
    cols = [] if response_cols is None else [str(c) for c in response_cols]
    d = _vibcam.ema(
        records[0][1] if records else _os.fspath(response),
        records[0][2] if records else _os.fspath(excitation),
        roving=records,
        response_cols=cols,
        response_fs=_setting("ema", "response_fs", response_fs, optional=True),
        excitation_col=([] if excitation_col is None else [str(excitation_col)]
                        if isinstance(excitation_col, str) else [str(c) for c in excitation_col]),
        excitation_fs=_setting("ema", "excitation_fs", excitation_fs, optional=True),
        impact=bool(impact),
        exp_window=exp_window,
        block_s=_setting("ema", "block_s", block_s, optional=True),
        delay_s=_setting("ema", "delay_s", delay_s, optional=True),
        response_quantity=response_quantity,
        bands=None if bands is None else _bands(bands),
        f_min_hz=_setting("ema", "f_min_hz", f_min_hz, optional=True),
        f_max_hz=_setting("ema", "f_max_hz", f_max_hz, optional=True),
        max_order=_setting("ema", "max_order", max_order),
        nperseg=_setting("ema", "nperseg", nperseg, optional=True),
        out=None if out is None else _os.fspath(out),
        force=bool(force),
        poles=None if poles is None else _os.fspath(poles),
        pdf=bool(pdf),
        geometry=None if geometry is None else _os.fspath(geometry),
        call=call,
    )
    return _result(EmaResult, d)


def _roving_record(r: _Any) -> tuple:
    """A roving-hammer record as ``(point, responses_file, force_file)``."""
    items = list(r) if isinstance(r, (list, tuple)) else None
    if items is None or len(items) not in (2, 3):
        raise ValueError(f"roving: {r!r} is not (point, file) or (point, responses, force)")
    point = items[0]
    if isinstance(point, bool) or not isinstance(point, int) or point < 1:
        raise ValueError(f"roving: the hit point {point!r} is not a whole number from 1")
    files = [_os.fspath(f) for f in items[1:]]
    return (point, files[0], files[-1])


def modal(
    displacement: _PathLike,
    *,
    fps: _Optional[float] = None,
    axis: str = "y",
    window: str = "hann",
    nperseg: _Optional[int] = None,
    noverlap: _Optional[int] = None,
    nfft: _Optional[int] = None,
    detrend: str = "constant",
    bands: _Optional[_Sequence[_Sequence[float]]] = None,
    prominence_db: float = 6.0,
    f_min_hz: _Optional[float] = None,
    efdd_quantity: str = "auto",
    plscf: bool = False,
    ssi: str = "cov",
    ssi_block_rows: _Optional[int] = None,
    ssi_max_order: _Optional[int] = None,
    references: _Optional[_Sequence[int]] = None,
    setups: _Optional[_Sequence[_Any]] = None,
    merge: str = "poser",
    out: _Optional[_PathLike] = None,
    force: bool = False,
    poles: _Optional[_PathLike] = None,
    pdf: bool = False,
    geometry: _Optional[_PathLike] = None,
) -> AnalysisResult:
    """Output-only modal analysis of a displacement file, exactly as ``host-harness modal``
    (the same numbers as its ``modes.csv`` and ``shapes.csv``).

    ``displacement``: ``displacement.csv`` of ``track``/``analyze`` (``axis`` the image axis
    of a file without millimetres), or a wide CSV (a time column and one column per target);
    ``fps`` when it has no time column. The Welch settings as :func:`frf`; ``bands``: ``[(lo,
    hi), ...]`` Hz, one mode per band (default: peaks of at least ``prominence_db`` picked);
    ``f_min_hz`` the lowest frequency analysed; ``efdd_quantity``: what the records measure
    (``"auto"``, ``"displacement"``, ``"velocity"``, ``"acceleration"``); ``plscf``: LSCF on
    half-spectra too; ``ssi``: ``"cov"`` or ``"dat"``, with ``ssi_block_rows`` and
    ``ssi_max_order``. Several setups of one structure: ``references`` the targets of
    ``displacement`` every setup shares, ``setups`` the others as ``[(file, [targets in
    references' order]), ...]``, ``merge`` ``"poser"`` (each setup alone, merged) or
    ``"preger"`` (SSI, FDD, EFDD and pLSCF of every setup together; docs/method.md §3.12,
    "Several setups"). ``poles``: a CSV with
    ``f_hz`` and ``damping`` (poles picked on the page's stabilisation diagram, or an earlier
    ``modes.csv``): SSI's modes exactly these, each one's shape the diagram's stable pole
    nearest it. ``out``: also write the command's files there (``force`` replaces an earlier
    ``modal`` output; ``pdf`` prints ``report.pdf`` too, through a headless Chromium).
    ``geometry``: a CSV of the structure's nodes (``node,x_mm,y_mm`` or ``node,x_px,y_px``)
    and lines (``from,to``) on which the page draws the shapes (docs/cli.md, "Geometry").
    """
    call = _call(modal, locals())
    for key, v in (("efdd_quantity", efdd_quantity), ("ssi", ssi), ("merge", merge)):
        _setting("modal", key, v)
    pairs = []
    for i, s in enumerate(setups or []):
        try:
            f, targets = s
            pairs.append((_os.fspath(f), [_whole(f"setups[{i}] target", t, 1, 1 << 20)
                                          for t in targets]))
        except (TypeError, ValueError):
            raise InputError(f"setups[{i}] = {s!r}: (file, [reference targets]) is needed") \
                from None
    d = _vibcam.modal(
        _os.fspath(displacement),
        fps=None if fps is None else _number("fps", fps),
        axis=axis,
        window=window,
        nperseg=_setting("modal", "nperseg", nperseg, optional=True),
        noverlap=_setting("modal", "noverlap", noverlap, optional=True),
        nfft=_setting("modal", "nfft", nfft, optional=True),
        detrend=detrend,
        bands=None if bands is None else _bands(bands),
        prominence_db=_setting("modal", "prominence_db", prominence_db),
        f_min_hz=None if f_min_hz is None else _number("f_min_hz", f_min_hz),
        efdd_quantity=efdd_quantity,
        plscf=bool(plscf),
        ssi=ssi,
        ssi_block_rows=_setting("modal", "ssi_block_rows", ssi_block_rows, optional=True),
        ssi_max_order=_setting("modal", "ssi_max_order", ssi_max_order, optional=True),
        references=None if references is None
        else [_whole("references", t, 1, 1 << 20) for t in references],
        setups=pairs,
        merge=merge,
        out=None if out is None else _os.fspath(out),
        force=bool(force),
        poles=None if poles is None else _os.fspath(poles),
        pdf=bool(pdf),
        geometry=None if geometry is None else _os.fspath(geometry),
        call=call,
    )
    rows = [dict(r, scale=complex(*r["scale"])) for r in d["setups"]]
    return _result(AnalysisResult, d, lost=None, camera_motion=None, setups=rows)


def _result(cls, d: dict, **given: _Any):
    """The result dataclass ``cls`` from the binding's dict ``d``: each field its entry (a
    ``list`` field as a Python list), or as ``given``."""
    kw = {}
    for f in _fields(cls):
        if f.name in given:
            kw[f.name] = given[f.name]
        elif f.name in d:
            kw[f.name] = list(d[f.name]) if f.type == "list" else d[f.name]
    return cls(**kw)


def _bands(bands: _Any) -> list:
    out = []
    for i, b in enumerate(bands):
        try:
            lo, hi = b
        except (TypeError, ValueError):
            raise InputError(f"bands[{i}] = {b!r}: (lo, hi) in Hz is needed") from None
        lo, hi = _number(f"bands[{i}][0]", lo), _number(f"bands[{i}][1]", hi)
        if not 0 <= lo < hi:
            raise InputError(f"bands[{i}] = ({lo}, {hi}): 0 <= lo < hi is needed")
        out.append((lo, hi))
    return out


@_dataclass
class StudyResult:
    """A Monte Carlo study's summary: ``table`` (what ``host-harness study`` prints),
    ``summary`` (the columns of ``summary.csv`` as arrays: numbers as float arrays, NaN for an
    empty cell; text columns as lists), ``summary_csv`` (its text) and ``out`` (the directory
    holding every output, or ``None`` when it was a temporary one)."""

    table: str
    summary: dict
    summary_csv: str
    out: _Optional[str]

    def to_pandas(self) -> _Any:
        """``summary.csv`` as a pandas DataFrame."""
        import pandas as pd

        return pd.read_csv(_io.StringIO(self.summary_csv))


def _columns(text: str) -> dict:
    rows = list(_csv.reader(_io.StringIO(text)))
    header, body = rows[0], rows[1:]
    out = {}
    for j, name in enumerate(header):
        cells = [r[j] if j < len(r) else "" for r in body]
        try:
            out[name] = _np.array([float(c) if c != "" else _np.nan for c in cells])
        except ValueError:
            out[name] = cells
    return out


def study(
    config: _Optional[_PathLike] = None,
    preset: _Optional[str] = None,
    *,
    runs: _Optional[int] = None,
    exposures_ms: _Optional[_Sequence[float]] = None,
    seed: _Optional[int] = None,
    out: _Optional[_PathLike] = None,
    threads: int = 0,
    progress: bool = True,
    plots: bool = False,
) -> StudyResult:
    """Runs a Monte Carlo study (as ``host-harness study``) and returns its summary.

    ``config``: a study TOML file, or ``preset``: ``"grandstand"`` (default) or
    ``"cantilever"``; ``runs``, ``exposures_ms``, ``seed`` override it. ``out``: the directory
    of its outputs (resumed when it holds the same study's checkpoint); default: a temporary
    directory, removed afterwards. ``progress``: a progress bar on a terminal's stderr.
    """
    def run(directory: str) -> tuple:
        return _vibcam.study(
            directory,
            config=None if config is None else _os.fspath(config),
            preset=preset,
            runs=_whole("runs", runs, 1, 1_000_000, optional=True),
            exposures_ms=None
            if exposures_ms is None
            else [_number(f"exposures_ms[{i}]", e, positive=True) for i, e in enumerate(exposures_ms)],
            seed=_whole("seed", seed, 0, 2**64 - 1, optional=True),
            threads=_setting("study", "threads", threads),
            progress=progress,
            plots=plots,
        )

    if out is None:
        with _tempfile.TemporaryDirectory(prefix="vibcam-study-") as tmp:
            where = _os.path.join(tmp, "study")
            table, summary = run(where)
        # the directory is gone: the line naming the files written in it goes with it
        table = "".join(ln for ln in table.splitlines(True) if not ln.rstrip().endswith(where))
        return StudyResult(table, _columns(summary), summary, None)
    table, summary = run(_os.fspath(out))
    return StudyResult(table, _columns(summary), summary, _os.fspath(out))


def region_points(
    frame: _Any,
    region: str,
    spacing: float = 10.0,
    window_px: int = 21,
    min_texture: float = 0.05,
    direction: str = "both",
) -> _np.ndarray:
    """The windows a region of ``frame`` gives, as ``pick --region`` chooses them (docs/method.md
    §2.12): the places of a grid every ``spacing`` px inside ``region`` (``"X,Y;X,Y;..."`` a
    polygon, ``"line:X,Y;..."`` along a line, ``"brush:R:X,Y;..."`` within R px of a stroke)
    whose ``window_px`` x ``window_px`` window has at least ``min_texture`` times the region's
    best texture: the structure tensor's smaller eigenvalue (``direction="both"``, Shi-Tomasi)
    or the gradient energy along ``"x"``, ``"y"`` or an angle in degrees. Returns the kept
    centres as an ``(N, 2)`` array of ``(x, y)`` px; ``track(points=...)`` takes them with the
    window size.

    >>> frame = next(iter(vibcam.open_frames("rec.cih")))  # doctest: +SKIP
    >>> xy = vibcam.region_points(frame, "0,0;640,0;640,40;0,40", spacing=4, direction="y")  # doctest: +SKIP
    """
    if not isinstance(region, str):
        raise InputError(f"region = {region!r}: 'X,Y;X,Y;...', 'line:...' or 'brush:R:...'")
    if not isinstance(direction, str):
        raise InputError(f"direction = {direction!r}: 'both', 'x', 'y' or degrees as text")
    kept, _line = _vibcam.region_points(
        _frames(frame),
        region,
        _number("spacing", spacing, positive=True),
        _whole("window_px", window_px, 5, 255),
        _number("min_texture", min_texture),
        direction,
    )
    return _np.asarray(kept, dtype=float).reshape(-1, 2)


def open_frames(
    path: _PathLike,
    fps: _Optional[float] = None,
    retime: bool = False,
    frame_range: _Optional[str] = None,
) -> FrameReader:
    """The frames of a recording one at a time, as ``uint8``/``uint16`` arrays ``(H, W)``:
    every format the command line reads (image directories and patterns, multi-page TIFF,
    Photron ``.cih``/``.cihx`` + ``.mraw``, Phantom ``.cine``, videos through ffmpeg; colour
    as BT.601 luma). ``fps`` is needed for a video (its timestamps are checked against it).
    The reader's ``fps`` and ``count`` are known before decoding; its ``label`` names the file
    or frame last returned. ``frame_range="A..B"`` reads frames A to B only (1-based,
    inclusive; ``"A.."`` to the end): a camera file with a damaged time stamp at one end.

    >>> for frame in vibcam.open_frames("rec/frames"):  # doctest: +SKIP
    ...     print(frame.shape, frame.dtype)
    """
    if frame_range is not None and not isinstance(frame_range, str):
        raise InputError(f"frame_range = {frame_range!r}: 'A..B' (frames A to B, 1-based)")
    return FrameReader(
        _os.fspath(path),
        fps=_setting("open_frames", "fps", fps, optional=True),
        retime=retime,
        frame_range=frame_range,
    )
