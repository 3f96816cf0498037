"""The documentation site builds with warnings as errors, and its examples run as written."""

from __future__ import annotations

import html
import importlib.util
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BUILD_TIMEOUT = 300  # seconds; the build takes about 5 s
KATEX = "assets/katex"  # where the site serves its own KaTeX (docs/assets/katex/PROVENANCE.txt)
KATEX_VERSION = "0.19.1"
NODE_TIMEOUT = 60  # seconds; KaTeX typesets every formula of the site in about 1 s

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
        "gbuffer": "vobscure.gbuffer.GBuffer",
        "render": "vobscure.render.render_gbuffer",
        "convert": "vobscure.convert.convert_buffers",
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
    # the nav reaches every page: each one is linked from the home page's navigation, except
    # the run reports under img/ (written by `vobscure compare`), which are built and reached
    # from the pages that cite them
    home = (site / "index.html").read_text()
    for page in DOCS.rglob("*.md"):
        if page == DOCS / "index.md":
            continue
        if page.relative_to(DOCS).parts[0] == "img":
            assert _built(site, page).is_file(), f"{page.relative_to(DOCS)} was not built"
            assert f'href="{_url(page)}"' not in home, f"{page.relative_to(DOCS)}: a run report in the nav"
            continue
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


# --- mathematics: KaTeX served by the site itself, formulas as arithmatex spans -------------

_TAG = re.compile(r"<(script|link)\b([^>]*)>", flags=re.I)
_ATTR = re.compile(r"""\b(src|href|rel)\s*=\s*["']([^"']*)["']""", flags=re.I)
# <link> relations whose target the browser fetches with the page (not canonical, alternate, ...)
_FETCHED_RELS = {"stylesheet", "icon", "preload", "modulepreload", "manifest", "prefetch"}
_MATH_SPAN = re.compile(r'<(span|div) class="arithmatex">(.*?)</\1>', flags=re.S)


def _html_pages(site: Path) -> list[Path]:
    return sorted(p for p in site.rglob("*.html") if p.name != "404.html")


def _loaded_urls(page_html: str) -> list[str]:
    """The URLs a page loads by itself: script sources and the hrefs of the <link> elements
    the browser fetches (stylesheets, icons, preloads). Hyperlinks (<a href>) and a canonical
    <link> are only followed when asked for."""
    urls = []
    for tag, attrs in _TAG.findall(page_html):
        found = {name.lower(): value for name, value in _ATTR.findall(attrs)}
        if tag.lower() == "script" and "src" in found:
            urls.append(found["src"])
        elif tag.lower() == "link" and "href" in found:
            if set(found.get("rel", "").lower().split()) & _FETCHED_RELS:
                urls.append(found["href"])
    return urls


def _formulas(site: Path) -> list[tuple[str, bool, str]]:
    """(page, display, TeX) of every formula that arithmatex left in the built site."""
    found = []
    for page in _html_pages(site):
        for tag, body in _MATH_SPAN.findall(page.read_text()):
            tex = html.unescape(body).strip()
            if tex[:2] in ("\\(", "\\[") and tex[-2:] in ("\\)", "\\]"):
                tex = tex[2:-2]
            found.append((page.relative_to(site).as_posix(), tag == "div", tex))
    return found


@needs_mkdocs
def test_math_assets_are_served_by_the_site(site):
    """KaTeX's script, stylesheet and the fonts the stylesheet names are in the built site,
    and every page loads the script and stylesheet by a relative URL that resolves to them."""
    katex = site / KATEX
    for name in ("katex.min.js", "katex.min.css", "LICENSE", "PROVENANCE.txt"):
        assert (katex / name).is_file(), f"{KATEX}/{name} is not in the site"
    assert f"KaTeX {KATEX_VERSION}" in (katex / "PROVENANCE.txt").read_text()
    assert f'version:"{KATEX_VERSION}"' in (katex / "katex.min.js").read_text().replace(" ", "")
    # the stylesheet's woff2 fonts (browsers take the first format they read: woff2)
    fonts = re.findall(r"url\((fonts/[^)]+\.woff2)\)", (katex / "katex.min.css").read_text())
    assert len(fonts) >= 20, "katex.min.css names fewer woff2 fonts than KaTeX has"
    missing = [f for f in fonts if not (katex / f).is_file()]
    assert not missing, f"fonts named by katex.min.css but not in the site: {missing}"
    for page in [site / "index.html", site / "conventions" / "index.html",
                 site / "api" / "index.html"]:
        urls = _loaded_urls(page.read_text())
        for asset in ("katex.min.js", "katex.min.css"):
            refs = [u for u in urls if u.endswith(f"{KATEX}/{asset}")]
            assert refs, f"{page.relative_to(site)} does not load {asset}"
            for ref in refs:
                assert "://" not in ref and not ref.startswith("/"), f"{ref} is not relative"
                assert (page.parent / ref).resolve() == (katex / asset).resolve(), \
                    f"{page.relative_to(site)}: {ref} does not lead to {KATEX}/{asset}"


@needs_mkdocs
def test_no_page_loads_anything_from_another_host(site):
    """The site works offline: no script, stylesheet or icon comes from a CDN or any host."""
    remote = {}
    for page in _html_pages(site):
        urls = [u for u in _loaded_urls(page.read_text())
                if re.match(r"(?i)(https?:)?//", u)]
        if urls:
            remote[page.relative_to(site).as_posix()] = urls
    assert not remote, f"pages that load from another host: {remote}"


@needs_mkdocs
def test_formulas_reach_the_pages_as_math(site):
    """$...$ and $$...$$ in docs/ and the docstrings' :math: roles and .. math:: directives
    arrive as arithmatex's spans (what katex-init.js typesets), with no Sphinx markup left."""
    conventions = (site / "conventions" / "index.html").read_text()
    assert '<span class="arithmatex">\\(' in conventions, "conventions.md: no inline math"
    assert '<div class="arithmatex">\\[' in conventions, "conventions.md: no display math"
    assert "katex-init.js" in conventions
    # docstrings: the API pages hold display and inline math, and no Sphinx math markup
    api = {page: page.read_text() for page in (site / "api").rglob("index.html")}
    assert any('<div class="arithmatex">\\[' in text for text in api.values()), \
        "no .. math:: directive of a docstring reached the API pages as display math"
    assert any('<span class="arithmatex">\\(' in text for text in api.values()), \
        "no :math: role of a docstring reached the API pages as inline math"
    for page, text in api.items():
        assert ".. math::" not in text and ":math:`" not in text, \
            f"{page.relative_to(site)}: Sphinx math markup left unconverted"


@needs_mkdocs
@pytest.mark.skipif(shutil.which("node") is None, reason="Node.js is not installed (node)")
def test_every_formula_typesets_in_katex(site):
    """Every formula of the site parses in the KaTeX the site serves, run in Node.js with
    errors raised: a formula KaTeX cannot read would show as red source text in the browser."""
    formulas = _formulas(site)
    assert len(formulas) >= 20, "the site has fewer formulas than the pages and docstrings hold"
    script = (
        "const katex = require(process.argv[1]);"
        "const items = JSON.parse(require('fs').readFileSync(0, 'utf8'));"
        "const bad = [];"
        "for (const [page, display, tex] of items) {"
        "  try { katex.renderToString(tex, {displayMode: display, throwOnError: true}); }"
        "  catch (e) { bad.push([page, tex, String(e.message)]); }"
        "}"
        "process.stdout.write(JSON.stringify(bad));"
    )
    proc = subprocess.run(
        ["node", "-e", script, str(site / KATEX / "katex.min.js")],
        input=json.dumps(formulas), capture_output=True, text=True, timeout=NODE_TIMEOUT,
    )
    assert proc.returncode == 0, proc.stderr
    bad = json.loads(proc.stdout)
    assert not bad, "formulas KaTeX cannot typeset:\n" + "\n".join(map(str, bad))


def test_sphinx_math_becomes_arithmatex_markdown():
    """mkdocs_hooks turns numpydoc math into the Markdown arithmatex reads: a :math: role on
    one line, a directive (one-line with continuation lines, or block form) into a $$ block
    set apart by blank lines, the text around it kept."""
    sys.path.insert(0, str(ROOT))
    try:
        import mkdocs_hooks
    finally:
        sys.path.remove(str(ROOT))
    role = mkdocs_hooks._MATH_ROLE.sub(mkdocs_hooks._inline_math, "with :math:`a +\n  b` here")
    assert role == "with $a + b$ here"
    one_line = "Text.\n.. math:: G = x, \\quad\n      a = 2\nAfter."
    assert mkdocs_hooks._math_blocks(one_line) == "Text.\n\n$$\nG = x, \\quad\na = 2\n$$\n\nAfter."
    block = "    Lead:\n\n    .. math::\n\n        S = 1\n            - r\n\n    Tail."
    assert mkdocs_hooks._math_blocks(block) == "    Lead:\n\n    $$\n    S = 1\n    - r\n    $$\n\n    Tail."
