"""Charge dynamics through the thickness: the linearised Poisson-Nernst-Planck sub-model.

Seed 002 §2.2.1 (eqs. 1-7, 11, 13); physics.md §2.  For a slice of polymer x ∈ [−h, h] with
blocking electrodes the charge density obeys  ∂ρ/∂t − d ∂²ρ/∂x² + K ρ = 0,
K = F² d C⁻ / (κe R T), and in the Laplace domain ρ = 2c sinh(βx), β = sqrt((s+K)/d),
γ(s) = h β(s).  Everything below is a function of the complex Laplace variable ``s`` [1/s]
and broadcasts over arrays.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .numerics import principal_sqrt, tanh_and_gmt
from .temperature import FARADAY, R_GAS


def debye_rate(d, C_minus, kappa_e, T):
    """K = F² d C⁻ / (κe R T) [1/s] (d [m²/s], C⁻ [mol/m³], κe [F/m], T [K])."""
    return FARADAY**2 * np.asarray(d) * C_minus / (kappa_e * R_GAS * T)


def gamma(s, h, d, K):
    """γ(s) = h sqrt((s + K)/d) [-], principal branch."""
    return principal_sqrt((s + K) * (h * h / d))


class ChargeTerms(NamedTuple):
    """Intermediate terms of the charge dynamics, computed once per point and shared."""

    u: np.ndarray      # s + K            [1/s]
    g: np.ndarray      # γ(s)             [-]
    sg: np.ndarray     # s γ              [1/s]
    t: np.ndarray      # tanh γ (scalar 1.0 when Re γ > 20 everywhere)
    gmt: np.ndarray    # γ − tanh γ       [-]
    den: np.ndarray    # s γ + K tanh γ   [1/s]


def _gamma_on_axis(w, K, c):
    """γ = sqrt(c (K + jω)) for real ω and K > 0 with real arithmetic only (K + jω is in the
    right half-plane, so Re γ = sqrt(c (|K + jω| + K)/2) and Im γ = c ω/(2 Re γ), no cancellation)."""
    re = np.hypot(K, w)
    re += K
    re *= 0.5 * c
    np.sqrt(re, out=re)
    im = w * c
    im /= 2.0 * re
    g = np.empty(np.broadcast(re, im).shape, dtype=complex)
    g.real = re
    g.imag = im
    return g


def charge_terms(s, h, d, K) -> ChargeTerms:
    """The shared terms ``u, γ, sγ, tanh γ, γ − tanh γ, sγ + K tanh γ`` at points ``s``."""
    s = np.asarray(s)
    u = s + K
    c = h * h / d
    if np.iscomplexobj(s) and not s.real.any():
        g = _gamma_on_axis(s.imag, K, c)        # frequency responses: s = jω
        t, gmt = tanh_and_gmt(g, min_real=np.sqrt(c * K).min())   # Re γ ≥ γ0 on the axis
    else:
        g = principal_sqrt(u * c)
        t, gmt = tanh_and_gmt(g)
    sg = s * g
    den = sg + K * t
    return ChargeTerms(u, g, sg, t, gmt, den)


def polymer_admittance(W, h, kappa_e, c: ChargeTerms):
    """θ(s) = s W κe γ (s + K) / (h (sγ + K tanh γ)) [S/m] (seed 002 eq. 11).

    θ is the admittance per unit length of one half of the slice (electrode to mid-plane): the
    full slice between the electrodes admits θ/2.  Limits: θ → s κe W/λ (λ = sqrt(d/K), the
    double layers) for s → 0 and W κe K/h (bulk conductance of a half) for K/γ0 ≪ |s| ≪ K.
    """
    theta = c.sg * c.u
    theta /= c.den
    theta *= W * kappa_e / h
    return theta


def moment_coupling(W, kappa_e, alpha0, K, c: ChargeTerms):
    """Φ(s) = α0 W κe K (γ − tanh γ)/(sγ + K tanh γ) [N·m/m per V].

    With the electrode at x = +h held at +V/2 and the one at −h at −V/2 (blocking electrodes),
    the induced bending moment per unit length, W ∫ α0 ρ(x) x dx, equals −Φ(s)·V.
    """
    phi = c.gmt / c.den
    phi *= alpha0 * W * kappa_e * K
    return phi


def boundary_charge_kernel(c: ChargeTerms):
    """k(γ) = (γ − tanh γ)/(γ² tanh γ) [-] (sensing, short-circuited faces).

    With boundary charge density a0·σ at x = ±h (Farinholt-Leo / Chen et al. 2007 assumption) the
    electrode charge per unit area is a0 σ h k(γ).  k → 1/3 for γ → 0 and ~1/γ for large γ.
    """
    return c.gmt / (c.g * c.g * c.t)
