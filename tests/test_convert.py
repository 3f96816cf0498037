"""vobscure.convert through GBuffer.from_arrays and GBuffer.derive_normals: other renderers'
depth and normal conventions converted to the library's.

Every forward conversion here (what OpenGL, Direct3D, a reversed-Z pipeline, a ray tracer or
a packed-normal G-buffer would have written) is computed the way those APIs do it: by
applying their projection matrices (glFrustum / glOrtho, D3DXMatrixPerspectiveFovLH /
D3DXMatrixOrthoLH, as printed on their reference pages) to view-space points, and a
gluLookAt view matrix to world-space normals. None of it calls the inverse formulas of
``vobscure.convert``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import (DEPTH_KINDS, NORMAL_LENGTH_TOL, GBuffer, NormalsRenormalizedWarning,
                              NormalsRepairedWarning)

#: Clip planes of the synthetic projections: the crease's depths are about 4 to 12.
NEAR, FAR = 0.5, 50.0
#: Relative depth error after a round trip through a projection, per dtype of the stored
#: values. float64: a few ulps times dz/dz_ndc * z_ndc / z (<= 2 f / n = 200 here) -> 1e-9.
#: float32: the stored z_ndc rounds by 6e-8 absolute; dz/dz_ndc = z^2 (f - n) / (2 f n)
#: <= 144 * 49.5 / 50 = 143 at z = 12, i.e. 8.6e-6 absolute, 7e-7 relative at z = 12 (and
#: less nearer); the output rounds by 6e-8. 5e-6: 7x that.
DEPTH_RTOL = {np.float64: 1e-9, np.float32: 5e-6}
#: Normals after a round trip (rotations and packing in float64, the stored values' dtype).
NORMAL_ATOL = {np.float64: 1e-12, np.float32: 1e-6}
#: vo_line on the converted G-buffer against the original one. The estimate is continuous in
#: the depths (line sampling intersects chords analytically), so it moves by about
#: (depth error) / (2 R z_s) <= 1e-9 * 12 / 0.6 in float64; float32 as tests/test_line.py
#: (FLOAT32_TOL, 2e-6) plus the float32 depth error above (8.6e-6 / (2 * 0.77) = 6e-6).
VO_ATOL = {np.float64: 1e-7, np.float32: 2e-5}
#: Derived normals on the crease rendered at 96 x 72 (measured at this commit: median 2e-4
#: degrees, 99th percentile of the pixels under 1 degree; the errors are at the one-pixel strip
#: of the wall's top face and the crease edge). The bounds leave a margin of about 2x.
DERIVED_MEDIAN_DEG = 1e-2
DERIVED_FRACTION_OVER_5DEG = 0.02
#: Derived normals on an analytic plane (float64 depths): rounding only.
PLANE_NORMAL_ATOL = 1e-9

SIZE = (48, 36)
RADIUS = 0.6


@pytest.fixture(scope="module")
def scene():
    return vo.scenes.get("crease")


@pytest.fixture(scope="module", params=["perspective", "orthographic"])
def rendered(request, scene):
    lens = dict(fov_y=50.0) if request.param == "perspective" else dict(ortho_height=5.0)
    cam = vo.Camera.look_at((4.0, 3.5, 5.0), (0.5, 0.0, 0.0), size=SIZE, **lens)
    gb = vo.render_gbuffer(scene, cam)
    assert 0.3 * gb.valid.size < gb.valid.sum() < gb.valid.size
    return gb


# ----------------------------------------------------------------------------- forward maps
def gl_projection(cam, n=NEAR, f=FAR):
    """The OpenGL projection matrix (glFrustum / glOrtho with a symmetric view volume)."""
    W, H = cam.size
    if cam.is_perspective:
        t = n * math.tan(math.radians(cam.fov_y) / 2)
        r = t * W / H
        return np.array([[n / r, 0, 0, 0], [0, n / t, 0, 0],
                         [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0]])
    t = cam.ortho_height / 2
    r = t * W / H
    return np.array([[1 / r, 0, 0, 0], [0, 1 / t, 0, 0], [0, 0, -2 / (f - n), -(f + n) / (f - n)],
                     [0, 0, 0, 1]])


def d3d_projection(cam, n=NEAR, f=FAR):
    """Direct3D's left-handed projection, row-vector form (D3DXMatrixPerspectiveFovLH /
    D3DXMatrixOrthoLH)."""
    W, H = cam.size
    if cam.is_perspective:
        ys = 1 / math.tan(math.radians(cam.fov_y) / 2)
        return np.array([[ys * H / W, 0, 0, 0], [0, ys, 0, 0], [0, 0, f / (f - n), 1],
                         [0, 0, -n * f / (f - n), 0]])
    w, h = cam.ortho_height * W / H, cam.ortho_height
    return np.array([[2 / w, 0, 0, 0], [0, 2 / h, 0, 0], [0, 0, 1 / (f - n), 0], [0, 0, n / (n - f), 1]])


def stored_depth(gb, kind, dtype=np.float64, n=NEAR, f=FAR):
    """What a renderer of the given kind would write for gb (background: its cleared value)."""
    p = np.asarray(gb.position, dtype=np.float64)
    X, Y, Z = p[..., 0], p[..., 1], p[..., 2]
    one = np.ones_like(Z)
    if kind == "linear":
        out = gb.depth.copy()
    elif kind == "distance":
        # the ray through the pixel centre at unit depth, from the field of view
        cam = gb.camera
        W, H = cam.size
        if cam.is_perspective:
            a = (np.arange(W) + 0.5 - cam.cx)[None, :] / cam.fx
            b = (cam.cy - np.arange(H) - 0.5)[:, None] / cam.fy
            out = gb.depth * np.sqrt(1 + a * a + b * b)
        else:
            out = gb.depth.copy()
    elif kind == "ndc":      # OpenGL: eye space looks down -z, column vectors
        clip = np.einsum("ij,...j->...i", gl_projection(gb.camera, n, f), np.stack([X, Y, -Z, one], -1))
        out = clip[..., 2] / clip[..., 3]
        out[~gb.valid] = 1.0
    elif kind == "ndc01":    # Direct3D: row vectors
        clip = np.stack([X, Y, Z, one], -1) @ d3d_projection(gb.camera, n, f)
        out = clip[..., 2] / clip[..., 3]
        out[~gb.valid] = 1.0
    elif kind == "reversed":  # Direct3D with near and far swapped
        clip = np.stack([X, Y, Z, one], -1) @ d3d_projection(gb.camera, f, n)
        out = clip[..., 2] / clip[..., 3]
        out[~gb.valid] = 0.0
    return out.astype(dtype)


def glu_look_at(cam):
    """gluLookAt's 4x4 world-to-eye matrix (OpenGL: rows s, u, -f; column vectors)."""
    f = (cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye)
    s = np.cross(f, cam.up_hint)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    M = np.eye(4)
    M[0, :3], M[1, :3], M[2, :3] = s, u, -f
    M[:3, 3] = -(M[:3, :3] @ cam.eye)
    return M


def check_round_trip(gb, back, dtype):
    assert back.dtype == dtype and back.conversion is not None
    np.testing.assert_array_equal(back.valid, gb.valid)
    v = gb.valid
    np.testing.assert_allclose(back.depth[v], gb.depth[v], rtol=DEPTH_RTOL[dtype])
    assert np.all(np.isposinf(back.depth[~v])) and np.all(back.normal[~v] == 0)
    np.testing.assert_allclose(back.normal, gb.normal, atol=NORMAL_ATOL[dtype])
    ref = gb.astype(dtype)
    a = vo.vo_line(ref, radius=RADIUS, normal_clamp=True)
    b = vo.vo_line(back, radius=RADIUS, normal_clamp=True)
    assert b.dtype == a.dtype
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    np.testing.assert_allclose(b[v], a[v], atol=VO_ATOL[dtype])


# ----------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("kind", DEPTH_KINDS)
def test_depth_kinds_round_trip(rendered, kind, dtype):
    gb = rendered
    depth = stored_depth(gb, kind, dtype)
    near_far = dict(near=NEAR, far=FAR) if kind in ("ndc", "ndc01", "reversed") else {}
    back = GBuffer.from_arrays(depth, gb.normal.astype(dtype), camera=gb.camera, depth_kind=kind,
                               **near_far)
    check_round_trip(gb, back, dtype)
    assert back.conversion["background"] == int((~gb.valid).sum())
    assert back.conversion["renormalized"] == back.conversion["flipped"] == 0


def test_linear_identity_gives_the_same_estimate_exactly(rendered):
    gb = rendered
    back = GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera)
    for clamp in (False, True):
        np.testing.assert_array_equal(vo.vo_line(back, radius=RADIUS, normal_clamp=clamp),
                                      vo.vo_line(gb, radius=RADIUS, normal_clamp=clamp))
    np.testing.assert_array_equal(vo.vo_point(back, radius=RADIUS), vo.vo_point(gb, radius=RADIUS))
    np.testing.assert_allclose(vo.vo_area(back, radius=RADIUS), vo.vo_area(gb, radius=RADIUS), atol=1e-12)


def test_ground_truth_reads_the_derived_world_data(scene, rendered):
    gb = rendered
    back = GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera)
    a = vo.ground_truth(scene, gb, quantity="ao", radius=RADIUS, rays=32, seed=1)
    b = vo.ground_truth(scene, back, quantity="ao", radius=RADIUS, rays=32, seed=1)
    # the same rays from points equal to ~1e-7: the same hits on the crease's faces
    np.testing.assert_allclose(b.value, a.value, atol=1e-12)
    v = vo.bilateral_blur(vo.vo_line(back, radius=RADIUS), back)
    np.testing.assert_allclose(v, vo.bilateral_blur(vo.vo_line(gb, radius=RADIUS), gb), atol=1e-12)


def test_reversed_infinite_far(rendered):
    gb = rendered
    z = np.where(gb.valid, NEAR / gb.depth, 0.0)        # reversed-Z, infinite far: z_r = n / z
    if not gb.camera.is_perspective:     # an infinite far plane is a perspective projection
        with pytest.raises(ValueError, match="orthographic camera needs a finite far"):
            GBuffer.from_arrays(z, gb.normal, camera=gb.camera, depth_kind="reversed", near=NEAR,
                                far=np.inf)
        return
    back = GBuffer.from_arrays(z, gb.normal, camera=gb.camera, depth_kind="reversed", near=NEAR,
                               far=np.inf)
    check_round_trip(gb, back, np.float64)


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("encoding", ["signed", "unit"])
@pytest.mark.parametrize("space_convention", [("view", "vobscure"), ("view", "opengl"),
                                              ("view", "directx"), ("world", "vobscure"),
                                              ("world", "opengl-view-matrix")])
def test_normal_encodings_spaces_conventions(rendered, encoding, space_convention, dtype):
    gb = rendered
    space, convention = space_convention
    extra = {}
    if space == "world":
        n = np.asarray(gb.world_normal, dtype=np.float64)
        if convention == "opengl-view-matrix":
            convention, extra = "opengl", dict(view=glu_look_at(gb.camera))
    elif convention == "opengl":
        n = gb.normal * np.array([1.0, 1.0, -1.0])     # eye space looks down -z
    else:
        n = gb.normal.copy()
    if encoding == "unit":
        n = 0.5 * n + 0.5
        n[~gb.valid] = 0.0
    back = GBuffer.from_arrays(gb.depth.astype(dtype), n.astype(dtype), camera=gb.camera,
                               normal_space=space, normal_encoding=encoding, convention=convention,
                               **extra)
    check_round_trip(gb, back, dtype)


def test_integer_packed_normals(rendered):
    gb = rendered
    n16 = np.round((0.5 * gb.normal + 0.5) * 65535).astype(np.uint16)
    back = GBuffer.from_arrays(gb.depth, n16, camera=gb.camera, normal_encoding="unit")
    np.testing.assert_allclose(back.normal, gb.normal, atol=1e-4)   # 16-bit: within normal_tol
    n8 = np.round((0.5 * gb.normal + 0.5) * 255).astype(np.uint8)
    n8[~gb.valid] = 0
    n8.reshape(-1, 3)[np.flatnonzero(gb.valid)[:3]] = (128, 250, 40)   # length 1.13: an edge pixel
    length = np.linalg.norm(n8 / 255 * 2 - 1, axis=-1)
    k = int(np.count_nonzero(gb.valid & (np.abs(length - 1) > NORMAL_LENGTH_TOL)))
    assert k >= 3
    with pytest.warns(NormalsRenormalizedWarning, match=rf"renormalized {k} normal"):
        back = GBuffer.from_arrays(gb.depth, n8, camera=gb.camera, normal_encoding="unit")
    assert back.conversion["renormalized"] == k
    rest = np.flatnonzero(gb.valid)[3:]
    np.testing.assert_allclose(back.normal.reshape(-1, 3)[rest], gb.normal.reshape(-1, 3)[rest], atol=2 / 255)
    with pytest.raises(ValueError, match="normal_encoding='unit'"):
        GBuffer.from_arrays(gb.depth, n8, camera=gb.camera)


def test_origin_lower_flips_rows(rendered):
    gb = rendered
    back = GBuffer.from_arrays(gb.depth[::-1], gb.normal[::-1], camera=gb.camera, origin="lower")
    np.testing.assert_array_equal(back.depth, gb.depth)


def test_world_space_data_from_the_pose(rendered):
    gb = rendered
    back = GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera)
    v = gb.valid
    scale = float(np.abs(gb.world_position[v]).max())
    np.testing.assert_allclose(back.world_position[v], gb.world_position[v], atol=1e-6 * scale)
    np.testing.assert_allclose(back.world_normal, gb.world_normal, atol=1e-12)
    np.testing.assert_allclose(back.position[v], gb.position[v], atol=1e-6 * scale)
    assert np.all(np.isnan(back.position[~v])) and np.all(back.primitive == -1)
    hits = back.hits
    np.testing.assert_array_equal(hits["index"], np.flatnonzero(v))
    np.testing.assert_array_equal(hits["world_geometric_normal"], hits["world_normal"])
    # astype keeps the derived nature
    b32 = back.astype(np.float32)
    assert b32.dtype == np.float32 and b32.conversion == back.conversion
    np.testing.assert_allclose(b32.world_normal, gb.world_normal, atol=1e-6)


# ----------------------------------------------------------------------------- synthetic plane
def plane_buffers(cam):
    """Analytic depth and view normal of the plane y = 0 through every pixel centre."""
    o, d = cam.primary_rays()
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[..., 1] / d[..., 1]
    hit = np.isfinite(t) & (t > 0)
    position = cam.world_to_view(o + t[..., None] * d)
    depth = np.where(hit, position[..., 2], np.inf)
    n = np.where(hit[..., None], cam.world_to_view_dir(np.array([0.0, 1.0, 0.0])), 0.0)
    return depth, n, hit, position


@pytest.mark.parametrize("lens", [dict(fov_y=60.0), dict(ortho_height=4.0)])
@pytest.mark.parametrize("kind", DEPTH_KINDS)
def test_synthetic_plane_reads_half_and_one(kind, lens):
    cam = vo.Camera.look_at((0.0, 2.0, 3.0), (0.0, 0.0, 0.0), size=(40, 30), **lens)
    depth, n, hit, position = plane_buffers(cam)
    assert hit.all()
    stored = stored_depth(SimpleNamespace(camera=cam, depth=depth, valid=hit, position=position), kind)
    near_far = dict(near=NEAR, far=FAR) if kind in ("ndc", "ndc01", "reversed") else {}
    for normals in (n, None):      # given, and derived from the depth
        gb = GBuffer.from_arrays(stored, normals, camera=cam, depth_kind=kind, **near_far)
        inner = (slice(8, -8), slice(8, -8))        # the ball's disk stays on screen
        open_ = vo.vo_line(gb, radius=0.2, normal_clamp=False)[inner]
        clamped = vo.vo_line(gb, radius=0.2, normal_clamp=True)[inner]
        np.testing.assert_allclose(open_, 0.5, atol=1e-6)
        np.testing.assert_allclose(clamped, 1.0, atol=1e-6)


@pytest.mark.parametrize("lens", [dict(fov_y=60.0), dict(ortho_height=4.0)])
def test_derived_normals_exact_on_a_plane(lens):
    cam = vo.Camera.look_at((0.3, 2.0, 3.0), (0.0, 0.0, 0.2), size=(40, 30), **lens)
    depth, n, hit, _ = plane_buffers(cam)
    gb = GBuffer.from_arrays(depth, camera=cam)
    np.testing.assert_allclose(gb.normal, n, atol=PLANE_NORMAL_ATOL)
    assert gb.conversion["derived"] == hit.sum() and gb.conversion["undetermined"] == 0
    np.testing.assert_allclose(GBuffer.derive_normals(cam, depth), n, atol=PLANE_NORMAL_ATOL)


def test_derived_normals_on_the_crease_within_the_measured_error(scene):
    cam = scene.camera((96, 72))
    gb = vo.render_gbuffer(scene, cam)
    derived = GBuffer.from_arrays(gb.depth, camera=cam)
    v = gb.valid
    cos = np.clip(np.einsum("...i,...i->...", derived.normal, gb.normal)[v], -1, 1)
    angle = np.degrees(np.arccos(cos))
    assert np.median(angle) < DERIVED_MEDIAN_DEG
    assert np.mean(angle > 5.0) < DERIVED_FRACTION_OVER_5DEG
    # normal_clamp without normals uses the derived ones
    a = vo.vo_line(gb, radius=RADIUS, normal_clamp=True)[v]
    b = vo.vo_line(derived, radius=RADIUS, normal_clamp=True)[v]
    assert np.median(np.abs(a - b)) < 1e-4 and np.mean(np.abs(a - b) > 0.01) < DERIVED_FRACTION_OVER_5DEG


def test_no_depth_only_gbuffer():
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(5, 4))
    with pytest.raises(ValueError, match="needs normals.*from_arrays.*derives them"):
        GBuffer(cam, depth=np.ones((4, 5)), normal=None, valid=np.ones((4, 5), bool),
                primitive=np.zeros((4, 5), int), hits=None)


def test_isolated_pixel_faces_the_camera():
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(5, 4), fov_y=40.0)
    depth = np.full((4, 5), np.inf)
    depth[2, 2] = 5.0
    gb = GBuffer.from_arrays(depth, camera=cam)
    assert gb.conversion["undetermined"] == 1
    ray = cam.unproject([2.5, 2.5], 1.0)
    np.testing.assert_allclose(gb.normal[2, 2], -ray / np.linalg.norm(ray), atol=1e-12)


# ----------------------------------------------------------------------------- background
def test_blender_background_value(rendered):
    gb = rendered
    depth = np.where(gb.valid, gb.depth, 1e10)           # Blender writes 1e10 where nothing is hit
    normal = np.where(gb.valid[..., None], gb.world_normal, 0.0)
    back = GBuffer.from_arrays(depth, normal, camera=gb.camera, normal_space="world", background=1e10)
    check_round_trip(gb, back, np.float64)
    assert back.conversion["background"] == int((~gb.valid).sum()) and back.conversion["nonfinite"] == 0
    # without background=, 1e10 is a surface: its zero normals are then reported
    k = int((~gb.valid).sum())
    with pytest.raises(ValueError, match=rf"{k} zero or NaN vector\(s\) on covered pixels"):
        GBuffer.from_arrays(depth, normal, camera=gb.camera, normal_space="world")
    # a predicate: a depth sensor's 0 = "no reading"
    sensor = np.where(gb.valid, gb.depth, 0.0)
    back = GBuffer.from_arrays(sensor, gb.normal, camera=gb.camera, background=lambda d: d == 0)
    np.testing.assert_array_equal(back.valid, gb.valid)


def test_nonfinite_depth_is_background_and_counted(rendered):
    gb = rendered
    depth = gb.depth.copy()
    i = np.flatnonzero(gb.valid)[:4]
    depth.reshape(-1)[i] = np.nan
    back = GBuffer.from_arrays(depth, gb.normal, camera=gb.camera)
    assert back.conversion["nonfinite"] == int((~gb.valid).sum()) + 4
    assert not back.valid.reshape(-1)[i].any() and np.all(back.normal.reshape(-1, 3)[i] == 0)
    assert np.all(np.isnan(vo.vo_line(back, radius=RADIUS).reshape(-1)[i]))


def test_ndc_default_background_is_the_cleared_far_value(rendered):
    gb = rendered
    for kind, cleared in (("ndc", 1.0), ("ndc01", 1.0), ("reversed", 0.0)):
        depth = stored_depth(gb, kind)
        assert np.all(depth[~gb.valid] == cleared)
        back = GBuffer.from_arrays(depth, gb.normal, camera=gb.camera, depth_kind=kind, near=NEAR, far=FAR)
        np.testing.assert_array_equal(back.valid, gb.valid)


# ----------------------------------------------------------------------------- normals repair
def test_renormalization_warns_once_with_the_count(rendered):
    gb = rendered
    n = gb.normal.copy()
    idx = np.flatnonzero(gb.valid)[:7]
    n.reshape(-1, 3)[idx] *= 1.1
    n.reshape(-1, 3)[np.flatnonzero(gb.valid)[7:10]] *= 1 + NORMAL_LENGTH_TOL / 2   # within: silent
    with pytest.warns(NormalsRenormalizedWarning, match=r"renormalized 7 normal\(s\)") as record:
        back = GBuffer.from_arrays(gb.depth, n, camera=gb.camera)
    assert len(record) == 1 and issubclass(NormalsRenormalizedWarning, UserWarning)
    assert back.conversion["renormalized"] == 7
    np.testing.assert_allclose(back.normal, gb.normal, atol=1e-12)


def test_flipped_normals_face_the_camera(rendered):
    gb = rendered
    n = gb.normal.copy()
    idx = np.flatnonzero(gb.valid)[::5]
    n.reshape(-1, 3)[idx] *= -1
    back = GBuffer.from_arrays(gb.depth, n, camera=gb.camera)
    assert back.conversion["flipped"] == len(idx)
    np.testing.assert_allclose(back.normal, gb.normal, atol=1e-12)


@pytest.mark.parametrize("bad", [0.0, np.nan])
def test_zero_or_nan_normals_rejected_or_repaired(rendered, bad):
    gb = rendered
    n = gb.normal.copy()
    idx = np.flatnonzero(gb.valid)[100:105]
    n.reshape(-1, 3)[idx] = bad
    with pytest.raises(ValueError, match=r"5 zero or NaN vector\(s\).*repair_normals=True"):
        GBuffer.from_arrays(gb.depth, n, camera=gb.camera)
    with pytest.warns(NormalsRepairedWarning, match="derived 5 zero or NaN normal"):
        back = GBuffer.from_arrays(gb.depth, n, camera=gb.camera, repair_normals=True)
    assert back.conversion["repaired"] == 5
    got = back.normal.reshape(-1, 3)[idx]
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, atol=1e-12)
    expect = GBuffer.derive_normals(gb.camera, gb.depth).reshape(-1, 3)[idx]
    np.testing.assert_allclose(got, expect, atol=1e-12)
    # NaN normals on background pixels are fine
    n2 = gb.normal.copy()
    n2[~gb.valid] = np.nan
    GBuffer.from_arrays(gb.depth, n2, camera=gb.camera)


# ----------------------------------------------------------------------------- validation
def test_shape_errors_name_both_arrays_and_the_camera_size(rendered):
    gb = rendered
    W, H = gb.camera.size
    with pytest.raises(ValueError) as info:
        GBuffer.from_arrays(gb.depth.T, gb.normal, camera=gb.camera)
    msg = str(info.value)
    assert "transposed?" in msg and f"({W}, {H})" in msg and f"depth ({W}, {H})" in msg
    assert f"normal ({H}, {W}, 3)" in msg and "camera.size" in msg
    with pytest.raises(ValueError, match=r"normal must have shape .*transposed\?"):
        GBuffer.from_arrays(gb.depth, gb.normal.transpose(1, 0, 2), camera=gb.camera)
    with pytest.raises(ValueError, match=r"normal must have shape \(36, 48, 3\).*got \(36, 48, 4\)"):
        GBuffer.from_arrays(gb.depth, np.zeros((H, W, 4)), camera=gb.camera)
    with pytest.raises(ValueError, match=r"depth must have shape \(36, 48\).*got \(10, 10\)") as info:
        GBuffer.from_arrays(np.ones((10, 10)), camera=gb.camera)
    assert "transposed" not in str(info.value)


def test_depth_errors(rendered):
    gb = rendered
    cam = gb.camera
    neg = np.where(gb.valid, -gb.depth, np.inf)
    k = int(gb.valid.sum())
    with pytest.raises(ValueError, match=rf"{k} pixel\(s\) do not.*OpenGL eye-space z is negative"):
        GBuffer.from_arrays(neg, gb.normal, camera=cam)
    with pytest.raises(ValueError, match="needs the clip distances near and far.*far not given"):
        GBuffer.from_arrays(stored_depth(gb, "ndc"), gb.normal, camera=cam, depth_kind="ndc", near=NEAR)
    with pytest.raises(ValueError, match="far must be greater than near"):
        GBuffer.from_arrays(stored_depth(gb, "ndc"), gb.normal, camera=cam, depth_kind="ndc", near=2.0, far=1.0)
    with pytest.raises(ValueError, match=r"must lie in \[0.0, 1.0\].*value\(s\) do not"):
        GBuffer.from_arrays(stored_depth(gb, "ndc01") - 1.5, gb.normal, camera=cam, depth_kind="ndc01",
                            near=NEAR, far=FAR)
    with pytest.raises(ValueError, match="depth_kind must be one of 'linear'"):
        GBuffer.from_arrays(gb.depth, camera=cam, depth_kind="log")
    with pytest.raises(ValueError, match="depth must be a numeric"):
        GBuffer.from_arrays(np.full(cam.shape, "a"), camera=cam)
    with pytest.raises(ValueError, match="background must be a depth value"):
        GBuffer.from_arrays(gb.depth, camera=cam, background="sky")
    with pytest.raises(ValueError, match=r"background\(depth\) must return a bool array"):
        GBuffer.from_arrays(gb.depth, camera=cam, background=lambda d: d[0])
    with pytest.raises(ValueError, match="camera must be a vobscure Camera"):
        GBuffer.from_arrays(gb.depth, camera=None)
    for name, value in (("normal_space", "screen"), ("normal_encoding", "oct"),
                        ("convention", "vulkan"), ("origin", "left")):
        with pytest.raises(ValueError, match=f"{name} must be one of"):
            GBuffer.from_arrays(gb.depth, camera=cam, **{name: value})


def test_world_space_needs_a_pose(scene):
    c = vo.Camera.look_at((4.0, 3.5, 5.0), (0.5, 0.0, 0.0), size=SIZE, fov_y=50.0)
    gb = vo.render_gbuffer(scene, c)
    cam = vo.Camera.from_intrinsics(c.fx, c.fy, c.cx, c.cy, c.size)      # no pose
    assert not cam.has_pose
    back = GBuffer.from_arrays(gb.depth, gb.normal, camera=cam)
    np.testing.assert_array_equal(vo.vo_line(back, radius=RADIUS), vo.vo_line(gb, radius=RADIUS))
    np.testing.assert_allclose(back.position[gb.valid], gb.position[gb.valid], atol=1e-5)
    for attribute in ("world_position", "world_normal", "hits"):
        with pytest.raises(ValueError, match="needs the camera's pose"):
            getattr(back, attribute)
    with pytest.raises(ValueError, match="normal_space='world' needs the world-to-view rotation"):
        GBuffer.from_arrays(gb.depth, gb.world_normal, camera=cam, normal_space="world")
    # with view= the world-space normals and data work without a pose
    back = GBuffer.from_arrays(gb.depth, gb.world_normal, camera=cam, normal_space="world",
                               view=glu_look_at(c), convention="opengl")
    np.testing.assert_allclose(back.normal, gb.normal, atol=1e-12)
    np.testing.assert_allclose(back.world_position[gb.valid], gb.world_position[gb.valid], atol=1e-5)
    # a camera with the pose as a matrix
    posed = vo.Camera.from_intrinsics(c.fx, c.fy, c.cx, c.cy, c.size, pose=c.pose)
    back = GBuffer.from_arrays(gb.depth, gb.world_normal, camera=posed, normal_space="world")
    np.testing.assert_allclose(back.normal, gb.normal, atol=1e-12)


def test_general_intrinsics_and_clip_planes_from_the_camera(scene):
    """An off-centre principal point and fx != fy (a crop of a sensor's image); near and far
    read from an OpenGL projection matrix by Camera.from_projection."""
    base = vo.Camera.look_at((4.0, 3.5, 5.0), (0.5, 0.0, 0.0), size=SIZE, fov_y=50.0)
    cam = vo.Camera.from_intrinsics(40.0, 36.0, 20.0, 21.0, SIZE, pose=base.pose)
    gb = vo.render_gbuffer(scene, cam)
    back = GBuffer.from_arrays(stored_depth(gb, "distance"), gb.normal, camera=cam, depth_kind="distance")
    np.testing.assert_allclose(back.depth[gb.valid], gb.depth[gb.valid], rtol=DEPTH_RTOL[np.float64])
    W, H = SIZE
    n, f = NEAR, FAR
    l, r = -cam.cx * n / cam.fx, (W - cam.cx) * n / cam.fx     # the frustum at the near plane
    t, b = cam.cy * n / cam.fy, -(H - cam.cy) * n / cam.fy
    P = np.array([[2 * n / (r - l), 0, (r + l) / (r - l), 0], [0, 2 * n / (t - b), (t + b) / (t - b), 0],
                  [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)], [0, 0, -1, 0]])
    projected = vo.Camera.from_projection(P, SIZE, convention="opengl", pose=base.pose)
    assert projected.near == pytest.approx(n) and projected.far == pytest.approx(f)
    X, Y, Z = np.moveaxis(np.asarray(gb.position), -1, 0)
    clip = np.einsum("ij,...j->...i", P, np.stack([X, Y, -Z, np.ones_like(Z)], -1))
    z_ndc = np.where(gb.valid, clip[..., 2] / clip[..., 3], 1.0)
    back = GBuffer.from_arrays(z_ndc, gb.normal, camera=projected, depth_kind="ndc")   # no near=, far=
    np.testing.assert_allclose(back.depth[gb.valid], gb.depth[gb.valid], rtol=1e-8)


def test_view_matrix_errors(rendered):
    gb = rendered
    V = glu_look_at(gb.camera)
    kw = dict(camera=gb.camera, normal_space="world")
    with pytest.raises(ValueError, match="view disagrees with the camera's pose"):
        GBuffer.from_arrays(gb.depth, gb.world_normal, view=V, convention="directx", **kw)
    with pytest.raises(ValueError, match=r"last row must be \(0, 0, 0, 1\).*transposed"):
        GBuffer.from_arrays(gb.depth, gb.world_normal, view=V.T, convention="opengl", **kw)
    with pytest.raises(ValueError, match="must be a rotation"):
        GBuffer.from_arrays(gb.depth, gb.world_normal, view=np.diag([2.0, 1, 1, 1]), **kw)
    with pytest.raises(ValueError, match=r"finite \(4, 4\)"):
        GBuffer.from_arrays(gb.depth, gb.world_normal, view=np.eye(3), **kw)
