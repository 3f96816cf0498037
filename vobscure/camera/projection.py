"""Projections: view space onto the pixels of an image, immutable.

Three kinds with one interface (:class:`Projection`), each bound to its image ``size``:

* :class:`Perspective` -- a vertical field of view, square pixels, centred principal point
  (``fx = fy = (H/2) / tan(fov_y/2)``, ``(cx, cy) = (W/2, H/2)``);
* :class:`Orthographic` -- the world-space height of the view (``fx = fy = H / ortho_height``
  pixels per unit, ``(cx, cy) = (W/2, H/2)``);
* :class:`Intrinsics` -- a general pinhole: focal lengths ``fx``, ``fy`` and principal point
  ``(cx, cy)`` in pixels, optional ``near`` / ``far``; also read from a 4x4 OpenGL or
  Direct3D projection matrix (:meth:`Intrinsics.from_matrix`).

Every kind projects with the one kernel of :mod:`vobscure.camera.kernel`; what differs
between kinds (which depths are visible, pixels per unit, how rays leave the camera, how the
view is resized, scaled, cropped and recorded) is a method of the kind.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_array, check_choice, check_positive
from ._checks import PROJECTION_ZERO_TOL, check_fov, check_int, check_size, optional_positive, scalar
from ._frozen import Frozen, read_only, vector_repr
from .kernel import project_xy, ray_xy, unproject_xy

__all__ = ["Projection", "Perspective", "Orthographic", "Intrinsics", "PROJECTION_CONVENTIONS"]

#: Projection-matrix conventions understood by :meth:`Intrinsics.from_matrix`.
PROJECTION_CONVENTIONS = ("opengl", "directx")


class Projection(Frozen):
    """A projection of view space onto an image of ``size`` pixels (base of the three kinds).

    Attributes
    ----------
    size : tuple of int
        ``(width, height)``.
    fx, fy : float
        Perspective: focal lengths in pixels (pixels per world unit at depth 1).
        Orthographic: pixels per world unit.
    cx, cy : float
        Principal point in pixels (x right, y down, from the top-left corner).
    near, far : float or None
        Clipping distances (informational).
    perspective : bool
        Class attribute.
    name : {"perspective", "orthographic"}
    fov_y, ortho_height, focal_length_px : float or None
        The lens parameters that apply to the kind (None otherwise).
    """

    __slots__ = ("_size", "_fx", "_fy", "_cx", "_cy", "_near", "_far")
    perspective = True

    def _set(self, size, fx, fy, cx, cy, near=None, far=None, **extra):
        """Set every slot (the one place that does)."""
        self._set_slots(_size=size, _fx=float(fx), _fy=float(fy), _cx=float(cx), _cy=float(cy), _near=near,
                        _far=far, **extra)

    # ------------------------------------------------------------------ attributes
    size, fx, fy, cx, cy, near, far = read_only("size", "fx", "fy", "cx", "cy", "near", "far")
    fov_y = property(lambda self: None, doc="Vertical field of view in degrees (:class:`Perspective` only).")
    ortho_height = property(lambda self: None, doc="World-space view height (:class:`Orthographic` only).")

    @property
    def name(self) -> str:
        """``"perspective"`` or ``"orthographic"``."""
        return "perspective" if self.perspective else "orthographic"

    @property
    def focal_length_px(self) -> float | None:
        """Vertical focal length ``fy`` in pixels (perspective), None (orthographic)."""
        return self._fy if self.perspective else None

    @property
    def is_centered_square(self) -> bool:
        """``fx == fy`` and the principal point is the image centre."""
        W, H = self._size
        return self._fx == self._fy and self._cx == W / 2.0 and self._cy == H / 2.0

    # ------------------------------------------------------------------ projection
    def _visible(self, Z):
        """The depths the kernel projects: NaN where a point cannot be seen."""
        return Z

    def project(self, view_points) -> tuple[np.ndarray, np.ndarray]:
        """View-space points to continuous pixel coordinates and depth.

        Parameters
        ----------
        view_points : (..., 3) float

        Returns
        -------
        pixels : (..., 2) float64
            ``(x, y)``: x to the right (columns), y down (rows); pixel ``(i, j)`` covers
            ``[j, j+1) x [i, i+1)``. Perspective: NaN for points with ``Z <= 0`` (at or
            behind the camera plane). Points outside the image are not clipped.
        depth : (...) float64
            The view-space z of each point.

        Notes
        -----
        Perspective ``x = cx + fx X/Z``, ``y = cy - fy Y/Z`` (``look_at``: ``cx = W/2``,
        ``cy = H/2``, ``fx = fy = f``); orthographic ``x = W/2 + s X``, ``y = H/2 - s Y`` with
        ``s = H / ortho_height``. Non-finite inputs give non-finite outputs without warnings.

        Examples
        --------
        >>> lens = Perspective(90.0, (20, 10))
        >>> pixels, depth = lens.project([[1.0, 1.0, 5.0], [0.0, 0.0, -1.0]])
        >>> pixels.round(6).tolist(), depth.tolist()
        ([[11.0, 4.0], [nan, nan]], [5.0, -1.0])
        """
        p = as_array(view_points, "view_points", shape=(..., 3), finite=False)
        X, Y, Z = p[..., 0], p[..., 1], p[..., 2]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x, y = project_xy(X, Y, self._visible(Z), self._fx, self._fy, self._cx, self._cy, self.perspective)
        pixels = np.stack([x, y], axis=-1)
        return pixels, scalar(np.array(Z, dtype=np.float64))

    def unproject(self, pixels, depth) -> np.ndarray:
        """Continuous pixel coordinates and depth to view-space points (inverse of project).

        Parameters
        ----------
        pixels : (..., 2) float
            ``(x, y)`` as in :meth:`project`.
        depth : (...) float
            View-space z; must broadcast with ``pixels[..., 0]``. Perspective depths
            ``<= 0`` give points at or behind the camera plane (which :meth:`project` maps
            to NaN); +inf depth (background) gives non-finite points, without warnings.

        Returns
        -------
        (..., 3) float64
            View-space points, shape ``broadcast(pixels[..., 0], depth) + (3,)``:
            perspective ``X = (x - cx) z / fx``, ``Y = (cy - y) z / fy``.

        Examples
        --------
        >>> lens = Perspective(90.0, (20, 10))
        >>> lens.unproject([11.0, 4.0], 5.0).round(6).tolist()
        [1.0, 1.0, 5.0]
        """
        px = as_array(pixels, "pixels", shape=(..., 2), finite=False)
        z = as_array(depth, "depth", finite=False)
        try:
            shape = np.broadcast_shapes(px.shape[:-1], z.shape)
        except ValueError:
            raise ValueError(f"depth of shape {z.shape} does not broadcast with pixels[..., 0] "
                             f"of shape {px.shape[:-1]}") from None
        with np.errstate(invalid="ignore", over="ignore"):
            X, Y = unproject_xy(px[..., 0], px[..., 1], z, self._fx, self._fy, self._cx, self._cy,
                                self.perspective)
        out = np.empty(shape + (3,), dtype=np.float64)
        out[..., 0] = X
        out[..., 1] = Y
        out[..., 2] = z
        return out

    def pixels_per_unit(self, depth):
        """How many pixels a world length at view depth ``depth`` spans vertically on screen.

        For a segment perpendicular to the view direction and along the view's y axis; this
        sizes screen-space sample disks. With anisotropic pixels (``fx != fy``) a horizontal
        segment spans ``fx / fy`` times as many: see :meth:`pixels_per_unit_xy`.

        Parameters
        ----------
        depth : (...) float
            View-space z.

        Returns
        -------
        (...) float64
            Perspective ``fy / depth`` (NaN where ``depth <= 0``, 0 at +inf); orthographic
            ``H / ortho_height`` everywhere. A NumPy scalar for a scalar ``depth``.

        Examples
        --------
        >>> lens = Perspective(90.0, (20, 10))
        >>> lens.pixels_per_unit([1.0, 5.0]).round(6).tolist()
        [5.0, 1.0]
        """
        return self._per_unit(as_array(depth, "depth", finite=False), self._fy)

    def pixels_per_unit_xy(self, depth) -> np.ndarray:
        """Pixels spanned by a world length at view depth ``depth``, along x and along y.

        Parameters
        ----------
        depth : (...) float
            As in :meth:`pixels_per_unit`.

        Returns
        -------
        (..., 2) float64
            ``(fx / depth, fy / depth)`` (perspective; NaN where ``depth <= 0``), or
            ``(s, s)`` with ``s = H / ortho_height`` (orthographic). A view-space offset
            ``(dx, dy)`` at depth z moves the projection by ``(fx dx / z, -fy dy / z)``
            pixels (rows grow down).

        Examples
        --------
        >>> lens = Intrinsics(40.0, 20.0, 10.0, 10.0, (20, 20))
        >>> lens.pixels_per_unit_xy(2.0).tolist()
        [20.0, 10.0]
        """
        z = as_array(depth, "depth", finite=False)
        return np.stack([np.asarray(self._per_unit(z, self._fx), dtype=np.float64),
                         np.asarray(self._per_unit(z, self._fy), dtype=np.float64)], axis=-1)

    def _per_unit(self, z, f):
        raise NotImplementedError

    def pixel_centers(self) -> np.ndarray:
        """(H, W, 2) float64 continuous coordinates of every pixel centre, ``[i, j] = (j + 0.5, i + 0.5)``."""
        W, H = self._size
        out = np.empty((H, W, 2), dtype=np.float64)
        out[..., 0] = np.arange(W, dtype=np.float64)[None, :] + 0.5
        out[..., 1] = np.arange(H, dtype=np.float64)[:, None] + 0.5
        return out

    def _centres(self, rows):
        """Pixel-centre coordinates of the columns and of the rows ``rows``."""
        W, H = self._size
        xs = np.arange(W, dtype=np.float64) + 0.5
        ys = np.arange(H, dtype=np.float64)[rows if rows is not None else slice(None)] + 0.5
        return xs, ys

    # ------------------------------------------------------------------ identity
    def _params(self) -> tuple:
        raise NotImplementedError

    def _key(self) -> tuple:
        # equal projections are of one kind with equal parameters
        return (type(self), self._params())

    def __reduce__(self):
        return (_rebuild, (type(self).__name__, self._params()))

    def __repr__(self) -> str:
        names = self._param_names
        return f"{type(self).__name__}(" + ", ".join(f"{n}={v!r}" for n, v in zip(names, self._params())) + ")"


class _Pinhole(Projection):
    """Rays through one centre: :class:`Perspective` and :class:`Intrinsics`."""

    __slots__ = ()
    perspective = True

    def _visible(self, Z):
        # points at or behind the camera plane project to NaN
        return np.where(Z > 0, Z, np.nan)

    def _per_unit(self, z, f):
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(z > 0, f / np.where(z > 0, z, 1.0), np.nan)
        return scalar(np.asarray(out, dtype=np.float64))

    def primary_rays(self, pose, *, dtype=np.float64, rows=None):
        """World rays through the pixel centres (see :meth:`vobscure.camera.Camera.primary_rays`):
        the direction of pixel (i, j) is ``a_j right + b_i up + forward``, normalized, with
        ``(a_j, b_i)`` the pixel's ray from :func:`~vobscure.camera.kernel.ray_xy`."""
        xs, ys = self._centres(rows)
        a, b = ray_xy(xs, ys, self._fx, self._fy, self._cx, self._cy)
        right, up, forward = (v.astype(dtype) for v in (pose.right, pose.up, pose.forward))
        a = a.astype(dtype)[None, :, None]
        b = b.astype(dtype)[:, None, None]
        directions = a * right + (b * up + forward)
        directions *= (1.0 / np.sqrt(a * a + b * b + 1.0)).astype(dtype)
        origins = np.broadcast_to(pose.eye.astype(dtype), directions.shape)
        return origins, directions

    def pixel_rays(self, pose, pixels):
        """World rays through pixel coordinates: from the eye, unit directions."""
        d_view = self.unproject(as_array(pixels, "pixels", shape=(..., 2)), 1.0)
        d_view /= np.linalg.norm(d_view, axis=-1, keepdims=True)
        directions = pose.view_to_world_dir(d_view)
        directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
        origins = np.broadcast_to(pose.eye, directions.shape).copy()
        return origins, directions

    def cropped(self, left, top, size) -> Intrinsics:
        """The projection of the crop whose top-left pixel is ``(top, left)`` of this image."""
        left, top = check_int(left, "left"), check_int(top, "top")
        return Intrinsics(self._fx, self._fy, self._cx - left, self._cy - top, size, near=self._near,
                          far=self._far)


class _LookAtRecord:
    """The record and repr of a :meth:`vobscure.camera.Camera.look_at` camera (eye, target, up
    and the lens: ``fov_y`` or ``ortho_height``); shared by :class:`Perspective` and
    :class:`Orthographic`."""

    __slots__ = ()

    def scaled(self, factor: float) -> Projection:
        return self

    def camera_record(self, pose) -> dict:
        return {**pose.to_dict(), "size": [int(self._size[0]), int(self._size[1])], "fov_y": self.fov_y,
                "ortho_height": self.ortho_height, "projection": self.name}

    def camera_repr(self, pose) -> str:
        lens = f"fov_y={self.fov_y!r}" if self.fov_y is not None else f"ortho_height={self.ortho_height!r}"
        return (f"Camera.look_at(eye={vector_repr(pose.eye)}, target={vector_repr(pose.target)}, "
                f"up={vector_repr(pose.up_hint)}, size={self._size!r}, {lens})")


class Perspective(_LookAtRecord, _Pinhole):
    """A perspective projection by its vertical field of view: square pixels, centred.

    Parameters
    ----------
    fov_y : float
        Degrees, in the open interval (0, 180).
    size : (2,) int
        ``(width, height)`` in pixels.

    Examples
    --------
    >>> lens = Perspective(90.0, (20, 10))
    >>> lens.fx, lens.cx, lens.cy
    (5.000000000000001, 10.0, 5.0)
    """

    __slots__ = ("_fov_y",)
    _param_names = ("fov_y", "size")

    def __init__(self, fov_y, size):
        fov_y = check_fov(fov_y)
        W, H = size = check_size(size)
        focal = (H / 2.0) / math.tan(math.radians(fov_y) / 2.0)
        self._set(size, focal, focal, W / 2.0, H / 2.0, _fov_y=float(fov_y))

    (fov_y,) = read_only("fov_y")

    def _params(self):
        return (self._fov_y, self._size)

    def with_size(self, size) -> Perspective:
        """The same field of view at another size."""
        return Perspective(self._fov_y, size)


class Orthographic(_LookAtRecord, Projection):
    """An orthographic projection by the world-space height of the view: square pixels, centred.

    Parameters
    ----------
    ortho_height : float
        > 0.
    size : (2,) int
        ``(width, height)`` in pixels.

    Examples
    --------
    >>> lens = Orthographic(2.0, (32, 16))
    >>> lens.fx, float(lens.pixels_per_unit(5.0))
    (8.0, 8.0)
    """

    __slots__ = ("_ortho_height",)
    perspective = False
    _param_names = ("ortho_height", "size")

    def __init__(self, ortho_height, size):
        ortho_height = check_positive(ortho_height, "ortho_height")
        W, H = size = check_size(size)
        scale = H / ortho_height
        self._set(size, scale, scale, W / 2.0, H / 2.0, _ortho_height=float(ortho_height))

    (ortho_height,) = read_only("ortho_height")

    def _params(self):
        return (self._ortho_height, self._size)

    def _per_unit(self, z, f):
        return scalar(np.full(z.shape, f, dtype=np.float64))

    def primary_rays(self, pose, *, dtype=np.float64, rows=None):
        """World rays through the pixel centres: origins ``a_j right + b_i up + eye`` on the
        plane through the eye (``a_j = (j + 0.5 - cx) ortho_height / H``, ``b_i`` likewise),
        every direction ``forward``."""
        xs, ys = self._centres(rows)
        x, y = xs - self._cx, self._cy - ys
        right, up, forward = (v.astype(dtype) for v in (pose.right, pose.up, pose.forward))
        s = self._ortho_height / self._size[1]
        a = (x * s).astype(dtype)[None, :, None]
        b = (y * s).astype(dtype)[:, None, None]
        origins = a * right + (b * up + pose.eye.astype(dtype))
        directions = np.broadcast_to(forward, origins.shape)
        return origins, directions

    def pixel_rays(self, pose, pixels):
        """World rays through pixel coordinates: from the plane through the eye, along forward."""
        origins = pose.view_to_world(self.unproject(as_array(pixels, "pixels", shape=(..., 2)), 0.0))
        directions = np.broadcast_to(pose.forward, origins.shape).copy()
        return origins, directions

    def cropped(self, left, top, size):
        raise ValueError("cropped() needs a perspective camera; Camera.from_intrinsics (the crop's "
                         "camera) has no orthographic form")

    def with_size(self, size) -> Orthographic:
        """The same view height at another size."""
        return Orthographic(self._ortho_height, size)

    def scaled(self, factor: float) -> Orthographic:
        """The view height of a world scaled by ``factor``."""
        return Orthographic(self._ortho_height * factor, self._size)


class Intrinsics(_Pinhole):
    """A general pinhole projection from its intrinsics, in pixels.

    ``x = cx + fx X / Z``, ``y = cy - fy Y / Z`` (see
    :meth:`vobscure.camera.Camera.from_intrinsics` for the parameters' meaning).

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels (> 0).
    cx, cy : float
        Principal point in pixels (finite, anywhere).
    size : (2,) int
        ``(width, height)`` in pixels.
    near, far : float, optional
        Clipping distances (> 0; ``far`` may be +inf), informational.

    Examples
    --------
    >>> lens = Intrinsics(100.0, 50.0, 10.0, 20.0, (64, 48))
    >>> lens.project([0.5, 0.2, 2.0])[0].tolist()
    [35.0, 15.0]
    """

    __slots__ = ()
    _param_names = ("fx", "fy", "cx", "cy", "size", "near", "far")

    def __init__(self, fx, fy, cx, cy, size, *, near=None, far=None):
        size = check_size(size)
        fx = check_positive(fx, "fx")
        fy = check_positive(fy, "fy")
        cx = float(as_array(cx, "cx", shape=()))
        cy = float(as_array(cy, "cy", shape=()))
        near = optional_positive(near, "near")
        far = optional_positive(far, "far", allow_inf=True)
        self._set(size, fx, fy, cx, cy, near, far)

    def _params(self):
        return (self._fx, self._fy, self._cx, self._cy, self._size, self._near, self._far)

    def with_size(self, size) -> Intrinsics:
        """The same view at another size: ``fx``, ``cx`` scaled by the ratio of widths, ``fy``,
        ``cy`` by the ratio of heights."""
        W2, H2 = check_size(size)
        W, H = self._size
        return Intrinsics(self._fx * W2 / W, self._fy * H2 / H, self._cx * W2 / W, self._cy * H2 / H, (W2, H2),
                          near=self._near, far=self._far)

    def scaled(self, factor: float) -> Intrinsics:
        """``near`` and ``far`` of a world scaled by ``factor``; the intrinsics kept."""
        return Intrinsics(self._fx, self._fy, self._cx, self._cy, self._size,
                          near=None if self._near is None else self._near * factor,
                          far=None if self._far is None else self._far * factor)

    def camera_record(self, pose) -> dict:
        return {"fx": self._fx, "fy": self._fy, "cx": self._cx, "cy": self._cy,
                "size": [int(self._size[0]), int(self._size[1])], "near": self._near, "far": self._far,
                "pose": None if pose is None else pose.to_dict()["pose"], "projection": "perspective"}

    def camera_repr(self, pose) -> str:
        matrix = None if pose is None else "(" + ", ".join(vector_repr(r) for r in pose.matrix) + ")"
        far = "float('inf')" if self._far == math.inf else repr(self._far)
        return (f"Camera.from_intrinsics({self._fx!r}, {self._fy!r}, {self._cx!r}, {self._cy!r}, "
                f"{self._size!r}, pose={matrix}, near={self._near!r}, far={far})")

    @classmethod
    def from_matrix(cls, matrix, size, *, convention="opengl") -> Intrinsics:
        """The intrinsics of a 4x4 perspective projection matrix and the viewport size.

        Reads ``fx``, ``fy``, ``cx``, ``cy``, ``near`` and ``far`` from the matrix of an
        off-centre frustum (``glFrustum`` / ``D3DXMatrixPerspectiveOffCenterLH``), with the
        viewport covering the whole image.

        Parameters
        ----------
        matrix : (4, 4) float
            The projection matrix as written mathematically, ``matrix[row, column]``.
        size : (2,) int
            Viewport ``(width, height)`` in pixels.
        convention : {"opengl", "directx"}
            ``"opengl"`` (default): column vectors, ``clip = P @ (x, y, z, 1)`` in an eye space
            looking down -z (eye z = -depth), NDC in [-1, 1]^3 with y up::

                P = [[2n/(r-l), 0,        (r+l)/(r-l),  0           ],
                     [0,        2n/(t-b), (t+b)/(t-b),  0           ],
                     [0,        0,        -(f+n)/(f-n), -2 f n/(f-n)],
                     [0,        0,        -1,           0           ]]

            (``glFrustum``). NumPy arrays read from OpenGL's column-major memory
            (``glGetFloatv``, glm) are the transpose of this. ``"directx"``: row vectors,
            ``clip = (x, y, z, 1) @ P`` in a left-handed eye space looking down +z (vobscure's
            view space), NDC x, y in [-1, 1] with y up and z in [0, 1]::

                P = [[2n/(r-l),    0,           0,         0],
                     [0,           2n/(t-b),    0,         0],
                     [(l+r)/(l-r), (t+b)/(b-t), f/(f-n),   1],
                     [0,           0,           n f/(n-f), 0]]

            (``D3DXMatrixPerspectiveOffCenterLH``).

        Returns
        -------
        Intrinsics
            With ``fx = P[0, 0] W/2``, ``fy = P[1, 1] H/2`` and, OpenGL,
            ``cx = (1 - P[0, 2]) W/2``, ``cy = (1 + P[1, 2]) H/2``, ``near = P[2, 3] / (P[2, 2] - 1)``,
            ``far = P[2, 3] / (P[2, 2] + 1)``; Direct3D, ``cx = (1 + P[2, 0]) W/2``,
            ``cy = (1 - P[2, 1]) H/2``, ``near = -P[3, 2] / P[2, 2]``,
            ``far = -P[3, 2] / (P[2, 2] - 1)`` (+inf for an infinite far plane).

        Raises
        ------
        ValueError
            If the matrix is not of the layout above (skew, an orthographic matrix, a
            transposed matrix, non-positive near or far), naming the offending entries.

        Notes
        -----
        The viewport maps NDC to pixels as OpenGL's and Direct3D 10+'s do,
        ``x = (x_ndc + 1) W/2`` and ``y = (1 - y_ndc) H/2`` (rows down, pixel centres at
        half-integers), so ``cx = W/2`` for a symmetric frustum. Direct3D 9's half-pixel
        offset is not modelled.

        References
        ----------
        .. [1] ``glFrustum`` (the matrix) and ``glViewport`` (window coordinates
           ``x_w = (x_nd + 1) width / 2 + x``, ``y_w = (y_nd + 1) height / 2 + y``, y up from
           the bottom), OpenGL 2.1 Reference Pages, Khronos Group (KhronosGroup/OpenGL-Refpages).
        .. [2] ``D3DXMatrixPerspectiveOffCenterLH`` (the matrix), D3DX 9 documentation,
           Microsoft; "Viewports and Clipping (Direct3D 9)" (the viewport, y down) and
           "Coordinate Systems (Direct3D 10)" (pixel centres at half-integers; Direct3D 9's
           are at integers, "Directly Mapping Texels to Pixels").

        Examples
        --------
        >>> P = np.array([[1.5, 0, 0.25, 0], [0, 2.0, 0, 0], [0, 0, -3, -4], [0, 0, -1, 0]])
        >>> Intrinsics.from_matrix(P, (40, 30))
        Intrinsics(fx=30.0, fy=30.0, cx=15.0, cy=15.0, size=(40, 30), near=1.0, far=2.0)
        """
        size = check_size(size)
        check_choice(convention, "convention", PROJECTION_CONVENTIONS)
        P = as_array(matrix, "matrix", shape=(4, 4))
        W, H = size
        tol = PROJECTION_ZERO_TOL * float(np.abs(P).max())
        if convention == "opengl":
            zeros = [(0, 1), (0, 3), (1, 0), (1, 3), (2, 0), (2, 1), (3, 0), (3, 1), (3, 3)]
            w_entry, w_value = (3, 2), -1.0
        else:
            zeros = [(0, 1), (0, 2), (0, 3), (1, 0), (1, 2), (1, 3), (3, 0), (3, 1), (3, 3)]
            w_entry, w_value = (2, 3), 1.0
        bad = [(i, j) for i, j in zeros if abs(P[i, j]) > tol]
        if bad or P[w_entry] != w_value:
            raise ValueError(f"matrix is not a {convention} perspective projection (layout in "
                             f"Camera.from_projection's docstring): entries {bad} must be 0 and entry "
                             f"{w_entry} must be {w_value}, got {P[w_entry]!r}; a transposed, skewed "
                             "or orthographic matrix is not supported")
        if not (P[0, 0] > 0 and P[1, 1] > 0):
            raise ValueError(f"matrix must have P[0, 0] > 0 and P[1, 1] > 0 (x right, y up), got "
                             f"{P[0, 0]!r} and {P[1, 1]!r}")
        fx, fy = P[0, 0] * W / 2.0, P[1, 1] * H / 2.0
        with np.errstate(divide="ignore"):
            if convention == "opengl":
                # NDC x = P00 X/Z - P02 (eye z = -Z) -> x = (x_ndc + 1) W/2
                cx, cy = (1.0 - P[0, 2]) * W / 2.0, (1.0 + P[1, 2]) * H / 2.0
                a, b = P[2, 2], P[2, 3]
                near = b / (a - 1.0)
                far = b / (a + 1.0) if a != -1.0 else math.inf
            else:
                # NDC x = P00 X/Z + P20 -> x = (x_ndc + 1) W/2
                cx, cy = (1.0 + P[2, 0]) * W / 2.0, (1.0 - P[2, 1]) * H / 2.0
                a, b = P[2, 2], P[3, 2]
                near = -b / a if a != 0 else math.nan
                far = -b / (a - 1.0) if a != 1.0 else math.inf
        near, far = float(near), float(far)
        if not (near > 0 and far > 0 and np.isfinite(near) and near != far):
            raise ValueError(f"matrix gives near={near!r} and far={far!r}: both must be > 0 and "
                             f"distinct (entries P[2, 2], P[{'2, 3' if convention == 'opengl' else '3, 2'}])")
        return cls(fx, fy, cx, cy, size, near=near, far=far)


_KINDS = {"Perspective": Perspective, "Orthographic": Orthographic, "Intrinsics": Intrinsics}


def _rebuild(kind: str, params: tuple) -> Projection:
    """Module-level constructor used by pickling."""
    if kind == "Intrinsics":
        *lens, near, far = params
        return Intrinsics(*lens, near=near, far=far)
    return _KINDS[kind](*params)
