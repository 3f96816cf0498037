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
>>> from vobscure.experiments import SweepConfig, sweep
>>> configs = [SweepConfig("slab", method, samples, size=(8, 8), radius=0.5, references=("screen",),
...                        screen_samples=64) for method, samples in (("line", 5), ("area", 1))]
>>> with ThreadPoolExecutor(1) as pool:
...     results = sweep(configs, executor=pool, progress=False)
>>> [(r.config.label, r.taps_per_pixel, r.errors["screen"].pixels == r.pixels) for r in results]
[('line:5', 5, True), ('area:1', 1, True)]
"""

from __future__ import annotations

import json
import multiprocessing
import os
import threading
import time
from collections import OrderedDict
from collections.abc import Iterable, Mapping
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

import numpy as np

from .. import methods as _methods
from .. import references as _references
from .._validate import check_choice, check_int, check_positive
from ..metrics import DECOMPOSITION_TERMS
from .common import default_radius, progress_bar, write_text

__all__ = ["SweepConfig", "SweepResult", "InlineExecutor", "sweep", "view", "view_reference", "results_to_csv",
           "results_to_markdown", "check_thickness", "REFERENCES", "TIMING_FIELDS", "DEFAULT_SIZE",
           "DEFAULT_WORKERS", "DEFAULT_LAYERS"]

#: The names of the references an estimate can be compared with, in the order of the result
#: columns: those of the registry :data:`vobscure.references.REFERENCES`, which says what each
#: measures and how it is computed.
REFERENCES = _references.names()
#: Fields of :meth:`SweepResult.as_row` that are measured times and so differ between runs.
TIMING_FIELDS = ("seconds", "seconds_runs", "cpu_seconds")
#: Image size (width, height) when a configuration gives neither size nor camera.
DEFAULT_SIZE = (64, 64)
#: Processes of the default local executor.
DEFAULT_WORKERS = 2
#: Depth-peeled layers of the G-buffer when ``thickness="layers"`` gives no count.
DEFAULT_LAYERS = 4
#: Scenes, G-buffers and references a worker process keeps in memory (least recently used
#: first out; a view with its scene and four references takes six).
MEMO_ENTRIES = 12
#: Statistics of :class:`~vobscure.metrics.ErrorReport` written per reference by :meth:`SweepResult.as_row`.
ERROR_STATS = ("rmse", "mae", "bias", "max_abs", "psnr", "ssim", "pixels")


def check_thickness(thickness, layers, *, frame=None) -> tuple:
    """``(thickness, layers)`` checked: ``thickness`` None, a positive number (the thickness
    model, Loos & Sloan 2010, Sec. 4.3) or ``"layers"`` (the solid intervals of a layered
    G-buffer); ``layers`` the depth-peeled layers K >= 2 to render, only with ``"layers"``
    (default :data:`DEFAULT_LAYERS`), None otherwise. ``frame``: a user's G-buffer, which
    brings its own intervals (``gbuffer.intervals``) and has no scene to render layers from.

    Examples
    --------
    >>> check_thickness("layers", None), check_thickness(0.2, None), check_thickness(None, None)
    (('layers', 4), (0.2, None), (None, None))
    >>> check_thickness("fat", None)
    Traceback (most recent call last):
    ...
    ValueError: thickness must be a positive number (the thickness model, world units) or 'layers' (the solid intervals of a depth-peeled G-buffer), got 'fat'
    """
    if isinstance(thickness, str):
        if thickness != "layers":
            raise ValueError(f"thickness must be a positive number (the thickness model, world units) or 'layers' "
                             f"(the solid intervals of a depth-peeled G-buffer), got {thickness!r}")
    elif thickness is not None:
        thickness = check_positive(thickness, "thickness")
    if layers is not None:
        layers = check_int(layers, "layers", minimum=2)
        if thickness != "layers":
            raise ValueError(f"layers={layers} renders depth-peeled layers that only thickness='layers' reads; "
                             f"give thickness='layers' (--thickness layers) or no layers")
    if thickness == "layers" and frame is not None:
        if layers is not None:
            raise ValueError("layers renders a scene's layers; a G-buffer brings its own (gbuffer.intervals), "
                             "so give no layers with it")
        if frame.intervals is None:
            raise ValueError("thickness='layers' reads the G-buffer's solid intervals, but gbuffer.intervals is "
                             "None: attach them (GBuffer.from_arrays(..., back_depth=...) or "
                             "gbuffer.with_intervals(...)) or give a numeric thickness")
    elif thickness == "layers" and layers is None:
        layers = DEFAULT_LAYERS
    return thickness, layers


def _scene_spec(scene):
    """A scene name or path that every worker can resolve (checked here, built there), or a
    Scene or a GBuffer (for executors in this process only: they are not sent to other
    processes)."""
    from ..gbuffer import GBuffer
    from ..scenes import Scene, check_spec

    return scene if isinstance(scene, (Scene, GBuffer)) else check_spec(scene, exists=False)


@dataclass(frozen=True)
class SweepConfig:
    """One estimator configuration on one scene and camera, and what to compare it with.

    Parameters
    ----------
    scene : str, Scene or GBuffer
        A built-in scene (:func:`vobscure.scenes.names`) or a mesh file (a path that every
        worker can read); a :class:`~vobscure.scenes.Scene` object only with an executor
        that runs in this process (:class:`InlineExecutor`, a thread pool); or a user's
        :class:`~vobscure.GBuffer` (e.g. from :func:`vobscure.io.read_gbuffer`), also in
        process only, whose only possible reference is ``"screen"``: without the geometry
        nothing can be ray cast.
    method : str
        A method of the registry (:func:`vobscure.methods.names`): ``"point"``, ``"line"``,
        ``"area"``, ``"reference"``, ...
    samples : int
        Samples of the method (points, lines, area samples, or the reference's points).
    fetch : str, optional
        Another depth fetch than the method's default (e.g. ``"nearest"`` for points).
    radius : float, optional
        Ball radius; default :data:`~vobscure.experiments.common.RADIUS_FRACTION` times the
        scene's extent.
    size : (int, int), optional
        Image (width, height). Default the camera's size, else :data:`DEFAULT_SIZE`.
    camera : Camera or mapping, optional
        The view (a :class:`~vobscure.Camera` or its ``to_dict()``); rendered at ``size``
        when both are given. Default ``scene.camera(size)``, the scene's suggested view.
    normal_clamp : bool
        Half-ball VO (Loos & Sloan 2010, Sec. 4.4) for the estimate and the VO references.
    thickness : float or "layers", optional
        A number: the thickness model (Sec. 4.3) of the estimate and of the screen-space
        reference. ``"layers"``: the G-buffer is rendered with ``layers`` depth-peeled layers
        and a method that takes ``thickness="layers"``
        (:meth:`vobscure.methods.Method.takes_thickness`) reads its solid intervals; the
        references have no thickness then (the screen-space reference is the single-depth
        model). A method that does not take the kind given runs as without it.
    layers : int, optional
        Layers K >= 2 of the G-buffer with ``thickness="layers"`` (default
        :data:`DEFAULT_LAYERS`; a user's G-buffer brings its own intervals and takes none).
    falloff : {"constant", "quadratic"}
        As in the estimators; the screen-space and world-space VO references use the same.
    seed : int
        Seed of the estimator.
    repeats : int
        Timed runs after the untimed first call; the median is reported. 0: not timed
        (``seconds`` is NaN), for configurations that only measure error.
    references : tuple of str
        Names of the reference registry :data:`vobscure.references.REFERENCES` (a single
        name is accepted): ``"screen"``, ``"volumetric"``, ``"ao"`` and ``"obscurance"``
        (within the radius), ``"sky"`` and ``"sky_uniform"`` (ambient occlusion with no
        distance limit, cosine-weighted or uniform), ... Each entry says which sampling
        parameter below it uses (:attr:`vobscure.references.Reference.samples`).
    rays : int
        Rays per pixel (directions) of the ray-cast references but ``volumetric``.
    volume_samples : int
        Points per ball of the world-space ``volumetric`` reference.
    screen_samples : int
        Points per ball of the ``screen`` reference (:func:`vobscure.vo_reference`).
    reference_seed : int
        Seed of every reference (shared by all configurations, so that a reference is
        computed once per scene and camera).
    allow_open : bool
        Accept a scene that is not closed for the ``volumetric`` reference.

    Examples
    --------
    >>> c = SweepConfig("crease", "line", 9, size=(32, 24), references="ao")
    >>> c.size, c.references, c.label, c.own_reference
    ((32, 24), ('ao',), 'line:9', 'volumetric')
    """

    scene: str = "crease"
    method: str = "line"
    samples: int = 9
    fetch: str | None = None
    radius: float | None = None
    size: tuple | None = None
    camera: object = None
    normal_clamp: bool = False
    thickness: float | str | None = None
    layers: int | None = None
    falloff: str = "constant"
    seed: int = 0
    repeats: int = 1
    references: tuple = ("screen",)
    rays: int = 256
    volume_samples: int = 1024
    screen_samples: int = _references.SCREEN_SAMPLES
    reference_seed: int = 0
    allow_open: bool = False

    def __post_init__(self):
        from ..camera import Camera, check_size
        from ..groundtruth import VO_FALLOFFS

        from ..gbuffer import GBuffer

        put = object.__setattr__
        put(self, "scene", _scene_spec(self.scene))
        if isinstance(self.scene, GBuffer):
            put(self, "camera", self.scene.camera)
            refs = (self.references,) if isinstance(self.references, str) else tuple(self.references)
            if any(r not in _references.REFERENCES or _references.get(r).needs_scene for r in refs):
                raise ValueError(f"references {refs} need the scene's geometry; a G-buffer alone has only the "
                                 f"converged screen-space reference, references=('screen',)")
        config = _methods.Config(_methods.get(self.method).name, self.samples, fetch=self.fetch)
        put(self, "samples", config.samples)
        put(self, "fetch", config.fetch)
        if self.radius is not None:
            put(self, "radius", check_positive(self.radius, "radius"))
        camera = self.camera
        if isinstance(camera, Mapping):
            camera = Camera.from_dict(camera)
        if camera is not None and not isinstance(camera, Camera):
            raise ValueError(f"camera must be a vobscure Camera, a Camera.to_dict() mapping or None, "
                             f"got {type(camera).__name__}")
        size = None if self.size is None else check_size(self.size)
        if camera is not None and size is not None and size != camera.size:
            camera = camera.with_size(size)
        put(self, "camera", camera)
        put(self, "size", camera.size if camera is not None else (size or DEFAULT_SIZE))
        put(self, "normal_clamp", _check_bool(self.normal_clamp, "normal_clamp"))
        thickness, layers = check_thickness(self.thickness, self.layers,
                                            frame=self.scene if isinstance(self.scene, GBuffer) else None)
        put(self, "thickness", thickness)
        put(self, "layers", layers)
        check_choice(self.falloff, "falloff", VO_FALLOFFS)
        put(self, "seed", check_int(self.seed, "seed", minimum=0))
        put(self, "repeats", check_int(self.repeats, "repeats", minimum=0))
        refs = (self.references,) if isinstance(self.references, str) else tuple(self.references)
        for r in refs:
            check_choice(r, "references", _references.names())
        if len(set(refs)) != len(refs):
            raise ValueError(f"references must not repeat a name, got {refs}")
        put(self, "references", refs)
        put(self, "rays", check_int(self.rays, "rays", minimum=2))
        put(self, "volume_samples", check_int(self.volume_samples, "volume_samples", minimum=2))
        put(self, "screen_samples", check_int(self.screen_samples, "screen_samples", minimum=2))
        put(self, "reference_seed", check_int(self.reference_seed, "reference_seed", minimum=0))
        put(self, "allow_open", _check_bool(self.allow_open, "allow_open"))

    @property
    def method_config(self) -> _methods.Config:
        """The registry configuration (method, samples, fetch)."""
        return _methods.Config(self.method, self.samples, fetch=self.fetch)

    @property
    def label(self) -> str:
        """``"<method>:<samples>[:<fetch>]"``, e.g. ``"line:9"``."""
        return self.method_config.label

    @property
    def method_thickness(self):
        """The thickness the method is given: :attr:`thickness` when it takes that kind
        (:meth:`vobscure.methods.Method.takes_thickness`), else None (it runs as without)."""
        return self.thickness if self.method_config.spec.takes_thickness(self.thickness) else None

    @property
    def reference_thickness(self) -> float | None:
        """The thickness the references are computed with: a number, or None (with
        ``"layers"``: no reference reads layers)."""
        return None if self.thickness == "layers" else self.thickness

    @property
    def quantity(self) -> str:
        """What the method estimates with this ``normal_clamp`` (:data:`vobscure.methods.QUANTITIES`)."""
        return self.method_config.quantity(self.normal_clamp)

    @property
    def own_reference(self) -> str:
        """The reference of the method's own quantity (others measure model error)."""
        return self.method_config.reference(self.normal_clamp)

    @property
    def scene_name(self) -> str:
        """The scene's name or path; ``"custom"`` for a Scene object."""
        if isinstance(self.scene, str):
            return self.scene
        return "gbuffer" if type(self.scene).__name__ == "GBuffer" else "custom"

    @property
    def view_key(self) -> str:
        """The scene and camera (or size) as one string: configurations that share it share
        references, and a G-buffer when they also share :attr:`layers` (the first layer of a
        layered G-buffer is the one-layer G-buffer, bit for bit, and no reference reads the
        others)."""
        cam = self.camera.to_dict() if self.camera is not None else {"size": list(self.size)}
        scene = self.scene if isinstance(self.scene, str) else f"<{type(self.scene).__name__} at {id(self.scene):#x}>"
        return json.dumps([scene, cam], sort_keys=True)


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
        (after one untimed warm-up call, which gives the image measured); NaN when
        ``repeats`` is 0.
    seconds_runs : tuple of float
        Every timed run.
    cpu_seconds : float
        Median process (CPU) seconds of the timed runs, over all threads.
    taps_per_pixel : int
        Depth-buffer taps per pixel (the machine-independent cost, from the method registry).
    texels_per_pixel : int
        Depth texels those taps read (:data:`vobscure.methods.TEXELS_PER_TAP`).
    pixels : int
        Covered (non-background) pixels of the G-buffer.
    errors : dict of str to ErrorReport
        The error against each requested reference.
    decomposition : dict or None
        :meth:`vobscure.metrics.Decomposition.as_dict` when ``screen`` and ``volumetric``
        were requested (against ``ao`` when that was requested too).
    cache_hits : dict of str to bool
        Whether each reference came from the disk cache.
    stage_seconds : dict of str to float
        Wall-clock seconds of each stage this configuration's task ran, in the order run:
        ``"gbuffer"`` (loading the scene and rendering the G-buffer), ``"reference:<name>"``
        for each requested reference (``"reference:screen"``, ``"reference:ao"``, ...), and
        ``"method"`` (the estimator's untimed first call plus its ``repeats`` timed runs).
        A stage whose result the task did not compute -- a reference read from the disk
        cache, or a G-buffer or reference an earlier task of the same worker made -- takes
        0.0 here, and :attr:`stage_status` says why.
    stage_status : dict of str to str
        For each key of :attr:`stage_seconds`: ``"computed"``, ``"cached"`` (read from the
        disk cache) or ``"reused"`` (made by an earlier task of the same worker).
    image : (H, W) ndarray or None
        The estimate, when :func:`sweep` was asked to keep images.
    references : dict of str to Estimate, or None
        The reference estimates (value and stderr), when asked to keep images.
    gbuffer : GBuffer or None
        The G-buffer, when asked to keep images and the task ran in this process (a G-buffer
        is not sent between processes: it is dropped when the result is pickled).
    """

    config: SweepConfig
    radius: float
    camera: dict
    seconds: float
    seconds_runs: tuple
    cpu_seconds: float
    taps_per_pixel: int
    texels_per_pixel: int
    pixels: int
    errors: dict = field(default_factory=dict)
    decomposition: dict | None = None
    cache_hits: dict = field(default_factory=dict)
    stage_seconds: dict = field(default_factory=dict)
    stage_status: dict = field(default_factory=dict)
    image: np.ndarray | None = None
    references: dict | None = None
    gbuffer: object = None

    def __getstate__(self):
        return {**self.__dict__, "gbuffer": None}

    def as_row(self) -> dict:
        """A flat record for tables: the configuration (``thickness`` the one the method ran
        with, :attr:`SweepConfig.method_thickness`; ``layers`` K when it read them), the costs,
        ``<stat>_<reference>`` for every reference and statistic of :data:`ERROR_STATS`, and the decomposition's
        ``<term>_<stat>`` columns (with ``decomposition_target``)."""
        c = self.config
        row = {
            "scene": c.scene_name, "width": c.size[0], "height": c.size[1], "method": c.method,
            "samples": c.samples, "fetch": c.method_config.fetch_used, "radius": self.radius,
            "normal_clamp": c.normal_clamp, "thickness": c.method_thickness,
            "layers": c.layers if c.method_thickness == "layers" else None, "falloff": c.falloff, "seed": c.seed,
            "repeats": c.repeats, "seconds": self.seconds,
            "seconds_runs": " ".join(repr(s) for s in self.seconds_runs), "cpu_seconds": self.cpu_seconds,
            "taps_per_pixel": self.taps_per_pixel, "texels_per_pixel": self.texels_per_pixel,
            "pixels": self.pixels, "quantity": c.quantity, "own_reference": c.own_reference,
        }
        for ref in sorted(c.references, key=_references.names().index):
            report = self.errors[ref].as_dict()
            for stat in ERROR_STATS:
                row[f"{stat}_{ref}"] = report[stat]
        if self.decomposition is not None:
            for key, value in self.decomposition.items():
                if key not in ("pixels", "ignored", "target"):
                    row[key] = value
            row["decomposition_target"] = self.decomposition["target"]
        row.update(references=" ".join(c.references), rays=c.rays, volume_samples=c.volume_samples,
                   screen_samples=c.screen_samples, reference_seed=c.reference_seed,
                   camera=json.dumps(self.camera, sort_keys=True))
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


def _stamp(spec):
    """What identifies a scene's content cheaply: None for a built-in or a Scene object (its
    identity is in the view key), (mtime, size) of a file."""
    from ..scenes import names

    if not isinstance(spec, str) or spec in names():
        return None
    st = os.stat(spec)
    return (st.st_mtime_ns, st.st_size)


class _Stages:
    """The seconds and status of the stages of one task (:attr:`SweepResult.stage_seconds`)."""

    def __init__(self):
        self.seconds: dict = {}
        self.status: dict = {}

    def timed(self, name: str, make):
        """``make`` wrapped to record its wall-clock seconds under ``name`` when it runs."""
        def run():
            start = time.perf_counter()
            value = make()
            self.seconds[name] = time.perf_counter() - start
            self.status[name] = "computed"
            return value
        return run

    def reused(self, name: str, status: str = "reused"):
        """Record ``name`` as not computed by this task (unless it was)."""
        if name not in self.seconds:
            self.seconds[name] = 0.0
            self.status[name] = status


def view(config: SweepConfig, stages: _Stages | None = None):
    """(scene, camera, G-buffer) of a configuration, made once per worker process and kept
    while the sweep runs, with ``config.layers`` depth-peeled layers when it gives them (a
    G-buffer per view and layer count). ``stages``: records the ``"gbuffer"`` stage's seconds."""
    from ..render import render_gbuffer
    from ..scenes import resolve

    stamp = _stamp(config.scene)

    def make_view():
        if config.scene_name == "gbuffer":
            return None, config.scene.camera, config.scene
        scene = _MEMO.get(("scene", config.view_key if not isinstance(config.scene, str) else config.scene, stamp),
                          lambda: resolve(config.scene)[0])
        camera = config.camera if config.camera is not None else scene.camera(config.size)
        layered = {} if config.layers is None else {"layers": config.layers}
        return scene, camera, render_gbuffer(scene, camera, **layered)

    if stages is not None:
        make_view = stages.timed("gbuffer", make_view)
    result = _MEMO.get(("view", config.view_key, config.layers, stamp), make_view)
    if stages is not None:
        stages.reused("gbuffer")
    return result


def view_reference(name: str, config: SweepConfig, scene, gb, radius: float, cache, stages: _Stages | None = None,
               progress: bool = False):
    """(Estimate, cache hit) of the reference ``name`` of the configuration's view, made once
    per worker: the registry entry's arguments, computed through the disk cache. ``stages``
    records the stage ``"reference:<name>"``; ``progress`` shows the computation's own bar."""
    from . import cache as _cache

    ref = _references.get(name)
    params = ref.arguments(radius=radius, seed=config.reference_seed, rays=config.rays,
                           volume_samples=config.volume_samples, screen_samples=config.screen_samples,
                           normal_clamp=config.normal_clamp, thickness=config.reference_thickness,
                           falloff=config.falloff,
                           allow_open=config.allow_open)
    compute = getattr(_cache, ref.cached_by)

    def make():
        if ref.needs_scene:
            return compute(scene, gb, cache=cache, progress=progress, **params)
        return compute(gb, scene, cache=cache, progress=progress, **params)

    stage = f"reference:{name}"
    key = ("reference", config.view_key, _stamp(config.scene), name, json.dumps(params, sort_keys=True))
    result = _MEMO.get(key, make if stages is None else stages.timed(stage, make))
    if stages is not None:
        if stages.status.get(stage) == "computed" and result[1]:
            # made by this task, but read from the disk cache
            stages.seconds[stage] = 0.0
            stages.status[stage] = "cached"
        stages.reused(stage, "cached" if result[1] else "reused")
    return result


def _run_config(config: SweepConfig, cache, keep_image: bool, progress: bool = False) -> SweepResult:
    """One task of :func:`sweep` (top level, so that any executor can pickle it); ``progress``:
    a progress bar for each reference computed."""
    from ..metrics import decompose, error
    from .common import time_calls

    stages = _Stages()
    scene, camera, gb = view(config, stages)
    radius = config.radius if config.radius is not None else default_radius(scene if scene is not None else gb)
    made = {name: view_reference(name, config, scene, gb, radius, cache, stages, progress) for name in config.references}
    refs = {name: est for name, (est, _) in made.items()}
    mc = config.method_config
    kwargs = dict(radius=radius, normal_clamp=config.normal_clamp, thickness=config.thickness,
                  falloff=config.falloff, seed=config.seed)
    if mc.spec.needs_scene:
        kwargs["scene"] = scene
    start = time.perf_counter()
    timings, values = time_calls({"run": lambda: mc.run(gb, **kwargs)}, config.repeats)
    stages.seconds["method"] = time.perf_counter() - start
    stages.status["method"] = "computed"
    image = values["run"]
    runs = timings["run"].runs
    errors = {name: error(image, ref.value) for name, ref in refs.items()}
    decomposition = None
    world = next((name for name in _references.WORLD_VO if name in refs), None)
    if "screen" in refs and world is not None:
        decomposition = decompose(image, refs["screen"].value, refs[world].value,
                                  ao=refs["ao"].value if "ao" in refs else None,
                                  obscurance=refs["obscurance"].value if "obscurance" in refs else None).as_dict()
    nan = float("nan")
    return SweepResult(config=config, radius=float(radius), camera=camera.to_dict(),
                       seconds=timings["run"].median if runs else nan, seconds_runs=runs,
                       cpu_seconds=timings["run"].cpu_median if runs else nan, taps_per_pixel=mc.taps,
                       texels_per_pixel=mc.texels, pixels=int(gb.valid.sum()), errors=errors,
                       decomposition=decomposition, cache_hits={n: bool(h) for n, (_, h) in made.items()},
                       stage_seconds=dict(stages.seconds), stage_status=dict(stages.status),
                       image=image if keep_image else None, references=refs if keep_image else None,
                       gbuffer=gb if keep_image else None)


class InlineExecutor(Executor):
    """Runs every task at once in the calling thread, one after another: the executor for
    timings that must not share the machine with other tasks (``vobscure compare``).

    Examples
    --------
    >>> InlineExecutor().submit(pow, 2, 10).result()
    1024
    """

    def submit(self, fn, /, *args, **kwargs):
        future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as exc:
            future.set_exception(exc)
        return future


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


def sweep(configs: Iterable[SweepConfig], *, executor: Executor | None = None, progress: bool = False,
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
        A tqdm progress bar over the configurations (off by default, as everywhere); with an
        :class:`InlineExecutor` also one bar per reference computation, named after it
        (tasks in other threads or processes draw none).
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
    stage_bars = bool(progress) and isinstance(executor, InlineExecutor)
    if own:
        executor = _default_executor(min(DEFAULT_WORKERS, len(configs)))
    results: list = [None] * len(configs)
    futures = {}
    try:
        for i in order:
            futures[executor.submit(_run_config, configs[i], cache, keep_images, stage_bars)] = i
        with progress_bar(len(configs), "sweep", progress) as bar:
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
_COLUMNS_HEAD = ("scene", "width", "height", "method", "samples", "fetch", "radius", "normal_clamp",
                 "thickness", "layers", "falloff", "seed", "repeats", "seconds", "seconds_runs", "cpu_seconds",
                 "taps_per_pixel", "texels_per_pixel", "pixels", "quantity", "own_reference")
_COLUMNS_TAIL = ("references", "rays", "volume_samples", "screen_samples", "reference_seed", "camera")


def _rows(results) -> tuple[list[dict], list[str]]:
    rows = []
    for i, r in enumerate(results):
        if not isinstance(r, SweepResult):
            raise ValueError(f"results[{i}] must be a SweepResult, got {type(r).__name__}")
        rows.append(r.as_row())
    # the order of as_row, with every reference's and the decomposition's columns in place
    # even when the first rows lack them
    present = {k for row in rows for k in row}
    canonical = list(_COLUMNS_HEAD)
    canonical += [f"{stat}_{ref}" for ref in _references.names() for stat in ERROR_STATS]
    canonical += [f"{term}_{stat}" for term in DECOMPOSITION_TERMS for stat in ("rmse", "bias", "mae")]
    canonical += ["decomposition_target", *_COLUMNS_TAIL]
    columns = [k for k in canonical if k in present]
    for row in rows:
        columns.extend(k for k in row if k not in columns)
    return rows, columns


def results_to_csv(results, path):
    """Write the results as CSV (one row per configuration, :meth:`SweepResult.as_row`),
    atomically. Columns are the union over the rows (a reference one row did not ask for is
    left empty); floats are written exactly (``repr``), booleans as 0 / 1. Returns the path."""
    from .common import write_csv

    rows, columns = _rows(results)
    return write_csv(path, rows, columns)


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
    from .common import cell, markdown_table

    rows, columns = _rows(results)
    if not rows:
        text = "(no results)\n"
    else:
        skip = {"seconds_runs", "camera"}
        common = [k for k in columns if k not in skip and len(rows) > 1
                  and all(k in r for r in rows) and len({cell(r[k]) for r in rows}) == 1]
        shown = [k for k in columns if k not in skip and k not in common]
        lines = []
        if common:
            lines.append("Common settings: " + ", ".join(f"{k} = {cell(rows[0][k]) or 'none'}" for k in common) + ".")
            lines.append("")
        lines.append(markdown_table(rows, shown))
        text = "\n".join(lines) + "\n"
    if path is not None:
        write_text(path, text)
    return text
