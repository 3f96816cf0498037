"""The shading terms of RTR 9.2 (vobscure.shading): each against its formula, its limits and
an independent computation (a geometric series summed term by term, quadrature over the
sphere, the ray-traced bent normals of the crease), plus broadcasting, dtypes and validation."""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.shading import (JIMENEZ_2016, LinearSky, ambient, bent_cosine, bent_normal_lookup,
                              iones_indirect, multibounce_jimenez, stewart_langer)

from analytic import crease_bent_normal, crease_cosine_ao
from conftest import t_threshold

EXACT = 1e-12          # closed forms evaluated two ways in float64
QUADRATURE = 1e-5      # midpoint rule on QUAD_N x QUAD_N cells of the sphere
QUAD_N = 800
R = 1.0                # ray length of the crease's ground truth (max_distance)
C_VALUES = np.array([0.05, 0.25, 0.5, 0.75, 0.95])
# Stewart-Langer vs the Jimenez fit on a 101 x 101 grid of k_A and albedo (docs/shading.md)
GRID = np.linspace(0.0, 1.0, 101)
MAX_DIFF = {0.5: 0.0230, 0.8: 0.1025, 0.9: 0.2468, 0.95: 0.3970, 1.0: 0.9660}   # albedo <= key: max |diff|
DIFF_ROUNDING = 1e-4


# ----------------------------------------------------------------------------- helpers
def sphere_quadrature(f, n=QUAD_N):
    """Integral of f(omega) over the upper (y > 0) hemisphere: midpoint rule in (theta, phi)
    about the y axis, d omega = sin theta d theta d phi. f: (m, 3) -> (m, k)."""
    theta = (np.arange(n) + 0.5) * (np.pi / 2) / n
    phi = (np.arange(2 * n) + 0.5) * (2 * np.pi) / (2 * n)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    omega = np.stack([np.sin(T) * np.cos(P), np.cos(T), np.sin(T) * np.sin(P)], axis=-1).reshape(-1, 3)
    w = (np.sin(T) * (np.pi / 2 / n) * (2 * np.pi / (2 * n))).reshape(-1)
    return np.einsum("m,mk->k", w, f(omega))


# ----------------------------------------------------------------------------- ambient
def test_ambient_is_k_A_c_amb_L_A():
    k_A = np.array([0.0, 0.3, 1.0])
    rgb = np.array([0.8, 0.5, 0.2])
    out = ambient(k_A[:, None], rgb)
    np.testing.assert_allclose(out, np.outer(k_A, rgb), rtol=0, atol=EXACT)
    np.testing.assert_allclose(ambient(0.5, 0.8, L_A=2.0), 0.8, rtol=0, atol=EXACT)
    # Eq. 9.19 with no lights is Eq. 9.17 with E_ind = pi L_A
    np.testing.assert_allclose(iones_indirect(0.3, rgb, np.pi * 2.0, [5.0], k_ind=0.0),
                               ambient(0.3, rgb, L_A=2.0), rtol=0, atol=EXACT)


def test_ambient_broadcasting_contract():
    k_A = np.full((4, 5), 0.5)
    assert ambient(k_A[..., None], [1.0, 0.5, 0.25]).shape == (4, 5, 3)
    assert ambient(k_A[..., None], np.ones((4, 5, 3))).shape == (4, 5, 3)
    assert ambient(k_A, 0.5).shape == (4, 5)
    with pytest.raises(ValueError, match=r"k_A \(4, 5\), c_amb \(3,\).*k_A\[\.\.\., None\]"):
        ambient(k_A, [1.0, 0.5, 0.25])


# ----------------------------------------------------------------------------- Stewart-Langer
def test_stewart_langer_formula_and_limits():
    k = GRID[:, None]
    c = GRID[None, :-1]                                       # c_amb < 1
    np.testing.assert_allclose(stewart_langer(k, c), k / (1 - c * (1 - k)), rtol=EXACT)
    np.testing.assert_array_equal(stewart_langer(1.0, GRID), 1.0)          # k_A = 1 -> 1
    np.testing.assert_array_equal(stewart_langer(GRID, 0.0), GRID)         # c_amb = 0 -> k_A
    np.testing.assert_array_equal(stewart_langer(0.0, GRID), 0.0)          # no light enters
    # c_amb -> 1: k'_A -> 1 for every k_A > 0, as 1 - (1 - c)(1 - k_A) / k_A to first order
    for eps in (1e-3, 1e-6):
        k_A = np.array([0.1, 0.5, 0.9])
        np.testing.assert_allclose(stewart_langer(k_A, 1 - eps), 1 - eps * (1 - k_A) / k_A,
                                   rtol=0, atol=10 * eps ** 2 / k_A.min() ** 2)
    np.testing.assert_allclose(stewart_langer(np.array([0.1, 0.5]), 1.0), 1.0, rtol=EXACT)
    out = stewart_langer(k, GRID[None, :])
    assert np.all(out >= k - EXACT) and np.all(out <= 1 + EXACT)


def test_stewart_langer_is_the_sum_of_the_bounces():
    """Independent computation: in a uniform-albedo enclosure, each bounce returns the
    fraction c_amb (1 - k_A) of the previous one (docs/shading.md); sum 400 bounces."""
    k_A = np.linspace(0.05, 1.0, 20)[:, None]
    c_amb = np.linspace(0.0, 0.95, 20)[None, :]
    E, bounce = np.zeros((20, 20)), k_A * np.ones_like(c_amb)   # bounce 0: the sky seen, k_A
    for _ in range(400):
        E += bounce
        bounce = bounce * c_amb * (1 - k_A)
    np.testing.assert_allclose(stewart_langer(k_A, c_amb), E, rtol=1e-9)


# ----------------------------------------------------------------------------- Jimenez
def test_jimenez_formula_and_structure():
    x, rho = GRID[:, None], GRID[None, :]
    a = 2.0404 * rho - 0.3324
    b = -4.7951 * rho + 0.6417
    c = 2.7552 * rho + 0.6903
    np.testing.assert_allclose(multibounce_jimenez(x, rho), np.maximum(x, ((a * x + b) * x + c) * x),
                               rtol=EXACT, atol=EXACT)
    assert JIMENEZ_2016 == {"a": (2.0404, -0.3324), "b": (-4.7951, 0.6417), "c": (2.7552, 0.6903)}
    G = multibounce_jimenez(x, rho)
    assert np.all(G >= x)                                      # never darker than k_A
    assert np.all(np.diff(G, axis=1) >= 0)                     # brighter with the albedo
    assert np.all(np.diff(G, axis=0) >= 0)                     # and with k_A
    np.testing.assert_array_equal(multibounce_jimenez(0.0, GRID), 0.0)
    np.testing.assert_array_equal(multibounce_jimenez(GRID, 0.0), GRID)  # albedo 0: no bounce
    np.testing.assert_allclose(multibounce_jimenez(1.0, GRID), 1.0, atol=1e-4)


def test_jimenez_against_stewart_langer():
    """The numbers of docs/shading.md: max |G - k'_A| over the grid, by largest albedo."""
    d = multibounce_jimenez(GRID[:, None], GRID[None, :]) - stewart_langer(GRID[:, None], GRID[None, :])
    for rho_max, expected in MAX_DIFF.items():
        cols = GRID <= rho_max + 1e-12
        assert abs(np.abs(d[:, cols]).max() - expected) < DIFF_ROUNDING, rho_max
    # at albedo 0 both are k_A; the worst case is albedo 1, where Stewart-Langer is 1 for any k_A > 0
    np.testing.assert_array_equal(d[:, 0], 0.0)
    i, j = np.unravel_index(np.argmax(np.abs(d)), d.shape)
    assert GRID[j] == 1.0 and GRID[i] == pytest.approx(0.01)


# ----------------------------------------------------------------------------- Iones
def test_iones_eq_9_19_and_9_20():
    k_A, c_amb, E_ind, k_ind = 0.6, np.array([0.9, 0.5, 0.1]), 2.0, 0.3
    E_L = np.array([4.0, 1.0, 2.5])
    expected = k_A * c_amb / np.pi * (E_ind + k_ind * E_L.sum())          # Eq. 9.19
    np.testing.assert_allclose(iones_indirect(k_A, c_amb, E_ind, E_L, k_ind=k_ind), expected, rtol=EXACT)
    l = np.array([[0, 1, 0], [1, 0, 0], [0, -1, 0]], dtype=float)
    n_bent = np.array([0.0, 1.0, 0.0])
    cos = bent_cosine(l, n_bent)
    np.testing.assert_array_equal(cos, [1.0, 0.0, 0.0])                   # clamped at 0
    expected = k_A * c_amb / np.pi * (E_ind + k_ind * 4.0)                # Eq. 9.20
    np.testing.assert_allclose(iones_indirect(k_A, c_amb, E_ind, E_L, k_ind=k_ind, cos_theta=cos),
                               expected, rtol=EXACT)
    # lights all along the bent normal: Eq. 9.20 is Eq. 9.19
    ones = bent_cosine(np.tile(n_bent, (3, 1)), n_bent)
    np.testing.assert_allclose(iones_indirect(k_A, c_amb, E_ind, E_L, k_ind=k_ind, cos_theta=ones),
                               iones_indirect(k_A, c_amb, E_ind, E_L, k_ind=k_ind), rtol=EXACT)


def test_iones_per_pixel_shapes():
    H, W, n = 4, 5, 2
    rng = np.random.default_rng(0)
    k_A = rng.uniform(size=(H, W))
    n_bent = rng.normal(size=(H, W, 3))
    l = np.array([[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    cos = bent_cosine(l, n_bent)
    assert cos.shape == (n, H, W)
    unit = n_bent / np.linalg.norm(n_bent, axis=-1, keepdims=True)
    np.testing.assert_allclose(cos[1], np.maximum(unit @ (l[1] / np.sqrt(2)), 0), rtol=EXACT)
    E_L = np.array([[1.0, 1.0, 1.0], [0.5, 0.2, 0.0]]).reshape(n, 1, 1, 3)   # RGB lights
    out = iones_indirect(k_A[..., None], [0.8, 0.8, 0.8], np.pi, E_L, k_ind=0.5, cos_theta=cos[..., None])
    assert out.shape == (H, W, 3)
    loop = np.zeros((H, W, 3))
    for i in range(H):
        for j in range(W):
            s = sum(E_L[k, 0, 0] * cos[k, i, j] for k in range(n))
            loop[i, j] = k_A[i, j] * 0.8 / np.pi * (np.pi + 0.5 * s)
    np.testing.assert_allclose(out, loop, rtol=EXACT)
    per_light_l = np.broadcast_to(l[:, None, None, :], (n, H, W, 3))       # one l per light and pixel
    np.testing.assert_allclose(bent_cosine(per_light_l, n_bent), cos, rtol=EXACT)


# ----------------------------------------------------------------------------- bent normals
def test_linear_sky_irradiance_by_quadrature():
    for up in [(0, 1, 0), (1, 0, 0), (1, 2, -0.5)]:
        sky = LinearSky(1.0, -0.7, up=up)
        # the surface's normal is y: E = integral of L cos theta over the y > 0 hemisphere
        q = sphere_quadrature(lambda w: (sky.radiance(w) * w[:, 1])[:, None])[0]
        assert sky.irradiance([0.0, 1.0, 0.0]) == pytest.approx(q, rel=QUADRATURE)


def test_crease_bent_normal_closed_form_by_quadrature():
    """b = integral over the open directions (omega_x >= -c) of omega cos theta: the closed
    form of docs/shading.md against quadrature; the same mask gives k_A (DESIGN.md)."""
    for c in C_VALUES:
        q = sphere_quadrature(lambda w: np.concatenate([w * w[:, 1:2], w[:, 1:2] / np.pi], axis=1)
                              * (w[:, :1] >= -c))
        np.testing.assert_allclose(crease_bent_normal(c), q[:3], atol=20 * QUADRATURE)
        assert q[3] == pytest.approx(crease_cosine_ao(c), abs=20 * QUADRATURE)


def test_crease_bent_normal_against_ground_truth(crease):
    """The ray-traced bent normal's tilt from the normal, over independent seeds: a t-test
    on the mean tilt against the closed form."""
    a = C_VALUES * R
    points = np.stack([a, np.zeros_like(a), np.zeros_like(a)], axis=1)
    normals = np.tile([0.0, 1.0, 0.0], (len(a), 1))
    runs = 16
    tilt = np.array([
        np.arctan2(*vo.ambient_occlusion(crease, points, normals, rays=512, max_distance=R,
                                         seed=s, bent_normals=True).bent_normal[:, :2].T)
        for s in range(runs)])                                               # (runs, points)
    b = crease_bent_normal(C_VALUES)
    exact = np.arctan2(b[:, 0], b[:, 1])
    assert np.all(exact > 0)                                                 # away from the wall
    t = (tilt.mean(axis=0) - exact) / (tilt.std(axis=0, ddof=1) / np.sqrt(runs))
    assert np.all(np.abs(t) < t_threshold(runs - 1, tests=len(C_VALUES))), t


def test_bent_normal_lookup_on_the_crease():
    """Against the exact shading c_amb / pi * integral of v L cos = c_amb / pi (pi L_0 k_A + L_1 u.b)
    (docs/shading.md): for a gradient across the wall the bent normal is the better lookup;
    for a sky gradient along the normal it is not."""
    k_A, b = crease_cosine_ao(C_VALUES), crease_bent_normal(C_VALUES)
    n_bent = b / np.linalg.norm(b, axis=1, keepdims=True)
    n = np.tile([0.0, 1.0, 0.0], (len(C_VALUES), 1))
    c_amb = 0.8
    errors = {}
    for name, up in [("across", (1, 0, 0)), ("along", (0, 1, 0))]:
        sky = LinearSky(1.0, 1.0, up=up)
        exact = c_amb / np.pi * (np.pi * sky.L_0 * k_A + sky.L_1 * b @ np.array(sky.up))
        bent = bent_normal_lookup(k_A, c_amb, n_bent, environment=sky)
        geometric = bent_normal_lookup(k_A, c_amb, n, environment=sky)
        errors[name] = (np.abs(bent - exact), np.abs(geometric - exact))
    assert np.all(errors["across"][0] < errors["across"][1])
    assert np.all(errors["along"][0] > errors["along"][1])
    # a constant environment: the lookup is exact whatever the normal (k_A is exact there)
    const = LinearSky(2.0, 0.0)
    np.testing.assert_allclose(bent_normal_lookup(k_A, c_amb, n_bent, environment=const),
                               c_amb * 2.0 * k_A, rtol=EXACT)
    # a plain callable works as the environment
    np.testing.assert_allclose(bent_normal_lookup(k_A, c_amb, n_bent, environment=const.irradiance),
                               c_amb * 2.0 * k_A, rtol=EXACT)


# ----------------------------------------------------------------------------- dtypes
@pytest.mark.parametrize("func,args", [
    (ambient, (0.5, [0.8, 0.6, 0.4])),
    (stewart_langer, (0.5, 0.5)),
    (multibounce_jimenez, (0.5, 0.5)),
])
def test_float32_in_float32_out(func, args):
    k32 = np.linspace(0, 1, 7, dtype=np.float32)[:, None]
    out = func(k32, *args[1:])
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, func(k32.astype(np.float64), *args[1:]), rtol=1e-6)
    assert func(k32.astype(np.float64), *args[1:]).dtype == np.float64
    assert np.asarray(func(*args)).dtype == np.float64           # Python scalars: float64


def test_float32_iones_and_lookup():
    k32 = np.float32([0.25, 0.75])
    assert iones_indirect(k32, 0.5, 1.0, [1.0], k_ind=0.5).dtype == np.float32
    assert bent_cosine(np.float32([[0, 1, 0]]), np.float32([[0, 1, 0]])).dtype == np.float32
    assert bent_normal_lookup(k32, 0.5, np.float32([[0, 1, 0]]), environment=LinearSky(1, 0)).dtype == np.float32


# ----------------------------------------------------------------------------- validation
@pytest.mark.parametrize("call,match", [
    (lambda: ambient(1.5, 0.5), "k_A must be in \\[0, 1\\]"),
    (lambda: ambient(-0.1, 0.5), "k_A must be in \\[0, 1\\]"),
    (lambda: ambient(0.5, [0.5, -0.1, 0.2]), "c_amb must be >= 0"),
    (lambda: ambient(0.5, 0.5, L_A=-1.0), "L_A must be >= 0"),
    (lambda: ambient(np.nan, 0.5), "k_A must be finite"),
    (lambda: ambient("a", 0.5), "k_A must be a numeric array"),
    (lambda: stewart_langer(0.5, 1.2), "c_amb must be in \\[0, 1\\]"),
    (lambda: stewart_langer(2.0, 0.5), "k_A must be in"),
    (lambda: multibounce_jimenez(0.5, 1.5), "albedo must be in \\[0, 1\\]"),
    (lambda: multibounce_jimenez(0.5, np.inf), "albedo must be finite"),
    (lambda: iones_indirect(0.5, 0.5, 1.0, [1.0], k_ind=1.5), "k_ind must be a number in \\[0, 1\\]"),
    (lambda: iones_indirect(0.5, 0.5, -1.0, [1.0], k_ind=0.5), "E_ind must be >= 0"),
    (lambda: iones_indirect(0.5, 0.5, 1.0, [-1.0], k_ind=0.5), "E_L must be >= 0"),
    (lambda: iones_indirect(0.5, 0.5, 1.0, 1.0, k_ind=0.5), "E_L must have the lights on its first axis"),
    (lambda: iones_indirect(0.5, 0.5, 1.0, [1.0], k_ind=0.5, cos_theta=[1.5]), "cos_theta must be in"),
    (lambda: bent_cosine([[0, 0, 0]], [0, 1, 0]), "l holds 1 zero-length"),
    (lambda: bent_cosine([[0, 1, 0]], [0, 1]), "n_bent must have a last axis of 3"),
    (lambda: bent_cosine([0, 1, 0], [0, 1, 0]), "l must have shape \\(n, 3\\)"),
    (lambda: LinearSky(0.5, 1.0), "L_0 must be >= \\|L_1\\|"),
    (lambda: LinearSky(1.0, 0.0, up=(0, 0, 0)), "up must have a length"),
    (lambda: bent_normal_lookup(0.5, 0.5, [0, 1, 0], environment=3), "environment must have"),
    (lambda: bent_normal_lookup(0.5, 0.5, [0, 1, 0], environment=lambda n: -1.0),
     "environment\\(n_bent\\) must be >= 0"),
])
def test_validation_names_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()
