"""Horizon-Based Ambient Occlusion (Bavoil, Sainz & Dimitrov 2008), image space.

Per pixel, ``directions`` screen-space directions (rotated per pixel); along each, ``steps``
taps march out to the projected radius, tracking the horizon: the highest elevation, above
the view plane, of a tap within distance R. Occlusion per direction is the rise of sin(h)
above sin(t), t the tangent plane's elevation in that direction, each rise weighted by the
attenuation W(r) = 1 - r^2 / R^2 of the tap that made it. See ``docs/screenspace.md``,
"SAO, Alchemy and HBAO".
"""

from __future__ import annotations

import numpy as np

from .._validate import check_choice, check_int, check_positive
from ..camera.kernel import ray_to_xy, ray_xy
from . import _common as C

__all__ = ["hbao", "hbao_taps"]


def hbao_taps(directions: int, steps: int) -> int:
    """Depth-buffer taps per pixel of :func:`hbao`: directions x steps."""
    return check_int(directions, "directions") * check_int(steps, "steps")


@C.inner_frame
def hbao(gbuffer, *, radius: float, directions: int = 8, steps: int = 4, angle_bias: float = np.pi / 18,
         attenuation: bool = True, randomize: bool = True, seed=0, offscreen: str = "clamp",
         noise_size: int = C.NOISE_SIZE, frame: int = 0, schedule: str = "white") -> np.ndarray:
    """Image-space horizon-based ambient occlusion (Bavoil, Sainz & Dimitrov 2008).

    For each direction theta (screen space; view-space (cos theta, sin theta, 0)), tap i of the
    march, at screen distance (i + j) R' / N_s (j a per-pixel jitter in (0, 1], 1 without
    ``randomize``; R' the projected radius), gives the view-space point S_i, D_i = S_i - P,
    r_i = |D_i| and sin h(S_i) = -D_z / r_i. Its tangent vector T_i = Q_i - P, Q_i where the
    tap's view ray meets the tangent plane (P, n), gives the tangent angle
    t_i = atan(-T_z / |T_xy|) (elevation towards the camera, above the view plane), raised by
    ``angle_bias``. Taps with r_i < R that raise the horizon add W(r_i) times the rise; then

        AO = (1 / N_d) sum_theta sum_i W(r_i) (sin h(S_i) - sin h(S_{i-1})),   V = 1 - AO.

    Parameters
    ----------
    gbuffer : GBuffer
        Depth (H, W) and view-space normals (H, W, 3), perspective (any pinhole) or
        orthographic camera.
    radius : float
        R, the world-space radius of influence (> 0).
    directions : int
        N_d, directions per pixel (>= 1, default 8).
    steps : int
        N_s, taps per direction (>= 1, default 4).
    angle_bias : float
        Added to the tangent angle t, in radians (in [0, pi/2), default pi/18 = 10 degrees,
        vobscure's choice): horizons less than this above the tangent plane do not occlude,
        so planes (and their depth-buffer noise) read fully open.
    attenuation : bool
        Weight each horizon rise by W(r) = 1 - r^2 / R^2 (default True, the paper's
        attenuation); False gives the unattenuated horizon integral, the uniformly weighted
        AO within R.
    randomize : bool
        A random rotation of the directions and a random jitter of the march per pixel, from a
        tiled ``noise_size`` x ``noise_size`` texture drawn from ``seed`` (default True).
    seed : int, numpy.random.Generator or None
        Seed of the texture, converted once (default 0).
    offscreen : {"clamp", "open"}
        A tap off the image moves to the nearest border pixel (``"clamp"``) or ends nothing
        and counts as no occluder (``"open"``).
    noise_size : int
        Edge of the texture in pixels (>= 1).
    frame, schedule : int, str
        The frame (>= 0, default 0) of a noise schedule (default ``"white"``), as for
        :func:`vobscure.vo_point`; unused without ``randomize``.

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], NaN on background; float32 for a float32 G-buffer.
        Depth-buffer taps per pixel: ``hbao_taps(directions, steps)``.

    Raises
    ------
    ValueError
        If ``gbuffer`` is not a GBuffer, ``radius`` is not a positive finite number,
        ``directions`` or ``steps`` is not an integer >= 1, ``angle_bias`` is not in
        [0, pi/2), ``seed``, ``noise_size`` or ``frame`` is invalid, or ``offscreen`` or
        ``schedule`` is not one of its values; the message names the argument.

    Notes
    -----
    Taps are snapped to pixel centres and S_i is that pixel's point (nearest fetch, as in
    :func:`vobscure.screenspace.sao.alchemy`); taps snapping onto the pixel itself are
    skipped. The tangent is taken per tap, at the tap's own screen position: Q_i lies on S_i's
    view ray, so a tap on a plane has D_i along T_i and never occludes, whatever the
    perspective or the snapping does to its azimuth. T_i is computed up to a positive factor
    without dividing by n_z or n . r (r the tap's ray): (n . r) P - (n . P) r under
    perspective (the tangent plane's direction in the plane of the eye, P and the tap, on the
    tap's side), (|n_z| D_xy, n_xy . D_xy) under an orthographic camera; it stays defined
    where the surface is seen with n_z = 0 (a floor or a wall under a level camera), where a
    tangent slope -(n_xy . u) / n_z would take the sign of rounding noise. A normal facing
    away from the eye (n . P > 0) is taken as edge-on (n . P = 0), and a tap whose T is 0 is
    skipped. The rises accumulated are those of the running maximum of
    sin h(S_i) - sin t'_i, t'_i = t_i + ``angle_bias``. The paper's blur is not implemented.

    The NVIDIA SDK shader of HBAO (checked in its public ports) has the same per-direction
    sum -- W(r) = 1 - r^2 / R^2 (``Falloff(d2) = d2 * NegInvR2 + 1``) times the rise of sin h
    over the running horizon, which starts at the biased tangent, and 1 - ao / N_d -- and,
    in its quality mode, the same per-tap tangent: ``tangent_vector(snapped_duv, dPdu, dPdv)``
    with dPdu, dPdv from the neighbouring pixels' rays meeting the tangent plane
    (``tangent_eye_pos``), its first-order form of Q_i - P, and ``h - h0`` the rise of
    sin h - sin t. It differs in two details: it adds the bias to tan t (``g_TanAngleBias``)
    where vobscure adds ``angle_bias`` to the angle t, and it steps R' / (N_s + 1) "so that the
    farthest samples are not fully attenuated" where vobscure's taps reach (i + j) R' / N_s.

    References
    ----------
    Bavoil, Sainz & Dimitrov, "Image-Space Horizon-Based Ambient Occlusion", SIGGRAPH 2008
    talk (and ShaderX7, Sec. 6.2): AO = 1 - 1/(2 pi) int (sin h - sin t) W dtheta, the
    per-sample attenuation, the angle bias, the tangent vector T found by intersecting a view
    ray with the tangent plane of P and n (the talk's and chapter's text were not available,
    this last as a forum thread quotes the talk: equation numbers are not cited; the
    structure, and t = atan(-T_z / |T_xy|) as the SDK's ``tangent(T)``, were checked against
    the SDK shader, see Notes and ``docs/screenspace.md``).

    Examples
    --------
    >>> import vobscure as vo
    >>> from vobscure.screenspace.hbao import hbao
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> float(hbao(gb, radius=0.3)[4, 4])
    1.0
    """
    gb = C.as_gbuffer(gbuffer)
    radius = check_positive(radius, "radius")
    N_d = check_int(directions, "directions")
    N_s = check_int(steps, "steps")
    angle_bias = check_positive(angle_bias, "angle_bias", allow_zero=True)
    if angle_bias >= np.pi / 2:
        raise ValueError(f"angle_bias must be in [0, pi/2) radians, got {angle_bias!r}")
    check_choice(offscreen, "offscreen", C.OFFSCREEN)
    check_int(noise_size, "noise_size")
    attenuation = C.check_bool(attenuation, "attenuation")
    texture = C.noise_texture(noise_size, seed, 3, randomize, frame=frame, schedule=schedule)
    R2 = radius * radius
    H, W = gb.depth.shape

    def kernel(px: C.Pixels) -> np.ndarray:
        k = len(px.index)
        v = C.noise_at(px, texture)
        if v is None:
            phi, jitter = np.zeros(k), np.ones(k)
        else:
            phi = np.arctan2(v[:, 1], v[:, 0])
            jitter = 1.0 - 0.5 * (v[:, 2] + 1.0)           # in [0, 1]
            jitter = np.where(jitter > 0, jitter, 1.0)      # (0, 1]
        n = px.n
        p = px.p
        ao = np.zeros(k)
        # n . P, clamped to <= 0: a normal facing away from the eye is taken as edge-on
        n_P = np.minimum(n[:, 0] * p[:, 0] + n[:, 1] * p[:, 1] + n[:, 2] * p[:, 2], 0.0)
        n_z = np.minimum(n[:, 2], 0.0)
        for d in range(N_d):
            theta = 2.0 * np.pi * d / N_d + phi
            ct, st = np.cos(theta), np.sin(theta)
            # the running maximum of sin h(S_i) - sin t'(S_i), starting at 0: the horizon's
            # rise above the biased tangent t' = t + angle_bias
            e_prev = np.zeros(k)
            for i in range(N_s):
                rho = (i + jitter) / N_s
                # screen step: (R'_x cos theta, -R'_y sin theta) pixels (rows go down)
                x = np.floor(px.center[:, 0] + px.radius_px_x * rho * ct) + 0.5
                y = np.floor(px.center[:, 1] - px.radius_px * rho * st) + 0.5
                if offscreen == "clamp":
                    x = np.clip(x, 0.5, W - 0.5)
                    y = np.clip(y, 0.5, H - 0.5)
                depth = C.fetch_depth(px.depth, x, y, offscreen=offscreen)
                ok = np.isfinite(depth) & ((x != px.center[:, 0]) | (y != px.center[:, 1]))
                depth = np.where(ok, depth, px.z)
                # the tap's view-space point S (the projection inverted), D = S - P
                a, b = ray_xy(x, y, px.fx, px.fy, px.cx, px.cy)
                sx, sy = ray_to_xy(a, b, depth, px.perspective)
                Dx, Dy, Dz = sx - p[:, 0], sy - p[:, 1], depth - px.z
                r2 = Dx * Dx + Dy * Dy + Dz * Dz
                ok &= (r2 < R2) & (r2 > 0)
                # HBAO 2008: sin h(S_i) = -D_z / |D| (elevation towards the camera)
                sin_h = -Dz / np.sqrt(np.where(ok, r2, 1.0))
                # HBAO 2008: the tangent vector T = Q - P, Q where the tap's view ray meets
                # the tangent plane (n, P), written without dividing by n . r or n_z so that
                # it stays defined where they vanish. Perspective, ray r = (a, b, 1):
                # Q = (n . P / n . r) r and T = (n . r) P - (n . P) r = -(n . r) (Q - P), a
                # positive multiple where the ray meets the plane in front of the eye
                # (n . r < 0); everywhere the tangent plane's direction in the plane of the
                # eye, P and the tap, on the tap's side. Orthographic, ray (a, b) + lambda z:
                # T = |n_z| (Q - P) = (|n_z| D_xy, n_xy . D_xy).
                if px.perspective:
                    n_r = n[:, 0] * a + n[:, 1] * b + n[:, 2]
                    Tx = n_r * p[:, 0] - n_P * a
                    Ty = n_r * p[:, 1] - n_P * b
                    Tz = n_r * p[:, 2] - n_P
                else:
                    Tx, Ty = -n_z * Dx, -n_z * Dy
                    Tz = n[:, 0] * Dx + n[:, 1] * Dy
                T_xy = np.sqrt(Tx * Tx + Ty * Ty)
                # a tap whose slice holds no tangent direction (T = 0) is skipped
                ok &= (T_xy > 0) | (Tz != 0)
                # HBAO 2008: t = atan(-T_z / |T_xy|), the tangent's elevation towards the
                # camera, plus the angle bias
                t = np.minimum(np.arctan2(-Tz, T_xy) + angle_bias, np.pi / 2)
                e = sin_h - np.sin(t)
                rise = ok & (e > e_prev)
                # HBAO 2008: W(r) = 1 - r^2 / R^2 times the horizon's rise sin h(S_i) - sin h(S_{i-1})
                w = (1.0 - r2 / R2) if attenuation else 1.0
                ao += np.where(rise, w * (e - e_prev), 0.0)
                e_prev = np.where(rise, e, e_prev)
        # HBAO 2008: AO = 1/(2 pi) int (sin h - sin t) W dtheta ~ (1 / N_d) sum_theta
        return np.clip(1.0 - ao / N_d, 0.0, 1.0)

    return C.run_chunks(gb, radius, kernel, C.out_dtype(gb))
