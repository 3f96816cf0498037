"""The view-ray segment kernel of :func:`vobscure.vo_reference` with a lower cost per ray.

It computes what :func:`vobscure.screenspace._segment.ray_kernel` computes (the same rays,
the same depth-buffer occupancy, the same closed forms; ``docs/screenspace.md``, "The
converged reference"), equal to it within the rounding of the float32 steps below (a
tolerance derived in ``tests/test_screen_reference.py``, which compares the two), restructured
for speed:

- the depth fetch reads one precomputed row per bilinear cell (:class:`DepthCells`: the
  cell's interpolant as a bilinear polynomial, and whether its four corners are all
  finite) instead of gathering four corners and testing them;
- the weights along a segment are differences of one antiderivative F(t) of J rho,
  evaluated in Horner form at the few points that bound the intervals (the segment's
  occupied part minus its part behind the tangent plane is F(cut) - F(lo), plus the
  even part F(h) + F(-h) where the half-ball lies beyond the plane);
- the arithmetic is in place where it can be, and the pixels of a chunk are split into
  blocks computed on a thread pool (NumPy releases the GIL in its loops); every operation
  is per pixel, so the blocks do not change the values;
- with the default options under perspective (``vobscure compare``'s case) the chord, the
  tangent plane and the terms are float32, four rays at a time (:func:`_simple_perspective`).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import _common as C
from ._segment import BALL_MASS, PLANE_RTOL, ball_box

#: Valid pixels per chunk of :func:`vobscure.vo_reference`'s segment path. The chunks run on a
#: thread pool, one per core at a time (NumPy releases the GIL in its loops, and the Python
#: between them in one chunk overlaps the other's arithmetic); every operation is per pixel, so
#: the chunks do not change the values. Peak memory: under 630 bytes a pixel of the chunks in
#: flight (82 MB measured by tracemalloc for the atrium at 640 x 360 with chunks of 131072
#: pixels, the per-image tables included).
CHUNK_PIXELS = 65536

#: Rays integrated at once by the float32 path (:func:`_simple_perspective`): its operations
#: on (rays, pixels) arrays are four times as long, so that the two threads spend less of their
#: time in the Python between them (which holds the interpreter's lock); the arrays of a chunk
#: grow by about 80 bytes a pixel per ray.
RAY_BATCH = 4

_POOL: list[ThreadPoolExecutor] = []


def _threads() -> int:
    """The cores this process may use (the chunks run on as many threads)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


def parallel_chunks(fn, items) -> list:
    """``[fn(item) for item in items]``, on this module's own thread pool when there are several
    (its own: a caller may itself run on the tracer's pool)."""
    if len(items) <= 1 or _threads() == 1:
        return [fn(item) for item in items]
    if not _POOL:
        _POOL.append(ThreadPoolExecutor(_threads(), thread_name_prefix="vobscure-segments"))
    return list(_POOL[0].map(fn, items))


def balanced_parts(index: np.ndarray, chunk: int) -> list[np.ndarray]:
    """``index`` cut into parts of at most ``chunk`` items, of equal sizes (within one) and as
    many as the threads of :func:`parallel_chunks` or a multiple of them, so that no thread
    idles while another finishes a last part (11 chunks of 65536 on 2 threads left one
    thread a chunk's time with nothing to do).

    Examples
    --------
    >>> sizes = [len(p) for p in balanced_parts(np.arange(10), 4)]   # 3 or 4 parts, by the threads
    >>> sum(sizes), max(sizes) <= 4, max(sizes) - min(sizes) <= 1
    (10, True, True)
    """
    threads = _threads()
    count = -(-len(index) // max(1, int(chunk)))
    count = max(threads, -(-count // threads) * threads)
    bounds = np.linspace(0, len(index), count + 1).round().astype(np.intp)
    return [index[a:b] for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


class DepthCells:
    """Per-cell bilinear data of a depth image, built once per image.

    Cell (i, j) spans the pixel centres (i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1)
    (clamped at the last row and column, as :func:`vobscure.screenspace._common.fetch_depth`
    does). With v the interpolated quantity (1/z under perspective, z otherwise) and
    (tx, ty) in [0, 1]^2 the position in the cell, the interpolant
    (1 - ty) ((1 - tx) v00 + tx v01) + ty ((1 - tx) v10 + tx v11) is stored as the
    coefficients of c0 + c1 tx + c2 ty + c3 tx ty, NaN where any of the four corners is not
    finite (there the nearest pixel's depth is read: the NaN marks those cells at no cost).

    The coefficients and the interpolation are float32, the depth buffer's own precision: the
    fetched depth then carries a relative rounding of a few float32 ulps (under 5e-7, against
    6e-8 for the float32 depths themselves), far inside :data:`~vobscure.screenspace._segment.PLANE_RTOL`
    and the margin :data:`~vobscure.screenspace._segment.CLEAR_MARGIN` of the exact pixels' tests,
    at about half the cost of the float64 gathers and arithmetic (the float32 chord of
    :func:`_simple_perspective` is another matter: see ``CLEAR_MARGIN``).

    Examples
    --------
    >>> import numpy as np
    >>> cells = DepthCells(np.array([[1.0, 2.0], [1.0, 2.0]]), reciprocal=True)
    >>> float(cells.fetch(np.array([0.5]), np.array([0.0]), "clamp")[0])    # 1 / (1/2 + 1/4)
    1.3333333333333333
    >>> cells = DepthCells(np.array([[1.0, 2.0], [1.0, np.inf]]), reciprocal=True)
    >>> float(cells.fetch(np.array([0.5]), np.array([0.0]), "clamp")[0])    # nearest: (0, 1)
    2.0
    """

    def __init__(self, depth: np.ndarray, reciprocal: bool):
        depth = np.asarray(depth, dtype=np.float64)
        H, W = depth.shape
        self.shape = (H, W)
        self.flat = depth.reshape(-1)
        self.reciprocal = bool(reciprocal)
        i1 = np.minimum(np.arange(H) + 1, H - 1)
        j1 = np.minimum(np.arange(W) + 1, W - 1)
        corners = (depth, depth[:, j1], depth[i1, :], depth[i1][:, j1])
        ok = np.isfinite(corners[0])
        for c in corners[1:]:
            ok &= np.isfinite(c)
        with np.errstate(divide="ignore", invalid="ignore"):
            v00, v01, v10, v11 = ((1.0 / c) if reciprocal else c for c in corners)
            coef = np.stack([v00, v01 - v00, v10 - v00, (v11 - v10) - (v01 - v00)], axis=-1)
        coef[~ok] = np.nan
        self.coef = coef.reshape(H * W, 4).astype(np.float32)
        self.any_background = not ok.all()

    def fetch(self, fx: np.ndarray, fy: np.ndarray, offscreen: str, inside: bool = False,
              single: bool = False) -> np.ndarray:
        """Bilinear depth at the finite pixel coordinates (fx + 1/2, fy + 1/2), as
        ``fetch_depth(..., fetch="bilinear")`` with this image's ``reciprocal``. ``fx`` and
        ``fy`` (the coordinates relative to the first pixel centre, float64) are overwritten.
        ``inside``: the caller knows every coordinate lies within [0, W - 1] x [0, H - 1]
        (nothing to clamp). ``single``: float32 depths (the reciprocal taken in float32, one
        rounding more), else float64."""
        H, W = self.shape
        if not inside:
            if offscreen == "open":
                outside = (fx < -0.5) | (fx >= W - 0.5) | (fy < -0.5) | (fy >= H - 0.5)
            # (np.maximum then np.minimum: the same values as np.clip at less than half its cost)
            np.minimum(np.maximum(fx, 0.0, out=fx), W - 1, out=fx)
            np.minimum(np.maximum(fy, 0.0, out=fy), H - 1, out=fy)
        j0 = np.floor(fx)
        i0 = np.floor(fy)
        fx -= j0                           # tx
        fy -= i0                           # ty
        i0 *= W
        i0 += j0
        cell = i0.astype(np.intp)          # the cell's flat index (exact in float64)
        c = self.coef.take(cell, axis=0)
        tx = fx.astype(np.float32)
        ty = fy.astype(np.float32)
        # c0 + c1 tx + c2 ty + c3 tx ty
        v = c[:, 3] * ty
        v += c[:, 1]
        v *= tx
        np.multiply(c[:, 2], ty, out=ty)
        v += ty
        v += c[:, 0]
        if single:
            d = v
        else:
            d = j0
            d[...] = v
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.reciprocal:
                np.divide(d.dtype.type(1.0), d, out=d)
        if self.any_background and np.isnan(np.add.reduce(d)):
            # a background corner (NaN coefficients): the nearest pixel's depth, the cell's
            # corner nearest to (x, y) = (fx + 1/2, fy + 1/2) (at a clamped edge t is 0 and
            # the corner the edge pixel)
            bad = np.flatnonzero(np.isnan(d))
            i, j = np.divmod(cell[bad], W)
            i += fy[bad] >= 0.5
            j += fx[bad] >= 0.5
            d[bad] = self.flat[i * W + j]
        if offscreen == "open" and not inside:
            d[outside] = np.inf
        return d


def _antiderivative(t, z_m, zz, h2, perspective, quadratic, out):
    """F(t) = int_0^t J rho' dt into ``out``, with rho' = h^2 - t^2 (the quadratic falloff
    without its factor |u|^2 / R^2, applied by the caller) or 1, J = (z_m + t)^2 under
    perspective and 1 orthographically (``_segment._weights`` gives int_a^b = F(b) - F(a))."""
    if perspective:
        if quadratic:
            # h2 (zz t + z_m t^2 + t^3/3) - (zz t^3/3 + z_m t^4/2 + t^5/5)
            np.multiply(t, -0.2, out=out)
            out -= 0.5 * z_m
            out *= t
            out += (h2 - zz) / 3.0
            out *= t
            out += h2 * z_m
            out *= t
            out += h2 * zz
        else:
            # zz t + z_m t^2 + t^3/3
            np.multiply(t, 1.0 / 3.0, out=out)
            out += z_m
            out *= t
            out += zz
    elif quadratic:
        # h2 t - t^3/3
        np.multiply(t, t, out=out)
        out *= -1.0 / 3.0
        out += h2
    else:
        out[...] = 1.0
    out *= t
    return out


def _cube_difference(x, y):
    """x^3 - y^3 as (x - y)(x^2 + x y + y^2): rounded relative to the difference itself (the
    difference of the cubes would be rounded relative to x^3)."""
    s = x * x
    s += x * y
    s += y * y
    s *= x - y
    return s


def _depth_terms(z_m, h, zp, d, away, perspective):
    """The control variate's difference along each ray for the default options (constant
    falloff, the whole ball, no thickness), from the depths of the chord's ends z_m -+ h, of the
    tangent plane along the ray ``zp`` and of the fetched depth ``d``: the occupied part
    [max(d, 0), z_m + h] minus the part behind the plane ([zp, z_m + h], or [z_m - h, zp] where
    ``away``), each clipped to the chord, integrated with J = z^2 as z^3 differences (three
    times the integral; the caller divides by 3) under perspective, J = 1 orthographically.
    A depth on the plane (within :data:`PLANE_RTOL`) adds exactly 0, as do a depth and a plane
    both beyond one end of the chord (their clipped depths are the same number). ``d`` and
    ``zp`` are overwritten. Any float dtype (the float32 path of :func:`_simple_perspective`
    too): each term is rounded relative to itself (the cubes' differences factored), and the
    plane's depth is selected by products with 0 and 1, exact for the finite, clipped ends
    (faster than a masked copy; a NaN depth gives a NaN term, which the caller sets to 0)."""
    z_lo = z_m - h
    z_hi = np.add(z_m, h, out=h)
    zc = np.minimum(np.maximum(zp, z_lo), z_hi)
    if not perspective:
        # Loos & Sloan 2010, Sec. 4: occupied where max(d, 0) < z (a negative d is never on
        # the plane below, whose test needs |d - zp| < PLANE_RTOL d)
        np.maximum(d, 0.0, out=d)
    zl = np.minimum(np.maximum(d, z_lo), z_hi)
    q = np.subtract(d, zp, out=zp)
    np.abs(q, out=q)
    # (< rather than <=: a background d = inf is not on the plane); on the plane the occupied
    # part starts where the plane does: zl = zc there
    on = np.less(q, PLANE_RTOL * d).view(np.uint8).astype(zl.dtype)
    zl *= 1 - on
    on *= zc
    zl += on
    if perspective:
        # Sec. 4.4: zc^3 - zl^3, or (z_hi^3 - zc^3) - (zl^3 - z_lo^3) where away
        out = _cube_difference(zc, zl)
        if away.any():
            other = _cube_difference(z_hi, zc)
            other -= _cube_difference(zl, z_lo)
            out = np.where(away, other, out)
        return out
    out = np.subtract(zc, zl)
    if away.any():
        out = np.where(away, (z_hi + z_lo) - zl - zc, out)
    return out


def _even(z_m, h2, perspective, quadratic):
    """F(h) + F(-h) (0 orthographically, where J is even in t)."""
    if not perspective:
        return 0.0
    return z_m * h2 * h2 if quadratic else 2.0 * z_m * h2


def segment_kernel(px, *, radius, unit, normal_clamp, thickness, falloff, cells, offscreen, shift):
    """:func:`vobscure.screenspace._segment.ray_kernel` with the bilinear depth of ``cells``
    (a :class:`DepthCells` of ``px.depth``; None: ``fetch="nearest"``): the same ((k,) V,
    (k,) exact) within the rounding of its float32 steps (see the module)."""
    R = float(radius)
    a0, a1, b0, b1, exact = ball_box(px, R)
    H, W = px.shape
    with np.errstate(invalid="ignore"):
        # the pixels whose every ray lands in the image (their fetches clamp nothing)
        x0, x1 = px.fx * a0 + px.cx - 0.5, px.fx * a1 + px.cx - 0.5
        y0, y1 = px.cy - 0.5 - px.fy * b1, px.cy - 0.5 - px.fy * b0
        inside = ((np.minimum(x0, x1) >= 0) & (np.maximum(x0, x1) <= W - 1) &
                  (np.minimum(y0, y1) >= 0) & (np.maximum(y0, y1) <= H - 1))
    v = np.empty(len(px.index))
    for sel, within in ((np.flatnonzero(inside), True), (np.flatnonzero(~inside), False)):
        if sel.size:
            v[sel] = _block(px, sel, a0[sel], a1[sel] - a0[sel], b0[sel], b1[sel] - b0[sel], R, unit, normal_clamp,
                            thickness, falloff, cells, offscreen, shift[sel], within)
    return v, exact


def _block(px, sel, a0, da, b0, db, R, unit, normal_clamp, thickness, falloff, cells, offscreen, shift, inside):
    """The V of the pixels ``sel`` of ``px`` (see :func:`segment_kernel`); ``inside``: all their
    rays land in the image."""
    quadratic = falloff == "quadratic"
    persp = px.perspective
    pc = [np.ascontiguousarray(px.p[sel, a]) for a in range(3)]
    nc = [np.ascontiguousarray(px.n[sel, a]) for a in range(3)]
    n_p = nc[0] * pc[0] + nc[1] * pc[1] + nc[2] * pc[2]
    pp = pc[0] * pc[0] + pc[1] * pc[1] + pc[2] * pc[2]
    RR = R * R
    RR_pp = RR - pp
    # the rays' pixel coordinates are finite when the box of rays is
    finite = all(np.isfinite(q).all() for q in (a0, da, b0, db))
    if cells is None or not finite:
        def fetch(fx, fy):
            return C.fetch_depth(px.depth, fx + 0.5, fy + 0.5, fetch="bilinear" if cells else "nearest",
                                 offscreen=offscreen, reciprocal=persp)
    else:
        def fetch(fx, fy):
            return cells.fetch(fx, fy, offscreen, inside)
    cx, cy = px.cx - 0.5, px.cy - 0.5
    s1 = np.ascontiguousarray(shift[:, 0])
    s2 = np.ascontiguousarray(shift[:, 1])
    m = len(a0)
    # the default options: the segment's terms from its ends' depths (_depth_terms)
    simple = thickness is None and not normal_clamp and not quadratic
    if simple and persp and cells is not None and finite:
        return _simple_perspective(px, pc, nc, n_p, a0, da, b0, db, R, unit, cells, offscreen, s1, s2, inside)
    acc = np.zeros(m)
    F_lo, F_b, tmp = np.empty(m), np.empty(m), np.empty(m)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for u1, u2 in unit:
            ua = u1 + s1
            ua -= np.floor(ua)
            ub = u2 + s2
            ub -= np.floor(ub)
            a = ua
            a *= da
            a += a0
            b = ub
            b *= db
            b += b0
            # every point of the ray projects here (camera.kernel.project_xy at Z = 1), minus
            # the half pixel to the first pixel centre
            fx = px.fx * a
            fx += cx
            fy = px.fy * b
            np.subtract(cy, fy, out=fy)
            if persp:
                uu = a * a
                uu += b * b
                uu += 1.0
                up = a * pc[0]
                up += b * pc[1]
                up += pc[2]
                z_m = up / uu
                h2 = up * z_m
                h2 += RR_pp
                h2 /= uu
                c1 = a * nc[0]
                c1 += b * nc[1]
                c1 += nc[2]
                # the tangent plane n . (X - p) = 0 meets the ray at depth n.p / n.u
                # (Loos & Sloan 2010, Sec. 4.4), t = cut there
                zp = n_p / c1
                cut = None if simple else zp - z_m
                if quadratic:
                    uu_r2 = uu
                    uu_r2 /= RR
            else:
                z_m = pc[2]
                ex, ey = a - pc[0], b - pc[1]
                h2 = ex * ex
                h2 += ey * ey
                np.subtract(RR, h2, out=h2)
                c1 = nc[2]
                # the tangent plane: n . (L(z_m + t) - p) = c0 + c1 t (Sec. 4.4) is 0 at cut
                cut = nc[0] * ex
                cut += nc[1] * ey
                cut /= c1
                np.negative(cut, out=cut)
                zp = z_m + cut
                uu_r2 = 1.0 / RR
            np.maximum(h2, 0.0, out=h2)
            h = np.sqrt(h2)
            away = c1 > 0          # the half-ball lies beyond the plane along the ray
            if simple:
                contrib = _depth_terms(z_m, h, zp, fetch(fx, fy), away, persp)
                if not np.isfinite(np.add.reduce(contrib)):
                    contrib[~np.isfinite(contrib)] = 0.0
                acc += contrib
                continue
            mh = np.negative(h)
            np.minimum(np.maximum(cut, mh, out=cut), h, out=cut)
            if normal_clamp:
                lo_seg = np.where(away, cut, mh)
                hi_seg = np.where(away, h, cut)
            else:
                lo_seg, hi_seg = mh, h
            d = fetch(fx, fy)
            # Sec. 4 (and 4.3): occupied where max(d, 0) < z (< d + thickness); a depth on
            # the tangent plane up to rounding starts exactly where the plane does
            # (under perspective the segment lies in z > 0, so max(d, 0) - z_m and d - z_m
            # clip to the same lo)
            lo = d - z_m if persp else np.maximum(d, 0.0) - z_m
            np.minimum(np.maximum(lo, lo_seg, out=lo), hi_seg, out=lo)
            q = np.subtract(d, zp, out=zp)                  # d minus the plane's depth
            np.abs(q, out=q)
            # (< rather than <=: a background d = inf is not on the plane)
            on_plane = q < PLANE_RTOL * d
            if on_plane.any():
                np.copyto(lo, cut, where=on_plane)          # cut lies in [lo_seg, hi_seg]
            zz = z_m * z_m if persp else None
            _antiderivative(lo, z_m, zz, h2, persp, quadratic, F_lo)
            if thickness is None and not normal_clamp:
                # occupied [lo, h] minus behind the plane ([cut, h], or [-h, cut] when away)
                _antiderivative(cut, z_m, zz, h2, persp, quadratic, F_b)
                if persp and away.any():
                    np.subtract(_even(z_m, h2, persp, quadratic), F_b, out=F_b, where=away)
                elif away.any():
                    np.negative(F_b, out=F_b, where=away)
                contrib = np.subtract(F_b, F_lo, out=F_b)
            else:
                if thickness is None:
                    hi = hi_seg
                else:
                    hi = d + thickness
                    hi -= z_m
                    np.minimum(np.maximum(hi, lo_seg, out=hi), hi_seg, out=hi)
                    np.maximum(hi, lo, out=hi)
                contrib = _antiderivative(hi, z_m, zz, h2, persp, quadratic, F_b)
                contrib -= F_lo
                if not normal_clamp:
                    F_c = _antiderivative(cut, z_m, zz, h2, persp, quadratic, F_lo)
                    F_h = _antiderivative(h, z_m, zz, h2, persp, quadratic, tmp)
                    # below = F(cut) - F(-h) where away, F(h) - F(cut) elsewhere; F(-h) = even - F(h)
                    below = np.where(away, F_c + F_h - _even(z_m, h2, persp, quadratic), F_h - F_c)
                    contrib -= below
            if quadratic:
                contrib *= uu_r2
            if not np.isfinite(np.add.reduce(contrib)):
                contrib[~np.isfinite(contrib)] = 0.0
            acc += contrib
    mass = BALL_MASS[falloff] * R ** 3
    scale = (da * db) / len(unit)
    if simple and persp:
        scale /= 3.0                # _depth_terms: 3 int z^2 dz
    if normal_clamp:
        return 1.0 - scale * acc / (0.5 * mass)
    # control variate: its scaled mean is mass / 2 exactly (_segment.ray_kernel)
    return 0.5 - scale * acc / mass


def _simple_perspective(px, pc, nc, n_p, a0, da, b0, db, R, unit, cells, offscreen, s1, s2, inside):
    """The V of :func:`_block` for the default options (constant falloff, the whole ball, no
    thickness) under perspective with the bilinear depth of ``cells``: each ray's terms by
    :func:`_depth_terms`, with the chord, the tangent plane and the terms in float32 (the ray's
    pixel position stays float64, so that the fetched depth and the plane's along the ray meet
    the ray at the same place). A term is rounded relative to itself (cube differences in
    factored form; the chord's half-length from |u x p|, equal by Lagrange's identity to
    |u|^2 |p|^2 - (u . p)^2, which cancels); the sum is float64. The difference from the float64
    kernel stays within the tolerance derived in ``tests/test_screen_reference.py`` (a few
    float32 ulps of the chord's ends, times z^2 and the box's area over the ball's weight). A
    depth on the tangent plane (within :data:`PLANE_RTOL`) adds exactly 0."""
    f4 = np.float32
    p0, p1, p2 = (q.astype(f4) for q in pc)
    n0, n1, n2 = (q.astype(f4) for q in nc)
    n_p = n_p.astype(f4)
    RR = f4(R * R)
    one, zero = f4(1.0), f4(0.0)
    # the ray's pixel position fx = fx0 + u_a fxa, fy = fy0 - u_b fyb (float64)
    fxa = px.fx * da
    fx0 = px.fx * a0 + (px.cx - 0.5)
    fyb = px.fy * db
    fy0 = (px.cy - 0.5) - px.fy * b0
    # (the box's area over the rays, float64: _depth_terms' 3 int z^2 dz)
    scale = (da * db) / len(unit) / 3.0
    a0, da, b0, db = (q.astype(f4) for q in (a0, da, b0, db))
    acc = np.zeros(len(a0))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for k in range(0, len(unit), RAY_BATCH):
            # RAY_BATCH rays at once, (rays, pixels) arrays; each ray's point of the unit
            # square, shifted (float64: the plain kernel's rays, which a float32 shift would
            # move across the depth buffer's edges)
            u1, u2 = np.asarray(unit[k:k + RAY_BATCH]).T[:, :, None]
            ua = u1 + s1
            ua -= np.floor(ua)
            ub = u2 + s2
            ub -= np.floor(ub)
            fx = ua * fxa
            fx += fx0
            fy = ub * fyb
            np.subtract(fy0, fy, out=fy)
            d = cells.fetch(fx.reshape(-1), fy.reshape(-1), offscreen, inside, single=True).reshape(fx.shape)
            a = ua.astype(f4)
            a *= da
            a += a0
            b = ub.astype(f4)
            b *= db
            b += b0
            # the ray u = (a, b, 1) meets the ball |z u - p| <= R for z in z_m -+ h:
            # z_m = u.p / |u|^2, h = sqrt(R^2 |u|^2 - |u x p|^2) / |u|^2
            uu = a * a
            uu += b * b
            uu += one
            inv_uu = np.divide(one, uu)
            z_m = a * p0
            z_m += b * p1
            z_m += p2
            z_m *= inv_uu
            t = b * p2
            t -= p1
            cross = t * t
            np.multiply(a, p2, out=t)
            np.subtract(p0, t, out=t)
            t *= t
            cross += t
            np.multiply(a, p1, out=t)
            t -= b * p0
            t *= t
            cross += t
            h = np.multiply(RR, uu, out=uu)
            h -= cross
            np.maximum(h, zero, out=h)
            np.sqrt(h, out=h)
            h *= inv_uu
            # the tangent plane n . (X - p) = 0 meets the ray at depth n.p / n.u
            # (Loos & Sloan 2010, Sec. 4.4)
            c1 = a * n0
            c1 += b * n1
            c1 += n2
            zp = np.divide(n_p, c1, out=t)
            away = c1 > 0          # the half-ball lies beyond the plane along the ray
            contrib = _depth_terms(z_m, h, zp, d, away, True)
            if not np.isfinite(np.add.reduce(contrib, axis=None)):
                contrib[~np.isfinite(contrib)] = 0.0
            for row in contrib:
                acc += row
    mass = BALL_MASS["constant"] * R ** 3
    return 0.5 - scale * acc / mass
