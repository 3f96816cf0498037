"""Thin geometry: time and taps against error of every thickness model, as Pareto fronts.

One PNG, ``thin_pareto.png``, its numbers, ``thin_pareto.csv``, and its tables,
``thin_pareto.md``, on three scenes (:data:`SCENES`: the Cornell box, the thin occluders and
the crease), each at one radius (:func:`vobscure.experiments.common.choose_radius`) and its
own camera:

- the G-buffer rendered with 1, 2 and 4 layers (:data:`LAYERS`, depth peeling,
  ``render_gbuffer(scene, camera, layers=K)``), each render timed: the ``render`` rows, and
  what the extra layers cost over one;
- the references once, on the one-layer G-buffer, by the reference registry
  (:mod:`vobscure.references`): the world-space VO (``"volumetric"``), ray-cast cosine AO
  within R (``"ao"``), uniform AO (``"ao_uniform"``) and the obscurance (``"obscurance"``);
- every configuration of :func:`configurations` (VO by lines and points, solid, with a constant
  thickness and with the layers; GTAO with and without its thin-occluder heuristic and with the
  layers; VBAO in each variant engines ship and with the layers; SAO and HBAO), each scored
  against the reference of its own quantity as the method registry maps it
  (:meth:`vobscure.methods.Method.reference`), over the whole frame and in the thin-feature
  band (:func:`vobscure.metrics.thin_feature_mask`).

Cost is the median wall time of the estimator's call alone (``seconds``) and that plus what
the configuration's layered G-buffer costs to render beyond one layer
(``seconds_incl_layers``); and the depth taps per pixel (``taps_per_pixel``, the registry's
count), with what one tap reads (``values_per_tap``): the depth texels of the fetch, and for a
layered configuration the front and back of every interval slot of the pixel the tap falls in.
The fronts are :func:`vobscure.experiments.compare.pareto_front` of the configurations of a
scene, each error against its own reference.

Regenerate with ``vobscure figures thin_pareto --out docs/img`` (full: 160 x 160, 5 repeats);
``--quick`` measures the same configurations at 32 x 32 in seconds.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from . import deprecated_make
from ._common import Rows, fmt, log_log

__all__ = ["measure", "plot", "markdown", "configurations", "fronts", "verdict", "Entry", "SCENES", "LAYERS",
           "VO_THICKNESS", "FRONTS", "YARDSTICK"]

ORDER = 95
FIGSIZE = (22.0, 15.0)

#: The scenes, by their :mod:`vobscure.scenes` builder names.
SCENES = ("cornell_box", "thin_occluders", "crease")
#: How the figure names them.
SCENE_TITLES = {"cornell_box": "Cornell box", "thin_occluders": "thin occluders", "crease": "crease"}
#: Layer counts of the rendered G-buffers; the first is the depth buffer alone.
LAYERS = (1, 2, 4)
#: Constant thicknesses of the VO configurations, as fractions of R (Loos & Sloan 2010, Sec. 4.3).
VO_THICKNESS = (0.25, 0.5, 1.0)
#: VBAO's constant thickness, a fraction of R (``vbao``'s default).
VBAO_THICKNESS = 0.5
#: Blender's near thickness (a fraction of R here) and its far thickness, an angle
#: (``fast_gi_thickness_far``, 45 degrees: docs/screenspace.md, "VBAO").
BLENDER_NEAR, BLENDER_FAR = 0.25, math.pi / 4
#: GTAO's thin-occluder compensation when on: the top of the "expected range [0.0, 0.7]" that
#: XeGTAO's settings clamp ``ThinOccluderCompensation`` to (``XeGTAO.h``, ``GTAOImGuiSettings``;
#: default ``XE_GTAO_DEFAULT_THIN_OCCLUDER_COMPENSATION``, 0).
THIN_OCCLUDER = 0.7
#: The configuration the verdict measures the others against: XeGTAO's "high" preset, 3 slices
#: of 3 steps a side, on the one-layer G-buffer.
YARDSTICK = "gtao:3"
#: What the quick and the full profile measure with: image size, timed repeats, rays a pixel of
#: the ray-cast AO and obscurance, points a ball of the world-space VO.
QUICK = dict(size=(32, 32), repeats=1, rays=32, volume_samples=64)
FULL = dict(size=(160, 160), repeats=5, rays=256, volume_samples=512)
#: The fronts: (row column, cost column, error column).
FRONTS = (("front_time", "seconds_incl_layers", "rmse"), ("front_time_band", "seconds_incl_layers", "thin_rmse"),
          ("front_taps", "taps_per_pixel", "rmse"), ("front_taps_band", "taps_per_pixel", "thin_rmse"))
#: The figure draws an RMSE below this (an exact 0: estimate and reference both 1 wherever no
#: ray is blocked) at this value, on its logarithmic axis.
PLOT_FLOOR = 1e-3
#: References by the registry (:data:`vobscure.references.REFERENCES`) names, and how tables name them.
REFERENCE_NAMES = {"volumetric": "world-space VO", "ao": "cosine AO", "ao_uniform": "uniform AO",
                   "obscurance": "obscurance"}

_COLUMNS = ("scene", "kind", "label", "family", "method", "samples", "variant", "layers", "radius", "reference",
            "seconds", "layer_seconds", "seconds_incl_layers", "ratio_to_one_layer", "taps_per_pixel",
            "values_per_tap", "interval_slots", "extra_bytes_per_pixel", "rmse", "bias", "thin_rmse",
            "thin_bias", "thin_pixels", *[f[0] for f in FRONTS])
_FAMILY_COLORS = {"VO line": "#d62728", "VO point": "#ff7f0e", "GTAO": "#1f77b4", "VBAO": "#2ca02c",
                  "SAO": "#9467bd", "HBAO": "#8c564b"}
_KIND_MARKERS = {"solid": "o", "thickness": "s", "layers": "^", "other": "D"}


@dataclass(frozen=True)
class Entry:
    """One configuration: a registered method with a sample count and options.

    Parameters
    ----------
    label : str
        The compact name in the figure and tables (``"line:9 t.5R"``, ``"gtao:3 L4"``).
    family : str
        The group it is drawn in (a key of the figure's colours).
    method : str
        The :mod:`vobscure.methods` name: its function, samples keyword, taps and reference.
    samples : int
        The method's sample count (samples, slices or directions).
    variant : str
        What distinguishes it within the method (``"solid"``, ``"thickness 0.5 R"``, ``"layers"``).
    layers : int
        K of the G-buffer it reads (1: the depth buffer alone).
    options : dict
        Keyword options of the method's function beyond ``radius`` and the sample count.
    """

    label: str
    family: str
    method: str
    samples: int
    variant: str
    layers: int = 1
    options: dict = field(default_factory=dict)

    @property
    def kind(self) -> str:
        """How its thickness is modelled: solid, a constant thickness, the layers, or other."""
        if self.layers > 1:
            return "layers"
        if self.variant == "solid" or self.variant == "default":
            return "solid"
        return "thickness" if self.variant.startswith("thickness") else "other"


def _short(fraction: float) -> str:
    """0.25 -> '.25', 1.0 -> '1': a fraction of R in a compact label."""
    return f"{fraction:g}".lstrip("0") or "0"


def configurations(radius: float, median_depth: float) -> list[Entry]:
    """The configurations measured on a scene at ``radius``.

    ``median_depth`` (the covered pixels' median view depth) sets VBAO's linear thickness so
    that it equals the constant one, :data:`VBAO_THICKNESS` x R, at that depth.

    Examples
    --------
    >>> entries = configurations(0.5, 4.0)
    >>> [e.label for e in entries if e.method == "gtao" and e.samples == 3]
    ['gtao:3', 'gtao:3 thin.7', 'gtao:3 L2', 'gtao:3 L4']
    >>> len(entries), sorted({e.family for e in entries})
    (50, ['GTAO', 'HBAO', 'SAO', 'VBAO', 'VO line', 'VO point'])
    """
    out = []
    layered = [K for K in LAYERS if K > 1]
    for method, family, counts in (("line", "VO line", (5, 9)), ("point", "VO point", (16, 32))):
        for n in counts:
            head = f"{method}:{n}"
            out.append(Entry(f"{head} solid", family, method, n, "solid"))
            out += [Entry(f"{head} t{_short(f)}R", family, method, n, f"thickness {f:g} R",
                          options=dict(thickness=f * radius)) for f in VO_THICKNESS]
            out += [Entry(f"{head} L{K}", family, method, n, "layers", K, dict(thickness="layers")) for K in layered]
    for n in (3, 6):
        head = f"gtao:{n}"
        out.append(Entry(head, "GTAO", "gtao", n, "default"))
        out.append(Entry(f"{head} thin{_short(THIN_OCCLUDER)}", "GTAO", "gtao", n,
                         f"thin occluder {THIN_OCCLUDER:g}", options=dict(thin_occluder=THIN_OCCLUDER)))
        out += [Entry(f"{head} L{K}", "GTAO", "gtao", n, "layers", K, dict(thickness="layers")) for K in layered]
    for n in (3, 6):
        head = f"vbao:{n}"
        out += [
            Entry(f"{head} t{_short(VBAO_THICKNESS)}R", "VBAO", "vbao", n, f"thickness {VBAO_THICKNESS:g} R",
                  options=dict(thickness=VBAO_THICKNESS * radius)),
            Entry(f"{head} linear", "VBAO", "vbao", n, "linear thickness",
                  options=dict(thickness=VBAO_THICKNESS * radius / median_depth, thickness_scale="linear")),
            Entry(f"{head} near/far", "VBAO", "vbao", n, f"near {BLENDER_NEAR:g} R, far pi/4",
                  options=dict(thickness=BLENDER_NEAR * radius, thickness_far=BLENDER_FAR)),
            Entry(f"{head} uniform", "VBAO", "vbao_uniform", n, f"uniform, thickness {VBAO_THICKNESS:g} R",
                  options=dict(thickness=VBAO_THICKNESS * radius)),
            Entry(f"{head} bitcount", "VBAO", "vbao", n, f"bitcount, thickness {VBAO_THICKNESS:g} R",
                  options=dict(thickness=VBAO_THICKNESS * radius, weighting="bitcount")),
        ]
        out += [Entry(f"{head} L{K}", "VBAO", "vbao", n, "layers", K, dict(thickness="layers")) for K in layered]
    out += [Entry(f"sao:{n}", "SAO", "sao", n, "default") for n in (12, 24)]
    out += [Entry(f"hbao:{n}", "HBAO", "hbao", n, "default") for n in (4, 8)]
    return out


def _run(entry: Entry, gbuffer, radius: float):
    """The zero-argument call of ``entry`` on ``gbuffer``: the registry's function (with its
    fixed steps) given the sample count under its own keyword."""
    from ...methods import get

    spec = get(entry.method)
    kwargs = dict(entry.options, radius=radius, **{spec.samples: entry.samples})
    return lambda: spec.function(gbuffer, **kwargs)


def _values_per_tap(entry: Entry, slots: int) -> int:
    """What one depth tap of ``entry`` reads: the texels of its fetch; with the layers, the
    front and back of each of the ``slots`` interval slots of the pixel it falls in (beside the
    fetched depth for the horizon methods, which still read it; instead of it for VO)."""
    from ...methods import TEXELS_PER_TAP, get

    texels = TEXELS_PER_TAP[get(entry.method).fetch]
    if entry.layers == 1:
        return texels
    return 2 * slots + (0 if entry.family.startswith("VO") else texels)


def _reference(scene, gbuffer, name: str, radius: float, settings: dict, seed: int):
    """The reference ``name`` of the registry on ``gbuffer``: :func:`vobscure.ground_truth`
    with the registry's arguments (ball, no thickness, constant falloff) at the ``settings``'
    rays or points."""
    from ... import ground_truth
    from ...references import get

    args = get(name).arguments(radius=radius, seed=seed, rays=settings["rays"],
                               volume_samples=settings["volume_samples"], normal_clamp=False, falloff="constant",
                               allow_open=False)
    return ground_truth(scene, gbuffer, **args)


def fronts(rows, scene: str) -> dict:
    """The Pareto fronts of ``scene``'s configurations, by :data:`FRONTS` column: the labels,
    by cost, of the rows no other beats in both cost and error
    (:func:`vobscure.experiments.compare.pareto_front`).

    Examples
    --------
    >>> rows = [dict(scene="s", kind="estimate", label=k, seconds_incl_layers=t, rmse=e, thin_rmse=e,
    ...              taps_per_pixel=t) for k, t, e in (("a", 1, 0.3), ("b", 2, 0.4), ("c", 3, 0.1))]
    >>> fronts(rows, "s")["front_time"]
    ['a', 'c']
    """
    from ..compare import pareto_front

    sel = [r for r in rows if r["scene"] == scene and r["kind"] == "estimate"]
    out = {}
    for name, cost, err in FRONTS:
        idx = pareto_front([_num(r[cost]) for r in sel], [_num(r[err]) for r in sel])
        out[name] = [sel[i]["label"] for i in idx]
    return out


def _num(value) -> float:
    """A cell as a float: None (an empty cell) is NaN."""
    return float("nan") if value is None else float(value)


def _load() -> float:
    """The 1-minute load average (NaN where the system has none)."""
    try:
        return float(os.getloadavg()[0])
    except (AttributeError, OSError):  # pragma: no cover - not Unix
        return float("nan")


def _scene_rows(name: str, settings: dict, seed: int) -> tuple[list, dict]:
    """Rows and title numbers of one scene: its renders, then every configuration."""
    from ... import render_gbuffer, scenes
    from ...metrics import error, thin_feature_mask
    from ...methods import get
    from ..common import choose_radius, time_calls

    sc = getattr(scenes, name)()
    camera = sc.camera(settings["size"])
    repeats = settings["repeats"]
    timings, gbs = time_calls({K: (lambda K=K: render_gbuffer(sc, camera, layers=K)) for K in LAYERS}, repeats)
    gb1 = gbs[1]
    radius = choose_radius(sc, gb1).radius
    covered = np.asarray(gb1.valid)
    median_depth = float(np.median(np.asarray(gb1.depth)[covered]))
    mask = thin_feature_mask(gb1, radius=radius)
    refs = {ref: _reference(sc, gb1, ref, radius, settings, seed) for ref in REFERENCE_NAMES}
    one = timings[1].median
    slots = {K: (0 if gbs[K].intervals is None else int(gbs[K].intervals.count)) for K in LAYERS}
    rows = []
    for K in LAYERS:
        s = gbs[K].intervals
        extra = 0 if s is None else s.front.nbytes + s.back.nbytes + s.layers.nbytes
        rows.append(dict(scene=name, kind="render", label=f"G-buffer K={K}", family="G-buffer", method="render",
                         layers=K, radius=radius, seconds=timings[K].median, layer_seconds=timings[K].median - one,
                         seconds_incl_layers=timings[K].median, ratio_to_one_layer=timings[K].median / one,
                         interval_slots=slots[K], extra_bytes_per_pixel=extra / covered.size))
    entries = configurations(radius, median_depth)
    calls = {e.label: _run(e, gbs[e.layers], radius) for e in entries}
    est_timings, images = time_calls(calls, repeats)
    for e in entries:
        spec = get(e.method)
        ref = spec.reference(normal_clamp=False)
        whole = error(images[e.label], refs[ref].value)
        band = error(images[e.label], refs[ref].value, mask=mask)
        extra = timings[e.layers].median - one if e.layers > 1 else 0.0
        rows.append(dict(scene=name, kind="estimate", label=e.label, family=e.family, method=e.method,
                         samples=e.samples, variant=e.variant, layers=e.layers, radius=radius, reference=ref,
                         seconds=est_timings[e.label].median, layer_seconds=extra,
                         seconds_incl_layers=est_timings[e.label].median + extra,
                         taps_per_pixel=spec.taps(e.samples), values_per_tap=_values_per_tap(e, slots[e.layers]),
                         interval_slots=slots[e.layers] if e.layers > 1 else 0, rmse=whole.rmse, bias=whole.bias,
                         thin_rmse=band.rmse, thin_bias=band.bias, thin_pixels=band.pixels))
    rows = [{c: r.get(c) for c in _COLUMNS} for r in rows]      # every row holds every column
    for column, labels in fronts(rows, name).items():
        for r in rows:
            r[column] = r["kind"] == "estimate" and r["label"] in labels
    meta = dict(radius=radius, median_depth=median_depth, covered=int(covered.sum()), band=int(mask.sum()),
                linear_thickness=VBAO_THICKNESS * radius / median_depth,
                reference_stderr={ref: float(np.sqrt(np.nanmean(np.asarray(e.stderr, float)[covered] ** 2)))
                                  for ref, e in refs.items()})
    return rows, meta


def measure(profile, *, scenes=SCENES):
    """Rows of every scene of ``scenes``: per scene the renders (``kind="render"``) and every
    configuration of :func:`configurations` (``kind="estimate"``), with the fronts.

    Parameters
    ----------
    profile : Profile
        Quick (:data:`QUICK`: 32 x 32, one timed repeat, 32 rays, 64 points a ball) or full
        (:data:`FULL`: 160 x 160, 5 repeats, 256 rays, 512 points); its seed seeds the
        references (the estimators keep their default seed, 0).
    scenes : sequence of str, optional
        Some of :data:`SCENES` (default all three).

    Returns
    -------
    Rows
        Every row with every column of the CSV; ``meta`` holds the run (size, repeats, the
        load average before and after, the machine) and per scene the radius, the band's size
        and the references' standard errors.
    """
    from ..common import machine

    unknown = [s for s in scenes if s not in SCENES]
    if unknown or not scenes:
        raise ValueError(f"scenes must be some of {', '.join(SCENES)}, got {scenes!r}")
    settings = profile.pick(QUICK, FULL)
    load = [_load()]
    rows, per_scene = [], {}
    for name in scenes:
        scene_rows, per_scene[name] = _scene_rows(name, settings, profile.seed)
        rows += scene_rows
    load.append(_load())
    meta = dict(scenes=list(scenes), size=list(settings["size"]), repeats=settings["repeats"], seed=profile.seed,
                quick=profile.quick, rays=settings["rays"], volume_samples=settings["volume_samples"],
                load_average=load, machine=machine(), per_scene=per_scene)
    return Rows(rows, columns=_COLUMNS, meta=meta)


# --------------------------------------------------------------------------- the verdict
def verdict(rows, scene: str, *, band: bool = False, same_reference: bool = False) -> dict:
    """Which configuration wins at equal time on ``scene``: the most accurate whose time
    (incl. its extra layers' render) is at most :data:`YARDSTICK`'s, against that yardstick.

    Among equal errors the cheaper wins, so the winner is on the time front (:func:`fronts`).
    With ``same_reference`` only the configurations scored against the yardstick's reference
    (cosine AO) compete: errors against one reference, not each against its own.

    Returns
    -------
    dict
        ``yardstick`` and ``best`` (their rows), ``ratio`` (yardstick's RMSE / best's),
        ``cheapest`` (the row of least time whose RMSE is at most the yardstick's: what the
        yardstick's accuracy costs at least) and ``sentence``; ``best`` and ``cheapest`` None
        when no configuration is scored (an empty band).
    """
    err = "thin_rmse" if band else "rmse"
    where = "in the thin-feature band" if band else "over the whole frame"
    sel = [r for r in rows if r["scene"] == scene and r["kind"] == "estimate"]
    yard = next(r for r in sel if r["label"] == YARDSTICK)
    limit = _num(yard["seconds_incl_layers"])
    within = [r for r in sel if _num(r["seconds_incl_layers"]) <= limit and np.isfinite(_num(r[err]))
              and (not same_reference or r["reference"] == yard["reference"])]
    title = SCENE_TITLES.get(scene, scene)
    if same_reference:
        where += f", against {REFERENCE_NAMES.get(yard['reference'], yard['reference'])} alone"
    if not within:
        return dict(yardstick=yard, best=None, ratio=float("nan"), cheapest=None,
                    sentence=f"{title}, {where}: no configuration is scored (the band is empty).")
    best = min(within, key=lambda r: (_num(r[err]), _num(r["seconds_incl_layers"])))
    ratio = _num(yard[err]) / _num(best[err]) if _num(best[err]) > 0 else float("inf")

    def ref(r):
        return REFERENCE_NAMES.get(r["reference"], r["reference"])

    if best["label"] == YARDSTICK:
        text = (f"{title}, {where}: nothing within the time of {YARDSTICK} ({_ms(limit)}) beats it "
                f"(RMSE {fmt(_num(yard[err]))} against {ref(yard)}).")
    else:
        text = (f"{title}, {where}: within the time of {YARDSTICK} ({_ms(limit)}), the most accurate is "
                f"{best['label']} ({_ms(_num(best['seconds_incl_layers']))}"
                + (" incl. its extra layers' render" if best["layers"] > 1 else "")
                + f"): RMSE {fmt(_num(best[err]))} against {ref(best)}"
                + (f", {ratio:.1f}x lower than {YARDSTICK}'s" if np.isfinite(ratio) else
                   f" (exact: it reads what its reference reads on every pixel), where {YARDSTICK} has")
                + f" {fmt(_num(yard[err]))} against {ref(yard)}.")
    good = [r for r in sel if _num(r[err]) <= _num(yard[err])
            and (not same_reference or r["reference"] == yard["reference"])]
    cheapest = min(good, key=lambda r: (_num(r["seconds_incl_layers"]), _num(r[err])))
    if cheapest["label"] != YARDSTICK:
        speed = limit / _num(cheapest["seconds_incl_layers"])
        text += (f" The cheapest as accurate is {cheapest['label']} ({_ms(_num(cheapest['seconds_incl_layers']))}, "
                 + (f"{speed:.1f}x faster" if speed >= 1 else f"{1 / speed:.1f}x slower")
                 + f", RMSE {fmt(_num(cheapest[err]))}).")
    return dict(yardstick=yard, best=best, ratio=ratio, cheapest=cheapest, sentence=text)


def _ms(seconds: float) -> str:
    return f"{1e3 * seconds:.1f} ms"


# --------------------------------------------------------------------------- the tables
def markdown(rows) -> str:
    """Per scene: the verdict, the renders' cost, the fronts and the table of every configuration."""
    meta = getattr(rows, "meta", {}) or {}
    out = []
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    for scene in scenes:
        info = (meta.get("per_scene") or {}).get(scene, {})
        out.append(f"### {SCENE_TITLES.get(scene, scene)}")
        if info:
            errs = ", ".join(f"{REFERENCE_NAMES[k]} {v:.4f}" for k, v in info["reference_stderr"].items())
            out.append(f"\nR = {info['radius']:.4g}; {info['band']} of {info['covered']} covered pixels in the "
                       f"thin-feature band; the references' standard error (RMS over the covered pixels): {errs}.")
        out.append("")
        out += [f"- {verdict(rows, scene, band=band, same_reference=same)['sentence']}"
                for same in (False, True) for band in (False, True)]
        renders = [r for r in rows if r["scene"] == scene and r["kind"] == "render"]
        out += ["", "| G-buffer | ms | x one layer | interval slots | extra bytes / px |", "|---|---:|---:|---:|---:|"]
        out += [f"| K = {r['layers']} | {1e3 * _num(r['seconds']):.2f} | {_num(r['ratio_to_one_layer']):.2f} | "
                f"{r['interval_slots']} | {_num(r['extra_bytes_per_pixel']):.1f} |" for r in renders]
        out.append("")
        names = {"front_time": "time, whole frame", "front_time_band": "time, band",
                 "front_taps": "taps, whole frame", "front_taps_band": "taps, band"}
        out += [f"- front ({names[k]}): " + " -> ".join(labels) for k, labels in fronts(rows, scene).items()]
        out += ["", "| configuration | reference | ms | ms incl. layers | taps/px | values/tap | RMSE | bias | "
                    "band RMSE | band bias | fronts |", "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
        for r in (r for r in rows if r["scene"] == scene and r["kind"] == "estimate"):
            marks = "".join(m for (col, _, _), m in zip(FRONTS, ("T", "t", "N", "n")) if r[col])
            out.append(f"| {r['label']} | {REFERENCE_NAMES.get(r['reference'], r['reference'])} | "
                       f"{1e3 * _num(r['seconds']):.2f} | {1e3 * _num(r['seconds_incl_layers']):.2f} | "
                       f"{r['taps_per_pixel']} | {r['values_per_tap']} | {fmt(_num(r['rmse']), 4)} | "
                       f"{_num(r['bias']):+.4f} | {fmt(_num(r['thin_rmse']), 4)} | {_num(r['thin_bias']):+.4f} | "
                       f"{marks} |")
        out.append("")
    out.append("Fronts: T time (incl. the extra layers' render) / whole frame, t time / band, N taps / whole "
               "frame, n taps / band. Each RMSE is against the configuration's own reference.")
    return "\n".join(out) + "\n"


# --------------------------------------------------------------------------- the figure
def _panel(ax, sel, cost, err, front_col, *, title, xlabel):
    """RMSE against ``cost`` for the rows ``sel``: families by colour, thickness model by
    marker, the front as a staircase with its points labelled."""
    for r in sel:
        x, y = _num(r[cost]), _num(r[err])
        if not (np.isfinite(x) and np.isfinite(y)) or x <= 0:
            continue
        y = max(y, PLOT_FLOOR)
        kind = Entry(r["label"], r["family"], r["method"], r["samples"], r["variant"], r["layers"]).kind
        ax.scatter(x * (1e3 if cost.startswith("seconds") else 1), y, s=22, color=_FAMILY_COLORS[r["family"]],
                   marker=_KIND_MARKERS[kind], alpha=0.85, edgecolors="none")
    front = [r for r in sel if r[front_col]]
    front.sort(key=lambda r: _num(r[cost]))
    if front:
        scale = 1e3 if cost.startswith("seconds") else 1
        xs = [_num(r[cost]) * scale for r in front]
        ys = [max(_num(r[err]), PLOT_FLOOR) for r in front]
        ax.step(xs, ys, where="post", color="k", lw=0.9, alpha=0.7)
        for x, y, r in zip(xs, ys, front):
            ax.annotate(r["label"], (x, y), textcoords="offset points", xytext=(3, 3), fontsize=6.5)
    log_log(ax)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel, fontsize=9)
    ax.set_ylabel(f"RMSE against its own reference (0 drawn at {PLOT_FLOOR:g})", fontsize=9)


def plot(rows, fig) -> None:
    """Per scene (rows of panels): RMSE against ms (incl. the extra layers' render) and against
    taps per pixel, over the whole frame and in the thin-feature band, the fronts drawn."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    axes = fig.subplots(len(scenes), 4, squeeze=False)
    for i, scene in enumerate(scenes):
        sel = [r for r in rows if r["scene"] == scene and r["kind"] == "estimate"]
        name = SCENE_TITLES.get(scene, scene)
        for j, (col, cost, err) in enumerate(FRONTS):
            where = "thin-feature band" if err == "thin_rmse" else "whole frame"
            xlabel = "ms (estimator + extra layers' render)" if cost.startswith("seconds") else "depth taps / pixel"
            _panel(axes[i, j], sel, cost, err, col, title=f"{name}: {where}", xlabel=xlabel)
    handles = [Patch(color=c, label=f) for f, c in _FAMILY_COLORS.items()]
    handles += [Line2D([], [], ls="", marker=m, color="0.4", label=k) for k, m in _KIND_MARKERS.items()]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=9)
    meta = getattr(rows, "meta", {}) or {}
    size = "x".join(str(s) for s in meta.get("size", ())) or "?"
    fig.suptitle(f"Thin geometry: time and taps against RMSE (each against its own reference), fronts in black; "
                 f"{size}, median of {meta.get('repeats', '?')} repeats", fontsize=12)


make = deprecated_make(__name__)
