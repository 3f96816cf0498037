"""What the figure modules share: the :class:`Profile` they are measured at, the
:class:`Rows` they measure, the files those are written to and read back from, the
measurements that several figures draw (the claims', the trees'), and the image panels.

The writers, the timer, the default radius and the machine record are those of
:mod:`vobscure.experiments.common` (one copy for every experiment); this module holds what
only figures need. Its name starts with an underscore, so the figure discovery of
:mod:`vobscure.experiments.figures` skips it.
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..common import write_csv

__all__ = ["BACKGROUND", "FULL_SIZE", "QUICK_SIZE", "CSV_DIGITS", "SCENE_NAMES", "Profile", "Rows",
           "write_rows", "read_rows", "claims_measurements", "tree_measurements", "compare_rows", "per_scene",
           "image_panel", "error_panel", "pixel_rmse", "log_log", "corr", "fmt",
           "stacked", "fitted_points_title"]

#: Colour of background pixels (NaN) in every image panel, as in the other figures.
BACKGROUND = "#e377c2"
#: Image size (width, height) of a figure of the paper's scenes in the full profile.
FULL_SIZE = (256, 256)
#: The same in the quick profile: the size of the claims' quick measurements, which
#: Figs. 5-7 share (:data:`vobscure.experiments.claims.QUICK_SIZE`).
QUICK_SIZE = (48, 48)
#: Significant digits of the floats in a figure's CSV.
CSV_DIGITS = 6
#: How a figure names a scene of :mod:`vobscure.scenes` in titles and tick labels.
SCENE_NAMES = {"cornell_box": "Cornell box", "blob": "blob"}


@dataclass(frozen=True)
class Profile:
    """How much a figure measures: the quick profile (what CI runs, seconds per figure) or the
    full one (the figures of the docs), the seed, and the image size of the paper's scenes.

    A figure reads the fields it needs; a number of its own that differs between the two
    profiles is written once as ``profile.pick(quick_value, full_value)``.

    Parameters
    ----------
    quick : bool, optional
        Small images, few samples and seeds.
    seed : int, optional
        Seed of every figure's noise and references (a figure may derive ``seed + k``).
    size : (int, int), optional
        Image (width, height) of the paper's scenes; default :data:`QUICK_SIZE` (48 x 48) or
        :data:`FULL_SIZE` (256 x 256). Figures of other scenes keep their own sizes.

    Examples
    --------
    >>> p = Profile(quick=True)
    >>> p.name, p.size, p.pick(64, 1024)
    ('quick', (48, 48), 64)
    >>> Profile().pick(64, 1024), Profile(size=(32, 24)).size
    (1024, (32, 24))
    >>> Profile(seed=-1)
    Traceback (most recent call last):
    ...
    ValueError: seed must be an integer >= 0, got -1
    """

    quick: bool = False
    seed: int = 0
    size: tuple | None = None

    def __post_init__(self):
        if not isinstance(self.quick, (bool, np.bool_)):
            raise ValueError(f"quick must be True or False, got {self.quick!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be an integer >= 0, got {self.seed!r}")
        size = self.pick(QUICK_SIZE, FULL_SIZE) if self.size is None else tuple(self.size)
        if len(size) != 2 or not all(isinstance(s, (int, np.integer)) and s > 0 for s in size):
            raise ValueError(f"size must be (width, height), two positive integers, got {self.size!r}")
        object.__setattr__(self, "quick", bool(self.quick))
        object.__setattr__(self, "seed", int(self.seed))
        object.__setattr__(self, "size", tuple(int(s) for s in size))

    @property
    def name(self) -> str:
        """``"quick"`` or ``"full"``."""
        return "quick" if self.quick else "full"

    def pick(self, quick, full):
        """``quick`` in the quick profile, else ``full``."""
        return quick if self.quick else full


class Rows(list):
    """What a figure's ``measure`` returns: its rows (dicts, written as the figure's CSV) and,
    beside them, what the CSV cannot hold.

    Parameters
    ----------
    rows : iterable of dict
        The CSV's rows; a key a row lacks is an empty cell.
    columns : sequence of str, optional
        The CSV's columns, in order; default every key, in order of first appearance. Keys
        outside ``columns`` are not written, so ``plot`` must not read them.
    arrays : dict of str to ndarray, optional
        Images and curves (numeric arrays), written beside the CSV as ``<name>.npz``.
    meta : dict, optional
        Scalars, strings and lists for titles (JSON), written into the same ``.npz``.
    digits : int or None, optional
        Significant digits of the CSV's floats; default :data:`CSV_DIGITS`; None: exact.

    Examples
    --------
    >>> r = Rows([{"n": 1, "rmse": 0.5}], arrays={"image": np.zeros((2, 2))}, meta={"seed": 0})
    >>> len(r), r[0]["rmse"], r.columns, r.arrays["image"].shape, r.meta
    (1, 0.5, ('n', 'rmse'), (2, 2), {'seed': 0})
    """

    def __init__(self, rows=(), *, columns=None, arrays=None, meta=None, digits: int | None = CSV_DIGITS):
        super().__init__(dict(r) for r in rows)
        if columns is None:
            columns = []
            for row in self:
                columns.extend(k for k in row if k not in columns)
        self.columns = tuple(columns)
        self.arrays = {k: np.asarray(v) for k, v in (arrays or {}).items()}
        self.meta = dict(meta or {})
        self.digits = digits


def _parse_cell(text: str):
    """A CSV cell read back: empty -> None, an integer -> int, a number -> float, else the text
    (booleans were written as 0 / 1 and come back as those ints)."""
    if text == "":
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def write_rows(rows: Rows, csv_path, npz_path=None) -> list[Path]:
    """Write ``rows`` as CSV (floats to ``rows.digits`` significant digits, booleans 0 / 1,
    None empty) and, when they carry arrays or meta, those as ``npz_path``; atomically.

    Returns
    -------
    list of Path
        ``[csv]`` or ``[csv, npz]``.
    """
    from ..._io import atomic_write

    paths = [write_csv(csv_path, rows, rows.columns, digits=rows.digits)]
    if npz_path is not None and (rows.arrays or rows.meta):
        payload = dict(rows.arrays, __meta__=np.array(json.dumps(rows.meta, sort_keys=True)))
        paths.append(atomic_write(Path(npz_path), lambda fh: np.savez_compressed(fh, **payload)))
    return paths


def read_rows(csv_path, npz_path=None) -> Rows:
    """The :class:`Rows` that :func:`write_rows` wrote: cells typed back (see
    :func:`_parse_cell`), floats as rounded in the file, arrays and meta from ``npz_path``
    when it exists.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     rows = Rows([{"a": 1, "b": True, "c": None, "d": 1 / 3, "e": "lines 9"}],
    ...                 arrays={"x": np.arange(3.0)}, meta={"seed": 7})
    ...     _ = write_rows(rows, f"{tmp}/f.csv", f"{tmp}/f.npz")
    ...     back = read_rows(f"{tmp}/f.csv", f"{tmp}/f.npz")
    >>> back[0]
    {'a': 1, 'b': 1, 'c': None, 'd': 0.333333, 'e': 'lines 9'}
    >>> back.columns, back.arrays["x"].tolist(), back.meta
    (('a', 'b', 'c', 'd', 'e'), [0.0, 1.0, 2.0], {'seed': 7})
    """
    with open(csv_path, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        columns = next(reader)
        rows = [{c: _parse_cell(v) for c, v in zip(columns, line)} for line in reader]
    arrays, meta = {}, {}
    if npz_path is not None and Path(npz_path).is_file():
        with np.load(npz_path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files if k != "__meta__"}
            meta = json.loads(str(data["__meta__"]))
    return Rows(rows, columns=columns, arrays=arrays, meta=meta)


def claims_measurements(profile: Profile) -> dict:
    """:func:`vobscure.experiments.claims.measurement` of every scene of
    :data:`~vobscure.experiments.claims.SCENES` at ``profile``, by scene name, measured now.

    Figures that draw it take it as the keyword ``claims`` of their ``measure``; the driver
    (:func:`vobscure.experiments.figures.make`) measures it once per run and passes it to each.
    """
    from .. import claims

    return {scene: claims.measurement(scene, size=profile.size, seed=profile.seed, quick=profile.quick)
            for scene in claims.SCENES}


def tree_measurements(profile: Profile, given=None):
    """The :class:`vobscure.experiments.trees.Measurements` of ``profile`` (its quick and
    seed): ``given`` when there is one, else a new one, which measures when first asked.

    Figures that draw the tree measurements take it as the keyword ``trees`` of their
    ``measure``; the driver (:func:`vobscure.experiments.figures.make`) makes one per run and
    passes it to each, so that they share the points, ground truths and timings.
    """
    from .. import trees

    return trees.Measurements(profile.quick, seed=profile.seed) if given is None else given


def compare_rows(scenes, columns, *, extra=None, **options) -> Rows:
    """The rows of :func:`vobscure.experiments.compare.compare` (``options``; no progress, no
    files) for each scene, each row with its ``scene`` and the ``extra`` keys, as :class:`Rows`
    with ``columns``."""
    from ..compare import compare

    rows = []
    for scene in scenes:
        res = compare(scene, progress=False, out=None, plots=False, write=False, **options)
        rows += [dict(row, scene=scene, **(extra or {})) for row in res.rows]
    return Rows(rows, columns=columns)


def per_scene(rows, scene):
    """The rows of ``scene``, their labels ("line 5") and bar positions 0, 1, ..."""
    sel = [r for r in rows if r["scene"] == scene]
    return sel, [f"{r['method']} {r['samples']}" for r in sel], np.arange(len(sel))


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


def stacked(fig, rows, panels, height_ratios, *, hspace: float = 0.03) -> None:
    """Draw ``panel(subfigure, rows)`` for each of ``panels`` in its own band of ``fig``, top to
    bottom, the bands' heights in ``height_ratios``."""
    parts = fig.subfigures(len(panels), 1, height_ratios=height_ratios, hspace=hspace)
    for part, panel in zip(parts, panels):
        panel(part, rows)


def fitted_points_title(meta, per: str) -> str:
    """The run of a tree figure fitted at points, for its title: points per ``per`` (half
    fitted, half scored), the ground truth's rays, the seed, and whether it is quick."""
    return (f"{meta['points']} points per {per}, half fitted, half scored; ground truth {meta['truth_rays']} rays, "
            f"seed {meta['seed']}{', quick' if meta['quick'] else ''}")


def pixel_rmse(model, truth) -> float:
    """RMSE over the pixels finite in both images; NaN if none."""
    model, truth = np.asarray(model, dtype=np.float64), np.asarray(truth, dtype=np.float64)
    ok = np.isfinite(truth) & np.isfinite(model)
    return float(np.sqrt(np.mean((model[ok] - truth[ok]) ** 2))) if ok.any() else float("nan")


def log_log(ax) -> None:
    """Both axes of ``ax`` logarithmic, ticks at 1, 2, 5 x 10^k labelled plainly, a light grid."""
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(FormatStrFormatter(""))
    ax.grid(True, which="both", color="0.9", lw=0.6)


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
