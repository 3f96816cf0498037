"""Array helpers shared by the tree models: raw (n, 3) inputs checked per chunk, and the
output dtype rule (float32 in, float32 out)."""

from __future__ import annotations

import numpy as np

__all__ = ["as_raw_points", "out_dtype"]


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


def out_dtype(*arrays) -> type:
    """float32 when every array input is float32 (or narrower float), else float64; inputs
    that are not arrays (Python scalars) do not count."""
    arrays = [a for a in arrays if isinstance(a, np.ndarray)]
    if arrays and all(a.dtype.kind == "f" and a.dtype.itemsize <= 4 for a in arrays):
        return np.float32
    return np.float64
