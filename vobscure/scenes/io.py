"""Load triangle meshes from OBJ, PLY, STL, GLB and glTF files into a :class:`Scene`, with the
alpha tests of their materials (read in :mod:`vobscure.scenes._materials`)."""

from __future__ import annotations

import io
import numbers
import os
import re
import warnings
from pathlib import Path

import numpy as np
import trimesh

from . import _materials
from ._alpha import AlphaMask
from ._materials import AlphaWarning
from ._scene import Scene
from .viewpoint import file_view

__all__ = ["load", "DegenerateFacesWarning", "AlphaWarning", "SUPPORTED_EXTENSIONS"]

#: File extensions :func:`load` reads (case-insensitive).
SUPPORTED_EXTENSIONS = (".obj", ".ply", ".stl", ".glb", ".gltf")

#: A face is degenerate when twice its area is at most this fraction of its longest edge
#: squared (its height is below this fraction of its length), or when it repeats a vertex.
_DEGENERATE_RELATIVE_AREA = 1e-12


class DegenerateFacesWarning(UserWarning):
    """Emitted by :func:`load` when it drops zero-area faces; the message gives the count."""


def load(path, *, name: str | None = None, smooth_angle: float = 60.0, alpha: bool = True) -> Scene:
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
    alpha : bool, optional
        Read the alpha tests of the materials (default): OBJ/MTL ``d``, ``Tr``, ``map_d`` and
        the alpha channel of ``map_Kd``; glTF ``alphaMode`` ``MASK`` (and ``BLEND``, read as
        a mask at 0.5) with ``alphaCutoff`` and the base colour's alpha. Texels below the
        cutoff are holes for every ray (:class:`AlphaMask`, ``docs/alpha.md``). False loads
        every mesh solid (said once in an :class:`AlphaWarning` when the file has alpha).

    Returns
    -------
    Scene
        A file that holds one object gives one mesh named after the file's stem. A file
        that holds several (the groups ``g`` and objects ``o`` of an OBJ file, the nodes of
        a glTF scene) gives one mesh per object, named after it, with its scene-graph
        transform applied. A mesh whose faces use several materials, some of them alpha
        tested, is split: the opaque faces keep the mesh's name, the faces of each
        alpha-tested material become the mesh ``"<name>/<material>"``. :attr:`Scene.alpha`
        holds the alpha tests.

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
    AlphaWarning
        Naming the file, material and meshes, for any part of a material's alpha that
        cannot be honoured (a texture that is missing or cannot be read, texture coordinates
        missing where a texture is to be read, a texture transform, a texture coordinate set
        other than 0, an unsupported MTL texture option): those faces are loaded solid. Also
        for readings beyond the format's specification (glTF BLEND and a partial MTL dissolve
        read as a mask at 0.5, alpha from a ``map_Kd`` image, ``Tr`` that makes a material a
        hole), and for ``alpha=False`` on a file with alpha.

    Notes
    -----
    The file is read with ``trimesh.load(..., process=False)`` so that NaN or inf
    coordinates are seen (trimesh's processing would silently drop them) and then
    rebuilt from positions alone: texture coordinates, normals and materials are
    discarded (except the texture coordinates of alpha-tested faces, corner by corner), and
    vertices with exactly equal positions are merged. Merging only exact
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
    if not isinstance(alpha, bool):
        raise ValueError(f"alpha must be True or False, got {alpha!r}")

    options = {}
    if ext == ".obj":
        # one mesh per `o` object and `g` group, whatever their materials
        options = {"split_objects": True, "split_groups": True, "group_material": False}
    try:
        loaded = trimesh.load(**_source(path, ext), process=False, **options)
    except Exception as exc:  # trimesh raises many types for malformed files
        raise ValueError(f"could not read {path} as {ext[1:].upper()}: {type(exc).__name__}: {exc}") from exc

    parts = _parts(loaded, path.stem)
    if not parts:
        raise ValueError(f"{path} holds no triangles")

    for part_name, vertices, _, _ in parts:
        bad = int(np.count_nonzero(~np.isfinite(vertices)))
        if bad:
            where = "" if len(parts) == 1 else f" (mesh {part_name!r})"
            raise ValueError(f"{path}{where} has {bad} NaN or inf vertex coordinate(s); "
                             "fix or remove those vertices in the file")
    notes = _Notes(path.name)
    if alpha:
        face_alpha = _face_alpha(path, ext, parts, notes)
    else:
        face_alpha = [None] * len(parts)
        if _has_alpha(path, ext):
            notes.add("alpha=False: every material is loaded solid, although the file has alpha-tested "
                      "materials", "", [])

    meshes, masks = {}, {}
    dropped = {}
    total = 0
    for (part_name, vertices, faces, _), fa in zip(parts, face_alpha):
        total += len(faces)
        vertices, faces = _merge_exact(vertices, faces)
        keep = ~_degenerate(vertices, faces)
        if not np.all(keep):
            dropped[part_name] = int(np.count_nonzero(~keep))
            faces = faces[keep]
        if len(faces) == 0:
            continue
        if fa is None:
            meshes[part_name] = _compact(vertices, faces)
            continue
        # the faces of each alpha-tested material become a mesh of their own
        material, uv, table = fa[0][keep], fa[1][keep], fa[2]
        present = np.unique(material)
        for k in present:
            rows = material == k
            mesh_name = part_name if len(present) == 1 or k < 0 else f"{part_name}/{table[k].name}"
            unique = mesh_name
            i = 1
            while unique in meshes:
                unique = f"{mesh_name}_{i}"
                i += 1
            meshes[unique] = _compact(vertices, faces[rows])
            if k >= 0:
                m = table[k]
                masks[unique] = AlphaMask(uv[rows], m.alpha, cutoff=m.cutoff,
                                          source=f"{path.name}, material {m.name!r}")
    notes.emit()
    if dropped:
        count = sum(dropped.values())
        detail = "" if len(parts) == 1 else " (" + ", ".join(f"{k}: {v}" for k, v in dropped.items()) + ")"
        warnings.warn(f"{path.name}: dropped {count} degenerate (zero-area) face(s) of {total}{detail}",
                      DegenerateFacesWarning, stacklevel=2)
    if not meshes:
        raise ValueError(f"{path} holds no triangles with a non-zero area")
    return Scene(meshes, name=name if name is not None else path.stem,
                 smooth_angle=float(smooth_angle), alpha=masks, **file_view(path, meshes))


#: An OBJ face or line statement with a relative (negative) index, e.g. ``f -4 -3 -2 -1``.
_RELATIVE_INDEX = re.compile(rb"^[ \t]*[fl][ \t][^\n]*?[ \t/]-[0-9]", re.MULTILINE)


def _source(path: Path, ext: str) -> dict:
    """The ``trimesh.load`` arguments that read ``path``: the path itself, or for an OBJ file
    with relative indices its text with them made absolute (and a resolver for its MTL and
    textures), since trimesh resolves a relative index against the end of the file instead of
    the statement's position (the OBJ specification's meaning: -1 is the last vertex defined
    so far)."""
    if ext != ".obj":
        return dict(file_obj=str(path), file_type=ext[1:])
    data = path.read_bytes()        # read once: trimesh parses these bytes, not the file again
    if _RELATIVE_INDEX.search(data):
        data = absolute_obj_indices(data.decode("utf-8", errors="replace")).encode("utf-8")
    return dict(file_obj=io.BytesIO(data), file_type="obj", resolver=trimesh.resolvers.FilePathResolver(str(path)))


def absolute_obj_indices(text: str) -> str:
    """OBJ text whose relative (negative) ``v``/``vt``/``vn`` indices in ``f`` and ``l``
    statements are made absolute: -k is the k-th last element of its kind defined before the
    statement (Wavefront OBJ specification, "Referencing groups of vertices").

    Examples
    --------
    >>> print(absolute_obj_indices("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf -3 -2 -1\\nv 0 0 1\\nf -4 2 -1"))
    v 0 0 0
    v 1 0 0
    v 0 1 0
    f 1 2 3
    v 0 0 1
    f 1 2 4
    """
    count = {"v": 0, "vt": 0, "vn": 0}
    out = []
    for line in text.split("\n"):
        tokens = line.split()
        if tokens and tokens[0] in count:
            count[tokens[0]] += 1
        elif tokens and tokens[0] in ("f", "l") and "-" in line:
            new = [tokens[0]]
            for token in tokens[1:]:
                if token.startswith("#"):
                    new.append(" ".join(tokens[tokens.index(token):]))
                    break
                fields = token.split("/")
                for i, kind in enumerate(("v", "vt", "vn")[:len(fields)]):
                    if fields[i].startswith("-") and fields[i][1:].isdigit():
                        fields[i] = str(count[kind] + 1 + int(fields[i]))
                new.append("/".join(fields))
            line = " ".join(new)
        out.append(line)
    return "\n".join(out)


def _compact(vertices: np.ndarray, faces: np.ndarray) -> trimesh.Trimesh:
    """A Trimesh of ``faces`` (same order) over the vertices they use."""
    used, faces = np.unique(faces, return_inverse=True)
    return trimesh.Trimesh(vertices[used], faces.reshape(-1, 3), process=False)


class _Notes:
    """The AlphaWarnings of one load, gathered: one per message, naming each material it is
    about with its meshes."""

    def __init__(self, file: str):
        self.file = file
        self.items: dict[str, dict[str, list[str]]] = {}

    def add(self, message: str, material: str, meshes) -> None:
        listed = self.items.setdefault(message, {}).setdefault(material, [])
        listed.extend(m for m in meshes if m not in listed)

    def emit(self) -> None:
        for message, materials in self.items.items():
            about = []
            for material, meshes in materials.items():
                if not material:
                    continue
                label = f"material {material!r}"
                if meshes:
                    label += f" (mesh{'es' if len(meshes) > 1 else ''} {', '.join(map(repr, meshes))})"
                about.append(label)
            where = (", " + ", ".join(about)) if about else ""
            warnings.warn(f"{self.file}{where}: {message}", AlphaWarning, stacklevel=3)


def _has_alpha(path: Path, ext: str) -> bool:
    """Whether the file has materials with an alpha test (without reading any image)."""
    try:
        if ext == ".obj":
            return bool(_materials.mtl_materials(path, read_images=False))
        if ext in (".gltf", ".glb"):
            return any(m["mode"] in ("MASK", "BLEND") for m in _materials.gltf_materials(path))
    except Exception:  # an unreadable material section: trimesh read the geometry anyway
        return False
    return False


def _face_alpha(path: Path, ext: str, parts, notes: _Notes) -> list:
    """Per part: None (opaque) or (material (f,) int, -1 opaque; uv (f, 3, 2); [MaterialAlpha])."""
    if ext == ".obj":
        return _obj_face_alpha(path, parts, notes)
    if ext in (".gltf", ".glb"):
        return _gltf_face_alpha(path, parts, notes)
    return [None] * len(parts)


def _usable(material, meshes, notes: _Notes) -> bool:
    """Whether a material's alpha is honoured and has holes (problems and remarks go to ``notes``)."""
    for remark in material.notes:
        notes.add(remark, material.name, meshes)
    if material.problem is not None:
        notes.add(f"{material.problem}; loaded solid", material.name, meshes)
        return False
    return material.is_masked


def _corner_uv(geometry, faces):
    """(f, 3, 2) texture coordinates of the faces' corners, or None when the mesh has none."""
    uv = getattr(getattr(geometry, "visual", None), "uv", None)
    if uv is None or len(uv) != len(geometry.vertices) or not np.all(np.isfinite(uv)):
        return None
    return np.asarray(uv, dtype=np.float64)[faces]


def _face_keys(triangles: np.ndarray) -> list[bytes]:
    """One bytes key per (3, 3) triangle: its corner coordinates, exactly (-0.0 as 0.0)."""
    flat = np.ascontiguousarray(triangles.reshape(-1, 9) + 0.0, dtype=np.float64)
    return [row.tobytes() for row in flat]


def _obj_face_alpha(path: Path, parts, notes: _Notes) -> list:
    for library in _materials.mtl_libraries(path):
        if not library.is_file():
            notes.add(f"its material library {library.name!r} is not found (looked for {library}); the "
                      "alpha of its materials is not read and every mesh is loaded solid", "", [])
    table = _materials.mtl_materials(path)
    if not table:
        return [None] * len(parts)
    # The parts hold one mesh per object/group whatever its materials: read the file again,
    # split by material as well, and find each face's material and corner texture
    # coordinates by its corner positions (the same numbers, parsed from the same text).
    text = path.read_text(errors="replace")
    used = set(re.findall(r"^[ \t]*usemtl[ \t]+(.+?)[ \t]*$", text, flags=re.MULTILINE))
    by_material = trimesh.load(**_source(path, ".obj"), process=False, split_objects=True,
                               split_groups=True, group_material=True)
    geometries = list(by_material.geometry.values()) if isinstance(by_material, trimesh.Scene) else [by_material]
    names = list(table)
    lookup: dict[bytes, tuple[int, np.ndarray | None]] = {}
    seen = set()
    for g in geometries:
        if not isinstance(g, trimesh.Trimesh) or len(g.faces) == 0:
            continue
        mname = getattr(getattr(getattr(g, "visual", None), "material", None), "name", None)
        if mname not in table:
            continue
        seen.add(mname)
        faces = np.asarray(g.faces, dtype=np.int64)
        uv = _corner_uv(g, faces)
        k = names.index(mname)
        for i, key in enumerate(_face_keys(np.asarray(g.vertices, dtype=np.float64)[faces])):
            lookup.setdefault(key, (k, None if uv is None else uv[i]))
    for mname in table:
        if mname in used and mname not in seen:
            notes.add("trimesh attributed no faces to this material (it reads the first mtllib only); "
                      "its faces are loaded solid", mname, [])
    found_per_part, users = [], {}
    for part_name, vertices, faces, _ in parts:
        found = [lookup.get(key) for key in _face_keys(vertices[faces])]
        found_per_part.append(found)
        for f in found:
            if f is not None and part_name not in users.setdefault(f[0], []):
                users[f[0]].append(part_name)
    usable = {k: _usable(table[names[k]], meshes, notes) for k, meshes in users.items()}
    out = []
    for (part_name, _, faces, _), found in zip(parts, found_per_part):
        material = np.full(len(faces), -1, dtype=np.int64)
        uv = np.zeros((len(faces), 3, 2))
        for i, f in enumerate(found):
            if f is None or not usable[f[0]]:
                continue
            k, corner_uv = f
            if corner_uv is None and table[names[k]].texture is not None:
                notes.add("faces without texture coordinates (vt) to read its alpha texture with are "
                          "loaded solid", names[k], [part_name])
                continue
            material[i] = k
            if corner_uv is not None:
                uv[i] = corner_uv
        out.append(None if np.all(material < 0) else (material, uv, [table[n] for n in names]))
    return out


def _gltf_face_alpha(path: Path, parts, notes: _Notes) -> list:
    try:
        info = _materials.gltf_materials(path)
    except Exception as exc:  # trimesh read the geometry; the material section is unreadable
        notes.add(f"its materials could not be read ({type(exc).__name__}: {exc}); every mesh is loaded solid",
                  "", [])
        return [None] * len(parts)
    if not any(m["mode"] in ("MASK", "BLEND") for m in info):
        return [None] * len(parts)
    out = []
    matched = set()
    for part_name, _, faces, geometry in parts:
        pbr = getattr(getattr(geometry, "visual", None), "material", None)
        if pbr is None or str(getattr(pbr, "alphaMode", None) or "OPAQUE").upper() not in ("MASK", "BLEND"):
            out.append(None)
            continue
        entry = _materials.match_gltf_material(info, pbr)
        if entry is None:
            notes.add("the material cannot be told apart from others of the same name with other alpha "
                      "settings; loaded solid", str(getattr(pbr, "name", "")), [part_name])
            out.append(None)
            continue
        matched.add(id(entry))
        material = _materials.gltf_material(entry, pbr)
        if material is None or not _usable(material, [part_name], notes):
            out.append(None)
            continue
        uv = np.zeros((len(faces), 3, 2))
        if material.texture is not None:
            uv = _corner_uv(geometry, faces)
            if uv is None:
                notes.add("the mesh has no TEXCOORD_0 to read its base colour texture with; loaded solid",
                          material.name, [part_name])
                out.append(None)
                continue
        out.append((np.zeros(len(faces), dtype=np.int64), uv, [material]))
    for m in info:
        if m["mode"] in ("MASK", "BLEND") and m["meshes"] and id(m) not in matched:
            notes.add(f"alphaMode {m['mode']}, but trimesh attached the material to no mesh it loaded; its "
                      "meshes are loaded solid", m["name"], m["meshes"])
    return out


#: The random suffix trimesh's glTF loader gives the frame of each primitive of a mesh with
#: several (``<node>_<6 random hex digits>``, trimesh.exchange.gltf, ``util.unique_id``).
_RANDOM_FRAME = re.compile(r"^(?P<parent>.+)_[0-9a-f]{6}$")


def _node_name(graph, node, geometry_name) -> str:
    """A scene-graph node's name, the same on every load: a primitive's frame that trimesh
    named with a random suffix is named after its parent node and its geometry instead (so
    that mesh names, their order and the cache's scene digest do not change between loads)."""
    match = _RANDOM_FRAME.match(str(node))
    parent = graph.transforms.parents.get(node)
    if match and parent is not None and match["parent"] == str(parent):
        return f"{parent}/{geometry_name}"
    return str(node)


def _parts(loaded, stem: str) -> list[tuple[str, np.ndarray, np.ndarray, trimesh.Trimesh]]:
    """(name, vertices (n, 3) float64 in world space, faces (m, 3) int64, the trimesh geometry)
    per triangle mesh. The faces index the geometry's vertices, reversed where a mirroring
    transform turned the winding inside out (their corners' texture coordinates follow).

    A Trimesh is one part named ``stem``; a trimesh.Scene gives one part per scene-graph
    node that instances a triangle mesh, named after the node (``stem`` when there is only
    one), with the node's transform applied. Point clouds and paths are ignored.
    """
    if isinstance(loaded, trimesh.Trimesh):
        items = [(stem, np.eye(4), loaded)]
    elif isinstance(loaded, trimesh.Scene):
        items = []
        for node in loaded.graph.nodes_geometry:
            transform, geometry_name = loaded.graph[node]
            items.append((_node_name(loaded.graph, node, geometry_name), np.asarray(transform, dtype=np.float64),
                          loaded.geometry[geometry_name]))
        items.sort(key=lambda item: item[0])
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
        parts.append((unique, vertices, faces, geometry))
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
