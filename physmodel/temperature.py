"""Temperature laws for the physical parameters (physics.md §7).

A temperature-dependent parameter is a reference value at the parameter set's reference
temperature ``T_ref`` [K] times a *factor* ``law.factor(T, T_ref)``.  Each law is a frozen
dataclass carrying its own validity range; evaluating outside it raises
:class:`~physmodel.errors.TemperatureRangeError`.  Kelvin inside, °C only at the edges.

Laws
----
Constant            factor 1.
Arrhenius           exp(-Ea/R (1/T - 1/T_ref)); default Ea = 15 kJ/mol (Nafion, 10.5-18 kJ/mol).
LogLinear           exp(slope (T - T_ref)); modulus default -0.75 %/K (DuPont: 114 MPa at 23 °C,
                    64 MPa at 100 °C for water-soaked Nafion).
Linear              1 + alpha (T - T_ref); electrode resistances, alpha <= 3.9e-3 /K (bulk Pt).
WaterPermittivity   eps_w(T)/eps_w(T_ref), Malmberg & Maryott (1956) polynomial, 0-100 °C.
IonicResistance     (T/T_ref) / (d(T)/d(T_ref)): Nernst-Einstein, resistance ∝ T/d (leakage Rp).
                    It needs the diffusivity factor, passed in by :func:`TemperatureLaws.factors`.

``K = F² d C⁻ / (κe R T)`` is not a law: it is computed from d(T), κe(T) and T.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace

import numpy as np
from scipy import constants

from .errors import ParameterError, TemperatureRangeError

#: Gas constant [J/(mol K)] (CODATA, from scipy.constants).
R_GAS = constants.R
#: Faraday constant [C/mol].
FARADAY = constants.physical_constants["Faraday constant"][0]
#: 0 °C in kelvin.
T0_K = constants.zero_Celsius


def celsius_to_kelvin(t_c):
    """Convert °C to K, refusing values below absolute zero or NaN."""
    t = np.asarray(t_c, dtype=float)
    if not np.all(np.isfinite(t)):
        raise TemperatureRangeError(f"temperature must be finite, got {t_c!r} [°C]")
    if np.any(t <= -T0_K):
        raise TemperatureRangeError(f"temperature {t_c!r} °C is at or below absolute zero")
    return t + T0_K


@dataclass(frozen=True)
class _Law:
    """Common part: validity range in °C (inclusive)."""

    valid_c: tuple[float, float] = field(default=(0.0, 100.0), kw_only=True)

    def check(self, T_K, name: str = "") -> None:
        lo, hi = self.valid_c
        t_c = np.asarray(T_K, dtype=float) - T0_K
        if np.any(t_c < lo - 1e-9) or np.any(t_c > hi + 1e-9):
            bad = t_c[(t_c < lo - 1e-9) | (t_c > hi + 1e-9)]
            raise TemperatureRangeError(
                f"{type(self).__name__} law{' for ' + name if name else ''} is valid on "
                f"[{lo:g}, {hi:g}] °C; got {np.round(bad, 3).tolist()[:5]} °C"
            )

    def describe(self) -> str:  # pragma: no cover - trivial
        return repr(self)


@dataclass(frozen=True)
class Constant(_Law):
    """The parameter does not depend on temperature."""

    valid_c: tuple[float, float] = field(default=(-273.15, 1e6), kw_only=True)

    def factor(self, T_K, T_ref_K, **_):
        return np.ones_like(np.asarray(T_K, dtype=float))


@dataclass(frozen=True)
class Arrhenius(_Law):
    """``exp(-Ea/R (1/T - 1/T_ref))``.  ``activation_energy`` Ea [J/mol]."""

    activation_energy: float = 15e3

    def __post_init__(self):
        if not np.isfinite(self.activation_energy):
            raise ParameterError(f"activation_energy must be finite, got {self.activation_energy!r} [J/mol]")

    def factor(self, T_K, T_ref_K, **_):
        T = np.asarray(T_K, dtype=float)
        return np.exp(-self.activation_energy / R_GAS * (1.0 / T - 1.0 / T_ref_K))


@dataclass(frozen=True)
class LogLinear(_Law):
    """``exp(slope (T - T_ref))``; ``slope`` [1/K] (−0.0075 = −0.75 %/K)."""

    slope: float = -0.0075

    def __post_init__(self):
        if not np.isfinite(self.slope):
            raise ParameterError(f"slope must be finite, got {self.slope!r} [1/K]")

    def factor(self, T_K, T_ref_K, **_):
        T = np.asarray(T_K, dtype=float)
        return np.exp(self.slope * (T - T_ref_K))


@dataclass(frozen=True)
class Linear(_Law):
    """``1 + alpha (T - T_ref)``; ``alpha`` [1/K].  Must stay positive over the validity range."""

    alpha: float = 3.9e-3

    def __post_init__(self):
        lo, hi = self.valid_c
        if not np.isfinite(self.alpha) or abs(self.alpha) * (hi - lo) >= 1:
            raise ParameterError(
                f"Linear law alpha={self.alpha!r} /K can make the factor non-positive on "
                f"[{lo:g}, {hi:g}] °C; expected |alpha|·(range width) < 1"
            )

    def factor(self, T_K, T_ref_K, **_):
        T = np.asarray(T_K, dtype=float)
        return 1.0 + self.alpha * (T - T_ref_K)


def water_permittivity(t_c):
    """Relative permittivity of water, Malmberg & Maryott (1956), ``t_c`` in °C (0-100 °C)."""
    t = np.asarray(t_c, dtype=float)
    return 87.740 - 0.40008 * t + 9.398e-4 * t**2 - 1.410e-6 * t**3


@dataclass(frozen=True)
class WaterPermittivity(_Law):
    """``eps_w(T)/eps_w(T_ref)`` (Malmberg & Maryott 1956), valid 0-100 °C."""

    def factor(self, T_K, T_ref_K, **_):
        return water_permittivity(np.asarray(T_K, dtype=float) - T0_K) / water_permittivity(T_ref_K - T0_K)


@dataclass(frozen=True)
class IonicResistance(_Law):
    """Nernst-Einstein: ionic resistance ∝ T/d(T), so the factor is (T/T_ref)/(d(T)/d(T_ref))."""

    def factor(self, T_K, T_ref_K, *, diffusivity_factor=None, **_):
        if diffusivity_factor is None:
            raise ParameterError("IonicResistance needs the diffusivity factor d(T)/d(T_ref)")
        T = np.asarray(T_K, dtype=float)
        return (T / T_ref_K) / diffusivity_factor


#: Parameters that may carry a temperature law; all others are constant.
LAW_PARAMETERS = ("d", "E", "kappa_e", "Rp_specific", "r1_sheet", "r2_specific", "C_minus", "h")


#: :meth:`TemperatureLaws.factors` kept per (laws, temperatures, T_ref), oldest dropped first.
_FACTORS_CACHE: dict = {}
_FACTORS_CACHE_SIZE = 64


@dataclass(frozen=True)
class TemperatureLaws:
    """One law per temperature-dependent parameter (physics.md §7 defaults).

    Fields name :class:`~physmodel.params.IPMCParameters` fields.  ``C_minus`` and ``h`` are
    constant by default; water uptake (C⁻ and thickness changing with T) is a discrepancy
    candidate, so they may be given laws too.
    """

    d: _Law = field(default_factory=Arrhenius)
    E: _Law = field(default_factory=LogLinear)
    kappa_e: _Law = field(default_factory=WaterPermittivity)
    Rp_specific: _Law = field(default_factory=IonicResistance)
    r1_sheet: _Law = field(default_factory=Constant)
    r2_specific: _Law = field(default_factory=Constant)
    C_minus: _Law = field(default_factory=Constant)
    h: _Law = field(default_factory=Constant)

    def describe(self) -> str:
        """One clause per non-constant law, e.g. ``d Arrhenius(activation_energy=15000); E
        LogLinear(slope=-0.0075)`` (reports, and the premise of a recommended bath step)."""
        parts = []
        for f in fields(self):
            law = getattr(self, f.name)
            kind = type(law).__name__
            if kind == "Constant":
                continue
            args = ", ".join(f"{k.name}={getattr(law, k.name):g}" for k in fields(law) if k.name != "valid_c")
            parts.append(f"{f.name} {kind}({args})")
        return "; ".join(parts) if parts else "every parameter constant (isothermal)"

    def factors(self, T_K, T_ref_K) -> dict[str, np.ndarray]:
        """Multiplicative factors for every law parameter at temperatures ``T_K`` [K].

        The laws are frozen values, so the factors at the same temperatures and ``T_ref`` are kept
        (a fit evaluates one laws object at one temperature grid thousands of times): the arrays
        returned are read-only and shared between calls."""
        key = None
        if np.ndim(T_ref_K) == 0:
            T = np.asarray(T_K, dtype=float)
            key = (self, T.shape, T.tobytes(), float(T_ref_K))
            hit = _FACTORS_CACHE.get(key)
            if hit is not None:
                return dict(hit)
        out: dict[str, np.ndarray] = {}
        for name in LAW_PARAMETERS:
            getattr(self, name).check(T_K, name)
        out["d"] = self.d.factor(T_K, T_ref_K)
        for name in LAW_PARAMETERS[1:]:
            out[name] = getattr(self, name).factor(T_K, T_ref_K, diffusivity_factor=out["d"])
        if key is not None:
            for name, v in out.items():         # own copies (a law may hand back its input)
                out[name] = v = np.array(v)
                v.flags.writeable = False
            if len(_FACTORS_CACHE) >= _FACTORS_CACHE_SIZE:
                _FACTORS_CACHE.pop(next(iter(_FACTORS_CACHE)))
            _FACTORS_CACHE[key] = out
        return dict(out)

    def with_(self, **laws: _Law) -> TemperatureLaws:
        """A copy with some laws replaced, e.g. ``laws.with_(E=Constant())``."""
        unknown = set(laws) - {f.name for f in fields(self)}
        if unknown:
            raise ParameterError(f"no temperature law for {sorted(unknown)}; expected one of {LAW_PARAMETERS}")
        return replace(self, **laws)

    def to_dict(self) -> dict:
        out = {}
        for f in fields(self):
            law = getattr(self, f.name)
            d = {k.name: getattr(law, k.name) for k in fields(law)}
            d["valid_c"] = list(d["valid_c"])
            out[f.name] = {"law": type(law).__name__, **d}
        return out

    @classmethod
    def from_dict(cls, data: Mapping) -> TemperatureLaws:
        """The laws from ``{quantity: {"law": NAME, parameter: value, "valid_c": [lo, hi]}}`` (what
        :meth:`to_dict` writes); a wrong shape, name or value is a ParameterError naming the key."""
        kinds = {c.__name__: c for c in (Constant, Arrhenius, LogLinear, Linear, WaterPermittivity, IonicResistance)}
        if not isinstance(data, Mapping):
            raise ParameterError(f"laws must be an object {{quantity: {{'law': NAME, ...}}}}, got {data!r}")
        names = [f.name for f in fields(cls)]
        laws = {}
        for name, spec in data.items():
            if name not in names:
                raise ParameterError(f"laws: unknown quantity {name!r}; expected one of {names}")
            if not isinstance(spec, Mapping):
                raise ParameterError(f"laws.{name}: expected an object with 'law' and its parameters, got {spec!r}")
            spec = dict(spec)
            if "law" not in spec:
                raise ParameterError(f"laws.{name}: missing 'law'; expected one of {sorted(kinds)}")
            kind = spec.pop("law")
            if not isinstance(kind, str) or kind not in kinds:
                raise ParameterError(f"unknown temperature law {kind!r} for {name}; expected one of {sorted(kinds)}")
            allowed = {f.name for f in fields(kinds[kind])}
            unknown = sorted(set(spec) - allowed)
            if unknown:
                raise ParameterError(f"laws.{name}: {kind} has no parameter(s) {unknown}; expected {sorted(allowed)}")
            for k, v in spec.items():
                where = f"laws.{name}.{k}"
                if k == "valid_c":
                    if not (isinstance(v, (list, tuple)) and len(v) == 2):
                        raise ParameterError(f"{where}: expected [lowest, highest] °C, got {v!r}")
                    lo, hi = (real_number(x, where) for x in v)
                    if not lo < hi:
                        raise ParameterError(f"{where}: expected lowest < highest, got {v!r}")
                    spec[k] = (lo, hi)
                else:
                    spec[k] = real_number(v, where)
            laws[name] = kinds[kind](**spec)
        return cls(**laws)


def real_number(v, where: str) -> float:
    """``v`` as a float: a JSON/TOML number (not a boolean) or the strings "inf"/"-inf" that
    parameter files use for infinities; a ParameterError naming ``where`` otherwise (NaN too)."""
    if isinstance(v, str) and v.strip().lower() in ("inf", "+inf", "-inf", "infinity", "-infinity"):
        return float(v)
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{where}: expected a number, got {v!r}")
    v = float(v)
    if math.isnan(v):
        raise ParameterError(f"{where}: expected a number, got NaN")
    return v


#: Every parameter constant (for isothermal studies and for the width/Taylor checks).
ISOTHERMAL = TemperatureLaws(
    d=Constant(), E=Constant(), kappa_e=Constant(), Rp_specific=Constant(),
    r1_sheet=Constant(), r2_specific=Constant(), C_minus=Constant(), h=Constant(),
)
