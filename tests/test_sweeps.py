"""Sweeps: configurations, results in input order, the same numbers on every executor (the
default process pool, a thread pool, a Dask local cluster), references made once and only
when asked, the reference cache, the CSV and markdown writers."""

from __future__ import annotations

import csv
import math
import pickle
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import vobscure as vo
from vobscure import _io
from vobscure.experiments import SweepConfig, SweepResult, results_to_csv, results_to_markdown, sweep
from vobscure.experiments import sweeps as S
from vobscure.experiments.cache import ReferenceCache

SMALL = dict(size=(32, 32), radius=0.5, rays=16, volume_samples=16, screen_samples=128)
ALL_REFS = ("screen", "volumetric", "ao")
SIDE_CAMERA = vo.Camera.look_at((3.0, 1.5, 2.0), (0.5, 0.3, 0.0), size=(24, 20), fov_y=50.0)


def _configs():
    # Sample patterns are built on a worker's first use of a count (about 1 s for a disk, 2 s
    # for a ball on 2 cores): the executor comparison keeps to a few cheap ones.
    return [
        SweepConfig("crease", "line", 5, references=ALL_REFS, seed=1, **SMALL),
        SweepConfig("crease", "area", 1, references=ALL_REFS, repeats=2, **SMALL),
        SweepConfig("slab", "line", 5, references=("ao",), normal_clamp=True, **SMALL),
        SweepConfig("crease", "area", 1, references=("screen", "obscurance"), thickness=0.25, **SMALL),
        SweepConfig("crease", "reference", 32, references=("screen",), camera=SIDE_CAMERA,
                    radius=0.5, rays=16, volume_samples=16, screen_samples=128),
    ]


def _numbers(results):
    """Every non-timing number of the results (NaN-safe), and the images."""
    rows = []
    for r in results:
        row = {k: v for k, v in r.as_row().items() if k not in S.TIMING_FIELDS}
        rows.append({k: ("nan" if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()})
    return rows, [r.image for r in results]


@pytest.fixture(scope="module")
def configs():
    return _configs()


@pytest.fixture(scope="module")
def threaded(configs):
    with ThreadPoolExecutor(2) as pool:
        return sweep(configs, executor=pool, progress=False, keep_images=True)


@pytest.fixture(scope="module")
def local(configs):
    return sweep(configs, progress=False, keep_images=True)     # default: local process pool


def _assert_same(a, b):
    rows_a, images_a = _numbers(a)
    rows_b, images_b = _numbers(b)
    assert rows_a == rows_b
    for x, y in zip(images_a, images_b):
        assert (x is None and y is None) or x.tobytes() == y.tobytes()


def test_default_executor_and_thread_pool_agree(threaded, local):
    _assert_same(threaded, local)


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed "
                                                            "(pip install 'vobscure[dask]')")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def test_dask_local_cluster_agrees_with_local_run(dask_client, configs, local):
    results = sweep(configs, executor=dask_client.get_executor(), progress=False, keep_images=True)
    _assert_same(results, local)
    # asked of the scheduler itself (its cached info can lag on a loaded machine)
    dask_client.wait_for_workers(2, timeout=120)
    assert len(dask_client.nthreads()) == 2


def test_results_in_input_order_with_sensible_values(configs, threaded):
    assert [r.config for r in threaded] == configs
    for c, r in zip(configs, threaded):
        assert isinstance(r, SweepResult) and set(r.errors) == set(c.references)
        assert r.seconds > 0 and len(r.seconds_runs) == c.repeats
        assert r.seconds == pytest.approx(float(np.median(r.seconds_runs)))
        assert r.image.shape == (c.size[1], c.size[0])
        assert r.pixels == int(np.isfinite(r.image).sum()) > 0
        for report in r.errors.values():
            assert report.pixels == r.pixels and 0 <= report.rmse < 1
        assert (r.decomposition is not None) == ({"screen", "volumetric"} <= set(c.references))
    assert [r.taps_per_pixel for r in threaded] == [5, 1, 5, 1, 32]
    assert [r.texels_per_pixel for r in threaded] == [5, 18, 5, 18, 128]
    assert threaded[4].camera == SIDE_CAMERA.to_dict()
    d = threaded[0].decomposition
    assert d["target"] == "ao" and d["pixels"] == threaded[0].pixels
    assert d["total_bias"] == pytest.approx(d["sampling_bias"] + d["screen_bias"] + d["model_bias"], abs=1e-12)


def test_numbers_equal_a_direct_computation(threaded):
    r = threaded[0]
    c = r.config
    scene = vo.scenes.crease()
    gb = vo.render_gbuffer(scene, scene.camera(c.size))
    est = vo.vo_line(gb, radius=0.5, samples=5, seed=1)
    screen = vo.vo_reference(gb, radius=0.5, samples=128, seed=0).value
    ao = vo.ground_truth(scene, gb, quantity="ao", radius=0.5, rays=16, seed=0, progress=False)
    assert est.tobytes() == r.image.tobytes()
    assert vo.error(est, screen) == r.errors["screen"]
    assert vo.error(est, ao.value) == r.errors["ao"]


def test_point_sampling_costs():
    c = SweepConfig("slab", "point", 8, references=("screen",), repeats=3, **SMALL)
    with ThreadPoolExecutor(1) as pool:
        (r,) = sweep([c], executor=pool, progress=False)
    assert (r.taps_per_pixel, r.texels_per_pixel, len(r.seconds_runs)) == (8, 32, 3)
    assert r.errors["screen"].pixels == r.pixels > 0 and r.decomposition is None


def test_references_made_once_and_only_when_asked(monkeypatch):
    calls = []
    real_gt, real_ref = vo.groundtruth.ground_truth, vo.screenspace.vo_reference

    def gt(*args, **kwargs):
        calls.append(kwargs["quantity"])
        return real_gt(*args, **kwargs)

    def ref(*args, **kwargs):
        calls.append("screen")
        return real_ref(*args, **kwargs)

    monkeypatch.setattr(vo.groundtruth, "ground_truth", gt)
    monkeypatch.setattr(vo.screenspace, "vo_reference", ref)
    S._MEMO.clear()
    configs = [SweepConfig("slab", m, s, references=("ao",), **SMALL)
               for m, s in (("line", 5), ("area", 1), ("line", 5))]
    configs.append(SweepConfig("slab", "line", 5, references=("ao", "screen"), seed=3, **SMALL))
    with ThreadPoolExecutor(2) as pool:
        sweep(configs, executor=pool, progress=False)
    assert sorted(calls) == ["ao", "screen"]
    assert not S._MEMO._data      # what the threads kept in this process is freed at the end


def test_reference_cache_across_sweeps(tmp_path, monkeypatch):
    cache = ReferenceCache(tmp_path)
    configs = [SweepConfig("slab", "line", 5, references=("screen", "ao"), **SMALL)]
    S._MEMO.clear()
    with ThreadPoolExecutor(1) as pool:
        first = sweep(configs, executor=pool, progress=False, cache=cache)
    assert len(list(tmp_path.glob("*.npz"))) == 2 and not S._MEMO._data

    def fail(*args, **kwargs):
        raise AssertionError("the reference was computed again")

    monkeypatch.setattr(vo.groundtruth, "ground_truth", fail)
    monkeypatch.setattr(vo.screenspace, "vo_reference", fail)
    with ThreadPoolExecutor(1) as pool:
        second = sweep(configs, executor=pool, progress=False, cache=cache)
    _assert_same(first, second)


def test_stage_seconds_of_computed_reused_and_cached_stages(tmp_path, monkeypatch, capsys):
    """Each result names the stages its task ran; a stage made by an earlier task of the
    worker, or read from the disk cache, takes 0 seconds and says so."""
    from vobscure.experiments import InlineExecutor

    slow = 0.05                              # seconds the patched reference sleeps at least
    real_ref = vo.screenspace.vo_reference

    def ref(*args, **kwargs):
        import time
        time.sleep(slow)
        return real_ref(*args, **kwargs)

    monkeypatch.setattr(vo.screenspace, "vo_reference", ref)
    cache = ReferenceCache(tmp_path)
    configs = [SweepConfig("slab", m, s, references=("screen", "ao"), repeats=1, **SMALL)
               for m, s in (("line", 5), ("area", 1))]
    S._MEMO.clear()
    first, second = sweep(configs, executor=InlineExecutor(), progress=True, cache=cache)
    keys = ["gbuffer", "reference:screen", "reference:ao", "method"]
    assert list(first.stage_seconds) == keys and list(first.stage_status) == keys
    assert set(first.stage_status.values()) == {"computed"}
    assert first.stage_seconds["reference:screen"] >= slow
    assert all(first.stage_seconds[k] > 0 for k in keys)
    # the second configuration shares the view: G-buffer and references come from memory
    assert second.stage_status == {"gbuffer": "reused", "reference:screen": "reused",
                                   "reference:ao": "reused", "method": "computed"}
    assert [second.stage_seconds[k] for k in keys[:3]] == [0.0, 0.0, 0.0]
    assert "vo_reference" in capsys.readouterr().err       # the reference's own progress bar
    S._MEMO.clear()
    (again,) = sweep(configs[:1], executor=InlineExecutor(), cache=cache)
    assert again.stage_status["reference:screen"] == again.stage_status["reference:ao"] == "cached"
    assert again.stage_seconds["reference:screen"] == 0.0
    assert again.stage_status["gbuffer"] == "computed"


def test_failures_name_the_configuration(tmp_path):
    bad = SweepConfig(str(tmp_path / "missing.obj"), "line", 5, **SMALL)
    with ThreadPoolExecutor(1) as pool, pytest.raises(FileNotFoundError) as info:
        sweep([SweepConfig("slab", "line", 5, **SMALL), bad], executor=pool, progress=False)
    assert any("missing.obj" in note for note in info.value.__notes__)


def test_config_validation_and_pickling():
    c = SweepConfig("crease", "point", 12, camera=SIDE_CAMERA.to_dict(), size=(16, 8),
                    references=["screen", "ao"])
    assert c.camera == SIDE_CAMERA.with_size((16, 8)) and c.size == (16, 8)
    assert c.references == ("screen", "ao")
    assert pickle.loads(pickle.dumps(c)) == c and hash(c) == hash(pickle.loads(pickle.dumps(c)))
    assert SweepConfig(camera=SIDE_CAMERA).size == SIDE_CAMERA.size
    assert SweepConfig().size == S.DEFAULT_SIZE
    for kwargs, name in [(dict(method="lines"), "method"), (dict(samples=0), "samples"),
                         (dict(references=("screen", "gtao")), "references"),
                         (dict(references=("ao", "ao")), "references"), (dict(radius=-1.0), "radius"),
                         (dict(seed=-1), "seed"), (dict(repeats=-1), "repeats"), (dict(rays=1), "rays"),
                         (dict(falloff="linear"), "falloff"), (dict(scene="nowhere"), "scene"),
                         (dict(camera=(0, 0, 1)), "camera"), (dict(size=(0, 4)), "size"),
                         (dict(normal_clamp=1), "normal_clamp"), (dict(thickness=0.0), "thickness")]:
        with pytest.raises(ValueError, match=name):
            SweepConfig(**kwargs)
    with pytest.raises(ValueError, match=r"configs\[1\]"):
        sweep([c, "line 9"], progress=False)
    with pytest.raises(ValueError, match="executor"):
        sweep([c], executor=object(), progress=False)
    with pytest.raises(ValueError, match="cache"):
        sweep([c], cache="/tmp", progress=False)
    assert sweep([], progress=False) == []


# ----------------------------------------------------------------------------- writers
def test_csv_round_trips_every_number(tmp_path, threaded):
    path = results_to_csv(threaded, tmp_path / "out" / "results.csv")
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(threaded)
    for row, r in zip(rows, threaded):
        want = r.as_row()
        assert row["method"] == r.config.method and int(row["samples"]) == r.config.samples
        for key in ("rmse_screen", "bias_ao", "ssim_volumetric", "sampling_rmse"):
            if key in want:
                assert float(row[key]) == want[key]        # written exactly
            else:
                assert row[key] == ""                      # not asked for by this row
    header = list(rows[0])
    assert header[:4] == ["scene", "width", "height", "method"] and header[-1] == "camera"
    # every reference's columns together, in the order of REFERENCES, whichever row asked first
    errors = [h for h in header if h.startswith("rmse_")]
    assert errors == ["rmse_screen", "rmse_volumetric", "rmse_ao", "rmse_obscurance"]
    assert header.index("pixels_obscurance") < header.index("sampling_rmse") < header.index("references")


def test_writers_are_atomic(tmp_path, threaded, monkeypatch):
    path = tmp_path / "results.csv"
    results_to_csv(threaded, path)
    before = path.read_bytes()
    real = _io.atomic_write

    def interrupted(target, write):
        def partial(fh):
            fh.write(b"scene,wid")
            raise KeyboardInterrupt
        return real(target, partial)

    from vobscure.experiments import common

    monkeypatch.setattr(common, "atomic_write", interrupted)      # the one writer of experiments
    with pytest.raises(KeyboardInterrupt):
        results_to_csv(threaded[:1], path)
    with pytest.raises(KeyboardInterrupt):
        results_to_markdown(threaded, tmp_path / "results.md")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


def test_markdown_table(tmp_path, threaded):
    text = results_to_markdown(threaded, tmp_path / "results.md")
    assert (tmp_path / "results.md").read_text() == text
    lines = text.splitlines()
    assert lines[0].startswith("Common settings:") and "falloff = constant" in lines[0]
    table = [line for line in lines if line.startswith("|")]
    assert len(table) == 2 + len(threaded)
    header = [h.strip() for h in table[0].strip("|").split("|")]
    assert "method" in header and "rmse_screen" in header and "camera" not in header
    assert table[2].split("|")[header.index("method") + 1].strip() == "line"
    with pytest.raises(ValueError, match=r"results\[0\]"):
        results_to_markdown([{"method": "line"}])


def test_the_package_attribute_is_the_sweep_function():
    """``vobscure.experiments.sweep(configs, executor=...)`` is the function of the module
    ``vobscure.experiments.sweeps``, a plain module."""
    import types

    assert vo.experiments.sweep is S.sweep and vo.experiments.SweepConfig is S.SweepConfig
    assert type(S) is types.ModuleType
    configs = [SweepConfig("slab", "line", 5, size=(8, 8), radius=0.5, references=("screen",),
                           screen_samples=32)]
    with ThreadPoolExecutor(1) as pool:
        a = vo.experiments.sweep(configs, executor=pool, progress=False)
        b = sweep(configs, executor=pool, progress=False)
    assert a[0].errors["screen"].rmse == b[0].errors["screen"].rmse


def test_sky_references_are_unbounded_ao_with_their_weighting():
    """"sky" / "sky_uniform": ray-cast AO with no distance limit, cosine / uniform weighted --
    the same numbers as ground_truth called directly, and different from AO within the radius."""
    from vobscure.experiments import InlineExecutor

    config = SweepConfig("crease", "line", 5, size=(12, 10), radius=0.2, rays=32,
                         references=("sky", "sky_uniform", "ao"))
    (res,) = sweep([config], executor=InlineExecutor(), keep_images=True)
    gb = res.gbuffer
    scene = vo.scenes.crease()
    for name, weighting in (("sky", "cosine"), ("sky_uniform", "uniform")):
        direct = vo.ground_truth(scene, gb, quantity="ao", radius=None, weighting=weighting, rays=32, seed=0)
        np.testing.assert_array_equal(res.references[name].value, direct.value)
    # the floor near the wall sees the wall beyond 0.2: unbounded AO is darker there
    assert np.nanmean(res.references["sky"].value) < np.nanmean(res.references["ao"].value)
    assert not np.array_equal(res.references["sky"].value, res.references["sky_uniform"].value)
