r"""The visibility a Poisson leaf cloud has in expectation: the canopy model exact in expectation.

Hegeman et al. (2006, Sec. 3) argue from a Poisson process of leaves and then replace its
expected visibility by :math:`e^{-\alpha \rho f V_{cap}}` (Eq. 6). The expectation itself is
simple. Leaves scattered uniformly in a shell with :math:`n` leaves per unit volume, each flat,
of one-sided area :math:`A` and of random orientation, block a segment of length :math:`L` a
Poisson number of times with mean :math:`\sigma L`, where the extinction
:math:`\sigma = n A / 2` (the mean projected area of a randomly oriented flat leaf is half its
area; ``docs/trees.md`` derives it). The probability that a ray from :math:`x` in direction
:math:`w` escapes is :math:`e^{-\sigma L(x, w)}`, :math:`L` the chord of the ray inside the
shell, and the expected visibility is its hemisphere average:

.. math::

    V(x, n) = \frac{1}{2\pi} \int_{n \cdot w > 0} e^{-\sigma L(x, w)} \, dw \quad
    \text{(uniform)}, \qquad
    V(x, n) = \frac{1}{\pi} \int_{n \cdot w > 0} e^{-\sigma L(x, w)} \, (n \cdot w) \, dw \quad
    \text{(cosine)}

For a sphere of radius :math:`R` the chord depends only on the angle :math:`\psi` between
:math:`w` and the direction from :math:`x` to the centre, so the integral is one-dimensional
once the azimuth about that direction is integrated in closed form (:func:`sphere_transmittance`, the one implementation
of this integral: the ``"porous"`` ground model of :func:`vobscure.trees.occluder_visibility`
calls it too). :math:`V` then depends only on :math:`\lVert x - c \rVert / R`, the angle
between :math:`n` and :math:`x - c`, and :math:`\sigma R`: :func:`poisson_visibility`
interpolates a table precomputed once (:data:`TABLE_RADIAL`, :data:`TABLE_ANGULAR`), exact
in :math:`\sigma R`, within
:data:`TABLE_ERROR` of the direct quadrature. Ellipsoids use Hegeman's affine map (an
approximation, measured against :func:`poisson_quadrature` in the true ellipsoid), sets of
shells Hegeman's Sec. 5 rule (each point belongs to the shell with the closest centre).
"""

from __future__ import annotations

import math
import numbers
from functools import lru_cache

import numpy as np

from .._validate import as_array, as_points, as_unit_vectors, check_choice, check_int, check_positive
from ._arrays import ZERO_NORMAL, as_raw_points, check_normal_lengths, out_dtype
from .shells import Ellipsoid, MultiShell, Sphere

__all__ = [
    "WEIGHTINGS",
    "DEFAULT_QUADRATURE",
    "TABLE_RADIAL",
    "TABLE_ANGULAR",
    "TABLE_QUADRATURE",
    "TABLE_ERROR",
    "TABLE_SIGMA_R_MAX",
    "DEFAULT_CHUNK",
    "extinction",
    "poisson_visibility",
    "sphere_transmittance",
    "poisson_quadrature",
]

#: Angular weightings: "cosine" (the form factor, RTR's k_A) or "uniform" (solid angle / 2 pi).
WEIGHTINGS = ("cosine", "uniform")
#: Gauss-Legendre nodes per piece of :func:`sphere_transmittance`'s integral in psi (two
#: pieces for a point outside the sphere, four inside).
DEFAULT_QUADRATURE = 16
#: Largest number of Gauss-Legendre nodes accepted (``quadrature`` of
#: :func:`sphere_transmittance` and of the porous occluders, ``nodes`` of
#: :func:`poisson_quadrature`): the nodes come from the eigenvalues of a (count, count)
#: matrix, 8 MB at this limit and 75 GB at 10^5. The default's error is already below 1e-6.
MAX_QUADRATURE = 1024
#: Cells of the table along its radial coordinate, on each side of the surface: inside,
#: ``a = 1 - (1 - rho)^(1/3)`` in [0, 1] (cells shrink as the cube toward the surface, where
#: V changes over a depth of about 1 / sigma: the last spans 4e-6 radii); outside,
#: ``a = 1 + cos(alpha)`` in [1, 2], ``sin(alpha) = 1 / rho`` the angular radius of the sphere (V is close to linear in
#: cos(alpha) far away, and the square root of the distance to the surface near it is
#: resolved). rho = |x - c| / R.
TABLE_RADIAL = 64
#: Cells of the table along ``v = sign(u) (1 - sqrt(1 - |u|))`` in [-1, 1], u = n.(x - c) /
#: |x - c| (near u = +-1, v is proportional to the angle, in which V is smooth).
TABLE_ANGULAR = 64
#: Gauss-Legendre nodes per piece of the quadrature at each node of the table.
TABLE_QUADRATURE = 24
#: Bound on the absolute error of :func:`poisson_visibility` on a sphere (bilinear
#: interpolation of the table) against the direct quadrature :func:`sphere_transmittance`
#: with 128 nodes per piece, for ``sigma R`` up to :data:`TABLE_SIGMA_R_MAX` and for the
#: opaque limit, over points from the centre to 4 radii (a fifth of them within 1e-3 to 1e-7
#: radii of the surface) and normals in every direction: largest errors measured 1.1e-3
#: (sigma R = 32), 6e-4 (10), 3e-4 (1), 7e-4 (inf), 2e-3 at sigma R = 100
#: (``tests/test_poisson.py::test_table_against_direct_quadrature`` checks it; see
#: ``docs/trees.md`` for the measured errors per sigma R).
TABLE_ERROR = 2e-3
#: The largest ``sigma R`` at which :data:`TABLE_ERROR` was measured (ten times the densest
#: scene's, ``leaf_cloud_dense``, 3.1); beyond it the error inside the sphere grows with the
#: steepness of V just below the surface.
TABLE_SIGMA_R_MAX = 32.0
#: Points evaluated at once by :func:`poisson_visibility`: its temporaries are about 190 bytes
#: per point of a chunk (the affine map, the interpolation's indices and weights), so 16384
#: points keep them near 3 MB, under 100 bytes per point from 32768 points on.
DEFAULT_CHUNK = 1 << 14
#: Floor of |m| |x| in the division that gives u (only the centre, where n.x = 0, reaches it).
_TINY = 1e-300


# ----------------------------------------------------------------------------- the core
def check_quadrature(value, name: str) -> int:
    """A node count in [1, :data:`MAX_QUADRATURE`], named ``name`` in the error."""
    count = check_int(value, name, minimum=1)
    if count > MAX_QUADRATURE:
        raise ValueError(f"{name} must be at most MAX_QUADRATURE = {MAX_QUADRATURE} Gauss-Legendre nodes "
                         f"(their computation needs a ({name}, {name}) matrix: {8 * count * count / 2**30:.3g} "
                         f"GiB for {count}); got {count}. The default {DEFAULT_QUADRATURE} is accurate to 1e-6")
    return count


def _gauss_nodes(count: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, pi]."""
    z, w = np.polynomial.legendre.leggauss(count)
    return 0.5 * np.pi * (z + 1.0), 0.5 * np.pi * w


def _sphere_nodes(d: np.ndarray, cos_theta: np.ndarray, weighting: str, count: int):
    """The quadrature of the hemisphere integral over a unit sphere's chords.

    ``d`` (m,) are distances from the points to the centre in radii, ``cos_theta`` (m,) the
    cosines of the angle between each normal and the direction *to* the centre (any value
    where d = 0). Returns chords ``L`` and weights ``W``, both (m, 4 count), such that the
    weighted fraction of the hemisphere that a medium of unit-frame extinction s absorbs is
    ``sum_k W_k (1 - exp(-s L_k))``; W is 0 for the unused nodes (the two inner pieces of a
    point outside the sphere).

    The directions are parametrized by psi, their angle from the direction to the centre, and
    the azimuth phi about it. The chord depends on psi only; the weight of the arc of the ring
    psi that lies above the horizon is closed-form in phi; the remaining integral in psi is
    split where it has kinks and each piece integrated by Gauss-Legendre after the
    substitution psi = a + (b - a)(1 - cos t) / 2, t in [0, pi], which removes the
    square-root endpoint behaviour of the chord at the cap's rim and of the arc at the kinks.
    """
    m = d.shape[0]
    t, wt = _gauss_nodes(count)
    cos_theta = np.where(d > 0, np.clip(cos_theta, -1.0, 1.0), 1.0)
    theta = np.arccos(cos_theta)
    sin_t = np.sin(theta)
    outside = d > 1.0
    # alpha: the half-angle of the cone of directions that meet the sphere (all from inside)
    alpha = np.where(outside, np.arcsin(1.0 / np.where(outside, d, 1.0)), np.pi)
    # Kinks: the ring psi meets the horizon from psi_1 = |pi/2 - theta| and lies wholly on
    # one side of it again from psi_2 = pi - psi_1; from inside, the chord
    # d cos psi + sqrt(1 - d^2 sin^2 psi) also bends sharply at psi = pi/2 when d is close to
    # 1. psi_1 <= pi/2 <= psi_2 and alpha < pi/2 outside the sphere: a point outside has two
    # pieces, a point inside four.
    psi_1 = np.minimum(np.abs(0.5 * np.pi - theta), alpha)
    mid = np.minimum(0.5 * np.pi, alpha)
    psi_2 = np.where(outside, mid, np.pi - psi_1)
    end = np.where(outside, mid, np.pi)
    pieces = ((np.zeros(m), psi_1), (psi_1, mid), (mid, psi_2), (psi_2, end))
    L = np.empty((m, 4 * count))
    W = np.empty((m, 4 * count))
    s_node = 0.5 * (1.0 - np.cos(t))                  # (count,) position in the piece
    for p, (a, b) in enumerate(pieces):
        half = 0.5 * (b - a)
        psi = a[:, None] + (b - a)[:, None] * s_node[None, :]
        cos_p, sin_p = np.cos(psi), np.sin(psi)
        # the chord of the unit sphere along the ray at angle psi from the centre's direction
        along = d[:, None] * cos_p                          # the centre's projection on the ray
        perp2 = (d[:, None] * sin_p) ** 2
        root = np.sqrt(np.maximum(1.0 - perp2, 0.0))
        inside = ~outside[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            # inside: the exit along + root, written (1 - d^2) / (root - along) when along < 0
            # (no cancellation near the surface); outside: the whole chord 2 root if ahead
            exit_ = np.where(along >= 0, along + root, (1.0 - d[:, None] ** 2) / (root - along))
        chord = np.where(inside, np.where(np.isfinite(exit_), np.maximum(exit_, 0.0), 0.0),
                         np.where((along > 0) & (perp2 < 1.0), 2.0 * root, 0.0))
        # the half-width phi_m of the arc above the horizon: n.w = cos psi cos theta +
        # sin psi sin theta cos phi > 0  <=>  cos phi > -cot psi cot theta
        num = -cos_p * cos_theta[:, None]
        den = sin_p * sin_t[:, None]
        ratio = np.divide(num, den, out=np.where(num < 0, -2.0, 2.0), where=den > 0)
        phi_m = np.arccos(np.clip(ratio, -1.0, 1.0))
        if weighting == "cosine":   # (1 / pi) int cos(angle to n) dphi over |phi| < phi_m
            ring = (2.0 / np.pi) * (phi_m * cos_p * cos_theta[:, None] + den * np.sin(phi_m))
        else:                       # (1 / 2 pi) int dphi over |phi| < phi_m
            ring = phi_m / np.pi
        cols = slice(p * count, (p + 1) * count)
        L[:, cols] = chord
        W[:, cols] = (half[:, None] * (np.sin(t) * wt)[None, :]) * np.maximum(ring, 0.0) * sin_p
    W[outside, 2 * count:] = 0.0
    L[outside, 2 * count:] = 0.0
    return L, W


def _absorbed(s: float, L: np.ndarray) -> np.ndarray:
    """1 - exp(-s L): the probability that the segment holds a leaf (s = inf: opaque)."""
    if math.isinf(s):
        return (L > 0).astype(np.float64)
    return -np.expm1(-s * L)


def sphere_transmittance(points, normals, sphere, *, extinction: float, weighting: str = "cosine",
                         quadrature: int = DEFAULT_QUADRATURE) -> np.ndarray:
    r"""Expected visibility past a sphere of absorbing medium, by direct quadrature.

    Parameters
    ----------
    points : (n, 3) float
        Points, inside or outside the sphere, finite.
    normals : (n, 3) float
        Their normals (renormalized; zero vectors are an error).
    sphere : Sphere
        The medium's sphere.
    extinction : float, keyword-only
        sigma, per unit length, >= 0; ``inf`` is an opaque sphere.
    weighting : {"cosine", "uniform"}, keyword-only
        The hemisphere weight (module docstring).
    quadrature : int, keyword-only
        Gauss-Legendre nodes per piece (two pieces outside the sphere, four inside), at most
        :data:`MAX_QUADRATURE`.

    Returns
    -------
    (n,) float64
        V in [0, 1]; exactly 1 where sigma = 0 or the sphere lies below the horizon.

    Notes
    -----
    .. math::

        V = 1 - \int_{\Omega} w(\omega) \left(1 - e^{-\sigma L(\omega)}\right) d\omega

    over the hemisphere, :math:`L` the chord of the ray in the sphere (from the point to the
    exit when the point is inside): the integral over :math:`\psi` (angle from the direction
    to the centre) of the closed-form azimuthal
    weight of the arc above the horizon, split at its kinks (module docstring and
    ``docs/trees.md``). With the default 16 nodes per piece the error is below 1e-6 (measured
    against 512 nodes; ``tests/test_occluders.py``). This is the one implementation of the
    porous sphere: :func:`vobscure.trees.occluder_visibility` (``model="porous"``) and the
    table of :func:`poisson_visibility` are built on it.

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3 (the Poisson argument of Eq. 6, whose expectation this evaluates).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 2.0)
    >>> V = sphere_transmittance([[0, 0, 0], [0, 5, 0]], [[0, 1, 0], [0, -1, 0]], s, extinction=0.5)
    >>> bool(abs(V[0] - np.exp(-0.5 * 2.0)) < 1e-9)        # every chord from the centre is R
    True
    >>> V1 = sphere_transmittance([0, 5, 0], [0, -1, 0], s, extinction=np.inf)
    >>> round(float(V1[0]), 6) == round(1 - (2 / 5) ** 2, 6)   # opaque: 1 - (R/d)^2 cos(theta)
    True
    """
    if not isinstance(sphere, Sphere):
        raise ValueError(f"sphere must be a vobscure.trees.Sphere, got {type(sphere).__name__}")
    weighting = check_choice(weighting, "weighting", WEIGHTINGS)
    sigma = check_positive(extinction, "extinction", allow_inf=True, allow_zero=True)
    count = check_quadrature(quadrature, "quadrature")
    x = as_points(points, "points")
    n = as_unit_vectors(normals, "normals", count=x.shape[0])
    D = sphere.center - x
    dist = np.sqrt(np.einsum("ij,ij->i", D, D))
    cos_theta = np.divide(np.einsum("ij,ij->i", n, D), dist, out=np.ones_like(dist), where=dist > 0)
    V = np.ones(x.shape[0])
    if sigma == 0 or x.shape[0] == 0:
        return V
    s = sigma * sphere.radius                            # the optical depth of a radius
    block = max(1, _QUADRATURE_CHUNK * DEFAULT_QUADRATURE // count)  # the temporaries' size whatever count
    for start in range(0, x.shape[0], block):
        sl = slice(start, start + block)
        L, W = _sphere_nodes(dist[sl] / sphere.radius, cos_theta[sl], weighting, count)
        V[sl] -= np.einsum("ij,ij->i", W, _absorbed(s, L))  # V = 1 - int w (1 - exp(-sigma L))
    return np.clip(V, 0.0, 1.0)


#: Points per block of the direct quadrature with the default nodes (its temporaries: about
#: ten (block, 4 quadrature) float64 arrays, 5 MB; the block shrinks as the nodes grow).
_QUADRATURE_CHUNK = 1024


# ----------------------------------------------------------------------------- the table
def _table_coordinate(r2: np.ndarray) -> np.ndarray:
    """The table's radial coordinate a in [0, 2] (TABLE_RADIAL) of r2 = (|x - c| / R)^2:
    ``1 - (1 - rho)^(1/3)`` inside, ``1 + sqrt(1 - 1 / rho^2)`` (1 + cos(alpha)) outside;
    branch-free, both sides computed for every point."""
    rho = np.sqrt(r2)
    a_in = np.subtract(1.0, rho)
    np.maximum(a_in, 0.0, out=a_in)
    np.cbrt(a_in, out=a_in)
    np.subtract(1.0, a_in, out=a_in)
    with np.errstate(divide="ignore"):
        a_out = np.divide(1.0, r2)
    np.subtract(1.0, a_out, out=a_out)
    np.maximum(a_out, 0.0, out=a_out)
    np.sqrt(a_out, out=a_out)
    a_out += 1.0
    return np.where(rho <= 1.0, a_in, a_out)


def _angular_coordinate(u: np.ndarray) -> np.ndarray:
    """The table's angular coordinate v = sign(u) (1 - sqrt(1 - |u|)) in [-1, 1] of u in
    [-1, 1] (TABLE_ANGULAR): near u = +-1 it is proportional to the angle between the normal
    and the radial direction, in which V is smooth (on the surface the uniform weighting's V
    is linear in that angle, so it has a square-root singularity in u)."""
    v = np.abs(u)
    np.subtract(1.0, v, out=v)
    np.sqrt(v, out=v)
    np.subtract(1.0, v, out=v)
    return np.copysign(v, u, out=v)


@lru_cache(maxsize=2)
def _table(weighting: str) -> tuple[np.ndarray, np.ndarray]:
    """Chords and weights at the table's nodes: (N_a * N_u, 4 TABLE_QUADRATURE) each.

    Node (i, j) is rho_i (a_i = i / TABLE_RADIAL) and u_j = -1 + 2 j / TABLE_ANGULAR. Inside
    (and on) the sphere every direction meets it, so the weights are scaled to sum exactly
    to 1 (the hemisphere's total weight): at the centre, where every chord is R, the table
    then gives exp(-sigma R) to rounding. The node at infinity (a = 2) has no weight.
    """
    a = np.arange(2 * TABLE_RADIAL + 1) / TABLE_RADIAL
    v = np.linspace(-1.0, 1.0, TABLE_ANGULAR + 1)
    u = np.copysign(1.0 - (1.0 - np.abs(v)) ** 2, v)         # the inverse of _angular_coordinate
    rho = np.where(a <= 1.0, 1.0 - (1.0 - a) ** 3, 0.0)
    out = a > 1.0
    cos_alpha = a[out] - 1.0
    with np.errstate(divide="ignore"):
        rho[out] = 1.0 / np.sqrt((1.0 - cos_alpha) * (1.0 + cos_alpha))
    finite = np.isfinite(rho)
    R, U = np.meshgrid(rho[finite], u, indexing="ij")
    L_f, W_f = _sphere_nodes(R.ravel(), -U.ravel(), weighting, TABLE_QUADRATURE)
    inner = R.ravel() <= 1.0
    W_f[inner] /= W_f[inner].sum(axis=1, keepdims=True)
    L = np.zeros((len(a) * len(u), L_f.shape[1]))
    W = np.zeros_like(L)
    L[: L_f.shape[0]] = L_f                           # the finite rho come first (a increasing)
    W[: W_f.shape[0]] = W_f
    L.setflags(write=False)
    W.setflags(write=False)
    return L, W


#: How many sums of the table (one per sigma R and weighting, 67 kB each) stay cached.
GRID_CACHE = 64


@lru_cache(maxsize=GRID_CACHE)
def _occlusion_grid(s: float, weighting: str) -> np.ndarray:
    """The table at sigma R = s: the absorbed fraction at each node, flat (N_a * N_u,),
    read-only. Cached for the last :data:`GRID_CACHE` values of (s, weighting): a frame's
    pixels, a sweep's configurations and a benchmark's repeats share one sigma R."""
    L, W = _table(weighting)
    grid = np.zeros(L.shape[0])
    if s != 0:
        for start in range(0, L.shape[0], _GRID_BLOCK):    # blocks: the temporaries stay small
            sl = slice(start, start + _GRID_BLOCK)
            grid[sl] = np.einsum("ij,ij->i", W[sl], _absorbed(s, L[sl]))
    grid.setflags(write=False)
    return grid


#: Table rows summed at once by ``_occlusion_grid`` (temporaries of 1024 x 96 float64, 0.8 MB).
_GRID_BLOCK = 1024


def _interpolate(grid: np.ndarray, x: np.ndarray, m: np.ndarray, r2: np.ndarray, mm: np.ndarray,
                 opaque: bool = False) -> np.ndarray:
    """1 - bilinear interpolation of ``grid`` at unit-frame points ``x`` with normals ``m``
    (any non-zero length) and their squared lengths ``r2``, ``mm``; (k,) float64.
    ``opaque``: the grid is sigma = inf's, whose V jumps at the surface from 0 (every ray
    from inside is blocked) to the fraction of the hemisphere outside the tangent plane;
    points strictly inside get their exact 0."""
    mx = np.einsum("ij,ij->i", m, x)
    den = mm * r2
    np.sqrt(den, out=den)
    np.maximum(den, _TINY, out=den)
    u = np.divide(mx, den, out=mx)              # at the centre (mx = 0) any u: every node is alike
    fa = _table_coordinate(r2)
    fa *= TABLE_RADIAL
    np.clip(u, -1.0, 1.0, out=u)
    fu = _angular_coordinate(u)
    fu += 1.0
    fu *= 0.5 * TABLE_ANGULAR
    i = fa.astype(np.intp)
    np.minimum(i, 2 * TABLE_RADIAL - 1, out=i)
    j = fu.astype(np.intp)
    np.minimum(j, TABLE_ANGULAR - 1, out=j)
    ta = fa - i
    tu = fu - j
    k = i * (TABLE_ANGULAR + 1)
    k += j
    g00, g01 = grid.take(k), grid.take(k + 1)
    k += TABLE_ANGULAR + 1
    g10, g11 = grid.take(k), grid.take(k + 1)
    g01 -= g00
    g01 *= tu
    g01 += g00                                             # the row a_i at u
    g11 -= g10
    g11 *= tu
    g11 += g10                                             # the row a_(i+1) at u
    g11 -= g01
    g11 *= ta
    g11 += g01                                             # bilinear: the absorbed fraction
    occluded = g11
    V = np.subtract(1.0, occluded, out=occluded)
    if opaque:
        V[r2 < 1.0] = 0.0
    return V


# ----------------------------------------------------------------------------- public API
def _check_shell(shell):
    if not isinstance(shell, (Sphere, Ellipsoid, MultiShell)):
        raise ValueError(f"shell must be a Sphere, an Ellipsoid or a MultiShell, got {type(shell).__name__}")
    return shell


def _as_extinctions(value, shell) -> np.ndarray:
    """One sigma per shell (a MultiShell may take one per shell), >= 0, inf allowed."""
    count = len(shell) if isinstance(shell, MultiShell) else 1
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return np.full(count, check_positive(value, "extinction", allow_inf=True, allow_zero=True))
    arr = as_array(value, "extinction", finite=False)
    if arr.ndim == 0:
        return np.full(count, check_positive(float(arr), "extinction", allow_inf=True, allow_zero=True))
    if arr.shape != (count,):
        raise ValueError(f"extinction must be one number or one per shell ({count}), got shape {arr.shape}")
    if np.any(np.isnan(arr)) or np.any(arr < 0):
        raise ValueError(f"extinction must be >= 0 (inf allowed) for every shell, got {arr.tolist()}")
    return arr


def extinction(n_leaves: float, leaf_area: float, shell) -> float:
    r"""sigma = n A / 2: leaves crossed per unit length in a uniform cloud of random leaves.

    Parameters
    ----------
    n_leaves : float
        Number of leaves (expected number) in the shell, > 0.
    leaf_area : float
        Mean one-sided area A of one flat leaf, > 0, world units squared.
    shell : Sphere, Ellipsoid or MultiShell
        The volume the leaves fill uniformly; a MultiShell's volume is the sum of its
        shells' (overlaps counted twice), the same sigma for every shell.

    Returns
    -------
    float
        :math:`\sigma = (n_{leaves} / \text{volume}) \, A / 2`, per unit length.

    Notes
    -----
    A flat leaf of area :math:`A`, oriented uniformly at random, casts along a fixed direction
    a shadow of mean area :math:`A / 2` (the mean of :math:`|\cos|` over the sphere is 1/2;
    ``docs/trees.md``). A segment of length :math:`L` is then met by a Poisson number of
    leaves with mean :math:`n (A / 2) L`: the leaves whose centres lie in the swept volume.

    References
    ----------
    Hegeman et al. 2006, Sec. 3 (the Poisson argument of Eq. 6). Ross 1981, "The radiation
    regime and architecture of plant stands" (the G-function, :math:`G = 1/2` for a spherical
    leaf angle distribution).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> round(extinction(1000, 0.01, s), 6)          # 1000 / (4 pi / 3) * 0.01 / 2
    1.193662
    """
    _check_shell(shell)
    n_leaves = check_positive(n_leaves, "n_leaves")
    A = check_positive(leaf_area, "leaf_area")
    n = n_leaves / shell.volume                                   # leaves per unit volume
    return n * A / 2.0                                            # sigma = n A / 2 (mean shadow A / 2)


def _unit_frame(shell, P: np.ndarray, N: np.ndarray):
    """Points x and normals m in the shell's unit frame (normals by the inverse transpose,
    not renormalized) with |x|^2 and |m|^2, float64; the checks of finiteness and of zero
    normals, done on the (k,) squared lengths (a NaN or inf coordinate makes them non-finite)."""
    P = np.asarray(P, dtype=np.float64)
    N = np.asarray(N, dtype=np.float64)
    if isinstance(shell, Sphere):
        x = P - shell.center
        x *= 1.0 / shell.radius
        m = N
    else:
        A = shell.rotation / shell.radii          # x' = diag(radii)^-1 Q^T (x - c), as a row product
        x = (P - shell.center) @ A
        m = N @ (shell.rotation * shell.radii)
    r2 = np.einsum("ij,ij->i", x, x)
    if not np.all(np.isfinite(r2)):
        bad = int(np.count_nonzero(~np.isfinite(P)))
        if bad:
            raise ValueError(f"points must be finite; they hold {bad} NaN or inf value(s)")
        raise ValueError("points must be finite and not so far from the shell that their squared distance "
                         "overflows")
    mm = np.einsum("ij,ij->i", m, m)
    check_normal_lengths(mm, N)
    return x, m, r2, mm


def poisson_visibility(points, normals, shell, *, extinction: float, weighting: str = "cosine",
                       chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    r"""Expected sky visibility in and around a Poisson leaf cloud filling a shell.

    Parameters
    ----------
    points : (n, 3) float
        Shading points x, world units, finite, inside or outside the shell (leaves of the
        crown, the ground under it). A single (3,) point is accepted.
    normals : (n, 3) float
        Their normals (any non-zero length).
    shell : Sphere, Ellipsoid or MultiShell
        The volume the leaves fill uniformly. With a MultiShell each point uses only the shell
        with the closest centre (Hegeman 2006, Sec. 5).
    extinction : float or (k,) float, keyword-only
        sigma, leaves crossed per unit length (:func:`extinction`: ``n A / 2``), >= 0;
        ``inf`` is an opaque shell. A MultiShell takes one value or one per shell.
    weighting : {"cosine", "uniform"}, keyword-only
        ``"cosine"``: (1/pi) int exp(-sigma L) cos, the ambient occlusion k_A;
        ``"uniform"``: (1 / 2 pi) int exp(-sigma L), the hemisphere average.
    chunk : int, keyword-only
        Points evaluated at once; the memory beyond the output is O(chunk).

    Returns
    -------
    (n,) float32 or float64
        V in [0, 1]; float32 when ``points`` and ``normals`` are both float32 (computed in
        float64), float64 otherwise. Exactly 1 where sigma = 0.

    Raises
    ------
    ValueError
        Bad shapes, NaN/inf in ``points`` or ``normals``, a zero normal, a negative or NaN
        ``extinction`` (or the wrong number of them), an unknown ``weighting``, or a
        ``shell`` of another type.

    Notes
    -----
    In the shell's unit frame (:math:`x' = (x - c) / R` for a sphere) :math:`V` depends on
    three numbers only: :math:`\rho = \lVert x' \rVert`, :math:`u = n \cdot x' / \lVert x'
    \rVert` (the cosine of the angle between the normal and the direction away from the
    centre) and :math:`s = \sigma R`. The table holds, at (2 :data:`TABLE_RADIAL` + 1) x
    (:data:`TABLE_ANGULAR` + 1) nodes in :math:`(\rho, u)`, the chords
    and weights of the direct quadrature of :func:`sphere_transmittance`
    (:data:`TABLE_QUADRATURE` nodes per piece), computed once per process and weighting
    (0.15-0.25 s measured); each call sums them for its own :math:`s`, so the table is exact
    in :math:`s`, and interpolates bilinearly in :math:`(\rho, u)`. Its error against the
    direct quadrature is below :data:`TABLE_ERROR` for :math:`s` up to
    :data:`TABLE_SIGMA_R_MAX` and for :math:`s = \infty` (measured, in ``docs/trees.md``). At
    the centre, :math:`V = e^{-\sigma R}` for both weightings to rounding.

    **Ellipsoids** are mapped to the unit sphere by Hegeman's affine map (points directly,
    normals by the inverse transpose, Sec. 3) and use the sphere's table with
    :math:`s = \sigma R_{eq}`, :math:`R_{eq} = (a b c)^{1/3}` the volume-equivalent radius:
    exact for a sphere, an approximation otherwise (a chord's world length is not its
    unit-frame length times :math:`R_{eq}`). ``docs/trees.md`` measures it against :func:`poisson_quadrature` in the
    true ellipsoid.

    References
    ----------
    Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
    I3D 2006, Sec. 3 (the Poisson leaf cloud; the affine map of an ellipsoid), Sec. 5
    (several shells). Ross 1981 (G = 1/2).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> V = poisson_visibility([[0, 0, 0], [0, 0.5, 0]], [[0, 1, 0], [0, 1, 0]], s, extinction=2.0)
    >>> bool(abs(V[0] - np.exp(-2.0)) < 1e-12)            # every chord from the centre is R
    True
    >>> direct = sphere_transmittance([0, 0.5, 0], [0, 1, 0], s, extinction=2.0)
    >>> bool(abs(V[1] - direct[0]) < TABLE_ERROR)
    True
    """
    _check_shell(shell)
    weighting = check_choice(weighting, "weighting", WEIGHTINGS)
    chunk = check_int(chunk, "chunk")
    sigmas = _as_extinctions(extinction, shell)
    P = as_raw_points(points, "points")
    N = as_raw_points(normals, "normals")
    if N.shape[0] != P.shape[0]:
        raise ValueError(f"normals must have one row per point ({P.shape[0]}), got {N.shape[0]}")
    shells = shell.shells if isinstance(shell, MultiShell) else (shell,)
    grids = [_occlusion_grid(sig * s.equivalent_radius, weighting) for sig, s in zip(sigmas, shells)]
    opaque = [bool(np.isinf(sig)) for sig in sigmas]
    out = np.empty(P.shape[0], dtype=out_dtype(P, N))
    for start in range(0, P.shape[0], chunk):
        sl = slice(start, min(start + chunk, P.shape[0]))
        if len(shells) == 1:
            out[sl] = _interpolate(grids[0], *_unit_frame(shells[0], P[sl], N[sl]), opaque[0])
            continue
        Pc = np.asarray(P[sl], dtype=np.float64)
        if not np.all(np.isfinite(Pc)):
            raise ValueError(f"points must be finite; they hold {int(np.count_nonzero(~np.isfinite(Pc)))} NaN "
                             f"or inf value(s)")
        which = shell.assign(Pc)                                 # Hegeman 2006, Sec. 5: closest centre
        V = np.empty(Pc.shape[0])
        for i, s in enumerate(shells):
            sel = which == i
            if np.any(sel):
                V[sel] = _interpolate(grids[i], *_unit_frame(s, Pc[sel], N[sl][sel]), opaque[i])
        out[sl] = V
    np.clip(out, 0.0, 1.0, out=out)
    return out


def poisson_quadrature(points, normals, shell, *, extinction: float, weighting: str = "cosine",
                       nodes: int = 96) -> np.ndarray:
    r"""The expected visibility by brute-force quadrature over the hemisphere, for any shell.

    The reference that :func:`poisson_visibility`'s affine map is measured against in an
    ellipsoid (and an independent check of the sphere's one-dimensional quadrature): slow,
    ``2 nodes^2`` chords per point.

    Parameters
    ----------
    points, normals : (n, 3) float
        As in :func:`poisson_visibility`.
    shell : Sphere or Ellipsoid
        The medium's shell (its true chords, :func:`vobscure.trees.chord_length`).
    extinction : float, keyword-only
        sigma, >= 0 (``inf``: opaque).
    weighting : {"cosine", "uniform"}, keyword-only
    nodes : int, keyword-only
        Gauss-Legendre nodes in the cosine of the polar angle about the normal; twice as many
        midpoint nodes in the azimuth; at most :data:`MAX_QUADRATURE`.

    Returns
    -------
    (n,) float64
        V in [0, 1].

    Notes
    -----
    :math:`V = \sum_{ij} w_{ij} \, e^{-\sigma L(x, \omega_{ij})}` over a product rule in
    :math:`(\mu, \phi)` about the normal: :math:`\mu` the cosine of the polar angle by
    Gauss-Legendre on :math:`[0, 1]` (weight :math:`\mu / \pi` per unit :math:`\mu` and
    :math:`\phi` for the cosine weighting, :math:`1 / (2\pi)` for the uniform one),
    :math:`\phi` by the midpoint rule (exact for the trigonometric polynomials of the azimuth up to degree
    ``2 nodes - 1``). The chord has kinks where the rays graze the shell, so the error falls
    only as a power of ``nodes``: with 96 nodes it is below 1e-4 against the sphere's
    one-dimensional quadrature on the test points (``tests/test_poisson.py``).

    Examples
    --------
    >>> s = Sphere((0, 0, 0), 1.0)
    >>> V = poisson_quadrature([[0.0, 0.3, 0.0]], [[0, 1.0, 0]], s, extinction=1.5, nodes=48)
    >>> bool(abs(V[0] - sphere_transmittance([0, 0.3, 0], [0, 1, 0], s, extinction=1.5)[0]) < 1e-3)
    True
    """
    if not isinstance(shell, (Sphere, Ellipsoid)):
        raise ValueError(f"shell must be a Sphere or an Ellipsoid, got {type(shell).__name__}")
    weighting = check_choice(weighting, "weighting", WEIGHTINGS)
    sigma = check_positive(extinction, "extinction", allow_inf=True, allow_zero=True)
    k = check_quadrature(nodes, "nodes")
    x = as_points(points, "points")
    n = as_unit_vectors(normals, "normals", count=x.shape[0])
    z, wz = np.polynomial.legendre.leggauss(k)
    mu, w_mu = 0.5 * (z + 1.0), 0.5 * wz                          # Gauss-Legendre on [0, 1]
    phi = 2.0 * np.pi * (np.arange(2 * k) + 0.5) / (2 * k)
    w_phi = 2.0 * np.pi / (2 * k)
    weight = (mu / np.pi if weighting == "cosine" else np.full(k, 1.0 / (2.0 * np.pi))) * w_mu * w_phi
    st = np.sqrt(1.0 - mu * mu)
    local = np.stack([np.outer(st, np.cos(phi)).ravel(), np.outer(st, np.sin(phi)).ravel(),
                      np.repeat(mu, 2 * k)], axis=1)              # (k * 2k, 3), z = the normal
    wts = np.repeat(weight, 2 * k)
    V = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        nz = n[i]
        helper = np.array([1.0, 0.0, 0.0]) if abs(nz[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        tx = np.cross(nz, helper)
        tx /= np.linalg.norm(tx)
        ty = np.cross(nz, tx)
        dirs = local @ np.stack([tx, ty, nz])
        L = shell.chord_length(np.broadcast_to(x[i], dirs.shape), dirs)
        V[i] = float(np.dot(wts, 1.0 - _absorbed(sigma, L)))
    return np.clip(V, 0.0, 1.0)
