"""Screen-space estimators of Volumetric Obscurance (Loos & Sloan, I3D 2010), and the
baselines engines ship instead: GTAO (Jimenez et al. 2016), VBAO (Therrien et al. 2023),
HBAO (Bavoil et al. 2008), Alchemy AO (McGuire et al. 2011) and SAO (McGuire et al. 2012); and
the per-frame noise schedules that randomize them all (:mod:`vobscure.screenspace.noise`)."""

from ._common import crop_guard, inner_shape  # the guard band's crop, for vobscure.methods
from .area import vo_area
from .blur import bilateral_blur, combine_radii
from .gtao import PRESETS as GTAO_PRESETS
from .gtao import gtao, gtao_bent_normals
from .hbao import hbao, hbao_taps
from .line import vo_line
from . import noise
from .noise import SCHEDULES, schedule_texture, schedule_uniforms
from .point import point_taps, vo_point, vo_reference
from .sao import alchemy, alchemy_taps, sao, sao_taps
from .vbao import vbao

__all__ = ["GTAO_PRESETS", "SCHEDULES", "alchemy", "alchemy_taps", "bilateral_blur", "combine_radii", "gtao",
           "gtao_bent_normals", "hbao", "hbao_taps", "noise", "point_taps", "sao", "sao_taps", "schedule_texture",
           "schedule_uniforms", "vbao", "vo_area", "vo_line", "vo_point", "vo_reference"]
