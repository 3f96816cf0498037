"""Alchemy AO (McGuire et al. 2011) and Scalable Ambient Obscurance (McGuire, Mara & Luebke 2012).

Both read the depth buffer at s taps on a screen-space disk (the projection of a world-space
disk of radius r around the pixel's point C), reconstruct the view-space point Q_i of each
tap, and sum a term of v_i = Q_i - C and the normal n at C. They differ in the sample
pattern (a per-pixel rotated disk for Alchemy, the SAO spiral) and in the falloff (SAO's
(r^2 - v.v)^3). See ``docs/screenspace.md``, "SAO, Alchemy and HBAO", for what each
estimates, how it compares with the ray-cast obscurance, and where vobscure departs from
the papers (scale-free sigma, beta and epsilon; full-resolution fetches instead of SAO's
MIP pyramid).
"""

from __future__ import annotations

import numpy as np

from .._validate import check_choice, check_int, check_positive
from . import _common as C

__all__ = ["alchemy", "sao", "alchemy_taps", "sao_taps"]

#: The golden angle (radians): the sunflower disk of :func:`alchemy`.
GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


def alchemy_taps(samples: int) -> int:
    """Depth-buffer taps per pixel of :func:`alchemy`: one per sample."""
    return check_int(samples, "samples")


def sao_taps(samples: int) -> int:
    """Depth-buffer taps per pixel of :func:`sao`: one per sample (full-resolution fetch)."""
    return check_int(samples, "samples")


def _check(gbuffer, radius, samples, sigma, k, epsilon, offscreen, noise_size):
    gb = C.as_gbuffer(gbuffer)
    radius = check_positive(radius, "radius")
    samples = check_int(samples, "samples")
    sigma = check_positive(sigma, "sigma", allow_zero=True)
    k = check_positive(k, "k")
    epsilon = check_positive(epsilon, "epsilon")
    check_choice(offscreen, "offscreen", C.OFFSCREEN)
    check_int(noise_size, "noise_size")
    return gb, radius, samples, sigma, k, epsilon


def _tap(px: C.Pixels, ox: np.ndarray, oy: np.ndarray, offscreen: str):
    """v = Q - C for the taps at unit-disk offsets (ox, oy) (k,) of each pixel, nearest fetch.

    The tap moves to the centre of the pixel it falls in (off the image: to the nearest
    border pixel with ``offscreen="clamp"``), and Q is that pixel's view-space point (its
    depth on its own view ray), so that Q is a point of the depth buffer's surface.
    Returns (vx, vy, vz, ok), ok False where the tap reads background (or an off-screen tap
    with ``offscreen="open"``): no occluder there.
    """
    x, y, _ = C.disk_pixels(px, np.column_stack([ox, oy]), snap=True)
    if offscreen == "clamp":
        # the tap moves to the nearest border pixel, position and depth: Q is that pixel's
        # point (reading the border depth at the off-screen position would invent a step)
        H, W = px.shape
        x = np.clip(x, 0.5, W - 0.5)
        y = np.clip(y, 0.5, H - 0.5)
    d = C.fetch_depth(px.depth, x, y, offscreen=offscreen)
    ok = np.isfinite(d)
    d = np.where(ok, d, px.z)
    # the camera's projection inverted (Camera.project): X = (x - cx) Z / fx,
    # Y = (cy - y) Z / fy (perspective); X = (x - cx) / fx, Y = (cy - y) / fy (orthographic)
    qx = (x - px.cx) / px.fx
    qy = (px.cy - y) / px.fy
    if px.perspective:
        qx = qx * d
        qy = qy * d
    p = px.p
    return qx - p[:, 0], qy - p[:, 1], d - px.z, ok


def _rotation(px: C.Pixels, texture):
    """(cos phi, sin phi) per pixel from the tiled unit-vector texture, or (1, 0)."""
    v = C.noise_at(px, texture)
    if v is None:
        return np.ones(len(px.index)), np.zeros(len(px.index))
    return v[:, 0], v[:, 1]


def alchemy(gbuffer, *, radius: float, samples: int = 12, beta: float = 1e-4, sigma: float = 1.0,
            k: float = 1.0, epsilon: float = 1e-4, randomize: bool = True, seed=0,
            offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE) -> np.ndarray:
    """Alchemy screen-space ambient obscurance (McGuire, Osman, Bukowski & Hennessy 2011).

    For each pixel's view-space point C with normal n, ``samples`` taps on the projection
    of the world-space disk of radius r (``radius``) around C give points Q_i of the depth
    buffer and v_i = Q_i - C; then

        A = max(0, 1 - (2 sigma r / s) sum_i max(0, v_i . n - z_C beta) / (v_i . v_i + epsilon r^2))^k

    summing only taps with v_i . v_i < r^2 (the paper's sphere of influence) that read
    geometry. The paper writes ``+ z_C beta`` with z_C < 0 in front of its camera; vobscure's
    z_C > 0, hence the minus sign.

    Parameters
    ----------
    gbuffer : GBuffer
        Depth (H, W) and view-space normals (H, W, 3) (:func:`vobscure.render_gbuffer`),
        perspective (any pinhole: fx, fy, cx, cy) or orthographic camera.
    radius : float
        World-space radius r of the sample disk and of the sphere of influence (> 0).
    samples : int
        s, taps per pixel (>= 1, default 12).
    beta : float
        Depth-proportional bias (>= 0, default 1e-4): a tap counts only where v . n > z_C
        beta, which makes planes (and depth-buffer noise on them) read fully open.
    sigma : float
        Intensity sigma (>= 0, default 1), in units of the radius (see Notes).
    k : float
        Contrast exponent (> 0, default 1).
    epsilon : float
        Regularizer of the denominator, as a fraction of r^2 (> 0, default 1e-4).
    randomize : bool
        A random rotation of the disk pattern per pixel, from a tiled ``noise_size`` x
        ``noise_size`` texture drawn from ``seed`` (default True).
    seed : int, numpy.random.Generator or None
        Seed of the rotation texture, converted once (default 0).
    offscreen : {"clamp", "open"}
        A tap off the image moves to the nearest border pixel (its point is Q, default
        ``"clamp"``) or finds no occluder (``"open"``).
    noise_size : int
        Edge of the rotation texture in pixels (>= 1).

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], NaN on background; float32 for a float32 G-buffer (accumulated
        in float64). Depth-buffer taps per pixel: ``alchemy_taps(samples)`` = s.

    Raises
    ------
    ValueError
        If ``gbuffer`` is not a GBuffer or an argument is out of range (the message names it).

    Notes
    -----
    Pattern: the sunflower (Vogel) disk, tap i at radius sqrt((i + 1/2) / s) and angle
    i times the golden angle, uniform by area, rotated per pixel. The published estimator
    is not dimensionless (its sum has units 1 / length); vobscure multiplies it by r, so
    ``sigma`` equals the paper's sigma when r = 1 scene unit and the result is scale
    invariant. Likewise epsilon scales with r^2. Nearest fetch at full resolution.

    References
    ----------
    McGuire, Osman, Bukowski & Hennessy, "The Alchemy Screen-Space Ambient Obscurance
    Algorithm", HPG 2011: the final estimator (Sec. 3; equation number not verified, see
    ``docs/screenspace.md``).

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> from vobscure.screenspace.sao import alchemy
    >>> float(alchemy(gb, radius=0.3)[4, 4])
    1.0
    """
    gb, radius, s, sigma, k, epsilon = _check(gbuffer, radius, samples, sigma, k, epsilon, offscreen,
                                              noise_size)
    beta = check_positive(beta, "beta", allow_zero=True)
    texture = C.noise_texture(noise_size, seed, 2, randomize)
    i = np.arange(s)
    rho = np.sqrt((i + 0.5) / s)
    theta = i * GOLDEN_ANGLE
    u0, w0 = rho * np.cos(theta), rho * np.sin(theta)
    r2 = radius * radius

    def kernel(px: C.Pixels) -> np.ndarray:
        cphi, sphi = _rotation(px, texture)
        n = px.n
        total = np.zeros(len(px.index))
        for a in range(s):
            vx, vy, vz, ok = _tap(px, cphi * u0[a] - sphi * w0[a], sphi * u0[a] + cphi * w0[a], offscreen)
            vv = vx * vx + vy * vy + vz * vz
            vn = vx * n[:, 0] + vy * n[:, 1] + vz * n[:, 2]
            # Alchemy 2011, the estimator's summand: max(0, v.n + z_C beta) / (v.v + epsilon),
            # z_C -> -z (vobscure's depth is positive)
            term = np.maximum(0.0, vn - px.z * beta) / (vv + epsilon * r2)
            total += np.where(ok & (vv < r2), term, 0.0)
        # Alchemy 2011: A = max(0, 1 - (2 sigma / s) sum ...)^k (times r: see Notes)
        return np.maximum(0.0, 1.0 - (2.0 * sigma * radius / s) * total) ** k

    return C.run_chunks(gb, radius, kernel, C.out_dtype(gb))


def sao(gbuffer, *, radius: float, samples: int = 12, turns: int = 7, beta: float = 0.01,
        sigma: float = 1.0, k: float = 1.0, epsilon: float = 0.01, randomize: bool = True, seed=0,
        offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE) -> np.ndarray:
    """Scalable Ambient Obscurance (McGuire, Mara & Luebke 2012).

    Taps on the SAO spiral: tap i of s has alpha_i = (i + 1/2) / s, screen-space distance
    h_i = alpha_i r' (r' the projected radius) and angle theta_i = 2 pi alpha_i tau + phi
    (tau = ``turns``, phi a per-pixel rotation). With v_i = Q_i - C,

        A = max(0, 1 - (5 sigma / (s r^5)) sum_i max(0, r^2 - v_i . v_i)^3
                        max(0, (v_i . n - beta r) / (v_i . v_i + epsilon r^2)))^k

    The falloff (r^2 - v.v)^3 goes to 0 at the sphere's surface, so no test of |v| < r is
    needed (it cancels the terms outside).

    Parameters
    ----------
    gbuffer : GBuffer
        As for :func:`alchemy`.
    radius : float
        World-space radius r (> 0).
    samples : int
        s, taps per pixel (>= 1, default 12).
    turns : int
        tau, turns of the spiral (>= 1, default 7; the paper picks tau per s so that taps
        do not line up, 7 for 9 taps among its choices).
    beta : float
        Bias distance as a fraction of r (>= 0, default 0.01): taps count where v . n >
        beta r; planes read fully open.
    sigma, k : float
        Intensity (in units of the radius, see :func:`alchemy`) and contrast exponent.
    epsilon : float
        Regularizer of the denominator as a fraction of r^2 (> 0, default 0.01).
    randomize, seed, offscreen, noise_size
        As for :func:`alchemy` (phi from the texture; phi = 0 without ``randomize``).

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], NaN on background, float32 for a float32 G-buffer.
        Depth-buffer taps per pixel: ``sao_taps(samples)`` = s.

    Raises
    ------
    ValueError
        If an argument is invalid (the message names it).

    Notes
    -----
    The paper's MIP depth pyramid (taps at distance h_i read MIP level floor(log2(h_i /
    q'))) serves GPU cache behaviour; vobscure reads every tap at full resolution, nearest,
    which is the limit of the pyramid with q' -> infinity. The paper's per-pixel hash angle
    is replaced by a seeded tiled random texture. The published normalization has units 1 /
    length (5 sigma / (s r^6) times a sum of length^5); vobscure multiplies by r so the
    result is scale invariant and ``sigma`` is the paper's sigma at r = 1 scene unit; beta
    and epsilon scale with r and r^2 for the same reason.

    References
    ----------
    McGuire, Mara & Luebke, "Scalable Ambient Obscurance", HPG 2012: the spiral pattern and
    the estimator (Sec. 2-3; equation numbers not verified, see ``docs/screenspace.md``).

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> from vobscure.screenspace.sao import sao
    >>> float(sao(gb, radius=0.3)[4, 4])
    1.0
    """
    gb, radius, s, sigma, k, epsilon = _check(gbuffer, radius, samples, sigma, k, epsilon, offscreen,
                                              noise_size)
    tau = check_int(turns, "turns")
    beta = check_positive(beta, "beta", allow_zero=True)
    texture = C.noise_texture(noise_size, seed, 2, randomize)
    # SAO 2012, the spiral: alpha_i = (i + 0.5) / s, h_i = r' alpha_i, theta_i = 2 pi alpha_i tau + phi
    alpha = (np.arange(s) + 0.5) / s
    theta = 2.0 * np.pi * alpha * tau
    u0, w0 = alpha * np.cos(theta), alpha * np.sin(theta)
    r2 = radius * radius

    def kernel(px: C.Pixels) -> np.ndarray:
        cphi, sphi = _rotation(px, texture)
        n = px.n
        total = np.zeros(len(px.index))
        for a in range(s):
            vx, vy, vz, ok = _tap(px, cphi * u0[a] - sphi * w0[a], sphi * u0[a] + cphi * w0[a], offscreen)
            vv = vx * vx + vy * vy + vz * vz
            vn = vx * n[:, 0] + vy * n[:, 1] + vz * n[:, 2]
            # SAO 2012, the estimator's summand: max(0, r^2 - v.v)^3 max(0, (v.n - beta) / (v.v + epsilon))
            term = np.maximum(0.0, r2 - vv) ** 3 * np.maximum(0.0, (vn - beta * radius) / (vv + epsilon * r2))
            total += np.where(ok, term, 0.0)
        # SAO 2012: A = max(0, 1 - (5 sigma / (s r^6)) sum ...)^k (times r: see Notes)
        return np.maximum(0.0, 1.0 - (5.0 * sigma / (s * radius ** 5)) * total) ** k

    return C.run_chunks(gb, radius, kernel, C.out_dtype(gb))
