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
TINY = ["compare", "--scene", "crease", "--size", "24", "24", "--repeats", "1", "--rays", "32",
        "--volume-samples", "64", "--screen-samples", "128", "--quiet"]
FILES = ("results.csv", "results.md", "summary.json", "tradeoff.png", "gallery.png", "provenance.json")


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


def test_files_and_rows(first_run):
    _, out, _ = first_run
    # no temporary files left; beside the set only its manifest and the folder's lock
    assert sorted(p.name for p in out.iterdir()) == sorted(FILES + (".compare.files.json", ".vobscure.lock"))
    rows = _rows(out / "results.csv")
    assert [(r["method"], r["samples"]) for r in rows] == [("line", "5"), ("point", "12"), ("area", "1")]
    # costs: the registry's, per method (points 4 texels a tap, lines 1, area 18 per lookup)
    assert [(int(r["taps_per_pixel"]), int(r["texels_per_pixel"])) for r in rows] == [(5, 5), (12, 48), (1, 18)]
    for r in rows:
        assert float(r["seconds"]) > 0
        # each VO estimator is scored against the world-space VO, its own quantity's reference
        assert r["quantity"] == "ball VO" and r["own_reference"] == "volumetric"
        assert float(r["own_rmse"]) == float(r["volumetric_rmse"])
        # the decomposition's total is the error against AO, and its sampling term the error
        # against the screen-space reference (same pixels here: none is background)
        assert float(r["total_error_rmse"]) == pytest.approx(float(r["ao_rmse"]), rel=1e-12)
        assert float(r["sampling_error_rmse"]) == pytest.approx(float(r["screen_rmse"]), rel=1e-12)
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["methods"] == ["line:5", "point:12", "area:1"]
    assert (out / "tradeoff.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "results.md").read_text()
    assert "## Verdict" in md and "ao_rmse (model error)" in md and "volumetric_rmse (model error)" not in md
    summary = json.loads((out / "summary.json").read_text())
    assert summary["text"] and summary["text"][0].startswith("Against the ray-cast world-space VO")


def test_every_row_carries_flip_per_reference(first_run):
    _, out, _ = first_run
    rows = _rows(out / "results.csv")
    for r in rows:
        for ref in ("screen", "volumetric", "ao"):
            assert 0 < float(r[f"{ref}_flip"]) < 1
    header = next(line for line in (out / "results.md").read_text().splitlines() if line.startswith("| label"))
    assert "| screen_flip |" in header and "ao_flip (model error)" in header
    assert C.METRICS[-1] == "flip"


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
    after = {p.name for p in out.iterdir() if not p.name.startswith(".")}
    assert after == set(FILES)                       # nothing partial beside them
    assert not [p for p in out.iterdir() if p.name.endswith(".part")]
    # the set is replaced as a whole or not at all: every file is the previous run's
    assert {name: (out / name).read_bytes() for name in FILES} == before


def test_only_requested_references_are_computed(tmp_path, monkeypatch):
    from vobscure.experiments import cache, sweeps

    calls = []
    real_screen, real_truth = cache.screen_reference_cached, cache.ground_truth_cached
    monkeypatch.setattr(cache, "screen_reference_cached",
                        lambda *a, **k: calls.append("screen") or real_screen(*a, **k))
    monkeypatch.setattr(cache, "ground_truth_cached",
                        lambda *a, **k: calls.append(k["quantity"]) or real_truth(*a, **k))
    res = C.compare("slab", size=(16, 16), methods="line:5,point:12", references=("screen",), quick=True,
                    cache=False, progress=False, out=tmp_path, plots=False)
    assert calls == ["screen"]                  # once, shared by both configurations
    assert sweeps._MEMO._data == {}              # the sweep's memory is freed afterwards
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
        # frames that change are perceptibly different to FLIP (0 only for identical frames)
        assert 0 < row["flicker_flip"] <= 1


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


def test_cli_errors_name_the_argument(capsys, tmp_path):
    assert main(["compare", "--methods", "line:x", "--out", str(tmp_path)]) == 2
    assert "--methods" in capsys.readouterr().err
    assert main(["compare", "--methods", "cone:3", "--out", str(tmp_path)]) == 2
    assert "expected one of point, line, area, reference" in capsys.readouterr().err
    assert main(["compare", "--camera", "1,2,3", "--out", str(tmp_path)]) == 2
    assert "--camera" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_help_lists_the_registry(capsys):
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    out = capsys.readouterr().out
    for name in vo.methods.names():
        assert f"\n  {name} (" in out


# --------------------------------------------------------------------------- the verdict
def _r(label, seconds, taps, rmse, ref="volumetric", radius=0.5, **terms):
    method = label.split(":")[0]
    return dict(label=label, method=method, samples=int(label.split(":")[1]), radius=radius, seconds=seconds,
                taps_per_pixel=taps, own_reference=ref, own_rmse=rmse, volumetric_rmse=rmse,
                **{f"{t}_error_rmse": v for t, v in terms.items()})


ROWS = [_r("line:5", 0.004, 5, 0.30), _r("line:9", 0.006, 9, 0.26), _r("point:12", 0.03, 12, 0.29),
        _r("point:33", 0.07, 32, 0.20), _r("area:1", 0.02, 1, 0.35)]


def test_verdict_fronts_and_the_cheapest_configuration_meeting_the_target():
    v = C.verdict(ROWS)
    g = v["groups"][0]
    assert g["best"] == "point:33" and g["target_rmse"] == pytest.approx(1.5 * 0.20)
    assert g["front_time"] == ["line:5", "line:9", "point:33"]
    assert g["front_taps"] == ["area:1", "line:5", "line:9", "point:33"]
    assert g["cheapest_time"] == "line:5" and g["cheapest_taps"] == "line:5"     # 0.30 <= 0.30
    g = C.verdict(ROWS, target_rmse=0.27, budget_ms=10)["groups"][0]
    assert g["cheapest_time"] == "line:9" and g["cheapest_taps"] == "line:9" and g["best_in_budget"] == "line:9"
    g = C.verdict(ROWS, target_rmse=0.26)["groups"][0]                   # met exactly counts as met
    assert g["cheapest_time"] == "line:9"
    g = C.verdict(ROWS, target_rmse=0.1, budget_ms=1)["groups"][0]
    assert g["cheapest_time"] is None and g["best_in_budget"] is None
    assert any("No configuration reaches RMSE 0.1000" in s for s in C.verdict(ROWS, target_rmse=0.1)["text"])


def test_verdict_names_the_dominant_term_and_the_measured_thickness():
    rows = [_r("line:9", 0.006, 9, 0.33, sampling=0.03, screen=0.32, model=0.19)]
    trials = [dict(label="line:9", radius=0.5, factor=f, thickness=f * 0.5, volumetric_rmse=e,
                   volumetric_bias=0.0, seconds=0.006, baseline_rmse=0.33)
              for f, e in ((0.25, 0.11), (0.5, 0.15), (1.0, 0.22), (2.0, 0.31))]
    v = C.verdict(rows, thickness_trials=trials)
    assert v["dominant"][0]["dominant"] == "screen"
    text = " ".join(v["text"])
    assert "the screen-space model error dominates" in text
    assert "--thickness 0.125" in text and "67% lower" in text
    rows = [_r("line:9", 0.006, 9, 0.2, sampling=0.15, screen=0.05, model=0.01)]
    assert C.verdict(rows)["dominant"][0]["dominant"] == "sampling"


def test_verdict_scores_methods_only_against_their_own_reference():
    rows = ROWS + [_r("gtao:3", 0.01, 18, 0.05, ref="ao")]
    groups = {g["reference"]: g for g in C.verdict(rows)["groups"]}
    assert set(groups) == {"volumetric", "ao"}
    assert groups["volumetric"]["best"] == "point:33"        # the AO method is not in the VO ranking
    assert groups["ao"]["front_time"] == ["gtao:3"]


def test_default_suggestion_on_a_thin_walled_scene(tmp_path):
    """The Cornell box's walls are thin: the screen-space term dominates and a thickness of
    the order of the walls' (0.25 R = 0.09 here, walls 0.1) lowers the error against the
    world-space VO, measured, not guessed."""
    res = C.compare("cornell_box", size=(32, 32), methods="line:9", quick=True, cache=False, progress=False,
                    write=False)
    v = res.summary
    assert v["dominant"][0]["dominant"] == "screen"
    best = v["thickness"]["best"]
    assert best["volumetric_rmse"] < 0.8 * best["baseline_rmse"]
    assert any(s.startswith("Thickness model") and "Use --thickness" in s for s in v["text"])


def test_verdict_also_ranks_the_sampling_error_alone():
    """Against the world-space VO every estimator sits on the same screen-space floor; against
    the converged screen-space VO the sampling error alone separates them."""
    rows = [dict(_r("line:5", 0.004, 5, 0.32), screen_rmse=0.045), dict(_r("point:33", 0.07, 32, 0.33),
                                                                       screen_rmse=0.023)]
    groups = {g["error"]: g for g in C.verdict(rows)["groups"]}
    assert groups["own_rmse"]["reference"] == "volumetric" and groups["own_rmse"]["best"] == "line:5"
    assert groups["screen_rmse"]["reference"] == "screen" and groups["screen_rmse"]["best"] == "point:33"
    assert groups["screen_rmse"]["front_time"] == ["line:5", "point:33"]
    assert groups["screen_rmse"]["cheapest_time"] == "point:33"        # 0.045 > 1.5 x 0.023


def test_compare_on_a_users_gbuffer_uses_the_screen_reference_only(tmp_path):
    """A frame from elsewhere (here: a rendered one passed as a GBuffer): no geometry, so the
    only reference is the converged screen-space VO, and the verdict says so."""
    gb = vo.render_gbuffer(vo.scenes.crease(), vo.scenes.crease().camera((20, 16)))
    res = C.compare(gb, name="frame", methods="line:5,point:12", quick=True, cache=False, out=tmp_path,
                    plots=False)
    assert res.provenance["references"] == ["screen"] and res.provenance["scene"] == "frame"
    assert res.summary["text"][0].startswith("A G-buffer without its scene")
    assert {r["own_reference"] for r in res.rows} == {"screen"}
    # the same numbers as the scene's own run of the same view
    again = C.compare("crease", camera=gb.camera, methods="line:5,point:12", references=("screen",),
                      quick=True, cache=False, write=False, radii=[res.rows[0]["radius"]])
    assert [r["screen_rmse"] for r in res.rows] == [r["screen_rmse"] for r in again.rows]
    with pytest.raises(ValueError, match="need the scene's geometry"):
        C.compare(gb, methods="line:5", references=("screen", "ao"), quick=True, cache=False, write=False)
    with pytest.raises(ValueError, match="orbit"):
        C.compare(gb, methods="line:5", orbit=3, quick=True, cache=False, write=False)


def test_cli_compare_on_a_frame_file(tmp_path, capsys):
    """`vobscure compare --gbuffer frame.exr --fov ...`: a renderer's frame read from EXR, the
    screen-space reference only, the same rows as compare() on the G-buffer itself."""
    from vobscure import io as vio

    cam = vo.Camera.look_at((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), size=(20, 16), fov_y=50.0)
    scene = vo.scenes.crease()
    view = vo.Camera.look_at((2.0, 1.5, 2.5), (0.4, 0.2, 0.0), size=(20, 16), fov_y=50.0)
    gb = vo.render_gbuffer(scene, view)
    vio.write_gbuffer(tmp_path / "frame.exr", gb)
    out = tmp_path / "out"
    assert main(["compare", "--gbuffer", str(tmp_path / "frame.exr"), "--fov", "50", "--methods", "line:5",
                 "--quick", "--no-cache", "--out", str(out), "--radius", "0.3"]) == 0
    assert "A G-buffer without its scene" in capsys.readouterr().out
    rows = _rows(out / "results.csv")
    assert [r["label"] for r in rows] == ["line:5"] and rows[0]["own_reference"] == "screen"
    # the view-space data do not depend on the pose: the fov camera at the origin sees the same frame
    direct = C.compare(vo.GBuffer.from_arrays(gb.depth, gb.normal, camera=cam), methods="line:5", radii=[0.3],
                       quick=True, cache=False, write=False)
    assert float(rows[0]["screen_rmse"]) == pytest.approx(direct.rows[0]["screen_rmse"], rel=1e-6)
    assert main(["compare", "--gbuffer", str(tmp_path / "frame.exr"), "--out", str(out)]) == 2
    assert "--fov, --intrinsics or --projection" in capsys.readouterr().err


def test_verdict_decomposes_only_vo_estimators_and_recommends_only_real_gains():
    rows = [dict(_r("gtao:2", 0.07, 12, 0.12, ref="ao", sampling=0.45, screen=0.32, model=0.19), quantity="cosine AO"),
            dict(_r("line:9", 0.009, 9, 0.317, sampling=0.034, screen=0.32, model=0.19), quantity="ball VO")]
    v = C.verdict(rows)
    assert [d["label"] for d in v["dominant"]] == ["line:9"] and v["dominant"][0]["dominant"] == "screen"
    trials = [dict(label="line:9", radius=0.5, factor=f, thickness=f * 0.5, volumetric_rmse=e, volumetric_bias=0.0,
                   seconds=0.006, baseline_rmse=0.0217) for f, e in ((0.25, 0.31), (2.0, 0.02169))]
    text = " ".join(C.verdict(rows, thickness_trials=trials)["text"])
    assert "no thickness beats none" in text and "Use --thickness" not in text


def test_verdict_calls_a_poor_best_a_poor_fit():
    # the best of ROWS (0.20) is at the threshold: nothing called out
    assert not any("poor fit" in s for s in C.verdict(ROWS)["text"])
    worse = [_r("line:9", 0.006, 9, 0.33), _r("ren:1", 0.02, 0, 0.66, ref="sky")]
    text = {s.split(":")[0]: s for s in C.verdict(worse)["text"]}
    vo_text = next(s for s in text.values() if "world-space VO" in s)
    sky_text = next(s for s in text.values() if "ray-cast sky" in s)
    assert "poor fit: even the best is off by 0.33" in vo_text and "error split below" in vo_text
    assert "poor fit: even the best is off by 0.66" in sky_text and "object-space model" in sky_text


def test_compare_refuses_a_view_that_sees_nothing():
    away = vo.Camera.look_at((0, 0, 20), (0, 0, 40), size=(8, 8), fov_y=40)
    with pytest.raises(ValueError, match="sees none of 'slab'"):
        vo.experiments.compare.compare("slab", camera=away, methods="line:5", quick=True, cache=False, write=False)


def test_a_view_of_one_flat_wall_is_warned_about_in_the_verdict():
    # the slab from straight above sees its top face only: one plane, one depth
    down = vo.Camera.look_at((0, 5, 0), (0, 0, 0), (0, 0, -1), size=(12, 12), ortho_height=2.0)
    res = vo.experiments.compare.compare("slab", camera=down, methods="line:5", quick=True, cache=False,
                                         write=False, radii=0.3)
    warnings = res.summary["view_warnings"]
    assert any("one plane" in w for w in warnings)
    assert res.summary["text"][:len(warnings)] == warnings          # said first
    assert res.provenance["view"]["coverage"] == 1.0 and res.provenance["view"]["chosen_by"] == "the caller"
    good = vo.experiments.compare.compare("cornell_box", size=(24, 24), methods="line:5", quick=True, cache=False,
                                          write=False, radii=0.3)
    assert good.summary["view_warnings"] == [] and good.provenance["view"]["chosen_by"] == "the scene's own view"


def test_thin_feature_band_is_reported_beside_the_whole_frame(tmp_path):
    res = C.compare("cornell_box", size=(32, 32), methods="line:5", references=("screen", "volumetric"),
                    quick=True, cache=False, out=tmp_path, plots=False, suggest=False, repeats=1)
    (row,) = res.rows
    radius = row["radius"]
    gb = vo.render_gbuffer(vo.scenes.cornell_box(), vo.scenes.cornell_box().camera((32, 32)))
    band = vo.metrics.thin_feature_mask(gb, radius=radius)
    assert 0 < band.sum() < 0.5 * gb.valid.sum()
    # the band's error, by hand from the images compare kept
    est, ref = res.images[(radius, "line:5")], res.references[radius]["volumetric"]
    use = band & np.isfinite(est) & np.isfinite(ref)
    d = est[use] - ref[use]
    assert row["thin_pixels"] == use.sum()
    assert row["own_thin_rmse"] == pytest.approx(np.sqrt(np.mean(d * d)), rel=1e-12)
    assert row["own_thin_bias"] == pytest.approx(np.mean(d), rel=1e-12)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["thin_band"] == [dict(radius=radius, pixels=int(band.sum()),
                                         fraction=pytest.approx(band.sum() / gb.valid.sum()))]
    (sentence,) = [t for t in summary["text"] if t.startswith("Thin-feature band")]
    assert f"{row['own_thin_rmse']:.4f}" in sentence and f"{row['own_rmse']:.4f}" in sentence
    csv_row, = _rows(tmp_path / "results.csv")
    assert float(csv_row["own_thin_rmse"]) == pytest.approx(row["own_thin_rmse"], rel=1e-12)


# --------------------------------------------------------------------------- thickness from layers
#: The methods of the layered comparison: four that read layers, two that do not.
LAYERED_METHODS = "point:12,line:5,gtao:2,vbao:2,area:1,sao:8"
#: Their registry's answer, written out by hand: which read thickness="layers".
READS_LAYERS = {"point": True, "line": True, "gtao": True, "vbao": True, "area": False, "sao": False}


@pytest.fixture(scope="module")
def layered_runs(tmp_path_factory):
    """The thin-occluder scene at 24 x 24 with and without thickness="layers" (K = 2), sharing a
    reference cache: thin legs, bars and a sheet in front of a floor and a wall."""
    base = tmp_path_factory.mktemp("layers")
    kw = dict(size=(24, 24), methods=LAYERED_METHODS, quick=True, suggest=False, repeats=1,
              cache=base / "cache", references=("screen", "volumetric", "ao", "obscurance"))
    with_layers = C.compare("thin_occluders", thickness="layers", layers=2, out=base / "layers", **kw)
    without = C.compare("thin_occluders", out=base / "plain", plots=False, **kw)
    return with_layers, without, base / "layers"


def test_thickness_layers_reaches_the_methods_that_read_layers(layered_runs):
    res, plain, _ = layered_runs
    scene = vo.scenes.thin_occluders()
    camera = vo.Camera.from_dict(res.provenance["camera"])
    layered_gb = vo.render_gbuffer(scene, camera, layers=2)
    for row, base in zip(res.rows, plain.rows):
        reads = READS_LAYERS[row["method"]]
        assert row["thickness"] == ("layers" if reads else None) and row["layers"] == (2 if reads else 0)
        key = (row["radius"], row["label"])
        image, image_plain = res.images[key], plain.images[key]
        if reads:
            # the legs, bars and sheet are seen: the layers open what a depth buffer closes
            assert np.nanmax(np.abs(image - image_plain)) > 0.1, row["label"]
            assert "sampling_error_rmse" not in row        # no split by cause against the single-depth VO
        else:
            np.testing.assert_array_equal(image, image_plain)   # runs as without a thickness
            assert "sampling_error_rmse" in row
    # an independent call on a G-buffer peeled to K = 2 gives the same images, bit for bit
    radius = res.rows[0]["radius"]
    np.testing.assert_array_equal(res.images[(radius, "line:5")],
                                  vo.vo_line(layered_gb, radius=radius, samples=5, thickness="layers", seed=0))
    np.testing.assert_array_equal(res.images[(radius, "gtao:2")],
                                  vo.gtao(layered_gb, radius=radius, slices=2, steps=3, thickness="layers", seed=0))
    # the references read no layers: the same entries of the cache serve both runs
    assert all(all(h.values()) for h in plain.provenance["cache_hits"].values())
    for name, image in res.references[radius].items():
        np.testing.assert_array_equal(image, plain.references[radius][name])


def test_thickness_layers_is_recorded_and_explained(layered_runs):
    res, plain, out = layered_runs
    prov = json.loads((out / "provenance.json").read_text())
    assert prov["thickness"] == "layers" and prov["layers"] == 2 and plain.provenance["layers"] is None
    (stage,) = [s for s in prov["stages"] if s["stage"].startswith("G-buffer with")]
    assert stage["stage"] == "G-buffer with 2 layers" and stage["seconds"] > 0 and stage["status"] == "computed"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["layers"]["with_layers"] == ["point:12", "line:5", "gtao:2", "vbao:2"]
    assert summary["layers"]["without_layers"] == ["area:1", "sao:8"]
    (sentence,) = [t for t in summary["text"] if t.startswith("Thickness from layers")]
    assert "K = 2" in sentence and "area:1, sao:8 take no layers" in sentence and "'screen') has no layers" in sentence
    # the sampling-error ranking against the single-depth screen-space VO holds no layered row
    (sampling,) = [g for g in summary["groups"] if g["error"] == "screen_rmse"]
    assert sampling["best"] == "area:1" and sampling["front_time"] == ["area:1"]
    assert all(d["label"] == "area:1" for d in summary["dominant"])
    md = (out / "results.md").read_text()
    assert "thickness: layers (K = 2" in md and "| label | thickness | layers |" in md
    rows = _rows(out / "results.csv")
    assert [(r["thickness"], r["layers"]) for r in rows] == [("layers", "2")] * 4 + [("", "0")] * 2
    # with the layers the thin geometry stops darkening what lies behind it
    line, line_plain = (next(r for r in x.rows if r["label"] == "line:5") for x in (res, plain))
    assert line["volumetric_rmse"] < 0.5 * line_plain["volumetric_rmse"]


def test_a_numeric_thickness_still_does_not_reach_gtao(tmp_path):
    """GTAO takes only the layers as its thickness: with a number the row says it ran without,
    and its image is the one without a thickness; the lines take the number."""
    kw = dict(size=(16, 16), methods="gtao:2,line:5", references=("screen",), quick=True, cache=False,
              write=False, suggest=False, radii=0.4)
    res, plain = C.compare("crease", thickness=0.2, **kw), C.compare("crease", **kw)
    gtao, line = res.rows
    assert gtao["thickness"] is None and gtao["layers"] == 0 and line["thickness"] == 0.2
    np.testing.assert_array_equal(res.images[(0.4, "gtao:2")], plain.images[(0.4, "gtao:2")])
    assert not np.array_equal(res.images[(0.4, "line:5")], plain.images[(0.4, "line:5")])


def test_layers_options_are_checked(tmp_path):
    kw = dict(size=(8, 8), methods="line:5", references=("screen",), quick=True, cache=False, write=False)
    with pytest.raises(ValueError, match="thickness must be a positive number .* or 'layers'.*'fat'"):
        C.compare("slab", thickness="fat", **kw)
    with pytest.raises(ValueError, match="layers must be an integer >= 2, got 1"):
        C.compare("slab", thickness="layers", layers=1, **kw)
    with pytest.raises(ValueError, match="only thickness='layers' reads"):
        C.compare("slab", layers=3, **kw)
    gb = vo.render_gbuffer(vo.scenes.slab(), vo.scenes.slab().camera((8, 8)))
    with pytest.raises(ValueError, match="gbuffer.intervals is None"):
        C.compare(gb, thickness="layers", **kw)


def test_a_frame_with_intervals_reads_its_own_layers(tmp_path):
    scene = vo.scenes.thin_occluders()
    gb = vo.render_gbuffer(scene, scene.camera((16, 16)), layers=2)
    res = C.compare(gb, methods="line:5,area:1", thickness="layers", quick=True, cache=False, write=False,
                    radii=0.5)
    line, area = res.rows
    assert (line["thickness"], area["thickness"]) == ("layers", None) and res.provenance["layers"] is None
    np.testing.assert_array_equal(res.images[(0.5, "line:5")],
                                  vo.vo_line(gb, radius=0.5, samples=5, thickness="layers", seed=0))
    assert any("the G-buffer's own solid intervals" in t and "'screen' is also their own reference" in t
               for t in res.summary["text"])


def test_the_sweep_keeps_one_gbuffer_per_layer_count():
    """The sweep's G-buffer of a view is keyed by its layer count too: K = 2 and K = 3 of one
    view are two renders, and the one-layer G-buffer a third."""
    from vobscure.experiments import InlineExecutor, SweepConfig, sweep

    common = dict(scene="thin_occluders", method="line", samples=5, size=(12, 12), radius=0.5,
                  references=("screen",), screen_samples=16, repeats=0)
    configs = [SweepConfig(thickness="layers", layers=2, **common), SweepConfig(thickness="layers", layers=3, **common),
               SweepConfig(**common), SweepConfig(thickness="layers", **common)]
    results = sweep(configs, executor=InlineExecutor(), keep_images=True)
    peeled = [None if r.gbuffer.intervals is None else r.gbuffer.intervals.layers.depth.shape[0] for r in results]
    assert peeled == [2, 3, None, 4]          # K = 4 by default with thickness="layers"
    assert [r.as_row()["layers"] for r in results] == [2, 3, None, 4]
    first = results[2].gbuffer
    for r in results:
        np.testing.assert_array_equal(r.gbuffer.depth, first.depth)   # the first layer is the plain G-buffer


def test_verdict_ranks_layered_rows_against_their_own_reference_only():
    """A row with thickness "layers" has another model than the single-depth screen-space VO:
    however close it comes to it, it is not in the sampling-error ranking nor split by cause."""
    terms = dict(sampling=0.01, screen=0.02, model=0.1)
    layered = dict(_r("line:5", 0.004, 5, 0.05, **terms), quantity="ball VO", screen_rmse=0.01, thickness="layers")
    plain = dict(_r("area:1", 0.002, 1, 0.30, sampling=0.05, screen=0.25, model=0.1), quantity="ball VO",
                 screen_rmse=0.05, thickness=None)
    v = C.verdict([layered, plain])
    own = next(g for g in v["groups"] if g["error"] == "own_rmse")
    (sampling,) = [g for g in v["groups"] if g["error"] == "screen_rmse"]
    assert own["best"] == "line:5" and sampling["best"] == "area:1" and sampling["front_taps"] == ["area:1"]
    assert [d["label"] for d in v["dominant"]] == ["area:1"]
    # without the mark the same row leads both
    v = C.verdict([dict(layered, thickness=None), plain])
    assert next(g for g in v["groups"] if g["error"] == "screen_rmse")["best"] == "line:5"
    assert [d["label"] for d in v["dominant"]] == ["line:5"]
