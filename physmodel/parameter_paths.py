"""Addressing parameters of an :class:`~physmodel.params.IPMCParameters` set by name.

A name is a numeric field (``"d"``, ``"kappa_e"``, ``"r1_sheet"`` ...), ``"omega_n"`` [rad/s] (the
first bending mode, set through the density), or a temperature-law parameter
``"laws.<quantity>.<attribute>"`` (e.g. ``"laws.d.activation_energy"`` [J/mol],
``"laws.E.slope"`` [1/K]; see :mod:`physmodel.temperature`).  Calibration, the effect models and
the command line address parameters through these functions only.

:func:`resolve_path` is the one place that reads a name: it checks it and returns a
:class:`ParameterPath` (what it addresses, its value in the set, its natural coordinate).  A caller
resolves each name once and hands the paths on (:func:`apply_values`, :class:`StateMap`,
:func:`~physmodel.estimation.calibration.default_free_parameter`);
:func:`check_parameter_name` and :func:`base_value` are the one-name shorthands.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from functools import lru_cache
from typing import Any

import numpy as np

from .errors import ParameterError
from .params import STATE_FIELDS, IPMCParameters, State

Values = Mapping[str, float]


# =============================================================================== one path, resolved once
_NUMERIC_FIELDS = tuple(f.name for f in fields(IPMCParameters) if f.name not in ("laws", "name", "source"))
#: What a parameter name can address: a numeric field, the first mode, a temperature-law parameter.
TARGETS = ("field", "omega_n", "law")


@dataclass(frozen=True)
class ParameterPath:
    """One parameter name resolved against one parameter set: what it addresses and its value there.

    Made by :func:`resolve_path` (the one place that reads a name); everything a caller needs of the
    name comes from here, so a calibration reads each name once and carries the path along.

    Parameters
    ----------
    name : str
        The name as given (``"d"``, ``"omega_n"``, ``"laws.d.activation_energy"``).
    target : str
        One of :data:`TARGETS`: ``"field"`` (a numeric field of
        :class:`~physmodel.params.IPMCParameters`), ``"omega_n"`` (the first bending mode, set
        through the density) or ``"law"`` (a temperature-law parameter).
    value : float
        The parameter's value in the set the path was resolved against. [the parameter's SI unit]
    quantity, attribute : str or None
        For a law: the quantity whose law it is (``"d"``) and the law's attribute
        (``"activation_energy"``); None otherwise.
    """

    name: str
    target: str
    value: float
    quantity: str | None = None
    attribute: str | None = None

    @property
    def is_law(self) -> bool:
        """Whether the path addresses a temperature-law parameter."""
        return self.target == "law"

    def natural(self, x):
        """Coordinate in which the state's logarithm is affine: the value itself for a
        temperature-law parameter, ln|x| for a field or ``omega_n``.

        Parameters
        ----------
        x : array_like
            Values of the parameter. [the parameter's SI unit]
        """
        x = np.asarray(x, dtype=float)
        return x if self.is_law else np.log(np.abs(x))


def resolve_path(base: IPMCParameters, name: str) -> ParameterPath:
    """The :class:`ParameterPath` of ``name`` in ``base``; :class:`ParameterError` (naming what
    is allowed) unless ``name`` is calibratable on ``base``."""
    if name.startswith("laws."):
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
        return ParameterPath(name, "law", float(getattr(law, parts[2])), parts[1], parts[2])
    if name == "omega_n":
        return ParameterPath(name, "omega_n", float(base.omega_n))
    if name not in _NUMERIC_FIELDS:
        raise ParameterError(f"unknown parameter {name!r}; expected one of {list(_NUMERIC_FIELDS) + ['omega_n']} "
                             "or 'laws.<quantity>.<attribute>'")
    return ParameterPath(name, "field", float(getattr(base, name)))


def resolve_paths(base: IPMCParameters, names) -> dict[str, ParameterPath]:
    """``{name: ParameterPath}`` for each of ``names`` in ``base`` (see :func:`resolve_path`)."""
    return {n: resolve_path(base, n) for n in names}


def is_effect_parameter(name: str) -> bool:
    """Whether ``name`` addresses an effect's parameter (``"time_delay.delay"``) rather than one of
    the parameter set (a field, ``omega_n`` or ``laws.<quantity>.<attribute>``)."""
    return "." in name and not name.startswith("laws.")


def check_parameter_name(base: IPMCParameters, name: str) -> None:
    """Raise :class:`ParameterError` unless ``name`` is calibratable on ``base``."""
    resolve_path(base, name)


def base_value(base: IPMCParameters, name: str) -> float:
    """The value of a calibratable parameter in ``base`` (physical units)."""
    return resolve_path(base, name).value


def apply_values(base: IPMCParameters, values: Values, paths: dict[str, ParameterPath] | None = None) -> IPMCParameters:
    """``base`` with parameters (fields, ``omega_n``, ``laws.<q>.<attr>``) replaced by ``values``.

    ``paths``: names already resolved against ``base`` (:func:`resolve_paths`); a name it lacks is
    resolved and added to it, so a caller that applies many values to one set reads each name once.
    """
    paths = {} if paths is None else paths
    plain: dict[str, Any] = {}
    law_changes: dict[str, dict[str, float]] = {}
    wn: float | None = None
    for name, v in values.items():
        path = paths.get(name)
        if path is None:
            path = paths[name] = resolve_path(base, name)
        if path.is_law:
            if float(v) != path.value:      # unchanged laws stay one object (one group in state_at)
                law_changes.setdefault(str(path.quantity), {})[str(path.attribute)] = float(v)
        elif path.target == "omega_n":
            wn = float(v)
        else:
            plain[name] = float(v)
    if law_changes:
        laws = base.laws.with_(**{q: replace(getattr(base.laws, q), **ch) for q, ch in law_changes.items()})
        plain["laws"] = laws
    p = replace(base, **plain) if plain else base
    return p.replace(omega_n=wn) if wn is not None else p


# =============================================================================== many sets as arrays
#: Largest disagreement in ln|state| between :class:`StateMap` and :func:`~physmodel.params.state_at`
#: at its check points for the map to be used (exact up to rounding when the state is log-affine).
STATE_MAP_TOL = 1e-10


class StateMap:
    """States of ``base`` with the parameters ``names`` set to the rows of an array, built as
    arrays (no parameter set per row).

    The fields, ``omega_n`` and the Arrhenius/log-linear temperature-law parameters act on the
    state (:class:`~physmodel.params.State`) multiplicatively: ln|state| is affine in u = ln|x|
    (fields, ``omega_n``) or u = x (temperature-law parameters), with coefficients that depend on
    the temperature.  :meth:`build` measures these coefficients with
    :func:`~physmodel.params.state_at` (the reference path) at a reference row and one move per
    parameter across its box, then checks the map at two rows inside the box where every
    parameter moves at once; where the state is not log-affine in a parameter (a linear law's
    ``alpha``, a box containing zero, ...) it returns None and callers build parameter sets.
    """

    def __init__(self, names, temperature_c, ref_state, u_ref, varying, log_ref, slope, sign):
        self.names = tuple(names)
        self.temperature_c = np.asarray(temperature_c, dtype=float)
        self._ref = ref_state          # State of the reference row, arrays (1, n_T, 1)
        self._u_ref = u_ref            # (n_names,)
        self._varying = varying        # state fields that move with the parameters
        self._log_ref = log_ref        # (n_var, n_T) ln|state| at the reference row
        self._slope = slope            # (n_var, n_T, n_names) ∂ln|state|/∂u
        self._sign = sign              # (n_var, n_T) sign of each moving field
        self._logged = np.flatnonzero([not m.startswith("laws.") for m in self.names])
        self._fixed_names = [f for f in STATE_FIELDS if f not in varying]
        self._fixed = np.array([getattr(ref_state, f)[:, :, 0] for f in self._fixed_names]).reshape(
            len(self._fixed_names), 1, -1)                                                    # (n_fixed, 1, n_T)
        # each State field's position in [moving fields..., fixed fields...]
        self._order = [varying.index(f) if f in varying else len(varying) + self._fixed_names.index(f)
                       for f in STATE_FIELDS]
        self._fixed_columns = {}          # n_rows -> the fixed fields as flat columns (see columns)

    @classmethod
    def build(cls, base: IPMCParameters, names, lower, upper, reference, temperature_c) -> StateMap | None:
        """The map for ``names`` over the box [``lower``, ``upper``] (physical units, per name),
        measured at the row ``reference``; None when the state is not log-affine there.  Maps are
        kept (the last 32): repeated calibrations of one problem (Monte Carlo draws) reuse theirs.

        Parameters
        ----------
        base : IPMCParameters
            The set whose other parameters are kept.
        names : sequence of str or ParameterPath
            Parameter names (see :func:`apply_values`), or their paths already resolved against ``base``.
        lower, upper, reference : array_like
            Box and reference row, one value per name. [each parameter's SI unit]
        temperature_c : array_like
            Temperatures of the states. [°C]
        """
        lo, hi, ref, temps = (tuple(np.asarray(a, dtype=float).reshape(-1).tolist())
                              for a in (lower, upper, reference, temperature_c))
        paths = tuple(m if isinstance(m, ParameterPath) else resolve_path(base, m) for m in names)
        try:
            return _cached_map(base, paths, lo, hi, ref, temps)
        except TypeError:           # unhashable (a law holding a list, ...): not kept
            return cls._build(base, paths, lo, hi, ref, temps)

    @classmethod
    def _build(cls, base, paths: tuple[ParameterPath, ...], lower, upper, reference, temperature_c) -> StateMap | None:
        from .params import state_at

        names = [pp.name for pp in paths]
        by_name = {pp.name: pp for pp in paths}
        lo, hi, ref = (np.asarray(a, dtype=float).reshape(-1) for a in (lower, upper, reference))
        n = len(names)
        if not names or not (lo.size == hi.size == ref.size == n):
            raise ParameterError("StateMap needs one lower, upper and reference value per name")
        for k, pp in enumerate(paths):
            if not pp.is_law and not (lo[k] > 0 or hi[k] < 0):
                return None      # ln|x| crosses zero inside the box

        def natural(row):
            return np.array([pp.natural(v) for pp, v in zip(paths, row)])

        u_lo, u_hi, u_ref = natural(lo), natural(hi), natural(ref)
        # reference row, one far move per parameter, two check rows moving every parameter
        far = np.where(np.abs(u_hi - u_ref) >= np.abs(u_lo - u_ref), hi, lo)
        rows = [ref]
        for k in range(n):
            r = ref.copy()
            r[k] = far[k]
            rows.append(r)
        frac = (np.arange(1, n + 1) * 0.6180339887498949) % 1.0
        for c in (0.15 + 0.7 * frac, 0.85 - 0.7 * frac):
            u = u_lo + c * (u_hi - u_lo)
            rows.append(np.array([v if pp.is_law else np.sign(lo[k]) * np.exp(v)
                                  for k, (pp, v) in enumerate(zip(paths, u))]))
        try:
            st = state_at([apply_values(base, dict(zip(names, r)), by_name) for r in rows], temperature_c)
        except (ParameterError, ValueError):
            return None
        arrays = {f: getattr(st, f)[:, :, 0] for f in STATE_FIELDS}
        varying = [f for f in STATE_FIELDS if not np.array_equal(arrays[f], np.broadcast_to(arrays[f][:1], arrays[f].shape))]
        if not varying:
            return None
        S = np.stack([arrays[f] for f in varying])                       # (n_var, rows, n_T)
        if not np.all(np.isfinite(S)) or np.any(S == 0) or np.any(np.sign(S) != np.sign(S[:, :1])):
            return None
        L = np.log(np.abs(S))
        du = natural(far) - u_ref     # never 0: far is the other end
        slope = np.stack([(L[:, 1 + k] - L[:, 0]) / du[k] for k in range(n)], axis=-1)
        ref_state = State(**{f: getattr(st, f)[:1] for f in STATE_FIELDS})
        out = cls(names, temperature_c, ref_state, u_ref, varying, L[:, 0], slope, np.sign(S[:, 0]))
        U_check = np.array([natural(r) for r in rows[n + 1:]])
        if np.max(np.abs(out._log_state(U_check) - np.moveaxis(L[:, n + 1:], 1, 0))) > STATE_MAP_TOL:
            return None
        return out

    def log_slopes(self) -> tuple[list, np.ndarray]:
        """(moving state fields, ∂ln|field(T)|/∂u (n_fields, n_T, n_names)), u the natural
        coordinate of each name (ln|x| for fields and ``omega_n``, x for law parameters)."""
        return list(self._varying), self._slope.copy()

    def _log_state(self, U):
        """ln|state| of the moving fields, (n_rows, n_var, n_T), at natural coordinates ``U``."""
        # (n_var, n_T, n_rows) seen as (n_rows, n_var, n_T): np.moveaxis(·, -1, 0), without its Python layer
        return self._log_ref[None] + (self._slope @ (U - self._u_ref[None, :]).T).transpose(2, 0, 1)

    def _moving(self, X):
        """The moving fields (n_var, n_rows, n_T) at the rows of ``X`` (n_rows, n_names)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.shape[1] != len(self.names):
            raise ParameterError(f"StateMap: {X.shape[1]} columns for {len(self.names)} parameters {self.names}")
        U = X.copy()
        U[:, self._logged] = np.log(np.abs(X[:, self._logged]))      # ParameterPath.natural, all columns at once
        E = np.exp(self._log_state(U).transpose(1, 0, 2))
        # written C-ordered (n_var, n_rows, n_T): each field's rows are then one contiguous block
        return np.multiply(self._sign[:, None, :], E, out=np.empty(E.shape))

    def columns(self, X) -> tuple[dict, int, tuple]:
        """The state of the rows of ``X`` (n_rows, n_names) [each parameter's SI unit] as flat
        columns {field: (n_rows·n_T, 1)}, set-major, with n_rows and the fields that move with
        the parameters (the others are the same in every row): what
        :meth:`~physmodel.actuator.ActuatorModel.evaluate_columns` takes.  The fixed fields'
        columns are kept per row count, read-only; the values are those of :meth:`__call__`."""
        moving = self._moving(X)
        n_rows = moving.shape[1]
        n = n_rows * moving.shape[2]
        cols = self._fixed_columns.get(n_rows)
        if cols is None:
            if len(self._fixed_columns) >= 16:
                self._fixed_columns.pop(next(iter(self._fixed_columns)))
            fixed = np.repeat(self._fixed, n_rows, axis=1)
            fixed.flags.writeable = False
            cols = self._fixed_columns[n_rows] = {f: fixed[i].reshape(n)[:, None] for i, f in enumerate(self._fixed_names)}
        p = dict(cols)
        for i, f in enumerate(self._varying):
            p[f] = moving[i].reshape(n)[:, None]
        return p, n_rows, tuple(self._varying)

    def __call__(self, X):
        """The :class:`~physmodel.params.State` (n_rows, n_T, 1) of the rows of ``X`` (n_rows, n_names)
        [each parameter's SI unit]."""
        moving = self._moving(X)                                              # (n_var, n_rows, n_T)
        fixed = np.repeat(self._fixed, moving.shape[1], axis=1)               # (n_fixed, n_rows, n_T)
        parts = [*moving[:, :, :, None], *fixed[:, :, :, None]]
        return State(**dict(zip(STATE_FIELDS, [parts[i] for i in self._order])))


@lru_cache(maxsize=32)
def _cached_map(base, paths, lower, upper, reference, temperature_c):
    return StateMap._build(base, paths, lower, upper, reference, temperature_c)
