"""Argument checks and constants shared by the camera's modules."""

from __future__ import annotations

import math
import numbers

import numpy as np

from .._validate import as_array, check_positive

#: Default vertical field of view in degrees when neither ``fov_y`` nor ``ortho_height`` is given.
DEFAULT_FOV_Y = 45.0

# eye and target closer than this, relative to their magnitude, give no view direction.
EYE_TARGET_RTOL = 1e-10
# |forward x unit(up)| below this: up is (nearly) parallel to the view direction.
UP_PARALLEL_TOL = 1e-6
# A pose's 3x3 part may differ from an orthogonal matrix by this much (per entry of R^T R - I).
POSE_ORTHO_TOL = 1e-6
# Entries of a projection matrix that must be zero may be this far from it (relative to the
# matrix's largest entry).
PROJECTION_ZERO_TOL = 1e-9


def vector3(value, name: str) -> np.ndarray:
    """A (3,) finite float64 array of its own, or a ValueError naming ``name``."""
    return as_array(value, name, shape=(3,)).copy()


def check_size(size) -> tuple[int, int]:
    """An image size as a pair ``(width, height)`` of positive ints, or a ValueError naming
    ``size``.

    Examples
    --------
    >>> check_size([640, 480])
    (640, 480)
    """
    if isinstance(size, (str, bytes)) or not hasattr(size, "__len__"):
        raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
    if isinstance(size, np.ndarray) and size.ndim != 1:
        raise ValueError(f"size must be a pair (width, height) of positive ints, got shape {size.shape}")
    if len(size) != 2:
        raise ValueError(f"size must be a pair (width, height) of positive ints, got {len(size)} value(s): {size!r}")
    out = []
    for v in size:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral):
            raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
        if v < 1:
            raise ValueError(f"size must be a pair (width, height) of positive ints, got {size!r}")
        out.append(int(v))
    return out[0], out[1]


def check_fov(fov_y) -> float:
    """``fov_y`` in degrees, in the open interval (0, 180)."""
    v = check_positive(fov_y, "fov_y")
    if not v < 180.0:
        raise ValueError(f"fov_y must be in the open interval (0, 180) degrees, got {fov_y!r}")
    return v


def optional_positive(value, name: str, *, allow_inf: bool = False):
    """None, or a float > 0 (+inf allowed with ``allow_inf``)."""
    if value is None:
        return None
    if allow_inf and isinstance(value, numbers.Real) and value == math.inf:
        return math.inf
    return check_positive(value, name)


def check_int(value, name: str) -> int:
    """An int (not a bool), or a ValueError naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be an int, got {value!r}")
    return int(value)


def scalar(arr: np.ndarray):
    """0-d arrays become NumPy scalars, like the result of a ufunc; others pass through."""
    return arr[()] if arr.ndim == 0 else arr


def freeze(v):
    """Lists (nested) to tuples, so a record can be hashed."""
    return tuple(freeze(x) for x in v) if isinstance(v, (list, tuple)) else v
