"""Reprojection and accumulation per frame against the gather floor of one tap per pixel.

The machine this runs on is shared and noisy, so every result is a *ratio* of two timings
taken in the same run (median of ``--repeats`` rounds, the calls interleaved round by round,
``_bench.interleaved``); absolute times are context only.

What is measured
----------------
The Cornell box at its suggested camera and that camera turned by 0.5 degrees about the
target (``vobscure.temporal.camera_path(cam, 2, "orbit")``), 512 x 512 (128 x 128 with
``--quick``). One :meth:`vobscure.temporal.Accumulator.update` of the second frame from a
history of the first (set by ``set_history``; the G-buffer is re-wrapped before each call so
that its lazily built view-space positions are built inside the timed call, as in a sequence):

- ``static mean``: the same camera twice (the in-place path: a depth test per pixel);
- ``orbit mean`` (bilinear history, the default), ``orbit mean nearest``, ``orbit mean clamp``
  (the 3 x 3 range clamp), ``orbit clip:0.1`` (variance clipping);

each against the **gather floor of one tap per pixel** (``bench_screenspace.gather_floor`` with
one offset: index arithmetic and one depth gather per covered pixel). Goal: within 3x.
Memory: the history an accumulator keeps (``HISTORY_BYTES_PER_PIXEL``: float64 value and int32
count) and the peak extra memory of one orbit update per pixel (``tracemalloc``).

Run from the repository root::

    python benchmarks/bench_temporal.py            # under a minute
    python benchmarks/bench_temporal.py --quick    # seconds (smoke test)
"""

from __future__ import annotations

import sys

import numpy as np

import _bench
from bench_screenspace import gather_floor, valid_pixels

import vobscure as vo
from vobscure.temporal import HISTORY_BYTES_PER_PIXEL, Accumulator, camera_path

GOAL_FLOOR = 3.0


class Report(_bench.Report):
    columns = f"{'configuration':<28} {'median s':>9} {'x floor':>8} {'peak B/px':>10}"
    label_width = 52

    def row(self, label, seconds, floor, peak=None):
        p = f"{peak:10.1f}" if peak is not None else f"{'':10}"
        print(f"  {label:<28} {seconds:9.4f} {seconds / floor:7.2f}x {p}")


def main(argv=None) -> int:
    p = _bench.parser(__doc__, quick="128 x 128, a few seconds", statistic="median")
    args = _bench.parse(p, argv)
    size = 128 if args.quick else 512
    _bench.machine_facts(f"image {size} x {size}, orbit step 0.5 degrees")

    def body(report):
        sc = vo.scenes.cornell_box()
        cams = camera_path(sc.camera(size=(size, size)), 2, "orbit")
        gb0, gb1 = (vo.render_gbuffer(sc, c) for c in cams)
        radius = 0.1 * sc.extent
        rng = np.random.default_rng(0)
        h0 = np.where(gb0.valid, rng.random(gb0.shape), np.nan)
        x1 = np.where(gb1.valid, rng.random(gb1.shape), np.nan)
        count = np.where(gb0.valid, 4, 0)
        px = valid_pixels(gb1, radius)
        one_tap = np.zeros((1, 2))

        def update(acc, prev, cur):
            def call():
                acc.set_history(h0, count, prev)
                # a fresh wrapper of the same buffers: its view-space positions are built in the call
                return acc.update(x1, cur.with_motion(None))
            return call

        configs = {
            "static mean": (Accumulator("mean"), gb0, gb0),
            "orbit mean": (Accumulator("mean"), gb0, gb1),
            "orbit mean nearest": (Accumulator("mean", fetch="nearest"), gb0, gb1),
            "orbit mean clamp": (Accumulator("mean", clamp=True), gb0, gb1),
            "orbit clip:0.1": (Accumulator("clip:0.1"), gb0, gb1),
        }
        fns = {"floor": lambda: gather_floor(px, one_tap)}
        fns.update({name: update(*cfg) for name, cfg in configs.items()})
        t = _bench.interleaved(fns, args.repeats, statistic="median")
        floor = t["floor"].seconds
        pixels = gb1.valid.size
        report.header(f"{size}x{size}: median of {args.repeats} interleaved rounds; floor = one tap per pixel")
        report.row("gather floor (1 tap)", floor, floor)
        for name in configs:
            peak = _bench.peak_bytes(fns[name]) / pixels if name == "orbit mean" else None
            report.row(name, t[name].seconds, floor, peak)
            report.goal(f"{name} / gather floor (1 tap)", t[name].seconds / floor, GOAL_FLOOR, at_least=False)
        report.note("history kept per pixel (bytes)", HISTORY_BYTES_PER_PIXEL, unit=" B")

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
