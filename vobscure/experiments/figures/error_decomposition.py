"""Why an estimator is off: its error split into sampling, screen-space and model error.

One PNG, ``error_decomposition.png``, and its numbers, ``error_decomposition.csv``, from
:func:`vobscure.experiments.compare.compare` on the
Cornell box and the blob, for lines 5 and 9, points 12 and 33 and one area sample, with the
normal (``normal_clamp=True``: half-ball VO, which reads 1 on an open flat surface as AO does;
unclamped ball VO reads 0.5 there and its model term would be mostly that constant):

(a) the mean signed error (bias) of each step, stacked: sampling (estimate minus the converged
    screen-space VO, :func:`vobscure.vo_reference`), screen space (that minus the world-space VO
    of the Embree ground truth) and model (world-space VO minus ray-cast AO within the
    radius). Biases add up exactly to the total bias against AO (the black tick);
(b) the RMSE of each step beside the total RMSE against AO (RMSEs do not add: the steps'
    errors partly cancel).

Regenerate with ``vobscure figures error_decomposition --out docs/img``, which also writes the
table of ``docs/figures.md`` as ``error_decomposition.md``.
"""

from __future__ import annotations

import numpy as np

from . import deprecated_make
from ._common import compare_rows, per_scene as _per_scene

__all__ = ["measure", "plot", "markdown", "METHODS", "SCENES", "TERMS"]

ORDER = 80
FIGSIZE = (12.0, 8.8)

_TERMS4 = ("sampling", "screen", "model", "total")
_COLUMNS = ("scene", "method", "samples", "taps_per_pixel", "seconds",
            *[f"{t}_error_{m}" for t in _TERMS4 for m in ("bias", "rmse")])
METHODS = "line:5,line:9,point:12,point:33,area:1"
SCENES = ("cornell_box", "blob")
TERMS = (("sampling", "#1f77b4"), ("screen", "#ff7f0e"), ("model", "#2ca02c"))


def measure(profile):
    """Rows of :func:`vobscure.experiments.compare.compare` for :data:`SCENES`, each with a
    ``scene`` key: half-ball VO against the three references, no reference cache. Quick:
    40 x 40, 32 AO rays, 64 and 128 reference samples; full: 160 x 160, 256, 512 and 2048."""
    return compare_rows(SCENES, _COLUMNS, size=profile.pick((40, 40), (160, 160)), methods=METHODS,
                        references=("screen", "volumetric", "ao"), normal_clamp=True, repeats=1,
                        rays=profile.pick(32, 256), volume_samples=profile.pick(64, 512),
                        screen_samples=profile.pick(128, 2048), seed=profile.seed, cache=False)


def plot(rows, fig) -> None:
    """Per scene: (a) the bias of each step, stacked; (b) the RMSE of each step."""
    axes = fig.subplots(len(SCENES), 2, squeeze=False)
    for i, scene in enumerate(SCENES):
        sel, labels, x = _per_scene(rows, scene)
        ax = axes[i, 0]
        pos, neg = np.zeros(len(sel)), np.zeros(len(sel))
        for term, color in TERMS:
            v = np.array([r[f"{term}_error_bias"] for r in sel])
            base = np.where(v >= 0, pos, neg)
            ax.bar(x, v, bottom=base, color=color, label=term, width=0.6)
            pos += np.maximum(v, 0)
            neg += np.minimum(v, 0)
        total = np.array([r["total_error_bias"] for r in sel])
        ax.scatter(x, total, marker="_", s=600, color="k", zorder=3, label="total (vs AO)")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xticks(x, labels)
        ax.set_ylabel("mean signed error")
        ax.set_title(f"{scene}: bias by step (adds up to the total)")
        ax.legend(fontsize=8)
        ax = axes[i, 1]
        w = 0.2
        for k, (term, color) in enumerate(TERMS):
            ax.bar(x + (k - 1.5) * w, [r[f"{term}_error_rmse"] for r in sel], w, color=color, label=term)
        ax.bar(x + 1.5 * w, [r["total_error_rmse"] for r in sel], w, color="0.3", label="total (vs AO)")
        ax.set_xticks(x, labels)
        ax.set_ylabel("RMSE")
        ax.set_title(f"{scene}: RMSE by step")
        ax.legend(fontsize=8)
    fig.suptitle("Half-ball VO, error decomposition: sampling (estimate - screen-space VO),\n"
                 "screen space (screen-space VO - world-space VO), model (world-space VO - AO)")


def markdown(rows) -> str:
    """The rows as the markdown table of ``docs/figures.md`` (bias and RMSE of each step)."""
    head = "| scene | configuration | " + " | ".join(f"{t} bias | {t} RMSE" for t in _TERMS4) + " |"
    lines = [head, "|---|---|" + "---:|" * (2 * len(_TERMS4))]
    for r in rows:
        cells = " | ".join(f"{r[f'{t}_error_bias']:+.4f} | {r[f'{t}_error_rmse']:.4f}"
                           for t in _TERMS4)
        lines.append(f"| {r['scene']} | {r['method']} {r['samples']} | {cells} |")
    return "\n".join(lines)


make = deprecated_make(__name__)
