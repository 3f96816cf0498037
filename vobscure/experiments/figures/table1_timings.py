"""Loos & Sloan 2010, Table 1: time per pass, this library beside the paper, as ratios.

One PNG, ``table1_timings.png`` (the table rendered with matplotlib, and a bar chart of its
ratios), and ``table1_timings.csv`` (one row per cell). The paper timed each pass on an NVIDIA
QuadroFX 4800 at 1024 x 1024; here every pass is NumPy on this machine's CPU, so absolute
milliseconds are not comparable. What is compared is the **ratio** of each configuration's
time to the time of ``points 12`` in the same row (the paper's Crytek baseline): a ratio below
1 is a pass cheaper than 12 point samples.

Rows of the table:

- the paper's, :data:`PAPER_TABLE1` (Dragon, Dragon with double radii, Cornell, Soldiers,
  Knight and the average over the four single-radius scenes; the bilateral blur's median
  2.23 ms, :data:`PAPER_BLUR_MS`, in the average row);
- this library's, at :data:`PAPER_RESOLUTION` (1024 x 1024; 48 x 48 in the quick profile): the
  Cornell box and the blob through their own cameras, radius 0.1 x the scene's extent
  (:data:`vobscure.experiments.common.RADIUS_FRACTION`), and the Cornell box with dual
  radii (each estimator run at the two radii of
  :data:`vobscure.experiments.figures.fig8_dual_radii.RADII` and combined with
  ``vo.combine_radii(mode="product")``; its ratios, like the paper's Dragon*, are to the
  single-radius ``points 12`` of the same scene).

Columns: the G-buffer pass (the paper's rasterized "Geometry"; here
:func:`vobscure.render_gbuffer`, Embree primary rays), ``vo_line`` with 5 and 9 lines,
``vo_point`` with 12 and 33 points (estimator defaults: lines fetch ``nearest``, points
``bilinear``, ``normal_clamp=False``), the paper's HSAO column (Horizon Split AO, which the
paper cites as Bavoil et al. 2008; vobscure's rows: n/a) and beside it the horizon-based
column(s) timed in the same run as everything else: ``hbao 8x4`` (:func:`vobscure.hbao`,
Bavoil, Sainz & Dimitrov 2008, the registry's 8 directions of 4 nearest taps, 32 taps) and
``gtao 3x3`` (:func:`vobscure.gtao`, Jimenez et al. 2016, today's horizon method: XeGTAO
"high", 3 slices of 3 bilinear taps a side, 18 taps); then the edge-aware blur
(:func:`vobscure.bilateral_blur`, defaults), and three configurations the paper's table does
not have: points with a one-texel ``nearest`` fetch (GPU bilinear fetches are free, NumPy's
are not) and one area sample (``vo_area``, Fig. 1 of the paper). The dual-radius row times
the VO columns only (the paper's Dragon* has no HSAO entry). Every time is the median of 3
runs after a warm-up (1 in the quick profile), round-robin over the configurations of a scene, so
every ratio of a row divides two times of the same run.

Regenerate with ``vobscure figures table1_timings --out docs/img`` (39 s on 2 shared cores;
``--quick`` in seconds, where the times are dominated by per-call overhead and say little).

References
----------
Loos & Sloan, "Volumetric Obscurance", I3D 2010, Sec. 5.1 and Table 1.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import Rows

__all__ = ["measure", "plot", "PAPER_TABLE1", "PAPER_BLUR_MS",
           "PAPER_RESOLUTION", "COLUMNS", "HORIZON_COLUMNS", "BASELINE", "paper_ratios"]

ORDER = 70
FIGSIZE = (21.0, 11.5)

#: Loos & Sloan 2010, Table 1: milliseconds per pass at 1024 x 1024 on an NVIDIA QuadroFX
#: 4800 ("Geometry" is the G-buffer pass; "Dragon (double radius)" used two radii and is not
#: in the average). Transcribed from the paper; the HSAO column and the "Geometry" header
#: are from the second extraction quoted in /work/shared/papers/README.md (the first lost
#: them). None: not in the paper.
PAPER_TABLE1 = {
    "Dragon": {"G-buffer": 3.39, "lines 5": 0.71, "lines 9": 1.01, "points 12": 1.18,
               "points 33": 3.11, "HSAO": 51.52},
    "Dragon (double radius)": {"G-buffer": 3.39, "lines 5": 1.06, "lines 9": 1.85,
                               "points 12": 2.44, "points 33": 7.36, "HSAO": None},
    "Cornell": {"G-buffer": 0.45, "lines 5": 0.71, "lines 9": 1.03, "points 12": 1.31,
                "points 33": 3.55, "HSAO": 60.55},
    "Soldiers": {"G-buffer": 2.37, "lines 5": 0.54, "lines 9": 0.77, "points 12": 1.14,
                 "points 33": 2.32, "HSAO": 17.04},
    "Knight": {"G-buffer": 0.27, "lines 5": 0.59, "lines 9": 0.82, "points 12": 0.97,
               "points 33": 2.52, "HSAO": 29.13},
    "Average": {"G-buffer": None, "lines 5": 0.64, "lines 9": 0.91, "points 12": 1.15,
                "points 33": 2.87, "HSAO": 39.56},
}
#: Loos & Sloan 2010, Table 1 caption: "The bilateral blur used for each scene required a
#: median time of 2.23 ms."
PAPER_BLUR_MS = 2.23
#: The paper's resolution (width, height).
PAPER_RESOLUTION = (1024, 1024)
#: Table columns: the paper's, then the blur, then this library's supplementary ones.
COLUMNS = ("G-buffer", "lines 5", "lines 9", "points 12", "points 33", "HSAO", "hbao 8x4", "gtao 3x3",
           "blur", "points 12 nearest", "points 33 nearest", "area 1")
#: The horizon-based columns (this library's rows only), beside the paper's HSAO.
HORIZON_COLUMNS = ("hbao 8x4", "gtao 3x3")
#: The configuration every ratio is relative to.
BASELINE = "points 12"

_SCENES = ("cornell_box", "blob")
_DUAL_SCENE = "cornell_box"
#: Column -> configuration of :mod:`vobscure.methods` (method, samples, fetch).
_ESTIMATORS = {"lines 5": ("line", 5), "lines 9": ("line", 9), "points 12": ("point", 12),
               "points 33": ("point", 33), "points 12 nearest": ("point", 12, "nearest"),
               "points 33 nearest": ("point", 33, "nearest"), "area 1": ("area", 1),
               "hbao 8x4": ("hbao", 8), "gtao 3x3": ("gtao", 3)}
_DUAL = ("lines 5", "lines 9", "points 12", "points 33")
_CSV_COLUMNS = ("source", "row", "column", "width", "height", "ms", "baseline_ms", "ratio")


def paper_ratios() -> dict:
    """The paper's Table 1 as ratios to ``points 12`` of the same row (Dragon for Dragon*).

    Returns
    -------
    dict
        ``{row: {column: ratio or None}}``, with the blur in the "Average" row.

    Examples
    --------
    >>> r = paper_ratios()
    >>> round(r["Average"]["lines 5"], 3), round(r["Average"]["points 33"], 3)
    (0.557, 2.496)
    """
    out = {}
    for row, cells in _paper_cells().items():
        base = _paper_baseline(row)
        out[row] = {c: (None if v is None else v / base) for c, v in cells.items()}
    return out


def measure(profile, *, normal_clamp: bool = False) -> Rows:
    """Time this library's passes; the paper's cells and ours, one row per cell.

    Parameters
    ----------
    profile : Profile
        Quick: ``profile.size`` (48 x 48: the ratios then mostly measure call overhead) and
        one timed run after the warm-up; full: the paper's 1024 x 1024 and 3 runs (the
        median is reported). Seed of the estimators' noise textures: ``profile.seed``.
    normal_clamp : bool, optional
        Passed to every estimator (the paper does not say; default the estimators' default).

    Returns
    -------
    Rows
        One row per filled cell: ``source`` ("paper" or "vobscure"), ``row``, ``column``,
        ``width``, ``height``, ``ms``, ``baseline_ms`` (the row's ``points 12``) and ``ratio`` =
        ms / baseline_ms.
    """
    size = profile.pick(profile.size, PAPER_RESOLUTION)
    runs = profile.pick(1, 3)
    ours = _measure(size, profile.seed, bool(normal_clamp), runs)
    return Rows(_csv_rows(ours, size), columns=_CSV_COLUMNS,
                meta={"size": list(size), "runs": runs, "quick": profile.quick})


def plot(rows, fig) -> None:
    """(a) the table, (b) its ratios as bars, from :func:`measure`'s rows."""
    ours = {}
    for r in rows:
        if r["source"] == "vobscure":
            ours.setdefault(r["row"], {})[r["column"]] = r["ms"] / 1000.0
    size, runs = rows.meta["size"], rows.meta["runs"]
    parts = fig.subfigures(2, 1, height_ratios=[1.15, 1.0], hspace=0.03)
    _table(parts[0], ours, size, runs)
    _bars(parts[1], ours)
    w, h = size
    fig.suptitle(f"Loos & Sloan 2010, Table 1: time per pass as a ratio to points 12 of the same row "
                 f"(paper: QuadroFX 4800, 1024 x 1024; vobscure: NumPy on this CPU, {w} x {h}"
                 f"{', quick' if rows.meta['quick'] else ''})", fontsize=13)


# ----------------------------------------------------------------------------- data
def _paper_cells() -> dict:
    cells = {row: dict(values) for row, values in PAPER_TABLE1.items()}
    cells["Average"]["blur"] = PAPER_BLUR_MS
    return cells


def _paper_baseline(row) -> float:
    return PAPER_TABLE1["Dragon" if row.startswith("Dragon") else row][BASELINE]


def _measure(size, seed, normal_clamp, runs) -> dict:
    """``{row: {column: seconds}}`` for this library's rows."""
    from ... import methods, scenes
    from ...render import render_gbuffer
    from ...screenspace import bilateral_blur, combine_radii, vo_line
    from ..common import default_radius, time_calls
    from .fig8_dual_radii import RADII

    configs = {label: methods.Config(*spec) for label, spec in _ESTIMATORS.items()}

    def estimator(gb, label, radius):
        return lambda: configs[label].run(gb, radius=radius, normal_clamp=normal_clamp, seed=seed)

    out = {}
    for name in _SCENES:
        scene = scenes.get(name)
        cam = scene.camera(size)
        gb = render_gbuffer(scene, cam)
        radius = default_radius(scene)
        visibility = vo_line(gb, radius=radius, samples=9, normal_clamp=normal_clamp, seed=seed)
        jobs = {"G-buffer": lambda scene=scene, cam=cam: render_gbuffer(scene, cam),
                "blur": lambda gb=gb, v=visibility: bilateral_blur(v, gb)}
        jobs.update({label: estimator(gb, label, radius) for label in _ESTIMATORS})
        if name == _DUAL_SCENE:
            radii = [f * scene.extent for f in RADII]
            for label in _DUAL:
                small, large = (estimator(gb, label, r) for r in radii)
                jobs[("dual", label)] = (lambda s=small, g=large:
                                         combine_radii(s(), g(), mode="product"))
        timings, _ = time_calls(jobs, runs)
        seconds = {k: t.median for k, t in timings.items()}
        out[name] = {k: v for k, v in seconds.items() if not isinstance(k, tuple)}
        if name == _DUAL_SCENE:
            out[f"{name} (dual radii)"] = {k[1]: v for k, v in seconds.items() if isinstance(k, tuple)}
    return out


def _our_baseline(ours, row) -> float:
    return ours[row.replace(" (dual radii)", "")][BASELINE]


def _csv_rows(ours, size) -> list[dict]:
    rows = []
    for row, cells in _paper_cells().items():
        base = _paper_baseline(row)
        for column, ms in cells.items():
            if ms is not None:
                rows.append({"source": "paper", "row": row, "column": column,
                             "width": PAPER_RESOLUTION[0], "height": PAPER_RESOLUTION[1], "ms": ms,
                             "baseline_ms": base, "ratio": ms / base})
    for row, cells in ours.items():
        base = _our_baseline(ours, row)
        for column in COLUMNS:
            if column in cells:
                rows.append({"source": "vobscure", "row": row, "column": column, "width": size[0],
                             "height": size[1], "ms": 1000.0 * cells[column],
                             "baseline_ms": 1000.0 * base, "ratio": cells[column] / base})
    return rows


# ----------------------------------------------------------------------------- drawing
def _cell(ms, ratio) -> str:
    if ms is None:
        return "-"
    digits = 2 if ms < 10 else (1 if ms < 100 else 0)
    return f"{ms:.{digits}f} ms\n({ratio:.2f})"


def _table(subfig, ours, size, runs):
    ax = subfig.subplots()
    ax.axis("off")
    text, labels, colours = [], [], []
    for row, cells in _paper_cells().items():
        base = _paper_baseline(row)
        text.append([_cell(cells.get(c), None if cells.get(c) is None else cells[c] / base)
                     for c in COLUMNS])
        labels.append(f"paper: {row}")
        colours.append("#fdf1e1")
    for row, cells in ours.items():
        base = _our_baseline(ours, row)
        line = []
        for c in COLUMNS:
            if c == "HSAO":
                line.append("n/a\n(see hbao)")
            elif c in cells:
                line.append(_cell(1000.0 * cells[c], cells[c] / base))
            else:
                line.append("-")
        text.append(line)
        labels.append(f"vobscure: {row}")
        colours.append("#e6f0fa")
    # the cells fill the axes right of the row labels (which the table draws left of its bbox)
    table = ax.table(cellText=text, rowLabels=labels, colLabels=list(COLUMNS), cellLoc="center",
                     rowLoc="right", bbox=[0.15, 0.0, 0.85, 1.0])
    table.auto_set_font_size(False)
    table.set_fontsize(9)
    for (r, c), cell in table.get_celld().items():
        if r == 0:
            cell.set_facecolor("#d9d9d9")
            cell.set_text_props(weight="bold")
        elif r >= 1:
            cell.set_facecolor(colours[r - 1])
            if c >= 0 and COLUMNS[c] == BASELINE:
                cell.set_text_props(weight="bold")
    w, h = size
    subfig.suptitle(f"(a) milliseconds per pass and, in brackets, the ratio to points 12 of the same row "
                    f"(dual-radius rows: to the single-radius points 12)\nvobscure: {w} x {h}, radius "
                    f"0.1 x extent, median of {runs} runs; the paper's blur ({PAPER_BLUR_MS} ms) is a "
                    f"median over its scenes", fontsize=10.5)


def _bars(subfig, ours):
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    ax = subfig.subplots()
    shown = ("G-buffer", "lines 5", "lines 9", "points 12", "points 33", "HSAO", "hbao 8x4", "gtao 3x3",
             "blur", "points 12 nearest", "points 33 nearest", "area 1")
    paper = paper_ratios()
    series = [("paper: Average", paper["Average"], "#e6550d"),
              ("paper: Cornell", paper["Cornell"], "#fdae6b"),
              ("paper: Dragon (double radius)", paper["Dragon (double radius)"], "#fdd0a2")]
    blues = ("#08519c", "#6baed6", "#c6dbef")
    for (row, cells), colour in zip(ours.items(), blues):
        base = _our_baseline(ours, row)
        series.append((f"vobscure: {row}", {c: v / base for c, v in cells.items()}, colour))
    x = np.arange(len(shown), dtype=float)
    width = 0.8 / len(series)
    for k, (label, ratios, colour) in enumerate(series):
        xs = x + (k - (len(series) - 1) / 2) * width
        ys = [ratios.get(c) for c in shown]
        ax.bar([a for a, b in zip(xs, ys) if b is not None], [b for b in ys if b is not None], width,
               color=colour, edgecolor="k", lw=0.5, label=label, zorder=2)
    ax.axhline(1.0, color="k", lw=1.0, ls="--", zorder=3)
    ax.text(-0.45, 1.0, "points 12 = 1", ha="left", va="bottom", fontsize=9)
    ax.set_yscale("log")
    ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(FormatStrFormatter(""))
    ax.set_xticks(x)
    ax.set_xticklabels(shown)
    ax.set_ylabel("time / time of points 12 (log)")
    ax.grid(True, axis="y", which="both", color="0.9", lw=0.6, zorder=0)
    ax.legend(fontsize=9, ncol=3, loc="upper left", framealpha=0.9)
    subfig.suptitle("(b) the same ratios (log); HSAO is the paper's only (Horizon Split AO on its GPU), "
                    "hbao 8x4 and gtao 3x3 this library's horizon-based passes", fontsize=10.5)


make = deprecated_make(__name__)
