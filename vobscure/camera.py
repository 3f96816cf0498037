"""The camera: world <-> view transforms and perspective / orthographic projection.

Spaces and pixels (the conventions of the whole library):

* **World space** is right-handed with y up.
* **View space** has the camera at the origin, x to the right, y up and z the depth,
  *positive in front of the camera*. The world -> view rotation therefore has the rows
  (right, up, forward) and determinant -1 (view space is left-handed); this is intended.
  A surface normal that faces the camera has ``n_z < 0`` in view space.
* **Images** are arrays ``(H, W[, C])`` whose row 0 is the top. Pixel ``(i, j)`` (row i,
  column j) has its centre at the continuous pixel coordinate ``(x, y) = (j + 0.5, i + 0.5)``:
  x grows to the right along the columns, y grows *down* along the rows. A camera's ``size``
  is ``(width, height) = (W, H)``.

Projection maps a view-space point ``(X, Y, Z)`` to the pixel coordinate ``(x, y)`` and the
depth ``Z`` (linear depth, not the distance along the ray):

* perspective: ``x = W/2 + f X / Z``, ``y = H/2 - f Y / Z`` with the focal length
  ``f = (H/2) / tan(fov_y / 2)`` in pixels;
* orthographic: ``x = W/2 + s X``, ``y = H/2 - s Y`` with ``s = H / ortho_height`` pixels per
  world unit.

Every method here is the one place of the library where these formulas live; estimators
and the G-buffer renderer call them rather than repeating them.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping

import numpy as np

from ._validate import as_array, check_choice, check_positive

__all__ = ["Camera", "check_size"]

#: Default vertical field of view in degrees when neither ``fov_y`` nor ``ortho_height`` is given.
DEFAULT_FOV_Y = 45.0

# eye and target closer than this, relative to their magnitude, give no view direction.
_EYE_TARGET_RTOL = 1e-10
# |forward x unit(up)| below this: up is (nearly) parallel to the view direction.
_UP_PARALLEL_TOL = 1e-6

_PROJECTIONS = ("perspective", "orthographic")
_DICT_KEYS = ("eye", "target", "up", "size", "fov_y", "ortho_height", "projection")


def _vector3(value, name: str) -> np.ndarray:
    arr = as_array(value, name, shape=(3,))
    return arr


def check_size(size) -> tuple[int, int]:
    """An image size as a pair ``(width, height)`` of positive ints, or a ValueError naming
    ``size``.

    Examples
    --------
    >>> check_size([640, 480])
    (640, 480)
    """
    if isinstance(size, (str, bytes)) or not hasattr(size, "__len__"):
        raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
    if isinstance(size, np.ndarray) and size.ndim != 1:
        raise ValueError(f"size must be a pair (width, height) of positive ints, got shape {size.shape}")
    if len(size) != 2:
        raise ValueError(f"size must be a pair (width, height) of positive ints, got {len(size)} value(s): {size!r}")
    out = []
    for v in size:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral):
            raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
        if v < 1:
            raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
        out.append(int(v))
    return out[0], out[1]


def _check_fov(fov_y) -> float:
    v = check_positive(fov_y, "fov_y")
    if not v < 180.0:
        raise ValueError(f"fov_y must be in the open interval (0, 180) degrees, got {fov_y!r}")
    return v


def _scalar(arr: np.ndarray):
    """0-d arrays become NumPy scalars, like the result of a ufunc; others pass through."""
    return arr[()] if arr.ndim == 0 else arr


class Camera:
    """An immutable pinhole (perspective) or orthographic camera.

    Build one with :meth:`look_at`; calling ``Camera(...)`` takes the same arguments.

    Parameters
    ----------
    eye : (3,) float
        Camera position in world space.
    target : (3,) float
        A world point the camera looks at; ``forward`` points from ``eye`` to it.
    up : (3,) float, optional
        Up hint; the camera's true ``up`` is the part of it perpendicular to ``forward``.
        Must not be (nearly) parallel to ``target - eye``. Default ``(0, 1, 0)``.
    size : (2,) int
        Image ``(width, height)`` in pixels, keyword-only.
    fov_y : float, optional
        Vertical field of view in degrees, in the open interval (0, 180): a perspective
        camera. Keyword-only.
    ortho_height : float, optional
        World-space height of the view, > 0: an orthographic camera. Keyword-only.
        Give at most one of ``fov_y`` and ``ortho_height``; with neither, the camera is
        perspective with ``fov_y = 45``.

    Attributes
    ----------
    eye, target : (3,) float64
    up_hint : (3,) float64
        The ``up`` argument as given (kept so that :meth:`to_dict` round-trips).
    forward : (3,) float64
        Unit view direction, ``normalize(target - eye)``.
    right : (3,) float64
        Unit, ``normalize(cross(forward, up_hint))``.
    up : (3,) float64
        Unit true up, ``cross(right, forward)``.
    rotation : (3, 3) float64
        World -> view rotation, rows ``(right, up, forward)``; determinant -1.
    size : tuple of int
        ``(width, height)``.
    width, height : int
    projection : {"perspective", "orthographic"}
    fov_y : float or None
        Degrees; None for an orthographic camera.
    ortho_height : float or None
        None for a perspective camera.
    focal_length_px : float or None
        Perspective focal length in pixels, ``(H/2) / tan(fov_y/2)`` (pixels per world
        unit at depth 1); None for an orthographic camera.

    Raises
    ------
    ValueError
        For any bad argument; the message names it.

    Notes
    -----
    View space: camera at the origin, x right, y up, z = depth > 0 in front of the camera.
    Pixel ``(i, j)`` has its centre at ``(x, y) = (j + 0.5, i + 0.5)``, y pointing down.
    All arrays held by a camera are read-only; cameras compare equal when their
    :meth:`to_dict` records are equal, and are hashable.

    Examples
    --------
    >>> from vobscure.camera import Camera
    >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(64, 48), fov_y=60)
    >>> cam.projection, cam.size
    ('perspective', (64, 48))
    >>> pixels, depth = cam.project(cam.world_to_view([[0, 0, 0], [0, 1, 0]]))
    >>> pixels.round(3).tolist(), depth.tolist()
    ([[32.0, 24.0], [32.0, 15.686]], [5.0, 5.0])
    """

    __slots__ = ("_eye", "_target", "_up_hint", "_forward", "_right", "_up", "_rotation",
                 "_size", "_fov_y", "_ortho_height", "_focal", "_scale", "_frozen")

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), *, size, fov_y=None, ortho_height=None):
        eye = _vector3(eye, "eye")
        target = _vector3(target, "target")
        up_hint = _vector3(up, "up")
        size = check_size(size)
        if fov_y is not None and ortho_height is not None:
            raise ValueError("give fov_y (perspective) or ortho_height (orthographic), not both; "
                             f"got fov_y={fov_y!r} and ortho_height={ortho_height!r}")
        if ortho_height is not None:
            ortho_height = check_positive(ortho_height, "ortho_height")
        else:
            fov_y = _check_fov(DEFAULT_FOV_Y if fov_y is None else fov_y)

        delta = target - eye
        dist = float(np.linalg.norm(delta))
        scale = max(float(np.linalg.norm(eye)), float(np.linalg.norm(target)))
        if not dist > _EYE_TARGET_RTOL * scale or not np.isfinite(dist):
            raise ValueError(f"eye and target must be distinct points, got eye={eye.tolist()} "
                             f"and target={target.tolist()}")
        forward = delta / dist
        up_len = float(np.linalg.norm(up_hint))
        if not up_len > 0.0 or not np.isfinite(up_len):
            raise ValueError(f"up must be a non-zero finite vector, got {up_hint.tolist()}")
        side = np.cross(forward, up_hint / up_len)
        side_len = float(np.linalg.norm(side))
        if side_len < _UP_PARALLEL_TOL:
            raise ValueError(f"up {up_hint.tolist()} is (nearly) parallel to the view direction "
                             f"{forward.tolist()}; choose an up vector across it")
        right = side / side_len
        true_up = np.cross(right, forward)
        true_up /= np.linalg.norm(true_up)
        # "+ 0.0" turns the -0.0 components a cross product can produce into +0.0
        forward, right, true_up = forward + 0.0, right + 0.0, true_up + 0.0
        rotation = np.stack([right, true_up, forward])

        for arr in (eye, target, up_hint, forward, right, true_up, rotation):
            arr.setflags(write=False)
        W, H = size
        set_ = object.__setattr__
        set_(self, "_eye", eye)
        set_(self, "_target", target)
        set_(self, "_up_hint", up_hint)
        set_(self, "_forward", forward)
        set_(self, "_right", right)
        set_(self, "_up", true_up)
        set_(self, "_rotation", rotation)
        set_(self, "_size", size)
        set_(self, "_fov_y", None if fov_y is None else float(fov_y))
        set_(self, "_ortho_height", None if ortho_height is None else float(ortho_height))
        if fov_y is not None:
            focal = (H / 2.0) / math.tan(math.radians(fov_y) / 2.0)
            set_(self, "_focal", focal)
            set_(self, "_scale", None)
        else:
            set_(self, "_focal", None)
            set_(self, "_scale", H / ortho_height)
        set_(self, "_frozen", True)

    @classmethod
    def look_at(cls, eye, target, up=(0.0, 1.0, 0.0), *, size, fov_y=None, ortho_height=None) -> Camera:
        """A camera at ``eye`` looking at ``target``.

        Parameters
        ----------
        eye, target : (3,) float
            World-space camera position and look-at point; they must differ.
        up : (3,) float, optional
            Up hint, not (nearly) parallel to ``target - eye``. Default ``(0, 1, 0)``.
        size : (2,) int
            ``(width, height)`` in pixels.
        fov_y : float, optional
            Vertical field of view in degrees, in (0, 180): perspective.
        ortho_height : float, optional
            World-space view height > 0: orthographic. With neither given, perspective
            with ``fov_y = 45``; giving both is an error.

        Returns
        -------
        Camera

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(32, 16), ortho_height=2.0)
        >>> cam.projection, float(cam.pixels_per_unit(5.0))
        ('orthographic', 8.0)
        >>> cam.forward.tolist(), cam.right.tolist()
        ([0.0, 0.0, -1.0], [1.0, 0.0, 0.0])
        """
        return cls(eye, target, up, size=size, fov_y=fov_y, ortho_height=ortho_height)

    # ------------------------------------------------------------------ immutability
    def __setattr__(self, name, value):
        raise AttributeError(f"Camera is immutable; cannot set {name!r}")

    def __delattr__(self, name):
        raise AttributeError(f"Camera is immutable; cannot delete {name!r}")

    def __reduce__(self):
        return (_camera_from_dict, (self.to_dict(),))

    def _key(self):
        d = self.to_dict()
        return tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in d.items())

    def __eq__(self, other):
        if not isinstance(other, Camera):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self) -> str:
        def vec(a):
            return "(" + ", ".join(repr(float(x)) for x in a) + ")"

        lens = (f"fov_y={self._fov_y!r}" if self._fov_y is not None
                else f"ortho_height={self._ortho_height!r}")
        return (f"Camera.look_at(eye={vec(self._eye)}, target={vec(self._target)}, "
                f"up={vec(self._up_hint)}, size={self._size!r}, {lens})")

    # ------------------------------------------------------------------ properties
    @property
    def eye(self) -> np.ndarray:
        return self._eye

    @property
    def target(self) -> np.ndarray:
        return self._target

    @property
    def up_hint(self) -> np.ndarray:
        return self._up_hint

    @property
    def forward(self) -> np.ndarray:
        return self._forward

    @property
    def right(self) -> np.ndarray:
        return self._right

    @property
    def up(self) -> np.ndarray:
        return self._up

    @property
    def rotation(self) -> np.ndarray:
        return self._rotation

    @property
    def size(self) -> tuple[int, int]:
        return self._size

    @property
    def width(self) -> int:
        return self._size[0]

    @property
    def height(self) -> int:
        return self._size[1]

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``: the shape of the images this camera renders."""
        return self._size[1], self._size[0]

    @property
    def projection(self) -> str:
        return "perspective" if self._fov_y is not None else "orthographic"

    @property
    def is_perspective(self) -> bool:
        return self._fov_y is not None

    @property
    def fov_y(self) -> float | None:
        return self._fov_y

    @property
    def ortho_height(self) -> float | None:
        return self._ortho_height

    @property
    def focal_length_px(self) -> float | None:
        return self._focal

    # ------------------------------------------------------------------ transforms
    def world_to_view(self, points) -> np.ndarray:
        """World-space points to view space.

        Parameters
        ----------
        points : (..., 3) float

        Returns
        -------
        (..., 3) float64
            ``rotation @ (p - eye)`` for each point. Non-finite entries propagate.
        """
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return (p - self._eye) @ self._rotation.T

    def view_to_world(self, points) -> np.ndarray:
        """View-space points to world space, the inverse of :meth:`world_to_view`.

        Parameters
        ----------
        points : (..., 3) float

        Returns
        -------
        (..., 3) float64
        """
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return p @ self._rotation + self._eye

    def world_to_view_dir(self, vectors) -> np.ndarray:
        """World-space directions or normals to view space (rotation only).

        Parameters
        ----------
        vectors : (..., 3) float

        Returns
        -------
        (..., 3) float64
            Lengths are preserved; a normal facing the camera gets ``n_z < 0``.
        """
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ self._rotation.T

    def view_to_world_dir(self, vectors) -> np.ndarray:
        """View-space directions or normals to world space (rotation only).

        Parameters
        ----------
        vectors : (..., 3) float

        Returns
        -------
        (..., 3) float64
        """
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ self._rotation

    # ------------------------------------------------------------------ projection
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
        Perspective ``x = W/2 + f X/Z``, ``y = H/2 - f Y/Z``; orthographic
        ``x = W/2 + s X``, ``y = H/2 - s Y`` with ``s = H / ortho_height``. Non-finite
        inputs give non-finite outputs without warnings.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> pixels, depth = cam.project([[1.0, 1.0, 5.0], [0.0, 0.0, -1.0]])
        >>> pixels.round(6).tolist(), depth.tolist()
        ([[11.0, 4.0], [nan, nan]], [5.0, -1.0])
        """
        p = as_array(view_points, "view_points", shape=(..., 3), finite=False)
        X, Y, Z = p[..., 0], p[..., 1], p[..., 2]
        W, H = self._size
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if self._focal is not None:
                in_front = Z > 0
                k = np.where(in_front, self._focal / np.where(in_front, Z, 1.0), np.nan)
                x = W / 2.0 + k * X
                y = H / 2.0 - k * Y
            else:
                x = W / 2.0 + self._scale * X
                y = H / 2.0 - self._scale * Y
        pixels = np.stack([x, y], axis=-1)
        return pixels, _scalar(np.array(Z, dtype=np.float64))

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
            View-space points, shape ``broadcast(pixels[..., 0], depth) + (3,)``.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> cam.unproject([11.0, 4.0], 5.0).round(6).tolist()
        [1.0, 1.0, 5.0]
        """
        px = as_array(pixels, "pixels", shape=(..., 2), finite=False)
        z = as_array(depth, "depth", finite=False)
        try:
            shape = np.broadcast_shapes(px.shape[:-1], z.shape)
        except ValueError:
            raise ValueError(f"depth of shape {z.shape} does not broadcast with pixels[..., 0] "
                             f"of shape {px.shape[:-1]}") from None
        W, H = self._size
        u = px[..., 0] - W / 2.0
        v = H / 2.0 - px[..., 1]
        with np.errstate(invalid="ignore", over="ignore"):
            if self._focal is not None:
                X = u * z / self._focal
                Y = v * z / self._focal
            else:
                X = u / self._scale
                Y = v / self._scale
        out = np.empty(shape + (3,), dtype=np.float64)
        out[..., 0] = X
        out[..., 1] = Y
        out[..., 2] = z
        return out

    def pixels_per_unit(self, depth):
        """How many pixels a world length at view depth ``depth`` spans on screen.

        For a segment perpendicular to the view direction; this sizes screen-space
        sample disks.

        Parameters
        ----------
        depth : (...) float
            View-space z.

        Returns
        -------
        (...) float64
            Perspective ``f / depth`` (NaN where ``depth <= 0``, 0 at +inf); orthographic
            ``H / ortho_height`` everywhere. A NumPy scalar for a scalar ``depth``.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> cam.pixels_per_unit([1.0, 5.0]).round(6).tolist()
        [5.0, 1.0]
        """
        z = as_array(depth, "depth", finite=False)
        if self._focal is None:
            return _scalar(np.full(z.shape, self._scale, dtype=np.float64))
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(z > 0, self._focal / np.where(z > 0, z, 1.0), np.nan)
        return _scalar(np.asarray(out, dtype=np.float64))

    def pixel_centers(self) -> np.ndarray:
        """Continuous coordinates of every pixel centre.

        Returns
        -------
        (H, W, 2) float64
            ``[i, j] = (j + 0.5, i + 0.5)``.
        """
        W, H = self._size
        out = np.empty((H, W, 2), dtype=np.float64)
        out[..., 0] = np.arange(W, dtype=np.float64)[None, :] + 0.5
        out[..., 1] = np.arange(H, dtype=np.float64)[:, None] + 0.5
        return out

    def pixel_rays(self, pixels) -> tuple[np.ndarray, np.ndarray]:
        """World-space rays through continuous pixel coordinates.

        Parameters
        ----------
        pixels : (..., 2) float

        Returns
        -------
        origins : (..., 3) float64
            Perspective: ``eye``. Orthographic: the point of the plane through ``eye``
            perpendicular to ``forward`` that projects to the pixel.
        directions : (..., 3) float64
            Unit; ``forward`` for every ray of an orthographic camera.
        """
        px = as_array(pixels, "pixels", shape=(..., 2))
        if self._focal is not None:
            d_view = self.unproject(px, 1.0)
            d_view /= np.linalg.norm(d_view, axis=-1, keepdims=True)
            directions = self.view_to_world_dir(d_view)
            directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
            origins = np.broadcast_to(self._eye, directions.shape).copy()
        else:
            origins = self.view_to_world(self.unproject(px, 0.0))
            directions = np.broadcast_to(self._forward, origins.shape).copy()
        return origins, directions

    def primary_rays(self, *, dtype=np.float64, rows: slice | None = None) -> tuple[np.ndarray, np.ndarray]:
        """World-space rays through every pixel centre.

        Parameters
        ----------
        dtype : numpy float dtype
            float64 (default) or float32 (what Embree consumes; the G-buffer asks for it).
        rows : slice, optional
            Only these image rows (the G-buffer makes bands of rows in parallel).

        Returns
        -------
        origins : (H, W, 3)  (or (rows, W, 3))
            ``eye`` for a perspective camera (a read-only broadcast view); points on the
            plane through ``eye`` perpendicular to ``forward`` for an orthographic one.
        directions : (H, W, 3)
            Unit directions; all ``forward`` for an orthographic camera.

        Notes
        -----
        The same rays as ``pixel_rays(pixel_centers())``, computed separably: a pixel's
        direction is ``a_j right + b_i up + forward`` with ``a_j`` depending on the column
        only and ``b_i`` on the row only, which is several times faster at image sizes.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(3, 3), fov_y=90)
        >>> origins, directions = cam.primary_rays()
        >>> directions.shape, directions[1, 1].round(6).tolist()
        ((3, 3, 3), [0.0, 0.0, -1.0])
        """
        W, H = self._size
        x = np.arange(W, dtype=np.float64) + 0.5 - W / 2.0
        y = H / 2.0 - (np.arange(H, dtype=np.float64)[rows if rows is not None else slice(None)] + 0.5)
        right, up, forward = (v.astype(dtype) for v in (self._right, self._up, self._forward))
        if self._focal is not None:
            a = (x / self._focal).astype(dtype)[None, :, None]
            b = (y / self._focal).astype(dtype)[:, None, None]
            directions = a * right + (b * up + forward)
            directions *= (1.0 / np.sqrt(a * a + b * b + 1.0)).astype(dtype)
            origins = np.broadcast_to(self._eye.astype(dtype), directions.shape)
        else:
            s = self._ortho_height / H
            a = (x * s).astype(dtype)[None, :, None]
            b = (y * s).astype(dtype)[:, None, None]
            origins = a * right + (b * up + self._eye.astype(dtype))
            directions = np.broadcast_to(forward, origins.shape)
        return origins, directions

    # ------------------------------------------------------------------ derived cameras
    def scaled(self, factor) -> Camera:
        """The same view of a scene scaled by ``factor`` about the world origin.

        ``eye``, ``target`` and ``ortho_height`` are multiplied by ``factor``; ``up``,
        ``size`` and ``fov_y`` are kept, so a scene scaled by the same factor renders the
        same image.

        Parameters
        ----------
        factor : float
            > 0 and finite.

        Returns
        -------
        Camera
        """
        f = check_positive(factor, "factor")
        return Camera(self._eye * f, self._target * f, self._up_hint, size=self._size,
                      fov_y=self._fov_y,
                      ortho_height=None if self._ortho_height is None else self._ortho_height * f)

    def with_size(self, size) -> Camera:
        """The same view rendered at another ``size`` ``(width, height)``."""
        return Camera(self._eye, self._target, self._up_hint, size=size, fov_y=self._fov_y,
                      ortho_height=self._ortho_height)

    # ------------------------------------------------------------------ provenance
    def to_dict(self) -> dict:
        """A JSON-serializable record of the camera (for provenance), see :meth:`from_dict`.

        Returns
        -------
        dict
            Keys ``eye``, ``target``, ``up`` (lists of 3 floats; ``up`` is the hint as
            given), ``size`` (list ``[W, H]``), ``fov_y``, ``ortho_height`` (float or
            None) and ``projection``.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(4, 3))
        >>> cam.to_dict()["fov_y"], Camera.from_dict(cam.to_dict()) == cam
        (45.0, True)
        """
        return {
            "eye": [float(x) for x in self._eye],
            "target": [float(x) for x in self._target],
            "up": [float(x) for x in self._up_hint],
            "size": [int(self._size[0]), int(self._size[1])],
            "fov_y": self._fov_y,
            "ortho_height": self._ortho_height,
            "projection": self.projection,
        }

    @classmethod
    def from_dict(cls, d) -> Camera:
        """The camera recorded by :meth:`to_dict`.

        Parameters
        ----------
        d : mapping
            Keys ``eye``, ``target``, ``size`` (required), ``up``, ``fov_y``,
            ``ortho_height``, ``projection`` (optional; ``projection``, when present, must
            agree with the lens parameters). Other keys are rejected.

        Returns
        -------
        Camera
        """
        if not isinstance(d, Mapping):
            raise ValueError(f"d must be a mapping (as returned by Camera.to_dict), got {type(d).__name__}")
        unknown = sorted(set(d) - set(_DICT_KEYS), key=str)
        if unknown:
            raise ValueError(f"d has unknown key(s) {unknown}; expected some of {list(_DICT_KEYS)}")
        for key in ("eye", "target", "size"):
            if key not in d:
                raise ValueError(f"d is missing the key {key!r}")
        cam = cls(d["eye"], d["target"], d.get("up", (0.0, 1.0, 0.0)), size=d["size"],
                  fov_y=d.get("fov_y"), ortho_height=d.get("ortho_height"))
        projection = d.get("projection")
        if projection is not None:
            check_choice(projection, "projection", _PROJECTIONS)
            if projection != cam.projection:
                raise ValueError(f"projection {projection!r} disagrees with fov_y={d.get('fov_y')!r} "
                                 f"and ortho_height={d.get('ortho_height')!r}")
        return cam


def _camera_from_dict(d: dict) -> Camera:
    """Module-level constructor used by pickling."""
    return Camera.from_dict(d)
