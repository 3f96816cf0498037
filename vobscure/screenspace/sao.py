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
from ..camera.kernel import ray_to_xy, ray_xy
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


def _check(gbuffer, radius, samples, sigma, k, epsilon, beta, offscreen, noise_size, seed, randomize, frame,
           schedule):
    """The arguments :func:`alchemy` and :func:`sao` share, validated, and the rotation texture:
    ``(gb, radius, samples, sigma, k, epsilon, beta, texture)``."""
    gb = C.as_gbuffer(gbuffer)
    radius = check_positive(radius, "radius")
    samples = check_int(samples, "samples")
    sigma = check_positive(sigma, "sigma", allow_zero=True)
    k = check_positive(k, "k")
    epsilon = check_positive(epsilon, "epsilon")
    check_choice(offscreen, "offscreen", C.OFFSCREEN)
    check_int(noise_size, "noise_size")
    beta = check_positive(beta, "beta", allow_zero=True)
    texture = C.noise_texture(noise_size, seed, 2, randomize, frame=frame, schedule=schedule)
    return gb, radius, samples, sigma, k, epsilon, beta, texture


def _disk_sums(gb, radius: float, u0: np.ndarray, w0: np.ndarray, texture, offscreen: str, summand,
               finish) -> np.ndarray:
    """(H, W) image of ``finish(total, px)``, total (k,) the sum over the taps of a summand.

    The taps are at unit-disk offsets (u0, w0) (s,), turned per pixel by the angle phi of
    the tiled rotation texture: (cos phi u0 - sin phi w0, sin phi u0 + cos phi w0). Pixels
    are processed in groups that share one texel (:func:`~vobscure.screenspace._common.
    noise_classes`), so a group's rotated offsets are s scalars and only the projected
    radius varies per pixel; with a large tile (``"r2"``, ``"gtao"``) each pixel's offsets
    are turned by its own texel, by the same operations on arrays, so the two groupings give
    the same values bit for bit.

    A tap moves to the centre of the pixel it falls in (off the image: to the nearest border
    pixel with ``offscreen="clamp"``), and Q is that pixel's view-space point (its depth on
    its own view ray), so that Q is a point of the depth buffer's surface. ``summand(px)``
    is called once per group of pixels ``px`` and returns a function ``f(vx, vy, vz, term)``
    that receives the (k,) components of v = Q - C of one tap and writes the tap's term
    into ``term`` (all four are buffers reused from tap to tap). Where the tap reads background
    (or, with ``offscreen="open"``, leaves the image) the depth read is NaN, so v is NaN;
    the summand must give 0 there (``np.fmax`` with 0 does). With ``offscreen="clamp"`` every
    array operation of a tap writes into one of these buffers (no temporary is allocated per
    tap); ``"open"`` adds a mask of the taps that leave the image.
    """
    gb, depth64, index = C.frame(gb, radius)
    H, W = gb.depth.shape
    out = np.full(H * W, np.nan, dtype=C.out_dtype(gb))
    if not len(index):
        return out.reshape(H, W)
    depth_nan = _background_as_nan(depth64)
    for chunk, rotation in C.noise_classes(depth64, (H, W), texture):
        px = C.prepare(gb, radius, index=chunk, depth64=depth64)
        if rotation is None:
            cphi, sphi = 1.0, 0.0
        elif rotation.ndim == 1:
            cphi, sphi = float(rotation[0]), float(rotation[1])
        else:
            # a texel per pixel (a large tile): the same operations on (k,) arrays
            cphi, sphi = np.ascontiguousarray(rotation[:, 0]), np.ascontiguousarray(rotation[:, 1])
        k = len(chunk)
        centre_x, centre_y = px.col + 0.5, px.row + 0.5
        p = px.p
        p_x, p_y = np.ascontiguousarray(p[:, 0]), np.ascontiguousarray(p[:, 1])
        x, y, d, vx, vy, vz, term = (np.empty(k) for _ in range(7))
        flat = np.empty(k, dtype=np.intp)
        total = np.zeros(k)
        tap_term = summand(px)
        for a in range(len(u0)):
            ox = cphi * u0[a] - sphi * w0[a]
            oy = sphi * u0[a] + cphi * w0[a]
            # the tap's pixel (column x, row y): the offset (ox, oy) moves the projection by
            # (R_x ox, -R_y oy) pixels (rows go down)
            np.multiply(px.radius_px_x, ox, out=x)
            x += centre_x
            np.floor(x, out=x)
            np.multiply(px.radius_px, oy, out=y)
            np.subtract(centre_y, y, out=y)
            np.floor(y, out=y)
            if offscreen == "clamp":
                np.clip(x, 0, W - 1, out=x)
                np.clip(y, 0, H - 1, out=y)
                outside = None
            else:
                outside = (x < 0) | (x >= W) | (y < 0) | (y >= H)
                if outside.any():
                    np.clip(x, 0, W - 1, out=x)
                    np.clip(y, 0, H - 1, out=y)
                else:
                    outside = None
            np.multiply(y, W, out=term)
            term += x
            flat[...] = term
            np.take(depth_nan, flat, out=d)
            if outside is not None:
                d[outside] = np.nan
            # Q: the projection inverted at the tap's pixel centre (vobscure.camera.kernel),
            # in place; then v = Q - C
            np.add(x, 0.5, out=vx)
            np.add(y, 0.5, out=vy)
            ray_xy(vx, vy, px.fx, px.fy, px.cx, px.cy, out=(vx, vy))
            ray_to_xy(vx, vy, d, px.perspective, out=(vx, vy))
            vx -= p_x
            vy -= p_y
            np.subtract(d, px.z, out=vz)
            tap_term(vx, vy, vz, term)
            total += term
        out[chunk] = finish(total, px)
    return out.reshape(H, W)


def _background_as_nan(depth64: np.ndarray) -> np.ndarray:
    """A copy of the flat float64 depth buffer with background (+inf) as NaN: a tap that
    reads it gives NaN terms (which ``np.fmax`` with 0 turns into 0), not inf - inf."""
    return np.where(np.isfinite(depth64), depth64, np.nan)


def _dot_products(px: C.Pixels):
    """``(dots, vv, vn)``: ``dots(vx, vy, vz)`` writes v . v into the buffer ``vv`` and
    v . n into ``vn``, n the normal of each pixel of ``px`` (taken once, as contiguous
    components)."""
    n = px.n
    n_x, n_y, n_z = (np.ascontiguousarray(n[:, i]) for i in range(3))
    scratch, vv, vn = np.empty(len(n_x)), np.empty(len(n_x)), np.empty(len(n_x))

    def dots(vx, vy, vz):
        np.multiply(vx, vx, out=vv)
        np.multiply(vy, vy, out=scratch)
        np.add(vv, scratch, out=vv)
        np.multiply(vz, vz, out=scratch)
        np.add(vv, scratch, out=vv)
        np.multiply(vx, n_x, out=vn)
        np.multiply(vy, n_y, out=scratch)
        np.add(vn, scratch, out=vn)
        np.multiply(vz, n_z, out=scratch)
        np.add(vn, scratch, out=vn)
    return dots, vv, vn


@C.inner_frame
def alchemy(gbuffer, *, radius: float, samples: int = 12, beta: float = 1e-4, sigma: float = 1.0,
            k: float = 1.0, epsilon: float = 1e-4, randomize: bool = True, seed=0,
            offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE, frame: int = 0,
            schedule: str = "white") -> np.ndarray:
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
    frame, schedule : int, str
        The frame (>= 0, default 0) of a noise schedule (default ``"white"``), as for
        :func:`vobscure.vo_point`; unused without ``randomize``.

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
    Algorithm", HPG 2011: the final estimator (the paper's text was not available: its
    section and equation numbers are not cited; the estimator and the parameters sigma, beta
    ("shadow bias, e.g. 1e-4"), epsilon ("avoids divide-by-zero, e.g. 1e-5", absolute in the
    talk, a fraction of r^2 here), s and k as listed on the authors' HPG 2011 slides). See
    ``docs/screenspace.md``, "Sources and equation numbers".

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> from vobscure.screenspace.sao import alchemy
    >>> float(alchemy(gb, radius=0.3)[4, 4])
    1.0
    """
    gb, radius, s, sigma, k, epsilon, beta, texture = _check(gbuffer, radius, samples, sigma, k, epsilon, beta,
                                                             offscreen, noise_size, seed, randomize, frame,
                                                             schedule)
    i = np.arange(s)
    rho = np.sqrt((i + 0.5) / s)
    theta = i * GOLDEN_ANGLE
    u0, w0 = rho * np.cos(theta), rho * np.sin(theta)
    r2 = radius * radius

    def summand(px):
        dots, vv, vn = _dot_products(px)
        bias = px.z * beta
        beyond = np.empty(len(px.z), dtype=bool)

        def tap_term(vx, vy, vz, term):
            dots(vx, vy, vz)
            # Alchemy 2011, the estimator's summand: max(0, v.n + z_C beta) / (v.v + epsilon),
            # z_C -> -z (vobscure's depth is positive), over taps inside the sphere of influence
            np.subtract(vn, bias, out=vn)
            np.fmax(vn, 0.0, out=vn)
            np.add(vv, epsilon * r2, out=term)
            np.divide(vn, term, out=term)
            # v.v < r^2 is False for a background tap (NaN), as for a tap outside the sphere
            np.less(vv, r2, out=beyond)
            np.logical_not(beyond, out=beyond)
            np.copyto(term, 0.0, where=beyond)
        return tap_term

    def finish(total, px):
        # Alchemy 2011: A = max(0, 1 - (2 sigma / s) sum ...)^k (times r: see Notes)
        return np.maximum(0.0, 1.0 - (2.0 * sigma * radius / s) * total) ** k

    return _disk_sums(gb, radius, u0, w0, texture, offscreen, summand, finish)


@C.inner_frame
def sao(gbuffer, *, radius: float, samples: int = 12, turns: int = 7, beta: float = 0.01,
        sigma: float = 1.0, k: float = 1.0, epsilon: float = 0.01, randomize: bool = True, seed=0,
        offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE, frame: int = 0,
        schedule: str = "white") -> np.ndarray:
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
        tau, turns of the spiral (>= 1, default 7: the authors' reference shader's value,
        which its comment says was tuned for 9 taps; the shader's library picks a tau per s
        that minimizes discrepancy, not reproduced here).
    beta : float
        Bias distance as a fraction of r (>= 0, default 0.01): taps count where v . n >
        beta r; planes read fully open.
    sigma, k : float
        Intensity (in units of the radius, see :func:`alchemy`) and contrast exponent.
    epsilon : float
        Regularizer of the denominator as a fraction of r^2 (> 0, default 0.01).
    randomize, seed, offscreen, noise_size, frame, schedule
        As for :func:`alchemy` (phi from the texture; phi = 0 without ``randomize``).

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], NaN on background, float32 for a float32 G-buffer.
        Depth-buffer taps per pixel: ``sao_taps(samples)`` = s.

    Raises
    ------
    ValueError
        If ``gbuffer`` is not a GBuffer, ``radius``, ``k`` or ``epsilon`` is not a positive
        finite number, ``sigma`` or ``beta`` is negative or not finite, ``samples`` or
        ``turns`` is not an integer >= 1, ``seed`` or ``noise_size`` is invalid, or
        ``offscreen`` is not one of its values; the message names the argument.

    Notes
    -----
    The paper's MIP depth pyramid (taps at distance h_i read MIP level floor(log2(h_i /
    q'))) serves GPU cache behaviour; vobscure reads every tap at full resolution, nearest,
    which is the limit of the pyramid with q' -> infinity. The paper's per-pixel hash angle
    is replaced by a seeded tiled random texture. The published normalization has units 1 /
    length (5 sigma / (s r^6) times a sum of length^5); vobscure multiplies by r so the
    result is scale invariant and ``sigma`` is the paper's sigma at r = 1 scene unit; beta
    and epsilon scale with r and r^2 for the same reason.

    The falloff (r^2 - v.v)^3 is the one the authors' reference shader recommends and uses
    by default (its variant "B", "smoother transition to zero"); the same shader marks a
    step falloff, max(0, (v.n - beta) / (v.v + epsilon)) over taps with v.v < r^2, as the
    HPG 2012 paper's (its variant "A"), which vobscure does not implement (``alchemy`` has
    the step falloff with Alchemy's bias).

    References
    ----------
    McGuire, Mara & Luebke, "Scalable Ambient Obscurance", HPG 2012 (the paper's text was
    not available: its section and equation numbers are not cited). The spiral, tau, the
    falloff, the 5 sigma / (s r^6) normalization and epsilon = 0.01 as in the authors'
    reference shader (McGuire & Mara, NVIDIA 2011-2012, BSD licence; G3D's
    ``AmbientOcclusion_AO.pix`` and its ports): ``tapLocation``, ``fallOffFunction`` (variant
    B) and ``main``. See ``docs/screenspace.md``, "Sources and equation numbers".

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> from vobscure.screenspace.sao import sao
    >>> float(sao(gb, radius=0.3)[4, 4])
    1.0
    """
    gb, radius, s, sigma, k, epsilon, beta, texture = _check(gbuffer, radius, samples, sigma, k, epsilon, beta,
                                                             offscreen, noise_size, seed, randomize, frame,
                                                             schedule)
    tau = check_int(turns, "turns")
    # SAO's spiral (reference shader, tapLocation): alpha_i = (i + 0.5) / s, h_i = r' alpha_i,
    # theta_i = 2 pi alpha_i tau + phi
    alpha = (np.arange(s) + 0.5) / s
    theta = 2.0 * np.pi * alpha * tau
    u0, w0 = alpha * np.cos(theta), alpha * np.sin(theta)
    r2 = radius * radius

    def summand(px):
        dots, vv, vn = _dot_products(px)

        def tap_term(vx, vy, vz, term):
            dots(vx, vy, vz)
            # SAO's summand (reference shader, fallOffFunction variant B): max(0, r^2 - v.v)^3
            # max(0, (v.n - beta) / (v.v + epsilon)); fmax turns a background tap's NaN into 0
            # in both factors
            np.subtract(vn, beta * radius, out=vn)
            np.add(vv, epsilon * r2, out=term)
            np.divide(vn, term, out=vn)
            np.fmax(vn, 0.0, out=vn)
            np.subtract(r2, vv, out=term)
            np.fmax(term, 0.0, out=term)
            np.multiply(vn, term, out=vn)
            np.multiply(term, term, out=term)
            term *= vn
        return tap_term

    def finish(total, px):
        # SAO (reference shader, main): A = max(0, 1 - (5 sigma / (s r^6)) sum ...)^k (times r:
        # see Notes)
        return np.maximum(0.0, 1.0 - (5.0 * sigma / (s * radius ** 5)) * total) ** k

    return _disk_sums(gb, radius, u0, w0, texture, offscreen, summand, finish)
