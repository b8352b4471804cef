"""Parameter records for IPMC strips: frozen, typed, SI, with their source.

:class:`IPMCParameters` holds the reference values of one strip at ``T_ref`` together with the
:class:`~physmodel.temperature.TemperatureLaws` that move them with temperature.  Per-width
electrode quantities (``r1_sheet``, ``r2_specific``, ``Rp_specific``) are stored so that changing
the width ``W`` keeps the physics width-independent, as seed 002 observes of eq. (13):

    r1 = r1_sheet / W      [Ω/m]   electrode resistance along the length (each electrode)
    r2 = r2_specific / W   [Ω·m]   through-thickness resistance of one electrode, per slice
    Rp = Rp_specific / W   [Ω·m]   polymer leakage through the full thickness, per slice

Named sets live in :mod:`physmodel.parameter_sets`; variants come from :meth:`IPMCParameters.replace`.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from dataclasses import MISSING, dataclass, field, fields, replace
from typing import Any

import numpy as np

from .errors import ParameterError
from .temperature import FARADAY, LAW_PARAMETERS, R_GAS, TemperatureLaws, celsius_to_kelvin, real_number

#: (β1 L)² for the first clamped-free bending mode (β1 L = 1.8751...).
BETA1L_SQ = 1.8751040687119611**2


def _meta(unit: str, doc: str, group: str, *, positive=True, allow_inf=False, allow_zero=False):
    return {"unit": unit, "doc": doc, "group": group, "positive": positive,
            "allow_inf": allow_inf, "allow_zero": allow_zero}


@dataclass(frozen=True)
class IPMCParameters:
    """Physical parameters of one IPMC strip at the reference temperature ``T_ref``.

    All values SI.  See ``fields(IPMCParameters)[i].metadata`` for unit, group and meaning.
    """

    # geometry
    L: float = field(metadata=_meta("m", "free length", "geometry"))
    W: float = field(metadata=_meta("m", "width", "geometry"))
    h: float = field(metadata=_meta("m", "half-thickness of the polymer (thickness 2h)", "geometry"))
    # material (transport)
    d: float = field(metadata=_meta("m^2/s", "effective cation diffusivity", "material"))
    C_minus: float = field(metadata=_meta("mol/m^3", "fixed anion concentration C-", "material"))
    kappa_e: float = field(metadata=_meta("F/m", "effective dielectric permittivity", "material"))
    # coupling
    alpha0: float = field(metadata=_meta("J/C", "actuation coupling: stress = alpha0 * charge density", "material", positive=False))
    a0: float = field(metadata=_meta("C/J", "sensing coupling: boundary charge density = a0 * stress", "material", positive=False))
    # electrodes
    r1_sheet: float = field(metadata=_meta("Ohm", "electrode sheet resistance along the length (r1' of seed 002; r1 = r1'/W)", "electrode", allow_zero=True))
    r2_specific: float = field(metadata=_meta("Ohm m^2", "through-thickness electrode resistance times width (r2' of seed 002; r2 = r2'/W)", "electrode", allow_zero=True))
    Rp_specific: float = field(metadata=_meta("Ohm m^2", "polymer leakage resistance times width (Rp' of seed 002; inf = no leakage)", "electrode", allow_inf=True))
    # mechanics
    E: float = field(metadata=_meta("Pa", "Young's modulus of the composite beam", "mechanics"))
    rho: float = field(metadata=_meta("kg/m^3", "effective density setting the first mode (includes any added mass)", "mechanics"))
    xi: float = field(metadata=_meta("-", "damping ratio of the first bending mode", "mechanics"))
    # bookkeeping
    T_ref: float = field(default=300.0, metadata=_meta("K", "reference temperature of the values above", "state"))
    laws: TemperatureLaws = field(default_factory=TemperatureLaws, metadata={"unit": "", "doc": "temperature laws", "group": "state"})
    name: str = field(default="custom", metadata={"unit": "", "doc": "name", "group": "source"})
    source: str = field(default="user", metadata={"unit": "", "doc": "where the values come from", "group": "source"})

    def __post_init__(self):
        for f in fields(self):
            if f.name in ("laws", "name", "source"):
                continue
            v = getattr(self, f.name)
            m = f.metadata
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
                raise ParameterError(f"{f.name} must be a real number [{m['unit']}], got {v!r}")
            v = float(v)
            object.__setattr__(self, f.name, v)
            if math.isnan(v):
                raise ParameterError(f"{f.name} is NaN; expected a number [{m['unit']}]")
            if math.isinf(v) and not m["allow_inf"]:
                raise ParameterError(f"{f.name}={v!r} [{m['unit']}] must be finite")
            if m["positive"]:
                if v < 0 or (v == 0 and not m["allow_zero"]):
                    need = ">= 0" if m["allow_zero"] else "> 0"
                    raise ParameterError(f"{f.name}={v!r} [{m['unit']}] ({m['doc']}) must be {need}")
        if not isinstance(self.laws, TemperatureLaws):
            raise ParameterError(f"laws must be a TemperatureLaws record, got {type(self.laws).__name__}")

    # ------------------------------------------------------------------ derived quantities
    @property
    def second_moment(self) -> float:
        """I = (2/3) W h³ [m⁴]."""
        return 2.0 / 3.0 * self.W * self.h**3

    @property
    def omega_n(self) -> float:
        """First clamped-free bending mode at ``T_ref`` [rad/s] (Euler-Bernoulli)."""
        return first_mode_omega(self.E, self.rho, self.L, self.h)

    @property
    def K(self) -> float:
        """K = F² d C⁻ / (κe R T_ref) [1/s]."""
        return FARADAY**2 * self.d * self.C_minus / (self.kappa_e * R_GAS * self.T_ref)

    @property
    def gamma0(self) -> float:
        """γ0 = h sqrt(K/d), the low-frequency value of γ(s) [-]."""
        return self.h * math.sqrt(self.K / self.d)

    def replace(self, **changes: Any) -> IPMCParameters:
        """A copy with fields replaced.  ``omega_n=`` sets the first mode by adjusting ``rho``."""
        changes = dict(changes)
        wn = changes.pop("omega_n", None)
        names = {f.name for f in fields(self)}
        unknown = set(changes) - names
        if unknown:
            raise ParameterError(f"unknown parameter(s) {sorted(unknown)}; expected names from {sorted(names)}")
        out = replace(self, **changes)
        if wn is not None:
            out = replace(out, rho=density_for_mode(wn, out.E, out.L, out.h))
        return out

    def to_dict(self) -> dict:
        d = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "laws"}
        d["laws"] = self.laws.to_dict()
        return d

    @classmethod
    def from_dict(cls, data: dict) -> IPMCParameters:
        """The record :meth:`to_dict` writes; a missing, unknown or non-numeric entry (``null``,
        ``true``, ``"abc"``) is a ParameterError naming the key."""
        if not isinstance(data, dict):
            raise ParameterError(f"a parameter record must be an object, got {type(data).__name__}")
        data = dict(data)
        laws = data.pop("laws", None)
        if laws is not None and not isinstance(laws, TemperatureLaws):
            laws = TemperatureLaws.from_dict(laws)
        names = {f.name for f in fields(cls)}
        unknown = set(data) - names
        if unknown:
            raise ParameterError(f"unknown parameter(s) {sorted(unknown)} in parameter record")
        required = [f.name for f in fields(cls) if f.default is MISSING and f.default_factory is MISSING]
        missing = [k for k in required if k not in data]
        if missing:
            raise ParameterError(f"parameter record misses {missing} (SI values)")
        out = {}
        for k, v in data.items():
            if k in ("name", "source"):
                if not isinstance(v, str):
                    raise ParameterError(f"{k}: expected a string, got {v!r}")
                out[k] = v
            else:
                out[k] = real_number(v, f"{k} [{cls.__dataclass_fields__[k].metadata['unit']}]")
        if laws is not None:
            out["laws"] = laws
        return cls(**out)

    @staticmethod
    def units() -> dict[str, str]:
        return {f.name: f.metadata["unit"] for f in fields(IPMCParameters)}


def first_mode_omega(E, rho, L, h):
    """ω1 = (β1L)²/L² sqrt(E I / (ρ A)) with I/A = h²/3 [rad/s]."""
    return BETA1L_SQ / L**2 * np.sqrt(E * h**2 / (3.0 * rho))


def field_range_ok(name: str, lo: float, hi: float) -> bool:
    """Whether values of numeric field ``name`` whose minimum is ``lo`` and maximum ``hi`` (NaN if
    any is NaN) all pass the checks :class:`IPMCParameters` makes (see :func:`check_field_values`)."""
    m = _FIELD_META[name]
    return (lo == lo and hi == hi and (m["allow_inf"] or (hi < math.inf and lo > -math.inf))
            and (not m["positive"] or lo > 0 or (lo == 0 and m["allow_zero"])))


def check_field_values(name: str, values) -> np.ndarray:
    """The checks :class:`IPMCParameters` makes of numeric field ``name``, over an array of values
    (one per parameter set, e.g. a batch built without a record per set); returns them as floats.
    A bad value is a :class:`ParameterError` worded as the record's own."""
    m = _FIELD_META[name]
    v = np.asarray(values, dtype=float)
    if v.size and field_range_ok(name, float(v.min()), float(v.max())):
        return v                # the usual case, all good, from two reductions (NaN propagates into both)
    bad = np.isnan(v)
    if not m["allow_inf"]:
        bad |= np.isinf(v)
    if m["positive"]:
        bad |= (v < 0) | ((v == 0) & (not m["allow_zero"]))
    if np.any(bad):
        x = float(v[bad].ravel()[0])
        if math.isnan(x):
            raise ParameterError(f"{name} is NaN; expected a number [{m['unit']}]")
        if math.isinf(x) and not m["allow_inf"]:
            raise ParameterError(f"{name}={x!r} [{m['unit']}] must be finite")
        need = ">= 0" if m["allow_zero"] else "> 0"
        raise ParameterError(f"{name}={x!r} [{m['unit']}] ({m['doc']}) must be {need}")
    return v


def density_for_mode(omega_n, E, L, h):
    """Effective density [kg/m³] that puts the first mode at ``omega_n`` [rad/s] (arrays broadcast)."""
    w = np.asarray(omega_n, dtype=float)
    if not (w.size and w.min() > 0 and w.max() < math.inf):  # the usual case in two reductions (NaN fails it)
        bad = ~(np.isfinite(w) & (w > 0))
        if np.any(bad):
            raise ParameterError(f"omega_n={float(w[bad].ravel()[0]) if w.ndim else omega_n!r} rad/s must be a "
                                 "positive finite number")
    return E * h**2 / 3.0 * (BETA1L_SQ / (L**2 * omega_n)) ** 2


# ---------------------------------------------------------------------- state at temperature
#: Names of the arrays in a :class:`State`.
STATE_FIELDS = ("L", "W", "h", "d", "C_minus", "kappa_e", "alpha0", "a0", "r1", "r2", "Rp",
                "E", "rho", "xi", "T", "K", "omega_n")


@dataclass(frozen=True)
class State:
    """Parameter values at given temperatures, as broadcastable arrays of shape (n_sets, n_T, 1).

    Electrode values here are per slice: ``r1`` [Ω/m], ``r2`` [Ω·m], ``Rp`` [Ω·m] (may be inf).
    """

    L: np.ndarray
    W: np.ndarray
    h: np.ndarray
    d: np.ndarray
    C_minus: np.ndarray
    kappa_e: np.ndarray
    alpha0: np.ndarray
    a0: np.ndarray
    r1: np.ndarray
    r2: np.ndarray
    Rp: np.ndarray
    E: np.ndarray
    rho: np.ndarray
    xi: np.ndarray
    T: np.ndarray
    K: np.ndarray
    omega_n: np.ndarray

    @property
    def gamma0(self):
        return self.h * np.sqrt(self.K / self.d)

    @property
    def second_moment(self):
        return 2.0 / 3.0 * self.W * self.h**3

    @classmethod
    def of(cls, values) -> State:
        """The state whose arrays are ``values[field]`` for every field of the state (``STATE_FIELDS``)
        (the arrays themselves, as ``State(**values)`` keeps them; without its per-field setup)."""
        st = object.__new__(cls)
        st.__dict__.update({k: values[k] for k in STATE_FIELDS})
        return st

    def take(self, i_set: int, i_T: int) -> State:
        """The state of one parameter set at one temperature (arrays of shape (1, 1, 1))."""
        return State(**{k: getattr(self, k)[i_set:i_set + 1, i_T:i_T + 1] for k in STATE_FIELDS})


_FIELD_META = {f.name: f.metadata for f in fields(IPMCParameters) if f.name not in ("laws", "name", "source")}


def as_parameter_list(params) -> list[IPMCParameters]:
    if isinstance(params, IPMCParameters):
        return [params]
    out = list(params)
    if not out:
        raise ParameterError("an empty batch of parameter sets was given; expected at least one IPMCParameters")
    for p in out:
        if not isinstance(p, IPMCParameters):
            raise ParameterError(f"expected IPMCParameters in the batch, got {type(p).__name__}")
    return out


#: The numeric fields ``state_at`` reads, one array each over the sets.
_NUMERIC_STATE = ("L", "W", "alpha0", "a0", "rho", "xi", "T_ref") + tuple(LAW_PARAMETERS)
_FIELD_GETTERS = {name: operator.attrgetter(name) for name in _NUMERIC_STATE}
_LAWS_GETTER = operator.attrgetter("laws")


@dataclass(frozen=True)
class ParameterTable:
    """The numbers of a batch of parameter sets as arrays, built once (no per-set work when
    the batch is evaluated again, e.g. by a model at other temperatures).

    Attributes
    ----------
    columns : dict[str, ndarray]
        Each numeric field of ``_NUMERIC_STATE`` over the sets, shape (n_sets, 1). [SI]
    groups : list of (IPMCParameters, ndarray or None)
        Sets sharing a temperature-laws object and ``T_ref``: a representative and the
        indices of its members (None: every set).
    n : int
        Number of sets.
    """

    columns: dict
    groups: list
    n: int
    #: The temperatures this table's groups were evaluated at: ``{(shape, bytes of °C): (T [K], the
    #: groups' law factors)}``, shared by the tables :meth:`with_columns` makes (the same groups);
    #: not an init field, so ``dataclasses.replace`` (other groups, perhaps) starts with none.
    seen: dict = field(default_factory=dict, init=False, compare=False, repr=False)

    @classmethod
    def of(cls, params: IPMCParameters | Sequence[IPMCParameters]) -> ParameterTable:
        """The table of one set or a sequence of sets (one column per field, one row per set).

        Parameters
        ----------
        params : IPMCParameters or sequence of IPMCParameters
            The sets, in row order.

        Returns
        -------
        ParameterTable
            Columns of shape (n, 1) in SI units; sets sharing a laws object and ``T_ref`` form one group.
        """
        plist = as_parameter_list(params)
        n = len(plist)
        columns = {name: np.fromiter(map(getter, plist), float, count=n)[:, None]
                   for name, getter in _FIELD_GETTERS.items()}
        # the temperature laws once per (laws object, T_ref): sets made by ``replace`` share theirs
        laws = list(map(_LAWS_GETTER, plist))
        first = laws[0]
        t_ref = columns["T_ref"][:, 0]
        if all(law is first for law in laws) and np.all(t_ref == t_ref[0]):
            return cls(columns, [(plist[0], None)], n)
        members: dict[tuple, list[int]] = {}
        for i, key in enumerate(zip(map(id, laws), t_ref.tolist(), strict=True)):
            members.setdefault(key, []).append(i)
        return cls(columns, [(plist[idx[0]], np.asarray(idx)) for idx in members.values()], n)

    def with_columns(self, columns: dict, n: int) -> ParameterTable:
        """A table of ``n`` sets with these ``columns`` (each (n, 1) [SI]) and this table's groups
        (their laws and ``T_ref``), sharing what the groups' laws gave at each temperature."""
        out = ParameterTable(columns, self.groups, n)
        object.__setattr__(out, "seen", self.seen)      # not an init field: replace() starts afresh
        return out

    def _laws_at(self, temperature_c) -> tuple:
        """``(T [K], [the law factors of each group], those of a single group as rows (1, n_T) or
        None)`` at ``temperature_c`` [°C], kept per temperature array (a fit evaluates one table's
        groups at one grid many times; the arrays are read-only)."""
        t = np.asarray(temperature_c, dtype=float)
        key = (t.shape, t.tobytes())
        hit = self.seen.get(key)
        if hit is not None:
            return hit
        T = np.atleast_1d(celsius_to_kelvin(temperature_c)).astype(float)
        if T.ndim != 1:
            raise ParameterError(f"temperature_c must be a scalar or 1-D array, got shape {T.shape}")
        T.flags.writeable = False
        factors = [p.laws.factors(T, p.T_ref) for p, _ in self.groups]
        out = (T, factors, {k: v[None, :] for k, v in factors[0].items()} if len(factors) == 1 else None)
        if len(self.seen) >= 16:
            self.seen.pop(next(iter(self.seen)))
        self.seen[key] = out
        return out

    def state(self, temperature_c) -> State:
        """The :class:`State` of the batch at ``temperature_c`` [°C]."""
        T, factors, fac = self._laws_at(temperature_c)
        n, col = self.n, self.columns
        if fac is None:
            fac = {name: np.empty((n, T.size)) for name in LAW_PARAMETERS}
            for (_, idx), f in zip(self.groups, factors, strict=True):
                for name in LAW_PARAMETERS:
                    fac[name][idx] = f[name]
        # the fields constant along T repeated over it (fresh arrays, as the products below are)
        vals = {name: col[name][:, :, None].repeat(T.size, axis=1) for name in ("L", "W", "alpha0", "a0", "rho", "xi")}
        for name in LAW_PARAMETERS:
            vals[name] = (col[name] * fac[name])[:, :, None]
        W = vals["W"]
        vals["T"] = T[None, :, None].repeat(n, axis=0)
        vals["r1"] = vals.pop("r1_sheet") / W
        vals["r2"] = vals.pop("r2_specific") / W
        vals["Rp"] = vals.pop("Rp_specific") / W
        vals["K"] = FARADAY**2 * vals["d"] * vals["C_minus"] / (vals["kappa_e"] * R_GAS * vals["T"])
        vals["omega_n"] = first_mode_omega(vals["E"], vals["rho"], vals["L"], vals["h"])
        return State.of(vals)


def state_at(params: IPMCParameters | Sequence[IPMCParameters], temperature_c) -> State:
    """Evaluate the temperature laws of one parameter set or a batch at ``temperature_c`` [°C].

    Returns a :class:`State` whose arrays have shape (n_sets, n_T, 1).
    """
    return ParameterTable.of(params).state(temperature_c)


def describe(p: IPMCParameters) -> str:
    """A human-readable table of a parameter set with units."""
    lines = [f"{p.name}  ({p.source})"]
    for f in fields(p):
        if f.name in ("laws", "name", "source"):
            continue
        lines.append(f"  {f.name:12s} = {getattr(p, f.name):<12.6g} [{f.metadata['unit']}]  {f.metadata['doc']}")
    lines.append(f"  omega_n      = {p.omega_n:<12.6g} [rad/s]  first bending mode at T_ref")
    lines.append(f"  K            = {p.K:<12.6g} [1/s]")
    lines.append(f"  gamma0       = {p.gamma0:<12.6g} [-]")
    return "\n".join(lines)


__all__ = ["IPMCParameters", "State", "ParameterTable", "state_at", "first_mode_omega", "density_for_mode", "describe",
           "check_field_values", "field_range_ok",
           "as_parameter_list"]
