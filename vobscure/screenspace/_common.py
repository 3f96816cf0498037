"""Pieces every screen-space estimator shares, each in one place.

- :func:`frame` / :func:`check_common`: validation of the G-buffer and the common arguments.
- :func:`prepare`: the per-pixel quantities (view position p, normal n, projected radius in
  pixels) of the valid pixels.
- :func:`run_chunks`: evaluation over chunks of pixels, so memory follows the chunk.
- :func:`disk_pixels` / :func:`nearest_taps`: disk offsets to pixels (and the nearest taps).
- :func:`fetch_depth`: the depth-buffer fetch (nearest or bilinear) with the off-screen policy.
- :func:`noise_texture` / :func:`noise_at`: the small tiled random texture that randomizes
  patterns per pixel, frame by frame (the schedules: :mod:`vobscure.screenspace.noise`).
- :func:`warper`: view depth to the estimator's line coordinate (see ``docs/screenspace.md``).
- :func:`tangent_plane_line`: the tangent plane's line coordinate (Loos & Sloan 2010, Sec. 4.4).
- :func:`solid_intervals` / :func:`nearest_pixel` / :func:`inside_intervals` /
  :func:`interval_back`: ``thickness="layers"``, the G-buffer's solid intervals read at the
  pixel a sample or tap falls in.
- the horizon-based estimators' slices and taps (GTAO, VBAO) are in
  :mod:`vobscure.screenspace._horizon`.
- :func:`inner_frame` / :func:`crop_guard`: the guard band (``render_gbuffer(..., guard=P)``):
  the estimators evaluate the inner frame's pixels only (:func:`frame`) and return it.

Used by the modules of :mod:`vobscure.screenspace` only (tests and benchmarks also reach in);
the estimators' public arguments are documented on the estimators.

Conventions (``docs/conventions.md``): view space, z = depth > 0 in front; continuous pixel
coordinates (x, y) with pixel (i, j) centred at (j + 0.5, i + 0.5). Cameras are general
pinholes (:meth:`vobscure.Camera.from_intrinsics`): a principal point (cx, cy) anywhere and
focal lengths fx, fy that may differ, so a view-space disk offset (dx, dy) at depth z moves
the projection by (fx dx / z, -fy dy / z) pixels; the projected radius therefore has an x
and a y extent (:attr:`Pixels.radius_px_x`, :attr:`Pixels.radius_px`), the same array when
fx = fy. NaN depths are treated
as background (+inf): the estimators return NaN there and treat such pixels as empty space
when a sample lands on them.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from .._validate import check_bool, check_choice, check_int, check_positive
from ..camera.kernel import ray_to_xy, ray_xy
from ..estimate import Estimate
from ..gbuffer import GBuffer
from ..patterns import SamplePattern, ball, disk
from .noise import NOISE_SIZE, check_frame, check_schedule, schedule_texture

FETCHES = ("nearest", "bilinear")
OFFSCREEN = ("clamp", "open")
FALLOFFS = ("constant", "quadratic")


@dataclass
class Pixels:
    """The valid pixels of a G-buffer (or a chunk of them), flattened: what estimators loop over.

    ``p``, ``center`` and ``n`` are computed on first use: an estimator that does not need
    them (line sampling without the normal, say) never pays for them.
    """

    index: np.ndarray        # (k,) flat indices into the (H, W) image
    z: np.ndarray            # (k,) view-space depth
    radius_px: np.ndarray    # (k,) the world radius projected at the pixel's depth, in pixels, along y
    depth: np.ndarray        # (H, W) float64 view of the depth buffer (NaN -> +inf)
    shape: tuple
    row: np.ndarray          # (k,) pixel row and column
    col: np.ndarray
    depth_flat: np.ndarray   # (H * W,) float64 copy of the depth buffer, for flat gathers
    perspective: bool
    fx: float                # pixels per unit at depth 1 (perspective) or per unit (ortho), along x
    fy: float                # the same along y (rows down: a view +y offset moves up the image)
    cx: float                # principal point (pixel coordinates, from the top-left corner)
    cy: float
    radius_px_x: np.ndarray = None   # (k,) the projected radius along x; radius_px itself when fx == fy
    normal_image: np.ndarray = field(repr=False, default=None)   # (H * W, 3) view-space normals

    def __post_init__(self):
        if self.radius_px_x is None:
            self.radius_px_x = self.radius_px

    @cached_property
    def ray(self) -> tuple[np.ndarray, np.ndarray]:
        """(x / z, y / z) of the pixels' view rays (perspective), or their view-space (x, y)
        (orthographic): the pixel centre's offset from the principal point (cx, cy) over
        ``fx`` and ``fy``: the kernel's ray of the column and row indices, whose centres are
        half a pixel past them."""
        return ray_xy(self.col, self.row, self.fx, self.fy, self.cx - 0.5, self.cy - 0.5)

    @cached_property
    def p(self) -> np.ndarray:
        """(k, 3) view-space positions (stored column by column, see :attr:`n`)."""
        rx, ry = self.ray
        p = np.empty((3, len(self.index))).T
        ray_to_xy(rx, ry, self.z, self.perspective, out=(p[:, 0], p[:, 1]))
        p[:, 2] = self.z
        return p

    @cached_property
    def center(self) -> np.ndarray:
        """(k, 2) continuous pixel coordinates (x, y) of the centres."""
        # stored column by column, as :attr:`p`
        c = np.empty((2, len(self.index))).T
        c[:, 0] = self.col + 0.5
        c[:, 1] = self.row + 0.5
        return c

    @cached_property
    def n(self) -> np.ndarray:
        """(k, 3) view-space unit normals (facing the camera); (0, 0, -1) where none."""
        # stored column by column ((3, k) memory, seen as (k, 3)): the estimators work on
        # the components one at a time, and contiguous columns make those passes fast
        n = np.take(self.normal_image, self.index, axis=0).T.copy().T
        nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
        length = np.sqrt(nx * nx + ny * ny + nz * nz)
        bad = ~(length > 0)
        if bad.any():
            length[bad] = 1.0
        n /= length[:, None]
        if bad.any():
            n[bad] = (0.0, 0.0, -1.0)
        return n


def as_gbuffer(gbuffer) -> GBuffer:
    """``gbuffer`` itself if it is a :class:`~vobscure.GBuffer`; ValueError otherwise."""
    if not isinstance(gbuffer, GBuffer):
        raise ValueError(f"gbuffer must be a vobscure GBuffer (from render_gbuffer), got {type(gbuffer).__name__}")
    return gbuffer


#: Pixels processed together: the estimators' temporaries scale with this, not with the
#: image (about 300 bytes a pixel of the chunk), which keeps peak memory per image pixel low.
CHUNK_PIXELS = 16384


def frame(gbuffer, radius):
    """Validate; the float64 depth buffer (NaN -> +inf), flat, and the valid pixels' indices
    (of the inner frame only when the G-buffer has a guard band: its pixels are read, not
    evaluated)."""
    gb = as_gbuffer(gbuffer)
    check_positive(radius, "radius")
    flat = np.asarray(gb.depth, dtype=np.float64).reshape(-1)
    nan = np.isnan(flat)
    depth64 = np.where(nan, np.inf, flat) if nan.any() else np.ascontiguousarray(flat)
    index = np.flatnonzero(np.isfinite(depth64) & (depth64 > 0))
    g = gb.guard
    if g:
        H, W = gb.shape
        i, j = np.divmod(index, W)
        index = index[(i >= g) & (i < H - g) & (j >= g) & (j < W - g)]
    return gb, depth64, index


def inner_shape(gbuffer) -> tuple[int, int]:
    """(H, W) of the frame the estimators return: the image less its guard band."""
    H, W = gbuffer.shape
    g = getattr(gbuffer, "guard", 0)
    return H - 2 * g, W - 2 * g


def crop_guard(result, gbuffer):
    """``result`` (an array whose first two axes are the G-buffer's image, or an
    :class:`~vobscure.Estimate` of such arrays) cropped to the inner frame of ``gbuffer``'s
    guard band; ``result`` itself when there is no guard band or when it is already of the
    inner frame's shape."""
    g = getattr(gbuffer, "guard", 0)
    if not g:
        return result
    H, W = gbuffer.shape

    def crop(a):
        a = np.asarray(a)
        if a.shape[:2] == inner_shape(gbuffer):
            return a
        if a.shape[:2] != (H, W):
            raise ValueError(f"result has shape {a.shape}, neither the guarded image's {(H, W)} "
                             f"nor its inner frame's {inner_shape(gbuffer)}")
        return np.ascontiguousarray(a[g:H - g, g:W - g])

    if isinstance(result, Estimate):
        bent = None if result.bent_normal is None else crop(result.bent_normal)
        return dataclasses.replace(result, value=crop(result.value), stderr=crop(result.stderr),
                                   bent_normal=bent)
    return crop(result)


def inner_frame(estimator):
    """Decorator of a public estimator ``estimator(gbuffer, ...)``: its result cropped to the
    inner frame when ``gbuffer`` has a guard band (:func:`crop_guard`), unchanged otherwise."""
    @functools.wraps(estimator)
    def wrapper(gbuffer, *args, **kwargs):
        return crop_guard(estimator(gbuffer, *args, **kwargs), gbuffer)

    return wrapper


def prepare(gbuffer, radius, *, index=None, depth64=None) -> Pixels:
    """The per-pixel inputs of the valid (finite-depth) pixels, or of ``index`` only."""
    gb = as_gbuffer(gbuffer)
    radius = check_positive(radius, "radius")
    if depth64 is None or index is None:
        _, depth64, all_index = frame(gb, radius)
        index = all_index if index is None else index
    cam = gb.camera
    H, W = gb.depth.shape
    i, j = np.divmod(index, W)
    z = depth64[index]
    fx, fy = cam.fx, cam.fy
    # a view-space offset (dx, dy) at depth z moves the projection by (fx dx / z, -fy dy / z)
    # pixels (perspective), (fx dx, -fy dy) (orthographic, fx = fy = H / ortho_height)
    if cam.is_perspective:
        radius_px = (radius * fy) / z
        radius_px_x = radius_px if fx == fy else (radius * fx) / z
    else:
        radius_px = radius_px_x = np.full(len(index), radius * fy)
    return Pixels(index=index, z=z, radius_px=radius_px, depth=depth64.reshape(H, W), shape=(H, W),
                  row=i, col=j, depth_flat=depth64, perspective=cam.is_perspective, fx=float(fx),
                  fy=float(fy), cx=float(cam.cx), cy=float(cam.cy), radius_px_x=radius_px_x,
                  normal_image=gb.normal.reshape(-1, 3))


def run_chunks(gbuffer, radius, kernel, dtype, *, prepared=None, chunk: int = CHUNK_PIXELS) -> np.ndarray:
    """(H, W) image of ``kernel(px)`` evaluated over chunks of CHUNK_PIXELS valid pixels.

    NaN on background. The estimators' whole per-pixel state lives in one chunk at a time.
    ``prepared``: the result of :func:`frame` when the caller already has it.
    """
    gb, depth64, index = prepared if prepared is not None else frame(gbuffer, radius)
    H, W = gb.depth.shape
    out = np.full(H * W, np.nan, dtype=dtype)
    for a in range(0, len(index), chunk):
        px = prepare(gb, radius, index=index[a:a + chunk], depth64=depth64)
        out[px.index] = kernel(px)
    return out.reshape(H, W)


def as_pattern(samples, dim: int, name: str = "samples") -> SamplePattern:
    """A count (-> the default symmetric pattern) or a SamplePattern of the right dimension."""
    if isinstance(samples, SamplePattern):
        if samples.dim != dim:
            kind = "disk (n, 2)" if dim == 2 else "ball (n, 3)"
            raise ValueError(f"{name} must be a {kind} pattern, got points of shape {samples.points.shape}")
        return samples
    n = check_int(samples, name)
    from ..patterns import SAMPLES_LIMIT

    if n > SAMPLES_LIMIT:
        raise ValueError(f"{name} must be at most {SAMPLES_LIMIT} points per pixel, got {n}; for converged values "
                         "use vo_reference (line integrals, not a pattern)")
    return _default_pattern(n, dim)


@lru_cache(maxsize=128)
def _default_pattern(n: int, dim: int) -> SamplePattern:
    """The estimators' default pattern for a count, built once per process (``disk(n)``
    copies its table entry and provenance on every call: milliseconds, as much as a
    small image's estimate). Its arrays are made read-only: it is shared."""
    p = disk(n) if dim == 2 else ball(n)
    p.points.flags.writeable = False
    p.weights.flags.writeable = False
    return p


def check_common(*, fetch="nearest", offscreen="clamp", falloff="constant", thickness=None,
                 noise_size=NOISE_SIZE):
    """Validate the estimators' shared arguments (ValueError naming the argument).

    ``fetch`` in :data:`FETCHES`, ``offscreen`` in :data:`OFFSCREEN`, ``falloff`` in
    :data:`FALLOFFS`, ``thickness`` None or a positive finite number, ``noise_size`` an
    int >= 1. Returns ``thickness`` as a float (or None).
    """
    check_choice(fetch, "fetch", FETCHES)
    check_choice(offscreen, "offscreen", OFFSCREEN)
    check_choice(falloff, "falloff", FALLOFFS)
    if thickness is not None:
        thickness = check_positive(thickness, "thickness")
    check_int(noise_size, "noise_size")
    return thickness


def noise_texture(noise_size: int, seed, dim: int, randomize: bool, *, frame: int = 0,
                  schedule: str = "white") -> np.ndarray | None:
    """The tile of unit vectors (T, T, dim) of frame ``frame`` of a noise schedule
    (:func:`vobscure.screenspace.noise.schedule_texture`; T = noise_size for ``"white"`` and
    ``"rotate"``, 64 for ``"r2"`` and ``"gtao"``), or None without randomization. ``frame``
    and ``schedule`` are checked either way; frame 0 of ``"white"`` is the single-frame
    texture: ``as_rng(seed).normal(size=(T, T, dim))`` normalized."""
    schedule, frame = check_schedule(schedule), check_frame(frame)
    randomize = check_bool(randomize, "randomize")
    if not randomize:
        return None
    return schedule_texture(schedule, frame, seed=seed, noise_size=noise_size, dim=dim)


def noise_at(px: Pixels, texture: np.ndarray | None) -> np.ndarray | None:
    """(k, dim) texture values at the pixels (the tile repeats across the image)."""
    if texture is None:
        return None
    size = texture.shape[0]
    return texture[px.row % size, px.col % size]


def reflect(s: np.ndarray, v: np.ndarray | None, count: int) -> np.ndarray:
    """One pattern point ``s`` (dim,) as seen by each of ``count`` pixels: (count, dim).

    With per-pixel unit vectors ``v`` (count, dim): the reflection about the line along v
    in 2-D (2 (s . v) v - s), the Householder reflection about the plane normal to v in
    3-D (s - 2 (s . v) v). Estimators loop over pattern points and call this once per
    point, so no (pixels x samples) array is ever built.
    """
    if v is None:
        return np.broadcast_to(s, (count, len(s)))
    dot = (v @ s)[:, None]
    if v.shape[1] == 2:
        return 2.0 * dot * v - s
    return s - 2.0 * dot * v


def disk_pixels(px: Pixels, xy: np.ndarray, *, snap: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixel coordinates of the disk points p + R (x, y, 0) for unit-disk offsets (k, 2).

    The offset (x, y) moves the projection by (R_x x, -R_y y) pixels, R_x and R_y the
    projected radius along x and y (:attr:`Pixels.radius_px_x`, :attr:`Pixels.radius_px`;
    equal for square pixels).

    With ``snap`` the points move to the centre of the pixel they fall in and the offsets
    are recomputed from there, so that the line at (x, y) and the depth read for it belong
    to the same place: a nearest fetch then describes a plane exactly (the depth at a pixel
    centre is the plane's depth there), and a point-symmetric pattern stays symmetric
    (rounding an integer-centred offset is odd). Returns x, y and the (k, 2) offsets used.
    """
    x = px.center[:, 0] + px.radius_px_x * xy[:, 0]
    y = px.center[:, 1] - px.radius_px * xy[:, 1]
    if not snap:
        return x, y, xy
    x = np.floor(x) + 0.5
    y = np.floor(y) + 0.5
    xy = np.column_stack([(x - px.center[:, 0]) / px.radius_px_x, (px.center[:, 1] - y) / px.radius_px])
    return x, y, xy


def bilinear_ok(px: Pixels, offsets, *, offscreen: str) -> np.ndarray:
    """(k,) True where every tap of the pixel can be read bilinearly (no background among
    the four texels around any tap). ``offsets`` yields the (k, 2) disk offsets of the taps."""
    ok = np.ones(len(px.index), dtype=bool)
    for xy in offsets:
        x, y, _ = disk_pixels(px, xy, snap=False)
        _, tap_ok = fetch_depth(px.depth, x, y, fetch="bilinear", offscreen=offscreen,
                                reciprocal=px.perspective, with_mask=True)
        ok &= tap_ok
    return ok


def fetch_disk(px: Pixels, xy: np.ndarray, *, fetch: str, offscreen: str, bilinear=None):
    """Depth for the disk points p + R (x, y, 0): returns (depth, the (k, 2) offsets used).

    ``nearest``: the points are snapped to pixel centres (:func:`disk_pixels`).
    ``bilinear``: the points stay where they are, except at pixels where ``bilinear`` (from
    :func:`bilinear_ok`) is False, i.e. where some tap would interpolate towards background:
    all taps of such a pixel are snapped like ``nearest``. Taps of one pixel are treated
    alike so that a point-symmetric pattern stays symmetric, and the offset and the depth
    always describe the same place.
    """
    if fetch == "nearest":
        x, y, used = disk_pixels(px, xy, snap=True)
        return fetch_depth(px.depth, x, y, offscreen=offscreen), used
    x, y, _ = disk_pixels(px, xy, snap=False)
    d = fetch_depth(px.depth, x, y, fetch="bilinear", offscreen=offscreen, reciprocal=px.perspective)
    if bilinear is None or np.all(bilinear):
        return d, xy
    xs, ys, snapped = disk_pixels(px, xy, snap=True)
    d_near = fetch_depth(px.depth, xs, ys, offscreen=offscreen)
    return np.where(bilinear, d, d_near), np.where(bilinear[:, None], xy, snapped)


#: Largest border (pixels) the nearest fast path pads the depth buffer with.
MAX_PAD = 256


class PaddedDepth:
    """The float64 depth buffer with a border, so that snapped taps need no clipping.

    The border replicates the edge pixels (``offscreen="clamp"``) or holds +inf
    (``"open"``): reading it is exactly what the off-screen policy prescribes.
    """

    def __init__(self, depth64: np.ndarray, shape: tuple, pad: int, offscreen: str):
        H, W = shape
        img = depth64.reshape(H, W)
        mode = dict(mode="edge") if offscreen == "clamp" else dict(mode="constant", constant_values=np.inf)
        self.pad = pad
        self.width = W + 2 * pad
        self.flat = np.pad(img, pad, **mode).reshape(-1)


def padded_depth(depth64, shape, radius_px_max: float, offscreen: str):
    """A :class:`PaddedDepth` wide enough for taps within ``radius_px_max`` pixels along
    either axis (the larger of the projected radius's x and y extents), or None if too wide."""
    pad = int(np.ceil(radius_px_max)) + 2
    return PaddedDepth(depth64, shape, pad, offscreen) if pad <= MAX_PAD else None


def padded_base(px: Pixels, padded: PaddedDepth) -> np.ndarray:
    """(k,) float64 flat index of each pixel of ``px`` in the padded buffer."""
    return ((px.row + padded.pad) * padded.width + (px.col + padded.pad)).astype(np.float64)


def nearest_taps(px: Pixels, dj: np.ndarray, e: np.ndarray, *, offscreen: str, padded=None, base=None,
                 out: np.ndarray | None = None, scratch: np.ndarray | None = None) -> np.ndarray:
    """Nearest-fetch fast path: the depth (k,) at integer pixel offsets (dj, e) (floats).

    ``dj`` columns to the right and ``e`` rows *up* (the disk's y axis points up, rows go
    down) of each pixel of ``px``. ``padded`` (a :class:`PaddedDepth` covering every tap)
    replaces the clipping: the flat index is computed over float arrays (exact for integers
    below 2^53) from ``base`` (:func:`padded_base`, computed once per chunk) and gathered by
    one ``take``. ``out`` and ``scratch`` (float64, (k,)) are reused buffers.
    """
    k = len(dj)
    out = np.empty(k) if out is None else out
    if padded is not None:
        scratch = np.empty(k) if scratch is None else scratch
        base = padded_base(px, padded) if base is None else base
        np.multiply(e, -float(padded.width), out=scratch)
        scratch += dj
        scratch += base
        np.take(padded.flat, scratch.astype(np.intp), out=out)
        return out
    H, W = px.shape
    j = px.col + dj.astype(np.intp)
    i = px.row - e.astype(np.intp)
    inside = (j >= 0) & (j < W) & (i >= 0) & (i < H)
    if inside.all():
        np.take(px.depth_flat, i * W + j, out=out)
    else:
        np.take(px.depth_flat, np.clip(i, 0, H - 1) * W + np.clip(j, 0, W - 1), out=out)
        if offscreen == "open":
            out[~inside] = np.inf
    return out


#: The most texels a noise texture may have for :func:`noise_classes` to group the pixels by
#: texel. A group costs a fixed overhead (a pass over the image's rows and columns of its
#: texel, a :func:`prepare`, a loop over the pattern), worth paying when groups are large: the
#: default 4 x 4 tile of the ``"white"`` and ``"rotate"`` schedules (and tiles up to 8 x 8)
#: are grouped; the 64 x 64 tiles of ``"r2"`` and ``"gtao"`` (4096 texels) are not, their
#: pixels read their texel one by one (:func:`per_pixel_noise`).
MAX_NOISE_CLASSES = 64


def per_pixel_noise(texture: np.ndarray | None) -> bool:
    """True when :func:`noise_classes` yields per-pixel texels for ``texture``: it has more
    than :data:`MAX_NOISE_CLASSES` texels (read at call time)."""
    return texture is not None and texture.shape[0] * texture.shape[1] > MAX_NOISE_CLASSES


def noise_classes(depth64: np.ndarray, shape: tuple, texture: np.ndarray | None, *, chunk: int = None):
    """Chunks of valid pixels with their texels of the tiled noise texture.

    Yields ``(index, v)``: flat pixel indices and their texel. For a texture of at most
    :data:`MAX_NOISE_CLASSES` texels a chunk's pixels share one texel and ``v`` is its unit
    vector (dim,): every pixel turns the pattern the same way, so the rotated pattern points
    are scalars and only the per-pixel radius varies (the line estimator's inner loop then
    does no per-pixel reflection at all). For a larger texture (:func:`per_pixel_noise`) the
    chunks are plain runs of valid pixels and ``v`` is (k, dim), each pixel's own texel
    (:func:`noise_at`): grouping by texel would cost a group per texel. Without
    randomization ``v`` is None and the chunks are plain runs of valid pixels.
    """
    chunk = CHUNK_PIXELS if chunk is None else chunk
    H, W = shape
    valid = (np.isfinite(depth64) & (depth64 > 0)).reshape(H, W)
    if per_pixel_noise(texture):
        size = texture.shape[0]
        index = np.flatnonzero(valid)
        for c in range(0, len(index), chunk):
            i, j = np.divmod(index[c:c + chunk], W)
            yield index[c:c + chunk], texture[i % size, j % size]
        return
    if texture is None:
        index = np.flatnonzero(valid)
        for c in range(0, len(index), chunk):
            yield index[c:c + chunk], None
        return
    size = texture.shape[0]
    for a in range(min(size, H)):
        for b in range(min(size, W)):
            ii, jj = np.nonzero(valid[a::size, b::size])
            index = (a + size * ii) * W + (b + size * jj)
            for c in range(0, len(index), chunk):
                yield index[c:c + chunk], texture[a, b]


def _nearest_index(xs, ys, H: int, W: int) -> np.ndarray:
    """Flat index of the pixel containing (xs, ys) (finite coordinates), clamped to the image."""
    j = np.clip(np.floor(xs), 0, W - 1).astype(np.intp)
    i = np.clip(np.floor(ys), 0, H - 1).astype(np.intp)
    return i * W + j


def fetch_depth(depth: np.ndarray, x: np.ndarray, y: np.ndarray, *, fetch: str = "nearest",
                offscreen: str = "clamp", reciprocal: bool = False, with_mask: bool = False):
    """Depth-buffer values at continuous pixel coordinates (x, y) (float64).

    ``fetch="nearest"``: the pixel containing (x, y). ``"bilinear"``: interpolation between
    the four nearest pixel centres, of 1/z when ``reciprocal`` (perspective: exact on
    planes) and of z otherwise; where any of them is background the nearest value is used
    (interpolating towards +inf would invent geometry; that pixel is one of the four, read
    again only there); ``with_mask`` also returns where the bilinear value was used.
    ``offscreen="clamp"``: coordinates outside the image read the nearest border pixel;
    ``"open"``: they read background (+inf), i.e. empty space. Non-finite coordinates
    (a point behind a perspective camera) read background.
    """
    H, W = depth.shape
    flat = depth.reshape(-1)
    finite = np.isfinite(x)
    finite &= np.isfinite(y)
    all_finite = bool(finite.all())
    if all_finite:
        xs, ys = x, y
    else:
        xs = np.where(finite, x, 0.0)
        ys = np.where(finite, y, 0.0)
    if fetch == "bilinear":
        fx = np.clip(xs - 0.5, 0, W - 1)
        fy = np.clip(ys - 0.5, 0, H - 1)
        # the texel below and left of (x, y) and the weights of its neighbours
        j0 = np.floor(fx)
        i0 = np.floor(fy)
        tx = np.subtract(fx, j0, out=fx)
        ty = np.subtract(fy, i0, out=fy)
        j0 = j0.astype(np.intp)
        i0 = i0.astype(np.intp)
        j1 = np.minimum(j0 + 1, W - 1)
        row0 = i0 * W
        row1 = np.minimum(i0 + 1, H - 1)
        row1 *= W
        d00, d01, d10, d11 = (flat[a + b].astype(np.float64, copy=False)
                              for a, b in ((row0, j0), (row0, j1), (row1, j0), (row1, j1)))
        ok = np.isfinite(d00)
        for texel in (d01, d10, d11):
            ok &= np.isfinite(texel)
        with np.errstate(invalid="ignore", divide="ignore"):
            ux, uy = 1 - tx, 1 - ty
            if reciprocal:
                # 1/z is affine across the screen on a plane (perspective): interpolate it
                inv = uy * (ux / d00 + tx / d01) + ty * (ux / d10 + tx / d11)
                d = np.divide(1.0, inv, out=inv)
            else:
                d = uy * (ux * d00 + tx * d01) + ty * (ux * d10 + tx * d11)
        if not ok.all():
            # the nearest texel where one of the four is background
            near = ~ok
            d[near] = flat[_nearest_index(xs[near], ys[near], H, W)]
    else:
        d = flat[_nearest_index(xs, ys, H, W)].astype(np.float64, copy=False)
        ok = np.ones(d.shape, dtype=bool)
    if offscreen == "open":
        outside = (xs < 0) | (xs >= W) | (ys < 0) | (ys >= H)
        if not all_finite:
            outside |= ~finite
        d[outside] = np.inf
        if with_mask:
            ok |= outside
    elif not all_finite:
        d[~finite] = np.inf
        if with_mask:
            ok |= ~finite
    return (d, ok) if with_mask else d


def warper(px: Pixels, radius: float):
    """View depth -> the line coordinate of the unit sphere around each pixel's point, as a
    one-argument function of the depth with the pixels' constants precomputed.

    Orthographic: (d - z_p) / R, the paper's mapping. Perspective: (z_p / R) (1 - z_p / d),
    the same to first order in (d - z_p) / z_p, but exact for planes: 1/d is affine across
    the screen for a plane, so depths on a plane through p map to an odd function of the
    disk offset and a point-symmetric pattern sees exactly half of a plane (see
    ``docs/screenspace.md``). +inf (background) maps to z_p / R (far behind every segment
    end) in perspective, +inf in orthographic.
    """
    z = px.z
    if px.perspective:
        # d_r = (z_p / R) (1 - z_p / d) = a - b / d (docs/screenspace.md, "Where vobscure
        # departs from the paper", 1)
        a, b = z / radius, z * z / radius

        def f(depth):
            with np.errstate(divide="ignore"):
                return a - b / depth
        return f
    # Loos & Sloan 2010, Sec. 4.1: the depth "mapped into the unit sphere's coordinate
    # system", d_r = (d - z_p) / R
    return lambda depth: (depth - z) / radius


def tangent_plane_coefficients(px: Pixels) -> tuple[np.ndarray, np.ndarray]:
    """(gx, gy) with tangent_plane_line = gx x + gy y (unclipped); see :func:`tangent_plane_line`.

    The coefficients are ratios of the normal's components, so the normal needs no
    normalization; only the grazing threshold scales with its length. A missing normal
    (zero vector) gives gx = gy = 0, as the fallback normal (0, 0, -1) of :attr:`Pixels.n` does.
    """
    # gathered rows, then one transposing copy: the arithmetic below runs on contiguous
    # components (strided (k, 3) columns make every pass slower)
    nx, ny, nz = np.take(px.normal_image, px.index, axis=0).T.astype(np.float64, order="C")
    # Loos & Sloan 2010, Sec. 4.4 and footnote 4: the plane n . (x - p) = 0 in the sphere's
    # frame; its line coordinate at disk offset (x, y) is -(n_x x + n_y y) / den
    if px.perspective:
        # n . p / z_p, with p / z_p = (x / z, y / z, 1) the pixel's ray (Pixels.ray)
        rx, ry = px.ray
        den = (nx * rx + ny * ry) + nz
    else:
        den = nz.copy()
    length = np.sqrt(nx * nx + ny * ny + nz * nz)
    np.minimum(den, -1e-12 * np.maximum(length, 1e-300), out=den)
    return -nx / den, -ny / den


def tangent_plane_line(px: Pixels, xy: np.ndarray, *, clip: bool = True) -> np.ndarray:
    """Line coordinate where the tangent plane at p crosses the line at disk offset (x, y).

    Loos & Sloan Sec. 4.4 (and footnote 4): in the unit sphere's frame the plane is given by
    the view-space normal. Orthographic: -(n_x x + n_y y) / n_z. Perspective, in the warped
    coordinate of :func:`warper`: -z_p (n_x x + n_y y) / (n . p). Grazing normals (denominator
    -> 0) give +-large values, which the segment clamp turns into "all open" or "all closed".
    """
    gx, gy = tangent_plane_coefficients(px)
    z = gx * xy[:, 0] + gy * xy[:, 1]
    return np.clip(z, -4.0, 4.0) if clip else z


def out_dtype(gbuffer) -> np.dtype:
    """float32 in, float32 out; float64 otherwise (accumulation is always float64)."""
    return np.dtype(np.float32) if gbuffer.depth.dtype == np.float32 else np.dtype(np.float64)




#: The ``thickness`` that reads the G-buffer's solid intervals instead of a model of what lies
#: behind the depth buffer (:class:`vobscure.layers.SolidIntervals`, ``GBuffer.intervals``).
LAYERS = "layers"


def solid_intervals(gbuffer, thickness):
    """The G-buffer's :class:`~vobscure.layers.SolidIntervals` when ``thickness == "layers"``,
    None for any other non-string ``thickness`` (the caller validates numbers).

    ValueError naming ``thickness`` for another string, or for ``"layers"`` when the G-buffer
    carries no intervals (``gbuffer.intervals is None``).
    """
    if not isinstance(thickness, str):
        return None
    if thickness != LAYERS:
        raise ValueError(f"thickness must be None, a positive number or {LAYERS!r}, got {thickness!r}")
    intervals = as_gbuffer(gbuffer).intervals
    if intervals is None:
        raise ValueError(f"thickness={LAYERS!r} reads the G-buffer's solid intervals, but gbuffer.intervals is "
                         f"None: render it with layers (render_gbuffer(..., layers=K)) or attach them with "
                         f"gbuffer.with_intervals(SolidIntervals(front, back))")
    return intervals


def nearest_pixel(shape: tuple, x: np.ndarray, y: np.ndarray, *, offscreen: str) -> tuple[np.ndarray, np.ndarray]:
    """The pixel :func:`fetch_depth` reads with ``fetch="nearest"`` at (x, y): ``(index, empty)``.

    ``index`` (k,): flat row-major index of the pixel containing (x, y), clamped to the image
    (the nearest border pixel for a point off it); ``empty`` (k,) bool: where the point reads
    empty space instead, as the depth fetch reads +inf there: non-finite coordinates (a point
    behind a perspective camera), and off the image with ``offscreen="open"``.
    """
    H, W = shape
    finite = np.isfinite(x) & np.isfinite(y)
    xs = np.where(finite, x, 0.0)
    ys = np.where(finite, y, 0.0)
    j = np.clip(np.floor(xs), 0, W - 1).astype(np.intp)
    i = np.clip(np.floor(ys), 0, H - 1).astype(np.intp)
    empty = ~finite
    if offscreen == "open":
        empty |= (xs < 0) | (xs >= W) | (ys < 0) | (ys >= H)
    return i * W + j, empty


def tap_pixel(px: Pixels, dj: np.ndarray, e: np.ndarray, *, offscreen: str) -> tuple[np.ndarray, np.ndarray]:
    """``(index, empty)`` of the pixels :func:`nearest_taps` reads at integer offsets (dj, e)
    (``e`` rows up): the flat index, clamped to the image, and where the tap is off the image
    with ``offscreen="open"`` (empty space)."""
    H, W = px.shape
    j = px.col + dj.astype(np.intp)
    i = px.row - e.astype(np.intp)
    inside = (j >= 0) & (j < W) & (i >= 0) & (i < H)
    index = np.clip(i, 0, H - 1) * W + np.clip(j, 0, W - 1)
    empty = ~inside if offscreen == "open" else np.zeros(len(index), dtype=bool)
    return index, empty


def interval_slots(intervals):
    """The ``(front, back)`` of every interval slot as (M, H * W) views, for flat gathers."""
    M = intervals.count
    return intervals.front.reshape(M, -1), intervals.back.reshape(M, -1)


def inside_intervals(intervals, index: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(k,) bool: view depth ``z`` lies inside a solid interval of the pixel ``index``,
    front < z < back, ``z`` compared in the intervals' precision.

    Strict, as the depth test z > d of a single depth buffer: the intervals ``[d, +inf)``
    then give that test bit for bit (an interval's ends have measure zero). The renderer's
    intervals are float32 (``docs/layers.md``, "Memory"): their ends are the float64 depths
    rounded to float32 (relative error at most 2^-24, 6e-8), and ``z`` is rounded to float32
    too before the comparison, so that a sample at the very depth of the pixel's surface
    (z = d) stays outside, as the depth test has it; only a depth within that rounding of an
    end may read the other side (a set of measure zero). float64 intervals compare ``z`` as
    it is. One gather per interval slot: the cost is linear in the slots M.
    """
    front, back = interval_slots(intervals)
    z = np.asarray(z)
    if front.dtype.itemsize < z.dtype.itemsize:
        with np.errstate(over="ignore"):      # beyond float32's range: +-inf, as far as any end
            z = z.astype(front.dtype)
    out = np.zeros(z.shape, dtype=bool)
    for m in range(intervals.count):
        out |= (front[m].take(index) < z) & (z < back[m].take(index))
    return out


def interval_back(intervals, index: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(k,) the back of the first solid interval of pixel ``index`` that contains or follows
    view depth ``d`` (back >= d); ``d`` itself where no interval ends at or behind ``d``.

    For a tap whose depth ``d`` is the pixel's first surface (a nearest fetch of a peeled
    G-buffer), it is the back of the pixel's first interval: the tapped occluder spans
    [d, back] along the tap's view ray. ``+inf``: the occluder's end was not seen (solid
    from ``d`` on, as a single depth buffer takes it). ``d`` itself (no interval at or behind
    it: an interpolated depth between a thin surface and the background behind it) makes
    the occluder a surface of no thickness.

    ``d`` is compared in the intervals' precision: with the renderer's float32 intervals
    (``docs/layers.md``, "Memory") a zero-thickness interval ``[d, d]`` of an open surface,
    whose end is ``d`` rounded to float32 and may lie below ``d``, is still the one found, and
    the back returned is at least ``d`` (an interval ending within that rounding, 6e-8 of the
    depth, before ``d`` then gives ``d``). float64 intervals compare ``d`` as it is.
    """
    front, back = interval_slots(intervals)
    d = np.asarray(d, dtype=np.float64)
    d_cmp = d
    if back.dtype.itemsize < d.dtype.itemsize:
        with np.errstate(over="ignore"):      # beyond float32's range: +-inf, as far as any end
            d_cmp = d.astype(back.dtype)
    out = d.copy()
    found = np.zeros(d.shape, dtype=bool)
    for m in range(intervals.count):
        f = front[m].take(index)
        b = back[m].take(index)
        # a slot is an interval when its front is finite (unused slots are +inf, +inf)
        first = ~found & (b >= d_cmp) & (f < np.inf)
        out[first] = b[first]
        found |= first
    if d_cmp is not d:
        np.maximum(out, d, out=out)
    return out
