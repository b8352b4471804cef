"""High-precision (mpmath, 50 digits) reference of the closed forms, written directly from
seed 002 eqs. (10)-(15) and the sensing kernels, with no series, no rewriting and no
cancellation guards: the 50 digits absorb every cancellation the fast path must avoid.

Kept apart from the test so it can be reused (pvlib/scipy style: generator beside its test).
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
from scipy import constants

F = constants.physical_constants["Faraday constant"][0]
R = constants.R
DPS = 50


def _mpf(v):
    return mp.mpf(float(v)) if np.isfinite(v) else mp.inf


def _quantities(p: dict, s, kernel: str) -> dict:
    """All quantities at one mp complex ``s`` from mp parameters ``p`` (direct closed forms)."""
    K = F**2 * p["d"] * p["C_minus"] / (p["kappa_e"] * R * p["T"])
    g = p["h"] * mp.sqrt((s + K) / p["d"])
    tg = mp.tanh(g)
    den = s * g + K * tg
    theta = s * p["W"] * p["kappa_e"] * g * (s + K) / (p["h"] * den)
    frac = 1 / (1 + p["r2"] * theta)
    A = theta * frac + (0 if p["Rp"] == mp.inf else 2 / p["Rp"])
    x = mp.sqrt(p["r1"] * A) * p["L"]
    if x == 0:
        X, xcoth = mp.mpf(1) / 2, mp.mpf(1)
    else:
        X = -(1 - mp.sech(x) - mp.tanh(x) * x) / x**2
        xcoth = x / mp.tanh(x)
    Z = 2 * xcoth / (A * p["L"])
    I = mp.mpf(2) / 3 * p["W"] * p["h"] ** 3
    H = -(p["L"] ** 2 * p["alpha0"] * p["W"]) / (2 * p["E"] * I) * K * p["kappa_e"] * (g - tg) / den * 2 * X * frac
    wn = p["omega_n"]
    G = wn**2 / (s**2 + 2 * p["xi"] * wn * s + wn**2)
    if kernel == "boundary_charge":
        S = s * p["W"] * p["a0"] * 3 * p["E"] * p["h"] ** 2 / p["L"] * (g - tg) / (g**2 * tg) * X * frac
    else:
        S = s * 3 * p["E"] * I / p["L"] ** 3 * H
    return {"Z": Z, "H": H, "G": G, "M": H * G, "S": S}


def reference(state_row: dict, s: complex, kernel: str = "boundary_charge") -> dict:
    """Z, H, G, M, S at one complex ``s`` for one parameter row (floats, SI, per-slice r1/r2/Rp)."""
    with mp.workdps(DPS):
        p = {k: _mpf(v) for k, v in state_row.items()}
        return {k: complex(v) for k, v in _quantities(p, mp.mpc(s.real, s.imag), kernel).items()}


def transfer_mp(state_row: dict, quantity: str, kernel: str = "boundary_charge"):
    """An mpmath function s ↦ quantity(s) (mp complex in, mp complex out) for invertlaplace."""
    p = {k: _mpf(v) for k, v in state_row.items()}
    return lambda s: _quantities(p, s, kernel)[quantity]
