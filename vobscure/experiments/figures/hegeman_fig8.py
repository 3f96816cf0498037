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

Regenerate with ``python -c "from vobscure.experiments.figures import hegeman_fig8 as f;
f.make('docs/img')"`` (about 30 s; ``quick=True`` in seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3-5 and Figs. 3, 4, 8, 12.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES"]

#: Name of the PNG :func:`make` writes.
FILENAME = "hegeman_fig8.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "hegeman_fig8.csv"
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"shells": (1, 8), "parameter": (0.0, 1e4), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0),
              "mae": (0.0, 1.0), "corr": (-1.0, 1.0), "rmse_calibration": (0.0, 1.0), "refit": (0, 1),
              "model_mean": (0.0, 1.0), "truth_mean": (0.0, 1.0),
              "truth_stderr": (0.0, 0.5), "points": (1, 10 ** 6), "fit_points": (1, 10 ** 6),
              "truth_rays": (2, 10 ** 5)}
#: Image size (full, quick) and rays per pixel of panel (a).
IMAGE_SIZE = {False: (72, 128), True: (27, 48)}
IMAGE_RAYS = {False: 256, True: 32}

_TREES = (("tree", "apple-like tree"), ("tree_poplar", "poplar-like tree"))
_CLOUDS = (("leaf_cloud", "sparse cloud"), ("leaf_cloud_dense", "dense cloud"))


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``hegeman_fig8.png`` and write ``hegeman_fig8.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        Few points, rays and pixels (seconds), for CI.
    seed : int, optional
    rows : list of dict, optional
        Rows of :func:`vobscure.experiments.trees.canopy_rows` already measured.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import hegeman_fig8
    >>> hegeman_fig8.CSV_FILENAME
    'hegeman_fig8.csv'
    """
    from .. import trees as X
    from ..common import new_figure
    from ._common import write_figure

    quick = bool(quick)
    if rows is None:
        rows = X.canopy_rows(quick, seed=seed)
    rows = [r for r in rows if r["source"] in ("fitted", "predicted")]

    fig = new_figure(17.0, 13.0)
    top, middle, bottom = fig.subfigures(3, 1, height_ratios=[1.05, 1.0, 1.0], hspace=0.03)
    _images(top, quick, seed)
    _shells(middle, rows)
    _reeves_blau(bottom, rows)
    s = X.setting(quick)
    fig.suptitle(f"Hegeman et al. 2006, Figs. 3, 4, 8, 12: Eq. 6 on clustered trees, its shells, and "
                 f"Reeves-Blau ({s['points']} points per scene, half fitted, half scored; ground truth "
                 f"{s['truth_rays']} rays, seed {seed}{', quick' if quick else ''})", fontsize=12.5)
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, X.CANOPY_COLUMNS)


def _images(subfig, quick, seed):
    from .. import trees as X
    from ._common import error_panel, image_panel

    im = X.canopy_images("tree_poplar", size=IMAGE_SIZE[quick], rays=IMAGE_RAYS[quick], seed=seed,
                         quick=quick, shells=("sphere", "ellipsoid"))
    t = im["truth"]
    axes = subfig.subplots(1, 5)
    image_panel(axes[0], t, "poplar-like tree\nray cast, cosine", fontsize=9)
    for k, label in enumerate(("sphere", "ellipsoid")):
        m = im["models"][label]
        ok = np.isfinite(t) & np.isfinite(m)
        rmse = float(np.sqrt(np.mean((m[ok] - t[ok]) ** 2))) if ok.any() else float("nan")
        image_panel(axes[1 + k], m, f"Eq. 6, bounding {label}\ndensity {im['densities'][label]:.3g}",
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
