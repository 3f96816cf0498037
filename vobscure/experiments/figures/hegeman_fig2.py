"""Hegeman et al. 2006, Fig. 2: the canopy model (Eqs. 4-6) on leaf clouds of two densities.

One PNG, ``hegeman_fig2.png``, and the numbers it plots, ``hegeman_fig2.csv`` (the rows of
:func:`vobscure.experiments.trees.canopy_rows` for the two leaf clouds, Eq. 6 on the
bounding sphere and ellipsoid).

(a) Per pixel, as in the paper's figure: the ray-cast cosine sky visibility of the visible
    leaves, Eq. 6 on the bounding sphere with the density fitted at points, and their signed
    difference, for the sparse (``leaf_cloud``) and the dense (``leaf_cloud_dense``) cloud.
(b) At points sampled on the leaves (the side facing out of the cloud), scored on the half
    not used for the fit: Eq. 6 against the ground truth, fitted and predicted density; the
    lines join the means of ten equal-count bins of the model's value (the average visibility
    the model predicts, whose error is ``rmse_calibration``).
(c) RMSE of Eq. 6 per density source (fitted, predicted, none, 10 x fitted) against the
    cosine-weighted and the uniform sky visibility; the ticks mark the ground truth's own
    standard error (the noise floor).

Regenerate with ``python -c "from vobscure.experiments.figures import hegeman_fig2 as f;
f.make('docs/img')"`` (about 20 s; ``quick=True`` in seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 and Fig. 2.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "SCENES"]

#: Name of the PNG :func:`make` writes.
FILENAME = "hegeman_fig2.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "hegeman_fig2.csv"
#: The two leaf clouds: (registered scene name, label).
SCENES = (("leaf_cloud", "sparse cloud (1500 leaves)"), ("leaf_cloud_dense", "dense cloud (6000 leaves)"))
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"shells": (1, 1), "parameter": (0.0, 1e4), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0),
              "mae": (0.0, 1.0), "corr": (-1.0, 1.0), "rmse_calibration": (0.0, 1.0), "refit": (0, 1),
              "model_mean": (0.0, 1.0), "truth_mean": (0.0, 1.0),
              "truth_stderr": (0.0, 0.5), "points": (1, 10 ** 6), "fit_points": (1, 10 ** 6),
              "truth_rays": (2, 10 ** 5)}
#: Image size (full, quick) and rays per pixel of panel (a).
IMAGE_SIZE = {False: (128, 128), True: (40, 40)}
IMAGE_RAYS = {False: 256, True: 32}

_SOURCES = ("fitted", "predicted", "none", "fitted x10")


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``hegeman_fig2.png`` and write ``hegeman_fig2.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        Few points, rays and pixels (seconds), for CI.
    seed : int, optional
        Seed of the points and of the ground truth.
    rows : list of dict, optional
        Rows of :func:`vobscure.experiments.trees.canopy_rows` already measured (the same
        ``quick`` and ``seed``); measured when omitted.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import hegeman_fig2
    >>> hegeman_fig2.FILENAME
    'hegeman_fig2.png'
    """
    from .. import trees as X
    from ..common import new_figure
    from ._common import write_figure

    quick = bool(quick)
    names = [n for n, _ in SCENES]
    if rows is None:
        rows = X.canopy_rows(quick, seed=seed, scenes=names)
    rows = [r for r in rows if r["scene"] in names and r["model"] == "hegeman"
            and r["shell"] in ("sphere", "ellipsoid")]

    fig = new_figure(16.0, 12.5)
    top, middle, bottom = fig.subfigures(3, 1, height_ratios=[0.72, 1.0, 0.85], hspace=0.03)
    _images(top, quick, seed)
    _scatter(middle, quick, seed)
    _bars(bottom, rows)
    s = X.setting(quick)
    fig.suptitle(f"Hegeman et al. 2006, Fig. 2: Eq. 6 on leaf clouds ({s['points']} points per cloud, "
                 f"half fitted, half scored; ground truth {s['truth_rays']} rays, seed {seed}"
                 f"{', quick' if quick else ''})", fontsize=13)
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, X.CANOPY_COLUMNS)


def _images(subfig, quick, seed):
    from .. import trees as X
    from ._common import error_panel, image_panel

    axes = subfig.subplots(1, 6)
    for i, (name, label) in enumerate(SCENES):
        im = X.canopy_images(name, size=IMAGE_SIZE[quick], rays=IMAGE_RAYS[quick], seed=seed, quick=quick)
        t, m = im["truth"], im["model"]
        ok = np.isfinite(t) & np.isfinite(m)
        rmse = float(np.sqrt(np.mean((m[ok] - t[ok]) ** 2))) if ok.any() else float("nan")
        a = axes[3 * i:3 * i + 3]
        image_panel(a[0], t, f"{label}\nray cast, cosine", fontsize=9)
        image_panel(a[1], m, f"Eq. 6, sphere,\nfitted density {im['density']:.3g}", fontsize=9)
        e = error_panel(a[2], m, t, f"Eq. 6 - ray cast\npixel RMSE {rmse:.3f}", fontsize=9)
    subfig.colorbar(e, ax=axes, shrink=0.8, label="signed difference (right panels)")
    subfig.suptitle("(a) per pixel, as in the paper's figure: ground truth, Eq. 6, difference "
                    "(grey scale: visibility 0-1; pink: background)", fontsize=11)


def _scatter(subfig, quick, seed):
    from .. import trees as X

    axes = subfig.subplots(1, 4)
    for i, (name, label) in enumerate(SCENES):
        d = X.canopy_data(name, quick, seed=seed)
        for j, w in enumerate(("cosine", "uniform")):
            ax = axes[2 * i + j]
            truth = np.asarray(d["truth"][w].value)[d["score"]]
            for source, color in (("fitted", "#1f77b4"), ("predicted", "#d62728")):
                c = next(c for c in d["configs"] if c["model"] == "hegeman" and c["shell"] == "sphere"
                         and c["source"] == source and c["reference"] == w)
                e = float(np.sqrt(np.mean((c["values"] - truth) ** 2)))
                ax.scatter(truth, c["values"], s=5, alpha=0.35, color=color,
                           label=f"{source} ({c['parameter']:.3g}): RMSE {e:.3f}")
                # bin means (equal counts by the model's value): the average the model predicts
                order = np.argsort(c["values"], kind="stable")
                groups = [g for g in np.array_split(order, 10) if len(g)]
                ax.plot([truth[g].mean() for g in groups], [c["values"][g].mean() for g in groups], "-o",
                        color=color, mec="k", mew=0.6, ms=5, lw=1.8)
            ax.plot([0, 1], [0, 1], color="k", lw=0.8)
            ax.set_xlim(0, 1)
            ax.set_ylim(0, 1)
            ax.set_aspect("equal")
            ax.set_xlabel(f"ray-cast sky visibility, {w}")
            ax.set_ylabel("Eq. 6, bounding sphere")
            ax.set_title(f"{label}\nagainst the {w} reference", fontsize=9.5)
            ax.legend(fontsize=7.5, loc="upper left", title="density", title_fontsize=7.5)
    subfig.suptitle("(b) at points on the leaves (scored half): Eq. 6 with the fitted and the "
                    "predicted density against the ground truth; lines: means of ten equal-count bins "
                    "of the model's value", fontsize=11)


def _bars(subfig, rows):
    axes = subfig.subplots(1, 2)
    colors = {"fitted": "#1f77b4", "predicted": "#d62728", "none": "#7f7f7f", "fitted x10": "#ff7f0e"}
    for ax, w in zip(axes, ("cosine", "uniform")):
        width = 0.8 / len(_SOURCES)
        for j, source in enumerate(_SOURCES):
            for i, (name, _) in enumerate(SCENES):
                r = next((r for r in rows if r["scene"] == name and r["shell"] == "sphere"
                          and r["source"] == source and r["reference"] == w), None)
                if r is None:
                    continue
                x = i + (j - (len(_SOURCES) - 1) / 2) * width
                ax.bar(x, r["rmse"], width, color=colors[source], label=source if i == 0 else None)
                ax.text(x, r["rmse"], f"{r['rmse']:.3f}", ha="center", va="bottom", fontsize=7.5)
                ax.plot([x - width / 2, x + width / 2], [r["truth_stderr"]] * 2, color="k", lw=2)
        ax.set_xticks(range(len(SCENES)))
        ax.set_xticklabels([label for _, label in SCENES])
        ax.set_ylabel(f"RMSE against the {w} sky visibility")
        ax.set_title(f"(c) RMSE of Eq. 6 (bounding sphere), {w} reference; black ticks: the ground "
                     "truth's stderr", fontsize=10)
        ax.set_ylim(0, max(0.05, 1.15 * max(r["rmse"] for r in rows if r["reference"] == w)))
        ax.legend(fontsize=8.5, title="density", title_fontsize=8.5, loc="upper left")
        ax.grid(True, axis="y", color="0.9")
