"""G-buffers: what a rasterizer would write, rendered with Embree primary rays.

A :class:`GBuffer` is the only input of the screen-space estimators. It follows the
conventions of ``docs/conventions.md``: view space has the camera at the origin, x right,
y up and z the depth, positive in front of the camera; ``depth`` is that z (linear depth,
not the distance along the ray); background pixels have ``depth = +inf``, zero normals,
NaN positions and ``valid = False``.

A G-buffer comes from :func:`render_gbuffer` (Embree) or from your own renderer's or depth
sensor's images through :meth:`GBuffer.from_arrays`, which converts the common depth and
normal conventions (OpenGL, Direct3D, reversed-Z, ray distance, packed normals, world-space
normals) into the library's (``docs/own-buffers.md``).
"""

from __future__ import annotations

import warnings
from functools import cached_property

import numpy as np

from ._validate import check_choice, check_positive

__all__ = ["GBuffer", "render_gbuffer", "NormalsRenormalizedWarning", "NormalsRepairedWarning",
           "DEPTH_KINDS", "NORMAL_LENGTH_TOL"]

#: The depth encodings :meth:`GBuffer.from_arrays` reads (``docs/own-buffers.md``).
DEPTH_KINDS = ("linear", "ndc", "ndc01", "reversed", "distance")
NORMAL_SPACES = ("view", "world")
NORMAL_ENCODINGS = ("signed", "unit")
CONVENTIONS = ("vobscure", "opengl", "directx")
#: A normal whose length differs from 1 by more than this is renormalized with a
#: :class:`NormalsRenormalizedWarning` (those within it are renormalized silently). Half-float
#: normals are within 5e-4; 8-bit ones (``0.5 n + 0.5`` in a PNG) are not.
NORMAL_LENGTH_TOL = 1e-3
#: A normal shorter than this has no direction: an error on a covered pixel (or repaired).
NORMAL_ZERO_TOL = 1e-6
#: |R Rᵀ - I| allowed for the rotation part of a ``view`` matrix, and the disagreement allowed
#: between ``view`` and the camera's own pose (relative to the translation's size).
VIEW_TOL = 1e-4
#: Derived normals: the central difference is used where the centre's second difference of the
#: plane coordinate (1/z perspective, z orthographic) is at most this many times the better
#: one-sided extrapolation error (smooth surface); otherwise the smoother side's one-sided one.
CENTRAL_RATIO = 2.0


class NormalsRenormalizedWarning(UserWarning):
    """:meth:`GBuffer.from_arrays` renormalized normals longer or shorter than 1 by more than
    ``normal_tol``; the message counts them. Real frames hold such normals (a pixel at an edge
    averages the normals of two faces, 8-bit storage rounds them)."""


class NormalsRepairedWarning(UserWarning):
    """:meth:`GBuffer.from_arrays` (with ``repair_normals=True``) replaced zero or NaN normals
    of covered pixels by normals derived from the depth; the message counts them."""


class GBuffer:
    """Per-pixel geometry of one view.

    Built by :func:`render_gbuffer`. The buffers below are read-only arrays. Only ``depth``,
    ``normal``, ``valid`` and ``primitive`` are made at render time; the other images are
    assembled from the per-hit data on first access and then kept, so a job that only needs
    the screen-space inputs never pays for world-space images (and the ground truth reads
    the per-hit data directly, see :attr:`hits`).

    The constructor stores what it is given after converting the dtypes; it does not check
    the conventions below, which :func:`render_gbuffer` guarantees. Construct one directly
    only to wrap buffers from elsewhere (e.g. a rasterizer) that keep them.

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
    """

    def __init__(self, camera, *, depth, normal, valid, primitive, hits, dtype=np.float64,
                 view_to_world=None, conversion=None):
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

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return self.depth.shape

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
                    repair_normals=False) -> "GBuffer":
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
            normals without a neighbour in x or y, set to face the camera) and the arguments
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
        """
        return _from_arrays(cls, depth, normal, camera=camera, depth_kind=depth_kind, near=near,
                            far=far, normal_space=normal_space, view=view,
                            normal_encoding=normal_encoding, convention=convention,
                            background=background, origin=origin, normal_tol=normal_tol,
                            repair_normals=repair_normals)

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
        n, _ = _derive_normals(camera, z, np.isfinite(z) & (z > 0))
        return n

    def astype(self, dtype) -> "GBuffer":
        """The same G-buffer whose float images are of ``dtype`` (e.g. float32 for precision tests)."""
        hits = None if self._hit_source is None else self.hits
        return GBuffer(self.camera, depth=self.depth, normal=self.normal, valid=self.valid,
                       primitive=self.primitive, hits=hits, dtype=dtype,
                       view_to_world=self._view_to_world, conversion=self.conversion)

    def __repr__(self) -> str:
        H, W = self.shape
        return f"GBuffer({W}x{H}, {int(self.valid.sum())} covered pixels, {self.dtype})"


def _frozen(a: np.ndarray) -> np.ndarray:
    a = a.view()
    a.flags.writeable = False
    return a


def render_gbuffer(scene, camera) -> GBuffer:
    """Render a G-buffer of ``scene`` seen by ``camera`` (one Embree ray per pixel centre).

    Parameters
    ----------
    scene : Scene or trimesh.Trimesh
    camera : Camera

    Returns
    -------
    GBuffer

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> gb.depth.round(6).tolist()[0]
    [3.0, 3.0, 3.0, 3.0]
    >>> gb.world_normal[0, 0].round(6).tolist()
    [0.0, 1.0, 0.0]
    """
    from .camera import Camera
    from .scenes import as_scene
    from .raytrace import CHUNK_RAYS, default_threads, parallel_map

    scene = as_scene(scene)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    H, W = camera.height, camera.width
    depth = np.full(H * W, np.inf)
    normal = np.zeros((H * W, 3))
    valid = np.zeros(H * W, dtype=bool)
    primitive = np.full(H * W, -1, dtype=np.int64)
    # Bands of rows are traced and shaded in parallel, each on one thread, and write their
    # own slices of the images. Bands of about CHUNK_RAYS pixels: with a few huge bands the
    # threads' temporaries are fresh multi-megabyte allocations whose page faults serialize
    # them (measured: 2 bands gave no speed-up on 2 cores, 8 bands of 32k pixels gave 2x).
    threads = default_threads()
    count = min(H, max(2 * threads, -(-H * W // CHUNK_RAYS)))
    edges = np.linspace(0, H, count + 1).astype(np.int64)
    bands = [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]

    def band(rows: slice):
        origins, dirs = camera.primary_rays(dtype=np.float32, rows=rows)
        part = _trace_block(scene, camera, origins.reshape(-1, 3), dirs.reshape(-1, 3))
        flat = part["index"] + rows.start * W
        depth[flat] = part.pop("depth")
        normal[flat] = part.pop("normal")
        valid[flat] = True
        primitive[flat] = part.pop("primitive")
        part["index"] = flat
        return part

    parts = parallel_map(band, bands, threads=threads)

    def hits():
        return {k: np.concatenate([p[k] for p in parts]) for k in
                ("index", "world_position", "world_normal", "world_geometric_normal")}

    return GBuffer(camera, depth=depth.reshape(H, W), normal=normal.reshape(H, W, 3),
                   valid=valid.reshape(H, W), primitive=primitive.reshape(H, W), hits=hits)


def _trace_block(scene, camera, origins, dirs) -> dict:
    """Primary hits of a block of pixels (flat, row-major) and their per-hit data."""
    hits = scene.tracer.intersect(origins, dirs, threads=1)
    local = np.flatnonzero(hits.primitive >= 0)
    prim = hits.primitive[local]
    d = dirs[local].astype(np.float64)
    o = camera.eye if camera.is_perspective else origins[local].astype(np.float64)

    n_face = scene.face_normals[prim]
    # Hit point: origin + t * direction in float64, then projected onto the triangle's plane
    # n . x = c, which removes Embree's float32 error across the plane (the error that
    # matters for self-intersection).
    p = o + hits.distance[local, None] * d
    p -= (np.einsum("ij,ij->i", p, n_face) - scene.plane_offsets[prim])[:, None] * n_face
    # geometric normal, flipped to face the camera (against the ray direction)
    sign = np.where(np.einsum("ij,ij->i", n_face, d) > 0, -1.0, 1.0)[:, None]
    n_geo = n_face * sign
    n_geo += 0.0  # no negative zeros in the output
    # shading normal: corner normals interpolated with Embree's barycentrics, only on
    # triangles whose corners are not all the face normal (flat meshes skip the gather)
    n_sh = n_geo.copy()
    smooth = scene.smooth_faces[prim]
    if smooth.any():
        js = np.flatnonzero(smooth)
        uv = hits.barycentric[local[js]]
        weights = np.column_stack([1.0 - uv[:, 0] - uv[:, 1], uv[:, 0], uv[:, 1]])
        ns = np.einsum("kj,kjc->kc", weights, scene.corner_normals[prim[js]]) * sign[js]
        length = np.sqrt(np.einsum("ij,ij->i", ns, ns))
        ok = (length > 0) & (np.einsum("ij,ij->i", ns, d[js]) < 0)
        # where the interpolated normal would face away from the camera, keep the geometric one
        n_sh[js[ok]] = ns[ok] / length[ok, None]
    return {"index": local, "world_position": p, "world_normal": n_sh, "world_geometric_normal": n_geo,
            "primitive": prim,
            "depth": (p - camera.eye) @ camera.forward,   # linear depth: the view z of the hit
            "normal": n_sh @ camera.rotation.T}


# ----------------------------------------------------------------------------- from_arrays
def _shape_error(name, arr_shape, camera, depth_shape=None, normal_shape=None) -> ValueError:
    H, W = camera.height, camera.width
    want = (H, W) if name == "depth" else (H, W, 3)
    hint = ""
    if tuple(arr_shape[:2]) == (W, H) and W != H:
        hint = " (transposed? images are (rows, columns) = (H, W); pass a.T or swap the camera size)"
    shapes = f"depth {depth_shape}" + ("" if normal_shape is None else f", normal {normal_shape}")
    return ValueError(f"{name} must have shape {want} for camera.size (W, H) = {camera.size}, "
                      f"got {tuple(arr_shape)}{hint}; arrays given: {shapes}")


def _clip_planes(camera, near, far, depth_kind):
    """``near``, ``far`` as floats (from the camera when not given), validated."""
    near = getattr(camera, "near", None) if near is None else near
    far = getattr(camera, "far", None) if far is None else far
    if near is None or far is None:
        missing = " and ".join(k for k, v in (("near", near), ("far", far)) if v is None)
        raise ValueError(f"depth_kind={depth_kind!r} needs the clip distances near and far to "
                         f"linearize; {missing} not given (and the camera has none). Pass "
                         "near=..., far=... (far=np.inf for an infinite far plane)")
    near = check_positive(near, "near")
    far = check_positive(far, "far", allow_inf=True)
    if not far > near:
        raise ValueError(f"far must be greater than near, got near={near!r}, far={far!r}")
    return near, far


def _view_rays(camera, rows: slice = slice(None)) -> np.ndarray:
    """(h, W, 3) view-space direction of each pixel centre's ray (not normalized), for the
    image's ``rows``."""
    H, W = camera.shape
    i = np.arange(H, dtype=np.float64)[rows] + 0.5
    if camera.is_perspective:
        centers = np.empty((len(i), W, 2))
        centers[..., 0] = np.arange(W, dtype=np.float64)[None, :] + 0.5
        centers[..., 1] = i[:, None]
        return camera.unproject(centers, 1.0)                    # (x, y, 1) at unit depth
    return np.broadcast_to(np.array([0.0, 0.0, 1.0]), (len(i), W, 3))


def _linearize(raw, kind, near, far, camera, rays):
    """Linear view depth z from the stored values (covered pixels, flat arrays)."""
    n, f = near, far
    perspective = camera.is_perspective
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if kind == "linear":
            return raw.copy()
        if kind == "distance":
            if not perspective:
                return raw.copy()           # parallel rays leave the camera plane: r = z
            return raw / np.linalg.norm(rays, axis=-1)   # z = r / |(x, y, 1)|
        if np.isinf(f):
            # the limits f -> inf of the formulas below
            if not perspective:
                raise ValueError(f"depth_kind={kind!r} on an orthographic camera needs a finite far")
            if kind == "ndc":
                return 2.0 * n / (1.0 - raw)            # z_ndc = 1 - 2 n / z
            if kind == "ndc01":
                return n / (1.0 - raw)                  # z_01 = 1 - n / z
            return n / raw                              # reversed: z_r = n / z
        if perspective:
            if kind == "ndc":
                # OpenGL (glFrustum): z_ndc = (f + n)/(f - n) - 2 f n / ((f - n) z)
                return 2.0 * f * n / ((f + n) - raw * (f - n))
            if kind == "ndc01":
                # Direct3D (D3DXMatrixPerspectiveFovLH): z_01 = f/(f - n) - f n / ((f - n) z)
                return f * n / (f - raw * (f - n))
            # reversed-Z: the same with n and f swapped, z_r = n/(n - f) - f n / ((n - f) z)
            return f * n / (n + raw * (f - n))
        # orthographic projections are affine in z (glOrtho, D3DXMatrixOrthoLH)
        if kind == "ndc":
            return ((f - n) * raw + f + n) / 2.0
        if kind == "ndc01":
            return n + raw * (f - n)
        return f - raw * (f - n)


_RANGES = {"ndc": (-1.0, 1.0), "ndc01": (0.0, 1.0), "reversed": (0.0, 1.0)}


def _background(raw, given, kind, background):
    """(H, W) bool background mask and the count of non-finite values."""
    nonfinite = ~np.isfinite(raw)
    if background is None:
        if kind in ("ndc", "ndc01"):
            beyond = raw >= 1.0
        elif kind == "reversed":
            beyond = raw <= 0.0
        else:
            beyond = np.zeros(raw.shape, dtype=bool)
    elif callable(background):
        beyond = np.asarray(background(given))
        if beyond.shape != raw.shape or beyond.dtype != bool:
            raise ValueError(f"background(depth) must return a bool array of the depth's shape "
                             f"{raw.shape}, got {beyond.dtype} of shape {beyond.shape}")
    else:
        if isinstance(background, bool) or not isinstance(background, (int, float, np.number)) \
                or np.isnan(background):
            raise ValueError(f"background must be a depth value (number) or a callable "
                             f"depth -> (H, W) bool mask, got {background!r}")
        with np.errstate(invalid="ignore"):
            beyond = raw <= background if kind == "reversed" else raw >= background
    return nonfinite | beyond, int(nonfinite.sum())


def _view_matrix(view, convention):
    """(R, t) of a world-to-view matrix, in the library's view frame."""
    V = np.asarray(view, dtype=np.float64)
    if V.shape != (4, 4) or not np.all(np.isfinite(V)):
        raise ValueError(f"view must be a finite (4, 4) world-to-view matrix, got shape {V.shape}")
    if not np.allclose(V[3], (0.0, 0.0, 0.0, 1.0), atol=VIEW_TOL):
        raise ValueError(f"view's last row must be (0, 0, 0, 1), got {V[3].tolist()}: a row-vector "
                         "(Direct3D) matrix must be transposed; a projection matrix is not a view")
    R, t = V[:3, :3].copy(), V[:3, 3].copy()
    err = float(np.abs(R @ R.T - np.eye(3)).max())
    if err > VIEW_TOL:
        raise ValueError(f"view's upper-left 3x3 must be a rotation (|R Rᵀ - I| = {err:.3g} > "
                         f"{VIEW_TOL}); scale or shear in the view matrix is not supported")
    if convention == "opengl":     # OpenGL eye space looks down -z: negate the z row
        R[2] *= -1.0
        t[2] *= -1.0
    return R, t


def _from_arrays(cls, depth, normal, *, camera, depth_kind, near, far, normal_space, view,
                 normal_encoding, convention, background, origin, normal_tol, repair_normals):
    from .camera import Camera

    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    check_choice(depth_kind, "depth_kind", DEPTH_KINDS)
    check_choice(normal_space, "normal_space", NORMAL_SPACES)
    check_choice(normal_encoding, "normal_encoding", NORMAL_ENCODINGS)
    check_choice(convention, "convention", CONVENTIONS)
    check_choice(origin, "origin", ("upper", "lower"))
    normal_tol = check_positive(normal_tol, "normal_tol")

    # -- shapes and dtypes
    try:
        given = np.asarray(depth)
        if given.dtype.kind not in "fiu":
            raise TypeError(f"dtype {given.dtype}")
    except (TypeError, ValueError) as exc:
        raise ValueError(f"depth must be a numeric (H, W) array, got {type(depth).__name__}: {exc}") from None
    nrm = None if normal is None else np.asarray(normal)
    nshape = None if nrm is None else nrm.shape
    if given.shape != camera.shape:
        raise _shape_error("depth", given.shape, camera, given.shape, nshape)
    if nrm is not None:
        if nrm.dtype.kind not in "fiu":
            raise ValueError(f"normal must be a numeric (H, W, 3) array, got dtype {nrm.dtype}")
        if nrm.shape != camera.shape + (3,):
            raise _shape_error("normal", nrm.shape, camera, given.shape, nshape)
    dtype = np.float32 if given.dtype in (np.float32, np.float16) else np.float64
    if origin == "lower":
        given = given[::-1]
        nrm = None if nrm is None else nrm[::-1]
    raw = given.astype(np.float64)

    # -- depth: background, then linearization of the covered pixels
    is_ndc = depth_kind in _RANGES
    if is_ndc:
        near, far = _clip_planes(camera, near, far, depth_kind)
    bg, nonfinite = _background(raw, given, depth_kind, background)
    covered = ~bg
    values = raw[covered]
    if is_ndc:
        lo, hi = _RANGES[depth_kind]
        outside = int(np.count_nonzero((values < lo) | (values > hi)))
        if outside:
            raise ValueError(f"depth (depth_kind={depth_kind!r}) must lie in [{lo}, {hi}] on covered "
                             f"pixels; {outside} value(s) do not (min {values.min():.6g}, max "
                             f"{values.max():.6g}). Is depth_kind right, or are they background?")
    z = _linearize(values, depth_kind, near, far, camera,
                   _view_rays(camera)[covered] if depth_kind == "distance" else None)
    bad = ~(np.isfinite(z) & (z > 0))
    if bad.any():
        hint = (" OpenGL eye-space z is negative in front of the camera: pass -z." if
                depth_kind in ("linear", "distance") else "")
        raise ValueError(f"depth must give a positive finite linear depth on covered pixels; "
                         f"{int(bad.sum())} pixel(s) do not (depth_kind={depth_kind!r}, values like "
                         f"{values[bad][:3].tolist()}).{hint} Mark background with background=...")
    linear = np.full(raw.shape, np.inf)
    linear[covered] = z

    counts = {"pixels": int(raw.size), "covered": int(covered.sum()), "background": int(bg.sum()),
              "nonfinite": nonfinite, "renormalized": 0, "flipped": 0, "repaired": 0, "derived": 0,
              "undetermined": 0}
    view_frame = None if view is None else _view_matrix(view, convention)
    if view_frame is not None and getattr(camera, "has_pose", True):
        R_cam = np.asarray(camera.rotation, dtype=np.float64)
        t_cam = -(R_cam @ np.asarray(camera.eye, dtype=np.float64))
        R_err = float(np.abs(view_frame[0] - R_cam).max())
        t_err = float(np.abs(view_frame[1] - t_cam).max()) / max(1.0, float(np.abs(t_cam).max()))
        if R_err > VIEW_TOL or t_err > VIEW_TOL:
            raise ValueError(f"view disagrees with the camera's pose (rotation by {R_err:.3g}, "
                             f"translation by {t_err:.3g} relative; convention={convention!r}): "
                             "pass the matching view, or a camera without a pose")

    # -- normals
    if nrm is None:
        n_view, undetermined = _derive_normals(camera, linear, covered)
        counts["derived"] = counts["covered"]
        counts["undetermined"] = undetermined
    else:
        n_view, fixes = _normals_in_bands(nrm, camera, linear, covered, dtype, normal_space=normal_space,
                                          encoding=normal_encoding, convention=convention,
                                          view_frame=view_frame, tol=normal_tol, repair=repair_normals)
        counts.update(fixes)
    counts.update(depth_kind=depth_kind, normal_space=None if nrm is None else normal_space,
                  normal_encoding=None if nrm is None else normal_encoding, convention=convention)
    H, W = camera.shape
    return cls(camera, depth=linear, normal=n_view, valid=covered,
               primitive=np.broadcast_to(np.int64(-1), (H, W)), hits=None, dtype=dtype,
               view_to_world=view_frame, conversion=counts)


#: Rows of the normal image converted and checked at once (bounded memory on large frames).
NORMAL_BAND_ROWS = 64


def _normals_in_bands(nrm, camera, depth, covered, dtype, *, normal_space, encoding, convention, view_frame,
                      tol, repair):
    """The normal image converted to the library's frame, checked, renormalized and flipped to
    face the camera, in bands of :data:`NORMAL_BAND_ROWS` rows (float64 work, ``dtype``
    output), with one warning for the whole image."""
    H, W = covered.shape
    out = np.zeros((H, W, 3), dtype=dtype)
    counts = {"renormalized": 0, "flipped": 0, "repaired": 0}
    missing_all, worst = np.zeros((H, W), dtype=bool), 0.0
    for r0 in range(0, H, NORMAL_BAND_ROWS):
        rows = slice(r0, min(r0 + NORMAL_BAND_ROWS, H))
        n = _convert_normals(nrm[rows], camera, covered[rows], normal_space=normal_space, encoding=encoding,
                             convention=convention, view_frame=view_frame)
        band, c, missing, diff = _check_normals(n, covered[rows], _view_rays(camera, rows), tol)
        out[rows] = band
        counts["renormalized"] += c["renormalized"]
        counts["flipped"] += c["flipped"]
        missing_all[rows] = missing
        worst = max(worst, diff)
    k = int(missing_all.sum())
    if k and not repair:
        raise ValueError(f"normal has {k} zero or NaN vector(s) on covered pixels (finite depth); "
                         "mark those pixels background, or pass repair_normals=True to derive "
                         "their normals from the depth")
    if counts["renormalized"]:
        warnings.warn(f"renormalized {counts['renormalized']} normal(s) of {int(covered.sum())} "
                      f"covered pixels whose length differed from 1 by more than normal_tol={tol:g} "
                      f"(largest difference {worst:.3g})", NormalsRenormalizedWarning, stacklevel=4)
    if k:
        derived, _ = _derive_normals(camera, depth, covered)
        out[missing_all] = derived[missing_all]
        counts["repaired"] = k
        warnings.warn(f"derived {k} zero or NaN normal(s) of covered pixels from the depth "
                      "(repair_normals=True)", NormalsRepairedWarning, stacklevel=4)
    return out, counts


def _convert_normals(nrm, camera, covered, *, normal_space, encoding, convention, view_frame):
    """The normal image unpacked and in the library's view frame (float64, not normalized)."""
    if nrm.dtype.kind in "iu":
        if encoding != "unit":
            raise ValueError(f"normal is an integer image ({nrm.dtype}): packed normals need "
                             "normal_encoding='unit' (0.5 n + 0.5 scaled to the dtype's range)")
        n = nrm.astype(np.float64) / float(np.iinfo(nrm.dtype).max)
    else:
        n = nrm.astype(np.float64)
    if encoding == "unit":
        n = 2.0 * n - 1.0                      # inverse of the packing 0.5 n + 0.5
    if normal_space == "world":
        if view_frame is not None:
            R = view_frame[0]
        elif getattr(camera, "has_pose", True):
            R = np.asarray(camera.rotation, dtype=np.float64)
        else:
            raise ValueError("normal_space='world' needs the world-to-view rotation: the camera "
                             "has no pose; pass view= (a 4x4 world-to-view matrix) or a camera "
                             "with a pose")
        with np.errstate(invalid="ignore", over="ignore"):
            n = n @ R.T
    elif convention == "opengl":
        n[..., 2] *= -1.0                      # OpenGL eye space: z points backwards
    n[~covered] = 0.0
    return n


def _check_normals(n, covered, rays, tol):
    """One band: renormalize, flag zero/NaN vectors, flip to face the camera.

    Returns (unit normals, zero where missing or uncovered; counts; the missing mask; the
    largest length difference beyond ``tol``)."""
    counts = {"renormalized": 0, "flipped": 0}
    with np.errstate(invalid="ignore", over="ignore"):
        length = np.sqrt(np.einsum("...i,...i->...", n, n))
    missing = covered & ~(np.isfinite(length) & (length > NORMAL_ZERO_TOL))
    ok = covered & ~missing
    off = ok & (np.abs(length - 1.0) > tol)
    counts["renormalized"] = int(off.sum())
    worst = float(np.abs(length[off] - 1.0).max()) if counts["renormalized"] else 0.0
    out = np.zeros_like(n)
    out[ok] = n[ok] / length[ok, None]
    # face the camera: n . d < 0 for the pixel's view ray d
    away = ok & (np.einsum("...i,...i->...", out, rays) > 0)
    out[away] *= -1.0
    counts["flipped"] = int(away.sum())
    out += 0.0   # no negative zeros
    return out, counts, missing, worst


def _derive_normals(camera, depth, covered, *, rays=None):
    """(H, W, 3) normals from linear depth and the number of undetermined pixels."""
    H, W = depth.shape
    rays = _view_rays(camera) if rays is None else rays
    P = np.full((H, W, 3), np.nan)
    with np.errstate(invalid="ignore", over="ignore"):
        P[covered] = camera.unproject(camera.pixel_centers()[covered], depth[covered])
    # the plane coordinate: affine in the pixel coordinates on any plane
    w = np.full((H, W), np.nan)
    w[covered] = 1.0 / depth[covered] if camera.is_perspective else depth[covered]
    Pp = np.pad(P, ((2, 2), (2, 2), (0, 0)), constant_values=np.nan)
    wp = np.pad(w, 2, constant_values=np.nan)

    def tangent(axis):
        def sh(a, k):   # the neighbour k steps along axis, on the unpadded grid
            idx = [slice(2, 2 + H), slice(2, 2 + W)]
            idx[axis] = slice(2 + k, 2 + k + (H, W)[axis])
            return a[tuple(idx)]
        w0, wm1, wm2, wp1, wp2 = w, sh(wp, -1), sh(wp, -2), sh(wp, 1), sh(wp, 2)
        have_f, have_b = np.isfinite(wp1), np.isfinite(wm1)
        big = np.finfo(np.float64).max
        with np.errstate(invalid="ignore", over="ignore"):
            # one-sided extrapolation errors (unknown when only one neighbour: big)
            e_f = np.where(have_f, np.abs(w0 - (2.0 * wp1 - wp2)), np.inf)
            e_b = np.where(have_b, np.abs(w0 - (2.0 * wm1 - wm2)), np.inf)
            e_f = np.where(have_f & ~np.isfinite(e_f), big, e_f)
            e_b = np.where(have_b & ~np.isfinite(e_b), big, e_b)
            c = np.abs(wp1 - 2.0 * w0 + wm1)
            central = have_f & have_b & (c <= CENTRAL_RATIO * np.minimum(e_f, e_b))
            forward = ~central & have_f & (e_f <= e_b)
            backward = ~central & ~forward & have_b
            # a blend of the backward and forward differences: (1/2, 1/2) central, (0, 1)
            # forward, (1, 0) backward, (0, 0) none (no covered neighbour)
            a = np.where(central, 0.5, np.where(backward, 1.0, 0.0))
            b = np.where(central, 0.5, np.where(forward, 1.0, 0.0))
            P0, Pm, Pf = P, sh(Pp, -1), sh(Pp, 1)
            t = np.empty((3, H, W))
            for c_ in range(3):
                back_ = np.where(a > 0, P0[..., c_] - Pm[..., c_], 0.0)
                fore_ = np.where(b > 0, Pf[..., c_] - P0[..., c_], 0.0)
                t[c_] = a * back_ + b * fore_
        return t, central | forward | backward

    tx, okx = tangent(1)
    ty, oky = tangent(0)
    n = np.stack([tx[1] * ty[2] - tx[2] * ty[1],     # tx x ty, component by component
                  tx[2] * ty[0] - tx[0] * ty[2],
                  tx[0] * ty[1] - tx[1] * ty[0]], axis=-1)
    ok = covered & okx & oky
    with np.errstate(invalid="ignore"):
        length = np.sqrt(np.einsum("...i,...i->...", n, n))
        ok &= length > 0
        out = np.where(ok[..., None], n / np.where(ok, length, 1.0)[..., None], 0.0)
    # no neighbour along an axis: face the camera
    undetermined = covered & ~ok
    d = np.asarray(rays, dtype=np.float64)
    out[undetermined] = -d[undetermined] / np.linalg.norm(d[undetermined], axis=-1, keepdims=True)
    away = ok & (np.einsum("...i,...i->...", out, d) > 0)
    out[away] *= -1.0
    out += 0.0
    return out, int(undetermined.sum())
