"""Screen-space estimators of Volumetric Obscurance (Loos & Sloan, I3D 2010)."""

from .line import vo_line
from .point import vo_point, vo_reference

__all__ = ["vo_line", "vo_point", "vo_reference"]
