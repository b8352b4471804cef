"""Set-ups shared by the next-measurement tests (not collected: no test_ prefix)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

from physmodel import get_parameter_set, physics_model

ROOT = Path(__file__).resolve().parents[2]
TAU = 2e-4          # the hidden amplifier pole [s]: corner 796 Hz


def virtual_lab_record():
    """The next-measurement scenario's first record: the seed 000 development sensor at 35 °C with a
    hidden amplifier pole ``TAU``, measured on the virtual lab (multisine, 10-100 Hz, 31 lines).
    Returns ``(parameters, truth, sweep)``."""

    from scenarios.steps_next_measurement import InstrumentModel
    from scenarios.virtual_lab import from_config

    p = get_parameter_set("seed000_sensor_dev", T_ref=308.15)
    truth = InstrumentModel(physics_model("sensor", p), {"amplifier_bandwidth": {"time_constant": TAU}})
    design = dict(source="virtual_lab", temperatures_c=[35.0], fmin_hz=10.0, fmax_hz=100.0, points=31,
                  excitation="multisine", fs_hz=5000.0, period_s=1.0, periods=8, transient_periods=2, rms=1.0,
                  oversample=8)
    rec = from_config(truth, design, {"kind": "time", "output_noise_rms": 3e-6, "seed": 5}).sweep
    return p, truth, rec


def independent(name: str):
    """A module of tests/discrepancy (the independently written generators), imported without
    leaving that folder on the path."""
    where = str(ROOT / "tests" / "discrepancy")
    sys.path.insert(0, where)
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(where)
