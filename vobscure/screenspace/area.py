"""Area sampling of Volumetric Obscurance (Loos & Sloan 2010, Sec. 4.2, 4.3, 4.4).

Each disk sample stands for its Voronoi region of the disk. Over the screen area the region
covers, the depth buffer is summarized by the mean and variance of its depth (the first two
moments, filtered in a mip-map as in Variance Shadow Maps); the occupancy along the sample's
line is then no longer a step at one depth but the probability that the surface lies behind
each point of the line, and its integral over the sphere's segment has a closed form.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import ndimage, special
from scipy.spatial import cKDTree

from .._validate import check_choice
from ..patterns import DISK_GRID, SamplePattern, _grid
from . import _common as C
from .line import _falloff_integral

__all__ = ["vo_area", "area_integral", "MODELS"]

#: Statistical models of the depth over an area sample (Loos & Sloan Sec. 4.2, footnote 3).
MODELS = ("box", "gaussian")
#: Standard deviations below this (line coordinates, sphere radius 1) are a step: the box
#: and Gaussian integrals differ from the step's by at most sigma / 2 (box) or
#: sigma / sqrt(2 pi) (Gaussian), i.e. by less than 1e-9 of the segment, so the switch is
#: continuous to that level, and 1 / (2 sigma) stays far from overflow.
SIGMA_STEP = 1e-9
#: The Gaussian visibility 0.5 erfc(x) is 1 or 0 to double precision beyond |x| > 6
#: (0.5 erfc(6) = 1.1e-17): the integral is split there into a constant part and a bounded one.
GAUSS_X_MAX = 6.0
#: Intervals narrower than this in x = (z - mu) / (sigma sqrt 2) are integrated by 8-point
#: Gauss-Legendre quadrature (error < 1e-15 of the integral for |x1 - x0| <= 0.5, the
#: 16th derivative of erfc being below 1e9); wider ones by the closed form, whose
#: differences of antiderivatives would cancel catastrophically on narrow intervals (a
#: large sigma: the antiderivatives are O(1) but scaled by sigma^3).
GAUSS_NARROW = 0.5
#: Standard deviation (pixels) of the optional Gaussian prefilter of the finest level (Sec. 4.2).
PREFILTER_SIGMA = 1.0

_SQRT2 = np.sqrt(2.0)
_SQRTPI = np.sqrt(np.pi)
_GL2 = 1.0 / np.sqrt(3.0)                  # 2-point Gauss-Legendre nodes +-1/sqrt(3), weights 1
_GL8_T, _GL8_W = np.polynomial.legendre.leggauss(8)


# --- the integrals along one line ---------------------------------------------------------

def _erfc_antiderivatives(x):
    """I_n(x) = int x^n erfc(x) dx for n = 0, 1, 2 (each up to a constant).

    I_0 = x erfc(x) - exp(-x^2) / sqrt(pi); I_1 = (x^2/2 - 1/4) erfc(x) - x exp(-x^2) / (2 sqrt(pi));
    I_2 = (x^3/3) erfc(x) - (x^2 + 1) exp(-x^2) / (3 sqrt(pi)) (integration by parts, with
    d erfc/dx = -2 exp(-x^2) / sqrt(pi); Abramowitz & Stegun 7.1.x, Ng & Geller 1969, 4.1).
    """
    e = special.erfc(x)
    g = np.exp(-x * x) / _SQRTPI
    return x * e - g, (0.5 * x * x - 0.25) * e - 0.5 * x * g, (x ** 3 / 3.0) * e - (x * x + 1.0) * g / 3.0


def _rho(z, z_s, falloff):
    return 1.0 if falloff == "constant" else z_s * z_s - z * z


def _box_part(z0, z1, mu, sigma, z_s, falloff):
    """int_{z0}^{z1} rho(z) v(z) dz on the box's ramp, v(z) = a z + b (Loos & Sloan Sec. 4.2).

    a = -1 / (2 sigma), b = -a (mu + sigma): the integrated visibility of a depth uniform on
    [mu - sigma, mu + sigma]. [z0, z1] lies inside that interval.
    """
    if falloff == "constant":
        # V_c(z0, z1, a, b) = a (z1^2 - z0^2) / 2 + b (z1 - z0)    (Loos & Sloan Sec. 4.2),
        # factored as (z1 - z0) (a (z0 + z1) / 2 + b): no cancellation between the two terms
        return (z1 - z0) * (mu + sigma - 0.5 * (z0 + z1)) / (2.0 * sigma)
    # rho v is a cubic: the 2-point Gauss-Legendre rule integrates it exactly
    mid, half = 0.5 * (z0 + z1), 0.5 * (z1 - z0)
    out = 0.0
    for t in (-_GL2, _GL2):
        z = mid + half * t
        out = out + _rho(z, z_s, falloff) * (mu + sigma - z) / (2.0 * sigma)
    return half * out


def _gauss_part(z0, z1, mu, sigma, z_s, falloff):
    """int_{z0}^{z1} rho(z) v(z) dz, v(z) = erfc((z - mu) / (sigma sqrt 2)) / 2 (depth ~ N(mu, sigma^2)).

    Closed form through the antiderivatives of x^n erfc(x) (n <= 2; footnote 3 of Loos &
    Sloan says there is none: there is); narrow intervals (a wide Gaussian) by 8-point
    Gauss-Legendre quadrature, see GAUSS_NARROW.
    """
    k = sigma * _SQRT2
    x0 = (z0 - mu) / k
    x1 = (z1 - mu) / k
    out = np.zeros_like(x0)
    narrow = (x1 - x0) <= GAUSS_NARROW
    if np.any(narrow):
        a, b, m, kk, zs = (q[narrow] for q in (z0, z1, mu, k, z_s))
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        acc = 0.0
        for t, w in zip(_GL8_T, _GL8_W):
            z = mid + half * t
            acc = acc + w * _rho(z, zs, falloff) * 0.5 * special.erfc((z - m) / kk)
        out[narrow] = half * acc
    wide = ~narrow
    if np.any(wide):
        a, b, m, kk, zs = (q[wide] for q in (x0, x1, mu, k, z_s))
        A0, A1, A2 = _erfc_antiderivatives(a)
        B0, B1, B2 = _erfc_antiderivatives(b)
        if falloff == "constant":
            # int 0.5 erfc((z - mu) / k) dz = (k / 2) [x erfc(x) - exp(-x^2) / sqrt(pi)]
            out[wide] = 0.5 * kk * (B0 - A0)
        else:
            # z = mu + k x: rho = (z_s^2 - mu^2) - 2 mu k x - k^2 x^2
            out[wide] = 0.5 * kk * ((zs * zs - m * m) * (B0 - A0) - 2.0 * m * kk * (B1 - A1)
                                    - kk * kk * (B2 - A2))
    return out


def _visible_integral(lo, hi, mu, sigma, z_s, model, falloff):
    """int_lo^hi rho(z) v(z) dz, v(z) = P(surface depth > z) under the model (lo <= hi)."""
    lo, hi, mu, sigma, z_s = np.broadcast_arrays(*(np.asarray(q, dtype=np.float64)
                                                  for q in (lo, hi, mu, sigma, z_s)))
    step = ~(sigma >= SIGMA_STEP)          # also catches NaN
    s = np.where(step, 1.0, sigma)
    h = s if model == "box" else GAUSS_X_MAX * _SQRT2 * s    # half-width of the support
    zc = np.clip(mu, lo, hi)
    z0 = np.where(step, zc, np.clip(mu - h, lo, hi))
    z1 = np.where(step, zc, np.clip(mu + h, lo, hi))
    # in front of the distribution v = 1: V_c(z_min, z_max) = z_max - z_min (Sec. 4.2; rho's
    # integral for the quadratic falloff). With a step (sigma -> 0) this is all there is:
    # the line integral max(min(z_s, d_r) + z_s, 0) of Sec. 4.1.
    out = np.array(_falloff_integral(lo, z0, z_s, falloff), dtype=np.float64)
    ramp = ~step & (z1 > z0)
    if np.any(ramp):
        args = (z0[ramp], z1[ramp], mu[ramp], s[ramp], z_s[ramp], falloff)
        out[ramp] += _box_part(*args) if model == "box" else _gauss_part(*args)
    return out


def area_integral(lo, hi, mu, sigma, z_s, *, model: str = "box", falloff: str = "constant",
                  mu_back=None, sigma_back=None):
    """Unoccupied and total integrals of rho along one segment, for a depth distribution.

    The surface's depth along the line is distributed with mean ``mu`` and standard
    deviation ``sigma`` (line coordinates of the unit sphere): uniformly on
    [mu - sigma, mu + sigma] (``"box"``, Loos & Sloan's Fig. 3) or normally (``"gaussian"``).
    A point z of the segment [lo, hi] is unoccupied with probability v(z) = P(depth > z).
    With the thickness model (Sec. 4.3) the back of the surface is distributed with
    ``mu_back``, ``sigma_back`` and z is also unoccupied behind it: the integral is computed
    twice, "once with the usual visibility function, and again with 1 - visibility function
    shifted back", and summed. As sigma -> 0 this is :func:`vobscure.screenspace.line.line_integral`.

    Parameters
    ----------
    lo, hi : array_like
        Segment ends (hi < lo means empty).
    mu, sigma : array_like
        Finite mean and standard deviation (>= 0) of the surface depth.
    z_s : array_like
        Half-length of the sphere's full segment (for the quadratic falloff rho = z_s^2 - z^2).
    model : {"box", "gaussian"}
    falloff : {"constant", "quadratic"}
    mu_back, sigma_back : array_like, optional
        The back surface's distribution; None: no thickness model.

    Returns
    -------
    unoccupied, total : ndarray

    Examples
    --------
    >>> u, t = area_integral(-1.0, 1.0, 0.0, 0.5, 1.0)   # a box centred on the point
    >>> float(u), float(t)
    (1.0, 2.0)
    """
    check_choice(model, "model", MODELS)
    check_choice(falloff, "falloff", C.FALLOFFS)
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.maximum(np.asarray(hi, dtype=np.float64), lo)
    total = _falloff_integral(lo, hi, z_s, falloff)
    unocc = _visible_integral(lo, hi, mu, sigma, z_s, model, falloff)
    if mu_back is not None:
        # + int rho (1 - v_back): what lies behind the surface's back is empty (Sec. 4.3)
        unocc = unocc + (total - _visible_integral(lo, hi, mu_back, sigma_back, z_s, model, falloff))
    return unocc, total + np.zeros_like(unocc)


# --- the moments mip-map -------------------------------------------------------------------

@lru_cache(maxsize=32)
def _region_areas_cached(key: bytes, n: int) -> np.ndarray:
    points = np.frombuffer(key, dtype=np.float64).reshape(n, 2)
    if n == 1:
        return np.array([np.pi])
    cells = _grid(2, DISK_GRID)
    _, owner = cKDTree(points).query(cells)
    area = np.bincount(owner, minlength=n) * (2.0 / DISK_GRID) ** 2
    # a region that no grid cell falls into (coincident points) still gets one cell
    return np.maximum(area, (2.0 / DISK_GRID) ** 2)


def region_areas(pattern: SamplePattern) -> np.ndarray:
    """Areas (n,) of the samples' Voronoi regions in the unit disk (sum pi), discrete as in Sec. 4.5."""
    return _region_areas_cached(np.ascontiguousarray(pattern.points).tobytes(), pattern.n)


class _Pyramid:
    """Mip-map of (coverage, mean, central second moment) of a depth quantity q.

    Level 0 is the image (prefiltered or not); level L + 1 averages 2 x 2 texels of level L
    (odd sizes padded: by edge replication for ``offscreen="clamp"``, by empty texels for
    ``"open"``). Coverage is the fraction of finite pixels; mean and variance are over the
    finite ones only, so background never enters an average. The moments are those of Sec.
    4.2 (M1 = E[q], M2 = E[q^2], sigma^2 = M2 - M1^2) kept as mean and central moment and
    combined with the parallel-variance update (Chan, Golub & LeVeque 1979), which equals
    M2 - M1^2 algebraically without its cancellation when sigma << mu.
    """

    def __init__(self, q: np.ndarray, finite: np.ndarray, *, offscreen: str, prefilter: bool):
        c = finite.astype(np.float64)
        m = np.where(finite, q, 0.0)
        v = np.zeros_like(m)
        if prefilter:
            c, m, v = _prefilter(c, m, finite, offscreen)
        levels = [(c, m, v)]
        while c.shape[0] > 1 or c.shape[1] > 1:
            c, m, v = _reduce(c, m, v, offscreen)
            levels.append((c, m, v))
        self.top = len(levels) - 1
        self.heights = np.array([lv[0].shape[0] for lv in levels], dtype=np.intp)
        self.widths = np.array([lv[0].shape[1] for lv in levels], dtype=np.intp)
        self.offsets = np.concatenate([[0], np.cumsum(self.heights * self.widths)[:-1]]).astype(np.intp)
        self.c, self.m, self.v = (np.concatenate([lv[i].ravel() for lv in levels]) for i in range(3))

    def lookup(self, x, y, lod, offscreen):
        """Trilinear (coverage, mean, variance) at continuous pixel coordinates (x, y) and lod.

        Texel j of level L has its centre at (j + 0.5) 2^L in level-0 pixels; bilinear
        within levels floor(lod) and floor(lod) + 1, linear between them. The eight texels
        are mixed as a mixture of distributions weighted by filter weight x coverage.
        """
        finite = np.isfinite(x) & np.isfinite(y)
        x = np.where(finite, x, -1e9)
        y = np.where(finite, y, -1e9)
        L0 = np.floor(lod).astype(np.intp)
        t = lod - L0
        L1 = np.minimum(L0 + 1, self.top)
        taps = []
        for L, wl in ((L0, 1.0 - t), (L1, t)):
            scale = np.ldexp(1.0, -L)
            H, W, off = self.heights[L], self.widths[L], self.offsets[L]
            fx = x * scale - 0.5
            fy = y * scale - 0.5
            if offscreen == "clamp":   # clamp to edge: the border texels extend outward
                fx = np.clip(fx, 0.0, W - 1)
                fy = np.clip(fy, 0.0, H - 1)
            else:                      # taps off the image are empty (coverage 0)
                fx = np.clip(fx, -2.0, W + 1.0)
                fy = np.clip(fy, -2.0, H + 1.0)
            j0 = np.floor(fx).astype(np.intp)
            i0 = np.floor(fy).astype(np.intp)
            tx, ty = fx - j0, fy - i0
            for di, wy in ((0, 1.0 - ty), (1, ty)):
                for dj, wx in ((0, 1.0 - tx), (1, tx)):
                    i, j = i0 + di, j0 + dj
                    inside = (i >= 0) & (i < H) & (j >= 0) & (j < W) & finite
                    flat = off + np.clip(i, 0, H - 1) * W + np.clip(j, 0, W - 1)
                    a = wl * wy * wx * np.where(inside, self.c[flat], 0.0)
                    taps.append((a, self.m[flat], self.v[flat]))
        cov = sum(a for a, _, _ in taps)
        safe = np.where(cov > 0, cov, 1.0)
        mean = sum(a * m for a, m, _ in taps) / safe
        var = sum(a * (v + (m - mean) ** 2) for a, m, v in taps) / safe
        return cov, mean, var


def _prefilter(c, m, finite, offscreen):
    """Coverage-weighted Gaussian blur of level 0 (Loos & Sloan Sec. 4.2)."""
    mode = "nearest" if offscreen == "clamp" else "constant"
    ref = m[finite].mean() if np.any(finite) else 0.0
    y = np.where(finite, m - ref, 0.0)      # centred: smaller raw moments, less cancellation
    blur = lambda a: ndimage.gaussian_filter(a, PREFILTER_SIGMA, mode=mode, cval=0.0)  # noqa: E731
    cb, s1, s2 = blur(c), blur(c * y), blur(c * y * y)
    ok = cb > 1e-12
    safe = np.where(ok, cb, 1.0)
    mean = s1 / safe
    var = np.maximum(s2 / safe - mean * mean, 0.0)
    return np.where(ok, cb, 0.0), np.where(ok, mean + ref, 0.0), np.where(ok, var, 0.0)


def _reduce(c, m, v, offscreen):
    """One 2 x 2 box reduction of (coverage, mean, central moment)."""
    H, W = c.shape
    pad = ((0, H % 2), (0, W % 2))
    if H % 2 or W % 2:
        if offscreen == "clamp":
            c, m, v = (np.pad(a, pad, mode="edge") for a in (c, m, v))
        else:
            c, m, v = (np.pad(a, pad, mode="constant") for a in (c, m, v))
    parts = [(c[i::2, j::2], m[i::2, j::2], v[i::2, j::2]) for i in (0, 1) for j in (0, 1)]
    csum = sum(p[0] for p in parts)
    safe = np.where(csum > 0, csum, 1.0)
    mean = sum(p[0] * p[1] for p in parts) / safe
    var = sum(p[0] * (p[2] + (p[1] - mean) ** 2) for p in parts) / safe
    return 0.25 * csum, mean, var


# --- the estimator -------------------------------------------------------------------------

def vo_area(gbuffer, *, radius: float, samples=1, normal_clamp: bool = False, thickness=None,
            falloff: str = "constant", model: str = "box", prefilter: bool = False,
            randomize: bool = True, seed=0, offscreen: str = "clamp",
            noise_size: int = C.NOISE_SIZE) -> np.ndarray:
    """Volumetric Obscurance by area sampling (Loos & Sloan 2010, Sec. 4.2).

    Each disk sample (x, y) of the pattern stands for its Voronoi region of the unit disk,
    of area a_i (pi for a single sample: the whole disk). The depth buffer's mean mu and
    standard deviation sigma over the region's screen footprint (a_i R_px^2 pixels) are read
    from a mip-map of the depth's first two moments (as in Variance Shadow Maps) at the
    level of detail lod = log2(R_px) + log2(a_i) / 2, trilinearly at the region's centre.
    The occupancy along the line at (x, y) is then smooth: a point of the segment
    [-z_s, z_s] is unoccupied with the probability v(z) that the surface lies behind it,
    and the segment's unoccupied integral is analytic. Segments are combined as in
    :func:`vobscure.vo_line`, with the pattern's footnote-5 weights.

    Parameters
    ----------
    gbuffer : GBuffer
    radius : float
        Ball radius in world units.
    samples : int or SamplePattern
        Disk pattern, or a count for the default point-symmetric pattern
        (:func:`vobscure.patterns.disk`); 1 is the centre alone, i.e. the whole disk as one
        area sample, the paper's single-sample method.
    normal_clamp : bool
        Clip every segment at the tangent plane (Sec. 4.4).
    thickness : float, optional
        Thickness model (Sec. 4.3): the surface occupies only this world thickness.
    falloff : {"constant", "quadratic"}
        rho = 1, or rho = 1 - r^2 = z_s^2 - z^2 along the line.
    model : {"box", "gaussian"}
        The depth distribution over an area sample: ``"box"`` (the paper's): uniform on
        [mu - sigma, mu + sigma], whose integrated visibility is linear on that interval
        (Sec. 4.2, Fig. 3); ``"gaussian"``: normal N(mu, sigma^2), visibility
        erfc((z - mu) / (sigma sqrt 2)) / 2 (integrated in closed form, footnote 3).
    prefilter : bool
        Gaussian blur (sigma = ``PREFILTER_SIGMA`` px, coverage-weighted) of the finest
        level before the mip chain, against trilinear reconstruction artifacts (Sec. 4.2).
    randomize : bool
        Reflect the pattern about a random 2-D direction per pixel (Sec. 4.5).
    seed : int, Generator or None
    offscreen : {"clamp", "open"}
        Footprints off the image read the border texels, or empty space.
    noise_size : int

    Returns
    -------
    (H, W) ndarray
        Visibility (1 = open), NaN on background; float32 for a float32 G-buffer.

    Notes
    -----
    The quantity mipped is the one the line coordinate is affine in: 1/z under a
    perspective camera, where the projective warp of
    :func:`vobscure.screenspace._common.warp` is d_r = (z_p / R) (1 - z_p / d), so that
    mu_r = (z_p / R) (1 - z_p mu_w) and sigma_r = (z_p^2 / R) sigma_w exactly; z under an
    orthographic camera (mu_r = (mu - z_p) / R, sigma_r = sigma / R). 1/z is affine across
    the screen on a plane, so its box averages and their bilinear interpolation are exact
    there: on a plane, mu_r is the plane itself and only sigma_r (the plane's spread over
    the footprint) differs from zero.

    Background: the mip-map carries the fraction of finite pixels (coverage); moments are
    over those only. The uncovered share of a footprint is empty space, so a segment's
    unoccupied integral is ``coverage * U + (1 - coverage) * total``; a footprint with no
    coverage is open, as a background tap is in line sampling.

    The box of Loos & Sloan has half-width sigma (a = -1 / (2 sigma)), i.e. the standard
    deviation sigma / sqrt(3); it is kept as the paper writes it. With the thickness model,
    the back surface is the front one moved back by ``thickness`` in depth: mean through
    the warp of (mean depth + thickness), standard deviation scaled by the warp's
    derivative there (1 / (1 + t mu_w)^2 for 1/z; unchanged orthographically).

    With ``normal_clamp`` a flat surface does not read exactly 1: the depth over a
    footprint of a tilted plane spreads by sigma around the tangent plane, and the part of
    the box (or Gaussian) above the plane's centre value counts as occupied within the
    clamped segment. Unclamped, the spread is symmetric and a plane reads 0.5.

    Depth-buffer taps per pixel: 8 texels x 3 channels per sample (after building the
    mip-map, 4/3 of the image), independent of the radius.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.2 (area sampling, the V_c
    integrals), footnote 3 (the Gaussian), 4.3 (thickness), 4.4 (normal), 4.5 and
    footnote 5 (patterns and weights).
    Donnelly & Lauritzen, "Variance Shadow Maps", I3D 2006 (filtering the first two
    moments of depth).
    The antiderivative int erfc(x) dx = x erfc(x) - exp(-x^2) / sqrt(pi) (and those of
    x erfc(x), x^2 erfc(x)): Ng & Geller, "A table of integrals of the error functions",
    J. Res. NBS 73B (1969), Sec. 4.1.

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> v = vo.vo_area(gb, radius=0.3)
    >>> round(float(v[4, 4]), 6)
    0.5
    """
    px = C.prepare(gbuffer, radius)
    radius = float(radius)
    pattern = C.as_pattern(samples, 2)
    check_choice(model, "model", MODELS)
    thickness = C.check_common(offscreen=offscreen, falloff=falloff, thickness=thickness, noise_size=noise_size)
    dtype = C.out_dtype(gbuffer)
    k = len(px.index)
    if k == 0:
        return C.output(px, np.zeros(0), dtype)

    # Step 1: the moments mip-map of the quantity the line coordinate is affine in
    finite = np.isfinite(px.depth) & (px.depth > 0)
    depth = np.where(finite, px.depth, 1.0).astype(np.float64)
    q = 1.0 / depth if px.perspective else depth
    pyramid = _Pyramid(q, finite, offscreen=offscreen, prefilter=bool(prefilter))

    # Step 2: one log2 per pixel; the regions' log2 areas are per-sample constants (Sec. 4.2)
    log_r = np.log2(np.maximum(px.radius_px, np.finfo(np.float64).tiny))
    half_log_area = 0.5 * np.log2(region_areas(pattern))

    z_p = px.p[:, 2]
    noise = C.noise(px, noise_size, seed, 2, randomize)
    num = np.zeros(k)
    den = np.zeros(k)
    for s, w, hla in zip(pattern.points, pattern.weights, half_log_area):
        x, y, xy = C.disk_pixels(px, C.reflect(s, noise, k), snap=False)
        z_s = np.sqrt(np.maximum(0.0, 1.0 - np.einsum("ij,ij->i", xy, xy)))
        # lod = log2 of the footprint's side: log2(R_px) + log2(a_i) / 2
        lod = np.clip(log_r + hla, 0.0, pyramid.top)
        # Step 3: trilinear moments at the region's centre
        cov, mean, var = pyramid.lookup(x, y, lod, offscreen)
        sd = np.sqrt(var)
        # Step 4: to the line coordinate (the warp is affine in the mipped quantity)
        if px.perspective:
            mu_r = (z_p / radius) * (1.0 - z_p * mean)
            sigma_r = (z_p * z_p / radius) * sd
        else:
            mu_r = (mean - z_p) / radius
            sigma_r = sd / radius
        covered = cov > 0
        mu_r = np.where(covered, mu_r, 2.0)        # placeholder beyond every segment; weight 0
        sigma_r = np.where(covered, sigma_r, 0.0)
        mu_back = sigma_back = None
        if thickness is not None:
            if px.perspective:
                # the back at mean depth + t: w -> w / (1 + t w), slope 1 / (1 + t w)^2
                g = 1.0 / (1.0 + thickness * mean)
                mu_back = (z_p / radius) * (1.0 - z_p * mean * g)
                sigma_back = sigma_r * g * g
            else:
                mu_back = mu_r + thickness / radius
                sigma_back = sigma_r
            mu_back = np.where(covered, mu_back, 3.0)
        # Step 5: the segment (clipped at the tangent plane, Sec. 4.4) against the model
        hi = np.minimum(z_s, C.tangent_plane_line(px, xy)) if normal_clamp else z_s
        unocc, total = area_integral(-z_s, hi, mu_r, sigma_r, z_s, model=model, falloff=falloff,
                                     mu_back=mu_back, sigma_back=sigma_back)
        # the footprint's uncovered share is empty space
        unocc = cov * unocc + (1.0 - cov) * total
        # Step 6: footnote-5 weights, each segment normalized by its full length
        full = _falloff_integral(-z_s, z_s, z_s, falloff)
        ok = full > 0
        safe = np.where(ok, full, 1.0)
        num += np.where(ok, w * unocc / safe, 0.0)
        den += np.where(ok, w * total / safe, 0.0)
    vis = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    return C.output(px, np.clip(vis, 0.0, 1.0), dtype)
