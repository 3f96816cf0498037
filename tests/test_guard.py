"""The guard band: render_gbuffer(..., guard=P) renders a wider frame whose inner pixels are the
unguarded render's rays; the estimators and the ground truth return the inner frame."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.screenspace import _common as C

#: Guard width of the tests: a multiple of the noise texture's edge (4), so the per-pixel
#: random rotations of the inner pixels are those of the unguarded render.
GUARD = 8
#: Interior pixels of a guarded and an unguarded estimate differ only by the rounding of the
#: tap's pixel coordinate (j + P + 0.5 + dx - (cx + P) against j + 0.5 + dx - cx, a few ulps
#: of the image's width); a visibility is a sum of a few dozen terms in [0, 1].
INTERIOR_ATOL = 1e-9
#: Orthographic: the widened camera's view height (ortho_height (H + 2P) / H) rounds, so its
#: ray origins differ from the unguarded ones by a few float64 ulps, which can move the
#: float32 origin Embree gets by one float32 ulp (eps32 |o|, |o| <= 12 on this view) and the
#: depth by that times the surface's slope along the view (< 4 on the crease's oblique view).
ORTHO_DEPTH_ATOL = 4.0 * 12.0 * 2.0 * np.finfo(np.float32).eps


@pytest.fixture(scope="module")
def box_camera():
    return vo.scenes.cornell_box().camera((40, 30))


@pytest.fixture(scope="module")
def box():
    return vo.scenes.cornell_box()


@pytest.fixture(scope="module")
def pair(box, box_camera):
    return vo.render_gbuffer(box, box_camera), vo.render_gbuffer(box, box_camera, guard=GUARD)


def test_widened_camera_shape_and_principal_point(box_camera):
    wide = box_camera.widened(GUARD)
    assert wide.size == (40 + 2 * GUARD, 30 + 2 * GUARD)
    assert (wide.cx, wide.cy) == (box_camera.cx + GUARD, box_camera.cy + GUARD)
    assert (wide.fx, wide.fy) == (box_camera.fx, box_camera.fy)
    assert box_camera.widened(0) is box_camera


def test_inner_pixels_are_the_unguarded_render_bit_for_bit(pair, box_camera):
    plain, guarded = pair
    assert guarded.guard == GUARD and guarded.shape == (30 + 2 * GUARD, 40 + 2 * GUARD)
    inner = guarded.inner()
    assert inner.camera == box_camera and inner.guard == 0 and inner.shape == plain.shape
    # the same float operations on the same rays: exactly equal
    for name in ("depth", "normal", "valid", "primitive", "position", "world_position",
                 "world_normal", "world_geometric_normal"):
        np.testing.assert_array_equal(getattr(inner, name), getattr(plain, name), err_msg=name)
    for key, value in plain.hits.items():
        np.testing.assert_array_equal(inner.hits[key], value, err_msg=key)
    # the guard band itself sees more of the scene
    assert guarded.valid.sum() > plain.valid.sum()


def test_orthographic_inner_pixels_agree_to_rounding(crease):
    cam = vo.Camera.look_at((3.0, 2.5, 5.0), (0.5, 0.5, 0.0), size=(24, 20), ortho_height=3.0)
    plain = vo.render_gbuffer(crease, cam)
    inner = vo.render_gbuffer(crease, cam, guard=5).inner()
    np.testing.assert_array_equal(inner.valid, plain.valid)
    np.testing.assert_allclose(inner.depth[plain.valid], plain.depth[plain.valid], rtol=0,
                               atol=ORTHO_DEPTH_ATOL)


@pytest.mark.parametrize("name", ["vo_line", "vo_point", "gtao", "vbao", "hbao", "sao", "vo_area"])
def test_estimators_return_the_inner_frame(pair, name):
    plain, guarded = pair
    estimator = getattr(vo, name)
    radius = 0.25
    a = estimator(plain, radius=radius)
    b = estimator(guarded, radius=radius)
    assert b.shape == plain.shape and b.dtype == a.dtype
    # away from the border (farther than any tap reaches) the guard changes nothing
    H, W = plain.shape
    reach = int(np.ceil(np.nanmax(radius * plain.camera.fy / plain.depth))) + 2
    assert reach < min(H, W) // 2
    core = (slice(reach, H - reach), slice(reach, W - reach))
    np.testing.assert_allclose(b[core], a[core], rtol=0, atol=INTERIOR_ATOL)
    np.testing.assert_array_equal(np.isnan(b), np.isnan(a))


def test_guard_changes_border_pixels(pair):
    plain, guarded = pair
    a = vo.vo_line(plain, radius=0.25)
    b = vo.vo_line(guarded, radius=0.25)
    border = np.ones(plain.shape, dtype=bool)
    border[4:-4, 4:-4] = False
    assert np.nanmax(np.abs(a - b)[border]) > 0.01


def test_reference_estimate_is_cropped(pair):
    _, guarded = pair
    est = vo.vo_reference(guarded, radius=0.25, samples=64)
    assert est.value.shape == est.stderr.shape == guarded.inner().shape


def test_ground_truth_computes_the_inner_frame(box, pair):
    plain, guarded = pair
    a = vo.ground_truth(box, plain, quantity="ao", radius=0.5, rays=16, seed=3)
    b = vo.ground_truth(box, guarded, quantity="ao", radius=0.5, rays=16, seed=3)
    # the same points, normals and seed: the same rays, the same numbers
    np.testing.assert_array_equal(b.value, a.value)
    np.testing.assert_array_equal(b.stderr, a.stderr)


def test_registry_runs_on_a_guarded_gbuffer(pair):
    _, guarded = pair
    out = vo.methods.get("line").run(guarded, 5, radius=0.25)
    assert out.shape == guarded.inner().shape


def test_crop_guard_rejects_a_foreign_shape(pair):
    _, guarded = pair
    with pytest.raises(ValueError, match="inner frame"):
        C.crop_guard(np.zeros((3, 3)), guarded)


@pytest.mark.parametrize("guard", [-1, 1.5, True, "2"])
def test_bad_guard(box, box_camera, guard):
    with pytest.raises(ValueError, match="guard"):
        vo.render_gbuffer(box, box_camera.with_size((8, 6)), guard=guard)


def test_inner_of_an_unguarded_gbuffer_is_itself(pair):
    plain, _ = pair
    assert plain.inner() is plain and plain.guard == 0


def test_inner_keeps_the_peeled_layers_of_the_inner_pixels():
    """A guarded layered render: the inner G-buffer's intervals and surfaces are those of an
    unguarded layered render of the inner camera."""
    sc = vo.scenes.cornell_box()
    cam = vo.Camera.look_at((0.2, 1.0, 0.6), (-0.3, 0.7, -1.0), size=(24, 16), fov_y=60.0)
    plain = vo.render_gbuffer(sc, cam, layers=3)
    inner = vo.render_gbuffer(sc, cam, layers=3, guard=4).inner()
    np.testing.assert_array_equal(inner.intervals.front, plain.intervals.front)
    np.testing.assert_array_equal(inner.intervals.back, plain.intervals.back)
    np.testing.assert_array_equal(inner.intervals.layers.depth, plain.intervals.layers.depth)
    np.testing.assert_array_equal(inner.intervals.layers.primitive, plain.intervals.layers.primitive)
