"""Figure modules run end to end in quick mode (STYLE.md item 9): they write a valid PNG."""

from __future__ import annotations

import numpy as np
import pytest

#: Smallest acceptable (height, width) of a figure, in pixels: a panel grid, not a thumbnail.
MIN_FIGURE_PIXELS = (600, 600)
#: Width of the border strip that must stay blank (nothing drawn is cut off at the edge).
BORDER_PIXELS = 2


@pytest.fixture(scope="module")
def conventions_png(tmp_path_factory):
    from vobscure.experiments.figures import conventions

    out_dir = tmp_path_factory.mktemp("figures")
    return out_dir, conventions.make(out_dir, quick=True)


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

