"""The void-and-cluster arrays (vobscure.screenspace.bluenoise) and the "blue" noise schedule.

Independent checks: the stored file against a fresh generation; the exact uniformity of ranks;
the low-frequency power of each frame's spatial pattern against the expectation for white
noise of the same values (derived below) and against a shuffled texture's measured spectrum;
each texel's values over frames against a discrepancy bound derived from the continued
fractions of the increments (below).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from vobscure.screenspace import bluenoise as bn
from vobscure.screenspace import noise

N_CELLS = 64 * 64
# Radial frequencies counted as "low": below 1/8 cycle per pixel, i.e. integer wave vectors k
# with 0 < |k| < 64 / 8 = 8 on the 64 x 64 torus (192 of the 4095 non-zero frequencies).
LOW_K = 8
# Blue: the low-frequency power of a frame's pattern is below 1/4 of white noise's expectation.
BLUE_FRACTION = 0.25
# The shuffled (white) texture's low-frequency power over its expectation: 192 frequencies in
# 96 conjugate pairs, each pair's power ~ exponential, so the ratio has mean 1 and standard
# deviation 1 / sqrt(96) = 0.10; 4 standard deviations (a two-sided tail of 6e-5).
WHITE_Z = 4.0
WHITE_SD = 1.0 / np.sqrt(96.0)


def _low_mask():
    k = np.fft.fftfreq(64) * 64
    r2 = k[:, None] ** 2 + k[None, :] ** 2
    return (r2 > 0) & (r2 < LOW_K ** 2)


def _low_power_over_white(u):
    """The low-frequency power of the (64, 64) values ``u`` over its expectation for a random
    permutation of the same values.

    For a random permutation of N values x_j with mean 0 and variance s2 (sum x_j^2 = N s2),
    E[x_j x_l] = -s2 / (N - 1) for j != l, so at every non-zero frequency
    E |F(k)|^2 = N s2 - s2 / (N - 1) (|sum_j w^j|^2 - N) = N^2 s2 / (N - 1).
    """
    x = u - u.mean()
    s2 = np.mean(x ** 2)
    power = np.abs(np.fft.fft2(x)) ** 2
    mask = _low_mask()
    white = N_CELLS ** 2 * s2 / (N_CELLS - 1)
    return power[mask].sum() / (mask.sum() * white)


# --- the stored arrays -------------------------------------------------------------------

def test_stored_ranks_are_permutations():
    ranks = bn.blue_ranks()
    assert ranks.shape == (64, 64, 2)
    for c in range(2):
        assert np.array_equal(np.sort(ranks[..., c].ravel()), np.arange(N_CELLS))
    assert not np.array_equal(ranks[..., 0], ranks[..., 1])


def test_values_are_exactly_uniform():
    # (rank + 0.5) / 4096 puts exactly 4096 / 16 = 256 values in each of 16 equal bins: the
    # chi-square statistic is 0, not merely small
    for c in range(2):
        u = noise.schedule_uniforms("blue", 0)[..., c]
        counts = np.bincount(np.floor(16 * u).astype(int).ravel(), minlength=16)
        expected = N_CELLS / 16
        chi2 = np.sum((counts - expected) ** 2 / expected)
        assert chi2 == 0.0
        assert u.min() == 0.5 / N_CELLS and u.max() == 1.0 - 0.5 / N_CELLS


def test_stored_file_regenerates():
    ranks = bn.blue_ranks()
    for c, seed in enumerate(bn.BLUE_SEEDS):
        assert np.array_equal(bn.void_and_cluster(64, sigma=1.5, initial_fraction=0.1, seed=seed), ranks[..., c])
    with np.load(bn._DATA) as f:
        prov = json.loads(str(f["provenance"]))
    assert prov["sigma"] == 1.5 and prov["size"] == 64 and prov["initial_fraction"] == 0.1
    assert prov["seeds"] == {"u1": bn.BLUE_SEEDS[0], "u2": bn.BLUE_SEEDS[1]}


# --- the generator -----------------------------------------------------------------------

def test_void_and_cluster_is_a_seeded_permutation():
    a = bn.void_and_cluster(16, seed=3)
    assert np.array_equal(np.sort(a.ravel()), np.arange(256))
    assert np.array_equal(a, bn.void_and_cluster(16, seed=3))
    assert np.array_equal(a, bn.void_and_cluster(16, seed=np.random.default_rng(3)))
    assert not np.array_equal(a, bn.void_and_cluster(16, seed=4))


def test_every_threshold_pattern_is_spread_out():
    # the defining property of a dither array: the cells of rank < k form a homogeneous
    # pattern for every k. At density 1/4 on the 16 x 16 torus no 4 x 4 window (16 cells) is
    # empty; a white pattern of that density leaves a window empty with probability about
    # (3/4)^16 = 1%, 2.6 of the 256 windows (2.2 measured over 200 draws, none in 26% of them)
    a = bn.void_and_cluster(16, seed=0)
    for k in (64, 128):
        pattern = a < k
        windows = sum(np.roll(np.roll(pattern, -i, 0), -j, 1) for i in range(4) for j in range(4))
        assert windows.min() >= 1, k


@pytest.mark.parametrize("kwargs, name", [
    (dict(size=1), "size"), (dict(size=2.5), "size"), (dict(sigma=0.0), "sigma"), (dict(sigma=np.nan), "sigma"),
    (dict(initial_fraction=0.0), "initial_fraction"), (dict(initial_fraction=0.6), "initial_fraction"),
    (dict(seed=-1), "seed"),
])
def test_void_and_cluster_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        bn.void_and_cluster(**{"size": 8, **kwargs})


# --- blue in space -----------------------------------------------------------------------

def test_a_shuffled_texture_has_the_white_expectation():
    u = noise.schedule_uniforms("blue", 0)[..., 0]
    white = np.random.default_rng(0).permutation(u.ravel()).reshape(64, 64)
    assert abs(_low_power_over_white(white) - 1.0) < WHITE_Z * WHITE_SD


@pytest.mark.parametrize("frame", [0, 1, 2, 5, 13, 100])
def test_every_frame_is_blue(frame):
    # frac(B + c) = B + c - [B >= 1 - c]: the array minus one of its own threshold patterns,
    # both blue, so the animated frames stay blue (less so than frame 0)
    u = noise.schedule_uniforms("blue", frame)
    for c in range(2):
        assert _low_power_over_white(u[..., c]) < BLUE_FRACTION, c


# --- low discrepancy in time -------------------------------------------------------------

def _bin_counts(values):
    """(T*T, 16) the count of each texel's values in 16 equal bins; values (frames, T, T)."""
    bins = np.floor(16 * values.reshape(len(values), -1)).astype(int)
    return np.stack([np.count_nonzero(bins == b, axis=0) for b in range(16)], axis=-1)


# Lemma: if p/q is a convergent of alpha (so |alpha - p/q| < 1 / q^2) and gcd(p, q) = 1, the q
# values frac(b + n alpha), n = m .. m + q - 1, lie within n |alpha - p/q| < 1/q of the q
# distinct points frac(b' + j/q), all displaced the same way. A bin of width 1/16 holds
# q/16 of those points to within 1, and the displacement moves at most one across each of its
# ends, one in and one out at most: |count - q/16| < 2 for every texel, bin and start m.
FIBONACCI = (5, 8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987, 1597)   # convergents of 0.618...
PELL = (5, 12, 29, 70, 169, 408, 985)                                    # convergents of sqrt(2) - 1
LEMMA_BOUND = 2


@pytest.mark.parametrize("channel, denominators", [(0, FIBONACCI), (1, PELL)])
def test_each_texel_is_equidistributed_over_frames(channel, denominators):
    frames = np.stack([noise.schedule_uniforms("blue", f)[..., channel] for f in range(max(denominators) + 7)])
    for q in denominators:
        for start in (0, 7):
            dev = np.abs(_bin_counts(frames[start:start + q]) - q / 16)
            assert dev.max() < LEMMA_BOUND, (q, start, dev.max())


def _zeckendorf_terms(n):
    terms, fib = 0, [1, 2]
    while fib[-1] <= n:
        fib.append(fib[-1] + fib[-2])
    for f in reversed(fib):
        if f <= n:
            n -= f
            terms += 1
    return terms


def test_u1_discrepancy_at_every_frame_count():
    # any N is a sum of Z(N) Fibonacci numbers (Zeckendorf); frames 0..N-1 split into blocks of
    # those lengths, each within the lemma's bound: |count - N/16| < 2 Z(N)
    n_max = 700
    frames = np.stack([noise.schedule_uniforms("blue", f)[::4, ::4, 0] for f in range(n_max)])
    bins = np.floor(16 * frames.reshape(n_max, -1)).astype(int)
    cumulative = np.cumsum(bins[..., None] == np.arange(16), axis=0)    # (N, texels, 16)
    for n in range(1, n_max + 1):
        dev = np.abs(cumulative[n - 1] - n / 16).max()
        assert dev < LEMMA_BOUND * _zeckendorf_terms(n), (n, dev)


# --- the schedule ------------------------------------------------------------------------

def test_blue_schedule_definition():
    ranks = bn.blue_ranks()
    b = (ranks + 0.5) / N_CELLS
    for n in (0, 1, 37, 10 ** 6):
        u = noise.schedule_uniforms("blue", n)
        assert u.shape == (64, 64, 2)
        want1 = (b[..., 0] + n * 0.6180339887498949) % 1.0
        want2 = (b[..., 1] + n * 0.41421356237309515) % 1.0
        assert np.array_equal(u[..., 0], want1) and np.array_equal(u[..., 1], want2)
    assert noise.period("blue") is None
    assert "blue" in noise.SCHEDULES
    # noise_size does not apply; the seed is unused but checked
    assert np.array_equal(noise.schedule_uniforms("blue", 3, noise_size=8, seed=9), noise.schedule_uniforms("blue", 3))
    with pytest.raises(ValueError, match="seed"):
        noise.schedule_uniforms("blue", 3, seed=-2)
    assert noise.schedule_texture("blue", 2, dim=2).shape == (64, 64, 2)


# Weyl's criterion: (u1, u2) over frames is equidistributed in the unit square iff every mean
# of exp(2 pi i (h1 u1 + h2 u2)), h != 0, tends to 0. For u = b + n alpha the mean over
# n < N is a geometric series: |mean| <= 1 / (N |sin(pi theta)|), theta = h1 alpha + h2 beta.
# Checked for |h1|, |h2| <= 3 with the documented increments; one increment for both would
# give |mean| = 1 at h = (1, -1).
WEYL_FRAMES = 1000
WEYL_H = 3
ROUNDING = 1e-9     # float64 phases of up to ~4000 turns: ~1e-12 each, summed over 1000 frames


def test_pairs_fill_the_unit_square():
    alpha, beta = (np.sqrt(5.0) - 1.0) / 2.0, np.sqrt(2.0) - 1.0
    u = np.stack([noise.schedule_uniforms("blue", f)[::8, ::8] for f in range(WEYL_FRAMES)])
    worst = 0.0
    for h1 in range(-WEYL_H, WEYL_H + 1):
        for h2 in range(-WEYL_H, WEYL_H + 1):
            if h1 == h2 == 0:
                continue
            mean = np.abs(np.exp(2j * np.pi * (h1 * u[..., 0] + h2 * u[..., 1])).mean(axis=0))
            bound = 1.0 / (WEYL_FRAMES * abs(np.sin(np.pi * (h1 * alpha + h2 * beta))))
            assert mean.max() <= bound + ROUNDING, (h1, h2, mean.max(), bound)
            worst = max(worst, bound)
    assert worst < 0.05      # the bounds say something: every such mean is below 5%
