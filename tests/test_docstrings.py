"""Every public name of physmodel, surrogate and inversion is documented: a docstring, its
parameters in a numpydoc ``Parameters`` section, and a unit in square brackets for each
numerical parameter (the project's style: ``frequency_hz : array_like  Frequencies. [Hz]``).
Every object the API reference renders (scenarios and submodules included) has a docstring.

What is checked (``docs/_ext/docstring_audit.py``, shared with the docs build and with
``python docs/_ext/docstring_policy.py --update``): each name in the package's ``__all__`` that
is a function or a class, the public methods and properties of those classes (defined in this
project, not inherited from Python), and the functions, classes, methods and properties the
reference renders.  The oracles are numpydoc's own parser (``numpydoc.docscrape``) against
``inspect.signature``, and Sphinx's ``getdoc`` for what the build shows.

Ratchet: the measured debt is listed in ``docs/_ext/docstring_debt.json`` (the docs build reads
the same file).  A name not listed must pass; a listed name that passes makes
``test_docstring_debt_is_current`` fail, so the lists only shrink.  After fixing docstrings, or
after a merge that adds public names, run ``python docs/_ext/docstring_policy.py --update``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpydoc  # noqa: F401  in the test extras: a missing test dependency fails, never skips

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import docstring_audit as audit  # noqa: E402
import docstring_policy  # noqa: E402

UPDATE = "run: python docs/_ext/docstring_policy.py --update"
_own_doc = audit._own_doc
_documented = audit.documented_parameters
_signature_parameters = audit.signature_parameters
_lookup = audit.lookup
NUMERIC, UNIT = audit.NUMERIC, audit.UNIT
OBJECTS = audit.checked_objects()


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


def test_the_rest_check_on_known_cases():
    """docutils, with Sphinx's roles and directives accepted, flags the plain-text idioms that
    break the build and passes valid numpydoc (written for the test, not taken from the packages)."""
    entry_ok = audit.Entry("x.f", _documented_fn, "function", "x")
    entry_fn = audit.Entry("x.g", _partly_documented_fn, "function", "x")
    entry_mod = audit.Entry("x", sys.modules[__name__], "module", "x")
    good = audit._as_rendered(entry_ok, _own_doc(_documented_fn) + "\n\nSee :func:`numpy.sinc` and |x|.")
    # the idioms behind the listed failures: an ASCII table under a heading, a list run on
    bad_module = "Data.\n\nModules\n-------\nunits     one\n          two\nsweep     three\n"
    bad_function = "Summary.\n\nThe free parameters:\n\n* d\n* xi\nthe rest is held.\n"
    from docutils import nodes
    from docutils.core import publish_doctree

    def problems(text):
        with audit._lenient_sphinx_markup():
            tree = publish_doctree(text, settings_overrides={"report_level": 5, "halt_level": 5})
        return [m for m in tree.findall(nodes.system_message) if m["level"] >= 2]

    assert problems(good) == []
    assert problems(audit._as_rendered(entry_mod, bad_module))
    assert problems(audit._as_rendered(entry_fn, bad_function))


def test_the_walk_finds_the_public_api():
    names = {q for q, _, _ in OBJECTS}
    # one name of each kind per package, so that an empty or broken walk cannot pass
    for expected in ("physmodel.ActuatorModel", "physmodel.ActuatorModel.frequency_response",
                     "physmodel.calibrate", "surrogate.ScheduledFit.fit", "surrogate.RationalModel.at",
                     "inversion.invert", "inversion.StreamingInverter.push"):
        assert expected in names
    assert len(names) > 150
    rendered = {e.name for e in audit.rendered_objects()}
    for expected in ("physmodel.FrequencySweep.to_frd", "physmodel.data.timesim.simulate",
                     "physmodel.estimation.frf.h1", "scenarios.cli.main", "inversion.StreamingInverter.push"):
        assert expected in rendered
    assert len(rendered) > len(names)


def test_public_names_have_docstrings():
    missing = audit.build_undocumented() | audit.checked_undocumented()
    new = sorted(missing - docstring_policy.KNOWN_UNDOCUMENTED)
    assert not new, f"public names without a docstring: {new}; write them, or {UPDATE}"


def test_documented_functions_list_their_parameters():
    missing = audit.missing_parameters()
    new = {q: v for q, v in missing.items()
           if not set(v) <= set(docstring_policy.KNOWN_PARAMETERS_UNDOCUMENTED.get(q, ()))}
    assert not new, ("numpydoc 'Parameters' sections lack these signature parameters "
                     f"(name: parameters): {new}; document them, or {UPDATE}")


def test_numerical_parameters_carry_units():
    missing = audit.missing_units()
    new = {q: v for q, v in missing.items() if not set(v) <= set(docstring_policy.KNOWN_UNITS_MISSING.get(q, ()))}
    assert not new, f"numerical parameters documented without a [unit] (name: parameters): {new}; or {UPDATE}"


def test_docstrings_are_valid_rest_and_references_resolve():
    bad = {n: why for n, why in audit.invalid_rest().items() if n not in docstring_policy.VERBATIM}
    assert not bad, f"docstrings that are not valid reST (name: first problem): {bad}; fix them, or {UPDATE}"
    unresolved = {t: who for t, who in audit.unresolved_references(docstring_policy.VERBATIM).items()
                  if t not in docstring_policy.UNRESOLVED_REFERENCES}
    assert not unresolved, f"cross-references to nothing documented (target: cited by): {unresolved}; or {UPDATE}"


def test_docstring_debt_is_current():
    """Every listed name still fails (else the list is stale: run the update)."""
    measured = audit.measure()
    stale = {}
    for key, listed in docstring_policy.load().items():
        now = measured[key]
        if isinstance(listed, dict):
            gone = {n: v for n, v in listed.items() if n not in now or set(v) - set(now[n])}
        else:
            gone = sorted(set(listed) - set(now))
        if gone:
            stale[key] = gone
    assert not stale, f"these listed names now pass (or pass in part): {stale}; {UPDATE}"
