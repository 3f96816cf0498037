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
