"""Warps and the RQMC direction generator."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from vobscure.sampling import (cube_to_uniform_ball, cube_to_uniform_half_ball, shifted_hemisphere_directions,
                               square_to_cosine_hemisphere, square_to_uniform_disk, square_to_uniform_disk_concentric,
                               square_to_uniform_half_disk, square_to_uniform_hemisphere, tangent_frame, to_world)

#: KS-test false-failure rate per assertion
ALPHA = 1e-4


def test_cosine_warp_distribution():
    u = np.random.default_rng(0).random((20000, 2))
    d = square_to_cosine_hemisphere(u)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    # pdf cos(theta)/pi  <=>  cos^2(theta) uniform on [0, 1]; azimuth uniform
    assert stats.kstest(d[:, 2] ** 2, "uniform").pvalue > ALPHA
    assert stats.kstest((np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi)) % 1, "uniform").pvalue > ALPHA


def test_uniform_warps_distribution():
    rng = np.random.default_rng(1)
    d = square_to_uniform_hemisphere(rng.random((20000, 2)))
    assert stats.kstest(d[:, 2], "uniform").pvalue > ALPHA  # uniform solid angle: cos(theta) uniform
    x = cube_to_uniform_ball(rng.random((20000, 3)))
    r = np.linalg.norm(x, axis=1)
    assert stats.kstest(r ** 3, "uniform").pvalue > ALPHA  # uniform volume: r^3 uniform
    assert stats.kstest((x[:, 2] / r + 1) / 2, "uniform").pvalue > ALPHA



@pytest.mark.parametrize("warp, half", [(square_to_uniform_disk, False), (square_to_uniform_half_disk, True),
                                        (square_to_uniform_disk_concentric, False)])
def test_disk_warps_distribution(warp, half):
    x = warp(np.random.default_rng(3).random((20000, 2)))
    r2 = np.sum(x * x, axis=1)
    assert np.all(r2 <= 1.0 + 1e-12)
    assert stats.kstest(r2, "uniform").pvalue > ALPHA  # uniform area: r^2 uniform
    angle = np.arctan2(x[:, 1], x[:, 0])
    if half:
        assert np.all(x[:, 0] >= 0)
        assert stats.kstest(angle / np.pi + 0.5, "uniform").pvalue > ALPHA
    else:
        assert stats.kstest(angle / (2 * np.pi) % 1, "uniform").pvalue > ALPHA


def test_half_ball_warp_distribution():
    x = cube_to_uniform_half_ball(np.random.default_rng(4).random((20000, 3)))
    r = np.linalg.norm(x, axis=1)
    assert np.all(x[:, 2] >= 0) and np.all(r <= 1.0 + 1e-12)
    assert stats.kstest(r ** 3, "uniform").pvalue > ALPHA  # uniform volume: r^3 uniform
    assert stats.kstest(x[:, 2] / r, "uniform").pvalue > ALPHA  # uniform over the hemisphere of directions

def test_tangent_frame_orthonormal_right_handed():
    n = np.random.default_rng(2).normal(size=(1000, 3))
    n = np.vstack([n, [[0, 0, 1], [0, 0, -1], [0, 0, -1 + 1e-12], [1, 0, 0]]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t, b = tangent_frame(n)
    for v in (t, b):
        np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(np.einsum("ij,ij->i", t, b), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.einsum("ij,ij->i", t, n), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.cross(t, b), n, atol=1e-9)


@pytest.mark.parametrize("weighting, warp", [("cosine", square_to_cosine_hemisphere),
                                             ("uniform", square_to_uniform_hemisphere)])
def test_fast_directions_equal_reference_path(weighting, warp):
    rng = np.random.default_rng(3)
    P, G, m = 7, 4, 16
    n = rng.normal(size=(P, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    base, shifts = rng.random((m, 2)), rng.random((P, G, 2))
    fast = shifted_hemisphere_directions(n, base, shifts, weighting)
    u = base[None, None] + shifts[:, :, None, :]
    u -= np.floor(u)
    slow = to_world(warp(u.reshape(P, -1, 2)), n).reshape(P, G, m, 3)
    assert fast.dtype == np.float32
    np.testing.assert_allclose(fast, slow, atol=1e-5)  # float32 rounding


def test_fused_origins_equal_tracer_offsets():
    import trimesh

    import vobscure as vo

    tracer = vo.Scene(trimesh.creation.box()).tracer
    rng = np.random.default_rng(4)
    P, G, m = 5, 2, 8
    n = rng.normal(size=(P, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    pts = rng.random((P, 3))
    base, shifts = rng.random((m, 2)), rng.random((P, G, 2))
    o, d = shifted_hemisphere_directions(n, base, shifts, origins=tracer.offset_origins(pts, n),
                                         step=tracer.offset)
    np.testing.assert_array_equal(d, shifted_hemisphere_directions(n, base, shifts))
    expect = tracer.offset_origins(pts, n, d.reshape(P, -1, 3)).reshape(o.shape)
    np.testing.assert_allclose(o, expect, rtol=0, atol=1e-6)
