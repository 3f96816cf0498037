"""Accumulated frames converge as Monte Carlo says (statistical tests, vobscure.temporal).

A static camera, independent noise per frame and the running mean: the accumulated image is
the mean of n independent frames. With an estimator whose expectation *is* the converged
screen-space VO (the reference itself at a handful of segments per frame, a fresh seed per
frame), the squared error against a converged reference S (reported standard errors s_p) has
expectation sigma^2 / n + mean(s_p^2): its excess over mean(s_p^2) falls as 1 / n, so the
RMSE as 1 / sqrt(n). And against a world-space truth T the squared error has expectation
sigma^2 / n + mean((mu - T)^2): it tends to the screen-space model error, not to 0.
"""

import numpy as np
import pytest
from scipy import stats

import vobscure as vo
from vobscure.temporal import Accumulator

#: False-failure rate of every test here (two-sided).
ALPHA = 1e-3
#: Frames at which the error is read.
FRAMES = (1, 2, 4, 8, 16, 32)
#: Independent replicate sequences (different seeds): the spread of their slopes is the
#: slope's standard error.
REPLICATES = 8
#: Segments per frame of the per-frame estimator, and of the converged reference.
FRAME_SEGMENTS, REFERENCE_SEGMENTS = 8, 4096
RADIUS = 0.35


@pytest.fixture(scope="module")
def runs():
    sc = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(sc, sc.camera(size=(24, 24)))
    S = vo.vo_reference(gb, radius=RADIUS, samples=REFERENCE_SEGMENTS, seed=777)
    T = vo.ground_truth(sc, gb, quantity="volumetric", radius=RADIUS, samples=1024, seed=5)
    errors_s, errors_t = [], []
    for rep in range(REPLICATES):
        acc = Accumulator("mean")
        es, et = [], []
        for n in range(1, FRAMES[-1] + 1):
            x = vo.vo_reference(gb, radius=RADIUS, samples=FRAME_SEGMENTS, seed=10_000 * (rep + 1) + n).value
            out = acc.update(x, gb)
            if n in FRAMES:
                es.append(np.nanmean((out - S.value) ** 2))
                et.append(np.nanmean((out - T.value) ** 2))
        errors_s.append(es)
        errors_t.append(et)
    return gb, S, T, np.array(errors_s), np.array(errors_t)


def test_sampling_error_falls_as_one_over_sqrt_n(runs):
    _, S, _, mse, _ = runs
    c = np.nanmean(S.stderr ** 2)            # the reference's own variance, from its stderr
    excess = mse - c
    assert np.all(excess > 0), "the reference's noise must be small against the frames' at 32 frames"
    # slope of log(MSE excess) against log n: -1 when the RMSE falls as n^(-1/2)
    slopes = np.array([np.polyfit(np.log(FRAMES), np.log(e), 1)[0] for e in excess])
    se = slopes.std(ddof=1) / np.sqrt(REPLICATES)
    t = (slopes.mean() + 1.0) / se
    assert abs(t) < stats.t.ppf(1 - ALPHA / 2, REPLICATES - 1), (slopes.mean(), se)
    # the test has power: a slope of -1/2 (an RMSE falling as n^(-1/4)) would be many se away
    assert se < 0.05


def test_error_against_the_truth_tends_to_the_model_error(runs):
    gb, S, T, _, mse_t = runs
    c = np.nanmean(S.stderr ** 2)
    use = np.isfinite(S.value) & np.isfinite(T.value)
    P = use.sum()
    model = np.mean((S.value[use] - T.value[use]) ** 2) - c     # mean (mu - T)^2, corrected for S's noise
    # E[MSE(n)] = a + b / n with a the squared model error: fit per replicate
    X = np.column_stack([np.ones(len(FRAMES)), 1.0 / np.array(FRAMES)])
    a = np.array([np.linalg.lstsq(X, m, rcond=None)[0][0] for m in mse_t])
    se_rep = a.std(ddof=1) / np.sqrt(REPLICATES)
    # S's noise also moves the corrected model error: var of mean 2 (S - mu)(mu - T) over pixels
    se_model = np.sqrt(4 * np.sum(S.stderr[use] ** 2 * (S.value[use] - T.value[use]) ** 2)) / P
    z = (a.mean() - model) / np.hypot(se_rep, se_model)
    assert abs(z) < stats.norm.ppf(1 - ALPHA / 2), (a.mean(), model, se_rep, se_model)
    # the floor is the model error, far from zero: the test tells the two apart
    assert model > 20 * np.hypot(se_rep, se_model)
