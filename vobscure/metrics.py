"""Masked error metrics: error against a reference, its decomposition, temporal flicker.

- :func:`error`: one estimate against one reference (RMSE, MAE, bias, PSNR, SSIM, FLIP).
- :func:`flip`: NVIDIA's FLIP difference evaluator (Andersson et al. 2020) on visibility
  images, its per-pixel map and mean over the compared pixels.
- :func:`decompose`: the error of a screen-space estimate against the ray-cast truth split
  into sampling, screen-space and model error, which add up to the total per pixel.
- :func:`flicker`: the mean absolute frame-to-frame change of an animated estimate, less
  that of its reference, and the mean FLIP between consecutive frames.
- :func:`correlation` and :func:`calibration_rmse`: how well a model's values order and
  predict on average a reference's, point by point.
- :func:`equal_error_rays`: the ray count at which a ray cast's measured error curve
  reaches a given error.
- :func:`thin_feature_mask`: the thin-feature band, the pixels just behind silhouettes where
  screen-space halos live (pass it to :func:`error` as ``mask``).

NaN policy: a pixel that is NaN (or inf) in any input (background, by the library's
convention) is ignored, and the result says how many pixels were ignored.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ._validate import as_array, check_bool, check_int, check_positive

__all__ = ["ErrorReport", "error", "FlipReport", "flip", "FLIP_PPD", "TermSummary", "Decomposition", "decompose",
           "Flicker", "flicker", "correlation", "calibration_rmse", "equal_error_rays", "thin_feature_mask",
           "THIN_JUMP", "THIN_WIDTH"]

#: SSIM's default Gaussian-free window (scikit-image): 7 x 7, shrunk to fit small images.
SSIM_WINDOW = 7
#: FLIP's default observer, in pixels per degree of visual angle: a 0.7 m wide 3840-pixel
#: display seen from 0.7 m (the default of FLIP's reference implementation, 67.02 rounded).
FLIP_PPD = 67.0
#: Equal-count bins of the model's value in :func:`calibration_rmse`.
CALIBRATION_BINS = 10
#: Steepest slope :func:`equal_error_rays` extrapolates with (log RMSE per log rays): a
#: flatter measured curve would send the extrapolated ray count to infinity.
FLATTEST_SLOPE = -1e-3
#: Relative depth jump between adjacent pixels that makes a depth discontinuity in
#: :func:`thin_feature_mask`: the far pixel is more than 10 % deeper. A plane changes its depth
#: by about z / (f tan(grazing angle)) per pixel (f the focal length in pixels), under 10 %
#: unless it is seen within a few degrees of edge-on (at f = 100 px, within about 6 degrees).
THIN_JUMP = 0.1
#: Width (pixels) of the band when neither ``width`` nor ``radius`` is given.
THIN_WIDTH = 8


class _FlatRecord:
    """A dataclass record of scalars, one row of a table."""

    __slots__ = ()

    def as_dict(self) -> dict:
        """The fields by name, in order (a row of a table or CSV file)."""
        return asdict(self)


@dataclass(frozen=True)
class ErrorReport(_FlatRecord):
    """Error of an estimate against a reference over the pixels both define.

    Attributes
    ----------
    rmse, mae, bias, max_abs : float
        Root-mean-square, mean absolute, mean signed (estimate - reference) and largest
        absolute error.
    psnr : float
        10 log10(1 / mse) in dB for data range 1 (inf when the images agree).
    ssim : float
        Mean structural similarity (scikit-image, data_range 1) over the used pixels; NaN
        for inputs that are not 2-D or smaller than 3 x 3.
    flip : float
        Mean FLIP (:func:`flip` at :data:`FLIP_PPD`, values clipped to [0, 1] for it) over
        the used pixels, in [0, 1], 0 when the images agree; NaN for inputs that are not 2-D
        or when it was not asked for (``error(..., flip=False)``).
    pixels : int
        Pixels compared.
    ignored : int
        Pixels skipped because either image is NaN there or the mask excludes them.
    """

    rmse: float
    mae: float
    bias: float
    max_abs: float
    psnr: float
    ssim: float
    flip: float
    pixels: int
    ignored: int


def error(estimate, reference, *, mask=None, flip: bool = True) -> ErrorReport:
    """Compare ``estimate`` with ``reference``.

    Parameters
    ----------
    estimate, reference : array_like, same shape
        Visibility images (or any arrays) with NaN where undefined.
    mask : array_like of bool, optional
        Only pixels where ``mask`` is True are compared.
    flip : bool, keyword-only
        Compute the mean FLIP, by far the costliest metric (on one core about 0.08 s at
        256 x 256 and 1.4 s at 1280 x 720, against 0.007 s and 0.12 s for all the others
        together); False leaves it NaN.

    Returns
    -------
    ErrorReport

    Notes
    -----
    FLIP is :func:`flip` with its defaults (the ignored pixels filled alike in both images).
    SSIM is computed on the full images with the ignored pixels of ``estimate`` replaced by
    the reference (so they add no dissimilarity) and the local SSIM map averaged over the
    compared pixels only, without the border where the window is clipped (as
    scikit-image's mean SSIM does, which this equals when no pixel is ignored). With no pixel to compare every error is NaN and ``pixels`` is 0.

    Examples
    --------
    >>> import numpy as np
    >>> ref = np.full((8, 8), 0.5); est = ref + 0.1; est[0, 0] = np.nan
    >>> r = error(est, ref)
    >>> round(r.rmse, 6), round(r.bias, 6), r.pixels, r.ignored
    (0.1, 0.1, 63, 1)
    """
    flip = check_bool(flip, "flip")
    est = as_array(estimate, "estimate", finite=False)
    ref = as_array(reference, "reference", finite=False)
    if est.shape != ref.shape:
        raise ValueError(f"estimate and reference must have the same shape, got {est.shape} and {ref.shape}")
    use = np.isfinite(est) & np.isfinite(ref)
    if mask is not None:
        m = np.asarray(mask)
        if m.shape != est.shape:
            raise ValueError(f"mask must have the shape of the images {est.shape}, got {m.shape}")
        if m.dtype != bool:
            raise ValueError(f"mask must be a boolean array, got dtype {m.dtype}")
        use &= m
    n = int(use.sum())
    ignored = int(est.size - n)
    if n == 0:
        nan = float("nan")
        return ErrorReport(nan, nan, nan, nan, nan, nan, nan, 0, ignored)
    diff = est[use] - ref[use]
    mse = float(np.mean(diff * diff))
    psnr = float("inf") if mse == 0 else float(10.0 * np.log10(1.0 / mse))
    return ErrorReport(rmse=float(np.sqrt(mse)), mae=float(np.mean(np.abs(diff))),
                       bias=float(np.mean(diff)), max_abs=float(np.max(np.abs(diff))), psnr=psnr,
                       ssim=_masked_ssim(est, ref, use),
                       flip=_flip_map(est, ref, use, FLIP_PPD)[1] if flip and est.ndim == 2 else float("nan"),
                       pixels=n, ignored=ignored)


def _masked_ssim(est, ref, use) -> float:
    if est.ndim != 2 or min(est.shape) < 3:
        return float("nan")
    from skimage.metrics import structural_similarity

    win = min(SSIM_WINDOW, min(est.shape) if min(est.shape) % 2 else min(est.shape) - 1)
    ref_f = np.where(use, ref, 0.0)
    est_f = np.where(use, est, ref_f)
    _, smap = structural_similarity(est_f, ref_f, data_range=1.0, win_size=win, full=True)
    # like scikit-image's mean SSIM, leave out the border where the window is clipped
    pad = (win - 1) // 2
    inner = np.zeros_like(use)
    inner[pad:use.shape[0] - pad, pad:use.shape[1] - pad] = True
    inner &= use
    return float(np.mean(smap[inner])) if inner.any() else float("nan")


# ----------------------------------------------------------------------------- FLIP
@dataclass(frozen=True, eq=False)
class FlipReport:
    """FLIP of an estimate against a reference (see :func:`flip`).

    Attributes
    ----------
    mean : float
        Mean FLIP over the compared pixels, in [0, 1] (0: the images agree); NaN when no
        pixel is compared.
    map : (H, W) float32 ndarray
        FLIP per pixel, NaN where not compared.
    pixels : int
        Pixels compared: finite in both images and inside the mask.
    ignored : int
        The other pixels.
    clipped : int
        Compared pixels where the estimate or the reference lay outside [0, 1] and was
        clipped for FLIP.
    ppd : float
        The observer's pixels per degree the map was computed for.
    """

    mean: float
    map: np.ndarray
    pixels: int
    ignored: int
    clipped: int
    ppd: float

    def as_dict(self) -> dict:
        """The scalars by name, without the map (a row of a table)."""
        return {"mean": self.mean, "pixels": self.pixels, "ignored": self.ignored,
                "clipped": self.clipped, "ppd": self.ppd}


def flip(estimate, reference, *, mask=None, ppd: float = FLIP_PPD) -> FlipReport:
    """NVIDIA's FLIP difference between a visibility estimate and its reference.

    FLIP estimates what a viewer alternating between the two images on a display would
    notice. Both images are filtered by the eye's contrast sensitivity at the viewing
    distance that ``ppd`` stands for and compared in a perceptual colour space (the HyAB
    distance of Hunt-adjusted CIELAB colours, remapped to [0, 1]; Andersson et al. 2020,
    Sec. 4.1); the colour error is then raised where edges and points differ (Sec. 4).

    Parameters
    ----------
    estimate, reference : (H, W) array_like
        Visibility images, nominally in [0, 1], NaN where undefined (background).
    mask : (H, W) bool array_like, optional
        Only pixels where ``mask`` is True are compared.
    ppd : float, keyword-only
        The observer's pixels per degree of visual angle, > 0 (default :data:`FLIP_PPD`). It
        sets the filters' width in pixels: a larger ppd (a farther viewer or a denser display)
        blurs more and hides finer noise.

    Returns
    -------
    FlipReport

    Notes
    -----
    **Linear light.** Visibility multiplies linear lighting, so each image is passed as the
    linear RGB grey that a white surface under uniform light would have (``inputsRGB=False``:
    FLIP converts linear RGB to its colour spaces and decodes nothing). Passing the values as
    sRGB-encoded (FLIP's LDR default) would score the raw buffer as a display shows it, where
    differences between dark values count less than here: the creases, where AO matters,
    would weigh less.

    **Background.** FLIP's filters are spatial, so undefined pixels cannot be left out of the
    call: every pixel not compared (undefined in either image, or outside the mask) is set to
    the same value in both images, the reference's where it is finite and 1 (open)
    elsewhere, so that it adds no difference of its own. It still enters its neighbours'
    filters: a compared pixel within the filters' radius of it (10 pixels at 67 ppd: three
    standard deviations of the widest contrast-sensitivity Gaussian) is scored in a context
    that the images do not hold there. The mean is over the compared pixels only.

    **Range.** FLIP's LDR mode takes values in [0, 1] and some estimators overshoot: both
    images are clipped to [0, 1] for FLIP only, and ``clipped`` counts the compared pixels
    where that changed a value.

    FLIP is computed by the ``flip-evaluator`` package (NVIDIA, BSD-3), in float32, with the
    images' borders extended by their edge pixels. The score is symmetric in the two images.

    References
    ----------
    P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström and M. D. Fairchild,
    "FLIP: A Difference Evaluator for Alternating Images", Proc. ACM Comput. Graph. Interact.
    Tech. 3(2) (HPG 2020), Sec. 4.

    Examples
    --------
    >>> import numpy as np
    >>> ref = np.full((8, 8), 0.5); est = ref.copy(); est[:, :4] = np.nan
    >>> f = flip(est, ref)
    >>> f.mean, f.pixels, f.ignored, f.map.shape
    (0.0, 32, 32, (8, 8))
    >>> round(flip(np.full((8, 8), 0.6), ref).mean, 4)      # a uniform offset: colour alone
    0.1963
    """
    est = as_array(estimate, "estimate", finite=False)
    ref = as_array(reference, "reference", finite=False)
    if est.ndim != 2:
        raise ValueError(f"estimate must be an (H, W) image, got shape {est.shape}")
    if est.shape != ref.shape:
        raise ValueError(f"estimate and reference must have the same shape, got {est.shape} and {ref.shape}")
    ppd = check_positive(ppd, "ppd")
    use = np.isfinite(est) & np.isfinite(ref)
    if mask is not None:
        use &= _bool_mask(mask, (est.shape,), "the images")
    fmap, mean, clipped = _flip_map(est, ref, use, ppd)
    n = int(np.count_nonzero(use))
    return FlipReport(mean=mean, map=fmap, pixels=n, ignored=int(use.size - n), clipped=clipped, ppd=ppd)


def _flip_map(est, ref, use, ppd) -> tuple[np.ndarray, float, int]:
    """FLIP's (H, W) float32 map (NaN off ``use``), its mean over ``use`` and the clipped count."""
    fmap = np.full(est.shape, np.nan, dtype=np.float32)
    if not use.any():
        return fmap, float("nan"), 0
    import flip_evaluator

    # the pixels not compared: the same value in both images (the reference's, or open)
    fill = np.where(np.isfinite(ref), ref, 1.0)
    ref_f = np.clip(np.where(use, ref, fill), 0.0, 1.0)
    est_f = np.clip(np.where(use, est, fill), 0.0, 1.0)
    clipped = int(np.count_nonzero(use & ((ref_f != ref) | (est_f != est))))

    def rgb(a):     # a new C-ordered (H, W, 3) float32 grey: FLIP may write into its input
        return np.repeat(a.astype(np.float32)[..., None], 3, axis=2)

    out = flip_evaluator.evaluate(rgb(ref_f), rgb(est_f), "LDR", inputsRGB=False, applyMagma=False,
                                  computeMeanError=False, parameters={"ppd": float(ppd)})[0]
    out = np.asarray(out, dtype=np.float32).reshape(est.shape)
    fmap[use] = out[use]
    return fmap, float(np.mean(out[use], dtype=np.float64)), clipped


# ----------------------------------------------------------------------------- decomposition
@dataclass(frozen=True)
class TermSummary:
    """Summary of one error map over the pixels it was measured on.

    Attributes
    ----------
    rmse : float
        Root-mean-square of the map.
    bias : float
        Its mean (signed).
    mae : float
        Its mean absolute value.
    """

    rmse: float
    bias: float
    mae: float

    @classmethod
    def of(cls, diff: np.ndarray) -> "TermSummary":
        """The summary of the 1-D float64 array ``diff`` (NaN for an empty one)."""
        if diff.size == 0:
            nan = float("nan")
            return cls(nan, nan, nan)
        return cls(rmse=float(np.sqrt(np.mean(diff * diff))), bias=float(np.mean(diff)),
                   mae=float(np.mean(np.abs(diff))))


#: Terms of a :class:`Decomposition`, in the order of the telescoping sum (then the extras).
DECOMPOSITION_TERMS = ("sampling", "screen", "model", "total", "model_obscurance")


@dataclass(frozen=True, eq=False)
class Decomposition:
    """The error of an estimate split into the steps that cause it (see :func:`decompose`).

    Every map is (H, W) float64, NaN on the ignored pixels (the same pixels for all maps).

    Attributes
    ----------
    sampling : ndarray
        estimate - screen_reference: what the estimator's finite sampling adds to the
        converged screen-space VO.
    screen : ndarray
        screen_reference - world_vo: what the screen-space model itself gets wrong (nothing
        is known behind the depth buffer, nothing outside the image).
    model : ndarray or None
        world_vo - ao: how far Volumetric Obscurance, even exact, is from ambient
        occlusion. None when no ``ao`` was given.
    total : ndarray
        sampling + screen + model (+ model only when ``ao`` was given): the estimate's error
        against ``target``. The sum holds exactly, bit for bit, per pixel; it equals
        ``estimate - ao`` (or ``estimate - world_vo``) up to float64 rounding.
    model_obscurance : ndarray or None
        world_vo - obscurance, when ``obscurance`` was given (outside the sum).
    target : {"ao", "volumetric"}
        What ``total`` is measured against.
    summary : dict of str to TermSummary
        rmse, bias and mae of every map present, keyed by the attribute names above.
    pixels : int
        Pixels used: finite in every input and inside the mask.
    ignored : int
        The other pixels.
    undefined : dict of str to int
        NaN or inf pixels per input (an ignored pixel may be counted under several inputs;
        the remaining ignored pixels were excluded by the mask).
    """

    sampling: np.ndarray
    screen: np.ndarray
    model: np.ndarray | None
    total: np.ndarray
    model_obscurance: np.ndarray | None
    target: str
    summary: dict
    pixels: int
    ignored: int
    undefined: dict

    def as_dict(self) -> dict:
        """Flat summary: ``<term>_rmse``, ``<term>_bias``, ``<term>_mae`` for every term
        present, then ``target``, ``pixels`` and ``ignored`` (for tables and CSV files)."""
        out = {}
        for term in DECOMPOSITION_TERMS:
            if term in self.summary:
                for stat, v in asdict(self.summary[term]).items():
                    out[f"{term}_{stat}"] = v
        out.update(target=self.target, pixels=self.pixels, ignored=self.ignored)
        return out


def _image(value, name: str, shape=None) -> np.ndarray:
    """A float64 array (an Estimate's value is accepted), NaN allowed, of ``shape`` if given."""
    from .estimate import Estimate

    if isinstance(value, Estimate):
        value = value.value
    arr = as_array(value, name, finite=False)
    if shape is not None and arr.shape != shape:
        raise ValueError(f"{name} must have the shape of estimate {shape}, got {arr.shape}")
    return arr


def _bool_mask(mask, shapes: tuple, what: str) -> np.ndarray:
    m = np.asarray(mask)
    if m.shape not in shapes:
        want = " or ".join(str(s) for s in shapes)
        raise ValueError(f"mask must have the shape of {what} {want}, got {m.shape}")
    if m.dtype != bool:
        raise ValueError(f"mask must be a boolean array, got dtype {m.dtype}")
    return m


def decompose(estimate, screen_reference, world_vo, *, ao=None, obscurance=None,
              mask=None) -> Decomposition:
    """Split an estimate's error into sampling, screen-space and model error.

    The error of a screen-space estimate E against ray-cast ambient occlusion A telescopes
    through the converged screen-space VO S and the world-space VO W::

        E - A = (E - S) + (S - W) + (W - A)
              = sampling + screen-space + model error

    which tells *why* an estimate is off: too few samples, the depth buffer's missing
    information, or the choice of VO as a stand-in for AO.

    Parameters
    ----------
    estimate : (H, W) array_like
        The estimator's visibility (e.g. :func:`vobscure.vo_line`), NaN on background.
    screen_reference : (H, W) array_like or Estimate
        The converged screen-space VO with the estimator's settings
        (:func:`vobscure.vo_reference`).
    world_vo : (H, W) array_like or Estimate
        The world-space VO (``vobscure.ground_truth(..., quantity="volumetric")``).
    ao : (H, W) array_like or Estimate, optional
        Ray-cast AO (``quantity="ao"``); when given, ``total`` is measured against it and the
        model term is W - A. Otherwise ``total`` is measured against ``world_vo``.
    obscurance : (H, W) array_like or Estimate, optional
        Ray-cast obscurance; adds the map ``model_obscurance`` = W - obscurance (reported
        beside the sum, not in it).
    mask : (H, W) bool array_like, optional
        Only pixels where ``mask`` is True are used.

    Returns
    -------
    Decomposition

    Notes
    -----
    A pixel is used when it is finite in every given input and inside the mask; all maps are
    NaN elsewhere, so every summary is taken over the same pixels and the summed biases
    also add up (to rounding). The terms are the plain float64 differences of the inputs;
    ``total`` is their sum, so that the identity sampling + screen + model == total holds
    exactly per pixel (it differs from ``estimate - ao`` by float64 rounding only).

    Examples
    --------
    >>> import numpy as np
    >>> E = np.array([[0.6, np.nan]]); S = np.array([[0.5, 0.5]])
    >>> W = np.array([[0.45, 0.5]]); A = np.array([[0.7, 0.7]])
    >>> d = decompose(E, S, W, ao=A)
    >>> [round(float(t[0, 0]), 6) for t in (d.sampling, d.screen, d.model, d.total)]
    [0.1, 0.05, -0.25, -0.1]
    >>> d.pixels, d.ignored, d.undefined["estimate"], bool(np.isnan(d.total[0, 1]))
    (1, 1, 1, True)
    """
    E = _image(estimate, "estimate")
    shape = E.shape
    inputs = {"estimate": E,
              "screen_reference": _image(screen_reference, "screen_reference", shape),
              "world_vo": _image(world_vo, "world_vo", shape)}
    if ao is not None:
        inputs["ao"] = _image(ao, "ao", shape)
    if obscurance is not None:
        inputs["obscurance"] = _image(obscurance, "obscurance", shape)
    undefined = {name: int(np.count_nonzero(~np.isfinite(a))) for name, a in inputs.items()}
    use = np.logical_and.reduce([np.isfinite(a) for a in inputs.values()])
    if mask is not None:
        use &= _bool_mask(mask, (shape,), "the images")
    S, W = inputs["screen_reference"], inputs["world_vo"]

    def diff(a, b):
        out = np.full(shape, np.nan)
        np.subtract(a, b, out=out, where=use)
        return out

    maps = {"sampling": diff(E, S), "screen": diff(S, W)}
    total = maps["sampling"] + maps["screen"]
    if ao is not None:
        maps["model"] = diff(W, inputs["ao"])
        total = total + maps["model"]
    maps["total"] = total
    if obscurance is not None:
        maps["model_obscurance"] = diff(W, inputs["obscurance"])
    summary = {term: TermSummary.of(m[use]) for term, m in maps.items()}
    pixels = int(np.count_nonzero(use))
    return Decomposition(sampling=maps["sampling"], screen=maps["screen"], model=maps.get("model"),
                         total=total, model_obscurance=maps.get("model_obscurance"),
                         target="ao" if ao is not None else "volumetric", summary=summary,
                         pixels=pixels, ignored=int(use.size - pixels), undefined=undefined)


# ----------------------------------------------------------------------------- flicker
@dataclass(frozen=True)
class Flicker(_FlatRecord):
    """Temporal instability of an animated estimate (see :func:`flicker`).

    Attributes
    ----------
    value : float
        ``estimate_change - reference_change`` (``estimate_change`` when no reference was
        given): the frame-to-frame change the estimator adds.
    estimate_change : float
        Mean absolute frame-to-frame change of the estimate.
    reference_change : float
        The same for the reference frames over the same pixels; NaN without reference.
    estimate_flip : float
        Mean FLIP (:func:`flip` at :data:`FLIP_PPD`) of every frame against the frame before
        it, over the same pixels: how visible the change is. NaN for frames that are not
        (H, W) images or when not asked for.
    reference_flip : float
        The same for the reference frames (the scene's real change seen by the same
        observer); NaN without reference. FLIP does not add up, so the two are reported side
        by side rather than subtracted.
    pairs : int
        (frame pair, pixel) entries averaged over.
    ignored : int
        Entries skipped: undefined in either frame of the pair (or either reference frame)
        or outside the mask.
    """

    value: float
    estimate_change: float
    reference_change: float
    estimate_flip: float
    reference_flip: float
    pairs: int
    ignored: int


def flicker(frames, reference_frames=None, *, mask=None, flip: bool = True) -> Flicker:
    """Mean absolute frame-to-frame change of an estimate, less that of its reference.

    For frames V_0 ... V_{T-1} (e.g. a camera orbit) the change is the mean of
    ``|V_{t+1}(p) - V_t(p)|`` over every consecutive pair t and every pixel p defined in both
    frames. Part of that change is real (the camera moves, so a pixel sees another surface
    point): the same mean over ``reference_frames`` (a converged reference of the same
    frames), taken over the same pixels, is subtracted, so that what remains is the flicker
    the estimator adds (noise that is not stable under motion, aliasing of its samples).
    Beside it, the mean :func:`flip` of every frame against the frame before (frame t - 1 as
    FLIP's reference of frame t) says how visible that change is, for the estimate and for the
    reference.

    Parameters
    ----------
    frames : (T, H, W) array_like
        T >= 2 frames of visibility (any trailing shape), NaN where undefined.
    reference_frames : (T, H, W) array_like, optional
        The reference for the same frames.
    mask : (H, W) or (T, H, W) bool array_like, optional
        Pixels to use, for all frames or per frame (a pair uses a pixel when both of its
        frames do).
    flip : bool, keyword-only
        Compute ``estimate_flip`` and ``reference_flip`` (one FLIP call per frame pair and
        sequence, see :func:`error` for its cost); False leaves them NaN.

    Returns
    -------
    Flicker

    Examples
    --------
    >>> import numpy as np
    >>> base = np.full((4, 2, 2), 0.5)
    >>> noisy = base + 0.1 * np.array([1, -1, 1, -1])[:, None, None]
    >>> f = flicker(noisy, base)
    >>> round(f.value, 12), round(f.estimate_change, 12), f.reference_change, f.pairs
    (0.2, 0.2, 0.0, 12)
    >>> f.reference_flip, f.estimate_flip > 0
    (0.0, True)
    """
    flip = check_bool(flip, "flip")
    V = _image(frames, "frames")
    if V.ndim < 2 or V.shape[0] < 2:
        raise ValueError(f"frames must be a sequence of at least 2 frames (T, H, W), got shape {V.shape}")
    use = np.isfinite(V[1:]) & np.isfinite(V[:-1])
    R = None
    if reference_frames is not None:
        R = _image(reference_frames, "reference_frames")
        if R.shape != V.shape:
            raise ValueError(f"reference_frames must have the shape of frames {V.shape}, got {R.shape}")
        use &= np.isfinite(R[1:]) & np.isfinite(R[:-1])
    if mask is not None:
        m = _bool_mask(mask, (V.shape[1:], V.shape), "a frame or of frames")
        use &= (m[1:] & m[:-1]) if m.shape == V.shape else m
    n = int(np.count_nonzero(use))
    ignored = int(use.size - n)
    nan = float("nan")
    if n == 0:
        return Flicker(nan, nan, nan, nan, nan, 0, ignored)
    est = float(np.mean(np.abs(V[1:][use] - V[:-1][use])))
    ref = float(np.mean(np.abs(R[1:][use] - R[:-1][use]))) if R is not None else nan
    pair_flip = flip and V.ndim == 3
    return Flicker(value=est - ref if R is not None else est, estimate_change=est, reference_change=ref,
                   estimate_flip=_pair_flip(V, use, n) if pair_flip else nan,
                   reference_flip=_pair_flip(R, use, n) if pair_flip and R is not None else nan,
                   pairs=n, ignored=ignored)


def _pair_flip(frames, use, n) -> float:
    """Mean FLIP of every frame against the one before, pooled over the pairs' ``n`` pixels."""
    total = 0.0
    for t in range(1, len(frames)):
        fmap, _, _ = _flip_map(frames[t], frames[t - 1], use[t - 1], FLIP_PPD)
        total += float(np.sum(fmap[use[t - 1]], dtype=np.float64))
    return total / n


# ----------------------------------------------------------------------------- point models
def _finite_pairs(a, b, names: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
    x = as_array(a, names[0], shape=(None,), finite=False)
    y = as_array(b, names[1], shape=(x.shape[0],), finite=False)
    use = np.isfinite(x) & np.isfinite(y)
    return x[use], y[use]


def correlation(model, reference) -> float:
    """Pearson's correlation coefficient r of a model's values and a reference's.

    Parameters
    ----------
    model, reference : (n,) array_like
        Values at the same n points; a pair with NaN (or inf) in either is ignored.

    Returns
    -------
    float
        r in [-1, 1]; NaN where it is undefined: fewer than 3 pairs, or either side constant
        (a model with no parameter effect, e.g. visibility 1 everywhere).

    Examples
    --------
    >>> round(correlation([0.1, 0.4, 0.5, 0.9], [0.2, 0.5, 0.4, 1.0]), 6)
    0.955975
    >>> correlation([1.0, 1.0, 1.0], [0.2, 0.5, 0.4])
    nan
    """
    a, b = _finite_pairs(model, reference, ("model", "reference"))
    if len(a) < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:      # a constant side: r is 0 / 0
        return float("nan")
    return float(np.corrcoef(a, b)[0, 1])


def calibration_rmse(model, reference, *, bins: int = CALIBRATION_BINS) -> float:
    r"""The error of a model as a predictor of the *average* reference value of the points it
    gives about one value.

    The points are sorted by the model's value and split into ``bins`` groups of equal count
    (``numpy.array_split``; the first groups one larger); the result is the RMSE of the
    groups' model means against their reference means, each group weighted by its count:
    :math:`\sqrt{\sum_g n_g (\bar m_g - \bar r_g)^2 / n}`. It leaves out the
    point-to-point scatter that no function of the model's inputs can follow (for a canopy
    model: Hegeman's ensemble mean :math:`\langle V \rangle`, Sec. 3), so it never exceeds
    the RMSE (Cauchy-Schwarz, group by group).

    Parameters
    ----------
    model, reference : (n,) array_like
        Values at the same n points; a pair with NaN (or inf) in either is ignored.
    bins : int, keyword-only
        Number of groups (at most the number of points), >= 1.

    Returns
    -------
    float
        >= 0; NaN when no pair is finite.

    Examples
    --------
    >>> m, r = [1.0, 2.0, 5.0, 6.0], [2.0, 1.0, 6.0, 5.0]
    >>> calibration_rmse(m, r, bins=2)     # bin means 1.5 and 5.5 on both sides
    0.0
    >>> calibration_rmse(m, r, bins=4)     # one point a bin: the RMSE
    1.0
    """
    bins = check_int(bins, "bins")
    model, t = _finite_pairs(model, reference, ("model", "reference"))
    if len(model) == 0:
        return float("nan")
    order = np.argsort(model, kind="stable")
    groups = np.array_split(order, min(bins, len(order)))
    sq = sum(len(g) * (model[g].mean() - t[g].mean()) ** 2 for g in groups if len(g))
    return float(np.sqrt(sq / len(model)))


# ----------------------------------------------------------------------------- ray counts
def equal_error_rays(rays, rmse, target) -> tuple[float, bool]:
    """Rays per point at which the ray cast's RMSE equals ``target``, by linear interpolation of
    log RMSE against log rays.

    The measured RMSE is made non-increasing first (a running minimum), so the answer is
    monotone (non-increasing) in ``target``. Outside the measured range the line through the
    nearer end point, with the slope fitted to all points (least squares in log-log, at most
    ``FLATTEST_SLOPE``), is extrapolated; a curve with no change at all extrapolates with
    the Monte Carlo slope -1/2.

    Parameters
    ----------
    rays : sequence of int
        Increasing ray counts.
    rmse : sequence of float
        The ray cast's RMSE at each count (> 0).
    target : float
        The RMSE to match (> 0).

    Returns
    -------
    rays : float
        The equal-error ray count (not rounded).
    extrapolated : bool
        Whether ``target`` lay outside the measured RMSE range.

    Raises
    ------
    ValueError
        Fewer than two counts, counts not increasing, one RMSE per count missing, or an RMSE
        or ``target`` that is not positive.

    Examples
    --------
    >>> rays, extrapolated = equal_error_rays([4, 16, 64], [0.2, 0.1, 0.05], 0.1)
    >>> round(rays, 6), extrapolated
    (16.0, False)
    >>> rays, extrapolated = equal_error_rays([4, 16], [0.2, 0.1], 0.05)   # slope -1/2 extended
    >>> round(rays, 6), extrapolated
    (64.0, True)
    """
    r = np.asarray(rays, dtype=np.float64)
    e = np.minimum.accumulate(np.asarray(rmse, dtype=np.float64))
    if r.ndim != 1 or len(r) < 2 or len(e) != len(r) or np.any(np.diff(r) <= 0):
        raise ValueError("rays must be at least two increasing counts, one RMSE each")
    if not np.all(e > 0) or not target > 0:
        raise ValueError("RMSE values and target must be positive")
    lr, le, lt = np.log(r), np.log(e), math.log(float(target))
    slope = float(np.polyfit(lr, le, 1)[0]) if np.ptp(le) > 0 else -0.5
    slope = min(slope, FLATTEST_SLOPE)
    if lt > le[0]:
        return float(math.exp(lr[0] + (lt - le[0]) / slope)), True
    if lt < le[-1]:
        return float(math.exp(lr[-1] + (lt - le[-1]) / slope)), True
    # le is non-increasing: interpolate on the reversed (non-decreasing) arrays
    return float(math.exp(np.interp(lt, le[::-1], lr[::-1]))), False


def thin_feature_mask(gbuffer, *, radius=None, width=None, jump: float = THIN_JUMP) -> np.ndarray:
    """The thin-feature band: covered pixels on the far side of a depth discontinuity, within
    ``width`` pixels of the nearer surface's silhouette.

    This is where a screen-space estimator that takes every surface as infinitely thick draws
    its halo: the taps of a pixel behind a silhouette land on the nearer object and count the
    space behind it as solid. ``error(estimate, reference, mask=thin_feature_mask(gb, radius=R))``
    is the error there, beside the whole frame's.

    Parameters
    ----------
    gbuffer : GBuffer or (H, W) array_like of float
        A G-buffer, or a linear depth image (+inf or NaN on background; then give ``width``).
    radius : float, optional
        The ball's world radius: each pixel's width is its projected radius, rounded up
        (``ceil(R fy / z)`` in perspective, ``ceil(R fy)`` orthographic): the band holds the
        pixels whose taps reach a nearer silhouette. Needs a G-buffer (its camera).
    width : int, optional
        The same width for every pixel (>= 1). Give ``radius`` or ``width``, not both;
        neither: :data:`THIN_WIDTH`.
    jump : float, optional
        The relative depth jump that makes a discontinuity, > 0 (default :data:`THIN_JUMP`).

    Returns
    -------
    (H, W) bool ndarray
        Of the inner frame when the G-buffer has a guard band (the band is found on the whole
        rendered frame, so silhouettes in the guard band count).

    Notes
    -----
    The rule, with z the depth and distances in pixels along the Chebyshev (chessboard) metric:

    1. A covered pixel q is on the near side of a silhouette when one of its 8 neighbours is
       covered by a surface more than ``jump`` deeper, ``z_n > (1 + jump) z_q``, or is background.
    2. A covered pixel p is in the band when some near-side pixel q lies within p's width
       and p is deeper than it by more than the jump, ``z_p > (1 + jump) z_q``.

    So the band lies behind the silhouette only (never on the near object), is ``width`` pixels
    wide across a straight edge, and is empty on any surface whose depth changes by less than
    the jump from pixel to pixel (a plane not seen nearly edge-on, see :data:`THIN_JUMP`).
    Background never belongs to the band. Step 2 runs one 3 x 3 minimum filter per pixel of
    the widest width, O(max width x H x W).

    Examples
    --------
    >>> import numpy as np
    >>> depth = np.full((4, 8), 5.0); depth[:, :3] = 2.0      # a near object on the left
    >>> thin_feature_mask(depth, width=2).astype(int)
    array([[0, 0, 0, 1, 1, 0, 0, 0],
           [0, 0, 0, 1, 1, 0, 0, 0],
           [0, 0, 0, 1, 1, 0, 0, 0],
           [0, 0, 0, 1, 1, 0, 0, 0]])
    """
    from scipy.ndimage import minimum_filter

    from .gbuffer import GBuffer

    jump = float(jump)
    if not (math.isfinite(jump) and jump > 0):
        raise ValueError(f"jump must be a finite number > 0, got {jump!r}")
    if radius is not None and width is not None:
        raise ValueError("give radius (a width per pixel from the ball) or width (pixels), not both")
    gb = gbuffer if isinstance(gbuffer, GBuffer) else None
    z = np.array(gb.depth if gb is not None else as_array(gbuffer, "gbuffer", finite=False), dtype=np.float64)
    if z.ndim != 2:
        raise ValueError(f"gbuffer must be a GBuffer or an (H, W) depth image, got shape {z.shape}")
    covered = np.isfinite(z) & (z > 0)
    z[~covered] = np.inf
    if radius is not None:
        if gb is None:
            raise ValueError("radius needs a GBuffer (its camera projects the radius); give width for a depth image")
        R = float(radius)
        if not (math.isfinite(R) and R > 0):
            raise ValueError(f"radius must be a finite number > 0, got {radius!r}")
        cam = gb.camera
        with np.errstate(divide="ignore"):
            px = R * cam.fy / z if cam.is_perspective else np.full(z.shape, R * cam.fy)
        w = np.where(covered, np.ceil(px), 0.0)
    else:
        w = np.where(covered, float(THIN_WIDTH if width is None else check_int(width, "width")), 0.0)
    threshold = 1.0 + jump
    # step 1: near-side pixels (a deeper or empty 8-neighbour); the image's outside is not a neighbour
    deepest = -minimum_filter(-z, size=3, mode="nearest")
    near = np.where(covered & (deepest > threshold * z), z, np.inf)
    # step 2: grow the near depths one ring (Chebyshev) at a time, up to each pixel's width
    band = np.zeros(z.shape, dtype=bool)
    reach = near
    for r in range(1, int(min(w.max(initial=0.0), max(z.shape))) + 1):   # no farther than the image
        reach = minimum_filter(reach, size=3, mode="constant", cval=np.inf)
        band |= (w >= r) & (z > threshold * reach)
    band &= covered
    g = gb.guard if gb is not None else 0
    return band[g:z.shape[0] - g, g:z.shape[1] - g] if g else band
