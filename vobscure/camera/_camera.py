"""The :class:`Camera`: a pose composed with a projection of an image size."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._validate import check_choice, check_int, check_positive
from ._checks import DEFAULT_FOV_Y, check_size, freeze, vector3
from ._frozen import Frozen
from .pose import Pose
from .projection import Intrinsics, Orthographic, Perspective, Projection

__all__ = ["Camera"]

_PROJECTIONS = ("perspective", "orthographic")
_DICT_KEYS = ("eye", "target", "up", "size", "fov_y", "ortho_height", "projection")
#: Keys of the record of a camera built from intrinsics (:meth:`Camera.to_dict`).
_INTRINSICS_KEYS = ("fx", "fy", "cx", "cy", "size", "near", "far", "pose", "projection")


def _no_pose_error(what: str) -> ValueError:
    return ValueError(f"{what} needs the camera's pose (view -> world), but this camera has none: it "
                      "was built by Camera.from_intrinsics / from_projection without pose=. Pass "
                      "pose=<4x4 view-to-world matrix> for world-space queries; view-space ones "
                      "(project, unproject, pixels_per_unit) work without it")


class Camera(Frozen):
    """An immutable pinhole (perspective) or orthographic camera: a :class:`Pose` and a
    :class:`Projection` of an image ``size``.

    Build one with :meth:`look_at` (calling ``Camera(...)`` takes the same arguments),
    :meth:`from_intrinsics` (a general pinhole: focal lengths ``fx``, ``fy`` and principal
    point ``(cx, cy)`` in pixels, optional pose) or :meth:`from_projection` (a 4x4 OpenGL or
    Direct3D projection matrix).

    Parameters
    ----------
    eye, target, up, size, fov_y, ortho_height
        As :meth:`look_at`.

    Attributes
    ----------
    lens : Projection
        :class:`Perspective` (``look_at`` with ``fov_y``), :class:`Orthographic` (``look_at``
        with ``ortho_height``) or :class:`Intrinsics` (``from_intrinsics``,
        ``from_projection``, ``cropped``).
    extrinsics : Pose or None
        The pose (view -> world) as an object; None for a camera from intrinsics built
        without ``pose``.
    eye, target, up_hint, forward, right, up : (3,) float64
        The pose's (:class:`Pose`): ``forward = normalize(target - eye)``, ``right =
        normalize(forward x up_hint)``, ``up = right x forward``; ``up_hint`` is the ``up``
        argument as given (so that :meth:`to_dict` round-trips). From a pose matrix:
        ``target = eye + forward``, ``up_hint = up``.
    rotation, pose : (3, 3) and (4, 4) float64
        World -> view rotation, rows ``(right, up, forward)``, determinant -1; view -> world
        matrix, columns ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``.
    has_pose : bool
        False for a camera from intrinsics built without ``pose``: then every world-space
        query (the attributes above, ``world_to_view``, ``primary_rays``, ...) raises a
        ValueError saying so.
    size : tuple of int
        ``(width, height)``; ``width``, ``height`` and ``shape = (height, width)`` too.
    projection : {"perspective", "orthographic"}
        The lens's kind.
    fx, fy, cx, cy : float
        Perspective: focal lengths in pixels (pixels per world unit at depth 1);
        ``fx = fy = (H/2) / tan(fov_y/2)`` for :meth:`look_at`. Orthographic: pixels per world
        unit, ``H / ortho_height``. ``(cx, cy)``: the principal point, the pixel coordinate
        (x right, y down, from the top-left corner) where the view axis meets the image,
        ``(W/2, H/2)`` for :meth:`look_at`.
    near, far : float or None
        Clipping distances read by :meth:`from_projection` (``far`` may be +inf), or given
        to :meth:`from_intrinsics`; None otherwise. Informational: nothing is clipped.
    fov_y, ortho_height, focal_length_px : float or None
        ``fov_y`` in degrees (perspective ``look_at`` only), ``ortho_height`` (orthographic
        only), ``focal_length_px = fy`` (perspective only).

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

    __slots__ = ("_pose", "_lens")

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), *, size, fov_y=None, ortho_height=None):
        eye = vector3(eye, "eye")
        target = vector3(target, "target")
        up_hint = vector3(up, "up")
        size = check_size(size)
        if fov_y is not None and ortho_height is not None:
            raise ValueError("give fov_y (perspective) or ortho_height (orthographic), not both; "
                             f"got fov_y={fov_y!r} and ortho_height={ortho_height!r}")
        if ortho_height is not None:
            lens = Orthographic(ortho_height, size)
        else:
            lens = Perspective(DEFAULT_FOV_Y if fov_y is None else fov_y, size)
        self._compose(Pose.look_at(eye, target, up_hint), lens)

    def _compose(self, pose: Pose | None, lens: Projection) -> Camera:
        """Set the two slots (the one place that does); returns the camera."""
        self._set_slots(_pose=pose, _lens=lens)
        return self

    @classmethod
    def _of(cls, pose: Pose | None, lens: Projection) -> Camera:
        return object.__new__(cls)._compose(pose, lens)

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
            View -> world matrix, columns ``(right, up, forward, eye)`` over ``(0, 0, 0, 1)``,
            determinant -1 (view space is left-handed), as :class:`Pose` takes it. Default
            None: no pose; view-space methods work, world-space ones raise ValueError.
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
        lens = Intrinsics(fx, fy, cx, cy, size, near=near, far=far)
        return cls._of(None if pose is None else Pose(pose), lens)

    @classmethod
    def from_projection(cls, matrix, size, *, convention="opengl", pose=None) -> Camera:
        """A pinhole camera from a 4x4 perspective projection matrix and the viewport size.

        Reads ``fx``, ``fy``, ``cx``, ``cy``, ``near`` and ``far`` from the matrix of an
        off-centre frustum (``glFrustum`` / ``D3DXMatrixPerspectiveOffCenterLH``), with the
        viewport covering the whole image: :meth:`Intrinsics.from_matrix` gives the two
        matrix layouts, the formulas and the references.

        Parameters
        ----------
        matrix, size, convention
            As in :meth:`Intrinsics.from_matrix`.
        pose : (4, 4) float, optional
            View -> world matrix in vobscure's convention, as in :meth:`from_intrinsics`.

        Returns
        -------
        Camera
            Whose :attr:`lens` is an :class:`Intrinsics`.

        Raises
        ------
        ValueError
            If the matrix is not of either layout (skew, an orthographic matrix, a
            transposed matrix, non-positive near or far), naming the offending entries.

        Examples
        --------
        >>> import numpy as np
        >>> P = np.array([[1.5, 0, 0.25, 0], [0, 2.0, 0, 0], [0, 0, -3, -4], [0, 0, -1, 0]])
        >>> cam = Camera.from_projection(P, (40, 30))
        >>> cam.fx, cam.fy, cam.cx, cam.cy, cam.near, cam.far
        (30.0, 30.0, 15.0, 15.0, 1.0, 2.0)
        """
        lens = Intrinsics.from_matrix(matrix, size, convention=convention)
        return cls._of(None if pose is None else Pose(pose), lens)

    # ------------------------------------------------------------------ identity
    def __reduce__(self):
        return (_camera_from_dict, (self.to_dict(),))

    def _key(self):
        return tuple((k, freeze(v)) for k, v in self.to_dict().items())

    def __repr__(self) -> str:
        return self._lens.camera_repr(self._pose)

    # ------------------------------------------------------------------ parts
    lens = property(lambda self: self._lens, doc="The :class:`Projection` (:class:`Perspective`, "
                    ":class:`Orthographic` or :class:`Intrinsics`).")
    extrinsics = property(lambda self: self._pose, doc="The :class:`Pose` (view -> world), None without a pose.")

    def _need_pose(self, what: str) -> Pose:
        """The pose, or the ValueError that names ``Camera.<what>``."""
        if self._pose is None:
            raise _no_pose_error(f"Camera.{what}")
        return self._pose

    # ------------------------------------------------------------------ properties
    eye = property(lambda self: self._need_pose("eye").eye)
    target = property(lambda self: self._need_pose("target").target)
    up_hint = property(lambda self: self._need_pose("up_hint").up_hint)
    forward = property(lambda self: self._need_pose("forward").forward)
    right = property(lambda self: self._need_pose("right").right)
    up = property(lambda self: self._need_pose("up").up)
    rotation = property(lambda self: self._need_pose("rotation").rotation)
    pose = property(lambda self: self._need_pose("pose").matrix, doc="(4, 4) view -> world matrix.")
    has_pose = property(lambda self: self._pose is not None, doc="True when world-space queries are possible.")
    size = property(lambda self: self._lens.size)
    width = property(lambda self: self._lens.size[0])
    height = property(lambda self: self._lens.size[1])
    shape = property(lambda self: (self._lens.size[1], self._lens.size[0]), doc="``(height, width)``.")
    projection = property(lambda self: self._lens.name, doc='``"perspective"`` or ``"orthographic"``.')
    is_perspective = property(lambda self: self._lens.perspective)
    fov_y = property(lambda self: self._lens.fov_y)
    ortho_height = property(lambda self: self._lens.ortho_height)
    focal_length_px = property(lambda self: self._lens.focal_length_px)
    fx = property(lambda self: self._lens.fx, doc="Focal length along x in pixels (orthographic: per unit).")
    fy = property(lambda self: self._lens.fy, doc="Focal length along y in pixels (orthographic: per unit).")
    cx = property(lambda self: self._lens.cx, doc="Principal point's x in pixels from the left edge.")
    cy = property(lambda self: self._lens.cy, doc="Principal point's y in pixels from the top edge (y down).")
    near = property(lambda self: self._lens.near)
    far = property(lambda self: self._lens.far)
    is_centered_square = property(lambda self: self._lens.is_centered_square,
                                  doc="``fx == fy``, principal point at the centre (every ``look_at`` camera).")

    # ------------------------------------------------------------------ transforms
    def world_to_view(self, points) -> np.ndarray:
        """World-space points ``(..., 3)`` to view space, ``rotation @ (p - eye)`` (float64)."""
        return self._need_pose("eye").world_to_view(points)

    def view_to_world(self, points) -> np.ndarray:
        """View-space points ``(..., 3)`` to world space, the inverse of :meth:`world_to_view`."""
        return self._need_pose("eye").view_to_world(points)

    def world_to_view_dir(self, vectors) -> np.ndarray:
        """World-space directions or normals ``(..., 3)`` to view space (rotation only)."""
        return self._need_pose("rotation").world_to_view_dir(vectors)

    def view_to_world_dir(self, vectors) -> np.ndarray:
        """View-space directions or normals ``(..., 3)`` to world space (rotation only)."""
        return self._need_pose("rotation").view_to_world_dir(vectors)

    # ------------------------------------------------------------------ projection
    def project(self, view_points) -> tuple[np.ndarray, np.ndarray]:
        """View-space points to continuous pixel coordinates and depth.

        The formulas and conventions: :meth:`Projection.project` (of :attr:`lens`).

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> pixels, depth = cam.project([[1.0, 1.0, 5.0], [0.0, 0.0, -1.0]])
        >>> pixels.round(6).tolist(), depth.tolist()
        ([[11.0, 4.0], [nan, nan]], [5.0, -1.0])
        """
        return self._lens.project(view_points)

    def unproject(self, pixels, depth) -> np.ndarray:
        """Continuous pixel coordinates and depth to view-space points (inverse of project).

        The formulas and conventions: :meth:`Projection.unproject` (of :attr:`lens`).

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> cam.unproject([11.0, 4.0], 5.0).round(6).tolist()
        [1.0, 1.0, 5.0]
        """
        return self._lens.unproject(pixels, depth)

    def pixels_per_unit(self, depth):
        """How many pixels a world length at view depth ``depth`` spans vertically on screen.

        The formulas and conventions: :meth:`Projection.pixels_per_unit` (of :attr:`lens`).

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> cam.pixels_per_unit([1.0, 5.0]).round(6).tolist()
        [5.0, 1.0]
        """
        return self._lens.pixels_per_unit(depth)

    def pixels_per_unit_xy(self, depth) -> np.ndarray:
        """Pixels spanned by a world length at view depth ``depth``, along x and along y.

        The formulas and conventions: :meth:`Projection.pixels_per_unit_xy` (of :attr:`lens`).

        Examples
        --------
        >>> cam = Camera.from_intrinsics(40.0, 20.0, 10.0, 10.0, (20, 20))
        >>> cam.pixels_per_unit_xy(2.0).tolist()
        [20.0, 10.0]
        """
        return self._lens.pixels_per_unit_xy(depth)

    def pixel_centers(self) -> np.ndarray:
        """(H, W, 2) float64 continuous coordinates of every pixel centre, ``[i, j] = (j + 0.5, i + 0.5)``."""
        return self._lens.pixel_centers()

    def pixel_rays(self, pixels) -> tuple[np.ndarray, np.ndarray]:
        """World-space rays through continuous pixel coordinates (needs a pose).

        Returns
        -------
        origins : (..., 3) float64
            Perspective: ``eye``. Orthographic: the point of the plane through ``eye``
            perpendicular to ``forward`` that projects to the pixel.
        directions : (..., 3) float64
            Unit; ``forward`` for every ray of an orthographic camera.
        """
        return self._lens.pixel_rays(self._need_pose("eye"), pixels)

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
        origins, directions : (H, W, 3)  (or (rows, W, 3))
            As :meth:`pixel_rays`; perspective origins are a read-only broadcast view.

        Notes
        -----
        The same rays as ``pixel_rays(pixel_centers())``, computed separably (see the lens's
        ``primary_rays``), which is several times faster at image sizes.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(3, 3), fov_y=90)
        >>> origins, directions = cam.primary_rays()
        >>> directions.shape, directions[1, 1].round(6).tolist()
        ((3, 3, 3), [0.0, 0.0, -1.0])
        """
        return self._lens.primary_rays(self._need_pose("eye"), dtype=dtype, rows=rows)

    # ------------------------------------------------------------------ derived cameras
    def scaled(self, factor) -> Camera:
        """The same view of a scene scaled by ``factor`` about the world origin.

        ``eye``, ``target`` and ``ortho_height`` (``near``, ``far``) are multiplied by
        ``factor``; ``up``, ``size``, ``fov_y`` and the intrinsics are kept, so a scene
        scaled by the same factor renders the same image. ``factor``: > 0 and finite.
        """
        f = check_positive(factor, "factor")
        return Camera._of(None if self._pose is None else self._pose.scaled(f), self._lens.scaled(f))

    def with_size(self, size) -> Camera:
        """The same view rendered at another ``size`` ``(width, height)``.

        ``look_at`` cameras keep their field of view; cameras from intrinsics scale ``fx``
        and ``cx`` by the ratio of widths, ``fy`` and ``cy`` by the ratio of heights.
        """
        return Camera._of(self._pose, self._lens.with_size(size))

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
            ``from_intrinsics(fx, fy, cx - left, cy - top, size)``, this pose, near and far.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
        >>> crop = cam.cropped(4, 2, (8, 6))
        >>> crop.cx, crop.cy, bool(np.allclose(crop.project([1.0, 1.0, 5.0])[0], [7.0, 2.0]))
        (6.0, 3.0, True)
        """
        lens = self._lens.cropped(left, top, size)
        return Camera._of(None if self._pose is None else self._pose.as_matrix_pose(), lens)

    def widened(self, pixels) -> Camera:
        """This image widened by ``pixels`` (int >= 0) on each side: a guard band.

        Pixel ``(i, j)`` here is pixel ``(i + pixels, j + pixels)`` there, on the same ray.
        Perspective: :meth:`cropped` to ``(-pixels, -pixels, (W + 2 pixels, H + 2 pixels))``,
        bit for bit the same primary rays. Orthographic: the view height scaled by
        ``(H + 2 pixels) / H``; the rays agree to a few ulps of their offset from the eye.

        Examples
        --------
        >>> wide = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90).widened(3)
        >>> wide.size, wide.cx
        ((26, 16), 13.0)
        """
        p = check_int(pixels, "pixels", minimum=0)
        W, H = self.size
        if p == 0:
            return self
        if isinstance(self._lens, Orthographic):
            return Camera._of(self._pose, Orthographic(self.ortho_height * (H + 2 * p) / H, (W + 2 * p, H + 2 * p)))
        return self.cropped(-p, -p, (W + 2 * p, H + 2 * p))

    # ------------------------------------------------------------------ provenance
    def to_dict(self) -> dict:
        """A JSON-serializable record of the camera (for provenance), see :meth:`from_dict`.

        Returns
        -------
        dict
            :meth:`look_at` cameras: ``eye``, ``target``, ``up`` (the hint as given), ``size``
            (``[W, H]``), ``fov_y``, ``ortho_height`` (float or None), ``projection``. Cameras
            from intrinsics: ``fx``, ``fy``, ``cx``, ``cy``, ``size``, ``near``, ``far`` (float
            or None; ``far`` may be +inf), ``pose`` (4 x 4 lists, or None), ``projection``.

        Examples
        --------
        >>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(4, 3))
        >>> cam.to_dict()["fov_y"], Camera.from_dict(cam.to_dict()) == cam
        (45.0, True)
        """
        return self._lens.camera_record(self._pose)

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
        return _from_record(cls, d)


def _camera_from_dict(d: dict) -> Camera:
    """Module-level constructor used by pickling."""
    return Camera.from_dict(d)


def _from_record(cls, d) -> Camera:
    """The camera of a :meth:`Camera.to_dict` record (see :meth:`Camera.from_dict`)."""
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
