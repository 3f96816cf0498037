"""G-buffers: the per-pixel geometry of one view, what a rasterizer would write.

A :class:`GBuffer` is the only input of the screen-space estimators. It follows the
conventions of ``docs/conventions.md``: view space has the camera at the origin, x right,
y up and z the depth, positive in front of the camera; ``depth`` is that z (linear depth,
not the distance along the ray); background pixels have ``depth = +inf``, zero normals,
NaN positions and ``valid = False``.

A G-buffer comes from :func:`~vobscure.render.render_gbuffer` (Embree primary rays, in
:mod:`vobscure.render`) or from your own renderer's or depth sensor's images through
:meth:`GBuffer.from_arrays`, which converts the common depth and normal conventions (OpenGL,
Direct3D, reversed-Z, ray distance, packed normals, world-space normals) into the library's
(``docs/own-buffers.md``; the conversions are in :mod:`vobscure.convert`). The names of
:mod:`vobscure.convert` that ``from_arrays`` documents (its constants and warnings) can be
imported from here too (``render_gbuffer`` too, deprecated: it is :func:`vobscure.render_gbuffer`).
"""

from __future__ import annotations

import importlib
import warnings
from functools import cached_property

import numpy as np

from .convert import (CENTRAL_RATIO, CONVENTIONS, DEPTH_KINDS, NORMAL_BAND_ROWS, NORMAL_ENCODINGS,
                      NORMAL_LENGTH_TOL, NORMAL_SPACES, NORMAL_ZERO_TOL, VIEW_TOL,
                      NormalsRenormalizedWarning, NormalsRepairedWarning, convert_buffers,
                      normals_from_depth)

__all__ = ["GBuffer", "NormalsRenormalizedWarning", "NormalsRepairedWarning", "DEPTH_KINDS",
           "NORMAL_SPACES", "NORMAL_ENCODINGS", "CONVENTIONS", "NORMAL_LENGTH_TOL", "NORMAL_ZERO_TOL",
           "VIEW_TOL", "CENTRAL_RATIO", "NORMAL_BAND_ROWS"]


class GBuffer:
    """Per-pixel geometry of one view.

    Built by :func:`~vobscure.render.render_gbuffer`. The buffers below are read-only
    arrays. Only ``depth``, ``normal``, ``valid`` and ``primitive`` are made at render time;
    the other images are assembled from the per-hit data on first access and then kept, so a
    job that only needs the screen-space inputs never pays for world-space images (and the
    ground truth reads the per-hit data directly, see :attr:`hits`).

    The constructor stores what it is given after converting the dtypes; it does not check
    the conventions below, which :func:`~vobscure.render.render_gbuffer` guarantees.
    Construct one directly only to wrap buffers from elsewhere (e.g. a rasterizer) that keep
    them.

    Parameters
    ----------
    camera : Camera
        The camera the view was rendered with: it defines view space (x right, y up, z the
        depth, positive in front of the camera), the pixel grid (H = ``camera.height`` rows,
        W = ``camera.width`` columns, pixel (i, j) centred at (x, y) = (j + 0.5, i + 0.5)) and
        the projection (perspective or orthographic) that the screen-space estimators invert.
    depth : (H, W) array_like of float
        Linear view depth z of the surface seen through each pixel centre (view-space z, not
        the distance along the ray), > 0 in front of the camera; +inf on background.
        Converted to ``dtype``.
    normal : (H, W, 3) array_like of float
        View-space unit normal of that surface, flipped to face the camera, so n_z < 0 (it
        points back towards the eye, against +z; ``docs/conventions.md``); (0, 0, 0) on
        background. Converted to ``dtype``.
    valid : (H, W) array_like of bool
        True where a surface was hit (finite depth), False on background.
    primitive : (H, W) array_like of int
        Index of the hit triangle in ``scene.triangles``, -1 on background; stored as int64.
    hits : dict or callable or None
        The per-hit world-space data of :attr:`hits` (``index`` (k,) flat row-major indices
        of the valid pixels; (k, 3) float64 ``world_position``, ``world_normal``,
        ``world_geometric_normal``), or a function of no arguments returning that dict,
        called on first access. None (what :meth:`from_arrays` passes): derived from
        ``depth`` and ``normal`` through the camera's pose (or ``view_to_world``); the
        geometric normal is then the normal, and :attr:`position` is unprojected from the
        depth.
    dtype : numpy dtype, optional
        dtype of the float images, float64 (default) or float32 (see :meth:`astype`).
    view_to_world : tuple (R, t), optional
        Only with ``hits=None``: the world -> view rotation R (3, 3) and translation t (3,)
        (``p_view = R p_world + t``) to use instead of the camera's pose.
    conversion : dict, optional
        What :meth:`from_arrays` did (see there); None for rendered G-buffers.
    intervals : SolidIntervals, optional
        The solid intervals along the pixels' rays (:class:`vobscure.layers.SolidIntervals`,
        of the image's shape), for the estimators' ``thickness="layers"``; None: only the
        first surface is known. float32 intervals are kept as they are in a float64 G-buffer
        (the renderer makes them float32: ``docs/layers.md``, "Memory"); float64 intervals
        are rounded to a float32 G-buffer's dtype.
    guard : int, optional
        Width in pixels of the guard band around the image (0: none): the buffers cover the
        inner frame widened by ``guard`` pixels on each side (what
        ``render_gbuffer(..., guard=P)`` renders), so that taps near the inner frame's
        edge read real depth. The estimators and the ground truth return the inner frame.
    inner_camera : Camera, optional
        With ``guard`` > 0: the camera of the inner frame (``camera`` is the widened one).
    motion : (H, W, 2) array_like of float, optional
        A renderer's motion vectors: per pixel the offset (dx, dy) in pixels (x right, y down)
        from the pixel's centre to where its surface point was seen in the previous frame;
        NaN where unknown. Read by :func:`vobscure.temporal.reproject` instead of the motion
        it derives from the two cameras and the depth.

    Attributes
    ----------
    depth : (H, W) float
        Linear view depth z > 0; +inf on background.
    normal : (H, W, 3) float
        View-space unit shading normal facing the camera (interpolated from the scene's
        corner normals; the geometric normal where the interpolated one would face away);
        0 on background.
    geometric_normal : (H, W, 3) float
        View-space unit normal of the hit triangle, facing the camera; 0 on background.
    position : (H, W, 3) float
        View-space position; NaN on background.
    world_position, world_normal, world_geometric_normal : (H, W, 3) float
        The same in world space.
    valid : (H, W) bool
        True where a surface was hit.
    primitive : (H, W) int64
        Index of the hit triangle in ``scene.triangles``; -1 on background.
    camera : Camera
    dtype : numpy dtype
        float64, or float32 after :meth:`astype`.
    conversion : dict or None
        For a G-buffer made by :meth:`from_arrays`, what the conversion touched (counts of
        pixels); None for a rendered one.
    intervals : SolidIntervals or None
        The solid intervals, when known (see :meth:`with_intervals`).
    guard : int
        The guard band's width in pixels, 0 when there is none (see :meth:`inner`).
    motion : (H, W, 2) float or None
        The motion vectors, when given (see :meth:`with_motion`).
    """

    def __init__(self, camera, *, depth, normal, valid, primitive, hits, dtype=np.float64,
                 view_to_world=None, conversion=None, intervals=None, guard=0, inner_camera=None,
                 motion=None):
        if normal is None:
            raise ValueError("a GBuffer needs normals (normal_clamp and the ground truth read them); "
                             "GBuffer.from_arrays(depth, camera=...) derives them from the depth")
        self.camera = camera
        self.dtype = np.dtype(dtype)
        self.depth = _frozen(np.asarray(depth, dtype=self.dtype))
        self.normal = _frozen(np.asarray(normal, dtype=self.dtype))
        self.valid = _frozen(np.asarray(valid, dtype=bool))
        self.primitive = _frozen(np.asarray(primitive, dtype=np.int64))
        self._hit_source = hits
        self._view_to_world = view_to_world
        self.conversion = conversion
        self.intervals = None if intervals is None else self._checked_intervals(intervals)
        self.guard, self._inner_camera = _checked_guard(guard, inner_camera, self.depth.shape)
        self.motion = None if motion is None else _frozen(_checked_motion(motion, self.depth.shape, self.dtype))

    def _checked_intervals(self, intervals):
        from .layers import SolidIntervals

        if not isinstance(intervals, SolidIntervals):
            raise ValueError(f"intervals must be a vobscure.layers.SolidIntervals, got {type(intervals).__name__}")
        if intervals.shape != self.depth.shape:
            raise ValueError(f"intervals must have the image's shape {self.depth.shape}, got {intervals.shape}")
        # float32 intervals are kept as they are in a float64 G-buffer (the renderer's: 8 bytes a
        # slot); float64 intervals in a float32 G-buffer are rounded to it
        return intervals.astype(self.dtype) if intervals.dtype.itemsize > self.dtype.itemsize else intervals

    def with_intervals(self, intervals) -> "GBuffer":
        """The same G-buffer with the solid intervals ``intervals`` (a
        :class:`vobscure.layers.SolidIntervals` of the image's shape, or None to drop them).

        Examples
        --------
        >>> import numpy as np, vobscure as vo
        >>> from vobscure.layers import SolidIntervals
        >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
        >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
        >>> front = gb.depth[None]
        >>> layered = gb.with_intervals(SolidIntervals(front, front + 0.5))
        >>> layered.intervals.count, gb.intervals is None
        (1, True)
        """
        return self._replace(intervals=intervals)

    def with_motion(self, motion) -> "GBuffer":
        """The same G-buffer with the motion vectors ``motion`` ((H, W, 2) pixels, see
        :attr:`motion`; None to drop them).

        Examples
        --------
        >>> import numpy as np, vobscure as vo
        >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
        >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam).with_motion(np.zeros((4, 4, 2)))
        >>> gb.motion.shape
        (4, 4, 2)
        """
        return self._replace(motion=motion)

    def _replace(self, **changes) -> "GBuffer":
        """A G-buffer with the same fields as this one except ``changes`` (constructor keywords)."""
        fields = dict(depth=self.depth, normal=self.normal, valid=self.valid, primitive=self.primitive,
                      hits=self._hit_source, dtype=self.dtype, view_to_world=self._view_to_world,
                      conversion=self.conversion, intervals=self.intervals, guard=self.guard,
                      inner_camera=self._inner_camera, motion=self.motion)
        fields.update(changes)
        return GBuffer(fields.pop("camera", self.camera), **fields)

    @property
    def view_transform(self) -> tuple[np.ndarray, np.ndarray]:
        """(R, t): the world -> view rotation (3, 3) and translation (3,) of this view,
        ``p_view = R p_world + t`` (the camera's pose, or the ``view`` matrix given to
        :meth:`from_arrays`); a ValueError when there is neither."""
        R, t = self._world_frame()
        return np.array(R, dtype=np.float64), np.array(t, dtype=np.float64)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return self.depth.shape

    @property
    def has_hit_data(self) -> bool:
        """True when the per-hit data (:attr:`hits`) were given (a render, or the caller), False
        when they are derived from ``depth`` and ``normal`` (:meth:`from_arrays`): then the
        world positions carry the depth's precision, not the renderer's."""
        return self._hit_source is not None

    @cached_property
    def hits(self) -> dict:
        """Per-hit world-space data, pixels in row-major order (the order of a boolean mask):
        ``index`` (k,) flat pixel indices and (k, 3) float64 ``world_position``,
        ``world_normal``, ``world_geometric_normal``. Equal to
        ``gb.world_position.reshape(-1, 3)[index]`` and so on, without building the images."""
        source = self._hit_source
        if source is None:
            return self._derived_hits()
        return source() if callable(source) else source

    def _world_frame(self) -> tuple[np.ndarray, np.ndarray]:
        """(R, t) with p_view = R p_world + t, or a ValueError when there is no pose."""
        if self._view_to_world is not None:
            return self._view_to_world
        cam = self.camera
        if not getattr(cam, "has_pose", True):
            raise ValueError(
                "world-space data (world_position, world_normal, hits, the ground truth) needs the "
                "camera's pose, and this G-buffer's camera has none (a camera made from intrinsics "
                "without pose=); give the camera a pose, or pass view= (a 4x4 world-to-view "
                "matrix) to GBuffer.from_arrays. View-space data (depth, normal, position) and the "
                "screen-space estimators need no pose.")
        R = np.asarray(cam.rotation, dtype=np.float64)
        return R, -(R @ np.asarray(cam.eye, dtype=np.float64))

    def _derived_hits(self) -> dict:
        R, t = self._world_frame()
        index = np.flatnonzero(self.valid.reshape(-1))
        p_view = np.asarray(self.position, dtype=np.float64).reshape(-1, 3)[index]
        n_view = np.asarray(self.normal, dtype=np.float64).reshape(-1, 3)[index]
        n_world = n_view @ R          # R is a rotation: its inverse is its transpose
        return {"index": index, "world_position": (p_view - t) @ R,
                "world_normal": n_world, "world_geometric_normal": n_world.copy()}

    def _image(self, values, fill) -> np.ndarray:
        H, W = self.shape
        out = np.full((H * W, 3), fill, dtype=self.dtype)
        out[self.hits["index"]] = values
        return _frozen(out.reshape(H, W, 3))

    def per_pixel(self, fn) -> np.ndarray:
        """An (H, W) float64 image of ``fn(points, normals)`` at the covered pixels, NaN on
        background.

        ``points`` and ``normals`` are the (k, 3) float64 world-space positions and shading
        normals of the k covered pixels, row-major (:attr:`hits`); ``fn`` returns k values. It
        is not called when no pixel is covered, so a model that needs set-up work does it
        inside ``fn``. The object-space models evaluate themselves per pixel through this
        (:func:`vobscure.objectspace.bunnell_gbuffer`, :mod:`vobscure.trees.pixels`).

        Examples
        --------
        >>> import vobscure as vo
        >>> gb = vo.render_gbuffer(vo.scenes.slab(), vo.Camera.look_at((0, 2, 1), (0, 0, 0), size=(4, 3)))
        >>> img = gb.per_pixel(lambda p, n: n[:, 1])       # the world normal's y: 1 on the top face
        >>> img.shape, float(img[1, 1])
        ((3, 4), 1.0)
        """
        out = np.full(self.shape, np.nan)
        if self.valid.any():
            hits = self.hits
            out[self.valid] = fn(np.asarray(hits["world_position"], dtype=np.float64),
                                 np.asarray(hits["world_normal"], dtype=np.float64))
        return out

    @cached_property
    def world_position(self) -> np.ndarray:
        return self._image(self.hits["world_position"], np.nan)

    @cached_property
    def world_normal(self) -> np.ndarray:
        return self._image(self.hits["world_normal"], 0.0)

    @cached_property
    def world_geometric_normal(self) -> np.ndarray:
        return self._image(self.hits["world_geometric_normal"], 0.0)

    @cached_property
    def position(self) -> np.ndarray:
        if self._hit_source is None:
            # from the depth alone: no pose needed
            valid = self.valid
            p = self.camera.unproject(self.camera.pixel_centers()[valid],
                                      np.asarray(self.depth, dtype=np.float64)[valid])
            out = np.full(self.shape + (3,), np.nan, dtype=self.dtype)
            out[valid] = p
            return _frozen(out)
        return self._image(self.camera.world_to_view(self.hits["world_position"]), np.nan)

    @cached_property
    def geometric_normal(self) -> np.ndarray:
        if self._hit_source is None:
            return self.normal
        return self._image(self.hits["world_geometric_normal"] @ self.camera.rotation.T, 0.0)

    @classmethod
    def from_arrays(cls, depth, normal=None, *, camera, depth_kind="linear", near=None, far=None,
                    normal_space="view", view=None, normal_encoding="signed", convention="vobscure",
                    background=None, origin="upper", normal_tol=NORMAL_LENGTH_TOL,
                    repair_normals=False, back_depth=None, motion=None) -> "GBuffer":
        """A G-buffer from your own depth (and normal) images, converted to the library's
        conventions.

        Every estimator accepts the result exactly like a rendered G-buffer. What the
        conversion touched is counted in ``gb.conversion``. The conventions of common
        renderers and sensors, and the formulas, are in ``docs/own-buffers.md``.

        Parameters
        ----------
        depth : (H, W) array_like of float
            One value per pixel, encoded as ``depth_kind`` says; H = ``camera.height``,
            W = ``camera.width``.
        normal : (H, W, 3) array_like, optional
            Surface normals in ``normal_space``, encoded as ``normal_encoding`` says. None:
            derived from the depth (:meth:`derive_normals`; an approximation, see Notes).
        camera : Camera
            The camera of the images (keyword-only): it defines the pixel rays. World-space
            normals and world-space data need its pose (or ``view``).
        depth_kind : {"linear", "ndc", "ndc01", "reversed", "distance"}
            ``linear``: view-space z, the distance along the view axis (> 0 in front).
            ``ndc``: OpenGL normalized device z in [-1, 1] (near -> -1, far -> 1).
            ``ndc01``: z in [0, 1] (near -> 0, far -> 1): Direct3D, Vulkan, and what an
            OpenGL depth buffer holds with the default ``glDepthRange(0, 1)``.
            ``reversed``: reversed-Z in [0, 1] (near -> 1, far -> 0; ``far=np.inf`` for the
            common infinite far plane). ``distance``: the length of the ray from the eye to
            the surface (ray tracers, Cycles' Z pass, time-of-flight sensors).
        near, far : float, optional
            Clip-plane distances, needed by the ndc kinds (``0 < near < far``; ``far`` may be
            ``np.inf``); default the camera's ``near`` / ``far`` when it has them. Unused by
            ``linear`` and ``distance``.
        normal_space : {"view", "world"}
            View-space normals are in the view frame of ``convention``; world-space normals
            are rotated with ``view`` or, without it, with the camera's pose.
        view : (4, 4) array_like, optional
            World-to-view matrix in the view frame of ``convention``, acting on column
            vectors (``p_view = view @ (p, 1)``; transpose a row-vector Direct3D matrix). Used
            for world-space normals and for world-space data; when the camera has a pose too,
            the two must agree (within :data:`VIEW_TOL`).
        normal_encoding : {"signed", "unit"}
            ``signed``: the components themselves, in [-1, 1]. ``unit``: packed as
            ``0.5 n + 0.5`` in [0, 1]; integer images (8- or 16-bit PNG) are first divided by
            their dtype's maximum.
        convention : {"vobscure", "opengl", "directx"}
            The view frame of view-space normals and of ``view``. ``vobscure`` and
            ``directx``: x right, y up, z forward (into the screen). ``opengl``: x right,
            y up, z *backward* (the camera looks down -z), so z is negated; x and y are kept.
        background : float or callable, optional
            Which pixels show no surface. A number: pixels whose ``depth`` value is at or
            beyond it (``>=``; ``<=`` for ``reversed``), e.g. Blender's 1e10 or 1.0 for a
            cleared ``ndc01`` buffer. A callable: ``background(depth) -> (H, W) bool``
            (e.g. ``lambda d: d == 0`` for a depth sensor's "no reading"). Non-finite depths are
            background in every case. Default: only non-finite depths, and for the ndc kinds
            the cleared far-plane value too (``>= 1``; ``<= 0`` for ``reversed``).
        origin : {"upper", "lower"}
            Where row 0 of the arrays is: ``upper`` (images, the library) or ``lower``
            (``glReadPixels``); ``lower`` flips the rows.
        normal_tol : float
            Normals whose length differs from 1 by more than this are renormalized with one
            :class:`NormalsRenormalizedWarning` that counts them. Default
            :data:`NORMAL_LENGTH_TOL`.
        repair_normals : bool
            What to do with zero or NaN normals on covered pixels: False (default) raise a
            ValueError that counts them; True derive those from the depth and warn
            (:class:`NormalsRepairedWarning`) with the count.
        back_depth : (H, W) array_like of float, optional
            A back-face depth pass (the depth of the farthest, or the first back-facing,
            surface: what an engine renders with the depth test or the culling reversed), in
            the conventions of ``depth`` (``depth_kind``, ``near``, ``far``, ``background``,
            ``origin``). It makes ``gb.intervals`` a one-interval
            :class:`~vobscure.layers.SolidIntervals` ``[depth, back]`` (``docs/layers.md``):
            where it is background or non-finite the back is +inf (the solid's end unseen);
            where it lies in front of the depth (rounding) it is set to the depth and counted in
            ``conversion["back_clamped"]`` (``conversion["back_background"]`` counts the
            former on covered pixels); on background pixels the slot is unused.
        motion : (H, W, 2) array_like of float, optional
            Motion vectors in pixels towards the previous frame, (dx, dy) with x right and y
            down the image as stored (``origin="lower"``: y up; the rows are flipped and dy
            negated with the images), NaN where unknown: :attr:`motion`, read by
            :func:`vobscure.temporal.reproject`. A renderer's vectors towards the *next*
            frame, or in other units (NDC, UV), must be converted first (negated, scaled by
            the image size).

        Returns
        -------
        GBuffer
            float32 images when ``depth`` is float32 (or float16), float64 otherwise.
            ``primitive`` is -1 everywhere (there are no triangles); ``geometric_normal`` is
            ``normal``; ``position`` is unprojected from the depth; world-space images are
            built on first access and need a pose. ``conversion`` is a dict with the counts
            ``pixels``, ``covered``, ``background`` (of which ``nonfinite``),
            ``renormalized``, ``flipped`` (normals turned to face the camera), ``repaired``,
            ``derived`` (pixels whose normal came from the depth), ``undetermined`` (derived
            normals without a neighbour in x or y, set to face the camera), with
            ``back_depth`` ``back_background`` and ``back_clamped``, and the arguments
            ``depth_kind``, ``normal_space``, ``normal_encoding``, ``convention``.

        Raises
        ------
        ValueError
            For shapes that disagree with ``camera.size`` (the message names both arrays'
            shapes; "transposed?" for a (W, H) image), depths that are not positive or
            outside their kind's range on covered pixels, zero or NaN normals on covered
            pixels (unless ``repair_normals``), missing ``near`` / ``far``, world-space
            normals without a pose or ``view``, and any bad argument.

        Notes
        -----
        Linearization (``n``, ``f`` the clip distances, ``z`` the linear depth). With an
        OpenGL projection (``glFrustum``; eye z = -z) ``z_ndc = (f + n)/(f - n) -
        2 f n / ((f - n) z)``, so ``z = 2 f n / ((f + n) - z_ndc (f - n))``; the window depth
        ``(z_ndc + 1) / 2`` (``glDepthRange(0, 1)``) equals Direct3D's ``z_01 = f/(f - n) -
        f n / ((f - n) z)`` (``D3DXMatrixPerspectiveFovLH``), so ``z = f n / (f - z_01 (f -
        n))``; reversed-Z swaps n and f: ``z = f n / (n + z_r (f - n))`` (``z = n / z_r`` for
        ``f = inf``). Orthographic cameras store depth linearly: ``z = ((f - n) z_ndc + f +
        n) / 2``, ``z = n + z_01 (f - n)``, ``z = f - z_r (f - n)``. ``distance``: ``z = r /
        |(x, y, 1)|`` with ``(x, y, 1)`` the pixel's view ray at unit depth (``z = r`` for an
        orthographic camera).

        Normals are converted in this order: unpacked, rotated to view space, renormalized,
        flipped to face the camera where ``n . d > 0`` (``d`` the pixel's view ray; a
        two-sided surface seen from behind).

        References
        ----------
        OpenGL 4.6 core profile specification, Sec. 13.8 (coordinate transformations:
        division by w, viewport depth ``glDepthRange``); the ``glFrustum`` / ``glOrtho``
        reference pages (the projection matrices). Direct3D 9 ``D3DXMatrixPerspectiveFovLH``
        and ``D3DXMatrixOrthoLH`` reference pages (learn.microsoft.com).

        Examples
        --------
        >>> import numpy as np, vobscure as vo
        >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 3), fov_y=60)
        >>> z = np.full((3, 4), 3.0)                       # a plane facing the camera
        >>> n, f = 0.5, 10.0
        >>> z_ndc = (f + n) / (f - n) - 2 * f * n / ((f - n) * z)   # what OpenGL would store
        >>> gb = vo.GBuffer.from_arrays(z_ndc, camera=cam, depth_kind="ndc", near=n, far=f)
        >>> gb.depth.round(9).tolist()[0], gb.normal[1, 1].round(9).tolist()
        ([3.0, 3.0, 3.0, 3.0], [0.0, 0.0, -1.0])
        >>> float(vo.vo_line(gb, radius=0.5, normal_clamp=True)[1, 1])
        1.0

        A back-face pass 0.25 behind it: one solid interval per pixel.

        >>> z_back = (f + n) / (f - n) - 2 * f * n / ((f - n) * (z + 0.25))
        >>> gb = vo.GBuffer.from_arrays(z_ndc, camera=cam, depth_kind="ndc", near=n, far=f, back_depth=z_back)
        >>> round(float(gb.intervals.front[0, 1, 1]), 9), round(float(gb.intervals.back[0, 1, 1]), 9)
        (3.0, 3.25)
        """
        return cls(camera, **convert_buffers(depth, normal, camera=camera, depth_kind=depth_kind,
                                             near=near, far=far, normal_space=normal_space, view=view,
                                             normal_encoding=normal_encoding, convention=convention,
                                             background=background, origin=origin,
                                             normal_tol=normal_tol, repair_normals=repair_normals,
                                             back_depth=back_depth), motion=_stored_motion(motion, origin))

    @staticmethod
    def derive_normals(camera, depth) -> np.ndarray:
        """View-space normals from a linear depth image (an approximation).

        The tangents are differences of the view-space positions of neighbouring pixels:
        central where the surface is smooth across the pixel, one-sided at silhouettes,
        creases and the image border (the side whose plane coordinate -- 1/z for perspective,
        z for orthographic, both affine on a plane -- extrapolates best to the centre; see
        :data:`CENTRAL_RATIO`). The normal is their cross product, turned to face the camera.
        Exact on planes (up to rounding); the measured errors on the built-in scenes are in
        ``docs/own-buffers.md``.

        Parameters
        ----------
        camera : Camera
        depth : (H, W) array_like of float
            Linear view depth; non-finite or <= 0 is background.

        Returns
        -------
        (H, W, 3) float64
            Unit normals with ``n . d < 0``; 0 on background. A pixel with no covered
            neighbour along x or along y gets the normal facing the camera, ``-d / |d|``.
        """
        z = np.asarray(depth, dtype=np.float64)
        if z.shape != camera.shape:
            raise ValueError(f"depth must have shape (H, W) = {camera.shape} for camera.size "
                             f"{camera.size}, got {z.shape}")
        n, _ = normals_from_depth(camera, z, np.isfinite(z) & (z > 0))
        return n

    def astype(self, dtype) -> "GBuffer":
        """The same G-buffer whose float images are of ``dtype`` (e.g. float32 for precision tests).

        Raises
        ------
        ValueError
            If ``dtype`` is not a float dtype, or a covered pixel's depth does not fit in it
            (it would overflow to +inf, which marks background, or underflow to 0): the error
            names the largest (smallest) depth and the dtype's range.
        """
        try:
            target = np.dtype(dtype)
        except TypeError:
            target = None
        if target is None or target.kind != "f":
            raise ValueError(f"dtype must be a float dtype such as numpy.float32, got {dtype!r}")
        depth = np.abs(np.asarray(self.depth, dtype=np.float64)[self.valid])
        if depth.size and target.itemsize < 8:
            info = np.finfo(target)
            if depth.max() > info.max:
                raise ValueError(f"astype({target}): the largest depth of a covered pixel, {depth.max():.6g}, exceeds "
                                 f"{target}'s maximum {float(info.max):.6g} and would become inf (background); "
                                 f"rescale the scene and camera, or keep float64")
            tiny = depth[(depth > 0) & (depth < info.tiny)]
            if tiny.size:
                raise ValueError(f"astype({target}): the smallest depth of a covered pixel, {tiny.min():.6g}, is "
                                 f"below {target}'s smallest normal number {float(info.tiny):.6g}; rescale the "
                                 f"scene and camera, or keep float64")
        hits = None if self._hit_source is None else self.hits
        return self._replace(hits=hits, dtype=target)

    def inner(self) -> "GBuffer":
        """The G-buffer of the inner frame: this one without its guard band (itself when
        ``guard`` is 0).

        The buffers, the per-hit data and the solid intervals are cropped by ``guard`` pixels
        on each side; the camera is the inner frame's (the one given to
        :func:`~vobscure.render_gbuffer`). The inner pixels are the same rays as an
        unguarded render of that camera (``tests/test_guard.py``).

        Examples
        --------
        >>> import vobscure as vo
        >>> cam = vo.Camera.look_at((0, 2, 1), (0, 0, 0), size=(8, 6))
        >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam, guard=3)
        >>> gb.shape, gb.guard, gb.inner().shape, gb.inner().camera == cam
        ((12, 14), 3, (6, 8), True)
        """
        g = self.guard
        if g == 0:
            return self
        H, W = self.shape
        rows, cols = slice(g, H - g), slice(g, W - g)
        width = W - 2 * g
        hits = None
        if self._hit_source is not None:
            def hits():
                full = self.hits
                i, j = np.divmod(full["index"], W)
                keep = (i >= g) & (i < H - g) & (j >= g) & (j < W - g)
                out = {k: np.asarray(v)[keep] for k, v in full.items()}
                out["index"] = (i[keep] - g) * width + (j[keep] - g)
                return out
        intervals = self.intervals
        if intervals is not None:
            from .layers import SolidIntervals

            layers = None if intervals.layers is None else intervals.layers.crop(rows, cols)
            intervals = SolidIntervals(intervals.front[:, rows, cols], intervals.back[:, rows, cols],
                                       dtype=intervals.dtype, layers=layers)
        motion = None if self.motion is None else self.motion[rows, cols]
        return self._replace(camera=self._inner_camera, depth=self.depth[rows, cols], normal=self.normal[rows, cols],
                             valid=self.valid[rows, cols], primitive=self.primitive[rows, cols], hits=hits,
                             intervals=intervals, guard=0, inner_camera=None, motion=motion)

    def __repr__(self) -> str:
        H, W = self.shape
        guard = f", guard {self.guard}" if self.guard else ""
        return f"GBuffer({W}x{H}, {int(self.valid.sum())} covered pixels, {self.dtype}{guard})"


def _checked_guard(guard, inner_camera, shape) -> tuple[int, object]:
    """(guard, inner_camera) validated against the image ``shape``."""
    if isinstance(guard, bool) or not isinstance(guard, (int, np.integer)) or guard < 0:
        raise ValueError(f"guard must be an int >= 0 (pixels), got {guard!r}")
    guard = int(guard)
    if guard == 0:
        return 0, None
    if inner_camera is None:
        raise ValueError("a GBuffer with guard > 0 needs inner_camera, the inner frame's camera")
    H, W = shape
    if tuple(inner_camera.shape) != (H - 2 * guard, W - 2 * guard):
        raise ValueError(f"inner_camera.shape must be the image's shape {shape} less 2 * guard = "
                         f"{2 * guard}, got {inner_camera.shape}")
    return guard, inner_camera


def _checked_motion(motion, shape, dtype) -> np.ndarray:
    """Motion vectors as an (H, W, 2) array of ``dtype``, finite (or NaN where unknown)."""
    from ._validate import as_numeric

    m = as_numeric(motion, "motion", kinds="fiu", expected="an (H, W, 2) array of pixel offsets")
    if m.shape != tuple(shape) + (2,):
        raise ValueError(f"motion must have shape {tuple(shape) + (2,)} (the image's, with (dx, dy) per pixel), "
                         f"got {m.shape}")
    m = m.astype(dtype, copy=True)
    if np.isinf(m).any():
        raise ValueError("motion must be finite (NaN where a pixel's motion is unknown), got +-inf")
    return m


def _stored_motion(motion, origin):
    """Motion vectors of an image stored with ``origin``, in the library's rows (row 0 at the top)."""
    if motion is None or origin != "lower":
        return motion
    from ._validate import as_numeric

    m = as_numeric(motion, "motion", kinds="fiu", expected="an (H, W, 2) array of pixel offsets")
    if m.ndim != 3 or m.shape[-1] != 2:
        raise ValueError(f"motion must have shape (H, W, 2) (the image's, with (dx, dy) per pixel), got {m.shape}")
    m = np.array(m[::-1], dtype=np.float64)
    m[..., 1] *= -1.0
    return m


def _frozen(a: np.ndarray) -> np.ndarray:
    a = a.view()
    a.flags.writeable = False
    return a


def __getattr__(name):
    # render_gbuffer lives in vobscure.render, which imports this module for GBuffer; the old
    # name is looked up there on first use (this module does not import the renderer).
    if name == "render_gbuffer":
        warnings.warn("vobscure.gbuffer.render_gbuffer is deprecated; use vobscure.render_gbuffer "
                      "(vobscure.render)", DeprecationWarning, stacklevel=2)
        return importlib.import_module(".render", __package__).render_gbuffer
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
