"""Screen-space VO by point sampling (Loos & Sloan 2010; vobscure.screenspace.point) and the
converged reference vo_reference: planes, the closed forms of the orthographic crease, the
reference's reported standard error, seeds and sample counts. Properties shared with line
sampling: test_line.py."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import vobscure as vo

from analytic import SLAB_VO, SLAB_VO_CLAMPED, crease_vo, crease_vo_clamped
from conftest import CREASE_RADIUS as R_CREASE
from conftest import FALSE_FAILURE, interior

#: Flat surfaces: the depth buffer holds Embree's float32 hits, so planes are exact to ~1e-5.
PLANE_TOL = 1e-3

VIEWS = {
    "persp-oblique": dict(eye=(1, 2, 1.5), fov_y=40.0),
    "ortho-oblique": dict(eye=(1, 2, 1.5), ortho_height=2.0),
}


@pytest.mark.parametrize("view", ["persp-oblique", "ortho-oblique"])
def test_point_exact_on_planes_with_symmetric_patterns(big_slab, view):
    kw = dict(VIEWS[view])
    cam = vo.Camera.look_at(kw.pop("eye"), (0, 0, 0), size=(64, 48), **kw)
    gb = vo.render_gbuffer(big_slab, cam)
    inside = interior(gb, 0.3)
    for n in (12, 13, 33):
        assert vo.patterns.ball(n).has_center == (n % 2 == 1)
        v = vo.vo_point(gb, radius=0.3, samples=n)
        vc = vo.vo_point(gb, radius=0.3, samples=n, normal_clamp=True)
        # antipodal pairs: one of each pair lies below the plane (bilinear 1/z reconstructs
        # it); the centre of odd n lies on it and counts half (open when clamped): before
        # that rule a plane read 0.5 + w_centre / 2 (0.530 with 13 samples)
        assert np.max(np.abs(v[inside] - SLAB_VO)) < PLANE_TOL, n
        assert np.max(np.abs(vc[inside] - SLAB_VO_CLAMPED)) < PLANE_TOL, n


def _noise_pairs(gb, floor, **kw):
    r1 = vo.vo_reference(gb, radius=R_CREASE, samples=2048, seed=11, **kw).value
    r2 = vo.vo_reference(gb, radius=R_CREASE, samples=2048, seed=12, **kw).value
    return r1, r2


#: Sub-cells per pixel side of the midpoint rule that integrates the bilinear depth's cut
#: corner (:func:`_cut_corner_volume`): the cut's depth is piecewise smooth on the pixel
#: scale, so 8 x 8 midpoints per pixel leave an error far below the z-test's resolution
#: (4 x 4 moves the predicted mean offset by 2 %, a sixth of the test's resolution).
CUT_CORNER_SUBCELLS = 8


def _cut_corner_volume(gb, pixels, radius, sub=CUT_CORNER_SUBCELLS):
    """(k,) volume inside each of the ``pixels``' balls of the crease's cut corner: the space
    between the true surface and the bilinear interpolation of the depth buffer's pixel
    centres, which the reference's bilinear fetch takes for the surface.

    Independent of the estimators: the true depth of the orthographic view is the nearer of
    the floor's and the wall's planes (depth affine in the pixel position, fitted to their
    pixels), the bilinear depth is scipy's ``map_coordinates`` of the centres; near the
    concave edge the interpolation lies in front of the surface, and each ball's part of that
    sliver is integrated by the midpoint rule on ``sub`` x ``sub`` cells per pixel (each cell's
    column between the two depths, clipped to the ball's chord).
    """
    from scipy import ndimage

    H, W = gb.shape
    depth = gb.depth.astype(np.float64)
    wp = gb.world_position
    i, j = np.mgrid[0:H, 0:W]
    planes = []
    for on in (gb.valid & (np.abs(wp[..., 1]) < 1e-9), gb.valid & (np.abs(wp[..., 0]) < 1e-9)):
        A = np.column_stack([j[on] + 0.5, i[on] + 0.5, np.ones(on.sum())])
        planes.append(np.linalg.lstsq(A, depth[on], rcond=None)[0])

    def true_depth(x, y):
        return np.minimum(*(c[0] * x + c[1] * y + c[2] for c in planes))
    # every pixel sees the floor or the wall, the nearer one (the edge is concave)
    assert np.allclose(true_depth(j + 0.5, i + 0.5)[gb.valid], depth[gb.valid], rtol=1e-5, atol=0.0)
    X, Y = np.meshgrid((np.arange(W * sub) + 0.5) / sub, (np.arange(H * sub) + 0.5) / sub)
    between = (X >= 0.5) & (X <= W - 0.5) & (Y >= 0.5) & (Y <= H - 0.5)   # between pixel centres
    X, Y = X[between], Y[between]
    front = ndimage.map_coordinates(depth, [Y - 0.5, X - 0.5], order=1)
    back = true_depth(X, Y)
    cut = back > front
    X, Y, front, back = X[cut], Y[cut], front[cut], back[cut]
    unit = gb.camera.ortho_height / H                      # world units per pixel
    rows, cols = np.nonzero(pixels)
    out = np.empty(len(rows))
    for k, (a, b) in enumerate(zip(rows, cols)):
        h = np.sqrt(np.maximum(radius ** 2 - ((X - b - 0.5) ** 2 + (Y - a - 0.5) ** 2) * unit ** 2, 0.0))
        z = depth[a, b]
        out[k] = np.clip(np.minimum(back, z + h) - np.maximum(front, z - h), 0.0, None).sum()
    return out * (unit / sub) ** 2


def test_reference_is_unbiased_on_the_crease(crease_view):
    """vo_reference is Monte Carlo: its mean error over the floor pixels is tested against
    the spread of two independent references (a z-test), not against a fixed tolerance.

    The reference integrates the depth buffer's occupancy, and its bilinear fetch cuts the
    crease's concave corner (between the last floor and the first wall pixel centres the
    interpolated surface lies in front of the true one): that sliver counts as occupied. Its
    volume inside each ball (:func:`_cut_corner_volume`, about 2.7e-4 R^3: a mean offset of
    -6.4e-5 unclamped, twice that in the half-ball, which holds all of it) is the screen-space
    model's, not a sampling error, so the expectation tested is the closed form minus it.
    Against the closed form alone the 2048-ray lattice reference is precise enough to see it
    (z near -6.4 unclamped); against the corrected form z is ordinary.
    """
    gb, floor, c = crease_view
    cut = _cut_corner_volume(gb, floor, R_CREASE)
    ball = 4.0 * np.pi / 3.0 * R_CREASE ** 3
    for kw, exact in ((dict(), crease_vo(c) - cut / ball),
                      (dict(normal_clamp=True), crease_vo_clamped(c) - cut / (ball / 2))):
        r1, r2 = _noise_pairs(gb, floor, **kw)
        sd = np.std((r1 - r2)[floor]) / np.sqrt(2)          # per-pixel noise of one reference
        n_eff = min(floor.sum(), 64 * 64)                    # the noise texture tiles every 64 px
        z = np.mean(r1[floor] - exact) / (sd / np.sqrt(n_eff))
        assert abs(z) < stats.norm.ppf(1 - FALSE_FAILURE / 2), (kw, z)


# ----------------------------------------------------------------------------- vo_reference
#: Probability that one of the reference's statistical tests below fails although the code is
#: right (each test splits it over its assertions, Bonferroni).
REFERENCE_FALSE_FAILURE = FALSE_FAILURE


def _reference_floor(crease_view, c_max=0.8):
    """Floor pixels of the orthographic crease with c < c_max (beyond, a group can miss the
    wall's small cap entirely: docs/groundtruth.md, "When the standard error degenerates")."""
    gb, floor, c = crease_view
    keep = np.zeros_like(floor)
    keep[floor] = c < c_max
    return gb, keep, c[c < c_max]


@pytest.mark.parametrize("normal_clamp", [False, True])
def test_reference_stderr_is_honest_against_closed_forms(crease_view, normal_clamp):
    """Every floor pixel's t-score against the closed-form ball / half-ball VO, with the
    reported stderr (groups - 1 degrees of freedom), Bonferroni over the pixels."""
    from conftest import t_threshold
    from vobscure.estimate import DEFAULT_GROUPS

    gb, floor, c = _reference_floor(crease_view)
    e = vo.vo_reference(gb, radius=R_CREASE, samples=1024, normal_clamp=normal_clamp, seed=21)
    assert isinstance(e, vo.Estimate) and e.value.shape == e.stderr.shape == gb.shape
    assert e.samples == 1024
    assert np.isnan(e.value[~gb.valid]).all() and np.isnan(e.stderr[~gb.valid]).all()
    exact = crease_vo_clamped(c) if normal_clamp else crease_vo(c)
    z = (e.value[floor] - exact) / e.stderr[floor]
    assert np.all(e.stderr[floor] > 0)
    limit = t_threshold(DEFAULT_GROUPS - 1, tests=2 * z.size, false_failure=REFERENCE_FALSE_FAILURE)
    assert np.max(np.abs(z)) < limit, (np.abs(z).max(), limit)


def test_reference_stderr_matches_the_spread_over_seeds(crease_view):
    """The reported stderr is the standard deviation of the value over seeds: at each of a
    few pixels, the variance of the values over independent seeds against the mean reported
    variance is F-distributed (seeds - 1 and seeds (groups - 1) degrees of freedom)."""
    from vobscure.estimate import DEFAULT_GROUPS

    gb, floor, c = _reference_floor(crease_view)
    rows, cols = np.nonzero(floor)
    pick = np.linspace(0, len(rows) - 1, 8).astype(int)        # spread over the floor
    seeds = 12
    runs = [vo.vo_reference(gb, radius=R_CREASE, samples=256, seed=100 + s) for s in range(seeds)]
    values = np.array([r.value[rows[pick], cols[pick]] for r in runs])     # (seeds, pixels)
    reported = np.array([r.stderr[rows[pick], cols[pick]] for r in runs]) ** 2
    ratio = values.var(axis=0, ddof=1) / reported.mean(axis=0)
    alpha = REFERENCE_FALSE_FAILURE / (2 * len(pick))
    lo, hi = stats.f.ppf([alpha, 1 - alpha], seeds - 1, seeds * (DEFAULT_GROUPS - 1))
    assert np.all((ratio > lo) & (ratio < hi)), (ratio, lo, hi)


def test_reference_is_deterministic_by_seed(crease_view):
    gb, _, _ = crease_view
    a = vo.vo_reference(gb, radius=0.5, samples=128, seed=4)
    b = vo.vo_reference(gb, radius=0.5, samples=128, seed=4)
    c = vo.vo_reference(gb, radius=0.5, samples=128, seed=5)
    for x, y in ((a.value, b.value), (a.stderr, b.stderr)):
        assert x.tobytes() == y.tobytes()
    assert a.samples == b.samples
    assert not np.array_equal(a.value, c.value, equal_nan=True)
    # a Generator is consumed, not copied: two calls from one Generator differ
    rng = np.random.default_rng(4)
    assert not np.array_equal(vo.vo_reference(gb, radius=0.5, samples=128, seed=rng).value,
                              vo.vo_reference(gb, radius=0.5, samples=128, seed=rng).value, equal_nan=True)


def test_reference_sample_counts_and_groups(crease_view):
    gb, _, _ = crease_view
    small = gb.astype(np.float32)
    e = vo.vo_reference(small, radius=0.5, samples=100, groups=4, seed=0)
    assert e.samples == 104                       # rounded up to a multiple of 2 * groups
    assert e.value.dtype == np.float32 and e.stderr.dtype == np.float32
    assert vo.vo_reference(gb, radius=0.5, samples=2, seed=0).samples == 2 * 8
    for bad in (dict(groups=1), dict(groups=2.5), dict(samples=1), dict(samples=vo.patterns.disk(5))):
        with pytest.raises(ValueError, match="groups" if "groups" in bad else "samples"):
            vo.vo_reference(gb, radius=0.5, **{"samples": 64, **bad})


def test_reference_accepts_a_sample_pattern(crease_view, big_slab):
    """A ball pattern: each group is the pattern under its own random per-pixel reflection."""
    gb, floor, c = crease_view
    pattern = vo.patterns.ball(33)
    e = vo.vo_reference(gb, radius=R_CREASE, samples=pattern, seed=2)
    assert e.samples == 8 * 33
    assert np.isnan(e.value[~gb.valid]).all() and np.isfinite(e.value[gb.valid]).all()
    assert np.all(e.stderr[floor] > 0)
    again = vo.vo_reference(gb, radius=R_CREASE, samples=pattern, seed=2)
    assert e.value.tobytes() == again.value.tobytes()
    # the mean of vo_point's randomizations: close to the converged value on the crease
    dense = vo.vo_reference(gb, radius=R_CREASE, samples=2048, seed=3)
    assert abs(np.mean(e.value[floor] - dense.value[floor])) < 0.02
    # a point-symmetric pattern is exact on a plane under any reflection: stderr 0 there
    cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(32, 24), ortho_height=2.0)
    plane = vo.render_gbuffer(big_slab, cam)
    inside = interior(plane, 0.3)
    p = vo.vo_reference(plane, radius=0.3, samples=vo.patterns.ball(12), normal_clamp=True, seed=0)
    assert np.max(np.abs(p.value[inside] - SLAB_VO_CLAMPED)) < PLANE_TOL



def test_estimators_converge_to_reference(crease_view):
    gb, floor, _ = crease_view
    r1, r2 = _noise_pairs(gb, floor)
    noise_var = np.mean(((r1 - r2)[floor]) ** 2) / 2
    n_eff = min(floor.sum(), 64 * 64)
    # line with many samples: its squared difference to the reference is the reference's
    # own noise (F test of the two variance estimates). The test can only pass when the
    # line's quadrature error is well below that noise (about 3e-4 per pixel at 2048 lattice
    # rays): squared, under (F quantile - 1) ~ 0.2 of its variance. Against the closed form
    # minus the cut corner (test_reference_is_unbiased_on_the_crease), the tabulated Lloyd
    # pattern of 257 chords errs by -3.1e-4 on average over these pixels (RMS 4.0e-4): a
    # fixed pattern's error, not noise, and above the allowance; the 1025-chord pattern errs
    # by 1e-6 on average (RMS 3e-5). The bilinear fetch is the reference's depth model (vo_line's default,
    # "nearest", reads a staircase with its own expectation).
    line = vo.vo_line(gb, radius=R_CREASE, samples=1025, randomize=False, fetch="bilinear")
    ratio = np.mean((line - r1)[floor] ** 2) / noise_var
    assert ratio < stats.f.ppf(1 - FALSE_FAILURE, n_eff, n_eff)
    # every estimator gets closer as samples grow
    for fn, counts in ((vo.vo_line, (5, 33)), (vo.vo_point, (12, 129))):
        err = [np.sqrt(np.mean((fn(gb, radius=R_CREASE, samples=n)[floor] - r1[floor]) ** 2)) for n in counts]
        assert err[1] < err[0], (fn.__name__, err)

