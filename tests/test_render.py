"""render_gbuffer (Embree primary rays) against analytic planes under both projections, normals,
background, one pixel, bad arguments and real meshes."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo

from conftest import MESH_DIR

#: Embree's float32 barycentrics place a hit within ~1e-7 of the true point along the plane.
DEPTH_RTOL = 1e-5
UNIT_ATOL = 1e-12


def _analytic_plane_depth(cam, plane_y=0.0):
    """Depth of the plane y = plane_y through every pixel centre, or inf where not hit."""
    o, d = cam.primary_rays()
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (plane_y - o[..., 1]) / d[..., 1]
    p = o + t[..., None] * d
    depth = cam.world_to_view(p)[..., 2]
    return np.where(t > 0, depth, np.inf), p


@pytest.mark.parametrize("kind", ["perspective", "orthographic"])
def test_slab_depth_matches_plane(slab, kind):
    lens = dict(fov_y=50.0) if kind == "perspective" else dict(ortho_height=3.0)
    cam = vo.Camera.look_at((0.3, 2.5, 2.0), (0.0, 0.0, -0.2), size=(40, 30), **lens)
    gb = vo.render_gbuffer(slab, cam)
    expect, p = _analytic_plane_depth(cam)
    on_top = np.isfinite(expect) & (np.abs(p[..., 0]) < 3.9) & (np.abs(p[..., 2]) < 3.9)
    assert on_top.sum() > 0.5 * on_top.size
    np.testing.assert_allclose(gb.depth[on_top], expect[on_top], rtol=DEPTH_RTOL)
    np.testing.assert_allclose(gb.world_position[on_top][:, 1], 0.0, atol=1e-12)
    # view-space normal of the top face: the world +y rotated into view, facing the camera
    n_view = cam.world_to_view_dir(np.array([0.0, 1.0, 0.0]))
    np.testing.assert_allclose(gb.normal[on_top], np.broadcast_to(n_view, gb.normal[on_top].shape), atol=1e-12)
    assert np.all(gb.normal[on_top][:, 2] < 0)
    # position is depth-consistent and unprojects from the pixel centres
    np.testing.assert_allclose(gb.position[..., 2][gb.valid], gb.depth[gb.valid], rtol=1e-12)
    back = cam.unproject(cam.pixel_centers()[gb.valid], gb.depth[gb.valid])
    np.testing.assert_allclose(back, gb.position[gb.valid], rtol=1e-5, atol=1e-5 * slab.extent)


def test_background_convention(slab):
    # camera looking up into the sky: everything is background
    cam = vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(8, 6))
    gb = vo.render_gbuffer(slab, cam)
    assert not gb.valid.any()
    assert np.all(np.isposinf(gb.depth))
    assert np.all(gb.normal == 0) and np.all(gb.world_normal == 0)
    assert np.all(np.isnan(gb.position)) and gb.primitive.max() == -1


def test_unit_camera_facing_normals_on_smooth_mesh():
    scene = vo.scenes.blob(subdivisions=3)
    gb = vo.render_gbuffer(scene, scene.camera((48, 40)))
    assert gb.valid.sum() > 200
    for field in (gb.normal, gb.geometric_normal, gb.world_normal, gb.world_geometric_normal):
        np.testing.assert_allclose(np.linalg.norm(field[gb.valid], axis=-1), 1.0, atol=UNIT_ATOL)
        assert np.all(field[~gb.valid] == 0)
    assert np.all(gb.normal[gb.valid][:, 2] < 0)
    assert np.all(gb.geometric_normal[gb.valid][:, 2] < 0)
    # smooth shading: interpolated normals differ from the facets somewhere, but stay close
    cosang = np.einsum("ij,ij->i", gb.normal[gb.valid], gb.geometric_normal[gb.valid])
    assert cosang.min() < 1 - 1e-6 and np.median(cosang) > 0.95
    # world and view fields are the same vectors
    np.testing.assert_allclose(gb.camera.world_to_view_dir(gb.world_normal[gb.valid]), gb.normal[gb.valid],
                               atol=1e-12)


def test_one_pixel_and_float32(slab):
    cam = vo.Camera.look_at((0, 2, 2), (0, 0, 0), size=(1, 1))
    gb = vo.render_gbuffer(slab, cam)
    assert gb.depth.shape == (1, 1) and gb.valid[0, 0]
    np.testing.assert_allclose(gb.depth[0, 0], np.sqrt(8.0), rtol=DEPTH_RTOL)
    g32 = gb.astype(np.float32)
    assert g32.depth.dtype == np.float32 and g32.valid[0, 0]


def test_render_bad_arguments(slab):
    cam = vo.Camera.look_at((0, 2, 2), (0, 0, 0), size=(2, 2))
    with pytest.raises(ValueError, match="camera"):
        vo.render_gbuffer(slab, "camera")
    with pytest.raises(ValueError, match="scene"):
        vo.render_gbuffer(42, cam)


MESHES = sorted(MESH_DIR.glob("*.obj")) if MESH_DIR.is_dir() else []


@pytest.mark.skipif(not MESHES, reason=f"real meshes not found in {MESH_DIR}")
@pytest.mark.parametrize("path", MESHES, ids=lambda p: p.stem)
def test_real_meshes_render(path):
    scene = vo.scenes.load(path)
    gb = vo.render_gbuffer(scene, scene.camera((64, 48)))
    assert gb.valid.mean() > 0.05, "the suggested camera should see the mesh"
    assert np.all(np.isfinite(gb.depth[gb.valid])) and np.all(gb.depth[gb.valid] > 0)
    np.testing.assert_allclose(np.linalg.norm(gb.normal[gb.valid], axis=-1), 1.0, atol=UNIT_ATOL)
    ref = vo.ground_truth(scene, gb, quantity="ao", radius=0.2 * scene.extent, rays=16, progress=False)
    assert np.all((ref.value[gb.valid] >= 0) & (ref.value[gb.valid] <= 1))
    assert np.array_equal(np.isnan(ref.value), ~gb.valid)
