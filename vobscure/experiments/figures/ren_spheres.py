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

Regenerate with ``vobscure figures ren_spheres --out docs/img`` (a few minutes on 2 cores;
``--quick`` in seconds).

References
----------
Ren, Wang, Snyder, Zhou, Liu, Sun, Sloan, Bao, Peng, Guo, "Real-time Soft Shadows in Dynamic
Scenes using Spherical Harmonic Exponentiation", SIGGRAPH 2006.
"""

from __future__ import annotations

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "COLUMNS"]

ORDER = 180
FIGSIZE = (18.0, 11.0)

COLUMNS = ("table", "method", "exp", "order", "count", "points", "rmse", "bias", "max_abs", "ref_stderr",
           "depth_lo", "depth_hi", "product_us", "shexp_us", "sum_us", "ratio_product_shexp")

_STYLE = {("product", ""): ("k", "-", "product"), ("sum", ""): ("#888888", ":", "sum"),
          ("shexp", "hybrid"): ("#d62728", "-", "shexp, hybrid"), ("shexp", "ol"): ("#ff7f0e", "--", "shexp, OL"),
          ("shexp", "exact"): ("#1f77b4", "-.", "shexp, exact exp*")}


def measure(profile) -> Rows:
    """The rows of :func:`vobscure.experiments.spheres.union_rows` (``table`` "count" and
    "depth") and :func:`~vobscure.experiments.spheres.timing_rows` ("timing"); quick: few
    spheres, points and rays."""
    from .. import spheres as X

    quick, seed = profile.quick, profile.seed
    by_count, by_depth = X.union_rows(quick, seed=seed)
    timing = X.timing_rows(quick, seed=seed)
    table = ([{"table": "count", **r} for r in by_count] + [{"table": "depth", **r} for r in by_depth]
             + [{"table": "timing", **r} for r in timing])
    return Rows(table, columns=COLUMNS, meta={"seed": seed, "quick": quick, **X.setting(quick)})


def plot(rows, fig) -> None:
    """(a)-(d) error per order, (e) against depth, (f) time, (g) speed-up."""
    s = rows.meta
    rows = {t: [r for r in rows if r["table"] == t] for t in ("count", "depth", "timing")}
    for r in rows["count"] + rows["depth"]:
        r["exp"] = r["exp"] or ""        # an empty cell: no exponential (product, sum)
    orders = sorted({r["order"] for r in rows["count"]})
    grid = fig.subplots(2, max(3, len(orders)), squeeze=False)
    for ax, order in zip(grid[0], orders):
        for key, (color, ls, label) in _STYLE.items():
            rs = [r for r in rows["count"] if (r["method"], r["exp"]) == key and r["order"] == order]
            ax.plot([r["count"] for r in rs], [r["rmse"] for r in rs], color=color, ls=ls, marker="o", ms=3,
                    label=label)
        rs = [r for r in rows["count"] if (r["method"], r["exp"]) == ("product", "") and r["order"] == order]
        ax.plot([r["count"] for r in rs], [r["ref_stderr"] for r in rs], color="0.6", ls=":", lw=1,
                label="union reference stderr")
        _over_spheres(ax, "RMSE against the exact union", f"order {order} ({order * order} coefficients)")
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
    _over_spheres(ax, "microseconds per receiver",
                  f"(f) time per receiver ({s['timing_points']} receivers, min of {s['repeats']})")
    ax.legend(fontsize=7)
    ax = grid[1][2]
    for order, ls in zip(sorted({r["order"] for r in rows["timing"]}), ("-", "--")):
        rs = [r for r in rows["timing"] if r["order"] == order]
        ax.plot([r["count"] for r in rs], [r["ratio_product_shexp"] for r in rs], "k", ls=ls, marker="o",
                label=f"order {order}")
    ax.axhline(10.0, color="#d62728", lw=1, ls=":", label="the paper's 10x")
    _over_spheres(ax, "time of product / time of shexp", "(g) speed-up of shexp over product (same run)")
    ax.legend(fontsize=8)
    for ax in grid[1][3:]:
        ax.set_visible(False)
    fig.suptitle(f"Ren et al. 2006 sphere sets in SH against the exact union ({s['union_rays']} rays per point, "
                 f"scales {', '.join(map(str, s['scales']))}, seed {s['seed']}{', quick' if s['quick'] else ''})",
                 fontsize=12)



def _over_spheres(ax, ylabel, title):
    """A panel over the sphere count: log-log (count in powers of 2), labels, a light grid."""
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("spheres")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3)


make = deprecated_make(__name__)
