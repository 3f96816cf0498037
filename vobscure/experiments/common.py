"""What every experiment shares: the default radius (and its cap from the view), the machine record, the timer, and the
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

__all__ = ["RADIUS_FRACTION", "RADIUS_METRES", "RADIUS_CAP_FRACTION", "RADIUS_CAP_COVERAGE", "RadiusChoice",
           "choose_radius", "radius_cap", "default_radius", "machine", "Timing", "time_calls", "cell", "columns_of",
           "csv_text", "write_csv", "markdown_table", "write_text", "write_json", "new_figure",
           "save_figure", "progress_bar"]

#: Default ball radius (and AO distance) as a fraction of the scene's extent, the diagonal of
#: its bounding box: the radius of every experiment and command that is given none, in a
#: scene that does not declare its units.
RADIUS_FRACTION = 0.1
#: Default radius in a scene that declares metres (``scene.metadata["units"] == "m"``, as
#: every glTF file does): 0.5 m, the default effect radius of XeGTAO (GameTechDev/XeGTAO,
#: ``XeGTAO.h``, ``GTAOSettings::Radius = 0.5f``, "world (view) space size of the occlusion
#: sphere"). Engines' defaults span a wide range: Unreal's ``AmbientOcclusionRadius`` is 200
#: (cm, ``FPostProcessSettings``), Unity HDRP's ``radius`` 2.0, Unity URP's SSAO ``Radius``
#: 0.035; XeGTAO's is the one tuned against a ray-traced ground truth.
RADIUS_METRES = 0.5
#: The cap: the default ball's projected radius stays under this fraction of the image height ...
RADIUS_CAP_FRACTION = 0.25
#: ... on at least this fraction of the covered pixels.
RADIUS_CAP_COVERAGE = 0.95
#: A capped radius is this fraction of the exact bound, so that rounding cannot put the
#: bounding pixel at exactly a quarter of the image height.
_CAP_MARGIN = 0.999


@dataclass(frozen=True)
class RadiusChoice:
    """A default radius and how it was chosen (see :func:`choose_radius`).

    Attributes
    ----------
    radius : float
        The radius, in scene units.
    rule : str
        ``"metres"`` (:data:`RADIUS_METRES`), ``"extent"`` (:data:`RADIUS_FRACTION` x the
        extent), ``"frame"`` (:data:`RADIUS_FRACTION` x the diagonal of a G-buffer's covered
        view-space positions), each followed by ``"+cap"`` when the view's cap lowered it.
    base : float
        The radius of the rule before the cap.
    cap : float
        The largest radius whose projection stays under ``limit_px`` on
        :data:`RADIUS_CAP_COVERAGE` of the covered pixels (inf without a view).
    percentile_px : float
        The projected radius (pixels) of ``radius`` at the :data:`RADIUS_CAP_COVERAGE`
        quantile of the covered pixels (NaN without a view).
    limit_px : float
        :data:`RADIUS_CAP_FRACTION` x the image height (NaN without a view).
    """

    radius: float
    rule: str
    base: float
    cap: float
    percentile_px: float
    limit_px: float

    @property
    def capped(self) -> bool:
        """True when the view's cap lowered the rule's radius."""
        return self.rule.endswith("+cap")

    def sentence(self) -> str:
        """How the radius was chosen, in one sentence (printed by ``vobscure compare``)."""
        why = {"metres": f"{RADIUS_METRES:g} m (the scene declares metres; XeGTAO's default radius)",
               "extent": f"{RADIUS_FRACTION:g} x the scene's extent",
               "frame": f"{RADIUS_FRACTION:g} x the diagonal of the frame's covered positions"}[self.rule.split("+")[0]]
        text = f"Radius {self.radius:.4g} (scene units): {why}"
        if self.capped:
            text += (f" = {self.base:.4g}, capped so that the ball's projected radius stays under a quarter of "
                     f"the image height ({self.limit_px:.4g} px) on {RADIUS_CAP_COVERAGE:.0%} of the covered pixels")
        elif math.isfinite(self.percentile_px):
            text += (f"; its projected radius is {self.percentile_px:.3g} px or less on {RADIUS_CAP_COVERAGE:.0%} of "
                     f"the covered pixels (under the cap of {self.limit_px:.4g} px, a quarter of the image height)")
        return text + "; --radius sets it in scene units."

    def to_dict(self) -> dict:
        """The fields, ``capped`` and :meth:`sentence`, for provenance records."""
        return {"radius": self.radius, "rule": self.rule, "base": self.base, "cap": self.cap,
                "percentile_px": self.percentile_px, "limit_px": self.limit_px, "capped": self.capped,
                "sentence": self.sentence()}


def _rule_radius(scene) -> tuple[float, str]:
    """The rule's radius before the cap: metres declared, the extent, or a frame's positions."""
    metadata = getattr(scene, "metadata", None) or {}
    if metadata.get("units") == "m":
        return RADIUS_METRES, "metres"
    if hasattr(scene, "extent"):
        return RADIUS_FRACTION * float(scene.extent), "extent"
    p = np.asarray(scene.position)[np.asarray(scene.valid)]
    if p.size == 0:
        raise ValueError("the G-buffer covers no pixel: give a radius")
    return RADIUS_FRACTION * float(np.linalg.norm(p.max(axis=0) - p.min(axis=0))), "frame"


def default_radius(scene) -> float:
    """The default radius of ``scene`` before any view's cap: :data:`RADIUS_METRES` when
    ``scene.metadata`` declares metres, else :data:`RADIUS_FRACTION` times ``scene.extent``;
    for a G-buffer (a user's frame, no scene), times the diagonal of the bounding box of its
    covered pixels' view-space positions. :func:`choose_radius` adds the cap of a view."""
    return _rule_radius(scene)[0]


def radius_cap(gbuffer) -> tuple[float, float]:
    """(cap, limit_px): the largest radius whose projection stays under a quarter of the image
    height on :data:`RADIUS_CAP_COVERAGE` of ``gbuffer``'s covered pixels, and that limit.

    A ball of radius R at view depth z projects to ``r_px = R * f_px / z`` pixels
    (perspective, ``f_px = H / (2 tan(fov_y / 2))``) or ``R * H / ortho_height``
    (orthographic): ``camera.pixels_per_unit(z)``. With ``k = ceil(0.95 n)`` of the n covered
    pixels and ``s_k`` the k-th smallest pixels-per-unit, every radius below ``limit / s_k``
    keeps k pixels under the limit; the cap is :data:`_CAP_MARGIN` times that bound.

    Raises
    ------
    ValueError
        When the G-buffer covers no pixel (an empty view has no scale to cap).
    """
    valid = np.asarray(gbuffer.valid, dtype=bool)
    if not valid.any():
        raise ValueError("the view covers no pixel of the scene: there is no scale to choose a radius from; "
                         "give a camera that sees the geometry, or a radius")
    cam = gbuffer.camera
    limit = RADIUS_CAP_FRACTION * cam.height
    per_unit = np.sort(np.asarray(cam.pixels_per_unit(np.asarray(gbuffer.depth)[valid]), dtype=np.float64).ravel())
    k = math.ceil(RADIUS_CAP_COVERAGE * per_unit.size)
    return _CAP_MARGIN * limit / float(per_unit[k - 1]), float(limit)


def choose_radius(scene, gbuffer=None) -> RadiusChoice:
    """The default radius of a scene (or a user's frame) seen through a view, and why.

    Parameters
    ----------
    scene : Scene or GBuffer
        A scene (its ``metadata`` units and ``extent`` set the rule) or a user's frame.
    gbuffer : GBuffer, optional
        The view the radius is for (the scene rendered by the camera); a frame is its own.
        Without one, the rule's radius is returned uncapped.

    Returns
    -------
    RadiusChoice
        ``radius = min(rule, cap)``; the rule is :data:`RADIUS_METRES` in a scene that
        declares metres, else :data:`RADIUS_FRACTION` x the extent (for a frame, x the
        diagonal of its covered view-space positions); the cap (:func:`radius_cap`) keeps
        the ball's projected radius under :data:`RADIUS_CAP_FRACTION` of the image height on
        :data:`RADIUS_CAP_COVERAGE` of the covered pixels.

    Examples
    --------
    >>> import vobscure as vo
    >>> sc = vo.scenes.slab()
    >>> choice = choose_radius(sc, vo.render_gbuffer(sc, sc.camera((32, 32))))
    >>> choice.rule, choice.radius == default_radius(sc), choice.percentile_px < choice.limit_px
    ('extent', True, True)
    """
    base, rule = _rule_radius(scene)
    if gbuffer is None and not hasattr(scene, "extent"):
        gbuffer = scene
    if gbuffer is None:
        return RadiusChoice(radius=base, rule=rule, base=base, cap=math.inf, percentile_px=math.nan,
                            limit_px=math.nan)
    cap, limit = radius_cap(gbuffer)
    radius = min(base, cap)
    if radius < base:
        rule += "+cap"
    cam = gbuffer.camera
    r_px = radius * np.asarray(cam.pixels_per_unit(np.asarray(gbuffer.depth)[np.asarray(gbuffer.valid)]))
    return RadiusChoice(radius=float(radius), rule=rule, base=float(base), cap=float(cap),
                        percentile_px=float(np.quantile(r_px, RADIUS_CAP_COVERAGE)), limit_px=limit)


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
