"""Scenes: named triangle meshes, procedural builders and file loading."""

from ._scene import Scene
from .io import DegenerateFacesWarning, load
from .procedural import blob, cornell_box, crease, get, groove, names, slab, sphere_on_plane, steps

__all__ = [
    "Scene",
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
