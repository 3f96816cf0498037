"""Tests of vobscure.camera: conventions, round trips, rays, validation, provenance."""

from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from vobscure.camera import Camera

# Absolute tolerance for exactly representable / well-conditioned values.
ATOL = 1e-9
# Relative tolerance for round trips of random data (errors grow with magnitude).
RTOL = 1e-9
# Looser relative tolerance for round trips through extreme fields of view (1 to 170 deg).
RTOL_ROUNDTRIP = 1e-7

SETTINGS = settings(max_examples=60, deadline=None)

coord = st.floats(-100.0, 100.0, allow_nan=False, allow_infinity=False)
vec3 = st.tuples(coord, coord, coord)
sizes = st.tuples(st.integers(1, 4096), st.integers(1, 4096))
fovs = st.floats(1.0, 170.0)
ortho_heights = st.floats(1e-2, 1e3)


@st.composite
def cameras(draw, projection=None):
    eye = np.array(draw(vec3))
    target = np.array(draw(vec3))
    up = np.array(draw(vec3))
    d = target - eye
    assume(np.linalg.norm(d) > 1e-2)
    assume(np.linalg.norm(up) > 1e-2)
    cos = abs(d @ up) / (np.linalg.norm(d) * np.linalg.norm(up))
    assume(cos < 0.999)
    size = draw(sizes)
    kind = projection or draw(st.sampled_from(["perspective", "orthographic"]))
    if kind == "perspective":
        return Camera.look_at(eye, target, up, size=size, fov_y=draw(fovs))
    return Camera.look_at(eye, target, up, size=size, ortho_height=draw(ortho_heights))


view_points_in_front = st.tuples(
    st.floats(-50.0, 50.0), st.floats(-50.0, 50.0), st.floats(1e-2, 1e3)
)


def _front_camera(projection="perspective", size=(64, 48)):
    if projection == "perspective":
        return Camera.look_at((0, 0, 5), (0, 0, 0), size=size, fov_y=60.0)
    return Camera.look_at((0, 0, 5), (0, 0, 0), size=size, ortho_height=3.0)


# ---------------------------------------------------------------------------- properties
@SETTINGS
@given(cam=cameras(), pts=st.lists(view_points_in_front, min_size=1, max_size=8))
def test_project_unproject_roundtrip(cam, pts):
    p = np.array(pts)
    pixels, depth = cam.project(p)
    assert pixels.shape == (len(pts), 2) and depth.shape == (len(pts),)
    np.testing.assert_array_equal(depth, p[:, 2])
    back = cam.unproject(pixels, depth)
    scale = np.maximum(1.0, np.linalg.norm(p, axis=-1, keepdims=True))
    assert np.all(np.abs(back - p) <= RTOL_ROUNDTRIP * scale)


@SETTINGS
@given(cam=cameras(), x=st.floats(-10.0, 5000.0), y=st.floats(-10.0, 5000.0),
       z=st.floats(1e-2, 1e3))
def test_unproject_project_roundtrip(cam, x, y, z):
    pixels, depth = cam.project(cam.unproject([x, y], z))
    assert depth == pytest.approx(z, rel=RTOL)
    assert np.all(np.abs(pixels - [x, y]) <= RTOL_ROUNDTRIP * max(1.0, abs(x), abs(y)))


@SETTINGS
@given(cam=cameras(), pts=st.lists(vec3, min_size=1, max_size=8))
def test_world_view_roundtrip(cam, pts):
    p = np.array(pts)
    v = cam.world_to_view(p)
    back = cam.view_to_world(v)
    scale = max(1.0, float(np.abs(p).max()), float(np.abs(cam.eye).max()))
    np.testing.assert_allclose(back, p, rtol=0, atol=RTOL * scale)
    # directions: rotation only, lengths kept
    d = cam.world_to_view_dir(p)
    np.testing.assert_allclose(cam.view_to_world_dir(d), p, rtol=0, atol=RTOL * scale)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), np.linalg.norm(p, axis=-1),
                               rtol=0, atol=RTOL * scale)
    # the affine map is the rotation of the offset from the eye
    np.testing.assert_allclose(v, cam.world_to_view_dir(p - cam.eye), rtol=0, atol=RTOL * scale)


@SETTINGS
@given(cam=cameras())
def test_rotation_orthogonal_det_minus_one(cam):
    R = cam.rotation
    np.testing.assert_allclose(R @ R.T, np.eye(3), rtol=0, atol=ATOL)
    assert np.linalg.det(R) == pytest.approx(-1.0, abs=ATOL)
    np.testing.assert_array_equal(R, np.stack([cam.right, cam.up, cam.forward]))
    d = cam.target - cam.eye
    np.testing.assert_allclose(cam.forward, d / np.linalg.norm(d), rtol=0, atol=ATOL)
    # right is perpendicular to the up hint, true up lies on the hint's side
    assert abs(cam.right @ cam.up_hint) <= ATOL * np.linalg.norm(cam.up_hint)
    assert cam.up @ cam.up_hint > 0
    np.testing.assert_allclose(np.cross(cam.right, cam.forward), cam.up, rtol=0, atol=ATOL)
    # the target is straight ahead in view space
    np.testing.assert_allclose(cam.world_to_view(cam.target), [0, 0, np.linalg.norm(d)],
                               rtol=0, atol=RTOL * max(1.0, np.abs(cam.eye).max(), np.abs(cam.target).max()))


# ---------------------------------------------------------------------------- known cases
@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_camera_on_z_axis(projection):
    W, H = 64, 48
    cam = _front_camera(projection, size=(W, H))
    pixels, depth = cam.project(cam.world_to_view([[0, 0, 0], [0, 1, 0], [1, 0, 0]]))
    np.testing.assert_allclose(pixels[0], [W / 2, H / 2], rtol=0, atol=ATOL)
    assert depth[0] == pytest.approx(5.0, abs=ATOL)
    # world +y is up in the image (smaller row coordinate), same column
    assert pixels[1, 1] < H / 2
    assert pixels[1, 0] == pytest.approx(W / 2, abs=ATOL)
    # world +x is right in the image, same row
    assert pixels[2, 0] > W / 2
    assert pixels[2, 1] == pytest.approx(H / 2, abs=ATOL)
    # exact pixel offsets of a unit length at depth 5
    s = H / 2 / math.tan(math.radians(30)) / 5 if projection == "perspective" else H / 3.0
    assert H / 2 - pixels[1, 1] == pytest.approx(s, rel=RTOL)
    assert pixels[2, 0] - W / 2 == pytest.approx(s, rel=RTOL)
    np.testing.assert_allclose(cam.forward, [0, 0, -1], atol=ATOL)
    np.testing.assert_allclose(cam.right, [1, 0, 0], atol=ATOL)
    np.testing.assert_allclose(cam.up, [0, 1, 0], atol=ATOL)


def test_normal_facing_camera_has_negative_z():
    cam = _front_camera()
    n = cam.world_to_view_dir([0, 0, 1])  # the xy plane's normal towards the eye
    np.testing.assert_allclose(n, [0, 0, -1], atol=ATOL)


def test_attributes():
    cam = Camera.look_at([1, 2, 3], np.array([1, 2, 0]), up=(0, 2, 0), size=(np.int64(40), 30))
    assert cam.projection == "perspective" and cam.is_perspective
    assert cam.fov_y == 45.0 and cam.ortho_height is None
    assert cam.size == (40, 30) and type(cam.size[0]) is int
    assert (cam.width, cam.height, cam.shape) == (40, 30, (30, 40))
    assert cam.focal_length_px == pytest.approx(15 / math.tan(math.radians(22.5)), rel=RTOL)
    assert cam.eye.dtype == np.float64 and cam.eye.shape == (3,)
    np.testing.assert_array_equal(cam.up_hint, [0, 2, 0])
    ortho = Camera.look_at((0, 0, 1), (0, 0, 0), size=(4, 4), ortho_height=2)
    assert ortho.projection == "orthographic" and not ortho.is_perspective
    assert ortho.fov_y is None and ortho.ortho_height == 2.0 and ortho.focal_length_px is None


def test_immutable():
    cam = _front_camera()
    with pytest.raises(AttributeError):
        cam.eye = np.zeros(3)
    with pytest.raises(AttributeError):
        cam.fov_y = 10.0
    with pytest.raises(ValueError):
        cam.eye[0] = 1.0  # read-only array
    with pytest.raises(ValueError):
        cam.rotation[0, 0] = 1.0


def test_broadcasting_shapes():
    cam = _front_camera()
    rng = np.random.default_rng(0)
    p = rng.uniform(-1, 1, (2, 3, 4, 3)) + [0, 0, 3]
    pixels, depth = cam.project(p)
    assert pixels.shape == (2, 3, 4, 2) and depth.shape == (2, 3, 4)
    assert cam.world_to_view(p).shape == (2, 3, 4, 3)
    assert cam.unproject(pixels, depth).shape == (2, 3, 4, 3)
    # one depth for many pixels, and one pixel for many depths
    assert cam.unproject(pixels, 2.0).shape == (2, 3, 4, 3)
    back = cam.unproject([10.0, 20.0], [1.0, 2.0, 3.0])
    assert back.shape == (3, 3)
    np.testing.assert_allclose(back[:, 2], [1, 2, 3], atol=ATOL)
    # a single point gives a (2,) pixel and a scalar depth
    px, d = cam.project([0.0, 0.0, 2.0])
    assert px.shape == (2,) and np.ndim(d) == 0 and d == 2.0
    assert np.ndim(cam.pixels_per_unit(2.0)) == 0
    assert cam.pixels_per_unit(np.ones((3, 2))).shape == (3, 2)
    assert _front_camera("orthographic").pixels_per_unit(np.ones((3, 2))).shape == (3, 2)


def test_points_behind_perspective_camera_are_nan():
    cam = _front_camera()
    pixels, depth = cam.project([[0, 0, 0.0], [1, 1, -2.0], [1, 1, 2.0]])
    assert np.all(np.isnan(pixels[:2])) and np.all(np.isfinite(pixels[2]))
    np.testing.assert_array_equal(depth, [0, -2, 2])
    ppu = cam.pixels_per_unit([-1.0, 0.0, np.inf])
    assert np.isnan(ppu[0]) and np.isnan(ppu[1]) and ppu[2] == 0.0
    # orthographic cameras see behind the eye plane as well
    ortho_px, _ = _front_camera("orthographic").project([1, 1, -2.0])
    assert np.all(np.isfinite(ortho_px))


def test_background_depth_propagates_without_warning():
    cam = _front_camera()
    pts = cam.unproject(cam.pixel_centers(), np.full(cam.shape, np.inf))
    assert pts.shape == cam.shape + (3,)
    assert np.all(pts[..., 2] == np.inf)


# ---------------------------------------------------------------------------- pixels and rays
def test_pixel_centers():
    cam = _front_camera(size=(5, 3))
    c = cam.pixel_centers()
    assert c.shape == (3, 5, 2)
    np.testing.assert_array_equal(c[0, 0], [0.5, 0.5])
    np.testing.assert_array_equal(c[2, 4], [4.5, 2.5])
    np.testing.assert_array_equal(c[1, 3], [3.5, 1.5])


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_primary_rays_pass_through_their_pixels(projection):
    cam = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), up=(0.1, 1.0, 0.3), size=(7, 5),
                         **({"fov_y": 70.0} if projection == "perspective" else {"ortho_height": 2.5}))
    origins, directions = cam.primary_rays()
    assert origins.shape == directions.shape == (5, 7, 3)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0, rtol=0, atol=ATOL)
    centers = cam.pixel_centers()
    for t in (0.3, 1.0, 10.0):
        pixels, depth = cam.project(cam.world_to_view(origins + t * directions))
        np.testing.assert_allclose(pixels, centers, rtol=0, atol=ATOL)
        assert np.all(depth > 0)
    if projection == "perspective":
        np.testing.assert_allclose(origins, np.broadcast_to(cam.eye, origins.shape), atol=ATOL)
    else:
        np.testing.assert_allclose(directions, np.broadcast_to(cam.forward, directions.shape),
                                   atol=ATOL)
        np.testing.assert_allclose((origins - cam.eye) @ cam.forward, 0.0, atol=ATOL)
        # the eye plane spans ortho_height vertically, ortho_height * W / H horizontally
        off = origins - cam.eye
        span_x = (off[0, -1] - off[0, 0]) @ cam.right
        span_y = (off[0, 0] - off[-1, 0]) @ cam.up
        assert span_x == pytest.approx(2.5 * 6 / 5, rel=RTOL)
        assert span_y == pytest.approx(2.5 * 4 / 5, rel=RTOL)


def test_top_pixel_row_looks_up():
    cam = Camera.look_at((0.3, 1.0, 4.0), (0.0, 0.5, 0.0), size=(9, 6), fov_y=50.0)
    _, directions = cam.primary_rays()
    assert directions[0, 9 // 2] @ cam.up > 0
    assert directions[-1, 9 // 2] @ cam.up < 0
    assert directions[3, -1] @ cam.right > 0


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
@pytest.mark.parametrize("z", [0.5, 5.0, 40.0])
@pytest.mark.parametrize("angle", [0.0, 0.7, 2.0])
def test_pixels_per_unit(projection, z, angle):
    cam = Camera.look_at((2.0, 1.0, 3.0), (0.0, 0.0, 0.0), size=(80, 60),
                         **({"fov_y": 40.0} if projection == "perspective" else {"ortho_height": 4.0}))
    L = 0.37
    a = cam.eye + z * cam.forward + 0.2 * cam.right - 0.1 * cam.up  # a world point at depth z
    b = a + L * (math.cos(angle) * cam.right + math.sin(angle) * cam.up)
    (pa, pb), depth = cam.project(cam.world_to_view([a, b]))
    np.testing.assert_allclose(depth, [z, z], rtol=RTOL)
    assert np.linalg.norm(pb - pa) == pytest.approx(L * cam.pixels_per_unit(z), rel=RTOL)
    expected = (30 / math.tan(math.radians(20)) / z) if projection == "perspective" else 60 / 4.0
    assert cam.pixels_per_unit(z) == pytest.approx(expected, rel=RTOL)


# ---------------------------------------------------------------------------- validation
GOOD = {"eye": (0, 0, 5), "target": (0, 0, 0), "up": (0, 1, 0), "size": (8, 6)}


@pytest.mark.parametrize(
    ("changes", "name"),
    [
        ({"eye": (0, 0)}, "eye"),
        ({"eye": (0, 0, np.nan)}, "eye"),
        ({"eye": (0, np.inf, 1)}, "eye"),
        ({"eye": "abc"}, "eye"),
        ({"target": (0, 0, 0, 0)}, "target"),
        ({"target": (np.nan, 0, 0)}, "target"),
        ({"up": (0, 1)}, "up"),
        ({"up": (0, np.nan, 0)}, "up"),
        ({"up": (0, 0, 0)}, "up"),
        ({"up": (0, 0, 1)}, "up"),  # parallel to the view direction
        ({"up": (0, 0, -3)}, "up"),  # anti-parallel
        ({"up": (1e-8, 0, 1)}, "up"),  # nearly parallel
        ({"eye": (0, 0, 0)}, "eye"),  # eye == target
        ({"eye": (1e6, 0, 0), "target": (1e6 + 1e-7, 0, 0)}, "eye"),  # too close for their size
        ({"size": (8,)}, "size"),
        ({"size": (8, 6, 1)}, "size"),
        ({"size": (8, 0)}, "size"),
        ({"size": (-8, 6)}, "size"),
        ({"size": (8.0, 6)}, "size"),
        ({"size": (2.5, 6)}, "size"),
        ({"size": (True, 6)}, "size"),
        ({"size": 8}, "size"),
        ({"size": "86"}, "size"),
        ({"size": None}, "size"),
        ({"size": np.ones((2, 2), dtype=int)}, "size"),
        ({"fov_y": 0.0}, "fov_y"),
        ({"fov_y": -10.0}, "fov_y"),
        ({"fov_y": 180.0}, "fov_y"),
        ({"fov_y": 200.0}, "fov_y"),
        ({"fov_y": np.nan}, "fov_y"),
        ({"fov_y": np.inf}, "fov_y"),
        ({"fov_y": "45"}, "fov_y"),
        ({"fov_y": True}, "fov_y"),
        ({"ortho_height": 0.0}, "ortho_height"),
        ({"ortho_height": -1.0}, "ortho_height"),
        ({"ortho_height": np.inf}, "ortho_height"),
        ({"ortho_height": np.nan}, "ortho_height"),
        ({"fov_y": 45.0, "ortho_height": 2.0}, "fov_y"),
        ({"fov_y": 45.0, "ortho_height": 2.0}, "ortho_height"),
    ],
)
def test_bad_arguments(changes, name):
    kwargs = {**GOOD, **changes}
    eye, target, up = kwargs.pop("eye"), kwargs.pop("target"), kwargs.pop("up")
    with pytest.raises(ValueError, match=name):
        Camera.look_at(eye, target, up, **kwargs)


@pytest.mark.parametrize("size", [(8, 6), [8, 6], (np.int32(8), np.uint16(6)), np.array([8, 6])])
def test_good_sizes(size):
    assert Camera.look_at((0, 0, 1), (0, 0, 0), size=size).size == (8, 6)


def test_bad_method_arguments():
    cam = _front_camera()
    with pytest.raises(ValueError, match="points"):
        cam.world_to_view(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="points"):
        cam.view_to_world([1.0, 2.0])
    with pytest.raises(ValueError, match="vectors"):
        cam.world_to_view_dir(np.zeros(4))
    with pytest.raises(ValueError, match="vectors"):
        cam.view_to_world_dir("x")
    with pytest.raises(ValueError, match="view_points"):
        cam.project(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="pixels"):
        cam.unproject(np.zeros((3, 3)), 1.0)
    with pytest.raises(ValueError, match="depth"):
        cam.unproject(np.zeros((3, 2)), np.ones(4))
    with pytest.raises(ValueError, match="depth"):
        cam.pixels_per_unit("far")
    with pytest.raises(ValueError, match="factor"):
        cam.scaled(0.0)
    with pytest.raises(ValueError, match="factor"):
        cam.scaled(np.nan)
    with pytest.raises(ValueError, match="d "):
        Camera.from_dict([1, 2])
    with pytest.raises(ValueError, match="eye"):
        Camera.from_dict({"target": [0, 0, 0], "size": [4, 4]})
    with pytest.raises(ValueError, match="unknown"):
        Camera.from_dict({**cam.to_dict(), "fovy": 3})
    with pytest.raises(ValueError, match="projection"):
        Camera.from_dict({**cam.to_dict(), "projection": "fisheye"})
    with pytest.raises(ValueError, match="projection"):
        Camera.from_dict({**cam.to_dict(), "projection": "orthographic"})


# ---------------------------------------------------------------------------- provenance
@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_to_dict_from_dict_roundtrip(projection):
    cam = Camera.look_at((0.1, 0.2, 3.3), (1 / 3, 0, -1), up=(0, 3, 0.5), size=(17, 9),
                         **({"fov_y": 33.3} if projection == "perspective" else {"ortho_height": 0.7}))
    d = json.loads(json.dumps(cam.to_dict()))
    assert d["projection"] == projection
    assert d["up"] == [0.0, 3.0, 0.5] and d["size"] == [17, 9]
    back = Camera.from_dict(d)
    assert back == cam and hash(back) == hash(cam)
    np.testing.assert_array_equal(back.rotation, cam.rotation)
    np.testing.assert_array_equal(back.eye, cam.eye)
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert eval(repr(cam), {"Camera": Camera}) == cam
    assert back != Camera.from_dict({**d, "size": [17, 10]})


@pytest.mark.parametrize("projection", ["perspective", "orthographic"])
def test_scaled(projection):
    cam = Camera.look_at((0.5, 1.0, 3.0), (0.0, 0.2, 0.0), size=(16, 12),
                         **({"fov_y": 55.0} if projection == "perspective" else {"ortho_height": 1.5}))
    k = 7.5
    big = cam.scaled(k)
    np.testing.assert_allclose(big.eye, k * cam.eye, rtol=RTOL)
    np.testing.assert_allclose(big.target, k * cam.target, rtol=RTOL)
    np.testing.assert_allclose(big.rotation, cam.rotation, atol=ATOL)
    assert big.size == cam.size and big.fov_y == cam.fov_y
    if projection == "orthographic":
        assert big.ortho_height == pytest.approx(k * 1.5, rel=RTOL)
    # a scaled scene looks the same through the scaled camera, at scaled depth
    pts = np.array([[0.1, 0.0, 0.2], [-0.3, 0.4, 0.5], [0.0, 0.0, 0.0]])
    px, depth = cam.project(cam.world_to_view(pts))
    px_big, depth_big = big.project(big.world_to_view(k * pts))
    np.testing.assert_allclose(px_big, px, rtol=0, atol=ATOL)
    np.testing.assert_allclose(depth_big, k * depth, rtol=RTOL)
    # a world length scaled by k spans the same pixels at the scaled depth
    assert k * big.pixels_per_unit(k * 2.0) == pytest.approx(cam.pixels_per_unit(2.0), rel=RTOL)
    back = big.scaled(1 / k)
    np.testing.assert_allclose(back.eye, cam.eye, rtol=RTOL)
    assert cam.with_size((4, 3)).size == (4, 3)
