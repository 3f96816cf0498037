"""vobscure.io: G-buffers from a renderer's files and visibility images to files.

The test of record writes the crease's buffers the way Blender does (a multilayer EXR with
``View Layer.Depth.Z`` and world-space ``View Layer.Normal.X/Y/Z``, an OpenGL camera pose,
1e10 on background), reads them back knowing only the file and the camera's fov and pose, and
gets the original G-buffer's ``vo_line`` estimate.
"""

from __future__ import annotations

import re
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import blender_frames
import vobscure as vo
from vobscure import io as vio

OpenEXR = pytest.importorskip("OpenEXR")

DOCS = Path(__file__).resolve().parents[1] / "docs"
#: The round trip's agreement with the original G-buffer's estimate, in float32.
ROUND_TRIP_TOL = 1e-6
#: Cycles writes the distance along the ray: its float32 rounding (relative 6e-8 of ~10 units)
#: moves the linear depth recovered from it by ~1e-6, and the estimate as much (measured 1.3e-6).
DISTANCE_TOL = 5e-6
#: Blender's depth on background pixels.
BLENDER_BACKGROUND = 1e10
SIZE = (48, 32)
#: PNG colour types (PNG specification, section 11.2.2, IHDR).
GREY, RGB = 0, 2


def _png_header(path) -> tuple[int, int]:
    """(bit depth, colour type) from a PNG's IHDR chunk, read from the bytes."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", f"{path} is not a PNG"
    return data[24], data[25]


@pytest.fixture(scope="module")
def crease():
    scene = vo.scenes.get("crease")
    return vo.render_gbuffer(scene, scene.camera(SIZE))


def _opengl_pose(cam) -> np.ndarray:
    """The camera-to-world matrix of an OpenGL camera (Blender's ``matrix_world``): columns
    right, up, back (the camera looks down its -z) and the eye."""
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = cam.right, cam.up, -cam.forward, cam.eye
    return pose


def _camera_from_pose(pose, size, fov_y):
    """What a user knows: the pose and the vertical field of view."""
    eye, up, back = pose[:3, 3], pose[:3, 1], pose[:3, 2]
    return vo.Camera.look_at(eye, eye - back, up=up, size=size, fov_y=fov_y)


def _write_exr(path, channels):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}).write(str(path))


def _blender_exr(path, gb, *, distance=False):
    """A multilayer EXR as Blender writes it: linear depth (Cycles: the ray's length) with 1e10
    on background, world normals."""
    depth = np.linalg.norm(gb.world_position - gb.camera.eye, axis=-1) if distance else gb.depth
    depth = np.where(gb.valid, depth, BLENDER_BACKGROUND)
    channels = {"View Layer.Depth.Z": depth, "View Layer.Combined.R": np.ones(gb.shape)}
    for k, axis in enumerate("XYZ"):
        channels[f"View Layer.Normal.{axis}"] = gb.world_normal[:, :, k]
    _write_exr(path, channels)


def _vo_line(gb, normal_clamp=False):
    return vo.vo_line(gb.astype(np.float32), radius=0.5, samples=9, normal_clamp=normal_clamp, seed=0)


# --------------------------------------------------------------------------- the test of record
def test_blender_exr_round_trip_gives_the_same_estimate(crease, tmp_path):
    path = tmp_path / "frame.exr"
    _blender_exr(path, crease)
    pose = _opengl_pose(crease.camera)
    cam = _camera_from_pose(np.loadtxt(_savetxt(tmp_path / "pose.txt", pose)), SIZE, crease.camera.fov_y)
    gb = vio.read_gbuffer(path, camera=cam, normal_space="world", background=BLENDER_BACKGROUND)
    np.testing.assert_array_equal(gb.valid, crease.valid)
    for normal_clamp in (False, True):   # the clamp reads the normals
        expected, got = _vo_line(crease, normal_clamp), _vo_line(gb, normal_clamp)
        assert got.dtype == np.float32
        np.testing.assert_array_equal(np.isnan(got), ~crease.valid)
        assert np.nanmax(np.abs(got - expected)) <= ROUND_TRIP_TOL
        # not trivially equal: the crease has occluded pixels
        assert np.nanmin(expected) < (0.9 if normal_clamp else 0.45)


def test_cycles_distance_exr_round_trip(crease, tmp_path):
    path = tmp_path / "frame.exr"
    _blender_exr(path, crease, distance=True)
    cam = _camera_from_pose(_opengl_pose(crease.camera), SIZE, crease.camera.fov_y)
    gb = vio.read_gbuffer(path, camera=cam, depth_kind="distance", normal_space="world",
                          background=BLENDER_BACKGROUND)
    np.testing.assert_allclose(gb.depth[gb.valid], crease.depth[crease.valid], rtol=1e-6)
    for normal_clamp in (False, True):
        assert np.nanmax(np.abs(_vo_line(gb, normal_clamp) - _vo_line(crease, normal_clamp))) <= DISTANCE_TOL


def _savetxt(path, matrix):
    np.savetxt(path, matrix)
    return path


def test_blender_exr_channels_are_found_by_default(crease, tmp_path):
    path = tmp_path / "frame.exr"
    _blender_exr(path, crease)
    depth, normal, found = vio.read_buffers(path)
    assert found["depth"].endswith(":View Layer.Depth.Z")
    assert found["normal"].endswith(":View Layer.Normal.X/View Layer.Normal.Y/View Layer.Normal.Z")
    assert depth.dtype == np.float32 and depth.shape == crease.shape
    np.testing.assert_array_equal(depth[~crease.valid], np.float32(BLENDER_BACKGROUND))
    np.testing.assert_array_equal(normal, crease.world_normal.astype(np.float32))


@pytest.mark.parametrize("names", [
    ("Depth.V", ("Normal.X", "Normal.Y", "Normal.Z")),          # compositor File Output node
    ("Z", ("N.X", "N.Y", "N.Z")),
    ("RenderLayer.Depth.Z", ("RenderLayer.Normal.X", "RenderLayer.Normal.Y", "RenderLayer.Normal.Z")),
])
def test_default_channel_names(tmp_path, names):
    depth_name, normal_names = names
    d = np.arange(6, dtype=np.float32).reshape(2, 3) + 1
    channels = {depth_name: d, "other.R": d}
    channels.update({n: d * (k + 1) for k, n in enumerate(normal_names)})
    _write_exr(tmp_path / "f.exr", channels)
    depth, normal, found = vio.read_buffers(tmp_path / "f.exr")
    np.testing.assert_array_equal(depth, d)
    np.testing.assert_array_equal(normal[:, :, 2], 3 * d)
    assert found["depth"].endswith(depth_name)


def test_configured_channels_and_layer_name(tmp_path):
    d = np.ones((2, 2), np.float32)
    _write_exr(tmp_path / "f.exr", {"mydepth": 2 * d, "Z": d, "geo.Nrm.R": d, "geo.Nrm.G": 0 * d, "geo.Nrm.B": -d})
    depth, normal, _ = vio.read_buffers(tmp_path / "f.exr", depth_channel="mydepth", normal_channels="geo.Nrm")
    assert depth[0, 0] == 2 and normal[0, 0].tolist() == [1, 0, -1]
    _, normal, _ = vio.read_buffers(tmp_path / "f.exr", normal_channels=("geo.Nrm.B", "geo.Nrm.G", "geo.Nrm.R"))
    assert normal[0, 0].tolist() == [-1, 0, 1]
    # one string of three comma-separated names, as the command line takes it
    _, normal, _ = vio.read_buffers(tmp_path / "f.exr", normal_channels="geo.Nrm.B, geo.Nrm.G,geo.Nrm.R")
    assert normal[0, 0].tolist() == [-1, 0, 1]
    with pytest.raises(ValueError, match="normal_channels"):
        vio.read_buffers(tmp_path / "f.exr", normal_channels="geo.Nrm.B,geo.Nrm.G")


def test_normals_from_a_second_file(tmp_path):
    d = np.full((2, 3), 5.0, np.float32)
    n = np.tile(np.float32([0, 0, -1]), (2, 3, 1))
    _write_exr(tmp_path / "depth.exr", {"Z": d})
    np.save(tmp_path / "normal.npy", n)
    for kwargs in ({"path_or_paths": (tmp_path / "depth.exr", tmp_path / "normal.npy")},
                   {"path_or_paths": tmp_path / "depth.exr", "normal_path": tmp_path / "normal.npy"}):
        depth, normal, _ = vio.read_buffers(**kwargs)
        np.testing.assert_array_equal(normal, n)
    depth, normal, _ = vio.read_buffers(tmp_path / "depth.exr")  # no normals in the file: None
    assert normal is None


# --------------------------------------------------------------------------- other formats
def test_npz_round_trip(crease, tmp_path):
    vio.write_gbuffer(tmp_path / "f.npz", crease)
    depth, normal, _ = vio.read_buffers(tmp_path / "f.npz")
    np.testing.assert_array_equal(depth, crease.depth)
    np.testing.assert_array_equal(normal, crease.normal)


def test_exr_gbuffer_round_trip(crease, tmp_path):
    vio.write_gbuffer(tmp_path / "f.exr", crease, layer="Layer")
    depth, normal, found = vio.read_buffers(tmp_path / "f.exr")
    assert found["depth"].endswith("Layer.Depth.Z")
    np.testing.assert_array_equal(depth, crease.depth.astype(np.float32))  # +inf kept
    np.testing.assert_array_equal(normal, crease.normal.astype(np.float32))


def test_npz_round_trip_gives_the_same_estimate(crease, tmp_path):
    vio.write_gbuffer(tmp_path / "f.npz", crease)
    gb = vio.read_gbuffer(tmp_path / "f.npz", camera=crease.camera)
    np.testing.assert_allclose(_vo_line(gb), _vo_line(crease), atol=ROUND_TRIP_TOL)


def test_npy_depth_round_trip(tmp_path):
    d = np.random.default_rng(0).uniform(1, 2, (5, 7))
    d[0, 0] = np.inf
    np.save(tmp_path / "d.npy", d)
    depth, normal, _ = vio.read_buffers(tmp_path / "d.npy")
    np.testing.assert_array_equal(depth, d)
    assert normal is None


@pytest.mark.parametrize("channels", [1, 3])
def test_pfm_round_trip(tmp_path, channels):
    shape = (4, 5) if channels == 1 else (4, 5, 3)
    a = np.random.default_rng(1).normal(size=shape).astype(np.float32)
    vio.write_pfm(tmp_path / "a.pfm", a)
    np.testing.assert_array_equal(vio.read_pfm(tmp_path / "a.pfm"), a)


def test_pfm_reader_follows_the_format(tmp_path):
    """An independently written big-endian PFM: rows bottom to top, byte order by the scale's sign."""
    a = np.arange(6, dtype=np.float32).reshape(2, 3)
    (tmp_path / "be.pfm").write_bytes(b"Pf\n3 2\n1.0\n" + a[::-1].astype(">f4").tobytes())
    np.testing.assert_array_equal(vio.read_pfm(tmp_path / "be.pfm"), a)
    (tmp_path / "le.pfm").write_bytes(b"Pf 3 2 -1\n" + a[::-1].astype("<f4").tobytes())
    np.testing.assert_array_equal(vio.read_pfm(tmp_path / "le.pfm"), a)
    (tmp_path / "short.pfm").write_bytes(b"Pf\n3 2\n-1.0\n" + a.astype("<f4").tobytes()[:-4])
    with pytest.raises(ValueError, match="holds 24 bytes of pixels, found 20"):
        vio.read_pfm(tmp_path / "short.pfm")


def test_png16_depth_round_trip(tmp_path):
    raw = np.array([[0, 1000, 65535], [2500, 1, 40000]], dtype=np.uint16)
    Image.fromarray(raw).save(tmp_path / "d.png")
    assert _png_header(tmp_path / "d.png") == (16, GREY)
    depth, normal, _ = vio.read_buffers(tmp_path / "d.png", depth_scale=0.001)
    np.testing.assert_allclose(depth, np.where(raw == 0, np.inf, raw * 0.001))
    with pytest.raises(ValueError, match="give depth_scale"):
        vio.read_buffers(tmp_path / "d.png")


# --------------------------------------------------------------------------- errors
def test_missing_channel_lists_the_files_channels(tmp_path):
    d = np.ones((2, 2), np.float32)
    _write_exr(tmp_path / "f.exr", {"beauty.R": d, "beauty.G": d})
    with pytest.raises(ValueError, match=r"no depth channel .*the file has the channels beauty\.G, beauty\.R"):
        vio.read_buffers(tmp_path / "f.exr")
    _write_exr(tmp_path / "g.exr", {"Z": d, "beauty.R": d})
    with pytest.raises(ValueError, match=r"no normal channels 'Nrm'; the file has the channels Z, beauty\.R"):
        vio.read_buffers(tmp_path / "g.exr", normal_channels="Nrm")
    with pytest.raises(ValueError, match=r"no depth channel 'depth'.*Z, beauty\.R"):
        vio.read_buffers(tmp_path / "g.exr", depth_channel="depth")


def test_wrong_shapes_are_refused(tmp_path):
    np.save(tmp_path / "d3.npy", np.ones((2, 2, 2)))
    with pytest.raises(ValueError, match=r"must be an \(H, W\) image, got an array of shape \(2, 2, 2\)"):
        vio.read_buffers(tmp_path / "d3.npy")
    np.savez(tmp_path / "f.npz", depth=np.ones((2, 3)), normal=np.ones((2, 3, 2)))
    with pytest.raises(ValueError, match=r"\(H, W, 3\) image, got an array of shape \(2, 3, 2\)"):
        vio.read_buffers(tmp_path / "f.npz")
    np.savez(tmp_path / "g.npz", depth=np.ones((2, 3)), normal=np.ones((3, 2, 3)))
    with pytest.raises(ValueError, match="normals .* are 2x3 pixels but the depth .* is 3x2"):
        vio.read_buffers(tmp_path / "g.npz")
    np.savez(tmp_path / "h.npz", d=np.ones((2, 3)))
    with pytest.raises(ValueError, match=r"no array 'depth'; the archive has the arrays d"):
        vio.read_buffers(tmp_path / "h.npz")


def test_camera_size_must_match(tmp_path):
    np.save(tmp_path / "d.npy", np.ones((2, 3)))
    cam = vo.Camera.look_at((0, 0, 0), (0, 0, 1), size=(2, 3))
    with pytest.raises(ValueError, match="is 3x2 pixels but the camera's size is 2x3"):
        vio.read_gbuffer(tmp_path / "d.npy", camera=cam)


class _Boom:
    """Unpickling this would run code: the reader must refuse it before that."""

    def __reduce__(self):
        return (_explode, ())


def _explode():  # pragma: no cover - must never run
    raise AssertionError("a pickle was executed")


def test_a_pickle_inside_an_npz_is_refused(tmp_path):
    np.savez(tmp_path / "evil.npz", depth=np.ones((2, 2)), normal=np.array([_Boom()], dtype=object))
    with pytest.raises(ValueError, match="holds Python objects, which are refused"):
        vio.read_buffers(tmp_path / "evil.npz")
    np.save(tmp_path / "evil.npy", np.array([_Boom()], dtype=object), allow_pickle=True)
    with pytest.raises(ValueError, match="pickled objects are refused"):
        vio.read_buffers(tmp_path / "evil.npy")


def test_missing_files_and_unknown_formats(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        vio.read_buffers(tmp_path / "nope.exr")
    (tmp_path / "f.tiff").write_bytes(b"x")
    with pytest.raises(ValueError, match="unknown format '.tiff'"):
        vio.read_buffers(tmp_path / "f.tiff")
    (tmp_path / "bad.exr").write_bytes(b"not an exr")
    with pytest.raises(ValueError, match="not a readable EXR file"):
        vio.read_buffers(tmp_path / "bad.exr")
    np.save(tmp_path / "d.npy", np.ones((2, 2)))
    with pytest.raises(ValueError, match="holds only a depth"):
        vio.read_buffers(tmp_path / "d.npy", normal_channels="normal")


# --------------------------------------------------------------------------- writing
def test_write_image_exr_keeps_nan(tmp_path):
    v = np.array([[0.25, np.nan], [1.0, 0.0]])
    vio.write_image(tmp_path / "v.exr", v)
    vio.write_image(tmp_path / "w.exr", v, channel="V")
    np.testing.assert_array_equal(vio.exr_channels(tmp_path / "v.exr")["Y"], v.astype(np.float32))
    assert list(vio.exr_channels(tmp_path / "w.exr")) == ["V"]
    vio.write_image(tmp_path / "v.npy", v)
    np.testing.assert_array_equal(np.load(tmp_path / "v.npy"), v.astype(np.float32))
    vio.write_image(tmp_path / "v.pfm", v)
    np.testing.assert_array_equal(vio.read_pfm(tmp_path / "v.pfm"), v.astype(np.float32))


@pytest.mark.parametrize("bits", [8, 16])
def test_write_image_png_background_colour(tmp_path, bits):
    top = (1 << bits) - 1
    v = np.array([[0.0, 0.5], [np.nan, 1.0]])
    vio.write_image(tmp_path / "g.png", v, bits=bits, background=0.25)
    assert _png_header(tmp_path / "g.png") == (bits, GREY)
    grey = np.asarray(Image.open(tmp_path / "g.png"))
    assert grey.tolist() == [[0, round(0.5 * top)], [round(0.25 * top), top]]
    vio.write_image(tmp_path / "c.png", v, bits=8, background=(1.0, 0.0, 0.0))
    assert _png_header(tmp_path / "c.png") == (8, RGB)
    rgb = np.asarray(Image.open(tmp_path / "c.png"))
    assert rgb.shape == (2, 2, 3)
    assert rgb[1, 0].tolist() == [255, 0, 0] and rgb[0, 1].tolist() == [128, 128, 128]
    with pytest.raises(ValueError, match="16-bit PNG is grey"):
        vio.write_image(tmp_path / "c16.png", v, bits=16, background=(1.0, 0.0, 0.0))


def test_write_image_refuses_bad_input(tmp_path):
    with pytest.raises(ValueError, match=r"\(H, W\) image"):
        vio.write_image(tmp_path / "v.exr", np.ones(3))
    with pytest.raises(ValueError, match="unknown output format '.jpg'"):
        vio.write_image(tmp_path / "v.jpg", np.ones((2, 2)))
    with pytest.raises(ValueError, match="bits must be 8 or 16"):
        vio.write_image(tmp_path / "v.png", np.ones((2, 2)), bits=12)


@pytest.mark.parametrize("name", ["v.exr", "v.png", "v.npy", "v.pfm"])
def test_a_failed_write_leaves_the_old_file(tmp_path, monkeypatch, name):
    path = tmp_path / name
    vio.write_image(path, np.full((2, 2), 0.5))
    before = path.read_bytes()

    class Interrupted(Exception):
        pass

    real_fsync = vio.atomic_write.__globals__["os"].fsync

    def fail(fd):  # the bytes are written, the rename has not happened
        raise Interrupted

    monkeypatch.setattr(vio.atomic_write.__globals__["os"], "fsync", fail)
    with pytest.raises(Interrupted):
        vio.write_image(path, np.full((2, 2), 0.75))
    monkeypatch.setattr(vio.atomic_write.__globals__["os"], "fsync", real_fsync)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary left behind


# --------------------------------------------------------------------------- the docs
def test_docs_exr_section_runs(tmp_path, monkeypatch):
    """The example of docs/own-buffers.md, "EXR and files", runs as written."""
    text = (DOCS / "own-buffers.md").read_text()
    section = text.split("## EXR and files", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert blocks, "the EXR section lost its example"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__own_buffers__"}
    for block in blocks:
        exec(compile(block, str(DOCS / "own-buffers.md"), "exec"), namespace)
    assert (tmp_path / "vo.exr").is_file() and (tmp_path / "vo.png").is_file()
    assert np.nanmax(np.abs(namespace["v"] - namespace["v_original"])) <= ROUND_TRIP_TOL


# --------------------------------------------------------------------------- more layouts
def test_multipart_half_float_exr(tmp_path):
    """Channels of a named part are found as '<part>.<channel>'; half floats become float32."""
    d = np.full((2, 3), 3.0, np.float16)
    parts = [OpenEXR.Part({}, {"R": d}, "beauty"),
             OpenEXR.Part({}, {"Z": d, "N.X": d * 0, "N.Y": d * 0, "N.Z": -d / 3}, "geometry")]
    OpenEXR.File(parts).write(str(tmp_path / "m.exr"))
    assert "geometry.Z" in vio.exr_channels(tmp_path / "m.exr")
    depth, normal, found = vio.read_buffers(tmp_path / "m.exr", depth_channel="geometry.Z")
    assert depth.dtype == np.float32 and depth[0, 0] == 3.0
    assert normal[0, 0].tolist() == [0, 0, -1]


def test_png_normal_map_is_read_as_unit_encoding(tmp_path):
    np.save(tmp_path / "d.npy", np.ones((2, 2)))
    rgb = np.zeros((2, 2, 3), np.uint8)
    rgb[..., 2] = 255
    Image.fromarray(rgb).save(tmp_path / "n.png")
    _, normal, found = vio.read_buffers((tmp_path / "d.npy", tmp_path / "n.png"))
    assert found["normal_encoding"] == "unit" and normal[0, 0].tolist() == [0, 0, 1]


def test_png_16_bit_normal_map_is_read_at_8_bits(tmp_path):
    """A 16-bit RGB PNG, encoded here by hand (zlib, filter 0), reads as its samples' high bytes."""
    np.save(tmp_path / "d.npy", np.ones((1, 2)))
    samples = np.array([[[0x0000, 0x8000, 0xFFFF], [0x12FF, 0xAB00, 0x7FFF]]], dtype=">u2")
    rows = b"\0" + samples.tobytes()   # one row, filter type 0

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    (tmp_path / "n.png").write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 1, 16, RGB, 0, 0, 0))
                                     + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
    _, normal, _ = vio.read_buffers((tmp_path / "d.npy", tmp_path / "n.png"))
    np.testing.assert_array_equal(normal[0] * 255, [[0x00, 0x80, 0xFF], [0x12, 0xAB, 0x7F]])


# --------------------------------------------------------------------------- Blender 5's own files
# data/blender holds what Blender 5.0.1 wrote (make_frames.py, Cycles); blender_frames.py the
# same view rendered by vobscure and the tolerances, derived there.
@pytest.fixture(scope="module")
def blender_view():
    return vo.render_gbuffer(blender_frames.scene(), blender_frames.camera())


def _blender_paths(key, directory=blender_frames.DIR):
    depth_file, normal_file, *_ = blender_frames.FILES[key]
    return directory / depth_file, None if normal_file is None else directory / normal_file


def test_blender_files_record_their_version():
    rec = blender_frames.record()
    assert rec["blender"].startswith("5.") and rec["engine"] == "CYCLES"
    assert rec["size"] == [32, 24]


@pytest.mark.parametrize("key", list(blender_frames.FILES))
def test_blender_channels_are_found_by_default(key):
    depth_path, normal_path = _blender_paths(key)
    _, _, depth_name, normal_names, _ = blender_frames.FILES[key]
    depth, normal, found = vio.read_buffers(depth_path, normal_path=normal_path)
    assert found["depth_channel"] == depth_name and found["normal_channels"] == normal_names
    assert found["depth"] == f"{depth_path}:{depth_name}"
    assert depth.shape == (24, 32) and normal.shape == (24, 32, 3)


def _check_blender_depth(depth, gb, half):
    """Blender's depth is vobscure's linear depth within the derived tolerance on every
    covered pixel, and is not the distance to the eye on any of them (float32) / by far."""
    valid = gb.valid
    tol = blender_frames.depth_rtol(gb, half=half)[valid]
    rel_linear = np.abs(depth[valid] / gb.depth[valid] - 1)
    assert (rel_linear <= tol).all(), f"linear: worst {np.max(rel_linear / tol):.3g} x the tolerance"
    distance = np.linalg.norm(gb.world_position - gb.camera.eye, axis=-1)[valid]
    rel_distance = np.abs(depth[valid] / distance - 1)
    if not half:   # even the pixel next to the image centre is off by 1.9e-4 as a distance
        assert (rel_distance > tol).all()
    assert np.max(rel_distance / tol) > 100


@pytest.mark.parametrize("key", list(blender_frames.FILES))
def test_blender_depth_is_the_planar_view_z(key, blender_view):
    depth_path, normal_path = _blender_paths(key)
    half = key.startswith("half")
    depth, normal, _ = vio.read_buffers(depth_path, normal_path=normal_path)
    background = blender_frames.FILES[key][4]
    np.testing.assert_array_equal(depth >= background, ~blender_view.valid)
    np.testing.assert_array_equal(depth[~blender_view.valid], np.float32(background))
    _check_blender_depth(depth.astype(np.float64), blender_view, half)
    # world-space normals, zero on background
    np.testing.assert_allclose(normal[blender_view.valid], blender_view.world_normal[blender_view.valid],
                               rtol=0, atol=blender_frames.NORMAL_ATOL)
    assert not normal[~blender_view.valid].any()


def test_blender_wall_facing_the_camera_has_constant_depth(blender_view):
    """What docs/own-buffers.md tells users to check: on a wall facing the camera the view z is
    constant (the distance would grow towards the edges)."""
    depth, _, _ = vio.read_buffers(blender_frames.DIR / "render" / "frame.exr")
    scene = blender_frames.scene()
    wall = blender_view.valid & (blender_view.primitive >= 0)
    wall &= scene.mesh_index[np.maximum(blender_view.primitive, 0)] == list(scene.meshes).index("wall")
    wall &= np.isclose(blender_view.world_normal[..., 1], -1.0)
    assert wall.sum() > 100
    assert np.ptp(depth[wall]) <= 8.0 * blender_frames.DEPTH_RTOL_ROUNDING   # z = 8 on the wall


def test_blender_read_gbuffer_gives_vobscures_gbuffer(blender_view):
    pose = blender_frames.pose()
    cam = blender_frames.camera()
    gb = vio.read_gbuffer(blender_frames.DIR / "render" / "frame.exr", camera=cam, normal_space="world",
                          background=blender_frames.BACKGROUND)
    np.testing.assert_array_equal(gb.valid, blender_view.valid)
    assert gb.conversion["source"]["depth_channel"] == "ViewLayer.Depth.Z"
    assert gb.conversion["background"] == int((~blender_view.valid).sum())
    # view-space normals: the world normals rotated by the float32 pose, as vobscure's camera
    np.testing.assert_allclose(gb.normal[gb.valid], blender_view.normal[gb.valid], rtol=0, atol=1e-6)
    assert np.allclose(pose[:3, 2], -cam.forward)


def test_blender_multipart_channels_are_not_doubled():
    names = vio.exr_channels(blender_frames.DIR / "render" / "frame.exr")
    assert sorted(names) == sorted(f"ViewLayer.{p}.{c}" for p, cs in (("Combined", "RGBA"), ("Depth", "Z"),
                                                                      ("Normal", "XYZ")) for c in cs)


# --------------------------------------------------------------------------- bad Blender-like input
def test_a_truncated_exr_is_named(tmp_path):
    data = (blender_frames.DIR / "render" / "frame.exr").read_bytes()
    for cut in (len(data) // 2, 40):
        path = tmp_path / f"cut{cut}.exr"
        path.write_bytes(data[:cut])
        with pytest.raises(ValueError, match=rf"not a readable EXR file: {re.escape(str(path))} \("):
            vio.read_buffers(path)


def test_a_normal_file_given_as_depth_lists_its_channels():
    path = blender_frames.DIR / "single" / "frameNormal.exr"
    with pytest.raises(ValueError) as err:
        vio.read_buffers(path)
    message = str(err.value)
    assert message.startswith(f"{path}: no depth channel") and "the file has the channels A, X, Y, Z" in message
    assert "a normal file?" in message and "depth_channel=" in message


def test_missing_normals_list_the_channels(tmp_path):
    depth = blender_frames.DIR / "single" / "frameDepth.exr"
    with pytest.raises(ValueError) as err:
        vio.read_buffers(depth, normal_path=depth)     # the depth file again, as the normal file
    assert f"{depth}: no normal channels" in str(err.value) and "the file has the channels A, B, G, R" in str(err.value)


def test_ambiguous_choices_list_the_candidates(tmp_path):
    d = np.ones((2, 3), np.float32)
    _write_exr(tmp_path / "two.exr", {f"{lay}.{p}.{c}": d for lay in ("Left", "Right")
                                      for p, cs in (("Depth", "Z"), ("Normal", "XYZ")) for c in cs})
    with pytest.raises(ValueError, match=r"several depth channels \(Left.Depth.Z, Right.Depth.Z.*depth_channel="):
        vio.read_buffers(tmp_path / "two.exr")
    with pytest.raises(ValueError, match=r"several normal layers \(Left.Normal, Right.Normal.*normal_channels="):
        vio.read_buffers(tmp_path / "two.exr", depth_channel="Left.Depth.Z")
    _, normal, found = vio.read_buffers(tmp_path / "two.exr", depth_channel="Left.Depth.Z",
                                        normal_channels="Right.Normal")
    assert found["normal_channels"] == ("Right.Normal.X", "Right.Normal.Y", "Right.Normal.Z")
    # a colour image is not a grey depth
    _write_exr(tmp_path / "rgb.exr", {"R": d, "G": d, "B": 2 * d, "A": d})
    with pytest.raises(ValueError, match=r"R, G, B differ.*the file has the channels A, B, G, R"):
        vio.read_buffers(tmp_path / "rgb.exr")
    _write_exr(tmp_path / "v.exr", {"V": 3 * d})
    assert vio.read_buffers(tmp_path / "v.exr")[2]["depth_channel"] == "V"


# --------------------------------------------------------------------------- regenerated by Blender
@pytest.mark.slow
def test_blender_regenerates_the_same_frames(tmp_path, blender_view):
    """Runs data/blender/make_frames.py (needs bpy) and checks the new files as the committed ones."""
    pytest.importorskip("bpy")
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_frames", blender_frames.DIR / "make_frames.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rec = module.main(tmp_path)
    assert rec["files"] == blender_frames.record()["files"]
    for key in blender_frames.FILES:
        depth, normal, found = vio.read_buffers(*_blender_paths(key, tmp_path)[:1],
                                                normal_path=_blender_paths(key, tmp_path)[1])
        assert found["depth_channel"] == blender_frames.FILES[key][2]
        _check_blender_depth(depth.astype(np.float64), blender_view, key.startswith("half"))


def test_docs_depth_check_runs_on_blenders_file(tmp_path, monkeypatch, capsys):
    """The check of docs/own-buffers.md ("Check what your renderer's depth holds") on Blender's
    file prints what the docs say: one depth on the wall."""
    text = (DOCS / "own-buffers.md").read_text()
    section = text.split("**Check what your renderer's depth holds.**", 1)[1]
    block = re.search(r"```python\n(.*?)```", section, flags=re.S).group(1)
    (tmp_path / "frame.exr").write_bytes((blender_frames.DIR / "render" / "frame.exr").read_bytes())
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__own_buffers__"}
    exec(compile(block, str(DOCS / "own-buffers.md"), "exec"), namespace)
    assert "wall depth from 8 to 8\n" in capsys.readouterr().out
    assert namespace["wall"].size == 4 * 26 and np.ptp(namespace["wall"]) <= 8.0 * blender_frames.DEPTH_RTOL_ROUNDING
