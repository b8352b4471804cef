"""Distributed electrode resistance: the transmission-line sub-model (seed 002 §2.2.2, Fig. 3).

Each slice dz between the electrodes is the polymer branch (impedance 2/θ per length, θ from
:mod:`physmodel.transport`) in series with the through-thickness resistance r2 of each electrode
(2 r2 per length), all in parallel with the leakage Rp.  The slice admittance per unit length is
A(s)/2 with

    A(s) = θ / (1 + r2 θ) + 2/Rp          (seed 002 eq. 11 with r2 = r2'/W, Rp = Rp'/W)

and the electrodes carry r1 per unit length each, so the line has propagation constant
sqrt(B), B = r1 A.  With x = L sqrt(B):

    terminal impedance  Z = 2 sqrt(B) / (A tanh(sqrt(B) L)) = 2 x coth x / (A L)     (eq. 10)
    bending kernel      X(x) = (x tanh x + sech x − 1)/x²                           (eq. 14)

Topology: this is the circuit of seed 002 eq. (11) (Chen & Tan 2008): the leakage Rp spans the
whole slice, in parallel with (polymer + r2 of each electrode).  physics.md §3 sketches an
alternative re-derivation with r2 in series with (polymer ‖ Rp); the two agree when r2 = 0 or
Rp = inf.  We follow the printed model; the other topology is a discrepancy candidate.

X is also the sensing collection kernel: ∫0^L (L−z) cosh(x(L−z)/L)/cosh x dz = L² X(x).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import transport
from .numerics import line_kernels, principal_sqrt


def slice_admittance(theta, r2, Rp):
    """``(A, frac)``: A(s) = θ/(1 + r2 θ) + 2/Rp [S/m] and frac = 1/(1 + r2 θ) [-].

    ``frac`` is the part of a slice's voltage that reaches the polymer.  ``Rp = inf`` means no
    leakage; ``r2 = 0`` is an ideal through-thickness contact.
    """
    frac = r2 * theta
    frac += 1.0
    np.reciprocal(frac, out=frac)
    A = theta * frac
    A += 2.0 / Rp
    return A, frac


def line_argument(A, r1, L):
    """x = L sqrt(r1 A) [-] (principal branch, Re x ≥ 0)."""
    return principal_sqrt(A * (r1 * L * L))


class StripTerms(NamedTuple):
    """Everything the actuator and sensor share at points s: charge terms, slice and line."""

    c: transport.ChargeTerms
    frac: np.ndarray       # 1/(1 + r2 θ)
    A: np.ndarray          # slice admittance term [S/m]
    X: np.ndarray          # bending / collection kernel X(x)
    xcoth: np.ndarray      # x coth x (None unless asked for)


def strip_terms(p, s, want_xcoth: bool) -> StripTerms:
    """Charge dynamics → polymer admittance → slice → electrode line, for parameter values ``p``
    (a mapping like :class:`~physmodel.params.State`) at Laplace points ``s``."""
    c = transport.charge_terms(s, p["h"], p["d"], p["K"])
    theta = transport.polymer_admittance(p["W"], p["h"], p["kappa_e"], c)
    A, frac = slice_admittance(theta, p["r2"], p["Rp"])
    X, xcoth = line_kernels(line_argument(A, p["r1"], p["L"]), want_xcoth=want_xcoth)
    return StripTerms(c, frac, A, X, xcoth)


def terminal_impedance(A, L, xcoth):
    """Z = 2 x coth x / (A L) [Ω] (seed 002 eq. 10)."""
    return 2.0 * xcoth / (A * L)
