"""Loos & Sloan 2010, Fig. 6: the surface normal off and on, for lines and points.

One PNG, ``fig6_normals.png``, and the numbers it plots, ``fig6_normals.csv``. Both scenes of
:data:`vobscure.experiments.claims.SCENES` (the Cornell box and the blob) through their own
cameras (256 x 256; 48 x 48 quick), ball radius R = 0.1 x the scene's extent,
seed 0. Estimates, ground truths and ray-cast AO are those of
:func:`vobscure.experiments.claims.measurement`, so the raw numbers agree with the tables of
``docs/results.md`` and a process that also draws Fig. 5 or Fig. 7 computes them once.

(a), (b) One row per scene: ``vo_line`` (9 lines) and ``vo_point`` (12 points) without the
    normal (``normal_clamp=False``: the ball) and with it (``True``: the half-ball; points
    below the tangent plane reflected above it, lines cut at the plane), after the
    edge-aware blur of the paper's pipeline (:func:`vobscure.bilateral_blur`, defaults),
    beside ray-cast ambient occlusion within R (cosine-weighted; the normal-aware target
    that every image is compared with) and the Embree ground truth of both quantities.
    Titles: the Pearson correlation with the AO image and the RMSE against the estimate's
    own ground truth, blurred.
(c) Correlation with ray-cast AO for lines 5, lines 9, points 12 and points 33 on both
    scenes, ball and half-ball: bars one frame (no blur), dots after the blur, and the
    ground truths' own correlation with AO (the quantity, without any sampling error) as
    short horizontal marks.
(d) RMSE of the same estimates against their own ground truth (ball against ball VO,
    half-ball against half-ball VO; log axis).

"Finer-scale detail" (Sec. 4.4) is a visual claim; (c) and (d) are its measurable proxies.

Regenerate with ``vobscure figures fig6_normals --out docs/img`` (a few minutes, most of it the two
scenes' ground truths; ``--quick`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 4.4 and Fig. 6.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, claims_measurements

__all__ = ["measure", "plot", "IMAGE_CONFIGS", "BAR_CONFIGS"]

ORDER = 40
FIGSIZE = (18.0, 13.0)

#: Configurations (labels of :data:`vobscure.experiments.claims.CONFIGS`) of the image rows.
IMAGE_CONFIGS = ("lines 9", "points 12")
#: Configurations of the bar charts.
BAR_CONFIGS = ("lines 5", "lines 9", "points 12", "points 33")

_COLUMNS = ("scene", "config", "samples", "normal_clamp", "corr_ao", "corr_ao_blurred", "gt_corr_ao",
            "rmse_gt", "rmse_gt_blurred", "bias_gt", "rmse_ref", "std_estimate", "std_gt")
_COLORS = {False: "#9ecae1", True: "#08519c"}


def measure(profile, *, claims=None) -> Rows:
    """The normal off and on for lines and points on both scenes of the claims.

    Parameters
    ----------
    profile : Profile
        Image size and seed; quick: fewer reference samples.
    claims : dict, optional
        The claims' measurement of ``profile`` (see :mod:`vobscure.experiments.figures`).

    Returns
    -------
    Rows
        One row per (scene, configuration, normal_clamp); arrays: per scene the blurred
        estimates of :data:`IMAGE_CONFIGS`, the AO and both ground truths.
    """
    claims = claims_measurements(profile) if claims is None else claims
    rows, blurred = _rows(claims)
    arrays, meta = {}, {"size": list(profile.size), "seed": profile.seed, "quick": profile.quick,
                        "scenes": list(claims), "radius": {}, "ao_rays": {}}
    for scene, m in claims.items():
        for config in IMAGE_CONFIGS:
            for nc in (False, True):
                arrays[f"{scene}|{config}|{nc}"] = blurred[(scene, config, nc)]
        arrays[f"{scene}|ao"] = m.ao.value
        for nc in (False, True):
            arrays[f"{scene}|truth|{nc}"] = m.truth[nc].value
        meta["radius"][scene] = m.radius
        meta["ao_rays"][scene] = int(m.ao.samples)
    return Rows(rows, columns=_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """Panels (a) to (e) from :func:`measure`'s rows."""
    m = rows.meta
    scenes = m["scenes"]
    parts = fig.subfigures(len(scenes) + 1, 1, height_ratios=[1.0] * len(scenes) + [1.2], hspace=0.03)
    for k, scene in enumerate(scenes):
        _image_row(parts[k], scene, rows, "abcdefgh"[k])
    _bars(parts[-1], rows, letters="abcdefgh"[len(scenes):])
    w, h = m["size"]
    fig.suptitle(f"Loos & Sloan 2010, Fig. 6 / Sec. 4.4: the normal off (ball) and on (half-ball), "
                 f"lines and points ({w} x {h}, R = 0.1 x extent, seed {m['seed']}"
                 f"{', quick' if m['quick'] else ''})", fontsize=13)


# ----------------------------------------------------------------------------- data
def _rows(data):
    from ...metrics import error
    from ...screenspace import bilateral_blur
    from ._common import corr

    rows, blurred = [], {}
    for scene, m in data.items():
        by = {(r["config"], r["normal_clamp"]): r for r in m.rows}
        for config in BAR_CONFIGS:
            for nc in (False, True):
                v = m.images[(config, nc)]
                b = bilateral_blur(v, m.gb)
                blurred[(scene, config, nc)] = b
                truth = m.truth[nc].value
                r = by[(config, nc)]
                rows.append({"scene": scene, "config": config, "samples": r["samples"],
                             "normal_clamp": nc, "corr_ao": corr(v, m.ao.value),
                             "corr_ao_blurred": corr(b, m.ao.value), "gt_corr_ao": corr(truth, m.ao.value),
                             "rmse_gt": r["rmse_gt"], "rmse_gt_blurred": error(b, truth).rmse,
                             "bias_gt": r["bias_gt"], "rmse_ref": r["rmse_ref"],
                             "std_estimate": float(np.nanstd(v)), "std_gt": float(np.nanstd(truth))})
    return rows, blurred


# ----------------------------------------------------------------------------- drawing
def _image_row(subfig, scene, rows, letter):
    from ._common import SCENE_NAMES, corr, fmt, image_panel

    a = rows.arrays
    by = {(r["config"], r["normal_clamp"]): r for r in rows if r["scene"] == scene}
    panels = []
    for config in IMAGE_CONFIGS:
        for nc in (False, True):
            r = by[(config, nc)]
            panels.append((a[f"{scene}|{config}|{nc}"],
                           f"{config}, {'normal on (half-ball)' if nc else 'normal off (ball)'}\n"
                           f"corr AO {fmt(r['corr_ao_blurred'])}, RMSE gt {fmt(r['rmse_gt_blurred'])}"))
    ao = a[f"{scene}|ao"]
    panels.append((ao, f"ray-cast AO within R\n{rows.meta['ao_rays'][scene]} rays, cosine"))
    for nc in (False, True):
        t = a[f"{scene}|truth|{nc}"]
        panels.append((t, f"ground truth, {'half-ball' if nc else 'ball'}\n"
                          f"corr AO {fmt(corr(t, ao))}"))
    axes = subfig.subplots(1, len(panels))
    for ax, (img, title) in zip(axes, panels):
        im = image_panel(ax, img, title, fontsize=9)
    subfig.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
    contrast = ", ".join(f"{'half-ball' if nc else 'ball'} {np.nanstd(a[f'{scene}|truth|{nc}']):.3f}"
                         for nc in (False, True))
    subfig.suptitle(f"({letter}) {SCENE_NAMES.get(scene, scene)}: one frame each after the edge-aware blur; "
                    f"R = {rows.meta['radius'][scene]:.3g}; all shown on 0-1 (standard deviation of the truth over "
                    f"pixels: {contrast})", fontsize=11)


def _bars(subfig, rows, letters):
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from ._common import SCENE_NAMES

    axes = subfig.subplots(1, 2)
    groups = list(dict.fromkeys((r["scene"], r["config"]) for r in rows))
    by = {(r["scene"], r["config"], r["normal_clamp"]): r for r in rows}
    x = np.arange(len(groups), dtype=float)
    width = 0.38
    specs = (("corr_ao", "corr_ao_blurred", f"({letters[0]}) correlation with ray-cast AO within R "
              "(higher: follows AO's detail)", "Pearson correlation with AO"),
             ("rmse_gt", "rmse_gt_blurred", f"({letters[1]}) RMSE against the estimate's own ground truth",
              "RMSE (log)"))
    for ax, (raw, blur, title, ylabel) in zip(axes, specs):
        for k, nc in enumerate((False, True)):
            xs = x + (k - 0.5) * width
            ax.bar(xs, [by[g + (nc,)][raw] for g in groups], width, color=_COLORS[nc], edgecolor="k",
                   lw=0.5, zorder=2)
            ax.plot(xs, [by[g + (nc,)][blur] for g in groups], "o", color="k", ms=4, zorder=3)
            if raw == "corr_ao":
                ax.plot(xs, [by[g + (nc,)]["gt_corr_ao"] for g in groups], "_", color="#d62728",
                        ms=16, mew=2.5, zorder=4)
        ax.set_xticks(x)
        ax.set_xticklabels([f"{c}\n{SCENE_NAMES.get(s, s)}" for s, c in groups], fontsize=9)
        for boundary in range(1, len(groups)):
            if groups[boundary][0] != groups[boundary - 1][0]:
                ax.axvline(boundary - 0.5, color="0.5", lw=1.0)
        if raw == "rmse_gt":
            ax.set_yscale("log")
        else:
            ax.set_ylim(min(0.0, min(min(r["corr_ao"], r["corr_ao_blurred"], r["gt_corr_ao"])
                                     for r in rows) - 0.05), 1.0)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=11)
        ax.grid(True, axis="y", which="both", color="0.9", lw=0.6, zorder=0)
    handles = [Patch(fc=_COLORS[False], ec="k", label="normal off (ball), one frame"),
               Patch(fc=_COLORS[True], ec="k", label="normal on (half-ball), one frame"),
               Line2D([], [], ls="", marker="o", color="k", ms=5, label="after the edge-aware blur"),
               Line2D([], [], ls="", marker="_", color="#d62728", ms=14, mew=2.5,
                      label="the ground truth's own correlation with AO")]
    subfig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=9.5, frameon=False)


make = deprecated_make(__name__)
