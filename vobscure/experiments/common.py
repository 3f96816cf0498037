"""What every experiment shares: the default radius, the machine record, the timer, and the
CSV, Markdown, JSON and PNG writers (all atomic: a file is the old good one or the new one).

:mod:`~vobscure.experiments.sweeps`, :mod:`~vobscure.experiments.compare`,
:mod:`~vobscure.experiments.claims` and the figure modules use these, so that a change of
format or of timing method happens once.

Examples
--------
>>> timings, values = time_calls({"sum": lambda: sum(range(100))}, repeats=2)
>>> values["sum"], len(timings["sum"].runs)
(4950, 2)
>>> print(markdown_table([{"method": "line", "rmse": 0.012345}], ["method", "rmse"]))
| method | rmse |
|---|---|
| line | 0.01235 |
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import platform
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._io import atomic_write

__all__ = ["RADIUS_FRACTION", "default_radius", "machine", "Timing", "time_calls", "cell", "columns_of",
           "csv_text", "write_csv", "markdown_table", "write_text", "write_json", "new_figure",
           "save_figure", "progress_bar"]

#: Default ball radius (and AO distance) as a fraction of the scene's extent, the diagonal of
#: its bounding box: the radius of every experiment and command that is given none.
RADIUS_FRACTION = 0.1


def default_radius(scene) -> float:
    """:data:`RADIUS_FRACTION` times ``scene.extent``; for a G-buffer (a user's frame, no scene),
    times the diagonal of the bounding box of its covered pixels' view-space positions."""
    if hasattr(scene, "extent"):
        return RADIUS_FRACTION * float(scene.extent)
    p = np.asarray(scene.position)[np.asarray(scene.valid)]
    if p.size == 0:
        raise ValueError("the G-buffer covers no pixel: give a radius")
    return RADIUS_FRACTION * float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


def machine() -> dict:
    """The machine and library versions that set the timings: cores available to this
    process, processor, Python, NumPy, SciPy, embreex and vobscure versions."""
    from importlib.metadata import PackageNotFoundError, version

    import scipy

    def installed(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return "unknown"

    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cores = os.cpu_count()
    return {"cores": cores, "cpu": platform.processor() or platform.machine(),
            "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
            "embreex": installed("embreex"), "vobscure": installed("vobscure")}


@dataclass(frozen=True)
class Timing:
    """Wall-clock and process seconds of the timed runs of one callable."""

    runs: tuple
    cpu_runs: tuple

    @property
    def median(self) -> float:
        """Median wall seconds."""
        return float(np.median(self.runs))

    @property
    def cpu_median(self) -> float:
        """Median process (CPU) seconds over all threads."""
        return float(np.median(self.cpu_runs))


def time_calls(functions: dict, repeats: int) -> tuple[dict, dict]:
    """Time zero-argument callables: one untimed warm-up call each, then ``repeats`` rounds
    that call every function once (round-robin).

    Round-robin spreads a slow spell of a shared machine over every function alike; the
    warm-up builds what the first call caches (sample patterns) and gives the value returned.

    Returns
    -------
    timings : dict of label to Timing
    values : dict of label to the warm-up call's result
    """
    values = {label: fn() for label, fn in functions.items()}
    wall = {label: [] for label in functions}
    cpu = {label: [] for label in functions}
    for _ in range(repeats):
        for label, fn in functions.items():
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[label].append(time.perf_counter() - t0)
            cpu[label].append(time.process_time() - c0)
    return {k: Timing(tuple(wall[k]), tuple(cpu[k])) for k in functions}, values


def cell(value, digits: int | None = 4) -> str:
    """A table cell: floats with ``digits`` significant digits (``None``: exact ``repr``),
    ``nan``/``inf``, booleans as yes/no, None as an empty cell."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value) if digits is None else f"{value:.{digits}g}"
    if isinstance(value, np.integer):
        return str(int(value))
    return str(value)


def columns_of(rows) -> list:
    """The union of the rows' keys, in order of first appearance."""
    cols = []
    for row in rows:
        cols.extend(k for k in row if k not in cols)
    return cols


def _csv_cell(value, digits):
    if isinstance(value, (bool, np.bool_)):
        return str(int(value))      # 0 / 1: what a spreadsheet or NumPy reads as a number
    return cell(value, digits)


def csv_text(rows, columns=None, *, digits: int | None = None) -> str:
    """Rows (dicts) as CSV text; a key a row lacks is an empty cell, booleans are 0 / 1, floats
    are exact (``repr``) unless ``digits`` is given.

    Examples
    --------
    >>> print(csv_text([{"a": 1, "b": 0.5}, {"a": 2}]), end="")
    a,b
    1,0.5
    2,
    """
    columns = list(columns) if columns is not None else columns_of(rows)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_csv_cell(row.get(c), digits) for c in columns])
    return buf.getvalue()


def write_text(path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    data = text.encode("utf-8")
    return atomic_write(Path(path), lambda fh: fh.write(data))


def write_csv(path, rows, columns=None, *, digits: int | None = None) -> Path:
    """:func:`csv_text` written atomically to ``path``."""
    return write_text(path, csv_text(rows, columns, digits=digits))


def markdown_table(rows, columns=None, *, digits: int = 4, headers=None) -> str:
    """Rows as a Markdown table (``headers`` renames columns), numbers to ``digits`` digits."""
    columns = list(columns) if columns is not None else columns_of(rows)
    names = [headers.get(c, c) if headers else c for c in columns]
    lines = ["| " + " | ".join(names) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        lines.append("| " + " | ".join(cell(row.get(c), digits).replace("|", "\\|") for c in columns) + " |")
    return "\n".join(lines)


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return str(value)


def write_json(path, record) -> Path:
    """``record`` as indented, key-sorted JSON (NumPy values converted), atomically."""
    return write_text(path, json.dumps(record, indent=2, sort_keys=True, default=_json_default))


def new_figure(width: float, height: float, dpi: int = 100):
    """A matplotlib ``Figure`` on the Agg canvas (never pyplot), constrained layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically."""
    return atomic_write(Path(path), lambda fh: fig.savefig(fh, format="png", dpi="figure"))


def progress_bar(total, desc: str, enabled: bool = True):
    """A tqdm bar (disabled when ``enabled`` is false) that leaves no line behind."""
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, disable=not enabled, leave=False)
