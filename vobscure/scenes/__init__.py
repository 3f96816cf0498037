"""Scenes: named triangle meshes, procedural builders, file loading, and the one resolver
(:func:`as_scene`, :func:`resolve`) of a scene argument."""

from ._resolve import as_scene, check_spec, resolve
from ._scene import Scene
from .io import DegenerateFacesWarning, load
from .procedural import blob, cornell_box, crease, get, groove, names, slab, sphere_on_plane, steps

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
]
