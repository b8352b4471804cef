"""Read the packages' plain-text docstring idioms as their authors meant them.

* ``|x|`` (absolute value, used throughout the docstrings) is not a reST substitution: bars
  outside inline literals, roles and literal blocks are escaped before numpydoc parses the text.
* The notes the docstrings cite, "physics.md §N" and "discrepancy.md §N", become links to those
  sections of ``docs/physics.md`` and ``docs/discrepancy.md``.
* Docstrings listed in :data:`docstring_policy.VERBATIM` are plain text that is not valid reST
  (indented lists without blank lines, ASCII layouts); they are shown as preformatted text so
  that the build stays strict for every other docstring.  The list is debt: fixing a docstring
  means deleting its name there (the build then checks it like the rest).
"""

from __future__ import annotations

import inspect
import re

import docstring_policy

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
    if name in docstring_policy.VERBATIM:
        return
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


def setup(app):
    # before numpydoc (priority 500) parses the sections
    app.connect("autodoc-process-docstring", process, priority=400)
    app.connect("autodoc-process-docstring", verbatim, priority=600)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
