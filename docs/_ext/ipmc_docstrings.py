"""Read the packages' plain-text docstring idioms as their authors meant them.

* ``|x|`` (absolute value, used throughout the docstrings) is not a reST substitution: bars
  outside inline literals, roles and literal blocks are escaped before numpydoc parses the text.
* The notes the docstrings cite, "physics.md §N" and "discrepancy.md §N", become links to those
  sections of ``docs/physics.md`` and ``docs/discrepancy.md``.
* Docstrings listed in :data:`docstring_policy.VERBATIM` are plain text that is not valid reST
  (indented lists without blank lines, ASCII layouts); they are shown as preformatted text so
  that the build stays strict for every other docstring.  The list is debt: fixing a docstring
  and running ``python docs/_ext/docstring_policy.py --update`` removes its name (the build then
  checks it like the rest).
* A public function, class, method or property without a docstring, and not listed in
  :data:`docstring_policy.KNOWN_UNDOCUMENTED`, is a warning (an error under ``-W``) that names
  it; the build ends with one summary of all of them.
"""

from __future__ import annotations

import inspect
import re

import docstring_policy
from sphinx.util import logging

logger = logging.getLogger(__name__)
_CHECKED_WHAT = {"function", "class", "exception", "method", "property", "classmethod", "staticmethod"}

_QUOTED = re.compile(r"(``.*?``|(?::[\w:+-]+:)?`[^`]*`_{0,2})")


_NOTE = re.compile(r"\b(physics|discrepancy)\.md(?: (§\s?(\d)))?")


def _link_note(m: re.Match) -> str:
    page, sec, num = m.group(1), m.group(2), m.group(3)
    if sec:
        return f":ref:`{page}.md {sec} <{page}-{num}>`"
    return f":doc:`{page}.md </{page}>`"


def escape_bars(line: str) -> str:
    """Escape ``|`` outside literals and roles; link the notes the docstrings cite
    (``physics.md §7`` → the section of docs/physics.md)."""
    parts = _QUOTED.split(line)
    for i in range(0, len(parts), 2):
        parts[i] = re.sub(r"(?<!\\)\|", r"\\|", parts[i])
        parts[i] = _NOTE.sub(_link_note, parts[i])
    return "".join(parts)


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def verbatim(app, what, name, obj, options, lines):
    """After numpydoc: show a listed plain-text docstring as it is written."""
    if name not in docstring_policy.VERBATIM:
        return
    raw = (inspect.getdoc(obj) or "").splitlines()
    lines[:] = ["::", ""] + [("    " + ln) if ln.strip() else "" for ln in raw] + [""]


def process(app, what, name, obj, options, lines):
    """Before numpydoc: escape ``|``, link the notes (not for docstrings shown verbatim)."""
    if name in docstring_policy.VERBATIM:
        return
    rewrite(lines)


def rewrite(lines: list[str]) -> None:
    """Escape ``|`` and link the notes in docstring ``lines`` (in place), outside literal blocks
    and doctests."""
    out = []
    literal_indent = None   # indentation of the paragraph that opened a literal block
    prev = ""
    for ln in lines:
        if literal_indent is not None:
            if ln.strip() and _indent(ln) <= literal_indent:
                literal_indent = None
            else:
                out.append(ln)
                prev = ln if ln.strip() else prev
                continue
        if prev.rstrip().endswith("::") and literal_indent is None and not ln.strip():
            out.append(ln)
            literal_indent = _indent(prev)
            continue
        if ln.lstrip().startswith(">>>") or ln.lstrip().startswith("..."):
            out.append(ln)
        else:
            out.append(escape_bars(ln))
        if ln.strip():
            prev = ln
    lines[:] = out


def undocumented(app, what, name, obj, options, lines):
    """First of all handlers: a rendered public object without a docstring that is not listed as
    debt is a warning naming it."""
    if what not in _CHECKED_WHAT or any(ln.strip() for ln in lines):
        return
    if name in docstring_policy.KNOWN_UNDOCUMENTED or name in _found(app):
        return                     # autosummary's table and the object's page both ask: warn once
    _found(app).add(name)
    logger.warning("undocumented public %s %s: write its docstring (numpydoc), or list it as debt with "
                   "'python docs/_ext/docstring_policy.py --update'", what, name,
                   type="ipmc", subtype="undocumented", location=_source(obj))


def _source(obj) -> str | None:
    """``file:line`` of an object's definition (for the warning), if Python knows it."""
    target = obj.fget if isinstance(obj, property) else getattr(obj, "__func__", obj)
    try:
        return f"{inspect.getsourcefile(target)}:{inspect.getsourcelines(target)[1]}"
    except (TypeError, OSError):
        return None


def _found(app) -> set:
    if not hasattr(app, "_ipmc_undocumented"):
        app._ipmc_undocumented = set()
    return app._ipmc_undocumented


def summary(app, exception):
    names = sorted(_found(app))
    if names and exception is None:
        logger.warning("%d public name(s) without a docstring (not listed in docs/_ext/docstring_debt.json):"
                       "\n    %s", len(names), "\n    ".join(names), type="ipmc", subtype="undocumented")


def setup(app):
    app.connect("autodoc-process-docstring", undocumented, priority=100)
    app.connect("build-finished", summary)
    # before numpydoc (priority 500) parses the sections
    app.connect("autodoc-process-docstring", process, priority=400)
    app.connect("autodoc-process-docstring", verbatim, priority=600)
    # the summary collects across documents in one process: serial reading (the build's default)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
