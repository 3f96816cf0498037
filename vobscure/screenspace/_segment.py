"""Segments along view rays: the kernel of the converged screen-space VO
(:func:`vobscure.vo_reference`).

Every point of a view ray (a line through the eye under perspective, a line along the view
axis under an orthographic camera) projects to the same pixel position, so ONE depth fetch
there gives the depth-buffer occupancy (Loos & Sloan 2010, Sec. 4) of the whole ray: a point
at view depth z is occupied when max(d, 0) < z (and z < d + thickness with the thickness
model of Sec. 4.3), d the fetched depth. The ball's occupied volume is then an integral over
rays of an integral along each ray that has a closed form; the rays are sampled, the
segments integrated exactly: the same integral as point sampling with one dimension done
exactly (``docs/screenspace.md``, "The converged reference").

Parametrization (view space, z = depth): the ray is L(z) = z u with u = (a, b, 1)
(perspective: the volume element is z^2 dz da db) or L(z) = (a, b, z) (orthographic:
dz da db). With z_m the depth of the ray's point closest to the ball's centre p and
t = z - z_m, the ball's segment is t in [-h, h], h^2 = (R^2 - |L(z_m) - p|^2) / |u|^2, and
the quadratic falloff along it is rho = 1 - |L - p|^2 / R^2 = |u|^2 (h^2 - t^2) / R^2: every
weight is a polynomial in t, integrated in closed form over the segment and its occupied
part.
"""

from __future__ import annotations

import numpy as np

from ..camera.kernel import project_xy
from . import _common as C


def _powers(a, b):
    """(b - a, (b^2 - a^2) / 2, (b^3 - a^3) / 3, (b^4 - a^4) / 4, (b^5 - a^5) / 5)."""
    a2, b2 = a * a, b * b
    return (b - a, (b2 - a2) / 2, (b2 * b - a2 * a) / 3, (b2 * b2 - a2 * a2) / 4, (b2 * b2 * b - a2 * a2 * a) / 5)


def _weights(a, b, z_m, h2, uu_r2, perspective: bool, quadratic: bool):
    """(int_a^b J dt, int_a^b J rho dt) along the rays, t = z - z_m.

    J = (z_m + t)^2 (perspective) or 1 (orthographic); rho = uu_r2 (h^2 - t^2) (quadratic
    falloff) or 1. Without ``quadratic`` the second is the first.
    """
    if not perspective and not quadratic:
        w = b - a
        return w, w
    P0, P1, P2, P3, P4 = _powers(a, b)
    if perspective:
        zz = z_m * z_m
        # int (z_m + t)^2 t^k dt = z_m^2 P_k + 2 z_m P_{k+1} + P_{k+2}
        J0 = zz * P0 + 2.0 * z_m * P1 + P2
        if not quadratic:
            return J0, J0
        J2 = zz * P2 + 2.0 * z_m * P3 + P4
        return J0, uu_r2 * (h2 * J0 - J2)
    return P0, uu_r2 * (h2 * P0 - P2)


#: A fetched depth within this fraction of itself of the tangent plane's depth along the
#: ray is the tangent plane: the depth buffer holds float32 hits (relative rounding 6e-8,
#: Embree's hit points ~1e-6), and without this a plane would read 1/2 (1 clamped) only up
#: to that rounding, with a spread over groups of the same size instead of 0.
PLANE_RTOL = 1e-5

#: The ball's weighted volume over R^3 (ball; the half-ball is half of it), by falloff:
#: int_ball rho dV with rho = 1 or 1 - |x|^2 / R^2 (4 pi / 3; 4 pi (1/3 - 1/5) = 8 pi / 15).
BALL_MASS = {"constant": 4.0 * np.pi / 3.0, "quadratic": 8.0 * np.pi / 15.0}


def ball_box(px, radius):
    """(a0, a1, b0, b1, exact) per pixel: the rays through the ball as a box of ray
    directions (a, b, 1) (perspective) or of view (x, y) (orthographic), and where that box
    holds every ray through the ball (perspective: the ball entirely in front, p_z > R)."""
    p = px.p
    R = float(radius)
    if not px.perspective:
        return p[:, 0] - R, p[:, 0] + R, p[:, 1] - R, p[:, 1] + R, np.ones(len(px.index), dtype=bool)
    pz = p[:, 2]
    front = pz > R * (1.0 + 1e-9)
    den = np.where(front, pz * pz - R * R, 1.0)
    bounds = []
    for q in (p[:, 0], p[:, 1]):
        # the two planes through the eye that touch the ball and hold the other axis:
        # q / z = (q p_z -+ R sqrt(q^2 + p_z^2 - R^2)) / (p_z^2 - R^2)
        root = R * np.sqrt(np.maximum(q * q + pz * pz - R * R, 0.0))
        bounds += [(q * pz - root) / den, (q * pz + root) / den]
    return (*bounds, front)


def ray_kernel(px, *, radius, unit, normal_clamp, thickness, falloff, fetch, offscreen, shift):
    """Segment-integrated VO of one chunk of pixels for one group of rays.

    ``unit`` (n, 2): points of the unit square (each uniform in it), moved by the pixel's toroidal
    ``shift`` ((k, 2), uniform in the square: a Cranley-Patterson rotation), mapped
    uniformly to the box :func:`ball_box` of rays through the ball. With A the box's area,
    A / n sum_i int_occ J rho estimates the occupied weighted volume without bias, and

        V = 1 - occupied / (the ball's weighted volume)      (the half-ball's with normal_clamp).

    Without ``normal_clamp`` the tangent plane at p is a control variate: the part of each
    segment behind it is subtracted and its exact mean, half the ball, added back, so a
    plane reads 1/2 exactly. Returns ((k,) V, (k,) bool where the box was exact); the caller
    computes the other pixels another way.
    """
    k = len(px.index)
    quadratic = falloff == "quadratic"
    R = float(radius)
    a0, a1, b0, b1, exact = ball_box(px, R)
    da, db = a1 - a0, b1 - b0
    pc = [np.ascontiguousarray(px.p[:, a]) for a in range(3)]
    nc = [np.ascontiguousarray(px.n[:, a]) for a in range(3)]
    n_p = nc[0] * pc[0] + nc[1] * pc[1] + nc[2] * pc[2]
    pp = pc[0] * pc[0] + pc[1] * pc[1] + pc[2] * pc[2]
    s1 = np.ascontiguousarray(shift[:, 0])
    s2 = np.ascontiguousarray(shift[:, 1])
    uu_r2 = 1.0 / (R * R)
    occ_sum = np.zeros(k)
    plane_sum = np.zeros(k)
    for u1, u2 in unit:
        ua = u1 + s1
        ua -= np.floor(ua)
        ub = u2 + s2
        ub -= np.floor(ub)
        a = a0 + ua * da
        b = b0 + ub * db
        with np.errstate(divide="ignore", invalid="ignore"):
            # every point of the ray projects here: (a, b) is the direction's (x / z, y / z),
            # or the orthographic view (x, y)
            x, y = project_xy(a, b, 1.0, px.fx, px.fy, px.cx, px.cy, False)
            if px.perspective:
                uu = a * a + b * b + 1.0
                up = a * pc[0] + b * pc[1] + pc[2]
                z_m = up / uu
                h2 = (R * R - (pp - up * z_m)) / uu
                c1 = a * nc[0] + b * nc[1] + nc[2]
                c0 = z_m * c1 - n_p
                uu_r2 = uu / (R * R)
            else:
                z_m = pc[2]
                ex, ey = a - pc[0], b - pc[1]
                h2 = R * R - (ex * ex + ey * ey)
                c1 = nc[2]
                c0 = nc[0] * ex + nc[1] * ey
            hit = h2 > 0
            h2 = np.maximum(h2, 0.0)
            h = np.sqrt(h2)
            # the tangent plane: n . (L(z_m + t) - p) = c0 + c1 t (Loos & Sloan 2010, Sec. 4.4)
            cut = np.clip(-c0 / c1, -h, h)
            away = c1 > 0          # the half-ball lies beyond the plane along the ray
            if normal_clamp:
                # the half-ball, n . (X - p) >= 0
                lo_seg = np.where(away, cut, -h)
                hi_seg = np.where(away, h, cut)
            else:
                lo_seg, hi_seg = -h, h
            d = C.fetch_depth(px.depth, x, y, fetch=fetch, offscreen=offscreen, reciprocal=px.perspective)
            # Sec. 4 (and 4.3): occupied where max(d, 0) < z (< d + thickness); a depth on
            # the tangent plane up to rounding starts exactly where the plane does
            lo = np.clip(np.maximum(d, 0.0) - z_m, lo_seg, hi_seg)
            on_plane = (np.abs(d - (z_m - c0 / c1)) <= PLANE_RTOL * d) & np.isfinite(d)
            lo = np.where(on_plane, np.clip(cut, lo_seg, hi_seg), lo)
            hi = hi_seg if thickness is None else np.clip(d + thickness - z_m, lo_seg, hi_seg)
            hi = np.maximum(lo, hi)
            _, occ = _weights(lo, hi, z_m, h2, uu_r2, px.perspective, quadratic)
            occ_sum += np.where(hit & np.isfinite(occ), occ, 0.0)
            if not normal_clamp:
                # the part of the segment on the plane's far side, n . (X - p) < 0
                blo = np.where(away, -h, cut)
                bhi = np.where(away, cut, h)
                _, below = _weights(blo, bhi, z_m, h2, uu_r2, px.perspective, quadratic)
                plane_sum += np.where(hit & np.isfinite(below), below, 0.0)
    mass = BALL_MASS[falloff] * R ** 3
    scale = (da * db) / len(unit)
    if normal_clamp:
        v = 1.0 - scale * occ_sum / (0.5 * mass)
    else:
        # control variate: scale * E[plane_sum] = mass / 2 exactly
        v = 0.5 - scale * (occ_sum - plane_sum) / mass
    return v, exact


#: Quantum of the plane keys of :func:`plane_labels`, relative (unit normals; plane offsets
#: over the scene's scale): far below :data:`PLANE_RTOL`, so two pixels share a label only when
#: their planes agree to better than the kernel's own plane test can tell.
PLANE_KEY_QUANTUM = 1e-9


def plane_labels(gbuffer) -> np.ndarray | None:
    """(H, W) int64 label of the world plane each pixel's flat triangle lies in, 0 where the
    pixel is background or its shading normal is not the triangle's (smooth shading); None when
    the G-buffer has no per-hit data (:meth:`vobscure.GBuffer.from_arrays`: its planes are
    known only to the depth's precision) or its per-hit data lack the world positions and normals.

    Pixels share a label when their triangles' planes (unit normal n, offset n . x) agree
    within :data:`PLANE_KEY_QUANTUM` (relative): coplanar triangles of a wall, not its
    neighbour. Each triangle's key is taken once, at its first hit (every hit of a triangle
    lies in its plane; keying every pixel cost 0.5 s at 1280 x 720, mostly in making the
    pixels' keys unique). A plane whose key falls on a quantum's edge may get two labels,
    which only makes :func:`on_one_plane` more cautious.
    """
    if not getattr(gbuffer, "has_hit_data", False):
        return None
    hits = gbuffer.hits
    if not {"index", "world_geometric_normal", "world_normal", "world_position"} <= set(hits):
        return None         # per-hit data without the planes (a G-buffer built by hand)
    index = np.asarray(hits["index"])
    labels = np.zeros(gbuffer.depth.size, dtype=np.int64)
    if not len(index):
        return labels.reshape(gbuffer.depth.shape)
    n_all = np.asarray(hits["world_geometric_normal"])
    flat = (np.asarray(hits["world_normal"]) == n_all).all(axis=1)
    prim = np.asarray(gbuffer.primitive).reshape(-1)[index]
    # each triangle's first hit (written last in reversed order), without sorting the hits
    first = np.full(int(prim.max()) + 1, -1, dtype=np.intp)
    first[prim[::-1]] = np.arange(len(prim) - 1, -1, -1)
    triangles = np.flatnonzero(first >= 0)
    at = first[triangles]
    n = n_all[at].astype(np.float64)
    p = np.asarray(hits["world_position"])[at].astype(np.float64)
    offset = np.einsum("ij,ij->i", n, p)
    scale = max(1.0, float(np.abs(p).max(initial=0.0)))
    key = np.column_stack([np.rint(n / PLANE_KEY_QUANTUM),
                           np.rint(offset / (scale * PLANE_KEY_QUANTUM))]).astype(np.int64)
    of_triangle = np.zeros(len(first), dtype=np.int64)
    of_triangle[triangles] = _row_ids(key) + 1
    labels[index[flat]] = of_triangle[prim[flat]]
    return labels.reshape(gbuffer.depth.shape)


def _row_ids(key: np.ndarray) -> np.ndarray:
    """(n,) int64 ids of the distinct rows of the (n, m) int64 ``key``, equal exactly where the
    rows are equal: each row hashed to one uint64 (wrapping arithmetic), the hashes made unique,
    and every row compared with its hash's first row; on a collision (two rows, one hash) the
    rows themselves are made unique. The ids are ``np.unique(key, axis=0)``'s up to their
    order, in a tenth of its time on a 1280 x 720 image (its row sort is the slow part).

    Examples
    --------
    >>> ids = _row_ids(np.array([[1, 2], [3, 4], [1, 2], [1, 3]]))
    >>> bool(ids[0] == ids[2]), len(set(ids.tolist()))
    (True, 3)
    """
    u = key.astype(np.uint64)
    h = np.zeros(len(u), dtype=np.uint64)
    with np.errstate(over="ignore"):
        for col in u.T:
            # FNV-style mixing: any injective-enough map does, the check below makes it exact
            h = (h ^ col) * np.uint64(0x100000001B3) + np.uint64(0x9E3779B97F4A7C15)
    _, first, inverse = np.unique(h, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    if (key == key[first[inverse]]).all():
        return inverse.astype(np.int64)
    return np.unique(key, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)


def _summed(a: np.ndarray) -> np.ndarray:
    """Summed-area table with a zero first row and column: S[i, j] = a[:i, :j].sum()."""
    S = np.zeros((a.shape[0] + 1, a.shape[1] + 1), dtype=np.int64)
    np.cumsum(np.cumsum(a, axis=0, dtype=np.int64), axis=1, out=S[1:, 1:])
    return S


def _pyramid(a: np.ndarray, reduce, fill) -> list[np.ndarray]:
    """[a, then ``reduce`` over 2 x 2 blocks of the level below (odd sizes padded with
    ``fill``), ...] down to one element: level l, element (i, j) covers the pixels of rows
    i 2^l .. (i + 1) 2^l - 1 and the same columns."""
    out = [a]
    while a.shape[0] > 1 or a.shape[1] > 1:
        H, W = a.shape
        b = np.full((H + H % 2, W + W % 2), fill)
        b[:H, :W] = a
        a = reduce(reduce(b[0::2, 0::2], b[0::2, 1::2]), reduce(b[1::2, 0::2], b[1::2, 1::2]))
        out.append(a)
    return out


class PlaneTables:
    """Summed-area tables of :func:`plane_labels` and of their squares, built once per image:
    a rectangle holds one label L when its sum is L n and its sum of squares L^2 n (zero
    variance; exact in int64). With ``depth`` ((H, W), +inf on background) also the least and
    greatest depth of each pixel's 3 x 3 neighbourhood (``near9``, ``far9``: every bilinear
    cell with the pixel as a corner reads between them) and their min / max pyramids
    (:func:`_pyramid`), for :func:`on_one_plane`'s test of the other surfaces in a footprint."""

    def __init__(self, labels: np.ndarray, depth: np.ndarray | None = None):
        self.labels = labels
        self.S1 = _summed(labels)
        self.S2 = _summed(labels * labels)
        self.near9 = self.far9 = self.near_pyramid = self.far_pyramid = None
        if depth is not None:
            from scipy import ndimage
            d = np.asarray(depth, dtype=np.float64)
            d = np.where(np.isnan(d), np.inf, d)
            self.near9 = ndimage.minimum_filter(d, size=3, mode="nearest")
            self.far9 = ndimage.maximum_filter(d, size=3, mode="nearest")
            self.near_pyramid = _pyramid(self.near9, np.minimum, np.inf)
            self.far_pyramid = _pyramid(self.far9, np.maximum, -np.inf)
            # the image's border lines (top, bottom, left, right), where a ray that leaves the
            # image reads with ``offscreen="clamp"``
            self.borders = {side: _RangeBounds(line) for side, line in
                            (("top", d[0]), ("bottom", d[-1]), ("left", d[:, 0]), ("right", d[:, -1]))}

    def border_bounds(self, side: str, lo, hi):
        """(least, greatest) depth of the texels lo..hi (inclusive, clipped to the line) of the
        border line ``side``; background is +inf."""
        return self.borders[side].bounds(lo, hi)

    def one_label(self, label, r0, r1, c0, c1) -> np.ndarray:
        """Whether every pixel of rows r0..r1, columns c0..c1 (inclusive) has ``label`` > 0."""
        def box(S):
            return S[r1 + 1, c1 + 1] - S[r0, c1 + 1] - S[r1 + 1, c0] + S[r0, c0]
        n = (r1 - r0 + 1) * (c1 - c0 + 1)
        return (label > 0) & (box(self.S1) == label * n) & (box(self.S2) == label * label * n)


class _RangeBounds:
    """Least and greatest value of any run lo..hi of a 1-D array, each in O(1) (sparse tables:
    level k holds the extremes of the runs of 2^k values; a run is two overlapping ones)."""

    def __init__(self, line: np.ndarray):
        self.size = len(line)
        self.low, self.high = [line], [line]
        k = 1
        while 2 * k <= self.size:
            a, b = self.low[-1], self.high[-1]
            self.low.append(np.minimum(a[:-k], a[k:]))
            self.high.append(np.maximum(b[:-k], b[k:]))
            k *= 2

    def bounds(self, lo, hi):
        lo = np.clip(lo, 0, self.size - 1)
        hi = np.clip(hi, 0, self.size - 1)
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        level = np.floor(np.log2(hi - lo + 1)).astype(np.intp)
        least = np.empty(len(lo))
        most = np.empty(len(lo))
        for k in np.unique(level):
            at = level == k
            a, b = lo[at], hi[at] - (1 << k) + 1
            least[at] = np.minimum(self.low[k][a], self.low[k][b])
            most[at] = np.maximum(self.high[k][a], self.high[k][b])
        return least, most


#: Horizontal strips of the ball's footprint that :func:`on_one_plane` checks one rectangle
#: each: the footprint is an ellipse (a disk orthographically), and its bounding box's corners
#: (a fifth of the box) reach pixels no ray through the ball reads. With 8 strips the
#: rectangles cover little more than the ellipse and its bilinear cells (the measured share of
#: the pixels in ``docs/screenspace.md``, "Pixels that see only their own plane").
FOOTPRINT_STRIPS = 8
#: Widening of each strip's extent, relative to the box's width: far above float64 rounding
#: (1e-16 relative in h^2, 1e-8 in a chord's end where it is a square root), far below a
#: pixel. The float32 kernel's ray directions differ from the float64 positions it reads by up
#: to about 1e-4 pixel, more than this pad for small footprints; what that can cost is said at
#: :data:`CLEAR_MARGIN`.
FOOTPRINT_PAD = 1e-6


def footprint_rows(px, radius, b_lo, b_hi, a0, a1):
    """(a_min, a_max) per pixel: the extent in a (x / z, or view x orthographically) of the
    rays through the ball whose b (y / z, or view y) lies in [b_lo, b_hi]; ``a0``, ``a1``
    the extremes over all b (:func:`ball_box`), for balls entirely in front.

    The rays through the ball form a convex set in (a, b): under perspective the direction
    u = (a, b, 1) meets the ball when |p|^2 |u|^2 - (u . p)^2 <= R^2 |u|^2, i.e.
    F(a, b) = q (a^2 + b^2 + 1) - (a p_x + b p_y + p_z)^2 <= 0 with q = |p|^2 - R^2, a
    quadratic in a for each b whose roots bound the chord; orthographically the disk
    (a - p_x)^2 + (b - p_y)^2 <= R^2. The chord's right end is concave in b, so its maximum
    over the interval is at the b of the rightmost point (dF/db = 0 there:
    b = p_y (a1 p_x + p_z) / (q - p_y^2)) clipped to the interval; the left end likewise.
    """
    p = px.p
    R = float(radius)
    px_, py_, pz_ = p[:, 0], p[:, 1], p[:, 2]
    if px.perspective:
        q = np.einsum("ij,ij->i", p, p) - R * R
        den = np.maximum(q - py_ * py_, np.finfo(float).tiny)      # p_x^2 + p_z^2 - R^2 > 0
        b_right = py_ * (a1 * px_ + pz_) / den
        b_left = py_ * (a0 * px_ + pz_) / den
        A = np.maximum(q - px_ * px_, np.finfo(float).tiny)        # p_y^2 + p_z^2 - R^2 > 0

        def chord(b):
            m = b * py_ + pz_
            B = px_ * m                                            # F = A a^2 - 2 B a + C
            C = q * (b * b + 1.0) - m * m
            root = np.sqrt(np.maximum(B * B - A * C, 0.0))
            return (B - root) / A, (B + root) / A
    else:
        b_right = b_left = py_

        def chord(b):
            half = np.sqrt(np.maximum(R * R - (b - py_) ** 2, 0.0))
            return px_ - half, px_ + half
    # widened by FOOTPRINT_PAD of the box: a ray the kernel's rounding puts barely inside the
    # ball (h^2 > 0 by an ulp) still lies within
    pad = FOOTPRINT_PAD * (a1 - a0)
    lo = chord(np.clip(b_left, b_lo, b_hi))[0] - pad
    hi = chord(np.clip(b_right, b_lo, b_hi))[1] + pad
    return np.maximum(lo, a0), np.minimum(hi, a1)


#: Margin of :func:`on_one_plane`'s depth tests of other surfaces, relative to |p| + R: far
#: above the float64 rounding of the chord's ends (z_m +- h; h a square root, 1e-8 relative
#: near the ball's rim, where the chord's end lies well inside the ball's depth range) and of
#: the bilinear depth and the plane's depth along a ray (a few ulps), far below any scene's
#: detail. It moves the thresholds toward "not exact". The tests are exact arithmetic's claims
#: made sound in float64: an exact pixel is never integrated. The float32 kernel
#: (``_segment_fast._simple_perspective``) rounds a chord's end near the rim by up to about
#: sqrt(eps32) R, more than this margin, so a pixel the tests would prove may read a value a
#: rounding away from the closed form in a group; it is then no candidate for the tests of
#: ``vo_reference`` and is integrated like any other pixel (its value right to that rounding,
#: its reported standard error tiny instead of 0). Measured: none on the two 1280 x 720 views
#: of ``benchmarks/bench_groundtruth.py``.
CLEAR_MARGIN = 1e-6
#: Texels a side of the grid that :func:`_clear_of_ball` tests in each of a pixel's rectangles,
#: then in each of its first boxes, before its quadtree: most pixels fail on many texels, and
#: a texel that fails fails its pixel (a shortcut to the verdict of the many that fail).
CLEAR_PROBES = 2


def _box_distance(a_lo, a_hi, b_lo, b_hi, a, b):
    """Euclidean distance from (a, b) to the boxes [a_lo, a_hi] x [b_lo, b_hi] (0 inside)."""
    da = np.maximum(np.maximum(a_lo - a, a - a_hi), 0.0)
    db = np.maximum(np.maximum(b_lo - b, b - b_hi), 0.0)
    return np.hypot(da, db)


def _clear_of_ball(px, radius, tables: PlaneTables, sel, rects, overflow=(), offscreen="clamp"):
    """(len(sel),) bool for the pixels ``px.index[sel]``: whether every pixel (texel) of their
    rectangles ``rects`` (one (c0, c1, r0, r1, one) tuple of (len(sel),) arrays per strip,
    ``one`` where the rectangle holds the pixel's label only; None: no strip to check) whose
    label is not the pixel's own is clear of the ball: every ray landing within one pixel of it
    (the rays of the bilinear cells it is a corner of) either misses the ball, or reads a depth
    d and meets the pixel's plane P at a depth z_P both behind the ray's chord through the
    ball, or both in front of it.

    Such a ray's occupied part and its part behind P (the tangent plane) clip to the same end
    of the chord (both empty behind, both the whole chord in front): its term in the control
    variate's difference is exactly 0, as on P itself (and with ``normal_clamp`` the half-ball's
    part of it is empty behind, the whole chord's empty part in front). The bounds, for a box of
    texels and the rays within one pixel of it:

    - d lies between the least and greatest depth of the texels' 3 x 3 neighbourhoods (the
      corners of every cell those rays read; ``PlaneTables`` keeps a min / max pyramid);
    - 1/z_P (z_P under an orthographic camera) is affine in the image position: its value at
      the box's centre plus the gradient's reach to the box's corners; P must face the rays
      (n . p < 0 and n . u < 0 along them) so that the chord is split as on P;
    - the chord's far end along a ray at angle theta from the centre p is at view depth
      (|p| cos theta + sqrt(R^2 - |p|^2 sin^2 theta)) / |u|, decreasing in theta, its near
      end with the minus sign, increasing (|p| > R); the distance D = |p| sin theta from p to
      the ray is at least p_z |(a, b) - (a_p, b_p)| / |u| (the offset in the plane z = p_z,
      foreshortened at most by 1 / |u|); orthographically the chord is
      p_z -+ sqrt(R^2 - D^2) with D the distance from (p_x, p_y) to the box;
    - every bound moves by :data:`CLEAR_MARGIN` toward "not clear".

    The texels are checked as a quadtree of boxes aligned with the pyramid: a box whose
    texels all carry P's label, or whose bounds pass, is done; another is split down to
    single texels, where a failure fails the pixel.

    ``overflow``: per strip None or the (x0, x1, y0, y1, out) arrays of its whole rectangle
    (``out`` where it leaves the image): the rays beyond the image's edge must be clear of the
    ball too (:func:`_overflow_clear`, with ``offscreen``).
    """
    R = float(radius)
    RR = R * R
    p = px.p[sel]
    n = px.n[sel]
    label = tables.labels.reshape(-1)[px.index[sel]]
    pp = np.einsum("ij,ij->i", p, p)
    m = CLEAR_MARGIN * (np.sqrt(pp) + R)
    # minus n . p (perspective) or minus n_z (orthographic): > 0 when P faces the rays
    facing = -np.einsum("ij,ij->i", n, p) if px.perspective else -n[:, 2]
    ok = facing > 0
    den = np.where(ok, facing, 1.0)
    gx = np.abs(n[:, 0]) / abs(px.fx) / den
    gy = np.abs(n[:, 1]) / abs(px.fy) / den
    top = len(tables.near_pyramid) - 1
    labels = tables.labels.reshape(-1)
    W = px.shape[1]
    rects = [r for r in rects if r is not None]
    for strip in overflow:
        if strip is not None:
            _overflow_clear(px, tables, ok, (p, n, pp, den, gx, gy, m, RR), strip, offscreen)
    g = (np.arange(CLEAR_PROBES) + 0.5) / CLEAR_PROBES
    for c0, c1, r0, r1, one in rects:
        for fi in g:
            for fj in g:
                ti = (r0 + fi * (r1 - r0 + 1)).astype(np.intp)
                tj = (c0 + fj * (c1 - c0 + 1)).astype(np.intp)
                q = np.flatnonzero(ok & ~one & (labels[ti * W + tj] != label))
                ti, tj = ti[q], tj[q]
                fine = _box_clear(px, p[q], n[q], pp[q], den[q], gx[q], gy[q], m[q], RR, ti, ti, tj, tj,
                                  tables.near9[ti, tj], tables.far9[ti, tj])
                ok[q[~fine]] = False
    parts = []
    for c0, c1, r0, r1, one in rects:
        q = np.flatnonzero(ok & ~one)
        if not q.size:
            continue
        c0, c1, r0, r1 = c0[q], c1[q], r0[q], r1[q]
        span = np.maximum(c1 - c0, r1 - r0) + 1
        # about 4 boxes a side to start with
        lev = np.minimum(np.ceil(np.log2(np.maximum(span / 4.0, 1.0))).astype(np.intp), top)
        bi0, bi1, bj0, bj1 = r0 >> lev, r1 >> lev, c0 >> lev, c1 >> lev
        nj = bj1 - bj0 + 1
        cnt = (bi1 - bi0 + 1) * nj
        k = np.repeat(np.arange(len(q)), cnt)
        off = np.arange(len(k)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        parts.append((q[k], lev[k], bi0[k] + off // nj[k], bj0[k] + off % nj[k], r0[k], r1[k], c0[k], c1[k]))
    if not parts:
        return ok
    pix, lev, bi, bj, r0, r1, c0, c1 = (np.concatenate(a) for a in zip(*parts))
    # and again in each first box, before the quadtree descends
    i_lo = np.maximum(bi << lev, r0)
    i_hi = np.minimum(((bi + 1) << lev) - 1, r1)
    j_lo = np.maximum(bj << lev, c0)
    j_hi = np.minimum(((bj + 1) << lev) - 1, c1)
    for fi in g:
        for fj in g:
            ti = (i_lo + fi * (i_hi - i_lo + 1)).astype(np.intp)
            tj = (j_lo + fj * (j_hi - j_lo + 1)).astype(np.intp)
            test = ok[pix] & (labels[ti * W + tj] != label[pix])
            q = pix[test]
            ti, tj = ti[test], tj[test]
            fine = _box_clear(px, p[q], n[q], pp[q], den[q], gx[q], gy[q], m[q], RR, ti, ti, tj, tj,
                              tables.near9[ti, tj], tables.far9[ti, tj])
            ok[q[~fine]] = False
    while len(pix):
        keep = ok[pix]
        pix, lev, bi, bj, r0, r1, c0, c1 = (a[keep] for a in (pix, lev, bi, bj, r0, r1, c0, c1))
        if not len(pix):
            break
        # the box's texels within the rectangle
        i_lo = np.maximum(bi << lev, r0)
        i_hi = np.minimum(((bi + 1) << lev) - 1, r1)
        j_lo = np.maximum(bj << lev, c0)
        j_hi = np.minimum(((bj + 1) << lev) - 1, c1)
        done = tables.one_label(label[pix], i_lo, i_hi, j_lo, j_hi)
        near9 = np.empty(len(pix))
        far9 = np.empty(len(pix))
        for lv in np.unique(lev):
            at = lev == lv
            near9[at] = tables.near_pyramid[lv][bi[at], bj[at]]
            far9[at] = tables.far_pyramid[lv][bi[at], bj[at]]
        done |= _box_clear(px, p[pix], n[pix], pp[pix], den[pix], gx[pix], gy[pix], m[pix], RR,
                           i_lo, i_hi, j_lo, j_hi, near9, far9)
        ok[pix[~done & (lev == 0)]] = False
        split = ~done & (lev > 0)
        pix, lev, bi, bj, r0, r1, c0, c1 = (a[split] for a in (pix, lev, bi, bj, r0, r1, c0, c1))
        lev = lev - 1
        kids = []
        for di in (0, 1):
            for dj in (0, 1):
                ci, cj = 2 * bi + di, 2 * bj + dj
                meet = ((ci << lev) <= r1) & (((ci + 1) << lev) - 1 >= r0) & \
                       ((cj << lev) <= c1) & (((cj + 1) << lev) - 1 >= c0)
                kids.append((pix[meet], lev[meet], ci[meet], cj[meet], r0[meet], r1[meet], c0[meet], c1[meet]))
        pix, lev, bi, bj, r0, r1, c0, c1 = (np.concatenate(a) for a in zip(*kids))
        # each child's middle texel: a failure there ends its pixel before the next level
        ti = (np.maximum(bi << lev, r0) + np.minimum(((bi + 1) << lev) - 1, r1)) // 2
        tj = (np.maximum(bj << lev, c0) + np.minimum(((bj + 1) << lev) - 1, c1)) // 2
        test = np.flatnonzero((lev > 0) & (labels[ti * W + tj] != label[pix]))
        q, ti, tj = pix[test], ti[test], tj[test]
        fine = _box_clear(px, p[q], n[q], pp[q], den[q], gx[q], gy[q], m[q], RR, ti, ti, tj, tj,
                          tables.near9[ti, tj], tables.far9[ti, tj])
        ok[q[~fine]] = False
    return ok


def past_edge_bounds(tables: PlaneTables, side, i_lo, i_hi, j_lo, j_hi, offscreen):
    """(least, greatest) depth that the rays of boxes past the image's edge ``side`` read there
    (one row per box): the border's texels their clamped cells span (a clamped ray's row and
    the next, or column), or +inf with ``offscreen="open"``."""
    if offscreen == "open":
        return np.full(len(i_lo), np.inf), np.full(len(i_lo), np.inf)
    if side in ("right", "left"):
        return tables.border_bounds(side, i_lo, i_hi + 1)
    return tables.border_bounds(side, j_lo, j_hi + 1)


def _past_edge_clear(px, tables: PlaneTables, geometry, side, q, i_lo, i_hi, j_lo, j_hi, offscreen):
    """:func:`_box_clear` of boxes past the image's edge ``side`` (one row per box and its pixel
    ``q``), with the depths of :func:`past_edge_bounds`."""
    p, n, pp, den, gx, gy, m, RR = geometry
    near, far = past_edge_bounds(tables, side, i_lo, i_hi, j_lo, j_hi, offscreen)
    return _box_clear(px, p[q], n[q], pp[q], den[q], gx[q], gy[q], m[q], RR, i_lo, i_hi, j_lo, j_hi, near, far)


def _leaf_clear(px, tables, ok, geometry, boxes, offscreen):
    """Set ``ok`` False for the pixels with a box of ``boxes`` (side, q, i_lo, i_hi, j_lo, j_hi)
    that :func:`_past_edge_clear` fails."""
    for side, q, i_lo, i_hi, j_lo, j_hi in boxes:
        keep = ok[q]
        if keep.any():
            q = q[keep]
            fine = _past_edge_clear(px, tables, geometry, side, q, i_lo[keep], i_hi[keep], j_lo[keep], j_hi[keep],
                                    offscreen)
            ok[q[~fine]] = False


#: Halvings of :func:`_overflow_clear`'s boxes (each axis, while longer than a texel) before a
#: failing box fails its pixel.
OVERFLOW_SPLITS = 2


def _overflow_clear(px, tables: PlaneTables, ok, geometry, strip, offscreen):
    """Set ``ok`` False for the pixels of one strip whose rays beyond the image's edge are not
    all clear of the ball (:func:`_clear_of_ball`'s test, :func:`_box_clear`).

    A ray past the right edge (pixel x beyond the last centre) reads, with
    ``offscreen="clamp"``, the bilinear depth at the clamped position: between two texels of
    the last column, those of the rows the strip's rays reach once clamped (so its depth lies
    between their least and greatest, +inf on background, where a NaN read adds 0 anyway); with
    ``"open"`` an infinite depth. Its depth on the pixel's plane is the plane's along the ray
    itself. Each side's box of rays past the edge (the strip's rectangle from the border line
    outward, the other axis whole) is tested with those bounds; a box that fails is halved in
    each axis up to :data:`OVERFLOW_SPLITS` times, the border's bounds following its rows (or
    columns), and a box that still fails fails its pixel. A corner's rays are past two edges
    and checked by both sides' boxes, with either side's bounds.
    """
    H, W = px.shape
    x0, x1, y0, y1, out = strip
    boxes = []
    for side, past in (("right", x1 > W - 1), ("left", x0 < 0), ("bottom", y1 > H - 1), ("top", y0 < 0)):
        q = np.flatnonzero(ok & out & past)
        if not q.size:
            continue
        i_lo, i_hi, j_lo, j_hi = y0[q], y1[q], x0[q], x1[q]
        if side == "right":
            j_lo = np.full(q.size, W - 1)
        elif side == "left":
            j_hi = np.zeros(q.size, dtype=np.intp)
        elif side == "bottom":
            i_lo = np.full(q.size, H - 1)
        else:
            i_hi = np.zeros(q.size, dtype=np.intp)
        boxes.append((side, q, i_lo, i_hi, j_lo, j_hi))
    # first one texel each: past the edge next to it, level with the pixel (most pixels that
    # fail, fail there; a texel that fails fails its pixel)
    row, col = np.divmod(px.index, W)
    probes = []
    for side, q, i_lo, i_hi, j_lo, j_hi in boxes:
        i = np.clip(row[q], i_lo, i_hi) if side in ("right", "left") else (i_lo if side == "bottom" else i_hi)
        j = np.clip(col[q], j_lo, j_hi) if side in ("top", "bottom") else (j_lo if side == "right" else j_hi)
        probes.append((side, q, i, i, j, j))
    _leaf_clear(px, tables, ok, geometry, probes, offscreen)
    for split in range(OVERFLOW_SPLITS + 1):
        more = []
        for side, q, i_lo, i_hi, j_lo, j_hi in boxes:
            keep = ok[q]
            q, i_lo, i_hi, j_lo, j_hi = q[keep], i_lo[keep], i_hi[keep], j_lo[keep], j_hi[keep]
            if not q.size:
                continue
            bad = ~_past_edge_clear(px, tables, geometry, side, q, i_lo, i_hi, j_lo, j_hi, offscreen)
            q, i_lo, i_hi, j_lo, j_hi = q[bad], i_lo[bad], i_hi[bad], j_lo[bad], j_hi[bad]
            single = (i_hi == i_lo) & (j_hi == j_lo)
            if split == OVERFLOW_SPLITS or single.all():
                ok[q] = False
                continue
            ok[q[single]] = False
            q, i_lo, i_hi, j_lo, j_hi = q[~single], i_lo[~single], i_hi[~single], j_lo[~single], j_hi[~single]
            i_mid = (i_lo + i_hi) // 2
            j_mid = (j_lo + j_hi) // 2
            for a_lo, a_hi in ((i_lo, i_mid), (i_mid + 1, i_hi)):
                for b_lo, b_hi in ((j_lo, j_mid), (j_mid + 1, j_hi)):
                    # (an axis one texel long has no second half)
                    real = (a_lo <= a_hi) & (b_lo <= b_hi)
                    more.append((side, q[real], a_lo[real], a_hi[real], b_lo[real], b_hi[real]))
        boxes = more
        if not boxes:
            break


def _box_clear(px, p, n, pp, den, gx, gy, m, RR, i_lo, i_hi, j_lo, j_hi, near9, far9):
    """Whether every ray within one pixel of the texels i_lo..i_hi, j_lo..j_hi misses the ball
    or has its depth (between ``near9`` and ``far9``) and its plane's depth on one side of its
    chord (:func:`_clear_of_ball`; one row per box and its pixel)."""
    # the rays' positions: from half a pixel before the first texel's centre minus one pixel to
    # the last one's plus one; as a box of directions (a, b) = (x / z, y / z), or of view (x, y)
    a_lo, a_hi = (j_lo - 0.5 - px.cx) / px.fx, (j_hi + 1.5 - px.cx) / px.fx
    a_lo, a_hi = np.minimum(a_lo, a_hi), np.maximum(a_lo, a_hi)
    b_lo, b_hi = (px.cy - i_hi - 1.5) / px.fy, (px.cy - i_lo + 0.5) / px.fy
    b_lo, b_hi = np.minimum(b_lo, b_hi), np.maximum(b_lo, b_hi)
    a = 0.5 * (a_lo + a_hi)
    b = 0.5 * (b_lo + b_hi)
    # the plane's reach from the centre to the box's corners, in pixels times the gradient
    s = (0.5 * (j_hi - j_lo) + 1.0) * gx + (0.5 * (i_hi - i_lo) + 1.0) * gy
    if px.perspective:
        gap = _box_distance(a_lo, a_hi, b_lo, b_hi, p[:, 0] / p[:, 2], p[:, 1] / p[:, 2])
        uu_lo = 1.0 + _box_distance(a_lo, a_hi, b_lo, b_hi, 0.0, 0.0) ** 2
        uu_hi = 1.0 + np.maximum(np.abs(a_lo), np.abs(a_hi)) ** 2 + np.maximum(np.abs(b_lo), np.abs(b_hi)) ** 2
        D2 = (p[:, 2] * gap) ** 2 / uu_hi
        along = np.sqrt(np.maximum(pp - D2, 0.0))
        half = np.sqrt(np.maximum(RR - D2, 0.0))
        z_far = (along + half) / np.sqrt(uu_lo) + m
        z_near = (along - half) / np.sqrt(uu_hi) - m
        # 1 / z_P = (n . u) / (n . p), u = (a, b, 1) (Loos & Sloan 2010, Sec. 4.4)
        inv = -(a * n[:, 0] + b * n[:, 1] + n[:, 2]) / den
        far = (inv + s <= 1.0 / z_far) & (inv - s > 0)
        with np.errstate(divide="ignore"):
            near = (z_near > 0) & (inv - s >= 1.0 / z_near)
    else:
        D2 = _box_distance(a_lo, a_hi, b_lo, b_hi, p[:, 0], p[:, 1]) ** 2
        half = np.sqrt(np.maximum(RR - D2, 0.0))
        z_far = p[:, 2] + half + m
        z_near = p[:, 2] - half - m
        z_P = p[:, 2] + (n[:, 0] * (a - p[:, 0]) + n[:, 1] * (b - p[:, 1])) / den
        far = z_P - s >= z_far
        near = (z_near > 0) & (z_P + s <= z_near)
    # rays that miss the ball by far more than the kernel's rounding of h^2 add 0
    misses = D2 > RR + 1e-8 * pp
    return misses | (far & (near9 >= z_far)) | (near & (far9 <= z_near))


def on_one_plane(px, radius, tables: PlaneTables, strips: int = FOOTPRINT_STRIPS, clear: bool = True,
                 offscreen: str | None = "clamp") -> np.ndarray:
    """(k,) bool: the pixels whose every view ray through the ball reads, with the bilinear
    fetch, a depth on the pixel's own plane, or (``clear`` and ``tables`` with depth) a depth
    that, with the plane's own along that ray, lies beyond the ball's depth range on one side
    (:func:`_clear_of_ball`).

    The ball's rays (the box of :func:`ball_box`, cut into ``strips`` equal bands of b) land,
    band by band, in rectangles of pixel positions (:func:`footprint_rows`: the rays through
    the ball only; a ray that misses it adds nothing to the kernel's sums); the bilinear cells
    of a rectangle span the pixels from floor of its low corner to one past floor of its high
    corner. When every such rectangle lies in the image and all its pixels carry the pixel's
    plane label, every fetched depth is the plane's (1/z, or z orthographically, is affine in
    the image position on a plane, and bilinear interpolation reproduces it), so each
    segment's occupied part is its part behind the tangent plane and the control variate of
    :func:`ray_kernel` cancels it exactly: V = 1/2 (1 with ``normal_clamp``), what the kernel
    returns there. The rays of :func:`_clear_of_ball` add exactly 0 too.

    A rectangle that leaves the image is checked in two parts: the rays that land in the image
    read the cells of its part in the image, as above; the others read the image's border line
    (``offscreen="clamp"``: the clamped position's depth, not the plane's along the ray) or
    nothing (``"open"``: an infinite depth), and qualify only as rays clear of the ball
    (:func:`_overflow_clear`). ``offscreen=None``: a footprint that leaves the image never
    qualifies.
    """
    a0, a1, b0, b1, exact = ball_box(px, radius)
    H, W = px.shape
    label = tables.labels.reshape(-1)[px.index]
    inside = exact & (label > 0)
    plane = np.ones(len(px.index), dtype=bool)
    rects = []
    overflow = []
    # footprints this far past the image's edge (balls at the eye) are not checked: no
    # integer overflow in the rectangles' corners
    reach = 4 * (H + W)
    edges = np.linspace(0.0, 1.0, int(strips) + 1)
    # the tests of other surfaces (and of the rays past the image's edge) run after the strips
    others = clear and tables.near9 is not None
    for s_lo, s_hi in zip(edges[:-1], edges[1:]):
        lo_b = b0 + s_lo * (b1 - b0)
        hi_b = b0 + s_hi * (b1 - b0)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            lo_a, hi_a = footprint_rows(px, radius, lo_b, hi_b, a0, a1) if strips > 1 else (a0, a1)
            # pixel coordinates relative to the first pixel centre; y decreases as b grows
            x0 = np.floor(px.fx * lo_a + px.cx - 0.5)
            x1 = np.floor(px.fx * hi_a + px.cx - 0.5) + 1
            y0 = np.floor(px.cy - 0.5 - px.fy * hi_b)
            y1 = np.floor(px.cy - 0.5 - px.fy * lo_b) + 1
        with np.errstate(invalid="ignore"):
            inside &= (x0 > -reach) & (y0 > -reach) & (x1 < W + reach) & (y1 < H + reach)
        x0, x1, y0, y1 = (np.where(inside, q, 0).astype(np.intp) for q in (x0, x1, y0, y1))
        # beyond the image's edge ``offscreen="clamp"`` repeats the border's depth (not the
        # plane's) and ``"open"`` reads nothing: those rays must be clear of the ball
        out = (x0 < 0) | (y0 < 0) | (x1 > W - 1) | (y1 > H - 1)
        if not (others and offscreen is not None):
            inside &= ~out
        # the part in the image: the rays that land there read its cells
        c0, c1 = np.clip(x0, 0, W - 1), np.clip(x1, 0, W - 1)
        r0, r1 = np.clip(y0, 0, H - 1), np.clip(y1, 0, H - 1)
        if others:
            one = tables.one_label(label, r0, r1, c0, c1)
        else:
            # the plane-only test: only the pixels still in it need this strip's rectangle
            one = np.zeros(len(label), dtype=bool)
            live = np.flatnonzero(inside & plane)
            one[live] = tables.one_label(label[live], r0[live], r1[live], c0[live], c1[live])
        plane &= one
        rects.append((c0, c1, r0, r1, one))
        overflow.append((x0, x1, y0, y1, out & inside))
    leaves = np.logical_or.reduce([o[4] for o in overflow])
    ok = inside & plane & ~leaves
    if others:
        sel = np.flatnonzero(inside & ~ok)
        if sel.size:
            ok[sel] = _clear_of_ball(px, radius, tables, sel, [
                None if rect[4][sel].all() else tuple(q[sel] for q in rect) for rect in rects],
                [tuple(q[sel] for q in o) if o[4][sel].any() else None for o in overflow], offscreen)
    return ok
