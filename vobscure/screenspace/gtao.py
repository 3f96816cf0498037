"""Ground-Truth based Ambient Occlusion, GTAO (Jimenez, Wu, Pesce & Jarabo 2016).

Horizon search along ``slices`` screen-space directions per pixel, then the closed-form
cosine-weighted integral between the two horizons of each slice. The paper's equations are
cited by section and by Algorithm 1's line numbers (the inner integral is Algorithm 1,
line 27; the paper's text was not available here, and the line number is the one XeGTAO's
source gives at its unrolled copy, "line ~27"); XeGTAO (Intel's reference implementation
of the paper) is cited for the options it adds (falloff range, thin-occluder compensation,
output power, normal fudge, presets), each checked against ``XeGTAO.h`` / ``XeGTAO.hlsli``
(defaults RadiusMultiplier 1.457, FalloffRange 0.615, SampleDistributionPower 2,
ThinOccluderCompensation 0, FinalValuePower 2.2; presets low 1 x 2, medium 2 x 2, high
3 x 3, ultra 9 x 3 slices x steps).
"""

from __future__ import annotations

from functools import partial

import numpy as np

from . import _common as C
from . import _horizon as Hz

__all__ = ["gtao", "gtao_bent_normals", "PRESETS"]

#: XeGTAO's quality presets: name -> (slices, steps per side). Taps per pixel: 2 x slices x steps.
PRESETS = {"low": (1, 2), "medium": (2, 2), "high": (3, 3), "ultra": (9, 3)}

#: The R1 (golden-ratio) increment of XeGTAO's per-slice, per-step jitter (``step_jitter="r1"``).
R1_STEP = 0.6180339887498948
#: The step jitters :func:`gtao` offers.
STEP_JITTERS = ("pixel", "r1")
#: XeGTAO's sample distribution: step j of n reaches ((j + u) / n) ** 2 of the radius
#: (denser near the centre, where small occluders matter most).
SAMPLE_DISTRIBUTION_POWER = 2.0
#: XeGTAO's "pixel too close" threshold: every tap is at least this many pixels from the
#: centre along the slice, so no tap reads the centre pixel itself.
PIXEL_TOO_CLOSE = 1.3


def _inner_integral(h, gamma, sin_g, cos_g):
    """One side of the slice's cosine-weighted inner integral (Jimenez et al. 2016, Sec. 4,
    Algorithm 1 line 27): 1/4 (-cos(2h - gamma) + cos gamma + 2 h sin gamma)."""
    return 0.25 * (cos_g + 2.0 * h * sin_g - np.cos(2.0 * h - gamma))


@C.inner_frame
def gtao(gbuffer, *, radius: float, slices: int = 3, steps: int = 3, falloff_range: float = 0.0,
         thin_occluder: float = 0.0, thickness=None, power: float = 1.0, normal_fudge: float = 0.0,
         randomize: bool = True, seed=0, fetch: str = "bilinear", offscreen: str = "clamp",
         noise_size: int = C.NOISE_SIZE, step_jitter: str = "pixel", frame: int = 0,
         schedule: str = "white", clip: bool = True) -> np.ndarray:
    """Cosine-weighted ambient occlusion within ``radius`` by horizon search (GTAO).

    For each pixel (view-space point p, normal n, view vector v from p to the camera),
    ``slices`` planes containing v are taken at view-space angles
    phi_k = pi (k + u) / slices around it (u from a tiled per-pixel noise). In each slice,
    ``steps`` depth-buffer taps on each side along the slice's screen direction find the two
    horizons: the largest cos of the angle to v of the vectors from p to the tapped points
    that lie within ``radius`` of p, starting from the tangent plane. The cosine-weighted
    visible arc between the horizons is integrated in closed form and weighted by the length
    of the normal projected onto the slice plane; the mean over slices is the visibility.

    Parameters
    ----------
    gbuffer : GBuffer
        Depth (H, W) and view-space normals (H, W, 3) from :func:`vobscure.render_gbuffer`;
        perspective (any pinhole, fx != fy allowed) or orthographic.
    radius : float
        World radius R (> 0): occluders farther than R from p are ignored, as in the
        ``quantity="ao"`` reference with ``max_distance=R``.
    slices : int, optional
        Slice directions per pixel (>= 1, default 3; see :data:`PRESETS`).
    steps : int, optional
        Depth taps per side of each slice (>= 1, default 3). Taps per pixel:
        2 x slices x steps.
    falloff_range : float, optional
        Fraction of the radius (in [0, 1]) over which XeGTAO blends a tap's horizon cosine
        towards the tangent-plane horizon: weight clip((R - dist) / (falloff_range R), 0, 1).
        Default 0: a hard cut at R (unbiased against the "ao" reference within R); XeGTAO
        ships 0.615.
    thin_occluder : float, optional
        XeGTAO's thin-occluder compensation (>= 0, default 0): the distance tested against
        the radius stretches the tap's depth offset by (1 + thin_occluder), so occluders far
        in front of or behind p drop out sooner.
    thickness : None or "layers", optional
        ``"layers"``: the occluders' true thickness from the G-buffer's solid intervals
        (``gbuffer.intervals``, from ``render_gbuffer(..., layers=K)`` or
        :meth:`vobscure.GBuffer.with_intervals`). A tap's occluder spans its view ray from the
        tapped depth to the back of the first solid interval of the tapped pixel that ends at
        or behind that depth; a tap whose occluder lies wholly above the current horizon (the
        horizon's line passes behind the occluder's back) does not raise the horizon, so light
        passes behind thin objects (Notes). Default None: every tap is a solid down to
        infinity, as the depth buffer says. Independent of ``thin_occluder``, which still
        applies to the distance test.
    power : float, optional
        The visibility is raised to this power (> 0, default 1). XeGTAO ships 2.2
        (``FinalValuePower``), an artistic darkening; it biases the estimate.
    normal_fudge : float, optional
        XeGTAO's "slight overdarkening on high slopes" fudge, in [0, 1] (default 0): the
        projected normal's length l becomes l + normal_fudge (1 - l). XeGTAO ships 0.05.
    clip : bool, optional
        Clip the visibility to [0, 1] (default True). With few slices the estimate of one
        pixel can exceed 1 (a slice's weight is its projected normal's length, exact only on
        average over the slice angle); clipped frames then average to a darker image. False
        keeps the unclipped value, whose mean over random slice angles is the integral: what
        a sequence accumulates (XeGTAO likewise keeps its raw term unclipped, "can overshoot
        1 but will later average out to 1", ``XE_GTAO_OCCLUSION_TERM_SCALE`` in
        ``XeGTAO.h``). ``power`` is applied after the clip, and only to values >= 0.
    randomize : bool, optional
        Rotate the slices and jitter the steps per pixel from a tiled noise texture
        (default True). False: u = 1/2 for both (a midpoint rule; ``seed`` unused).
    seed : int, numpy.random.Generator or None, optional
        Seed of the noise texture (default 0), converted once.
    fetch : {"bilinear", "nearest"}, optional
        How a tap's depth is read (:func:`vobscure.screenspace._common.fetch_depth`).
        ``"bilinear"`` (default): 1/z (perspective) or z (orthographic) interpolated at the
        tap's exact position on the slice line, exact on planes, so that every tap lies in
        the slice plane and a plane reads exactly open (the nearest depth of a background
        neighbourhood is used). ``"nearest"``: the tap snaps to the centre of its pixel, as
        XeGTAO does; the snapped point leaves the slice plane, and on a tilted plane it can
        rise above the slice's tangent-plane horizon (measured: a plane reads down to 0.92
        with 3 slices on a grazing view).
    offscreen : {"clamp", "open"}, optional
        Taps off the image read the nearest border pixel's depth at their own position
        (``"clamp"``, default) or empty space (``"open"``, ignored).
    noise_size : int, optional
        Edge of the tiled noise texture in pixels (>= 1, default 4).
    step_jitter : {"pixel", "r1"}, optional
        ``"pixel"`` (default): one step jitter u per pixel, shared by its slices. ``"r1"``:
        XeGTAO's, u advanced along the R1 (golden-ratio) sequence by slice + step * steps, so
        that a pixel's slices sample different radii. Both unbiased; without a denoiser
        ``"r1"`` measured slightly worse per frame (docs/screenspace.md, "GTAO"). Unused with
        ``randomize=False``.
    frame, schedule : int, str, optional
        The frame (>= 0, default 0) of a noise schedule (default ``"white"``), as for
        :func:`vobscure.vo_point`; ``"r2"`` is XeGTAO's own noise (u1 the slice rotation, u2
        the step jitter). Unused without ``randomize``.

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1] (1 = open), NaN on background (and NaN depth); float32 for a
        float32 G-buffer, float64 otherwise (computed in float64).

    Raises
    ------
    ValueError
        If an argument is out of range or of the wrong type (``thickness`` neither None nor
        ``"layers"``, or ``"layers"`` on a G-buffer without intervals); the message names it.

    Notes
    -----
    With gamma the angle of the projected normal n_p in the slice (measured from v, positive
    towards the slice's screen direction) and h_1 <= 0 <= h_2 the horizon angles, each
    clamped to the hemisphere [gamma - pi/2, gamma + pi/2], the slice contributes

        |n_p| (a(h_1) + a(h_2)),  a(h) = (-cos(2h - gamma) + cos gamma + 2 h sin gamma) / 4,

    and the visibility is the mean over slices (Jimenez et al. 2016, Sec. 4: the slice
    parameterization of the cosine-weighted visibility integral, its closed-form inner
    integral, and the weighting by the projected normal's length; Algorithm 1). It equals
    cosine-weighted AO within R in the limit of many slices and exact horizons when the
    scene is a height field seen from the camera (no hidden gaps behind the depth buffer).

    The slices are uniform in the view-space angle phi around the view axis, and a slice's
    screen direction is (fx cos phi, -fy sin phi), so non-square pixels are honoured; a
    slice plane under perspective is the plane through the eye, p and that screen line, so
    the taps lie exactly in it. Each tap is snapped to a pixel centre (nearest fetch) and
    its view-space position is reconstructed there. Under perspective the slices are
    uniform around the view axis, not around v, an approximation the paper shares.

    With ``thickness="layers"`` the horizon search runs near to far along each side as
    without; at a tap with occluder [d, b] along its view ray (b the back of the tapped pixel's
    interval, nearest pixel, whatever ``fetch``), the points of that segment, seen from p,
    have horizon cosines falling from the front's to the back's. If the back's cosine exceeds
    the current horizon's, the current horizon's line crosses the tap's ray behind b: the
    occluder is separated from the horizon by open space, and the tap is dropped (the rule
    of the thickness variants of horizon methods, which treat a tap whose sample lies behind
    the object's back as not occluding). Otherwise the tap raises the horizon to its front as
    usual. A single maximum horizon per side cannot represent what the layers describe
    beyond that: an occluder dropped this way is not counted at all (it blocks the arc
    between its back's and its front's angles, which the estimate reads open, so it errs
    towards open), and a gap below an occluder that has raised the horizon stays closed
    (light through a gap and then blocked again is not seen). It equals the depth buffer's
    GTAO where every interval is ``[d, +inf)``. With ``fetch="bilinear"`` a tap across a
    silhouette reads a depth interpolated between the two surfaces, in neither's interval:
    it takes the back of the interval behind it (``docs/screenspace.md``, "Thickness from
    layers").

    To match XeGTAO's defaults set ``falloff_range=0.615, power=2.2, normal_fudge=0.05``
    and use its ``RadiusMultiplier`` 1.457 on the radius; XeGTAO also clamps the output
    below at 0.03 and samples a depth MIP chain, which are not reproduced.

    References
    ----------
    Jimenez, Wu, Pesce & Jarabo, "Practical Real-Time Strategies for Accurate Indirect
    Occlusion", SIGGRAPH 2016 course (Activision tech report ATVI-TR-16-01), Sec. 4 and
    Algorithm 1. XeGTAO, Intel (2021), ``XeGTAO.hlsli`` (falloff, thin-occluder
    compensation, final power, normal fudge, sample distribution, presets).

    Examples
    --------
    A plane is open, up to the quadrature over slices (exact on average over the slice
    angle, not slice by slice, for a normal tilted from the view vector):

    >>> import vobscure as vo
    >>> from vobscure.screenspace.gtao import gtao
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> round(float(gtao(gb, radius=0.3, slices=9)[4, 4]), 6)
    1.0
    >>> round(float(gtao(gb, radius=0.3, slices=3)[4, 4]), 3)
    0.999

    Solid intervals from every surface to infinity are what the depth buffer assumes:

    >>> import numpy as np
    >>> from vobscure.layers import SolidIntervals
    >>> solid = gb.with_intervals(SolidIntervals(gb.depth[None], np.full((1, 8, 8), np.inf)))
    >>> bool(np.array_equal(gtao(solid, radius=0.3, thickness="layers"), gtao(gb, radius=0.3), equal_nan=True))
    True
    """
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    options = _check(slices=slices, steps=steps, falloff_range=falloff_range, thin_occluder=thin_occluder,
                     power=power, normal_fudge=normal_fudge, randomize=randomize, fetch=fetch,
                     offscreen=offscreen, noise_size=noise_size, step_jitter=step_jitter)
    options["intervals"] = _layers(gbuffer, thickness)
    # a 3-D unit vector per texel: the azimuth of its (x, y) and its z are independent and
    # uniform (Archimedes), giving the slice rotation and the step jitter
    texture = C.noise_texture(noise_size, seed, 3, randomize, frame=frame, schedule=schedule)
    kernel = partial(_gtao_kernel, radius=radius, texture=texture, clip=C.check_bool(clip, "clip"), **options)
    return C.run_chunks(gbuffer, radius, kernel, C.out_dtype(gbuffer))


@C.inner_frame
def gtao_bent_normals(gbuffer, *, radius: float, slices: int = 3, steps: int = 3,
                      falloff_range: float = 0.0, thin_occluder: float = 0.0, thickness=None,
                      normal_fudge: float = 0.0,
                      randomize: bool = True, seed=0, fetch: str = "bilinear", offscreen: str = "clamp",
                      noise_size: int = C.NOISE_SIZE, step_jitter: str = "pixel", frame: int = 0,
                      schedule: str = "white") -> np.ndarray:
    """View-space bent normals from the GTAO horizons (Jimenez et al. 2016).

    The same horizon search as :func:`gtao` (same arguments and defaults, same seed -> same
    horizons); each slice adds |n_p| times the integral of omega cos(theta - gamma) over its
    visible arc between the horizons, in closed form along the slice direction t and the view
    vector v (XeGTAO's ``t0``, ``t1``); the sum is normalized. This is the cosine-weighted mean
    unoccluded direction within ``radius``.

    Parameters
    ----------
    gbuffer, radius, slices, steps, falloff_range, thin_occluder, thickness, normal_fudge, randomize, seed, fetch, offscreen, noise_size, step_jitter, frame, schedule
        As in :func:`gtao` (``power`` does not apply to a direction).

    Returns
    -------
    (H, W, 3) ndarray
        Unit bent normals in view space (facing the camera like the G-buffer's normals), NaN on
        background; float32 for a float32 G-buffer, float64 otherwise.

    References
    ----------
    Jimenez, Wu, Pesce & Jarabo 2016, Algorithm 2 (the extension that computes bent normals
    from the GTAO horizons; numbered as XeGTAO's source cites it); XeGTAO,
    ``XeGTAO.hlsli`` (the closed forms t0, t1).

    Examples
    --------
    >>> import vobscure as vo
    >>> from vobscure.screenspace.gtao import gtao_bent_normals
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(8, 8), ortho_height=2.0)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(size=50.0), cam)
    >>> [round(float(c), 6) + 0.0 for c in gtao_bent_normals(gb, radius=0.2)[4, 4]]
    [0.0, 0.0, -1.0]
    """
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    options = _check(slices=slices, steps=steps, falloff_range=falloff_range, thin_occluder=thin_occluder,
                     power=1.0, normal_fudge=normal_fudge, randomize=randomize, fetch=fetch,
                     offscreen=offscreen, noise_size=noise_size, step_jitter=step_jitter)
    options["intervals"] = _layers(gbuffer, thickness)
    texture = C.noise_texture(noise_size, seed, 3, randomize, frame=frame, schedule=schedule)
    gb, depth64, index = C.frame(gbuffer, radius)
    H, W = gb.depth.shape
    out = np.full((H * W, 3), np.nan, dtype=C.out_dtype(gbuffer))
    for a in range(0, len(index), C.CHUNK_PIXELS):
        px = C.prepare(gb, radius, index=index[a:a + C.CHUNK_PIXELS], depth64=depth64)
        b = _gtao_kernel(px, radius=radius, texture=texture, bent=True, **options)
        length = np.linalg.norm(b, axis=1, keepdims=True)
        # no open direction at all (never on a valid pixel: the arc at the normal stays open)
        out[px.index] = np.where(length > 0, b / np.where(length > 0, length, 1.0), px.n)
    return out.reshape(H, W, 3)


def _check(*, slices, steps, falloff_range, thin_occluder, power, normal_fudge, randomize, fetch, offscreen,
           noise_size, step_jitter):
    """Validate the arguments shared by :func:`gtao` and :func:`gtao_bent_normals`."""
    options = dict(slices=C.check_int(slices, "slices"), steps=C.check_int(steps, "steps"),
                   falloff_range=_fraction(falloff_range, "falloff_range"),
                   thin_occluder=C.check_positive(thin_occluder, "thin_occluder", allow_zero=True),
                   power=C.check_positive(power, "power"),
                   normal_fudge=_fraction(normal_fudge, "normal_fudge"), fetch=fetch, offscreen=offscreen)
    C.check_bool(randomize, "randomize")
    if step_jitter not in STEP_JITTERS:
        raise ValueError(f"step_jitter must be one of {', '.join(STEP_JITTERS)}, got {step_jitter!r}")
    options["r1_jitter"] = step_jitter == "r1"
    C.check_common(fetch=fetch, offscreen=offscreen, noise_size=noise_size)
    return options


def _layers(gbuffer, thickness):
    """The G-buffer's solid intervals for ``thickness="layers"``, None for None."""
    if thickness is None:
        return None
    if not isinstance(thickness, str):
        raise ValueError(f"thickness must be None or {C.LAYERS!r} for GTAO (its depth-buffer heuristic for thin "
                         f"occluders is thin_occluder), got {thickness!r}")
    return C.solid_intervals(gbuffer, thickness)


def _fraction(value, name):
    v = C.check_positive(value, name, allow_zero=True)
    if v > 1.0:
        raise ValueError(f"{name} must be in [0, 1], got {value!r}")
    return v


def _gtao_kernel(px, *, radius, slices, steps, falloff_range, thin_occluder, power, normal_fudge, fetch,
                 offscreen, texture, r1_jitter=False, bent=False, intervals=None, clip=True):
    """GTAO of one chunk of pixels (see :func:`gtao`): loops over slices and steps only.

    Returns the (k,) visibility, or with ``bent`` the (k, 3) unnormalized bent normal. With
    ``intervals`` (``thickness="layers"``) a tap whose occluder's back lies above the current
    horizon does not raise it."""
    k = len(px.index)
    (vx, vy, vz), b1, b2 = Hz.view_basis(px)
    noise = Hz.slice_noise(px, texture)
    u_step, has_noise = noise.u_step, noise.has_noise
    visibility = np.zeros(k)
    bent_normal = np.zeros((k, 3)) if bent else None
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for s in range(slices):
            # Algorithm 1: phi = pi (slice + noise) / slices (uniform around v, not the view axis)
            sl = Hz.horizon_slice(px, noise.rotation(s, slices), (vx, vy, vz), b1, b2, min_px=PIXEL_TOO_CLOSE)
            tx, ty, tz = sl.t
            gamma, sin_g, cos_g, pn_len = sl.gamma, sl.sin_g, sl.cos_g, sl.pn_len
            # horizons start at the tangent plane: cos(gamma +- pi/2) = -+ sin(gamma)
            low = (-sin_g, sin_g)
            horizon_cos = [low[0].copy(), low[1].copy()]
            for j in range(steps):
                # the step jitter: the pixel's own, or with r1_jitter XeGTAO's, advanced along
                # the R1 sequence by (slice + step * steps) golden-ratio steps (XeGTAO.hlsli,
                # XeGTAO_MainPass); then XeGTAO's distribution ((j + u) / steps) ** 2 plus the
                # minimum offset
                u = (u_step + (s + j * steps) * R1_STEP) % 1.0 if (r1_jitter and has_noise) else u_step
                t = ((j + u) / steps) ** SAMPLE_DISTRIBUTION_POWER + sl.min_s
                for side, sign in ((0, 1.0), (1, -1.0)):
                    tap = Hz.horizon_tap(px, sl, sign * t, fetch=fetch, offscreen=offscreen)
                    ok, dist = tap.ok, tap.dist
                    ddx, ddy, ddz = tap.delta
                    # Sec. 4: the horizon is the largest cos of the angle to v
                    shc = (ddx * vx + ddy * vy + ddz * vz) / dist
                    # XeGTAO's thin-occluder compensation stretches the depth offset
                    if thin_occluder > 0:
                        ddz = ddz * (1.0 + thin_occluder)
                        base = np.sqrt(ddx * ddx + ddy * ddy + ddz * ddz)
                    else:
                        base = dist
                    if falloff_range > 0:
                        # XeGTAO: weight = saturate((R - dist) / (falloff_range R))
                        w = np.clip((radius - base) / (falloff_range * radius), 0.0, 1.0)
                    else:
                        w = (base <= radius).astype(np.float64)    # hard cut at R
                    w = np.where(ok, w, 0.0)
                    if intervals is not None:
                        w = _behind_back(w, intervals, px, tap.x, tap.y, tap.d, tap.ray, horizon_cos[side],
                                         v=(vx, vy, vz), offscreen=offscreen)
                    shc = low[side] + w * (shc - low[side])
                    np.maximum(horizon_cos[side], shc, out=horizon_cos[side])
            # h_2 on the + side (towards t), h_1 = -acos on the - side, clamped to the hemisphere
            h2 = np.arccos(np.clip(horizon_cos[0], -1.0, 1.0))
            h1 = -np.arccos(np.clip(horizon_cos[1], -1.0, 1.0))
            h2 = gamma + np.clip(h2 - gamma, -0.5 * np.pi, 0.5 * np.pi)
            h1 = gamma + np.clip(h1 - gamma, -0.5 * np.pi, 0.5 * np.pi)
            if normal_fudge > 0:
                pn_len = pn_len + normal_fudge * (1.0 - pn_len)
            # Sec. 4, Algorithm 1 line 27: |n_p| (a(h_1) + a(h_2))
            visibility += pn_len * (_inner_integral(h1, gamma, sin_g, cos_g)
                                    + _inner_integral(h2, gamma, sin_g, cos_g))
            if bent:
                # bent normal (Jimenez et al. 2016, Algorithm 2), XeGTAO's closed form: the integral
                # of omega cos(theta - gamma) |sin theta| over the visible arc, along t and v
                t_0 = (6.0 * np.sin(h1 - gamma) - np.sin(3.0 * h1 - gamma) + 6.0 * np.sin(h2 - gamma)
                       - np.sin(3.0 * h2 - gamma) + 16.0 * sin_g
                       - 3.0 * (np.sin(h1 + gamma) + np.sin(h2 + gamma))) / 12.0
                t_1 = (-np.cos(3.0 * h1 - gamma) - np.cos(3.0 * h2 - gamma) + 8.0 * cos_g
                       - 3.0 * (np.cos(h1 + gamma) + np.cos(h2 + gamma))) / 12.0
                bent_normal[:, 0] += pn_len * (t_0 * tx + t_1 * vx)
                bent_normal[:, 1] += pn_len * (t_0 * ty + t_1 * vy)
                bent_normal[:, 2] += pn_len * (t_0 * tz + t_1 * vz)
    if bent:
        return bent_normal
    visibility /= slices
    if clip:
        np.clip(visibility, 0.0, 1.0, out=visibility)
    if power != 1.0:
        np.power(visibility, power, out=visibility, where=visibility >= 0)
    return visibility


def _behind_back(w, intervals, px, x, y, d, tap_ray, horizon, *, v, offscreen):
    """The taps' weights ``w`` with 0 where the current horizon passes behind the tap's occluder.

    The occluder at a tap spans its view ray from the tapped depth ``d`` to ``back``, the back
    of the first solid interval of the tapped pixel (nearest: the pixel containing (x, y))
    that ends at or behind ``d`` (:func:`vobscure.screenspace._common.interval_back`). Seen
    from p, the ray's points fall monotonically in the slice as their depth grows, so the
    current horizon's line crosses the tap's ray behind ``back`` exactly when the back point's
    horizon cosine exceeds the current one: the occluder then lies wholly above the horizon,
    with open space between them, and the tap is dropped (weight 0) instead of raising the
    horizon over that gap. ``back = +inf`` (the solid's end not seen) always raises, as the
    depth buffer does.
    """
    vx, vy, vz = v
    index, _ = C.nearest_pixel(px.shape, x, y, offscreen=offscreen)
    back = C.interval_back(intervals, index, d)
    seen = np.isfinite(back) & (w > 0)
    if not seen.any():
        return w
    back = np.where(seen, back, d)
    # the back point on the tap's view ray, minus p; its horizon cosine (Jimenez et al. 2016,
    # Sec. 4: the cos of the angle to v)
    bx, by = C.ray_to_xy(*tap_ray, back, px.perspective)
    p = px.p
    ddx, ddy, ddz = bx - p[:, 0], by - p[:, 1], back - p[:, 2]
    dist = np.sqrt(ddx * ddx + ddy * ddy + ddz * ddz)
    dist = np.where(dist > 0, dist, 1.0)
    cos_back = (ddx * vx + ddy * vy + ddz * vz) / dist
    return np.where(seen & (cos_back > horizon), 0.0, w)
