"""Seed 002 sets.

seed002_table2 / seed002_table3
    Seed 002 (Frequency response of IPMC actuators), Tables 1-3: L = 15 mm, W = 4 mm,
    thickness 0.25 mm, T = 300 K, E = 154 MPa, ωn = 75.4 rad/s, ξ = 0.18, Rp' = 0.37 Ω·m²,
    d, C⁻, α0, κe, r2', r1' initial (Table 2) and fitted (Table 3).

    Two unit conventions had to be pinned down:

    * Seed 002 writes the mode as ωn/(s² + 2ξωn s + ωn²) (eq. 15), whose DC gain is 1/ωn [s].
      Its fitted α0 (a pure gain knob, §4) therefore absorbed a factor 1/ωn.  We use the
      unit-DC-gain mode ωn²/(…) and store ``alpha0 = α0_printed / ωn`` [J/C], which reproduces the
      seed's DC gain exactly: M(0) = 5.7 mm/V for Table 3 (a few mm/V, as measured IPMC strips
      of this size give), instead of 430 mm/V if −155 were read as J/C with a unit-gain mode.
    * r1' is printed as "Ω·m" in Table 2 and "Ω" in Table 3; eq. (11) needs r1'/W in Ω/m, so r1'
      is a sheet resistance [Ω] and r2', Rp' are per-width quantities [Ω·m²].
    The density is chosen so that the Euler-Bernoulli first mode is 75.4 rad/s at 154 MPa
    (it includes the added mass of the water the strip was tested in).
    No sensing coupling is printed; ``a0`` is the development value of ``dev``.
"""

from __future__ import annotations

from ..params import IPMCParameters, density_for_mode
from ..temperature import TemperatureLaws
from .dev import DEV_A0

_SEED002_SOURCE = "seed 002 (Frequency response of IPMC actuators), Tables 1-3"
_OMEGA_N_002 = 75.4
_E_002 = 154e6


def _seed002(table: int) -> IPMCParameters:
    L, W, h = 15e-3, 4e-3, 0.125e-3
    if table == 2:
        vals = dict(d=3.48e-11, C_minus=1068.0, alpha0=-40.0, kappa_e=5.07e-7, r2_specific=9.99e-6, r1_sheet=64.0)
    else:
        vals = dict(d=3.07e-11, C_minus=941.94, alpha0=-155.0, kappa_e=4.47e-7, r2_specific=8.81e-6, r1_sheet=56.44)
    vals["alpha0"] = vals["alpha0"] / _OMEGA_N_002  # seed's mode has ωn, not ωn², in its numerator
    return IPMCParameters(
        L=L, W=W, h=h, E=_E_002, rho=density_for_mode(_OMEGA_N_002, _E_002, L, h), xi=0.18,
        Rp_specific=0.37, a0=DEV_A0, T_ref=300.0, laws=TemperatureLaws(),
        name=f"seed002_table{table}",
        source=f"{_SEED002_SOURCE}; Table {table}{' (initial)' if table == 2 else ' (fitted)'}; "
               "alpha0 = printed/omega_n (see module doc)",
        **vals,
    )


SETS = {
    "seed002_table2": lambda: _seed002(2),
    "seed002_table3": lambda: _seed002(3),
}
