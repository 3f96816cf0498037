"""Reprojection of a history image from the previous frame into the current one.

Each covered pixel of the current frame looks up where its surface point was in the previous
frame: from the two views and its depth (the point's world position seen by the previous
view), or from a renderer's motion vectors (:attr:`vobscure.GBuffer.motion`). The history is
read there (bilinearly, or at the nearest pixel), tap by tap, and a tap counts only when the
previous frame saw the *same* surface there: its point lies within ``depth_tolerance`` x depth
of the current point's tangent plane. A pixel whose taps all fail is *disoccluded* (revealed in
this frame, or coming from outside the previous image): it has no history.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import check_choice, check_positive
from ..gbuffer import GBuffer

__all__ = ["DEPTH_TOLERANCE", "REPROJECT_FETCHES", "CHUNK_PIXELS", "Reprojection", "reproject"]

#: Default tolerance of the same-surface test, as a fraction of the depth: a previous-frame tap
#: counts when its surface point lies within 1 % of the depth of the current point's tangent plane.
DEPTH_TOLERANCE = 0.01
#: How the history is read at the reprojected position.
REPROJECT_FETCHES = ("bilinear", "nearest")
#: Pixels per block of the reprojection (bounds its temporaries to a few MB).
CHUNK_PIXELS = 32768


@dataclass(frozen=True)
class Reprojection:
    """The history of the previous frame seen from the current one (all (H, W) of the current
    frame).

    Attributes
    ----------
    value : (H, W) float
        The reprojected history; NaN where there is none.
    count : (H, W) int32
        The number of frames accumulated in that history (the smallest of the taps used); 0
        where there is none.
    found : (H, W) bool
        True where at least one tap passed the same-surface test.
    source : (H, W, 2) float64
        The continuous previous-frame pixel position (x, y) of each covered pixel; NaN on
        background and where the point is behind the previous camera.
    covered : (H, W) bool
        The current frame's covered pixels.
    """

    value: np.ndarray
    count: np.ndarray
    found: np.ndarray
    source: np.ndarray
    covered: np.ndarray

    @property
    def disoccluded(self) -> np.ndarray:
        """(H, W) bool: covered pixels of the current frame without history (revealed in this
        frame, or seen from outside the previous image)."""
        return self.covered & ~self.found


def _as_gbuffer(value, name: str) -> GBuffer:
    if not isinstance(value, GBuffer):
        raise ValueError(f"{name} must be a vobscure.GBuffer, got {type(value).__name__}")
    return value.inner()


def _same_view(current: GBuffer, previous: GBuffer) -> bool:
    """Whether the two frames share camera and world frame (a static camera)."""
    if current.camera != previous.camera or current.shape != previous.shape:
        return False
    try:
        Rc, tc = current.view_transform
        Rp, tp = previous.view_transform
    except ValueError:
        return False
    return bool(np.array_equal(Rc, Rp) and np.array_equal(tc, tp))


def _in_place(hist, cnt, current: GBuffer, previous: GBuffer, tol: float) -> Reprojection:
    """The reprojection between two frames of one view: every pixel reads its own history
    where it sees the same depth (within ``tol`` x depth) as before."""
    z = np.asarray(current.depth, dtype=np.float64)
    zp = np.asarray(previous.depth, dtype=np.float64)
    valid = current.valid
    with np.errstate(invalid="ignore"):
        found = valid & previous.valid & np.isfinite(hist) & (np.abs(zp - z) <= tol * z)
    H, W = current.shape
    jj, ii = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    source = np.where(valid[..., None], np.stack([jj, ii], axis=-1), np.nan)
    return Reprojection(value=np.where(found, hist, np.nan), count=np.where(found, cnt, 0).astype(np.int32),
                        found=found, source=source, covered=np.array(valid))


def _taps(px: np.ndarray, py: np.ndarray, shape: tuple, fetch: str):
    """The previous-frame pixels read at the continuous positions (px, py): per tap (rows, cols,
    weight, inside), rows and cols clipped into the image (``inside`` says which were in it;
    a NaN position is outside)."""
    H, W = shape
    lost = ~(np.isfinite(px) & np.isfinite(py))
    x = np.where(lost, -2.0, px - 0.5)
    y = np.where(lost, -2.0, py - 0.5)
    if fetch == "nearest":
        corners = [(np.rint(y), np.rint(x), None)]
    else:
        j0 = np.floor(x)
        i0 = np.floor(y)
        fx, fy = x - j0, y - i0
        gx, gy = 1.0 - fx, 1.0 - fy
        corners = [(i0, j0, gx * gy), (i0, j0 + 1, fx * gy), (i0 + 1, j0, gx * fy), (i0 + 1, j0 + 1, fx * fy)]
    out = []
    for i, j, w in corners:
        inside = (i >= 0) & (i < H) & (j >= 0) & (j < W)
        ii = np.clip(i, 0, H - 1, out=np.empty_like(i)).astype(np.intp)
        jj = np.clip(j, 0, W - 1, out=np.empty_like(j)).astype(np.intp)
        out.append((ii, jj, w, inside))
    return out


def _ray_tables(camera):
    """(a_x, b_x) per column and (a_y, b_y) per row: the view-space point seen through pixel
    centre (i, j) at depth z is (a_x[j] + b_x[j] z, a_y[i] + b_y[i] z, z) (perspective: a = 0;
    orthographic: b = 0), from the camera's own unproject."""
    W, H = camera.size
    cols = np.column_stack([np.arange(W) + 0.5, np.full(W, 0.5)])
    rows = np.column_stack([np.full(H, 0.5), np.arange(H) + 0.5])
    c0, c1 = camera.unproject(cols, 0.0), camera.unproject(cols, 1.0)
    r0, r1 = camera.unproject(rows, 0.0), camera.unproject(rows, 1.0)
    return c0[:, 0], c1[:, 0] - c0[:, 0], r0[:, 1], r1[:, 1] - r0[:, 1]


class _Frames:
    """The two frames of a reprojection and what every block of pixels reads."""

    def __init__(self, current, previous, hist, cnt, tol, fetch, motion):
        self.W = current.shape[1]
        self.prev_shape = previous.shape
        self.z = np.asarray(current.depth, dtype=np.float64).reshape(-1)
        self.zp = np.asarray(previous.depth, dtype=np.float64).reshape(-1)
        self.normal = np.asarray(current.normal, dtype=np.float64).reshape(-1, 3)
        self.hist, self.cnt = hist.reshape(-1), cnt.reshape(-1)
        self.tol, self.fetch, self.motion = tol, fetch, motion
        if motion is None:
            Rc, tc = current.view_transform
            Rp, tp = previous.view_transform
            # current view -> world -> previous view: p_prev = Rp Rc^T (p_cur - tc) + tp
            self.M = Rp @ Rc.T
            self.t = tp - self.M @ tc
            self.cur_rays = _ray_tables(current.camera)
            self.prev_rays = _ray_tables(previous.camera)
            self.prev_camera = previous.camera

    def block(self, idx):
        """(px, py, weighted history sum, weight sum, smallest count) of the pixels ``idx``."""
        i_c, j_c = np.divmod(idx, self.W)
        z_c = self.z[idx]
        zp = self.zp
        if self.motion is not None:
            m = self.motion[idx]
            px, py = j_c + 0.5 + m[:, 0], i_c + 0.5 + m[:, 1]
            limit = self.tol * z_c

            def passes(flat, iq, jq):
                return np.abs(zp[flat] - z_c) <= limit
        else:
            M, t = self.M, self.t
            ax, bx, ay, by = self.cur_rays
            X = ax[j_c] + bx[j_c] * z_c
            Y = ay[i_c] + by[i_c] * z_c
            P = [M[r, 0] * X + M[r, 1] * Y + M[r, 2] * z_c + t[r] for r in range(3)]
            n = self.normal[idx]
            n_p = [n @ M[r] for r in range(3)]
            offset = n_p[0] * P[0] + n_p[1] * P[1] + n_p[2] * P[2]
            pixels, _ = self.prev_camera.project(np.column_stack(P))
            px, py = pixels[:, 0], pixels[:, 1]
            limit = self.tol * np.abs(P[2])
            ax, bx, ay, by = self.prev_rays

            def passes(flat, iq, jq):
                # the tap's surface point along its pixel ray, against the current point's tangent plane
                zq = zp[flat]
                d = n_p[0] * (ax[jq] + bx[jq] * zq) + n_p[1] * (ay[iq] + by[iq] * zq) + n_p[2] * zq
                return np.abs(d - offset) <= limit

        k = len(idx)
        value_sum = np.zeros(k)
        weight = np.zeros(k)
        low = np.full(k, np.iinfo(np.int32).max, dtype=np.int64)
        Wp = self.prev_shape[1]
        with np.errstate(invalid="ignore", over="ignore"):
            for iq, jq, w, inside in _taps(px, py, self.prev_shape, self.fetch):
                flat = iq * Wp + jq
                h = self.hist[flat]
                ok = inside & np.isfinite(h) & passes(flat, iq, jq)
                w_ok = ok if w is None else w * ok
                value_sum += w_ok * np.where(ok, h, 0.0)
                weight += w_ok
                np.minimum(low, np.where(ok, self.cnt[flat], low), out=low)
        return px, py, value_sum, weight, low


def reproject(history, current, previous, *, count=None, fetch: str = "bilinear",
              depth_tolerance: float = DEPTH_TOLERANCE, motion=None) -> Reprojection:
    r"""The previous frame's ``history`` image as seen from the current frame.

    Parameters
    ----------
    history : (H', W') array_like of float
        An image of the previous frame (the accumulated visibility); NaN where undefined.
    current, previous : GBuffer
        The current and the previous frame (their inner frames when they have a guard band);
        ``history`` has the previous frame's shape.
    count : (H', W') array_like of int, optional
        The frames accumulated in ``history`` per pixel, reprojected alongside (the smallest
        of the taps used); default 1 where ``history`` is finite.
    fetch : {"bilinear", "nearest"}
        ``bilinear``: the four pixels around the reprojected position, weighted bilinearly
        over the taps that pass the test (renormalized); ``nearest``: the nearest pixel.
    depth_tolerance : float
        The same-surface test (> 0): a tap q passes when its previous-frame surface point
        :math:`X_q` lies within ``depth_tolerance`` x z of the current point's tangent plane,
        :math:`|n \cdot (X_q - X)| \le \tau z` (both in the previous view space; z the
        current point's depth there). A plane test rather than a depth test, so that taps
        along a surface seen at a grazing angle pass.
    motion : (H, W, 2) array_like, optional
        Motion vectors of the current frame in pixels towards the previous one (see
        :attr:`vobscure.GBuffer.motion`); default ``current.motion``, and when that is None too,
        the motion of the views. With motion vectors the test is on depth alone:
        :math:`|z_q - z| \le \tau z` with z the current depth.

    Returns
    -------
    Reprojection

    Examples
    --------
    A static camera: every covered pixel finds its own history.

    >>> import numpy as np, vobscure as vo
    >>> gb = vo.render_gbuffer(vo.scenes.cornell_box(), vo.scenes.cornell_box().camera(size=(16, 16)))
    >>> h = np.where(gb.valid, 0.25, np.nan)
    >>> r = vo.temporal.reproject(h, gb, gb)
    >>> bool(r.found[gb.valid].all()), float(np.nanmax(np.abs(r.value - h)))
    (True, 0.0)
    """
    current = _as_gbuffer(current, "current")
    previous = _as_gbuffer(previous, "previous")
    check_choice(fetch, "fetch", REPROJECT_FETCHES)
    tol = check_positive(depth_tolerance, "depth_tolerance")
    hist = np.asarray(history, dtype=np.float64)
    if hist.shape != previous.shape:
        raise ValueError(f"history must have the previous frame's shape {previous.shape}, got {hist.shape}")
    if count is None:
        cnt = np.isfinite(hist).astype(np.int32)
    else:
        cnt = np.asarray(count)
        if cnt.shape != previous.shape:
            raise ValueError(f"count must have the previous frame's shape {previous.shape}, got {cnt.shape}")
        cnt = cnt.astype(np.int32)
    if motion is None:
        motion = current.motion
    valid = current.valid
    if motion is None and _same_view(current, previous):
        return _in_place(hist, cnt, current, previous, tol)
    H, W = current.shape
    if motion is not None:
        motion = np.asarray(motion, dtype=np.float64)
        if motion.shape != current.shape + (2,):
            raise ValueError(f"motion must have shape {current.shape + (2,)}, got {motion.shape}")
        motion = motion.reshape(-1, 2)
    found = np.zeros(H * W, bool)
    value = np.full(H * W, np.nan)
    count_out = np.zeros(H * W, np.int32)
    source = np.full((H * W, 2), np.nan)
    frame = _Frames(current, previous, hist, cnt, tol, fetch, motion)
    all_idx = np.flatnonzero(valid)
    # blocks of pixels: the temporaries stay a few MB whatever the image size
    for start in range(0, len(all_idx), CHUNK_PIXELS):
        idx = all_idx[start:start + CHUNK_PIXELS]
        px, py, v, w, low = frame.block(idx)
        hit = w > 0
        found[idx] = hit
        value[idx[hit]] = v[hit] / w[hit]
        count_out[idx[hit]] = low[hit]
        source[idx, 0], source[idx, 1] = px, py
    found, value, count_out = found.reshape(H, W), value.reshape(H, W), count_out.reshape(H, W)
    source = source.reshape(H, W, 2)
    return Reprojection(value=value, count=count_out, found=found, source=source, covered=np.array(valid))
