"""The patterns the estimators ask for: :func:`disk`, :func:`ball` and :func:`best_method`.

A pattern comes from the precomputed tables when one holds it (:mod:`vobscure.patterns.precomputed`)
and is generated otherwise (:mod:`vobscure.patterns.generators`). The default,
``method="best"``, is the best measured pattern: per count and variant, the table entry with
the lowest recorded quality.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_rng, check_choice, check_int
from ._pattern import SamplePattern, int_seed
from . import generators
from .generators import METHODS
from .precomputed import DIM, recorded_qualities, table_or_generated
from .quick import QUICK, check_count, quick_pattern

__all__ = ["disk", "ball", "best_method", "BEST", "BEST_FALLBACK"]

#: The default ``method`` of :func:`disk` and :func:`ball`: per count and variant, the table
#: entry with the lowest recorded quality (see :func:`best_method`).
BEST = "best"
#: What ``method="best"`` uses when no table holds the count: the quick generator (a spiral
#: with a bounded electrostatic refinement, :mod:`vobscure.patterns.quick`).
BEST_FALLBACK = QUICK


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


def make_pattern(dim: int, n, method, center, symmetric, seed) -> SamplePattern:
    """The shared body of :func:`disk` (dim 2) and :func:`ball` (dim 3), positional arguments.

    Examples
    --------
    >>> make_pattern(2, 5, "spiral", None, True, 0).points.shape
    (5, 2)
    """
    n = check_int(n, "n")
    check_choice(method, "method", (BEST,) + METHODS + (QUICK,))
    check_count(n, method)
    symmetric = _check_bool(symmetric, "symmetric")
    center = _resolve_center(n, center, symmetric)
    selection = None
    if method == BEST:
        method, scores = _best(dim, n, symmetric, center)
        selection = {"rule": "lowest recorded quality among the tables holding n" if scores
                     else f"no table holds n: {BEST_FALLBACK}", "candidates": dict(scores)}
    key = int_seed(seed)
    if method == QUICK:
        if key is None:
            as_rng(seed)                              # validated; the quick pattern does not use it
        p = quick_pattern(dim, n, symmetric, center)
    elif key is None:
        p = generators.generate(dim, n, method, symmetric, center, as_rng(seed))
    else:
        p = table_or_generated(dim, n, method, symmetric, center, key)
    if selection is not None:
        p.provenance["selection"] = selection
    return p


def disk(n: int, *, method: str = BEST, center: bool | None = None, symmetric: bool = True,
         seed=0) -> SamplePattern:
    """A pattern of ``n`` points in the unit disk with footnote-5 weights, for line sampling.

    Parameters
    ----------
    n : int
        Number of samples, 1 <= n <= 65536 (:data:`~vobscure.patterns.SAMPLES_LIMIT`; larger
        counts raise ValueError: for converged values use ``vobscure.vo_reference``).
    method : str, optional
        One of :data:`METHODS`, ``"quick"``, or ``"best"`` (default): the generator whose
        table entry for this count and variant has the lowest recorded :func:`quality`
        (:func:`best_method`), and ``"quick"`` where no table holds the count (disk n <= 33
        and 64, 65, 128, 129, 256, 257 are tabulated; ball n <= 40 and the same six).
        ``pattern.method`` names the generator used.

        ``"quick"`` (:mod:`vobscure.patterns.quick`) takes about a second at most: the
        sunflower spiral (spherical-Fibonacci shells in the ball), refined by one
        electrostatic relaxation (Loos & Sloan 2010, Sec. 4.5) with a budget of at most 300
        steps and 3e6 pair interactions, for n <= 128 on the disk and n <= 512 in the ball;
        above that, or when the budget allows fewer than 20 steps, the spiral is returned as
        it is, with the weights of its equal-measure bands. It is deterministic (``seed`` is
        validated and unused); ``provenance["refinement"]`` records the budget and the steps
        taken. The named generators ``"electrostatic"``, ``"lloyd"`` and ``"poisson"`` cost
        O(n^2) or more (seconds at n = 9, minutes at n = 257) and raise ValueError above
        n = 257; the others are fast at every count.
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

    Raises
    ------
    ValueError
        Naming the argument: a bad ``n``, ``method``, ``center``, ``symmetric`` or ``seed``;
        n > 65536; n > 257 with ``"electrostatic"``, ``"lloyd"`` or ``"poisson"``.

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
    >>> q = disk(1000)                   # no table holds it: the spiral, unrefined
    >>> q.method, q.provenance["refinement"]["skipped"]
    ('quick', True)
    """
    return make_pattern(2, n, method, center, symmetric, seed)


def ball(n: int, *, method: str = BEST, center: bool | None = None, symmetric: bool = True,
         seed=0) -> SamplePattern:
    """A pattern of ``n`` points in the unit ball with volume weights, for point sampling.

    Parameters are those of :func:`disk` (the same limits: n <= 65536, the slow generators
    n <= 257, ``"quick"`` and the default about a second at any untabulated count); the
    weights are the volumes of the discrete Voronoi regions (128^3 grid, Loos & Sloan 2010,
    Sec. 4.5), or 1/n for an unrefined quick pattern (its points split the ball into
    equal-volume shares). A point sample at the centre
    lies on any surface through it and reads open (occupied means behind the surface), so
    for point sampling the even counts, without the centre, are the better symmetric ones.

    Returns
    -------
    SamplePattern
        ``points`` (n, 3), ``weights`` (n,) summing to 1.

    Raises
    ------
    ValueError
        As :func:`disk`.

    Examples
    --------
    >>> p = ball(12)
    >>> p.points.shape, p.is_symmetric
    ((12, 3), True)
    >>> ball(5, method="spiral", symmetric=False).is_symmetric
    False
    """
    return make_pattern(3, n, method, center, symmetric, seed)


def _best(dim: int, n: int, symmetric: bool, center: bool) -> tuple[str, dict]:
    """The method whose table entry (seed 0) for this count and variant has the lowest
    recorded quality, and every candidate's quality; ties go to the earlier method."""
    scores = recorded_qualities(dim, n, symmetric, center)
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
        ``"quick"`` when none does (:mod:`vobscure.patterns.quick`). The choice is made on the tables' seed-0
        patterns; another seed runs the chosen generator with that seed.

    Examples
    --------
    >>> best_method("disk", 9) in METHODS
    True
    >>> best_method("disk", 1000)      # no table holds it: the quick generator
    'quick'
    """
    check_choice(domain, "domain", ("disk", "ball"))
    n = check_int(n, "n")
    symmetric = _check_bool(symmetric, "symmetric")
    center = _resolve_center(n, center, symmetric)
    return _best(DIM[domain], n, symmetric, center)[0]
