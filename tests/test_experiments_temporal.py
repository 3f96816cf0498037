"""The error after N frames (vobscure.experiments.temporal, compare --frames).

Behaviour checked against facts that do not depend on the code under test: a periodic noise
schedule repeats its frames exactly, so the running mean after 2P frames *is* the mean after P;
reprojection follows the surfaces (tests/test_temporal.py checks it against the renderer), so
with a moving camera the accumulated error stays below one frame's, while the history used in
place mixes other surfaces' values in (ghosting).
"""

import json

import numpy as np
import pytest

import vobscure as vo
from vobscure.experiments import temporal
from vobscure.temporal import Accumulator

#: A running mean of repeated frames agrees with the shorter one to rounding of n terms.
MEAN_ROUNDING = 1e-12


@pytest.fixture(scope="module")
def box24():
    sc = vo.scenes.cornell_box()
    return sc, vo.render_gbuffer(sc, sc.camera(size=(24, 24)))


@pytest.fixture(scope="module")
def gtao_limit(box24):
    """The expectation of randomized gtao (over slice rotation and step jitter), estimated by 128
    white-noise frames at 8 slices: the same expectation as 2 slices, a quarter of the variance."""
    _, gb = box24
    return np.mean([vo.gtao(gb, radius=0.4, slices=8, steps=3, frame=n, clip=False) for n in range(128)], axis=0)


def _rmse(a, b):
    return float(np.sqrt(np.nanmean((a - b) ** 2)))


@pytest.mark.parametrize("schedule", ["gtao", "r2"])
def test_periodic_schedule_floors_at_its_period(box24, gtao_limit, schedule):
    _, gb = box24
    P = vo.screenspace.noise.period(schedule)
    limit = gtao_limit
    acc = Accumulator("mean")
    err, images = {}, {}
    for n in range(2 * P):
        out = acc.update(vo.gtao(gb, radius=0.4, slices=2, steps=3, frame=n, schedule=schedule, clip=False), gb)
        if n + 1 in (P // 4, P // 2, P, 2 * P):
            err[n + 1], images[n + 1] = _rmse(out, limit), out
    # frames P+1 .. 2P repeat frames 1 .. P: the mean, and so any error, stops at P
    np.testing.assert_allclose(images[2 * P], images[P], atol=MEAN_ROUNDING)
    assert err[P] < err[P // 2] < err[P // 4]


def test_white_noise_keeps_improving_past_any_period(box24, gtao_limit):
    _, gb = box24
    limit = gtao_limit
    acc = Accumulator("mean")
    err = {}
    for n in range(48):
        out = acc.update(vo.gtao(gb, radius=0.4, slices=2, steps=3, frame=n, clip=False), gb)
        if n + 1 in (24, 48):
            err[n + 1] = _rmse(out, limit)
    assert err[48] < err[24]


@pytest.fixture(scope="module")
def orbit_run():
    configs = (temporal.configurations("line:3", accumulate="ema:0.2")
               + temporal.configurations("line:3", accumulate="ema:0.2", reproject=False))
    return temporal.run("cornell_box", configs, size=(40, 40), frames=12, motion="orbit", step=1.0,
                        references=("screen",), screen_samples=256)


def test_orbit_reprojection_beats_one_frame_and_in_place_ghosts(orbit_run):
    rows = orbit_run.rows
    rep = [r for r in rows if r["reproject"] and r["frame"] > 3]
    inplace = [r for r in rows if not r["reproject"] and r["frame"] > 3]
    acc_rep = np.array([r["rmse_screen"] for r in rep])
    one = np.array([r["one_frame_rmse_screen"] for r in rep])
    acc_in = np.array([r["rmse_screen"] for r in inplace])
    # paired over frames 4..12 (the same frames and noise in all three)
    assert np.all(acc_rep < one)
    assert np.all(acc_in > acc_rep)
    assert [r["disoccluded"] for r in rep][0] < 0.1


def test_run_outputs(orbit_run):
    res = orbit_run
    assert len(res.rows) == 2 * 12 and len(res.cameras) == 12 and len(res.references) == 12
    labels = [s["config"] for s in res.series]
    assert labels == ["line:3 white ema:0.2", "line:3 white ema:0.2 in-place"]
    assert all(len(s["rmse"]) == 12 and s["reference"] == "screen" for s in res.series)
    first = res.rows[0]
    assert np.isnan(first["flicker_screen"]) and np.isnan(first["flicker_flip"]) and first["frame"] == 1
    later = res.rows[-1]
    assert np.isfinite(later["flicker_flip"]) and 0 <= later["flip"] <= 1
    assert later["total_ms"] >= later["ms"] > 0
    assert any("Against the converged screen-space VO" in t for t in res.summary["text"])


def test_verdict_names_the_cheapest_that_reaches_the_target():
    class C:
        def __init__(self, label):
            self.label = label

    def rows(label, ms, errs):
        return [dict(config=label, frame=n + 1, ms=ms, own_reference="screen", quantity="vo", rmse_screen=e)
                for n, e in enumerate(errs)]

    data = rows("fast", 1.0, [0.3, 0.2, 0.1, 0.08]) + rows("slow", 5.0, [0.09, 0.08, 0.07, 0.06])
    v = temporal.temporal_verdict(data, [C("fast"), C("slow")], target_rmse=0.1)
    g = v["groups"][0]
    assert g["winner"] == "fast" and g["one_frame_winner"] == "slow"
    assert g["frames_to_target"] == {"fast": 3, "slow": 1}
    assert temporal.frames_to_target([0.3, np.nan, 0.2], 0.1) is None


@pytest.mark.parametrize("kwargs, match", [
    (dict(schedules="pink"), "schedule"), (dict(accumulate="ema:2"), "alpha"), (dict(denoise="now"), "denoise"),
])
def test_configuration_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        temporal.configurations("line:3", **kwargs)


def test_run_errors():
    with pytest.raises(ValueError, match="frames"):
        temporal.run("slab", "line:3", size=(8, 8), frames=0)
    with pytest.raises(ValueError, match="thickness"):
        temporal.run("slab", "line:3", size=(8, 8), frames=2, thickness="layers")
    cam = vo.scenes.slab().camera(size=(8, 8))
    with pytest.raises(ValueError, match="exceeds"):
        temporal.run("slab", "line:3", cameras=[cam, cam], frames=3)


def test_compare_frames_writes_the_sequence(tmp_path):
    sc = vo.scenes.cornell_box()
    path = vo.temporal.camera_path(sc.camera(size=(16, 16)), 3, "orbit")
    f = tmp_path / "cams.json"
    f.write_text(json.dumps([c.to_dict() for c in path]))
    from vobscure.cli import main

    out = tmp_path / "out"
    assert main(["compare", "--scene", "cornell_box", "--quick", "--size", "16", "16", "--methods", "gtao:1",
                 "--reference", "screen", "ao", "--cameras", str(f), "--schedule", "white,r2", "--no-cache",
                 "--quiet", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert {(e["config"], e["reference"]) for e in summary["temporal"]} == {
        ("gtao:1 white mean", "screen"), ("gtao:1 white mean", "ao"), ("gtao:1 r2 mean", "screen"),
        ("gtao:1 r2 mean", "ao")}
    assert all(len(e["rmse"]) == 3 for e in summary["temporal"])
    assert (out / "temporal.csv").read_text().count("\n") == 1 + 2 * 3
    assert (out / "temporal.png").stat().st_size > 0
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["temporal"]["motion"] == "list" and len(prov["temporal"]["cameras"]) == 3


def test_compare_frames_errors(tmp_path, capsys):
    from vobscure.cli import main

    assert main(["compare", "--scene", "slab", "--quick", "--frames", "1", "--quiet", "--no-cache",
                 "--out", str(tmp_path)]) == 2
    assert "--frames needs at least 2 frames" in capsys.readouterr().err
    gb = vo.render_gbuffer(vo.scenes.slab(), vo.scenes.slab().camera(size=(8, 8)))
    with pytest.raises(ValueError, match="G-buffer is one frame"):
        vo.experiments.compare.compare(gb, frames=3, write=False, cache=False)
