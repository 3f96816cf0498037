"""Masked error metrics between a visibility image and its reference.

NaN policy: a pixel that is NaN in either image (background, by the library's convention)
is ignored, and the result says how many pixels were ignored.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ._validate import as_array

__all__ = ["ErrorReport", "error"]

#: SSIM's default Gaussian-free window (scikit-image): 7 x 7, shrunk to fit small images.
SSIM_WINDOW = 7


@dataclass(frozen=True)
class ErrorReport:
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
    pixels: int
    ignored: int

    def as_dict(self) -> dict:
        return asdict(self)


def error(estimate, reference, *, mask=None) -> ErrorReport:
    """Compare ``estimate`` with ``reference``.

    Parameters
    ----------
    estimate, reference : array_like, same shape
        Visibility images (or any arrays) with NaN where undefined.
    mask : array_like of bool, optional
        Only pixels where ``mask`` is True are compared.

    Returns
    -------
    ErrorReport

    Notes
    -----
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
        return ErrorReport(nan, nan, nan, nan, nan, nan, 0, ignored)
    diff = est[use] - ref[use]
    mse = float(np.mean(diff * diff))
    psnr = float("inf") if mse == 0 else float(10.0 * np.log10(1.0 / mse))
    return ErrorReport(rmse=float(np.sqrt(mse)), mae=float(np.mean(np.abs(diff))),
                       bias=float(np.mean(diff)), max_abs=float(np.max(np.abs(diff))), psnr=psnr,
                       ssim=_masked_ssim(est, ref, use), pixels=n, ignored=ignored)


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
