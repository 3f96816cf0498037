"""G-buffers: what a rasterizer would write, rendered with Embree primary rays.

A :class:`GBuffer` is the only input of the screen-space estimators. It follows the
conventions of ``docs/conventions.md``: view space has the camera at the origin, x right,
y up and z the depth, positive in front of the camera; ``depth`` is that z (linear depth,
not the distance along the ray); background pixels have ``depth = +inf``, zero normals,
NaN positions and ``valid = False``.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

__all__ = ["GBuffer", "render_gbuffer"]


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
    hits : dict or callable
        The per-hit world-space data of :attr:`hits` (``index`` (k,) flat row-major indices
        of the valid pixels; (k, 3) float64 ``world_position``, ``world_normal``,
        ``world_geometric_normal``), or a function of no arguments returning that dict,
        called on first access.
    dtype : numpy dtype, optional
        dtype of the float images, float64 (default) or float32 (see :meth:`astype`).

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
    """

    def __init__(self, camera, *, depth, normal, valid, primitive, hits, dtype=np.float64):
        self.camera = camera
        self.dtype = np.dtype(dtype)
        self.depth = _frozen(np.asarray(depth, dtype=self.dtype))
        self.normal = _frozen(np.asarray(normal, dtype=self.dtype))
        self.valid = _frozen(np.asarray(valid, dtype=bool))
        self.primitive = _frozen(np.asarray(primitive, dtype=np.int64))
        self._hit_source = hits

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
        return source() if callable(source) else source

    def _image(self, values, fill) -> np.ndarray:
        H, W = self.shape
        out = np.full((H * W, 3), fill, dtype=self.dtype)
        out[self.hits["index"]] = values
        return _frozen(out.reshape(H, W, 3))

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
        return self._image(self.camera.world_to_view(self.hits["world_position"]), np.nan)

    @cached_property
    def geometric_normal(self) -> np.ndarray:
        return self._image(self.hits["world_geometric_normal"] @ self.camera.rotation.T, 0.0)

    def astype(self, dtype) -> "GBuffer":
        """The same G-buffer whose float images are of ``dtype`` (e.g. float32 for precision tests)."""
        return GBuffer(self.camera, depth=self.depth, normal=self.normal, valid=self.valid,
                       primitive=self.primitive, hits=self.hits, dtype=dtype)

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
