"""The next-measurement search for a joint diagnosis (S and Z of one strip, issue 27 items 2-3):
the record's quantities each keep their own σ and the effects their ``acts_on``, a measurement of a
diagnosed quantity is merged into that quantity's record, and every candidate is evaluated with
the whole joint record.  Checked on the independent sensor (its own strip, laws and chain), whose
lab then measures the recommendation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from next_measurement_cases import independent

from physmodel import get_parameter_set
from physmodel.data.sweep import FrequencySweep
from physmodel.estimation.discrepancy import diagnose
from physmodel.estimation.next_measurement import merge_records, next_measurement

CANDS = ["amplifier_bandwidth", "time_delay", "transimpedance"]


@pytest.fixture(scope="module")
def gen():
    return independent("independent_sensor"), independent("joint_cases")


def test_joint_record_search_and_the_lab_confirms(gen):
    """Seed 950 (the benchmark's development range): a hidden two-pole amplifier; S and the strip's
    own Z at 35 °C leave the amplifier, a delay and the op-amp stage ambiguous (Z carries no chain
    element: ``acts_on`` S).  The search sees both quantities' noise, recommends an S record (Z
    cannot separate chain elements) and the independent sensor measured there, merged into the S
    record and diagnosed jointly with Z again, names the amplifier."""
    from scenarios.steps_chain import physics_free

    isn, jc = gen
    S, Z, truth = jc.make_joint_sensor_case(950, "amplifier")
    p0 = get_parameter_set("seed000_sensor_dev", T_ref=isn.TEMPERATURE_C + 273.15)

    def diag(data):
        return diagnose(data, p0, kind="sensor", quantity=("S", "Z"), candidates=CANDS,
                        free=physics_free(p0, ["a0", "d", "kappa_e"], math.copysign(1, p0.a0)), null_draws=400,
                        null_refits=2, baseline_starts=2, seed=1, acts_on={c: ["S"] for c in CANDS})

    d = diag([S, Z])
    assert d.joint is not None and d.verdict == "ambiguous" and "amplifier_bandwidth" in d.named
    nm = next_measurement(d, band_limits_hz=(0.1, 1000.0))
    assert set(nm.noise_model["by_quantity"]) == {"S", "Z"}
    assert nm.best_by_quantity["Z"] < 1.0 < nm.target < nm.best_by_quantity["S"]     # Z sees no chain element
    r = nm.recommended
    assert nm.separates and r.quantity == "S" and r.joint and not r.added_quantity
    assert "merged with the diagnosed record" in r.describe()
    # no new line repeats one the S record holds
    have = set(zip(S.temperature_c.tolist(), S.frequency_hz.tolist()))
    assert not have & set(zip(r.line_temperatures_c.tolist(), r.line_frequencies_hz.tolist()))
    f, T = r.line_frequencies_hz, r.line_temperatures_c
    H = isn.response(truth["base"], truth["effects"], f, temperature_c=T) * 1e3
    sig = truth["sigma_rel"] / math.sqrt(2.0)
    rng = np.random.default_rng(27_0005)
    new = FrequencySweep(T, f, H * (1 + sig * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))),
                         np.full(f.size, 20 / math.log(10) * sig), np.full(f.size, math.degrees(sig)),
                         "tip_displacement", "mm", "current", "uA")
    d2 = diag([merge_records(S, new), Z])
    assert d2.verdict == "named" and d2.named == ["amplifier_bandwidth"]
