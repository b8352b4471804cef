"""Measure the packages' docstring debt without Sphinx: one walk that the docs build, the test and
``python docs/_ext/docstring_policy.py --update`` all share.

Two views of the public API:

* :func:`rendered_objects` — what the API reference renders (``ipmc_apigen.plan`` for the four
  packages, and the members autodoc shows of each class: its own public methods and
  properties).  The docs build fails on a name here without a docstring (Sphinx's own
  ``getdoc``, which inherits a method's docstring from a base class), on a docstring that is not
  valid reST, and on a cross-reference it cannot resolve.
* :func:`checked_objects` (in ``docstring_params``, re-exported here) — what
  ``tests/test_docstrings.py`` checks in depth (``__all__`` of
  physmodel, surrogate and inversion and every public method and property of those classes,
  inherited ones included): a docstring of its own (not the ``Name(field, ...)`` text that
  ``dataclasses`` writes), every signature parameter in a numpydoc ``Parameters`` section, and a
  unit in square brackets for each numerical parameter.

The oracles are numpydoc's parser (``numpydoc.docscrape``), ``inspect.signature`` and docutils.
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import re
import warnings
from functools import lru_cache

import docstring_policy
import ipmc_apigen
from docstring_params import (CHECKED_PACKAGES, NUMERIC, UNIT, _own_doc, checked_objects,  # noqa: F401
                              checked_undocumented, documented_parameters, lookup, missing_parameters,
                              missing_units, signature_parameters)

API_PACKAGES = ("physmodel", "surrogate", "inversion", "scenarios")
#: Python cross-reference roles in docstrings: ``:class:`~physmodel.FrequencySweep```.
ROLE = re.compile(r":(?:py:)?(class|func|meth|mod|obj|data|attr|exc|const):`(?:[^`<]*<)?[~!.]?([\w.]+)>?`")


# ------------------------------------------------------------------------ what the API renders
class Entry:
    """One rendered object: documented ``name``, the object, autodoc's ``what``, and the module
    and class that relative cross-references in its docstring are read against."""

    __slots__ = ("name", "obj", "what", "module", "cls")

    def __init__(self, name, obj, what, module, cls=None):
        self.name, self.obj, self.what, self.module, self.cls = name, obj, what, module, cls


def _class_members(cls):
    """(name, member, what) of the members autodoc shows: defined in the class itself, public."""
    for attr, member in vars(cls).items():
        if attr.startswith("_"):
            continue
        if isinstance(member, (property,)) or type(member).__name__ == "cached_property":
            yield attr, member, "property"
        elif isinstance(member, (staticmethod, classmethod)) or inspect.isfunction(member):
            yield attr, member, "method"
        elif not inspect.isclass(member) and not callable(member):
            yield attr, member, "attribute"
    for attr in getattr(cls, "__annotations__", {}):
        if not attr.startswith("_") and attr not in vars(cls):
            yield attr, None, "attribute"


def _what(obj) -> str:
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.ismodule(obj):
        return "module"
    if inspect.isroutine(obj):
        return "function"
    return "data"


@lru_cache(maxsize=None)
def rendered_objects() -> tuple[Entry, ...]:
    """Every object the API reference renders, under the name it is documented by."""
    out = []
    for package in API_PACKAGES:
        for module_name, own, _again in ipmc_apigen.plan(package):
            mod = importlib.import_module(module_name)
            out.append(Entry(module_name, mod, "module", module_name))
            for n in own:
                obj = getattr(mod, n)
                what = _what(obj)
                name = f"{module_name}.{n}"
                out.append(Entry(name, obj, what, module_name))
                if what in ("class", "exception"):
                    for attr, member, mwhat in _class_members(obj):
                        out.append(Entry(f"{name}.{attr}", member, mwhat, module_name, obj))
    return tuple(out)


def _sphinx_doc(entry: Entry) -> str:
    """The docstring autodoc shows (inherits a method's docstring from a base class)."""
    from sphinx.util.inspect import getdoc, safe_getattr

    obj = entry.obj
    if isinstance(obj, (staticmethod, classmethod)):
        obj = obj.__func__
    elif isinstance(obj, property):
        obj = obj.fget
    if entry.cls is not None:
        doc = getdoc(obj, safe_getattr, True, entry.cls, entry.name.rsplit(".", 1)[-1])
    else:
        doc = getdoc(obj, safe_getattr, True)
    return inspect.cleandoc(doc) if doc and doc.strip() else ""


def build_undocumented() -> set[str]:
    """Rendered functions, classes, methods and properties without a docstring (the build's
    'undocumented public name' errors)."""
    return {e.name for e in rendered_objects()
            if e.what not in ("module", "data", "attribute") and not _sphinx_doc(e)}


# --------------------------------------------------------------------- reST validity (docutils)
def _generic_role(name, rawtext, text, lineno, inliner, options=None, content=None):
    from docutils import nodes

    return [nodes.literal(rawtext, text)], []


@contextlib.contextmanager
def _lenient_sphinx_markup():
    """Let docutils accept Sphinx's roles and directives (their content is not checked)."""
    from docutils.parsers.rst import Directive, directives, roles

    class Generic(Directive):
        has_content = True
        optional_arguments = 100
        final_argument_whitespace = True
        option_spec = None

        def run(self):
            return []

    class AnyOptions(dict):
        def __missing__(self, key):
            return directives.unchanged

    Generic.option_spec = AnyOptions()
    old_role, old_directive = roles.role, directives.directive

    def role(name, language_module, lineno, reporter):
        fn, msgs = old_role(name, language_module, lineno, reporter)
        return (fn, msgs) if fn is not None else (_generic_role, [])

    def directive(name, language_module, document):
        cls, msgs = old_directive(name, language_module, document)
        return (cls, msgs) if cls is not None else (Generic, [])

    roles.role, directives.directive = role, directive
    try:
        yield
    finally:
        roles.role, directives.directive = old_role, old_directive


def _as_rendered(entry: Entry, text: str) -> str:
    """The docstring as the build parses it: the ``ipmc_docstrings`` rewrite, then numpydoc."""
    import ipmc_docstrings
    from numpydoc.docscrape_sphinx import get_doc_object

    lines = text.splitlines()
    ipmc_docstrings.rewrite(lines)
    if entry.what == "module":
        return "\n".join(lines)
    obj = entry.obj.fget if isinstance(entry.obj, property) else entry.obj
    if isinstance(obj, (staticmethod, classmethod)):
        obj = obj.__func__
    cfg = {"show_class_members": False, "class_members_toctree": False}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return str(get_doc_object(obj, entry.what, "\n".join(lines), config=cfg))


def invalid_rest() -> dict[str, str]:
    """{rendered name: first docutils problem} for docstrings that are not valid reST."""
    return dict(_invalid_rest())


@lru_cache(maxsize=None)
def _invalid_rest() -> tuple:
    from docutils.core import publish_doctree
    from docutils.utils import SystemMessage

    out = {}
    with _lenient_sphinx_markup():
        for e in rendered_objects():
            if e.what in ("attribute", "data"):
                continue
            doc = _sphinx_doc(e)
            if not doc:
                continue
            try:
                text = _as_rendered(e, doc)
            except Exception as exc:       # numpydoc cannot parse it: shown verbatim as well
                out[e.name] = f"numpydoc: {exc}"
                continue
            try:
                tree = publish_doctree(text, settings_overrides={
                    "report_level": 5, "halt_level": 5, "warning_stream": False, "file_insertion_enabled": False,
                    "raw_enabled": False, "input_encoding": "unicode"})
            except SystemMessage as exc:   # pragma: no cover - halt_level 5 never halts
                out[e.name] = str(exc)
                continue
            from docutils import nodes

            msgs = [m for m in tree.findall(nodes.system_message) if m["level"] >= 2]
            if msgs:
                out[e.name] = msgs[0].astext().splitlines()[0]
    return tuple(out.items())


# --------------------------------------------------------------------------- cross-references
@lru_cache(maxsize=None)
def _index():
    """(documented name -> object key, key -> documented names, last component -> names)."""
    by_name, by_key, by_last = {}, {}, {}
    for e in rendered_objects():
        k = object_key(e.obj)
        by_name[e.name] = k
        by_key.setdefault(k, []).append(e.name)
        by_last.setdefault(e.name.rsplit(".", 1)[-1], []).append(e.name)
    return by_name, by_key, by_last


def object_key(obj):
    """Identity of an object across the ways Python hands it out (bound methods, descriptors)."""
    if isinstance(obj, (staticmethod, classmethod)):
        obj = obj.__func__
    obj = getattr(obj, "__func__", obj)
    return id(obj)


def import_name(name: str):
    """The object a dotted name denotes (module, then attributes), or None."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except Exception:
            continue
        try:
            for attr in parts[i:]:
                obj = inspect.getattr_static(obj, attr) if inspect.isclass(obj) else getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def resolve(target: str, module: str | None = None, cls: str | None = None) -> str | None:
    """The documented name a Python cross-reference means, or None.

    Tried in order: the name itself; relative to the current class (and what it inherits) and
    module, as Sphinx reads it; the object the name denotes when imported (any documented name for
    the same object, the shortest); a unique documented name ending in ``.target``, preferring the
    referring package.
    """
    by_name, by_key, by_last = _index()
    contexts = [c for c in (cls, module) if c] + [""]
    for ctx in contexts:
        full = f"{ctx}.{target}" if ctx else target
        if full in by_name:
            return full
    for ctx in contexts:
        full = f"{ctx}.{target}" if ctx else target
        obj = import_name(full) if "." in full else None
        if obj is not None:
            same = by_key.get(object_key(obj), [])
            if same:
                return min(same, key=len)
    last = target.rsplit(".", 1)[-1]
    cands = [n for n in by_last.get(last, []) if n == target or n.endswith("." + target)]
    if len(cands) > 1 and module:
        top = module.split(".")[0]
        local = [n for n in cands if n.split(".")[0] == top]
        if len({by_name[n] for n in local}) == 1:
            return min(local, key=len)
    if cands and len({by_name[n] for n in cands}) == 1:
        return min(cands, key=len)
    return None


def unresolved_references(verbatim=None) -> dict[str, list[str]]:
    """{target: [rendered names citing it]} for cross-references no documented name answers
    (docstrings shown verbatim, default: those :func:`invalid_rest` finds, are not read)."""
    verbatim = set(invalid_rest()) if verbatim is None else set(verbatim)
    out: dict[str, list[str]] = {}
    for e in rendered_objects():
        if e.name in verbatim or e.what in ("attribute", "data"):
            continue
        doc = _sphinx_doc(e)
        if not doc:
            continue
        cls = None
        if e.cls is not None:
            cls = e.name.rsplit(".", 1)[0]
        elif e.what in ("class", "exception"):
            cls = e.name
        module = e.name if e.what == "module" else e.module
        for role, target in _references(doc, e.what):
            if not target or docstring_policy.is_external(target, role):
                continue
            if resolve(target, module, cls) is None:
                out.setdefault(target, []).append(e.name)
    return out


def _references(doc: str, what: str):
    """(role, target) of the Python cross-references in a docstring: explicit roles and the
    entries of a numpydoc ``See Also`` section (which numpydoc turns into references)."""
    for m in ROLE.finditer(doc):
        yield "py:" + m.group(1), m.group(2).strip(".")
    if what == "module" or "See Also" not in doc:
        return
    from numpydoc import docscrape

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            parsed = docscrape.NumpyDocString(doc)
        except Exception:
            return
    for funcs, _desc in parsed["See Also"]:
        for name, role in funcs:
            yield f"py:{role or 'obj'}", name.strip(".~")


def measure() -> dict:
    """The whole debt as the lists in ``docstring_debt.json`` hold it."""
    verbatim = invalid_rest()
    return {
        "undocumented": sorted(build_undocumented() | checked_undocumented()),
        "parameters_undocumented": dict(sorted(missing_parameters().items())),
        "units_missing": dict(sorted(missing_units().items())),
        "verbatim": sorted(verbatim),
        "unresolved_references": sorted(unresolved_references(verbatim)),
        "undocumented_bases": undocumented_bases(),
    }


def undocumented_bases() -> list[str]:
    """Our public base classes that rendered classes show (``show-inheritance``) but the
    reference does not document (not in any ``__all__``)."""
    by_name, by_key, _ = _index()
    out = set()
    for e in rendered_objects():
        if e.what not in ("class", "exception"):
            continue
        for base in e.obj.__bases__:
            mod = getattr(base, "__module__", "") or ""
            if mod.split(".")[0] not in API_PACKAGES or base.__name__.startswith("_"):
                continue
            if any(p.startswith("_") for p in mod.split(".")):
                continue
            if not by_key.get(object_key(base)):
                out.add(f"{mod}.{base.__qualname__}")
    return sorted(out)
