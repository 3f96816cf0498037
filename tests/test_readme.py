"""The README's example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "README.md has no python example"
    namespace: dict = {}
    exec(compile(blocks[0], str(README), "exec"), namespace)
    e = namespace["e"]
    # the example's claim: the estimate sits on the closed form within its standard error
    from analytic import crease_cosine_ao
    from conftest import t_threshold
    from vobscure.groundtruth import DEFAULT_GROUPS

    assert abs(e.value[0] - crease_cosine_ao(0.5)) < t_threshold(DEFAULT_GROUPS - 1) * e.stderr[0]
    assert "(96, 128)" in capsys.readouterr().out


def test_readme_commands():
    """The README's install line runs the main job, and .ci/run runs what the README says."""
    text = README.read_text()
    assert 'python -m pip install -e ".[test]" && vobscure compare' in text
    assert "python -m pytest" in text
    ci = (README.parent / ".ci" / "run").read_text()
    assert 'python -m pip install -e ".[test]"' in ci and "vobscure compare" in ci
    assert "python -m pytest" in ci


def test_readme_images_and_links_exist():
    """Every image and relative link of the README points at a file of the repository."""
    import re

    text = README.read_text()
    targets = re.findall(r"\]\(([^)#\s]+)\)", text)
    assert any(t.endswith("tradeoff.png") for t in targets), "the README lost the trade-off plot"
    for target in targets:
        if "://" not in target:
            assert (README.parent / target).exists(), f"README links to missing {target}"
