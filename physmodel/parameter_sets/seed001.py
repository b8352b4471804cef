"""Seed 001 actuator set.

seed001_actuator
    The seed 001 actuator (Dong and Tan, Smart Mater. Struct. 21, 065014, 2012; 45 mm free length
    × 11 mm × 0.3 mm, in water): development values with E at T_ref = 23 °C and a log-linear C⁻ law
    solved from one printed claim only, ``trends[1]`` (Sec. 2.2, Fig. 2): the largest 19-vs-55 °C
    magnitude difference is about 7 dB, at about 3 Hz, 19 °C larger — two equations, D(3 Hz) = 7 dB
    and dD/dln f (3 Hz) = 0, in two unknowns: E = 421.4 MPa, C⁻ slope −2.609 %/K.
    E keeps the physics.md default slope −0.75 %/K (a literature input), which moves the first mode
    from 2.79 Hz (19 °C) to 2.44 Hz (55 °C): the falling resonance (``trends[0]``) follows from that
    input.  Not used: the order claims and the right-half-plane zero pair (predictions), and the
    35/45 °C hold-out of the scheduled model and the 45 °C tracking comparison (round trips of a
    surrogate fitted to the physics, which pass with the uncalibrated set too; no predictions).

    Plausibility: E = 421 MPa at 23 °C is of the order of the 300 MPa development value and above
    the 154 MPa of seed 002's Table 2; it is fixed by the first mode (the added mass of water is in
    ρ), so it is only as good as the beam model.  A C⁻ falling 2.6 %/K (−61 % over 19–55 °C) is a
    stand-in, not a material property: C⁻ is set by the membrane's ion-exchange capacity, and is
    used here only because the physics has no law-able coupling that weakens with T (with default
    laws the gain near 2 Hz rises with T).
    The zpk schedules' numbers are not printed, so no response is fitted.
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

#: The published claims (``published.toml`` ids) the set was solved to; no other claim was used.
CALIBRATION = {"seed001_actuator": {
    "actuator_seed001.trends[1]": "E at T_ref and the C- slope solved from D(3 Hz) = 7 dB, dD/dlnf(3 Hz) = 0",
}}
