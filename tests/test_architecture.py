"""The package's architecture, read statically from its source with ``ast``.

(a) no import cycle between the modules of ``vobscure``; (b) no module imports a private
name or a private module of another part of the package; (c) the core (everything but
``vobscure.experiments`` and ``vobscure.cli``) never imports the experiments or matplotlib.

Every import counts: module level and inside functions (a lazy import still ties the two
modules together), except under ``if TYPE_CHECKING:``. ``import vobscure`` (or ``from
vobscure import name`` of a non-module) inside a submodule is an edge to the package root,
whose ``__init__`` imports the submodules. ``from pkg import x`` where ``x`` is a submodule
is an edge to that submodule only, whether spelled relative or absolute.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE_DIR = Path(__file__).resolve().parents[1] / "vobscure"

#: Private modules any module of the package may import from (the package's shared helpers).
SHARED_PRIVATE = frozenset({"vobscure._validate", "vobscure._io"})
#: What the core modules must not import (packages and modules, with everything under them);
#: the CLI too, which imports the experiments: checked on direct imports, this covers the
#: transitive ones.
CORE_FORBIDDEN = ("vobscure.experiments", "vobscure.cli", "matplotlib")
#: Modules outside the core (with everything under them).
NON_CORE = ("vobscure.experiments", "vobscure.cli")


# ----------------------------------------------------------------------------- the helper
@dataclass(frozen=True)
class Import:
    """One import statement's binding: ``importer`` imports ``target`` (a dotted module,
    inside the package or not) at ``line``; ``name`` is the attribute taken from ``target``
    (``from target import name``), None when the module itself is imported."""

    importer: str
    target: str
    name: str | None
    line: int

    def __str__(self) -> str:
        what = self.target if self.name is None else f"{self.name} from {self.target}"
        return f"{self.importer} imports {what} (line {self.line})"


def package_modules(package_dir: Path) -> dict[str, Path]:
    """Dotted name -> file of every module under ``package_dir`` (a package is its __init__)."""
    modules = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = [package_dir.name, *path.relative_to(package_dir).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports_of(module: str, path: Path, modules: dict[str, Path]) -> list[Import]:
    """Every import in ``path`` (module ``module``), resolved against ``modules``."""
    is_package = path.name == "__init__.py"
    found: list[Import] = []

    def add(target, name, node):
        found.append(Import(module, target, name, node.lineno))

    def visit(node):
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, None, node)
        elif isinstance(node, ast.ImportFrom):
            source = node.module
            if node.level:
                base = module.split(".")[:None if is_package else -1]
                keep = len(base) - (node.level - 1)     # None: beyond the top level
                source = ".".join(base[:keep] + ([node.module] if node.module else [])) if keep > 0 else None
            for alias in node.names if source else ():
                if f"{source}.{alias.name}" in modules:      # a submodule
                    add(f"{source}.{alias.name}", None, node)
                else:
                    add(source, alias.name, node)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
    return found


def all_imports(package_dir: Path) -> tuple[dict[str, Path], list[Import]]:
    modules = package_modules(package_dir)
    return modules, [imp for name, path in modules.items() for imp in imports_of(name, path, modules)]


def import_graph(modules, imports) -> dict[str, set[str]]:
    """module -> the package's modules it imports (no self-loops)."""
    graph = {name: set() for name in modules}
    for imp in imports:
        if imp.target in modules and imp.target != imp.importer:
            graph[imp.importer].add(imp.target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module, each sorted."""
    def reachable(start):
        seen, todo = set(), [start]
        while todo:
            for nxt in graph[todo.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    reach = {name: reachable(name) for name in graph}
    components = {frozenset({v} | {u for u in reach[v] if v in reach[u]}) for v in graph}
    return sorted(sorted(c) for c in components if len(c) > 1)


def _under(module: str, prefixes) -> bool:
    return any(module == p or module.startswith(p + ".") for p in prefixes)


def _private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def private_imports(modules, imports) -> list[Import]:
    """Imports of a private name, or from a private module, of another part of the package.

    Allowed: the package's shared helpers (SHARED_PRIVATE), and a ``_module`` of the
    importer's own (sub)package with anything in it.
    """
    root = min(modules, key=len)
    bad = []
    for imp in imports:
        if imp.target.split(".")[0] != root or imp.target == imp.importer:
            continue
        parts = imp.target.split(".")
        if not (any(_private(p) for p in parts[1:]) or (imp.name is not None and _private(imp.name))):
            continue
        own_package = imp.importer if modules[imp.importer].name == "__init__.py" else imp.importer.rpartition(".")[0]
        if imp.target in SHARED_PRIVATE or (_private(parts[-1]) and ".".join(parts[:-1]) == own_package):
            continue
        bad.append(imp)
    return bad


def _cycle_report(imports, components) -> str:
    """Each component, then its internal edges with the lines of the imports."""
    lines = []
    for comp in components:
        edges = {}
        for imp in imports:
            if imp.importer in comp and imp.target in comp and imp.target != imp.importer:
                edges.setdefault((imp.importer, imp.target), set()).add(imp.line)
        lines.append("cycle: " + ", ".join(comp))
        lines += [f"    {a} -> {b} (line {', '.join(map(str, sorted(n)))})" for (a, b), n in sorted(edges.items())]
    return "\n".join(lines)


# ----------------------------------------------------------------------------- the helper, tested
def _write(root: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return root / "pkg"


@pytest.fixture
def toy(tmp_path):
    return _write(tmp_path, {
        "pkg/__init__.py": "from . import a\nfrom .sub import c\n",
        "pkg/a.py": "from . import b\n\ndef _hidden():\n    pass\n",
        "pkg/b.py": "def f():\n    from .a import _hidden\n    return _hidden\n",
        "pkg/sub/__init__.py": "",
        "pkg/sub/_priv.py": "def helper():\n    pass\n",
        "pkg/sub/c.py": ("from typing import TYPE_CHECKING\nfrom ._priv import helper\n"
                         "if TYPE_CHECKING:\n    from ..d import thing\nelse:\n    import numpy\n"),
        "pkg/d.py": ("import pkg as p\nfrom pkg.sub._priv import helper\nfrom .sub import c\n"
                     "from .. import nothing\nthing = 1\n"),
    })


def test_helper_resolves_every_kind_of_import(toy):
    modules, imports = all_imports(toy)
    assert set(modules) == {"pkg", "pkg.a", "pkg.b", "pkg.sub", "pkg.sub._priv", "pkg.sub.c", "pkg.d"}
    graph = import_graph(modules, imports)
    assert graph["pkg"] == {"pkg.a", "pkg.sub.c"}          # a package's own submodules: edges
    assert graph["pkg.a"] == {"pkg.b"}                      # from . import b: the submodule
    assert graph["pkg.b"] == {"pkg.a"}                      # a function-level import is seen
    assert graph["pkg.sub.c"] == {"pkg.sub._priv"}          # TYPE_CHECKING ignored, else kept
    assert graph["pkg.d"] == {"pkg", "pkg.sub._priv", "pkg.sub.c"}   # import pkg: the root
    assert any(i.importer == "pkg.sub.c" and i.target == "numpy" for i in imports)


def test_helper_detects_a_two_module_cycle(toy):
    modules, imports = all_imports(toy)
    assert cycles(import_graph(modules, imports)) == [["pkg.a", "pkg.b"]]
    # without the function-level import there is none
    (toy / "b.py").write_text("def f():\n    pass\n", encoding="utf-8")
    modules, imports = all_imports(toy)
    assert cycles(import_graph(modules, imports)) == []


def test_helper_detects_a_cycle_through_the_root(toy):
    (toy / "a.py").write_text("import pkg\n", encoding="utf-8")
    modules, imports = all_imports(toy)
    assert cycles(import_graph(modules, imports)) == [["pkg", "pkg.a"]]


def test_helper_flags_private_imports(toy):
    modules, imports = all_imports(toy)
    flagged = {(i.importer, i.target, i.name) for i in private_imports(modules, imports)}
    # pkg.sub.c's import of its own package's _priv is allowed; pkg.d's is not
    assert flagged == {("pkg.b", "pkg.a", "_hidden"), ("pkg.d", "pkg.sub._priv", "helper")}


# ----------------------------------------------------------------------------- the package
@pytest.fixture(scope="module")
def package():
    modules, imports = all_imports(PACKAGE_DIR)
    assert "vobscure.screenspace.area" in modules and imports
    return modules, imports


def test_no_import_cycles(package):
    modules, imports = package
    found = cycles(import_graph(modules, imports))
    assert not found, "import cycles between modules of vobscure:\n" + _cycle_report(imports, found)


def test_no_private_imports_across_modules(package):
    bad = private_imports(*package)
    assert not bad, "private names imported from another module of vobscure:\n" + "\n".join(
        f"    {imp}" for imp in bad)


def test_core_imports_neither_experiments_nor_matplotlib(package):
    modules, imports = package
    bad = [imp for imp in imports if not _under(imp.importer, NON_CORE) and _under(imp.target, CORE_FORBIDDEN)]
    assert not bad, "core modules importing the experiments, the CLI or matplotlib:\n" + "\n".join(
        f"    {imp}" for imp in bad)
