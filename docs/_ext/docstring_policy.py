"""Docstring debt of the packages, measured, in one place: the docs build and
``tests/test_docstrings.py`` both read it.

The lists live in ``docstring_debt.json`` next to this file and are written by this script from
the code, never by hand::

    python docs/_ext/docstring_policy.py --update   # re-measure, rewrite the lists, print +/- names
    python docs/_ext/docstring_policy.py --check    # exit 1 if the lists differ from the code

Run ``--update`` after a merge that adds public names (it lists their debt) and after fixing
docstrings (it removes the fixed names).  The test ``test_docstring_debt_is_current`` fails
while a listed name already passes, so the lists cannot go stale, and a name that is not listed
is checked strictly: a public function, class, method or property without a docstring fails the
docs build and the test.

Names are the ones the API reference documents them under (``docs/_ext/ipmc_apigen.py``: the
package-level name for what a package exports, ``physmodel.ActuatorModel.state``; else the
module path).  The lists:

``undocumented``
    Public objects without a docstring: what the build renders (Sphinx's ``getdoc``) and what the
    test checks (``__all__`` of physmodel, surrogate, inversion and their classes' methods and
    properties; a dataclass whose only docstring is the one ``dataclasses`` writes counts).
``parameters_undocumented``
    {name: signature parameters missing from the numpydoc ``Parameters`` (classes: also
    ``Attributes``) section}.
``units_missing``
    {name: numerical parameters (float, complex, array, ...) documented without a unit in square
    brackets (``[-]`` for dimensionless)}.
``verbatim``
    Docstrings written as plain text that is not valid reST (indented lists without blank lines,
    ASCII layouts): the reference shows them preformatted instead of failing the build.
``unresolved_references``
    Cross-reference targets in docstrings that name nothing documented (mostly module paths from
    before the issue-19 restructure): the reference shows them as plain text.
``undocumented_bases``
    Public base classes shown by ``show-inheritance`` that no page documents.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEBT_FILE = HERE / "docstring_debt.json"

#: Cross-reference targets that are not ours (no intersphinx: CI builds offline) or are type words
#: of numpydoc parameter lines; the build does not check them ((role regex, target regex) pairs,
#: Sphinx's ``nitpick_ignore_regex``).
EXTERNAL_TARGETS = [
    # private names (bases shown by show-inheritance, private modules) are not documented
    (r"py:.*", r"(.*\.)?_[^.]*(\..*)?"),
    (r"py:.*", r"(numpy|np|scipy|control|casadi|matplotlib|distributed|dask|pathlib|os|typing|"
               r"collections|concurrent|argparse|io|json|datetime|dataclasses|enum)(\..*)?"),
    (r"py:.*", r"(ndarray|array_like|array-like|ArrayLike|Path|PathLike|Callable|Mapping|Sequence|"
               r"Iterable|Iterator|Any|Figure|Axes|Client|TransferFunction|StateSpace|"
               r"FrequencyResponseData|Namespace|ArgumentParser|_SubParsersAction|Generator|"
               r"SeedSequence|memmap|optional|default|callable|scalar|int|float|str|bool|dict|list|"
               r"tuple|complex|object|None|type|set|bytes|function|iterable|sequence|mapping|"
               r"array|arrays|path|file|float64|complex128|inf|nan|number|numbers|or|of|shape|"
               r"\(.*|.*\)|\{.*|.*\}|.*\[.*|.*\]|.*'.*|.*\".*|.*,.*|[0-9].*|\.\.\.)"),
]

_KEYS = ("undocumented", "parameters_undocumented", "units_missing", "verbatim", "unresolved_references",
         "undocumented_bases")


def load() -> dict:
    """The lists as stored (empty lists for a missing file or key)."""
    data = json.loads(DEBT_FILE.read_text(encoding="utf-8")) if DEBT_FILE.exists() else {}
    return {k: data.get(k, {} if k in ("parameters_undocumented", "units_missing") else []) for k in _KEYS}


_DEBT = load()
KNOWN_UNDOCUMENTED: set[str] = set(_DEBT["undocumented"])
KNOWN_PARAMETERS_UNDOCUMENTED: dict[str, list[str]] = dict(_DEBT["parameters_undocumented"])
KNOWN_UNITS_MISSING: dict[str, list[str]] = dict(_DEBT["units_missing"])
VERBATIM: set[str] = set(_DEBT["verbatim"])
UNRESOLVED_REFERENCES: set[str] = set(_DEBT["unresolved_references"])
UNDOCUMENTED_BASES: set[str] = set(_DEBT["undocumented_bases"])


def is_external(target: str, role: str = "py:obj") -> bool:
    """True for a cross-reference target the build does not check (:data:`EXTERNAL_TARGETS`)."""
    import re

    return any(re.fullmatch(r, role) and re.fullmatch(t, target) for r, t in EXTERNAL_TARGETS)


def _write(data: dict) -> None:
    text = json.dumps({k: data[k] for k in _KEYS}, indent=1, ensure_ascii=False, sort_keys=False)
    tmp = DEBT_FILE.with_suffix(".json.tmp")
    tmp.write_text(text + "\n", encoding="utf-8")
    tmp.replace(DEBT_FILE)


def _names(value) -> set[str]:
    return set(value) if not isinstance(value, dict) else {f"{k}: {', '.join(v)}" for k, v in value.items()}


def diff(old: dict, new: dict) -> dict[str, tuple[list[str], list[str]]]:
    """{list: (added, removed)} between two measurements."""
    out = {}
    for k in _KEYS:
        a, b = _names(old.get(k, [])), _names(new.get(k, []))
        out[k] = (sorted(b - a), sorted(a - b))
    return out


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python docs/_ext/docstring_policy.py",
                                 description="Measure the packages' docstring debt and compare it with "
                                             "docs/_ext/docstring_debt.json (or rewrite that file).")
    ap.add_argument("--update", action="store_true", help="rewrite docstring_debt.json from the code")
    ap.add_argument("--check", action="store_true", help="exit 1 if the file differs from the code")
    ap.add_argument("-v", "--verbose", action="store_true", help="list every added and removed name")
    args = ap.parse_args(argv)

    root = HERE.parents[1]
    sys.path.insert(0, str(root))      # measure this checkout's packages
    sys.path.insert(0, str(HERE))
    import docstring_audit

    new = docstring_audit.measure()
    changes = diff(_DEBT, new)
    total_added = total_removed = 0
    for k, (added, removed) in changes.items():
        total_added += len(added)
        total_removed += len(removed)
        print(f"{k:24s} {len(new[k]):4d} listed   +{len(added)} added   -{len(removed)} removed")
        if args.verbose or args.check or len(added) + len(removed) <= 40:
            for n in added:
                print(f"    + {n}")
            for n in removed:
                print(f"    - {n}")
    print(f"total: +{total_added} added, -{total_removed} removed")
    if args.update:
        _write(new)
        print(f"wrote {DEBT_FILE}")
        return 0
    if args.check and (total_added or total_removed):
        print("docstring_debt.json differs from the code: run python docs/_ext/docstring_policy.py --update")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
