"""The one module that talks to Embree (through ``embreex``).

Everything else in vobscure asks this module for two things: whether rays are blocked
within a distance (*occlusion* queries) and where rays first hit (*hit* queries). The
module builds the Embree scene from a flat (m, 3, 3) triangle array, spreads batches of rays
over a thread pool (embreex releases the GIL while it traces), and owns the
self-intersection policy.

Precision
---------
Embree traces in float32 and always starts a ray at ``tnear = 0``. A ray that leaves a
surface point must therefore start a little off the surface, on the side it leaves
towards, or it may hit the very triangle it starts on. The offset is relative to the
scene's length scale, ``OFFSET_RELATIVE * scale`` with ``scale = max(extent, largest
|coordinate|)``: float32 rounds a coordinate of magnitude c by up to 6e-8 c, so an
absolute epsilon that works for a 0.15-unit bunny fails for a 1e4-unit building and vice
versa. ``OFFSET_RELATIVE = 1e-5`` leaves two orders of magnitude of margin over float32
rounding and is far below any gap a scene would resolve (the groove test in
``tests/test_raytrace.py`` checks that occluders at 1e-3 of the extent are still found).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ._validate import as_array, check_int

__all__ = ["Tracer", "Hits", "OFFSET_RELATIVE", "default_threads", "parallel_map"]

#: Ray-origin offset along the geometric normal, as a fraction of the scene scale.
OFFSET_RELATIVE = 1e-5
#: Rays handed to one embreex call; large enough to amortize the Python call, small
#: enough to spread over the pool and keep temporary buffers in cache.
CHUNK_RAYS = 1 << 15

_POOLS: dict[int, ThreadPoolExecutor] = {}


def default_threads() -> int:
    """Worker threads used when a call does not say: every core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


def _pool(threads: int) -> ThreadPoolExecutor:
    pool = _POOLS.get(threads)
    if pool is None:
        pool = _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix="vobscure-embree")
    return pool


def parallel_map(fn, items, *, threads: int | None = None, progress=None) -> list:
    """``[fn(item) for item in items]`` spread over the shared thread pool, in order.

    Worker functions should call the tracer's queries with ``threads=1``: the parallelism
    is here, one level up, so that sampling arithmetic (NumPy, which also releases the GIL
    in its loops) overlaps with tracing. ``progress`` is an optional tqdm bar, advanced
    once per finished item.
    """
    threads = default_threads() if threads is None else check_int(threads, "threads")
    items = list(items)
    if threads == 1 or len(items) <= 1:
        out = []
        for item in items:
            out.append(fn(item))
            if progress is not None:
                progress.update(1)
        return out
    futures = [_pool(threads).submit(fn, item) for item in items]
    out = []
    try:
        for f in futures:
            out.append(f.result())
            if progress is not None:
                progress.update(1)
    except BaseException:
        for f in futures:
            f.cancel()
        raise
    return out


@dataclass(frozen=True)
class Hits:
    """First hits of a batch of rays.

    Attributes
    ----------
    distance : (n,) float64
        Ray parameter of the hit (distance for unit directions); inf where the ray missed.
    primitive : (n,) int64
        Index of the hit triangle in the tracer's triangle array; -1 where the ray missed.
    barycentric : (n, 2) float64
        Embree's (u, v): the hit point is (1 - u - v) v0 + u v1 + v v2. Zero on a miss.
    """

    distance: np.ndarray
    primitive: np.ndarray
    barycentric: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        """(n,) bool, True where the ray hit a triangle."""
        return self.primitive >= 0


class Tracer:
    """An Embree scene over a fixed set of triangles, with batched, threaded queries.

    Parameters
    ----------
    triangles : (m, 3, 3) float
        Triangle corners. Copied once to float32 for Embree (the flat-array build path).
    face_normals : (m, 3) float, optional
        Unit geometric normals; computed from the winding when omitted.
    extent : float, optional
        The scene's length scale (bounding-box diagonal); computed when omitted.
    threads : int, optional
        Worker threads for queries; default :func:`default_threads`.

    Examples
    --------
    >>> import numpy as np
    >>> tri = np.array([[[-1, 0, -1], [1, 0, -1], [0, 0, 1]]], float)   # one triangle, y = 0
    >>> tracer = Tracer(tri)
    >>> tracer.occluded([[0, 1, 0], [0, 1, 0]], [[0, -1, 0], [0, 1, 0]]).tolist()
    [True, False]
    >>> round(float(tracer.intersect([[0, 1, 0]], [[0, -1, 0]]).distance[0]), 6)
    1.0
    """

    def __init__(self, triangles, *, face_normals=None, extent=None, threads: int | None = None):
        from embreex import mesh_construction, rtcore_scene

        tri = as_array(triangles, "triangles", shape=(None, 3, 3))
        if len(tri) == 0:
            raise ValueError("triangles must hold at least one triangle, got an empty array")
        self.triangles = tri
        if face_normals is None:
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            length = np.linalg.norm(n, axis=1, keepdims=True)
            face_normals = n / np.where(length > 0, length, 1.0)
        self.face_normals = as_array(face_normals, "face_normals", shape=(len(tri), 3))
        lo, hi = tri.reshape(-1, 3).min(0), tri.reshape(-1, 3).max(0)
        self.extent = float(extent) if extent is not None else float(np.linalg.norm(hi - lo))
        #: the length that float32 rounding is relative to
        self.scale = max(self.extent, float(np.abs(tri).max()))
        #: ray-origin offset along the geometric normal (world units)
        self.offset = OFFSET_RELATIVE * self.scale
        self.threads = check_int(threads, "threads") if threads is not None else default_threads()
        self._scene = rtcore_scene.EmbreeScene()
        mesh_construction.TriangleMesh(self._scene, np.ascontiguousarray(tri, dtype=np.float32))
        # Embree commits lazily on the first query; do it now, single-threaded, so that
        # concurrent first queries from the pool never race on the commit.
        self._scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), query="OCCLUDED")

    @property
    def embree_scene(self):
        """The underlying ``embreex.rtcore_scene.EmbreeScene`` (for benchmarks)."""
        return self._scene

    # -- ray-origin policy -------------------------------------------------------------
    def offset_origins(self, points, normals, directions=None) -> np.ndarray:
        """Ray origins for rays that leave surface points: moved off by :attr:`offset`.

        Parameters
        ----------
        points : (n, 3) float
        normals : (n, 3) float
            Unit normals pointing to the side the rays leave towards (the open side).
        directions : (n, k, 3) float, optional
            The unit directions of k rays per point. Each origin then also moves
            :attr:`offset` along its own ray, which matters where a point lies on two
            surfaces at once (the edge of a crease): the normal offset alone leaves the
            origin in the other surface's plane, where Embree reports a hit at t = 0.

        Returns
        -------
        (n, 3) float64, or (n, k, 3) float32 when ``directions`` are given.
        """
        base = np.asarray(points, np.float64) + self.offset * np.asarray(normals, np.float64)
        if directions is None:
            return base
        d = np.asarray(directions, np.float32)
        out = np.empty(d.shape, dtype=np.float32)
        step = np.float32(self.offset)
        base32 = base.astype(np.float32)
        for k in range(3):  # contiguous per-component passes (see sampling.shifted_hemisphere_directions)
            comp = d[..., k] * step
            comp += base32[:, None, k]
            out[..., k] = comp
        return out

    # -- queries -----------------------------------------------------------------------
    def _prepare(self, origins, directions, max_distance):
        """float32 C-contiguous (n, 3) rays and tfar: a float, or an (n,) float32 array."""
        o = np.ascontiguousarray(np.asarray(origins, dtype=np.float32).reshape(-1, 3))
        d = np.ascontiguousarray(np.asarray(directions, dtype=np.float32).reshape(-1, 3))
        if o.shape != d.shape:
            raise ValueError(f"origins and directions must have the same shape, got {o.shape} and {d.shape}")
        n = len(o)
        tfar = np.asarray(max_distance, dtype=np.float64)
        if np.any(np.isnan(tfar)) or np.any(tfar < 0):
            raise ValueError("max_distance must be >= 0 (inf allowed), got a negative or NaN value")
        if tfar.ndim == 0:
            return o, d, float(tfar)  # embreex fills a scalar itself: no per-ray array
        tfar = tfar.reshape(-1)
        if tfar.shape != (n,):
            raise ValueError(f"max_distance must be a scalar or one value per ray ({n}), got shape {tfar.shape}")
        return o, d, np.ascontiguousarray(tfar.astype(np.float32))

    def _chunks(self, n: int, threads: int | None):
        threads = self.threads if threads is None else check_int(threads, "threads")
        size = max(1024, min(CHUNK_RAYS, -(-n // threads)))
        return threads, [slice(i, min(i + size, n)) for i in range(0, n, size)]

    @staticmethod
    def _tfar(tfar, s):
        # embreex writes hit distances into an array tfar it was given: hand it a copy
        return tfar if isinstance(tfar, float) else tfar[s].copy()

    def occluded(self, origins, directions, max_distance=np.inf, *, threads: int | None = None) -> np.ndarray:
        """Whether each ray hits any triangle within ``max_distance``.

        Parameters
        ----------
        origins, directions : (n, 3) float
            Ray origins (already offset off any surface) and directions. float32
            C-contiguous input is used as is; anything else is converted once.
        max_distance : float or (n,) float
            Ray length limit (tfar); inf for unlimited.
        threads : int, optional
            Worker threads; default the tracer's.

        Returns
        -------
        (n,) bool
            True where the ray is blocked. (embreex's OCCLUDED query returns 0 for a
            blocked ray and -1 for a free one.)
        """
        o, d, tfar = self._prepare(origins, directions, max_distance)
        out = np.empty(len(o), dtype=bool)
        if len(o) == 0:
            return out
        threads, chunks = self._chunks(len(o), threads)

        def work(s):
            out[s] = self._scene.run(o[s], d[s], dists=self._tfar(tfar, s), query="OCCLUDED") != -1

        self._run(work, chunks, threads)
        return out

    def intersect(self, origins, directions, max_distance=np.inf, *, threads: int | None = None) -> Hits:
        """First hit of each ray within ``max_distance`` (see :class:`Hits`)."""
        o, d, tfar = self._prepare(origins, directions, max_distance)
        n = len(o)
        dist = np.empty(n, dtype=np.float64)
        prim = np.empty(n, dtype=np.int64)
        bary = np.empty((n, 2), dtype=np.float64)
        if n:
            threads, chunks = self._chunks(n, threads)

            def work(s):
                res = self._scene.run(o[s], d[s], dists=self._tfar(tfar, s), output=1)
                p = res["primID"]
                miss = p < 0  # embreex reports -1 (RTC_INVALID_GEOMETRY_ID) for a miss
                t, u, v = res["tfar"], res["u"], res["v"]
                t[miss] = np.inf  # embreex leaves tfar (or 1e37) on a miss
                u[miss] = 0.0
                v[miss] = 0.0
                prim[s] = p
                dist[s] = t
                bary[s, 0] = u
                bary[s, 1] = v

            self._run(work, chunks, threads)
        return Hits(distance=dist, primitive=prim, barycentric=bary)

    def hit_points(self, hits: Hits) -> np.ndarray:
        """(n, 3) float64 hit positions rebuilt from barycentrics (NaN on a miss).

        Rebuilding from the triangle in float64 puts the point on the triangle's plane to
        float64 precision, rather than at origin + t * direction, which carries Embree's
        float32 error in t.
        """
        p = np.full((len(hits.primitive), 3), np.nan)
        hit = hits.hit
        tri = self.triangles[hits.primitive[hit]]
        u, v = hits.barycentric[hit, 0:1], hits.barycentric[hit, 1:2]
        p[hit] = (1.0 - u - v) * tri[:, 0] + u * tri[:, 1] + v * tri[:, 2]
        return p

    @staticmethod
    def _run(work, chunks, threads):
        if threads == 1 or len(chunks) == 1:
            for s in chunks:
                work(s)
        else:
            # list() propagates the first exception raised in a worker
            list(_pool(threads).map(work, chunks))
