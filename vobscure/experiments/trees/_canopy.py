"""Points on the leaves of the canopy scenes: Eqs. 4-6 and Reeves-Blau with fitted and
predicted parameters against the sky visibility (Figs. 2, 3, 4, 8)."""

from __future__ import annotations

import numpy as np

from ...metrics import CALIBRATION_BINS, calibration_rmse
from ._common import CANOPY_SCENES, REFERENCES, _measurements, _scene, _scores, _sub, _truth, kept, setting

#: Columns of :func:`canopy_rows` (and :func:`reeves_blau_rows`).
CANOPY_COLUMNS = ("scene", "kind", "model", "shell", "shells", "source", "parameter", "refit", "reference",
                  "rmse", "bias", "mae", "corr", "rmse_calibration", "model_mean", "truth_mean", "truth_stderr",
                  "points", "fit_points", "truth_rays")


def _shells(scene, quick, seed) -> dict:
    """label -> (shell, number of shells): bounding sphere, bounding ellipsoid, k spheres."""
    from ... import trees as T

    cp = np.asarray(scene.metadata["canopy_points"], dtype=np.float64)
    shells = {"sphere": (T.bounding_sphere(cp), 1), "ellipsoid": (T.bounding_ellipsoid(cp), 1)}
    for k in setting(quick)["multi_k"]:
        shells[f"{k} spheres"] = (T.shells_from_points(cp, k, kind="sphere", seed=seed), k)
    return shells


@kept
def _canopy(run, name: str) -> dict:
    """Points on a canopy scene's leaves, their ground truths, shells and every model's values
    (kept in the run's :class:`Measurements` ``run``: every canopy figure and the trade-off share it)."""
    from ... import trees as T
    from ...scenes import leaf_points

    quick, seed = run.quick, run.seed
    s = setting(quick)
    scene = _scene(run, name)
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
            fitted = float(T.fit_density(points[fit], normals[fit], shell, truth[w].value[fit]))
            sources = [("fitted", fitted)] + ([("predicted", predicted)] if predicted is not None else [])
            if label == "sphere":
                sources += [("none", 0.0), ("fitted x10", 10.0 * fitted)]
            for source, density in sources:
                v = T.canopy_visibility(points[score], normals[score], shell, density=density)
                configs.append({"model": "hegeman", "shell": label, "shells": k, "source": source,
                                "parameter": density, "reference": w, "values": v, "shell_obj": shell})
            if label in ("sphere", "ellipsoid"):
                kk = T.fit_reeves_blau(points[fit], shell, truth[w].value[fit])
                v = T.reeves_blau(points[score], shell, k=kk)
                configs.append({"model": "reeves_blau", "shell": label, "shells": k, "source": "fitted",
                                "parameter": kk, "reference": w, "values": v, "shell_obj": shell})
    return {"scene": scene, "points": points, "normals": normals, "fit": fit, "score": score,
            "truth": truth, "shells": shells, "configs": configs, "truth_rays": s["truth_rays"]}


def canopy_rows(quick: bool = False, *, seed: int = 0, scenes=CANOPY_SCENES, measurements=None) -> list[dict]:
    """Eqs. 4-6 and Reeves-Blau against the sky visibility at points on the leaves.

    One row per (scene, model, shell, density source, reference); columns
    :data:`CANOPY_COLUMNS`. ``parameter`` is the density alpha rho of Eq. 6 (model
    ``"hegeman"``) or Reeves-Blau's k; ``source`` says where it came from (``"fitted"`` to
    this reference on the fit half, ``"predicted"`` from the leaf statistics, ``"none"``: 0,
    ``"fitted x10"``); the density by :func:`vobscure.trees.fit_density`, Reeves-Blau's k by
    :func:`vobscure.trees.fit_reeves_blau`. Scores are over the other half (``points``).
    ``refit`` is always False (``fit_density``'s answer is final; the column keeps the
    tables' layout). ``rmse_calibration``
    is :func:`vobscure.metrics.calibration_rmse` (:data:`CALIBRATION_BINS` equal-count bins of
    the model's value): the error in the *average* visibility the model predicts, Hegeman's
    ensemble mean <V>, without the point-to-point scatter. ``measurements``: the run's
    :class:`Measurements` (of ``quick``, ``seed``) to share, default a new one.
    """
    run = _measurements(quick, seed, measurements)
    rows = []
    for name in scenes:
        d = _canopy(run, name)
        kind = d["scene"].metadata.get("kind", "")
        for c in d["configs"]:
            truth = _sub(d["truth"][c["reference"]], d["score"])
            sc = _scores(c["values"], truth)
            rows.append({"scene": name, "kind": kind, "model": c["model"], "shell": c["shell"],
                         "shells": c["shells"], "source": c["source"], "parameter": c["parameter"],
                         "refit": False, "reference": c["reference"], **sc,
                         "rmse_calibration": calibration_rmse(c["values"], truth.value, bins=CALIBRATION_BINS),
                         "fit_points": int(len(d["fit"])), "truth_rays": d["truth_rays"]})
    return rows


def reeves_blau_rows(quick: bool = False, *, seed: int = 0, scenes=CANOPY_SCENES,
                     measurements=None) -> list[dict]:
    """Reeves-Blau against Hegeman (Figs. 4, 12) on the same points: the rows of
    :func:`canopy_rows` with a fitted parameter on the bounding sphere and ellipsoid."""
    return [r for r in canopy_rows(quick, seed=seed, scenes=scenes, measurements=measurements)
            if r["source"] == "fitted" and r["shell"] in ("sphere", "ellipsoid")]

def canopy_images(name: str, *, size=(64, 64), rays: int = 128, seed: int = 0, quick: bool = False,
                  shells=("sphere",), measurements=None):
    """Per-pixel images of a canopy scene (Fig. 2): the ray-cast cosine sky visibility of the
    visible leaves (the G-buffer's normal, turned toward the camera) and Eq. 6 on each of
    ``shells`` (labels of :func:`canopy_data`'s shells) with the density fitted to the cosine
    reference at points (:func:`canopy_rows`; ``measurements`` as there).

    Returns
    -------
    dict
        ``truth`` (H, W), NaN off the foliage (background and, for a tree, ground and wood),
        ``stderr`` (H, W), ``models`` (shell label -> (H, W)) and ``densities`` (shell label
        -> density); ``model`` and ``density`` are those of the first shell.
    """
    from ... import trees as T
    from ...camera import Camera
    from ...render import render_gbuffer

    run = _measurements(quick, seed, measurements)
    scene = _scene(run, name)
    v = scene.view
    kw = {"fov_y": v["fov_y"]} if "fov_y" in v else {"ortho_height": v["ortho_height"]}
    cam = Camera.look_at(v["eye"], v["target"], up=v.get("up", (0, 1, 0)), size=tuple(size), **kw)
    gb = render_gbuffer(scene, cam)
    d = _canopy(run, name)
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

def canopy_data(name: str, quick: bool = False, *, seed: int = 0, measurements=None) -> dict:
    """The points behind :func:`canopy_rows` for one scene (kept in ``measurements``): ``points``,
    ``normals`` (n, 3); ``fit`` and ``score`` index arrays; ``truth`` (reference -> Estimate
    over all n points); ``shells`` (label -> (shell, count)); ``configs``: one dict per
    model configuration with ``values`` over the ``score`` points. Read only."""
    return _canopy(_measurements(quick, seed, measurements), str(name))
