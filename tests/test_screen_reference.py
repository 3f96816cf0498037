"""The converged screen-space VO (vo_reference) as segments along view rays, against an
independent computation of the same occupancy integral: the stratified point sampling of
the ball (vobscure.screenspace.point._reference with along="point", each point's occupancy
tested on its own). Closed forms of the crease: test_point.py."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.estimate import DEFAULT_GROUPS
from vobscure.screenspace import point as P

from conftest import FALSE_FAILURE, INSIDE_RADIUS, INSIDE_SIZE, inside_views, t_threshold

#: Views inside the Cornell box (conftest.INSIDE_VIEWS).
SIZE, RADIUS = INSIDE_SIZE, INSIDE_RADIUS
#: Rays of the segments and points of the independent point sampling.
SEGMENTS, POINTS = 256, 512
#: Below this stderr both computations agree that a pixel is exact (a plane in the ball):
#: there the values must agree to PLANE_TOL instead (the depth buffer holds Embree's
#: float32 hits, so a plane's occupancy is exact to ~1e-6).
EXACT_STDERR, PLANE_TOL = 1e-6, 1e-4
CASES = [dict(), dict(normal_clamp=True), dict(thickness=0.1), dict(falloff="quadratic"),
         dict(falloff="quadratic", normal_clamp=True), dict(fetch="nearest"), dict(offscreen="open"),
         dict(normal_clamp=True, thickness=0.05, fetch="nearest", offscreen="open")]
#: Every call of _agree is one test; Bonferroni over the pixels and the calls of this module.
CALLS = 2 * len(CASES) + 3


@pytest.fixture(scope="module")
def views():
    return inside_views()


def _both(gb, radius=RADIUS, seed=0, **kw):
    args = dict(radius=radius, normal_clamp=False, thickness=None, falloff="constant", fetch="bilinear",
                offscreen="clamp", groups=DEFAULT_GROUPS, progress=False)
    args.update(kw)
    seg = P._reference(gb, samples=SEGMENTS, seed=seed, along="segment", **args)
    pts = P._reference(gb, samples=POINTS, seed=seed + 1, along="point", **args)
    return seg, pts


def _agree(seg, pts, valid):
    """Per-pixel t-test of the difference with both reported stderrs (Welch's degrees of
    freedom are at least groups - 1, so that quantile is conservative), Bonferroni over the
    pixels and the module's tests; pixels both call exact must agree to PLANE_TOL. Where every
    group of points reads 0 or 1 the points report a stderr of 0 although they may all have
    missed a part of the ball smaller than about one point's share: their error there is taken
    as one step of a group mean."""
    groups = DEFAULT_GROUPS
    step = 1.0 / ((pts.samples // groups) * np.sqrt(groups))
    missed = (pts.stderr == 0) & ((pts.value == 0) | (pts.value == 1))
    s = np.hypot(seg.stderr, np.where(missed, step, pts.stderr))[valid]
    diff = (seg.value - pts.value)[valid]
    exact = s < EXACT_STDERR
    assert np.all(np.abs(diff[exact]) < PLANE_TOL), np.abs(diff[exact]).max()
    z = diff[~exact] / s[~exact]
    limit = t_threshold(DEFAULT_GROUPS - 1, tests=CALLS * valid.sum(), false_failure=FALSE_FAILURE)
    assert np.max(np.abs(z)) < limit, (np.abs(z).max(), limit)
    return z


@pytest.mark.parametrize("view", ["perspective", "orthographic"])
@pytest.mark.parametrize("case", range(len(CASES)), ids=lambda i: ",".join(f"{k}={v}" for k, v in CASES[i].items())
                         or "default")
def test_segments_agree_with_point_sampling(views, view, case):
    gb = views[view]
    seg, pts = _both(gb, **CASES[case])
    assert np.isnan(seg.value[~gb.valid]).all() and np.isfinite(seg.value[gb.valid]).all()
    _agree(seg, pts, gb.valid)


def test_segments_have_less_noise_than_points_of_the_same_count(views):
    """The point of the construction: one dimension integrated exactly. At equal counts the
    mean reported stderr of the segments is below the points' (measured ratio ~0.5 here)."""
    gb = views["perspective"]
    args = dict(radius=RADIUS, normal_clamp=False, thickness=None, falloff="constant", fetch="bilinear",
                offscreen="clamp", groups=DEFAULT_GROUPS, progress=False)
    seg = P._reference(gb, samples=POINTS, seed=3, along="segment", **args)
    pts = P._reference(gb, samples=POINTS, seed=3, along="point", **args)
    assert np.mean(seg.stderr[gb.valid]) < np.mean(pts.stderr[gb.valid])


@pytest.mark.parametrize("radius", [1e-2, 50.0])
def test_extreme_radii(views, radius):
    """A small ball sees its tangent plane only, away from the box's edges (1/2, 1
    clamped: the control variate and the clamp make it exact); a huge one holds the eye,
    where the perspective pixels are point sampled (the fallback), still agreeing."""
    gb = views["perspective"]
    seg, pts = _both(gb, radius=radius)
    _agree(seg, pts, gb.valid)
    if radius < 1:
        plane = gb.valid & (seg.value == 0.5)
        assert plane.sum() > 0.5 * gb.valid.sum()       # the walls away from the edges (57 %)
        assert np.max(np.abs(seg.value[plane] - 0.5)) < PLANE_TOL
        clamped = vo.vo_reference(gb, radius=radius, samples=64, normal_clamp=True)
        assert np.max(np.abs(clamped.value[plane] - 1.0)) < PLANE_TOL


def test_float32_gbuffer(views):
    gb = views["orthographic"].astype(np.float32)
    seg, pts = _both(gb)
    assert seg.value.dtype == np.float32 and seg.stderr.dtype == np.float32
    _agree(seg, pts, gb.valid)


def test_one_pixel_and_an_empty_view():
    scene = vo.scenes.cornell_box()
    one = vo.render_gbuffer(scene, vo.Camera.look_at((0, 1, 0.5), (0, 1, -1), size=(1, 1), fov_y=40))
    e = vo.vo_reference(one, radius=RADIUS, samples=64)
    assert e.value.shape == (1, 1) and 0 < e.value[0, 0] < 1 and e.stderr[0, 0] > 0
    empty = vo.render_gbuffer(scene, vo.Camera.look_at((0, 1, 5), (0, 1, 10), size=(6, 4), fov_y=40))
    assert not empty.valid.any()
    e = vo.vo_reference(empty, radius=RADIUS, samples=64)
    assert np.isnan(e.value).all() and np.isnan(e.stderr).all()


#: The fast segment kernel against the plain one: the same rays and closed forms with the
#: operations regrouped (the segment's ends cubed, a bilinear polynomial per cell of
#: reciprocals) and the bilinear depth interpolated in float32, the depth buffer's own
#: precision (``_segment_fast.DepthCells``): a fetched depth moves by at most FETCH_ROUNDING of
#: itself. A ray's term moves by at most z^2 |dd| times the box's area over the rays and the
#: ball's weight; the box of rays through a ball at depth z spans about pi R^2 / z^2 of
#: directions and the ball weighs 4 pi R^3 / 3, so a value moves by at most about
#: 0.75 FETCH_ROUNDING z / R: the tolerance takes the view's largest depth (measured: at most
#: 1.3e-7 on these views, where the bound is 2e-6 to 4e-6; the stderrs are above 1e-4). With
#: ``fetch="nearest"`` nothing is interpolated: a few ulps (measured 2e-16).
FETCH_ROUNDING = 4e-7
#: With the default options under perspective the fast kernel also computes each ray's chord
#: (z_m -+ h) and the tangent plane's depth along it in float32
#: (``_segment_fast._simple_perspective``): z_m and h are each a handful of float32 operations on
#: terms of about z, so the chord's two ends move by at most about 8 float32 ulps of z
#: (GEOMETRY_ROUNDING); a moved end moves the ray's term as a moved depth does, z^2 |dz|, so the
#: bound adds twice this to FETCH_ROUNDING there (measured: 6.0e-7 against the bound's 4.8e-6 on
#: the perspective view; 3.6e-8 with float64 geometry).
GEOMETRY_ROUNDING = 8 * float(np.finfo(np.float32).eps) / 2


def _rounding_tol(gb, single: bool = False) -> float:
    """The fast kernel's largest expected difference from the plain one on ``gb`` (FETCH_ROUNDING,
    plus GEOMETRY_ROUNDING at both ends of each chord where ``single``: the float32 path)."""
    depth = gb.depth[np.isfinite(gb.depth)]
    rounding = FETCH_ROUNDING + (2 * GEOMETRY_ROUNDING if single else 0.0)
    return 0.75 * rounding * float(depth.max()) / RADIUS
#: A perspective view from outside the box: background around it, so bilinear cells with a
#: background corner read the nearest pixel.
OUTSIDE = dict(eye=(0.3, 1.2, 3.6), target=(0.0, 0.9, 0.0), fov_y=50.0)


@pytest.fixture(scope="module")
def outside_view():
    kw = dict(OUTSIDE)
    cam = vo.Camera.look_at(kw.pop("eye"), kw.pop("target"), size=SIZE, **kw)
    gb = vo.render_gbuffer(vo.scenes.cornell_box(), cam)
    assert 0 < gb.valid.sum() < gb.valid.size
    return gb


@pytest.mark.parametrize("view", ["perspective", "orthographic", "outside"])
@pytest.mark.parametrize("case", range(len(CASES)), ids=lambda i: ",".join(f"{k}={v}" for k, v in CASES[i].items())
                         or "default")
def test_fast_segment_kernel_equals_the_plain_one(views, outside_view, view, case):
    gb = outside_view if view == "outside" else views[view]
    args = dict(radius=RADIUS, normal_clamp=False, thickness=None, falloff="constant", fetch="bilinear",
                offscreen="clamp", groups=DEFAULT_GROUPS, progress=False)
    args.update(CASES[case])
    fast = P._reference(gb, samples=SEGMENTS, seed=5, along="segment", fast=True, **args)
    plain = P._reference(gb, samples=SEGMENTS, seed=5, along="segment", fast=False, **args)
    np.testing.assert_array_equal(np.isnan(fast.value), np.isnan(plain.value))
    single = (gb.camera.is_perspective and args["thickness"] is None and not args["normal_clamp"]
              and args["falloff"] == "constant")
    tol = _rounding_tol(gb, single) if args["fetch"] == "bilinear" else 1e-12
    np.testing.assert_allclose(fast.value, plain.value, rtol=0, atol=tol)
    np.testing.assert_allclose(fast.stderr, plain.stderr, rtol=0, atol=tol)
    assert fast.samples == plain.samples


def test_fast_segment_kernel_chunks_do_not_change_values(outside_view, monkeypatch):
    """The pixels split into chunks that run on threads, in any order; every operation is per
    pixel, so the values are the same bit for bit as one chunk on one thread."""
    from vobscure.screenspace import _segment_fast as F
    monkeypatch.setattr(F, "_threads", lambda: 1)
    monkeypatch.setattr(P, "SEGMENT_CHUNK_PIXELS", 10 ** 9)
    monkeypatch.setattr(P.C, "CHUNK_PIXELS", 10 ** 9)
    one = vo.vo_reference(outside_view, radius=RADIUS, samples=64)
    monkeypatch.setattr(F, "_threads", lambda: 3)
    monkeypatch.setattr(P, "SEGMENT_CHUNK_PIXELS", 16)
    monkeypatch.setattr(P.C, "CHUNK_PIXELS", 16)
    split = vo.vo_reference(outside_view, radius=RADIUS, samples=64)
    np.testing.assert_array_equal(one.value, split.value)
    np.testing.assert_array_equal(one.stderr, split.stderr)


@pytest.mark.parametrize("threads", [1, 2, 3])
@pytest.mark.parametrize("n, chunk", [(729326, 65536), (10, 4), (5, 1), (1, 65536), (0, 8), (131072, 65536)])
def test_balanced_parts(monkeypatch, threads, n, chunk):
    """The index in order, in parts of at most ``chunk`` whose sizes differ by at most one, as
    many as the threads or a multiple of them (fewer only when there are fewer items)."""
    from vobscure.screenspace import _segment_fast as F
    monkeypatch.setattr(F, "_threads", lambda: threads)
    index = np.arange(n) * 3
    parts = F.balanced_parts(index, chunk)
    assert np.array_equal(np.concatenate(parts) if parts else np.empty(0, int), index)
    sizes = [len(p) for p in parts]
    assert all(0 < s <= chunk for s in sizes)
    if n:
        assert max(sizes) - min(sizes) <= 1
        assert len(parts) % threads == 0 or len(parts) == n
        assert len(parts) >= -(-n // chunk)
    # 729326 pixels in chunks of 65536 on 2 threads: 12 parts of 60777-60778, not 11 + 1
    if (n, chunk, threads) == (729326, 65536, 2):
        assert len(sizes) == 12 and set(sizes) == {60777, 60778}


@pytest.mark.parametrize("n, grid", [(128, (8, 16)), (100, (10, 10)), (6, (2, 3)), (7, (3, 3)), (22, (5, 5))])
def test_stratified_square_puts_one_point_per_cell(n, grid):
    """A full a x b grid when n factors into cells at most twice as long as wide (8 x 16 for
    128), else n distinct cells of the smallest square grid holding n (3 x 3 for 7, 5 x 5 for 22)."""
    a, b = grid
    u = P._stratified_square(np.random.default_rng(3), n)
    assert u.shape == (n, 2) and ((u >= 0) & (u < 1)).all()
    cells = set(zip((u[:, 0] * a).astype(int).tolist(), (u[:, 1] * b).astype(int).tolist()))
    assert len(cells) == n
    if a * b == n:
        assert cells == {(i, j) for i in range(a) for j in range(b)}


def _plane_view(size=(48, 32), ortho=False):
    """A slab's top (y = 0 plane) with a unit cube standing on it, seen from above at an angle."""
    import trimesh
    slab = trimesh.creation.box(extents=(8.0, 1.0, 8.0))
    slab.apply_translation((0.0, -0.5, 0.0))
    cube = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    cube.apply_translation((0.0, 0.25, 0.0))
    scene = vo.scenes.Scene({"slab": slab, "cube": cube})
    view = dict(size=size, ortho_height=3.0) if ortho else dict(size=size, fov_y=50.0)
    cam = vo.Camera.look_at((0.0, 2.5, 2.5), (0.0, 0.0, 0.0), **view)
    return vo.render_gbuffer(scene, cam)


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("ortho", [False, True])
def test_plane_shortcut_changes_nothing(case, ortho):
    """Pixels whose rays all read their own plane take 1/2 (1 clamped) without integrating:
    the value and stderr the integration gives them, bit for bit (every group reads exactly
    that there, the control variate cancelling each segment), for every option."""
    from vobscure.screenspace import _segment as S
    from vobscure.screenspace import _common as Cm
    gb = _plane_view(ortho=ortho)
    args = dict(radius=0.3, normal_clamp=False, thickness=None, falloff="constant", fetch="bilinear",
                offscreen="clamp", groups=DEFAULT_GROUPS, progress=False)
    args.update(CASES[case])
    px = Cm.prepare(gb, args["radius"])
    flat = S.on_one_plane(px, args["radius"], S.PlaneTables(S.plane_labels(gb)))
    assert 0.2 < flat.mean() < 0.9          # the shortcut is exercised, and not everywhere
    on = P._reference(gb, samples=SEGMENTS, seed=2, along="segment", shortcut=True, **args)
    off = P._reference(gb, samples=SEGMENTS, seed=2, along="segment", shortcut=False, **args)
    np.testing.assert_array_equal(on.value, off.value)
    np.testing.assert_array_equal(on.stderr, off.stderr)


def test_on_one_plane_by_hand():
    """The slab's pixels far (in pixels) from anything else and from the image's edge qualify; those
    whose ball reaches the cube or whose footprint reaches the image's edge do not; a G-buffer from arrays
    (planes known only to the depth's precision) has no labels."""
    from vobscure.screenspace import _segment as S
    from vobscure.screenspace import _common as Cm
    gb = _plane_view(size=(60, 40))
    labels = S.plane_labels(gb)
    slab_top = labels[gb.world_normal[..., 1] > 0.999]
    assert len(np.unique(slab_top)) == 2      # the slab's top and the cube's top: two planes
    R = 0.2
    px = Cm.prepare(gb, R)
    flat = np.zeros(gb.depth.size, dtype=bool)
    flat[px.index] = S.on_one_plane(px, R, S.PlaneTables(labels))
    flat = flat.reshape(gb.shape)
    # world distance of each pixel's point from the cube's footprint [-0.25, 0.25]^2 on y = 0
    p = gb.world_position
    gap = np.maximum(np.abs(p[..., 0]), np.abs(p[..., 2])) - 0.25
    on_slab = labels == labels[gb.shape[0] - 1, gb.shape[1] // 2]
    assert not flat[on_slab & (gap < R)].any()                  # the ball reaches the cube
    reach = np.ceil(R * gb.camera.fy / np.where(gb.valid, gb.depth, np.inf)).astype(int) + 2
    i, j = np.indices(gb.shape)
    edge = np.minimum(np.minimum(i, gb.shape[0] - 1 - i), np.minimum(j, gb.shape[1] - 1 - j))
    assert not flat[edge < reach // 2].any()                    # a footprint past the edge
    # in the image, at more than twice the footprint's radius from any pixel not on the slab
    from scipy import ndimage
    away = ndimage.distance_transform_edt(on_slab) > 2 * reach
    assert flat[on_slab & away & (edge > 2 * reach)].all()
    assert (on_slab & away & (edge > 2 * reach)).sum() > 50
    assert S.plane_labels(vo.GBuffer.from_arrays(gb.depth, camera=gb.camera)) is None


@pytest.mark.parametrize("ortho", [False, True])
def test_footprint_rows_hold_every_ray_through_the_ball(ortho):
    """Each strip's extent holds every ray of the strip that meets the ball and not much more:
    a dense grid of rays over the box, each tested by the distance from the ball's centre to
    its line (an independent test of the conic's roots and of where the chord is widest)."""
    from vobscure.screenspace import _segment as S
    from vobscure.screenspace import _common as Cm
    gb = _plane_view(size=(24, 16), ortho=ortho)
    R = 0.3
    px = Cm.prepare(gb, R)
    a0, a1, b0, b1, exact = S.ball_box(px, R)
    pick = np.flatnonzero(exact)[::7]
    p = px.p[pick]
    grid = (np.arange(400) + 0.5) / 400
    for s_lo, s_hi in ((0.0, 0.125), (0.375, 0.5), (0.5, 0.625), (0.875, 1.0), (0.0, 1.0)):
        lo_b = b0 + s_lo * (b1 - b0)
        hi_b = b0 + s_hi * (b1 - b0)
        lo, hi = S.footprint_rows(px, R, lo_b, hi_b, a0, a1)
        for k, q in enumerate(pick):
            a, b = np.meshgrid(a0[q] + grid * (a1[q] - a0[q]), lo_b[q] + grid * (hi_b[q] - lo_b[q]))
            if ortho:
                dist2 = (a - p[k, 0]) ** 2 + (b - p[k, 1]) ** 2
            else:
                u = np.stack([a, b, np.ones_like(a)], axis=-1)
                along = u @ p[k] / np.einsum("...i,...i", u, u)
                dist2 = np.sum((along[..., None] * u - p[k]) ** 2, axis=-1)
            a_in = a[dist2 < R * R]
            assert a_in.size > 0
            assert lo[q] <= a_in.min() and a_in.max() <= hi[q]
            # tight: within two grid steps of the rays found (plus the pad)
            step = 2.0 * (a1[q] - a0[q]) / 400
            assert a_in.min() - lo[q] < step and hi[q] - a_in.max() < step


def test_strips_check_no_less_than_the_box():
    """The strips' test passes every pixel the box's test passes (its rectangles lie inside the
    box's) and more beside the cube (the box's corners reach pixels no ray through the ball
    reads); every pixel it passes reads 1/2 in every group (bit for bit, the shortcut test
    above)."""
    from vobscure.screenspace import _segment as S
    from vobscure.screenspace import _common as Cm
    gb = _plane_view(size=(60, 40))
    R = 0.2
    px = Cm.prepare(gb, R)
    tables = S.PlaneTables(S.plane_labels(gb))
    box = S.on_one_plane(px, R, tables, strips=1)
    strips = S.on_one_plane(px, R, tables)
    assert np.all(strips[box]) and strips.sum() > box.sum()


@pytest.mark.parametrize("normal_clamp", [False, True])
def test_exact_pixels_report_stderr_zero(normal_clamp):
    """The pixels that see only their own plane carry their closed form and stderr 0; the
    same plane in a G-buffer built from arrays (no triangle planes to prove it) reads the
    same value in every group but keeps the floor of one step of a group mean."""
    from vobscure.screenspace import _segment as S
    from vobscure.screenspace import _common as Cm
    gb = _plane_view(size=(48, 32))
    R = 0.3
    e = vo.vo_reference(gb, radius=R, samples=SEGMENTS, normal_clamp=normal_clamp, seed=4)
    px = Cm.prepare(gb, R)
    flat = np.zeros(gb.depth.size, dtype=bool)
    flat[px.index] = S.on_one_plane(px, R, S.PlaneTables(S.plane_labels(gb), gb.depth))
    flat = flat.reshape(gb.shape)
    assert flat.sum() > 100
    assert np.all(e.stderr[flat] == 0) and np.all(e.value[flat] == (1.0 if normal_clamp else 0.5))
    assert np.all(e.stderr[gb.valid & ~flat & (e.value > 0) & (e.value < 1)] > 0)
    bare = vo.GBuffer.from_arrays(gb.depth, gb.normal, camera=gb.camera)
    b = vo.vo_reference(bare, radius=R, samples=SEGMENTS, normal_clamp=normal_clamp, seed=4)
    agree = flat & (b.value == e.value)
    floor = 1.0 / ((SEGMENTS // DEFAULT_GROUPS) * np.sqrt(DEFAULT_GROUPS))
    if not normal_clamp:
        assert agree.sum() > 0.9 * flat.sum()
        np.testing.assert_allclose(b.stderr[agree], floor, rtol=1e-6)
