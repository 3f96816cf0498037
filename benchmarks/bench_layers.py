"""The layered G-buffer: render time and peak memory per layer of depth peeling, as ratios.

The machine this runs on is shared and noisy, so every time is a *ratio* of two timings taken
in the same run (best of ``--repeats`` rounds, the calls interleaved round by round,
``_bench.interleaved``); absolute times are context only. Memory: tracemalloc's peak of one
call (``_bench.peak_bytes``), which counts NumPy's arrays exactly; the bands of rows run on
several threads, whose temporaries overlap differently from call to call (one call's peak
moves by up to ~10 B/px), so each peak is the median of ``--repeats`` calls (interleaved
round by round), and the spread (max - min) of those calls is printed beside it.

What is measured
----------------
``vo.render_gbuffer(scene, camera, layers=K)`` for K = 1, 2, 4, 8 on the Cornell box and the
atrium (``vo.scenes.atrium()``: 41k triangles, alpha-tested leaves and open banners), each at
its suggested camera, 512 x 512 (128 x 128 with ``--quick``), on every usable core:

- **time**: K layers / one layer (the G-buffer of today), and that ratio per extra layer;
- **memory**: the peak of one call, (peak(K) - peak(1)) / ((K - 1) pixels): bytes per pixel
  per layer beyond one (goal <= 24), with what the result holds beyond the one-layer
  G-buffer (the surfaces, ``PeeledLayers.nbytes``, and the intervals' float32 slots) per
  pixel beside it;
- **coverage**: the interval slots M, and the fraction of covered pixels whose last interval
  is still open after K layers (its end unseen: the ray crossed at least K surfaces);
- **the estimators that read the layers** (``thickness="layers"``: ``vo_line`` 9 lines,
  ``vo_point`` 16 points, ``gtao`` and ``vbao`` at their defaults) on the G-buffers of K = 2, 4,
  8: time against K = 2, beside K / 2 (goal: at most linear in K, ratio <= K / 2) and beside
  the interval slots' ratio M(K) / M(2) (what the estimators loop over); the same estimator
  without layers (the depth buffer) for scale.

Run from the repository root::

    python benchmarks/bench_layers.py            # about two minutes
    python benchmarks/bench_layers.py --quick    # a few seconds (smoke test)
"""

from __future__ import annotations

import sys

import numpy as np

import _bench
import vobscure as vo

LAYERS = (1, 2, 4, 8)
#: Goal: peak memory of the layered G-buffer per pixel per layer beyond one.
MEMORY_GOAL = 24.0


class Report(_bench.Report):
    columns = (f"{'scene':<12} {'K':>2} {'seconds':>9} {'x K=1':>7} {'cores':>6} {'peak B/px':>10} "
               f"{'spread':>7} {'B/px/extra':>11} {'held B/px':>10} {'M':>3} {'open end':>9}")
    summary_title = "Summary (K layers against one, same run)"

    def row(self, name, K, t, ratio, peak, spread, extra, held, M, unseen):
        extra_s = "" if extra is None else f"{extra:11.1f}"
        print(f"  {name:<12} {K:>2} {t.seconds:9.4f} {ratio:7.2f} {t.cores:6.2f} {peak:10.1f} "
              f"{spread:7.1f} {extra_s:>11} {held:10.1f} {M:>3} {unseen:9.1%}")


def main(argv=None) -> int:
    parser = _bench.parser(__doc__, quick="128 x 128 (a few seconds)", statistic="best")
    args = _bench.parse(parser, argv)
    size = (128, 128) if args.quick else (512, 512)

    def body(report):
        _bench.machine_facts("render_gbuffer on every usable core")
        for name in ("cornell_box", "atrium"):
            scene = vo.scenes.get(name)
            cam = scene.camera(size)
            scene.tracer  # noqa: B018 - build the Embree scene outside the timings
            pixels = cam.width * cam.height
            times = _bench.interleaved({K: (lambda K=K: vo.render_gbuffer(scene, cam, layers=K)) for K in LAYERS},
                                       args.repeats)
            calls = {K: [] for K in LAYERS}
            for _ in range(args.repeats):
                for K in LAYERS:
                    calls[K].append(_bench.peak_bytes(lambda K=K: vo.render_gbuffer(scene, cam, layers=K)))
            peaks = {K: float(np.median(v)) for K, v in calls.items()}
            report.header(f"{name}: {cam.width} x {cam.height}, {len(scene.triangles)} triangles "
                          f"({args.repeats} rounds, best)")
            for K in LAYERS:
                gb = times[K].result
                ratio = times[K].seconds / times[1].seconds
                if K == 1:
                    held, M, unseen, extra = 0.0, 0, 0.0, None
                else:
                    s = gb.intervals
                    held = (s.layers.nbytes + s.front.nbytes + s.back.nbytes) / pixels
                    M = s.count
                    covered = gb.valid
                    last = np.where(np.isfinite(s.front), np.arange(M)[:, None, None], -1).max(axis=0)
                    open_end = np.take_along_axis(s.back, np.maximum(last, 0)[None], axis=0)[0]
                    unseen = float(np.mean(np.isinf(open_end[covered]) & (last[covered] >= 0)))
                    extra = (peaks[K] - peaks[1]) / ((K - 1) * pixels)
                    report.note(f"{name}: time K={K} / K=1 (per extra layer {(ratio - 1) / (K - 1):.2f})", ratio)
                    report.goal(f"{name}: peak bytes per pixel per extra layer, K={K}", extra, MEMORY_GOAL,
                                at_least=False, unit=" B")
                spread = (max(calls[K]) - min(calls[K])) / pixels
                report.row(name, K, times[K], ratio, peaks[K] / pixels, spread, extra, held, M, unseen)

            bench_estimators(name, {K: times[K].result for K in LAYERS}, args.repeats, report)

    return _bench.run(body, Report())


#: The layered estimators timed against K, with the options they are run with.
ESTIMATORS = {"vo_line:9": (vo.vo_line, dict(samples=9)), "vo_point:16": (vo.vo_point, dict(samples=16)),
              "gtao": (vo.gtao, {}), "vbao": (vo.vbao, {})}


def bench_estimators(name, gbuffers, repeats, report):
    """Time of each layered estimator on the G-buffers of K = 2, 4, 8 against K = 2."""
    radius = vo.experiments.compare.choose_radius(vo.scenes.get(name), gbuffers[1]).radius
    layered = [K for K in LAYERS if K > 1]
    print(f"\n  {name}: estimators with thickness='layers', radius {radius:.4g} (best of {repeats})")
    print(f"  {'estimator':<12} {'K':>2} {'M':>3} {'seconds':>9} {'x K=2':>7} {'K/2':>5} {'M/M(2)':>7}")
    for label, (fn, options) in ESTIMATORS.items():
        calls = {"solid": lambda: fn(gbuffers[1], radius=radius, **options)}
        calls.update({K: (lambda K=K: fn(gbuffers[K], radius=radius, thickness="layers", **options))
                      for K in layered})
        t = _bench.interleaved(calls, repeats)
        print(f"  {label:<12} {'':>2} {'':>3} {t['solid'].seconds:9.4f}   (the depth buffer, no layers)")
        M2 = gbuffers[2].intervals.count
        for K in layered:
            ratio = t[K].seconds / t[2].seconds
            M = gbuffers[K].intervals.count
            print(f"  {label:<12} {K:>2} {M:>3} {t[K].seconds:9.4f} {ratio:7.2f} {K / 2:5.1f} {M / M2:7.2f}")
            if K > 2:
                report.goal(f"{name}: {label} time K={K} / K=2 (at most K/2 = {K // 2})", ratio, K / 2,
                            at_least=False)


if __name__ == "__main__":
    sys.exit(main())
