"""How much of a screen-space estimator's error comes from the image border: the guard band.

For each scene the G-buffer is rendered without a guard band and with one as wide as the
ball's largest projected radius (``guard = ceil(max R fy / z)`` over the covered pixels, so
that every tap of every inner pixel reads real depth); the estimators run on both and are
scored on the same inner frame against:

- ``vo_line`` (9 lines): the converged screen-space VO, ``vo_reference`` on the guarded
  G-buffer (the screen-space VO of an unbounded depth buffer);
- ``gtao`` (3 slices x 3 steps): the ray-cast cosine AO within R, ``ground_truth(quantity="ao")``
  (world space: the same with or without the guard).

Printed per scene and estimator: the RMSE over the whole frame and over the border strip (the
pixels within ``guard`` of the edge) without and with the guard, and the share of the whole
frame's squared error the strip holds without the guard.

Run from the repository's root::

    python benchmarks/guard_band.py           # about a minute on 2 cores
"""

from __future__ import annotations

import math
import time

import numpy as np

import vobscure as vo
from vobscure.experiments.common import choose_radius

#: (scene, image size): the Cornell box at 128 x 128 and the atrium at 192 x 108.
SCENES = (("cornell_box", (128, 128)), ("atrium", (192, 108)))
#: Segments per pixel of the screen-space reference, rays per pixel of the AO reference, seed.
REFERENCE_SAMPLES, AO_RAYS, SEED = 1024, 128, 0


def _rmse(a, b, mask):
    d = (a - b)[mask & np.isfinite(a) & np.isfinite(b)]
    return float(np.sqrt(np.mean(d * d))), float(np.sum(d * d))


def measure(name, size):
    scene = vo.scenes.get(name)
    camera = scene.camera(size)
    plain = vo.render_gbuffer(scene, camera)
    radius = choose_radius(scene, plain).radius
    z = plain.depth[plain.valid]
    guard = int(math.ceil(np.max(radius * camera.fy / z)))
    guarded = vo.render_gbuffer(scene, camera, guard=guard)
    H, W = plain.shape
    border = np.ones((H, W), dtype=bool)
    border[guard:H - guard, guard:W - guard] = False
    whole = np.ones((H, W), dtype=bool)
    allow_open = bool(scene.open_meshes)
    screen = vo.vo_reference(guarded, radius=radius, samples=REFERENCE_SAMPLES, seed=SEED).value
    ao = vo.ground_truth(scene, plain, quantity="ao", radius=radius, rays=AO_RAYS, seed=SEED,
                         allow_open=allow_open).value
    rows = []
    for label, fn, ref in (("vo_line:9 vs screen VO", lambda gb: vo.vo_line(gb, radius=radius, samples=9), screen),
                           ("gtao:3x3 vs ray-cast AO", lambda gb: vo.gtao(gb, radius=radius), ao)):
        row = dict(scene=name, size=f"{W}x{H}", radius=radius, guard=guard, estimator=label,
                   border_share_pixels=float(border.mean()))
        for g, gb in ((0, plain), (guard, guarded)):
            t0 = time.perf_counter()
            est = fn(gb)
            row[f"seconds_g{g > 0:d}"] = time.perf_counter() - t0
            row[f"rmse_g{g > 0:d}"], sse = _rmse(est, ref, whole)
            row[f"border_rmse_g{g > 0:d}"], sse_border = _rmse(est, ref, border)
            row[f"interior_rmse_g{g > 0:d}"], _ = _rmse(est, ref, ~border)
            if g == 0:
                row["border_share_sse_g0"] = sse_border / sse
        rows.append(row)
    return rows


def main():
    rows = [r for name, size in SCENES for r in measure(name, size)]
    cols = ["scene", "size", "radius", "guard", "estimator", "rmse_g0", "rmse_g1", "border_rmse_g0",
            "border_rmse_g1", "interior_rmse_g0", "interior_rmse_g1", "border_share_pixels",
            "border_share_sse_g0", "seconds_g0", "seconds_g1"]
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(f"{r[c]:.4g}" if isinstance(r[c], float) else str(r[c]) for c in cols) + " |")


if __name__ == "__main__":
    main()
