"""The Scene: named triangle meshes, their extent, a suggested camera, a cached tracer."""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property

import numpy as np
import trimesh

from ._alpha import AlphaMask

__all__ = ["Scene"]


class Scene:
    """One or more named triangle meshes that are traced together.

    Parameters
    ----------
    meshes : trimesh.Trimesh or mapping of str to trimesh.Trimesh
        The geometry. A single mesh is stored under the name ``"mesh"``.
    name : str, optional
        A label used in provenance records and figure titles.
    view : dict, optional
        A suggested camera: keys ``eye``, ``target``, ``up`` and either ``fov_y`` or
        ``ortho_height``. When absent, :func:`~vobscure.scenes.viewpoint.suggest_view`
        chooses one (from inside an enclosed scene), once.
    smooth_angle : float or mapping of str to float, optional
        Crease angle in degrees for the shading normals, per mesh or for all: a triangle
        corner's normal is the area-weighted mean of the normals of the faces around that
        vertex that lie within this angle of the triangle's own normal. 0 gives flat
        shading (the geometric normal), which polyhedral scenes such as the slab use.
    metadata : mapping, optional
        Facts about how the scene was built that are not geometry, for the models and
        experiments that use it (for example the leaf statistics of the vegetation scenes,
        :mod:`vobscure.scenes.vegetation`). Stored as a dict; empty by default. It is not part
        of the scene's geometry digest, and :meth:`scaled` does not carry it over (its lengths
        would be wrong).
    alpha : mapping of str to AlphaMask, optional
        Alpha-tested meshes (leaf cards, curtains, chains): mesh name -> its
        :class:`~vobscure.scenes.AlphaMask`. Texels below the cutoff are holes for every ray.

    Attributes
    ----------
    meshes : dict of str to trimesh.Trimesh
    triangles : (m, 3, 3) float64
        All triangles, mesh after mesh, in the order of ``meshes``.
    face_normals : (m, 3) float64
        Unit geometric normals of ``triangles`` (outward for closed, consistently wound meshes).
    mesh_index : (m,) int
        Which entry of ``meshes`` each triangle came from.
    corner_normals : (m, 3, 3) float64
        Unit shading normal at each corner of each triangle (see ``smooth_angle``).
    plane_offsets : (m,) float64
        c in each triangle's plane equation ``face_normals . x = c``.
    smooth_faces : (m,) bool
        Triangles whose corner normals are not all their face normal (the others are flat
        shaded, and the G-buffer skips their interpolation).
    bounds : (2, 3) float64
    extent : float
        Length of the bounding-box diagonal: the scene's length scale, which every
        epsilon in the library is relative to.
    metadata : dict
        See Parameters.
    alpha : dict of str to AlphaMask
        See Parameters; empty when every mesh is opaque.

    Examples
    --------
    >>> import trimesh, vobscure as vo
    >>> scene = vo.Scene(trimesh.creation.box(extents=(2, 1, 1)))
    >>> scene.triangles.shape
    (12, 3, 3)
    >>> round(scene.extent, 4)
    2.4495
    """

    def __init__(self, meshes, *, name: str | None = None, view: Mapping | None = None,
                 smooth_angle: float | Mapping = 60.0, metadata: Mapping | None = None,
                 alpha: Mapping | None = None):
        if isinstance(meshes, trimesh.Trimesh):
            meshes = {"mesh": meshes}
        if not isinstance(meshes, Mapping) or not meshes:
            raise ValueError(
                "meshes must be a trimesh.Trimesh or a non-empty dict of name -> trimesh.Trimesh, "
                f"got {type(meshes).__name__}"
            )
        clean = {}
        for key, mesh in meshes.items():
            if not isinstance(mesh, trimesh.Trimesh):
                raise ValueError(f"meshes[{key!r}] must be a trimesh.Trimesh, got {type(mesh).__name__}")
            if len(mesh.faces) == 0:
                raise ValueError(f"meshes[{key!r}] has no faces")
            if not np.all(np.isfinite(mesh.vertices)):
                raise ValueError(f"meshes[{key!r}] has NaN or inf vertices")
            clean[str(key)] = mesh
        self.meshes: dict[str, trimesh.Trimesh] = clean
        self.name = name if name is not None else ("+".join(clean) if len(clean) < 4 else "scene")
        self.triangles = np.concatenate([m.triangles for m in clean.values()]).astype(np.float64)
        normals = np.concatenate([m.face_normals for m in clean.values()]).astype(np.float64)
        self.face_normals = normals
        angles = {k: float(smooth_angle.get(k, 60.0) if isinstance(smooth_angle, Mapping) else smooth_angle)
                  for k in clean}
        self.smooth_angle: dict[str, float] = angles
        self.corner_normals = np.concatenate(
            [_corner_normals(m, angles[k]) for k, m in clean.items()]).astype(np.float64)
        #: c of each triangle's plane n . x = c (float64), for projecting points onto it
        self.plane_offsets = np.einsum("ij,ij->i", normals, self.triangles[:, 0])
        self.smooth_faces = np.any(np.abs(self.corner_normals - normals[:, None, :]) > 1e-12, axis=(1, 2))
        self.mesh_index = np.concatenate(
            [np.full(len(m.faces), i, dtype=np.int32) for i, m in enumerate(clean.values())]
        )
        lo = self.triangles.reshape(-1, 3).min(axis=0)
        hi = self.triangles.reshape(-1, 3).max(axis=0)
        self.bounds = np.stack([lo, hi])
        self.extent = float(np.linalg.norm(hi - lo))
        if not self.extent > 0:
            raise ValueError("the scene's triangles span no volume (all vertices coincide)")
        self._view = dict(view) if view is not None else None
        if metadata is not None and not isinstance(metadata, Mapping):
            raise ValueError(f"metadata must be a mapping or None, got {type(metadata).__name__}")
        self.metadata: dict = dict(metadata) if metadata is not None else {}
        self.alpha: dict[str, AlphaMask] = _check_alpha(alpha, clean)

    def __repr__(self) -> str:
        masked = f", alpha={list(self.alpha)}" if self.alpha else ""
        return (f"Scene({self.name!r}, meshes={list(self.meshes)}, triangles={len(self.triangles)}, "
                f"extent={self.extent:.4g}{masked})")

    @property
    def center(self) -> np.ndarray:
        """(3,) centre of the bounding box."""
        return self.bounds.mean(axis=0)

    @cached_property
    def is_watertight(self) -> bool:
        """True when every mesh is closed and consistently wound (inside/outside defined):
        :attr:`open_meshes` is empty."""
        return not self.open_meshes

    @cached_property
    def open_meshes(self) -> list[str]:
        """Names of the meshes that do not bound a solid: not closed, not consistently wound,
        or alpha-tested with holes (texels below the cutoff), which open a closed mesh."""
        return [k for k, m in self.meshes.items()
                if not (m.is_watertight and m.is_winding_consistent)
                or (k in self.alpha and self.alpha[k].has_holes)]

    @cached_property
    def tracer(self):
        """The Embree scene of these triangles, built once on first use; alpha-tested meshes
        (:attr:`alpha`) are traced with their holes (:attr:`triangle_alpha`)."""
        from ..raytrace import Tracer

        return Tracer(self.triangles, face_normals=self.face_normals, extent=self.extent,
                      alpha=self.triangle_alpha)

    @cached_property
    def triangle_alpha(self):
        """The alpha test per triangle of :attr:`triangles` (a
        :class:`vobscure.raytrace.TriangleAlpha`: texture index per triangle, -1 opaque, the
        masks' corner texture coordinates, textures and cutoffs), or None when no mesh has an
        :class:`AlphaMask` with a hole (a mask whose texels are all solid is opaque)."""
        holed = {k: a for k, a in self.alpha.items() if a.has_holes}
        if not holed:
            return None
        from ..raytrace import TriangleAlpha

        names = list(self.meshes)
        first = np.concatenate([[0], np.cumsum([len(m.faces) for m in self.meshes.values()])])
        mask = np.full(len(self.triangles), -1, dtype=np.int64)
        uv = np.zeros((len(self.triangles), 3, 2))
        textures, cutoffs = [], []
        for i, (key, alpha) in enumerate(holed.items()):
            j = names.index(key)
            rows = slice(int(first[j]), int(first[j + 1]))
            mask[rows] = i
            uv[rows] = alpha.uv
            textures.append(alpha.texture)
            cutoffs.append(alpha.cutoff)
        return TriangleAlpha(mask, uv, textures, cutoffs)

    @property
    def view(self) -> dict:
        """The suggested camera parameters (eye, target, up, fov_y or ortho_height)."""
        if self._view is not None:
            return dict(self._view)
        return dict(self._suggested_view)

    @cached_property
    def _suggested_view(self) -> dict:
        """:func:`~vobscure.scenes.viewpoint.suggest_view` of a scene without a view, once."""
        from .viewpoint import suggest_view

        return suggest_view(self)

    def camera(self, size=(256, 256)):
        """The suggested :class:`~vobscure.Camera` at the given (width, height)."""
        from ..camera import Camera

        view = self.view
        return Camera.look_at(view["eye"], view["target"], view.get("up", (0, 1, 0)), size=size,
                              fov_y=view.get("fov_y"), ortho_height=view.get("ortho_height"))

    def scaled(self, factor: float) -> "Scene":
        """A copy with every coordinate (and the suggested camera) scaled by ``factor``."""
        meshes = {}
        for key, mesh in self.meshes.items():
            m = mesh.copy()
            m.apply_scale(factor)
            meshes[key] = m
        view = None
        if self._view is not None:
            view = dict(self._view)
            view["eye"] = tuple(np.asarray(view["eye"], float) * factor)
            view["target"] = tuple(np.asarray(view["target"], float) * factor)
            if view.get("ortho_height") is not None:
                view["ortho_height"] = view["ortho_height"] * factor
        return Scene(meshes, name=self.name, view=view, smooth_angle=self.smooth_angle, alpha=self.alpha)

    @property
    def mesh(self) -> trimesh.Trimesh:
        """All meshes concatenated into one (vertices not merged across meshes)."""
        return trimesh.util.concatenate(list(self.meshes.values()))


def _check_alpha(alpha, meshes: dict) -> dict:
    """``alpha`` as a dict of mesh name -> AlphaMask, checked against the meshes' faces."""
    if alpha is None:
        return {}
    if not isinstance(alpha, Mapping):
        raise ValueError(f"alpha must be a mapping of mesh name -> AlphaMask or None, got {type(alpha).__name__}")
    out = {}
    for key, mask in alpha.items():
        key = str(key)
        if key not in meshes:
            raise ValueError(f"alpha names mesh {key!r}, which the scene does not have "
                             f"(meshes: {', '.join(meshes)})")
        if not isinstance(mask, AlphaMask):
            raise ValueError(f"alpha[{key!r}] must be a vobscure.scenes.AlphaMask, got {type(mask).__name__}")
        if len(mask.uv) != len(meshes[key].faces):
            raise ValueError(f"alpha[{key!r}] has texture coordinates for {len(mask.uv)} faces; "
                             f"the mesh has {len(meshes[key].faces)}")
        out[key] = mask
    return out


def _corner_normals(mesh: trimesh.Trimesh, smooth_angle: float) -> np.ndarray:
    """(f, 3, 3) shading normal per triangle corner, smoothed within ``smooth_angle`` degrees.

    For every pair of faces (f, g) that share a vertex v, face g contributes its
    area-weighted normal to corner (f, v) when the angle between the two face normals is at
    most ``smooth_angle``; coplanar neighbours always contribute, so a flat quad made of two
    triangles keeps one normal.
    """
    faces = np.asarray(mesh.faces)
    n_f = np.asarray(mesh.face_normals, dtype=np.float64)
    out = np.repeat(n_f[:, None, :], 3, axis=1)
    if smooth_angle <= 0:
        return out
    weighted = n_f * np.asarray(mesh.area_faces, dtype=np.float64)[:, None]
    cos_limit = np.cos(np.radians(min(float(smooth_angle), 180.0))) - 1e-9
    # vertex -> faces incidence, as sorted (vertex, face) lists
    corner_face = np.repeat(np.arange(len(faces)), 3)
    corner_vertex = faces.ravel()
    order = np.argsort(corner_vertex, kind="stable")
    v_sorted, f_sorted = corner_vertex[order], corner_face[order]
    starts = np.searchsorted(v_sorted, np.arange(len(mesh.vertices)))
    counts = np.bincount(v_sorted, minlength=len(mesh.vertices))
    # every (corner, face sharing the corner's vertex) pair
    reps = counts[corner_vertex]
    pair_corner = np.repeat(np.arange(len(corner_vertex)), reps)
    offsets = np.arange(len(pair_corner)) - np.repeat(np.cumsum(reps) - reps, reps)
    pair_face = f_sorted[starts[corner_vertex][pair_corner] + offsets]
    keep = np.einsum("ij,ij->i", n_f[corner_face[pair_corner]], n_f[pair_face]) >= cos_limit
    acc = np.zeros((len(corner_vertex), 3))
    np.add.at(acc, pair_corner[keep], weighted[pair_face[keep]])
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    acc = np.where(length > 0, acc / np.where(length > 0, length, 1.0), n_f[corner_face])
    return acc.reshape(-1, 3, 3)
