"""vobscure: a reference library for ambient occlusion, obscurance and Volumetric Obscurance.

The public API is listed in ``__all__``; see ``docs/`` and DESIGN.md for the conventions
(view space z positive in front of the camera, visibility 1 = open, NaN on background).
"""

from importlib.metadata import PackageNotFoundError, version as _version

from . import scenes
from .camera import Camera
from .estimate import Estimate
from .gbuffer import GBuffer, NormalsRenormalizedWarning, NormalsRepairedWarning
from .groundtruth import ambient_occlusion, ground_truth, obscurance, volumetric_obscurance
from .metrics import Decomposition, ErrorReport, Flicker, decompose, error, flicker
from .raytrace import Tracer
from .render import render_gbuffer
from .scenes import Scene
from .screenspace import (alchemy, bilateral_blur, combine_radii, gtao, gtao_bent_normals, hbao, sao, vbao,
                          vo_area, vo_line, vo_point, vo_reference)
from . import io, methods, objectspace, patterns, references, shading, temporal, trees


def __getattr__(name):
    # vobscure.experiments (comparisons, sweeps, figures) sits above the core and is imported
    # on first use: no core module depends on it, and `import vobscure` stays light.
    if name == "experiments":
        import importlib

        return importlib.import_module(f"{__name__}.experiments")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


try:
    __version__ = _version("vobscure")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

__all__ = [
    "Camera",
    "Decomposition",
    "ErrorReport",
    "Estimate",
    "Flicker",
    "GBuffer",
    "NormalsRenormalizedWarning",
    "NormalsRepairedWarning",
    "Scene",
    "Tracer",
    "__version__",
    "alchemy",
    "ambient_occlusion",
    "bilateral_blur",
    "combine_radii",
    "decompose",
    "error",
    "experiments",
    "flicker",
    "gtao",
    "gtao_bent_normals",
    "hbao",
    "io",
    "methods",
    "objectspace",
    "ground_truth",
    "obscurance",
    "references",
    "render_gbuffer",
    "sao",
    "scenes",
    "shading",
    "vbao",
    "volumetric_obscurance",
    "patterns",
    "temporal",
    "trees",
    "vo_area",
    "vo_line",
    "vo_point",
    "vo_reference",
]
