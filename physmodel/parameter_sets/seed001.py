"""Seed 001 actuator set.

seed001_actuator
    The seed 001 actuator: development values with E at T_ref = 23 °C and a log-linear C⁻ law
    solved from the printed trend (largest 19-vs-55 °C difference 7 dB at 3 Hz, 19 °C larger, a
    maximum there): E = 421.4 MPa, C⁻ slope −2.609 %/K; E keeps the default −0.75 %/K, which moves
    the first mode from 2.79 Hz (19 °C) to 2.44 Hz (55 °C).  C⁻ is the law-able proxy for a coupling
    that weakens with temperature (default laws make the gain near 2 Hz rise with T).  The zpk
    schedules' numbers are not printed, so no response is fitted.
    Derivation: ``python3 -m physmodel.parameter_sets.derivation``.
"""

from __future__ import annotations

from ..params import IPMCParameters
from ..temperature import LogLinear
from .dev import dev_set

#: Calibrated seed values (derived by physmodel/parameter_sets/derivation.py; see the module doc).
SEED001_ACTUATOR_CAL = {"E": 4.21417e8, "C_minus_slope": -0.026088}


def _seed001_actuator() -> IPMCParameters:
    c = SEED001_ACTUATOR_CAL
    p = dev_set("seed001_actuator", 45e-3, 11e-3, 150e-6,
             "seed 001 actuator geometry with development values; E (first mode) and a C- log-linear law "
             "(-2.61 %/K) solved from the printed trend: largest 19-vs-55 C difference 7 dB at 3 Hz "
             "(physmodel/parameter_sets/derivation.py)")
    return p.replace(E=c["E"], laws=p.laws.with_(C_minus=LogLinear(slope=c["C_minus_slope"])))


SETS = {"seed001_actuator": _seed001_actuator}
