"""Speed against accuracy for Hegeman et al. 2006's models: how many ray-cast rays per point
give the same error, what that ray cast costs, and the paper's cost claim.

One PNG, ``hegeman_tradeoff.png``, and the numbers it plots, ``hegeman_tradeoff.csv``: the
rows of :func:`vobscure.experiments.trees.convergence_rows` (``table`` = ``"convergence"``),
:func:`~vobscure.experiments.trees.tradeoff_rows` (``"tradeoff"``) and
:func:`~vobscure.experiments.trees.cost_rows` (``"cost"``), one CSV.

(a) Per scene: the ray cast's RMSE (reference noise removed) against rays per point, log-log,
    against the high-ray reference (cosine weighting), with the slope -1/2 of plain Monte
    Carlo for comparison; horizontal lines: each model's RMSE against the same reference,
    marked where it meets the ray-cast curve (the equal-error ray count).
(b) The equal-error ray count of every model (cosine reference; hollow: extrapolated beyond
    the swept counts; ">=": the model's error is within the reference's noise, the count is
    the reference's rays, a lower bound).
(c) Speed-up of the model over the ray cast of equal error: ray-cast time per point at the
    equal-error count over the model's time per point (models single-threaded NumPy, ray
    casts Embree on every core, timed in one run).
(d) The paper's cost claim: time per point of Eq. 6 relative to ambient only (a constant) and
    to Reeves-Blau, beside the paper's 2300 / 460 = 5.0 and 580 / 460 = 1.26.

Regenerate with ``vobscure figures hegeman_tradeoff --out docs/img`` (about a minute; ``--quick`` in
seconds; times vary from run to run).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 4 (the NVShaderPerf throughputs and frame rates).
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, tree_measurements

__all__ = ["measure", "plot"]



def _columns():
    """The CSV's columns: ``table``, then the union of the three tables' columns."""
    from .. import trees as X

    cols = ["table"]
    for group in (X.CONVERGENCE_COLUMNS, X.TRADEOFF_COLUMNS, X.COST_COLUMNS):
        cols.extend(c for c in group if c not in cols)
    return tuple(cols)


_SCENE_LABELS = {"leaf_cloud": "sparse cloud", "leaf_cloud_dense": "dense cloud", "tree": "apple tree",
                 "tree_poplar": "poplar tree", "grass": "grass"}


ORDER = 150
FIGSIZE = (17.0, 16.0)


def measure(profile, *, trees=None) -> Rows:
    """The rows of :func:`vobscure.experiments.trees.convergence_rows`,
    :func:`~vobscure.experiments.trees.tradeoff_rows` and
    :func:`~vobscure.experiments.trees.cost_rows`, each with its ``table`` (quick: few points
    and rays, ray counts 4-16).
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    quick, seed = profile.quick, profile.seed
    run = tree_measurements(profile, trees)
    conv, trade, cost = (X.convergence_rows(quick, seed=seed, measurements=run),
                         X.tradeoff_rows(quick, seed=seed, measurements=run),
                         X.cost_rows(quick, seed=seed, measurements=run))
    table = ([{"table": "convergence", **r} for r in conv] + [{"table": "tradeoff", **r} for r in trade]
             + [{"table": "cost", **r} for r in cost])
    meta = {"seed": seed, "quick": quick, **X.setting(quick)}
    return Rows(table, columns=_columns(), meta=meta)


def plot(rows, fig) -> None:
    """(a) convergence, (b) equal-error rays, (c) speed-up, (d) the paper's cost claim."""
    s = rows.meta
    conv, trade, cost = ([r for r in rows if r["table"] == t] for t in ("convergence", "tradeoff", "cost"))
    top, bottom = fig.subfigures(2, 1, height_ratios=[0.55, 1.45], hspace=0.03)
    _convergence(top, conv, trade)
    axes = bottom.subplots(1, 3, width_ratios=[1.0, 1.0, 0.8])
    _bars(axes[0], trade, "equal_rays", "(b) equal-error rays per point (cosine reference)",
          "ray-cast rays per point with the model's RMSE (log)")
    _bars(axes[1], trade, "speedup", "(c) speed-up over the equal-error ray cast",
          "ray-cast time / model time, per point (log)", labels=False)
    _cost(axes[2], cost)
    fig.suptitle(f"Hegeman et al. 2006: speed against accuracy (reference {s['truth_rays']} rays, ray casts "
                 f"at {', '.join(map(str, s['rays']))} rays, models timed on {s['timing_points']} points, "
                 f"median of {s['repeats']}, seed {s['seed']}{', quick' if s['quick'] else ''})", fontsize=12.5)


def _targets(rows):
    out = []
    for r in rows:
        key = (r["scene"], r["points_on"])
        if key not in out:
            out.append(key)
    return out


def _convergence(subfig, conv, trade):
    targets = _targets(conv)
    axes = subfig.subplots(1, len(targets), sharey=True)
    colors = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2"]
    for ax, (scene, on) in zip(np.atleast_1d(axes), targets):
        rs = [r for r in conv if (r["scene"], r["points_on"]) == (scene, on) and r["reference"] == "cosine"]
        x = np.array([r["rays"] for r in rs], dtype=float)
        y = np.array([r["rmse_corrected"] for r in rs])
        ax.plot(x, y, "ko-", lw=2, ms=4, label="ray cast")
        ax.plot(x, y[0] * np.sqrt(x[0] / x), color="0.6", ls=":", label="slope -1/2")
        ms = [r for r in trade if (r["scene"], r["points_on"]) == (scene, on) and r["reference"] == "cosine"]
        for i, m in enumerate(ms):
            c = colors[i % len(colors)]
            ax.axhline(m["model_rmse_corrected"], color=c, lw=1, ls="--")
            if not m["lower_bound"]:
                ax.plot([m["equal_rays"]], [m["model_rmse_corrected"]], "o", color=c, ms=6,
                        mfc="white" if m["extrapolated"] else c)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("rays per point")
        ax.set_title(f"{_SCENE_LABELS.get(scene, scene)}, {on}", fontsize=10)
        ax.grid(True, which="both", color="0.92")
    np.atleast_1d(axes)[0].set_ylabel("RMSE (reference noise removed)")
    np.atleast_1d(axes)[0].legend(fontsize=8, loc="lower left")
    subfig.suptitle("(a) ray-cast RMSE against rays (cosine reference); dashed: each model's RMSE, dot: "
                    "where they meet (hollow: extrapolated)", fontsize=11)


def _bars(ax, trade, key, title, xlabel, labels=True):
    rs = [r for r in trade if r["reference"] == "cosine"]
    y = np.arange(len(rs))[::-1]
    colors = {"leaves": "#2ca02c", "ground": "#8c564b", "blades": "#bcbd22"}
    for yi, r in zip(y, rs):
        c = colors.get(r["points_on"], "#7f7f7f")
        ax.barh(yi, r[key], color=c if not (key == "equal_rays" and r["extrapolated"]) else "white",
                edgecolor=c, lw=1.5)
        mark = ">=" if r.get("lower_bound") and key == "equal_rays" else ""
        ax.text(r[key], yi, f" {mark}{r[key]:.3g}", va="center", fontsize=7)
    ax.set_yticks(y)
    ax.set_yticklabels([f"{_SCENE_LABELS.get(r['scene'], r['scene'])}: {r['model']}" for r in rs] if labels
                       else [""] * len(rs), fontsize=7.5)
    if key == "speedup":
        ax.axvline(1.0, color="k", lw=1)      # left of it the ray cast is the faster
    ax.set_xscale("log")
    lo = min(r[key] for r in rs)
    hi = max(r[key] for r in rs)
    ax.set_xlim(lo / 2, hi * 8)
    ax.set_xlabel(xlabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="x", which="both", color="0.92")
    ax.set_axisbelow(True)


def _cost(ax, cost):
    rs = [r for r in cost if r["shader"] != "ambient"]
    x = np.arange(len(rs))
    ax.bar(x - 0.2, [r["vs_ambient"] for r in rs], 0.4, color="#1f77b4", label="here: time / ambient only")
    ax.bar(x + 0.2, [r["vs_reeves_blau"] for r in rs], 0.4, color="#d62728", label="here: time / Reeves-Blau")
    for xi, r in zip(x, rs):
        ax.text(xi - 0.2, r["vs_ambient"], f"{r['vs_ambient']:.3g}", ha="center", va="bottom", fontsize=7.5)
        ax.text(xi + 0.2, r["vs_reeves_blau"], f"{r['vs_reeves_blau']:.3g}", ha="center", va="bottom", fontsize=7.5)
    paper = next((r for r in rs if r["paper_vs_ambient"] is not None), None)
    if paper is not None:
        i = rs.index(paper)
        ax.plot([i - 0.4, i], [paper["paper_vs_ambient"]] * 2, "k-", lw=2.5, label="the paper (5.0, 1.26)")
        ax.plot([i, i + 0.4], [paper["paper_vs_reeves_blau"]] * 2, "k-", lw=2.5)
    ax.set_yscale("log")
    ax.set_xticks(x)
    ax.set_xticklabels([r["shader"].replace("hegeman", "Eq. 6").replace("reeves_blau", "Reeves-Blau")
                        .replace(", ", "\n") for r in rs], fontsize=8)
    ax.set_ylabel("time per point, ratio (log)")
    ax.set_title(f"(d) the cost claim ({rs[0]['scene'] if rs else ''}, {rs[0]['timing_points'] if rs else 0} points)",
                 fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(True, axis="y", which="both", color="0.92")
    ax.set_axisbelow(True)


make = deprecated_make(__name__)
