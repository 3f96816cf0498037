"""Object-space ambient occlusion: visibility computed from the geometry itself, not from a
G-buffer or rays.

- :mod:`vobscure.objectspace.disks`: Bunnell 2005, the surface as oriented disks
  (RTR 3rd ed. Sec. 9.2.5), per vertex (:func:`bunnell`) and per pixel
  (:func:`bunnell_gbuffer`).

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
           "vertex_disks"]
__all__ += ["SphereSet", "sphere_set", "sphere_set_ao", "sphere_set_gbuffer", "union_visibility"]
