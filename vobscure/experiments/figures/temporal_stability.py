"""Temporal stability: do line samples flicker less than point samples in animation?

Loos & Sloan 2010 (Sec. 5.1) report that line sampling aliases much less than point sampling
when the camera moves. One PNG, ``temporal_stability.png``, and its numbers, ``temporal_stability.csv``: over a camera orbit (10 degrees,
``frames`` frames) of the Cornell box and the blob, the flicker of lines 5 and 9, points 12
and 33 and one area sample (:func:`vobscure.metrics.flicker`: the mean absolute
frame-to-frame change of the estimate minus that of the converged screen-space VO over the
same frames), beside each configuration's RMSE against that reference. Per-pixel
randomization uses the same screen-fixed noise texture every frame, as a renderer would.
The reference is Monte Carlo too: its own residual noise changes from frame to frame and is
subtracted with the true change, so an estimator smoother than that noise reads slightly
negative (with ``quick``, 256 reference samples, this dominates; the full figure uses 4096).

Regenerate with::

    python -m vobscure.experiments.figures.temporal_stability --out docs/img

which also prints the table of ``docs/figures.md`` (``vobscure figures temporal_stability``
draws the same files without the table).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "measure", "markdown", "main", "FILENAME", "CSV_FILENAME", "CSV_RANGES"]

#: Name of the PNG :func:`make` writes.
FILENAME = "temporal_stability.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "temporal_stability.csv"
#: Range of each numeric CSV column (the tests check every row against it). Flicker is a
#: difference of two mean absolute changes, so it may be slightly negative.
CSV_RANGES = {"samples": (1, 256), "frames": (2, 1000), "taps_per_pixel": (1, 256),
              "flicker": (-1.0, 1.0), "flicker_raw": (0.0, 1.0), "screen_rmse": (0.0, 1.0)}
_COLUMNS = ("scene", "method", "samples", "frames", "taps_per_pixel", "flicker", "flicker_raw",
            "screen_rmse")
METHODS = "line:5,line:9,point:12,point:33,area:1"
SCENES = ("cornell_box", "blob")
_COLORS = {"line": "#1f77b4", "point": "#d62728", "area": "#2ca02c"}


def measure(quick: bool = False, *, seed: int = 0):
    """Rows of :func:`vobscure.experiments.compare.compare` with an orbit, per scene."""
    from ..compare import compare

    size, frames = ((40, 40), 4) if quick else ((128, 128), 12)
    rows = []
    for scene in SCENES:
        res = compare(scene, size=size, methods=METHODS, references=("screen",), repeats=1,
                      screen_samples=256 if quick else 4096, seed=seed, orbit=frames, cache=False,
                      progress=False, out=None, plots=False, write=False)
        rows += [dict(row, scene=scene, frames=frames) for row in res.rows]
    return rows


def make(out_dir, quick: bool = False, *, seed: int = 0, rows=None) -> list[Path]:
    """Draw ``temporal_stability.png``.

    Parameters
    ----------
    out_dir : str or path-like
    quick : bool
        40 x 40 images, 4 frames (seconds), for CI; 128 x 128 and 12 frames otherwise.
    seed : int
    rows : list of dict, optional
        The rows of :func:`measure`, when already computed (drawn as given).

    Returns
    -------
    list of Path

    Examples
    --------
    >>> FILENAME
    'temporal_stability.png'
    """
    from ..common import new_figure
    from ._common import write_figure

    rows = measure(quick, seed=seed) if rows is None else rows
    fig = new_figure(12, 3.9 * len(SCENES))
    axes = fig.subplots(len(SCENES), 2, squeeze=False)
    for i, scene in enumerate(SCENES):
        sel = [r for r in rows if r["scene"] == scene]
        labels = [f"{r['method']} {r['samples']}" for r in sel]
        x = np.arange(len(sel))
        colors = [_COLORS[r["method"]] for r in sel]
        axes[i, 0].bar(x, [r["flicker"] for r in sel], color=colors)
        axes[i, 0].axhline(0, color="k", lw=0.6)
        axes[i, 0].set_xticks(x, labels)
        axes[i, 0].set_ylabel("flicker\n(mean |change| - reference's)")
        axes[i, 0].set_title(f"{scene}: flicker over {sel[0]['frames']} frames")
        axes[i, 1].bar(x, [r["screen_rmse"] for r in sel], color=colors)
        axes[i, 1].set_xticks(x, labels)
        axes[i, 1].set_ylabel("RMSE vs screen-space VO")
        axes[i, 1].set_title(f"{scene}: error of one frame")
    fig.suptitle("Temporal stability over a 10-degree camera orbit (Loos & Sloan 2010, Sec. 5.1)")
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, _COLUMNS)


def markdown(rows) -> str:
    """The rows as the markdown table of ``docs/figures.md``."""
    lines = ["| scene | configuration | taps/px | flicker | raw frame change | RMSE (one frame) |",
             "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['method']} {r['samples']} | {r['taps_per_pixel']} | "
                     f"{r['flicker']:.4f} | {r['flicker_raw']:.4f} | {r['screen_rmse']:.4f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    """``python -m vobscure.experiments.figures.temporal_stability [--quick] [--out DIR]``."""
    from ._common import table_main

    return table_main("vobscure.experiments.figures.temporal_stability", measure, make, markdown, argv)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
