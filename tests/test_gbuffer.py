"""The GBuffer container: world-space data derived from depth and normals through the pose (or
a given view frame), the lazy images and their read-only views, per_pixel, bad input, and the
names ``vobscure.gbuffer`` exports."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.gbuffer import GBuffer

#: World positions unprojected from float64 depths and mapped back through the pose: rounding
#: of a few operations on coordinates of size ~5.
WORLD_ATOL = 1e-12


def _plane_view(cam):
    """Depth, view-space normal and world position of the plane y = 0 through every pixel
    centre, from the camera's own primary rays (no GBuffer code): inf / 0 / NaN off the plane."""
    o, d = cam.primary_rays()
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -o[..., 1] / d[..., 1]
    hit = t > 0
    p = np.where(hit[..., None], o + t[..., None] * d, np.nan)
    depth = np.where(hit, cam.world_to_view(np.where(hit[..., None], p, 0.0))[..., 2], np.inf)
    normal = np.where(hit[..., None], cam.world_to_view_dir(np.array([0.0, 1.0, 0.0])), 0.0)
    return depth, normal, hit, p


@pytest.fixture(scope="module")
def plane():
    cam = vo.Camera.look_at((1.0, 1.0, 3.0), (0.0, 0.6, 0.0), size=(9, 7), fov_y=70.0)
    depth, normal, hit, p = _plane_view(cam)
    assert 0 < hit.sum() < hit.size        # the plane and the sky both in view
    gb = GBuffer(cam, depth=depth, normal=normal, valid=hit, primitive=np.full(hit.shape, -1), hits=None)
    return gb, p


def test_world_data_derived_from_depth_and_pose(plane):
    gb, p = plane
    v = gb.valid
    np.testing.assert_array_equal(gb.hits["index"], np.flatnonzero(v))
    np.testing.assert_allclose(gb.world_position[v], p[v], rtol=0, atol=WORLD_ATOL)
    np.testing.assert_allclose(gb.world_normal[v], np.broadcast_to([0.0, 1.0, 0.0], (v.sum(), 3)),
                               rtol=0, atol=WORLD_ATOL)
    assert np.all(np.isnan(gb.world_position[~v])) and np.all(gb.world_normal[~v] == 0)
    # without per-hit data the geometric normal is the normal, the position unprojected
    assert gb.geometric_normal is gb.normal
    np.testing.assert_allclose(gb.position[..., 2][v], gb.depth[v], rtol=1e-15)
    assert np.all(np.isnan(gb.position[~v]))


def test_view_frame_replaces_the_pose(plane):
    gb, _ = plane
    # the identity frame: world space is view space
    same = GBuffer(gb.camera, depth=gb.depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive,
                   hits=None, view_to_world=(np.eye(3), np.zeros(3)))
    np.testing.assert_array_equal(same.world_position, same.position)
    np.testing.assert_array_equal(same.world_normal, same.normal)


def test_world_data_without_a_pose_is_an_error(plane):
    gb, _ = plane
    cam = gb.camera
    bare = vo.Camera.from_intrinsics(cam.fx, cam.fy, cam.cx, cam.cy, cam.size)
    no_pose = GBuffer(bare, depth=gb.depth, normal=gb.normal, valid=gb.valid, primitive=gb.primitive,
                      hits=None)
    np.testing.assert_array_equal(no_pose.position, gb.position)   # view space needs no pose
    with pytest.raises(ValueError, match="pose"):
        no_pose.world_position
    with pytest.raises(ValueError, match="normals"):
        GBuffer(cam, depth=gb.depth, normal=None, valid=gb.valid, primitive=gb.primitive, hits=None)


def test_per_pixel(plane):
    gb, p = plane
    img = gb.per_pixel(lambda points, normals: points[:, 0] + normals[:, 1])
    np.testing.assert_allclose(img[gb.valid], p[gb.valid][:, 0] + 1.0, rtol=0, atol=WORLD_ATOL)
    assert np.all(np.isnan(img[~gb.valid]))
    empty = GBuffer(gb.camera, depth=np.full(gb.shape, np.inf), normal=np.zeros(gb.shape + (3,)),
                    valid=np.zeros(gb.shape, bool), primitive=gb.primitive, hits=None)

    def never(points, normals):
        raise AssertionError("called on an empty frame")

    assert np.all(np.isnan(empty.per_pixel(never)))


def test_names_of_vobscure_gbuffer():
    import vobscure.convert
    import vobscure.gbuffer
    import vobscure.render

    assert vobscure.render.render_gbuffer is vo.render_gbuffer
    with pytest.warns(DeprecationWarning, match="vobscure.render_gbuffer"):
        assert vobscure.gbuffer.render_gbuffer is vo.render_gbuffer
    for name in ("DEPTH_KINDS", "NORMAL_SPACES", "NORMAL_ENCODINGS", "CONVENTIONS", "NORMAL_LENGTH_TOL",
                 "NORMAL_ZERO_TOL", "VIEW_TOL", "CENTRAL_RATIO", "NORMAL_BAND_ROWS",
                 "NormalsRenormalizedWarning", "NormalsRepairedWarning"):
        assert getattr(vobscure.gbuffer, name) is getattr(vobscure.convert, name), name
    assert vo.NormalsRenormalizedWarning is vobscure.convert.NormalsRenormalizedWarning
    with pytest.raises(AttributeError, match="no attribute 'renderer'"):
        vobscure.gbuffer.renderer


def test_hits_match_images_and_lazy_fields_are_read_only():
    scene = vo.scenes.sphere_on_plane(subdivisions=2)
    gb = vo.render_gbuffer(scene, scene.camera((37, 23)))
    hits = gb.hits
    np.testing.assert_array_equal(hits["index"], np.flatnonzero(gb.valid))
    for key in ("world_position", "world_normal", "world_geometric_normal"):
        np.testing.assert_array_equal(getattr(gb, key).reshape(-1, 3)[hits["index"]], hits[key])
    np.testing.assert_allclose(gb.camera.world_to_view(hits["world_position"]),
                               gb.position.reshape(-1, 3)[hits["index"]], atol=1e-12)
    for field in (gb.depth, gb.normal, gb.position, gb.world_position, gb.valid):
        assert not field.flags.writeable
    with pytest.raises(ValueError):
        gb.depth[0, 0] = 1.0
    g32 = gb.astype(np.float32)
    assert g32.world_position.dtype == np.float32 and g32.normal.dtype == np.float32
    np.testing.assert_allclose(g32.depth[gb.valid], gb.depth[gb.valid], rtol=1e-6)


def test_has_hit_data_tells_rendered_from_derived():
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
    gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    assert gb.has_hit_data and gb.astype(np.float32).has_hit_data
    assert not vo.GBuffer.from_arrays(gb.depth, camera=cam).has_hit_data
