"""Screen-space performance of vobscure: time against a NumPy "gather floor", taps, memory.

The machine this runs on is shared and noisy, so the time results are *ratios* of two
timings taken in the same run, with the compared calls interleaved round by round so that
load changes hit both alike. Absolute times are printed too, but only as context. Unlike
``bench_groundtruth.py``, the statistic is the **median** over ``--repeats`` rounds, not
the best (the "best" of each is kept in :class:`Timing` for context).

What is measured (DESIGN.md, "Performance")
-------------------------------------------
Scene ``vo.scenes.cornell_box()`` with its suggested camera ``scene.camera((W, H))``, at
512^2 and 1024^2 (256^2 and 512^2 with ``--quick``), ``radius`` 0.3 (about 0.08 of the
scene's extent; ``--radius``). The configurations are registry configurations
(:class:`vobscure.methods.Config`: a method and a sample count, each method's default
fetch) -- ``point:12``, ``point:33``, ``line:5``, ``line:9``, ``area:1`` -- each with
``normal_clamp`` False and True, run through ``Config.run`` (``randomize`` on, every other
argument at its default); then the engines' baselines without the clamp: ``gtao:3``,
``vbao:3`` and ``sao:12`` (goal: within 2x of the floor of their own reads) and ``alchemy:12`` (reported,
no goal). Every configuration runs once on a 16^2 render before anything
is measured (sample patterns and caches built), and each timed call has one more untimed
warm-up call (:func:`vobscure.experiments.common.time_calls`).

Per configuration:

- **median s**: median wall time of one call (G-buffer given; everything inside the
  estimator included). **cores**: process CPU time / wall time in the median round: how
  many cores the call actually got.
- **taps/px** and **texels/px**: the registry's cost model (``Config.taps``,
  ``Config.texels``; DESIGN.md): depth-buffer taps per pixel (one per sample, less the
  centre of an odd point pattern, which ``vo_point`` does not tap; one mip lookup per area
  sample) and the depth texels they read (``vobscure.methods.TEXELS_PER_TAP`` of the fetch:
  nearest 1, bilinear 2 x 2 = 4, ``vo_area``'s B-spline lookup 2 levels x 3 x 3 = 18).
  Building the mip-map (one pass over 4/3 of the image) is a per-frame cost, not a tap.
- **reads/px**: the elements the estimator actually gathers from the depth buffer (or from
  the moments mip-map) per valid pixel, *counted* in a separate untimed call: the depth
  arrays of the estimators' per-chunk pixels, ``vo_line``'s bordered depth copy and the
  mip-map's channels are replaced by views that count what integer-array indexing and
  ``take`` return (once per configuration, on a 128^2 render: the count per pixel does not
  depend on the size). This is white-box instrumentation, an independent check of the
  registry's texel model; it patches library internals found by attribute
  (:func:`_internals`), and prints a NOTE instead of a count if they have moved.
- **floor s** and **x floor**: the NumPy "gather floor" for ``texels/px`` one-texel reads
  and the estimator's median time over it. The floor is :func:`gather_floor`: for each of
  the T reads, continuous pixel coordinates of every valid pixel (centre + offset x
  radius_px), floored to integer indices, clipped to the image, and ``depth[i, j]``
  gathered, nothing else, over the flat arrays of the valid pixels (:func:`valid_pixels`,
  from the public G-buffer and camera, built outside the timing and timed alone as
  context). The T offsets are a golden-angle spiral filling the unit disk, the same for
  every pixel (no per-pixel randomization: neighbouring pixels read neighbouring texels,
  so the floor is slightly kinder to the cache than the randomized estimators). Goal:
  ``vo_line`` within 1.5x of its floor.
- **peak B/px**: peak extra memory per pixel: ``tracemalloc`` (NumPy reports its buffers to
  it) is started after the G-buffer is built and the sample patterns are cached, the
  estimator runs once, and the peak of traced memory is divided by W x H. It includes the
  estimator's per-pixel arrays and the returned image (8 B/px in float64). Goal: under
  100 B/px and not growing with the sample count (at most ``GOAL_GROWTH_BYTES`` = 1 B/px
  more): point 12 vs 33, line 5 vs 9, and line 33 vs 65 (memory only) side by side.

The registry's texels against the counted reads
-----------------------------------------------
The two count different things, and differ by fixed factors (measured: line 1.000, point
1.000, area 3.000, clamped area 10.000, at every sample count):

- **nearest** (``vo_line``): one read per texel, reads = texels.
- **bilinear** (``vo_point``, ``gtao``, ``vbao``): 4 reads per tap, the 2 x 2 texels around
  it (what a GPU's bilinear fetch reads); the texel containing the tap, one of the four, is
  gathered again only where one of them is background (the value the fetch falls back to
  there): none on the Cornell box's frames, whose pixels are all valid.
- **mip-map lookup** (``vo_area``): 54 reads per lookup = 18 texels x 3 channels (coverage,
  mean, central second moment of 1/z), 180 = 18 x 10 channels with ``normal_clamp`` (the
  pixel positions' means and the 3 x 3 central moments of (q, X, Y) are mipped too). The
  model counts a texel once whatever it holds, as a GPU fetch of a multi-channel texel;
  the NumPy code keeps each channel in its own array, so each channel is a gather.

Run from the repository root::

    python benchmarks/bench_screenspace.py            # 512^2 and 1024^2, a few minutes
    python benchmarks/bench_screenspace.py --quick    # 256^2 and 512^2, under 60 s
    python benchmarks/bench_screenspace.py --repeats 5 --radius 0.3
    python benchmarks/bench_screenspace.py --only gtao:3,sao:12,alchemy:12   # some rows only

``--only`` times the configurations named (registry labels, as printed; the timed set is
the same as in a full run, minus the others) and reports only the goals that concern them.

The exit code is 0 unless something raises; no timing is asserted.
"""

from __future__ import annotations

import dataclasses
import os
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source tree
sys.path.insert(0, str(Path(__file__).resolve().parent))      # the shared _bench module

import _bench  # noqa: E402
import vobscure as vo  # noqa: E402
from _bench import Timing, interleaved, peak_bytes  # noqa: E402
from vobscure.methods import Config  # noqa: E402

FULL_SIZES = (512, 1024)
QUICK_SIZES = (256, 512)
RADIUS = 0.3
#: the timed configurations (registry Configs, each method's default fetch), each run with
#: normal_clamp False and True
CONFIGS = (Config("point", 12), Config("point", 33), Config("line", 5), Config("line", 9), Config("area", 1))
#: the engines' baselines, timed without the normal clamp (they estimate AO, which
#: has no clamp): GTAO "high" (3 slices x 3 steps a side), VBAO on the same taps (32 sectors,
#: a bitmask per slice) and SAO with 12 taps
BASELINES = (Config("gtao", 3), Config("vbao", 3), Config("sao", 12))
#: baselines timed beside them without a goal: Alchemy AO with 12 taps shares SAO's code
#: path (a disk of nearest taps, a sum of a term of v = Q - C)
BASELINE_NOTES = (Config("alchemy", 12),)
#: configurations measured for memory only, to show the trend with samples
MEMORY_CONFIGS = (Config("line", 33), Config("line", 65))
#: peak memory of the second of each pair minus the first's: "not growing with samples"
GROWTH_PAIRS = ((Config("point", 12), Config("point", 33)), (Config("line", 5), Config("line", 9)),
                (Config("line", 33), Config("line", 65)))
#: image edge of the render on which the reads per pixel are counted
READS_SIZE = 128
#: goals
GOAL_LINE_FLOOR = 1.5
#: the baselines against the gather floor of their own taps (horizon marching is sequential)
GOAL_BASELINE_FLOOR = 2.0
GOAL_BYTES_PER_PIXEL = 100.0
#: "not growing with samples": more samples may cost at most this many bytes per pixel more
GOAL_GROWTH_BYTES = 1.0


# --------------------------------------------------------------------------- configurations
@dataclass(frozen=True)
class Bench:
    """A registry configuration with the ``normal_clamp`` it runs with."""

    config: Config
    clamp: bool = False

    @property
    def name(self) -> str:          # e.g. "line:9 clamp"
        return f"{self.config.label}{' clamp' if self.clamp else ''}"

    @property
    def method(self) -> str:
        return self.config.method

    def call(self, gb, radius: float):
        """The estimator on ``gb``: the registry's ``Config.run``, randomize on, every
        argument but the samples, the radius and normal_clamp at its default."""
        return self.config.run(gb, radius=radius, normal_clamp=self.clamp)


#: labels of the configurations to time (``--only``); None: every one
ONLY = None


def configurations() -> list[Bench]:
    """Every timed configuration, without and then with the normal clamp (those of ``--only``
    when it is given)."""
    every = ([Bench(cfg, clamp) for clamp in (False, True) for cfg in CONFIGS]
             + [Bench(cfg) for cfg in BASELINES + BASELINE_NOTES])
    return every if ONLY is None else [b for b in every if b.name in ONLY]


def warm_up(radius: float):
    """Run every configuration once on a 16 x 16 render: the sample patterns and other
    caches are built outside the timings and the memory traces."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((16, 16)))
    for b in configurations() + [Bench(cfg) for cfg in _memory_configs()]:
        b.call(gb, radius)


def _memory_configs():
    """The memory-only configurations, unless ``--only`` leaves out the lines."""
    return MEMORY_CONFIGS if ONLY is None else ()


# --------------------------------------------------------------------------- the gather floor
@dataclass(frozen=True)
class FloorPixels:
    """The valid pixels of a G-buffer, flattened, from the public G-buffer and camera: the
    depth buffer in float64 (NaN as +inf), the pixel centres and the radius in pixels."""

    cx: np.ndarray
    cy: np.ndarray
    radius_px: np.ndarray
    depth: np.ndarray


def valid_pixels(gb, radius: float) -> FloorPixels:
    """The per-pixel setup every estimator starts with (valid pixels, their centres, the
    ball radius projected at their depth), here as the floor's input."""
    depth = np.asarray(gb.depth, dtype=np.float64)
    depth = np.where(np.isnan(depth), np.inf, depth)
    index = np.flatnonzero(np.isfinite(depth) & (depth > 0))
    i, j = np.divmod(index, depth.shape[1])
    radius_px = radius * gb.camera.pixels_per_unit(depth.reshape(-1)[index])
    return FloorPixels(j + 0.5, i + 0.5, radius_px, depth)


def spiral(count: int) -> np.ndarray:
    """``count`` offsets (count, 2) filling the unit disk evenly (golden-angle spiral)."""
    i = np.arange(count) + 0.5
    r = np.sqrt(i / count)
    a = i * np.pi * (3.0 - np.sqrt(5.0))
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def gather_floor(px: FloorPixels, offsets: np.ndarray) -> np.ndarray:
    """The time floor of ``len(offsets)`` one-texel reads per pixel: index arithmetic and gathers.

    For each (ox, oy) of ``offsets`` (unit-disk offsets): continuous pixel coordinates
    centre + offset x radius_px of every valid pixel, floored to integer indices, clipped
    to the image, and the depth gathered. Nothing else (no projection, no warp, no integral,
    no accumulation). Returns the last gather, so that nothing can be skipped.
    """
    H, W = px.depth.shape
    d = None
    for ox, oy in offsets:
        j = np.clip(np.floor(px.cx + ox * px.radius_px), 0, W - 1).astype(np.intp)
        i = np.clip(np.floor(px.cy - oy * px.radius_px), 0, H - 1).astype(np.intp)
        d = px.depth[i, j]
    return d


# --------------------------------------------------------------------------- counting reads
class _Counting(np.ndarray):
    """An ndarray view that counts the elements integer-array indexing and take() return."""

    total = 0          # class-wide counter (reset by reads_per_pixel)
    _counting = False  # the views made by _count() and views of them (reshape, ravel,
                       # slices); arrays computed from them (ufuncs) do not count

    def __array_finalize__(self, obj):
        self._counting = bool(getattr(obj, "_counting", False)) and self.base is obj

    def __getitem__(self, key):
        out = super().__getitem__(key)
        if self._counting:
            keys = key if isinstance(key, tuple) else (key,)
            if any(isinstance(k, np.ndarray) and k.dtype.kind in "iu" for k in keys):
                _Counting.total += np.size(out)
                return np.asarray(out).view(np.ndarray)
        return out

    def take(self, indices, *args, **kwargs):
        out = np.ndarray.take(self.view(np.ndarray), indices, *args, **kwargs)
        if self._counting:
            _Counting.total += np.size(out)
        return out


def _count(a):
    v = a.view(_Counting)
    v._counting = True
    return v


def _internals():
    """The library internals the read counter patches, found where the estimators find them.

    Counting gathers is white-box by nature: no public API hands out the arrays the
    estimators index. The counter reaches, by attribute and not by import, (1) the
    estimators' shared module (``vobscure.screenspace.line.C``, the module whose
    ``prepare`` every estimator calls for its per-chunk pixels and whose ``PaddedDepth``
    holds ``vo_line``'s bordered depth copy), (2) ``vo_area``'s mip-map class
    (``vobscure.screenspace.pyramid.MomentPyramid``) and (3) the module of ``sao`` and ``alchemy``,
    whose ``_background_as_nan`` makes the depth copy their taps read. If a refactoring moves them the count fails
    with a NOTE and the rest of the benchmark runs.
    """
    import importlib

    from vobscure.screenspace import area, line

    return line.C, area.MomentPyramid, importlib.import_module("vobscure.screenspace.sao")


@contextmanager
def counting_reads():
    """While active, the depth arrays of prepare()'s result, vo_line's padded depth copy and
    the area mip-map's arrays count the elements gathered from them. Patches class and
    module attributes only, and restores them."""
    common, pyramid, sao_module = _internals()
    original_prepare, original_build = common.prepare, pyramid._build
    original_padded = common.PaddedDepth.__init__
    original_nan = sao_module._background_as_nan

    def prepare(*args, **kwargs):
        px = original_prepare(*args, **kwargs)
        images = {f.name: _count(getattr(px, f.name)) for f in dataclasses.fields(px)
                  if f.name.startswith("depth") and isinstance(getattr(px, f.name), np.ndarray)}
        return dataclasses.replace(px, **images)

    def build(self, *args, **kwargs):
        # the pyramid's channels: self.c and the lists self.m, self.v (built by _build, which
        # both __init__ and from_depth call)
        original_build(self, *args, **kwargs)
        for name, value in list(vars(self).items()):
            if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                setattr(self, name, _count(value))
            elif isinstance(value, list) and value and all(isinstance(x, np.ndarray) for x in value):
                setattr(self, name, [_count(x) if x.dtype.kind == "f" else x for x in value])

    def padded_init(self, *args, **kwargs):
        # vo_line's snapped taps read a bordered copy of the depth buffer (PaddedDepth.flat)
        original_padded(self, *args, **kwargs)
        self.flat = _count(self.flat)

    def background_as_nan(*args, **kwargs):
        # sao's and alchemy's taps read a copy of the depth buffer with background as NaN
        return _count(original_nan(*args, **kwargs))

    patched = [(common, "prepare", original_prepare), (pyramid, "_build", original_build),
               (common.PaddedDepth, "__init__", original_padded),
               (sao_module, "_background_as_nan", original_nan)]
    common.prepare, pyramid._build, common.PaddedDepth.__init__ = prepare, build, padded_init
    sao_module._background_as_nan = background_as_nan
    try:
        yield
    finally:
        for owner, name, value in patched:
            setattr(owner, name, value)


def reads_per_pixel(b: Bench, gb, radius: float, pixels: int) -> float | None:
    """Elements gathered from the depth buffer (or mip-map) per valid pixel, or None."""
    try:
        with counting_reads():
            _Counting.total = 0
            b.call(gb, radius)
            return _Counting.total / pixels
    except Exception as exc:  # noqa: BLE001 - white-box instrumentation: report, go on
        print(f"  NOTE: counting the reads of {b.name} failed ({type(exc).__name__}: {exc})")
        return None


# --------------------------------------------------------------------------- memory
# --------------------------------------------------------------------------- report
class Report(_bench.Report):
    columns = (f"{'configuration':<22} {'median s':>9} {'cores':>5} {'taps/px':>7} {'texels/px':>9} "
               f"{'reads/px':>8} {'floor s':>8} {'x floor':>8} {'peak B/px':>10}")
    summary_title = ("Summary (time ratios are medians from this one run; the 'cores' column above\n"
                     "   shows how many cores each measurement got on this shared machine)")
    label_width = 62

    @staticmethod
    def row(label, timing: Timing | None, taps=None, texels=None, reads=None, floor: Timing | None = None,
            peak=None, note=""):
        sec = f"{timing.seconds:9.4f}" if timing else f"{'':9}"
        cores = f"{timing.cores:5.2f}" if timing else f"{'':5}"
        t = f"{taps:7d}" if taps is not None else f"{'':7}"
        x = f"{texels:9d}" if texels is not None else f"{'':9}"
        r = f"{reads:8.1f}" if reads is not None else f"{'':8}"
        fl = f"{floor.seconds:8.4f}" if floor else f"{'':8}"
        ratio = f"{timing.seconds / floor.seconds:7.2f}x" if (timing and floor) else f"{'':8}"
        p = f"{peak:10.1f}" if peak is not None else f"{'':10}"
        print(f"  {label:<22} {sec} {cores} {t} {x} {r} {fl} {ratio} {p} {note}".rstrip())


# --------------------------------------------------------------------------- setup
def machine_facts():
    threads = {k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
               if k in os.environ}
    _bench.machine_facts(f"BLAS thread variables: {threads or 'unset'}   (the estimators are NumPy "
                         "code on one thread;\n   'cores' above 1 means BLAS or another library used more "
                         "than one)")


# --------------------------------------------------------------------------- benchmark
def count_reads(radius: float) -> dict:
    """reads/px of every configuration, counted once on a READS_SIZE^2 render (the count per
    pixel is structural: it does not depend on the image size), printed beside the
    registry's texels/px."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((READS_SIZE, READS_SIZE)))
    k = int(np.count_nonzero(np.isfinite(gb.depth) & (gb.depth > 0)))
    reads = {b.name: reads_per_pixel(b, gb, radius, k) for b in configurations()}
    print(f"\n== The registry's texel model against the reads counted ({READS_SIZE}x{READS_SIZE}, "
          f"{k} valid pixels)")
    print(f"  {'configuration':<22} {'fetch':>9} {'taps/px':>7} {'texels/px':>9} {'reads/px':>8} "
          f"{'reads/texel':>11}")
    for b in configurations():
        r = reads[b.name]
        ratio = f"{r / b.config.texels:11.3f}" if r is not None else f"{'':11}"
        counted = f"{r:8.1f}" if r is not None else f"{'':8}"
        print(f"  {b.name:<22} {b.config.fetch_used:>9} {b.config.taps:7d} {b.config.texels:9d} "
              f"{counted} {ratio}")
    print("  (reads count array elements gathered, texels count distinct depth texels: a bilinear\n"
          "   tap gathers the nearest texel, one of its 4, again where a neighbour is background;\n"
          "   a mip texel holds 3 moment channels, 10 with normal_clamp: 3x and 10x)")
    return reads


def bench_size(size: int, radius: float, repeats: int, reads: dict, report: Report):
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((size, size)))
    pixels_all = size * size
    px = valid_pixels(gb, radius)
    k = len(px.cx)
    configs = configurations()
    floors = {T: spiral(T) for T in sorted({b.config.texels for b in configs})}

    print(f"\n-- {scene.name}, {size}x{size} = {pixels_all} pixels ({k} valid), radius {radius:g} "
          f"({radius / scene.extent:.3f} x extent), median radius {np.median(px.radius_px):.1f} px")
    fns = {"setup": lambda: valid_pixels(gb, radius)}
    for T, offsets in floors.items():
        fns[f"floor {T}"] = lambda offsets=offsets: gather_floor(px, offsets)
    for b in configs:
        fns[b.name] = lambda b=b: b.call(gb, radius)
    t = interleaved(fns, repeats, statistic="median")

    def floor(b):
        return t[f"floor {b.config.texels}"]

    peaks = {b.name: peak_bytes(lambda b=b: b.call(gb, radius)) / pixels_all for b in configs}
    peaks["setup"] = peak_bytes(lambda: valid_pixels(gb, radius)) / pixels_all
    for cfg in _memory_configs():
        peaks[cfg.label] = peak_bytes(lambda cfg=cfg: Bench(cfg).call(gb, radius)) / pixels_all

    report.header(f"{size}x{size}: median of {repeats} interleaved rounds; floor = texels/px one-texel reads")
    for b in configs:
        report.row(b.name, t[b.name], b.config.taps, b.config.texels, reads[b.name], floor(b), peaks[b.name])
    print("  context:")
    report.row("valid-pixel setup", t["setup"], peak=peaks["setup"], note="(what every estimator starts with)")
    for T in floors:
        report.row(f"gather floor {T}", t[f"floor {T}"], T, T, float(T))
    pairs = [(a, b) for a, b in GROWTH_PAIRS if a.label in peaks and b.label in peaks]
    if pairs:
        print("  peak extra memory per pixel against the sample count (B/px):")
    for a, b in pairs:
        pa, pb = peaks[a.label], peaks[b.label]
        print(f"    {a.label:>8} vs {b.label:<8}: {pa:7.1f} vs {pb:7.1f}  ({pb - pa:+.1f} B/px, "
              f"{(pb - pa) / (b.samples - a.samples):+.2f} B/px per extra sample)")

    tag = f"[{size}^2]"
    for b in configs:
        label, ratio = f"{tag} {b.name} / gather floor ({b.config.texels} reads)", t[b.name].seconds / floor(b).seconds
        if b.method == "line":
            report.goal(label, ratio, GOAL_LINE_FLOOR, at_least=False)
    for b in configs:
        if b.config in BASELINES:
            report.goal(f"{tag} {b.name} / gather floor ({b.config.texels} reads)",
                        t[b.name].seconds / floor(b).seconds, GOAL_BASELINE_FLOOR, at_least=False)
        elif b.method != "line":
            report.note(f"{tag} {b.name} / gather floor ({b.config.texels} reads)",
                        t[b.name].seconds / floor(b).seconds)
    line = max(c.texels for c in CONFIGS if c.method == "line")
    if f"floor {line}" in t:
        report.note(f"{tag} valid-pixel setup alone / gather floor ({line} reads)",
                    t["setup"].seconds / t[f"floor {line}"].seconds)
    for method in dict.fromkeys(b.method for b in configs):
        worst = max((b for b in configs if b.method == method), key=lambda b: peaks[b.name])
        report.goal(f"{tag} peak memory, worst {method} ({worst.name})", peaks[worst.name],
                    GOAL_BYTES_PER_PIXEL, at_least=False, unit=" B/px")
    for a, b in pairs:
        report.goal(f"{tag} peak memory growth, {a.label} -> {b.label}", peaks[b.label] - peaks[a.label],
                    GOAL_GROWTH_BYTES, at_least=False, unit=" B/px")


# --------------------------------------------------------------------------- main
def parse_args(argv):
    parser = _bench.parser(__doc__, quick="256^2 and 512^2 (< 60 s), for smoke tests", statistic="median")
    parser.add_argument("--radius", type=float, default=RADIUS, help=f"ball radius (default {RADIUS})")
    parser.add_argument("--only", default=None, metavar="LABELS",
                        help="comma-separated configurations to time, as labelled in the report "
                             "(e.g. 'gtao:3,sao:12,alchemy:12' or 'line:9 clamp'); default every one")
    args = _bench.parse(parser, argv)
    if not args.radius > 0:
        parser.error("--radius must be > 0")
    if args.only is not None:
        args.only = tuple(label.strip() for label in args.only.split(",") if label.strip())
        every = {b.name for b in [Bench(cfg, clamp) for clamp in (False, True) for cfg in CONFIGS]
                 + [Bench(cfg) for cfg in BASELINES + BASELINE_NOTES]}
        unknown = sorted(set(args.only) - every)
        if unknown or not args.only:
            parser.error(f"--only: unknown configuration(s) {', '.join(unknown) or '(none given)'}; "
                         f"expected labels among {', '.join(sorted(every))}")
    return args


def main(argv=None) -> int:
    global ONLY
    args = parse_args(argv)
    ONLY = args.only
    sizes = QUICK_SIZES if args.quick else FULL_SIZES

    def body(report):
        machine_facts()
        print(f"  mode: {'quick' if args.quick else 'full'}   repeats: median of {args.repeats}   "
              f"sizes: {', '.join(f'{s}^2' for s in sizes)}")
        warm_up(args.radius)
        reads = count_reads(args.radius)
        for size in sizes:
            bench_size(size, args.radius, args.repeats, reads, report)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
