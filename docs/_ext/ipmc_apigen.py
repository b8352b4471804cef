"""Generate the API reference pages from the packages themselves (no hand-kept module lists).

At ``config-inited`` (before Sphinx lists the sources and autosummary writes its stubs) this extension writes
``api/<package>.rst`` for each package in ``ipmc_api_packages``:

* the package docstring and an autosummary table of its ``__all__`` (the curated public API,
  documented once, under the package's name: ``physmodel.ActuatorModel``);
* for every public submodule (no component starting with ``_``; found with
  :func:`pkgutil.walk_packages`, so a restructure that moves modules needs no edit here) a page
  with the module docstring and its public names: the module's ``__all__`` if it has one, else
  the functions and classes defined in it whose names do not start with ``_``.

Every function and class is documented once, at its home (:func:`plan`: the shallowest package
that exports it, else its defining module); the other pages that list it link there.  A name
that moves between modules moves in the reference by itself.  ``docstring_audit`` walks the
same plan, so the docstring debt is measured on exactly what the reference renders.  The generated files live in ``api/_auto/`` (not committed).
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import shutil
from pathlib import Path

AUTO = "_auto"


def _title(text: str, char: str = "=") -> str:
    return f"{text}\n{char * len(text)}\n"


def public_submodules(package) -> list[str]:
    """Dotted names of the importable public submodules of ``package`` (sorted)."""
    out = []
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if any(part.startswith("_") for part in info.name.split(".")):
            continue
        out.append(info.name)
    return sorted(out)


def module_public_names(module) -> list[str]:
    """``__all__`` if the module defines it, else its own public functions and classes and the
    module-level constants it documents with ``#:`` comments.  Submodules are left out: each has
    its own page (:func:`public_submodules`)."""
    names = getattr(module, "__all__", None)
    if names is not None:
        # a submodule listed in a package's ``__all__`` (``inversion.references``) has its own
        # page from public_submodules; stubbing it too would document every member twice
        return [n for n in names if hasattr(module, n) and not inspect.ismodule(getattr(module, n))]
    try:
        from sphinx.pycode import ModuleAnalyzer

        documented = {name for (scope, name) in ModuleAnalyzer.for_module(module.__name__).find_attr_docs()
                      if scope == ""}
    except Exception:
        documented = set()
    own = []
    for name, obj in vars(module).items():
        if name.startswith("_"):
            continue
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and getattr(obj, "__module__", None) == module.__name__:
            own.append(name)
        elif name in documented:
            own.append(name)
    return own


def _autosummary(module_name: str, names: list[str]) -> str:
    if not names:
        return ""
    body = "\n".join(f"   {n}" for n in names)
    return (f".. currentmodule:: {module_name}\n\n.. autosummary::\n   :toctree: generated/\n\n{body}\n")


def _is_routine_or_class(obj) -> bool:
    return inspect.isroutine(obj) or inspect.isclass(obj)


def _depth(name: str) -> int:
    return name.count(".")


def plan(package_name: str) -> list[tuple[str, list[str], dict[str, str]]]:
    """What the reference documents for one package: ``[(module, own names, {name: home})]``.

    The package comes first, then its public submodules.  Every function and class is
    documented once, at its *home*: the shallowest package ``__init__`` that lists it in
    ``__all__`` (``physmodel.FrequencySweep``, ``physmodel.data.read_npz``), else the module that
    defines it; other modules that list it point there.  Constants are documented wherever they
    are listed.
    """
    pkg = importlib.import_module(package_name)
    modules = [package_name] + public_submodules(pkg)
    listed = {m: module_public_names(importlib.import_module(m)) for m in modules}

    def rank(module_name: str, obj) -> tuple:
        mod = importlib.import_module(module_name)
        is_pkg = hasattr(mod, "__path__") and module_name != getattr(obj, "__module__", None)
        defines = getattr(obj, "__module__", None) == module_name
        return (0 if is_pkg else 1 if defines else 2, _depth(module_name), module_name)

    home: dict[int, str] = {}
    for m in sorted(modules, key=lambda m: (_depth(m), m)):
        mod = importlib.import_module(m)
        for n in listed[m]:
            obj = getattr(mod, n)
            if not _is_routine_or_class(obj):
                continue
            key = id(obj)
            if key not in home or rank(m, obj) < rank(home[key].rsplit(".", 1)[0], obj):
                home[key] = f"{m}.{n}"
    out = []
    for m in modules:
        mod = importlib.import_module(m)
        own, again = [], {}
        for n in listed[m]:
            obj = getattr(mod, n)
            where = home.get(id(obj)) if _is_routine_or_class(obj) else None
            if where is None or where == f"{m}.{n}":
                own.append(n)
            else:
                again[n] = where
        out.append((m, own, again))
    return out


def package_pages(package_name: str) -> dict[str, str]:
    """{relative file name: reST text} for one package and its public submodules."""
    pages: dict[str, str] = {}
    entries = plan(package_name)
    subs = [m for m, _, _ in entries[1:]]
    for m, own, again in entries:
        text = [_title(f"``{m}``"), f".. automodule:: {m}\n   :no-members:\n"]
        if m == package_name:
            if own or again:
                text.append(_title("Public names", "-"))
                text.append(f"Everything below is importable as ``from {package_name} import NAME``.\n")
        if again:
            refs = ", ".join(f":obj:`{n} <{where}>`" for n, where in again.items())
            text.append(f"Also importable from here, documented where listed: {refs}.\n")
        text.append(_autosummary(m, own))
        if m == package_name and subs:
            text.append(_title("Modules", "-"))
            text.append(".. toctree::\n   :maxdepth: 1\n\n" + "\n".join(f"   {s}" for s in subs) + "\n")
        pages[f"{m}.rst"] = "\n".join(text)
    return pages


def generate(app, config) -> None:
    out = Path(app.srcdir) / "api" / AUTO
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    for package_name in config.ipmc_api_packages:
        for fname, text in package_pages(package_name).items():
            (out / fname).write_text(text, encoding="utf-8")


def refresh_found_docs(app) -> None:
    """Let autosummary see the pages :func:`generate` just wrote, on incremental builds too.

    ``sphinx.ext.autosummary`` writes its stubs at ``builder-inited`` for the documents in
    ``env.found_docs``.  A fresh environment lists the source files before that event, but a
    pickled one (``docs/_build`` from an earlier run) still holds the old list until
    ``Builder.read`` scans again, so a module added since the last build got its page here and
    no stubs: every name on it was "stub file not found" / "reference target not found".
    Scanning now (``Builder.read`` scans once more anyway) gives autosummary the current list.
    """
    app.env.find_files(app.config, app.builder)


def setup(app):
    app.add_config_value("ipmc_api_packages", ["physmodel", "surrogate", "inversion", "scenarios"], "env")
    # at config-inited, so that the files exist when Sphinx lists the sources and
    # sphinx.ext.autosummary (builder-inited) writes the stub pages they ask for
    app.connect("config-inited", generate)
    # before autosummary's own builder-inited handler (priority 500) writes the stubs
    app.connect("builder-inited", refresh_found_docs, priority=100)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
