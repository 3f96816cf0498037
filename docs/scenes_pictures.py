"""The pictures of docs/scenes.md: every built-in scene from its suggested view, and the
atrium from its two named views, shaded by ray-cast ambient occlusion times a headlight.

Run from the repository's root::

    python docs/scenes_pictures.py            # writes docs/img/scenes/ (about 15 s)

``make(out_dir, quick=True)`` renders the same pictures at a quarter of the pixels and a
quarter of the rays (tests/test_atrium.py runs it so that the script cannot rot).
Next to the pictures, ``provenance.json`` records the scenes, sizes, radii, rays and seed.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

#: Rays per pixel of the AO shading, and its seed.
RAYS, SEED = 32, 0
#: Size of one tile of the contact sheet and of one atrium view, (width, height).
TILE, ATRIUM = (192, 108), (480, 270)
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


if __name__ == "__main__":
    root = Path(__file__).resolve().parent
    for path in make(root / "img" / "scenes", quick="--quick" in sys.argv[1:]):
        print(path)
