"""The Blender 5 frames of ``data/blender`` (written by ``make_frames.py``) and the same view
rendered by vobscure: what the tests of reading real frames compare.

``scene.json`` holds the boxes and the camera the script gave Blender; ``frames.json`` what
Blender reported after the render (its version, the camera's ``matrix_world`` as Blender
stores it, in float32, and the vertical field of view). The vobscure camera is built from
that record, as a user would from their own file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import trimesh

import vobscure as vo

DIR = Path(__file__).resolve().parents[1] / "data" / "blender"
#: Blender's depth on background pixels in float32 files (Cycles' "no hit" value).
BACKGROUND = 1e10
#: ... and in half-float files: 1e10 does not fit a half, Blender clamps it to the largest.
BACKGROUND_HALF = float(np.finfo(np.float16).max)
EPS32 = float(np.finfo(np.float32).eps)
#: Both renderers intersect in float32: the ray's origin and direction (from the float32
#: ``matrix_world``), and the hit, each rounded once per renderer. Their relative error
#: grows as 1 / |cos theta| on a surface seen at the angle theta from its normal (the hit
#: distance along the ray is the plane distance over cos theta). Budget: 8 roundings.
#: Measured on the committed frame: at most 2.7 eps32 / |cos theta| (14 eps32 at 84 degrees).
DEPTH_RTOL_ROUNDING = 8 * EPS32
#: A half float keeps 11 significant bits: storing rounds by at most 2^-11, relative.
HALF_RTOL = 2.0 ** -11
#: Normals of axis-aligned faces: one float32 rounding on each side.
NORMAL_ATOL = 2 * EPS32

#: The frames, as written: depth file, normal file (None: in the depth file), the depth
#: channel and the normal channels the reader must find by default, and the background value.
FILES = {
    "render": ("render/frame.exr", None, "ViewLayer.Depth.Z",
               ("ViewLayer.Normal.X", "ViewLayer.Normal.Y", "ViewLayer.Normal.Z"), BACKGROUND),
    "multilayer": ("multilayer/frame.exr", None, "Depth.V", ("Normal.X", "Normal.Y", "Normal.Z"), BACKGROUND),
    "single": ("single/frameDepth.exr", "single/frameNormal.exr", "R", ("X", "Y", "Z"), BACKGROUND),
    "single-colour": ("single/frameDepthColor.exr", "single/frameNormal.exr", "R", ("X", "Y", "Z"), BACKGROUND),
    "half-colour": ("half/frameDepthColor.exr", "half/frameNormal.exr", "R", ("X", "Y", "Z"), BACKGROUND_HALF),
}


def record(directory=DIR) -> dict:
    return json.loads((Path(directory) / "frames.json").read_text())


def pose(directory=DIR) -> np.ndarray:
    """Blender's ``matrix_world`` of the camera: OpenGL camera-to-world (columns right, up,
    back, eye)."""
    return np.array(record(directory)["camera"]["matrix_world"], dtype=np.float64)


def camera(directory=DIR) -> vo.Camera:
    """The camera as a user builds it from ``matrix_world`` and the vertical field of view."""
    rec = record(directory)
    m = pose(directory)
    eye, up, back = m[:3, 3], m[:3, 1], m[:3, 2]
    return vo.Camera.look_at(eye, eye - back, up=up, size=tuple(rec["size"]), fov_y=rec["camera"]["fov_y_degrees"])


def scene() -> vo.Scene:
    """The boxes of ``scene.json`` (corners taken from lo and hi exactly), flat shaded."""
    spec = json.loads((DIR / "scene.json").read_text())
    unit = trimesh.creation.box()
    corner = np.asarray(unit.vertices) > 0
    meshes = {name: trimesh.Trimesh(np.where(corner, np.asarray(hi, float), np.asarray(lo, float)),
                                    np.asarray(unit.faces), process=False)
              for name, (lo, hi) in spec["boxes"].items()}
    return vo.Scene(meshes, name="blender_boxes", smooth_angle=0.0)


def depth_rtol(gb, half: bool = False) -> np.ndarray:
    """Per-pixel relative tolerance of Blender's depth against ``gb.depth`` (see the
    constants above), on covered pixels."""
    ray = gb.world_position - gb.camera.eye
    ray /= np.linalg.norm(ray, axis=-1, keepdims=True)
    cos = np.abs(np.einsum("...i,...i->...", ray, gb.world_normal))
    with np.errstate(divide="ignore", invalid="ignore"):
        tol = DEPTH_RTOL_ROUNDING / cos
    return tol + (HALF_RTOL if half else 0.0)
