"""The pictures of docs/scenes.md: every built-in scene from its suggested view, the
atrium from its two named views, and the thin occluders beside their thin-feature band,
shaded by ray-cast ambient occlusion times a headlight.

Run from the repository's root::

    python docs/scenes_pictures.py            # writes docs/img/scenes/ (about 20 s)

``make(out_dir, quick=True)`` and ``make_thin(out_dir, quick=True)`` render the same
pictures at a quarter of the pixels and a quarter of the rays (tests/test_atrium.py and
tests/test_thin_scene.py run them so that the script cannot rot). Next to the pictures,
``provenance.json`` and ``thin_occluders.json`` record the scenes, sizes, radii, rays and seed.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

#: Rays per pixel of the AO shading, and its seed.
RAYS, SEED = 32, 0
#: Size of one tile of the contact sheet, of one atrium view and of the thin occluders' view.
TILE, ATRIUM, THIN = (192, 108), (480, 270), (400, 300)
#: Background colour (RGB) of pixels that see no surface.
BACKGROUND = np.array([0.72, 0.80, 0.90])
#: Radius of the AO ball: 0.5 m in the atrium (metres); a tenth of the extent elsewhere.
ATRIUM_RADIUS, EXTENT_FRACTION = 0.5, 0.1


def _shade(scene, camera, radius, rays):
    """(h, w, 3) picture: cosine AO within ``radius`` times the facing ratio |n . view
    axis| (a headlight, so that planes at different angles differ), on a sky-blue
    background; and the fraction of pixels covered."""
    import vobscure as vo

    gb = vo.render_gbuffer(scene, camera)
    ao = vo.ground_truth(scene, gb, quantity="ao", radius=radius, rays=rays, seed=SEED)
    grey = ao.value * (0.35 + 0.65 * np.abs(gb.normal[..., 2]))
    image = np.where(gb.valid[..., None], np.nan_to_num(grey)[..., None], BACKGROUND)
    return np.clip(image, 0.0, 1.0), float(gb.valid.mean())


def make(out_dir, quick: bool = False) -> list[Path]:
    """Write ``builtin.png``, ``atrium.png`` and ``provenance.json`` into ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import vobscure as vo

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scale = 2 if quick else 1
    rays = RAYS // (scale * scale)
    tile = (TILE[0] // scale, TILE[1] // scale)
    record = {"generator": "docs/scenes_pictures.py",
              "quantity": "ao (cosine, within the radius) x |view-space normal z|",
              "rays": rays, "seed": SEED, "quick": quick, "scenes": {}}

    names = vo.scenes.names()
    cols = 4
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 1.95 * rows))
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, name in zip(axes.ravel(), names):
        scene = vo.scenes.get(name)
        metres = scene.metadata.get("units") == "m"
        radius = ATRIUM_RADIUS if metres else EXTENT_FRACTION * scene.extent
        image, coverage = _shade(scene, scene.camera(tile), radius, rays)
        ax.imshow(image)
        ax.set_title(f"{name} ({len(scene.triangles)} triangles)", fontsize=8)
        record["scenes"][name] = {"size": list(tile), "radius": radius, "coverage": coverage,
                                  "triangles": len(scene.triangles), "view": scene.view}
    fig.tight_layout()
    paths = [out / "builtin.png"]
    fig.savefig(paths[0], dpi=80)
    plt.close(fig)

    scene = vo.scenes.atrium()
    size = (ATRIUM[0] // scale, ATRIUM[1] // scale)
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.6))
    for ax, (label, view) in zip(axes, scene.metadata["views"].items()):
        camera = vo.Camera.look_at(view["eye"], view["target"], view["up"], size=size, fov_y=view["fov_y"])
        image, coverage = _shade(scene, camera, ATRIUM_RADIUS, rays)
        ax.imshow(image)
        ax.set_title(f'atrium, view "{label}" (AO within {ATRIUM_RADIUS} m)', fontsize=9)
        ax.set_axis_off()
        record["scenes"][f"atrium/{label}"] = {"size": list(size), "radius": ATRIUM_RADIUS,
                                               "coverage": coverage, "view": view}
    fig.tight_layout()
    paths.append(out / "atrium.png")
    fig.savefig(paths[1], dpi=80)
    plt.close(fig)

    paths.append(out / "provenance.json")
    paths[2].write_text(json.dumps(record, indent=1, default=float) + "\n")
    return paths


def make_thin(out_dir, quick: bool = False) -> list[Path]:
    """Write ``thin_occluders.png`` (the scene's default view beside its thin-feature band at
    the default radius) and ``thin_occluders.json`` into ``out_dir``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import vobscure as vo
    from vobscure.experiments.common import choose_radius

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scale = 2 if quick else 1
    rays = RAYS // (scale * scale)
    scene = vo.scenes.thin_occluders()
    camera = scene.camera((THIN[0] // scale, THIN[1] // scale))
    gb = vo.render_gbuffer(scene, camera)
    radius = choose_radius(scene, gb).radius
    image, coverage = _shade(scene, camera, radius, rays)
    band = vo.metrics.thin_feature_mask(gb, radius=radius)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.9))
    axes[0].imshow(image)
    axes[0].set_title(f"thin_occluders (AO within {radius:g} m)", fontsize=9)
    axes[1].imshow(np.where(band[..., None], np.array([0.85, 0.2, 0.1]), image))
    axes[1].set_title(f"its thin-feature band at R = {radius:g} m ({band.mean():.0%} of the pixels)", fontsize=9)
    for ax in axes:
        ax.set_axis_off()
    fig.tight_layout()
    paths = [out / "thin_occluders.png", out / "thin_occluders.json"]
    fig.savefig(paths[0], dpi=80)
    plt.close(fig)
    record = {"generator": "docs/scenes_pictures.py (make_thin)", "scene": "thin_occluders",
              "quantity": "ao (cosine, within the radius) x |view-space normal z|; red: "
                          "vobscure.metrics.thin_feature_mask(gb, radius=radius)",
              "size": list(camera.size), "radius": radius, "rays": rays, "seed": SEED, "quick": quick,
              "coverage": coverage, "band_fraction": float(band.mean()), "view": scene.view}
    paths[1].write_text(json.dumps(record, indent=1, default=float) + "\n")
    return paths


if __name__ == "__main__":
    root = Path(__file__).resolve().parent
    quick = "--quick" in sys.argv[1:]
    for path in make(root / "img" / "scenes", quick=quick) + make_thin(root / "img" / "scenes", quick=quick):
        print(path)
