"""A room corner of thin occluders, in metres: the scene where a depth buffer's "every surface
is infinitely thick" fails most visibly.

A table on four thin legs, a chair (thin legs, a seat, two back posts and a backrest slat), a
railing of thin bars between a bottom and a top rail, and a sheet 1 cm thick hanging from a bar
on two thin posts, all standing on a floor slab before a wall. Seen from the default camera,
each thin part stands in front of the floor or the wall at a depth well behind it, so a
screen-space estimator's taps from the floor and wall behind a leg, a bar or the sheet land on
it and count the space behind it as solid: the halos the thin-feature band
(:func:`vobscure.metrics.thin_feature_mask`) measures.

World space is right-handed, y up, in metres; the floor's top is y = 0 and the wall's face is
z = :data:`WALL_Z`. Every part is a union of axis-aligned boxes, each closed (watertight,
consistently wound, outward normals); boxes touch along faces (a leg and the table top, the
sheet and its bar) but never overlap in volume, so the scene is closed
(``Scene.open_meshes`` is empty) and every reference, the solid world-space VO included,
applies.

Meshes
------
``"floor"``, ``"wall"``
    Slabs 10 cm thick.
``"table"``
    A 1.0 x 0.6 m top 3 cm thick at 0.75 m on four legs :data:`TABLE_LEG` (3 cm) square.
``"chair"``
    Four legs :data:`CHAIR_LEG` (2.5 cm) square, a seat at 0.45 m, two back posts and a
    backrest slat 2 cm thick.
``"railing"``
    A bottom and a top rail, two end posts (4 cm) and bars :data:`RAIL_BAR` (1.2 cm) square
    every :data:`RAIL_SPACING` (12 cm).
``"sheet"``
    A sheet :data:`SHEET_THICKNESS` (1 cm) thick, 0.6 m wide and 1.2 m tall, hanging from a bar.
``"stand"``
    The sheet's bar and its two posts (3 cm).

Metadata
--------
``"units"`` : ``"m"``; ``"kind"`` : ``"thin_occluders"``; ``"thin_parts"`` : the names of the
meshes with thin features; ``"n_triangles"`` : triangles per mesh.

Examples
--------
>>> from vobscure.scenes import thin_occluders
>>> scene = thin_occluders()
>>> scene.open_meshes, scene.metadata["units"]
([], 'm')
"""

from __future__ import annotations

import numpy as np
import trimesh

from ._scene import Scene

__all__ = ["thin_occluders", "TABLE_LEG", "CHAIR_LEG", "RAIL_BAR", "RAIL_SPACING", "SHEET_THICKNESS",
           "WALL_Z"]

#: Side of the table's square legs (m).
TABLE_LEG = 0.03
#: Side of the chair's square legs and back posts (m).
CHAIR_LEG = 0.025
#: Side of the railing's square bars (m), and their spacing centre to centre.
RAIL_BAR, RAIL_SPACING = 0.012, 0.12
#: Thickness of the hanging sheet (m).
SHEET_THICKNESS = 0.01
#: The wall's face (z) and the floor's half extents along x and z.
WALL_Z, FLOOR_HALF_X, FLOOR_FRONT_Z = -1.6, 3.5, 2.0
#: Thickness of the floor and the wall, and the wall's height.
SLAB, WALL_HEIGHT = 0.1, 3.0


def _box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the box [lo, hi], outward wound; corners taken from lo and hi
    exactly, so that boxes meant to touch share their face planes bit for bit."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    unit = trimesh.creation.box()  # the cube [-0.5, 0.5]^3, outward normals
    return np.where(np.asarray(unit.vertices) > 0, hi, lo), np.asarray(unit.faces)


def _join(boxes) -> trimesh.Trimesh:
    """One mesh of several closed boxes; vertices not merged, so each box stays closed."""
    offsets = np.cumsum([0] + [len(v) for v, _ in boxes[:-1]])
    vertices = np.concatenate([v for v, _ in boxes])
    faces = np.concatenate([f + o for (_, f), o in zip(boxes, offsets)])
    return trimesh.Trimesh(vertices, faces, process=False)


def _legs(x0, x1, z0, z1, side, y0, y1):
    """Four square legs of ``side`` in the corners of the rectangle [x0, x1] x [z0, z1]."""
    return [_box((x, y0, z), (x + side, y1, z + side)) for x in (x0, x1 - side) for z in (z0, z1 - side)]


def _table():
    x0, x1, z0, z1, top, thick = -0.7, 0.2, -1.1, -0.5, 0.75, 0.03
    return _legs(x0 + 0.04, x1 - 0.04, z0 + 0.04, z1 - 0.04, TABLE_LEG, 0.0, top - thick) + [
        _box((x0, top - thick, z0), (x1, top, z1))]


def _chair():
    x0, x1, z0, z1, seat, thick, s = 0.35, 0.8, -0.45, 0.0, 0.45, 0.03, CHAIR_LEG
    back = 0.9
    posts = [_box((x, seat, z0), (x + s, back, z0 + s)) for x in (x0, x1 - s)]
    slat = _box((x0 + s, back - 0.12, z0), (x1 - s, back - 0.04, z0 + 0.02))
    return _legs(x0, x1, z0, z1, s, 0.0, seat - thick) + [_box((x0, seat - thick, z0), (x1, seat, z1))] + posts + [slat]


def _railing():
    x0, x1, z, height, post, rail = 0.95, 1.85, 0.3, 0.95, 0.04, 0.04
    zc = z - 0.5 * post                      # the rails and posts, 4 cm deep, centred on z
    parts = [_box((x0, 0.0, zc), (x0 + post, height, zc + post)),
             _box((x1 - post, 0.0, zc), (x1, height, zc + post)),
             _box((x0 + post, 0.0, zc), (x1 - post, rail, zc + post)),                  # bottom rail
             _box((x0 + post, height - rail, zc), (x1 - post, height, zc + post))]      # top rail
    first, last = x0 + post + 0.5 * RAIL_SPACING, x1 - post - 0.5 * RAIL_BAR
    for xc in np.arange(first, last, RAIL_SPACING):
        b = 0.5 * RAIL_BAR
        parts.append(_box((xc - b, rail, z - b), (xc + b, height - rail, z + b)))
    return parts


def _sheet_and_stand():
    x0, x1, z, bar_y, post = -1.6, -0.85, 0.3, 1.7, 0.03
    half = 0.5 * SHEET_THICKNESS
    bar = _box((x0, bar_y, z - 0.015), (x1, bar_y + 0.03, z + 0.015))
    posts = [_box((x0, 0.0, z - 0.015), (x0 + post, bar_y, z + 0.015)),
             _box((x1 - post, 0.0, z - 0.015), (x1, bar_y, z + 0.015))]
    sheet = _box((x0 + 0.1, bar_y - 1.2, z - half), (x1 - 0.1, bar_y, z + half))
    return [sheet], [bar] + posts


def thin_occluders() -> Scene:
    """A table, a chair, a railing of thin bars and a hanging sheet on a floor before a wall.

    See the module's docstring for the parts and their dimensions (:mod:`vobscure.scenes.thin`).

    Returns
    -------
    Scene
        Meshes ``"floor"``, ``"wall"``, ``"table"``, ``"chair"``, ``"railing"``, ``"sheet"``,
        ``"stand"``, all closed, flat shaded; ``metadata["units"] == "m"`` (so the default
        radius of :func:`vobscure.experiments.common.choose_radius` is half a metre, capped for
        the view). The suggested view (``scene.view``) looks at the room from the front,
        slightly above, and sees every part.

    Examples
    --------
    >>> from vobscure.scenes import thin_occluders
    >>> scene = thin_occluders()
    >>> sorted(scene.meshes), scene.is_watertight
    (['chair', 'floor', 'railing', 'sheet', 'stand', 'table', 'wall'], True)
    """
    sheet, stand = _sheet_and_stand()
    meshes = {
        "floor": _join([_box((-FLOOR_HALF_X, -SLAB, WALL_Z - SLAB), (FLOOR_HALF_X, 0.0, FLOOR_FRONT_Z))]),
        "wall": _join([_box((-FLOOR_HALF_X, 0.0, WALL_Z - SLAB), (FLOOR_HALF_X, WALL_HEIGHT, WALL_Z))]),
        "table": _join(_table()),
        "chair": _join(_chair()),
        "railing": _join(_railing()),
        "sheet": _join(sheet),
        "stand": _join(stand),
    }
    view = {"eye": (0.1, 1.5, 3.9), "target": (0.1, 0.65, -0.4), "up": (0.0, 1.0, 0.0), "fov_y": 50.0}
    metadata = {"units": "m", "kind": "thin_occluders",
                "thin_parts": ["table", "chair", "railing", "sheet", "stand"],
                "n_triangles": {k: len(m.faces) for k, m in meshes.items()}}
    return Scene(meshes, name="thin_occluders", view=view, smooth_angle=0.0, metadata=metadata)
