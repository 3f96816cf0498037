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

    def __init__(self, camera, index, world_position, world_normal, world_geometric_normal,
                 primitive, *, dtype=np.float64, _depth=None, _normal=None):
        self.camera = camera
        self.dtype = np.dtype(dtype)
        H, W = camera.height, camera.width
        self._index = np.asarray(index, dtype=np.int64)
        self._hits = {"world_position": np.asarray(world_position, np.float64),
                      "world_normal": np.asarray(world_normal, np.float64),
                      "world_geometric_normal": np.asarray(world_geometric_normal, np.float64)}
        valid = np.zeros(H * W, dtype=bool)
        valid[self._index] = True
        prim = np.full(H * W, -1, dtype=np.int64)
        prim[self._index] = primitive
        depth = np.full(H * W, np.inf, dtype=self.dtype)
        # linear depth: the view z of the hit, i.e. (p - eye) . forward
        if _depth is None:
            _depth = (self._hits["world_position"] - camera.eye) @ camera.forward
        depth[self._index] = _depth
        self.valid = _frozen(valid.reshape(H, W))
        self.primitive = _frozen(prim.reshape(H, W))
        self.depth = _frozen(depth.reshape(H, W))
        if _normal is None:
            _normal = self._hits["world_normal"] @ camera.rotation.T
        self.normal = self._image(_normal, 0.0)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return self.depth.shape

    @property
    def hits(self) -> dict:
        """Per-hit world-space data, pixels in row-major order: ``index`` (k,) flat pixel
        indices and (k, 3) float64 ``world_position``, ``world_normal``,
        ``world_geometric_normal``. Equal to ``gb.world_position.reshape(-1, 3)[index]``
        and so on, without building the images."""
        return {"index": self._index, **self._hits}

    def _image(self, values, fill) -> np.ndarray:
        H, W = self.camera.height, self.camera.width
        out = np.full((H * W, 3), fill, dtype=self.dtype)
        out[self._index] = values
        return _frozen(out.reshape(H, W, 3))

    @cached_property
    def world_position(self) -> np.ndarray:
        return self._image(self._hits["world_position"], np.nan)

    @cached_property
    def world_normal(self) -> np.ndarray:
        return self._image(self._hits["world_normal"], 0.0)

    @cached_property
    def world_geometric_normal(self) -> np.ndarray:
        return self._image(self._hits["world_geometric_normal"], 0.0)

    @cached_property
    def position(self) -> np.ndarray:
        return self._image(self.camera.world_to_view(self._hits["world_position"]), np.nan)

    @cached_property
    def geometric_normal(self) -> np.ndarray:
        return self._image(self._hits["world_geometric_normal"] @ self.camera.rotation.T, 0.0)

    def astype(self, dtype) -> "GBuffer":
        """The same G-buffer whose float images are of ``dtype`` (e.g. float32 for precision tests)."""
        return GBuffer(self.camera, self._index, primitive=self.primitive.reshape(-1)[self._index],
                       dtype=dtype, **self._hits)

    def __repr__(self) -> str:
        H, W = self.shape
        return f"GBuffer({W}x{H}, {int(self.valid.sum())} covered pixels, {self.dtype})"


def _frozen(a: np.ndarray) -> np.ndarray:
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
    from .groundtruth import _as_scene
    from .raytrace import CHUNK_RAYS, default_threads, parallel_map

    scene = _as_scene(scene)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    origins, dirs = camera.primary_rays(dtype=np.float32)
    origins, dirs = origins.reshape(-1, 3), dirs.reshape(-1, 3)
    n = len(dirs)
    # Tracing and shading of blocks of pixels run in parallel, each block on one thread.
    # Blocks of about CHUNK_RAYS pixels: with a few huge blocks the threads' temporaries are
    # fresh multi-megabyte allocations whose page faults serialize them (measured: 2 blocks
    # gave no speed-up on 2 cores, 8 blocks of 32k pixels gave 2x).
    threads = default_threads()
    count = max(2 * threads, -(-n // CHUNK_RAYS))
    bounds = np.linspace(0, n, count + 1).astype(np.int64)
    blocks = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
    parts = parallel_map(lambda s: _trace_block(scene, camera, origins, dirs, s), blocks, threads=threads)
    idx, p, n_sh, n_geo, prim, depth, normal = (np.concatenate(a) for a in zip(*parts))
    return GBuffer(camera, idx, world_position=p, world_normal=n_sh, world_geometric_normal=n_geo,
                   primitive=prim, _depth=depth, _normal=normal)


def _trace_block(scene, camera, origins, dirs, block: slice):
    """Primary hits of the pixels in ``block`` (flat, row-major) and their per-hit data."""
    hits = scene.tracer.intersect(origins[block], dirs[block], threads=1)
    local = np.flatnonzero(hits.primitive >= 0)
    prim = hits.primitive[local]
    d = dirs[block][local].astype(np.float64)
    o = camera.eye if camera.is_perspective else origins[block][local].astype(np.float64)

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
    depth = (p - camera.eye) @ camera.forward      # linear depth: the view z of the hit
    return local + block.start, p, n_sh, n_geo, prim, depth, n_sh @ camera.rotation.T
