"""Per-frame noise schedules (vobscure.screenspace.noise) and the estimators' frame / schedule.

Independent checks: the single-frame texture written out as numpy draws; a correlation z-test
between white frames; the estimators' own reading of a texture (``slice_noise``, the angle of
a 2-D vector) for the round trip; the Hilbert curve's defining property (a walk through every
cell by 4-neighbour steps) and index values worked by hand from XeGTAO's ``HilbertIndex`` loop;
the period of each schedule by comparing frames.
"""

from __future__ import annotations

import inspect
from types import SimpleNamespace

import numpy as np
import pytest

import vobscure as vo
from vobscure import methods
from vobscure.screenspace import _common as C
from vobscure.screenspace import _horizon as Hz
from vobscure.screenspace import noise

# Round trip (u1, u2) -> unit vector -> reading: cos, sin, sqrt and arctan2 each round to
# ~1 ulp; 1e-12 leaves three orders of magnitude of margin over float64 rounding of 2 pi u.
ROUNDTRIP_TOL = 1e-12
# Two-sided z-test on a correlation of n = 4096 pairs, sqrt(n) r ~ N(0, 1) under independence:
# |z| > 4.0 happens with probability 6e-5 per component (three components: 2e-4 per run).
Z_CRIT = 4.0
# The rotate schedule's angle: arctan2 of turned vectors, ~1e-15 rad; 1e-12 with margin.
ANGLE_TOL = 1e-12


@pytest.fixture(scope="module")
def cornell():
    scene = vo.scenes.cornell_box()
    return vo.render_gbuffer(scene, scene.camera((24, 24)))


def _old_texture(noise_size, seed, dim):
    v = np.random.default_rng(seed).normal(size=(noise_size, noise_size, dim))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _texels(size):
    """A stand-in for the Pixels of a size x size image, as slice_noise reads them."""
    row, col = np.divmod(np.arange(size * size), size)
    return SimpleNamespace(index=np.arange(size * size), row=row, col=col)


def _circular(a, b):
    d = np.abs(a - b) % 1.0
    return np.minimum(d, 1.0 - d)


# --- white ---------------------------------------------------------------------------------

@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed, size", [(0, 4), (7, 4), (3, 64)])
def test_white_frame_zero_is_the_single_frame_texture(dim, seed, size):
    old = _old_texture(size, seed, dim)
    assert np.array_equal(C.noise_texture(size, seed, dim, True), old)
    assert np.array_equal(C.noise_texture(size, seed, dim, True, frame=0, schedule="white"), old)
    assert np.array_equal(noise.schedule_texture("white", 0, seed=seed, noise_size=size, dim=dim), old)


def test_white_frames_are_independent():
    a = noise.schedule_texture("white", 1, seed=5, noise_size=64, dim=3).reshape(-1, 3)
    b = noise.schedule_texture("white", 2, seed=5, noise_size=64, dim=3).reshape(-1, 3)
    n = len(a)
    for c in range(3):
        r = np.corrcoef(a[:, c], b[:, c])[0, 1]
        assert abs(np.sqrt(n) * r) < Z_CRIT, (c, r)
    assert not np.array_equal(a, b)


def test_white_generator_seed_is_drawn_from_as_given():
    late = noise.schedule_texture("white", 5, seed=np.random.default_rng(3))
    assert np.array_equal(late, noise.schedule_texture("white", 0, seed=np.random.default_rng(3)))
    assert not np.array_equal(noise.schedule_texture("white", 5, seed=3), noise.schedule_texture("white", 0, seed=3))


# --- (u1, u2) <-> texture ------------------------------------------------------------------

def test_uniforms_round_trip_through_the_estimators_readings():
    rng = np.random.default_rng(11)
    u = rng.random((8, 8, 2))
    # the edges: u1 = 0, u2 = 0 (a pole), u2 just below 1, u1 just below 1
    u[0, 0] = (0.0, 0.0)
    u[0, 1] = (0.3, 0.0)
    u[0, 2] = (0.7, np.nextafter(1.0, 0.0))
    u[0, 3] = (np.nextafter(1.0, 0.0), 0.25)
    v3 = noise.uniforms_to_texture(u, 3)
    assert np.allclose(np.linalg.norm(v3, axis=-1), 1.0, rtol=0, atol=ROUNDTRIP_TOL)
    read = Hz.slice_noise(_texels(8), v3)
    assert _circular(read.u_texel, u[..., 0].ravel()).max() < ROUNDTRIP_TOL
    assert np.abs(read.u_step - u[..., 1].ravel()).max() < ROUNDTRIP_TOL
    v2 = noise.uniforms_to_texture(u, 2)
    angle = (np.arctan2(v2[..., 1], v2[..., 0]) / (2 * np.pi)) % 1.0
    assert _circular(angle, u[..., 0]).max() < ROUNDTRIP_TOL


@pytest.mark.parametrize("schedule", noise.SCHEDULES)
def test_schedule_texture_reads_back_as_its_uniforms(schedule):
    u = noise.schedule_uniforms(schedule, 5, seed=2)
    assert u.shape[-1] == 2 and u.min() >= 0.0 and u.max() < 1.0
    tex = noise.schedule_texture(schedule, 5, seed=2, dim=3)
    read = Hz.slice_noise(_texels(tex.shape[0]), tex)
    assert _circular(read.u_texel, u[..., 0].ravel()).max() < ROUNDTRIP_TOL
    assert np.abs(read.u_step - u[..., 1].ravel()).max() < ROUNDTRIP_TOL


# --- r2 --------------------------------------------------------------------------------------

def test_hilbert_index_walks_the_grid_by_neighbour_steps():
    row, col = np.mgrid[0:64, 0:64]
    h = noise.hilbert_index(col, row)
    assert np.array_equal(np.sort(h.ravel()), np.arange(4096))
    where = np.empty((4096, 2), dtype=np.int64)
    where[h.ravel()] = np.column_stack([col.ravel(), row.ravel()])
    steps = np.abs(np.diff(where, axis=0)).sum(axis=1)
    assert np.all(steps == 1)
    # XeGTAO's HilbertIndex by hand: the first cells (0, 0), (1, 0), (1, 1), (0, 1), the
    # quarters visited top-left, bottom-left (rows 32..63), bottom-right, top-right
    assert h[0, 0] == 0 and h[0, 1] == 1 and h[1, 1] == 2 and h[1, 0] == 3
    quarters = [h[:32, :32], h[32:, :32], h[32:, 32:], h[:32, 32:]]
    for q, part in enumerate(quarters):
        assert part.min() == 1024 * q and part.max() == 1024 * q + 1023
    assert h[0, 63] == 4095
    assert np.array_equal(noise.hilbert_index(col + 64, row + 128), h)


def test_r2_values_period_and_distinct_frames():
    u0 = noise.schedule_uniforms("r2", 0)
    assert u0.shape == (64, 64, 2)
    # index 0 and 1 of XeGTAO's SpatioTemporalNoise: frac(0.5 + index * alpha)
    assert u0[0, 0].tolist() == [0.5, 0.5]
    assert np.allclose(u0[0, 1], [0.25487766624669276, 0.06984029099805333], rtol=0, atol=1e-15)
    frames = [noise.schedule_uniforms("r2", f) for f in range(64)]
    for f in (0, 5, 63):
        assert np.array_equal(frames[f], noise.schedule_uniforms("r2", f + 64))
    flat = np.stack([f.ravel() for f in frames])
    assert len(np.unique(flat, axis=0)) == 64
    assert noise.period("r2") == 64
    # noise_size does not apply
    assert np.array_equal(noise.schedule_uniforms("r2", 3, noise_size=8), noise.schedule_uniforms("r2", 3))


# --- gtao ------------------------------------------------------------------------------------

def test_gtao_temporal_pairs_and_period():
    pairs = [noise.gtao_temporal(f) for f in range(24)]
    assert len(set(pairs)) == 24
    assert {p[0] for p in pairs} == {0.0, 60.0, 120.0, 180.0, 240.0, 300.0}
    assert {p[1] for p in pairs} == {0.0, 0.25, 0.5, 0.75}
    frames = [noise.schedule_uniforms("gtao", f) for f in range(24)]
    for f in (0, 7, 23):
        assert np.array_equal(frames[f], noise.schedule_uniforms("gtao", f + 24))
    assert len(np.unique(np.stack([f.ravel() for f in frames]), axis=0)) == 24
    assert noise.period("gtao") == 24


def test_gtao_spatial_part():
    u = noise.schedule_uniforms("gtao", 0)
    # pixel (x, y) = (0, 0): interleaved gradient noise 0, plus frame 0's 60 degrees
    assert u[0, 0, 0] == pytest.approx(60.0 / 360.0, abs=1e-15)
    # IGN(1, 0) = frac(52.9829189 * 0.06711056), worked out apart: 0.555713357813584
    assert u[0, 1, 0] == pytest.approx((0.555713357813584 + 60.0 / 360.0) % 1.0, abs=1e-12)
    # the spatial step offset 0.25 ((y - x) mod 4): down a diagonal it is constant, along a
    # row it falls by 1/4 per pixel
    diag = np.array([u[i, i, 1] for i in range(64)])
    assert np.all(diag == 0.0)
    assert np.allclose((u[:, 1:, 1] - u[:, :-1, 1]) % 1.0, 0.75, rtol=0, atol=1e-15)


# --- rotate ----------------------------------------------------------------------------------

@pytest.mark.parametrize("dim", [2, 3])
def test_rotate_turns_frame_zero_by_golden_ratio_increments(dim):
    base = noise.schedule_texture("rotate", 0, seed=4, noise_size=8, dim=dim)
    assert np.array_equal(base, noise.schedule_texture("white", 0, seed=4, noise_size=8, dim=dim))
    a0 = np.arctan2(base[..., 1], base[..., 0])
    for n in (1, 2, 10, 1000):
        v = noise.schedule_texture("rotate", n, seed=4, noise_size=8, dim=dim)
        turn = (np.arctan2(v[..., 1], v[..., 0]) - a0) % (2 * np.pi)
        want = (n * 2 * np.pi * 0.6180339887498949) % (2 * np.pi)
        d = np.abs(turn - want)
        assert np.minimum(d, 2 * np.pi - d).max() < ANGLE_TOL
        if dim == 3:
            assert np.array_equal(v[..., 2], base[..., 2])
    assert noise.period("rotate") is None and noise.period("white") is None


# --- the estimators --------------------------------------------------------------------------

def _randomized_estimators():
    out = []
    for name in methods.names():
        m = methods.get(name)
        if not getattr(m.function, "func", m.function).__module__.startswith("vobscure.screenspace"):
            continue
        params = inspect.signature(m.function).parameters
        if "seed" not in params or m.reference_only:
            continue
        out.append(name)
    return out


def test_every_randomized_screenspace_function_takes_frame_and_schedule():
    names = _randomized_estimators()
    assert {"point", "line", "area", "gtao", "vbao", "hbao", "alchemy", "sao"} <= set(names)
    for f in (vo.vo_point, vo.vo_line, vo.vo_area, vo.gtao, vo.gtao_bent_normals, vo.hbao, vo.sao,
              vo.alchemy, vo.vbao):
        params = inspect.signature(f).parameters
        for p in ("frame", "schedule"):
            assert params[p].kind is inspect.Parameter.KEYWORD_ONLY, (f.__name__, p)
        assert params["frame"].default == 0 and params["schedule"].default == "white"
    assert "frame" not in inspect.signature(vo.vo_reference).parameters


@pytest.mark.parametrize("name", _randomized_estimators())
@pytest.mark.parametrize("schedule", noise.SCHEDULES)
def test_estimators_change_with_the_frame(cornell, name, schedule):
    m = methods.get(name)
    run = lambda frame: m.run(cornell, 4, radius=0.5, frame=frame, schedule=schedule)
    # frames 0 and 1: under "gtao" frames 0 and 3 turn the texels by 60 and 240 degrees, the
    # same reflection for vo_line and vo_area (test_noise_tiles.py)
    first, second = run(0), run(1)
    assert np.array_equal(second, run(1), equal_nan=True)
    assert not np.array_equal(first, second, equal_nan=True)
    assert np.array_equal(np.isnan(first), np.isnan(second))


def test_without_randomization_the_frame_is_unused(cornell):
    a = vo.gtao(cornell, radius=0.5, randomize=False)
    b = vo.gtao(cornell, radius=0.5, randomize=False, frame=9, schedule="r2")
    assert np.array_equal(a, b, equal_nan=True)


def test_r2_period_mean_converges_towards_many_slices(cornell):
    # Two slices per frame: at one slice GTAO's per-pixel clip of the visibility to [0, 1]
    # biases each frame (a single slice's value exceeds 1 on oblique open surfaces), so its
    # frames average to a different image than many slices give.
    r = 0.5
    ref = np.mean([vo.gtao(cornell, radius=r, slices=32, frame=f) for f in range(8)], axis=0)
    frames = [vo.gtao(cornell, radius=r, slices=2, frame=f, schedule="r2") for f in range(64)]
    rmse = lambda a: float(np.sqrt(np.nanmean((a - ref) ** 2)))
    assert rmse(np.mean(frames, axis=0)) < rmse(frames[0]) / 3


def test_registry_passes_frame_and_schedule(cornell):
    got = methods.get("gtao").run(cornell, 3, radius=0.5, frame=5, schedule="r2")
    assert np.array_equal(got, vo.gtao(cornell, radius=0.5, slices=3, frame=5, schedule="r2"), equal_nan=True)
    assert not np.array_equal(got, vo.gtao(cornell, radius=0.5, slices=3), equal_nan=True)
    with pytest.raises(ValueError, match="no registered method takes the option.*'fram'"):
        methods.get("gtao").run(cornell, 3, radius=0.5, fram=5)
    # a method without the keywords (the converged reference) runs as without them
    reference = methods.get("reference")
    assert np.array_equal(reference.run(cornell, 64, radius=0.5, frame=3, schedule="r2"),
                          reference.run(cornell, 64, radius=0.5), equal_nan=True)


# --- bad arguments ---------------------------------------------------------------------------

@pytest.mark.parametrize("frame", [-1, 1.5, "x", True, None])
def test_bad_frame(cornell, frame):
    with pytest.raises(ValueError, match="frame"):
        vo.gtao(cornell, radius=0.5, frame=frame)
    with pytest.raises(ValueError, match="frame"):
        vo.vo_line(cornell, radius=0.5, frame=frame, randomize=False)
    with pytest.raises(ValueError, match="frame"):
        noise.schedule_uniforms("white", frame)


@pytest.mark.parametrize("schedule", ["pink", 3, None, "R2"])
def test_bad_schedule(cornell, schedule):
    for call in (lambda: vo.sao(cornell, radius=0.5, schedule=schedule),
                 lambda: vo.vo_point(cornell, radius=0.5, schedule=schedule, randomize=False),
                 lambda: noise.schedule_uniforms(schedule, 0),
                 lambda: noise.period(schedule)):
        with pytest.raises(ValueError, match="schedule must be one of 'white', 'rotate', 'r2', 'gtao', 'blue'"):
            call()
