"""Canopy models: Hegeman's Eq. 6 with a fitted density against the Poisson leaf cloud's
expected visibility with nothing fitted (issue 15).

One PNG, ``canopy_models.png``, and the numbers behind it, ``canopy_models.csv`` (the rows of
:func:`vobscure.experiments.trees.poisson_rows`).

(a) Per pixel, one row per scene (the sparse and dense leaf clouds, the apple-like and the
    poplar-like tree): the ray-cast cosine sky visibility of the foliage (and of the trees'
    ground), Eq. 6 on the bounding sphere with the density fitted at leaf points (Eqs. 7-8 on
    the ground), the Poisson leaf cloud in the same sphere with ``sigma = n A / 2`` from the
    leaf count and size, and the signed errors of both.
(b) RMSE against the cosine and the uniform sky visibility per scene and shell, on leaf points
    and on foliage pixels, for both models, with the uniform leaf-cloud twins of the trees
    (same leaf count, leaf size and shell: the Poisson model's own error without clustering);
    black ticks: the ground truth's own standard error.

Regenerate with ``python -c "from vobscure.experiments.figures import canopy_models as f;
f.make('docs/img')"`` (``quick=True`` in seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 (Eqs. 4-8, the Poisson argument).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "SCENES"]

#: Name of the PNG :func:`make` writes.
FILENAME = "canopy_models.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "canopy_models.csv"
#: The scenes of panel (a): (registered name, label).
SCENES = (("leaf_cloud", "sparse leaf cloud"), ("leaf_cloud_dense", "dense leaf cloud"),
          ("tree", "apple-like tree"), ("tree_poplar", "poplar-like tree"))
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"parameter": (0.0, 1e4), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0), "corr": (-1.0, 1.0),
              "model_mean": (0.0, 1.0), "truth_mean": (0.0, 1.0), "truth_stderr": (0.0, 0.5),
              "points": (1, 10 ** 6), "truth_rays": (2, 10 ** 5)}

_COLORS = {"hegeman fitted": "#1f77b4", "poisson predicted": "#d62728"}


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``canopy_models.png`` and write ``canopy_models.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        Few points, rays and pixels (seconds), for CI.
    seed : int, optional
        Seed of the points and of the ground truth.
    rows : list of dict, optional
        Rows of :func:`vobscure.experiments.trees.poisson_rows` already measured (the same
        ``quick`` and ``seed``); measured when omitted.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import canopy_models
    >>> canopy_models.FILENAME
    'canopy_models.png'
    """
    from .. import trees as X
    from ..common import new_figure
    from ._common import write_figure

    quick = bool(quick)
    if rows is None:
        rows = X.poisson_rows(quick, seed=seed)
    fig = new_figure(16.0, 19.0)
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.55, 1.0], hspace=0.03)
    _images(top, quick, seed)
    _bars(bottom, rows)
    s = X.setting(quick)
    px = X.POISSON_PIXELS[quick]
    fig.suptitle(f"Canopy models: Eq. 6 with a fitted density against the Poisson leaf cloud, nothing "
                 f"fitted ({s['points']} leaf points per scene, {s['truth_rays']} rays; pixels "
                 f"{px['size'][0]}x{px['size'][1]}, {px['rays']} rays; seed {seed}{', quick' if quick else ''})",
                 fontsize=12.5)
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, X.POISSON_COLUMNS)


def _images(subfig, quick, seed):
    from .. import trees as X
    from ._common import error_panel, image_panel

    axes = subfig.subplots(len(SCENES), 5)
    err = None
    for i, (name, label) in enumerate(SCENES):
        im = X.poisson_images(name, shell="sphere", reference="cosine", quick=quick, seed=seed)
        t = im["truth"]
        ok = np.isfinite(t)

        def rmse(m):
            return float(np.sqrt(np.mean((m[ok] - t[ok]) ** 2))) if ok.any() else float("nan")

        a = axes[i]
        image_panel(a[0], t, f"{label}\nray cast, cosine ({im['rays']} rays)", fontsize=9)
        image_panel(a[1], im["hegeman"], f"Eq. 6, fitted density {im['density']:.3g}", fontsize=9)
        image_panel(a[2], im["poisson"], f"Poisson, sigma = nA/2 = {im['sigma']:.3g}", fontsize=9)
        error_panel(a[3], im["hegeman"], t, f"Eq. 6 - ray cast\nRMSE {rmse(im['hegeman']):.3f}", fontsize=9)
        err = error_panel(a[4], im["poisson"], t, f"Poisson - ray cast\nRMSE {rmse(im['poisson']):.3f}",
                          fontsize=9)
    subfig.colorbar(err, ax=axes, shrink=0.6, label="signed difference (right two columns)")
    subfig.suptitle("(a) per pixel, bounding sphere: ground truth, Eq. 6 fitted (Eqs. 7-8 on the ground), "
                    "Poisson predicted, and their errors (grey: visibility 0-1; pink: not scored)", fontsize=11)


def _bars(subfig, rows):
    from .. import trees as X

    axes = subfig.subplots(2, 2)
    scenes = list(X.POISSON_SCENES)
    models = ("hegeman fitted", "poisson predicted")
    for r_i, where in enumerate(("leaves", "foliage pixels")):
        for c_i, w in enumerate(X.REFERENCES):
            ax = axes[r_i, c_i]
            slots = [(sc, sh) for sc in scenes for sh in ("sphere", "ellipsoid")]
            width = 0.38
            for j, model in enumerate(models):
                for k, (sc, sh) in enumerate(slots):
                    r = next((r for r in rows if r["scene"] == sc and r["shell"] == sh and r["model"] == model
                              and r["reference"] == w and r["points_on"] == where), None)
                    if r is None:
                        continue
                    x = k + (j - 0.5) * width
                    ax.bar(x, r["rmse"], width, color=_COLORS[model], label=model if k == 0 else None)
                    ax.plot([x - width / 2, x + width / 2], [r["truth_stderr"]] * 2, color="k", lw=1.5)
            ax.set_xticks(range(len(slots)))
            ax.set_xticklabels([f"{sc}\n{sh}" for sc, sh in slots], rotation=60, ha="right", fontsize=7.5)
            ax.set_ylabel("RMSE")
            ax.set_title(f"({'b' if r_i == 0 else 'c'}) {where}, {w} sky visibility", fontsize=10)
            ax.grid(True, axis="y", color="0.9")
            ax.legend(fontsize=8, loc="upper left")
    subfig.suptitle("RMSE per scene and shell; '_uniform': a uniform leaf cloud with the tree's leaf count, "
                    "leaf size and shell (the error without clustering); black ticks: the ground truth's stderr",
                    fontsize=10.5)
