"""Per-frame noise schedules: the tiled texture that randomizes a screen-space estimator, frame
by frame.

Every screen-space estimator randomizes its pattern per pixel from one small tiled texture
(``noise_texture`` in :mod:`vobscure.screenspace._common`): (T, T, dim) unit vectors, texel
(i mod T, j mod T) for pixel (i, j). Engines draw few samples per frame and change the texture
from frame to frame so that an accumulation over frames converges; a *schedule* says how.
This module is the one place that defines the schedules (:data:`SCHEDULES`):

- ``"white"``: independent white noise per frame (frame 0 is the library's single-frame
  texture, bit for bit);
- ``"rotate"``: frame 0's texture turned about the z axis by golden-ratio increments;
- ``"r2"``: XeGTAO's spatio-temporal noise, the R2 sequence along a 64 x 64 Hilbert curve;
- ``"gtao"``: the temporal rotations and step offsets of Jimenez et al. 2016 over the spatial
  interleaved gradient noise, as Unity HDRP's GTAO runs them;
- ``"blue"``: two 64 x 64 void-and-cluster blue-noise arrays (:mod:`.bluenoise`), u1 shifted
  by the golden ratio and u2 by sqrt(2) - 1 per frame: spatial blue noise animated per frame,
  not spatiotemporal blue noise.

A texel carries two numbers in [0, 1), (u1, u2) (:func:`schedule_uniforms`). The estimators
read them back from the unit vectors as follows, and :func:`uniforms_to_texture` is the exact
inverse of that reading:

- dim 3 (vo_point's Householder reflection; the horizon estimators' slices): u1 is the
  azimuth of (x, y) over 2 pi (the slice rotation of GTAO and VBAO, HBAO's direction
  rotation) and u2 = (z + 1) / 2 (GTAO's and VBAO's step jitter; HBAO's is 1 - u2);
- dim 2 (vo_line, vo_area, Alchemy AO, SAO): the angle of the vector over 2 pi is u1; u2 is
  not used.

For a uniform (u1, u2) the dim-3 vector is uniform on the sphere (Archimedes' hat-box theorem),
so the schedules built from (u1, u2) randomize vo_point as white noise does.

References
----------
.. [1] J. Jimenez, X. Wu, A. Pesce, A. Jarabo, "Practical Real-Time Strategies for Accurate
   Indirect Occlusion", Activision technical report ATVI-TR-16-01 / SIGGRAPH 2016 course
   "Physically Based Shading in Theory and Practice", Sec. 5 (spatial and temporal
   denoising).
.. [2] F. Strugar, S. McCalla, XeGTAO 1.20 (Intel, 2021), https://github.com/GameTechDev/XeGTAO:
   ``Source/Rendering/Shaders/XeGTAO.h`` (``HilbertIndex``, ``XE_HILBERT_LEVEL``) and
   ``vaGTAO.hlsl`` (``SpatioTemporalNoise``).
.. [3] M. Roberts, "The Unreasonable Effectiveness of Quasirandom Sequences" (2018): the R2
   sequence, alpha = (1 / g, 1 / g^2), g the plastic number's generalization (g^3 = g + 1).
.. [4] J. Jimenez, "Next Generation Post Processing in Call of Duty: Advanced Warfare",
   SIGGRAPH 2014 course "Advances in Real-Time Rendering": interleaved gradient noise.
.. [5] Unity Technologies, High Definition Render Pipeline: the ``AmbientOcclusion`` volume
   component's C# (the temporal tables and their indices) and the GTAO HLSL's ``GetOffset``
   and ``GetDirection`` (read in copies of the public source; repository version not
   identified).
.. [6] R. Ulichney, "The void-and-cluster method for dither array generation", Proc. SPIE
   1913 (1993): the blue-noise arrays of the ``"blue"`` schedule.
.. [7] A. Wolfe, N. Morrical, R. Ramamoorthi, "Spatiotemporal Blue Noise Masks", EGSR 2022
   (authors as on https://research.nvidia.com/publication/2022-07_spatiotemporal-blue-noise-masks):
   masks blue over time too, which ``"blue"`` is not.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_rng, check_choice, check_int
from .bluenoise import BLUE_TILE, blue_ranks, ranks_to_uniforms

__all__ = ["SCHEDULES", "NOISE_SIZE", "GOLDEN", "GTAO_ROTATIONS", "GTAO_OFFSETS", "R2_TILE", "GTAO_TILE",
           "BLUE_TILE", "SILVER",
           "period", "check_frame", "check_schedule", "hilbert_index", "gtao_temporal",
           "schedule_uniforms", "uniforms_to_texture", "schedule_texture"]

#: The noise schedules, in the order of the documentation.
SCHEDULES = ("white", "rotate", "r2", "gtao", "blue")
#: Default edge of the tiled random texture (pixels) of the ``"white"`` and ``"rotate"`` schedules.
NOISE_SIZE = 4
#: The golden-ratio increment of the ``"rotate"`` schedule, (sqrt(5) - 1) / 2: the turns
#: n * GOLDEN mod 1 never repeat and are equidistributed in [0, 1) (Weyl).
GOLDEN = 0.6180339887498949
#: The ``"blue"`` schedule's per-frame increment of u2, sqrt(2) - 1: 1, GOLDEN and SILVER are
#: linearly independent over the rationals, so a texel's pairs (u1, u2) over the frames are
#: equidistributed in the unit square (Weyl); one increment for both would keep them on a line.
SILVER = 0.41421356237309515
#: Edge of the ``"r2"`` tile: XeGTAO's Hilbert curve of level 6 (``XE_HILBERT_LEVEL``).
R2_TILE = 64
_R2_LEVEL = 6
#: XeGTAO's R2 increments per Hilbert index (u1, u2) and its index offset per frame.
_R2_ALPHA = (0.75487766624669276005, 0.5698402909980532659114)
_R2_FRAME_STRIDE = 288
_R2_PERIOD = 64
#: The ``"gtao"`` schedule's temporal slice rotations (degrees), indexed by frame mod 6, and its
#: temporal step offsets, indexed by (frame // 6) mod 4 (Jimenez et al. 2016; Unity HDRP).
GTAO_ROTATIONS = (60.0, 300.0, 180.0, 240.0, 120.0, 0.0)
GTAO_OFFSETS = (0.0, 0.5, 0.25, 0.75)
#: Edge of the ``"gtao"`` tile: the interleaved gradient noise is evaluated on 64 x 64 pixels
#: and tiled (an engine evaluates it at every pixel; it has no short period).
GTAO_TILE = 64
# Jimenez 2014's interleaved gradient noise: frac(c * frac(a x + b y))
_IGN = (0.06711056, 0.00583715, 52.9829189)
# the last float below 1: an azimuth survives at the pole u2 = 0 (z = -1 + 2^-53, so that
# (z + 1) / 2 = 2^-54 reads back as 0 within rounding)
_Z_MIN = np.nextafter(-1.0, 0.0)


def check_schedule(schedule) -> str:
    """``schedule`` if it is one of :data:`SCHEDULES`, else a ValueError naming the argument
    and listing the valid names."""
    return check_choice(schedule, "schedule", SCHEDULES)


def check_frame(frame) -> int:
    """``frame`` as an int if it is an integer >= 0 (not a bool), else a ValueError naming it."""
    return check_int(frame, "frame", minimum=0)


def period(schedule: str) -> int | None:
    """The number of frames after which ``schedule`` repeats exactly; None if it never does.

    Examples
    --------
    >>> [period(s) for s in SCHEDULES]
    [None, None, 64, 24, None]
    """
    check_schedule(schedule)
    return {"r2": _R2_PERIOD, "gtao": len(GTAO_ROTATIONS) * len(GTAO_OFFSETS)}.get(schedule)


def hilbert_index(x, y, *, level: int = _R2_LEVEL) -> np.ndarray:
    """The position along the Hilbert curve of the 2^level x 2^level grid of pixel (x, y).

    The curve XeGTAO's ``HilbertIndex`` walks (level 6: 64 x 64): x the column, y the row
    counted from the top (Direct3D's pixel coordinates), index 0 at (0, 0), the quarters of
    the grid visited top-left, bottom-left, bottom-right, top-right; consecutive indices are
    4-neighbours. Coordinates are taken mod 2^level.

    Parameters
    ----------
    x, y : array_like of int
        Pixel column and row (broadcast together).
    level : int, optional
        log2 of the grid's edge (default 6).

    Returns
    -------
    ndarray of int64
        The index in [0, 4^level), of the broadcast shape of x and y.

    Notes
    -----
    The grid is split into quarters level by level, from the coarsest. In the frame of the
    current sub-square, its quarter (q_x, q_y) is the base-4 digit (3 q_x) XOR q_y of the index
    (0, 1, 2, 3 for (0, 0), (0, 1), (1, 1), (1, 0)). The sub-curve in the quarter is the parent
    curve transposed (quarter (0, 0)), transposed across the anti-diagonal (quarter (1, 0)) or
    kept (the other two). Those frames form Klein's four-group, generated by the transpose
    and by the complement of both coordinates (a half turn), so the frame of every pixel is
    two flags, toggled per level: no coordinate is rewritten.

    Examples
    --------
    >>> hilbert_index([0, 1, 1, 0], [0, 0, 1, 1]).tolist()
    [0, 1, 2, 3]
    """
    x, y = np.broadcast_arrays(np.asarray(x, dtype=np.int64), np.asarray(y, dtype=np.int64))
    index = np.zeros(x.shape, dtype=np.int64)
    swap = np.zeros(x.shape, dtype=bool)     # the frame transposes
    flip = np.zeros(x.shape, dtype=bool)     # the frame complements both coordinates
    for b in range(level - 1, -1, -1):
        bx, by = ((x >> b) & 1).astype(bool), ((y >> b) & 1).astype(bool)
        qx = np.where(swap, by, bx) ^ flip
        qy = np.where(swap, bx, by) ^ flip
        index = 4 * index + ((3 * qx.astype(np.int64)) ^ qy.astype(np.int64))
        swap ^= ~qy              # quarters (0, 0) and (1, 0) transpose
        flip ^= ~qy & qx         # quarter (1, 0) also turns by half
    return index


def gtao_temporal(frame: int) -> tuple[float, float]:
    """The ``"gtao"`` schedule's temporal (rotation in degrees, step offset) of ``frame``:
    ``GTAO_ROTATIONS[frame % 6]`` and ``GTAO_OFFSETS[(frame // 6) % 4]`` (Unity HDRP's
    indexing), period 24.

    Examples
    --------
    >>> [gtao_temporal(f) for f in (0, 1, 6, 23, 24)]
    [(60.0, 0.0), (300.0, 0.0), (60.0, 0.5), (0.0, 0.75), (60.0, 0.0)]
    """
    frame = check_frame(frame)
    return GTAO_ROTATIONS[frame % len(GTAO_ROTATIONS)], GTAO_OFFSETS[(frame // len(GTAO_ROTATIONS)) % len(GTAO_OFFSETS)]


def _white_texture(seed, frame: int, noise_size: int, dim: int) -> np.ndarray:
    """Unit vectors of normal draws, normalized: frame 0 draws from ``as_rng(seed)``; a later
    frame of an int seed from ``default_rng([seed, frame])``; a Generator is drawn from as
    given, None draws fresh entropy."""
    if frame == 0 or seed is None or isinstance(seed, np.random.Generator):
        rng = as_rng(seed)
    else:
        as_rng(seed)                       # the seed's own check (a ValueError naming it)
        rng = np.random.default_rng([int(seed), frame])
    v = rng.normal(size=(noise_size, noise_size, dim))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _turn(frame: int) -> float:
    """The ``"rotate"`` schedule's angle of ``frame`` in [0, 2 pi): 2 pi frac(frame GOLDEN)."""
    return 2.0 * np.pi * ((frame * GOLDEN) % 1.0)


def _rotate_texture(seed, frame: int, noise_size: int, dim: int) -> np.ndarray:
    """Frame 0's white texture with every vector turned about the z axis by :func:`_turn`."""
    v = _white_texture(seed, 0, noise_size, dim)
    if frame == 0:
        return v
    c, s = np.cos(_turn(frame)), np.sin(_turn(frame))
    out = v.copy()
    out[..., 0] = c * v[..., 0] - s * v[..., 1]
    out[..., 1] = s * v[..., 0] + c * v[..., 1]
    return out


def _read(texture: np.ndarray) -> np.ndarray:
    """(T, T, 2) the (u1, u2) a dim-3 texture encodes: azimuth / 2 pi and (z + 1) / 2."""
    u1 = (np.arctan2(texture[..., 1], texture[..., 0]) / (2.0 * np.pi)) % 1.0
    u2 = 0.5 * (texture[..., 2] + 1.0)
    return np.minimum(np.stack([u1, u2], axis=-1), np.nextafter(1.0, 0.0))


def _r2_uniforms(frame: int) -> np.ndarray:
    """XeGTAO's ``SpatioTemporalNoise`` on the 64 x 64 tile: (u1, u2) =
    frac(0.5 + index alpha), index = Hilbert index + 288 (frame mod 64)."""
    row, col = np.mgrid[0:R2_TILE, 0:R2_TILE]
    index = hilbert_index(col, row) + _R2_FRAME_STRIDE * (frame % _R2_PERIOD)
    alpha = np.asarray(_R2_ALPHA)
    return (0.5 + index[..., None] * alpha) % 1.0


def _gtao_uniforms(frame: int) -> np.ndarray:
    """Jimenez et al. 2016's spatial and temporal noise on the 64 x 64 tile:
    u1 = frac(IGN(x, y) + rotation / 360), u2 = frac(0.25 ((y - x) & 3) + offset)."""
    y, x = np.mgrid[0:GTAO_TILE, 0:GTAO_TILE]
    a, b, c = _IGN
    direction = (c * ((a * x + b * y) % 1.0)) % 1.0     # Jimenez 2014, interleaved gradient noise
    offset = 0.25 * ((y - x) & 3)                       # Jimenez et al. 2016, spatial offsets
    rotation, temporal_offset = gtao_temporal(frame)
    u1 = (direction + rotation / 360.0) % 1.0
    u2 = (offset + temporal_offset) % 1.0
    return np.stack([u1, u2], axis=-1)


def _blue_uniforms(frame: int) -> np.ndarray:
    """The stored void-and-cluster arrays B1, B2 ((rank + 0.5) / 4096) on the 64 x 64 tile,
    animated: u1 = frac(B1 + n GOLDEN), u2 = frac(B2 + n SILVER)."""
    b = ranks_to_uniforms(blue_ranks()[..., 0]), ranks_to_uniforms(blue_ranks()[..., 1])
    return np.stack([(b[0] + frame * GOLDEN) % 1.0, (b[1] + frame * SILVER) % 1.0], axis=-1)


def _validate(schedule, frame, noise_size) -> tuple[str, int]:
    schedule = check_schedule(schedule)
    frame = check_frame(frame)
    check_int(noise_size, "noise_size")
    return schedule, frame


def schedule_uniforms(schedule: str, frame: int, *, seed=0, noise_size: int = NOISE_SIZE) -> np.ndarray:
    """The per-texel pair (u1, u2) in [0, 1) of frame ``frame`` of a noise schedule.

    Parameters
    ----------
    schedule : {"white", "rotate", "r2", "gtao", "blue"}
        The schedule (:data:`SCHEDULES`; ``docs/screenspace.md``, "Noise schedules").
    frame : int
        The frame, >= 0.
    seed : int, numpy.random.Generator or None, optional
        The white texture's seed (``"white"``, ``"rotate"``; default 0), as the estimators
        take it; unused by ``"r2"``, ``"gtao"`` and ``"blue"``, which are deterministic
        (still checked).
    noise_size : int, optional
        Edge T of the ``"white"`` and ``"rotate"`` tiles (>= 1, default 4). ``"r2"``,
        ``"gtao"`` and ``"blue"`` ignore it: their tile is 64 x 64.

    Returns
    -------
    (T, T, 2) ndarray of float64
        (u1, u2) of texel (row, column); u1 drives the slice (pattern) rotation, u2 the step
        jitter. For ``"white"`` and ``"rotate"``: the pair the dim-3 texture encodes (its
        azimuth over 2 pi and (z + 1) / 2); their dim-2 texture is drawn apart (its angle is
        as uniform).

    Raises
    ------
    ValueError
        If ``schedule`` is not one of :data:`SCHEDULES` (the message lists them), ``frame`` is
        not an integer >= 0, ``noise_size`` is not an integer >= 1 or ``seed`` is invalid.

    Examples
    --------
    >>> u = schedule_uniforms("r2", 0)
    >>> u.shape, u[0, 0].tolist()      # index 0: frac(0.5 + 0)
    ((64, 64, 2), [0.5, 0.5])
    >>> bool(np.array_equal(schedule_uniforms("gtao", 3), schedule_uniforms("gtao", 27)))
    True
    >>> ranks = schedule_uniforms("blue", 0)[..., 0] * 4096 - 0.5     # frame 0: the stored ranks
    >>> bool(np.array_equal(np.sort(ranks.round().ravel()), np.arange(4096)))
    True
    """
    schedule, frame = _validate(schedule, frame, noise_size)
    deterministic = {"r2": _r2_uniforms, "gtao": _gtao_uniforms, "blue": _blue_uniforms}
    if schedule in deterministic:
        as_rng(seed)                       # unused, but checked as everywhere
        return deterministic[schedule](frame)
    maker = _white_texture if schedule == "white" else _rotate_texture
    return _read(maker(seed, frame, noise_size, 3))


def uniforms_to_texture(u, dim: int) -> np.ndarray:
    """(T, T, dim) unit vectors that the estimators read as the pairs ``u`` (T, T, 2).

    dim 3: azimuth 2 pi u1 and z = 2 u2 - 1, so that the horizon estimators' reading
    (``slice_noise``: azimuth / 2 pi, (z + 1) / 2) returns (u1, u2) within float rounding
    (at u2 = 0, z is the float above -1, which keeps the azimuth). dim 2: the angle 2 pi u1.

    Examples
    --------
    >>> v = uniforms_to_texture(np.array([[[0.25, 0.5]]]), 3)
    >>> np.round(v, 12).tolist()
    [[[0.0, 1.0, 0.0]]]
    """
    u = np.asarray(u, dtype=np.float64)
    if u.ndim != 3 or u.shape[-1] != 2:
        raise ValueError(f"u must have shape (T, T, 2), got {u.shape}")
    if dim not in (2, 3):
        raise ValueError(f"dim must be 2 or 3, got {dim!r}")
    phi = 2.0 * np.pi * u[..., 0]
    if dim == 2:
        return np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    z = np.maximum(2.0 * u[..., 1] - 1.0, _Z_MIN)
    r = np.sqrt((1.0 - z) * (1.0 + z))      # sqrt(1 - z^2), accurate near the poles
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def schedule_texture(schedule: str, frame: int, *, seed=0, noise_size: int = NOISE_SIZE, dim: int = 3) -> np.ndarray:
    """The (T, T, dim) texture of unit vectors of frame ``frame`` of a schedule: what the
    estimators read (through ``noise_texture`` of :mod:`vobscure.screenspace._common`).

    ``"white"``: normal draws normalized (frame 0 draws from ``as_rng(seed)``, the
    single-frame texture bit for bit; frame n > 0 of an int seed from
    ``numpy.random.default_rng([seed, n])``; a Generator is drawn from as given, the caller
    advancing it from frame to frame; None: fresh entropy). NumPy's ``SeedSequence`` reads
    ``[seed, 0]`` as ``seed`` (trailing zero words add no entropy), so frame 0 follows the same
    rule; the int seed s + n 2^32 coincides with frame n of seed s. ``"rotate"``: frame 0's white
    texture turned about the z axis by 2 pi frac(n GOLDEN) (the step jitter z unchanged).
    ``"r2"``, ``"gtao"``, ``"blue"``: :func:`uniforms_to_texture` of :func:`schedule_uniforms`
    (64 x 64).
    Arguments as for :func:`schedule_uniforms`; ``dim`` 2 or 3.

    Examples
    --------
    >>> schedule_texture("white", 0, seed=7, dim=2).shape, schedule_texture("r2", 5, dim=3).shape
    ((4, 4, 2), (64, 64, 3))
    """
    schedule, frame = _validate(schedule, frame, noise_size)
    if dim not in (2, 3):
        raise ValueError(f"dim must be 2 or 3, got {dim!r}")
    if schedule == "white":
        return _white_texture(seed, frame, noise_size, dim)
    if schedule == "rotate":
        return _rotate_texture(seed, frame, noise_size, dim)
    return uniforms_to_texture(schedule_uniforms(schedule, frame, seed=seed), dim)
