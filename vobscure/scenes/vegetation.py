"""Vegetation scenes: leaf clouds, trees and grass, the test scenes of Hegeman et al. 2006.

Every builder returns a :class:`~vobscure.scenes.Scene` whose foliage (leaves, grass
blades) is a set of small, open, two-sided triangles, each with its own three vertices.
World space is right-handed with y up. The scenes are what the canopy, occluder and grass
models of Hegeman et al. [1]_ are measured on: :func:`leaf_cloud` is their Fig. 2 test
scene (random leaves in a sphere, at two densities), :func:`tree` a tree standing on the
ground (trunk, branches and a clustered crown, apple-like or poplar-like), :func:`grass` a
field of blades.

Meshes
------
``"leaves"`` (leaf clouds, trees) or ``"blades"`` (grass)
    The foliage: one triangle per leaf or blade, flat shaded. Its name is
    ``scene.metadata["foliage_mesh"]``.
``"wood"`` (trees)
    Trunk and branches: capped frusta (closed, outward wound, 8 sides), smooth shaded
    (60 degrees); they overlap one another where branches fork.
``"ground"`` (trees, grass)
    A square of two triangles in the plane y = ``ground_y``, facing +y.

Open surfaces
-------------
Leaves and blades have no inside, so ``scene.is_watertight`` is False and world-space VO
(``volumetric_obscurance``, ``ground_truth(quantity="volumetric")``), which needs an inside
test, refuses these scenes with a ValueError; AO and obscurance (ray casts) apply. The
G-buffer turns every normal toward the camera (:func:`~vobscure.render_gbuffer`), which is
what a two-sided leaf needs for per-pixel AO. At points on leaves (not pixels) the caller
chooses the side: :func:`leaf_points` samples points with the normal of the side facing
out of the crown (leaf clouds, trees) or up (grass); the stored geometric normal
(``scene.face_normals``) of a leaf is random in sign and says nothing.

Metadata
--------
``scene.metadata`` (a dict) records how the scene was built. Lengths are in scene units,
angles in degrees; arrays are float64. Every vegetation scene has

``"kind"`` : str
    ``"leaf_cloud"``, ``"tree"`` or ``"grass"``.
``"parameters"`` : dict
    The builder's arguments (with the defaults filled in).
``"foliage_mesh"`` : str
    The name of the mesh of open foliage triangles (``"leaves"`` or ``"blades"``).
``"ground_y"`` : float or None
    Height of the ground plane; None for the leaf cloud, which floats.

Leaf clouds and trees also have

``"n_leaves"`` : int
    Number of leaf triangles.
``"leaf_area"`` : float
    Mean one-sided area of one leaf (equal to every leaf's area in a leaf cloud).
``"leaf_areas"`` : (n_leaves,)
    One-sided area of each leaf, in the order of the ``"leaves"`` mesh.
``"canopy_points"`` : (n_leaves, 3)
    Leaf centres (triangle centroids), in the order of the ``"leaves"`` mesh: fit a
    bounding sphere or ellipsoid to them.
``"canopy_center"`` : (3,), ``"canopy_radii"`` : (3,)
    The axis-aligned ellipsoid ``sum(((x - center) / radii)**2) <= 1`` that every leaf
    centre lies in: the volume the leaf cloud's centres were drawn from uniformly, or the
    tree's crown (leaf centres drawn in clusters, those outside the crown redrawn). A leaf's
    corners may lie outside it by up to the leaf's circumradius.
``"canopy_volume"`` : float
    Volume of that ellipsoid, 4/3 pi r_x r_y r_z.
``"leaf_area_density"`` : float
    Total one-sided leaf area per unit volume of the ellipsoid (n_leaves * leaf_area /
    canopy_volume): the density of the Poisson leaf-cloud model.

Trees also have ``"n_clusters"`` and ``"cluster_centers"`` (n_clusters, 3). Grass has

``"n_blades"`` : int
``"blade_bases"`` : (n_blades, 3)
    Midpoint of each blade's base edge, on the ground.
``"blade_tips"`` : (n_blades, 3)
``"blade_heights"`` : (n_blades,)
    Height of each tip above the ground (``blade_tips[:, 1] - ground_y``).
``"blade_tilts"`` : (n_blades,)
    Angle of each blade from the vertical, degrees.
``"blade_lengths"`` : (n_blades,)
    Distance from base midpoint to tip, ``blade_heights / cos(tilt)``.
``"blade_width"`` : float
    Width of every blade's base.
``"blade_area"`` : float
    Mean one-sided area of one blade (``blade_width * blade_lengths / 2``, averaged).
``"field_size"`` : float, ``"blade_density"`` : float
    Side of the square the bases were drawn in, and blades per unit of its area.

All builders are deterministic: the same arguments and ``seed`` give the same vertices, bit
for bit.

Notes
-----
The trees are built here, not by the ``modular-tree`` package (``m_tree``, MIT): its 5.6
release meshes trunks and branches deterministically, but it does not place leaves (its
``LeafShapeGenerator`` makes the outline of one leaf; distributing leaves over the
branches is left to its Blender add-on), and its default tree has about 13 million quads
and takes 8 to 12 s. The crown shape, which the canopy models need to control, is easier
to guarantee by drawing the leaves first and growing the branches to them.

References
----------
.. [1] K. Hegeman, S. Premoze, M. Ashikhmin, G. Drettakis, "Approximate ambient occlusion
   for trees", ACM SIGGRAPH Symposium on Interactive 3D Graphics and Games (I3D) 2006;
   Section 3 (canopy), Fig. 2 (the leaf cloud test scene).

Examples
--------
>>> from vobscure.scenes import leaf_cloud, leaf_points
>>> scene = leaf_cloud(200, seed=1)
>>> scene.metadata["n_leaves"], scene.is_watertight
(200, False)
>>> points, normals = leaf_points(scene, 5, seed=0)
>>> points.shape, normals.shape
((5, 3), (5, 3))
"""

from __future__ import annotations

import numbers

import numpy as np
import trimesh

from .._validate import as_array, as_rng, check_choice, check_int, check_positive
from ._scene import Scene

__all__ = ["leaf_cloud", "leaf_cloud_dense", "tree", "tree_poplar", "grass", "leaf_points"]

#: Leaves of the registered sparse and dense leaf clouds (Hegeman 2006, Fig. 2).
LEAF_CLOUD_LEAVES = 1500
LEAF_CLOUD_DENSE_LEAVES = 6000
#: Sides of the wood's frusta, and the crease angle (degrees) of their shading normals.
_WOOD_SIDES = 8
_WOOD_SMOOTH_ANGLE = 60.0
#: Largest number of foliage triangles a builder accepts (memory and build time).
_MAX_FOLIAGE = 2_000_000

#: Per-kind defaults of :func:`tree`. Lengths in scene units (the apple tree is about 3 tall).
_TREE_KINDS = {
    "apple": {
        "crown_center": (0.0, 1.9, 0.0), "crown_radii": (1.2, 1.0, 1.2),
        "n_leaves": 3000, "leaf_size": 0.1, "n_clusters": 40, "cluster_radius": 0.35,
        "trunk_radius": 0.09, "n_limbs": 5, "limb_start": (0.0, 0.15),
        "limb_elevation": (-0.2, 0.6), "limb_reach": 0.75,
    },
    "poplar": {
        "crown_center": (0.0, 3.0, 0.0), "crown_radii": (0.6, 2.2, 0.6),
        "n_leaves": 3000, "leaf_size": 0.1, "n_clusters": 50, "cluster_radius": 0.25,
        "trunk_radius": 0.08, "n_limbs": 7, "limb_start": (0.0, 0.6),
        "limb_elevation": (0.5, 1.2), "limb_reach": 0.8,
    },
}


# --------------------------------------------------------------------------------------
# Geometry helpers
# --------------------------------------------------------------------------------------

def _view(eye, target, *, fov_y: float = 45.0) -> dict:
    return {"eye": tuple(float(v) for v in eye), "target": tuple(float(v) for v in target),
            "up": (0.0, 1.0, 0.0), "fov_y": float(fov_y)}


def _random_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3, 3) rotation matrices uniform on SO(3): normalised Gaussian quaternions."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=1)


def _uniform_in_ellipsoid(rng: np.random.Generator, n: int, center, radii) -> np.ndarray:
    """(n, 3) points uniform in the axis-aligned ellipsoid (a linear image of the unit ball)."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    r = rng.random(n) ** (1.0 / 3.0)
    return np.asarray(center) + np.asarray(radii) * d * r[:, None]


def _inside_ellipsoid(points, center, radii) -> np.ndarray:
    return np.sum(((points - np.asarray(center)) / np.asarray(radii)) ** 2, axis=1) <= 1.0


def _leaf_triangles(rng: np.random.Generator, centers: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(n, 3, 3) equilateral triangles of side ``sizes`` centred (centroid) on ``centers``,
    each turned by a rotation uniform on SO(3)."""
    unit = np.array([[np.cos(a), np.sin(a), 0.0] for a in (np.pi / 2 + 2 * np.pi * k / 3 for k in range(3))])
    unit /= np.sqrt(3.0)  # circumradius of the unit-side equilateral triangle
    rotations = _random_rotations(rng, len(centers))
    corners = np.einsum("nij,kj->nki", rotations, unit)
    return centers[:, None, :] + sizes[:, None, None] * corners


def _triangle_areas(triangles: np.ndarray) -> np.ndarray:
    e1 = triangles[:, 1] - triangles[:, 0]
    e2 = triangles[:, 2] - triangles[:, 0]
    return 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)


def _soup(triangles: np.ndarray) -> trimesh.Trimesh:
    """A mesh of separate triangles (no shared vertices), in the given order."""
    triangles = np.asarray(triangles, dtype=np.float64)
    faces = np.arange(3 * len(triangles)).reshape(-1, 3)
    return trimesh.Trimesh(triangles.reshape(-1, 3), faces, process=False)


def _ground(half: float, y: float) -> trimesh.Trimesh:
    """The square [-half, half]^2 at height y, two triangles facing +y."""
    v = np.array([(-half, y, -half), (half, y, -half), (half, y, half), (-half, y, half)])
    return trimesh.Trimesh(v, np.array([(0, 3, 2), (0, 2, 1)]), process=False)


def _frusta(a, b, ra, rb, *, sides: int = _WOOD_SIDES) -> trimesh.Trimesh:
    """Capped frusta from ``a`` (radius ``ra``) to ``b`` (radius ``rb``), outward wound.

    Each frustum has ``2 sides + 2`` vertices (two rings and two cap centres) and
    ``4 sides`` triangles; each is a closed solid.
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    ra, rb = np.asarray(ra, float), np.asarray(rb, float)
    w = b - a
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    # u: any unit vector perpendicular to w; v = w x u, so that u x v = w
    helper = np.where(np.abs(w[:, 1:2]) < 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(helper, w)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(w, u)
    theta = 2 * np.pi * np.arange(sides) / sides
    radial = np.cos(theta)[None, :, None] * u[:, None, :] + np.sin(theta)[None, :, None] * v[:, None, :]
    ring_a = a[:, None, :] + ra[:, None, None] * radial
    ring_b = b[:, None, :] + rb[:, None, None] * radial
    per = 2 * sides + 2
    vertices = np.concatenate([ring_a, ring_b, a[:, None, :], b[:, None, :]], axis=1).reshape(-1, 3)
    i = np.arange(sides)
    j = (i + 1) % sides
    ca, cb = 2 * sides, 2 * sides + 1
    local = np.concatenate([
        np.column_stack([i, j, j + sides]),                 # sides: (a_i, a_j, b_j)
        np.column_stack([i, j + sides, i + sides]),         #        (a_i, b_j, b_i)
        np.column_stack([np.full(sides, cb), i + sides, j + sides]),  # cap at b, facing +w
        np.column_stack([np.full(sides, ca), j, i]),        # cap at a, facing -w
    ])
    faces = (local[None, :, :] + per * np.arange(len(a))[:, None, None]).reshape(-1, 3)
    return trimesh.Trimesh(vertices, faces, process=False)


def _check_count(value, name: str) -> int:
    n = check_int(value, name, minimum=1)
    if n > _MAX_FOLIAGE:
        raise ValueError(f"{name} must be at most {_MAX_FOLIAGE}, got {n}")
    return n


def _check_radii(radii, shape: str) -> np.ndarray:
    if isinstance(radii, numbers.Real) and not isinstance(radii, bool):
        radii = (radii, radii, radii)
    r = as_array(radii, "radii", shape=(3,))
    if not np.all(r > 0):
        raise ValueError(f"radii must be three positive numbers, got {r.tolist()}")
    if shape == "sphere" and not (r[0] == r[1] == r[2]):
        raise ValueError(f"radii must be equal for shape='sphere' (or a single number); got "
                         f"{r.tolist()}: use shape='ellipsoid'")
    return r


def _seed_record(seed):
    """The seed as recorded in the metadata: the int, None, or "Generator"."""
    if seed is None or isinstance(seed, numbers.Integral):
        return None if seed is None else int(seed)
    return "Generator"


def _canopy_metadata(kind, parameters, triangles, center, radii, ground_y) -> dict:
    areas = _triangle_areas(triangles)
    volume = 4.0 / 3.0 * np.pi * float(np.prod(radii))
    return {
        "kind": kind,
        "parameters": parameters,
        "foliage_mesh": "leaves",
        "ground_y": ground_y,
        "n_leaves": len(triangles),
        "leaf_area": float(areas.mean()),
        "leaf_areas": areas,
        "canopy_points": triangles.mean(axis=1),
        "canopy_center": np.asarray(center, dtype=np.float64).copy(),
        "canopy_radii": np.asarray(radii, dtype=np.float64).copy(),
        "canopy_volume": volume,
        "leaf_area_density": float(areas.sum() / volume),
    }


# --------------------------------------------------------------------------------------
# Builders
# --------------------------------------------------------------------------------------

def leaf_cloud(n_leaves: int = LEAF_CLOUD_LEAVES, *, shape: str = "sphere", radii=(1.0, 1.0, 1.0),
               leaf_size: float = 0.1, seed=0, name: str = "leaf_cloud") -> Scene:
    """Random small leaves floating in a sphere or ellipsoid: Hegeman et al. 2006, Fig. 2.

    Each leaf is an equilateral triangle of side ``leaf_size`` whose centroid is drawn
    uniformly in the volume and whose orientation is uniform over all rotations: the
    Poisson leaf cloud that the canopy model assumes.

    Parameters
    ----------
    n_leaves : int, optional
        Number of leaves. The registered ``leaf_cloud`` has 1500 (sparse: the optical depth
        of a diameter is about 1.5), ``leaf_cloud_dense`` 6000 (about 6); see
        :func:`leaf_cloud_dense`.
    shape : {"sphere", "ellipsoid"}, optional
        The volume: a sphere (``radii`` equal, or one number) or an axis-aligned ellipsoid.
    radii : float or (3,) float, optional
        Semi-axes along x, y, z; the volume is centred at the origin.
    leaf_size : float, optional
        Side of each leaf triangle; its area is sqrt(3)/4 leaf_size^2.
    seed : int, numpy.random.Generator or None, optional
    name : str, optional
        The scene's name.

    Returns
    -------
    Scene
        One mesh ``"leaves"`` (``n_leaves`` separate triangles), flat shaded, with the
        metadata of a canopy (module docstring); ``ground_y`` is None. The suggested view
        looks at the centre from +z, a little above.

    Notes
    -----
    Leaf centres are uniform in the volume; a leaf's corners may reach out of it by its
    circumradius leaf_size / sqrt(3). With G = 1/2 for randomly oriented leaves, a ray
    through the cloud is blocked at the rate G * leaf_area_density per unit length.

    Examples
    --------
    >>> scene = leaf_cloud(100, shape="ellipsoid", radii=(1.0, 2.0, 1.0), seed=3)
    >>> scene.metadata["canopy_radii"].tolist()
    [1.0, 2.0, 1.0]
    >>> round(scene.metadata["leaf_area"], 6)  # sqrt(3)/4 * 0.1**2
    0.00433
    """
    n = _check_count(n_leaves, "n_leaves")
    check_choice(shape, "shape", ("sphere", "ellipsoid"))
    r = _check_radii(radii, shape)
    size = check_positive(leaf_size, "leaf_size")
    rng = as_rng(seed)
    center = np.zeros(3)
    centers = _uniform_in_ellipsoid(rng, n, center, r)
    triangles = _leaf_triangles(rng, centers, np.full(n, size))
    params = {"n_leaves": n, "shape": shape, "radii": r.tolist(), "leaf_size": size,
              "seed": _seed_record(seed)}
    metadata = _canopy_metadata("leaf_cloud", params, triangles, center, r, None)
    reach = float(r.max()) + size
    direction = np.array([0.0, 0.3, 1.0]) / np.linalg.norm([0.0, 0.3, 1.0])
    view = _view(center + direction * reach / np.sin(np.radians(22.5)) * 1.05, center)
    return Scene({"leaves": _soup(triangles)}, name=name, view=view, smooth_angle=0.0,
                 metadata=metadata)


def leaf_cloud_dense(n_leaves: int = LEAF_CLOUD_DENSE_LEAVES, *, shape: str = "sphere",
                     radii=(1.0, 1.0, 1.0), leaf_size: float = 0.1, seed=0) -> Scene:
    """The dense leaf cloud of Hegeman et al. 2006, Fig. 2: :func:`leaf_cloud` with 6000 leaves.

    Parameters
    ----------
    n_leaves, shape, radii, leaf_size, seed
        As :func:`leaf_cloud`; only the default number of leaves differs (four times the
        sparse cloud's).

    Returns
    -------
    Scene
        Named ``"leaf_cloud_dense"``.

    Examples
    --------
    >>> leaf_cloud_dense(seed=0).metadata["n_leaves"]
    6000
    """
    return leaf_cloud(n_leaves, shape=shape, radii=radii, leaf_size=leaf_size, seed=seed,
                      name="leaf_cloud_dense")


def tree(kind: str = "apple", *, seed=0, n_leaves: int | None = None, leaf_size: float | None = None,
         n_clusters: int | None = None, cluster_radius: float | None = None,
         name: str | None = None) -> Scene:
    """A tree on the ground: trunk, branches and a clustered crown of leaves.

    The crown is an axis-aligned ellipsoid: nearly a sphere for ``"apple"`` (centre
    (0, 1.9, 0), radii (1.2, 1.0, 1.2)), tall and narrow for ``"poplar"`` (centre
    (0, 3.0, 0), radii (0.6, 2.2, 0.6)). The tree is built from the leaves inward:

    1. ``n_clusters`` cluster centres are drawn uniformly in the crown shrunk by
       ``cluster_radius`` (so every cluster reaches into it);
    2. the leaves are shared out among the clusters as evenly as possible; each leaf's
       centroid is uniform in the ball of ``cluster_radius`` around its cluster's centre,
       redrawn until it lies inside the crown; each leaf is an equilateral triangle of side
       ``leaf_size`` times a factor uniform in [0.7, 1.3], uniformly oriented;
    3. the trunk rises from the ground (y = 0) to a quarter of the crown's height, and
       continues as a leader to 0.7 of the crown's upper semi-axis above its centre;
    4. limbs (5 for the apple, 7 for the poplar) leave the leader at random heights (near
       its base for the apple, along its lower 60 % for the poplar), at azimuths evenly
       spread with jitter and random elevations (flat for the apple, steep for the poplar),
       and end at 0.75 (0.8) of the crown's semi-axes from its centre;
    5. a twig joins each cluster's centre to the nearest point of the leader or a limb.

    Trunk, leader, limbs and twigs are capped 8-sided frusta, tapering from the trunk
    radius to a fifth of it (limbs) and a tenth (twigs).

    Parameters
    ----------
    kind : {"apple", "poplar"}, optional
    seed : int, numpy.random.Generator or None, optional
    n_leaves : int, optional
        Default 3000.
    leaf_size : float, optional
        Mean side of a leaf triangle; default 0.1.
    n_clusters : int, optional
        Leaf clusters; default 40 (apple), 50 (poplar).
    cluster_radius : float, optional
        Radius of the ball of each cluster; default 0.35 (apple), 0.25 (poplar).
    name : str, optional
        The scene's name; default ``"tree"`` for the apple, ``"tree_poplar"`` for the poplar.

    Returns
    -------
    Scene
        Meshes ``"ground"`` (a square at y = 0 of half-side max(2.5 max(r_x, r_z), crown top /
        2): side 6 for the apple, 5.2 for the poplar), ``"wood"``
        and ``"leaves"``; the metadata of a canopy (module docstring) with ``ground_y`` = 0,
        ``"n_clusters"`` and ``"cluster_centers"``. The suggested view looks at the whole
        tree from the side, a little above.

    Notes
    -----
    Why not the ``modular-tree`` package: see the module's Notes. Build time is about
    20 ms for the defaults.

    Examples
    --------
    >>> scene = tree("poplar", n_leaves=500, seed=2)
    >>> sorted(scene.meshes), scene.name
    (['ground', 'leaves', 'wood'], 'tree_poplar')
    >>> scene.metadata["ground_y"], scene.metadata["n_leaves"]
    (0.0, 500)
    """
    check_choice(kind, "kind", tuple(_TREE_KINDS))
    spec = _TREE_KINDS[kind]
    n = _check_count(spec["n_leaves"] if n_leaves is None else n_leaves, "n_leaves")
    size = check_positive(spec["leaf_size"] if leaf_size is None else leaf_size, "leaf_size")
    k = check_int(spec["n_clusters"] if n_clusters is None else n_clusters, "n_clusters", minimum=1)
    if k > n:
        raise ValueError(f"n_clusters must be at most n_leaves ({n}), got {k}")
    rho = check_positive(spec["cluster_radius"] if cluster_radius is None else cluster_radius,
                         "cluster_radius")
    c = np.asarray(spec["crown_center"], dtype=np.float64)
    R = np.asarray(spec["crown_radii"], dtype=np.float64)
    if not rho < 0.9 * R.min():
        raise ValueError(f"cluster_radius must be less than 0.9 times the crown's smallest "
                         f"semi-axis ({0.9 * R.min():.3g}), got {rho}")
    rng = as_rng(seed)
    ground_y = 0.0

    # 1-2: clusters, then leaves around them, inside the crown
    cluster_centers = _uniform_in_ellipsoid(rng, k, c, R - rho)
    owner = np.arange(n) % k
    centers = np.empty((n, 3))
    todo = np.arange(n)
    while len(todo):
        p = cluster_centers[owner[todo]] + _uniform_in_ellipsoid(rng, len(todo), np.zeros(3), (rho,) * 3)
        ok = _inside_ellipsoid(p, c, R)
        centers[todo[ok]] = p[ok]
        todo = todo[~ok]
    sizes = size * rng.uniform(0.7, 1.3, size=n)
    leaves = _leaf_triangles(rng, centers, sizes)

    # 3: trunk and leader
    r0 = spec["trunk_radius"]
    top = c[1] - 0.75 * R[1]
    base = np.array([0.0, ground_y, 0.0])
    trunk_top = np.array([0.0, top, 0.0])
    leader_top = c + np.array([0.0, 0.7 * R[1], 0.0])
    seg_a = [base, trunk_top]
    seg_b = [trunk_top, leader_top]
    rad_a = [r0, 0.7 * r0]
    rad_b = [0.7 * r0, 0.25 * r0]
    # 4: limbs
    m = spec["n_limbs"]
    start = trunk_top + rng.uniform(*spec["limb_start"], size=m)[:, None] * (leader_top - trunk_top)
    azimuth = 2 * np.pi * (np.arange(m) + rng.uniform(-0.3, 0.3, size=m)) / m
    elevation = rng.uniform(*spec["limb_elevation"], size=m)
    d = np.column_stack([np.cos(elevation) * np.cos(azimuth), np.sin(elevation),
                         np.cos(elevation) * np.sin(azimuth)])
    end = c + spec["limb_reach"] * R * d
    seg_a += list(start)
    seg_b += list(end)
    rad_a += [0.4 * r0] * m
    rad_b += [0.2 * r0] * m
    # 5: twigs from the nearest point of the leader or a limb to each cluster
    A = np.array([trunk_top] + list(start))
    B = np.array([leader_top] + list(end))
    AB = B - A
    t = np.einsum("kmj,mj->km", cluster_centers[:, None, :] - A[None], AB) / np.einsum("mj,mj->m", AB, AB)
    t = np.clip(t, 0.0, 1.0)
    nearest = A[None] + t[..., None] * AB[None]
    which = np.argmin(np.linalg.norm(cluster_centers[:, None, :] - nearest, axis=2), axis=1)
    twig_start = nearest[np.arange(k), which]
    long_enough = np.linalg.norm(cluster_centers - twig_start, axis=1) > 1e-6
    seg_a += list(twig_start[long_enough])
    seg_b += list(cluster_centers[long_enough])
    rad_a += [0.15 * r0] * int(long_enough.sum())
    rad_b += [0.1 * r0] * int(long_enough.sum())
    wood = _frusta(np.array(seg_a), np.array(seg_b), np.array(rad_a), np.array(rad_b))

    half = max(2.5 * float(R[[0, 2]].max()), 0.5 * float(c[1] + R[1]))
    params = {"kind": kind, "n_leaves": n, "leaf_size": size, "n_clusters": k, "cluster_radius": rho,
              "seed": _seed_record(seed)}
    metadata = _canopy_metadata("tree", params, leaves, c, R, ground_y)
    metadata["n_clusters"] = k
    metadata["cluster_centers"] = cluster_centers
    height = c[1] + R[1] + size
    target = np.array([0.0, 0.5 * height, 0.0])
    direction = np.array([0.35, 0.3, 1.0]) / np.linalg.norm([0.35, 0.3, 1.0])
    view = _view(target + direction * 0.5 * height / np.tan(np.radians(22.5)) * 1.15, target)
    if name is None:
        name = "tree" if kind == "apple" else f"tree_{kind}"
    return Scene({"ground": _ground(half, ground_y), "wood": wood, "leaves": _soup(leaves)},
                 name=name, view=view,
                 smooth_angle={"ground": 0.0, "wood": _WOOD_SMOOTH_ANGLE, "leaves": 0.0},
                 metadata=metadata)


def tree_poplar(*, seed=0, n_leaves: int | None = None, leaf_size: float | None = None,
                n_clusters: int | None = None, cluster_radius: float | None = None) -> Scene:
    """A poplar-like tree, tall and narrow: :func:`tree` with ``kind="poplar"``.

    Parameters
    ----------
    seed, n_leaves, leaf_size, n_clusters, cluster_radius
        As :func:`tree`.

    Returns
    -------
    Scene
        Named ``"tree_poplar"``.

    Examples
    --------
    >>> tree_poplar(n_leaves=200).metadata["canopy_radii"].tolist()
    [0.6, 2.2, 0.6]
    """
    return tree("poplar", seed=seed, n_leaves=n_leaves, leaf_size=leaf_size, n_clusters=n_clusters,
                cluster_radius=cluster_radius)


def grass(n_blades: int = 3000, *, height: float = 0.3, height_spread: float = 0.5,
          tilt: float = 30.0, width: float = 0.02, size: float = 2.0, seed=0) -> Scene:
    """A square field of thin grass blades on the ground, with varying heights and tilts.

    Each blade is one narrow triangle: a base edge of ``width`` on the ground (y = 0),
    centred on a point uniform in the field [-size/2, size/2]^2 and turned about the
    vertical by an angle uniform in [0, 360) degrees, and a tip above it. The blade leans
    out of the vertical, across its base edge, by a tilt uniform in [0, ``tilt``] degrees,
    toward either face (the azimuth covers both); its tip's height above the ground is
    uniform in [height (1 - height_spread), height (1 + height_spread)].

    Parameters
    ----------
    n_blades : int, optional
    height : float, optional
        Mean height of the tips above the ground.
    height_spread : float, optional
        Relative half-width of the heights' range, 0 <= height_spread < 1.
    tilt : float, optional
        Largest angle of a blade from the vertical, degrees, 0 <= tilt < 90.
    width : float, optional
        Width of each blade's base.
    size : float, optional
        Side of the square the blades stand in; the ground square is 1.5 times as wide.
    seed : int, numpy.random.Generator or None, optional

    Returns
    -------
    Scene
        Meshes ``"ground"`` and ``"blades"``, flat shaded, with the grass metadata (module
        docstring); ``ground_y`` = 0. The suggested view looks down on the field
        obliquely.

    Examples
    --------
    >>> scene = grass(100, height=0.5, height_spread=0.2, seed=1)
    >>> h = scene.metadata["blade_heights"]
    >>> bool(h.min() >= 0.4 and h.max() <= 0.6)
    True
    """
    n = _check_count(n_blades, "n_blades")
    height = check_positive(height, "height")
    spread = check_positive(height_spread, "height_spread", allow_zero=True)
    if not spread < 1.0:
        raise ValueError(f"height_spread must be less than 1 (heights stay positive), got {height_spread}")
    tilt = check_positive(tilt, "tilt", allow_zero=True)
    if not tilt < 90.0:
        raise ValueError(f"tilt must be less than 90 degrees, got {tilt}")
    width = check_positive(width, "width")
    size = check_positive(size, "size")
    rng = as_rng(seed)
    ground_y = 0.0
    xz = rng.uniform(-0.5 * size, 0.5 * size, size=(n, 2))
    bases = np.column_stack([xz[:, 0], np.full(n, ground_y), xz[:, 1]])
    azimuth = rng.uniform(0.0, 2 * np.pi, size=n)
    tilts = rng.uniform(0.0, tilt, size=n)
    heights = height * rng.uniform(1.0 - spread, 1.0 + spread, size=n)
    side = np.column_stack([np.cos(azimuth), np.zeros(n), np.sin(azimuth)])
    face = np.column_stack([-np.sin(azimuth), np.zeros(n), np.cos(azimuth)])  # side x up
    t = np.radians(tilts)
    lengths = heights / np.cos(t)
    direction = np.cos(t)[:, None] * np.array([0.0, 1.0, 0.0]) + np.sin(t)[:, None] * face
    tips = bases + lengths[:, None] * direction
    tips[:, 1] = ground_y + heights  # exact, whatever the rounding of cos
    half_side = 0.5 * width * side
    blades = np.stack([bases - half_side, bases + half_side, tips], axis=1)
    areas = _triangle_areas(blades)
    metadata = {
        "kind": "grass",
        "parameters": {"n_blades": n, "height": height, "height_spread": spread, "tilt": tilt,
                       "width": width, "size": size,
                       "seed": _seed_record(seed)},
        "foliage_mesh": "blades",
        "ground_y": ground_y,
        "n_blades": n,
        "blade_bases": bases,
        "blade_tips": tips,
        "blade_heights": heights,
        "blade_tilts": tilts,
        "blade_lengths": lengths,
        "blade_width": width,
        "blade_area": float(areas.mean()),
        "field_size": size,
        "blade_density": n / size**2,
    }
    target = np.array([0.0, 0.0, 0.0])
    view = _view(target + size * np.array([0.0, 0.9, 0.9]), target)
    return Scene({"ground": _ground(0.75 * size, ground_y), "blades": _soup(blades)}, name="grass",
                 view=view, smooth_angle=0.0, metadata=metadata)


# --------------------------------------------------------------------------------------
# Sampling
# --------------------------------------------------------------------------------------

def leaf_points(scene, n: int, *, seed=0, orient: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Points uniform by area on a vegetation scene's foliage, with the normal of one side.

    Parameters
    ----------
    scene : Scene
        A scene built by this module (its ``metadata["foliage_mesh"]`` names the foliage).
    n : int
        Number of points.
    seed : int, numpy.random.Generator or None, optional
    orient : {"outward", "up", "geometric"} or None, optional
        Which side's normal each point gets. ``"outward"``: the side facing away from the
        canopy centre, ``n . (p - canopy_center) >= 0`` (the side that looks out of the
        crown); ``"up"``: the side with ``n_y >= 0`` (the side that looks at the sky);
        ``"geometric"``: the stored face normal, whose sign is arbitrary for a leaf. A
        tie (zero dot product) keeps the geometric normal. None (default): ``"outward"``
        for leaf clouds and trees, ``"up"`` for grass.

    Returns
    -------
    points : (n, 3) float64
        On the foliage triangles: a triangle is chosen with probability proportional to its
        area, and a point uniform in it (by the square-root warp of barycentric
        coordinates).
    normals : (n, 3) float64
        Unit normals of the triangles, oriented by ``orient``.

    Notes
    -----
    The normal is that of one side of a two-sided leaf. A leaf's AO differs between its two
    sides; the experiments choose the side per point (the outward side answers "how much
    sky does the outer surface of the crown see"), or average both by calling the ground
    truth with ``normals`` and ``-normals``.

    Examples
    --------
    >>> from vobscure.scenes import tree
    >>> p, nrm = leaf_points(tree(n_leaves=300), 4, seed=1)
    >>> bool(np.all(np.einsum("ij,ij->i", nrm, p - [0.0, 1.9, 0.0]) >= 0))
    True
    """
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a vobscure Scene built by vobscure.scenes.vegetation, "
                         f"got {type(scene).__name__}")
    foliage = scene.metadata.get("foliage_mesh")
    if foliage not in scene.meshes:
        raise ValueError("scene has no foliage: its metadata['foliage_mesh'] names no mesh of it "
                         "(build it with leaf_cloud, tree or grass)")
    n = check_int(n, "n", minimum=1)
    if orient is None:
        orient = "up" if scene.metadata.get("kind") == "grass" else "outward"
    check_choice(orient, "orient", ("outward", "up", "geometric"))
    if orient == "outward" and "canopy_center" not in scene.metadata:
        raise ValueError("orient='outward' needs scene.metadata['canopy_center'] (leaf clouds, "
                         "trees); use orient='up' for grass")
    rng = as_rng(seed)
    index = list(scene.meshes).index(foliage)
    faces = np.flatnonzero(scene.mesh_index == index)
    triangles = scene.triangles[faces]
    areas = _triangle_areas(triangles)
    cdf = np.cumsum(areas)
    chosen = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side="right"), len(faces) - 1)
    u, v = rng.random(n), rng.random(n)
    su = np.sqrt(u)
    b0, b1, b2 = 1.0 - su, su * (1.0 - v), su * v
    tri = triangles[chosen]
    points = b0[:, None] * tri[:, 0] + b1[:, None] * tri[:, 1] + b2[:, None] * tri[:, 2]
    normals = scene.face_normals[faces[chosen]].copy()
    if orient == "outward":
        s = np.einsum("ij,ij->i", normals, points - scene.metadata["canopy_center"])
        normals[s < 0] *= -1.0
    elif orient == "up":
        normals[normals[:, 1] < 0] *= -1.0
    return points, normals
