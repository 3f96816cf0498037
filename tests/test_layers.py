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
from vobscure.layers import PeeledLayers, interval_count, intervals_from_layers  # noqa: E402

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
    pairs = [p for p in zip(s.front[:, 0, 0].tolist(), s.back[:, 0, 0].tolist()) if p != (INF, INF)]
    # the count the renderer allocates by, from the surfaces' kinds alone
    flat = [a.reshape(K, 1) for a in (layers.primitive >= 0, layers.entering, layers.open_surface)]
    assert interval_count(*flat).tolist() == [len(pairs)]
    return pairs


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


# ------------------------------------------------------------------ layer 0 borrowed
def _two_pixels(**kw):
    """Two pixels, two layers: a solid from 1 to 2.5 (triangles 3 and 1), and background;
    layer 0 borrowed from (H, W) images as the renderer borrows the G-buffer's."""
    return PeeledLayers(np.array([[[2.5, INF]]], np.float32), np.array([[[1, -1]]], np.int32),
                        np.array([[[True, False]], [[False, False]]]), face_normals=np.eye(4, 3),
                        rotation=np.eye(3), first=(np.array([[1.0, INF]]), np.array([[3, -1]])), **kw)


def test_a_borrowed_first_layer_reads_as_the_full_stack():
    layers = _two_pixels()
    assert layers.count == 2 and layers.shape == (1, 2)
    assert layers.depth.dtype == np.float32 and layers.primitive.dtype == np.int32
    assert layers.depth[:, 0].tolist() == [[1.0, INF], [2.5, INF]]
    assert layers.primitive[:, 0].tolist() == [[3, -1], [1, -1]]
    # stored: the layer behind (4 + 4 bytes a pixel) and entering of both layers (1 + 1)
    assert layers.nbytes == (4 + 4 + 2) * 2
    full = PeeledLayers(layers.depth, layers.primitive, layers.entering, face_normals=np.eye(4, 3),
                        rotation=np.eye(3))
    assert full.nbytes == 9 * 2 * 2
    a, b = intervals_from_layers(layers), intervals_from_layers(full)
    assert np.array_equal(a.front, b.front) and np.array_equal(a.back, b.back)
    assert a.front[:, 0].tolist() == [[1.0, INF]] and a.back[:, 0].tolist() == [[2.5, INF]]
    assert np.array_equal(layers.normal, full.normal)
    # a crop keeps layer 0 borrowed
    right = layers.crop(slice(0, 1), slice(1, 2))
    assert right.depth[:, 0, 0].tolist() == [INF, INF] and right.nbytes == 10


def test_open_flags_made_from_the_triangles():
    # triangle 1 (the layer behind) belongs to an open mesh; none where there is no surface
    layers = _two_pixels(open_triangle=np.array([False, True, False, False]))
    assert layers.open_surface[:, 0].tolist() == [[False, False], [True, False]]
    assert layers.nbytes == (4 + 4 + 2) * 2
    assert layers.crop(slice(0, 1), slice(0, 1)).open_surface[:, 0, 0].tolist() == [False, True]
    assert not _two_pixels().open_surface.any()


def test_borrowed_first_layer_errors():
    with pytest.raises(ValueError, match="first must be a pair"):
        PeeledLayers(np.ones((1, 1, 2)), np.zeros((1, 1, 2), int), np.zeros((2, 1, 2), bool),
                     face_normals=[[0, 0, 1]], rotation=np.eye(3), first=np.ones((1, 2)))
    with pytest.raises(ValueError, match="first's depth must be a float array"):
        PeeledLayers(np.ones((1, 1, 2)), np.zeros((1, 1, 2), int), np.zeros((2, 1, 2), bool),
                     face_normals=[[0, 0, 1]], rotation=np.eye(3), first=(np.ones((2, 1)), np.zeros((1, 2), int)))
    with pytest.raises(ValueError, match="first's primitive must be an integer array"):
        PeeledLayers(np.ones((1, 1, 2)), np.zeros((1, 1, 2), int), np.zeros((2, 1, 2), bool),
                     face_normals=[[0, 0, 1]], rotation=np.eye(3), first=(np.ones((1, 2)), np.zeros((1, 2))))
    with pytest.raises(ValueError, match=r"entering must be a bool array of shape \(2, 1, 2\)"):
        PeeledLayers(np.ones((1, 1, 2)), np.zeros((1, 1, 2), int), np.zeros((1, 1, 2), bool),
                     face_normals=[[0, 0, 1]], rotation=np.eye(3), first=(np.ones((1, 2)), np.zeros((1, 2), int)))
    with pytest.raises(ValueError, match="open_surface or open_triangle, not both"):
        _two_pixels(open_surface=np.zeros((2, 1, 2), bool), open_triangle=np.zeros(4, bool))
    with pytest.raises(ValueError, match="open_triangle must be a bool array of shape \\(4,\\)"):
        _two_pixels(open_triangle=np.zeros(3, bool))


# ------------------------------------------------------------------ float32 intervals, read
def test_float32_intervals_are_read_in_their_precision():
    """The renderer's float32 intervals against float64 tap and sample depths: compared in
    float32, a surface's own depth d meets the interval that starts (or is) at float32(d)."""
    from vobscure.screenspace import _common as C

    d = 1.0 + 2.0 ** -30                          # float32 rounds it down to 1.0
    d32 = float(np.float32(d))
    assert d32 < d
    idx = np.zeros(1, dtype=np.intp)
    # an open sheet at d, then a solid 2..3: the tapped occluder is the sheet, of no thickness
    sheet = SolidIntervals([[[d32]], [[2.0]]], [[[d32]], [[3.0]]], dtype=np.float32)
    assert C.interval_back(sheet, idx, np.array([d])).tolist() == [d]
    # the same ends in float64 are read as they are: the sheet ends before d, the solid is found
    assert C.interval_back(sheet.astype(np.float64), idx, np.array([d])).tolist() == [3.0]
    # a sample at the surface's own depth is outside, as the depth test z > d has it; past
    # float32's rounding it is inside
    solid = SolidIntervals([[[d32]]], [[[INF]]], dtype=np.float32)
    z = np.array([d, float(np.nextafter(np.float32(d32), np.float32(2.0)))])
    assert C.inside_intervals(solid, np.zeros(2, np.intp), z).tolist() == [False, True]
    assert C.inside_intervals(solid.astype(np.float64), np.zeros(2, np.intp), z).tolist() == [True, True]
