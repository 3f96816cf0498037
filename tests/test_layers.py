"""SolidIntervals: validation, lookup, and the G-buffer carrying them."""

import numpy as np
import pytest

import vobscure as vo
from vobscure.layers import SolidIntervals

INF = np.inf


def two_pixels():
    # pixel 0: solid on [1, 2] and from 3 on; pixel 1: one solid [0.5, 0.75]
    front = np.array([[[1.0, 0.5]], [[3.0, INF]]])
    back = np.array([[[2.0, 0.75]], [[INF, INF]]])
    return SolidIntervals(front, back)


def test_inside_by_hand():
    s = two_pixels()
    z = np.array([0.9, 1.0, 1.5, 2.0, 2.5, 3.0, 1e9, 0.4, 0.6, 0.8])
    index = np.array([0, 0, 0, 0, 0, 0, 0, 1, 1, 1])
    assert s.inside(z, index).tolist() == [False, True, True, True, False, True, True, False, True, False]


def test_at_gathers_columns():
    s = two_pixels()
    f, b = s.at(np.array([1, 0]))
    assert f.tolist() == [[0.5, 1.0], [INF, 3.0]]
    assert b.tolist() == [[0.75, 2.0], [INF, INF]]


@pytest.mark.parametrize("front, back, match", [
    (np.ones((2, 2)), np.ones((2, 2)), "front must have shape"),
    (np.ones((1, 2, 2)), np.ones((1, 2, 3)), "back must have the shape"),
    (np.full((1, 1, 1), np.nan), np.ones((1, 1, 1)), "NaN"),
    (np.full((1, 1, 1), 2.0), np.ones((1, 1, 1)), "back must be >= front"),
    (np.array([[[3.0]], [[1.0]]]), np.array([[[4.0]], [[2.0]]]), "ascending and disjoint"),
    (np.array([[[INF]], [[1.0]]]), np.array([[[INF]], [[2.0]]]), "unused slots"),
])
def test_bad_intervals(front, back, match):
    with pytest.raises(ValueError, match=match):
        SolidIntervals(front, back)


def test_gbuffer_carries_intervals_through_astype():
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
    gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    layered = gb.with_intervals(SolidIntervals(gb.depth[None], gb.depth[None] + 0.25))
    assert gb.intervals is None
    g32 = layered.astype(np.float32)
    assert g32.intervals.dtype == np.float32
    assert np.array_equal(g32.intervals.back, (gb.depth[None] + 0.25).astype(np.float32))
    assert np.array_equal(layered.depth, gb.depth)
    with pytest.raises(ValueError, match="image's shape"):
        gb.with_intervals(SolidIntervals(np.ones((1, 2, 2)), np.ones((1, 2, 2))))
    with pytest.raises(ValueError, match="SolidIntervals"):
        gb.with_intervals(np.ones((1, 4, 4)))


# ------------------------------------------------------------------ the enter/leave rule
from vobscure.layers import PeeledLayers, intervals_from_layers  # noqa: E402

E, L, S = "enter", "leave", "sheet"


def _one_ray(events, origin_inside=None):
    """Intervals of one pixel whose ray crosses ``events`` [(depth, kind), ...] in order."""
    K = len(events)
    depth = np.array([z for z, _ in events], float).reshape(K, 1, 1)
    kinds = [k for _, k in events]
    layers = PeeledLayers(depth, np.zeros((K, 1, 1), int),
                          np.array([k == E for k in kinds]).reshape(K, 1, 1),
                          face_normals=[[0, 0, 1]], rotation=np.eye(3),
                          open_surface=np.array([k == S for k in kinds]).reshape(K, 1, 1))
    inside = None if origin_inside is None else np.array([[origin_inside]])
    s = intervals_from_layers(layers, origin_inside=inside)
    pairs = list(zip(s.front[:, 0, 0].tolist(), s.back[:, 0, 0].tolist()))
    return [p for p in pairs if p != (INF, INF)]


@pytest.mark.parametrize("events, expected", [
    ([(1, E), (2, L)], [(1, 2)]),                                   # a box
    ([(1, E), (2, L), (3, E), (4, L)], [(1, 2), (3, 4)]),           # two boxes
    ([(1, E), (2, L), (3, E)], [(1, 2), (3, INF)]),                 # the layers ran out inside
    ([(1, L), (3, E), (4, L)], [(0, 1), (3, 4)]),                   # the camera inside
    ([(1, E), (2, L), (3, L)], [(1, 3)]),                           # touching: the entry at 2 skipped
    ([(1, E), (2, E), (3, L)], [(1, 3)]),                           # touching: the leave at 2 skipped
    ([(1, E), (2, E), (3, L), (4, L)], [(1, 4)]),                   # overlapping solids
    ([(1, E), (2, E), (3, L), (4, L), (5, E), (6, L)], [(1, 4), (5, 6)]),
    ([(1, S), (2, E), (3, S), (4, L), (5, S)], [(1, 1), (2, 4), (5, 5)]),   # open sheets
    ([(1, S), (2, L)], [(1, 2)]),                                   # a leave after a sheet extends it
    ([], []),
])
def test_enter_leave_rule_by_hand(events, expected):
    if not events:   # a pixel with no surface: one unused slot
        layers = PeeledLayers(np.full((2, 1, 1), INF), np.full((2, 1, 1), -1), np.zeros((2, 1, 1), bool),
                              face_normals=[[0, 0, 1]], rotation=np.eye(3))
        s = intervals_from_layers(layers)
        assert s.count == 1 and np.isinf(s.front).all() and np.isinf(s.back).all()
        return
    assert _one_ray(events) == expected


def test_first_leave_with_the_origin_outside_starts_at_the_surface():
    # a ray through an edge shared with a touching solid: leave (the wall's top) then leave
    # (the ceiling's top); the camera is not inside the wall
    assert _one_ray([(1, L), (2, L)], origin_inside=False) == [(1, 2)]
    assert _one_ray([(1, L), (2, L)], origin_inside=True) == [(0, 2)]
    assert _one_ray([(1, L), (3, E), (4, L)], origin_inside=False) == [(1, 1), (3, 4)]


def test_documented_limit_three_solids_in_a_chain():
    """A overlaps B, B overlaps C, A and C apart: the rule leaves a gap inside B (documented)."""
    assert _one_ray([(1, E), (2, E), (3, L), (4, E), (5, L), (6, L)]) == [(1, 3), (4, 6)]


def test_rounding_never_reorders_layers():
    # float32 depths one ulp out of order (a face hit twice at a grazing edge)
    z = np.float32(2.0)
    below = np.nextafter(z, np.float32(0))
    assert _one_ray([(1, E), (float(z), L), (float(below), E), (3, L)]) == [(1, 2), (2, 3)]


def test_peeled_layers_errors_and_astype_keeps_them():
    ok = dict(face_normals=[[0, 0, 1]], rotation=np.eye(3))
    with pytest.raises(ValueError, match="depth must have shape"):
        PeeledLayers(np.ones((2, 2)), np.zeros((2, 2), int), np.zeros((2, 2), bool), **ok)
    with pytest.raises(ValueError, match="primitive must be an integer array"):
        PeeledLayers(np.ones((1, 2, 2)), np.zeros((1, 2, 2)), np.zeros((1, 2, 2), bool), **ok)
    with pytest.raises(ValueError, match="entering must be a bool array"):
        PeeledLayers(np.ones((1, 2, 2)), np.zeros((1, 2, 2), int), np.zeros((1, 2, 2)), **ok)
    with pytest.raises(ValueError, match="layers must be a vobscure.layers.PeeledLayers"):
        intervals_from_layers(np.ones((1, 2, 2)))
    layers = PeeledLayers(np.ones((1, 2, 2)), np.zeros((1, 2, 2), int), np.ones((1, 2, 2), bool), **ok)
    s = intervals_from_layers(layers)
    assert s.astype(np.float32).layers is layers
    with pytest.raises(ValueError, match="layers must have the intervals' image shape"):
        SolidIntervals(np.ones((1, 3, 3)), np.ones((1, 3, 3)), layers=layers)
    with pytest.raises(ValueError, match="origin_inside must be a bool array"):
        intervals_from_layers(layers, origin_inside=np.ones((2, 2)))
