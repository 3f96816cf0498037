"""Fig. 4 of Loos & Sloan 2010 (pattern noise in images): the figure measures what it says.

Quick mode only (48 x 48, 512 reference samples): its numbers are smoke-test numbers, so
nothing here asserts the paper's or the issue's claim; the checks are that the rows are
recomputed exactly by independent calls of the estimators, that the reported standard errors
are those of the seeds' spread and describe it, and that the goal's arithmetic is right.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

#: Width of the border strip that must stay blank (as in tests/test_figures.py).
BORDER_PIXELS = 2
#: Two-sided z beyond which two seed means are called different. The standard errors come
#: from 8 and 16 seeds, so z is roughly t with ~15 degrees of freedom: P(|t| > 4) ~ 0.1 %.
Z_SEEDS = 4.0
#: Relative tolerance of a CSV cell (6 significant digits) against the value it was written from.
CSV_RTOL = 1e-5
#: Seeds per random / Sobol' pattern in the quick profile (its docstring's number).
QUICK_SEEDS = 4
#: Range of each numeric CSV column: RMSEs of visibilities lie in [0, 1], biases in [-1, 1].
CSV_RANGES = {"samples": (1, 64), "normal_clamp": (0, 1), "seeds": (1, 1000), "width": (1, 8192),
              "height": (1, 8192), "ref_samples": (2, 10 ** 6), "rmse_ref": (0.0, 1.0),
              "rmse_ref_se": (0.0, 1.0), "rmse_ref_sd": (0.0, 1.0), "rmse_ref_first": (0.0, 1.0),
              "bias_ref": (-1.0, 1.0), "rmse_limit": (0.0, 1.0), "rmse_limit_se": (0.0, 1.0),
              "limit_rmse_ref": (0.0, 1.0), "ref_noise": (0.0, 1.0), "target": (0.0, 10.0),
              "ratio": (0.0, 100.0), "ratio_se": (0.0, 100.0), "z": (-1e4, 1e4),
              "ratio_limit": (0.0, 100.0), "ratio_limit_se": (0.0, 100.0), "pixels": (1, 10 ** 8)}


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    from vobscure.experiments import figures
    from vobscure.experiments.figures import fig4_noise as F

    out_dir = tmp_path_factory.mktemp("fig4")
    paths = figures.make("fig4_noise", out_dir, figures.Profile(quick=True))
    rows = F.measure(figures.Profile(quick=True))       # measured again: deterministic by the seed
    return F, out_dir, paths, rows


@pytest.fixture(scope="module")
def scene_setup():
    """G-buffer, radius and half-ball reference built here, independently of the module."""
    import vobscure as vo

    scene = vo.scenes.get("cornell_box")
    gb = vo.render_gbuffer(scene, scene.camera((48, 48)))
    radius = 0.1 * scene.extent
    ref = vo.vo_reference(gb, radius=radius, samples=512, normal_clamp=True, seed=0).value
    return gb, radius, ref


def _csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _row(rows, **keys):
    (row,) = [r for r in rows if all(r[k] == v for k, v in keys.items())]
    return row


def test_quick_make_writes_png_and_csv(quick):
    import matplotlib.image as mpimg

    F, out_dir, paths, _ = quick
    names = ["fig4_noise.csv", "fig4_noise.npz", "fig4_noise.md", "fig4_noise.png"]
    assert paths == [out_dir / n for n in names]
    # atomic writes: exactly these files, no temporary ones
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(names)
    assert "### The goal (lines 9, symmetric, half-ball)" in (out_dir / "fig4_noise.md").read_text()
    png = out_dir / "fig4_noise.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rgb = mpimg.imread(png)[..., :3]
    assert rgb.shape[0] >= 600 and rgb.shape[1] >= 600 and rgb.std() > 0.05
    b = BORDER_PIXELS
    border = np.concatenate([rgb[:b].reshape(-1, 3), rgb[-b:].reshape(-1, 3),
                             rgb[:, :b].reshape(-1, 3), rgb[:, -b:].reshape(-1, 3)])
    assert np.all(border == 1.0), "a label or panel reaches the edge of the figure (clipped)"


def test_csv_columns_rows_and_ranges(quick):
    F, out_dir, paths, rows = quick
    table = _csv(out_dir / "fig4_noise.csv")
    assert tuple(table[0]) == F._COLUMNS
    for column in CSV_RANGES:
        assert column in table[0]
    # every configuration once: lines 3 variants x 2 counts, points 2 x 2; 2 normal settings; 3 methods
    assert len(table) == len(rows) == (3 * 2 + 2 * 2) * 2 * len(F.METHODS)
    keys = {(r["estimator"], r["normal_clamp"], r["variant"], r["method"], r["samples"]) for r in table}
    assert len(keys) == len(table)
    for i, r in enumerate(table):
        for column, (lo, hi) in CSV_RANGES.items():
            if r[column] == "":
                continue
            value = float(r[column])
            assert np.isfinite(value) and lo <= value <= hi, f"row {i}: {column} = {value}"
        if r["method"] == "electrostatic":
            # one deterministic pattern: no spread over seeds, no comparison with itself
            assert r["seeds"] == "1" and r["rmse_ref_se"] == "" and r["verdict"] == ""
            assert float(r["rmse_ref"]) == float(r["rmse_ref_first"])
        else:
            assert int(r["seeds"]) == QUICK_SEEDS
            assert r["verdict"] in ("met", "not met", "undecided")
            assert float(r["target"]) == F.GOAL[r["method"]]
    # the CSV holds the rows measure() returns
    for r, m in zip(table, rows):
        assert math.isclose(float(r["rmse_ref"]), m["rmse_ref"], rel_tol=CSV_RTOL)


def test_electrostatic_rmse_is_a_direct_recomputation(quick, scene_setup):
    """The row's RMSE is vo_line on the table pattern, randomization off, against vo_reference."""
    import vobscure as vo
    from vobscure import patterns as P

    _, _, _, rows = quick
    gb, radius, ref = scene_setup
    for n in (9, 10):
        p = P.disk(n, method="electrostatic", symmetric=True)
        assert p.provenance["source"].startswith("table")      # nothing generated at run time
        v = vo.vo_line(gb, radius=radius, samples=p, normal_clamp=True, randomize=False)
        row = _row(rows, estimator="line", normal_clamp=True, variant="symmetric", method="electrostatic",
                   samples=n)
        assert row["rmse_ref"] == vo.error(v, ref).rmse
    p = P.ball(12, method="electrostatic", symmetric=False)
    v = vo.vo_point(gb, radius=radius, samples=p, normal_clamp=True, randomize=False)
    row = _row(rows, estimator="point", normal_clamp=True, variant="plain", method="electrostatic", samples=12)
    assert row["rmse_ref"] == vo.error(v, ref).rmse


def test_random_row_is_the_mean_over_seeds_with_its_standard_error(quick, scene_setup):
    import vobscure as vo
    from vobscure import patterns as P

    F, _, _, rows = quick
    gb, radius, ref = scene_setup
    k = QUICK_SEEDS
    rmse = [vo.error(vo.vo_line(gb, radius=radius, samples=P.disk(9, method="random", seed=s),
                                normal_clamp=True, randomize=False), ref).rmse for s in range(k)]
    row = _row(rows, estimator="line", normal_clamp=True, variant="symmetric", method="random", samples=9)
    assert row["rmse_ref"] == pytest.approx(np.mean(rmse), rel=1e-12)
    assert row["rmse_ref_first"] == rmse[0]
    sd = np.std(rmse, ddof=1)
    assert sd > 0                                  # the seeds are different patterns
    assert row["rmse_ref_se"] == pytest.approx(sd / math.sqrt(k), rel=1e-12)
    es = _row(rows, estimator="line", normal_clamp=True, variant="symmetric", method="electrostatic",
              samples=9)["rmse_ref"]
    assert row["ratio"] == pytest.approx(es / np.mean(rmse), rel=1e-12)
    assert row["ratio_se"] == pytest.approx(row["ratio"] * row["rmse_ref_se"] / row["rmse_ref"], rel=1e-12)
    assert row["z"] == pytest.approx((row["rmse_ref"] - es) / row["rmse_ref_se"], rel=1e-12)


def test_reported_standard_error_describes_other_seeds(scene_setup):
    """z-test: the seed mean of measure() against the mean over 16 further seeds, computed here.

    If the standard error understated the seed-to-seed spread, the two means would differ by
    many of them.
    """
    import vobscure as vo
    from vobscure import patterns as P
    from vobscure.experiments.figures import fig4_noise as F

    gb, radius, ref = scene_setup
    k = 8
    from vobscure.experiments.figures import Profile

    rows = F.measure(Profile(quick=True), seeds=k, line_counts=(9,), point_counts=())
    assert {r["estimator"] for r in rows} == {"line"}
    for method in ("random", "sobol"):
        row = _row(rows, estimator="line", normal_clamp=True, variant="symmetric", method=method, samples=9)
        assert row["seeds"] == k
        other = [vo.error(vo.vo_line(gb, radius=radius, samples=P.disk(9, method=method, seed=s),
                                     normal_clamp=True, randomize=False), ref).rmse for s in range(k, 3 * k)]
        se_other = np.std(other, ddof=1) / math.sqrt(len(other))
        z = (row["rmse_ref"] - np.mean(other)) / math.hypot(row["rmse_ref_se"], se_other)
        assert abs(z) < Z_SEEDS, f"{method}: seed means differ by z = {z:.2f}"


def test_goal_arithmetic_and_verdicts(quick):
    F, _, _, rows = quick
    gs = F.goal(rows)
    assert [g["rival"] for g in gs] == ["random", "sobol"]
    for g in gs:
        assert g["target"] == F.GOAL[g["rival"]]
        assert g["ratio"] == pytest.approx(g["electrostatic"] / g["mean"], rel=1e-12)
        assert g["ratio_se"] > 0
        assert g["upper"] == pytest.approx(g["ratio"] + F.GOAL_Z * g["ratio_se"])
        expected = ("met" if g["upper"] <= g["target"] else
                    "not met" if g["lower"] > g["target"] else "undecided")
        assert g["verdict"] == expected
        row = _row(rows, estimator="line", normal_clamp=True, variant="symmetric", method=g["rival"], samples=9)
        assert row["verdict"] == g["verdict"] and row["ratio"] == g["ratio"]
    with pytest.raises(ValueError, match="samples=11"):
        F.goal(rows, samples=11)
    text = F.markdown(rows)
    assert "### The goal (lines 9, symmetric, half-ball)" in text and "| Sobol' |" in text


def test_registered_and_quick_mode_generates_no_electrostatic_pattern(monkeypatch, tmp_path):
    """Registered before fig5; every electrostatic pattern (quick and full) comes from a table."""
    from vobscure import patterns as P
    from vobscure.experiments.figures import fig4_noise as F
    from vobscure.experiments.figures import names

    order = names()
    assert "fig4_noise" in order and "patterns_quality" in order
    assert order.index("fig4_noise") < order.index("fig5_thickness")

    from vobscure.patterns import generators

    real = generators.generate

    def no_electrostatic(dim, n, method, *args, **kwargs):
        assert method != "electrostatic", f"generated an electrostatic pattern (dim {dim}, n {n}) at run time"
        return real(dim, n, method, *args, **kwargs)

    monkeypatch.setattr(generators, "generate", no_electrostatic)   # what disk/ball and the tables call
    for estimator, counts in (("line", F.PAPER_COUNTS["line"] + F.LINE_COUNTS),
                              ("point", F.PAPER_COUNTS["point"] + F.POINT_COUNTS)):
        for variant in F.VARIANTS[estimator]:
            for n in counts:
                p = F._pattern(estimator, n, "electrostatic", variant, seed=3)
                assert p.provenance["source"].startswith("table")
