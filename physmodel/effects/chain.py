"""Effects of the measurement chain: amplifier, acquisition delay, elements in series with the
strip, the excitation coupling of a sensor, and (out of library) a fixture resonance.

Series elements (``level = "series"``) return an impedance ``Z_s(s)`` [Ω]; the model adds all of
them once, ``Z_tot = Z + ΣZ_s``, and scales the driven quantities by the divider ``Z/(Z + ΣZ_s)``
(actuator: the strip sees that part of the source voltage; sensor: the short-circuit current
through the strip's own impedance), so several series elements compose exactly.

Interface constant-phase element (``series_cpe``).  The electrode double layer of an IPMC is most
often modelled in impedance spectroscopy by a CPE in series with the strip,
``Z_cpe = 1/(Q (jω)^n)`` (Macdonald & Barsoukov, Impedance Spectroscopy, 2nd ed. §2.2.2.2;
n = 1 an ideal capacitor; 0.9-1 for metal electrodes, down to 0.5 for porous ones).  Here
``Q = W L / S'`` with the area-specific parameter ``S'`` [Ω·m²·s^(−n)] (0 = off), so one value
describes strips of any size.  This is an element *in series*, distinct from the fractional
charge transport inside the polymer (``fractional_transport`` in :mod:`physmodel.effects.physical`).
"""

from __future__ import annotations

import numpy as np

from ..transport import debye_rate
from .base import Effect, P

_MEAS = ("M", "H", "Z", "I", "S")


def _r_amplifier(q, ctx, v):
    return 1.0 / ((1.0 + ctx.s * v["time_constant"]) * (1.0 + ctx.s * v["second_time_constant"]))


def _r_delay(q, ctx, v):
    return np.exp(-ctx.s * v["delay"])


def _r_coupling(q, ctx, v):
    st = ctx.st
    from ..beam import first_mode

    G1 = first_mode(ctx.s, st.omega_n, st.xi)
    # tip driven through a spring k_c: w_tip/w_drive = 1/(1 + k_b(s)/k_c), k_b(s) = k_tip/G1(s)
    return 1.0 / (1.0 + v["compliance_ratio"] / G1)


def _r_fixture(q, ctx, v):
    s = ctx.s
    wf = 2 * np.pi * v["frequency_hz"]
    zp = v["damping"]
    zz = zp * (1.0 - v["depth"])
    return (s * s + 2 * zz * wf * s + wf * wf) / (s * s + 2 * zp * wf * s + wf * wf)


def _z_series_resistance(ctx, v):
    return v["resistance"]


def cpe_impedance(s, S_area, n, W, L):
    """Z_cpe = S'/(W L) · s^(−n) [Ω] of an interface CPE with area-specific S' [Ω·m²·s^(−n)]
    (principal power: arg = −n π/2 on the imaginary axis)."""
    return S_area / (W * L) * s ** (-n)


def _z_series_cpe(ctx, v):
    st = ctx.st
    return cpe_impedance(ctx.s, v["S_area"], v["n"], st.W, st.L)


def double_layer_area_impedance(p) -> float:
    """2λ/κe [Ω·m²·s] with λ = sqrt(d/K): the inverse area capacitance of the strip's own two
    double layers at T_ref (seed 002: ≈ 0.05), the scale of an interface CPE's S'."""
    K = float(debye_rate(p.d, p.C_minus, p.kappa_e, p.T_ref))
    return 2.0 * np.sqrt(p.d / K) / p.kappa_e


def _cpe_bounds(p):
    s0 = double_layer_area_impedance(p)
    return {"S_area": (0.0, min(50.0 * s0, 1e3), s0)}


EFFECTS = [
    Effect("amplifier_bandwidth", "measurement-amplifier bandwidth",
           "The poles of the measuring amplifier (transimpedance or displacement sensor), "
           "1/((1 + s τa)(1 + s τb)): a dominant pole and a non-dominant one (0 = single pole); "
           "independent of temperature.", "seed 000 Fig. 4 (op-amp chain); Franco, Design with "
           "Operational Amplifiers (two-pole open-loop response)",
           "response", (P("time_constant", "s", 0.0, 0.0, 0.05, 1.5e-3, "τa = 1/ωa"),
                        P("second_time_constant", "s", 0.0, 0.0, 0.05, 3e-4, "τb of a second pole")),
           quantities=_MEAS, apply=_r_amplifier),
    Effect("time_delay", "acquisition time delay",
           "A pure delay e^{-sτ} between excitation and acquisition channels: phase −ωτ, magnitude "
           "unchanged.", "Pintelon & Schoukens, System Identification (2012), ch. 2", "response",
           (P("delay", "s", 0.0, 0.0, 0.05, 1e-3, "delay τ"),), quantities=_MEAS, apply=_r_delay),
    Effect("series_resistance", "lumped series resistance",
           "A lumped resistance Rs in series with the strip (leads, clamp contacts, source/amplifier "
           "input resistance): divider Z/(Z + Rs) on the driven or measured signal.",
           "standard equivalent-circuit practice (Barsoukov & Macdonald, Impedance Spectroscopy)",
           "series", (P("resistance", "Ohm", 0.0, 0.0, 1e4, 20.0, "series resistance Rs"),),
           quantities=_MEAS, apply=_z_series_resistance),
    Effect("series_cpe", "interface constant-phase element in series",
           "An electrode double-layer CPE in series with the strip, Z_cpe = S'/(W L)·(jω)^(−n): "
           "divider Z/(Z + Z_cpe) on the driven or measured signal, a low-frequency roll-off with "
           "constant phase −nπ/2 of the added impedance.",
           "Macdonald & Barsoukov, Impedance Spectroscopy (2005) §2.2.2.2; CPE exponent 0.9-1 for "
           "metal electrodes", "series",
           (P("S_area", "Ohm m^2 s^-n", 0.0, 0.0, 1e3, 0.05, "area-specific CPE coefficient S' = W L/Q"),
            P("n", "1", 0.9, 0.5, 1.0, 0.8, "CPE exponent n", limits=("upper",))),
           quantities=_MEAS, apply=_z_series_cpe, switch="S_area", fit_bounds=_cpe_bounds,
           bounds_doc="S' in [0, 50·2λ/κe]: up to fifty times the inverse area capacitance of the strip's "
                      "own double layers at T_ref (≈ 2.5 Ω·m²·s^(−n) for seed 002); typical 1× it; n in [0.5, 1]."),
    Effect("coupling_compliance", "excitation-coupling compliance",
           "The imposed tip displacement is applied through a spring: w_tip/w_drive = "
           "1/(1 + ε/G1(s)), ε = tip stiffness / coupling stiffness.", "seed 000 §III (imposed tip "
           "displacement)", "response",
           (P("compliance_ratio", "1", 0.0, 0.0, 5.0, 0.2, "ε = k_tip/k_coupling"),),
           kinds=("sensor",), quantities=("S",), apply=_r_coupling),
]

#: Effects kept OUT of the candidate list: used by blind generators only.
OUT_OF_LIBRARY = [
    Effect("fixture_resonance", "fixture resonance (out of library)",
           "A notch/resonance of the test fixture: (s² + 2ζz ωf s + ωf²)/(s² + 2ζ ωf s + ωf²), "
           "ζz = ζ (1 − depth).", "generator only", "response",
           (P("frequency_hz", "Hz", 1.0, 0.01, 1e4, 5.0, "fixture resonance"),
            P("depth", "1", 0.0, 0.0, 1.0, 0.6, "notch depth (0 off)"),
            P("damping", "1", 0.05, 0.001, 1.0, 0.1, "damping ratio of the fixture")),
           quantities=_MEAS, apply=_r_fixture, switch="depth"),
]

__all__ = ["EFFECTS", "OUT_OF_LIBRARY", "cpe_impedance", "double_layer_area_impedance"]
