"""Post-processing of screen-space visibility: the edge-aware blur and dual radii.

Loos & Sloan 2010 sample VO sparsely per pixel and then denoise it with an edge-aware
(bilateral) blur (Sec. 4.1; Table 1 times "the bilateral blur"), and combine VO computed at
a small and a large radius (Sec. 6, Fig. 8). Both operate on (H, W) visibility images with
NaN on background pixels, as every estimator of :mod:`vobscure.screenspace` returns them.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_numeric, check_choice, check_int, check_positive
from ..gbuffer import GBuffer

__all__ = ["bilateral_blur", "combine_radii", "BLUR_PASSES", "COMBINE_MODES"]

#: The two ways to apply the blur: two 1-D passes (the real-time approximation) or the
#: exact 2-D window.
BLUR_PASSES = ("separable", "full")

#: How :func:`combine_radii` merges two visibility images (Loos & Sloan 2010, Sec. 6).
COMBINE_MODES = {"product": np.multiply, "min": np.minimum}


def bilateral_blur(visibility, gbuffer, *, radius_px=4, sigma_spatial=None, sigma_depth=0.05,
                   sigma_normal=0.2, passes="separable") -> np.ndarray:
    r"""Edge-aware (bilateral) blur of a visibility image, guided by the G-buffer.

    Every covered pixel p becomes the weighted mean of the defined pixels q in the
    (2 ``radius_px`` + 1)-wide window around it, with weights

    .. math::

        w(p, q) = \exp\left(-\frac{|q - p|^2}{2 \sigma_s^2}\right)
                  \exp\left(-\frac{1}{2}\left(\frac{z_q - z_p}{\sigma_z z_p}\right)^2\right)
                  \exp\left(-\frac{1 - n_p \cdot n_q}{\sigma_n^2}\right),

    a spatial Gaussian in pixels, a Gaussian in the *relative* depth difference and a
    Gaussian-like term in the angle between the view-space normals (Tomasi & Manduchi 1998
    with the G-buffer as the range image).

    Parameters
    ----------
    visibility : (H, W) array_like of float
        Visibility to blur; NaN on background pixels (and wherever it is undefined).
        Finite values elsewhere; +-inf is rejected.
    gbuffer : GBuffer
        The G-buffer ``visibility`` was computed from: ``depth`` (H, W), ``normal``
        (H, W, 3), ``valid`` (H, W).
    radius_px : int, optional
        Half-width r of the window in pixels (>= 0, default 4); 0 returns a copy (NaN on
        background).
    sigma_spatial : float, optional
        Standard deviation sigma_s of the spatial Gaussian in pixels (> 0); default None:
        ``radius_px / 2``.
    sigma_depth : float, optional
        Standard deviation sigma_z of the depth term as a fraction of the centre pixel's
        depth z_p (> 0, default 0.05): a neighbour 5% nearer or farther then has depth
        weight exp(-1/2).
    sigma_normal : float, optional
        Angular standard deviation sigma_n of the normal term in radians (> 0, see Notes);
        default 0.2 (about 11.5 degrees).
    passes : {"separable", "full"}, optional
        ``"separable"`` (default): a horizontal then a vertical 1-D pass, each with the full
        bilateral weight (2 (2r + 1) taps per pixel; the usual real-time approximation).
        ``"full"``: the exact 2-D window ((2r + 1)^2 taps per pixel).

    Returns
    -------
    (H, W) ndarray
        The blurred visibility; float32 if ``visibility`` is float32, float64 otherwise
        (the sums are accumulated in float64 either way). NaN wherever the G-buffer is
        background or ``visibility`` is NaN: the NaN mask of the input (together with the
        background) is kept exactly.

    Raises
    ------
    ValueError
        If ``gbuffer`` is not a :class:`~vobscure.GBuffer`, ``visibility`` does not have the
        G-buffer's shape or holds +-inf, ``radius_px`` is not an int >= 0, a sigma is not
        positive and finite, or ``passes`` is not one of :data:`BLUR_PASSES`.

    Notes
    -----
    *Normal term.* For unit normals at angle theta, 1 - cos(theta) = theta^2 / 2 + O(theta^4),
    so exp(-(1 - n_p . n_q) / sigma_n^2) is, for small angles, a Gaussian in the angle with
    standard deviation ``sigma_normal`` radians; it needs no arccos and stays monotonic up to
    180 degrees. Across a 90-degree crease the weight is exp(-1 / sigma_n^2) = exp(-25) with
    the defaults.

    *Depth term.* The difference is divided by ``sigma_depth * z_p``, so the weights do not
    change when the scene and camera are scaled together: the blur is scale invariant.
    Across a 50% depth jump (z_q = 1.5 z_p) the default weight is exp(-50); from the far
    side (z_q = z_p / 1.5) it is exp(-22.2), about 2e-10.

    *Cameras.* The blur reads the images only, never the camera: a principal point anywhere
    changes nothing. The window and ``sigma_spatial`` are in pixels, so with non-square
    pixels (``camera.fx != camera.fy``) the window covers fx / fy times as much of the view
    vertically as horizontally (per unit of view angle); give ``radius_px`` for the axis
    that matters.

    *Masking.* Neighbours that are background, NaN or outside the image get weight zero and
    the weights are renormalized over the rest, so edges of the image and of the coverage
    are handled the same way. The centre pixel always has weight 1, so every defined pixel
    stays defined. The result at p is a convex combination of defined input values: it
    stays within their range (up to rounding), and a constant image stays constant.

    *Separable passes.* The horizontal pass writes an intermediate image (NaN mask kept)
    that the vertical pass blurs with the same weights along columns. On a G-buffer with
    constant depth and normal both modes apply the same truncated 2-D Gaussian; near edges
    the separable result differs from the exact one, as in real-time renderers.

    The loop runs over window offsets and accumulates on whole shifted image slices, so
    memory is a few (H, W) float64 images whatever the radius.

    References
    ----------
    .. [1] B. J. Loos and P.-P. Sloan, "Volumetric Obscurance", Proc. I3D 2010, Sec. 4.1
       (line samples "still need an edge aware blur pass") and Table 1 (bilateral blur).
    .. [2] C. Tomasi and R. Manduchi, "Bilateral Filtering for Gray and Color Images",
       Proc. ICCV 1998.

    Examples
    --------
    A checkerboard on a flat slab seen from above loses almost all of its contrast:

    >>> import numpy as np
    >>> import vobscure as vo
    >>> from vobscure.screenspace.blur import bilateral_blur
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(8, 8), ortho_height=2.0)
    >>> gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    >>> v = (np.indices((8, 8)).sum(axis=0) % 2).astype(float)
    >>> out = bilateral_blur(v, gb, radius_px=2)
    >>> float(v.std()), bool(out.std() < 0.1), bool(np.all((out >= 0) & (out <= 1)))
    (0.5, True, True)
    """
    if not isinstance(gbuffer, GBuffer):
        raise ValueError("gbuffer must be a vobscure GBuffer (from render_gbuffer), "
                         f"got {type(gbuffer).__name__}")
    r = check_int(radius_px, "radius_px", minimum=0)
    sigma_s = r / 2.0 if sigma_spatial is None else check_positive(sigma_spatial, "sigma_spatial")
    sigma_z = check_positive(sigma_depth, "sigma_depth")
    sigma_n = check_positive(sigma_normal, "sigma_normal")
    check_choice(passes, "passes", BLUR_PASSES)
    v, out_dtype = _as_visibility(visibility, gbuffer.shape)

    valid = np.asarray(gbuffer.valid, dtype=bool)
    defined = valid & ~np.isnan(v)
    out = np.full(v.shape, np.nan)
    if r == 0 or not defined.any():
        out[defined] = v[defined]
        return out.astype(out_dtype, copy=False)

    # Guide images in float64, with harmless stand-ins on background pixels (their weight is
    # zeroed by `defined`, but inf - inf or NaN * 0 would still poison the sums).
    z = np.where(valid, np.asarray(gbuffer.depth, dtype=np.float64), 1.0)
    normal = np.asarray(gbuffer.normal, dtype=np.float64)
    n = tuple(np.ascontiguousarray(np.where(valid, normal[..., c], 0.0)) for c in range(3))
    guide = (z, n, sigma_z, sigma_n)
    values = np.where(defined, v, 0.0)

    d = np.arange(-r, r + 1)
    if passes == "full":
        dy, dx = (a.ravel() for a in np.meshgrid(d, d, indexing="ij"))
        offsets = list(zip(dy.tolist(), dx.tolist(), np.exp(-(dy**2 + dx**2) / (2.0 * sigma_s**2)).tolist()))
        blurred = _bilateral_pass(values, defined, guide, offsets)
    else:
        g = np.exp(-(d**2) / (2.0 * sigma_s**2)).tolist()
        horizontal = [(0, int(k), w) for k, w in zip(d, g)]
        vertical = [(int(k), 0, w) for k, w in zip(d, g)]
        blurred = _bilateral_pass(values, defined, guide, horizontal)
        blurred = _bilateral_pass(np.where(defined, blurred, 0.0), defined, guide, vertical)
    out[defined] = blurred[defined]
    return out.astype(out_dtype, copy=False)


def _as_visibility(visibility, shape) -> tuple[np.ndarray, np.dtype]:
    """(H, W) float64 copy of ``visibility`` and the dtype to return."""
    arr = as_numeric(visibility, "visibility", kinds="biuf", expected="a real numeric array")
    if arr.shape != tuple(shape):
        raise ValueError(f"visibility must have the G-buffer's shape {tuple(shape)} (gbuffer.depth.shape), "
                         f"got {arr.shape}")
    out_dtype = np.dtype(np.float32) if arr.dtype == np.float32 else np.dtype(np.float64)
    v = arr.astype(np.float64)
    if np.isinf(v).any():
        raise ValueError(f"visibility must be finite or NaN; it holds {int(np.isinf(v).sum())} inf value(s)")
    return v, out_dtype


def _shift(k: int, size: int) -> tuple[slice, slice]:
    """Slices (of p, of q = p + k) along one axis of length ``size`` where both are inside."""
    return slice(max(0, -k), size - max(0, k)), slice(max(0, k), size + min(0, k))


def _bilateral_pass(values, defined, guide, offsets) -> np.ndarray:
    """One bilateral pass over the window ``offsets`` = [(dy, dx, spatial weight), ...].

    ``values`` is 0 where not ``defined``; returns the normalized sums at defined pixels
    (NaN elsewhere). Accumulates on whole slices: no (H, W, taps) array.
    """
    z, (nx, ny, nz), sigma_z, sigma_n = guide
    H, W = values.shape
    num = np.zeros((H, W))
    den = np.zeros((H, W))
    weight_q = defined.astype(np.float64)
    for dy, dx, g in offsets:
        if abs(dy) >= H or abs(dx) >= W:
            continue
        (py, qy), (px, qx) = _shift(dy, H), _shift(dx, W)
        p, q = (py, px), (qy, qx)
        z_p = z[p]
        t = (z[q] - z_p) / (sigma_z * z_p)       # relative depth difference in units of sigma_depth
        cos = nx[p] * nx[q] + ny[p] * ny[q] + nz[p] * nz[q]
        # Tomasi & Manduchi 1998: domain weight g times range weight, here the G-buffer's
        # exp(-t^2 / 2) * exp(-(1 - n_p . n_q) / sigma_n^2) in one exponential
        w = np.exp(-0.5 * t * t - (1.0 - cos) / sigma_n**2)
        w *= g
        w *= weight_q[q]
        num[p] += w * values[q]
        den[p] += w
    out = np.full((H, W), np.nan)
    np.divide(num, den, out=out, where=defined)
    return out


def combine_radii(a, b, *, mode="product") -> np.ndarray:
    """Combine visibility computed at two radii into one image (dual radii).

    A small radius keeps fine detail but loses contact shadows and broad darkening; a large
    one captures those but blurs fine features. Loos & Sloan combine the two by a product or
    a minimum (Sec. 6, Fig. 8).

    Parameters
    ----------
    a, b : (H, W) array_like of float
        Visibility images of the same shape (any shape, as long as both agree), typically
        in [0, 1], with NaN on background.
    mode : {"product", "min"}, optional
        ``"product"`` (default): a * b (both darkenings apply); ``"min"``: the elementwise minimum
        (the stronger one wins). Keys of :data:`COMBINE_MODES`.

    Returns
    -------
    ndarray, the shape of ``a``
        float32 if both inputs are float32, float64 otherwise. NaN where either input is
        NaN. Inputs in [0, 1] give values in [0, 1], never above the smaller input.

    Raises
    ------
    ValueError
        If the shapes differ, an input is not numeric or ``mode`` is unknown.

    References
    ----------
    .. [1] B. J. Loos and P.-P. Sloan, "Volumetric Obscurance", Proc. I3D 2010, Sec. 6
       ("using either a product of the two results (or the minimum)") and Fig. 8.

    Examples
    --------
    >>> import numpy as np
    >>> from vobscure.screenspace.blur import combine_radii
    >>> small = np.array([[1.0, 0.5], [0.8, np.nan]])
    >>> large = np.array([[0.6, 0.9], [0.5, 0.7]])
    >>> combine_radii(small, large).tolist()
    [[0.6, 0.45], [0.4, nan]]
    >>> combine_radii(small, large, mode="min").tolist()
    [[0.6, 0.5], [0.5, nan]]
    """
    check_choice(mode, "mode", COMBINE_MODES)
    a_arr, b_arr = (as_numeric(value, name, kinds="biuf", expected="a real numeric array")
                    for name, value in (("a", a), ("b", b)))
    if a_arr.shape != b_arr.shape:
        raise ValueError(f"a and b must have the same shape, got a {a_arr.shape} and b {b_arr.shape}")
    dtype = np.float32 if a_arr.dtype == np.float32 and b_arr.dtype == np.float32 else np.float64
    # Sec. 6 of Loos & Sloan 2010: product or minimum of the two radii's results; NaN propagates.
    return COMBINE_MODES[mode](a_arr.astype(dtype), b_arr.astype(dtype))
