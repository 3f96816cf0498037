"""Temporal stability: do line samples flicker less than point samples in animation?

Loos & Sloan 2010 (Sec. 5.1) report that line sampling aliases much less than point sampling
when the camera moves. One PNG, ``temporal_stability.png``, and its numbers,
``temporal_stability.csv``: over a camera orbit (10 degrees,
``frames`` frames) of the Cornell box and the blob, the flicker of lines 5 and 9, points 12
and 33 and one area sample (:func:`vobscure.metrics.flicker`: the mean absolute
frame-to-frame change of the estimate minus that of the converged screen-space VO over the
same frames), beside each configuration's RMSE against that reference. Per-pixel
randomization uses the same screen-fixed noise texture every frame, as a renderer would.
The reference is Monte Carlo too: its own residual noise changes from frame to frame and is
subtracted with the true change, so an estimator smoother than that noise reads slightly
negative (in the quick profile, 256 reference samples, this dominates; the full figure uses 4096).

Regenerate with ``vobscure figures temporal_stability --out docs/img``, which also writes the
table of ``docs/figures.md`` as ``temporal_stability.md``.
"""

from __future__ import annotations

from . import deprecated_make
from ._common import compare_rows, per_scene as _per_scene

__all__ = ["measure", "plot", "markdown", "METHODS", "SCENES"]

ORDER = 90
FIGSIZE = (12.0, 7.8)

_COLUMNS = ("scene", "method", "samples", "frames", "taps_per_pixel", "flicker", "flicker_raw",
            "screen_rmse")
METHODS = "line:5,line:9,point:12,point:33,area:1"
SCENES = ("cornell_box", "blob")
_COLORS = {"line": "#1f77b4", "point": "#d62728", "area": "#2ca02c"}


def measure(profile):
    """Rows of :func:`vobscure.experiments.compare.compare` with an orbit, per scene. Quick:
    40 x 40, 4 frames, 256 reference samples; full: 128 x 128, 12 frames, 4096."""
    frames = profile.pick(4, 12)
    return compare_rows(SCENES, _COLUMNS, size=profile.pick((40, 40), (128, 128)), methods=METHODS,
                        references=("screen",), repeats=1, screen_samples=profile.pick(256, 4096),
                        seed=profile.seed, orbit=frames, cache=False, extra={"frames": frames})


def plot(rows, fig) -> None:
    """Per scene: the flicker and the error of one frame of each configuration."""
    axes = fig.subplots(len(SCENES), 2, squeeze=False)
    for i, scene in enumerate(SCENES):
        sel, labels, x = _per_scene(rows, scene)
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


def markdown(rows) -> str:
    """The rows as the markdown table of ``docs/figures.md``."""
    lines = ["| scene | configuration | taps/px | flicker | raw frame change | RMSE (one frame) |",
             "|---|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['method']} {r['samples']} | {r['taps_per_pixel']} | "
                     f"{r['flicker']:.4f} | {r['flicker_raw']:.4f} | {r['screen_rmse']:.4f} |")
    return "\n".join(lines)


make = deprecated_make(__name__)
