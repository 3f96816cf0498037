"""Sampling warps and randomized quasi-Monte Carlo point sets.

Warps are named ``source_to_target`` as in Mitsuba 3 (``warp.h``), each with its pdf where
one is needed. The RQMC scheme gives every ground-truth estimate an honest standard error:
one scrambled Sobol' base set is shared by all points, and each point gets ``groups``
independent uniform random shifts of it (Cranley-Patterson rotations). Each shifted set is
an unbiased estimator; the spread of the ``groups`` group means gives the standard error.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

__all__ = [
    "square_to_cosine_hemisphere",
    "square_to_uniform_hemisphere",
    "cube_to_uniform_ball",
    "cube_to_uniform_half_ball",
    "square_to_uniform_disk",
    "square_to_uniform_half_disk",
    "square_to_uniform_disk_concentric",
    "tangent_frame",
    "to_world",
    "sobol_base",
    "shifted_hemisphere_directions",
]


def _polar(r: np.ndarray, phi: np.ndarray, *z: np.ndarray) -> np.ndarray:
    """(..., 2) points ``r (cos phi, sin phi)``, or (..., 3) with ``z`` as third coordinate."""
    return np.stack([r * np.cos(phi), r * np.sin(phi), *z], axis=-1)


def square_to_cosine_hemisphere(u: np.ndarray) -> np.ndarray:
    """(..., 2) uniform in [0, 1)^2 -> (..., 3) unit vectors on the z >= 0 hemisphere, pdf cos(theta)/pi.

    Malley's method: uniform on the unit disk (polar map r = sqrt(u0)), lifted to the hemisphere.
    """
    r = np.sqrt(u[..., 0])
    phi = 2.0 * np.pi * u[..., 1]
    z = np.sqrt(np.maximum(0.0, 1.0 - u[..., 0]))
    return _polar(r, phi, z)


def square_to_uniform_hemisphere(u: np.ndarray) -> np.ndarray:
    """(..., 2) uniform in [0, 1)^2 -> (..., 3) unit vectors on the z >= 0 hemisphere, pdf 1/(2 pi)."""
    z = u[..., 0]
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * np.pi * u[..., 1]
    return _polar(r, phi, z)


def cube_to_uniform_ball(u: np.ndarray) -> np.ndarray:
    """(..., 3) uniform in [0, 1)^3 -> (..., 3) uniform in the unit ball (volume preserving)."""
    r = np.cbrt(u[..., 0])
    z = 1.0 - 2.0 * u[..., 1]
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = 2.0 * np.pi * u[..., 2]
    return r[..., None] * _polar(s, phi, z)


def cube_to_uniform_half_ball(u: np.ndarray) -> np.ndarray:
    """(..., 3) uniform in [0, 1)^3 -> (..., 3) uniform in the half ball z >= 0 (volume preserving).

    The polar map of :func:`cube_to_uniform_ball` with the direction from
    :func:`square_to_uniform_hemisphere`: radius cbrt(u0), direction from (u1, u2).

    Parameters
    ----------
    u : (..., 3) float
        Points in [0, 1)^3.

    Returns
    -------
    (..., 3) float64
        Points with |x| < 1 and z >= 0.

    Examples
    --------
    >>> x = cube_to_uniform_half_ball(np.array([[0.125, 0.0, 0.25], [1.0, 1.0, 0.0]]))
    >>> np.round(x, 12).tolist()
    [[0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]
    """
    return np.cbrt(u[..., 0])[..., None] * square_to_uniform_hemisphere(u[..., 1:])


def square_to_uniform_disk(u: np.ndarray) -> np.ndarray:
    """(..., 2) uniform in [0, 1)^2 -> (..., 2) uniform in the unit disk (polar map, area preserving).

    Radius sqrt(u0), angle 2 pi u1.

    Parameters
    ----------
    u : (..., 2) float
        Points in [0, 1)^2.

    Returns
    -------
    (..., 2) float64
        Points with |x| < 1.

    Examples
    --------
    >>> np.round(square_to_uniform_disk(np.array([[0.25, 0.25], [1.0, 0.5]])), 12).tolist()
    [[0.0, 0.5], [-1.0, 0.0]]
    """
    r = np.sqrt(u[..., 0])
    phi = 2.0 * np.pi * u[..., 1]
    return _polar(r, phi)


def square_to_uniform_half_disk(u: np.ndarray) -> np.ndarray:
    """(..., 2) uniform in [0, 1)^2 -> (..., 2) uniform in the half disk x >= 0 (area preserving).

    The polar map of :func:`square_to_uniform_disk` with the angle pi u1 - pi / 2.

    Parameters
    ----------
    u : (..., 2) float
        Points in [0, 1)^2.

    Returns
    -------
    (..., 2) float64
        Points with |x| < 1 and x_0 >= 0.

    Examples
    --------
    >>> np.round(square_to_uniform_half_disk(np.array([[0.25, 0.5], [1.0, 0.0]])), 12).tolist()
    [[0.5, 0.0], [0.0, -1.0]]
    """
    r = np.sqrt(u[..., 0])
    phi = np.pi * u[..., 1] - 0.5 * np.pi
    return _polar(r, phi)


def square_to_uniform_disk_concentric(u: np.ndarray) -> np.ndarray:
    """(..., 2) uniform in [0, 1)^2 -> (..., 2) uniform in the unit disk, concentric map.

    The area-preserving, low-distortion map of Shirley & Chiu 1997: squares about the centre
    of [0, 1)^2 go to circles, so a stratified or low-discrepancy set keeps its spacing.

    Parameters
    ----------
    u : (..., 2) float
        Points in [0, 1)^2.

    Returns
    -------
    (..., 2) float64
        Points with |x| <= 1.

    References
    ----------
    Shirley, P. and Chiu, K. 1997. A low distortion map between disk and square. JGT 2(3).

    Examples
    --------
    >>> np.round(square_to_uniform_disk_concentric(np.array([[0.5, 0.5], [1.0, 0.5], [0.5, 0.0]])), 12).tolist()
    [[0.0, 0.0], [1.0, 0.0], [-0.0, -1.0]]
    """
    a = 2.0 * u[..., 0] - 1.0
    b = 2.0 * u[..., 1] - 1.0
    big_a = np.abs(a) > np.abs(b)
    r = np.where(big_a, a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi = np.where(big_a, 0.25 * np.pi * b / np.where(a == 0, 1.0, a),
                       0.5 * np.pi - 0.25 * np.pi * a / np.where(b == 0, 1.0, b))
    phi = np.where(r == 0, 0.0, phi)
    return _polar(r, phi)


def tangent_frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents (t, b) with (t, b, n) right-handed orthonormal, for unit (..., 3) n.

    The branchless construction of Duff et al., "Building an Orthonormal Basis, Revisited",
    JCGT 6(1), 2017, Listing 3.
    """
    sign = np.where(n[..., 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    t = np.stack([1.0 + sign * n[..., 0] ** 2 * a, sign * b, -sign * n[..., 0]], axis=-1)
    bb = np.stack([b, sign + n[..., 1] ** 2 * a, -n[..., 1]], axis=-1)
    return t, bb


def to_world(local: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rotate (P, k, 3) local vectors (z along the normal) into the frames of (P, 3) normals."""
    t, b = tangent_frame(n)
    return (local[..., 0:1] * t[:, None, :] + local[..., 1:2] * b[:, None, :]
            + local[..., 2:3] * n[:, None, :])


def sobol_base(dim: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """(n, dim) scrambled Sobol' points (n rounded up to a power of two, then truncated)."""
    m = max(1, int(np.ceil(np.log2(max(n, 1)))))
    engine = qmc.Sobol(d=dim, scramble=True, seed=rng)
    return engine.random_base2(m)[:n]


def shifted_hemisphere_directions(normals: np.ndarray, base: np.ndarray, shifts: np.ndarray,
                                  weighting: str = "cosine", *, origins=None, step: float = 0.0):
    """World directions of a Cranley-Patterson-shifted 2-D point set, in float32.

    Equal (to float32 rounding) to ``to_world(warp((base + shift) mod 1), normals)`` with
    ``warp`` :func:`square_to_cosine_hemisphere` or :func:`square_to_uniform_hemisphere`,
    but about twice as fast: a shift of the azimuth coordinate u1 is a rotation of the
    tangent frame about the normal, so cos/sin are taken once for the base set and once per
    (point, group) rather than once per sample.

    Parameters
    ----------
    normals : (P, 3) float
        Unit normals.
    base : (m, 2) float
        Base points in [0, 1)^2.
    shifts : (P, G, 2) float
        One shift per point and group.
    weighting : {"cosine", "uniform"}
    origins : (P, 3) float, optional
        When given, also return ray origins ``origins + step * direction`` per sample,
        computed in the same pass (see :meth:`vobscure.raytrace.Tracer.offset_origins`).
    step : float
        The step along each ray for ``origins``.

    Returns
    -------
    (P, G, m, 3) float32
        The directions; a pair (origins, directions) of such arrays when ``origins`` is given.
    """
    f32 = np.float32
    phi = 2.0 * np.pi * base[:, 1]
    cos_phi, sin_phi = np.cos(phi).astype(f32), np.sin(phi).astype(f32)
    alpha = 2.0 * np.pi * shifts[..., 1]
    cos_a, sin_a = np.cos(alpha).astype(f32)[..., None], np.sin(alpha).astype(f32)[..., None]
    t, b = tangent_frame(normals)
    t, b = t.astype(f32)[:, None, :], b.astype(f32)[:, None, :]
    t_rot = cos_a * t + sin_a * b                                   # (P, G, 3)
    b_rot = cos_a * b - sin_a * t
    u0 = base[:, 0].astype(f32)[None, None, :] + shifts[..., 0:1].astype(f32)   # (P, G, m)
    u0 -= np.floor(u0)
    if weighting == "cosine":
        r, z = np.sqrt(u0), np.sqrt(np.maximum(f32(0), f32(1) - u0))
    else:
        z, r = u0, np.sqrt(np.maximum(f32(0), f32(1) - u0 * u0))
    x, y = r * cos_phi, r * sin_phi                                 # (P, G, m) each
    n32 = normals.astype(f32)
    # one contiguous (P, G, m) pass per output component: broadcasting over a trailing
    # axis of length 3 is several times slower
    out = np.empty(u0.shape + (3,), dtype=f32)
    out_o = None if origins is None else np.empty(u0.shape + (3,), dtype=f32)
    o32 = None if origins is None else np.asarray(origins, np.float64).astype(f32)
    for k in range(3):
        comp = x * t_rot[:, :, None, k]
        comp += y * b_rot[:, :, None, k]
        comp += z * n32[:, None, None, k]
        out[..., k] = comp
        if out_o is not None:
            comp *= f32(step)
            comp += o32[:, None, None, k]
            out_o[..., k] = comp
    return out if out_o is None else (out_o, out)
