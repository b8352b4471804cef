"""Generate the API reference pages from the packages themselves (no hand-kept module lists).

At ``config-inited`` (before Sphinx lists the sources and autosummary writes its stubs) this extension writes
``api/<package>.rst`` for each package in ``ipmc_api_packages``:

* the package docstring and an autosummary table of its ``__all__`` (the curated public API,
  documented once, under the package's name: ``physmodel.ActuatorModel``);
* for every public submodule (no component starting with ``_``; found with
  :func:`pkgutil.walk_packages`, so a restructure that moves modules needs no edit here) a page
  with the module docstring and its public names that the package does not already export:
  the module's ``__all__`` if it has one, else the functions and classes defined in it whose
  names do not start with ``_``.

So every public name is documented exactly once, and a name that moves between modules moves
in the reference by itself.  The generated files live in ``api/_auto/`` (not committed).
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
    module-level constants it documents with ``#:`` comments."""
    names = getattr(module, "__all__", None)
    if names is not None:
        return [n for n in names if hasattr(module, n)]
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


def _exported_ids(package) -> set[int]:
    return {id(getattr(package, n)) for n in getattr(package, "__all__", ()) if hasattr(package, n)}


def package_pages(package_name: str) -> dict[str, str]:
    """{relative file name: reST text} for one package and its public submodules."""
    pkg = importlib.import_module(package_name)
    exported = _exported_ids(pkg)
    pages: dict[str, str] = {}
    subs = public_submodules(pkg)
    top = [_title(f"``{package_name}``"),
           f".. automodule:: {package_name}\n   :no-members:\n"]
    names = list(getattr(pkg, "__all__", ()))
    if names:
        top.append(_title("Public names", "-"))
        top.append(f"Everything below is importable as ``from {package_name} import NAME``.\n")
        top.append(_autosummary(package_name, names))
    if subs:
        top.append(_title("Modules", "-"))
        top.append(".. toctree::\n   :maxdepth: 1\n\n" + "\n".join(f"   {s}" for s in subs) + "\n")
    pages[f"{package_name}.rst"] = "\n".join(top)
    for sub in subs:
        mod = importlib.import_module(sub)
        own = [n for n in module_public_names(mod)
               if id(getattr(mod, n)) not in exported or not _is_routine_or_class(getattr(mod, n))]
        again = [n for n in module_public_names(mod) if n not in own]
        text = [_title(f"``{sub}``"), f".. automodule:: {sub}\n   :no-members:\n"]
        if again:
            refs = ", ".join(f":obj:`{package_name}.{n}`" for n in again if hasattr(pkg, n))
            if refs:
                text.append(f"Also defined here and documented under the package: {refs}.\n")
        text.append(_autosummary(sub, own))
        pages[f"{sub}.rst"] = "\n".join(text)
    return pages


def _is_routine_or_class(obj) -> bool:
    return inspect.isroutine(obj) or inspect.isclass(obj)


def generate(app, config) -> None:
    out = Path(app.srcdir) / "api" / AUTO
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    for package_name in config.ipmc_api_packages:
        for fname, text in package_pages(package_name).items():
            (out / fname).write_text(text, encoding="utf-8")


def setup(app):
    app.add_config_value("ipmc_api_packages", ["physmodel", "surrogate", "inversion", "scenarios"], "env")
    # at config-inited, so that the files exist when Sphinx lists the sources and
    # sphinx.ext.autosummary (builder-inited) writes the stub pages they ask for
    app.connect("config-inited", generate)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
