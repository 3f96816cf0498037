"""Rendering a G-buffer with Embree: one primary ray per pixel centre.

:func:`render_gbuffer` traces the camera's primary rays through the scene's tracer
(:mod:`vobscure.raytrace`) in bands of rows, shades each hit (the hit point moved onto its
triangle's plane, geometric and interpolated normals facing the camera) and returns a
:class:`~vobscure.gbuffer.GBuffer` whose world-space images are built on first access from
the per-hit data. With ``layers=K`` it peels: every ray continues past its hits to the first
K surfaces, and the G-buffer carries their solid intervals
(:class:`~vobscure.layers.SolidIntervals`, with the surfaces as
:class:`~vobscure.layers.PeeledLayers`; ``docs/layers.md``).
"""

from __future__ import annotations

import numpy as np

from .gbuffer import GBuffer

__all__ = ["render_gbuffer", "PEEL_RAYS"]

#: Rays peeled together (all their layers, then their intervals): bounds the temporaries of
#: ``render_gbuffer(layers=K)`` to a few megabytes per thread whatever the image's size.
PEEL_RAYS = 4096


def render_gbuffer(scene, camera, *, layers: int = 1) -> GBuffer:
    """Render a G-buffer of ``scene`` seen by ``camera`` (one Embree ray per pixel centre).

    Parameters
    ----------
    scene : Scene or trimesh.Trimesh
    camera : Camera
    layers : int, optional
        K >= 1, the surfaces found along each pixel's ray (depth peeling, Everitt 2001). 1
        (default): the first surface only, ``intervals`` None. K > 1: each ray continues
        past its hit (from just beyond the hit triangle's plane,
        :meth:`vobscure.raytrace.Tracer.continue_rays`; alpha-tested holes are passed as every
        ray passes them) until it has crossed K surfaces or leaves the scene, and
        ``gb.intervals`` holds the solid intervals they bound
        (:func:`vobscure.layers.intervals_from_layers`: the enter/leave rule, the camera inside
        a solid, open meshes as zero-thickness intervals) with the surfaces in
        ``gb.intervals.layers`` (:class:`vobscure.layers.PeeledLayers`). The first layer is
        the G-buffer of ``layers=1``, bit for bit.

    Returns
    -------
    GBuffer

    Notes
    -----
    Memory: ``layers=K`` adds to the one-layer G-buffer 9 bytes per pixel per layer for the
    surfaces (float32 depth, int32 triangle, bool entering; 10 with an open mesh in the scene,
    whose flag is kept too) and 16 bytes per pixel per interval slot for the float64 intervals
    (M slots, the most intervals any pixel has: about K / 2 on closed scenes).
    ``benchmarks/bench_layers.py`` measures the peak (``docs/layers.md``). Time: one more
    Embree query per layer, on the rays still going.

    A surface closer than the tracer's offset (1e-5 of the scene's scale) behind a hit is not
    seen: of two faces that touch (a box standing on a floor) the peeling finds one, which
    the enter/leave rule of :func:`~vobscure.layers.intervals_from_layers` absorbs.

    References
    ----------
    Everitt, C. (2001). Interactive order-independent transparency. NVIDIA technical report
    (depth peeling). Mara, M., McGuire, M., Nowrouzezahrai, D. and Luebke, D. (2016). Deep
    G-buffers for stable global illumination approximation. HPG 2016.

    Examples
    --------
    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 4), ortho_height=2.0)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> gb.depth.round(6).tolist()[0]
    [3.0, 3.0, 3.0, 3.0]
    >>> gb.world_normal[0, 0].round(6).tolist()
    [0.0, 1.0, 0.0]
    >>> layered = vo.render_gbuffer(vo.scenes.slab(), cam, layers=2)
    >>> s = layered.intervals                   # the slab (y in [-1, 0]) seen through: [top, bottom]
    >>> float(s.front[0, 0, 0]), round(float(s.back[0, 0, 0]), 6), s.layers.entering[:, 0, 0].tolist()
    (3.0, 4.0, [True, False])
    """
    from .camera import Camera
    from .scenes import as_scene
    from ._validate import check_int
    from .raytrace import CHUNK_RAYS, default_threads, parallel_map

    scene = as_scene(scene)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    K = check_int(layers, "layers")
    H, W = camera.height, camera.width
    depth = np.full(H * W, np.inf)
    normal = np.zeros((H * W, 3))
    valid = np.zeros(H * W, dtype=bool)
    primitive = np.full(H * W, -1, dtype=np.int64)
    peel = _Peeling(scene, camera, K, H * W) if K > 1 else None
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
        origins, dirs = origins.reshape(-1, 3), dirs.reshape(-1, 3)
        hits = scene.tracer.intersect(origins, dirs, threads=1)
        part = _shade(scene, camera, origins, dirs, hits)
        if peel is not None:
            peel.band(rows.start * W, origins, dirs, hits, part["index"], part["depth"])
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
                   intervals=None if peel is None else peel.intervals(H, W))


class _Peeling:
    """The layers beyond the first of :func:`render_gbuffer`: per band, the rays continued
    past their hits K - 1 times, the surfaces stored (float32 depth, int32 triangle, entering,
    open) and the band's intervals made from its float64 depths."""

    def __init__(self, scene, camera, K: int, n: int):
        self.scene, self.camera, self.K = scene, camera, K
        self.depth = np.full((K, n), np.inf, dtype=np.float32)
        self.primitive = np.full((K, n), -1, dtype=np.int32)
        self.entering = np.zeros((K, n), dtype=bool)
        names = list(scene.meshes)
        open_ids = [names.index(k) for k in scene.open_meshes]
        #: per triangle: whether its mesh bounds no solid (None: every mesh is closed)
        self.open_triangle = np.isin(scene.mesh_index, open_ids) if open_ids else None
        self.open_surface = np.zeros((K, n), dtype=bool) if open_ids else None
        self.pieces: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _store(self, k, flat, prim, z, d64, z_band, local):
        scene = self.scene
        z_band[k, local] = z
        self.depth[k, flat] = z
        self.primitive[k, flat] = prim
        # entering: the winding (outward) normal points against the ray
        self.entering[k, flat] = np.einsum("ij,ij->i", scene.face_normals[prim], d64) < 0
        if self.open_surface is not None:
            self.open_surface[k, flat] = self.open_triangle[prim]

    def band(self, offset, origins, dirs, hits, local, depth0):
        """Peel a band's rays (flat pixels ``offset`` on) in chunks of :data:`PEEL_RAYS`, so that
        the temporaries are bounded whatever the band's size."""
        from .raytrace import Hits

        z0 = np.full(len(dirs), np.inf)
        z0[local] = depth0
        for a in range(0, len(dirs), PEEL_RAYS):
            s = slice(a, min(a + PEEL_RAYS, len(dirs)))
            self._chunk(offset + a, origins[s], dirs[s],
                        Hits(hits.distance[s], hits.primitive[s], hits.barycentric[s]), z0[s])

    def _chunk(self, offset, origins, dirs, hits, z0):
        from .layers import ray_intervals

        scene, camera, tracer = self.scene, self.camera, self.scene.tracer
        n = len(dirs)
        z_band = np.full((self.K, n), np.inf)
        h = np.flatnonzero(hits.hit)
        self._store(0, offset + h, hits.primitive[h], z0[h], dirs[h].astype(np.float64), z_band, h)
        going, o, d = np.arange(n), origins, dirs
        for k in range(1, self.K):
            keep = np.flatnonzero(hits.hit)
            o, _ = tracer.continue_rays(o, d, hits)
            going, d = going[keep], d[keep]
            if not len(going):
                break
            hits = tracer.intersect(o, d, threads=1)
            h = np.flatnonzero(hits.hit)
            prim = hits.primitive[h]
            d64 = d[h].astype(np.float64)
            # the hit in float64, projected onto its triangle's plane (as the first layer's)
            n_face = scene.face_normals[prim]
            p = o[h].astype(np.float64) + hits.distance[h, None] * d64
            p -= (np.einsum("ij,ij->i", p, n_face) - scene.plane_offsets[prim])[:, None] * n_face
            self._store(k, offset + going[h], prim, (p - camera.eye) @ camera.forward, d64, z_band, going[h])
        opened = None if self.open_surface is None else self.open_surface[:, offset:offset + n]
        hit = self.primitive[:, offset:offset + n] >= 0
        entering = self.entering[:, offset:offset + n]
        opened = np.zeros_like(hit) if opened is None else opened
        self.pieces[offset] = ray_intervals(z_band, hit, entering, opened,
                                              self._origin_inside(origins, hit[0] & ~opened[0] & ~entering[0],
                                                                  self.primitive[0, offset:offset + n]))

    def _origin_inside(self, origins, first_leaves, prim) -> np.ndarray:
        """(n,) bool: where the first surface leaves a solid, whether the ray's origin is inside
        that surface's mesh (trimesh's ``contains``, once per distinct origin and mesh)."""
        out = np.zeros(len(first_leaves), dtype=bool)
        rays = np.flatnonzero(first_leaves)
        if not len(rays):
            return out
        names = list(self.scene.meshes)
        mesh = self.scene.mesh_index[prim[rays]]
        for m in np.unique(mesh):
            sel = rays[mesh == m]
            points, which = np.unique(np.asarray(origins[sel], dtype=np.float64), axis=0, return_inverse=True)
            out[sel] = self.scene.meshes[names[m]].contains(points)[which.reshape(-1)]
        return out

    def intervals(self, H, W):
        from .layers import PeeledLayers, SolidIntervals

        K, n = self.K, H * W
        M = max(f.shape[0] for f, _ in self.pieces.values())
        front = np.full((M, n), np.inf)
        back = np.full((M, n), np.inf)
        for offset in sorted(self.pieces):
            f, b = self.pieces.pop(offset)
            front[:f.shape[0], offset:offset + f.shape[1]] = f
            back[:b.shape[0], offset:offset + b.shape[1]] = b
        layers = PeeledLayers(self.depth.reshape(K, H, W), self.primitive.reshape(K, H, W),
                              self.entering.reshape(K, H, W), face_normals=self.scene.face_normals,
                              rotation=self.camera.rotation,
                              open_surface=None if self.open_surface is None else self.open_surface.reshape(K, H, W))
        return SolidIntervals(front.reshape(M, H, W), back.reshape(M, H, W), layers=layers)


def _shade(scene, camera, origins, dirs, hits) -> dict:
    """The per-hit data of a block of pixels (flat, row-major) from their primary hits."""
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
