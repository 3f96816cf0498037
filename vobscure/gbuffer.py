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
    origins, dirs = camera.primary_rays()
    H, W = camera.height, camera.width
    hits = tracer.intersect(origins.reshape(-1, 3), dirs.reshape(-1, 3))
    valid = hits.hit
    prim = hits.primitive[valid]
    dirs_v = dirs.reshape(-1, 3)[valid]

    world_pos = np.full((H * W, 3), np.nan)
    world_pos[valid] = tracer.hit_points(hits)[valid]

    # geometric normal, flipped to face the camera (against the ray direction)
    n_geo = scene.face_normals[prim]
    flip = np.einsum("ij,ij->i", n_geo, dirs_v) > 0
    sign = np.where(flip, -1.0, 1.0)[:, None]
    n_geo = n_geo * sign
    # shading normal: corner normals interpolated with Embree's barycentrics
    u, v = hits.barycentric[valid, 0:1], hits.barycentric[valid, 1:2]
    corners = scene.corner_normals[prim]
    n_sh = (1.0 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]
    n_sh *= sign
    length = np.linalg.norm(n_sh, axis=1, keepdims=True)
    n_sh = n_sh / np.where(length > 0, length, 1.0)
    away = (length[:, 0] == 0) | (np.einsum("ij,ij->i", n_sh, dirs_v) >= 0)
    n_sh[away] = n_geo[away]

    def full(values, fill):
        out = np.full((H * W, 3), fill, dtype=np.float64)
        out[valid] = values
        return out.reshape(H, W, 3)

    world_normal = full(n_sh, 0.0)
    world_geo = full(n_geo, 0.0)
    position = np.full((H * W, 3), np.nan)
    position[valid] = camera.world_to_view(world_pos[valid])
    view_n = full(camera.world_to_view_dir(n_sh), 0.0)
    view_g = full(camera.world_to_view_dir(n_geo), 0.0)
    depth = np.full(H * W, np.inf)
    depth[valid] = position[valid, 2]
    primitive = np.full(H * W, -1, dtype=np.int64)
    primitive[valid] = prim
    return GBuffer(depth=depth.reshape(H, W), normal=view_n, geometric_normal=view_g,
                   position=position.reshape(H, W, 3), world_position=world_pos.reshape(H, W, 3),
                   world_normal=world_normal, world_geometric_normal=world_geo,
                   valid=valid.reshape(H, W), primitive=primitive.reshape(H, W), camera=camera)
