"""Helpers shared by the figure modules: atomic PNG and CSV output, image panels, timing.

Not a figure itself (it is not in :data:`vobscure.experiments.figures.FIGURES`).
"""

from __future__ import annotations

import csv
import io
import time
from pathlib import Path

import numpy as np

__all__ = ["BACKGROUND", "new_figure", "save_figure", "write_csv", "image_panel",
           "error_panel", "median_seconds", "corr", "fmt", "table_main"]

#: Colour of background pixels (NaN) in every image panel, as in the other figures.
BACKGROUND = "#e377c2"


def new_figure(width: float, height: float, dpi: int = 100):
    """A matplotlib ``Figure`` on the Agg canvas (never pyplot), constrained layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically (temporary file, then rename)."""
    from vobscure._io import atomic_write

    return atomic_write(Path(path), lambda fh: fig.savefig(fh, format="png", dpi="figure"))


def write_csv(path, rows, columns) -> Path:
    """Write ``rows`` (dicts) with the given ``columns`` as CSV, atomically.

    Floats are written with 6 significant digits, None as an empty cell, booleans as 0 / 1.
    """
    from vobscure._io import atomic_write

    def cell(value):
        if value is None:
            return ""
        if isinstance(value, (bool, np.bool_)):
            return str(int(value))
        if isinstance(value, (float, np.floating)):
            return f"{float(value):.6g}"
        return str(value)

    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([cell(row.get(c)) for c in columns])
    data = text.getvalue().encode("utf-8")
    return atomic_write(Path(path), lambda fh: fh.write(data))


def image_panel(ax, image, title=None, *, vmin=0.0, vmax=1.0, cmap="gray", fontsize=9.5):
    """Show an (H, W) visibility image, NaN (background) in :data:`BACKGROUND`; no ticks."""
    import matplotlib as mpl

    cm = mpl.colormaps[cmap].with_extremes(bad=BACKGROUND)
    im = ax.imshow(np.ma.masked_invalid(np.asarray(image, dtype=np.float64)), cmap=cm, vmin=vmin,
                   vmax=vmax, interpolation="nearest")
    if title:
        ax.set_title(title, fontsize=fontsize)
    ax.set_xticks([])
    ax.set_yticks([])
    return im


def error_panel(ax, estimate, truth, title=None, *, limit=0.5, fontsize=9.5):
    """Signed error ``estimate - truth`` in a diverging map (blue: too open, red: too dark)."""
    diff = np.asarray(estimate, dtype=np.float64) - np.asarray(truth, dtype=np.float64)
    return image_panel(ax, diff, title, vmin=-limit, vmax=limit, cmap="RdBu", fontsize=fontsize)


def median_seconds(functions: dict, runs: int) -> dict:
    """Median wall seconds of each zero-argument callable, round-robin after one warm-up each.

    Round-robin (all functions once, ``runs`` times) spreads a slow spell of a shared machine
    over every function alike; the warm-up call builds cached sample patterns.
    """
    for f in functions.values():
        f()
    times = {k: [] for k in functions}
    for _ in range(runs):
        for k, f in functions.items():
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return {k: float(np.median(v)) for k, v in times.items()}


def corr(a, b, mask=None) -> float:
    """Pearson correlation over pixels finite in both (and in ``mask``); NaN if undefined."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    use = np.isfinite(a) & np.isfinite(b)
    if mask is not None:
        use &= np.asarray(mask, dtype=bool)
    if use.sum() < 3 or np.std(a[use]) == 0 or np.std(b[use]) == 0:
        return float("nan")
    return float(np.corrcoef(a[use], b[use])[0, 1])


def fmt(x, digits: int = 3) -> str:
    """A float for a title or table cell: fixed ``digits``, "nan" when not finite."""
    return "nan" if x is None or not np.isfinite(x) else f"{x:.{digits}f}"


def table_main(module: str, measure, make, markdown, argv=None) -> int:
    """``python -m <module> [--quick] [--out DIR] [--seed N]``: measure once, draw the figure
    from those rows (``make(..., rows=rows)``) and print them as ``markdown(rows)``."""
    import argparse

    ap = argparse.ArgumentParser(prog=f"python -m {module}")
    ap.add_argument("--quick", action="store_true", help="small and fast")
    ap.add_argument("--out", default=".", help="directory of the PNG and CSV")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    rows = measure(args.quick, seed=args.seed)
    paths = make(args.out, quick=args.quick, seed=args.seed, rows=rows)
    print(markdown(rows))
    for path in paths:
        print(f"wrote {path}")
    return 0
