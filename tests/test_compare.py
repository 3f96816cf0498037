"""`vobscure compare`: files, columns, ranges, atomic writes, the reference cache, flicker."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import vobscure as vo
from vobscure.cli import main
from vobscure.experiments import compare as C

#: Tiny and fast: 24 x 24 pixels, few reference rays (the numbers are not the point here).
TINY = ["compare", "--scene", "crease", "--size", "24", "24", "--repeats", "1", "--rays", "32", "--samples", "64",
        "--screen-samples", "128", "--quiet"]
FILES = ("results.csv", "results.md", "tradeoff.png", "gallery.png", "provenance.json")


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def first_run(tmp_path_factory):
    base = tmp_path_factory.mktemp("compare")
    out, cache = base / "out", base / "cache"
    argv = TINY + ["--methods", "line:5,point:12,area:1", "--out", str(out), "--cache", str(cache),
                   "--reference", "screen", "volumetric", "ao"]
    assert main(argv) == 0
    return argv, out, cache


def test_files_columns_and_ranges(first_run):
    _, out, _ = first_run
    assert sorted(p.name for p in out.iterdir()) == sorted(FILES)      # no temporary files left
    rows = _rows(out / "results.csv")
    assert [(r["method"], r["samples"]) for r in rows] == [("line", "5"), ("point", "12"), ("area", "1")]
    for r in rows:
        assert float(r["seconds"]) > 0
        assert int(r["taps_per_pixel"]) == int(r["samples"])
        assert int(r["texels_per_pixel"]) == C.TEXELS_PER_SAMPLE[r["method"]] * int(r["samples"])
        for ref in ("screen", "volumetric", "ao"):
            assert 0 <= float(r[f"{ref}_rmse"]) <= 1 and 0 <= float(r[f"{ref}_mae"]) <= float(r[f"{ref}_rmse"])
            assert -1 <= float(r[f"{ref}_bias"]) <= 1 and -1 <= float(r[f"{ref}_ssim"]) <= 1
        # the decomposition's total is the error against AO, and its sampling term the error
        # against the screen-space reference (same pixels here: none is background)
        assert float(r["total_error_rmse"]) == pytest.approx(float(r["ao_rmse"]), rel=1e-12)
        assert float(r["sampling_error_rmse"]) == pytest.approx(float(r["screen_rmse"]), rel=1e-12)
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["methods"] == ["line:5", "point:12", "area:1"] and prov["primary_reference"] == "volumetric"
    assert (out / "tradeoff.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "| method |" in (out / "results.md").read_text()


def test_second_run_hits_the_cache_with_identical_numbers(first_run, tmp_path):
    argv, out, cache = first_run
    out2 = tmp_path / "again"
    argv2 = [a if a != str(out) else str(out2) for a in argv]
    assert main(argv2) == 0
    prov = json.loads((out2 / "provenance.json").read_text())
    assert all(all(h.values()) for h in prov["cache_hits"].values())
    first, second = _rows(out / "results.csv"), _rows(out2 / "results.csv")
    for a, b in zip(first, second):
        for key in a:
            if key not in ("seconds",):
                assert a[key] == b[key], key


def test_interrupted_run_keeps_the_previous_files(first_run, monkeypatch):
    argv, out, _ = first_run
    before = {name: (out / name).read_bytes() for name in FILES}

    def boom(*args, **kwargs):
        raise KeyboardInterrupt("simulated interruption while drawing")

    monkeypatch.setattr(C, "_gallery", boom)
    with pytest.raises(KeyboardInterrupt):
        main(argv)
    after = {p.name for p in out.iterdir()}
    assert after == set(FILES)                       # nothing partial beside them
    # files written before the interruption were replaced whole, the rest untouched
    assert (out / "gallery.png").read_bytes() == before["gallery.png"]
    assert (out / "provenance.json").read_bytes() == before["provenance.json"]
    assert len(_rows(out / "results.csv")) == 3      # complete, parseable


def test_only_requested_references_are_computed(tmp_path, monkeypatch):
    calls = []
    real = C._references

    def spy(*args, **kwargs):
        calls.append(args[3])
        return real(*args, **kwargs)

    monkeypatch.setattr(C, "_references", spy)
    res = C.compare("slab", size=(16, 16), methods="line:5", references=("screen",), quick=True, cache=False,
                    progress=False, out=tmp_path, plots=False)
    assert calls == [("screen",)]
    assert set(res.references[res.rows[0]["radius"]]) == {"screen"}
    assert not any(k.startswith(("volumetric", "ao", "total_error")) for k in res.rows[0])


def test_orbit_measures_flicker(tmp_path):
    res = C.compare("crease", size=(20, 20), methods="line:5,point:12", references=("screen",), orbit=3,
                    quick=True, cache=False, progress=False, out=tmp_path, plots=False)
    for row in res.rows:
        # the camera moves, so every estimate changes; the excess over the reference's own
        # change can be of either sign but never exceeds the raw change
        assert np.isfinite(row["flicker"]) and row["flicker_raw"] > 0
        assert row["flicker"] <= row["flicker_raw"]


def test_orbit_cameras_turn_about_the_target():
    cam = vo.scenes.cornell_box().camera((8, 8))
    cams = C.orbit_cameras(cam, 5, degrees=20)
    target = np.array(cam.to_dict()["target"])
    dist = [np.linalg.norm(np.array(c.to_dict()["eye"]) - target) for c in cams]
    np.testing.assert_allclose(dist, dist[2], rtol=1e-12)
    np.testing.assert_allclose(cams[2].to_dict()["eye"], cam.to_dict()["eye"], atol=1e-12)


def test_pareto_front():
    assert C.pareto_front([1, 2, 3], [3, 2, 1]).tolist() == [0, 1, 2]
    assert C.pareto_front([1, 2, 3], [1, 2, 3]).tolist() == [0]
    assert C.pareto_front([1, np.nan, 3], [2, 0, 1]).tolist() == [0, 2]


@pytest.mark.parametrize("spec, match", [("", "at least one"), ("line", "NAME:SAMPLES"),
                                         ("cone:3", "unknown method"), ("line:0", "samples"),
                                         ("line:5,line:5", "twice")])
def test_bad_methods(spec, match):
    with pytest.raises(ValueError, match=match):
        C.parse_methods(spec)


def test_cli_errors_name_the_argument(capsys, tmp_path):
    assert main(["compare", "--methods", "line:x", "--out", str(tmp_path)]) == 2
    assert "--methods" in capsys.readouterr().err
    assert main(["compare", "--camera", "1,2,3", "--out", str(tmp_path)]) == 2
    assert "--camera" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
