"""Sample patterns for the screen-space estimators: disks (line/area sampling) and balls (points).

A :class:`SamplePattern` holds points in the unit disk or ball and one weight per point
(summing to 1). Weights follow Loos & Sloan 2010, footnote 5: a disk sample stands for its
Voronoi region of the disk, weighted by the sphere's z-extent over it (the integral of
2 sqrt(1 - x^2 - y^2) over the region); a ball sample for the volume of its region.
Regions are computed discretely on a grid with a KD-tree nearest-sample query.

This module provides the point-symmetric patterns the estimators need to stay exact on
planes (antipodal pairs, plus the centre for odd counts), relaxed by a symmetric Lloyd
iteration. The electrostatic generator of Sec. 4.5 and its rivals build on this module
(issue 4).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from ._validate import check_choice, check_int

__all__ = ["SamplePattern", "disk", "ball", "voronoi_weights"]

#: Grid resolution of the discrete Voronoi regions (Loos & Sloan Sec. 4.5 use 512^2 / 128^3).
DISK_GRID = 512
BALL_GRID = 128
#: Symmetric Lloyd iterations of the default patterns.
LLOYD_ITERATIONS = 30


@dataclass(frozen=True, eq=False)
class SamplePattern:
    """Points in the unit disk (n, 2) or unit ball (n, 3) with weights summing to 1.

    Attributes
    ----------
    points : (n, 2) or (n, 3) float64
    weights : (n,) float64
    method : str
    provenance : dict
        Generator, parameters and seed.
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
    def is_symmetric(self) -> bool:
        """True when the pattern equals its point reflection (points and weights)."""
        tree = cKDTree(self.points)
        dist, j = tree.query(-self.points)
        return bool(np.all(dist < 1e-9) and np.allclose(self.weights[j], self.weights, rtol=1e-9))


def _grid(dim: int, res: int) -> np.ndarray:
    c = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    g = np.stack(np.meshgrid(*([c] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    return g[np.sum(g * g, axis=1) < 1.0]


def voronoi_weights(points: np.ndarray, *, grid: int | None = None) -> np.ndarray:
    """Footnote-5 weights of disk or ball points from a discrete Voronoi diagram.

    Disk: the integral of the sphere's z-extent 2 sqrt(1 - x^2 - y^2) over each region
    (Loos & Sloan 2010, footnote 5). Ball: the volume of each region. Normalized to sum 1.
    """
    points = np.asarray(points, dtype=np.float64)
    dim = points.shape[1]
    cells = _grid(dim, grid or (DISK_GRID if dim == 2 else BALL_GRID))
    _, owner = cKDTree(points).query(cells)
    if dim == 2:
        mass = 2.0 * np.sqrt(np.maximum(0.0, 1.0 - np.sum(cells * cells, axis=1)))
    else:
        mass = np.ones(len(cells))
    w = np.bincount(owner, weights=mass, minlength=len(points))
    return w / w.sum()


def _symmetric_lloyd(dim: int, n: int, iterations: int, res: int, rng) -> np.ndarray:
    """Antipodal pairs (plus the origin for odd n), relaxed towards centroidal Voronoi."""
    pairs = n // 2
    center = n % 2 == 1
    cells = _grid(dim, res)
    # start: random points in the half space x0 > 0 (pairs) -> full symmetric set
    half = rng.normal(size=(pairs, dim))
    half /= np.linalg.norm(half, axis=1, keepdims=True)
    half *= rng.random((pairs, 1)) ** (1.0 / dim) * 0.9
    for _ in range(iterations):
        pts = np.vstack([half, -half] + ([np.zeros((1, dim))] if center else []))
        _, owner = cKDTree(pts).query(cells)
        counts = np.bincount(owner, minlength=len(pts)).astype(float)
        sums = np.stack([np.bincount(owner, weights=cells[:, k], minlength=len(pts)) for k in range(dim)], 1)
        cent = np.where(counts[:, None] > 0, sums / np.maximum(counts, 1)[:, None], pts)
        # symmetrize: a pair moves to the mean of its centroid and the reflection of its partner's
        half = 0.5 * (cent[:pairs] - cent[pairs:2 * pairs])
    pts = np.vstack([half, -half] + ([np.zeros((1, dim))] if center else []))
    r = np.linalg.norm(pts, axis=1, keepdims=True)
    return np.where(r > 1.0, pts / np.maximum(r, 1e-300), pts)


def _symmetrize_weights(points: np.ndarray, w: np.ndarray) -> np.ndarray:
    _, j = cKDTree(points).query(-points)
    return 0.5 * (w + w[j])


@lru_cache(maxsize=64)
def _cached(dim: int, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    if n == 1:
        pts = np.zeros((1, dim))
    else:
        pts = _symmetric_lloyd(dim, n, LLOYD_ITERATIONS, 256 if dim == 2 else 48, rng)
    w = _symmetrize_weights(pts, voronoi_weights(pts))
    pts.flags.writeable = False
    w.flags.writeable = False
    return pts, w


def _pattern(dim: int, n, method: str, seed) -> SamplePattern:
    """The shared body of :func:`disk` (dim 2) and :func:`ball` (dim 3)."""
    n = check_int(n, "n")
    check_choice(method, "method", ("lloyd-symmetric",))
    pts, w = _cached(dim, n, int(seed))
    return SamplePattern(pts.copy(), w.copy(), method=method,
                         provenance={"generator": f"vobscure.patterns.{'disk' if dim == 2 else 'ball'}",
                                     "n": n, "seed": int(seed), "iterations": LLOYD_ITERATIONS,
                                     "weights_grid": DISK_GRID if dim == 2 else BALL_GRID})


def disk(n: int, *, method: str = "lloyd-symmetric", seed: int = 0) -> SamplePattern:
    """A point-symmetric pattern of ``n`` points in the unit disk with footnote-5 weights.

    Odd ``n`` include the centre. Symmetry makes line and area sampling exact on planes.

    Examples
    --------
    >>> p = disk(9)
    >>> p.points.shape, p.is_symmetric, round(float(p.weights.sum()), 12)
    ((9, 2), True, 1.0)
    """
    return _pattern(2, n, method, seed)


def ball(n: int, *, method: str = "lloyd-symmetric", seed: int = 0) -> SamplePattern:
    """A point-symmetric pattern of ``n`` points in the unit ball with volume weights.

    Examples
    --------
    >>> p = ball(12)
    >>> p.points.shape, p.is_symmetric
    ((12, 3), True)
    """
    return _pattern(3, n, method, seed)
