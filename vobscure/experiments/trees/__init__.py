"""Hegeman et al. 2006 measured: the canopy, occluder and grass models of :mod:`vobscure.trees`
against the ray-cast sky visibility of the vegetation scenes (:mod:`vobscure.scenes.vegetation`).

Every measurement is a function returning rows (a list of dicts, one column per key) with a
``quick`` mode that runs in seconds (the figures' CI mode); ``python -m
vobscure.experiments.trees [--quick] [--seed N] [--out DIR] [--poisson]`` runs them all
(:func:`main`; with ``--poisson`` only the Poisson tables, :func:`poisson_main`) and prints
Markdown tables. The science is in the library: the models and their fits in
:mod:`vobscure.trees`, the scores in :mod:`vobscure.metrics`; this package measures them
on the scenes and lays out the rows. The figures ``hegeman_fig2``, ``hegeman_fig8``,
``hegeman_fig9``, ``hegeman_fig10``, ``hegeman_tradeoff`` and ``canopy_models`` of
:mod:`vobscure.experiments.figures` draw from these rows; ``docs/trees.md`` ("Results")
quotes them.

The ground truth is :func:`vobscure.groundtruth.ambient_occlusion` with no distance limit
(``max_distance=inf``: the sky visibility), in both hemisphere weightings, because the paper
does not say which integral its model approximates: Eq. 3 writes the uniform average
(1 / 2 pi) of V, while its renderer's 128 directions (Sec. 4) are not specified. Every model
is scored against both (column ``reference``: ``"cosine"`` or ``"uniform"``) and
:func:`weighting_rows` says which one it fits better. Beside every RMSE is the ground truth's
own standard error (``truth_stderr``, the root mean square of the per-point standard errors):
the noise floor below which an RMSE means nothing.

Measurements
------------
:func:`canopy_rows`
    Eqs. 4-6 (:func:`vobscure.trees.canopy_visibility`) and Reeves-Blau
    (:func:`vobscure.trees.reeves_blau`) at points on the leaves (:func:`leaf_points`, the
    side facing out of the crown) of the leaf clouds (Fig. 2) and the trees (Figs. 3, 4, 8):
    per shell (bounding sphere, bounding ellipsoid, k = 2..5 spheres of k-means clusters)
    and per density (fitted to the ground truth by :func:`vobscure.trees.fit_density`,
    predicted from the leaf statistics by :func:`vobscure.trees.predict_density`, and two
    controls: none (V = 1) and ten times the fitted one). Parameters are fitted on one half of
    the points (``fit_points``) and scored on the other (``points``). Reeves-Blau's k is
    fitted the same way (:func:`vobscure.trees.fit_reeves_blau`).
:func:`ground_rows`
    Fig. 9: ground points on rings around the tree's trunk, at distances from 0.15 to 2.5
    bounding-sphere radii, against :func:`vobscure.trees.occluder_visibility` with models
    ``"hegeman"`` (Eqs. 7-8), ``"exact"`` and ``"porous"``.
:func:`grass_rows`
    Fig. 10: points on grass blades (central half of the field) at known relative heights
    ``P_z / h``, against Eq. 9 (:func:`vobscure.trees.grass_visibility`), per height and
    orientation bin.
:func:`convergence_rows`
    The ray-cast estimate's RMSE at 4..256 rays per point against the high-ray reference
    (the same ground truth the models are scored against), per scene and weighting.
:func:`tradeoff_rows`
    The equal-error ray count of each model (the rays per point whose ray-cast RMSE equals
    the model's RMSE, interpolated in log-log by :func:`vobscure.metrics.equal_error_rays`)
    and the time of the model relative to that ray cast, timed in one run
    (:func:`~vobscure.experiments.common.time_calls`).
:func:`poisson_rows`
    The canopy model exact in expectation: the Poisson leaf cloud's expected
    visibility (:func:`vobscure.trees.poisson_visibility`, extinction ``n A / 2`` from the
    leaf count and size, nothing fitted) beside Eq. 6 with the *fitted* density, on the leaf
    points of :func:`canopy_rows` and per pixel (foliage pixels, and the ground pixels of the
    trees, where Hegeman's model is Eqs. 7-8), for the bounding sphere and ellipsoid; and the
    same on uniform leaf clouds with each tree's leaf count and leaf size in its shell
    (``tree_uniform``, ``tree_poplar_uniform``), which separates the error that clustering
    causes from the model's own. :func:`poisson_images` holds the per-pixel images (the
    figure ``canopy_models``).
:func:`cost_rows`
    The paper's cost claim (Sec. 4: 460 MP/s for Hegeman's shader, 580 for Reeves-Blau's, 2300
    for ambient only, i.e. 5.0 x ambient and 1.26 x Reeves-Blau) as ratios of evaluation
    times here; ambient only is writing a constant per point.

Every function takes the keyword ``measurements``: a :class:`Measurements` of the run
(``quick``, ``seed``) that keeps what its functions measured (points, ground truths, models,
the timed convergence sweep), so that functions given the same one share them; without it a
function measures what it needs and keeps nothing. :func:`all_rows` uses one for all its
tables; :func:`vobscure.experiments.figures.make` one for all the tree figures of a run.

Times are wall seconds on this machine: the ray casts use every core (Embree through
:func:`vobscure.raytrace.parallel_map`), the models are single-threaded NumPy.

Examples
--------
>>> from vobscure.experiments import trees
>>> s = trees.setting(quick=True)
>>> s["points"], s["truth_rays"], s["rays"]
(96, 64, (4, 8, 16))
"""

from __future__ import annotations

import warnings

from ._canopy import CANOPY_COLUMNS, canopy_data, canopy_images, canopy_rows, reeves_blau_rows
from ._cli import all_rows, main, poisson_main
from ._common import (
    CANOPY_SCENES,
    GRASS_SCENE,
    PAPER_MPS,
    REFERENCES,
    SETTINGS,
    TREE_SCENES,
    Measurements,
    setting,
)
from ._ground import GRASS_COLUMNS, GROUND_COLUMNS, grass_data, grass_rows, ground_data, ground_rows
from ._poisson import (
    ELLIPSOID_MAP,
    ELLIPSOID_MAP_COLUMNS,
    POISSON_COLUMNS,
    POISSON_PIXELS,
    POISSON_SCENES,
    POISSON_SHELLS,
    UNIFORM_TWINS,
    ellipsoid_map_rows,
    poisson_images,
    poisson_rows,
)
from ._tradeoff import (
    CONVERGENCE_COLUMNS,
    COST_COLUMNS,
    TRADEOFF_COLUMNS,
    WEIGHTING_COLUMNS,
    convergence_rows,
    cost_rows,
    tradeoff_rows,
    weighting_rows,
)

__all__ = ["CANOPY_SCENES", "TREE_SCENES", "GRASS_SCENE", "REFERENCES", "PAPER_MPS", "SETTINGS", "setting",
           "Measurements",
           "canopy_rows", "reeves_blau_rows", "ground_rows", "grass_rows", "convergence_rows",
           "tradeoff_rows", "cost_rows", "weighting_rows", "canopy_images", "canopy_data", "ground_data",
           "grass_data", "all_rows", "CANOPY_COLUMNS", "GROUND_COLUMNS", "GRASS_COLUMNS",
           "CONVERGENCE_COLUMNS", "TRADEOFF_COLUMNS", "COST_COLUMNS", "WEIGHTING_COLUMNS", "main",
           "poisson_rows", "poisson_images", "POISSON_COLUMNS", "POISSON_SCENES", "POISSON_SHELLS",
           "POISSON_PIXELS", "UNIFORM_TWINS", "poisson_main", "ellipsoid_map_rows", "ELLIPSOID_MAP",
           "ELLIPSOID_MAP_COLUMNS"]

#: Deprecated names of this package -> (module, name) of the function they stand for.
_MOVED = {"equal_error_rays": ("vobscure.metrics", "equal_error_rays"),
          "fit_reeves_blau": ("vobscure.trees", "fit_reeves_blau")}


def __getattr__(name: str):
    """``equal_error_rays`` and ``fit_reeves_blau`` under their names here, with a
    ``DeprecationWarning`` naming where they are: :func:`vobscure.metrics.equal_error_rays`,
    :func:`vobscure.trees.fit_reeves_blau`."""
    if name in _MOVED:
        import importlib

        module, attr = _MOVED[name]
        warnings.warn(f"vobscure.experiments.trees.{name} is deprecated; use {module}.{attr}",
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
