"""The memory model checked: each stage's measured peak beside the estimate that refuses requests.

``vobscure._memory`` estimates, before any work, the peak memory of a request (bytes per pixel
plus fixed bytes per stage) and refuses what exceeds the memory available. This script measures
the peaks those estimates stand for and prints both, so the model is checked, not assumed:

- per stage on the Cornell box at its suggested camera: ``render_gbuffer`` (one layer and
  ``layers=4``), every lazy world- and view-space image, each reference kind
  (``ground_truth`` ao / obscurance / volumetric, ``vo_reference``), the screen-space
  estimators (the model has one figure: the largest's), the ``vobscure render`` job, the
  ``vobscure estimate`` job (one frame; four with a flicker reference) and a whole
  ``compare()`` job;
- ``GBuffer.from_arrays`` of a float32 depth image (without normals: derived from the depth;
  and with float32 normals): its peak over its input's and its output's size.

Memory is tracemalloc's peak of one call (``_bench.peak_bytes``, tracing started just before
it; the render and compare jobs after a 16 x 16 warm-up of each, whose imports and caches are
not a request's memory): NumPy's arrays exactly; allocations outside Python's allocator (Embree's scene and its
per-thread stacks, matplotlib's Agg canvas) are not seen, which is one reason the refusal
leaves 20 % of the memory available aside (``MEMORY_FRACTION``). The ratio column is
estimate / measured: the models must not under-estimate by more than ``MODEL_UNDER`` (ratio
>= 0.8); over-estimates only make the refusal cautious.

Run from the repository root::

    python benchmarks/bench_memory.py            # 128^2 and 256^2, about a minute and a half
    python benchmarks/bench_memory.py --quick    # 64^2 and 96^2, about 20 s
"""

from __future__ import annotations

import sys
import tempfile

import numpy as np

import _bench
import vobscure as vo
from vobscure import _memory as mem
from vobscure.raytrace import default_threads


class Report(_bench.Report):
    columns = f"{'stage':<34} {'size':>9} {'measured B/px':>14} {'model B/px':>11} {'model/measured':>15}"
    summary_title = "Summary (estimate / measured peak; the smallest over sizes)"
    label_width = 44

    def row(self, stage, n, measured, model):
        print(f"  {stage:<34} {n:>4}x{n:<4} {measured:14.1f} {model:11.1f} {model / measured:15.2f}")


def from_arrays_peak(n: int, normals: bool) -> tuple[float, float, float]:
    """(peak / input bytes, peak / output bytes, peak bytes) of ``GBuffer.from_arrays`` on an
    n x n float32 depth of a tilted wave (an eighth of it background)."""
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(n, n), fov_y=40)
    yy, xx = np.mgrid[0:n, 0:n] / n
    depth = (4 + 0.5 * np.sin(6 * xx) * np.cos(5 * yy)).astype(np.float32)
    depth[:, : n // 8] = np.inf
    del yy, xx
    nrm = None
    if normals:
        nrm = np.zeros((n, n, 3), np.float32)
        nrm[..., 2] = -1.0
    held = {}

    def call():
        held["gb"] = vo.GBuffer.from_arrays(depth, nrm, camera=cam)

    peak = _bench.peak_bytes(call)
    gb = held["gb"]
    given = depth.nbytes + (0 if nrm is None else nrm.nbytes)
    out = gb.depth.nbytes + gb.normal.nbytes + gb.valid.nbytes
    return peak / given, peak / out, peak


def main(argv=None) -> int:
    parser = _bench.parser(__doc__, quick="64^2 and 96^2 (about 20 s)", statistic="one call; ignored")
    args = _bench.parse(parser, argv)
    sizes = (64, 96) if args.quick else (128, 256)
    fa_sizes = (512, 1024) if args.quick else (1024, 4096)
    threads = default_threads()

    def body(report):
        _bench.machine_facts(f"tracemalloc peaks; {threads} threads; the model's fixed bytes scale with them")
        scene = vo.scenes.cornell_box()
        scene.tracer  # noqa: B018 - the Embree scene is built outside the measured calls
        worst = {}
        with tempfile.TemporaryDirectory() as tmp:   # first calls' imports and caches are not a request's memory
            from vobscure.cli import render
            from vobscure.experiments.compare import compare

            render(size=(16, 16), rays=4, out=tmp, progress=False)
            compare(scene, size=(16, 16), quick=True, cache=False, out=tmp, suggest=False)

        def check(stage, n, peak, need):
            pixels = n * n
            measured, model = peak / pixels, need.bytes(pixels) / pixels
            report.row(stage, n, measured, model)
            worst[stage] = min(worst.get(stage, np.inf), model / measured)

        for n in sizes:
            report.header(f"Cornell box, {n} x {n}")
            cam = scene.camera((n, n))
            r = 0.1 * scene.extent
            check("render_gbuffer", n, _bench.peak_bytes(lambda: vo.render_gbuffer(scene, cam)), mem.gbuffer_need(1))
            check("render_gbuffer layers=4", n, _bench.peak_bytes(lambda: vo.render_gbuffer(scene, cam, layers=4)),
                  mem.gbuffer_need(4))
            gb = vo.render_gbuffer(scene, cam)
            check("lazy images", n, _bench.peak_bytes(lambda: (gb.hits, gb.world_position, gb.world_normal,
                                                                gb.world_geometric_normal, gb.position,
                                                                gb.geometric_normal)), mem.lazy_images_need())
            for name, kw in (("ao", dict(rays=256)), ("obscurance", dict(rays=256)), ("volumetric", dict(samples=256))):
                check(f"ground_truth {name}", n,
                      _bench.peak_bytes(lambda: vo.ground_truth(scene, gb, quantity=name, radius=r, **kw)),
                      mem.reference_need(name))
            check("vo_reference (screen, 800)", n,
                  _bench.peak_bytes(lambda: vo.vo_reference(gb, radius=r, samples=800)), mem.reference_need("screen"))
            estimators = {"vo_point 33": lambda: vo.vo_point(gb, radius=r, samples=33),
                          "vo_line 9": lambda: vo.vo_line(gb, radius=r, samples=9),
                          "vo_area 1": lambda: vo.vo_area(gb, radius=r, samples=1),
                          "gtao": lambda: vo.gtao(gb, radius=r), "hbao": lambda: vo.hbao(gb, radius=r),
                          "vbao": lambda: vo.vbao(gb, radius=r, thickness=r)}
            peaks = {k: _bench.peak_bytes(f) for k, f in estimators.items()}
            top = max(peaks, key=peaks.get)
            check(f"estimators (largest: {top})", n, peaks[top], mem.estimator_need())
            del gb
            with tempfile.TemporaryDirectory() as tmp:
                from vobscure.cli import render

                check("vobscure render (ao, 64 rays)", n,
                      _bench.peak_bytes(lambda: render(size=(n, n), rays=64, out=tmp, progress=False)),
                      mem.render_job_need("ao"))
                from vobscure.experiments.compare import DEFAULT_METHODS, compare, parse_methods

                refs = ("screen", "volumetric", "ao")
                depth = vo.render_gbuffer(scene, cam).depth.astype(np.float32)
                for k in range(4):
                    np.save(f"{tmp}/frame_{k}.npy", depth)
                from vobscure.cli import main

                fov = str(cam.to_dict()["fov_y"])
                for frames, pattern, extra in ((1, "frame_0.npy", []), (4, "frame_*.npy", ["--flicker-reference", "64"])):
                    argv = ["estimate", "--depth", f"{tmp}/{pattern}", "--fov", fov, "--radius", "0.5", "--quiet",
                            "--out", f"{tmp}/est{frames}" + (".npy" if frames == 1 else ""), *extra]
                    if frames > 1:
                        import os

                        os.makedirs(f"{tmp}/est{frames}", exist_ok=True)
                    main(argv)                                           # warm-up: the first call's imports
                    check(f"estimate ({frames} frame{'s, flicker' if extra else ''})", n,
                          _bench.peak_bytes(lambda: main(argv)),
                          mem.estimate_job_need(frames, flicker_reference=bool(extra)))
                check("compare() (3 refs, 5 methods)", n,
                      _bench.peak_bytes(lambda: compare(scene, size=(n, n), references=refs, repeats=1, rays=64,
                                                        volume_samples=256, screen_samples=256, cache=False,
                                                        out=tmp, suggest=False)),
                      mem.compare_need(references=refs, configs=len(parse_methods(DEFAULT_METHODS)),
                                       pixels=n * n))
        report.header("GBuffer.from_arrays of a float32 depth (peak / input, peak / output)")
        for n in fa_sizes:
            for normals in (False, True):
                per_in, per_out, peak = from_arrays_peak(n, normals)
                print(f"  from_arrays {'with' if normals else 'without'} normals {n}x{n}: peak "
                      f"{mem.format_bytes(peak)} = {per_in:.2f} x input, {per_out:.2f} x output")
                report.note(f"from_arrays {'+' if normals else '-'}normals {n}^2: peak / output", per_out)
        for stage, ratio in worst.items():
            report.goal(stage, ratio, 1 - mem.MODEL_UNDER, at_least=True)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
