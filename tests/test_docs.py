"""The documentation site builds with warnings as errors, and its examples run as written."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BUILD_TIMEOUT = 300  # seconds; the build takes about 5 s

needs_mkdocs = pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None,
    reason='mkdocs and mkdocstrings are not installed (python -m pip install -e ".[docs]")',
)


def _built(site: Path, page: Path) -> Path:
    """The HTML file mkdocs writes for ``page`` (use_directory_urls: a/b.md -> a/b/index.html)."""
    rel = page.relative_to(DOCS).with_suffix("")
    if rel.name == "index":
        return site / rel.parent / "index.html"
    return site / rel / "index.html"


def _url(page: Path) -> str:
    """The page's URL relative to the site root: a/b.md -> "a/b/", a/index.md -> "a/"."""
    rel = page.relative_to(DOCS).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "index" else rel.parts
    return "".join(part + "/" for part in parts)


def _python_blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
         str(ROOT / "mkdocs.yml"), "--site-dir", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=BUILD_TIMEOUT,
    )
    assert proc.returncode == 0, f"mkdocs build --strict failed:\n{proc.stdout}\n{proc.stderr}"
    return out


@needs_mkdocs
def test_site_builds_strict(site):
    assert (site / "index.html").is_file()
    for page in DOCS.rglob("*.md"):
        html = _built(site, page)
        assert html.is_file(), f"{page.relative_to(ROOT)} was not built ({html} missing)"


@needs_mkdocs
def test_api_pages_render_the_docstrings(site):
    api = sorted((DOCS / "api").glob("*.md"))
    assert api, "docs/api has no pages"
    # every page renders its ::: directives; spot-check one object per module page
    expected = {
        "camera": "vobscure.camera.Camera",
        "gbuffer": "vobscure.gbuffer.render_gbuffer",
        "groundtruth": "vobscure.groundtruth.ground_truth",
        "screenspace": "vobscure.screenspace.line.vo_line",
        "metrics": "vobscure.metrics.error",
        "estimate": "vobscure.estimate.Estimate",
    }
    for page in api:
        text = page.read_text()
        assert ":::" in text, f"{page.name} has no mkdocstrings directive"
        html = _built(site, page).read_text()
        assert ":::" not in html, f"{page.name}: a directive was left unrendered"
        if page.stem in expected:
            assert f'id="{expected[page.stem]}"' in html, f"{page.name}: {expected[page.stem]} missing"
    # the nav reaches every page: each one is linked from the home page's navigation
    home = (site / "index.html").read_text()
    for page in DOCS.rglob("*.md"):
        if page != DOCS / "index.md":
            assert f'href="{_url(page)}"' in home, f"{page.relative_to(DOCS)} is not in the site's navigation"


def test_getting_started_runs(tmp_path, monkeypatch):
    """The code of docs/getting-started.md runs in order in one namespace, as the page says."""
    blocks = _python_blocks(DOCS / "getting-started.md")
    assert len(blocks) >= 4, "getting-started.md lost its examples"
    monkeypatch.chdir(tmp_path)  # the page writes its PNGs into the working directory
    namespace: dict = {"__name__": "__getting_started__"}
    for block in blocks:
        exec(compile(block, str(DOCS / "getting-started.md"), "exec"), namespace)
    import numpy as np

    # what the page's comments claim
    gb, lines = namespace["gb"], namespace["lines"]
    assert lines.shape == gb.depth.shape == (64, 64)
    assert np.isnan(lines[~gb.valid]).all() and np.isfinite(lines[gb.valid]).all()
    assert np.nanmedian(lines) == pytest.approx(1.0, abs=0.01)
    assert float(np.nanmean(namespace["truth"].stderr)) < 0.01
    assert (tmp_path / "crease_lines.png").is_file() and (tmp_path / "crease_truth.png").is_file()


def test_home_page_example_runs(capsys):
    """The example on docs/index.md runs as written."""
    blocks = _python_blocks(DOCS / "index.md")
    assert blocks, "index.md has no python example"
    namespace: dict = {"__name__": "__docs_index__"}
    exec(compile(blocks[0], str(DOCS / "index.md"), "exec"), namespace)
    lines, truth = namespace["lines"], namespace["truth"]
    assert lines.shape == truth.value.shape == (48, 64)
    assert "ErrorReport(" in capsys.readouterr().out


def test_compare_page_example_runs(tmp_path, monkeypatch):
    """The Python example of docs/compare.md runs as written and returns one row per method."""
    blocks = _python_blocks(DOCS / "compare.md")
    assert len(blocks) == 1, "compare.md lost its example"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__compare_page__"}
    exec(compile(blocks[0], str(DOCS / "compare.md"), "exec"), namespace)
    rows = namespace["res"].rows
    assert [(r["method"], r["samples"]) for r in rows] == [("line", 5), ("point", 12)]
    assert all(0.0 <= r["screen_rmse"] < 1.0 for r in rows)
    assert not any(tmp_path.iterdir()), "write=False wrote files"


def test_methods_page_examples_run(capsys):
    """docs/methods.md: the registry listing and the ten-line "adding an estimator" example
    run as written; the new method gets a row beside the registered one, and is removed after."""
    from vobscure import methods

    blocks = _python_blocks(DOCS / "methods.md")
    assert len(blocks) == 2, "methods.md lost an example"
    adding = blocks[1].strip().splitlines()
    assert len([line for line in adding if line.strip()]) <= 14, "the example should stay short"
    namespace = {"__name__": "docs_methods"}
    try:
        for block in blocks:
            exec(compile(block, str(DOCS / "methods.md"), "exec"), namespace)
        labels = [r["label"] for r in namespace["res"].rows]
        assert labels == ["random_points:12", "point:12"]
        assert "random_points" in methods.names()
    finally:
        if "random_points" in methods.names():
            methods.unregister("random_points")
    out = capsys.readouterr().out
    assert "point:33 32 128 half-ball VO" in out
