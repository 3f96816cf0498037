"""What the figure modules share beyond :mod:`vobscure.experiments.common`: the image panels,
the figures' sizes, the writing of a figure with its CSV, and the ``python -m`` main of a
measured figure.

The writers, the timer, the default radius and the machine record are those of
:mod:`vobscure.experiments.common` (one copy for every experiment); this module holds what
only figures need. Not a figure itself (it is not in
:data:`vobscure.experiments.figures.FIGURES`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..common import save_figure, write_csv

__all__ = ["BACKGROUND", "FULL_SIZE", "CSV_DIGITS", "SCENE_NAMES", "size_for", "measurements",
           "write_figure",
           "image_panel", "error_panel", "corr", "fmt", "table_main"]

#: Colour of background pixels (NaN) in every image panel, as in the other figures.
BACKGROUND = "#e377c2"
#: Image size (width, height) of a figure of the paper's scenes, without ``quick``.
FULL_SIZE = (256, 256)
#: Significant digits of the floats in a figure's CSV.
CSV_DIGITS = 6
#: How a figure names a scene of :mod:`vobscure.scenes` in titles and tick labels.
SCENE_NAMES = {"cornell_box": "Cornell box", "blob": "blob"}


def size_for(quick: bool, size=None, *, full=FULL_SIZE) -> tuple:
    """The image size (width, height) of a figure: ``size`` when given, else ``full`` or, with
    ``quick``, :data:`vobscure.experiments.claims.QUICK_SIZE` (48 x 48: the size of the
    claims' quick measurements, which Figs. 5-7 share)."""
    if size is not None:
        return tuple(size)
    if quick:
        from ..claims import QUICK_SIZE

        return tuple(QUICK_SIZE)
    return tuple(full)


def measurements(size, seed: int, quick: bool) -> dict:
    """:func:`vobscure.experiments.claims.measurement` of every scene of
    :data:`~vobscure.experiments.claims.SCENES`, by scene name (cached per process)."""
    from .. import claims

    return {scene: claims.measurement(scene, size=size, seed=seed, quick=quick) for scene in claims.SCENES}


def write_figure(fig, out_dir, filename: str, rows=None, csv_filename: str | None = None,
                 columns=None) -> list[Path]:
    """Write ``fig`` as ``out_dir / filename`` (PNG) and, when ``rows`` are given, the rows as
    ``out_dir / csv_filename`` with ``columns`` (floats to :data:`CSV_DIGITS` significant
    digits, booleans 0 / 1, None empty); both atomically, ``out_dir`` created if missing.

    Returns
    -------
    list of Path
        ``[png]`` or ``[png, csv]``.
    """
    out_dir = Path(out_dir)
    paths = [save_figure(fig, out_dir / filename)]
    if rows is not None:
        paths.append(write_csv(out_dir / csv_filename, rows, columns, digits=CSV_DIGITS))
    return paths


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
