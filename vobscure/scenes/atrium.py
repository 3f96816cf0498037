"""A procedural atrium: two storeys of arcades around a courtyard open to the sky, in metres.

The realistic interior of the library: what a user's scene looks like (columns, round
arches, galleries, thin banners and chains, alpha-tested foliage, open and closed meshes
side by side) with every dimension known, built in a few tenths of a second on a machine
with no downloads.

World space is right-handed, y up, in metres. The courtyard is the rectangle between the
column lines, x in [-L/2, L/2] (the long axis) and z in [-W/2, W/2]; the floor's top is
y = 0. Around it, on each storey of height ``storey_height`` (H), an arcade: columns at
every bay's end, round arches between them, a covered walk ``arcade_depth`` deep out to the
outer wall. The first storey's ceiling is the gallery floor of the second, whose arcade has
a parapet between its columns; a roof covers the upper walk. The courtyard itself has no
roof.

Meshes
------
``"floor"``, ``"walls"``, ``"slabs"``, ``"columns"``, ``"arches"``, ``"parapets"``,
``"pots"``, ``"lanterns"``, ``"chains"``
    Structural solids, each part closed (watertight, consistently wound, outward normals,
    positive volume). Parts touch along faces (a column's capital and the arch above it,
    a slab and the wall) but do not overlap in volume. ``"chains"`` are closed links of
    1 cm wire (tori around an elliptic centreline) hanging from the crowns of the ground
    storey's arches, a lantern at each end.
``"banners"``
    Open: one folded sheet per banner (a grid of quads, no thickness) hanging from the roof
    over the courtyard face of the upper storey.
``"leaves"``
    Open: leaf cards (one quad of two triangles per leaf) of potted plants, alpha-tested:
    ``scene.alpha["leaves"]`` is an :class:`~vobscure.scenes.AlphaMask` whose texture,
    :func:`leaf_texture`, is a compound leaf (a midrib, pairs of elliptic leaflets and a
    terminal one), cutoff 0.5.

The scene as a whole is therefore not watertight (``scene.is_watertight`` is False), as
real scenes are not; ``scene.metadata["structural_meshes"]`` names the closed meshes.

Metadata
--------
``"units"`` : ``"m"``
``"kind"`` : ``"atrium"``
``"parameters"`` : dict
    The builder's arguments, defaults filled in (the seed as an int, None or
    ``"Generator"``).
``"courtyard"`` : (2,)
    (L, W), the distances between opposite column lines.
``"storey_height"`` : float
``"springing_height"`` : float
    Height of the capitals' tops (where the arches spring) above each storey's floor.
``"column_centers"`` : (n, 2)
    x, z of every column (both storeys stand on the same lines).
``"open_meshes"`` : list of str, ``"structural_meshes"`` : list of str
``"n_triangles"`` : dict of str to int
    Triangles per mesh.
``"views"`` : dict of str to dict
    Named cameras (eye, target, up, fov_y): ``"arcade"`` (the default view, ``scene.view``)
    and ``"gallery"``.

Examples
--------
>>> from vobscure.scenes import atrium
>>> scene = atrium()
>>> scene.metadata["units"], scene.is_watertight, sorted(scene.alpha)
('m', False, ['leaves'])
>>> all(scene.meshes[m].is_watertight for m in scene.metadata["structural_meshes"])
True
"""

from __future__ import annotations

import numbers

import numpy as np
import trimesh

from .._validate import as_rng, check_int, check_positive
from ._alpha import AlphaMask
from ._scene import Scene

__all__ = ["atrium", "leaf_texture"]

# Dimensions of the parts, in metres. The values are those of a modest stone arcade; what
# the tests rely on is written next to each.
#: Thickness of the outer wall.
WALL_THICKNESS = 0.5
#: How far the outer wall rises above the roof (a parapet around the roof).
WALL_ABOVE_ROOF = 0.6
#: Thickness of the ground slab, the gallery floor and the roof.
SLAB_THICKNESS = 0.3
#: How far a slab reaches from the column line into the courtyard; more than the
#: pedestals' half width, so that every upper column stands on the slab.
SLAB_OVERHANG = 0.4
#: Half width (square) and height of a ground column's plinth.
PLINTH_HALF, PLINTH_HEIGHT = 0.35, 0.3
#: Height of an upper column's pedestal: the parapet's height, so that parapets abut it.
PEDESTAL_HEIGHT = 1.0
#: Radius of a column's shaft.
SHAFT_RADIUS = 0.2
#: Half width (square) and height of a capital. Wider than the arches' half thickness, so
#: the arcade wall stands on the capitals.
CAPITAL_HALF, CAPITAL_HEIGHT = 0.3, 0.25
#: Half thickness of the arcade wall (the arches) across its line.
ARCH_HALF_THICKNESS = 0.25
#: Wall left between the highest arch's crown and the slab above it.
CROWN_CLEARANCE = 0.3
#: Half thickness of a parapet's wall, half width and height of its coping.
PARAPET_HALF, COPING_HALF, COPING_HEIGHT = 0.1, 0.15, 0.08
#: Shortest column shaft accepted (the upper storey's, above its pedestal).
MIN_SHAFT = 0.5
#: Smallest clear span of an arch (between two capitals).
MIN_SPAN = 0.6
#: Chain links: half length a and half width b of the wire's centreline (an ellipse), the
#: wire's radius r (1 cm wire), and the gap between interlocking links. The tube does not
#: fold over itself while r < b^2 / a, the centreline's smallest radius of curvature.
LINK_A, LINK_B, WIRE_RADIUS, LINK_GAP = 0.03, 0.018, 0.005, 0.001
#: Around-the-wire segments of a link.
WIRE_SEGMENTS = 6
#: Lantern at a chain's end: half width and height.
LANTERN_HALF, LANTERN_HEIGHT = 0.08, 0.24
#: Gap between the top link and the arch's crown, and between the last link and the lantern.
HANG_GAP = 0.003
#: Banners: width, length, distance in front of the slab edge, fold depth, fold count, grid.
BANNER_WIDTH, BANNER_LENGTH, BANNER_OFFSET = 1.2, 3.0, 0.05
BANNER_FOLD, BANNER_FOLDS, BANNER_GRID = 0.03, 3, (6, 12)
#: Pots: bottom radius, top radius, height; distance of their centres from the column line.
POT_R0, POT_R1, POT_HEIGHT, POT_INSET = 0.18, 0.25, 0.5, 1.2
#: Leaf cards: length range, width / length, elevation range (degrees), roll (degrees),
#: height of their base above the soil and its distance from the plant's axis.
LEAF_LENGTH, LEAF_ASPECT, LEAF_ELEVATION, LEAF_ROLL = (0.45, 0.65), 0.55, (20.0, 70.0), 20.0
LEAF_BASE_HEIGHT, LEAF_BASE_RADIUS = 0.08, 0.03
#: Alpha cutoff of the leaf cards (glTF's default alphaCutoff).
LEAF_CUTOFF = 0.5
#: Side of the leaf texture in texels, and supersamples per texel side (antialiased edges).
LEAF_TEXTURE_SIZE, LEAF_SUPERSAMPLES = 128, 4

_STRUCTURAL = ["floor", "walls", "slabs", "columns", "arches", "parapets", "pots", "lanterns",
               "chains"]
_OPEN = ["banners", "leaves"]
#: Crease angles (degrees) of the shading normals: round parts smooth, the rest flat. An
#: arch's intrados facets meet at 180 / arch_segments degrees, its other edges at 90.
_SMOOTH = {"columns": 60.0, "arches": 30.0, "pots": 60.0, "chains": 60.0, "banners": 60.0}


# --------------------------------------------------------------------------------------
# Parts: each returns (vertices, faces) of closed, outward-wound solids or open sheets
# --------------------------------------------------------------------------------------

def _box(lo, hi):
    """The axis-aligned box [lo, hi]: 8 vertices, 12 outward-wound triangles."""
    unit = trimesh.creation.box()  # the cube [-0.5, 0.5]^3, outward normals
    corner = np.asarray(unit.vertices) > 0
    return np.where(corner, np.asarray(hi, float), np.asarray(lo, float)), np.asarray(unit.faces)


def _frustum(center_xz, y0: float, y1: float, r0: float, r1: float, sides: int):
    """A vertical capped frustum: radius r0 at y0, r1 at y1 (> y0), outward wound."""
    theta = 2.0 * np.pi * np.arange(sides) / sides
    # counter-clockwise seen from +y: x = cos, z = -sin
    ring = np.column_stack([np.cos(theta), np.zeros(sides), -np.sin(theta)])
    c = np.array([center_xz[0], 0.0, center_xz[1]])
    vertices = np.concatenate([c + r0 * ring + [0.0, y0, 0.0], c + r1 * ring + [0.0, y1, 0.0],
                               [c + [0.0, y0, 0.0], c + [0.0, y1, 0.0]]])
    i = np.arange(sides)
    j = (i + 1) % sides
    bottom, top = 2 * sides, 2 * sides + 1
    faces = np.concatenate([
        np.column_stack([i, j, j + sides]),                   # side quads, facing out
        np.column_stack([i, j + sides, i + sides]),
        np.column_stack([np.full(sides, top), i + sides, j + sides]),  # top cap, facing +y
        np.column_stack([np.full(sides, bottom), j, i]),      # bottom cap, facing -y
    ])
    return vertices, faces


def _arcade_block(bottom_s, bottom_y, y_top: float, half: float):
    """The arcade wall of one side and storey, in local coordinates (s, y, t).

    s runs along the arcade, t across it (s, y, t right-handed). The profile in the (s, y)
    plane lies between the polyline ``(bottom_s, bottom_y)`` (s strictly increasing: flat
    runs over the capitals and the arches' intradoses) and the line y = ``y_top``; it is
    extruded over t in [-half, half]. The profile is s-monotone, so the strips between
    each bottom vertex and the point above it on the top line triangulate it.
    """
    m = len(bottom_s)
    # the profile, counter-clockwise: the bottom left to right, then the top right to left
    profile = np.concatenate([np.column_stack([bottom_s, bottom_y]),
                              np.column_stack([bottom_s[::-1], np.full(m, y_top)])])
    n = 2 * m
    k = np.arange(m - 1)
    # strip k: bottom k, bottom k + 1, top above k + 1 (index n - 2 - k), top above k (n - 1 - k)
    cap = np.concatenate([np.column_stack([k, k + 1, n - 2 - k]),
                          np.column_stack([k, n - 2 - k, n - 1 - k])])
    vertices = np.concatenate([
        np.column_stack([profile[:, 0], profile[:, 1], np.full(n, -half)]),
        np.column_stack([profile[:, 0], profile[:, 1], np.full(n, half)])])
    i = np.arange(n)
    j = (i + 1) % n
    # a counter-clockwise profile has its outside on the right of each edge, so the quad
    # (front i, front j, back j, back i) is counter-clockwise seen from outside
    faces = np.concatenate([cap[:, ::-1],          # front cap, facing -t
                            cap + n,               # back cap, facing +t
                            np.column_stack([i, j, j + n]),
                            np.column_stack([i, j + n, i + n])])
    return vertices, faces


def _arch_bottom(ends, bays, spring: float, radius: float, segments: int):
    """The bottom polyline of an arcade: flat over each capital, a semicircle in each bay.

    ``ends`` = (s0, s1) are where the block starts and ends; ``bays`` the s of the column
    centres. Each bay k has an arch of ``radius`` centred between its columns, springing
    at height ``spring`` from the capitals' faces (``CAPITAL_HALF`` from the centres).
    """
    s, y = [ends[0]], [spring]
    theta = np.pi - np.pi * np.arange(segments + 1) / segments  # pi .. 0: left to right
    for left, right in zip(bays[:-1], bays[1:]):
        centre = 0.5 * (left + right)
        s.extend(centre + radius * np.cos(theta))
        y.extend(spring + radius * np.sin(theta))
        # the arcs end exactly on the capitals' faces
        s[-segments - 1], s[-1] = left + CAPITAL_HALF, right - CAPITAL_HALF
        y[-segments - 1], y[-1] = spring, spring
    s.append(ends[1])
    y.append(spring)
    return np.asarray(s), np.asarray(y)


def _link(center, axis: int, segments: int):
    """One chain link hanging along y: a torus of radius ``WIRE_RADIUS`` around the ellipse
    of half length ``LINK_A`` (along y) and half width ``LINK_B`` (along x for axis 0, z for
    axis 2), centred at ``center``; closed and outward wound."""
    e1 = np.zeros(3)
    e1[axis] = 1.0
    ey = np.array([0.0, 1.0, 0.0])
    binormal = np.cross(e1, ey)  # the normal of the link's plane; (tangent x binormal) is outward
    u = 2.0 * np.pi * np.arange(segments) / segments
    v = 2.0 * np.pi * np.arange(WIRE_SEGMENTS) / WIRE_SEGMENTS
    centre_line = LINK_B * np.cos(u)[:, None] * e1 + LINK_A * np.sin(u)[:, None] * ey
    # outward normal of the ellipse (x/b)^2 + (y/a)^2 = 1 at u: the gradient (cos u / b, sin u / a)
    normal = LINK_A * np.cos(u)[:, None] * e1 + LINK_B * np.sin(u)[:, None] * ey
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    ring = (np.cos(v)[None, :, None] * normal[:, None, :]
            + np.sin(v)[None, :, None] * binormal[None, None, :])
    vertices = (np.asarray(center, float) + centre_line[:, None, :] + WIRE_RADIUS * ring).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(segments), np.arange(WIRE_SEGMENTS), indexing="ij")
    i1, j1 = (i + 1) % segments, (j + 1) % WIRE_SEGMENTS
    v00, v10 = i * WIRE_SEGMENTS + j, i1 * WIRE_SEGMENTS + j
    v11, v01 = i1 * WIRE_SEGMENTS + j1, i * WIRE_SEGMENTS + j1
    faces = np.concatenate([np.stack([v00, v10, v11], -1).reshape(-1, 3),
                            np.stack([v00, v11, v01], -1).reshape(-1, 3)])
    return vertices, faces


def _banner(s_center: float, y_top: float, plane: float, toward: float, along: int):
    """A folded hanging sheet: ``BANNER_WIDTH`` wide along world axis ``along`` (0 = x,
    2 = z) centred on ``s_center``, from ``y_top`` down by ``BANNER_LENGTH``, in the plane
    (other horizontal axis) = ``plane``; its folds bulge by up to ``BANNER_FOLD`` towards
    ``toward`` (+1 or -1 along that axis), deeper towards the bottom."""
    nu, nv = BANNER_GRID
    a = (np.arange(nu + 1) / nu)[:, None]
    b = (np.arange(nv + 1) / nv)[None, :]
    fold = BANNER_FOLD * 0.5 * (1.0 - np.cos(2.0 * np.pi * BANNER_FOLDS * a)) * (0.3 + 0.7 * b)
    vertices = np.zeros((nu + 1, nv + 1, 3))
    other = 2 - along
    vertices[..., along] = s_center + BANNER_WIDTH * (a - 0.5)
    vertices[..., 1] = y_top - BANNER_LENGTH * b
    vertices[..., other] = plane + toward * fold
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    v00, v10 = i * (nv + 1) + j, (i + 1) * (nv + 1) + j
    v11, v01 = (i + 1) * (nv + 1) + j + 1, i * (nv + 1) + j + 1
    faces = np.concatenate([np.stack([v00, v10, v11], -1).reshape(-1, 3),
                            np.stack([v00, v11, v01], -1).reshape(-1, 3)])
    return vertices.reshape(-1, 3), faces


def _leaf_cards(rng: np.random.Generator, base, n: int):
    """``n`` leaf cards of one plant rising from ``base`` (3,): vertices (4n, 3), faces
    (2n, 3) and per-face-corner texture coordinates (2n, 3, 2); v = 0 at the card's base."""
    k = np.arange(n)
    phi = 2.0 * np.pi * (k + rng.uniform(-0.3, 0.3, n)) / n
    elevation = np.radians(rng.uniform(*LEAF_ELEVATION, n))
    length = rng.uniform(*LEAF_LENGTH, n)
    roll = np.radians(rng.uniform(-LEAF_ROLL, LEAF_ROLL, n))
    radial = np.column_stack([np.cos(phi), np.zeros(n), np.sin(phi)])
    d = np.cos(elevation)[:, None] * radial + np.sin(elevation)[:, None] * [0.0, 1.0, 0.0]
    h = np.column_stack([-np.sin(phi), np.zeros(n), np.cos(phi)])  # horizontal, across the card
    h = np.cos(roll)[:, None] * h + np.sin(roll)[:, None] * np.cross(d, h)
    p0 = np.asarray(base, float) + LEAF_BASE_RADIUS * radial
    half_w = (0.5 * LEAF_ASPECT * length)[:, None] * h
    tip = length[:, None] * d
    corners = np.stack([p0 - half_w, p0 + half_w, p0 + tip + half_w, p0 + tip - half_w], axis=1)
    faces = (np.array([[0, 1, 2], [0, 2, 3]])[None] + 4 * k[:, None, None]).reshape(-1, 3)
    uv_quad = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    uv = np.tile(uv_quad[np.array([[0, 1, 2], [0, 2, 3]])], (n, 1, 1))
    return corners.reshape(-1, 3), faces, uv


def leaf_texture(size: int = LEAF_TEXTURE_SIZE) -> np.ndarray:
    """The alpha texture of the atrium's leaf cards: a compound leaf on a transparent card.

    In texture coordinates (u across the card, v from its base, v = 0, to its tip, v = 1)
    the leaf is the union of a midrib, |u - 0.5| <= 0.02 for v <= 0.9; a terminal leaflet,
    the ellipse centred at (0.5, 0.8) with semi-axes 0.12 (u) and 0.18 (v); and three pairs
    of leaflets, ellipses of semi-axes 0.2 by 0.075 centred at (0.5 +- 0.22, v_k + 0.05),
    v_k = 0.22, 0.42, 0.62, their long axes turned 30 degrees up from the u axis. Alpha is
    the covered fraction of each texel (4 x 4 samples), so edges are antialiased.

    Parameters
    ----------
    size : int, optional
        Side of the square texture in texels (>= 8).

    Returns
    -------
    (size, size) float32
        Alpha in [0, 1]; row 0 is the top of the image (v = 1), as
        :class:`~vobscure.scenes.AlphaMask` expects. The leaflets' total area bounds the
        solid fraction by 0.39 (the sum of their areas), so at least 61 % of the texels
        are holes at the cutoff 0.5, up to antialiasing.

    Examples
    --------
    >>> from vobscure.scenes.atrium import leaf_texture
    >>> alpha = leaf_texture(64)
    >>> alpha.shape, alpha.dtype, float(alpha[0, 0]), float(alpha[64 - 52, 32])  # corner, v = 0.8
    ((64, 64), dtype('float32'), 0.0, 1.0)
    """
    size = check_int(size, "size", minimum=8)
    n = size * LEAF_SUPERSAMPLES
    centres = (np.arange(n) + 0.5) / n
    u = centres[None, :]
    v = 1.0 - centres[:, None]  # row 0 is v = 1
    solid = (np.abs(u - 0.5) <= 0.02) & (v <= 0.9)
    solid |= ((u - 0.5) / 0.12) ** 2 + ((v - 0.8) / 0.18) ** 2 <= 1.0
    for v_k in (0.22, 0.42, 0.62):
        for side in (-1.0, 1.0):
            angle = np.radians(30.0)
            du, dv = u - (0.5 + side * 0.22), v - (v_k + 0.05)
            # coordinates along and across the leaflet's long axis, (side cos, sin) 30 deg up
            along = side * du * np.cos(angle) + dv * np.sin(angle)
            across = -side * du * np.sin(angle) + dv * np.cos(angle)
            solid |= (along / 0.2) ** 2 + (across / 0.075) ** 2 <= 1.0
    s = LEAF_SUPERSAMPLES
    return solid.reshape(size, s, size, s).mean(axis=(1, 3)).astype(np.float32)


# --------------------------------------------------------------------------------------
# The builder
# --------------------------------------------------------------------------------------

def _pair(value, name: str, check):
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name} must be a pair (along x, along z), got {value!r}")
    return tuple(check(v, name) for v in value)


def _join(parts):
    """One mesh of several parts, each given as (vertices, faces); vertices not merged."""
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.concatenate([v for v, _ in parts])
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)])
    return trimesh.Trimesh(vertices, faces, process=False)


def _swap_xz(part):
    """A part mirrored across the plane x = z (x and z exchanged), faces re-wound outward."""
    vertices, faces = part
    return vertices[:, [2, 1, 0]], faces[:, ::-1]


def atrium(*, size=(20.0, 12.0), storey_height: float = 4.0, bays=(8, 5), arcade_depth: float = 3.0,
           arch_segments: int = 24, column_segments: int = 16, link_segments: int = 12,
           chain_length: float = 1.0, leaves_per_plant: int = 24, seed=0) -> Scene:
    """A two-storey arcaded courtyard in metres, open to the sky: the library's interior.

    See :mod:`vobscure.scenes.atrium` for the meshes and the metadata.

    Parameters
    ----------
    size : (2,) float, optional
        (L, W): the courtyard between the column lines, along x and z, metres.
    storey_height : float, optional
        Floor-to-floor height H; the gallery floor's top is y = H, the roof's y = 2 H.
    bays : (2,) int, optional
        Bays along x and along z (columns per line: bays + 1, corners shared), >= 2 each.
        Every arch springs at the same height; the wider bays' arches reach
        ``CROWN_CLEARANCE`` below the slab.
    arcade_depth : float, optional
        Depth of the covered walks, from the column line to the outer wall (>= 1 m).
    arch_segments : int, optional
        Straight segments of each arch's semicircle (>= 2).
    column_segments : int, optional
        Sides of the column shafts and the pots (>= 3).
    link_segments : int, optional
        Segments along each chain link (>= 4).
    chain_length : float, optional
        Length of each chain (> 0), hung from the crown of every second ground-floor arch of
        the long sides; its lantern must end at least 1 m above the floor.
    leaves_per_plant : int, optional
        Leaf cards of each potted plant (>= 1); a plant stands in front of every second bay
        of the long sides.
    seed : int, numpy.random.Generator or None, optional
        The plants' leaf directions, lengths and rolls; the same seed gives the same scene,
        bit for bit. Nothing else is random.

    Returns
    -------
    Scene
        The meshes of :mod:`vobscure.scenes.atrium`; 41 324 triangles with the
        defaults, 23 040 of them the chains' links. ``scene.view`` is the default camera: in the south arcade at eye height
        (1.6 m), looking along the long axis (+x) and across the courtyard.

    Raises
    ------
    ValueError
        For a bad argument (named in the message), or dimensions whose parts do not fit
        (bays too narrow for an arch, a storey too low for its columns, a chain too long).

    Examples
    --------
    >>> from vobscure.scenes import atrium
    >>> scene = atrium(bays=(6, 4), arch_segments=8, leaves_per_plant=4)
    >>> scene.metadata["courtyard"], len(scene.metadata["column_centers"])
    ((20.0, 12.0), 20)
    >>> sorted(scene.metadata["views"])
    ['arcade', 'gallery']
    """
    L, W = _pair(size, "size", check_positive)
    n_x, n_z = _pair(bays, "bays", lambda v, name: check_int(v, name, minimum=2))
    H = check_positive(storey_height, "storey_height")
    D = check_positive(arcade_depth, "arcade_depth")
    if D < 1.0:
        raise ValueError(f"arcade_depth must be at least 1 m (a walk behind the columns), got {D}")
    arch_segments = check_int(arch_segments, "arch_segments", minimum=2)
    column_segments = check_int(column_segments, "column_segments", minimum=3)
    link_segments = check_int(link_segments, "link_segments", minimum=4)
    chain_length = check_positive(chain_length, "chain_length")
    leaves_per_plant = check_int(leaves_per_plant, "leaves_per_plant", minimum=1)
    rng = as_rng(seed)

    bay_x, bay_z = L / n_x, W / n_z
    for bay, axis, n in ((bay_x, "x", n_x), (bay_z, "z", n_z)):
        if bay - 2.0 * CAPITAL_HALF < MIN_SPAN:
            raise ValueError(
                f"size and bays leave bays of {bay:.3g} m along {axis} ({n} bays); an arch needs "
                f"at least {MIN_SPAN + 2 * CAPITAL_HALF:g} m (a clear span of {MIN_SPAN:g} m "
                f"between capitals {2 * CAPITAL_HALF:g} m wide): use fewer bays or a larger size")
    radius = 0.5 * (max(bay_x, bay_z) - 2.0 * CAPITAL_HALF)  # the widest arch
    crown = H - SLAB_THICKNESS - CROWN_CLEARANCE                # its crown, above a storey's floor
    spring = crown - radius
    upper_shaft = spring - CAPITAL_HEIGHT - PEDESTAL_HEIGHT
    if upper_shaft < MIN_SHAFT:
        raise ValueError(
            f"storey_height {H:g} m is too low for arches of radius {radius:.3g} m "
            f"(bays of {max(bay_x, bay_z):.3g} m): the upper columns' shafts would be "
            f"{upper_shaft:.3g} m, at least {MIN_SHAFT:g} m are needed; need storey_height >= "
            f"{H + MIN_SHAFT - upper_shaft:.3g} or narrower bays")

    xs = -0.5 * L + bay_x * np.arange(n_x + 1)
    zs = -0.5 * W + bay_z * np.arange(n_z + 1)
    xs[-1], zs[-1] = 0.5 * L, 0.5 * W  # the corners exactly on the lines
    columns = [(x, z) for z in (-0.5 * W, 0.5 * W) for x in xs]
    columns += [(x, z) for x in (-0.5 * L, 0.5 * L) for z in zs[1:-1]]
    columns = np.asarray(columns)
    t = ARCH_HALF_THICKNESS
    outer_x, outer_z = 0.5 * L + D, 0.5 * W + D          # inner faces of the outer wall
    top = 2.0 * H + WALL_ABOVE_ROOF
    T = WALL_THICKNESS

    floor = [_box((-outer_x - T, -SLAB_THICKNESS, -outer_z - T), (outer_x + T, 0.0, outer_z + T))]
    walls = [_box((-outer_x - T, 0.0, sign * outer_z + min(0, sign) * T),
                  (outer_x + T, top, sign * outer_z + max(0, sign) * T)) for sign in (-1, 1)]
    walls += [_box((sign * outer_x + min(0, sign) * T, 0.0, -outer_z),
                   (sign * outer_x + max(0, sign) * T, top, outer_z)) for sign in (-1, 1)]

    slabs, parts_columns, arches, parapets = [], [], [], []
    e = SLAB_OVERHANG
    for y_floor in (H, 2.0 * H):  # the gallery floor, the roof
        y0 = y_floor - SLAB_THICKNESS
        for sign in (-1, 1):
            # long strips (full length, out to the walls), then short ones between them
            slabs.append(_box((-outer_x, y0, min(sign * (0.5 * W - e), sign * outer_z)),
                              (outer_x, y_floor, max(sign * (0.5 * W - e), sign * outer_z))))
            slabs.append(_box((min(sign * (0.5 * L - e), sign * outer_x), y0, -(0.5 * W - e)),
                              (max(sign * (0.5 * L - e), sign * outer_x), y_floor, 0.5 * W - e)))
    for storey, base in enumerate((0.0, H)):
        foot = PLINTH_HEIGHT if storey == 0 else PEDESTAL_HEIGHT
        for x, z in columns:
            parts_columns.append(_box((x - PLINTH_HALF, base, z - PLINTH_HALF),
                                      (x + PLINTH_HALF, base + foot, z + PLINTH_HALF)))
            parts_columns.append(_frustum((x, z), base + foot, base + spring - CAPITAL_HEIGHT,
                                          SHAFT_RADIUS, SHAFT_RADIUS, column_segments))
            parts_columns.append(_box((x - CAPITAL_HALF, base + spring - CAPITAL_HEIGHT, z - CAPITAL_HALF),
                                      (x + CAPITAL_HALF, base + spring, z + CAPITAL_HALF)))
        y_top = base + H - SLAB_THICKNESS
        r_x, r_z = 0.5 * bay_x - CAPITAL_HALF, 0.5 * bay_z - CAPITAL_HALF
        # long sides span the corners (out to the short sides' outer faces), short sides fit between
        s, y = _arch_bottom((-0.5 * L - t, 0.5 * L + t), xs, base + spring, r_x, arch_segments)
        for z in (-0.5 * W, 0.5 * W):
            v, f = _arcade_block(s, y, y_top, t)
            arches.append((v + [0.0, 0.0, z], f))
        s, y = _arch_bottom((-0.5 * W + t, 0.5 * W - t), zs, base + spring, r_z, arch_segments)
        for x in (-0.5 * L, 0.5 * L):
            v, f = _arcade_block(s, y, y_top, t)
            arches.append(_swap_xz((v + [0.0, 0.0, x], f)))
    # parapets between the upper pedestals, on the column lines
    y1, y2 = H + PEDESTAL_HEIGHT - COPING_HEIGHT, H + PEDESTAL_HEIGHT
    for line, stations, swap in ((0.5 * W, xs, False), (0.5 * L, zs, True)):
        for c in (-line, line):
            for a, b in zip(stations[:-1], stations[1:]):
                a1, b1 = a + PLINTH_HALF, b - PLINTH_HALF
                pieces = [_box((a1, H, c - PARAPET_HALF), (b1, y1, c + PARAPET_HALF)),
                          _box((a1, y1, c - COPING_HALF), (b1, y2, c + COPING_HALF))]
                parapets += [_swap_xz(p) for p in pieces] if swap else pieces

    # chains with lanterns from the crowns of the odd ground-floor bays of the long sides
    chains, lanterns = [], []
    crown_y = spring + r_x * (1.0 if arch_segments % 2 == 0 else np.cos(0.5 * np.pi / arch_segments))
    pitch = 2.0 * (LINK_A - WIRE_RADIUS) - LINK_GAP   # interlocking: the wires pass LINK_GAP apart
    n_links = max(1, int(chain_length // pitch))
    lantern_bottom = crown_y - HANG_GAP - 2 * (LINK_A + WIRE_RADIUS) - (n_links - 1) * pitch \
        - HANG_GAP - LANTERN_HEIGHT
    if lantern_bottom < 1.0:
        raise ValueError(f"chain_length {chain_length:g} m is too long: the lanterns would end "
                         f"{lantern_bottom:.3g} m above the floor, at least 1 m is needed "
                         f"(the arches' crowns are {crown_y:.3g} m high)")
    for z in (-0.5 * W, 0.5 * W):
        for k in range(1, n_x, 2):
            x = 0.5 * (xs[k] + xs[k + 1])
            y = crown_y - HANG_GAP - LINK_A - WIRE_RADIUS
            for i in range(n_links):
                chains.append(_link((x, y - i * pitch, z), 0 if i % 2 == 0 else 2, link_segments))
            y_end = y - (n_links - 1) * pitch - LINK_A - WIRE_RADIUS - HANG_GAP
            lanterns.append(_box((x - LANTERN_HALF, y_end - LANTERN_HEIGHT, z - LANTERN_HALF),
                                 (x + LANTERN_HALF, y_end, z + LANTERN_HALF)))

    # banners over the roof's edge in front of the upper storey: even bays of the long sides,
    # the middle bay of the short sides; folds bulge toward the courtyard
    banners = []
    y_banner = 2.0 * H - 0.05
    for sign in (-1, 1):
        plane = sign * (0.5 * W - e - BANNER_OFFSET)
        for k in range(0, n_x, 2):
            banners.append(_banner(0.5 * (xs[k] + xs[k + 1]), y_banner, plane, -sign, along=0))
        plane = sign * (0.5 * L - e - BANNER_OFFSET)
        k = n_z // 2
        banners.append(_banner(0.5 * (zs[k] + zs[k + 1]), y_banner, plane, -sign, along=2))

    # potted plants in the courtyard in front of the even bays of the long sides
    pots, leaves, uvs = [], [], []
    for sign in (-1, 1):
        for k in range(0, n_x, 2):
            centre = (0.5 * (xs[k] + xs[k + 1]), sign * (0.5 * W - POT_INSET))
            pots.append(_frustum(centre, 0.0, POT_HEIGHT, POT_R0, POT_R1, column_segments))
            base = (centre[0], POT_HEIGHT + LEAF_BASE_HEIGHT, centre[1])
            v, f, uv = _leaf_cards(rng, base, leaves_per_plant)
            leaves.append((v, f))
            uvs.append(uv)

    meshes = {name: _join(parts) for name, parts in (
        ("floor", floor), ("walls", walls), ("slabs", slabs), ("columns", parts_columns),
        ("arches", arches), ("parapets", parapets), ("pots", pots), ("lanterns", lanterns),
        ("chains", chains), ("banners", banners), ("leaves", leaves))}
    mask = AlphaMask(np.concatenate(uvs), leaf_texture(), cutoff=LEAF_CUTOFF,
                     source="atrium leaf cards (vobscure.scenes.atrium.leaf_texture)")
    views = {
        # in the south arcade at eye height, looking along it and into the courtyard
        "arcade": _view((-0.5 * L - 0.3 * D, 1.6, 0.5 * W + 0.6 * D),
                        (0.25 * L, 1.5, 0.5 * W - 0.35 * W)),
        # from the upper gallery, behind the parapet of the second bay, down into the courtyard
        "gallery": _view((-0.5 * L + 1.5 * bay_x, H + 1.6, 0.5 * W + 0.8),
                         (0.2 * L, 0.5, -0.25 * W)),
    }
    metadata = {
        "units": "m",
        "kind": "atrium",
        "parameters": {"size": (L, W), "storey_height": H, "bays": (n_x, n_z), "arcade_depth": D,
                       "arch_segments": arch_segments, "column_segments": column_segments,
                       "link_segments": link_segments, "chain_length": chain_length,
                       "leaves_per_plant": leaves_per_plant, "seed": _seed_record(seed)},
        "courtyard": (L, W),
        "storey_height": H,
        "springing_height": spring,
        "column_centers": columns,
        "open_meshes": list(_OPEN),
        "structural_meshes": list(_STRUCTURAL),
        "n_triangles": {k: len(m.faces) for k, m in meshes.items()},
        "views": views,
    }
    smooth = {k: _SMOOTH.get(k, 0.0) for k in meshes}
    return Scene(meshes, name="atrium", view=views["arcade"], smooth_angle=smooth,
                 metadata=metadata, alpha={"leaves": mask})


def _view(eye, target, *, fov_y: float = 60.0) -> dict:
    return {"eye": tuple(float(v) for v in eye), "target": tuple(float(v) for v in target),
            "up": (0.0, 1.0, 0.0), "fov_y": float(fov_y)}


def _seed_record(seed):
    """The seed as recorded in the metadata: the int, None, or "Generator"."""
    if seed is None or isinstance(seed, numbers.Integral):
        return None if seed is None else int(seed)
    return "Generator"
