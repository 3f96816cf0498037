"""Ren et al. (2006) sphere sets in SH against the exact union of the same spheres: error and
time against the number of spheres, per method and order.

One PNG, ``ren_spheres.png``, and the numbers it plots, ``ren_spheres.csv`` (column
``table``: ``"count"`` rows of :func:`vobscure.experiments.spheres.union_rows`, ``"depth"``
rows, ``"timing"`` rows of :func:`~vobscure.experiments.spheres.timing_rows`).

(a)-(d) RMSE against the exact union visibility (analytic ray-sphere tests) against the number
    of spheres, one panel per order, one line per method (``product``, ``sum``, ``shexp``
    with the hybrid, optimal-linear and exact exponentials); the union reference's RMS
    standard error dotted.
(e) RMSE against the occlusion depth (the union's 1 - V), all counts pooled, order 4 and 6.
(f) Time per receiver against the number of spheres, product against shexp (and sum), with
    the ratio product / shexp printed per count: measured in the same run.

Regenerate with ``python -c "from vobscure.experiments.figures import ren_spheres as f;
f.make('docs/img')"`` (a few minutes on 2 cores; ``quick=True`` in seconds).

References
----------
Ren, Wang, Snyder, Zhou, Liu, Sun, Sloan, Bao, Peng, Guo, "Real-time Soft Shadows in Dynamic
Scenes using Spherical Harmonic Exponentiation", SIGGRAPH 2006.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "COLUMNS"]

FILENAME = "ren_spheres.png"
CSV_FILENAME = "ren_spheres.csv"
COLUMNS = ("table", "method", "exp", "order", "count", "points", "rmse", "bias", "max_abs", "ref_stderr",
           "depth_lo", "depth_hi", "product_us", "shexp_us", "sum_us", "ratio_product_shexp")
CSV_RANGES = {"order": (1, 8), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0), "ref_stderr": (0.0, 0.5),
              "depth_lo": (0.0, 1.0), "depth_hi": (0.0, 1.0), "ratio_product_shexp": (0.0, 10 ** 4)}

_STYLE = {("product", ""): ("k", "-", "product"), ("sum", ""): ("#888888", ":", "sum"),
          ("shexp", "hybrid"): ("#d62728", "-", "shexp, hybrid"), ("shexp", "ol"): ("#ff7f0e", "--", "shexp, OL"),
          ("shexp", "exact"): ("#1f77b4", "-.", "shexp, exact exp*")}


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``ren_spheres.png`` and write ``ren_spheres.csv``.

    Parameters
    ----------
    out_dir : str or path-like
    quick : bool, optional
        Few spheres, points and rays (seconds), for CI.
    seed : int, optional
    rows : dict, optional
        ``{"count": ..., "depth": ..., "timing": ...}`` already measured.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import ren_spheres
    >>> ren_spheres.FILENAME
    'ren_spheres.png'
    """
    from .. import spheres as X
    from ..common import new_figure
    from ._common import write_figure

    quick = bool(quick)
    if rows is None:
        by_count, by_depth = X.union_rows(quick, seed=seed)
        rows = {"count": by_count, "depth": by_depth, "timing": X.timing_rows(quick, seed=seed)}
    s = X.setting(quick)
    orders = sorted({r["order"] for r in rows["count"]})
    fig = new_figure(18.0, 11.0)
    grid = fig.subplots(2, max(3, len(orders)), squeeze=False)
    for ax, order in zip(grid[0], orders):
        for key, (color, ls, label) in _STYLE.items():
            rs = [r for r in rows["count"] if (r["method"], r["exp"]) == key and r["order"] == order]
            ax.plot([r["count"] for r in rs], [r["rmse"] for r in rs], color=color, ls=ls, marker="o", ms=3,
                    label=label)
        rs = [r for r in rows["count"] if (r["method"], r["exp"]) == ("product", "") and r["order"] == order]
        ax.plot([r["count"] for r in rs], [r["ref_stderr"] for r in rs], color="0.6", ls=":", lw=1,
                label="union reference stderr")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("spheres")
        ax.set_ylabel("RMSE against the exact union")
        ax.set_title(f"order {order} ({order * order} coefficients)", fontsize=10)
        ax.grid(alpha=0.3)
    grid[0][0].legend(fontsize=8)
    for ax in grid[0][len(orders):]:
        ax.set_visible(False)
    ax = grid[1][0]
    for order, marker in ((min(orders), "o"), (max(orders), "s")):
        for key, (color, ls, label) in _STYLE.items():
            rs = [r for r in rows["depth"] if (r["method"], r["exp"]) == key and r["order"] == order]
            ax.plot([0.5 * (r["depth_lo"] + r["depth_hi"]) for r in rs], [r["rmse"] for r in rs], color=color,
                    ls=ls, marker=marker, ms=4, label=f"{label}, order {order}")
    ax.set_xlabel("occlusion depth (union's 1 - V), bin centre")
    ax.set_ylabel("RMSE against the exact union")
    ax.set_title("(e) error against occlusion depth, all counts pooled", fontsize=10)
    ax.legend(fontsize=6.5, ncol=2)
    ax.grid(alpha=0.3)
    ax = grid[1][1]
    for order, ls in zip(sorted({r["order"] for r in rows["timing"]}), ("-", "--")):
        rs = [r for r in rows["timing"] if r["order"] == order]
        x = [r["count"] for r in rs]
        ax.plot(x, [r["product_us"] for r in rs], "k", ls=ls, marker="o", ms=3, label=f"product, order {order}")
        ax.plot(x, [r["shexp_us"] for r in rs], color="#d62728", ls=ls, marker="o", ms=3,
                label=f"shexp (hybrid), order {order}")
        ax.plot(x, [r["sum_us"] for r in rs], color="#888888", ls=ls, marker="o", ms=3, label=f"sum, order {order}")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("spheres")
    ax.set_ylabel("microseconds per receiver")
    ax.set_title(f"(f) time per receiver ({s['timing_points']} receivers, min of {s['repeats']})", fontsize=10)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax = grid[1][2]
    for order, ls in zip(sorted({r["order"] for r in rows["timing"]}), ("-", "--")):
        rs = [r for r in rows["timing"] if r["order"] == order]
        ax.plot([r["count"] for r in rs], [r["ratio_product_shexp"] for r in rs], "k", ls=ls, marker="o",
                label=f"order {order}")
    ax.axhline(10.0, color="#d62728", lw=1, ls=":", label="the paper's 10x")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("spheres")
    ax.set_ylabel("time of product / time of shexp")
    ax.set_title("(g) speed-up of shexp over product (same run)", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    for ax in grid[1][3:]:
        ax.set_visible(False)
    fig.suptitle(f"Ren et al. 2006 sphere sets in SH against the exact union ({s['union_rays']} rays per point, "
                 f"scales {', '.join(map(str, s['scales']))}, seed {seed}{', quick' if quick else ''})",
                 fontsize=12)
    table = ([{"table": "count", **r} for r in rows["count"]] + [{"table": "depth", **r} for r in rows["depth"]]
             + [{"table": "timing", **r} for r in rows["timing"]])
    return write_figure(fig, out_dir, FILENAME, table, CSV_FILENAME, COLUMNS)
