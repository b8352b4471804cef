"""The IPMC sensor: imposed tip displacement → short-circuit current.

Seed 000 measures a cantilever whose tip displacement w is imposed and takes the short-circuit
current i as output (µA per mm in its plots).  Two charge-generation kernels are provided
(physics.md §4); both share the electrode network of the actuator:

* ``"boundary_charge"`` (default) — Chen et al. (2007), the model seed 000 cites: the boundary
  charge density at x = ±h is a0 times the surface stress σ(z) = ±3 E h w (L − z)/L³.  Solving
  the charge equation with short-circuited faces gives an electrode charge per area
  a0 σ h (γ − tanh γ)/(γ² tanh γ).  Default because it is the published sensing model.
* ``"reciprocal"`` — Onsager reciprocity with the actuator: the current per tip displacement is
  s times the tip stiffness times the actuator's quasi-static response,
  S(s) = s (3 E I / L³) H(s).  It needs no a0 (uses α0) and is the consistent choice when one
  strip is characterised both as actuator and sensor.

With resistive electrodes each slice is a Norton source behind the polymer impedance and r2, so
the source current reaching the electrodes is i_p/(1 + r2 θ); collected through the electrode
line with kernel cosh(x(L − z)/L)/cosh x, ∫0^L (L − z)·kernel dz = L² X(x).  Hence

    S(s) = I/w = s W a0 (3 E h²/L) k(γ) X(x) / (1 + r2 θ)        [A/m]  (boundary_charge)
    S(s) = I/w = −3 s Φ(s) X(x) / (L (1 + r2 θ))                   [A/m]  (reciprocal)

Optional measurement chain: :class:`TransimpedanceChain` (seed 000 Fig. 4, v2 = (R3 R1/R2) i).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import electrode, transport
from .errors import IPMCError
from .model import DEFAULT_CHUNK, PhysicsModel

KERNELS = ("boundary_charge", "reciprocal")
UNITS = {"S": "A/m", "Z": "Ohm"}
DESCRIPTIONS = {
    "S": "short-circuit current per tip displacement I/w",
    "Z": "terminal impedance of the strip",
}


def sensor_kernel(p, s, quantities=("S",), kernel: str = "boundary_charge") -> dict:
    K = p["K"]
    W, h, L = p["W"], p["h"], p["L"]
    c, frac, A, X, xcoth = electrode.strip_terms(p, s, want_xcoth="Z" in quantities)
    out = {}
    if "S" in quantities:
        if kernel == "boundary_charge":
            S = transport.boundary_charge_kernel(c)
            S *= s
            S *= W * p["a0"] * 3.0 * p["E"] * h * h / L
        else:
            S = transport.moment_coupling(W, p["kappa_e"], p["alpha0"], K, c)
            S *= s
            S *= -3.0 / L
        S *= X
        S *= frac
        out["S"] = S
    if "Z" in quantities:
        out["Z"] = electrode.terminal_impedance(A, L, xcoth)
    return out


class SensorModel(PhysicsModel):
    """Displacement-driven IPMC sensor (short-circuit current), one parameter set or a batch.

    ``kernel``: ``"boundary_charge"`` (Chen et al. 2007, default) or ``"reciprocal"``.
    """

    kind = "sensor"
    primary_quantity = "S"

    quantities = ("S", "Z")
    units = UNITS
    descriptions = DESCRIPTIONS

    def __init__(self, params, kernel: str = "boundary_charge", chunk_size: int = DEFAULT_CHUNK):
        super().__init__(params, chunk_size)
        if kernel not in KERNELS:
            raise IPMCError(f"unknown sensing kernel {kernel!r}; expected one of {KERNELS}")
        self.kernel = kernel

    def _kernel(self, p, s, quantities):
        return sensor_kernel(p, s, quantities, self.kernel)


@dataclass(frozen=True)
class TransimpedanceChain:
    """Seed 000 Fig. 4: two inverting op-amp stages, v1 = R1 i, v2 = (R3 R1/R2) i. Gain in V/A.

    R1, R2, R3 [Ω] (seed 000: 470 kΩ, 10 kΩ, 0-50 kΩ).  ``bandwidth_hz``: an optional first-order
    pole [Hz] of the whole chain (None: none).  ``gbw_hz``: the op-amps' gain-bandwidth product [Hz]
    (None: ideal op-amps, the "virtual ground" of the defaults); with it the chain depends on the
    strip's impedance Z (the first stage's noise gain is 1 + R1/Z, so it closes its loop near
    GBW·|Z|/R1, in the band for a strip of tens of ohms) and :meth:`response` needs
    ``source_impedance``; ``dc_gain`` A0 [-] (None: infinite).  The circuit is solved in
    :func:`physmodel.effects.sensing.transimpedance`.
    """

    R1: float = 470e3
    R2: float = 10e3
    R3: float = 10e3
    bandwidth_hz: float | None = None
    gbw_hz: float | None = None
    dc_gain: float | None = None

    def __post_init__(self):
        for name in ("R1", "R2"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise IPMCError(f"{name}={v!r} Ω must be a positive finite resistance")
        if not (np.isfinite(self.R3) and self.R3 >= 0):
            raise IPMCError(f"R3={self.R3!r} Ω must be a finite resistance >= 0")
        for name in ("bandwidth_hz", "gbw_hz", "dc_gain"):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and v > 0):
                raise IPMCError(f"{name}={v!r} must be a positive finite number or None")

    @property
    def gain(self) -> float:
        """DC transimpedance v2/i with ideal op-amps [V/A]."""
        return self.R3 * self.R1 / self.R2

    @property
    def ideal_opamps(self) -> bool:
        return self.gbw_hz is None and self.dc_gain is None

    def response(self, s, source_impedance=None):
        """v2/i at s [rad/s] [V/A]; ``source_impedance`` Z [Ω] of the strip (needed with finite op-amps)."""
        s = np.asarray(s, dtype=complex)
        if self.ideal_opamps or self.R3 == 0:
            g = np.full_like(s, self.gain)
        else:
            if source_impedance is None:
                raise IPMCError("TransimpedanceChain with gbw_hz or dc_gain needs the strip's source_impedance [Ohm]")
            from .effects.sensing import transimpedance

            g = transimpedance(s, source_impedance, self.R1, self.R2, self.R3,
                               unity_gain_time=0.0 if self.gbw_hz is None else 1.0 / (2 * np.pi * self.gbw_hz),
                               inverse_dc_gain=0.0 if self.dc_gain is None else 1.0 / self.dc_gain)
        if self.bandwidth_hz is not None:
            g = g / (1.0 + s / (2 * np.pi * self.bandwidth_hz))
        return g

    def transfer_function(self):
        """python-control transfer function (ideal op-amps only: with finite ones the chain depends on Z)."""
        import control

        if not self.ideal_opamps:
            raise IPMCError("transfer_function() needs ideal op-amps (gbw_hz = dc_gain = None): the finite-op-amp "
                            "chain depends on the strip's impedance; use response(s, source_impedance)")
        if self.bandwidth_hz is None:
            return control.tf([self.gain], [1.0])
        wc = 2 * np.pi * self.bandwidth_hz
        return control.tf([self.gain * wc], [1.0, wc])
