"""Temporal stability: do line samples flicker less than point samples in animation?

Loos & Sloan 2010 (Sec. 5.1) report that line sampling aliases much less than point sampling
when the camera moves. One PNG, ``temporal_stability.png``: over a camera orbit (10 degrees,
``frames`` frames) of the Cornell box and the blob, the flicker of lines 5 and 9, points 12
and 33 and one area sample (:func:`vobscure.metrics.flicker`: the mean absolute
frame-to-frame change of the estimate minus that of the converged screen-space VO over the
same frames), beside each configuration's RMSE against that reference. Per-pixel
randomization uses the same screen-fixed noise texture every frame, as a renderer would.
The reference is Monte Carlo too: its own residual noise changes from frame to frame and is
subtracted with the true change, so an estimator smoother than that noise reads slightly
negative (with ``quick``, 256 reference samples, this dominates; the full figure uses 4096).

Regenerate with::

    vobscure figures temporal_stability --out docs/img
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "FILENAME"]

#: Name of the one file :func:`make` writes.
FILENAME = "temporal_stability.png"
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


def make(out_dir, quick: bool = False, *, seed: int = 0) -> list[Path]:
    """Draw ``temporal_stability.png``.

    Parameters
    ----------
    out_dir : str or path-like
    quick : bool
        40 x 40 images, 4 frames (seconds), for CI; 128 x 128 and 12 frames otherwise.
    seed : int

    Returns
    -------
    list of Path

    Examples
    --------
    >>> FILENAME
    'temporal_stability.png'
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..._io import atomic_write

    rows = measure(quick, seed=seed)
    fig = Figure(figsize=(12, 4.0 * len(SCENES)), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(SCENES), 2, squeeze=False)
    for i, scene in enumerate(SCENES):
        sel = [r for r in rows if r["scene"] == scene]
        labels = [f"{r['method']} {r['samples']}" for r in sel]
        x = np.arange(len(sel))
        colors = [_COLORS[r["method"]] for r in sel]
        axes[i, 0].bar(x, [r["flicker"] for r in sel], color=colors)
        axes[i, 0].axhline(0, color="k", lw=0.6)
        axes[i, 0].set_xticks(x, labels)
        axes[i, 0].set_ylabel("flicker (mean |frame change|, minus the reference's)")
        axes[i, 0].set_title(f"{scene}: flicker over {sel[0]['frames']} frames")
        axes[i, 1].bar(x, [r["screen_rmse"] for r in sel], color=colors)
        axes[i, 1].set_xticks(x, labels)
        axes[i, 1].set_ylabel("RMSE vs converged screen-space VO")
        axes[i, 1].set_title(f"{scene}: per-frame error (last frame)")
    fig.suptitle("Temporal stability over a 10-degree camera orbit (Loos & Sloan 2010, Sec. 5.1)")
    path = Path(out_dir) / FILENAME
    atomic_write(path, lambda fh: fig.savefig(fh, format="png"))
    return [path]
