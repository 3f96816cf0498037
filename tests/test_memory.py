"""The size guard: the memory available, the per-stage models against measured peaks, the
refusal before any work (API and command), and ``GBuffer.from_arrays``' bounded peak."""

from __future__ import annotations

import gc
import time
import tracemalloc

import numpy as np
import pytest

import vobscure as vo
from vobscure import _memory, cli, convert
from vobscure._memory import MEMORY_FRACTION, MODEL_UNDER, MemoryBudgetError, Need

#: A refusal comes before any work: the request is estimated and refused in well under a
#: second (a 20000 x 20000 render took 173 s to be killed before the guard).
REFUSAL_SECONDS = 0.5
#: The memory the refusal tests pretend to have: 16 GiB, far less than a 20000^2 request.
LIMIT = 16 << 30
#: The models may under-estimate a measured peak by MODEL_UNDER at most: with requests refused
#: above MEMORY_FRACTION of the memory available, an estimate >= (1 - MODEL_UNDER) x the true
#: peak keeps an accepted request's true peak within the memory available when
#: MEMORY_FRACTION <= 1 - MODEL_UNDER (checked below).
LEAST_RATIO = 1.0 - MODEL_UNDER
#: GBuffer.from_arrays' peak at 1024 x 1024 over its output (float32 depth and normals, bool
#: valid: 17 B a pixel). Measured 2.1-2.2 (the float64 linear depth kept while the normals are
#: made, plus one band's temporaries); it was 14.8 at 4096 x 4096 without normals when the
#: normals were derived on the whole image at once.
FROM_ARRAYS_PEAK_RATIO = 2.5


def _peak(fn):
    """(result, tracemalloc peak in bytes) of one call."""
    gc.collect()
    tracemalloc.start()
    try:
        out = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return out, peak


def test_the_reserve_covers_the_largest_under_estimate_allowed():
    assert MEMORY_FRACTION <= 1.0 - MODEL_UNDER


# --------------------------------------------------------------------------- memory available
@pytest.fixture
def fake_system(tmp_path, monkeypatch):
    """Point the module at a fake /proc and /sys/fs/cgroup under tmp_path, with no override."""
    monkeypatch.delenv(_memory.ENV_LIMIT, raising=False)
    paths = {"meminfo": tmp_path / "meminfo", "cgroup": tmp_path / "self_cgroup",
             "v2": tmp_path / "cg2", "v1": tmp_path / "cg1"}
    paths["v2"].mkdir()
    paths["v1"].mkdir()
    monkeypatch.setattr(_memory, "_MEMINFO", paths["meminfo"])
    monkeypatch.setattr(_memory, "_PROC_CGROUP", paths["cgroup"])
    monkeypatch.setattr(_memory, "_CGROUP_V2", paths["v2"])
    monkeypatch.setattr(_memory, "_CGROUP_V1", paths["v1"])
    paths["meminfo"].write_text("MemTotal:       32000000 kB\nMemFree:         1000000 kB\n"
                                "MemAvailable:    2000000 kB\n")
    return paths


def test_meminfo_alone(fake_system):
    assert _memory.available_bytes() == 2000000 * 1024


def test_cgroup_v2_room_of_the_process_group_is_used_when_smaller(fake_system):
    fake_system["cgroup"].write_text("0::/jobs/mine\n")
    group = fake_system["v2"] / "jobs" / "mine"
    group.mkdir(parents=True)
    (group / "memory.max").write_text("1000000000\n")
    (group / "memory.current").write_text("400000000\n")
    assert _memory.available_bytes() == 600000000
    (group / "memory.max").write_text("max\n")            # no limit: meminfo
    assert _memory.available_bytes() == 2000000 * 1024
    (group / "memory.max").write_text("9000000000\n")     # a limit above MemAvailable: meminfo
    assert _memory.available_bytes() == 2000000 * 1024


def test_cgroup_v1_limit_and_its_unlimited_value(fake_system):
    fake_system["cgroup"].write_text("4:memory:/x\n0::/\n")
    (fake_system["v1"] / "memory.limit_in_bytes").write_text("500000000\n")
    (fake_system["v1"] / "memory.usage_in_bytes").write_text("100000000\n")
    assert _memory.available_bytes() == 400000000
    (fake_system["v1"] / "memory.limit_in_bytes").write_text("9223372036854771712\n")   # v1's "no limit"
    assert _memory.available_bytes() == 2000000 * 1024
    # the process's own group (the line of the memory controller) under the hierarchy
    fake_system["cgroup"].write_text("5:cpu,cpuacct:/y\n4:memory:/x/job\n0::/\n")
    group = fake_system["v1"] / "x" / "job"
    group.mkdir(parents=True)
    (group / "memory.limit_in_bytes").write_text("300000000\n")
    (group / "memory.usage_in_bytes").write_text("50000000\n")
    assert _memory.available_bytes() == 250000000


def test_nothing_readable_falls_back_to_sysconf(fake_system):
    fake_system["meminfo"].unlink()
    value = _memory.available_bytes()
    assert value is None or (isinstance(value, int) and value > 0)


def test_the_environment_override(monkeypatch):
    monkeypatch.setenv(_memory.ENV_LIMIT, "12345")
    assert _memory.available_bytes() == 12345
    monkeypatch.setenv(_memory.ENV_LIMIT, "a lot")
    with pytest.raises(ValueError, match="VOBSCURE_MEMORY_LIMIT must be a number of bytes"):
        _memory.available_bytes()


def test_format_bytes():
    assert [_memory.format_bytes(n) for n in (0, 1023, 1024, 1536, 3 << 30, 5 << 40)] == \
        ["0 B", "1023 B", "1 KiB", "1.5 KiB", "3 GiB", "5 TiB"]


# --------------------------------------------------------------------------- require
def test_require_passes_what_fits_and_names_the_largest_size_that_does(monkeypatch):
    monkeypatch.setenv(_memory.ENV_LIMIT, str(1_000_000))
    need = Need(100)                              # 100 B a pixel: 8000 pixels fit in 80 % of 1 MB
    _memory.require(need, size=(100, 80), what="w", reduce="r")
    with pytest.raises(MemoryBudgetError) as info:
        _memory.require(need, size=(200, 100), what="rendering a 200 x 100 thing", reduce="--size")
    message = str(info.value)
    assert message.startswith("rendering a 200 x 100 thing needs about 1.91 MiB (100 bytes a pixel)")
    assert "977 KiB are available" in message and "reduce --size" in message
    W, H = (int(v) for v in message.split("at most about ")[1].split(" here")[0].split(" x "))
    assert W / H == pytest.approx(2.0, rel=0.02)
    _memory.require(need, size=(W, H), what="w", reduce="r")          # the size named fits ...
    with pytest.raises(MemoryBudgetError):
        _memory.require(need, size=(W + 2, H + 1), what="w", reduce="r")   # ... and is about the largest


def test_require_does_nothing_when_the_memory_is_unknown(monkeypatch):
    monkeypatch.delenv(_memory.ENV_LIMIT, raising=False)
    monkeypatch.setattr(_memory, "available_bytes", lambda: None)
    _memory.require(Need(1e12), size=(10, 10), what="w", reduce="r")


# --------------------------------------------------------------------------- refusals
def test_render_gbuffer_is_refused_before_any_work(monkeypatch):
    monkeypatch.setenv(_memory.ENV_LIMIT, str(LIMIT))
    scene = vo.scenes.cornell_box()
    t0 = time.perf_counter()
    with pytest.raises(MemoryBudgetError, match=r"rendering a 20000 x 20000 G-buffer needs about 70\.8 GiB"):
        vo.render_gbuffer(scene, scene.camera((20000, 20000)))
    with pytest.raises(ValueError, match=r"of 4 layers needs about .* reduce the camera's size or layers"):
        vo.render_gbuffer(scene, scene.camera((20000, 20000)), layers=4)
    assert time.perf_counter() - t0 < REFUSAL_SECONDS


def test_a_request_that_fits_runs_unchanged(monkeypatch):
    scene = vo.scenes.slab()
    cam = vo.Camera.look_at((0, 3, 0), (0, 0, 0), up=(0, 0, -1), size=(8, 6), ortho_height=2.0)
    monkeypatch.delenv(_memory.ENV_LIMIT, raising=False)
    free = vo.render_gbuffer(scene, cam)
    monkeypatch.setenv(_memory.ENV_LIMIT, str(10 << 20))         # 10 MiB: plenty for 48 pixels
    tight = vo.render_gbuffer(scene, cam)
    np.testing.assert_array_equal(free.depth, tight.depth)
    np.testing.assert_array_equal(free.normal, tight.normal)


def test_compare_is_refused_before_any_work(monkeypatch, tmp_path):
    from vobscure.experiments.compare import compare

    monkeypatch.setenv(_memory.ENV_LIMIT, str(LIMIT))
    t0 = time.perf_counter()
    with pytest.raises(MemoryBudgetError, match=r"comparing on a 20000 x 20000 image needs about .* GiB "
                                                r"\(\d+ bytes a pixel.*reduce size \(--size\)"):
        compare("cornell_box", size=(20000, 20000), cache=False, out=tmp_path / "out")
    with pytest.raises(MemoryBudgetError, match=r"comparing on a 4000 x 3000 image"):
        compare("cornell_box", size=(4000, 3000), frames=3, schedules="white,rotate", cache=False, write=False)
    assert time.perf_counter() - t0 < REFUSAL_SECONDS
    assert not (tmp_path / "out").exists()


def test_the_compare_estimate_grows_with_what_is_kept():
    base = dict(references=("screen", "ao"), configs=5, pixels=256 * 256)
    need = _memory.compare_need(**base).bytes(256 * 256)
    for more in (dict(radii=3), dict(layers=4), dict(frames=8, frame_configs=10), dict(configs=9),
                 dict(references=("screen", "ao", "volumetric"))):
        assert _memory.compare_need(**{**base, **more}).bytes(256 * 256) > need, more


def test_compare_with_frames_runs_under_the_guard(monkeypatch):
    from vobscure.experiments.compare import compare

    monkeypatch.setenv(_memory.ENV_LIMIT, str(LIMIT))
    res = compare("slab", size=(12, 12), methods="line:3", references=("screen",), frames=2, quick=True,
                  cache=False, write=False)
    assert res.rows and res.summary["temporal"]


@pytest.mark.parametrize("command", ["render", "compare"])
def test_the_command_refuses_a_huge_size_in_one_line(command, monkeypatch, tmp_path, capsys):
    monkeypatch.setenv(_memory.ENV_LIMIT, str(LIMIT))
    argv = [command, "--size", "20000", "20000", "--out", str(tmp_path / "out"), "--quiet"]
    if command == "render":
        argv += ["--rays", "2"]
    else:
        argv += ["--no-cache"]
    t0 = time.perf_counter()
    status = cli.main(argv)
    seconds = time.perf_counter() - t0
    captured = capsys.readouterr()
    assert status == 2 and captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith(f"vobscure {command}: error: ")
    assert "20000 x 20000" in lines[0] and "needs about" in lines[0] and "16 GiB are available" in lines[0]
    assert "reduce" in lines[0] and "--size" in lines[0] and "at most about" in lines[0]
    assert seconds < REFUSAL_SECONDS
    assert not any(p.suffix in (".npz", ".png") for p in tmp_path.rglob("*"))


def test_the_estimate_command_refuses_before_the_first_estimate(monkeypatch, tmp_path, capsys):
    depth = np.full((48, 64), 3.0, dtype=np.float32)
    for k in range(3):
        np.save(tmp_path / f"frame_{k}.npy", depth)
    out = tmp_path / "out"
    out.mkdir()
    argv = ["estimate", "--depth", str(tmp_path / "frame_*.npy"), "--fov", "40", "--radius", "0.5", "--quiet",
            "--flicker-reference", "64", "--out", str(out)]
    monkeypatch.setenv(_memory.ENV_LIMIT, str(100_000))      # 100 kB: less than three frames' work
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("vobscure estimate: error: estimating 3 frame(s) of 64 x 48 "
                                               "with a flicker reference needs about"), err
    assert "reduce the frames given (--depth) or --flicker-reference 0" in err[0]
    assert not any(out.iterdir())
    monkeypatch.setenv(_memory.ENV_LIMIT, str(1 << 30))
    assert cli.main(argv) == 0 and len(list(out.iterdir())) == 3


# --------------------------------------------------------------------------- the models
@pytest.fixture(scope="module")
def cornell():
    scene = vo.scenes.cornell_box()
    scene.tracer  # noqa: B018 - the Embree scene is built outside the measured calls
    return scene


@pytest.mark.parametrize("n", [48, 80])
def test_the_models_do_not_under_estimate_measured_peaks(cornell, n):
    cam = cornell.camera((n, n))
    r = 0.1 * cornell.extent
    pixels = n * n
    ratios = {}
    gb, peak = _peak(lambda: vo.render_gbuffer(cornell, cam))
    ratios["gbuffer"] = _memory.gbuffer_need(1).bytes(pixels) / peak
    _, peak = _peak(lambda: vo.render_gbuffer(cornell, cam, layers=3))
    ratios["layers=3"] = _memory.gbuffer_need(3).bytes(pixels) / peak
    _, peak = _peak(lambda: (gb.hits, gb.world_position, gb.world_normal, gb.world_geometric_normal,
                             gb.position, gb.geometric_normal))
    ratios["lazy"] = _memory.lazy_images_need().bytes(pixels) / peak
    for quantity, kw in (("ao", dict(rays=64)), ("volumetric", dict(samples=64))):
        _, peak = _peak(lambda: vo.ground_truth(cornell, gb, quantity=quantity, radius=r, **kw))
        ratios[quantity] = _memory.reference_need(quantity).bytes(pixels) / peak
    _, peak = _peak(lambda: vo.vo_reference(gb, radius=r, samples=800))
    ratios["screen"] = _memory.reference_need("screen").bytes(pixels) / peak
    for name, fn in (("gtao", lambda: vo.gtao(gb, radius=r)), ("vbao", lambda: vo.vbao(gb, radius=r, thickness=r)),
                     ("point", lambda: vo.vo_point(gb, radius=r, samples=33))):
        _, peak = _peak(fn)
        ratios[name] = _memory.estimator_need().bytes(pixels) / peak
    low = {k: round(v, 2) for k, v in ratios.items() if v < LEAST_RATIO}
    assert not low, f"estimate / measured peak below {LEAST_RATIO} at {n} x {n}: {low}"


def test_the_compare_model_covers_a_whole_job(cornell, tmp_path):
    from vobscure.experiments.compare import compare

    n, refs = 48, ("screen", "ao")
    compare(cornell, size=(16, 16), methods="line:5", references=refs, quick=True, cache=False,
            out=tmp_path / "warm", suggest=False)           # the first call's imports are no request's memory
    _, peak = _peak(lambda: compare(cornell, size=(n, n), methods="point:12,line:5,gtao:3", references=refs,
                                    repeats=1, rays=32, screen_samples=128, cache=False, out=tmp_path / "o",
                                    suggest=False))
    need = _memory.compare_need(references=refs, configs=3, pixels=n * n)
    assert need.bytes(n * n) / peak >= LEAST_RATIO


def test_the_estimate_model_covers_the_command(cornell, tmp_path):
    n = 96
    cam = cornell.camera((n, n))
    depth = vo.render_gbuffer(cornell, cam).depth.astype(np.float32)
    for k in range(3):
        np.save(tmp_path / f"frame_{k}.npy", depth)
    fov = str(cam.to_dict()["fov_y"])
    for frames, extra in ((1, []), (3, ["--flicker-reference", "64"])):
        out = tmp_path / f"out{frames}"
        out.mkdir()
        pattern = "frame_0.npy" if frames == 1 else "frame_*.npy"
        argv = ["estimate", "--depth", str(tmp_path / pattern), "--fov", fov, "--radius", "0.5", "--quiet",
                "--out", str(out / "v.npy" if frames == 1 else out), *extra]
        assert cli.main(argv) == 0                               # the first call's imports
        status, peak = _peak(lambda: cli.main(argv))
        assert status == 0
        need = _memory.estimate_job_need(frames, flicker_reference=bool(extra))
        assert need.bytes(n * n) / peak >= LEAST_RATIO, (frames, need.bytes(n * n) / peak)


# --------------------------------------------------------------------------- from_arrays
def _wave_depth(H, W, background=True):
    yy, xx = np.mgrid[0:H, 0:W] / max(H, W)
    depth = (4 + 0.5 * np.sin(6 * xx) * np.cos(5 * yy)).astype(np.float32)
    if background:
        depth[:, : W // 8] = np.inf
        depth[H // 3: H // 3 + 2, W // 2:] = np.inf     # a thin gap: one-sided differences around it
    return depth


@pytest.mark.parametrize("size", [(7, 1), (9, 3), (31, 65), (40, 130)])
def test_normals_derived_in_bands_equal_the_whole_image_bit_for_bit(size, monkeypatch):
    W, H = size
    cams = (vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(W, H), fov_y=40),
            vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(W, H), ortho_height=2.0))
    depth = _wave_depth(H, W).astype(np.float64)
    covered = np.isfinite(depth)
    for cam in cams:
        monkeypatch.setattr(convert, "NORMAL_BAND_ROWS", 1 << 20)          # one band: the whole image
        whole, k_whole = convert.normals_from_depth(cam, depth, covered)
        for rows in (1, 2, 3, 5, 64):
            monkeypatch.setattr(convert, "NORMAL_BAND_ROWS", rows)
            banded, k = convert.normals_from_depth(cam, depth, covered)
            assert k == k_whole
            np.testing.assert_array_equal(banded, whole)


def test_from_arrays_in_bands_equals_one_band_for_distance_depth(monkeypatch):
    H, W = 70, 50
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(W, H), fov_y=40)
    depth = _wave_depth(H, W)
    monkeypatch.setattr(convert, "NORMAL_BAND_ROWS", 1 << 20)
    whole = vo.GBuffer.from_arrays(depth, camera=cam, depth_kind="distance")
    monkeypatch.setattr(convert, "NORMAL_BAND_ROWS", 4)
    banded = vo.GBuffer.from_arrays(depth, camera=cam, depth_kind="distance")
    np.testing.assert_array_equal(banded.depth, whole.depth)
    np.testing.assert_array_equal(banded.normal, whole.normal)
    assert banded.normal.dtype == np.float32


@pytest.mark.parametrize("with_normals", [False, True])
def test_from_arrays_peak_stays_near_its_output(with_normals):
    n = 1024
    cam = vo.Camera.look_at((0, 0, 5), (0, 0, 0), size=(n, n), fov_y=40)
    depth = _wave_depth(n, n)
    normal = None
    if with_normals:
        normal = np.zeros((n, n, 3), np.float32)
        normal[..., 2] = -1.0
    gb, peak = _peak(lambda: vo.GBuffer.from_arrays(depth, normal, camera=cam))
    out = gb.depth.nbytes + gb.normal.nbytes + gb.valid.nbytes
    assert peak / out < FROM_ARRAYS_PEAK_RATIO, f"peak {peak / out:.2f} x the output"
