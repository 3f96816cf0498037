"""The line-versus-point figure: Table 1's configurations as images and as error against time.

One PNG, ``screenspace_claims.png`` (its numbers in ``screenspace_claims.csv``), that goes with ``docs/results.md``:

(a) the Cornell box, ball VO (``normal_clamp=False``): lines 5, lines 9, points 12, points 33
    (one frame each, seed 0, no blur), the converged screen-space VO (:func:`vobscure.vo_reference`)
    and the Embree ground truth, each titled with its RMSE against the reference and the truth;
(b) the same with the normal (``normal_clamp=True``, the half-ball);
(c) error against time: RMSE against the converged screen-space VO (the sampling error) over
    the median seconds per frame, one point per configuration, scene and normal setting;
(d) the same RMSE over depth taps per pixel (the machine-independent cost);
(e) RMSE against the ground truth (sampling plus screen-space model error) over seconds.

The numbers come from :func:`vobscure.experiments.claims.measurement`, measured once per run of
the figures and shared with Figs. 5-7.

Regenerate with ``vobscure figures screenspace_claims --out docs/img`` (``--quick``: 48 x 48
in seconds).
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows, claims_measurements

__all__ = ["measure", "plot"]

ORDER = 10
FIGSIZE = (16.0, 13.2)

_COLORS = {"lines 5": "#1f77b4", "lines 9": "#17becf", "points 12": "#d62728", "points 33": "#ff7f0e",
           "points 12 nearest": "#9467bd", "points 33 nearest": "#8c564b", "area 1": "#2ca02c"}
_MARKERS = {"cornell_box": "o", "blob": "s"}
_IMAGE_CONFIGS = ("lines 5", "lines 9", "points 12", "points 33")


def measure(profile, *, claims=None) -> Rows:
    """The rows of :func:`vobscure.experiments.claims.line_vs_point` for both scenes and the
    Cornell box's images.

    Parameters
    ----------
    profile : Profile
        Image size ``profile.size`` (256 x 256; 48 x 48 and fewer reference samples quick), seed.
    claims : dict, optional
        The claims' measurement of ``profile`` (see :mod:`vobscure.experiments.figures`).

    Returns
    -------
    Rows
        One row per (scene, configuration, normal_clamp) with the columns of
        :func:`~vobscure.experiments.claims.line_vs_point`; arrays: each shown configuration's
        estimate, the converged screen-space VO and the ground truth (value and stderr) for
        both normal settings.
    """
    from .. import claims as C

    claims = claims_measurements(profile) if claims is None else claims
    rows = [dict(r) for s in C.SCENES for r in claims[s].rows]
    cornell = claims["cornell_box"]
    arrays = {}
    for nc in (False, True):
        for c in _IMAGE_CONFIGS:
            arrays[f"{c}|{nc}"] = cornell.images[(c, nc)]
        arrays[f"reference|{nc}"] = cornell.reference[nc]
        arrays[f"truth|{nc}"] = cornell.truth[nc].value
        arrays[f"truth_stderr|{nc}"] = cornell.truth[nc].stderr
    meta = {"size": list(profile.size), "seed": profile.seed, "quick": profile.quick,
            "truth_samples": int(cornell.truth[True].samples)}
    return Rows(rows, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """Panels (a) to (e) from :func:`measure`'s rows."""
    m = rows.meta
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.25], hspace=0.03)
    for k, nc in enumerate((False, True)):
        _image_row(parts[k], rows, nc, "ab"[k])
    _scatter_row(parts[2], rows)
    size = m["size"]
    fig.suptitle(f"Loos & Sloan 2010, Table 1 / Sec. 5.1 on the CPU: lines 5 and 9 against points 12 "
                 f"and 33 ({size[0]} x {size[1]}, radius 0.1 x scene extent, seed {m['seed']}"
                 f"{', quick' if m['quick'] else ''})", fontsize=13)


def _image_row(subfig, rows, normal_clamp, letter):
    from ._common import image_panel

    a = rows.arrays
    by = {r["config"]: r for r in rows if r["scene"] == "cornell_box" and r["normal_clamp"] == normal_clamp}
    panels = [(c, a[f"{c}|{normal_clamp}"],
               f"{c}: {by[c]['taps_per_pixel']} taps/px, {1000 * by[c]['seconds']:.0f} ms\n"
               f"RMSE ref {by[c]['rmse_ref']:.3f}, truth {by[c]['rmse_gt']:.3f}") for c in _IMAGE_CONFIGS]
    ref_samples = by[_IMAGE_CONFIGS[0]]["ref_samples"]
    panels.append(("reference", a[f"reference|{normal_clamp}"],
                   f"converged screen space\nvo_reference, {ref_samples} samples"))
    panels.append(("truth", a[f"truth|{normal_clamp}"],
                   f"Embree ground truth, {rows.meta['truth_samples']} pts\n"
                   f"mean stderr {np.nanmean(a[f'truth_stderr|{normal_clamp}']):.4f}"))
    axes = subfig.subplots(1, len(panels))
    for ax, (_, img, title) in zip(axes, panels):
        im = image_panel(ax, img, title)
    subfig.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
    what = ("half-ball VO (normal_clamp=True)" if normal_clamp
            else "ball VO (normal_clamp=False): the truth is brighter because the walls are only 0.1 thick")
    subfig.suptitle(f"({letter}) Cornell box, {what}; one frame each, randomized 4 x 4 noise, no blur",
                    fontsize=11)


def _scatter_row(subfig, rows):
    from matplotlib.lines import Line2D
    from ._common import SCENE_NAMES, log_log

    axes = subfig.subplots(1, 3)
    specs = [("ms", "rmse_ref", "(c) error against the converged screen-space VO, over time",
              "median milliseconds per frame (NumPy, CPU; log)", "RMSE against vo_reference (log)"),
             ("taps_per_pixel", "rmse_ref", "(d) the same error over depth taps per pixel",
              "depth-buffer taps per pixel (machine-independent cost; log)", "RMSE against vo_reference (log)"),
             ("ms", "rmse_gt", "(e) error against the Embree ground truth, over time",
              "median milliseconds per frame (NumPy, CPU; log)", "RMSE against ground truth (log)")]
    rows = [dict(r, ms=1000.0 * r["seconds"]) for r in rows]
    for ax, (xkey, ykey, title, xlabel, ylabel) in zip(axes, specs):
        for r in rows:
            color = _COLORS.get(r["config"], "0.4")
            marker = _MARKERS.get(r["scene"], "^")
            filled = not r["normal_clamp"]
            ax.scatter([r[xkey]], [r[ykey]], s=70 if r["primary"] else 40, marker=marker,
                       facecolors=color if filled else "white", edgecolors=color, linewidths=1.8,
                       alpha=1.0 if r["primary"] else 0.75, zorder=3)
        # join the two claims' partners: lines -> points, per scene and normal setting
        for scene in dict.fromkeys(r["scene"] for r in rows):
            for nc in (False, True):
                by = {r["config"]: r for r in rows if r["scene"] == scene and r["normal_clamp"] == nc}
                for a, b in (("lines 5", "points 12"), ("lines 9", "points 33")):
                    if a in by and b in by:
                        ax.plot([by[a][xkey], by[b][xkey]], [by[a][ykey], by[b][ykey]], color="0.75",
                                lw=0.8, ls="--" if nc else "-", zorder=1)
        log_log(ax)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=11)
    configs = list(dict.fromkeys(r["config"] for r in rows))
    handles = [Line2D([], [], ls="", marker="o", ms=8, color=_COLORS.get(c, "0.4"), label=c) for c in configs]
    handles += [Line2D([], [], ls="", marker=_MARKERS.get(s, "^"), ms=8, mfc="0.3", mec="0.3",
                       label=SCENE_NAMES.get(s, s))
                for s in dict.fromkeys(r["scene"] for r in rows)]
    handles += [Line2D([], [], ls="", marker="o", ms=8, mfc="0.3", mec="0.3", label="ball (filled)"),
                Line2D([], [], ls="", marker="o", ms=8, mfc="white", mec="0.3", mew=1.8,
                       label="half-ball (hollow)"),
                Line2D([], [], color="0.75", lw=1.0, label="claim pairs: lines 5-points 12, lines 9-points 33")]
    subfig.legend(handles=handles, loc="outside lower center", ncol=6, fontsize=9.5, frameon=False)


make = deprecated_make(__name__)
