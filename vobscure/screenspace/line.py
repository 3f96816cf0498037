"""Line sampling of Volumetric Obscurance (Loos & Sloan 2010, Sec. 4.1, 4.3, 4.4, 4.5).

The paper does not number its equations; they are cited by section and content (the list is
in ``docs/screenspace.md``, "How the paper is cited").
"""

from __future__ import annotations

from functools import partial

import numpy as np

from . import _common as C

__all__ = ["vo_line", "line_integral", "falloff_integral"]


def falloff_integral(a, b, z_s, *, falloff="constant"):
    """Integral of the falloff rho along the line at a disk offset, over [a, b].

    Coordinates are those of the unit sphere around the pixel's point p: z along the line
    through the disk point (x, y), whose chord is [-z_s, z_s] with z_s = sqrt(1 - x^2 - y^2)
    (Loos & Sloan 2010, Sec. 4.1).

    Parameters
    ----------
    a, b : float or array_like
        Ends of the interval, in line coordinates; broadcast together. ``a <= b`` is the
        caller's to ensure (for ``b < a`` the result is the negated integral over [b, a]).
    z_s : float or array_like
        Half-length of the line's chord in the unit sphere; used by the quadratic falloff
        only, and broadcast with ``a`` and ``b``.
    falloff : {"constant", "quadratic"}, optional
        ``"constant"`` (default): rho = 1, the paper's choice (Sec. 4), so the integral is the
        length b - a. ``"quadratic"``: rho = 1 - r^2 with r = |x - p| / R, the quadratic
        falloff the paper mentions in Sec. 4; on the line r^2 = x^2 + y^2 + z^2, so
        rho = z_s^2 - z^2 and the integral is z_s^2 (b - a) - (b^3 - a^3) / 3.
        Not validated here (the estimators validate it).

    Returns
    -------
    float or ndarray
        The integral, of the broadcast shape of the inputs.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4 (the falloff rho, constant or
    quadratic) and Sec. 4.1 (z_s = sqrt(1 - x^2 - y^2)).

    Examples
    --------
    The whole chord of the centre line (z_s = 1): its length 2 for rho = 1, and
    int_{-1}^{1} (1 - z^2) dz = 4/3 for the quadratic falloff.

    >>> falloff_integral(-1.0, 1.0, 1.0)
    2.0
    >>> round(falloff_integral(-1.0, 1.0, 1.0, falloff="quadratic"), 12)
    1.333333333333
    """
    if falloff == "constant":
        return b - a
    # int_a^b (z_s^2 - z^2) dz
    return z_s * z_s * (b - a) - (b ** 3 - a ** 3) / 3.0


def line_integral(lo, hi, occ_lo, occ_hi, z_s, falloff="constant"):
    """Unoccupied and total integrals of rho along one line segment.

    The segment [lo, hi] of the line is occupied on [occ_lo, occ_hi]: from the depth
    buffer's surface d_r to the back of the surface (occ_hi = +inf without the thickness
    model). For a constant rho, the whole chord [-z_s, z_s] and no thickness, the unoccupied
    integral is the paper's line integral max(min(z_s, d_r) + z_s, 0) (Loos & Sloan 2010,
    Sec. 4.1). With the thickness model (Sec. 4.3) the part behind occ_hi is unoccupied
    again: the paper's "integral computed twice, once with the usual visibility function,
    and again with 1 - visibility function shifted back by the fixed thickness", summed.
    With the normal (Sec. 4.4) the segment ends at the tangent plane: hi < z_s.

    Parameters
    ----------
    lo, hi : float or array_like
        Ends of the segment in line coordinates of the unit sphere; ``hi < lo`` means an
        empty segment (both integrals 0).
    occ_lo, occ_hi : float or array_like
        The occupied interval: the surface's line coordinate d_r and the back of the
        surface (``np.inf`` for a solid half-space behind the depth buffer). May lie
        anywhere on the line; only their part inside [lo, hi] counts.
    z_s : float or array_like
        Half-length of the line's chord in the unit sphere, z_s = sqrt(1 - x^2 - y^2) for
        the disk offset (x, y); only the quadratic falloff uses it.
    falloff : {"constant", "quadratic"}, optional
        The falloff rho along the line (default ``"constant"``), as in
        :func:`falloff_integral`.

    Returns
    -------
    unoccupied, total : ndarray
        Integral of rho over the unoccupied part of [lo, hi], and over all of [lo, hi]; of
        the broadcast shape of the inputs.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.1 (the line integral
    int_{-z_s}^{z_s} f(z) dz = max(min(z_s, d_r) + z_s, 0)), Sec. 4.3 (thickness), Sec. 4.4
    (the segment clamped at the tangent plane).

    Examples
    --------
    The centre line (z_s = 1) with the surface at d_r = 0.25: the paper's
    max(min(1, 0.25) + 1, 0) = 1.25 of the chord's 2 is unoccupied; a thickness that ends
    at 0.75 opens the last 0.25 again.

    >>> import numpy as np
    >>> u, t = line_integral(-1.0, 1.0, 0.25, np.inf, 1.0)
    >>> float(u), float(t)
    (1.25, 2.0)
    >>> float(line_integral(-1.0, 1.0, 0.25, 0.75, 1.0)[0])
    1.5
    """
    hi = np.maximum(hi, lo)
    total = falloff_integral(lo, hi, z_s, falloff=falloff)
    # Loos & Sloan 2010, Sec. 4.1, line integral of f(z): the segment minus its occupied
    # part [max(d_r, lo), min(occ_hi, hi)]; Sec. 4.3: occ_hi < inf is the thickness model
    a = np.clip(occ_lo, lo, hi)
    b = np.clip(occ_hi, lo, hi)
    occupied = falloff_integral(a, b, z_s, falloff=falloff)
    return total - occupied, total


def _intervals_line_integral(lo, hi, occupied, z_s, falloff):
    """:func:`line_integral` with several occupied intervals: ``occupied`` yields the
    (occ_lo, occ_hi) of each, disjoint, in line coordinates. The unoccupied integral is the
    segment's minus the sum over the intervals of their overlaps with it (each integrated
    exactly, :func:`falloff_integral`); with one interval the same operations as
    :func:`line_integral`, so the same values bit for bit."""
    hi = np.maximum(hi, lo)
    total = falloff_integral(lo, hi, z_s, falloff=falloff)
    occ = 0.0
    for occ_lo, occ_hi in occupied:
        # Loos & Sloan 2010, Sec. 4.1 and 4.3: each solid interval [front, back] removes its
        # part inside the segment, [max(front, lo), min(back, hi)]
        occ = occ + falloff_integral(np.clip(occ_lo, lo, hi), np.clip(occ_hi, lo, hi), z_s, falloff=falloff)
    return total - occ, total


@C.inner_frame
def vo_line(gbuffer, *, radius: float, samples=9, normal_clamp: bool = False, thickness=None,
            falloff: str = "constant", randomize: bool = True, seed=0, fetch: str = "nearest",
            offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE, frame: int = 0,
            schedule: str = "white") -> np.ndarray:
    """Volumetric Obscurance by line sampling (Loos & Sloan 2010, Sec. 4.1).

    For each disk sample (x, y) of the pattern, the chord [-z_s, z_s] of the unit sphere
    around the pixel's point p (z_s = sqrt(1 - x^2 - y^2)) is compared analytically with the
    depth d_r read where the disk point p + R (x, y, 0) projects: the part in front of the
    depth buffer is unoccupied. The chords are combined with the pattern's footnote-5
    weights w_i, in ratio form (Notes).

    Parameters
    ----------
    gbuffer : GBuffer
        The view's depth and view-space normals, as for :func:`vobscure.vo_point` (any
        pinhole or orthographic camera); the normals are read only with ``normal_clamp``.
    radius : float
        Radius R of the ball around each pixel's point, in world units (> 0).
    samples : int or SamplePattern, optional
        The disk pattern: a count n >= 1 for the default point-symmetric pattern
        ``vobscure.patterns.disk(n)`` (default 9: the larger line configuration of Loos &
        Sloan 2010, Table 1), or a
        :class:`~vobscure.patterns.SamplePattern` with (n, 2) ``points`` in the unit disk and
        (n,) footnote-5 ``weights``. Counts n <= 33, 64, 65, 128, 129, 256 and 257 load from
        the precomputed tables; any other count is built by the quick generator
        (:mod:`vobscure.patterns.quick`: about a second at most, once per process): the
        sunflower spiral refined by a bounded electrostatic relaxation for n <= 128, the
        spiral as it is above. n > 65536 raises ValueError (for converged values use
        :func:`vobscure.vo_reference`).
    normal_clamp : bool, optional
        Restrict the ball to the half-ball on the normal's side (Sec. 4.4): every chord is
        clipped at the tangent plane. A flat open surface then reads 1.0 instead of 0.5.
        Default False.
    thickness : float or "layers", optional
        Thickness model (Sec. 4.3): a point of the line is occupied only within this world
        thickness (> 0) behind the depth buffer. ``"layers"``: the G-buffer's solid intervals
        (``gbuffer.intervals``, from ``render_gbuffer(..., layers=K)`` or
        :meth:`vobscure.GBuffer.with_intervals`) at the tapped pixel: the occupied part of the
        line is the sum of the overlaps of those intervals with its chord, each integrated
        exactly with the falloff (Notes). Default None: everything behind the depth buffer is
        solid.
    falloff : {"constant", "quadratic"}, optional
        The falloff rho: ``"constant"`` (default, the paper's choice), or ``"quadratic"``,
        rho = 1 - r^2 with r the distance from p over R (z_s^2 - z^2 along the line); see
        :func:`falloff_integral`.
    randomize : bool, optional
        Reflect the pattern per pixel about a random 2-D direction (Sec. 4.5), read from a
        tiled ``noise_size`` x ``noise_size`` texture of unit vectors. Default True; False
        uses the pattern as given at every pixel (``seed`` is then unused).
    seed : int, numpy.random.Generator or None, optional
        Seed of the random texture (default 0), as for :func:`vobscure.vo_point`.
    fetch : {"nearest", "bilinear"}, optional
        How the depth for a disk point is read. ``"nearest"`` (default): the depth of the
        pixel the point falls in, the line keeping its exact offset (x, y); the tap offset
        is rounded with ``rint``, so a point-symmetric pattern reads point-symmetric pixels.
        ``"bilinear"``: 1/z (perspective) or z (orthographic) interpolated between the four
        nearest pixel centres, exact on planes; where any tap of a pixel would interpolate
        towards background, all of that pixel's taps are snapped to pixel centres (offsets
        recomputed there). With ``thickness="layers"`` the intervals are read as
        ``"nearest"`` reads the depth, whatever ``fetch`` says (interval ends are not
        interpolated across pixels).
    offscreen : {"clamp", "open"}, optional
        Disk points that project off the image read the nearest border pixel
        (``"clamp"``, default) or empty space (``"open"``).
    noise_size : int, optional
        Edge of the tiled random texture in pixels, as for :func:`vobscure.vo_point`
        (default 4). Unused without ``randomize``.
    frame, schedule : int, str, optional
        The frame (>= 0, default 0) of a noise schedule (default ``"white"``), as for
        :func:`vobscure.vo_point`; unused without ``randomize``.

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1], as for :func:`vobscure.vo_point` (1 = open, NaN on
        background, float32 for a float32 G-buffer). Depth-buffer taps per pixel: n, one
        per sample.

    Raises
    ------
    ValueError
        For the arguments :func:`vobscure.vo_point` rejects (``thickness="layers"`` on a
        G-buffer without intervals among them), ``samples`` being a disk pattern here; the
        message names the argument.

    Notes
    -----
    With chords U_i (unoccupied integral of rho over sample i's segment, clipped at the
    tangent plane with ``normal_clamp``), E_i (integral of rho over that segment) and N_i
    (over the whole chord [-z_s, z_s]), the visibility is

        V = sum_i w_i U_i / N_i  /  sum_i w_i E_i / N_i,

    the footnote-5 weighting ("each sample will scale its line integral by the integral of
    all the discrete samples in its Voronoi region") in ratio form. Without the normal
    E_i = N_i and the denominator is 1 (sum w_i = 1); with it, a plane reads exactly 1.

    With ``thickness="layers"`` a line reads the solid intervals [front_m, back_m] of the
    pixel its disk point falls in, and

        U_i = E_i - sum_m int_{[front_m, back_m] within the segment} rho,

    every end mapped to the line coordinate as the depth is. The intervals ``[d, +inf)`` give
    the single depth buffer's occupancy and ``[d, d + t]`` the thickness model t, up to the
    order of the floating-point operations. The ends are read at the tapped pixel, not
    interpolated: across a silhouette the neighbours' intervals belong to different objects,
    and a blend of their ends would be an interval of neither (``docs/screenspace.md``,
    "Thickness from layers").

    Under a perspective camera the depths are mapped to the sphere's line coordinate with
    the projective warp d_r = (z_p / R) (1 - z_p / d) instead of the paper's linear
    (d - z_p) / R; the two agree to first order in (d - z_p) / z_p and the warp keeps
    planes exact. Both read each line's depth along the pixel's line of sight, which for a
    pixel off the view axis crosses the ball obliquely: the estimate converges to a ball
    sheared by the off-axis angle, not to :func:`vobscure.vo_reference` (measured in
    ``docs/screenspace.md``; the difference shrinks with the field of view, not the
    radius). Under an orthographic camera the two converge to the same value.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010: Sec. 4.1 (the line integral
    int_{-z_s}^{z_s} f(z) dz = max(min(z_s, d_r) + z_s, 0), z_s = sqrt(1 - x^2 - y^2)),
    Sec. 4.3 (thickness: the integral computed twice and summed), Sec. 4.4 and footnote 4
    (clamping at the tangent plane given by the eye-space normal), Sec. 4.5 (reflection
    about a random 2-D direction per pixel from a random texture) and footnote 5 (weights).

    Examples
    --------
    A plane reads 1/2 with the whole ball and 1 with the half-ball:

    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> v = vo.vo_line(gb, radius=0.3, samples=9)
    >>> round(float(v[4, 4]), 6), round(float(vo.vo_line(gb, radius=0.3, normal_clamp=True)[4, 4]), 6)
    (0.5, 1.0)
    """
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    pattern = C.as_pattern(samples, 2)
    normal_clamp = C.check_bool(normal_clamp, "normal_clamp")
    intervals = C.solid_intervals(gbuffer, thickness)
    thickness = C.check_common(fetch=fetch, offscreen=offscreen, falloff=falloff,
                               thickness=None if intervals is not None else thickness, noise_size=noise_size)
    texture = C.noise_texture(noise_size, seed, 2, randomize, frame=frame, schedule=schedule)
    prepared = C.frame(gbuffer, radius)
    gb, depth64, index = prepared
    options = dict(radius=radius, normal_clamp=normal_clamp, thickness=thickness, falloff=falloff,
                   offscreen=offscreen)
    if fetch == "bilinear" and intervals is None:
        kernel = partial(_line_kernel, pattern=pattern, texture=texture, **options)
        return C.run_chunks(gb, radius, kernel, C.out_dtype(gbuffer), prepared=prepared)
    H, W = gb.depth.shape
    out = np.full(H * W, np.nan, dtype=C.out_dtype(gbuffer))
    if not len(index):
        return out.reshape(H, W)
    if intervals is None:
        # the largest projected radius decides how wide a border the taps can reach
        z_min = float(np.min(depth64[index]))
        # (the larger of its x and y extents: fx != fy for non-square pixels)
        padded = C.padded_depth(depth64, (H, W), radius * float(np.max(gb.camera.pixels_per_unit_xy(z_min))),
                                offscreen)
    else:
        padded = None       # the layers are gathered from the clamped tap index (C.tap_pixel)
        options["intervals"] = intervals
    antipodal = _exactly_antipodal(pattern)
    for chunk, v in C.noise_classes(depth64, (H, W), texture):
        px = C.prepare(gb, radius, index=chunk, depth64=depth64)
        if v is not None and v.ndim == 2:
            # a large tile: a texel per pixel, the reflection done per pixel in the kernel
            out[chunk] = _line_nearest(px, points=pattern.points, weights=pattern.weights, padded=padded,
                                       antipodal=antipodal, turn=v, **options)
            continue
        # Sec. 4.5: reflection about a random 2-D direction per pixel, 2 (s . v) v - s; one
        # texel of the tiled texture per chunk, so the reflected points are the same for
        # every pixel of the chunk
        points = pattern.points if v is None else 2.0 * (pattern.points @ v)[:, None] * v - pattern.points
        out[chunk] = _line_nearest(px, points=points, weights=pattern.weights, padded=padded,
                                   antipodal=antipodal, **options)
    return out.reshape(H, W)


def _exactly_antipodal(pattern) -> bool:
    """True when every point's exact negation is in the pattern with exactly its weight.

    Then, in the clamped line sum, the tangent-plane terms of the two lines of a pair cancel
    exactly (rint is odd, the plane is linear in the tap offset, the clip is symmetric), and
    the half-ball's share the samples see is the constant sum of w / 2 (see
    :func:`_line_nearest`). The reflection of Sec. 4.5 is linear, so it keeps pairs exact.
    """
    pts, w = pattern.points, pattern.weights
    for i in range(len(pts)):
        match = np.flatnonzero(np.all(pts == -pts[i], axis=1) & (w == w[i]))
        if not len(match):
            return False
    return True


def _line_nearest(px, *, points, weights, radius, normal_clamp, thickness, falloff, offscreen, padded,
                  antipodal=False, intervals=None, turn=None):
    """Line-sampled VO of pixels that share one rotated pattern, nearest fetch (see :func:`vo_line`).

    With ``turn`` (k, 2), unit vectors, one per pixel, each pixel reflects ``points`` about
    the line along its own vector (Sec. 4.5), here in the tap offsets: the reflection
    2 (s . v) v - s is the matrix [[c, s], [s, -c]] with c = 2 v_x^2 - 1 and s = 2 v_x v_y
    (cosine and sine of twice v's angle), folded with the projected radius once per chunk. It
    keeps a point's length, so the chord z_s (and whether a point is on the rim) is the
    pattern point's, a scalar as for shared points.

    Each line keeps its exact disk offset (x, y), hence a scalar z_s per sample, and reads
    the depth of the pixel its disk point falls in (the same occupancy test as
    :func:`vo_reference`). A point-symmetric pattern stays exact on planes: the tap offsets
    are rounded with ``rint``, an odd function, so antipodal samples read antipodal pixels
    whose warped depths are opposite on a plane, and the two chords add up to exactly half.
    With ``normal_clamp`` the tangent plane is crossed at the *tapped* pixel's offset, where
    the plane's depth was read, so a plane reads exactly 1.

    The inner loop works in place on a few (k,) buffers; the constant parts of the sums
    (the z_s half of every chord) are accumulated as scalars. With ``normal_clamp`` the
    denominator, the half-ball's share the lines see, is sum k_s (hi_s + z_s); for an
    exactly antipodal pattern (``antipodal``) the hi_s of a pair are opposite and cancel,
    so it is the constant sum k_s z_s and is not accumulated per pixel.

    With ``intervals`` (``thickness="layers"``) each line reads the solid intervals of the
    tapped pixel instead of its depth: the occupied part of its segment is the sum of the
    intervals' overlaps with it (:func:`_intervals_line_integral`).
    """
    k = len(px.index)
    r_x, r_y = px.radius_px_x, px.radius_px      # the projected radius along x and y (pixels)
    z = px.z
    base = C.padded_base(px, padded) if padded is not None else None
    dj, e, t, d = np.empty(k), np.empty(k), np.empty(k), np.empty(k)
    num = np.zeros(k)
    simple = falloff == "constant" and thickness is None and intervals is None
    if intervals is not None:
        fronts, backs = C.interval_slots(intervals)
    # unclamped (constant falloff), or clamped with an exactly antipodal pattern, the
    # denominator is the scalar ``const`` (docstring)
    den = np.zeros(k) if (not simple or (normal_clamp and not antipodal)) else None
    if normal_clamp:
        # tangent plane crossing z_plane = gx x + gy y (Sec. 4.4, footnote 4), per tap pixel:
        # x = dj / r_x, y = e / r_y
        gx, gy = C.tangent_plane_coefficients(px)
        gx, gy = gx / r_x, gy / r_y
    if px.perspective:
        a, b = z / radius, z * z / radius          # warp: d_r = a - b / d (C.warp)
    if intervals is not None:
        # the interval ends to line coordinates by the operations the depth d goes through
        # below, so the intervals [d, +inf) read exactly what d does
        if px.perspective:
            def warp(depth):
                return a - b / depth
        else:
            inv_radius = 1.0 / radius

            def warp(depth):
                return (depth - z) * inv_radius
    raw = np.empty(k) if thickness is not None else None
    if turn is not None:
        # Sec. 4.5, the per-pixel reflection times the projected radius: the tap offsets
        # (dj, e) = (R_x x', R_y y') of the reflected point (x', y') = (c x + s y, s x - c y)
        v_x, v_y = turn[:, 0], turn[:, 1]
        c2 = 2.0 * v_x * v_x - 1.0          # cos and sin of twice the angle of v
        s2 = 2.0 * v_x * v_y
        j_x, j_y = r_x * c2, r_x * s2        # dj = j_x x + j_y y
        e_x, e_y = r_y * s2, -r_y * c2       # e = e_x x + e_y y
    const = 0.0     # the scalar parts of num and den
    wsum = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        for (x, y), w in zip(points, weights):
            # Loos & Sloan 2010, Sec. 4.1: z_s = sqrt(1 - x^2 - y^2)
            z_s2 = 1.0 - x * x - y * y
            if not z_s2 > 0.0:
                continue        # a point on the rim has no chord
            z_s = float(np.sqrt(z_s2))
            # the pixel the disk point p + R (x, y, 0) falls in
            if turn is None:
                np.multiply(r_x, x, out=dj)
                np.multiply(r_y, y, out=e)
            else:
                np.multiply(j_x, x, out=dj)
                np.multiply(j_y, y, out=t)     # t: scratch until the tap is read
                dj += t
                np.multiply(e_x, x, out=e)
                np.multiply(e_y, y, out=t)
                e += t
            np.rint(dj, out=dj)
            np.rint(e, out=e)
            if intervals is not None:
                # the tapped pixel, whose intervals are read below (none: empty space)
                tap, empty = C.tap_pixel(px, dj, e, offscreen=offscreen)
                empty = empty if empty.any() else None
            else:
                C.nearest_taps(px, dj, e, offscreen=offscreen, padded=padded, base=base, out=d, scratch=t)
                if raw is not None:
                    raw[:] = d
                # depth -> line coordinate d_r of the unit sphere, in place in d (C.warp; the
                # paper's linear (d - z_p) / R of Sec. 4.1 under an orthographic camera)
                if px.perspective:
                    np.divide(b, d, out=d)
                    np.subtract(a, d, out=d)
                else:
                    d -= z
                    d *= 1.0 / radius
            if normal_clamp:
                # Sec. 4.4: the chord ends where the tangent plane crosses it, in t
                np.multiply(gx, dj, out=t)
                np.multiply(gy, e, out=dj)
                t += dj
                np.clip(t, -z_s, z_s, out=t)       # hi: the segment is [-z_s, hi]
            if simple:
                k_s = 0.5 * w / z_s                # footnote 5: weight w over the chord N = 2 z_s
                if normal_clamp:
                    # Sec. 4.1 and 4.4: unoccupied = clip(d_r, -z_s, hi) + z_s, total = hi + z_s
                    np.clip(d, -z_s, t, out=d)         # hi >= -z_s: max(min(d, hi), -z_s)
                    d *= k_s
                    num += d
                    if den is not None:
                        t *= k_s
                        den += t
                else:
                    # Sec. 4.1: max(min(z_s, d_r) + z_s, 0), as k_s clip(d_r) + w / 2
                    d *= k_s
                    np.clip(d, -0.5 * w, 0.5 * w, out=d)
                    num += d
                const += k_s * z_s
                wsum += w
                continue
            hi = t if normal_clamp else z_s
            if intervals is not None:
                # the solid intervals of the tapped pixel, each end warped to the line
                # coordinate as the depth is (none off the image with offscreen="open")
                ends = []
                for m in range(intervals.count):
                    f_m, b_m = fronts[m].take(tap), backs[m].take(tap)
                    if empty is not None:
                        f_m, b_m = np.where(empty, np.inf, f_m), np.where(empty, np.inf, b_m)
                    ends.append((warp(f_m), warp(b_m)))
                unocc, total = _intervals_line_integral(-z_s, hi, ends, z_s, falloff)
            else:
                # occupied from the surface to the thickness (Sec. 4.3), or to infinity
                if thickness is None:
                    occ_hi = np.inf
                elif px.perspective:
                    occ_hi = a - b / (raw + thickness)
                else:
                    occ_hi = (raw + thickness - z) / radius
                unocc, total = line_integral(-z_s, hi, d, occ_hi, z_s, falloff)
            # footnote 5: the chord's weight w over its full integral N = int_{-z_s}^{z_s} rho
            scale = w / float(falloff_integral(-z_s, z_s, z_s, falloff=falloff))
            num += scale * unocc
            den += scale * np.broadcast_to(total, (k,))
    if simple and not normal_clamp:
        return np.clip((num + const) / wsum, 0.0, 1.0) if wsum > 0 else np.ones(k)
    if simple:
        num += const
        if den is None:        # antipodal: the pairs' plane terms cancelled
            return np.clip(num / const, 0.0, 1.0) if const > 0 else np.ones(k)
        den += const
    # clamped, den is the half-ball's share seen by the samples (0: the whole ball lies
    # behind the tangent plane, nothing to occlude)
    vis = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    return np.clip(vis, 0.0, 1.0)


def _line_kernel(px, *, radius, pattern, normal_clamp, thickness, falloff, offscreen, texture):
    """Line-sampled VO of one chunk of pixels with the bilinear fetch (see :func:`vo_line`)."""
    k = len(px.index)
    v = C.noise_at(px, texture)
    vx, vy = (None, None) if v is None else (np.ascontiguousarray(v[:, 0]), np.ascontiguousarray(v[:, 1]))
    if normal_clamp:
        # the tangent plane's line coordinate is linear in the offset: z_plane = gx x + gy y
        # (Sec. 4.4, footnote 4; C.tangent_plane_line derives it)
        gx, gy = C.tangent_plane_coefficients(px)
    warp = C.warper(px, radius)
    num = np.zeros(k)
    den = np.zeros(k)
    bilinear = C.bilinear_ok(px, (C.reflect(s, v, k) for s in pattern.points), offscreen=offscreen)
    for s, w in zip(pattern.points, pattern.weights):
        # Sec. 4.5: reflection about a random 2-D direction per pixel: 2 (s . v) v - s
        if vx is None:
            ox, oy = np.full(k, s[0]), np.full(k, s[1])
        else:
            dot2 = 2.0 * (vx * s[0] + vy * s[1])
            ox, oy = dot2 * vx - s[0], dot2 * vy - s[1]
        d, xy = C.fetch_disk(px, np.column_stack([ox, oy]), fetch="bilinear", offscreen=offscreen,
                             bilinear=bilinear)
        ox, oy = xy[:, 0], xy[:, 1]
        z_s = np.sqrt(np.maximum(0.0, 1.0 - ox * ox - oy * oy))   # Loos & Sloan 2010, Sec. 4.1
        # depth -> line coordinate d_r of the unit sphere (Sec. 4.1; the warp under perspective)
        d_r = warp(d)
        # Sec. 4.4: "clamp the evaluation of the integral" at the tangent plane's depth
        hi = np.minimum(z_s, np.clip(gx * ox + gy * oy, -4.0, 4.0)) if normal_clamp else z_s
        # occupied from the surface to the thickness (Sec. 4.3), or to infinity
        occ_hi = np.inf if thickness is None else warp(d + thickness)
        unocc, total = line_integral(-z_s, hi, d_r, occ_hi, z_s, falloff)
        # footnote 5: the chord's weight w over its full integral N = int_{-z_s}^{z_s} rho
        full = falloff_integral(-z_s, z_s, z_s, falloff=falloff)
        ok = full > 0   # a snapped point can leave the disk: it then has no segment
        scale = np.where(ok, w / np.where(ok, full, 1.0), 0.0)
        num += scale * unocc
        den += scale * total
    # unclamped, den is the weight of the segments that exist (1 unless snapping moved
    # points out of the disk); clamped, it is the half-ball's share seen by the samples
    vis = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    return np.clip(vis, 0.0, 1.0)
