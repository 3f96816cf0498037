"""FLIP on visibility images: `vobscure.metrics.flip`, `ErrorReport.flip` and the FLIP of `flicker`.

The independent computation is the colour pipeline of LDR-FLIP (Andersson et al. 2020,
"FLIP: A Difference Evaluator for Alternating Images", HPG 2020, Sec. 4.1) for two uniform
grey images, written here from the paper and the colour standards: on a uniform image the
contrast-sensitivity filters (normalized to sum 1) change nothing and the edge and point
detectors (derivatives of a Gaussian) respond with 0, so FLIP is the redistributed colour
difference alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import vobscure as vo
from vobscure.metrics import FLIP_PPD, flip

#: FLIP runs in float32. Its derivative filters, normalized in float32, leave a response of
#: order 1e-7 on a uniform image; the feature term takes its square root (q_f = 1/2),
#: a few 1e-4, and FLIP is the colour error dE_c raised to 1 - that: a relative change of
#: about 4e-4 |ln dE_c|, under 1e-3 for the colour errors used here (dE_c > 0.09, |ln dE_c| <
#: 2.5). Measured: 1.3e-5 to 3.0e-4, with deviation / |ln dE_c| between 1.8e-4 and 4e-4.
UNIFORM_REL = 1e-3
#: Radius (pixels) of FLIP's widest filter at ppd: three standard deviations, rounded up, of
#: the widest contrast-sensitivity Gaussian (scale b = 0.04 deg^2, sigma = sqrt(b / (2 pi^2))
#: deg, the blue-yellow channel's first term) or of the feature detectors (sigma = w / 2 with
#: w = 0.082 deg), as FLIP's reference implementation sizes them (FLIP.h,
#: ``calculateSpatialFilterRadius`` and ``setFeatureFilter``).


def support_radius(ppd: float) -> int:
    spatial = math.ceil(3.0 * math.sqrt(0.04 / (2.0 * math.pi ** 2)) * ppd)
    feature = math.ceil(3.0 * 0.5 * 0.082 * ppd)
    return max(spatial, feature)


# ----------------------------------------------------------------------------- the colour pipeline
def _srgb_to_xyz() -> np.ndarray:
    """Linear sRGB to CIE XYZ from the primaries' and D65's chromaticities (IEC 61966-2-1)."""
    xy = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    white = np.array([0.3127, 0.3290])
    P = np.stack([xy[:, 0] / xy[:, 1], np.ones(3), (1 - xy.sum(1)) / xy[:, 1]])   # primaries with Y = 1
    W = np.array([white[0] / white[1], 1.0, (1 - white.sum()) / white[1]])
    return P * np.linalg.solve(P, W)            # scaled so that RGB (1, 1, 1) is the white


M = _srgb_to_xyz()
WHITE = M.sum(axis=1)


def cielab(rgb) -> np.ndarray:
    """CIELAB of a linear RGB colour, D65 white (CIE 15)."""
    t = M @ np.asarray(rgb, float) / WHITE
    d = 6 / 29
    f = np.where(t > d ** 3, np.cbrt(t), t / (3 * d * d) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def hunt(lab) -> np.ndarray:
    """The Hunt adjustment: chroma scaled by 0.01 L (Sec. 4.1)."""
    return np.array([lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]])


def hyab(a, b) -> float:
    """HyAB: city-block in L, Euclidean in (a, b) (Sec. 4.1)."""
    return abs(a[0] - b[0]) + math.hypot(a[1] - b[1], a[2] - b[2])


def colour_flip(g1: float, g2: float, *, q_c=0.7, p_c=0.4, p_t=0.95) -> float:
    """FLIP's colour error of two uniform linear greys, remapped to [0, 1] (Sec. 4.1)."""
    c_max = hyab(hunt(cielab([0, 1, 0])), hunt(cielab([0, 0, 1]))) ** q_c   # green to blue
    e = hyab(hunt(cielab([g1] * 3)), hunt(cielab([g2] * 3))) ** q_c
    if e < p_c * c_max:
        return e * p_t / (p_c * c_max)
    return p_t + (e - p_c * c_max) / (c_max - p_c * c_max) * (1 - p_t)


# ----------------------------------------------------------------------------- tests
def _scene(shape=(32, 48), seed=0) -> np.ndarray:
    """A smooth visibility-like image with structure at several scales, in [0.1, 0.9]."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:shape[0], 0:shape[1]] / 8.0
    v = 0.5 + 0.2 * np.sin(x + 2 * y) + 0.1 * np.cos(3 * x) + 0.05 * rng.standard_normal(shape)
    return np.clip(v, 0.1, 0.9)


def test_identical_images_score_zero_exactly():
    ref = _scene()
    est = ref.copy()
    est[:5, :7] = np.nan                          # background too
    f = flip(est, ref)
    assert f.mean == 0.0 and np.nanmax(f.map) == 0.0
    assert f.pixels == ref.size - 35 and f.ignored == 35 and f.clipped == 0
    assert f.map.dtype == np.float32 and np.isnan(f.map[:5, :7]).all()


@pytest.mark.parametrize("g1, g2", [(0.5, 0.4), (0.5, 0.6), (0.5, 0.9), (0.1, 0.15), (0.8, 0.85),
                                    (0.05, 1.0), (0.0, 1.0)])
def test_uniform_greys_match_the_colour_pipeline(g1, g2):
    f = flip(np.full((12, 20), g2), np.full((12, 20), g1))
    want = colour_flip(g1, g2)
    assert f.mean == pytest.approx(want, rel=UNIFORM_REL)
    np.testing.assert_allclose(f.map, want, rtol=UNIFORM_REL)      # uniform, borders included


def test_the_colour_pipeline_has_both_branches_of_the_remapping():
    # (0.05, 1.0) and (0.0, 1.0) lie above p_t = 0.95, the others below: both branches tested
    assert colour_flip(0.0, 1.0) > 0.95 > colour_flip(0.5, 0.9)


def test_dark_differences_weigh_more_in_linear_light():
    # equal steps of visibility: lightness L* changes faster in the dark (the linear choice)
    dark = flip(np.full((8, 8), 0.15), np.full((8, 8), 0.1)).mean
    bright = flip(np.full((8, 8), 0.85), np.full((8, 8), 0.8)).mean
    assert dark > 2 * bright


def test_symmetric_and_monotone_in_a_uniform_offset():
    ref = _scene()
    est = np.clip(ref + 0.05 * np.random.default_rng(1).standard_normal(ref.shape), 0, 1)
    np.testing.assert_array_equal(flip(est, ref).map, flip(ref, est).map)
    means = [flip(ref + d, ref).mean for d in (0.0, 0.01, 0.03, 0.06, 0.1)]
    assert means[0] == 0 and np.all(np.diff(means) > 0)


def test_background_scores_like_the_cropped_frame_away_from_the_cut():
    ref = _scene((32, 64))
    est = np.clip(ref + 0.08 * np.random.default_rng(2).standard_normal(ref.shape), 0, 1)
    half_ref, half_est = ref.copy(), est.copy()
    half_ref[:, :32] = np.nan                     # the left half is background in both
    half_est[:, :32] = np.nan
    half = flip(half_est, half_ref)
    crop = flip(est[:, 32:], ref[:, 32:])
    assert half.pixels == crop.pixels == 32 * 32 and half.ignored == 32 * 32
    R = support_radius(FLIP_PPD)
    assert R == 10
    # beyond the filters' reach of the cut the two calls see the same pixels: the same map
    np.testing.assert_array_equal(half.map[:, 32 + R:], crop.map[:, R:])
    # within it the fill changes the context: the means differ by at most the share of those
    # columns (R of 32), each FLIP value being in [0, 1]
    assert abs(half.mean - crop.mean) <= R / 32
    assert half.mean == pytest.approx(float(np.nanmean(half.map)), rel=1e-6)


def test_mask_selects_the_pixels_and_nothing_outside_it_counts():
    ref = _scene()
    est = np.clip(ref + 0.05, 0, 1)
    mask = np.zeros(ref.shape, bool)
    mask[8:20, 10:30] = True
    f = flip(est, ref, mask=mask)
    assert f.pixels == mask.sum() and f.ignored == (~mask).sum()
    assert np.isnan(f.map[~mask]).all() and np.isfinite(f.map[mask]).all()
    assert f.mean == pytest.approx(float(np.mean(f.map[mask], dtype=np.float64)), rel=1e-12)
    other = est.copy()
    other[~mask] = np.random.default_rng(3).random(int((~mask).sum()))    # anything outside
    g = flip(other, ref, mask=mask)
    assert g.mean == f.mean
    np.testing.assert_array_equal(g.map, f.map)


def test_values_outside_the_unit_range_are_clipped_and_counted():
    ref = _scene()
    est = ref.copy()
    est[0, :4] = 1.2
    est[1, :3] = -0.1
    ref2 = ref.copy()
    ref2[2, 0] = 1.5
    f = flip(est, ref2)
    assert f.clipped == 8
    g = flip(np.clip(est, 0, 1), np.clip(ref2, 0, 1))
    assert g.clipped == 0 and f.mean == g.mean


def test_nothing_to_compare():
    f = flip(np.full((4, 4), np.nan), np.zeros((4, 4)))
    assert f.pixels == 0 and f.ignored == 16 and np.isnan(f.mean) and np.isnan(f.map).all()


def test_ppd_widens_the_filters():
    # a fine checkerboard against its mean grey: the farther the viewer, the less it shows
    ref = np.full((32, 32), 0.5)
    est = ref + 0.2 * (np.indices(ref.shape).sum(0) % 2 - 0.5)
    near, far = flip(est, ref, ppd=10.0).mean, flip(est, ref, ppd=120.0).mean
    assert near > far > 0
    assert flip(est, ref).ppd == FLIP_PPD == 67.0


@pytest.mark.parametrize("args, kwargs, match", [
    ((np.zeros((4, 4)), np.zeros((4, 5))), {}, "estimate and reference"),
    ((np.zeros(4), np.zeros(4)), {}, "estimate"),
    ((np.zeros((4, 4)), np.zeros((4, 4))), {"ppd": 0.0}, "ppd"),
    ((np.zeros((4, 4)), np.zeros((4, 4))), {"ppd": -67.0}, "ppd"),
    ((np.zeros((4, 4)), np.zeros((4, 4))), {"ppd": float("inf")}, "ppd"),
    ((np.zeros((4, 4)), np.zeros((4, 4))), {"mask": np.ones((4, 4))}, "mask"),
    ((np.zeros((4, 4)), np.zeros((4, 4))), {"mask": np.ones((4, 5), bool)}, "mask"),
    (("x", np.zeros((4, 4))), {}, "estimate"),
])
def test_bad_arguments_name_them(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        flip(*args, **kwargs)


# ----------------------------------------------------------------------------- error and flicker
def test_error_report_carries_the_mean_flip():
    ref = _scene()
    est = np.clip(ref + 0.05 * np.random.default_rng(4).standard_normal(ref.shape), 0, 1)
    est[:3] = np.nan
    mask = np.ones(ref.shape, bool)
    mask[:, :5] = False
    r = vo.error(est, ref, mask=mask)
    assert r.flip == flip(est, ref, mask=mask).mean and 0 < r.flip < 1
    assert np.isnan(vo.error(est, ref, flip=False).flip)
    assert np.isnan(vo.error(np.array([0.5, 0.6]), np.array([0.5, 0.5])).flip)     # not an image
    assert vo.error(ref, ref).flip == 0.0


def test_flicker_flip_of_a_constant_sequence_is_zero():
    frames = np.repeat(_scene()[None], 4, axis=0)
    f = vo.metrics.flicker(frames, frames)
    assert f.estimate_flip == 0.0 and f.reference_flip == 0.0


def test_flicker_flip_of_alternating_greys_is_the_colour_error():
    grey = np.array([0.5, 0.6, 0.5, 0.6, 0.5])[:, None, None] * np.ones((1, 8, 8))
    still = np.full_like(grey, 0.5)
    f = vo.metrics.flicker(grey, still)
    assert f.estimate_flip == pytest.approx(colour_flip(0.5, 0.6), rel=UNIFORM_REL)
    assert f.reference_flip == 0.0
    assert np.isnan(vo.metrics.flicker(grey, still, flip=False).estimate_flip)
    assert np.isnan(vo.metrics.flicker(grey).reference_flip)


def test_flicker_flip_pools_the_pairs_over_their_own_pixels():
    rng = np.random.default_rng(5)
    frames = np.clip(_scene()[None] + 0.05 * rng.standard_normal((3,) + _scene().shape), 0, 1)
    frames[1, :4] = np.nan                      # rows 0-3 drop out of both pairs
    f = vo.metrics.flicker(frames)
    pair = [flip(frames[t], frames[t - 1]) for t in (1, 2)]
    want = sum(p.mean * p.pixels for p in pair) / sum(p.pixels for p in pair)
    assert f.pairs == sum(p.pixels for p in pair)
    assert f.estimate_flip == pytest.approx(want, rel=1e-12)


def test_flip_switch_must_be_a_bool():
    img = np.full((8, 8), 0.5)
    with pytest.raises(ValueError, match="flip"):
        vo.metrics.error(img, img, flip="no")
    with pytest.raises(ValueError, match="flip"):
        vo.metrics.flicker(np.stack([img, img]), flip="no")
