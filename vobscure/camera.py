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

* perspective (a general pinhole): ``x = c_x + f_x X / Z``, ``y = c_y - f_y Y / Z`` with the
  focal lengths ``f_x, f_y`` in pixels and the principal point ``(c_x, c_y)`` in the pixel
  coordinates above (from the top-left corner, y down). :meth:`Camera.look_at` gives
  ``f_x = f_y = f = (H/2) / tan(fov_y / 2)`` and ``(c_x, c_y) = (W/2, H/2)``;
  :meth:`Camera.from_intrinsics` and :meth:`Camera.from_projection` any values;
* orthographic (:meth:`Camera.look_at` only): ``x = W/2 + s X``, ``y = H/2 - s Y`` with
  ``s = H / ortho_height`` pixels per world unit.

Every method here is the one place of the library where these formulas live; estimators
and the G-buffer renderer call them rather than repeating them.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping

import numpy as np

from ._validate import as_array, check_choice, check_positive

__all__ = ["Camera", "check_size", "PROJECTION_CONVENTIONS"]

#: Default vertical field of view in degrees when neither ``fov_y`` nor ``ortho_height`` is given.
DEFAULT_FOV_Y = 45.0

# eye and target closer than this, relative to their magnitude, give no view direction.
_EYE_TARGET_RTOL = 1e-10
# |forward x unit(up)| below this: up is (nearly) parallel to the view direction.
_UP_PARALLEL_TOL = 1e-6

_PROJECTIONS = ("perspective", "orthographic")
_DICT_KEYS = ("eye", "target", "up", "size", "fov_y", "ortho_height", "projection")
#: Keys of the record of a camera built from intrinsics (:meth:`Camera.to_dict`).
_INTRINSICS_KEYS = ("fx", "fy", "cx", "cy", "size", "near", "far", "pose", "projection")
#: Projection-matrix conventions understood by :meth:`Camera.from_projection`.
PROJECTION_CONVENTIONS = ("opengl", "directx")
# A pose's 3x3 part may differ from an orthogonal matrix by this much (per entry of R^T R - I).
_POSE_ORTHO_TOL = 1e-6
# Entries of a projection matrix that must be zero may be this far from it (relative to the
# matrix's largest entry).
_PROJECTION_ZERO_TOL = 1e-9


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


def _no_pose_error(what: str) -> ValueError:
    return ValueError(f"{what} needs the camera's pose (view -> world), but this camera has none: it "
                      "was built by Camera.from_intrinsics / from_projection without pose=. Pass "
                      "pose=<4x4 view-to-world matrix> for world-space queries; view-space ones "
                      "(project, unproject, pixels_per_unit) work without it")


def _check_pose(pose) -> np.ndarray:
    """A (4, 4) float64 view -> world matrix whose 3x3 part is orthogonal with determinant -1."""
    m = as_array(pose, "pose", shape=(4, 4)).copy()
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"pose must be a rigid 4x4 view-to-world matrix with last row (0, 0, 0, 1), "
                         f"got last row {m[3].tolist()}")
    r = m[:3, :3]
    err = float(np.abs(r.T @ r - np.eye(3)).max())
    if err > _POSE_ORTHO_TOL:
        raise ValueError(f"pose's 3x3 part must be a rotation (orthonormal columns: view x, y, z axes in "
                         f"world space), but R^T R differs from I by {err:.3g}")
    det = float(np.linalg.det(r))
    if det > 0:
        raise ValueError("pose's 3x3 part has determinant +1, but vobscure's view space (x right, y up, "
                         "z = depth in front) is left-handed in a right-handed world: its columns are "
                         "(right, up, forward), determinant -1. An OpenGL camera-to-world matrix (camera "
                         "looking down -z) becomes one by negating its third column")
    m += 0.0
    m.setflags(write=False)
    return m


def _optional_positive(value, name: str, *, allow_inf: bool = False):
    if value is None:
        return None
    if allow_inf and isinstance(value, numbers.Real) and value == math.inf:
        return math.inf
    return check_positive(value, name)


def _freeze(v):
    """Lists (nested) to tuples, so a record can be hashed."""
    return tuple(_freeze(x) for x in v) if isinstance(v, (list, tuple)) else v


class Camera:
    """An immutable pinhole (perspective) or orthographic camera.

    Build one with :meth:`look_at` (calling ``Camera(...)`` takes the same arguments),
    :meth:`from_intrinsics` (a general pinhole: focal lengths ``fx``, ``fy`` and principal
    point ``(cx, cy)`` in pixels, optional pose) or :meth:`from_projection` (a 4x4 OpenGL or
    Direct3D projection matrix).

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
        For a camera from intrinsics with a pose: the pose's translation, and
        ``eye + forward``. World-space attributes raise ValueError on a camera without pose.
    up_hint : (3,) float64
        The ``up`` argument as given (kept so that :meth:`to_dict` round-trips); ``up`` for a
        camera from intrinsics.
    forward : (3,) float64
        Unit view direction, ``normalize(target - eye)``.
    right : (3,) float64
        Unit, ``normalize(cross(forward, up_hint))``.
    up : (3,) float64
        Unit true up, ``cross(right, forward)``.
    rotation : (3, 3) float64
        World -> view rotation, rows ``(right, up, forward)``; determinant -1.
    pose : (4, 4) float64
        View -> world matrix, columns ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``.
    has_pose : bool
        False for a camera from intrinsics built without ``pose``: then every world-space
        query (``eye``, ``rotation``, ``world_to_view``, ``primary_rays``, ...) raises a
        ValueError saying so.
    size : tuple of int
        ``(width, height)``.
    width, height : int
    projection : {"perspective", "orthographic"}
    fx, fy : float
        Perspective: focal lengths in pixels (pixels per world unit at depth 1) along x and
        y; ``fx = fy = (H/2) / tan(fov_y/2)`` for :meth:`look_at`. Orthographic: pixels per
        world unit, ``H / ortho_height`` for both.
    cx, cy : float
        Principal point: the pixel coordinate (x right, y down, from the image's top-left
        corner; pixel (i, j) centred at (j + 0.5, i + 0.5)) where the view axis meets the
        image. ``(W/2, H/2)`` for :meth:`look_at`.
    near, far : float or None
        Clipping distances read by :meth:`from_projection` (``far`` may be +inf), or given
        to :meth:`from_intrinsics`; None otherwise. Informational: nothing is clipped.
    fov_y : float or None
        Degrees; None for an orthographic camera and for cameras from intrinsics.
    ortho_height : float or None
        None for a perspective camera.
    focal_length_px : float or None
        Perspective vertical focal length ``fy`` in pixels (``(H/2) / tan(fov_y/2)`` for
        :meth:`look_at`); None for an orthographic camera.

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
                 "_size", "_fov_y", "_ortho_height", "_focal", "_scale", "_frozen",
                 "_kind", "_fx", "_fy", "_cx", "_cy", "_near", "_far", "_pose", "_perspective")

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

        W, H = size
        if fov_y is not None:
            focal = (H / 2.0) / math.tan(math.radians(fov_y) / 2.0)
            fx = fy = focal
            scale = None
        else:
            focal = None
            scale = H / ortho_height
            fx = fy = scale
        self._init(kind="look_at", size=size, perspective=fov_y is not None, fx=fx, fy=fy,
                   cx=W / 2.0, cy=H / 2.0, eye=eye, target=target, up_hint=up_hint, forward=forward,
                   right=right, up=true_up, rotation=rotation, fov_y=None if fov_y is None else float(fov_y),
                   ortho_height=None if ortho_height is None else float(ortho_height), focal=focal,
                   scale=scale, near=None, far=None)

    def _init(self, *, kind, size, perspective, fx, fy, cx, cy, eye=None, target=None, up_hint=None,
              forward=None, right=None, up=None, rotation=None, fov_y=None, ortho_height=None,
              focal=None, scale=None, near=None, far=None):
        """Set every slot (the one place that does) and freeze the camera."""
        pose = None
        if rotation is not None:
            pose = np.zeros((4, 4))
            pose[:3, :3] = rotation.T
            pose[:3, 3] = eye
            pose[3, 3] = 1.0
        for arr in (eye, target, up_hint, forward, right, up, rotation, pose):
            if arr is not None:
                arr.setflags(write=False)
        set_ = object.__setattr__
        for name, value in (("_kind", kind), ("_size", size), ("_perspective", perspective),
                            ("_fx", float(fx)), ("_fy", float(fy)), ("_cx", float(cx)), ("_cy", float(cy)),
                            ("_eye", eye), ("_target", target), ("_up_hint", up_hint),
                            ("_forward", forward), ("_right", right), ("_up", up), ("_rotation", rotation),
                            ("_pose", pose), ("_fov_y", fov_y), ("_ortho_height", ortho_height),
                            ("_focal", focal), ("_scale", scale), ("_near", near), ("_far", far),
                            ("_frozen", True)):
            set_(self, name, value)

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

    @classmethod
    def from_intrinsics(cls, fx, fy, cx, cy, size, *, pose=None, near=None, far=None) -> Camera:
        """A general pinhole camera from its intrinsics, in pixels.

        Projection: ``x = cx + fx X / Z``, ``y = cy - fy Y / Z`` for the view-space point
        ``(X, Y, Z)`` (x right, y up, z = depth in front) and the pixel coordinate ``(x, y)``
        (x right, y down, from the top-left corner of the image; pixel (i, j) is centred at
        ``(j + 0.5, i + 0.5)``).

        Parameters
        ----------
        fx, fy : float
            Focal lengths in pixels along x and y (> 0): ``fx = fy`` for square pixels.
        cx, cy : float
            Principal point in that pixel coordinate (finite; it may lie anywhere, also off
            the image, as after cropping). ``(W/2, H/2)`` is the image centre; an
            OpenCV-style ``K`` matrix whose pixel centres are integers gives
            ``cx = K[0, 2] + 0.5``, ``cy = K[1, 2] + 0.5``.
        size : (2,) int
            ``(width, height)`` in pixels.
        pose : (4, 4) float, optional
            View -> world matrix in vobscure's view convention: columns
            ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``, its 3x3 part orthogonal (to
            1e-6 per entry of R^T R - I; used as given, world -> view is its transpose) with
            determinant -1 (view space is left-handed). Default None: no pose; view-space
            methods work, world-space ones raise ValueError naming the missing pose.
        near, far : float, optional
            Clipping distances (> 0; ``far`` may be +inf), kept as attributes only.

        Returns
        -------
        Camera
            Perspective; ``fov_y`` is None.

        Raises
        ------
        ValueError
            For a bad argument (the message names it).

        Examples
        --------
        >>> cam = Camera.from_intrinsics(100.0, 50.0, 10.0, 20.0, (64, 48))
        >>> cam.project([0.5, 0.2, 2.0])[0].tolist()
        [35.0, 15.0]
        >>> cam.has_pose
        False
        """
        size = check_size(size)
        fx = check_positive(fx, "fx")
        fy = check_positive(fy, "fy")
        cx = float(as_array(cx, "cx", shape=()))
        cy = float(as_array(cy, "cy", shape=()))
        near = _optional_positive(near, "near")
        far = _optional_positive(far, "far", allow_inf=True)
        cam = object.__new__(cls)
        extra = {}
        if pose is not None:
            m = _check_pose(pose)
            rotation = np.ascontiguousarray(m[:3, :3].T)
            eye = m[:3, 3].copy()
            right, up, forward = (rotation[a].copy() for a in range(3))
            extra = dict(eye=eye, target=eye + forward, up_hint=up.copy(), forward=forward, right=right,
                         up=up, rotation=rotation)
        cam._init(kind="intrinsics", size=size, perspective=True, fx=fx, fy=fy, cx=cx, cy=cy,
                  near=near, far=far, **extra)
        return cam

    @classmethod
    def from_projection(cls, matrix, size, *, convention="opengl", pose=None) -> Camera:
        """A pinhole camera from a 4x4 perspective projection matrix and the viewport size.

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
        pose : (4, 4) float, optional
            View -> world matrix in vobscure's convention, as in :meth:`from_intrinsics`.

        Returns
        -------
        Camera
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
        >>> import numpy as np
        >>> P = np.array([[1.5, 0, 0.25, 0], [0, 2.0, 0, 0], [0, 0, -3, -4], [0, 0, -1, 0]])
        >>> cam = Camera.from_projection(P, (40, 30))
        >>> cam.fx, cam.fy, cam.cx, cam.cy, cam.near, cam.far
        (30.0, 30.0, 15.0, 15.0, 1.0, 2.0)
        """
        size = check_size(size)
        check_choice(convention, "convention", PROJECTION_CONVENTIONS)
        P = as_array(matrix, "matrix", shape=(4, 4))
        W, H = size
        tol = _PROJECTION_ZERO_TOL * float(np.abs(P).max())
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
        return cls.from_intrinsics(fx, fy, cx, cy, size, pose=pose, near=near, far=far)

    # ------------------------------------------------------------------ immutability
    def __setattr__(self, name, value):
        raise AttributeError(f"Camera is immutable; cannot set {name!r}")

    def __delattr__(self, name):
        raise AttributeError(f"Camera is immutable; cannot delete {name!r}")

    def __reduce__(self):
        return (_camera_from_dict, (self.to_dict(),))

    def _key(self):
        d = self.to_dict()
        return tuple((k, _freeze(v)) for k, v in d.items())

    def __eq__(self, other):
        if not isinstance(other, Camera):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self) -> str:
        def vec(a):
            return "(" + ", ".join(repr(float(x)) for x in a) + ")"

        if self._kind == "intrinsics":
            pose = None if self._pose is None else "(" + ", ".join(vec(r) for r in self._pose) + ")"
            far = "float('inf')" if self._far == math.inf else repr(self._far)
            return (f"Camera.from_intrinsics({self._fx!r}, {self._fy!r}, {self._cx!r}, {self._cy!r}, "
                    f"{self._size!r}, pose={pose}, near={self._near!r}, far={far})")
        lens = (f"fov_y={self._fov_y!r}" if self._fov_y is not None
                else f"ortho_height={self._ortho_height!r}")
        return (f"Camera.look_at(eye={vec(self._eye)}, target={vec(self._target)}, "
                f"up={vec(self._up_hint)}, size={self._size!r}, {lens})")

    # ------------------------------------------------------------------ properties
    def _world(self, name):
        value = getattr(self, name)
        if value is None:
            raise _no_pose_error(f"Camera.{name.lstrip('_')}")
        return value

    @property
    def eye(self) -> np.ndarray:
        return self._world("_eye")

    @property
    def target(self) -> np.ndarray:
        return self._world("_target")

    @property
    def up_hint(self) -> np.ndarray:
        return self._world("_up_hint")

    @property
    def forward(self) -> np.ndarray:
        return self._world("_forward")

    @property
    def right(self) -> np.ndarray:
        return self._world("_right")

    @property
    def up(self) -> np.ndarray:
        return self._world("_up")

    @property
    def rotation(self) -> np.ndarray:
        return self._world("_rotation")

    @property
    def pose(self) -> np.ndarray:
        """(4, 4) view -> world matrix, columns ``(right, up, forward, eye)``; ValueError
        without a pose (see :attr:`has_pose`)."""
        return self._world("_pose")

    @property
    def has_pose(self) -> bool:
        """True when world-space queries are possible (always, for :meth:`look_at` cameras)."""
        return self._pose is not None

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
        return "perspective" if self._perspective else "orthographic"

    @property
    def is_perspective(self) -> bool:
        return self._perspective

    @property
    def fov_y(self) -> float | None:
        return self._fov_y

    @property
    def ortho_height(self) -> float | None:
        return self._ortho_height

    @property
    def focal_length_px(self) -> float | None:
        return self._fy if self._perspective else None

    @property
    def fx(self) -> float:
        """Focal length along x in pixels (perspective), pixels per world unit (orthographic)."""
        return self._fx

    @property
    def fy(self) -> float:
        """Focal length along y in pixels (perspective), pixels per world unit (orthographic)."""
        return self._fy

    @property
    def cx(self) -> float:
        """Principal point's x in pixels from the image's left edge."""
        return self._cx

    @property
    def cy(self) -> float:
        """Principal point's y in pixels from the image's top edge (y down)."""
        return self._cy

    @property
    def near(self) -> float | None:
        return self._near

    @property
    def far(self) -> float | None:
        return self._far

    @property
    def is_centered_square(self) -> bool:
        """True when ``fx == fy`` and the principal point is the image centre (every
        :meth:`look_at` camera)."""
        W, H = self._size
        return self._fx == self._fy and self._cx == W / 2.0 and self._cy == H / 2.0

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
        eye, rotation = self._world("_eye"), self._world("_rotation")
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return (p - eye) @ rotation.T

    def view_to_world(self, points) -> np.ndarray:
        """View-space points to world space, the inverse of :meth:`world_to_view`.

        Parameters
        ----------
        points : (..., 3) float

        Returns
        -------
        (..., 3) float64
        """
        eye, rotation = self._world("_eye"), self._world("_rotation")
        p = as_array(points, "points", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return p @ rotation + eye

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
        rotation = self._world("_rotation")
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ rotation.T

    def view_to_world_dir(self, vectors) -> np.ndarray:
        """View-space directions or normals to world space (rotation only).

        Parameters
        ----------
        vectors : (..., 3) float

        Returns
        -------
        (..., 3) float64
        """
        rotation = self._world("_rotation")
        v = as_array(vectors, "vectors", shape=(..., 3), finite=False)
        with np.errstate(invalid="ignore", over="ignore"):
            return v @ rotation

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
        Perspective ``x = cx + fx X/Z``, ``y = cy - fy Y/Z`` (``look_at``: ``cx = W/2``,
        ``cy = H/2``, ``fx = fy = f``); orthographic ``x = W/2 + s X``, ``y = H/2 - s Y`` with
        ``s = H / ortho_height``. Non-finite inputs give non-finite outputs without warnings.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> pixels, depth = cam.project([[1.0, 1.0, 5.0], [0.0, 0.0, -1.0]])
        >>> pixels.round(6).tolist(), depth.tolist()
        ([[11.0, 4.0], [nan, nan]], [5.0, -1.0])
        """
        p = as_array(view_points, "view_points", shape=(..., 3), finite=False)
        X, Y, Z = p[..., 0], p[..., 1], p[..., 2]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if self._perspective:
                in_front = Z > 0
                Zs = np.where(in_front, Z, 1.0)
                kx = np.where(in_front, self._fx / Zs, np.nan)
                ky = kx if self._fy == self._fx else np.where(in_front, self._fy / Zs, np.nan)
                x = self._cx + kx * X
                y = self._cy - ky * Y
            else:
                x = self._cx + self._scale * X
                y = self._cy - self._scale * Y
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
            View-space points, shape ``broadcast(pixels[..., 0], depth) + (3,)``:
            perspective ``X = (x - cx) z / fx``, ``Y = (cy - y) z / fy``.

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
        u = px[..., 0] - self._cx
        v = self._cy - px[..., 1]
        with np.errstate(invalid="ignore", over="ignore"):
            if self._perspective:
                X = u * z / self._fx
                Y = v * z / self._fy
            else:
                X = u / self._scale
                Y = v / self._scale
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
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> cam.pixels_per_unit([1.0, 5.0]).round(6).tolist()
        [5.0, 1.0]
        """
        return self._per_unit(depth, self._fy)

    def pixels_per_unit_xy(self, depth) -> np.ndarray:
        """Pixels spanned by a world length at view depth ``depth``, along x and along y.

        Parameters
        ----------
        depth : (...) float
            View-space z.

        Returns
        -------
        (..., 2) float64
            ``(fx / depth, fy / depth)`` (perspective; NaN where ``depth <= 0``), or
            ``(s, s)`` with ``s = H / ortho_height`` (orthographic). A view-space offset
            ``(dx, dy)`` at depth z moves the projection by ``(fx dx / z, -fy dy / z)``
            pixels (rows grow down).

        Examples
        --------
        >>> cam = Camera.from_intrinsics(40.0, 20.0, 10.0, 10.0, (20, 20))
        >>> cam.pixels_per_unit_xy(2.0).tolist()
        [20.0, 10.0]
        """
        return np.stack([np.asarray(self._per_unit(depth, self._fx), dtype=np.float64),
                         np.asarray(self._per_unit(depth, self._fy), dtype=np.float64)], axis=-1)

    def _per_unit(self, depth, f):
        z = as_array(depth, "depth", finite=False)
        if not self._perspective:
            return _scalar(np.full(z.shape, self._scale, dtype=np.float64))
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(z > 0, f / np.where(z > 0, z, 1.0), np.nan)
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
        """World-space rays through continuous pixel coordinates (needs a pose).

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
        eye = self._world("_eye")
        px = as_array(pixels, "pixels", shape=(..., 2))
        if self._perspective:
            d_view = self.unproject(px, 1.0)
            d_view /= np.linalg.norm(d_view, axis=-1, keepdims=True)
            directions = self.view_to_world_dir(d_view)
            directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
            origins = np.broadcast_to(eye, directions.shape).copy()
        else:
            origins = self.view_to_world(self.unproject(px, 0.0))
            directions = np.broadcast_to(self._forward, origins.shape).copy()
        return origins, directions

    def primary_rays(self, *, dtype=np.float64, rows: slice | None = None) -> tuple[np.ndarray, np.ndarray]:
        """World-space rays through every pixel centre (needs a pose).

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
        direction is ``a_j right + b_i up + forward`` with ``a_j = (j + 0.5 - cx) / fx``
        depending on the column only and ``b_i = (cy - i - 0.5) / fy`` on the row only, which
        is several times faster at image sizes.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(3, 3), fov_y=90)
        >>> origins, directions = cam.primary_rays()
        >>> directions.shape, directions[1, 1].round(6).tolist()
        ((3, 3, 3), [0.0, 0.0, -1.0])
        """
        eye = self._world("_eye")
        W, H = self._size
        x = np.arange(W, dtype=np.float64) + 0.5 - self._cx
        y = self._cy - (np.arange(H, dtype=np.float64)[rows if rows is not None else slice(None)] + 0.5)
        right, up, forward = (v.astype(dtype) for v in (self._right, self._up, self._forward))
        if self._perspective:
            a = (x / self._fx).astype(dtype)[None, :, None]
            b = (y / self._fy).astype(dtype)[:, None, None]
            directions = a * right + (b * up + forward)
            directions *= (1.0 / np.sqrt(a * a + b * b + 1.0)).astype(dtype)
            origins = np.broadcast_to(eye.astype(dtype), directions.shape)
        else:
            s = self._ortho_height / H
            a = (x * s).astype(dtype)[None, :, None]
            b = (y * s).astype(dtype)[:, None, None]
            origins = a * right + (b * up + eye.astype(dtype))
            directions = np.broadcast_to(forward, origins.shape)
        return origins, directions

    # ------------------------------------------------------------------ derived cameras
    def scaled(self, factor) -> Camera:
        """The same view of a scene scaled by ``factor`` about the world origin.

        ``eye``, ``target`` and ``ortho_height`` (``near``, ``far``) are multiplied by
        ``factor``; ``up``, ``size``, ``fov_y`` and the intrinsics are kept, so a scene
        scaled by the same factor renders the same image.

        Parameters
        ----------
        factor : float
            > 0 and finite.

        Returns
        -------
        Camera
        """
        f = check_positive(factor, "factor")
        if self._kind == "intrinsics":
            pose = None
            if self._pose is not None:
                pose = self._pose.copy()
                pose[:3, 3] *= f
            return Camera.from_intrinsics(self._fx, self._fy, self._cx, self._cy, self._size, pose=pose,
                                          near=None if self._near is None else self._near * f,
                                          far=None if self._far is None else self._far * f)
        return Camera(self._eye * f, self._target * f, self._up_hint, size=self._size,
                      fov_y=self._fov_y,
                      ortho_height=None if self._ortho_height is None else self._ortho_height * f)

    def with_size(self, size) -> Camera:
        """The same view rendered at another ``size`` ``(width, height)``.

        ``look_at`` cameras keep their field of view; cameras from intrinsics scale ``fx``
        and ``cx`` by the ratio of widths, ``fy`` and ``cy`` by the ratio of heights.
        """
        if self._kind == "intrinsics":
            W2, H2 = check_size(size)
            W, H = self._size
            return Camera.from_intrinsics(self._fx * W2 / W, self._fy * H2 / H, self._cx * W2 / W,
                                          self._cy * H2 / H, (W2, H2), pose=self._pose, near=self._near,
                                          far=self._far)
        return Camera(self._eye, self._target, self._up_hint, size=size, fov_y=self._fov_y,
                      ortho_height=self._ortho_height)

    def cropped(self, left, top, size) -> Camera:
        """The camera of a crop of this camera's image (perspective only).

        Pixel ``(i, j)`` of the crop is pixel ``(i + top, j + left)`` of this image: the same
        view ray, so a G-buffer cropped from this camera's G-buffer belongs to the result.

        Parameters
        ----------
        left, top : int
            Offset of the crop's top-left pixel in this image (any ints; the crop may
            extend past the image).
        size : (2,) int
            The crop's ``(width, height)``.

        Returns
        -------
        Camera
            ``Camera.from_intrinsics(fx, fy, cx - left, cy - top, size)`` with this camera's
            pose (when it has one), near and far.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> crop = cam.cropped(4, 2, (8, 6))
        >>> crop.cx, crop.cy, bool(np.allclose(crop.project([1.0, 1.0, 5.0])[0], [7.0, 2.0]))
        (6.0, 3.0, True)
        """
        if not self._perspective:
            raise ValueError("cropped() needs a perspective camera; Camera.from_intrinsics (the crop's "
                             "camera) has no orthographic form")
        for value, name in ((left, "left"), (top, "top")):
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
                raise ValueError(f"{name} must be an int, got {value!r}")
        return Camera.from_intrinsics(self._fx, self._fy, self._cx - int(left), self._cy - int(top), size,
                                      pose=self._pose, near=self._near, far=self._far)

    # ------------------------------------------------------------------ provenance
    def to_dict(self) -> dict:
        """A JSON-serializable record of the camera (for provenance), see :meth:`from_dict`.

        Returns
        -------
        dict
            :meth:`look_at` cameras: keys ``eye``, ``target``, ``up`` (lists of 3 floats;
            ``up`` is the hint as given), ``size`` (list ``[W, H]``), ``fov_y``,
            ``ortho_height`` (float or None) and ``projection``. Cameras from intrinsics:
            ``fx``, ``fy``, ``cx``, ``cy`` (floats), ``size``, ``near``, ``far`` (float or
            None; ``far`` may be +inf), ``pose`` (4 lists of 4 floats, or None) and
            ``projection`` (``"perspective"``).

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(4, 3))
        >>> cam.to_dict()["fov_y"], Camera.from_dict(cam.to_dict()) == cam
        (45.0, True)
        """
        if self._kind == "intrinsics":
            return {
                "fx": self._fx, "fy": self._fy, "cx": self._cx, "cy": self._cy,
                "size": [int(self._size[0]), int(self._size[1])],
                "near": self._near, "far": self._far,
                "pose": None if self._pose is None else [[float(x) for x in row] for row in self._pose],
                "projection": "perspective",
            }
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
            A :meth:`look_at` record: keys ``eye``, ``target``, ``size`` (required), ``up``,
            ``fov_y``, ``ortho_height``, ``projection`` (optional; ``projection``, when
            present, must agree with the lens parameters). Or a record from intrinsics
            (recognized by its ``fx`` key): ``fx``, ``fy``, ``cx``, ``cy``, ``size``
            (required), ``near``, ``far``, ``pose``, ``projection`` (optional; must be
            ``"perspective"``). Other keys are rejected.

        Returns
        -------
        Camera
        """
        if not isinstance(d, Mapping):
            raise ValueError(f"d must be a mapping (as returned by Camera.to_dict), got {type(d).__name__}")
        if "fx" in d:
            unknown = sorted(set(d) - set(_INTRINSICS_KEYS), key=str)
            if unknown:
                raise ValueError(f"d has unknown key(s) {unknown}; a camera from intrinsics has some of "
                                 f"{list(_INTRINSICS_KEYS)}")
            for key in ("fx", "fy", "cx", "cy", "size"):
                if key not in d:
                    raise ValueError(f"d is missing the key {key!r}")
            projection = d.get("projection")
            if projection is not None:
                check_choice(projection, "projection", _PROJECTIONS)
                if projection != "perspective":
                    raise ValueError(f"projection {projection!r} disagrees with the intrinsics fx, fy, cx, cy "
                                     "(a perspective camera)")
            return cls.from_intrinsics(d["fx"], d["fy"], d["cx"], d["cy"], d["size"], pose=d.get("pose"),
                                       near=d.get("near"), far=d.get("far"))
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
