"""Sphinx configuration of the ipmc documentation.

Build (from the repository root; warnings are errors, so broken references, undocumented public
names and failing gallery examples fail the build)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
# document the packages of this checkout, not whatever else is installed
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import docstring_policy  # noqa: E402  (docs/_ext)

# -- project -------------------------------------------------------------------------------
project = "ipmc"
author = "the ipmc developers"
copyright = "the ipmc developers (BSD-3-Clause)"
from physmodel import __version__ as release  # noqa: E402  (one version, in the package)

version = ".".join(release.split(".")[:2])

# -- extensions ----------------------------------------------------------------------------
extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
    "ipmc_apigen",
    "ipmc_docstrings",
    "ipmc_refs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "examples/README.rst", "**/.ipynb_checkpoints"]
templates_path = ["_templates"]

# Every unresolved cross-reference to our own objects is a warning (so an error under -W);
# names from other libraries (no intersphinx: CI builds offline) are not checked
# (docs/_ext/docstring_policy.py: EXTERNAL_TARGETS).
nitpicky = True
nitpick_ignore_regex = docstring_policy.EXTERNAL_TARGETS

nitpick_ignore = [("py:class", n) for n in docstring_policy.UNDOCUMENTED_BASES]

# -- autodoc / autosummary / numpydoc ------------------------------------------------------
autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True
autoclass_content = "class"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# A public function, class, method or property without a docstring fails the build, except the
# names listed in docs/_ext/docstring_debt.json (python docs/_ext/docstring_policy.py --update).
# The check is ipmc_docstrings' (it names each object and says what to do), not numpydoc's GL08.
numpydoc_validation_checks: set[str] = set()

# -- gallery -------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "ignore_pattern": r"__init__\.py|_stub",
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    "remove_config_comments": True,
    "download_all_examples": False,
    "show_memory": False,
    "matplotlib_animations": False,
    "reference_url": {},
    "min_reported_time": 1,
    "default_thumb_file": None,
}

# -- HTML ----------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"ipmc {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_show_sourcelink = False

# -- MyST (physics.md, discrepancy.md are Markdown with LaTeX math) -------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True
