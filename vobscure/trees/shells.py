r"""Shells that enclose a tree's canopy: spheres, ellipsoids and sets of them.

Hegeman et al. 2006 enclose a tree in "a spherical shell" (Sec. 3), in an ellipsoid when the
crown is elongated (Sec. 3, Fig. 3 right), and suggest several shells with each point
belonging to the one with the closest centre (Sec. 5, Fig. 3 left). Every shell here is the
image of the unit sphere under an affine map :math:`x = c + Q \operatorname{diag}(r) \, x'`
(:math:`r` the ``radii``); ``to_unit`` is its inverse, and every model (canopy visibility,
chord lengths) is computed in that unit frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.cluster.vq import ClusterError, kmeans2
from scipy.spatial import ConvexHull

from .._validate import as_array, as_points, as_rng, as_unit_vectors, check_choice, check_int, check_positive

__all__ = [
    "Sphere",
    "Ellipsoid",
    "MultiShell",
    "bounding_sphere",
    "bounding_ellipsoid",
    "shells_from_points",
    "chord_length",
]

#: How far ``rotation.T @ rotation`` may be from the identity (absolute, per entry).
ORTHONORMAL_TOL = 1e-8
#: Relative slack of the bounding-sphere containment test in Welzl's algorithm.
WELZL_TOL = 1e-12
#: Smallest singular value of the centred points, relative to the largest, below which the
#: points are taken as coplanar (or collinear) and have no enclosing ellipsoid of volume > 0.
FLAT_TOL = 1e-9
#: Relative enlargement of a fitted shell so that the points on its boundary test as
#: contained despite round-off.
ENCLOSE_SLACK = 1e-10
#: Iteration cap of Khachiyan's algorithm (the tolerance, not this cap, normally stops it).
KHACHIYAN_MAX_ITER = 100_000
#: The range of a shell's volume: every model multiplies by it (the canopy's optical depth,
#: the density fits), so it must be a finite, normal float64 (no overflow to inf, no
#: underflow to 0). For a sphere this bounds the radius to about [1.7e-103, 3.5e102].
VOLUME_MIN = float(np.finfo(np.float64).tiny)
VOLUME_MAX = float(np.finfo(np.float64).max)


def _check_volume(volume_scale: float, name: str, value) -> None:
    """Reject a shell whose volume 4/3 pi ``volume_scale`` overflows or underflows float64."""
    volume = 4.0 / 3.0 * math.pi * volume_scale
    if not (VOLUME_MIN <= volume <= VOLUME_MAX):
        lo = (VOLUME_MIN / (4.0 / 3.0 * math.pi)) ** (1.0 / 3.0)
        hi = (VOLUME_MAX / (4.0 / 3.0 * math.pi)) ** (1.0 / 3.0)
        raise ValueError(f"{name} {value!r} gives a volume of {volume:.3g}, outside the float64 range "
                         f"[{VOLUME_MIN:.3g}, {VOLUME_MAX:.3g}] that the models multiply by; a sphere's "
                         f"radius must lie in [{lo:.3g}, {hi:.3g}] (rescale the scene's units)")


# ----------------------------------------------------------------------------- shells
class _UnitBallImage:
    """The queries every shell answers in its unit frame, where it is the closed unit ball;
    a subclass supplies the map (``to_unit`` and ``vectors_to_unit``)."""

    __slots__ = ()

    def contains(self, points) -> np.ndarray:
        """(n,) bool: the point lies in the closed shell."""
        x = self.to_unit(points)
        return np.einsum("ij,ij->i", x, x) <= 1.0

    def chord_length(self, origins, directions) -> np.ndarray:
        r"""(n,) length of the part of the ray :math:`\{o + t d, t \ge 0\}` inside the shell.

        0 for a miss (and for a tangent ray); from the origin to the exit when the origin is
        inside. ``directions`` need not be unit vectors (they are normalized). See
        :func:`chord_length`.
        """
        return chord_length(self, origins, directions)


@dataclass(frozen=True, eq=False)
class Sphere(_UnitBallImage):
    """A sphere of centre ``center`` and radius ``radius`` (Hegeman 2006's "spherical shell").

    Parameters
    ----------
    center : (3,) float
        The centre c, in world units.
    radius : float
        The radius R > 0, finite.

    Attributes
    ----------
    center : (3,) float64 array, read-only
    radius : float

    Raises
    ------
    ValueError
        If ``center`` is not three finite numbers, or ``radius`` is not positive and finite,
        or the volume 4/3 pi R^3 over- or underflows float64 (see
        :data:`VOLUME_MIN`, :data:`VOLUME_MAX`).

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3 and Fig. 1.

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 2.0)
    >>> round(s.volume, 4)
    33.5103
    >>> s.chord_length([[-5.0, 0, 0]], [[1.0, 0, 0]])
    array([4.])
    """

    center: np.ndarray
    radius: float

    def __post_init__(self):
        center = as_array(self.center, "center", shape=(3,)).copy()
        center.setflags(write=False)
        object.__setattr__(self, "center", center)
        radius = check_positive(self.radius, "radius")
        _check_volume(radius * radius * radius, "radius", radius)
        object.__setattr__(self, "radius", radius)

    @property
    def volume(self) -> float:
        r""":math:`\frac{4}{3} \pi R^3`."""
        return 4.0 / 3.0 * math.pi * self.radius ** 3

    @property
    def volume_scale(self) -> float:
        """:math:`R^3`: the factor from volumes in the unit frame to world volumes."""
        return self.radius ** 3

    @property
    def equivalent_radius(self) -> float:
        """The radius of the sphere of the same volume: R."""
        return self.radius

    def to_unit(self, points) -> np.ndarray:
        """(n, 3) coordinates :math:`(x - c) / R` of ``points`` (n, 3) in the unit-sphere frame."""
        return (as_points(points, "points") - self.center) / self.radius

    def vectors_to_unit(self, vectors) -> np.ndarray:
        """(n, 3) displacements mapped by the linear part of ``to_unit`` (not renormalized)."""
        return as_points(vectors, "vectors") / self.radius

    def normals_to_unit(self, normals) -> np.ndarray:
        """(n, 3) unit normals in the unit-sphere frame (a uniform scale keeps them)."""
        return as_unit_vectors(normals, "normals")


@dataclass(frozen=True, eq=False)
class Ellipsoid(_UnitBallImage):
    r"""An ellipsoid :math:`\{c + Q \operatorname{diag}(r) \, x' : \lVert x' \rVert \le 1\}`.

    Parameters
    ----------
    center : (3,) float
        The centre c.
    radii : (3,) float
        The semi-axes (a, b, c), each positive and finite, in the order of ``rotation``'s
        columns.
    rotation : (3, 3) float or None
        Orthonormal matrix Q whose columns are the ellipsoid's axes (a reflection is
        accepted); None for the world axes (Q = identity).

    Attributes
    ----------
    center : (3,) float64 array, read-only
    radii : (3,) float64 array, read-only
    rotation : (3, 3) float64 array, read-only

    Raises
    ------
    ValueError
        If a radius is zero, negative or not finite, the volume over- or underflows float64
        (:data:`VOLUME_MIN`, :data:`VOLUME_MAX`), or ``rotation`` is not orthonormal (to
        ``ORTHONORMAL_TOL``).

    References
    ----------
    Hegeman et al. 2006, Sec. 3 (ellipsoidal shells, "scaling along the axes is applied,
    bringing the ellipsoidal shell into a sphere") and Fig. 3 right.

    Examples
    --------
    >>> e = Ellipsoid((0, 0, 0), (3.0, 1.0, 1.0))
    >>> e.chord_length([[-5.0, 0, 0], [0, -5.0, 0]], [[1.0, 0, 0], [0, 1.0, 0]])
    array([6., 2.])
    >>> e.contains([[2.9, 0, 0], [0, 1.1, 0]])
    array([ True, False])
    """

    center: np.ndarray
    radii: np.ndarray
    rotation: np.ndarray | None = None

    def __post_init__(self):
        center = as_array(self.center, "center", shape=(3,)).copy()
        radii = as_array(self.radii, "radii", shape=(3,)).copy()
        if np.any(radii <= 0):
            raise ValueError(f"radii must be three positive numbers (a degenerate ellipsoid has a zero "
                             f"semi-axis), got {radii.tolist()}")
        _check_volume(float(radii[0]) * float(radii[1]) * float(radii[2]), "radii", radii.tolist())
        if self.rotation is None:
            rotation = np.eye(3)
        else:
            rotation = as_array(self.rotation, "rotation", shape=(3, 3)).copy()
            err = np.abs(rotation.T @ rotation - np.eye(3)).max()
            if err > ORTHONORMAL_TOL:
                raise ValueError(f"rotation must be orthonormal (its columns are the ellipsoid's unit axes); "
                                 f"max |Q^T Q - I| = {err:.3g}")
        for name, arr in (("center", center), ("radii", radii), ("rotation", rotation)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def volume(self) -> float:
        r""":math:`\frac{4}{3} \pi a b c`."""
        return 4.0 / 3.0 * math.pi * self.volume_scale

    @property
    def volume_scale(self) -> float:
        """:math:`a b c`: the factor from volumes in the unit frame to world volumes."""
        return float(np.prod(self.radii))

    @property
    def equivalent_radius(self) -> float:
        """:math:`(a b c)^{1/3}`: the radius of the sphere of the same volume."""
        return float(np.cbrt(np.prod(self.radii)))

    def to_unit(self, points) -> np.ndarray:
        r"""(n, 3) coordinates :math:`\operatorname{diag}(r)^{-1} Q^T (x - c)` of ``points`` (n, 3)."""
        return ((as_points(points, "points") - self.center) @ self.rotation) / self.radii

    def vectors_to_unit(self, vectors) -> np.ndarray:
        """(n, 3) displacements mapped by the linear part of ``to_unit`` (not renormalized)."""
        return (as_points(vectors, "vectors") @ self.rotation) / self.radii

    def normals_to_unit(self, normals) -> np.ndarray:
        """(n, 3) unit normals mapped by the inverse transpose ``diag(radii) Q^T``, renormalized.

        A plane with normal n through x maps to the plane through ``to_unit(x)`` with this
        normal (Hegeman 2006, Sec. 3: "a new point position and cutting plane orientation").
        """
        n = (as_unit_vectors(normals, "normals") @ self.rotation) * self.radii
        return n / np.linalg.norm(n, axis=1, keepdims=True)


def chord_length(shell, origins, directions) -> np.ndarray:
    r"""(n,) length of the part of each ray :math:`\{o + t d, t \ge 0\}` inside ``shell``.

    Parameters
    ----------
    shell : Sphere or Ellipsoid
    origins : (n, 3) float
        Ray origins o, finite.
    directions : (n, 3) float
        Ray directions d, nonzero (normalized here, so t is a world length).

    Returns
    -------
    (n,) float64
        0 when the ray misses the shell or only touches it (tangent ray); the distance from
        o to the exit when o is inside; the full chord otherwise. World units.

    Notes
    -----
    Solved in the shell's unit frame, where the shell is the unit sphere: with :math:`e` the
    unit direction there, :math:`b = o \cdot e` and :math:`D = 1 - \lVert o - b e \rVert^2`
    (the cancellation-free form of the discriminant); the exit from inside is
    :math:`-b + \sqrt{D}`, written :math:`-(\lVert o \rVert^2 - 1) / (\sqrt{D} + b)` when
    :math:`b > 0`. Lengths in the unit frame are
    divided by the length of the mapped world unit step.

    Examples
    --------
    >>> chord_length(Sphere((0, 0, 0), 1.0), [[-3, 0, 0], [0, 0, 0], [-3, 1, 0]],
    ...              [[1, 0, 0], [0, 0, 2], [1, 0, 0]])
    array([2., 1., 0.])
    """
    o = shell.to_unit(origins)
    w = as_unit_vectors(directions, "directions", count=o.shape[0])
    d = shell.vectors_to_unit(w)                      # the world unit step, in the unit frame
    d_len = np.linalg.norm(d, axis=1)
    e = d / d_len[:, None]
    # |o + s e| = 1 in the unit frame; the discriminant as 1 - |o_perp|^2 (no b^2 - c
    # cancellation for distant origins); s is a length in the unit frame, t = s / |d| in world.
    b = np.einsum("ij,ij->i", o, e)
    perp = o - b[:, None] * e
    disc = 1.0 - np.einsum("ij,ij->i", perp, perp)
    c0 = np.einsum("ij,ij->i", o, o) - 1.0
    s = np.sqrt(np.maximum(disc, 0.0))
    inside = c0 < 0
    # inside: the exit -b + s, written -c0 / (s + b) when b > 0 (no cancellation near the surface)
    with np.errstate(divide="ignore", invalid="ignore"):
        exit_ = np.where(b > 0, -c0 / (s + b), s - b)
    length = np.where(inside, exit_, np.where((b < 0) & (disc > 0), 2.0 * s, 0.0))
    return np.where(disc > 0, length, 0.0) / d_len


Shell = Sphere | Ellipsoid


# ----------------------------------------------------------------------------- several shells
class MultiShell:
    """Several shells; a point belongs to the shell whose centre is closest.

    Parameters
    ----------
    shells : sequence of Sphere or Ellipsoid
        At least one.

    Attributes
    ----------
    shells : tuple of Sphere or Ellipsoid
    centers : (k, 3) float64 array

    References
    ----------
    Hegeman et al. 2006, Sec. 5 ("we can consider a point to belong to exactly one such shell
    (that with the closest center) even if geometrically it lies in several shells
    simultaneously") and Fig. 3 left.

    Examples
    --------
    >>> m = MultiShell([Sphere((0, 0, 0), 1.0), Sphere((3, 0, 0), 1.5)])
    >>> m.assign([[0.2, 0, 0], [1.6, 0, 0], [9, 9, 9]])
    array([0, 1, 1])
    """

    def __init__(self, shells: Sequence[Shell]):
        shells = tuple(shells)
        if not shells:
            raise ValueError("shells must hold at least one Sphere or Ellipsoid")
        for i, s in enumerate(shells):
            if not isinstance(s, (Sphere, Ellipsoid)):
                raise ValueError(f"shells[{i}] must be a Sphere or an Ellipsoid, got {type(s).__name__}")
        self.shells = shells
        self.centers = np.array([s.center for s in shells])
        self.centers.setflags(write=False)

    def __len__(self) -> int:
        return len(self.shells)

    def __iter__(self) -> Iterator[Shell]:
        return iter(self.shells)

    def __getitem__(self, i) -> Shell:
        return self.shells[i]

    def __repr__(self) -> str:
        return f"MultiShell({list(self.shells)!r})"

    @property
    def volume(self) -> float:
        """The sum of the shells' volumes (overlaps counted twice)."""
        return float(sum(s.volume for s in self.shells))

    def assign(self, points) -> np.ndarray:
        """(n,) int index of the shell whose centre is closest to each point (ties: lowest)."""
        x = as_points(points, "points")
        d2 = ((x[:, None, :] - self.centers[None, :, :]) ** 2).sum(axis=-1)
        return np.argmin(d2, axis=1)


# ----------------------------------------------------------------------------- fitting shells
def _circumball(support: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """The smallest sphere through 1-4 points (its centre in their affine hull)."""
    p0 = support[0]
    if len(support) == 1:
        return p0, 0.0
    A = np.array(support[1:]) - p0
    M = 2.0 * A @ A.T
    rhs = np.einsum("ij,ij->i", A, A)
    lam = np.linalg.lstsq(M, rhs, rcond=None)[0]
    c = p0 + lam @ A
    return c, float(np.sqrt(max(np.dot(c - p0, c - p0), *(np.dot(c - p, c - p) for p in support[1:]))))


def _welzl(P: np.ndarray, support: list[np.ndarray], scale: float) -> tuple[np.ndarray | None, float]:
    """Smallest ball of P with ``support`` on its boundary (Welzl 1991, iterative over P)."""
    if support:
        c, r = _circumball(support)
    else:
        c, r = None, -1.0
    if len(support) == 4:
        return c, r
    i = 0
    while i < len(P):
        if c is None:
            j = i
        else:
            dist = np.linalg.norm(P[i:] - c, axis=1)
            out = np.flatnonzero(dist > r + WELZL_TOL * scale)
            if out.size == 0:
                break
            j = i + int(out[0])
        c, r = _welzl(P[:j], support + [P[j]], scale)
        i = j + 1
    return c, r


def _as_cloud(points, name: str = "points", minimum: int = 1) -> np.ndarray:
    P = as_points(points, name)
    if P.shape[0] < minimum:
        raise ValueError(f"{name} must hold at least {minimum} point(s), got {P.shape[0]}")
    return P


def bounding_sphere(points) -> Sphere:
    """The smallest sphere enclosing ``points`` (Hegeman 2006's "spherical bounding box").

    Parameters
    ----------
    points : (n, 3) float
        At least two distinct finite points.

    Returns
    -------
    Sphere
        The minimal enclosing sphere (exact up to round-off: every point lies within
        ``R`` of the centre, R enlarged by the relative ``ENCLOSE_SLACK`` so that the
        points on the sphere test as contained).

    Raises
    ------
    ValueError
        If ``points`` is empty, holds NaN/inf, or all points coincide (radius 0).

    Notes
    -----
    Welzl's randomized incremental algorithm, over the convex hull's vertices when the points
    span 3D (expected linear time; the point order is shuffled by a fixed private generator,
    so the result is deterministic; the minimal sphere is unique anyway).

    References
    ----------
    Welzl 1991, "Smallest enclosing disks (balls and ellipsoids)", LNCS 555.
    Hegeman et al. 2006, Sec. 3 ("a simple spherical bounding box computation").

    Examples
    --------
    >>> s = bounding_sphere([[1, 0, 0], [-1, 0, 0], [0, 0.5, 0], [0, 0, 0.2]])
    >>> s.center.round(9).tolist(), round(s.radius, 9)
    ([0.0, 0.0, 0.0], 1.0)
    """
    P = _candidates(_as_cloud(points))
    scale = float(np.ptp(P, axis=0).max())
    if scale == 0:
        raise ValueError("points must hold at least two distinct points (their bounding sphere has radius 0)")
    P = P[np.random.default_rng(0).permutation(P.shape[0])]
    c, r = _welzl(P, [], scale)
    # the exact minimal radius, from the final centre
    r = float(np.linalg.norm(P - c, axis=1).max())
    return Sphere(c, r * (1.0 + ENCLOSE_SLACK))


def _candidates(P: np.ndarray) -> np.ndarray:
    """The convex hull's vertices when the points span 3D (else all points)."""
    if P.shape[0] > 16 and _flatness(P) > FLAT_TOL:
        return P[ConvexHull(P).vertices]
    return P


def _flatness(P: np.ndarray) -> float:
    """Smallest singular value of the centred points relative to the largest (0 when flat)."""
    sv = np.linalg.svd(P - P.mean(axis=0), compute_uv=False)
    return float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0


def bounding_ellipsoid(points, *, tol: float = 1e-4) -> Ellipsoid:
    r"""The minimum-volume ellipsoid enclosing ``points`` (Khachiyan's algorithm).

    Parameters
    ----------
    points : (n, 3) float
        At least 4 finite points, not coplanar.
    tol : float, keyword-only
        Relative optimality tolerance epsilon: the iteration stops when every point's lifted
        Mahalanobis value ``M_j`` is at most ``(1 + tol)(d + 1)`` and every point of positive
        weight's at least ``(1 - tol)(d + 1)`` (d = 3), the eps-approximate optimality
        condition of Todd & Yildirim.

    Returns
    -------
    Ellipsoid
        An ellipsoid that encloses every point (the final shape is scaled so that the
        farthest point lies on its surface), of volume within a factor ``(1 + tol)^(3/2)``
        of the minimum.

    Raises
    ------
    ValueError
        Fewer than 4 points, NaN/inf, or points that are coplanar or collinear (their
        enclosing ellipsoid would be flat, of volume 0).

    Notes
    -----
    Khachiyan's barycentric coordinate ascent on the dual weights :math:`u` (lifted points
    :math:`q_j = (p_j, 1)`, :math:`X(u) = \sum_j u_j q_j q_j^T`,
    :math:`M_j = q_j^T X^{-1} q_j`), with Todd & Yildirim's away steps (weight moved off the
    point of smallest :math:`M_j`), which make the convergence linear. It runs on the convex
    hull's vertices. The ellipsoid is

    .. math::

        \{x : (x - c)^T \Sigma^{-1} (x - c) \le \max_j (M_j - 1)\}, \quad
        c = \sum_j u_j p_j, \quad \Sigma = \sum_j u_j (p_j - c)(p_j - c)^T.

    References
    ----------
    Khachiyan 1996, "Rounding of polytopes in the real number model of computation",
    Mathematics of Operations Research 21(2).
    Todd & Yildirim 2007, "On Khachiyan's algorithm for the computation of minimum-volume
    enclosing ellipsoids", Discrete Applied Mathematics 155(13), Sec. 2-3 (the WA-TY
    algorithm).

    Examples
    --------
    >>> corners = np.array([[x, y, z] for x in (-2, 2) for y in (-1, 1) for z in (-1, 1)], float)
    >>> e = bounding_ellipsoid(corners, tol=1e-9)
    >>> np.sort(e.radii).round(6).tolist()     # the box's half-sides times sqrt(3)
    [1.732051, 1.732051, 3.464102]
    """
    tol = check_positive(tol, "tol")
    P = _as_cloud(points, minimum=4)
    if _flatness(P) <= FLAT_TOL:
        raise ValueError("points are coplanar or collinear: their enclosing ellipsoid is flat (volume 0); "
                         "bound them with bounding_sphere or add points off the plane")
    P = P[ConvexHull(P).vertices] if P.shape[0] > 4 else P
    mean = P.mean(axis=0)
    spread = float(np.abs(P - mean).max())
    X_pts = (P - mean) / spread                     # conditioned: centred, unit extent
    n, d = X_pts.shape
    Q = np.vstack([X_pts.T, np.ones(n)])            # (d + 1, n) lifted points
    u = np.full(n, 1.0 / n)
    for _ in range(KHACHIYAN_MAX_ITER):
        X = (Q * u) @ Q.T
        M = np.einsum("ij,ij->j", Q, np.linalg.solve(X, Q))
        j_up = int(np.argmax(M))
        positive = u > 0
        j_down = int(np.flatnonzero(positive)[np.argmin(M[positive])])
        kappa_up, kappa_down = M[j_up], M[j_down]
        if kappa_up <= (1 + tol) * (d + 1) and kappa_down >= (1 - tol) * (d + 1):
            break
        if kappa_up - (d + 1) >= (d + 1) - kappa_down:
            lam = (kappa_up / (d + 1) - 1.0) / (kappa_up - 1.0)      # Khachiyan's step
            u *= 1.0 - lam
            u[j_up] += lam
        else:                                                         # away step (Todd-Yildirim)
            lam = min((1.0 - kappa_down / (d + 1)) / (kappa_down - 1.0), u[j_down] / (1.0 - u[j_down]))
            u *= 1.0 + lam
            u[j_down] -= lam
            u[j_down] = max(u[j_down], 0.0)
    c = X_pts.T @ u
    D = X_pts - c
    Sigma = (D.T * u) @ D
    Sigma_inv = np.linalg.inv(Sigma)
    m = float(np.einsum("ij,jk,ik->i", D, Sigma_inv, D).max())     # scale so every point is enclosed
    A = Sigma_inv / m                                                # {x : x^T A x <= 1}
    eigval, eigvec = np.linalg.eigh(A)
    radii = spread / np.sqrt(eigval) * (1.0 + ENCLOSE_SLACK)
    if np.linalg.det(eigvec) < 0:
        eigvec[:, 0] *= -1.0
    return Ellipsoid(mean + spread * c, radii, eigvec)


def shells_from_points(points, k: int, *, kind: str = "sphere", seed=0) -> MultiShell:
    """``k`` shells around the clusters of ``points`` (k-means, then a bounding shell each).

    Parameters
    ----------
    points : (n, 3) float
        The tree's points (leaf vertices, say).
    k : int
        Number of shells, >= 1.
    kind : {"sphere", "ellipsoid"}, keyword-only
        Bound each cluster with ``bounding_sphere`` or ``bounding_ellipsoid``.
    seed : int, numpy.random.Generator or None, keyword-only
        The k-means initialization (k-means++); the same seed gives the same shells.

    Returns
    -------
    MultiShell
        The shells in cluster order. Each encloses its own cluster; a point is then assigned
        to the shell with the closest centre (which need not be its cluster's).

    Raises
    ------
    ValueError
        Bad ``k`` or ``kind``, a cluster left empty by k-means, or (ellipsoids) a cluster of
        fewer than 4 points or a flat one.

    References
    ----------
    Hegeman et al. 2006, Sec. 5 and Fig. 3 left (several shells).
    Lloyd 1982 / Arthur & Vassilvitskii 2007 (k-means, k-means++), via
    ``scipy.cluster.vq.kmeans2``.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> pts = np.vstack([rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) + 10])
    >>> m = shells_from_points(pts, 2, seed=0)
    >>> len(m), bool(np.all([s.radius < 5 for s in m]))
    (2, True)
    """
    P = _as_cloud(points)
    k = check_int(k, "k", minimum=1)
    kind = check_choice(kind, "kind", ("sphere", "ellipsoid"))
    rng = as_rng(seed)
    if k > P.shape[0]:
        raise ValueError(f"k must not exceed the number of points ({P.shape[0]}), got {k}")
    if k == 1:
        labels = np.zeros(P.shape[0], dtype=int)
    else:
        try:
            _, labels = kmeans2(P, k, minit="++", missing="raise", rng=rng)
        except ClusterError:
            raise ValueError(f"k-means left a cluster empty with k={k}; use a smaller k or another seed") from None
    fit = bounding_sphere if kind == "sphere" else bounding_ellipsoid
    shells = []
    for i in range(k):
        cluster = P[labels == i]
        try:
            shells.append(fit(cluster))
        except ValueError as exc:
            raise ValueError(f"cluster {i} of {k} ({cluster.shape[0]} points) has no {kind}: {exc}") from None
    return MultiShell(shells)
