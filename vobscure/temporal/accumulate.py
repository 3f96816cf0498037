"""Temporal accumulation of a sequence of noisy visibility images.

One :class:`Accumulator` holds the history of a sequence: the accumulated image, the number
of frames behind each pixel, and the previous frame's G-buffer. Each :meth:`Accumulator.update`
reprojects the history into the new frame (:func:`~vobscure.temporal.reproject`), restarts
the pixels it reveals, optionally limits the history to the new frame's 3 x 3 neighbourhood,
and blends:

- ``mean``: the running mean, weight 1 / n for the n-th frame behind a pixel (with a static
  camera, exactly the mean of the frames);
- ``ema:ALPHA``: an exponential moving average, weight max(ALPHA, 1 / n) (the running mean until
  1 / n falls to ALPHA, so that a restarted pixel converges as fast as the mean at first: the
  rule of the temporal pass of SVGF's reference code, Schied et al. 2017,
  ``max(gAlpha, 1.0 / historyLength)`` with ``gAlpha = 0.2``, read in public copies of that
  shader, not in the paper's text);
- ``clip:ALPHA``: the moving average with the history first clipped to the new frame's 3 x 3
  mean +- ``gamma`` standard deviations (variance clipping, Salvi 2016, "An excursion in
  temporal supersampling", GDC talk, gamma = 1 there; for one channel the clip of the history
  towards the box is a clamp to that interval).

``clamp=True`` clamps the history to the range (min, max) of the new frame's 3 x 3 neighbours
first (the neighbourhood clamp of temporal anti-aliasing, Karis 2014, "High quality temporal
supersampling", SIGGRAPH course), in any mode. The two talks' texts were not re-read here.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .._validate import check_bool, check_choice, check_positive
from ..gbuffer import GBuffer
from .reproject import DEPTH_TOLERANCE, REPROJECT_FETCHES, reproject

__all__ = ["ACCUMULATE_MODES", "DENOISE_STEPS", "VARIANCE_GAMMA", "AccumulateSpec", "parse_accumulate",
           "Accumulator", "neighbourhood_range", "neighbourhood_moments", "HISTORY_BYTES_PER_PIXEL"]

#: The accumulation modes.
ACCUMULATE_MODES = ("mean", "ema", "clip")
#: Where the spatial denoiser (:func:`vobscure.screenspace.bilateral_blur`) runs: on each frame
#: before it is accumulated, or on the accumulated image shown (the history stays unblurred).
DENOISE_STEPS = ("before", "after")
#: Variance clipping's width in standard deviations (Salvi 2016 uses 1).
VARIANCE_GAMMA = 1.0
#: The history an accumulator keeps per pixel beyond the current and previous G-buffers: the
#: accumulated value (float64, 8 bytes) and the frame count (int32, 4 bytes).
HISTORY_BYTES_PER_PIXEL = 12


@dataclass(frozen=True)
class AccumulateSpec:
    """A parsed accumulation setting: ``mode`` of :data:`ACCUMULATE_MODES` and ``alpha`` (None
    for ``mean``)."""

    mode: str
    alpha: float | None = None

    @property
    def label(self) -> str:
        """The setting as written: ``mean``, ``ema:0.1``, ``clip:0.1``."""
        return self.mode if self.alpha is None else f"{self.mode}:{self.alpha:g}"


def parse_accumulate(spec) -> AccumulateSpec:
    """``"mean"``, ``"ema:ALPHA"`` or ``"clip:ALPHA"`` (0 < ALPHA <= 1) as an :class:`AccumulateSpec`.

    Examples
    --------
    >>> parse_accumulate("ema:0.1")
    AccumulateSpec(mode='ema', alpha=0.1)
    >>> parse_accumulate("mean").label
    'mean'
    """
    if isinstance(spec, AccumulateSpec):
        return spec
    if not isinstance(spec, str):
        raise ValueError(f"accumulate must be 'mean', 'ema:ALPHA' or 'clip:ALPHA', got {spec!r}")
    mode, _, rest = spec.strip().partition(":")
    check_choice(mode, "accumulate", ACCUMULATE_MODES)
    if mode == "mean":
        if rest:
            raise ValueError(f"accumulate 'mean' takes no alpha, got {spec!r}")
        return AccumulateSpec("mean")
    if not rest:
        raise ValueError(f"accumulate {mode!r} needs an alpha, as in '{mode}:0.1', got {spec!r}")
    try:
        alpha = float(rest)
    except ValueError:
        raise ValueError(f"accumulate {spec!r}: the alpha {rest!r} is not a number") from None
    if not 0.0 < alpha <= 1.0:
        raise ValueError(f"accumulate {spec!r}: alpha must be in (0, 1], got {alpha:g}")
    return AccumulateSpec(mode, alpha)


def neighbourhood_range(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) over each pixel's 3 x 3 neighbourhood of the finite values of ``image`` (NaN
    pixels are skipped; NaN where a neighbourhood has no finite value)."""
    finite = np.isfinite(image)
    lo = ndimage.minimum_filter(np.where(finite, image, np.inf), size=3, mode="nearest")
    hi = ndimage.maximum_filter(np.where(finite, image, -np.inf), size=3, mode="nearest")
    none = ~np.isfinite(lo)
    lo[none] = np.nan
    hi[none] = np.nan
    return lo, hi


def neighbourhood_moments(image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean, standard deviation) over each pixel's 3 x 3 neighbourhood of the finite values of
    ``image`` (population moments; NaN where a neighbourhood has no finite value)."""
    finite = np.isfinite(image)
    v = np.where(finite, image, 0.0)
    n = ndimage.uniform_filter(finite.astype(np.float64), size=3, mode="nearest")
    s1 = ndimage.uniform_filter(v, size=3, mode="nearest")
    s2 = ndimage.uniform_filter(v * v, size=3, mode="nearest")
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(n > 0, s1 / n, np.nan)
        var = np.where(n > 0, s2 / n - mean * mean, np.nan)
    return mean, np.sqrt(np.maximum(var, 0.0))


class Accumulator:
    """The temporal accumulation of one sequence of visibility images.

    Parameters
    ----------
    accumulate : str or AccumulateSpec
        ``"mean"``, ``"ema:ALPHA"`` or ``"clip:ALPHA"`` (see the module's description).
    clamp : bool
        Clamp the history to the new frame's 3 x 3 range before blending (default False).
    reproject : bool
        True (default): the history follows the surfaces (:func:`~vobscure.temporal.reproject`)
        and revealed pixels restart. False: the history is used in place, pixel for pixel
        (what a moving camera without reprojection shows: ghosting).
    fetch : {"bilinear", "nearest"}
        How the history is read at the reprojected position.
    depth_tolerance : float
        The same-surface test of the reprojection.
    gamma : float
        Variance clipping's width in standard deviations (``clip`` only).
    denoise : {None, "before", "after"}
        Run :func:`vobscure.screenspace.bilateral_blur` on each new frame before accumulating
        it, or on the accumulated image returned (the history itself stays unblurred).
    denoise_options : dict, optional
        Keywords of :func:`~vobscure.screenspace.bilateral_blur` (default its defaults).

    Attributes
    ----------
    history : (H, W) float64 or None
        The accumulated image after the last update (unblurred); None before the first.
    count : (H, W) int32 or None
        Frames behind each pixel's history (0 on background).
    seconds : float
        Time spent in :meth:`update` (reprojection, clamping and blending; not the denoiser).

    Examples
    --------
    A static camera and the running mean: the mean of the frames.

    >>> import numpy as np, vobscure as vo
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), vo.Camera.look_at((0, 2, 1), (0, 0, 0), size=(4, 4)))
    >>> acc = vo.temporal.Accumulator("mean")
    >>> for x in (0.2, 0.4, 0.9):
    ...     out = acc.update(np.where(gb.valid, x, np.nan), gb)
    >>> round(float(np.nanmax(out)), 12), int(acc.count.max())
    (0.5, 3)
    """

    def __init__(self, accumulate="mean", *, clamp: bool = False, reproject: bool = True,
                 fetch: str = "bilinear", depth_tolerance: float = DEPTH_TOLERANCE,
                 gamma: float = VARIANCE_GAMMA, denoise=None, denoise_options=None):
        self.spec = parse_accumulate(accumulate)
        self.clamp = check_bool(clamp, "clamp")
        self.reproject = check_bool(reproject, "reproject")
        self.fetch = check_choice(fetch, "fetch", REPROJECT_FETCHES)
        self.depth_tolerance = check_positive(depth_tolerance, "depth_tolerance")
        self.gamma = check_positive(gamma, "gamma")
        if denoise is not None:
            check_choice(denoise, "denoise", DENOISE_STEPS)
        self.denoise = denoise
        self.denoise_options = dict(denoise_options or {})
        self.reset()

    def reset(self) -> None:
        """Forget the history (the next update starts a new sequence)."""
        self.history = None
        self.count = None
        self._previous = None
        self.seconds = 0.0
        self.frames = 0

    def set_history(self, history, count, gbuffer) -> None:
        """Start from a given history: the accumulated image ``history`` (H, W) of ``gbuffer``'s
        frame and its frame counts ``count`` (H, W) (e.g. to resume a sequence, or to time one
        update from a known state)."""
        if not isinstance(gbuffer, GBuffer):
            raise ValueError(f"gbuffer must be a vobscure.GBuffer, got {type(gbuffer).__name__}")
        gb = gbuffer.inner()
        h = np.array(history, dtype=np.float64)
        n = np.array(count)
        if h.shape != gb.shape or n.shape != gb.shape:
            raise ValueError(f"history and count must have the G-buffer's shape {gb.shape}, got {h.shape} and {n.shape}")
        if not np.issubdtype(n.dtype, np.integer) or (n < 0).any():
            raise ValueError("count must hold integers >= 0")
        self.history, self.count, self._previous = h, n.astype(np.int32), gb

    def _blur(self, image, gbuffer):
        from ..screenspace.blur import bilateral_blur

        return bilateral_blur(image, gbuffer, **self.denoise_options)

    def update(self, image, gbuffer) -> np.ndarray:
        """Accumulate the next frame and return the accumulated image.

        Parameters
        ----------
        image : (H, W) array_like of float
            This frame's visibility (NaN on background), of ``gbuffer``'s inner frame.
        gbuffer : GBuffer
            This frame's G-buffer (its camera, depth and normals drive the reprojection; its
            :attr:`~vobscure.GBuffer.motion` when it has motion vectors).

        Returns
        -------
        (H, W) float64
            The accumulated visibility (blurred when ``denoise="after"``); NaN on background.
        """
        if not isinstance(gbuffer, GBuffer):
            raise ValueError(f"gbuffer must be a vobscure.GBuffer, got {type(gbuffer).__name__}")
        gb = gbuffer.inner()
        x = np.asarray(image, dtype=np.float64)
        if x.shape != gb.shape:
            raise ValueError(f"image must have the G-buffer's shape {gb.shape}, got {x.shape}")
        if np.isinf(x).any():
            raise ValueError("image must be finite (NaN on background), got +-inf")
        if self.denoise == "before":
            x = self._blur(x, gb)
        t0 = time.perf_counter()
        fresh = np.isfinite(x)
        restart = np.where(fresh, x, np.nan)
        if self.history is None or (not self.reproject and self.history.shape != x.shape):
            # the first frame (or an in-place history of another shape): the frame itself
            out, n = restart, fresh.astype(np.int32)
        else:
            if self.reproject:
                r = reproject(self.history, gb, self._previous, count=self.count, fetch=self.fetch,
                              depth_tolerance=self.depth_tolerance)
                prev, n_prev, ok = r.value, r.count, r.found & fresh
            else:
                prev, n_prev = self.history, self.count
                ok = fresh & np.isfinite(prev)
            prev = self._limit(prev, x)
            n = np.where(ok, n_prev + 1, fresh).astype(np.int32)
            w = 1.0 / np.maximum(n, 1)
            if self.spec.alpha is not None:
                w = np.maximum(self.spec.alpha, w)
            with np.errstate(invalid="ignore"):
                out = np.where(ok, prev + w * (x - prev), restart)
        self.history, self.count, self._previous = out, n, gb
        self.seconds += time.perf_counter() - t0
        self.frames += 1
        return self._blur(out, gb) if self.denoise == "after" else out.copy()

    def _limit(self, prev: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The history clamped to the new frame's 3 x 3 range and/or variance-clipped."""
        if self.clamp:
            lo, hi = neighbourhood_range(x)
            prev = np.where(np.isfinite(lo), np.clip(prev, lo, hi), prev)
        if self.spec.mode == "clip":
            mean, std = neighbourhood_moments(x)
            lo, hi = mean - self.gamma * std, mean + self.gamma * std
            prev = np.where(np.isfinite(mean), np.clip(prev, lo, hi), prev)
        return prev
