"""Every public name of physmodel, surrogate and inversion is documented: a docstring, its
parameters in a numpydoc ``Parameters`` section, and a unit in square brackets for each
numerical parameter (the project's style: ``frequency_hz : array_like  Frequencies. [Hz]``).

What is checked: each name in the package's ``__all__`` that is a function or a class, and the
public methods and properties of those classes (defined in this project, not inherited from
Python).  The oracle is numpydoc's own parser (``numpydoc.docscrape``) against
``inspect.signature``.

Ratchet: the debt measured on the pre-restructure tree is listed in
``docs/_ext/docstring_policy.py`` (the docs build reads the same file).  A name not listed must
pass; a listed name that passes makes ``test_docstring_debt_is_current`` fail, so the lists only
shrink.  Fix a docstring, then delete its name from the list.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
import warnings
from pathlib import Path

from numpydoc import docscrape as numpydoc_docscrape   # in the test extras: never skipped

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import docstring_policy  # noqa: E402

PACKAGES = ("physmodel", "surrogate", "inversion")
#: Type words that mark a numerical parameter, which then needs a unit in square brackets.
NUMERIC = re.compile(r"\b(float|floats|complex|array|array_like|ndarray|scalar|number|numeric)\b")
UNIT = re.compile(r"\[[^\]]+\]")


def _own_doc(obj) -> str | None:
    """The object's own docstring (not one inherited from a base class or Python itself, and not
    the ``Name(field, ...)`` text that ``dataclasses`` writes for an undocumented class)."""
    if inspect.isclass(obj):
        doc = obj.__dict__.get("__doc__")
        if doc and doc.startswith(obj.__name__ + "("):
            return None
    elif isinstance(obj, property):
        doc = obj.fget.__doc__ if obj.fget else None
    else:
        doc = getattr(obj, "__doc__", None)
    return inspect.cleandoc(doc) if doc and doc.strip() else None


def _ours(obj) -> bool:
    mod = getattr(obj, "__module__", "") or ""
    return mod.split(".")[0] in PACKAGES


def public_objects():
    """(documented name, object, kind) for every checked name; kind is function|class|method|property."""
    out = []
    for pkg_name in PACKAGES:
        pkg = importlib.import_module(pkg_name)
        for name in pkg.__all__:
            obj = getattr(pkg, name)
            qual = f"{pkg_name}.{name}"
            if inspect.isclass(obj):
                out.append((qual, obj, "class"))
                seen = set()
                for klass in obj.__mro__:
                    if not _ours(klass):
                        continue
                    for attr, member in vars(klass).items():
                        if attr.startswith("_") or attr in seen:
                            continue
                        seen.add(attr)
                        if isinstance(member, property):
                            out.append((f"{qual}.{attr}", member, "property"))
                        elif isinstance(member, (staticmethod, classmethod)):
                            out.append((f"{qual}.{attr}", member.__func__, "method"))
                        elif inspect.isfunction(member):
                            out.append((f"{qual}.{attr}", member, "method"))
            elif inspect.isroutine(obj):
                out.append((qual, obj, "function"))
    return out


OBJECTS = public_objects()


def _signature_parameters(obj, kind) -> list[str]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    names = []
    for i, p in enumerate(sig.parameters.values()):
        if kind == "method" and i == 0 and p.name in ("self", "cls"):
            continue
        if p.name.startswith("_"):
            continue
        if p.kind is p.VAR_POSITIONAL:
            names.append("*" + p.name)
        elif p.kind is p.VAR_KEYWORD:
            names.append("**" + p.name)
        else:
            names.append(p.name)
    return names


def _documented(doc_text: str, kind: str):
    """{name: (type, description)} from the numpydoc sections that document parameters."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # unknown sections are reported elsewhere
        doc = numpydoc_docscrape.NumpyDocString(doc_text)
    sections = ["Parameters", "Other Parameters"] + (["Attributes"] if kind == "class" else [])
    out = {}
    for section in sections:
        for p in doc[section]:
            for raw in p.name.split(","):
                key = raw.strip()
                if key:
                    out[key] = (p.type or "", " ".join(p.desc))
    return out


def _lookup(documented: dict, name: str):
    for key in (name, name.lstrip("*")):
        if key in documented:
            return documented[key]
    return None


def missing_docstrings() -> set[str]:
    return {q for q, obj, kind in OBJECTS if _own_doc(obj) is None}


def missing_parameters() -> dict[str, list[str]]:
    """{name: undocumented parameters} for documented functions, methods and classes."""
    out = {}
    for q, obj, kind in OBJECTS:
        if kind == "property":
            continue
        doc = _own_doc(obj)
        if doc is None:
            continue
        params = _signature_parameters(obj, kind)
        if not params:
            continue
        documented = _documented(doc, kind)
        lacking = [p for p in params if _lookup(documented, p) is None]
        if lacking:
            out[q] = lacking
    return out


def missing_units() -> dict[str, list[str]]:
    """{name: documented numerical parameters without a [unit]} (``[-]`` marks dimensionless)."""
    out = {}
    for q, obj, kind in OBJECTS:
        if kind == "property":
            continue
        doc = _own_doc(obj)
        if doc is None:
            continue
        documented = _documented(doc, kind)
        params = set(_signature_parameters(obj, kind)) | (set(documented) if kind == "class" else set())
        lacking = []
        for p in sorted(params):
            entry = _lookup(documented, p)
            if entry is None:
                continue
            typ, desc = entry
            if NUMERIC.search(typ) and not UNIT.search(typ + " " + desc):
                lacking.append(p.lstrip("*"))
        if lacking:
            out[q] = lacking
    return out


def _checked_debt(known) -> set[str]:
    """The listed names this test can see (the others are the docs build's, for submodules)."""
    checked = {q for q, _, _ in OBJECTS}
    return {n for n in known if n in checked}


def _documented_fn(frequency_hz, gain, n_points=3, *args, **kwargs):
    """Evaluate something.

    Parameters
    ----------
    frequency_hz : array_like
        Frequencies. [Hz]
    gain : float
        A gain without its unit.
    n_points : int
        How many.
    *args, **kwargs
        Passed on.
    """


def _partly_documented_fn(a, b):
    """Summary only, no sections."""


class _Undocumented:
    def method(self, x):
        return x


def test_the_checker_on_known_cases():
    """The rules themselves, on objects written for them (independent of the packages)."""
    doc = _own_doc(_documented_fn)
    documented = _documented(doc, "function")
    params = _signature_parameters(_documented_fn, "function")
    assert params == ["frequency_hz", "gain", "n_points", "*args", "**kwargs"]
    assert all(_lookup(documented, p) is not None for p in params)
    assert _lookup(_documented(_own_doc(_partly_documented_fn), "function"), "a") is None
    assert _own_doc(_Undocumented) is None and _own_doc(_Undocumented.method) is None
    typ, desc = documented["gain"]
    assert NUMERIC.search(typ) and not UNIT.search(typ + " " + desc)       # would be reported
    typ, desc = documented["frequency_hz"]
    assert NUMERIC.search(typ) and UNIT.search(typ + " " + desc)           # passes
    assert not NUMERIC.search(documented["n_points"][0])                   # counts need no unit


def test_the_walk_finds_the_public_api():
    names = {q for q, _, _ in OBJECTS}
    # one name of each kind per package, so that an empty or broken walk cannot pass
    for expected in ("physmodel.ActuatorModel", "physmodel.ActuatorModel.frequency_response",
                     "physmodel.calibrate", "surrogate.ScheduledFit.fit", "surrogate.RationalModel.at",
                     "inversion.invert", "inversion.StreamingInverter.push"):
        assert expected in names
    assert len(names) > 150


def test_public_names_have_docstrings():
    new = sorted(missing_docstrings() - set(docstring_policy.KNOWN_UNDOCUMENTED))
    assert not new, f"public names without a docstring: {new}"


def test_documented_functions_list_their_parameters():
    missing = missing_parameters()
    new = {q: v for q, v in missing.items() if q not in docstring_policy.KNOWN_PARAMETERS_UNDOCUMENTED}
    assert not new, ("numpydoc 'Parameters' sections lack these signature parameters "
                     f"(name: parameters): {new}")


def test_numerical_parameters_carry_units():
    missing = missing_units()
    new = {q: v for q, v in missing.items() if q not in docstring_policy.KNOWN_UNITS_MISSING}
    assert not new, f"numerical parameters documented without a [unit] (name: parameters): {new}"


def test_docstring_debt_is_current():
    """Every listed name still fails (else delete it from docs/_ext/docstring_policy.py)."""
    fixed = sorted(_checked_debt(docstring_policy.KNOWN_UNDOCUMENTED) - missing_docstrings())
    fixed += sorted(n for n in docstring_policy.KNOWN_PARAMETERS_UNDOCUMENTED if n not in missing_parameters())
    fixed += sorted(n for n in docstring_policy.KNOWN_UNITS_MISSING if n not in missing_units())
    assert not fixed, f"these names now pass; remove them from docs/_ext/docstring_policy.py: {fixed}"


if __name__ == "__main__":   # print the measured debt (used to write docstring_policy.py)
    print("undocumented:", len(missing_docstrings()))
    for n in sorted(missing_docstrings()):
        print("  ", n)
    mp = missing_parameters()
    print("parameters not documented:", len(mp), "names,", sum(map(len, mp.values())), "parameters")
    for n, v in sorted(mp.items()):
        print("  ", n, v)
    mu = missing_units()
    print("numerical parameters without a unit:", len(mu), "names,", sum(map(len, mu.values())), "parameters")
    for n, v in sorted(mu.items()):
        print("  ", n, v)
    print("checked names:", len(OBJECTS))
