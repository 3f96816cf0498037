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
    assert r.rmse == 0.25 and np.isnan(r.ssim) and np.isnan(r.flip)
    r = vo.error(np.full((4, 4), np.nan), np.zeros((4, 4)))
    assert np.isnan(r.flip)


def test_bad_inputs():
    with pytest.raises(ValueError, match="same shape"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="mask"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 3)), mask=np.ones((2, 2), bool))
    with pytest.raises(ValueError, match="mask"):
        vo.error(np.zeros((3, 3)), np.zeros((3, 3)), mask=np.ones((3, 3)))
    with pytest.raises(ValueError, match="estimate"):
        vo.error("abc", np.zeros(3))


# ----------------------------------------------------------------------------- decompose
#: |total - (estimate - ao)|: the telescoped sum against the direct difference, float64 rounding.
TELESCOPE_ATOL = 1e-15


def _decomposition_inputs(shape=(12, 16), seed=0, dtype=np.float64):
    rng = np.random.default_rng(seed)
    E, S, W, A, O = (rng.random(shape).astype(dtype) for _ in range(5))
    E[0, :3] = np.nan          # background of the estimate
    S[1, 0] = np.nan
    W[2, :2] = np.inf          # non-finite counts as undefined too
    A[3, 4] = np.nan
    return E, S, W, A, O


def test_decompose_identity_is_exact_per_pixel():
    E, S, W, A, O = _decomposition_inputs()
    d = vo.metrics.decompose(E, S, W, ao=A, obscurance=O)
    use = np.isfinite(E) & np.isfinite(S) & np.isfinite(W) & np.isfinite(A) & np.isfinite(O)
    assert d.pixels == use.sum() == 12 * 16 - 7 and d.ignored == 7
    assert d.undefined == {"estimate": 3, "screen_reference": 1, "world_vo": 2, "ao": 1, "obscurance": 0}
    np.testing.assert_array_equal(d.sampling + d.screen + d.model, d.total)    # bit for bit
    np.testing.assert_array_equal(d.sampling[use], E[use] - S[use])
    np.testing.assert_array_equal(d.screen[use], S[use] - W[use])
    np.testing.assert_array_equal(d.model[use], W[use] - A[use])
    np.testing.assert_array_equal(d.model_obscurance[use], W[use] - O[use])
    np.testing.assert_allclose(d.total[use], E[use] - A[use], rtol=0, atol=TELESCOPE_ATOL)
    for m in (d.sampling, d.screen, d.model, d.total, d.model_obscurance):
        assert np.array_equal(np.isnan(m), ~use) and m.dtype == np.float64
    assert d.target == "ao"
    # summaries over the same pixels, by hand
    for term, diff in (("sampling", E - S), ("screen", S - W), ("model", W - A), ("total", E - A)):
        x = diff[use]
        s = d.summary[term]
        assert s.rmse == pytest.approx(np.sqrt(np.mean(x ** 2)), rel=1e-12)
        assert s.bias == pytest.approx(np.mean(x), rel=1e-12)
        assert s.mae == pytest.approx(np.mean(np.abs(x)), rel=1e-12)
    b = d.summary
    assert b["sampling"].bias + b["screen"].bias + b["model"].bias == pytest.approx(b["total"].bias, abs=1e-14)
    row = d.as_dict()
    assert row["total_rmse"] == b["total"].rmse and row["pixels"] == d.pixels and row["target"] == "ao"
    assert "model_obscurance_bias" in row


def test_decompose_without_ao_and_with_mask():
    E, S, W, _, _ = _decomposition_inputs(dtype=np.float32)
    mask = np.zeros(E.shape, bool)
    mask[4:, :] = True
    d = vo.metrics.decompose(E, S, W, mask=mask)
    assert d.model is None and d.model_obscurance is None and d.target == "volumetric"
    assert set(d.summary) == {"sampling", "screen", "total"}
    np.testing.assert_array_equal(d.sampling + d.screen, d.total)
    assert d.pixels == 8 * 16 and d.ignored == 4 * 16    # every undefined pixel lies in rows 0-3
    use = mask
    E64, S64, W64 = (a.astype(np.float64) for a in (E, S, W))
    np.testing.assert_allclose(d.total[use], E64[use] - W64[use], rtol=0, atol=TELESCOPE_ATOL)
    assert np.all(np.isnan(d.total[~mask]))


def test_decompose_accepts_estimates_and_handles_all_background():
    E, S, W, A, _ = _decomposition_inputs(shape=(4, 5))
    est = vo.Estimate(W, np.zeros_like(W), 64)
    d = vo.metrics.decompose(E, S, est, ao=vo.Estimate(A, np.zeros_like(A), 64))
    np.testing.assert_array_equal(d.screen, vo.metrics.decompose(E, S, W, ao=A).screen)
    empty = vo.metrics.decompose(np.full((3, 3), np.nan), np.zeros((3, 3)), np.zeros((3, 3)))
    assert empty.pixels == 0 and empty.ignored == 9 and np.isnan(empty.summary["total"].rmse)


def test_decompose_bad_inputs_name_the_argument():
    a = np.zeros((3, 4))
    with pytest.raises(ValueError, match="screen_reference"):
        vo.metrics.decompose(a, np.zeros((4, 3)), a)
    with pytest.raises(ValueError, match="world_vo"):
        vo.metrics.decompose(a, a, np.zeros(12))
    with pytest.raises(ValueError, match="^ao"):
        vo.metrics.decompose(a, a, a, ao=np.zeros((3, 5)))
    with pytest.raises(ValueError, match="obscurance"):
        vo.metrics.decompose(a, a, a, obscurance="x")
    with pytest.raises(ValueError, match="mask"):
        vo.metrics.decompose(a, a, a, mask=np.ones((3, 4)))
    with pytest.raises(ValueError, match="mask"):
        vo.metrics.decompose(a, a, a, mask=np.ones((4, 3), bool))


# ----------------------------------------------------------------------------- flicker
def test_flicker_known_sequences():
    rng = np.random.default_rng(3)
    base = rng.random((6, 5))
    constant = np.repeat(base[None], 7, axis=0)
    f = vo.metrics.flicker(constant)
    assert f.value == 0 and f.estimate_change == 0 and np.isnan(f.reference_change)
    assert f.estimate_flip == 0 and np.isnan(f.reference_flip)
    assert f.pairs == 6 * 30 and f.ignored == 0
    d = 0.05
    steps = base[None] + d * (np.arange(7) % 2)[:, None, None]      # x, x + d, x, x + d, ...
    assert vo.metrics.flicker(steps).value == pytest.approx(d, rel=1e-12)
    signs = base[None] + d * np.array([1, -1] * 3 + [1])[:, None, None]   # x + d, x - d, ...
    assert vo.metrics.flicker(signs).value == pytest.approx(2 * d, rel=1e-12)
    # a reference that moves by r every frame: what remains is the estimator's own flicker
    r = 0.01
    ref = base[None] + r * np.arange(7)[:, None, None]
    est = ref + d * (np.arange(7) % 2)[:, None, None]           # |r +- d| alternately: mean d
    f = vo.metrics.flicker(est, ref)
    assert f.reference_change == pytest.approx(r, rel=1e-9)
    assert f.estimate_change == pytest.approx(d, rel=1e-9)     # (d + r + d - r) / 2
    assert f.value == pytest.approx(d - r, rel=1e-9)
    assert vo.metrics.flicker(ref, ref).value == 0


def test_flicker_nan_and_masks():
    frames = np.full((3, 2, 2), 0.5)
    frames[1] += 0.1
    frames[1, 0, 0] = np.nan                       # pixel (0, 0) undefined in frame 1: both pairs
    frames[2, 1, 1] = np.inf                       # (1, 1) undefined in frame 2: the second pair
    f = vo.metrics.flicker(frames)
    assert f.pairs == 2 * 4 - 3 and f.ignored == 3
    assert f.value == pytest.approx(0.1, rel=1e-12)
    mask = np.array([[True, False], [True, True]])
    g = vo.metrics.flicker(frames, mask=mask)
    assert g.pairs == 5 - 2 and g.ignored == 5      # (0, 1) masked out of both pairs
    per_frame = np.ones((3, 2, 2), bool)
    per_frame[2] = False                            # frame 2 unused: only the first pair counts
    h = vo.metrics.flicker(frames, mask=per_frame)
    assert h.pairs == 3 and h.value == pytest.approx(0.1, rel=1e-12)
    none = vo.metrics.flicker(np.full((2, 3), np.nan))
    assert none.pairs == 0 and none.ignored == 3 and np.isnan(none.value)
    ref = np.full((3, 2, 2), 0.5)
    ref[0, 1, 0] = np.nan                           # the reference's undefined pixels count too
    assert vo.metrics.flicker(frames, ref).pairs == f.pairs - 1


def test_flicker_bad_inputs_name_the_argument():
    with pytest.raises(ValueError, match="frames"):
        vo.metrics.flicker(np.zeros((1, 4, 4)))
    with pytest.raises(ValueError, match="frames"):
        vo.metrics.flicker(np.zeros(5))
    with pytest.raises(ValueError, match="reference_frames"):
        vo.metrics.flicker(np.zeros((3, 4, 4)), np.zeros((3, 4, 5)))
    with pytest.raises(ValueError, match="mask"):
        vo.metrics.flicker(np.zeros((3, 4, 4)), mask=np.ones((4, 5), bool))
    with pytest.raises(ValueError, match="mask"):
        vo.metrics.flicker(np.zeros((3, 4, 4)), mask=np.ones((4, 4)))


# ----------------------------------------------------------------------------- point models
def test_correlation_matches_scipy_and_ignores_nan_pairs():
    from scipy import stats

    from vobscure.metrics import correlation

    rng = np.random.default_rng(3)
    a = rng.random(50)
    b = a + rng.normal(0, 0.3, 50)
    assert correlation(a, b) == pytest.approx(stats.pearsonr(a, b).statistic, rel=1e-12)
    a_nan, b_nan = a.copy(), b.copy()
    a_nan[3], b_nan[7] = np.nan, np.inf
    keep = np.ones(50, bool)
    keep[[3, 7]] = False
    assert correlation(a_nan, b_nan) == pytest.approx(stats.pearsonr(a[keep], b[keep]).statistic, rel=1e-12)


@pytest.mark.parametrize("a, b", [([0.5, 0.5, 0.5, 0.5], [0.1, 0.2, 0.3, 0.4]),   # a constant model
                                  ([0.1, 0.2, 0.3], [0.7, 0.7, 0.7]),             # a constant reference
                                  ([0.1, 0.2], [0.3, 0.5])])                      # too few pairs
def test_correlation_is_nan_where_undefined(a, b):
    from vobscure.metrics import correlation

    assert np.isnan(correlation(a, b))


def test_calibration_rmse_hand_made_and_its_limits():
    """Three bins of two points by hand; one bin is the |bias|, one point a bin the RMSE, and
    in between it never exceeds the RMSE (Cauchy-Schwarz)."""
    from vobscure.metrics import calibration_rmse

    m = [0.9, 0.1, 0.5, 0.2, 0.6, 1.0]         # sorted: 0.1 0.2 | 0.5 0.6 | 0.9 1.0
    r = [0.7, 0.3, 0.6, 0.2, 0.6, 1.0]         # their references: 0.3 0.2 | 0.6 0.6 | 0.7 1.0
    # bin mean differences: 0.15 - 0.25, 0.55 - 0.6, 0.95 - 0.85
    want = np.sqrt(2 * (0.1 ** 2 + 0.05 ** 2 + 0.1 ** 2) / 6)
    assert calibration_rmse(m, r, bins=3) == pytest.approx(want, rel=1e-12)
    rng = np.random.default_rng(4)
    a, b = rng.random(101), rng.random(101)
    rmse = np.sqrt(np.mean((a - b) ** 2))
    assert calibration_rmse(a, b, bins=1) == pytest.approx(abs(np.mean(a - b)), rel=1e-12)
    assert calibration_rmse(a, b, bins=101) == pytest.approx(rmse, rel=1e-12)
    assert calibration_rmse(a, b, bins=500) == pytest.approx(rmse, rel=1e-12)   # capped at n
    assert 0 <= calibration_rmse(a, b) <= rmse
    with pytest.raises(ValueError, match="bins"):
        calibration_rmse(a, b, bins=0)
    with pytest.raises(ValueError, match="reference"):
        calibration_rmse(a, b[:-1])


# ----------------------------------------------------------------------------- ray counts
def test_equal_error_rays_interpolates_and_extrapolates():
    """RMSE halving per 4x rays is the line log RMSE = log 0.4 - (1/2) log rays: 0.1 at 16
    rays, 0.1 / sqrt(2) at 32 (between points), 0.4 at 1 ray (beyond the measured end)."""
    from vobscure.metrics import equal_error_rays

    rays, rmse = [4, 16, 64], [0.2, 0.1, 0.05]
    r, extra = equal_error_rays(rays, rmse, 0.1)
    assert not extra and r == pytest.approx(16.0, rel=1e-12)
    r, extra = equal_error_rays(rays, rmse, 0.1 / np.sqrt(2))
    assert not extra and r == pytest.approx(32.0, rel=1e-12)
    r, extra = equal_error_rays(rays, rmse, 0.4)
    assert extra and r == pytest.approx(1.0, rel=1e-12)
    r, extra = equal_error_rays(rays, rmse, 0.025)
    assert extra and r == pytest.approx(256.0, rel=1e-12)
    # a flat curve extrapolates with the Monte Carlo slope -1/2: 4x the rays for half the error
    r, extra = equal_error_rays([4, 16], [0.2, 0.2], 0.1)
    assert extra and r == pytest.approx(64.0, rel=1e-12)
    with pytest.raises(ValueError, match="increasing"):
        equal_error_rays([16, 4], [0.1, 0.2], 0.1)
    with pytest.raises(ValueError, match="positive"):
        equal_error_rays([4, 16], [0.1, 0.0], 0.1)


def test_equal_error_rays_is_monotone_on_a_curve_that_rises_once():
    """A noisy measured curve may rise once; the answer is still one count per target, and
    never more rays for a larger error."""
    from vobscure.metrics import equal_error_rays

    rays, rmse = [4, 8, 16, 32, 64], [0.2, 0.1, 0.12, 0.06, 0.03]
    counts = [equal_error_rays(rays, rmse, t)[0] for t in np.geomspace(0.02, 0.3, 60)]
    assert np.all(np.diff(counts) <= 1e-9 * np.maximum(counts[:-1], 1.0))
    # between 8 and 16 rays the running minimum is flat at 0.1: 0.1 is reached at 8 rays
    assert equal_error_rays(rays, rmse, 0.1)[0] == pytest.approx(8.0, rel=1e-12)


# ------------------------------------------------------------------ the thin-feature band
def _step(width=16, height=6, edge=5, near=2.0, far=5.0):
    """A vertical step edge: columns < edge at depth ``near``, the rest at ``far``."""
    depth = np.full((height, width), far)
    depth[:, :edge] = near
    return depth


@pytest.mark.parametrize("width", [1, 2, 3, 5])
def test_thin_band_lies_behind_a_step_edge_with_the_width_asked(width):
    band = vo.metrics.thin_feature_mask(_step(), width=width)
    expect = np.zeros(band.shape, dtype=bool)
    expect[:, 5:5 + width] = True           # the far side, `width` columns from the silhouette
    np.testing.assert_array_equal(band, expect)


def test_thin_band_follows_the_far_side_whichever_way_the_edge_faces():
    depth = _step()[:, ::-1]                # the near object on the right
    band = vo.metrics.thin_feature_mask(depth, width=2)
    assert band.sum() == 2 * depth.shape[0] and np.all(band[:, -7:-5]) and not band[:, -5:].any()


def test_thin_band_ignores_small_jumps_and_background():
    depth = _step(near=4.8)                 # a 4 % jump: below THIN_JUMP
    assert not vo.metrics.thin_feature_mask(depth, width=3).any()
    assert vo.metrics.thin_feature_mask(depth, width=3, jump=0.03).sum() == 3 * depth.shape[0]
    sky = _step(far=np.inf)                 # an object against the background: no surface behind it
    assert not vo.metrics.thin_feature_mask(sky, width=3).any()


def test_thin_band_is_empty_on_a_rendered_plane(slab):
    cam = vo.Camera.look_at((0.3, 2.5, 2.0), (0.0, 0.0, -0.2), size=(64, 48), fov_y=50.0)
    gb = vo.render_gbuffer(slab, cam)
    assert gb.valid.mean() > 0.5
    assert not vo.metrics.thin_feature_mask(gb, radius=0.5).any()


def test_thin_band_width_from_the_projected_radius():
    # orthographic: every pixel's projected radius is R * fy = 0.25 * (6 / 0.5) = 3 pixels
    cam = vo.Camera.look_at((0, 0, 10), (0, 0, 0), size=(16, 6), ortho_height=0.5)
    gb = vo.GBuffer.from_arrays(_step(), camera=cam)
    band = vo.metrics.thin_feature_mask(gb, radius=0.25)
    np.testing.assert_array_equal(band, vo.metrics.thin_feature_mask(_step(), width=3))
    # perspective: the far pixels' own projected radius, ceil(R fy / z_far)
    cam = vo.Camera.look_at((0, 0, 10), (0, 0, 0), size=(16, 6), fov_y=60.0)
    gb = vo.GBuffer.from_arrays(_step(), camera=cam)
    w = int(np.ceil(2.0 * cam.fy / 5.0))
    assert w == 3
    np.testing.assert_array_equal(vo.metrics.thin_feature_mask(gb, radius=2.0),
                                  vo.metrics.thin_feature_mask(_step(), width=w))


def test_error_restricted_to_the_thin_band():
    rng = np.random.default_rng(3)
    depth = _step()
    band = vo.metrics.thin_feature_mask(depth, width=2)
    ref = rng.random(depth.shape)
    est = ref + rng.normal(0.0, 0.1, depth.shape)
    r = vo.error(est, ref, mask=band)
    d = est[:, 5:7] - ref[:, 5:7]           # the band, indexed by hand
    assert r.pixels == d.size and r.ignored == depth.size - d.size
    assert r.rmse == pytest.approx(np.sqrt(np.mean(d ** 2)), rel=1e-12)
    assert r.bias == pytest.approx(np.mean(d), rel=1e-12)


def test_thin_band_of_a_guarded_gbuffer_is_of_the_inner_frame():
    scene = vo.scenes.cornell_box()
    cam = scene.camera((32, 24))
    guarded = vo.render_gbuffer(scene, cam, guard=4)
    band = vo.metrics.thin_feature_mask(guarded, radius=0.2)
    assert band.shape == (24, 32)
    # the inner frame's own band can only miss silhouettes that lie in the guard band
    inner = vo.metrics.thin_feature_mask(guarded.inner(), radius=0.2)
    assert band.any() and np.all(band[inner])


@pytest.mark.parametrize("kwargs, match", [(dict(width=0), "width"), (dict(jump=0.0), "jump"),
                                           (dict(jump=np.nan), "jump"), (dict(radius=0.1), "radius"),
                                           (dict(radius=0.1, width=2), "not both")])
def test_thin_band_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        vo.metrics.thin_feature_mask(_step(), **kwargs)
