"""vobscure.trees: shells (closed forms, fits) and the Hegeman 2006 canopy model.

Deterministic code is checked against closed forms and independent computations (dense
sampling along rays, numerical integration of the cap, a generic optimizer for the minimal
sphere); the Poisson argument behind ``predict_density`` by a Monte Carlo leaf cloud, with
a t-test against its own standard error.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from conftest import FALSE_FAILURE, t_threshold
from vobscure.trees import (
    Ellipsoid,
    MultiShell,
    Sphere,
    bounding_ellipsoid,
    bounding_sphere,
    canopy_visibility,
    chord_length,
    fit_density,
    fit_reeves_blau,
    optical_depth,
    predict_density,
    reeves_blau,
    shells_from_points,
)

#: Closed forms evaluated in float64 (a few roundings).
EXACT = 1e-12
#: Dense sampling along a ray: step 1e-5 of the ray's extent.
SAMPLED = 2e-4
#: Numerical quadrature (scipy.integrate, default tolerances).
QUAD = 1e-7
#: float32 output against the float64 computation.
FLOAT32 = 2e-6
#: A noise-free fit recovers the density to this relative error.
FIT_EXACT = 1e-9
#: Reeves-Blau's k is fitted by Brent to 1e-6 in log k: a noise-free fit recovers k to
#: about that relative error (2e-6 leaves room for the bracket's end).
FIT_K = 2e-6


def _rotation(seed=0):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# ----------------------------------------------------------------------------- shells: validation
@pytest.mark.parametrize("radius", [0.0, -1.0, np.nan, np.inf])
def test_sphere_rejects_bad_radius(radius):
    with pytest.raises(ValueError, match="radius"):
        Sphere((0, 0, 0), radius)


@pytest.mark.parametrize("radii, match", [((1, 1, 0), "radii"), ((1, -2, 1), "radii"),
                                          ((1, np.nan, 1), "radii"), ((1, 1), "radii")])
def test_ellipsoid_rejects_bad_radii(radii, match):
    with pytest.raises(ValueError, match=match):
        Ellipsoid((0, 0, 0), radii)


def test_ellipsoid_rejects_non_orthonormal_rotation():
    with pytest.raises(ValueError, match="rotation"):
        Ellipsoid((0, 0, 0), (1, 2, 3), np.diag([1.0, 1.0, 1.1]))
    with pytest.raises(ValueError, match="center"):
        Ellipsoid((0, np.nan, 0), (1, 2, 3))


def test_shells_are_frozen():
    s = Sphere((0, 0, 0), 1.0)
    with pytest.raises(AttributeError):
        s.radius = 2.0
    with pytest.raises(ValueError):
        s.center[0] = 1.0


# ----------------------------------------------------------------------------- shells: closed forms
def test_sphere_chord_closed_forms():
    R, c = 1.5, np.array([1.0, -2.0, 0.5])
    s = Sphere(c, R)
    o = np.array([c + [-10, 0, 0],          # through the centre: 2R
                  c + [-10, R, 0],          # tangent: 0
                  c + [-10, 2 * R, 0],      # miss: 0
                  c,                        # from the centre: R
                  c + [10, 0, 0],           # pointing away: 0
                  c + [0, 0.6, 0],          # inside, off-centre: exit
                  c + [-10, 0.9, 0]])       # off-centre chord 2 sqrt(R^2 - p^2)
    d = np.array([[1, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, 3.0], [1, 0, 0], [1, 0, 0], [2, 0, 0]])
    want = [2 * R, 0, 0, R, 0, np.sqrt(R**2 - 0.36), 2 * np.sqrt(R**2 - 0.81)]
    np.testing.assert_allclose(s.chord_length(o, d), want, rtol=EXACT, atol=EXACT)
    np.testing.assert_allclose(chord_length(s, o, d), want, rtol=EXACT, atol=EXACT)


def test_chord_of_a_distant_origin_keeps_its_precision():
    s = Sphere((0, 0, 0), 1.0)
    got = s.chord_length([[-1e8, 0.6, 0]], [[1, 0, 0]])
    np.testing.assert_allclose(got, [1.6], rtol=1e-9)


def test_chord_exit_near_the_surface_from_inside():
    s = Sphere((0, 0, 0), 1.0)
    eps = 1e-9
    np.testing.assert_allclose(s.chord_length([[1 - eps, 0, 0]], [[1, 0, 0]]), [eps], rtol=1e-6)


def _sampled_chord(shell, o, d, t_max, steps=100_001):
    t = np.linspace(0.0, t_max, steps)
    inside = shell.contains(o + t[:, None] * _unit(d))
    return inside.mean() * t_max


def test_ellipsoid_chord_against_dense_sampling():
    rng = np.random.default_rng(3)
    e = Ellipsoid((0.3, -0.2, 1.0), (2.0, 0.7, 1.3), _rotation(1))
    o = np.vstack([rng.uniform(-3, 3, (6, 3)) + e.center, e.center + [0.1, 0.1, 0.1]])
    d = np.vstack([e.center - o[:6] + rng.normal(scale=0.5, size=(6, 3)), rng.normal(size=(1, 3))])
    got = e.chord_length(o, d)
    t_max = 12.0
    want = [_sampled_chord(e, oi, di, t_max) for oi, di in zip(o, d)]
    assert np.count_nonzero(got) >= 5
    np.testing.assert_allclose(got, want, atol=SAMPLED * t_max)


def test_axis_aligned_ellipsoid_chords_are_its_diameters():
    e = Ellipsoid((0, 0, 0), (3.0, 1.0, 0.5), _rotation(2))
    o = -10 * e.rotation.T          # rows: -10 along each axis
    np.testing.assert_allclose(e.chord_length(o, e.rotation.T), 2 * e.radii, rtol=EXACT)


def test_sphere_shaped_ellipsoid_matches_sphere():
    rng = np.random.default_rng(0)
    s = Sphere((1, 2, 3), 1.7)
    e = Ellipsoid((1, 2, 3), (1.7, 1.7, 1.7), _rotation(5))
    x = rng.normal(size=(100, 3)) + s.center
    n = rng.normal(size=(100, 3))
    np.testing.assert_allclose(e.chord_length(x, n), s.chord_length(x, n), rtol=EXACT, atol=EXACT)
    assert np.array_equal(e.contains(x), s.contains(x))
    assert e.volume == pytest.approx(s.volume, rel=EXACT)


def test_unit_maps():
    e = Ellipsoid((1, 0, 0), (2.0, 1.0, 0.5), _rotation(3))
    surface = e.center + _unit([[1, 2, 3], [-1, 0, 0], [0, 0, 1]]) @ (e.rotation * e.radii).T
    np.testing.assert_allclose(np.linalg.norm(e.to_unit(surface), axis=1), 1.0, rtol=EXACT)
    # a plane through x with normal n maps to the plane through to_unit(x) with the mapped normal
    rng = np.random.default_rng(0)
    x, n = rng.normal(size=(1, 3)), _unit(rng.normal(size=(1, 3)))
    t1, t2 = np.cross(n, [[1.0, 0, 0]]), np.cross(n, [[0.0, 1, 0]])
    in_plane = e.to_unit(np.vstack([x + t1, x + t2])) - e.to_unit(x)
    n_unit = e.normals_to_unit(n)
    np.testing.assert_allclose(in_plane @ n_unit[0], 0.0, atol=EXACT)
    np.testing.assert_allclose(np.linalg.norm(n_unit, axis=1), 1.0, rtol=EXACT)


# ----------------------------------------------------------------------------- shells: fits
@pytest.mark.parametrize("cloud", ["gaussian", "shell"])
def test_bounding_sphere_is_minimal(cloud):
    rng = np.random.default_rng(0)
    if cloud == "gaussian":
        P = rng.normal(size=(3000, 3)) * [3, 1, 0.5]
    else:                                   # many points near the sphere: no slack goes unnoticed
        P = _unit(rng.normal(size=(3000, 3))) * rng.uniform(0.97, 1.0, (3000, 1)) * [1.0, 0.9, 0.95]
    s = bounding_sphere(P)
    assert s.contains(P).all()
    # optimality certificate (independent of the algorithm): a ball enclosing P is the
    # smallest one iff its centre lies in the convex hull of the points on its boundary
    dist = np.linalg.norm(P - s.center, axis=1)
    support = P[dist >= s.radius * (1 - 1e-9)]
    assert 2 <= len(support) <= 4
    weight = 1e3 * s.radius
    lam, residual = optimize.nnls(np.vstack([support.T, weight * np.ones(len(support))]),
                                  np.r_[s.center, weight])
    assert residual < 1e-9 * s.radius, (lam, residual)


def test_bounding_sphere_closed_forms():
    s = bounding_sphere([[0, 0, 0], [2, 0, 0]])                 # two points: the diameter
    np.testing.assert_allclose(s.center, [1, 0, 0], atol=EXACT)
    assert s.radius == pytest.approx(1.0, rel=1e-9)
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    s = bounding_sphere(np.vstack([tet, 0.1 * tet]))            # regular tetrahedron: circumsphere
    np.testing.assert_allclose(s.center, 0, atol=1e-9)
    assert s.radius == pytest.approx(np.sqrt(3), rel=1e-9)
    s = bounding_sphere([[0, 0, 0], [1, 0, 0], [0.5, 0.1, 0]])  # obtuse triangle: its long side
    assert s.radius == pytest.approx(0.5, rel=1e-9)


@pytest.mark.parametrize("points, match", [(np.zeros((0, 3)), "at least"),
                                           ([[1, 2, 3]] * 3, "distinct"),
                                           ([[0, 0, np.nan], [1, 0, 0]], "finite")])
def test_bounding_sphere_errors(points, match):
    with pytest.raises(ValueError, match=match):
        bounding_sphere(points)


def test_bounding_ellipsoid_recovers_an_ellipsoid():
    rng = np.random.default_rng(1)
    truth = Ellipsoid((1, -2, 0.5), (3.0, 1.5, 0.7), _rotation(7))
    u = _unit(rng.normal(size=(2000, 3)))
    P = truth.center + (u * truth.radii) @ truth.rotation.T    # points on its surface
    e = bounding_ellipsoid(P, tol=1e-7)
    assert e.contains(P).all()
    np.testing.assert_allclose(np.sort(e.radii), np.sort(truth.radii), rtol=1e-5)
    np.testing.assert_allclose(e.center, truth.center, atol=1e-5)
    assert e.volume == pytest.approx(truth.volume, rel=1e-5)


def test_bounding_ellipsoid_of_a_cloud_contains_it():
    P = np.random.default_rng(2).normal(size=(5000, 3)) * [3, 1, 0.5]
    e = bounding_ellipsoid(P)
    assert e.contains(P).all()
    assert e.volume < bounding_sphere(P).volume


@pytest.mark.parametrize("points, match", [
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "at least 4"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 1]], "finite"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.2, 0]], "coplanar"),
    ([[t, 2 * t, -t] for t in range(6)], "collinear"),
])
def test_bounding_ellipsoid_errors(points, match):
    with pytest.raises(ValueError, match=match):
        bounding_ellipsoid(points)


def test_multishell_assigns_the_closest_centre():
    m = MultiShell([Sphere((0, 0, 0), 5.0), Ellipsoid((4, 0, 0), (1, 1, 1))])
    # (3, 0, 0) lies inside both shells: it belongs to the closer centre (Sec. 5)
    assert m.assign([[3, 0, 0], [1.9, 0, 0], [2.1, 0, 0]]).tolist() == [1, 0, 1]
    with pytest.raises(ValueError, match="shells"):
        MultiShell([])
    with pytest.raises(ValueError, match=r"shells\[1\]"):
        MultiShell([Sphere((0, 0, 0), 1.0), "tree"])


@pytest.mark.parametrize("kind", ["sphere", "ellipsoid"])
def test_shells_from_points(kind):
    rng = np.random.default_rng(4)
    centres = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0]], float)
    P = np.vstack([c + rng.normal(size=(200, 3)) for c in centres])
    m = shells_from_points(P, 3, kind=kind, seed=1)
    assert len(m) == 3 and all(isinstance(s, Sphere if kind == "sphere" else Ellipsoid) for s in m)
    assert all(np.min(np.linalg.norm(centres - s.center, axis=1)) < 1.0 for s in m)
    again = shells_from_points(P, 3, kind=kind, seed=1)
    assert np.array_equal(m.centers, again.centers)
    with pytest.raises(ValueError, match="kind"):
        shells_from_points(P, 3, kind="box")
    with pytest.raises(ValueError, match="k must"):
        shells_from_points(P[:2], 3)


# ----------------------------------------------------------------------------- canopy: Eqs. 4-6
def _brute_cap_volume(h, R):
    """V_cap by integrating disk areas pi (R^2 - z^2) over the cap's heights."""
    return integrate.quad(lambda z: np.pi * (R * R - z * z), R - h, R)[0]


@pytest.mark.parametrize("h_frac", [0.0, 1e-3, 0.3, 1.0, 1.7, 2.0])
def test_eq4_cap_volume_against_integration(h_frac):
    R = 1.3
    h = h_frac * R
    s = Sphere((0, 0, 0), R)
    # the point on the axis, where d = 0 and f = 1 (for h > 0): optical depth = V_cap
    x = np.array([[0, R - h, 0]])
    tau = optical_depth(x, [[0, 1, 0]], s)
    np.testing.assert_allclose(tau, [_brute_cap_volume(h, R)], rtol=QUAD, atol=QUAD * R**3)


def test_eq5_off_centre_factor():
    R, h, d = 1.0, 0.4, 0.3
    s = Sphere((0, 0, 0), R)
    V_cap = np.pi * h**2 * (3 * R - h) / 3
    tau = optical_depth([[d, R - h, 0]], [[0, 1, 0]], s)
    np.testing.assert_allclose(tau, [h**2 / (h**2 + d**2) * V_cap], rtol=EXACT)
    # limits: f -> 1 as d -> 0, f -> 0 as d -> inf; f = 1 at h = d = 0 (V = 1 either way)
    taus = optical_depth([[1e-12, R - h, 0], [1e6, R - h, 0], [0, R, 0]], [[0, 1, 0]] * 3, s)
    np.testing.assert_allclose(taus[0], V_cap, rtol=EXACT)
    assert 0 <= taus[1] < 1e-12 * V_cap
    assert taus[2] == 0


def test_eq6_closed_forms():
    s = Sphere((0, 0, 0), 2.0)
    a = 0.05
    x = [[0, 0, 0], [0, 2, 0], [0, 2, 0], [0, 3, 0], [0, 3, 0], [3, -3, 0], [0, -3, 0]]
    n = [[1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 1, 0], [0, -1, 0], [1, 0, 0], [1, 0, 0]]
    V = canopy_visibility(x, n, s, density=a)
    R = 2.0
    full = 4 / 3 * np.pi * R**3
    want = [np.exp(-a * 2 / 3 * np.pi * R**3),     # centre: h = R, f = 1
            1.0,                                   # on the surface facing out: h = 0
            np.exp(-a * full),                     # on the surface facing in: h = 2R, d = 0
            1.0,                                   # outside, facing away
            np.exp(-a * full),                     # outside, facing the centre: h clamps to 2R, d = 0
            1.0,                                   # outside, plane misses the shell: h = 0
            np.exp(-a * 4 / 13 * full / 2)]        # outside, plane through the centre: h = R, d = 3
    np.testing.assert_allclose(V, want, rtol=EXACT)


def test_h_limits_are_continuous():
    s = Sphere((0, 0, 0), 1.0)
    eps = np.array([1e-3, 1e-6, 1e-9, 0.0])
    n = np.tile([[0, 1.0, 0]], (4, 1))
    near_0 = canopy_visibility(np.c_[0 * eps, 1 - eps, 0 * eps], n, s, density=2.0)
    near_2R = canopy_visibility(np.c_[0 * eps, -1 + eps, 0 * eps], n, s, density=2.0)
    assert np.all(np.diff(near_0) >= 0) and near_0[-1] == 1.0
    np.testing.assert_allclose(near_0[:-1], np.exp(-2 * np.pi * eps[:-1] ** 2 * (3 - eps[:-1]) / 3), rtol=1e-9)
    assert np.all(np.diff(near_2R) <= 0)
    np.testing.assert_allclose(near_2R[-1], np.exp(-2 * 4 / 3 * np.pi), rtol=EXACT)
    np.testing.assert_allclose(near_2R[:-1], near_2R[-1], rtol=1e-2)


def test_density_zero_is_exactly_one_and_huge_is_zero():
    rng = np.random.default_rng(0)
    s = Ellipsoid((0, 0, 0), (1e-3, 2e5, 7.0), _rotation(1))
    x = (rng.normal(size=(500, 3)) * [1e-3, 1e5, 3] * 0.5) @ s.rotation.T
    n = rng.normal(size=(500, 3))
    assert np.all(canopy_visibility(x, n, s, density=0.0) == 1.0)
    V = canopy_visibility(x, n, s, density=1e308)       # overflows to inf: warnings are errors here
    assert np.all(np.isfinite(V)) and np.all((V == 0) | (V == 1))
    assert np.mean(V == 0) > 0.5
    V_tiny = canopy_visibility(x, n, s, density=1e-300)
    assert np.all(np.isfinite(V_tiny)) and np.all(V_tiny <= 1)


def test_sphere_shaped_ellipsoid_gives_the_sphere_visibility():
    rng = np.random.default_rng(1)
    s = Sphere((0.5, 1, -1), 2.5)
    e = Ellipsoid((0.5, 1, -1), (2.5, 2.5, 2.5), _rotation(9))
    x = s.center + rng.normal(size=(1000, 3)) * 2
    n = rng.normal(size=(1000, 3))
    np.testing.assert_allclose(canopy_visibility(x, n, e, density=0.3), canopy_visibility(x, n, s, density=0.3),
                               rtol=EXACT, atol=EXACT)


def test_ellipsoid_density_is_per_world_volume():
    # a point at an ellipsoid's centre, normal along an axis: the half-ellipsoid, f = 1
    e = Ellipsoid((1, 1, 1), (3.0, 1.0, 0.5), _rotation(4))
    for axis in range(3):
        V = canopy_visibility(e.center, e.rotation[:, axis], e, density=0.7)
        np.testing.assert_allclose(V, [np.exp(-0.7 * e.volume / 2)], rtol=EXACT)


def test_ellipsoid_model_is_the_sphere_model_after_the_affine_map():
    rng = np.random.default_rng(2)
    e = Ellipsoid((0, 1, 0), (2.0, 1.0, 0.6), _rotation(6))
    x = e.center + rng.normal(size=(50, 3))
    n = _unit(rng.normal(size=(50, 3)))
    unit = Sphere((0, 0, 0), 1.0)
    want = canopy_visibility(e.to_unit(x), e.normals_to_unit(n), unit, density=0.4 * np.prod(e.radii))
    np.testing.assert_allclose(canopy_visibility(x, n, e, density=0.4), want, rtol=EXACT)


def test_multishell_uses_each_points_shell():
    a, b = Sphere((0, 0, 0), 1.0), Ellipsoid((5, 0, 0), (2.0, 1.0, 1.0))
    m = MultiShell([a, b])
    rng = np.random.default_rng(3)
    x = np.vstack([rng.normal(size=(20, 3)) * 0.5, rng.normal(size=(20, 3)) * 0.5 + [5, 0, 0]])
    n = rng.normal(size=(40, 3))
    V = canopy_visibility(x, n, m, density=1.0)
    np.testing.assert_allclose(V[:20], canopy_visibility(x[:20], n[:20], a, density=1.0), rtol=EXACT)
    np.testing.assert_allclose(V[20:], canopy_visibility(x[20:], n[20:], b, density=1.0), rtol=EXACT)


def test_float32_in_float32_out():
    rng = np.random.default_rng(4)
    s = Ellipsoid((0, 0, 0), (2.0, 1.0, 1.5), _rotation(2))
    x, n = rng.normal(size=(300, 3)), rng.normal(size=(300, 3))
    V64 = canopy_visibility(x, n, s, density=0.5)
    V32 = canopy_visibility(x.astype(np.float32), n.astype(np.float32), s, density=0.5)
    assert V64.dtype == np.float64 and V32.dtype == np.float32
    np.testing.assert_allclose(V32, V64, rtol=FLOAT32, atol=FLOAT32)
    assert canopy_visibility(x.astype(np.float32), n, s, density=0.5).dtype == np.float64
    assert reeves_blau(x.astype(np.float32), s, k=1.0).dtype == np.float32


def test_chunked_equals_unchunked_and_memory_is_bounded():
    rng = np.random.default_rng(5)
    s = MultiShell([Sphere((0, 0, 0), 1.0), Ellipsoid((2, 0, 0), (1.0, 0.5, 0.8))])
    n_pts = 400_000
    x = (rng.normal(size=(n_pts, 3)) * 0.8).astype(np.float32)
    n = rng.normal(size=(n_pts, 3)).astype(np.float32)
    whole = canopy_visibility(x, n, s, density=1.3, chunk=n_pts)
    chunk = 7_777                                        # not a divisor of n_pts
    tracemalloc.start()
    try:
        chunked = canopy_visibility(x, n, s, density=1.3, chunk=chunk)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert np.array_equal(chunked, whole)
    # the output plus O(chunk) temporaries (at most ~60 float64 per point of a chunk), far
    # below the O(n) float64 temporaries of one pass (the (n, 3) arrays alone are 9.6 MB)
    assert peak < chunked.nbytes + 60 * 8 * chunk, peak


@pytest.mark.parametrize("kwargs, match", [
    ({"density": -1.0}, "density"), ({"density": np.nan}, "density"), ({"density": np.inf}, "density"),
    ({"density": 1.0, "chunk": 0}, "chunk"),
])
def test_canopy_validation_of_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        canopy_visibility([[0, 0, 0]], [[0, 1, 0]], Sphere((0, 0, 0), 1.0), **kwargs)


@pytest.mark.parametrize("points, normals, match", [
    ([[0, 0, np.nan]], [[0, 1, 0]], "points"),
    ([[0, 0, 0]], [[0, 0, 0]], "normals"),
    ([[0, 0, 0]], [[0, np.inf, 0]], "normals"),
    ([[0, 0, 0], [1, 0, 0]], [[0, 1, 0]], "normals"),
    ([[0, 0]], [[0, 1, 0]], "points"),
    ([["a", "b", "c"]], [[0, 1, 0]], "points"),
])
def test_canopy_validation_of_inputs(points, normals, match):
    with pytest.raises(ValueError, match=match):
        canopy_visibility(points, normals, Sphere((0, 0, 0), 1.0), density=1.0)


def test_canopy_rejects_a_non_shell():
    with pytest.raises(ValueError, match="shell"):
        canopy_visibility([[0, 0, 0]], [[0, 1, 0]], (0, 0, 0, 1), density=1.0)


@pytest.mark.parametrize("model", ["canopy", "poisson"])
def test_leaf_models_count_the_bad_normals(model):
    """Both leaf models reject zero-length and non-finite normals, counting them: per row
    for the canopy model, per value for the Poisson cloud."""
    from vobscure.trees import poisson_visibility

    def run(normals):
        x, s = np.zeros((3, 3)), Sphere((0, 0, 0), 1.0)
        if model == "canopy":
            return canopy_visibility(x, normals, s, density=1.0)
        return poisson_visibility(x, normals, s, extinction=1.0)

    with pytest.raises(ValueError, match=r"normals hold 2 zero-length vector\(s\)"):
        run([[0, 0, 0], [0, 1, 0], [0, 0, 0]])
    counted = "1 NaN or inf row" if model == "canopy" else "2 NaN or inf value"
    with pytest.raises(ValueError, match=f"normals must be finite; they hold {counted}"):
        run([[np.nan, np.inf, 0], [0, 1, 0], [0, 1, 0]])


# ----------------------------------------------------------------------------- Reeves-Blau
def test_reeves_blau_closed_forms():
    s = Sphere((1, 0, 0), 2.0)
    V = reeves_blau([[1, 0, 0], [2, 0, 0], [3, 0, 0], [9, 0, 0]], s, k=0.5)
    np.testing.assert_allclose(V, np.exp(-0.5 * np.array([2.0, 1.0, 0.0, 0.0])), rtol=EXACT)
    e = Ellipsoid((1, 0, 0), (2.0, 2.0, 2.0), _rotation(0))
    np.testing.assert_allclose(reeves_blau([[1.5, 0.5, 0]], e, k=0.5), reeves_blau([[1.5, 0.5, 0]], s, k=0.5),
                               rtol=EXACT)
    # ellipsoid: the depth of the volume-equivalent sphere's frame, R_eq (1 - |x'|)
    e = Ellipsoid((0, 0, 0), (4.0, 1.0, 2.0))
    np.testing.assert_allclose(reeves_blau([[2.0, 0, 0]], e, k=1.0), [np.exp(-2.0 * 0.5)], rtol=EXACT)
    with pytest.raises(ValueError, match="k"):
        reeves_blau([[0, 0, 0]], s, k=-1.0)


# ----------------------------------------------------------------------------- fitting and predicting
@pytest.fixture(scope="module")
def fit_data():
    rng = np.random.default_rng(6)
    e = Ellipsoid((0, 2, 0), (2.0, 1.5, 1.0), _rotation(3))
    x = e.center + (rng.uniform(-1, 1, (400, 3)) * e.radii * 0.6) @ e.rotation.T
    n = rng.normal(size=(400, 3))
    return e, x, n


@pytest.mark.parametrize("density", [1e-3, 0.4, 5.0])
def test_fit_density_recovers_a_noise_free_density(fit_data, density):
    e, x, n = fit_data
    V = canopy_visibility(x, n, e, density=density)
    assert fit_density(x, n, e, V) == pytest.approx(density, rel=FIT_EXACT)


def test_fit_density_zero_and_nan_and_weights(fit_data):
    e, x, n = fit_data
    assert fit_density(x, n, e, np.ones(len(x))) == 0.0
    V = canopy_visibility(x, n, e, density=0.4)
    V_bad = V.copy()
    V_bad[::3] = np.nan
    assert fit_density(x, n, e, V_bad) == pytest.approx(0.4, rel=FIT_EXACT)
    V_bad = V.copy()
    V_bad[:10] = 0.0                                     # wrong values, weighted out
    w = np.ones(len(x))
    w[:10] = 0
    assert fit_density(x, n, e, V_bad, weights=w) == pytest.approx(0.4, rel=FIT_EXACT)


def test_fit_density_with_noise_is_within_its_standard_error(fit_data):
    e, x, n = fit_data
    a_true, sigma, trials = 0.4, 0.02, 20
    tau = optical_depth(x, n, e)
    J = -tau * np.exp(-a_true * tau)
    se = sigma / np.sqrt(np.sum(J * J))                   # linearized least-squares standard error
    rng = np.random.default_rng(7)
    fits = np.array([fit_density(x, n, e, canopy_visibility(x, n, e, density=a_true)
                                 + rng.normal(scale=sigma, size=len(x))) for _ in range(trials)])
    z = (fits - a_true) / se
    limit = float(stats.norm.ppf(1 - FALSE_FAILURE / (2 * trials)))
    assert np.all(np.abs(z) < limit), z
    # and the spread matches the standard error (chi-square on trials degrees of freedom)
    chi2 = float(np.sum(z * z))
    assert stats.chi2.ppf(FALSE_FAILURE / 2, trials) < chi2 < stats.chi2.ppf(1 - FALSE_FAILURE / 2, trials)


def test_fit_density_errors(fit_data):
    e, x, n = fit_data
    with pytest.raises(ValueError, match="reference"):
        fit_density(x, n, e, np.ones(len(x) - 1))
    with pytest.raises(ValueError, match="inf"):
        fit_density(x, n, e, np.full(len(x), np.inf))
    with pytest.raises(ValueError, match="nothing to fit"):
        fit_density(x, n, e, np.full(len(x), np.nan))
    with pytest.raises(ValueError, match="weights"):
        fit_density(x, n, e, np.ones(len(x)), weights=-np.ones(len(x)))


def test_predict_density_formula_and_errors():
    s = Sphere((0, 0, 0), 2.0)
    sigma = 500 / s.volume * 0.02 / 2
    assert predict_density(500, 0.02, s) == pytest.approx(3 * sigma / (2 * np.pi * 4.0), rel=EXACT)
    e = Ellipsoid((0, 0, 0), (4.0, 2.0, 1.0))             # volume-equivalent radius 2
    assert predict_density(500, 0.02, e) == pytest.approx(predict_density(500, 0.02, s), rel=EXACT)
    for bad in ({"n_leaves": 0}, {"leaf_area": -1.0}, {"n_leaves": np.nan}):
        args = {"n_leaves": 500, "leaf_area": 0.02, **bad}
        with pytest.raises(ValueError, match=next(iter(bad))):
            predict_density(args["n_leaves"], args["leaf_area"], s)
    with pytest.raises(ValueError, match="shell"):
        predict_density(500, 0.02, MultiShell([s]))


def _cosine_directions(normal, count, rng):
    """Cosine-weighted directions about ``normal`` (Malley: disk samples lifted)."""
    r, phi = np.sqrt(rng.random(count)), 2 * np.pi * rng.random(count)
    local = np.c_[r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - r * r)]
    t = _unit(np.cross(normal, [1.0, 0, 0]) if abs(normal[0]) < 0.9 else np.cross(normal, [0, 1.0, 0]))
    b = np.cross(normal, t)
    return local @ np.array([t, b, normal])


def test_predict_density_matches_a_poisson_leaf_cloud_at_the_centre():
    """Random disk leaves in a sphere: the cosine-weighted transmittance at the centre is
    exp(-sigma R) exactly (for small leaves), and so is Eq. 6 with predict_density."""
    R, leaf_r = 1.0, 0.025
    A = np.pi * leaf_r**2
    sigma = 1.0 / R                                      # sigma R = 1: V about 0.37
    s = Sphere((0, 0, 0), R)
    n_leaves = 2 * sigma / A * s.volume                  # sigma = n A / 2
    exact = np.exp(-sigma * R)
    model = canopy_visibility([0, 0, 0], [0, 0, 1], s, density=predict_density(n_leaves, A, s))[0]
    assert model == pytest.approx(exact, rel=EXACT)

    rng = np.random.default_rng(11)
    groups, rays = 24, 256
    means = np.empty(groups)
    normal = np.array([0, 0, 1.0])
    for g in range(groups):
        count = rng.poisson(n_leaves)
        u = rng.random(count)                            # leaf centres uniform in the ball
        p = _unit(rng.normal(size=(count, 3))) * (R * np.cbrt(u))[:, None]
        m = _unit(rng.normal(size=(count, 3)))           # random leaf orientations
        w = _cosine_directions(normal, rays, rng)
        wm = w @ m.T                                     # (rays, leaves)
        pm = np.einsum("ij,ij->i", p, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = pm[None, :] / wm
        # |t w - p|^2 <= r^2 with t > 0: the ray from the centre crosses the disk
        dist2 = t * t - 2 * t * (w @ p.T) + np.einsum("ij,ij->i", p, p)[None, :]
        hit = (t > 0) & np.isfinite(t) & (dist2 <= leaf_r**2)
        means[g] = np.mean(~hit.any(axis=1))
    value, stderr = means.mean(), means.std(ddof=1) / np.sqrt(groups)
    limit = t_threshold(groups - 1)
    # the finite leaf size changes the exact value by O(leaf_r / R) at the boundary only
    assert abs(value - exact) < limit * stderr, (value, exact, stderr)


@pytest.mark.parametrize("density", [2.0, 8.0])
def test_fit_density_is_no_worse_than_a_grid_search_when_depths_span_decades(density):
    """Points at the shell's rim (normal outward, 1e-5 inside) have optical depths ~3e-10,
    so the log-density search spans 30 decades, most of it a plateau where every interior
    point reads 0: the fit must still find the interior minimum (a bounded search over the
    whole range lands on the plateau, density ~1e8, at these settings). A grid search over
    the whole range is the independent check."""
    from vobscure.trees import optical_depth

    rng = np.random.default_rng(1)
    s = Sphere((0, 0, 0), 1.0)
    x = np.vstack([rng.uniform(-0.6, 0.6, (100, 3)), np.tile([[0.0, 1 - 1e-5, 0.0]], (20, 1))])
    n = np.vstack([rng.normal(size=(100, 3)), np.tile([[0.0, 1.0, 0.0]], (20, 1))])
    tau = optical_depth(x, n, s)
    assert tau.min() < 1e-9 < 0.1 < tau.max()
    v = np.clip(np.exp(-density * tau) + rng.normal(0, 0.05, tau.shape), 0, 1)
    a = fit_density(x, n, s, v)

    def loss(d):
        return float(np.sum((np.exp(-d * tau) - v) ** 2))

    grid = np.exp(np.linspace(np.log(1e-3), np.log(1e12), 4001))
    assert loss(a) <= min(loss(d) for d in grid) * (1 + 1e-9)
    assert a == pytest.approx(density, rel=0.1)


def _points_with_optical_depths(tau):
    """Points of the unit sphere's equatorial plane at distance D from the centre, normal
    (0, 1, 0): h = R = 1, V_cap = 2 pi / 3 (Eq. 4), d = D, f = 1 / (1 + D^2) (Eq. 5), so
    tau = (2 pi / 3) / (1 + D^2) for D = sqrt(2 pi / (3 tau) - 1)."""
    D = np.sqrt(2 * np.pi / (3 * np.asarray(tau, float)) - 1)
    x = np.column_stack([D, np.zeros_like(D), np.zeros_like(D)])
    return x, np.tile([0.0, 1.0, 0.0], (len(D), 1))


def test_fit_density_finds_the_deeper_of_two_dips_decades_apart():
    """Two groups whose optical depths lie 47 decades apart, each fitted exactly by its own
    density: four points with tau_B = 5e-14 and reference 0.1 (exact at a_B = ln 10 / tau_B)
    and three with tau_A = 5e-61 and reference 0.9 (exact at a_A = ln(10 / 9) / tau_A). At
    a_B the A points read exp(-a_B tau_A) = 1 - 2e-47, so the loss is 3 (1 - 0.9)^2 = 0.03;
    at a_A the B points read 0, a loss of 4 (0.1)^2 = 0.04: the least-squares density is a_B.
    The range of log(density) is 130 wide here; a fixed count of grid points over it steps
    over the dip at a_B (its grid loss reads above the plateau's 0.04) and returns a_A."""
    s = Sphere((0, 0, 0), 1.0)
    tau_want = np.array([5e-14] * 4 + [5e-61] * 3)
    x, n = _points_with_optical_depths(tau_want)
    tau = optical_depth(x, n, s)
    np.testing.assert_allclose(tau, tau_want, rtol=EXACT)
    v = np.array([0.1] * 4 + [0.9] * 3)
    a_B = np.log(10.0) / tau[0]
    assert fit_density(x, n, s, v) == pytest.approx(a_B, rel=FIT_EXACT)


@pytest.mark.parametrize("k", [0.05, 2.5, 300.0])
def test_fit_reeves_blau_recovers_a_noise_free_k(k):
    """Depths from the closed form (a sphere: R - |x - c|), the reference exp(-k depth)
    written out here, not through reeves_blau."""
    rng = np.random.default_rng(4)
    s = Sphere((1.0, 2.0, 0.0), 2.0)
    r = 2.0 * rng.uniform(0, 1, 300) ** (1 / 3)
    x = s.center + r[:, None] * _unit(rng.normal(size=(300, 3)))
    depth = 2.0 - r
    assert fit_reeves_blau(x, s, np.exp(-k * depth)) == pytest.approx(k, rel=FIT_K)


def test_fit_reeves_blau_weights_and_a_noisy_reference():
    """Weights that zero out a corrupted half recover k from the clean half; with noise the
    fit is no worse than a dense grid over the search range (an independent minimizer)."""
    rng = np.random.default_rng(5)
    s = Sphere((0, 0, 0), 1.0)
    x = rng.uniform(-0.55, 0.55, (200, 3))
    depth = 1.0 - np.linalg.norm(x, axis=1)
    v = np.exp(-1.7 * depth)
    v_bad = v.copy()
    v_bad[::2] = 1.0
    w = np.ones(200)
    w[::2] = 0.0
    assert fit_reeves_blau(x, s, v_bad, weights=w) == pytest.approx(1.7, rel=FIT_K)
    noisy = np.clip(v + rng.normal(0, 0.05, 200), 0, 1)
    k = fit_reeves_blau(x, s, noisy)

    def loss(kk):
        return float(np.sum((np.exp(-kk * depth) - noisy) ** 2))

    grid = np.geomspace(1e-4, 1e4, 20001)
    assert loss(k) <= min(loss(g) for g in grid) * (1 + 1e-9)


def test_fit_reeves_blau_errors():
    s = Sphere((0, 0, 0), 1.0)
    x = np.zeros((3, 3))
    with pytest.raises(ValueError, match="reference"):
        fit_reeves_blau(x, s, np.ones(2))
    with pytest.raises(ValueError, match="reference"):
        fit_reeves_blau(x, s, [1.0, np.nan, 1.0])
    with pytest.raises(ValueError, match="weights"):
        fit_reeves_blau(x, s, np.ones(3), weights=[1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="shell"):
        fit_reeves_blau(x, "sphere", np.ones(3))
