"""Speed against accuracy: the ray cast's convergence, each model's equal-error ray count and
time, the paper's cost claim, and which hemisphere integral each model fits better."""

from __future__ import annotations

import math

import numpy as np

from ...metrics import equal_error_rays
from ._canopy import _canopy, canopy_rows
from ._common import (
    CANOPY_SCENES,
    GRASS_SCENE,
    PAPER_MPS,
    REFERENCES,
    TREE_SCENES,
    _measurements,
    _sub,
    kept,
    setting,
)
from ._ground import _grass, _ground, grass_rows, ground_rows

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


def _targets(run) -> list[dict]:
    """What the trade-off measures: per (scene, points), the points, truth and the models
    (label -> (values per reference, callable for timing on any points))."""
    from ... import trees as T

    out = []
    for name in CANOPY_SCENES:
        d = _canopy(run, name)
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
        g = _ground(run, name)
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
    gr = _grass(run)
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

@kept
def _convergence(run) -> dict:
    """Ray-cast estimates at each ray count of the sweep, per (scene, points_on, reference),
    and their timings, measured in one run (round-robin with the models' timings).

    The ray casts are timed on the scored points tiled to ``raycast_timing_points`` (each copy
    its own random directions; the estimates of the first copy give the RMSE), the models on
    the points tiled to ``timing_points``: enough work per call that the fixed cost of a call
    does not dominate the time per point."""
    from ...estimate import Estimate
    from ...groundtruth import ambient_occlusion
    from ..common import time_calls

    seed = run.seed
    s = setting(run.quick)
    targets = _targets(run)
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

def convergence_rows(quick: bool = False, *, seed: int = 0, measurements=None) -> list[dict]:
    """The ray cast's RMSE against the reference at each ray count of the sweep.

    Columns :data:`CONVERGENCE_COLUMNS`. ``rmse_corrected`` removes the reference's own noise,
    sqrt(RMSE^2 - mean stderr^2) (the two are independent); ``rmse_sqrt_rays`` is
    ``rmse_corrected * sqrt(rays)``, constant if the error falls as 1 / sqrt(rays).
    ``measurements``: the run's :class:`Measurements` to share (with :func:`tradeoff_rows`,
    the same timed run), default a new one.
    """
    s = setting(quick)
    c = _convergence(_measurements(quick, seed, measurements))
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

def tradeoff_rows(quick: bool = False, *, seed: int = 0, measurements=None) -> list[dict]:
    """Speed against accuracy: each model's equal-error ray count and its time relative to that
    ray cast.

    Columns :data:`TRADEOFF_COLUMNS`. ``equal_rays`` is
    :func:`vobscure.metrics.equal_error_rays` of the
    noise-corrected RMSEs (model and ray cast alike, both against the same reference);
    ``extrapolated`` says it lies outside the swept ray counts; ``lower_bound`` that the
    model's RMSE is within sqrt(2) of the reference's own noise, so that the reference cannot
    resolve its error and ``equal_rays`` is set to the reference's rays (a lower bound).
    ``model_us`` is the model's
    time per point (on ``timing_points`` points), ``raycast_us`` the ray cast's per point at
    ``equal_rays`` (log-log interpolation of the measured times), ``time_ratio`` their ratio
    and ``speedup`` its inverse (wall time: the ray cast runs on every core, the model on
    one); ``speedup_cpu`` the same with process CPU time summed over threads.
    ``measurements`` as in :func:`convergence_rows`.
    """
    s = setting(quick)
    run = _measurements(quick, seed, measurements)
    c = _convergence(run)
    conv = convergence_rows(quick, seed=seed, measurements=run)
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

def cost_rows(quick: bool = False, *, seed: int = 0, scenes=("tree",), measurements=None) -> list[dict]:
    """The paper's cost claim as ratios of evaluation time per point, timed in one run.

    Shaders: ``"ambient"`` (a constant written per point), ``"reeves_blau"`` and
    ``"hegeman"`` on the bounding sphere (the paper's single shell), and Eq. 6 on the
    ellipsoid and on the best multi-sphere shell (extras the paper did not time). Columns
    :data:`COST_COLUMNS`; ``paper_vs_*`` are the paper's ratios of throughput (2300 / 460 = 5.0
    and 580 / 460 = 1.26). ``measurements``: the run's :class:`Measurements` to share,
    default a new one.
    """
    from ... import trees as T
    from ..common import time_calls

    s = setting(quick)
    run = _measurements(quick, seed, measurements)
    rows = []
    for name in scenes:
        d = _canopy(run, name)

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

def weighting_rows(quick: bool = False, *, seed: int = 0, measurements=None) -> list[dict]:
    """Which hemisphere integral each model fits better: its RMSE against the cosine-weighted
    and the uniform sky visibility, side by side (columns :data:`WEIGHTING_COLUMNS`).

    Canopy models with a fitted parameter are fitted to each reference separately; the
    predicted density, the occluder models and Eq. 9 have no fitted parameter.
    ``measurements``: the run's :class:`Measurements` to share, default a new one.
    """
    run = _measurements(quick, seed, measurements)
    rows = []

    def pair(scene, what, model, rs):
        by = {r["reference"]: r for r in rs}
        if set(by) != set(REFERENCES):
            return
        c, u = by["cosine"], by["uniform"]
        rows.append({"scene": scene, "what": what, "model": model, "rmse_cosine": c["rmse"],
                     "rmse_uniform": u["rmse"], "better": "cosine" if c["rmse"] < u["rmse"] else "uniform",
                     "stderr_cosine": c["truth_stderr"], "stderr_uniform": u["truth_stderr"]})

    canopy = canopy_rows(quick, seed=seed, measurements=run)
    keys = []
    for r in canopy:
        k = (r["scene"], r["model"], r["shell"], r["source"])
        if k not in keys and r["source"] in ("fitted", "predicted"):
            keys.append(k)
    for scene, model, shell, source in keys:
        rs = [r for r in canopy if (r["scene"], r["model"], r["shell"], r["source"]) == (scene, model, shell, source)]
        name = "Eq. 6" if model == "hegeman" else "Reeves-Blau"
        pair(scene, "leaves", f"{name}, {shell}, {source}", rs)
    ground = [r for r in ground_rows(quick, seed=seed, measurements=run) if r["distance"] is None]
    for scene in TREE_SCENES:
        for mdl in ("hegeman", "exact", "porous"):
            pair(scene, "ground", f"occluder {mdl}", [r for r in ground if r["scene"] == scene and r["model"] == mdl])
    grass = [r for r in grass_rows(quick, seed=seed, measurements=run)
             if r["height_lo"] == 0.0 and r["height_hi"] == 1.0]
    pair(GRASS_SCENE, "blades", "Eq. 9", grass)
    return rows
