"""Why an estimator is off: its error split into sampling, screen-space and model error.

One PNG, ``error_decomposition.png``, and its numbers, ``error_decomposition.csv``, from :func:`vobscure.experiments.compare.compare` on the
Cornell box and the blob, for lines 5 and 9, points 12 and 33 and one area sample, with the
normal (``normal_clamp=True``: half-ball VO, which reads 1 on an open flat surface as AO does;
unclamped ball VO reads 0.5 there and its model term would be mostly that constant):

(a) the mean signed error (bias) of each step, stacked: sampling (estimate minus the converged
    screen-space VO, :func:`vobscure.vo_reference`), screen space (that minus the world-space VO
    of the Embree ground truth) and model (world-space VO minus ray-cast AO within the
    radius). Biases add up exactly to the total bias against AO (the black tick);
(b) the RMSE of each step beside the total RMSE against AO (RMSEs do not add: the steps'
    errors partly cancel).

Regenerate with::

    python -m vobscure.experiments.figures.error_decomposition --out docs/img

which also prints the table of ``docs/figures.md``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["make", "measure", "markdown", "main", "FILENAME", "CSV_FILENAME", "CSV_RANGES"]

#: Name of the PNG :func:`make` writes.
FILENAME = "error_decomposition.png"
#: Name of the CSV of the plotted numbers.
CSV_FILENAME = "error_decomposition.csv"
_TERMS4 = ("sampling", "screen", "model", "total")
#: Range of each numeric CSV column (the tests check every row against it).
CSV_RANGES = {"samples": (1, 256), "taps_per_pixel": (1, 256), "seconds": (0.0, 1e4),
              **{f"{t}_error_bias": (-1.0, 1.0) for t in _TERMS4},
              **{f"{t}_error_rmse": (0.0, 1.0) for t in _TERMS4}}
_COLUMNS = ("scene", "method", "samples", "taps_per_pixel", "seconds",
            *[f"{t}_error_{m}" for t in _TERMS4 for m in ("bias", "rmse")])
METHODS = "line:5,line:9,point:12,point:33,area:1"
SCENES = ("cornell_box", "blob")
TERMS = (("sampling", "#1f77b4"), ("screen", "#ff7f0e"), ("model", "#2ca02c"))


def measure(quick: bool = False, *, seed: int = 0, cache=False):
    """Rows of :func:`vobscure.experiments.compare.compare` for :data:`SCENES` (list of dicts,
    each with a ``scene`` key)."""
    from ..compare import compare

    size = (40, 40) if quick else (160, 160)
    rows = []
    for scene in SCENES:
        res = compare(scene, size=size, methods=METHODS, references=("screen", "volumetric", "ao"),
                      normal_clamp=True,
                      repeats=1, rays=32 if quick else 256, volume_samples=64 if quick else 512,
                      screen_samples=128 if quick else 2048, seed=seed, cache=cache, progress=False,
                      out=None, plots=False, write=False)
        rows += [dict(row, scene=scene) for row in res.rows]
    return rows


def make(out_dir, quick: bool = False, *, seed: int = 0, cache=False, rows=None) -> list[Path]:
    """Draw ``error_decomposition.png``.

    Parameters
    ----------
    out_dir : str or path-like
    quick : bool
        40 x 40 images and few reference samples (seconds), for CI; 160 x 160 otherwise.
    seed : int
    rows : list of dict, optional
        The rows of :func:`measure`, when already computed (drawn as given).
    cache : bool or path
        Reference cache, as in :func:`vobscure.experiments.compare.compare`.

    Returns
    -------
    list of Path

    Examples
    --------
    >>> FILENAME
    'error_decomposition.png'
    """
    from ..common import new_figure
    from ._common import write_figure

    rows = measure(quick, seed=seed, cache=cache) if rows is None else rows
    fig = new_figure(12, 4.2 * len(SCENES) + 0.4)
    axes = fig.subplots(len(SCENES), 2, squeeze=False)
    for i, scene in enumerate(SCENES):
        sel = [r for r in rows if r["scene"] == scene]
        labels = [f"{r['method']} {r['samples']}" for r in sel]
        x = np.arange(len(sel))
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
    return write_figure(fig, out_dir, FILENAME, rows, CSV_FILENAME, _COLUMNS)


def markdown(rows) -> str:
    """The rows as the markdown table of ``docs/figures.md`` (bias and RMSE of each step)."""
    head = "| scene | configuration | " + " | ".join(f"{t} bias | {t} RMSE" for t in _TERMS4) + " |"
    lines = [head, "|---|---|" + "---:|" * (2 * len(_TERMS4))]
    for r in rows:
        cells = " | ".join(f"{r[f'{t}_error_bias']:+.4f} | {r[f'{t}_error_rmse']:.4f}"
                           for t in _TERMS4)
        lines.append(f"| {r['scene']} | {r['method']} {r['samples']} | {cells} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    """``python -m vobscure.experiments.figures.error_decomposition [--quick] [--out DIR]``."""
    from ._common import table_main

    return table_main("vobscure.experiments.figures.error_decomposition", measure, make, markdown, argv)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
