"""The figures driver and every figure module, in the quick profile: measure -> CSV (and NPZ)
-> plot -> PNG, drawn again from the files without measuring, and the example of
docs/figures.md ("Adding a figure") run through the same driver."""

from __future__ import annotations

import csv
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from vobscure.experiments import figures
from vobscure.experiments.figures import Profile, Rows

#: Smallest acceptable (height, width) of a figure, in pixels: a panel grid, not a thumbnail.
MIN_FIGURE_PIXELS = (600, 600)
#: Width of the border strip that must stay blank (nothing drawn is cut off at the edge).
BORDER_PIXELS = 2
#: Smallest acceptable PNG file of a figure, in bytes (a panel grid, not a stub).
MIN_PNG_BYTES = 20_000
#: Ranges of CSV columns by name, wherever they appear: errors of visibilities (in [0, 1]) are
#: in [0, 1], biases in [-1, 1], correlations in [-1, 1], booleans 0 / 1.
COLUMN_RANGES = {"rmse": (0.0, 1.0), "bias": (-1.0, 1.0), "corr": (-1.0, 1.0), "normal_clamp": (0, 1)}
#: Significant digits of the CSV's floats, and the relative agreement they give.
CSV_RTOL = 1e-5
#: Columns documented to be NaN where not measured (:func:`vobscure.experiments.claims.line_vs_point`).
NAN_ALLOWED = {"screenspace_claims": {"rmse_limit", "limit_rmse_ref"}}
DOCS = Path(__file__).resolve().parents[1] / "docs" / "figures.md"
QUICK = Profile(quick=True)


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """Every figure made once, in one driver run (the claims' measurement shared): (dir, paths)."""
    out_dir = tmp_path_factory.mktemp("figures")
    return out_dir, figures.make(figures.names(), out_dir, QUICK)


def _range_of(column):
    for key, rng in COLUMN_RANGES.items():
        if column == key or column.startswith(key + "_"):
            return rng
    return None


def _png(path):
    import matplotlib.image as mpimg

    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    return mpimg.imread(path)[..., :3]


@pytest.mark.parametrize("name", figures.names())
def test_figure_quick_writes_png_and_csv_named_after_it(quick_run, name):
    out_dir, paths = quick_run
    mine = [p for p in paths if p.stem == name]
    assert {p.suffix for p in mine} <= {".csv", ".npz", ".md", ".png"}
    assert out_dir / f"{name}.csv" in mine and out_dir / f"{name}.png" in mine
    png = out_dir / f"{name}.png"
    assert png.stat().st_size >= MIN_PNG_BYTES
    rgb = _png(png)
    assert rgb.shape[0] >= MIN_FIGURE_PIXELS[0] and rgb.shape[1] >= MIN_FIGURE_PIXELS[1]
    assert np.isfinite(rgb).all() and rgb.std() > 0.05, f"{name}: the figure is blank"
    b = BORDER_PIXELS
    border = np.concatenate([rgb[:b].reshape(-1, 3), rgb[-b:].reshape(-1, 3),
                             rgb[:, :b].reshape(-1, 3), rgb[:, -b:].reshape(-1, 3)])
    assert np.all(border == 1.0), f"{name}: a label or panel reaches the edge of the figure (clipped)"


def test_driver_writes_exactly_the_files_it_returns(quick_run):
    out_dir, paths = quick_run
    # atomic writes: no temporary file is left beside them
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(p.name for p in paths)


@pytest.mark.parametrize("name", figures.names())
def test_figure_csv_finite_and_in_range(quick_run, name):
    out_dir, _ = quick_run
    with open(out_dir / f"{name}.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert rows, f"{name}.csv has no rows"
    for i, row in enumerate(rows):
        for column, cell in row.items():
            try:
                value = float(cell)
            except ValueError:
                continue    # a label, or an empty cell (not measured)
            if math.isnan(value) and column in NAN_ALLOWED.get(name, ()):
                continue
            assert math.isfinite(value), f"{name}.csv row {i}: {column} = {cell}"
            rng = _range_of(column)
            if rng is not None:
                assert rng[0] <= value <= rng[1], f"{name}.csv row {i}: {column} = {value} not in {rng}"


def test_replot_from_the_files_gives_the_same_png(quick_run, tmp_path):
    """--from-csv draws from the files alone: copied to a fresh folder, the PNG comes out
    byte-identical to the one of the measuring run."""
    import shutil

    out_dir, _ = quick_run
    for name in ("conventions", "fig5_thickness", "table1_timings"):
        for suffix in (".csv", ".npz"):
            if (out_dir / f"{name}{suffix}").is_file():
                shutil.copy(out_dir / f"{name}{suffix}", tmp_path)
    paths = figures.replot(["conventions", "fig5_thickness", "table1_timings"], tmp_path)
    assert [p.name for p in paths] == ["conventions.png", "fig5_thickness.png", "table1_timings.png"]
    for p in paths:
        assert p.read_bytes() == (out_dir / p.name).read_bytes(), p.name


def test_rows_round_trip_through_the_files(tmp_path):
    """A hand-made Rows: the CSV holds its columns in order, 6 significant digits, booleans
    0 / 1, None empty; the NPZ its arrays and meta exactly."""
    from vobscure.experiments.figures._common import read_rows, write_rows

    image = np.arange(6.0).reshape(2, 3) / 7.0
    rows = Rows([{"method": "lines 9", "n": 9, "rmse": 2.0 / 3.0, "clamp": True, "factor": None, "extra": 1}],
                columns=("method", "n", "rmse", "clamp", "factor"), arrays={"image": image},
                meta={"size": [3, 2], "title": "a"})
    paths = write_rows(rows, tmp_path / "f.csv", tmp_path / "f.npz")
    assert (tmp_path / "f.csv").read_text() == "method,n,rmse,clamp,factor\nlines 9,9,0.666667,1,\n"
    back = read_rows(*paths)
    assert back == [{"method": "lines 9", "n": 9, "rmse": 0.666667, "clamp": 1, "factor": None}]
    assert back.meta == {"size": [3, 2], "title": "a"}
    np.testing.assert_array_equal(back.arrays["image"], image)


def test_names_are_discovered_in_order():
    names = figures.names()
    assert names[:8] == ["conventions", "screenspace_claims", "fig4_noise", "fig5_thickness", "fig6_normals",
                         "fig7_lines_vs_points", "fig8_dual_radii", "table1_timings"]
    assert not any(n.startswith("_") for n in names) and len(set(names)) == len(names)
    on_disk = {p.stem for p in Path(figures.__file__).parent.glob("[!_]*.py")}
    assert set(names) == on_disk


def test_unknown_names_are_rejected_before_anything_is_measured(tmp_path):
    assert figures.make([], tmp_path, QUICK) == []
    with pytest.raises(ValueError, match="fig5_thickness"):      # the message lists the valid names
        figures.make(["conventions", "no_such_figure"], tmp_path, QUICK)
    with pytest.raises(ValueError, match="unknown figure name '_common'"):
        figures.make("_common", tmp_path, QUICK)
    with pytest.raises(FileNotFoundError, match="make the figure"):
        figures.replot("conventions", tmp_path)
    assert not any(tmp_path.iterdir())


# ----------------------------------------------------------------------------- docs/figures.md
def _example_module() -> str:
    text = DOCS.read_text(encoding="utf-8")
    section = text.split("## Adding a figure", 1)[1].split("\n## ", 1)[0]
    (code,) = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    return code


def test_the_docs_example_is_about_20_lines():
    code = [line for line in _example_module().splitlines() if line.strip()]
    assert len(code) <= 30


def test_the_docs_example_runs_through_the_driver(tmp_path, monkeypatch):
    """The example of "Adding a figure", written as the module of a figure package of its own,
    measured, written, drawn and drawn again from its CSV by the driver of ``vobscure figures``;
    its numbers checked against the closed form of the half-ball VO of a crease floor point,
    1 - (1 - c)^2 (2 + c) / 4 (DESIGN.md, "Testing")."""
    package = tmp_path / "docfigs"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "crease_visibility.py").write_text(_example_module())
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "docfigs", raising=False)

    assert figures.names("docfigs") == ["crease_visibility"]
    out = tmp_path / "out"
    paths = figures.make("crease_visibility", out, QUICK, package="docfigs")
    assert [p.name for p in paths] == ["crease_visibility.csv", "crease_visibility.png"]
    with open(out / "crease_visibility.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["c"]) for r in rows] == pytest.approx([0.1, 0.4, 0.7, 1.0])
    for r in rows:
        c, v, se = float(r["c"]), float(r["vo"]), float(r["stderr"])
        exact = 1.0 - (1.0 - c) ** 2 * (2.0 + c) / 4.0
        assert abs(v - exact) <= 4.0 * se + 1e-12, (c, v, exact, se)   # z-test at 4 sigma
    first = (out / "crease_visibility.png").read_bytes()
    (out / "crease_visibility.png").unlink()
    assert figures.replot("crease_visibility", out, package="docfigs") == [out / "crease_visibility.png"]
    assert (out / "crease_visibility.png").read_bytes() == first


def test_cli_from_csv_redraws_without_measuring(tmp_path, monkeypatch, capsys):
    from vobscure.cli import main
    from vobscure.experiments.figures import conventions

    assert main(["figures", "conventions", "--quick", "--out", str(tmp_path)]) == 0
    assert "conventions.png" in capsys.readouterr().out

    def no_measuring(profile):
        raise AssertionError("--from-csv measured")

    monkeypatch.setattr(conventions, "measure", no_measuring)
    (tmp_path / "conventions.png").unlink()
    assert main(["figures", "conventions", "--from-csv", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "conventions.png").is_file()
    assert main(["figures", "fig5_thickness", "--from-csv", "--out", str(tmp_path)]) == 2
    assert "make the figure" in capsys.readouterr().err


# ----------------------------------------------------------------------------- shared measurements
_SHARING_FIGURES = {
    "_seen.py": "import weakref\nREFS = {}\nLOG = []\n",
    "first.py": ("ORDER = 1\n"
                 "def measure(profile, *, trees=None):\n"
                 "    from . import _seen\n"
                 "    _seen.REFS['first'] = _seen.weakref.ref(trees)\n"
                 "    _seen.LOG.append(('first', trees.quick, trees.seed))\n"
                 "    return [{'x': 1}]\n"
                 "def plot(rows, fig):\n"
                 "    fig.subplots()\n"),
    "second.py": ("ORDER = 2\n"
                  "def measure(profile, *, trees=None):\n"
                  "    from . import _seen\n"
                  "    _seen.LOG.append(('second', _seen.REFS['first']() is trees))\n"
                  "    return [{'x': 2}]\n"
                  "def plot(rows, fig):\n"
                  "    fig.subplots()\n"),
    "third.py": ("ORDER = 3\n"
                 "def measure(profile):\n"
                 "    from . import _seen\n"
                 "    _seen.LOG.append(('third', _seen.REFS['first']() is None))\n"
                 "    return [{'x': 3}]\n"
                 "def plot(rows, fig):\n"
                 "    fig.subplots()\n"),
}


def test_the_driver_shares_a_measurement_and_drops_it_after_its_last_user(tmp_path, monkeypatch):
    """Two figures asking for ``trees`` get the same Measurements of the run's profile; a third
    figure, after the last one that asks, finds it gone (no copy kept anywhere)."""
    package = tmp_path / "sharefigs"
    package.mkdir()
    (package / "__init__.py").write_text("")
    for name, text in _SHARING_FIGURES.items():
        (package / name).write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "sharefigs", raising=False)

    figures.make(["first", "second", "third"], tmp_path / "out", Profile(quick=True, seed=3), package="sharefigs")
    log = sys.modules["sharefigs._seen"].LOG
    assert log == [("first", True, 3), ("second", True), ("third", True)]


def test_a_tree_figure_measured_alone_makes_its_own_measurements(quick_run):
    """``measure`` without the driver's shared measurement gives the rows the run wrote."""
    from vobscure.experiments.figures import _common, hegeman_fig9

    out_dir, _ = quick_run
    rows = hegeman_fig9.measure(QUICK)
    _common.write_rows(rows, out_dir / "alone.csv")
    assert (out_dir / "alone.csv").read_bytes() == (out_dir / "hegeman_fig9.csv").read_bytes()


# ----------------------------------------------------------------------------- deprecated names
@pytest.mark.parametrize("name", figures.names())
def test_deprecated_make_of_a_figure_module_runs_the_driver(name, tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(figures, "make", lambda *args, **kw: calls.append((args, kw)) or ["written"])
    mod = figures.module(name)
    with pytest.warns(DeprecationWarning, match=rf"use `vobscure figures {name}` or .*figures\.make\('{name}'"):
        assert mod.make(tmp_path, quick=True, seed=2) == ["written"]
    assert calls == [((name, tmp_path, Profile(quick=True, seed=2)), {})]


def test_deprecated_make_writes_the_figure(tmp_path):
    from vobscure.experiments.figures import conventions

    with pytest.warns(DeprecationWarning, match="vobscure figures conventions"):
        paths = conventions.make(tmp_path, quick=True)
    assert paths[-1] == tmp_path / "conventions.png" and all(p.is_file() for p in paths)


def test_deprecated_figures_registry_maps_every_name_to_itself():
    with pytest.warns(DeprecationWarning, match=r"figures\.names\(\)"):
        registry = figures.FIGURES
    assert registry == {name: name for name in figures.names()}
    with pytest.raises(AttributeError, match="NO_SUCH_NAME"):
        figures.NO_SUCH_NAME
