"""The pattern type and its discrete Voronoi diagram (Loos & Sloan 2010, Sec. 4.5, footnote 5).

A :class:`SamplePattern` holds points in the unit disk or ball and one weight per point. The
weights and the regions the optimizers move points in come from one discrete Voronoi diagram:
the cells of a grid inside the disk or ball (:func:`grid_cells`), each assigned to its nearest
sample by a KD-tree query.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from .._validate import as_rng, check_int

__all__ = ["SamplePattern", "voronoi_weights", "grid_cells", "DISK_GRID", "BALL_GRID"]

#: Grid resolution of the discrete Voronoi regions that give the weights (Loos & Sloan
#: Sec. 4.5: "128^3 cells for the volume and 512^2 for the disk").
DISK_GRID = 512
BALL_GRID = 128
#: A pattern equals its point reflection when every reflected point is within this distance
#: of a point of the pattern with the same weight (relative tolerance).
SYMMETRY_ATOL = 1e-9
SYMMETRY_RTOL = 1e-9
#: Name and volume of the domain, per dimension.
DOMAIN = {2: "disk", 3: "ball"}
VOLUME = {2: np.pi, 3: 4.0 * np.pi / 3.0}


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


def exact_pattern(points, weights, method: str, provenance: dict) -> SamplePattern:
    """A validated pattern that keeps ``weights`` bit for bit.

    The weights are normalized already: normalizing again could change the last bits, and a
    table entry must equal the pattern it was generated as.
    """
    p = SamplePattern(points, weights, method=method, provenance=provenance)
    object.__setattr__(p, "weights", np.array(weights, dtype=np.float64))
    return p


def int_seed(seed) -> int | None:
    """``seed`` as an int when it is one (validated: non-negative), else None.

    An int seed gives the same result every time, so what it gives can be cached.
    """
    if isinstance(seed, numbers.Integral) and not isinstance(seed, bool):
        as_rng(seed)                                  # validates (non-negative)
        return int(seed)
    return None


def weights_grid(dim: int) -> int:
    """Cells per axis of the grid of the final weights: :data:`DISK_GRID` or :data:`BALL_GRID`."""
    return DISK_GRID if dim == 2 else BALL_GRID


def grid_cells(dim: int, res: int) -> np.ndarray:
    """Centres of the cells of a ``res``^dim grid over [-1, 1]^dim that lie inside the unit disk or ball.

    The cells of the discrete Voronoi diagram of Loos & Sloan 2010, Sec. 4.5; each stands for
    an area (2 / res)^2 of the disk or a volume (2 / res)^3 of the ball.

    Parameters
    ----------
    dim : {2, 3}
        2: the unit disk, 3: the unit ball.
    res : int
        Cells per axis (:data:`DISK_GRID`, :data:`BALL_GRID` for the weights).

    Returns
    -------
    (m, dim) float64
        The centres with |x| < 1, in C order of the grid.

    Examples
    --------
    >>> c = grid_cells(2, 4)
    >>> c.shape, c[0].tolist()
    ((12, 2), [-0.75, -0.25])
    """
    c = (np.arange(res) + 0.5) / res * 2.0 - 1.0
    g = np.stack(np.meshgrid(*([c] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    return g[np.sum(g * g, axis=1) < 1.0]


@lru_cache(maxsize=8)
def weighted_cells(dim: int, res: int) -> tuple[np.ndarray, np.ndarray]:
    """Grid cells (:func:`grid_cells`) and their mass: 2 z_s on the disk (footnote 5), 1 in the ball.

    Cached; the arrays are read-only.
    """
    cells = grid_cells(dim, res)
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
    res = check_int(grid, "grid", minimum=2) if grid is not None else weights_grid(dim)
    cells, mass = weighted_cells(dim, res)
    _, owner = cKDTree(points).query(cells)
    w = np.bincount(owner, weights=mass, minlength=len(points))
    return w / w.sum()


def symmetrize_weights(points: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Average each weight with its antipode's: the discrete diagram can split ties unevenly."""
    _, j = cKDTree(points).query(-points)
    return 0.5 * (w + w[j])


def voronoi_regions(full: np.ndarray, cells: np.ndarray, mass: np.ndarray):
    """Owner of every cell, region masses (n,) and mass-weighted centroids (n, dim)."""
    _, owner = cKDTree(full).query(cells)
    m = np.bincount(owner, weights=mass, minlength=len(full))
    sums = np.stack([np.bincount(owner, weights=mass * cells[:, a], minlength=len(full))
                     for a in range(full.shape[1])], axis=1)
    centroid = np.where(m[:, None] > 0, sums / np.maximum(m, 1e-300)[:, None], full)
    return owner, m, centroid


def equal_integral_error(m: np.ndarray) -> float:
    """RMS relative deviation of the region integrals from their mean: 0 when all are equal.

    Loos & Sloan 2010, Sec. 4.5: "the goal is to have the integral over the Voronoi region of
    every sample to be equal".
    """
    return float(np.sqrt(np.mean((m * (len(m) / m.sum()) - 1.0) ** 2)))
