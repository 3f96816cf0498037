"""The package's import rules.

The rules are import-linter contracts in ``pyproject.toml`` (``[tool.importlinter]``), run here
with ``lint-imports``: the core (everything but ``vobscure.experiments`` and ``vobscure.cli``)
never imports the experiments, the CLI or matplotlib; a private module is imported only from
inside its parent package; no import cycle between the parts of a package.

Two rules import-linter does not state are checked on its import graph (grimp):

- no import cycle through a package's own ``__init__`` (``acyclic_siblings`` compares the parts
  of a package with each other, never with the package itself);
- no module imports a private *name* from another module (import-linter's graph has modules,
  not names, and its maintainer declines symbol-level contracts).
"""

from __future__ import annotations

import ast
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import grimp
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_DIR = ROOT / "vobscure"


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


@pytest.fixture(scope="module")
def graph():
    return grimp.build_graph("vobscure", exclude_type_checking_imports=True, cache_dir=None)


def test_import_contracts():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
           "NO_COLOR": "1", "COLUMNS": "160"}
    run = subprocess.run(
        [sys.executable, "-c", "from importlinter.cli import lint_imports_command; lint_imports_command()",
         str(ROOT / "pyproject.toml"), "--no-cache"],
        cwd=ROOT, env=env, capture_output=True, text=True)
    assert run.returncode == 0 and "0 broken" in run.stdout, run.stdout + run.stderr


def test_no_import_cycle_between_modules(graph):
    assert graph.find_matching_modules("vobscure.screenspace.*"), "the graph lacks the package"
    bad = [" -> ".join((a, *graph.find_shortest_chain(importer=b, imported=a)))
           for a in sorted(graph.modules) for b in sorted(graph.find_modules_directly_imported_by(a))
           if graph.chain_exists(importer=b, imported=a)]
    assert not bad, "import cycles between modules of vobscure:\n    " + "\n    ".join(bad)


def test_no_private_names_imported_across_modules(graph):
    bad = []
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        module = ".".join(parts[:-1] if path.name == "__init__.py" else parts)
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            source = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
            # a private module's contents are the private_modules contract's concern
            if source in graph.modules and source != module and not _private(source.rpartition(".")[2]):
                bad += [f"{module} imports {alias.name} from {source} (line {node.lineno})"
                        for alias in node.names
                        if _private(alias.name) and f"{source}.{alias.name}" not in graph.modules]
    assert not bad, "private names imported from another module of vobscure:\n    " + "\n    ".join(bad)
