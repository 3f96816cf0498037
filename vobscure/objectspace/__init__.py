"""Object-space ambient occlusion: visibility computed from the geometry itself, not from a
G-buffer or rays.

- :mod:`vobscure.objectspace.disks`: Bunnell 2005, the surface as oriented disks
  (RTR 3rd ed. Sec. 9.2.5).

Everything public is importable from here: ``from vobscure.objectspace import bunnell``.
"""

from __future__ import annotations

from .disks import bunnell, disk_shadow, vertex_disks

__all__ = ["bunnell", "disk_shadow", "vertex_disks"]
