"""The cost of the 64 x 64 noise tiles (``"r2"``, ``"gtao"``) against the 4 x 4 white tile.

The machine this runs on is shared and noisy, so every result is a *ratio* of two timings
taken in the same run (median of ``--repeats`` rounds, the calls interleaved round by round,
``_bench.interleaved``); absolute times are context only.

What is measured
----------------
The Cornell box at its suggested camera, 256 x 256 (64 x 64 with ``--quick``), radius
0.1 x the scene's extent, each estimator at its default arguments under the schedules
``"white"`` (the default 4 x 4 tile: pixels grouped by texel), ``"r2"`` and ``"gtao"`` (64 x 64
tiles: a texel per pixel, ``_common.per_pixel_noise``): ``vo_line`` (its default nearest
fetch), ``sao`` and ``alchemy``, the estimators that group pixels by texel. Goal: r2 and gtao
within 1.5x of white. ``--others`` adds ``vo_area``, ``hbao`` and ``vbao``, which read the
texel per pixel whatever the tile (no goal: context). ``--grouped`` adds r2 with the pixels
grouped by texel as a tile of 4096 texels used to be (``MAX_NOISE_CLASSES`` raised for the
call): the cost the per-pixel reading avoids (seconds a call at 256 x 256).

Run from the repository root::

    python benchmarks/bench_noise_tiles.py              # about a minute
    python benchmarks/bench_noise_tiles.py --quick      # seconds (smoke test)
"""

from __future__ import annotations

import sys

import _bench

import vobscure as vo
from vobscure.screenspace import _common

GOAL_WHITE = 1.5
FIXED = ("vo_line", "sao", "alchemy")
OTHERS = ("vo_area", "hbao", "vbao")
SCHEDULES = ("white", "r2", "gtao")


class Report(_bench.Report):
    columns = f"{'estimator':<10} {'schedule':<12} {'median s':>9} {'x white':>8}"
    label_width = 40

    def row(self, name, schedule, seconds, white):
        print(f"  {name:<10} {schedule:<12} {seconds:9.4f} {seconds / white:7.2f}x")


def grouped(fn):
    """``fn`` run with the pixels grouped by texel whatever the tile's size."""
    def call():
        saved = _common.MAX_NOISE_CLASSES
        _common.MAX_NOISE_CLASSES = 1 << 30
        try:
            return fn()
        finally:
            _common.MAX_NOISE_CLASSES = saved
    return call


def main(argv=None) -> int:
    p = _bench.parser(__doc__, quick="64 x 64, a few seconds", statistic="median")
    p.add_argument("--others", action="store_true", help="also vo_area, hbao, vbao (context)")
    p.add_argument("--grouped", action="store_true", help="also r2 grouped by texel (slow)")
    args = _bench.parse(p, argv)
    size = 64 if args.quick else 256
    _bench.machine_facts(f"image {size} x {size}, Cornell box, radius 0.1 x extent")

    def body(report):
        sc = vo.scenes.cornell_box()
        gb = vo.render_gbuffer(sc, sc.camera(size=(size, size)))
        radius = 0.1 * sc.extent
        names = FIXED + (OTHERS if args.others else ())
        fns = {}
        for name in names:
            f = getattr(vo, name)
            for schedule in SCHEDULES:
                fns[name, schedule] = (lambda f=f, s=schedule: f(gb, radius=radius, schedule=s))
            if args.grouped and name in FIXED:
                fns[name, "r2 grouped"] = grouped(lambda f=f: f(gb, radius=radius, schedule="r2"))
        t = _bench.interleaved(fns, args.repeats, statistic="median")
        report.header(f"{size}x{size}: median of {args.repeats} interleaved rounds")
        for name in names:
            white = t[name, "white"].seconds
            for schedule in SCHEDULES + (("r2 grouped",) if (name, "r2 grouped") in t else ()):
                report.row(name, schedule, t[name, schedule].seconds, white)
                if schedule in ("r2", "gtao"):
                    ratio = t[name, schedule].seconds / white
                    label = f"{name} {schedule} / white"
                    if name in FIXED:
                        report.goal(label, ratio, GOAL_WHITE, at_least=False)
                    else:
                        report.note(label, ratio)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
