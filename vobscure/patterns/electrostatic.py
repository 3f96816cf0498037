"""The electrostatic generator of Loos & Sloan 2010, Sec. 4.5.

Particles in the unit disk or ball repel each other with a 1/d^4 force; a uniform charge on
the boundary, with the same law, keeps them inside and is optimized so that the forces push
the particles toward the weighted centroids of their Voronoi regions; a step is applied only
when it decreases the error, and tens of Poisson starts are relaxed. ``docs/patterns.md`` maps
the paper's sentences to the code.

References
----------
Loos, B. J. and Sloan, P.-P. 2010. Volumetric Obscurance. I3D 2010, Sec. 4.5.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ._layout import R_MAX, Layout, clip_to_domain, dart_throw, optimization_grid
from ._pattern import equal_integral_error, voronoi_regions, weighted_cells

__all__ = ["electrostatic", "relax", "ELECTROSTATIC", "PAIR_CHUNK"]

#: Parameters of the electrostatic generator (see :func:`electrostatic` and docs/patterns.md).
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

#: Pairs per block of the repulsion (a block of rows of the (free, n) distance matrix): memory
#: O(n * block) instead of O(n^2). The tables' counts (n <= 257) fit in one block.
PAIR_CHUNK = 1 << 16

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


def _repulsion(layout: Layout, free: np.ndarray) -> tuple[np.ndarray, float]:
    """1/d^4 repulsion on each free point from every other point, and the potential energy
    sum_{pairs} 1 / (3 d^3) of the whole set.

    The energy comes from the free points' rows alone: the antipodes' rows repeat them and the
    centre's row holds the free points' distances to the origin. The rows are taken in blocks
    of at most :data:`PAIR_CHUNK` pairs, so that memory stays O(n * block) (one block for every
    count the tables hold, where the sums are those of one array).
    """
    full = layout.full(free)
    rows_per_block = max(1, PAIR_CHUNK // len(full))
    force = np.empty_like(free)
    own = layout.self_index()
    rows = 0.0
    for a in range(0, layout.free, rows_per_block):
        b = min(layout.free, a + rows_per_block)
        diff = free[a:b, None, :] - full[None, :, :]
        d2 = np.sum(diff * diff, axis=2)
        d2[np.arange(b - a), own[a:b]] = np.inf
        d2 = np.maximum(d2, 1e-24)
        force[a:b] = np.sum(diff * (d2 ** -2.5)[:, :, None], axis=1)    # |F| = 1 / d^4, away from x_j
        rows += float(np.sum(d2 ** -1.5))
    rows /= 3.0
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

    def __init__(self, layout: Layout, free: np.ndarray, params: dict, cells, mass):
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
            _, m, _ = voronoi_regions(lay.full(free), self.cells, self.mass)
            return force, equal_integral_error(m)
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
        _, m, centroid = voronoi_regions(lay.full(self.free), self.cells, self.mass)
        r = np.linalg.norm(self.free, axis=1)
        out = np.divide(self.free, r[:, None], out=np.zeros_like(self.free), where=r[:, None] > 0)
        if self.q == 0.0:
            rep = float(np.sum(_repulsion(lay, self.free)[0] * out))
            bnd = float(np.sum(_boundary(lay.dim, self.free)[0] * out))
            self.q = -rep / bnd if bnd < 0 and rep > 0 else 1.0
            return
        g = float(np.mean(np.sum((lay.free_centroids(centroid) - self.free) * out, axis=1))) / lay.spacing
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
            trial = clip_to_domain(self.free + (self.step / big) * self.force)
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
        _, m, _ = voronoi_regions(self.layout.full(self.free), self.cells, self.mass)
        return equal_integral_error(m)


def electrostatic(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """The free points of the electrostatic generator of Loos & Sloan 2010, Sec. 4.5.

    "This process is initialized with tens of starting point sets generated using Poisson
    sampling": ``starts`` dart-throwing sets, each relaxed until it is at rest (at most
    ``steps`` steps); the one whose Voronoi regions come closest to equal integrals is kept.

    Parameters
    ----------
    layout : Layout
        Dimension, count and variant; the generator places ``layout.free`` points.
    rng : numpy.random.Generator
    params : dict
        :data:`ELECTROSTATIC` or a variation of it.

    Returns
    -------
    (layout.free, dim) float64
        The free points; ``layout.ordered`` adds the antipodes and the centre.

    References
    ----------
    Loos & Sloan 2010, Sec. 4.5; docs/patterns.md maps each sentence to the code.

    Examples
    --------
    >>> from vobscure.patterns._layout import Layout
    >>> free = electrostatic(Layout(2, 4, True, False), np.random.default_rng(0),
    ...                      dict(ELECTROSTATIC, starts=2))
    >>> free.shape, bool(np.all(np.linalg.norm(free, axis=1) < 1))
    ((2, 2), True)
    """
    if layout.free == 0:
        return np.zeros((0, layout.dim))
    cells, mass = weighted_cells(layout.dim, optimization_grid(layout.dim, layout.n))
    best, best_score = None, np.inf
    for _ in range(params["starts"]):
        run = _Relaxation(layout, dart_throw(layout, rng), params, cells, mass).run(params["steps"])
        score = run.score()
        if score < best_score:
            best, best_score = run, score
    return best.free


def relax(layout: Layout, start: np.ndarray, steps: int, params: dict | None = None) -> tuple[np.ndarray, int]:
    """One electrostatic relaxation (Loos & Sloan 2010, Sec. 4.5) from ``start``, at most ``steps`` steps.

    The loop of :func:`electrostatic` for a single given start and a hard step budget: what
    the quick patterns (:mod:`vobscure.patterns.quick`) refine their spiral with.

    Parameters
    ----------
    layout : Layout
    start : (layout.free, dim) float
        The free points to start from.
    steps : int
        Step budget (>= 0); each step costs one evaluation of the (free, n) repulsion.
    params : dict, optional
        Default :data:`ELECTROSTATIC` (its ``starts`` and ``steps`` are not used).

    Returns
    -------
    free : (layout.free, dim) float64
    steps_done : int
        Steps taken (<= ``steps``): fewer when the start came to rest first.

    Examples
    --------
    >>> from vobscure.patterns._layout import Layout
    >>> lay = Layout(2, 6, True, False)
    >>> free, done = relax(lay, np.array([[0.5, 0.1], [0.1, 0.6], [-0.4, 0.3]]), 20)
    >>> free.shape, done <= 20
    ((3, 2), True)
    """
    p = ELECTROSTATIC if params is None else params
    if layout.free == 0 or steps <= 0:
        return np.asarray(start, dtype=np.float64), 0
    cells, mass = weighted_cells(layout.dim, optimization_grid(layout.dim, layout.n))
    run = _Relaxation(layout, clip_to_domain(np.asarray(start, dtype=np.float64)), p, cells, mass).run(steps)
    return run.free, run.steps_done
