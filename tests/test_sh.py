"""Tests of vobscure.objectspace.sh: the real SH basis, zonal caps and rotation, the SH
product, log and exponentials (Ren et al. 2006).

Independent references: scipy's complex spherical harmonics (``sph_harm_y``, with the
Condon-Shortley phase), scipy quadrature of Legendre polynomials, and direct projections of
functions by a fine product quadrature.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, special

from vobscure.objectspace import sh

ORDERS = [3, 4, 5, 6]
#: Agreement of two exact computations in float64 (quadratures exact for the polynomials).
EXACT_ATOL = 1e-10
#: Agreement with scipy.integrate.quad of a smooth integrand.
QUAD_ATOL = 1e-9
#: exp*(log*(g)) against g for smooth g. Not exact: the truncated product is not associative,
#: so the product matrix of log*(g) = log(M_g) 1 is not log(M_g), and the defect is of the
#: size of the bands the truncation drops (measured 6e-8 to 2e-6 on these inputs).
ROUND_TRIP_ATOL = 1e-5
#: float32 directions against float64 (one rounding of the input to float32).
FLOAT32_ATOL = 1e-6


def _random_directions(n, seed=0):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _scipy_real_sh(order, d):
    """Real SH without the Condon-Shortley phase, from scipy's complex Y_l^m (which has it)."""
    theta = np.arccos(np.clip(d[:, 2], -1, 1))
    phi = np.arctan2(d[:, 1], d[:, 0])
    out = np.empty((len(d), order * order))
    for l in range(order):
        for m in range(-l, l + 1):
            Y = special.sph_harm_y(l, abs(m), theta, phi)
            cs = (-1.0) ** abs(m)
            if m > 0:
                out[:, l * (l + 1) + m] = np.sqrt(2) * cs * Y.real
            elif m < 0:
                out[:, l * (l + 1) + m] = np.sqrt(2) * cs * Y.imag
            else:
                out[:, l * (l + 1)] = Y.real
    return out


@pytest.mark.parametrize("order", ORDERS)
def test_basis_matches_scipy(order):
    d = _random_directions(200)
    np.testing.assert_allclose(sh.sh_basis(d, order), _scipy_real_sh(order, d), atol=EXACT_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_basis_orthonormal(order):
    d, w = sh._quadrature(order + 4, 2 * order + 8)
    y = sh.sh_basis(d, order)
    np.testing.assert_allclose((y * w[:, None]).T @ y, np.eye(order * order), atol=EXACT_ATOL)


@pytest.mark.parametrize("alpha", [0.0, 0.2, 1.0, np.pi / 2, 2.5, np.pi])
def test_cap_zonal_against_quadrature(alpha):
    order = 6
    expected = [2 * np.pi * np.sqrt((2 * l + 1) / (4 * np.pi))
                * integrate.quad(lambda mu: special.eval_legendre(l, mu), np.cos(alpha), 1.0)[0]
                for l in range(order)]
    np.testing.assert_allclose(sh.cap_zonal(alpha, order), expected, atol=QUAD_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_kernels_against_quadrature(order):
    cosine = [2 * np.sqrt((2 * l + 1) / (4 * np.pi))
              * integrate.quad(lambda mu: special.eval_legendre(l, mu) * mu, 0.0, 1.0)[0] for l in range(order)]
    np.testing.assert_allclose(sh.clamped_cosine_zonal(order), cosine, atol=QUAD_ATOL)
    # both kernels integrate to 1 over the sphere: a constant visibility 1 gives AO 1
    assert sh.clamped_cosine_zonal(order)[0] * np.sqrt(4 * np.pi) == pytest.approx(1.0, abs=EXACT_ATOL)
    assert sh.hemisphere_zonal(order)[0] * np.sqrt(4 * np.pi) == pytest.approx(1.0, abs=EXACT_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_rotate_zonal_against_projection(order):
    # a smooth zonal function exp(k mu) about axis a, projected directly after rotation
    k = 1.3
    axis = _random_directions(1, seed=3)[0]
    zonal = [2 * np.pi * np.sqrt((2 * l + 1) / (4 * np.pi))
             * integrate.quad(lambda mu: special.eval_legendre(l, mu) * np.exp(k * mu), -1, 1)[0]
             for l in range(order)]
    direct = sh.sh_project(lambda d: np.exp(k * d @ axis), order, resolution=48)
    np.testing.assert_allclose(sh.rotate_zonal(zonal, axis), direct, atol=QUAD_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_product_against_quadrature(order):
    rng = np.random.default_rng(order)
    f, g = rng.normal(size=(2, order * order))
    # the product of two band-limited functions is a polynomial of degree 2 (n - 1):
    # projected exactly by a quadrature of resolution >= 2 n
    direct = sh.sh_project(lambda d: (sh.sh_basis(d, order) @ f) * (sh.sh_basis(d, order) @ g), order,
                           resolution=2 * order + 2)
    np.testing.assert_allclose(sh.sh_product(f, g), direct, atol=EXACT_ATOL)
    # commutative, and the constant 1 is its unit
    np.testing.assert_allclose(sh.sh_product(g, f), sh.sh_product(f, g), atol=EXACT_ATOL)
    one = np.zeros(order * order)
    one[0] = np.sqrt(4 * np.pi)
    np.testing.assert_allclose(sh.sh_product(one, g), g, atol=EXACT_ATOL)
    # batched against one at a time, and M_f g
    F, Gv = rng.normal(size=(2, 5, order * order))
    batched = sh.sh_product(F, Gv)
    np.testing.assert_allclose(batched[2], sh.sh_product(F[2], Gv[2]), atol=EXACT_ATOL)
    np.testing.assert_allclose(sh.product_matrix(F[2]) @ Gv[2], batched[2], atol=EXACT_ATOL)


def _smooth_positive(order, seed):
    """A visibility-like vector: constant 0.7 plus small random higher bands."""
    g = 0.05 * np.random.default_rng(seed).normal(size=order * order)
    g[0] = 0.7 * np.sqrt(4 * np.pi)
    return g


@pytest.mark.parametrize("order", ORDERS)
def test_exp_log_round_trips(order):
    for seed in range(3):
        g = _smooth_positive(order, seed)
        lam = np.linalg.eigvalsh(sh.product_matrix(g))
        assert lam[0] > sh.LOG_EPSILON * lam[-1]          # no eigenvalue clamped: exact inverse
        f = sh.sh_log(g)
        np.testing.assert_allclose(sh.sh_exp(f, method="exact"), g, atol=ROUND_TRIP_ATOL)
        np.testing.assert_allclose(sh.sh_log(sh.sh_exp(f, method="exact")), f, atol=ROUND_TRIP_ATOL)
        # Taylor in the SH algebra converges to the matrix exponential (an identity)
        np.testing.assert_allclose(sh.sh_exp(f, method="taylor", terms=30), sh.sh_exp(f, method="exact"),
                                   atol=EXACT_ATOL)
    # a constant: log and exp act pointwise
    c = np.zeros(order * order)
    c[0] = np.sqrt(4 * np.pi) * 0.25
    assert sh.sh_log(c)[0] == pytest.approx(np.sqrt(4 * np.pi) * np.log(0.25), abs=EXACT_ATOL)


def test_quadrature_exp_against_closed_form():
    # f(omega) = k z: exp(f) is zonal with coefficients 2 pi sqrt((2l+1)/4pi) int P_l(mu) e^{k mu}
    order, k = 5, 0.8
    f = np.zeros(order * order)
    f[2] = k / np.sqrt(3 / (4 * np.pi))                     # y_10 = sqrt(3 / 4 pi) z
    expected = np.zeros(order * order)
    for l in range(order):
        expected[l * (l + 1)] = 2 * np.pi * np.sqrt((2 * l + 1) / (4 * np.pi)) * integrate.quad(
            lambda mu: special.eval_legendre(l, mu) * np.exp(k * mu), -1, 1)[0]
    np.testing.assert_allclose(sh.sh_exp(f, method="quadrature"), expected, atol=QUAD_ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_ol_is_the_least_squares_fit(order):
    """At a table entry, a 1 + b f_hat is the best approximation of exp*(f_hat) of that form."""
    t = sh.log_table(order)
    i = len(t.ol_magnitude) // 2
    f = np.zeros(order * order)
    f[np.arange(order) * (np.arange(order) + 1)] = t.log_zonal[i]
    f_hat = f.copy()
    f_hat[0] = 0.0
    target = sh.sh_exp(f_hat, method="exact")
    ol = sh.sh_exp(f_hat, method="ol")
    best = np.linalg.norm(ol - target)
    one = np.zeros(order * order)
    one[0] = np.sqrt(4 * np.pi)
    for da, db in [(0.01, 0), (-0.01, 0), (0, 0.01), (0, -0.01)]:
        other = ol + da * one + db * f_hat
        assert np.linalg.norm(other - target) > best
    # DC isolation: a constant added to f scales the result by its exponential
    shifted = f_hat.copy()
    shifted[0] = -0.3 * np.sqrt(4 * np.pi)
    for method in ("ol", "hybrid", "taylor", "exact"):
        np.testing.assert_allclose(sh.sh_exp(shifted, method=method),
                                   np.exp(-0.3) * sh.sh_exp(f_hat, method=method), atol=EXACT_ATOL)


def test_hybrid_beats_ol_on_large_logs():
    """Scaling and squaring makes the hybrid closer to exp* than OL once several blockers add."""
    order = 4
    t = sh.log_table(order)
    axes = _random_directions(8, seed=5)
    f = sh.rotate_zonal(t.log_zonal[150], axes).sum(axis=0)      # eight blockers of ~26 degrees
    exact = sh.sh_exp(f, method="exact")
    err_ol = np.linalg.norm(sh.sh_exp(f, method="ol") - exact)
    err_hyb = np.linalg.norm(sh.sh_exp(f, method="hybrid") - exact)
    assert err_hyb < err_ol


def test_log_table_shape_and_monotone_prefix():
    t = sh.log_table(5)
    assert t.log_zonal.shape == (sh.LOG_TABLE_SIZE, 5)
    assert np.all(np.diff(t.ol_magnitude) > 0)
    assert t.alpha[0] == 0.0 and t.alpha[-1] == pytest.approx(np.pi / 2)


def test_float32_directions():
    d = _random_directions(50)
    d32 = d.astype(np.float32)
    np.testing.assert_allclose(sh.sh_basis(d32, 6), sh.sh_basis(d32.astype(np.float64), 6), atol=FLOAT32_ATOL)
    assert sh.sh_basis(d32, 6).dtype == np.float64


def test_validation():
    with pytest.raises(ValueError, match="order"):
        sh.sh_basis([0, 0, 1], order=0)
    with pytest.raises(ValueError, match="order"):
        sh.cap_zonal(0.1, order=sh.MAX_ORDER + 1)
    with pytest.raises(ValueError, match="directions"):
        sh.sh_basis([0, 1], order=2)
    with pytest.raises(ValueError, match="alpha"):
        sh.cap_zonal(-0.1)
    with pytest.raises(ValueError, match="alpha"):
        sh.cap_zonal(np.nan)
    with pytest.raises(ValueError, match="same order"):
        sh.sh_product(np.zeros(9), np.zeros(16))
    with pytest.raises(ValueError, match="f must have shape"):
        sh.sh_exp(np.zeros(10))
    with pytest.raises(ValueError, match="method"):
        sh.sh_exp(np.zeros(9), method="pade")
    with pytest.raises(ValueError, match="epsilon"):
        sh.sh_log(np.eye(9)[0], epsilon=0.0)
