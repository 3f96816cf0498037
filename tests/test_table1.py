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
#: three is written with CSV_DIGITS (6) significant digits, so they agree to about 1e-6.
CSV_RELATIVE_TOLERANCE = 1e-5


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """The quick table's CSV rows, grouped: {(source, row): {column: csv row}}."""
    out_dir = tmp_path_factory.mktemp("table1")
    paths = T.make(out_dir, quick=True)
    assert [p.name for p in paths] == [T.FILENAME, T.CSV_FILENAME]
    with open(out_dir / T.CSV_FILENAME, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    grouped = {}
    for r in rows:
        grouped.setdefault((r["source"], r["row"]), {})[r["column"]] = r
    return grouped


def _ours(table, *, dual):
    return {row: cells for (source, row), cells in table.items()
            if source == "vobscure" and (row.endswith("(dual radii)") == dual)}


def test_horizon_columns_sit_beside_the_papers_hsao():
    assert T.HORIZON_COLUMNS == ("hbao 8x4", "gtao 3x3")
    i = T.COLUMNS.index("HSAO")
    assert T.COLUMNS[i + 1:i + 3] == T.HORIZON_COLUMNS


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
