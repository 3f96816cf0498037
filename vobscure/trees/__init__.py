"""Analytic ambient-visibility models of trees (Hegeman et al. 2006).

``shells``: the spheres, ellipsoids and sets of shells that enclose a canopy, and their
fits to a point cloud; ``canopy``: the canopy visibility of Eqs. 4-6, the Reeves-Blau
baseline, the density (alpha rho) fitted to a reference or predicted from leaf statistics,
and Reeves-Blau's k fitted to a reference; ``poisson``: the visibility a Poisson leaf cloud
has in expectation (the chord transmittance integrated over the hemisphere, tabulated for
spheres), the one implementation that the ``"porous"`` occluder model of ``occluders``
shares. See ``docs/trees.md``.
"""

from .shells import (
    Ellipsoid,
    MultiShell,
    Sphere,
    bounding_ellipsoid,
    bounding_sphere,
    chord_length,
    shells_from_points,
)
from .canopy import (
    canopy_visibility,
    fit_density,
    fit_reeves_blau,
    optical_depth,
    predict_density,
    reeves_blau,
)
from .poisson import extinction, poisson_quadrature, poisson_visibility, sphere_transmittance
from .occluders import grass_visibility, occluder_visibility, sphere_occlusion

__all__ = [
    "Ellipsoid",
    "MultiShell",
    "Sphere",
    "bounding_ellipsoid",
    "bounding_sphere",
    "canopy_visibility",
    "chord_length",
    "fit_density",
    "fit_reeves_blau",
    "optical_depth",
    "predict_density",
    "reeves_blau",
    "shells_from_points",
    "grass_visibility",
    "occluder_visibility",
    "sphere_occlusion",
    "extinction",
    "poisson_visibility",
    "poisson_quadrature",
    "sphere_transmittance",
]
