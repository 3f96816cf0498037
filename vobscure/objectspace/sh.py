r"""Real spherical harmonics of low order, and the SH algebra of Ren et al. (2006).

Convention
----------
Real, orthonormal spherical harmonics :math:`y_{lm}`, bands :math:`l = 0 \dots n-1`;
a function of **order n** has :math:`n^2` coefficients, stored at index
:math:`i = l(l + 1) + m`. With :math:`z = \cos\theta` and
:math:`x + iy = \sin\theta\, e^{i\phi}`,

.. math::

    y_{lm} = \sqrt{2} K_l^m P_l^m(z) \cos(m\phi)\ (m > 0),\quad
    y_{l0} = K_l^0 P_l(z),\quad
    y_{lm} = \sqrt{2} K_l^{|m|} P_l^{|m|}(z) \sin(|m|\phi)\ (m < 0),

:math:`K_l^m = \sqrt{\frac{2l+1}{4\pi}\frac{(l-m)!}{(l+m)!}}`, with the associated Legendre
functions *without* the Condon-Shortley phase (so :math:`y_{11} \propto +x`). Nothing in this
module depends on that choice except the signs of individual coefficients.

The product ``*`` of two SH vectors is the projection of the product of the functions they
stand for back onto order n (Ren et al. 2006, "SH products"), through the triple-product
(Gaunt) tensor :math:`\Gamma_{ijk} = \int y_i y_j y_k\,d\omega`, computed here once per order
by a quadrature that is exact for polynomials of the degree involved. ``exp*`` and ``log*``
are the functions of that algebra: :math:`\exp^*(f) = \sum_k f^{*k}/k!`, i.e. the matrix
exponential of the product matrix :math:`M_f` (:math:`(M_f)_{ik} = \sum_j f_j \Gamma_{ijk}`)
applied to the constant function 1.

References
----------
.. [1] Z. Ren, R. Wang, J. Snyder, K. Zhou, X. Liu, B. Sun, P.-P. Sloan, H. Bao, Q. Peng,
   B. Guo, "Real-time Soft Shadows in Dynamic Scenes using Spherical Harmonic
   Exponentiation", ACM Trans. Graph. 25(3) (SIGGRAPH 2006), 977-986.
.. [2] P.-P. Sloan, J. Kautz, J. Snyder, "Precomputed Radiance Transfer for Real-Time
   Rendering in Dynamic, Low-Frequency Lighting Environments", SIGGRAPH 2002 (the zonal
   rotation :math:`f_{lm} = \sqrt{4\pi/(2l+1)}\, z_l\, y_{lm}(d)`).

Section names are cited instead of equation numbers: the text of Ren et al. available to
the author was the abstract, the supplement's summary and third-party material, not the
numbered paper (see ``docs/sphere-sets.md``).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from functools import lru_cache
from math import factorial

import numpy as np

from .._validate import as_array, check_choice, check_int

__all__ = ["MAX_ORDER", "MIN_ORDER", "sh_basis", "sh_index", "cap_zonal", "rotate_zonal", "clamped_cosine_zonal",
           "hemisphere_zonal", "triple_product_tensor", "sh_product", "product_matrix", "sh_exp", "sh_log",
           "sh_project", "log_table", "LogTable", "EXP_METHODS", "LOG_EPSILON", "HYBRID_FRACTION"]

#: Orders supported (order n = n^2 coefficients): the issue asks for 3 to 6.
MIN_ORDER = 1
MAX_ORDER = 8

#: Methods of :func:`sh_exp`.
EXP_METHODS = ("ol", "hybrid", "taylor", "exact", "quadrature")

#: Eigenvalues of the product matrix below LOG_EPSILON * (largest eigenvalue) are clamped to
#: it before the log (a cap's visibility vanishes on the cap, so its product matrix has
#: eigenvalues near 0 or below, where the log does not exist).
LOG_EPSILON = 0.02

#: Terms of the ``"taylor"`` exponential (after DC isolation).
TAYLOR_TERMS = 12

_SQRT_4PI = np.sqrt(4.0 * np.pi)


def sh_index(l: int, m: int) -> int:
    """Index of coefficient (l, m): l (l + 1) + m.

    Examples
    --------
    >>> sh_index(0, 0), sh_index(1, -1), sh_index(2, 2)
    (0, 1, 8)

    Raises
    ------
    ValueError
        If l is not an integer >= 0 or m not an integer with |m| <= l (outside that range
        the formula would alias another coefficient: (2, 3) would be (3, -3)).
    """
    l = check_int(l, "l", minimum=0)
    if isinstance(m, bool) or not isinstance(m, numbers.Integral) or abs(m) > l:
        raise ValueError(f"m must be an integer with |m| <= l = {l}, got {m!r}")
    return l * (l + 1) + int(m)


def _check_order(order) -> int:
    order = check_int(order, "order", minimum=MIN_ORDER)
    if order > MAX_ORDER:
        raise ValueError(f"order must be at most {MAX_ORDER} (order n has n^2 coefficients), got {order}")
    return order


#: How far from 1 the length of a direction given to :func:`sh_basis` or :func:`rotate_zonal`
#: may be (the basis is a polynomial in x, y, z, so a longer or shorter vector gives values
#: of no direction; float32 unit vectors are within 1e-7).
UNIT_TOL = 1e-3


def _check_unit(d: np.ndarray, name: str) -> None:
    length = np.sqrt(np.einsum("...i,...i->...", d, d))
    bad = ~(np.abs(length - 1.0) <= UNIT_TOL)                  # NaN fails too
    if np.any(bad):
        raise ValueError(f"{name} must be unit vectors (|d| within {UNIT_TOL} of 1); {int(np.count_nonzero(bad))} "
                         f"are not, e.g. |d| = {float(np.ravel(length)[np.ravel(bad)][0])!r} (a zero direction "
                         f"has no axis)")


def sh_basis(directions, order: int = 4) -> np.ndarray:
    r"""The real SH basis :math:`y_i(\omega)` of order ``order`` at unit directions.

    Parameters
    ----------
    directions : (..., 3) float
        Unit vectors (not renormalized; the basis is a polynomial in x, y, z): a length
        further than :data:`UNIT_TOL` from 1 (a zero or NaN vector included) is an error.
    order : int
        n: bands 0 .. n-1, n^2 functions.

    Returns
    -------
    (..., n^2) float64

    Examples
    --------
    >>> y = sh_basis([0.0, 0.0, 1.0], order=2)
    >>> np.round(y, 6).tolist()   # y00 = 1 / sqrt(4 pi), y10 = sqrt(3 / 4 pi) z
    [0.282095, 0.0, 0.488603, 0.0]
    """
    order = _check_order(order)
    d = as_array(directions, "directions", finite=False)
    if d.shape[-1:] != (3,):
        raise ValueError(f"directions must have shape (..., 3), got {d.shape}")
    _check_unit(d, "directions")
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    out = np.empty(d.shape[:-1] + (order * order,))
    # Re and Im of (x + i y)^m: sin^m(theta) cos(m phi), sin^m(theta) sin(m phi).
    c = [np.ones_like(x)]
    s = [np.zeros_like(x)]
    for m in range(1, order):
        c.append(c[-1] * x - s[-1] * y)
        s.append(c[-2] * y + s[-1] * x)
    for m in range(order):
        # P_l^m(z) / sin^m(theta) by the standard three-term recurrence in l, no CS phase.
        q_prev = None
        q = np.full_like(z, float(np.prod(np.arange(1, 2 * m, 2))) if m > 0 else 1.0)   # (2m-1)!!
        for l in range(m, order):
            if l == m + 1:
                q_prev, q = q, z * (2 * m + 1) * q
            elif l > m + 1:
                q_prev, q = q, ((2 * l - 1) * z * q - (l + m - 1) * q_prev) / (l - m)
            K = np.sqrt((2 * l + 1) / (4 * np.pi) * factorial(l - m) / factorial(l + m))
            if m == 0:
                out[..., sh_index(l, 0)] = K * q
            else:
                out[..., sh_index(l, m)] = np.sqrt(2.0) * K * q * c[m]
                out[..., sh_index(l, -m)] = np.sqrt(2.0) * K * q * s[m]
    return out


def _legendre(l_max: int, x) -> np.ndarray:
    """P_0 .. P_l_max at x: (l_max + 1, *x.shape)."""
    x = np.asarray(x, dtype=np.float64)
    P = np.empty((l_max + 1,) + x.shape)
    P[0] = 1.0
    if l_max >= 1:
        P[1] = x
    for l in range(2, l_max + 1):
        P[l] = ((2 * l - 1) * x * P[l - 1] - (l - 1) * P[l - 2]) / l
    return P


def cap_zonal(alpha, order: int = 4) -> np.ndarray:
    r"""Zonal coefficients of the indicator of a cap of half-angle ``alpha`` around +z.

    .. math::

        z_l = 2\pi \sqrt{\tfrac{2l+1}{4\pi}} \int_{\cos\alpha}^{1} P_l(\mu)\,d\mu,\qquad
        \int_{x}^{1} P_l = \frac{P_{l-1}(x) - P_{l+1}(x)}{2l+1}\ (l \ge 1),\quad 1 - x\ (l = 0).

    Parameters
    ----------
    alpha : (...) float
        Half-angles in [0, pi] (radians).
    order : int

    Returns
    -------
    (..., order) float64
        :math:`z_0 \dots z_{n-1}`, the coefficients of :math:`y_{l0}`.

    Examples
    --------
    >>> z = cap_zonal(np.pi / 2, order=3)   # the upper hemisphere
    >>> np.round(z, 6).tolist()              # sqrt(pi), sqrt(3 pi) / 2, 0
    [1.772454, 1.53499, 0.0]
    """
    order = _check_order(order)
    alpha = as_array(alpha, "alpha")
    if np.any((alpha < 0) | (alpha > np.pi)):
        raise ValueError("alpha must lie in [0, pi] (a cap's half-angle in radians)")
    x = np.cos(alpha)
    P = _legendre(order, x)
    out = np.empty(alpha.shape + (order,))
    out[..., 0] = 1.0 - x
    for l in range(1, order):
        out[..., l] = (P[l - 1] - P[l + 1]) / (2 * l + 1)
    ls = np.arange(order)
    return 2.0 * np.pi * np.sqrt((2 * ls + 1) / (4 * np.pi)) * out


def rotate_zonal(zonal, direction) -> np.ndarray:
    r"""Rotate zonal coefficients from +z to ``direction``.

    :math:`f_{lm} = \sqrt{4\pi/(2l+1)}\, z_l\, y_{lm}(d)` (the addition theorem; Sloan et al.
    2002; Ren et al. 2006 rotate each blocker's tabulated vector this way).

    Parameters
    ----------
    zonal : (..., n) float
        Zonal coefficients :math:`z_l`.
    direction : (..., 3) float
        Unit axis (broadcast against ``zonal``'s leading shape); a zero, NaN or non-unit
        axis is an error (as in :func:`sh_basis`).

    Returns
    -------
    (..., n^2) float64

    Examples
    --------
    >>> f = rotate_zonal(cap_zonal(0.3, order=3), [0.0, 0.0, 1.0])
    >>> bool(np.allclose(f[[0, 2, 6]], cap_zonal(0.3, order=3)))
    True
    """
    zonal = np.asarray(zonal, dtype=np.float64)
    n = zonal.shape[-1]
    direction = as_array(direction, "direction", finite=False)
    if direction.shape[-1:] == (3,):
        _check_unit(direction, "direction")
    y = sh_basis(direction, order=n)
    ls = np.repeat(np.arange(n), 2 * np.arange(n) + 1)            # band of every index
    scale = np.sqrt(4.0 * np.pi / (2 * ls + 1))
    z = zonal[..., ls]
    if np.broadcast_shapes(y.shape, z.shape) != y.shape:
        y = np.broadcast_to(y, np.broadcast_shapes(y.shape, z.shape)).copy()
    y *= z                                                         # in place: one (..., n^2) array
    y *= scale
    return y


def clamped_cosine_zonal(order: int = 4) -> np.ndarray:
    r"""Zonal coefficients of :math:`\max(0, \cos\theta)/\pi` (the cosine-weighted AO kernel).

    :math:`h_l = 2\sqrt{\tfrac{2l+1}{4\pi}}\int_0^1 P_l(\mu)\,\mu\,d\mu`, a polynomial integral
    evaluated exactly by Gauss-Legendre quadrature. The visibility a normal n sees is then
    :math:`V = \sum_i g_i\,\hat h_i` with :math:`\hat h` these coefficients rotated to n.

    Examples
    --------
    >>> h = clamped_cosine_zonal(3)      # 1 / sqrt(4 pi), 1 / sqrt(3 pi), sqrt(5 / pi) / 8
    >>> np.round(h, 6).tolist()
    [0.282095, 0.325735, 0.157696]
    """
    order = _check_order(order)
    mu, w = np.polynomial.legendre.leggauss(order + 2)
    mu = 0.5 * (mu + 1.0)
    w = 0.5 * w
    P = _legendre(order - 1, mu)
    ls = np.arange(order)
    return 2.0 * np.sqrt((2 * ls + 1) / (4 * np.pi)) * (P @ (w * mu))


def hemisphere_zonal(order: int = 4) -> np.ndarray:
    r"""Zonal coefficients of the uniform-hemisphere AO kernel :math:`[\cos\theta > 0]/(2\pi)`."""
    return cap_zonal(np.pi / 2, order) / (2.0 * np.pi)


@lru_cache(maxsize=None)
def _quadrature(n_theta: int, n_phi: int):
    """Gauss-Legendre in cos(theta) x uniform in phi: directions (N, 3) and weights (N,)."""
    mu, w = np.polynomial.legendre.leggauss(n_theta)
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    st = np.sqrt(1.0 - mu * mu)
    d = np.stack([st[:, None] * np.cos(phi)[None, :], st[:, None] * np.sin(phi)[None, :],
                  np.broadcast_to(mu[:, None], (n_theta, n_phi))], axis=-1).reshape(-1, 3)
    weights = np.repeat(w, n_phi) * (2 * np.pi / n_phi)
    d.setflags(write=False)
    weights.setflags(write=False)
    return d, weights


@lru_cache(maxsize=None)
def triple_product_tensor(order: int = 4) -> np.ndarray:
    r"""The Gaunt tensor :math:`\Gamma_{ijk} = \int y_i y_j y_k\,d\omega` of order n, (n^2, n^2, n^2).

    Computed once per order by a product quadrature that is exact for the integrand, a
    polynomial of degree :math:`3(n-1)` on the sphere: Gauss-Legendre with
    :math:`\lceil (3n - 2)/2 \rceil` nodes in :math:`\cos\theta` (exact to degree 3n - 3) and
    :math:`3n - 2` equispaced :math:`\phi` (exact for harmonics of frequency up to 3n - 3).
    Entries below 1e-12 in magnitude are set to 0 (they are 0 by the selection rules).

    Examples
    --------
    >>> G = triple_product_tensor(2)
    >>> round(float(G[0, 0, 0]), 6), round(float(G[0, 1, 1]), 6), float(G[1, 2, 3])
    (0.282095, 0.282095, 0.0)
    """
    order = _check_order(order)
    deg = 3 * (order - 1)
    d, w = _quadrature(deg // 2 + 1, deg + 1)
    y = sh_basis(d, order)
    G = np.einsum("q,qi,qj,qk->ijk", w, y, y, y)
    G[np.abs(G) < 1e-12] = 0.0
    G.setflags(write=False)
    return G


def _as_coeffs(f, name: str) -> tuple[np.ndarray, int]:
    f = as_array(f, name)
    n = int(round(np.sqrt(f.shape[-1]))) if f.ndim else 0
    if f.ndim == 0 or n * n != f.shape[-1] or not MIN_ORDER <= n <= MAX_ORDER:
        raise ValueError(f"{name} must have shape (..., n^2) with n in {MIN_ORDER}..{MAX_ORDER}, got {f.shape}")
    return f, n


def product_matrix(f) -> np.ndarray:
    r"""The product matrix :math:`(M_f)_{ik} = \sum_j f_j \Gamma_{ijk}`: :math:`f * g = M_f g`.

    Parameters
    ----------
    f : (..., n^2) float

    Returns
    -------
    (..., n^2, n^2) float64, symmetric.
    """
    f, n = _as_coeffs(f, "f")
    G = triple_product_tensor(n)
    return np.tensordot(f, G, axes=([-1], [1]))


def sh_product(f, g) -> np.ndarray:
    r"""The SH product :math:`f * g`: the projection of the product of the two functions onto
    order n (Ren et al. 2006, "SH products"; the triple-product tensor).

    Parameters
    ----------
    f, g : (..., n^2) float
        The same order; leading shapes broadcast.

    Returns
    -------
    (..., n^2) float64

    Examples
    --------
    >>> one = np.zeros(9); one[0] = np.sqrt(4 * np.pi)       # the constant 1
    >>> g = np.arange(9.0)
    >>> bool(np.allclose(sh_product(one, g), g))
    True
    """
    f, n = _as_coeffs(f, "f")
    g, m = _as_coeffs(g, "g")
    if n != m:
        raise ValueError(f"f and g must have the same order, got {n} and {m}")
    return _product(f, g, triple_product_tensor(n))


def _product(f: np.ndarray, g: np.ndarray, G: np.ndarray) -> np.ndarray:
    """sum_j g_j (f @ G[:, j, :]): one (..., n^2) temporary at a time (no (..., n^2, n^2))."""
    f, g = np.broadcast_arrays(f, g)
    out = np.zeros(f.shape)
    for j in range(G.shape[1]):
        tmp = f @ G[:, j, :]
        tmp *= g[..., j, None]
        out += tmp
    return out


def sh_project(func, order: int = 4, *, resolution: int = 64) -> np.ndarray:
    r"""Project ``func(directions) -> (N, ...)`` onto order n by quadrature.

    Gauss-Legendre in :math:`\cos\theta` (``resolution`` nodes) times ``2 resolution``
    equispaced azimuths: exact for polynomials of degree below ``2 resolution``, and
    spectrally accurate for smooth functions (not for indicators, whose edges it samples).

    Returns
    -------
    (..., n^2) float64, the leading shape that of ``func``'s output after N.
    """
    order = _check_order(order)
    resolution = check_int(resolution, "resolution", minimum=order)
    d, w = _quadrature(resolution, 2 * resolution)
    values = np.asarray(func(d), dtype=np.float64)
    y = sh_basis(d, order)
    return np.einsum("q...,q,qi->...i", values, w, y)


def _unit(n: int) -> np.ndarray:
    e = np.zeros(n * n)
    e[0] = _SQRT_4PI
    return e


def _sym_function(M: np.ndarray, fn) -> np.ndarray:
    """fn applied to the eigenvalues of symmetric matrices M (..., k, k), times the unit."""
    lam, R = np.linalg.eigh(M)
    return fn(lam, R)


def _exact_exp(f: np.ndarray, n: int) -> np.ndarray:
    """exp*(f) = exp(M_f) 1 by the eigendecomposition of the symmetric M_f."""
    M = product_matrix(f)

    def fn(lam, R):
        # exp(M) 1 = R diag(e^lam) R^T 1, and 1 = sqrt(4 pi) e_0.
        return np.einsum("...ik,...k,...k->...i", R, np.exp(lam), _SQRT_4PI * R[..., 0, :])
    return _sym_function(M, fn)


def sh_log(g, *, epsilon: float = LOG_EPSILON) -> np.ndarray:
    r"""The SH logarithm :math:`\log^*(g)`: the vector whose :math:`\exp^*` is g.

    Computed through the product matrix: :math:`\log^*(g) = \log(M_g)\,1` with
    :math:`M_g = R\,\mathrm{diag}(\lambda)\,R^T`; eigenvalues below
    ``epsilon`` :math:`\lambda_{max}` are raised to it, since a blocker's visibility is 0
    on the blocked cap and its band-limited projection dips to or below 0 there, where no
    logarithm exists (Ren et al. 2006, "SH log"; the clamp threshold is this library's
    choice, see ``docs/sphere-sets.md``).

    Parameters
    ----------
    g : (..., n^2) float
        SH vectors of positive-ish functions (visibilities). The domain: the largest
        eigenvalue of each product matrix :math:`M_g` must be > 0 (g positive somewhere);
        g = 0 or a function <= 0 everywhere is an error, not NaN.
    epsilon : float
        Relative eigenvalue floor, in (0, 1).

    Returns
    -------
    (..., n^2) float64

    Examples
    --------
    >>> g = np.zeros(9); g[0] = np.sqrt(4 * np.pi) * 0.5     # the constant 1/2
    >>> f = sh_log(g)
    >>> round(float(f[0] / np.sqrt(4 * np.pi)), 6)           # log(1/2) everywhere
    -0.693147
    """
    g, n = _as_coeffs(g, "g")
    epsilon = float(epsilon)
    if not 0.0 < epsilon < 1.0:
        raise ValueError(f"epsilon must lie in (0, 1), got {epsilon!r}")
    M = product_matrix(g)

    def fn(lam, R):
        top = lam[..., -1]
        if not np.all(top > 0):
            raise ValueError(f"sh_log needs g positive somewhere: {int(np.count_nonzero(~(top > 0)))} vector(s) of g "
                             f"have a product matrix whose largest eigenvalue is <= 0 (g = 0, or a function <= 0 "
                             f"everywhere), and the log of such a function does not exist")
        floor = epsilon * lam[..., -1:]
        lam = np.maximum(lam, floor)
        return np.einsum("...ik,...k,...k->...i", R, np.log(lam), _SQRT_4PI * R[..., 0, :])
    return _sym_function(M, fn)


# ----------------------------------------------------------------------------- exponentials
def _split_dc(f: np.ndarray):
    """DC isolation: exp*(f) = exp(f_0 / sqrt(4 pi)) exp*(f_hat), f_hat = f without f_0
    (the constant f_0 y_00 commutes with every product; Ren et al. 2006, "DC isolation")."""
    f_hat = f.copy()
    f_hat[..., 0] = 0.0
    return np.exp(f[..., 0] / _SQRT_4PI), f_hat


@dataclass(frozen=True)
class LogTable:
    """The log-visibility table of one spherical blocker (:func:`log_table`).

    Attributes
    ----------
    alpha : (size,) float64
        Angular radii, evenly spaced in [0, pi/2].
    log_zonal : (size, n) float64
        Zonal coefficients of the log-visibility vector at each angular radius.
    magnitude : (size,) float64
        ``||f_hat||``, the norm of the non-DC part of each log vector.
    ol_magnitude, ol_a, ol_b : (k,) float64
        The optimal-linear coefficients against the magnitude, over the table's prefix on
        which the magnitude increases (k <= size; past it the eigenvalue floor of
        :func:`sh_log` makes the magnitude level off and dip, so it no longer identifies a
        blocker).
    """

    alpha: np.ndarray
    log_zonal: np.ndarray
    magnitude: np.ndarray
    ol_magnitude: np.ndarray
    ol_a: np.ndarray
    ol_b: np.ndarray


#: Angular radii of :func:`log_table`.
LOG_TABLE_SIZE = 512


@lru_cache(maxsize=None)
def log_table(order: int = 4, *, size: int = LOG_TABLE_SIZE, epsilon: float = LOG_EPSILON) -> LogTable:
    r"""The log-visibility table of one blocker and the optimal-linear coefficients.

    For ``size`` angular radii :math:`\alpha` evenly spaced in :math:`[0, \pi/2]` (a sphere
    of radius r at distance d has :math:`\alpha = \arcsin(r/d)`): the zonal log vector
    :math:`f(\alpha) = \log^*(g(\alpha))` of the sphere's visibility
    :math:`g = 1 - \mathrm{cap}` seen on the +z axis (Ren et al. 2006 tabulate the blockers'
    log vectors against the angular radius), and the optimal-linear coefficients at the
    magnitude :math:`m = \|\hat f\|` of its non-DC part,

    .. math::

        a = \frac{\langle \exp^*(\hat f), 1\rangle}{\langle 1, 1\rangle},\qquad
        b = \frac{\langle \exp^*(\hat f), \hat f\rangle}{\langle \hat f, \hat f\rangle},

    the least-squares fit :math:`\exp^*(\hat f) \approx a\,1 + b\,\hat f` (Ren et al. 2006,
    "optimal linear approximation"; :math:`\hat f \perp 1`, so the two projections are
    independent), with :math:`\exp^*` exact (the matrix exponential).

    Returns
    -------
    LogTable

    Examples
    --------
    >>> t = log_table(4)
    >>> t.log_zonal.shape, float(t.log_zonal[0, 0]), float(t.ol_a[0]), float(t.ol_b[0])
    ((512, 4), 0.0, 1.0, 1.0)
    """
    order = _check_order(order)
    size = check_int(size, "size", minimum=2)
    alpha = np.linspace(0.0, np.pi / 2, size)
    zonal_g = -cap_zonal(alpha, order)
    zonal_g[:, 0] += _SQRT_4PI                                         # g = 1 - cap
    ls = np.arange(order)
    idx = ls * (ls + 1)
    g = np.zeros((size, order * order))
    g[:, idx] = zonal_g
    f = sh_log(g, epsilon=epsilon)
    log_zonal = np.ascontiguousarray(f[:, idx])
    log_zonal[0] = 0.0                                                 # no blocker: log 1 = 0
    f[0] = 0.0
    _, f_hat = _split_dc(f)
    magnitude = np.linalg.norm(f_hat, axis=-1)
    rising = np.flatnonzero(np.diff(magnitude) <= 0)
    k = size if len(rising) == 0 else int(rising[0]) + 1
    e_hat = _exact_exp(f_hat[:k], order)
    m = magnitude[:k]
    a = e_hat[:, 0] / _SQRT_4PI
    with np.errstate(invalid="ignore", divide="ignore"):
        b = np.einsum("...i,...i->...", e_hat, f_hat[:k]) / m ** 2
    a[m == 0] = 1.0                                                    # exp(x) = 1 + x + o(x)
    b[m == 0] = 1.0
    table = LogTable(alpha, log_zonal, magnitude, m.copy(), a, b)
    for arr in (table.alpha, table.log_zonal, table.magnitude, table.ol_magnitude, table.ol_a, table.ol_b):
        arr.setflags(write=False)
    return table


def _exp_ol(f: np.ndarray, n: int) -> np.ndarray:
    scale, f_hat = _split_dc(f)
    t = log_table(n)
    mag_table, a_table, b_table = t.ol_magnitude, t.ol_a, t.ol_b
    m = np.linalg.norm(f_hat, axis=-1)
    # Beyond the table (several blockers add up), a and b are held at its last entry.
    a = np.interp(m, mag_table, a_table)
    b = np.interp(m, mag_table, b_table)
    out = b[..., None] * f_hat                                         # optimal linear: a 1 + b f_hat
    out[..., 0] = a * _SQRT_4PI
    return scale[..., None] * out


#: The hybrid exponential halves f until ||f_hat|| is at most this fraction of the table's
#: largest magnitude, applies the optimal-linear fit, and squares the result back.
HYBRID_FRACTION = 0.05


def _exp_hybrid(f: np.ndarray, n: int) -> np.ndarray:
    scale, f_hat = _split_dc(f)
    mag_table = log_table(n).ol_magnitude
    limit = HYBRID_FRACTION * mag_table[-1]
    m = np.linalg.norm(f_hat, axis=-1)
    with np.errstate(divide="ignore"):
        k = np.where(m > limit, np.ceil(np.log2(np.maximum(m, 1e-300) / limit)), 0).astype(int)
    out = _exp_ol(f_hat * np.ldexp(1.0, -k)[..., None], n)
    G = triple_product_tensor(n)
    # scaling and squaring: exp*(f) = exp*(f / 2^k)^(*2^k), one SH product per squaring
    for step in range(int(k.max(initial=0))):
        more = k > step
        out[more] = _product(out[more], out[more], G)
    return scale[..., None] * out


def _exp_taylor(f: np.ndarray, n: int, terms: int) -> np.ndarray:
    scale, f_hat = _split_dc(f)
    term = np.broadcast_to(_unit(n), f.shape).copy()
    out = term.copy()
    G = triple_product_tensor(n)
    for k in range(1, terms + 1):
        term = _product(term, f_hat, G) / k
        out += term
    return scale[..., None] * out


def sh_exp(f, *, method: str = "hybrid", terms: int = TAYLOR_TERMS, resolution: int = 64) -> np.ndarray:
    r"""The SH exponential :math:`\exp^*(f)` by one of Ren et al.'s approximations.

    Parameters
    ----------
    f : (..., n^2) float
        Log-visibility vectors.
    method : {"hybrid", "ol", "taylor", "exact", "quadrature"}
        All but ``"quadrature"`` apply DC isolation first
        (:math:`\exp^*(f) = e^{f_0/\sqrt{4\pi}} \exp^*(\hat f)`).

        - ``"ol"``: the optimal-linear approximation :math:`a(\|\hat f\|)\,1 + b(\|\hat f\|)\,\hat f`
          with a, b from :func:`log_table` (Ren et al. 2006, "optimal linear approximation").
        - ``"hybrid"``: scaling and squaring around it: halve :math:`\hat f` k times until its
          magnitude is at most :data:`HYBRID_FRACTION` of the table's largest, OL, then k SH
          squarings (Ren et al. 2006, the hybrid of OL and scaling/squaring).
        - ``"taylor"``: :math:`\sum_{k \le terms} \hat f^{*k}/k!` in the SH algebra.
        - ``"exact"``: :math:`\exp(M_f)\,1`, the limit of ``"taylor"`` (eigendecomposition).
        - ``"quadrature"``: the projection of :math:`e^{f(\omega)}` onto order n by quadrature
          (:func:`sh_project`), the exponential of the function rather than of the algebra;
          a reference for tests.
    terms : int
        Terms of ``"taylor"``.
    resolution : int
        Quadrature resolution of ``"quadrature"``.

    Returns
    -------
    (..., n^2) float64

    Raises
    ------
    ValueError
        When the result is not finite: the domain is the vectors whose exponential (and, for
        ``"hybrid"`` and ``"taylor"``, the intermediate SH products) fit in float64, e.g. any
        log-visibility (a function <= 0); a NaN result is never returned.

    Examples
    --------
    >>> g = np.zeros(16); g[0] = np.sqrt(4 * np.pi) * 0.8
    >>> g[2] = 0.3                                           # a smooth, positive function
    >>> f = sh_log(g)
    >>> float(np.abs(sh_exp(f, method="exact") - g).max()) < 1e-5   # exp*(log*(g)) ~ g
    True
    """
    f, n = _as_coeffs(f, "f")
    check_choice(method, "method", EXP_METHODS)
    if method == "taylor":
        terms = check_int(terms, "terms")
    with np.errstate(over="ignore", invalid="ignore"):
        if method == "exact":
            out = _exact_exp(f, n)
        elif method == "ol":
            out = _exp_ol(f, n)
        elif method == "hybrid":
            out = _exp_hybrid(f, n)
        elif method == "taylor":
            out = _exp_taylor(f, n, terms)
        else:
            # quadrature: project exp(f(omega)) point by point
            flat = f.reshape(-1, n * n)
            out = sh_project(lambda dirs: np.exp(sh_basis(dirs, n) @ flat.T), n, resolution=resolution)
            out = out.reshape(f.shape)
    if not np.all(np.isfinite(out)):
        bad = ~np.all(np.isfinite(out), axis=-1)
        worst = float(np.max(np.linalg.norm(f, axis=-1)[bad]))
        raise ValueError(f"sh_exp({method!r}) overflows float64 for {int(np.count_nonzero(bad))} vector(s) of f "
                         f"(largest ||f|| = {worst:.3g}): the exponential of a function reaching about 700 "
                         f"exceeds 1.8e308, and the SH products of the scaling and squaring overflow sooner; "
                         f"f must be a log-visibility (<= 0) or of moderate size")
    return out
