"""Rendering a G-buffer with Embree: one primary ray per pixel centre.

:func:`render_gbuffer` traces the camera's primary rays through the scene's tracer
(:mod:`vobscure.raytrace`) in bands of rows, shades each hit (the hit point moved onto its
triangle's plane, geometric and interpolated normals facing the camera) and returns a
:class:`~vobscure.gbuffer.GBuffer` whose world-space images are built on first access from
the per-hit data.
"""

from __future__ import annotations

import numpy as np

from .gbuffer import GBuffer

__all__ = ["render_gbuffer"]


def render_gbuffer(scene, camera, *, guard: int = 0) -> GBuffer:
    """Render a G-buffer of ``scene`` seen by ``camera`` (one Embree ray per pixel centre).

    Parameters
    ----------
    scene : Scene or trimesh.Trimesh
    camera : Camera
    guard : int, optional
        A guard band of this many pixels on each side (default 0, none): the frame of
        :meth:`camera.widened(guard) <vobscure.Camera.widened>` is rendered (the same focal
        length, the same rays for the inner pixels), so that the screen-space estimators'
        taps near the edge read real depth; they and the ground truth return the inner
        frame (``camera``'s), and :meth:`GBuffer.inner` crops the G-buffer.

    Returns
    -------
    GBuffer
        Of ``camera.widened(guard)``'s shape, with ``guard`` set.

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
    inner_camera, camera, guard = _widen(camera, guard)
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
                   valid=valid.reshape(H, W), primitive=primitive.reshape(H, W), hits=hits,
                   guard=guard, inner_camera=inner_camera if guard else None)


def _widen(camera, guard):
    """(the inner camera, the camera to trace, guard): the frame widened by ``guard`` pixels."""
    from ._validate import check_int

    guard = check_int(guard, "guard", minimum=0)
    return camera, camera.widened(guard), guard


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
