"""What the generators share: the layout of free and derived points, uniform points in the
domain (the warps of :mod:`vobscure.sampling`), Poisson-disk starting sets and the grids of the
optimization loops.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sampling import (cube_to_uniform_ball, cube_to_uniform_half_ball, square_to_uniform_disk,
                        square_to_uniform_half_disk)
from ._pattern import VOLUME

#: Coarser grids for the Voronoi regions inside the optimization loops (Lloyd, electrostatic),
#: where they are queried hundreds of times; the final weights use DISK_GRID / BALL_GRID.
#: Large n get a finer grid, at least OPTIMIZATION_CELLS cells per region.
OPTIMIZATION_GRID = {2: 128, 3: 32}
OPTIMIZATION_CELLS = 200
#: Points farther than this from the origin are pulled back inside (relaxation steps).
R_MAX = 0.999
#: Dart throwing: candidates rejected in a row before the exclusion radius shrinks, the
#: shrink factor, and the first radius as a fraction of the mean spacing.
POISSON = {"attempts": 100, "shrink": 0.95, "first_radius": 1.0}

#: Uniform points in the domain from uniform points in [0, 1)^dim, per (dim, half).
_WARPS = {(2, False): square_to_uniform_disk, (2, True): square_to_uniform_half_disk,
          (3, False): cube_to_uniform_ball, (3, True): cube_to_uniform_half_ball}


@dataclass(frozen=True)
class Layout:
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
        return (VOLUME[self.dim] / self.n) ** (1.0 / self.dim)

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

    def free_centroids(self, centroid: np.ndarray) -> np.ndarray:
        """Centroids (free, dim) of the free points' regions, from the centroids of :meth:`full`.

        Symmetric: the mean of a point's centroid and the reflection of its antipode's, so that
        the pair moves as one.
        """
        idx = self.self_index()
        c = centroid[idx]
        if self.symmetric:
            c = 0.5 * (c - centroid[idx + self.free])
        return c


def optimization_grid(dim: int, n: int) -> int:
    """Cells per axis of the optimization grid for n samples (see :data:`OPTIMIZATION_GRID`)."""
    fill = VOLUME[dim] / 2.0 ** dim                  # fraction of the cube inside the domain
    need = math.ceil((OPTIMIZATION_CELLS * n / fill) ** (1.0 / dim))
    return max(OPTIMIZATION_GRID[dim], need)


def clip_to_domain(x: np.ndarray, r_max: float = R_MAX) -> np.ndarray:
    """Points (k, dim) with those farther than ``r_max`` from the origin pulled back to it."""
    r = np.linalg.norm(x, axis=1, keepdims=True)
    return np.where(r > r_max, x * (r_max / np.maximum(r, 1e-300)), x)


def to_domain(u: np.ndarray, *, half: bool = False) -> np.ndarray:
    """(k, dim) uniform in [0, 1)^dim -> uniform in the unit disk/ball (polar, measure-preserving).

    ``half``: in the half x_0 > 0 (disk) or z > 0 (ball), for the free points of a symmetric
    layout.
    """
    return _WARPS[u.shape[-1], bool(half)](u)


def dart_throw(layout: Layout, rng: np.random.Generator, params: dict | None = None) -> np.ndarray:
    """Poisson-disk dart throwing: the free points (free, dim) of ``layout``.

    Uniform candidates, rejected when closer than r to a sample (antipodes and the centre
    included); after ``attempts`` rejections in a row r shrinks. ``params``: default
    :data:`POISSON`.
    """
    p = POISSON if params is None else params
    k, dim = layout.free, layout.dim
    r = p["first_radius"] * layout.spacing
    fixed = [np.zeros(dim)] if layout.center else []
    free: list[np.ndarray] = []
    fails = 0
    while len(free) < k:
        x = to_domain(rng.random((1, dim)))[0]
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
