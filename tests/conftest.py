"""Shared fixtures and helpers for the vobscure test suite (closed forms: tests/analytic.py)."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

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


@pytest.fixture(scope="module")
def big_slab():
    """A slab far larger than any view of it: no image shows its edge."""
    import vobscure as vo

    return vo.scenes.slab(size=200.0)


def interior(gb, radius, margin=1.0):
    """Pixels whose whole tap disk of ``radius`` (plus ``margin`` pixels) lies on the image:
    an estimator's off-screen taps legitimately read other values."""
    H, W = gb.shape
    rp = radius * np.asarray(gb.camera.pixels_per_unit(np.where(gb.valid, gb.depth, 1.0)))
    i, j = np.mgrid[0:H, 0:W]
    return (gb.valid & (j + 0.5 - rp - margin > 0) & (j + 0.5 + rp + margin < W)
            & (i + 0.5 - rp - margin > 0) & (i + 0.5 + rp + margin < H))


#: The orthographic view of the crease shared by the screen-space tests: its depth buffer
#: describes the solids exactly, so an estimator converges to the closed forms.
CREASE_EYE, CREASE_TARGET = (3.0, 3.0, 1.0), (0.4, 0.2, 0.0)
CREASE_SIZE = 128
#: The radius R of ``crease_view``'s floor pixels (c = x / R).
CREASE_RADIUS = 1.0


class CreaseView(NamedTuple):
    """The crease's G-buffer, the floor pixels with 0.05 < c < 0.95 whose tap disk of radius
    CREASE_RADIUS lies on the image, and their c = x / R."""

    gb: object
    floor: np.ndarray
    c: np.ndarray


@pytest.fixture(scope="module")
def crease_view(crease):
    import vobscure as vo

    cam = vo.Camera.look_at(CREASE_EYE, CREASE_TARGET, size=(CREASE_SIZE, CREASE_SIZE), ortho_height=4.0)
    gb = vo.render_gbuffer(crease, cam)
    x, y = gb.world_position[..., 0], gb.world_position[..., 1]
    R = CREASE_RADIUS
    floor = interior(gb, R) & (np.abs(y) < 1e-9) & (x > 0.05 * R) & (x < 0.95 * R)
    return CreaseView(gb, floor, x[floor] / R)


#: Views inside the Cornell box (the realistic case of walls, creases and boxes in the ball) of
#: the converged reference's tests, with their image size and ball radius.
INSIDE_VIEWS = {"perspective": dict(eye=(0.2, 1.0, 0.6), target=(-0.3, 0.7, -1.0), fov_y=60.0),
                "orthographic": dict(eye=(0.1, 1.1, 2.5), target=(-0.2, 0.8, -1.0), ortho_height=1.6)}
INSIDE_SIZE = (20, 14)
INSIDE_RADIUS = 0.375


def inside_views() -> dict:
    """The G-buffers of :data:`INSIDE_VIEWS`, by name."""
    import vobscure as vo

    scene = vo.scenes.cornell_box()
    out = {}
    for name, view in INSIDE_VIEWS.items():
        kw = dict(view)
        cam = vo.Camera.look_at(kw.pop("eye"), kw.pop("target"), size=INSIDE_SIZE, **kw)
        out[name] = vo.render_gbuffer(scene, cam)
    return out


def one_slice_z(estimator, *, clip: bool, frames: int = 64) -> float:
    """z-score of the mean of ``frames`` independent one-slice frames (white noise per frame) of
    ``estimator`` (gtao, vbao) on an open plane seen obliquely, against its integral 1."""
    import vobscure as vo

    cam = vo.Camera.look_at((1, 2, 1.5), (0, 0, 0), size=(16, 16), fov_y=40)
    gb = vo.render_gbuffer(vo.scenes.slab(), cam)
    means = np.array([np.nanmean(estimator(gb, radius=0.3, slices=1, frame=n, clip=clip)) for n in range(frames)])
    return float((means.mean() - 1.0) / (means.std(ddof=1) / np.sqrt(frames)))
