"""The library of named effects that extend the Chen-Tan models (discrepancy.md §3), and the
model that composes them with a base parameter set.

The effects are declared in :mod:`physmodel.effects.physical` (polymer, electrodes, beam,
temperature laws), :mod:`physmodel.effects.chain` (amplifier, delay, series resistance, series
interface CPE, excitation coupling), :mod:`physmodel.effects.sensing` (seed 000's sensing chain) and
:mod:`physmodel.effects.forms` (higher modes with their own damping, a distributed interface CPE, a
compliant clamp mount); :mod:`physmodel.effects.base` holds the records.  :data:`CONFUSABLE` declares
the pairs that are the same physics in two forms (:func:`declared_confusable`).  Each
:class:`Effect` has one or two parameters and an "off" value at which the model is exactly the
base model, and acts at one of four levels:

``parameter``  it changes the parameter values at each temperature (the :class:`State`);
``strip``      it changes the strip's own responses and impedance (a distributed interface CPE);
``response``   it multiplies a response by a factor (amplifier pole, delay, higher modes, coupling);
``series``     it adds an impedance in series with the strip (series resistance, interface CPE);
``kernel``     it changes the charge dynamics itself (fractional transport).

:class:`EffectModel` composes any set of effects with a base parameter set; it is an
``ActuatorModel`` / ``SensorModel`` (so :func:`physmodel.data.sweep.synthesize_sweep` simulates data
with any effect switched on) and gives the ``predict(values)`` closure used by the calibration
engine (:meth:`EffectModel.predictor`).  Effect parameters are addressed as ``"effect.param"``.
Out-of-library effects for blind tests live in :data:`OUT_OF_LIBRARY` and are never candidates.
``constant_phase_element`` is accepted as an old name of ``fractional_transport``, and
``added_fluid_mass`` of ``viscous_fluid`` (its parameters changed: the constant added mass is its
inviscid limit) (:data:`ALIASES`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from .. import electrode
from ..actuator import ActuatorModel
from ..beam import first_mode
from ..errors import IPMCError, ParameterError
from ..model import DEFAULT_CHUNK, FrequencyResponse, check_frequencies, evaluate_grid
from ..params import (
    STATE_FIELDS,
    IPMCParameters,
    ParameterTable,
    State,
    check_field_values,
    density_for_mode,
    field_range_ok,
    first_mode_omega,
)
from ..sensor import SensorModel
from ..transport import debye_rate
from . import chain, forms, physical, sensing
from .base import KINDS, Effect, EffectParameter
from .physical import CPE_REFERENCE_HZ, SECOND_MODE_RATIO

DEFAULT_QUANTITY = {"actuator": "M", "sensor": "S"}

#: The candidate library, by name.
LIBRARY: dict[str, Effect] = {e.name: e for e in physical.EFFECTS + chain.EFFECTS + sensing.EFFECTS + forms.EFFECTS}
#: Pairs of library effects declared confusable with the effects ({frozenset((a, b)): reason}):
#: the same physics in two forms, which a band may not separate.
CONFUSABLE: dict[frozenset, str] = dict(forms.CONFUSABLE)
#: Effects kept OUT of the candidate list: used by blind generators only.
OUT_OF_LIBRARY: dict[str, Effect] = {e.name: e for e in chain.OUT_OF_LIBRARY}
ALL_EFFECTS = {**LIBRARY, **OUT_OF_LIBRARY}
#: Old names still accepted on input.
ALIASES = {"constant_phase_element": "fractional_transport", "added_fluid_mass": "viscous_fluid"}


class _Context:
    """What response and series effects see: s (1, 1, n_f), ŝ of the charge dynamics, the State,
    the base responses (n_sets, n_T, n_f), the reference temperatures T_ref (n_sets, 1, 1) [K] and,
    on demand, the electrode line argument x at ŝ."""

    def __init__(self, s, s_kernel, st: State, base: dict, T_ref=None):
        self.s, self.s_kernel, self.st, self.base, self.T_ref = s, s_kernel, st, base, T_ref
        self._x = None

    @property
    def x(self):
        if self._x is None:
            p = {k: getattr(self.st, k) for k in STATE_FIELDS}
            A = electrode.strip_terms(p, self.s_kernel, want_xcoth=False).A
            self._x = electrode.line_argument(A, p["r1"], p["L"])
        return self._x


@functools.lru_cache(maxsize=256)
def _needed(quantities: tuple, qs: tuple, series: bool) -> tuple:
    """The quantities of ``quantities`` (a model's, in its order) to evaluate for ``qs``: Z too
    when a series effect is on."""
    need = set(qs) | ({"Z"} if series else set())
    return tuple(q for q in quantities if q in need)


def _where_on(on, value, off_value):
    """``value`` in the parameter sets where an effect is on, ``off_value`` elsewhere (``on`` None: all)."""
    return value if on is None else np.where(on, value, off_value)


def candidate_free_parameters(effect: str, params: IPMCParameters | None = None,
                              overrides: Mapping[str, Mapping[str, float]] | None = None) -> tuple:
    """The parameters of library ``effect`` with candidate bounds for the strip ``params`` (see
    :meth:`Effect.candidate_parameters`); ``overrides = {param: {"lower"|"upper"|"typical": value}}``."""
    return get_effect(effect).candidate_parameters(params, overrides)


def declared_confusable(a: str, b: str) -> str | None:
    """The reason library effects ``a`` and ``b`` are declared confusable (:data:`CONFUSABLE`), or None."""
    return CONFUSABLE.get(frozenset((ALIASES.get(a, a), ALIASES.get(b, b))))


def get_effect(name: str) -> Effect:
    """The effect called ``name`` (library or out-of-library)."""
    name = ALIASES.get(name, name)
    if name not in ALL_EFFECTS:
        raise ParameterError(f"unknown effect {name!r}; expected one of {sorted(LIBRARY)} "
                             f"(or out-of-library {sorted(OUT_OF_LIBRARY)})")
    return ALL_EFFECTS[name]


def candidates_for(kind: str, quantity: str, n_temperatures: int = 2) -> list[str]:
    """Library effects that can change ``quantity`` of a ``kind`` model with this many temperatures."""
    return [e.name for e in LIBRARY.values()
            if e.applies_to(kind, quantity) and (n_temperatures > 1 or not e.needs_temperatures)]


def normalize_effects(effects: Mapping[str, Mapping[str, float]] | None) -> dict[str, dict[str, float]]:
    """Validate ``{effect: {param: value}}``; missing parameters take their off values."""
    out: dict[str, dict[str, float]] = {}
    for name, vals in (effects or {}).items():
        eff = get_effect(name)
        name = eff.name
        vals = dict(vals or {})
        full = eff.off
        for k, v in vals.items():
            p = eff.parameter(k)
            v = float(v)
            if not math.isfinite(v) or not (p.lower <= v <= p.upper):
                raise ParameterError(f"{name}.{k}={v!r} [{p.unit}] must lie in [{p.lower:g}, {p.upper:g}]")
            full[k] = v
        out[name] = full
    return out


def split_values(values: Mapping[str, float]) -> tuple[dict, dict]:
    """Split ``{"alpha0": .., "time_delay.delay": ..}`` into base-parameter and effect dicts.

    Base names are IPMCParameters fields, ``omega_n`` or ``laws.<quantity>.<attribute>``
    (see :func:`physmodel.parameter_paths.apply_values`)."""
    base, eff = {}, {}
    for k, v in values.items():
        ep = _effect_parameter(k)
        if ep is None:
            base[k] = float(v)
        else:
            eff.setdefault(ep[0], {})[ep[1]] = float(v)
    return base, eff


@functools.lru_cache(maxsize=4096)
def _effect_parameter(name: str) -> tuple | None:
    """``(effect, param)`` of an effect parameter's name, None for a base name (read once per name)."""
    from ..parameter_paths import is_effect_parameter

    return tuple(name.split(".", 1)) if is_effect_parameter(name) else None


# --------------------------------------------------------------------------- the model
def _apply(p: IPMCParameters, base_vals: Mapping[str, float], paths: dict | None = None) -> IPMCParameters:
    """``p`` with ``base_vals``; ``paths``: names resolved against ``p`` (kept across calls)."""
    if not base_vals:
        return p
    from ..parameter_paths import apply_values

    return apply_values(p, base_vals, paths)


def _table_of(base: IPMCParameters, base_vals: Sequence[Mapping[str, float]], paths: dict,
              table: ParameterTable | None = None) -> ParameterTable | None:
    """The :class:`ParameterTable` of ``base`` with ``base_vals[i]`` in set i, built as arrays (no
    record per set; values checked as :class:`IPMCParameters` checks them, ``omega_n`` set through
    the density as :meth:`IPMCParameters.replace` does).  None when a name addresses a temperature
    law or ``T_ref`` (the table's sets would not share one laws group): the caller then builds one
    record per set.  ``paths``: names resolved against ``base`` (kept across calls); ``table``: the
    table of ``base`` if the caller keeps it."""
    from ..parameter_paths import resolve_path

    names: dict = {}
    for bv in base_vals:
        names.update(dict.fromkeys(bv))
    table = ParameterTable.of(base) if table is None else table
    for name in names:
        path = paths.get(name)
        if path is None:
            path = paths[name] = resolve_path(base, name)
        if path.is_law or (path.target == "field" and (name == "T_ref" or name not in table.columns)):
            return None
    n = len(base_vals)
    cols = dict(table.columns)          # the base's (1, 1) columns, repeated over the sets at the end
    for name in (*(k for k in names if k != "omega_n"), *(("rho",) if "omega_n" in names else ())):
        src = "omega_n" if name == "rho" else name
        given = [src in bv for bv in base_vals]
        if name == "rho":
            wn = np.array([bv.get("omega_n", 1.0) for bv in base_vals], dtype=float)
            a = density_for_mode(wn, cols["E"][:, 0], cols["L"][:, 0], cols["h"][:, 0])
        else:
            a = np.array([bv.get(name, 1.0) for bv in base_vals], dtype=float)
        if all(given):
            cols[name] = check_field_values(name, a)[:, None]
        else:
            g = np.array(given)
            cols[name] = np.where(g, check_field_values(name, np.where(g, a, 1.0)), cols[name][:, 0])[:, None]
    cols = {k: v if len(v) == n else np.repeat(v, n, axis=0) for k, v in cols.items()}
    return table.with_columns(cols, n)


def _group_value(e: Effect, given: Mapping[str, float], own_effects: Mapping) -> tuple:
    """How the sets of a batch are grouped by a non-batchable effect ``e`` (one model call per
    group): by its values, except a kernel effect, by whether it is on — the sets where it is on go
    in one call with their own ŝ each (:meth:`_EffectMixin._batch_effects`), e.g. a Jacobian's
    finite-difference set of the CPE order with the point's."""
    if e.level == "kernel":
        return ("on",) if not e.is_off({**own_effects.get(e.name, e.off), **given}) else ("off",)
    return tuple(sorted(given.items()))


def _batched_entry(e: Effect, vals: dict):
    """The ``_active`` entry ``(effect, {param: (n_sets, 1, 1)}, on mask or None)`` of a batchable
    effect with values ``vals = {param: (n_sets,) array}`` (checked against its bounds), None where it
    is off in every set; sets where it is off take its off values."""
    for p in e.parameters:
        a = vals[p.name]
        lo, hi = float(a.min()), float(a.max())     # NaN propagates into both: the usual case in two reductions
        if not (p.lower <= lo and hi <= p.upper and math.isfinite(lo) and math.isfinite(hi)):
            ok = np.isfinite(a) & (a >= p.lower) & (a <= p.upper)
            v = float(a[~ok][0])
            raise ParameterError(f"{e.name}.{p.name}={v!r} [{p.unit}] must lie in [{p.lower:g}, {p.upper:g}]")
    on = e.on_mask(vals)
    n_on = np.count_nonzero(on)
    if not n_on:
        return None
    if n_on == on.size:
        mask = None
    else:            # off sets take the off values: the effect sees no switched-off mixture
        mask = on[:, None, None]
        vals = {p.name: np.where(on, vals[p.name], p.off) for p in e.parameters}
    return e, {k: a[:, None, None] for k, a in vals.items()}, mask


class _EffectMixin:
    """Shared by the actuator and sensor flavours of :class:`EffectModel`."""

    kind: str

    def _init_effects(self, effects):
        self.effects = normalize_effects(effects)
        for name in self.effects:
            e = get_effect(name)
            if self.kind not in e.kinds:
                raise IPMCError(f"effect {name!r} does not apply to a {self.kind} model "
                                f"(it applies to {e.kinds})")
        # (effect, values, on): ``on`` None = on in every parameter set; else a boolean (n_sets, 1, 1)
        # array, the values arrays over the sets (see _batch_effects)
        self._active: list = [(get_effect(n), v, None) for n, v in self.effects.items()
                              if not get_effect(n).is_off(v)]
        self._batch_table: ParameterTable | None = None
        self._split: tuple | None = None            # _active by level (_levels)
        self._t_ref_of: tuple | None = None         # (params, T_ref) (_t_ref)

    def _use_table(self, table: ParameterTable) -> None:
        """Evaluate the parameter sets of ``table`` (built as arrays by :func:`_table_of`, one row
        per set of ``self.params``, which then only carry the names and ``T_ref``)."""
        if table.n != len(self.params):
            raise IPMCError(f"a table of {table.n} sets for {len(self.params)} parameter sets")
        self._batch_table = table

    def _batch_effects(self, values_per_set: Sequence[Mapping[str, Mapping[str, float]]]) -> None:
        """Switch this model's batchable effects to per-set values: ``values_per_set[i]`` =
        ``{effect: {param: value}}`` of parameter set i on top of ``self.effects`` (missing: this
        model's value, else off).  Values are checked as :func:`normalize_effects` does; a set where
        an effect is off gets its off values and the effect's result is replaced by the base's
        exactly there.  Non-batchable effects must be given the same values in every set (they
        stay as built)."""
        n = len(self.params)
        if len(values_per_set) != n:
            raise IPMCError(f"{len(values_per_set)} sets of effect values for {n} parameter sets")
        names = list(self.effects)
        canon = []
        for ev in values_per_set:
            canon.append({get_effect(k).name: pv for k, pv in ev.items()})
            for k in canon[-1]:
                if k not in names:
                    names.append(k)
        active = []
        for name in names:
            e = get_effect(name)
            if self.kind not in e.kinds:
                raise IPMCError(f"effect {name!r} does not apply to a {self.kind} model (it applies to {e.kinds})")
            own = self.effects.get(name, e.off)
            if not e.batchable:
                if any(ev.get(name, {}) != canon[0].get(name, {}) for ev in canon):
                    if e.level != "kernel":
                        raise IPMCError(f"effect {name!r} is not batchable: one model call needs one set of its values")
                    # a kernel effect on in every set: its ŝ per set (ModelBase evaluate_grid's per-set points)
                    vals = {p.name: np.array([ev.get(name, {}).get(p.name, own[p.name]) for ev in canon], dtype=float)
                            for p in e.parameters}
                    entry = _batched_entry(e, vals)
                    if entry is None or entry[2] is not None:
                        raise IPMCError(f"effect {name!r}: one model call takes its values per set only where it is "
                                        "on in every set")
                    active.append(entry)
                    continue
                if e.level == "kernel":       # the same values in every set: these (the model may be a cached one)
                    own = {**own, **canon[0].get(name, {})}
                    if not e.is_off(own):
                        active.append((e, own, None))
                elif name in self.effects and not e.is_off(own):
                    active.append((e, own, None))
                continue
            for ev in canon:
                bad = set(ev.get(name, {})) - set(own)
                if bad:
                    e.parameter(sorted(bad)[0])                 # raises: no such parameter
            vals = {p.name: np.array([ev.get(name, {}).get(p.name, own[p.name]) for ev in canon], dtype=float)
                    for p in e.parameters}
            entry = _batched_entry(e, vals)
            if entry is not None:
                active.append(entry)
        self._active = active

    def _batch_effect_arrays(self, given: Mapping[str, Mapping[str, np.ndarray]]) -> bool:
        """:meth:`_batch_effects` with the values already as arrays over the sets: ``given`` =
        ``{effect: {param: (n_sets,) array}}``, canonical names of batchable effects or of a kernel
        effect with known parameters (missing parameters: this model's value, else off).  False
        (nothing changed) when a kernel effect is on in some sets and off in others: those go in
        separate calls (:meth:`_batch_effects`)."""
        n = len(self.params)
        active = []
        for name in (*self.effects, *(k for k in given if k not in self.effects)):
            e = get_effect(name)
            if self.kind not in e.kinds:
                raise IPMCError(f"effect {name!r} does not apply to a {self.kind} model (it applies to {e.kinds})")
            own = self.effects[name] if name in self.effects else e.off
            if not e.batchable and name in given and e.level == "kernel":
                g = given[name]
                vals = {p.name: np.asarray(g[p.name], dtype=float) if p.name in g else np.full(n, float(own[p.name]))
                        for p in e.parameters}
                entry = _batched_entry(e, vals)                     # checks the values; None: off in every set
                if entry is None:
                    continue
                if all(np.all(a == a[0]) for a in vals.values()):   # one ŝ grid, as a call of its own
                    active.append((e, {k: float(a[0]) for k, a in vals.items()}, None))
                elif entry[2] is not None:
                    return False
                else:
                    active.append(entry)
                continue
            if not e.batchable:
                if name in given:
                    raise IPMCError(f"effect {name!r} is not batchable: give its values through _batch_effects")
                if not e.is_off(own):
                    active.append((e, own, None))
                continue
            g = given.get(name, {})
            vals = {p.name: np.asarray(g[p.name], dtype=float) if p.name in g else np.full(n, float(own[p.name]))
                    for p in e.parameters}
            entry = _batched_entry(e, vals)
            if entry is not None:
                active.append(entry)
        self._active = active
        return True

    def state(self, temperature_c) -> State:
        st = super().state(temperature_c) if self._batch_table is None else self._batch_table.state(temperature_c)
        acts = self._levels()["parameter"]
        if not acts:
            return st
        # the state's own arrays (fresh ones each call; the effects replace entries, never write into them)
        d0 = {k: getattr(st, k) for k in STATE_FIELDS}
        d = dict(d0)
        T_ref = self._t_ref()
        for e, v, m in acts:
            new = e.apply(dict(d), T_ref, v)
            d = new if m is None else {k: np.where(m, new[k], d[k]) for k in d}
        # recomputed from what the effects replaced (inputs they left are the same arrays, and the
        # state's K and ωn are these expressions of them: the same numbers)
        if any(d[k] is not d0[k] for k in ("K", "d", "C_minus", "kappa_e", "T")):
            d["K"] = debye_rate(d["d"], d["C_minus"], d["kappa_e"], d["T"])
        if any(d[k] is not d0[k] for k in ("omega_n", "E", "rho", "L", "h")):
            d["omega_n"] = first_mode_omega(d["E"], d["rho"], d["L"], d["h"])
        if all(m is not None for _, _, m in acts):      # sets with every parameter effect off: the base state
            changed = np.logical_or.reduce([m for _, _, m in acts])
            for k in ("K", "omega_n"):
                d[k] = np.where(changed, d[k], d0[k])
        return State.of(d)

    def frequency_response(self, frequency_hz, temperature_c, quantities=None, out=None,
                           progress=None, *, checked: tuple | None = None) -> FrequencyResponse:
        """Like the base model's, with every effect applied.  ``out`` is filled if given.
        ``checked``: ``(f, T, s)``, these ``frequency_hz`` checked, ``temperature_c`` as a 1-D float
        array and s = 2j·π·f, made once by a caller that evaluates them many times (a predictor);
        when given, ``frequency_hz`` and ``temperature_c`` are not read (the caller vouches for it)."""
        qs = self._check_quantities(quantities or self.quantities)
        if checked is None:
            f = check_frequencies(frequency_hz)
            T = np.atleast_1d(np.asarray(temperature_c, dtype=float))
            checked = (f, T, 2j * np.pi * f)
        f, T, _ = checked
        res = self._respond(*checked, qs, out, progress)
        return FrequencyResponse(
            frequency_hz=f, temperature_c=T, parameter_sets=self._names,
            values=res, units={q: self.units[q] for q in qs},
            descriptions={q: self.descriptions[q] for q in qs},
        )

    def _levels(self) -> dict:
        """The entries of ``_active`` by level (in their order; "kernel": the first kernel effect's
        ``(effect, values)`` or None), split once per ``_active`` list."""
        split = self._split
        if split is None or split[0] is not self._active:
            by: dict = {"parameter": [], "strip": [], "response": [], "series": [], "kernel": None}
            for x in self._active:
                level = x[0].level
                if level != "kernel":
                    by[level].append(x)
                elif by["kernel"] is None:
                    by["kernel"] = x[:2]
            split = self._split = (self._active, by)
        return split[1]

    def _t_ref(self) -> np.ndarray:
        """The sets' reference temperatures (n_sets, 1, 1) [K], read-only, once per ``params`` list."""
        hit, params = self._t_ref_of, self.params
        if hit is None or hit[0] is not params or len(hit[1]) != len(params):
            t = np.array([p.T_ref for p in params], dtype=float)[:, None, None]
            t.flags.writeable = False
            hit = self._t_ref_of = (params, t)
        return hit[1]

    def _respond(self, f, T, s, qs, out=None, progress=None) -> dict:
        """:meth:`frequency_response`'s values ``{q: (n_sets, n_T, n_f)}`` at checked frequencies
        ``f`` [Hz] (1-D), temperatures ``T`` [°C] (1-D float) and ``s = 2j·π·f`` [1/s]."""
        st = self.state(T)
        levels = self._levels()
        resp, series, kern = levels["response"], levels["series"], levels["kernel"]
        need = _needed(self.quantities, qs, bool(series))
        s_kernel = s if kern is None else kern[0].apply(s, kern[1])
        if kern is None and progress is None:
            # the model's own evaluation of a state: an actuator batch whose sets repeat an
            # electrode line or slice (finite-difference sets of the gain, the mode, a response or
            # series effect) evaluates those terms once (ActuatorModel.evaluate_state)
            vals = self.evaluate_state(st, s, need)
        elif kern is None:
            vals = evaluate_grid(st, s, self._kernel, need, self.chunk_size, None, progress)
        else:
            # the charge dynamics at ŝ, the mechanics at s
            electrical = tuple(q for q in need if q not in ("G", "M"))
            if "M" in need and "H" not in electrical:
                electrical = electrical + ("H",)
            vals = evaluate_grid(st, s_kernel, self._kernel, electrical, self.chunk_size, None, progress)
            if "G" in need or "M" in need:
                G = first_mode(s[None, None, :], st.omega_n, st.xi)
                if "G" in need:
                    vals["G"] = G
                if "M" in need:
                    vals["M"] = vals["H"] * G
        T_ref = self._t_ref()
        ctx = _Context(s[None, None, :], s_kernel if s_kernel.ndim == 3 else s_kernel[None, None, :], st, dict(vals),
                       T_ref)
        strip = levels["strip"]
        if strip:                           # the strip itself: every quantity computed, Z included
            partly = [m for _, _, m in strip if m is not None]
            x0 = ctx.x if partly else None  # the line without them, for the sets where they are off
            for q in need:
                for e, ev, m in strip:
                    if q in e.quantities:
                        vals[q] = vals[q] * _where_on(m, e.apply(q, ctx, ev), 1.0)
            if partly and len(partly) == len(strip) and ctx._x is not x0:
                ctx._x = np.where(np.logical_or.reduce(partly), ctx._x, x0)
            ctx.base = dict(vals)
        for q in qs:
            fac = [_where_on(m, e.apply(q, ctx, ev), 1.0) for e, ev, m in resp if q in e.quantities]
            if fac:
                v = vals[q].copy()
                for x in fac:
                    v *= x
                vals[q] = v
        if series:
            Z0 = ctx.base["Z"]
            zs = sum(_where_on(m, e.apply(ctx, ev), 0.0) for e, ev, m in series)
            masks = [m for _, _, m in series]
            on = None if any(m is None for m in masks) else np.logical_or.reduce(masks)
            for q in qs:
                if q == "Z":
                    vals[q] = vals[q] + zs
                elif q != "G":                 # voltage divider (actuator) / current divider (sensor)
                    vals[q] = _where_on(on, vals[q] * (Z0 / (Z0 + zs)), vals[q])
        res = {}
        for q in qs:
            if out is not None and q in out:
                out[q][...] = vals[q]
                res[q] = out[q]
            else:
                res[q] = np.asarray(vals[q], dtype=complex)
        return res

    def evaluate(self, *a, **k):  # pragma: no cover - guard
        raise IPMCError("EffectModel evaluates on the imaginary axis only; use frequency_response()")

    def with_values(self, values: Mapping[str, float]) -> _EffectMixin:
        """A model with base parameters and/or ``"effect.param"`` values replaced (effects may be new)."""
        base_vals, eff_vals = split_values(values)
        params = [_apply(p, base_vals) for p in self.params]
        effects = {n: dict(v) for n, v in self.effects.items()}
        for n, v in eff_vals.items():
            effects.setdefault(n, {}).update(v)
        return make_effect_model(params, self.kind, effects, **self._extra())

    def predictor(self, data, quantity: str | None = None) -> Callable[[Mapping[str, float]], np.ndarray]:
        """``predict(values) -> complex response at every row of ``data`` in its units``.

        ``values`` maps base-parameter names (``omega_n`` allowed) and ``"effect.param"`` names to
        numbers; anything not given keeps this model's value.  One vectorised model call per
        prediction (unique temperatures × union of frequencies).  ``predict.many(list_of_values)``
        is the batched form (n_sets, N) for ``fit_parameters(predict_many=...)``; it uses the first
        parameter set of this model as the base and evaluates every set in one model call, the
        values of the batchable effects (:attr:`Effect.batchable`) as arrays over the sets (one call
        per distinct set of values of the others, except a kernel effect's: one call for the sets
        where it is on, each on its own ŝ, one for those where it is off).  ``predict.many_grouped``
        is the same with one
        model call per distinct set of effect values.
        """
        from ..data.sweep import sweep_layout

        lay = sweep_layout(data, self.kind, quantity or DEFAULT_QUANTITY[self.kind])
        q, scale, freqs, fi, temps, ti = (lay.quantity, lay.factor, lay.frequencies_hz, lay.f_index,
                                          lay.temperatures_c, lay.t_index)

        def predict(values: Mapping[str, float]) -> np.ndarray:
            m = self.with_values(values) if values else self
            r = m.frequency_response(freqs, temps, quantities=(q,))[q][0]
            return r[ti, fi] * scale

        paths: dict = {}        # the base names, each resolved once against self.params[0]
        table0 = ParameterTable.of(self.params[0])
        # the models of the batched calls, by (values of the non-batchable effects, number of sets):
        # each call gives them its own table and effect values (_use_table, _batch_effects)
        models: dict = {}

        plans: dict = {}        # the fast path's plan of each tuple of names (None: the general path)
        repeated: dict = {}     # the fast path's base columns over n sets, by n
        grid: list = []         # the fast path's (frequencies [Hz], temperatures [°C], s), checked once

        def plan_of(keys: tuple):
            """Where the names ``keys`` go when every set gives exactly these: ``(base, omega,
            effects)`` = ([(field, column)], column of omega_n or None, {effect: {param: column}}),
            or None (a temperature law, T_ref, a non-batchable effect or an error: the general path
            handles and words them)."""
            from ..parameter_paths import resolve_path

            base, omega, effects = [], None, {}
            for j, k in enumerate(keys):
                ep = _effect_parameter(k)
                try:
                    if ep is None:
                        path = paths.get(k)
                        if path is None:
                            path = paths[k] = resolve_path(self.params[0], k)
                        if path.target == "omega_n":
                            omega = j
                        elif path.is_law or k == "T_ref" or k not in table0.columns:
                            return None
                        else:
                            base.append((k, j))
                        continue
                    e = get_effect(ep[0])
                    e.parameter(ep[1])
                except IPMCError:
                    return None
                if (not e.batchable and e.level != "kernel") or self.kind not in e.kinds or ep[1] in effects.get(e.name, {}):
                    return None
                effects.setdefault(e.name, {})[ep[1]] = j
            return base, omega, effects

        def predict_fast(values_list, plan, n_names: int) -> np.ndarray | None:
            # every set names the same parameters: one array of values, columns by name; the same
            # numbers and checks as the general path below (the table of _table_of, _batch_effects)
            n = len(values_list)
            X = np.array([list(v.values()) for v in values_list], dtype=float)
            if X.shape != (n, n_names):
                return None
            base, omega, effects = plan
            cols = dict(table0.columns)
            lo, hi = X.min(axis=0).tolist(), X.max(axis=0).tolist()     # each column's (NaN propagates)
            for name, j in base:
                # check_field_values's test from the column's extremes; it words a bad value
                cols[name] = (X[:, j] if field_range_ok(name, lo[j], hi[j]) else check_field_values(name, X[:, j]))[:, None]
            if omega is not None:
                rho = density_for_mode(X[:, omega], cols["E"][:, 0], cols["L"][:, 0], cols["h"][:, 0])
                cols["rho"] = check_field_values("rho", rho)[:, None]
            rep = repeated.get(n)
            if rep is None:         # the base's columns over n sets, once per n (read-only, only read)
                if len(repeated) >= 16:
                    repeated.pop(next(iter(repeated)))
                rep = repeated[n] = {k: np.repeat(v, n, axis=0) for k, v in table0.columns.items()}
                for v in rep.values():
                    v.flags.writeable = False
            table = table0.with_columns({k: v if len(v) == n else rep[k] for k, v in cols.items()}, n)
            m = models.get(((), n))
            if m is None:
                if len(models) >= 64:
                    models.pop(next(iter(models)))
                m = models[(), n] = make_effect_model([self.params[0]] * n, self.kind, self.effects, **self._extra())
            m._use_table(table)
            if not m._batch_effect_arrays({e: {p: X[:, j] for p, j in pj.items()} for e, pj in effects.items()}):
                return None                 # a kernel effect on in some sets only: the general path
            if not grid:            # the frequencies and temperatures, checked once (as frequency_response does)
                f = check_frequencies(freqs)
                T = np.array(np.atleast_1d(np.asarray(temps, dtype=float)))
                s = 2j * np.pi * f
                f.flags.writeable = T.flags.writeable = s.flags.writeable = False
                grid.append((f, T, s))
            r = m.frequency_response(freqs, temps, quantities=(q,), checked=grid[0])[q]
            # C order, as the general path's: r[:, ti, fi] alone comes out in Fortran order, and the
            # estimation layer's reductions and products over it then round differently
            out = np.empty((n, data.response.size), dtype=complex)
            np.multiply(r[:, ti, fi], scale, out=out)
            return out

        def predict_many(values_list: Sequence[Mapping[str, float]]) -> np.ndarray:
            # one batched model call for every set (effect values as arrays over the sets), or one
            # per distinct set of values of the non-batchable effects (Effect.batchable; a kernel
            # effect's: one per on / off)
            if values_list:
                keys = tuple(values_list[0])
                if all(tuple(v) == keys for v in values_list):
                    plan = plans.get(keys, False)
                    if plan is False:
                        if len(plans) >= 256:
                            plans.pop(next(iter(plans)))
                        plan = plans[keys] = plan_of(keys)
                    if plan is not None:
                        r = predict_fast(values_list, plan, len(keys))
                        if r is not None:
                            return r
            out = np.empty((len(values_list), data.response.size), dtype=complex)
            split = [split_values(v) for v in values_list]
            groups: dict = {}
            for i, (_, e) in enumerate(split):
                key = tuple(sorted((get_effect(n).name, _group_value(get_effect(n), pv, self.effects))
                                   for n, pv in e.items() if not get_effect(n).batchable))
                groups.setdefault(key, []).append(i)
            for key, rows in groups.items():
                effects = {n: dict(v) for n, v in self.effects.items()}
                # the non-batchable values (all the same in a group, but a kernel effect's, which
                # _batch_effects takes per set)
                for n, pv in split[rows[0]][1].items():
                    if not get_effect(n).batchable:
                        effects.setdefault(n, {}).update(pv)
                # the base values as arrays (no record per set), or a record per set when a name
                # addresses a temperature law or T_ref
                table = _table_of(self.params[0], [split[i][0] for i in rows], paths, table0)
                if table is not None:
                    m = models.get((key, len(rows)))
                    if m is None:
                        if len(models) >= 64:
                            models.pop(next(iter(models)))
                        m = models[key, len(rows)] = make_effect_model([self.params[0]] * len(rows), self.kind,
                                                                       effects, **self._extra())
                    m._use_table(table)
                else:
                    m = make_effect_model([_apply(self.params[0], split[i][0], paths) for i in rows], self.kind,
                                          effects, **self._extra())
                m._batch_effects([split[i][1] for i in rows])
                r = m.frequency_response(freqs, temps, quantities=(q,))[q]
                out[rows] = r[:, ti, fi] * scale
            return out

        def predict_many_grouped(values_list: Sequence[Mapping[str, float]]) -> np.ndarray:
            # one batched model call per distinct set of effect values (base values vary freely): the
            # reference the batched form is tested against
            out = np.empty((len(values_list), data.response.size), dtype=complex)
            groups: dict = {}
            for i, v in enumerate(values_list):
                b, e = split_values(v)
                key = tuple(sorted((n, tuple(sorted(pv.items()))) for n, pv in e.items()))
                groups.setdefault(key, []).append((i, b, e))
            for items in groups.values():
                e = items[0][2]
                effects = {n: dict(v) for n, v in self.effects.items()}
                for n, pv in e.items():
                    effects.setdefault(n, {}).update(pv)
                plist = [_apply(self.params[0], b, paths) for _, b, _ in items]
                m = make_effect_model(plist, self.kind, effects, **self._extra())
                r = m.frequency_response(freqs, temps, quantities=(q,))[q]
                for k, (i, _, _) in enumerate(items):
                    out[i] = r[k][ti, fi] * scale
            return out

        predict.many = predict_many
        predict.many_grouped = predict_many_grouped
        return predict

    def _extra(self) -> dict:
        return {}


class EffectActuatorModel(_EffectMixin, ActuatorModel):
    """An :class:`ActuatorModel` with effects (build it with :func:`EffectModel`)."""

    kind = "actuator"

    def __init__(self, params, effects=None, chunk_size: int = DEFAULT_CHUNK):
        ActuatorModel.__init__(self, params, chunk_size)
        self._init_effects(effects)

    def dc_gain(self, temperature_c):  # pragma: no cover - guard
        raise IPMCError("dc_gain is not defined with effects; use frequency_response at low frequency")

    def reduced(self, *a, **k):  # pragma: no cover - guard
        raise IPMCError("the reduced Taylor model ignores effects; use the base ActuatorModel")


class EffectSensorModel(_EffectMixin, SensorModel):
    """A :class:`SensorModel` with effects (build it with :func:`EffectModel`)."""

    kind = "sensor"

    def __init__(self, params, effects=None, kernel: str = "boundary_charge", chunk_size: int = DEFAULT_CHUNK):
        SensorModel.__init__(self, params, kernel, chunk_size)
        self._init_effects(effects)

    def _extra(self) -> dict:
        return {"kernel": self.kernel}


def make_effect_model(params, kind: str, effects=None, *, kernel: str = "boundary_charge",
                      chunk_size: int = DEFAULT_CHUNK):
    if kind == "actuator":
        return EffectActuatorModel(params, effects, chunk_size)
    if kind == "sensor":
        return EffectSensorModel(params, effects, kernel, chunk_size)
    raise IPMCError(f"kind must be one of {KINDS}, got {kind!r}")


def EffectModel(base_params: IPMCParameters | Sequence[IPMCParameters], kind: str = "actuator",
                effects: Mapping[str, Mapping[str, float]] | None = None, *,
                kernel: str = "boundary_charge", chunk_size: int = DEFAULT_CHUNK):
    """A base model (``kind`` "actuator" | "sensor") with named effects switched on.

    ``effects`` maps effect names (see :data:`LIBRARY`, :data:`OUT_OF_LIBRARY`) to
    ``{parameter: value}`` (SI; omitted parameters are off).  The result is an
    :class:`ActuatorModel`/:class:`SensorModel` subclass: ``frequency_response(f_hz, T_c)``
    works on batches of parameter sets, and ``synthesize_sweep`` simulates data from it.

    >>> m = EffectModel(get_parameter_set("seed002_table3"), "actuator", {"time_delay": {"delay": 1e-3}})
    """
    return make_effect_model(base_params, kind, effects, kernel=kernel, chunk_size=chunk_size)


__all__ = ["Effect", "EffectParameter", "EffectModel", "EffectActuatorModel", "EffectSensorModel",
           "LIBRARY", "OUT_OF_LIBRARY", "ALL_EFFECTS", "ALIASES", "get_effect", "candidates_for", "normalize_effects",
           "split_values", "candidate_free_parameters", "CONFUSABLE", "declared_confusable", "CPE_REFERENCE_HZ", "SECOND_MODE_RATIO", "DEFAULT_QUANTITY",
           "KINDS"]
