"""Closed forms of the test scenes, in one place (DESIGN.md, "Testing").

**The slab** (``vo.scenes.slab``): a plane. At a point on it nothing occludes: AO 1; the
world-space VO of the ball centred on the point is 1/2 (the half below the plane is solid),
1 when the ball is clamped to the normal's side (``normal_clamp``).

**The crease** (``vo.scenes.crease``): the floor y = 0 (x > 0) meets the wall x = 0. A
receiver on the floor at distance a from the wall, normal +y, within a distance R, has
c = a / R in [0, 1]; the wall cuts the hemisphere (or ball) of radius R at x = -a, so it
blocks the directions with omega_x < -c.
"""

from __future__ import annotations

import numpy as np

#: A point on the slab: AO, VO of the ball, VO of the ball clamped to the normal's side.
SLAB_AO = 1.0
SLAB_VO = 0.5
SLAB_VO_CLAMPED = 1.0


def crease_points(c, radius=1.0):
    """Receivers on the crease's floor at x = c R, and their normals (+y): (n, 3) each."""
    a = np.atleast_1d(np.asarray(c, dtype=float)) * radius
    points = np.stack([a, np.zeros_like(a), np.zeros_like(a)], axis=1)
    normals = np.tile([0.0, 1.0, 0.0], (len(a), 1))
    return points, normals


def crease_cosine_ao(c):
    """Cosine-weighted AO within R: 1 - (acos c - c sqrt(1 - c^2)) / pi."""
    c = np.asarray(c, dtype=float)
    return 1.0 - (np.arccos(c) - c * np.sqrt(1.0 - c * c)) / np.pi


def crease_uniform_ao(c):
    """Uniform-hemisphere AO within R: (1 + c) / 2."""
    return (1.0 + np.asarray(c, dtype=float)) / 2.0


def crease_vo(c):
    """World-space VO of the ball of radius R: 1/2 - (1 - c)^2 (2 + c) / 8. The floor fills
    the lower half; the wall fills the upper half of the cap of height R (1 - c) beyond
    x = -a, pi R^3 (1 - c)^2 (2 + c) / 6, of the ball's 4 pi R^3 / 3."""
    c = np.asarray(c, dtype=float)
    return 0.5 - (1.0 - c) ** 2 * (2.0 + c) / 8.0


def crease_vo_clamped(c):
    """VO of the ball clamped to the normal's side (the half ball above the floor):
    1 - (1 - c)^2 (2 + c) / 4 (the same half cap, of a half ball of 2 pi R^3 / 3)."""
    c = np.asarray(c, dtype=float)
    return 1.0 - (1.0 - c) ** 2 * (2.0 + c) / 4.0


def crease_bent_normal(c):
    """The unnormalized bent normal, the integral of omega cos(theta) over the open directions
    (omega_x >= -c, omega_y > 0): (2/3 (1 - c^2)^(3/2), pi/3 + pi c/2 - pi c^3/6, 0)
    (docs/shading.md)."""
    c = np.asarray(c, dtype=float)
    b_x = 2.0 / 3.0 * (1.0 - c * c) ** 1.5
    b_y = np.pi / 3.0 + np.pi * c / 2.0 - np.pi * c ** 3 / 6.0
    return np.stack([b_x, b_y, np.zeros_like(c)], axis=-1)


def slab_shell_vo(depth, radius=1.0):
    """World-space VO of the ball of radius R centred on a point of a plane when only a layer
    ``depth`` deep below the plane is solid (the shell reference seen along a straight line
    through the plane): one minus the volume of the ball between the plane and ``depth`` below
    it, over the ball's volume. The layer is two spherical caps' difference, a cap of height h
    having volume pi h^2 (3R - h) / 3."""
    h = np.minimum(np.asarray(depth, dtype=float), radius)

    def cap(height):
        return np.pi * height**2 * (3 * radius - height) / 3

    return 1.0 - (cap(radius) - cap(radius - h)) / (4.0 / 3.0 * np.pi * radius**3)
