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

Regenerate with ``python -c "from vobscure.experiments.figures import proxy_bunny as f;
f.make('docs/img')"`` (a minute or two; ``quick=True`` in seconds).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "COLUMNS"]

FILENAME = "proxy_bunny.png"
CSV_FILENAME = "proxy_bunny.csv"
COLUMNS = ("target", "k", "method", "order", "points", "rmse", "bias", "corr", "ref_stderr", "spheres_volume_ratio")
CSV_RANGES = {"k": (1, 4096), "rmse": (0.0, 1.0), "bias": (-1.0, 1.0), "corr": (-1.0, 1.0),
              "ref_stderr": (0.0, 0.5), "spheres_volume_ratio": (0.0, 100.0)}

_LABELS = {"bunny": "ground under the bunny", "cornell_boxes": "Cornell box floor around the boxes"}


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``proxy_bunny.png`` and write ``proxy_bunny.csv``.

    Parameters
    ----------
    out_dir : str or path-like
    quick : bool, optional
        Small grids, few rays, k = 8 and 32 (seconds), for CI.
    seed : int, optional
    rows : tuple, optional
        ``(rows, images)`` of :func:`~vobscure.experiments.spheres.proxy_rows` with
        ``images=True``.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``.

    Examples
    --------
    >>> from vobscure.experiments.figures import proxy_bunny
    >>> proxy_bunny.FILENAME
    'proxy_bunny.png'
    """
    from .. import spheres as X
    from ..common import new_figure
    from ._common import error_panel, image_panel, write_figure

    quick = bool(quick)
    table, images = X.proxy_rows(quick, seed=seed, images=True) if rows is None else rows
    s = X.setting(quick)
    targets = list(images)
    ks = list(s["proxy_ks"])
    # one row per target; without the bunny (its mesh lives outside the repository) only the
    # Cornell box row is drawn, with a line saying why, in a figure no smaller than two rows
    fig = new_figure(4.0 * (len(ks) + 2), 4.4 * max(len(targets), 2) + 0.8)
    axes = fig.subplots(len(targets), len(ks) + 2, squeeze=False)
    for row, target in zip(axes, targets):
        pics = images[target]
        image_panel(row[0], pics["truth"], f"{_LABELS.get(target, target)}:\nEmbree AO of the mesh")
        for ax, k in zip(row[1:], ks):
            r = next(x for x in table if x["target"] == target and x["k"] == k and x["method"] == "shexp")
            u = next(x for x in table if x["target"] == target and x["k"] == k and x["method"] == "union")
            image_panel(ax, pics[k]["shexp"], f"k = {k} spheres, shexp order {s['proxy_order']}\n"
                        f"RMSE {r['rmse']:.3f} (union of spheres {u['rmse']:.3f})")
        im = error_panel(row[-1], pics[ks[-1]]["shexp"], pics["truth"], f"k = {ks[-1]}: shexp - mesh AO",
                         limit=0.3)
        fig.colorbar(im, ax=row[-1], fraction=0.046)
    if "bunny" not in targets:
        fig.text(0.5, 0.02, "The bunny's row is missing: the mesh stanford-bunny.obj was not found in the shared "
                 "meshes folder.", ha="center", fontsize=11)
    fig.suptitle(f"Sphere-set proxies (inscribed, k-means) against the mesh: cosine AO, {s['proxy_rays']} rays "
                 f"per point for the truth, seed {seed}{', quick' if quick else ''}", fontsize=12)
    return write_figure(fig, out_dir, FILENAME, table, CSV_FILENAME, COLUMNS)
