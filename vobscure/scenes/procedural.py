"""Procedural test scenes: closed solids with known geometry and a suggested camera.

Every builder returns a :class:`~vobscure.scenes.Scene` whose meshes are closed solids
(watertight, consistently wound, outward normals, positive volume) that do not
interpenetrate one another; they may touch along faces, edges or points. World space is
right-handed with y up. Polyhedral scenes are flat shaded (``smooth_angle=0``); curved
ones (the sphere, the blob) are smooth shaded with a 60-degree crease angle.

The scenes are the analytic test cases of the library (see DESIGN.md, "Testing"): a point
on the slab sees an open half-space, a point on the crease floor at distance ``a`` from the
wall sees a half-space cut by one plane, and the groove generalises the crease to any
opening angle.
"""

from __future__ import annotations

import inspect
import numbers

import numpy as np
import trimesh

from .._validate import as_rng, check_int, check_positive
from ._scene import Scene
from .atrium import atrium
from .thin import thin_occluders
from .vegetation import grass, leaf_cloud, leaf_cloud_dense, tree, tree_poplar

__all__ = [
    "slab",
    "crease",
    "groove",
    "sphere_on_plane",
    "steps",
    "cornell_box",
    "blob",
    "names",
    "get",
]

#: Crease angle (degrees) of the shading normals of curved solids.
_SMOOTH_ANGLE = 60.0
#: Largest icosphere subdivision level accepted (level 8 already has 1.3 million faces).
_MAX_SUBDIVISIONS = 8
#: Largest |amplitude * f| of the blob, so that the radius stays in [0.4, 1.6].
_BLOB_MAX_AMPLITUDE = 0.6


# --------------------------------------------------------------------------------------
# Geometry helpers
# --------------------------------------------------------------------------------------

def _signed_area(polygon_xy: np.ndarray) -> float:
    """Signed area of a polygon (positive for counter-clockwise), by the shoelace formula."""
    x, y = polygon_xy[:, 0], polygon_xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _triangulate(polygon_xy: np.ndarray) -> np.ndarray:
    """(k - 2, 3) int triangles of a simple counter-clockwise polygon, by ear clipping.

    A vertex is an ear when its corner is strictly convex and no other remaining vertex
    lies inside or on the triangle it spans with its two neighbours; clipping ears one at
    a time triangulates any simple polygon (Meisters' two-ears theorem). O(k^3), which is
    fine for the profiles of this module (tens of vertices). Every triangle is
    counter-clockwise, like the polygon.
    """
    p = np.asarray(polygon_xy, dtype=np.float64)
    scale = float(np.max(np.ptp(p, axis=0)))
    tol = 1e-12 * scale * scale
    remaining = list(range(len(p)))
    triangles = []
    while len(remaining) > 3:
        n = len(remaining)
        for j in range(n):
            a, b, c = remaining[j - 1], remaining[j], remaining[(j + 1) % n]
            pa, pb, pc = p[a], p[b], p[c]
            turn = (pb[0] - pa[0]) * (pc[1] - pb[1]) - (pb[1] - pa[1]) * (pc[0] - pb[0])
            if turn <= tol:  # reflex or straight corner: not an ear
                continue
            others = p[[i for i in remaining if i not in (a, b, c)]]
            if len(others):
                # edge functions of the three edges; >= -tol on all three = inside or on
                def edge(q0, q1):
                    return ((q1[0] - q0[0]) * (others[:, 1] - q0[1])
                            - (q1[1] - q0[1]) * (others[:, 0] - q0[0]))
                inside = (edge(pa, pb) >= -tol) & (edge(pb, pc) >= -tol) & (edge(pc, pa) >= -tol)
                if np.any(inside):
                    continue
            triangles.append((a, b, c))
            del remaining[j]
            break
        else:
            raise ValueError("polygon_xy is not a simple polygon without straight corners; "
                             "ear clipping found no ear")
    triangles.append(tuple(remaining))
    return np.asarray(triangles, dtype=np.int64)


def _extrude(polygon_xy, z0: float, z1: float) -> trimesh.Trimesh:
    """Extrude a simple counter-clockwise polygon in the xy plane along z into a closed prism.

    Parameters
    ----------
    polygon_xy : (k, 2) float
        Vertices of a simple (possibly concave) polygon in counter-clockwise order, without
        repeating the first vertex and without straight (180-degree) corners.
    z0, z1 : float
        The prism spans z in [z0, z1], z0 < z1.

    Returns
    -------
    trimesh.Trimesh
        2k vertices (the polygon at z0, then at z1) and 2(k - 2) + 2k triangles: the two caps
        triangulated by ear clipping and one quad per polygon edge. Watertight, consistently
        wound, outward normals; the volume is ``area(polygon) * (z1 - z0)``.
    """
    p = np.asarray(polygon_xy, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise ValueError(f"polygon_xy must have shape (k, 2) with k >= 3, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("polygon_xy must be finite")
    if not z1 > z0:
        raise ValueError(f"z1 must be greater than z0, got z0={z0}, z1={z1}")
    if not _signed_area(p) > 0:
        raise ValueError("polygon_xy must be counter-clockwise (positive signed area)")
    k = len(p)
    cap = _triangulate(p)
    vertices = np.concatenate([np.column_stack([p, np.full(k, float(z0))]),
                               np.column_stack([p, np.full(k, float(z1))])])
    i = np.arange(k)
    j = (i + 1) % k
    # A counter-clockwise polygon has its outside on the right of each edge, so the quad
    # (bottom i, bottom j, top j, top i) is counter-clockwise seen from outside.
    sides = np.concatenate([np.column_stack([i, j, j + k]), np.column_stack([i, j + k, i + k])])
    faces = np.concatenate([cap[:, ::-1],  # bottom cap, facing -z
                            cap + k,        # top cap, facing +z
                            sides])
    return trimesh.Trimesh(vertices, faces, process=False)


def _box(lo, hi, *, angle_y: float = 0.0) -> trimesh.Trimesh:
    """The box [lo, hi], optionally rotated by ``angle_y`` degrees about its vertical axis.

    The corners are taken from ``lo`` and ``hi`` exactly (not rebuilt from a centre and
    extents), so boxes that should touch share their face planes bit for bit; a rotation
    about y keeps the y coordinates exact.
    """
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    unit = trimesh.creation.box()  # the cube [-0.5, 0.5]^3, outward normals
    corner = np.asarray(unit.vertices) > 0
    vertices = np.where(corner, hi, lo)
    if angle_y:
        a = np.radians(angle_y)
        centre = 0.5 * (lo + hi)
        dx, dz = vertices[:, 0] - centre[0], vertices[:, 2] - centre[2]
        # rotation about +y by a (right-handed): x' = x cos a + z sin a, z' = -x sin a + z cos a
        vertices[:, 0] = centre[0] + dx * np.cos(a) + dz * np.sin(a)
        vertices[:, 2] = centre[2] - dx * np.sin(a) + dz * np.cos(a)
    return trimesh.Trimesh(vertices, np.asarray(unit.faces), process=False)


def _view(eye, target, *, fov_y: float = 45.0) -> dict:
    return {"eye": tuple(float(v) for v in eye), "target": tuple(float(v) for v in target),
            "up": (0.0, 1.0, 0.0), "fov_y": float(fov_y)}


def _check_subdivisions(subdivisions) -> int:
    s = check_int(subdivisions, "subdivisions", minimum=0)
    if s > _MAX_SUBDIVISIONS:
        raise ValueError(f"subdivisions must be at most {_MAX_SUBDIVISIONS} "
                         f"(20 * 4**{_MAX_SUBDIVISIONS} triangles), got {s}")
    return s


# --------------------------------------------------------------------------------------
# Builders
# --------------------------------------------------------------------------------------

def slab(*, size: float = 8.0, thickness: float = 1.0) -> Scene:
    """A square slab whose top face y = 0 faces +y: the open half-space test case.

    Parameters
    ----------
    size : float, optional
        Side length of the square top face, x and z in [-size/2, size/2].
    thickness : float, optional
        The slab occupies y in [-thickness, 0].

    Returns
    -------
    Scene
        One mesh ``"slab"`` (12 triangles), flat shaded; the suggested view looks at the
        origin obliquely from above.

    Notes
    -----
    A point on the top face, far enough from the rim, is unoccluded: AO and obscurance are
    1, the unclamped world-space VO of a ball centred on the surface is exactly 1/2 and the
    normal-clamped VO is 1 (DESIGN.md, "Conventions"). The unclamped value needs the slab to
    fill the lower half of the ball: radius <= thickness, and radius <= size/2 - max(|x|, |z|)
    for a point (x, 0, z).

    Examples
    --------
    >>> from vobscure.scenes import slab
    >>> vo_scene = slab()
    >>> vo_scene.is_watertight
    True
    >>> vo_scene.bounds.tolist()
    [[-4.0, -1.0, -4.0], [4.0, 0.0, 4.0]]
    """
    size = check_positive(size, "size")
    thickness = check_positive(thickness, "thickness")
    h = 0.5 * size
    mesh = _box((-h, -thickness, -h), (h, 0.0, h))
    view = _view((0.0, 0.6 * size, 0.9 * size), (0.0, 0.0, 0.0))
    return Scene({"slab": mesh}, name="slab", view=view, smooth_angle=0.0)


def crease(*, length: float = 4.0, height: float = 4.0, depth: float = 8.0,
           thickness: float = 2.0) -> Scene:
    """An L-shaped prism: a floor (top y = 0) meeting a wall (face x = 0) at a concave edge.

    The cross-section in the xy plane is the L-shaped polygon
    (-t, -t), (L, -t), (L, 0), (0, 0), (0, H), (-t, H), extruded along z over
    [-depth/2, depth/2]. The free space near the edge is x > 0, y > 0: a 90-degree
    concave edge along the z axis. It is one solid, not two boxes, so no face lies inside
    another.

    Parameters
    ----------
    length : float, optional
        L: the floor's top face spans x in [0, L].
    height : float, optional
        H: the wall's face spans y in [0, H].
    depth : float, optional
        Extent along the edge (z).
    thickness : float, optional
        t: the floor occupies y in [-t, 0], the wall x in [-t, 0].

    Returns
    -------
    Scene
        One mesh ``"crease"`` (20 triangles), flat shaded.

    Notes
    -----
    For a point on the floor at (a, 0, 0), 0 <= a <= R, and a radius R <= min(L - a, H,
    depth/2), only the wall cuts the hemisphere, and with c = a / R (DESIGN.md, "Testing"):
    cosine-weighted AO = 1 - (acos c - c sqrt(1 - c^2)) / pi and
    uniform AO = (1 + c) / 2. The world-space VO of the whole ball,
    1/2 - (1 - c)^2 (2 + c) / 8, also needs the solid to fill the ball's lower half and the
    part of it behind the wall: R <= t. The default thickness is 2 (not 1) so that the
    defaults serve every formula for R up to 2 and a up to 2.

    Examples
    --------
    >>> from vobscure.scenes import crease
    >>> vo_scene = crease()
    >>> vo_scene.is_watertight
    True
    >>> float(vo_scene.meshes["crease"].volume)  # (t (L + t) + t H) depth
    160.0
    """
    L = check_positive(length, "length")
    H = check_positive(height, "height")
    depth = check_positive(depth, "depth")
    t = check_positive(thickness, "thickness")
    profile = np.array([(-t, -t), (L, -t), (L, 0.0), (0.0, 0.0), (0.0, H), (-t, H)])
    mesh = _extrude(profile, -0.5 * depth, 0.5 * depth)
    s = max(L, H) / 4.0
    target = np.array([0.3 * L, 0.3 * H, 0.0])
    view = _view(target + s * np.array([4.0, 3.0, 6.0]), target)
    return Scene({"crease": mesh}, name="crease", view=view, smooth_angle=0.0)


def groove(angle: float = 90.0, *, depth: float = 2.0, width: float = 8.0, length: float = 8.0,
           thickness: float = 1.0) -> Scene:
    """A V-shaped groove of opening ``angle`` cut into the top of a block.

    The apex line runs along z through the origin; the walls rise from it in the directions
    (+-sin(angle/2), cos(angle/2)) in the xy plane until y = depth, where a flat top runs
    out to x = +-width/2; the solid extends down to y = -thickness. The groove is symmetric
    about the +y axis and the free space is above the walls.

    Parameters
    ----------
    angle : float, optional
        Opening angle of the V in degrees, 0 < angle < 180. 90 is a crease turned by 45
        degrees; 180 would be a flat floor.
    depth : float, optional
        Height of the groove's rim above the apex.
    width : float, optional
        The block spans x in [-width/2, width/2]; the groove's mouth,
        2 depth tan(angle/2), must be narrower.
    length : float, optional
        Extent along the apex line, z in [-length/2, length/2].
    thickness : float, optional
        The solid extends below the apex down to y = -thickness.

    Returns
    -------
    Scene
        One mesh ``"groove"`` (24 triangles), flat shaded.

    Notes
    -----
    The two wall normals are (+-cos(angle/2), sin(angle/2)); they make an angle of
    180 - ``angle`` degrees. The volume is
    (width (depth + thickness) - depth^2 tan(angle/2)) length.

    Examples
    --------
    >>> from vobscure.scenes import groove
    >>> vo_scene = groove(60.0)
    >>> vo_scene.is_watertight
    True
    """
    if isinstance(angle, bool) or not isinstance(angle, numbers.Real) or not 0.0 < float(angle) < 180.0:
        raise ValueError(f"angle must be a number of degrees in (0, 180), got {angle!r}")
    angle = float(angle)
    depth = check_positive(depth, "depth")
    width = check_positive(width, "width")
    length = check_positive(length, "length")
    thickness = check_positive(thickness, "thickness")
    half_mouth = depth * np.tan(np.radians(0.5 * angle))
    if not 0.5 * width - half_mouth > 1e-9 * width:  # leave a flat top of non-zero width
        raise ValueError(
            f"width must exceed the groove's mouth 2 * depth * tan(angle / 2) = {2 * half_mouth:.6g} "
            f"(angle={angle}, depth={depth}), got width={width}")
    w = 0.5 * width
    profile = np.array([(-w, -thickness), (w, -thickness), (w, depth), (half_mouth, depth),
                        (0.0, 0.0), (-half_mouth, depth), (-w, depth)])
    mesh = _extrude(profile, -0.5 * length, 0.5 * length)
    target = np.array([0.0, 0.4 * depth, 0.0])
    view = _view(target + np.array([0.25 * width, depth + 0.5 * width, 0.8 * length]), target)
    return Scene({"groove": mesh}, name="groove", view=view, smooth_angle=0.0)


def sphere_on_plane(*, radius: float = 1.0, size: float = 8.0, thickness: float = 1.0,
                    subdivisions: int = 4) -> Scene:
    """A sphere resting on a floor slab: contact shadow and curved-surface test case.

    Parameters
    ----------
    radius : float, optional
        Radius of the sphere, centred at (0, radius, 0).
    size : float, optional
        Side of the square floor, x and z in [-size/2, size/2]; must exceed 2 radius.
    thickness : float, optional
        The floor occupies y in [-thickness, 0].
    subdivisions : int, optional
        Subdivision level of the icosphere (20 * 4**subdivisions triangles), 0 to 8.

    Returns
    -------
    Scene
        Meshes ``"floor"`` (flat shaded) and ``"sphere"`` (smooth shaded, 60 degrees).

    Notes
    -----
    The icosphere is rotated so that one of its vertices is exactly the contact point
    (0, 0, 0): the polyhedron touches the floor at that point and nowhere else, without a
    gap and without overlap. Its vertices lie on the sphere of ``radius``; its faces are
    chords, slightly inside.

    Examples
    --------
    >>> from vobscure.scenes import sphere_on_plane
    >>> vo_scene = sphere_on_plane(subdivisions=2)
    >>> vo_scene.is_watertight, sorted(vo_scene.meshes)
    (True, ['floor', 'sphere'])
    """
    radius = check_positive(radius, "radius")
    size = check_positive(size, "size")
    thickness = check_positive(thickness, "thickness")
    subdivisions = _check_subdivisions(subdivisions)
    if not size > 2.0 * radius:
        raise ValueError(f"size must exceed the sphere's diameter 2 * radius = {2 * radius}, got {size}")
    h = 0.5 * size
    floor = _box((-h, -thickness, -h), (h, 0.0, h))
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    # Turn the lowest vertex to the south pole, so the sphere stands on a vertex.
    v = np.asarray(sphere.vertices, dtype=np.float64)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    low = int(np.argmin(v[:, 1]))
    rotation = trimesh.geometry.align_vectors(v[low], (0.0, -1.0, 0.0))[:3, :3]
    v = v @ rotation.T
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    v[low] = (0.0, -1.0, 0.0)
    v = radius * v + np.array([0.0, radius, 0.0])
    v[low] = 0.0  # exact contact point
    sphere = trimesh.Trimesh(v, np.asarray(sphere.faces), process=False)
    target = np.array([0.0, 0.6 * radius, 0.0])
    view = _view(target + radius * np.array([1.2, 2.2, 4.5]), target)
    return Scene({"floor": floor, "sphere": sphere}, name="sphere_on_plane", view=view,
                 smooth_angle={"floor": 0.0, "sphere": _SMOOTH_ANGLE})


def steps(*, count: int = 4, rise: float = 0.25, run: float = 0.5, width: float = 2.0) -> Scene:
    """A staircase: ``count`` steps climbing in +x, as one closed prism.

    The profile in the xy plane starts at the origin: step i (1 to ``count``) has its tread
    at y = i rise over x in [(i - 1) run, i run] and its riser, facing -x, at
    x = (i - 1) run. The bottom is y = 0, the back face x = count run. The profile is
    extruded along z over [-width/2, width/2]. The inner corners between treads and risers
    are 90-degree concave edges; the nosings are convex ones.

    Parameters
    ----------
    count : int, optional
        Number of steps (>= 1).
    rise : float, optional
        Height of each step.
    run : float, optional
        Depth of each tread.
    width : float, optional
        Extent along z.

    Returns
    -------
    Scene
        One mesh ``"steps"``, flat shaded; volume rise run count (count + 1) / 2 width.

    Examples
    --------
    >>> from vobscure.scenes import steps
    >>> vo_scene = steps(count=3)
    >>> vo_scene.is_watertight
    True
    >>> float(vo_scene.meshes["steps"].volume)  # 0.25 * 0.5 * 6 * 2.0
    1.5
    """
    count = check_int(count, "count", minimum=1)
    rise = check_positive(rise, "rise")
    run = check_positive(run, "run")
    width = check_positive(width, "width")
    profile = [(0.0, 0.0), (count * run, 0.0), (count * run, count * rise)]
    for i in range(count, 0, -1):
        profile.append(((i - 1) * run, i * rise))      # front edge of tread i
        if i > 1:
            profile.append(((i - 1) * run, (i - 1) * rise))  # foot of riser i
    mesh = _extrude(np.array(profile), -0.5 * width, 0.5 * width)
    extent = float(np.linalg.norm([count * run, count * rise, width]))
    target = np.array([0.5 * count * run, 0.4 * count * rise, 0.0])
    view = _view(target + extent * np.array([-0.9, 0.8, 1.1]), target)
    return Scene({"steps": mesh}, name="steps", view=view, smooth_angle=0.0)


def cornell_box() -> Scene:
    """The Cornell box layout, built from closed slabs and boxes.

    The interior is x in [-1, 1], y in [0, 2], z in [-1, 1], open toward +z. The five walls
    are slabs 0.1 thick outside the interior, arranged so that no two overlap in volume:
    the floor and ceiling span the full outer width and depth (x in [-1.1, 1.1], z in
    [-1.1, 1]), the back wall (z in [-1.1, -1]) spans the full width between them, and
    the side walls fit between floor, ceiling and back wall. The short box
    (0.6 x 0.6 x 0.6, rotated by -17 degrees about y) stands front right, the tall box
    (0.6 x 1.2 x 0.6, rotated by +17 degrees) back left, both on the floor.

    Returns
    -------
    Scene
        Meshes ``floor``, ``ceiling``, ``back_wall``, ``left_wall``, ``right_wall``,
        ``short_box``, ``tall_box``, flat shaded. The suggested view is the classic one:
        perspective from (0, 1, 3.9) toward (0, 1, 0) with a 39-degree vertical field of view.

    Notes
    -----
    The box positions and angles follow the measured Cornell box as distributed by
    McGuire (CornellBox-Original.obj, Computer Graphics Archive, 2017), whose short box
    is centred near (0.33, 0.37) in xz and turned by about -16.6 degrees, and tall box near
    (-0.335, -0.29), turned by about +17.5 degrees. There is no light: AO needs none.

    References
    ----------
    .. [1] Goral, Torrance, Greenberg, Battaile, "Modeling the interaction of light between
       diffuse surfaces", SIGGRAPH 1984.
    .. [2] M. McGuire, Computer Graphics Archive, https://casual-effects.com/data, 2017.

    Examples
    --------
    >>> from vobscure.scenes import cornell_box
    >>> vo_scene = cornell_box()
    >>> vo_scene.is_watertight, len(vo_scene.meshes)
    (True, 7)
    """
    T = 0.1  # wall thickness
    meshes = {
        "floor": _box((-1 - T, -T, -1 - T), (1 + T, 0.0, 1.0)),
        "ceiling": _box((-1 - T, 2.0, -1 - T), (1 + T, 2.0 + T, 1.0)),
        "back_wall": _box((-1 - T, 0.0, -1 - T), (1 + T, 2.0, -1.0)),
        "left_wall": _box((-1 - T, 0.0, -1.0), (-1.0, 2.0, 1.0)),
        "right_wall": _box((1.0, 0.0, -1.0), (1 + T, 2.0, 1.0)),
        "short_box": _box((0.33 - 0.3, 0.0, 0.37 - 0.3), (0.33 + 0.3, 0.6, 0.37 + 0.3), angle_y=-17.0),
        "tall_box": _box((-0.335 - 0.3, 0.0, -0.29 - 0.3), (-0.335 + 0.3, 1.2, -0.29 + 0.3),
                         angle_y=17.0),
    }
    view = _view((0.0, 1.0, 3.9), (0.0, 1.0, 0.0), fov_y=39.0)
    return Scene(meshes, name="cornell_box", view=view, smooth_angle=0.0)


def blob(*, subdivisions: int = 4, detail: int = 8, amplitude: float = 0.25, seed=0) -> Scene:
    """A lumpy closed star-shaped solid with many concavities: a stand-in for a scanned model.

    An icosphere's vertices u (unit vectors) are moved radially to
    r(u) = 1 + amplitude f(u), where f is a sum of ``detail`` Gaussian lobes on the sphere,
    f(u) = sum_k s_k m_k exp((u . c_k - 1) / sigma_k^2), with random centres c_k (uniform
    on the sphere), signs s_k (bumps and dents; at least one of each when detail >= 2),
    magnitudes m_k in [0.5, 1] and angular widths sigma_k in [0.2, 0.5] radians, and
    normalised so that max |f| over the vertices is 1.

    Parameters
    ----------
    subdivisions : int, optional
        Subdivision level of the icosphere (20 * 4**subdivisions triangles), 0 to 8.
    detail : int, optional
        Number of lobes (>= 1).
    amplitude : float, optional
        Largest radial displacement, 0 <= amplitude <= 0.6, so the radius stays in
        [1 - amplitude, 1 + amplitude].
    seed : int, numpy.random.Generator or None, optional
        The same seed gives the same blob, bit for bit.

    Returns
    -------
    Scene
        One mesh ``"blob"``, smooth shaded (60 degrees).

    Notes
    -----
    Moving every vertex along its own ray to a positive radius keeps each triangle's
    radial projection equal to the icosphere's spherical triangle, so the surface stays a
    single-valued graph over the sphere: closed, star-shaped about the origin and free of
    self-intersections for any positive radii.

    Examples
    --------
    >>> from vobscure.scenes import blob
    >>> vo_scene = blob(subdivisions=3, seed=1)
    >>> vo_scene.is_watertight
    True
    """
    subdivisions = _check_subdivisions(subdivisions)
    detail = check_int(detail, "detail", minimum=1)
    amplitude = check_positive(amplitude, "amplitude", allow_zero=True)
    if amplitude > _BLOB_MAX_AMPLITUDE:
        raise ValueError(f"amplitude must be at most {_BLOB_MAX_AMPLITUDE} so the radius stays "
                         f"positive and the bumps stay resolvable, got {amplitude}")
    rng = as_rng(seed)
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    u = np.asarray(sphere.vertices, dtype=np.float64)
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    c = rng.normal(size=(detail, 3))
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    s = rng.choice([-1.0, 1.0], size=detail)
    if detail >= 2 and np.all(s == s[0]):
        s[-1] = -s[0]
    m = rng.uniform(0.5, 1.0, size=detail)
    sigma = rng.uniform(0.2, 0.5, size=detail)
    f = (s * m * np.exp((u @ c.T - 1.0) / sigma**2)).sum(axis=1)
    f /= np.max(np.abs(f))
    r = 1.0 + amplitude * f
    mesh = trimesh.Trimesh(u * r[:, None], np.asarray(sphere.faces), process=False)
    view = _view((0.0, 1.2, 4.0), (0.0, 0.0, 0.0))
    return Scene({"blob": mesh}, name="blob", view=view, smooth_angle=_SMOOTH_ANGLE)


# --------------------------------------------------------------------------------------
# Registry
# --------------------------------------------------------------------------------------

_BUILDERS = {
    "blob": blob,
    "cornell_box": cornell_box,
    "crease": crease,
    "groove": groove,
    "slab": slab,
    "sphere_on_plane": sphere_on_plane,
    "steps": steps,
    # vegetation (open, two-sided foliage; vobscure.scenes.vegetation)
    "grass": grass,
    "leaf_cloud": leaf_cloud,
    "leaf_cloud_dense": leaf_cloud_dense,
    "tree": tree,
    "tree_poplar": tree_poplar,
    # the interior (open banners and alpha-tested leaf cards; vobscure.scenes.atrium)
    "atrium": atrium,
    # thin occluders on a floor before a wall, all closed (vobscure.scenes.thin)
    "thin_occluders": thin_occluders,
}


def names() -> list[str]:
    """Sorted names of the procedural scenes that :func:`get` builds: the closed solids of
    this module, the vegetation scenes of :mod:`vobscure.scenes.vegetation` (``grass``,
    ``leaf_cloud``, ``leaf_cloud_dense``, ``tree``, ``tree_poplar``), whose foliage is open,
    and the interior of :mod:`vobscure.scenes.atrium` (``atrium``).

    Examples
    --------
    >>> from vobscure.scenes import names
    >>> names()  # doctest: +NORMALIZE_WHITESPACE
    ['atrium', 'blob', 'cornell_box', 'crease', 'grass', 'groove', 'leaf_cloud', 'leaf_cloud_dense',
     'slab', 'sphere_on_plane', 'steps', 'thin_occluders', 'tree', 'tree_poplar']
    """
    return sorted(_BUILDERS)


def get(name: str, **kwargs) -> Scene:
    """Build the procedural scene called ``name`` with the builder's keyword arguments.

    Parameters
    ----------
    name : str
        One of :func:`names`.
    **kwargs
        Passed to the builder, e.g. ``get("groove", angle=60.0)``.

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        For an unknown name (the message lists the valid ones) or a bad keyword argument.

    Examples
    --------
    >>> from vobscure.scenes import get
    >>> get("crease", length=2.0).name
    'crease'
    """
    builder = _BUILDERS.get(name) if isinstance(name, str) else None
    if builder is None:
        raise ValueError(f"name must be one of {', '.join(repr(n) for n in names())}; got {name!r}")
    try:
        inspect.signature(builder).bind(**kwargs)
    except TypeError as exc:
        raise ValueError(f"bad arguments for scene {name!r}: {exc}") from None
    return builder(**kwargs)
