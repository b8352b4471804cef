"""A library of named physical effects that extend the Chen-Tan models (discrepancy.md §3).

Each :class:`Effect` is a documented, physically meaningful extension of
:class:`~physmodel.actuator.ActuatorModel` / :class:`~physmodel.sensor.SensorModel` with one or
two parameters and an "off" value at which the model is exactly the base model.  Effects act at
one of three levels:

``parameter``  they change the parameter values at each temperature (the :class:`State`):
               r1, r2, leakage, added fluid mass/damping, extra temperature laws, water uptake.
``response``   they multiply (or add to) the response: amplifier pole, time delay, a second
               bending mode, excitation-coupling compliance, a lumped series resistance.
``kernel``     they change the charge dynamics itself: the constant-phase element.

Constant-phase element (derivation).  Replace the first-order time derivative of the linearised
PNP charge equation by a Caputo derivative of order β (anomalous, distributed charge relaxation,
as in fractional PNP models of impedance spectroscopy; Macdonald, Evangelista & Lenzi)::

    ω_c^{1-β} D^β ρ = d ∂²ρ/∂x² − K ρ ,   and the continuity equation  ω_c^{1-β} D^β q + ∂J/∂x = 0

so that in the Laplace domain every ``s`` of the transport sub-model (γ, θ, Φ, the sensing current
s·charge) becomes ``ŝ = ω_c (s/ω_c)^β``.  The polymer admittance then tends to ŝ κe W/λ at low
frequency — a constant-phase double layer with exponent β — and the electrode line sees θ(ŝ).
Mechanics are unchanged, so ``Z, H, I, S`` are the base quantities evaluated at ŝ and
``M = H(ŝ) G(s)``.  β = 1 is off; ω_c = 2π·:data:`CPE_REFERENCE_HZ` is where |ŝ| = |s|.

:class:`EffectModel` composes any set of effects with a base parameter set; it is an
``ActuatorModel`` / ``SensorModel`` (so :func:`physmodel.data.sweep.synthesize_sweep` simulates data
with any effect switched on) and gives the ``predict(values)`` closure used by the calibration
engine (:meth:`EffectModel.predictor`).  Effect parameters are addressed as ``"effect.param"``.
Out-of-library effects for blind tests live in :data:`OUT_OF_LIBRARY` and are never candidates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from ..actuator import ActuatorModel
from ..errors import IPMCError, ParameterError
from ..model import DEFAULT_CHUNK, FrequencyResponse, check_frequencies, evaluate_grid
from ..params import STATE_FIELDS, IPMCParameters, State, first_mode_omega
from ..sensor import SensorModel
from ..temperature import FARADAY, R_GAS

#: Frequency [Hz] at which |ŝ| = |s| for the constant-phase element (ŝ = ω_c (s/ω_c)^β).
CPE_REFERENCE_HZ = 10.0
#: ω2/ω1 of a clamped-free Euler-Bernoulli beam, (4.694091/1.875104)².
SECOND_MODE_RATIO = (4.694091132974175 / 1.8751040687119611) ** 2

KINDS = ("actuator", "sensor")
DEFAULT_QUANTITY = {"actuator": "M", "sensor": "S"}


@dataclass(frozen=True)
class EffectParameter:
    """One parameter of an effect: SI ``unit``, ``off`` value, fit bounds and a typical size.

    ``typical`` is a moderate, clearly visible value for a seed-002-sized strip (used by the blind
    generator and as a scale); ``scale`` is a hint for optimisers (``"linear"`` here: every "off"
    value sits at 0 or at a bound, so log scales are not used).
    """

    name: str
    unit: str
    off: float
    lower: float
    upper: float
    typical: float
    doc: str = ""
    scale: str = "linear"

    def __post_init__(self):
        if not (self.lower <= self.off <= self.upper) or not (self.lower <= self.typical <= self.upper):
            raise ParameterError(f"effect parameter {self.name}: off={self.off} and typical={self.typical} "
                                 f"must lie in [{self.lower}, {self.upper}]")


@dataclass(frozen=True)
class Effect:
    """A named candidate effect: meaning, reference, parameters and where it applies.

    ``apply`` is private machinery (see the module functions ``_p_*``, ``_r_*``).
    ``kinds``/``quantities``: the model kinds and response quantities it changes.
    ``needs_temperatures``: it only shows in data taken at two or more temperatures.
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

    def applies_to(self, kind: str, quantity: str) -> bool:
        return kind in self.kinds and quantity in self.quantities

    def describe(self) -> str:
        pars = ", ".join(f"{p.name} [{p.unit}] off={p.off:g} in [{p.lower:g}, {p.upper:g}]" for p in self.parameters)
        return f"{self.name}: {self.title}. {self.description} Parameters: {pars}. Ref: {self.reference}"


# --------------------------------------------------------------------------- parameter level
# Each _p_* receives a dict of State arrays (n_sets, n_T, 1), the reference temperature array
# and the effect's values, and returns the updated dict (K and omega_n are recomputed after).
def _dT(st, T_ref):
    return st["T"] - T_ref


def _p_electrode(st, T_ref, v):
    st["r1"] = st["r1"] + v["r1_sheet"] / st["W"]
    return st


def _p_contact(st, T_ref, v):
    st["r2"] = st["r2"] + v["r2_specific"] / st["W"]
    return st


def _p_leakage(st, T_ref, v):
    with np.errstate(divide="ignore"):
        g = 1.0 / st["Rp"] + v["conductance"] * st["W"]      # 1/Rp [S/m] per slice
        st["Rp"] = np.where(g > 0, 1.0 / np.where(g > 0, g, 1.0), np.inf)
    return st


def _p_fluid(st, T_ref, v):
    mu, zf = v["mass_ratio"], v["damping_ratio"]
    st["rho"] = st["rho"] * (1.0 + mu)
    st["xi"] = (st["xi"] + zf) / math.sqrt(1.0 + mu)
    return st


def _p_modulus_T(st, T_ref, v):
    st["E"] = st["E"] * np.exp(v["slope"] * _dT(st, T_ref))
    return st


def _p_diffusivity_T(st, T_ref, v):
    fac = np.exp(-v["activation_energy"] / R_GAS * (1.0 / st["T"] - 1.0 / T_ref))
    st["d"] = st["d"] * fac
    st["Rp"] = st["Rp"] / fac            # Nernst-Einstein: ionic resistance ∝ T/d
    return st


def _p_permittivity_T(st, T_ref, v):
    st["kappa_e"] = st["kappa_e"] * np.exp(v["slope"] * _dT(st, T_ref))
    return st


def _p_water_uptake(st, T_ref, v):
    sw = 1.0 + v["swelling"] * _dT(st, T_ref)
    if np.any(sw <= 0):
        raise ParameterError(f"water_uptake.swelling={v['swelling']!r} /K makes the thickness non-positive "
                             "in the requested temperature range")
    st["h"] = st["h"] * sw
    st["C_minus"] = st["C_minus"] / sw   # fixed charges diluted by the absorbed water
    return st


# --------------------------------------------------------------------------- response level
# Each _r_* receives (quantity, s, state, base, values) with s (1, 1, n_f), the State and the
# base responses dict (arrays (n_sets, n_T, n_f)) and returns a multiplicative factor on quantity q.
# All response effects are factors computed from the base model, so they commute.
def _r_amplifier(q, s, st, base, v):
    return 1.0 / (1.0 + s * v["time_constant"])


def _r_delay(q, s, st, base, v):
    return np.exp(-s * v["delay"])


def _first_mode(s, wn, xi):
    return wn * wn / (s * s + 2.0 * xi * wn * s + wn * wn)


def _r_second_mode(q, s, st, base, v):
    G1 = _first_mode(s, st.omega_n, st.xi)
    G2 = _first_mode(s, SECOND_MODE_RATIO * st.omega_n, st.xi)
    # M = H·(G1 + b (G2 − 1)) keeps the DC gain and adds the second mode's participation b
    return 1.0 + v["participation"] * (G2 - 1.0) / G1


def _r_coupling(q, s, st, base, v):
    G1 = _first_mode(s, st.omega_n, st.xi)
    # tip driven through a spring k_c: w_tip/w_drive = 1/(1 + k_b(s)/k_c), k_b(s) = k_tip/G1(s)
    return 1.0 / (1.0 + v["compliance_ratio"] / G1)


def _r_series(q, s, st, base, v):
    Rs = v["resistance"]
    Z = base["Z"]
    if q == "Z":
        return 1.0 + Rs / Z              # Z + Rs
    return Z / (Z + Rs)                  # I = 1/(Z + Rs); voltage divider (actuator) / current divider (sensor)


def _r_fixture(q, s, st, base, v):
    wf = 2 * np.pi * v["frequency_hz"]
    zp = v["damping"]
    zz = zp * (1.0 - v["depth"])
    return (s * s + 2 * zz * wf * s + wf * wf) / (s * s + 2 * zp * wf * s + wf * wf)


def _P(*args, **kw):
    return EffectParameter(*args, **kw)


_MEAS = ("M", "H", "Z", "I", "S")
_LIB = [
    Effect("electrode_resistance", "distributed electrode resistance",
           "Sheet resistance of the electrodes along the length (added to the base r1'), making the "
           "strip a lossy transmission line: gain and phase fall at high frequency, more near the tip.",
           "Chen & Tan 2008; seed 002 eq. (10)-(14)", "parameter",
           (_P("r1_sheet", "Ohm", 0.0, 0.0, 2000.0, 300.0, "added electrode sheet resistance r1'"),),
           apply=_p_electrode),
    Effect("contact_resistance", "through-thickness / contact electrode resistance",
           "Resistance r2' between the electrode surface and the polymer (added to the base r2'): a "
           "series loss on every slice that lowers the gain where the polymer admittance is high.",
           "Chen & Tan 2008; seed 002 eq. (11), Fig. 11 (increasing r2 lowers the gain)", "parameter",
           (_P("r2_specific", "Ohm m^2", 0.0, 0.0, 1e-3, 5e-5, "added through-thickness resistance r2'"),),
           apply=_p_contact),
    Effect("leakage", "polymer leakage",
           "A temperature-independent (electronic) leakage conductance through the polymer, 1/Rp' "
           "added to the base's (ionic) leakage at every temperature: a resistive path in parallel with "
           "the double layers, visible at low frequency (impedance) and through the electrode line.",
           "Chen & Tan 2008; seed 002 eq. (11)", "parameter",
           (_P("conductance", "S/m^2", 0.0, 0.0, 500.0, 50.0, "added leakage conductance 1/Rp'"),),
           apply=_p_leakage),
    Effect("second_mode", "second bending mode",
           "Participation b of the second clamped-free mode at 6.27 ωn (same damping), added as "
           "H·b·(G2 − 1) so the DC gain is kept: a resonance/antiresonance above the first mode.",
           "Euler-Bernoulli modal expansion (Meirovitch, Fundamentals of Vibrations)", "response",
           (_P("participation", "1", 0.0, -1.0, 1.0, 0.3, "relative modal participation b"),),
           kinds=("actuator",), quantities=("M",), apply=_r_second_mode),
    Effect("added_fluid_mass", "added fluid mass and damping",
           "Hydrodynamic added mass μ (fraction of the modelled modal mass; negative when the model "
           "already holds more fluid mass than the strip carries, e.g. a narrower strip, since the added "
           "mass per length π ρ_f W²/4 grows faster with W than the beam's) and fluid damping ζf: "
           "ωn → ωn/√(1+μ), ξ → (ξ + ζf)/√(1+μ).",
           "Sader 1998, J. Appl. Phys. 84:64 (cantilevers in fluid)", "parameter",
           (_P("mass_ratio", "1", 0.0, -0.9, 5.0, 0.5, "added mass / modelled modal mass"),
            _P("damping_ratio", "1", 0.0, 0.0, 1.0, 0.1, "added damping ratio")),
           kinds=("actuator",), quantities=("M",), apply=_p_fluid),
    Effect("modulus_temperature", "temperature dependence of the modulus",
           "An extra log-linear slope of E with temperature, E → E·exp(c (T − T_ref)): gain and "
           "resonance move with T.", "physics.md §7; seed 000 Fig. 6, seed 001 (resonance falls with T)",
           "parameter", (_P("slope", "1/K", 0.0, -0.03, 0.03, -0.01, "extra d ln E / dT"),),
           quantities=("M", "H", "S"), needs_temperatures=True, apply=_p_modulus_T),
    Effect("diffusivity_temperature", "temperature dependence of the diffusivity",
           "An extra Arrhenius activation energy for d (and Rp by Nernst-Einstein): the charge "
           "dynamics speed up with T.", "physics.md §7 (Nafion 10.5-18 kJ/mol)", "parameter",
           (_P("activation_energy", "J/mol", 0.0, -60e3, 60e3, 20e3, "extra activation energy of d"),),
           needs_temperatures=True, apply=_p_diffusivity_T),
    Effect("permittivity_temperature", "temperature dependence of the permittivity",
           "An extra log-linear slope of κe with temperature, κe → κe·exp(c (T − T_ref)).",
           "physics.md §7 (water permittivity, Malmberg & Maryott 1956)", "parameter",
           (_P("slope", "1/K", 0.0, -0.05, 0.05, 0.015, "extra d ln κe / dT"),),
           needs_temperatures=True, apply=_p_permittivity_T),
    Effect("water_uptake", "water uptake with temperature",
           "Swelling through the thickness h → h (1 + u ΔT) with the fixed anions diluted, "
           "C⁻ → C⁻/(1 + u ΔT): stiffness, Debye length and gain change with T.",
           "Nafion water uptake (Hinatsu et al. 1994, J. Electrochem. Soc. 141:1493)", "parameter",
           (_P("swelling", "1/K", 0.0, -0.008, 0.008, 0.004, "relative thickness change per kelvin"),),
           needs_temperatures=True, apply=_p_water_uptake),
    Effect("amplifier_bandwidth", "measurement-amplifier bandwidth",
           "A first-order pole 1/(1 + s τa) of the measuring amplifier (transimpedance or "
           "displacement sensor); independent of temperature.", "seed 000 Fig. 4 (op-amp chain)",
           "response", (_P("time_constant", "s", 0.0, 0.0, 0.05, 1.5e-3, "τa = 1/ωa"),),
           quantities=_MEAS, apply=_r_amplifier),
    Effect("time_delay", "acquisition time delay",
           "A pure delay e^{-sτ} between excitation and acquisition channels: phase −ωτ, magnitude "
           "unchanged.", "Pintelon & Schoukens, System Identification (2012), ch. 2", "response",
           (_P("delay", "s", 0.0, 0.0, 0.05, 1e-3, "delay τ"),), quantities=_MEAS, apply=_r_delay),
    Effect("series_resistance", "lumped series resistance",
           "A lumped resistance Rs in series with the strip (leads, clamp contacts, source/amplifier "
           "input resistance): divider Z/(Z + Rs) on the driven or measured signal.",
           "standard equivalent-circuit practice (Barsoukov & Macdonald, Impedance Spectroscopy)",
           "response", (_P("resistance", "Ohm", 0.0, 0.0, 1e4, 20.0, "series resistance Rs"),),
           quantities=_MEAS, apply=_r_series),
    Effect("coupling_compliance", "excitation-coupling compliance",
           "The imposed tip displacement is applied through a spring: w_tip/w_drive = "
           "1/(1 + ε/G1(s)), ε = tip stiffness / coupling stiffness.", "seed 000 §III (imposed tip "
           "displacement)", "response",
           (_P("compliance_ratio", "1", 0.0, 0.0, 5.0, 0.2, "ε = k_tip/k_coupling"),),
           kinds=("sensor",), quantities=("S",), apply=_r_coupling),
    Effect("constant_phase_element", "constant-phase electrode element",
           "Anomalous (fractional, order β) charge relaxation at the electrodes: every s of the "
           "transport sub-model becomes ω_c (s/ω_c)^β, a constant-phase double layer "
           "(see module docstring).", "Macdonald (Impedance Spectroscopy); Evangelista & Lenzi, "
           "fractional PNP models", "kernel",
           (_P("beta", "1", 1.0, 0.5, 1.0, 0.85, "CPE exponent β"),), quantities=_MEAS),
]

#: The candidate library, by name.
LIBRARY: dict[str, Effect] = {e.name: e for e in _LIB}

#: Effects kept OUT of the candidate list: used by the blind generator only.
OUT_OF_LIBRARY: dict[str, Effect] = {
    "fixture_resonance": Effect(
        "fixture_resonance", "fixture resonance (out of library)",
        "A notch/resonance of the test fixture: (s² + 2ζz ωf s + ωf²)/(s² + 2ζ ωf s + ωf²), "
        "ζz = ζ (1 − depth).", "generator only", "response",
        (_P("frequency_hz", "Hz", 1.0, 0.01, 1e4, 5.0, "fixture resonance"),
         _P("depth", "1", 0.0, 0.0, 1.0, 0.6, "notch depth (0 off)"),
         _P("damping", "1", 0.05, 0.001, 1.0, 0.05, "damping ratio of the fixture")),
        quantities=_MEAS, apply=_r_fixture),
}

ALL_EFFECTS = {**LIBRARY, **OUT_OF_LIBRARY}


def get_effect(name: str) -> Effect:
    """The effect called ``name`` (library or out-of-library)."""
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


def _is_off(eff: Effect, vals: Mapping[str, float]) -> bool:
    if eff.name == "fixture_resonance":
        return vals["depth"] == 0.0
    return all(vals[p.name] == p.off for p in eff.parameters)


def split_values(values: Mapping[str, float]) -> tuple[dict, dict]:
    """Split ``{"alpha0": .., "time_delay.delay": ..}`` into base-parameter and effect dicts.

    Base names are IPMCParameters fields, ``omega_n`` or ``laws.<quantity>.<attribute>``
    (see :func:`physmodel.estimation.calibration.apply_values`)."""
    base, eff = {}, {}
    for k, v in values.items():
        if "." in k and not k.startswith("laws."):
            e, p = k.split(".", 1)
            eff.setdefault(e, {})[p] = float(v)
        else:
            base[k] = float(v)
    return base, eff


# --------------------------------------------------------------------------- the model
def _apply(p: IPMCParameters, base_vals: Mapping[str, float]) -> IPMCParameters:
    if not base_vals:
        return p
    from ..parameter_paths import apply_values

    return apply_values(p, base_vals)


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
        self._active = [(get_effect(n), v) for n, v in self.effects.items() if not _is_off(get_effect(n), v)]

    def state(self, temperature_c) -> State:
        st = super().state(temperature_c)
        acts = [(e, v) for e, v in self._active if e.level == "parameter"]
        if not acts:
            return st
        d = {k: np.array(getattr(st, k), dtype=float) for k in STATE_FIELDS}
        T_ref = np.array([p.T_ref for p in self.params], dtype=float)[:, None, None]
        for e, v in acts:
            d = e.apply(d, T_ref, v)
        d["K"] = FARADAY**2 * d["d"] * d["C_minus"] / (d["kappa_e"] * R_GAS * d["T"])
        d["omega_n"] = first_mode_omega(d["E"], d["rho"], d["L"], d["h"])
        return State(**d)

    def frequency_response(self, frequency_hz, temperature_c, quantities=None, out=None,
                           progress=None) -> FrequencyResponse:
        """Like the base model's, with every effect applied.  ``out`` is filled if given."""
        qs = self._check_quantities(quantities or self.quantities)
        f = check_frequencies(frequency_hz)
        T = np.atleast_1d(np.asarray(temperature_c, dtype=float))
        s = 2j * np.pi * f
        st = self.state(T)
        resp = [(e, v) for e, v in self._active if e.level == "response"]
        need = set(qs)
        if any(e.name == "series_resistance" for e, _ in resp):
            need.add("Z")
        need = tuple(q for q in self.quantities if q in need)
        cpe = next((v for e, v in self._active if e.level == "kernel"), None)
        if cpe is None:
            vals = evaluate_grid(st, s, self._kernel, need, self.chunk_size, None, progress)
        else:
            beta = cpe["beta"]
            wc = 2 * np.pi * CPE_REFERENCE_HZ
            s_hat = wc * (s / wc) ** beta              # principal power: arg = β·π/2
            electrical = tuple(q for q in need if q not in ("G", "M"))
            if "M" in need and "H" not in electrical:
                electrical = electrical + ("H",)
            vals = evaluate_grid(st, s_hat, self._kernel, electrical, self.chunk_size, None, progress)
            if "G" in need or "M" in need:
                G = _first_mode(s[None, None, :], st.omega_n, st.xi)
                if "G" in need:
                    vals["G"] = G
                if "M" in need:
                    vals["M"] = vals["H"] * G
        base = dict(vals)
        for q in qs:
            fac = [e.apply(q, s[None, None, :], st, base, ev) for e, ev in resp if q in e.quantities]
            if fac:
                v = vals[q].copy()
                for x in fac:
                    v *= x
                vals[q] = v
        res = {}
        for q in qs:
            if out is not None and q in out:
                out[q][...] = vals[q]
                res[q] = out[q]
            else:
                res[q] = np.asarray(vals[q], dtype=complex)
        return FrequencyResponse(
            frequency_hz=f, temperature_c=T, parameter_sets=tuple(p.name for p in self.params),
            values=res, units={q: self.units[q] for q in qs},
            descriptions={q: self.descriptions[q] for q in qs},
        )

    def evaluate(self, *a, **k):  # pragma: no cover - guard
        raise IPMCError("EffectModel evaluates on the imaginary axis only; use frequency_response()")

    def with_values(self, values: Mapping[str, float]) -> "_EffectMixin":
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
        parameter set of this model as the base.
        """
        from ..data.sweep import sweep_layout

        lay = sweep_layout(data, self.kind, quantity or DEFAULT_QUANTITY[self.kind])
        q, scale, freqs, fi, temps, ti = (lay.quantity, lay.factor, lay.frequencies_hz, lay.f_index,
                                          lay.temperatures_c, lay.t_index)

        def predict(values: Mapping[str, float]) -> np.ndarray:
            m = self.with_values(values) if values else self
            r = m.frequency_response(freqs, temps, quantities=(q,))[q][0]
            return r[ti, fi] * scale

        def predict_many(values_list: Sequence[Mapping[str, float]]) -> np.ndarray:
            # one batched model call per distinct set of effect values (base values vary freely)
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
                plist = [_apply(self.params[0], b) for _, b, _ in items]
                m = make_effect_model(plist, self.kind, effects, **self._extra())
                r = m.frequency_response(freqs, temps, quantities=(q,))[q]
                for k, (i, _, _) in enumerate(items):
                    out[i] = r[k][ti, fi] * scale
            return out

        predict.many = predict_many
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
           "LIBRARY", "OUT_OF_LIBRARY", "ALL_EFFECTS", "get_effect", "candidates_for", "normalize_effects",
           "split_values", "CPE_REFERENCE_HZ", "SECOND_MODE_RATIO", "DEFAULT_QUANTITY"]
