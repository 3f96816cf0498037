"""G-buffers: what a rasterizer would write, rendered with Embree primary rays.

A :class:`GBuffer` is the only input of the screen-space estimators. It follows the
conventions of ``docs/conventions.md``: view space has the camera at the origin, x right,
y up and z the depth, positive in front of the camera; ``depth`` is that z (linear depth,
not the distance along the ray); background pixels have ``depth = +inf``, zero normals,
NaN positions and ``valid = False``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GBuffer", "render_gbuffer"]


@dataclass(frozen=True, eq=False)
class GBuffer:
    """Per-pixel geometry of one view.

    Attributes
    ----------
    depth : (H, W) float64
        Linear view depth z > 0; +inf on background.
    normal : (H, W, 3) float64
        View-space unit shading normal facing the camera (interpolated from the scene's
        corner normals; the geometric normal where the interpolated one would face away);
        0 on background.
    geometric_normal : (H, W, 3) float64
        View-space unit normal of the hit triangle, facing the camera; 0 on background.
    position : (H, W, 3) float64
        View-space position; NaN on background.
    world_position, world_normal, world_geometric_normal : (H, W, 3) float64
        The same in world space.
    valid : (H, W) bool
        True where a surface was hit.
    primitive : (H, W) int64
        Index of the hit triangle in ``scene.triangles``; -1 on background.
    camera : Camera
    """

    depth: np.ndarray
    normal: np.ndarray
    geometric_normal: np.ndarray
    position: np.ndarray
    world_position: np.ndarray
    world_normal: np.ndarray
    world_geometric_normal: np.ndarray
    valid: np.ndarray
    primitive: np.ndarray
    camera: object

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W)."""
        return self.depth.shape

    def astype(self, dtype) -> "GBuffer":
        """A copy with every float buffer cast to ``dtype`` (e.g. float32 for precision tests)."""
        cast = {k: getattr(self, k).astype(dtype) for k in
                ("depth", "normal", "geometric_normal", "position", "world_position",
                 "world_normal", "world_geometric_normal")}
        return GBuffer(valid=self.valid.copy(), primitive=self.primitive.copy(), camera=self.camera, **cast)


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

    scene = _as_scene(scene)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    tracer = scene.tracer
    H, W = camera.height, camera.width
    origins, dirs = camera.primary_rays(dtype=np.float32)
    dirs = dirs.reshape(-1, 3)
    hits = tracer.intersect(origins.reshape(-1, 3), dirs)
    idx = np.flatnonzero(hits.primitive >= 0)          # covered pixels, row-major
    prim = hits.primitive[idx]
    d = dirs[idx].astype(np.float64)

    # geometric normal, flipped to face the camera (against the ray direction)
    n_geo = scene.face_normals[prim]
    sign = np.where(np.einsum("ij,ij->i", n_geo, d) > 0, -1.0, 1.0)[:, None]
    n_geo *= sign
    n_geo += 0.0  # no negative zeros in the output
    # Hit point: origin + t * direction in float64, then projected onto the triangle's plane,
    # which removes Embree's float32 error across the plane (the error that matters for
    # self-intersection) at the cost of two (k, 3) gathers instead of a (k, 3, 3) one.
    o = origins.reshape(-1, 3)[idx].astype(np.float64) if origins.strides[0] else camera.eye
    p = o + hits.distance[idx, None] * d
    p -= np.einsum("ij,ij->i", p - scene.triangles[prim, 0], n_geo)[:, None] * n_geo
    # shading normal: corner normals interpolated with Embree's barycentrics, only on
    # triangles whose corners are not all the face normal (flat meshes skip the gather)
    n_sh = n_geo.copy()
    smooth = scene.smooth_faces[prim]
    if smooth.any():
        js = np.flatnonzero(smooth)
        u, v = hits.barycentric[idx[js], 0:1], hits.barycentric[idx[js], 1:2]
        corners = scene.corner_normals[prim[js]]
        ns = ((1.0 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]) * sign[js]
        length = np.sqrt(np.einsum("ij,ij->i", ns, ns))[:, None]
        ok = (length[:, 0] > 0) & (np.einsum("ij,ij->i", ns, d[js]) < 0)
        # where the interpolated normal would face away from the camera, keep the geometric one
        n_sh[js[ok]] = ns[ok] / length[ok]

    view_p = camera.world_to_view(p)
    rot_t = camera.rotation.T

    def image(values, fill):
        out = np.full((H * W, 3), fill)
        out[idx] = values
        return out.reshape(H, W, 3)

    depth = np.full(H * W, np.inf)
    depth[idx] = view_p[:, 2]
    primitive = np.full(H * W, -1, dtype=np.int64)
    primitive[idx] = prim
    valid = np.zeros(H * W, dtype=bool)
    valid[idx] = True
    return GBuffer(depth=depth.reshape(H, W), normal=image(n_sh @ rot_t, 0.0),
                   geometric_normal=image(n_geo @ rot_t, 0.0), position=image(view_p, np.nan),
                   world_position=image(p, np.nan), world_normal=image(n_sh, 0.0),
                   world_geometric_normal=image(n_geo, 0.0), valid=valid.reshape(H, W),
                   primitive=primitive.reshape(H, W), camera=camera)
