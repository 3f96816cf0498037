"""The thin-geometry Pareto figure: its rows, its fronts (against a brute-force dominance test)
and its equal-time verdict (on the crease in the quick profile, and on hand-made rows)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vobscure import methods
from vobscure.experiments.figures import Profile, thin_pareto
from vobscure.experiments.figures._common import read_rows, write_rows

#: The scene measured: the crease, the cheapest of the three to ray cast (20 triangles).
SCENE = "crease"


@pytest.fixture(scope="module")
def rows():
    """The quick profile's rows of the crease (32 x 32, one timed repeat)."""
    return thin_pareto.measure(Profile(quick=True), scenes=(SCENE,))


def _dominated(i, cost, err) -> bool:
    """Whether another configuration is at most as costly and as wrong as ``i``, and better in one."""
    return any(cost[j] <= cost[i] and err[j] <= err[i] and (cost[j] < cost[i] or err[j] < err[i])
               for j in range(len(cost)) if j != i)


def test_rows_have_the_columns_and_the_registrys_taps_and_references(rows):
    estimates = [r for r in rows if r["kind"] == "estimate"]
    renders = [r for r in rows if r["kind"] == "render"]
    assert [r["layers"] for r in renders] == list(thin_pareto.LAYERS)
    assert len(estimates) == len(thin_pareto.configurations(1.0, 1.0))
    for r in rows:
        assert set(thin_pareto._COLUMNS) <= set(r), sorted(set(thin_pareto._COLUMNS) - set(r))
    for r in estimates:
        spec = methods.get(r["method"])
        assert r["taps_per_pixel"] == spec.taps(r["samples"])
        assert r["reference"] == spec.reference(normal_clamp=False)
        assert 0.0 <= r["rmse"] <= 1.0 and 0.0 <= r["thin_rmse"] <= 1.0 and r["thin_pixels"] > 0
        assert abs(r["bias"]) <= r["rmse"] + 1e-12        # |mean| <= root mean square
        assert math.isclose(r["seconds_incl_layers"], r["seconds"] + r["layer_seconds"])
        # the extra layers' render is the layered G-buffer's time over the one-layer one
        render = next(x for x in renders if x["layers"] == r["layers"])
        assert math.isclose(r["layer_seconds"], render["seconds"] - renders[0]["seconds"]) if r["layers"] > 1 \
            else r["layer_seconds"] == 0.0
    # VO against the world-space VO, the horizon methods against AO, by the registry
    by_family = {r["family"]: r["reference"] for r in estimates if r["method"] != "vbao_uniform"}
    assert by_family == {"VO line": "volumetric", "VO point": "volumetric", "GTAO": "ao", "VBAO": "ao",
                         "SAO": "obscurance", "HBAO": "ao_uniform"}


def test_layered_configurations_read_the_layers(rows):
    """A layered configuration reads the interval slots: its error differs from the same
    configuration's on the depth buffer alone, and a tap reads the front and back of each slot."""
    by_label = {r["label"]: r for r in rows if r["kind"] == "estimate"}
    for head in ("line:9", "point:16", "gtao:3", "vbao:3"):
        solid = by_label[f"{head} solid"] if head.startswith(("line", "point")) else by_label[
            head if head.startswith("gtao") else f"{head} t.5R"]
        for K in (2, 4):
            layered = by_label[f"{head} L{K}"]
            assert layered["rmse"] != solid["rmse"], f"{head} L{K} reads no layers"
            assert layered["interval_slots"] >= 1
            fetch = 0 if head.startswith(("line", "point")) else 4      # bilinear depth beside the slots
            assert layered["values_per_tap"] == 2 * layered["interval_slots"] + fetch


@pytest.mark.parametrize("front, cost, err", thin_pareto.FRONTS)
def test_fronts_are_exactly_the_non_dominated_configurations(rows, front, cost, err):
    """Every row on a front is dominated by no other row; every row off it is dominated, or
    ties a front row in both cost and error."""
    sel = [r for r in rows if r["kind"] == "estimate"]
    c = [r[cost] for r in sel]
    e = [r[err] for r in sel]
    on = thin_pareto.fronts(rows, SCENE)[front]
    assert on, f"{front} is empty"
    for i, r in enumerate(sel):
        assert bool(r[front]) == (r["label"] in on)
        if r["label"] in on:
            assert not _dominated(i, c, e), f"{r['label']} is dominated but on {front}"
        else:
            assert _dominated(i, c, e) or any(c[j] == c[i] and e[j] == e[i] for j in range(len(sel))
                                             if sel[j]["label"] in on), f"{r['label']} is off {front}"
    # by cost, errors falling
    costs = [next(r[cost] for r in sel if r["label"] == k) for k in on]
    errors = [next(r[err] for r in sel if r["label"] == k) for k in on]
    assert costs == sorted(costs) and all(a > b for a, b in zip(errors, errors[1:]))


@pytest.mark.parametrize("band", [False, True])
def test_the_verdict_names_a_configuration_on_the_time_front(rows, band):
    v = thin_pareto.verdict(rows, SCENE, band=band)
    front = thin_pareto.fronts(rows, SCENE)["front_time_band" if band else "front_time"]
    assert v["best"]["label"] in front
    assert v["best"]["label"] in v["sentence"]
    assert v["best"]["seconds_incl_layers"] <= v["yardstick"]["seconds_incl_layers"]
    err = "thin_rmse" if band else "rmse"
    assert v["ratio"] == pytest.approx(v["yardstick"][err] / v["best"][err], rel=1e-12)
    assert v["cheapest"][err] <= v["yardstick"][err]


def test_the_verdict_on_hand_made_rows():
    """The yardstick at 10 ms, RMSE 0.1: 'a' (5 ms, 0.05) wins at equal time by 2x and is the
    cheapest as accurate; 'b' is more accurate but slower; 'c' cheaper but worse; against the
    yardstick's reference alone 'd' wins; without 'a' and 'd' nothing beats the yardstick."""
    def row(label, ms, e, reference="ao", layers=1):
        return dict(scene="s", kind="estimate", label=label, seconds_incl_layers=ms / 1e3, rmse=e, thin_rmse=e,
                    taps_per_pixel=1, reference=reference, layers=layers)

    rows = [row("gtao:3", 10, 0.1), row("d", 7, 0.05), row("a", 5, 0.05, "volumetric", 2), row("b", 12, 0.01),
            row("c", 2, 0.3)]                     # 'd' ties 'a' in error at more time: 'a' wins
    v = thin_pareto.verdict(rows, "s")
    assert (v["best"]["label"], v["ratio"], v["cheapest"]["label"]) == ("a", 2.0, "a")
    assert "a (5.0 ms incl. its extra layers' render): RMSE 0.050 against world-space VO, 2.0x lower than " \
        "gtao:3's 0.100 against cosine AO." in v["sentence"]
    same = thin_pareto.verdict(rows, "s", same_reference=True)      # 'a' is scored against another reference
    assert (same["best"]["label"], same["ratio"], same["cheapest"]["label"]) == ("d", 2.0, "d")
    alone = thin_pareto.verdict([rows[0], rows[3], rows[4]], "s")
    assert alone["best"]["label"] == "gtao:3" and alone["cheapest"]["label"] == "gtao:3"
    assert "nothing within the time of gtao:3 (10.0 ms) beats it" in alone["sentence"]


def test_markdown_and_the_files(rows, tmp_path):
    """The CSV round trip keeps the fronts; the markdown holds the verdicts and every label."""
    paths = write_rows(rows, tmp_path / "t.csv", tmp_path / "t.npz")
    back = read_rows(*paths)
    assert thin_pareto.fronts(back, SCENE) == thin_pareto.fronts(rows, SCENE)
    text = thin_pareto.markdown(back)
    assert thin_pareto.verdict(rows, SCENE)["sentence"] in text
    assert all(f"| {r['label']} |" in text for r in rows if r["kind"] == "estimate")
    assert back.meta["per_scene"][SCENE]["band"] == next(r["thin_pixels"] for r in rows if r["kind"] == "estimate")


def test_bad_scenes_are_rejected():
    with pytest.raises(ValueError, match="scenes must be some of"):
        thin_pareto.measure(Profile(quick=True), scenes=("slab",))


def test_configurations_cover_the_variants():
    entries = thin_pareto.configurations(0.5, 4.0)
    labels = [e.label for e in entries]
    assert len(set(labels)) == len(labels)
    vbao = {e.variant for e in entries if e.family == "VBAO"}
    assert {"linear thickness", "layers"} <= vbao and any(v.startswith("bitcount") for v in vbao)
    linear = next(e for e in entries if e.label == "vbao:3 linear")
    # the linear thickness equals the constant one at the median depth
    assert linear.options["thickness"] * 4.0 == pytest.approx(thin_pareto.VBAO_THICKNESS * 0.5, rel=1e-15)
    assert {e.layers for e in entries} == set(thin_pareto.LAYERS)
    assert np.all([e.options.get("thickness") == "layers" for e in entries if e.layers > 1])
