"""Canopy models: Hegeman's Eq. 6 with a fitted density against the Poisson leaf cloud's
expected visibility with nothing fitted.

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

Regenerate with ``vobscure figures canopy_models --out docs/img`` (``--quick`` in seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 (Eqs. 4-8, the Poisson argument).
"""

from __future__ import annotations

from . import deprecated_make
from ._common import Rows, tree_measurements

__all__ = ["measure", "plot", "SCENES"]

ORDER = 170
FIGSIZE = (16.0, 19.0)

#: The scenes of panel (a): (registered name, label).
SCENES = (("leaf_cloud", "sparse leaf cloud"), ("leaf_cloud_dense", "dense leaf cloud"),
          ("tree", "apple-like tree"), ("tree_poplar", "poplar-like tree"))

_COLORS = {"hegeman fitted": "#1f77b4", "poisson predicted": "#d62728"}


def measure(profile, *, trees=None) -> Rows:
    """The rows of :func:`vobscure.experiments.trees.poisson_rows` and the per-pixel images of
    panel (a) (:func:`~vobscure.experiments.trees.poisson_images`, bounding sphere, cosine
    reference); quick: few points, rays and pixels.
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    quick, seed = profile.quick, profile.seed
    run = tree_measurements(profile, trees)
    rows = X.poisson_rows(quick, seed=seed, measurements=run)
    arrays, meta = {}, {"seed": seed, "quick": quick, **X.setting(quick), "pixels": dict(X.POISSON_PIXELS[quick]),
                        "images": {}}
    for name, _ in SCENES:
        im = X.poisson_images(name, shell="sphere", reference="cosine", quick=quick, seed=seed,
                              measurements=run)
        for key in ("truth", "hegeman", "poisson"):
            arrays[f"{name}|{key}"] = im[key]
        meta["images"][name] = {"rays": im["rays"], "density": im["density"], "sigma": im["sigma"]}
    return Rows(rows, columns=X.POISSON_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """(a) per pixel, (b)-(c) RMSE per scene and shell."""
    s = rows.meta
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.55, 1.0], hspace=0.03)
    _images(top, rows)
    _bars(bottom, rows)
    px = s["pixels"]
    fig.suptitle(f"Canopy models: Eq. 6 with a fitted density against the Poisson leaf cloud, nothing "
                 f"fitted ({s['points']} leaf points per scene, {s['truth_rays']} rays; pixels "
                 f"{px['size'][0]}x{px['size'][1]}, {px['rays']} rays; seed {s['seed']}"
                 f"{', quick' if s['quick'] else ''})", fontsize=12.5)


def _images(subfig, rows):
    from ._common import error_panel, image_panel, pixel_rmse

    axes = subfig.subplots(len(SCENES), 5)
    err = None
    for i, (name, label) in enumerate(SCENES):
        im = {key: rows.arrays[f"{name}|{key}"] for key in ("truth", "hegeman", "poisson")}
        im.update(rows.meta["images"][name])
        t = im["truth"]
        a = axes[i]
        image_panel(a[0], t, f"{label}\nray cast, cosine ({im['rays']} rays)", fontsize=9)
        image_panel(a[1], im["hegeman"], f"Eq. 6, fitted density {im['density']:.3g}", fontsize=9)
        image_panel(a[2], im["poisson"], f"Poisson, sigma = nA/2 = {im['sigma']:.3g}", fontsize=9)
        error_panel(a[3], im["hegeman"], t, f"Eq. 6 - ray cast\nRMSE {pixel_rmse(im['hegeman'], t):.3f}",
                    fontsize=9)
        err = error_panel(a[4], im["poisson"], t, f"Poisson - ray cast\nRMSE {pixel_rmse(im['poisson'], t):.3f}",
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


make = deprecated_make(__name__)
