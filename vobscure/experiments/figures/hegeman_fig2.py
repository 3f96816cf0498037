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

Regenerate with ``vobscure figures hegeman_fig2 --out docs/img`` (about 20 s; ``--quick`` in
seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 and Fig. 2.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, fitted_points_title, stacked, tree_measurements

__all__ = ["measure", "plot", "SCENES"]

#: The two leaf clouds: (registered scene name, label).
SCENES = (("leaf_cloud", "sparse cloud (1500 leaves)"), ("leaf_cloud_dense", "dense cloud (6000 leaves)"))

_SOURCES = ("fitted", "predicted", "none", "fitted x10")


ORDER = 110
FIGSIZE = (16.0, 12.5)


def measure(profile, *, trees=None) -> Rows:
    """Eq. 6 on the two leaf clouds: rows of :func:`vobscure.experiments.trees.canopy_rows`
    (bounding sphere and ellipsoid), the per-pixel images of panel (a) (quick: 40 x 40, 32
    rays; full: 128 x 128, 256) and the scored points of panel (b).
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    quick, seed = profile.quick, profile.seed
    run = tree_measurements(profile, trees)
    names = [n for n, _ in SCENES]
    rows = [r for r in X.canopy_rows(quick, seed=seed, scenes=names, measurements=run) if r["model"] == "hegeman"
            and r["shell"] in ("sphere", "ellipsoid")]
    arrays, meta = {}, {"seed": seed, "quick": quick, **X.setting(quick), "density": {}, "parameter": {}}
    for name, _ in SCENES:
        im = X.canopy_images(name, size=profile.pick((40, 40), (128, 128)), rays=profile.pick(32, 256),
                             seed=seed, quick=quick, measurements=run)
        arrays[f"{name}|truth"], arrays[f"{name}|model"] = im["truth"], im["model"]
        meta["density"][name] = im["density"]
        d = X.canopy_data(name, quick, seed=seed, measurements=run)
        for w in ("cosine", "uniform"):
            arrays[f"{name}|{w}|truth"] = np.asarray(d["truth"][w].value)[d["score"]]
            for source in ("fitted", "predicted"):
                c = next(c for c in d["configs"] if c["model"] == "hegeman" and c["shell"] == "sphere"
                         and c["source"] == source and c["reference"] == w)
                arrays[f"{name}|{w}|{source}"] = c["values"]
                meta["parameter"][f"{name}|{w}|{source}"] = c["parameter"]
    return Rows(rows, columns=X.CANOPY_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """(a) per pixel, (b) at the scored points, (c) RMSE per density source."""
    stacked(fig, rows, (_images, _scatter, _bars), [0.72, 1.0, 0.85])
    fig.suptitle(f"Hegeman et al. 2006, Fig. 2: Eq. 6 on leaf clouds ({fitted_points_title(rows.meta, 'cloud')})",
                 fontsize=13)


def _images(subfig, rows):
    from ._common import error_panel, image_panel, pixel_rmse

    axes = subfig.subplots(1, 6)
    for i, (name, label) in enumerate(SCENES):
        t, m = rows.arrays[f"{name}|truth"], rows.arrays[f"{name}|model"]
        rmse = pixel_rmse(m, t)
        a = axes[3 * i:3 * i + 3]
        image_panel(a[0], t, f"{label}\nray cast, cosine", fontsize=9)
        image_panel(a[1], m, f"Eq. 6, sphere,\nfitted density {rows.meta['density'][name]:.3g}", fontsize=9)
        e = error_panel(a[2], m, t, f"Eq. 6 - ray cast\npixel RMSE {rmse:.3f}", fontsize=9)
    subfig.colorbar(e, ax=axes, shrink=0.8, label="signed difference (right panels)")
    subfig.suptitle("(a) per pixel, as in the paper's figure: ground truth, Eq. 6, difference "
                    "(grey scale: visibility 0-1; pink: background)", fontsize=11)


def _scatter(subfig, rows):
    axes = subfig.subplots(1, 4)
    for i, (name, label) in enumerate(SCENES):
        for j, w in enumerate(("cosine", "uniform")):
            ax = axes[2 * i + j]
            truth = rows.arrays[f"{name}|{w}|truth"]
            for source, color in (("fitted", "#1f77b4"), ("predicted", "#d62728")):
                c = {"values": rows.arrays[f"{name}|{w}|{source}"],
                     "parameter": rows.meta["parameter"][f"{name}|{w}|{source}"]}
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


make = deprecated_make(__name__)
