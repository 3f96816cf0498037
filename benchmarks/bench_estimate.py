"""A user's frame through ``vobscure estimate``: time and peak extra memory per pixel.

The Cornell box is rendered at 4096 x 2048 (1024 x 512 with ``--quick``) and written as a
Blender-style EXR (``vobscure.io.write_gbuffer``: ``View Layer.Depth.Z`` and
``View Layer.Normal.X/Y/Z``, float32). Then, each traced from its own start with tracemalloc
(peak bytes over the pixel count):

- reading the EXR (``vobscure.io.read_buffers``: the float32 depth and normals it returns are
  16 bytes a pixel of the peak),
- ``GBuffer.from_arrays`` on them (converted and checked in bands of rows),
- the whole command ``vobscure estimate --depth frame.exr --fov ... --radius ... --out vo.exr``
  in this process (read, convert, ``line:9``, write).

Goal: peak extra memory of the command < 100 bytes per pixel. Times are one run's
on a shared machine.

Run ``python benchmarks/bench_estimate.py [--quick]`` from the repository root.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _bench  # noqa: E402
from _bench import peak_bytes  # noqa: E402

#: Frame sizes (width, height): full and --quick.
SIZES = {False: (4096, 2048), True: (1024, 512)}
#: Goal of the command's peak extra memory, bytes per pixel.
GOAL_BYTES_PER_PIXEL = 100.0
#: Ball radius of the estimate (the Cornell box is about 3.75 across).
RADIUS = 0.3


def main(argv=None) -> int:
    p = _bench.parser(__doc__, quick="1024 x 512 instead of 4096 x 2048", statistic="best")
    args = _bench.parse(p, argv)
    import vobscure as vo
    from vobscure import io as vio
    from vobscure.cli import main as cli

    _bench.machine_facts()
    W, H = SIZES[args.quick]
    pixels = W * H
    scene = vo.scenes.cornell_box()
    camera = scene.camera((W, H))
    with tempfile.TemporaryDirectory() as tmp:
        frame = Path(tmp) / "frame.exr"
        vio.write_gbuffer(frame, vo.render_gbuffer(scene, camera))
        fov = camera.to_dict()["fov_y"]
        view = vo.Camera.look_at((0, 0, 0), (0, 0, 1), size=(W, H), fov_y=fov)
        read = {}
        peak_read = peak_bytes(lambda: read.setdefault("buffers", vio.read_buffers(frame)))
        depth, normal, _ = read["buffers"]
        peak_convert = peak_bytes(lambda: vo.GBuffer.from_arrays(depth, normal, camera=view))
        del depth, normal, read
        argv_cli = ["estimate", "--depth", str(frame), "--fov", f"{fov}", "--radius", f"{RADIUS}",
                    "--out", str(Path(tmp) / "vo.exr"), "--quiet"]
        t0 = time.perf_counter()
        peak_cli = peak_bytes(lambda: cli(argv_cli))
        seconds = time.perf_counter() - t0
    print(f"\n  frame {W} x {H} ({pixels / 1e6:.1f} Mpixels), line:9, radius {RADIUS}")
    print(f"  read EXR (read_buffers)          peak {peak_read / pixels:7.1f} B/px")
    print(f"  GBuffer.from_arrays              peak {peak_convert / pixels:7.1f} B/px")
    met = peak_cli / pixels < GOAL_BYTES_PER_PIXEL
    print(f"  vobscure estimate (in process)   peak {peak_cli / pixels:7.1f} B/px "
          f"(goal < {GOAL_BYTES_PER_PIXEL:g}: {'met' if met else 'MISSED'}), {seconds:.1f} s (traced)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
