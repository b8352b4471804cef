"""The in-depth check of ``tests/test_docstrings.py`` (part of the docstring audit, see
``docstring_audit``): ``__all__`` of physmodel, surrogate and inversion and every public method and
property of those classes, inherited ones included, must have a docstring of their own (not the
``Name(field, ...)`` text that ``dataclasses`` writes), every signature parameter in a numpydoc
``Parameters`` section, and a unit in square brackets for each numerical parameter.
"""

from __future__ import annotations

import importlib
import inspect
import re
import warnings
from functools import lru_cache

CHECKED_PACKAGES = ("physmodel", "surrogate", "inversion")
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
    return mod.split(".")[0] in CHECKED_PACKAGES


@lru_cache(maxsize=None)
def checked_objects() -> tuple[tuple[str, object, str], ...]:
    """(documented name, object, kind) for every name the test checks; kind is
    function|class|method|property."""
    out = []
    for pkg_name in CHECKED_PACKAGES:
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
    return tuple(out)


def signature_parameters(obj, kind) -> list[str]:
    """Parameter names of the signature (``*args``/``**kw`` with their stars), without self/cls.
    A ``typing.Protocol`` class has none (it is never instantiated; its signature is a placeholder)."""
    if inspect.isclass(obj) and getattr(obj, "_is_protocol", False):
        return []
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


def documented_parameters(doc_text: str, kind: str):
    """{name: (type, description)} from the numpydoc sections that document parameters."""
    from numpydoc import docscrape

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # unknown sections are reported elsewhere
        doc = docscrape.NumpyDocString(doc_text)
    sections = ["Parameters", "Other Parameters"] + (["Attributes"] if kind == "class" else [])
    out = {}
    for section in sections:
        for p in doc[section]:
            for raw in p.name.split(","):
                key = raw.strip()
                if key:
                    out[key] = (p.type or "", " ".join(p.desc))
    return out


def lookup(documented: dict, name: str):
    """The documented entry of a parameter (``*args`` may be documented as ``args``)."""
    for key in (name, name.lstrip("*")):
        if key in documented:
            return documented[key]
    return None


def checked_undocumented() -> set[str]:
    """Checked names without a docstring of their own."""
    return {q for q, obj, kind in checked_objects() if _own_doc(obj) is None}


def missing_parameters() -> dict[str, list[str]]:
    """{name: undocumented parameters} for documented functions, methods and classes."""
    out = {}
    for q, obj, kind in checked_objects():
        if kind == "property":
            continue
        doc = _own_doc(obj)
        if doc is None:
            continue
        params = signature_parameters(obj, kind)
        if not params:
            continue
        documented = documented_parameters(doc, kind)
        lacking = [p for p in params if lookup(documented, p) is None]
        if lacking:
            out[q] = lacking
    return out


def missing_units() -> dict[str, list[str]]:
    """{name: documented numerical parameters without a [unit]} (``[-]`` marks dimensionless)."""
    out = {}
    for q, obj, kind in checked_objects():
        if kind == "property":
            continue
        doc = _own_doc(obj)
        if doc is None:
            continue
        documented = documented_parameters(doc, kind)
        params = set(signature_parameters(obj, kind)) | (set(documented) if kind == "class" else set())
        lacking = []
        for p in sorted(params):
            entry = lookup(documented, p)
            if entry is None:
                continue
            typ, desc = entry
            if NUMERIC.search(typ) and not UNIT.search(typ + " " + desc):
                lacking.append(p.lstrip("*"))
        if lacking:
            out[q] = lacking
    return out
