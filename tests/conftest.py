"""Shared fixtures and statistical helpers for the vobscure test suite."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

#: Where the real meshes live (beside the repository, in the workplace's shared folder).
MESH_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"

#: Probability that one statistical assertion fails although the code is right.
FALSE_FAILURE = 1e-4


def t_threshold(df: int, tests: int = 1, false_failure: float = FALSE_FAILURE) -> float:
    """Two-sided Student-t critical value, Bonferroni-corrected over ``tests`` assertions.

    The ground truth's stderr comes from ``groups`` independent randomizations, so
    (value - exact) / stderr is t-distributed with groups - 1 degrees of freedom.
    """
    return float(stats.t.ppf(1.0 - false_failure / (2.0 * tests), df))


def assert_unbiased(estimate, exact, *, df: int, false_failure: float = FALSE_FAILURE):
    """z(t)-test of every entry of an Estimate against exact values."""
    z = np.atleast_1d(estimate.zscore(exact))
    limit = t_threshold(df, tests=z.size, false_failure=false_failure)
    assert np.all(np.isfinite(z)), f"non-finite z-scores {z}"
    assert np.all(np.abs(z) < limit), (
        f"|t| up to {np.abs(z).max():.2f} exceeds {limit:.2f}: value {estimate.value}, exact {exact}, "
        f"stderr {estimate.stderr}")


@pytest.fixture(scope="session")
def crease():
    import vobscure as vo

    return vo.scenes.crease()


@pytest.fixture(scope="session")
def slab():
    import vobscure as vo

    return vo.scenes.slab()
