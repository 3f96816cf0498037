"""Estimators that read the layers (``thickness="layers"``): vo_point, vo_line and gtao on the
G-buffer's solid intervals (vobscure.layers.SolidIntervals).

The intervals are made by hand: every surface to infinity and every surface to a constant
thickness (which must give the depth buffer's and the thickness model's numbers), and the
exact view-ray intervals of boxes (the slab method, below), on a thin plate floating over a
floor, seen straight down by an orthographic camera whose pixel boundaries fall on the
plate's edge: there the pixels' intervals describe the solids exactly, and the estimators
are compared with the ray-cast truth and the closed form of a ball cut by two slabs.
"""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest
import trimesh

import vobscure as vo
from vobscure.layers import SolidIntervals
from vobscure.patterns import SamplePattern
from vobscure.sampling import cube_to_uniform_ball
from vobscure.screenspace.gtao import gtao, gtao_bent_normals

from analytic import slab_shell_vo
from conftest import t_threshold

#: Two float64 evaluations of the same line sums in a different order (the constant falloff's
#: depth-buffer path sums k_s clip(d_r) and constants; the layered path integrates each
#: interval): every chord term is O(1) with a few roundings of 2^-53 = 1.1e-16, over at most
#: 33 lines: < 1e-14. 1e-12 leaves room; a misread pixel or interval moves a value by a
#: chord's weight (> 1e-3).
ORDER_TOL = 1e-12
#: float32 against float64 (see tests/test_line.py, FLOAT32_TOL, for the derivation): the
#: interval ends round by 6e-8 relative, 2 u z / (2 R z_s) of a chord (z <= 3, R = 0.8,
#: z_s >= 0.05 for the random lines: 4e-6); a point sample flips only if it lies within that
#: of an end (none did: measured 0). 1e-5.
FLOAT32_TOL = 1e-5
#: GTAO float32 against float64: tests/test_gtao.py, FLOAT32_TOL.
GTAO_FLOAT32_TOL = 1e-5
#: An open slice of an orthographic view of a plane facing the camera: |n_p| = 1, gamma = 0
#: and the horizons at -+pi/2, a(h) = 1/2 each, exact up to the rounding of acos and cos (a
#: few 1e-16); 1e-12.
OPEN_TOL = 1e-12

#: The plate scene: a floor y in [-1, 0] and a plate y in [H_GAP, H_GAP + T_PLATE] over x < 0,
#: both 8 x 8 wide (closed boxes, in metres); the ball of radius R_PLATE around a point of the
#: plate's top reaches the floor (D = H_GAP + T_PLATE < R_PLATE) and the gap under the plate
#: is in reach of the floor's points next to it.
H_GAP, T_PLATE, R_PLATE = 0.4, 0.15, 0.8
BOXES = {"floor": ((-4.0, -1.0, -4.0), (4.0, 0.0, 4.0)),
         "plate": ((-4.0, H_GAP, -4.0), (0.0, H_GAP + T_PLATE, 4.0))}
#: Orthographic, straight down, 0.1 m pixels: the plate's edge x = 0 is the boundary between
#: columns EDGE - 1 and EDGE. The scene is the same along z and beyond the image's left and
#: right edges, so the clamped off-screen taps read what is there.
SIZE, EDGE, PIXEL = (24, 12), 12, 0.1
#: Independent random patterns for the standard errors of vo_point and vo_line (the degrees
#: of freedom are GROUPS - 1), points per pattern.
GROUPS, POINTS = 16, 256


def _box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    mesh = trimesh.creation.box(extents=hi - lo)
    mesh.apply_translation((lo + hi) / 2)
    return mesh


def box_intervals(camera, boxes) -> SolidIntervals:
    """The view-depth intervals of every pixel ray through disjoint axis-aligned boxes,
    by the slab method (the ray is inside a box between the largest entry and the smallest
    exit parameter over the three axes), computed independently of the renderer."""
    o, d = camera.primary_rays()
    fronts, backs = [], []
    for lo, hi in boxes:
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = (np.asarray(lo) - o) / d
            t1 = (np.asarray(hi) - o) / d
            # an axis the ray runs parallel to gives -+inf (inside the slab) and imposes nothing
            t_in = np.nanmax(np.minimum(t0, t1), axis=-1)
            t_out = np.nanmin(np.maximum(t0, t1), axis=-1)
        hit = (t_out >= t_in) & (t_out > 0)
        t_in, t_out = np.where(hit, t_in, 0.0), np.where(hit, t_out, 0.0)
        z_in = camera.world_to_view(o + t_in[..., None] * d)[..., 2]
        z_out = camera.world_to_view(o + t_out[..., None] * d)[..., 2]
        fronts.append(np.where(hit, z_in, np.inf))
        backs.append(np.where(hit, z_out, np.inf))
    front, back = np.stack(fronts), np.stack(backs)
    order = np.argsort(front, axis=0, kind="stable")
    return SolidIntervals(np.take_along_axis(front, order, 0), np.take_along_axis(back, order, 0))


@pytest.fixture(scope="module")
def plate():
    """(scene, G-buffer without intervals, the same with the boxes' exact intervals)."""
    scene = vo.scenes.Scene({name: _box(*b) for name, b in BOXES.items()}, name="plate")
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=SIZE, ortho_height=SIZE[1] * PIXEL)
    gb = vo.render_gbuffer(scene, cam)
    assert gb.valid.all()
    return scene, gb, gb.with_intervals(box_intervals(cam, BOXES.values()))


@pytest.fixture(scope="module")
def steps_views():
    """G-buffers with depth discontinuities, background and off-screen taps (perspective and
    orthographic)."""
    scene = vo.scenes.steps()
    return [vo.render_gbuffer(scene, vo.Camera.look_at((2.0, 1.2, 1.5), (0, 0.3, 0), size=(40, 30), **lens))
            for lens in (dict(fov_y=50.0), dict(ortho_height=2.5))]


def surfaces_on(gb, back=None) -> vo.GBuffer:
    """``gb`` with the intervals [depth, back] (back = +inf by default) and an unused slot."""
    depth = np.asarray(gb.depth, dtype=np.float64)[None]
    back = np.full_like(depth, np.inf) if back is None else np.asarray(back, dtype=np.float64)[None]
    unused = np.full_like(depth, np.inf)
    return gb.with_intervals(SolidIntervals(np.concatenate([depth, unused]), np.concatenate([back, unused])))


def _silent(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise"):
            return fn(*args, **kw)


def random_patterns(seed):
    """GROUPS independent patterns of POINTS uniform points in the ball (weights 1); the line
    patterns are their (x, y), whose density over the disk is the chord length, so an equally
    weighted line pattern estimates the ball's VO without bias."""
    rng = np.random.default_rng(seed)
    for _ in range(GROUPS):
        pts = cube_to_uniform_ball(rng.random((POINTS, 3)))
        yield SamplePattern(pts, np.ones(POINTS)), SamplePattern(pts[:, :2], np.ones(POINTS))


def mean_and_stderr(images):
    a = np.asarray(images, dtype=np.float64)
    return a.mean(axis=0), a.std(axis=0, ddof=1) / np.sqrt(len(a))


# --- bad input ------------------------------------------------------------------------------

def test_layers_need_intervals_and_bad_thickness_is_named(plate):
    _, gb, layered = plate
    for fn in (vo.vo_point, vo.vo_line, gtao, gtao_bent_normals):
        with pytest.raises(ValueError, match=r"thickness='layers'.*gbuffer.intervals is None"):
            fn(gb, radius=0.5, thickness="layers")
        with pytest.raises(ValueError, match="thickness"):
            fn(layered, radius=0.5, thickness="layer")
    for bad in (0.5, 0, -1.0, np.inf):
        with pytest.raises(ValueError, match="thickness"):
            gtao(layered, radius=0.5, thickness=bad)
    for fn in (vo.vo_point, vo.vo_line):
        with pytest.raises(ValueError, match="thickness"):
            fn(layered, radius=0.5, thickness=-1.0)


# --- the layers that say what the depth buffer says -----------------------------------------

def test_solid_from_every_surface_is_the_depth_buffer(steps_views):
    """Intervals [depth, +inf): the depth buffer's own assumption. The same comparisons run
    (a nearest fetch), so the same numbers, bit for bit, where the same operations run."""
    for gb in steps_views:
        layered = surfaces_on(gb)
        for kw in (dict(), dict(normal_clamp=True), dict(offscreen="open")):
            for falloff in ("constant", "quadratic"):
                a = vo.vo_point(layered, radius=0.4, thickness="layers", samples=33, falloff=falloff, **kw)
                b = vo.vo_point(gb, radius=0.4, fetch="nearest", samples=33, falloff=falloff, **kw)
                assert np.array_equal(a, b, equal_nan=True), kw
            # the depth buffer's quadratic falloff runs line_integral: the same operations
            a = vo.vo_line(layered, radius=0.4, thickness="layers", falloff="quadratic", **kw)
            b = vo.vo_line(gb, radius=0.4, falloff="quadratic", **kw)
            assert np.array_equal(a, b, equal_nan=True), kw
            # the constant falloff's depth-buffer path sums in another order
            a = vo.vo_line(layered, radius=0.4, thickness="layers", falloff="constant", **kw)
            b = vo.vo_line(gb, radius=0.4, falloff="constant", **kw)
            assert np.array_equal(np.isnan(a), np.isnan(b))
            assert np.nanmax(np.abs(a - b)) < ORDER_TOL, kw
        for fetch in ("bilinear", "nearest"):
            for kw in (dict(), dict(offscreen="open", falloff_range=0.5, thin_occluder=0.5)):
                a = gtao(layered, radius=0.4, thickness="layers", fetch=fetch, slices=4, **kw)
                assert np.array_equal(a, gtao(gb, radius=0.4, fetch=fetch, slices=4, **kw), equal_nan=True)
            a = gtao_bent_normals(layered, radius=0.4, thickness="layers", fetch=fetch)
            assert np.array_equal(a, gtao_bent_normals(gb, radius=0.4, fetch=fetch), equal_nan=True)
        # float32 G-buffers: the intervals are float32 too, the comparisons the same
        g32 = gb.astype(np.float32)
        a = vo.vo_point(surfaces_on(g32), radius=0.4, thickness="layers")
        assert a.dtype == np.float32
        assert np.array_equal(a, vo.vo_point(g32, radius=0.4, fetch="nearest"), equal_nan=True)


def test_a_constant_thickness_of_intervals_is_the_thickness_model(steps_views):
    """Intervals [depth, depth + t]: the thickness model t (Loos & Sloan Sec. 4.3)."""
    t = 0.15
    for gb in steps_views:
        layered = surfaces_on(gb, back=np.asarray(gb.depth, dtype=np.float64) + t)
        for kw in (dict(), dict(normal_clamp=True), dict(falloff="quadratic", offscreen="open")):
            a = vo.vo_point(layered, radius=0.4, thickness="layers", **kw)
            b = vo.vo_point(gb, radius=0.4, thickness=t, fetch="nearest", **kw)
            assert np.array_equal(a, b, equal_nan=True), kw
            # the thickness path warps (d + t - z) / R, the layers (back - z) (1 / R)
            a = vo.vo_line(layered, radius=0.4, thickness="layers", **kw)
            b = vo.vo_line(gb, radius=0.4, thickness=t, **kw)
            assert np.array_equal(np.isnan(a), np.isnan(b))
            assert np.nanmax(np.abs(a - b)) < ORDER_TOL, kw
            # and the layers do differ from the solid depth buffer
            assert np.nanmax(np.abs(a - vo.vo_line(gb, radius=0.4, **kw))) > 0.05


# --- the thin plate: against the ray-cast truth and the closed form --------------------------

def _plate_truth(scene, gb):
    return vo.ground_truth(scene, gb, quantity="volumetric", radius=R_PLATE, samples=2048, groups=GROUPS, seed=3)


def _layered_estimates(gb, **kw):
    """vo_point and vo_line over the independent random patterns: (mean, stderr) each."""
    points, lines = [], []
    for ball, disk in random_patterns(seed=5):
        points.append(vo.vo_point(gb, radius=R_PLATE, samples=ball, randomize=False, **kw))
        lines.append(vo.vo_line(gb, radius=R_PLATE, samples=disk, randomize=False, **kw))
    return {"point": mean_and_stderr(points), "line": mean_and_stderr(lines)}


def _t_scores(mean, se, truth):
    """(estimate - truth) over their combined standard error; where both are 0 (every group
    and every ray agree), the difference itself must be 0."""
    s = np.sqrt(se ** 2 + truth.stderr ** 2)
    diff = mean - truth.value
    assert np.all(np.abs(diff[s == 0]) < ORDER_TOL)
    return np.where(s > 0, diff / np.where(s > 0, s, 1.0), 0.0)


@pytest.fixture(scope="module")
def plate_layered(plate):
    """vo_point and vo_line with the plate's exact intervals: (mean, stderr) each."""
    return _layered_estimates(plate[2], thickness="layers")


@pytest.mark.slow
def test_point_and_line_with_layers_match_the_ray_cast_truth_on_a_thin_plate(plate, plate_layered):
    """Seen straight down, each pixel's intervals are exact (the plate's edge on a pixel
    boundary), so vo_point and vo_line with the layers estimate the world-space VO without a
    model error: a t-test at every pixel against ground_truth("volumetric"), with both
    standard errors (GROUPS - 1 degrees of freedom each). The depth buffer, which fills the
    gap under the plate and the floor under it, fails the same test."""
    scene, gb, _ = plate
    truth = _plate_truth(scene, gb)
    limit = t_threshold(GROUPS - 1, tests=2 * gb.valid.size)
    for name, (mean, se) in plate_layered.items():
        t = _t_scores(mean, se, truth)
        assert np.abs(t).max() < limit, (name, np.abs(t).max(), limit)
    for name, (mean, se) in _layered_estimates(gb).items():
        t = _t_scores(mean, se, truth)
        # the plate's pixels (0.48 for 0.78) and the floor's next to it
        assert np.all(np.abs(t[:, :EDGE]) > limit) and np.all(np.abs(t[:, EDGE:EDGE + 3]) > limit), name


def test_layers_on_the_plate_give_the_closed_form(plate_layered):
    """A point of the plate's top whose ball does not reach the plate's edge: the ball is cut
    by the plate (T_PLATE thick) and by the floor D = H_GAP + T_PLATE below; with V(t) the VO
    of a ball over a layer t thick (slab_shell_vo), the solid below D is V(D) - 1/2 of the
    ball and the VO is V(T_PLATE) - V(D) + 1/2. A z-test of the pixels' mean."""
    D = H_GAP + T_PLATE
    exact = slab_shell_vo(T_PLATE, R_PLATE) - slab_shell_vo(D, R_PLATE) + 0.5
    inner = np.arange(SIZE[0]) + 0.5 < EDGE - R_PLATE / PIXEL     # the ball's edge left of x = 0
    assert inner.sum() >= 3
    limit = t_threshold(GROUPS - 1)
    for name, (mean, se) in plate_layered.items():
        # every pixel of a column reads the same (the scene does not change along z): one value
        value, err = mean[:, inner], se[:, inner]
        assert np.ptp(value) < ORDER_TOL and np.ptp(err) < ORDER_TOL, name
        assert abs(value[0, 0] - exact) < limit * err[0, 0], (name, value[0, 0], exact, err[0, 0])
        assert abs(value[0, 0] - 0.5) > 0.2         # the depth buffer's solid would read 1/2


def test_gtao_light_passes_behind_a_thin_plate(plate):
    """The floor next to the plate, seen straight down: every tap on the plate has its back
    (the plate's bottom, H_GAP above the floor) above the tangent-plane horizon, so none
    raises it and the layered GTAO reads open, exactly; the depth buffer's GTAO takes the
    plate for a block down to the floor and reads darker than the ray-cast cosine AO. The
    truth lies between: a single horizon cannot put back the plate above the gap (the
    documented limit), so the layers err towards open there."""
    scene, gb, layered = plate
    truth = vo.ground_truth(scene, gb, quantity="ao", radius=R_PLATE, rays=2048, groups=GROUPS, seed=4)
    kw = dict(radius=R_PLATE, slices=16, steps=16, fetch="nearest")
    solid = gtao(gb, **kw)
    light = gtao(layered, thickness="layers", **kw)
    near = np.zeros(gb.valid.shape, dtype=bool)
    near[:, EDGE:EDGE + 5] = True          # floor pixels whose radius reaches under the plate
    limit = t_threshold(GROUPS - 1, tests=2 * near.sum())
    np.testing.assert_allclose(light[near], 1.0, rtol=0, atol=OPEN_TOL)
    assert np.all(truth.value[near] < 1.0 - limit * truth.stderr[near])
    # (the plate's top is within R of the floor's points up to 0.58 from its edge: the
    # depth buffer's darkening fades there)
    darker = near & (np.arange(SIZE[0]) < EDGE + 4)
    assert np.all(solid[darker] < truth.value[darker] - limit * truth.stderr[darker])
    # elsewhere (the plate's top, the floor out of its reach) both read the open plane
    np.testing.assert_allclose(light[~near], solid[~near], rtol=0, atol=OPEN_TOL)
    # the bent normals: the open hemisphere's, the normal itself
    bent = gtao_bent_normals(layered, thickness="layers", **kw)
    np.testing.assert_allclose(bent[near], np.broadcast_to(gb.normal[near], bent[near].shape), atol=1e-9)


def test_float32_layers(plate):
    _, _, layered = plate
    l32 = layered.astype(np.float32)
    assert l32.intervals.dtype == np.float32
    ball, disk = next(random_patterns(seed=6))
    for fn, pattern in ((vo.vo_point, ball), (vo.vo_line, disk)):
        v64 = fn(layered, radius=R_PLATE, samples=pattern, randomize=False, thickness="layers")
        v32 = fn(l32, radius=R_PLATE, samples=pattern, randomize=False, thickness="layers")
        assert v64.dtype == np.float64 and v32.dtype == np.float32
        np.testing.assert_allclose(v32.astype(np.float64), v64, rtol=0, atol=FLOAT32_TOL)
    v64 = gtao(layered, radius=R_PLATE, thickness="layers", seed=2)
    v32 = gtao(l32, radius=R_PLATE, thickness="layers", seed=2)
    assert v32.dtype == np.float32
    np.testing.assert_allclose(v32.astype(np.float64), v64, rtol=0, atol=GTAO_FLOAT32_TOL)


def test_extremes_with_layers(steps_views):
    """Tiny and huge radii, off-screen taps, background, a hole in the depth buffer, several
    intervals per pixel (one of them with an unseen end): finite values in [0, 1] on the
    valid pixels, NaN elsewhere, no warning."""
    for gb in steps_views:
        depth = np.asarray(gb.depth, dtype=np.float64)
        # the surface 0.05 thick, then solid again from 0.2 behind it on
        front = np.stack([depth, depth + 0.2])
        back = np.stack([depth + 0.05, np.full_like(depth, np.inf)])
        layered = gb.with_intervals(SolidIntervals(front, back))
        for radius in (1e-7, 0.4, 1e3):
            for offscreen in ("clamp", "open"):
                images = [_silent(vo.vo_point, layered, radius=radius, thickness="layers", offscreen=offscreen),
                          _silent(vo.vo_line, layered, radius=radius, thickness="layers", offscreen=offscreen,
                                  normal_clamp=True),
                          _silent(gtao, layered, radius=radius, thickness="layers", offscreen=offscreen)]
                for v in images:
                    assert np.all(np.isfinite(v[gb.valid])) and np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1))
                    assert np.all(np.isnan(v[~gb.valid]))
        # a tiny radius: every sample of a plane's pixel is in front of it or within 0.05
        # behind it, as a surface of that thickness
        v = vo.vo_point(layered, radius=1e-7, thickness="layers")
        assert np.array_equal(v, vo.vo_point(gb, radius=1e-7, thickness=0.05, fetch="nearest"), equal_nan=True)


# --- the layered renderer ---------------------------------------------------------------------

def _peeled(scene, camera, layers):
    if "layers" not in inspect.signature(vo.render_gbuffer).parameters:
        pytest.skip("render_gbuffer(..., layers=K) (depth peeling) is not in this build yet")
    return vo.render_gbuffer(scene, camera, layers=layers)


def test_peeled_layers_give_the_hand_made_intervals(plate):
    """Depth peeling with four layers finds the plate's top and bottom and the floor's top
    and bottom: the estimators then read the same occupancy as with the boxes' exact
    intervals, up to Embree's float32 hits (a sample flips only within ~1e-7 of an end)."""
    scene, gb, layered = plate
    peeled = _peeled(scene, gb.camera, layers=4)
    assert peeled.intervals is not None
    ball, disk = next(random_patterns(seed=7))
    for fn, pattern in ((vo.vo_point, ball), (vo.vo_line, disk)):
        a = fn(peeled, radius=R_PLATE, samples=pattern, randomize=False, thickness="layers")
        b = fn(layered, radius=R_PLATE, samples=pattern, randomize=False, thickness="layers")
        np.testing.assert_allclose(a, b, rtol=0, atol=FLOAT32_TOL)
    kw = dict(radius=R_PLATE, slices=16, steps=16, fetch="nearest", thickness="layers")
    np.testing.assert_allclose(gtao(peeled, **kw), gtao(layered, **kw), rtol=0, atol=GTAO_FLOAT32_TOL)
    # two layers: the plate's top and bottom (and the floor's top and bottom beside it)
    two = _peeled(scene, gb.camera, layers=2)
    np.testing.assert_allclose(gtao(two, **kw)[:, EDGE:], gtao(layered, **kw)[:, EDGE:], rtol=0,
                               atol=GTAO_FLOAT32_TOL)
