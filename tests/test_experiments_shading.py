"""The interreflection experiment (vobscure.experiments.shading) and its figure."""

from __future__ import annotations

import numpy as np
import pytest

from vobscure.experiments import shading as X


@pytest.fixture(scope="module")
def crease_measured():
    return X.measure("crease", quick=True, albedos=(0.3, 0.9), seed=2)


def test_rows_cover_every_albedo_and_correction(crease_measured):
    rows = X.interreflection_rows(crease_measured)
    assert {(r["albedo"], r["correction"]) for r in rows} == {
        (a, c) for a in (0.3, 0.9) for c in X.CORRECTIONS}
    assert all(r["pixels"] == int(crease_measured.gbuffer.valid.sum()) for r in rows)


def test_black_occluders_are_darker_than_the_reference(crease_measured):
    # The reference shares k_A's primary rays and only adds reflected light, so k_A is below
    # it at every occluded pixel and equal elsewhere: "none" has a negative bias, growing
    # with the albedo.
    valid = crease_measured.gbuffer.valid
    for a, ref in crease_measured.reference.items():
        assert np.all(crease_measured.k_A[valid] <= ref[valid])
    rows = {(r["albedo"], r["correction"]): r for r in X.interreflection_rows(crease_measured)}
    assert rows[0.3, "none"]["bias"] < 0 and rows[0.9, "none"]["bias"] < rows[0.3, "none"]["bias"]
    # both corrections move k_A towards the reference on this crease
    for a in (0.3, 0.9):
        for name in ("stewart_langer", "jimenez"):
            assert rows[a, name]["rmse"] < rows[a, "none"]["rmse"]


def test_verdict_names_the_closer_correction(crease_measured):
    rows = X.interreflection_rows(crease_measured)
    text = X.verdict(rows)
    for a in (0.3, 0.9):
        by = {r["correction"]: r["rmse"] for r in rows if r["albedo"] == a}
        best = min(("stewart_langer", "jimenez"), key=by.get)
        assert f"crease, albedo {a}: {best} is closer" in text


def test_main_prints_table_and_verdict(capsys):
    assert X.main(["--quick", "--scenes", "crease"]) == 0
    out = capsys.readouterr().out
    assert "| crease |" in out and "is closer" in out


def test_gtao_bent_normals_point_closer_to_the_truth_than_the_normal():
    rows = {r["source"]: r for r in X.bent_normal_rows("cornell_box", quick=True)}
    normal = rows["geometric normal, ray-traced k_A"]
    # the Cornell box's corners bend the normals: the geometric normal is off the ray-traced
    # bent normal, and the lookup with it misses the target
    assert normal["angle_median_deg"] > 0 and normal["lookup_rel_rmse"] > 0
    for slices, steps in X.GTAO_BENT:
        r = rows[f"gtao {slices}x{steps}"]
        assert r["angle_median_deg"] < normal["angle_median_deg"]
        assert r["normal_only_rel_rmse"] < normal["normal_only_rel_rmse"]
