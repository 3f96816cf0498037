"""Frame sequences: camera paths, reprojection and temporal accumulation.

Engines run a screen-space estimator with few samples per frame, vary its noise per frame
(:mod:`vobscure.screenspace.noise`) and accumulate the frames. This package holds the pieces:

- :mod:`~vobscure.temporal.paths`: the cameras of a sequence (static, orbit, dolly, a list);
- :mod:`~vobscure.temporal.reproject`: the history of the previous frame seen from the current
  one, with disocclusion;
- :mod:`~vobscure.temporal.accumulate`: the running mean, the moving average and variance
  clipping, with the neighbourhood clamp and the spatial denoiser before or after.

The measurement of a configuration over frames (error per frame against the references,
flicker, time) is :func:`vobscure.experiments.temporal.run` and ``vobscure compare --frames``.
``docs/temporal.md`` describes the model and what was measured.
"""

from .accumulate import (ACCUMULATE_MODES, DENOISE_STEPS, HISTORY_BYTES_PER_PIXEL, VARIANCE_GAMMA, AccumulateSpec,
                         Accumulator, neighbourhood_moments, neighbourhood_range, parse_accumulate)
from .paths import (DOLLY_FRACTION_PER_FRAME, MOTIONS, ORBIT_DEGREES_PER_FRAME, camera_path, cameras_from_file,
                    cameras_from_records, dolly_camera, orbit_camera)
from .reproject import CHUNK_PIXELS, DEPTH_TOLERANCE, REPROJECT_FETCHES, Reprojection, reproject

__all__ = [
    "ACCUMULATE_MODES", "DENOISE_STEPS", "HISTORY_BYTES_PER_PIXEL", "VARIANCE_GAMMA", "AccumulateSpec",
    "Accumulator", "neighbourhood_moments", "neighbourhood_range", "parse_accumulate",
    "DOLLY_FRACTION_PER_FRAME", "MOTIONS", "ORBIT_DEGREES_PER_FRAME", "camera_path", "cameras_from_file",
    "cameras_from_records", "dolly_camera", "orbit_camera",
    "CHUNK_PIXELS", "DEPTH_TOLERANCE", "REPROJECT_FETCHES", "Reprojection", "reproject",
]
