"""The mip pyramid of depth moments read by area sampling (Loos & Sloan 2010, Sec. 4.2).

:class:`MomentPyramid` holds, level by level, the coverage, the mean and the central second
moment of a depth quantity q (1/z for a perspective camera, z for an orthographic one) over
the finite pixels, as Variance Shadow Maps filter the first two moments of the depth
(Donnelly & Lauritzen 2006). :func:`vobscure.vo_area` reads the mean and variance of the
depth over each sample region's screen footprint from it.

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.2 (the moments M1, M2 and the
optional prefilter). Chan, Golub & LeVeque, "Algorithms for computing the sample variance:
analysis and recommendations", The American Statistician 37(3), 1983 (the parallel update of
means and central moments).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["MomentPyramid", "PREFILTER_SIGMA"]

#: Standard deviation (pixels) of the optional Gaussian prefilter of the finest level (Sec. 4.2).
PREFILTER_SIGMA = 1.0


class MomentPyramid:
    """Mip-map of coverage, means and central second moments of a depth quantity q.

    Level 0 is the image (prefiltered or not); level L + 1 averages 2 x 2 texels of level L
    (odd sizes padded: by edge replication for ``offscreen="clamp"``, by empty texels for
    ``"open"``). Coverage is the fraction of finite pixels; means and moments are over the
    finite ones only, so background never enters an average. The moments are those of Sec.
    4.2 (M1 = E[q], M2 = E[q^2], sigma^2 = M2 - M1^2) kept as mean and central moment and
    combined with the parallel-variance update (Chan, Golub & LeVeque 1983), which equals
    M2 - M1^2 algebraically without its cancellation when sigma << mu.

    With ``positions`` the pixel-centre coordinates X, Y of the finite pixels are mipped
    along with q (means, and the 3 x 3 central moments of (q, X, Y)): what
    :meth:`lookup` needs to measure q against a plane (its ``slope``). At level 0 a pixel
    is a point (zero central moments); a texel of level L that is fully covered and not
    padded has its centre as mean position and (4^L - 1) / 12 as each axis's variance, but
    partly covered and edge-padded texels do not, so the positions are stored, not assumed.

    Parameters
    ----------
    q : (H, W) array_like of float
        The quantity per pixel; what is stored where ``finite`` is False does not matter.
    finite : (H, W) ndarray of bool
        The pixels that show a surface.
    offscreen : {"clamp", "open"}
        How odd sizes are padded and what a lookup reads off the image: the border texels
        extended outward (``"clamp"``), or empty space (``"open"``).
    prefilter : bool
        Blur level 0 with a coverage-weighted Gaussian of :data:`PREFILTER_SIGMA` pixels
        before the levels are built (Sec. 4.2).
    positions : bool, optional
        Mip the pixel-centre coordinates too, for :meth:`lookup`'s ``slope``. Default False.

    Attributes
    ----------
    top : int
        The coarsest level, 1 x 1.
    heights, widths : (top + 1,) ndarray of intp
        Each level's size in texels.
    offsets : (top + 1,) ndarray of intp
        Where each level starts in the flat channels.
    c : ndarray of float64
        Coverage of every texel of every level.
    m, v : list of ndarray of float64
        The means of q (, X, Y) and the central moments in ``_pairs`` order: qq (, qX, qY,
        XX, XY, YY). Without the prefilter every channel but the coverage and the mean of q
        starts at level 1, ``skip`` texels later (level 0's pixels are points at their
        centres).

    Examples
    --------
    >>> import numpy as np
    >>> q = np.arange(16.0).reshape(4, 4)
    >>> pyramid = MomentPyramid(q, np.ones((4, 4), bool), offscreen="clamp", prefilter=False)
    >>> pyramid.heights.tolist()
    [4, 2, 1]
    >>> cov, mean, var = pyramid.lookup(np.array([2.0]), np.array([2.0]), np.array([2.0]),
    ...                                 "clamp", "trilinear")
    >>> float(cov[0]), float(mean[0]), float(var[0])     # the image's mean and variance
    (1.0, 7.5, 21.25)
    """

    def __init__(self, q: np.ndarray, finite: np.ndarray, *, offscreen: str, prefilter: bool,
                 positions: bool = False):
        q = np.asarray(q, dtype=np.float64)
        self._build(lambda out: np.copyto(out, q), finite, offscreen=offscreen, prefilter=prefilter,
                    positions=positions)

    @classmethod
    def from_depth(cls, depth: np.ndarray, finite: np.ndarray, *, perspective: bool, offscreen: str,
                   prefilter: bool, positions: bool = False):
        """The pyramid of q = 1/z (perspective) or z, written straight into level 0 (no copy of
        the image besides the pyramid's own)."""
        def fill(out):
            np.copyto(out, depth)
            out[~finite] = 1.0
            if perspective:
                np.reciprocal(out, out=out)
        self = cls.__new__(cls)
        self._build(fill, finite, offscreen=offscreen, prefilter=prefilter, positions=positions)
        return self

    def _build(self, fill, finite, *, offscreen, prefilter, positions):
        # the levels' sizes, then one flat array per channel holding every level, filled
        # level by level (no list of levels plus a concatenated copy: half the peak memory)
        shapes = [finite.shape]
        while shapes[-1] != (1, 1):
            h, w = shapes[-1]
            shapes.append(((h + 1) // 2, (w + 1) // 2))
        self.top = len(shapes) - 1
        self.heights = np.array([h for h, _ in shapes], dtype=np.intp)
        self.widths = np.array([w for _, w in shapes], dtype=np.intp)
        sizes = self.heights * self.widths
        self.offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.intp)
        n_chan = 3 if positions else 1
        total = int(sizes.sum())
        # Without the prefilter, level 0 of the positions and of every central moment is
        # implicit: a pixel is a point at its centre (X = j + 0.5, Y = i + 0.5, no spread).
        # Those channels start at level 1 (``skip`` texels later), which saves 8 of the
        # 10 full-size channels of the clamped pyramid.
        self.skip = 0 if prefilter else int(sizes[0])
        self.c = np.empty(total)
        #: means of q (, X, Y) and central moments in ``_pairs`` order: qq (, qX, qY, XX, XY, YY)
        self.m = [np.empty(total)] + [np.empty(total - self.skip) for _ in range(n_chan - 1)]
        self.v = [np.empty(total - self.skip) for _ in _pairs(n_chan)]
        self.positions = positions
        H0, W0 = shapes[0]

        def level(L):
            a, b = self.offsets[L], self.offsets[L] + sizes[L]
            shape = shapes[L]
            if L == 0 and self.skip:
                # the implicit channels as views of no memory
                X = np.broadcast_to(np.arange(W0) + 0.5, shape)
                Y = np.broadcast_to((np.arange(H0) + 0.5)[:, None], shape)
                return self.c[a:b].reshape(shape), [self.m[0][a:b].reshape(shape), X, Y][:n_chan], \
                    [None] * len(self.v)
            m = [self.m[0][a:b].reshape(shape)] + [x[a - self.skip:b - self.skip].reshape(shape)
                                                   for x in self.m[1:]]
            return (self.c[a:b].reshape(shape), m,
                    [x[a - self.skip:b - self.skip].reshape(shape) for x in self.v])

        c0, m0, v0 = level(0)
        c0[...] = finite
        fill(m0[0])
        m0[0][~finite] = 0.0
        if prefilter:
            if positions:
                m0[1][...] = np.where(finite, np.arange(W0) + 0.5, 0.0)
                m0[2][...] = np.where(finite, (np.arange(H0) + 0.5)[:, None], 0.0)
            c, m, v = _prefilter(c0, [x.copy() for x in m0], finite, offscreen)
            c0[...] = c
            for dst, src in zip(m0 + v0, list(m) + list(v)):
                dst[...] = src
            del c, m, v
        for L in range(1, len(shapes)):
            c, m, v = _reduce(*level(L - 1), offscreen)
            cL, mL, vL = level(L)
            cL[...] = c
            for dst, src in zip(mL + vL, list(m) + list(v)):
                dst[...] = src
            del c, m, v

    def _channel(self, arr, flat, level0, virtual):
        """Texels ``flat`` of a channel stored from level 1 on; ``virtual`` where ``level0``."""
        if not self.skip:
            return arr.take(flat)
        if arr.size == 0:      # a 1 x 1 image: level 0 is the only level
            return np.zeros(flat.shape) if virtual is None else np.asarray(virtual, dtype=np.float64)
        got = arr.take(np.maximum(flat - self.skip, 0))
        if virtual is None:
            return np.where(level0, 0.0, got)
        return np.where(level0, virtual, got)

    def lookup(self, x, y, lod, offscreen, reconstruction, slope=None, ref=None, carry_to=None):
        """(coverage, mean, variance) at continuous pixel coordinates (x, y) and level ``lod``.

        Texel j of level L has its centre at (j + 0.5) 2^L in level-0 pixels. Within each
        of the levels floor(lod) and floor(lod) + 1 the texels are weighted by a tent
        (``"trilinear"``: 2 x 2 taps, bilinear) or a quadratic B-spline (``"bspline"``: 3 x 3
        taps); the two levels are blended linearly. The texels are combined as a mixture of
        distributions, each weighted by filter weight x coverage: the filtered moments
        M1, M2 of Sec. 4.2, accumulated about ``ref`` (a value near the mean, e.g. the
        pixel's own q; default the first tap's mean) so that the variance
        M2 - M1^2 loses nothing to cancellation, in one pass over the taps.

        ``slope`` = (g_x, g_y), per lookup (needs ``positions``): the moments are those of
        q - g_x (X - x) - g_y (Y - y) instead of q, each texel's depth carried along a
        plane of that gradient to the line at (x, y). A texel contributes the mean
        m_q - g . (m_XY - (x, y)) and the variance (1, -g)^T S (1, -g), S its 3 x 3 central
        moments of (q, X, Y) (exact for any content of the texel); the mixture is then
        formed as for q. On a plane of gradient g the quantity is constant: every texel
        gives the plane's value at (x, y) and zero variance, whatever the weights.
        ``carry_to`` = (x0, y0): carry the depths to this point instead of (x, y) (one probe
        of an anisotropic footprint centred at (x0, y0), see :mod:`vobscure.screenspace.area`).
        """
        if slope is not None and not self.positions:
            raise ValueError("a slope needs a pyramid built with positions=True")
        finite = np.isfinite(x) & np.isfinite(y)
        x = np.where(finite, x, -1e9)     # read empty space: weight 0 below
        y = np.where(finite, y, -1e9)
        if carry_to is None:
            x0, y0 = x, y
        else:
            x0, y0 = (np.where(finite, c, -1e9) for c in carry_to)
        L0 = np.floor(lod).astype(np.intp)
        t = lod - L0
        L1 = np.minimum(L0 + 1, self.top)
        cov = s1 = s2 = 0.0
        for L, wl in ((L0, np.where(finite, 1.0 - t, 0.0)), (L1, np.where(finite, t, 0.0))):
            scale = np.ldexp(1.0, -L)
            H, W, off = self.heights[L], self.widths[L], self.offsets[L]
            level0 = L == 0
            fx = x * scale - 0.5           # in texel-centre units of level L
            fy = y * scale - 0.5
            if offscreen == "clamp":       # clamp to edge: the border texels extend outward
                fx = np.minimum(np.maximum(fx, 0.0), W - 1)
                fy = np.minimum(np.maximum(fy, 0.0), H - 1)
            else:                          # taps off the image are empty (weight 0)
                fx = np.minimum(np.maximum(fx, -3.0), W + 2.0)
                fy = np.minimum(np.maximum(fy, -3.0), H + 2.0)
            rows = []
            for i, wy in _filter_taps(fy, reconstruction):
                ic = np.minimum(np.maximum(i, 0), H - 1)
                rows.append((ic, off + ic * W,
                             wl * (wy if offscreen == "clamp" else np.where((i >= 0) & (i < H), wy, 0.0))))
            cols = [(np.minimum(np.maximum(j, 0), W - 1),
                     wx if offscreen == "clamp" else np.where((j >= 0) & (j < W), wx, 0.0))
                    for j, wx in _filter_taps(fx, reconstruction)]
            for ic, row, wy in rows:
                for jc, wx in cols:
                    flat = row + jc
                    a = wy * wx * self.c.take(flat)
                    if slope is None:
                        mean = self.m[0].take(flat)
                        var = self._channel(self.v[0], flat, level0, None)
                    else:
                        gx, gy = slope
                        mx = self._channel(self.m[1], flat, level0, jc + 0.5)
                        my = self._channel(self.m[2], flat, level0, ic + 0.5)
                        mean = self.m[0].take(flat) - gx * (mx - x0) - gy * (my - y0)
                        qq, qx, qy, xx, xy, yy = (self._channel(s, flat, level0, None) for s in self.v)
                        var = qq - 2.0 * (gx * qx + gy * qy) + gx * gx * xx + 2.0 * gx * gy * xy + gy * gy * yy
                        var = np.maximum(var, 0.0)   # >= 0 but for rounding
                    if ref is None:
                        ref = mean.copy()
                    dm = mean - ref
                    cov = cov + a
                    s1 = s1 + a * dm
                    s2 = s2 + a * (var + dm * dm)
        safe = np.where(cov > 0, cov, 1.0)
        mu = s1 / safe
        var = np.maximum(s2 / safe - mu * mu, 0.0)
        return cov, mu + ref, var


def _pairs(d):
    """Index pairs (i <= j) of the central moments of d channels: (0, 0), (0, 1), ..., (d-1, d-1)."""
    return [(i, j) for i in range(d) for j in range(i, d)]


def _filter_taps(f, reconstruction):
    """Texel indices and weights along one axis at texel-centre coordinate ``f``.

    Tent: floor(f), floor(f) + 1 with weights 1 - u, u. Quadratic B-spline centred at f:
    j - 1, j, j + 1 (j = round(f), u = f - j in [-1/2, 1/2]) with weights (1/2 - u)^2 / 2,
    3/4 - u^2, (1/2 + u)^2 / 2. Both reproduce linear functions (the weights' mean is f);
    the B-spline's weights also have a spread (1/4) independent of u, so on a plane the
    mixture variance does not depend on the sub-texel position, while the tent's, u (1 - u),
    does.
    """
    if reconstruction == "trilinear":
        j = np.floor(f)
        u = f - j
        j = j.astype(np.intp)
        return ((j, 1.0 - u), (j + 1, u))
    j = np.floor(f + 0.5)
    u = f - j
    j = j.astype(np.intp)
    return ((j - 1, 0.5 * (0.5 - u) ** 2), (j, 0.75 - u * u), (j + 1, 0.5 * (0.5 + u) ** 2))


def _prefilter(c, m, finite, offscreen):
    """Coverage-weighted Gaussian blur of level 0 (Loos & Sloan Sec. 4.2), of every channel
    of ``m`` and of their products (the level's central moments; level 0 has none)."""
    mode = "nearest" if offscreen == "clamp" else "constant"
    blur = lambda a: ndimage.gaussian_filter(a, PREFILTER_SIGMA, mode=mode, cval=0.0)  # noqa: E731
    cb = blur(c)
    ok = cb > 1e-12
    safe = np.where(ok, cb, 1.0)
    # centred: smaller raw moments, less cancellation in E[y_i y_j] - E[y_i] E[y_j]
    refs = [a[finite].mean() if np.any(finite) else 0.0 for a in m]
    ys = [np.where(finite, a - ref, 0.0) for a, ref in zip(m, refs)]
    means = [blur(c * yy) / safe for yy in ys]
    moments = []
    for i, j in _pairs(len(m)):
        s = blur(c * ys[i] * ys[j]) / safe - means[i] * means[j]
        moments.append(np.where(ok, np.maximum(s, 0.0) if i == j else s, 0.0))
    means = [np.where(ok, mu + ref, 0.0) for mu, ref in zip(means, refs)]
    return np.where(ok, cb, 0.0), means, moments


def _reduce(c, m, v, offscreen):
    """One 2 x 2 box reduction of coverage, means ``m`` and central moments ``v`` (``_pairs`` order)."""
    H, W = c.shape
    if H % 2 or W % 2:
        pad = ((0, H % 2), (0, W % 2))
        mode = "edge" if offscreen == "clamp" else "constant"
        c = np.pad(c, pad, mode=mode)
        m = [np.pad(a, pad, mode=mode) for a in m]
        v = [None if a is None else np.pad(a, pad, mode=mode) for a in v]
    parts = [(i, j) for i in (0, 1) for j in (0, 1)]
    cs = [c[i::2, j::2] for i, j in parts]
    csum = sum(cs)
    safe = np.where(csum > 0, csum, 1.0)
    means = [sum(ck * a[i::2, j::2] for ck, (i, j) in zip(cs, parts)) / safe for a in m]
    # Chan et al.: S = sum_k c_k (S_k + (m_k - m)(m_k - m)^T) / sum_k c_k
    moments = []
    for s, (p, q) in zip(v, _pairs(len(m))):
        # s None: the texels are points (level 0 without the prefilter)
        moments.append(sum(ck * ((0.0 if s is None else s[i::2, j::2])
                                 + (m[p][i::2, j::2] - means[p]) * (m[q][i::2, j::2] - means[q]))
                           for ck, (i, j) in zip(cs, parts)) / safe)
    return 0.25 * csum, means, moments
