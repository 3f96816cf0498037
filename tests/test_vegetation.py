"""Tests of vobscure.scenes.vegetation: leaf clouds, trees, grass and leaf_points."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from scipy import stats

import vobscure as vo
from vobscure.experiments.cache import scene_digest
from vobscure.scenes import (
    Scene,
    get,
    grass,
    leaf_cloud,
    leaf_cloud_dense,
    leaf_points,
    names,
    tree,
    tree_poplar,
)

from conftest import FALSE_FAILURE

VEGETATION = ["grass", "leaf_cloud", "leaf_cloud_dense", "tree", "tree_poplar"]
#: Coordinates are computed in float64 from unit-size numbers.
COORD_ATOL = 1e-12
#: Metadata keys of every vegetation scene, of leaf clouds and trees, and of grass.
COMMON_KEYS = {"kind", "parameters", "foliage_mesh", "ground_y"}
CANOPY_KEYS = COMMON_KEYS | {"n_leaves", "leaf_area", "leaf_areas", "canopy_points", "canopy_center",
                             "canopy_radii", "canopy_volume", "leaf_area_density"}
GRASS_KEYS = COMMON_KEYS | {"n_blades", "blade_bases", "blade_tips", "blade_heights", "blade_tilts",
                            "blade_lengths", "blade_width", "blade_area", "field_size", "blade_density"}


# --------------------------------------------------------------------------------------
# helpers (independent of the code under test)
# --------------------------------------------------------------------------------------

def _foliage(scene):
    """(m, 3, 3) foliage triangles, read from the trimesh (not from the scene's arrays)."""
    mesh = scene.meshes[scene.metadata["foliage_mesh"]]
    return np.asarray(mesh.triangles, dtype=np.float64)


def _edges(tri):
    return np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)


def _barycentric(points, tri):
    """(n, m, 3) barycentric coordinates of each point in each triangle's plane, and (n, m)
    distance to that plane."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    n_hat = n / area2[:, None]
    d = points[:, None, :] - a[None]
    height = np.einsum("nmj,mj->nm", d, n_hat)
    q = points[:, None, :] - height[..., None] * n_hat[None]
    bary = []
    for u, v in ((b, c), (c, a), (a, b)):  # sub-triangle opposite each corner
        bary.append(np.einsum("nmj,mj->nm", np.cross(u[None] - q, v[None] - q), n_hat) / area2)
    return np.stack(bary, axis=-1), np.abs(height)


# --------------------------------------------------------------------------------------
# registry, determinism, openness
# --------------------------------------------------------------------------------------

def test_registered():
    assert set(VEGETATION) <= set(names())
    for name in VEGETATION:
        scene = get(name)
        assert isinstance(scene, Scene) and scene.name == name
        assert not scene.is_watertight
        assert scene.metadata["foliage_mesh"] in scene.meshes
    assert get("tree", kind="poplar").name == "tree_poplar"
    assert get("leaf_cloud_dense").metadata["n_leaves"] == 4 * get("leaf_cloud").metadata["n_leaves"]


@pytest.mark.parametrize("build", [
    lambda seed: leaf_cloud(300, seed=seed),
    lambda seed: leaf_cloud(300, shape="ellipsoid", radii=(1, 2, 0.5), seed=seed),
    lambda seed: tree("apple", n_leaves=400, seed=seed),
    lambda seed: tree_poplar(n_leaves=400, seed=seed),
    lambda seed: grass(300, seed=seed),
])
def test_deterministic_by_seed(build):
    a, b, c = build(7), build(7), build(8)
    assert list(a.meshes) == list(b.meshes)
    for key in a.meshes:
        np.testing.assert_array_equal(a.meshes[key].vertices, b.meshes[key].vertices)
        np.testing.assert_array_equal(a.meshes[key].faces, b.meshes[key].faces)
    assert scene_digest(a) == scene_digest(b) != scene_digest(c)
    foliage = a.metadata["foliage_mesh"]
    assert not np.array_equal(a.meshes[foliage].vertices, c.meshes[foliage].vertices)
    # a Generator is accepted and consumed like its seed
    np.testing.assert_array_equal(build(np.random.default_rng(7)).triangles, a.triangles)


def test_world_space_vo_is_refused():
    scene = leaf_cloud(100)
    points, normals = leaf_points(scene, 3, seed=0)
    with pytest.raises(ValueError, match="closed"):
        vo.volumetric_obscurance(scene, points, radius=0.2, samples=16)


def test_metadata_is_optional_and_outside_the_digest():
    import trimesh

    plain = Scene(trimesh.creation.box())
    assert plain.metadata == {}
    scene = grass(50, seed=1)
    bare = Scene(dict(scene.meshes), smooth_angle=scene.smooth_angle)
    assert scene_digest(bare) == scene_digest(scene)
    again = pickle.loads(pickle.dumps(scene))
    np.testing.assert_array_equal(again.metadata["blade_heights"], scene.metadata["blade_heights"])
    assert scene.scaled(2.0).metadata == {}
    with pytest.raises(ValueError, match="metadata"):
        Scene(trimesh.creation.box(), metadata=[1, 2])


# --------------------------------------------------------------------------------------
# leaf clouds
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("shape, radii", [("sphere", 1.5), ("ellipsoid", (0.5, 2.0, 1.0))])
def test_leaf_cloud_counts_sizes_and_volume(shape, radii):
    size = 0.08
    scene = leaf_cloud(700, shape=shape, radii=radii, leaf_size=size, seed=2)
    tri = _foliage(scene)
    meta = scene.metadata
    assert set(meta) >= CANOPY_KEYS and meta["kind"] == "leaf_cloud"
    assert len(tri) == meta["n_leaves"] == 700
    np.testing.assert_allclose(_edges(tri), size, rtol=1e-12)  # equilateral, side leaf_size
    r = np.broadcast_to(np.asarray(radii, float), (3,))
    np.testing.assert_array_equal(meta["canopy_radii"], r)
    np.testing.assert_array_equal(meta["canopy_center"], 0.0)
    centres = tri.mean(axis=1)
    np.testing.assert_allclose(meta["canopy_points"], centres, atol=COORD_ATOL)
    assert np.all(np.sum((centres / r) ** 2, axis=1) <= 1.0 + 1e-12)
    # corners within a circumradius of the volume: inside the ellipsoid grown by it
    assert np.all(np.sum((tri.reshape(-1, 3) / (r + size / np.sqrt(3))) ** 2, axis=1) <= 1.0 + 1e-12)
    # the centres fill the volume: the fraction within half the radii is 1/8
    inner = np.mean(np.sum((centres / r) ** 2, axis=1) <= 0.25)
    sd = np.sqrt(0.125 * 0.875 / 700)
    assert abs(inner - 0.125) < stats.norm.isf(FALSE_FAILURE / 2) * sd
    # area statistics against the triangles (trimesh's own areas)
    areas = scene.meshes["leaves"].area_faces
    np.testing.assert_allclose(meta["leaf_areas"], areas, rtol=1e-12)
    assert meta["leaf_area"] == pytest.approx(np.sqrt(3) / 4 * size**2, rel=1e-12)
    assert meta["leaf_area"] == pytest.approx(areas.mean(), rel=1e-12)
    volume = 4 / 3 * np.pi * np.prod(r)
    assert meta["canopy_volume"] == pytest.approx(volume, rel=1e-12)
    assert meta["leaf_area_density"] == pytest.approx(700 * areas.mean() / volume, rel=1e-12)
    assert meta["ground_y"] is None


def test_leaf_cloud_validation():
    with pytest.raises(ValueError, match="radii"):
        leaf_cloud(10, radii=(1, 2, 1))  # a sphere needs equal radii
    with pytest.raises(ValueError, match="shape"):
        leaf_cloud(10, shape="cube")
    with pytest.raises(ValueError, match="n_leaves"):
        leaf_cloud(0)
    with pytest.raises(ValueError, match="leaf_size"):
        leaf_cloud(10, leaf_size=-1.0)
    assert leaf_cloud_dense(50, radii=0.5).metadata["canopy_radii"].tolist() == [0.5] * 3


# --------------------------------------------------------------------------------------
# trees
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["apple", "poplar"])
def test_tree_structure(kind):
    scene = tree(kind, n_leaves=900, n_clusters=30, leaf_size=0.12, seed=4)
    meta = scene.metadata
    assert set(meta) >= CANOPY_KEYS | {"n_clusters", "cluster_centers"} and meta["kind"] == "tree"
    assert sorted(scene.meshes) == ["ground", "leaves", "wood"]
    tri = _foliage(scene)
    assert len(tri) == meta["n_leaves"] == 900 and meta["n_clusters"] == 30
    assert meta["cluster_centers"].shape == (30, 3)
    edges = _edges(tri)
    np.testing.assert_allclose(edges, np.repeat(edges[:, :1], 3, axis=1), rtol=1e-9)  # equilateral
    assert edges.min() >= 0.7 * 0.12 * (1 - 1e-12) and edges.max() <= 1.3 * 0.12 * (1 + 1e-12)
    c, r = meta["canopy_center"], meta["canopy_radii"]
    centres = tri.mean(axis=1)
    np.testing.assert_allclose(meta["canopy_points"], centres, atol=COORD_ATOL)
    assert np.all(np.sum(((centres - c) / r) ** 2, axis=1) <= 1.0 + 1e-12)
    areas = scene.meshes["leaves"].area_faces
    assert meta["leaf_area"] == pytest.approx(areas.mean(), rel=1e-12)
    assert meta["leaf_area_density"] == pytest.approx(areas.sum() / (4 / 3 * np.pi * np.prod(r)),
                                                      rel=1e-12)
    # standing on the ground: the wood starts on it, nothing goes below it
    g = meta["ground_y"]
    assert g == 0.0
    assert np.all(scene.meshes["ground"].vertices[:, 1] == g)
    assert scene.meshes["wood"].vertices[:, 1].min() == pytest.approx(g, abs=1e-12)
    assert scene.triangles[..., 1].min() >= g - 1e-12
    assert scene.meshes["wood"].body_count > 1  # trunk, limbs and twigs: capped frusta
    assert all(part.is_watertight for part in scene.meshes["wood"].split(only_watertight=False)[:5])
    # the shapes: the poplar is tall and narrow, the apple round
    if kind == "poplar":
        assert r[1] > 3 * r[0]
    else:
        assert r[1] < r[0] * 1.2


def test_tree_validation():
    with pytest.raises(ValueError, match="kind"):
        tree("oak")
    with pytest.raises(ValueError, match="n_clusters"):
        tree(n_leaves=10, n_clusters=20)
    with pytest.raises(ValueError, match="cluster_radius"):
        tree(cluster_radius=5.0)


# --------------------------------------------------------------------------------------
# grass
# --------------------------------------------------------------------------------------

def test_grass_blades():
    h, spread, tilt, width, size = 0.4, 0.25, 35.0, 0.03, 3.0
    scene = grass(800, height=h, height_spread=spread, tilt=tilt, width=width, size=size, seed=5)
    meta = scene.metadata
    assert set(meta) >= GRASS_KEYS and meta["kind"] == "grass"
    tri = _foliage(scene)
    assert len(tri) == meta["n_blades"] == 800
    g = meta["ground_y"]
    heights = meta["blade_heights"]
    assert np.all(heights >= h * (1 - spread)) and np.all(heights <= h * (1 + spread))
    # the heights fill the spread: uniform, so a Kolmogorov-Smirnov test
    assert stats.kstest(heights, stats.uniform(h * (1 - spread), 2 * h * spread).cdf).pvalue > FALSE_FAILURE
    # geometry agrees with the metadata
    bases = 0.5 * (tri[:, 0] + tri[:, 1])
    np.testing.assert_allclose(meta["blade_bases"], bases, atol=COORD_ATOL)
    np.testing.assert_array_equal(meta["blade_tips"], tri[:, 2])
    assert np.all(tri[:, :2, 1] == g)
    np.testing.assert_allclose(tri[:, 2, 1] - g, heights, atol=COORD_ATOL)
    np.testing.assert_allclose(np.linalg.norm(tri[:, 1] - tri[:, 0], axis=1), width, rtol=1e-12)
    axis = tri[:, 2] - bases
    lengths = np.linalg.norm(axis, axis=1)
    np.testing.assert_allclose(meta["blade_lengths"], lengths, rtol=1e-9)
    np.testing.assert_allclose(meta["blade_tilts"], np.degrees(np.arccos(axis[:, 1] / lengths)),
                               atol=1e-6)
    assert np.all(meta["blade_tilts"] >= 0) and np.all(meta["blade_tilts"] <= tilt)
    assert np.all(np.abs(bases[:, [0, 2]]) <= size / 2)
    assert meta["blade_area"] == pytest.approx(scene.meshes["blades"].area_faces.mean(), rel=1e-12)
    assert meta["blade_density"] == pytest.approx(800 / size**2)
    # the blade leans across its base edge (the axis is perpendicular to it)
    np.testing.assert_allclose(np.einsum("ij,ij->i", axis, tri[:, 1] - tri[:, 0]), 0.0, atol=1e-12)


def test_grass_validation():
    with pytest.raises(ValueError, match="height_spread"):
        grass(10, height_spread=1.0)
    with pytest.raises(ValueError, match="tilt"):
        grass(10, tilt=90.0)
    assert np.all(grass(20, height_spread=0.0, tilt=0.0).metadata["blade_heights"] == 0.3)


# --------------------------------------------------------------------------------------
# rendering and AO on every registered scene
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", VEGETATION)
def test_renders_and_ao(name):
    scene = get(name)
    gb = vo.render_gbuffer(scene, scene.camera((48, 48)))
    assert gb.valid.mean() > 0.2  # the suggested view frames the scene
    # two-sided: every normal faces the camera (against the view ray to the point)
    assert np.all(np.einsum("ij,ij->i", gb.geometric_normal[gb.valid], gb.position[gb.valid]) <= 0)
    points, normals = leaf_points(scene, 6, seed=1)
    ao = vo.ambient_occlusion(scene, points, normals, rays=32, seed=0)
    assert ao.value.shape == (6,) and np.all((ao.value >= 0) & (ao.value <= 1))
    ref = vo.ground_truth(scene, gb, quantity="ao", radius=0.1 * scene.extent, rays=8, seed=0)
    assert np.all(np.isfinite(ref.value[gb.valid]))


# --------------------------------------------------------------------------------------
# leaf_points
# --------------------------------------------------------------------------------------

def test_leaf_points_uniform_by_area():
    """Chi-square test over cells of equal area: each blade cut into its four midpoint
    sub-triangles; expected counts n * area(cell) / total area. Blade areas vary twenty-fold
    (height_spread 0.9), so a sampler that picked triangles by count would fail. The test
    fails with probability FALSE_FAILURE when the sampler is right."""
    scene = grass(60, height_spread=0.9, seed=3)
    tri = _foliage(scene)
    n = 30_000
    points, normals = leaf_points(scene, n, seed=11)
    bary, dist = _barycentric(points, tri)
    inside = np.all(bary >= -1e-9, axis=2) & (dist <= 1e-9)
    assert np.all(inside.sum(axis=1) >= 1)  # every point lies on a blade
    which = np.argmax(inside, axis=1)
    b = bary[np.arange(n), which]
    corner = np.argmax(b, axis=1)
    cell = np.where(b.max(axis=1) > 0.5, corner, 3)  # three corner sub-triangles and the middle one
    observed = np.bincount(4 * which + cell, minlength=4 * len(tri))
    areas = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    expected = np.repeat(n * areas / areas.sum() / 4, 4)
    assert expected.min() >= 5  # the chi-square approximation holds
    assert stats.chisquare(observed, expected).pvalue > FALSE_FAILURE
    # the normals are the blades' normals, turned up
    face = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    face /= np.linalg.norm(face, axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", normals, face[which])), 1.0, atol=1e-12)
    assert np.all(normals[:, 1] >= 0)


def test_leaf_points_orientation_and_determinism():
    scene = tree(n_leaves=500, seed=1)
    p, nrm = leaf_points(scene, 400, seed=2)
    np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", nrm, p - scene.metadata["canopy_center"]) >= 0)  # outward
    p2, n2 = leaf_points(scene, 400, seed=2)
    np.testing.assert_array_equal(p, p2)
    np.testing.assert_array_equal(nrm, n2)
    _, up = leaf_points(scene, 400, seed=2, orient="up")
    assert np.all(up[:, 1] >= 0)
    _, geo = leaf_points(scene, 400, seed=2, orient="geometric")
    np.testing.assert_allclose(np.abs(geo), np.abs(nrm), atol=1e-12)
    leaves = set(map(tuple, np.round(scene.meshes["leaves"].face_normals, 12)))
    assert all(tuple(v) in leaves for v in np.round(geo, 12))  # only leaves, never wood or ground
    with pytest.raises(ValueError, match="foliage"):
        leaf_points(vo.scenes.slab(), 3)
    with pytest.raises(ValueError, match="outward"):
        leaf_points(grass(10), 3, orient="outward")
