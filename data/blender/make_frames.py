"""Render the scene of ``scene.json`` with Blender's Cycles and write the frames Blender writes.

Runs only where Blender's Python module is installed (``pip install bpy``, in its own
environment: bpy is not a dependency of vobscure)::

    python make_frames.py [OUT_DIR]      # default: the folder of this script

Writes to OUT_DIR, through Blender's own writers:

- ``single/`` -- the compositor's File Output node, single-layer OpenEXR, float32: one file
  per input, the input ``Depth`` (a float socket), ``Normal`` (a vector socket) and
  ``DepthColor`` (a colour socket fed the Depth pass, as when Depth is linked to the node's
  colour input);
- ``half/`` -- the same node in half float (``color_depth = '16'``);
- ``multilayer/`` -- the File Output node, multilayer OpenEXR, inputs ``Depth`` and ``Normal``;
- ``render/`` -- the render result saved as multilayer OpenEXR (the passes of the view layer,
  ``ViewLayer``, Blender's default name);
- ``frames.json`` -- Blender's version, the camera as Blender reports it after the render
  (``matrix_world``, vertical field of view), the render settings and every written file's
  channels (name and pixel type), parsed from the file's header here (no library needed
  beyond bpy).

The settings that make the passes comparable with a pinhole renderer that samples pixel
centres: Cycles' pixel filter is 0.01 pixel wide (its minimum), so every sample's ray leaves
within 0.005 pixel of the pixel's centre.
"""

from __future__ import annotations

import json
import math
import shutil
import struct
import sys
from pathlib import Path

import bpy
from mathutils import Vector

HERE = Path(__file__).resolve().parent
SAMPLES = 4
#: The narrowest pixel filter Cycles accepts (``film_filter_width`` minimum), in pixels.
FILTER_WIDTH = 0.01


def _box(name, lo, hi):
    """An axis-aligned box mesh object with outward quads."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    verts = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
             (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _camera(spec):
    W, H = spec["size"]
    data = bpy.data.cameras.new("Camera")
    data.sensor_fit = "VERTICAL"
    data.lens_unit = "FOV"
    data.angle_y = math.radians(spec["fov_y_degrees"])
    obj = bpy.data.objects.new("Camera", data)
    bpy.context.scene.collection.objects.link(obj)
    eye, target = Vector(spec["eye"]), Vector(spec["target"])
    obj.location = eye
    # Blender's camera looks down its local -z with its local y up
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = (target - eye).to_track_quat("-Z", "Y")
    bpy.context.scene.camera = obj
    r = bpy.context.scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    return obj


def _file_output(tree, layers, directory, *, multilayer, half):
    node = tree.nodes.new("CompositorNodeOutputFile")
    node.directory = str(directory) + "/"
    node.file_name = "frame"
    node.format.media_type = "MULTI_LAYER_IMAGE" if multilayer else "IMAGE"
    node.format.file_format = "OPEN_EXR_MULTILAYER" if multilayer else "OPEN_EXR"
    node.format.color_depth = "16" if half else "32"
    node.format.exr_codec = "ZIP"
    inputs = [("Depth", "FLOAT", "Depth"), ("Normal", "VECTOR", "Normal")]
    if not multilayer:
        inputs.append(("DepthColor", "RGBA", "Depth"))
    for name, socket_type, pass_name in inputs:
        node.file_output_items.new(socket_type, name)
        tree.links.new(layers.outputs[pass_name], node.inputs[name])
    return node


def _exr_channels(path):
    """(name, pixel type) of every channel of a scanline OpenEXR file, from its header
    (OpenEXR file layout: magic, version, then attributes name\\0 type\\0 size value)."""
    data = Path(path).read_bytes()
    if data[:4] != b"\x76\x2f\x31\x01":
        raise ValueError(f"{path} is not an OpenEXR file")
    pos, parts, channels = 8, [], []
    multipart = bool(struct.unpack("<I", data[4:8])[0] & 0x1000)
    while True:
        if data[pos] == 0:           # end of a header
            parts.append(channels)
            if not multipart or data[pos + 1] == 0:
                break
            pos, channels = pos + 1, []
            continue
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        kind = data[end + 1:tend].decode()
        size = struct.unpack("<i", data[tend + 1:tend + 5])[0]
        value = data[tend + 5:tend + 5 + size]
        if kind == "chlist":
            q = 0
            while value[q] != 0:
                cend = value.index(b"\0", q)
                cname = value[q:cend].decode()
                ptype = struct.unpack("<i", value[cend + 1:cend + 5])[0]
                channels.append([cname, {0: "uint", 1: "half", 2: "float"}[ptype]])
                q = cend + 1 + 16
        pos = tend + 5 + size
    return [c for part in parts for c in part]


def main(out_dir: Path) -> dict:
    spec = json.loads((HERE / "scene.json").read_text())
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    for name, (lo, hi) in spec["boxes"].items():
        _box(name, lo, hi)
    cam = _camera(spec["camera"])

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.seed = 0
    scene.cycles.filter_width = FILTER_WIDTH
    layer = scene.view_layers[0]
    layer.use_pass_z = True
    layer.use_pass_normal = True

    for sub in ("single", "half", "multilayer", "render"):
        shutil.rmtree(out_dir / sub, ignore_errors=True)
    tree = bpy.data.node_groups.new("Compositing", "CompositorNodeTree")
    scene.compositing_node_group = tree
    layers = tree.nodes.new("CompositorNodeRLayers")
    _file_output(tree, layers, out_dir / "single", multilayer=False, half=False)
    _file_output(tree, layers, out_dir / "half", multilayer=False, half=True)
    _file_output(tree, layers, out_dir / "multilayer", multilayer=True, half=False)

    settings = scene.render.image_settings
    settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.filepath = str(out_dir / "render" / "frame.exr")
    scene.frame_set(1)
    bpy.ops.render.render(write_still=True)

    bpy.context.view_layer.update()
    record = {
        "blender": bpy.app.version_string,
        "engine": "CYCLES",
        "samples": SAMPLES,
        "filter_width_pixels": FILTER_WIDTH,
        "view_layer": layer.name,
        "size": [scene.render.resolution_x, scene.render.resolution_y],
        "camera": {
            "matrix_world": [list(row) for row in cam.matrix_world],
            "fov_y_degrees": math.degrees(cam.data.angle_y),
            "sensor_fit": cam.data.sensor_fit,
            "clip_start": cam.data.clip_start,
            "clip_end": cam.data.clip_end,
        },
        "files": {},
    }
    for path in sorted(out_dir.glob("*/*.exr")):
        record["files"][str(path.relative_to(out_dir))] = _exr_channels(path)
    (out_dir / "frames.json").write_text(json.dumps(record, indent=2) + "\n")
    return record


if __name__ == "__main__":
    out = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE
    out.mkdir(parents=True, exist_ok=True)
    print(json.dumps(main(out)["files"], indent=1))
