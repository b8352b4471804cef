"""Declarations shared by every effect module: :class:`EffectParameter` and :class:`Effect`.

An effect parameter carries two sets of bounds:

* its *absolute* bounds ``lower``/``upper``: the values any model accepts (physical limits), used
  to validate ``{effect: {param: value}}`` wherever effects are switched on;
* its *candidate* bounds for the discrepancy search, which may depend on the strip:
  :meth:`Effect.candidate_parameters` applies the effect's ``fit_bounds(params)`` rule (bounds
  from the physics and the data's scale, e.g. a contact resistance up to five times the polymer's
  own through-thickness area resistance) and any user overrides, clipped to the absolute bounds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import numpy as np

from .. import beam
from ..errors import ParameterError

KINDS = ("actuator", "sensor")
LEVELS = ("parameter", "strip", "response", "series", "kernel")


@dataclass(frozen=True)
class EffectParameter:
    """One parameter of an effect: SI ``unit``, ``off`` value, absolute bounds and a typical size.

    ``typical`` is a moderate, clearly visible value (a scale for signatures and a start value);
    ``scale`` is a hint for optimisers (``"linear"``: every "off" value sits at 0 or at a bound).
    ``limits``: the sides (``"lower"``/``"upper"``) whose bound is a physical limit (a CPE exponent
    of 1, a damping share of 0 or 1): a fit ending there needs no wider bound.
    """

    name: str
    unit: str
    off: float
    lower: float
    upper: float
    typical: float
    doc: str = ""
    scale: str = "linear"
    limits: tuple = ()

    def __post_init__(self):
        for k in ("off", "lower", "upper", "typical"):
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ParameterError(f"effect parameter {self.name}: {k}={v!r} must be a finite number")
        if not self.lower < self.upper:
            raise ParameterError(f"effect parameter {self.name}: bounds [{self.lower}, {self.upper}] are empty")
        if not (self.lower <= self.off <= self.upper) or not (self.lower <= self.typical <= self.upper):
            raise ParameterError(f"effect parameter {self.name}: off={self.off} and typical={self.typical} "
                                 f"must lie in [{self.lower}, {self.upper}]")
        if self.typical == self.off:
            raise ParameterError(f"effect parameter {self.name}: typical must differ from off ({self.off})")


@dataclass(frozen=True)
class Effect:
    """A named candidate effect: meaning, reference, parameters and where it applies.

    ``level``: ``parameter`` (changes the State), ``strip`` (a factor on every quantity of the strip
    itself, its impedance included, applied before the chain), ``response`` (a factor on a response),
    ``series`` (an impedance in series with the strip), ``kernel`` (changes the charge dynamics).
    ``apply`` is private machinery of the declaring module (a parameter-level ``apply`` returns the
    state's dict with the arrays it changes replaced, never written into in place).  ``switch``: the parameter whose off
    value switches the effect off whatever the others are (None: all parameters at off).
    ``fit_bounds(params) -> {param: (lower, upper, typical)}``: candidate bounds scaled to the
    strip ``params`` (:class:`~physmodel.params.IPMCParameters`), with their rationale in
    ``bounds_doc``.  ``kinds``/``quantities``: the model kinds and response quantities it
    changes.  ``needs_temperatures``: it only shows in data at two or more temperatures.
    ``batchable``: ``apply`` takes its values as arrays over parameter sets, shaped (n_sets, 1, 1)
    to broadcast against the model's (n_sets, n_T, n_f) arrays, so one model call evaluates sets
    with different values of it (``EffectModel(...).predictor(...).many``); a
    ``kernel`` effect is not, but the sets of a batch where it is on still share one call, each
    with its own ŝ (:func:`physmodel.model.evaluate_grid`'s per-set points); those where it is off
    take another.
    """

    name: str
    title: str
    description: str
    reference: str
    level: str
    parameters: tuple
    kinds: tuple = KINDS
    quantities: tuple = ("M", "H", "Z", "I", "S")
    needs_temperatures: bool = False
    apply: Callable = field(default=None, repr=False, compare=False)
    switch: str | None = None
    fit_bounds: Callable | None = field(default=None, repr=False, compare=False)
    bounds_doc: str = ""
    batchable: bool = True

    def __post_init__(self):
        if self.level not in LEVELS:
            raise ParameterError(f"effect {self.name}: level {self.level!r} not in {LEVELS}")
        if self.level == "kernel" and self.batchable:
            raise ParameterError(f"effect {self.name}: a kernel effect cannot be batchable (one ŝ grid per model call)")
        if self.switch is not None:
            self.parameter(self.switch)

    @property
    def off(self) -> dict:
        return {p.name: p.off for p in self.parameters}

    @property
    def typical(self) -> dict:
        return {p.name: p.typical for p in self.parameters}

    def parameter(self, name: str) -> EffectParameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise ParameterError(f"effect {self.name!r} has no parameter {name!r}; "
                             f"expected one of {[p.name for p in self.parameters]}")

    def is_off(self, values: Mapping[str, float]) -> bool:
        if self.switch is not None:
            return values[self.switch] == self.parameter(self.switch).off
        return all(values[p.name] == p.off for p in self.parameters)

    def on_mask(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """:meth:`is_off` negated, elementwise over arrays of values (one entry per parameter set)."""
        if self.switch is not None:
            return np.asarray(values[self.switch]) != self.parameter(self.switch).off
        on = None               # the parameters' tests or-ed in turn (no stacked array)
        for p in self.parameters:
            x = np.asarray(values[p.name]) != p.off
            on = x if on is None else on | x
        return np.asarray(False) if on is None else on

    def applies_to(self, kind: str, quantity: str) -> bool:
        return kind in self.kinds and quantity in self.quantities

    def candidate_parameters(self, params=None, overrides: Mapping[str, Mapping[str, float]] | None = None) -> tuple:
        """The parameters with candidate bounds: ``fit_bounds(params)`` (when ``params`` is given),
        then ``overrides = {param: {"lower": .., "upper": .., "typical": ..}}``; clipped to the
        absolute bounds; ``off`` must stay inside."""
        scaled = self.fit_bounds(params) if (self.fit_bounds is not None and params is not None) else {}
        out = []
        for p in self.parameters:
            lo, hi, ty = scaled.get(p.name, (p.lower, p.upper, p.typical))
            ov = dict((overrides or {}).get(p.name, {}))
            bad = set(ov) - {"lower", "upper", "typical"}
            if bad:
                raise ParameterError(f"{self.name}.{p.name}: unknown bound key(s) {sorted(bad)}; "
                                     "expected lower, upper, typical")
            lo, hi, ty = (float(ov.get("lower", lo)), float(ov.get("upper", hi)), float(ov.get("typical", ty)))
            for k, v in (("lower", lo), ("upper", hi)):
                if not math.isfinite(v) or not (p.lower <= v <= p.upper):
                    raise ParameterError(f"{self.name}.{p.name}: candidate {k} {v!r} [{p.unit}] must lie in the "
                                         f"absolute bounds [{p.lower:g}, {p.upper:g}]")
            if not lo < hi or not lo <= p.off <= hi:
                raise ParameterError(f"{self.name}.{p.name}: candidate bounds [{lo:g}, {hi:g}] must be increasing "
                                     f"and contain the off value {p.off:g}")
            ty = min(max(ty, lo), hi)
            if ty == p.off:
                ty = p.off + 0.1 * ((hi - p.off) if hi > p.off else (lo - p.off))
            out.append(replace(p, lower=lo, upper=hi, typical=ty))
        return tuple(out)

    def describe(self) -> str:
        pars = ", ".join(f"{p.name} [{p.unit}] off={p.off:g} in [{p.lower:g}, {p.upper:g}]" for p in self.parameters)
        extra = f" Candidate bounds: {self.bounds_doc}" if self.bounds_doc else ""
        return f"{self.name}: {self.title}. {self.description} Parameters: {pars}.{extra} Ref: {self.reference}"


def law_factor(law: type, field_name: str, value, T, T_ref):
    """``law(field_name=value).factor(T, T_ref)`` of a temperature law of :mod:`physmodel.temperature`
    whose parameter ``value`` may be an array over parameter sets (shaped to broadcast against ``T``).

    The laws' constructors check a scalar; an array of effect values has been checked against the
    effect parameter's bounds (finite, in range) where the values were gathered, so the law's own
    ``factor`` is evaluated on them directly (one formula, the law's)."""
    if np.ndim(value) == 0:
        return law(**{field_name: float(value)}).factor(T, T_ref)
    holder = SimpleNamespace(**{field_name: np.asarray(value, dtype=float)})
    return law.factor(holder, T, T_ref)


def rows_of(a, rows):
    """``a`` restricted to the parameter sets ``rows`` (first axis), unless it broadcasts over them."""
    return a if np.ndim(a) == 0 or np.shape(a)[0] == 1 else np.asarray(a)[rows]


def by_mode_count(ctx, modal):
    """A modal response with each parameter set's own number of modes.

    ``modal(rows, n_modes)`` evaluates the response of the parameter sets ``rows`` (an index into
    the first axis; :func:`rows_of` restricts arrays to them) with ``n_modes`` modes.  The count is
    :func:`physmodel.beam.modes_for_band` of each set's own ωn over the band, so a set's response
    does not depend on which other sets share its model call (the count of the whole batch is
    set by its softest strip)."""
    wmax = float(np.max(np.abs(ctx.s)))
    wn = np.asarray(ctx.st.omega_n)
    counts = np.array([beam.modes_for_band(w, wmax) for w in wn])
    if np.all(counts == counts[0]):
        return modal(slice(None), int(counts[0]))
    out = None
    for n in np.unique(counts):
        rows = np.flatnonzero(counts == n)
        r = modal(rows, int(n))
        if out is None:
            out = np.empty((wn.shape[0],) + np.shape(r)[1:], dtype=complex)
        out[rows] = r
    return out


def P(*args, **kw) -> EffectParameter:
    """Short constructor used by the declaring modules."""
    return EffectParameter(*args, **kw)


__all__ = ["EffectParameter", "Effect", "KINDS", "LEVELS", "P", "by_mode_count", "law_factor", "rows_of"]
