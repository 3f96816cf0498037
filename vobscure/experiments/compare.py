"""``vobscure compare``: the speed/accuracy trade of the screen-space estimators on one scene.

For one scene and camera, the G-buffer is rendered once; the references a request names are
computed once per radius (and cached on disk, see :mod:`vobscure.experiments.cache`); every
configuration (method x samples x radius) is run ``repeats`` times and its median time kept;
every error metric is measured against every reference; and the error is split into the
steps that cause it (:func:`vobscure.metrics.decompose`): sampling (estimate vs the converged
screen-space VO), screen space (that vs the world-space VO) and model (world-space VO vs AO).

Outputs (all written atomically into ``out``): ``results.csv``, ``results.md``,
``tradeoff.png`` (error against time and against depth texels read per pixel, one curve per method,
the Pareto front marked), ``gallery.png`` (each estimate beside the references and its error
map) and ``provenance.json``. With ``orbit`` > 1, a camera orbit of that many frames also
measures temporal stability (:func:`vobscure.metrics.flicker`).
"""

from __future__ import annotations

import io
import json
import math
import os
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._validate import check_choice, check_int, check_positive

__all__ = ["Method", "parse_methods", "compare", "CompareResult", "DEFAULT_METHODS", "REFERENCES",
           "pareto_front", "orbit_cameras"]

METHODS = ("point", "line", "area")
#: The paper's Table 1 configurations (Loos & Sloan 2010): points 12 and 33, lines 5 and 9, area 1.
DEFAULT_METHODS = "point:12,point:33,line:5,line:9,area:1"
#: Reference quantities: the converged screen-space VO, the world-space VO (Embree), ray-cast
#: AO within the radius, and obscurance with a linear falloff.
REFERENCES = ("screen", "volumetric", "ao", "obscurance")
DEFAULT_REFERENCES = ("screen", "volumetric", "ao")
#: Depth-buffer texels one tap (sample) reads with each method's default fetch: points
#: bilinear (4), lines nearest (1), vo_area's B-spline mip lookup 2 levels x 3 x 3 (18, of 3
#: channels); as in :mod:`vobscure.experiments.sweep` and ``benchmarks/bench_screenspace.py``.
TEXELS_PER_SAMPLE = {"point": 4, "line": 1, "area": 18}
#: Default radius as a fraction of the scene's extent (as ``vobscure render``).
RADIUS_FRACTION = 0.1
#: Sizes of the default and the quick run.
DEFAULT_SIZE = (256, 256)
QUICK_SIZE = (64, 64)
#: Metrics kept per reference.
METRICS = ("rmse", "mae", "bias", "ssim")


@dataclass(frozen=True)
class Method:
    """One estimator and sample count, e.g. ``Method("line", 9)`` (written ``line:9``)."""

    name: str
    samples: int

    def __post_init__(self):
        check_choice(self.name, "method", METHODS)
        check_int(self.samples, "samples")

    @property
    def label(self) -> str:
        return f"{self.name}:{self.samples}"

    @property
    def taps(self) -> int:
        """Depth-buffer taps (fetches) per pixel: one per sample, except the centre of an
        odd point pattern, which ``vo_point`` does not tap (it lies on the surface)."""
        if self.name == "point":
            from ..screenspace import point_taps

            return point_taps(self.samples)
        return self.samples

    @property
    def texels(self) -> int:
        """Depth-buffer texels read per pixel: taps x texels per tap."""
        return TEXELS_PER_SAMPLE[self.name] * self.taps

    def run(self, gbuffer, *, radius, normal_clamp, thickness, seed):
        from .. import screenspace

        fn = {"point": screenspace.vo_point, "line": screenspace.vo_line, "area": screenspace.vo_area}[self.name]
        return fn(gbuffer, radius=radius, samples=self.samples, normal_clamp=normal_clamp,
                  thickness=thickness, seed=seed)


def parse_methods(spec) -> tuple[Method, ...]:
    """``"point:12,line:5"`` (or a list of such strings / Methods) -> Methods.

    Examples
    --------
    >>> [m.label for m in parse_methods("point:12, line:5,area:1")]
    ['point:12', 'line:5', 'area:1']
    """
    if isinstance(spec, str):
        items = [s.strip() for s in spec.split(",") if s.strip()]
    else:
        items = list(spec)
    if not items:
        raise ValueError("--methods must name at least one method, e.g. 'line:9,point:12'")
    out = []
    for item in items:
        if isinstance(item, Method):
            out.append(item)
            continue
        name, sep, count = str(item).partition(":")
        if not sep or not count.strip().isdigit():
            raise ValueError(f"--methods entry {item!r} must be NAME:SAMPLES with NAME one of "
                             f"{', '.join(METHODS)} and SAMPLES a positive integer, e.g. 'line:9'")
        if name.strip() not in METHODS:
            raise ValueError(f"--methods entry {item!r}: unknown method {name.strip()!r}; "
                             f"expected one of {', '.join(METHODS)}")
        out.append(Method(name.strip(), int(count)))
    if len(set(out)) != len(out):
        raise ValueError(f"--methods lists a configuration twice: {', '.join(m.label for m in out)}")
    return tuple(out)


def pareto_front(cost, error) -> np.ndarray:
    """Indices of the configurations no other beats in both cost and error, by cost.

    Examples
    --------
    >>> pareto_front([1, 2, 3, 4], [0.5, 0.6, 0.2, 0.1]).tolist()
    [0, 2, 3]
    """
    cost = np.asarray(cost, dtype=float)
    error = np.asarray(error, dtype=float)
    ok = np.flatnonzero(np.isfinite(cost) & np.isfinite(error))
    order = ok[np.lexsort((error[ok], cost[ok]))]
    front, best = [], np.inf
    for i in order:
        if error[i] < best:
            front.append(int(i))
            best = error[i]
    return np.array(front, dtype=np.intp)


def orbit_cameras(camera, frames: int, *, degrees: float = 10.0):
    """``frames`` cameras turning about the vertical axis through the target, ``degrees`` in all."""
    from ..camera import Camera

    d = camera.to_dict()
    eye, target = np.array(d["eye"], float), np.array(d["target"], float)
    rel = eye - target
    out = []
    for t in np.linspace(-0.5, 0.5, frames) * math.radians(degrees):
        c, s = math.cos(t), math.sin(t)
        e = target + np.array([c * rel[0] + s * rel[2], rel[1], -s * rel[0] + c * rel[2]])
        kw = dict(fov_y=d["fov_y"]) if d["ortho_height"] is None else dict(ortho_height=d["ortho_height"])
        out.append(Camera.look_at(e, target, d["up"], size=tuple(d["size"]), **kw))
    return out


@dataclass
class CompareResult:
    """What :func:`compare` measured: one row per configuration, and where it wrote them."""

    rows: list
    files: dict
    provenance: dict
    references: dict = field(repr=False, default_factory=dict)
    images: dict = field(repr=False, default_factory=dict)


def _references(scene, gb, radius, references, *, normal_clamp, thickness, rays, samples,
                screen_samples, seed, cache, progress):
    """The requested reference images at one radius: {name: (H, W) array}, and cache hits."""
    from .cache import ground_truth_cached, screen_reference_cached

    refs, hits = {}, {}
    for name in references:
        if name == "screen":
            est, hits[name] = screen_reference_cached(
                gb, scene, cache=cache, radius=radius, samples=screen_samples, normal_clamp=normal_clamp,
                thickness=thickness, seed=seed)
            refs[name] = est.value
        elif name == "volumetric":
            est, hits[name] = ground_truth_cached(scene, gb, cache=cache, quantity="volumetric", radius=radius,
                                                  samples=samples, normal_clamp=normal_clamp, seed=seed,
                                                  progress=progress)
            refs[name] = est.value
        else:   # ao within the radius, obscurance with the linear falloff
            est, hits[name] = ground_truth_cached(scene, gb, cache=cache, quantity=name, radius=radius,
                                                  rays=rays, seed=seed, progress=progress)
            refs[name] = est.value
    return refs, hits


def _time(fn, repeats):
    """Median seconds of ``repeats`` calls after one untimed warm-up call (pattern tables,
    caches), and the last result."""
    fn()
    times, value = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), value


def _primary(references) -> str:
    for name in ("volumetric", "screen", "ao", "obscurance"):
        if name in references:
            return name
    raise AssertionError("no reference")


def compare(scene="cornell_box", *, camera=None, size=None, radii=None, methods=DEFAULT_METHODS,
            normal_clamp: bool = False, thickness=None, references=DEFAULT_REFERENCES, repeats: int = 3,
            rays: int = 256, samples: int = 1024, screen_samples: int = 2048, seed: int = 0,
            orbit: int = 0, quick: bool = False, out=None, cache=True, progress: bool = True,
            plots: bool = True, write: bool = True) -> CompareResult:
    """Measure error, time and taps per pixel of screen-space estimators on one scene.

    Parameters
    ----------
    scene : str, path or Scene
        A built-in scene name, a mesh file, or a :class:`vobscure.scenes.Scene`.
    camera : Camera, optional
        Default: the scene's suggested camera at ``size``.
    size : (int, int), optional
        (width, height); default 256 x 256 (64 x 64 with ``quick``).
    radii : sequence of float, optional
        Ball radii; default 0.1 x the scene's extent.
    methods : str or sequence
        ``"point:12,point:33,line:5,line:9,area:1"`` (the paper's Table 1) by default.
    normal_clamp, thickness
        Passed to every estimator and to the references they are compared with.
    references : sequence of {"screen", "volumetric", "ao", "obscurance"}
        Only these are computed. The error decomposition needs "screen" and "volumetric"
        (its model term also "ao").
    repeats : int
        Timed runs per configuration; the median is kept.
    rays, samples, screen_samples : int
        Rays per pixel of AO/obscurance, ball samples of the world-space VO, samples of the
        screen-space reference.
    seed : int
    orbit : int
        With N > 1, N frames of a 10-degree camera orbit measure the flicker of each
        configuration (minus the screen-space reference's own frame-to-frame change).
    quick : bool
        64 x 64, one repeat, fewer rays and samples: the whole run in seconds.
    out : path, optional
        Output folder; default ``./vobscure-out/compare-<scene>``.
    cache : bool, path or ReferenceCache
        True: the default user cache folder; a path: that folder; False: no cache.
    progress : bool
    plots : bool
        Write the PNGs.
    write : bool
        False: write nothing at all (figure modules use the rows directly).

    Returns
    -------
    CompareResult

    Examples
    --------
    >>> import vobscure as vo, tempfile
    >>> res = vo.experiments.compare.compare("slab", size=(16, 16), methods="line:5", quick=True,
    ...                                      references=("screen",), cache=False, progress=False,
    ...                                      out=tempfile.mkdtemp(), plots=False)
    >>> r = res.rows[0]
    >>> r["method"], r["samples"], r["taps_per_pixel"], r["texels_per_pixel"]
    ('line', 5, 5, 5)
    """
    from .. import render_gbuffer
    from ..metrics import decompose, error, flicker
    from .cache import ReferenceCache

    methods = parse_methods(methods)
    references = tuple(references)
    if not references:
        raise ValueError("references must name at least one of " + ", ".join(REFERENCES))
    for name in references:
        check_choice(name, "references", REFERENCES)
    repeats = check_int(repeats, "repeats")
    orbit = check_int(orbit, "orbit", minimum=0) if orbit else 0
    if thickness is not None:
        thickness = check_positive(thickness, "thickness")
    if quick:
        repeats, rays, samples, screen_samples = 1, min(rays, 64), min(samples, 256), min(screen_samples, 512)
        orbit = min(orbit, 4) if orbit else 0
    sc, scene_name = _scene(scene)
    if camera is None:
        size = tuple(size) if size is not None else (QUICK_SIZE if quick else DEFAULT_SIZE)
        camera = sc.camera(size)
    if radii is None:
        radii = (RADIUS_FRACTION * sc.extent,)
    radii = tuple(check_positive(r, "radius") for r in np.atleast_1d(radii))
    if isinstance(cache, ReferenceCache):
        store = cache
    elif cache is True:
        store = ReferenceCache()
    elif cache is False or cache is None:
        store = ReferenceCache(enabled=False)
    else:
        store = ReferenceCache(cache)
    out = Path(out) if out is not None else Path("vobscure-out") / f"compare-{scene_name}"

    t_start = time.perf_counter()
    gb = render_gbuffer(sc, camera)
    primary = _primary(references)
    rows, images, all_refs, hits = [], {}, {}, {}
    steps = len(radii) * len(methods)
    bar = _bar(steps, "compare", progress)
    for radius in radii:
        refs, h = _references(sc, gb, radius, references, normal_clamp=normal_clamp, thickness=thickness,
                              rays=rays, samples=samples, screen_samples=screen_samples, seed=seed,
                              cache=store, progress=progress)
        all_refs[radius] = refs
        hits[radius] = h
        for m in methods:
            seconds, est = _time(lambda: m.run(gb, radius=radius, normal_clamp=normal_clamp,
                                               thickness=thickness, seed=seed), repeats)
            row = dict(method=m.name, samples=m.samples, radius=float(radius), normal_clamp=bool(normal_clamp),
                       thickness=thickness, seconds=seconds, taps_per_pixel=m.taps,
                       texels_per_pixel=m.texels)
            for name, ref in refs.items():
                rep = error(est, ref)
                for metric in METRICS:
                    row[f"{name}_{metric}"] = float(getattr(rep, metric))
            if "screen" in refs and "volumetric" in refs:
                dec = decompose(est, refs["screen"], refs["volumetric"], ao=refs.get("ao"),
                                obscurance=refs.get("obscurance"))
                for term in ("sampling", "screen", "model", "total"):
                    if term in dec.summary:
                        row[f"{term}_error_rmse"] = dec.summary[term].rmse
                        row[f"{term}_error_bias"] = dec.summary[term].bias
            rows.append(row)
            images[(radius, m.label)] = est
            bar.update(1)
    bar.close()

    if orbit > 1:
        _orbit(sc, camera, rows, methods, radii, orbit, normal_clamp=normal_clamp, thickness=thickness,
               screen_samples=screen_samples, seed=seed, progress=progress, flicker=flicker)

    provenance = dict(
        command="vobscure compare", scene=scene_name, camera=camera.to_dict(), radii=list(radii),
        methods=[m.label for m in methods], normal_clamp=bool(normal_clamp), thickness=thickness,
        references=list(references), primary_reference=primary, repeats=repeats, rays=rays, samples=samples,
        screen_samples=screen_samples, seed=seed, orbit=orbit, quick=bool(quick),
        cache=None if not store.enabled else str(store.directory),
        cache_hits={f"{r:g}": h for r, h in hits.items()}, seconds=time.perf_counter() - t_start,
        machine=_machine(), date=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    files = _write(out, rows, provenance, all_refs, images, gb, primary, plots) if write else {}
    return CompareResult(rows=rows, files=files, provenance=provenance, references=all_refs, images=images)


def _orbit(sc, camera, rows, methods, radii, frames, *, normal_clamp, thickness, screen_samples, seed,
           progress, flicker):
    """Add ``flicker`` (estimate minus reference) and ``flicker_raw`` to every row."""
    from .. import render_gbuffer, vo_reference

    cams = orbit_cameras(camera, frames)
    seq = {key: [] for key in [(r, m.label) for r in radii for m in methods]}
    refs = {r: [] for r in radii}
    bar = _bar(frames, "orbit", progress)
    for cam in cams:
        gb = render_gbuffer(sc, cam)
        for r in radii:
            refs[r].append(vo_reference(gb, radius=r, samples=screen_samples, normal_clamp=normal_clamp,
                                        thickness=thickness, seed=seed).value)
            for m in methods:
                seq[(r, m.label)].append(m.run(gb, radius=r, normal_clamp=normal_clamp, thickness=thickness,
                                               seed=seed))
        bar.update(1)
    bar.close()
    for row in rows:
        key = (row["radius"], f"{row['method']}:{row['samples']}")
        f = flicker(np.stack(seq[key]), np.stack(refs[row["radius"]]))
        row["flicker"] = float(f.value)
        row["flicker_raw"] = float(f.estimate_change)


def _scene(scene):
    from ..scenes import Scene, get, load, names

    if isinstance(scene, Scene):
        return scene, "custom"
    spec = str(scene)
    if spec in names():
        return get(spec), spec
    path = Path(spec)
    if path.suffix or path.exists():
        return load(path), path.stem
    raise ValueError(f"scene {spec!r} is neither a built-in scene ({', '.join(names())}) nor a mesh file")


def _bar(total, desc, enabled):
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, disable=not enabled, leave=False)


def _machine() -> dict:
    import numpy
    import scipy

    from .. import __version__

    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cores = os.cpu_count()
    return dict(cores=cores, machine=platform.machine(), python=platform.python_version(),
                numpy=numpy.__version__, scipy=scipy.__version__, vobscure=__version__)


# --------------------------------------------------------------------------- writing
def _columns(rows) -> list:
    cols = []
    for row in rows:
        for k in row:
            if k not in cols:
                cols.append(k)
    return cols


def _csv_text(rows) -> str:
    import csv

    buf = io.StringIO()
    cols = _columns(rows)
    w = csv.DictWriter(buf, fieldnames=cols, lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow({k: ("" if row.get(k) is None else row.get(k)) for k in cols})
    return buf.getvalue()


def _fmt(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if not math.isfinite(v):
            return "nan"
        return f"{v:.4g}"
    return str(v)


def _markdown(rows, provenance) -> str:
    cols = [c for c in _columns(rows) if c not in ("normal_clamp", "thickness")]
    lines = [f"# vobscure compare: {provenance['scene']}", "",
             f"Camera {provenance['camera']['size'][0]} x {provenance['camera']['size'][1]}, "
             f"normal clamp: {_fmt(provenance['normal_clamp'])}, thickness: {'none' if provenance['thickness'] is None else _fmt(provenance['thickness'])}, "
             f"median of {provenance['repeats']} run(s), seed {provenance['seed']}. "
             f"Errors are against each reference (`<reference>_<metric>`); the decomposition "
             f"columns split the error into sampling + screen space + model.", "",
             "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for row in rows:
        lines.append("| " + " | ".join(_fmt(row.get(c)) for c in cols) + " |")
    mach = provenance["machine"]
    lines += ["", "Machine: " + ", ".join(f"{k} {v}" for k, v in mach.items()) + ".", ""]
    return "\n".join(lines)


def _write(out: Path, rows, provenance, refs, images, gb, primary, plots) -> dict:
    from .._io import atomic_write

    out.mkdir(parents=True, exist_ok=True)
    files = {}
    files["results.csv"] = atomic_write(out / "results.csv", lambda fh: fh.write(_csv_text(rows).encode()))
    files["results.md"] = atomic_write(out / "results.md", lambda fh: fh.write(_markdown(rows, provenance).encode()))
    if plots:
        files["tradeoff.png"] = _tradeoff(out / "tradeoff.png", rows, provenance)
        files["gallery.png"] = _gallery(out / "gallery.png", rows, refs, images, gb, primary)
    text = json.dumps(provenance, indent=2, sort_keys=True, default=_json_default)
    files["provenance.json"] = atomic_write(out / "provenance.json", lambda fh: fh.write(text.encode()))
    return files


def _json_default(v):
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return str(v)


def _figure(width, height):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path):
    from .._io import atomic_write

    return atomic_write(path, lambda fh: fig.savefig(fh, format="png"))


_METHOD_COLORS = {"point": "#d62728", "line": "#1f77b4", "area": "#2ca02c"}
_RADIUS_MARKERS = "os^Dv<>"


def _tradeoff(path, rows, provenance):
    refs = [r for r in provenance["references"]]
    from matplotlib.ticker import LogLocator, NullFormatter

    costs = (("seconds", "median seconds per frame"), ("taps_per_pixel", "depth taps per pixel"),
             ("texels_per_pixel", "depth texels read per pixel"))
    fig = _figure(4.2 * len(costs), 3.2 * len(refs) + 0.6)
    axes = fig.subplots(len(refs), len(costs), squeeze=False)
    radii = sorted({row["radius"] for row in rows})
    for i, ref in enumerate(refs):
        for j, (cost, label) in enumerate(costs):
            ax = axes[i, j]
            x = np.array([row[cost] for row in rows], float)
            y = np.array([row[f"{ref}_rmse"] for row in rows], float)
            for name in METHODS:
                for k, radius in enumerate(radii):
                    sel = [n for n, row in enumerate(rows) if row["method"] == name and row["radius"] == radius]
                    if not sel:
                        continue
                    sel = sorted(sel, key=lambda n: rows[n]["samples"])
                    ax.plot(x[sel], y[sel], "-", marker=_RADIUS_MARKERS[k % len(_RADIUS_MARKERS)],
                            color=_METHOD_COLORS[name], label=f"{name} (R={radius:.3g})")
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
            ax.set_ylabel(f"RMSE vs {ref}")
            ax.grid(alpha=0.3)
            if i == 0 and j == 0:
                ax.legend(fontsize=7)
    fig.suptitle(f"{provenance['scene']}: error against cost (labels: samples)")
    return _save(fig, path)


def _gallery(path, rows, refs, images, gb, primary):
    radius = rows[0]["radius"]
    ref_imgs = refs[radius]
    configs = [f"{row['method']}:{row['samples']}" for row in rows if row["radius"] == radius]
    ncol = max(len(ref_imgs), 4)
    nrow = 1 + math.ceil(len(configs) / max(ncol // 2, 1))
    per_row = max(ncol // 2, 1)
    fig = _figure(2.2 * ncol, 2.3 * nrow)
    axes = fig.subplots(nrow, ncol, squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    bg = ~gb.valid
    for k, (name, img) in enumerate(ref_imgs.items()):
        axes[0, k].imshow(np.ma.masked_where(bg, img), cmap="gray", vmin=0, vmax=1)
        axes[0, k].set_title(f"reference: {name}", fontsize=8)
    for n, label in enumerate(configs):
        r, c = 1 + n // per_row, 2 * (n % per_row)
        est = images[(radius, label)]
        diff = est - ref_imgs[primary]
        rmse = float(np.sqrt(np.nanmean(diff ** 2)))
        axes[r, c].imshow(np.ma.masked_where(bg, est), cmap="gray", vmin=0, vmax=1)
        axes[r, c].set_title(label, fontsize=8)
        lim = max(float(np.nanmax(np.abs(diff))) if np.isfinite(diff).any() else 0.0, 1e-6)
        axes[r, c + 1].imshow(np.ma.masked_where(bg, diff), cmap="RdBu_r", vmin=-lim, vmax=lim)
        axes[r, c + 1].set_title(f"error vs {primary}: RMSE {rmse:.3f}", fontsize=8)
    fig.suptitle(f"R = {radius:.3g}: estimates and their error maps (red: too open)")
    return _save(fig, path)
