"""Masked error metrics."""

from __future__ import annotations

import numpy as np
import pytest
from skimage.metrics import structural_similarity

import vobscure as vo


def test_values_against_hand_computation():
    rng = np.random.default_rng(0)
    ref = rng.random((20, 30))
    est = ref + rng.normal(0, 0.05, ref.shape)
    est[0, :5] = np.nan
    ref[1, 0] = np.nan
    r = vo.error(est, ref)
    use = np.isfinite(est) & np.isfinite(ref)
    d = est[use] - ref[use]
    assert r.pixels == use.sum() == 600 - 6 and r.ignored == 6
    assert r.rmse == pytest.approx(np.sqrt(np.mean(d ** 2)), rel=1e-12)
    assert r.mae == pytest.approx(np.mean(np.abs(d)), rel=1e-12)
    assert r.bias == pytest.approx(np.mean(d), rel=1e-12)
    assert r.max_abs == pytest.approx(np.abs(d).max(), rel=1e-12)
    assert r.psnr == pytest.approx(10 * np.log10(1 / np.mean(d ** 2)), rel=1e-12)
    assert -1 <= r.ssim <= 1


def test_ssim_matches_scikit_image_without_nan():
    rng = np.random.default_rng(1)
    ref = rng.random((16, 16))
    est = np.clip(ref + rng.normal(0, 0.1, ref.shape), 0, 1)
    r = vo.error(est, ref)
    assert r.ssim == pytest.approx(structural_similarity(est, ref, data_range=1.0), rel=1e-12)


def test_identity_and_mask():
    ref = np.linspace(0, 1, 64).reshape(8, 8)
    r = vo.error(ref, ref)
    assert r.rmse == 0 and r.psnr == np.inf and r.ssim == pytest.approx(1.0)
    mask = np.zeros((8, 8), bool)
    mask[:2] = True
    r = vo.error(ref + 0.2, ref, mask=mask)
    assert r.pixels == 16 and r.ignored == 48 and r.bias == pytest.approx(0.2)


def test_empty_and_small():
    r = vo.error(np.full((4, 4), np.nan), np.zeros((4, 4)))
    assert r.pixels == 0 and r.ignored == 16 and np.isnan(r.rmse)
    r = vo.error(np.array([0.5]), np.array([0.25]))
    assert r.rmse == 0.25 and np.isnan(r.ssim)


def test_bad_inputs():
    with pytest.raises(ValueError, match="same shape"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="mask"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 3)), mask=np.ones((2, 2), bool))
    with pytest.raises(ValueError, match="mask"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 3)), mask=np.ones((3, 3)))
    with pytest.raises(ValueError, match="estimate"):
        vo.error("abc", np.zeros(3))
