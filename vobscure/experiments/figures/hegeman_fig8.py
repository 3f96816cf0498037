"""Hegeman et al. 2006, Figs. 3, 4, 8 and 12: the canopy model on clustered trees, its shells
(sphere, ellipsoid, several spheres) and the Reeves-Blau baseline.

One PNG, ``hegeman_fig8.png``, and the numbers it plots, ``hegeman_fig8.csv`` (the rows of
:func:`vobscure.experiments.trees.canopy_rows` with a fitted or predicted parameter, every
canopy scene: the leaf clouds are the uniform control).

(a) Per pixel on the poplar-like tree (Fig. 8): the ray-cast cosine sky visibility of the
    visible leaves, Eq. 6 on the bounding sphere and on the bounding ellipsoid (density fitted
    at points), and the two signed differences.
(b) RMSE of Eq. 6 with the fitted density per shell (bounding sphere, bounding ellipsoid,
    k = 2..5 spheres of k-means clusters, Sec. 5 and Fig. 3) on the two trees, against the
    cosine and the uniform sky visibility; dashed: the same model on the sparse and dense
    leaf clouds (the paper's "works well" case); dotted: the ground truth's stderr.
(c) Eq. 6 against Reeves-Blau (Figs. 4, 12), each with its parameter fitted (1-D least
    squares) on the bounding sphere and the ellipsoid: RMSE and Pearson correlation.

Regenerate with ``vobscure figures hegeman_fig8 --out docs/img`` (about 30 s; ``--quick`` in seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3-5 and Figs. 3, 4, 8, 12.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, fitted_points_title, stacked, tree_measurements

__all__ = ["measure", "plot"]


_TREES = (("tree", "apple-like tree"), ("tree_poplar", "poplar-like tree"))
_CLOUDS = (("leaf_cloud", "sparse cloud"), ("leaf_cloud_dense", "dense cloud"))


ORDER = 120
FIGSIZE = (17.0, 13.0)


def measure(profile, *, trees=None) -> Rows:
    """Rows of :func:`vobscure.experiments.trees.canopy_rows` with a fitted or predicted
    parameter, and the poplar's per-pixel images of panel (a) (quick: 27 x 48, 32 rays;
    full: 72 x 128, 256).
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    quick, seed = profile.quick, profile.seed
    run = tree_measurements(profile, trees)
    rows = [r for r in X.canopy_rows(quick, seed=seed, measurements=run) if r["source"] in ("fitted", "predicted")]
    im = X.canopy_images("tree_poplar", size=profile.pick((27, 48), (72, 128)), rays=profile.pick(32, 256),
                         seed=seed, quick=quick, shells=("sphere", "ellipsoid"), measurements=run)
    arrays = {"truth": im["truth"], **{f"model|{k}": v for k, v in im["models"].items()}}
    meta = {"seed": seed, "quick": quick, **X.setting(quick), "densities": dict(im["densities"])}
    return Rows(rows, columns=X.CANOPY_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """(a) the poplar per pixel, (b) the shells, (c) Reeves-Blau."""
    stacked(fig, rows, (_images, _shells, _reeves_blau), [1.05, 1.0, 1.0])
    fig.suptitle(f"Hegeman et al. 2006, Figs. 3, 4, 8, 12: Eq. 6 on clustered trees, its shells, and "
                 f"Reeves-Blau ({fitted_points_title(rows.meta, 'scene')})", fontsize=12.5)


def _images(subfig, rows):
    from ._common import error_panel, image_panel, pixel_rmse

    t = rows.arrays["truth"]
    axes = subfig.subplots(1, 5)
    image_panel(axes[0], t, "poplar-like tree\nray cast, cosine", fontsize=9)
    for k, label in enumerate(("sphere", "ellipsoid")):
        m = rows.arrays[f"model|{label}"]
        rmse = pixel_rmse(m, t)
        image_panel(axes[1 + k], m, f"Eq. 6, bounding {label}\ndensity {rows.meta['densities'][label]:.3g}",
                    fontsize=9)
        e = error_panel(axes[3 + k], m, t, f"{label} - ray cast\npixel RMSE {rmse:.3f}", fontsize=9)
    subfig.colorbar(e, ax=axes, shrink=0.8, label="signed difference")
    subfig.suptitle("(a) Fig. 8 per pixel (leaves only; pink: background, ground and wood): one "
                    "sphere against one ellipsoid on an elongated crown", fontsize=11)


def _shell_order(rows):
    labels = []
    for r in rows:
        if r["model"] == "hegeman" and r["shell"] not in labels:
            labels.append(r["shell"])
    return labels


def _shells(subfig, rows):
    axes = subfig.subplots(1, 2)
    labels = _shell_order(rows)
    colors = {"tree": "#2ca02c", "tree_poplar": "#9467bd", "leaf_cloud": "#1f77b4",
              "leaf_cloud_dense": "#17becf"}
    for ax, w in zip(axes, ("cosine", "uniform")):
        x = np.arange(len(labels))
        for name, label in _TREES:
            rs = {r["shell"]: r for r in rows if r["scene"] == name and r["model"] == "hegeman"
                  and r["source"] == "fitted" and r["reference"] == w}
            y = [rs[s]["rmse"] if s in rs else np.nan for s in labels]
            ax.plot(x, y, "o-", color=colors[name], lw=2, label=f"{label}, fitted density")
            for xi, yi in zip(x, y):
                ax.annotate(f"{yi:.3f}", (xi, yi), textcoords="offset points", xytext=(0, 5),
                            ha="center", fontsize=7.5, color=colors[name])
            se = np.nanmean([rs[s]["truth_stderr"] for s in rs])
            ax.axhline(se, color=colors[name], ls=":", lw=1)
        for name, label in _CLOUDS:
            r = next((r for r in rows if r["scene"] == name and r["model"] == "hegeman"
                      and r["source"] == "fitted" and r["reference"] == w and r["shell"] == "sphere"), None)
            if r is not None:
                ax.axhline(r["rmse"], color=colors[name], ls="--", lw=1.2,
                           label=f"{label}, sphere (uniform leaves)")
        ax.set_xticks(x)
        ax.set_xticklabels(labels)
        ax.set_xlabel("shell (fitted to the leaf centres)")
        ax.set_ylabel(f"RMSE against the {w} sky visibility")
        ax.set_ylim(bottom=0)
        ax.grid(True, axis="y", color="0.9")
        ax.set_title(f"(b) Eq. 6 per shell, {w} reference (dotted: ground-truth stderr)", fontsize=10)
        ax.legend(fontsize=8, loc="lower left")


def _reeves_blau(subfig, rows):
    axes = subfig.subplots(1, 2)
    scenes = [n for n, _ in _CLOUDS + _TREES]
    names = dict(_CLOUDS + _TREES)
    series = (("hegeman", "sphere", "Eq. 6, sphere", "#1f77b4"),
              ("hegeman", "ellipsoid", "Eq. 6, ellipsoid", "#aec7e8"),
              ("reeves_blau", "sphere", "Reeves-Blau, sphere", "#d62728"),
              ("reeves_blau", "ellipsoid", "Reeves-Blau, ellipsoid", "#ff9896"))
    width = 0.8 / len(series)
    for ax, key, ylabel in zip(axes, ("rmse", "corr"),
                               ("RMSE against the cosine sky visibility", "Pearson r with the cosine sky visibility")):
        for j, (model, shell, label, color) in enumerate(series):
            for i, name in enumerate(scenes):
                r = next((r for r in rows if r["scene"] == name and r["model"] == model and r["shell"] == shell
                          and r["source"] == "fitted" and r["reference"] == "cosine"), None)
                if r is None or r[key] is None:
                    continue
                x = i + (j - (len(series) - 1) / 2) * width
                ax.bar(x, r[key], width, color=color, label=label if i == 0 else None)
                ax.text(x, r[key], f"{r[key]:.2f}", ha="center", va="bottom", fontsize=7)
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels([names[n] for n in scenes])
        ax.set_ylabel(ylabel)
        ax.set_ylim(0, 1.05 if key == "corr" else None)
        ax.grid(True, axis="y", color="0.9")
        ax.legend(fontsize=8, loc="upper left", ncol=2)
    axes[0].set_title("(c) Eq. 6 against Reeves-Blau, each parameter fitted (1-D least squares): RMSE",
                      fontsize=10)
    axes[1].set_title("(c) ... and correlation (the paper's \"richer visual detail\")", fontsize=10)


make = deprecated_make(__name__)
