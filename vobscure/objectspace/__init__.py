"""Object-space ambient occlusion: visibility computed from the geometry itself, not from a
G-buffer or rays.

- :mod:`vobscure.objectspace.disks`: Bunnell 2005, the surface as oriented disks
  (RTR 3rd ed. Sec. 9.2.5), per vertex (:func:`bunnell`) and per pixel
  (:func:`bunnell_gbuffer`).
- :mod:`vobscure.objectspace.spheres`: Ren et al. 2006, occluders as sets of spheres whose
  visibilities are combined in spherical harmonics (:func:`sphere_set_ao`), the exact union
  by ray casting (:func:`union_visibility`), and sets fitted to a mesh (:func:`sphere_set`).
- :mod:`vobscure.objectspace.sh`: the real spherical harmonics those use (zonal caps,
  rotation, products, log and exp).

Everything public is importable from here: ``from vobscure.objectspace import bunnell``.
"""

from __future__ import annotations

from .disks import (
    DEFAULT_TERM,
    TERMS,
    bunnell,
    bunnell_gbuffer,
    disk_shadow,
    shadow_evaluations,
    vertex_disks,
)
from .spheres import SphereSet, sphere_set, sphere_set_ao, sphere_set_gbuffer, union_visibility

__all__ = ["DEFAULT_TERM", "TERMS", "bunnell", "bunnell_gbuffer", "disk_shadow", "shadow_evaluations",
           "vertex_disks", "SphereSet", "sphere_set", "sphere_set_ao", "sphere_set_gbuffer", "union_visibility"]
