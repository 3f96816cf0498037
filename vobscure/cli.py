"""The ``vobscure`` command.

``vobscure compare`` (the main job) measures the screen-space estimators on one scene against
the references a request names: error, time and taps per pixel, the error decomposition, and
optionally temporal flicker over a camera orbit (:mod:`vobscure.experiments.compare`).
``vobscure figures`` regenerates the paper figures (:mod:`vobscure.experiments.figures`).
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
                   help="AO ray length / obscurance distance / VO ball radius (default 0.1 x the scene extent)")
    r.add_argument("--rays", type=int, default=256, help="rays per pixel for ao/obscurance (default 256)")
    r.add_argument("--samples", type=int, default=1024, help="points per ball for volumetric (default 1024)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    r.add_argument("--allow-open", action="store_true",
                   help="volumetric: accept meshes that are not closed (the inside test may be wrong near holes)")
    r.add_argument("--out", type=Path, default=Path("vobscure-out"), help="output folder (default ./vobscure-out)")
    r.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    sub.add_parser("scenes", help="list the built-in scenes")

    from . import methods

    c = sub.add_parser("compare", help="which estimator, with how many samples, at what cost and accuracy",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Measure the screen-space estimators on one scene against the requested "
                                   "references, print the verdict (Pareto fronts, the cheapest configuration "
                                   "meeting a target RMSE, the dominant error term and what reduces it) and "
                                   "write results.csv, results.md, summary.json, tradeoff.png, gallery.png "
                                   "and provenance.json.",
                       epilog="methods (--methods NAME[:SAMPLES[:FETCH]], from vobscure.methods):\n  "
                              + methods.describe().replace("\n", "\n  "))
    c.add_argument("--scene", default=DEFAULT_SCENE, help=f"built-in scene or mesh file (default {DEFAULT_SCENE})")
    c.add_argument("--camera", default=None, metavar="EX,EY,EZ,TX,TY,TZ[,FOV]",
                   help="eye and target (and vertical field of view in degrees); default the scene's camera")
    c.add_argument("--size", nargs=2, type=int, metavar=("W", "H"), default=None,
                   help="image size (default 256 256; 64 64 with --quick)")
    c.add_argument("--radius", type=float, nargs="+", default=None,
                   help="one or more ball radii (default 0.1 x the scene extent)")
    c.add_argument("--methods", default=None,
                   help="comma-separated NAME[:SAMPLES[:FETCH]] with NAME one of "
                        f"{', '.join(methods.names())} (listed below; default point:12,point:33,line:5,line:9,area:1, plus the vegetation models on a "
                        "vegetation scene)")
    c.add_argument("--normals", action="store_true", help="normal clamp (half-ball VO, Sec. 4.4)")
    c.add_argument("--thickness", type=float, default=None, help="thickness model (Sec. 4.3), world units")
    from .experiments.sweep import REFERENCES

    c.add_argument("--reference", nargs="+", default=None, choices=REFERENCES,
                   help="references to compute (default screen volumetric ao; volumetric left out for a scene "
                        "that is not closed, sky added for a vegetation scene; sky and sky_uniform: AO with "
                        "no distance limit, cosine-weighted or uniform, what the vegetation models estimate)")
    c.add_argument("--repeats", type=int, default=3, help="timed runs per configuration, median kept (default 3)")
    c.add_argument("--rays", type=int, default=256, help="rays per pixel of ao/obscurance (default 256)")
    c.add_argument("--volume-samples", "--samples", dest="volume_samples", type=int, default=1024,
                   help="points per ball of the world-space VO (default 1024)")
    c.add_argument("--screen-samples", type=int, default=2048,
                   help="samples of the converged screen-space VO (default 2048)")
    c.add_argument("--orbit", type=int, default=0, metavar="N", help="N-frame camera orbit: temporal flicker")
    c.add_argument("--seed", type=int, default=0)
    c.add_argument("--target-rmse", type=float, default=None, metavar="X",
                   help="the accuracy to meet against each method's own reference "
                        "(default 1.5 x the best configuration's RMSE)")
    c.add_argument("--budget-ms", type=float, default=None, metavar="T",
                   help="a time budget per frame: name the most accurate configuration within it")
    c.add_argument("--no-suggest", dest="suggest", action="store_false",
                   help="do not try the thickness model when the screen-space error dominates")
    c.add_argument("--quick", action="store_true", help="small and fast (under two minutes)")
    c.add_argument("--out", type=Path, default=None, help="output folder (default ./vobscure-out/compare-<scene>)")
    c.add_argument("--cache", type=Path, default=None, help="reference cache folder (default: user cache)")
    c.add_argument("--no-cache", action="store_true", help="recompute every reference, write no cache")
    c.add_argument("--quiet", action="store_true", help="no progress bars or summary")

    f = sub.add_parser("figures", help="regenerate the paper figures",
                       description="Regenerate figures (one module each in vobscure.experiments.figures).")
    f.add_argument("names", nargs="*", default=["all"], metavar="NAME", help="figure names or 'all' (default)")
    f.add_argument("--quick", action="store_true", help="small and fast versions (what CI runs)")
    f.add_argument("--out", type=Path, default=Path("vobscure-out") / "figures", help="output folder")
    f.add_argument("--list", action="store_true", help="list the figure names and exit")
    return p


def _camera_arg(spec: str, size):
    from .camera import Camera

    parts = [p for p in spec.replace(" ", "").split(",") if p]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) not in (6, 7):
        raise ValueError(f"--camera must be EX,EY,EZ,TX,TY,TZ[,FOV] (6 or 7 numbers), got {spec!r}")
    fov = values[6] if len(values) == 7 else 45.0
    return Camera.look_at(values[:3], values[3:6], size=tuple(size), fov_y=fov)


def _compare_main(args) -> int:
    from .experiments.compare import DEFAULT_SIZE, QUICK_SIZE, compare, report_text

    size = tuple(args.size) if args.size else (QUICK_SIZE if args.quick else DEFAULT_SIZE)
    camera = _camera_arg(args.camera, size) if args.camera else None
    cache = False if args.no_cache else (args.cache if args.cache is not None else True)
    result = compare(args.scene, camera=camera, size=size, radii=args.radius,
                     methods=args.methods, normal_clamp=args.normals, thickness=args.thickness,
                     references=tuple(args.reference) if args.reference else None,
                     repeats=args.repeats, rays=args.rays, volume_samples=args.volume_samples,
                     screen_samples=args.screen_samples, seed=args.seed, orbit=args.orbit,
                     target_rmse=args.target_rmse, budget_ms=args.budget_ms, suggest=args.suggest,
                     quick=args.quick, out=args.out, cache=cache, progress=not args.quiet)
    if not args.quiet:
        print(report_text(result))
    return 0


def _figures_main(args) -> int:
    from .experiments import figures

    if args.list:
        for name in figures.FIGURES:
            print(name)
        return 0
    names = None if args.names in ([], ["all"]) else args.names
    unknown = [n for n in (names or []) if n not in figures.FIGURES]
    if unknown:
        raise ValueError(f"unknown figure(s) {', '.join(unknown)}; expected 'all' or one of "
                         f"{', '.join(figures.FIGURES)}")
    paths = figures.make_all(args.out, quick=args.quick, names=names, progress=True)
    for path in paths:
        print(f"wrote {path}")
    return 0


def render(*, scene: str = DEFAULT_SCENE, size=DEFAULT_SIZE, quantity: str = "ao", radius=None,
           rays: int = 256, samples: int = 1024, seed: int = 0, threads=None,
           out=Path("vobscure-out"), progress: bool = True, allow_open: bool = False) -> dict:
    """Run the render job; returns the provenance record (also stored in the ``.npz``)."""
    from . import __version__
    from ._io import save_npz
    from .experiments.common import default_radius
    from .gbuffer import render_gbuffer
    from .groundtruth import ground_truth
    from .scenes import resolve

    t0 = time.perf_counter()
    sc, scene_spec = resolve(scene)
    cam = sc.camera(tuple(size))
    if radius is None:
        radius = default_radius(sc)
    gb = render_gbuffer(sc, cam)
    ref = ground_truth(sc, gb, quantity=quantity, radius=radius, rays=rays, samples=samples,
                          seed=seed, progress=progress, threads=threads, allow_open=allow_open)
    seconds = time.perf_counter() - t0
    out = Path(out)
    provenance = {
        "tool": "vobscure render", "version": __version__, "scene": scene_spec,
        "scene_extent": sc.extent, "triangles": int(len(sc.triangles)), "camera": cam.to_dict(),
        "quantity": quantity, "radius": float(radius), "rays": int(rays), "samples": int(samples),
        "samples_per_pixel": int(ref.samples), "seed": int(seed), "seconds": round(seconds, 3),
        "valid_pixels": int(gb.valid.sum()), "allow_open": bool(allow_open),
    }
    stem = f"{Path(scene_spec).stem}_{quantity}"
    save_npz(out / f"{stem}.npz", provenance, depth=gb.depth, normal=gb.normal, valid=gb.valid,
             world_position=gb.world_position, world_normal=gb.world_normal,
             visibility=ref.value, stderr=ref.stderr)
    _save_png(out / f"{stem}_depth.png", _depth_image(gb.depth, gb.valid))
    _save_png(out / f"{stem}_normal.png", _normal_image(gb.normal, gb.valid))
    _save_png(out / f"{stem}_visibility.png", _visibility_image(ref.value, gb.valid))
    provenance["files"] = [f"{stem}{s}" for s in (".npz", "_depth.png", "_normal.png", "_visibility.png")]
    return provenance


def _save_png(path, image: np.ndarray) -> Path:
    """Write a float image in [0, 1] ((H, W), (H, W, 3) or (H, W, 4)) as PNG, atomically."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.image as mpimg

    img = np.clip(np.nan_to_num(np.asarray(image, dtype=np.float64), nan=0.0), 0.0, 1.0)
    kwargs = {"cmap": "gray", "vmin": 0.0, "vmax": 1.0} if img.ndim == 2 else {}
    from ._io import atomic_write

    return atomic_write(path, lambda fh: mpimg.imsave(fh, img, format="png", **kwargs))


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
    if args.command in ("compare", "figures"):
        try:
            return _compare_main(args) if args.command == "compare" else _figures_main(args)
        except (ValueError, FileNotFoundError) as exc:
            print(f"vobscure {args.command}: error: {exc}", file=sys.stderr)
            return 2
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
