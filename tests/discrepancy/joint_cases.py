"""M and Z records of one independent strip (issue 27, item 2: joint diagnosis over several quantities).

The tip displacement per volt M comes from :func:`independent_generator.make_case` unchanged; the
impedance Z of the same strip (same base, same hidden effects) from the generator's own physics
(:func:`independent_physics.actuator_response`, no ``physmodel`` physics) on the same lines, with
circular complex Gaussian noise of relative σ = the case's ``sigma_rel`` × ``z_noise``, seeded apart
from M's (``[Z_NOISE, seed]``).  The only ``physmodel`` import is the record type.

    M, Z, truth = make_joint_case(7, "contact_resistance")
"""

from __future__ import annotations

import math

import numpy as np

from physmodel.data.sweep import FrequencySweep

try:                                      # imported as tests/discrepancy/joint_cases
    from . import independent_generator as ig
    from . import independent_physics as ip
    from . import independent_sensor as isn
except ImportError:                       # imported with tests/discrepancy on sys.path
    import independent_generator as ig
    import independent_physics as ip
    import independent_sensor as isn

#: Seed root of the Z records' noise (not the generator's).
Z_NOISE = 0x27_0002


def z_record(truth: dict, seed: int, z_noise: float = 1.0, declare: bool = True) -> FrequencySweep:
    """The impedance Z [V/A] of ``truth``'s strip at the generator's lines, relative noise
    σ = sigma_rel·``z_noise`` (per-line σ declared unless ``declare`` is False)."""
    f, T = np.asarray(ig.FREQUENCIES_HZ, float), np.asarray(ig.TEMPERATURES_C, float)
    Z = ip.actuator_response(truth["base"], f, T, truth["effects"])["Z"].reshape(-1)
    sig = truth["noise"]["sigma_rel"] * float(z_noise) / math.sqrt(2.0)
    rng = np.random.default_rng([Z_NOISE, int(seed)])
    noisy = Z * (1 + sig * (rng.standard_normal(Z.size) + 1j * rng.standard_normal(Z.size)))
    n = Z.size
    std = (np.full(n, 20 / math.log(10) * sig), np.full(n, math.degrees(sig))) if declare else (None, None)
    return FrequencySweep(np.repeat(T, f.size), np.tile(f, T.size), noisy, *std, "current", "A", "voltage", "V",
                          {"source": "independent generator's impedance (tests/discrepancy/joint_cases.py)"})


def make_joint_case(seed: int, label: str, z_noise: float = 1.0, declare: bool = True, **kw):
    """``(M sweep [mm/V], Z sweep [V/A], truth)`` of one independent case (see the module docstring);
    ``declare=False`` drops the per-line σ of both records."""
    M, truth = ig.make_case(seed, label, **kw)
    Zs = z_record(truth, seed, z_noise, declare)
    if not declare:
        M = FrequencySweep(M.temperature_c, M.frequency_hz, M.response, None, None, M.input_name, M.input_unit,
                           M.output_name, M.output_unit, dict(M.metadata))
    return M, Zs, truth


def make_joint_sensor_case(seed: int, label: str, z_noise: float = 1.0, **kw):
    """``(S sweep [uA/mm], Z sweep [V/A], truth)`` of one independent sensor case
    (:func:`independent_sensor.make_case`): Z is the strip's own terminal impedance
    (:func:`independent_sensor.strip_sensor`) at the same lines, as an impedance analyser on the
    strip measures it — not through the current amplifier or the acquisition, so the hidden chain
    element does not act on it — with relative noise sigma_rel·``z_noise``, seeded apart."""
    S, truth = isn.make_case(seed, label, **kw)
    f = S.frequency_hz
    Z = isn.strip_sensor(truth["base"], 2j * np.pi * f)[1]
    sig = truth["sigma_rel"] * float(z_noise) / math.sqrt(2.0)
    rng = np.random.default_rng([Z_NOISE + 1, int(seed)])
    noisy = Z * (1 + sig * (rng.standard_normal(Z.size) + 1j * rng.standard_normal(Z.size)))
    Zs = FrequencySweep(S.temperature_c, f, noisy, np.full(f.size, 20 / math.log(10) * sig),
                        np.full(f.size, math.degrees(sig)), "current", "A", "voltage", "V",
                        {"source": "independent sensor's strip impedance (tests/discrepancy/joint_cases.py)"})
    return S, Zs, truth


__all__ = ["make_joint_case", "make_joint_sensor_case", "z_record", "Z_NOISE"]
