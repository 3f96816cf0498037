"""Figure modules run end to end in quick mode (STYLE.md item 9): they write a valid PNG."""

from __future__ import annotations

import numpy as np
import pytest

#: Smallest acceptable (height, width) of a figure, in pixels: a panel grid, not a thumbnail.
MIN_FIGURE_PIXELS = (600, 600)
#: Width of the border strip that must stay blank (nothing drawn is cut off at the edge).
BORDER_PIXELS = 2


@pytest.fixture(scope="module")
def quick_figures(tmp_path_factory):
    """Each registered figure made once in quick mode, in its own folder: name -> (module,
    dir, paths). Shared by every test of this module: no figure is rendered twice."""
    made = {}

    def run(name):
        if name not in made:
            import importlib

            from vobscure.experiments.figures import FIGURES

            module = importlib.import_module(f"vobscure.experiments.figures.{FIGURES[name]}")
            out_dir = tmp_path_factory.mktemp(name)
            made[name] = (module, out_dir, module.make(out_dir, quick=True))
        return made[name]

    return run


@pytest.fixture(scope="module")
def conventions_png(quick_figures):
    """The conventions figure's (dir, paths): the same render as the registered-figure tests'."""
    _, out_dir, paths = quick_figures("conventions")
    return out_dir, paths


def test_conventions_returns_its_path(conventions_png):
    out_dir, paths = conventions_png
    assert paths == [out_dir / "conventions.png"]
    assert paths[0].is_file()
    # written atomically: no temporary file is left beside it
    assert sorted(p.name for p in out_dir.iterdir()) == ["conventions.png"]


def test_conventions_is_a_valid_png(conventions_png):
    import matplotlib.image as mpimg

    _, (path,) = conventions_png
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    assert image.shape[0] >= MIN_FIGURE_PIXELS[0] and image.shape[1] >= MIN_FIGURE_PIXELS[1]
    assert np.isfinite(image).all()
    rgb = image[..., :3]
    assert rgb.std() > 0.05  # something was drawn


def test_conventions_nothing_cut_off_at_the_border(conventions_png):
    import matplotlib.image as mpimg

    _, (path,) = conventions_png
    rgb = mpimg.imread(path)[..., :3]
    b = BORDER_PIXELS
    border = np.concatenate([rgb[:b].reshape(-1, 3), rgb[-b:].reshape(-1, 3),
                             rgb[:, :b].reshape(-1, 3), rgb[:, -b:].reshape(-1, 3)])
    assert np.all(border == 1.0), "a label or panel reaches the edge of the figure (clipped)"



# ----------------------------------------------------------------------------- every registered figure
#: Smallest acceptable PNG file of a registered figure, in bytes (a panel grid, not a stub).
MIN_PNG_BYTES = 20_000


def _registered():
    from vobscure.experiments.figures import FIGURES

    return list(FIGURES)


@pytest.mark.parametrize("name", _registered())
def test_registered_figure_quick(quick_figures, name):
    import matplotlib.image as mpimg

    module, out_dir, paths = quick_figures(name)
    assert paths and all(p.parent == out_dir and p.is_file() for p in paths)
    # written atomically: the folder holds exactly the files returned, no temporary ones
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(p.name for p in paths)
    pngs = [p for p in paths if p.suffix == ".png"]
    assert len(pngs) == 1, f"{name}: one PNG per figure module, got {[p.name for p in pngs]}"
    png = pngs[0]
    if hasattr(module, "FILENAME"):
        assert png.name == module.FILENAME
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size >= MIN_PNG_BYTES
    image = mpimg.imread(png)
    assert image.ndim == 3 and image.shape[2] in (3, 4)
    assert image.shape[0] >= MIN_FIGURE_PIXELS[0] and image.shape[1] >= MIN_FIGURE_PIXELS[1]
    rgb = image[..., :3]
    assert np.isfinite(rgb).all() and rgb.std() > 0.05, f"{name}: the figure is blank"


@pytest.mark.parametrize("name", _registered())
def test_registered_figure_nothing_cut_off_at_the_border(quick_figures, name):
    import matplotlib.image as mpimg

    _, _, paths = quick_figures(name)
    rgb = mpimg.imread(next(p for p in paths if p.suffix == ".png"))[..., :3]
    b = BORDER_PIXELS
    border = np.concatenate([rgb[:b].reshape(-1, 3), rgb[-b:].reshape(-1, 3),
                             rgb[:, :b].reshape(-1, 3), rgb[:, -b:].reshape(-1, 3)])
    assert np.all(border == 1.0), f"{name}: a label or panel reaches the edge of the figure (clipped)"


@pytest.mark.parametrize("name", _registered())
def test_registered_figure_csv_finite_and_in_range(quick_figures, name):
    import csv

    module, _, paths = quick_figures(name)
    csvs = [p for p in paths if p.suffix == ".csv"]
    if not csvs:
        pytest.skip(f"{name} writes no CSV")
    ranges = getattr(module, "CSV_RANGES", {})
    for path in csvs:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
        assert rows, f"{path.name} has no rows"
        for column in ranges:
            assert column in rows[0], f"{path.name} lacks the column {column!r}"
        for i, row in enumerate(rows):
            for column, cell in row.items():
                try:
                    value = float(cell)
                except ValueError:
                    continue    # a label, or an empty cell (not measured)
                assert np.isfinite(value), f"{path.name} row {i}: {column} = {cell}"
                if column in ranges:
                    lo, hi = ranges[column]
                    assert lo <= value <= hi, f"{path.name} row {i}: {column} = {value} not in [{lo}, {hi}]"


def test_make_all_checks_names(tmp_path):
    from vobscure.experiments.figures import FIGURES, make_all

    assert make_all(tmp_path, quick=True, names=[], progress=False) == []
    with pytest.raises(ValueError, match="fig5_thickness"):   # the message lists valid names
        make_all(tmp_path, quick=True, names=["no_such_figure"], progress=False)
    assert {"conventions", "screenspace_claims", "fig5_thickness", "fig6_normals", "fig7_lines_vs_points",
            "fig8_dual_radii", "table1_timings"} <= set(FIGURES)
    assert not any(tmp_path.iterdir())
