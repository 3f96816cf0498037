"""Patterns for the counts no table holds: a spiral, a bounded electrostatic refinement, limits.

``method="quick"`` (and ``method="best"`` where no table holds the count) builds a pattern in
about a second at most at any count up to :data:`SAMPLES_LIMIT` (measured on 2 shared cores:
0.4-1.4 s with the process's one-time tables built, 1.3-2.1 s on a process's first call;
``benchmarks/bench_patterns.py``):

1. The start is the ``"spiral"`` generator's pattern: the sunflower spiral on the disk,
   spherical-Fibonacci shells in the ball (Vogel 1979), O(n).
2. For n <= :data:`REFINE_MAX` (128 on the disk, 512 in the ball) it is refined by one
   electrostatic relaxation (Loos & Sloan 2010, Sec. 4.5;
   :func:`~vobscure.patterns.electrostatic.relax`) with a step budget
   (:func:`refinement_steps`): at most :data:`REFINE_STEPS` steps and at most
   :data:`PAIR_BUDGET` pair interactions in all, so the work is bounded by a constant whatever
   n is, and at least :data:`MIN_STEPS` (a smaller budget skips it). The weights are then the
   footnote-5 Voronoi weights on the paper's grids (512^2, 128^3).
3. Otherwise the spiral is returned as it is, with the weights of its equal-measure bands
   (:func:`band_weights`): O(n), no Voronoi diagram and no (n, n) array.

Counts above :data:`SAMPLES_LIMIT` are refused (:func:`check_count`): no few-sample estimator
needs them, and the converged screen-space VO is ``vobscure.vo_reference``.

The step budget is a count, not a wall-clock time, so the same call gives the same pattern bit
for bit on every run; the seed is not used (the spiral is deterministic).

References
----------
Loos, B. J. and Sloan, P.-P. 2010. Volumetric Obscurance. I3D 2010, Sec. 4.5, footnote 5.
Vogel, H. 1979. A better way to construct the sunflower head. Math. Biosci. 44.
"""

from __future__ import annotations

import json
import time
from functools import lru_cache

import numpy as np

from ._layout import Layout, optimization_grid
from ._pattern import DOMAIN, SamplePattern, exact_pattern, symmetrize_weights, voronoi_weights, weights_grid
from .electrostatic import ELECTROSTATIC, relax
from .generators import GENERATOR, GENERATOR_VERSION, GENERATORS

__all__ = ["quick_pattern", "refinement_steps", "band_weights", "check_count", "QUICK", "SAMPLES_LIMIT",
           "REFINE_MAX", "REFINE_STEPS", "MIN_STEPS", "PAIR_BUDGET", "SLOW_METHODS", "SLOW_LIMIT"]

#: The name of the quick generator (``method=`` of :func:`~vobscure.patterns.disk`).
QUICK = "quick"
#: The largest count any pattern is built for. A per-pixel pattern of more points than this
#: is no few-sample estimate; the converged value is what ``vobscure.vo_reference`` computes.
SAMPLES_LIMIT = 65536
#: The largest count the quick generator refines, per dimension; above it the spiral is
#: returned as it is. Measured with :func:`quality` (docs/patterns.md, "Untabulated sizes"):
#: on the disk the bounded refinement improves the sunflower up to n = 64, leaves it as it is
#: at 128 and makes it worse from 256 on; in the ball it improves the shells up to 512.
REFINE_MAX = {2: 128, 3: 512}
#: At most this many relaxation steps (a start of the full generator comes to rest in 200-400).
REFINE_STEPS = 300
#: At least this many: a budget of fewer steps skips the refinement (3 to 12 steps measured
#: worse than the start in the ball at n = 512 and 1024: the boundary charge is still settling).
MIN_STEPS = 20
#: At most this many pair interactions (free points x all points, per step, summed over the
#: steps): about half a second of repulsion on one core.
PAIR_BUDGET = 3_000_000
#: The generators whose cost grows as n^2 or faster (Poisson starts by dart throwing, then
#: relaxation with tens of starts): refused above :data:`SLOW_LIMIT` when asked for by name.
SLOW_METHODS = ("electrostatic", "lloyd", "poisson")
#: The largest count the slow generators build: the largest count the tables hold (where the
#: electrostatic generator took 5.7 minutes a pattern).
SLOW_LIMIT = 257
#: The relaxation's parameters: the full generator's, one start.
REFINE_PARAMETERS = dict(ELECTROSTATIC, starts=1, steps=REFINE_STEPS)
#: Parameters recorded in the provenance of a quick pattern.
QUICK_PARAMETERS = {"start": "spiral", "refine_max": {DOMAIN[d]: m for d, m in REFINE_MAX.items()},
                    "refine_steps": REFINE_STEPS, "min_steps": MIN_STEPS, "pair_budget": PAIR_BUDGET,
                    "relaxation": REFINE_PARAMETERS}


def check_count(n: int, method: str) -> None:
    """Refuse counts no estimator needs, and slow generators at counts they would take hours for.

    ``n`` is already a validated int >= 1; ``method`` a validated name.

    Raises
    ------
    ValueError
        Naming ``n``, the limit and what to do instead.
    """
    if n > SAMPLES_LIMIT:
        raise ValueError(
            f"n must be at most {SAMPLES_LIMIT} (the estimators' `samples` builds a pattern of n = samples "
            f"points), got {n}: a few-sample pattern that large only costs time and memory; for converged "
            f"screen-space VO use vobscure.vo_reference(gbuffer, radius=..., samples=...)")
    if method in SLOW_METHODS and n > SLOW_LIMIT:
        raise ValueError(
            f"n must be at most {SLOW_LIMIT} for method={method!r} (its cost grows as n^2 or faster: minutes "
            f"at n = {SLOW_LIMIT}), got {n}; use method='best' or method='quick' (a spiral with a bounded "
            f"electrostatic refinement, about a second) or a quasi-random method ('sobol', 'halton')")


def refinement_steps(layout: Layout) -> int:
    """The step budget of the refinement of a quick pattern.

    min(:data:`REFINE_STEPS`, :data:`PAIR_BUDGET` // (free points x n)); 0 (no refinement) when
    n exceeds :data:`REFINE_MAX` for the dimension or the budget is below :data:`MIN_STEPS`.

    Examples
    --------
    >>> refinement_steps(Layout(2, 34, True, False)), refinement_steps(Layout(3, 500, True, False))
    (300, 24)
    >>> refinement_steps(Layout(2, 200, True, False)), refinement_steps(Layout(3, 514, True, False))
    (0, 0)
    """
    if layout.n > REFINE_MAX[layout.dim] or layout.free == 0:
        return 0
    steps = int(min(REFINE_STEPS, PAIR_BUDGET // (layout.free * layout.n)))
    return steps if steps >= MIN_STEPS else 0


def band_weights(layout: Layout) -> np.ndarray:
    """Weights (n,) of the spiral's points in :meth:`Layout.ordered` order: the mass of each
    point's equal-measure band.

    The spiral gives sample j the j-th of n equal-area annuli of the disk (u = r^2 from
    (first + step j) / n to (first + step (j + 1)) / n, a symmetric pair sharing two), or an
    equal share of an equal-volume shell of the ball. A disk point's weight is the footnote-5
    mass of its annulus, the integral of the sphere's z-extent 2 sqrt(1 - r^2) over it:
    proportional to (1 - u_lo)^(3/2) - (1 - u_hi)^(3/2) (Loos & Sloan 2010, footnote 5). A
    ball point's weight is its share of the volume, 1 / n.

    Examples
    --------
    >>> w = band_weights(Layout(2, 3, True, True))
    >>> bool(w[0] > w[1] == w[2]), round(float(w.sum()), 12)
    (True, 1.0)
    """
    n = layout.n
    if layout.dim == 3:
        return np.full(n, 1.0 / n)
    step = 2 if layout.symmetric else 1
    first = 1 if layout.center else 0
    j = np.arange(layout.free)
    lo, hi = (first + step * j) / n, (first + step * (j + 1)) / n
    band = (1.0 - lo) ** 1.5 - (1.0 - hi) ** 1.5                  # Loos & Sloan 2010, footnote 5
    free = np.repeat(band / step, step)                           # a pair shares its two bands
    centre = [1.0 - (1.0 - 1.0 / n) ** 1.5] if layout.center else []
    w = np.concatenate([centre, free])
    return w / w.sum()


@lru_cache(maxsize=64)
def _quick(dim: int, n: int, symmetric: bool, center: bool) -> SamplePattern:
    layout = Layout(dim, n, symmetric, center)
    t0 = time.perf_counter()
    spiral, _ = GENERATORS["spiral"]
    start = spiral(layout, None, {})
    budget = refinement_steps(layout)
    free, done = relax(layout, start, budget, REFINE_PARAMETERS)
    points = layout.ordered(free)
    if budget == 0:
        w, weights = band_weights(layout), "spiral bands (band_weights)"
    else:
        w, weights = voronoi_weights(points), "footnote-5 Voronoi regions"
        if symmetric:
            w = symmetrize_weights(points, w)
    prov = {"generator": GENERATOR, "version": GENERATOR_VERSION, "domain": DOMAIN[dim], "method": QUICK,
            "n": n, "symmetric": symmetric, "center": center, "seed": None,
            "parameters": dict(QUICK_PARAMETERS), "weights": weights,
            "weights_grid": weights_grid(dim) if budget else None,
            "optimization_grid": optimization_grid(dim, n) if budget else None,
            "refinement": {"steps_budget": budget, "steps_done": done, "skipped": budget == 0},
            "seconds": round(time.perf_counter() - t0, 3), "source": "generated"}
    points.flags.writeable = False
    return exact_pattern(points, w, QUICK, prov)


def quick_pattern(dim: int, n: int, symmetric: bool, center: bool) -> SamplePattern:
    """The quick pattern (module docstring); cached per process, returned as a copy.

    Arguments as in :func:`~vobscure.patterns.generators.generate` (not validated; ``n`` at most
    :data:`SAMPLES_LIMIT`).

    Returns
    -------
    SamplePattern
        ``method`` ``"quick"``; ``provenance["refinement"]`` holds the step budget, the steps
        taken and whether the refinement was skipped; ``provenance["weights"]`` how the
        weights were computed.

    Examples
    --------
    >>> p = quick_pattern(2, 34, True, False)
    >>> p.points.shape, p.is_symmetric, p.provenance["refinement"]["steps_done"] <= 300
    ((34, 2), True, True)
    """
    p = _quick(dim, n, symmetric, center)
    return exact_pattern(p.points.copy(), p.weights, p.method, json.loads(json.dumps(p.provenance)))
