"""Hegeman et al. 2006, Fig. 10 (and Fig. 6, Eq. 9): visibility on grass blades against the
height on the blade and its orientation.

One PNG, ``hegeman_fig10.png``, and the numbers it plots, ``hegeman_fig10.csv`` (the rows of
:func:`vobscure.experiments.trees.grass_rows`: per reference, relative-height bin and
orientation bin; the rows with ``height_lo`` 0 and ``height_hi`` 1 are over every point).

Points are sampled on blades of the central half of the ``grass`` field (away from its
edges), at stratified relative heights P_z / h, with the normal of the blade's side that
faces up; cos theta of Eq. 9 is that normal's vertical component (the blades lean by up to 30
degrees, so cos theta is in [0, 0.5]). Eq. 9: V = P_z / (2 h) (1 + cos theta).

(a) Every point: ray-cast sky visibility (cosine, uniform) and Eq. 9 against P_z / h.
(b) Bin means against P_z / h, per orientation bin: the ground truth (band +-2 standard errors
    of the bin mean) and Eq. 9.
(c) RMSE and bias of Eq. 9 per height bin (all orientations), both references; dotted: the
    ground truth's stderr.

Regenerate with ``vobscure figures hegeman_fig10 --out docs/img`` (seconds).

References
----------
Hegeman, Premoze, Ashikhmin, Drettakis 2006, "Approximate ambient occlusion for trees",
I3D 2006, Sec. 3 ("Visibility approximation for grass", Eq. 9) and Figs. 6, 10.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, tree_measurements

__all__ = ["measure", "plot"]


_COLORS = {"cosine": "#1f77b4", "uniform": "#ff7f0e"}


ORDER = 140
FIGSIZE = (16.0, 11.0)


def measure(profile, *, trees=None) -> Rows:
    """Rows of :func:`vobscure.experiments.trees.grass_rows` and, for panel (a), every
    point's relative height, Eq. 9 and the ground truth (quick: few points and rays).
    ``trees``: the run's shared tree measurements (:mod:`vobscure.experiments.figures`)."""
    from .. import trees as X

    quick, seed = profile.quick, profile.seed
    run = tree_measurements(profile, trees)
    rows = X.grass_rows(quick, seed=seed, measurements=run)
    d = X.grass_data(quick, seed=seed, measurements=run)
    arrays = {"height": d["height"], "model": d["model"],
              **{f"truth|{w}": np.asarray(d["truth"][w].value) for w in ("cosine", "uniform")}}
    meta = {"seed": seed, "quick": quick, **X.setting(quick)}
    return Rows(rows, columns=X.GRASS_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """(a) every point against its height, (b)-(d) per height bin."""
    s, a = rows.meta, rows.arrays
    top, bottom = fig.subfigures(2, 1, hspace=0.04)
    axes = top.subplots(1, 2)
    for ax, w in zip(axes, ("cosine", "uniform")):
        ax.scatter(a["height"], a[f"truth|{w}"], s=6, alpha=0.45, color=_COLORS[w], label=f"ray cast, {w}")
        ax.scatter(a["height"], a["model"], s=6, alpha=0.45, color="#d62728", label="Eq. 9")
        overall = next(r for r in rows if r["reference"] == w and r["height_lo"] == 0.0
                       and r["height_hi"] == 1.0)
        ax.set_title(f"(a) every point, {w} reference: Eq. 9 RMSE {overall['rmse']:.3f}, bias "
                     f"{overall['bias']:+.3f}, r {_fmt(overall['corr'])} (stderr {overall['truth_stderr']:.3f})",
                     fontsize=10)
        ax.set_xlabel("relative height on the blade, P_z / h")
        ax.set_ylabel("sky visibility")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.02)
        ax.grid(True, color="0.92")
        ax.legend(fontsize=9, loc="upper left", markerscale=2)
    axes = bottom.subplots(1, 3)
    _bins(axes[0], rows, "cosine")
    _bins(axes[1], rows, "uniform")
    _errors(axes[2], rows)
    fig.suptitle(f"Hegeman et al. 2006, Fig. 10: Eq. 9 on grass blades ({s['grass_points']} points, "
                 f"ground truth {s['truth_rays']} rays, seed {s['seed']}{', quick' if s['quick'] else ''})",
                 fontsize=13)


def _fmt(x):
    return "n/a" if x is None else f"{x:.2f}"


def _binned(rows, w):
    """Height-bin rows by orientation bin ((cos_lo, cos_hi) -> sorted rows), all-orientation rows
    under the key None."""
    lo_all = min(r["cos_lo"] for r in rows)
    hi_all = max(r["cos_hi"] for r in rows)
    out = {}
    for r in rows:
        if r["reference"] != w or (r["height_lo"] == 0.0 and r["height_hi"] == 1.0):
            continue
        key = None if (r["cos_lo"], r["cos_hi"]) == (lo_all, hi_all) else (r["cos_lo"], r["cos_hi"])
        out.setdefault(key, []).append(r)
    return {k: sorted(v, key=lambda r: r["height_lo"]) for k, v in out.items()}


def _bins(ax, rows, w):
    styles = ["-", "--", ":"]
    for i, (key, rs) in enumerate(sorted(_binned(rows, w).items(), key=lambda kv: (kv[0] is not None, kv[0]))):
        if key is None:
            continue
        x = np.array([(r["height_lo"] + r["height_hi"]) / 2 for r in rs])
        t = np.array([r["truth_mean"] for r in rs])
        se = np.array([r["truth_stderr"] / np.sqrt(r["points"]) for r in rs])
        ls = styles[(i - 1) % len(styles)]
        label = f"cos theta {key[0]:.2f}-{key[1]:.2f}"
        ax.fill_between(x, t - 2 * se, t + 2 * se, color=_COLORS[w], alpha=0.2)
        ax.plot(x, t, ls, color=_COLORS[w], marker="o", ms=4, label=f"ray cast, {label}")
        ax.plot(x, [r["model_mean"] for r in rs], ls, color="#d62728", marker="s", ms=4, label=f"Eq. 9, {label}")
    ax.set_xlabel("relative height on the blade, P_z / h")
    ax.set_ylabel(f"bin mean of the sky visibility, {w}")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.grid(True, color="0.92")
    ax.legend(fontsize=7.5, loc="upper left")
    ax.set_title(f"(b) bin means by orientation, {w} reference", fontsize=10)


def _errors(ax, rows):
    for w in ("cosine", "uniform"):
        rs = _binned(rows, w).get(None, [])
        x = [(r["height_lo"] + r["height_hi"]) / 2 for r in rs]
        ax.plot(x, [r["rmse"] for r in rs], "o-", color=_COLORS[w], label=f"RMSE, {w}")
        ax.plot(x, [r["bias"] for r in rs], "s--", color=_COLORS[w], label=f"bias, {w}")
        ax.plot(x, [r["truth_stderr"] for r in rs], ":", color=_COLORS[w], label=f"ground-truth stderr, {w}")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("relative height on the blade, P_z / h")
    ax.set_ylabel("Eq. 9 - ray cast")
    ax.set_xlim(0, 1)
    ax.grid(True, color="0.92")
    ax.legend(fontsize=7.5, loc="best")
    ax.set_title("(c) Eq. 9's RMSE and bias per height bin", fontsize=10)


make = deprecated_make(__name__)
