"""Ray-cast ground truth: ambient occlusion, obscurance and world-space Volumetric Obscurance.

Every estimator in vobscure is measured against these references, so each returns an
:class:`~vobscure.estimate.Estimate` whose ``stderr`` is honest for the sampler used.

Sampling
--------
Randomized quasi-Monte Carlo. A scrambled Sobol' base set of ``m`` points is drawn once per
call; every query point gets ``groups`` independent uniform shifts of it (Cranley-Patterson
rotations, modulo 1), so its ``groups * m`` samples form ``groups`` independent, unbiased
estimates. The value is their mean and the standard error is their standard deviation over
sqrt(groups): a Student-t quantity with ``groups - 1`` degrees of freedom. Rays of one point
are contiguous in memory, which keeps Embree's traversal coherent.

All functions accept what :func:`vobscure.scenes.as_scene` accepts: a
:class:`~vobscure.scenes.Scene`, a ``trimesh.Trimesh``, a built-in scene's name or a mesh
file's path. Sample counts are ``rays`` for directions (ambient occlusion, obscurance) and
``samples`` for points in a volume (volumetric obscurance); ``progress`` (a tqdm bar) is off
by default everywhere, as in the rest of the library (``docs/conventions.md``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
from tqdm.auto import tqdm

from ._validate import as_points, as_rng, as_unit_vectors, check_bool, check_choice, check_int, check_positive
from .estimate import DEFAULT_GROUPS, Estimate
from .raytrace import CHUNK_RAYS, OFFSET_RELATIVE, Hits, parallel_map
from .sampling import (cube_to_uniform_ball, shifted_hemisphere_directions, sobol_base, to_world,
                       square_to_cosine_hemisphere, square_to_uniform_hemisphere)
from .scenes import Scene, as_scene

__all__ = ["ambient_occlusion", "obscurance", "volumetric_obscurance", "ground_truth", "SmallRadiusWarning",
           "SCENE_CHECK_SAMPLES",
           "OBSCURANCE_FALLOFFS", "VO_FALLOFFS", "DEFAULT_GROUPS", "DEFAULT_FALLOFF", "QUANTITIES"]

_WARPS = {"cosine": square_to_cosine_hemisphere, "uniform": square_to_uniform_hemisphere}

#: Covered pixels (evenly spaced in row-major order) whose hit points :func:`ground_truth`
#: checks against their triangles in the scene, to catch a G-buffer of another scene.
SCENE_CHECK_SAMPLES = 256


class SmallRadiusWarning(UserWarning):
    """The volumetric obscurance's radius is below the tracer's ray offset (1e-5 of the scene's
    scale, :attr:`vobscure.raytrace.Tracer.offset`): the ball then lies within the distance at
    which the inside test can tell the two sides of a surface apart, and whole balls test as
    occupied or as empty (values of exactly 0 or 1 where the limit is 1/2). The result is
    returned as computed, not corrected."""


def _linear(t):
    return t


def _smooth(t):
    return t * t * (3.0 - 2.0 * t)


def _step(t):
    return np.zeros_like(t)


#: rho(t) for t = d / radius in [0, 1); rho = 1 for t >= 1 and for misses (RTR Sec. 9.2.3).
OBSCURANCE_FALLOFFS: dict[str, Callable] = {"step": _step, "linear": _linear, "smooth": _smooth}

#: Loos & Sloan 2010 Sec. 4: rho(r) on the ball, r = |x - P| / radius, with the integral of
#: rho over the unit ball divided by the ball's volume (the normalization of the weights).
VO_FALLOFFS = {
    "constant": (lambda r2: np.ones_like(r2), 1.0),
    # 1 - r^2: integral 4 pi (1/3 - 1/5) = 8 pi / 15 over the ball's 4 pi / 3 -> 2/5.
    "quadratic": (lambda r2: 1.0 - r2, 2.0 / 5.0),
}


def _groups(count: int, groups: int, name: str) -> tuple[int, int]:
    """Split ``count`` samples into ``g`` groups of ``m`` (count rounded up to g * m)."""
    g = min(check_int(groups, "groups", minimum=2), count)
    if count < 2:
        raise ValueError(f"{name} must be >= 2 (the standard error needs two randomizations), got {count}")
    return g, -(-count // g)


def _chunked(kernel, n: int, g: int, m: int, dim: int, rng, *, threads, progress, desc,
             extra_dim: int = 0, per_group: int | None = None):
    """Evaluate ``kernel(index_slice, base, shifts, child_rng)`` over chunks of points.

    ``base`` is the (m, dim) scrambled Sobol' set shared by all points and ``shifts`` the
    (P, g, dim) Cranley-Patterson shifts of the chunk's P points. The kernel returns (P, g)
    group means, or a tuple of that and a (P, extra_dim) per-point extra (the summed
    unoccluded directions for bent normals). ``per_group`` is the number of samples behind
    one group mean (default m; 2 m for the antithetic ball samples).
    """
    progress = check_bool(progress, "progress")
    base = sobol_base(dim, m, rng)
    shifts = rng.random((n, g, dim))
    per_chunk = max(1, CHUNK_RAYS * 2 // (g * m))
    chunks = [slice(i, min(i + per_chunk, n)) for i in range(0, n, per_chunk)]
    child = rng.spawn(len(chunks))

    def work(k):
        return kernel(chunks[k], base, shifts[chunks[k]], child[k])

    bar = tqdm(total=len(chunks), desc=desc, unit="chunk", disable=not progress, leave=False)
    try:
        results = parallel_map(work, range(len(chunks)), threads=threads, progress=bar)
    finally:
        bar.close()
    means = np.concatenate([r[0] if isinstance(r, tuple) else r for r in results]) if n else np.zeros((0, g))
    extra = None
    if extra_dim:
        extra = np.concatenate([r[1] for r in results]) if n else np.zeros((0, extra_dim))
    value = means.mean(axis=1)
    stderr = means.std(axis=1, ddof=1) / np.sqrt(g)
    # Stratification can make every group count the same number of occluded samples, so the
    # spread of the group means is 0 although the value is not exact (a point next to an
    # edge, where any shift of the base set puts exactly half the directions behind the
    # wall). A group mean of binary samples moves in steps of 1 / m: report one such step
    # per group instead of 0 there (docs/groundtruth.md, "When the standard error degenerates").
    degenerate = (stderr == 0) & (value > 0) & (value < 1)
    stderr[degenerate] = 1.0 / ((per_group or m) * np.sqrt(g))
    return value, stderr, extra


def _hemisphere_rays(tracer, points, normals, offset_normals, base, shifts, weighting):
    """float32 origins (P*R, 3), directions (P*R, 3) and directions (P, R, 3), rays of a point contiguous."""
    # origins p + offset (n + d): Tracer.offset_origins, fused into the direction pass
    origins, dirs = shifted_hemisphere_directions(normals, base, shifts, weighting,
                                                  origins=tracer.offset_origins(points, offset_normals),
                                                  step=tracer.offset)     # (P, g, m, 3) each
    dirs = dirs.reshape(len(points), -1, 3)
    return origins.reshape(-1, 3), dirs.reshape(-1, 3), dirs


#: Attempts to move a shading point off a surface its rays start behind (see
#: :func:`_primary_hits`); what is still trapped after them counts as black.
EDGE_RETRIES = 3


def _primary_hits(tracer, o, d, max_distance, p, n, closed):
    """First hits of the primary rays, with rays that started inside a neighbouring solid
    traced again from a point moved off it.

    A shading point on a concave edge (a floor pixel touching a wall) has its ray origins
    moved along each ray by the tracer's offset, which puts the origins of rays towards the
    wall inside the wall's solid. For black occluders that is harmless (the ray is blocked
    either way), but the path would continue inside the solid and bring back nothing. In a
    closed scene a ray leaving a surface can only hit a *back* face from inside a solid, so
    those rays are traced again from the point moved by two offsets against the ray's
    tangential direction (away from the wall), a displacement far below any feature of the
    scene. Open scenes are left as they are (a back face is a legitimate hit there).
    """
    hits = tracer.intersect(o, d, max_distance, threads=1)
    if not closed:
        return hits, o
    dist, prim, bary = hits.distance.copy(), hits.primitive.copy(), hits.barycentric.copy()
    o = o.copy()
    shift = np.zeros(len(o))
    for _ in range(EDGE_RETRIES):
        hit = prim >= 0
        back = np.zeros(len(o), dtype=bool)
        back[hit] = np.einsum("ij,ij->i", tracer.face_normals[prim[hit]], d[hit].astype(np.float64)) > 0.0
        idx = np.flatnonzero(back)
        if not len(idx):
            break
        d_i = d[idx].astype(np.float64)
        tangent = d_i - np.einsum("ij,ij->i", d_i, n[idx])[:, None] * n[idx]
        length = np.linalg.norm(tangent, axis=1, keepdims=True)
        tangent = np.where(length > 1e-12, tangent / np.maximum(length, 1e-300), 0.0)
        shift[idx] += 2.0 * tracer.offset
        moved = p[idx] - shift[idx, None] * tangent
        o[idx] = tracer.offset_origins(moved, n[idx], d_i[:, None, :])[:, 0, :]
        again = tracer.intersect(o[idx], d[idx], max_distance, threads=1)
        dist[idx], prim[idx], bary[idx] = again.distance, again.primitive, again.barycentric
    return Hits(dist, prim, bary), o


def _bounce_paths(tracer, o, d, max_distance, bounces, albedo, rng, p, n, closed):
    """Radiance carried back along each primary ray under a white sky of radiance 1.

    Every surface is Lambertian with ``albedo``; a path that leaves the scene (or travels
    farther than ``max_distance``) after b diffuse reflections brings ``albedo**b``; a path
    still inside after ``bounces`` reflections brings 0. Continuation directions are
    cosine-distributed about the hit's normal (turned to face the incoming ray), which is the
    importance sampling that makes each reflection's weight exactly the albedo
    (Lambertian BRDF a / pi times cos / pdf with pdf = cos / pi).

    o, d : (R, 3) float32 primary ray origins and directions; p, n : (R, 3) float64 the
    shading point and normal of each ray. Returns (R,) float64.
    """
    value = np.zeros(len(o))
    alive = np.arange(len(o))
    weight = 1.0
    for b in range(bounces + 1):
        if b == 0:
            hits, o = _primary_hits(tracer, o, d, max_distance, p, n, closed)
        else:
            hits = tracer.intersect(o, d, max_distance, threads=1)
        escaped = ~hits.hit
        value[alive[escaped]] += weight
        if b == bounces:
            break
        keep = hits.hit
        alive = alive[keep]
        if not len(alive):
            break
        q = tracer.hit_points(Hits(hits.distance[keep], hits.primitive[keep], hits.barycentric[keep]))
        n_q = tracer.face_normals[hits.primitive[keep]]
        d_in = d[keep].astype(np.float64)
        # two-sided surfaces: the normal of the side the ray arrived on
        n_q = np.where((np.einsum("ij,ij->i", n_q, d_in) > 0.0)[:, None], -n_q, n_q)
        local = square_to_cosine_hemisphere(rng.random((len(q), 1, 2)))
        d_out = to_world(local, n_q)                                    # (R, 1, 3)
        o = tracer.offset_origins(q, n_q, d_out)[:, 0, :]
        d = d_out[:, 0, :].astype(np.float32)
        weight *= albedo
    return value


def _ao(scene, points, normals, offset_normals, *, rays, weighting, max_distance, seed,
        bent_normals, groups, threads, progress, bounces=0, albedo=0.0, desc="ambient occlusion"):
    tracer = scene.tracer
    g, m = _groups(rays, groups, "rays")
    rng = as_rng(seed)
    closed = bool(bounces) and scene.is_watertight

    def kernel(s, base, shifts, child):
        o, d, dirs = _hemisphere_rays(tracer, points[s], normals[s], offset_normals[s], base, shifts, weighting)
        P = len(shifts)
        if bounces:
            R = g * m
            carried = _bounce_paths(tracer, o, d, max_distance, bounces, albedo, child,
                                    np.repeat(points[s], R, axis=0), np.repeat(offset_normals[s], R, axis=0), closed)
            return carried.reshape(P, g, m).mean(axis=2)
        free = ~tracer.occluded(o, d, max_distance, threads=1)
        means = free.reshape(P, g, m).mean(axis=2)
        if not bent_normals:
            return means
        # RTR 3rd ed. Sec. 9.2.1: the bent normal is the mean unoccluded direction.
        summed = np.einsum("pr,prk->pk", free.reshape(P, -1).astype(float), dirs.astype(float))
        return means, summed

    value, stderr, summed = _chunked(kernel, len(points), g, m, 2, rng, threads=threads,
                                        progress=progress, desc=desc, extra_dim=3 if bent_normals else 0)
    bent = None
    if bent_normals:
        length = np.linalg.norm(summed, axis=1, keepdims=True)
        # where every ray is blocked the direction is undefined: fall back to the normal
        bent = np.where(length > 0, summed / np.where(length > 0, length, 1.0), normals)
    return Estimate(value=value, stderr=stderr, samples=g * m, bent_normal=bent)


def _check_bounces(bounces, albedo) -> tuple[int, float]:
    """Validated (bounces, albedo); bounces 0 when the albedo is 0 (black occluders)."""
    bounces = check_int(bounces, "bounces", minimum=0)
    if isinstance(albedo, (str, bool)) or np.ndim(albedo) != 0 or not 0.0 <= float(albedo) <= 1.0:
        raise ValueError(f"albedo must be a number in [0, 1], got {albedo!r}")
    albedo = float(albedo)
    return (bounces if albedo > 0.0 else 0), albedo


def ambient_occlusion(scene, points, normals, *, rays: int = 256, weighting: str = "cosine",
                      max_distance: float = np.inf, seed=0, bent_normals: bool = False,
                      bounces: int = 0, albedo: float = 0.0,
                      groups: int = DEFAULT_GROUPS, threads: int | None = None,
                      progress: bool = False) -> Estimate:
    r"""Ambient occlusion k_A at surface points by ray casting (visibility: 1 = open).

    .. math:: k_A(p) = \frac{1}{\pi} \int_\Omega v(p, l) \cos\theta \, d\omega

    (RTR 3rd ed. Sec. 9.2, Eq. 9.14), or the unweighted hemisphere average
    :math:`\frac{1}{2\pi}\int_\Omega v \, d\omega` with ``weighting="uniform"``. v is 0 where
    the ray hits geometry within ``max_distance``.

    With ``bounces=N > 0`` the occluders are not black: every surface is Lambertian with
    ``albedo`` a and the sky has radiance 1, so that a ray blocked at q brings back the light
    q reflects, and the result is the irradiance at p over pi, light reflected up to N times:

    .. math:: k'_A(p) = \frac{1}{\pi} \int_\Omega \big[v(p, l) + (1 - v(p, l))\, a\,
              k'_{A, N-1}(q(p, l))\big] \cos\theta \, d\omega, \quad k'_{A,0} = k_A

    the quantity that the interreflection corrections of RTR Sec. 9.2.1 (Stewart & Langer,
    Eqs. 9.22-9.23; Jimenez et al. 2016's multi-bounce fit) approximate from k_A alone
    (:mod:`vobscure.shading`). Each path's contribution is a^b after b reflections before it
    leaves the scene, 0 if it has not left after N (path tracing with cosine-distributed
    continuation, for which each reflection's weight is exactly a). A surface reflects on
    both sides. ``bounces=0`` (or ``albedo=0``) is plain k_A, bit for bit.

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts.
    points : (n, 3) float
        Surface points, world space.
    normals : (n, 3) float
        Unit normals on the open side (renormalized). Rays start ``tracer.offset`` along
        them (:mod:`vobscure.raytrace`).
    rays : int
        Rays per point, rounded up to a multiple of ``groups``.
    weighting : {"cosine", "uniform"}
    max_distance : float
        Ray length limit (inf: any hit occludes).
    seed : int, Generator or None
    bent_normals : bool
        Also return the bent normals (the normalized mean unoccluded direction, RTR 9.2.1).
        Not with ``bounces`` > 0 (compute them in a separate call).
    bounces : int
        Diffuse reflections followed, >= 0 (0: black occluders, plain k_A).
    albedo : float
        The surfaces' reflectance a in [0, 1] with ``bounces`` > 0; 0 gives plain k_A.
    groups : int
        Independent randomizations (stderr degrees of freedom + 1).
    threads : int, optional
    progress : bool
        Show a tqdm progress bar (default False, as everywhere in vobscure).

    Returns
    -------
    Estimate
        ``value`` and ``stderr`` of shape (n,); ``bent_normal`` (n, 3) if requested
        (equal to the normal where every ray was blocked).

    Notes
    -----
    A closed form for the multi-bounce case: inside a sphere of radius R, any two points see
    each other with the same form factor per unit area, :math:`dA / (4 \pi R^2)`. In a
    spherical cavity whose opening is a fraction f of the sphere's area, every interior point
    therefore has :math:`k_A = f` and the same :math:`k'_A`, which solves
    :math:`k' = f + a (1 - f) k'` in the limit of many bounces, and is the partial geometric sum
    :math:`f \sum_{b=0}^{N} (a (1 - f))^b` with N bounces: Stewart and Langer's correction
    :math:`k_A / (1 - a (1 - k_A))` (RTR Eq. 9.23, :func:`vobscure.shading.stewart_langer`) is
    exact there. ``tests/test_groundtruth.py`` checks the tracer against it.

    References
    ----------
    Akenine-Moller, Haines & Hoffman, Real-Time Rendering 3rd ed., Sec. 9.2, Eq. 9.14;
    Sec. 9.2.1, Eqs. 9.22-9.23 (interreflections). Stewart & Langer, "Toward Accurate
    Recovery of Shape from Shading under Diffuse Lighting", IEEE PAMI 19(9), 1997.

    Examples
    --------
    >>> import vobscure as vo
    >>> e = vo.ambient_occlusion(vo.scenes.slab(), [[0, 0, 0]], [[0, 1, 0]], rays=64)
    >>> float(e.value[0]), float(e.stderr[0])
    (1.0, 0.0)
    """
    scene = as_scene(scene)
    points = as_points(points, "points")
    normals = as_unit_vectors(normals, "normals", count=len(points))
    rays = check_int(rays, "rays", minimum=2)
    check_choice(weighting, "weighting", _WARPS)
    max_distance = check_positive(max_distance, "max_distance", allow_inf=True)
    bounces, albedo = _check_bounces(bounces, albedo)
    bent_normals = check_bool(bent_normals, "bent_normals")
    if bounces and bent_normals:
        raise ValueError("bent_normals is not available with bounces > 0: the bent normal is a property of "
                         "the black-occluder visibility; compute it in a call with bounces=0")
    return _ao(scene, points, normals, normals, rays=rays, weighting=weighting,
               max_distance=max_distance, seed=seed, bent_normals=bent_normals,
               groups=groups, threads=threads, progress=progress, bounces=bounces, albedo=albedo)


def _rho(falloff):
    if callable(falloff):
        return falloff
    check_choice(falloff, "falloff", list(OBSCURANCE_FALLOFFS) + ["<callable>"])
    return OBSCURANCE_FALLOFFS[falloff]


def _obscurance(scene, points, normals, offset_normals, *, radius, falloff, rays, weighting,
                seed, groups, threads, progress, desc="obscurance"):
    tracer = scene.tracer
    rho = _rho(falloff)
    g, m = _groups(rays, groups, "rays")
    rng = as_rng(seed)

    def kernel(s, base, shifts, _rng):
        o, d, _ = _hemisphere_rays(tracer, points[s], normals[s], offset_normals[s], base, shifts, weighting)
        hits = tracer.intersect(o, d, radius, threads=1)
        t = hits.distance / radius
        value = np.ones_like(t)
        hit = hits.hit & (t < 1.0)
        # RTR 3rd ed. Sec. 9.2.3, Eq. 9.21: rho(d) replaces the binary visibility v(l)
        rho_t = np.asarray(rho(t[hit]), dtype=float)
        if rho_t.shape != t[hit].shape or np.any(~np.isfinite(rho_t)) or np.any((rho_t < 0) | (rho_t > 1)):
            raise ValueError("falloff must map distances d / radius in [0, 1) to finite values in [0, 1], "
                             "elementwise on an array")
        value[hit] = rho_t
        return value.reshape(len(shifts), g, m).mean(axis=2)

    value, stderr, _ = _chunked(kernel, len(points), g, m, 2, rng, threads=threads,
                                   progress=progress, desc=desc)
    return Estimate(value=value, stderr=stderr, samples=g * m)


def obscurance(scene, points, normals, *, radius: float, falloff="linear", rays: int = 256,
               weighting: str = "cosine", seed=0, groups: int = DEFAULT_GROUPS,
               threads: int | None = None, progress: bool = False) -> Estimate:
    r"""Zhukov obscurance at surface points by ray casting.

    .. math:: W(p) = \frac{1}{\pi} \int_\Omega \rho(d(p, l)) \cos\theta \, d\omega

    (RTR 3rd ed. Sec. 9.2.3, Eq. 9.21; Loos & Sloan 2010 Sec. 3), where d is the distance to
    the first hit and rho rises from 0 at d = 0 to 1 at d >= ``radius`` (and for misses).

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts.
    points, normals : (n, 3) float
    radius : float
        d_max: the distance beyond which geometry no longer obscures.
    falloff : {"linear", "smooth", "step"} or callable
        rho as a function of t = d / radius on [0, 1): ``"linear"`` t, ``"smooth"``
        3t^2 - 2t^3, ``"step"`` 0 (obscurance then equals AO with ``max_distance=radius``),
        or a vectorized callable returning values in [0, 1].
    rays, weighting, seed, groups, threads, progress
        As in :func:`ambient_occlusion`.

    Returns
    -------
    Estimate
        W per point: (n,) ``value`` in [0, 1] and its ``stderr``.

    References
    ----------
    Zhukov, Iones & Kronin, "An ambient light illumination model", EGWR 1998; RTR 3rd ed.
    Sec. 9.2.3, Eq. 9.21.

    Examples
    --------
    >>> import vobscure as vo
    >>> e = vo.obscurance(vo.scenes.slab(), [[0, 0, 0]], [[0, 1, 0]], radius=0.5, rays=64)
    >>> float(e.value[0])
    1.0
    """
    scene = as_scene(scene)
    points = as_points(points, "points")
    normals = as_unit_vectors(normals, "normals", count=len(points))
    radius = check_positive(radius, "radius")
    rays = check_int(rays, "rays", minimum=2)
    check_choice(weighting, "weighting", _WARPS)
    return _obscurance(scene, points, normals, normals, radius=radius, falloff=falloff, rays=rays,
                       weighting=weighting, seed=seed, groups=groups, threads=threads,
                       progress=progress)


def _check_closed(scene: Scene, allow_open: bool) -> None:
    if allow_open or scene.is_watertight:
        return
    bad = scene.open_meshes
    raise ValueError(
        f"volumetric obscurance needs closed, consistently wound meshes to tell inside from outside; "
        f"mesh(es) {bad} are not. Repair them (e.g. trimesh.repair.fill_holes) or pass "
        f"allow_open=True (`--allow-open` on the command line) to accept an inside test that may be "
        f"wrong near the holes, or use the shell model, defined for open surfaces: thickness= here, "
        f"the reference 'shell' in vobscure compare (docs/groundtruth.md).")


def _shell_occupied(tracer, q, shell) -> np.ndarray:
    """(n,) bool: the shell model's occupancy of world points ``q`` (docs/groundtruth.md, "The
    shell reference"): every surface is a slab ``thickness`` thick on its far side from the
    camera, so a point is occupied when the first surface on its ray towards the camera lies
    within ``thickness`` of it measured along that surface's normal (ray length times |cos|).

    ``shell`` is ``(eye, forward, perspective, thickness)``. The ray runs towards the eye
    (perspective) or against the view direction (orthographic), up to the eye's plane; a point
    not in front of the eye (view depth <= 0) looks against the view direction within
    ``thickness``.
    """
    eye, forward, perspective, thickness = shell
    n = len(q)
    rel = q - eye
    z = rel @ forward
    front = z > 0
    directions = np.broadcast_to(-forward, (n, 3)).copy()
    reach = np.where(front, z, thickness)
    if perspective:
        dist = np.linalg.norm(rel[front], axis=1)
        directions[front] = -rel[front] / dist[:, None]
        reach[front] = dist
    hits = tracer.intersect(q, directions, reach, threads=1)
    hit = hits.hit
    depth = np.full(n, np.inf)
    cos = np.abs(np.einsum("ij,ij->i", tracer.face_normals[hits.primitive[hit]], directions[hit]))
    depth[hit] = hits.distance[hit] * cos
    return depth <= thickness


def _volumetric(scene, points, normals, *, radius, samples, falloff, seed, votes, groups,
                threads, progress, desc="volumetric obscurance", shell=None):
    tracer = scene.tracer
    if radius < tracer.offset:
        warnings.warn(f"radius {radius:.3g} is below the tracer's ray offset {tracer.offset:.3g} ({OFFSET_RELATIVE:g} of the scene's "
                      f"scale {tracer.scale:.3g}): the inside test cannot resolve a ball this small, and its "
                      f"samples test all occupied or all empty (0 or 1 where a flat surface gives 1/2); use "
                      f"radius >= {tracer.offset:.3g}", SmallRadiusWarning, stacklevel=3)
    rho, rho_mean = VO_FALLOFFS[falloff]
    # antithetic pairs: each base point x also gives -x, so m base points make 2 m samples
    g, m2 = _groups(samples, groups, "samples")
    m = max(1, -(-m2 // 2))
    rng = as_rng(seed)
    face_normals = tracer.face_normals

    def kernel(s, base, shifts, child):
        P = len(shifts)
        u = base[None, None, :, :] + shifts[:, :, None, :]
        u -= np.floor(u)
        x = cube_to_uniform_ball(u)                                    # (P, g, m, 3), unit ball
        x = np.concatenate([x, -x], axis=2)                            # (P, g, 2m, 3)
        if normals is not None:
            # Loos & Sloan Sec. 4.4: the half-ball on the normal's side; reflecting the
            # samples below the tangent plane keeps them uniform on the half-ball.
            n = normals[s][:, None, None, :]
            dn = np.sum(x * n, axis=-1, keepdims=True)
            x = x - 2.0 * np.minimum(dn, 0.0) * n
        r2 = np.sum(x * x, axis=-1)
        world = points[s][:, None, None, :] + radius * x
        q = world.reshape(-1, 3)
        if shell is not None:
            occupied = _shell_occupied(tracer, q, shell).reshape(P, g, 2 * m)
            w = rho(r2) / rho_mean
            return np.mean(w * ~occupied, axis=2)
        # Inside test: a point is inside a closed, outward-wound solid when the first
        # surface a ray from it meets faces away from it (the ray is leaving). Majority
        # of `votes` rays in independent random directions.
        dirs = child.normal(size=(votes, len(q), 3))
        dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
        inside_votes = np.zeros(len(q), dtype=np.int32)
        for v in range(votes):
            hits = tracer.intersect(q, dirs[v], threads=1)
            hit = hits.hit
            leaving = np.zeros(len(q), dtype=bool)
            leaving[hit] = np.einsum("ij,ij->i", face_normals[hits.primitive[hit]], dirs[v][hit]) > 0
            inside_votes += leaving
        occupied = (inside_votes * 2 > votes).reshape(P, g, 2 * m)
        # Loos & Sloan 2010 Sec. 4, V(P) = int_X rho(d(P, x)) O(x) dx, normalized by int_X rho
        w = rho(r2) / rho_mean
        return np.mean(w * ~occupied, axis=2)

    value, stderr, _ = _chunked(kernel, len(points), g, m, 3, rng, threads=threads,
                                progress=progress, desc=desc, per_group=2 * m)
    return Estimate(value=value, stderr=stderr, samples=g * 2 * m)


def _check_same_scene(tracer, primitive: np.ndarray, points: np.ndarray) -> None:
    """Reject a G-buffer rendered from another scene: every covered pixel's primitive must be
    a triangle of ``tracer``, and :data:`SCENE_CHECK_SAMPLES` hit points must lie on their
    triangles within the tracer's ray offset (1e-5 of the scene's scale; a float32 hit point
    is within about 1e-7 of it)."""
    count = len(tracer.triangles)
    bad = (primitive < 0) | (primitive >= count)
    if np.any(bad):
        raise ValueError(f"gbuffer does not belong to this scene: {int(np.count_nonzero(bad))} covered pixel(s) "
                         f"hit primitive indices outside the scene's {count} triangles (largest "
                         f"{int(primitive.max())}); render the G-buffer from the scene given here")
    if len(points) == 0:
        return
    pick = np.unique(np.linspace(0, len(points) - 1, min(SCENE_CHECK_SAMPLES, len(points))).astype(np.int64))
    p = np.asarray(points, dtype=np.float64)[pick]
    tri = np.asarray(tracer.triangles, dtype=np.float64)[primitive[pick]]
    a, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    # barycentric coordinates of p's projection on the triangle's plane, clipped to the
    # triangle: a point of the triangle, so |p - q| bounds p's distance from it from above
    d = p - a
    g11, g12, g22 = np.einsum("ij,ij->i", e1, e1), np.einsum("ij,ij->i", e1, e2), np.einsum("ij,ij->i", e2, e2)
    b1, b2 = np.einsum("ij,ij->i", d, e1), np.einsum("ij,ij->i", d, e2)
    det = g11 * g22 - g12 * g12
    safe = np.where(det > 0, det, 1.0)
    u = np.where(det > 0, (g22 * b1 - g12 * b2) / safe, 0.0)
    v = np.where(det > 0, (g11 * b2 - g12 * b1) / safe, 0.0)
    lam = np.clip(np.stack([1.0 - u - v, u, v], axis=1), 0.0, None)
    lam /= np.maximum(lam.sum(axis=1, keepdims=True), 1e-300)
    q = np.einsum("ik,ikj->ij", lam, tri)
    off = np.linalg.norm(p - q, axis=1)
    far = off > tracer.offset
    if np.any(far):
        raise ValueError(f"gbuffer does not belong to this scene: {int(np.count_nonzero(far))} of {len(pick)} checked "
                         f"hit points lie off their triangles (up to {float(off.max()):.3g}, tolerance "
                         f"{tracer.offset:.3g}, {OFFSET_RELATIVE:g} of the scene's scale); render the G-buffer from the scene "
                         f"given here")


def _check_votes(votes) -> int:
    votes = check_int(votes, "votes")
    if votes % 2 == 0:
        raise ValueError(f"votes must be odd so that a majority exists, got {votes}")
    return votes


def volumetric_obscurance(scene, points, normals=None, *, radius: float, normal_clamp: bool = False,
                          samples: int = 4096, falloff: str = "constant", seed=0, votes: int = 3,
                          allow_open: bool = False, thickness=None, camera=None,
                          groups: int = DEFAULT_GROUPS, threads: int | None = None,
                          progress: bool = False) -> Estimate:
    r"""World-space Volumetric Obscurance: the unoccupied fraction of a ball around each point.

    .. math:: V(P) = \int_X \rho(d(P, x)) O(x) \, dx \Big/ \int_X \rho(d(P, x)) \, dx

    (Loos & Sloan 2010, Sec. 4), X the ball of ``radius`` around P, or the half-ball on the
    normal's side with ``normal_clamp=True`` (Sec. 4.4); O is 1 in empty space and 0 inside
    a solid. A point on a flat open surface has V = 0.5 (1.0 clamped).

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        Anything :func:`vobscure.scenes.as_scene` accepts: closed, consistently wound,
        non-interpenetrating solids.
    points : (n, 3) float
    normals : (n, 3) float, optional
        Unit normals on the open side (renormalized); required with ``normal_clamp=True``,
        unused otherwise.
    radius : float
        The ball's radius; below the tracer's ray offset (:data:`vobscure.raytrace.OFFSET_RELATIVE`
        of the scene's scale) a :class:`SmallRadiusWarning` says that the inside test cannot
        resolve the ball (the sub-offset radius is not corrected: the warning is the policy).
    normal_clamp : bool
        The half-ball on the normal's side instead of the ball (default False), as
        ``normal_clamp`` of :func:`ground_truth` and of the screen-space estimators. Before
        this keyword existed, passing ``normals`` selected the half-ball; now it must be
        asked for.
    samples : int
        Points per ball (antithetic pairs x, -x; rounded up to a multiple of 2 * groups).
    falloff : {"constant", "quadratic"}
        rho = 1 (the paper's choice) or 1 - (d / radius)^2 (its other candidate).
    seed : int, Generator or None
    votes : int
        Odd number of rays per inside test (majority vote; default 3).
    allow_open : bool
        Accept meshes that are not closed (the inside test may then be wrong).
    thickness : float, optional
        The shell model instead of the inside test: every surface is a solid slab ``thickness``
        thick (along its normal) on its far side from ``camera`` -- a point is occupied when the
        first surface on its ray towards the camera lies within ``thickness`` of it, measured
        along that surface's normal (docs/groundtruth.md, "The shell reference"). Defined for
        any scene, closed or not: the thickness model of the screen-space estimators (Loos &
        Sloan 2010, Sec. 4.3) with the thickness measured across each surface, for every
        surface, hidden and off-screen ones included. None: the solid model (closed scenes).
    camera : Camera, optional
        The view of the shell model (required with ``thickness``; it needs a pose).
    groups, threads, progress
        As in :func:`ambient_occlusion` (``progress`` off by default).

    Returns
    -------
    Estimate
        V per point, the unoccupied fraction of its ball (or half-ball): (n,) ``value`` in
        [0, 1] and its ``stderr``.

    References
    ----------
    Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4 and 4.4.

    Examples
    --------
    >>> import vobscure as vo
    >>> slab = vo.scenes.slab()
    >>> e = vo.volumetric_obscurance(slab, [[0, 0, 0]], radius=0.5, samples=256)
    >>> h = vo.volumetric_obscurance(slab, [[0, 0, 0]], [[0, 1, 0]], radius=0.5, normal_clamp=True,
    ...                              samples=256)
    >>> float(e.value[0]), float(h.value[0])
    (0.5, 1.0)
    """
    scene = as_scene(scene)
    points = as_points(points, "points")
    normal_clamp = check_bool(normal_clamp, "normal_clamp")
    allow_open = check_bool(allow_open, "allow_open")
    if normal_clamp and normals is None:
        raise ValueError("normal_clamp=True needs normals: pass normals (n, 3), the side of each "
                         "point's half-ball, or normal_clamp=False for the whole ball")
    if normals is not None:
        normals = as_unit_vectors(normals, "normals", count=len(points))
    radius = check_positive(radius, "radius")
    samples = check_int(samples, "samples", minimum=2)
    check_choice(falloff, "falloff", VO_FALLOFFS)
    votes = _check_votes(votes)
    shell = _shell(thickness, camera)
    if shell is None:
        _check_closed(scene, allow_open)
    return _volumetric(scene, points, normals if normal_clamp else None, radius=radius, samples=samples,
                       falloff=falloff, seed=seed, votes=votes, groups=groups, threads=threads,
                       progress=progress, shell=shell)


def _shell(thickness, camera):
    """``(eye, forward, perspective, thickness)`` of the shell model, or None for the solid one."""
    from .camera import Camera

    if thickness is None:
        return None
    thickness = check_positive(thickness, "thickness")
    if not isinstance(camera, Camera):
        raise ValueError("thickness (the shell model) needs camera: the view whose depth the thickness is "
                         f"measured in, a vobscure Camera; got {type(camera).__name__}")
    if not camera.has_pose:
        raise ValueError("thickness (the shell model) needs a camera with a pose (where it is in the world)")
    return (np.asarray(camera.eye, np.float64), np.asarray(camera.forward, np.float64),
            bool(camera.is_perspective), thickness)


#: What :func:`ground_truth` computes (its ``quantity``). The references an estimate is scored
#: against -- these with a weighting, a distance limit and sampling settings, and the
#: screen-space VO -- are the registry :data:`vobscure.references.REFERENCES`.
QUANTITIES = ("ao", "obscurance", "volumetric")

#: The falloff of each quantity when :func:`ground_truth` is given ``falloff=None``.
DEFAULT_FALLOFF = {"obscurance": "linear", "volumetric": "constant"}


def ground_truth(scene, gbuffer, *, quantity: str = "ao", radius: float | None = None,
                 rays: int = 256, samples: int = 4096, falloff=None, weighting: str = "cosine",
                 normal_clamp: bool = False, seed=0, votes: int = 3, progress: bool = False,
                 groups: int = DEFAULT_GROUPS, threads: int | None = None,
                 allow_open: bool = False, thickness=None, bounces: int = 0,
                 albedo: float = 0.0) -> Estimate:
    """The ray-cast reference at every pixel of a G-buffer.

    Parameters
    ----------
    scene : Scene, trimesh.Trimesh, str or os.PathLike
        The scene the G-buffer was rendered from (anything :func:`vobscure.scenes.as_scene`
        accepts).
    gbuffer : GBuffer
    quantity : {"ao", "obscurance", "volumetric"}
        ``"ao"``: :func:`ambient_occlusion` with ``max_distance=radius`` (inf when radius is
        None); ``"obscurance"``: :func:`obscurance` (radius required); ``"volumetric"``:
        :func:`volumetric_obscurance` (radius required, the half-ball when ``normal_clamp``).
    radius : float, optional
    rays : int
        Rays (directions) per pixel (ao, obscurance).
    samples : int
        Points per ball (volumetric).
    falloff : str, callable or None
        None: the quantity's default, :data:`DEFAULT_FALLOFF` ("linear" for obscurance,
        "constant" for volumetric). Unused for ao.
    weighting, normal_clamp, seed, groups, threads, allow_open
        Passed on.
    thickness : float, optional
        ``"volumetric"`` only: the shell model of :func:`volumetric_obscurance`, surfaces this
        thick on their far side from the G-buffer's camera; any scene, closed or not. None: the
        solid model, which needs a closed scene.
    bounces, albedo
        Interreflections for ``"ao"`` (see :func:`ambient_occlusion`); an error for the
        other quantities when ``bounces`` > 0.
    votes : int
        Odd number of rays per inside test of the volumetric ball (default 3; see
        :func:`volumetric_obscurance`). Unused for ao and obscurance.
    progress : bool
        A tqdm progress bar (default False, as everywhere in vobscure).

    Returns
    -------
    Estimate
        (H, W) value and stderr, NaN on background pixels; of the inner frame
        (:meth:`GBuffer.inner`) when the G-buffer has a guard band.

    Raises
    ------
    ValueError
        Bad arguments (a bool argument that is not True or False included), or a rendered
        G-buffer that does not belong to ``scene``: a covered pixel's primitive index is not
        one of the scene's triangles, or one of :data:`SCENE_CHECK_SAMPLES` hit points lies
        further than the tracer's ray offset from its triangle. A G-buffer from
        :meth:`GBuffer.from_arrays` has no primitives and is not checked.

    Warns
    -----
    SmallRadiusWarning
        ``"volumetric"`` with a radius below the tracer's ray offset, where the inside test
        cannot resolve the ball (the value is returned uncorrected).

    Notes
    -----
    Hemispheres are centred on the G-buffer's world-space shading normal; rays start off
    the surface along the geometric normal (facing the camera), so that shading normals
    never put an origin inside the surface.
    """
    from .gbuffer import GBuffer

    scene = as_scene(scene)
    if not isinstance(gbuffer, GBuffer):
        raise ValueError(f"gbuffer must be a vobscure GBuffer (from render_gbuffer), got {type(gbuffer).__name__}")
    check_choice(quantity, "quantity", QUANTITIES)
    normal_clamp = check_bool(normal_clamp, "normal_clamp")
    allow_open = check_bool(allow_open, "allow_open")
    check_bool(progress, "progress")
    if radius is not None:
        radius = check_positive(radius, "radius", allow_inf=(quantity == "ao"))
    elif quantity != "ao":
        raise ValueError(f"radius is required for quantity={quantity!r}")
    if thickness is not None and quantity != "volumetric":
        raise ValueError(f"thickness (the shell model) is defined for quantity='volumetric' only, "
                         f"got quantity={quantity!r}")
    bounces, albedo = _check_bounces(bounces, albedo)
    if bounces and quantity != "ao":
        raise ValueError(f"bounces > 0 is defined for quantity='ao' only, got quantity={quantity!r}")
    gbuffer = gbuffer.inner()  # a guard band's pixels are not computed: the inner frame only
    valid = gbuffer.valid
    hits = gbuffer.hits  # per covered pixel, row-major: the order of a boolean mask
    points, normals, geo = hits["world_position"], hits["world_normal"], hits["world_geometric_normal"]
    if gbuffer.has_hit_data:
        _check_same_scene(scene.tracer, gbuffer.primitive[valid], points)
    desc = f"ground truth ({quantity})"
    if quantity == "ao":
        check_choice(weighting, "weighting", _WARPS)
        est = _ao(scene, points, normals, geo, rays=check_int(rays, "rays", minimum=2),
                  weighting=weighting, max_distance=np.inf if radius is None else radius, seed=seed,
                  bent_normals=False, groups=groups, threads=threads, progress=progress, desc=desc,
                  bounces=bounces, albedo=albedo)
    elif quantity == "obscurance":
        check_choice(weighting, "weighting", _WARPS)
        est = _obscurance(scene, points, normals, geo, radius=radius,
                          falloff=DEFAULT_FALLOFF[quantity] if falloff is None else falloff,
                          rays=check_int(rays, "rays", minimum=2), weighting=weighting, seed=seed,
                          groups=groups, threads=threads, progress=progress, desc=desc)
    else:
        falloff = DEFAULT_FALLOFF[quantity] if falloff is None else falloff
        check_choice(falloff, "falloff", VO_FALLOFFS)
        votes = _check_votes(votes)
        shell = _shell(thickness, gbuffer.camera)
        if shell is None:
            _check_closed(scene, allow_open)
        est = _volumetric(scene, points, normals if normal_clamp else None, radius=radius,
                          samples=check_int(samples, "samples", minimum=2), falloff=falloff,
                          seed=seed, votes=votes, groups=groups, threads=threads, progress=progress,
                          desc=desc if shell is None else "ground truth (shell)", shell=shell)
    value = np.full(valid.shape, np.nan)
    stderr = np.full(valid.shape, np.nan)
    value[valid] = est.value
    stderr[valid] = est.stderr
    return Estimate(value=value, stderr=stderr, samples=est.samples)
