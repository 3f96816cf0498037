"""Scenes: named triangle meshes, procedural builders, file loading, and the one resolver
(:func:`as_scene`, :func:`resolve`) of a scene argument; vegetation scenes (leaf clouds, trees,
grass) with open, two-sided foliage in :mod:`vobscure.scenes.vegetation`; an interior with
alpha-tested foliage, :func:`atrium`, in :mod:`vobscure.scenes.atrium`; thin occluders (a
table, a chair, a railing, a hanging sheet), :func:`thin_occluders`, in :mod:`vobscure.scenes.thin`."""

from . import _alpha, _resolve, _scene, procedural, vegetation
from ._alpha import AlphaMask
from .atrium import atrium
from .thin import thin_occluders
from ._resolve import as_scene, check_spec, resolve
from ._scene import Scene
from .io import AlphaWarning, DegenerateFacesWarning, load
from .procedural import blob, cornell_box, crease, get, groove, names, slab, sphere_on_plane, steps
from .vegetation import grass, leaf_cloud, leaf_cloud_dense, leaf_points, tree, tree_poplar

# every public name of the submodules, but of io only the loader and its warnings
__all__ = [
    *_scene.__all__,
    *_alpha.__all__,
    *_resolve.__all__,
    "load",
    "DegenerateFacesWarning",
    "AlphaWarning",
    *procedural.__all__,
    *vegetation.__all__,
    "atrium",
    "thin_occluders",
]
