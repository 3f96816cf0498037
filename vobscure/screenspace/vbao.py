"""Visibility-bitmask ambient occlusion, VBAO (Therrien, Levesque & Gilet 2023).

GTAO's horizon search (Jimenez et al. 2016; the slices, steps and taps of
:mod:`vobscure.screenspace.gtao`, shared through :mod:`vobscure.screenspace._common`), with
each slice's hemisphere split into ``sectors`` equal angles and a bitmask of the occluded
ones in place of the two horizons: a tap occludes the sectors between its front horizon and
the horizon of the same tap moved back by a thickness, so light passes behind thin objects.
The variants engines ship are options, each checked against its source:

- Bevy 0.15 ``crates/bevy_pbr/src/ssao/ssao.wgsl`` (read at commit fafcf49): the back point is
  the tap moved by a constant thickness along p's view vector (``constant_object_thickness``,
  0.25 by default with an effect radius 0.5 x 1.457), the sectors a tap touches are marked
  (``updateSectors``: first sector floor(a S), ceil((b - a) S) of them), the visibility is
  1 - (occluded sectors) / (sectors x slices), unweighted; XeGTAO's ((j + u) / n) ** 2 steps.
- SSRT3 (the authors' code, ``HDRP/Shaders/Resources/SSRTCS.compute``): the same constant
  thickness along the view vector, or with ``_LinearThickness`` a thickness growing linearly
  with the tap's depth (``saturate(z / far) * 100`` times it); steps at
  (stepRadius (j + u) / radius) ** ``_ExpFactor`` (a power law, which SSRT3 calls
  exponential); 32 sectors; the same touch rule.
- Blender EEVEE's horizon scan (``eevee_horizon_scan_eval_lib.glsl`` and
  ``eevee_horizon_scan_lib.glsl``, read in blender/blender): a near thickness along the view
  vector and a far thickness as an angle, the back horizon at least that angle past the front
  one (``theta.y = max(theta.x + thickness_far, theta.y)``); taps whose front lies beyond the
  search distance skipped; the cosine weighting approximated by four groups of sectors
  (``horizon_scan_bitmask_to_occlusion_cosine``), the slices weighted by the projected
  normal's length and normalized by its sum.

Not read here: three.js ``SSGINode`` and Filament's implementation.
"""

from __future__ import annotations

from functools import lru_cache, partial

import numpy as np

from .._validate import check_choice, check_positive
from . import _common as C
from . import _horizon as Hz
from .gtao import PIXEL_TOO_CLOSE, R1_STEP, SAMPLE_DISTRIBUTION_POWER, STEP_JITTERS

__all__ = ["vbao", "sector_weights", "WEIGHTINGS", "THICKNESS_SCALES", "SECTOR_RULES", "EEVEE_WEIGHTS"]

#: How a slice's visible sectors are summed (see :func:`vbao`).
WEIGHTINGS = ("cosine", "uniform", "bitcount", "eevee")
#: How a numeric ``thickness`` applies: as is, or times the tap's view depth (SSRT3's linear option).
THICKNESS_SCALES = ("constant", "linear")
#: Which sectors an occluded angle interval marks (see :func:`vbao`).
SECTOR_RULES = ("centre", "touch")
#: ``thickness=None``: this fraction of the radius.
THICKNESS_FRACTION = 0.5
#: Blender's piecewise approximation of the cosine weighting at 32 sectors: the weight of each
#: of the 4 sectors of a group, the groups from the hemisphere's edges inwards
#: (``eevee_horizon_scan_lib.glsl``, ``horizon_scan_bitmask_to_occlusion_cosine``: "the
#: accumulated weights from the reference loop", which sums cos(centre angle) pi / 64).
EEVEE_WEIGHTS = np.array([0.0095061, 0.0270951, 0.0405571, 0.0478421])
#: Sectors per slice a bitmask of 64 bits holds.
MAX_SECTORS = 64
#: Pixels per chunk (the screen-space estimators' own).
CHUNK_PIXELS = C.CHUNK_PIXELS

# _LOW[i]: the bitmask of sectors 0 .. i - 1 (i in 0 .. 64)
_LOW = np.array([(1 << i) - 1 for i in range(MAX_SECTORS + 1)], dtype=np.uint64)


@C.inner_frame
def vbao(gbuffer, *, radius: float, slices: int = 3, steps: int = 3, thickness=None,
         thickness_scale: str = "constant", thickness_far: float = 0.0, weighting: str = "cosine",
         sectors: int = 32, sector_rule: str = "centre", step_power: float = SAMPLE_DISTRIBUTION_POWER,
         randomize: bool = True, seed=0, fetch: str = "bilinear", offscreen: str = "clamp",
         noise_size: int = C.NOISE_SIZE, step_jitter: str = "pixel", frame: int = 0,
         schedule: str = "white") -> np.ndarray:
    """Ambient occlusion within ``radius`` by a visibility bitmask per slice (VBAO).

    The slices, steps and taps are :func:`vobscure.screenspace.gtao.gtao`'s (same arguments,
    same seed -> same taps). In each slice the hemisphere around the normal, the angles
    theta from the view vector v in [gamma - pi/2, gamma + pi/2] (gamma the projected
    normal's angle), is split into ``sectors`` equal angles. A tap whose point lies within
    ``radius`` of p is an occluder from its front point to a back point behind it; it marks
    the sectors between the angles of the two. The visibility is the weighted sum of the
    unmarked sectors, averaged over the slices.

    Parameters
    ----------
    gbuffer : GBuffer
        Depth (H, W) and view-space normals (H, W, 3); perspective or orthographic. With
        ``thickness="layers"`` it must carry solid intervals (:meth:`GBuffer.with_intervals`).
    radius : float
        World radius R (> 0): taps farther than R from p are skipped, as in the
        ``quantity="ao"`` reference with ``max_distance=R``.
    slices, steps : int, optional
        Slice directions per pixel and depth taps per side of each (>= 1, default 3 each).
        Taps per pixel: 2 x slices x steps.
    thickness : float, "layers" or None, optional
        The occluders' thickness behind their front point: a world length (>= 0, ``inf``
        allowed: a depth buffer's infinitely thick surfaces, the GTAO limit) by which the
        tapped point is moved away from the camera along p's view vector (Bevy, SSRT3,
        Blender's near thickness); None (default): ``THICKNESS_FRACTION`` (0.5) x ``radius``.
        ``"layers"``: the back of the solid interval of the tapped pixel (the pixel the tap
        falls in, whatever ``fetch``) that contains or follows the tapped depth
        (:class:`vobscure.layers.SolidIntervals`), on the tapped position's own ray: the true
        thickness (+inf: an unseen end; none ending behind the tapped depth, as a bilinear
        tap across a silhouette can read: a surface of no thickness).
    thickness_scale : {"constant", "linear"}, optional
        ``"linear"``: a numeric thickness is per unit of the tap's view depth (thickness x z),
        SSRT3's ``_LinearThickness`` (which multiplies its thickness by 100 z / far:
        ``thickness = 100 _Thickness / far`` reproduces it). Default ``"constant"``.
    thickness_far : float, optional
        Blender's far thickness, an angle in radians (>= 0, default 0: off): the back
        horizon lies at least this angle past the front one. Blender ships 45 degrees
        (``fast_gi_thickness_far``, with ``fast_gi_thickness_near`` 0.25).
    weighting : {"cosine", "uniform", "bitcount", "eevee"}, optional
        ``"cosine"`` (default): each sector weighs the cosine-weighted solid angle it spans,
        the integral of cos(theta - gamma) |sin theta| over it (GTAO's inner integral,
        Jimenez et al. 2016, Sec. 4, taken sector by sector), times the projected normal's
        length: cosine-weighted AO within R. ``"uniform"``: the solid angle it spans,
        (1/2) of the integral of |sin theta| (no normal weighting): uniformly weighted AO
        within R. ``"bitcount"``: every sector 1 / sectors, slices unweighted: the
        fraction of unoccluded sectors (Therrien et al. 2023, Algorithm 1; Bevy, SSRT3), an
        angle-uniform weighting that is neither of the two. ``"eevee"``: Blender's
        approximation of the cosine weighting (:data:`EEVEE_WEIGHTS`: cos of a sector's
        centre angle from the normal times pi / 64, averaged over groups of 4 sectors; no
        |sin theta| factor), slices weighted by the projected normal's length and normalized
        by its sum; ``sectors`` must be 32.
    sectors : int, optional
        Sectors per slice, 1 to 64 (default 32, as every engine above).
    sector_rule : {"centre", "touch"}, optional
        ``"centre"`` (default): an occluded angle interval marks the sectors whose centre it
        covers (error at most half a sector at each end, either sign). ``"touch"``: every
        sector it touches, Bevy's ``updateSectors`` and SSRT3's (first sector floor(a S),
        ceil((b - a) S) sectors; over-occludes by up to one sector per interval).
    step_power : float, optional
        Step j of n reaches ((j + u) / n) ** step_power of the radius (> 0;
        default 2, XeGTAO's and Bevy's; 1: linear; SSRT3's ``_ExpFactor``).
    randomize, seed, fetch, offscreen, noise_size, step_jitter, frame, schedule
        As in :func:`vobscure.screenspace.gtao.gtao`.

    Returns
    -------
    (H, W) ndarray
        Visibility in [0, 1] (1 = open), NaN on background; float32 for a float32 G-buffer,
        float64 otherwise (computed in float64).

    Raises
    ------
    ValueError
        If an argument is out of range or of the wrong type (the message names it), or
        ``thickness="layers"`` on a G-buffer without solid intervals.

    Notes
    -----
    A tap whose front point lies within R counts with its whole segment to the back point
    (Blender's test; Bevy and SSRT3 test no distance); a segment that enters the ball from a
    front point beyond R is not seen. With ``thickness=inf`` every tap within R marks every
    sector from its front horizon to the hemisphere's edge, so the unmarked sectors are
    GTAO's visible arc between the two horizons, quantized to sectors: with
    ``weighting="cosine"`` and the centre rule, the result differs from
    :func:`~vobscure.screenspace.gtao.gtao` with the same slices, steps and seed by at most
    pi / sectors (half a sector at each horizon, the cosine-weighted integrand at most 1).

    References
    ----------
    Therrien, Levesque & Gilet, "Screen Space Indirect Lighting with Visibility Bitmask",
    The Visual Computer 2023 (arXiv:2301.11376), Algorithm 1 (sectors of the slice, the
    front and back horizons, the bit count). Jimenez, Wu, Pesce & Jarabo 2016, Sec. 4 (the
    slices and the cosine-weighted slice integral). Bevy 0.15 ``ssao.wgsl``; SSRT3
    ``SSRTCS.compute``; Blender ``eevee_horizon_scan_eval_lib.glsl``,
    ``eevee_horizon_scan_lib.glsl``.

    Examples
    --------
    A plane is open (up to the quadrature over slices):

    >>> import vobscure as vo
    >>> cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(8, 8), fov_y=40)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> round(float(vbao(gb, radius=0.3, slices=9)[4, 4]), 3)
    1.0
    """
    C.as_gbuffer(gbuffer)
    radius = C.check_positive(radius, "radius")
    options = _check(gbuffer, radius=radius, slices=slices, steps=steps, thickness=thickness,
                     thickness_scale=thickness_scale, thickness_far=thickness_far, weighting=weighting,
                     sectors=sectors, sector_rule=sector_rule, step_power=step_power, randomize=randomize,
                     fetch=fetch, offscreen=offscreen, noise_size=noise_size, step_jitter=step_jitter)
    texture = C.noise_texture(noise_size, seed, 3, randomize, frame=frame, schedule=schedule)
    kernel = partial(_vbao_kernel, radius=radius, texture=texture, intervals=gbuffer.intervals, **options)
    return C.run_chunks(gbuffer, radius, kernel, C.out_dtype(gbuffer), chunk=CHUNK_PIXELS)


def _check(gbuffer, *, radius, slices, steps, thickness, thickness_scale, thickness_far, weighting, sectors,
           sector_rule, step_power, randomize, fetch, offscreen, noise_size, step_jitter):
    """Validate :func:`vbao`'s arguments (ValueError naming the argument); the kernel's options."""
    layers = isinstance(thickness, str)
    if layers:
        # ValueError naming thickness for another string or a G-buffer without intervals
        C.solid_intervals(gbuffer, thickness)
        value = np.inf
    elif thickness is None:
        value = THICKNESS_FRACTION * radius
    else:
        value = check_positive(thickness, "thickness", allow_inf=True, allow_zero=True)
    check_choice(thickness_scale, "thickness_scale", THICKNESS_SCALES)
    check_choice(weighting, "weighting", WEIGHTINGS)
    check_choice(sector_rule, "sector_rule", SECTOR_RULES)
    sectors = C.check_int(sectors, "sectors")
    if sectors > MAX_SECTORS:
        raise ValueError(f"sectors must be an integer in 1 .. {MAX_SECTORS}, got {sectors!r}")
    if weighting == "eevee" and sectors != 32:
        raise ValueError(f"sectors must be 32 with weighting='eevee' (Blender's weights), got {sectors!r}")
    C.check_bool(randomize, "randomize")
    check_choice(step_jitter, "step_jitter", STEP_JITTERS)
    C.check_common(fetch=fetch, offscreen=offscreen, noise_size=noise_size)
    return dict(slices=C.check_int(slices, "slices"), steps=C.check_int(steps, "steps"), thickness=value,
                linear=thickness_scale == "linear" and not layers, layers=layers,
                thickness_far=check_positive(thickness_far, "thickness_far", allow_zero=True),
                weighting=weighting, sectors=sectors, touch=sector_rule == "touch",
                step_power=check_positive(step_power, "step_power"), fetch=fetch, offscreen=offscreen,
                r1_jitter=step_jitter == "r1")


def sector_weights(gamma: np.ndarray, sectors: int, weighting: str) -> np.ndarray:
    """(k, sectors) weight of each sector of the slices with projected-normal angles ``gamma``
    (k,); sector i spans theta in gamma - pi/2 + pi [i, i + 1] / sectors.

    ``"cosine"``: F(theta_{i+1}) - F(theta_i), F(h) = sign(h) a(h) the antiderivative of
    cos(theta - gamma) |sin theta| with a(h) = (-cos(2h - gamma) + cos gamma + 2 h sin gamma) / 4
    (Jimenez et al. 2016, Sec. 4, Algorithm 1 line 27); a slice open from edge to edge sums to
    a(gamma - pi/2) + a(gamma + pi/2). ``"uniform"``: G(theta_{i+1}) - G(theta_i),
    G(h) = sign(h) (1 - cos h) / 2 (the slice parameterization's measure |sin theta| / 2);
    sums to 1. ``"bitcount"``: 1 / sectors. ``"eevee"``: Blender's grouped cosine weights
    (see :func:`vbao`).

    Examples
    --------
    >>> import numpy as np
    >>> w = sector_weights(np.array([0.0, 0.4]), 32, "uniform")
    >>> np.round(w.sum(axis=1), 12).tolist()
    [1.0, 1.0]
    >>> float(np.round(sector_weights(np.zeros(1), 32, "eevee").sum(), 4))
    1.0
    """
    k = len(gamma)
    if weighting == "bitcount":
        return np.full((k, sectors), 1.0 / sectors)
    if weighting == "eevee":
        # Blender: four weights, for the sectors 0-3 and 28-31, 4-7 and 24-27, ... (the masks
        # 0xF000000F, 0x0F0000F0, 0x00F00F00, 0x000FF000 of horizon_scan_bitmask_to_occlusion_cosine)
        half = np.repeat(EEVEE_WEIGHTS, 4)
        return np.broadcast_to(np.concatenate([half, half[::-1]]), (k, sectors))
    phi = -0.5 * np.pi + np.pi * np.arange(sectors + 1) / sectors      # theta_i - gamma
    g = gamma[:, None]
    sin_g, cos_g = np.sin(g), np.cos(g)
    theta = g + phi
    if weighting == "cosine":
        # a(theta_i), with cos(2 theta_i - gamma) = cos(gamma + 2 phi_i) expanded
        F = 0.25 * (-(cos_g * np.cos(2.0 * phi) - sin_g * np.sin(2.0 * phi)) + cos_g + 2.0 * theta * sin_g)
    else:
        F = 0.5 * (1.0 - (cos_g * np.cos(phi) - sin_g * np.sin(phi)))
    F = np.where(theta < 0, -F, F)
    return np.diff(F, axis=1)


class _Weights:
    """Byte lookup tables that sum the weights of the open sectors of a bitmask (k,) uint64,
    without unpacking it into (k, sectors) bits.

    For the weights that do not depend on gamma (``"bitcount"``, ``"eevee"``), a table per
    byte of the mask holds the sum of the weights of the bits set in each of its 256 values.
    For ``"cosine"`` and ``"uniform"`` the weight of sector i is F(theta_{i+1}) - F(theta_i),
    with theta_j = gamma + phi_j, phi_j = -pi/2 + pi j / S, and the antiderivative
    F(theta) = sign(theta) (cos gamma P(phi) + sin gamma Q(phi) + R(gamma)):

    - cosine, GTAO's inner integral a(h) = (-cos(2h - gamma) + cos gamma + 2 h sin gamma) / 4
      (Jimenez et al. 2016, Sec. 4, Algorithm 1 line 27) expanded at h = gamma + phi:
      P = (1 - cos 2 phi) / 4, Q = sin 2 phi / 4 + phi / 2, R = gamma sin gamma / 2;
    - uniform, (1 - cos h) / 2 (the slice measure |sin theta| / 2): P = -cos phi / 2,
      Q = sin phi / 2, R = 1 / 2.

    The sectors below theta = 0 (j < j0, the boundaries with theta_j < 0) weigh -(dP, dQ),
    those above +(dP, dQ) (dP_i = P_{i+1} - P_i: the tables), and the sector across theta = 0
    (P_{j0} + P_{j0-1}, Q_{j0} + Q_{j0-1}, 2 R).
    """

    def __init__(self, sectors: int, weighting: str):
        self.S = sectors
        self.weighting = weighting
        self.full = _LOW[sectors]
        nbytes = -(-sectors // 8)
        bits = (np.arange(256)[:, None] >> np.arange(8)) & 1                     # (256, 8)
        if weighting in ("bitcount", "eevee"):
            w = np.zeros(8 * nbytes)
            w[:sectors] = sector_weights(np.zeros(1), sectors, weighting)[0]
            self.table = [(bits @ w[8 * b:8 * b + 8],) for b in range(nbytes)]         # per byte: (256,)
            return
        self.phi = -0.5 * np.pi + np.pi * np.arange(sectors + 1) / sectors
        if weighting == "cosine":
            PQ = np.stack([0.25 * (1.0 - np.cos(2.0 * self.phi)), 0.25 * np.sin(2.0 * self.phi) + 0.5 * self.phi],
                          axis=1)
        else:
            PQ = np.stack([-0.5 * np.cos(self.phi), 0.5 * np.sin(self.phi)], axis=1)
        self.PQ = PQ                                                               # (S + 1, 2)
        dPQ = np.zeros((8 * nbytes, 2))
        dPQ[:sectors] = np.diff(PQ, axis=0)
        # per byte: the (256,) sums of dP and of dQ, as the real and imaginary parts of one
        # complex table (one gather reads both; complex sums add the parts separately)
        self.table = []
        for b in range(nbytes):
            table = np.empty(256, dtype=np.complex128)
            table.real, table.imag = bits @ dPQ[8 * b:8 * b + 8, 0], bits @ dPQ[8 * b:8 * b + 8, 1]
            self.table.append((table,))
        # per j0 in 0 .. S + 1: the masks of the sectors below and above theta = 0, the bit of
        # the sector across it (0 when none), and that sector's (P_{j0} + P_{j0-1}, Q_{j0} + Q_{j0-1})
        j0 = np.arange(sectors + 2)
        self.below = _LOW[np.maximum(j0 - 1, 0)]
        self.above = ~_LOW[np.minimum(j0, sectors)]
        jc = np.clip(j0 - 1, 0, sectors - 1)
        across = (j0 >= 1) & (j0 <= sectors)
        self.across = np.where(across, np.left_shift(np.uint64(1), jc.astype(np.uint64)), np.uint64(0))
        jn = np.minimum(jc + 1, sectors)
        self.across_PQ = tuple(PQ[jn, c] + PQ[jc, c] for c in (0, 1))

    def _sum(self, mask):
        """The table sums over the bits set in ``mask`` (k,) uint64: a list of (k,) arrays,
        one per table column (complex for ``"cosine"`` and ``"uniform"``: dP + i dQ)."""
        # the mask's bytes, least significant first, gathered from without shifting
        octets = np.asarray(mask, dtype="<u8").view(np.uint8).reshape(-1, 8)
        out = None
        for b, columns in enumerate(self.table):
            byte = octets[:, b]
            parts = [np.take(c, byte) for c in columns]
            if out is None:
                out = parts
            else:
                for o, q in zip(out, parts):
                    o += q
        return out

    def open_weight(self, occluded, sl):
        """(k,) the weighted sum of the sectors not set in ``occluded`` (k,) of slice ``sl``."""
        open_bits = np.invert(occluded)
        open_bits &= self.full
        if self.weighting in ("bitcount", "eevee"):
            return self._sum(open_bits)[0]
        S = self.S
        # j0: the boundaries below theta = 0 (phi_j < -gamma), 0 .. S + 1
        j0 = np.clip(np.ceil((0.5 * np.pi - sl.gamma) * S / np.pi), 0, S + 1).astype(np.intp)
        # (sum of dP) + i (sum of dQ) above theta = 0, less the same below
        pq = self._sum(np.take(self.above, j0) & open_bits)[0]
        pq -= self._sum(np.take(self.below, j0) & open_bits)[0]
        # the sector across theta = 0, where open (a product with the bit, not a select: the
        # terms are finite)
        bit = (np.take(self.across, j0) & open_bits) != 0
        p = pq.real + np.take(self.across_PQ[0], j0) * bit
        q = pq.imag + np.take(self.across_PQ[1], j0) * bit
        R = 0.5 * sl.gamma * sl.sin_g if self.weighting == "cosine" else 0.5
        out = sl.cos_g * p
        out += sl.sin_g * q
        out += (2.0 * R) * bit
        return out


def _layer_back(px, tap, intervals, offscreen):
    """The back depth (k,) of the solid interval of the tapped pixel (the pixel the tap falls
    in) that contains or follows the tapped depth (:func:`vobscure.screenspace._common.interval_back`:
    +inf for an unseen end, the tapped depth itself when no interval ends behind it)."""
    index, _ = C.nearest_pixel(px.shape, tap.x, tap.y, offscreen=offscreen)
    return C.interval_back(intervals, index, tap.d)


#: Abramowitz & Stegun 1964, Eq. 4.4.46: arccos x = sqrt(1 - x) (a_0 + a_1 x + ... + a_7 x^7)
#: on [0, 1], error at most 2e-8 (measured 2.2e-8 in float64 with these coefficients); about
#: twice as fast as numpy's arccos, which is a quarter of VBAO's time otherwise.
ACOS_COEFFICIENTS = (1.5707963050, -0.2145988016, 0.0889789874, -0.0501743046, 0.0308918810, -0.0170881256,
                     0.0066700901, -0.0012624911)


def _acos(c, out=None):
    """arccos of ``c`` clamped to [-1, 1] (A&S 4.4.46, :data:`ACOS_COEFFICIENTS`), in ``out``
    (a new array without it); overwrites ``c``.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.linspace(-1.0, 1.0, 10001)
    >>> bool(np.max(np.abs(_acos(x.copy()) - np.arccos(x))) < 2.5e-8)
    True
    """
    c = np.clip(c, -1.0, 1.0, out=c)
    negative = c < 0
    x = np.abs(c, out=c)
    # Horner's scheme from a_7 down
    r = np.multiply(x, ACOS_COEFFICIENTS[-1], out=out)
    r += ACOS_COEFFICIENTS[-2]
    for a in ACOS_COEFFICIENTS[-3::-1]:
        r *= x
        r += a
    np.subtract(1.0, x, out=x)
    r *= np.sqrt(x, out=x)
    # arccos(-x) = pi - arccos(x)
    return np.subtract(np.pi, r, out=r, where=negative)


def _back_angle(px, tap, v, dv, *, thickness, linear, layers, intervals, offscreen):
    """The angle from v (k,) of the tap's back point (``dv``: the tap's offset from p along v),
    for a thickness that varies per tap (``linear``) or read from the layers (``layers``);
    :class:`_Kernel` computes the constant thicknesses in place."""
    if not layers:
        T = thickness * tap.d if linear else thickness
        # Bevy processSample, SSRT3 HorizonSampling, Blender: the tap moved away from the
        # camera by T along p's view vector (unit): (delta - T v) . v = dv - T and
        # |delta - T v|^2 = dist^2 - 2 T dv + T^2
        length2 = tap.dist * tap.dist - 2.0 * T * dv + T * T
        return _acos((dv - T) / np.sqrt(np.maximum(length2, 1e-300)))
    vx, vy, vz = v
    p = px.p
    z_b = _layer_back(px, tap, intervals, offscreen)
    finite = np.isfinite(z_b)
    z = np.where(finite, z_b, tap.d)
    srx, sry = tap.ray
    bx, by = C.ray_to_xy(srx, sry, z, px.perspective)
    bx, by, bz = bx - p[:, 0], by - p[:, 1], z - p[:, 2]
    # an unseen end: the direction of the tapped ray, away from the camera
    if px.perspective:
        rx, ry, rz = srx, sry, np.ones_like(srx)
    else:
        rx, ry, rz = np.zeros_like(bx), np.zeros_like(bx), np.ones_like(bx)
    bx, by, bz = np.where(finite, bx, rx), np.where(finite, by, ry), np.where(finite, bz, rz)
    length = np.sqrt(bx * bx + by * by + bz * bz)
    cos_b = (bx * vx + by * vy + bz * vz) / np.where(length > 0, length, 1.0)
    return np.where(length > 0, _acos(cos_b), 0.0)


class _Kernel:
    """VBAO's per-tap work on one chunk of pixels, with its (k,) work arrays allocated once:
    every step runs in place on them (a chunk's taps are its whole per-pixel state)."""

    def __init__(self, px, v, *, radius, thickness, linear, layers, thickness_far, sectors, touch, offscreen,
                 intervals):
        k = len(px.index)
        self.px, self.v, self.radius, self.S = px, v, radius, sectors
        self.thickness, self.linear, self.layers = thickness, linear, layers
        self.thickness_far, self.touch, self.offscreen, self.intervals = thickness_far, touch, offscreen, intervals
        self.dv, self.tmp, self.lo, self.hi = (np.empty(k) for _ in range(4))
        # the cosines and the angles of the front (row 0) and back (row 1) points: one arccos
        # evaluates both
        self.cosines, self.alpha = np.empty((2, k)), np.empty((2, k))
        self.alpha_f, self.alpha_b = self.alpha
        self.index, self.mask = np.empty(k, dtype=np.intp), np.empty(k, dtype=np.uint64)
        self.runs = _run_masks(sectors)

    def angles(self, tap):
        """The front and back angles (k,) from v of the tap's occluder, alpha_f <= alpha_b
        (Therrien et al. 2023, Algorithm 1), in :attr:`alpha_f` and :attr:`alpha_b`."""
        vx, vy, vz = self.v
        ddx, ddy, ddz = tap.delta
        dv, tmp, alpha_f, alpha_b = self.dv, self.tmp, self.alpha_f, self.alpha_b
        # dv = delta . v (summed in x, y, z order)
        np.multiply(ddx, vx, out=dv)
        dv += np.multiply(ddy, vy, out=tmp)
        dv += np.multiply(ddz, vz, out=tmp)
        cos_f, cos_b = self.cosines
        np.divide(dv, tap.dist, out=cos_f)
        T = self.thickness
        if self.layers or self.linear:
            _acos(cos_f, out=alpha_f)
            alpha_b[:] = _back_angle(self.px, tap, self.v, dv, thickness=T, linear=self.linear, layers=self.layers,
                                     intervals=self.intervals, offscreen=self.offscreen)
        elif np.isinf(T):
            _acos(cos_f, out=alpha_f)
            alpha_b.fill(np.pi)
        else:
            # Bevy processSample, SSRT3 HorizonSampling, Blender: the tap moved away from the
            # camera by T along p's view vector (unit): (delta - T v) . v = dv - T and
            # |delta - T v|^2 = dist^2 - 2 T dv + T^2
            length = np.multiply(tap.dist, tap.dist, out=self.lo)
            length -= np.multiply(dv, 2.0 * T, out=tmp)
            length += T * T
            np.sqrt(np.maximum(length, 1e-300, out=length), out=length)
            np.subtract(dv, T, out=cos_b)
            cos_b /= length
            _acos(self.cosines.reshape(-1), out=self.alpha.reshape(-1))
        np.maximum(alpha_b, alpha_f, out=alpha_b)
        if self.thickness_far > 0:
            # Blender: the back horizon at least thickness_far past the front one
            np.maximum(alpha_b, np.add(alpha_f, self.thickness_far, out=tmp), out=alpha_b)

    def mark(self, tap, sign, per_radian, origin):
        """The bitmask (k,) uint64 of the sectors the tap's occluder marks (none where the
        tap is not used): the angles of :meth:`angles`, signed (positive towards t), to
        sectors, S ((theta - gamma) / pi + 1/2) = theta per_radian + origin (Algorithm 1;
        Bevy's n, Blender's ratio)."""
        S, lo, hi = self.S, self.lo, self.hi
        np.multiply(self.alpha_f if sign > 0 else self.alpha_b, per_radian, out=lo)
        np.multiply(self.alpha_b if sign > 0 else self.alpha_f, per_radian, out=hi)
        if sign > 0:
            lo += origin
            hi += origin
        else:
            # theta = -alpha: -(alpha per_radian) + origin
            np.subtract(origin, lo, out=lo)
            np.subtract(origin, hi, out=hi)
        if self.touch:
            # Bevy updateSectors / SSRT3 ComputeOccludedBitfield: from floor(a),
            # ceil(b - a) sectors, a and b clamped to the hemisphere
            np.clip(lo, 0.0, S, out=lo)
            np.clip(hi, 0.0, S, out=hi)
            hi -= lo
            np.ceil(hi, out=hi)
            np.floor(lo, out=lo)
            hi += lo
            np.minimum(hi, S, out=hi)
        else:
            # the sectors whose centre i + 1/2 lies in [lo, hi]
            lo -= 0.5
            np.clip(np.ceil(lo, out=lo), 0.0, S, out=lo)
            hi -= 0.5
            np.floor(hi, out=hi)
            hi += 1.0
            np.maximum(np.minimum(hi, S, out=hi), lo, out=hi)
        # Blender: a tap counts when its front point lies within the radius; a tap not
        # counted reads the empty interval (0, 0)
        use = tap.dist <= self.radius
        use &= tap.ok
        lo *= S + 1
        lo += hi
        lo *= use
        np.copyto(self.index, lo, casting="unsafe")
        return np.take(self.runs, self.index, out=self.mask)


@lru_cache(maxsize=None)
def _run_masks(sectors: int) -> np.ndarray:
    """((sectors + 1)^2,) uint64: entry i0 (sectors + 1) + i1 the bitmask of the sectors
    i0 .. i1 - 1 (empty for i1 <= i0)."""
    i0, i1 = np.divmod(np.arange((sectors + 1) ** 2), sectors + 1)
    masks = _LOW[np.maximum(i1, i0)] ^ _LOW[i0]
    masks.flags.writeable = False
    return masks


def _vbao_kernel(px, *, radius, slices, steps, thickness, linear, layers, thickness_far, weighting, sectors,
                 touch, step_power, fetch, offscreen, texture, intervals, r1_jitter=False):
    """VBAO of one chunk of pixels (see :func:`vbao`): loops over slices and steps only."""
    k = len(px.index)
    v, b1, b2 = Hz.view_basis(px)
    noise = Hz.slice_noise(px, texture)
    u_step, has_noise = noise.u_step, noise.has_noise
    S = sectors
    weights = _Weights(S, weighting)
    work = _Kernel(px, v, radius=radius, thickness=thickness, linear=linear, layers=layers,
                   thickness_far=thickness_far, sectors=S, touch=touch, offscreen=offscreen, intervals=intervals)
    visibility = np.zeros(k)
    weight_sum = np.zeros(k)
    # theta -> sectors: S ((theta - gamma) / pi + 1/2) = theta per_radian + origin
    per_radian = S / np.pi
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for s in range(slices):
            # the slices of GTAO (Jimenez et al. 2016, Algorithm 1)
            sl = Hz.horizon_slice(px, noise.rotation(s, slices), v, b1, b2, min_px=PIXEL_TOO_CLOSE)
            occluded = np.zeros(k, dtype=np.uint64)
            origin = S * (0.5 - sl.gamma / np.pi)
            for j in range(steps):
                u = (u_step + (s + j * steps) * R1_STEP) % 1.0 if (r1_jitter and has_noise) else u_step
                t = ((j + u) / steps) ** step_power + sl.min_s
                for sign in (1.0, -1.0):
                    tap = Hz.horizon_tap(px, sl, t if sign > 0 else -t, fetch=fetch, offscreen=offscreen)
                    # Therrien et al. 2023, Algorithm 1: the front and back horizon angles
                    # from v, then the sectors between them
                    work.angles(tap)
                    occluded |= work.mark(tap, sign, per_radian, origin)
            # the unmarked sectors, weighted
            slice_vis = weights.open_weight(occluded, sl)
            if weighting in ("cosine", "eevee"):
                # Jimenez et al. 2016, Sec. 4: the slice weighted by the projected normal's length
                visibility += sl.pn_len * slice_vis
                weight_sum += sl.pn_len
            else:
                visibility += slice_vis
                weight_sum += 1.0
    if weighting == "eevee":
        # Blender normalizes by the sum of the projected normals' lengths
        visibility = np.where(weight_sum > 0, visibility / np.where(weight_sum > 0, weight_sum, 1.0), 1.0)
    else:
        visibility /= slices
    np.clip(visibility, 0.0, 1.0, out=visibility)
    return visibility
