"""An independently written IPMC displacement sensor with a hidden measurement-chain element (issue 16).

Written without ``physmodel`` (the only import is the output record ``FrequencySweep``): the strip,
the chain elements and their parametrisation are this module's own, so data made with it test the
discrepancy workflow against code it was not built from.

Strip (Chen et al. 2007 boundary-charge sensing, short-circuited; seed 000's set-up)
------------------------------------------------------------------------------------
A tip deflection w of a cantilever (static shape) stresses the surfaces x = ±h by
σ(z) = 3 E h w (L − z)/L³.  A boundary charge density a0 σ there, redistributed by the linearised
PNP with short-circuited faces (γ = h sqrt((s + K)/d), K = F² d C/(ε R T)), puts a charge per area
a0 σ h q(γ) on the electrodes, q(γ) = (γ − tanh γ)/(γ² tanh γ); per length the slice is a current
source s W a0 σ h q(γ) in parallel with the polymer's own admittance y_p (electrode to electrode)
and behind the two through-thickness resistances 2 r2 (r2 = r2'/W), so the part 1/(1 + 2 r2 y_p)
reaches the electrodes.  The electrodes (r1 = r1'/W each) collect it with the line weight
cosh(x(L − z)/L)/cosh x (reciprocal to the actuator's voltage profile; x = L sqrt(2 r1 y), y the
slice admittance with leakage), so with ∫0^1 (1 − ξ) cosh(x(1 − ξ))/cosh x dξ = X(x):

    G(s) = I/w = s W a0 (3 E h²/L) q(γ) X(x)/(1 + 2 r2 y_p)          [A/m]

(the polymer admittance y_p, Z, X come from :mod:`independent_physics`, which re-derives them).

Chain elements (own parametrisation), each a factor on G:
``amplifier``     1/((1 + s/ωa)(1 + s/(ρ ωa))): dominant corner f_a [Hz], pole ratio ρ
``delay``         e^{-sτ}, skew τ [s]
``laser``         a laser with bandwidth f_l [Hz] reads D/(1 + s/ω_l): G gains the lead 1 + s/ω_l
``ac_coupling``   s/(s + ωc), corner f_c [Hz]
``joint``         cup → tip through a spring-damper: (1 + 2ζ s/ωj)/(1 + 2ζ s/ωj + s²/ωj²), f_j [Hz]
``slit_beam``     the strip clamped at 0 and pinned at the tip (driven), its own inertia: the tip
                  slope per tip displacement from the 4×4 boundary-value problem of
                  EI w'''' = −m̃ (s² + 2ζ ω s) w solved per frequency (numpy.linalg.solve), over its
                  static value 3/(2L); first clamped-pinned frequency f_cp [Hz], damping ζ
``mount``         (issue 27) the wood piece on a joint to the cup, damped by the water around it:
                  k/(m s² + c s + k), resonance f_m [Hz], damping ratio ζ (no zero: the damping is not the joint's)
``opamp``         seed 000's two inverting stages (R1 470 kΩ, R2 = R3 10 kΩ) with single-pole
                  op-amps (GBW, A0) and the strip's impedance Z as source: the node equations solved
                  per frequency, over the ideal gain
out of library:   ``gain_ripple`` (a sinusoidal ripple of ln|G| and ∠G in log f) and ``notch``
                  ((s² + 2ζ(1 − depth) ωn s + ωn²)/(s² + 2ζ ωn s + ωn²)).

Bath temperature (issue 27 item 3: a bath step as the next measurement)
-----------------------------------------------------------------------
The records of :func:`make_case` are at the strip's own temperature ``base["T"]`` (35 °C); given
``temperature_c``, :func:`response` and :func:`strip_sensor` move the strip there with laws
written here (physics.md §7's defaults, the ones the actuator generator's thermal base uses, each
factor over its value at ``base["T"]``):

* diffusivity, Arrhenius with :data:`EA_D` = 15 kJ/mol: d ∝ exp(−Ea/R (1/T − 1/T0));
* permittivity ∝ that of water, Owen, Miller, Milner & Cogan (1961) (``independent_physics``;
  the library uses Malmberg & Maryott 1956, 0.1–0.2 % apart over 5–65 °C);
* modulus, log-linear :data:`E_LOGSLOPE` = −0.75 %/K (the stress per tip displacement ∝ E);
* leakage conductance Gp by Nernst–Einstein (∝ d/T), and T itself in K = F² d C/(ε R T);
* electrode sheet and through-thickness resistances, C and a0: constant (as the user's laws).

These are this module's own code but the library's law FORMS and CONSTANTS (only the water
permittivity fit differs): a bath step checked with them measures the search on the premise that
the user's temperature laws are right.  ``laws={"ea_d": ..., "e_logslope": ...}``
(:func:`law_constants`) gives the strip other constants (a strip the user's laws misdescribe);
left out, the module's constants are used and every record is as before, bit for bit.

Z follows through d, ε, Gp and T, so the ``opamp`` element (the strip as its source) changes with
the bath while the other chain elements do not.  At ``base["T"]`` every factor is exactly 1 and the
default path (``temperature_c=None``) is the module as it was: earlier sets stay bit-identical.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from physmodel.data.sweep import FrequencySweep

try:
    from . import independent_physics as ip
except ImportError:
    import independent_physics as ip

SEALED = 0x5E_45_0016
FREQUENCIES_HZ = np.logspace(1.0, 2.0, 31)
TEMPERATURE_C = 35.0
NOISE_RANGE = (0.005, 0.02)
PERTURBED = ("a0", "d", "eps")
#: seed 000 strip (18 × 6.5 × 0.21 mm, Sec. II-A) with development values of the polymer
#: (d 4e-11 m²/s, κe 1.3e-6 F/m, C 1091 mol/m³, E 0.3 GPa, r1' 10 Ω, r2' 1e-5 Ω·m², Rp' 0.5 Ω·m²,
#: a0 0.3 C/J), transcribed here.
START = dict(L=18e-3, W=6.5e-3, h=0.105e-3, d=4e-11, C=1091.0, eps=1.3e-6, a0=0.3, r1s=10.0, r2s=1e-5,
             Gp=2.0, E=3e8, T=TEMPERATURE_C + ip.T_ZERO)
R1, R2, R3, A0 = 470e3, 10e3, 10e3, 2e5
LAMBDA_CP = 3.926602312047919          # first root of tan λ = tanh λ (brentq check in the benchmark)
#: Temperature laws of the strip (module doc, "Bath temperature"): diffusivity activation energy
#: [J/mol] and the modulus's log-linear slope [1/K] (physics.md §7 defaults).
EA_D = 15e3
E_LOGSLOPE = -0.0075

# name -> (library name or None, {param: (draw, lo, hi)}); "log": lo·(hi/lo)^q, "lin": lo + q(hi − lo)
EFFECT_SPECS = {
    "amplifier": ("amplifier_bandwidth", {"f_a": ("log", 3000.0, 150.0), "ratio": ("lin", 3.0, 10.0)}),
    "delay": ("time_delay", {"tau": ("log", 2e-5, 3e-3)}),
    "laser": ("laser_lag", {"f_l": ("log", 3000.0, 180.0)}),
    "ac_coupling": ("ac_coupling", {"f_c": ("log", 0.3, 20.0)}),
    "joint": ("fixture_joint", {"f_j": ("log", 1500.0, 150.0), "zeta": ("lin", 0.05, 0.3)}),
    "slit_beam": ("tip_driven_beam", {"f_cp": ("log", 400.0, 45.0), "zeta": ("lin", 0.05, 0.3)}),
    "opamp": ("transimpedance", {"gbw": ("log", 3e7, 5e5)}),
    "gain_ripple": (None, {"amp": ("log", 0.02, 0.1), "period": ("lin", 0.3, 0.6), "phase": ("lin", 0.0, 6.28)}),
    "notch": (None, {"f_n": ("log", 25.0, 70.0), "depth": ("lin", 0.3, 0.8), "zeta": ("lin", 0.03, 0.1)}),
}
IN_LIBRARY = tuple(k for k, v in EFFECT_SPECS.items() if v[0] is not None)
OUT_OF_LIBRARY = tuple(k for k, v in EFFECT_SPECS.items() if v[0] is None)
#: Added for issue 27 (drawn only by name, so IN_LIBRARY and the earlier sets' seeds stay as they were):
#: ``mount`` the wood piece (mass m) on a joint of stiffness k to the cup, damped by the water around it
#: (not by the joint): m x'' + c x' + k (x − y) = 0, resonance f_m [Hz], damping ratio ζ = c/(2 sqrt(k m)).
PHYSICAL_FORM_SPECS = {"mount": ("mount_resonance", {"f_m": ("log", 1500.0, 60.0), "zeta": ("lin", 0.05, 0.3)})}
EFFECT_SPECS.update(PHYSICAL_FORM_SPECS)


# --------------------------------------------------------------------------- strip
def law_constants(laws: dict | None) -> tuple[float, float]:
    """(Ea_d [J/mol], E log-slope [1/K]) of ``laws`` = {"ea_d": ..., "e_logslope": ...} (either key
    may be left out; None: :data:`EA_D`, :data:`E_LOGSLOPE`, the library's defaults).  Another
    strip than the user's laws assume: ``bench_next_measurement.py --law-error``."""
    laws = dict(laws or {})
    bad = set(laws) - {"ea_d", "e_logslope"}
    if bad:
        raise ValueError(f"laws: unknown key(s) {sorted(bad)}; expected 'ea_d' [J/mol] and/or 'e_logslope' [1/K]")
    ea, sl = float(laws.get("ea_d", EA_D)), float(laws.get("e_logslope", E_LOGSLOPE))
    if not (math.isfinite(ea) and ea >= 0.0 and math.isfinite(sl) and abs(sl) < 0.1):
        raise ValueError(f"laws={laws!r}: expected ea_d >= 0 J/mol and |e_logslope| < 0.1 /K")
    return ea, sl


def at_temperature(base: dict, temperature_c: float, laws: dict | None = None) -> dict:
    """The strip ``base`` (given at its temperature ``base["T"]`` [K]) at ``temperature_c`` [°C]
    (module doc, "Bath temperature"): d, ε, E and Gp by their laws, T; the rest unchanged.
    ``laws``: other law constants (:func:`law_constants`; default the module's)."""
    T0, T = base["T"], float(temperature_c) + ip.T_ZERO
    if not 0.0 < float(temperature_c) < 100.0:
        raise ValueError(f"temperature_c={temperature_c!r}: the laws here hold for liquid water, 0-100 °C")
    ea_d, e_logslope = law_constants(laws)
    arr = math.exp(-ea_d / ip.R_GAS * (1.0 / T - 1.0 / T0))
    out = dict(base)
    out["d"] = base["d"] * arr
    out["eps"] = base["eps"] * float(ip.water_permittivity(T - ip.T_ZERO) / ip.water_permittivity(T0 - ip.T_ZERO))
    out["E"] = base["E"] * math.exp(e_logslope * (T - T0))
    out["Gp"] = base["Gp"] * arr * T0 / T
    out["T"] = T
    return out


def strip_sensor(base: dict, s, temperature_c=None, laws: dict | None = None) -> tuple:
    """(G [A/m], Z [Ω]) of the strip at Laplace points s (1-D); ``temperature_c`` [°C] (a number or
    one per point; default the strip's own ``base["T"]``); ``laws`` other law constants
    (:func:`at_temperature`)."""
    if temperature_c is not None:
        s = np.asarray(s, complex)
        t = np.broadcast_to(np.asarray(temperature_c, float), s.shape)
        G, Z = np.empty(s.shape, complex), np.empty(s.shape, complex)
        for tc in np.unique(t):
            on = t == tc
            G[on], Z[on] = strip_sensor(at_temperature(base, tc, laws), s[on])
        return G, Z
    st = {k: np.asarray(v, float) for k, v in base.items()}
    st.update(alpha=0.0, zeta=0.1, f1=1.0)
    s2 = np.asarray(s, complex)[None, :]
    r = ip.strip_response({k: np.atleast_2d(v) for k, v in st.items()}, s2)
    K = r["K"]
    gam = base["h"] * np.sqrt((s2 + K) / base["d"])
    tg = np.tanh(gam)
    q = (gam - tg) / (gam * gam * tg)
    W, h, L = base["W"], base["h"], base["L"]
    y_p = W * base["eps"] * s2 * gam * (s2 + K) / (2.0 * h * (s2 * gam + K * tg))
    frac = 1.0 / (1.0 + 2.0 * (base["r2s"] / W) * y_p)
    G = s2 * W * base["a0"] * 3.0 * base["E"] * h * h / L * q * ip.bending_kernel(r["x"]) * frac
    return G.ravel(), r["Z"].ravel()


# --------------------------------------------------------------------------- chain
def slit_beam(s, f_cp, zeta):
    """Tip slope per tip displacement of the clamped-pinned strip over its static value (BVP)."""
    L = 1.0
    w = 2 * np.pi * f_cp
    b = (-(LAMBDA_CP ** 4) * ((s / w) ** 2 + 2 * zeta * s / w) + 0j) ** 0.25          # βL
    c, sn, ch, sh = np.cos(b), np.sin(b), np.cosh(b), np.sinh(b)
    one, zero = np.ones_like(b), np.zeros_like(b)
    # w = A cos βz + B sin βz + C cosh βz + D sinh βz;  w(0) = 0, w'(0) = 0, w''(L) = 0, w(L) = 1
    M = np.stack([np.stack([one, zero, one, zero], -1), np.stack([zero, one, zero, one], -1),
                  np.stack([-c, -sn, ch, sh], -1), np.stack([c, sn, ch, sh], -1)], -2)
    rhs = np.stack([zero, zero, zero, one], -1)[..., None]
    A, B, C, D = np.moveaxis(np.linalg.solve(M, rhs)[..., 0], -1, 0)
    slope = b * (-A * sn + B * c + C * sh + D * ch) / L
    return slope / (1.5 / L)


def opamp_chain(s, Z, gbw):
    """v2/i over R3 R1/R2 from the node equations (op-amp out = −A(s) v−, A = A0/(1 + s A0/ωt))."""
    A = A0 / (1.0 + s * A0 / (2 * np.pi * gbw))
    n = s.size
    M = np.zeros((n, 4, 4), complex)          # unknowns v_n1, v1, v_n2, v2
    M[:, 0, 0] = 1 / Z + 1 / R1
    M[:, 0, 1] = -1 / R1
    M[:, 1, 0], M[:, 1, 1] = A, 1.0
    M[:, 2, 1], M[:, 2, 2], M[:, 2, 3] = -1 / R2, 1 / R2 + 1 / R3, -1 / R3
    M[:, 3, 2], M[:, 3, 3] = A, 1.0
    rhs = np.zeros((n, 4, 1), complex)
    rhs[:, 0, 0] = 1.0
    return np.linalg.solve(M, rhs)[:, 3, 0] / (R3 * R1 / R2)


def chain_factor(name: str, v: dict, s, Z, f_hz):
    if name == "amplifier":
        wa = 2 * np.pi * v["f_a"]
        return 1.0 / ((1 + s / wa) * (1 + s / (v["ratio"] * wa)))
    if name == "delay":
        return np.exp(-s * v["tau"])
    if name == "laser":
        return 1.0 + s / (2 * np.pi * v["f_l"])
    if name == "ac_coupling":
        return s / (s + 2 * np.pi * v["f_c"])
    if name == "joint":
        wj = 2 * np.pi * v["f_j"]
        num = 1 + 2 * v["zeta"] * s / wj
        return num / (num + (s / wj) ** 2)
    if name == "mount":
        wm = 2 * np.pi * v["f_m"]
        k, m = wm * wm, 1.0                                   # unit mass: k = ω², c = 2ζω
        return k / (m * s * s + 2 * v["zeta"] * wm * s + k)
    if name == "slit_beam":
        return slit_beam(s, v["f_cp"], v["zeta"])
    if name == "opamp":
        return opamp_chain(s, Z, v["gbw"])
    if name == "gain_ripple":
        arg = 2 * np.pi * np.log10(f_hz) / v["period"] + v["phase"]
        return np.exp(v["amp"] * (np.sin(arg) + 1j * np.cos(arg)))
    if name == "notch":
        wn, z = 2 * np.pi * v["f_n"], v["zeta"]
        return (s * s + 2 * z * (1 - v["depth"]) * wn * s + wn * wn) / (s * s + 2 * z * wn * s + wn * wn)
    raise ValueError(f"unknown effect {name!r}; expected one of {sorted(EFFECT_SPECS)}")


def response(base: dict, effects: dict, f_hz, temperature_c=None, laws: dict | None = None) -> np.ndarray:
    """Measured G [A/m] with the chain elements ``effects`` = {name: {param: value}}; ``temperature_c``
    [°C] the bath (a number or one per line; default the strip's own ``base["T"]``); ``laws`` other
    temperature-law constants than the module's (:func:`law_constants`)."""
    f = np.asarray(f_hz, float)
    s = 2j * np.pi * f
    G, Z = strip_sensor(base, s, temperature_c, laws)
    for n, v in effects.items():
        G = G * chain_factor(n, v, s, Z, f)
    return G


# --------------------------------------------------------------------------- cases
def draw_effect(name, rng, size=None):
    q = rng.uniform() if size is None else float(size)
    out = {}
    for p, (kind, lo, hi) in EFFECT_SPECS[name][1].items():
        out[p] = lo * (hi / lo) ** q if kind == "log" else lo + q * (hi - lo)
        q = rng.uniform() if size is None else q
    return out


def baseline_noncentrality(H1, base, sig, f):
    """λ after refitting a0, d, ε (log scale) of this module's strip to the noiseless H1."""
    x0 = np.log([abs(base[k]) for k in PERTURBED])
    sg = {k: math.copysign(1.0, base[k]) for k in PERTURBED}

    def res(x):
        if np.max(x) > 709.0:                 # math.exp would overflow (it raised, ending the case): a
            return np.full(2 * f.size, 1e6)   # large residual LM refuses; every other step is as before
        b = dict(base, **{k: sg[k] * math.exp(v) for k, v in zip(PERTURBED, x)})
        r = np.log(H1 / response(b, {}, f)) / sig
        return np.concatenate([r.real, r.imag])

    with np.errstate(all="ignore"):                      # trial steps may overflow exp(x)
        fit = least_squares(res, x0, method="lm", xtol=1e-10, ftol=1e-10, max_nfev=400)
    return float(np.sum(fit.fun ** 2))


def make_case(seed: int, label: str, *, size=None, sigma_rel=None, frequencies_hz=FREQUENCIES_HZ):
    """``(FrequencySweep in µA/mm with per-line σ, truth)``; ``label`` "none" or an effect name."""
    if label != "none" and label not in EFFECT_SPECS:
        raise ValueError(f"label {label!r}: expected 'none' or one of {sorted(EFFECT_SPECS)}")
    rb, re_, rn = (np.random.default_rng(x) for x in np.random.SeedSequence([SEALED, int(seed)]).spawn(3))
    base = dict(START)
    for k in PERTURBED:
        base[k] = START[k] * math.exp(rb.uniform(-1, 1) * math.log(1.35))
    effects = {} if label == "none" else {label: draw_effect(label, re_, size)}
    f = np.asarray(frequencies_hz, float)
    H1 = response(base, effects, f)
    sig_rel = rn.uniform(*NOISE_RANGE) if sigma_rel is None else float(sigma_rel)
    sig = sig_rel / math.sqrt(2.0)
    noisy = H1 * (1 + sig * (rn.standard_normal(f.size) + 1j * rn.standard_normal(f.size)))
    sweep = FrequencySweep(np.full(f.size, TEMPERATURE_C), f, noisy * 1e3, np.full(f.size, 20 / math.log(10) * sig),
                           np.full(f.size, math.degrees(sig)), "tip_displacement", "mm", "current", "uA",
                           {"source": "independent sensor generator (tests/discrepancy), blind case"})
    lib = EFFECT_SPECS[label][0] if label != "none" else None
    truth = {"seed": int(seed), "label": label, "effects": effects, "expected": [lib] if lib else [],
             "out_of_library": label in OUT_OF_LIBRARY, "base": base, "sigma_rel": sig_rel,
             "lam_baseline": baseline_noncentrality(H1, base, sig, f) if effects else 0.0}
    return sweep, truth


def library_fields(base: dict) -> dict:
    """The strip as ``physmodel.IPMCParameters`` fields (T_ref = T; E, ρ irrelevant to the sensor's S)."""
    return dict(L=base["L"], W=base["W"], h=base["h"], d=base["d"], C_minus=base["C"], kappa_e=base["eps"],
                a0=base["a0"], r1_sheet=base["r1s"], r2_specific=base["r2s"], Rp_specific=1.0 / base["Gp"],
                E=base["E"], T_ref=base["T"])


__all__ = [
    "EA_D",
    "EFFECT_SPECS",
    "E_LOGSLOPE",
    "IN_LIBRARY",
    "OUT_OF_LIBRARY",
    "PHYSICAL_FORM_SPECS",
    "START",
    "at_temperature",
    "chain_factor",
    "law_constants",
    "library_fields",
    "make_case",
    "opamp_chain",
    "response",
    "slit_beam",
    "strip_sensor",
]
