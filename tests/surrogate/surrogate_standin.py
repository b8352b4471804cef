"""STAND-IN physics data generator for the surrogate tests and benchmark.

This is *not* the project's physics model: it is a compact, self-contained evaluation of
the Chen–Tan IPMC actuator transfer function as printed in seed 002 (eqs. 10–16), with
the default temperature laws of ``shared/docs/physics.md`` §7, so that the surrogate
fitters can be exercised on infinite-dimensional (non-rational) responses before
``physmodel`` exists.  The benchmark calls only :func:`physics_sweep`; replacing its body
by a call to ``physmodel`` (returning a ``FrequencySweep`` and going through
``surrogate.from_sweep``) is the single swap point.

Model (s in rad/s):
  γ = h·sqrt((s+K)/d),  K = F² d C⁻ / (κe R T)
  θ = s W κe γ (s+K) / (h (s γ + K tanh γ)),  A = θ/(1 + r2 θ/W) + 2W/Rp,  B = (r1/W) A
  X(x) = (x tanh x + sech x − 1)/x²,  x = sqrt(B)·L
  H = g · (γ − tanh γ)/(s γ + K tanh γ) · X · 1/(1 + r2 θ/W) · (K κe / E) · ωn²/(s² + 2ξωn s + ωn²)
Parameters: seed 002 Table 3 (h = 0.125 mm, L = 15 mm, W = 4 mm, d = 3.07e-11 m²/s,
C⁻ = 941.94 mol/m³, κe = 4.47e-7 F/m, r1 = 56.44 Ω (per unit width), r2 = 8.81e-6 Ω·m,
Rp = 0.37 Ω·m²) and Table 2 (ωn = 75.4 rad/s, ξ = 0.18, E = 154 MPa at 300 K).
Temperature laws: d Arrhenius (15 kJ/mol), E log-linear −0.75 %/K (ωn ∝ √E), κe ∝ water
permittivity (Malmberg–Maryott), Rp ∝ T/d, K explicit in 1/T.
The gain g is set so that the 300 K quasi-static gain is 1 mm/V.
"""

from __future__ import annotations

import numpy as np

F_CONST = 96485.33212  # C/mol
R_CONST = 8.314462618  # J/(mol K)
T_REF_K = 300.0

PARAMS = {
    "h": 0.125e-3, "L": 15e-3, "W": 4e-3, "d": 3.07e-11, "C": 941.94, "kappa": 4.47e-7,
    "r1": 56.44, "r2": 8.81e-6, "Rp": 0.37, "wn": 75.4, "xi": 0.18, "E": 154e6,
    "Ea": 15e3, "E_slope_per_K": -0.0075,
}


def _eps_water(t_c):
    return 87.740 - 0.40008 * t_c + 9.398e-4 * t_c ** 2 - 1.410e-6 * t_c ** 3


def _tanh(z):
    z = np.asarray(z, complex)
    out = np.ones_like(z)
    small = z.real < 20
    out[small] = np.tanh(z[small])
    return out


def _x_factor(x):
    """(x tanh x + sech x − 1)/x² with a series near 0 and an overflow-free sech."""
    x = np.asarray(x, complex)
    out = np.empty_like(x)
    small = np.abs(x) < 1e-2
    xs = x[small]
    out[small] = 0.5 - xs ** 2 / 8 + 7 * xs ** 4 / 144
    xl = x[~small]
    e = np.exp(-2 * xl)
    sech = 2 * np.exp(-xl) / (1 + e)
    out[~small] = (xl * _tanh(xl) + sech - 1) / xl ** 2
    return out


def _raw(s, t_c, p):
    t_k = t_c + 273.15
    d = p["d"] * np.exp(-p["Ea"] / R_CONST * (1 / t_k - 1 / T_REF_K))
    kappa = p["kappa"] * _eps_water(t_c) / _eps_water(T_REF_K - 273.15)
    e_mod = p["E"] * (1 + p["E_slope_per_K"]) ** (t_k - T_REF_K)
    wn = p["wn"] * np.sqrt(e_mod / p["E"])
    rp = p["Rp"] * (t_k / T_REF_K) * (p["d"] / d)
    k = F_CONST ** 2 * d * p["C"] / (kappa * R_CONST * t_k)
    h, w_, L = p["h"], p["W"], p["L"]
    gam = h * np.sqrt((s + k) / d)
    th = _tanh(gam)
    theta = s * w_ * kappa * gam * (s + k) / (h * (s * gam + k * th))
    corr = 1 + p["r2"] * theta / w_
    a = theta / corr + 2 * w_ / rp
    b = (p["r1"] / w_) * a
    x = np.sqrt(b) * L
    elec = (gam - th) / (s * gam + k * th) * k * kappa / e_mod
    mode = wn ** 2 / (s ** 2 + 2 * p["xi"] * wn * s + wn ** 2)
    return elec * 2 * _x_factor(x) / corr * mode


def _gain(p):
    s0 = np.array([2j * np.pi * 1e-4])
    return 1.0 / abs(_raw(s0, T_REF_K - 273.15, p)[0])


def actuator_response(frequency_hz, temperature_c, params=None):
    """Complex tip displacement / voltage [mm/V] of the stand-in actuator."""
    p = dict(PARAMS, **(params or {}))
    f = np.asarray(frequency_hz, float)
    t = np.broadcast_to(np.asarray(temperature_c, float), f.shape)
    return _gain(p) * _raw(2j * np.pi * f, t, p)


def physics_sweep(temperatures_c, frequency_hz, *, magnitude_std_db=0.0, phase_std_deg=0.0,
                  seed=0, params=None):
    """Tidy noisy sweep (the benchmark's single swap point for ``physmodel``).

    Returns ``(frequency_hz, temperature_c, response, truth, magnitude_std_db, phase_std_deg)``
    with multiplicative log-normal magnitude noise and additive phase noise.
    """
    temps = np.asarray(temperatures_c, float)
    f1 = np.asarray(frequency_hz, float)
    f = np.tile(f1, temps.size)
    t = np.repeat(temps, f1.size)
    truth = actuator_response(f, t, params)
    rng = np.random.default_rng(seed)
    noise = (rng.normal(size=f.size) * magnitude_std_db * np.log(10) / 20
             + 1j * np.deg2rad(rng.normal(size=f.size) * phase_std_deg))
    resp = truth * np.exp(noise)
    if magnitude_std_db > 0 and phase_std_deg > 0:
        smag = np.full(f.size, float(magnitude_std_db))
        sph = np.full(f.size, float(phase_std_deg))
    else:
        smag = sph = None
    return f, t, resp, truth, smag, sph
