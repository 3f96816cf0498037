"""Alpha-tested geometry: ray throughput with and without the alpha test, as ratios.

The machine this runs on is shared and noisy, so every result is a *ratio* of two timings
taken in the same run (best of ``--repeats`` rounds, the compared calls interleaved round by
round, ``_bench.interleaved``); absolute rates are context only.

What is measured
----------------
A plant over a floor: 400 leaf cards (0.15 x 0.15 quads, random orientations, centres
uniform in a ball of radius 0.5 whose centre is 0.6 above a 4 x 4 floor), all sharing one
64 x 64 alpha texture of an elliptic leaf (about 45 % of the texels are holes). Rays: the
ambient-occlusion rays of 4096 floor points under the plant (1024 with ``--quick``), 64
cosine-distributed directions each, origins offset as :func:`vobscure.ambient_occlusion`
offsets them, float32, built once. The same triangles are traced

- **opaque**: a :class:`~vobscure.raytrace.Tracer` without ``alpha`` (one Embree scene), and
- **alpha**: the same triangles with the cards' alpha test (``Scene(alpha=...)``: an Embree
  scene of the floor, one of the cards, and the alpha loop over the cards).

for ``occluded`` (unlimited, and limited to 0.3, the experiments' default radius of 0.1 x
the extent order) and ``intersect``, on the tracer's threads; and end to end,
``vo.ambient_occlusion(..., rays=64)`` on the two scenes. The summary gives alpha / opaque
time ratios (the cost of the alpha test) and how many rays the alpha loop handled.

Run from the repository root::

    python benchmarks/bench_alpha.py            # about half a minute
    python benchmarks/bench_alpha.py --quick    # a few seconds (smoke test)
"""

from __future__ import annotations

import sys

import numpy as np
import trimesh

import _bench
import vobscure as vo
from vobscure.sampling import square_to_cosine_hemisphere, to_world

CARDS = 400
CARD_SIZE = 0.15
RAYS = 64


def leaf_texture(size: int = 64) -> np.ndarray:
    """An elliptic leaf on a 64 x 64 card: alpha 1 inside, 0 outside."""
    i, j = np.mgrid[0:size, 0:size]
    x, y = (j + 0.5) / size - 0.5, (i + 0.5) / size - 0.5
    return ((x / 0.45) ** 2 + (y / 0.3) ** 2 <= 1.0).astype(np.float32)


def plant_scenes(seed: int = 0):
    """(scene with the cards alpha-tested, the same triangles all opaque)."""
    rng = np.random.default_rng(seed)
    h = CARD_SIZE / 2
    corners = np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], float)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    vertices, card_uv = [], []
    for _ in range(CARDS):
        r = rng.random() ** (1 / 3) * 0.5
        direction = rng.normal(size=3)
        centre = np.array([0.0, 0.6, 0.0]) + r * direction / np.linalg.norm(direction)
        rotation = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
        vertices.append(corners @ rotation.T + centre)
        card_uv.append(uv[faces])
    offsets = 4 * np.arange(CARDS)[:, None, None]
    cards = trimesh.Trimesh(np.concatenate(vertices), (faces[None] + offsets).reshape(-1, 3), process=False)
    floor = trimesh.Trimesh([[-2, 0, -2], [2, 0, -2], [2, 0, 2], [-2, 0, 2]], [[0, 2, 1], [0, 3, 2]], process=False)
    mask = vo.scenes.AlphaMask(np.concatenate(card_uv), leaf_texture())
    meshes = {"floor": floor, "cards": cards}
    return vo.Scene(meshes, alpha={"cards": mask}, smooth_angle=0), vo.Scene(meshes, smooth_angle=0)


def floor_rays(tracer, count: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    r, phi = 0.6 * np.sqrt(rng.random(count)), 2 * np.pi * rng.random(count)
    points = np.column_stack([r * np.cos(phi), np.zeros(count), r * np.sin(phi)])
    normals = np.tile([0.0, 1.0, 0.0], (count, 1))
    dirs = to_world(square_to_cosine_hemisphere(rng.random((count, RAYS, 2))), normals)
    origins = tracer.offset_origins(points, normals, dirs)
    return (points, normals, np.ascontiguousarray(origins.reshape(-1, 3), np.float32),
            np.ascontiguousarray(dirs.reshape(-1, 3), np.float32))


class Report(_bench.Report):
    columns = f"{'call':<34} {'scene':<7} {'seconds':>9} {'Mrays/s':>9} {'cores':>6}"
    summary_title = "Summary (alpha / opaque, same rays, same run)"

    def row(self, call, scene, t, rays):
        print(f"  {call:<34} {scene:<7} {t.seconds:9.4f} {rays / t.seconds / 1e6:9.2f} {t.cores:6.2f}")


def main(argv=None) -> int:
    parser = _bench.parser(__doc__, quick="1024 floor points (a few seconds)", statistic="best")
    args = _bench.parse(parser, argv)
    count = 1024 if args.quick else 4096

    def body(report):
        _bench.machine_facts("the tracer's default threads")
        alpha, opaque = plant_scenes()
        points, normals, o, d = floor_rays(alpha.tracer, count)
        n = len(o)
        ta, to = alpha.tracer, opaque.tracer
        calls = {
            "occluded": (lambda t: t.occluded(o, d)),
            "occluded, max_distance 0.3": (lambda t: t.occluded(o, d, 0.3)),
            "intersect": (lambda t: t.intersect(o, d)),
        }
        # the alpha scene finds the same floor hits as the opaque one where no card is in the way
        blocked_alpha, blocked_opaque = ta.occluded(o, d), to.occluded(o, d)
        assert np.all(blocked_alpha <= blocked_opaque)
        reached = ta._masked.run(o, d, query="OCCLUDED") != -1
        print(f"  {count} floor points x {RAYS} rays = {n} rays; {reached.mean():.1%} meet a card's "
              f"triangle, {blocked_opaque.mean():.1%} blocked with opaque cards, {blocked_alpha.mean():.1%} "
              f"through the holes")
        report.header(f"{n} rays ({args.repeats} rounds, best)")
        for name, call in calls.items():
            t = _bench.interleaved({"opaque": lambda c=call: c(to), "alpha": lambda c=call: c(ta)}, args.repeats)
            report.row(name, "opaque", t["opaque"], n)
            report.row(name, "alpha", t["alpha"], n)
            report.note(f"{name}: alpha / opaque time", t["alpha"].seconds / t["opaque"].seconds)
        t = _bench.interleaved({
            "opaque": lambda: vo.ambient_occlusion(opaque, points, normals, rays=RAYS),
            "alpha": lambda: vo.ambient_occlusion(alpha, points, normals, rays=RAYS)}, args.repeats)
        report.row("ambient_occlusion (end to end)", "opaque", t["opaque"], n)
        report.row("ambient_occlusion (end to end)", "alpha", t["alpha"], n)
        report.note("ambient_occlusion: alpha / opaque time", t["alpha"].seconds / t["opaque"].seconds)

    return _bench.run(body, Report())


if __name__ == "__main__":
    sys.exit(main())
