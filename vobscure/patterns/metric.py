"""The quality metric of a pattern and the closed-form volumes it is measured against.

:func:`quality` is the RMS error of a pattern's VO estimate over random planes and creases
whose exact VO is known in closed form: the volume of a cap (:func:`cap_volume`, Hegeman et al.
2006, Eq. 4) and of the ball on the open side of two planes (:func:`crease_volume`).

References
----------
Loos, B. J. and Sloan, P.-P. 2010. Volumetric Obscurance. I3D 2010, Sec. 4.1, 4.5.
Hegeman, K., Premoze, S., Ashikhmin, M. and Drettakis, G. 2006. Approximate Ambient
Occlusion for Trees. I3D 2006, Eq. 4 (the volume of a spherical cap).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .._validate import as_rng, check_choice, check_int
from ..estimate import Estimate
from ..sampling import square_to_uniform_hemisphere
from ._pattern import VOLUME, SamplePattern, int_seed

__all__ = ["quality", "squared_errors", "cap_volume", "crease_volume", "QUALITY_TRIALS", "QUALITY_SEED",
           "QUALITY_VERSION", "QUALITY_NOTES", "FAMILIES"]

#: Default number of random configurations and seed of :func:`quality`.
QUALITY_TRIALS = 16384
QUALITY_SEED = 0
#: Version of :func:`quality`, recorded with the tables' qualities; ``QUALITY_NOTES`` says what
#: each version measures. The versions differ on ball patterns with a sample at the centre
#: only; points and weights do not depend on the metric (``GENERATOR_VERSION`` is separate).
#: A table that records another version (a table without one: version 1) is re-evaluated by
#: ``build_tables`` for the entries it keeps, and by ``python -m vobscure.patterns rescore``.
QUALITY_VERSION = 2
QUALITY_NOTES = {
    1: "a ball sample at the centre depth-tested like any other",
    2: "a ball sample at the centre counts half occupied by a plane through the centre (t1 == 0), "
       "as vo_point counts it (docs/screenspace.md, 'The centre sample')",
}
#: The configuration families of :func:`quality`.
FAMILIES = ("mixed", "cap", "crease")


def cap_volume(h):
    r"""Volume of a cap of height ``h`` cut from the unit ball.

    Parameters
    ----------
    h : float or array
        Cap height in [0, 2] (clipped).

    Returns
    -------
    float64 array
        :math:`\pi h^2 (3 - h) / 3` (Hegeman et al. 2006, Eq. 4, with :math:`R = 1`).

    Examples
    --------
    >>> round(float(cap_volume(1.0) / (4 * np.pi / 3)), 12)   # a half ball
    0.5
    """
    h = np.clip(np.asarray(h, dtype=np.float64), 0.0, 2.0)
    return np.pi * h * h * (3.0 - h) / 3.0           # V_cap, Hegeman 2006, Eq. 4 (R = 1)


def _halfspace_volume(t):
    """Volume of {x in unit ball : n . x <= t} for a unit n."""
    return VOLUME[3] - cap_volume(1.0 - np.asarray(t, dtype=np.float64))


def _line_piece(t, d, k):
    """G(t) = psi(t) - I(t): the fan integral of F(rho) = (2/3)(1 - (1 - rho^2)^(3/2)) over the
    line at distance d from the origin, up to the factor (2/3) sign(a); see crease_volume."""
    s = np.sqrt(np.maximum(k * k - t * t, 0.0))
    asn = np.arcsin(np.clip(np.divide(t, k, out=np.zeros_like(t), where=k > 0), -1.0, 1.0))
    psi = np.arctan2(t, d)
    I = np.arctan2(t, d * s) - d * asn - 0.5 * d * (t * s + k * k * asn)
    return psi - I


def crease_volume(n1, t1, n2, t2):
    r"""Volume of the unit ball on the open side of two planes, :math:`\{n_1 \cdot x \le t_1\}` and
    :math:`\{n_2 \cdot x \le t_2\}`.

    Exact (closed form), vectorized over leading dimensions.

    Parameters
    ----------
    n1, n2 : (..., 3) float
        Plane normals (normalized here).
    t1, t2 : (...) float
        Signed distances of the planes from the centre.

    Returns
    -------
    (...) float64

    Notes
    -----
    Let :math:`e` be the direction of the planes' common line. Along :math:`e` the region is a
    prism over a 2-D wedge :math:`W = \{u_1 \cdot x \le a_1\} \cap \{u_2 \cdot x \le a_2\}`
    (:math:`u_i`: the normals in the plane normal to :math:`e`, :math:`a_i = t_i`), so its
    volume is the integral over :math:`W` within the unit disk of the chord length
    :math:`2\sqrt{1 - \lVert x \rVert^2}`. With

    .. math::

        F(\rho) = \int_0^\rho 2 \sqrt{1 - r^2} \, r \, dr
                = \tfrac{2}{3} \left(1 - (1 - \rho^2)^{3/2}\right),

    Green's theorem turns that area integral into the boundary integral of
    :math:`F(\rho) \, d\theta`: arcs of the unit circle give :math:`\frac{2}{3} d\theta`; the
    piece of line :math:`i` at distance :math:`d = |a_i|` gives
    :math:`\frac{2}{3} \operatorname{sign}(a_i) [\psi - I]`, :math:`\psi = \arctan(t / d)`,
    with :math:`t` the coordinate along the line, :math:`k^2 = 1 - d^2` and

    .. math::

        I = \arctan\frac{t}{d \sqrt{k^2 - t^2}} - d \arcsin\frac{t}{k}
            - \frac{d}{2} \left(t \sqrt{k^2 - t^2} + k^2 \arcsin\frac{t}{k}\right),

    the antiderivative of :math:`d (k^2 - t^2)^{3/2} / (d^2 + t^2)`. Parallel planes reduce
    to caps and slabs. The tests check it against Monte Carlo and the split identity
    :math:`V(n_1, t_1, n_2, t_2) + V(n_1, t_1, -n_2, -t_2) = V_{ball} - V_{cap}(1 - t_1)`.

    Examples
    --------
    >>> v = crease_volume([0, 0, 1], 0.0, [1, 0, 0], 0.0)     # a quarter of the ball
    >>> round(float(v / (4 * np.pi / 3)), 12)
    0.25
    """
    n1 = np.asarray(n1, dtype=np.float64)
    n2 = np.asarray(n2, dtype=np.float64)
    n1 = n1 / np.linalg.norm(n1, axis=-1, keepdims=True)
    n2 = n2 / np.linalg.norm(n2, axis=-1, keepdims=True)
    shape = np.broadcast_shapes(n1.shape[:-1], n2.shape[:-1], np.shape(t1), np.shape(t2))
    n1 = np.broadcast_to(n1, shape + (3,)).reshape(-1, 3)
    n2 = np.broadcast_to(n2, shape + (3,)).reshape(-1, 3)
    a1 = np.broadcast_to(np.asarray(t1, dtype=np.float64), shape).ravel()
    a2 = np.broadcast_to(np.asarray(t2, dtype=np.float64), shape).ravel()

    e = np.cross(n1, n2)
    sin = np.linalg.norm(e, axis=1)
    parallel = sin < 1e-9
    # the 2-D frame normal to e: b1 = n1, b2 = e x n1 / |e|
    b2 = np.cross(e, n1) / np.where(parallel, 1.0, sin)[:, None]
    u = np.stack([np.stack([np.ones_like(a1), np.zeros_like(a1)], axis=1),
                  np.stack([np.sum(n2 * n1, axis=1), np.sum(n2 * b2, axis=1)], axis=1)])  # (2, m, 2)
    a = np.stack([a1, a2])                                                                 # (2, m)

    # arcs: the allowed angles of the unit circle, 2 pi minus the union of the two excluded
    # arcs |theta - alpha_i| < beta_i, beta_i = acos(a_i)
    alpha = np.arctan2(u[..., 1], u[..., 0])
    beta = np.arccos(np.clip(a, -1.0, 1.0))
    delta = np.abs((alpha[0] - alpha[1] + np.pi) % (2.0 * np.pi) - np.pi)          # in [0, pi]
    near = np.maximum(0.0, np.minimum(beta[0], delta + beta[1]) - np.maximum(-beta[0], delta - beta[1]))
    far = np.maximum(0.0, np.minimum(beta[0], delta - 2.0 * np.pi + beta[1])
                     - np.maximum(-beta[0], delta - 2.0 * np.pi - beta[1]))
    arc = 2.0 * np.pi - 2.0 * beta[0] - 2.0 * beta[1] + near + far
    volume = (2.0 / 3.0) * arc

    # lines: the piece of line i inside the disk and on the open side of the other line
    for i, j in ((0, 1), (1, 0)):
        d = np.abs(a[i])
        inside = d < 1.0
        k = np.sqrt(np.maximum(0.0, 1.0 - d * d))
        tau = np.stack([-u[i, :, 1], u[i, :, 0]], axis=1)        # direction, interior on the left
        c = np.sum(u[j] * tau, axis=1)
        rhs = a[j] - a[i] * np.sum(u[j] * u[i], axis=1)
        lo, hi = -k, k.copy()
        bound = np.divide(rhs, c, out=np.zeros_like(c), where=c != 0)
        hi = np.where(c > 0, np.minimum(hi, bound), hi)
        lo = np.where(c < 0, np.maximum(lo, bound), lo)
        empty = (c == 0) & (rhs < 0)
        ok = inside & ~empty & (hi > lo)
        piece = _line_piece(np.where(ok, hi, 0.0), d, k) - _line_piece(np.where(ok, lo, 0.0), d, k)
        volume = volume + np.where(ok, (2.0 / 3.0) * np.sign(a[i]) * piece, 0.0)

    if np.any(parallel):
        same = np.sum(n1 * n2, axis=1) > 0
        v_same = _halfspace_volume(np.minimum(a1, a2))
        # n2 = -n1: the slab -t2 <= n1 . x <= t1
        v_slab = np.maximum(0.0, _halfspace_volume(a1) - _halfspace_volume(np.minimum(-a2, a1)))
        volume = np.where(parallel, np.where(same, v_same, v_slab), volume)
    return np.clip(volume, 0.0, VOLUME[3]).reshape(shape)

def _hemisphere(rng: np.random.Generator, count: int) -> np.ndarray:
    """Uniform unit vectors with n_z > 0: normals of planes a depth buffer can hold."""
    u = np.stack([np.maximum(rng.random(count), 1e-12), rng.random(count)], axis=-1)
    return square_to_uniform_hemisphere(u)


@dataclass(frozen=True)
class _Configurations:
    """Random planes and creases with their exact VO, and one random orthogonal map per trial."""

    n1: np.ndarray      # (T, 3) normals, n_z > 0; occupied side n . x > t (behind the surface)
    t1: np.ndarray      # (T,)
    n2: np.ndarray      # (T, 3)
    t2: np.ndarray      # (T,)
    kind: np.ndarray    # (T,) 0 plane, 1 concave crease (union occupied), 2 convex (intersection)
    exact: np.ndarray   # (T,) exact VO: unoccupied fraction of the ball
    rot2: np.ndarray    # (T, 2, 2) random elements of O(2)
    rot3: np.ndarray    # (T, 3, 3) random elements of O(3)


def _configurations_from(rng: np.random.Generator, trials: int, family: str) -> _Configurations:
    T = trials
    if family == "mixed":
        kind = np.where(np.arange(T) < T // 2, 0, 1)
    else:
        kind = np.full(T, 0 if family == "cap" else 1)
    n1 = _hemisphere(rng, T)
    n2 = _hemisphere(rng, T)
    offset = rng.random(T)
    convex = rng.random(T) < 0.5
    crease = kind > 0
    kind = np.where(crease & convex, 2, kind)
    # planes: anywhere across the ball, t ~ U(-1, 1). Creases: the first plane through the
    # centre (the depth buffer's surface point P), the second at a distance t2 from P on the
    # side that keeps P on the visible surface: open side for a concave crease (t2 > 0),
    # occupied side for a convex edge (t2 < 0)
    t1 = np.where(crease, 0.0, 2.0 * offset - 1.0)
    t2 = np.where(convex, -offset, offset)
    vball = VOLUME[3]
    # occupied = {n . x > t}; a plane leaves the open volume V_ball - V_cap(h = 1 - t)
    exact = np.where(kind == 0, 1.0 - cap_volume(1.0 - t1) / vball, 0.0)      # Hegeman Eq. 4
    concave = kind == 1
    # concave: open = both open sides; convex: open = the complement of both occupied sides
    open_cc = crease_volume(n1, t1, n2, t2) / vball
    occ_cx = crease_volume(-n1, -t1, -n2, -t2) / vball
    exact = np.where(concave, open_cc, np.where(kind == 2, 1.0 - occ_cx, exact))
    phi = 2.0 * np.pi * rng.random(T)
    flip = np.where(rng.random(T) < 0.5, -1.0, 1.0)
    c, s = np.cos(phi), np.sin(phi)
    rot2 = np.stack([np.stack([c, -s * flip], axis=1), np.stack([s, c * flip], axis=1)], axis=1)
    q, r = np.linalg.qr(rng.normal(size=(T, 3, 3)))
    rot3 = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]      # Haar on O(3)
    for arr in (n1, t1, n2, t2, kind, exact, rot2, rot3):
        arr.flags.writeable = False
    return _Configurations(n1, t1, n2, t2, kind, exact, rot2, rot3)


@lru_cache(maxsize=8)
def _configurations(trials: int, seed: int, family: str) -> _Configurations:
    return _configurations_from(np.random.default_rng(seed), trials, family)


def _estimates(pattern: SamplePattern, cfg: _Configurations) -> np.ndarray:
    """The pattern's VO estimate for every configuration (T,)."""
    w = pattern.weights
    kind = cfg.kind[:, None]
    if pattern.dim == 3:
        # point sampling: the pattern turned by a random orthogonal map, each point occupied
        # or not
        x = np.einsum("tij,nj->tni", cfg.rot3, pattern.points)
        occ1 = (np.einsum("tni,ti->tn", x, cfg.n1) > cfg.t1[:, None]).astype(np.float64)
        occ2 = (np.einsum("tni,ti->tn", x, cfg.n2) > cfg.t2[:, None]).astype(np.float64)
        # The centre sample, as vo_point counts it (docs/screenspace.md, "The centre sample";
        # Loos & Sloan 2010, Sec. 4): a sample at the origin, when the first plane passes
        # through the centre (t1 == 0: every crease, where the centre is the depth buffer's
        # surface point), lies on that plane, so its test "behind the surface" compares the
        # surface with itself. It counts half occupied by that plane, the share of its small
        # Voronoi region behind it. The second plane then decides as for any sample: open
        # side at a concave crease (t2 > 0, max(1/2, 0)), occupied side at a convex edge
        # (t2 < 0, min(1/2, 1)), so the centre reads 1/2 on every crease.
        centre = np.all(pattern.points == 0.0, axis=1)
        if np.any(centre):
            on_plane = (cfg.t1 == 0.0)[:, None] & centre[None, :]
            occ1 = np.where(on_plane, 0.5, occ1)
        # occupancies in {0, 1/2, 1}: the union is the max, the intersection the min
        occ = np.where(kind == 0, occ1, np.where(kind == 1, np.maximum(occ1, occ2), np.minimum(occ1, occ2)))
        return (1.0 - occ) @ w
    # line sampling (Sec. 4.1): the pattern turned or reflected about the view axis; each
    # sample (x, y) stands for the chord [-z_s, z_s] and reads the surface height h(x, y);
    # occupied means behind the surface, z > h
    xy = np.einsum("tij,nj->tni", cfg.rot2, pattern.points)
    x, y = xy[..., 0], xy[..., 1]
    z_s = np.sqrt(np.maximum(0.0, 1.0 - x * x - y * y))

    def height(nv, t):
        return (t[:, None] - nv[:, 0:1] * x - nv[:, 1:2] * y) / nv[:, 2:3]

    h1, h2 = height(cfg.n1, cfg.t1), height(cfg.n2, cfg.t2)
    h = np.where(kind == 0, h1, np.where(kind == 1, np.minimum(h1, h2), np.maximum(h1, h2)))
    # Sec. 4.1: the unoccupied length max(min(z_s, d_r) + z_s, 0), over the chord's 2 z_s
    unocc = np.clip(h, -z_s, z_s) + z_s
    frac = np.divide(unocc, 2.0 * z_s, out=(h > 0).astype(np.float64), where=z_s > 0)
    return frac @ w

def squared_errors(pattern: SamplePattern, *, trials: int = QUALITY_TRIALS, seed=QUALITY_SEED,
                   family: str = "mixed") -> np.ndarray:
    r"""Squared errors of a pattern's VO estimate, configuration by configuration.

    Parameters
    ----------
    pattern, trials, seed, family
        As in :func:`quality`.

    Returns
    -------
    (trials,) float64
        :math:`(\text{estimate} - \text{exact})^2` per configuration; :func:`quality` is the
        root of their mean.

    Examples
    --------
    >>> from vobscure.patterns import disk
    >>> e2 = squared_errors(disk(9), trials=1000)
    >>> e2.shape, bool(np.all(e2 >= 0))
    ((1000,), True)
    """
    if not isinstance(pattern, SamplePattern):
        raise ValueError(f"pattern must be a SamplePattern, got {type(pattern).__name__}")
    trials = check_int(trials, "trials", minimum=2)
    check_choice(family, "family", FAMILIES)
    key = int_seed(seed)
    if key is None:
        cfg = _configurations_from(as_rng(seed), trials, family)
    else:
        cfg = _configurations(trials, key, family)
    return (_estimates(pattern, cfg) - cfg.exact) ** 2


def quality(pattern: SamplePattern, *, trials: int = QUALITY_TRIALS, seed=QUALITY_SEED,
            family: str = "mixed") -> Estimate:
    r"""RMS error of a pattern's VO estimate over random configurations with exact VO.

    Parameters
    ----------
    pattern : SamplePattern
        A disk pattern is measured with line sampling (each sample :math:`(x, y)` integrates
        the chord :math:`[-z_s, z_s]`, :math:`z_s = \sqrt{1 - x^2 - y^2}`, against a height
        field), a ball pattern with
        point sampling as ``vo_point`` does it, a sample at the centre included (Notes).
    trials : int, optional
        Number of random configurations (default :data:`QUALITY_TRIALS`).
    seed : int, numpy.random.Generator or None, optional
        The configurations and the per-trial rotations; the same int gives the same numbers.
    family : {"mixed", "cap", "crease"}, optional
        ``"cap"``: the ball cut by one plane at a uniform signed distance in (-1, 1) from the
        centre; ``"crease"``: two planes, the first through the centre, the second at a
        uniform distance in (0, 1) on the side that keeps the centre on the visible surface
        (a concave crease or a convex edge, half each); ``"mixed"`` (default): half of each.

    Returns
    -------
    Estimate
        ``value``: the RMS error :math:`\sqrt{\operatorname{mean}((\text{estimate} -
        \text{exact})^2)}`; ``stderr``: its standard error by the delta method,
        :math:`\operatorname{sd}((\text{estimate} - \text{exact})^2) / (2 \, \text{RMS}
        \sqrt{\text{trials}})`;
        ``samples``: trials.

    Notes
    -----
    Every plane has a normal uniform over the hemisphere :math:`n_z > 0` and is occupied on its
    far side :math:`n \cdot x > t` ("behind the surface" along the view axis :math:`z`), so that
    a depth buffer can hold every configuration. A crease's occupied set is the union (concave)
    or the intersection (convex) of the two half-spaces. Per trial the pattern is turned by a
    random element of O(2) about the view axis (disk) or of O(3) (ball), as the estimators
    randomize per pixel (Sec. 4.5). A ball sample is open when it is not occupied, except a
    sample exactly at the centre when the first plane passes through it (every crease: the
    centre is the depth buffer's surface point): its test would compare the surface with itself,
    so it counts half occupied by that plane, as ``vo_point`` counts it (docs/screenspace.md,
    "The centre sample"), and the second plane decides as for any sample; the centre alone then
    reads 1/2 on every crease. The exact VO: the cap volume (Hegeman et al. 2006, Eq. 4) and
    :func:`crease_volume`. The same ``trials`` and int ``seed`` give every pattern the same
    configurations, so differences between patterns are measured with common random numbers.

    Examples
    --------
    >>> from vobscure.patterns import disk
    >>> q = quality(disk(9), trials=2000)
    >>> bool(0 < q.value < 0.1), bool(q.stderr < q.value)
    (True, True)
    """
    err2 = squared_errors(pattern, trials=trials, seed=seed, family=family)
    trials = len(err2)
    mse = float(np.mean(err2))
    rms = math.sqrt(mse)
    se_mse = float(np.std(err2, ddof=1)) / math.sqrt(trials)
    stderr = se_mse / (2.0 * rms) if rms > 0 else 0.0
    return Estimate(np.float64(rms), np.float64(stderr), trials)
