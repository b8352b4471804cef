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
