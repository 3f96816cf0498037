"""The converged screen-space reference's exact pixels next to other surfaces: a pixel on a plane
whose ball's footprint also reads other surfaces is exact when those surfaces and the plane both
lie beyond each ray's chord through the ball, on one side (``_segment._clear_of_ball``); so is a
pixel whose footprint leaves the image when the rays past the edge, which read the border's depth,
are clear in the same way (``_segment._overflow_clear``).

Checked on hand-made scenes against the segment kernel itself with the shortcut off (every
group must read the closed form bit for bit) and against the independent point sampling of the
ball (``along="point"``, each point's occupancy tested on its own) by t-tests."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.estimate import DEFAULT_GROUPS
from vobscure.screenspace import _common as Cm
from vobscure.screenspace import _segment as S
from vobscure.screenspace import point as P

from conftest import FALSE_FAILURE, t_threshold

RADIUS = 0.3
#: Rays of the segment path and points of the independent point sampling.
SEGMENTS, POINTS = 128, 4096
OBSTACLES = ["wall", "cube", "ledge"]
#: Calls of the t-test in this module (Bonferroni with the pixels).
CALLS = 2 * len(OBSTACLES) + 3


def _floor_scene(obstacle: str):
    """A floor (the top of a slab, y = 0) with a wall far behind ("wall": the box's face at
    z = -2 faces the camera, 1.5 behind the nearest floor pixels' balls), a cube standing on
    it ("cube": its faces reach some balls and hide others from the camera), or a ledge
    ("ledge": the floor ends at z = -1 above a lower floor at y = -3, which the rays past the
    edge read far behind the balls, where the floor's plane would still cross them)."""
    import trimesh
    slab = trimesh.creation.box(extents=(8.0, 1.0, 8.0 if obstacle != "ledge" else 3.0))
    slab.apply_translation((0.0, -0.5, 0.0 if obstacle != "ledge" else 0.5))
    if obstacle == "ledge":
        other = trimesh.creation.box(extents=(8.0, 1.0, 8.0))
        other.apply_translation((0.0, -3.5, -3.0))
    elif obstacle == "wall":
        other = trimesh.creation.box(extents=(8.0, 3.0, 0.2))
        other.apply_translation((0.0, 1.5, -2.1))
    else:
        other = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
        other.apply_translation((0.0, 0.25, 0.0))
    return vo.scenes.Scene({"slab": slab, obstacle: other})


def _view(obstacle: str, ortho: bool, size=(64, 48)):
    scene = _floor_scene(obstacle)
    if obstacle in ("wall", "ledge"):
        eye, target = (0.0, 1.2, 1.5), (0.0, 0.0, -1.5)
    else:
        eye, target = (0.0, 2.5, 2.5), (0.0, 0.0, 0.0)
    view = dict(ortho_height=3.0) if ortho else dict(fov_y=50.0)
    cam = vo.Camera.look_at(eye, target, size=size, **view)
    return vo.render_gbuffer(scene, cam)


def _claims(gb, radius=RADIUS, offscreen="clamp"):
    """(H, W) bool images: exact with the plane-only test, and exact with the extended one."""
    tables = S.PlaneTables(S.plane_labels(gb), gb.depth)
    px = Cm.prepare(gb, radius)
    out = []
    for clear in (False, True):
        flat = np.zeros(gb.depth.size, dtype=bool)
        flat[px.index] = S.on_one_plane(px, radius, tables, clear=clear, offscreen=offscreen)
        out.append(flat.reshape(gb.shape))
    return out


def _corridor_view(pit: bool = False):
    """Inside a corridor (a floor, two side walls, an end wall), looking along it: the side walls
    and the floor meet the image's edges at grazing angles, and many of their balls' footprints
    leave the image. ``pit``: the floor has a hole (x in [0.2, 0.6], z in [-1.6, -0.8]) over a
    lower floor 2 below, which the image's bottom row crosses: there the border reads depths
    far behind the balls of the floor next to it."""
    import trimesh
    parts = {}
    floor = [("floor", (2.0, 0.2, 12.0), (0.0, -0.1, -5.0))]
    if pit:
        floor = [("floor_left", (1.2, 0.2, 12.0), (-0.4, -0.1, -5.0)),
                 ("floor_right", (0.4, 0.2, 12.0), (0.8, -0.1, -5.0)),
                 ("floor_near", (0.4, 0.2, 1.8), (0.4, -0.1, 0.1)),
                 ("floor_far", (0.4, 0.2, 9.4), (0.4, -0.1, -6.3)),
                 ("pit_bottom", (2.0, 0.2, 12.0), (0.0, -2.1, -5.0))]
    for name, extents, centre in floor + [("left", (0.2, 2.5, 12.0), (-1.1, 1.25, -5.0)),
                                          ("right", (0.2, 2.5, 12.0), (1.1, 1.25, -5.0)),
                                          ("end", (2.0, 2.5, 0.2), (0.0, 1.25, -11.0))]:
        box = trimesh.creation.box(extents=extents)
        box.apply_translation(centre)
        parts[name] = box
    cam = vo.Camera.look_at((0.0, 1.0, 0.5), (0.0, 0.9, -5.0), size=(64, 48), fov_y=60.0)
    return vo.render_gbuffer(vo.scenes.Scene(parts), cam)


def _past_the_edge(gb, radius=RADIUS):
    """(H, W) bool: the pixels exact with the rays past the image's edge checked, and not without."""
    return _claims(gb, radius)[1] & ~_claims(gb, radius, offscreen=None)[1]


def _args(**kw):
    args = dict(radius=RADIUS, normal_clamp=False, thickness=None, falloff="constant", fetch="bilinear",
                offscreen="clamp", groups=DEFAULT_GROUPS, progress=False)
    args.update(kw)
    return args


@pytest.mark.parametrize("ortho", [False, True])
@pytest.mark.parametrize("obstacle", OBSTACLES)
def test_more_pixels_are_exact(obstacle, ortho):
    """The extended test keeps every plane-only pixel and adds pixels whose footprint reads the
    other surface."""
    gb = _view(obstacle, ortho)
    plane, extended = _claims(gb)
    assert np.all(extended[plane])
    assert (extended & ~plane).sum() >= 20, (extended & ~plane).sum()


@pytest.mark.parametrize("case", [dict(), dict(normal_clamp=True), dict(falloff="quadratic"),
                                  dict(falloff="quadratic", normal_clamp=True), dict(offscreen="open")],
                         ids=lambda c: ",".join(f"{k}={v}" for k, v in c.items()) or "default")
@pytest.mark.parametrize("ortho", [False, True])
@pytest.mark.parametrize("obstacle", OBSTACLES)
def test_new_exact_pixels_read_the_closed_form_in_every_group(obstacle, ortho, case, monkeypatch):
    """With no plane tables at all (no shortcut, no exact pixels) the segment kernel integrates
    every ray of the newly exact pixels: every group reads 1/2 (1 clamped) there bit for bit
    (the spread over groups is 0, reported as the floor of one step of a group mean), so the
    value and the stderr 0 the shortcut reports are the kernel's own; elsewhere the shortcut
    changes nothing."""
    gb = _view(obstacle, ortho)
    plane, extended = _claims(gb, offscreen=case.get("offscreen", "clamp"))
    new = extended & ~plane
    on = P._reference(gb, samples=SEGMENTS, seed=5, along="segment", **_args(**case))
    with monkeypatch.context() as mp:
        mp.setattr(P, "_plane_tables", lambda *a, **k: None)
        off = P._reference(gb, samples=SEGMENTS, seed=5, along="segment", **_args(**case))
    expected = 1.0 if case.get("normal_clamp") else 0.5
    floor = 1.0 / ((SEGMENTS // DEFAULT_GROUPS) * np.sqrt(DEFAULT_GROUPS))
    assert np.all(off.value[new] == expected), np.abs(off.value[new] - expected).max()
    if case.get("normal_clamp"):
        assert np.all(off.stderr[new] == 0.0)       # every group 1: no spread, no floor at 1
    else:
        np.testing.assert_allclose(off.stderr[new], floor, rtol=1e-6)
    np.testing.assert_array_equal(on.value, off.value)
    assert np.all(on.stderr[extended] == 0.0)
    np.testing.assert_array_equal(on.stderr[~extended], off.stderr[~extended])


@pytest.mark.parametrize("ortho", [False, True])
@pytest.mark.parametrize("obstacle", OBSTACLES)
def test_new_exact_pixels_agree_with_point_sampling(obstacle, ortho):
    """The independent point sampling of the ball (each point's occupancy on its own) agrees with
    the closed form on every newly exact pixel (t-test with its reported stderr, Bonferroni over
    the pixels and this module's calls)."""
    gb = _view(obstacle, ortho)
    plane, extended = _claims(gb)
    new = extended & ~plane
    pts = P._reference(gb, samples=POINTS, seed=7, along="point", **_args())
    z = (pts.value[new] - 0.5) / pts.stderr[new]
    limit = t_threshold(DEFAULT_GROUPS - 1, tests=CALLS * int(new.sum()), false_failure=FALSE_FAILURE)
    assert np.all(pts.stderr[new] > 0)
    assert np.max(np.abs(z)) < limit, (np.abs(z).max(), limit)


@pytest.mark.parametrize("ortho", [False, True])
def test_balls_that_meet_or_hide_behind_the_cube_are_not_exact(ortho):
    """No pixel whose ball reaches into the cube (its world distance to the cube below R) is
    claimed, nor any pixel whose point-sampled value is far from 1/2 (a ball the cube hides
    from the camera: its footprint reads the cube in front of rays whose floor lies in the
    ball); both kinds exist in the view."""
    gb = _view("cube", ortho)
    _, extended = _claims(gb)
    p = gb.world_position
    # distance from each pixel's world point to the cube [-0.25, 0.25] x [0, 0.5] x [-0.25, 0.25]
    lo, hi = np.array([-0.25, 0.0, -0.25]), np.array([0.25, 0.5, 0.25])
    gap = np.linalg.norm(np.maximum(np.maximum(lo - p, p - hi), 0.0), axis=-1)
    on_floor = gb.valid & (gb.world_normal[..., 1] > 0.999) & (p[..., 1] < 1e-6)
    meets = on_floor & (gap < RADIUS)
    assert meets.sum() > 20 and not extended[meets].any()
    pts = P._reference(gb, samples=POINTS, seed=11, along="point", **_args())
    limit = t_threshold(DEFAULT_GROUPS - 1, tests=CALLS * int(gb.valid.sum()), false_failure=FALSE_FAILURE)
    off_half = on_floor & ~meets & (np.abs(pts.value - 0.5) > limit * pts.stderr)
    assert off_half.sum() > 5 and not extended[off_half].any()


def test_footprints_past_the_edge_can_be_exact():
    """Inside the corridor, pixels of the grazing walls and floor whose footprint leaves the image
    are exact once the rays past the edge are checked (with ``offscreen="clamp"``: their border
    reads and the plane lie in front of their chords); every pixel exact without that check stays
    exact; with ``"open"`` (an infinite depth past the edge) the same rays are not clear."""
    gb = _corridor_view()
    assert np.all(_claims(gb)[1][_claims(gb, offscreen=None)[1]])
    assert _past_the_edge(gb).sum() >= 50, _past_the_edge(gb).sum()
    np.testing.assert_array_equal(_claims(gb, offscreen="open")[1], _claims(gb, offscreen=None)[1])


@pytest.mark.parametrize("case", [dict(), dict(normal_clamp=True), dict(falloff="quadratic")],
                         ids=lambda c: ",".join(f"{k}={v}" for k, v in c.items()) or "default")
@pytest.mark.parametrize("pit", [False, True])
def test_past_the_edge_pixels_read_the_closed_form_in_every_group(case, pit, monkeypatch):
    """The segment kernel without the shortcut reads 1/2 (1 clamped) bit for bit in every group on
    the pixels exact past the edge, and the shortcut changes no value; the check has teeth: other
    pixels whose footprint leaves the image read something else (with the pit, some through the
    border's reads of the pit), and are not claimed."""
    gb = _corridor_view(pit)
    past = _past_the_edge(gb)
    _, extended = _claims(gb)
    on = P._reference(gb, samples=SEGMENTS, seed=9, along="segment", **_args(**case))
    with monkeypatch.context() as mp:
        mp.setattr(P, "_plane_tables", lambda *a, **k: None)
        off = P._reference(gb, samples=SEGMENTS, seed=9, along="segment", **_args(**case))
    expected = 1.0 if case.get("normal_clamp") else 0.5
    assert np.all(off.value[past] == expected), np.abs(off.value[past] - expected).max()
    np.testing.assert_array_equal(on.value, off.value)
    assert np.all(on.stderr[extended] == 0.0)
    # footprints that leave the image (the plane-only test's refusal) and read other values
    H, W = gb.shape
    i, j = np.indices(gb.shape)
    reach = RADIUS * gb.camera.fy / np.where(gb.valid, gb.depth, np.inf)
    leaves = gb.valid & (np.minimum(np.minimum(i, H - 1 - i), np.minimum(j, W - 1 - j)) < reach)
    assert (leaves & (off.value != expected)).sum() >= 50
    assert not extended[leaves & (off.value != expected)].any()


def test_past_the_edge_pixels_agree_with_point_sampling():
    """The independent point sampling of the ball agrees with 1/2 on every pixel exact past the
    edge (t-test with its reported stderr, Bonferroni over the pixels and this module's calls)."""
    gb = _corridor_view()
    past = _past_the_edge(gb)
    pts = P._reference(gb, samples=POINTS, seed=13, along="point", **_args())
    z = (pts.value[past] - 0.5) / pts.stderr[past]
    limit = t_threshold(DEFAULT_GROUPS - 1, tests=CALLS * int(past.sum()), false_failure=FALSE_FAILURE)
    assert np.all(pts.stderr[past] > 0)
    assert np.max(np.abs(z)) < limit, (np.abs(z).max(), limit)


@pytest.mark.parametrize("size", [1, 2, 3, 7, 64, 100])
def test_border_bounds_are_the_least_and_greatest_of_each_run(size):
    """The sparse tables behind the border lines' bounds give each run's least and greatest value,
    against a direct minimum and maximum (runs given in either order, clipped to the line)."""
    rng = np.random.default_rng(size)
    line = rng.random(size)
    line[rng.random(size) < 0.2] = np.inf                    # background
    table = S._RangeBounds(line)
    lo, hi = rng.integers(-3, size + 3, 400), rng.integers(-3, size + 3, 400)
    least, most = table.bounds(lo, hi)
    a, b = np.clip(np.minimum(lo, hi), 0, size - 1), np.clip(np.maximum(lo, hi), 0, size - 1)
    assert np.array_equal(least, [line[x:y + 1].min() for x, y in zip(a, b)])
    assert np.array_equal(most, [line[x:y + 1].max() for x, y in zip(a, b)])


@pytest.mark.parametrize("side", ["right", "left", "bottom", "top"])
def test_past_edge_bounds_hold_every_depth_the_clamped_fetch_reads(side):
    """The bounds of a box past the image's edge (texel rows i_lo..i_hi, or columns) hold every
    depth a ray landing past that edge level with the box reads with ``offscreen="clamp"``:
    the bilinear fetch itself (``_common.fetch_depth``, 1/z interpolated) at positions past the
    edge whose cell starts at one of the box's rows, against the bounds; background corners
    read the nearest texel, +inf or a finite one, both within the bounds."""
    rng = np.random.default_rng(["right", "left", "bottom", "top"].index(side))
    H, W = 23, 31
    depth = rng.uniform(1.0, 9.0, (H, W))
    depth[rng.random((H, W)) < 0.15] = np.inf
    tables = S.PlaneTables(np.ones((H, W), dtype=np.int64), depth)
    n = 300
    along = H if side in ("right", "left") else W
    lo = rng.integers(0, along, n)
    hi = np.minimum(lo + rng.integers(0, 5, n), along - 1)
    zeros = np.zeros(n, dtype=np.intp)
    if side in ("right", "left"):
        near, far = S.past_edge_bounds(tables, side, lo, hi, zeros, zeros, "clamp")
    else:
        near, far = S.past_edge_bounds(tables, side, zeros, zeros, lo, hi, "clamp")
    for k in range(8):
        # a position in the box's span along the edge (its cell starts at one of rows lo..hi)
        # and 0.1 to 5 pixels past the edge; pixel coordinates with centres at + 1/2
        t = lo + rng.random(n) * (hi - lo + 1) + 0.5
        past = rng.uniform(0.1, 5.0, n)
        x, y = {"right": (W - 0.5 + past, t), "left": (0.5 - past, t),
                "bottom": (t, H - 0.5 + past), "top": (t, 0.5 - past)}[side]
        d = Cm.fetch_depth(depth, x, y, fetch="bilinear", offscreen="clamp", reciprocal=True)
        ok = (d >= near * (1 - 1e-12)) & (d <= far * (1 + 1e-12))
        assert ok.all(), (side, k, np.flatnonzero(~ok)[:5])
