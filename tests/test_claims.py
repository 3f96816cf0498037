"""The claim experiments (vobscure.experiments.claims) and their figure, in quick mode.

Structure only, no timing assertions: every configuration measured for both normal
settings, finite errors, taps per pixel equal to the sample count, the claims derived from
the rows, and the figure's PNG written.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

SIZE = (48, 48)


@pytest.fixture(scope="module")
def measured():
    from vobscure.experiments.claims import measurement

    return measurement("cornell_box", quick=True, size=SIZE)


@pytest.fixture(scope="module")
def rows(measured):
    return [dict(r) for r in measured.rows]


def test_every_configuration_for_both_normal_settings(rows):
    from vobscure.experiments.claims import CONFIGS

    got = {(r["config"], r["normal_clamp"]) for r in rows}
    for c in CONFIGS:
        assert (c.label, False) in got and (c.label, True) in got
    assert len(got) == len(rows), "one row per (configuration, normal setting)"
    assert {r["scene"] for r in rows} == {"cornell_box"}
    assert all(r["size"] == SIZE and r["quick"] for r in rows)


def test_errors_belong_to_their_configuration(rows):
    from vobscure.experiments.claims import SEED_REPEATS, measurement

    m = measurement("cornell_box", quick=True, size=SIZE)
    for r in rows:
        assert r["pixels"] == SIZE[0] * SIZE[1]  # the Cornell box covers every pixel
        assert r["seconds"] > 0 and len(r["seconds_runs"]) >= 3
        # the row's errors are those of its own image against its own references
        image = m.images[(r["config"], r["normal_clamp"])]
        diff = image - m.reference[r["normal_clamp"]]
        assert r["rmse_ref"] == pytest.approx(float(np.sqrt(np.mean(diff ** 2))), rel=1e-12)
        assert r["bias_gt"] == pytest.approx(float(np.mean(image - m.truth[r["normal_clamp"]].value)), rel=1e-9)
        # further seeds change the noise texture of points and lines, so their errors spread
        # (one area sample, at the disk's centre, is the same under every rotation)
        assert (r["rmse_ref_seeds_sd"] > 0) == (r["method"] != "area") and SEED_REPEATS >= 2
    # more point samples converge: 33 points are closer to the converged reference than 12
    by = {(r["config"], r["normal_clamp"]): r for r in rows}
    for nc in (False, True):
        assert by[("points 33", nc)]["rmse_ref"] < 0.8 * by[("points 12", nc)]["rmse_ref"]


def test_taps_per_pixel_equal_the_sample_counts(rows):
    primary = {r["config"]: r for r in rows if r["primary"]}
    # the centre of the odd point pattern (33) is not tapped: it lies on the surface
    for label, n, taps in (("lines 5", 5, 5), ("lines 9", 9, 9), ("points 12", 12, 12), ("points 33", 33, 32)):
        assert primary[label]["samples"] == n
        assert primary[label]["taps_per_pixel"] == taps
    assert primary["lines 9"]["texels_per_pixel"] == 9       # nearest fetch: one texel a tap
    assert primary["points 12"]["texels_per_pixel"] == 48    # bilinear fetch: four


def test_own_limit_of_bilinear_points_is_the_reference(rows):
    for r in rows:
        if r["method"] == "point" and r["fetch"] == "bilinear":
            assert r["limit_rmse_ref"] == 0.0
            assert r["rmse_limit"] == pytest.approx(r["rmse_ref"])
        if r["method"] == "line":
            assert math.isfinite(r["rmse_limit"]) and math.isfinite(r["limit_rmse_ref"])


def test_reference_and_ground_truth_settings(rows):
    from vobscure.experiments.claims import REFERENCE_SAMPLES

    for r in rows:
        assert r["ref_samples"] == REFERENCE_SAMPLES[True]
        assert r["gt_samples"] >= 256
    # the half-ball is mostly open in the Cornell box: the estimators see that too
    flat = {r["normal_clamp"]: r for r in rows if r["config"] == "points 33"}
    assert flat[True]["rmse_gt"] < flat[False]["rmse_gt"]


def _row(config, rmse_ref, seconds, scene="blob", normal_clamp=False):
    nan = float("nan")
    return dict(scene=scene, normal_clamp=normal_clamp, config=config, rmse_ref=rmse_ref, seconds=seconds,
                rmse_gt=nan, rmse_limit=nan, rmse_ref_blurred=nan, cpu_seconds=seconds, taps_per_pixel=1,
                texels_per_pixel=1)


@pytest.mark.parametrize("lines, points, verdict", [
    ((0.04, 0.01), (0.05, 0.03), "confirmed"),         # better and faster
    ((0.04, 0.05), (0.05, 0.03), "partly"),            # better, slower
    ((0.06, 0.01), (0.05, 0.03), "partly"),            # worse, faster
    ((0.06, 0.05), (0.05, 0.03), "not confirmed"),     # worse and slower
    ((0.05, 0.01), (0.05, 0.03), "confirmed"),         # the same quality counts as the points'
])
def test_claim_verdicts(lines, points, verdict):
    from vobscure.experiments.claims import claims

    rows = [_row("lines 5", *lines), _row("points 12", *points)]
    (c,) = claims(rows)
    assert (c["lines"], c["points"], c["verdict"]) == ("lines 5", "points 12", verdict)
    assert c["speedup"] == pytest.approx(points[1] / lines[1])


def test_claims_of_the_measured_rows(rows):
    from vobscure.experiments.claims import CLAIMS, claims

    out = claims(rows)
    assert len(out) == 2 * len(CLAIMS)
    assert {(c["lines"], c["points"]) for c in out} == set(CLAIMS)


def test_line_vs_point_measures_again_and_deterministically(rows):
    """Nothing is cached between calls: a second call measures again and returns new dicts,
    equal to the first in every column but the times."""
    from vobscure.experiments.claims import line_vs_point

    times = {"seconds", "seconds_runs", "cpu_seconds"}

    def untimed(rs):   # NaN (not measured) as a string, so that equal rows compare equal
        return [{k: "nan" if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()
                 if k not in times} for r in rs]

    mine = line_vs_point("cornell_box", quick=True, size=SIZE)
    assert mine[0] is not rows[0]
    assert untimed(mine) == untimed(rows)


def test_thickness_and_normal_tables(measured):
    from vobscure.experiments.claims import THICKNESS_FACTORS, normals_on_off, thickness_at_silhouettes

    thick = thickness_at_silhouettes("cornell_box", quick=True, size=SIZE, measured=measured)
    assert len(thick) == 2 * (1 + len(THICKNESS_FACTORS))
    assert [t["thickness"] is None for t in thick].count(True) == 2
    for t in thick:
        assert t["pixels_band"] > 0 and t["pixels_far"] > 0
        assert t["pixels_far"] <= t["pixels_band"] < t["pixels_all"]
        assert math.isfinite(t["rmse_all"]) and math.isfinite(t["rmse_band"])
    normals = normals_on_off("cornell_box", quick=True, size=SIZE, measured=measured)
    assert [n["normal_clamp"] for n in normals] == [False, True]
    assert all(-1 <= n["corr_ao"] <= 1 and math.isfinite(n["rmse_gt"]) for n in normals)
    with pytest.raises(ValueError, match="measured must be the Measurement of 'blob'"):
        normals_on_off("blob", quick=True, size=SIZE, measured=measured)


def test_silhouette_mask_on_a_step():
    from vobscure.experiments.claims import silhouette_mask

    d = np.full((6, 10), 2.0)
    d[:, 5:] = 2.1            # a 5 % step: no silhouette
    band, far = silhouette_mask(d, width=1)
    assert not band.any() and not far.any()
    d[:, 5:] = 3.0            # a 50 % step: band of width 1 on both sides, far side behind
    band, far = silhouette_mask(d, width=1)
    assert band[:, 3:7].all() and not band[:, :3].any() and not band[:, 7:].any()
    assert far[:, 5:7].all() and not far[:, :5].any()
    d[0, 0] = np.inf          # background is never in the band
    band, _ = silhouette_mask(d, width=1)
    assert not band[0, 0] and band[0, 1]


def test_bad_scene_name_names_the_valid_ones():
    from vobscure.experiments.claims import line_vs_point

    with pytest.raises(ValueError, match="cornell_box"):
        line_vs_point("no_such_scene", quick=True, size=(8, 8))


def test_figure_is_drawn_from_the_measurement_passed_in(measured, tmp_path, monkeypatch):
    """The figure draws the claims' measurement it is given and measures none itself."""
    import matplotlib.image as mpimg

    from vobscure.experiments import claims, figures
    from vobscure.experiments.figures import screenspace_claims

    blob = claims.measurement("blob", quick=True, size=SIZE)

    def no_measuring(*args, **kwargs):
        raise AssertionError("measured again")

    monkeypatch.setattr(claims, "measurement", no_measuring)
    rows = screenspace_claims.measure(figures.Profile(quick=True, size=SIZE),
                                      claims={"cornell_box": measured, "blob": blob})
    assert [r["rmse_ref"] for r in rows if r["scene"] == "cornell_box"] == [r["rmse_ref"] for r in measured.rows]
    fig = figures.plot("screenspace_claims", rows)
    from vobscure.experiments.common import save_figure

    path = save_figure(fig, tmp_path / "screenspace_claims.png")
    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[0] >= 600 and image.shape[1] >= 600
    assert image[..., :3].std() > 0.05
