"""Hegeman et al. 2006, Fig. 9 (and Fig. 5, Eqs. 7-8): the tree's occlusion of the ground,
against the distance from the trunk.

One PNG, ``hegeman_fig9.png``, and the numbers it plots, ``hegeman_fig9.csv`` (the rows of
:func:`vobscure.experiments.trees.ground_rows`: per tree, occluder model, reference and ring
distance, and per tree, model and reference over all rings with ``distance`` empty).

Ground points lie on rings around the trunk, at distances given in radii R of the bounding
sphere of the leaf centres (the one sphere the models see), normal up. The ground truth is
the ray-cast sky visibility (leaves, wood; the ground itself never occludes an upward
hemisphere). The models of :func:`vobscure.trees.occluder_visibility`: ``"hegeman"`` (Eqs. 7-8,
the solid angle pi (r/d)^2 over 2 pi), ``"exact"`` (an opaque sphere, exact cosine or uniform
weighting) and ``"porous"`` (the sphere as a leaf cloud of extinction sigma = n A / (2 V), the
Poisson model with the leaves' mean projected area A / 2).

(a) Visibility against distance, per tree and reference: the ground truth (mean over the ring,
    band: +-2 standard errors of that mean from the ray cast) and the three models.
(b) RMSE against distance over the ring's points (per point, not the mean), per model; dotted:
    the ground truth's own stderr.

Regenerate with ``vobscure figures hegeman_fig9 --out docs/img`` (seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 ("Interaction with Objects", Eqs. 7-8) and Figs. 5, 9.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, tree_measurements

__all__ = ["measure", "plot", "MODELS"]

#: The occluder models: (model, label, colour).
MODELS = (("hegeman", "Eqs. 7-8 (Hegeman)", "#d62728"), ("exact", "opaque sphere, exact", "#1f77b4"),
          ("porous", "porous sphere (Poisson)", "#2ca02c"))

_TREES = (("tree", "apple-like tree"), ("tree_poplar", "poplar-like tree"))


ORDER = 130
FIGSIZE = (16.0, 11.5)


def measure(profile, *, trees=None) -> Rows:
    """Rows of :func:`vobscure.experiments.trees.ground_rows`: the ground under the trees
    (quick: three rings of eight points, few rays).
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    run = tree_measurements(profile, trees)
    meta = {"seed": profile.seed, "quick": profile.quick, **X.setting(profile.quick)}
    return Rows(X.ground_rows(profile.quick, seed=profile.seed, measurements=run), columns=X.GROUND_COLUMNS,
                meta=meta)


def plot(rows, fig) -> None:
    """The ground truth and each model per ring (top), their RMSE (bottom)."""
    s = rows.meta
    top, bottom = fig.subfigures(2, 1, height_ratios=[1.0, 1.0], hspace=0.04)
    ring = [r for r in rows if r["distance"] is not None]
    _curves(top, ring, "truth")
    _curves(bottom, ring, "rmse")
    fig.suptitle(f"Hegeman et al. 2006, Fig. 9: the tree's occlusion of the ground ({s['ring_points']} "
                 f"points per ring, ground truth {s['truth_rays']} rays, seed {s['seed']}"
                 f"{', quick' if s['quick'] else ''})", fontsize=13)


def _curves(subfig, rows, what):
    from matplotlib.lines import Line2D

    axes = subfig.subplots(1, 4)
    k = 0
    for name, label in _TREES:
        for w in ("cosine", "uniform"):
            ax = axes[k]
            k += 1
            rs = [r for r in rows if r["scene"] == name and r["reference"] == w]
            if not rs:
                continue
            if what == "truth":
                base = sorted([r for r in rs if r["model"] == MODELS[0][0]], key=lambda r: r["distance_r"])
                x = np.array([r["distance_r"] for r in base])
                y = np.array([r["truth_mean"] for r in base])
                se = np.array([r["truth_stderr"] / np.sqrt(r["points"]) for r in base])
                ax.fill_between(x, y - 2 * se, y + 2 * se, color="0.8")
                ax.plot(x, y, "k-", lw=2.2)
                for model, _, color in MODELS:
                    m = sorted([r for r in rs if r["model"] == model], key=lambda r: r["distance_r"])
                    ax.plot([r["distance_r"] for r in m], [r["model_mean"] for r in m], "o--", color=color,
                            ms=4, lw=1.5)
                ax.set_ylabel(f"sky visibility, {w} (ring mean)")
                ax.set_ylim(0, 1.02)
            else:
                for model, _, color in MODELS:
                    m = sorted([r for r in rs if r["model"] == model], key=lambda r: r["distance_r"])
                    ax.plot([r["distance_r"] for r in m], [r["rmse"] for r in m], "o-", color=color, ms=4)
                base = sorted([r for r in rs if r["model"] == MODELS[0][0]], key=lambda r: r["distance_r"])
                ax.plot([r["distance_r"] for r in base], [r["truth_stderr"] for r in base], "k:", lw=1.5)
                ax.set_ylabel(f"RMSE against the {w} reference")
                ax.set_ylim(bottom=0)
            ax.axvline(1.0, color="0.6", lw=0.8)
            ax.set_xlabel("distance from the trunk / R (sphere radius)")
            ax.set_title(f"{label}, {w}", fontsize=10)
            ax.grid(True, color="0.92")
    if what == "truth":
        handles = [Line2D([], [], color="k", lw=2.2, label="ray cast (band: +-2 stderr of the mean)")]
        handles += [Line2D([], [], color=c, ls="--", marker="o", ms=4, label=lab) for _, lab, c in MODELS]
        subfig.suptitle("(a) visibility of the ground against the distance from the trunk (grey line: the "
                        "bounding sphere's radius)", fontsize=11)
    else:
        handles = [Line2D([], [], color=c, marker="o", ms=4, label=lab) for _, lab, c in MODELS]
        handles += [Line2D([], [], color="k", ls=":", label="ground truth's stderr (per point)")]
        subfig.suptitle("(b) RMSE over each ring's points against the distance from the trunk", fontsize=11)
    subfig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=9, frameon=False)


make = deprecated_make(__name__)
