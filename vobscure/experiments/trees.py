"""Hegeman et al. 2006 measured: the canopy, occluder and grass models of :mod:`vobscure.trees`
against the ray-cast sky visibility of the vegetation scenes (:mod:`vobscure.scenes.vegetation`).

Every measurement is a function returning rows (a list of dicts, one column per key) with a
``quick`` mode that runs in seconds (the figures' CI mode); ``python -m
vobscure.experiments.trees [--quick]`` runs them all and prints Markdown tables. The figures
``hegeman_fig2``, ``hegeman_fig8``, ``hegeman_fig9``, ``hegeman_fig10`` and
``hegeman_tradeoff`` of :mod:`vobscure.experiments.figures` draw from these rows;
``docs/trees.md`` ("Results") quotes them.

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
    fitted the same way: a 1-D least-squares fit of ``log k`` (a 33-point grid, then bounded Brent,
    :func:`fit_reeves_blau`), the counterpart of ``fit_density``.
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
    the model's RMSE, interpolated in log-log by :func:`equal_error_rays`) and the time of
    the model relative to that ray cast, timed in one run (:func:`~vobscure.experiments.common.time_calls`).
:func:`poisson_rows`
    The canopy model exact in expectation (issue 15): the Poisson leaf cloud's expected
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

Times are wall seconds on this machine: the ray casts use every core (Embree through
:func:`vobscure.raytrace.parallel_map`), the models are single-threaded NumPy.

Examples
--------
>>> from vobscure.experiments import trees
>>> rays, extrapolated = trees.equal_error_rays([4, 16, 64], [0.2, 0.1, 0.05], 0.1)
>>> round(rays, 6), extrapolated
(16.0, False)
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

__all__ = ["CANOPY_SCENES", "TREE_SCENES", "GRASS_SCENE", "REFERENCES", "PAPER_MPS", "setting",
           "canopy_rows", "reeves_blau_rows", "ground_rows", "grass_rows", "convergence_rows",
           "tradeoff_rows", "cost_rows", "weighting_rows", "equal_error_rays", "fit_reeves_blau",
           "canopy_images", "canopy_data", "ground_data", "grass_data", "all_rows", "CANOPY_COLUMNS",
           "GROUND_COLUMNS", "GRASS_COLUMNS",
           "CONVERGENCE_COLUMNS", "TRADEOFF_COLUMNS", "COST_COLUMNS", "WEIGHTING_COLUMNS", "main",
           "poisson_rows", "poisson_images", "POISSON_COLUMNS", "POISSON_SCENES", "UNIFORM_TWINS",
           "poisson_main", "ellipsoid_map_rows", "ELLIPSOID_MAP_COLUMNS"]

#: The scenes with a canopy (registered names of :func:`vobscure.scenes.get`): the sparse and
#: dense leaf clouds of Fig. 2 and the two trees (apple-like, poplar-like) of Figs. 3-9.
CANOPY_SCENES = ("leaf_cloud", "leaf_cloud_dense", "tree", "tree_poplar")
#: The scenes with a tree standing on the ground (Fig. 9's ground points).
TREE_SCENES = ("tree", "tree_poplar")
#: The grass field of Fig. 10.
GRASS_SCENE = "grass"
#: The two hemisphere integrals the models are scored against: ``weighting`` of
#: :func:`vobscure.groundtruth.ambient_occlusion`, with ``max_distance=inf``.
REFERENCES = ("cosine", "uniform")
#: Hegeman et al. 2006, Sec. 4: NVShaderPerf throughput of the three fragment shaders on a
#: GeForce 6800 Ultra, megapixels per second.
PAPER_MPS = {"hegeman": 460.0, "reeves_blau": 580.0, "ambient": 2300.0}

#: Sizes of a run (full, quick): points sampled per scene (half fit, half scored), rays of the
#: ground truth, ray counts of the convergence sweep, shells of the multi-shell fits, ring
#: distances (bounding-sphere radii) and points per ring of Fig. 9, grass points, bins,
#: points the models are timed on, and timing repeats.
SETTINGS = {
    False: {"points": 2048, "truth_rays": 1024, "rays": (4, 8, 16, 32, 64, 128, 256),
            "multi_k": (2, 3, 4, 5), "rings": (0.15, 0.3, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 2.5),
            "ring_points": 64, "grass_points": 2048, "height_bins": 10, "cos_bins": 2,
            "timing_points": 65536, "raycast_timing_points": 8192, "repeats": 3},
    True: {"points": 96, "truth_rays": 64, "rays": (4, 8, 16),
           "multi_k": (2, 4), "rings": (0.3, 1.0, 2.0), "ring_points": 8, "grass_points": 96,
           "height_bins": 4, "cos_bins": 2, "timing_points": 4096, "raycast_timing_points": 96,
           "repeats": 1},
}

#: Columns of :func:`canopy_rows` (and :func:`reeves_blau_rows`).
CANOPY_COLUMNS = ("scene", "kind", "model", "shell", "shells", "source", "parameter", "refit", "reference",
                  "rmse", "bias", "mae", "corr", "rmse_calibration", "model_mean", "truth_mean", "truth_stderr",
                  "points", "fit_points", "truth_rays")
#: Columns of :func:`ground_rows`.
GROUND_COLUMNS = ("scene", "model", "reference", "distance", "distance_r", "sphere_radius", "rmse",
                  "bias", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")
#: Columns of :func:`grass_rows`.
GRASS_COLUMNS = ("scene", "model", "reference", "height_lo", "height_hi", "cos_lo", "cos_hi", "rmse",
                 "bias", "corr", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")
#: Columns of :func:`convergence_rows`.
CONVERGENCE_COLUMNS = ("scene", "points_on", "reference", "rays", "rmse", "rmse_corrected",
                       "reference_stderr", "rmse_sqrt_rays", "points", "reference_rays")
#: Columns of :func:`tradeoff_rows`.
TRADEOFF_COLUMNS = ("scene", "points_on", "model", "reference", "model_rmse", "model_rmse_corrected",
                    "equal_rays", "extrapolated", "lower_bound", "model_us", "raycast_us", "time_ratio",
                    "speedup", "speedup_cpu", "reference_stderr", "points", "timing_points",
                    "raycast_timing_points")
#: Columns of :func:`cost_rows`.
COST_COLUMNS = ("scene", "shader", "us_per_point", "vs_ambient", "vs_reeves_blau", "paper_vs_ambient",
                "paper_vs_reeves_blau", "timing_points", "repeats")
#: Columns of :func:`weighting_rows`.
WEIGHTING_COLUMNS = ("scene", "what", "model", "rmse_cosine", "rmse_uniform", "better",
                     "stderr_cosine", "stderr_uniform")

#: Columns of :func:`poisson_rows`.
POISSON_COLUMNS = ("scene", "kind", "points_on", "model", "shell", "parameter", "reference", "rmse", "bias",
                   "corr", "model_mean", "truth_mean", "truth_stderr", "points", "truth_rays")
#: The uniform leaf clouds that stand beside the clustered trees: name -> the tree.
UNIFORM_TWINS = {"tree_uniform": "tree", "tree_poplar_uniform": "tree_poplar"}
#: Every scene of :func:`poisson_rows`.
POISSON_SCENES = CANOPY_SCENES + tuple(UNIFORM_TWINS)
#: The shells of :func:`poisson_rows`.
POISSON_SHELLS = ("sphere", "ellipsoid")
#: Per-pixel sizes of :func:`poisson_rows` (full, quick): image size and rays per pixel.
POISSON_PIXELS = {False: {"size": (96, 96), "rays": 256}, True: {"size": (24, 24), "rays": 32}}

#: Equal-count bins of the model's value in ``rmse_calibration`` (:func:`canopy_rows`).
CALIBRATION_BINS = 10
#: Bounds of the log-spaced grid that checks :func:`vobscure.trees.fit_density`'s answer.
LOG_DENSITY_BOUNDS = (math.log(1e-4), math.log(1e5))
#: Bounds of log(k) in the fit of Reeves-Blau's k (k in 1/length; the scenes are metres-ish).
LOG_K_BOUNDS = (math.log(1e-4), math.log(1e4))


def setting(quick: bool) -> dict:
    """The sizes of a run (:data:`SETTINGS`), full or ``quick``."""
    return dict(SETTINGS[bool(quick)])


# ----------------------------------------------------------------------------- helpers
@lru_cache(maxsize=None)
def _scene(name: str):
    from .. import scenes

    return scenes.get(name)


def _truth(scene, points, normals, reference, rays, seed):
    from ..groundtruth import ambient_occlusion

    return ambient_occlusion(scene, points, normals, rays=rays, weighting=reference,
                             max_distance=np.inf, seed=seed)


def _corr(a, b) -> float | None:
    """Pearson r; None (an empty cell) where undefined, e.g. a constant model (density 0)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if len(a) < 3 or np.std(a) == 0 or np.std(b) == 0:
        return None
    return float(np.corrcoef(a, b)[0, 1])


def _scores(model, truth: "Estimate") -> dict:   # noqa: F821 - Estimate of vobscure.estimate
    """RMSE, bias, MAE, Pearson r, means and the truth's RMS stderr of ``model`` against it."""
    model = np.asarray(model, dtype=np.float64)
    t = np.asarray(truth.value, dtype=np.float64)
    diff = model - t
    return {"rmse": float(np.sqrt(np.mean(diff ** 2))), "bias": float(np.mean(diff)),
            "mae": float(np.mean(np.abs(diff))), "corr": _corr(model, t),
            "model_mean": float(np.mean(model)), "truth_mean": float(np.mean(t)),
            "truth_stderr": float(np.sqrt(np.mean(np.asarray(truth.stderr, float) ** 2))),
            "points": int(len(t))}


def _calibration(model, truth_value, bins: int = CALIBRATION_BINS) -> float:
    """RMSE of the model's bin means against the truth's bin means, the points binned by the
    model's value (equal counts) and weighted by count: the error of the model as a predictor
    of the *average* visibility of the points it gives one value (Hegeman's <V>, the ensemble
    mean of Sec. 3), without the point-to-point scatter no local model can follow."""
    model = np.asarray(model, dtype=np.float64)
    t = np.asarray(truth_value, dtype=np.float64)
    order = np.argsort(model, kind="stable")
    groups = np.array_split(order, min(bins, len(order)))
    sq = sum(len(g) * (model[g].mean() - t[g].mean()) ** 2 for g in groups if len(g))
    return float(np.sqrt(sq / len(model)))


def _sub(estimate, index):
    from ..estimate import Estimate

    return Estimate(value=np.asarray(estimate.value)[index], stderr=np.asarray(estimate.stderr)[index],
                    samples=estimate.samples)


def _grid_then_brent(loss, bounds, points: int = 33) -> tuple[float, float]:
    """Minimize ``loss(log_x)``: a log-spaced grid over ``bounds``, then a bounded Brent search
    between the best grid point's neighbours. Returns (log_x, loss)."""
    from scipy.optimize import minimize_scalar

    grid = np.linspace(*bounds, points)
    values = [loss(g) for g in grid]
    best = int(np.argmin(values))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)]
    res = minimize_scalar(loss, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6})
    if res.fun <= values[best]:
        return float(res.x), float(res.fun)
    return float(grid[best]), float(values[best])


def _fit_density_checked(points, normals, shell, reference) -> tuple[float, bool]:
    """:func:`vobscure.trees.fit_density`, checked against a grid search over
    :data:`LOG_DENSITY_BOUNDS` (:func:`_grid_then_brent`); the grid's answer replaces it when
    its squared error is lower by more than 1e-9 relative (``refit`` True)."""
    from .. import trees as T

    ref = np.asarray(reference, dtype=np.float64)

    def loss_of(density):
        return float(np.sum((T.canopy_visibility(points, normals, shell, density=density) - ref) ** 2))

    fitted = float(T.fit_density(points, normals, shell, ref))
    log_x, grid_loss = _grid_then_brent(lambda x: loss_of(math.exp(x)), LOG_DENSITY_BOUNDS)
    if grid_loss < loss_of(fitted) * (1 - 1e-9):
        return math.exp(log_x), True
    return fitted, False


def fit_reeves_blau(points, shell, reference, *, weights=None) -> float:
    """The k of :func:`vobscure.trees.reeves_blau` that minimizes the (weighted) squared error
    against ``reference``: a 1-D least-squares fit of ``log k``, a 33-point grid then bounded Brent over
    :data:`LOG_K_BOUNDS`, the counterpart of :func:`vobscure.trees.fit_density`.

    Parameters
    ----------
    points : (n, 3) float
    shell : Sphere, Ellipsoid or MultiShell
    reference : (n,) float
        Visibility to fit (a ground truth's ``value``).
    weights : (n,) float, optional
        Non-negative weights of the squared errors (default 1).

    Returns
    -------
    float
        k > 0.
    """
    from .. import trees as T

    ref = np.asarray(reference, dtype=np.float64)
    w = np.ones_like(ref) if weights is None else np.asarray(weights, dtype=np.float64)

    def loss(log_k):
        return float(np.sum(w * (T.reeves_blau(points, shell, k=math.exp(log_k)) - ref) ** 2))

    # a coarse grid first: the loss need not be unimodal in log k over eight decades
    return float(math.exp(_grid_then_brent(loss, LOG_K_BOUNDS)[0]))


def equal_error_rays(rays, rmse, target) -> tuple[float, bool]:
    """Rays per point at which the ray cast's RMSE equals ``target``, by linear interpolation of
    log RMSE against log rays.

    The measured RMSE is made non-increasing first (a running minimum), so the answer is
    monotone (non-increasing) in ``target``. Outside the measured range the line through the
    two end points' slope fitted to all points (least squares in log-log) is extrapolated.

    Parameters
    ----------
    rays : sequence of int
        Increasing ray counts.
    rmse : sequence of float
        The ray cast's RMSE at each count (> 0).
    target : float
        The RMSE to match (> 0).

    Returns
    -------
    rays : float
        The equal-error ray count (not rounded).
    extrapolated : bool
        Whether ``target`` lay outside the measured RMSE range.

    Examples
    --------
    >>> rays, extrapolated = equal_error_rays([4, 16], [0.2, 0.1], 0.05)   # slope -1/2 extended
    >>> round(rays, 6), extrapolated
    (64.0, True)
    """
    r = np.asarray(rays, dtype=np.float64)
    e = np.minimum.accumulate(np.asarray(rmse, dtype=np.float64))
    if r.ndim != 1 or len(r) < 2 or len(e) != len(r) or np.any(np.diff(r) <= 0):
        raise ValueError("rays must be at least two increasing counts, one RMSE each")
    if not np.all(e > 0) or not target > 0:
        raise ValueError("RMSE values and target must be positive")
    lr, le, lt = np.log(r), np.log(e), math.log(float(target))
    slope = float(np.polyfit(lr, le, 1)[0]) if np.ptp(le) > 0 else -0.5
    slope = min(slope, -1e-3)        # a flat curve would send the extrapolation to infinity
    if lt > le[0]:
        return float(math.exp(lr[0] + (lt - le[0]) / slope)), True
    if lt < le[-1]:
        return float(math.exp(lr[-1] + (lt - le[-1]) / slope)), True
    # le is non-increasing: interpolate on the reversed (non-decreasing) arrays
    return float(math.exp(np.interp(lt, le[::-1], lr[::-1]))), False


# ----------------------------------------------------------------------------- canopy data
def _shells(scene, quick, seed) -> dict:
    """label -> (shell, number of shells): bounding sphere, bounding ellipsoid, k spheres."""
    from .. import trees as T

    cp = np.asarray(scene.metadata["canopy_points"], dtype=np.float64)
    shells = {"sphere": (T.bounding_sphere(cp), 1), "ellipsoid": (T.bounding_ellipsoid(cp), 1)}
    for k in setting(quick)["multi_k"]:
        shells[f"{k} spheres"] = (T.shells_from_points(cp, k, kind="sphere", seed=seed), k)
    return shells


@lru_cache(maxsize=None)
def _canopy(name: str, quick: bool, seed: int) -> dict:
    """Points on a canopy scene's leaves, their ground truths, shells and every model's values
    (cached per process: every canopy figure and the trade-off share it)."""
    from .. import trees as T
    from ..scenes import leaf_points

    s = setting(quick)
    scene = _scene(name)
    points, normals = leaf_points(scene, s["points"], seed=seed)
    fit, score = np.arange(0, len(points), 2), np.arange(1, len(points), 2)
    truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 1 + i)
             for i, w in enumerate(REFERENCES)}
    md = scene.metadata
    shells = _shells(scene, quick, seed)
    configs = []
    for label, (shell, k) in shells.items():
        # predict_density takes one shell (the leaves uniform in it): not a MultiShell
        predicted = None if k > 1 else float(T.predict_density(md["n_leaves"], md["leaf_area"], shell))
        for w in REFERENCES:
            fitted, refit = _fit_density_checked(points[fit], normals[fit], shell, truth[w].value[fit])
            sources = [("fitted", fitted)] + ([("predicted", predicted)] if predicted is not None else [])
            if label == "sphere":
                sources += [("none", 0.0), ("fitted x10", 10.0 * fitted)]
            for source, density in sources:
                v = T.canopy_visibility(points[score], normals[score], shell, density=density)
                configs.append({"model": "hegeman", "shell": label, "shells": k, "source": source,
                                "parameter": density, "reference": w, "values": v, "shell_obj": shell,
                                "refit": refit and source in ("fitted", "fitted x10")})
            if label in ("sphere", "ellipsoid"):
                kk = fit_reeves_blau(points[fit], shell, truth[w].value[fit])
                v = T.reeves_blau(points[score], shell, k=kk)
                configs.append({"model": "reeves_blau", "shell": label, "shells": k, "source": "fitted",
                                "parameter": kk, "reference": w, "values": v, "shell_obj": shell,
                                "refit": False})
    return {"scene": scene, "points": points, "normals": normals, "fit": fit, "score": score,
            "truth": truth, "shells": shells, "configs": configs, "truth_rays": s["truth_rays"]}


def canopy_rows(quick: bool = False, *, seed: int = 0, scenes=CANOPY_SCENES) -> list[dict]:
    """Eqs. 4-6 and Reeves-Blau against the sky visibility at points on the leaves.

    One row per (scene, model, shell, density source, reference); columns
    :data:`CANOPY_COLUMNS`. ``parameter`` is the density alpha rho of Eq. 6 (model
    ``"hegeman"``) or Reeves-Blau's k; ``source`` says where it came from (``"fitted"`` to
    this reference on the fit half, ``"predicted"`` from the leaf statistics, ``"none"``: 0,
    ``"fitted x10"``). Scores are over the other half (``points``). ``refit`` marks a
    density where :func:`vobscure.trees.fit_density`'s answer had a larger squared error than
    a grid search's, which replaced it (:func:`_fit_density_checked`). ``rmse_calibration``
    is the RMSE of the model's bin means against the truth's (:data:`CALIBRATION_BINS` equal-count
    bins of the model's value): the error in the *average* visibility the model predicts,
    Hegeman's ensemble mean <V>, without the point-to-point scatter.
    """
    rows = []
    for name in scenes:
        d = _canopy(name, bool(quick), int(seed))
        kind = d["scene"].metadata.get("kind", "")
        for c in d["configs"]:
            truth = _sub(d["truth"][c["reference"]], d["score"])
            sc = _scores(c["values"], truth)
            rows.append({"scene": name, "kind": kind, "model": c["model"], "shell": c["shell"],
                         "shells": c["shells"], "source": c["source"], "parameter": c["parameter"],
                         "refit": c["refit"], "reference": c["reference"], **sc,
                         "rmse_calibration": _calibration(c["values"], truth.value),
                         "fit_points": int(len(d["fit"])), "truth_rays": d["truth_rays"]})
    return rows


def reeves_blau_rows(quick: bool = False, *, seed: int = 0, scenes=CANOPY_SCENES) -> list[dict]:
    """Reeves-Blau against Hegeman (Figs. 4, 12) on the same points: the rows of
    :func:`canopy_rows` with a fitted parameter on the bounding sphere and ellipsoid."""
    return [r for r in canopy_rows(quick, seed=seed, scenes=scenes)
            if r["source"] == "fitted" and r["shell"] in ("sphere", "ellipsoid")]


def canopy_images(name: str, *, size=(64, 64), rays: int = 128, seed: int = 0, quick: bool = False,
                  shells=("sphere",)):
    """Per-pixel images of a canopy scene (Fig. 2): the ray-cast cosine sky visibility of the
    visible leaves (the G-buffer's normal, turned toward the camera) and Eq. 6 on each of
    ``shells`` (labels of :func:`canopy_data`'s shells) with the density fitted to the cosine
    reference at points (:func:`canopy_rows`).

    Returns
    -------
    dict
        ``truth`` (H, W), NaN off the foliage (background and, for a tree, ground and wood),
        ``stderr`` (H, W), ``models`` (shell label -> (H, W)) and ``densities`` (shell label
        -> density); ``model`` and ``density`` are those of the first shell.
    """
    from .. import trees as T
    from ..camera import Camera
    from ..gbuffer import render_gbuffer

    scene = _scene(name)
    v = scene.view
    kw = {"fov_y": v["fov_y"]} if "fov_y" in v else {"ortho_height": v["ortho_height"]}
    cam = Camera.look_at(v["eye"], v["target"], up=v.get("up", (0, 1, 0)), size=tuple(size), **kw)
    gb = render_gbuffer(scene, cam)
    d = _canopy(name, bool(quick), int(seed))
    densities = {label: next(c["parameter"] for c in d["configs"] if c["model"] == "hegeman"
                             and c["shell"] == label and c["source"] == "fitted" and c["reference"] == "cosine")
                 for label in shells}
    valid = np.asarray(gb.valid)
    truth = np.full(valid.shape, np.nan)
    models = {label: np.full(valid.shape, np.nan) for label in shells}
    stderr = np.full(valid.shape, np.nan)
    pos = np.asarray(gb.world_position)[valid]
    nrm = np.asarray(gb.world_normal)[valid]
    foliage = _on_foliage(scene, gb, valid)
    pos, nrm = pos[foliage], nrm[foliage]
    if len(pos):
        e = _truth(scene, pos, nrm, "cosine", rays, seed + 7)
        idx = np.flatnonzero(valid.ravel())[foliage]
        truth.ravel()[idx] = e.value
        stderr.ravel()[idx] = e.stderr
        for label in shells:
            models[label].ravel()[idx] = T.canopy_visibility(pos, nrm, d["shells"][label][0],
                                                             density=densities[label])
    first = shells[0]
    return {"truth": truth, "stderr": stderr, "models": models, "densities": densities,
            "model": models[first], "density": densities[first]}


def _on_foliage(scene, gb, valid) -> np.ndarray:
    """Which valid pixels show the foliage mesh (the G-buffer's hit triangle's mesh)."""
    index = list(scene.meshes).index(scene.metadata.get("foliage_mesh"))
    return np.asarray(scene.mesh_index)[np.asarray(gb.primitive)[valid]] == index


def canopy_data(name: str, quick: bool = False, *, seed: int = 0) -> dict:
    """The points behind :func:`canopy_rows` for one scene (cached per process): ``points``,
    ``normals`` (n, 3); ``fit`` and ``score`` index arrays; ``truth`` (reference -> Estimate
    over all n points); ``shells`` (label -> (shell, count)); ``configs``: one dict per
    model configuration with ``values`` over the ``score`` points. Read only."""
    return _canopy(str(name), bool(quick), int(seed))


def ground_data(name: str, quick: bool = False, *, seed: int = 0) -> dict:
    """The ground points behind :func:`ground_rows` (cached per process): ``points``,
    ``distance`` (n,), ``radius`` (the bounding sphere's), ``truth`` (reference -> Estimate),
    ``values`` ((model, reference) -> (n,)), ``sigma`` of the porous model. Read only."""
    return _ground(str(name), bool(quick), int(seed))


def grass_data(quick: bool = False, *, seed: int = 0) -> dict:
    """The blade points behind :func:`grass_rows` (cached per process): ``points``,
    ``height`` (P_z / h), ``cos`` (cos theta), ``blade_height``, ``truth`` (reference ->
    Estimate), ``model`` (Eq. 9). Read only."""
    return _grass(bool(quick), int(seed))


# ----------------------------------------------------------------------------- Poisson (issue 15)
@lru_cache(maxsize=None)
def _uniform_twin(name: str, seed: int):
    """A uniform leaf cloud with the tree's leaf count and leaf size in the tree's bounding
    sphere (the sphere rows) or, as ``(sphere twin, ellipsoid twin)``, in its crown ellipsoid
    (``canopy_radii``, axis-aligned, the ellipsoid rows)."""
    from .. import scenes
    from .. import trees as T

    tree = _scene(UNIFORM_TWINS[name])
    md = tree.metadata
    n, size = int(md["n_leaves"]), float(md["parameters"]["leaf_size"])
    R = float(T.bounding_sphere(np.asarray(md["canopy_points"], dtype=np.float64)).radius)
    sphere = scenes.leaf_cloud(n, radii=R, leaf_size=size, seed=seed + 100, name=name)
    ellipsoid = scenes.leaf_cloud(n, shape="ellipsoid", radii=tuple(md["canopy_radii"]), leaf_size=size,
                                  seed=seed + 200, name=f"{name} (ellipsoid)")
    return sphere, ellipsoid


@lru_cache(maxsize=None)
def _poisson_leaves(name: str, shell_label: str, quick: bool, seed: int) -> dict:
    """Leaf points, their truth and both models for one scene and shell (scored half)."""
    from .. import trees as T
    from ..scenes import leaf_points

    s = setting(quick)
    if name in CANOPY_SCENES:
        d = _canopy(name, quick, seed)
        scene, points, normals, fit, score, truth = (d["scene"], d["points"], d["normals"], d["fit"], d["score"],
                                                     d["truth"])
        shell = d["shells"][shell_label][0]
        fitted = {c["reference"]: (c["parameter"], c["values"]) for c in d["configs"]
                  if c["model"] == "hegeman" and c["shell"] == shell_label and c["source"] == "fitted"}
    else:
        scene = _uniform_twin(name, seed)[0 if shell_label == "sphere" else 1]
        points, normals = leaf_points(scene, s["points"], seed=seed)
        fit, score = np.arange(0, len(points), 2), np.arange(1, len(points), 2)
        truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 1 + i)
                 for i, w in enumerate(REFERENCES)}
        cp = np.asarray(scene.metadata["canopy_points"], dtype=np.float64)
        shell = T.bounding_sphere(cp) if shell_label == "sphere" else T.bounding_ellipsoid(cp)
        fitted = {}
        for w in REFERENCES:
            rho, _ = _fit_density_checked(points[fit], normals[fit], shell, truth[w].value[fit])
            fitted[w] = (rho, T.canopy_visibility(points[score], normals[score], shell, density=rho))
    md = scene.metadata
    sigma = T.extinction(md["n_leaves"], md["leaf_area"], shell)
    poisson = {w: T.poisson_visibility(points[score], normals[score], shell, extinction=sigma, weighting=w)
               for w in REFERENCES}
    return {"scene": scene, "shell": shell, "sigma": sigma, "fitted": fitted, "poisson": poisson,
            "points": points[score], "normals": normals[score],
            "truth": {w: _sub(truth[w], score) for w in REFERENCES}, "truth_rays": s["truth_rays"]}


@lru_cache(maxsize=None)
def _poisson_pixels(name: str, shell_label: str, quick: bool, seed: int) -> dict:
    """Per-pixel truth (both weightings) and both models on one scene's view."""
    from .. import trees as T
    from ..camera import Camera
    from ..gbuffer import render_gbuffer

    px = POISSON_PIXELS[bool(quick)]
    leaves = _poisson_leaves(name, shell_label, quick, seed)
    scene, shell, sigma = leaves["scene"], leaves["shell"], leaves["sigma"]
    v = scene.view
    kw = {"fov_y": v["fov_y"]} if "fov_y" in v else {"ortho_height": v["ortho_height"]}
    cam = Camera.look_at(v["eye"], v["target"], up=v.get("up", (0, 1, 0)), size=tuple(px["size"]), **kw)
    gb = render_gbuffer(scene, cam)
    valid = np.asarray(gb.valid)
    H, W = valid.shape
    pos = np.asarray(gb.world_position, dtype=np.float64)[valid]
    nrm = np.asarray(gb.world_normal, dtype=np.float64)[valid]
    names = list(scene.meshes)
    mesh = np.asarray(scene.mesh_index)[np.asarray(gb.primitive)[valid]]
    foliage = mesh == names.index(scene.metadata["foliage_mesh"])
    ground = (mesh == names.index("ground")) if "ground" in names else np.zeros(len(pos), bool)
    use = foliage | ground
    idx = np.flatnonzero(valid.ravel())[use]
    pos, nrm, foliage, ground = pos[use], nrm[use], foliage[use], ground[use]

    def image(values):
        out = np.full(H * W, np.nan)
        out[idx] = values
        return out.reshape(H, W)

    truth, hegeman, poisson = {}, {}, {}
    sphere = T.bounding_sphere(np.asarray(scene.metadata["canopy_points"], dtype=np.float64))
    for i, w in enumerate(REFERENCES):
        truth[w] = _truth(scene, pos, nrm, w, px["rays"], seed + 31 + i)
        rho = leaves["fitted"][w][0]
        h = np.empty(len(pos))
        h[foliage] = T.canopy_visibility(pos[foliage], nrm[foliage], shell, density=rho)      # Eqs. 4-6
        if ground.any():                                                                     # Eqs. 7-8
            h[ground] = T.occluder_visibility(pos[ground], nrm[ground], sphere, model="hegeman")
        hegeman[w] = h
        poisson[w] = T.poisson_visibility(pos, nrm, shell, extinction=sigma, weighting=w)
    return {"foliage": foliage, "ground": ground, "truth": truth, "hegeman": hegeman, "poisson": poisson,
            "image": image, "rays": px["rays"], "size": (H, W)}


def poisson_rows(quick: bool = False, *, seed: int = 0, scenes=POISSON_SCENES) -> list[dict]:
    """The Poisson leaf cloud's expected visibility, predicted, beside Eq. 6 with the fitted
    density, against the ray-cast sky visibility.

    One row per (scene, points_on, model, shell, reference); columns
    :data:`POISSON_COLUMNS`. ``points_on``: ``"leaves"`` (the scored half of the leaf points
    of :func:`canopy_rows`; for the uniform twins their own leaf points), ``"foliage pixels"``
    and ``"ground pixels"`` (trees only; Hegeman's model there is Eqs. 7-8 of the bounding
    sphere) of the scene's view at :data:`POISSON_PIXELS`. ``model``: ``"hegeman fitted"``
    (``parameter`` = alpha rho fitted on the fit half of the leaf points to that reference)
    or ``"poisson predicted"`` (``parameter`` = sigma = n A / 2 from the leaf statistics,
    nothing fitted). ``truth_stderr`` is the reference's RMS standard error (its noise floor).
    The scenes ``tree_uniform`` and ``tree_poplar_uniform`` (:data:`UNIFORM_TWINS`) are
    uniform leaf clouds with each tree's leaf count and leaf size, in its bounding sphere (the
    sphere rows) or its crown ellipsoid (the ellipsoid rows): the Poisson model's error there
    is its own, the difference on the tree is the clustering's.
    """
    rows = []
    for name in scenes:
        for label in POISSON_SHELLS:
            lv = _poisson_leaves(name, label, bool(quick), int(seed))
            kind = lv["scene"].metadata.get("kind", "")
            pix = _poisson_pixels(name, label, bool(quick), int(seed))
            for w in REFERENCES:
                rho, hv = lv["fitted"][w]
                groups = [("leaves", hv, lv["poisson"][w], lv["truth"][w], lv["truth_rays"])]
                for where, mask in (("foliage pixels", pix["foliage"]), ("ground pixels", pix["ground"])):
                    if mask.any():
                        idx = np.flatnonzero(mask)
                        groups.append((where, pix["hegeman"][w][idx], pix["poisson"][w][idx],
                                       _sub(pix["truth"][w], idx), pix["rays"]))
                for where, h, p, truth, rays in groups:
                    for model, values, param in (("hegeman fitted", h, rho), ("poisson predicted", p, lv["sigma"])):
                        sc = _scores(values, truth)
                        del sc["mae"]
                        rows.append({"scene": name, "kind": kind, "points_on": where, "model": model,
                                     "shell": label, "parameter": float(param), "reference": w, **sc,
                                     "truth_rays": int(rays)})
    return rows


#: Columns of :func:`ellipsoid_map_rows`.
ELLIPSOID_MAP_COLUMNS = ("scene", "reference", "radii", "sigma", "rmse_map", "max_map", "bias_map",
                         "rmse_truth_map", "rmse_truth_exact", "truth_stderr", "points", "nodes")
#: Leaf points and quadrature nodes of :func:`ellipsoid_map_rows` (full, quick).
ELLIPSOID_MAP = {False: {"points": 256, "nodes": 64}, True: {"points": 12, "nodes": 24}}


def ellipsoid_map_rows(quick: bool = False, *, seed: int = 0,
                       scenes=("tree", "tree_poplar", "tree_uniform", "tree_poplar_uniform")) -> list[dict]:
    """The affine map of an ellipsoid (Hegeman 2006, Sec. 3), as :func:`vobscure.trees.poisson_visibility`
    uses it, against the Poisson leaf cloud's expected visibility in the true ellipsoid
    (:func:`vobscure.trees.poisson_quadrature`, brute-force quadrature over the hemisphere).

    On the first ``points`` scored leaf points of :func:`poisson_rows` (ellipsoid shell):
    ``rmse_map``, ``max_map`` and ``bias_map`` of the mapped model against the true
    ellipsoid's; ``rmse_truth_map`` and ``rmse_truth_exact`` of each against the ray-cast sky
    visibility (how much of the model's error the map is). Columns
    :data:`ELLIPSOID_MAP_COLUMNS`.
    """
    from .. import trees as T

    cfg = ELLIPSOID_MAP[bool(quick)]
    rows = []
    for name in scenes:
        lv = _poisson_leaves(name, "ellipsoid", bool(quick), int(seed))
        if name in CANOPY_SCENES:
            d = _canopy(name, bool(quick), int(seed))
            P, N = d["points"][d["score"]], d["normals"][d["score"]]
        else:
            P, N = lv["points"], lv["normals"]
        k = min(cfg["points"], len(P))
        P, N = P[:k], N[:k]
        shell, sigma = lv["shell"], lv["sigma"]
        for w in REFERENCES:
            mapped = lv["poisson"][w][:k]
            exact = T.poisson_quadrature(P, N, shell, extinction=sigma, weighting=w, nodes=cfg["nodes"])
            t = np.asarray(lv["truth"][w].value)[:k]
            diff = mapped - exact
            rows.append({"scene": name, "reference": w, "radii": "x".join(f"{r:.3g}" for r in shell.radii),
                         "sigma": float(sigma), "rmse_map": float(np.sqrt(np.mean(diff ** 2))),
                         "max_map": float(np.max(np.abs(diff))), "bias_map": float(np.mean(diff)),
                         "rmse_truth_map": float(np.sqrt(np.mean((mapped - t) ** 2))),
                         "rmse_truth_exact": float(np.sqrt(np.mean((exact - t) ** 2))),
                         "truth_stderr": float(np.sqrt(np.mean(np.asarray(lv["truth"][w].stderr)[:k] ** 2))),
                         "points": int(k), "nodes": cfg["nodes"]})
    return rows


def poisson_images(name: str, *, shell: str = "sphere", reference: str = "cosine", quick: bool = False,
                   seed: int = 0) -> dict:
    """The per-pixel images behind :func:`poisson_rows` (the figure ``canopy_models``):
    ``truth``, ``stderr``, ``hegeman`` (Eq. 6 fitted; Eqs. 7-8 on the ground), ``poisson``
    (predicted), each (H, W) with NaN where no foliage or ground is seen, and the parameters
    ``density`` and ``sigma``."""
    lv = _poisson_leaves(str(name), shell, bool(quick), int(seed))
    pix = _poisson_pixels(str(name), shell, bool(quick), int(seed))
    img = pix["image"]
    t = pix["truth"][reference]
    return {"truth": img(np.asarray(t.value)), "stderr": img(np.asarray(t.stderr)),
            "hegeman": img(pix["hegeman"][reference]), "poisson": img(pix["poisson"][reference]),
            "density": float(lv["fitted"][reference][0]), "sigma": float(lv["sigma"]), "rays": pix["rays"]}


def poisson_main(argv=None) -> int:
    """:func:`poisson_rows` and :func:`ellipsoid_map_rows` as Markdown tables (and
    ``trees_poisson.csv``, ``trees_poisson_ellipsoid_map.csv`` with ``--out``): what
    ``python -m vobscure.experiments.trees --poisson [--quick] [--seed N] [--out DIR]`` runs."""
    import argparse
    import time
    from pathlib import Path

    from .common import machine, markdown_table, write_csv

    ap = argparse.ArgumentParser(prog="vobscure.experiments.trees.poisson_main")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = poisson_rows(args.quick, seed=args.seed)
    print(markdown_table(rows, POISSON_COLUMNS))
    emap = ellipsoid_map_rows(args.quick, seed=args.seed)
    print("\n## the ellipsoid's affine map against the true ellipsoid\n")
    print(markdown_table(emap, ELLIPSOID_MAP_COLUMNS))
    print(f"\n{time.perf_counter() - t0:.1f} s, machine {machine()}")
    if args.out:
        write_csv(Path(args.out) / "trees_poisson.csv", rows, POISSON_COLUMNS, digits=6)
        write_csv(Path(args.out) / "trees_poisson_ellipsoid_map.csv", emap, ELLIPSOID_MAP_COLUMNS, digits=6)
    return 0


# ----------------------------------------------------------------------------- ground (Fig. 9)
@lru_cache(maxsize=None)
def _ground(name: str, quick: bool, seed: int) -> dict:
    from .. import trees as T

    s = setting(quick)
    scene = _scene(name)
    md = scene.metadata
    sphere = T.bounding_sphere(np.asarray(md["canopy_points"], dtype=np.float64))
    R = float(sphere.radius)
    c = np.asarray(md["canopy_center"], dtype=np.float64)
    y = float(md["ground_y"])
    rng = np.random.default_rng(seed)
    m = s["ring_points"]
    dist, pts = [], []
    for f in s["rings"]:
        # a ring may reach past the ground square: an upward hemisphere never sees the
        # ground plane, so a point at ground height sees the same sky with or without it
        rho = f * R
        phi = 2 * np.pi * (np.arange(m) + rng.random()) / m
        ring = np.column_stack([c[0] + rho * np.cos(phi), np.full(m, y), c[2] + rho * np.sin(phi)])
        pts.append(ring)
        dist.append(np.full(m, rho))
    points = np.concatenate(pts)
    distance = np.concatenate(dist)
    normals = np.tile([0.0, 1.0, 0.0], (len(points), 1))
    truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 11 + i)
             for i, w in enumerate(REFERENCES)}
    # the porous sphere's extinction: the Poisson leaf cloud's sigma = n A / 2 (G = 1/2 for
    # leaves of random orientation), the leaves spread over the bounding sphere's volume
    sigma = T.extinction(md["n_leaves"], md["leaf_area"], sphere)
    values = {(mdl, w): T.occluder_visibility(points, normals, [sphere], model=mdl, weighting=w,
                                              **({"sigma": sigma} if mdl == "porous" else {}))
              for mdl in ("hegeman", "exact", "porous") for w in REFERENCES}
    return {"scene": scene, "points": points, "normals": normals, "distance": distance, "radius": R,
            "truth": truth, "values": values, "sphere": sphere, "sigma": sigma,
            "truth_rays": s["truth_rays"]}


def ground_rows(quick: bool = False, *, seed: int = 0, scenes=TREE_SCENES) -> list[dict]:
    """Fig. 9: the occluder models on the ground around a tree against the sky visibility.

    One row per (scene, model, reference, ring distance) and one per (scene, model,
    reference) over all rings (``distance`` empty); columns :data:`GROUND_COLUMNS`.
    ``distance_r`` is the distance from the trunk in bounding-sphere radii.
    """
    rows = []
    for name in scenes:
        d = _ground(name, bool(quick), int(seed))
        for (mdl, w), v in d["values"].items():
            truth = d["truth"][w]
            for rho in [*np.unique(d["distance"]), None]:
                idx = np.arange(len(v)) if rho is None else np.flatnonzero(d["distance"] == rho)
                sc = _scores(v[idx], _sub(truth, idx))
                del sc["corr"], sc["mae"]
                rows.append({"scene": name, "model": mdl, "reference": w,
                             "distance": None if rho is None else float(rho),
                             "distance_r": None if rho is None else float(rho / d["radius"]),
                             "sphere_radius": d["radius"], **sc, "truth_rays": d["truth_rays"]})
    return rows


# ----------------------------------------------------------------------------- grass (Fig. 10)
@lru_cache(maxsize=None)
def _grass(quick: bool, seed: int) -> dict:
    from .. import trees as T

    s = setting(quick)
    scene = _scene(GRASS_SCENE)
    md = scene.metadata
    index = list(scene.meshes).index(md["foliage_mesh"])
    tri = scene.triangles[np.asarray(scene.mesh_index) == index]     # base-, base+, tip per blade
    bases = np.asarray(md["blade_bases"], dtype=np.float64)
    central = np.flatnonzero(np.all(np.abs(bases[:, [0, 2]]) <= 0.25 * md["field_size"], axis=1))
    rng = np.random.default_rng(seed)
    n = s["grass_points"]
    blade = rng.choice(central, size=n)
    t = (np.arange(n) + rng.random(n)) / n          # stratified relative heights P_z / h
    rng.shuffle(t)
    a = rng.uniform(0.1, 0.9, size=n)
    tb = tri[blade]
    points = (1 - t)[:, None] * (a[:, None] * tb[:, 0] + (1 - a)[:, None] * tb[:, 1]) + t[:, None] * tb[:, 2]
    normals = np.asarray(scene.face_normals)[np.asarray(scene.mesh_index) == index][blade].copy()
    normals[normals[:, 1] < 0] *= -1.0                  # the side that looks up
    h = np.asarray(md["blade_heights"], dtype=np.float64)[blade]
    P_z = points[:, 1] - md["ground_y"]
    cos_theta = normals[:, 1]
    truth = {w: _truth(scene, points, normals, w, s["truth_rays"], seed + 21 + i)
             for i, w in enumerate(REFERENCES)}
    model = np.asarray(T.grass_visibility(P_z, h, cos_theta), dtype=np.float64)   # Eq. 9
    return {"scene": scene, "points": points, "normals": normals, "height": P_z / h, "cos": cos_theta,
            "blade_height": h, "truth": truth, "model": model, "truth_rays": s["truth_rays"]}


def grass_rows(quick: bool = False, *, seed: int = 0) -> list[dict]:
    """Fig. 10: Eq. 9 against the sky visibility at points on grass blades.

    Rows per (reference, relative-height bin) over all orientations, per (reference,
    height bin, orientation bin), and one per reference over every point (``height_lo`` 0,
    ``height_hi`` 1, ``cos_lo`` / ``cos_hi`` the observed range); columns
    :data:`GRASS_COLUMNS`. ``cos`` is cos theta of Eq. 9, the normal's vertical component.
    """
    s = setting(quick)
    d = _grass(bool(quick), int(seed))
    hb = np.linspace(0.0, 1.0, s["height_bins"] + 1)
    cos = d["cos"]
    cb = np.quantile(cos, np.linspace(0, 1, s["cos_bins"] + 1))
    cos_all = (float(cos.min()), float(cos.max()))
    rows = []
    for w in REFERENCES:
        def add(idx, hl, hh, cl, ch):
            if len(idx) == 0:
                return
            sc = _scores(d["model"][idx], _sub(d["truth"][w], idx))
            del sc["mae"]
            rows.append({"scene": GRASS_SCENE, "model": "eq9", "reference": w, "height_lo": hl,
                         "height_hi": hh, "cos_lo": cl, "cos_hi": ch, **sc, "truth_rays": d["truth_rays"]})
        add(np.arange(len(cos)), 0.0, 1.0, *cos_all)
        for i in range(len(hb) - 1):
            inh = (d["height"] >= hb[i]) & (d["height"] < hb[i + 1])
            add(np.flatnonzero(inh), float(hb[i]), float(hb[i + 1]), *cos_all)
            for j in range(len(cb) - 1):
                inc = (cos >= cb[j]) & ((cos < cb[j + 1]) if j < len(cb) - 2 else (cos <= cb[j + 1]))
                add(np.flatnonzero(inh & inc), float(hb[i]), float(hb[i + 1]), float(cb[j]), float(cb[j + 1]))
    return rows


# ----------------------------------------------------------------------------- speed against accuracy
def _targets(quick: bool, seed: int) -> list[dict]:
    """What the trade-off measures: per (scene, points), the points, truth and the models
    (label -> (values per reference, callable for timing on any points))."""
    from .. import trees as T

    out = []
    for name in CANOPY_SCENES:
        d = _canopy(name, quick, seed)
        sp = d["score"]
        best = _best_multi(d, "cosine")      # one multi-shell for both references
        models = {}
        for c in d["configs"]:
            if c["source"] not in ("fitted", "predicted"):
                continue
            if c["model"] == "reeves_blau":
                if c["shell"] != "sphere":
                    continue
                label = "Reeves-Blau, sphere, fitted k"
                fn = (lambda shell, k: lambda P, N: T.reeves_blau(P, shell, k=k))(c["shell_obj"], c["parameter"])
            else:
                if c["shell"] not in ("sphere", "ellipsoid", best):
                    continue
                if c["source"] == "predicted" and c["shell"] != "sphere":
                    continue
                label = f"Eq. 6, {c['shell']}, {c['source']} density"
                fn = (lambda shell, rho: lambda P, N: T.canopy_visibility(P, N, shell, density=rho))(
                    c["shell_obj"], c["parameter"])
            models.setdefault(label, {"values": {}, "fn": {}})
            models[label]["values"][c["reference"]] = c["values"]
            models[label]["fn"][c["reference"]] = fn
        out.append({"scene": name, "points_on": "leaves", "scene_obj": d["scene"], "points": d["points"][sp],
                    "normals": d["normals"][sp], "truth": {w: _sub(d["truth"][w], sp) for w in REFERENCES},
                    "models": models})
    for name in TREE_SCENES:
        g = _ground(name, quick, seed)
        models = {}
        for (mdl, w), v in g["values"].items():
            label = f"occluder {mdl}"
            kw = {"sigma": g["sigma"]} if mdl == "porous" else {}
            fn = (lambda m, w, kw: lambda P, N: T.occluder_visibility(P, N, [g["sphere"]], model=m,
                                                                      weighting=w, **kw))(mdl, w, kw)
            models.setdefault(label, {"values": {}, "fn": {}})
            models[label]["values"][w] = v
            models[label]["fn"][w] = fn
        out.append({"scene": name, "points_on": "ground", "scene_obj": g["scene"], "points": g["points"],
                    "normals": g["normals"], "truth": g["truth"], "models": models})
    gr = _grass(quick, seed)
    h = gr["blade_height"]
    P_z = gr["points"][:, 1] - gr["scene"].metadata["ground_y"]

    def eq9(P, N, _P_z=P_z, _h=h, _cos=gr["cos"]):
        # the per-point inputs of Eq. 9 are the blade's height and the point's; tiled for timing
        reps = -(-len(P) // len(_P_z))
        return T.grass_visibility(np.tile(_P_z, reps)[:len(P)], np.tile(_h, reps)[:len(P)],
                                  np.tile(_cos, reps)[:len(P)])

    out.append({"scene": GRASS_SCENE, "points_on": "blades", "scene_obj": gr["scene"], "points": gr["points"],
                "normals": gr["normals"], "truth": gr["truth"],
                "models": {"Eq. 9": {"values": {w: gr["model"] for w in REFERENCES},
                                     "fn": {w: eq9 for w in REFERENCES}}}})
    return out


def _best_multi(d, reference) -> str:
    """The multi-sphere shell label with the smallest fitted-density RMSE for ``reference``."""
    best, label = np.inf, None
    truth = np.asarray(d["truth"][reference].value)[d["score"]]
    for c in d["configs"]:
        if (c["model"] == "hegeman" and c["source"] == "fitted" and c["reference"] == reference
                and c["shell"].endswith("spheres")):
            e = float(np.sqrt(np.mean((c["values"] - truth) ** 2)))
            if e < best:
                best, label = e, c["shell"]
    return label


@lru_cache(maxsize=None)
def _convergence(quick: bool, seed: int) -> dict:
    """Ray-cast estimates at each ray count of the sweep, per (scene, points_on, reference),
    and their timings, measured in one run (round-robin with the models' timings).

    The ray casts are timed on the scored points tiled to ``raycast_timing_points`` (each copy
    its own random directions; the estimates of the first copy give the RMSE), the models on
    the points tiled to ``timing_points``: enough work per call that the fixed cost of a call
    does not dominate the time per point."""
    from ..estimate import Estimate
    from ..groundtruth import ambient_occlusion
    from .common import time_calls

    s = setting(quick)
    targets = _targets(quick, seed)
    funcs = {}

    def tiled(a, count):
        return np.tile(a, (-(-count // len(a)), 1))[:max(count, len(a))]

    for ti, t in enumerate(targets):
        P, N = t["points"], t["normals"]
        PT, NT = tiled(P, s["timing_points"]), tiled(N, s["timing_points"])
        PR, NR = tiled(P, s["raycast_timing_points"]), tiled(N, s["raycast_timing_points"])
        for w in REFERENCES:
            for r in s["rays"]:
                funcs[("raycast", ti, w, r)] = (
                    lambda P=PR, N=NR, w=w, r=r, sc=t["scene_obj"], sd=seed + 1000 + r:
                    ambient_occlusion(sc, P, N, rays=r, weighting=w, max_distance=np.inf, seed=sd))
            for label, m in t["models"].items():
                funcs[("model", ti, w, label)] = (lambda f=m["fn"][w], PT=PT, NT=NT: f(PT, NT))
    timings, values = time_calls(funcs, repeats=s["repeats"])
    for key, e in values.items():
        if key[0] == "raycast":
            n = len(targets[key[1]]["points"])
            values[key] = Estimate(value=e.value[:n], stderr=e.stderr[:n], samples=e.samples)
    return {"targets": targets, "timings": timings, "values": values}


def convergence_rows(quick: bool = False, *, seed: int = 0) -> list[dict]:
    """The ray cast's RMSE against the reference at each ray count of the sweep.

    Columns :data:`CONVERGENCE_COLUMNS`. ``rmse_corrected`` removes the reference's own noise,
    sqrt(RMSE^2 - mean stderr^2) (the two are independent); ``rmse_sqrt_rays`` is
    ``rmse_corrected * sqrt(rays)``, constant if the error falls as 1 / sqrt(rays).
    """
    s = setting(quick)
    c = _convergence(bool(quick), int(seed))
    rows = []
    for ti, t in enumerate(c["targets"]):
        for w in REFERENCES:
            truth = t["truth"][w]
            ref_var = float(np.mean(np.asarray(truth.stderr) ** 2))
            for r in s["rays"]:
                e = c["values"][("raycast", ti, w, r)]
                rmse = float(np.sqrt(np.mean((np.asarray(e.value) - np.asarray(truth.value)) ** 2)))
                corrected = math.sqrt(max(rmse ** 2 - ref_var, 1e-12))
                rows.append({"scene": t["scene"], "points_on": t["points_on"], "reference": w, "rays": r,
                             "rmse": rmse, "rmse_corrected": corrected,
                             "reference_stderr": math.sqrt(ref_var), "rmse_sqrt_rays": corrected * math.sqrt(r),
                             "points": int(len(t["points"])), "reference_rays": int(truth.samples)})
    return rows


def _time_at(r_eq, rays, times) -> float:
    """Time per point of a ray cast with ``r_eq`` rays: log-log interpolation of the measured
    ``times`` at ``rays``; beyond the sweep, proportional to the rays from the nearest end."""
    if r_eq > rays[-1]:
        return float(times[-1] * r_eq / rays[-1])
    if r_eq < rays[0]:
        return float(times[0] * r_eq / rays[0])
    return float(np.exp(np.interp(np.log(r_eq), np.log(rays), np.log(times))))


def tradeoff_rows(quick: bool = False, *, seed: int = 0) -> list[dict]:
    """Speed against accuracy: each model's equal-error ray count and its time relative to that
    ray cast.

    Columns :data:`TRADEOFF_COLUMNS`. ``equal_rays`` is :func:`equal_error_rays` of the
    noise-corrected RMSEs (model and ray cast alike, both against the same reference);
    ``extrapolated`` says it lies outside the swept ray counts; ``lower_bound`` that the
    model's RMSE is within sqrt(2) of the reference's own noise, so that the reference cannot
    resolve its error and ``equal_rays`` is set to the reference's rays (a lower bound).
    ``model_us`` is the model's
    time per point (on ``timing_points`` points), ``raycast_us`` the ray cast's per point at
    ``equal_rays`` (log-log interpolation of the measured times), ``time_ratio`` their ratio
    and ``speedup`` its inverse (wall time: the ray cast runs on every core, the model on
    one); ``speedup_cpu`` the same with process CPU time summed over threads.
    """
    s = setting(quick)
    c = _convergence(bool(quick), int(seed))
    conv = convergence_rows(quick, seed=seed)
    rays = np.asarray(s["rays"], dtype=np.float64)
    rows = []
    for ti, t in enumerate(c["targets"]):
        n = len(t["points"])
        for w in REFERENCES:
            truth = t["truth"][w]
            ref_var = float(np.mean(np.asarray(truth.stderr) ** 2))
            curve = [r["rmse_corrected"] for r in conv if r["scene"] == t["scene"]
                     and r["points_on"] == t["points_on"] and r["reference"] == w]
            n_rc = max(s["raycast_timing_points"], n)
            t_rc = np.array([c["timings"][("raycast", ti, w, r)].median / n_rc for r in s["rays"]])
            c_rc = np.array([c["timings"][("raycast", ti, w, r)].cpu_median / n_rc for r in s["rays"]])
            for label, m in t["models"].items():
                v = m["values"][w]
                rmse = float(np.sqrt(np.mean((v - np.asarray(truth.value)) ** 2)))
                corrected = math.sqrt(max(rmse ** 2 - ref_var, 1e-12))
                # a model whose error the reference cannot resolve (its RMSE within the
                # reference's noise) is as good as the reference: a lower bound
                lower = rmse ** 2 <= 2.0 * ref_var
                if lower:
                    r_eq, extra = float(truth.samples), False
                else:
                    r_eq, extra = equal_error_rays(rays, curve, corrected)
                rc_s = _time_at(r_eq, rays, t_rc)
                rc_cpu = _time_at(r_eq, rays, c_rc)
                timing = c["timings"][("model", ti, w, label)]
                model_s = timing.median / s["timing_points"]
                model_cpu = timing.cpu_median / s["timing_points"]
                rows.append({"scene": t["scene"], "points_on": t["points_on"], "model": label, "reference": w,
                             "model_rmse": rmse, "model_rmse_corrected": corrected, "equal_rays": r_eq,
                             "extrapolated": extra, "lower_bound": lower, "model_us": 1e6 * model_s,
                             "raycast_us": 1e6 * rc_s,
                             "time_ratio": model_s / rc_s, "speedup": rc_s / model_s,
                             "speedup_cpu": rc_cpu / model_cpu if model_cpu > 0 else None,
                             "reference_stderr": math.sqrt(ref_var), "points": n,
                             "timing_points": s["timing_points"], "raycast_timing_points": n_rc})
    return rows


def cost_rows(quick: bool = False, *, seed: int = 0, scenes=("tree",)) -> list[dict]:
    """The paper's cost claim as ratios of evaluation time per point, timed in one run.

    Shaders: ``"ambient"`` (a constant written per point), ``"reeves_blau"`` and
    ``"hegeman"`` on the bounding sphere (the paper's single shell), and Eq. 6 on the
    ellipsoid and on the best multi-sphere shell (extras the paper did not time). Columns
    :data:`COST_COLUMNS`; ``paper_vs_*`` are the paper's ratios of throughput (2300 / 460 = 5.0
    and 580 / 460 = 1.26).
    """
    from .. import trees as T
    from .common import time_calls

    s = setting(quick)
    rows = []
    for name in scenes:
        d = _canopy(name, bool(quick), int(seed))

        def param(model, shell):
            return next(c["parameter"] for c in d["configs"] if c["model"] == model and c["shell"] == shell
                        and c["source"] == "fitted" and c["reference"] == "cosine")

        n = s["timing_points"]
        reps = -(-n // len(d["points"]))
        P, N = np.tile(d["points"], (reps, 1))[:n], np.tile(d["normals"], (reps, 1))[:n]
        sphere = d["shells"]["sphere"][0]
        best = _best_multi(d, "cosine")
        funcs = {
            "ambient": lambda: np.full(len(P), 1.0),
            "reeves_blau": lambda: T.reeves_blau(P, sphere, k=param("reeves_blau", "sphere")),
            "hegeman": lambda: T.canopy_visibility(P, N, sphere, density=param("hegeman", "sphere")),
            "hegeman, ellipsoid": lambda: T.canopy_visibility(P, N, d["shells"]["ellipsoid"][0],
                                                              density=param("hegeman", "ellipsoid")),
            f"hegeman, {best}": lambda: T.canopy_visibility(P, N, d["shells"][best][0],
                                                            density=param("hegeman", best)),
        }
        timings, _ = time_calls(funcs, repeats=max(3, s["repeats"]))
        us = {k: 1e6 * v.median / n for k, v in timings.items()}
        for shader, t in us.items():
            rows.append({"scene": name, "shader": shader, "us_per_point": t,
                         "vs_ambient": t / us["ambient"], "vs_reeves_blau": t / us["reeves_blau"],
                         "paper_vs_ambient": PAPER_MPS["ambient"] / PAPER_MPS["hegeman"]
                         if shader == "hegeman" else None,
                         "paper_vs_reeves_blau": PAPER_MPS["reeves_blau"] / PAPER_MPS["hegeman"]
                         if shader == "hegeman" else None,
                         "timing_points": n, "repeats": max(3, s["repeats"])})
    return rows


def weighting_rows(quick: bool = False, *, seed: int = 0) -> list[dict]:
    """Which hemisphere integral each model fits better: its RMSE against the cosine-weighted
    and the uniform sky visibility, side by side (columns :data:`WEIGHTING_COLUMNS`).

    Canopy models with a fitted parameter are fitted to each reference separately; the
    predicted density, the occluder models and Eq. 9 have no fitted parameter.
    """
    rows = []

    def pair(scene, what, model, rs):
        by = {r["reference"]: r for r in rs}
        if set(by) != set(REFERENCES):
            return
        c, u = by["cosine"], by["uniform"]
        rows.append({"scene": scene, "what": what, "model": model, "rmse_cosine": c["rmse"],
                     "rmse_uniform": u["rmse"], "better": "cosine" if c["rmse"] < u["rmse"] else "uniform",
                     "stderr_cosine": c["truth_stderr"], "stderr_uniform": u["truth_stderr"]})

    canopy = canopy_rows(quick, seed=seed)
    keys = []
    for r in canopy:
        k = (r["scene"], r["model"], r["shell"], r["source"])
        if k not in keys and r["source"] in ("fitted", "predicted"):
            keys.append(k)
    for scene, model, shell, source in keys:
        rs = [r for r in canopy if (r["scene"], r["model"], r["shell"], r["source"]) == (scene, model, shell, source)]
        name = "Eq. 6" if model == "hegeman" else "Reeves-Blau"
        pair(scene, "leaves", f"{name}, {shell}, {source}", rs)
    ground = [r for r in ground_rows(quick, seed=seed) if r["distance"] is None]
    for scene in TREE_SCENES:
        for mdl in ("hegeman", "exact", "porous"):
            pair(scene, "ground", f"occluder {mdl}", [r for r in ground if r["scene"] == scene and r["model"] == mdl])
    grass = [r for r in grass_rows(quick, seed=seed) if r["height_lo"] == 0.0 and r["height_hi"] == 1.0]
    pair(GRASS_SCENE, "blades", "Eq. 9", grass)
    return rows


def all_rows(quick: bool = False, *, seed: int = 0) -> dict:
    """Every measurement, by name (the order of :func:`main`'s tables)."""
    return {"canopy": canopy_rows(quick, seed=seed), "ground": ground_rows(quick, seed=seed),
            "grass": grass_rows(quick, seed=seed), "weighting": weighting_rows(quick, seed=seed),
            "convergence": convergence_rows(quick, seed=seed), "tradeoff": tradeoff_rows(quick, seed=seed),
            "cost": cost_rows(quick, seed=seed)}


_TABLE_COLUMNS = {"canopy": CANOPY_COLUMNS, "ground": GROUND_COLUMNS, "grass": GRASS_COLUMNS,
                  "weighting": WEIGHTING_COLUMNS, "convergence": CONVERGENCE_COLUMNS,
                  "tradeoff": TRADEOFF_COLUMNS, "cost": COST_COLUMNS}


def main(argv=None) -> int:
    """``python -m vobscure.experiments.trees [--quick] [--seed N] [--out DIR] [--poisson]``: run
    every measurement (with ``--poisson`` only :func:`poisson_rows`), print Markdown tables (and, with ``--out``, write one CSV per table and a
    ``trees.json`` with the machine record)."""
    import argparse
    import time
    from pathlib import Path

    from .common import machine, markdown_table, write_csv, write_json

    ap = argparse.ArgumentParser(prog="python -m vobscure.experiments.trees")
    ap.add_argument("--quick", action="store_true", help="small and fast (what CI runs)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=None, help="directory for the CSV tables and trees.json")
    ap.add_argument("--poisson", action="store_true",
                    help="only the Poisson leaf cloud against Eq. 6 (poisson_rows; trees_poisson.csv)")
    args = ap.parse_args(argv)
    if args.poisson:
        return poisson_main([*(["--quick"] if args.quick else []), "--seed", str(args.seed),
                             *(["--out", args.out] if args.out else [])])
    t0 = time.perf_counter()
    tables = all_rows(args.quick, seed=args.seed)
    elapsed = time.perf_counter() - t0
    for name, rows in tables.items():
        cols = _TABLE_COLUMNS[name]
        if name == "ground":
            rows = [r for r in rows if r["distance"] is None] + [r for r in rows if r["distance"] is not None]
        print(f"\n## {name}\n")
        print(markdown_table(rows, cols))
    print(f"\n{elapsed:.1f} s, settings {setting(args.quick)}, machine {machine()}")
    if args.out:
        out = Path(args.out)
        for name, rows in tables.items():
            write_csv(out / f"trees_{name}.csv", rows, _TABLE_COLUMNS[name], digits=6)
        write_json(out / "trees.json", {"quick": args.quick, "seed": args.seed, "seconds": elapsed,
                                        "settings": setting(args.quick), "machine": machine()})
    return 0


if __name__ == "__main__":   # pragma: no cover
    raise SystemExit(main())
