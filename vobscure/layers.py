"""Solid intervals along the pixels' rays: what lies behind the first surface.

A depth buffer holds one surface per pixel, so a screen-space estimator must guess what is
behind it (everything solid, or a constant thickness). A layered G-buffer knows: along the
ray of each pixel, the view-depth intervals ``[front, back]`` inside solids (depth peeling,
Everitt 2001; the deep G-buffer of Mara et al. 2016 keeps two such layers).
:class:`SolidIntervals` is that knowledge in the form the estimators read it, whatever made it
(:func:`vobscure.render_gbuffer` with ``layers=K``, or an engine's back-face depth pass through
:meth:`vobscure.GBuffer.from_arrays`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SolidIntervals"]


class SolidIntervals:
    """The solid intervals of view depth along every pixel's ray.

    Interval m of pixel (i, j) is ``[front[m, i, j], back[m, i, j]]`` in linear view depth z
    (the G-buffer's ``depth`` convention): points of the pixel's ray (any view ray through that
    pixel position) with front <= z <= back are inside a solid. Per pixel the intervals are
    ascending and disjoint; unused slots hold ``front = back = +inf``. ``back = +inf`` with a
    finite ``front`` is a solid whose end was not seen (the ray entered it and the layers ran out):
    everything behind ``front`` is taken as solid, as a single depth buffer takes it.

    Parameters
    ----------
    front, back : (M, H, W) array_like of float
        Entry and exit depths, M >= 1 intervals per pixel.
    dtype : numpy dtype, optional
        float64 (default) or float32.

    Attributes
    ----------
    front, back : (M, H, W) float
        Read-only.
    count : int
        M, the interval slots per pixel.

    Examples
    --------
    >>> import numpy as np
    >>> front = np.array([[[1.0, np.inf]], [[3.0, np.inf]]])
    >>> back = np.array([[[2.0, np.inf]], [[np.inf, np.inf]]])
    >>> s = SolidIntervals(front, back)
    >>> s.count, s.shape
    (2, (1, 2))
    >>> s.inside(np.array([1.5, 2.5, 4.0]), np.array([0, 0, 0])).tolist()
    [True, False, True]
    """

    def __init__(self, front, back, *, dtype=np.float64):
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
            raise ValueError(f"dtype must be float32 or float64, got {self.dtype}")
        f = np.asarray(front, dtype=self.dtype)
        b = np.asarray(back, dtype=self.dtype)
        if f.ndim != 3 or f.shape[0] < 1:
            raise ValueError(f"front must have shape (M, H, W) with M >= 1, got {f.shape}")
        if b.shape != f.shape:
            raise ValueError(f"back must have the shape of front {f.shape}, got {b.shape}")
        if np.isnan(f).any() or np.isnan(b).any():
            raise ValueError("front and back must not hold NaN (use +inf for an unused slot or an unseen end)")
        if (b < f).any():
            raise ValueError("back must be >= front in every interval")
        if f.shape[0] > 1:
            with np.errstate(invalid="ignore"):
                # the next interval starts after this one ends (inf slots only at the end)
                gap = f[1:] >= b[:-1]
                unused = np.isinf(f[1:]) & np.isinf(b[1:])
            if not (gap | unused).all():
                raise ValueError("the intervals of a pixel must be ascending and disjoint "
                                 "(front[m + 1] >= back[m]), unused slots (+inf) last")
        self.front = _frozen(f)
        self.back = _frozen(b)

    @property
    def count(self) -> int:
        return int(self.front.shape[0])

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.front.shape[1:])

    def at(self, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(front, back) of shape (M, k) at the flat row-major pixel indices ``index`` (k,)."""
        M = self.count
        return self.front.reshape(M, -1)[:, index], self.back.reshape(M, -1)[:, index]

    def inside(self, z: np.ndarray, index: np.ndarray) -> np.ndarray:
        """Whether view depth ``z`` (k,) at flat pixel ``index`` (k,) lies in a solid interval."""
        f, b = self.at(np.asarray(index))
        z = np.asarray(z)
        return ((f <= z) & (z <= b)).any(axis=0)

    def astype(self, dtype) -> "SolidIntervals":
        return SolidIntervals(self.front, self.back, dtype=dtype)

    def __repr__(self) -> str:
        H, W = self.shape
        return f"SolidIntervals({self.count} per pixel, {W}x{H}, {self.dtype})"


def _frozen(a: np.ndarray) -> np.ndarray:
    a = a.view()
    a.flags.writeable = False
    return a
