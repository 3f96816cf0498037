"""Camera paths, reprojection with disocclusion, and temporal accumulation (vobscure.temporal).

Independent checks: orbit and dolly cameras against distances and angles computed here; the
reprojected position of a pixel against the previous frame's rendered world positions; the
pixels a camera move reveals against rays cast from the previous eye (the tracer, not the
depth test); the accumulation modes against hand-computed sequences.
"""

import json

import numpy as np
import pytest

import vobscure as vo
from vobscure.temporal import (Accumulator, camera_path, cameras_from_file, cameras_from_records, dolly_camera,
                               neighbourhood_moments, neighbourhood_range, orbit_camera, parse_accumulate,
                               reproject)

#: Exact float agreement is asked only where the same operations run in the same order; sums
#: of a few terms in another order agree to this.
SUM_ORDER_TOL = 1e-12


@pytest.fixture(scope="module")
def box():
    sc = vo.scenes.cornell_box()
    return sc, sc.camera(size=(32, 32))


# ----------------------------------------------------------------------------- paths
def test_static_path_repeats_the_camera(box):
    _, cam = box
    path = camera_path(cam, 4)
    assert len(path) == 4 and all(c == cam for c in path)


def test_orbit_turns_about_the_vertical_through_the_target(box):
    _, cam = box
    path = camera_path(cam, 5, "orbit", step=3.0)
    target = np.asarray(cam.to_dict()["target"])
    rel = [np.asarray(c.eye) - target for c in path]
    for a, b in zip(rel, rel[1:]):
        # same height, same distance to the vertical axis, 3 degrees apart about y
        assert a[1] == pytest.approx(b[1], abs=1e-12)
        ra, rb = np.hypot(a[0], a[2]), np.hypot(b[0], b[2])
        assert ra == pytest.approx(rb, rel=1e-12)
        cos = (a[0] * b[0] + a[2] * b[2]) / (ra * rb)
        assert np.degrees(np.arccos(np.clip(cos, -1, 1))) == pytest.approx(3.0, abs=1e-9)
    assert all(np.allclose(c.to_dict()["target"], target) for c in path)


def test_dolly_moves_along_the_view_direction(box):
    _, cam = box
    eye, target = np.asarray(cam.eye), np.asarray(cam.to_dict()["target"])
    length = np.linalg.norm(target - eye)
    path = camera_path(cam, 3, "dolly", step=0.1)
    for n, c in enumerate(path):
        assert np.linalg.norm(target - np.asarray(c.eye)) == pytest.approx(length * (1 - 0.1 * n), rel=1e-12)
    assert np.asarray(dolly_camera(cam, -1.0).eye) == pytest.approx(eye - (target - eye) / length)


@pytest.mark.parametrize("kwargs, match", [
    (dict(frames=0), "frames"), (dict(frames=2, motion="spin"), "motion"),
    (dict(frames=3, motion="orbit", step=-1.0), "step"), (dict(frames=30, motion="dolly", step=0.05), "target"),
])
def test_camera_path_errors(box, kwargs, match):
    with pytest.raises(ValueError, match=match):
        camera_path(box[1], **kwargs)


def test_orbit_needs_a_look_at_camera():
    cam = vo.Camera.from_intrinsics(10, 10, 4, 4, (8, 8))
    with pytest.raises(ValueError, match="look_at"):
        orbit_camera(cam, 5)


def test_cameras_from_file_round_trip(box, tmp_path):
    _, cam = box
    path = camera_path(cam, 3, "orbit", step=2.0)
    f = tmp_path / "path.json"
    f.write_text(json.dumps([c.to_dict() for c in path]))
    assert cameras_from_file(f) == path
    g = tmp_path / "wrapped.json"
    g.write_text(json.dumps({"cameras": [c.to_dict() for c in path]}))
    assert [c.size for c in cameras_from_file(g, size=(8, 6))] == [(8, 6)] * 3


def test_cameras_from_file_errors(box, tmp_path):
    with pytest.raises(ValueError, match="cannot be read"):
        cameras_from_file(tmp_path / "absent.json")
    bad = tmp_path / "bad.json"
    bad.write_text("[{")
    with pytest.raises(ValueError, match="not JSON"):
        cameras_from_file(bad)
    small = box[1].with_size((8, 8)).to_dict()
    with pytest.raises(ValueError, match="same size"):
        cameras_from_records([box[1].to_dict(), small])
    with pytest.raises(ValueError, match=r"records\[1\]"):
        cameras_from_records([box[1].to_dict(), {"eye": [0, 0, 1]}])


# ----------------------------------------------------------------------------- reprojection
def test_static_reprojection_is_the_identity(box):
    sc, cam = box
    gb = vo.render_gbuffer(sc, cam)
    h = np.where(gb.valid, np.linspace(0, 1, gb.valid.size).reshape(gb.shape), np.nan)
    count = np.where(gb.valid, 7, 0)
    r = reproject(h, gb, gb, count=count)
    assert r.found[gb.valid].all() and not r.found[~gb.valid].any()
    # the bilinear weights of a pixel centre are (1, 0, 0, 0)
    np.testing.assert_array_equal(r.value[gb.valid], h[gb.valid])
    np.testing.assert_array_equal(r.count[gb.valid], 7)
    assert not r.disoccluded.any()


def test_reprojected_position_lands_on_the_same_surface_point(box):
    # the previous frame's rendered world position at the pixel the reprojection names is the
    # current pixel's world position, to within the previous pixel's footprint
    sc, cam = box
    prev_cam, cur_cam = camera_path(cam, 2, "orbit", step=4.0)
    prev, cur = vo.render_gbuffer(sc, prev_cam), vo.render_gbuffer(sc, cur_cam)
    r = reproject(np.where(prev.valid, 0.5, np.nan), cur, prev, fetch="nearest")
    pix = r.source[r.found]
    i = np.clip(np.floor(pix[:, 1]).astype(int), 0, prev.shape[0] - 1)
    j = np.clip(np.floor(pix[:, 0]).astype(int), 0, prev.shape[1] - 1)
    dist = np.linalg.norm(prev.world_position[i, j] - cur.world_position[r.found], axis=1)
    # a pixel's footprint at depth z is 1 / pixels_per_unit(z); the nearest centre is within
    # sqrt(2)/2 pixel, and a surface seen obliquely stretches it by at most 1/|n_z|. Where two
    # surfaces meet (a box on the floor), the other one's pixel can pass the plane test: only
    # pixels whose tap sees a surface of the same orientation are held to the bound.
    same = np.einsum("ij,ij->i", prev.world_normal[i, j], cur.world_normal[r.found]) > 0.99
    footprint = 1.0 / prev.camera.pixels_per_unit(prev.depth[i, j])
    slant = 1.0 / np.maximum(np.abs(prev.normal[i, j, 2]), 0.2)
    assert np.all((dist <= footprint * slant)[same])
    assert same.sum() > 0.9 * r.found.sum() and r.found.sum() > 0.9 * cur.valid.sum()


def test_bilinear_reprojection_of_a_smooth_field(box):
    # a history equal to the world-space x coordinate comes back as the current pixels' world
    # x, to within one pixel's change of that field (bilinear interpolation error)
    sc, cam = box
    prev_cam, cur_cam = camera_path(cam, 2, "orbit", step=2.0)
    prev, cur = vo.render_gbuffer(sc, prev_cam), vo.render_gbuffer(sc, cur_cam)
    h = np.where(prev.valid, prev.world_position[..., 0], np.nan)
    r = reproject(h, cur, prev)
    step = np.nanmax(np.abs(np.diff(h, axis=1)[np.isfinite(np.diff(h, axis=1))]))
    diff = np.abs(r.value - cur.world_position[..., 0])[r.found]
    assert np.quantile(diff, 0.95) <= step
    assert r.found.sum() > 0.9 * cur.valid.sum()


def test_motion_vectors_are_read_when_given(box):
    # motion vectors of zero make the reprojection the identity even when the cameras differ
    sc, cam = box
    prev_cam, cur_cam = camera_path(cam, 2, "orbit", step=4.0)
    prev = vo.render_gbuffer(sc, prev_cam)
    cur = vo.render_gbuffer(sc, cur_cam).with_motion(np.zeros(prev.shape + (2,)))
    h = np.where(prev.valid, 0.25, np.nan)
    r = reproject(h, cur, prev)
    expect = cur.valid & prev.valid & (np.abs(prev.depth - cur.depth) <= 0.01 * cur.depth)
    np.testing.assert_array_equal(r.found, expect)


def test_from_arrays_motion_with_lower_origin_flips_rows_and_dy():
    cam = vo.Camera.look_at((0, 0, 3), (0, 0, 0), size=(3, 2))
    m = np.zeros((2, 3, 2))
    m[0, :, 1] = 1.0      # the bottom row of a y-up image moves up by one
    gb = vo.GBuffer.from_arrays(np.full((2, 3), 3.0), camera=cam, origin="lower", motion=m)
    assert gb.motion[1, 0, 1] == -1.0 and gb.motion[0, 0, 1] == 0.0


def test_reproject_errors(box):
    sc, cam = box
    gb = vo.render_gbuffer(sc, cam)
    with pytest.raises(ValueError, match="history"):
        reproject(np.zeros((3, 3)), gb, gb)
    with pytest.raises(ValueError, match="fetch"):
        reproject(np.zeros(gb.shape), gb, gb, fetch="cubic")
    with pytest.raises(ValueError, match="depth_tolerance"):
        reproject(np.zeros(gb.shape), gb, gb, depth_tolerance=0)
    with pytest.raises(ValueError, match="previous"):
        reproject(np.zeros(gb.shape), gb, "gb")
    with pytest.raises(ValueError, match="motion"):
        gb.with_motion(np.zeros((2, 2, 2)))


# ----------------------------------------------------------------------------- disocclusion
def _hidden_from(scene, eye, points):
    """True where the segment from ``eye`` to a point hits something first (ray cast)."""
    d = points - eye
    length = np.linalg.norm(d, axis=1)
    return scene.tracer.occluded(np.broadcast_to(eye, points.shape).copy(), d / length[:, None],
                                 length * (1 - 1e-3))


def test_revealed_pixels_restart_their_history():
    sc = vo.scenes.sphere_on_plane()
    cam = sc.camera(size=(48, 48))
    prev_cam, cur_cam = camera_path(cam, 2, "orbit", step=25.0)
    prev, cur = vo.render_gbuffer(sc, prev_cam), vo.render_gbuffer(sc, cur_cam)
    acc = Accumulator("mean")
    acc.update(np.where(prev.valid, 0.9, np.nan), prev)
    x = np.where(cur.valid, 0.1, np.nan)
    out = acc.update(x, cur)
    hidden = np.zeros(cur.shape, bool)
    hidden[cur.valid] = _hidden_from(sc, np.asarray(prev_cam.eye), cur.world_position[cur.valid])
    # away from the silhouettes (every 3 x 3 neighbour alike) the answer is unambiguous
    from scipy import ndimage

    revealed = ndimage.binary_erosion(hidden & cur.valid, np.ones((3, 3)))
    seen = ndimage.binary_erosion(~hidden & cur.valid, np.ones((3, 3)), border_value=0)
    r = reproject(np.where(prev.valid, 0.9, np.nan), cur, prev)
    inside = np.isfinite(r.source[..., 0]) & (r.source[..., 0] > 2) & (r.source[..., 0] < 46) \
        & (r.source[..., 1] > 2) & (r.source[..., 1] < 46)
    seen &= inside
    assert revealed.sum() >= 10 and seen.sum() >= 200
    np.testing.assert_array_equal(acc.count[revealed], 1)
    np.testing.assert_array_equal(out[revealed], 0.1)
    np.testing.assert_array_equal(acc.count[seen], 2)
    np.testing.assert_allclose(out[seen], 0.5, atol=SUM_ORDER_TOL)


# ----------------------------------------------------------------------------- accumulation
@pytest.fixture(scope="module")
def slab_gb():
    return vo.render_gbuffer(vo.scenes.slab(), vo.Camera.look_at((0, 2, 1), (0, 0, 0), size=(6, 5)))


def _run(acc, gb, values):
    return [acc.update(np.where(gb.valid, v, np.nan), gb) for v in values]


def test_running_mean_of_a_static_sequence(slab_gb):
    rng = np.random.default_rng(3)
    frames = [np.where(slab_gb.valid, rng.random(slab_gb.shape), np.nan) for _ in range(9)]
    acc = Accumulator("mean")
    for f in frames:
        out = acc.update(f, slab_gb)
    np.testing.assert_allclose(out[slab_gb.valid], np.mean(frames, axis=0)[slab_gb.valid], atol=SUM_ORDER_TOL)
    assert np.isnan(out[~slab_gb.valid]).all() and acc.count.max() == 9


def test_ema_weights_by_hand(slab_gb):
    # alpha 0.5: weights max(0.5, 1/n) -> 1, 1/2, 1/2, 1/2: 1, 0.5, 0.25, 0.125
    outs = _run(Accumulator("ema:0.5"), slab_gb, [1.0, 0.0, 0.0, 0.0])
    assert [float(np.nanmax(o)) for o in outs] == [1.0, 0.5, 0.25, 0.125]
    # alpha 0.2: the running mean until 1/n < 0.2 -> 1, 1/2, 1/3, 1/4, 1/5 then 0.2
    outs = _run(Accumulator("ema:0.2"), slab_gb, [1.0] + [0.0] * 5)
    expect = [1.0, 0.5, 1 / 3, 0.25, 0.2, 0.16]
    np.testing.assert_allclose([float(np.nanmax(o)) for o in outs], expect, rtol=SUM_ORDER_TOL)


def test_neighbourhood_clamp_bounds_the_history(slab_gb):
    acc = Accumulator("mean", clamp=True)
    _run(acc, slab_gb, [1.0])
    new = np.where(slab_gb.valid, 0.2, np.nan)
    new[2, 2] = 0.4
    out = acc.update(new, slab_gb)
    # the history 1.0 is clamped to each pixel's 3 x 3 maximum: 0.4 next to (2, 2), else 0.2
    near = np.zeros(slab_gb.shape, bool)
    near[1:4, 1:4] = True
    np.testing.assert_allclose(out[near & (new == 0.2)], 0.3, atol=SUM_ORDER_TOL)
    np.testing.assert_allclose(out[~near & slab_gb.valid], 0.2, atol=SUM_ORDER_TOL)


def test_neighbourhood_statistics_by_hand():
    img = np.array([[0.0, 1.0, 2.0], [3.0, np.nan, 5.0], [6.0, 7.0, 8.0]])
    lo, hi = neighbourhood_range(img)
    assert lo[1, 1] == 0.0 and hi[1, 1] == 8.0 and lo[0, 0] == 0.0 and hi[0, 0] == 3.0
    mean, std = neighbourhood_moments(img)
    vals = np.array([0, 1, 2, 3, 5, 6, 7, 8.0])
    assert mean[1, 1] == pytest.approx(vals.mean()) and std[1, 1] == pytest.approx(vals.std())


def test_variance_clipping_by_hand(slab_gb):
    acc = Accumulator("clip:0.5")
    _run(acc, slab_gb, [1.0])
    rng = np.random.default_rng(0)
    new = np.where(slab_gb.valid, 0.3 + 0.1 * rng.random(slab_gb.shape), np.nan)
    out = acc.update(new, slab_gb)
    mean, std = neighbourhood_moments(new)
    clipped = np.minimum(1.0, mean + std)
    expect = clipped + 0.5 * (new - clipped)
    np.testing.assert_allclose(out[slab_gb.valid], expect[slab_gb.valid], atol=SUM_ORDER_TOL)


def test_in_place_history_without_reprojection(box):
    sc, cam = box
    prev_cam, cur_cam = camera_path(cam, 2, "orbit", step=10.0)
    prev, cur = vo.render_gbuffer(sc, prev_cam), vo.render_gbuffer(sc, cur_cam)
    acc = Accumulator("mean", reproject=False)
    acc.update(np.where(prev.valid, 1.0, np.nan), prev)
    out = acc.update(np.where(cur.valid, 0.0, np.nan), cur)
    both = prev.valid & cur.valid
    np.testing.assert_array_equal(out[both], 0.5)


def test_denoise_after_leaves_the_history_unblurred(slab_gb):
    rng = np.random.default_rng(1)
    frames = [np.where(slab_gb.valid, rng.random(slab_gb.shape), np.nan) for _ in range(3)]
    plain, after = Accumulator("mean"), Accumulator("mean", denoise="after", denoise_options=dict(radius_px=1))
    for f in frames:
        a = plain.update(f, slab_gb)
        b = after.update(f, slab_gb)
    np.testing.assert_array_equal(after.history, plain.history)
    np.testing.assert_allclose(b, vo.bilateral_blur(a, slab_gb, radius_px=1), atol=SUM_ORDER_TOL)


@pytest.mark.parametrize("spec, match", [
    ("ema", "needs an alpha"), ("ema:0", r"\(0, 1\]"), ("clip:x", "not a number"), ("mean:0.1", "no alpha"),
    ("median", "accumulate"), (3, "accumulate"),
])
def test_parse_accumulate_errors(spec, match):
    with pytest.raises(ValueError, match=match):
        parse_accumulate(spec)


def test_update_errors(slab_gb):
    acc = Accumulator()
    with pytest.raises(ValueError, match="shape"):
        acc.update(np.zeros((2, 2)), slab_gb)
    with pytest.raises(ValueError, match="finite"):
        acc.update(np.full(slab_gb.shape, np.inf), slab_gb)
    with pytest.raises(ValueError, match="GBuffer"):
        acc.update(np.zeros(slab_gb.shape), None)
    with pytest.raises(ValueError, match="denoise"):
        Accumulator(denoise="during")
    with pytest.raises(ValueError, match="reproject"):
        Accumulator(reproject="no")
