"""An independently written Chen–Tan IPMC actuator with hidden effects (discrepancy.md §5).

Written from the equations of seed 002 (§2.2, eqs. 1–16) and physics.md §2–3, re-derived here, and
on purpose NOT importing ``physmodel``: every formula, parametrisation and numerical trick is this
module's own, so data made with it test the discrepancy workflow against physics it was not built
from.  Only scipy constants and special functions are shared.

Base strip (per unit length along z; x ∈ [−h, h] through the thickness)
-----------------------------------------------------------------------
Linearised PNP with blocking electrodes: ρ = 2c sinh(βx), β = √((s + K)/d), γ = hβ,
K = F² d C⁻/(κe R T).  Solving Gauss' law with zero ion flux at x = ±h for a slice held at ±v/2:

    slice admittance (polymer, electrode to electrode)  y_p = s W κe γ (s + K) / (2h (sγ + K tanh γ))
    bending moment per length per polymer volt          Φ   = α0 W κe K (γ − tanh γ)/(sγ + K tanh γ)

Each electrode adds a through-thickness resistance r2 = r2'/W [Ω·m] in series with the polymer;
a leakage conductance g = G'·W [S/m] spans the slice (seed 002 Fig. 3, eq. 11).  The electrodes
carry r1 = r1'/W [Ω/m] each, so the slice voltage v(z) obeys v'' = q² v with q² = 2 r1 y,
y = 1/(1/y_p + 2 r2) + g, v(0) = V, v'(L) = 0 ⇒ v = V cosh(q(L − z))/cosh(qL).  With x = qL:

    Z     = x coth x / (y L)                                  terminal impedance [Ω]
    H_qs  = −L² Φ f X(x)/(E I),  f = (1/y_p)/(1/y_p + 2 r2)   quasi-static tip/volt [m/V] (eq. 13 sign)
    X(x)  = ∫0^1 (1 − ξ) cosh(x(1 − ξ))/cosh x dξ = tanh(x/2)(x − tanh(x/2))(1 + sech x)/x²

(the last form has no cancellation as x → 0, unlike (x tanh x + sech x − 1)/x²).  I = (2/3) W h³.

Beam (Euler–Bernoulli cantilever, clamped at z = 0)
----------------------------------------------------
Modes φ_n(ξ) with cos λ cosh λ = −1 (roots found here by brentq), ∫0^1 φ_n² dξ = 1, ω_n = ω1 (λn/λ1)².
A distributed active moment m(ξ) drives mode n by Q_n = ∫0^1 m φ_n'' dξ; the tip deflection is
w(L) = (L²/EI) Σ φ_n(1) Q_n η_n/λ_n⁴ with η_n the unit-DC-gain modal response.  Normalised by the
quasi-static deflection, mode n carries the participation

    π_n(x) = φ_n(1) Q_n(x)/(λ_n⁴ X(x)),   Q_n(x) = ∫0^1 cosh(x(1 − ξ))/cosh x · φ_n''(ξ) dξ,

which for a uniform moment (x = 0) is 2 φ_n(1) φ_n'(1)/λ_n⁴ = 0.8908, 0.0788, 0.0165, 0.0060, …
(Σ = 1); with resistive electrodes the moment decays along z and π_n depends on s through x.
``second_mode`` uses M = H_qs [1/ε + Σ_{n ≤ N} π_n(x) (g_n − 1/ε)] (modal sum with the
quasi-static residual of the higher modes, :func:`modal_mechanics`); without it the base folds
every mode into the first, M = H_qs g_1 (seed 002 eq. 16).  g_n = 1/(ε + 2ζ_n' s/ω_n +
(1 + μ)(s/ω_n)²): Rayleigh damping split into a mass-proportional ζ_n' and a Kelvin–Voigt modulus
ε = e + b s, e = E(s)/E (1 unless viscoelastic creep), μ an extra fluid load (0 unless added
fluid mass).

Parametrisation of the base (keys of the ``base`` dict, SI): L, W, h, d, C, eps, alpha, r1s [Ω],
r2s [Ω·m²], Gp [S/m²] (leakage conductance per area; 0 = none), E [Pa], f1 [Hz] (first mode at T0),
zeta, T0_c [°C], thermal (bool) and, when thermal, Q10_d (Arrhenius diffusivity written as its
factor over T0 → T0 + 10 K), E_logslope [1/K] and eps_water (κe ∝ water permittivity, Owen et al.
1961: log10 ε = 1.94404 − 1.991e-3 t).  Leakage follows Nernst–Einstein (∝ d/T) when thermal.
"""

from __future__ import annotations

import numpy as np
from scipy import constants, special
from scipy.optimize import brentq

FARADAY = constants.physical_constants["Faraday constant"][0]
R_GAS = constants.R
T_ZERO = constants.zero_Celsius


# --------------------------------------------------------------------------- beam modes
def cantilever_roots(n: int) -> np.ndarray:
    """First ``n`` roots λ of cos λ cosh λ = −1 (clamped-free), written cos λ + sech λ = 0."""
    f = lambda lam: np.cos(lam) + 1.0 / np.cosh(lam)  # noqa: E731
    out = []
    for k in range(1, n + 1):
        c = (k - 0.5) * np.pi
        out.append(brentq(f, max(c - 0.6, 1.0), c + 0.6, xtol=1e-15, rtol=1e-15))
    return np.array(out)


def _mode_parts(lam, xi):
    """Stable pieces of φ = (cosh − σ sinh)(λξ) − cos λξ + σ sin λξ, σ = (cosh λ + cos λ)/(sinh λ + sin λ).

    (cosh − σ sinh)(u) = ((1 − σ) e^u + (1 + σ) e^−u)/2 with 1 − σ computed without cancellation."""
    lam = np.asarray(lam, dtype=float)[:, None]
    e = np.exp(-lam)
    den = (1.0 - e * e) / 2.0 + e * np.sin(lam)            # (sinh λ + sin λ)·e^−λ
    one_m_sig = e * (np.sin(lam) - np.cos(lam) - e) / den  # 1 − σ
    sig = 1.0 - one_m_sig
    u = lam * np.asarray(xi, dtype=float)[None, :]
    hyp_c = (one_m_sig * np.exp(u) + (1.0 + sig) * np.exp(-u)) / 2.0     # cosh u − σ sinh u
    hyp_s = (one_m_sig * np.exp(u) - (1.0 + sig) * np.exp(-u)) / 2.0     # sinh u − σ cosh u
    return lam, sig, u, hyp_c, hyp_s


def mode_shape(lam, xi, derivative: int = 0) -> np.ndarray:
    """φ_n^(k)(ξ) for k = 0, 1, 2 (derivatives in ξ), shape (n_modes, n_xi); ∫0^1 φ² dξ = 1."""
    lam, sig, u, hc, hs = _mode_parts(lam, xi)
    if derivative == 0:
        return hc - np.cos(u) + sig * np.sin(u)
    if derivative == 1:
        return lam * (hs + np.sin(u) + sig * np.cos(u))
    if derivative == 2:
        return lam**2 * (hc + np.cos(u) - sig * np.sin(u))
    raise ValueError(f"derivative must be 0, 1 or 2, got {derivative!r}")


def uniform_moment_participation(n: int) -> np.ndarray:
    """π_n = 2 φ_n(1) φ_n'(1)/λ_n⁴ for a uniform bending moment (x = 0)."""
    lam = cantilever_roots(n)
    return 2.0 * mode_shape(lam, [1.0])[:, 0] * mode_shape(lam, [1.0], 1)[:, 0] / lam**4


def _gauss_panels(edges=(0.0, 1 / 256, 1 / 64, 1 / 16, 1 / 4, 1.0), order: int = 24):
    """Composite Gauss–Legendre nodes/weights on [0, 1], graded towards ξ = 0 where
    cosh(x(1 − ξ))/cosh x varies fastest (boundary layer of width 1/|x|)."""
    t, w = np.polynomial.legendre.leggauss(order)
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        nodes.append(a + (b - a) * (t + 1) / 2)
        weights.append(w * (b - a) / 2)
    return np.concatenate(nodes), np.concatenate(weights)


_XI_Q, _W_Q = _gauss_panels()


def line_profile(x, xi):
    """cosh(x(1 − ξ))/cosh x for Re x ≥ 0, without overflow: (e^{−xξ} + e^{−x(2−ξ)})/(1 + e^{−2x})."""
    x = np.asarray(x)[..., None]
    return (np.exp(-x * xi) + np.exp(-x * (2.0 - xi))) / (1.0 + np.exp(-2.0 * x))


def modal_participation(x, n_modes: int) -> np.ndarray:
    """π_n(x) of the first ``n_modes`` modes for the moment profile cosh(x(1 − ξ))/cosh x.

    Returns shape x.shape + (n_modes,).  Quadrature on graded Gauss panels (exact to rounding
    for |x| ≲ 300)."""
    lam = cantilever_roots(n_modes)
    d2 = mode_shape(lam, _XI_Q, 2)                               # (n, q)
    prof = line_profile(x, _XI_Q)                                # (..., q)
    Q = np.einsum("...q,nq->...n", prof * _W_Q, d2)
    tip = mode_shape(lam, [1.0])[:, 0]
    return tip * Q / (lam**4 * bending_kernel(x)[..., None])


# --------------------------------------------------------------------------- strip kernels
def bending_kernel(x):
    """X(x) = tanh(x/2)(x − tanh(x/2))(1 + sech x)/x², X(0) = 1/2 (Re x ≥ 0)."""
    x = np.asarray(x, dtype=complex)
    small = np.abs(x) < 1e-150
    xs = np.where(small, 1.0, x)
    t = np.tanh(xs / 2)
    sech = 2.0 * np.exp(-xs) / (1.0 + np.exp(-2.0 * xs))
    return np.where(small, 0.5, t * (xs - t) * (1.0 + sech) / xs**2)


def x_coth_x(x):
    x = np.asarray(x, dtype=complex)
    small = np.abs(x) < 1e-150
    xs = np.where(small, 1.0, x)
    return np.where(small, 1.0, xs / np.tanh(xs))


def water_permittivity(t_c):
    """Relative permittivity of water, Owen, Miller, Milner & Cogan (1961): log10 ε = 1.94404 − 1.991e-3 t."""
    return 10.0 ** (1.94404 - 1.991e-3 * np.asarray(t_c, dtype=float))


def ea_from_q10(q10, t0_c):
    """Arrhenius activation energy [J/mol] whose factor over T0 → T0 + 10 K is ``q10``."""
    T0 = t0_c + T_ZERO
    return R_GAS * np.log(q10) / (1.0 / T0 - 1.0 / (T0 + 10.0))


def q10_from_ea(ea, t0_c):
    T0 = t0_c + T_ZERO
    return float(np.exp(ea / R_GAS * (1.0 / T0 - 1.0 / (T0 + 10.0))))


def base_state(base: dict, temperature_c) -> dict:
    """Base parameters at temperatures [°C] as arrays of shape (n_T, 1) (electrode terms per slice)."""
    t = np.asarray(temperature_c, dtype=float).reshape(-1, 1)
    T, T0 = t + T_ZERO, base["T0_c"] + T_ZERO
    one = np.ones_like(t)
    st = {k: base[k] * one for k in ("L", "W", "h", "d", "C", "eps", "alpha", "r1s", "r2s", "Gp", "E", "zeta")}
    st["T"], st["f1"] = T, base["f1"] * one
    if base.get("thermal", False):
        arr = np.exp(-ea_from_q10(base["Q10_d"], base["T0_c"]) / R_GAS * (1.0 / T - 1.0 / T0))
        st["d"] = st["d"] * arr
        st["Gp"] = st["Gp"] * arr * T0 / T                       # Nernst–Einstein: σ ∝ d/T
        fe = np.exp(base["E_logslope"] * (T - T0))
        st["E"] = st["E"] * fe
        st["f1"] = st["f1"] * np.sqrt(fe)
        if base.get("eps_water", True):
            st["eps"] = st["eps"] * water_permittivity(t) / water_permittivity(base["T0_c"])
    return st


def strip_response(st: dict, s, s_transport=None, z_interface=None) -> dict:
    """Electrical and quasi-static quantities of the strip at Laplace points s (shape (1, n_f)).

    ``s_transport`` replaces s inside the charge dynamics (fractional transport); default s.
    ``z_interface``: an impedance per unit length [Ω·m] in series with the polymer branch of every
    slice (an interface CPE along the electrodes: de Levie's line with a CPE wall); default none."""
    st_ = s if s_transport is None else s_transport
    K = FARADAY**2 * st["d"] * st["C"] / (st["eps"] * R_GAS * st["T"])
    W, h, L = st["W"], st["h"], st["L"]
    gam = h * np.sqrt((st_ + K) / st["d"])
    tg = np.tanh(gam)
    den = st_ * gam + K * tg
    y_p = W * st["eps"] * st_ * gam * (st_ + K) / (2.0 * h * den)
    r1, r2 = st["r1s"] / W, st["r2s"] / W
    z_branch = 1.0 / y_p + 2.0 * r2
    if z_interface is not None:
        z_branch = z_branch + z_interface
    y = 1.0 / z_branch + st["Gp"] * W
    f_pol = (1.0 / y_p) / z_branch
    x = L * np.sqrt(2.0 * r1 * y + 0j)
    phi = st["alpha"] * W * st["eps"] * K * (gam - tg) / den
    I2 = 2.0 / 3.0 * W * h**3
    Hqs = -(L * L) * phi * f_pol * bending_kernel(x) / (st["E"] * I2)
    return {"Z": x_coth_x(x) / (y * L), "Hqs": Hqs, "x": x, "K": K}


def hydrodynamic_gamma(reynolds):
    """Sader (1998, J. Appl. Phys. 84:64, eq. 19) circular-cylinder hydrodynamic function Γ(Re),
    Re = ρ_f ω b²/(4η), in Sader's e^{−iωt} convention (Im Γ > 0 is dissipation)."""
    a = np.sqrt(1j * np.asarray(reynolds, dtype=float))
    return 1.0 + 4j * special.kv(1, -1j * a) / (a * special.kv(0, -1j * a))


def modal_mechanics(x, s, w1, zeta1, n_modes: int = 1, viscous_share: float = 1.0, e=1.0, mu=0.0):
    """Dynamic tip deflection / quasi-static tip deflection of the cantilever.

    ``n_modes`` = 1: the base's folded first mode g_1 = 1/(e + 2ζ s/ω1 + (1 + μ)(s/ω1)²).
    ``n_modes`` > 1: the Euler–Bernoulli modal sum 1/ε + Σ_{n ≤ N} π_n(x) (g_n − 1/ε) with the
    quasi-static residual 1/ε of the modes above N, ω_n = ω1 (λn/λ1)² and Rayleigh damping
    ζ_n = ζ1 (ν ω1/ω_n + (1 − ν) ω_n/ω1) (ν = ``viscous_share``: mass-proportional part), whose
    stiffness part is the Kelvin–Voigt modulus ε = e + 2ζ1(1 − ν) s/ω1 shared by all modes.
    ``x`` line argument (moment profile cosh(x(1 − ξ))/cosh x), ``s`` Laplace points [1/s],
    ``w1`` [rad/s], ``e`` = E(s)/E, ``mu`` extra fluid load ratio; all broadcast together.
    """
    if n_modes <= 1:
        sn = s / w1
        return 1.0 / (e + 2 * zeta1 * sn + (1 + mu) * sn * sn)
    lam = cantilever_roots(n_modes)
    # the stiffness-proportional part is a Kelvin–Voigt modulus E (1 + b s), the same for every
    # mode (2 ζ_n s/ω_n = b s), so it belongs to the static residual of the higher modes too
    ekv = e + 2 * zeta1 * (1 - viscous_share) * s / w1
    w1_, z1_ = np.asarray(w1)[..., None], np.asarray(zeta1)[..., None]
    wn = w1_ * (lam / lam[0]) ** 2
    sn = np.asarray(s)[..., None] / wn
    e_, mu_ = np.asarray(ekv)[..., None], np.asarray(mu)[..., None]
    g = 1.0 / (e_ + 2 * z1_ * viscous_share * (w1_ / wn) * sn + (1 + mu_) * sn * sn)
    return 1.0 / ekv + np.sum(modal_participation(x, n_modes) * (g - 1.0 / e_), axis=-1)


def modes_with_modal_damping(x, s, w1, zeta1, zeta_higher, n_modes: int):
    """Tip deflection / quasi-static tip deflection with every mode n ≤ N dynamic and the rest
    static: Σ_{n ≤ N} π_n(x) η_n + (1 − Σ_{n ≤ N} π_n(x)), η_1 = 1/(1 + 2ζ1 s/ω1 + (s/ω1)²) and
    η_n = 1/(1 + 2ζ_h s/ω_n + (s/ω_n)²) for n ≥ 2 (one damping ratio for the higher modes)."""
    lam = cantilever_roots(n_modes)
    wn = np.asarray(w1)[..., None] * (lam / lam[0]) ** 2
    z = np.concatenate([[0.0], np.full(n_modes - 1, float(zeta_higher))])
    z = np.where(np.arange(n_modes) == 0, np.asarray(zeta1)[..., None], z)
    sn = np.asarray(s)[..., None] / wn
    eta = 1.0 / (1.0 + 2.0 * z * sn + sn * sn)
    pi = modal_participation(x, n_modes)
    return np.sum(pi * eta, axis=-1) + (1.0 - np.sum(pi, axis=-1))


# --------------------------------------------------------------------------- hidden effects
#: Temperature coefficient of an electronic (metallic Pt) leakage path's resistance [1/K] (bulk Pt).
PT_TCR = 3.9e-3


def _parameter_effects(st: dict, eff: dict, T0_c: float) -> dict:
    """Effects that change the strip's parameters at each temperature (own parametrisations)."""
    dT = st["T"] - (T0_c + T_ZERO)
    if "electrode_resistance" in eff:      # extra sheet resistance of both electrodes [Ω]
        st["r1s"] = st["r1s"] + eff["electrode_resistance"]["extra_sheet_ohm"]
    if "contact_resistance" in eff:        # extra area-specific through-thickness resistance [Ω·m²]
        st["r2s"] = st["r2s"] + eff["contact_resistance"]["extra_area_resistance"]
    if "modulus_temperature" in eff:       # extra LINEAR modulus change per kelvin
        fac = 1.0 + eff["modulus_temperature"]["linear_coeff"] * dT
        st["E"], st["f1"] = st["E"] * fac, st["f1"] * np.sqrt(fac)
    if "diffusivity_temperature" in eff:   # extra factor q10 per 10 K on d (and the ionic leakage)
        fac = eff["diffusivity_temperature"]["q10"] ** (dT / 10.0)
        st["d"], st["Gp"] = st["d"] * fac, st["Gp"] * fac
    if "permittivity_temperature" in eff:  # extra LINEAR permittivity change per kelvin
        st["eps"] = st["eps"] * (1.0 + eff["permittivity_temperature"]["linear_coeff"] * dT)
    if "water_uptake" in eff:              # isotropic swelling from the water volume fraction φ(T)
        p = eff["water_uptake"]
        vol = (1.0 - p["phi0"]) / (1.0 - (p["phi0"] + p["dphi_dT"] * dT))
        lin = vol ** (1.0 / 3.0)
        st["h"], st["L"], st["W"] = st["h"] * lin, st["L"] * lin, st["W"] * lin
        st["C"] = st["C"] / vol            # fixed anions diluted
        # ω1 ∝ sqrt(E W h³/m')/L² with m' ∝ W² (fluid added mass dominates) ⇒ ∝ 1/lin
        st["f1"] = st["f1"] / lin
    if "leakage" in eff:                   # electronic leakage through the polymer [S/m²], Pt-like TCR
        st["Gp"] = st["Gp"] + eff["leakage"]["conductance"] / (1.0 + PT_TCR * dT)
    return st


def actuator_response(base: dict, frequency_hz, temperature_c, effects: dict | None = None) -> dict:
    """Tip displacement per volt ``M`` [m/V] and terminal impedance ``Z`` [Ω], shape (n_T, n_f).

    ``effects`` maps effect names (see :data:`EFFECT_NAMES`) to their parameter dicts; an absent
    effect is off.  Every effect also has an explicit off value in its own parameters (0 for the
    additive ones, 1 for q10, ``n_modes`` = 1 … see the generator's specs)."""
    eff = dict(effects or {})
    unknown = set(eff) - set(EFFECT_NAMES)
    if unknown:
        raise ValueError(f"unknown effect(s) {sorted(unknown)}; expected some of {EFFECT_NAMES}")
    f = np.asarray(frequency_hz, dtype=float).reshape(1, -1)
    s, w = 2j * np.pi * f, 2 * np.pi * f
    st = _parameter_effects(base_state(base, temperature_c), eff, base["T0_c"])
    s_tr = None
    if "fractional_transport" in eff:      # anomalous charge relaxation: s → ω_c (s/ω_c)^β in transport only
        p = eff["fractional_transport"]
        wc = 2 * np.pi * p["f_ref_hz"]
        s_tr = wc * (s / wc) ** p["beta"]
    z_if = None
    if "distributed_cpe" in eff:           # interface CPE in every slice: Q' = q_area·W per length
        p = eff["distributed_cpe"]
        if p["q_area"] != np.inf:
            z_if = 1.0 / (p["q_area"] * st["W"] * s ** p["n"])
    sr = strip_response(st, s, s_tr, z_if)
    Z, H = sr["Z"], sr["Hqs"]
    z_ser = np.zeros_like(s)
    if "series_resistance" in eff:         # leads, clamp contact, amplifier output resistance [Ω]
        z_ser = z_ser + eff["series_resistance"]["resistance"]
    if "series_cpe" in eff:                # interface CPE in series, Q = q_area · W L [F s^(n−1)]
        p = eff["series_cpe"]
        if p["q_area"] != np.inf:
            z_ser = z_ser + 1.0 / (p["q_area"] * base["W"] * base["L"] * s ** p["n"])
    if np.any(z_ser != 0):                 # actuation follows the voltage across the strip
        H = H * Z / (Z + z_ser)
        Z = Z + z_ser
    w1 = 2 * np.pi * st["f1"]
    e = 1.0
    if "viscoelastic_creep" in eff:        # Cole–Cole relaxation of the modulus, E(s)/E(∞)
        p = eff["viscoelastic_creep"]
        e = 1.0 - p["delta"] / (1.0 + (s * p["tau_s"]) ** p["a"])
    mu = 0.0
    if "added_fluid_mass" in eff:          # extra hydrodynamic load, Sader's Γ (conjugated for e^{+jωt})
        p = eff["added_fluid_mass"]
        mu = p["mass_ratio"] * np.conj(hydrodynamic_gamma(p["reynolds"] * w / w1))
    sm = eff.get("second_mode", {})
    mech = modal_mechanics(sr["x"], s, w1, st["zeta"], int(sm.get("n_modes", 1)), sm.get("viscous_share", 1.0), e, mu)
    bm = eff.get("bending_modes", {"n_modes": 1})
    if int(bm["n_modes"]) > 1:            # modes 2..N with one modal damping ratio (replaces the folded mode)
        p = bm
        mech = modes_with_modal_damping(sr["x"], s, w1, st["zeta"], p["zeta_higher"], int(p["n_modes"]))
    M = H * mech
    if "amplifier_bandwidth" in eff:       # dominant pole f_a and a non-dominant one at ratio·f_a
        p = eff["amplifier_bandwidth"]
        wa = 2 * np.pi * p["f_dominant_hz"]
        M = M / ((1 + s / wa) * (1 + s / (p["pole_ratio"] * wa)))
    if "time_delay" in eff:                # inter-channel sampling skew + zero-order-hold output DAC
        p = eff["time_delay"]
        M = M * np.exp(-s * p["skew_s"])
        if p["dac_period_s"] > 0:
            Tu = p["dac_period_s"]
            M = M * (-np.expm1(-s * Tu)) / (s * Tu)
    if "fixture_resonance" in eff:         # compliant fixture: DC 1, high-frequency 1 + κ
        p = eff["fixture_resonance"]
        wf, z, k = 2 * np.pi * p["f_hz"], p["zeta"], p["kappa"]
        M = M * (wf * wf + 2 * z * wf * s + (1 + k) * s * s) / (wf * wf + 2 * z * wf * s + s * s)
    if "gain_ripple" in eff:               # magnitude-only ripple periodic in log frequency (calibration)
        p = eff["gain_ripple"]
        M = M * (1 + p["amplitude"] * np.sin(2 * np.pi * np.log10(f) / p["period_decades"] + p["phase"]))
    return {"M": M, "Z": np.broadcast_to(Z, M.shape).copy()}


#: Every effect this module can hide (library-mappable and out-of-library ones).
EFFECT_NAMES = ("electrode_resistance", "contact_resistance", "leakage", "second_mode", "added_fluid_mass",
                "modulus_temperature", "diffusivity_temperature", "permittivity_temperature", "water_uptake",
                "amplifier_bandwidth", "time_delay", "series_resistance", "fractional_transport", "series_cpe",
                "fixture_resonance", "gain_ripple", "viscoelastic_creep", "distributed_cpe", "bending_modes")

__all__ = ["FARADAY", "R_GAS", "T_ZERO", "cantilever_roots", "mode_shape", "uniform_moment_participation",
           "modal_participation", "line_profile", "bending_kernel", "x_coth_x", "water_permittivity",
           "ea_from_q10", "q10_from_ea", "base_state", "strip_response", "hydrodynamic_gamma",
           "actuator_response", "modal_mechanics", "modes_with_modal_damping", "EFFECT_NAMES", "PT_TCR"]
