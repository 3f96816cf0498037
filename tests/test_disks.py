"""Bunnell's disk-based AO (vobscure.objectspace): the three shadow terms against closed forms
and scipy quadrature, their geometric cases, subdivision of coarse meshes, the passes and
their mean against ray-cast AO on a subdivided crease, the tree against the exact sum (thin
two-sided walls included), the per-pixel form and its registry entry, validation."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy import integrate

import vobscure as vo
from vobscure import methods
from vobscure.objectspace import (
    DEFAULT_TERM,
    TERMS,
    bunnell,
    bunnell_gbuffer,
    disk_shadow,
    shadow_evaluations,
    vertex_disks,
)
from vobscure.objectspace import disks as disks_module

#: Agreement of two float64 evaluations of the same closed form.
EXACT = 1e-12
#: Agreement with scipy.integrate.quad (its default tolerances are 1.5e-8).
QUAD = 1e-8
#: float32 inputs against float64 ones (the inputs' rounding, ~1e-7 relative).
FLOAT32 = 1e-5
#: Measured on crease_sub2 (162 vertices) against 256 rays a vertex (seed 0), exact sum:
#: the default term ("gpugems") against the uniformly weighted AO, RMSE pass 1 0.0091, pass 2
#: 0.0090; "solid_angle" against the cosine-weighted AO, pass 1 0.068, pass 2 0.071. Bounds
#: with margin above the measurements: these are an approximation's errors, not noise.
RMSE_DEFAULT_MAX = 0.02
RMSE_SOLID_ANGLE_MAX = 0.09
#: Measured: mean visibility of "solid_angle" pass 1 0.988 vs ray-cast 0.965 (too light).
UNDER_DARKEN_MIN = 0.01
#: Measured on crease_sub2, open_ratio 4, passes 1 and 2, every term: tree vs exact sum max
#: 0.0076, RMSE 0.0010 (gpugems; solid_angle 0.0025 / 0.0002, form_factor 0.0050 / 0.0004).
TREE_MAX_DIFF = 0.015
TREE_RMSE = 0.003

UP = [0.0, 0.0, 1.0]
DOWN = [0.0, 0.0, -1.0]


def _on_axis(a, d, term):
    """A disk of radius a facing the receiver at distance d along its normal."""
    normal = UP if term == "gpugems" else DOWN    # "gpugems" casts from the disk's back
    return float(disk_shadow([[0, 0, 0]], [UP], [[0, 0, d]], [normal], [np.pi * a * a], term=term)[0, 0])


# ----------------------------------------------------------------------------- the terms


@pytest.mark.parametrize("a, d", [(1.0, 1.0), (0.1, 1.0), (2.0, 0.5), (0.01, 3.0), (5.0, 0.01)])
def test_on_axis_closed_forms(a, d):
    # solid angle of a disk on axis 2 pi (1 - d / sqrt(d^2 + a^2)); over the hemisphere's 2 pi
    assert _on_axis(a, d, "solid_angle") == pytest.approx(1 - d / np.sqrt(d * d + a * a), abs=EXACT)
    assert _on_axis(a, d, "gpugems") == pytest.approx(1 - d / np.sqrt(d * d + a * a), abs=EXACT)
    # cosine-weighted: the point-to-disk form factor a^2 / (d^2 + a^2)
    assert _on_axis(a, d, "form_factor") == pytest.approx(a * a / (d * d + a * a), abs=EXACT)


@pytest.mark.parametrize("a, d", [(1.0, 1.0), (0.1, 1.0), (2.0, 0.5)])
def test_on_axis_against_quadrature(a, d):
    # the disk as rings of radius rho seen at polar angle theta, tan theta = rho / d:
    # solid angle fraction (1/2pi) int dOmega and cosine-weighted fraction (1/pi) int cos dOmega
    def d_omega(rho):     # dOmega of the ring, divided by 2 pi
        return d * rho / (d * d + rho * rho) ** 1.5

    uniform = integrate.quad(d_omega, 0.0, a)[0]
    cosine = integrate.quad(lambda rho: 2.0 * d_omega(rho) * d / np.hypot(d, rho), 0.0, a)[0]
    assert _on_axis(a, d, "solid_angle") == pytest.approx(uniform, abs=QUAD)
    assert _on_axis(a, d, "form_factor") == pytest.approx(cosine, abs=QUAD)


def test_solid_angle_is_half_the_form_factor_for_small_disks():
    for a, d in [(0.01, 1.0), (0.001, 2.0)]:
        assert _on_axis(a, d, "solid_angle") / _on_axis(a, d, "form_factor") == pytest.approx(0.5, rel=1e-3)


@pytest.mark.parametrize("term", TERMS)
def test_symmetric_for_equal_disks_and_under_rotation(term):
    rng = np.random.default_rng(1)
    p = rng.normal(size=(6, 3))
    n = rng.normal(size=(6, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    A = np.full(6, 0.3)
    S = disk_shadow(p, n, p, n, A, term=term)
    assert np.all(np.diag(S) == 0)                       # no disk shadows itself
    if term != "gpugems":                                # clamp(4 cos) breaks the symmetry
        np.testing.assert_allclose(S, S.T, atol=EXACT)
    R = trimesh.transformations.random_rotation_matrix(rng.random(3))[:3, :3]
    S_rot = disk_shadow(p @ R.T + 2.0, n @ R.T, p @ R.T + 2.0, n @ R.T, A, term=term)
    np.testing.assert_allclose(S_rot, S, atol=1e-12)


@pytest.mark.parametrize("term", TERMS)
def test_receiver_facing_away_gets_no_shadow(term):
    for normal in (UP, DOWN):
        assert disk_shadow([[0, 0, 0]], [DOWN], [[0, 0, 1]], [normal], [1.0], term=term)[0, 0] == 0


@pytest.mark.parametrize("term", TERMS)
def test_emitter_behind_receiver_plane_casts_none(term):
    S = disk_shadow([[0, 0, 0]], [UP], [[0.3, 0, -1], [1, 0, 0], [1, 0, 0]], [UP, [-1, 0, 0], [1, 0, 0]],
                    [1.0, 1.0, 1.0], term=term)
    np.testing.assert_array_equal(S, 0)


def test_which_side_casts():
    # "solid_angle" and "form_factor" cast from the front, "gpugems" from the back (Sec. 14.1)
    for term, casts, silent in [("solid_angle", DOWN, UP), ("form_factor", DOWN, UP), ("gpugems", UP, DOWN)]:
        assert disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [casts], [1.0], term=term)[0, 0] > 0
        assert disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [silent], [1.0], term=term)[0, 0] == 0


@pytest.mark.parametrize("theta", [0.4, 1.2, 1.5])
def test_off_axis_is_the_cosines_times_the_axis_term(theta):
    a, r = 0.5, 2.0
    e = np.array([np.sin(theta), 0.0, np.cos(theta)])
    A = np.pi * a * a
    axis = 1 - r / np.hypot(r, a)
    cos_R = np.cos(theta)
    S = {term: disk_shadow([[0, 0, 0]], [UP], [r * e], [e if term == "gpugems" else -e], [A], term=term)[0, 0]
         for term in TERMS}
    assert S["solid_angle"] == pytest.approx(axis * cos_R, abs=EXACT)
    assert S["gpugems"] == pytest.approx(axis * min(1.0, 4.0 * cos_R), abs=EXACT)   # Listing 14-1
    assert S["form_factor"] == pytest.approx(A * cos_R / (np.pi * r * r + A), abs=EXACT)


def test_float32_inputs():
    rng = np.random.default_rng(2)
    p, n = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    A = rng.random(5)
    for term in TERMS:
        S64 = disk_shadow(p, n, p + 1.0, -n, A, term=term)
        S32 = disk_shadow(*(x.astype(np.float32) for x in (p, n, p + 1.0, -n, A)), term=term)
        assert S32.dtype == np.float64
        np.testing.assert_allclose(S32, S64, atol=FLOAT32)


# ----------------------------------------------------------------------------- the disks


def test_vertex_disk_areas_sum_to_surface_area():
    mesh = trimesh.creation.icosphere(subdivisions=1)
    c, n, A = vertex_disks(mesh)
    assert c.shape == n.shape == (len(mesh.vertices), 3)
    assert A.sum() == pytest.approx(mesh.area, rel=1e-12)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("max_edge", [0.5, 0.2])
def test_max_edge_subdivides_a_box_into_a_surface_of_disks(max_edge):
    box = trimesh.creation.box(extents=(2.0, 1.0, 0.1))
    c, n, A = vertex_disks(box, max_edge=max_edge)
    assert A.sum() == pytest.approx(box.area, rel=1e-12)
    # every disk centre lies on the box's surface, and the spacing is at most max_edge
    half = np.array([1.0, 0.5, 0.05])
    np.testing.assert_allclose(np.max(np.abs(c) - half, axis=1), 0.0, atol=1e-12)
    v, f = trimesh.remesh.subdivide_to_size(box.vertices, box.faces, max_edge)
    assert len(c) == len(trimesh.Trimesh(v, f).vertices)
    edges = trimesh.Trimesh(v, f).edges_unique_length
    assert edges.max() <= max_edge
    # the interior of the large faces: disks with the face's own normal
    top = np.isclose(c[:, 2], 0.05) & (np.abs(c[:, 0]) < 0.99) & (np.abs(c[:, 1]) < 0.49)
    assert top.sum() > 0
    np.testing.assert_allclose(n[top], [[0, 0, 1]] * int(top.sum()), atol=1e-9)


def test_max_edge_auto_is_a_fraction_of_the_diagonal():
    scene = vo.scenes.get("cornell_box")
    lo, hi = scene.bounds
    edge = disks_module.AUTO_EDGE_FRACTION * np.linalg.norm(hi - lo)
    np.testing.assert_array_equal(vertex_disks(scene, max_edge="auto")[0], vertex_disks(scene, max_edge=edge)[0])
    assert len(vertex_disks(scene, max_edge="auto")[0]) > 100 * len(vertex_disks(scene)[0])


def test_max_edge_larger_than_the_mesh_changes_nothing():
    box = trimesh.creation.box()
    for a, b in zip(vertex_disks(box, max_edge=10.0), vertex_disks(box)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("max_edge", [0.0, -1.0, np.nan, np.inf, "fine", True])
def test_max_edge_validation(max_edge):
    with pytest.raises(ValueError, match="max_edge"):
        vertex_disks(trimesh.creation.box(), max_edge=max_edge)
    with pytest.raises(ValueError, match="max_edge"):
        bunnell(trimesh.creation.box(), max_edge=max_edge)


def test_max_edge_that_would_exhaust_memory_is_refused():
    with pytest.raises(ValueError, match="max_edge=1e-05"):
        vertex_disks(trimesh.creation.box(), max_edge=1e-5)


# ----------------------------------------------------------------------------- the passes


@pytest.fixture(scope="module")
def fine_crease():
    mesh = next(iter(vo.scenes.get("crease").meshes.values())).subdivide().subdivide()
    return vo.Scene(mesh)


@pytest.fixture(scope="module")
def crease_reference(fine_crease):
    p, n, _ = vertex_disks(fine_crease)
    return {w: vo.ambient_occlusion(fine_crease, p, n, rays=256, weighting=w, max_distance=np.inf, seed=0).value
            for w in ("cosine", "uniform")}


def test_convex_mesh_is_unoccluded():
    for term in TERMS:
        for hierarchy in (False, True):
            V = bunnell(trimesh.creation.icosphere(subdivisions=2), term=term, hierarchy=hierarchy)
            np.testing.assert_allclose(V, 1.0, atol=EXACT)


def _rmse(V, ref):
    return float(np.sqrt(np.mean((V - ref) ** 2)))


def test_default_term_against_ray_cast(fine_crease, crease_reference):
    assert DEFAULT_TERM == "gpugems"
    ref = crease_reference["uniform"]
    V1, V2 = (bunnell(fine_crease, passes=p, hierarchy=False) for p in (1, 2))
    assert _rmse(V1, ref) < RMSE_DEFAULT_MAX and _rmse(V2, ref) < RMSE_DEFAULT_MAX
    # the fine_crease occludes: not everything is open
    assert V1.min() < 0.9


def test_solid_angle_passes_against_ray_cast(fine_crease, crease_reference):
    ref = crease_reference["cosine"]
    V1, V2 = (bunnell(fine_crease, passes=p, term="solid_angle", hierarchy=False) for p in (1, 2))
    assert _rmse(V1, ref) < RMSE_SOLID_ANGLE_MAX and _rmse(V2, ref) < RMSE_SOLID_ANGLE_MAX
    # the second pass only lightens (its weights are accessibilities <= 1) ...
    assert np.all(V2 >= V1 - EXACT)
    assert np.any(V2 > V1 + 1e-3)
    # ... and with the solid-angle term the first is already too light, not too dark
    assert V1.mean() - ref.mean() > UNDER_DARKEN_MIN


@pytest.mark.parametrize("term", TERMS)
def test_one_pass_is_one_minus_the_row_sums(fine_crease, term):
    p, n, A = vertex_disks(fine_crease)
    expected = np.clip(1 - disk_shadow(p, n, p, n, A, term=term).sum(axis=1), 0, 1)
    np.testing.assert_allclose(bunnell(fine_crease, passes=1, term=term, hierarchy=False), expected, atol=EXACT)


def test_second_pass_weights_the_emitters_by_the_first(fine_crease):
    p, n, A = vertex_disks(fine_crease)
    S = disk_shadow(p, n, p, n, A)
    V1 = np.clip(1 - S.sum(axis=1), 0, 1)
    np.testing.assert_allclose(bunnell(fine_crease, hierarchy=False), np.clip(1 - S @ V1, 0, 1), atol=EXACT)


@pytest.mark.parametrize("hierarchy", [False, True])
def test_average_is_the_mean_of_the_last_two_passes(fine_crease, hierarchy):
    V2, V3 = (bunnell(fine_crease, passes=p, hierarchy=hierarchy) for p in (2, 3))
    np.testing.assert_allclose(bunnell(fine_crease, passes=3, average=True, hierarchy=hierarchy), (V2 + V3) / 2,
                               atol=EXACT)
    p, n, _ = vertex_disks(fine_crease)
    np.testing.assert_allclose(bunnell(fine_crease, p, n, passes=3, average=True, hierarchy=hierarchy), (V2 + V3) / 2,
                               atol=EXACT)


def test_points_at_the_vertices_match_per_vertex(fine_crease):
    p, n, _ = vertex_disks(fine_crease)
    np.testing.assert_allclose(bunnell(fine_crease, p, n), bunnell(fine_crease), atol=EXACT)
    np.testing.assert_allclose(bunnell(fine_crease, p.astype(np.float32), n.astype(np.float32)),
                               bunnell(fine_crease), atol=FLOAT32)


@pytest.mark.parametrize("hierarchy", [False, True])
def test_blocks_do_not_change_the_result(fine_crease, hierarchy):
    np.testing.assert_allclose(bunnell(fine_crease, block=7, hierarchy=hierarchy), bunnell(fine_crease, hierarchy=hierarchy),
                               atol=EXACT)


def test_results_on_a_scene_object_are_cached_and_equal_to_a_fresh_computation(fine_crease, monkeypatch):
    calls = []
    real = disks_module.vertex_disks
    monkeypatch.setattr(disks_module, "vertex_disks", lambda *a, **k: calls.append(1) or real(*a, **k))
    scene = vo.Scene(next(iter(fine_crease.meshes.values())))
    first = bunnell(scene, passes=3)
    again = [bunnell(scene, passes=p) for p in (1, 2, 3)]      # passes 1-2 computed on the way to 3
    assert len(calls) == 1
    np.testing.assert_array_equal(again[2], first)
    # a mesh (not a Scene) is not cached: same values, computed again
    np.testing.assert_allclose(bunnell(next(iter(fine_crease.meshes.values())), passes=3), first, atol=EXACT)
    assert len(calls) == 2


# ----------------------------------------------------------------------------- the tree


@pytest.mark.parametrize("passes", [1, 2])
@pytest.mark.parametrize("term", TERMS)
def test_tree_that_never_aggregates_is_the_exact_sum(fine_crease, passes, term):
    np.testing.assert_allclose(bunnell(fine_crease, passes=passes, term=term, open_ratio=np.inf),
                               bunnell(fine_crease, passes=passes, term=term, hierarchy=False), atol=EXACT)


@pytest.mark.parametrize("passes", [1, 2])
@pytest.mark.parametrize("term", TERMS)
def test_tree_is_close_to_the_exact_sum(fine_crease, passes, term):
    V_tree = bunnell(fine_crease, passes=passes, term=term)
    V = bunnell(fine_crease, passes=passes, term=term, hierarchy=False)
    assert np.abs(V_tree - V).max() < TREE_MAX_DIFF
    assert np.sqrt(np.mean((V_tree - V) ** 2)) < TREE_RMSE


@pytest.mark.parametrize("term", TERMS)
def test_tree_keeps_the_shadow_of_a_far_thin_wall(term):
    # a thin closed wall (both sides have disks) far from receivers on a floor: aggregating
    # its two sides into one disk would cancel the normals and lose its shadow
    wall = trimesh.creation.box(extents=(0.02, 1.0, 2.0))
    wall.apply_translation((0.0, 0.5, 0.0))
    scene = vo.Scene({"wall": wall})
    x = np.linspace(0.5, 3.0, 6)
    points = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    normals = np.tile([0.0, 1.0, 0.0], (len(x), 1))
    exact = bunnell(scene, points, normals, passes=1, term=term, hierarchy=False, max_edge=0.05)
    tree = bunnell(scene, points, normals, passes=1, term=term, max_edge=0.05)
    assert np.all(exact < 1 - 1e-3)                      # the wall does shadow them
    np.testing.assert_allclose(tree, exact, atol=TREE_MAX_DIFF * (1 - exact).max())


def test_tree_with_points_and_on_a_convex_mesh(fine_crease):
    p, n, _ = vertex_disks(fine_crease)
    np.testing.assert_allclose(bunnell(fine_crease, p, n), bunnell(fine_crease), atol=EXACT)
    V = bunnell(trimesh.creation.icosphere(subdivisions=2), open_ratio=1.0)
    np.testing.assert_allclose(V, 1.0, atol=EXACT)


def test_shadow_evaluations(fine_crease):
    k = len(vertex_disks(fine_crease)[0])
    assert shadow_evaluations(fine_crease, hierarchy=False) == k * k
    assert shadow_evaluations(fine_crease, open_ratio=np.inf) == k * k     # every leaf, for every receiver
    assert shadow_evaluations(fine_crease) < k * k
    assert shadow_evaluations(fine_crease, open_ratio=2.0) < shadow_evaluations(fine_crease, open_ratio=8.0)
    p = np.array([[0.5, 0.01, 0.0]])
    assert shadow_evaluations(fine_crease, p, [[0, 1, 0]], hierarchy=False) == k


# ----------------------------------------------------------------------------- per pixel


@pytest.fixture(scope="module")
def fine_crease_gbuffer(fine_crease):
    cam = vo.Camera.look_at((1.5, 1.2, 2.5), (0.3, 0.2, 0.0), size=(24, 18), fov_y=50.0)
    return vo.render_gbuffer(fine_crease, cam)


@pytest.mark.parametrize("kwargs", [{}, {"passes": 1, "term": "form_factor"}, {"hierarchy": False},
                                    {"passes": 3, "average": True}])
def test_gbuffer_is_the_points_form_at_the_pixels(fine_crease, fine_crease_gbuffer, kwargs):
    gb = fine_crease_gbuffer
    assert gb.valid.any() and not gb.valid.all()
    V = bunnell_gbuffer(gb, scene=fine_crease, **kwargs)
    assert V.shape == gb.valid.shape and V.dtype == np.float64
    assert np.all(np.isnan(V[~gb.valid])) and not np.any(np.isnan(V[gb.valid]))
    expected = bunnell(fine_crease, gb.world_position[gb.valid], gb.world_normal[gb.valid], **kwargs)
    np.testing.assert_allclose(V[gb.valid], expected, atol=EXACT)


def test_gbuffer_background_only_and_unused_options(fine_crease, fine_crease_gbuffer):
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 10), size=(4, 3), fov_y=30.0)   # looks away
    gb = vo.render_gbuffer(fine_crease, cam)
    assert np.all(np.isnan(bunnell_gbuffer(gb, scene=fine_crease)))
    a = bunnell_gbuffer(fine_crease_gbuffer, scene=fine_crease)
    b = bunnell_gbuffer(fine_crease_gbuffer, scene=fine_crease, radius=0.1, normal_clamp=True, thickness=0.2, seed=5)
    np.testing.assert_array_equal(a, b)


def test_gbuffer_needs_a_scene_object(fine_crease_gbuffer):
    with pytest.raises(ValueError, match="scene"):
        bunnell_gbuffer(fine_crease_gbuffer, scene="crease")


def test_registry_entry(fine_crease, fine_crease_gbuffer):
    m = methods.get("bunnell")
    assert m.fetch == "none" and m.samples is None and m.needs_scene
    assert m.taps(1) == 0 and m.texels(1) == 0
    assert m.reference(False) == m.reference(True) == "sky_uniform"
    got = m.run(fine_crease_gbuffer, scene=fine_crease, radius=0.3, normal_clamp=False, thickness=None, falloff="constant",
                seed=0)
    np.testing.assert_array_equal(got, bunnell_gbuffer(fine_crease_gbuffer, scene=fine_crease, max_edge="auto"))


@pytest.mark.slow
def test_compare_runs_bunnell_on_the_cornell_box():
    from vobscure.experiments.compare import compare

    result = compare("cornell_box", methods="bunnell,line:9", quick=True, size=(24, 24), write=False,
                     plots=False, cache=False)
    row = next(r for r in result.rows if r["method"] == "bunnell")
    assert row["own_reference"] == "sky_uniform" and row["taps_per_pixel"] == 0
    assert np.isfinite(row["own_rmse"])


# ----------------------------------------------------------------------------- validation


@pytest.mark.parametrize("kwargs, name", [
    ({"passes": 0}, "passes"),
    ({"passes": 1.5}, "passes"),
    ({"block": 0}, "block"),
    ({"hierarchy": "yes"}, "hierarchy"),
    ({"average": 1}, "average"),
    ({"average": True, "passes": 1}, "average"),
    ({"term": "disk"}, "term"),
    ({"open_ratio": 0.0}, "open_ratio"),
    ({"open_ratio": np.nan}, "open_ratio"),
    ({"points": [[0, 0, 0]]}, "normals"),
    ({"normals": [[0, 0, 1]]}, "normals"),
    ({"points": [[0, 0]], "normals": [[0, 0, 1]]}, "points"),
    ({"points": [[0, 0, np.nan]], "normals": [[0, 0, 1]]}, "points"),
    ({"points": [[0, 0, 0]], "normals": [[0, 0, 1], [0, 0, 1]]}, "normals"),
    ({"points": [[0, 0, 0]], "normals": [[0, 0, 0]]}, "normals"),
])
def test_bunnell_validation_names_the_argument(fine_crease, kwargs, name):
    with pytest.raises(ValueError, match=name):
        bunnell(fine_crease, **kwargs)


@pytest.mark.parametrize("kwargs, name", [({"passes": 0}, "passes"), ({"term": "x"}, "term"),
                                          ({"max_edge": -1.0}, "max_edge"), ({"hierarchy": None}, "hierarchy")])
def test_gbuffer_validation_names_the_argument(fine_crease, fine_crease_gbuffer, kwargs, name):
    with pytest.raises(ValueError, match=name):
        bunnell_gbuffer(fine_crease_gbuffer, scene=fine_crease, **kwargs)


def test_disk_shadow_validation_names_the_argument():
    with pytest.raises(ValueError, match="emitter_areas"):
        disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [DOWN], [-1.0])
    with pytest.raises(ValueError, match="emitter_areas"):
        disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [DOWN], [1.0, 2.0])
    with pytest.raises(ValueError, match="emitter_normals"):
        disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [DOWN, DOWN], [1.0])
    with pytest.raises(ValueError, match="receivers"):
        disk_shadow([[0, 0]], [UP], [[0, 0, 1]], [DOWN], [1.0])
    with pytest.raises(ValueError, match="term"):
        disk_shadow([[0, 0, 0]], [UP], [[0, 0, 1]], [DOWN], [1.0], term="Bunnell")
