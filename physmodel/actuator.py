"""The Chen-Tan IPMC actuator: impedance Z, quasi-static actuation H, first mode G, M = H·G.

Seed 002 eqs. (10)-(16) (after Chen & Tan, IEEE/ASME T-Mech 13(5), 2008), composed from the
sub-models :mod:`~physmodel.transport` (charge dynamics), :mod:`~physmodel.electrode`
(distributed electrode resistance) and :mod:`~physmodel.beam` (mechanics):

    Z(s) = 2 x coth x / (A L)                                   [Ω]    eq. (10)
    H(s) = −L² Φ(s) X(x) / (E I (1 + r2 θ))                       [m/V]  eq. (13)
         = −(L² α0 W)/(2EI) · Kκe(γ − tanh γ)/(sγ + K tanh γ) · 2X/(1 + r2 θ)
    G(s) = ωn² / (s² + 2ξωn s + ωn²)                             [-]    eq. (15), unit DC gain
    M(s) = H(s) G(s)                                            [m/V]  eq. (16)

Sign convention of eq. (13): with α0 < 0 a positive voltage gives a positive tip displacement.
"""

from __future__ import annotations

import numpy as np

from . import beam, electrode
from .model import PhysicsModel
from .numerics import line_kernels, principal_sqrt, tanh_and_gmt

UNITS = {"Z": "Ohm", "H": "m/V", "G": "1", "M": "m/V", "I": "A/V"}
DESCRIPTIONS = {
    "Z": "terminal impedance V/I",
    "H": "quasi-static actuation: tip displacement per volt without the mode",
    "G": "first bending mode (unit DC gain)",
    "M": "actuation: tip displacement per volt, H*G",
    "I": "terminal admittance I/V = 1/Z",
}


def actuator_kernel(p, s, quantities=("Z", "H", "G", "M")) -> dict:
    """All actuator quantities at points ``s`` for parameter values ``p`` (see :class:`State`)."""
    K = p["K"]
    W, h, L = p["W"], p["h"], p["L"]
    want_z = "Z" in quantities or "I" in quantities
    c, frac, A, X, xcoth = electrode.strip_terms(p, s, want_xcoth=want_z)
    out = {}
    if want_z:
        Z = electrode.terminal_impedance(A, L, xcoth)
        if "Z" in quantities:
            out["Z"] = Z
        if "I" in quantities:
            out["I"] = 1.0 / Z
    need_g = "G" in quantities or "M" in quantities
    wn = p["omega_n"]
    if need_g:
        # G = ωn²/(s² + 2ξωn s + ωn²); keep the denominator, fold ωn² into the gain below
        gden = s + 2.0 * p["xi"] * wn
        gden *= s
        gden += wn * wn
    if "G" in quantities:
        out["G"] = (wn * wn) / gden
    if "H" in quantities or "M" in quantities:
        # H = −L² Φ X frac/(E I), with Φ = α0 W κe K (γ − tanh γ)/(sγ + K tanh γ)
        # (transport.moment_coupling); constants folded into one scalar multiplication.
        gain = -(L * L) / (p["E"] * beam.second_moment(W, h)) * (p["alpha0"] * W * p["kappa_e"] * K)
        H = c.gmt / c.den
        H *= X
        H *= frac
        if "H" in quantities:
            out["H"] = H * gain
        if "M" in quantities:
            H /= gden
            H *= gain * wn * wn
            out["M"] = H
    return out


class ActuatorModel(PhysicsModel):
    """Voltage-driven IPMC actuator (Chen-Tan), for one parameter set or a batch.

    >>> from physmodel import ActuatorModel, get_parameter_set
    >>> m = ActuatorModel(get_parameter_set("seed002_table3"))
    >>> r = m.frequency_response([1.0, 10.0], temperature_c=[25, 45])
    >>> r["M"].shape     # (n_sets, n_T, n_f), tip displacement per volt [m/V]
    (1, 2, 2)
    """

    kind = "actuator"
    primary_quantity = "M"

    quantities = ("Z", "H", "G", "M", "I")
    units = UNITS
    descriptions = DESCRIPTIONS

    def _kernel(self, p, s, quantities):
        return actuator_kernel(p, s, quantities)

    def dc_gain(self, temperature_c) -> dict:
        """Closed-form DC limits (n_sets, n_T): ``H0 = M0`` [m/V] and ``Z0`` [Ω] (inf without leakage).

        At s = 0: θ = 0, so A = 2/Rp, x0 = L sqrt(2 r1/Rp), Φ(0) = α0 W κe (γ0 − tanh γ0)/tanh γ0.
        """
        st = self.state(temperature_c)
        g0 = st.h * principal_sqrt(st.K / st.d)
        t0, gmt0 = tanh_and_gmt(g0)
        A0 = (2.0 / st.Rp).astype(complex)
        x0 = st.L * principal_sqrt(st.r1 * A0)
        X0, xcoth0 = line_kernels(x0)
        phi0 = st.alpha0 * st.W * st.kappa_e * gmt0 / t0
        H0 = -(st.L**2) * phi0 * X0 / (st.E * st.second_moment)
        with np.errstate(divide="ignore"):
            Z0 = np.where(np.isinf(st.Rp), np.inf, np.real(2.0 * xcoth0 / (np.where(A0 == 0, 1, A0) * st.L)))
        return {"H0": np.real(H0)[..., 0], "M0": np.real(H0)[..., 0], "Z0": Z0[..., 0]}

    def reduced(self, temperature_c: float, taylor_order: int = 3, set_index: int = 0, include_mode: bool = True):
        """Seed 002 §2.2.4 finite-order model H_r·G (or H_r) as a python-control TransferFunction."""
        from .reduced import reduced_actuator

        st = self.state([temperature_c]).take(set_index, 0)
        return reduced_actuator(st, taylor_order, include_mode=include_mode)
