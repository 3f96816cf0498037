"""Sample patterns for the screen-space estimators: disks (line/area sampling) and balls (points).

A :class:`SamplePattern` holds points in the unit disk or ball and one weight per point
(summing to 1). Weights follow Loos & Sloan 2010, footnote 5: a disk sample stands for its
Voronoi region of the disk, weighted by the sphere's z-extent over it (the integral of
2 sqrt(1 - x^2 - y^2) over the region); a ball sample for the volume of its region.
Regions are computed discretely on a grid with a KD-tree nearest-sample query.

Generators (``method=``), for the disk (:func:`disk`) and the ball (:func:`ball`):

``"electrostatic"``
    Loos & Sloan 2010, Sec. 4.5: 1/d^4 repulsion, a boundary charge optimized so that the
    forces push the particles toward the weighted centroids of their Voronoi regions,
    an adaptive step, tens of Poisson starts. ``docs/patterns.md`` maps the paper's
    sentences to the code.
``"lloyd"``
    Lloyd relaxation toward a centroidal Voronoi tessellation (unweighted, as in Lloyd 1982),
    a few Poisson starts, the lowest centroidal energy kept.
``"poisson"``
    Poisson-disk dart throwing with a shrinking radius.
``"sobol"``, ``"halton"``
    Scrambled quasi-Monte Carlo points (:mod:`scipy.stats.qmc`) mapped to the disk by the
    concentric map, to the ball by the polar volume-preserving map.
``"random"``
    Independent uniform points.
``"spiral"``
    A sunflower (Vogel) spiral on the disk; spherical-Fibonacci shells in the ball.
    Deterministic: ``seed`` is accepted and unused.

Every method has a point-symmetric variant (``symmetric=True``, the default): antipodal pairs,
plus the centre for odd n. The screen-space estimators rely on it: a point-symmetric pattern is
exact on a plane through the ball's centre. ``center=True`` forces a sample at the origin.

The default, ``method="best"``, is the best measured pattern: per count and variant, the table
entry with the lowest recorded quality (Lloyd or electrostatic at every count of the disk
tables; see ``docs/patterns_results.md``).

:func:`quality` measures any pattern with one metric (the RMS error of its VO estimate over
random planes and creases whose exact VO is known in closed form), and the defaults load from
precomputed tables in ``data/patterns/`` (``python -m vobscure.patterns build`` regenerates
them).

References
----------
Loos, B. J. and Sloan, P.-P. 2010. Volumetric Obscurance. I3D 2010, Sec. 4.5, footnote 5.
Hegeman, K., Premoze, S., Ashikhmin, M. and Drettakis, G. 2006. Approximate Ambient
Occlusion for Trees. I3D 2006, Eq. 4 (the volume of a spherical cap).
Lloyd, S. P. 1982. Least squares quantization in PCM. IEEE Trans. Inf. Theory 28(2).
Shirley, P. and Chiu, K. 1997. A low distortion map between disk and square. JGT 2(3).
Vogel, H. 1979. A better way to construct the sunflower head. Math. Biosci. 44.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import numbers
import sys
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from .._validate import as_rng, check_choice, check_int
from ..estimate import Estimate

__all__ = [
    "SamplePattern",
    "disk",
    "ball",
    "voronoi_weights",
    "quality",
    "cap_volume",
    "crease_volume",
    "best_method",
    "load_table",
    "build_tables",
    "METHODS",
    "TABLE_DIR",
]

#: Version of the generators; a table written by another version is not used.
GENERATOR_VERSION = 1
#: The generators, in the order tables and figures list them.
METHODS = ("electrostatic", "lloyd", "poisson", "sobol", "halton", "random", "spiral")
#: The default ``method`` of :func:`disk` and :func:`ball`: per count and variant, the table
#: entry with the lowest recorded quality (see :func:`best_method`).
BEST = "best"
#: What ``method="best"`` uses when no table holds the count: the paper's generator.
BEST_FALLBACK = "electrostatic"
#: Grid resolution of the discrete Voronoi regions that give the weights (Loos & Sloan
#: Sec. 4.5: "128^3 cells for the volume and 512^2 for the disk").
DISK_GRID = 512
BALL_GRID = 128
#: Coarser grids for the Voronoi regions inside the optimization loops (Lloyd, electrostatic),
#: where they are queried hundreds of times; the final weights use DISK_GRID / BALL_GRID.
#: Large n get a finer grid, at least OPTIMIZATION_CELLS cells per region.
OPTIMIZATION_GRID = {2: 128, 3: 32}
OPTIMIZATION_CELLS = 200

#: Parameters of the electrostatic generator (see :func:`_electrostatic` and docs/patterns.md).
ELECTROSTATIC = {
    "starts": 24,          # "tens of starting point sets generated using Poisson sampling"
    "steps": 1000,         # at most, per start (a start usually comes to rest in 200-400)
    "charge_every": 10,    # "periodically": steps between two boundary-charge updates
    "charge_gain": 2.0,    # q <- q exp(-gain g), g the radial mismatch to the centroids
    "charge_tol": 1e-3,    # |g| below which the charge counts as optimized
    "grow": 1.25,          # step factor after a step that decreased the error ...
    "shrink": 0.5,         # ... and after one that did not (the step is then not applied)
    "first_step": 0.1,     # first step, as a fraction of the mean spacing (vol / n)^(1/dim)
    "min_step": 1e-3,      # a step below this fraction of the spacing: the start is at rest
    "error": "energy",     # what a step must decrease: "energy" or "voronoi"
}
#: Parameters of Lloyd relaxation.
LLOYD = {"starts": 8, "iterations": 100}
#: Dart throwing: candidates rejected in a row before the exclusion radius shrinks, the
#: shrink factor, and the first radius as a fraction of the mean spacing.
POISSON = {"attempts": 100, "shrink": 0.95, "first_radius": 1.0}

#: Points farther than this from the origin are pulled back inside (relaxation steps).
R_MAX = 0.999
#: A pattern equals its point reflection when every reflected point is within this distance
#: of a point of the pattern with the same weight (relative tolerance).
SYMMETRY_ATOL = 1e-9
SYMMETRY_RTOL = 1e-9

#: Default number of random configurations and seed of :func:`quality`.
QUALITY_TRIALS = 16384
QUALITY_SEED = 0
#: Version of :func:`quality`, recorded with the tables' qualities. 1: a ball sample at the
#: centre was depth-tested like any other (and read open on every crease); 2: it counts half
#: occupied by a plane through the centre, as ``vo_point`` counts it (docs/screenspace.md,
#: "The centre sample"). Disk qualities are the same in both; points and weights do not depend
#: on it (:data:`GENERATOR_VERSION` does not change).
QUALITY_VERSION = 2
QUALITY_NOTES = {
    1: "a ball sample at the centre depth-tested like any other",
    2: "a ball sample at the centre counts half occupied by a plane through the centre (t1 == 0), "
       "as vo_point counts it (docs/screenspace.md, 'The centre sample')",
}
#: The configuration families of :func:`quality`.
FAMILIES = ("mixed", "cap", "crease")

#: Where the precomputed tables live: ``data/patterns/`` at the root of the repository. The
#: package is installed editable, so the repository root is the parent of the package folder;
#: when the folder does not exist (a plain install), every pattern is generated on first use.
# The tables live inside the package (so that a wheel carries them: package data) and are
# reached from the repository's documented path data/patterns/ through a symbolic link.
TABLE_DIR = Path(__file__).resolve().parent / "tables"
#: Pattern counts of the tables (n = 1..N), per dimension.
TABLE_N = {2: 33, 3: 40}
#: Further counts in the symmetric electrostatic and Lloyd tables (the candidates of the
#: default): the sizes the screen-space estimators and their tests ask for beyond n <= 33.
TABLE_EXTRA_N = (64, 65, 128, 129, 256, 257)

_DOMAIN = {2: "disk", 3: "ball"}
_VOLUME = {2: np.pi, 3: 4.0 * np.pi / 3.0}
_GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


# ============================================================================ the pattern type
@dataclass(frozen=True, eq=False)
class SamplePattern:
    """Points in the unit disk (n, 2) or unit ball (n, 3) with weights summing to 1.

    Attributes
    ----------
    points : (n, 2) or (n, 3) float64
    weights : (n,) float64
        Normalized to sum 1 on construction.
    method : str
    provenance : dict
        Generator, version, parameters and seed (and, for a table entry, the table).

    Examples
    --------
    >>> p = SamplePattern([[0.5, 0.0], [-0.5, 0.0]], [1.0, 1.0])
    >>> p.n, p.dim, p.weights.tolist(), p.is_symmetric
    (2, 2, [0.5, 0.5], True)
    """

    points: np.ndarray
    weights: np.ndarray
    method: str = "custom"
    provenance: dict = field(default_factory=dict)

    def __post_init__(self):
        pts = np.asarray(self.points, dtype=np.float64)
        w = np.asarray(self.weights, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3) or len(pts) == 0:
            raise ValueError(f"points must have shape (n, 2) or (n, 3) with n >= 1, got {pts.shape}")
        if w.shape != (len(pts),):
            raise ValueError(f"weights must have shape ({len(pts)},), got {w.shape}")
        if not (np.all(np.isfinite(pts)) and np.all(np.isfinite(w))):
            raise ValueError("points and weights must be finite")
        if np.any(np.sum(pts * pts, axis=1) > 1.0 + 1e-9):
            raise ValueError("points must lie inside the unit disk or ball")
        if np.any(w < 0) or not w.sum() > 0:
            raise ValueError("weights must be non-negative with a positive sum")
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "weights", w / w.sum())

    @property
    def n(self) -> int:
        return len(self.points)

    @property
    def dim(self) -> int:
        return self.points.shape[1]

    @property
    def has_center(self) -> bool:
        """True when one of the points is the origin."""
        return bool(np.any(np.all(self.points == 0.0, axis=1)))

    @property
    def is_symmetric(self) -> bool:
        """True when the pattern equals its point reflection (points and weights)."""
        tree = cKDTree(self.points)
        dist, j = tree.query(-self.points)
        return bool(np.all(dist < SYMMETRY_ATOL)
                    and np.allclose(self.weights[j], self.weights, rtol=SYMMETRY_RTOL, atol=0.0))


# ============================================================================ discrete Voronoi
def _grid(dim: int, res: int) -> np.ndarray:
    """Centres of the cells of a res^dim grid over [-1, 1]^dim that lie inside the unit disk/ball."""
    c = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    g = np.stack(np.meshgrid(*([c] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    return g[np.sum(g * g, axis=1) < 1.0]


@lru_cache(maxsize=8)
def _cells(dim: int, res: int) -> tuple[np.ndarray, np.ndarray]:
    """Grid cells and their mass: 2 z_s on the disk (footnote 5), 1 in the ball. Read-only."""
    cells = _grid(dim, res)
    if dim == 2:
        # footnote 5: the disk is the orthographic projection of the sphere; a disk cell
        # stands for the sphere's z-extent 2 z_s above it
        mass = 2.0 * np.sqrt(np.maximum(0.0, 1.0 - np.sum(cells * cells, axis=1)))
    else:
        mass = np.ones(len(cells))
    cells.flags.writeable = False
    mass.flags.writeable = False
    return cells, mass


def voronoi_weights(points, *, grid: int | None = None) -> np.ndarray:
    """Footnote-5 weights of disk or ball points from a discrete Voronoi diagram.

    Parameters
    ----------
    points : (n, 2) or (n, 3) float
        Points in the unit disk or ball.
    grid : int, optional
        Cells per axis of the discrete diagram; default 512 for the disk, 128 for the ball
        (Loos & Sloan 2010, Sec. 4.5).

    Returns
    -------
    (n,) float64
        Disk: the integral of the sphere's z-extent 2 sqrt(1 - x^2 - y^2) over each region
        (Loos & Sloan 2010, footnote 5). Ball: the volume of each region. Normalized to sum 1.
        A region no cell falls into gets weight 0.

    Examples
    --------
    >>> w = voronoi_weights([[0.0, 0.0], [0.9, 0.0]], grid=128)
    >>> bool(w[0] > w[1]), round(float(w.sum()), 12)
    (True, 1.0)
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) == 0:
        raise ValueError(f"points must have shape (n, 2) or (n, 3) with n >= 1, got {points.shape}")
    dim = points.shape[1]
    res = check_int(grid, "grid", minimum=2) if grid is not None else (DISK_GRID if dim == 2 else BALL_GRID)
    cells, mass = _cells(dim, res)
    _, owner = cKDTree(points).query(cells)
    w = np.bincount(owner, weights=mass, minlength=len(points))
    return w / w.sum()


def _symmetrize_weights(points: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Average each weight with its antipode's: the discrete diagram can split ties unevenly."""
    _, j = cKDTree(points).query(-points)
    return 0.5 * (w + w[j])


# ============================================================================ layouts
@dataclass(frozen=True)
class _Layout:
    """Which points a generator places freely and which follow from them.

    Symmetric: ``n // 2`` free points h, their antipodes -h, and the origin for odd n.
    Plain: ``n`` free points, or the origin plus ``n - 1`` with ``center``.
    """

    dim: int
    n: int
    symmetric: bool
    center: bool

    @property
    def free(self) -> int:
        return self.n // 2 if self.symmetric else self.n - int(self.center)

    @property
    def spacing(self) -> float:
        """Mean distance between samples, (volume / n)^(1/dim)."""
        return (_VOLUME[self.dim] / self.n) ** (1.0 / self.dim)

    def full(self, free: np.ndarray) -> np.ndarray:
        """All points, in the internal order: [origin], free, [-free]."""
        parts = [np.zeros((1, self.dim))] if self.center else []
        parts.append(free)
        if self.symmetric:
            parts.append(-free)
        return np.concatenate(parts, axis=0)

    def ordered(self, free: np.ndarray) -> np.ndarray:
        """The published order: the origin first, then the free points (each followed by its
        antipode when symmetric)."""
        parts = [np.zeros((1, self.dim))] if self.center else []
        if self.symmetric:
            parts.append(np.stack([free, -free], axis=1).reshape(-1, self.dim))
        else:
            parts.append(free)
        return np.concatenate(parts, axis=0)

    def self_index(self) -> np.ndarray:
        """Index in :meth:`full` of each free point."""
        return np.arange(self.free) + int(self.center)


def _optimization_grid(dim: int, n: int) -> int:
    """Cells per axis of the optimization grid for n samples (see OPTIMIZATION_GRID)."""
    fill = _VOLUME[dim] / 2.0 ** dim                  # fraction of the cube inside the domain
    need = math.ceil((OPTIMIZATION_CELLS * n / fill) ** (1.0 / dim))
    return max(OPTIMIZATION_GRID[dim], need)


def _clip_to_domain(x: np.ndarray, r_max: float = R_MAX) -> np.ndarray:
    r = np.linalg.norm(x, axis=1, keepdims=True)
    return np.where(r > r_max, x * (r_max / np.maximum(r, 1e-300)), x)


def _uniform(dim: int, u: np.ndarray, *, half: bool = False) -> np.ndarray:
    """(k, dim) uniform in [0, 1)^dim -> uniform in the unit disk/ball (polar, measure-preserving);
    ``half``: in the half x_0 > 0 (disk) or z > 0 (ball)."""
    if dim == 2:
        r = np.sqrt(u[:, 0])
        phi = (np.pi * u[:, 1] - 0.5 * np.pi) if half else 2.0 * np.pi * u[:, 1]
        return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    r = np.cbrt(u[:, 0])
    z = u[:, 1] if half else 1.0 - 2.0 * u[:, 1]
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * np.pi * u[:, 2]
    return r[:, None] * np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def _square_to_disk_concentric(u: np.ndarray) -> np.ndarray:
    """Shirley & Chiu 1997: the area-preserving, low-distortion map of [0, 1)^2 to the disk."""
    a = 2.0 * u[:, 0] - 1.0
    b = 2.0 * u[:, 1] - 1.0
    big_a = np.abs(a) > np.abs(b)
    r = np.where(big_a, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(big_a, 0.25 * np.pi * b / np.where(a == 0, 1.0, a),
                       0.5 * np.pi - 0.25 * np.pi * a / np.where(b == 0, 1.0, b))
    phi = np.where(r == 0, 0.0, phi)
    return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)


# ============================================================================ simple generators
def _random(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    return _uniform(layout.dim, rng.random((layout.free, layout.dim)), half=layout.symmetric)


def _qmc(kind: str):
    def generate(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
        from scipy.stats import qmc

        k, dim = layout.free, layout.dim
        if k == 0:
            return np.zeros((0, dim))
        if kind == "sobol":
            # random_base2: a power-of-two prefix keeps Sobol' balanced (and scipy quiet);
            # the first k points of it are used
            engine = qmc.Sobol(d=dim, scramble=True, seed=rng)
            u = engine.random_base2(max(0, int(math.ceil(math.log2(k)))))[:k]
        else:
            u = qmc.Halton(d=dim, scramble=True, seed=rng).random(k)
        if dim == 2 and not layout.symmetric:
            return _square_to_disk_concentric(u)
        return _uniform(dim, u, half=layout.symmetric)
    return generate


def _dart_throw(layout: _Layout, rng: np.random.Generator, params: dict | None = None) -> np.ndarray:
    """Poisson-disk dart throwing: uniform candidates, rejected when closer than r to a sample
    (antipodes and the centre included); after ``attempts`` rejections in a row r shrinks."""
    p = POISSON if params is None else params
    k, dim = layout.free, layout.dim
    r = p["first_radius"] * layout.spacing
    fixed = [np.zeros(dim)] if layout.center else []
    free: list[np.ndarray] = []
    fails = 0
    while len(free) < k:
        x = _uniform(dim, rng.random((1, dim)))[0]
        others = fixed + free + ([-f for f in free] if layout.symmetric else [])
        ok = all(np.sum((x - o) ** 2) >= r * r for o in others)
        if layout.symmetric:
            ok = ok and 4.0 * float(x @ x) >= r * r      # its own antipode
        if ok:
            free.append(x)
            fails = 0
        else:
            fails += 1
            if fails >= p["attempts"]:
                r *= p["shrink"]
                fails = 0
    return np.array(free).reshape(k, dim)


def _poisson(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    return _dart_throw(layout, rng, params)


def _spiral(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """Sunflower spiral (disk) or spherical-Fibonacci shells (ball); deterministic.

    Sample j of the free set takes the j-th equal-measure band (the centre, when present,
    takes the innermost one) and the golden angle j * pi (3 - sqrt 5) around the axis.
    """
    k, dim, n = layout.free, layout.dim, layout.n
    if k == 0:
        return np.zeros((0, dim))
    j = np.arange(k)
    step = 2.0 if layout.symmetric else 1.0          # a pair takes two bands
    first = 1.0 if layout.center else 0.0            # the centre takes the innermost band
    u = (first + step * j + 0.5 * step) / n          # band middle, as a measure fraction
    if dim == 2:
        r = np.sqrt(u)
        phi = j * _GOLDEN_ANGLE
        return np.stack([r * np.cos(phi), r * np.sin(phi)], axis=1)
    # ball: shells of equal volume, each holding its share of the points on a spherical
    # Fibonacci lattice; the radius of a shell is its middle by volume
    shells = max(1, int(round(0.5 * k ** (1.0 / 3.0))))
    counts = np.full(shells, k // shells)
    counts[shells - k % shells:] += 1                # the outer shells take the remainder
    out = []
    lo = first / n
    for s, c in enumerate(counts):
        share = c * step / n
        r = np.cbrt(lo + 0.5 * share)
        lo += share
        i = np.arange(c)
        # symmetric: the lattice on the upper hemisphere (the antipodes fill the lower one)
        z = 1.0 - (i + 0.5) / c if layout.symmetric else 1.0 - 2.0 * (i + 0.5) / c
        rho = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        phi = i * _GOLDEN_ANGLE + s * 0.5 * _GOLDEN_ANGLE
        out.append(r * np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1))
    return np.concatenate(out, axis=0)


# ============================================================================ Voronoi helpers
def _regions(full: np.ndarray, cells: np.ndarray, mass: np.ndarray):
    """Owner of every cell, region masses (n,) and mass-weighted centroids (n, dim)."""
    _, owner = cKDTree(full).query(cells)
    m = np.bincount(owner, weights=mass, minlength=len(full))
    sums = np.stack([np.bincount(owner, weights=mass * cells[:, a], minlength=len(full))
                     for a in range(full.shape[1])], axis=1)
    centroid = np.where(m[:, None] > 0, sums / np.maximum(m, 1e-300)[:, None], full)
    return owner, m, centroid


def _equal_integral_error(m: np.ndarray) -> float:
    """RMS relative deviation of the region integrals from their mean: 0 when all are equal
    ("the goal is to have the integral over the Voronoi region of every sample to be equal")."""
    return float(np.sqrt(np.mean((m * (len(m) / m.sum()) - 1.0) ** 2)))


def _free_centroids(layout: _Layout, centroid: np.ndarray) -> np.ndarray:
    """Centroids of the free points' regions; symmetric: the mean of a point's centroid and
    the reflection of its antipode's, so that the pair moves as one."""
    idx = layout.self_index()
    c = centroid[idx]
    if layout.symmetric:
        c = 0.5 * (c - centroid[idx + layout.free])
    return c


# ============================================================================ Lloyd
def _lloyd(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """Lloyd relaxation (Lloyd 1982): every free point moves to the centroid of its region.

    The standard, unweighted relaxation toward a centroidal Voronoi tessellation of the disk
    (area) or ball (volume): the paper's rival. Several Poisson starts; the one with the
    lowest centroidal energy sum_i int_{V_i} |x - x_i|^2 is kept.
    """
    if layout.free == 0:
        return np.zeros((0, layout.dim))
    cells, _ = _cells(layout.dim, _optimization_grid(layout.dim, layout.n))
    area = np.ones(len(cells))
    best, best_energy = None, np.inf
    for _ in range(params["starts"]):
        free = _dart_throw(layout, rng)
        for _ in range(params["iterations"]):
            _, _, centroid = _regions(layout.full(free), cells, area)
            free = _free_centroids(layout, centroid)
        dist, _ = cKDTree(layout.full(free)).query(cells)
        energy = float(np.sum(dist * dist))
        if energy < best_energy:
            best, best_energy = free, energy
    return best


# ============================================================================ electrostatic
_BOUNDARY_R = np.linspace(0.0, R_MAX, 4001)


@lru_cache(maxsize=2)
def _boundary_table(dim: int) -> tuple[np.ndarray, np.ndarray]:
    """Radial force B(r) (< 0: inward) and potential Phi(r) (Phi(0) = 0, Phi' = -B) of a unit
    charge spread uniformly over the unit circle (dim 2) or sphere (dim 3), 1/d^4 law.

    Circle: B(r) = (1/2pi) int_0^2pi (r - cos t) / (1 + r^2 - 2 r cos t)^(5/2) dt, by the
    periodic trapezoid rule (exponentially accurate). Sphere: B(r) = (1/2) int_-1^1 (r - mu) /
    (1 + r^2 - 2 r mu)^(5/2) dmu, in closed form with s = 1 + r^2 - 2 r mu:
    B = 1/(8 r^2) [-2 s^-1/2 - (2/3)(r^2 - 1) s^-3/2] from s = (1 - r)^2 to (1 + r)^2.
    """
    r = _BOUNDARY_R
    if dim == 2:
        t = np.linspace(0.0, 2.0 * np.pi, 8192, endpoint=False)
        B = np.empty_like(r)
        for a in range(0, len(r), 256):
            rr = r[a:a + 256, None]
            B[a:a + 256] = np.mean((rr - np.cos(t)) / (1.0 + rr * rr - 2.0 * rr * np.cos(t)) ** 2.5, axis=1)
    else:
        rr = np.maximum(r, 1e-2)

        def prim(s):
            return -2.0 / np.sqrt(s) - (2.0 / 3.0) * (rr * rr - 1.0) / s ** 1.5

        B = (prim((1.0 + rr) ** 2) - prim((1.0 - rr) ** 2)) / (8.0 * rr * rr)
        B = np.where(r < 1e-2, B * r / rr, B)        # linear near the centre (B(0) = 0)
    # Phi(r) = -int_0^r B: trapezoid on the fine table
    phi = -np.concatenate([[0.0], np.cumsum(0.5 * (B[1:] + B[:-1]) * np.diff(r))])
    B.flags.writeable = False
    phi.flags.writeable = False
    return B, phi


def _boundary(dim: int, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Force vectors (k, dim) and potentials (k,) of the unit boundary charge at points x."""
    B, phi = _boundary_table(dim)
    r = np.linalg.norm(x, axis=1)
    b = np.interp(r, _BOUNDARY_R, B)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(r[:, None] > 0, x / r[:, None], 0.0)
    return b[:, None] * unit, np.interp(r, _BOUNDARY_R, phi)


def _repulsion(layout: _Layout, free: np.ndarray) -> tuple[np.ndarray, float]:
    """1/d^4 repulsion on each free point from every other point, and the potential energy
    sum_{pairs} 1 / (3 d^3) of the whole set.

    The energy comes from the free points' rows alone: the antipodes' rows repeat them and the
    centre's row holds the free points' distances to the origin.
    """
    full = layout.full(free)
    diff = free[:, None, :] - full[None, :, :]
    d2 = np.sum(diff * diff, axis=2)
    d2[np.arange(layout.free), layout.self_index()] = np.inf
    d2 = np.maximum(d2, 1e-24)
    force = np.sum(diff * (d2 ** -2.5)[:, :, None], axis=1)    # |F| = 1 / d^4, away from x_j
    rows = float(np.sum(d2 ** -1.5)) / 3.0
    if layout.center:
        rows += float(np.sum(np.maximum(np.sum(free * free, axis=1), 1e-24) ** -1.5)) / 3.0
    return force, 0.5 * (1 + int(layout.symmetric)) * rows


class _Relaxation:
    """One electrostatic relaxation from one start (Loos & Sloan 2010, Sec. 4.5).

    State: the free points, the boundary charge q and the step. A step moves every free point
    along its net force F = F_rep + q F_boundary, the largest move being ``step``; it is
    applied only when it decreases the error (``params["error"]``): the potential energy of
    the system ("energy", the default) or the equal-integral error of the Voronoi regions
    ("voronoi").
    """

    def __init__(self, layout: _Layout, free: np.ndarray, params: dict, cells, mass):
        self.layout, self.p, self.cells, self.mass = layout, params, cells, mass
        self.free = free
        self.q = 0.0
        self.mismatch = np.inf
        self.step = params["first_step"] * layout.spacing
        self.steps_done = 0
        self._optimize_charge()
        self.force, self.error = self._evaluate(self.free)

    def _evaluate(self, free: np.ndarray) -> tuple[np.ndarray, float]:
        """Net forces on the free points and the error of the configuration."""
        lay = self.layout
        rep, energy = _repulsion(lay, free)
        bf, pot = _boundary(lay.dim, free)
        force = rep + self.q * bf
        if self.p["error"] == "voronoi":
            _, m, _ = _regions(lay.full(free), self.cells, self.mass)
            return force, _equal_integral_error(m)
        # the antipodes sit at the same radii; the centre at Phi(0) = 0
        return force, energy + self.q * (1 + int(lay.symmetric)) * float(np.sum(pot))

    # "optimize the boundary charge to push points toward the weighted centroid of their
    # Voronoi regions periodically"
    def _optimize_charge(self) -> None:
        """One update of the boundary charge q from the weighted Voronoi centroids c_i.

        g = mean_i (c_i - x_i) . x_i / |x_i|, in units of the spacing: positive when the
        centroids lie farther out than the points (the charge squeezes them too much), so
        q <- q exp(-gain g). The first call sets q so that the radial forces on the free
        points balance, sum_i (F_rep,i + q F_b,i) . x_i / |x_i| = 0.
        """
        lay = self.layout
        _, m, centroid = _regions(lay.full(self.free), self.cells, self.mass)
        r = np.linalg.norm(self.free, axis=1)
        out = np.divide(self.free, r[:, None], out=np.zeros_like(self.free), where=r[:, None] > 0)
        if self.q == 0.0:
            rep = float(np.sum(_repulsion(lay, self.free)[0] * out))
            bnd = float(np.sum(_boundary(lay.dim, self.free)[0] * out))
            self.q = -rep / bnd if bnd < 0 and rep > 0 else 1.0
            return
        g = float(np.mean(np.sum((_free_centroids(lay, centroid) - self.free) * out, axis=1))) / lay.spacing
        self.mismatch = g
        self.q *= math.exp(-self.p["charge_gain"] * g)

    def run(self, steps: int) -> "_Relaxation":
        lay, p = self.layout, self.p
        if lay.free == 0:
            return self
        min_step = p["min_step"] * lay.spacing
        for _ in range(steps):
            big = float(np.max(np.linalg.norm(self.force, axis=1)))
            if big == 0.0:
                break
            # "The net force is reduced until the error decreases (not applying the force
            # until there is a reduction) and increased otherwise."
            trial = _clip_to_domain(self.free + (self.step / big) * self.force)
            force, error = self._evaluate(trial)
            if error < self.error:
                self.free, self.force, self.error = trial, force, error
                self.step *= p["grow"]
            else:
                self.step *= p["shrink"]
            self.steps_done += 1
            at_rest = self.step < min_step
            if at_rest or self.steps_done % p["charge_every"] == 0:
                self._optimize_charge()
                self.force, self.error = self._evaluate(self.free)    # both change with q
                if at_rest:
                    if abs(self.mismatch) < p["charge_tol"]:
                        break            # at rest, and the charge no longer changes
                    self.step = p["first_step"] * lay.spacing
        return self

    def score(self) -> float:
        """How close the start came to the aim: the equal-integral error of its regions."""
        _, m, _ = _regions(self.layout.full(self.free), self.cells, self.mass)
        return _equal_integral_error(m)


def _electrostatic(layout: _Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """The electrostatic generator of Loos & Sloan 2010, Sec. 4.5 (see docs/patterns.md).

    "This process is initialized with tens of starting point sets generated using Poisson
    sampling": ``starts`` dart-throwing sets, each relaxed until it is at rest (at most
    ``steps`` steps); the one whose Voronoi regions come closest to equal integrals is kept.
    """
    if layout.free == 0:
        return np.zeros((0, layout.dim))
    cells, mass = _cells(layout.dim, _optimization_grid(layout.dim, layout.n))
    best, best_score = None, np.inf
    for _ in range(params["starts"]):
        run = _Relaxation(layout, _dart_throw(layout, rng), params, cells, mass).run(params["steps"])
        score = run.score()
        if score < best_score:
            best, best_score = run, score
    return best.free


_GENERATORS = {
    "electrostatic": (_electrostatic, ELECTROSTATIC),
    "lloyd": (_lloyd, LLOYD),
    "poisson": (_poisson, POISSON),
    "sobol": (_qmc("sobol"), {}),
    "halton": (_qmc("halton"), {}),
    "random": (_random, {}),
    "spiral": (_spiral, {}),
}


def _generate(dim: int, n: int, method: str, symmetric: bool, center: bool, seed,
              params: dict | None = None) -> SamplePattern:
    """Run a generator and compute the footnote-5 weights on the full grid."""
    layout = _Layout(dim, n, symmetric, center)
    fn, defaults = _GENERATORS[method]
    params = dict(defaults) if params is None else params
    rng = as_rng(seed)
    t0 = time.perf_counter()
    free = fn(layout, rng, params)
    points = layout.ordered(free)
    w = voronoi_weights(points)
    if symmetric:
        w = _symmetrize_weights(points, w)
    seconds = time.perf_counter() - t0
    prov = _provenance(dim, n, method, symmetric, center, seed, params)
    prov["seconds"] = round(seconds, 3)
    prov["source"] = "generated"
    return SamplePattern(points, w, method=method, provenance=prov)


def _provenance(dim, n, method, symmetric, center, seed, params) -> dict:
    return {"generator": "vobscure.patterns", "version": GENERATOR_VERSION, "domain": _DOMAIN[dim],
            "method": method, "n": n, "symmetric": symmetric, "center": center,
            "seed": seed if isinstance(seed, numbers.Integral) else None,
            "parameters": dict(params), "weights_grid": DISK_GRID if dim == 2 else BALL_GRID,
            "optimization_grid": _optimization_grid(dim, n) if method in ("electrostatic", "lloyd") else None}


# ============================================================================ public constructors
def _check_bool(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _resolve_center(n: int, center, symmetric: bool) -> bool:
    if center is None:
        return symmetric and n % 2 == 1
    center = _check_bool(center, "center")
    if symmetric and center != (n % 2 == 1):
        have = "odd" if n % 2 else "even"
        raise ValueError(
            f"center={center} is impossible for a symmetric pattern of {have} n={n}: a point-symmetric "
            f"pattern holds the centre exactly when n is odd; pass center=None, or symmetric=False")
    return center


def _pattern(dim: int, n, method, center, symmetric, seed) -> SamplePattern:
    """The shared body of :func:`disk` (dim 2) and :func:`ball` (dim 3)."""
    n = check_int(n, "n")
    check_choice(method, "method", (BEST,) + METHODS)
    symmetric = _check_bool(symmetric, "symmetric")
    center = _resolve_center(n, center, symmetric)
    selection = None
    if method == BEST:
        method, scores = _best(dim, n, symmetric, center)
        selection = {"rule": "lowest recorded quality among the tables holding n" if scores
                     else f"no table holds n: {BEST_FALLBACK}", "candidates": dict(scores)}
    if isinstance(seed, numbers.Integral) and not isinstance(seed, bool):
        as_rng(seed)                                  # validates (non-negative)
        p = _copy(_cached(dim, n, method, symmetric, center, int(seed)))
    else:
        p = _generate(dim, n, method, symmetric, center, as_rng(seed))
    if selection is not None:
        p.provenance["selection"] = selection
    return p


def _exact(points, weights, method: str, provenance: dict) -> SamplePattern:
    """A validated pattern that keeps ``weights`` bit for bit (they are normalized already:
    normalizing again could change the last bits, and a table entry must equal the pattern
    it was generated as)."""
    p = SamplePattern(points, weights, method=method, provenance=provenance)
    object.__setattr__(p, "weights", np.array(weights, dtype=np.float64))
    return p


def _copy(p: SamplePattern) -> SamplePattern:
    return _exact(p.points.copy(), p.weights, p.method, json.loads(json.dumps(p.provenance)))


@lru_cache(maxsize=256)
def _cached(dim, n, method, symmetric, center, seed) -> SamplePattern:
    entry = _table_entry(dim, method, symmetric, center, n, seed)
    if entry is not None:
        return entry
    return _generate(dim, n, method, symmetric, center, seed)


def disk(n: int, *, method: str = BEST, center: bool | None = None, symmetric: bool = True,
         seed=0) -> SamplePattern:
    """A pattern of ``n`` points in the unit disk with footnote-5 weights, for line sampling.

    Parameters
    ----------
    n : int
        Number of samples, >= 1.
    method : str, optional
        One of :data:`METHODS`, or ``"best"`` (default): the generator whose table entry for
        this count and variant has the lowest recorded :func:`quality`
        (:func:`best_method`; the electrostatic generator of Loos & Sloan 2010, Sec. 4.5,
        where no table holds the count). ``pattern.method`` names the generator used.
    center : bool or None, optional
        True forces a sample at the origin, False forbids forcing one (a generator may still
        put a point near it). None: the centre exactly when the pattern is symmetric and n is
        odd. A symmetric pattern holds the centre exactly when n is odd, so the other choice
        raises ValueError.
    symmetric : bool, optional
        Antipodal pairs, plus the centre for odd n (default True). The screen-space
        estimators need it to be exact on planes.
    seed : int, numpy.random.Generator or None, optional
        Converted once; the same int gives the same pattern bit for bit. The defaults (seed 0)
        load from ``data/patterns/`` when the table holds the entry, lazily, and are cached.

    Returns
    -------
    SamplePattern
        ``points`` (n, 2) (the centre first when present; symmetric: each free point followed
        by its antipode), ``weights`` (n,) summing to 1, ``method`` and ``provenance``.

    References
    ----------
    Loos & Sloan 2010, Sec. 4.5 (generation, the discrete 512^2 Voronoi diagram) and footnote 5
    (weights: the integral of 2 sqrt(1 - x^2 - y^2) over each Voronoi region).

    Examples
    --------
    >>> p = disk(9)
    >>> p.points.shape, p.is_symmetric, p.has_center, round(float(p.weights.sum()), 12)
    ((9, 2), True, True, 1.0)
    >>> disk(6, method="sobol", symmetric=False, center=True, seed=1).has_center
    True
    """
    return _pattern(2, n, method, center, symmetric, seed)


def ball(n: int, *, method: str = BEST, center: bool | None = None, symmetric: bool = True,
         seed=0) -> SamplePattern:
    """A pattern of ``n`` points in the unit ball with volume weights, for point sampling.

    Parameters are those of :func:`disk`; the weights are the volumes of the discrete
    Voronoi regions (128^3 grid, Loos & Sloan 2010, Sec. 4.5). A point sample at the centre
    lies on any surface through it and reads open (occupied means behind the surface), so
    for point sampling the even counts, without the centre, are the better symmetric ones.

    Returns
    -------
    SamplePattern
        ``points`` (n, 3), ``weights`` (n,) summing to 1.

    Examples
    --------
    >>> p = ball(12)
    >>> p.points.shape, p.is_symmetric
    ((12, 3), True)
    >>> ball(5, method="spiral", symmetric=False).is_symmetric
    False
    """
    return _pattern(3, n, method, center, symmetric, seed)


@lru_cache(maxsize=512)
def _best(dim: int, n: int, symmetric: bool, center: bool) -> tuple[str, dict]:
    """The method whose table entry (seed 0) for this count and variant has the lowest
    recorded quality, and every candidate's quality; ties go to the earlier method."""
    scores = {}
    for method in METHODS:
        entry = _table_entry(dim, method, symmetric, center, n, 0)
        if entry is not None:
            scores[method] = entry.provenance["quality"]
    if not scores:
        return BEST_FALLBACK, {}
    return min(scores, key=lambda m: (scores[m], METHODS.index(m))), scores


def best_method(domain: str, n: int, *, center: bool | None = None, symmetric: bool = True) -> str:
    """The generator ``method="best"`` (the default of :func:`disk` and :func:`ball`) uses.

    Parameters
    ----------
    domain : {"disk", "ball"}
    n : int
    center, symmetric : optional
        As in :func:`disk`.

    Returns
    -------
    str
        Among the tables in :data:`TABLE_DIR` that hold this count and variant, the method
        whose recorded :func:`quality` is the lowest (ties: the earlier in :data:`METHODS`);
        ``"electrostatic"`` when none does. The choice is made on the tables' seed-0
        patterns; another seed runs the chosen generator with that seed.

    Examples
    --------
    >>> best_method("disk", 9) in METHODS
    True
    >>> best_method("disk", 1000)      # no table holds it
    'electrostatic'
    """
    check_choice(domain, "domain", ("disk", "ball"))
    n = check_int(n, "n")
    symmetric = _check_bool(symmetric, "symmetric")
    center = _resolve_center(n, center, symmetric)
    return _best(2 if domain == "disk" else 3, n, symmetric, center)[0]


# ============================================================================ exact volumes
def cap_volume(h):
    """Volume of a cap of height ``h`` cut from the unit ball.

    Parameters
    ----------
    h : float or array
        Cap height in [0, 2] (clipped).

    Returns
    -------
    float64 array
        ``pi h^2 (3 - h) / 3`` (Hegeman et al. 2006, Eq. 4, with R = 1).

    Examples
    --------
    >>> round(float(cap_volume(1.0) / (4 * np.pi / 3)), 12)   # a half ball
    0.5
    """
    h = np.clip(np.asarray(h, dtype=np.float64), 0.0, 2.0)
    return np.pi * h * h * (3.0 - h) / 3.0           # V_cap, Hegeman 2006, Eq. 4 (R = 1)


def _halfspace_volume(t):
    """Volume of {x in unit ball : n . x <= t} for a unit n."""
    return 4.0 * np.pi / 3.0 - cap_volume(1.0 - np.asarray(t, dtype=np.float64))


def _line_piece(t, d, k):
    """G(t) = psi(t) - I(t): the fan integral of F(rho) = (2/3)(1 - (1 - rho^2)^(3/2)) over the
    line at distance d from the origin, up to the factor (2/3) sign(a); see crease_volume."""
    s = np.sqrt(np.maximum(k * k - t * t, 0.0))
    asn = np.arcsin(np.clip(np.divide(t, k, out=np.zeros_like(t), where=k > 0), -1.0, 1.0))
    psi = np.arctan2(t, d)
    I = np.arctan2(t, d * s) - d * asn - 0.5 * d * (t * s + k * k * asn)
    return psi - I


def crease_volume(n1, t1, n2, t2):
    """Volume of the unit ball on the open side of two planes, {n1 . x <= t1} and {n2 . x <= t2}.

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
    Let e be the direction of the planes' common line. Along e the region is a prism over a
    2-D wedge W = {u1 . x <= a1} and {u2 . x <= a2} (u_i: the normals in the plane normal to e,
    a_i = t_i), so its volume is the integral over W within the unit disk of the chord length
    2 sqrt(1 - |x|^2). With F(rho) = int_0^rho 2 sqrt(1 - r^2) r dr = (2/3)(1 - (1 - rho^2)^(3/2)),
    Green's theorem turns that area integral into the boundary integral of F(rho) dtheta:
    arcs of the unit circle give (2/3) dtheta; the piece of line i at distance d = |a_i| gives
    (2/3) sign(a_i) [psi - I], psi = atan(t / d), with t the coordinate along the line,
    k^2 = 1 - d^2 and I = atan(t / (d sqrt(k^2 - t^2))) - d asin(t / k)
    - (d / 2)(t sqrt(k^2 - t^2) + k^2 asin(t / k)), the antiderivative of
    d (k^2 - t^2)^(3/2) / (d^2 + t^2). Parallel planes reduce to caps and slabs.
    The tests check it against Monte Carlo and the split identity
    V(n1, t1, n2, t2) + V(n1, t1, -n2, -t2) = V_ball - V_cap(1 - t1).

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
    return np.clip(volume, 0.0, 4.0 * np.pi / 3.0).reshape(shape)


# ============================================================================ quality
def _hemisphere(rng: np.random.Generator, count: int) -> np.ndarray:
    """Uniform unit vectors with n_z > 0: normals of planes a depth buffer can hold."""
    z = np.maximum(rng.random(count), 1e-12)
    phi = 2.0 * np.pi * rng.random(count)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


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
    vball = 4.0 * np.pi / 3.0
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


def _squared_errors(pattern, *, trials, seed, family) -> np.ndarray:
    """(trials,) squared errors of the pattern's estimate, configuration by configuration."""
    if not isinstance(pattern, SamplePattern):
        raise ValueError(f"pattern must be a SamplePattern, got {type(pattern).__name__}")
    trials = check_int(trials, "trials", minimum=2)
    check_choice(family, "family", FAMILIES)
    if isinstance(seed, numbers.Integral) and not isinstance(seed, bool):
        as_rng(seed)
        cfg = _configurations(trials, int(seed), family)
    else:
        cfg = _configurations_from(as_rng(seed), trials, family)
    return (_estimates(pattern, cfg) - cfg.exact) ** 2


def quality(pattern: SamplePattern, *, trials: int = QUALITY_TRIALS, seed=QUALITY_SEED,
            family: str = "mixed") -> Estimate:
    """RMS error of a pattern's VO estimate over random configurations with exact VO.

    Parameters
    ----------
    pattern : SamplePattern
        A disk pattern is measured with line sampling (each sample (x, y) integrates the chord
        [-z_s, z_s], z_s = sqrt(1 - x^2 - y^2), against a height field), a ball pattern with
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
        ``value``: the RMS error sqrt(mean((estimate - exact)^2)); ``stderr``: its standard
        error by the delta method, sd((estimate - exact)^2) / (2 RMS sqrt(trials));
        ``samples``: trials.

    Notes
    -----
    Every plane has a normal uniform over the hemisphere n_z > 0 and is occupied on its far
    side n . x > t ("behind the surface" along the view axis z), so that a depth buffer can
    hold every configuration. A crease's occupied set is the union (concave) or the
    intersection (convex) of the two half-spaces. Per trial the pattern is turned by a random
    element of O(2) about the view axis (disk) or of O(3) (ball), as the estimators randomize
    per pixel (Sec. 4.5). A ball sample is open when it is not occupied, except a sample
    exactly at the centre when the first plane passes through it (every crease: the centre is
    the depth buffer's surface point): its test would compare the surface with itself, so it
    counts half occupied by that plane, as ``vo_point`` counts it (docs/screenspace.md, "The
    centre sample"), and the second plane decides as for any sample; the centre alone then
    reads 1/2 on every crease. (Before :data:`QUALITY_VERSION` 2 it read open there, the bias
    the estimator had.) The exact VO: the cap volume (Hegeman et al. 2006, Eq. 4) and
    :func:`crease_volume`. The same ``trials`` and int ``seed`` give every pattern the same
    configurations, so differences between patterns are measured with common random numbers.

    Examples
    --------
    >>> q = quality(disk(9), trials=2000)
    >>> bool(0 < q.value < 0.1), bool(q.stderr < q.value)
    (True, True)
    """
    err2 = _squared_errors(pattern, trials=trials, seed=seed, family=family)
    trials = len(err2)
    mse = float(np.mean(err2))
    rms = math.sqrt(mse)
    se_mse = float(np.std(err2, ddof=1)) / math.sqrt(trials)
    stderr = se_mse / (2.0 * rms) if rms > 0 else 0.0
    return Estimate(np.float64(rms), np.float64(stderr), trials)


# ============================================================================ tables
def _variant(symmetric: bool, center: bool) -> str:
    return "symmetric" if symmetric else ("center" if center else "plain")


#: The table families per dimension: symmetric (the centre exactly for odd n), plain with the
#: centre forced, plain without.
VARIANTS = {2: ("symmetric", "center", "plain"), 3: ("symmetric", "plain")}


def _variant_flags(variant: str, n: int) -> tuple[bool, bool]:
    """(symmetric, center) of a table variant at count n."""
    if variant == "symmetric":
        return True, n % 2 == 1
    return False, variant == "center"


def _table_path(dim: int, method: str, variant: str, directory=None) -> Path:
    return Path(TABLE_DIR if directory is None else directory) / f"{_DOMAIN[dim]}_{method}_{variant}.npz"


def _table_counts(dim: int, method: str, variant: str, quick: bool = False) -> list[int]:
    """The counts n a table holds (``quick``: the subset ``build --quick`` regenerates)."""
    top = 4 if quick else TABLE_N[dim]
    counts = list(range(1, top + 1))
    if not quick and method in ("electrostatic", "lloyd") and variant == "symmetric":
        counts += list(TABLE_EXTRA_N)
    return counts


def _jsonable(value):
    """Round-trip through JSON, so that recorded and current parameters compare equal."""
    return json.loads(json.dumps(value))


@lru_cache(maxsize=64)
def _read_table(path: str):
    """The table at ``path`` as {n: (points, weights, entry)} plus its provenance; None if
    the file is missing or unreadable."""
    try:
        with np.load(path, allow_pickle=False) as z:
            prov = json.loads(str(z["provenance"]))
            counts, offsets = z["counts"], z["offsets"]
            points, weights = z["points"], z["weights"]
    except (OSError, KeyError, ValueError):
        return None
    entries = {}
    for i, n in enumerate(counts.tolist()):
        p = points[offsets[i]:offsets[i + 1]]
        w = weights[offsets[i]:offsets[i + 1]]
        p.flags.writeable = False
        w.flags.writeable = False
        entries[n] = (p, w, prov["entries"][str(n)])
    return prov, entries


def _table_usable(prov: dict, dim: int, method: str, seed) -> bool:
    """A table is used only when it was written by this generator version with the current
    parameters and the requested seed."""
    return (prov.get("version") == GENERATOR_VERSION and prov.get("seed") == seed
            and prov.get("domain") == _DOMAIN[dim] and prov.get("method") == method
            and prov.get("parameters") == _jsonable(_GENERATORS[method][1]))


def _table_entry(dim, method, symmetric, center, n, seed, directory=None) -> SamplePattern | None:
    if not symmetric and dim == 3 and center:
        return None
    variant = _variant(symmetric, center)
    path = _table_path(dim, method, variant, directory)
    table = _read_table(str(path))
    if table is None:
        return None
    prov, entries = table
    if n not in entries or not _table_usable(prov, dim, method, seed):
        return None
    points, weights, entry = entries[n]
    record = _provenance(dim, n, method, symmetric, center, seed, _GENERATORS[method][1])
    record.update(source=f"table {path.name}", **entry)
    return _exact(points, weights, method, record)


def load_table(domain: str, method: str = "electrostatic", *, variant: str = "symmetric",
               directory=None) -> dict[int, SamplePattern]:
    """Every pattern of one precomputed table, by count n.

    Parameters
    ----------
    domain : {"disk", "ball"}
    method : str, optional
        One of :data:`METHODS`.
    variant : {"symmetric", "center", "plain"}, optional
        ``"symmetric"``: antipodal pairs (the centre for odd n); ``"center"``: the centre
        forced (disk only); ``"plain"``: no centre forced.
    directory : path-like, optional
        Default :data:`TABLE_DIR` (``data/patterns/`` in the repository).

    Returns
    -------
    dict of int to SamplePattern
        Empty when the table is missing or was written by another generator version or
        with other parameters. Each pattern's ``provenance`` holds the table's record for it
        (seconds, quality and its standard error).

    Examples
    --------
    >>> table = load_table("disk", "electrostatic", variant="symmetric")
    >>> table[9].is_symmetric, table[9].provenance["source"]
    (True, 'table disk_electrostatic_symmetric.npz')
    """
    check_choice(domain, "domain", ("disk", "ball"))
    check_choice(method, "method", METHODS)
    dim = 2 if domain == "disk" else 3
    check_choice(variant, "variant", VARIANTS[dim])
    path = _table_path(dim, method, variant, directory)
    table = _read_table(str(path))
    if table is None:
        return {}
    prov, entries = table
    if not _table_usable(prov, dim, method, prov.get("seed")):
        return {}
    out = {}
    for n in entries:
        symmetric, center = _variant_flags(variant, n)
        out[n] = _table_entry(dim, method, symmetric, center, n, prov["seed"], directory)
    return out


def _build_one(task):
    """Generate one table entry and measure it (runs in a worker process)."""
    dim, method, variant, n, seed = task
    symmetric, center = _variant_flags(variant, n)
    p = _generate(dim, n, method, symmetric, center, seed)
    q = quality(p)
    _, m, _ = _regions(p.points, *_cells(dim, DISK_GRID if dim == 2 else BALL_GRID))
    return task, p.points, p.weights, {
        "seconds": p.provenance["seconds"], "quality": float(q.value), "quality_stderr": float(q.stderr),
        "equal_integral_error": _equal_integral_error(m)}


def _software() -> dict:
    """Versions of Python, NumPy and SciPy, and NumPy's disabled SIMD kernels when any are
    (``NPY_DISABLE_CPU_FEATURES``: they can change the last bits of a result)."""
    import os
    import platform

    import scipy

    out = {"python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__}
    if os.environ.get("NPY_DISABLE_CPU_FEATURES", "").strip():
        out["NPY_DISABLE_CPU_FEATURES"] = os.environ["NPY_DISABLE_CPU_FEATURES"].strip()
    return out


def _write_table(path: Path, dim: int, method: str, variant: str, seed: int, entries: dict, *,
                 generated: dict | None = None, command: str = "python -m vobscure.patterns build") -> Path:
    """Write one table atomically. ``entries``: {n: (points, weights, record)}.

    ``generated``: the provenance of the table the points come from, when they were not
    generated by this call (:func:`_rescore_tables`): its ``command`` and ``software`` are kept
    as the generation's, and the quality record names ``command`` and this software.
    """
    from .. import _io

    counts = sorted(entries)
    offsets = np.concatenate([[0], np.cumsum([len(entries[n][0]) for n in counts])])
    software = _software()
    prov = {
        "generator": "vobscure.patterns", "version": GENERATOR_VERSION, "domain": _DOMAIN[dim],
        "method": method, "variant": variant,
        "symmetric": variant == "symmetric",
        "center": {"symmetric": "exactly for odd n", "center": "forced", "plain": "not forced"}[variant],
        "seed": seed, "parameters": _jsonable(_GENERATORS[method][1]),
        "weights_grid": DISK_GRID if dim == 2 else BALL_GRID,
        "optimization_grid": {"base": OPTIMIZATION_GRID[dim], "cells_per_region": OPTIMIZATION_CELLS},
        "quality": {"function": "vobscure.patterns.quality", "trials": QUALITY_TRIALS,
                    "seed": QUALITY_SEED, "family": "mixed", "version": QUALITY_VERSION,
                    "note": QUALITY_NOTES[QUALITY_VERSION], "command": command, "software": software},
        "command": command if generated is None else generated["command"],
        "software": software if generated is None else generated["software"],
        "entries": {str(n): entries[n][2] for n in counts},
    }
    arrays = {
        "counts": np.array(counts, dtype=np.int64),
        "offsets": offsets.astype(np.int64),
        "points": np.concatenate([entries[n][0] for n in counts], axis=0),
        "weights": np.concatenate([entries[n][1] for n in counts]),
        "quality": np.array([entries[n][2]["quality"] for n in counts]),
        "quality_stderr": np.array([entries[n][2]["quality_stderr"] for n in counts]),
    }
    _io.save_npz(path, prov, **arrays)
    _read_table.cache_clear()
    _cached.cache_clear()
    _best.cache_clear()
    return path


def build_tables(directory=None, *, quick: bool = False, methods=METHODS, dims=(2, 3), jobs: int = 1,
                 seed: int = 0, progress: bool = True) -> list[Path]:
    """Generate the pattern tables and write one ``.npz`` per family (atomically).

    Parameters
    ----------
    directory : path-like, optional
        Default :data:`TABLE_DIR`.
    quick : bool, optional
        Regenerate only n <= 4 of every family (seconds to a minute). Entries already in a
        table that was written by this generator version with the same parameters and seed
        are kept; the regenerated ones replace theirs.
    methods : sequence of str, optional
    dims : sequence of {2, 3}, optional
        2: the disk tables, 3: the ball tables.
    jobs : int, optional
        Worker processes.
    seed : int, optional
        Seed of every generator call (the tables of :func:`disk` / :func:`ball` use 0).
    progress : bool, optional
        A tqdm bar over the patterns.

    Returns
    -------
    list of Path
        The files written.
    """
    from tqdm.auto import tqdm

    for m in methods:
        check_choice(m, "methods", METHODS)
    jobs = check_int(jobs, "jobs")
    seed = check_int(seed, "seed", minimum=0)
    families = [(dim, m, v) for dim in dims for m in methods for v in VARIANTS[dim]]
    tasks = [(dim, m, v, n, seed) for dim, m, v in families for n in _table_counts(dim, m, v, quick)]
    # the expensive ones first, so that the workers finish together
    tasks.sort(key=lambda t: (t[1] not in ("electrostatic", "lloyd"), -t[3] * (1 + (t[0] == 3))))
    results: dict = {f: {} for f in families}
    with contextlib.ExitStack() as stack:
        bar = stack.enter_context(tqdm(total=len(tasks), desc="patterns", unit="pattern", disable=not progress))
        if jobs == 1:
            mapper = map
        else:
            from concurrent.futures import ProcessPoolExecutor

            mapper = stack.enter_context(ProcessPoolExecutor(max_workers=jobs)).map
        for task, pts, w, entry in mapper(_build_one, tasks):
            results[task[:3]][task[3]] = (pts, w, entry)
            bar.update(1)
    written = []
    for (dim, method, variant), new in results.items():
        path = _table_path(dim, method, variant, directory)
        entries = {}
        table = _read_table(str(path))
        if table is not None and _table_usable(table[0], dim, method, seed):
            entries = {n: (p, w, e) for n, (p, w, e) in table[1].items() if n not in new}
            if table[0].get("quality", {}).get("version", 1) != QUALITY_VERSION:
                entries = _rescored(entries, method)         # kept entries, current metric
        entries.update(new)
        written.append(_write_table(path, dim, method, variant, seed, entries))
    return written


def _rescore_tables(directory=None, *, methods=METHODS, dims=(3,)) -> list[Path]:
    """Re-evaluate the recorded quality of every entry of the existing tables with the current
    :func:`quality` and rewrite them (atomically), points and weights bit for bit.

    For a change of the metric alone (:data:`QUALITY_VERSION`): the generation's command and
    software stay in the provenance, the quality record names the re-evaluation. A missing
    table, or one written by another generator version or with other parameters, is skipped.

    Returns
    -------
    list of Path
        The files rewritten.
    """
    for m in methods:
        check_choice(m, "methods", METHODS)
    written = []
    for dim in dims:
        for method in methods:
            for variant in VARIANTS[dim]:
                path = _table_path(dim, method, variant, directory)
                table = _read_table(str(path))
                if table is None or not _table_usable(table[0], dim, method, table[0].get("seed")):
                    continue
                prov, entries = table
                written.append(_write_table(path, dim, method, variant, prov["seed"],
                                            _rescored(entries, method), generated=prov,
                                            command=f"python -m vobscure.patterns rescore --domain "
                                                    f"{_DOMAIN[dim]}"))
    return written


def _rescored(entries: dict, method: str) -> dict:
    """Table entries {n: (points, weights, record)} with the record's quality and its standard
    error evaluated afresh by :func:`quality`."""
    out = {}
    for n, (points, weights, record) in entries.items():
        q = quality(_exact(points, weights, method, {}))
        out[n] = (points, weights, dict(record, quality=float(q.value), quality_stderr=float(q.stderr)))
    return out


def main(argv=None) -> int:
    """``python -m vobscure.patterns build [--quick] [--jobs N] [--methods ...] [--dir DIR]``;
    ``python -m vobscure.patterns rescore [--domain ball] [--dir DIR]``: re-record the quality."""
    parser = argparse.ArgumentParser(prog="python -m vobscure.patterns",
                                     description="Precomputed sample-pattern tables (data/patterns/).")
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build", help="generate the tables")
    b.add_argument("--quick", action="store_true", help="only n <= 4 of every family")
    b.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    b.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    b.add_argument("--domain", choices=("disk", "ball", "both"), default="both")
    b.add_argument("--dir", default=None, help=f"output directory (default {TABLE_DIR})")
    b.add_argument("--no-progress", action="store_true")
    r = sub.add_parser("rescore", help="re-evaluate the recorded quality of the existing tables "
                                       "(points and weights kept)")
    r.add_argument("--domain", choices=("disk", "ball", "both"), default="ball")
    r.add_argument("--dir", default=None, help=f"table directory (default {TABLE_DIR})")
    args = parser.parse_args(argv)
    dims = {"disk": (2,), "ball": (3,), "both": (2, 3)}[args.domain]
    t0 = time.perf_counter()
    if args.command == "rescore":
        paths = _rescore_tables(args.dir, dims=dims)
    else:
        paths = build_tables(args.dir, quick=args.quick, methods=args.methods, dims=dims, jobs=args.jobs,
                             progress=not args.no_progress)
    for p in paths:
        print(p)
    print(f"{len(paths)} tables in {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 0

