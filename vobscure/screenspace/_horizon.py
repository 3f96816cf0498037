"""The slices and taps of the horizon-based estimators (:func:`vobscure.gtao`,
:func:`vobscure.vbao`): the view basis per pixel, the per-texel slice rotation, a slice's
direction and frame, and one step's tap along it (its pixel, depth and view-space vector).
Shared by both so that, at the same options, they walk the same slices and read the same taps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera.kernel import ray_to_xy, shift_ray
from . import _common as C
from ._common import Pixels

@dataclass
class Slice:
    """One slice of a horizon search (Jimenez et al. 2016, Sec. 4) for each pixel of a chunk.

    ``t``: the slice's unit direction (orthogonal to v); ``gamma``: the projected normal's angle
    from v, positive towards t, with its sine and cosine; ``pn_len``: the length of the normal
    projected onto the slice plane; ``ox, oy``: the slice's screen direction in pixels per
    unit of the step parameter (x right, rows up); ``min_s``: the step parameter of the
    smallest offset a tap may take (``min_px`` pixels along the slice).
    """

    t: tuple
    gamma: np.ndarray
    sin_g: np.ndarray
    cos_g: np.ndarray
    pn_len: np.ndarray
    ox: np.ndarray
    oy: np.ndarray
    min_s: np.ndarray


def view_basis(px: Pixels):
    """Per pixel: v, the unit vector from p to the camera (Jimenez et al. 2016, Sec. 4, "view
    vector"; (0, 0, -1) in orthographic), and a frame (b1, b2) orthogonal to it: b1 the view
    x axis made orthogonal to v, b2 = b1 x v (for v = (0, 0, -1): b1 = x, b2 = y). Each a
    tuple of three (k,) arrays."""
    k = len(px.index)
    p = px.p
    px_, py_, pz_ = p[:, 0], p[:, 1], p[:, 2]
    if px.perspective:
        inv = 1.0 / np.sqrt(px_ * px_ + py_ * py_ + pz_ * pz_)
        vx, vy, vz = -px_ * inv, -py_ * inv, -pz_ * inv
    else:
        vx, vy, vz = np.zeros(k), np.zeros(k), -np.ones(k)
    b1x, b1y, b1z = 1.0 - vx * vx, -vx * vy, -vx * vz
    b1l = np.sqrt(b1x * b1x + b1y * b1y + b1z * b1z)
    b1x, b1y, b1z = b1x / b1l, b1y / b1l, b1z / b1l
    b2x, b2y, b2z = b1y * vz - b1z * vy, b1z * vx - b1x * vz, b1x * vy - b1y * vx
    return (vx, vy, vz), (b1x, b1y, b1z), (b2x, b2y, b2z)


@dataclass
class SliceNoise:
    """The per-pixel randomization of a horizon search (see :func:`slice_noise`).

    ``u_step``: (k,) the step jitter in [0, 1); ``has_noise``: whether a texture was given;
    ``texel``: (k,) each pixel's texel of the tiled texture (flat, row-major), None without
    one; ``u_texel``: the slice rotation u in [0, 1) of every texel, None without a texture
    (u = 1/2 for every pixel).
    """

    u_step: np.ndarray
    has_noise: bool
    texel: np.ndarray | None = None
    u_texel: np.ndarray | None = None

    def rotation(self, s: int, slices: int):
        """(cos phi, sin phi) of slice ``s`` of ``slices``, phi = pi (s + u) / slices
        (Jimenez et al. 2016, Algorithm 1): (k,) arrays, or floats without a texture. The
        angle is evaluated once per texel and gathered: the same numbers as per pixel."""
        if self.texel is None:
            phi = np.pi * (s + 0.5) / slices
            return np.cos(phi), np.sin(phi)
        phi = np.pi * (s + self.u_texel) / slices
        return np.take(np.cos(phi), self.texel), np.take(np.sin(phi), self.texel)


def slice_noise(px: Pixels, texture: np.ndarray | None) -> SliceNoise:
    """The slice rotation and the step jitter of each pixel from a 3-D unit-vector noise
    texture (:class:`SliceNoise`): the azimuth of a texel's (x, y) and its z are independent
    and uniform (Archimedes), u_slice = azimuth / (2 pi) and u_step = (z + 1) / 2; 1/2 for
    both without a texture."""
    k = len(px.index)
    if texture is None:
        return SliceNoise(u_step=np.full(k, 0.5), has_noise=False)
    size = texture.shape[0]
    # the texel of each pixel, as noise_at reads it
    texel = (px.row % size) * size + px.col % size
    noise = texture.reshape(-1, 3)
    u_slice = (np.arctan2(noise[:, 1], noise[:, 0]) / (2.0 * np.pi)) % 1.0
    u_step = np.clip(0.5 * (noise[:, 2] + 1.0), 0.0, 1.0 - 1e-12)
    return SliceNoise(u_step=np.take(u_step, texel), has_noise=True, texel=texel, u_texel=u_slice)


def horizon_slice(px: Pixels, rotation, v, b1, b2, *, min_px: float) -> Slice:
    """The slice at view-space angle phi around v (see :class:`Slice`); ``rotation`` is
    (cos phi, sin phi) (:meth:`SliceNoise.rotation`)."""
    vx, vy, vz = v
    n = px.n
    nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
    rx, ry = px.ray
    # Algorithm 1: the slice direction t is cos phi b1 + sin phi b2, orthogonal to v
    cphi, sphi = rotation
    tx, ty, tz = cphi * b1[0] + sphi * b2[0], cphi * b1[1] + sphi * b2[1], cphi * b1[2] + sphi * b2[2]
    # the slice's axis (normal of the plane) and the normal projected onto the plane
    ax, ay, az = ty * vz - tz * vy, tz * vx - tx * vz, tx * vy - ty * vx
    na = nx * ax + ny * ay + nz * az
    pnx, pny, pnz = nx - na * ax, ny - na * ay, nz - na * az
    pn_len = np.sqrt(pnx * pnx + pny * pny + pnz * pnz)
    # gamma: the projected normal's angle from v, positive towards t (Sec. 4)
    g_t = pnx * tx + pny * ty + pnz * tz
    g_v = pnx * vx + pny * vy + pnz * vz
    gamma = np.arctan2(g_t, g_v)
    # its sine and cosine from the same components (within rounding of np.sin and np.cos of
    # gamma, at a fraction of their cost); a zero projection takes the arctangent's angle
    g_len = np.sqrt(g_t * g_t + g_v * g_v)
    sin_g, cos_g = np.divide(g_t, g_len, out=g_t), np.divide(g_v, g_len, out=g_v)
    zero = g_len == 0
    if zero.any():
        sin_g[zero], cos_g[zero] = np.sin(gamma[zero]), np.cos(gamma[zero])
    # the slice's screen direction: the projection of p + R t to first order, in pixels (x
    # right, rows up), honouring fx and fy; the eye, p and every point of that screen line
    # lie in the slice plane
    if px.perspective:
        ox, oy = px.radius_px_x * (tx - rx * tz), px.radius_px * (ty - ry * tz)
    else:
        ox, oy = px.radius_px_x * tx, px.radius_px * ty
    length_px = np.sqrt(ox * ox + oy * oy)
    return Slice(t=(tx, ty, tz), gamma=gamma, sin_g=sin_g, cos_g=cos_g, pn_len=pn_len, ox=ox, oy=oy,
                 min_s=min_px / length_px)


@dataclass
class Tap:
    """A depth tap of a horizon search, per pixel: ``ok`` where it read a surface at a
    distance > 0 from p; ``d`` its depth (p's where not ok); ``delta`` the (3,) tuple of
    (k,) components of the tapped point minus p; ``dist`` its length (1 where not ok);
    ``ray`` the tapped screen position's view ray (see :attr:`Pixels.ray`); ``x, y`` its
    continuous pixel coordinates."""

    ok: np.ndarray
    d: np.ndarray
    delta: tuple
    dist: np.ndarray
    ray: tuple
    x: np.ndarray
    y: np.ndarray


def horizon_tap(px: Pixels, sl: Slice, s, *, fetch: str, offscreen: str) -> Tap:
    """The depth tap at step parameter ``s`` (signed: < 0 on the side opposite to t) along
    the slice ``sl``: read with ``fetch`` (``"nearest"`` snaps the tap to its pixel's centre)
    and reconstructed in view space on the tapped position's own ray."""
    dj = s * sl.ox
    de = s * sl.oy                   # rows up
    if fetch == "nearest":
        # the tap snapped to the centre of the pixel it falls in
        dj, de = np.rint(dj, out=dj), np.rint(de, out=de)
    centre = px.center
    x, y = centre[:, 0] + dj, centre[:, 1] - de
    d = C.fetch_depth(px.depth, x, y, fetch=fetch, offscreen=offscreen, reciprocal=px.perspective)
    p = px.p
    ok = np.isfinite(d)
    ok &= d > 0
    moved = dj != 0
    moved |= de != 0
    ok &= moved
    np.copyto(d, p[:, 2], where=~ok)
    # the tap's view-space position (the pixel's ray shifted to the tap), minus p
    srx, sry = shift_ray(*px.ray, dj, -de, px.fx, px.fy)
    if px.perspective:
        # (a Z, b Z) in new arrays: the offsets from p overwrite them
        ddx, ddy = ray_to_xy(srx, sry, d, True)
        ddx -= p[:, 0]
        ddy -= p[:, 1]
    else:
        ddx, ddy = srx - p[:, 0], sry - p[:, 1]
    ddz = d - p[:, 2]
    dist = ddx * ddx
    dist += np.multiply(ddy, ddy, out=dj)
    dist += np.multiply(ddz, ddz, out=dj)
    np.sqrt(dist, out=dist)
    ok &= dist > 0
    np.copyto(dist, 1.0, where=~ok)
    return Tap(ok=ok, d=d, delta=(ddx, ddy, ddz), dist=dist, ray=(srx, sry), x=x, y=y)
