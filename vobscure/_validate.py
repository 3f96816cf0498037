"""Argument checks shared by every public function.

Every check names the argument it rejects and says what was expected, so that a bad call
fails with a sentence, never with a raw NumPy traceback from deep inside an estimator.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable

import numpy as np

__all__ = [
    "as_array",
    "as_numeric",
    "as_points",
    "as_unit_vectors",
    "as_rng",
    "check_bool",
    "check_choice",
    "check_positive",
    "check_int",
]


def as_array(value, name: str, *, shape=None, dtype=np.float64, finite: bool = True) -> np.ndarray:
    """Convert ``value`` to an array and check its shape and finiteness.

    ``shape`` is a tuple whose entries are ints (exact) or None (any length); a leading
    ``...`` entry allows any number of leading dimensions.
    """
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array, got {type(value).__name__}: {exc}") from None
    if shape is not None:
        _check_shape(arr, name, shape)
    if finite and arr.dtype.kind == "f" and not np.all(np.isfinite(arr)):
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        raise ValueError(
            f"{name} must be finite; it holds {bad} NaN or inf value(s). "
            f"Remove or mask those entries before the call."
        )
    return arr


def as_numeric(value, name: str, *, kinds: str = "fiu", expected: str = "a numeric array") -> np.ndarray:
    """``np.asarray(value)``, its dtype kept, if the dtype's kind is one of ``kinds``.

    Anything else (strings, objects, ragged sequences) raises a ValueError naming ``name``:
    "{name} must be {expected}, got {type}: {reason}".
    """
    try:
        arr = np.asarray(value)
        if arr.dtype.kind not in kinds:
            raise TypeError(f"dtype {arr.dtype}")
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__}: {exc}") from None
    return arr


def _check_shape(arr: np.ndarray, name: str, shape) -> None:
    shape = tuple(shape)
    if shape and shape[0] is Ellipsis:
        tail = shape[1:]
        ok = arr.ndim >= len(tail) and all(
            s is None or s == a for s, a in zip(tail, arr.shape[arr.ndim - len(tail):])
        )
    else:
        ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
    if not ok:
        want = "(" + ", ".join("..." if s is Ellipsis else ("n" if s is None else str(s)) for s in shape) + ")"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")


def as_points(value, name: str) -> np.ndarray:
    """(n, 3) finite float64 points; a single (3,) point is promoted to (1, 3)."""
    arr = as_array(value, name)
    if arr.ndim == 1 and arr.shape == (3,):
        arr = arr[None, :]
    _check_shape(arr, name, (None, 3))
    return arr


def as_unit_vectors(value, name: str, *, count: int | None = None, atol: float = 1e-3) -> np.ndarray:
    """(n, 3) vectors, renormalized to unit length.

    Vectors whose length differs from 1 by more than ``atol`` are still accepted and
    normalized; only zero-length vectors are rejected, since they have no direction.
    """
    arr = as_points(value, name)
    if count is not None and arr.shape[0] != count:
        raise ValueError(f"{name} must have one row per point ({count}), got {arr.shape[0]}")
    length = np.linalg.norm(arr, axis=-1, keepdims=True)
    if np.any(length < 1e-12):
        raise ValueError(f"{name} holds {int(np.count_nonzero(length < 1e-12))} zero-length vector(s); "
                         "every normal or direction needs a length")
    return arr / length


def as_rng(seed) -> np.random.Generator:
    """The one conversion of a ``seed`` argument (int, Generator or None) to a Generator."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None or (isinstance(seed, numbers.Integral) and not isinstance(seed, bool) and seed >= 0):
        return np.random.default_rng(seed)
    raise ValueError(f"seed must be a non-negative int, a numpy.random.Generator or None, got {seed!r}")


def check_bool(value, name: str) -> bool:
    """``value`` as a bool when it is one (Python's or NumPy's); anything else is an error.

    Truthy strings such as ``"no"`` or ``"False"`` and numbers are rejected rather than taken
    by their truth value, which would silently read ``"no"`` as True.
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{name} must be True or False, got {value!r}")


def check_choice(value, name: str, choices: Iterable[str]) -> str:
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in choices)}; got {value!r}")
    return value


def check_positive(value, name: str, *, allow_inf: bool = False, allow_zero: bool = False) -> float:
    """A real number > 0 (>= 0 with ``allow_zero``), finite unless ``allow_inf``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a positive number, got {value!r}")
    v = float(value)
    if np.isnan(v) or (np.isinf(v) and not allow_inf) or v < 0 or (v == 0 and not allow_zero):
        what = "a non-negative" if allow_zero else "a positive"
        fin = "" if allow_inf else " finite"
        raise ValueError(f"{name} must be {what}{fin} number, got {value!r}")
    return v


def check_int(value, name: str, *, minimum: int = 1) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value}")
    return int(value)
