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
``"quick"``
    For counts no table holds (:mod:`~vobscure.patterns.quick`): the spiral, refined by one
    electrostatic relaxation with a bounded step budget (disk n <= 128, ball n <= 512), else
    returned as it is with the weights of its equal-measure bands; about a second at most.
    Deterministic.

Every method has a point-symmetric variant (``symmetric=True``, the default): antipodal pairs,
plus the centre for odd n. The screen-space estimators rely on it: a point-symmetric pattern is
exact on a plane through the ball's centre. ``center=True`` forces a sample at the origin.

The default, ``method="best"``, is the best measured pattern: per count and variant, the table
entry with the lowest recorded quality (Lloyd or electrostatic at every count of the disk
tables; see ``docs/patterns_results.md``), and ``"quick"`` where no table holds the count.

Limits: n <= :data:`SAMPLES_LIMIT` (65536) for every method; n <= 257 for the generators whose
cost grows as n^2 or faster (electrostatic, Lloyd, Poisson). Beyond them ValueError.

:func:`quality` measures any pattern with one metric (the RMS error of its VO estimate over
random planes and creases whose exact VO is known in closed form), and the defaults load from
precomputed tables in ``data/patterns/`` (``python -m vobscure.patterns build`` regenerates
them).

Modules: :mod:`~vobscure.patterns.constructors` (:func:`disk`, :func:`ball`,
:func:`best_method`), :mod:`~vobscure.patterns.generators` (the generators and
:func:`~vobscure.patterns.generators.generate`), :mod:`~vobscure.patterns.electrostatic`
(the paper's generator), :mod:`~vobscure.patterns.quick` (untabulated counts and the limits),
:mod:`~vobscure.patterns.metric` (:func:`quality` and the closed-form
volumes), :mod:`~vobscure.patterns.precomputed` (the tables: :func:`load_table`,
:func:`build_tables`); the pattern type and the discrete Voronoi diagram in ``_pattern``, what
the generators share in ``_layout``; the command line in ``__main__``.

References
----------
Loos, B. J. and Sloan, P.-P. 2010. Volumetric Obscurance. I3D 2010, Sec. 4.5, footnote 5.
Hegeman, K., Premoze, S., Ashikhmin, M. and Drettakis, G. 2006. Approximate Ambient
Occlusion for Trees. I3D 2006, Eq. 4 (the volume of a spherical cap).
Lloyd, S. P. 1982. Least squares quantization in PCM. IEEE Trans. Inf. Theory 28(2).
Shirley, P. and Chiu, K. 1997. A low distortion map between disk and square. JGT 2(3).
Vogel, H. 1979. A better way to construct the sunflower head. Math. Biosci. 44.
"""

from ._layout import OPTIMIZATION_CELLS, OPTIMIZATION_GRID, POISSON, R_MAX
from ._pattern import (BALL_GRID, DISK_GRID, SYMMETRY_ATOL, SYMMETRY_RTOL, SamplePattern, grid_cells,
                       voronoi_weights)
from .constructors import BEST, BEST_FALLBACK, ball, best_method, disk, make_pattern
from .electrostatic import ELECTROSTATIC
from .generators import GENERATOR_VERSION, LLOYD, METHODS, generate
from .metric import (FAMILIES, QUALITY_NOTES, QUALITY_SEED, QUALITY_TRIALS, QUALITY_VERSION, cap_volume,
                     crease_volume, quality, squared_errors)
from .quick import PAIR_BUDGET, QUICK, REFINE_MAX, REFINE_STEPS, SAMPLES_LIMIT, SLOW_LIMIT, SLOW_METHODS
from .precomputed import (TABLE_DIR, TABLE_EXTRA_N, TABLE_N, VARIANTS, build_tables, load_table, rescore_tables,
                          variant_flags)

__all__ = [
    "SamplePattern",
    "disk",
    "ball",
    "voronoi_weights",
    "grid_cells",
    "quality",
    "cap_volume",
    "crease_volume",
    "best_method",
    "load_table",
    "build_tables",
    "METHODS",
    "TABLE_DIR",
    "QUICK",
    "SAMPLES_LIMIT",
]
