"""Edge-aware blur and dual-radius combination (vobscure.screenspace.blur).

The blur is deterministic, so it is checked against properties that hold exactly (constant
images, NaN mask, convex combination, scale invariance), against a direct per-pixel loop
written from the weight formula, against the variance reduction that Gaussian weights
predict for i.i.d. noise, and across depth and normal discontinuities.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import vobscure as vo
from vobscure.screenspace.blur import bilateral_blur, combine_radii

from conftest import FALSE_FAILURE

PASSES = ("separable", "full")

#: A constant image stays constant: the result is sum(w c) / sum(w), a few roundings off c.
CONSTANT_ATOL = 1e-12
#: The output is a convex combination of inputs: outside their range only by rounding.
RANGE_ATOL = 1e-12
#: Agreement with the direct per-pixel loop (same formula, different summation order).
REFERENCE_ATOL = 1e-12
#: Scale invariance on exactly scaled depths: the relative depth term sees the same ratios,
#: up to the rounding of k * z (1e-16 relative).
SCALE_TOL = 1e-9
#: Scale invariance end to end through the renderer. Embree works in float32, so the depths of
#: the scene rendered at 1e3 scale agree with the unit scene only to ~1e-6 relative and the
#: smooth-shading normals to ~5e-6 (measured on sphere_on_plane at 96 x 64). The log-weight
#: -t^2/2 - (1 - n.n)/sigma_n^2 then moves by about |t| * 2e-6 / sigma_depth +
#: 1e-5 / sigma_normal^2 ~ 3e-4 for the |t| <= 5 that carry weight, and a weighted mean of
#: values in [0, 1] moves by at most half of that per pass; 1e-3 bounds both passes.
RENDERED_SCALE_TOL = 1e-3
#: The same argument for a float32 G-buffer (depth and normals rounded to 6e-8 relative).
FLOAT32_GBUFFER_TOL = 1e-4
#: float32 visibility: the input and the output are each rounded once to float32 (eps 1.2e-7).
FLOAT32_ATOL = 4 * np.finfo(np.float32).eps
#: Largest change allowed across a discontinuity. The worst cross-edge weight in the tests
#: below is the depth weight seen from the far side of a 50% depth jump (z_q = z_p / 1.5):
#: exp(-((1 - 1/1.5) / 0.05)^2 / 2) = exp(-22.2) = 2.3e-10 (seen from the near side it is
#: exp(-50) = 2e-22; across a 90-degree crease, exp(-1 / 0.2^2) = exp(-25) = 1.4e-11). With
#: the centre weight 1 and at most (2r + 1)^2 = 289 cross-edge taps for r = 8 (the separable
#: passes have 2 (2r + 1) in all), the leak is below 289 * 2.3e-10 = 7e-8; 1e-6 leaves room
#: while staying far below any visible bleed (1e-3).
BLEED_TOL = 1e-6


# ---------------------------------------------------------------------------- helpers


def _gbuffer(depth, normal):
    """A synthetic G-buffer with the given (H, W) depth (inf = background) and (H, W, 3) normals."""
    depth = np.asarray(depth, dtype=float)
    H, W = depth.shape
    valid = np.isfinite(depth)
    normal = np.where(valid[..., None], np.broadcast_to(normal, (H, W, 3)), 0.0)
    cam = vo.Camera.look_at((0.0, 0.0, -5.0), (0.0, 0.0, 0.0), size=(W, H), fov_y=45.0)
    return vo.GBuffer(cam, depth=depth, normal=normal, valid=valid,
                      primitive=np.where(valid, 0, -1), hits={})


def _scaled_depth(gb, k):
    """The G-buffer of the same view with every length (so every depth) multiplied by k."""
    return vo.GBuffer(gb.camera.scaled(k), depth=gb.depth * k, normal=gb.normal, valid=gb.valid,
                      primitive=gb.primitive, hits={})


def _noise(gb, seed=0):
    """Uniform [0, 1] visibility on the covered pixels, NaN on background."""
    rng = np.random.default_rng(seed)
    return np.where(gb.valid, rng.random(gb.shape), np.nan)


@pytest.fixture(scope="module")
def sphere_scene():
    return vo.scenes.sphere_on_plane(subdivisions=3)


@pytest.fixture(scope="module")
def sphere_gb(sphere_scene):
    """sphere_on_plane from its suggested camera: smooth normals, silhouettes, a contact point."""
    return vo.render_gbuffer(sphere_scene, sphere_scene.camera((96, 64)))


def _naive_pass(v, gb, taps, sigma_s, sigma_z, sigma_n):
    """Bilateral pass written pixel by pixel from the formula in the docstring."""
    H, W = v.shape
    out = np.full((H, W), np.nan)
    for i in range(H):
        for j in range(W):
            if not gb.valid[i, j] or np.isnan(v[i, j]):
                continue
            z_p, n_p = gb.depth[i, j], gb.normal[i, j]
            num = den = 0.0
            for di, dj in taps:
                a, b = i + di, j + dj
                if not (0 <= a < H and 0 <= b < W) or not gb.valid[a, b] or np.isnan(v[a, b]):
                    continue
                w = (np.exp(-(di * di + dj * dj) / (2 * sigma_s**2))
                     * np.exp(-0.5 * ((gb.depth[a, b] - z_p) / (sigma_z * z_p)) ** 2)
                     * np.exp(-(1.0 - n_p @ gb.normal[a, b]) / sigma_n**2))
                num += w * v[a, b]
                den += w
            out[i, j] = num / den
    return out


# ---------------------------------------------------------------------------- properties


@pytest.mark.parametrize("passes", PASSES)
@pytest.mark.parametrize("radius_px", [0, 1, 3])
def test_matches_direct_loop(sphere_scene, passes, radius_px):
    gb = vo.render_gbuffer(sphere_scene, sphere_scene.camera((24, 18)))
    v = _noise(gb, seed=1)
    v[5, 5] = v[9, 12] = np.nan  # holes in covered pixels stay holes and get zero weight
    kw = dict(sigma_spatial=1.3, sigma_depth=0.08, sigma_normal=0.3)
    out = bilateral_blur(v, gb, radius_px=radius_px, passes=passes, **kw)
    s = (kw["sigma_spatial"], kw["sigma_depth"], kw["sigma_normal"])
    d = range(-radius_px, radius_px + 1)
    if passes == "full":
        expect = _naive_pass(v, gb, [(a, b) for a in d for b in d], *s)
    else:
        expect = _naive_pass(_naive_pass(v, gb, [(0, b) for b in d], *s), gb, [(a, 0) for a in d], *s)
    np.testing.assert_array_equal(np.isnan(out), np.isnan(expect))
    np.testing.assert_allclose(out, expect, rtol=0, atol=REFERENCE_ATOL)


@pytest.mark.parametrize("passes", PASSES)
def test_constant_image_stays_constant(sphere_gb, passes):
    v = np.where(sphere_gb.valid, 0.37, np.nan)
    out = bilateral_blur(v, sphere_gb, radius_px=5, passes=passes)
    np.testing.assert_allclose(out[sphere_gb.valid], 0.37, rtol=0, atol=CONSTANT_ATOL)
    for c in (0.0, 1.0):  # the ends of the visibility range are kept exactly
        out = bilateral_blur(np.where(sphere_gb.valid, c, np.nan), sphere_gb, passes=passes)
        assert np.all(out[sphere_gb.valid] == c)


@pytest.mark.parametrize("passes", PASSES)
def test_nan_exactly_on_background_and_holes(sphere_gb, passes):
    assert 0 < sphere_gb.valid.sum() < sphere_gb.valid.size
    v = _noise(sphere_gb)
    hole = np.zeros(sphere_gb.shape, dtype=bool)
    ii, jj = np.nonzero(sphere_gb.valid)
    hole[ii[::97], jj[::97]] = True
    v[hole] = np.nan
    v[~sphere_gb.valid] = 0.5  # finite values on background are ignored, and NaN comes out
    out = bilateral_blur(v, sphere_gb, radius_px=4, passes=passes)
    np.testing.assert_array_equal(np.isnan(out), ~sphere_gb.valid | hole)


@pytest.mark.parametrize("passes", PASSES)
def test_output_within_input_range(sphere_gb, passes):
    rng = np.random.default_rng(3)
    v = np.where(sphere_gb.valid, 0.2 + 0.5 * rng.random(sphere_gb.shape) ** 3, np.nan)
    out = bilateral_blur(v, sphere_gb, radius_px=6, passes=passes)
    lo, hi = np.nanmin(v), np.nanmax(v)
    m = sphere_gb.valid
    assert np.all(out[m] >= lo - RANGE_ATOL) and np.all(out[m] <= hi + RANGE_ATOL)
    assert out[m].std() < v[m].std()  # and it does smooth


@pytest.mark.parametrize("passes", PASSES)
def test_variance_reduction_of_iid_noise(passes):
    """On a flat plane facing the camera every range weight is 1, so both modes apply the
    normalized truncated Gaussian a_i at interior pixels. For i.i.d. input of variance s^2 the
    output has variance s^2 sum(a_i^2). The measured ratio of sample variances is tested
    against that with the standard error of a variance estimated from correlated Gaussian
    pixels: var(S^2) = 2 s^4 sum_d c(d)^2 / N, with c the autocorrelation of a (the
    covariance of two output pixels d apart)."""
    H = W = 384
    r = 4
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(W, H), ortho_height=2.0)
    gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    assert gb.valid.all() and np.ptp(gb.depth) == 0 and np.ptp(gb.normal, axis=(0, 1)).max() == 0
    x = np.random.default_rng(7).standard_normal((H, W))
    out = bilateral_blur(x, gb, radius_px=r, passes=passes)

    # expected ratio from the weights (default sigma_spatial = r / 2)
    d = np.arange(-r, r + 1)
    g = np.exp(-(d**2) / (2 * (r / 2) ** 2))
    a1 = g / g.sum()
    a = np.outer(a1, a1)
    expected = float(np.sum(a**2))
    c1 = np.correlate(a1, a1, mode="full")            # 1-D autocorrelation; c = outer(c1, c1)
    interior = out[r:H - r, r:W - r]
    n_out = interior.size
    n_eff = n_out * expected**2 / float(np.sum(c1**2)) ** 2
    measured = interior.var() / x.var()
    # relative standard error of the ratio: the output's variance estimate (n_eff) and the
    # input's (N independent pixels); their positive correlation only makes this conservative
    rel_se = np.sqrt(2.0 / n_eff + 2.0 / x.size)
    z_bound = stats.norm.isf(FALSE_FAILURE / 2)
    assert abs(measured / expected - 1.0) < z_bound * rel_se, (measured, expected, rel_se)
    # tight enough to tell the kernel from its neighbours: sigma_spatial 10% off moves the
    # ratio by about 20% (measured: 6.6 and 9.6 standard errors at this size)
    assert z_bound * rel_se < 0.1


def test_separable_equals_full_on_constant_guide():
    gb = _gbuffer(np.full((40, 50), 2.0), (0.0, 0.0, -1.0))
    v = np.random.default_rng(2).random(gb.shape)
    sep = bilateral_blur(v, gb, radius_px=3, passes="separable")
    full = bilateral_blur(v, gb, radius_px=3, passes="full")
    np.testing.assert_allclose(sep[3:-3, 3:-3], full[3:-3, 3:-3], rtol=0, atol=REFERENCE_ATOL)


# ---------------------------------------------------------------------------- discontinuities


@pytest.mark.parametrize("passes", PASSES)
@pytest.mark.parametrize("radius_px", [4, 8])
def test_no_bleeding_across_depth_jump(passes, radius_px):
    # two fronto-parallel planes side by side: z = 1 (visibility 0) and z = 1.5 (visibility 1)
    H, W = 20, 30
    depth = np.where(np.arange(W) < W // 2, 1.0, 1.5)[None, :].repeat(H, axis=0)
    gb = _gbuffer(depth, (0.0, 0.0, -1.0))
    v = np.where(depth < 1.2, 0.0, 1.0)
    # the analytic leak bound quoted at BLEED_TOL
    worst = np.exp(-0.5 * ((1 - 1 / 1.5) / 0.05) ** 2)
    assert (2 * radius_px + 1) ** 2 * worst < BLEED_TOL
    out = bilateral_blur(v, gb, radius_px=radius_px, passes=passes)
    assert np.max(np.abs(out - v)) < BLEED_TOL
    # control: without the depth term the pixels next to the edge do bleed
    loose = bilateral_blur(v, gb, radius_px=radius_px, passes=passes, sigma_depth=1e3)
    edge = slice(W // 2 - 1, W // 2 + 1)
    assert np.min(np.abs(loose[:, edge] - v[:, edge])) > 0.1


@pytest.mark.parametrize("passes", PASSES)
def test_no_bleeding_across_normal_crease(passes):
    # equal depth, normals 90 degrees apart (both facing the camera)
    H, W = 16, 24
    left = np.arange(W)[None, :].repeat(H, axis=0) < W // 2
    s = np.sqrt(0.5)
    normal = np.where(left[..., None], np.array([-s, 0.0, -s]), np.array([s, 0.0, -s]))
    gb = _gbuffer(np.full((H, W), 3.0), normal)
    v = np.where(left, 1.0, 0.0)
    out = bilateral_blur(v, gb, radius_px=6, passes=passes)
    assert np.max(np.abs(out - v)) < BLEED_TOL
    loose = bilateral_blur(v, gb, radius_px=6, passes=passes, sigma_normal=1e3)
    assert np.min(np.abs(loose[:, W // 2 - 1:W // 2 + 1] - v[:, W // 2 - 1:W // 2 + 1])) > 0.1


@pytest.mark.parametrize("passes", PASSES)
def test_no_bleeding_rendered_sphere_on_plane(sphere_scene, sphere_gb, passes):
    # visibility 0 on the sphere, 1 on the floor: the silhouette is a depth jump, the contact
    # region a normal jump; neither may leak
    sphere = list(sphere_scene.meshes).index("sphere")
    on_sphere = sphere_gb.valid & (sphere_scene.mesh_index[np.maximum(sphere_gb.primitive, 0)] == sphere)
    assert 100 < on_sphere.sum() < sphere_gb.valid.sum() - 100
    v = np.where(sphere_gb.valid, np.where(on_sphere, 0.0, 1.0), np.nan)
    out = bilateral_blur(v, sphere_gb, radius_px=8, passes=passes)
    assert np.nanmax(np.abs(out - v)) < BLEED_TOL


# ---------------------------------------------------------------------------- invariances


@pytest.mark.parametrize("passes", PASSES)
@pytest.mark.parametrize("k", [1e3, 1e-3])
def test_scale_invariance_exact_depths(sphere_gb, passes, k):
    v = _noise(sphere_gb, seed=4)
    a = bilateral_blur(v, sphere_gb, passes=passes)
    b = bilateral_blur(v, _scaled_depth(sphere_gb, k), passes=passes)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    np.testing.assert_allclose(a, b, rtol=0, atol=SCALE_TOL)


@pytest.mark.parametrize("passes", PASSES)
def test_scale_invariance_rendered(sphere_scene, sphere_gb, passes):
    k = 1e3
    big = vo.render_gbuffer(sphere_scene.scaled(k), sphere_scene.camera((96, 64)).scaled(k))
    np.testing.assert_array_equal(big.valid, sphere_gb.valid)
    m = sphere_gb.valid
    np.testing.assert_allclose(big.depth[m], k * sphere_gb.depth[m], rtol=1e-5)  # premise of the tolerance
    v = _noise(sphere_gb, seed=5)
    a = bilateral_blur(v, sphere_gb, passes=passes)
    b = bilateral_blur(v, big, passes=passes)
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
    np.testing.assert_allclose(a, b, rtol=0, atol=RENDERED_SCALE_TOL)


def test_radius_zero_is_identity(sphere_gb):
    v = _noise(sphere_gb)
    out = bilateral_blur(v, sphere_gb, radius_px=0)
    np.testing.assert_array_equal(out, v)
    assert out is not v and not np.shares_memory(out, v)


@pytest.mark.parametrize("passes", PASSES)
def test_one_pixel_image(passes):
    gb = _gbuffer([[2.0]], (0.0, 0.0, -1.0))
    out = bilateral_blur([[0.25]], gb, radius_px=3, passes=passes)
    assert out.shape == (1, 1) and out[0, 0] == 0.25
    gb_bg = _gbuffer([[np.inf]], (0.0, 0.0, -1.0))
    assert np.isnan(bilateral_blur([[np.nan]], gb_bg, passes=passes)).all()


@pytest.mark.parametrize("passes", PASSES)
def test_all_background_gives_all_nan_silently(passes):
    gb = vo.render_gbuffer(vo.scenes.slab(), vo.Camera.look_at((0, 1, 0), (0, 5, 0.1), size=(8, 6)))
    assert not gb.valid.any()
    with np.errstate(divide="raise", invalid="raise", over="raise"):  # warnings are errors already
        out = bilateral_blur(np.full(gb.shape, np.nan), gb, passes=passes)
    assert out.shape == gb.shape and np.isnan(out).all()


@pytest.mark.parametrize("passes", PASSES)
def test_no_floating_point_errors_with_background(sphere_gb, passes):
    with np.errstate(divide="raise", invalid="raise", over="raise"):
        out = bilateral_blur(_noise(sphere_gb), sphere_gb, passes=passes)
    assert np.isfinite(out[sphere_gb.valid]).all()


@pytest.mark.parametrize("passes", PASSES)
def test_float32_visibility(sphere_gb, passes):
    v = _noise(sphere_gb, seed=6)
    out64 = bilateral_blur(v, sphere_gb, passes=passes)
    out32 = bilateral_blur(v.astype(np.float32), sphere_gb, passes=passes)
    assert out64.dtype == np.float64 and out32.dtype == np.float32
    np.testing.assert_allclose(out32, out64, rtol=0, atol=FLOAT32_ATOL)
    # integer input is promoted to float64
    assert bilateral_blur(sphere_gb.valid.astype(int), sphere_gb).dtype == np.float64


def test_float32_gbuffer(sphere_gb):
    v = _noise(sphere_gb, seed=8)
    out = bilateral_blur(v, sphere_gb.astype(np.float32))
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, bilateral_blur(v, sphere_gb), rtol=0, atol=FLOAT32_GBUFFER_TOL)


# ---------------------------------------------------------------------------- validation


@pytest.mark.parametrize("kwargs, match", [
    (dict(radius_px=-1), "radius_px"),
    (dict(radius_px=2.5), "radius_px"),
    (dict(radius_px=True), "radius_px"),
    (dict(sigma_spatial=0.0), "sigma_spatial"),
    (dict(sigma_spatial=np.inf), "sigma_spatial"),
    (dict(sigma_depth=-0.1), "sigma_depth"),
    (dict(sigma_depth=np.nan), "sigma_depth"),
    (dict(sigma_normal=0.0), "sigma_normal"),
    (dict(sigma_normal=np.inf), "sigma_normal"),
    (dict(passes="fast"), "passes.*'separable', 'full'"),
])
def test_bad_arguments(sphere_gb, kwargs, match):
    with pytest.raises(ValueError, match=match):
        bilateral_blur(_noise(sphere_gb), sphere_gb, **kwargs)


def test_bad_visibility_and_gbuffer(sphere_gb):
    v = _noise(sphere_gb)
    with pytest.raises(ValueError, match="visibility.*shape"):
        bilateral_blur(v[:, :-1], sphere_gb)
    with pytest.raises(ValueError, match="visibility.*shape"):
        bilateral_blur(v[None], sphere_gb)
    bad = v.copy()
    bad[sphere_gb.valid.nonzero()[0][0], sphere_gb.valid.nonzero()[1][0]] = np.inf
    with pytest.raises(ValueError, match="visibility.*inf"):
        bilateral_blur(bad, sphere_gb)
    with pytest.raises(ValueError, match="visibility"):
        bilateral_blur(np.full(sphere_gb.shape, "a"), sphere_gb)
    with pytest.raises(ValueError, match="gbuffer"):
        bilateral_blur(v, sphere_gb.depth)


# ---------------------------------------------------------------------------- combine_radii


def test_combine_radii_by_hand():
    small = np.array([[1.0, 0.5, 0.0], [0.25, np.nan, 0.9]])
    large = np.array([[0.5, 0.5, 0.7], [1.0, 0.3, np.nan]])
    np.testing.assert_array_equal(combine_radii(small, large),
                                  [[0.5, 0.25, 0.0], [0.25, np.nan, np.nan]])
    np.testing.assert_array_equal(combine_radii(small, large, mode="min"),
                                  [[0.5, 0.5, 0.0], [0.25, np.nan, np.nan]])


@pytest.mark.parametrize("mode", ["product", "min"])
def test_combine_radii_properties(mode):
    rng = np.random.default_rng(9)
    a, b = rng.random((2, 50, 40))
    a[0, :5] = np.nan
    b[1, 3:9] = np.nan
    out = combine_radii(a, b, mode=mode)
    assert out.shape == a.shape and out.dtype == np.float64
    np.testing.assert_array_equal(np.isnan(out), np.isnan(a) | np.isnan(b))
    ok = ~np.isnan(out)
    assert np.all((out[ok] >= 0) & (out[ok] <= np.minimum(a, b)[ok]))
    np.testing.assert_array_equal(out, combine_radii(b, a, mode=mode))  # symmetric
    assert combine_radii(a.astype(np.float32), b.astype(np.float32), mode=mode).dtype == np.float32
    assert combine_radii(a.astype(np.float32), b, mode=mode).dtype == np.float64


def test_combine_radii_errors():
    with pytest.raises(ValueError, match=r"a and b.*\(2, 3\).*\(3, 2\)"):
        combine_radii(np.zeros((2, 3)), np.zeros((3, 2)))
    with pytest.raises(ValueError, match="mode.*'product', 'min'"):
        combine_radii(np.zeros(2), np.zeros(2), mode="max")
    with pytest.raises(ValueError, match="b must be a real numeric array"):
        combine_radii(np.zeros(2), ["x", "y"])
