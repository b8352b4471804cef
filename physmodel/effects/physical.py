"""Effects of the strip itself: polymer, electrodes, beam and temperature laws (discrepancy.md §3).

Every effect composes the physmodel sub-models rather than re-deriving them:

* parameter-level effects change the :class:`~physmodel.params.State` (r1, r2, Rp, E, d, κe,
  h, C⁻); the model then recomputes K with :func:`physmodel.transport.debye_rate` and the
  first mode with :func:`physmodel.params.first_mode_omega`; the temperature effects multiply by
  the factors of the laws in :mod:`physmodel.temperature` (Arrhenius, LogLinear);
* ``second_mode`` is the Euler–Bernoulli modal expansion of :mod:`physmodel.beam`
  (:func:`~physmodel.beam.modal_tip_response`) driven by the moment profile of the electrode line
  (:func:`physmodel.electrode.strip_terms`), with as many modes as the band needs;
* ``viscous_fluid`` is Sader's hydrodynamic load on the beam (:mod:`physmodel.effects.fluid`): the first
  mode of :mod:`physmodel.beam` with a frequency-dependent complex modal mass;
* ``fractional_transport`` replaces s by ŝ = ω_c (s/ω_c)^β inside the charge dynamics only.

Fractional transport (derivation).  Replace the first-order time derivative of the linearised
PNP charge equation by a Caputo derivative of order β (anomalous, distributed charge relaxation,
fractional PNP models of impedance spectroscopy; Macdonald, Evangelista & Lenzi)::

    ω_c^{1-β} D^β ρ = d ∂²ρ/∂x² − K ρ ,   and the continuity equation  ω_c^{1-β} D^β q + ∂J/∂x = 0

so that every ``s`` of the transport sub-model becomes ``ŝ = ω_c (s/ω_c)^β``: the polymer admittance
tends to ŝ κe W/λ at low frequency, a constant-phase double layer *inside* the transport.  This is
a different mechanism from the interface constant-phase element in series with the strip
(:mod:`physmodel.effects.chain`, ``series_cpe``).  β = 1 is off; ω_c = 2π·:data:`CPE_REFERENCE_HZ`.
"""

from __future__ import annotations

import numpy as np

from .. import beam
from ..temperature import Arrhenius, LogLinear
from ..transport import debye_rate
from . import fluid
from .base import Effect, P, by_mode_count, law_factor, rows_of

#: Frequency [Hz] at which |ŝ| = |s| for the fractional transport (ŝ = ω_c (s/ω_c)^β).
CPE_REFERENCE_HZ = 10.0
#: ω2/ω1 of a clamped-free Euler-Bernoulli beam, (λ2/λ1)².
SECOND_MODE_RATIO = float((beam.cantilever_roots(2)[1] / beam.cantilever_roots(2)[0]) ** 2)


def polymer_area_resistance(p) -> float:
    """Through-thickness ionic area resistance of the polymer at T_ref, 2h/(κe K) [Ω·m²]
    (the bulk conductance per length of a slice is W κe K/(2h), :func:`physmodel.transport.polymer_admittance`)."""
    return 2.0 * p.h / (p.kappa_e * float(debye_rate(p.d, p.C_minus, p.kappa_e, p.T_ref)))


# --------------------------------------------------------------------------- parameter level
# Each _p_* receives a dict of State arrays (n_sets, n_T, 1), the reference temperature array
# and the effect's values, and returns the updated dict with the arrays it changes REPLACED, never
# written into (the model recomputes K and omega_n after only when an input of theirs was replaced,
# and keeps the base state's arrays between calls).
def _p_electrode(st, T_ref, v):
    st["r1"] = st["r1"] + v["r1_sheet"] / st["W"]
    return st


def _p_contact(st, T_ref, v):
    st["r2"] = st["r2"] + v["r2_specific"] / st["W"]
    return st


def _p_leakage(st, T_ref, v):
    tf = 1.0 + v["tcr"] * (st["T"] - T_ref)                  # resistance of the path ∝ 1 + tcr ΔT
    if np.any(tf <= 0):
        from ..errors import ParameterError

        raise ParameterError(f"leakage.tcr={v['tcr']!r} /K makes the leakage resistance non-positive in the "
                             "requested temperature range")
    with np.errstate(divide="ignore"):
        g = 1.0 / st["Rp"] + v["conductance"] * st["W"] / tf  # 1/Rp [S/m] per slice
        st["Rp"] = np.where(g > 0, 1.0 / np.where(g > 0, g, 1.0), np.inf)
    return st


def _curved(st, T_ref, v):
    """exp(c2 (T − T_ref)²): the second-order term of any smooth law in ln(factor) — another
    author's linear-in-T, Q10 or VTF law differs from the log-linear / Arrhenius law by it."""
    return np.exp(v["curvature"] * (st["T"] - T_ref) ** 2)


def _p_modulus_T(st, T_ref, v):
    st["E"] = st["E"] * law_factor(LogLinear, "slope", v["slope"], st["T"], T_ref) * _curved(st, T_ref, v)
    return st


def _p_diffusivity_T(st, T_ref, v):
    fac = law_factor(Arrhenius, "activation_energy", v["activation_energy"], st["T"], T_ref) * _curved(st, T_ref, v)
    st["d"] = st["d"] * fac
    st["Rp"] = st["Rp"] / fac            # Nernst-Einstein: ionic resistance ∝ T/d (T part in the base law)
    return st


def _p_permittivity_T(st, T_ref, v):
    st["kappa_e"] = st["kappa_e"] * law_factor(LogLinear, "slope", v["slope"], st["T"], T_ref) * _curved(st, T_ref, v)
    return st


def _p_water_uptake(st, T_ref, v):
    sw = 1.0 + v["swelling"] * (st["T"] - T_ref)                         # thickness
    sp = 1.0 + v["in_plane_share"] * v["swelling"] * (st["T"] - T_ref)   # length and width
    if np.any(sw <= 0) or np.any(sp <= 0):
        from ..errors import ParameterError

        raise ParameterError(f"water_uptake.swelling={v['swelling']!r} /K makes the strip's size non-positive "
                             "in the requested temperature range")
    st["h"] = st["h"] * sw
    st["L"], st["W"] = st["L"] * sp, st["W"] * sp
    for k in ("r1", "r2", "Rp"):         # per-length values of the sheet/area-specific ones: ∝ 1/W
        st[k] = st[k] / sp
    st["C_minus"] = st["C_minus"] / (sw * sp * sp)   # fixed charges diluted by the absorbed water
    return st


# --------------------------------------------------------------------------- response / kernel level
def _r_second_mode(q, ctx, v):
    """M = H_qs·[g1 + c (T_modal − g1)]: c = 1 is the Euler–Bernoulli modal sum, c = 0 the base."""
    st, x = ctx.st, ctx.x

    def modal(rows, n):
        wn, xi = rows_of(st.omega_n, rows), rows_of(st.xi, rows)
        g1 = beam.first_mode(ctx.s, wn, xi)
        full = beam.modal_tip_response(ctx.s, wn, xi, rows_of(x, rows), n, rows_of(v["viscous_share"], rows))
        return 1.0 + rows_of(v["weight"], rows) * (full / g1 - 1.0)

    return by_mode_count(ctx, modal)


def fractional_s(s, v):
    """ŝ = ω_c (s/ω_c)^β (principal power: arg ŝ = β·π/2 on the axis)."""
    wc = 2 * np.pi * CPE_REFERENCE_HZ
    return wc * (s / wc) ** v["beta"]


# --------------------------------------------------------------------------- candidate bounds
def _contact_bounds(p):
    ra = polymer_area_resistance(p)
    return {"r2_specific": (0.0, min(5.0 * ra, 1.0), 0.2 * ra)}


def _leakage_bounds(p):
    g = 1.0 / polymer_area_resistance(p)          # κe K/(2h)
    return {"conductance": (0.0, min(3.0 * g, 1e5), 0.1 * g)}


_CURV = P("curvature", "1/K^2", 0.0, -2e-3, 2e-3, 1e-4, "second-order term c2 of ln(factor)")

EFFECTS = [
    Effect("electrode_resistance", "distributed electrode resistance",
           "Sheet resistance of the electrodes along the length (added to the base r1'), making the "
           "strip a lossy transmission line: gain and phase fall at high frequency, more near the tip.",
           "Chen & Tan 2008; seed 002 eq. (10)-(14); cracked/dried Pt electrodes reach 10²-10³ Ω "
           "(Shahinpoor & Kim 2000, Smart Mater. Struct. 9:543)", "parameter",
           (P("r1_sheet", "Ohm", 0.0, 0.0, 2e4, 300.0, "added electrode sheet resistance r1'"),),
           apply=_p_electrode),
    Effect("contact_resistance", "through-thickness / contact electrode resistance",
           "Resistance r2' between the electrode surface and the polymer (added to the base r2'): a "
           "series loss on every slice that lowers the gain where the polymer admittance is high.",
           "Chen & Tan 2008; seed 002 eq. (11), Fig. 11; acid-form Nafion 117 area resistance "
           "1.6e-5 Ω·m² (Slade et al. 2002, J. Electrochem. Soc. 149:A1556)", "parameter",
           (P("r2_specific", "Ohm m^2", 0.0, 0.0, 1.0, 5e-5, "added through-thickness resistance r2'"),),
           apply=_p_contact, fit_bounds=_contact_bounds,
           bounds_doc="r2' in [0, 5·2h/(κe K)]: up to five times the polymer's own through-thickness "
                      "area resistance at T_ref (1.2e-2 Ω·m² for seed 002); typical 0.2× it."),
    Effect("leakage", "polymer leakage",
           "An electronic leakage conductance through the polymer (metal particles bridging the "
           "electrodes), 1/Rp' at T_ref added to the base's (ionic) leakage, its resistance changing "
           "as 1 + tcr (T − T_ref) (metallic paths: tcr > 0; Pt 3.9e-3 /K): a resistive path in "
           "parallel with the double layers, visible at low frequency and through the electrode line.",
           "Chen & Tan 2008; seed 002 eq. (11); Pt resistivity coefficient (CRC Handbook)", "parameter",
           (P("conductance", "S/m^2", 0.0, 0.0, 1e5, 50.0, "added leakage conductance 1/Rp' at T_ref"),
            P("tcr", "1/K", 0.0, -0.01, 0.01, 3.9e-3, "temperature coefficient of the path's resistance")),
           apply=_p_leakage, fit_bounds=_leakage_bounds, switch="conductance",
           bounds_doc="1/Rp' in [0, 3·κe K/(2h)]: up to three times the polymer's own ionic conductance "
                      "per area at T_ref (≈ 1300 S/m² for seed 002); typical 0.1× it."),
    Effect("second_mode", "higher bending modes (Euler-Bernoulli modal expansion)",
           "The cantilever's modal sum instead of the first mode alone: M = H_qs·[g1 + c (Σ_n π_n(x) "
           "(g_n − 1/ε) + 1/ε − g1)], with the participations π_n(x) of the moment profile the "
           "electrode line gives (0.891, 0.079, 0.016, … for a uniform moment), ω_n = ω1 (λn/λ1)² "
           "and Rayleigh damping with mass-proportional share ν (stiffness share as a Kelvin-Voigt "
           "modulus ε). c = 1 is the full expansion; above ω1 it adds the quasi-static residual "
           "of the higher modes (an antiresonance), below it the DC gain is kept.",
           "Euler-Bernoulli modal expansion (Meirovitch, Fundamentals of Vibrations, §8); physmodel.beam",
           "response",
           (P("weight", "1", 0.0, 0.0, 1.2, 1.0, "weight c of the higher modes (1 = modal expansion)"),
            P("viscous_share", "1", 1.0, 0.0, 1.0, 0.75, "mass-proportional share ν of the damping",
              limits=("lower", "upper"))),
           kinds=("actuator",), quantities=("M",), apply=_r_second_mode, switch="weight"),
    Effect("viscous_fluid", "beam in a viscous fluid (frequency-dependent added mass and damping)",
           "Sader's hydrodynamic load on the strip: the modal mass becomes ρ·2hW + (π/4) ρ_f W² Γ_rect*(Re), "
           "Re = ω W²/(4ν), with the added mass (Re Γ) falling and the viscous damping (Im Γ) rising as the "
           "frequency falls; parametrised by √(ρ_f η) (what the data determine), ν and an Andrade energy "
           "E_η.  The inviscid limit (ν → 0) is the constant added mass π ρ_f W²/4 per length, which a free "
           "ωn absorbs (see physmodel.effects.fluid).",
           "Sader 1998, J. Appl. Phys. 84:64, eqs. (10), (19)-(21); water/glycerol viscosity (CRC Handbook)",
           "response",
           (P("viscous_load", "kg m^-2 s^-0.5", 0.0, 0.0, 70.0, 1.0,
              "√(ρ_f η) = ρ_f √ν at T_ref (water 1.0, glycerol 42 at 20 °C); ρ_f = it/√ν"),
            P("log10_viscosity", "log10(m^2/s)", -6.0, -6.6, -2.5, -4.55,
              "log10 of the kinematic viscosity ν at T_ref (water −6.0 at 20 °C, glycerol −2.95)",
              limits=("lower",)),
            P("viscosity_energy", "J/mol", 16e3, 0.0, 70e3, 35e3,
              "Andrade activation energy E_η of the viscosity (water ≈ 16e3, glycerol ≈ 60e3)", limits=("lower",))),
           kinds=("actuator",), quantities=("M",), apply=fluid.response_factor, switch="viscous_load",
           bounds_doc="√(ρ_f η) in [0, 70] kg m⁻² s^-½ (no liquid, up to glycerol near 10 °C: 1263 kg/m³, 3.9 Pa·s); "
                      "ν from hot water (2.5e-7 m²/s, −6.6: the high-Re end, where ν is not determined and, with "
                      "ωn free, the load tends to the boundary-layer asymptote — a limit, not a bound to widen; "
                      "with ωn held, ρ_f = √(ρ_f η)/√ν keeps growing there) to glycerol "
                      "near 10 °C (3.1e-3 m²/s, −2.5); E_η in [0, 70] kJ/mol (liquids' viscosity falls with T; "
                      "glycerol ≈ 60 kJ/mol).  Off values (the signature's probe and the first start): water; "
                      "typical (a second start): water's √(ρ_f η) and the centre of the ν and E_η ranges."),
    Effect("modulus_temperature", "temperature dependence of the modulus",
           "An extra log-linear slope of E with temperature (physmodel.temperature.LogLinear) and a "
           "curvature, E → E·exp(c (T − T_ref) + c2 (T − T_ref)²): gain and resonance move with T "
           "(c2 covers a law of another shape, e.g. linear in T).",
           "physics.md §7; seed 000 Fig. 6, seed 001 (resonance falls with T)",
           "parameter", (P("slope", "1/K", 0.0, -0.03, 0.03, -0.01, "extra d ln E / dT"), _CURV),
           quantities=("M", "H", "S"), needs_temperatures=True, apply=_p_modulus_T),
    Effect("diffusivity_temperature", "temperature dependence of the diffusivity",
           "An extra Arrhenius activation energy for d (physmodel.temperature.Arrhenius; and Rp by "
           "Nernst-Einstein) and a curvature exp(c2 (T − T_ref)²) (a Q10 or VTF law of another author): "
           "the charge dynamics speed up with T.", "physics.md §7 (Nafion 10.5-18 kJ/mol)",
           "parameter", (P("activation_energy", "J/mol", 0.0, -60e3, 60e3, 20e3, "extra activation energy of d"),
                         _CURV),
           needs_temperatures=True, apply=_p_diffusivity_T),
    Effect("permittivity_temperature", "temperature dependence of the permittivity",
           "An extra log-linear slope of κe with temperature and a curvature, "
           "κe → κe·exp(c (T − T_ref) + c2 (T − T_ref)²).",
           "physics.md §7 (water permittivity, Malmberg & Maryott 1956)", "parameter",
           (P("slope", "1/K", 0.0, -0.05, 0.05, 0.015, "extra d ln κe / dT"), _CURV),
           needs_temperatures=True, apply=_p_permittivity_T),
    Effect("water_uptake", "water uptake with temperature",
           "Swelling h → h (1 + u ΔT) through the thickness and L, W → ·(1 + s u ΔT) in the plane "
           "(s = 0: thickness only, s = 1: isotropic) with the fixed anions diluted by the volume, "
           "C⁻ → C⁻/((1 + u ΔT)(1 + s u ΔT)²): stiffness, resonance, Debye length and gain change with T.",
           "Nafion water uptake (Hinatsu et al. 1994, J. Electrochem. Soc. 141:1493)", "parameter",
           (P("swelling", "1/K", 0.0, -0.008, 0.008, 0.004, "relative thickness change per kelvin"),
            P("in_plane_share", "1", 0.0, 0.0, 1.0, 0.5, "in-plane over through-thickness swelling",
              limits=("lower", "upper"))),
           needs_temperatures=True, apply=_p_water_uptake, switch="swelling"),
    Effect("fractional_transport", "fractional-order charge transport (constant phase inside the polymer)",
           "Anomalous (fractional, order β) charge relaxation in the polymer: every s of the "
           "transport sub-model becomes ω_c (s/ω_c)^β, a constant-phase double layer inside the "
           "transport (see module docstring; not the series interface CPE).",
           "Macdonald (Impedance Spectroscopy); Evangelista & Lenzi, fractional PNP models", "kernel",
           (P("beta", "1", 1.0, 0.5, 1.0, 0.85, "fractional order β", limits=("upper",)),), quantities=("M", "H", "Z", "I", "S"),
           apply=fractional_s, batchable=False),
]

__all__ = ["EFFECTS", "CPE_REFERENCE_HZ", "SECOND_MODE_RATIO", "polymer_area_resistance", "fractional_s"]
