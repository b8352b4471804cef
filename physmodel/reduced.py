"""Finite-order (rational) actuator model of seed 002 §2.2.4, eqs. (17)-(22).

For |s| ≪ K: tanh γ ≈ 1 and γ(s) ≈ γ0 = h sqrt(K/d), so θ and A become rational in s:

    θ_r(s) = s W κe γ0 (s + K) / (h (γ0 s + K))
    A_r(s) = θ_r/(1 + r2 θ_r) + 2/Rp = N_A(s)/D_A(s)                     (degree 2/2)
    f(s)   = −(L² α0 W)/(2EI) · K κe (γ0 − 1)/(γ0 s + K)                  eq. (19)
    g(s)   = 2/(1 + r2 θ_r)                                              eq. (20)
    X_m(s) = P_m(u)/Q_m(u),  u = B L² = r1 L² A_r(s)                     eq. (21)

with, from the Taylor series of x sinh x and cosh x truncated at order m (seed 002 eq. 21,
X = (x sinh x − cosh x + 1)/(x² cosh x)):

    P_m(u) = Σ_{j=0}^{m−1} (1/(2j+1)! − 1/(2j+2)!) u^j + u^m/(2m+1)!,   Q_m(u) = Σ_{n=0}^{m} u^n/(2n)!

so that H_r = f g X_m is rational of order 2 + 2m (the pole of f cancels the zero of g), and
M_r = H_r G adds the two poles of the first mode.  Seed 002 Fig. 4: a third-order expansion
(m = 3) matches the infinite model around the first mode; lower orders do not.
"""

from __future__ import annotations

from math import factorial

import numpy as np

from .errors import IPMCError


def taylor_coefficients(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (ascending powers of u) of P_m and Q_m."""
    if not isinstance(m, (int, np.integer)) or m < 1:
        raise IPMCError(f"taylor_order must be an integer >= 1, got {m!r}")
    P = [1.0 / factorial(2 * j + 1) - 1.0 / factorial(2 * j + 2) for j in range(m)] + [1.0 / factorial(2 * m + 1)]
    Q = [1.0 / factorial(2 * n) for n in range(m + 1)]
    return np.array(P), np.array(Q)


def _scalar(st, name):
    v = np.asarray(getattr(st, name)).reshape(-1)
    if v.size != 1:
        raise IPMCError(f"reduced model needs one parameter set at one temperature; {name} has {v.size} values")
    return float(v[0])


def reduced_polynomials(st, taylor_order: int = 3, include_mode: bool = True):
    """Numerator and denominator (descending powers of s) of H_r (or M_r = H_r G)."""
    P_u, Q_u = taylor_coefficients(taylor_order)
    L, W, h = (_scalar(st, k) for k in ("L", "W", "h"))
    d, K, kap = _scalar(st, "d"), _scalar(st, "K"), _scalar(st, "kappa_e")
    r1, r2, Rp = _scalar(st, "r1"), _scalar(st, "r2"), _scalar(st, "Rp")
    E, a0 = _scalar(st, "E"), _scalar(st, "alpha0")
    wn, xi = _scalar(st, "omega_n"), _scalar(st, "xi")
    g0 = h * np.sqrt(K / d)
    EI = E * 2.0 / 3.0 * W * h**3
    P = np.polynomial.polynomial  # ascending-power arithmetic
    num_theta = W * kap * g0 * np.array([0.0, K, 1.0])        # s W κe γ0 (s + K)
    den_theta = h * np.array([K, g0])                         # h (γ0 s + K)
    D_A = P.polyadd(den_theta, r2 * num_theta)                # h(γ0 s + K) + r2 s W κe γ0 (s + K)
    N_A = num_theta.copy()
    if np.isfinite(Rp):
        N_A = P.polyadd(N_A, (2.0 / Rp) * D_A)
    c = r1 * L * L
    m = taylor_order
    num_X = np.zeros(1)
    den_X = np.zeros(1)
    term: np.ndarray
    for n in range(m + 1):
        term = np.asarray(P.polymul(P.polypow(c * N_A, n), P.polypow(D_A, m - n)))
        num_X = P.polyadd(num_X, P_u[n] * term)
        den_X = P.polyadd(den_X, Q_u[n] * term)
    # f g = −(L² α0 W)/(2EI) K κe (γ0 − 1) · 2h / D_A   (γ0 s + K cancelled)
    gain = -(L * L * a0 * W) / (2.0 * EI) * K * kap * (g0 - 1.0) * 2.0 * h
    num = gain * num_X
    den = P.polymul(D_A, den_X)
    if include_mode:
        num = num * wn * wn
        den = P.polymul(den, np.array([wn * wn, 2.0 * xi * wn, 1.0]))
    # trim exact zeros at the top (e.g. r2 = 0 lowers the degree of D_A)
    num = np.trim_zeros(num, "b")
    den = np.trim_zeros(den, "b")
    return num[::-1], den[::-1]


def reduced_actuator(st, taylor_order: int = 3, include_mode: bool = True):
    """The reduced model as a ``control.TransferFunction`` in s [rad/s], output in m/V."""
    import control

    num, den = reduced_polynomials(st, taylor_order, include_mode)
    # normalise the leading denominator coefficient for conditioning
    return control.tf(num / den[0], den / den[0])


def reduced_frequency_response(st, frequency_hz, taylor_order: int = 3, include_mode: bool = True):
    """Evaluate the reduced model at ``frequency_hz`` [Hz] by Horner on its polynomials."""
    num, den = reduced_polynomials(st, taylor_order, include_mode)
    s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)
