"""Solid intervals along the pixels' rays: what lies behind the first surface.

A depth buffer holds one surface per pixel, so a screen-space estimator must guess what is
behind it (everything solid, or a constant thickness). A layered G-buffer knows: along the
ray of each pixel, the view-depth intervals ``[front, back]`` inside solids (depth peeling,
Everitt 2001; the deep G-buffer of Mara et al. 2016 keeps two such layers).
:class:`SolidIntervals` is that knowledge in the form the estimators read it, whatever made it
(:func:`vobscure.render_gbuffer` with ``layers=K``, or an engine's back-face depth pass through
:meth:`vobscure.GBuffer.from_arrays`). :class:`PeeledLayers` keeps the surfaces themselves (the
first K along each ray) and :func:`intervals_from_layers` turns them into intervals by the
enter/leave rule documented there (``docs/layers.md``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SolidIntervals", "PeeledLayers", "intervals_from_layers", "ray_intervals", "interval_count"]


class SolidIntervals:
    """The solid intervals of view depth along every pixel's ray.

    Interval m of pixel (i, j) is ``[front[m, i, j], back[m, i, j]]`` in linear view depth z
    (the G-buffer's ``depth`` convention): points of the pixel's ray (any view ray through that
    pixel position) with front <= z <= back are inside a solid. Per pixel the intervals are
    ascending and disjoint; unused slots hold ``front = back = +inf``. ``back = +inf`` with a
    finite ``front`` is a solid whose end was not seen (the ray entered it and the layers ran out):
    everything behind ``front`` is taken as solid, as a single depth buffer takes it.

    Parameters
    ----------
    front, back : (M, H, W) array_like of float
        Entry and exit depths, M >= 1 intervals per pixel.
    dtype : numpy dtype, optional
        float64 (default) or float32. :func:`vobscure.render_gbuffer` makes float32
        intervals (8 bytes a slot: the float64 depths rounded, relative 6e-8), and the
        estimators compare depths with them in float32 (``docs/layers.md``, "Memory").
    layers : PeeledLayers, optional
        The surfaces the intervals were made of (depth peeling); None when they came from
        elsewhere (a back-face depth pass, or made by hand).

    Attributes
    ----------
    front, back : (M, H, W) float
        Read-only.
    count : int
        M, the interval slots per pixel.
    layers : PeeledLayers or None
        See Parameters; kept by :meth:`astype`.

    Examples
    --------
    >>> import numpy as np
    >>> front = np.array([[[1.0, np.inf]], [[3.0, np.inf]]])
    >>> back = np.array([[[2.0, np.inf]], [[np.inf, np.inf]]])
    >>> s = SolidIntervals(front, back)
    >>> s.count, s.shape
    (2, (1, 2))
    >>> s.inside(np.array([1.5, 2.5, 4.0]), np.array([0, 0, 0])).tolist()
    [True, False, True]
    """

    def __init__(self, front, back, *, dtype=np.float64, layers=None):
        self.dtype = np.dtype(dtype)
        if self.dtype not in (np.dtype(np.float32), np.dtype(np.float64)):
            raise ValueError(f"dtype must be float32 or float64, got {self.dtype}")
        f = np.asarray(front, dtype=self.dtype)
        b = np.asarray(back, dtype=self.dtype)
        if f.ndim != 3 or f.shape[0] < 1:
            raise ValueError(f"front must have shape (M, H, W) with M >= 1, got {f.shape}")
        if b.shape != f.shape:
            raise ValueError(f"back must have the shape of front {f.shape}, got {b.shape}")
        if np.isnan(f).any() or np.isnan(b).any():
            raise ValueError("front and back must not hold NaN (use +inf for an unused slot or an unseen end)")
        if (b < f).any():
            raise ValueError("back must be >= front in every interval")
        if f.shape[0] > 1:
            with np.errstate(invalid="ignore"):
                # the next interval starts after this one ends (inf slots only at the end)
                gap = f[1:] >= b[:-1]
                unused = np.isinf(f[1:]) & np.isinf(b[1:])
            if not (gap | unused).all():
                raise ValueError("the intervals of a pixel must be ascending and disjoint "
                                 "(front[m + 1] >= back[m]), unused slots (+inf) last")
        if layers is not None:
            if not isinstance(layers, PeeledLayers):
                raise ValueError(f"layers must be a vobscure.layers.PeeledLayers or None, got {type(layers).__name__}")
            if layers.shape != f.shape[1:]:
                raise ValueError(f"layers must have the intervals' image shape {f.shape[1:]}, got {layers.shape}")
        self.front = _frozen(f)
        self.back = _frozen(b)
        self.layers = layers

    @property
    def count(self) -> int:
        return int(self.front.shape[0])

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.front.shape[1:])

    def at(self, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(front, back) of shape (M, k) at the flat row-major pixel indices ``index`` (k,)."""
        M = self.count
        return self.front.reshape(M, -1)[:, index], self.back.reshape(M, -1)[:, index]

    def inside(self, z: np.ndarray, index: np.ndarray) -> np.ndarray:
        """Whether view depth ``z`` (k,) at flat pixel ``index`` (k,) lies in a solid interval."""
        f, b = self.at(np.asarray(index))
        z = np.asarray(z)
        return ((f <= z) & (z <= b)).any(axis=0)

    def astype(self, dtype) -> "SolidIntervals":
        return SolidIntervals(self.front, self.back, dtype=dtype, layers=self.layers)

    def __repr__(self) -> str:
        H, W = self.shape
        return f"SolidIntervals({self.count} per pixel, {W}x{H}, {self.dtype})"


class PeeledLayers:
    """The first K surfaces along every pixel's ray (depth peeling), as
    :func:`vobscure.render_gbuffer` with ``layers=K`` finds them.

    Layer 0 is the G-buffer's own surface; layer k the (k+1)-th surface the pixel centre's ray
    crosses (alpha-tested holes are passed, as the tracer passes them). The renderer does not
    repeat layer 0: its depth and triangle are the G-buffer's own images, kept by reference
    (``first``), and each pixel stores 1 byte for layer 0 (entering) and 9 bytes for each
    layer behind it (float32 depth, int32 triangle, bool entering). The normals, and with
    ``open_triangle`` the open flags, are not stored but made on access from the triangles.

    Parameters
    ----------
    depth : (K, H, W) array_like of float
        Linear view depth z of each surface (float32 when stored); +inf where the ray crossed
        fewer than k + 1 surfaces. Non-decreasing along k. With ``first``: (K - 1, H, W), the
        layers 1 to K - 1.
    primitive : (K, H, W) array_like of int
        The triangle (index into ``scene.triangles``), -1 where there is no surface. With
        ``first``: (K - 1, H, W), as ``depth``.
    entering : (K, H, W) array_like of bool
        True where the ray enters the solid behind the surface: the triangle's outward
        (winding) normal points against the ray, ``n . d < 0``; False where it leaves one, or
        where there is no surface. All K layers, with or without ``first``.
    face_normals : (m, 3) array_like of float
        Unit outward (winding) normals of the triangles in world space (``scene.face_normals``;
        kept by reference, not copied).
    rotation : (3, 3) array_like of float
        The camera's world -> view rotation (``camera.rotation``).
    open_surface : (K, H, W) array_like of bool, optional
        True where the surface belongs to an open mesh (``scene.open_meshes``): it bounds no
        solid. Default: all False (or made from ``open_triangle``).
    first : tuple of two (H, W) arrays, optional
        ``(depth0, primitive0)``: layer 0's view depth (float, +inf where none) and triangle
        (-1 where none), kept by reference (the renderer passes the G-buffer's ``depth`` and
        ``primitive``). ``depth`` and ``primitive`` then hold the layers behind it only.
    open_triangle : (m,) array_like of bool, optional
        Per triangle, whether its mesh is open; ``open_surface`` is then made on access from
        the triangles instead of stored. Not together with ``open_surface``.

    Attributes
    ----------
    depth : (K, H, W) float32
    primitive : (K, H, W) int32
        Both made on access from layer 0's images and the stored layers behind it (4 bytes
        per pixel per layer while held).
    entering, open_surface : (K, H, W) bool
    count : int
        K.
    nbytes : int
        Bytes of the per-pixel images the layers store themselves (not layer 0's borrowed
        images, nor the per-triangle tables).

    Examples
    --------
    >>> import numpy as np
    >>> depth = np.array([[[1.0]], [[2.0]]])              # one pixel, a solid from 1 to 2
    >>> layers = PeeledLayers(depth, [[[0]], [[1]]], [[[True]], [[False]]],
    ...                       face_normals=[[0, 0, -1], [0, 0, 1]], rotation=np.eye(3))
    >>> layers.count, layers.normal[:, 0, 0].tolist()
    (2, [[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    >>> intervals_from_layers(layers).front[:, 0, 0].tolist(), intervals_from_layers(layers).back[:, 0, 0].tolist()
    ([1.0], [2.0])

    Layer 0 borrowed from a G-buffer's images (here made by hand), the layer behind it stored:

    >>> behind = PeeledLayers(depth[1:], [[[1]]], [[[True]], [[False]]], face_normals=[[0, 0, -1], [0, 0, 1]],
    ...                       rotation=np.eye(3), first=(np.array([[1.0]]), np.array([[0]])))
    >>> behind.depth[:, 0, 0].tolist(), behind.primitive[:, 0, 0].tolist(), behind.nbytes
    ([1.0, 2.0], [0, 1], 10)
    """

    def __init__(self, depth, primitive, entering, *, face_normals, rotation, open_surface=None,
                 first=None, open_triangle=None):
        z = np.asarray(depth, dtype=np.float32)
        behind = first is not None
        if z.ndim != 3 or (z.shape[0] < 1 and not behind):
            raise ValueError(f"depth must have shape (K, H, W) with K >= 1, got {z.shape}")
        prim = np.asarray(primitive)
        if prim.shape != z.shape or prim.dtype.kind not in "iu":
            raise ValueError(f"primitive must be an integer array of the depth's shape {z.shape}, "
                             f"got {prim.dtype} of shape {prim.shape}")
        if behind:
            z0, prim0 = _first_layer(first, z.shape[1:])
        else:
            z0, prim0, z, prim = z[0], prim[0].astype(np.int32, copy=False), z[1:], prim[1:]
        shape = (z.shape[0] + 1,) + z.shape[1:]
        enter = np.asarray(entering)
        if enter.shape != shape or enter.dtype != bool:
            raise ValueError(f"entering must be a bool array of shape {shape} (K, H, W), "
                             f"got {enter.dtype} of shape {enter.shape}")
        if open_surface is not None and open_triangle is not None:
            raise ValueError("give open_surface or open_triangle, not both")
        opened = None
        if open_surface is not None:
            opened = np.asarray(open_surface)
            if opened.shape != shape or opened.dtype != bool:
                raise ValueError(f"open_surface must be a bool array of shape {shape} (K, H, W), "
                                 f"got {opened.dtype} of shape {opened.shape}")
        self._face_normals = np.asarray(face_normals, dtype=np.float64)
        self._rotation = np.asarray(rotation, dtype=np.float64)
        if self._face_normals.ndim != 2 or self._face_normals.shape[1] != 3:
            raise ValueError(f"face_normals must have shape (m, 3), got {self._face_normals.shape}")
        if self._rotation.shape != (3, 3):
            raise ValueError(f"rotation must have shape (3, 3), got {self._rotation.shape}")
        if open_triangle is not None:
            open_triangle = np.asarray(open_triangle)
            if open_triangle.shape != (len(self._face_normals),) or open_triangle.dtype != bool:
                raise ValueError(f"open_triangle must be a bool array of shape ({len(self._face_normals)},) "
                                 f"(one per triangle), got {open_triangle.dtype} of shape {open_triangle.shape}")
        self._first = (_frozen(z0), _frozen(prim0))
        self._borrowed = behind
        self._depth = _frozen(z)
        self._primitive = _frozen(prim.astype(np.int32, copy=False))
        self.entering = _frozen(enter)
        self._open = None if opened is None else _frozen(opened)
        self._open_triangle = open_triangle

    @property
    def count(self) -> int:
        return int(self.entering.shape[0])

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.entering.shape[1:])

    @property
    def nbytes(self) -> int:
        """Bytes of the per-pixel images stored here: the layers behind layer 0 (depth,
        primitive), entering, and ``open_surface`` when it is stored; layer 0's images, when
        borrowed (``first``), and the per-triangle tables are not counted."""
        own = self._depth.nbytes + self._primitive.nbytes + self.entering.nbytes
        if not self._borrowed:
            own += self._first[0].nbytes + self._first[1].nbytes
        return int(own + (0 if self._open is None else self._open.nbytes))

    def _stacked(self, first, rest, dtype) -> np.ndarray:
        """(K, H, W): layer 0's image ``first`` above the stored layers ``rest``."""
        out = np.empty(self.entering.shape, dtype=dtype)
        out[0] = first
        out[1:] = rest
        return _frozen(out)

    @property
    def depth(self) -> np.ndarray:
        """(K, H, W) float32 view depths, layer 0 rounded from its own image; made on access."""
        return self._stacked(self._first[0], self._depth, np.float32)

    @property
    def primitive(self) -> np.ndarray:
        """(K, H, W) int32 triangles, -1 where there is no surface; made on access."""
        return self._stacked(self._first[1], self._primitive, np.int32)

    @property
    def open_surface(self) -> np.ndarray:
        """(K, H, W) bool: the surface belongs to an open mesh (stored, or made on access from
        ``open_triangle``)."""
        if self._open is not None:
            return self._open
        if self._open_triangle is None:
            return np.broadcast_to(False, self.entering.shape)
        prim = self.primitive
        return _frozen((prim >= 0) & self._open_triangle[np.maximum(prim, 0)])

    @property
    def normal(self) -> np.ndarray:
        """(K, H, W, 3) float32 view-space outward normals of the surfaces, as the meshes wind
        them (not turned to face the camera; ``n_z > 0`` where the ray leaves a solid); 0 where
        there is no surface. Made on each access from the triangles (12 bytes per pixel per
        layer while held)."""
        prim = self.primitive
        out = np.zeros(prim.shape + (3,), dtype=np.float32)
        hit = prim >= 0
        out[hit] = self._face_normals[prim[hit]] @ self._rotation.T
        out += 0.0   # no negative zeros
        return out

    def crop(self, rows: slice, cols: slice) -> "PeeledLayers":
        """The layers of the pixels ``[rows, cols]`` (e.g. a guard band's inner frame); layer 0
        stays a view of its images."""
        opened = None if self._open is None else self._open[:, rows, cols]
        out = PeeledLayers(self._depth[:, rows, cols], self._primitive[:, rows, cols],
                            self.entering[:, rows, cols], face_normals=self._face_normals,
                            rotation=self._rotation, open_surface=opened,
                            first=(self._first[0][rows, cols], self._first[1][rows, cols]),
                            open_triangle=self._open_triangle)
        out._borrowed = self._borrowed
        return out

    def __repr__(self) -> str:
        H, W = self.shape
        return f"PeeledLayers({self.count} per pixel, {W}x{H})"


def _first_layer(first, shape) -> tuple[np.ndarray, np.ndarray]:
    """Layer 0's ``(depth, primitive)`` images of ``shape``, validated, not copied."""
    try:
        z0, prim0 = first
    except (TypeError, ValueError):
        raise ValueError("first must be a pair (depth0, primitive0) of (H, W) arrays") from None
    z0, prim0 = np.asarray(z0), np.asarray(prim0)
    if z0.shape != shape or z0.dtype.kind != "f":
        raise ValueError(f"first's depth must be a float array of the layers' image shape {shape}, "
                         f"got {z0.dtype} of shape {z0.shape}")
    if prim0.shape != shape or prim0.dtype.kind not in "iu":
        raise ValueError(f"first's primitive must be an integer array of the layers' image shape {shape}, "
                         f"got {prim0.dtype} of shape {prim0.shape}")
    return z0, prim0


def intervals_from_layers(layers: PeeledLayers, *, dtype=np.float64, depth=None,
                          origin_inside=None) -> SolidIntervals:
    """The solid intervals of peeled layers, by the enter/leave rule.

    Along each pixel's ray the surfaces are read in order with one state, inside or outside:

    - entering a solid from outside opens an interval at its depth; entering while inside
      changes nothing (overlapping solids, or a leave the peeling skipped because it
      coincided with this surface, as where a box stands on a floor);
    - leaving from inside closes the interval; leaving from outside extends the previous
      interval to this depth (a solid whose entry coincided with the previous surface and was
      skipped, or overlapping solids). When there is no previous interval (the first surface
      leaves a solid) and the ray's origin is inside that solid (``origin_inside``), the camera
      is inside it: the interval starts at the near plane z = 0. Otherwise the entry coincided
      with this very surface (a ray through the edge of a face that touches another solid's,
      where the tracer may report either): the interval starts here, ``[z, z]``, and the next
      leave extends it;
    - a surface of an open mesh (``open_surface``) bounds no solid: seen from outside it is a
      zero-thickness interval ``[z, z]`` (a surface of no depth, which an occupancy test never
      counts but which tells a thickness estimate that nothing solid lies behind it); inside
      a solid it changes nothing;
    - an interval still open after the K layers ends at +inf (its end was not seen).

    For solids that do not overlap, and touch at most in pairs, this is the union of the
    solids along the ray, within the K layers. It can be wrong where three solids chain along
    one ray (A overlaps B, B overlaps C, A and C apart: a gap appears inside B), and when the
    camera is inside a solid that holds another (the interval starts at the inner solid).

    Parameters
    ----------
    layers : PeeledLayers
    dtype : numpy dtype, optional
        Of the intervals.
    depth : (K, H, W) array_like of float, optional
        The layers' depths at a higher precision than the stored float32 (e.g. layer 0 from
        the G-buffer's float64 ``depth``); default ``layers.depth``.
    origin_inside : (H, W) array_like of bool, optional
        Where the first surface leaves a solid: whether the ray's origin (the camera) is inside
        that solid (the renderer asks the mesh, ``trimesh.Trimesh.contains``). Default: True
        everywhere (a first leave means the camera is inside).

    Returns
    -------
    SolidIntervals
        With M = the most intervals of any pixel (at least 1) slots, and ``layers`` attached.

    Examples
    --------
    >>> import numpy as np
    >>> # one pixel: enter 1, leave 2, leave 3 (a second solid touching the first at 2)
    >>> layers = PeeledLayers(np.array([1.0, 2.0, 3.0]).reshape(3, 1, 1), np.zeros((3, 1, 1), int),
    ...                       np.array([True, False, False]).reshape(3, 1, 1),
    ...                       face_normals=[[0, 0, 1]], rotation=np.eye(3))
    >>> s = intervals_from_layers(layers)
    >>> s.front.ravel().tolist(), s.back.ravel().tolist()
    ([1.0], [3.0])
    """
    if not isinstance(layers, PeeledLayers):
        raise ValueError(f"layers must be a vobscure.layers.PeeledLayers, got {type(layers).__name__}")
    K = layers.count
    H, W = layers.shape
    z = layers.depth if depth is None else np.asarray(depth)
    if z.shape != (K, H, W):
        raise ValueError(f"depth must have the layers' shape {(K, H, W)}, got {z.shape}")
    inside = None
    if origin_inside is not None:
        inside = np.asarray(origin_inside)
        if inside.shape != (H, W) or inside.dtype != bool:
            raise ValueError(f"origin_inside must be a bool array of shape {(H, W)}, got "
                             f"{inside.dtype} of shape {inside.shape}")
        inside = inside.reshape(-1)
    front, back = ray_intervals(z.reshape(K, -1), layers.primitive.reshape(K, -1) >= 0,
                                  layers.entering.reshape(K, -1), layers.open_surface.reshape(K, -1),
                                  inside)
    M = front.shape[0]
    return SolidIntervals(front.reshape(M, H, W), back.reshape(M, H, W), dtype=dtype, layers=layers)


def ray_intervals(z, hit, entering, open_surface, origin_inside=None) -> tuple[np.ndarray, np.ndarray]:
    """The enter/leave rule of :func:`intervals_from_layers` on flat arrays of n rays.

    Parameters
    ----------
    z : (K, n) array_like of float
        View depth of each ray's k-th surface (+inf where none).
    hit, entering, open_surface : (K, n) array_like of bool
        Whether there is a k-th surface, whether the ray enters a solid there, whether it is
        open (see :class:`PeeledLayers`).
    origin_inside : (n,) array_like of bool, optional
        As in :func:`intervals_from_layers`; None: all True.

    Returns
    -------
    front, back : (M, n) float64
        M the most intervals of any ray, at least 1; unused slots +inf.

    Examples
    --------
    >>> import numpy as np
    >>> f, b = ray_intervals(np.array([[1.0], [2.0]]), np.ones((2, 1), bool),
    ...                      np.array([[True], [False]]), np.zeros((2, 1), bool))
    >>> f.tolist(), b.tolist()
    ([[1.0]], [[2.0]])
    """
    K, n = z.shape
    z = np.maximum.accumulate(np.asarray(z, dtype=np.float64), axis=0)   # rounding never reorders
    front = np.full((K, n), np.inf)
    back = np.full((K, n), np.inf)
    used = _enter_leave(hit, entering, open_surface, z=z, origin_inside=origin_inside, front=front, back=back)
    M = max(1, int(used.max()) if n else 1)
    return front[:M].copy(), back[:M].copy()


def interval_count(hit, entering, open_surface) -> np.ndarray:
    """(n,) int: the intervals the enter/leave rule of :func:`ray_intervals` makes along each
    of n rays, from the surfaces' kinds alone (the depths do not change the count): the
    slots M to allocate before the intervals are written.

    Examples
    --------
    >>> import numpy as np
    >>> interval_count(np.ones((3, 2), bool), np.array([[True, True], [False, True], [True, False]]),
    ...                np.zeros((3, 2), bool)).tolist()
    [2, 1]
    """
    return _enter_leave(hit, entering, open_surface)


def _enter_leave(hit, entering, open_surface, *, z=None, origin_inside=None, front=None, back=None):
    """The enter/leave rule over the K layers of n rays: the intervals written per ray (n,),
    and, given the depths ``z`` (K, n) float64 (non-decreasing) and ``front``, ``back``
    (>= (M, n), +inf), the intervals themselves written into them."""
    K, n = np.shape(hit)
    write = z is not None
    used = np.zeros(n, dtype=np.int64)           # intervals written per ray
    inside = np.zeros(n, dtype=bool)
    start = np.zeros(n) if write else None
    for k in range(K):
        h, op = hit[k], open_surface[k]
        zk = z[k] if write else None
        solid = h & ~op
        sheet = np.flatnonzero(h & op & ~inside)                 # [z, z], outside only
        if write:
            front[used[sheet], sheet] = zk[sheet]
            back[used[sheet], sheet] = zk[sheet]
        used[sheet] += 1
        opening = solid & entering[k] & ~inside
        leave = solid & ~entering[k]
        close = np.flatnonzero(leave & inside)
        if write:
            start[opening] = zk[opening]
            front[used[close], close] = start[close]
            back[used[close], close] = zk[close]
        used[close] += 1
        stray = leave & ~inside                                   # a leave without its entry
        first = np.flatnonzero(stray & (used == 0))               # no interval before it
        if write:
            extend = np.flatnonzero(stray & (used > 0))
            back[used[extend] - 1, extend] = zk[extend]
            camera = first if origin_inside is None else first[origin_inside[first]]
            front[0, first] = zk[first]                            # the entry was here...
            front[0, camera] = 0.0                                 # ...or the camera is inside
            back[0, first] = zk[first]
        used[first] = 1
        inside = (inside | opening) & ~leave
    unseen = np.flatnonzero(inside)                               # the layers ran out inside
    if write:
        front[used[unseen], unseen] = start[unseen]
    used[unseen] += 1
    return used


def _frozen(a: np.ndarray) -> np.ndarray:
    a = a.view()
    a.flags.writeable = False
    return a
