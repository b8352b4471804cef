r"""Effects in their physical form (issue 27 item 4): higher bending modes with their own damping,
an interface constant-phase element distributed along the electrodes, and a compliant clamp mount.

``higher_modes`` (actuator, M).  The Euler–Bernoulli cantilever's modal expansion
(:func:`physmodel.beam.modal_damping_response`): frequencies ω_n = ω1 (λ_n/λ1)² from the roots of
1 + cos λ cosh λ = 0 (λ1..3 = 1.87510, 4.69409, 7.85476; ω2/ω1 = 6.2669), participations
π_n(x) of the moment profile the electrode line gives (0.890772, 0.078774, 0.016495, … for a
uniform moment, :func:`physmodel.beam.moment_participation`), every mode above the first with one
modal damping ratio ζ_h.  Tied to the strip's first mode (ωn, ξ of the base) and its electrode
line, so the effect has one physical parameter, ζ_h, and a weight c (1: the modal expansion; 0:
the base, which folds every mode into the first):

    M = H_qs·[g1 + c (T − g1)],   T = 1 + Σ_{n ≤ N} π_n(x) (g_n − 1)

(Meirovitch, Fundamentals of Vibrations (2001) §7.16, §8.7; modal damping: Clough & Penzien,
Dynamics of Structures, 2nd ed. §12-5).  ``second_mode`` is the same expansion with Rayleigh
damping tied to ξ1 (ζ_n = ξ1 (ν ω1/ω_n + (1 − ν) ω_n/ω1)) and a Kelvin–Voigt residual; the two
coincide for one mode above the first when ζ_h equals its Rayleigh value, so they are declared
confusable (:data:`CONFUSABLE`).

``distributed_cpe`` (all kinds and quantities).  The electrode/polymer interface as a
constant-phase element *in every slice* of the transmission line (de Levie's porous electrode with
a CPE interface: Lasia, Electrochemical Impedance Spectroscopy and its Applications (2014) §9.3,
eqs. 9.31–9.40; CPE: Macdonald & Barsoukov, Impedance Spectroscopy (2005) §2.2.2.2).  Per unit
length, the two interfaces add the impedance z_cpe = S'/W·s^(−n) in series with the polymer branch
and the through-thickness resistances (seed 002 eq. 11, :mod:`physmodel.electrode`), i.e. each
electrode's r2 becomes r2 + S'/(2W)·s^(−n): the slice admittance, the part of a slice's voltage
that reaches the polymer, the line argument, the bending/collection kernel X(x) and the terminal
impedance x coth x/(A L/2) all change with it.  S' [Ω·m²·s^(−n)] is the same area-specific
coefficient as ``series_cpe``'s: with ideal electrodes (r1 → 0) and no leakage the two are the
same impedance (S'/(W L)·s^(−n) in series), so they are declared confusable; with resistive
electrodes the distributed CPE acts along the line (a frequency-dependent penetration depth),
which the terminal CPE cannot.  It is a ``strip``-level effect: it returns the ratio of each
quantity with and without it (the charge dynamics and the mode are untouched), applied before
the measurement chain and the series elements, whose divider sees the strip's changed impedance.

``clamp_mount`` (actuator, M).  The clamp holding the strip's root (mass m_c) sits on a compliant
stand (stiffness k_c, damping c_c to the lab) and the laser reads the tip in the lab.  With the
strip reduced to its first mode (tip-equivalent mass m_t = k_t/ω1², stiffness k_t = 3EI/L³, damping
c_t to the surrounding fluid as in the base) and the active moment an internal force pair F between
tip and clamp, the two-mass circuit

    (m_t s² + c_t s) x_t + k_t (x_t − x_c) = F,      (m_c s² + c_c s + k_c) x_c − k_t (x_t − x_c) = −F

gives the tip over that of a rigid clamp (base: x_t = F G1/k_t, G1 the base's first mode)

    R = 1/(1 + G1 μ τ²(s² + 2ξ ωn s)/(1 + 2ζ_m τ s + τ² s²)),   μ = m_t/m_c,  τ = 1/ω_m = sqrt(m_c/k_c)

— its own pole pair (the mount) and, through G1, a zero pair (the anti-resonance where the strip's
reaction cancels the mount's motion) (Den Hartog, Mechanical Vibrations (1985) §3.2, the two-mass
system; Thomson & Dahleh §5).  τ = 0 is a rigid clamp.
"""

from __future__ import annotations

import numpy as np

from .. import beam, electrode, transport
from ..numerics import line_kernels
from ..params import STATE_FIELDS
from .base import Effect, P, by_mode_count, rows_of
from .chain import double_layer_area_impedance

#: Pairs of effects the band may not separate, with the reason (declared with the effects; the
#: diagnosis's own data-driven declarations add to these).
CONFUSABLE = {
    frozenset(("higher_modes", "second_mode")): "the same modal expansion; differ only in the higher modes' "
                                                "damping law (one ratio vs Rayleigh tied to ξ1)",
    frozenset(("distributed_cpe", "series_cpe")): "the same interface CPE; identical when the electrodes are ideal "
                                                 "(r1 → 0) and there is no leakage",
    frozenset(("mount_resonance", "fixture_joint")): "the same mount resonance; differ only in where the damping "
                                                    "acts (surroundings vs joint: a zero at 1/(2ζτ))",
}


# --------------------------------------------------------------------------- higher modes
def _r_higher_modes(q, ctx, v):
    """1 + c (T/g1 − 1) on M (module doc)."""
    st, x = ctx.st, ctx.x

    def modal(rows, n):
        wn, xi = rows_of(st.omega_n, rows), rows_of(st.xi, rows)
        g1 = beam.first_mode(ctx.s, wn, xi)
        full = beam.modal_damping_response(ctx.s, wn, xi, rows_of(v["damping"], rows), rows_of(x, rows), n)
        return 1.0 + rows_of(v["weight"], rows) * (full / g1 - 1.0)

    return by_mode_count(ctx, modal)


# --------------------------------------------------------------------------- distributed CPE
def interface_impedance(s, S_area, n, W):
    """z = S'/W · s^(−n) [Ω·m]: the two interfaces' CPE per unit length of a strip of width W [m]
    with area-specific coefficient S' [Ω·m²·s^(−n)] (principal power)."""
    return S_area / W * np.asarray(s, dtype=complex) ** (-n)


def distributed_cpe_terms(p, s_kernel, s, S_area, n):
    """``(ratio_xf, ratio_z, x)``: X(x)·frac and the terminal impedance with the interface CPE over
    those without, and the line argument with it, for State values ``p`` (arrays broadcasting
    against ``s``); the charge dynamics at ``s_kernel``, the interface at ``s``."""
    terms = electrode.strip_terms(p, s_kernel, want_xcoth=True)
    theta = transport.polymer_admittance(p["W"], p["h"], p["kappa_e"], terms.c)
    r2 = p["r2"] + 0.5 * interface_impedance(s, S_area, n, p["W"])
    A, frac = electrode.slice_admittance(theta, r2, p["Rp"])
    x = electrode.line_argument(A, p["r1"], p["L"])
    X, xcoth = line_kernels(x, want_xcoth=True)
    ratio_xf = (X * frac) / (terms.X * terms.frac)
    ratio_z = (xcoth / A) / (terms.xcoth / terms.A)
    return ratio_xf, ratio_z, x


def _r_distributed_cpe(q, ctx, v):
    cache = getattr(ctx, "_dcpe", None)
    if cache is None:
        p = {k: getattr(ctx.st, k) for k in STATE_FIELDS}
        cache = ctx._dcpe = distributed_cpe_terms(p, ctx.s_kernel, ctx.s, v["S_area"], v["n"])
        ctx._x = cache[2]                 # the modal effects see the line with the CPE
    rxf, rz, _ = cache
    if q == "Z":
        return rz
    if q == "I":
        return 1.0 / rz
    if q == "G":
        return 1.0
    return rxf


def _dcpe_bounds(p):
    s0 = double_layer_area_impedance(p)
    return {"S_area": (0.0, min(50.0 * s0, 1e3), s0)}


# --------------------------------------------------------------------------- clamp mount
def clamp_mount_factor(s, G1, omega_n, xi, time_constant, damping, mass_ratio):
    """R = 1/(1 + G1 μ τ²(s² + 2ξωn s)/(1 + 2ζτs + τ²s²)) [-] (module doc); off at τ = 0 or μ = 0."""
    tau = np.asarray(time_constant, dtype=float)
    load = mass_ratio * tau * tau * (s * s + 2.0 * xi * omega_n * s) / (1.0 + 2.0 * damping * tau * s + (tau * s) ** 2)
    return 1.0 / (1.0 + G1 * load)


def _r_clamp_mount(q, ctx, v):
    st = ctx.st
    G1 = beam.first_mode(ctx.s, st.omega_n, st.xi)
    return clamp_mount_factor(ctx.s, G1, st.omega_n, st.xi, v["time_constant"], v["damping"], v["mass_ratio"])


EFFECTS = [
    Effect("higher_modes", "higher bending modes with their own damping (Euler-Bernoulli modal expansion)",
           "The cantilever's modes above the first, from beam theory: ω_n = ω1 (λn/λ1)² with 1 + cos λ cosh λ = 0 "
           "(ω2 = 6.267 ω1), participations π_n of the electrode line's moment profile (0.891, 0.079, 0.016 … "
           "for a uniform moment), one modal damping ratio ζ_h for all of them: M = H_qs·[g1 + c (T − g1)], "
           "T = 1 + Σ π_n (g_n − 1); c = 1 is the expansion, c = 0 the base.  Unlike second_mode, the higher "
           "modes' damping is not tied to ξ1.",
           "Meirovitch, Fundamentals of Vibrations (2001) §7.16, §8.7; Clough & Penzien, Dynamics of "
           "Structures §12-5 (modal damping); physmodel.beam.modal_damping_response", "response",
           (P("weight", "1", 0.0, 0.0, 1.2, 1.0, "weight c of the higher modes (1 = modal expansion)"),
            P("damping", "1", 0.05, 0.002, 1.0, 0.15, "modal damping ratio ζ_h of the modes above the first")),
           kinds=("actuator",), quantities=("M",), apply=_r_higher_modes, switch="weight"),
    Effect("distributed_cpe", "interface constant-phase element distributed along the electrodes",
           "The electrode/polymer interface as a CPE in every slice of the electrode line: each electrode's "
           "through-thickness resistance r2 becomes r2 + S'/(2W)·(jω)^(−n), so the slice admittance, the "
           "polymer's share of the slice voltage, the line's penetration depth, the bending/collection kernel and "
           "the terminal impedance all change (see physmodel.effects.forms).  With ideal electrodes it is "
           "series_cpe.", "de Levie transmission line with a CPE interface: Lasia, Electrochemical Impedance "
           "Spectroscopy and its Applications (2014) §9.3 eqs. 9.31-9.40; Macdonald & Barsoukov (2005) §2.2.2.2",
           "strip",
           (P("S_area", "Ohm m^2 s^-n", 0.0, 0.0, 1e3, 0.05, "area-specific CPE coefficient S' (both interfaces)"),
            P("n", "1", 0.9, 0.5, 1.0, 0.8, "CPE exponent n", limits=("upper",))),
           quantities=("M", "H", "Z", "I", "S"), apply=_r_distributed_cpe, switch="S_area", fit_bounds=_dcpe_bounds,
           bounds_doc="S' in [0, 50·2λ/κe] as series_cpe (the strip's own double layers' inverse area capacitance "
                      "at T_ref); n in [0.5, 1]."),
    Effect("clamp_mount", "compliant clamp mount (two-mass system)",
           "The clamp holding the root rides on a compliant stand (resonance 1/τ, damping ζ) and the strip's first "
           "mode (tip-equivalent mass μ times the clamp's) shakes it: tip/tip_rigid = 1/(1 + G1 μ τ²(s² + "
           "2ξωn s)/(1 + 2ζτs + τ²s²)) — the mount's pole pair and an anti-resonance zero pair.",
           "Den Hartog, Mechanical Vibrations (1985) §3.2 (two-mass system); Thomson & Dahleh (1998) §5; "
           "physmodel.effects.forms", "response",
           (P("time_constant", "s", 0.0, 0.0, 1.0 / (2 * np.pi * 1.0), 1.0 / (2 * np.pi * 30.0),
              "τ = 1/ω_m of the mount (0: rigid clamp)"),
            P("damping", "1", 0.05, 0.005, 1.0, 0.1, "damping ratio ζ of the mount"),
            P("mass_ratio", "1", 0.0, 0.0, 2.0, 0.05, "μ = tip-equivalent mass of the strip / mount mass")),
           kinds=("actuator",), quantities=("M",), apply=_r_clamp_mount, switch="time_constant"),
]

__all__ = ["CONFUSABLE", "EFFECTS", "clamp_mount_factor", "distributed_cpe_terms", "interface_impedance"]
