"""The ``vobscure`` command.

``vobscure compare`` (the main job) measures the screen-space estimators on one scene against
the references a request names: error, time and taps per pixel, the error decomposition, and
optionally temporal flicker over a camera orbit (:mod:`vobscure.experiments.compare`).
``vobscure figures`` regenerates the paper figures (:mod:`vobscure.experiments.figures`).
``vobscure render`` renders a G-buffer of a scene and its ray-cast reference (AO,
obscurance or world-space VO) and writes depth, normal and visibility PNGs plus an ``.npz``
with every array and a provenance record. ``vobscure scenes`` lists the built-in scenes.
``vobscure estimate`` runs one estimator on your own frame(s), read from EXR, NPY/NPZ, PFM or
PNG files (:mod:`vobscure.io`), and writes the visibility.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ._argv import joined_list_values, numbers_as_written
from .references import SCREEN_SAMPLES
from .screenspace.noise import SCHEDULES
from .temporal import DENOISE_STEPS, MOTIONS

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
    from .groundtruth import QUANTITIES

    r.add_argument("--quantity", choices=QUANTITIES, default="ao",
                   help="what to compute: a quantity of vobscure.ground_truth (default ao)")
    r.add_argument("--radius", type=float, default=None,
                   help="AO ray length / obscurance distance / VO ball radius (default 0.5 m in a file that "
                        "declares metres, else 0.1 x the scene extent)")
    _view_options(r)
    r.add_argument("--fov", type=float, default=None, metavar="DEG",
                   help="vertical field of view in degrees (default the scene's view's)")
    r.add_argument("--rays", type=int, default=256, help="rays per pixel for ao/obscurance (default 256)")
    r.add_argument("--samples", type=int, default=1024, help="points per ball for volumetric (default 1024)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    r.add_argument("--allow-open", action="store_true",
                   help="volumetric: accept meshes that are not closed (the inside test may be wrong near holes)")
    r.add_argument("--out", type=Path, default=Path("vobscure-out"), help="output folder (default ./vobscure-out)")
    r.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    sub.add_parser("scenes", help="list the built-in scenes")

    from . import methods, references

    c = sub.add_parser("compare", help="which estimator, with how many samples, at what cost and accuracy",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Measure the screen-space estimators on one scene against the requested "
                                   "references, print the verdict (Pareto fronts, the cheapest configuration "
                                   "meeting a target RMSE, the dominant error term and what reduces it) and "
                                   "write results.csv, results.md, summary.json, tradeoff.png, gallery.png "
                                   "and provenance.json.",
                       epilog="methods (--methods NAME[:SAMPLES[:FETCH]], from vobscure.methods):\n  "
                              + methods.describe().replace("\n", "\n  ")
                              + "\n\nreferences (--reference NAME ..., from vobscure.references):\n  "
                              + references.describe().replace("\n", "\n  "))
    c.add_argument("--scene", default=DEFAULT_SCENE, help=f"built-in scene or mesh file (default {DEFAULT_SCENE})")
    c.add_argument("--gbuffer", default=None, metavar="PATH",
                   help="your own frame instead of a scene: a depth (and normal) file read as `vobscure estimate` "
                        "reads it (give its camera with --fov, --intrinsics or --projection; the options below "
                        "under 'your own frame'); the only reference is then the converged screen-space VO")
    c.add_argument("--camera", default=None, metavar="EX,EY,EZ,TX,TY,TZ[,FOV]",
                   help="eye and target (and vertical field of view in degrees); default the scene's camera")
    _view_options(c, fov_note=True)
    c.add_argument("--size", nargs=2, type=int, metavar=("W", "H"), default=None,
                   help="image size (default 256 256; 64 64 with --quick)")
    c.add_argument("--radius", type=float, nargs="+", default=None,
                   help="one or more ball radii in scene units (default 0.5 m in a file that declares metres, "
                        "else 0.1 x the scene extent; capped so the ball projects under a quarter of the image "
                        "height on 95%% of the covered pixels)")
    c.add_argument("--methods", default=None,
                   help="comma-separated NAME[:SAMPLES[:FETCH]] with NAME one of "
                        f"{', '.join(methods.names())} (listed below; default point:12,point:33,line:5,line:9,area:1, plus the vegetation models on a "
                        "vegetation scene)")
    c.add_argument("--normals", action="store_true", help="normal clamp (half-ball VO, Sec. 4.4)")
    c.add_argument("--thickness", type=_thickness_arg, default=None, metavar="T|layers",
                   help="a number: the thickness model (Sec. 4.3) in world units, for every method that takes one; "
                        "'layers': render the G-buffer with --layers depth-peeled layers and let every method that "
                        "reads them (point, line, gtao, vbao) take the true thickness from them, the others run "
                        "without (docs/compare.md)")
    c.add_argument("--layers", type=_layers_arg, default=None, metavar="K",
                   help="depth-peeled layers of the G-buffer with --thickness layers (an integer >= 2, default 4)")
    c.add_argument("--reference", nargs="+", default=None, choices=references.names(), metavar="NAME",
                   help=f"references to compute, some of {', '.join(references.names())} (listed below; default "
                        "screen volumetric ao, and each method's own; on a scene that is not closed, shell in "
                        "place of volumetric (the verdict names the open meshes); sky added for a vegetation scene)")
    c.add_argument("--allow-open", action="store_true",
                   help="compute the volumetric reference on a scene that is not closed (the inside test may be "
                        "wrong near holes) instead of the shell reference")
    c.add_argument("--repeats", type=int, default=3, help="timed runs per configuration, median kept (default 3)")
    c.add_argument("--rays", type=int, default=256, help="rays per pixel of ao/obscurance (default 256)")
    c.add_argument("--volume-samples", "--samples", dest="volume_samples", type=int, default=1024,
                   help="points per ball of the world-space VO (default 1024)")
    c.add_argument("--screen-samples", type=int, default=SCREEN_SAMPLES,
                   help=f"view-ray segments per pixel of the converged screen-space VO (default {SCREEN_SAMPLES})")
    c.add_argument("--orbit", type=int, default=0, metavar="N", help="N-frame camera orbit: temporal flicker")
    seq = c.add_argument_group("frame sequences: the error after N frames (docs/temporal.md)")
    seq.add_argument("--frames", type=int, default=0, metavar="N",
                     help="run every method over N frames, accumulate, and score each frame (temporal.csv, "
                          "temporal.png, the verdict's frame sentences)")
    seq.add_argument("--motion", choices=MOTIONS, default="static",
                     help="the camera path of the frames (default static)")
    seq.add_argument("--step", type=float, default=None, metavar="X",
                     help="per-frame step: degrees for orbit (default 0.5), fraction of the eye-target distance "
                          "for dolly (default 0.005)")
    seq.add_argument("--cameras", type=Path, default=None, metavar="FILE",
                     help="a JSON list of camera records (Camera.to_dict) as the path, in place of --motion")
    seq.add_argument("--schedule", default="white", metavar="LIST",
                     help=f"noise schedules per frame, comma-separated: {', '.join(SCHEDULES)} (default white)")
    seq.add_argument("--accumulate", default="mean", metavar="LIST",
                     help="accumulations, comma-separated: mean, ema:ALPHA, clip:ALPHA (default mean)")
    seq.add_argument("--clamp", action="store_true", help="clamp the history to the new frame's 3x3 range")
    seq.add_argument("--no-reprojection", dest="reproject", action="store_false",
                     help="use the history in place (shows the ghosting that reprojection avoids)")
    seq.add_argument("--denoise", choices=DENOISE_STEPS, default=None,
                     help="the bilateral blur on each frame before accumulating, or on the accumulated image")
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

    _estimate_parser(sub)

    frame = c.add_argument_group("your own frame (with --gbuffer)")
    frame.add_argument("--normal", default=None, metavar="PATH", help="normal file, when not in the --gbuffer file")
    _frame_options(frame, lens_required=False)

    f = sub.add_parser("figures", help="regenerate the paper figures",
                       description="Regenerate figures (one module each in vobscure.experiments.figures): "
                                   "measure, write NAME.csv, draw NAME.png.")
    f.add_argument("names", nargs="*", default=["all"], metavar="NAME", help="figure names or 'all' (default)")
    f.add_argument("--quick", action="store_true", help="small and fast versions (what CI runs)")
    f.add_argument("--out", type=Path, default=Path("vobscure-out") / "figures", help="output folder")
    f.add_argument("--from-csv", action="store_true",
                   help="draw again from the NAME.csv (and NAME.npz) in --out, measuring nothing")
    f.add_argument("--list", action="store_true", help="list the figure names and exit")
    return p


def _view_options(p, *, fov_note: bool = False) -> None:
    """--eye, --target, --up: the camera's pose, each overriding the scene's view."""
    fov = (" and --fov DEG (vertical field of view; with --gbuffer it is the frame's lens instead)"
           if fov_note else "")
    for name, what in (("--eye", "camera position"), ("--target", "point looked at"),
                       ("--up", "up direction hint (default the scene's view's, usually 0 1 0)")):
        p.add_argument(name, type=float, nargs=3, default=None, metavar=("X", "Y", "Z"),
                       help=f"{what} in scene units, negative numbers as written (-14 2 0); "
                            f"default the scene's view's{fov if name == '--eye' else ''}")


def _view_camera(args, size, scene_spec):
    """The camera of --eye/--target/--up/--fov, each overriding the scene's view (resolved only
    when --eye or --target is missing), or None when none is given."""
    from .camera import Camera

    given = {k: getattr(args, k, None) for k in ("eye", "target", "up", "fov")}
    if all(v is None for v in given.values()):
        return None
    if getattr(args, "camera", None):
        raise ValueError("give the view either as --camera or as --eye/--target/--up/--fov, not both")
    for key in ("eye", "target", "up"):
        if given[key] is not None and not np.all(np.isfinite(given[key])):
            raise ValueError(f"--{key} must be three finite numbers, got {' '.join(map(str, given[key]))}")
    if given["fov"] is not None and not 0.0 < given["fov"] < 180.0:
        raise ValueError(f"--fov must be a vertical field of view in degrees in (0, 180), got {given['fov']}")
    view = {}
    if given["eye"] is None or given["target"] is None:
        from .scenes import resolve

        view = resolve(scene_spec)[0].view
    eye = given["eye"] if given["eye"] is not None else view["eye"]
    target = given["target"] if given["target"] is not None else view["target"]
    up = given["up"] if given["up"] is not None else view.get("up", (0.0, 1.0, 0.0))
    lens = ({"fov_y": given["fov"]} if given["fov"] is not None
            else {"fov_y": view.get("fov_y"), "ortho_height": view.get("ortho_height")} if view
            else {"fov_y": 45.0})
    try:
        return Camera.look_at(eye, target, up, size=tuple(size), **lens)
    except ValueError as exc:
        raise ValueError(f"--eye/--target/--up: {exc}") from exc


def _thickness_arg(text: str):
    """``--thickness``: a positive number or ``layers``."""
    if text == "layers":
        return text
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number (the thickness model, world units) or 'layers' "
                                         f"(the depth-peeled layers' solid intervals), got {text!r}")
    return value


def _layers_arg(text: str) -> int:
    """``--layers``: an integer >= 2."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be an integer >= 2 (the depth-peeled layers K), got {text!r}")
    return value


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
    from ._io import check_writable_dir
    from .experiments.compare import DEFAULT_SIZE, QUICK_SIZE, compare, report_text

    size = tuple(args.size) if args.size else (QUICK_SIZE if args.quick else DEFAULT_SIZE)
    if args.out is not None:
        check_writable_dir(args.out, "--out")   # before the work, not after it
    cache = False if args.no_cache else (args.cache if args.cache is not None else True)
    scene, name = args.scene, None
    if args.gbuffer is not None:
        if args.camera or args.size or args.eye or args.target or args.up:
            raise ValueError("--gbuffer brings its own view: give its camera with --fov, --intrinsics or "
                             "--projection, not --camera, --eye, --target, --up or --size")
        path = Path(args.gbuffer)
        if not path.is_file():
            raise FileNotFoundError(f"--gbuffer: no such file: {path}")
        scene, camera = _frame_reader(args)(path, Path(args.normal) if args.normal else None, None)
        name, size, camera = path.stem, None, None
    elif args.normal is not None:
        raise ValueError("--normal goes with --gbuffer (your own frame)")
    else:
        camera = _view_camera(args, size, args.scene)
        camera = _camera_arg(args.camera, size) if camera is None and args.camera else camera
    result = compare(scene, name=name, camera=camera, size=size, radii=args.radius,
                     methods=args.methods, normal_clamp=args.normals, thickness=args.thickness, layers=args.layers,
                     references=tuple(args.reference) if args.reference else None,
                     repeats=args.repeats, rays=args.rays, volume_samples=args.volume_samples,
                     screen_samples=args.screen_samples, seed=args.seed, orbit=args.orbit,
                     target_rmse=args.target_rmse, budget_ms=args.budget_ms, suggest=args.suggest,
                     quick=args.quick, out=args.out, cache=cache, progress=not args.quiet,
                     allow_open=args.allow_open, **_sequence_options(args))
    if not args.quiet:
        print(report_text(result))
    return 0


def _sequence_options(args) -> dict:
    """compare()'s frame-sequence keywords from the command line (--frames, --cameras, ...)."""
    opts = dict(frames=args.frames, motion=args.motion, step=args.step, schedules=args.schedule,
                accumulate=args.accumulate, clamp=args.clamp, reproject=args.reproject, denoise=args.denoise)
    if args.frames < 0:
        raise ValueError(f"--frames must be a number of frames >= 0, got {args.frames}")
    if args.cameras is not None:
        from .temporal import cameras_from_file

        opts["cameras"] = cameras_from_file(args.cameras)
    elif args.frames == 1:
        raise ValueError("--frames needs at least 2 frames (or --cameras FILE)")
    return opts


def _figures_main(args) -> int:
    from .experiments import figures

    known = figures.names()
    if args.list:
        for name in known:
            print(name)
        return 0
    names = known if args.names in ([], ["all"]) else args.names
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown figure(s) {', '.join(unknown)}; expected 'all' or one of {', '.join(known)}")
    from ._io import check_writable_dir

    check_writable_dir(args.out, "--out")   # before the work, not after it
    if args.from_csv:
        paths = figures.replot(names, args.out)
    else:
        paths = figures.make(names, args.out, figures.Profile(quick=args.quick), progress=True)
    for path in paths:
        print(f"wrote {path}")
    return 0


# --------------------------------------------------------------------------- vobscure estimate
#: Frames of at least this many pixels get a progress bar over the stages of their estimate.
ESTIMATE_PROGRESS_PIXELS = 1 << 20
#: Where `vobscure estimate` writes without --out (a directory).
DEFAULT_ESTIMATE_OUT = "vobscure-out"
#: The counts of GBuffer.conversion that `vobscure estimate` prints, one line each.
CONVERSION_LINES = (
    ("background", "background pixels", "no surface: depth not finite{background}"),
    ("renormalized", "renormalized normals", "length off 1 by more than the tolerance, rescaled"),
    ("flipped", "flipped normals", "facing away from the camera, turned towards it"),
    ("repaired", "repaired normals", "zero or NaN on covered pixels, derived from the depth"),
)


def _frame_options(e, *, lens_required: bool) -> None:
    """The options that read a renderer's frame (camera, conversions, channels): shared by
    `vobscure estimate` and `vobscure compare --gbuffer`."""
    lens = e.add_mutually_exclusive_group(required=lens_required)
    lens.add_argument("--fov", type=float, metavar="DEG", help="vertical field of view in degrees")
    lens.add_argument("--intrinsics", type=float, nargs=4, metavar=("FX", "FY", "CX", "CY"),
                      help="pinhole intrinsics in pixels (principal point from the top-left corner)")
    lens.add_argument("--projection", type=Path, metavar="FILE",
                      help="a 4x4 projection matrix as text (numpy.loadtxt)")
    e.add_argument("--projection-convention", choices=("opengl", "directx"), default="opengl",
                   help="how --projection is written (default opengl: column vectors, looking down -z)")
    e.add_argument("--pose", type=Path, default=None, metavar="FILE",
                   help="4x4 camera-to-world matrix as text, OpenGL style (the camera looks down its -z, y up; "
                        "Blender's camera matrix_world); needed for world-space normals")
    e.add_argument("--depth-kind", default="linear",
                   help="what the depth values are (default linear view depth; see GBuffer.from_arrays)")
    e.add_argument("--near", type=float, default=None, help="near plane, for non-linear depth kinds")
    e.add_argument("--far", type=float, default=None, help="far plane, for non-linear depth kinds")
    e.add_argument("--normal-space", choices=("view", "world"), default=None,
                   help="space of the stored normals (default view)")
    e.add_argument("--normal-encoding", choices=("signed", "unit"), default=None,
                   help="signed [-1, 1] or unit [0, 1] stored normals (default signed; unit for PNG maps)")
    e.add_argument("--convention", choices=("vobscure", "opengl", "directx"), default=None,
                   help="axis convention of view-space normals (default vobscure)")
    e.add_argument("--background", type=float, default=None, metavar="Z",
                   help="depth value of background pixels (e.g. 1e10 for Blender); default inf")
    e.add_argument("--depth-channel", default=None, metavar="NAME", help="EXR channel or NPZ array of the depth")
    e.add_argument("--normal-channels", default=None, metavar="NAME",
                   help="EXR layer (e.g. 'View Layer.Normal') or X,Y,Z channel names, or NPZ array")
    e.add_argument("--depth-scale", type=float, default=None, metavar="S",
                   help="scene units per stored depth unit (required for PNG depth)")
    e.add_argument("--repair-normals", action="store_true",
                   help="derive zero or NaN normals of covered pixels from the depth (default: an error)")


def _estimate_parser(sub) -> None:
    from . import methods

    e = sub.add_parser("estimate", help="estimate the VO of your own frame(s) from depth (and normal) files",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Estimate screen-space Volumetric Obscurance of a renderer's frame: read "
                                   "its depth (and normals) from EXR, NPY/NPZ, PFM or 16-bit PNG files "
                                   "(vobscure.io.read_gbuffer), run one estimator and write the visibility "
                                   "(EXR, PNG, NPY or PFM). A directory or glob of frames runs frame by frame "
                                   "with the same seed and reports the temporal flicker.",
                       epilog="example:\n  vobscure estimate --depth frame.exr --fov 39.6 --radius 0.5 "
                              "--out vo.exr\n  vobscure estimate --depth 'frames/*.exr' --fov 39.6 --radius 0.5 "
                              "--method gtao --out vo/\n  (writes vo/<frame>_gtao.exr for each frame)\n\n"
                              "methods (--method NAME[:SAMPLES[:FETCH]], from vobscure.methods; the models that "
                              "need the scene's description do not run on a frame):\n  "
                              + methods.describe().replace("\n", "\n  "))
    e.add_argument("--depth", required=True, metavar="PATH",
                   help="depth file (.exr .npy .npz .pfm .png), a directory of them or a glob in quotes")
    e.add_argument("--normal", default=None, metavar="PATH",
                   help="normal file(s) when the normals are not in the depth file (same count as --depth)")
    _frame_options(e, lens_required=True)
    e.add_argument("--method", default="line:9", metavar="NAME[:SAMPLES[:FETCH]]",
                   help="one screen-space configuration from vobscure.methods, NAME one of "
                        f"{', '.join(n for n in methods.names() if not methods.get(n).needs_scene)} "
                        "(listed below; default line:9)")
    e.add_argument("--radius", type=float, required=True, help="ball radius in scene units")
    e.add_argument("--normal-clamp", action="store_true", help="half-ball VO (Sec. 4.4)")
    e.add_argument("--thickness", type=float, default=None, help="thickness model (Sec. 4.3), scene units")
    e.add_argument("--blur", action="store_true", help="edge-aware bilateral blur of the result (Sec. 4.1)")
    e.add_argument("--seed", type=int, default=0, help="random seed, the same for every frame (default 0)")
    e.add_argument("--flicker-reference", type=int, default=0, metavar="SAMPLES",
                   help="sequences: also compute the converged screen-space VO (vo_reference) with SAMPLES "
                        "samples per frame and subtract its frame-to-frame change from the flicker, as "
                        "`compare --orbit` does (default 0: report the raw change)")
    e.add_argument("--out", type=Path, default=Path(DEFAULT_ESTIMATE_OUT), metavar="PATH",
                   help="output .exr/.png/.npy/.pfm file, or a directory (EXR files <frame>_<method>.exr, "
                        "<frame> the frame file's name without the word depth, e.g. frame0001_gtao.exr for "
                        "frame0001_depth.exr), or a pattern with {frame}, {stem} (the file's name as it is) and "
                        f"{{method}}, e.g. 'vo/{{frame}}.png' (default: the directory {DEFAULT_ESTIMATE_OUT}/)")
    e.add_argument("--bits", type=int, choices=(8, 16), default=8, help="PNG bit depth (default 8)")
    e.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def _frame_paths(spec: str, what: str) -> list[Path]:
    """A file, a directory of frames (sorted) or a glob (sorted)."""
    import glob

    from .io import SUFFIXES

    path = Path(spec)
    if path.is_dir():
        found = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)
        if not found:
            raise ValueError(f"--{what} {spec}: the directory holds no {'/'.join(SUFFIXES)} files")
        return found
    if any(c in spec for c in "*?["):
        found = sorted(Path(p) for p in glob.glob(spec) if Path(p).is_file())
        if not found:
            raise FileNotFoundError(f"--{what} {spec!r}: the pattern matches no file")
        return found
    if not path.exists():
        raise FileNotFoundError(f"--{what}: no such file: {spec}")
    return [path]


def _matrix_arg(path: Path, name: str) -> np.ndarray:
    if not path.is_file():
        raise FileNotFoundError(f"--{name}: no such file: {path}")
    try:
        m = np.loadtxt(path, dtype=np.float64, delimiter=None, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"--{name} {path}: not a matrix of numbers ({exc})") from None
    if m.shape != (4, 4) or not np.isfinite(m).all():
        raise ValueError(f"--{name} {path}: expected a 4x4 matrix of finite numbers, got shape {m.shape}")
    return m


def _estimate_camera(args, size, pose):
    """The camera of the frames: --fov (Camera.look_at), --intrinsics or --projection."""
    from .camera import Camera

    if args.fov is not None:
        if pose is None:  # at the origin, looking down +z with y up (view space = this frame)
            return Camera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), up=(0.0, 1.0, 0.0), size=size, fov_y=args.fov)
        eye, up, back = pose[:3, 3], pose[:3, 1], pose[:3, 2]   # OpenGL: columns right, up, back, eye
        return Camera.look_at(eye, eye - back, up=up, size=size, fov_y=args.fov)
    vobscure_pose = None if pose is None else pose @ np.diag([1.0, 1.0, -1.0, 1.0])  # columns right, up, forward
    if args.intrinsics is not None:
        fx, fy, cx, cy = args.intrinsics
        return Camera.from_intrinsics(fx, fy, cx, cy, size, pose=vobscure_pose)
    matrix = _matrix_arg(args.projection, "projection")
    return Camera.from_projection(matrix, size, convention=args.projection_convention, pose=vobscure_pose)


def _frame_reader(args):
    """``read(depth_path, normal_path, camera) -> (GBuffer, camera)`` for the frame options of
    :func:`_frame_options`: files by :func:`vobscure.io.read_buffers`, the camera made from the
    first frame's size (later frames must match it), conversions by ``GBuffer.from_arrays``."""
    from .gbuffer import GBuffer
    from .io import read_buffers

    if args.fov is None and args.intrinsics is None and args.projection is None:
        raise ValueError("a frame needs its camera: give --fov, --intrinsics or --projection")
    pose = _matrix_arg(args.pose, "pose") if args.pose is not None else None
    channels = args.normal_channels
    convert = {k: v for k, v in (("near", args.near), ("far", args.far), ("normal_space", args.normal_space),
                                 ("normal_encoding", args.normal_encoding), ("convention", args.convention),
                                 ("background", args.background)) if v is not None}
    if getattr(args, "repair_normals", False):
        convert["repair_normals"] = True
    if args.normal_space == "world" and pose is None and args.intrinsics is None and args.projection is None:
        raise ValueError("--normal-space world needs the camera's --pose")

    def read(depth_path, normal_path, camera):
        depth, normal, found = read_buffers(depth_path, normal_path=normal_path, depth_channel=args.depth_channel,
                                            normal_channels=channels, depth_scale=args.depth_scale)
        H, W = depth.shape
        if camera is None:
            camera = _estimate_camera(args, (W, H), pose)
        elif camera.size != (W, H):
            raise ValueError(f"{depth_path} is {W}x{H} pixels but the first frame is "
                             f"{camera.size[0]}x{camera.size[1]}; every frame must have one size")
        kwargs = dict(convert)
        if found.get("normal_encoding") and "normal_encoding" not in kwargs:
            kwargs["normal_encoding"] = found["normal_encoding"]
        gb = GBuffer.from_arrays(depth, normal, camera=camera, depth_kind=args.depth_kind, **kwargs)
        gb.conversion["source"] = dict(found)
        return gb, camera

    return read


def _estimate_main(args) -> int:
    from tqdm import tqdm

    from . import methods
    from ._io import check_writable_dir
    from ._memory import require_estimate
    from .convert import NormalsRenormalizedWarning, NormalsRepairedWarning
    from .io import write_image
    from .metrics import flicker
    from .screenspace import bilateral_blur, vo_reference

    depth_paths = _frame_paths(args.depth, "depth")
    normal_paths = _frame_paths(args.normal, "normal") if args.normal is not None else [None] * len(depth_paths)
    if len(normal_paths) != len(depth_paths):
        raise ValueError(f"--depth names {len(depth_paths)} frame(s) but --normal {len(normal_paths)}; "
                         f"give one normal file per depth file")
    configs = methods.parse(args.method)
    if len(configs) != 1:
        raise ValueError(f"--method takes one configuration, got {len(configs)}: {args.method!r}")
    config = configs[0]
    if config.spec.needs_scene:
        raise ValueError(f"--method {config.label}: this model needs the scene's description, not a G-buffer; "
                         f"choose a screen-space method: "
                         f"{', '.join(n for n in methods.names() if not methods.get(n).needs_scene)}")
    if args.flicker_reference < 0:
        raise ValueError(f"--flicker-reference must be >= 0 samples, got {args.flicker_reference}")
    if not (np.isfinite(args.radius) and args.radius > 0):
        raise ValueError(f"--radius must be a finite number > 0, got {args.radius}")
    many = len(depth_paths) > 1
    outs = _estimate_outputs(args.out, depth_paths, _method_tag(args.method))
    for folder in dict.fromkeys(o.parent for o in outs):
        check_writable_dir(folder, "the folder of --out")   # before the work, not after it
    read_frame = _frame_reader(args)

    frames, references, camera, started = [], [], None, time.perf_counter()
    totals, sources = {key: 0 for key in ("pixels", "covered", "derived")}, []
    totals.update((key, 0) for key, *_ in CONVERSION_LINES)
    bar = tqdm(total=len(depth_paths), desc="estimate", unit="frame", disable=args.quiet or not many)
    for depth_path, normal_path, out in zip(depth_paths, normal_paths, outs):
        with warnings.catch_warnings():
            # the counts these warnings carry are printed below, one line each
            warnings.simplefilter("ignore", NormalsRenormalizedWarning)
            warnings.simplefilter("ignore", NormalsRepairedWarning)
            gb, camera = read_frame(depth_path, normal_path, camera)
        for key in totals:
            totals[key] += int(gb.conversion[key])
        sources.append(gb.conversion["source"])
        H, W = gb.valid.shape
        if not frames:   # the whole job, refused before the first estimate when it cannot fit
            require_estimate(len(depth_paths), flicker_reference=many and args.flicker_reference > 0, size=(W, H))
        stages = tqdm(total=3 + args.blur, desc=depth_path.name, leave=False,
                      disable=args.quiet or many or H * W < ESTIMATE_PROGRESS_PIXELS)
        stages.update()
        v = config.run(gb, radius=args.radius, normal_clamp=args.normal_clamp, thickness=args.thickness,
                       seed=args.seed)
        v = np.asarray(v)
        stages.update()
        if args.blur:
            v = bilateral_blur(v, gb)
            stages.update()
        write_image(out, v, bits=args.bits) if out.suffix.lower() == ".png" else write_image(out, v)
        stages.update()
        stages.close()
        frames.append(v)
        if many and args.flicker_reference:
            references.append(vo_reference(gb, radius=args.radius, samples=args.flicker_reference,
                                           normal_clamp=args.normal_clamp, thickness=args.thickness,
                                           seed=args.seed).value)
        bar.update()
    bar.close()
    seconds = time.perf_counter() - started
    if not args.quiet:
        last = frames[-1]
        print(f"{config.label} radius {args.radius:g}{' normal clamp' if args.normal_clamp else ''}"
              f"{'' if args.thickness is None else f' thickness {args.thickness:g}'}{' blurred' if args.blur else ''}: "
              f"{len(frames)} frame(s) of {camera.width}x{camera.height}, {seconds:.2f} s")
        print(f"  mean visibility {np.nanmean(last):.4f} over {int(np.isfinite(last).sum())} covered pixels "
              f"(last frame)" if np.isfinite(last).any() else "  no covered pixel (background only)")
        for line in _source_lines(sources):
            print(f"  {line}")
        for line in _conversion_lines(totals, len(frames), args.background):
            print(f"  {line}")
        if not many:
            print(f"  wrote {outs[0]}")
        else:
            print(f"  wrote {len(outs)} files: {outs[0]} ... {outs[-1]}")
    if many and not args.quiet:
        if references:
            f = flicker(np.stack(frames), np.stack(references), flip=False)
            print(f"  flicker: {f.value:.5f} (mean |V(t+1) - V(t)| = {f.estimate_change:.5f} less the "
                  f"reference's {f.reference_change:.5f}, vo_reference with {args.flicker_reference} samples) "
                  f"over {f.pairs} pixel pairs ({f.ignored} skipped)")
        else:
            f = flicker(np.stack(frames), flip=False)
            print(f"  flicker: mean |V(t+1) - V(t)| = {f.estimate_change:.5f} over {f.pairs} pixel pairs "
                  f"({f.ignored} undefined skipped); it includes the real change of the frames "
                  f"(--flicker-reference SAMPLES subtracts it)")
    return 0


def _source_lines(sources) -> list[str]:
    """Which files and channels the depth and normals came from (the first frame's, and how
    many frames)."""
    first, n = sources[0], len(sources)
    every = "" if n == 1 else f" (the same channels in all {n} frames)"
    depth = first["depth"]
    if first.get("depth_channel") is not None:
        name = first["depth_channel"]
        depth = (f"{depth[: -len(name) - 1]}, channel {name}"
                 + (" (R = G = B: a grey image, as Blender's single-layer File Output writes a float)"
                    if name == "R" else ""))
    lines = [f"depth: {depth}{every}"]
    if first.get("normal_channels") is not None:
        names = first["normal_channels"]
        lines.append(f"normals: {first['normal'][: -len('/'.join(names)) - 1]}, channels {', '.join(names)}")
    elif first.get("normal"):
        lines.append(f"normals: {first['normal']}")
    else:
        lines.append("normals: none in the files; derived from the depth")
    return lines


def _conversion_lines(totals, frames: int, background) -> list[str]:
    """One line per count of the conversion (:data:`CONVERSION_LINES`), summed over the frames."""
    where = "" if frames == 1 else f", over {frames} frames"
    extra = "" if background is None else f" or >= {background:g}"
    lines = []
    for key, label, meaning in CONVERSION_LINES:
        if key != "background" and totals["derived"] == totals["covered"]:
            continue    # the normals were all derived: nothing stored to renormalize, flip or repair
        of = totals["pixels"] if key == "background" else totals["covered"]
        lines.append(f"{label}: {totals[key]} of {of} {'pixels' if key == 'background' else 'covered pixels'}"
                     f"{where} ({meaning.format(background=extra)})")
    if totals["derived"]:
        lines.append(f"derived normals: {totals['derived']} of {totals['covered']} covered pixels{where} (no normals "
                     f"in the files)")
    return lines


def _method_tag(spec: str) -> str:
    """The method as written on the command line, fit for a file name (``line:9`` -> ``line-9``)."""
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in spec.strip().replace(":", "-"))


def _frame_name(path) -> str:
    """A frame file's name without the word depth (and one separator next to it): the name
    the outputs of `vobscure estimate` take. A name left empty or with digits only gets
    ``frame`` in front.

    Examples
    --------
    >>> [_frame_name(p) for p in ("frame0001_depth.exr", "frameDepth0001.exr", "Depth0001.exr",
    ...                           "depth.exr", "shot_Depth_0001.exr", "hallway.exr", "zdepth.exr")]
    ['frame0001', 'frame0001', 'frame0001', 'frame', 'shot_0001', 'hallway', 'zdepth']
    """
    import re

    stem = Path(path).stem
    m = re.search(r"Depth|DEPTH|(?<![a-z])depth(?![a-z])", stem)
    if m is None:
        return stem
    before, after, seps = stem[:m.start()], stem[m.end():], ("_", "-", ".", " ")
    if before.endswith(seps) and (after.startswith(seps) or not after):
        before = before[:-1]
    elif after.startswith(seps):
        after = after[1:]
    name = (before + after).strip("._- ")
    return f"frame{name}" if not name or name.isdigit() else name


def _estimate_outputs(out: Path, depth_paths, method: str) -> list[Path]:
    from .io import SUFFIXES

    pattern = any(key in str(out) for key in ("{stem}", "{frame}", "{method}"))
    if len(depth_paths) == 1 and not pattern:
        if out.is_dir() or str(out).endswith(("/", os.sep)) or out.suffix == "":
            return [out / f"{_frame_name(depth_paths[0])}_{method}.exr"]
        if out.suffix.lower() not in (".exr", ".png", ".npy", ".pfm"):
            raise ValueError(f"--out {out}: the suffix must be .exr, .png, .npy or .pfm")
        if out.resolve() == depth_paths[0].resolve():
            raise ValueError(f"--out {out}: would overwrite the input frame")
        return [out]
    if pattern:
        outs = [Path(str(out).replace("{stem}", p.stem).replace("{frame}", _frame_name(p)).replace("{method}", method))
                for p in depth_paths]
        if outs[0].suffix.lower() not in (".exr", ".png", ".npy", ".pfm"):
            raise ValueError(f"--out {out}: the suffix must be .exr, .png, .npy or .pfm")
    else:
        if out.suffix.lower() in SUFFIXES and not out.is_dir():
            raise ValueError(f"--out {out}: {len(depth_paths)} frames need a directory or a pattern with "
                             f"{{frame}}, e.g. 'vo/{{frame}}.exr'")
        outs = [out / f"{_frame_name(p)}_{method}.exr" for p in depth_paths]
    if len(set(outs)) != len(outs):
        raise ValueError(f"--out {out}: two frames would write the same file (frames with the same name)")
    resolved = {p.resolve() for p in depth_paths}
    if any(o.resolve() in resolved for o in outs):
        raise ValueError(f"--out {out}: would overwrite an input frame")
    return outs


def render(*, scene: str = DEFAULT_SCENE, size=DEFAULT_SIZE, quantity: str = "ao", radius=None,
           rays: int = 256, samples: int = 1024, seed: int = 0, threads=None,
           out=Path("vobscure-out"), progress: bool = True, allow_open: bool = False, camera=None) -> dict:
    """Run the render job; returns the provenance record (also stored in the ``.npz``).
    ``camera`` (a :class:`~vobscure.Camera` of ``size``) replaces the scene's view."""
    from . import __version__
    from ._io import check_writable_dir, file_set, save_npz
    from ._memory import render_job_need, require
    from .experiments.common import default_radius
    from .render import render_gbuffer
    from .groundtruth import ground_truth
    from .scenes import resolve

    check_writable_dir(out, "out")   # before the work, not after it
    t0 = time.perf_counter()
    sc, scene_spec = resolve(scene)
    cam = sc.camera(tuple(size)) if camera is None else camera
    if radius is None:
        radius = default_radius(sc)
    require(render_job_need(quantity, threads=threads), size=cam.size, reduce="--size",
            what=f"rendering a {cam.width} x {cam.height} G-buffer with its ground truth")
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
    with file_set(out, stem) as stage:    # the four files replace the previous run's together
        save_npz(stage / f"{stem}.npz", provenance, depth=gb.depth, normal=gb.normal, valid=gb.valid,
                 world_position=gb.world_position, world_normal=gb.world_normal,
                 visibility=ref.value, stderr=ref.stderr)
        _save_png(stage / f"{stem}_depth.png", _depth_image(gb.depth, gb.valid))
        _save_png(stage / f"{stem}_normal.png", _normal_image(gb.normal, gb.valid))
        _save_png(stage / f"{stem}_visibility.png", _visibility_image(ref.value, gb.valid))
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


def _error_text(exc: BaseException) -> str:
    """One line for an error: the message of a ValueError; for a file-system error (OSError)
    its reason and the path it names."""
    if isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror if exc.filename is None else f"{exc.filename}: {exc.strerror}"
        if exc.filename2 is not None:
            text += f" (-> {exc.filename2})"
    else:
        text = str(exc)
    return " ".join(text.split())


def _warning_printer(prefix: str):
    """A ``warnings.showwarning`` that prints one line, ``PREFIX: warning: MESSAGE``."""
    def show(message, category, filename, lineno, file=None, line=None):
        print(f"{prefix}: warning: {' '.join(str(message).split())}", file=sys.stderr if file is None else file)

    return show


def main(argv=None) -> int:
    """Entry point of the ``vobscure`` command; returns the exit status.

    Errors in the arguments, in the input files and in writing the outputs are one line on
    stderr naming the option or path, and the exit status 2.
    """
    from ._io import check_writable_dir

    parser = _parser()
    argv = [str(a) for a in (sys.argv[1:] if argv is None else argv)]
    args = parser.parse_args(numbers_as_written(joined_list_values(argv)))
    if args.command is None:
        parser.print_help()
        return 0
    if args.command == "scenes":
        from . import scenes

        for name in scenes.names():
            doc = (getattr(scenes, name).__doc__ or "").strip().splitlines()
            print(f"{name:16s} {doc[0] if doc else ''}")
        return 0
    with warnings.catch_warnings():
        warnings.showwarning = _warning_printer(f"vobscure {args.command}")
        try:
            if args.command == "estimate":
                return _estimate_main(args)
            if args.command in ("compare", "figures"):
                return _compare_main(args) if args.command == "compare" else _figures_main(args)
            check_writable_dir(args.out, "--out")   # before the work, not after it
            record = render(scene=args.scene, size=args.size, quantity=args.quantity, radius=args.radius,
                            rays=args.rays, samples=args.samples, seed=args.seed, threads=args.threads,
                            out=args.out, progress=not args.quiet, allow_open=args.allow_open,
                            camera=_view_camera(args, args.size, args.scene))
        except (ValueError, OSError) as exc:
            print(f"vobscure {args.command}: error: {_error_text(exc)}", file=sys.stderr)
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
