"""The error after N frames: estimators run per frame, accumulated, and scored per frame.

An engine runs a screen-space estimator with few samples per frame, varies its noise per frame
(:mod:`vobscure.screenspace.noise`) and accumulates the frames
(:class:`vobscure.temporal.Accumulator`). :func:`run` measures that: for every configuration
(method and samples, noise schedule, accumulation) over a camera path, per frame n = 1..N, the
error of the accumulated image against that frame's references (the converged screen-space VO,
whose distance is the sampling error, and the ray-cast reference of the method's own quantity),
its flicker (:func:`vobscure.metrics.flicker` of the frame pair), and the time per frame.
:func:`vobscure.experiments.compare.compare` calls it with ``frames=N`` (``vobscure compare
--frames N``) and writes ``temporal.csv``, ``temporal.png`` and the verdict's sentences.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field

import numpy as np

from .. import methods as _methods
from .. import references as _references
from .._validate import check_bool, check_choice, check_int, check_positive
from ..temporal import AccumulateSpec, Accumulator, camera_path, parse_accumulate
from .common import new_figure, progress_bar, save_figure
from .verdict import POOR_RMSE, TARGET_FACTOR

__all__ = ["TemporalConfig", "TemporalResult", "configurations", "run", "frames_to_target", "temporal_verdict",
           "plot", "VERDICT_FRAMES", "TIME_TIE"]

#: The frame after which the verdict compares the configurations (or the last frame, when fewer).
VERDICT_FRAMES = 8
#: Times per frame within this fraction of the least count as equal in the verdict: on 2 shared
#: cores one frame's time moves by about that much from run to run (docs/temporal.md).
TIME_TIE = 0.15


@dataclass(frozen=True)
class TemporalConfig:
    """One configuration of a sequence: a method configuration of the registry, the noise schedule
    of its frames, the accumulation, and the accumulator's options.

    Examples
    --------
    >>> c = configurations("gtao:2", schedules="r2", accumulate="ema:0.1")[0]
    >>> c.label
    'gtao:2 r2 ema:0.1'
    """

    method: _methods.Config
    schedule: str = "white"
    accumulate: AccumulateSpec = field(default_factory=lambda: AccumulateSpec("mean"))
    clamp: bool = False
    reproject: bool = True
    denoise: str | None = None

    @property
    def label(self) -> str:
        parts = [self.method.label, self.schedule, self.accumulate.label]
        parts += ["clamp"] if self.clamp else []
        parts += [] if self.reproject else ["in-place"]
        parts += [f"blur-{self.denoise}"] if self.denoise else []
        return " ".join(parts)

    def accumulator(self) -> Accumulator:
        return Accumulator(self.accumulate, clamp=self.clamp, reproject=self.reproject, denoise=self.denoise)


def _as_list(value, name: str) -> list:
    if isinstance(value, str):
        return [v.strip() for v in value.split(",") if v.strip()]
    if value is None or not hasattr(value, "__iter__"):
        raise ValueError(f"{name} must be a string or a sequence, got {value!r}")
    return list(value)


def configurations(methods, *, schedules="white", accumulate="mean", clamp: bool = False, reproject: bool = True,
                   denoise=None) -> tuple[TemporalConfig, ...]:
    """Every combination of ``methods`` (registry configurations, ``"NAME:SAMPLES[:FETCH]"``,
    comma-separated), ``schedules`` and ``accumulate`` settings (each a comma-separated string or
    a sequence), with the same accumulator options."""
    from ..screenspace.noise import SCHEDULES
    from ..temporal import DENOISE_STEPS

    configs = _methods.parse(methods)
    scheds = _as_list(schedules, "schedules")
    for s in scheds:
        check_choice(s, "schedule", SCHEDULES)
    accs = [parse_accumulate(a) for a in _as_list(accumulate, "accumulate")]
    if not scheds or not accs:
        raise ValueError("schedules and accumulate must each name at least one setting")
    if denoise is not None:
        check_choice(denoise, "denoise", DENOISE_STEPS)
    clamp, reproject = check_bool(clamp, "clamp"), check_bool(reproject, "reproject")
    return tuple(TemporalConfig(m, s, a, clamp, reproject, denoise)
                 for m, s, a in itertools.product(configs, scheds, accs))


@dataclass
class TemporalResult:
    """What :func:`run` measured.

    Attributes
    ----------
    rows : list of dict
        One per configuration and frame: ``config``, ``method``, ``samples``, ``schedule``,
        ``accumulate``, ``clamp``, ``reproject``, ``denoise``, ``frame`` (1-based),
        ``estimator_ms``, ``accumulate_ms``, ``ms`` (their sum: the time of the frame),
        ``total_ms`` (accumulated over the frames so far), ``disoccluded`` (fraction of the
        covered pixels whose history restarted in this frame), ``own_reference``, and per
        reference REF ``rmse_REF``, ``bias_REF``, ``one_frame_rmse_REF`` (the frame alone),
        ``flicker_REF`` (frame pair n-1, n, less the reference's own change; NaN at frame 1),
        ``flip`` (FLIP of the accumulated image against the own reference,
        :func:`vobscure.metrics.flip`) and ``flicker_flip`` (FLIP of frame n against frame
        n - 1 of the accumulated sequence: the change the eye sees; NaN at frame 1).
    series : list of dict
        ``{"config": label, "reference": REF, "rmse": [per frame]}`` for every configuration and
        reference (``summary.json``'s ``"temporal"``).
    summary : dict
        :func:`temporal_verdict`: ``text`` (sentences) and its numbers.
    cameras : list of dict
        The frames' cameras (:meth:`Camera.to_dict`).
    references : list of dict
        Per frame, reference name -> (H, W) image.
    images : dict
        Configuration label -> the accumulated image of the last frame.
    """

    rows: list
    series: list
    summary: dict
    cameras: list
    references: list = field(repr=False, default_factory=list)
    images: dict = field(repr=False, default_factory=dict)


def _frame_references(names, scene, camera, radius, *, normal_clamp, thickness, rays, screen_samples,
                      volume_samples, seed, cache, allow_open):
    """The references ``names`` of one camera's view (through the sweep's memo and the disk cache)."""
    from .sweeps import SweepConfig, view, view_reference

    # a sweep configuration names the view and the references' parameters; its method is not run
    cfg = SweepConfig(scene=scene, camera=camera, method="line", samples=1, radius=radius, normal_clamp=normal_clamp,
                      thickness=thickness, references=tuple(names), rays=rays, screen_samples=screen_samples,
                      volume_samples=volume_samples, reference_seed=seed, allow_open=allow_open)
    sc, _, gb = view(cfg)
    refs = {n: view_reference(n, cfg, sc, gb, radius, cache)[0].value for n in names}
    return gb, refs


def run(scene, configs, *, camera=None, size=None, frames: int = 8, motion: str = "static", step=None,
        cameras=None, radius=None, references=None, normal_clamp: bool = False, thickness=None, rays: int = 256,
        screen_samples: int = _references.SCREEN_SAMPLES, volume_samples: int = 1024, seed: int = 0,
        target_rmse=None, cache=False, progress: bool = False, allow_open: bool = False) -> TemporalResult:
    """Run every configuration over ``frames`` frames of a camera path and score each frame.

    Parameters
    ----------
    scene : str, path or Scene
        A built-in scene name, a mesh file or a :class:`vobscure.scenes.Scene`.
    configs : sequence of TemporalConfig, or str
        :func:`configurations`, or method configurations (then white noise and the running
        mean).
    camera : Camera, optional
        The first frame's camera; default the scene's at ``size`` (default 128 x 128).
    frames : int
        Frames N (>= 1); with ``cameras``, default their number.
    motion : {"static", "orbit", "dolly"}
        The camera path (:func:`vobscure.temporal.camera_path`); ``step`` its per-frame step.
    cameras : sequence of Camera, optional
        A user's path instead of ``motion`` (e.g. :func:`vobscure.temporal.cameras_from_file`).
    radius : float, optional
        Ball radius; default the experiments' rule for the first view
        (:func:`vobscure.experiments.common.choose_radius`).
    references : sequence of str, optional
        Default ``"screen"`` and the reference of each method's own quantity; a reference the
        scene cannot have (``volumetric`` on an open scene) is replaced by its stand-in and the
        verdict says so.
    normal_clamp, thickness, rays, screen_samples, volume_samples, seed, allow_open
        As in :func:`vobscure.experiments.compare.compare` (``thickness`` a number: the
        estimators' and the screen-space reference's; not ``"layers"``); the frame index of the
        estimators' noise schedule runs from 0 to N - 1 with the same ``seed``. Estimators
        that clip their value to [0, 1] per frame (``gtao``) run unclipped (``clip=False``:
        clipped frames average darker), and the accumulated image is clipped to [0, 1] before
        it is scored, as it would be shown; a single frame is scored clipped.
    target_rmse : float, optional
        The verdict's target; default :data:`~vobscure.experiments.verdict.TARGET_FACTOR` x the
        best error after :data:`VERDICT_FRAMES` frames.
    cache : bool, path or ReferenceCache
        The references' disk cache (default off).
    progress : bool
        A progress bar over the frames.

    Returns
    -------
    TemporalResult

    Examples
    --------
    >>> from vobscure.experiments import temporal
    >>> res = temporal.run("slab", "line:5", size=(12, 12), frames=3, references=("screen",), screen_samples=64)
    >>> [r["frame"] for r in res.rows], res.series[0]["reference"]
    ([1, 2, 3], 'screen')
    """
    from ..camera import Camera
    from ..metrics import error, flicker
    from ..scenes import resolve
    from .cache import open_cache
    from .common import choose_radius

    sc, scene_name = resolve(scene)
    if isinstance(configs, str):
        configs = configurations(configs)
    configs = tuple(configs)
    if not configs or not all(isinstance(c, TemporalConfig) for c in configs):
        raise ValueError("configs must be a non-empty sequence of TemporalConfig (see configurations())")
    if cameras is not None:
        cams = list(cameras)
        if not cams or not all(isinstance(c, Camera) for c in cams):
            raise ValueError("cameras must be a non-empty sequence of vobscure.Camera")
        frames = len(cams) if frames is None else check_int(frames, "frames")
        if frames > len(cams):
            raise ValueError(f"frames ({frames}) exceeds the {len(cams)} cameras given")
        cams = cams[:frames]
    else:
        frames = check_int(frames, "frames")
        if camera is None:
            camera = sc.camera(tuple(size) if size is not None else (128, 128))
        cams = camera_path(camera, frames, motion, step=step)
    first_gb = None
    if radius is None:
        from ..render import render_gbuffer

        first_gb = render_gbuffer(sc, cams[0])
        radius = choose_radius(sc, first_gb).radius
    radius = check_positive(radius, "radius")
    missing = {}
    if references is None:
        wanted = ("screen",) + tuple(c.method.reference(normal_clamp) for c in configs)
        references = []
        for name in dict.fromkeys(wanted):
            use = name if allow_open else _references.usable(name, sc)
            if use != name:
                missing[name] = use
            if use is not None and use not in references:
                references.append(use)
    references = tuple(references)
    for name in references:
        check_choice(name, "references", _references.names())
    if target_rmse is not None:
        target_rmse = check_positive(target_rmse, "target_rmse")
    if thickness is not None:
        if isinstance(thickness, str):
            raise ValueError("thickness must be a number or None for a frame sequence; the layered G-buffer "
                             "(thickness='layers') is not rendered per frame")
        thickness = check_positive(thickness, "thickness")
    store = open_cache(cache)

    def own(c):
        ref = c.method.reference(normal_clamp)
        ref = missing.get(ref, ref)
        return ref if ref in references else references[0]

    accs = {c.label: c.accumulator() for c in configs}
    prev = {c.label: None for c in configs}
    rows, per_frame_refs, last = [], [], {}
    total = {c.label: 0.0 for c in configs}
    bar = progress_bar(frames * len(configs), "frames", progress)
    ref_memo = {}
    for n, cam in enumerate(cams):
        if cam not in ref_memo:        # a static path's frames share one view
            ref_memo[cam] = _frame_references(references, sc, cam, radius, normal_clamp=normal_clamp,
                                              thickness=thickness, rays=rays,
                                              screen_samples=screen_samples, volume_samples=volume_samples,
                                              seed=seed, cache=store, allow_open=allow_open)
        gb, refs = ref_memo[cam]
        per_frame_refs.append(refs)
        for c in configs:
            # unclipped frames (gtao's clip=False) average to the integral; what is shown is clipped
            kwargs = dict(radius=radius, normal_clamp=normal_clamp, thickness=thickness, seed=seed, frame=n,
                          schedule=c.schedule, clip=False)
            if c.method.spec.needs_scene:
                kwargs["scene"] = sc
            t0 = time.perf_counter()
            x = c.method.run(gb, **kwargs)
            t_est = time.perf_counter() - t0
            acc = accs[c.label]
            before = acc.seconds
            out = np.clip(acc.update(x, gb), 0.0, 1.0)
            t_acc = acc.seconds - before
            x = np.clip(x, 0.0, 1.0)
            total[c.label] += t_est + t_acc
            covered = int(gb.valid.sum())
            restarted = int(np.count_nonzero((acc.count == 1) & gb.valid)) if n > 0 else covered
            row = dict(config=c.label, method=c.method.method, samples=c.method.samples, schedule=c.schedule,
                       accumulate=c.accumulate.label, clamp=c.clamp, reproject=c.reproject, denoise=c.denoise,
                       frame=n + 1, estimator_ms=1e3 * t_est, accumulate_ms=1e3 * t_acc,
                       ms=1e3 * (t_est + t_acc), total_ms=1e3 * total[c.label],
                       disoccluded=restarted / covered if covered and n > 0 else 0.0, own_reference=own(c),
                       quantity=c.method.quantity(normal_clamp))
            own_ref = own(c)
            p = prev[c.label]
            for name, ref in refs.items():
                # FLIP (a second per megapixel) only against the configuration's own reference
                e = error(out, ref, flip=name == own_ref)
                row[f"rmse_{name}"] = e.rmse
                row[f"bias_{name}"] = e.bias
                row[f"one_frame_rmse_{name}"] = error(x, ref, flip=False).rmse
                row[f"flicker_{name}"] = (flicker(np.stack([p[0], out]), np.stack([p[1][name], ref]), flip=False).value
                                          if p is not None else float("nan"))
                if name == own_ref:
                    row["flip"] = e.flip
            # FLIP between this accumulated frame and the last, as the eye sees the change
            row["flicker_flip"] = (flicker(np.stack([p[0], out]), flip=True).estimate_flip
                                   if p is not None else float("nan"))
            prev[c.label] = (out, refs)
            last[c.label] = out
            rows.append(row)
            bar.update(1)
    bar.close()
    series = [dict(config=c.label, reference=name, rmse=[r[f"rmse_{name}"] for r in rows if r["config"] == c.label])
              for c in configs for name in references]
    summary = temporal_verdict(rows, configs, target_rmse=target_rmse, motion="list" if cameras is not None else motion,
                               missing=missing)
    return TemporalResult(rows=rows, series=series, summary=summary, cameras=[c.to_dict() for c in cams],
                          references=per_frame_refs, images=last)


def frames_to_target(rmse, target) -> int | None:
    """The first frame (1-based) whose error is at most ``target``, or None.

    Examples
    --------
    >>> frames_to_target([0.3, 0.2, 0.09, 0.1], 0.1)
    3
    """
    for n, e in enumerate(rmse, start=1):
        if np.isfinite(e) and e <= target:
            return n
    return None


def _pick(cands, key):
    cands = [c for c in cands if np.isfinite(key(c))]
    return min(cands, key=key) if cands else None


def _cheapest(cands, per_frame, reach, err):
    """The configuration of ``cands`` with the least time per frame; those within
    :data:`TIME_TIE` of it count as equally fast (a shared machine's timing noise: a noise
    schedule or an accumulation does not change an estimator's cost by that much), and among
    them the one that reaches the target first, then the most accurate, wins."""
    cands = [c for c in cands if np.isfinite(per_frame[c])]
    if not cands:
        return None
    fastest = min(per_frame[c] for c in cands)
    tied = [c for c in cands if per_frame[c] <= (1.0 + TIME_TIE) * fastest]
    return min(tied, key=lambda c: (reach[c], err[c], per_frame[c]))


def temporal_verdict(rows, configs, *, target_rmse=None, motion="static", missing=None) -> dict:
    """Sentences and numbers from :func:`run`'s rows: per reference, which configuration reaches the
    target error after :data:`VERDICT_FRAMES` frames (or the last) at the least time per frame,
    and how that differs from the one-frame answer; the frames each needs to reach the target.

    Each configuration is scored against its own reference (``own_reference``) and, when the
    converged screen-space VO is the limit of its quantity, against ``"screen"`` as well (the
    sampling error alone, what accumulation reduces). The time per frame is the estimator plus
    the accumulation, the least over the frames: every frame does the same work, and on a
    shared machine the least is the one least disturbed by other load (as the best of the
    timed repeats elsewhere). Times within :data:`TIME_TIE` of the least count as equal, and
    among those the configuration that reaches the target first is named.

    Returns
    -------
    dict
        ``text`` (sentences), ``frames``, ``verdict_frames`` (K), ``ms_per_frame`` (per
        configuration) and ``groups``: per reference ``reference``, ``configs``,
        ``target_rmse``, ``winner`` (least time per frame reaching the target by frame K, or
        None), ``one_frame_winner`` (the same in one frame), ``frames_to_target`` (per
        configuration: the first frame at or below the target, or None).
    """
    labels = [c.label for c in configs]
    by = {lab: [r for r in rows if r["config"] == lab] for lab in labels}
    N = max(len(v) for v in by.values())
    K = min(VERDICT_FRAMES, N)
    per_frame = {lab: float(np.min([r["ms"] for r in by[lab]])) for lab in labels}
    members = {}
    for lab in labels:
        first = by[lab][0]
        members.setdefault(first["own_reference"], []).append(lab)
        q = first.get("quantity")
        if first["own_reference"] != "screen" and "rmse_screen" in first and q is not None \
                and _methods.QUANTITIES[q].screen_limit:
            members.setdefault("screen", []).append(lab)
    order = _references.names()
    words = {"static": "a static camera", "orbit": "an orbiting camera", "dolly": "a dolly",
             "list": "the cameras given"}.get(motion, motion)
    text = []
    if missing:
        text.append("Missing references in the frames: " + "; ".join(
            f"{k} is replaced by {v}" if v else f"{k} is not available" for k, v in missing.items()) + ".")
    text.append(f"Over {N} frame(s) with {words} (docs/temporal.md), time per frame = the estimator plus the "
                f"accumulation (the least over the frames):")
    groups = []
    for ref in sorted(members, key=order.index):
        labs = members[ref]
        err = {lab: [r[f"rmse_{ref}"] for r in by[lab]] for lab in labs}
        best_k = min((err[lab][K - 1] for lab in labs if np.isfinite(err[lab][K - 1])), default=float("nan"))
        target = float(target_rmse) if target_rmse is not None else TARGET_FACTOR * best_k
        reach = {lab: frames_to_target(err[lab], target) for lab in labs}
        win = _cheapest([lab for lab in labs if reach[lab] is not None and reach[lab] <= K], per_frame, reach,
                        {lab: err[lab][K - 1] for lab in labs})
        one = _cheapest([lab for lab in labs if reach[lab] == 1], per_frame, reach,
                        {lab: err[lab][0] for lab in labs})
        what = "the converged screen-space VO (the sampling error)" if ref == "screen" else f"{ref!r}"
        head = (f"Against {what}, target RMSE {target:.4f}"
                + ("" if target_rmse is not None else f" ({TARGET_FACTOR:g} x the best after {K} frames)") + ": ")
        if win is not None:
            line = (f"after {K} frames {win} reaches it at the least time per frame (RMSE {err[win][K - 1]:.4f} "
                    f"at {per_frame[win]:.1f} ms, reached at frame {reach[win]})")
        else:
            close = _pick(labs, lambda lab: err[lab][K - 1])
            line = (f"no configuration reaches it within {K} frames (closest: {close}, RMSE "
                    f"{err[close][K - 1]:.4f})")
        if one is not None:
            line += ("; in one frame the answer is the same" if one == win else
                     f"; in one frame the answer would be {one} (RMSE {err[one][0]:.4f} at {per_frame[one]:.1f} ms)")
        else:
            first = _pick(labs, lambda lab: err[lab][0])
            line += (f"; no configuration reaches it in one frame (the best single frame: {first}, RMSE "
                     f"{err[first][0]:.4f})")
        never = [lab for lab in labs if reach[lab] is None]
        if never and len(never) < len(labs):
            line += f". Not within {N} frames: {', '.join(never)}"
        if best_k > POOR_RMSE:
            line += (f". Even the best is off by {best_k:.2f} after {K} frames: that error is the model's "
                     f"(what the depth buffer cannot see), which frames do not reduce")
        text.append(head + line + ".")
        groups.append(dict(reference=ref, configs=labs, target_rmse=target, winner=win, one_frame_winner=one,
                           frames_to_target=reach))
    return dict(text=text, frames=N, verdict_frames=K, ms_per_frame=per_frame, groups=groups)


def plot(path, result: TemporalResult):
    """Error against frames and against the accumulated time, per configuration (its own
    reference: solid; the converged screen-space VO, for the quantities it is the limit of:
    dotted), on log axes."""
    labels = list(dict.fromkeys(r["config"] for r in result.rows))
    rows_of_legend = int(np.ceil(len(labels) / 3))
    fig = new_figure(11.0, 4.0 + 0.18 * rows_of_legend)
    ax1, ax2 = fig.subplots(1, 2)
    import matplotlib

    cmap = matplotlib.colormaps["tab20"]
    colours = {lab: cmap(i % 20) for i, lab in enumerate(labels)}
    for lab in labels:
        rows = [r for r in result.rows if r["config"] == lab]
        own = rows[0]["own_reference"]
        f = [r["frame"] for r in rows]
        t = [r["total_ms"] for r in rows]
        q = rows[0].get("quantity")
        limited = q is not None and _methods.QUANTITIES[q].screen_limit
        for ref, style in ((own, "-"), ("screen", ":")):
            key = f"rmse_{ref}"
            # the screen-space VO is scored only for the quantities it is the limit of
            if key not in rows[0] or (ref == "screen" and (own == "screen" or not limited)):
                continue
            e = [r[key] for r in rows]
            ax1.plot(f, e, style, color=colours[lab], label=lab if style == "-" else None)
            ax2.plot(t, e, style, color=colours[lab])
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("RMSE of the accumulated image")
        ax.grid(True, which="both", alpha=0.3)
    ax1.set_xlabel("frame")
    ax2.set_xlabel("accumulated time (ms)")
    fig.legend(loc="outside lower center", ncol=3, fontsize=7, frameon=False)
    fig.suptitle("Error of the accumulated image after N frames (solid: own reference; dotted: screen-space VO)")
    return save_figure(fig, path)
