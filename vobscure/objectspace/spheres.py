r"""Ambient occlusion from sphere sets in spherical harmonics (Ren et al. 2006).

Blocking geometry is a set of spheres. Seen from a receiver point, one sphere of radius r at
distance d blocks a cap of half-angle (angular radius) :math:`\alpha = \arcsin(r/d)` around
its direction; the cap's indicator is a zonal function whose coefficients have a closed form
(:func:`vobscure.objectspace.sh.cap_zonal`), rotated to the sphere's direction. The
receiver's visibility function g is the product of the spheres' visibilities
:math:`1 - \mathrm{cap}_i`, and its AO the dot product of g with the clamped-cosine kernel
rotated to the normal (or the hemisphere's indicator for uniformly weighted AO). Three ways to
form g at order n:

- ``"product"``: the SH product of the band-limited visibilities, one after another (the
  expensive baseline of Ren et al.);
- ``"shexp"``: the paper's method: sum the spheres' log-visibility vectors, looked up against
  the angular radius in a table (:func:`vobscure.objectspace.sh.log_table`) and rotated, and
  exponentiate once (:func:`vobscure.objectspace.sh.sh_exp`);
- ``"sum"``: one minus the sum of the spheres' projected caps (double-counts overlaps).

:func:`union_visibility` is the exact visibility of the union of the same spheres (analytic
ray-sphere tests, Monte Carlo over directions), the reference of the three.
:func:`sphere_set` approximates a closed mesh by k spheres.

References
----------
.. [1] Z. Ren, R. Wang, J. Snyder, K. Zhou, X. Liu, B. Sun, P.-P. Sloan, H. Bao, Q. Peng,
   B. Guo, "Real-time Soft Shadows in Dynamic Scenes using Spherical Harmonic
   Exponentiation", ACM Trans. Graph. 25(3) (SIGGRAPH 2006), 977-986.
.. [2] T. Akenine-Moeller, E. Haines, N. Hoffman, Real-Time Rendering, 3rd ed., Sec. 9.2.5.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np
from scipy.cluster.vq import kmeans2
from scipy.spatial import cKDTree

from .._validate import as_array, as_points, as_rng, as_unit_vectors, check_bool, check_choice, check_int
from ..estimate import DEFAULT_GROUPS, Estimate
from ..raytrace import Tracer
from ..sampling import shifted_hemisphere_directions, sobol_base
from ..scenes import as_scene
from . import sh

__all__ = ["sphere_set_ao", "union_visibility", "sphere_set", "sphere_set_gbuffer", "inside_mesh", "SphereSet",
           "METHODS", "MEMORY_PER_POINT", "TOUCH_RTOL"]

#: Methods of :func:`sphere_set_ao`.
METHODS = ("shexp", "product", "sum")

#: Bytes of temporaries per receiver point that :func:`sphere_set_ao` aims at: spheres are
#: processed in blocks small enough that the per-block arrays stay within it.
MEMORY_PER_POINT = 1536

#: A receiver closer to a sphere's centre than r (1 - TOUCH_RTOL) is inside it (visibility
#: 0); one within that relative distance of the surface touches it (the sphere then blocks a
#: hemisphere, alpha = pi/2).
TOUCH_RTOL = 1e-9

#: Receivers per chunk of :func:`sphere_set_ao` (the memory bound is per point).
DEFAULT_CHUNK = 1024

#: Receivers exponentiated at once within a chunk (the exponentials' temporaries are several
#: (n, n^2) arrays; ``exp="exact"`` builds an (n, n^2, n^2) product matrix, 10 KB per
#: receiver at order 6).
EXP_CHUNK = 256

_SQRT_4PI = np.sqrt(4.0 * np.pi)


class SphereSet(NamedTuple):
    """Spheres: ``centers`` (k, 3) and ``radii`` (k,)."""

    centers: np.ndarray
    radii: np.ndarray


def _check_spheres(centers, radii):
    centers = as_points(centers, "centers")
    radii = as_array(radii, "radii")
    if radii.ndim == 0:
        radii = radii[None]
    if radii.shape != (len(centers),):
        raise ValueError(f"radii must have shape ({len(centers)},), one per centre, got {radii.shape}")
    if np.any(radii <= 0):
        raise ValueError("radii must be > 0")
    return centers, radii


def _check_receivers(points, normals):
    points = as_points(points, "points")
    normals = as_unit_vectors(normals, "normals", count=len(points))
    return points, normals


def _kernel_zonal(weighting: str, order: int) -> np.ndarray:
    return sh.clamped_cosine_zonal(order) if weighting == "cosine" else sh.hemisphere_zonal(order)


def _log_lookup(table: sh.LogTable, alpha: np.ndarray) -> np.ndarray:
    """Linear interpolation of the zonal log vectors at angular radii alpha: (..., n)."""
    size = len(table.alpha)
    t = np.clip(alpha, 0.0, np.pi / 2) * ((size - 1) / (np.pi / 2))
    i = np.minimum(t.astype(np.int64), size - 2)
    w = (t - i)[..., None]
    return (1.0 - w) * table.log_zonal[i] + w * table.log_zonal[i + 1]


def sphere_set_ao(points, normals, centers, radii, *, order: int = 4, method: str = "shexp",
                  exp: str = "hybrid", weighting: str = "cosine", chunk: int = DEFAULT_CHUNK,
                  clip: bool = True) -> np.ndarray:
    r"""Visibility of receivers occluded by a set of spheres, in spherical harmonics.

    Parameters
    ----------
    points : (P, 3) float
        Receivers.
    normals : (P, 3) float
        Their unit normals (renormalized).
    centers : (K, 3) float
    radii : (K,) float
        Sphere radii, > 0.
    order : int
        SH order n (n^2 coefficients), 1 to :data:`vobscure.objectspace.sh.MAX_ORDER`; Ren et
        al. use 4 to 6.
    method : {"shexp", "product", "sum"}
        How the spheres' visibilities combine (module docstring).
    exp : {"hybrid", "ol", "taylor", "exact", "quadrature"}
        The SH exponential of ``"shexp"`` (:func:`vobscure.objectspace.sh.sh_exp`).
    weighting : {"cosine", "uniform"}
        Cosine-weighted AO (:math:`\frac1\pi\int V \max(0, n\cdot\omega)\,d\omega`) or the
        uniform-hemisphere average.
    chunk : int
        Receivers evaluated at once. The temporaries of a chunk are about
        :data:`MEMORY_PER_POINT` bytes per receiver plus a few (chunk, n^2) arrays, whatever
        the number of spheres; the exponential runs on :data:`EXP_CHUNK` receivers at a time.
    clip : bool
        Clip the result to [0, 1]; band-limited products can leave that range.

    Returns
    -------
    (P,) float64
        Visibility (1 = open), no distance limit ("sky visibility" of the spheres).

    Notes
    -----
    A receiver **inside** a sphere (closer to its centre than its radius) sees nothing: its
    visibility is 0, whatever the other spheres. A receiver **touching** one (on its surface,
    within :data:`TOUCH_RTOL`) has that sphere block the hemisphere facing it
    (:math:`\alpha = \pi/2`), which the band limit smears like any other cap.

    With one sphere wholly above the horizon, ``"product"`` and ``"sum"`` give the
    band-limited :math:`1 - \cos\theta\,(r/d)^2` exactly: the error is the band limit's
    alone (``docs/sphere-sets.md`` tabulates it); ``"shexp"`` adds the error of its log table
    and its exponential.

    References
    ----------
    Ren et al. 2006: blockers as spheres, the zonal visibility of one sphere rotated to its
    direction, the product of visibilities ("SH products"), the sum of log vectors tabulated
    against the angular radius and one SH exponentiation ("SH exponentiation"); the shading
    dot product of the visibility vector with the clamped cosine (their ambient-occlusion
    special case).

    Examples
    --------
    >>> import numpy as np
    >>> p, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    >>> c, r = np.array([[0.0, 0.0, 2.0]]), np.array([1.0])
    >>> v = sphere_set_ao(p, n, c, r, order=6, method="product")
    >>> round(1.0 - (1.0 / 2.0) ** 2, 4), round(float(v[0]), 4)   # exact cos(theta) (r/d)^2
    (0.75, 0.7518)
    """
    points, normals = _check_receivers(points, normals)
    centers, radii = _check_spheres(centers, radii)
    order = sh._check_order(order)
    check_choice(method, "method", METHODS)
    check_choice(exp, "exp", sh.EXP_METHODS)
    check_choice(weighting, "weighting", ("cosine", "uniform"))
    chunk = check_int(chunk, "chunk")
    clip = check_bool(clip, "clip")
    n2 = order * order
    kernel = _kernel_zonal(weighting, order)
    G = sh.triple_product_tensor(order) if method == "product" else None
    table = sh.log_table(order) if method == "shexp" else None
    # spheres per block: (P, block, n^2) float64 arrays, a few alive at once
    block = max(1, MEMORY_PER_POINT // (8 * n2 * 3))
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk]
        P = len(p)
        inside = np.zeros(P, dtype=bool)
        if method == "product":
            acc = np.zeros((P, n2))
            acc[:, 0] = _SQRT_4PI                                  # the constant 1
        else:
            acc = np.zeros((P, n2))
        for b in range(0, len(centers), block):
            c, r = centers[b:b + block], radii[b:b + block]
            v = c[None, :, :] - p[:, None, :]                      # (P, B, 3) to the centres
            d = np.sqrt(np.einsum("pbi,pbi->pb", v, v))
            inside |= np.any(d < r * (1.0 - TOUCH_RTOL), axis=1)
            with np.errstate(invalid="ignore", divide="ignore"):
                ratio = np.clip(r / d, 0.0, 1.0)
                w = v / d[..., None]
            w[~np.isfinite(w)] = 0.0
            w[..., 2][d == 0] = 1.0                                # any axis; the point is inside
            alpha = np.arcsin(np.where(np.isfinite(ratio), ratio, 1.0))   # angular radius
            if method == "shexp":
                zonal = _log_lookup(table, alpha)                  # log-visibility table lookup
            else:
                zonal = -sh.cap_zonal(alpha, order)                # -cap: occlusion of the sphere
            vec = sh.rotate_zonal(zonal, w)                        # (P, B, n^2)
            if method == "product":
                for j in range(vec.shape[1]):
                    g = vec[:, j]
                    g[:, 0] += _SQRT_4PI                           # 1 - cap
                    acc = sh._product(acc, g, G)                   # "SH products", one blocker at a time
            else:
                acc += vec.sum(axis=1)                             # log vectors add (shexp); caps add (sum)
        if method == "shexp":
            g = np.empty_like(acc)
            for e in range(0, P, EXP_CHUNK):                       # one SH exponentiation per receiver
                g[e:e + EXP_CHUNK] = sh.sh_exp(acc[e:e + EXP_CHUNK], method=exp)
        elif method == "sum":
            g = acc
            g[:, 0] += _SQRT_4PI
        else:
            g = acc
        h = sh.rotate_zonal(kernel, normals[s:s + chunk])          # kernel turned to the normal
        value = np.einsum("pi,pi->p", g, h)                        # AO: <g, h> (Parseval)
        value[inside] = 0.0
        out[s:s + chunk] = value
    return np.clip(out, 0.0, 1.0) if clip else out


def union_visibility(points, normals, centers, radii, *, rays: int = 256, seed=0,
                     weighting: str = "cosine", groups: int = DEFAULT_GROUPS) -> Estimate:
    r"""The exact visibility of the union of spheres, by analytic ray-sphere tests.

    A ray from p in direction w meets the ball :math:`|x - c| \le r` at some t > 0 when p is
    inside it, or when :math:`b = w\cdot(c - p) > 0` and :math:`b^2 > |c - p|^2 - r^2`.
    Directions are a scrambled Sobol' set warped to the hemisphere (cosine-weighted or
    uniform) with ``groups`` independent Cranley-Patterson shifts per point, as in
    :func:`vobscure.ambient_occlusion`; the standard error is that of the group means
    (``groups - 1`` degrees of freedom).

    Parameters
    ----------
    points : (P, 3) float
    normals : (P, 3) float
    centers : (K, 3) float
    radii : (K,) float
    rays : int
        Rays per point (rounded up to a multiple of ``groups``).
    seed : int, Generator or None
    weighting : {"cosine", "uniform"}
    groups : int
        Independent randomizations, >= 2.

    Returns
    -------
    Estimate
        (P,) visibility with its standard error.

    Examples
    --------
    >>> import numpy as np
    >>> e = union_visibility([[0.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]], [[0.0, 0.0, 2.0]], [1.0],
    ...                      rays=4096, seed=1)
    >>> bool(abs(e.value[0] - 0.75) < 4 * e.stderr[0])   # 1 - cos(theta) (r/d)^2
    True
    """
    points, normals = _check_receivers(points, normals)
    centers, radii = _check_spheres(centers, radii)
    check_choice(weighting, "weighting", ("cosine", "uniform"))
    rays = check_int(rays, "rays", minimum=2)
    g = min(check_int(groups, "groups", minimum=2), rays)
    m = -(-rays // g)
    rng = as_rng(seed)
    base = sobol_base(2, m, rng)
    shifts = rng.random((len(points), g, 2))
    means = np.empty((len(points), g))
    per_chunk = max(1, 2 ** 18 // (g * m))
    r2 = radii * radii
    for s in range(0, len(points), per_chunk):
        p = points[s:s + per_chunk]
        w = shifted_hemisphere_directions(normals[s:s + per_chunk], base, shifts[s:s + per_chunk],
                                          weighting).astype(np.float64)   # (P, g, m, 3)
        hit = np.zeros(w.shape[:-1], dtype=bool)
        for k in range(len(centers)):
            v = centers[k] - p                                    # (P, 3)
            vv = np.einsum("pi,pi->p", v, v)
            b = np.einsum("pgmi,pi->pgm", w, v)
            inside = (vv < r2[k])[:, None, None]
            hit |= inside | ((b > 0) & (b * b > (vv - r2[k])[:, None, None]))
        means[s:s + per_chunk] = 1.0 - hit.mean(axis=2)
    value = means.mean(axis=1)
    stderr = means.std(axis=1, ddof=1) / np.sqrt(g)
    # Binary samples can give identical group means with an inexact value (see
    # docs/groundtruth.md, "When the standard error degenerates"): one step of 1/m per group.
    degenerate = (stderr == 0) & (value > 0) & (value < 1)
    stderr[degenerate] = 1.0 / (m * np.sqrt(g))
    return Estimate(value=value, stderr=stderr, samples=g * m)


# ----------------------------------------------------------------------------- sphere sets
def _inside(tracer: Tracer, face_normals: np.ndarray, q: np.ndarray, rng, votes: int = 3) -> np.ndarray:
    """Inside a closed, outward-wound solid: the first surface a ray meets faces away from
    it (the ray is leaving); majority of ``votes`` random directions (robust to small holes)."""
    count = np.zeros(len(q), dtype=np.int32)
    for _ in range(votes):
        d = rng.normal(size=(len(q), 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        hits = tracer.intersect(q, d, threads=1)
        hit = hits.hit
        leaving = np.zeros(len(q), dtype=bool)
        leaving[hit] = np.einsum("ij,ij->i", face_normals[hits.primitive[hit]], d[hit]) > 0
        count += leaving
    return 2 * count > votes


def _point_triangle_distance(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Distance from points p (N, 3) to triangles tri (N, C, 3, 3): (N, C). Exact (the
    closest point on the triangle: the projection when it falls inside, else the closest
    point on an edge)."""
    a, b, c = tri[..., 0, :], tri[..., 1, :], tri[..., 2, :]
    p = p[:, None, :]
    n = np.cross(b - a, c - a)
    nn = np.linalg.norm(n, axis=-1, keepdims=True)
    n = n / np.where(nn > 0, nn, 1.0)
    h = np.einsum("nci,nci->nc", p - a, n)
    q = p - h[..., None] * n
    inside = nn[..., 0] > 0
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("nci,nci->nc", np.cross(v - u, q - u), n) >= 0
    best = np.where(inside, np.abs(h), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        e = v - u
        ee = np.einsum("nci,nci->nc", e, e)
        t = np.clip(np.einsum("nci,nci->nc", p - u, e) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - (u + t[..., None] * e), axis=-1))
    return best


#: Triangles whose distance is computed exactly per query point (nearest by centroid).
NEAREST_TRIANGLES = 48


def _surface_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest of ``triangles`` (m, 3, 3): exact over all
    triangles for small meshes, else over the NEAREST_TRIANGLES with the nearest centroids
    (exact unless a farther-centred triangle is closer, which needs triangles much larger
    than their neighbours)."""
    m = len(triangles)
    if m <= NEAREST_TRIANGLES:
        cand = np.broadcast_to(np.arange(m), (len(points), m))
    else:
        tree = cKDTree(triangles.mean(axis=1))
        _, cand = tree.query(points, k=NEAREST_TRIANGLES)
    out = np.empty(len(points))
    for s in range(0, len(points), 2048):
        out[s:s + 2048] = _point_triangle_distance(points[s:s + 2048], triangles[cand[s:s + 2048]]).min(axis=1)
    return out


def _selected(scene, meshes):
    """Triangles, face normals and names of the chosen meshes of a Scene."""
    names = list(scene.meshes)
    if meshes is None:
        chosen = names
    else:
        chosen = [meshes] if isinstance(meshes, str) else list(meshes)
        unknown = [m for m in chosen if m not in names]
        if unknown or not chosen:
            raise ValueError(f"meshes must name meshes of the scene ({', '.join(names)}); got {meshes!r}")
    mask = np.isin(scene.mesh_index, [names.index(m) for m in chosen])
    return (np.asarray(scene.triangles, dtype=np.float64)[mask],
            np.asarray(scene.face_normals, dtype=np.float64)[mask], chosen)


def inside_mesh(scene, points, *, meshes=None, votes: int = 3, seed=0) -> np.ndarray:
    """Which points lie inside the closed meshes of a scene.

    A point is inside when the first surface a random ray from it meets faces away from it
    (the ray is leaving the solid); the majority of ``votes`` rays decides, so that small
    holes of a scanned mesh flip few answers.

    Parameters
    ----------
    scene : Scene, str or path
    points : (P, 3) float
    meshes : sequence of str, optional
        The meshes that count (default all).
    votes : int
        Odd number of rays per point.
    seed : int, Generator or None

    Returns
    -------
    (P,) bool

    Examples
    --------
    >>> from vobscure.scenes import cornell_box
    >>> inside_mesh(cornell_box(), [[0.33, 0.3, 0.37], [0.0, 1.0, 0.0]], meshes="short_box").tolist()
    [True, False]
    """
    scene = as_scene(scene)
    points = as_points(points, "points")
    votes = check_int(votes, "votes")
    if votes % 2 == 0:
        raise ValueError(f"votes must be odd (a majority decides), got {votes}")
    triangles, face_normals, _ = _selected(scene, meshes)
    tracer = Tracer(triangles, face_normals=face_normals, threads=1)
    return _inside(tracer, face_normals, points, as_rng(seed), votes)


def sphere_set(scene, k: int, *, seed=0, meshes=None, samples: int = 20000) -> SphereSet:
    r"""Approximate a closed mesh by k inscribed spheres (k-means of interior points).

    1. ``samples`` points uniform in the solid: uniform in the bounding box, kept when
       inside (majority of three ray-parity votes, so small holes in a scanned mesh such as
       the Stanford bunny do not flip the test).
    2. k-means (Lloyd's algorithm, k-means++ seeding; ``scipy.cluster.vq.kmeans2``) of
       those points: the centres. A centre that falls outside the solid (a non-convex
       cluster) is replaced by the cluster's interior point nearest to it.
    3. Radius: the centre's distance to the surface, so that every sphere is inscribed.

    Inscribed spheres never occlude more than the mesh does, and leave gaps between them
    (they under-occlude). Ren et al. (2006) build their sphere sets with a sphere-tree
    construction (Bradshaw & O'Sullivan 2004, medial-axis based) instead; this is a simpler
    stand-in, not theirs.

    Parameters
    ----------
    scene : Scene, str or path
        Anything :func:`vobscure.scenes.as_scene` accepts.
    k : int
        Number of spheres.
    seed : int, Generator or None
    meshes : sequence of str, optional
        Names of the scene's meshes to approximate (together); default all.
    samples : int
        Interior points for the clustering.

    Returns
    -------
    SphereSet
        ``centers`` (k, 3) and ``radii`` (k,), float64 (fewer than k only if fewer distinct
        interior points were found).

    Examples
    --------
    >>> from vobscure.scenes import cornell_box
    >>> s = sphere_set(cornell_box(), 4, meshes=["tall_box"], samples=4000, seed=0)
    >>> s.centers.shape, bool(np.all(s.radii <= 0.3 + 1e-9))   # inscribed in a 0.6-wide box
    ((4, 3), True)
    """
    scene = as_scene(scene)
    k = check_int(k, "k")
    samples = check_int(samples, "samples")
    if k > samples:
        raise ValueError(f"k = {k} spheres need at least k interior points to cluster, but samples = {samples}; "
                         f"pass a smaller k or samples >= k")
    rng = as_rng(seed)
    triangles, face_normals, chosen = _selected(scene, meshes)
    tracer = Tracer(triangles, face_normals=face_normals, threads=1)
    lo, hi = triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0)
    interior = []
    found = 0
    for _ in range(64):
        q = rng.uniform(lo, hi, size=(max(samples, 1024), 3))
        q = q[_inside(tracer, face_normals, q, rng)]
        interior.append(q)
        found += len(q)
        if found >= samples:
            break
    interior = np.concatenate(interior)[:samples]
    if len(interior) < k:
        raise ValueError(f"found only {len(interior)} interior points of meshes {chosen}: is the mesh closed?")
    centers, label = kmeans2(interior, k, minit="++", seed=rng)
    used = np.unique(label)
    centers = centers[used]
    outside = ~_inside(tracer, face_normals, centers, rng)
    for j in np.flatnonzero(outside):
        members = interior[label == used[j]]
        centers[j] = members[np.argmin(np.linalg.norm(members - centers[j], axis=1))]
    radii = _surface_distance(centers, triangles)
    keep = radii > 0
    return SphereSet(centers[keep], radii[keep])


# ----------------------------------------------------------------------------- per pixel
_SPHERE_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _cached_sphere_set(scene, k: int, seed) -> SphereSet:
    per_scene = _SPHERE_CACHE.setdefault(scene, {})
    key = (k, seed if isinstance(seed, int) else None)
    if key[1] is None or key not in per_scene:
        value = sphere_set(scene, k, seed=seed)
        if key[1] is None:
            return value
        per_scene[key] = value
    return per_scene[key]


def sphere_set_gbuffer(gbuffer, *, scene, k: int = 32, order: int = 4, method: str = "shexp",
                       exp: str = "hybrid", weighting: str = "cosine", radius=None,
                       normal_clamp: bool = False, thickness=None, falloff: str = "constant",
                       seed=0) -> np.ndarray:
    """Ren et al. (2006) sphere-set AO at every covered pixel of a G-buffer.

    The scene's meshes are replaced by k inscribed spheres (:func:`sphere_set`, cached per
    scene, k and integer seed in a weak-keyed dictionary), and every covered pixel's world
    position and normal gets :func:`sphere_set_ao`.

    Parameters
    ----------
    gbuffer : GBuffer
        Of ``scene``.
    scene : Scene
    k, order, method, exp, weighting
        As in :func:`sphere_set` and :func:`sphere_set_ao`.
    radius, normal_clamp, thickness, falloff
        Accepted for the estimators' common signature and not used: the model has no radius
        (it estimates the visibility of the whole sky).
    seed : int, Generator or None
        Seed of the sphere set's k-means.

    Returns
    -------
    (H, W) float64
        Visibility, NaN on background.
    """
    k = check_int(k, "k")

    def spheres_ao(x, n):
        spheres = _cached_sphere_set(as_scene(scene), k, seed)
        return sphere_set_ao(x, n, spheres.centers, spheres.radii, order=order, method=method, exp=exp,
                             weighting=weighting)

    return gbuffer.per_pixel(spheres_ao)
