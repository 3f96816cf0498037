"""Area sampling of Volumetric Obscurance (Loos & Sloan 2010, Sec. 4.2, 4.3, 4.4, 4.5).

Each disk sample stands for its Voronoi region of the disk. Over the screen area the region
covers, the depth buffer is summarized by the mean and variance of its depth (the first two
moments, filtered in a mip-map as in Variance Shadow Maps); the occupancy along the sample's
line is then the probability that the surface lies behind each point of the line, instead of
a step at one depth, and its integral over the sphere's chord has a closed form.

The paper does not number its equations; they are cited by section and content (the list is
in ``docs/screenspace.md``, "How the paper is cited").
"""

from __future__ import annotations

import warnings
from functools import lru_cache, partial

import numpy as np
from scipy import special
from scipy.spatial import cKDTree

from .._validate import as_array, check_choice
from ..patterns import DISK_GRID, SamplePattern, grid_cells
from . import _common as C
from .line import falloff_integral
# PREFILTER_SIGMA: the prefilter's width, which vo_area's docstring names
from .pyramid import PREFILTER_SIGMA, MomentPyramid  # noqa: F401

__all__ = ["vo_area", "area_integral", "region_areas", "MODELS", "RECONSTRUCTIONS"]

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
#: Gauss-Legendre quadrature (remainder (b-a)^17 (8!)^4 / (17 (16!)^3) max|f^(16)| < 1e-19
#: in x for b - a <= 0.5, as |d^16 erfc / dx^16| < 3e8); wider ones by the closed form,
#: whose differences of antiderivatives would cancel catastrophically on narrow intervals
#: (a wide Gaussian: the antiderivatives are O(1) but scaled by up to sigma^3). Wide
#: intervals imply sigma < 2 (z1 - z0), at most 4 on the unit sphere's segments, and
#: |x| <= GAUSS_X_MAX, so the closed form's terms stay O(1).
GAUSS_NARROW = 0.5
#: Pixels per chunk of :func:`vo_area` (see the comment at its ``run_chunks`` call).
AREA_CHUNK_PIXELS = 8192

#: Reconstructions of the moments between texels and levels (see ``MomentPyramid.lookup``).
RECONSTRUCTIONS = ("bspline", "trilinear")
#: Subtracted from log2 of the footprint's side to pick the level. At level L the
#: B-spline's footprint has, on a plane, the second moments of a square of side 2^(L+1)
#: (texel variance h^2/12 plus tap spread h^2/4 = (2h)^2/12, h = 2^L): one level finer
#: makes it the region's. The tent's spread varies across a texel; the paper's (and GPU
#: hardware's) convention lod = log2(side) is kept for it.
LOD_BIAS = {"bspline": 1.0, "trilinear": 0.0}

_SQRT2 = np.sqrt(2.0)
_SQRTPI = np.sqrt(np.pi)
_GL2 = 1.0 / np.sqrt(3.0)                  # 2-point Gauss-Legendre nodes +-1/sqrt(3), weights 1
_GL8_T, _GL8_W = np.polynomial.legendre.leggauss(8)


# --- the integrals along one line ---------------------------------------------------------

def _erfc_antiderivatives(x):
    """I_n(x) = int x^n erfc(x) dx for n = 0, 1, 2 (each up to a constant).

    I_0 = x erfc(x) - exp(-x^2) / sqrt(pi); I_1 = (x^2/2 - 1/4) erfc(x) - x exp(-x^2) / (2 sqrt(pi));
    I_2 = (x^3/3) erfc(x) - (x^2 + 1) exp(-x^2) / (3 sqrt(pi)) (integration by parts, with
    d erfc/dx = -2 exp(-x^2) / sqrt(pi); see Ng & Geller 1969).
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
    out = np.array(falloff_integral(lo, z0, z_s, falloff=falloff), dtype=np.float64)
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
    shifted back", and summed. As sigma -> 0 this is
    :func:`vobscure.screenspace.line.line_integral`.

    Parameters
    ----------
    lo, hi : float or array_like
        Segment ends in line coordinates of the unit sphere (hi < lo means empty: both
        integrals 0); broadcast with the other arrays.
    mu, sigma : float or array_like
        Finite mean and standard deviation (>= 0) of the surface depth along the line, in
        line coordinates. sigma below ``SIGMA_STEP`` (1e-9, or NaN) is treated as a step at
        mu: the line integral of Sec. 4.1.
    z_s : float or array_like
        Half-length of the line's chord in the unit sphere, z_s = sqrt(1 - x^2 - y^2); only
        the quadratic falloff rho = z_s^2 - z^2 uses it.
    model : {"box", "gaussian"}, optional
        Distribution of the depth: ``"box"`` (default, the paper's Sec. 4.2) or
        ``"gaussian"`` (integrated in closed form; footnote 3).
    falloff : {"constant", "quadratic"}, optional
        The falloff rho along the line (default ``"constant"``), as in
        :func:`vobscure.screenspace.line.falloff_integral`.
    mu_back, sigma_back : float or array_like, optional
        Mean and standard deviation of the back of the surface (thickness model, Sec. 4.3),
        in line coordinates; default None: no thickness model (everything behind the
        surface is occupied). Give both or neither.

    Returns
    -------
    unoccupied, total : ndarray
        Integral of rho v (plus rho (1 - v_back) with the thickness model) over [lo, hi],
        and of rho over [lo, hi]; float64, of the broadcast shape of the inputs.

    Raises
    ------
    ValueError
        If ``model`` or ``falloff`` is not one of its values.

    Notes
    -----
    Box: v = 1 in front of mu - sigma, the ramp v(z) = a z + b on [mu - sigma, mu + sigma]
    with a = -1 / (2 sigma), b = -a (mu + sigma), 0 beyond; the integral of rho v is the
    paper's V_c(z_min, z_max) on the constant part plus V_c(z_0, z_1, a, b) on the ramp
    (quadratic falloff: 2-point Gauss-Legendre, exact for the cubic rho v). Gaussian:
    v(z) = erfc((z - mu) / (sigma sqrt 2)) / 2, integrated through the antiderivatives of
    x^n erfc(x), n <= 2; intervals narrower than ``GAUSS_NARROW`` in x use 8-point
    Gauss-Legendre quadrature (the differences of antiderivatives would cancel).

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010: Sec. 4.2 (the box model and the
    integrals V_c(z_min, z_max) = z_max - z_min and
    V_c(z_0, z_1, a, b) = a (z_1^2 - z_0^2) / 2 + b (z_1 - z_0)), footnote 3 (the Gaussian),
    Sec. 4.3 (thickness). Ng & Geller, "A table of integrals of the error functions",
    J. Res. NBS 73B (1969).

    Examples
    --------
    A box centred on the sphere's centre leaves half of the centre chord open; with sigma
    0 it is the line integral of Sec. 4.1:

    >>> u, t = area_integral(-1.0, 1.0, 0.0, 0.5, 1.0)
    >>> float(u), float(t)
    (1.0, 2.0)
    >>> float(area_integral(-1.0, 1.0, 0.25, 0.0, 1.0)[0])
    1.25
    """
    check_choice(model, "model", MODELS)
    check_choice(falloff, "falloff", C.FALLOFFS)
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.maximum(np.asarray(hi, dtype=np.float64), lo)
    total = falloff_integral(lo, hi, z_s, falloff=falloff)
    unocc = _visible_integral(lo, hi, mu, sigma, z_s, model, falloff)
    if mu_back is not None:
        # + int rho (1 - v_back): what lies behind the surface's back is empty (Sec. 4.3)
        unocc = unocc + (total - _visible_integral(lo, hi, mu_back, sigma_back, z_s, model, falloff))
    return unocc, total + np.zeros_like(unocc)


# --- the samples' regions -----------------------------------------------------------------

@lru_cache(maxsize=32)
def _region_areas_cached(key: bytes, n: int) -> np.ndarray:
    points = np.frombuffer(key, dtype=np.float64).reshape(n, 2)
    if n == 1:
        return np.array([np.pi])
    cells = grid_cells(2, DISK_GRID)
    _, owner = cKDTree(points).query(cells)
    area = np.bincount(owner, minlength=n) * (2.0 / DISK_GRID) ** 2
    # a region that no grid cell falls into (coincident points) still gets one cell
    return np.maximum(area, (2.0 / DISK_GRID) ** 2)


def region_areas(pattern: SamplePattern) -> np.ndarray:
    """Areas of the samples' Voronoi regions in the unit disk: the a_i of :func:`vo_area`.

    The regions are discrete, as in Loos & Sloan 2010, Sec. 4.5: the cells of a
    ``DISK_GRID`` x ``DISK_GRID`` grid over [-1, 1]^2 whose centres lie in the unit disk are
    assigned to their nearest sample. A single sample owns the whole disk, pi exactly.
    Results are cached per pattern (the points' bytes); a copy is returned.

    Parameters
    ----------
    pattern : SamplePattern
        A disk pattern, (n, 2) ``points`` in the unit disk.

    Returns
    -------
    (n,) ndarray of float64
        The areas, summing to about pi; each at least one grid cell, (2 / DISK_GRID)^2,
        also for a region no cell centre falls into (coincident points).

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.2 ("the logs for the fractional
    area covered by a sample are precomputed") and Sec. 4.5 (discrete Voronoi regions).

    Examples
    --------
    >>> import numpy as np
    >>> from vobscure.patterns import disk
    >>> bool(np.isclose(region_areas(disk(1))[0], np.pi))
    True
    >>> a = region_areas(disk(5))
    >>> a.shape, bool(abs(a.sum() - np.pi) < 0.01)
    ((5,), True)
    """
    return _region_areas_cached(np.ascontiguousarray(pattern.points).tobytes(), pattern.n).copy()


# --- the estimator -------------------------------------------------------------------------

@C.inner_frame
def vo_area(gbuffer, *, radius: float, samples=1, normal_clamp: bool = False, thickness=None,
            falloff: str = "constant", model: str = "box", fetch: str = "bspline",
            prefilter: bool = False, lod_bias=None, randomize: bool = True, seed=0,
            offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE, reconstruction=None, frame: int = 0,
            schedule: str = "white") -> np.ndarray:
    """Volumetric Obscurance by area sampling (Loos & Sloan 2010, Sec. 4.2).

    Each disk sample (x, y) of the pattern stands for its Voronoi region of the unit disk,
    of area a_i (pi for a single sample: the whole disk). The depth buffer's mean mu and
    standard deviation sigma over the region's screen footprint (a_i R_px^2 pixels) are read
    from a mip-map of the depth's first two moments (as in Variance Shadow Maps) at the
    level of detail lod = log2(R_px) + log2(a_i) / 2 - ``lod_bias``, filtered at the
    region's centre. The occupancy along the line at (x, y) is then smooth: a point z of
    the chord [-z_s, z_s] is unoccupied with the probability v(z) that the surface lies
    behind it, and the chord's unoccupied integral is analytic (:func:`area_integral`).
    The chords are combined as in :func:`vobscure.vo_line`, with the pattern's footnote-5
    weights in ratio form.

    Parameters
    ----------
    gbuffer : GBuffer
        The view's depth and view-space normals, as for :func:`vobscure.vo_point` (any
        pinhole or orthographic camera); the normals are read only with ``normal_clamp``.
    radius : float
        Radius R of the ball around each pixel's point, in world units (> 0).
    samples : int or SamplePattern, optional
        The disk pattern: a count n >= 1 for the default point-symmetric pattern
        ``vobscure.patterns.disk(n)``, or a :class:`~vobscure.patterns.SamplePattern` with
        (n, 2) ``points`` in the unit disk and (n,) footnote-5 ``weights``. Default 1: the
        centre alone, i.e. the whole disk as one area sample, the paper's single-sample
        method. Counts n <= 33, 64, 65, 128, 129, 256 and 257 load from the precomputed
        tables; any other count is built by the quick generator
        (:mod:`vobscure.patterns.quick`: about a second at most, once per process). n > 65536
        raises ValueError.
    normal_clamp : bool, optional
        Clip every chord at the tangent plane (Sec. 4.4); the depth distribution is then
        that of the surface relative to the tangent plane (see Notes). A flat surface reads
        1 instead of 0.5. Default False.
    thickness : float, optional
        Thickness model (Sec. 4.3): the surface occupies only this world thickness (> 0)
        behind the depth buffer. Default None: everything behind it is solid.
    falloff : {"constant", "quadratic"}, optional
        The falloff rho: ``"constant"`` (default, the paper's choice) or ``"quadratic"``,
        rho = 1 - r^2 = z_s^2 - z^2 along the line
        (:func:`vobscure.screenspace.line.falloff_integral`).
    model : {"box", "gaussian"}, optional
        The depth distribution over an area sample. ``"box"`` (default, the paper's):
        uniform on [mu - sigma, mu + sigma], whose integrated visibility is linear on that
        interval (Sec. 4.2, Fig. 3). ``"gaussian"``: normal N(mu, sigma^2), visibility
        erfc((z - mu) / (sigma sqrt 2)) / 2, integrated in closed form (footnote 3).
    fetch : {"bspline", "trilinear"}, optional
        How the mip-map is read between texel centres and levels (the depth fetch, as
        ``fetch`` of :func:`vobscure.vo_point` and :func:`vobscure.vo_line`). ``"bspline"`` (default):
        3 x 3 texels per level weighted by a quadratic B-spline, whose spread does not
        depend on the sub-texel position (Notes). ``"trilinear"``: the paper's GPU hardware
        filtering, bilinear in two levels and linear between them.
    prefilter : bool, optional
        Blur the finest level with a coverage-weighted Gaussian (sigma =
        ``PREFILTER_SIGMA`` = 1 px) before the mip chain is built, against reconstruction
        artifacts (Sec. 4.2). Default False.
    lod_bias : float, optional
        Levels subtracted from log2 of a region's footprint side when choosing the mip
        level; larger is finer. Default None: ``LOD_BIAS[fetch]``, 1 for the
        B-spline (its footprint then has the region's second moments), 0 for the trilinear
        tent (the paper's rule). Planes stay exact whatever the value; elsewhere the best
        value depends on the scene (``docs/screenspace.md``, "Level of detail").
    randomize : bool, optional
        Reflect the pattern per pixel about a random 2-D direction (Sec. 4.5), as
        :func:`vobscure.vo_line` does. Default True.
    seed : int, numpy.random.Generator or None, optional
        Seed of the random texture (default 0), as for :func:`vobscure.vo_point`.
    offscreen : {"clamp", "open"}, optional
        Footprints off the image read the border texels (``"clamp"``, default: the mip
        levels are padded by edge replication) or empty space (``"open"``).
    noise_size : int, optional
        Edge of the tiled random texture in pixels, as for :func:`vobscure.vo_point`
        (default 4). Unused without ``randomize``.
    frame, schedule : int, str, optional
        The frame (>= 0, default 0) of a noise schedule (default ``"white"``), as for
        :func:`vobscure.vo_point`; unused without ``randomize``.
    reconstruction : {"bspline", "trilinear"}, optional
        Deprecated name of ``fetch`` (a DeprecationWarning); given, it replaces ``fetch``.

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], as for :func:`vobscure.vo_point` (1 = open, NaN on
        background, float32 for a float32 G-buffer). Depth-buffer reads: see Notes.

    Raises
    ------
    ValueError
        For the arguments :func:`vobscure.vo_line` rejects, a ``lod_bias`` that is not a
        finite scalar, or a ``model`` or ``fetch`` that is not one of its values; the
        message names the argument.

    Notes
    -----
    The derivations and measurements are in ``docs/screenspace.md`` ("Area sampling"); in
    short:

    *What is mipped.* The quantity q the line coordinate is affine in: q = 1/z under a
    perspective camera, where the projective warp is d_r = (z_p / R) (1 - z_p q), so that
    mu_r = (z_p / R) (1 - z_p E[q]) and sigma_r = (z_p^2 / R) sd[q]; q = z under an
    orthographic camera (mu_r = (E[z] - z_p) / R, sigma_r = sd[z] / R). On a plane q is
    affine across the screen, so its box averages and their interpolation are exact and
    mu_r is the plane itself. Each texel holds the coverage (fraction of finite pixels) and
    the mean and central second moment of q over the finite pixels (the paper's
    M1 = E[z], M2 = E[z^2], sigma^2 = M2 - M1^2, combined by the parallel-variance update
    of Chan et al. instead of the raw M2 - M1^2). The uncovered share of a footprint is
    empty space: the unoccupied integral is coverage x U + (1 - coverage) x total.

    *Reconstruction.* On a tilted plane sigma_r is not small, and the tent of trilinear
    filtering adds u (1 - u) h^2 to the variance of a linear field, u the sub-texel
    position: the two samples of an antipodal pair see different sigmas and a plane reads
    0.5 only to about 5e-3. The B-spline's spread is constant, so point-symmetric patterns
    read 0.5 on planes up to the G-buffer's rounding. Its footprint at level L has the
    second moments of a square of side 2^(L+1), hence ``LOD_BIAS["bspline"] = 1``.

    *Box model.* The box of Sec. 4.2 has half-width sigma (a = -1 / (2 sigma)), i.e. the
    standard deviation sigma / sqrt(3); it is kept as the paper writes it.

    *Thickness.* The back surface is the front one moved back by ``thickness`` in depth:
    mean through the warp of (mean depth + thickness), standard deviation scaled by the
    warp's slope there. Under perspective the warp shortens a thickness, and the Gaussian's
    back has unbounded tails, so only the box under an orthographic camera is unchanged by
    any t >= 2R.

    *Normal clamping.* The chord is clipped at the tangent plane's value t(x, y) at the
    sample, and the depth distribution used is that of t(x, y) + r over the footprint, r
    the surface's line coordinate minus the plane's along each line: inside a clipped
    chord, occupancy depends on r only (min(t, t + r) = t + min(0, r)). On a plane r = 0,
    so a plane reads 1 at any tilt. The moments of r come from the same mip-map, which then
    also carries the pixel positions X, Y and the central moments of (q, X, Y).

    *Cameras.* Any pinhole (:meth:`vobscure.Camera.from_intrinsics`): the pixels' view rays
    use the principal point (cx, cy), and with non-square pixels (fx != fy) a region of the
    disk spans R_x = R fx / z pixels along x and R_y = R fy / z along y. The isotropic mip-map
    then reads such a footprint with n = ceil(max(fx, fy) / min(fx, fy)) lookups spread along
    its long axis, each of side sqrt(s_long s_short / n), combined as a mixture (as GPUs'
    anisotropic filtering does; ``ANISOTROPIC_FOOTPRINT`` in this module, measured there).

    Depth-buffer reads per pixel and sample: 18 texels (B-spline) or 8 (trilinear) of 3
    channels (10 with ``normal_clamp``), independent of the radius, after building the
    mip-map (4/3 of the image); n times that with non-square pixels.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010: Sec. 4.2 (area sampling: the moments
    M1 = E[z], M2 = E[z^2], sigma^2 = M2 - M1^2; the box's a = -1 / (2 sigma),
    b = -a (mu + sigma); the integrals V_c(z_min, z_max) = z_max - z_min and
    V_c(z_0, z_1, a, b) = a (z_1^2 - z_0^2) / 2 + b (z_1 - z_0); the LOD from one log2 per
    pixel plus precomputed per-sample logs), footnote 3 (the Gaussian), Sec. 4.3
    (thickness), Sec. 4.4 and footnote 4 (the tangent plane), Sec. 4.5 and footnote 5
    (randomization, patterns and weights).
    Donnelly & Lauritzen, "Variance Shadow Maps", I3D 2006 (filtering the first two
    moments of depth).
    The antiderivative int erfc(x) dx = x erfc(x) - exp(-x^2) / sqrt(pi) (and those of
    x erfc(x), x^2 erfc(x)): Ng & Geller, "A table of integrals of the error functions",
    J. Res. NBS 73B (1969).
    Chan, Golub & LeVeque, "Algorithms for computing the sample variance", The American
    Statistician 37 (1983) (combining means and central moments of parts).

    Examples
    --------
    One area sample on a plane reads 1/2 (1 with the normal):

    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> v = vo.vo_area(gb, radius=0.3)
    >>> w = vo.vo_area(gb, radius=0.3, normal_clamp=True)
    >>> round(float(v[4, 4]), 6), round(float(w[4, 4]), 6)
    (0.5, 1.0)
    """
    gb, depth64, index = C.frame(gbuffer, radius)
    radius = float(radius)
    pattern = C.as_pattern(samples, 2)
    normal_clamp = C.check_bool(normal_clamp, "normal_clamp")
    check_choice(model, "model", MODELS)
    if reconstruction is not None:
        warnings.warn("vo_area(reconstruction=...) is deprecated: use fetch=, the name of the depth fetch of "
                      "every estimator", DeprecationWarning, stacklevel=2)
        fetch = reconstruction
    reconstruction = check_choice(fetch, "fetch", RECONSTRUCTIONS)
    lod_bias = LOD_BIAS[reconstruction] if lod_bias is None else float(as_array(lod_bias, "lod_bias", shape=()))
    thickness = C.check_common(offscreen=offscreen, falloff=falloff, thickness=thickness, noise_size=noise_size)
    texture = C.noise_texture(noise_size, seed, 2, randomize, frame=frame, schedule=schedule)
    dtype = C.out_dtype(gbuffer)
    H, W = gb.depth.shape
    if len(index) == 0:
        return np.full((H, W), np.nan, dtype=dtype)

    # Step 1: the moments mip-map of the quantity the line coordinate is affine in
    depth2 = depth64.reshape(H, W)
    finite = np.isfinite(depth2) & (depth2 > 0)
    pyramid = MomentPyramid.from_depth(depth2, finite, perspective=gb.camera.is_perspective, offscreen=offscreen,
                                  prefilter=C.check_bool(prefilter, "prefilter"), positions=normal_clamp)
    # Step 2 (per sample): the regions' log2 areas are constants (Sec. 4.2)
    half_log_area = 0.5 * np.log2(region_areas(pattern))
    kernel = partial(_area_kernel, radius=radius, pattern=pattern, normal_clamp=normal_clamp,
                     thickness=thickness, falloff=falloff, model=model, reconstruction=reconstruction,
                     lod_bias=lod_bias, offscreen=offscreen, pyramid=pyramid, half_log_area=half_log_area,
                     texture=texture)
    # smaller chunks than the other estimators: a lookup holds 2 levels x 3 x 3 texels of
    # moments per pixel (measured at 512^2: 75 B/px peak with 8192 pixels, 101 with 16384)
    return C.run_chunks(gb, radius, kernel, dtype, prepared=(gb, depth64, index), chunk=AREA_CHUNK_PIXELS)


#: How an anisotropic footprint (non-square pixels, fx != fy: a region of side s spans
#: s R_x pixels along x and s R_y along y, R_x / R_y = fx / fy) is read from the isotropic
#: mip-map. "probes" (default): like a GPU's anisotropic filtering, n = ceil(N) isotropic
#: lookups (N = max(fx, fy) / min(fx, fy)) spread evenly along the long axis, each of side
#: sqrt(s_long s_short / n), their moments combined as a coverage-weighted mixture (the
#: mixture of n equal rectangles side by side has the whole rectangle's second moments).
#: "max": one lookup sized by the longer axis (conservative: never under-filters, but
#: blurs the short axis N times too much); "geometric": one lookup of side
#: sqrt(s_long s_short) (the footprint's area, but the wrong shape). Measured with fx = 2 fy
#: on the crease, mean |V_wide - V_square| over the image (tests/test_camera.py,
#: ``test_area_anisotropic_footprint``), 1 / 5 samples: "probes" 0.0055 / 0.0053,
#: "geometric" 0.0377 / 0.0114, "max" 0.0609 / 0.0255. Square pixels are unaffected (one
#: lookup, as before).
ANISOTROPIC_FOOTPRINT = "probes"
FOOTPRINTS = ("probes", "max", "geometric")


def _anisotropic_probes(px):
    """None for square pixels; else (R_lookup (k,), n, axis, R_long (k,)).

    R_lookup sizes each lookup's mip level (its side over the region's sqrt(a_i)); ``n``
    lookups are spread along ``axis`` (0 = x, 1 = y) over the region's long side, whose
    half-extent over sqrt(a_i) is R_long pixels. ``ANISOTROPIC_FOOTPRINT`` picks the scheme.
    """
    if px.radius_px_x is px.radius_px:
        return None
    check_choice(ANISOTROPIC_FOOTPRINT, "ANISOTROPIC_FOOTPRINT", FOOTPRINTS)
    r_x, r_y = px.radius_px_x, px.radius_px
    axis = 0 if px.fx >= px.fy else 1
    r_long, r_short = (r_x, r_y) if axis == 0 else (r_y, r_x)
    if ANISOTROPIC_FOOTPRINT == "max":
        return r_long, 1, axis, r_long
    if ANISOTROPIC_FOOTPRINT == "geometric":
        return np.sqrt(r_x * r_y), 1, axis, r_long
    ratio = max(px.fx, px.fy) / min(px.fx, px.fy)
    n = max(1, int(np.ceil(ratio - 1e-9)))
    return np.sqrt(r_long * r_short / n), n, axis, r_long


def _probe_lookup(pyramid, x, y, lod, hla, probes, *, offscreen, reconstruction, slope, ref):
    """The moments over an anisotropic footprint centred at (x, y): ``n`` isotropic lookups
    along the long axis (:func:`_anisotropic_probes`), combined as a mixture with equal
    shares (each weighted by its coverage; Chan et al. for the variance)."""
    _, n, axis, r_long = probes
    if n == 1:
        return pyramid.lookup(x, y, lod, offscreen, reconstruction, slope=slope, ref=ref)
    side = np.exp2(hla) * r_long            # the region's side along the long axis, pixels
    parts = []
    for k in range(n):
        shift = ((k + 0.5) / n - 0.5) * side
        xs, ys = (x + shift, y) if axis == 0 else (x, y - shift)
        parts.append(pyramid.lookup(xs, ys, lod, offscreen, reconstruction, slope=slope, ref=ref,
                                    carry_to=(x, y)))
    cov = sum(c for c, _, _ in parts)
    safe = np.where(cov > 0, cov, 1.0)
    mean = sum(c * m for c, m, _ in parts) / safe
    var = sum(c * (v + (m - mean) ** 2) for c, m, v in parts) / safe
    return cov / n, mean, var


def _area_kernel(px, *, radius, pattern, normal_clamp, thickness, falloff, model, reconstruction,
                 lod_bias, offscreen, pyramid, half_log_area, texture):
    """Area-sampled VO of one chunk of pixels (see :func:`vo_area`)."""
    k = len(px.index)
    z_p = px.z
    slope = None
    if normal_clamp:
        # Sec. 4.4 for an area sample (derived in docs/screenspace.md, "Normal clamping"):
        # the line at disk offset (u, v) is clipped at the tangent plane's line coordinate
        # t(u, v) = a u + b v (footnote 4), and occupancy inside the clipped segment
        # depends only on r = d_r - t, the surface measured from the plane. The sample's
        # line at the region's centre (x, y) therefore gets the distribution of
        # t(x, y) + r over the footprint, i.e. the moments of q - g . ((X, Y) - (x, y)):
        # each pixel's q carried along the plane to the line. g is the plane's gradient in
        # q per pixel: with X = X_p + R_px u, Y = Y_p - R_px v (rows down),
        # g = (dq/dd_r) (a, -b) / R_px, dq/dd_r = -R / z_p^2 (perspective) or R
        # (orthographic). MomentPyramid.lookup(slope=g) returns those moments exactly.
        a, b = C.tangent_plane_coefficients(px)      # t(u, v) = a u + b v, unclipped
        # With non-square pixels X = X_p + R_px_x u, Y = Y_p - R_px_y v: each axis its own R_px.
        dq_dr = -radius / (z_p * z_p) if px.perspective else radius
        dq_x = dq_dr / px.radius_px_x
        dq_y = dq_x if px.radius_px_x is px.radius_px else dq_dr / px.radius_px
        slope = (dq_x * a, -dq_y * b)

    # Step 2: "only a single log2 has to be computed" per pixel; the regions' log2 areas
    # are per-sample constants (Loos & Sloan 2010, Sec. 4.2)
    probes = _anisotropic_probes(px)
    log_r = np.log2(np.maximum(px.radius_px if probes is None else probes[0], np.finfo(np.float64).tiny))
    q_p = 1.0 / z_p if px.perspective else z_p
    noise = C.noise_at(px, texture)
    num = np.zeros(k)
    den = np.zeros(k)
    for s, w, hla in zip(pattern.points, pattern.weights, half_log_area):
        x, y, xy = C.disk_pixels(px, C.reflect(s, noise, k), snap=False)
        z_s = np.sqrt(np.maximum(0.0, 1.0 - np.einsum("ij,ij->i", xy, xy)))   # Sec. 4.1
        # Sec. 4.2: lod = log2 of the footprint's side, log2(R_px) + log2(a_i) / 2, minus the bias
        lod = np.clip(log_r + hla - lod_bias, 0.0, pyramid.top)
        # Step 3: the filtered moments M1, M2 (Sec. 4.2) at the region's centre; clamped, of
        # the depth carried along the tangent plane to this line (see ``slope`` above).
        # They are accumulated about the pixel's own q (carried along the plane when clamped)
        ref = q_p if slope is None else q_p + slope[0] * (x - px.center[:, 0]) + slope[1] * (y - px.center[:, 1])
        if probes is None:
            cov, mean, var = pyramid.lookup(x, y, lod, offscreen, reconstruction, slope=slope, ref=ref)
        else:
            cov, mean, var = _probe_lookup(pyramid, x, y, lod, hla, probes, offscreen=offscreen,
                                           reconstruction=reconstruction, slope=slope, ref=ref)
        sd = np.sqrt(var)
        # Step 4: mu and sigma of Sec. 4.2 in the line coordinate (the warp is affine in q)
        if px.perspective:
            # q = 1/z >= 0. Carried along a steep tangent plane the mean can cross 0, the
            # plane's horizon: no surface on this line, as for background (q = 0: d_r = z_p / R).
            mean = np.maximum(mean, 0.0)
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
        # Step 5: the segment (clipped at the tangent plane, Sec. 4.4) against the model:
        # the V_c integrals of Sec. 4.2 (box) or the Gaussian's closed form (footnote 3)
        hi = np.minimum(z_s, C.tangent_plane_line(px, xy)) if normal_clamp else z_s
        unocc, total = area_integral(-z_s, hi, mu_r, sigma_r, z_s, model=model, falloff=falloff,
                                     mu_back=mu_back, sigma_back=sigma_back)
        # the footprint's uncovered share is empty space
        unocc = cov * unocc + (1.0 - cov) * total
        # Step 6: footnote-5 weights, each segment normalized by its full integral
        # N = int_{-z_s}^{z_s} rho
        full = falloff_integral(-z_s, z_s, z_s, falloff=falloff)
        ok = full > 0
        safe = np.where(ok, full, 1.0)
        num += np.where(ok, w * unocc / safe, 0.0)
        den += np.where(ok, w * total / safe, 0.0)
    vis = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    return np.clip(vis, 0.0, 1.0)
