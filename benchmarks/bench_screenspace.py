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
scene's extent; ``--radius``). Configurations, each with ``normal_clamp`` False and True,
``randomize`` on (the default), every other argument at its default:

- ``vo.vo_point(gb, radius=r, samples=n)`` for n = 12, 33;
- ``vo.vo_line(gb, radius=r, samples=n)`` for n = 5, 9;
- ``vo.vo_area(gb, radius=r, samples=1)`` (skipped with a note when it is missing or fails).

Per configuration:

- **median s**: median wall time of one call (G-buffer given; ``prepare`` and everything
  else inside the estimator included). **cores**: process CPU time / wall time in the
  median round: how many cores the call actually got.
- **taps/px**: depth-buffer taps per pixel, the cost model of DESIGN.md: one per sample for
  point and line sampling; for area sampling the texels one mip lookup reads per sample:
  2 levels (floor(lod) and floor(lod) + 1) x (taps per axis)^2, the taps per axis read from
  the code (``area._filter_taps`` for ``vo_area``'s default ``reconstruction``: 2 for the
  trilinear tent, i.e. 8 texels, 3 for the quadratic B-spline, i.e. 18 texels). Each texel
  holds the 3 channels the mip-map stores (coverage, mean, central second moment), so
  reads/px is 3 x taps/px there. Building the mip-map (one pass over 4/3 of the image) is
  a per-frame cost, not a tap.
- **reads/px**: the elements the estimator actually gathers from the depth buffer (or from
  the moments mip-map) per pixel, *counted* in a separate untimed call: the depth arrays of
  ``prepare``'s result (and the mip-map's arrays) are replaced by a view that counts what
  integer-array indexing and ``take`` return (once per configuration, on a 128^2 render:
  the count per pixel does not depend on the size). A bilinear fetch reads 4 texels (plus one
  nearest read for the background fallback); the mip lookup reads taps/px texels x the
  channels the mip-map stores (3 unclamped: coverage, mean, central moment; 10 clamped, with
  the pixel positions and their moments).
- **floor s** and **x floor**: the NumPy "gather floor" for ``taps/px`` taps and the
  estimator's median time over it. The floor is :func:`gather_floor`: for each of the T taps,
  continuous pixel coordinates of every valid pixel (centre + offset x radius_px), floored
  to integer indices, clipped to the image, and ``depth[i, j]`` gathered, nothing else, over
  the flat arrays of valid pixels of ``vobscure.screenspace._common.prepare(gb, radius)``
  (built outside the timing: ``prepare`` is timed alone as context). The T offsets are a
  golden-angle spiral filling the unit disk, the same for every pixel (no per-pixel
  randomization: neighbouring pixels read neighbouring texels, so the floor is slightly
  kinder to the cache than the randomized estimators). Goal: ``vo_line`` within 1.5x of
  its floor.
- **peak B/px**: peak extra memory per pixel: ``tracemalloc`` (NumPy reports its buffers to
  it) is started after the G-buffer is built and the sample patterns are cached, the
  estimator runs once, and the peak of traced memory is divided by W x H. It includes
  ``prepare``'s per-pixel arrays and the returned image (8 B/px in float64). Goal: under
  100 B/px and not growing with the sample count (at most ``GOAL_GROWTH_BYTES`` = 1 B/px
  more): point 12 vs 33, line 5 vs 9, and line 33 vs 65 (memory only) side by side.

Run from the repository root::

    python benchmarks/bench_screenspace.py            # 512^2 and 1024^2, a few minutes
    python benchmarks/bench_screenspace.py --quick    # 256^2 and 512^2, under 60 s
    python benchmarks/bench_screenspace.py --repeats 5 --radius 0.3

The exit code is 0 unless something raises; no timing is asserted.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import os
import platform
import sys
import time
import tracemalloc
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source tree
sys.path.insert(0, str(Path(__file__).resolve().parent))      # the shared _bench module

import _bench  # noqa: E402
import vobscure as vo  # noqa: E402
from _bench import Timing, interleaved, load_average  # noqa: E402
from vobscure.screenspace import _common as C  # noqa: E402

FULL_SIZES = (512, 1024)
QUICK_SIZES = (256, 512)
RADIUS = 0.3
POINT_SAMPLES = (12, 33)
LINE_SAMPLES = (5, 9)
#: line sample counts measured for memory only, to show the trend with samples
LINE_MEMORY_SAMPLES = (33, 65)
AREA_SAMPLES = 1
#: image edge of the render on which the reads per pixel are counted
READS_SIZE = 128
#: mip levels one area lookup blends (floor(lod) and floor(lod) + 1)
AREA_LEVELS = 2
#: channels of a mip texel: coverage, mean, central second moment
AREA_CHANNELS = 3
#: goals
GOAL_LINE_FLOOR = 1.5
GOAL_BYTES_PER_PIXEL = 100.0
#: "not growing with samples": more samples may cost at most this many bytes per pixel more
GOAL_GROWTH_BYTES = 1.0


# --------------------------------------------------------------------------- configurations
@dataclass(frozen=True)
class Config:
    name: str                      # e.g. "line 9 clamp"
    kind: str                      # "point" | "line" | "area"
    samples: int
    clamp: bool
    fn: Callable                   # fn(gb) -> image
    taps_per_sample: int = 1       # area: texels of one mip lookup

    @property
    def taps(self) -> int:
        """Depth-buffer taps per pixel (DESIGN.md's cost model), see the module docstring.
        ``vo_point`` does not tap the centre of an odd (point-symmetric) pattern: it lies on
        the surface and counts half open without a fetch."""
        if self.kind == "point":
            return vo.screenspace.point_taps(self.samples)
        return self.samples * self.taps_per_sample


@dataclass(frozen=True)
class Area:
    fn: Callable
    reconstruction: str            # the default reconstruction between texels
    texels: int                    # texels one lookup reads (both levels)


def area_texels(fn) -> tuple[str, int]:
    """(reconstruction, texels per lookup) of vo_area's defaults, from the code's structure:
    AREA_LEVELS levels x (taps per axis)^2, the taps per axis being what
    ``area._filter_taps`` returns for the default ``reconstruction`` (a tent: 2, the
    quadratic B-spline: 3). Falls back to the trilinear 2 x 2 x 2 = 8 with a note."""
    try:
        import inspect

        from vobscure.screenspace import area as A
        rec = inspect.signature(fn).parameters["reconstruction"].default
        per_axis = len(A._filter_taps(np.zeros(1), rec))
        return rec, AREA_LEVELS * per_axis * per_axis
    except Exception as exc:  # noqa: BLE001 - the area module is being written concurrently
        print(f"  NOTE: cannot read vo_area's lookup structure ({type(exc).__name__}: {exc}); "
              "assuming trilinear, 8 texels per sample")
        return "trilinear?", AREA_LEVELS * 2 * 2


def find_area() -> Area | None:
    """vo.vo_area, or None with a printed note when it is missing or fails."""
    fn = getattr(vo, "vo_area", None)
    where = "vo.vo_area"
    if fn is None:
        try:
            from vobscure.screenspace.area import vo_area as fn
            where = "vobscure.screenspace.area.vo_area (not exported as vo.vo_area yet)"
        except Exception as exc:  # noqa: BLE001 - being written concurrently: report, skip
            print(f"  NOTE: vo_area unavailable ({type(exc).__name__}: {exc}); area rows skipped")
            return None
    try:   # smoke test on a tiny G-buffer
        scene = vo.scenes.cornell_box()
        gb = vo.render_gbuffer(scene, scene.camera((16, 16)))
        for clamp in (False, True):
            fn(gb, radius=RADIUS, samples=AREA_SAMPLES, normal_clamp=clamp)
    except Exception as exc:  # noqa: BLE001
        print(f"  NOTE: vo_area fails on a 16x16 G-buffer ({type(exc).__name__}: {exc}); "
              "area rows skipped")
        return None
    rec, texels = area_texels(fn)
    print(f"  area sampling: {where}; default reconstruction {rec!r}: {texels} texels "
          f"({AREA_LEVELS} levels) x {AREA_CHANNELS} channels per lookup")
    return Area(fn, rec, texels)


def configurations(radius: float, area: Area | None) -> list[Config]:
    """Every timed configuration: randomize on, every argument but samples and
    normal_clamp at its default."""
    def call(fn, n, clamp):
        return lambda gb: fn(gb, radius=radius, samples=n, normal_clamp=clamp)

    out = []
    for clamp in (False, True):
        tag = " clamp" if clamp else ""
        for n in POINT_SAMPLES:
            out.append(Config(f"point {n}{tag}", "point", n, clamp, call(vo.vo_point, n, clamp)))
        for n in LINE_SAMPLES:
            out.append(Config(f"line {n}{tag}", "line", n, clamp, call(vo.vo_line, n, clamp)))
        if area is not None:
            out.append(Config(f"area {AREA_SAMPLES}{tag}", "area", AREA_SAMPLES, clamp,
                              call(area.fn, AREA_SAMPLES, clamp), taps_per_sample=area.texels))
    return out


def line_config(radius: float, n: int) -> Config:
    return Config(f"line {n}", "line", n, False, lambda gb: vo.vo_line(gb, radius=radius, samples=n))


def warm_patterns():
    """Build (and cache) every sample pattern outside the timings and the memory traces."""
    for n in POINT_SAMPLES:
        vo.patterns.ball(n)
    for n in LINE_SAMPLES + LINE_MEMORY_SAMPLES + (AREA_SAMPLES,):
        vo.patterns.disk(n)


# --------------------------------------------------------------------------- the gather floor
def spiral(count: int) -> np.ndarray:
    """``count`` offsets (count, 2) filling the unit disk evenly (golden-angle spiral)."""
    i = np.arange(count) + 0.5
    r = np.sqrt(i / count)
    a = i * np.pi * (3.0 - np.sqrt(5.0))
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def gather_floor(px, offsets: np.ndarray) -> np.ndarray:
    """The time floor of ``len(offsets)`` depth taps per pixel: index arithmetic and gathers.

    For each (ox, oy) of ``offsets`` (unit-disk offsets): continuous pixel coordinates
    centre + offset x radius_px of every valid pixel, floored to integer indices, clipped
    to the image, and the depth gathered. Nothing else (no projection, no warp, no integral,
    no accumulation). Returns the last gather, so that nothing can be skipped.
    """
    H, W = px.depth.shape
    cx, cy, r, depth = px.center[:, 0], px.center[:, 1], px.radius_px, px.depth
    d = None
    for ox, oy in offsets:
        j = np.clip(np.floor(cx + ox * r), 0, W - 1).astype(np.intp)
        i = np.clip(np.floor(cy - oy * r), 0, H - 1).astype(np.intp)
        d = depth[i, j]
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


@contextmanager
def counting_reads():
    """While active, the depth arrays of prepare()'s result and the area mip-map's arrays
    count the elements gathered from them. Patches module attributes only, and restores them."""
    patched = []
    original_prepare = C.prepare

    def prepare(*args, **kwargs):
        px = original_prepare(*args, **kwargs)
        images = {f.name: _count(getattr(px, f.name)) for f in dataclasses.fields(px)
                  if f.name.startswith("depth") and isinstance(getattr(px, f.name), np.ndarray)}
        return dataclasses.replace(px, **images)

    C.prepare = prepare
    patched.append((C, "prepare", original_prepare))
    try:
        from vobscure.screenspace import area as A
        pyramid = getattr(A, "_Pyramid", None)
    except Exception:  # noqa: BLE001 - area sampling absent
        pyramid = None
    if pyramid is not None:
        # the pyramid's channels: self.c and the lists self.m, self.v (built by _build, which
        # both __init__ and from_depth call)
        original_build = pyramid._build

        def build(self, *args, **kwargs):
            original_build(self, *args, **kwargs)
            for name, value in list(vars(self).items()):
                if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                    setattr(self, name, _count(value))
                elif isinstance(value, list) and value and all(isinstance(x, np.ndarray) for x in value):
                    setattr(self, name, [_count(x) if x.dtype.kind == "f" else x for x in value])

        pyramid._build = build
        patched.append((pyramid, "_build", original_build))
    padded = getattr(C, "PaddedDepth", None)
    if padded is not None:
        # vo_line's snapped taps read a bordered copy of the depth buffer (PaddedDepth.flat)
        original_padded = padded.__init__

        def padded_init(self, *args, **kwargs):
            original_padded(self, *args, **kwargs)
            self.flat = _count(self.flat)

        padded.__init__ = padded_init
        patched.append((padded, "__init__", original_padded))
    try:
        yield
    finally:
        for owner, name, value in patched:
            setattr(owner, name, value)


def reads_per_pixel(cfg: Config, gb, pixels: int) -> float | None:
    """Elements gathered from the depth buffer (or mip-map) per valid pixel, or None."""
    try:
        with counting_reads():
            _Counting.total = 0
            cfg.fn(gb)
            return _Counting.total / pixels
    except Exception as exc:  # noqa: BLE001 - instrumentation is best effort
        print(f"  NOTE: counting the reads of {cfg.name} failed ({type(exc).__name__}: {exc})")
        return None


# --------------------------------------------------------------------------- memory
def peak_bytes(fn: Callable) -> int:
    """Peak traced memory (bytes) of one call of ``fn``, tracing started just before it."""
    gc.collect()
    tracemalloc.start()
    try:
        result = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    del result
    return peak


# --------------------------------------------------------------------------- report
class Report(_bench.Report):
    columns = (f"{'configuration':<22} {'median s':>9} {'cores':>5} {'taps/px':>8} {'reads/px':>9} "
               f"{'floor s':>8} {'x floor':>8} {'peak B/px':>10}")
    summary_title = ("Summary (time ratios are medians from this one run; the 'cores' column above\n"
                     "   shows how many cores each measurement got on this shared machine)")
    label_width = 62

    @staticmethod
    def row(label, timing: Timing | None, taps=None, reads=None, floor: Timing | None = None,
            peak=None, note=""):
        sec = f"{timing.seconds:9.4f}" if timing else f"{'':9}"
        cores = f"{timing.cores:5.2f}" if timing else f"{'':5}"
        t = f"{taps:8d}" if taps is not None else f"{'':8}"
        r = f"{reads:9.1f}" if reads is not None else f"{'':9}"
        fl = f"{floor.seconds:8.4f}" if floor else f"{'':8}"
        ratio = f"{timing.seconds / floor.seconds:7.2f}x" if (timing and floor) else f"{'':8}"
        p = f"{peak:10.1f}" if peak is not None else f"{'':10}"
        print(f"  {label:<22} {sec} {cores} {t} {r} {fl} {ratio} {p} {note}".rstrip())


# --------------------------------------------------------------------------- setup
def machine_facts():
    _bench.machine_facts()
    threads = {k: os.environ[k] for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
               if k in os.environ}
    print(f"  platform: {platform.platform()}   BLAS thread variables: {threads or 'unset'}")
    print("  (the estimators are NumPy code on one thread; 'cores' above 1 means BLAS or another")
    print("   library used more than one)")


# --------------------------------------------------------------------------- benchmark
def count_reads(radius: float, area: Area | None) -> dict:
    """reads/px of every configuration, counted once on a READS_SIZE^2 render (the count per
    pixel is structural: it does not depend on the image size)."""
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((READS_SIZE, READS_SIZE)))
    k = int(np.count_nonzero(np.isfinite(gb.depth) & (gb.depth > 0)))
    return {cfg.name: reads_per_pixel(cfg, gb, k) for cfg in configurations(radius, area)}


def bench_size(size: int, radius: float, repeats: int, area: Area | None, reads: dict, report: Report):
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera((size, size)))
    pixels_all = size * size
    px = C.prepare(gb, radius)
    k = len(px.index)
    configs = configurations(radius, area)
    floors = {T: spiral(T) for T in sorted({c.taps for c in configs})}
    for cfg in configs:     # warm up (patterns, mip-map caches, first-touch of the pages)
        cfg.fn(gb)

    print(f"\n-- {scene.name}, {size}x{size} = {pixels_all} pixels ({k} valid), radius {radius:g} "
          f"({radius / scene.extent:.3f} x extent), median radius {np.median(px.radius_px):.1f} px")
    fns = {"prepare": lambda: C.prepare(gb, radius)}
    for T, offsets in floors.items():
        fns[f"floor {T}"] = lambda offsets=offsets: gather_floor(px, offsets)
    for cfg in configs:
        fns[cfg.name] = lambda cfg=cfg: cfg.fn(gb)
    t = interleaved(fns, repeats, statistic="median")

    peaks = {cfg.name: peak_bytes(lambda cfg=cfg: cfg.fn(gb)) / pixels_all for cfg in configs}
    peaks["prepare"] = peak_bytes(lambda: C.prepare(gb, radius)) / pixels_all
    for n in LINE_MEMORY_SAMPLES:
        cfg = line_config(radius, n)
        peaks[cfg.name] = peak_bytes(lambda cfg=cfg: cfg.fn(gb)) / pixels_all

    report.header(f"{size}x{size}: median of {repeats} interleaved rounds")
    for cfg in configs:
        report.row(cfg.name, t[cfg.name], cfg.taps, reads[cfg.name], t[f"floor {cfg.taps}"], peaks[cfg.name])
    print("  context:")
    report.row("prepare() alone", t["prepare"], peak=peaks["prepare"], note="(inside every estimator)")
    for T in floors:
        report.row(f"gather floor, {T} taps", t[f"floor {T}"], T, float(T))
    print("  peak extra memory per pixel against the sample count (B/px):")
    for kind, (a, b) in (("point", POINT_SAMPLES), ("line", LINE_SAMPLES), ("line", LINE_MEMORY_SAMPLES)):
        pa, pb = peaks[f"{kind} {a}"], peaks[f"{kind} {b}"]
        print(f"    {kind} {a:>2} vs {b:>2} samples: {pa:7.1f} vs {pb:7.1f}  ({pb - pa:+.1f} B/px, "
              f"{(pb - pa) / (b - a):+.2f} B/px per extra sample)")

    tag = f"[{size}^2]"
    for cfg in configs:
        if cfg.kind == "line":
            report.goal(f"{tag} {cfg.name} / gather floor ({cfg.taps} taps)",
                        t[cfg.name].seconds / t[f"floor {cfg.taps}"].seconds, GOAL_LINE_FLOOR, at_least=False)
    for cfg in configs:
        if cfg.kind != "line":
            report.note(f"{tag} {cfg.name} / gather floor ({cfg.taps} taps)",
                        t[cfg.name].seconds / t[f"floor {cfg.taps}"].seconds)
    report.note(f"{tag} prepare() alone / gather floor ({LINE_SAMPLES[-1]} taps)",
                t["prepare"].seconds / t[f"floor {LINE_SAMPLES[-1]}"].seconds)
    for kind in ("point", "line", "area"):
        rows = [c for c in configs if c.kind == kind]
        if rows:
            worst = max(rows, key=lambda c: peaks[c.name])
            report.goal(f"{tag} peak memory, worst {kind} ({worst.name})", peaks[worst.name],
                        GOAL_BYTES_PER_PIXEL, at_least=False, unit=" B/px")
    for kind, (a, b) in (("point", POINT_SAMPLES), ("line", LINE_SAMPLES), ("line", LINE_MEMORY_SAMPLES)):
        report.goal(f"{tag} peak memory growth, {kind} {a} -> {b} samples",
                    peaks[f"{kind} {b}"] - peaks[f"{kind} {a}"], GOAL_GROWTH_BYTES,
                    at_least=False, unit=" B/px")


# --------------------------------------------------------------------------- main
def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--quick", action="store_true", help="256^2 and 512^2 (< 60 s), for smoke tests")
    parser.add_argument("--repeats", type=int, default=3, help="median of N rounds (default 3)")
    parser.add_argument("--radius", type=float, default=RADIUS, help=f"ball radius (default {RADIUS})")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be >= 1")
    if not args.radius > 0:
        parser.error("--radius must be > 0")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    sizes = QUICK_SIZES if args.quick else FULL_SIZES
    start = time.perf_counter()
    machine_facts()
    print(f"  mode: {'quick' if args.quick else 'full'}   repeats: median of {args.repeats}   "
          f"sizes: {', '.join(f'{s}^2' for s in sizes)}")
    warm_patterns()
    area = find_area()
    reads = count_reads(args.radius, area)
    report = Report()
    for size in sizes:
        bench_size(size, args.radius, args.repeats, area, reads, report)
    report.print_summary()
    print(f"\n  total benchmark time {time.perf_counter() - start:.1f} s   "
          f"load average now: {load_average()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
