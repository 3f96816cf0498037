"""Loos & Sloan 2010, Fig. 7: line samples against point samples, quality and time.

One PNG, ``fig7_lines_vs_points.png``, and the numbers it plots, ``fig7_lines_vs_points.csv``.
Both scenes of :data:`vobscure.experiments.claims.SCENES` through their own cameras
(256 x 256; 48 x 48 quick), ball radius R = 0.1 x the scene's extent, seed 0. The
converged screen-space VO (:func:`vobscure.vo_reference`) and the Embree ground truth are
those of :func:`vobscure.experiments.claims.measurement` (shared with Fig. 5, Fig. 6 and
:mod:`~vobscure.experiments.figures.screenspace_claims` within one process).

(a) Cornell box, half-ball (``normal_clamp=True``): the pairs of the paper's claim, lines 5
    against points 12 and lines 9 against points 33, one frame each (randomized 4 x 4
    noise), beside the converged screen-space VO. Titles: median milliseconds per frame and
    RMSE against that reference.
(b) The same frames after the edge-aware blur of the paper's pipeline
    (:func:`vobscure.bilateral_blur`, defaults), beside the Embree ground truth.
(c)-(f) Error against time, one panel per scene and normal setting: RMSE against the
    converged screen-space VO (the sampling error) over the median wall time of one frame,
    for ``vo_line`` with 3-16 lines and ``vo_point`` with 6-48 points (their defaults:
    nearest fetch for lines, bilinear for points), one frame (solid) and blurred (dashed).
    The claim pairs are ringed. A line curve below and left of the point curve is the
    paper's "better quality in less time".

Times are NumPy on this machine's CPU (median of 3 runs after a warm-up, round-robin); the
machine-independent cost, depth taps per pixel (= samples, less the centre of an odd point
pattern, which ``vo_point`` does not tap), is in the CSV beside them.
:mod:`~vobscure.experiments.figures.screenspace_claims` draws the four Table 1
configurations against the ground truth and against taps; ``docs/results.md`` has the full
tables.

Regenerate with ``vobscure figures fig7_lines_vs_points --out docs/img`` (a few minutes, most of it
the two scenes' references; ``--quick`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 5.1, Table 1 and Fig. 7.
"""

from __future__ import annotations

from . import deprecated_make
from ._common import Rows, claims_measurements

__all__ = ["measure", "plot", "PAIRS"]

ORDER = 50
FIGSIZE = (17.0, 13.5)

#: The claim pairs of Sec. 5.1: (lines, points).
PAIRS = ((5, 12), (9, 33))

_COLUMNS = ("scene", "method", "samples", "normal_clamp", "taps_per_pixel", "ms", "rmse_ref",
            "rmse_ref_blurred", "bias_ref", "rmse_gt")
_COLORS = {"line": "#1f77b4", "point": "#d62728"}


def measure(profile, *, claims=None) -> Rows:
    """Time and error of lines and points at several sample counts, both scenes.

    Parameters
    ----------
    profile : Profile
        Quick: only the paper's counts (lines 5, 9; points 12, 33), one timed run after the
        warm-up; full: lines 3-16 and points 6-48 (6 counts each), 3 timed runs. Image size
        and seed as the profile's.
    claims : dict, optional
        The claims' measurement of ``profile`` (see :mod:`vobscure.experiments.figures`).

    Returns
    -------
    Rows
        One row per (scene, method, samples, normal_clamp). ``ms`` is machine-dependent; all
        other columns are deterministic by the seed. Arrays: the Cornell box's frames of the
        claim pairs (raw and blurred), its converged screen-space VO and ground truth.
    """
    from ...metrics import error

    claims = claims_measurements(profile) if claims is None else claims
    rows, frames = _sweep(claims, profile)
    m = claims["cornell_box"]
    ref, truth = m.reference[True], m.truth[True].value
    arrays = {"reference": ref, "truth": truth}
    for (method, n), (v, b) in frames.items():
        arrays[f"{method}|{n}|raw"], arrays[f"{method}|{n}|blurred"] = v, b
    meta = {"size": list(profile.size), "seed": profile.seed, "quick": profile.quick, "scenes": list(claims),
            "ref_samples": m.settings["ref_samples"], "rmse_reference_truth": error(ref, truth).rmse}
    return Rows(rows, columns=_COLUMNS, arrays=arrays, meta=meta)


def plot(rows, fig) -> None:
    """Panels (a) to (g) from :func:`measure`'s rows."""
    m = rows.meta
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.2], hspace=0.03)
    _image_rows(parts[0], parts[1], rows)
    _curves(parts[2], rows, m["scenes"])
    w, h = m["size"]
    fig.suptitle(f"Loos & Sloan 2010, Fig. 7 / Sec. 5.1: line samples against point samples, "
                 f"quality and time ({w} x {h}, R = 0.1 x extent, seed {m['seed']}, NumPy on the CPU"
                 f"{', quick' if m['quick'] else ''})", fontsize=13)


# ----------------------------------------------------------------------------- data
def _sweep(data, profile):
    """Time and error of every (scene, method, samples, normal_clamp); the frames of (a), (b)."""
    from ... import methods
    from ...metrics import error
    from ...screenspace import bilateral_blur
    from ..common import time_calls

    seed = profile.seed
    # 5 and 9 lines, 12 and 33 points are the paper's
    configs = ([methods.Config("line", n) for n in profile.pick((5, 9), (3, 5, 7, 9, 13, 16))] +
               [methods.Config("point", n) for n in profile.pick((12, 33), (6, 12, 16, 24, 33, 48))])
    runs = profile.pick(1, 3)      # timed runs after a warm-up; the median is plotted
    rows, frames = [], {}
    for scene, m in data.items():
        for nc in (False, True):
            def frame(c, gb=m.gb, r=m.radius, nc=nc):
                return lambda: c.run(gb, radius=r, normal_clamp=nc, seed=seed)

            timings, images = time_calls({c: frame(c) for c in configs}, runs)
            ref, truth = m.reference[nc], m.truth[nc].value
            for c in configs:
                method, n, v = c.method, c.samples, images[c]
                b = bilateral_blur(v, m.gb)
                e_ref = error(v, ref)
                rows.append({"scene": scene, "method": method, "samples": n, "normal_clamp": nc,
                             "taps_per_pixel": c.taps, "ms": 1000.0 * timings[c].median,
                             "rmse_ref": e_ref.rmse, "rmse_ref_blurred": error(b, ref).rmse,
                             "bias_ref": e_ref.bias, "rmse_gt": error(v, truth).rmse})
                if scene == "cornell_box" and nc and any(n in p for p in PAIRS):
                    frames[(method, n)] = (v, b)
    return rows, frames


# ----------------------------------------------------------------------------- drawing
def _image_rows(top, bottom, rows):
    from ._common import fmt, image_panel

    a = rows.arrays
    by = {(r["method"], r["samples"]): r for r in rows if r["scene"] == "cornell_box" and r["normal_clamp"]}
    ref = a["reference"]
    order = [c for pair in PAIRS for c in (("line", pair[0]), ("point", pair[1]))]
    names = {"line": "lines", "point": "points"}
    for subfig, k, letter in ((top, 0, "a"), (bottom, 1, "b")):
        axes = subfig.subplots(1, len(order) + 1)
        for ax, c in zip(axes, order):
            r = by[c]
            img = a[f"{c[0]}|{c[1]}|{('raw', 'blurred')[k]}"]
            rmse = r["rmse_ref"] if k == 0 else r["rmse_ref_blurred"]
            im = image_panel(ax, img, f"{names[c[0]]} {c[1]}: {r['ms']:.0f} ms/frame\n"
                                      f"RMSE vs converged {fmt(rmse, 4)}")
        if k == 0:
            image_panel(axes[-1], ref, f"converged screen-space VO\nvo_reference, "
                                       f"{rows.meta['ref_samples']} samples")
        else:
            image_panel(axes[-1], a["truth"], f"Embree ground truth\nRMSE of the converged "
                                              f"{fmt(rows.meta['rmse_reference_truth'], 4)}")
        subfig.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
        what = ("one frame, no blur" if k == 0 else
                "the same frames after the edge-aware blur (vo.bilateral_blur, defaults)")
        subfig.suptitle(f"({letter}) Cornell box, half-ball (normal_clamp=True): the claim pairs, {what}",
                        fontsize=11)


def _curves(subfig, rows, scenes):
    from matplotlib.lines import Line2D
    from ._common import SCENE_NAMES, log_log

    panels = [(s, nc) for s in scenes for nc in (False, True)]
    axes = subfig.subplots(1, len(panels))
    letters = "cdefghij"
    paired = {("line", p[0]) for p in PAIRS} | {("point", p[1]) for p in PAIRS}
    for ax, (scene, nc), letter in zip(axes, panels, letters):
        for method in ("line", "point"):
            rs = sorted((r for r in rows if r["scene"] == scene and r["normal_clamp"] == nc
                         and r["method"] == method), key=lambda r: r["samples"])
            ms = [r["ms"] for r in rs]
            color = _COLORS[method]
            ax.plot(ms, [r["rmse_ref"] for r in rs], "-o", color=color, ms=4, lw=1.6)
            ax.plot(ms, [r["rmse_ref_blurred"] for r in rs], "--", color=color, lw=1.2, alpha=0.8)
            for r in rs:
                if (method, r["samples"]) in paired:
                    ax.plot([r["ms"]], [r["rmse_ref"]], "o", ms=11, mfc="none", mec=color, mew=1.6)
                ax.annotate(str(r["samples"]), xy=(r["ms"], r["rmse_ref"]), xytext=(3, 3),
                            textcoords="offset points", fontsize=7.5, color=color)
        log_log(ax)
        ax.set_xlabel("median ms per frame (log)")
        ax.set_ylabel("RMSE vs converged screen-space VO (log)")
        ax.set_title(f"({letter}) {SCENE_NAMES.get(scene, scene)}, {'half-ball' if nc else 'ball'}",
                     fontsize=11)
    counts = {m: sorted({r["samples"] for r in rows if r["method"] == m}) for m in ("line", "point")}
    handles = [Line2D([], [], color=_COLORS["line"], marker="o", ms=4,
                      label=f"vo_line, {counts['line'][0]}-{counts['line'][-1]} lines"),
               Line2D([], [], color=_COLORS["point"], marker="o", ms=4,
                      label=f"vo_point, {counts['point'][0]}-{counts['point'][-1]} points"),
               Line2D([], [], color="0.3", ls="--", label="after the edge-aware blur"),
               Line2D([], [], ls="", marker="o", ms=10, mfc="none", mec="0.3", mew=1.6,
                      label="claim pairs: lines 5 / points 12, lines 9 / points 33"),
               Line2D([], [], ls="", marker="$n$", color="0.3",
                      label="n = samples (= depth taps per pixel,\nless an odd point pattern's centre)")]
    subfig.legend(handles=handles, loc="outside lower center", ncol=5, fontsize=9.5, frameon=False)


make = deprecated_make(__name__)
