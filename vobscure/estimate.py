"""The result type of every Monte Carlo computation in vobscure."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Estimate", "DEFAULT_GROUPS"]

#: Independent randomizations behind every Monte Carlo reference (the ray-cast ground truth,
#: :func:`vobscure.vo_reference`): the stderr has DEFAULT_GROUPS - 1 degrees of freedom.
DEFAULT_GROUPS = 8


@dataclass(frozen=True)
class Estimate:
    """A Monte Carlo estimate with its standard error.

    Attributes
    ----------
    value : ndarray
        The estimate (visibility in [0, 1] for every reference in vobscure).
    stderr : ndarray
        Its standard error, same shape: the standard deviation of ``value`` over repeated
        runs with independent seeds. Computed from independent randomizations of the
        sampler (see ``docs/groundtruth.md``); NaN where ``value`` is NaN.
    samples : int
        Samples (rays or points) spent per entry of ``value``.
    bent_normal : ndarray or None
        (..., 3) unit bent normals when they were requested (ambient occlusion only).

    Examples
    --------
    >>> import numpy as np
    >>> e = Estimate(np.array([0.5]), np.array([0.01]), 256)
    >>> e.zscore(0.52).round(3).tolist()
    [-2.0]
    """

    value: np.ndarray
    stderr: np.ndarray
    samples: int
    bent_normal: np.ndarray | None = None

    @property
    def shape(self) -> tuple:
        return np.shape(self.value)

    def zscore(self, exact) -> np.ndarray:
        """(value - exact) / stderr; 0 where both the difference and stderr are 0."""
        diff = np.asarray(self.value, float) - np.asarray(exact, float)
        se = np.asarray(self.stderr, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = diff / se
        return np.where((diff == 0) & (se == 0), 0.0, z)
