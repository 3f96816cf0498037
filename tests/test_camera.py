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


# ---------------------------------------------------------------------------- intrinsics (issue 12)
def _gl_matrix(fx, fy, cx, cy, W, H, n, f):
    """glFrustum(l, r, b, t, n, f) for the frustum whose window is the image (column vectors)."""
    # pixel x = cx + fx X/Z reaches the image edges 0 and W at X/Z = -cx/fx, (W - cx)/fx
    l, r = -cx / fx * n, (W - cx) / fx * n
    b, t = -(H - cy) / fy * n, cy / fy * n        # rows down: y = H is the bottom
    return np.array([[2 * n / (r - l), 0, (r + l) / (r - l), 0],
                     [0, 2 * n / (t - b), (t + b) / (t - b), 0],
                     [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
                     [0, 0, -1, 0]])


def _dx_matrix(fx, fy, cx, cy, W, H, n, f):
    """D3DXMatrixPerspectiveOffCenterLH(l, r, b, t, n, f) (row vectors)."""
    l, r = -cx / fx * n, (W - cx) / fx * n
    b, t = -(H - cy) / fy * n, cy / fy * n
    return np.array([[2 * n / (r - l), 0, 0, 0],
                     [0, 2 * n / (t - b), 0, 0],
                     [(l + r) / (l - r), (t + b) / (b - t), f / (f - n), 1],
                     [0, 0, n * f / (n - f), 0]])


INTRINSICS = dict(fx=70.0, fy=35.0, cx=12.25, cy=40.5)


def _pose(cam):
    return cam.pose.copy()


def test_look_at_intrinsics_attributes():
    cam = Camera.look_at((1, 2, 3), (0, 0, 0), size=(64, 48), fov_y=50.0)
    f = 24 / math.tan(math.radians(25))
    assert cam.fx == cam.fy == pytest.approx(f, rel=RTOL) and (cam.cx, cam.cy) == (32.0, 24.0)
    assert cam.has_pose and cam.near is None and cam.far is None and cam.is_centered_square
    ortho = Camera.look_at((1, 2, 3), (0, 0, 0), size=(64, 48), ortho_height=4.0)
    assert ortho.fx == ortho.fy == 12.0 and (ortho.cx, ortho.cy) == (32.0, 24.0)
    # the pose is the view -> world matrix: columns right, up, forward, eye
    np.testing.assert_array_equal(cam.pose[:3, :3], cam.rotation.T)
    np.testing.assert_array_equal(cam.pose[:3, 3], cam.eye)
    np.testing.assert_array_equal(cam.pose[3], [0, 0, 0, 1])


@pytest.mark.parametrize("size", [(64, 48), (1, 1), (7, 300)])
def test_from_intrinsics_equals_look_at_bit_for_bit(size):
    """fx = fy = focal, (cx, cy) = (W/2, H/2) and the look_at pose: the same numbers exactly."""
    a = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), up=(0.1, 1.0, 0.3), size=size, fov_y=55.0)
    b = Camera.from_intrinsics(a.fx, a.fy, a.cx, a.cy, size, pose=a.pose)
    assert b != a and b.is_centered_square   # different records, the same projection
    pts = np.random.default_rng(0).normal(size=(40, 3)) * 3
    np.testing.assert_array_equal(a.world_to_view(pts), b.world_to_view(pts))
    for x, y in zip(a.project(pts), b.project(pts)):
        np.testing.assert_array_equal(x, y)
    px = np.random.default_rng(1).uniform(0, 64, size=(40, 2))
    np.testing.assert_array_equal(a.unproject(px, 2.5), b.unproject(px, 2.5))
    for dtype in (np.float32, np.float64):
        for x, y in zip(a.primary_rays(dtype=dtype), b.primary_rays(dtype=dtype)):
            np.testing.assert_array_equal(x, y)


def test_intrinsics_projection_formula():
    cam = Camera.from_intrinsics(size=(64, 48), **INTRINSICS)
    (x, y), z = cam.project([0.3, -0.2, 2.0])
    assert (x, y, z) == pytest.approx((12.25 + 70 * 0.15, 40.5 + 35 * 0.1, 2.0), rel=RTOL)
    np.testing.assert_allclose(cam.unproject([x, y], z), [0.3, -0.2, 2.0], rtol=RTOL)
    assert cam.pixels_per_unit(2.0) == pytest.approx(17.5, rel=RTOL)
    np.testing.assert_allclose(cam.pixels_per_unit_xy([2.0, 4.0]), [[35.0, 17.5], [17.5, 8.75]], rtol=RTOL)
    assert cam.pixels_per_unit_xy(2.0).shape == (2,)
    assert not cam.is_centered_square and cam.focal_length_px == 35.0 and cam.fov_y is None


@given(st.floats(1.0, 1e4), st.floats(1.0, 1e4), st.floats(-1e3, 1e3), st.floats(-1e3, 1e3),
       view_points_in_front)
@SETTINGS
def test_intrinsics_roundtrip(fx, fy, cx, cy, p):
    cam = Camera.from_intrinsics(fx, fy, cx, cy, (100, 80))
    pixels, depth = cam.project(p)
    np.testing.assert_allclose(cam.unproject(pixels, depth), p, rtol=RTOL_ROUNDTRIP, atol=1e-9 * max(1, abs(p[2])))


def test_intrinsics_primary_rays_pass_through_their_pixels():
    look = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(9, 5), fov_y=70.0)
    cam = Camera.from_intrinsics(size=(9, 5), pose=look.pose, **INTRINSICS)
    origins, directions = cam.primary_rays()
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0, atol=ATOL)
    for t in (0.3, 1.0, 10.0):
        pixels, depth = cam.project(cam.world_to_view(origins + t * directions))
        np.testing.assert_allclose(pixels, cam.pixel_centers(), rtol=0, atol=1e-7)
        assert np.all(depth > 0)


def test_no_pose_world_queries_raise_naming_the_pose():
    cam = Camera.from_intrinsics(size=(64, 48), **INTRINSICS)
    assert not cam.has_pose
    cam.project([0, 0, 1.0])
    cam.unproject([1.0, 2.0], 3.0)
    cam.pixels_per_unit(1.0)
    for call in (lambda: cam.eye, lambda: cam.target, lambda: cam.rotation, lambda: cam.forward,
                 lambda: cam.right, lambda: cam.up, lambda: cam.up_hint, lambda: cam.pose,
                 lambda: cam.world_to_view([0, 0, 0]), lambda: cam.view_to_world([0, 0, 1]),
                 lambda: cam.world_to_view_dir([0, 0, 1]), lambda: cam.view_to_world_dir([0, 0, 1]),
                 lambda: cam.primary_rays(), lambda: cam.pixel_rays([1.0, 1.0])):
        with pytest.raises(ValueError, match="pose"):
            call()


def test_bad_intrinsics():
    good = dict(size=(8, 6), **INTRINSICS)
    for key, value in (("fx", 0.0), ("fy", -1.0), ("fx", np.nan), ("cx", np.inf), ("cy", "a"),
                       ("size", (8, 0))):
        with pytest.raises(ValueError, match=key):
            Camera.from_intrinsics(**{**good, key: value})
    pose = np.diag([1.0, 1.0, -1.0, 1.0])
    Camera.from_intrinsics(**good, pose=pose)
    with pytest.raises(ValueError, match="determinant"):
        Camera.from_intrinsics(**good, pose=np.eye(4))     # right-handed: an OpenGL camera's
    with pytest.raises(ValueError, match="rotation"):
        Camera.from_intrinsics(**good, pose=np.diag([2.0, 1.0, -1.0, 1.0]))
    with pytest.raises(ValueError, match="last row"):
        Camera.from_intrinsics(**good, pose=pose + np.array([[0, 0, 0, 0]] * 3 + [[0, 0, 1, 0]]))
    with pytest.raises(ValueError, match="pose"):
        Camera.from_intrinsics(**good, pose=np.eye(3))


@pytest.mark.parametrize("far", [9.0, math.inf])
@pytest.mark.parametrize("convention", ["opengl", "directx"])
def test_from_projection_reads_known_intrinsics(convention, far):
    W, H, n = 64, 48, 0.25
    make = _gl_matrix if convention == "opengl" else _dx_matrix
    if math.isinf(far):
        P = make(W=W, H=H, n=n, f=1e300, **INTRINSICS)
        P[2, 2] = -1.0 if convention == "opengl" else 1.0      # the limit f -> inf
        P[(2, 3) if convention == "opengl" else (3, 2)] = -2 * n if convention == "opengl" else -n
    else:
        P = make(W=W, H=H, n=n, f=far, **INTRINSICS)
    cam = Camera.from_projection(P, (W, H), convention=convention)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == pytest.approx(tuple(INTRINSICS.values()), rel=RTOL)
    assert cam.near == pytest.approx(n, rel=RTOL) and cam.far == pytest.approx(far, rel=RTOL)
    # independently: clip coordinates -> NDC -> viewport (y up in NDC, rows down)
    p = np.array([0.3, -0.2, 2.0])
    if convention == "opengl":
        clip = P @ np.array([p[0], p[1], -p[2], 1.0])           # eye space looks down -z
        ndc_z_range = (-1, 1)
    else:
        clip = np.array([*p, 1.0]) @ P
        ndc_z_range = (0, 1)
    ndc = clip[:3] / clip[3]
    expected = ((ndc[0] + 1) * W / 2, (1 - ndc[1]) * H / 2)
    np.testing.assert_allclose(cam.project(p)[0], expected, rtol=RTOL)
    # depth at the near plane maps to the near end of NDC z
    if not math.isinf(far):
        for depth, nz in ((n, ndc_z_range[0]), (far, ndc_z_range[1])):
            q = np.array([0.0, 0.0, depth])
            c = P @ [0, 0, -depth, 1.0] if convention == "opengl" else np.array([*q, 1.0]) @ P
            assert c[2] / c[3] == pytest.approx(nz, abs=1e-9)


def test_from_projection_rejects_other_layouts():
    P = _gl_matrix(W=64, H=48, n=0.25, f=9.0, **INTRINSICS)
    with pytest.raises(ValueError, match="opengl"):
        Camera.from_projection(P.T, (64, 48))                     # column-major memory read as rows
    with pytest.raises(ValueError, match="directx"):
        Camera.from_projection(P, (64, 48), convention="directx")
    skew = P.copy()
    skew[0, 1] = 0.3
    with pytest.raises(ValueError, match="skew"):
        Camera.from_projection(skew, (64, 48))
    ortho = np.diag([1.0, 1.0, -0.2, 1.0])
    with pytest.raises(ValueError, match="orthographic"):
        Camera.from_projection(ortho, (64, 48))
    with pytest.raises(ValueError, match="convention"):
        Camera.from_projection(P, (64, 48), convention="vulkan")
    flipped = P.copy()
    flipped[1, 1] *= -1
    with pytest.raises(ValueError, match=r"P\[1, 1\]"):
        Camera.from_projection(flipped, (64, 48))


@pytest.mark.parametrize("with_pose", [False, True])
def test_intrinsics_records_roundtrip(with_pose):
    look = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(9, 5), fov_y=70.0)
    cam = Camera.from_intrinsics(size=(9, 5), pose=look.pose if with_pose else None, near=0.1, far=math.inf,
                                 **INTRINSICS)
    d = json.loads(json.dumps(cam.to_dict()))
    back = Camera.from_dict(d)
    assert back == cam and hash(back) == hash(cam) and back.to_dict() == cam.to_dict()
    assert pickle.loads(pickle.dumps(cam)) == cam
    assert eval(repr(cam), {"Camera": Camera}) == cam
    assert cam != Camera.from_intrinsics(size=(9, 5), **{**INTRINSICS, "cx": 12.0})
    assert len({cam, back, look}) == 2
    with pytest.raises(ValueError, match="unknown"):
        Camera.from_dict({**d, "fov_y": 40.0})
    with pytest.raises(ValueError, match="projection"):
        Camera.from_dict({**d, "projection": "orthographic"})
    with pytest.raises(ValueError, match="'cy'"):
        Camera.from_dict({k: v for k, v in d.items() if k != "cy"})


def test_look_at_record_unchanged():
    """The cache keys cameras by to_dict(): a look_at record keeps exactly its old keys."""
    cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(4, 3))
    assert list(cam.to_dict()) == ["eye", "target", "up", "size", "fov_y", "ortho_height", "projection"]


def test_cropped_and_derived_cameras():
    look = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(40, 30), fov_y=60.0)
    crop = look.cropped(7, 3, (11, 13))
    o1, d1 = look.primary_rays()
    o2, d2 = crop.primary_rays()
    np.testing.assert_allclose(d2, d1[3:16, 7:18], atol=1e-12)
    with pytest.raises(ValueError, match="perspective"):
        Camera.look_at((0, 0, 5), (0, 0, 0), size=(4, 3), ortho_height=1.0).cropped(0, 0, (2, 2))
    with pytest.raises(ValueError, match="left"):
        look.cropped(1.5, 0, (2, 2))
    cam = Camera.from_intrinsics(size=(64, 48), pose=look.pose, near=0.5, **INTRINSICS)
    big = cam.with_size((128, 24))
    assert (big.fx, big.fy, big.cx, big.cy) == (140.0, 17.5, 24.5, 20.25)
    s = cam.scaled(2.0)
    np.testing.assert_array_equal(s.eye, 2 * cam.eye)
    assert s.near == 1.0 and s.fx == cam.fx
