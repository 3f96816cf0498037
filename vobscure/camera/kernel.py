"""The projection kernel: view space <-> continuous pixel coordinates, on arrays.

Plain functions of arrays and a projection's numbers (``fx``, ``fy``, ``cx``, ``cy`` and
whether it is perspective), with no validation, no copies and no warnings control: the
callers (:class:`~vobscure.camera.Camera` and the screen-space estimators' inner loops)
check their inputs once and call these on every tap. Each function performs its arithmetic
in the order written in its docstring, so a result does not depend on which caller asked.

A view-space point ``(X, Y, Z)`` (x right, y up, z = depth in front) and the continuous pixel
coordinate ``(x, y)`` (x right, y down, pixel (i, j) centred at (j + 0.5, i + 0.5)) are related
by

* perspective (a general pinhole): ``x = cx + fx X / Z``, ``y = cy - fy Y / Z``;
* orthographic: ``x = cx + fx X``, ``y = cy - fy Y`` (``fx = fy`` pixels per world unit).

Two forms of the inverse exist because callers need both: :func:`unproject_xy` scales the
pixel offset by the depth first (``(x - cx) Z / fx``), :func:`ray_xy` then :func:`ray_to_xy`
divide first (``((x - cx) / fx) Z``), which lets an estimator keep a pixel's ray
``((x - cx) / fx, (cy - y) / fy)`` and reuse it at every depth. The two can differ in the
last bit.
"""

from __future__ import annotations

import numpy as np

__all__ = ["project_xy", "unproject_xy", "ray_xy", "ray_to_xy", "shift_ray"]


def project_xy(X, Y, Z, fx, fy, cx, cy, perspective):
    """View-space points to continuous pixel coordinates.

    Parameters
    ----------
    X, Y, Z : array_like of float
        View-space coordinates (broadcasting).
    fx, fy, cx, cy : float
        The projection's focal lengths (perspective; pixels per world unit, orthographic)
        and principal point, in pixels.
    perspective : bool

    Returns
    -------
    x, y : ndarray
        Perspective: ``k_x = fx / Z``, ``k_y = fy / Z`` (``k_y`` is ``k_x`` when
        ``fy == fx``), ``x = cx + k_x X``, ``y = cy - k_y Y``; ``Z <= 0`` is not special
        (a caller that wants NaN there passes NaN depths). Orthographic:
        ``x = cx + fx X``, ``y = cy - fy Y``.

    Examples
    --------
    >>> project_xy(1.0, 1.0, 5.0, 5.0, 5.0, 10.0, 5.0, True)
    (11.0, 4.0)
    >>> project_xy(1.0, 1.0, 5.0, 5.0, 5.0, 10.0, 5.0, False)
    (15.0, 0.0)
    """
    if perspective:
        kx = fx / Z
        ky = kx if fy == fx else fy / Z
        return cx + kx * X, cy - ky * Y
    return cx + fx * X, cy - fy * Y


def unproject_xy(x, y, Z, fx, fy, cx, cy, perspective):
    """Continuous pixel coordinates and depth to view-space ``(X, Y)``, the inverse of
    :func:`project_xy`, scaling by the depth first.

    Parameters
    ----------
    x, y : array_like of float
        Pixel coordinates.
    Z : array_like of float
        View-space depth (unused by an orthographic projection).
    fx, fy, cx, cy : float
    perspective : bool

    Returns
    -------
    X, Y : ndarray
        With ``u = x - cx``, ``v = cy - y``: perspective ``X = u Z / fx``,
        ``Y = v Z / fy``; orthographic ``X = u / fx``, ``Y = v / fy``.

    Examples
    --------
    >>> unproject_xy(11.0, 4.0, 5.0, 5.0, 5.0, 10.0, 5.0, True)
    (1.0, 1.0)
    """
    u = x - cx
    v = cy - y
    if perspective:
        return u * Z / fx, v * Z / fy
    return u / fx, v / fy


def ray_xy(x, y, fx, fy, cx, cy, *, out=None):
    """The view ray through continuous pixel coordinates: ``((x - cx) / fx, (cy - y) / fy)``.

    The ray's ``(X / Z, Y / Z)`` under perspective, its view-space ``(X, Y)`` under an
    orthographic projection; :func:`ray_to_xy` turns it into the point at a depth.

    Parameters
    ----------
    x, y : array_like of float
        Pixel coordinates. Pixel indices ``(col, row)`` with the principal point passed as
        ``(cx - 0.5, cy - 0.5)`` give the rays through the pixel centres.
    fx, fy, cx, cy : float
    out : pair of ndarray, optional
        Where to write the two results (may be ``x`` and ``y`` themselves).

    Returns
    -------
    a, b : ndarray
        ``a = (x - cx) / fx``, ``b = (cy - y) / fy``.

    Examples
    --------
    >>> ray_xy(11.0, 4.0, 5.0, 5.0, 10.0, 5.0)
    (0.2, 0.2)
    """
    if out is None:
        return (x - cx) / fx, (cy - y) / fy
    a, b = out
    np.subtract(x, cx, out=a)
    a /= fx
    np.subtract(cy, y, out=b)
    b /= fy
    return a, b


def ray_to_xy(a, b, Z, perspective, *, out=None):
    """The view-space ``(X, Y)`` at depth ``Z`` on the ray ``(a, b)`` of :func:`ray_xy`.

    Parameters
    ----------
    a, b : array_like of float
        A ray from :func:`ray_xy` (or :func:`shift_ray`).
    Z : array_like of float
        View-space depth (unused by an orthographic projection).
    perspective : bool
    out : pair of ndarray, optional
        Where to write the two results (may be ``a`` and ``b`` themselves).

    Returns
    -------
    X, Y : ndarray
        Perspective ``(a Z, b Z)``; orthographic ``(a, b)`` (the arrays themselves
        without ``out``).

    Examples
    --------
    >>> ray_to_xy(0.2, 0.2, 5.0, True)
    (1.0, 1.0)
    """
    if out is None:
        return (a * Z, b * Z) if perspective else (a, b)
    X, Y = out
    if perspective:
        np.multiply(a, Z, out=X)
        np.multiply(b, Z, out=Y)
    else:
        if X is not a:
            X[...] = a
        if Y is not b:
            Y[...] = b
    return X, Y


def shift_ray(a, b, dx, dy, fx, fy):
    """The ray of the pixel ``(dx, dy)`` pixels away from the one whose ray is ``(a, b)``.

    Parameters
    ----------
    a, b : array_like of float
        A ray from :func:`ray_xy`.
    dx, dy : array_like of float
        Offset in pixels, x right and y down.
    fx, fy : float

    Returns
    -------
    a2, b2 : ndarray
        ``a + dx / fx``, ``b - dy / fy``: the ray :func:`ray_xy` gives at ``(x + dx, y + dy)``,
        up to rounding.

    Examples
    --------
    >>> shift_ray(0.2, 0.2, 5.0, -5.0, 5.0, 5.0)
    (1.2, 1.2)
    """
    return a + dx / fx, b - dy / fy
