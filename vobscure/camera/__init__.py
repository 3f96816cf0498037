"""The camera: a pose (view -> world) and a projection (perspective, orthographic, intrinsics).

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

The parts, as pbrt-v4 and Mitsuba 3 split a camera:

* :class:`Pose` (:mod:`vobscure.camera.pose`): eye and view axes, world <-> view transforms;
* :class:`Projection` (:mod:`vobscure.camera.projection`): :class:`Perspective`,
  :class:`Orthographic` and :class:`Intrinsics`, each bound to an image size, with one
  interface (project, unproject, pixels per unit, rays, resizing, scaling, cropping);
* the kernel (:mod:`vobscure.camera.kernel`): :func:`project_xy`, :func:`unproject_xy`,
  :func:`ray_xy`, :func:`ray_to_xy`, :func:`shift_ray`, plain functions of arrays without
  checks: the one place where the formulas above are computed. The projections call them,
  and so do the screen-space estimators on their hot paths;
* :class:`Camera`: a pose (or none) and a projection, with the constructors
  :meth:`Camera.look_at`, :meth:`Camera.from_intrinsics`, :meth:`Camera.from_projection`;
  ``camera.extrinsics`` is its :class:`Pose`, ``camera.lens`` its :class:`Projection`.

Examples
--------
>>> cam = Camera.look_at((0, 0, 5), (0, 0, 0), size=(20, 10), fov_y=90)
>>> type(cam.lens).__name__, cam.extrinsics.eye.tolist()
('Perspective', [0.0, 0.0, 5.0])
>>> project_xy(1.0, 1.0, 5.0, cam.fx, cam.fy, cam.cx, cam.cy, cam.is_perspective)
(11.0, 4.0)
"""

from __future__ import annotations

from ._camera import Camera
from ._checks import DEFAULT_FOV_Y, check_size
from .kernel import project_xy, ray_to_xy, ray_xy, shift_ray, unproject_xy
from .pose import Pose
from .projection import PROJECTION_CONVENTIONS, Intrinsics, Orthographic, Perspective, Projection

__all__ = ["Camera", "Pose", "Projection", "Perspective", "Orthographic", "Intrinsics", "check_size",
           "PROJECTION_CONVENTIONS", "DEFAULT_FOV_Y", "project_xy", "unproject_xy", "ray_xy", "ray_to_xy",
           "shift_ray"]
