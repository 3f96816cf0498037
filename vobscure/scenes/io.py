"""Load triangle meshes from OBJ, PLY, STL, GLB and glTF files into a :class:`Scene`."""

from __future__ import annotations

import numbers
import os
import warnings
from pathlib import Path

import numpy as np
import trimesh

from ._scene import Scene
from .viewpoint import file_view

__all__ = ["load", "DegenerateFacesWarning", "SUPPORTED_EXTENSIONS"]

#: File extensions :func:`load` reads (case-insensitive).
SUPPORTED_EXTENSIONS = (".obj", ".ply", ".stl", ".glb", ".gltf")

#: A face is degenerate when twice its area is at most this fraction of its longest edge
#: squared (its height is below this fraction of its length), or when it repeats a vertex.
_DEGENERATE_RELATIVE_AREA = 1e-12


class DegenerateFacesWarning(UserWarning):
    """Emitted by :func:`load` when it drops zero-area faces; the message gives the count."""


def load(path, *, name: str | None = None, smooth_angle: float = 60.0) -> Scene:
    """Read a mesh file into a :class:`Scene`, one named mesh per object of the file.

    Parameters
    ----------
    path : str or os.PathLike
        An ``.obj``, ``.ply``, ``.stl``, ``.glb`` or ``.gltf`` file.
    name : str, optional
        The scene's name; the file's stem by default.
    smooth_angle : float, optional
        Crease angle in degrees (0 to 180) of the shading normals of every mesh; 0 gives
        flat shading. See :class:`Scene`.

    Returns
    -------
    Scene
        A file that holds one object gives one mesh named after the file's stem. A file
        that holds several (the groups ``g`` and objects ``o`` of an OBJ file, the nodes of
        a glTF scene) gives one mesh per object, named after it, with its scene-graph
        transform applied.

    Raises
    ------
    FileNotFoundError
        When ``path`` does not exist.
    ValueError
        For an unsupported extension (the message lists the supported ones), a file trimesh
        cannot parse, a file with no triangles, or NaN or inf vertex coordinates.

    Warns
    -----
    DegenerateFacesWarning
        When degenerate faces (zero area: a repeated vertex, or a height below 1e-12 of the
        face's longest edge) were dropped; the message says how many.

    Notes
    -----
    The file is read with ``trimesh.load(..., process=False)`` so that NaN or inf
    coordinates are seen (trimesh's processing would silently drop them) and then
    rebuilt from positions alone: texture coordinates, normals and materials are
    discarded, and vertices with exactly equal positions are merged. Merging only exact
    duplicates needs no absolute tolerance, so the result does not depend on the file's
    units, and it closes the texture seams that OBJ files split vertices along (spot.obj
    is watertight only after this). Meshes that are not closed load fine;
    :attr:`Scene.is_watertight` tells.

    Examples
    --------
    >>> import tempfile, pathlib, trimesh
    >>> from vobscure.scenes import load
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = pathlib.Path(folder) / "cube.stl"
    ...     _ = trimesh.creation.box().export(path)
    ...     vo_scene = load(path)
    >>> list(vo_scene.meshes), len(vo_scene.triangles), vo_scene.is_watertight
    (['cube'], 12, True)
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path must be a str or os.PathLike, got {type(path).__name__}")
    if name is not None and not isinstance(name, str):
        raise ValueError(f"name must be a str or None, got {type(name).__name__}")
    if (isinstance(smooth_angle, bool) or not isinstance(smooth_angle, numbers.Real)
            or not 0.0 <= float(smooth_angle) <= 180.0):
        raise ValueError(f"smooth_angle must be a number of degrees in [0, 180], got {smooth_angle!r}")
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"mesh file not found: {path}")
    if not path.is_file():
        raise ValueError(f"path must be a mesh file, {path} is not a regular file")
    ext = path.suffix.lower()
    if ext not in SUPPORTED_EXTENSIONS:
        raise ValueError(f"unsupported mesh file extension {path.suffix!r} of {path}; "
                         f"supported: {', '.join(SUPPORTED_EXTENSIONS)}")
    if path.stat().st_size == 0:
        raise ValueError(f"{path} is empty: it holds no triangles")

    options = {}
    if ext == ".obj":
        # one mesh per `o` object and `g` group, whatever their materials
        options = {"split_objects": True, "split_groups": True, "group_material": False}
    try:
        loaded = trimesh.load(str(path), file_type=ext[1:], process=False, **options)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise ValueError(f"could not read {path} as {ext[1:].upper()}: {type(exc).__name__}: {exc}") from exc

    parts = _parts(loaded, path.stem)
    if not parts:
        raise ValueError(f"{path} holds no triangles")

    meshes = {}
    dropped = {}
    total = 0
    for part_name, vertices, faces in parts:
        bad = int(np.count_nonzero(~np.isfinite(vertices)))
        if bad:
            where = "" if len(parts) == 1 else f" (mesh {part_name!r})"
            raise ValueError(f"{path}{where} has {bad} NaN or inf vertex coordinate(s); "
                             "fix or remove those vertices in the file")
        total += len(faces)
        vertices, faces = _merge_exact(vertices, faces)
        keep = ~_degenerate(vertices, faces)
        if not np.all(keep):
            dropped[part_name] = int(np.count_nonzero(~keep))
            faces = faces[keep]
        if len(faces) == 0:
            continue
        used, faces = np.unique(faces, return_inverse=True)
        meshes[part_name] = trimesh.Trimesh(vertices[used], faces.reshape(-1, 3), process=False)
    if dropped:
        count = sum(dropped.values())
        detail = "" if len(parts) == 1 else " (" + ", ".join(f"{k}: {v}" for k, v in dropped.items()) + ")"
        warnings.warn(f"{path.name}: dropped {count} degenerate (zero-area) face(s) of {total}{detail}",
                      DegenerateFacesWarning, stacklevel=2)
    if not meshes:
        raise ValueError(f"{path} holds no triangles with a non-zero area")
    return Scene(meshes, name=name if name is not None else path.stem,
                 smooth_angle=float(smooth_angle), **file_view(path, meshes))


def _parts(loaded, stem: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, vertices (n, 3) float64 in world space, faces (m, 3) int64) per triangle mesh.

    A Trimesh is one part named ``stem``; a trimesh.Scene gives one part per scene-graph
    node that instances a triangle mesh, named after the node (``stem`` when there is only
    one), with the node's transform applied. Point clouds and paths are ignored.
    """
    if isinstance(loaded, trimesh.Trimesh):
        items = [(stem, np.eye(4), loaded)]
    elif isinstance(loaded, trimesh.Scene):
        items = []
        for node in sorted(loaded.graph.nodes_geometry):
            transform, geometry_name = loaded.graph[node]
            items.append((str(node), np.asarray(transform, dtype=np.float64),
                          loaded.geometry[geometry_name]))
    else:
        items = []
    items = [(n, t, g) for n, t, g in items
             if isinstance(g, trimesh.Trimesh) and len(g.faces) > 0]
    if len(items) == 1:
        items = [(stem, items[0][1], items[0][2])]
    parts = []
    seen = set()
    for part_name, transform, geometry in items:
        unique = part_name
        i = 1
        while unique in seen:
            unique = f"{part_name}_{i}"
            i += 1
        seen.add(unique)
        vertices = np.asarray(geometry.vertices, dtype=np.float64)
        faces = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
        linear = transform[:3, :3]
        if not np.allclose(transform, np.eye(4)):
            vertices = vertices @ linear.T + transform[:3, 3]
            if np.linalg.det(linear) < 0:  # a mirroring transform turns the winding inside out
                faces = faces[:, ::-1]
        parts.append((unique, vertices, faces))
    return parts


def _merge_exact(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices with exactly equal coordinates (-0.0 equals 0.0); reindex the faces."""
    unique, inverse = np.unique(vertices + 0.0, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1)[faces]


def _degenerate(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(m,) bool: faces that repeat a vertex or have (numerically) zero area."""
    tri = vertices[faces]
    edges = tri[:, [1, 2, 0]] - tri
    longest_sq = np.max(np.einsum("ijk,ijk->ij", edges, edges), axis=1)
    twice_area = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    return repeated | (twice_area <= _DEGENERATE_RELATIVE_AREA * longest_sq)
