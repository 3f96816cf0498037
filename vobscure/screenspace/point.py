"""Point sampling of Volumetric Obscurance (Loos & Sloan 2010, Sec. 4; the Crytek / StarCraft II
family the paper compares against) and the converged screen-space reference.

The paper does not number its equations; they are cited by section and content (the list is
in ``docs/screenspace.md``, "How the paper is cited").
"""

from __future__ import annotations

from functools import lru_cache, partial

import numpy as np

from .._validate import as_rng, check_int
from ..estimate import DEFAULT_GROUPS, Estimate
from ..patterns import SamplePattern
from ..camera.kernel import project_xy
from ..sampling import cube_to_uniform_ball
from . import _common as C
from ._segment import PlaneTables, on_one_plane, plane_labels, ray_kernel
from ._segment_fast import CHUNK_PIXELS as SEGMENT_CHUNK_PIXELS
from ._segment_fast import DepthCells, balanced_parts, parallel_chunks, segment_kernel

__all__ = ["vo_point", "vo_reference", "point_taps"]


def _point_vo(gbuffer, *, radius, pattern: SamplePattern, normal_clamp, thickness, falloff,
              randomize, seed, fetch, offscreen, noise_size, intervals=None, frame=0, schedule="white"):
    """Point-sampled VO (:func:`vo_point`); ``intervals``: the G-buffer's solid intervals
    (``thickness="layers"``, resolved by the caller; ``thickness`` is then None)."""
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    thickness = C.check_common(fetch=fetch, offscreen=offscreen, falloff=falloff, thickness=thickness,
                               noise_size=noise_size)
    texture = C.noise_texture(noise_size, seed, 3, randomize, frame=frame, schedule=schedule)
    kernel = partial(_point_kernel, radius=radius, pattern=pattern, normal_clamp=normal_clamp,
                     thickness=thickness, falloff=falloff, fetch=fetch, offscreen=offscreen,
                     texture=texture, intervals=intervals)
    return C.run_chunks(gbuffer, radius, kernel, C.out_dtype(gbuffer))


def _ray_vo(gbuffer, *, radius, unit, normal_clamp, thickness, falloff, rng, fetch, offscreen, fast=True,
            flat=None, cells=None):
    """The ball VO from the view-ray segments of the ``unit`` square points (each uniform)
    (:mod:`vobscure.screenspace._segment`), toroidally shifted per pixel by a tiled
    64 x 64 texture of uniform shifts. Pixels whose ball reaches the eye's plane z = 0
    (perspective) are point sampled instead, with as many points. ``fast``: the kernel of
    :mod:`vobscure.screenspace._segment_fast` (the same values within the rounding of its
    float32 steps), its chunks on threads; False: the plain ``_segment.ray_kernel``, one chunk
    after another.
    ``flat``: None or the (H, W) bool image of :func:`_exact_pixels` (the pixels whose rays all
    read their own plane), which take the value the kernel returns there, 1/2 (1 with
    ``normal_clamp``), without integrating their segments. ``cells``: the
    :class:`~vobscure.screenspace._segment_fast.DepthCells` of the image when the caller has
    them (they do not depend on the rays)."""
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    thickness = C.check_common(fetch=fetch, offscreen=offscreen, falloff=falloff, thickness=thickness)
    texture = rng.random((64, 64, 2))
    # drawn before the chunks run (on threads, in any order), whether or not a ball reaches z = 0
    half = max(1, len(unit) // 2)
    pts = cube_to_uniform_ball(np.column_stack([unit[:half], rng.random(half)]))
    fallback = dict(pattern=SamplePattern(np.vstack([pts, -pts]), np.ones(2 * half)),
                    texture=C.noise_texture(64, rng, 3, True))
    gb, depth64, index = C.frame(gbuffer, radius)
    if fast and fetch == "bilinear" and cells is None:
        cells = DepthCells(depth64.reshape(gb.depth.shape), gb.camera.is_perspective)

    def segments(px):
        shift = C.noise_at(px, texture)
        if fast:
            v, exact = segment_kernel(px, radius=radius, unit=unit, normal_clamp=normal_clamp, thickness=thickness,
                                      falloff=falloff, cells=cells if fetch == "bilinear" else None,
                                      offscreen=offscreen, shift=shift)
        else:
            v, exact = ray_kernel(px, radius=radius, unit=unit, normal_clamp=normal_clamp, thickness=thickness,
                                  falloff=falloff, fetch=fetch, offscreen=offscreen, shift=shift)
        if not exact.all():
            sub = C.prepare(gb, radius, index=px.index[~exact], depth64=depth64)
            v[~exact] = _point_kernel(sub, radius=radius, pattern=fallback["pattern"], normal_clamp=normal_clamp,
                                      thickness=thickness, falloff=falloff, fetch=fetch, offscreen=offscreen,
                                      texture=fallback["texture"])
        return v

    if flat is not None:
        # the exact pixels take the closed form; only the others are integrated
        index = index[~flat.reshape(-1)[index]]
    parts = balanced_parts(index, SEGMENT_CHUNK_PIXELS if fast else C.CHUNK_PIXELS)

    def run(ix):
        return segments(C.prepare(gb, radius, index=ix, depth64=depth64))
    H, W = gb.depth.shape
    out = np.full(H * W, np.nan)
    if flat is not None:
        out[flat.reshape(-1)] = 1.0 if normal_clamp else 0.5
    for ix, v in zip(parts, parallel_chunks(run, parts) if fast else [run(ix) for ix in parts]):
        out[ix] = v
    return out.reshape(H, W)


def _plane_tables(gbuffer, *, thickness, fetch):
    """The :class:`PlaneTables` of a rendered G-buffer for the plane shortcut of :func:`_ray_vo`
    (which holds for the bilinear fetch without thickness), else None."""
    if thickness is not None or fetch != "bilinear":
        return None
    labels = plane_labels(gbuffer)
    return None if labels is None else PlaneTables(labels, gbuffer.depth)


#: Pixels per chunk of :func:`_exact_pixels`' tests of other surfaces and of the image's edge
#: (the plane-only test takes the estimators' chunks). Those tests run many small NumPy calls
#: per chunk, so a chunk of 512 pixels spent most of its time in the calls' overhead: the
#: candidates' test of ``vo_reference`` at 1280 x 720 took 3.4-3.7 s on the Cornell box and
#: 6.4-8.7 s on the atrium with 512, 1.0-1.1 s and 1.4-1.5 s with 4096, 0.9-1.0 s with 16384
#: (the same pixels found). Peak memory of the whole reference with 4096: docs/screenspace.md.
EXACT_CHUNK_PIXELS = 4096


def _exact_pixels(gbuffer, radius, tables: PlaneTables, offscreen: str = "clamp", *, clear: bool = True,
                  candidates=None) -> np.ndarray:
    """(H, W) bool: the pixels of :func:`vobscure.screenspace._segment.on_one_plane` (every
    view ray through the ball reads the pixel's own plane, or, with ``clear``, a depth that lies
    with the plane's beyond the ball's depth range), whose reference value is exact.
    ``candidates``: an (H, W) bool image of the only pixels to examine (the others are not
    exact), else every covered pixel."""
    gb, depth64, index = C.frame(gbuffer, radius)
    if candidates is not None:
        index = index[candidates.reshape(-1)[index]]
    # the tests of other surfaces hold a row per box of texels per pixel (thousands for a large
    # footprint): smaller chunks keep their memory near the plane-only test's
    parts = balanced_parts(index, C.CHUNK_PIXELS if not clear else EXACT_CHUNK_PIXELS)

    def run(ix):
        px = C.prepare(gb, radius, index=ix, depth64=depth64)
        return on_one_plane(px, radius, tables, clear=clear, offscreen=offscreen)
    flat = np.zeros(gb.depth.size, dtype=bool)
    # on threads (NumPy releases the GIL in its loops); each chunk's pixels are its own
    for ix, ok in zip(parts, parallel_chunks(run, parts)):
        flat[ix] = ok
    return flat.reshape(gb.depth.shape)


def _is_centre(s) -> bool:
    """True for the sample at the ball's centre, which :func:`vo_point` does not tap."""
    return not np.any(s)


def point_taps(samples=12) -> int:
    """Depth taps per pixel that :func:`vo_point` makes with ``samples``.

    One per sample except the centre (s = 0) of an odd point-symmetric pattern, which lies
    on the surface and is counted without a fetch (see :func:`vo_point`).

    Parameters
    ----------
    samples : int or SamplePattern, optional
        As in :func:`vo_point`: a count 1 <= n <= 65536 for the default pattern
        ``vobscure.patterns.ball(n)`` (default 12), or a ball pattern ((n, 3) ``points``).

    Returns
    -------
    int
        The number of the pattern's points other than the centre.

    Raises
    ------
    ValueError
        If ``samples`` is neither a count 1 <= n <= 65536 nor a ball pattern.

    Examples
    --------
    The default 33-point pattern holds the centre, the 12-point one does not:

    >>> point_taps(12), point_taps(33)
    (12, 32)
    """
    pattern = C.as_pattern(samples, 3)
    return sum(not _is_centre(s) for s in pattern.points)


def _point_kernel(px, *, radius, pattern, normal_clamp, thickness, falloff, fetch, offscreen, texture,
                  intervals=None):
    """Point-sampled VO of one chunk of pixels (see :func:`vo_point`); with ``intervals``
    (:class:`vobscure.layers.SolidIntervals`) the occupancy is read from them at the nearest
    pixel instead of from the depth buffer."""
    k = len(px.index)
    v = C.noise_at(px, texture)
    vc = None if v is None else [np.ascontiguousarray(v[:, a]) for a in range(3)]
    nc = [np.ascontiguousarray(px.n[:, a]) for a in range(3)]
    pc = [np.ascontiguousarray(px.p[:, a]) for a in range(3)]
    num = np.zeros(k)
    den = np.zeros(k)
    for s, w in zip(pattern.points, pattern.weights):
        if _is_centre(s):
            # A sample at the ball's centre lies on the surface itself: the depth buffer
            # cannot tell which side it is on (the test z > d compares a depth with itself
            # up to rounding and filtering), and every point-symmetric pattern of odd n has
            # one. Its Voronoi region is a small ball around p, which the tangent plane
            # bisects: it counts half open for the ball and open for the half-ball (Sec.
            # 4.4), its expectation on a locally flat surface (docs/screenspace.md, "The
            # centre sample").
            num += w * (1.0 if normal_clamp else 0.5)
            den += w
            continue
        # Loos & Sloan 2010, Sec. 4.5: a random 3-D (Householder) reflection per pixel,
        # s - 2 (s . v) v
        if vc is None:
            o = [np.full(k, s[a]) for a in range(3)]
        else:
            dot2 = 2.0 * (vc[0] * s[0] + vc[1] * s[1] + vc[2] * s[2])
            o = [s[a] - dot2 * vc[a] for a in range(3)]
        if normal_clamp:
            # Loos & Sloan Sec. 4.4 (after Filion & McNaughton 2008): samples below the
            # tangent plane are reflected above it
            m = 2.0 * np.minimum(o[0] * nc[0] + o[1] * nc[1] + o[2] * nc[2], 0.0)
            o = [o[a] - m * nc[a] for a in range(3)]
        qx, qy, z = (pc[a] + radius * o[a] for a in range(3))
        # the camera's projection (vobscure.camera.kernel)
        with np.errstate(divide="ignore", invalid="ignore"):
            x, y = project_xy(qx, qy, z, px.fx, px.fy, px.cx, px.cy, px.perspective)
        if intervals is None:
            d = C.fetch_depth(px.depth, x, y, fetch=fetch, offscreen=offscreen, reciprocal=px.perspective)
            # occupied = 1 - O(x) of Sec. 4 (O = 1 in empty space): behind the depth buffer,
            # within the thickness when one is given (Sec. 4.3); z is the sample's view depth X_z
            occupied = (z > d) & (z > 0)
            if thickness is not None:
                occupied &= z < d + thickness
        else:
            # thickness="layers": occupied when X_z lies inside a solid interval of the pixel
            # X projects to, read at the nearest pixel (interval ends are not interpolated:
            # docs/screenspace.md, "Thickness from layers")
            index, empty = C.nearest_pixel(px.shape, x, y, offscreen=offscreen)
            occupied = C.inside_intervals(intervals, index, z) & ~empty & (z > 0)
        # rho(d(P, x)) of Sec. 4: 1, or 1 - |s|^2 (reflections keep |s|)
        rho = 1.0 if falloff == "constant" else 1.0 - float(s @ s)
        num += (w * rho) * ~occupied
        den += w * rho
    return np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)


@C.inner_frame
def vo_point(gbuffer, *, radius: float, samples=12, normal_clamp: bool = False, thickness=None,
             falloff: str = "constant", randomize: bool = True, seed=0, fetch: str = "bilinear",
             offscreen: str = "clamp", noise_size: int = C.NOISE_SIZE, frame: int = 0,
             schedule: str = "white") -> np.ndarray:
    """Volumetric Obscurance by point sampling of the ball (Loos & Sloan 2010, Sec. 4).

    Each 3-D sample X = p + R s of the ball pattern is projected to the screen and is
    occupied when it lies behind the depth buffer there (within ``thickness`` behind it
    when given): a Monte Carlo estimate of the paper's V(P) = int_X rho(d(P, x)) O(x) dx,
    normalized by int_X rho. Visibility is the weighted unoccupied fraction. A sample at
    the centre (s = 0, in every symmetric pattern of odd n) lies on the surface, where the
    depth test is undecidable; it counts half open (open with ``normal_clamp``), its
    expectation on a locally flat surface, and is not tapped (:func:`point_taps`). With
    point-symmetric patterns a plane then reads 1/2 (1 clamped) up to the depth buffer's
    quantization.

    Parameters
    ----------
    gbuffer : GBuffer
        The view's depth (H, W) (view-space z > 0, +inf on background) and view-space
        normals (H, W, 3) (facing the camera, n_z < 0), from
        :func:`vobscure.render_gbuffer`; perspective (any pinhole: principal point
        anywhere, fx != fy allowed) or orthographic camera. The normals
        are read only with ``normal_clamp``.
    radius : float
        Radius R of the ball around each pixel's point, in world units (> 0).
    samples : int or SamplePattern, optional
        The ball pattern: a count n >= 1 for the default point-symmetric pattern
        ``vobscure.patterns.ball(n)`` (default 12: the smaller point configuration of Loos &
        Sloan 2010, Table 1, and ``vobscure compare``'s default), or a
        :class:`~vobscure.patterns.SamplePattern` with (n, 3) ``points`` in the unit ball
        and (n,) volume ``weights``. Counts n <= 40, 64, 65, 128, 129, 256 and 257 load
        from the precomputed tables; any other count is built by the quick generator
        (:mod:`vobscure.patterns.quick`: about a second at most, once per process): a
        spherical-Fibonacci spiral refined by a bounded electrostatic relaxation for
        n <= 512, the spiral as it is above. n > 65536 raises ValueError (for converged
        values use :func:`vo_reference`).
    normal_clamp : bool, optional
        Reflect samples below the tangent plane above it (Sec. 4.4, after Filion &
        McNaughton 2008): the half-ball on the normal's side. A plane then reads 1.0
        instead of 0.5. Default False.
    thickness : float or "layers", optional
        Thickness model (Sec. 4.3): a sample is occupied only within this world thickness
        (> 0) behind the depth buffer. ``"layers"``: what is behind the depth buffer is read
        from the G-buffer's solid intervals (``gbuffer.intervals``, from
        ``render_gbuffer(..., layers=K)`` or :meth:`vobscure.GBuffer.with_intervals`): a
        sample is occupied when its view depth lies inside a solid interval of the pixel it
        projects to, that pixel's intervals read as they are (nearest; Notes). Default None:
        everything behind the depth buffer is solid.
    falloff : {"constant", "quadratic"}, optional
        The falloff rho: ``"constant"`` (default, the paper's choice, Sec. 4) or
        ``"quadratic"``, rho = 1 - |s|^2; samples are weighted by rho and the result is
        normalized by the sum of the weights.
    randomize : bool, optional
        A random 3-D (Householder) reflection of the pattern per pixel (Sec. 4.5), read from
        a tiled ``noise_size`` x ``noise_size`` texture of unit vectors. Default True; False
        uses the pattern as given at every pixel (``seed`` is then unused).
    seed : int, numpy.random.Generator or None, optional
        Seed of the random texture (default 0), converted once: an int >= 0 or None
        (fresh OS entropy) goes through ``numpy.random.default_rng``, a Generator is used
        as is. The same int gives the same image.
    fetch : {"bilinear", "nearest"}, optional
        ``"bilinear"`` (default) reconstructs the surface between pixel centres as planes
        (interpolating 1/z under perspective, z orthographically), so a sample's occupancy
        on a plane is exact; ``"nearest"`` reads the pixel's depth as a constant over the
        pixel (staircase surfaces: a sample just above a tilted plane can read as behind
        it). Unused with ``thickness="layers"``, which reads the intervals of the pixel the
        sample falls in.
    offscreen : {"clamp", "open"}, optional
        Samples that project off the image read the nearest border pixel (``"clamp"``,
        default) or empty space (``"open"``); the same with ``thickness="layers"`` (the border
        pixel's intervals, or none).
    noise_size : int, optional
        Edge of the tiled random texture in pixels (>= 1, default
        ``vobscure.screenspace._common.NOISE_SIZE`` = 4): pixel (i, j) uses texel
        (i mod noise_size, j mod noise_size). Unused without ``randomize``.
    frame : int, optional
        The frame (>= 0, default 0) of the noise ``schedule``.
    schedule : {"white", "rotate", "r2", "gtao", "blue"}, optional
        How the texture changes from frame to frame (:mod:`vobscure.screenspace.noise`,
        ``docs/screenspace.md``, "Noise schedules"): ``"white"`` (default; frame 0 is the
        texture above), ``"rotate"``, ``"r2"`` or ``"gtao"`` (a 64 x 64 tile whatever
        ``noise_size``). Both are unused without ``randomize`` (and checked either way).

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1] (1 = open), NaN on background; float32 for a float32
        G-buffer, float64 otherwise (accumulated in float64). Depth-buffer taps per pixel:
        ``point_taps(samples)``, n without the centre sample.

    Raises
    ------
    ValueError
        If ``gbuffer`` is not a GBuffer, ``radius`` is not a positive finite number,
        ``thickness`` is neither None, a positive finite number nor ``"layers"`` (or is
        ``"layers"`` and ``gbuffer.intervals`` is None), ``samples`` is neither a count >= 1
        nor a ball pattern, ``seed``, ``noise_size`` or ``frame`` is invalid, or a choice argument
        (``schedule`` among them) is not one of its values; the message names the argument.

    Notes
    -----
    A sample is occupied when X_z > d (and X_z < d + thickness with the thickness model),
    d the depth buffer at X's projection; with ``thickness="layers"`` when
    front_m < X_z < back_m for one of the solid intervals m of the pixel X falls in (the
    intervals ``[d, +inf)`` give the depth-buffer test with a nearest fetch exactly, and
    ``[d, d + t]`` the thickness model t). The intervals are read at that pixel, never
    interpolated between pixels: across a silhouette the neighbours' intervals belong to
    different objects (a thin sheet in front, the floor behind), and a blend of their ends
    would be an interval of neither, solid where both are empty (``docs/screenspace.md``,
    "Thickness from layers"). With weights w_i and rho_i = rho(|s_i|),

        V = sum_i w_i rho_i O(X_i)  /  sum_i w_i rho_i,

    O = 1 for an unoccupied sample, 0 for an occupied one (the occupancy function of Sec. 4);
    the centre sample, when the pattern has one, enters with O = 1/2 (1 with
    ``normal_clamp``) and no tap.

    This is the point-sampling family the paper compares line sampling with (Crytek,
    Mittring 2007; StarCraft II, Filion & McNaughton 2008), not one of its own estimators.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010: Sec. 4 (V(P) = int_X rho(d(P, x)) O(x)
    dx, the constant or quadratic rho), Sec. 4.3 (thickness), Sec. 4.4 (reflecting the
    points below the hemisphere), Sec. 4.5 (per-pixel randomization from a random
    texture). Mittring, "Finding next gen: CryEngine 2", SIGGRAPH 2007 course; Filion &
    McNaughton, "Effects & techniques", SIGGRAPH 2008 course (StarCraft II).

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> float(vo.vo_point(gb, radius=0.3, samples=12, normal_clamp=True)[4, 4])
    1.0

    With the solid known to end 0.1 behind the surface (intervals ``[d, d + 0.1]``), the
    layers read the thickness model of 0.1 (the same test; a nearest fetch):

    >>> from vobscure.layers import SolidIntervals
    >>> layered = gb.with_intervals(SolidIntervals(gb.depth[None], gb.depth[None] + 0.1))
    >>> a = vo.vo_point(layered, radius=0.3, thickness="layers")
    >>> b = vo.vo_point(gb, radius=0.3, thickness=0.1, fetch="nearest")
    >>> bool(np.array_equal(a, b, equal_nan=True))
    True
    """
    normal_clamp = C.check_bool(normal_clamp, "normal_clamp")
    intervals = C.solid_intervals(gbuffer, thickness)
    return _point_vo(gbuffer, radius=radius, pattern=C.as_pattern(samples, 3), normal_clamp=normal_clamp,
                     thickness=None if intervals is not None else thickness, falloff=falloff,
                     randomize=randomize, seed=seed, fetch=fetch, offscreen=offscreen, noise_size=noise_size,
                     intervals=intervals, frame=frame, schedule=schedule)


@C.inner_frame
def vo_reference(gbuffer, *, radius: float, samples=4096, normal_clamp: bool = False,
                 thickness=None, falloff: str = "constant", seed=0, fetch: str = "bilinear",
                 offscreen: str = "clamp", groups: int = DEFAULT_GROUPS,
                 progress: bool = False) -> Estimate:
    """The converged screen-space VO: dense sampling of the depth-buffer occupancy.

    What every screen-space estimator tends to with infinitely many samples (line sampling
    exactly so under an orthographic camera): the reference that separates an estimator's
    sampling error from the error of the screen-space model itself. It integrates the same
    occupancy as :func:`vo_point`: a point X = p + R s of the ball (of the half-ball with
    ``normal_clamp``) is occupied when it lies behind the depth buffer at its projection
    (within ``thickness`` behind it with the thickness model).

    Each sample is a view ray through the ball: all of a ray's points project to the same
    place, so one depth fetch there gives the occupancy along the ray's whole segment in
    the ball, which is integrated exactly (volume element z^2 dz per unit of ray directions
    under perspective, dz per unit area orthographically; the quadratic falloff is a
    polynomial along the ray). The rays are drawn uniformly in the box of rays through the
    ball, on a randomly shifted rank-1 lattice (every ray uniform, the rays evenly spread), so
    the mean over rays times the box's measure estimates the occupied volume without bias; without ``normal_clamp`` the part of each
    segment behind the tangent plane is a control variate with the known mean half the
    ball, so planes read exactly 1/2 (``docs/screenspace.md``, "The converged reference").
    Pixels whose ball reaches the eye's plane z = 0 (perspective) sample points of the
    ball instead (half of the group's square points with a uniform third coordinate,
    mapped into the ball, antithetic pairs, a random reflection per pixel).

    The ``samples`` are split into ``groups`` independent randomizations, computed one after
    another (memory follows the image, not ``samples``). Each group draws its own random
    shift of the lattice and gives each pixel its own further random shift of it (toroidal,
    in the unit square the lattice lives in). Every group mean is then an unbiased estimate of the
    pixel's screen-space VO; the value is their mean and the standard error their standard
    deviation over sqrt(groups), a Student-t quantity with ``groups - 1`` degrees of
    freedom (as for the ray-cast ground truth, ``docs/groundtruth.md``). The value is not
    clipped: an unbiased estimate may stray from [0, 1] by its noise.

    Parameters
    ----------
    gbuffer : GBuffer
        The depth and view-space normal images (:func:`vobscure.render_gbuffer`).
    radius : float
        Radius R of the ball, in world units.
    samples : int or SamplePattern
        An int: rays (one depth tap each) per pixel over all groups, rounded up to a
        multiple of 2 * ``groups``. A ball pattern
        ((n, 3), :func:`vobscure.patterns.ball`): each group uses that pattern with its own
        random 3-D reflection per pixel (the randomization of :func:`vo_point`), so the
        result is the expectation of :func:`vo_point` with that pattern over its per-pixel
        randomization, with a standard error for that randomization only; a reflected fixed
        pattern is not uniform in the ball, so this expectation may differ from the
        screen-space VO by the pattern's bias, which the stderr does not include.
        ``samples`` of the result is then ``groups * n``.
    normal_clamp : bool
        Reflect samples below the tangent plane above it (Loos & Sloan Sec. 4.4): the
        half-ball on the normal's side. A plane then reads 1.0 instead of 0.5.
    thickness : float, optional
        A point is occupied only within this world thickness behind the depth buffer (Sec.
        4.3); None: everything behind the depth buffer is solid.
    falloff : {"constant", "quadratic"}
        rho = 1, or 1 - |s|^2 (samples weighted by it and the result normalized).
    seed : int, Generator or None
        Converted once; the groups draw their points and reflections from it in turn, so the
        same seed gives the same result bit for bit.
    fetch : {"bilinear", "nearest"}
        Depth-buffer reconstruction between pixel centres: ``"bilinear"`` (planes exact,
        1/z interpolated under perspective) or ``"nearest"`` (the pixel's depth as a constant).
    offscreen : {"clamp", "open"}
        Points that project off the image read the nearest edge pixel (``"clamp"``) or count
        as open (``"open"``).
    groups : int
        Independent randomizations (>= 2; the standard error's degrees of freedom + 1).
        Default :data:`vobscure.estimate.DEFAULT_GROUPS`, as for the ground truth.
    progress : bool
        A tqdm progress bar over the groups (default False, as everywhere in vobscure).

    Returns
    -------
    Estimate
        ``value`` and ``stderr`` of shape (H, W), NaN on background (float32 for a float32
        G-buffer). ``stderr`` is 0 where the value is exact: the pixels whose every view ray
        through the ball reads the pixel's own flat plane, or another surface where it and the
        plane both lie beyond the ray's chord through the ball on one side (a rendered
        G-buffer, the bilinear fetch, no thickness; ``docs/screenspace.md``, "Pixels that see
        only their own plane" and "Other surfaces beyond the ball"),
        where the control variate's closed form, 1/2 (1 with ``normal_clamp``), is the value
        and no Monte Carlo mean; and where every group reads 0 or every group reads 1. Where
        every group agrees on another value strictly between 0 and 1, ``stderr`` is one step
        of a group mean (1 / samples per group, over sqrt(groups)) instead of 0.
        ``samples`` is the number of rays (points with a pattern) per pixel.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4 (point sampling of the ball),
    4.3 (thickness), 4.4 (the half-ball), 4.5 (per-pixel randomization).

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> ref = vo.vo_reference(gb, radius=0.3, samples=256, normal_clamp=True)
    >>> float(ref.value[4, 4]), float(ref.stderr[4, 4]), ref.samples
    (1.0, 0.0, 256)
    """
    normal_clamp = C.check_bool(normal_clamp, "normal_clamp")
    return _reference(gbuffer, radius=radius, samples=samples, normal_clamp=normal_clamp,
                      thickness=thickness, falloff=falloff, seed=seed, fetch=fetch, offscreen=offscreen,
                      groups=groups, progress=progress, along="segment")


def _stratified_square(rng, n: int) -> np.ndarray:
    """(n, 2) jittered points of the unit square, one in each cell of a grid.

    The grid is a x b = n with a the largest divisor of n up to sqrt(n), when its cells are
    at most twice as long as wide (every cell gets a point: 8 x 16 for 128); otherwise n random
    cells of the smallest q x q grid with q^2 >= n. A full grid is worth it: on the atrium's
    default view the reference's mean standard error at 1024 rays was 0.0031 with 8 x 16 cells
    per group against 0.0034 with 128 of 12 x 12 (``docs/screenspace.md``, "The converged
    reference").
    """
    a = int(np.floor(np.sqrt(n)))
    while n % a:
        a -= 1
    b = n // a
    if b <= 2 * a:
        i, j = np.divmod(rng.permutation(n), b)
        return np.column_stack([(i + rng.random(n)) / a, (j + rng.random(n)) / b])
    q = int(np.ceil(np.sqrt(n)))
    idx = rng.permutation(q * q)[:n]
    ij = np.stack(np.divmod(idx, q), axis=1)
    return (ij + rng.random((n, 2))) / q


#: Above this many points per group the lattice generator is searched near n / golden ratio
#: only (the Fibonacci lattice's generator; a full search costs n^2 operations).
LATTICE_FULL_SEARCH = 2048
#: Candidates on each side of round(n / golden ratio) in the restricted search.
LATTICE_WINDOW = 256


@lru_cache(maxsize=64)
def lattice_generator(n: int) -> int:
    """The generator z of the rank-1 lattice {(i / n, frac(i z / n)), i = 0..n-1} with the
    least figure of merit P_2 among the z coprime to n (all of them up to
    :data:`LATTICE_FULL_SEARCH` points, else :data:`LATTICE_WINDOW` on each side of
    n / golden ratio, where the Fibonacci lattice's generator lies); ties go to the smallest z
    (z and n - z always tie: one lattice mirrored).

    P_2 = sum over the nonzero dual vectors h (h_1 + z h_2 = 0 mod n) of
    1 / (max(1, |h_1|) max(1, |h_2|))^2: the squared worst-case error of the rule for periodic
    integrands whose Fourier coefficients fall as that product, and the mean squared error of
    the randomly shifted rule there. It is a product over the axes, so it does not change when
    one axis of the integrand is stretched (each pixel's box of rays maps to the unit square with
    its own aspect ratio); the shortest lattice vector does, and ranked generators whose
    lattices are nearly square with short dual vectors along the axes first (n = 48: z = 7, P_2
    0.105, against z = 11, 0.060; ``docs/screenspace.md``, "The converged reference").

    References
    ----------
    Sloan & Joe, "Lattice Methods for Multiple Integration", Oxford 1994, Ch. 4 and 5 (P_alpha,
    and for even alpha its closed form through the Bernoulli polynomial: with B_2(x) =
    x^2 - x + 1/6, P_2 = -1 + (1/n) sum_k prod_j (1 + 2 pi^2 B_2(frac(k z_j / n)))).

    Examples
    --------
    For 89 = F_11 points the best is 34 = F_9, the Fibonacci lattice:

    >>> lattice_generator(89), lattice_generator(48)
    (34, 11)
    """
    n = int(n)
    if n <= 2:
        return 1
    if n <= LATTICE_FULL_SEARCH:
        candidates = np.arange(1, n // 2 + 1)
    else:
        g = int(round(n / ((1.0 + np.sqrt(5.0)) / 2.0)))
        candidates = np.arange(max(1, g - LATTICE_WINDOW), min(n, g + LATTICE_WINDOW + 1))
    candidates = candidates[np.gcd(candidates, n) == 1]
    return int(candidates[np.argmin(lattice_merit(n, candidates))])


def lattice_merit(n: int, z) -> np.ndarray:
    """P_2 of the rank-1 lattices of n points with the generators ``z`` (:func:`lattice_generator`),
    from the closed form -1 + (1/n) sum_k (1 + 2 pi^2 B_2(k / n)) (1 + 2 pi^2 B_2(frac(k z / n))),
    rounded to 12 significant digits (the ranking must not hang on the summation's rounding)."""
    k = np.arange(n)

    def factor(j):
        x = j / n
        # Sloan & Joe 1994, Ch. 5: sum over h != 0 of exp(2 pi i h x) / h^2 = 2 pi^2 B_2(x)
        return 1.0 + 2.0 * np.pi ** 2 * (x * x - x + 1.0 / 6.0)
    z = np.atleast_1d(np.asarray(z, dtype=np.int64))
    out = np.empty(len(z))
    first = factor(k)
    for a in range(0, len(z), 256):
        rows = factor(np.outer(z[a:a + 256], k) % n)
        out[a:a + 256] = rows @ first / n - 1.0
    return np.array([float(f"{v:.12g}") for v in out])


def _lattice_square(rng, n: int) -> np.ndarray:
    """(n, 2) points of the unit square: the rank-1 lattice of :func:`lattice_generator`,
    shifted as a whole by one uniform random vector modulo 1 (a Cranley-Patterson rotation),
    so that every point is uniform in the square.

    The segment integrand of :func:`vo_reference` vanishes on the edge of the box of rays
    (those rays only touch the ball), so its periodic extension is continuous, where a
    randomly shifted lattice rule converges faster than a jittered grid: inside the Cornell
    box and the atrium (320 x 180, compare's radius, 800 rays, seed 1) the mean reported
    standard error over the pixels off the one-step floor (those not exactly 1/2) fell from
    0.0032 and 0.0037 with 10 x 10 jittered cells per group to 0.0017 and 0.0019 with the
    100-point lattice (``docs/screenspace.md``, "The converged reference").

    References
    ----------
    Cranley & Patterson, "Randomization of number theoretic methods for multiple
    integration", SIAM J. Numer. Anal. 13(6), 1976 (the random shift); Sloan & Joe,
    "Lattice Methods for Multiple Integration", Oxford 1994, Ch. 4 (rank-1 lattice rules).
    """
    k = np.arange(n)
    z = lattice_generator(n)
    lattice = np.column_stack([k / n, (k * z % n) / n])
    u = lattice + rng.random(2)
    return u - np.floor(u)


def _reference(gbuffer, *, radius, samples, normal_clamp, thickness, falloff, seed, fetch, offscreen,
               groups, progress, along: str, fast: bool = True, shortcut: bool = True, lattice: bool = True):
    """:func:`vo_reference`; ``along="point"`` tests each stratified point on its own instead of
    integrating its view-ray segment (the same expectation, more variance: the independent
    check of the tests); ``shortcut=False`` integrates the segments of the pixels that see only
    their own plane too (the same values: the tests' check of the shortcut); ``lattice=False``
    draws each group's rays on a jittered grid (:func:`_stratified_square`) instead of the
    shifted lattice (:func:`_lattice_square`): the same expectation, more variance (the
    benchmark's and the tests' comparison)."""
    from tqdm.auto import tqdm

    pattern = samples if isinstance(samples, SamplePattern) else None
    if pattern is not None:
        pattern = C.as_pattern(pattern, 3)
    else:
        samples = check_int(samples, "samples", minimum=2)
    g = check_int(groups, "groups", minimum=2)
    rng = as_rng(seed)
    if pattern is None:
        # each group: half points and their antithetic partners
        half = max(1, -(-samples // (2 * g)))
        cells = int(np.ceil(half ** (1 / 3)))
        total = g * 2 * half
    else:
        total = g * len(pattern.points)
    tables = _plane_tables(gbuffer, thickness=thickness, fetch=fetch) if pattern is None and along == "segment" else None
    # found once per image, for every group: first the pixels whose footprint reads their own
    # plane only (a cheap test of every pixel), after the first group the others
    exact = None if tables is None else _exact_pixels(gbuffer, radius, tables, offscreen, clear=False)
    closed_form = 1.0 if normal_clamp else 0.5
    depth_cells = None
    if pattern is None and along == "segment" and fast and fetch == "bilinear":
        gb, depth64, _ = C.frame(gbuffer, radius)
        depth_cells = DepthCells(depth64.reshape(gb.depth.shape), gb.camera.is_perspective)
    mean = M2 = None
    for k in tqdm(range(1, g + 1), desc="vo_reference", unit="group", disable=not progress, leave=False):
        if pattern is None and along == "point":
            # stratified: jittered cells of a grid in the unit cube (a random subset of the
            # cells when half is not a cube), mapped volume-preservingly into the ball
            idx = rng.permutation(cells ** 3)[:half]
            ijk = np.stack(np.unravel_index(idx, (cells,) * 3), axis=1)
            pts = cube_to_uniform_ball((ijk + rng.random((half, 3))) / cells)
            points = np.vstack([pts, -pts])
        if pattern is None and along == "segment":
            unit = (_lattice_square if lattice else _stratified_square)(rng, total // g)
            x = _ray_vo(gbuffer, radius=radius, unit=unit, normal_clamp=normal_clamp,
                        thickness=thickness, falloff=falloff, rng=rng, fetch=fetch, offscreen=offscreen,
                        fast=fast, flat=exact if shortcut else None, cells=depth_cells)
        else:
            group_pattern = pattern if pattern is not None else SamplePattern(
                points, np.ones(2 * half), method="stratified",
                provenance={"generator": "vobscure.vo_reference", "samples": 2 * half})
            x = _point_vo(gbuffer, radius=radius, pattern=group_pattern, normal_clamp=normal_clamp,
                          thickness=thickness, falloff=falloff, randomize=True, seed=rng, fetch=fetch,
                          offscreen=offscreen, noise_size=64).astype(np.float64)
        if k <= 2 and exact is not None:
            # An exact pixel's every ray adds exactly 0 to the control variate's difference, so
            # each of its groups reads the closed form bit for bit (tests/test_screen_reference_exact.py;
            # the float32 kernel's rounding can spoil that near a ball's rim: _segment.CLEAR_MARGIN):
            # only the pixels whose first two groups read it can be exact, and only they are
            # given the costlier test of the other surfaces in their footprint (the same set as
            # testing every pixel; after two groups rather than one, since a test costs several
            # groups' rays of a pixel and the second group rules out about a third of the
            # pixels the first leaves)
            closed = x == closed_form
            if k == 1:
                first = closed
            elif (candidates := first & closed & ~exact).any():
                exact = exact | _exact_pixels(gbuffer, radius, tables, offscreen, candidates=candidates)
        # Welford's running mean and sum of squared deviations of the group means
        if mean is None:
            mean, M2 = x, np.zeros_like(x)
        else:
            delta = x - mean
            mean = mean + delta / k
            M2 += delta * (x - mean)
    dtype = C.out_dtype(gbuffer)
    stderr = np.sqrt(np.maximum(M2, 0.0) / (g - 1)) / np.sqrt(g)
    # Few points per group can make every group read the same (a pixel whose ball barely
    # reaches an occluder that no group's points hit): a spread of 0 although the value is
    # not exact. As for the ground truth (docs/groundtruth.md, "When the standard error
    # degenerates"), report one step of a group mean, 1 / (points per group), per group there.
    degenerate = (stderr == 0) & (mean > 0) & (mean < 1)
    stderr[degenerate] = 1.0 / ((total // g) * np.sqrt(g))
    if exact is not None:
        # the pixels whose every ray reads their own plane hold the control variate's closed
        # form, 1/2 (1 clamped), in every group: no Monte Carlo error to report
        stderr[exact] = 0.0
    return Estimate(value=mean.astype(dtype), stderr=stderr.astype(dtype), samples=int(total))
