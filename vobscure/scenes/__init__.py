"""Scenes: named triangle meshes, procedural builders, file loading, and the one resolver
(:func:`as_scene`, :func:`resolve`) of a scene argument; vegetation scenes (leaf clouds, trees,
grass) with open, two-sided foliage in :mod:`vobscure.scenes.vegetation`."""

from ._resolve import as_scene, check_spec, resolve
from ._scene import Scene
from .io import DegenerateFacesWarning, load
from .procedural import blob, cornell_box, crease, get, groove, names, slab, sphere_on_plane, steps
from .vegetation import grass, leaf_cloud, leaf_cloud_dense, leaf_points, tree, tree_poplar

__all__ = [
    "Scene",
    "as_scene",
    "check_spec",
    "resolve",
    "load",
    "DegenerateFacesWarning",
    "names",
    "get",
    "slab",
    "crease",
    "groove",
    "sphere_on_plane",
    "steps",
    "cornell_box",
    "blob",
    "leaf_cloud",
    "leaf_cloud_dense",
    "tree",
    "tree_poplar",
    "grass",
    "leaf_points",
]
