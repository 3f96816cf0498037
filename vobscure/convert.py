"""Other programs' depth and normal images converted to the library's G-buffer conventions.

The machinery of :meth:`GBuffer.from_arrays <vobscure.gbuffer.GBuffer.from_arrays>` and
:meth:`GBuffer.derive_normals <vobscure.gbuffer.GBuffer.derive_normals>`: depth linearization
(OpenGL, Direct3D, reversed-Z, ray distance), background masks, view matrices, normals
unpacked, rotated to view space, renormalized and flipped to face the camera, and normals
derived from the depth (``docs/own-buffers.md``). :mod:`vobscure.io` reads the files and
hands their arrays to ``GBuffer.from_arrays``.
"""

from __future__ import annotations

import warnings

import numpy as np

from ._validate import as_numeric, check_bool, check_choice, check_positive

__all__ = ["convert_buffers", "normals_from_depth", "NormalsRenormalizedWarning", "NormalsRepairedWarning",
           "DEPTH_KINDS", "NORMAL_SPACES", "NORMAL_ENCODINGS", "CONVENTIONS", "NORMAL_LENGTH_TOL",
           "NORMAL_ZERO_TOL", "VIEW_TOL", "CENTRAL_RATIO", "NORMAL_BAND_ROWS"]


#: The depth encodings :meth:`GBuffer.from_arrays` reads (``docs/own-buffers.md``).
DEPTH_KINDS = ("linear", "ndc", "ndc01", "reversed", "distance")
NORMAL_SPACES = ("view", "world")
NORMAL_ENCODINGS = ("signed", "unit")
CONVENTIONS = ("vobscure", "opengl", "directx")
#: A normal whose length differs from 1 by more than this is renormalized with a
#: :class:`NormalsRenormalizedWarning` (those within it are renormalized silently). Half-float
#: normals are within 5e-4; 8-bit ones (``0.5 n + 0.5`` in a PNG) are not.
NORMAL_LENGTH_TOL = 1e-3
#: A normal shorter than this has no direction: an error on a covered pixel (or repaired).
NORMAL_ZERO_TOL = 1e-6
#: |R Rᵀ - I| allowed for the rotation part of a ``view`` matrix, and the disagreement allowed
#: between ``view`` and the camera's own pose (relative to the translation's size).
VIEW_TOL = 1e-4
#: Derived normals: the central difference is used where the centre's second difference of the
#: plane coordinate (1/z perspective, z orthographic) is at most this many times the better
#: one-sided extrapolation error (smooth surface); otherwise the smoother side's one-sided one.
CENTRAL_RATIO = 2.0


class NormalsRenormalizedWarning(UserWarning):
    """:meth:`GBuffer.from_arrays` renormalized normals longer or shorter than 1 by more than
    ``normal_tol``; the message counts them. Real frames hold such normals (a pixel at an edge
    averages the normals of two faces, 8-bit storage rounds them)."""


class NormalsRepairedWarning(UserWarning):
    """:meth:`GBuffer.from_arrays` (with ``repair_normals=True``) replaced zero or NaN normals
    of covered pixels by normals derived from the depth; the message counts them."""



def convert_buffers(depth, normal, *, camera, depth_kind, near, far, normal_space, view,
                    normal_encoding, convention, background, origin, normal_tol, repair_normals,
                    back_depth=None) -> dict:
    """The keyword arguments of a :class:`~vobscure.gbuffer.GBuffer` holding ``depth`` and
    ``normal`` converted to the library's conventions.

    The work of :meth:`GBuffer.from_arrays <vobscure.gbuffer.GBuffer.from_arrays>`, whose
    documentation gives the parameters (here all required, keyword-only after ``normal``),
    the conversions, the errors and the warnings.

    Parameters
    ----------
    depth : (H, W) array_like of float
    normal : (H, W, 3) array_like or None
    camera, depth_kind, near, far, normal_space, view, normal_encoding, convention, background, origin, normal_tol, repair_normals
        As in :meth:`GBuffer.from_arrays <vobscure.gbuffer.GBuffer.from_arrays>`.
    back_depth : (H, W) array_like of float or None
        As in :meth:`GBuffer.from_arrays <vobscure.gbuffer.GBuffer.from_arrays>`; given, the
        result also holds ``intervals``.

    Returns
    -------
    dict
        ``depth`` (H, W) linear depth, +inf on background; ``normal`` (H, W, 3) view-space
        unit normals facing the camera, 0 on background; ``valid`` (H, W) bool;
        ``primitive`` (-1 everywhere); ``hits`` None (derived from depth and normals);
        ``dtype``; ``view_to_world`` (R, t) of ``view`` or None; ``conversion`` (the counts);
        with ``back_depth``, ``intervals`` (a one-interval
        :class:`~vobscure.layers.SolidIntervals`).

    Examples
    --------
    >>> import numpy as np, vobscure as vo
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 3), ortho_height=2.0)
    >>> fields = convert_buffers(np.full((3, 4), 0.25), None, camera=cam, depth_kind="ndc01",
    ...                          near=2.0, far=6.0, normal_space="view", view=None,
    ...                          normal_encoding="signed", convention="vobscure", background=None,
    ...                          origin="upper", normal_tol=NORMAL_LENGTH_TOL, repair_normals=False)
    >>> fields["depth"][0].tolist(), fields["normal"][1, 1].tolist(), fields["conversion"]["derived"]
    ([3.0, 3.0, 3.0, 3.0], [0.0, 0.0, -1.0], 12)
    """
    from .camera import Camera

    if not isinstance(camera, Camera):
        raise ValueError(f"camera must be a vobscure Camera, got {type(camera).__name__}")
    check_choice(depth_kind, "depth_kind", DEPTH_KINDS)
    check_choice(normal_space, "normal_space", NORMAL_SPACES)
    check_choice(normal_encoding, "normal_encoding", NORMAL_ENCODINGS)
    check_choice(convention, "convention", CONVENTIONS)
    check_choice(origin, "origin", ("upper", "lower"))
    normal_tol = check_positive(normal_tol, "normal_tol")
    repair_normals = check_bool(repair_normals, "repair_normals")

    # -- shapes and dtypes
    given = as_numeric(depth, "depth", expected="a numeric (H, W) array")
    nrm = None if normal is None else np.asarray(normal)
    nshape = None if nrm is None else nrm.shape
    if given.shape != camera.shape:
        raise _shape_error("depth", given.shape, camera, given.shape, nshape)
    if nrm is not None:
        if nrm.dtype.kind not in "fiu":
            raise ValueError(f"normal must be a numeric (H, W, 3) array, got dtype {nrm.dtype}")
        if nrm.shape != camera.shape + (3,):
            raise _shape_error("normal", nrm.shape, camera, given.shape, nshape)
    dtype = np.float32 if given.dtype in (np.float32, np.float16) else np.float64
    if origin == "lower":
        given = given[::-1]
        nrm = None if nrm is None else nrm[::-1]
    raw = given.astype(np.float64)

    # -- depth: background, then linearization of the covered pixels
    is_ndc = depth_kind in _RANGES
    if is_ndc:
        near, far = _clip_planes(camera, near, far, depth_kind)
    bg, nonfinite = _background(raw, given, depth_kind, background)
    covered = ~bg
    values = raw[covered]
    if is_ndc:
        lo, hi = _RANGES[depth_kind]
        outside = int(np.count_nonzero((values < lo) | (values > hi)))
        if outside:
            raise ValueError(f"depth (depth_kind={depth_kind!r}) must lie in [{lo}, {hi}] on covered "
                             f"pixels; {outside} value(s) do not (min {values.min():.6g}, max "
                             f"{values.max():.6g}). Is depth_kind right, or are they background?")
    z = _linearize(values, depth_kind, near, far, camera,
                   _view_rays(camera)[covered] if depth_kind == "distance" else None)
    bad = ~(np.isfinite(z) & (z > 0))
    if bad.any():
        hint = (" OpenGL eye-space z is negative in front of the camera: pass -z." if
                depth_kind in ("linear", "distance") else "")
        raise ValueError(f"depth must give a positive finite linear depth on covered pixels; "
                         f"{int(bad.sum())} pixel(s) do not (depth_kind={depth_kind!r}, values like "
                         f"{values[bad][:3].tolist()}).{hint} Mark background with background=...")
    linear = np.full(raw.shape, np.inf)
    linear[covered] = z

    counts = {"pixels": int(raw.size), "covered": int(covered.sum()), "background": int(bg.sum()),
              "nonfinite": nonfinite, "renormalized": 0, "flipped": 0, "repaired": 0, "derived": 0,
              "undetermined": 0}
    view_frame = None if view is None else _view_matrix(view, convention)
    if view_frame is not None and getattr(camera, "has_pose", True):
        R_cam = np.asarray(camera.rotation, dtype=np.float64)
        t_cam = -(R_cam @ np.asarray(camera.eye, dtype=np.float64))
        R_err = float(np.abs(view_frame[0] - R_cam).max())
        t_err = float(np.abs(view_frame[1] - t_cam).max()) / max(1.0, float(np.abs(t_cam).max()))
        if R_err > VIEW_TOL or t_err > VIEW_TOL:
            raise ValueError(f"view disagrees with the camera's pose (rotation by {R_err:.3g}, "
                             f"translation by {t_err:.3g} relative; convention={convention!r}): "
                             "pass the matching view, or a camera without a pose")

    # -- normals
    if nrm is None:
        n_view, undetermined = normals_from_depth(camera, linear, covered)
        counts["derived"] = counts["covered"]
        counts["undetermined"] = undetermined
    else:
        n_view, fixes = _normals_in_bands(nrm, camera, linear, covered, dtype, normal_space=normal_space,
                                          encoding=normal_encoding, convention=convention,
                                          view_frame=view_frame, tol=normal_tol, repair=repair_normals)
        counts.update(fixes)
    counts.update(depth_kind=depth_kind, normal_space=None if nrm is None else normal_space,
                  normal_encoding=None if nrm is None else normal_encoding, convention=convention)
    H, W = camera.shape
    out = dict(depth=linear, normal=n_view, valid=covered,
               primitive=np.broadcast_to(np.int64(-1), (H, W)), hits=None, dtype=dtype,
               view_to_world=view_frame, conversion=counts)
    if back_depth is not None:
        out["intervals"], back_counts = _back_interval(back_depth, linear, covered, camera=camera,
                                                       depth_kind=depth_kind, near=near, far=far,
                                                       background=background, origin=origin,
                                                       depth_shape=given.shape, normal_shape=nshape)
        counts.update(back_counts)
    return out


def _back_interval(back_depth, linear, covered, *, camera, depth_kind, near, far, background, origin,
                   depth_shape, normal_shape):
    """The one-interval :class:`~vobscure.layers.SolidIntervals` ``[depth, back]`` of a
    back-face depth image, and its counts ``back_background`` (covered pixels whose back is
    background or non-finite: +inf, the end unseen) and ``back_clamped`` (back in front of the
    front, by rounding: set to the front)."""
    from .layers import SolidIntervals

    given = as_numeric(back_depth, "back_depth", expected="a numeric (H, W) array")
    if given.shape != camera.shape:
        err = _shape_error("back_depth", given.shape, camera, depth_shape, normal_shape)
        raise ValueError(str(err).replace("arrays given: ", f"arrays given: back_depth {given.shape}, "))
    if origin == "lower":
        given = given[::-1]
    raw = given.astype(np.float64)
    bg, _ = _background(raw, given, depth_kind, background)
    use = covered & ~bg                   # a back value to read: the front is covered and it is not background
    values = raw[use]
    if depth_kind in _RANGES:
        lo, hi = _RANGES[depth_kind]
        outside = int(np.count_nonzero((values < lo) | (values > hi)))
        if outside:
            raise ValueError(f"back_depth (depth_kind={depth_kind!r}) must lie in [{lo}, {hi}] where it is "
                             f"not background; {outside} value(s) do not")
    z = _linearize(values, depth_kind, near, far, camera,
                   _view_rays(camera)[use] if depth_kind == "distance" else None)
    bad = ~(z > 0)
    if bad.any():
        raise ValueError(f"back_depth must give a positive linear depth where it is not background; "
                         f"{int(bad.sum())} pixel(s) do not (depth_kind={depth_kind!r}, values like "
                         f"{values[bad][:3].tolist()})")
    back = np.full(raw.shape, np.inf)
    back[use] = z
    with np.errstate(invalid="ignore"):
        ahead = covered & (back < linear)
    back[ahead] = linear[ahead]
    back[~covered] = np.inf
    counts = {"back_background": int(np.count_nonzero(covered & bg)), "back_clamped": int(ahead.sum())}
    return SolidIntervals(linear[None], back[None]), counts


def _shape_error(name, arr_shape, camera, depth_shape=None, normal_shape=None) -> ValueError:
    H, W = camera.height, camera.width
    want = (H, W) if name == "depth" else (H, W, 3)
    hint = ""
    if tuple(arr_shape[:2]) == (W, H) and W != H:
        hint = " (transposed? images are (rows, columns) = (H, W); pass a.T or swap the camera size)"
    shapes = f"depth {depth_shape}" + ("" if normal_shape is None else f", normal {normal_shape}")
    return ValueError(f"{name} must have shape {want} for camera.size (W, H) = {camera.size}, "
                      f"got {tuple(arr_shape)}{hint}; arrays given: {shapes}")


def _clip_planes(camera, near, far, depth_kind):
    """``near``, ``far`` as floats (from the camera when not given), validated."""
    near = getattr(camera, "near", None) if near is None else near
    far = getattr(camera, "far", None) if far is None else far
    if near is None or far is None:
        missing = " and ".join(k for k, v in (("near", near), ("far", far)) if v is None)
        raise ValueError(f"depth_kind={depth_kind!r} needs the clip distances near and far to "
                         f"linearize; {missing} not given (and the camera has none). Pass "
                         "near=..., far=... (far=np.inf for an infinite far plane)")
    near = check_positive(near, "near")
    far = check_positive(far, "far", allow_inf=True)
    if not far > near:
        raise ValueError(f"far must be greater than near, got near={near!r}, far={far!r}")
    return near, far


def _view_rays(camera, rows: slice = slice(None)) -> np.ndarray:
    """(h, W, 3) view-space direction of each pixel centre's ray (not normalized), for the
    image's ``rows``."""
    H, W = camera.shape
    i = np.arange(H, dtype=np.float64)[rows] + 0.5
    if camera.is_perspective:
        centers = np.empty((len(i), W, 2))
        centers[..., 0] = np.arange(W, dtype=np.float64)[None, :] + 0.5
        centers[..., 1] = i[:, None]
        return camera.unproject(centers, 1.0)                    # (x, y, 1) at unit depth
    return np.broadcast_to(np.array([0.0, 0.0, 1.0]), (len(i), W, 3))


def _linearize(raw, kind, near, far, camera, rays):
    """Linear view depth z from the stored values (covered pixels, flat arrays)."""
    n, f = near, far
    perspective = camera.is_perspective
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if kind == "linear":
            return raw.copy()
        if kind == "distance":
            if not perspective:
                return raw.copy()           # parallel rays leave the camera plane: r = z
            return raw / np.linalg.norm(rays, axis=-1)   # z = r / |(x, y, 1)|
        if np.isinf(f):
            # the limits f -> inf of the formulas below
            if not perspective:
                raise ValueError(f"depth_kind={kind!r} on an orthographic camera needs a finite far")
            if kind == "ndc":
                return 2.0 * n / (1.0 - raw)            # z_ndc = 1 - 2 n / z
            if kind == "ndc01":
                return n / (1.0 - raw)                  # z_01 = 1 - n / z
            return n / raw                              # reversed: z_r = n / z
        if perspective:
            if kind == "ndc":
                # OpenGL (glFrustum): z_ndc = (f + n)/(f - n) - 2 f n / ((f - n) z)
                return 2.0 * f * n / ((f + n) - raw * (f - n))
            if kind == "ndc01":
                # Direct3D (D3DXMatrixPerspectiveFovLH): z_01 = f/(f - n) - f n / ((f - n) z)
                return f * n / (f - raw * (f - n))
            # reversed-Z: the same with n and f swapped, z_r = n/(n - f) - f n / ((n - f) z)
            return f * n / (n + raw * (f - n))
        # orthographic projections are affine in z (glOrtho, D3DXMatrixOrthoLH)
        if kind == "ndc":
            return ((f - n) * raw + f + n) / 2.0
        if kind == "ndc01":
            return n + raw * (f - n)
        return f - raw * (f - n)


_RANGES = {"ndc": (-1.0, 1.0), "ndc01": (0.0, 1.0), "reversed": (0.0, 1.0)}


def _background(raw, given, kind, background):
    """(H, W) bool background mask and the count of non-finite values."""
    nonfinite = ~np.isfinite(raw)
    if background is None:
        if kind in ("ndc", "ndc01"):
            beyond = raw >= 1.0
        elif kind == "reversed":
            beyond = raw <= 0.0
        else:
            beyond = np.zeros(raw.shape, dtype=bool)
    elif callable(background):
        beyond = np.asarray(background(given))
        if beyond.shape != raw.shape or beyond.dtype != bool:
            raise ValueError(f"background(depth) must return a bool array of the depth's shape "
                             f"{raw.shape}, got {beyond.dtype} of shape {beyond.shape}")
    else:
        if isinstance(background, bool) or not isinstance(background, (int, float, np.number)) \
                or np.isnan(background):
            raise ValueError(f"background must be a depth value (number) or a callable "
                             f"depth -> (H, W) bool mask, got {background!r}")
        with np.errstate(invalid="ignore"):
            beyond = raw <= background if kind == "reversed" else raw >= background
    return nonfinite | beyond, int(nonfinite.sum())


def _view_matrix(view, convention):
    """(R, t) of a world-to-view matrix, in the library's view frame."""
    V = np.asarray(view, dtype=np.float64)
    if V.shape != (4, 4) or not np.all(np.isfinite(V)):
        raise ValueError(f"view must be a finite (4, 4) world-to-view matrix, got shape {V.shape}")
    if not np.allclose(V[3], (0.0, 0.0, 0.0, 1.0), atol=VIEW_TOL):
        raise ValueError(f"view's last row must be (0, 0, 0, 1), got {V[3].tolist()}: a row-vector "
                         "(Direct3D) matrix must be transposed; a projection matrix is not a view")
    R, t = V[:3, :3].copy(), V[:3, 3].copy()
    err = float(np.abs(R @ R.T - np.eye(3)).max())
    if err > VIEW_TOL:
        raise ValueError(f"view's upper-left 3x3 must be a rotation (|R Rᵀ - I| = {err:.3g} > "
                         f"{VIEW_TOL}); scale or shear in the view matrix is not supported")
    if convention == "opengl":     # OpenGL eye space looks down -z: negate the z row
        R[2] *= -1.0
        t[2] *= -1.0
    return R, t


#: Rows of the normal image converted and checked at once (bounded memory on large frames).
NORMAL_BAND_ROWS = 64


def _normals_in_bands(nrm, camera, depth, covered, dtype, *, normal_space, encoding, convention, view_frame,
                      tol, repair):
    """The normal image converted to the library's frame, checked, renormalized and flipped to
    face the camera, in bands of :data:`NORMAL_BAND_ROWS` rows (float64 work, ``dtype``
    output), with one warning for the whole image."""
    H, W = covered.shape
    out = np.zeros((H, W, 3), dtype=dtype)
    counts = {"renormalized": 0, "flipped": 0, "repaired": 0}
    missing_all, worst, zero = np.zeros((H, W), dtype=bool), 0.0, 0
    for r0 in range(0, H, NORMAL_BAND_ROWS):
        rows = slice(r0, min(r0 + NORMAL_BAND_ROWS, H))
        n = _convert_normals(nrm[rows], camera, covered[rows], normal_space=normal_space, encoding=encoding,
                             convention=convention, view_frame=view_frame)
        band, c, missing, diff = _check_normals(n, covered[rows], _view_rays(camera, rows), tol)
        out[rows] = band
        counts["renormalized"] += c["renormalized"]
        counts["flipped"] += c["flipped"]
        zero += c["zero"]
        missing_all[rows] = missing
        worst = max(worst, diff)
    k = int(missing_all.sum())
    if k and not repair:
        raise ValueError(f"normal has {k} zero or NaN vector(s) on covered pixels (finite depth): "
                         f"{zero} of length <= {NORMAL_ZERO_TOL:g}, {k - zero} with a NaN or inf component; "
                         "mark those pixels background, or pass repair_normals=True to derive "
                         "their normals from the depth")
    if counts["renormalized"]:
        warnings.warn(f"renormalized {counts['renormalized']} normal(s) of {int(covered.sum())} "
                      f"covered pixels whose length differed from 1 by more than normal_tol={tol:g} "
                      f"(largest difference {worst:.3g})", NormalsRenormalizedWarning, stacklevel=4)
    if k:
        derived, _ = normals_from_depth(camera, depth, covered)
        out[missing_all] = derived[missing_all]
        counts["repaired"] = k
        warnings.warn(f"derived {k} zero or NaN normal(s) of covered pixels from the depth "
                      "(repair_normals=True)", NormalsRepairedWarning, stacklevel=4)
    return out, counts


def _convert_normals(nrm, camera, covered, *, normal_space, encoding, convention, view_frame):
    """The normal image unpacked and in the library's view frame (float64, not normalized)."""
    if nrm.dtype.kind in "iu":
        if encoding != "unit":
            raise ValueError(f"normal is an integer image ({nrm.dtype}): packed normals need "
                             "normal_encoding='unit' (0.5 n + 0.5 scaled to the dtype's range)")
        n = nrm.astype(np.float64) / float(np.iinfo(nrm.dtype).max)
    else:
        n = nrm.astype(np.float64)
    if encoding == "unit":
        n = 2.0 * n - 1.0                      # inverse of the packing 0.5 n + 0.5
    if normal_space == "world":
        if view_frame is not None:
            R = view_frame[0]
        elif getattr(camera, "has_pose", True):
            R = np.asarray(camera.rotation, dtype=np.float64)
        else:
            raise ValueError("normal_space='world' needs the world-to-view rotation: the camera "
                             "has no pose; pass view= (a 4x4 world-to-view matrix) or a camera "
                             "with a pose")
        with np.errstate(invalid="ignore", over="ignore"):
            n = n @ R.T
    elif convention == "opengl":
        n[..., 2] *= -1.0                      # OpenGL eye space: z points backwards
    n[~covered] = 0.0
    return n


def _check_normals(n, covered, rays, tol):
    """One band: renormalize, flag zero/NaN vectors, flip to face the camera.

    Returns (unit normals, zero where missing or uncovered; counts; the missing mask; the
    largest length difference beyond ``tol``)."""
    counts = {"renormalized": 0, "flipped": 0}
    with np.errstate(invalid="ignore", over="ignore"):
        # |n| = s |n / s| with s the largest |component|: finite for any finite vector, where
        # n . n itself would overflow (|n| = 1e200) or underflow
        s = np.max(np.abs(n), axis=-1)
        s = np.where(np.isfinite(s) & (s > 0), s, 1.0)
        m = n / s[..., None]
        length = s * np.sqrt(np.einsum("...i,...i->...", m, m))
    missing = covered & ~(np.isfinite(length) & (length > NORMAL_ZERO_TOL))
    counts["zero"] = int(np.count_nonzero(missing & np.isfinite(length)))
    ok = covered & ~missing
    off = ok & (np.abs(length - 1.0) > tol)
    counts["renormalized"] = int(off.sum())
    worst = float(np.abs(length[off] - 1.0).max()) if counts["renormalized"] else 0.0
    out = np.zeros_like(n)
    out[ok] = n[ok] / length[ok, None]
    # face the camera: n . d < 0 for the pixel's view ray d
    away = ok & (np.einsum("...i,...i->...", out, rays) > 0)
    out[away] *= -1.0
    counts["flipped"] = int(away.sum())
    out += 0.0   # no negative zeros
    return out, counts, missing, worst


def normals_from_depth(camera, depth, covered, *, rays=None) -> tuple[np.ndarray, int]:
    """View-space normals of the covered pixels of a linear depth image, and the number of
    pixels whose normal is undetermined.

    The method of :meth:`GBuffer.derive_normals <vobscure.gbuffer.GBuffer.derive_normals>`
    (see there), on a depth image already checked.

    Parameters
    ----------
    camera : Camera
    depth : (H, W) ndarray of float64
        Linear view depth, used where ``covered``.
    covered : (H, W) ndarray of bool
        The pixels that show a surface.
    rays : (H, W, 3) array_like, optional
        The pixels' view rays (not normalized); default the camera's.

    Returns
    -------
    normals : (H, W, 3) ndarray of float64
        Unit normals with ``n . d < 0``; 0 where not covered.
    undetermined : int
        Covered pixels with no covered neighbour along x or along y, whose normal is set to
        face the camera, ``-d / |d|``.

    Examples
    --------
    >>> import numpy as np, vobscure as vo
    >>> cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(4, 3), ortho_height=2.0)
    >>> covered = np.ones((3, 4), dtype=bool)
    >>> covered[0, 0] = False
    >>> n, undetermined = normals_from_depth(cam, np.full((3, 4), 3.0), covered)
    >>> n[1, 1].tolist(), n[0, 0].tolist(), undetermined
    ([0.0, 0.0, -1.0], [0.0, 0.0, 0.0], 0)
    """
    H, W = depth.shape
    rays = _view_rays(camera) if rays is None else rays
    P = np.full((H, W, 3), np.nan)
    with np.errstate(invalid="ignore", over="ignore"):
        P[covered] = camera.unproject(camera.pixel_centers()[covered], depth[covered])
    # the plane coordinate: affine in the pixel coordinates on any plane
    w = np.full((H, W), np.nan)
    w[covered] = 1.0 / depth[covered] if camera.is_perspective else depth[covered]
    Pp = np.pad(P, ((2, 2), (2, 2), (0, 0)), constant_values=np.nan)
    wp = np.pad(w, 2, constant_values=np.nan)

    def tangent(axis):
        def sh(a, k):   # the neighbour k steps along axis, on the unpadded grid
            idx = [slice(2, 2 + H), slice(2, 2 + W)]
            idx[axis] = slice(2 + k, 2 + k + (H, W)[axis])
            return a[tuple(idx)]
        w0, wm1, wm2, wp1, wp2 = w, sh(wp, -1), sh(wp, -2), sh(wp, 1), sh(wp, 2)
        have_f, have_b = np.isfinite(wp1), np.isfinite(wm1)
        big = np.finfo(np.float64).max
        with np.errstate(invalid="ignore", over="ignore"):
            # one-sided extrapolation errors (unknown when only one neighbour: big)
            e_f = np.where(have_f, np.abs(w0 - (2.0 * wp1 - wp2)), np.inf)
            e_b = np.where(have_b, np.abs(w0 - (2.0 * wm1 - wm2)), np.inf)
            e_f = np.where(have_f & ~np.isfinite(e_f), big, e_f)
            e_b = np.where(have_b & ~np.isfinite(e_b), big, e_b)
            c = np.abs(wp1 - 2.0 * w0 + wm1)
            central = have_f & have_b & (c <= CENTRAL_RATIO * np.minimum(e_f, e_b))
            forward = ~central & have_f & (e_f <= e_b)
            backward = ~central & ~forward & have_b
            # a blend of the backward and forward differences: (1/2, 1/2) central, (0, 1)
            # forward, (1, 0) backward, (0, 0) none (no covered neighbour)
            a = np.where(central, 0.5, np.where(backward, 1.0, 0.0))
            b = np.where(central, 0.5, np.where(forward, 1.0, 0.0))
            P0, Pm, Pf = P, sh(Pp, -1), sh(Pp, 1)
            t = np.empty((3, H, W))
            for c_ in range(3):
                back_ = np.where(a > 0, P0[..., c_] - Pm[..., c_], 0.0)
                fore_ = np.where(b > 0, Pf[..., c_] - P0[..., c_], 0.0)
                t[c_] = a * back_ + b * fore_
        return t, central | forward | backward

    tx, okx = tangent(1)
    ty, oky = tangent(0)
    n = np.stack([tx[1] * ty[2] - tx[2] * ty[1],     # tx x ty, component by component
                  tx[2] * ty[0] - tx[0] * ty[2],
                  tx[0] * ty[1] - tx[1] * ty[0]], axis=-1)
    ok = covered & okx & oky
    with np.errstate(invalid="ignore"):
        length = np.sqrt(np.einsum("...i,...i->...", n, n))
        ok &= length > 0
        out = np.where(ok[..., None], n / np.where(ok, length, 1.0)[..., None], 0.0)
    # no neighbour along an axis: face the camera
    undetermined = covered & ~ok
    d = np.asarray(rays, dtype=np.float64)
    out[undetermined] = -d[undetermined] / np.linalg.norm(d[undetermined], axis=-1, keepdims=True)
    away = ok & (np.einsum("...i,...i->...", out, d) > 0)
    out[away] *= -1.0
    out += 0.0
    return out, int(undetermined.sum())
