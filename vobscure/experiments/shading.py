"""Interreflection corrections measured against the ray-traced multi-bounce reference.

RTR 3rd ed. Sec. 9.2.1 (Eqs. 9.22-9.23) corrects the black-occluder visibility k_A for the
light the occluders reflect, from k_A and an albedo alone: Stewart and Langer's
``k_A / (1 - a (1 - k_A))`` (:func:`vobscure.shading.stewart_langer`) and Jimenez et al.'s
cubic fit (:func:`vobscure.shading.multibounce_jimenez`). Here both are applied to the
ray-traced k_A of every pixel of a scene and compared with the visibility with
interreflections that :func:`vobscure.ambient_occlusion` computes by path tracing
(``bounces``, ``albedo``), so that the error is the correction's alone: k_A itself is exact
up to its standard error.

:func:`interreflection_rows` returns one row per (scene, albedo, correction);
``python -m vobscure.experiments.shading`` prints them as a table with a verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..groundtruth import ambient_occlusion, ground_truth
from ..render import render_gbuffer
from ..scenes import get as get_scene
from ..screenspace import gtao, gtao_bent_normals
from ..shading import LinearSky, bent_normal_lookup, multibounce_jimenez, stewart_langer
from .common import default_radius

__all__ = ["CORRECTIONS", "ALBEDOS", "BOUNCES", "Interreflections", "measure", "interreflection_rows",
           "bent_normal_rows", "verdict", "main"]

#: The corrections compared: name -> f(k_A, albedo). "none" is k_A itself (black occluders).
CORRECTIONS = {
    "none": lambda k_A, a: np.asarray(k_A, dtype=np.float64),
    "stewart_langer": stewart_langer,          # RTR 3rd ed. Eq. 9.23
    "jimenez": multibounce_jimenez,            # Jimenez et al. 2016, multi-bounce fit
}
#: Albedos measured (grey surfaces).
ALBEDOS = (0.3, 0.6, 0.9)
#: Reflections followed by the reference. The light lost by stopping after N reflections is
#: at most (a (1 - k_min))^(N+1) / (1 - a (1 - k_min)) of the sky's; with a = 0.9 and the
#: Cornell box's darkest pixels (k_A about 0.1) that is 0.04 at N = 24 (and 0.2 at N = 8).
BOUNCES = 24
#: Image size and rays per pixel, full and quick.
SIZE = {False: (128, 128), True: (24, 24)}
RAYS = {False: 1024, True: 32}
#: Scenes measured by default: the enclosure the corrections are meant for, and a crease.
SCENES = ("cornell_box", "crease")


@dataclass
class Interreflections:
    """One scene's measurement: the G-buffer, the black-occluder k_A and, per albedo, the
    reference with interreflections (values and standard errors, (H, W), NaN on background)."""

    scene: str
    gbuffer: object
    k_A: np.ndarray
    k_A_stderr: np.ndarray
    reference: dict
    reference_stderr: dict
    bounces: int
    rays: int


def measure(scene: str = "cornell_box", *, albedos=ALBEDOS, bounces: int = BOUNCES, quick: bool = False,
            seed: int = 0, size=None, rays=None) -> Interreflections:
    """Ray-trace k_A and the multi-bounce reference at each albedo, per pixel of the scene's
    suggested view (sky visibility: no distance limit)."""
    sc = get_scene(scene)
    size = SIZE[quick] if size is None else size
    rays = RAYS[quick] if rays is None else rays
    gb = render_gbuffer(sc, sc.camera(size))
    plain = ground_truth(sc, gb, quantity="ao", rays=rays, seed=seed)
    reference, stderr = {}, {}
    for a in albedos:
        est = ground_truth(sc, gb, quantity="ao", rays=rays, seed=seed, bounces=bounces, albedo=a)
        reference[a], stderr[a] = est.value, est.stderr
    return Interreflections(scene, gb, plain.value, plain.stderr, reference, stderr, bounces, rays)


def interreflection_rows(measured: Interreflections) -> list[dict]:
    """One row per (albedo, correction): RMSE and bias against the reference over the covered
    pixels, the largest error, and the reference's mean standard error (the noise floor)."""
    valid = measured.gbuffer.valid
    k_A = measured.k_A[valid]
    rows = []
    for a, ref_image in measured.reference.items():
        ref = ref_image[valid]
        floor = float(np.sqrt(np.mean(measured.reference_stderr[a][valid] ** 2)))
        for name, correct in CORRECTIONS.items():
            err = np.asarray(correct(k_A, a), dtype=np.float64) - ref
            rows.append({"scene": measured.scene, "albedo": a, "correction": name,
                         "rmse": float(np.sqrt(np.mean(err ** 2))), "bias": float(err.mean()),
                         "max_abs": float(np.abs(err).max()), "ref_mean": float(ref.mean()),
                         "k_A_mean": float(k_A.mean()), "ref_stderr": floor,
                         "pixels": int(valid.sum()), "bounces": measured.bounces, "rays": measured.rays})
    return rows


def verdict(rows) -> str:
    """The answer in words: per scene and albedo, which correction is closer, by how much."""
    lines = []
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for a in dict.fromkeys(r["albedo"] for r in rows if r["scene"] == scene):
            by = {r["correction"]: r for r in rows if r["scene"] == scene and r["albedo"] == a}
            best = min(("stewart_langer", "jimenez"), key=lambda n: by[n]["rmse"])
            other = "jimenez" if best == "stewart_langer" else "stewart_langer"
            lines.append(
                f"{scene}, albedo {a}: {best} is closer (RMSE {by[best]['rmse']:.4f}, bias {by[best]['bias']:+.4f}) "
                f"than {other} ({by[other]['rmse']:.4f}, {by[other]['bias']:+.4f}); black occluders are off by "
                f"{by['none']['rmse']:.4f} (bias {by['none']['bias']:+.4f}); the reference's noise is "
                f"{by['none']['ref_stderr']:.4f}.")
    return "\n".join(lines)


#: GTAO configurations whose bent normals are compared: (slices, steps per side).
GTAO_BENT = ((3, 3), (9, 3))
#: The sky of the lookup comparison: brighter at the zenith, L(w) = 0.6 + 0.4 w_y.
SKY = LinearSky(0.6, 0.4, up=(0.0, 1.0, 0.0))


def _angles(a, b) -> np.ndarray:
    """Angles in degrees between rows of unit vectors."""
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)))


def bent_normal_rows(scene: str = "cornell_box", *, radius=None, quick: bool = False, seed: int = 0,
                     size=None, rays=None) -> list[dict]:
    """Bent normals for the environment lookup from the ground truth and from GTAO.

    The reference is the ray-traced bent normal within ``radius`` (default the scene's
    :func:`~vobscure.experiments.common.default_radius`), with its k_A. Each row is one
    source of (k_A, bent normal): GTAO at the slices and steps of :data:`GTAO_BENT`, or the
    geometric normal with the ray-traced k_A (no bent normal at all). Columns: the angle to
    the reference bent normal (median and 90th percentile, degrees, over the pixels with
    some occlusion), and the relative difference of the sky lookup
    (:func:`~vobscure.shading.bent_normal_lookup` of :data:`SKY`, white albedo) from the
    lookup with the reference's k_A and bent normal (RMSE and mean), and the RMSE of the same
    difference with the ray-traced k_A in every lookup (the normal's share alone).
    """
    sc = get_scene(scene)
    size = SIZE[quick] if size is None else size
    rays = RAYS[quick] if rays is None else rays
    radius = default_radius(sc) if radius is None else float(radius)
    gb = render_gbuffer(sc, sc.camera(size))
    valid = gb.valid
    hits = gb.hits
    truth = ambient_occlusion(sc, hits["world_position"], hits["world_normal"], rays=rays, max_distance=radius,
                              seed=seed, bent_normals=True)
    occluded = truth.value < 1.0
    target = bent_normal_lookup(truth.value, 1.0, truth.bent_normal, environment=SKY)
    sources = {"geometric normal, ray-traced k_A": (truth.value, hits["world_normal"])}
    for slices, steps in GTAO_BENT:
        k = gtao(gb, radius=radius, slices=slices, steps=steps, seed=seed)[valid]
        b = gtao_bent_normals(gb, radius=radius, slices=slices, steps=steps, seed=seed)[valid]
        sources[f"gtao {slices}x{steps}"] = (k, gb.camera.view_to_world_dir(b))
    rows = []
    for name, (k, n) in sources.items():
        n = np.asarray(n, dtype=np.float64)
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
        angle = _angles(n, truth.bent_normal)[occluded]
        rel = bent_normal_lookup(np.clip(k, 0.0, 1.0), 1.0, n, environment=SKY) / target - 1.0
        # the same lookup with the ray-traced k_A: the bent normal's share of the difference
        rel_n = bent_normal_lookup(truth.value, 1.0, n, environment=SKY) / target - 1.0
        rows.append({"scene": scene, "source": name, "radius": radius,
                     "angle_median_deg": float(np.median(angle)), "angle_p90_deg": float(np.percentile(angle, 90)),
                     "lookup_rel_rmse": float(np.sqrt(np.mean(rel ** 2))), "lookup_rel_bias": float(rel.mean()),
                     "normal_only_rel_rmse": float(np.sqrt(np.mean(rel_n ** 2))),
                     "occluded_pixels": int(occluded.sum()), "pixels": int(valid.sum()), "rays": rays})
    return rows


def main(argv=None) -> int:
    """``python -m vobscure.experiments.shading [--quick]``: the table and the verdict."""
    import argparse

    from .common import markdown_table

    parser = argparse.ArgumentParser(prog="python -m vobscure.experiments.shading", description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="small images, few rays (seconds)")
    parser.add_argument("--scenes", default=",".join(SCENES), help="comma-separated scene names")
    args = parser.parse_args(argv)
    rows = []
    for scene in args.scenes.split(","):
        rows += interreflection_rows(measure(scene.strip(), quick=args.quick))
    print(markdown_table(rows, ["scene", "albedo", "correction", "rmse", "bias", "max_abs", "ref_mean",
                                "k_A_mean", "ref_stderr"]))
    print()
    print(verdict(rows))
    print()
    bent = bent_normal_rows(quick=args.quick)
    print(markdown_table(bent, ["scene", "source", "radius", "angle_median_deg", "angle_p90_deg",
                                "lookup_rel_rmse", "lookup_rel_bias", "normal_only_rel_rmse", "occluded_pixels"]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
