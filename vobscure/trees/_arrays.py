"""Array helpers shared by the tree models: raw (n, 3) inputs checked per chunk, the check of
the normals' lengths, and the output dtype rule (float32 in, float32 out)."""

from __future__ import annotations

import numpy as np

__all__ = ["as_raw_points", "check_normal_lengths", "out_dtype", "ZERO_NORMAL"]

#: Normals shorter than this are rejected (they have no direction).
ZERO_NORMAL = 1e-12


def as_raw_points(value, name: str) -> np.ndarray:
    """(n, 3) numeric array without a copy (converted and checked for finiteness per chunk by
    the caller); a single (3,) point is one row."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array: {exc}") from None
    if arr.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be a numeric array, got dtype {arr.dtype}")
    if arr.shape == (3,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {arr.shape}")
    return arr


def check_normal_lengths(mm: np.ndarray, normals: np.ndarray | None = None) -> None:
    """Reject normals from their (k,) squared lengths ``mm``: a non-finite one (a NaN or inf
    coordinate makes it non-finite) or one shorter than :data:`ZERO_NORMAL`. The message
    counts the NaN or inf values of ``normals`` when they are given, else the rows."""
    if not np.all(np.isfinite(mm)):
        if normals is None:
            raise ValueError(f"normals must be finite; they hold {int(np.count_nonzero(~np.isfinite(mm)))} "
                             f"NaN or inf row(s)")
        raise ValueError(f"normals must be finite; they hold {int(np.count_nonzero(~np.isfinite(normals)))} "
                         f"NaN or inf value(s)")
    if np.any(mm < ZERO_NORMAL ** 2):
        raise ValueError(f"normals hold {int(np.count_nonzero(mm < ZERO_NORMAL ** 2))} zero-length vector(s); "
                         f"every normal needs a length")


def out_dtype(*arrays) -> type:
    """float32 when every array input is float32 (or narrower float), else float64; inputs
    that are not arrays (Python scalars) do not count."""
    arrays = [a for a in arrays if isinstance(a, np.ndarray)]
    if arrays and all(a.dtype.kind == "f" and a.dtype.itemsize <= 4 for a in arrays):
        return np.float32
    return np.float64
