"""The pattern generators and the weighted pattern they give (Loos & Sloan 2010, Sec. 4.5).

A generator places the free points of a :class:`~vobscure.patterns._layout.Layout` (the
antipodes and the centre follow); :func:`generate` runs one by name and adds the footnote-5
weights. The electrostatic generator, the paper's, is in :mod:`vobscure.patterns.electrostatic`.

References
----------
Lloyd, S. P. 1982. Least squares quantization in PCM. IEEE Trans. Inf. Theory 28(2).
Shirley, P. and Chiu, K. 1997. A low distortion map between disk and square. JGT 2(3).
Vogel, H. 1979. A better way to construct the sunflower head. Math. Biosci. 44.
"""

from __future__ import annotations

import numbers
import time

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import qmc

from .._validate import as_rng
from ..sampling import sobol_base, square_to_uniform_disk_concentric
from ._layout import POISSON, Layout, dart_throw, optimization_grid, to_domain
from ._pattern import (DOMAIN, SamplePattern, symmetrize_weights, voronoi_regions, voronoi_weights,
                       weighted_cells, weights_grid)
from .electrostatic import ELECTROSTATIC, electrostatic

__all__ = ["generate", "METHODS", "GENERATOR_VERSION", "ELECTROSTATIC", "LLOYD", "POISSON"]

#: Version of the generators; a table written by another version is not used.
GENERATOR_VERSION = 1
#: The generators, in the order tables and figures list them.
METHODS = ("electrostatic", "lloyd", "poisson", "sobol", "halton", "random", "spiral")
#: Parameters of Lloyd relaxation.
LLOYD = {"starts": 8, "iterations": 100}
#: The generator recorded in every provenance (the package that holds the generators).
GENERATOR = "vobscure.patterns"
#: The methods that optimize on a discrete Voronoi diagram (their provenance records its grid).
OPTIMIZERS = ("electrostatic", "lloyd")
GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


def _random(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """Independent uniform points (the half disk/ball for a symmetric layout)."""
    return to_domain(rng.random((layout.free, layout.dim)), half=layout.symmetric)


def _qmc(kind: str):
    """The generator of scrambled Sobol' (``"sobol"``) or Halton (``"halton"``) points."""
    def points(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
        k, dim = layout.free, layout.dim
        if k == 0:
            return np.zeros((0, dim))
        if kind == "sobol":
            u = sobol_base(dim, k, rng)      # a power-of-two prefix keeps Sobol' balanced
        else:
            u = qmc.Halton(d=dim, scramble=True, seed=rng).random(k)
        if dim == 2 and not layout.symmetric:
            return square_to_uniform_disk_concentric(u)
        return to_domain(u, half=layout.symmetric)
    return points


def _poisson(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """Poisson-disk dart throwing (:func:`~vobscure.patterns._layout.dart_throw`)."""
    return dart_throw(layout, rng, params)


def _spiral(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
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
        phi = j * GOLDEN_ANGLE
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
        phi = i * GOLDEN_ANGLE + s * 0.5 * GOLDEN_ANGLE
        out.append(r * np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1))
    return np.concatenate(out, axis=0)


def _lloyd(layout: Layout, rng: np.random.Generator, params: dict) -> np.ndarray:
    """Lloyd relaxation (Lloyd 1982): every free point moves to the centroid of its region.

    The standard, unweighted relaxation toward a centroidal Voronoi tessellation of the disk
    (area) or ball (volume): the paper's rival. Several Poisson starts; the one with the
    lowest centroidal energy sum_i int_{V_i} |x - x_i|^2 is kept.
    """
    if layout.free == 0:
        return np.zeros((0, layout.dim))
    cells, _ = weighted_cells(layout.dim, optimization_grid(layout.dim, layout.n))
    area = np.ones(len(cells))
    best, best_energy = None, np.inf
    for _ in range(params["starts"]):
        free = dart_throw(layout, rng)
        for _ in range(params["iterations"]):
            _, _, centroid = voronoi_regions(layout.full(free), cells, area)
            free = layout.free_centroids(centroid)
        dist, _ = cKDTree(layout.full(free)).query(cells)
        energy = float(np.sum(dist * dist))
        if energy < best_energy:
            best, best_energy = free, energy
    return best


#: Every generator by name, with its default parameters.
GENERATORS = {
    "electrostatic": (electrostatic, ELECTROSTATIC),
    "lloyd": (_lloyd, LLOYD),
    "poisson": (_poisson, POISSON),
    "sobol": (_qmc("sobol"), {}),
    "halton": (_qmc("halton"), {}),
    "random": (_random, {}),
    "spiral": (_spiral, {}),
}


def generate(dim: int, n: int, method: str, symmetric: bool, center: bool, seed,
             params: dict | None = None) -> SamplePattern:
    """Run a generator and compute the footnote-5 weights on the full grid.

    Unlike :func:`~vobscure.patterns.disk` and :func:`~vobscure.patterns.ball`, it always
    generates (no table is read) and does not validate its arguments.

    Parameters
    ----------
    dim : {2, 3}
        2: the disk, 3: the ball.
    n : int
    method : str
        One of :data:`METHODS`.
    symmetric, center : bool
        The variant (``center`` must be ``n % 2 == 1`` when ``symmetric``).
    seed : int, numpy.random.Generator or None
    params : dict, optional
        The generator's parameters; default its defaults (:data:`GENERATORS`).

    Returns
    -------
    SamplePattern
        With ``provenance`` (:func:`provenance`), its ``seconds`` and ``source`` "generated".

    Examples
    --------
    >>> p = generate(2, 5, "spiral", True, True, 0)
    >>> p.points.shape, p.is_symmetric, p.provenance["source"]
    ((5, 2), True, 'generated')
    """
    layout = Layout(dim, n, symmetric, center)
    fn, defaults = GENERATORS[method]
    params = dict(defaults) if params is None else params
    rng = as_rng(seed)
    t0 = time.perf_counter()
    free = fn(layout, rng, params)
    points = layout.ordered(free)
    w = voronoi_weights(points)
    if symmetric:
        w = symmetrize_weights(points, w)
    seconds = time.perf_counter() - t0
    prov = provenance(dim, n, method, symmetric, center, seed, params)
    prov["seconds"] = round(seconds, 3)
    prov["source"] = "generated"
    return SamplePattern(points, w, method=method, provenance=prov)


def provenance(dim, n, method, symmetric, center, seed, params) -> dict:
    """The record of one pattern: generator, version, variant, seed (an int, else None),
    parameters and grids."""
    return {"generator": GENERATOR, "version": GENERATOR_VERSION, "domain": DOMAIN[dim],
            "method": method, "n": n, "symmetric": symmetric, "center": center,
            "seed": seed if isinstance(seed, numbers.Integral) else None,
            "parameters": dict(params), "weights_grid": weights_grid(dim),
            "optimization_grid": optimization_grid(dim, n) if method in OPTIMIZERS else None}
