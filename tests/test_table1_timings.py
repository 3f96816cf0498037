"""Table 1 of Loos & Sloan 2010 with the horizon-based columns: what the CSV of
:mod:`vobscure.experiments.figures.table1_timings` holds, in quick mode.

Timings are not asserted (they belong to ``benchmarks/``); what is tested is the table's
structure and that every ratio divides two times of one run.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from vobscure.experiments.figures import table1_timings as T

#: Relative agreement of ratio with ms / baseline_ms as read back from the CSV: each of the
#: three is written with CSV_DIGITS (6) significant digits, so each carries a relative rounding
#: error of at most half a unit in the sixth digit, 0.5e-5 (for a value starting with 1; less for
#: larger leading digits); the quotient of two such values compared with a third can differ by up
#: to 3 x 0.5e-5 = 1.5e-5 (first order), with a little room for the second-order terms.
CSV_RELATIVE_TOLERANCE = 1.6e-5


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """The quick table's CSV rows, grouped: {(source, row): {column: csv row}}."""
    from vobscure.experiments import figures

    out_dir = tmp_path_factory.mktemp("table1")
    paths = figures.make("table1_timings", out_dir, figures.Profile(quick=True))
    assert [p.name for p in paths] == ["table1_timings.csv", "table1_timings.npz", "table1_timings.png"]
    with open(out_dir / "table1_timings.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    grouped = {}
    for r in rows:
        grouped.setdefault((r["source"], r["row"]), {})[r["column"]] = r
    return grouped


def _ours(table, *, dual):
    return {row: cells for (source, row), cells in table.items()
            if source == "vobscure" and (row.endswith("(dual radii)") == dual)}


def test_rows_of_a_hand_made_timing():
    """Hand-made times of one scene (seconds): the rows hold them in ms, in the table's column
    order, each over the row's points 12 (2 ms), and the paper's cells before them."""
    ours = {"blob": {"lines 5": 0.001, "points 12": 0.002, "gtao 3x3": 0.005, "G-buffer": 0.004},
            "blob (dual radii)": {"points 12": 0.003}}
    rows = [r for r in T._csv_rows(ours, (8, 6)) if r["source"] == "vobscure"]
    assert [(r["row"], r["column"], r["ms"], r["baseline_ms"], r["ratio"]) for r in rows] == [
        ("blob", "G-buffer", 4.0, 2.0, 2.0), ("blob", "lines 5", 1.0, 2.0, 0.5),
        ("blob", "points 12", 2.0, 2.0, 1.0), ("blob", "gtao 3x3", 5.0, 2.0, 2.5),
        ("blob (dual radii)", "points 12", 3.0, 2.0, 1.5)]
    assert all((r["width"], r["height"]) == (8, 6) for r in rows)
    paper = [r for r in T._csv_rows(ours, (8, 6)) if r["source"] == "paper"]
    # 6 rows of the paper's Table 1: 6 + 5 + 6 + 6 + 6 + 5 filled cells, and the blur's
    assert len(paper) == 35 and ("Average", "blur", 2.23) in {(r["row"], r["column"], r["ms"]) for r in paper}


def test_every_single_radius_row_has_the_horizon_columns(table):
    ours = _ours(table, dual=False)
    assert set(ours) == {"cornell_box", "blob"}
    for row, cells in ours.items():
        for column in T.HORIZON_COLUMNS:
            assert column in cells, f"{row} lacks {column}"
            ms, ratio = float(cells[column]["ms"]), float(cells[column]["ratio"])
            assert np.isfinite(ms) and ms > 0, f"{row}, {column}: {ms} ms"
            assert np.isfinite(ratio) and ratio > 0, f"{row}, {column}: ratio {ratio}"
        # the paper's HSAO is the paper's alone: vobscure's rows do not fill it
        assert "HSAO" not in cells


def test_horizon_columns_are_not_in_the_paper_or_dual_rows(table):
    for (source, row), cells in table.items():
        if source == "paper" or row.endswith("(dual radii)"):
            assert not set(T.HORIZON_COLUMNS) & set(cells), (source, row)


def test_ratios_divide_times_of_one_run(table):
    """points 12 is exactly 1; every ratio is ms / the same row's points 12 ms (the single-radius
    row's for dual radii), read back from the CSV."""
    single = _ours(table, dual=False)
    for row, cells in {**single, **_ours(table, dual=True)}.items():
        base_row = single[row.replace(" (dual radii)", "")]
        base_ms = float(base_row[T.BASELINE]["ms"])
        if row in single:
            assert float(cells[T.BASELINE]["ratio"]) == 1.0
        for column, r in cells.items():
            ms, baseline_ms, ratio = float(r["ms"]), float(r["baseline_ms"]), float(r["ratio"])
            assert baseline_ms == base_ms, f"{row}, {column}: baseline {baseline_ms} != {base_ms}"
            assert ratio == pytest.approx(ms / base_ms, rel=CSV_RELATIVE_TOLERANCE), (row, column)
            assert np.isfinite(ratio) and ratio > 0


def test_papers_hsao_ratios_from_its_own_table():
    """The paper's HSAO over its points 12, row by row (Loos & Sloan 2010, Table 1, as
    transcribed in the papers' README): Dragon 51.52 / 1.18, Cornell 60.55 / 1.31, Soldiers
    17.04 / 1.14, Knight 29.13 / 0.97, Average 39.56 / 1.15; no entry for Dragon*."""
    published = {"Dragon": (51.52, 1.18), "Cornell": (60.55, 1.31), "Soldiers": (17.04, 1.14),
                 "Knight": (29.13, 0.97), "Average": (39.56, 1.15)}
    ratios = T.paper_ratios()
    for row, (hsao, points12) in published.items():
        assert ratios[row]["HSAO"] == pytest.approx(hsao / points12, rel=1e-12)
    assert ratios["Dragon (double radius)"]["HSAO"] is None
