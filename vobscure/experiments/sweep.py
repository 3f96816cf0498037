"""Sweeps: many scenes x cameras x estimator configurations, on any executor.

:func:`sweep` runs a list of :class:`SweepConfig` and returns one :class:`SweepResult` per
configuration, in the input order: the median seconds over ``repeats`` timed runs, depth
taps per pixel, and the error (:func:`vobscure.metrics.error`) against every reference the
configuration asks for, plus the error decomposition (:func:`vobscure.metrics.decompose`)
when both the screen-space and the world-space VO are asked for.

Every configuration is one task, a call of a top-level function with picklable arguments,
so the sweep runs on any :class:`concurrent.futures.Executor`: the default local process
pool, a thread pool, or a Dask cluster through ``client.get_executor()`` (see
``docs/experiments.md``). A worker keeps the scenes, G-buffers and references it has made
(a small in-memory store per process), and tasks are submitted grouped by scene and
camera, so a G-buffer or reference is computed once per group per worker, and only the
references that are asked for. With a :class:`~vobscure.experiments.cache.ReferenceCache`
the references are also kept on disk across runs.

The numbers do not depend on the executor: every random choice comes from the
configuration's integer seeds, and the references' parallel chunks do not depend on the
number of threads. Only the timing fields (:data:`TIMING_FIELDS`) differ between runs.

Examples
--------
>>> from concurrent.futures import ThreadPoolExecutor
>>> from vobscure.experiments.sweep import SweepConfig, sweep
>>> configs = [SweepConfig("slab", method, samples, size=(8, 8), radius=0.5, references=("screen",),
...                        reference_samples=64) for method, samples in (("line", 5), ("area", 1))]
>>> with ThreadPoolExecutor(1) as pool:
...     results = sweep(configs, executor=pool, progress=False)
>>> [(r.config.label, r.taps_per_pixel, r.errors["screen"].pixels == r.pixels) for r in results]
[('line 5', 5, True), ('area 1', 1, True)]
"""

from __future__ import annotations

import csv
import io
import json
import math
import multiprocessing
import os
import threading
import time
from collections import OrderedDict
from collections.abc import Iterable, Mapping
from concurrent.futures import Executor, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from .._io import atomic_write
from .._validate import check_choice, check_int, check_positive
from ..metrics import DECOMPOSITION_TERMS

__all__ = ["SweepConfig", "SweepResult", "sweep", "results_to_csv", "results_to_markdown",
           "METHODS", "REFERENCES", "TIMING_FIELDS", "DEFAULT_SIZE", "DEFAULT_WORKERS",
           "RADIUS_FRACTION"]

#: Estimators a configuration can run: ``vo_point``, ``vo_line``, ``vo_area``, ``vo_reference``.
METHODS = ("point", "line", "area", "reference")
#: References an estimate can be compared with: the converged screen-space VO
#: (:func:`vobscure.vo_reference`, same settings as the estimate) and the ray-cast
#: world-space VO, ambient occlusion within the radius and obscurance (linear falloff).
REFERENCES = ("screen", "volumetric", "ao", "obscurance")
#: Fields of :meth:`SweepResult.as_row` that are measured times and so differ between runs.
TIMING_FIELDS = ("seconds", "seconds_runs")
#: Image size (width, height) when a configuration gives neither size nor camera.
DEFAULT_SIZE = (64, 64)
#: Ball radius as a fraction of the scene's extent when a configuration gives none.
RADIUS_FRACTION = 0.1
#: Processes of the default local executor.
DEFAULT_WORKERS = 2
#: Scenes, G-buffers and references a worker process keeps in memory (least recently used
#: first out; a view with its scene and four references takes six).
MEMO_ENTRIES = 12
#: The fetch each method uses (the estimators' defaults) and the depth texels one tap reads
#: (nearest 1, bilinear 4, vo_area's quadratic B-spline mip lookup 18; as in
#: :data:`vobscure.experiments.claims.TEXELS_PER_TAP`).
FETCH = {"point": "bilinear", "line": "nearest", "area": "bspline", "reference": "bilinear"}
TEXELS_PER_TAP = {"nearest": 1, "bilinear": 4, "bspline": 18}
#: Statistics of :class:`~vobscure.metrics.ErrorReport` written per reference by :meth:`SweepResult.as_row`.
ERROR_STATS = ("rmse", "mae", "bias", "max_abs", "psnr", "ssim", "pixels")


def _scene_spec(scene) -> str:
    from ..scenes import names
    from ..scenes.io import SUPPORTED_EXTENSIONS

    if isinstance(scene, os.PathLike):
        scene = os.fspath(scene)
    if not isinstance(scene, str):
        raise ValueError(f"scene must be a built-in scene name or a mesh path, got {type(scene).__name__}")
    if scene in names() or Path(scene).suffix.lower() in SUPPORTED_EXTENSIONS:
        return scene
    raise ValueError(f"scene must be one of {', '.join(names())} or a mesh file "
                     f"({', '.join(SUPPORTED_EXTENSIONS)}), got {scene!r}")


@dataclass(frozen=True)
class SweepConfig:
    """One estimator configuration on one scene and camera, and what to compare it with.

    Parameters
    ----------
    scene : str
        A built-in scene (:func:`vobscure.scenes.names`) or a mesh file (a path that every
        worker can read).
    method : {"point", "line", "area", "reference"}
    samples : int
        Samples of the estimator (points, lines, area samples, or the reference's points).
    radius : float, optional
        Ball radius; default :data:`RADIUS_FRACTION` times the scene's extent.
    size : (int, int), optional
        Image (width, height). Default the camera's size, else :data:`DEFAULT_SIZE`.
    camera : Camera or mapping, optional
        The view (a :class:`~vobscure.Camera` or its ``to_dict()``); rendered at ``size``
        when both are given. Default ``scene.camera(size)``, the scene's suggested view.
    normal_clamp : bool
    thickness : float, optional
    falloff : {"constant", "quadratic"}
        As in the estimators; the screen-space and world-space VO references use the same.
    seed : int
        Seed of the estimator.
    repeats : int
        Timed runs; the median is reported.
    references : tuple of str
        Some of :data:`REFERENCES` (a single name is accepted).
    rays : int
        Rays per pixel of the ray-cast ``ao`` and ``obscurance`` references and points per
        ball of the ``volumetric`` one.
    reference_samples : int
        Points per ball of the ``screen`` reference.
    reference_seed : int
        Seed of every reference (shared by all configurations, so that a reference is
        computed once per scene and camera).
    allow_open : bool
        Accept a scene that is not closed for the ``volumetric`` reference.

    Examples
    --------
    >>> c = SweepConfig("crease", "line", 9, size=(32, 24), references="ao")
    >>> c.size, c.references, c.label
    ((32, 24), ('ao',), 'line 9')
    """

    scene: str = "crease"
    method: str = "line"
    samples: int = 9
    radius: float | None = None
    size: tuple | None = None
    camera: object = None
    normal_clamp: bool = False
    thickness: float | None = None
    falloff: str = "constant"
    seed: int = 0
    repeats: int = 1
    references: tuple = ("screen",)
    rays: int = 256
    reference_samples: int = 1024
    reference_seed: int = 0
    allow_open: bool = False

    def __post_init__(self):
        from ..camera import Camera, _check_size
        from ..groundtruth import VO_FALLOFFS

        put = object.__setattr__
        put(self, "scene", _scene_spec(self.scene))
        check_choice(self.method, "method", METHODS)
        put(self, "samples", check_int(self.samples, "samples"))
        if self.radius is not None:
            put(self, "radius", check_positive(self.radius, "radius"))
        camera = self.camera
        if isinstance(camera, Mapping):
            camera = Camera.from_dict(camera)
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a vobscure Camera, a Camera.to_dict() mapping or None, "
                             f"got {type(camera).__name__}")
        size = None if self.size is None else _check_size(self.size)
        if camera is not None and size is not None and size != camera.size:
            camera = camera.with_size(size)
        put(self, "camera", camera)
        put(self, "size", camera.size if camera is not None else (size or DEFAULT_SIZE))
        put(self, "normal_clamp", _check_bool(self.normal_clamp, "normal_clamp"))
        if self.thickness is not None:
            put(self, "thickness", check_positive(self.thickness, "thickness"))
        check_choice(self.falloff, "falloff", VO_FALLOFFS)
        put(self, "seed", check_int(self.seed, "seed", minimum=0))
        put(self, "repeats", check_int(self.repeats, "repeats"))
        refs = (self.references,) if isinstance(self.references, str) else tuple(self.references)
        for r in refs:
            check_choice(r, "references", REFERENCES)
        if len(set(refs)) != len(refs):
            raise ValueError(f"references must not repeat a name, got {refs}")
        put(self, "references", refs)
        put(self, "rays", check_int(self.rays, "rays", minimum=2))
        put(self, "reference_samples", check_int(self.reference_samples, "reference_samples", minimum=2))
        put(self, "reference_seed", check_int(self.reference_seed, "reference_seed", minimum=0))
        put(self, "allow_open", _check_bool(self.allow_open, "allow_open"))

    @property
    def label(self) -> str:
        """``"<method> <samples>"``, e.g. ``"line 9"``."""
        return f"{self.method} {self.samples}"

    @property
    def view_key(self) -> str:
        """The scene and camera (or size) as one string: configurations that share it share a
        G-buffer and references."""
        cam = self.camera.to_dict() if self.camera is not None else {"size": list(self.size)}
        return json.dumps([self.scene, cam], sort_keys=True)


def _check_bool(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


@dataclass(frozen=True, eq=False)
class SweepResult:
    """The measurements of one :class:`SweepConfig`.

    Attributes
    ----------
    config : SweepConfig
    radius : float
        The radius used (the configuration's, or its default resolved on the scene).
    camera : dict
        The camera used (``Camera.to_dict()``).
    seconds : float
        Median wall-clock seconds of one estimator call over ``config.repeats`` timed runs
        (after one untimed warm-up call, which gives the image measured).
    seconds_runs : tuple of float
        Every timed run.
    taps_per_pixel : int
        Depth-buffer taps per pixel (the machine-independent cost).
    texels_per_pixel : int
        Depth texels those taps read (see :data:`TEXELS_PER_TAP`).
    pixels : int
        Covered (non-background) pixels of the G-buffer.
    errors : dict of str to ErrorReport
        The error against each requested reference.
    decomposition : dict or None
        :meth:`vobscure.metrics.Decomposition.as_dict` when ``screen`` and ``volumetric``
        were requested (against ``ao`` when that was requested too).
    image : (H, W) ndarray or None
        The estimate, when :func:`sweep` was asked to keep images.
    """

    config: SweepConfig
    radius: float
    camera: dict
    seconds: float
    seconds_runs: tuple
    taps_per_pixel: int
    texels_per_pixel: int
    pixels: int
    errors: dict = field(default_factory=dict)
    decomposition: dict | None = None
    image: np.ndarray | None = None

    def as_row(self) -> dict:
        """A flat record for tables: the configuration, the costs, ``<stat>_<reference>`` for
        every reference and statistic of :data:`ERROR_STATS`, and the decomposition's
        ``<term>_<stat>`` columns (with ``decomposition_target``)."""
        c = self.config
        row = {
            "scene": c.scene, "width": c.size[0], "height": c.size[1], "method": c.method,
            "samples": c.samples, "radius": self.radius, "normal_clamp": c.normal_clamp,
            "thickness": c.thickness, "falloff": c.falloff, "seed": c.seed, "repeats": c.repeats,
            "seconds": self.seconds, "seconds_runs": " ".join(repr(s) for s in self.seconds_runs),
            "taps_per_pixel": self.taps_per_pixel, "texels_per_pixel": self.texels_per_pixel,
            "pixels": self.pixels,
        }
        for ref in sorted(c.references, key=REFERENCES.index):
            report = self.errors[ref].as_dict()
            for stat in ERROR_STATS:
                row[f"{stat}_{ref}"] = report[stat]
        if self.decomposition is not None:
            for key, value in self.decomposition.items():
                if key not in ("pixels", "ignored", "target"):
                    row[key] = value
            row["decomposition_target"] = self.decomposition["target"]
        row.update(references=" ".join(c.references), rays=c.rays, reference_samples=c.reference_samples,
                   reference_seed=c.reference_seed, camera=json.dumps(self.camera, sort_keys=True))
        return row


# ----------------------------------------------------------------------------- worker side
class _Memo:
    """A small thread-safe LRU store; ``get(key, make)`` calls ``make`` once per key at a time."""

    def __init__(self, maxsize: int):
        self.maxsize = maxsize
        self._data: OrderedDict = OrderedDict()
        self._lock = threading.Lock()
        self._making: dict = {}

    def get(self, key, make):
        with self._lock:
            if key in self._data:
                self._data.move_to_end(key)
                return self._data[key]
            key_lock = self._making.setdefault(key, threading.Lock())
        with key_lock:
            with self._lock:
                if key in self._data:
                    self._data.move_to_end(key)
                    return self._data[key]
            value = make()
            with self._lock:
                self._data[key] = value
                while len(self._data) > self.maxsize:
                    self._data.popitem(last=False)
                self._making.pop(key, None)
        return value

    def clear(self):
        with self._lock:
            self._data.clear()


_MEMO = _Memo(MEMO_ENTRIES)


def _stamp(spec: str):
    """What identifies a scene's content cheaply: None for a built-in, (mtime, size) of a file."""
    from ..scenes import names

    if spec in names():
        return None
    st = os.stat(spec)
    return (st.st_mtime_ns, st.st_size)


def _view(config: SweepConfig):
    """(scene, camera, G-buffer) of the configuration, made once per worker."""
    from ..gbuffer import render_gbuffer
    from ..scenes import get, load, names

    stamp = _stamp(config.scene)

    def make_scene():
        return get(config.scene) if config.scene in names() else load(config.scene)

    def make_view():
        scene = _MEMO.get(("scene", config.scene, stamp), make_scene)
        camera = config.camera if config.camera is not None else scene.camera(config.size)
        gb = render_gbuffer(scene, camera)
        return scene, camera, gb

    return _MEMO.get(("view", config.view_key, stamp), make_view)


def _reference(name: str, config: SweepConfig, scene, gb, radius: float, cache) -> np.ndarray:
    """The (H, W) reference ``name`` of the configuration's view, made once per worker."""
    from .cache import ground_truth_cached, screen_reference_cached

    seed = config.reference_seed
    if name == "screen":
        params = dict(radius=radius, samples=config.reference_samples, normal_clamp=config.normal_clamp,
                      thickness=config.thickness, falloff=config.falloff, seed=seed)

        def make():
            return screen_reference_cached(gb, scene, cache=cache, **params)[0].value
    else:
        params = dict(quantity=name, radius=radius, rays=config.rays, samples=config.rays, seed=seed)
        if name == "volumetric":
            params.update(falloff=config.falloff, normal_clamp=config.normal_clamp,
                          allow_open=config.allow_open)

        def make():
            return ground_truth_cached(scene, gb, cache=cache, progress=False, **params)[0].value

    key = ("reference", config.view_key, _stamp(config.scene), name, json.dumps(params, sort_keys=True))
    return _MEMO.get(key, make)


def _estimator(config: SweepConfig):
    from .. import screenspace

    return {"point": screenspace.vo_point, "line": screenspace.vo_line, "area": screenspace.vo_area,
            "reference": _reference_value}[config.method]


def _reference_value(gbuffer, **kwargs) -> np.ndarray:
    from .. import screenspace

    return screenspace.vo_reference(gbuffer, **kwargs).value


def _taps(config: SweepConfig) -> int:
    if config.method == "reference":
        from ..estimate import DEFAULT_GROUPS   # vo_reference: antithetic pairs in every group
        return 2 * DEFAULT_GROUPS * -(-config.samples // (2 * DEFAULT_GROUPS))
    return config.samples


def _run_config(config: SweepConfig, cache, keep_image: bool) -> SweepResult:
    """One task of :func:`sweep` (top level, so that any executor can pickle it)."""
    from ..metrics import decompose, error

    scene, camera, gb = _view(config)
    radius = config.radius if config.radius is not None else RADIUS_FRACTION * scene.extent
    refs = {name: _reference(name, config, scene, gb, radius, cache) for name in config.references}
    fn = _estimator(config)
    kwargs = dict(radius=radius, samples=config.samples, normal_clamp=config.normal_clamp,
                  thickness=config.thickness, falloff=config.falloff, seed=config.seed)
    image = fn(gb, **kwargs)   # warm-up (sample patterns are built and kept on the first call)
    runs = []
    for _ in range(config.repeats):
        t0 = time.perf_counter()
        fn(gb, **kwargs)
        runs.append(time.perf_counter() - t0)
    errors = {name: error(image, ref) for name, ref in refs.items()}
    decomposition = None
    if "screen" in refs and "volumetric" in refs:
        decomposition = decompose(image, refs["screen"], refs["volumetric"], ao=refs.get("ao"),
                                  obscurance=refs.get("obscurance")).as_dict()
    taps = _taps(config)
    return SweepResult(config=config, radius=float(radius), camera=camera.to_dict(),
                       seconds=float(np.median(runs)), seconds_runs=tuple(runs), taps_per_pixel=taps,
                       texels_per_pixel=taps * TEXELS_PER_TAP[FETCH[config.method]],
                       pixels=int(gb.valid.sum()), errors=errors, decomposition=decomposition,
                       image=image if keep_image else None)


# ----------------------------------------------------------------------------- driver
def _default_executor(workers: int) -> ProcessPoolExecutor:
    # A fresh interpreter per worker (never fork): the parent may hold Embree's and the
    # tracer pool's threads, which a forked child would inherit in an undefined state.
    # With forkserver, the server imports vobscure once and the workers are forked from it
    # (before any tracer exists): two workers importing the library side by side took 7 s on
    # 2 cores, one import 3 s. This sets the preload list of this process's forkserver (it
    # has no effect once the server runs).
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["__main__", __name__])
    else:
        ctx = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=ctx)


def sweep(configs: Iterable[SweepConfig], *, executor: Executor | None = None, progress: bool = True,
          cache=None, keep_images: bool = False) -> list[SweepResult]:
    """Run every configuration; one :class:`SweepResult` per configuration, in input order.

    Parameters
    ----------
    configs : iterable of SweepConfig
    executor : concurrent.futures.Executor, optional
        Where the tasks run: any executor whose ``submit`` returns
        :class:`concurrent.futures.Future` objects -- a ``ThreadPoolExecutor``, a
        ``ProcessPoolExecutor``, or Dask's ``client.get_executor()``. Default: a local process
        pool of :data:`DEFAULT_WORKERS` processes (started with ``forkserver``, or ``spawn``
        where that is missing), shut down at the end. A given executor is left running.
    progress : bool
        A tqdm progress bar over the configurations.
    cache : ReferenceCache, optional
        A disk cache for the references (shared by the workers; they must see its folder).
        Default: references live in the workers' memory only.
    keep_images : bool
        Return every configuration's estimate in :attr:`SweepResult.image`.

    Returns
    -------
    list of SweepResult

    Notes
    -----
    Time is measured inside the workers, which share the machine: with several workers the
    seconds include their contention. For timings to compare with each other, run on one
    worker (``concurrent.futures.ThreadPoolExecutor(1)``); the other numbers are the same on
    any executor.
    """
    from .cache import ReferenceCache

    configs = list(configs)
    for i, c in enumerate(configs):
        if not isinstance(c, SweepConfig):
            raise ValueError(f"configs[{i}] must be a SweepConfig, got {type(c).__name__}")
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise ValueError(f"executor must be a concurrent.futures.Executor (with submit), got {type(executor).__name__}")
    if cache is not None and not isinstance(cache, ReferenceCache):
        raise ValueError(f"cache must be a ReferenceCache or None, got {type(cache).__name__}")
    keep_images = _check_bool(keep_images, "keep_images")
    if not configs:
        return []
    # grouped by view, so that the tasks of one G-buffer reach the workers together
    order = sorted(range(len(configs)), key=lambda i: (configs[i].view_key, i))
    own = executor is None
    if own:
        executor = _default_executor(min(DEFAULT_WORKERS, len(configs)))
    results: list = [None] * len(configs)
    futures = {}
    try:
        for i in order:
            futures[executor.submit(_run_config, configs[i], cache, keep_images)] = i
        with tqdm(total=len(configs), desc="sweep", unit="config", disable=not progress) as bar:
            for future in as_completed(futures):
                i = futures[future]
                try:
                    results[i] = future.result()
                except BaseException as exc:
                    for f in futures:
                        f.cancel()
                    exc.add_note(f"in sweep configuration {i}: {configs[i]!r}")
                    raise
                bar.update(1)
    finally:
        if own:
            executor.shutdown(wait=True, cancel_futures=True)
        # tasks that ran in this process (a thread pool) leave their G-buffers here: free them
        _MEMO.clear()
    return results


# ----------------------------------------------------------------------------- writers
_COLUMNS_HEAD = ("scene", "width", "height", "method", "samples", "radius", "normal_clamp", "thickness",
                 "falloff", "seed", "repeats", "seconds", "seconds_runs", "taps_per_pixel",
                 "texels_per_pixel", "pixels")
_COLUMNS_TAIL = ("references", "rays", "reference_samples", "reference_seed", "camera")


def _rows(results) -> tuple[list[dict], list[str]]:
    rows = []
    for i, r in enumerate(results):
        if not isinstance(r, SweepResult):
            raise ValueError(f"results[{i}] must be a SweepResult, got {type(r).__name__}")
        rows.append(r.as_row())
    # the order of as_row, with every reference's and the decomposition's columns in place
    # even when the first rows lack them
    present = {k for row in rows for k in row}
    canonical = [k for k in _COLUMNS_HEAD]
    canonical += [f"{stat}_{ref}" for ref in REFERENCES for stat in ERROR_STATS]
    canonical += [f"{term}_{stat}" for term in DECOMPOSITION_TERMS for stat in ("rmse", "bias", "mae")]
    canonical += ["decomposition_target", *_COLUMNS_TAIL]
    columns = [k for k in canonical if k in present]
    for row in rows:
        columns.extend(k for k in row if k not in columns)
    return rows, columns


def results_to_csv(results, path) -> Path:
    """Write the results as CSV (one row per configuration, :meth:`SweepResult.as_row`),
    atomically. Columns are the union over the rows (a reference one row did not ask for is
    left empty); floats are written exactly (``repr``). Returns the path."""
    rows, columns = _rows(results)
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: ("" if v is None else v) for k, v in row.items()})
    text = buf.getvalue().encode()
    return atomic_write(path, lambda fh: fh.write(text))


def _cell(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, str) and value == "":
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return f"{value:.4g}"
    return str(value).replace("|", "\\|")


def results_to_markdown(results, path=None) -> str:
    """The results as a markdown table; written atomically to ``path`` when given.

    Columns whose value is the same in every row (and the camera, the individual timed runs)
    are listed once above the table as common settings; numbers have 4 significant digits.

    Examples
    --------
    >>> print(results_to_markdown([]))
    (no results)
    <BLANKLINE>
    """
    rows, columns = _rows(results)
    if not rows:
        text = "(no results)\n"
    else:
        skip = {"seconds_runs", "camera"}
        common = [k for k in columns if k not in skip and len(rows) > 1
                  and all(k in r for r in rows) and len({_cell(r[k]) for r in rows}) == 1]
        shown = [k for k in columns if k not in skip and k not in common]
        lines = []
        if common:
            lines.append("Common settings: " + ", ".join(f"{k} = {_cell(rows[0][k])}" for k in common) + ".")
            lines.append("")
        lines.append("| " + " | ".join(shown) + " |")
        lines.append("|" + "|".join("---" for _ in shown) + "|")
        for r in rows:
            lines.append("| " + " | ".join(_cell(r[k]) if k in r else "" for k in shown) + " |")
        text = "\n".join(lines) + "\n"
    if path is not None:
        data = text.encode()
        atomic_write(path, lambda fh: fh.write(data))
    return text


class _CallableModule(__import__("types").ModuleType):
    """Lets ``vobscure.experiments.sweep(configs, executor=...)`` call :func:`sweep` while
    ``vobscure.experiments.sweep.SweepConfig`` etc. stay reachable (the module and its main
    function share a name)."""

    def __call__(self, configs, **kwargs):
        return sweep(configs, **kwargs)


__import__("sys").modules[__name__].__class__ = _CallableModule
