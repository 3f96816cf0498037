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


def render_gbuffer(scene, camera, *, layers: int = 1, guard: int = 0) -> GBuffer:
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

    Notes
    -----
    Memory: ``layers=K`` adds to the one-layer G-buffer, per pixel, 1 byte for the first
    layer (whether the ray enters a solid there: its depth and triangle are the G-buffer's
    own ``depth`` and ``primitive``, not repeated), 9 bytes for each layer behind it (float32
    depth, int32 triangle, bool entering; whether a surface is open is made from its
    triangle) and 8 bytes per interval slot (float32 front and back; M slots, the most
    intervals any pixel has: about K / 2 on closed scenes). The intervals are made after the
    peeling, when the bands' temporaries are gone, and are the float64 depths' intervals
    rounded to float32 (relative 6e-8 of the depth; how the estimators read them:
    ``docs/layers.md``, "Memory"). ``benchmarks/bench_layers.py`` measures the peak. Time:
    one more Embree query per layer, on the rays still going. A request whose estimated peak
    (:func:`vobscure._memory.gbuffer_need`) exceeds the memory available is refused before
    any work with a ValueError (:class:`vobscure._memory.MemoryBudgetError`) that says what it
    needs and the largest size that fits (``docs/compare.md``, "Memory").

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
    from ._memory import gbuffer_need, require
    from ._validate import check_int
    from .raytrace import CHUNK_RAYS, default_threads, parallel_map

    scene = as_scene(scene)
    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    K = check_int(layers, "layers")
    inner_camera, camera, guard = _widen(camera, guard)
    H, W = camera.height, camera.width
    # refused before any work when the result and its temporaries cannot fit (docs/compare.md, "Memory")
    require(gbuffer_need(K), size=(W, H), what=f"rendering a {W} x {H} G-buffer" + (f" of {K} layers" if K > 1 else ""),
            reduce="the camera's size" + (" or layers" if K > 1 else ""))
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
            peel.band(rows.start * W, origins, dirs, hits)
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
                   intervals=None if peel is None else peel.intervals(depth, primitive, H, W, threads),
                   guard=guard, inner_camera=inner_camera if guard else None)


def _widen(camera, guard):
    """(the inner camera, the camera to trace, guard): the frame widened by ``guard`` pixels."""
    from ._validate import check_int

    guard = check_int(guard, "guard", minimum=0)
    return camera, camera.widened(guard), guard


class _Peeling:
    """The layers beyond the first of :func:`render_gbuffer`: per band, the rays continued
    past their hits K - 1 times and the surfaces stored (layer 0: entering only, its depth
    and triangle are the G-buffer's; layers 1 to K - 1: float32 depth, int32 triangle,
    entering); the intervals are made at the end (:meth:`intervals`), in float32."""

    def __init__(self, scene, camera, K: int, n: int):
        import threading

        self.scene, self.camera, self.K, self.n = scene, camera, K, n
        self.depth = np.full((K - 1, n), np.inf, dtype=np.float32)
        self.primitive = np.full((K - 1, n), -1, dtype=np.int32)
        self.entering = np.zeros((K, n), dtype=bool)
        names = list(scene.meshes)
        open_ids = [names.index(k) for k in scene.open_meshes]
        #: per triangle: whether its mesh bounds no solid (None: every mesh is closed)
        self.open_triangle = np.isin(scene.mesh_index, open_ids) if open_ids else None
        #: (n,) bool, made when a first surface leaves a solid whose mesh holds the ray's origin
        self.origin_inside = None
        self._lock = threading.Lock()

    def _opened(self, prim: np.ndarray) -> np.ndarray:
        """Whether the surfaces of triangles ``prim`` (-1: none) belong to an open mesh."""
        if self.open_triangle is None:
            return np.zeros(prim.shape, dtype=bool)
        return (prim >= 0) & self.open_triangle[np.maximum(prim, 0)]

    def _store(self, k, flat, prim, z, d64):
        # entering: the winding (outward) normal points against the ray
        self.entering[k, flat] = np.einsum("ij,ij->i", self.scene.face_normals[prim], d64) < 0
        if k:
            self.depth[k - 1, flat] = z
            self.primitive[k - 1, flat] = prim

    def band(self, offset, origins, dirs, hits):
        """Peel a band's rays (flat pixels ``offset`` on) in chunks of :data:`PEEL_RAYS`, so that
        the temporaries are bounded whatever the band's size."""
        from .raytrace import Hits

        for a in range(0, len(dirs), PEEL_RAYS):
            s = slice(a, min(a + PEEL_RAYS, len(dirs)))
            self._chunk(offset + a, origins[s], dirs[s],
                        Hits(hits.distance[s], hits.primitive[s], hits.barycentric[s]))

    def _chunk(self, offset, origins, dirs, hits):
        scene, camera, tracer = self.scene, self.camera, self.scene.tracer
        n = len(dirs)
        h = np.flatnonzero(hits.hit)
        prim0 = hits.primitive[h]
        self._store(0, offset + h, prim0, None, dirs[h].astype(np.float64))
        # where the first surface leaves a solid: is the ray's origin inside that solid?
        leaves = ~self.entering[0, offset + h] & ~self._opened(prim0)
        if leaves.any():
            inside = self._origin_inside(origins[h[leaves]], prim0[leaves])
            if inside.any():
                with self._lock:
                    if self.origin_inside is None:
                        self.origin_inside = np.zeros(self.n, dtype=bool)
                self.origin_inside[offset + h[leaves][inside]] = True
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
            self._store(k, offset + going[h], prim, (p - camera.eye) @ camera.forward, d64)

    def _origin_inside(self, origins, prim) -> np.ndarray:
        """(n,) bool: whether each ray's origin is inside the mesh of its first surface's
        triangle ``prim`` (trimesh's ``contains``, once per distinct origin and mesh)."""
        out = np.zeros(len(prim), dtype=bool)
        names = list(self.scene.meshes)
        mesh = self.scene.mesh_index[prim]
        for m in np.unique(mesh):
            sel = np.flatnonzero(mesh == m)
            points, which = np.unique(np.asarray(origins[sel], dtype=np.float64), axis=0, return_inverse=True)
            out[sel] = self.scene.meshes[names[m]].contains(points)[which.reshape(-1)]
        return out

    def _kinds(self, s: slice, primitive0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(hit, entering, open) (K, c) of the pixels ``s``."""
        prim = np.concatenate([primitive0[None, s], self.primitive[:, s]])
        hit = prim >= 0
        return hit, self.entering[:, s], self._opened(prim)

    def intervals(self, depth0, primitive0, H, W, threads):
        """The :class:`~vobscure.layers.SolidIntervals` of the stored layers, float32, with the
        layers attached; ``depth0``, ``primitive0`` (H * W,): the G-buffer's own images.

        Made after the peeling, when the bands' temporaries are gone, in two passes over
        chunks of :data:`PEEL_RAYS` pixels: the interval count of every pixel (the slots M),
        then the intervals, written straight into the (M, H, W) float32 images. Rounding to
        float32 commutes with the rule (it only takes maxima of the depths and copies them),
        so these are the float64 intervals of the same surfaces rounded to float32.
        """
        from .layers import PeeledLayers, SolidIntervals, interval_count, ray_intervals
        from .raytrace import parallel_map

        K, n = self.K, H * W
        chunks = [slice(a, min(a + PEEL_RAYS, n)) for a in range(0, n, PEEL_RAYS)]

        def count(s):
            return int(interval_count(*self._kinds(s, primitive0)).max(initial=1))

        M = max(parallel_map(count, chunks, threads=threads), default=1)
        front = np.full((M, n), np.inf, dtype=np.float32)
        back = np.full((M, n), np.inf, dtype=np.float32)
        inside = self.origin_inside

        def fill(s):
            hit, entering, opened = self._kinds(s, primitive0)
            z = np.empty((K, s.stop - s.start))
            z[0] = depth0[s]
            z[1:] = self.depth[:, s]
            f, b = ray_intervals(z, hit, entering, opened, np.zeros(len(z[0]), bool) if inside is None else inside[s])
            front[:len(f), s] = f
            back[:len(b), s] = b

        parallel_map(fill, chunks, threads=threads)
        layers = PeeledLayers(self.depth.reshape(K - 1, H, W), self.primitive.reshape(K - 1, H, W),
                              self.entering.reshape(K, H, W), face_normals=self.scene.face_normals,
                              rotation=self.camera.rotation, first=(depth0.reshape(H, W), primitive0.reshape(H, W)),
                              open_triangle=self.open_triangle)
        return SolidIntervals(front.reshape(M, H, W), back.reshape(M, H, W), dtype=np.float32, layers=layers)


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
