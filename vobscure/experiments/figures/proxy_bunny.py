"""Sphere-set proxies against the mesh itself: ground-plane AO under the Stanford bunny and on
the Cornell box's floor around its two boxes, Embree ground truth beside k = 8, 32, 128
inscribed spheres (Ren et al. 2006's SH, order 4, shexp).

One PNG, ``proxy_bunny.png``, and the numbers, ``proxy_bunny.csv`` (the rows of
:func:`vobscure.experiments.spheres.proxy_rows`: per target, k and method -- ``shexp``,
``product`` and the spheres' exact ``union`` -- the RMSE, bias and correlation against the
Embree AO of the mesh). Without ``../shared/data/meshes/stanford-bunny.obj`` only the Cornell
row is drawn.

Per target, one row of images seen from above (cosine AO on the ground, no distance limit):
the Embree AO of the mesh, then the shexp AO of k spheres for each k, then its signed error
for the largest k.

Regenerate with ``vobscure figures proxy_bunny --out docs/img`` (a minute or two; ``--quick`` in
seconds).
"""

from __future__ import annotations

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "COLUMNS"]

ORDER = 190

COLUMNS = ("target", "k", "method", "order", "points", "rmse", "bias", "corr", "ref_stderr", "spheres_volume_ratio")

_LABELS = {"bunny": "ground under the bunny", "cornell_boxes": "Cornell box floor around the boxes"}


def measure(profile) -> Rows:
    """The rows of :func:`vobscure.experiments.spheres.proxy_rows` and its images (quick:
    few points and rays)."""
    from .. import spheres as X

    quick, seed = profile.quick, profile.seed
    table, images = X.proxy_rows(quick, seed=seed, images=True)
    s = X.setting(quick)
    ks = list(s["proxy_ks"])
    arrays = {}
    for target, pics in images.items():
        arrays[f"{target}|truth"] = pics["truth"]
        for k in ks:
            arrays[f"{target}|{k}|shexp"] = pics[k]["shexp"]
    meta = {"seed": seed, "quick": quick, "targets": list(images), "proxy_ks": ks,
            "proxy_order": s["proxy_order"], "proxy_rays": s["proxy_rays"]}
    return Rows(table, columns=COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """One row of images per target: the mesh's AO, the spheres' for each k, the error."""
    from ._common import error_panel, image_panel

    s, a = rows.meta, rows.arrays
    table, targets, ks = rows, s["targets"], s["proxy_ks"]
    # one row per target; without the bunny (its mesh lives outside the repository) only the
    # Cornell box row is drawn, with a line saying why, in a figure no smaller than two rows
    fig.set_size_inches(4.0 * (len(ks) + 2), 4.4 * max(len(targets), 2) + 0.8)
    axes = fig.subplots(len(targets), len(ks) + 2, squeeze=False)
    for row, target in zip(axes, targets):
        image_panel(row[0], a[f"{target}|truth"], f"{_LABELS.get(target, target)}:\nEmbree AO of the mesh")
        for ax, k in zip(row[1:], ks):
            r = next(x for x in table if x["target"] == target and x["k"] == k and x["method"] == "shexp")
            u = next(x for x in table if x["target"] == target and x["k"] == k and x["method"] == "union")
            image_panel(ax, a[f"{target}|{k}|shexp"], f"k = {k} spheres, shexp order {s['proxy_order']}\n"
                        f"RMSE {r['rmse']:.3f} (union of spheres {u['rmse']:.3f})")
        im = error_panel(row[-1], a[f"{target}|{ks[-1]}|shexp"], a[f"{target}|truth"], f"k = {ks[-1]}: shexp - mesh AO",
                         limit=0.3)
        fig.colorbar(im, ax=row[-1], fraction=0.046)
    if "bunny" not in targets:
        fig.text(0.5, 0.02, "The bunny's row is missing: the mesh stanford-bunny.obj was not found in the shared "
                 "meshes folder.", ha="center", fontsize=11)
    fig.suptitle(f"Sphere-set proxies (inscribed, k-means) against the mesh: cosine AO, {s['proxy_rays']} rays "
                 f"per point for the truth, seed {s['seed']}{', quick' if s['quick'] else ''}", fontsize=12)


make = deprecated_make(__name__)
