"""Screen-space estimators of Volumetric Obscurance (Loos & Sloan, I3D 2010)."""

from .area import vo_area
from .blur import bilateral_blur, combine_radii
from .line import vo_line
from .point import point_taps, vo_point, vo_reference

__all__ = ["bilateral_blur", "combine_radii", "point_taps", "vo_area", "vo_line", "vo_point", "vo_reference"]
