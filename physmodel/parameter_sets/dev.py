"""Development sets.

dev
    A development set with values often quoted for Chen-Tan-type models (physics.md §8; not
    verifiable here, for development only): C⁻ = 1091 mol/m³, κe = 1.3e-6 F/m, α0 = −0.13 J/C,
    d = 4e-11 m²/s, E = 300 MPa, with a 20 mm × 5 mm × 0.2 mm strip in water.

seed000_sensor_dev, seed001_actuator_dev
    The geometries printed by seed 000 (Nafion-117 sensor, 18 mm × 6.5 mm × 210 µm) and seed 001
    (actuator, 45 mm free length × 11 mm × 0.3 mm) with development material values.
"""

from __future__ import annotations

import math

from ..params import IPMCParameters
from ..temperature import TemperatureLaws

#: Development sensing coupling [C/J]; gives ~10 µA/mm at 50 Hz for the seed 000 sample.
DEV_A0 = 0.3


def _water_density(W: float, h: float, rho_polymer: float = 2000.0, rho_fluid: float = 1000.0) -> float:
    """Polymer density plus the inviscid added mass of a thin plate in water, π ρ_f W²/4 per length."""
    return rho_polymer + rho_fluid * math.pi * W**2 / 4.0 / (2.0 * h * W)


def dev_set(name: str, L: float, W: float, h: float, source: str) -> IPMCParameters:
    return IPMCParameters(
        L=L, W=W, h=h, d=4e-11, C_minus=1091.0, kappa_e=1.3e-6, alpha0=-0.13, a0=DEV_A0,
        r1_sheet=10.0, r2_specific=1e-5, Rp_specific=0.5, E=300e6, rho=_water_density(W, h), xi=0.1,
        T_ref=296.15, laws=TemperatureLaws(), name=name, source=source,
    )


SETS = {
    "dev": lambda: dev_set("dev", 20e-3, 5e-3, 0.1e-3,
                           "development values quoted for Chen-Tan-type models (physics.md §8), not verifiable"),
    "seed000_sensor_dev": lambda: dev_set("seed000_sensor_dev", 18e-3, 6.5e-3, 105e-6,
                                          "seed 000 sensor geometry (Nafion-117, 18 x 6.5 mm, 210 um) with "
                                          "development material values"),
    "seed001_actuator_dev": lambda: dev_set("seed001_actuator_dev", 45e-3, 11e-3, 150e-6,
                                            "seed 001 actuator geometry (45 x 11 mm, 0.3 mm) with development "
                                            "material values"),
}
