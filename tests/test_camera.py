"""Tests of vobscure.camera: conventions, round trips, rays, validation, provenance; the
projection kernel against 4x4 matrices applied by hand; and general pinhole cameras in the
screen-space estimators.

The estimators honour a principal point anywhere and non-square pixels (fx != fy):

(a) A camera from intrinsics equal to a look_at camera gives bit-identical estimates.
(b) Crop invariance: a crop of a G-buffer, with the principal point shifted by the crop's
    offset, gives the full frame's values on the crop's interior.
(c) Anisotropic pixels: the same view rendered with fx = 2 fy (twice as wide) reads the same
    VO as the square-pixel image at the pixels that share its view rays.
(d) Planes read exactly 1/2 (1 clamped) under an off-centre principal point and fx != fy.
"""

from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.ndimage import distance_transform_edt

import vobscure as vo
import vobscure.screenspace.area as area_module
from vobscure.camera import (Camera, Intrinsics, Orthographic, Perspective, Pose, Projection, project_xy,
                             ray_to_xy, ray_xy, shift_ray, unproject_xy)
from vobscure.gbuffer import GBuffer
from vobscure.screenspace.area import region_areas
from vobscure.screenspace.blur import bilateral_blur

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


# ---------------------------------------------------------------------------- intrinsics
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


# ---------------------------------------------------------------------------- the kernel and the parts
def _gl_ortho(W, H, ortho_height, n, f):
    """glOrtho(l, r, b, t, n, f) for a centred view ``ortho_height`` high (column vectors)."""
    t = ortho_height / 2
    r = t * W / H
    l, b = -r, -t
    return np.array([[2 / (r - l), 0, 0, -(r + l) / (r - l)],
                     [0, 2 / (t - b), 0, -(t + b) / (t - b)],
                     [0, 0, -2 / (f - n), -(f + n) / (f - n)],
                     [0, 0, 0, 1.0]])


def _by_hand(P, W, H, view_points):
    """Pixels of view-space points through the OpenGL matrix P: clip = P (X, Y, -Z, 1) (eye space
    looks down -z), NDC = clip / w, then the viewport (y up in NDC, rows down)."""
    v = np.asarray(view_points, dtype=np.float64)
    eye = np.stack([v[:, 0], v[:, 1], -v[:, 2], np.ones(len(v))])
    clip = P @ eye
    ndc = clip[:3] / clip[3]
    return np.stack([(ndc[0] + 1) * W / 2, (1 - ndc[1]) * H / 2], axis=-1)


def _unproject_by_hand(P, W, H, pixels, depth):
    """View-space points at the pixels and depths, by inverting P: NDC from the pixel, the
    clip z and w of eye z = -depth from P's last two rows, then P^-1."""
    pixels = np.asarray(pixels, dtype=np.float64)
    ndc_x, ndc_y = pixels[:, 0] * 2 / W - 1, 1 - pixels[:, 1] * 2 / H
    z_eye = -np.asarray(depth, dtype=np.float64)
    w = P[3, 2] * z_eye + P[3, 3]
    clip_z = P[2, 2] * z_eye + P[2, 3]
    eye = np.linalg.inv(P) @ np.stack([ndc_x * w, ndc_y * w, clip_z, w])
    return np.stack([eye[0], eye[1], -eye[2]], axis=-1)


#: Agreement of the kernel with the 4x4 matrices applied by hand (a few float64 roundings of
#: different operations, on pixel coordinates up to ~1e2 and a matrix inverse).
HAND_RTOL = 1e-10

_W, _H = 64, 48
_KINDS = {
    "perspective": (lambda: Camera.look_at((0, 0, 5), (0, 0, 0), size=(_W, _H), fov_y=60.0),
                    lambda c: _gl_matrix(c.fx, c.fy, c.cx, c.cy, _W, _H, 0.1, 50.0)),
    "orthographic": (lambda: Camera.look_at((0, 0, 5), (0, 0, 0), size=(_W, _H), ortho_height=3.0),
                     lambda c: _gl_ortho(_W, _H, 3.0, 0.1, 50.0)),
    "intrinsics": (lambda: Camera.from_intrinsics(size=(_W, _H), **INTRINSICS),
                   lambda c: _gl_matrix(W=_W, H=_H, n=0.1, f=50.0, **INTRINSICS)),
    "from_projection": (lambda: Camera.from_projection(_gl_matrix(W=_W, H=_H, n=0.1, f=50.0, **INTRINSICS), (_W, _H)),
                        lambda c: _gl_matrix(W=_W, H=_H, n=0.1, f=50.0, **INTRINSICS)),
}


@pytest.mark.parametrize("kind", _KINDS)
def test_kernel_and_camera_agree_with_the_matrix_by_hand(kind):
    make_camera, make_matrix = _KINDS[kind]
    cam = make_camera()
    P = make_matrix(cam)
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-1, 1, 50), rng.uniform(-1, 1, 50), rng.uniform(0.5, 20, 50)])
    expected = _by_hand(P, _W, _H, pts)
    # the kernel
    x, y = project_xy(pts[:, 0], pts[:, 1], pts[:, 2], cam.fx, cam.fy, cam.cx, cam.cy, cam.is_perspective)
    np.testing.assert_allclose(np.stack([x, y], -1), expected, rtol=HAND_RTOL)
    # the camera and its lens
    pixels, depth = cam.project(pts)
    np.testing.assert_allclose(pixels, expected, rtol=HAND_RTOL)
    np.testing.assert_array_equal(cam.lens.project(pts)[0], pixels)
    np.testing.assert_array_equal(depth, pts[:, 2])
    # the inverse: unproject_xy, the ray form, and Camera.unproject, against P^-1
    back = _unproject_by_hand(P, _W, _H, expected, pts[:, 2])
    np.testing.assert_allclose(back, pts, rtol=HAND_RTOL, atol=1e-12)
    X, Y = unproject_xy(x, y, pts[:, 2], cam.fx, cam.fy, cam.cx, cam.cy, cam.is_perspective)
    np.testing.assert_allclose(np.stack([X, Y], -1), back[:, :2], rtol=HAND_RTOL, atol=1e-12)
    X, Y = ray_to_xy(*ray_xy(x, y, cam.fx, cam.fy, cam.cx, cam.cy), pts[:, 2], cam.is_perspective)
    np.testing.assert_allclose(np.stack([X, Y], -1), back[:, :2], rtol=HAND_RTOL, atol=1e-12)
    np.testing.assert_allclose(cam.unproject(pixels, depth), back, rtol=HAND_RTOL, atol=1e-12)


def test_ray_kernel_in_place_and_shifted():
    cam = Camera.from_intrinsics(size=(_W, _H), **INTRINSICS)
    fx, fy, cx, cy = cam.fx, cam.fy, cam.cx, cam.cy
    rng = np.random.default_rng(4)
    col, row = rng.integers(0, _W, 40), rng.integers(0, _H, 40)
    z = rng.uniform(0.5, 9.0, 40)
    # pixel indices with the principal point half a pixel back: the rays through the centres
    a, b = ray_xy(col, row, fx, fy, cx - 0.5, cy - 0.5)
    np.testing.assert_allclose(a, (col + 0.5 - 12.25) / 70.0, rtol=1e-14)
    np.testing.assert_allclose(b, (40.5 - row - 0.5) / 35.0, rtol=1e-14)
    # out= writes into the given arrays (the inputs themselves, too) with the same values
    u, v = col + 0.5, row + 0.5
    ra, rb = ray_xy(u, v, fx, fy, cx, cy, out=(u, v))
    assert ra is u and rb is v
    np.testing.assert_array_equal(ra, ray_xy(col + 0.5, row + 0.5, fx, fy, cx, cy)[0])
    X, Y = np.empty(40), np.empty(40)
    ray_to_xy(a, b, z, True, out=(X, Y))
    np.testing.assert_array_equal(X, a * z)
    ray_to_xy(a, b, z, False, out=(X, Y))
    np.testing.assert_array_equal(Y, b)
    # shift_ray gives the ray of the pixel (dx, dy) away, as ray_xy there
    dx, dy = rng.normal(size=40) * 5, rng.normal(size=40) * 5
    shifted = shift_ray(a, b, dx, dy, fx, fy)
    np.testing.assert_allclose(shifted, ray_xy(col + 0.5 + dx, row + 0.5 + dy, fx, fy, cx, cy), rtol=1e-12,
                               atol=1e-14)


def test_camera_is_a_pose_and_a_projection():
    look = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(40, 30), fov_y=60.0)
    ortho = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(40, 30), ortho_height=2.0)
    intr = Camera.from_intrinsics(size=(40, 30), pose=look.pose, **INTRINSICS)
    assert type(look.lens) is Perspective and type(ortho.lens) is Orthographic and type(intr.lens) is Intrinsics
    assert isinstance(look.lens, Projection) and look.lens == Perspective(60.0, (40, 30))
    assert ortho.lens == Orthographic(2.0, (40, 30)) and intr.lens == Intrinsics(size=(40, 30), **INTRINSICS)
    assert look.extrinsics == Pose.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1))
    assert intr.extrinsics == Pose(look.pose) and intr.extrinsics != look.extrinsics    # other records
    np.testing.assert_array_equal(intr.extrinsics.rotation, look.rotation)
    assert Camera.from_intrinsics(size=(40, 30), **INTRINSICS).extrinsics is None
    # every part is immutable, hashable and pickles to an equal object
    for part in (look.lens, ortho.lens, intr.lens, look.extrinsics, intr.extrinsics):
        with pytest.raises(AttributeError, match="immutable"):
            part._size = (1, 1)
        assert pickle.loads(pickle.dumps(part)) == part and hash(part) == hash(pickle.loads(pickle.dumps(part)))
    assert eval(repr(intr.lens), {"Intrinsics": Intrinsics}) == intr.lens
    assert eval(repr(look.extrinsics), {"Pose": Pose}) == look.extrinsics
    with pytest.raises(ValueError):
        look.extrinsics.eye[0] = 1.0
    # the camera's numbers are its lens's
    for cam in (look, ortho, intr):
        assert (cam.fx, cam.fy, cam.cx, cam.cy, cam.size) == (cam.lens.fx, cam.lens.fy, cam.lens.cx, cam.lens.cy,
                                                              cam.lens.size)
        assert cam.projection == cam.lens.name


def test_parts_equal_only_their_own_kind():
    look = Camera.look_at((1.0, 2.0, 3.0), (-0.5, 0.2, 0.1), size=(40, 30), fov_y=60.0)
    lens = look.lens
    # the same numbers in another kind of projection: the same pixels, not the same record
    twin = Intrinsics(lens.fx, lens.fy, lens.cx, lens.cy, lens.size)
    np.testing.assert_array_equal(twin.project([0.3, -0.2, 2.0])[0], lens.project([0.3, -0.2, 2.0])[0])
    assert twin != lens and lens != twin
    # the same parameter values (60, (40, 30)) mean a view height or a field of view by kind
    assert Orthographic(60.0, (40, 30)) != Perspective(60.0, (40, 30))
    assert hash(Orthographic(60.0, (40, 30))) != hash(Perspective(60.0, (40, 30)))
    # a lens, a pose and a camera never compare equal to each other
    parts = (lens, look.extrinsics, look)
    for a in parts:
        for b in parts:
            assert (a == b) is (a is b)
    assert lens.__eq__(look.extrinsics) is NotImplemented and look.__eq__(lens) is NotImplemented
    # equal values of one kind are one element of a set, whatever the int / float spelling
    assert len({Perspective(60, (40, 30)), Perspective(60.0, (40, 30)), lens}) == 1
    for part, slot in zip(parts, ("_size", "_eye", "_pose")):
        with pytest.raises(AttributeError, match=f"{type(part).__name__} is immutable; cannot delete"):
            delattr(part, slot)


def test_look_at_does_not_freeze_the_callers_arrays():
    eye = np.array([0.0, 0.0, 5.0])
    Camera.look_at(eye, (0, 0, 0), size=(4, 3))
    eye[0] = 1.0


# ---------------------------------------------------------------------------- pinhole cameras in the estimators
#: Flat surfaces: the depth buffer holds Embree's float32 hits, so planes are exact to ~1e-5
#: (as tests/test_line.py). Measured here, off-centre principal points (one off the
#: image) and fx / fy in {0.5, 1, 1.7, 2}: max 6.1e-5 (area), 1.4e-5 (line), 0 (point).
PLANE_TOL = 1e-3
#: Crop invariance. Line and point read the same pixels with the same offsets (measured: 0,
#: bit-identical; the point estimator's x = cx + fx X / Z could round differently with the
#: crop's cx - left, hence not 0 here). Area reads the same mip texels (crop offsets are
#: multiples of 2^5), but the mip stores the texels' mean pixel positions, which differ by
#: the crop's offset and round differently: measured 2.3e-14 (square), 8.0e-15 (fx != fy).
CROP_TOL = 1e-12
#: Anisotropic pixels (fx = 2 fy) against square pixels, mean |difference| over the valid
#: pixels of the crease at R = 0.4. Not 0: the wide image samples the depth twice as densely
#: along x, so nearest taps land on other pixel centres, bilinear fetches interpolate other
#: texels and the area estimator's mip texels cover other pixels. Measured (commit of this
#: file): line 9 samples 0.0022 (max 0.047), line 32 bilinear not randomized 0.0002 (max
#: 0.032), point 33 not randomized 0.00003 (max 0.028), area 5 samples 0.0053 (max 0.062),
#: area 5 clamped 0.0054, area 9 Gaussian 0.0018; the converged reference (4096 samples)
#: 0.0017, its own stderr. Ignoring fx (a camera with fx = fy over the wide G-buffer) gives
#: 0.007 - 0.046: the limits below sit between the two.
ANISO_MEAN_TOL = {"line": 0.005, "line_bilinear": 0.002, "point": 0.002, "area": 0.01,
                  "area_clamped": 0.01, "area_gaussian": 0.005, "reference": 0.004}
#: Ignoring fx must be at least this many times worse than honouring it (measured >= 2.5x).
ANISO_GAIN = 2.0


def crop_gbuffer(gb: GBuffer, left: int, top: int, size) -> GBuffer:
    """The G-buffer of a crop: arrays sliced, camera ``gb.camera.cropped(left, top, size)``."""
    W, H = size
    rows, cols = slice(top, top + H), slice(left, left + W)
    full_W = gb.shape[1]
    hits = gb.hits
    i, j = np.divmod(hits["index"], full_W)
    keep = (i >= top) & (i < top + H) & (j >= left) & (j < left + W)
    cropped_hits = {k: v[keep] for k, v in hits.items() if k != "index"}
    cropped_hits["index"] = (i[keep] - top) * W + (j[keep] - left)
    return GBuffer(gb.camera.cropped(left, top, size), depth=gb.depth[rows, cols],
                   normal=gb.normal[rows, cols], valid=gb.valid[rows, cols],
                   primitive=gb.primitive[rows, cols], hits=cropped_hits)


def with_camera(gb: GBuffer, camera) -> GBuffer:
    """The same buffers seen as rendered by another camera."""
    return GBuffer(camera, depth=gb.depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive,
                   hits=gb.hits if camera.has_pose else {})


ESTIMATORS = {
    "line": lambda gb, r: vo.vo_line(gb, radius=r, samples=9),
    "line_clamped_thick": lambda gb, r: vo.vo_line(gb, radius=r, samples=8, normal_clamp=True, thickness=r),
    "line_bilinear": lambda gb, r: vo.vo_line(gb, radius=r, samples=9, fetch="bilinear", normal_clamp=True),
    "line_open_quadratic": lambda gb, r: vo.vo_line(gb, radius=r, samples=12, offscreen="open",
                                                    falloff="quadratic"),
    "point": lambda gb, r: vo.vo_point(gb, radius=r, samples=12),
    "point_nearest_clamped": lambda gb, r: vo.vo_point(gb, radius=r, samples=33, fetch="nearest",
                                                       normal_clamp=True),
    "area": lambda gb, r: vo.vo_area(gb, radius=r, samples=1),
    "area_clamped": lambda gb, r: vo.vo_area(gb, radius=r, samples=5, normal_clamp=True),
    "area_gaussian_thick": lambda gb, r: vo.vo_area(gb, radius=r, samples=5, model="gaussian",
                                                    thickness=r, offscreen="open"),
    "reference": lambda gb, r: vo.vo_reference(gb, radius=r, samples=64).value,
    "reference_clamped": lambda gb, r: vo.vo_reference(gb, radius=r, samples=64, normal_clamp=True).stderr,
}


@pytest.fixture(scope="module")
def crease_look():
    cam = vo.Camera.look_at((1.6, 1.4, 2.2), (0.3, 0.2, 0.0), size=(48, 40), fov_y=50.0)
    return cam, vo.render_gbuffer(vo.scenes.crease(), cam)


# ---------------------------------------------------------------------------- (a)
@pytest.mark.parametrize("pose", [True, False], ids=["pose", "no-pose"])
def test_intrinsics_camera_gives_bit_identical_estimates(crease_look, pose):
    """from_intrinsics(fx = fy = f, (W/2, H/2)) is the look_at camera, bit for bit; the
    estimators need no pose (a pose-less camera gives the same numbers, no NoneType error)."""
    look, gb = crease_look
    cam = vo.Camera.from_intrinsics(look.fx, look.fy, look.cx, look.cy, look.size,
                                    pose=look.pose if pose else None)
    if pose:
        rendered = vo.render_gbuffer(vo.scenes.crease(), cam)
        np.testing.assert_array_equal(rendered.depth, gb.depth)
        np.testing.assert_array_equal(rendered.normal, gb.normal)
    other = with_camera(gb, cam)
    for name, f in ESTIMATORS.items():
        a, b = f(gb, 0.4), f(other, 0.4)
        np.testing.assert_array_equal(a, b, err_msg=name)
    v = vo.vo_line(gb, radius=0.4)
    np.testing.assert_array_equal(bilateral_blur(v, gb), bilateral_blur(v, other))


# ---------------------------------------------------------------------------- (b)
CROP = dict(left=64, top=32, size=(96, 64))   # off-centre; offsets multiples of 2^5


def _interior(cam, depth, valid, radius, margin):
    """Pixels whose taps (within ``margin`` pixels beyond the projected radius) stay inside."""
    H, W = depth.shape
    r = radius * np.asarray(cam.pixels_per_unit_xy(np.where(valid, depth, 1.0)))
    i, j = np.mgrid[0:H, 0:W]
    return (valid & (j + 0.5 - r[..., 0] - margin > 0) & (j + 0.5 + r[..., 0] + margin < W)
            & (i + 0.5 - r[..., 1] - margin > 0) & (i + 0.5 + r[..., 1] + margin < H))


@pytest.fixture(scope="module", params=["square", "anisotropic"])
def crop_case(request):
    look = vo.Camera.look_at((2.4, 2.0, 3.0), (0.2, 0.3, 0.0), size=(200, 128), fov_y=45.0)
    cam = look if request.param == "square" else vo.Camera.from_intrinsics(
        1.5 * look.fy, look.fy, 93.25, 70.0, look.size, pose=look.pose)
    gb = vo.render_gbuffer(vo.scenes.crease(), cam)
    return gb, crop_gbuffer(gb, CROP["left"], CROP["top"], CROP["size"])


CROP_ESTIMATORS = {
    # name: (estimator, reach: taps stay within reach x the projected radius + 2 pixels)
    "line": (lambda gb, r: vo.vo_line(gb, radius=r, samples=9), 1.0),
    "line_clamped": (lambda gb, r: vo.vo_line(gb, radius=r, samples=16, normal_clamp=True), 1.0),
    "line_bilinear": (lambda gb, r: vo.vo_line(gb, radius=r, samples=9, fetch="bilinear"), 1.0),
    "point": (lambda gb, r: vo.vo_point(gb, radius=r, samples=12), 1.0),
    "point_clamped": (lambda gb, r: vo.vo_point(gb, radius=r, samples=33, normal_clamp=True), 1.0),
    # the mip lookup: a region's footprint plus 1.5 texels of its level on each side (the
    # B-spline): within twice the radius (measured: within 1 R + 4 px already exact)
    "area": (lambda gb, r: vo.vo_area(gb, radius=r, samples=1), 2.0),
    "area_clamped": (lambda gb, r: vo.vo_area(gb, radius=r, samples=5, normal_clamp=True), 2.0),
}


@pytest.mark.parametrize("name", CROP_ESTIMATORS)
def test_crop_invariance(crop_case, name):
    gb, crop = crop_case
    f, reach = CROP_ESTIMATORS[name]
    radius = 0.15
    full = f(gb, radius)
    part = f(crop, radius)
    inside = _interior(crop.camera, crop.depth, crop.valid, reach * radius, 2.0)
    assert inside.sum() > 1000, inside.sum()
    W, H = CROP["size"]
    expected = full[CROP["top"]:CROP["top"] + H, CROP["left"]:CROP["left"] + W]
    err = np.max(np.abs(part[inside] - expected[inside]))
    assert err <= CROP_TOL, (name, err)
    # the crop is off-centre: its principal point is not its centre
    assert not crop.camera.is_centered_square


def test_crop_invariance_fails_without_the_principal_point(crop_case):
    """The crop's arrays with a centred camera (the principal point ignored) differ: the
    test above has teeth."""
    gb, crop = crop_case
    centred = vo.Camera.from_intrinsics(crop.camera.fx, crop.camera.fy, 48.0, 32.0, crop.camera.size,
                                        pose=crop.camera.pose)
    wrong = with_camera(crop, centred)
    v_right = vo.vo_line(crop, radius=0.15, normal_clamp=True)
    v_wrong = vo.vo_line(wrong, radius=0.15, normal_clamp=True)
    assert np.nanmax(np.abs(v_right - v_wrong)) > 0.01


# ---------------------------------------------------------------------------- (c)
@pytest.fixture(scope="module")
def aniso_pair():
    """The crease seen through square pixels (W x H) and through pixels half as wide
    (2W x H, fx = 2 fy). With cx' = 2 cx - 1/2, column 2j of the wide image has exactly the
    view ray of column j of the square one: (2j + 1/2 - cx') / (2 fy) = (j + 1/2 - cx) / fy."""
    sq = vo.Camera.look_at((1.6, 1.4, 2.2), (0.3, 0.2, 0.0), size=(64, 48), fov_y=50.0)
    W, H = sq.size
    wide = vo.Camera.from_intrinsics(2 * sq.fy, sq.fy, 2 * sq.cx - 0.5, sq.cy, (2 * W, H), pose=sq.pose)
    scene = vo.scenes.crease()
    g_sq, g_wide = vo.render_gbuffer(scene, sq), vo.render_gbuffer(scene, wide)
    # the camera that ignores fx: square pixels claimed for the wide buffers
    ignoring = vo.Camera.from_intrinsics(sq.fy, sq.fy, wide.cx, wide.cy, wide.size, pose=sq.pose)
    return g_sq, g_wide, with_camera(g_wide, ignoring)


ANISO_ESTIMATORS = {
    "line": lambda gb, r: vo.vo_line(gb, radius=r, samples=9),
    "line_bilinear": lambda gb, r: vo.vo_line(gb, radius=r, samples=32, randomize=False, fetch="bilinear"),
    "point": lambda gb, r: vo.vo_point(gb, radius=r, samples=33, randomize=False),
    "area": lambda gb, r: vo.vo_area(gb, radius=r, samples=5),
    "area_clamped": lambda gb, r: vo.vo_area(gb, radius=r, samples=5, normal_clamp=True),
    "area_gaussian": lambda gb, r: vo.vo_area(gb, radius=r, samples=9, model="gaussian"),
}


def test_anisotropic_views_share_rays(aniso_pair):
    g_sq, g_wide, _ = aniso_pair
    np.testing.assert_array_equal(g_wide.valid[:, ::2], g_sq.valid)
    np.testing.assert_array_equal(g_wide.depth[:, ::2][g_sq.valid], g_sq.depth[g_sq.valid])


@pytest.mark.parametrize("name", ANISO_ESTIMATORS)
def test_anisotropic_pixels_match_square_pixels(aniso_pair, name):
    g_sq, g_wide, g_ignoring = aniso_pair
    f = ANISO_ESTIMATORS[name]
    radius = 0.4
    v_sq = f(g_sq, radius)
    ok = g_sq.valid
    honoured = np.abs(f(g_wide, radius)[:, ::2] - v_sq)[ok].mean()
    ignored = np.abs(f(g_ignoring, radius)[:, ::2] - v_sq)[ok].mean()
    assert honoured < ANISO_MEAN_TOL[name], (name, honoured)
    assert ignored > ANISO_GAIN * honoured, (name, honoured, ignored)


def test_anisotropic_reference_matches_square_reference(aniso_pair):
    g_sq, g_wide, _ = aniso_pair
    # 1024 rays: about the standard error of 4096 points (docs/screenspace.md, "The converged
    # reference"), against which the depth-edge outliers below are counted
    a = vo.vo_reference(g_sq, radius=0.4, samples=1024, seed=1)
    b = vo.vo_reference(g_wide, radius=0.4, samples=1024, seed=2)
    ok = g_sq.valid
    diff = (b.value[:, ::2] - a.value)[ok]
    assert np.abs(diff).mean() < ANISO_MEAN_TOL["reference"]
    # the two converge to the same screen-space VO but for the depth reconstruction near
    # depth edges (the wide image's bilinear texels are half as wide): few outliers
    se = np.hypot(a.stderr, b.stderr[:, ::2])[ok]
    z = np.abs(diff) / np.where(se > 0, se, np.inf)
    assert np.mean(z > 4) < 0.01


def test_area_anisotropic_footprint(aniso_pair, monkeypatch):
    """The mip footprint of a non-square region: the anisotropic probes beat one isotropic
    lookup sized by the longer axis ("max", over-blurs the short axis) or by the geometric
    mean ("geometric"). Measured mean |V_wide - V_square| (crease, R = 0.4, fx = 2 fy):

    ============  =======  =========  ======
    samples       probes   geometric  max
    ============  =======  =========  ======
    1             0.0055   0.0377     0.0609
    5             0.0053   0.0114     0.0255
    5, clamped    0.0054   0.0100     0.0298
    9, Gaussian   0.0018   0.0057     0.0140
    ============  =======  =========  ======
    """
    g_sq, g_wide, _ = aniso_pair
    err = {}
    for scheme in area_module.FOOTPRINTS:
        monkeypatch.setattr(area_module, "ANISOTROPIC_FOOTPRINT", scheme)
        for samples in (1, 5):
            v_sq = vo.vo_area(g_sq, radius=0.4, samples=samples)
            v = vo.vo_area(g_wide, radius=0.4, samples=samples)[:, ::2]
            err[scheme, samples] = np.abs(v - v_sq)[g_sq.valid].mean()
            # square pixels never see the scheme
            np.testing.assert_array_equal(v_sq, vo.vo_area(g_sq, radius=0.4, samples=samples))
    for samples in (1, 5):
        assert err["probes", samples] < err["geometric", samples] < err["max", samples], err
    monkeypatch.setattr(area_module, "ANISOTROPIC_FOOTPRINT", "nonsense")
    with pytest.raises(ValueError, match="ANISOTROPIC_FOOTPRINT"):
        vo.vo_area(g_wide, radius=0.4)


# ---------------------------------------------------------------------------- (d)
def _plane_interior(gb, radius, margin=1.0):
    """On the image and far from the background (whose taps would see no plane there)."""
    r = radius * np.asarray(gb.camera.pixels_per_unit_xy(np.where(gb.valid, gb.depth, 1.0)))
    far_from_background = distance_transform_edt(gb.valid) > 2 * np.max(r, axis=-1) + 4
    return _interior(gb.camera, gb.depth, gb.valid, radius, margin) & far_from_background


def _area_plane_interior(gb, radius, samples):
    """As tests/test_area.py: the disk plus the B-spline's support (1.5 texels) at the
    coarsest mip level used stays inside the image, on levels that need no padding; the
    level is bounded with the longer axis's projected radius (conservative)."""
    H, W = gb.shape
    r = radius * np.asarray(gb.camera.pixels_per_unit_xy(np.where(gb.valid, gb.depth, 1.0)))
    lod = (np.log2(np.max(r, axis=-1)) + 0.5 * np.log2(region_areas(vo.patterns.disk(samples)).max())
           - area_module.LOD_BIAS["bspline"])
    L1 = np.floor(np.maximum(lod, 0.0)) + 1
    support = 1.5 * 2.0 ** L1
    clean = (H % 2 ** L1 == 0) & (W % 2 ** L1 == 0)
    i, j = np.mgrid[:H, :W]
    mx, my = r[..., 0] + 1.0 + support, r[..., 1] + 1.0 + support
    return (_plane_interior(gb, radius) & clean & (j + 0.5 - mx >= 0) & (j + 0.5 + mx <= W)
            & (i + 0.5 - my >= 0) & (i + 0.5 + my <= H))


# (fx / fy, cx, cy) on a 64 x 48 image: principal points off-centre, one off the image
PLANE_INTRINSICS = [(1.7, 15.25, 33.0), (0.5, 50.0, 10.5), (2.0, -6.0, 24.0), (1.0, 5.0, 40.0)]


@pytest.mark.parametrize("eye", [(1, 2, 1.5), (0.01, 3, 0.0), (2.5, 1.2, 0.4)])
@pytest.mark.parametrize("intrinsics", PLANE_INTRINSICS, ids=[f"{r}-{cx}-{cy}" for r, cx, cy in PLANE_INTRINSICS])
@pytest.mark.parametrize("radius", [0.02, 0.15])
def test_planes_read_one_half(big_slab, eye, intrinsics, radius):
    ratio, cx, cy = intrinsics
    look = vo.Camera.look_at(eye, (0, 0, 0), size=(64, 48), fov_y=40.0)
    cam = vo.Camera.from_intrinsics(ratio * look.fy, look.fy, cx, cy, (64, 48), pose=look.pose)
    gb = vo.render_gbuffer(big_slab, cam)
    inside = _plane_interior(gb, radius)
    assert inside.sum() > 50, inside.sum()
    inside_area = {n: _area_plane_interior(gb, radius, n) for n in (1, 5, 9)}
    assert min(m.sum() for m in inside_area.values()) > 20
    for name, f in (("line", lambda **kw: vo.vo_line(gb, radius=radius, samples=9, **kw)),
                    ("line16", lambda **kw: vo.vo_line(gb, radius=radius, samples=16, **kw)),
                    ("line-bilinear", lambda **kw: vo.vo_line(gb, radius=radius, samples=9, fetch="bilinear", **kw)),
                    ("area", lambda **kw: vo.vo_area(gb, radius=radius, samples=1, **kw)),
                    ("area5", lambda **kw: vo.vo_area(gb, radius=radius, samples=5, **kw)),
                    ("area-gaussian", lambda **kw: vo.vo_area(gb, radius=radius, samples=9, model="gaussian", **kw)),
                    ("point", lambda **kw: vo.vo_point(gb, radius=radius, samples=12, **kw))):
        v, vc = f(), f(normal_clamp=True)
        mask = inside_area[{"area": 1, "area5": 5, "area-gaussian": 9}[name]] if name.startswith("area") else inside
        assert np.max(np.abs(v[mask] - 0.5)) < PLANE_TOL, name
        assert np.max(np.abs(vc[mask] - 1.0)) < PLANE_TOL, name


def test_orthographic_cameras_keep_their_intrinsics():
    """Orthographic stays look_at-only: centred, square pixels, fx = fy = H / ortho_height."""
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(8, 6), ortho_height=2.0)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (3.0, 3.0, 4.0, 3.0)
    assert cam.is_centered_square
