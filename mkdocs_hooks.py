"""Build helpers for the documentation site (mkdocs.yml names both).

- ``on_config``, an MkDocs hook, keeps the nav in step with the pages in docs/. Pages are
  written by several changes at once: a nav entry whose file does not exist would fail
  ``mkdocs build --strict``, and a page left out of the nav would be unreachable. So the
  entries whose file is missing are dropped, and every other Markdown page of the docs
  folder (but the run reports under ``img/``) is appended under "More".
- ``SphinxMarkup``, a griffe extension used by mkdocstrings, turns the Sphinx markup of the
  numpydoc docstrings into Markdown, their mathematics into the ``$...$`` / ``$$...$$`` that
  pymdownx.arithmatex hands to the site's KaTeX (mkdocs.yml).

Nothing here downloads anything.
"""

from __future__ import annotations

import re
from pathlib import Path

import griffe


def _prune(items, docs: Path, listed: set) -> list:
    """The nav ``items`` without pages missing from ``docs``; collects the pages kept."""
    kept = []
    for item in items:
        title, value = next(iter(item.items())) if isinstance(item, dict) else (None, item)
        if isinstance(value, list):
            value = _prune(value, docs, listed)
            if not value:
                continue
        elif "://" not in value:
            if not (docs / value).is_file():
                continue
            listed.add(Path(value).as_posix())
        kept.append(value if title is None else {title: value})
    return kept


def on_config(config, **kwargs):
    if not config.get("nav"):
        return config
    docs = Path(config["docs_dir"])
    listed: set = set()
    nav = _prune(config["nav"], docs, listed)
    extra = sorted(p.relative_to(docs).as_posix() for p in docs.rglob("*.md"))
    # the reports that `vobscure compare` writes next to its images (docs/img/**/results.md)
    # are reached from the pages that cite them, not from the nav
    extra = [p for p in extra if p not in listed and not p.startswith("img/")]
    if extra:
        nav.append({"More": extra})
    config["nav"] = nav
    return config


# --- griffe extension (mkdocs.yml: handlers.python.options.extensions) -------------------
# The docstrings are written for numpydoc/Sphinx: cross-reference roles (:func:`x`,
# :class:`~a.B`), ``.. math::`` directives, ``.. [1]`` citations and ``text::`` before a
# literal block, which Markdown would show verbatim. Roles become code spans naming the object
# (the last component for ``~``); a :math: role becomes inline math, $...$, and a math
# directive display math, a $$ ... $$ block, which pymdownx.arithmatex passes to KaTeX; a
# citation keeps its label, ``[1]``; ``::`` at the end of a line becomes ``:`` (the indented
# block after it is code in Markdown too).

_ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|obj|exc|const):`(~?)([^`]+)`")
_MATH_ROLE = re.compile(r":math:`([^`]+)`")
_CITATION = re.compile(r"^(\s*)\.\. (\[[^\]]+\])", flags=re.M)
_LITERAL = re.compile(r"(\S)::$", flags=re.M)
_MATH = re.compile(r"^(\s*)\.\. math::\s*(.*)$")


def _code_span(match: re.Match) -> str:
    tilde, target = match.groups()
    if tilde:
        target = target.rsplit(".", 1)[-1]
    return f"`{target}`"


def _inline_math(match: re.Match) -> str:
    # on one line, without blanks next to the dollars: arithmatex does not read "$ x $" as
    # math (smart dollars keep prices such as "$5 and $6" as text)
    return "$" + " ".join(match.group(1).split()) + "$"


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _math_blocks(text: str) -> str:
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        m = _MATH.match(lines[i])
        if not m:
            out.append(lines[i])
            i += 1
            continue
        indent, body = m.group(1), [m.group(2).strip()] if m.group(2).strip() else []
        i += 1
        if not body:  # the block form: blank lines, then the indented body
            while i < len(lines) and not lines[i].strip():
                i += 1
        # the body (or the continuation of a one-line directive): the lines indented deeper
        # than the directive, up to the first line that is not
        while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > len(indent)):
            body.append(lines[i].strip())
            i += 1
        while body and not body[-1]:
            body.pop()
        if out and out[-1].strip():
            out.append("")  # arithmatex reads a $$ block only as a paragraph of its own
        out += [indent + "$$", *(indent + b for b in body if b), indent + "$$"]
        if i < len(lines) and lines[i].strip():
            out.append("")
    return "\n".join(out)


class SphinxMarkup(griffe.Extension):
    """Turn Sphinx roles and math directives in docstrings into Markdown."""

    def on_instance(self, *, obj, **kwargs) -> None:
        doc = obj.docstring
        if doc is None:
            return
        value = doc.value
        if ":`" in value:
            value = _MATH_ROLE.sub(_inline_math, value)
            value = _ROLE.sub(_code_span, value)
        if ".. math::" in value:
            value = _math_blocks(value)
        if ".. [" in value:
            value = _CITATION.sub(r"\1\2", value)
        if "::" in value:
            value = _LITERAL.sub(r"\1:", value)
        doc.value = value
