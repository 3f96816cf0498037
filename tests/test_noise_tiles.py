"""Large noise tiles (the 64 x 64 ``"r2"`` and ``"gtao"`` tiles): a texel per pixel.

``vo_line`` (nearest fetch), ``sao`` and ``alchemy`` group the pixels by texel when the tile
has at most ``_common.MAX_NOISE_CLASSES`` texels, and read a texel per pixel above. The two
routes compute the same estimator; each test forces both on the same texture (by setting
``MAX_NOISE_CLASSES`` for the call) and compares them. The grouped route is the one the rest
of the suite tests against closed forms; the white default tile must keep taking it.
"""

from __future__ import annotations

import numpy as np
import pytest

import vobscure as vo
from vobscure.screenspace import _common as C
from vobscure.screenspace import noise

# vo_line's two routes reflect the pattern by equivalent formulas that round differently:
# grouped, 2 (s . v) v - s by a matrix product, then times the projected radius R (pixels);
# per pixel, the reflection matrix [[c, s], [s, -c]] folded with R. The tap offsets then differ
# by a few ulp of R (< 1e-13 pixels here), and the chord z_s (from the reflected point, or
# the pattern point whose length the reflection keeps) by a few ulp. Each line's term is
# Lipschitz in z_s with a constant of order w / z_s (w the weight, z_s >= 0.1 for the default
# patterns), so the visibility moves by ~1e-15; 1e-12 leaves a factor 1000. A tap offset within
# that rounding of half a pixel would round to another pixel (a set of measure zero: the
# frames here are fixed, so a pass is not luck that can change from run to run).
LINE_TOL = 1e-12

GROUPED = 1 << 30        # MAX_NOISE_CLASSES: every texture grouped by texel
PER_PIXEL = 0            # every texture read a texel per pixel


@pytest.fixture(scope="module")
def scene():
    return vo.scenes.cornell_box()


@pytest.fixture(scope="module")
def gbuffers(scene):
    """Small frames of the Cornell box: its perspective camera; a camera with fx != fy and an
    off-centre principal point (the tap offsets along x and y scale differently); the same
    scene depth-peeled (``thickness="layers"``); a float32 copy."""
    cam = scene.camera(size=(32, 24))
    gb = vo.render_gbuffer(scene, cam)
    odd = vo.Camera.from_intrinsics(cam.fx * 1.3, cam.fy * 0.8, 13.0, 15.0, (32, 24), pose=cam.pose)
    return {
        "perspective": gb,
        "intrinsics": vo.render_gbuffer(scene, odd),
        "layers": vo.render_gbuffer(scene, cam, layers=3),
        "float32": gb.astype(np.float32),
    }


def _routes(monkeypatch, f, gb, **kwargs):
    """``f(gb, **kwargs)`` grouped by texel and read per pixel."""
    out = []
    for limit in (GROUPED, PER_PIXEL):
        monkeypatch.setattr(C, "MAX_NOISE_CLASSES", limit)
        out.append(f(gb, **kwargs))
    return out


def test_which_tiles_are_read_per_pixel():
    for schedule in ("r2", "gtao", "blue"):
        assert C.per_pixel_noise(noise.schedule_texture(schedule, 0, dim=2))
    for schedule in ("white", "rotate"):
        for size in (1, noise.NOISE_SIZE, 8):
            assert not C.per_pixel_noise(noise.schedule_texture(schedule, 2, noise_size=size, dim=2))
    assert not C.per_pixel_noise(None)


def test_per_pixel_chunks_carry_each_valid_pixel_once_with_its_texel():
    # an image wider than the tile and with background pixels, in chunks smaller than it
    H, W = 70, 150
    rng = np.random.default_rng(1)
    depth = np.where(rng.random(H * W) < 0.8, 1.0 + rng.random(H * W), np.inf)
    texture = noise.schedule_texture("r2", 5, dim=2)
    seen = []
    for index, v in C.noise_classes(depth, (H, W), texture, chunk=1000):
        assert v.shape == (len(index), 2) and len(index) <= 1000
        i, j = index // W, index % W        # the texel tiles the image from its top-left pixel
        assert np.array_equal(v, texture[i % 64, j % 64])
        seen.append(index)
    seen = np.concatenate(seen)
    assert np.array_equal(np.sort(seen), np.flatnonzero(np.isfinite(depth)))


LINE_CASES = [
    ("perspective", {}),
    ("perspective", {"normal_clamp": True}),
    ("perspective", {"samples": 8}),                              # not point-symmetric
    ("perspective", {"samples": 8, "normal_clamp": True}),
    ("perspective", {"thickness": 0.05, "offscreen": "open"}),
    ("perspective", {"falloff": "quadratic", "normal_clamp": True}),
    ("intrinsics", {"normal_clamp": True}),
    ("layers", {"thickness": "layers"}),
    ("layers", {"thickness": "layers", "normal_clamp": True, "falloff": "quadratic"}),
    ("float32", {}),
]


@pytest.mark.parametrize("schedule", ["r2", "gtao"])
@pytest.mark.parametrize("frame_name, kwargs", LINE_CASES)
def test_vo_line_routes_agree(monkeypatch, scene, gbuffers, schedule, frame_name, kwargs):
    gb = gbuffers[frame_name]
    grouped, per_pixel = _routes(monkeypatch, vo.vo_line, gb, radius=0.1 * scene.extent, schedule=schedule,
                                 frame=3, **kwargs)
    assert per_pixel.dtype == grouped.dtype == gb.depth.dtype
    assert np.array_equal(np.isnan(per_pixel), np.isnan(grouped))
    valid = ~np.isnan(grouped)
    assert valid.sum() > 500
    diff = np.abs(per_pixel[valid].astype(np.float64) - grouped[valid])
    # float32 output: the two float64 results round to float32 apart by at most one ulp
    tol = LINE_TOL if gb.depth.dtype == np.float64 else float(np.finfo(np.float32).eps)
    assert diff.max() <= tol
    # the pattern turns per pixel: the image is not that of the unrotated pattern
    assert not np.array_equal(grouped, vo.vo_line(gb, radius=0.1 * scene.extent, randomize=False, **kwargs),
                              equal_nan=True)


@pytest.mark.parametrize("schedule", ["r2", "gtao"])
@pytest.mark.parametrize("name, kwargs", [("sao", {}), ("sao", {"samples": 5, "turns": 3}),
                                          ("alchemy", {}), ("alchemy", {"offscreen": "open"})])
@pytest.mark.parametrize("frame_name", ["perspective", "intrinsics", "float32"])
def test_sao_and_alchemy_routes_are_equal(monkeypatch, scene, gbuffers, schedule, name, kwargs, frame_name):
    # the same float64 operations in the same order on scalars and on arrays: equal bits
    f = getattr(vo, name)
    grouped, per_pixel = _routes(monkeypatch, f, gbuffers[frame_name], radius=0.1 * scene.extent,
                                 schedule=schedule, frame=5, **kwargs)
    assert np.array_equal(grouped, per_pixel, equal_nan=True)
    assert grouped.dtype == per_pixel.dtype


@pytest.mark.parametrize("schedule", ["white", "rotate"])
@pytest.mark.parametrize("name, kwargs", [("vo_line", {}), ("vo_line", {"normal_clamp": True, "samples": 8}),
                                          ("sao", {}), ("alchemy", {})])
def test_white_and_rotate_default_tiles_stay_grouped(monkeypatch, scene, gbuffers, schedule, name, kwargs):
    f = getattr(vo, name)
    gb = gbuffers["perspective"]
    radius = 0.1 * scene.extent
    default = f(gb, radius=radius, schedule=schedule, frame=2, **kwargs)
    monkeypatch.setattr(C, "MAX_NOISE_CLASSES", GROUPED)
    assert np.array_equal(default, f(gb, radius=radius, schedule=schedule, frame=2, **kwargs), equal_nan=True)


@pytest.mark.parametrize("name", ["vo_line", "sao", "alchemy"])
def test_a_small_tile_read_per_pixel_agrees(monkeypatch, scene, gbuffers, name):
    # the per-pixel route with the white 4 x 4 tile, forced: the grouped route's values
    f = getattr(vo, name)
    grouped, per_pixel = _routes(monkeypatch, f, gbuffers["perspective"], radius=0.1 * scene.extent, seed=4)
    valid = ~np.isnan(grouped)
    assert np.array_equal(valid, ~np.isnan(per_pixel))
    assert np.abs(per_pixel[valid] - grouped[valid]).max() <= LINE_TOL


def test_gtao_frames_half_a_turn_apart_are_one_reflection(scene, gbuffers):
    # vo_line reflects its pattern about the line along the texel's vector (Loos & Sloan 2010,
    # Sec. 4.5), the same line for v and -v. The "gtao" schedule turns frame 3 by 240 degrees
    # and frame 0 by 60, and dim-2 texels carry no step offset: one image within rounding.
    # sao turns its spiral instead (a rotation, 360-degree periodic): two images.
    gb, radius = gbuffers["perspective"], 0.1 * scene.extent
    first, fourth = (vo.vo_line(gb, radius=radius, schedule="gtao", frame=f) for f in (0, 3))
    valid = ~np.isnan(first)
    assert np.abs(first[valid] - fourth[valid]).max() <= LINE_TOL
    assert not np.allclose(*(vo.sao(gb, radius=radius, schedule="gtao", frame=f) for f in (0, 3)), equal_nan=True)
