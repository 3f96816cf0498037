"""Loos & Sloan 2010, Fig. 7: line samples against point samples, quality and time.

One PNG, ``fig7_lines_vs_points.png``, and the numbers it plots, ``fig7_lines_vs_points.csv``.
Both scenes of :data:`vobscure.experiments.claims.SCENES` through their own cameras
(256 x 256; 48 x 48 with ``quick``), ball radius R = 0.1 x the scene's extent, seed 0. The
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

Regenerate with::

    python -c "from vobscure.experiments.figures import fig7_lines_vs_points as f; f.make('docs/img')"

(a few minutes, most of it the two scenes' references; ``quick=True`` in seconds).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 5.1, Table 1 and Fig. 7.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["make", "FILENAME", "CSV_FILENAME", "CSV_RANGES", "LINE_SAMPLES", "POINT_SAMPLES",
           "PAIRS", "TIMING_RUNS"]

#: Name of the PNG :func:`make` writes.
FILENAME = "fig7_lines_vs_points.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "fig7_lines_vs_points.csv"
#: Sample counts of the line curves (full, quick). 5 and 9 are the paper's.
LINE_SAMPLES = {False: (3, 5, 7, 9, 13, 16), True: (5, 9)}
#: Sample counts of the point curves (full, quick). 12 and 33 are the paper's.
POINT_SAMPLES = {False: (6, 12, 16, 24, 33, 48), True: (12, 33)}
#: The claim pairs of Sec. 5.1: (lines, points).
PAIRS = ((5, 12), (9, 33))
#: Timed runs per configuration after a warm-up, (full, quick); the median is plotted.
TIMING_RUNS = {False: 3, True: 1}
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"samples": (1, 256), "normal_clamp": (0, 1), "taps_per_pixel": (1, 256),
              "ms": (0.0, 1e6), "rmse_ref": (0.0, 1.0), "rmse_ref_blurred": (0.0, 1.0),
              "rmse_gt": (0.0, 1.0), "bias_ref": (-1.0, 1.0)}

_COLUMNS = ("scene", "method", "samples", "normal_clamp", "taps_per_pixel", "ms", "rmse_ref",
            "rmse_ref_blurred", "bias_ref", "rmse_gt")
_COLORS = {"line": "#1f77b4", "point": "#d62728"}


def make(out_dir, quick: bool = False, *, size=None, seed: int = 0) -> list[Path]:
    """Draw ``fig7_lines_vs_points.png`` and write ``fig7_lines_vs_points.csv``.

    Parameters
    ----------
    out_dir : str or path-like
        Directory to write into; created if missing.
    quick : bool, optional
        48 x 48 pixels, fewer reference samples, only the paper's sample counts (seconds).
    size : (int, int), optional
        Image size; default 256 x 256 (48 x 48 with ``quick``).
    seed : int, optional
        Seed of the estimators' noise and of the references.

    Returns
    -------
    list of Path
        ``[out_dir / FILENAME, out_dir / CSV_FILENAME]``, each written atomically; the CSV has
        one row per (scene, method, samples, normal_clamp). ``ms`` is machine-dependent; all
        other columns are deterministic by ``seed``.

    Examples
    --------
    >>> from vobscure.experiments.figures import fig7_lines_vs_points
    >>> fig7_lines_vs_points.FILENAME
    'fig7_lines_vs_points.png'
    """
    from ..common import new_figure
    from ._common import measurements, size_for, write_figure

    quick = bool(quick)
    size = size_for(quick, size)
    data = measurements(size, seed, quick)
    rows, frames = _sweep(data, quick, seed)

    fig = new_figure(17.0, 13.5)
    parts = fig.subfigures(3, 1, height_ratios=[1.0, 1.0, 1.2], hspace=0.03)
    _image_rows(parts[0], parts[1], data["cornell_box"], rows, frames)
    _curves(parts[2], rows, list(data))
    w, h = size
    fig.suptitle(f"Loos & Sloan 2010, Fig. 7 / Sec. 5.1: line samples against point samples, "
                 f"quality and time ({w} x {h}, R = 0.1 x extent, seed {seed}, NumPy on the CPU"
                 f"{', quick' if quick else ''})", fontsize=13)
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, _COLUMNS)


# ----------------------------------------------------------------------------- data
def _sweep(data, quick, seed):
    """Time and error of every (scene, method, samples, normal_clamp); the frames of (a), (b)."""
    from ... import methods
    from ...metrics import error
    from ...screenspace import bilateral_blur
    from ..common import time_calls

    configs = ([methods.Config("line", n) for n in LINE_SAMPLES[quick]] +
               [methods.Config("point", n) for n in POINT_SAMPLES[quick]])
    rows, frames = [], {}
    for scene, m in data.items():
        for nc in (False, True):
            def frame(c, gb=m.gb, r=m.radius, nc=nc):
                return lambda: c.run(gb, radius=r, normal_clamp=nc, seed=seed)

            timings, images = time_calls({c: frame(c) for c in configs}, TIMING_RUNS[quick])
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
def _image_rows(top, bottom, m, rows, frames):
    from ...metrics import error
    from ._common import fmt, image_panel

    by = {(r["method"], r["samples"]): r for r in rows if r["scene"] == "cornell_box" and r["normal_clamp"]}
    ref, truth = m.reference[True], m.truth[True]
    order = [c for pair in PAIRS for c in (("line", pair[0]), ("point", pair[1]))]
    names = {"line": "lines", "point": "points"}
    for subfig, k, letter in ((top, 0, "a"), (bottom, 1, "b")):
        axes = subfig.subplots(1, len(order) + 1)
        for ax, c in zip(axes, order):
            r = by[c]
            img = frames[c][k]
            rmse = r["rmse_ref"] if k == 0 else r["rmse_ref_blurred"]
            im = image_panel(ax, img, f"{names[c[0]]} {c[1]}: {r['ms']:.0f} ms/frame\n"
                                      f"RMSE vs converged {fmt(rmse, 4)}")
        if k == 0:
            image_panel(axes[-1], ref, f"converged screen-space VO\nvo_reference, "
                                       f"{m.settings['ref_samples']} samples")
        else:
            image_panel(axes[-1], truth.value, f"Embree ground truth\nRMSE of the converged "
                                               f"{fmt(error(ref, truth.value).rmse, 4)}")
        subfig.colorbar(im, ax=axes, shrink=0.85, label="visibility (1 = open)")
        what = ("one frame, no blur" if k == 0 else
                "the same frames after the edge-aware blur (vo.bilateral_blur, defaults)")
        subfig.suptitle(f"({letter}) Cornell box, half-ball (normal_clamp=True): the claim pairs, {what}",
                        fontsize=11)


def _curves(subfig, rows, scenes):
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    from ._common import SCENE_NAMES

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
        ax.set_xscale("log")
        ax.set_yscale("log")
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FormatStrFormatter("%g"))
            axis.set_minor_formatter(FormatStrFormatter(""))
        ax.grid(True, which="both", color="0.9", lw=0.6)
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
