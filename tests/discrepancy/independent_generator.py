"""Blind test cases from an independently written IPMC actuator (issue 11; discrepancy.md §5).

The physics lives in :mod:`independent_physics` (no ``physmodel`` import); this module draws cases:
a hidden effect (or none, two, or one the library does not hold) with a random size, a base strip
drawn ±30–40 % away from the user's starting set, 0.5–2 % noise with a per-line σ, 5 temperatures
19–55 °C and 0.05–50 Hz.  The only ``physmodel`` import is the output record ``FrequencySweep``.

    sweep, truth = make_case(7, "contact_resistance")
    cases = case_grid(n_per_label=2)                 # [(sweep, truth), ...]

``truth`` holds the label, the drawn effect parameters, the library names the workflow should
report (``expected``), the base and starting sets (also as ``physmodel.IPMCParameters`` fields via
:func:`library_fields`) and the detectability λ: the weighted squared distance between the noiseless
data with and without the hidden effect (``lam``) and the same after refitting the perturbed base
parameters with this module's own model (``lam_baseline``: what a baseline cannot absorb).
Seeds are combined with :data:`SEALED`, which the workflow never sees.

Ranges and their sources are in :data:`EFFECT_SPECS` (see also the report for issue 11).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from physmodel.data.sweep import FrequencySweep

try:                                      # imported as tests/discrepancy/independent_generator
    from . import independent_physics as ip
except ImportError:                       # imported with tests/discrepancy on sys.path
    import independent_physics as ip

#: Sealed seed root of this generator (differs from the library generator's).
SEALED = 0x1D_6E_2011
FREQUENCIES_HZ = np.logspace(math.log10(0.05), math.log10(50.0), 31)
TEMPERATURES_C = (19.0, 28.0, 37.0, 46.0, 55.0)
#: Base parameters drawn away from the starting set (the ones the benchmark's baseline frees).
PERTURBED = ("alpha", "d", "zeta", "f1")
PERTURBATION = (0.30, 0.40)
NOISE_RANGE = (0.005, 0.02)
T0_C = 25.0

#: Seed 002 Table 3 (fitted) actuator, transcribed from the paper: L = 15 mm, W = 4 mm, 0.25 mm
#: thick, T = 300 K, E = 154 MPa, ωn = 75.4 rad/s, ξ = 0.18, Rp' = 0.37 Ω·m², d = 3.07e-11 m²/s,
#: C⁻ = 941.94 mol/m³, κe = 4.47e-7 F/m, r2' = 8.81e-6, r1' = 56.44 Ω, α0 = −155.  The paper's
#: mode is ωn/(s² + …) (DC gain 1/ωn); with a unit-DC-gain mode the printed α0 becomes α0/ωn
#: [J/C], which gives its few-mm/V DC gain.  Laws: physics.md §7 defaults (Ea 15 kJ/mol,
#: −0.75 %/K log-linear modulus, κe ∝ water permittivity, leakage ∝ d/T).
START_SEED002 = dict(
    L=15e-3, W=4e-3, h=0.125e-3, d=3.07e-11, C=941.94, eps=4.47e-7, alpha=-155.0 / 75.4,
    r1s=56.44, r2s=8.81e-6, Gp=1.0 / 0.37, E=154e6, f1=75.4 / (2 * math.pi), zeta=0.18, T0_c=300.0 - ip.T_ZERO,
    thermal=True, Q10_d=ip.q10_from_ea(15e3, 300.0 - ip.T_ZERO), E_logslope=-0.0075, eps_water=True,
)

# name -> (library label or None for out-of-library, {param: (draw, lo, hi)}, {param: off value})
# draws at quantile q: "log" lo·(hi/lo)^q, "lin" lo + q(hi − lo), "sym" random sign × lin magnitude,
# "symlog" a log factor or its inverse, "fix" constant lo.  Ranges run from a small (often
# undetectable) effect at q = 0 to the largest physical one at q = 1 (hence lo > hi in places).
EFFECT_SPECS: dict[str, tuple] = {
    # +1…2000 Ω sheet resistance: fresh Pt electrodes are a few Ω/sq, cracking under strain and
    # drying raise it by one to two orders (Shahinpoor & Kim 2000, Smart Mater. Struct. 9:543).
    "electrode_resistance": ("electrode_resistance", {"extra_sheet_ohm": ("log", 1.0, 2000.0)},
                             {"extra_sheet_ohm": 0.0}),
    # +1e-5…1e-2 Ω·m²: from the seed-002 fit (8.8e-6) to ~4× the polymer's own area resistance
    # 2h/(κe K) ≈ 2.4e-3 Ω·m² (seed 002), the range the independent simulator used.
    "contact_resistance": ("contact_resistance", {"extra_area_resistance": ("log", 1e-5, 1e-2)},
                           {"extra_area_resistance": 0.0}),
    # +0.3…300 S/m²: 0.1× to 100× seed 002's 1/Rp' = 2.7 S/m², up to the polymer's ionic
    # conductance per area κe K/(2h) ≈ 420 S/m²; electronic (Pt) path, resistance +0.39 %/K.
    "leakage": ("leakage", {"conductance": ("log", 0.3, 300.0)}, {"conductance": 0.0}),
    # Euler-Bernoulli modal sum (6 modes + static residual), Rayleigh damping share of the fluid.
    "second_mode": ("second_mode", {"n_modes": ("fix", 6, 6), "viscous_share": ("lin", 0.5, 1.0)},
                    {"n_modes": 1, "viscous_share": 1.0}),
    # Extra fluid load: inviscid mass ratio and Reynolds number at ω1 (Sader 1998 Γ_circ); the
    # library's viscous_fluid (its own Γ_rect, fluid density and viscosity parametrisation).
    "added_fluid_mass": ("viscous_fluid", {"mass_ratio": ("log", 0.01, 1.0), "reynolds": ("log", 300.0, 3.0)},
                         {"mass_ratio": 0.0, "reynolds": 30.0}),
    "modulus_temperature": ("modulus_temperature", {"linear_coeff": ("sym", 3e-4, 0.012)}, {"linear_coeff": 0.0}),
    "diffusivity_temperature": ("diffusivity_temperature", {"q10": ("symlog", 1.01, 1.6)}, {"q10": 1.0}),
    "permittivity_temperature": ("permittivity_temperature", {"linear_coeff": ("sym", 5e-4, 0.02)},
                                 {"linear_coeff": 0.0}),
    # Nafion in liquid water holds φ ≈ 0.3-0.4 water by volume; uptake rises with T
    # (Hinatsu et al. 1994, J. Electrochem. Soc. 141:1493).
    "water_uptake": ("water_uptake", {"phi0": ("lin", 0.3, 0.4), "dphi_dT": ("log", 1e-4, 0.005)},
                     {"phi0": 0.35, "dphi_dT": 0.0}),
    "amplifier_bandwidth": ("amplifier_bandwidth", {"f_dominant_hz": ("log", 5000.0, 15.0),
                                                    "pole_ratio": ("lin", 3.0, 10.0)},
                            {"f_dominant_hz": math.inf, "pole_ratio": 5.0}),
    "time_delay": ("time_delay", {"skew_s": ("log", 1e-5, 5e-3), "dac_period_s": ("log", 1e-5, 1e-3)},
                   {"skew_s": 0.0, "dac_period_s": 0.0}),
    "series_resistance": ("series_resistance", {"resistance": ("log", 0.5, 200.0)}, {"resistance": 0.0}),
    # The library's fractional_transport mechanism with a free reference frequency.
    "fractional_transport": ("fractional_transport", {"beta": ("lin", 0.995, 0.7), "f_ref_hz": ("log", 1.0, 30.0)},
                             {"beta": 1.0, "f_ref_hz": 10.0}),
    # Interface CPE in series, Q = q_area·W·L; n 0.95-0.6 (rough/porous metal electrodes, CPE
    # exponent n = 1/(D − 1) for fractal dimension D), q_area 2000-2 F s^(n−1)/m² around the
    # strip's own double layer κe/(2λ) ≈ 20 F/m² (seed 002); the library's series_cpe.
    "series_cpe": ("series_cpe", {"n": ("lin", 0.95, 0.6), "q_area": ("log", 2000.0, 2.0)},
                   {"n": 0.8, "q_area": math.inf}),
    # out of library
    "fixture_resonance": (None, {"f_hz": ("log", 1.0, 40.0), "kappa": ("sym", 0.005, 0.5), "zeta": ("lin", 0.02, 0.15)},
                          {"f_hz": 10.0, "kappa": 0.0, "zeta": 0.05}),
    "gain_ripple": (None, {"amplitude": ("log", 0.002, 0.08), "period_decades": ("lin", 0.3, 1.0),
                           "phase": ("lin", 0.0, 2 * math.pi)}, {"amplitude": 0.0, "period_decades": 0.5, "phase": 0.0}),
    "viscoelastic_creep": (None, {"delta": ("log", 0.01, 0.4), "tau_s": ("log", 0.3, 10.0), "a": ("lin", 0.5, 1.0)},
                           {"delta": 0.0, "tau_s": 1.0, "a": 1.0}),
}
#: Effects in their physical form (issue 27): drawn only when asked for by name, so the labels and
#: seeds of the earlier sets (LABELS) stay as they were.
PHYSICAL_FORM_SPECS: dict[str, tuple] = {
    # Interface CPE in every slice of the electrode line (de Levie's line with a CPE wall), the
    # same q_area and n ranges as the series CPE above; the library's distributed_cpe.
    "distributed_cpe": ("distributed_cpe", {"n": ("lin", 0.95, 0.6), "q_area": ("log", 2000.0, 2.0)},
                        {"n": 0.8, "q_area": math.inf}),
    # Modes 2..8 of the cantilever with one modal damping ratio of their own (water-loaded higher
    # modes of a cm-size strip: ζ 0.01-0.2), not Rayleigh damping tied to ζ1; the library's higher_modes.
    "bending_modes": ("higher_modes", {"n_modes": ("fix", 8, 8), "zeta_higher": ("log", 0.2, 0.01)},
                      {"n_modes": 1, "zeta_higher": 0.05}),
}
IN_LIBRARY = tuple(k for k, v in EFFECT_SPECS.items() if v[0] is not None)
OUT_OF_LIBRARY = tuple(k for k, v in EFFECT_SPECS.items() if v[0] is None)
EFFECT_SPECS.update(PHYSICAL_FORM_SPECS)
#: Effects that need data at several temperatures (always the case here).
THERMAL_EFFECTS = ("modulus_temperature", "diffusivity_temperature", "permittivity_temperature", "water_uptake")
#: Two-effect cases named by issue 11, plus contact resistance with a mechanical/measurement effect.
PAIRS = ("modulus_temperature+diffusivity_temperature", "contact_resistance+time_delay",
         "contact_resistance+second_mode", "contact_resistance+leakage", "time_delay+leakage")
LABELS = ("none",) + IN_LIBRARY + OUT_OF_LIBRARY + PAIRS


def off_values(name: str) -> dict:
    """The parameter values at which effect ``name`` vanishes."""
    return dict(EFFECT_SPECS[name][2])


def draw_effect(name: str, rng: np.random.Generator, size: float | None = None) -> dict:
    """Parameters of effect ``name``; ``size`` ∈ [0, 1] is the quantile of every range (random if None)."""
    if name not in EFFECT_SPECS:
        raise ValueError(f"unknown effect {name!r}; expected one of {sorted(EFFECT_SPECS)}")
    out = {}
    for k, (kind, lo, hi) in EFFECT_SPECS[name][1].items():
        q = rng.uniform() if size is None else float(size)
        if not 0.0 <= q <= 1.0:
            raise ValueError(f"size={size!r} must lie in [0, 1]")
        if kind == "fix":
            out[k] = lo
        elif kind == "log":
            out[k] = lo * (hi / lo) ** q
        elif kind == "lin":
            out[k] = lo + q * (hi - lo)
        elif kind == "sym":
            out[k] = (lo + q * (hi - lo)) * (1 if rng.uniform() < 0.5 else -1)
        elif kind == "symlog":
            out[k] = (lo * (hi / lo) ** q) ** (1 if rng.uniform() < 0.5 else -1)
    return out


def _at_reference(start: dict, t0_c: float, thermal: bool) -> dict:
    """The starting set re-expressed at the reference temperature ``t0_c`` (same laws)."""
    b = dict(start)
    if thermal and start.get("thermal", False):
        st = ip.base_state(start, [t0_c])
        for k in ("d", "E", "eps", "Gp", "f1"):
            b[k] = float(st[k][0, 0])
        b["Q10_d"] = ip.q10_from_ea(ip.ea_from_q10(start["Q10_d"], start["T0_c"]), t0_c)
    b["T0_c"] = t0_c
    b["thermal"] = bool(thermal and start.get("thermal", False))
    return b


def draw_base(start: dict, rng: np.random.Generator, perturbed=PERTURBED, thermal: bool = True) -> dict:
    """A base strip: the starting set at 25 °C with each ``perturbed`` value × (1 ± U[0.30, 0.40])."""
    b = _at_reference(start, T0_C, thermal)
    for k in perturbed:
        if k not in b:
            raise ValueError(f"cannot perturb {k!r}; base keys are {sorted(b)}")
        u = rng.uniform(*PERTURBATION)
        b[k] = b[k] * (1 + u if rng.uniform() < 0.5 else 1 - u)
    return b


def library_fields(base: dict) -> dict:
    """``base`` as ``physmodel.IPMCParameters.from_dict`` input (SI, T_ref = T0), laws included."""
    lam1 = ip.cantilever_roots(1)[0]
    w1 = 2 * math.pi * base["f1"]
    rho = base["E"] * base["h"] ** 2 / 3.0 * (lam1**2 / (base["L"] ** 2 * w1)) ** 2
    const = {"law": "Constant"}
    laws = {k: dict(const) for k in ("d", "E", "kappa_e", "Rp_specific", "r1_sheet", "r2_specific", "C_minus", "h")}
    if base.get("thermal", False):
        laws["d"] = {"law": "Arrhenius", "activation_energy": float(ip.ea_from_q10(base["Q10_d"], base["T0_c"]))}
        laws["E"] = {"law": "LogLinear", "slope": float(base["E_logslope"])}
        laws["kappa_e"] = {"law": "WaterPermittivity"} if base.get("eps_water", True) else dict(const)
        laws["Rp_specific"] = {"law": "IonicResistance"}
    return dict(L=base["L"], W=base["W"], h=base["h"], d=base["d"], C_minus=base["C"], kappa_e=base["eps"],
                alpha0=base["alpha"], a0=0.0, r1_sheet=base["r1s"], r2_specific=base["r2s"],
                Rp_specific=(1.0 / base["Gp"] if base["Gp"] > 0 else math.inf), E=base["E"], rho=rho,
                xi=base["zeta"], T_ref=base["T0_c"] + ip.T_ZERO, laws=laws,
                name="independent_truth", source="tests/discrepancy/independent_generator.py")


def _response(base, effects, f, T):
    return ip.actuator_response(base, f, T, effects)["M"].reshape(-1)


def noncentrality(H1, H0, sig) -> float:
    """Σ over lines of (ln|H1/H0|² + arg(H1/H0)²)/σ², σ the per-line log-magnitude/phase std [Np, rad]."""
    r = np.log(np.asarray(H1) / np.asarray(H0))
    return float(np.sum((r.real / sig) ** 2 + (r.imag / sig) ** 2))


def baseline_noncentrality(H1, base, effects, f, T, sig, free=PERTURBED) -> float:
    """λ after refitting the ``free`` base parameters (log scale, sign kept) to the noiseless data
    ``H1`` with ``effects`` (the others of a pair) held at their true values, by this module's model."""
    x0 = np.array([math.log(abs(base[k])) for k in free])
    sgn = {k: math.copysign(1.0, base[k]) for k in free}

    def res(x):
        b = dict(base)
        for k, v in zip(free, x):
            b[k] = sgn[k] * math.exp(v)
        r = np.log(H1 / _response(b, effects, f, T)) / sig
        return np.concatenate([r.real, r.imag])

    with np.errstate(all="ignore"):
        fit = least_squares(res, x0, method="lm", x_scale=1.0, xtol=1e-10, ftol=1e-10, max_nfev=400)
    return float(np.sum(fit.fun**2))


def _parse(label: str) -> list[str]:
    if label == "none":
        return []
    names = label.split("+")
    bad = [n for n in names if n not in EFFECT_SPECS]
    if bad or len(set(names)) != len(names):
        raise ValueError(f"label {label!r}: expected 'none', an effect of {sorted(EFFECT_SPECS)} or 'a+b'")
    return names


def make_case(seed: int, label: str, *, start: dict = START_SEED002, thermal: bool = True,
              frequencies_hz=FREQUENCIES_HZ, temperatures_c=TEMPERATURES_C, perturbed=PERTURBED,
              size: float | None = None, sigma_rel: float | None = None, baseline_lambda: bool = True,
              workflow_free: tuple | None = None):
    """One blind case: ``(FrequencySweep in mm/V with per-line σ, truth dict)``.

    ``label``: "none", an effect name of :data:`EFFECT_SPECS`, or "a+b".  ``thermal``: the base
    follows the starting set's temperature laws (else every parameter is constant: give the workflow
    isothermal laws too).  ``size``: quantile of the effect ranges (random if None).
    ``sigma_rel``: relative noise (drawn from 0.5-2 % if None).  ``workflow_free``: base keys the
    workflow frees (e.g. ``("alpha", "d", "eps", "zeta", "f1")``); if given, ``lam_workflow`` (and
    ``lam_each_workflow`` for a pair) is λ after refitting those instead of the perturbed ones.
    """
    names = _parse(label)
    r_base, r_eff, r_noise = (np.random.default_rng(s) for s in np.random.SeedSequence([SEALED, int(seed)]).spawn(3))
    base = draw_base(start, r_base, perturbed, thermal)
    effects = {n: draw_effect(n, r_eff, size) for n in names}
    f = np.asarray(frequencies_hz, dtype=float)
    T = np.asarray(temperatures_c, dtype=float)
    H0 = _response(base, {}, f, T)
    H1 = _response(base, effects, f, T) if effects else H0
    sig_rel = r_noise.uniform(*NOISE_RANGE) if sigma_rel is None else float(sigma_rel)
    floor = r_noise.uniform(0.0, 1.0) * sig_rel * np.min(np.abs(H1))      # displacement noise floor [m/V]
    sigma = np.sqrt(sig_rel**2 + (floor / np.abs(H1)) ** 2)               # per-line relative σ
    sig = sigma / math.sqrt(2.0)                                          # per-line ln|H| and phase σ
    noisy = H1 + np.abs(H1) * sig * (r_noise.standard_normal(H1.size) + 1j * r_noise.standard_normal(H1.size))
    Tl = np.repeat(T, f.size)
    fl = np.tile(f, T.size)
    sweep = FrequencySweep(Tl, fl, noisy * 1e3, 20.0 / math.log(10.0) * sig, np.degrees(sig),
                           "voltage", "V", "tip_displacement", "mm",
                           {"source": "independent generator (tests/discrepancy), blind case"})
    expected = sorted(EFFECT_SPECS[n][0] for n in names if EFFECT_SPECS[n][0] is not None)
    truth = {
        "seed": int(seed), "label": label, "effects": effects, "expected": expected,
        "out_of_library": any(EFFECT_SPECS[n][0] is None for n in names),
        "thermal": bool(thermal), "perturbed": tuple(perturbed), "base": base,
        "library_base": library_fields(base), "library_start": library_fields(_at_reference(start, start["T0_c"], thermal)),
        "noise": {"sigma_rel": sig_rel, "floor_m_per_V": float(floor)},
        "lam": noncentrality(H1, H0, sig) if effects else 0.0,
        "lam_each": {}, "lam_baseline": None, "lam_each_baseline": {}, "lam_workflow": None, "lam_each_workflow": {},
    }
    for n in names if len(names) > 1 else []:
        rest = {k: v for k, v in effects.items() if k != n}
        truth["lam_each"][n] = noncentrality(H1, _response(base, rest, f, T), sig)
        if baseline_lambda:
            truth["lam_each_baseline"][n] = baseline_noncentrality(H1, base, rest, f, T, sig, perturbed)
    if baseline_lambda:
        truth["lam_baseline"] = baseline_noncentrality(H1, base, {}, f, T, sig, perturbed) if effects else 0.0
    if workflow_free is not None:
        truth["lam_workflow"] = baseline_noncentrality(H1, base, {}, f, T, sig, workflow_free) if effects else 0.0
        for n in names if len(names) > 1 else []:
            rest = {k: v for k, v in effects.items() if k != n}
            truth["lam_each_workflow"][n] = baseline_noncentrality(H1, base, rest, f, T, sig, workflow_free)
    return sweep, truth


def case_grid(labels=LABELS, n_per_label: int = 1, first_seed: int = 0, **kw) -> list:
    """``[(sweep, truth), ...]`` for every label × ``n_per_label``, seeds first_seed, first_seed + 1, …"""
    out, seed = [], int(first_seed)
    for lab in labels:
        for _ in range(n_per_label):
            out.append(make_case(seed, lab, **kw))
            seed += 1
    return out


__all__ = ["make_case", "case_grid", "PHYSICAL_FORM_SPECS", "draw_effect", "draw_base", "off_values", "library_fields", "noncentrality",
           "baseline_noncentrality", "EFFECT_SPECS", "IN_LIBRARY", "OUT_OF_LIBRARY", "PAIRS", "LABELS",
           "START_SEED002", "SEALED", "FREQUENCIES_HZ", "TEMPERATURES_C", "PERTURBED"]
