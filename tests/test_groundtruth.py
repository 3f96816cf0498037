"""Ground truth against closed forms (DESIGN.md "Testing"), by t-tests on the reported stderr."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

import vobscure as vo
from vobscure.groundtruth import DEFAULT_GROUPS

from analytic import crease_cosine_ao, crease_points, crease_uniform_ao, crease_vo, crease_vo_clamped
from conftest import assert_unbiased, t_threshold

R = 1.0
C_VALUES = np.array([0.05, 0.25, 0.5, 0.75, 0.95])
GROUPS = 32  # more randomizations than the default: tighter t thresholds in the tests
DF = GROUPS - 1


def test_crease_cosine_ao(crease):
    p, n = crease_points(C_VALUES, R)
    e = vo.ambient_occlusion(crease, p, n, rays=2048, max_distance=R, seed=1, groups=GROUPS)
    assert e.value.shape == (len(C_VALUES),) and e.samples == 2048
    assert np.all(e.stderr > 0)
    assert_unbiased(e, crease_cosine_ao(C_VALUES), df=DF)


def test_point_on_the_crease_edge(crease):
    """c = 0: the point lies on the floor and in the wall's plane at once.

    Rays start off the floor along the normal *and* along their own direction, so rays
    that leave the wall are not stopped by it at t = 0 and rays into the wall start inside
    it and meet its far side (docs/groundtruth.md, "Rays leaving surfaces").
    """
    p, n = crease_points([0.0], R)
    e = vo.ambient_occlusion(crease, p, n, rays=2048, seed=12, groups=GROUPS)
    assert_unbiased(e, crease_cosine_ao(np.array([0.0])), df=DF)
    e = vo.ambient_occlusion(crease, p, n, rays=2048, weighting="uniform", seed=12, groups=GROUPS)
    assert_unbiased(e, crease_uniform_ao(np.array([0.0])), df=DF)


def test_stderr_never_zero_inside_the_range(crease):
    """Next to the edge every group of stratified directions sees exactly half the wall,
    the group means agree and their spread is 0; the reported stderr must not be 0 there."""
    p, n = crease_points([0.003, 0.01], R)
    e = vo.ambient_occlusion(crease, p, n, rays=256, max_distance=R, seed=0)
    assert np.all(e.stderr > 0)
    assert_unbiased(e, crease_cosine_ao(np.array([0.003, 0.01])), df=DEFAULT_GROUPS - 1)
    v = vo.volumetric_obscurance(crease, p, radius=R, samples=512, seed=0)
    assert np.all(v.stderr > 0)
    assert_unbiased(v, crease_vo(np.array([0.003, 0.01])), df=DEFAULT_GROUPS - 1)


def test_crease_uniform_ao(crease):
    p, n = crease_points(C_VALUES, R)
    e = vo.ambient_occlusion(crease, p, n, rays=2048, max_distance=R, weighting="uniform", seed=2,
                             groups=GROUPS)
    assert_unbiased(e, crease_uniform_ao(C_VALUES), df=DF)


def test_crease_ball_vo(crease):
    p, _ = crease_points(C_VALUES, R)
    e = vo.volumetric_obscurance(crease, p, radius=R, samples=2048, seed=3, groups=GROUPS)
    assert_unbiased(e, crease_vo(C_VALUES), df=DF)


def test_crease_half_ball_vo(crease):
    p, n = crease_points(C_VALUES, R)
    e = vo.volumetric_obscurance(crease, p, n, radius=R, normal_clamp=True, samples=2048, seed=4, groups=GROUPS)
    assert_unbiased(e, crease_vo_clamped(C_VALUES), df=DF)


def test_crease_quadratic_vo_against_quadrature(crease):
    """Falloff 1 - r^2 on the half ball: exact value by quadrature over the wall's cap."""
    c = np.array([0.2, 0.6])
    p, n = crease_points(c, R)
    e = vo.volumetric_obscurance(crease, p, n, radius=R, normal_clamp=True, samples=2048, falloff="quadratic",
                                 seed=5, groups=GROUPS)
    exact = []
    for ci in c:
        # occupied part of the half ball (y > 0): x < -c (wall). Integrate rho over the cap
        # slice by slice in x: the disk of radius s = sqrt(1 - x^2) in (y, z), half of it,
        # with rho = 1 - x^2 - q^2 at in-plane radius q.
        def slab_integral(x):
            s2 = 1.0 - x * x
            # int over the half disk of (s2 - q^2) q dq dphi = pi/2 * s2^2 / 2
            return np.pi / 2.0 * s2 * s2 / 2.0
        occupied, _ = integrate.quad(slab_integral, -1.0, -ci)
        total = 2.0 / 5.0 * (2.0 * np.pi / 3.0)  # int of rho over the unit half ball
        exact.append(1.0 - occupied / total)
    assert_unbiased(e, np.array(exact), df=DF)


def test_obscurance_linear_against_quadrature(crease):
    """Cosine-weighted obscurance, rho(d) = d / R, on the crease floor (RTR Eq. 9.21).

    Projected to the unit disk, cosine-weighted directions are uniform; a direction with
    disk coordinate x < -c meets the wall at d = a / |x| < R, where rho = c / |x|.
    """
    c = np.array([0.1, 0.4, 0.8])
    p, n = crease_points(c, R)
    e = vo.obscurance(crease, p, n, radius=R, falloff="linear", rays=2048, seed=6, groups=GROUPS)
    exact = []
    for ci in c:
        loss, _ = integrate.quad(lambda x: (1.0 - ci / x) * 2.0 * np.sqrt(1.0 - x * x), ci, 1.0)
        exact.append(1.0 - loss / np.pi)
    assert_unbiased(e, np.array(exact), df=DF)


def test_obscurance_step_equals_ao_within_radius(crease):
    p, n = crease_points(C_VALUES, R)
    ob = vo.obscurance(crease, p, n, radius=R, falloff="step", rays=512, seed=7)
    ao = vo.ambient_occlusion(crease, p, n, rays=512, max_distance=R, seed=7)
    # same seed, same directions: the two estimators count exactly the same rays
    np.testing.assert_array_equal(ob.value, ao.value)


def test_obscurance_callable_and_smooth(crease):
    p, n = crease_points([0.3], R)
    lin = vo.obscurance(crease, p, n, radius=R, falloff="linear", rays=512, seed=8)
    same = vo.obscurance(crease, p, n, radius=R, falloff=lambda t: t, rays=512, seed=8)
    np.testing.assert_array_equal(lin.value, same.value)
    smooth = vo.obscurance(crease, p, n, radius=R, falloff="smooth", rays=512, seed=8)
    # 3t^2 - 2t^3 <= t on [0, 1/2] and >= t above; here hits have t = c/|x| in [0.3, 1)
    assert smooth.value[0] != lin.value[0]
    with pytest.raises(ValueError, match="falloff"):
        vo.obscurance(crease, p, n, radius=R, falloff=lambda t: t + 5.0, rays=64)


def test_slab_exact_values(slab):
    pts = np.array([[0.0, 0.0, 0.0], [1.3, 0.0, -2.1], [-2.5, 0.0, 0.7]])
    up = np.tile([0.0, 1.0, 0.0], (3, 1))
    ao = vo.ambient_occlusion(slab, pts, up, rays=256, seed=0)
    np.testing.assert_array_equal(ao.value, 1.0)
    np.testing.assert_array_equal(ao.stderr, 0.0)
    v = vo.volumetric_obscurance(slab, pts, radius=0.7, samples=512, seed=0)
    np.testing.assert_array_equal(v.value, 0.5)   # antithetic pairs split exactly by the plane
    vh = vo.volumetric_obscurance(slab, pts, up, radius=0.7, normal_clamp=True, samples=512, seed=0)
    np.testing.assert_array_equal(vh.value, 1.0)


def test_stderr_is_honest(crease):
    """The reported stderr matches the spread of estimates over independent seeds."""
    p, n = crease_points([0.4], R)
    seeds = 40
    vals = np.array([vo.ambient_occlusion(crease, p, n, rays=64, max_distance=R, seed=s).value[0]
                     for s in range(seeds)])
    ses = np.array([vo.ambient_occlusion(crease, p, n, rays=64, max_distance=R, seed=s).stderr[0]
                    for s in range(seeds)])
    # mean of the reported variances vs the sample variance of the values: their ratio
    # follows F(seeds - 1, seeds * (groups - 1)) when the stderr is honest.
    from scipy import stats

    ratio = vals.var(ddof=1) / np.mean(ses ** 2)
    lo, hi = stats.f.ppf([1e-4, 1 - 1e-4], seeds - 1, seeds * (DEFAULT_GROUPS - 1))
    assert lo < ratio < hi, f"variance ratio {ratio:.3f} outside [{lo:.3f}, {hi:.3f}]"


def test_bent_normals_point_away_from_wall(crease, slab):
    p, n = crease_points([0.05, 0.5], R)
    e = vo.ambient_occlusion(crease, p, n, rays=1024, max_distance=R, seed=0, bent_normals=True)
    assert e.bent_normal.shape == (2, 3)
    np.testing.assert_allclose(np.linalg.norm(e.bent_normal, axis=1), 1.0, rtol=1e-12)
    # the wall at x = 0 blocks directions with x < 0: the bent normal leans towards +x,
    # more so closer to the wall; z stays near 0 by symmetry.
    assert e.bent_normal[0, 0] > e.bent_normal[1, 0] > 0
    # on an open plane with cosine weighting the bent normal is the normal (up to noise:
    # the mean of cosine-distributed directions has x, z means 0 with stderr ~ 0.5/sqrt(n))
    open_ = vo.ambient_occlusion(slab, [[0, 0, 0]], [[0, 1, 0]], rays=4096, seed=0, bent_normals=True)
    assert open_.bent_normal[0, 1] > 0.99


def test_scale_invariance(crease):
    c = np.array([0.2, 0.7])
    p, n = crease_points(c, R)
    base = vo.ambient_occlusion(crease, p, n, rays=256, max_distance=R, seed=11)
    vbase = vo.volumetric_obscurance(crease, p, radius=R, samples=256, seed=11)
    for k in (1e-3, 1e3):
        scaled = crease.scaled(k)
        e = vo.ambient_occlusion(scaled, p * k, n, rays=256, max_distance=R * k, seed=11)
        v = vo.volumetric_obscurance(scaled, p * k, radius=R * k, samples=256, seed=11)
        # same seed, same directions, geometry scaled exactly: identical counts
        np.testing.assert_array_equal(e.value, base.value)
        np.testing.assert_array_equal(v.value, vbase.value)


def test_determinism_and_threads(crease):
    p, n = crease_points(C_VALUES, R)
    a = vo.ambient_occlusion(crease, p, n, rays=128, seed=5, threads=1)
    b = vo.ambient_occlusion(crease, p, n, rays=128, seed=5, threads=2)
    c = vo.ambient_occlusion(crease, p, n, rays=128, seed=6, threads=2)
    np.testing.assert_array_equal(a.value, b.value)
    np.testing.assert_array_equal(a.stderr, b.stderr)
    assert not np.array_equal(a.value, c.value)
    rng_a = vo.volumetric_obscurance(crease, p, radius=R, samples=128, seed=np.random.default_rng(3))
    rng_b = vo.volumetric_obscurance(crease, p, radius=R, samples=128, seed=3)
    np.testing.assert_array_equal(rng_a.value, rng_b.value)


def test_accepts_trimesh():
    import trimesh

    box = trimesh.creation.box(extents=(4, 1, 4))
    e = vo.ambient_occlusion(box, [[0, 0.5, 0]], [[0, 1, 0]], rays=32)
    assert e.value[0] == 1.0


def test_ground_truth_per_pixel(crease):
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(24, 16), fov_y=50.0)
    gb = vo.render_gbuffer(crease, cam)
    ref = vo.ground_truth(crease, gb, quantity="ao", radius=R, rays=256, seed=0, progress=False)
    assert ref.value.shape == (16, 24)
    assert np.array_equal(np.isnan(ref.value), ~gb.valid)
    # pixels on the floor: compare with the closed form through their distance to the wall.
    # Only c < 0.8: nearer c = 1 a group of 32 rays often sees no occluder at all, the
    # group means coincide and the t statistic degenerates (stderr 0, value != exact).
    x = gb.world_position[..., 0]
    floor = gb.valid & (np.abs(gb.world_position[..., 1]) < 1e-9) & (x > 0) & (x < 0.8 * R)
    assert floor.sum() > 20
    c = np.minimum(gb.world_position[floor][:, 0] / R, 1.0)
    sub = vo.Estimate(ref.value[floor], ref.stderr[floor], ref.samples)
    assert_unbiased(sub, crease_cosine_ao(c), df=DEFAULT_GROUPS - 1)
    vol = vo.ground_truth(crease, gb, quantity="volumetric", radius=R, samples=256, seed=0, progress=False)
    sub = vo.Estimate(vol.value[floor], vol.stderr[floor], vol.samples)
    assert_unbiased(sub, crease_vo(c), df=DEFAULT_GROUPS - 1)
    obs = vo.ground_truth(crease, gb, quantity="obscurance", radius=R, rays=64, progress=False)
    assert np.all((obs.value[gb.valid] >= 0) & (obs.value[gb.valid] <= 1))


def test_open_mesh_needs_opt_in():
    import trimesh

    box = trimesh.creation.box()
    box.update_faces(np.arange(len(box.faces)) != 0)  # drop one triangle: a hole
    with pytest.raises(ValueError, match="allow_open"):
        vo.volumetric_obscurance(box, [[0, 0.5, 0]], radius=0.2)
    e = vo.volumetric_obscurance(box, [[0, 0.5, 0]], radius=0.2, samples=64, allow_open=True)
    assert e.value.shape == (1,)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rays=1), "rays"),
    (dict(rays=2.5), "rays"),
    (dict(weighting="phong"), "weighting"),
    (dict(max_distance=-1.0), "max_distance"),
    (dict(max_distance=float("nan")), "max_distance"),
    (dict(seed=-3), "seed"),
    (dict(seed="abc"), "seed"),
])
def test_ao_bad_arguments(crease, kwargs, match):
    p, n = crease_points([0.5], R)
    with pytest.raises(ValueError, match=match):
        vo.ambient_occlusion(crease, p, n, **kwargs)


def test_bad_points_and_normals(crease):
    with pytest.raises(ValueError, match="points"):
        vo.ambient_occlusion(crease, [[0, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="points"):
        vo.ambient_occlusion(crease, [[np.nan, 0, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="normals"):
        vo.ambient_occlusion(crease, [[0, 0, 0]], [[0, 0, 0]])
    with pytest.raises(ValueError, match="normals"):
        vo.ambient_occlusion(crease, [[0, 0, 0], [1, 0, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="scene"):
        vo.ambient_occlusion("no_such_scene", [[0, 0, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="scene"):
        vo.ambient_occlusion(3, [[0, 0, 0]], [[0, 1, 0]])
    with pytest.raises(ValueError, match="radius"):
        vo.volumetric_obscurance(crease, [[0, 0, 0]], radius=0)
    with pytest.raises(ValueError, match="falloff"):
        vo.volumetric_obscurance(crease, [[0, 0, 0]], radius=1, falloff="cubic")
    with pytest.raises(ValueError, match="votes"):
        vo.volumetric_obscurance(crease, [[0, 0, 0]], radius=1, votes=2)
    with pytest.raises(ValueError, match="radius"):
        vo.obscurance(crease, [[0, 0, 0]], [[0, 1, 0]], radius=-1)


def test_ground_truth_bad_arguments(crease):
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(4, 4))
    gb = vo.render_gbuffer(crease, cam)
    with pytest.raises(ValueError, match="quantity"):
        vo.ground_truth(crease, gb, quantity="gi")
    with pytest.raises(ValueError, match="radius"):
        vo.ground_truth(crease, gb, quantity="volumetric")
    with pytest.raises(ValueError, match="gbuffer"):
        vo.ground_truth(crease, np.zeros((4, 4)))


def test_empty_point_set(crease):
    e = vo.ambient_occlusion(crease, np.zeros((0, 3)), np.zeros((0, 3)) + [0, 1, 0], rays=16)
    assert e.value.shape == (0,)


# ----------------------------------------------------------------------------- one vocabulary
def test_normal_clamp_selects_the_half_ball(slab):
    pts = np.array([[0.0, 0.0, 0.0], [1.3, 0.0, -2.1]])
    up = np.tile([0.0, 1.0, 0.0], (2, 1))
    # DESIGN.md's contract line: normals optional when unclamped
    ball = vo.volumetric_obscurance(slab, pts, normals=None, radius=0.7, samples=512, seed=0)
    np.testing.assert_array_equal(ball.value, 0.5)
    # normals alone no longer select the half-ball: unclamped, they are unused
    with_normals = vo.volumetric_obscurance(slab, pts, up, radius=0.7, samples=512, seed=0)
    assert with_normals.value.tobytes() == ball.value.tobytes()
    assert with_normals.stderr.tobytes() == ball.stderr.tobytes()
    half = vo.volumetric_obscurance(slab, pts, up, radius=0.7, normal_clamp=True, samples=512, seed=0)
    np.testing.assert_array_equal(half.value, 1.0)
    with pytest.raises(ValueError, match="normal_clamp=True needs normals") as info:
        vo.volumetric_obscurance(slab, pts, radius=0.7, normal_clamp=True)
    assert "normals" in str(info.value) and "normal_clamp" in str(info.value)
    with pytest.raises(ValueError, match="normal_clamp"):
        vo.volumetric_obscurance(slab, pts, up, radius=0.7, normal_clamp="yes")


def test_ground_truth_passes_votes_on(crease, monkeypatch):
    from vobscure import groundtruth as G

    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(6, 5), fov_y=50.0)
    gb = vo.render_gbuffer(crease, cam)
    seen = []
    real = G._volumetric

    def spy(*args, **kwargs):
        seen.append(kwargs["votes"])
        return real(*args, **kwargs)

    monkeypatch.setattr(G, "_volumetric", spy)
    gt = vo.ground_truth(crease, gb, quantity="volumetric", radius=R, samples=32, votes=5, seed=2)
    vo.ground_truth(crease, gb, quantity="volumetric", radius=R, samples=32, seed=2)
    direct = vo.volumetric_obscurance(crease, gb.hits["world_position"], radius=R, samples=32, votes=5, seed=2)
    assert seen == [5, 3, 5]
    assert gt.value[gb.valid].tobytes() == direct.value.tobytes()
    with pytest.raises(ValueError, match="votes"):
        vo.ground_truth(crease, gb, quantity="volumetric", radius=R, samples=32, votes=4)


def test_one_progress_default_and_sample_names():
    """progress is off by default in every public function that has it; ``rays`` counts
    directions and ``samples`` points in a volume (docs/conventions.md)."""
    import inspect

    from vobscure.experiments import cache

    functions = [vo.ground_truth, vo.ambient_occlusion, vo.obscurance, vo.volumetric_obscurance,
                 vo.vo_reference, cache.ground_truth_cached, cache.screen_reference_cached]
    for fn in functions:
        params = inspect.signature(fn).parameters
        assert params["progress"].default is False, fn.__name__
    for fn in (vo.ambient_occlusion, vo.obscurance):
        params = inspect.signature(fn).parameters
        assert "rays" in params and "samples" not in params, fn.__name__
    for fn in (vo.volumetric_obscurance, vo.vo_reference):
        params = inspect.signature(fn).parameters
        assert "samples" in params and "rays" not in params, fn.__name__
    for fn in (vo.volumetric_obscurance, vo.ground_truth, vo.vo_reference):
        assert inspect.signature(fn).parameters["normal_clamp"].default is False, fn.__name__


# ----------------------------------------------------------------------------- interreflections
ALBEDO = 0.6
CAVITY_OPENING = 0.5  # the opening is the cap y > 0.5 of the unit sphere: a quarter of its area


@pytest.fixture(scope="module")
def cavity():
    """A unit sphere with a polar cap removed, seen from inside, and its opening fraction f
    (from the mesh's own areas, so that the faceting does not bias f)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    keep = sphere.triangles_center[:, 1] < CAVITY_OPENING
    f = float(sphere.area_faces[~keep].sum() / sphere.area_faces.sum())
    mesh = trimesh.Trimesh(sphere.vertices, sphere.faces[keep], process=False)
    rng = np.random.default_rng(5)
    faces = rng.choice(np.flatnonzero(keep[keep]), 16, replace=False)
    return mesh, mesh.triangles_center[faces], -mesh.face_normals[faces], f


@pytest.mark.parametrize("bounces", [1, 2, 40])
def test_interreflections_in_a_spherical_cavity(cavity, bounces):
    # Inside a sphere every point sees every area element with the same form factor, so
    # k_A = f and k'_A = f * sum_{b <= N} (a (1 - f))^b at every interior point; with many
    # bounces this is Stewart & Langer's k_A / (1 - a (1 - k_A)) (RTR Eq. 9.23).
    mesh, p, n, f = cavity
    e = vo.ambient_occlusion(mesh, p, n, rays=2048, bounces=bounces, albedo=ALBEDO, groups=GROUPS, seed=3)
    exact = f * sum((ALBEDO * (1.0 - f)) ** b for b in range(bounces + 1))
    assert_unbiased(e, np.full(len(p), exact), df=DF)
    # pooled over the points (independent estimates): a test with sqrt(16) times the power
    pooled = (e.value - exact).sum() / np.sqrt((e.stderr ** 2).sum())
    assert abs(pooled) < t_threshold(DF * len(p)), f"pooled t {pooled:.2f}"
    if bounces == 40:
        assert exact == pytest.approx(float(vo.shading.stewart_langer(f, ALBEDO)), rel=1e-8)


def test_interreflections_only_add_light(crease, slab):
    # The primary rays are the same draws with and without bounces (same seed), and a path
    # that escapes at once brings 1 either way: light reflected by the occluders only adds.
    p, n = crease_points([0.02, 0.1, 0.3], R)
    plain = vo.ambient_occlusion(crease, p, n, rays=256, seed=4)
    assert vo.ambient_occlusion(crease, p, n, rays=256, seed=4, bounces=0, albedo=0.7).value.tolist() == \
        plain.value.tolist()
    assert vo.ambient_occlusion(crease, p, n, rays=256, seed=4, bounces=3, albedo=0.0).value.tolist() == \
        plain.value.tolist()
    lit = vo.ambient_occlusion(crease, p, n, rays=256, seed=4, bounces=2, albedo=0.7)
    assert np.all(lit.value > plain.value)
    # nothing to reflect on an open plane: exactly 1 whatever the albedo
    open_plane = vo.ambient_occlusion(slab, [[0, 0, 0]], [[0, 1, 0]], rays=64, bounces=3, albedo=1.0)
    assert open_plane.value.tolist() == [1.0]


@pytest.mark.parametrize("kwargs, match", [
    (dict(bounces=-1, albedo=0.5), "bounces"),
    (dict(bounces=1.5, albedo=0.5), "bounces"),
    (dict(bounces=1, albedo=1.5), "albedo"),
    (dict(bounces=1, albedo=-0.1), "albedo"),
    (dict(bounces=1, albedo=float("nan")), "albedo"),
    (dict(bounces=1, albedo="white"), "albedo"),
    (dict(bounces=1, albedo=0.5, bent_normals=True), "bent_normals"),
])
def test_interreflection_bad_arguments(crease, kwargs, match):
    p, n = crease_points([0.5], R)
    with pytest.raises(ValueError, match=match):
        vo.ambient_occlusion(crease, p, n, **kwargs)


def test_ground_truth_per_pixel_interreflections(crease):
    cam = vo.Camera.look_at((2.0, 2.0, 3.0), (0.5, 0.3, 0.0), size=(12, 8), fov_y=50.0)
    gb = vo.render_gbuffer(crease, cam)
    plain = vo.ground_truth(crease, gb, quantity="ao", rays=64, seed=1)
    lit = vo.ground_truth(crease, gb, quantity="ao", rays=64, seed=1, bounces=2, albedo=0.8)
    assert np.array_equal(np.isnan(lit.value), ~gb.valid)
    occluded = gb.valid & (plain.value < 1.0)
    assert occluded.sum() > 5
    assert np.all(lit.value[occluded] > plain.value[occluded])
    assert np.array_equal(lit.value[gb.valid & ~occluded], plain.value[gb.valid & ~occluded])
    with pytest.raises(ValueError, match="quantity='ao' only"):
        vo.ground_truth(crease, gb, quantity="obscurance", radius=R, bounces=1, albedo=0.5)


def test_interreflections_at_a_concave_edge(crease):
    # A point on the crease's edge has the rays towards the wall start inside the wall's
    # solid; they are traced again from the point moved two ray offsets off the wall, so
    # the edge gets the light of its neighbours instead of paths lost inside the wall.
    p = np.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0]])
    n = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    e = vo.ambient_occlusion(crease, p, n, rays=4096, bounces=3, albedo=0.8, groups=GROUPS, seed=6)
    t = (e.value[0] - e.value[1]) / np.hypot(e.stderr[0], e.stderr[1])
    assert abs(t) < t_threshold(2 * DF), f"edge {e.value[0]:.4f} vs 1e-3 away {e.value[1]:.4f} (t = {t:.1f})"
