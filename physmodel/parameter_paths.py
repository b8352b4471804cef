"""Addressing parameters of an :class:`~physmodel.params.IPMCParameters` set by name.

A name is a numeric field (``"d"``, ``"kappa_e"``, ``"r1_sheet"`` ...), ``"omega_n"`` [rad/s] (the
first bending mode, set through the density), or a temperature-law parameter
``"laws.<quantity>.<attribute>"`` (e.g. ``"laws.d.activation_energy"`` [J/mol],
``"laws.E.slope"`` [1/K]; see :mod:`physmodel.temperature`).  Calibration, the effect models and
the command line address parameters through these functions only.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import fields, replace
from typing import Any

from .errors import ParameterError
from .params import IPMCParameters

Values = Mapping[str, float]



# =============================================================================== physics wrapper
_NUMERIC_FIELDS = tuple(f.name for f in fields(IPMCParameters) if f.name not in ("laws", "name", "source"))


def _law_target(base: IPMCParameters, name: str):
    """(quantity, attribute, law) for a ``laws.<quantity>.<attribute>`` name, or a clear error."""
    parts = name.split(".")
    laws = base.laws
    qnames = [f.name for f in fields(laws)]
    if len(parts) != 3 or parts[1] not in qnames:
        raise ParameterError(f"unknown temperature-law parameter {name!r}; expected 'laws.<quantity>.<attribute>' "
                             f"with quantity in {qnames}")
    law = getattr(laws, parts[1])
    attrs = [f.name for f in fields(law) if f.name != "valid_c"]
    if parts[2] not in attrs:
        raise ParameterError(f"{name!r}: the law for {parts[1]} is {type(law).__name__}, whose parameters are "
                             f"{attrs or 'none'}")
    return parts[1], parts[2], law


def check_parameter_name(base: IPMCParameters, name: str) -> None:
    """Raise :class:`ParameterError` unless ``name`` is calibratable on ``base``."""
    if name.startswith("laws."):
        _law_target(base, name)
    elif name != "omega_n" and name not in _NUMERIC_FIELDS:
        raise ParameterError(f"unknown parameter {name!r}; expected one of {list(_NUMERIC_FIELDS) + ['omega_n']} "
                             "or 'laws.<quantity>.<attribute>'")


def base_value(base: IPMCParameters, name: str) -> float:
    """The value of a calibratable parameter in ``base`` (physical units)."""
    check_parameter_name(base, name)
    if name.startswith("laws."):
        q, attr, law = _law_target(base, name)
        return float(getattr(law, attr))
    if name == "omega_n":
        return float(base.omega_n)
    return float(getattr(base, name))


def apply_values(base: IPMCParameters, values: Values) -> IPMCParameters:
    """``base`` with parameters (fields, ``omega_n``, ``laws.<q>.<attr>``) replaced by ``values``."""
    plain: dict[str, Any] = {}
    law_changes: dict[str, dict[str, float]] = {}
    wn: float | None = None
    for name, v in values.items():
        if name.startswith("laws."):
            q, attr, _ = _law_target(base, name)
            law_changes.setdefault(q, {})[attr] = float(v)
        elif name == "omega_n":
            wn = float(v)
        else:
            check_parameter_name(base, name)
            plain[name] = float(v)
    if law_changes:
        laws = base.laws.with_(**{q: replace(getattr(base.laws, q), **ch) for q, ch in law_changes.items()})
        plain["laws"] = laws
    p = replace(base, **plain) if plain else base
    return p.replace(omega_n=wn) if wn is not None else p
