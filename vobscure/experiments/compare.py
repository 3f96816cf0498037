"""``vobscure compare``: which estimator, with how many samples, gives what accuracy at what
cost on one scene -- answered in words and numbers.

A comparison is a list of :class:`~vobscure.experiments.SweepConfig` (method x samples x
radius, from the method registry :mod:`vobscure.methods`) run by
:func:`~vobscure.experiments.sweep` one after another in this process (timings do not share
the machine): the G-buffer is rendered once, the references a request names (from the registry
:mod:`vobscure.references`) are computed once per radius (and cached on disk,
:mod:`vobscure.experiments.cache`), every configuration is timed (median of ``repeats`` after
a warm-up) and its error measured against every reference, and split into the steps that cause
it (:func:`vobscure.metrics.decompose`): sampling (estimate vs the converged screen-space VO),
screen space (that vs the world-space VO) and model (world-space VO vs AO).

Each method is scored against the reference of *its own quantity* (registry: the VO
estimators against the world-space VO of the ball or half-ball); numbers against a reference of
another quantity (a VO estimator against ray-cast AO) are reported as model error, never as
the method's accuracy. :func:`verdict` turns the rows into the answer: per reference the
Pareto front in time and in taps, the cheapest configuration that meets a target RMSE or the
best that fits a time budget, which error term dominates and what measurably reduces it (for
the screen-space term, the thickness model is tried at a few thicknesses), and the error in the
thin-feature band (:func:`vobscure.metrics.thin_feature_mask`: just behind silhouettes, where
halos live) beside the whole frame's (the verdict's text is :mod:`vobscure.experiments.verdict`).
With ``thickness="layers"`` the G-buffer is depth-peeled to ``layers`` surfaces a pixel and
the methods whose registry entry reads layers (:attr:`vobscure.methods.Method.thickness_kinds`)
take their thickness from its solid intervals; the verdict says which did.

Outputs (written into ``out`` as one set that replaces the previous run's as a whole,
:func:`vobscure._io.file_set`): ``results.csv``, ``results.md`` (verdict, then
the table), ``summary.json`` (the verdict as data), ``tradeoff.png`` (error against time, taps
and texels per pixel, one curve per method, the Pareto front marked), ``gallery.png`` (each
estimate beside the references and its error map) and ``provenance.json``. With ``orbit`` > 1,
a camera orbit of that many frames also measures temporal stability
(:func:`vobscure.metrics.flicker`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import methods as _methods
from .._io import check_writable_dir, file_set
from .. import references as _references
from .._validate import check_choice, check_int, check_positive
from .common import (choose_radius, machine, markdown_table, new_figure, save_figure, write_csv, write_json,
                     write_text)
from .cache import open_cache
from .sweeps import DEFAULT_LAYERS, REFERENCES, InlineExecutor, SweepConfig, check_thickness, sweep
from .verdict import POOR_RMSE, SUGGEST_MIN_GAIN, TARGET_FACTOR, layers_sentence, pareto_front, thin_sentence, verdict

__all__ = ["compare", "CompareResult", "verdict", "report_text", "pareto_front", "orbit_cameras", "parse_methods",
           "missing_note", "panel_reference",
           "DEFAULT_METHODS", "DEFAULT_REFERENCES", "DEFAULT_LAYERS", "REFERENCES", "TARGET_FACTOR", "POOR_RMSE",
           "SUGGEST_THICKNESS", "SUGGEST_MIN_GAIN"]

#: The paper's Table 1 configurations (Loos & Sloan 2010): points 12 and 33, lines 5 and 9, area 1.
DEFAULT_METHODS = "point:12,point:33,line:5,line:9,area:1"
DEFAULT_REFERENCES = ("screen", "volumetric", "ao")
#: Added to the default methods on a vegetation scene: the models of Hegeman et al. 2006.
VEGETATION_METHODS = "hegeman,hegeman_ellipsoid,hegeman_multishell,reeves_blau,poisson"
#: Sizes of the default and the quick run.
DEFAULT_SIZE = (256, 256)
QUICK_SIZE = (64, 64)
#: Metrics kept per reference (fields of :class:`~vobscure.metrics.ErrorReport`; flip: the mean FLIP).
METRICS = ("rmse", "mae", "bias", "ssim", "flip")
#: Thicknesses (fractions of the radius) tried when the screen-space error dominates.
SUGGEST_THICKNESS = (0.25, 0.5, 1.0, 2.0)

parse_methods = _methods.parse


def orbit_cameras(camera, frames: int, *, degrees: float = 10.0):
    """``frames`` cameras turning about the vertical axis through the target, ``degrees`` in all
    (centred on ``camera``; :func:`vobscure.temporal.orbit_camera`)."""
    from ..temporal import orbit_camera

    return [orbit_camera(camera, a) for a in np.linspace(-0.5, 0.5, frames) * degrees]


class Stages:
    """The seconds of each stage of a comparison, in the order they ran, for the printout and
    ``provenance.json``: the view, each reference per radius (computed, read from the cache or
    reused), the G-buffer's depth-peeled layers (with ``thickness="layers"``), the methods' runs
    (warm-up and timed repeats), the orbit and the thickness trials."""

    def __init__(self):
        self._records: dict[str, dict] = {}

    def add(self, name: str, seconds: float, status: str) -> None:
        rec = self._records.setdefault(name, dict(stage=name, seconds=0.0, status=status))
        rec["seconds"] += float(seconds)
        # one computation makes a stage computed; else read from the cache; else reused
        order = ("computed", "cached", "reused")
        rec["status"] = min(rec["status"], status, key=order.index)

    def add_sweep(self, results) -> None:
        """The stages of :class:`~vobscure.experiments.SweepResult.stage_seconds`, summed over the
        results (a reused or cached stage costs nothing)."""
        radii = {res.radius for res in results}
        for res in results:
            for key, seconds in res.stage_seconds.items():
                status = res.stage_status.get(key, "computed")
                if key == "method":
                    name = "methods"
                elif key.startswith("reference:"):
                    name = f"reference {key.split(':', 1)[1]}" + (f" (R = {res.radius:.4g})" if len(radii) > 1 else "")
                elif key == "gbuffer":
                    if res.config.layers is None:
                        continue      # rendered with the view, before the sweep
                    name = f"G-buffer with {res.config.layers} layers"     # depth peeling for thickness='layers'

                else:
                    name = key
                self.add(name, seconds, status)

    @property
    def records(self) -> list[dict]:
        return [dict(r) for r in self._records.values()]

    @staticmethod
    def describe(record: dict) -> str:
        """``"reference screen 12.3 s"``, with the status when it is not "computed".

        Examples
        --------
        >>> Stages.describe(dict(stage="reference ao", seconds=0.01, status="cached"))
        'reference ao 0.0 s (cached)'
        """
        status = "" if record["status"] == "computed" else f" ({record['status']})"
        return f"{record['stage']} {record['seconds']:.1f} s{status}"


@dataclass
class CompareResult:
    """What :func:`compare` measured: one row per configuration, the verdict, and the files.

    Attributes
    ----------
    rows : list of dict
        One per configuration (see :func:`compare`).
    summary : dict
        :func:`verdict` of the rows: ``text`` (the answer in sentences) and its numbers.
    files : dict of str to Path
    provenance : dict
    references : dict
        radius -> {reference name: (H, W) array}.
    images : dict
        (radius, label) -> (H, W) estimate.
    """

    rows: list
    summary: dict
    files: dict
    provenance: dict
    references: dict = field(repr=False, default_factory=dict)
    images: dict = field(repr=False, default_factory=dict)


def _names(items, limit: int = 6) -> str:
    items = list(items)
    shown = ", ".join(items[:limit])
    return shown + (f" and {len(items) - limit} more" if len(items) > limit else "")


def missing_note(missing: dict, scene, thickness=None) -> str:
    """The verdict's sentences on the references that could not be computed on the scene and
    what scores their quantity instead (``missing``: name -> stand-in or None; ``thickness``:
    the comparison's, None when it has none; with ``"layers"`` the shell has its default thickness).

    Examples
    --------
    >>> import vobscure as vo
    >>> print(missing_note({"volumetric": None}, vo.scenes.leaf_cloud()))  # doctest: +ELLIPSIS
    No 'volumetric' reference: it tells solid from empty space by an inside test, which needs closed meshes, and 1 of 1 mesh(es) are open or alpha-tested with holes (leaves).
    """
    bad = scene.open_meshes
    parts = []
    for name, stand in missing.items():
        why = (f"No {name!r} reference: it tells solid from empty space by an inside test, which needs closed "
               f"meshes, and {len(bad)} of {len(scene.meshes)} mesh(es) are open or alpha-tested with holes "
               f"({_names(bad)}).")
        if stand == "shell":
            t = (f"{_references.SHELL_THICKNESS:g} x the radius thick behind them (a numeric --thickness sets it)"
                 if thickness is None or thickness == "layers" else f"{thickness:.4g} thick behind them (--thickness)")
            why += (f" The VO estimators are scored against 'shell' instead: the ray-cast VO of surfaces {t}, "
                    f"the thickness model applied across every surface, hidden and off-screen ones included "
                    f"(docs/groundtruth.md); no thickness trials are run against it, since its thickness is "
                    f"that choice. --allow-open computes {name!r} anyway, with an inside test that may be wrong "
                    f"near the holes.")
        elif stand:
            why += f" Its quantity is scored against {stand!r} instead."
        parts.append(why)
    return " ".join(parts)


def _row(result, metrics=METRICS) -> dict:
    """A compare row from a sweep result: configuration, cost, error against every reference,
    the method's own reference, and the decomposition."""
    c = result.config
    layered = c.method_thickness == "layers"
    row = dict(method=c.method, samples=c.samples, label=c.label, radius=result.radius,
               normal_clamp=c.normal_clamp, thickness=c.method_thickness, layers=c.layers if layered else 0,
               seconds=result.seconds,
               taps_per_pixel=result.taps_per_pixel, texels_per_pixel=result.texels_per_pixel,
               quantity=c.quantity, reference_only=_methods.get(c.method).reference_only)
    for name, rep in result.errors.items():
        for metric in metrics:
            row[f"{name}_{metric}"] = float(getattr(rep, metric))
    own = c.own_reference if c.own_reference in result.errors else _references.get(c.own_reference).stand_in
    own = own if own in result.errors else None
    if own is None and "screen" in result.errors and _methods.QUANTITIES[c.quantity].screen_limit:
        own = "screen"
    row["own_reference"] = own
    row["own_rmse"] = row[f"{own}_rmse"] if own else float("nan")
    row["own_bias"] = row[f"{own}_bias"] if own else float("nan")
    # with layers the estimate's limit is not the single-depth screen-space VO: no split by cause
    if result.decomposition is not None and not layered:
        for term in ("sampling", "screen", "model", "total"):
            if f"{term}_rmse" in result.decomposition:
                row[f"{term}_error_rmse"] = result.decomposition[f"{term}_rmse"]
                row[f"{term}_error_bias"] = result.decomposition[f"{term}_bias"]
    return row


def compare(scene="cornell_box", *, name=None, camera=None, size=None, radii=None, methods=None,
            normal_clamp: bool = False, thickness=None, layers=None, references=None, repeats: int = 3,
            rays: int = 256, volume_samples: int = 1024,
            screen_samples: int = _references.SCREEN_SAMPLES, seed: int = 0,
            orbit: int = 0, target_rmse=None, budget_ms=None, suggest: bool = True, quick: bool = False,
            out=None, cache=True, progress: bool = False, plots: bool = True,
            write: bool = True, allow_open: bool = False, frames: int = 0, motion: str = "static",
            step=None, cameras=None, schedules="white", accumulate="mean", clamp: bool = False, reproject: bool = True,
            denoise=None) -> CompareResult:
    """Measure error, time and taps per pixel of screen-space estimators on one scene, and say
    which to use.

    Parameters
    ----------
    scene : str, path, Scene or GBuffer
        A built-in scene name, a mesh file, a :class:`vobscure.scenes.Scene`, or a user's
        :class:`~vobscure.GBuffer` (e.g. :func:`vobscure.io.read_gbuffer` of a renderer's
        frame): then the only reference is the converged screen-space VO (``"screen"``),
        the camera is the G-buffer's, and the default radius is 0.1 x the diagonal of its
        covered pixels' view-space bounding box.
    name : str, optional
        The name in the outputs for a G-buffer (default ``"gbuffer"``).
    camera : Camera, optional
        Default: the scene's suggested camera at ``size``.
    size : (int, int), optional
        (width, height); default 256 x 256 (64 x 64 with ``quick``).
    radii : sequence of float, optional
        Ball radii; default 0.1 x the scene's extent.
    methods : str or sequence, optional
        Configurations of the method registry, ``"NAME:SAMPLES[:FETCH]"`` comma-separated;
        default the paper's Table 1, ``"point:12,point:33,line:5,line:9,area:1"``, and on a
        vegetation scene (one whose ``metadata`` holds a canopy) also :data:`VEGETATION_METHODS`.
    normal_clamp : bool
        Half-ball VO (Loos & Sloan 2010, Sec. 4.4) for every estimator and VO reference.
    thickness : float or "layers", optional
        A number: the thickness model (Sec. 4.3) of every estimator that takes one and of the
        screen-space reference. ``"layers"``: the G-buffer is rendered with ``layers``
        depth-peeled layers (``render_gbuffer(..., layers=K)``, ``docs/layers.md``) and every
        method that takes ``thickness="layers"`` (:attr:`vobscure.methods.Method.thickness_kinds`:
        point, line, gtao, vbao) reads its solid intervals; the others run as without a
        thickness, the references too (``"screen"`` stays the single-depth converged VO), and
        the verdict says which ran with layers. A user's G-buffer reads its own
        ``gbuffer.intervals``.
    layers : int, optional
        The layers K >= 2 with ``thickness="layers"``; default
        :data:`~vobscure.experiments.sweeps.DEFAULT_LAYERS` (4). Only with ``"layers"``.
    references : sequence of str, optional
        Some of the registry :data:`vobscure.references.REFERENCES`; only these are computed.
        Default ``("screen", "volumetric", "ao")`` and the reference of every method's own
        quantity; on a scene that is not closed, a reference that needs one (``"volumetric"``:
        the world-space VO needs an inside test) is replaced by its stand-in (``"shell"``, the
        VO of surfaces a thickness thick), and the verdict says so, naming the open meshes; on
        a vegetation scene with ``"sky"`` (what the vegetation models estimate). The error
        decomposition needs "screen" and a world-space VO, "volumetric" or "shell" (its model
        term also "ao").
    repeats : int
        Timed runs per configuration; the median is kept.
    rays : int
        Rays per pixel of the ``ao`` and ``obscurance`` references.
    volume_samples : int
        Points per ball of the world-space VO (``volumetric`` and ``shell``).
    screen_samples : int
        View-ray segments per pixel of the converged screen-space VO (``screen``, :func:`vobscure.vo_reference`).
    seed : int
        Seed of the estimators and of every reference.
    orbit : int
        With N > 1, N frames of a 10-degree camera orbit measure the flicker of each
        configuration (minus the screen-space reference's own frame-to-frame change).
    target_rmse : float, optional
        The accuracy the verdict looks for (against each method's own reference); default
        :data:`TARGET_FACTOR` times the best configuration's error.
    budget_ms : float, optional
        A time budget per frame: the verdict names the most accurate configuration within it.
    suggest : bool
        When the screen-space term dominates, time the best configuration with the thickness
        model at :data:`SUGGEST_THICKNESS` times the radius and report what it gives (a few
        estimator calls: on by default).
    quick : bool
        64 x 64, one repeat, fewer rays and samples: the whole run in seconds.
    out : path, optional
        Output folder; default ``./vobscure-out/compare-<scene>``.
    cache : bool, path or ReferenceCache
        True: the default user cache folder; a path: that folder; False: no cache.
    progress : bool
        Progress bars (off by default, as everywhere in the library; the command turns them on).
    plots : bool
        Write the PNGs.
    write : bool
        False: write nothing at all (figure modules use the rows directly).
    allow_open : bool
        Compute ``"volumetric"`` on a scene that is not closed (an inside test that may be wrong
        near the holes) instead of replacing it by ``"shell"``.
    frames : int
        With N >= 2 (or ``cameras``), also the error after N frames
        (:func:`vobscure.experiments.temporal.run`, ``docs/temporal.md``): every configuration
        run per frame with its noise ``schedules`` and ``accumulate`` settings (all
        combinations), over the camera path ``motion`` (``"static"``, ``"orbit"``, ``"dolly"``)
        or ``cameras``, scored per frame against ``"screen"`` and its own reference at the first
        radius; the rows go to ``temporal.csv``, the curves to ``temporal.png``, the sentences to
        the verdict and ``summary["temporal"]`` lists ``{"config", "reference", "rmse"}``.
    motion, step, cameras, schedules, accumulate, clamp, reproject, denoise
        The sequence's camera path (``step``: per frame, :func:`vobscure.temporal.camera_path`), noise schedules (``"white"``, ``"rotate"``, ``"r2"``,
        ``"gtao"``, ``"blue"``; comma-separated or a list), accumulation settings (``"mean"``,
        ``"ema:ALPHA"``, ``"clip:ALPHA"``) and accumulator options
        (:class:`vobscure.temporal.Accumulator`); used only with ``frames``.

    Returns
    -------
    CompareResult
        ``rows`` hold per configuration ``method, samples, label, radius, normal_clamp,
        thickness, seconds, taps_per_pixel, texels_per_pixel, quantity``,
        ``<reference>_<metric>`` for every reference and metric of :data:`METRICS`,
        ``own_reference, own_rmse, own_bias`` (the reference of the method's own quantity),
        ``thickness`` (the one the method ran with: None when it does not take the kind given)
        and ``layers`` (K when it read the layers, 0 when not),
        ``own_thin_rmse, own_thin_bias, thin_pixels`` (the same in the thin-feature band,
        :func:`vobscure.metrics.thin_feature_mask` at the row's radius)
        and, with the screen and volumetric references, the decomposition
        ``<term>_error_rmse`` / ``_bias`` (not for a row with layers, whose limit is not the
        single-depth screen-space VO).

    Examples
    --------
    >>> import vobscure as vo, tempfile
    >>> res = vo.experiments.compare.compare("slab", size=(16, 16), methods="line:5", quick=True,
    ...                                      references=("screen",), cache=False, progress=False,
    ...                                      out=tempfile.mkdtemp(), plots=False)
    >>> r = res.rows[0]
    >>> r["method"], r["samples"], r["taps_per_pixel"], r["texels_per_pixel"], r["own_reference"]
    ('line', 5, 5, 5, 'screen')
    """
    from ..gbuffer import GBuffer
    from ..scenes import resolve

    frame = isinstance(scene, GBuffer)        # a user's frame: no geometry, no ray-cast reference
    if frame:
        sc, scene_name = scene, name or "gbuffer"
        if orbit:
            raise ValueError("orbit needs a scene to render from other viewpoints; a G-buffer is one view")
        if frames or cameras is not None:
            raise ValueError("frames needs a scene to render every frame's view; a G-buffer is one frame")
    else:
        sc, scene_name = resolve(scene)
    vegetation = "canopy_points" in (getattr(sc, "metadata", None) or {})
    if methods is None:
        methods = DEFAULT_METHODS + ("," + VEGETATION_METHODS if vegetation else "")
    configs = parse_methods(methods)
    allow_open = bool(allow_open)
    missing = {}          # a reference the scene cannot have -> what stands in for it
    if references is None and frame:
        references = ("screen",)
    elif references is None:
        wanted = DEFAULT_REFERENCES + (("sky",) if vegetation else ())
        # and the reference of every requested method's own quantity (e.g. uniform AO for HBAO)
        wanted += tuple(c.reference(normal_clamp) for c in configs)
        references = ()
        for name in dict.fromkeys(wanted):
            use = name if allow_open else _references.usable(name, sc)
            if use != name:
                missing[name] = use
            if use is not None and use not in references:
                references += (use,)
    references = tuple(references)
    if not references:
        raise ValueError("references must name at least one of " + ", ".join(_references.names()))
    for name in references:
        check_choice(name, "references", _references.names())
        if not frame and not allow_open and _references.usable(name, sc) != name:
            bad = sc.open_meshes
            stand = _references.get(name).stand_in
            raise ValueError(f"reference {name!r} needs closed meshes (an inside test), and {len(bad)} of "
                             f"{len(sc.meshes)} mesh(es) of {scene_name!r} are open ({_names(bad)}); use "
                             + (f"{stand!r} (defined for open surfaces, docs/groundtruth.md) or " if stand else "")
                             + "allow_open=True (--allow-open) to accept an inside test that may be wrong "
                               "near the holes")
    repeats = check_int(repeats, "repeats")
    orbit = check_int(orbit, "orbit", minimum=0) if orbit else 0
    frames = check_int(frames, "frames", minimum=0) if frames else 0
    if (frames or cameras is not None) and isinstance(thickness, str):
        raise ValueError("frames with thickness='layers' is not supported: the layered G-buffer is not rendered "
                         "per frame; give a number or no thickness")
    thickness, layers = check_thickness(thickness, layers, frame=sc if frame else None)
    if target_rmse is not None:
        target_rmse = check_positive(target_rmse, "target_rmse")
    if budget_ms is not None:
        budget_ms = check_positive(budget_ms, "budget_ms")
    if quick:
        repeats, rays = 1, min(rays, 64)
        volume_samples, screen_samples = min(volume_samples, 256), min(screen_samples, 512)
        orbit = min(orbit, 4) if orbit else 0
    camera_given = camera is not None
    if frame:
        camera = sc.camera
    elif camera is None:
        size = tuple(size) if size is not None else (QUICK_SIZE if quick else DEFAULT_SIZE)
        camera = sc.camera(size)
    from ..render import render_gbuffer
    from ..scenes.viewpoint import view_diagnostics, view_warnings
    from .._memory import compare_need, count_items, require

    # the whole job's estimated peak, refused before any work when it cannot fit
    n_frames = (len(cameras) if cameras is not None else frames) if frames > 1 or cameras is not None else 0
    kinds = ["screen" if _references.get(r).ground_truth is None else _references.get(r).ground_truth
             for r in references]
    require(compare_need(references=kinds, configs=len(configs),
                         layers=(layers or 1) if thickness == "layers" and not frame else 1, radii=1 if radii is None else len(np.atleast_1d(radii)), frames=n_frames,
                         frame_configs=len(configs) * count_items(schedules) * count_items(accumulate),
                         orbit=orbit, plots=write and plots, pixels=camera.width * camera.height),
            size=camera.size, what=f"comparing on a {camera.width} x {camera.height} image",
            reduce="size (--size), the references, methods, radii or frames")
    t_view = time.perf_counter()
    view_gb = sc if frame else render_gbuffer(sc, camera)     # a frame is its own view
    if not view_gb.valid.any():
        raise ValueError(f"the camera sees none of {scene_name!r}: no pixel of the {camera.width} x {camera.height} "
                         f"image is covered, so there is nothing to score; aim it at the scene (--eye, --target, "
                         f"--camera, or leave the default view)")
    view_facts = view_diagnostics(view_gb, scene=None if frame else sc)
    view_facts["chosen_by"] = ("the frame" if frame else "the caller" if camera_given
                               else "the scene's own view" if getattr(sc, "_view", None) is not None
                               else "vobscure.scenes.viewpoint.suggest_view (the scene holds no camera)")
    radius_choice = None
    if radii is None:   # the rule, capped for this camera's view
        radius_choice = choose_radius(sc, view_gb)
        radii = (radius_choice.radius,)
    radii = tuple(check_positive(r, "radius") for r in np.atleast_1d(radii))
    store = open_cache(cache)
    out = Path(out) if out is not None else Path("vobscure-out") / f"compare-{scene_name}"
    if write:
        check_writable_dir(out, "out")   # before the work, not after it

    t_start = time.perf_counter()
    stages = Stages()
    stages.add("view (G-buffer, radius)", t_start - t_view, "computed")
    common = dict(scene=sc, camera=camera, normal_clamp=normal_clamp, thickness=thickness, layers=layers, seed=seed,
                  references=references, rays=rays, volume_samples=volume_samples,
                  screen_samples=screen_samples, reference_seed=seed, allow_open=allow_open)
    sweep_configs = [SweepConfig(method=c.method, samples=c.samples, fetch=c.fetch, radius=radius,
                                 repeats=repeats, **common) for radius in radii for c in configs]
    results = sweep(sweep_configs, executor=InlineExecutor(), cache=store, keep_images=True,
                    progress=progress)
    rows, images, all_refs, hits = [], {}, {}, {}
    for res in results:
        rows.append(_row(res))
        images[(res.radius, res.config.label)] = res.image
        all_refs.setdefault(res.radius, {k: v.value for k, v in res.references.items()})
        hits.setdefault(res.radius, res.cache_hits)
    gb = results[0].gbuffer
    thin_band = _thin_band(rows, images, all_refs, gb)
    stages.add_sweep(results)
    if orbit > 1:
        t0 = time.perf_counter()
        _orbit(sc, camera, rows, configs, radii, orbit, normal_clamp=normal_clamp, thickness=thickness, layers=layers,
               screen_samples=screen_samples, seed=seed, cache=store, progress=progress)
        stages.add(f"orbit ({orbit} frames)", time.perf_counter() - t0, "computed")
    thickness_trials = []
    t0 = time.perf_counter()
    if suggest and thickness is None and "volumetric" in references:
        thickness_trials = _thickness_trials(rows, images, all_refs, gb, normal_clamp=normal_clamp,
                                             seed=seed, repeats=repeats)
    if thickness_trials:
        stages.add("thickness trials", time.perf_counter() - t0, "computed")
    summary = verdict(rows, target_rmse=target_rmse, budget_ms=budget_ms, thickness_trials=thickness_trials)
    sequence = None
    if frames > 1 or cameras is not None:
        from . import temporal as _temporal

        t0 = time.perf_counter()
        tconfigs = _temporal.configurations(configs, schedules=schedules, accumulate=accumulate, clamp=clamp,
                                            reproject=reproject, denoise=denoise)
        sequence = _temporal.run(sc, tconfigs, camera=camera, frames=frames if frames > 1 else None,
                                 motion=motion, step=step, cameras=cameras, radius=radii[0],
                                 references=tuple(r for r in references if r == "screen" or r in
                                                  {c.reference(normal_clamp) for c in configs} | set(missing.values())),
                                 normal_clamp=normal_clamp, thickness=thickness, rays=rays,
                                 screen_samples=screen_samples, volume_samples=volume_samples, seed=seed,
                                 target_rmse=target_rmse, cache=store, progress=progress, allow_open=allow_open)
        stages.add(f"frames ({len(sequence.cameras)} x {len(tconfigs)} configurations)",
                   time.perf_counter() - t0, "computed")
        summary["temporal"] = sequence.series
        summary["temporal_verdict"] = {k: v for k, v in sequence.summary.items() if k != "text"}
        summary["text"] += sequence.summary["text"]
    summary["thin_band"] = thin_band
    summary["text"] += [thin_sentence(band, rows) for band in thin_band if band["pixels"]]
    if thickness == "layers":
        summary["text"].append(layers_sentence(rows, layers))
    summary["layers"] = None if thickness != "layers" else dict(
        layers=layers, slots=int(gb.intervals.count),
        with_layers=list(dict.fromkeys(r["label"] for r in rows if r["thickness"] == "layers")),
        without_layers=list(dict.fromkeys(r["label"] for r in rows if r["thickness"] != "layers")))
    if missing:
        summary["text"].insert(0, missing_note(missing, sc, thickness))
    summary["missing_references"] = {k: dict(stand_in=v, open_meshes=list(sc.open_meshes)) for k, v in missing.items()}
    if frame:
        summary["text"].insert(0, "A G-buffer without its scene: the converged screen-space VO is the only "
                                  "reference possible (nothing can be ray cast), so these errors are the "
                                  "estimators' sampling errors; what the screen-space model itself misses "
                                  "(thickness, hidden and off-screen geometry) cannot be measured here.")
    summary["text"] += [radius_choice.sentence()] if radius_choice is not None else []
    summary["view_warnings"] = view_warnings(view_facts)
    summary["text"][:0] = summary["view_warnings"]

    provenance = dict(
        command="vobscure compare", scene=scene_name, camera=camera.to_dict(), radii=list(radii),
        radius_rule=radius_choice.to_dict() if radius_choice is not None else None,
        view={k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in view_facts.items()},
        methods=[c.label for c in configs], normal_clamp=bool(normal_clamp), thickness=thickness, layers=layers,
        references=list(references), missing_references=dict(missing), allow_open=allow_open,
        shell_thickness=({f"{r:g}": (_references.SHELL_THICKNESS * r if thickness in (None, "layers") else thickness)
                          for r in radii} if "shell" in references else None),
        repeats=repeats, rays=rays, volume_samples=volume_samples,
        screen_samples=screen_samples, seed=seed, orbit=orbit, quick=bool(quick),
        temporal=None if sequence is None else dict(
            frames=len(sequence.cameras), motion="list" if cameras is not None else motion,
            cameras=sequence.cameras, schedules=schedules, accumulate=accumulate, clamp=bool(clamp),
            reproject=bool(reproject), denoise=denoise),
        target_rmse=target_rmse, budget_ms=budget_ms,
        cache=None if not store.enabled else str(store.directory),
        cache_hits={f"{r:g}": h for r, h in hits.items()}, stages=stages.records,
        seconds=time.perf_counter() - t_view,
        machine=machine(), date=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    files = _write(out, rows, summary, provenance, all_refs, images, gb, plots, sequence) if write else {}
    return CompareResult(rows=rows, summary=summary, files=files, provenance=provenance,
                         references=all_refs, images=images)


def _orbit(sc, camera, rows, configs, radii, frames, *, normal_clamp, thickness, layers, screen_samples, seed,
           cache, progress):
    """Add ``flicker`` (estimate minus reference), ``flicker_raw`` and ``flicker_flip`` (FLIP of
    each frame against the previous one) to every row: the same configurations over an orbit of
    cameras, measured (not timed) by the sweep."""
    from ..metrics import flicker

    cams = orbit_cameras(camera, frames)
    sweep_configs = [SweepConfig(scene=sc, camera=cam, method=c.method, samples=c.samples, fetch=c.fetch,
                                 radius=r, normal_clamp=normal_clamp, thickness=thickness, layers=layers, seed=seed,
                                 repeats=0, references=("screen",), screen_samples=screen_samples,
                                 reference_seed=seed)
                     for cam in cams for r in radii for c in configs]
    results = sweep(sweep_configs, executor=InlineExecutor(), cache=cache, keep_images=True, progress=progress)
    seq, refs = {}, {}
    for res in results:
        key = (res.radius, res.config.label)
        seq.setdefault(key, []).append(res.image)
        refs.setdefault(key, []).append(res.references["screen"].value)
    for row in rows:
        key = (row["radius"], row["label"])
        f = flicker(np.stack(seq[key]), np.stack(refs[key]))
        row["flicker"] = float(f.value)
        row["flicker_raw"] = float(f.estimate_change)
        row["flicker_flip"] = float(f.estimate_flip)     # FLIP of each frame against the one before


def _thickness_trials(rows, images, refs, gb, *, normal_clamp, seed, repeats) -> list[dict]:
    """The most accurate shippable configuration at the first radius, re-run with the thickness
    model at :data:`SUGGEST_THICKNESS` x radius, against the world-space VO."""
    from ..metrics import error
    from .common import time_calls

    radius = rows[0]["radius"]
    cands = [r for r in rows if r["radius"] == radius and not r["reference_only"]
             and _methods.QUANTITIES[r["quantity"]].screen_limit      # the thickness model is VO's
             and np.isfinite(r.get("volumetric_rmse", np.nan))]
    if not cands:
        return []
    best = min(cands, key=lambda r: r["volumetric_rmse"])
    config = _methods.parse([best["label"]])[0]
    truth = refs[radius]["volumetric"]
    trials = []
    for factor in SUGGEST_THICKNESS:
        t = factor * radius
        timings, values = time_calls({"run": lambda: config.run(gb, radius=radius, normal_clamp=normal_clamp,
                                                                 thickness=t, seed=seed)}, max(1, repeats))
        rep = error(values["run"], truth)
        trials.append(dict(label=best["label"], radius=radius, factor=factor, thickness=t,
                           volumetric_rmse=rep.rmse, volumetric_bias=rep.bias, seconds=timings["run"].median,
                           baseline_rmse=best["volumetric_rmse"]))
    return trials


def _thin_band(rows, images, all_refs, gb) -> list:
    """Add ``own_thin_rmse``, ``own_thin_bias`` (against the row's own reference, in the
    thin-feature band of :func:`vobscure.metrics.thin_feature_mask` at the row's radius) and
    ``thin_pixels`` to every row; per radius the band's size."""
    from ..metrics import error, thin_feature_mask

    bands = []
    for radius, refs in all_refs.items():
        mask = thin_feature_mask(gb, radius=radius)
        covered = int(np.count_nonzero(gb.inner().valid))
        bands.append(dict(radius=radius, pixels=int(mask.sum()), fraction=float(mask.sum() / max(covered, 1))))
        for row in (r for r in rows if r["radius"] == radius):
            rep = error(images[(radius, row["label"])], refs[row["own_reference"]], mask=mask) \
                if row["own_reference"] in refs else None
            row["own_thin_rmse"] = rep.rmse if rep else float("nan")
            row["own_thin_bias"] = rep.bias if rep else float("nan")
            row["thin_pixels"] = rep.pixels if rep else 0
    return bands


# --------------------------------------------------------------------------- writing
def _markdown(rows, summary, provenance) -> str:
    w, h = provenance["camera"]["size"]
    cols = ["label", "quantity", "radius", "seconds", "taps_per_pixel", "texels_per_pixel", "own_reference",
            "own_rmse", "own_bias", "own_thin_rmse"]
    refs = provenance["references"]
    cols += [f"{ref}_{m}" for ref in refs for m in METRICS]
    cols += [c for c in ("sampling_error_rmse", "screen_error_rmse", "model_error_rmse", "total_error_rmse",
                         "flicker") if any(c in r for r in rows)]
    headers = {}
    own = {r["own_reference"] for r in rows}
    for ref in refs:
        if ref not in own and ref != "screen":
            for m in METRICS:
                headers[f"{ref}_{m}"] = f"{ref}_{m} (model error)"
    thick = provenance["thickness"]
    if thick == "layers":
        cols[1:1] = ["thickness", "layers"]
        thick = (f"layers (K = {provenance['layers']}; `layers` 0: the method takes none and ran without)"
                 if provenance["layers"] is not None else "layers (the G-buffer's own intervals)")
    else:
        thick = "none" if thick is None else f"{thick:.4g}"
    lines = [f"# vobscure compare: {provenance['scene']}", "", "## Verdict", ""]
    lines += [f"- {s}" for s in summary["text"]] or ["- (no configuration could be scored)"]
    lines += ["", "## Measurements", "",
              f"Camera {w} x {h}, normal clamp: {'yes' if provenance['normal_clamp'] else 'no'}, thickness: "
              f"{thick}, median of {provenance['repeats']} run(s), seed {provenance['seed']}. Each row is "
              f"scored against the reference of its own quantity (`own_reference`); columns against a "
              f"reference of another quantity are marked *model error*. `<term>_error_rmse` split the error "
              f"into sampling + screen space + model.", "",
              markdown_table(rows, cols, headers=headers), ""]
    if summary.get("thickness"):
        lines += ["## Thickness trials", "",
                  markdown_table(summary["thickness"]["trials"],
                                 ["label", "factor", "thickness", "volumetric_rmse", "volumetric_bias", "seconds"]), ""]
    mach = provenance["machine"]
    lines += ["Machine: " + ", ".join(f"{k} {v}" for k, v in mach.items()) + ".", ""]
    return "\n".join(lines)


def _write(out: Path, rows, summary, provenance, refs, images, gb, plots, sequence=None) -> dict:
    """Write the run's files as one set (:func:`vobscure._io.file_set`): they replace the
    previous run's set in ``out`` as a whole, or, when the run is interrupted, not at all."""
    with file_set(out, "compare") as stage:
        names = [write_csv(stage / "results.csv", rows).name,
                 write_text(stage / "results.md", _markdown(rows, summary, provenance)).name,
                 write_json(stage / "summary.json", summary).name]
        if sequence is not None:
            names.append(write_csv(stage / "temporal.csv", sequence.rows).name)
        if plots:
            names.append(_tradeoff(stage / "tradeoff.png", rows, provenance).name)
            names.append(_gallery(stage / "gallery.png", rows, refs, images, gb).name)
            if sequence is not None:
                from .temporal import plot as plot_temporal

                names.append(plot_temporal(stage / "temporal.png", sequence).name)
        names.append(write_json(stage / "provenance.json", provenance).name)
    return {name: out / name for name in names}


_METHOD_COLORS = ("#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22")
_RADIUS_MARKERS = "os^Dv<>"


def _tradeoff(path, rows, provenance):
    from matplotlib.ticker import LogLocator, NullFormatter

    refs = list(provenance["references"])
    costs = (("seconds", "median seconds per frame"), ("taps_per_pixel", "depth taps per pixel"),
             ("texels_per_pixel", "depth texels read per pixel"))
    fig = new_figure(4.2 * len(costs), 3.2 * len(refs) + 0.6)
    axes = fig.subplots(len(refs), len(costs), squeeze=False)
    radii = sorted({row["radius"] for row in rows})
    names = list(dict.fromkeys(row["method"] for row in rows))
    for i, ref in enumerate(refs):
        for j, (cost, label) in enumerate(costs):
            ax = axes[i, j]
            x = np.array([row[cost] for row in rows], float)
            y = np.array([row[f"{ref}_rmse"] for row in rows], float)
            for n_m, name in enumerate(names):
                for k, radius in enumerate(radii):
                    sel = [n for n, row in enumerate(rows) if row["method"] == name and row["radius"] == radius]
                    if not sel:
                        continue
                    sel = sorted(sel, key=lambda n: rows[n]["samples"])
                    ax.plot(x[sel], y[sel], "-", marker=_RADIUS_MARKERS[k % len(_RADIUS_MARKERS)],
                            color=_METHOD_COLORS[n_m % len(_METHOD_COLORS)], label=f"{name} (R={radius:.3g})")
                    for n in sel:
                        ax.annotate(str(rows[n]["samples"]), (x[n], y[n]), textcoords="offset points",
                                    xytext=(3, 3), fontsize=7)
            front = pareto_front(x, y)
            if len(front):
                ax.step(x[front], y[front], where="post", color="k", lw=1, ls="--", alpha=0.7,
                        label="Pareto front")
                ax.scatter(x[front], y[front], s=90, facecolors="none", edgecolors="k", zorder=3)
            ax.set_xscale("log")
            ax.xaxis.set_minor_locator(LogLocator(subs="auto"))
            ax.xaxis.set_minor_formatter(NullFormatter())  # unlabelled minor ticks never overlap
            ax.set_xlabel(label)
            own = any(row["own_reference"] == ref for row in rows)
            ax.set_ylabel(f"RMSE vs {ref}" + (" (sampling error)" if ref == "screen" and not own else
                                              "" if own else " (model error)"))
            ax.grid(alpha=0.3)
            if i == 0 and j == 0:
                ax.legend(fontsize=7)
    fig.suptitle(f"{provenance['scene']}: error against cost (labels: samples)")
    return save_figure(fig, path)


def panel_reference(row, available) -> tuple[str, bool]:
    """The reference a gallery panel of ``row`` is scored against, the one the verdict scores it
    against: its own quantity's (``own_reference``), else the first available in registry order;
    and whether that is its own (False: the difference is model error, and the title says so)."""
    own = row.get("own_reference")
    if own in available:
        return own, True
    return next(n for n in _references.names() if n in available), False


def _gallery(path, rows, refs, images, gb):
    radius = rows[0]["radius"]
    ref_imgs = refs[radius]
    configs = [row for row in rows if row["radius"] == radius]
    ncol = max(len(ref_imgs), 4)
    per_row = max(ncol // 2, 1)
    nrow = 1 + math.ceil(len(configs) / per_row)
    fig = new_figure(2.2 * ncol, 2.3 * nrow)
    axes = fig.subplots(nrow, ncol, squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    bg = ~gb.valid
    for k, (name, img) in enumerate(ref_imgs.items()):
        axes[0, k].imshow(np.ma.masked_where(bg, img), cmap="gray", vmin=0, vmax=1)
        axes[0, k].set_title(f"reference: {name}", fontsize=8)
    if len(ref_imgs) < ncol:      # the thin-feature band the verdict scores separately
        from ..metrics import thin_feature_mask

        axes[0, len(ref_imgs)].imshow(np.where(bg, 0.5, thin_feature_mask(gb, radius=radius)), cmap="gray_r", vmin=0, vmax=1)
        axes[0, len(ref_imgs)].set_title("thin-feature band", fontsize=8)
    for n, row in enumerate(configs):
        r, c = 1 + n // per_row, 2 * (n % per_row)
        label = row["label"]
        est = images[(radius, label)]
        against, own = panel_reference(row, ref_imgs)
        diff = est - ref_imgs[against]
        rmse = float(np.sqrt(np.nanmean(diff ** 2))) if np.isfinite(diff).any() else float("nan")
        axes[r, c].imshow(np.ma.masked_where(bg, est), cmap="gray", vmin=0, vmax=1)
        axes[r, c].set_title(label, fontsize=8)
        lim = max(float(np.nanmax(np.abs(diff))) if np.isfinite(diff).any() else 0.0, 1e-6)
        axes[r, c + 1].imshow(np.ma.masked_where(bg, diff), cmap="RdBu_r", vmin=-lim, vmax=lim)
        axes[r, c + 1].set_title(f"vs {against}{'' if own else ' (model error)'}: RMSE {rmse:.3f}", fontsize=8)
    fig.suptitle(f"R = {radius:.3g}: estimates and their error against their own reference (red: too open)")
    return save_figure(fig, path)


def report_text(result: CompareResult) -> str:
    """The verdict and the files, as printed by ``vobscure compare``."""
    lines = [f"{result.provenance['scene']}: {len(result.rows)} configurations in "
             f"{result.provenance['seconds']:.1f} s.", ""]
    if result.provenance.get("stages"):
        lines += ["Time per stage: " + "; ".join(Stages.describe(r) for r in result.provenance["stages"]) + ".", ""]
    lines += [f"* {s}" for s in result.summary["text"]]
    lines.append("")
    lines += [f"wrote {p}" for p in result.files.values()]
    return "\n".join(lines)

