"""Tests of vobscure.scenes: procedural builders, the registry and the mesh loader."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from vobscure import scenes
from vobscure.scenes import (
    Scene,
    blob,
    cornell_box,
    crease,
    get,
    groove,
    load,
    names,
    slab,
    sphere_on_plane,
    steps,
)
from vobscure.scenes.io import SUPPORTED_EXTENSIONS, DegenerateFacesWarning
from vobscure.scenes.procedural import _extrude, _signed_area

#: Relative tolerance of analytic volumes (exact up to float64 rounding).
VOLUME_RTOL = 1e-9
#: Absolute tolerance of coordinates of scenes of unit-ish size.
COORD_ATOL = 1e-12
#: Relative volume tolerance after a float32 file format (STL, GLB) round trip.
FLOAT32_RTOL = 1e-6

ALL_BUILDERS = ["blob", "cornell_box", "crease", "groove", "slab", "sphere_on_plane", "steps"]
#: The registered vegetation scenes (open foliage; tested in test_vegetation.py).
VEGETATION = ["grass", "leaf_cloud", "leaf_cloud_dense", "tree", "tree_poplar"]
#: The registered interiors: the atrium (open banners, alpha-tested leaves; tested in
#: test_atrium.py) and the thin occluders (closed; tested in test_thin_scene.py).
INTERIORS = ["atrium", "thin_occluders"]
MESH_DIR = Path(__file__).resolve().parents[2] / "shared/data/meshes"


# --------------------------------------------------------------------------------------
# helpers (independent of the code under test)
# --------------------------------------------------------------------------------------

def _point_triangle_distance(p, tri):
    """Distance from point p (3,) to each triangle of tri (m, 3, 3)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    height = np.einsum("ij,ij->i", p - a, n)
    q = p - height[:, None] * n
    inside = np.ones(len(tri), dtype=bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, q - u), n) >= 0
    best = np.full(len(tri), np.inf)
    for u, v in ((a, b), (b, c), (c, a)):
        d = v - u
        s = np.clip(np.einsum("ij,ij->i", p - u, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(p - (u + s[:, None] * d), axis=1))
    return np.where(inside, np.abs(height), best)


def _edge_directions(mesh):
    d = mesh.vertices[mesh.edges_unique[:, 1]] - mesh.vertices[mesh.edges_unique[:, 0]]
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _separated(a, b, tol):
    """True when convex meshes a and b have disjoint interiors (separating axis theorem)."""
    axes = [a.face_normals, b.face_normals]
    ea, eb = _edge_directions(a), _edge_directions(b)
    cross = np.cross(ea[:, None, :], eb[None, :, :]).reshape(-1, 3)
    length = np.linalg.norm(cross, axis=1)
    axes.append(cross[length > 1e-9] / length[length > 1e-9, None])
    for n in np.concatenate(axes):
        pa, pb = a.vertices @ n, b.vertices @ n
        if pa.max() <= pb.min() + tol or pb.max() <= pa.min() + tol:
            return True
    return False


def _assert_closed_solid(mesh):
    assert mesh.is_watertight
    assert mesh.is_winding_consistent
    assert mesh.volume > 0


# --------------------------------------------------------------------------------------
# every builder
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ALL_BUILDERS)
def test_builder_gives_closed_solids_and_a_view(name):
    scene = get(name)
    assert isinstance(scene, Scene)
    assert scene.name == name
    assert scene.is_watertight
    for mesh in scene.meshes.values():
        _assert_closed_solid(mesh)
    view = scene.view
    assert {"eye", "target", "up"} <= set(view)
    assert ("fov_y" in view) != ("ortho_height" in view)
    eye, target = np.asarray(view["eye"]), np.asarray(view["target"])
    lo, hi = scene.bounds
    # the camera stands outside the geometry and looks at something inside its box
    assert np.any((eye < lo) | (eye > hi))
    assert np.all((target >= lo) & (target <= hi))


@pytest.mark.parametrize("name", ["cornell_box", "crease", "groove", "slab", "steps"])
def test_polyhedral_scenes_are_flat_shaded(name):
    scene = get(name)
    flat = np.repeat(scene.face_normals[:, None, :], 3, axis=1)
    np.testing.assert_array_equal(scene.corner_normals, flat)


def test_curved_scenes_are_smooth_shaded():
    scene = sphere_on_plane(subdivisions=2)
    flat = np.repeat(scene.face_normals[:, None, :], 3, axis=1)
    on_sphere = scene.mesh_index == list(scene.meshes).index("sphere")
    assert not np.allclose(scene.corner_normals[on_sphere], flat[on_sphere])
    np.testing.assert_array_equal(scene.corner_normals[~on_sphere], flat[~on_sphere])
    b = blob(subdivisions=2)
    assert not np.allclose(b.corner_normals, np.repeat(b.face_normals[:, None, :], 3, axis=1))


@pytest.mark.parametrize("call, argument", [
    (lambda: slab(size=-1.0), "size"),
    (lambda: slab(size=float("nan")), "size"),
    (lambda: slab(thickness=0.0), "thickness"),
    (lambda: crease(length=0.0), "length"),
    (lambda: crease(height=float("inf")), "height"),
    (lambda: crease(depth="4"), "depth"),
    (lambda: crease(thickness=-1.0), "thickness"),
    (lambda: groove(0.0), "angle"),
    (lambda: groove(180.0), "angle"),
    (lambda: groove(float("nan")), "angle"),
    (lambda: groove(90.0, depth=4.0, width=8.0), "width"),
    (lambda: groove(length=0.0), "length"),
    (lambda: sphere_on_plane(radius=0.0), "radius"),
    (lambda: sphere_on_plane(radius=4.0, size=8.0), "size"),
    (lambda: sphere_on_plane(subdivisions=9), "subdivisions"),
    (lambda: sphere_on_plane(subdivisions=2.0), "subdivisions"),
    (lambda: steps(count=0), "count"),
    (lambda: steps(count=1.5), "count"),
    (lambda: steps(rise=0.0), "rise"),
    (lambda: steps(run=-1.0), "run"),
    (lambda: steps(width=0.0), "width"),
    (lambda: blob(amplitude=0.7), "amplitude"),
    (lambda: blob(amplitude=-0.1), "amplitude"),
    (lambda: blob(detail=0), "detail"),
    (lambda: blob(seed=-1), "seed"),
    (lambda: blob(subdivisions=-1), "subdivisions"),
])
def test_bad_arguments_name_the_argument(call, argument):
    with pytest.raises(ValueError, match=argument):
        call()


def test_parameters_are_keyword_only():
    with pytest.raises(TypeError):
        slab(8.0)  # noqa
    with pytest.raises(TypeError):
        crease(4.0)  # noqa
    assert groove(60.0).is_watertight  # the angle alone may be positional


# --------------------------------------------------------------------------------------
# the extrusion helper
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(8))
def test_extrude_concave_star_polygons(seed):
    rng = np.random.default_rng(seed)
    k = int(rng.integers(5, 40))
    theta = np.sort(rng.uniform(0, 2 * np.pi, k))
    theta = theta[np.diff(np.r_[theta, theta[0] + 2 * np.pi]) > 1e-3]
    r = rng.uniform(0.2, 1.0, len(theta))
    poly = np.column_stack([r * np.cos(theta), r * np.sin(theta)]) + rng.normal(size=2)
    # shoelace area, written out independently of the module's helper
    x, y = poly[:, 0], poly[:, 1]
    area = 0.5 * sum(x[i] * y[(i + 1) % len(x)] - x[(i + 1) % len(x)] * y[i] for i in range(len(x)))
    mesh = _extrude(poly, -0.3, 0.9)
    _assert_closed_solid(mesh)
    assert len(mesh.faces) == 2 * (len(poly) - 2) + 2 * len(poly)
    assert mesh.volume == pytest.approx(area * 1.2, rel=VOLUME_RTOL)
    # the caps cover the polygon once: their areas add up to the polygon's
    caps = np.abs(mesh.face_normals[:, 2]) > 0.5
    assert mesh.area_faces[caps].sum() == pytest.approx(2 * area, rel=VOLUME_RTOL)


def test_extrude_comb_polygon():
    # a comb: deep, narrow notches make most vertices reflex or blocked
    teeth = 6
    top = []
    for i in range(teeth):
        top += [(2 * i + 1, 5.0), (2 * i + 1, 1.0), (2 * i + 2, 1.0), (2 * i + 2, 5.0)]
    poly = np.array([(0.0, 0.0), (2 * teeth + 1, 0.0), (2 * teeth + 1, 5.0)] + top[::-1] + [(0.0, 5.0)])
    assert _signed_area(poly) == pytest.approx((2 * teeth + 1) * 5.0 - teeth * 4.0)
    mesh = _extrude(poly, 0.0, 2.0)
    _assert_closed_solid(mesh)
    assert mesh.volume == pytest.approx(2.0 * ((2 * teeth + 1) * 5.0 - teeth * 4.0), rel=VOLUME_RTOL)


def test_extrude_rejects_clockwise_and_bad_input():
    square = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
    with pytest.raises(ValueError, match="counter-clockwise"):
        _extrude(square[::-1], 0.0, 1.0)
    with pytest.raises(ValueError, match="z1"):
        _extrude(square, 1.0, 1.0)
    with pytest.raises(ValueError, match="polygon_xy"):
        _extrude(square[:2], 0.0, 1.0)


# --------------------------------------------------------------------------------------
# slab, crease, groove, steps
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("size, thickness", [(8.0, 1.0), (0.3, 0.05), (1e3, 7.0)])
def test_slab_geometry(size, thickness):
    mesh = slab(size=size, thickness=thickness).meshes["slab"]
    assert mesh.volume == pytest.approx(size * size * thickness, rel=VOLUME_RTOL)
    up = mesh.face_normals[:, 1] > 0.5
    np.testing.assert_allclose(mesh.face_normals[up], [[0.0, 1.0, 0.0]] * int(up.sum()), atol=COORD_ATOL)
    assert np.all(mesh.triangles[up][:, :, 1] == 0.0)
    assert mesh.area_faces[up].sum() == pytest.approx(size * size, rel=VOLUME_RTOL)
    np.testing.assert_allclose(mesh.bounds, [[-size / 2, -thickness, -size / 2], [size / 2, 0, size / 2]])


@pytest.mark.parametrize("L, H, D, t", [(4.0, 4.0, 8.0, 1.0), (2.0, 3.0, 5.0, 0.25), (10.0, 0.5, 1.0, 2.0)])
def test_crease_volume(L, H, D, t):
    mesh = crease(length=L, height=H, depth=D, thickness=t).meshes["crease"]
    assert mesh.volume == pytest.approx((t * (L + t) + t * H) * D, rel=VOLUME_RTOL)
    np.testing.assert_allclose(mesh.bounds, [[-t, -t, -D / 2], [L, H, D / 2]])


def test_crease_floor_and_wall():
    scene = crease()
    mesh = scene.meshes["crease"]
    tri = mesh.triangles
    for a in (0.1, 0.5, 1.0):
        p = np.array([a, 0.0, 0.0])
        d = _point_triangle_distance(p, tri)
        assert d.min() == 0.0
        closest = d == 0.0
        # the closest triangles are on the floor's top face, facing +y
        np.testing.assert_allclose(mesh.face_normals[closest], [[0, 1, 0]] * int(closest.sum()),
                                   atol=COORD_ATOL)
    plus_x = mesh.face_normals[:, 0] > 0.5
    wall = plus_x & (tri[:, :, 0].max(axis=1) < 1.0)   # the wall face, not the floor's end
    assert np.all(tri[wall][:, :, 0] == 0.0)
    assert mesh.area_faces[wall].sum() == pytest.approx(4.0 * 8.0, rel=VOLUME_RTOL)  # H * depth
    # every +x face is either the wall face x = 0 or the floor's far end x = L
    assert set(np.unique(tri[plus_x][:, :, 0])) == {0.0, 4.0}
    # the closed forms hold for radii up to 1.5 around (a, 0, 0), a <= 1: the ball's part
    # below the floor and behind the wall is solid, the rest of it is free
    R, a_max = 1.5, 1.0
    lo, hi = mesh.bounds
    assert lo[1] <= -R and lo[0] <= -R           # thick enough for the whole ball
    assert hi[0] >= a_max + R and hi[1] >= R     # the floor and wall reach past the ball
    assert hi[2] >= R and lo[2] <= -R


@pytest.mark.parametrize("angle", [20.0, 60.0, 90.0, 120.0, 170.0])
def test_groove_wall_angle_and_volume(angle):
    depth, width, length, thickness = 1.0, 30.0, 3.0, 0.5
    mesh = groove(angle, depth=depth, width=width, length=length, thickness=thickness).meshes["groove"]
    beta = math.radians(angle / 2)
    volume = (width * (depth + thickness) - depth**2 * math.tan(beta)) * length
    assert mesh.volume == pytest.approx(volume, rel=VOLUME_RTOL)
    n = mesh.face_normals
    slanted = (np.abs(n[:, 0]) > 1e-6) & (np.abs(n[:, 1]) > 1e-6)
    left, right = n[slanted & (n[:, 0] > 0)], n[slanted & (n[:, 0] < 0)]
    assert len(left) == 2 and len(right) == 2
    np.testing.assert_allclose(left, [[math.cos(beta), math.sin(beta), 0.0]] * 2, atol=1e-12)
    np.testing.assert_allclose(right, [[-math.cos(beta), math.sin(beta), 0.0]] * 2, atol=1e-12)
    between = math.degrees(math.acos(np.clip(left[0] @ right[0], -1.0, 1.0)))
    assert between == pytest.approx(180.0 - angle, abs=1e-9)
    # the apex line is the lowest point of the free space, on the z axis
    apex = mesh.vertices[(np.abs(mesh.vertices[:, 0]) < 1e-12) & (np.abs(mesh.vertices[:, 1]) < 1e-12)]
    assert len(apex) == 2


@pytest.mark.parametrize("count, rise, run, width",
                         [(1, 1.0, 1.0, 1.0), (4, 0.25, 0.5, 2.0), (12, 0.17, 0.3, 1.0)])
def test_steps_volume_and_treads(count, rise, run, width):
    mesh = steps(count=count, rise=rise, run=run, width=width).meshes["steps"]
    assert mesh.volume == pytest.approx(rise * run * count * (count + 1) / 2 * width, rel=VOLUME_RTOL)
    up = mesh.face_normals[:, 1] > 0.5
    heights = np.unique(np.round(mesh.triangles[up][:, :, 1] / rise, 9))
    np.testing.assert_allclose(heights, np.arange(1, count + 1))
    assert mesh.area_faces[up].sum() == pytest.approx(count * run * width, rel=VOLUME_RTOL)
    riser = mesh.face_normals[:, 0] < -0.5
    assert mesh.area_faces[riser].sum() == pytest.approx(count * rise * width, rel=VOLUME_RTOL)


# --------------------------------------------------------------------------------------
# sphere on plane
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("radius, subdivisions", [(1.0, 4), (0.37, 0), (2.5, 2)])
def test_sphere_rests_on_the_floor(radius, subdivisions):
    scene = sphere_on_plane(radius=radius, size=8.0 * radius, thickness=radius, subdivisions=subdivisions)
    floor, sphere = scene.meshes["floor"], scene.meshes["sphere"]
    assert len(sphere.faces) == 20 * 4**subdivisions
    assert floor.volume == pytest.approx(64.0 * radius**3, rel=VOLUME_RTOL)
    v = sphere.vertices
    np.testing.assert_allclose(np.linalg.norm(v - [0, radius, 0], axis=1), radius, rtol=1e-12)
    lowest = np.argmin(v[:, 1])
    np.testing.assert_array_equal(v[lowest], [0.0, 0.0, 0.0])  # touches at one point
    assert np.all(np.delete(v[:, 1], lowest) > 0.0)             # and nowhere else
    assert sphere.volume < 4 / 3 * math.pi * radius**3


# --------------------------------------------------------------------------------------
# Cornell box
# --------------------------------------------------------------------------------------

def test_cornell_box_layout():
    scene = cornell_box()
    assert list(scene.meshes) == ["floor", "ceiling", "back_wall", "left_wall", "right_wall",
                                  "short_box", "tall_box"]
    m = scene.meshes
    T = 0.1
    volumes = {"floor": 2.2 * T * 2.1, "ceiling": 2.2 * T * 2.1, "back_wall": 2.2 * 2.0 * T,
               "left_wall": T * 2.0 * 2.0, "right_wall": T * 2.0 * 2.0,
               "short_box": 0.6 * 0.6 * 0.6, "tall_box": 0.6 * 1.2 * 0.6}
    for key, volume in volumes.items():
        assert m[key].volume == pytest.approx(volume, rel=VOLUME_RTOL), key
    # the interior x in [-1, 1], y in [0, 2], z in [-1, 1] is bounded by the walls' inner faces
    assert m["floor"].bounds[1, 1] == 0.0 and m["ceiling"].bounds[0, 1] == 2.0
    assert m["left_wall"].bounds[1, 0] == -1.0 and m["right_wall"].bounds[0, 0] == 1.0
    assert m["back_wall"].bounds[1, 2] == -1.0
    assert scene.bounds[1, 2] == 1.0  # open toward +z
    for key, height in (("short_box", 0.6), ("tall_box", 1.2)):
        lo, hi = m[key].bounds
        assert lo[1] == pytest.approx(0.0, abs=COORD_ATOL) and hi[1] == pytest.approx(height)
        assert np.all(lo[[0, 2]] > -1.0) and np.all(hi[[0, 2]] < 1.0)
    assert m["short_box"].centroid[0] > 0 and m["short_box"].centroid[2] > 0   # front right
    assert m["tall_box"].centroid[0] < 0 and m["tall_box"].centroid[2] < 0     # back left
    # rotations: the boxes' side normals are turned by -17 and +17 degrees about y
    for key, angle in (("short_box", -17.0), ("tall_box", 17.0)):
        n = m[key].face_normals
        side = n[np.abs(n[:, 1]) < 0.5]
        turned = {round(math.degrees(math.atan2(-z, x)) % 90.0, 6) for x, _, z in side}
        assert turned == {round(angle % 90.0, 6)}
    view = scene.view
    assert view["eye"] == (0.0, 1.0, 3.9) and view["target"] == (0.0, 1.0, 0.0)
    assert view["fov_y"] == pytest.approx(39.0)


def test_cornell_box_solids_do_not_interpenetrate():
    meshes = list(cornell_box().meshes.values())
    tol = 1e-12
    for i in range(len(meshes)):
        for j in range(i + 1, len(meshes)):
            assert _separated(meshes[i], meshes[j], tol), (i, j)
    # the check does see an overlap when there is one
    a = trimesh.creation.box(extents=(1, 1, 1))
    b = trimesh.creation.box(extents=(1, 1, 1),
                             transform=trimesh.transformations.rotation_matrix(0.3, (0, 1, 0)) @
                             trimesh.transformations.translation_matrix((0.9, 0, 0)))
    assert not _separated(a, b, tol)


# --------------------------------------------------------------------------------------
# blob
# --------------------------------------------------------------------------------------

def test_blob_is_deterministic_per_seed():
    a = blob(seed=3).meshes["blob"].vertices
    b = blob(seed=3).meshes["blob"].vertices
    c = blob(seed=4).meshes["blob"].vertices
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    g = blob(seed=np.random.default_rng(3)).meshes["blob"].vertices
    np.testing.assert_array_equal(a, g)


@pytest.mark.parametrize("seed", [0, 1, 7])
@pytest.mark.parametrize("amplitude", [0.1, 0.25, 0.6])
def test_blob_is_star_shaped_with_concavities(seed, amplitude):
    mesh = blob(subdivisions=3, amplitude=amplitude, seed=seed).meshes["blob"]
    _assert_closed_solid(mesh)
    r = np.linalg.norm(mesh.vertices, axis=1)
    assert r.min() >= 1.0 - amplitude - 1e-12 and r.max() <= 1.0 + amplitude + 1e-12
    assert np.max(np.abs(r - 1.0)) == pytest.approx(amplitude)
    assert r.min() < 1.0 < r.max()  # bumps and dents
    # star-shaped: every face faces away from the origin
    centres = mesh.triangles.mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", mesh.face_normals, centres) > 0)
    # concave edges: some neighbouring faces meet at a reflex dihedral angle
    assert not np.all(mesh.face_adjacency_convex)


def test_blob_default_has_many_concave_edges():
    mesh = blob().meshes["blob"]
    assert len(mesh.faces) == 20 * 4**4
    assert np.mean(~mesh.face_adjacency_convex) > 0.02


def test_blob_zero_amplitude_is_a_unit_sphere():
    mesh = blob(subdivisions=2, amplitude=0.0).meshes["blob"]
    np.testing.assert_allclose(np.linalg.norm(mesh.vertices, axis=1), 1.0, rtol=1e-12)
    assert np.all(mesh.face_adjacency_convex)


# --------------------------------------------------------------------------------------
# registry
# --------------------------------------------------------------------------------------

def test_registry_names_and_get():
    assert names() == sorted(ALL_BUILDERS + VEGETATION + INTERIORS)
    assert get("groove", angle=45.0, depth=1.0).meshes["groove"].volume == pytest.approx(
        groove(45.0, depth=1.0).meshes["groove"].volume)
    assert get("crease", length=2.0).bounds[1, 0] == 2.0


def test_registry_bad_name_lists_the_names():
    with pytest.raises(ValueError) as info:
        get("sponza")
    for n in ALL_BUILDERS:
        assert repr(n) in str(info.value)
    with pytest.raises(ValueError, match="name"):
        get(3)


def test_registry_bad_keyword():
    with pytest.raises(ValueError, match="slab"):
        get("slab", radius=1.0)


def test_package_exports():
    expected = {"Scene", "load", "names", "get", "slab", "crease", "groove", "sphere_on_plane",
                "steps", "cornell_box", "blob"}
    assert expected <= set(scenes.__all__)
    for n in scenes.__all__:
        assert hasattr(scenes, n)


# --------------------------------------------------------------------------------------
# loading files
# --------------------------------------------------------------------------------------

REAL_MESHES = {
    # file: (triangles, watertight)
    "stanford-bunny.obj": (69451, False),
    "spot.obj": (5856, True),
    "teapot.obj": (6320, False),
    "CornellBox-Original.obj": (36, False),
}


@pytest.mark.parametrize("filename", sorted(REAL_MESHES))
def test_real_meshes_load(filename):
    path = MESH_DIR / filename
    if not path.is_file():
        pytest.skip(f"real mesh {path} is absent (the shared data folder is not on this machine)")
    scene = load(path)  # warnings are errors: no degenerate faces are dropped
    triangles, watertight = REAL_MESHES[filename]
    assert len(scene.triangles) == triangles
    assert scene.is_watertight == watertight
    assert scene.name == path.stem
    if filename == "spot.obj":
        # watertight only once the texture seams are merged
        assert scene.meshes["spot"].volume > 0
    if filename == "CornellBox-Original.obj":
        assert len(scene.meshes) >= 7   # one mesh per OBJ group
        assert {"floor", "ceiling", "backWall", "rightWall", "light"} <= set(scene.meshes)
        assert scene.bounds[0, 1] == 0.0 and scene.bounds[1, 1] == pytest.approx(1.99)
    else:
        assert list(scene.meshes) == [path.stem]


@pytest.mark.parametrize("ext", [".obj", ".ply", ".stl", ".glb"])
@pytest.mark.parametrize("builder", ["crease", "blob"])
def test_round_trip(tmp_path, ext, builder):
    original = get(builder, subdivisions=2) if builder == "blob" else get(builder)
    mesh = original.meshes[builder]
    path = tmp_path / f"solid{ext}"
    mesh.export(path)
    scene = scenes.load(path)
    assert list(scene.meshes) == ["solid"]
    loaded = scene.meshes["solid"]
    assert len(loaded.faces) == len(mesh.faces)
    assert scene.is_watertight
    assert loaded.volume == pytest.approx(mesh.volume, rel=FLOAT32_RTOL)


def test_round_trip_multi_mesh_glb_applies_transforms(tmp_path):
    original = cornell_box()
    graph = trimesh.Scene()
    shift = np.array([0.5, -2.0, 3.0])
    for key, mesh in original.meshes.items():
        # store each mesh about its own centre and put it back with the node's transform
        centre = mesh.bounds.mean(axis=0)
        local = mesh.copy()
        local.apply_translation(-centre)
        graph.add_geometry(local, node_name=key, geom_name=key + "_geometry",
                           transform=trimesh.transformations.translation_matrix(centre + shift))
    path = tmp_path / "cornell.glb"
    graph.export(path)
    scene = load(path, name="cornell", smooth_angle=0.0)
    assert scene.name == "cornell"
    assert set(scene.meshes) == set(original.meshes)
    for key, mesh in original.meshes.items():
        np.testing.assert_allclose(scene.meshes[key].bounds, mesh.bounds + shift, atol=1e-6)
        assert scene.meshes[key].volume == pytest.approx(mesh.volume, rel=FLOAT32_RTOL)


def test_mirroring_transform_keeps_outward_normals(tmp_path):
    graph = trimesh.Scene()
    graph.add_geometry(trimesh.creation.box(), node_name="a")
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0]) @ trimesh.transformations.translation_matrix((3, 0, 0))
    graph.add_geometry(trimesh.creation.box(), node_name="b", transform=mirror)
    path = tmp_path / "mirror.glb"
    graph.export(path)
    scene = scenes.load(path)
    assert set(scene.meshes) == {"a", "b"}
    assert scene.meshes["b"].volume == pytest.approx(1.0, rel=FLOAT32_RTOL)
    assert scene.meshes["b"].bounds[0, 0] == pytest.approx(-3.5)


def test_obj_groups_become_named_meshes(tmp_path):
    path = tmp_path / "two.obj"
    a = trimesh.creation.box()
    lines = [f"v {x} {y} {z}" for x, y, z in a.vertices]
    lines += [f"v {x + 2} {y} {z}" for x, y, z in a.vertices]
    lines += ["g left"] + [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in a.faces]
    lines += ["g right"] + [f"f {i + 9} {j + 9} {k + 9}" for i, j, k in a.faces]
    path.write_text("\n".join(lines) + "\n")
    scene = scenes.load(path)
    assert set(scene.meshes) == {"left", "right"}
    assert scene.is_watertight
    assert scene.meshes["right"].bounds[0, 0] == pytest.approx(1.5)


def test_load_missing_file(tmp_path):
    path = tmp_path / "nowhere" / "bunny.obj"
    with pytest.raises(FileNotFoundError, match="bunny.obj"):
        load(path)


def test_load_unsupported_extension(tmp_path):
    path = tmp_path / "points.xyz"
    path.write_text("0 0 0\n1 0 0\n0 1 0\n")
    with pytest.raises(ValueError, match=r"\.xyz") as info:
        load(path)
    for ext in SUPPORTED_EXTENSIONS:
        assert ext in str(info.value)


@pytest.mark.parametrize("ext", [".obj", ".ply", ".stl", ".glb"])
def test_load_empty_file(tmp_path, ext):
    path = tmp_path / f"empty{ext}"
    path.write_bytes(b"")
    with pytest.raises(ValueError, match="empty"):
        load(path)


@pytest.mark.parametrize("text", ["# only a comment\n", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"])
def test_load_file_without_triangles(tmp_path, text):
    path = tmp_path / "nothing.obj"
    path.write_text(text)
    with pytest.raises(ValueError, match="no triangles"):
        load(path)


@pytest.mark.parametrize("ext", [".obj", ".ply", ".stl"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_load_rejects_nan_and_inf_vertices(tmp_path, ext, bad):
    mesh = trimesh.creation.box()
    vertices = np.array(mesh.vertices)
    vertices[3, 1] = bad
    broken = trimesh.Trimesh(vertices, mesh.faces, process=False)
    path = tmp_path / f"broken{ext}"
    with np.errstate(invalid="ignore"):  # trimesh computes normals of the broken face
        broken.export(path)
    with pytest.raises(ValueError, match="NaN or inf"):
        load(path)


def test_load_drops_degenerate_faces_with_a_warning(tmp_path):
    box = trimesh.creation.box()
    lines = [f"v {x} {y} {z}" for x, y, z in box.vertices]
    lines += ["v 2 0 0", "v 3 0 0", "v 4 0 0"]                       # three collinear points
    lines += [f"f {i + 1} {j + 1} {k + 1}" for i, j, k in box.faces]
    lines += ["f 9 10 11",                                           # zero area, collinear
              "f 1 1 2"]                                             # zero area, repeated vertex
    path = tmp_path / "degenerate.obj"
    path.write_text("\n".join(lines) + "\n")
    with pytest.warns(DegenerateFacesWarning, match=r"dropped 2 degenerate") as record:
        scene = load(path)
    assert issubclass(DegenerateFacesWarning, UserWarning)
    assert len(record) == 1
    mesh = scene.meshes["degenerate"]
    assert len(mesh.faces) == 12
    assert len(mesh.vertices) == 8   # the collinear points are gone with their face
    assert scene.is_watertight
    assert mesh.volume == pytest.approx(1.0, rel=VOLUME_RTOL)


def test_load_only_degenerate_faces(tmp_path):
    path = tmp_path / "line.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    with pytest.warns(DegenerateFacesWarning, match="dropped 1 "):
        with pytest.raises(ValueError, match="no triangles"):
            load(path)


def test_load_keeps_open_meshes(tmp_path):
    open_box = trimesh.Trimesh(trimesh.creation.box().vertices, trimesh.creation.box().faces[:-2],
                               process=False)
    path = tmp_path / "open.ply"
    open_box.export(path)
    scene = scenes.load(path)
    assert len(scene.triangles) == 10
    assert not scene.is_watertight


@pytest.mark.parametrize("kwargs, argument", [
    ({"smooth_angle": -1.0}, "smooth_angle"),
    ({"smooth_angle": 200.0}, "smooth_angle"),
    ({"name": 3}, "name"),
])
def test_load_bad_arguments(tmp_path, kwargs, argument):
    path = tmp_path / "cube.stl"
    trimesh.creation.box().export(path)
    with pytest.raises(ValueError, match=argument):
        load(path, **kwargs)


def test_load_smooth_angle_applies(tmp_path):
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(subdivisions=2).export(path)
    flat = load(path, smooth_angle=0.0)
    smooth = load(path)
    np.testing.assert_array_equal(flat.corner_normals,
                                  np.repeat(flat.face_normals[:, None, :], 3, axis=1))
    assert not np.allclose(smooth.corner_normals, flat.corner_normals)


def test_round_trip_gltf_with_external_buffer(tmp_path):
    mesh = crease().meshes["crease"]
    # write the files ourselves: trimesh's gltf export to a path leaves a file handle open
    for filename, data in trimesh.exchange.gltf.export_gltf(mesh).items():
        (tmp_path / filename).write_bytes(data)
    scene = load(tmp_path / "model.gltf")
    assert list(scene.meshes) == ["model"]
    assert len(scene.triangles) == len(mesh.faces)
    assert scene.is_watertight
    assert scene.meshes["model"].volume == pytest.approx(mesh.volume, rel=FLOAT32_RTOL)


# --------------------------------------------------------------------------------------
# the one resolver of a scene argument: as_scene / resolve
# --------------------------------------------------------------------------------------

def test_resolve_every_kind_of_scene(tmp_path, monkeypatch):
    from vobscure.scenes import as_scene, resolve

    built, name = resolve("crease")
    assert isinstance(built, Scene) and name == "crease" and built.name == "crease"
    own = scenes.slab(size=3.0)
    assert resolve(own) == (own, "custom") and as_scene(own) is own
    box = trimesh.creation.box(extents=(2, 1, 1))
    wrapped, name = resolve(box)
    assert isinstance(wrapped, Scene) and name == "custom" and len(wrapped.triangles) == 12
    path = tmp_path / "brick.ply"
    box.export(path)
    for spec in (path, str(path)):
        loaded, name = resolve(spec)
        assert name == "brick" and len(loaded.triangles) == 12
    # a built-in name wins over a path of that name in the working folder
    monkeypatch.chdir(tmp_path)
    (tmp_path / "slab").mkdir()
    assert resolve("slab")[1] == "slab" and resolve("brick.ply")[1] == "brick"


def test_resolve_errors_name_the_argument_and_the_built_in_scenes(tmp_path):
    from vobscure.scenes import as_scene, resolve

    for bad in ("cornel_box", 3, None, np.zeros((3, 3))):
        with pytest.raises(ValueError, match="scene must be") as info:
            resolve(bad)
        assert all(n in str(info.value) for n in names())
    with pytest.raises(FileNotFoundError, match="cornell_box") as info:
        as_scene(tmp_path / "missing.obj")
    assert "missing.obj" in str(info.value)
    with pytest.raises(ValueError, match="^target must be"):
        as_scene("nothing", argument="target")


def test_scene_arguments_go_through_the_resolver():
    """ground truth, G-buffers and cache digests take a scene's name as well as the scene."""
    import vobscure as vo
    from vobscure.experiments.cache import scene_digest

    assert {"as_scene", "resolve"} <= set(scenes.__all__)
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
    a, b = vo.render_gbuffer("slab", cam), vo.render_gbuffer(scenes.slab(), cam)
    assert np.array_equal(a.depth, b.depth)
    assert scene_digest("slab") == scene_digest(scenes.slab())
    e = vo.ambient_occlusion("slab", [[0, 0, 0]], [[0, 1, 0]], rays=16)
    assert e.value[0] == 1.0
    with pytest.raises(ValueError, match="blob, cornell_box"):
        vo.ground_truth("no-such-scene", a)


def test_check_spec_validates_without_building(tmp_path, monkeypatch):
    from vobscure import scenes
    from vobscure.scenes import _resolve

    monkeypatch.setattr(_resolve, "get", lambda name: pytest.fail("check_spec built a scene"))
    assert scenes.check_spec("slab") == "slab"
    assert scenes.check_spec(tmp_path / "far.obj", exists=False) == str(tmp_path / "far.obj")
    with pytest.raises(FileNotFoundError, match="far.obj"):
        scenes.check_spec(tmp_path / "far.obj")
    with pytest.raises(ValueError, match="mesh file"):
        scenes.check_spec(tmp_path / "notes.txt", exists=False)
    with pytest.raises(ValueError, match="cornell_box"):
        scenes.check_spec("nowhere")


def test_obj_relative_indices_refer_to_the_vertices_defined_so_far(tmp_path):
    # two quads, each written after its own four vertices with indices -4..-1: the second
    # must use vertices 5-8, not the file's last four (the reading trimesh gives on its own)
    text = ("o low\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf -4 -3 -2 -1\n"
            "o high\nv 0 2 0\nv 1 2 0\nv 1 2 1\nv 0 2 1\nf -4 -3 -2 -1\n")
    path = tmp_path / "relative.obj"
    path.write_text(text)
    scene = scenes.load(path)
    assert sorted(scene.meshes) == ["high", "low"]
    assert np.all(scene.meshes["low"].vertices[:, 1] == 0.0)
    assert np.all(scene.meshes["high"].vertices[:, 1] == 2.0)
    absolute = tmp_path / "absolute.obj"
    absolute.write_text(text.replace("f -4 -3 -2 -1\no high", "f 1 2 3 4\no high").replace(
        "v 0 2 1\nf -4 -3 -2 -1", "v 0 2 1\nf 5 6 7 8"))
    same = scenes.load(absolute)
    for name in ("low", "high"):
        np.testing.assert_array_equal(scene.meshes[name].triangles, same.meshes[name].triangles)


def test_gltf_mesh_of_several_primitives_loads_with_the_same_names_every_time(tmp_path):
    # one node whose mesh has two primitives: trimesh names each primitive's frame with a random
    # suffix; the scene's mesh names (and so the cache's scene digest) must not change per load
    import base64
    import json
    import struct

    from vobscure.experiments.cache import scene_digest

    positions = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1]
    blob = struct.pack("<18f", *positions)
    gltf = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "pair", "mesh": 0}],
        "meshes": [{"name": "two", "primitives": [{"attributes": {"POSITION": 0}},
                                                  {"attributes": {"POSITION": 1}}]}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 36}],
        "accessors": [{"bufferView": k, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0 + k], "max": [1, 1, 0 + k]} for k in (0, 1)],
    }
    path = tmp_path / "pair.gltf"
    path.write_text(json.dumps(gltf))
    first, second = scenes.load(path), scenes.load(path)
    assert len(first.meshes) == 2 and list(first.meshes) == list(second.meshes)
    assert all(name.startswith("pair/") for name in first.meshes)
    assert scene_digest(first) == scene_digest(second)
