"""The mip pyramid of depth moments (Loos & Sloan 2010, Sec. 4.2): exact on linear fields,
background ignored, odd sizes and lookups off the image, and slope lookups against a
brute-force mixture of the level-0 pixels."""

from __future__ import annotations

import numpy as np
import pytest

from vobscure.screenspace.area import RECONSTRUCTIONS
from vobscure.screenspace.pyramid import MomentPyramid


def _linear_field(H=96, W=128, gx=0.3, gy=-0.2):
    i, j = np.mgrid[:H, :W]
    return 1.0 + gx * (j + 0.5) + gy * (i + 0.5), gx, gy


@pytest.mark.parametrize("reconstruction", RECONSTRUCTIONS)
def test_pyramid_is_exact_on_linear_fields(reconstruction):
    q, gx, gy = _linear_field()
    pyr = MomentPyramid(q, np.ones(q.shape, bool), offscreen="clamp", prefilter=False)
    rng = np.random.default_rng(1)
    x, y = rng.uniform(40, 88, 500), rng.uniform(40, 56, 500)
    for lod in (0.0, 0.5, 1.0, 2.3, 3.0):
        cov, mean, var = pyr.lookup(x, y, np.full(500, lod), "clamp", reconstruction)
        np.testing.assert_allclose(cov, 1.0, atol=1e-14)
        np.testing.assert_allclose(mean, 1.0 + gx * x + gy * y, rtol=0, atol=1e-12)
        assert np.all(var >= 0)
        if reconstruction == "bspline":
            # texel variance (4^L - 1)/12 plus the B-spline's constant tap spread 4^L/4 per
            # axis, blended between levels: independent of the position
            L0 = int(np.floor(lod))
            t = lod - L0
            s2 = [(4.0 ** L - 1) / 12 + 4.0 ** L / 4 for L in (L0, L0 + 1)]
            expect = ((1 - t) * s2[0] + t * s2[1]) * (gx * gx + gy * gy)
            np.testing.assert_allclose(var, expect, rtol=1e-10)


def test_pyramid_ignores_background():
    q, _, _ = _linear_field(64, 64)
    finite = np.ones(q.shape, bool)
    finite[:, 32:] = False                       # right half is background
    q_bg = np.where(finite, q, 123.0)            # whatever is stored there must not matter
    pyr = MomentPyramid(q_bg, finite, offscreen="clamp", prefilter=False)
    # level 6 (1 x 1): half coverage, the mean and variance of the finite half only
    cov, mean, var = pyr.lookup(np.array([32.0]), np.array([32.0]), np.array([6.0]), "clamp", "trilinear")
    assert cov[0] == pytest.approx(0.5)
    assert mean[0] == pytest.approx(q[finite].mean(), rel=1e-12)
    assert var[0] == pytest.approx(q[finite].var(), rel=1e-10)
    # far inside the background: no coverage
    cov, _, _ = pyr.lookup(np.array([60.0]), np.array([10.0]), np.array([0.0]), "clamp", "bspline")
    assert cov[0] == 0.0


def test_pyramid_odd_sizes_and_offscreen():
    q = np.random.default_rng(2).uniform(1, 2, (7, 5))
    finite = np.ones(q.shape, bool)
    for offscreen in ("clamp", "open"):
        pyr = MomentPyramid(q, finite, offscreen=offscreen, prefilter=False)
        assert pyr.heights.tolist() == [7, 4, 2, 1] and pyr.widths.tolist() == [5, 3, 2, 1]
        cov, mean, var = pyr.lookup(np.array([-50.0, 2.5, np.nan]), np.array([3.5, 3.5, 1.0]),
                                    np.array([0.0, 0.0, 1.0]), offscreen, "bspline")
        assert np.all(np.isfinite(mean)) and np.all(np.isfinite(var))
        assert cov[2] == 0.0                      # a non-finite position reads empty space
        if offscreen == "open":
            assert cov[0] == 0.0                  # far off the image: empty space
        else:
            assert cov[0] == pytest.approx(1.0)   # the border extends outward


def test_pyramid_slope_lookup_matches_a_pixel_mixture():
    """The clamped pyramid (positions, level 0 implicit) against a brute-force mixture of the
    level-0 pixels: a trilinear lookup at level L is a mixture of the finite pixels, each
    weighted by its texel's tent weight over the texel's finite pixels."""
    rng = np.random.default_rng(4)
    H, W = 16, 12
    q = rng.uniform(1.0, 2.0, (H, W))
    finite = rng.random((H, W)) < 0.8
    pyr = MomentPyramid(q, finite, offscreen="clamp", prefilter=False, positions=True)
    assert pyr.skip == H * W                    # positions and moments start at level 1
    X, Y = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    for x, y, lod in ((5.3, 7.9, 0.0), (4.1, 6.6, 1.0), (6.2, 8.4, 0.4), (5.5, 7.0, 1.7)):
        g = rng.normal(size=2) * 0.1
        weights = np.zeros((H, W))
        L0 = int(np.floor(lod))
        for L, wl in ((L0, 1 - (lod - L0)), (L0 + 1, lod - L0)):
            s = 2 ** L
            fx, fy = x / s - 0.5, y / s - 0.5
            j0, i0 = int(np.floor(fx)), int(np.floor(fy))
            for i, wy in ((i0, 1 - (fy - i0)), (i0 + 1, fy - i0)):
                for j, wx in ((j0, 1 - (fx - j0)), (j0 + 1, fx - j0)):
                    block = (slice(i * s, (i + 1) * s), slice(j * s, (j + 1) * s))
                    weights[block] += wl * wy * wx * finite[block] / s ** 2
        carried = q - g[0] * (X - x) - g[1] * (Y - y)
        expect_mean = np.sum(weights * carried) / weights.sum()
        expect_var = np.sum(weights * (carried - expect_mean) ** 2) / weights.sum()
        cov, mean, var = pyr.lookup(np.array([x]), np.array([y]), np.array([lod]), "clamp", "trilinear",
                                    slope=(np.array([g[0]]), np.array([g[1]])))
        assert cov[0] == pytest.approx(weights.sum(), rel=1e-12)
        assert mean[0] == pytest.approx(expect_mean, rel=1e-12)
        assert var[0] == pytest.approx(expect_var, rel=1e-9)
