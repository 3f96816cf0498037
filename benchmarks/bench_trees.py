"""Tree models of vobscure (Hegeman 2006): time against a NumPy memory floor, and memory.

The models are closed forms evaluated per point, so the floor they are measured against is
the memory traffic any per-point function of (points, normals) must do: read the points and
the normals and write one float per point. The results are *ratios* of timings taken in the
same run, the compared calls interleaved round by round (``_bench.interleaved`` over
:func:`vobscure.experiments.common.time_calls`, one untimed warm-up call each); absolute
times are context only.

What is measured
----------------
Inputs (float64, built once per size, seed 0): n points uniform in the cube [-3, 3]^3 around
a crown at the origin, unit normals uniform on the sphere. About 6 % of the points fall in
the sphere, so every model meets inside and outside points, normals facing towards, away
from and across the crown. At 10^6 and 10^7 points (10^5 and 10^6 with ``--quick``):

- **floor**: ``np.einsum("ij,ij->i", points, normals, out=out)``: reads the 48 B of a
  point and its normal, writes the 8 B of one float, with 3 multiply-adds per point. It is
  the floor of every row marked "points floor". A plain copy of the same 56 B per point
  (``np.copyto``) is printed as context, and the summary gives floor / copy: at 10^7
  points the copy is about twice as fast as the einsum (which is not purely
  bandwidth-bound on 3-element rows), so multiply a ratio by that factor to get it against
  the raw copy.
- **canopy, sphere** / **canopy, ellipsoid**: ``vobscure.trees.canopy_visibility`` (Eqs.
  4-6) on ``Sphere((0, 0, 0), 1.5)`` and on ``Ellipsoid((0, 0, 0), (2.0, 1.2, 0.9))``
  rotated off the axes, density 0.3. Goals: <= 8x and <= 12x the floor.
- **poisson, sphere** / **poisson, ellipsoid**: ``vobscure.trees.poisson_visibility`` (the
  Poisson leaf cloud's expected visibility, cosine weighting, extinction 1) on the same
  shells: a bilinear lookup in a (rho, u) table summed once per call for the call's sigma R.
  Goal: <= 2x ``canopy_visibility`` on the same shell, timed in the same
  interleaved rounds (the summary prints the ratios). The table's geometry is built once per
  process, at the first call: that first call is timed on its own, before everything else
  (``poisson table build``), and is not part of the ratios.
- **occluder, hegeman / exact (cosine) / porous (cosine, sigma 1)**:
  ``vobscure.trees.occluder_visibility`` with the same sphere. The porous model is the direct
  quadrature of the same integral (``vobscure.trees.sphere_transmittance``: 2 x 16
  Gauss-Legendre nodes in psi per point, 4 x 16 inside the sphere, each a closed-form chord
  and azimuthal weight); it is far above the floor by construction, and is timed in its own
  interleaved pair (floor, porous) with ONE round after the warm-up.
- **grass**: ``vobscure.trees.grass_visibility(height, h, cos_theta)`` on (n,) float64
  arrays; its own floor is ``np.add(height, cos_theta, out=out)`` (reads 16 B, writes
  8 B per point), the "grass floor".
- **peak B/pt**: peak extra memory per point, ``tracemalloc`` started after the inputs are
  built, one call, peak / n. It includes the returned (n,) float64 array (8 B/pt). Goal:
  < 100 B/pt for every model. The models work on chunks (``chunk``), so this
  does not grow with n.

Run from the repository root::

    python benchmarks/bench_trees.py            # 10^6 and 10^7 points, a few minutes
    python benchmarks/bench_trees.py --quick    # 10^5 and 10^6 points, under a minute
    python benchmarks/bench_trees.py --repeats 5
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

# The only BLAS calls of the measured functions are the ellipsoids' (n, 3) @ (3, 3) maps, for
# which threads are pure overhead; on a shared machine OpenBLAS's spinning threads stall them
# (canopy on an ellipsoid measured at 107x the floor with threads, 7x without, same minute).
# Set before NumPy loads; an explicit setting in the environment wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source tree
sys.path.insert(0, str(Path(__file__).resolve().parent))      # the shared _bench module

import _bench  # noqa: E402
from _bench import Timing, interleaved, peak_bytes  # noqa: E402
from vobscure.trees import (  # noqa: E402
    Ellipsoid,
    Sphere,
    canopy_visibility,
    grass_visibility,
    occluder_visibility,
    poisson_visibility,
)

FULL_SIZES = (10**6, 10**7)
QUICK_SIZES = (10**5, 10**6)
#: the crown: a sphere and an ellipsoid of about the same size, rotated off the axes
SPHERE = Sphere((0.0, 0.0, 0.0), 1.5)
_c, _s = np.cos(0.4), np.sin(0.4)
ELLIPSOID = Ellipsoid((0.0, 0.0, 0.0), (2.0, 1.2, 0.9),
                      np.array([[_c, -_s, 0.0], [_s, _c, 0.0], [0.0, 0.0, 1.0]]))
DENSITY = 0.3        # alpha rho of the canopy model
SIGMA = 1.0          # extinction of the porous occluder
BLADE_HEIGHT = 0.3
#: the goals: canopy_visibility against the floor, and memory per point
GOAL_CANOPY_SPHERE = 8.0
GOAL_CANOPY_ELLIPSOID = 12.0
GOAL_PEAK_BYTES = 100.0
#: the goal: poisson_visibility against canopy_visibility on the same shell
GOAL_POISSON_VS_CANOPY = 2.0


# --------------------------------------------------------------------------- inputs
def inputs(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    points = rng.uniform(-3.0, 3.0, (n, 3))
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    height = rng.uniform(0.0, BLADE_HEIGHT, n)
    cos_theta = rng.uniform(-1.0, 1.0, n)
    return points, normals, height, cos_theta


# --------------------------------------------------------------------------- report
class Report(_bench.Report):
    columns = (f"{'call':<30} {'median s':>9} {'cores':>5} {'ns/pt':>7} {'floor':>14} {'floor s':>8} "
               f"{'x floor':>8} {'peak B/pt':>10}")
    summary_title = ("Summary (time ratios are medians from this one run, each against the floor\n"
                     "   timed in the same interleaved rounds)")
    label_width = 58

    @staticmethod
    def row(label, n, timing: Timing, floor: Timing | None = None, floor_name="", peak=None, note=""):
        ratio = f"{timing.seconds / floor.seconds:7.2f}x" if floor else f"{'':8}"
        fl = f"{floor.seconds:8.4f}" if floor else f"{'':8}"
        p = f"{peak / n:10.1f}" if peak is not None else f"{'':10}"
        print(f"  {label:<30} {timing.seconds:9.4f} {timing.cores:5.2f} {timing.seconds / n * 1e9:7.1f} "
              f"{floor_name:>14} {fl} {ratio} {p} {note}".rstrip())


# --------------------------------------------------------------------------- benchmark
def bench_size(n: int, repeats: int, report: Report):
    points, normals, height, cos_theta = inputs(n)
    out = np.empty(n)
    copy_src, copy_dst = np.empty(7 * n), np.empty(7 * n)          # 56 B per point
    grass_out = np.empty(n)
    calls = {
        "floor": lambda: np.einsum("ij,ij->i", points, normals, out=out),
        "copy 56 B/pt": lambda: np.copyto(copy_dst, copy_src),
        # each Poisson call right after the canopy call it is compared with, so that both
        # follow a call of the same kind (the ellipsoids' (n, 3) @ (3, 3) products go to BLAS,
        # whose threads may still hold the second core for the next call)
        "canopy, sphere": lambda: canopy_visibility(points, normals, SPHERE, density=DENSITY),
        "poisson, sphere": lambda: poisson_visibility(points, normals, SPHERE, extinction=SIGMA),
        "canopy, ellipsoid": lambda: canopy_visibility(points, normals, ELLIPSOID, density=DENSITY),
        "poisson, ellipsoid": lambda: poisson_visibility(points, normals, ELLIPSOID, extinction=SIGMA),
        "occluder, hegeman": lambda: occluder_visibility(points, normals, SPHERE, model="hegeman"),
        "occluder, exact": lambda: occluder_visibility(points, normals, SPHERE, model="exact"),
        "grass floor": lambda: np.add(height, cos_theta, out=grass_out),
        "grass": lambda: grass_visibility(height, BLADE_HEIGHT, cos_theta),
    }
    porous = {
        "floor": calls["floor"],
        "occluder, porous": lambda: occluder_visibility(points, normals, SPHERE, model="porous", sigma=SIGMA),
    }
    t = interleaved(calls, repeats, statistic="median")
    tp = interleaved(porous, 1, statistic="median")
    peaks = {k: peak_bytes(calls[k]) for k in calls if "floor" not in k and "copy" not in k}
    peaks["occluder, porous"] = peak_bytes(porous["occluder, porous"])

    report.header(f"{n:.0e} points ({repeats} rounds; the porous pair 1 round)")
    report.row("floor (einsum row dot)", n, t["floor"], floor_name="", note="reads 48 B, writes 8 B per point")
    report.row("copy 56 B/pt (context)", n, t["copy 56 B/pt"], t["floor"], "points floor")
    for k in ("canopy, sphere", "canopy, ellipsoid", "poisson, sphere", "poisson, ellipsoid", "occluder, hegeman",
              "occluder, exact"):
        report.row(k, n, t[k], t["floor"], "points floor", peaks[k])
    report.row("occluder, porous", n, tp["occluder, porous"], tp["floor"], "points floor", peaks["occluder, porous"],
               note="(floor of its own pair)")
    report.row("grass floor (np.add)", n, t["grass floor"], note="reads 16 B, writes 8 B per point")
    report.row("grass", n, t["grass"], t["grass floor"], "grass floor", peaks["grass"])

    tag = f"{n:.0e}"
    report.note(f"floor (einsum) / copy of the same 56 B/pt ({tag})", t["floor"].seconds / t["copy 56 B/pt"].seconds)
    report.goal(f"canopy_visibility, sphere / floor ({tag})", t["canopy, sphere"].seconds / t["floor"].seconds,
                GOAL_CANOPY_SPHERE, at_least=False)
    report.goal(f"canopy_visibility, ellipsoid / floor ({tag})",
                t["canopy, ellipsoid"].seconds / t["floor"].seconds, GOAL_CANOPY_ELLIPSOID, at_least=False)
    for shell in ("sphere", "ellipsoid"):
        report.goal(f"poisson_visibility / canopy_visibility, {shell} ({tag})",
                    t[f"poisson, {shell}"].seconds / t[f"canopy, {shell}"].seconds, GOAL_POISSON_VS_CANOPY,
                    at_least=False)
    for k in ("occluder, hegeman", "occluder, exact"):
        report.note(f"{k} / floor ({tag})", t[k].seconds / t["floor"].seconds)
    report.note(f"occluder, porous / floor ({tag})", tp["occluder, porous"].seconds / tp["floor"].seconds)
    report.note(f"grass / grass floor ({tag})", t["grass"].seconds / t["grass floor"].seconds)
    worst = max(peaks, key=peaks.get)
    report.goal(f"peak extra memory, worst call ({worst}, {tag})", peaks[worst] / n, GOAL_PEAK_BYTES,
                at_least=False, unit=" B/pt")


def main(argv=None) -> int:
    parser = _bench.parser(__doc__, quick="10^5 and 10^6 points (under a minute)", statistic="median")
    args = _bench.parse(parser, argv)
    sizes = QUICK_SIZES if args.quick else FULL_SIZES

    def body(report):
        import time

        _bench.machine_facts("NumPy code on one thread (the 'cores' column shows what each call got)")
        t0 = time.perf_counter()
        poisson_visibility([[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]], SPHERE, extinction=SIGMA)
        print(f"  poisson table build (first call in this process, once): {time.perf_counter() - t0:.3f} s")
        print(f"  mode: {'quick' if args.quick else 'full'}   repeats: median of {args.repeats}   "
              f"sizes: {', '.join(f'{n:.0e}' for n in sizes)} points")
        for n in sizes:
            bench_size(n, args.repeats, report)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
