"""Tests of vobscure.objectspace.spheres: sphere-set AO in SH (Ren et al. 2006), the exact
union visibility of the spheres, and sphere sets of meshes.

Independent references: the cosine-weighted occlusion of one sphere wholly above the horizon,
cos(theta) (r/d)^2 (its form factor; uniform weighting: the cap's solid-angle fraction
1 - cos(alpha)); the band-limited occlusion of one sphere as a Legendre series (Funk-Hecke:
the integral of two zonal functions is sum_l a_l b_l P_l(cos theta), a_l, b_l their
zonal coefficients) with
coefficients from scipy's quad; the occlusion of a sphere partly below the horizon by scipy's
dblquad over its cap.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, special

import vobscure as vo
from vobscure.objectspace import sh
from vobscure.objectspace.spheres import (
    METHODS,
    sphere_set,
    sphere_set_ao,
    sphere_set_gbuffer,
    union_visibility,
)

MESH_DIR = Path(__file__).resolve().parents[2] / "shared/data/meshes"
BUNNY = MESH_DIR / "stanford-bunny.obj"

ORDERS = [3, 4, 5, 6]
#: Two float64 evaluations of the same finite series (quad-accurate coefficients).
SERIES_ATOL = 1e-9
#: Remainder of the Legendre series of one sphere's occlusion after LONG_SERIES bands
#: (terms decay like l^-2.5 for the cosine kernel, like l^-1.5 P_l for the uniform one).
LONG_SERIES = 1500
REMAINDER_ATOL = {"cosine": 2e-6, "uniform": 2e-3}
#: Two-sided z-test threshold: false-failure rate 1e-4 per comparison (normal quantile).
Z_MAX = 3.9
#: shexp of one small blocker against product: the log round trip's defect (the truncated
#: algebra is not associative; measured below 6e-8 at these angular radii).
SMALL_BLOCKER_ATOL = 1e-6
#: float32 inputs against float64 (inputs rounded to float32, ~6e-8 relative).
FLOAT32_ATOL = 1e-5


def _zonal_coefficients(weighting, alpha, L):
    """Cap (half-angle alpha) and kernel zonal coefficients for bands 0..L-1, by quad for the
    first bands and by the Legendre closed form (scipy) beyond, where quad is slow."""
    ls = np.arange(L)
    norm = np.sqrt((2 * ls + 1) / (4 * np.pi))
    x = np.cos(alpha)
    Pm = special.eval_legendre(np.maximum(ls - 1, 0), x)
    Pp = special.eval_legendre(ls + 1, x)
    cap_int = np.where(ls == 0, 1 - x, (Pm - Pp) / (2 * ls + 1))
    for l in range(min(L, 8)):
        cap_int[l] = integrate.quad(lambda mu: special.eval_legendre(l, mu), x, 1.0)[0]
    cap = 2 * np.pi * norm * cap_int
    # I_k = int_0^1 P_k (mu) dmu, closed form from P_k(0)
    ks = np.arange(L + 2)
    I = np.where(ks == 0, 1.0, (special.eval_legendre(np.maximum(ks - 1, 0), 0.0)
                                - special.eval_legendre(ks + 1, 0.0)) / (2 * ks + 1))
    if weighting == "cosine":
        # mu P_l = ((l + 1) P_{l+1} + l P_{l-1}) / (2l + 1); quad for the first bands
        k_int = ((ls + 1) * I[ls + 1] + ls * I[np.maximum(ls - 1, 0)]) / (2 * ls + 1)
        for l in range(min(L, 8)):
            k_int[l] = integrate.quad(lambda m: special.eval_legendre(l, m) * m, 0.0, 1.0)[0]
        kernel = 2 * norm * k_int
    else:
        kernel = 2 * np.pi * norm * I[:L] / (2 * np.pi)
    return cap, kernel


def _series_occlusion(weighting, theta, alpha, L):
    """sum_{l < L} cap_l kernel_l P_l(cos theta): the occlusion band-limited to L bands."""
    cap, kernel = _zonal_coefficients(weighting, alpha, L)
    ls = np.arange(L)
    return float(np.sum(cap * kernel * special.eval_legendre(ls, np.cos(theta))))


def _cap_occlusion_quad(theta, alpha):
    """(1/pi) int_cap max(0, n . w) dw for a cap of half-angle alpha at angle theta from n."""
    def inner(beta):
        f = lambda phi: max(0.0, np.cos(beta) * np.cos(theta) + np.sin(beta) * np.sin(theta) * np.cos(phi))
        return np.sin(beta) * integrate.quad(f, 0, 2 * np.pi, limit=200)[0]
    return integrate.quad(inner, 0, alpha, limit=200)[0] / np.pi


def _one_sphere(theta, alpha, d=2.0):
    """Receiver at the origin with normal +z; a sphere of angular radius alpha at angle theta."""
    axis = np.array([np.sin(theta), 0.0, np.cos(theta)])
    return np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), (d * axis)[None], np.array([d * np.sin(alpha)])


# ----------------------------------------------------------------------------- one sphere
ABOVE = [(0.0, 0.3), (0.4, 0.5), (0.9, 0.2), (0.2, 1.2)]     # theta + alpha <= pi / 2


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("weighting", ["cosine", "uniform"])
def test_one_sphere_above_horizon_meets_closed_form_within_band_limit(order, weighting):
    """The SH result differs from the closed form by exactly the band limit's error."""
    for theta, alpha in ABOVE:
        closed = (np.cos(theta) * np.sin(alpha) ** 2 if weighting == "cosine"   # cos(theta) (r/d)^2
                  else 1.0 - np.cos(alpha))                                   # the cap's solid angle / 2 pi
        full = _series_occlusion(weighting, theta, alpha, LONG_SERIES)
        assert full == pytest.approx(closed, abs=REMAINDER_ATOL[weighting])   # the series is right
        band_limit_error = closed - _series_occlusion(weighting, theta, alpha, order)
        p, n, c, r = _one_sphere(theta, alpha)
        for method in ("product", "sum"):
            v = sphere_set_ao(p, n, c, r, order=order, method=method, weighting=weighting, clip=False)[0]
            assert (1.0 - closed) + band_limit_error == pytest.approx(v, abs=SERIES_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_one_sphere_partly_below_horizon(order):
    """Band-limited: the Legendre series; exact: the union reference against dblquad (z-test)."""
    for theta, alpha in [(1.3, 0.5), (1.7, 0.4), (np.pi / 2, 0.8)]:
        p, n, c, r = _one_sphere(theta, alpha)
        expected = 1.0 - _series_occlusion("cosine", theta, alpha, order)
        for method in ("product", "sum"):
            v = sphere_set_ao(p, n, c, r, order=order, method=method, clip=False)[0]
            assert v == pytest.approx(expected, abs=SERIES_ATOL)


def test_union_reference_partly_below_horizon():
    for k, (theta, alpha) in enumerate([(1.3, 0.5), (1.7, 0.4), (np.pi / 2, 0.8), (0.3, 0.4)]):
        p, n, c, r = _one_sphere(theta, alpha)
        exact = 1.0 - _cap_occlusion_quad(theta, alpha)
        e = union_visibility(p, n, c, r, rays=2048, seed=k)
        assert abs(e.zscore(exact)[0]) < Z_MAX


def test_union_reference_two_disjoint_spheres_uniform():
    """Two spheres whose caps do not overlap: the union's occlusion is the sum of the caps."""
    p, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    c = np.array([[0.0, 0.0, 3.0], [3.0 * np.sin(1.2), 0.0, 3.0 * np.cos(1.2)]])
    r = np.array([1.0, 0.6])
    alphas = np.arcsin(r / 3.0)
    assert alphas.sum() < 1.2                               # disjoint caps
    exact = 1.0 - (1.0 - np.cos(alphas)).sum()               # both wholly above the horizon
    e = union_visibility(p, n, c, r, rays=4096, seed=3, weighting="uniform")
    assert abs(e.zscore(exact)[0]) < Z_MAX


@pytest.mark.parametrize("order", ORDERS)
def test_shexp_one_small_sphere_matches_product(order):
    """Below the eigenvalue floor the log is exact up to the algebra's non-associativity; on
    the table's grid of angular radii there is no interpolation error either."""
    t = sh.log_table(order)
    for i in (20, 60):
        alpha = t.alpha[i]
        p, n, c, r = _one_sphere(0.3, alpha)
        product = sphere_set_ao(p, n, c, r, order=order, method="product", clip=False)
        shexp = sphere_set_ao(p, n, c, r, order=order, method="shexp", exp="exact", clip=False)
        np.testing.assert_allclose(shexp, product, atol=SMALL_BLOCKER_ATOL)


# ----------------------------------------------------------------------------- inside, touching
@pytest.mark.parametrize("method", METHODS)
def test_receiver_inside_a_sphere_sees_nothing(method):
    p = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    c = np.array([[0.1, 0.0, 0.0], [5.0, 5.0, 5.0]])           # the point is inside the first
    r = np.array([0.5, 1.0])
    v = sphere_set_ao(p, n, c, r, method=method)
    assert v.tolist() == [0.0, 0.0]
    e = union_visibility(p, n, c, r, rays=64)
    assert e.value.tolist() == [0.0, 0.0] and e.stderr.tolist() == [0.0, 0.0]
    # the centre itself too (no direction to the sphere)
    assert sphere_set_ao(p[:1], n[:1], p[:1], [0.5], method=method).tolist() == [0.0]


@pytest.mark.parametrize("order", ORDERS)
def test_receiver_touching_a_sphere(order):
    """Tangent from below (the sphere under the surface): exactly visible in the union, the
    band-limited hemisphere cap in SH; tangent from above: exactly hidden, likewise."""
    p, n = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    for sign, exact in ((-1.0, 1.0), (1.0, 0.0)):
        c = np.array([[0.0, 0.0, sign * 0.5]])
        r = np.array([0.5])
        e = union_visibility(p, n, c, r, rays=256)
        assert e.value[0] == exact
        theta = 0.0 if sign > 0 else np.pi
        expected = 1.0 - _series_occlusion("cosine", theta, np.pi / 2, order)
        v = sphere_set_ao(p, n, c, r, order=order, method="product", clip=False)[0]
        assert v == pytest.approx(expected, abs=SERIES_ATOL)


# ----------------------------------------------------------------------------- many spheres
def _cloud(seed=0, k=12, points=40):
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(k, 3))
    c[:, 2] = np.abs(c[:, 2]) + 0.8
    r = rng.uniform(0.2, 0.5, k)
    p = np.column_stack([rng.uniform(-1, 1, points), rng.uniform(-1, 1, points), np.zeros(points)])
    n = np.tile([0.0, 0.0, 1.0], (points, 1))
    return p, n, c, r


#: How far chunking may move a visibility. Chunking changes, per receiver, only how many rows
#: each BLAS product ``f @ G_j`` of the SH algebra gets, and so possibly which BLAS kernel
#: computes the receiver's row: the same dot products of length K = n^2, summed in another
#: order (OpenBLAS picks kernels by shape). Two summation orders of one dot product differ by
#: at most 2 gamma_K sum |a_i b_i|, gamma_K = K u / (1 - K u), u = 2^-53 (Higham, "Accuracy
#: and Stability of Numerical Algorithms", 2nd ed., Sec. 3.1). The hybrid exponential squares
#: its result k times, each squaring at most doubling a relative error (k <= 6 for these
#: clouds: ||f_hat|| below 2^6 times the squaring threshold), so 2^(k+1) products' worth; the
#: sum of |terms| is at most n^2 times the result's scale (coefficients bounded by sqrt(4 pi)
#: times the DC term for these positive visibility functions). Visibilities are in [0, 1]:
#: 2^7 * 2 gamma_16 * 16 = 7.3e-12 absolute. A chunking bug (a receiver paired with another's
#: spheres or normal) moves visibilities by 1e-3 or more.
CHUNK_ATOL = 2.0 ** 7 * 2 * (16 * 2.0 ** -53 / (1 - 16 * 2.0 ** -53)) * 16


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("chunk", [1, 3, 7])
def test_chunking_does_not_change_the_result(method, chunk):
    p, n, c, r = _cloud()
    whole = sphere_set_ao(p, n, c, r, method=method)
    np.testing.assert_allclose(sphere_set_ao(p, n, c, r, method=method, chunk=chunk), whole,
                               rtol=0, atol=CHUNK_ATOL)


@pytest.mark.parametrize("method", METHODS)
def test_float32_inputs(method):
    p, n, c, r = _cloud(points=10)
    args32 = [a.astype(np.float32) for a in (p, n, c, r)]
    v32 = sphere_set_ao(*args32, method=method)
    v64 = sphere_set_ao(*[a.astype(np.float64) for a in args32], method=method)
    assert v32.dtype == np.float64
    np.testing.assert_allclose(v32, v64, atol=FLOAT32_ATOL)


def test_union_is_deterministic_per_seed():
    p, n, c, r = _cloud(points=5)
    a = union_visibility(p, n, c, r, rays=64, seed=7)
    b = union_visibility(p, n, c, r, rays=64, seed=7)
    np.testing.assert_array_equal(a.value, b.value)
    assert a.samples == 64


def test_validation():
    p, n, c, r = _cloud(points=3)
    with pytest.raises(ValueError, match="radii"):
        sphere_set_ao(p, n, c, -r)
    with pytest.raises(ValueError, match="radii"):
        sphere_set_ao(p, n, c, r[:-1])
    with pytest.raises(ValueError, match="method"):
        sphere_set_ao(p, n, c, r, method="volterra")
    with pytest.raises(ValueError, match="exp"):
        sphere_set_ao(p, n, c, r, exp="pade")
    with pytest.raises(ValueError, match="weighting"):
        sphere_set_ao(p, n, c, r, weighting="phong")
    with pytest.raises(ValueError, match="order"):
        sphere_set_ao(p, n, c, r, order=0)
    with pytest.raises(ValueError, match="normals"):
        sphere_set_ao(p, n[:2], c, r)
    with pytest.raises(ValueError, match="points"):
        sphere_set_ao(np.full_like(p, np.nan), n, c, r)
    with pytest.raises(ValueError, match="centers"):
        union_visibility(p, n, c[:, :2], r)
    with pytest.raises(ValueError, match="rays"):
        union_visibility(p, n, c, r, rays=1)
    with pytest.raises(ValueError, match="k"):
        sphere_set(vo.scenes.cornell_box(), 0)
    with pytest.raises(ValueError, match="meshes"):
        sphere_set(vo.scenes.cornell_box(), 2, meshes=["teapot"])


# ----------------------------------------------------------------------------- sphere sets
def _box_inside_distance(x, lo, hi, angle_y):
    """Distance from points inside a box (rotated by angle_y degrees about y about its centre)
    to its surface, in the box's own frame."""
    centre = 0.5 * (np.asarray(lo) + np.asarray(hi))
    a = np.radians(angle_y)
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    local = (x - centre) @ R                               # R^T (x - c), for either sign convention
    half = 0.5 * (np.asarray(hi) - np.asarray(lo))
    return np.min(half - np.abs(local), axis=1), local, half


def test_sphere_set_is_inscribed_in_the_tall_box():
    s = sphere_set(vo.scenes.cornell_box(), 6, meshes=["tall_box"], samples=4000, seed=1)
    assert s.centers.shape == (6, 3) and s.radii.shape == (6,)
    lo, hi = (-0.335 - 0.3, 0.0, -0.29 - 0.3), (-0.335 + 0.3, 1.2, -0.29 + 0.3)
    # the box is turned by +17 degrees; the frame's sign is whichever puts the centres inside
    for angle in (17.0, -17.0):
        dist, local, half = _box_inside_distance(s.centers, lo, hi, angle)
        if np.all(dist > 0):
            break
    assert np.all(dist > 0)
    np.testing.assert_allclose(s.radii, dist, atol=1e-9)   # inscribed: touching the nearest face
    again = sphere_set(vo.scenes.cornell_box(), 6, meshes=["tall_box"], samples=4000, seed=1)
    np.testing.assert_array_equal(again.centers, s.centers)


@pytest.mark.skipif(not BUNNY.exists(), reason=f"shared mesh {BUNNY} not present")
def test_sphere_set_runs_on_the_bunny():
    scene = vo.scenes.load(BUNNY)
    s = sphere_set(scene, 16, seed=0, samples=5000)
    assert len(s.radii) == 16 and np.all(s.radii > 0)
    lo, hi = scene.bounds
    assert np.all((s.centers >= lo) & (s.centers <= hi))
    assert np.all(s.radii < 0.5 * np.min(hi - lo))
    # ground points under the bunny are occluded, and AO decreases toward it
    y0 = lo[1]
    p = np.array([[0.0, y0, 0.0], [0.5, y0, 0.0]])
    v = sphere_set_ao(p, np.tile([0.0, 1.0, 0.0], (2, 1)), s.centers, s.radii)
    assert v[0] < v[1] <= 1.0


def test_sphere_set_gbuffer_on_the_cornell_box():
    scene = vo.scenes.cornell_box()
    gb = vo.render_gbuffer(scene, scene.camera(size=(24, 18)))
    v = sphere_set_gbuffer(gb, scene=scene, k=8)
    assert v.shape == (18, 24)
    assert np.all(np.isnan(v) == ~gb.valid)
    assert np.all((v[gb.valid] >= 0) & (v[gb.valid] <= 1))
