"""Object-space AO of vobscure: cost growth over mesh sizes, one section per method.

Section ``bunnell``: Bunnell's disks (``vobscure.objectspace.bunnell``), the exact
O(n^2) sum (``hierarchy=False``) against the tree of aggregated disks (``hierarchy=True``,
``open_ratio`` 4), on one family of meshes at growing sizes. The results are ratios and
log-log slopes of timings taken in the same run; absolute times are context only.

What is measured
----------------
Meshes: an icosphere of 3 to 6 subdivisions (642, 2562, 10242, 40962 vertices; 642 to 10242
with ``--quick``) with its radius modulated, r = 1 + 0.3 sin(3x) sin(3y) sin(3z), so that half
the surface lies in dents that occlude each other (the disks are not all open). Passed as a
``trimesh.Trimesh``, so that nothing is cached between calls. Per size and form:

- **pass 1 s**: wall time of ``bunnell(mesh, passes=1)``: the disks, (the tree), one pass.
- **pass 2 s**: of ``passes=2`` minus that of ``passes=1``: one more pass, the tree reused.
- **evals/pass**: ``shadow_evaluations`` (shadow terms of one pass; n^2 for the exact sum).
- **peak B/disk**: peak extra memory of one ``passes=1`` call (``tracemalloc``) per disk.

The exact sum stops at 10242 disks (2562 with ``--quick``): at 40962 it would take minutes.
The summary fits log t = a + b log n by least squares over the sizes of each form and prints
b (2 for an O(n^2) cost, a little above 1 for O(n log n)), the same for the evaluations, and
the tree / exact ratios at the largest size both ran.

Timings are the median (``--repeats``) of interleaved rounds after one warm-up call
(``_bench.interleaved``); the sizes above 2562 disks get one round.

Section ``spheres``: Ren et al. 2006's sphere sets in SH
(``vobscure.objectspace.sphere_set_ao``). Receivers on a plane under 1 to 256 spheres (1 to 64
with ``--quick``) of the same total volume; per SH order (4 and 6; 4 with ``--quick``) and
count, the median time per receiver of ``method="product"`` (one SH product per sphere),
``"shexp"`` (log vectors summed, one hybrid exponential) and ``"sum"``, interleaved in the same
rounds, and the ratio product / shexp (the paper claims 10x or more on the CPU). Then the
peak extra memory per receiver (``tracemalloc``) at order 6 with 256 spheres
(64 spheres with ``--quick``), 2048 receivers and one chunk of 1024 (goal < 2 KB per receiver).

Run from the repository root::

    python benchmarks/bench_objectspace.py            # up to 40962 disks, a few minutes
    python benchmarks/bench_objectspace.py --quick    # up to 10242 disks, about a minute
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source tree
sys.path.insert(0, str(Path(__file__).resolve().parent))      # the shared _bench module

import _bench  # noqa: E402
from _bench import Timing, interleaved, peak_bytes  # noqa: E402
from vobscure.objectspace import bunnell, shadow_evaluations  # noqa: E402
from vobscure.objectspace import sphere_set_ao  # noqa: E402

#: icosphere subdivisions: 10 * 4^s + 2 vertices
FULL_SUBDIVISIONS = (3, 4, 5, 6)
QUICK_SUBDIVISIONS = (3, 4, 5)
#: the largest mesh the exact O(n^2) sum is timed on
EXACT_MAX = {False: 10242, True: 2562}
#: sizes above this get one timing round
ONE_ROUND_ABOVE = 2562
OPEN_RATIO = 4.0


def dented_sphere(subdivisions: int) -> trimesh.Trimesh:
    """An icosphere with its radius modulated by 1 + 0.3 sin(3x) sin(3y) sin(3z)."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    r = 1.0 + 0.3 * np.sin(3 * v[:, 0]) * np.sin(3 * v[:, 1]) * np.sin(3 * v[:, 2])
    return trimesh.Trimesh(v * r[:, None], mesh.faces, process=False)


def slope(n, y) -> float:
    """Least-squares slope of log y against log n."""
    return float(np.polyfit(np.log(np.asarray(n, float)), np.log(np.asarray(y, float)), 1)[0])


class Report(_bench.Report):
    columns = (f"{'form':<7} {'disks':>7} {'pass 1 s':>9} {'cores':>5} {'pass 2 s':>9} {'evals/pass':>12} "
               f"{'evals/n^2':>9} {'peak B/disk':>11}")
    summary_title = "Summary (slopes and ratios from this one run)"
    label_width = 62

    @staticmethod
    def row(form, n, t1: Timing, t2: Timing, evals: int, peak: int):
        print(f"  {form:<7} {n:7d} {t1.seconds:9.3f} {t1.cores:5.2f} {t2.seconds - t1.seconds:9.3f} "
              f"{evals:12d} {evals / n / n:9.4f} {peak / n:11.0f}")


# --------------------------------------------------------------------------- sections
def bench_bunnell(args, report: Report):
    """Bunnell's disks: exact sum against the tree over mesh sizes."""
    subdivisions = QUICK_SUBDIVISIONS if args.quick else FULL_SUBDIVISIONS
    report.header(f"bunnell: exact sum vs tree (open_ratio {OPEN_RATIO:g}), dented icospheres")
    measured = {"exact": {}, "tree": {}}
    for s in subdivisions:
        mesh = dented_sphere(s)
        n = len(mesh.vertices)
        repeats = args.repeats if n <= ONE_ROUND_ABOVE else 1
        for form, hierarchy in (("exact", False), ("tree", True)):
            if form == "exact" and n > EXACT_MAX[args.quick]:
                continue
            opts = dict(hierarchy=hierarchy, open_ratio=OPEN_RATIO)
            t = interleaved({"1": lambda: bunnell(mesh, passes=1, **opts),
                             "2": lambda: bunnell(mesh, passes=2, **opts)}, repeats, statistic="median")
            evals = shadow_evaluations(mesh, **opts)
            peak = peak_bytes(lambda: bunnell(mesh, passes=1, **opts))
            report.row(form, n, t["1"], t["2"], evals, peak)
            measured[form][n] = (t["1"].seconds, t["2"].seconds - t["1"].seconds, evals, peak)
    for form, rows in measured.items():
        n = sorted(rows)
        if len(n) >= 2:
            report.note(f"{form}: slope of log(pass 1 s) on log(disks), {n[0]}-{n[-1]}",
                        slope(n, [rows[k][0] for k in n]), unit="")
            report.note(f"{form}: slope of log(pass 2 s) on log(disks)",
                        slope(n, [max(rows[k][1], 1e-9) for k in n]), unit="")
            report.note(f"{form}: slope of log(evaluations) on log(disks)", slope(n, [rows[k][2] for k in n]),
                        unit="")
    common = sorted(set(measured["exact"]) & set(measured["tree"]))
    if common:
        n = common[-1]
        e, t = measured["exact"][n], measured["tree"][n]
        report.note(f"tree / exact, pass 1 time at {n} disks", t[0] / e[0])
        report.note(f"tree / exact, pass 2 time at {n} disks", t[1] / e[1])
        report.note(f"tree / exact, evaluations at {n} disks", t[2] / e[2])
        report.note(f"tree / exact, peak memory at {n} disks", t[3] / e[3])
    largest = max(measured["tree"])
    report.note(f"tree: peak extra memory per disk at {largest} disks", measured["tree"][largest][3] / largest,
                unit=" B")


# --------------------------------------------------------------------------- sphere sets
#: Sphere counts of the ``spheres`` section (Ren et al. 2006).
SPHERE_COUNTS = {False: (1, 2, 4, 8, 16, 32, 64, 128, 256), True: (1, 4, 16, 64)}
#: SH orders timed (order n = n^2 coefficients).
SPHERE_ORDERS = {False: (4, 6), True: (4,)}
#: Receivers per timed call.
SPHERE_POINTS = {False: 2048, True: 256}
#: Receivers of the peak-memory measurement (order 6; two chunks of 1024) and the goal per
#: receiver; spheres: 256 (64 with ``--quick``).
SPHERE_MEMORY_POINTS = 2048
SPHERE_MEMORY_SPHERES = {False: 256, True: 64}
SPHERE_MEMORY_GOAL = 2048


def sphere_inputs(count: int, points: int, seed: int = 0):
    """Receivers on the plane z = 0 (normals +z) under ``count`` spheres in the slab
    z in [0.3, 1.2], radii 0.5 count^(-1/3) (the same total volume at every count)."""
    rng = np.random.default_rng(seed)
    c = np.column_stack([rng.uniform(-1, 1, count), rng.uniform(-1, 1, count), rng.uniform(0.3, 1.2, count)])
    r = 0.5 * count ** (-1.0 / 3.0) * rng.uniform(0.6, 1.0, count)
    p = np.column_stack([rng.uniform(-1.3, 1.3, points), rng.uniform(-1.3, 1.3, points), np.zeros(points)])
    return p, np.tile([0.0, 0.0, 1.0], (points, 1)), c, r


def bench_spheres(args, report: Report):
    """Ren et al.'s sphere sets: time per receiver against the number of spheres, product
    against shexp (and sum), and peak memory per receiver at order 6."""
    points = SPHERE_POINTS[args.quick]
    print(f"\n== spheres: sphere_set_ao per receiver ({points} receivers), product vs shexp (hybrid) vs sum")
    print(f"  {'order':>5} {'spheres':>7} {'product us':>10} {'shexp us':>9} {'sum us':>8} {'cores':>5} "
          f"{'product/shexp':>13}")
    ratios = {}
    for order in SPHERE_ORDERS[args.quick]:
        for count in SPHERE_COUNTS[args.quick]:
            p, n, c, r = sphere_inputs(count, points)
            t = interleaved({m: (lambda m=m: sphere_set_ao(p, n, c, r, order=order, method=m))
                             for m in ("product", "shexp", "sum")}, args.repeats, statistic="median")
            us = {m: 1e6 * t[m].seconds / points for m in t}
            ratios[order, count] = us["product"] / us["shexp"]
            print(f"  {order:5d} {count:7d} {us['product']:10.2f} {us['shexp']:9.2f} {us['sum']:8.2f} "
                  f"{t['shexp'].cores:5.2f} {ratios[order, count]:13.2f}")
    for order in SPHERE_ORDERS[args.quick]:
        counts = [k for o, k in ratios if o == order]
        report.note(f"spheres: product / shexp time, order {order}, {counts[-1]} spheres", ratios[order, counts[-1]])
        report.note(f"spheres: largest product / shexp, order {order}", max(ratios[order, k] for k in counts))
    k = SPHERE_MEMORY_SPHERES[args.quick]
    p, n, c, r = sphere_inputs(k, SPHERE_MEMORY_POINTS)
    for method in ("shexp", "product", "sum"):
        sphere_set_ao(p[:8], n[:8], c, r, order=6, method=method)          # tables built, untimed
        peak = peak_bytes(lambda: sphere_set_ao(p, n, c, r, order=6, method=method))
        report.goal(f"spheres: peak B per receiver, {method}, order 6, {k} spheres",
                    peak / SPHERE_MEMORY_POINTS, SPHERE_MEMORY_GOAL, at_least=False, unit=" B")
    p, n, c, r = sphere_inputs(k, 1024)
    peak = peak_bytes(lambda: sphere_set_ao(p, n, c, r, order=6, method="shexp"))
    report.goal("spheres: the same, shexp, 1024 receivers (one chunk)", peak / 1024, SPHERE_MEMORY_GOAL,
                at_least=False, unit=" B")


# Another section goes here as ``bench_<name>(args, report)`` and one entry of SECTIONS.
SECTIONS = {"bunnell": bench_bunnell, "spheres": bench_spheres}


def main(argv=None) -> int:
    parser = _bench.parser(__doc__, quick="smaller meshes (about a minute)", statistic="median")
    parser.add_argument("--sections", default=",".join(SECTIONS),
                        help=f"comma-separated sections to run (default all: {', '.join(SECTIONS)})")
    args = _bench.parse(parser, argv)
    chosen = [s.strip() for s in args.sections.split(",") if s.strip()]
    for s in chosen:
        if s not in SECTIONS:
            parser.error(f"unknown section {s!r}; expected some of {', '.join(SECTIONS)}")

    def body(report):
        _bench.machine_facts("NumPy code on one thread (the 'cores' column shows what each call got)")
        print(f"  mode: {'quick' if args.quick else 'full'}   repeats: median of {args.repeats}   "
              f"sections: {', '.join(chosen)}")
        for s in chosen:
            SECTIONS[s](args, report)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
