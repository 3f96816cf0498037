"""The ``vobscure`` command.

``vobscure render`` renders a G-buffer of a scene and its ray-cast reference (AO,
obscurance or world-space VO) and writes depth, normal and visibility PNGs plus an ``.npz``
with every array and a provenance record. ``vobscure scenes`` lists the built-in scenes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

__all__ = ["main", "render"]

DEFAULT_SCENE = "cornell_box"
DEFAULT_SIZE = (256, 256)
#: default radius as a fraction of the scene's extent (bounding-box diagonal)
DEFAULT_RADIUS_FRACTION = 0.1


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="vobscure", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    r = sub.add_parser("render", help="render a G-buffer and its ray-cast reference",
                       description="Render a G-buffer and its ray-cast reference; write PNGs and an .npz.")
    r.add_argument("--scene", default=DEFAULT_SCENE,
                   help=f"a built-in scene name (see `vobscure scenes`) or a mesh file (default {DEFAULT_SCENE})")
    r.add_argument("--size", nargs=2, type=int, metavar=("W", "H"), default=DEFAULT_SIZE,
                   help="image width and height in pixels (default 256 256)")
    r.add_argument("--quantity", choices=("ao", "obscurance", "volumetric"), default="ao",
                   help="what to compute (default ao)")
    r.add_argument("--radius", type=float, default=None,
                   help=f"AO ray length / obscurance distance / VO ball radius "
                        f"(default {DEFAULT_RADIUS_FRACTION} x the scene extent)")
    r.add_argument("--rays", type=int, default=256, help="rays per pixel for ao/obscurance (default 256)")
    r.add_argument("--samples", type=int, default=1024, help="points per ball for volumetric (default 1024)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    r.add_argument("--allow-open", action="store_true",
                   help="volumetric: accept meshes that are not closed (the inside test may be wrong near holes)")
    r.add_argument("--out", type=Path, default=Path("vobscure-out"), help="output folder (default ./vobscure-out)")
    r.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    sub.add_parser("scenes", help="list the built-in scenes")
    return p


def _load_scene(spec: str):
    from . import scenes

    if spec in scenes.names():
        return scenes.get(spec), spec
    path = Path(spec)
    if path.suffix or path.exists():
        return scenes.load(path), str(path)
    raise ValueError(f"--scene {spec!r} is neither a built-in scene ({', '.join(scenes.names())}) "
                     f"nor a mesh file")


def render(*, scene: str = DEFAULT_SCENE, size=DEFAULT_SIZE, quantity: str = "ao", radius=None,
           rays: int = 256, samples: int = 1024, seed: int = 0, threads=None,
           out=Path("vobscure-out"), progress: bool = True, allow_open: bool = False) -> dict:
    """Run the render job; returns the provenance record (also stored in the ``.npz``)."""
    import vobscure as vo

    from ._io import save_npz, save_png

    t0 = time.perf_counter()
    sc, scene_spec = _load_scene(scene)
    cam = sc.camera(tuple(size))
    if radius is None:
        radius = DEFAULT_RADIUS_FRACTION * sc.extent
    gb = vo.render_gbuffer(sc, cam)
    ref = vo.ground_truth(sc, gb, quantity=quantity, radius=radius, rays=rays, samples=samples,
                          seed=seed, progress=progress, threads=threads, allow_open=allow_open)
    seconds = time.perf_counter() - t0
    out = Path(out)
    provenance = {
        "tool": "vobscure render", "version": vo.__version__, "scene": scene_spec,
        "scene_extent": sc.extent, "triangles": int(len(sc.triangles)), "camera": cam.to_dict(),
        "quantity": quantity, "radius": float(radius), "rays": int(rays), "samples": int(samples),
        "samples_per_pixel": int(ref.samples), "seed": int(seed), "seconds": round(seconds, 3),
        "valid_pixels": int(gb.valid.sum()), "allow_open": bool(allow_open),
    }
    stem = f"{Path(scene_spec).stem}_{quantity}"
    save_npz(out / f"{stem}.npz", provenance, depth=gb.depth, normal=gb.normal, valid=gb.valid,
             world_position=gb.world_position, world_normal=gb.world_normal,
             visibility=ref.value, stderr=ref.stderr)
    save_png(out / f"{stem}_depth.png", _depth_image(gb.depth, gb.valid))
    save_png(out / f"{stem}_normal.png", _normal_image(gb.normal, gb.valid))
    save_png(out / f"{stem}_visibility.png", _visibility_image(ref.value, gb.valid))
    provenance["files"] = [f"{stem}{s}" for s in (".npz", "_depth.png", "_normal.png", "_visibility.png")]
    return provenance


def _depth_image(depth, valid):
    img = np.zeros(depth.shape + (4,))
    if valid.any():
        d = depth[valid]
        lo, hi = d.min(), d.max()
        g = 1.0 - (d - lo) / (hi - lo) if hi > lo else np.ones_like(d)
        img[valid] = np.column_stack([g, g, g, np.ones_like(g)]) * [0.9, 0.9, 0.9, 1.0] + [0.1, 0.1, 0.1, 0]
    return img


def _normal_image(normal, valid):
    img = np.zeros(normal.shape[:2] + (4,))
    img[valid, :3] = 0.5 * (normal[valid] * [1, 1, -1] + 1.0)
    img[valid, 3] = 1.0
    return img


def _visibility_image(vis, valid):
    img = np.zeros(vis.shape + (4,))
    img[valid, :3] = vis[valid][:, None]
    img[valid, 3] = 1.0
    return img


def main(argv=None) -> int:
    """Entry point of the ``vobscure`` command; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    if args.command == "scenes":
        from . import scenes

        for name in scenes.names():
            doc = (getattr(scenes, name).__doc__ or "").strip().splitlines()
            print(f"{name:16s} {doc[0] if doc else ''}")
        return 0
    try:
        record = render(scene=args.scene, size=args.size, quantity=args.quantity, radius=args.radius,
                        rays=args.rays, samples=args.samples, seed=args.seed, threads=args.threads,
                        out=args.out, progress=not args.quiet, allow_open=args.allow_open)
    except (ValueError, FileNotFoundError) as exc:
        print(f"vobscure render: error: {exc}", file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"{record['scene']}: {record['quantity']} at {args.size[0]}x{args.size[1]}, radius "
              f"{record['radius']:.4g}, {record['samples_per_pixel']} samples/pixel, "
              f"{record['seconds']:.1f} s")
        for name in record["files"]:
            print(f"  wrote {args.out / name}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
