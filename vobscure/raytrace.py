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

Alpha-tested triangles
----------------------
A tracer built with ``alpha=`` (a :class:`TriangleAlpha`) treats the texels of masked
triangles whose alpha is below their cutoff as holes: ``intersect`` and ``occluded`` continue
each ray past such a hit, in either direction through the triangle. The masked triangles live
in a second Embree scene; the opaque ones are traced once, the masked ones in passes. Each
pass starts the rays whose hit was a hole again just beyond it, with the rest of their
length: on the ray's own line, :attr:`Tracer.offset` past the rejected triangle's plane, so
that the ray goes on exactly as through a hole cut in the geometry (float32 cannot place an
origin closer to a plane than about 6e-8 of the scene's scale; ``offset`` is 1e-5 of it).
A ray within ``COS_GRAZING`` of the plane, which would need more than ten offsets along
itself, instead restarts ``offset`` along itself and ``offset`` off the plane on the far
side (the policy of :meth:`Tracer.offset_origins`). Every pass thus crosses a different
masked triangle, which bounds the passes by the number of masked triangles; a ray that
needs more is an error, not a silent answer. Geometry closer than ``offset`` behind a hole
is not seen from that hole, the same blind distance as every ray leaving a surface.
A tracer without masked triangles builds one scene and runs exactly the queries it would run
without ``alpha``.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ._validate import as_array, check_int

__all__ = ["Tracer", "Hits", "TriangleAlpha", "texel_lookup", "OFFSET_RELATIVE", "default_threads",
           "parallel_map"]

#: Ray-origin offset along the geometric normal, as a fraction of the scene scale.
OFFSET_RELATIVE = 1e-5
#: |cos| between a ray and a masked triangle's plane below which a ray that passes a hole
#: restarts off the plane along the normal rather than on its own line (where stepping
#: ``offset`` clear of the plane would take more than 10 offsets along the ray).
COS_GRAZING = 0.1
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


def _texel_index(uv: np.ndarray, height, width) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of the texel that contains each texture coordinate (nearest, repeat)."""
    u = uv[..., 0] - np.floor(uv[..., 0])   # repeat: the fractional part, in [0, 1]
    v = uv[..., 1] - np.floor(uv[..., 1])
    # u - floor(u) rounds to exactly 1.0 for a tiny negative u: clamp into the last texel
    col = np.minimum((u * width).astype(np.int64), np.asarray(width) - 1)
    # v up, row 0 the top of the image: v in [0, 1/h) is the bottom row h - 1
    row = np.asarray(height) - 1 - np.minimum((v * height).astype(np.int64), np.asarray(height) - 1)
    return row, col


def texel_lookup(texture, uv) -> np.ndarray:
    """Alpha of ``texture`` at texture coordinates ``uv``: nearest texel, repeat wrap.

    Parameters
    ----------
    texture : (h, w) float
        Row 0 is the top of the image (v = 1).
    uv : (..., 2) float
        OpenGL / OBJ convention: u to the right, v up, (0, 0) the bottom-left corner. The
        texel that contains (u mod 1, v mod 1) is returned: texel (row i, column j) covers
        u in [j / w, (j + 1) / w) and v in [1 - (i + 1) / h, 1 - i / h). No interpolation:
        the alpha test is exact on a texel's area, as a rasterizer's nearest-neighbour
        (``GL_NEAREST``, ``GL_REPEAT``) lookup.

    Returns
    -------
    (...,) float32

    Examples
    --------
    >>> import numpy as np
    >>> tex = np.array([[0.0, 1.0], [0.25, 0.5]])     # top row, bottom row
    >>> texel_lookup(tex, [[0.1, 0.9], [0.9, 0.9], [0.1, 0.1], [1.9, -0.9]]).tolist()
    [0.0, 1.0, 0.25, 0.5]
    """
    tex = np.asarray(texture, dtype=np.float32)
    if tex.ndim != 2 or tex.size == 0:
        raise ValueError(f"texture must be a non-empty (height, width) array, got shape {tex.shape}")
    uv = np.asarray(uv, dtype=np.float64)
    if uv.shape[-1:] != (2,):
        raise ValueError(f"uv must have shape (..., 2), got {uv.shape}")
    row, col = _texel_index(uv, tex.shape[0], tex.shape[1])
    return tex[row, col]


@dataclass(frozen=True, eq=False)
class TriangleAlpha:
    """The alpha test of a tracer's triangles, one entry per triangle.

    Parameters
    ----------
    mask : (m,) int
        Index into ``textures`` of each triangle's alpha texture; -1 for an opaque triangle.
    uv : (m, 3, 2) float
        Texture coordinates of each triangle's corners, in the order of its vertices (the
        rows of opaque triangles are not read). Convention of :func:`texel_lookup`.
    textures : sequence of (h, w) float
        Alpha in [0, 1]; row 0 is the top of the image.
    cutoffs : sequence of float
        One per texture: a texel whose alpha is below it is a hole; ``alpha >= cutoff`` is
        solid (glTF 2.0, ``material.alphaCutoff``), so cutoff 0 makes every texel solid. The
        comparison is made once, in float64, when the tracer is built.

    Examples
    --------
    >>> import numpy as np
    >>> uv = np.array([[[0, 0], [1, 0], [0, 1]]] * 2, float)
    >>> a = TriangleAlpha([-1, 0], uv, [np.array([[1.0, 0.0]])], [0.5])
    >>> a.solid([0, 1, 1], [[0.5, 0.1], [0.1, 0.1], [0.8, 0.1]]).tolist()   # u > 0.5 is a hole
    [True, True, False]
    """

    mask: np.ndarray
    uv: np.ndarray
    textures: tuple
    cutoffs: tuple

    def __post_init__(self):
        mask = np.asarray(self.mask)
        if mask.ndim != 1 or (mask.size and mask.dtype.kind not in "iu"):
            raise ValueError(f"alpha mask must be a 1-D integer array (one texture index per triangle, "
                             f"-1 opaque), got shape {mask.shape} and dtype {mask.dtype}")
        mask = mask.astype(np.int64)
        uv = as_array(self.uv, "alpha uv", shape=(len(mask), 3, 2))
        textures = tuple(np.asarray(t, dtype=np.float32) for t in self.textures)
        cutoffs = np.asarray(self.cutoffs, dtype=np.float64).reshape(-1)
        if len(cutoffs) != len(textures):
            raise ValueError(f"alpha needs one cutoff per texture, got {len(cutoffs)} cutoffs "
                             f"for {len(textures)} textures")
        if np.any(~np.isfinite(cutoffs)) or np.any((cutoffs < 0) | (cutoffs > 1)):
            raise ValueError("alpha cutoffs must be in [0, 1]")
        for i, tex in enumerate(textures):
            if tex.ndim != 2 or tex.size == 0:
                raise ValueError(f"alpha texture {i} must be a non-empty (height, width) array, "
                                 f"got shape {tex.shape}")
        if mask.size and (mask.min() < -1 or mask.max() >= len(textures)):
            raise ValueError(f"alpha mask holds texture indices outside [-1, {len(textures) - 1}]")
        object.__setattr__(self, "mask", mask)
        object.__setattr__(self, "uv", uv)
        object.__setattr__(self, "textures", textures)
        object.__setattr__(self, "cutoffs", tuple(float(c) for c in cutoffs))
        # Per masked triangle ("local" index, in triangle order): uv0 and the edges uv1 - uv0,
        # uv2 - uv0, and (first texel, height, width) of its texture in one flat array of
        # solid flags (alpha >= that texture's cutoff), so that a hit's test is two row
        # gathers and one flag gather, whatever its texture.
        masked = np.flatnonzero(mask >= 0)
        local = np.full(len(mask), -1, dtype=np.int64)
        local[masked] = np.arange(len(masked))
        c = uv[masked]
        sizes = np.array([t.size for t in textures], dtype=np.int64)
        first = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        shape = np.array([t.shape for t in textures], dtype=np.int64).reshape(-1, 2)
        which = mask[masked]
        object.__setattr__(self, "_local", local)
        object.__setattr__(self, "_uv_affine", np.concatenate([c[:, 0], c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]], axis=1))
        object.__setattr__(self, "_texture_of", np.column_stack([first[which], shape[which]]).reshape(-1, 3))
        object.__setattr__(self, "_solid_texels", np.concatenate(
            [t.ravel().astype(np.float64) >= cut for t, cut in zip(textures, cutoffs)]) if textures else np.zeros(0, bool))

    @property
    def masked(self) -> np.ndarray:
        """(m,) bool: the triangles with an alpha test."""
        return self.mask >= 0

    def __repr__(self) -> str:
        return (f"TriangleAlpha(triangles={len(self.mask)}, masked={int(np.count_nonzero(self.masked))}, "
                f"textures={[t.shape for t in self.textures]}, cutoffs={list(self.cutoffs)})")

    def solid(self, primitive, barycentric) -> np.ndarray:
        """Whether each hit lands on a solid texel (True on opaque triangles).

        Parameters
        ----------
        primitive : (n,) int
            Triangle indices (no misses).
        barycentric : (n, 2) float
            Embree's (u, v) of each hit: the texture coordinates are interpolated as
            (1 - u - v) uv0 + u uv1 + v uv2, then looked up as in :func:`texel_lookup`.

        Returns
        -------
        (n,) bool
        """
        prim = np.asarray(primitive, dtype=np.int64)
        bary = np.asarray(barycentric, dtype=np.float64).reshape(-1, 2)
        out = np.ones(len(prim), dtype=bool)
        local = self._local[prim]
        k = np.flatnonzero(local >= 0)
        if len(k):
            out[k] = self._solid_local(local[k], bary[k, 0], bary[k, 1])
        return out

    def _solid_local(self, local, b1, b2) -> np.ndarray:
        """:meth:`solid` for hits on masked triangles given by their local index (the order of
        the masked triangles), with barycentrics b1, b2 as separate (n,) arrays."""
        a = self._uv_affine[local]                       # (n, 6): uv0, uv1 - uv0, uv2 - uv0
        b1 = np.asarray(b1, dtype=np.float64)
        b2 = np.asarray(b2, dtype=np.float64)
        # (1 - b1 - b2) uv0 + b1 uv1 + b2 uv2, written from uv0 along the two edges
        uv = np.empty((len(local), 2))
        uv[:, 0] = a[:, 0] + b1 * a[:, 2] + b2 * a[:, 4]
        uv[:, 1] = a[:, 1] + b1 * a[:, 3] + b2 * a[:, 5]
        tex = self._texture_of[local]                    # (n, 3): first texel, height, width
        row, col = _texel_index(uv, tex[:, 1], tex[:, 2])
        return self._solid_texels[tex[:, 0] + row * tex[:, 2] + col]


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
    alpha : TriangleAlpha, optional
        The alpha test of the triangles: texels below the cutoff of a masked triangle are
        holes for every query (see the module's notes). Without masked triangles the tracer
        is the plain one.

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

    def __init__(self, triangles, *, face_normals=None, extent=None, threads: int | None = None,
                 alpha: TriangleAlpha | None = None):
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
        if alpha is not None and not isinstance(alpha, TriangleAlpha):
            raise ValueError(f"alpha must be a vobscure.raytrace.TriangleAlpha or None, got {type(alpha).__name__}")
        if alpha is not None and len(alpha.mask) != len(tri):
            raise ValueError(f"alpha describes {len(alpha.mask)} triangles; the tracer has {len(tri)}")
        #: the alpha test of the triangles (None: all opaque)
        self.alpha = alpha if alpha is not None and alpha.masked.any() else None
        #: Embree scene of the opaque triangles (all of them without alpha); None if there are none
        self._scene = None
        #: Embree scene of the alpha-tested triangles; None without alpha
        self._masked = None
        if self.alpha is None:
            self._scene = _embree_scene(tri)
            return
        masked = self.alpha.masked
        self._opaque_ids = np.flatnonzero(~masked)
        self._masked_ids = np.flatnonzero(masked)
        if len(self._opaque_ids):
            self._scene = _embree_scene(tri[self._opaque_ids])
        self._masked = _embree_scene(tri[self._masked_ids])
        self._masked_normals = self.face_normals[self._masked_ids]
        self._masked_planes = np.einsum("ij,ij->i", self._masked_normals, tri[self._masked_ids, 0])
        #: passes of the alpha loop after which a ray that is still going is an error: every
        #: pass crosses one masked triangle (the restart is off its plane), so a ray that
        #: needs more passes than there are masked triangles is caught in a cycle
        self._max_passes = len(self._masked_ids) + 2

    @property
    def embree_scene(self):
        """The underlying ``embreex.rtcore_scene.EmbreeScene`` (for benchmarks): of the opaque
        triangles when the tracer has alpha-tested ones."""
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

        if self._masked is not None:
            def work(s):
                out[s] = self._occluded_alpha(o[s], d[s], tfar if isinstance(tfar, float) else tfar[s])
        else:
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
                if self._masked is not None:
                    dist[s], prim[s], bary[s] = self._intersect_alpha(
                        o[s], d[s], tfar if isinstance(tfar, float) else tfar[s])
                    return
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

    # -- alpha-tested triangles ----------------------------------------------------------
    def _occluded_alpha(self, o, d, tfar) -> np.ndarray:
        """occluded() of one chunk: opaque scene, then the alpha loop for the rays still free."""
        n = len(o)
        if self._scene is not None:
            blocked = self._scene.run(o, d, dists=self._tfar_copy(tfar, n), query="OCCLUDED") != -1
        else:
            blocked = np.zeros(n, dtype=bool)
        # only rays that meet a masked triangle at all need the alpha test
        free = np.flatnonzero(~blocked)
        if len(free):
            near = self._masked.run(o[free], d[free], dists=self._tfar_copy(tfar, n, free), query="OCCLUDED") != -1
            free = free[near]
        if len(free):
            limit = np.broadcast_to(np.float64(tfar), (n,))[free] if isinstance(tfar, float) else tfar[free]
            _, prim, _ = self._masked_first(o[free], d[free], limit)
            blocked[free] = prim >= 0
        return blocked

    def _intersect_alpha(self, o, d, tfar):
        """intersect() of one chunk: the nearer of the opaque hit and the first solid masked hit."""
        n = len(o)
        dist = np.full(n, np.inf)
        prim = np.full(n, -1, dtype=np.int64)
        bary = np.zeros((n, 2))
        if self._scene is not None:
            res = self._scene.run(o, d, dists=self._tfar_copy(tfar, n), output=1)
            hit = res["primID"] >= 0
            prim[hit] = self._opaque_ids[res["primID"][hit]]
            dist[hit] = res["tfar"][hit]
            bary[hit, 0] = res["u"][hit]
            bary[hit, 1] = res["v"][hit]
        # a masked hit counts only in front of the opaque one
        limit = np.minimum(np.float64(tfar) if isinstance(tfar, float) else tfar.astype(np.float64), dist)
        m_dist, m_prim, m_bary = self._masked_first(o, d, limit)
        nearer = m_prim >= 0
        dist[nearer], prim[nearer], bary[nearer] = m_dist[nearer], m_prim[nearer], m_bary[nearer]
        return dist, prim, bary

    @staticmethod
    def _tfar_copy(tfar, n, rows=None):
        if isinstance(tfar, float):
            return tfar
        return (tfar if rows is None else tfar[rows]).astype(np.float32)

    def _masked_first(self, o, d, limit):
        """First solid hit on the masked triangles within ``limit`` (ray parameter), in passes.

        o, d : (n, 3) float32 rays; limit : (n,) float. Returns (distance (n,) float64, inf on a
        miss; primitive (n,) int64 into the full triangle array, -1 on a miss; barycentric (n, 2)).
        The rays still going are kept compact: each pass works on them alone.
        """
        n = len(o)
        dist = np.full(n, np.inf)
        prim = np.full(n, -1, dtype=np.int64)
        bary = np.zeros((n, 2))
        limit = np.asarray(limit, dtype=np.float64)
        ray = np.flatnonzero(limit > 0)                  # which input ray each active row is
        org, dirs, lim = o[ray], d[ray], limit[ray]
        start = np.zeros(len(ray))                       # ray parameter of the current origin
        alpha, normals, planes = self.alpha, self._masked_normals, self._masked_planes
        for _ in range(self._max_passes):
            if not len(ray):
                return dist, prim, bary
            res = self._masked.run(org, dirs, dists=(lim - start).astype(np.float32), output=1)
            local = res["primID"]
            hit = local >= 0
            t, b1, b2 = res["tfar"], res["u"], res["v"]
            if not hit.all():
                ray, org, dirs, lim, start = ray[hit], org[hit], dirs[hit], lim[hit], start[hit]
                local, t, b1, b2 = local[hit], t[hit], b1[hit], b2[hit]
            solid = alpha._solid_local(local, b1, b2)
            done = ray[solid]
            dist[done] = start[solid] + t[solid]
            prim[done] = self._masked_ids[local[solid]]
            bary[done, 0] = b1[solid]
            bary[done, 1] = b2[solid]
            # rejected hits: start again just beyond the hole, off the far side of its triangle
            rej = ~solid
            ray, org, dirs, lim, start, local = ray[rej], org[rej], dirs[rej], lim[rej], start[rej], local[rej]
            org, advance = _past_plane(org, dirs, t[rej], normals[local], planes[local], self.offset)
            start = start + advance
            going = start < lim
            if not going.all():
                ray, org, dirs, lim, start = ray[going], org[going], dirs[going], lim[going], start[going]
        if len(ray):
            raise RuntimeError(f"the alpha test of {len(ray)} ray(s) did not finish after {self._max_passes} "
                               f"passes over {len(self._masked_ids)} masked triangles; the masked geometry "
                               "sends rays around a cycle (please report the scene)")
        return dist, prim, bary

    def continue_rays(self, origins, directions, hits: Hits) -> tuple[np.ndarray, np.ndarray]:
        """Origins that continue rays past their hits, for the next hit behind (depth peeling).

        Each hit ray restarts on its own line :attr:`offset` beyond the plane of the triangle it
        hit (within ``COS_GRAZING`` of that plane: ``offset`` along itself and ``offset`` off
        the plane on the far side), the policy of the alpha loop (module notes). Surfaces closer
        than that behind the hit (a coincident face of a touching solid) are not seen.

        Parameters
        ----------
        origins, directions : (n, 3) float
            The rays of the last query.
        hits : Hits
            Its result; only the hit rays (``hits.hit``) are continued.

        Returns
        -------
        origins : (k, 3) float32
            The new origins of the k hit rays, in the order of ``np.flatnonzero(hits.hit)``.
        advance : (k,) float64
            Ray parameter of each new origin along the old ray (for unit directions, the
            distance from the old origin): add it to the next query's distances.

        Examples
        --------
        >>> import numpy as np
        >>> tri = np.array([[[-1, 0, -1], [1, 0, -1], [0, 0, 1]],
        ...                 [[-1, -1, -1], [0, -1, 1], [1, -1, -1]]], float)   # y = 0 and y = -1
        >>> tracer = Tracer(tri)
        >>> o, d = np.array([[0.0, 1.0, 0.0]]), np.array([[0.0, -1.0, 0.0]])
        >>> first = tracer.intersect(o, d)
        >>> o2, advance = tracer.continue_rays(o, d, first)
        >>> second = tracer.intersect(o2, d)
        >>> int(second.primitive[0]), round(float(advance[0] + second.distance[0]), 5)
        (1, 2.0)
        """
        hit = np.flatnonzero(hits.hit)
        o = np.asarray(origins, dtype=np.float32).reshape(-1, 3)[hit]
        d = np.asarray(directions, dtype=np.float32).reshape(-1, 3)[hit]
        prim = hits.primitive[hit]
        planes = np.einsum("ij,ij->i", self.face_normals[prim], self.triangles[prim, 0])
        return _past_plane(o, d, hits.distance[hit], self.face_normals[prim], planes, self.offset)

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


def _past_plane(org, dirs, t, n_f, planes, offset) -> tuple[np.ndarray, np.ndarray]:
    """Rays (float32 ``org``, ``dirs``) that hit the planes ``n_f . x = planes`` at ray parameter
    ``t``, restarted just beyond them: the new float32 origins and their ray parameter along
    the old rays (see :meth:`Tracer.continue_rays`)."""
    org64, d64 = org.astype(np.float64), dirs.astype(np.float64)
    dd = np.einsum("ij,ij->i", d64, d64)
    unit = d64 / np.sqrt(dd)[:, None]
    cos = np.einsum("ij,ij->i", n_f, unit)
    side = np.where(cos >= 0.0, 1.0, -1.0)
    q = org64 + t[:, None] * d64                   # the hit, on the ray's line
    past = side * (np.einsum("ij,ij->i", n_f, q) - planes)   # how far beyond the plane
    # Stay on the ray's line, at `offset` beyond the plane; a ray within COS_GRAZING of
    # the plane steps `offset` along itself and `offset` off the plane instead.
    graze = np.abs(cos) < COS_GRAZING
    step = np.where(graze, offset, (offset - past) / np.maximum(np.abs(cos), COS_GRAZING))
    moved = q + step[:, None] * unit
    moved[graze] += offset * side[graze, None] * n_f[graze]
    return moved.astype(np.float32), np.einsum("ij,ij->i", moved - org64, d64) / dd


def _embree_scene(tri: np.ndarray):
    """A committed ``embreex`` scene of (m, 3, 3) triangles."""
    from embreex import mesh_construction, rtcore_scene

    scene = rtcore_scene.EmbreeScene()
    mesh_construction.TriangleMesh(scene, np.ascontiguousarray(tri, dtype=np.float32))
    # Embree commits lazily on the first query; do it now, single-threaded, so that
    # concurrent first queries from the pool never race on the commit.
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), query="OCCLUDED")
    return scene
