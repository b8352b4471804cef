"""Beam mechanics: Euler-Bernoulli cantilever, quasi-static bending and the first mode.

Seed 002 eqs. (12), (15); physics.md §3.  The quasi-static tip deflection of a cantilever under a
bending moment per unit length m(z) is w(L) = ∫0^L (L − z) m(z)/(E I) dz; under a uniform moment
M it is M L²/(2 E I).  The first bending mode is appended as a unit-DC-gain second-order system

    G(s) = ωn² / (s² + 2 ξ ωn s + ωn²)

(seed 002 prints ωn in the numerator; see :mod:`physmodel.parameter_sets` for what that does to
its α0).  Scaling the mode to the quasi-static gain folds the higher modes into mode 1, which is
fine below ωn.
"""

from __future__ import annotations

import numpy as np


def second_moment(W, h):
    """I = (2/3) W h³ [m⁴] for a strip of width W and thickness 2h."""
    return 2.0 / 3.0 * W * h**3


def tip_stiffness(E, W, h, L):
    """Static tip stiffness of the cantilever 3 E I / L³ [N/m]."""
    return 3.0 * E * second_moment(W, h) / L**3


def first_mode(s, omega_n, xi):
    """G(s) = ωn²/(s² + 2ξωn s + ωn²) [-]."""
    wn = np.asarray(omega_n)
    return wn * wn / (s * s + 2.0 * xi * wn * s + wn * wn)


def surface_curvature_per_tip(L, z):
    """Curvature of a cantilever with a tip load per unit tip displacement, 3 (L − z)/L³ [1/m²]."""
    return 3.0 * (L - z) / L**3


# --------------------------------------------------------------------------- modal expansion
# Euler-Bernoulli cantilever, clamped at ξ = z/L = 0, free at ξ = 1.  Modes φ_n(ξ) with
# cos λ cosh λ = −1, normalised ∫0^1 φ_n² dξ = 1, ω_n = ω1 (λn/λ1)² (Meirovitch, Fundamentals of
# Vibrations, §8).  A distributed active moment m(ξ) (curvature EI w'' = m at a free section)
# drives mode n by Q_n = ∫0^1 m φ_n'' dξ (two integrations by parts with φ(0) = φ'(0) = 0 and
# m-free boundary terms), and the tip deflection over the quasi-static one is
#
#     w(1)/w_qs = Σ_n π_n (g_n),   π_n = φ_n(1) Q_n / (λ_n⁴ X),   X = ∫0^1 (1 − ξ) m dξ,  Σ π_n = 1,
#
# with g_n the unit-DC-gain response of mode n.  For the electrode line of
# :mod:`physmodel.electrode` the moment decays as m = cosh(x(1 − ξ))/cosh x (x the line argument),
# X = X(x) of :func:`physmodel.numerics.line_kernels`, and (integrating φ'' against cosh twice)
#
#     Q_n(x) = sech x·φ_n'(1) + x² B_n/(λ_n⁴ − x⁴),
#     B_n = x² sech x·φ_n'(1) + 2 σ_n λ_n³ − 2 x tanh x·λ_n²,  σ_n = (cosh λ + cos λ)/(sinh λ + sin λ),
#
# (a removable singularity at x⁴ = λ_n⁴, evaluated there as the mean of two neighbours).  For a
# uniform moment (x = 0): π_n = 2 φ_n(1) φ_n'(1)/λ_n⁴ = 0.890772, 0.078774, 0.016495, 0.006018, …
_ROOTS_CACHE: dict[int, np.ndarray] = {}


def cantilever_roots(n_modes: int) -> np.ndarray:
    """First ``n_modes`` roots λ_n of cos λ cosh λ = −1 (clamped-free) [-].

    Newton iterations on cos λ + sech λ = 0 from (n − ½)π; for λ > 20 the root equals (n − ½)π
    + (−1)^n·2e^{−λ} to rounding."""
    n_modes = int(n_modes)
    if n_modes < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes}")
    if n_modes not in _ROOTS_CACHE:
        lam = (np.arange(1, n_modes + 1) - 0.5) * np.pi
        for _ in range(60):
            f = np.cos(lam) + 1.0 / np.cosh(lam)
            df = -np.sin(lam) - np.tanh(lam) / np.cosh(lam)
            lam = lam - f / df
        _ROOTS_CACHE[n_modes] = lam
    return _ROOTS_CACHE[n_modes].copy()


def mode_tip_values(lam):
    """``(φ_n(1), φ_n'(1), σ_n)`` of the normalised clamped-free modes with roots ``lam``.

    φ = (cosh − σ sinh)(λξ) − cos λξ + σ sin λξ; cosh λ − σ sinh λ is formed from 1 − σ =
    (sin λ − cos λ − e^{−λ})/(sinh λ + sin λ) without cancellation."""
    lam = np.asarray(lam, dtype=float)
    e = np.exp(-lam)
    den = 0.5 * (1.0 - e * e) + e * np.sin(lam)                 # (sinh λ + sin λ) e^{−λ}
    one_m = e * (np.sin(lam) - np.cos(lam) - e) / den           # 1 − σ
    sig = 1.0 - one_m
    hc = 0.5 * (one_m / e + (1.0 + sig) * e)                    # cosh λ − σ sinh λ
    hs = 0.5 * (one_m / e - (1.0 + sig) * e)                    # sinh λ − σ cosh λ
    phi1 = hc - np.cos(lam) + sig * np.sin(lam)
    dphi1 = lam * (hs + np.sin(lam) + sig * np.cos(lam))
    return phi1, dphi1, sig


def _tanh_sech(x):
    """tanh x and sech x for Re x ≥ 0 without overflow."""
    e = np.exp(-x)
    e2 = e * e
    return (1.0 - e2) / (1.0 + e2), 2.0 * e / (1.0 + e2)


def _q_closed(x, lam, dphi1, sig):
    th, sech = _tanh_sech(x)
    x2 = x * x
    B = x2 * sech * dphi1 + 2.0 * sig * lam**3 - 2.0 * x * th * lam**2
    return sech * dphi1 + x2 * B / (lam**4 - x2 * x2)


def moment_participation(x, n_modes: int) -> np.ndarray:
    """π_n(x) of the first ``n_modes`` modes for the moment profile cosh(x(1 − ξ))/cosh x [-].

    ``x``: line argument (Re x ≥ 0), any shape; returns shape x.shape + (n_modes,).  x = 0 gives
    the uniform-moment participations (Σ over all modes = 1)."""
    from .numerics import line_kernels

    lam = cantilever_roots(n_modes)
    phi1, dphi1, sig = mode_tip_values(lam)
    x = np.asarray(x, dtype=complex)[..., None]
    near = np.abs(x**4 / lam**4 - 1.0) < 1e-4
    if np.any(near):
        d = 2e-4
        xs = np.where(near, x * (1 + d), x)
        Q = _q_closed(xs, lam, dphi1, sig)
        Q = np.where(near, 0.5 * (Q + _q_closed(x * (1 - d), lam, dphi1, sig)), Q)
    else:
        Q = _q_closed(x, lam, dphi1, sig)
    x0 = x[..., 0]
    X = line_kernels(np.atleast_1d(x0), want_xcoth=False)[0].reshape(x0.shape)[..., None]
    return phi1 * Q / (lam**4 * X)


def modes_for_band(omega_1, omega_max, minimum: int = 4, maximum: int = 16) -> int:
    """Number of modes for a modal sum up to ``omega_max`` [rad/s]: every mode below 10·omega_max
    plus one, within [minimum, maximum].  The rest enter quasi-statically through Σ π_n = 1; the
    dynamic error this leaves is about π_{N+1} (omega_max/ω_{N+1})² ≤ 1e-2·π_{N+1}."""
    w1 = float(np.min(omega_1))
    lam = cantilever_roots(maximum)
    n = int(np.sum(w1 * (lam / lam[0]) ** 2 < 10.0 * float(omega_max))) + 1
    return int(min(max(n, minimum), maximum))


def modal_tip_response(s, omega_1, xi_1, x, n_modes: int, viscous_share=1.0):
    """Tip deflection over the quasi-static one of the cantilever with all modes [-]:

        1/ε + Σ_{n ≤ N} π_n(x) (g_n − 1/ε),  g_n = 1/(ε + 2 ξ1 ν (ω1/ω_n)(s/ω_n) + (s/ω_n)²),
        ε = 1 + 2 ξ1 (1 − ν) s/ω1

    — Rayleigh damping ζ_n = ξ1 (ν ω1/ω_n + (1 − ν) ω_n/ω1): a mass-proportional share ν and a
    stiffness-proportional (Kelvin–Voigt, E(1 + b s)) share 1 − ν, which also carries the
    quasi-static residual 1/ε of the modes above N.  Mode 1 with ν = 1 alone is :func:`first_mode`.
    ``s`` [1/s], ``omega_1`` [rad/s], ``xi_1``, ``x`` (line argument), ``viscous_share`` ν: all
    broadcast together."""
    lam = cantilever_roots(n_modes)
    s = np.asarray(s)
    nu = np.asarray(viscous_share, dtype=float)
    eps = 1.0 + 2.0 * xi_1 * (1.0 - nu) * s / omega_1
    w1 = np.asarray(omega_1)[..., None]
    wn = w1 * (lam / lam[0]) ** 2
    sn = s[..., None] / wn
    g = 1.0 / (eps[..., None] + 2.0 * np.asarray(xi_1)[..., None] * nu[..., None] * (w1 / wn) * sn + sn * sn)
    pi = moment_participation(x, n_modes)
    return 1.0 / eps + np.sum(pi * (g - 1.0 / eps[..., None]), axis=-1)


def modal_damping_response(s, omega_1, xi_1, zeta_higher, x, n_modes: int):
    """Tip deflection over the quasi-static one with modal (not Rayleigh) damping [-]:

        1 + Σ_{n ≤ N} π_n(x) (g_n − 1),   g_1 = first_mode(s, ω1, ξ1),
        g_n = 1/(1 + 2 ζ_h s/ω_n + (s/ω_n)²)  (n ≥ 2),  ω_n = ω1 (λn/λ1)²,

    the modes above N quasi-static (g_n = 1, through Σ π_n = 1).  Every mode above the first has
    the same damping ratio ``zeta_higher`` ζ_h (the usual modal-damping assumption, Clough &
    Penzien, Dynamics of Structures, §12-5; Meirovitch, Fundamentals of Vibrations, §7.16), so the
    higher modes' damping is one number, independent of ξ1 (which the first mode's fit absorbs
    together with the fluid and the polymer's losses).  ``s`` [1/s], ``omega_1`` [rad/s],
    ``xi_1``, ``zeta_higher``, ``x`` (line argument of :mod:`physmodel.electrode`): all
    broadcast together."""
    lam = cantilever_roots(n_modes)
    s = np.asarray(s)
    w1 = np.asarray(omega_1, dtype=float)[..., None]
    wn = w1 * (lam / lam[0]) ** 2
    z = np.where(np.arange(n_modes) == 0, np.asarray(xi_1, dtype=float)[..., None],
                 np.asarray(zeta_higher, dtype=float)[..., None])
    sn = s[..., None] / wn
    g = 1.0 / (1.0 + 2.0 * z * sn + sn * sn)
    pi = moment_participation(x, n_modes)
    return 1.0 + np.sum(pi * (g - 1.0), axis=-1)


def tip_force_participation(n_modes: int) -> np.ndarray:
    """π_n = 3 φ_n(1)²/λ_n⁴ of a cantilever loaded by a force at its tip (the sensing loading: a
    probe or slit pushing the tip) [-]: the share of mode n in the static tip deflection F L³/(3EI)
    (w(L) = Σ φ_n(1)² F L³/(EI λ_n⁴); Σ π_n = 1): 0.970688, 0.024716, 0.003152, …"""
    lam = cantilever_roots(n_modes)
    phi1, _, _ = mode_tip_values(lam)
    return 3.0 * phi1 * phi1 / lam**4
