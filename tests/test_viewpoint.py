"""Default views (scenes.viewpoint), glTF cameras, view diagnostics and the default radius's cap."""

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.experiments.common import (RADIUS_CAP_COVERAGE, RADIUS_CAP_FRACTION, RADIUS_METRES, choose_radius,
                                         default_radius)
from vobscure.scenes.viewpoint import (BACK_FACES, INSIDE_FOV_Y, ONE_PLANE, gltf_view, suggest_view,
                                       view_diagnostics, view_warnings)

MESHES = Path("/work/shared/data/meshes")
#: World-space agreement of a rendered hit with a hand-made ray-plane intersection: Embree
#: traces in float32 (relative error ~1e-7 of the distance, a few units here), and the hit is
#: then projected onto its plane in float64.
HIT_TOL = 1e-5


def _projected_radius_px(radius, view, size, depth):
    """r_px = R f_px / z with f_px = H / (2 tan(fov_y / 2)), or R H / ortho_height, written
    from the camera model, not through Camera.pixels_per_unit."""
    H = size[1]
    if view.get("ortho_height") is not None:
        return np.full(depth.shape, radius * H / view["ortho_height"])
    f_px = H / (2.0 * math.tan(math.radians(view["fov_y"]) / 2.0))
    return radius * f_px / depth


def _assert_cap_holds(scene, view, size):
    cam = vo.Camera.look_at(view["eye"], view["target"], view.get("up", (0, 1, 0)), size=size,
                            fov_y=view.get("fov_y"), ortho_height=view.get("ortho_height"))
    gb = vo.render_gbuffer(scene, cam)
    choice = choose_radius(scene, gb)
    r_px = _projected_radius_px(choice.radius, view, size, gb.depth[gb.valid])
    under = np.mean(r_px < RADIUS_CAP_FRACTION * size[1])
    assert under >= RADIUS_CAP_COVERAGE, (choice, under)
    assert choice.radius <= choice.base
    return choice, gb


# --------------------------------------------------------------------------- the radius rule
@pytest.mark.parametrize("name", vo.scenes.names())
def test_default_radius_projects_under_a_quarter_of_the_image_for_every_builtin_view(name):
    scene = vo.scenes.get(name)
    choice, _ = _assert_cap_holds(scene, scene.view, (64, 48))
    if scene.metadata.get("units") == "m":   # a scene in metres (the atrium) starts from 0.5 m
        assert choice.base == RADIUS_METRES and choice.rule in ("metres", "metres+cap")
    else:   # without units the rule is a tenth of the extent, lowered only by the cap
        assert choice.base == pytest.approx(0.1 * scene.extent, rel=1e-12)
        assert choice.rule in ("extent", "extent+cap")


def test_cap_inside_the_cornell_box_and_one_pixel_by_hand():
    scene = vo.scenes.cornell_box()
    view = {"eye": (0.0, 1.0, 0.3), "target": (0.0, 1.0, -1.0), "up": (0.0, 1.0, 0.0), "fov_y": 90.0}
    size = (40, 30)
    choice, gb = _assert_cap_holds(scene, view, size)
    # from 1.3 in front of the back wall with a 90-degree lens the default 0.1 x extent
    # (0.375) would project to 0.375 * 15 / 1.3 = 4.3 px at the wall but far more on the
    # nearby floor and side walls: the cap binds
    assert choice.capped
    # pixel (15, 25) looks right of the tall box and over the short one at the back wall
    # z = -1, which faces the camera: view depth 1.3; f = H / 2 / tan(45 deg) = 15 px
    i, j = 15, 25
    assert gb.depth[i, j] == pytest.approx(1.3, abs=1e-6)
    assert choice.radius * gb.camera.pixels_per_unit(gb.depth[i, j]) == pytest.approx(choice.radius * 15 / 1.3,
                                                                                         rel=1e-6)


def test_frame_without_scene_gets_the_same_cap_from_its_camera():
    scene = vo.scenes.sphere_on_plane()
    gb = vo.render_gbuffer(scene, scene.camera((48, 36)))
    frame = vo.GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera)
    choice = choose_radius(frame)
    assert choice.rule.startswith("frame")
    assert choice.radius == pytest.approx(min(choice.base, choose_radius(scene, gb).cap), rel=1e-12)
    r_px = _projected_radius_px(choice.radius, scene.view, (48, 36), gb.depth[gb.valid])
    assert np.mean(r_px < 9.0) >= RADIUS_CAP_COVERAGE


def test_orthographic_cap_is_a_quarter_of_the_view_height():
    scene = vo.scenes.slab()
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(16, 16), ortho_height=2.0)
    choice = choose_radius(scene, vo.render_gbuffer(scene, cam))
    # every pixel projects R at H / ortho_height = 8 px per unit: the cap is 4 px / 8 = 0.5
    assert choice.cap == pytest.approx(0.5, rel=2e-3) and choice.cap < 0.5


def test_radius_without_a_view_is_the_rule_and_default_radius_unchanged():
    scene = vo.scenes.crease()
    choice = choose_radius(scene)
    assert choice.radius == default_radius(scene) == 0.1 * scene.extent
    assert not choice.capped and math.isinf(choice.cap)
    assert "0.1 x the scene's extent" in choice.sentence()


def test_empty_view_is_a_clear_error_and_warning():
    scene = vo.scenes.slab()
    cam = vo.Camera.look_at((0, 3, 0), (0, 6, 0), up=(0, 0, -1), size=(8, 8), fov_y=30)   # looking away
    gb = vo.render_gbuffer(scene, cam)
    with pytest.raises(ValueError, match="covers no pixel"):
        choose_radius(scene, gb)
    d = view_diagnostics(gb)
    assert d["coverage"] == 0.0
    assert "covers no pixel" in view_warnings(d)[0]


# --------------------------------------------------------------------------- default views
def _inward_box(extents, centre):
    """A box whose faces are wound (and whose normals point) into it: a closed room."""
    box = trimesh.creation.box(extents=extents)
    return trimesh.Trimesh(box.vertices + np.asarray(centre, dtype=float), box.faces[:, ::-1])


def _room_obj(path: Path) -> Path:
    """A closed room (inward-facing box, 6 x 3 x 8) with two boxes standing on its floor."""
    room = _inward_box((6.0, 3.0, 8.0), (0.0, 1.5, 0.0))
    a = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    a.apply_translation((1.5, 0.5, -2.0))
    b = trimesh.creation.box(extents=(0.8, 2.0, 0.8))
    b.apply_translation((-1.8, 1.0, 1.5))
    scene = trimesh.Scene({"room": room, "box_a": a, "box_b": b})
    scene.export(path)
    return path


def test_closed_room_from_a_file_is_seen_from_inside(tmp_path):
    scene = vo.scenes.load(_room_obj(tmp_path / "room.obj"))
    assert set(scene.meshes) == {"room", "box_a", "box_b"}
    view = scene.view
    eye = np.array(view["eye"])
    assert np.all(eye > [-3, 0, -4]) and np.all(eye < [3, 3, 4])          # inside the room
    assert not (np.all(np.abs(eye - [1.5, 0.5, -2.0]) < 0.5))              # not inside a box
    # no units declared: the eye stands at EYE_HEIGHT_FRACTION (0.4) of the 3-high clear height
    assert eye[1] == pytest.approx(1.2, abs=1e-6)
    assert view["fov_y"] == INSIDE_FOV_Y
    d = view_diagnostics(vo.render_gbuffer(scene, scene.camera((64, 36))), scene)
    assert d["coverage"] == 1.0 and d["back_faces"] == 0.0
    assert view_warnings(d) == []
    assert scene.view == view                                             # chosen once, cached


def test_probe_inside_a_solid_is_not_an_eye(tmp_path):
    """A closed room whose centre is inside a pillar: the eye is found from another probe."""
    room = _inward_box((6.0, 3.0, 6.0), (0.0, 1.5, 0.0))
    pillar = trimesh.creation.box(extents=(1.0, 3.0, 1.0))
    pillar.apply_translation((0.0, 1.5, 0.0))
    scene = vo.Scene({"room": room, "pillar": pillar})
    eye = np.array(scene.view["eye"])
    assert not np.all(np.abs(eye - [0.0, 1.5, 0.0]) < [0.5, 1.5, 0.5])
    d = view_diagnostics(vo.render_gbuffer(scene, scene.camera((48, 27))), scene)
    assert d["coverage"] == 1.0 and d["back_faces"] == 0.0


def test_plane_only_scene_is_flagged_as_one_plane():
    quad = trimesh.Trimesh([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    scene = vo.Scene(quad)
    view = suggest_view(scene)
    assert view["eye"][1] > 0                                    # from above, the side it faces
    d = view_diagnostics(vo.render_gbuffer(scene, scene.camera((48, 27))), scene)
    assert d["plane_fraction"] == 1.0
    assert any("one plane" in w for w in view_warnings(d))


def test_wall_seen_head_on_is_one_depth():
    scene = vo.scenes.slab()
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(16, 16), fov_y=20)
    d = view_diagnostics(vo.render_gbuffer(scene, cam))
    assert d["depth_spread"] == pytest.approx(0.0, abs=1e-12)
    assert any("one depth" in w for w in view_warnings(d))


def test_camera_inside_a_solid_is_warned():
    scene = vo.Scene(trimesh.creation.box(extents=(2, 2, 2)))
    cam = vo.Camera.look_at((0, 0, 0), (0, 0, -1), size=(16, 12), fov_y=60)
    d = view_diagnostics(vo.render_gbuffer(scene, cam), scene)
    assert d["back_faces"] == 1.0
    assert any("inside a" in w for w in view_warnings(d))


def test_builtin_scenes_keep_their_views():
    box = vo.scenes.cornell_box()
    assert box.view["eye"] == (0.0, 1.0, 3.9) and box.view["fov_y"] == 39.0


@pytest.mark.parametrize("name", ["CornellBox-Original.obj", "stanford-bunny.obj", "spot.obj", "teapot.obj"])
def test_real_meshes_get_a_view_that_sees_them(name):
    path = MESHES / name
    if not path.exists():
        pytest.skip(f"{path} is absent")
    scene = vo.scenes.load(path)
    d = view_diagnostics(vo.render_gbuffer(scene, scene.camera((64, 36))), scene)
    # the chosen view covers most of the image, is not one plane, and does not look from
    # inside a solid (the open teapot shows some back faces, inside its spout and rim)
    assert d["coverage"] > 0.5 and d["plane_fraction"] < ONE_PLANE and d["back_faces"] < BACK_FACES
    _assert_cap_holds(scene, scene.view, (64, 36))


# --------------------------------------------------------------------------- glTF cameras
def _quat_y(angle):
    """Unit quaternion (x, y, z, w) of a rotation by ``angle`` radians about +y."""
    return [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]


def _gltf_doc(camera_node: dict, camera: dict, buffer_uri: str | None):
    """A glTF 2.0 document: a wall (the square |x|, |y| <= 2 at z = 0, facing +z) and a camera
    node; the positions and indices in one buffer."""
    positions = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], dtype=np.float32)
    indices = np.array([0, 1, 2, 0, 2, 3], dtype=np.uint16)
    blob = positions.tobytes() + indices.tobytes()
    buffer = {"byteLength": len(blob)}
    if buffer_uri is not None:
        buffer["uri"] = buffer_uri + base64.b64encode(blob).decode()
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "name": "wall"}, camera_node],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [buffer],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-2, -2, 0], "max": [2, 2, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "cameras": [camera],
    }
    return doc, blob


def _write_glb(path: Path, doc: dict, blob: bytes) -> Path:
    """GLB container (glTF 2.0 Sec. 4.4): 12-byte header, JSON chunk padded with spaces, BIN
    chunk padded with zeros, every chunk 4-byte aligned."""
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
    return path


@pytest.mark.parametrize("container", ["gltf", "glb"])
def test_gltf_camera_is_the_view_and_renders_the_expected_pixel(tmp_path, container):
    yaw, yfov = math.radians(20.0), 0.8
    eye = np.array([0.7, -0.3, 4.0])
    node = {"name": "cam", "translation": eye.tolist(), "rotation": _quat_y(yaw), "camera": 0}
    camera = {"type": "perspective", "perspective": {"yfov": yfov, "aspectRatio": 1.5, "znear": 0.05}}
    doc, blob = _gltf_doc(node, camera, "data:application/octet-stream;base64," if container == "gltf" else None)
    path = tmp_path / f"wall.{container}"
    if container == "gltf":
        path.write_text(json.dumps(doc))
    else:
        _write_glb(path, doc, blob)
    scene = vo.scenes.load(path)
    assert scene.metadata == {"units": "m"}
    view = scene.view
    assert view["fov_y"] == pytest.approx(math.degrees(yfov), rel=1e-12)
    assert view["aspect_ratio"] == 1.5
    np.testing.assert_allclose(view["eye"], eye, rtol=0, atol=1e-12)
    # the camera looks down its local -z turned by the yaw about +y: (-sin, 0, -cos)
    forward = np.subtract(view["target"], view["eye"])
    np.testing.assert_allclose(forward / np.linalg.norm(forward), [-math.sin(yaw), 0, -math.cos(yaw)], atol=1e-12)
    # a pixel's ray, made from the glTF camera model by hand, meets the wall z = 0 where
    # the render's hit is
    W, H = 30, 20
    gb = vo.render_gbuffer(scene, scene.camera((W, H)))
    f = H / (2 * math.tan(yfov / 2))
    i, j = 6, 22
    d_cam = np.array([(j + 0.5 - W / 2) / f, -(i + 0.5 - H / 2) / f, -1.0])
    c, s = math.cos(yaw), math.sin(yaw)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])                      # rotation about +y
    d = R @ d_cam
    expected = eye + (-eye[2] / d[2]) * d
    assert gb.valid[i, j]
    np.testing.assert_allclose(gb.world_position[i, j], expected, rtol=0, atol=HIT_TOL)
    # a glTF scene is in metres: the default radius is 0.5 m when the view allows it
    assert choose_radius(scene, gb).radius == RADIUS_METRES


def test_gltf_orthographic_camera_and_files_without_one(tmp_path):
    node = {"translation": [0, 0, 3], "camera": 0}
    doc, _ = _gltf_doc(node, {"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.0, "znear": 0.1,
                                                                        "zfar": 10}}, "data:;base64,")
    path = tmp_path / "ortho.gltf"
    path.write_text(json.dumps(doc))
    view = gltf_view(path)
    assert view["ortho_height"] == 2.0 and "fov_y" not in view and view["aspect_ratio"] == 2.0
    del doc["cameras"]
    doc["nodes"][1] = {"translation": [0, 0, 3]}
    path.write_text(json.dumps(doc))
    assert gltf_view(path) is None
    scene = vo.scenes.load(path)
    assert scene.metadata == {"units": "m"} and scene.view["fov_y"] == 45.0     # suggested


def test_gltf_camera_without_its_parameters_is_a_clear_error(tmp_path):
    doc, _ = _gltf_doc({"camera": 0}, {"type": "perspective", "name": "broken"}, "data:;base64,")
    path = tmp_path / "broken.gltf"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="camera 0 .'broken'. has type 'perspective' without"):
        gltf_view(path)
    (tmp_path / "bad.glb").write_bytes(b"not a glb file at all")
    with pytest.raises(ValueError, match="not a GLB file"):
        gltf_view(tmp_path / "bad.glb")


def test_gltf_camera_under_a_parent_node_composes_the_transforms(tmp_path):
    """A camera node that is the child of a translated, matrix-transformed parent."""
    parent = np.eye(4)
    parent[:3, 3] = [1.0, 2.0, 3.0]
    doc, _ = _gltf_doc({"name": "rig", "matrix": parent.T.ravel().tolist(), "children": [2]},
                       {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}, "data:;base64,")
    doc["nodes"].append({"translation": [0.0, 0.0, 1.0], "rotation": _quat_y(math.pi / 2), "camera": 0})
    path = tmp_path / "rig.gltf"
    path.write_text(json.dumps(doc))
    view = gltf_view(path)
    np.testing.assert_allclose(view["eye"], [1.0, 2.0, 4.0], atol=1e-12)
    # turned a quarter about +y, the lens (-z) looks down -x
    np.testing.assert_allclose(np.subtract(view["target"], view["eye"]), [-1.0, 0.0, 0.0], atol=1e-12)
