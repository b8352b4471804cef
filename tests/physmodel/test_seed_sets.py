"""The calibrated seed sets ``seed000_sensor`` and ``seed001_actuator``.

Oracles: the printed 35 °C sensor model (evaluated here with python-control from
shared/data/published.toml, independently of the package's copy of the numbers), the printed
seed 001 trend (7 dB at about 3 Hz, resonance moving down), the Euler-Bernoulli scaling of the first
mode with the modulus law, and re-running the derivation (physmodel/parameter_sets/derivation.py) to
check that the stored numbers are what it produces.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from physmodel import ActuatorModel, SensorModel, get_parameter_set, load_parameter_set, save_parameter_set
from physmodel.parameter_sets.seed000 import SEED000_SENSOR_CAL
from physmodel.parameter_sets.seed001 import SEED001_ACTUATOR_CAL
from physmodel.temperature import TemperatureLaws
from physmodel.parameter_sets import derivation as sc
from scenarios.validate import DEFAULT_PUBLISHED


@pytest.fixture(scope="module")
def published():
    return tomllib.loads(DEFAULT_PUBLISHED.read_text(encoding="utf-8"))


def _printed_35c(published, f):
    import control

    s = published["sensor_seed000"]
    G = control.tf(s["model_35c_num"], s["model_35c_den"])
    return np.asarray(G(2j * np.pi * f), complex)


def test_geometries_and_dev_sets_unchanged(published):
    sen, act = get_parameter_set("seed000_sensor"), get_parameter_set("seed001_actuator")
    smp = published["sensor_seed000"]["sample"]
    assert (sen.L, sen.W, 2 * sen.h) == pytest.approx((smp["length_mm"] * 1e-3, smp["width_mm"] * 1e-3, smp["thickness_um"] * 1e-6))
    smp = published["actuator_seed001"]["sample"]
    assert (act.L, act.W, 2 * act.h) == pytest.approx((smp["free_length_mm"] * 1e-3, smp["width_mm"] * 1e-3, smp["thickness_mm"] * 1e-3))
    dev = get_parameter_set("seed000_sensor_dev")
    assert dev.a0 == 0.3 and dev.laws == TemperatureLaws()        # the development sets are kept as they were
    assert "calibrated" in sen.source and "35 C" in sen.source and "7 dB" in act.source


@pytest.mark.parametrize("name", ["seed000_sensor", "seed001_actuator"])
def test_json_round_trip(tmp_path, name):
    p = get_parameter_set(name)
    q = load_parameter_set(save_parameter_set(p, tmp_path / f"{name}.json"))
    assert q.to_dict() == p.to_dict()


def test_sensor_calibration_reproduces_stored_values():
    res = sc.calibrate_seed000_sensor()
    assert res.converged
    assert sorted(res.held) == ["kappa_e", "r1_sheet", "r2_specific"]       # ran to their bounds
    for k in ("a0", "d"):
        assert res.values[k] == pytest.approx(SEED000_SENSOR_CAL[k], rel=1e-4)
        assert res.ci_lower[k] <= SEED000_SENSOR_CAL[k] <= res.ci_upper[k]


def test_sensor_misfit_against_printed_model(published):
    """Independent evaluation of the printed 35 °C model (python-control) gives the reported misfit,
    and the calibration improved on the development values."""
    f = np.logspace(1, 2, 91)
    G = _printed_35c(published, f)
    m = sc.sensor_misfit_35c(get_parameter_set("seed000_sensor"))
    S = SensorModel(get_parameter_set("seed000_sensor")).frequency_response(f, [35.0])["S"][0, 0] * 1e3
    db = 20 * np.log10(np.abs(S / G))
    assert m.rms_db == pytest.approx(math.sqrt(np.mean(db**2)), rel=1e-9)
    dev = sc.sensor_misfit_35c(get_parameter_set("seed000_sensor_dev"))
    assert m.rms_db < dev.rms_db and m.rms_deg < dev.rms_deg
    # the documented finding: the physics cannot follow the printed phase (RHP zeros)
    assert m.rms_deg > 30


def test_sensor_laws_reproduce_published_directions_and_defaults_do_not():
    sen = get_parameter_set("seed000_sensor")
    tr = sc.sensor_trends(sen)
    assert tr.monotone() == {"cutoff_decreases": True, "hf_gain_decreases": True, "phase_lag_increases": True}
    # independent look at the ends: the 100 Hz gain straight from the model
    S = SensorModel(sen).frequency_response([100.0], [23.0, 65.0])["S"][0, :, 0]
    assert 20 * np.log10(abs(S[1]) * 1e3) < 20 * np.log10(abs(S[0]) * 1e3)
    # with the physics.md default laws the cut-off rises and the lag falls (why the laws were chosen)
    default = sc.sensor_trends(sen.replace(laws=TemperatureLaws()))
    assert default.monotone()["cutoff_decreases"] is False and default.monotone()["phase_lag_increases"] is False
    assert sc.choose_sensor_laws(sen)[:2] == (SEED000_SENSOR_CAL["C_minus_slope"], SEED000_SENSOR_CAL["E_slope"])


def test_actuator_trend_solution_reproduces_stored_values():
    p, sol = sc.solve_actuator_trend()
    assert p.E == pytest.approx(SEED001_ACTUATOR_CAL["E"], rel=1e-4)
    assert p.laws.C_minus.slope == pytest.approx(SEED001_ACTUATOR_CAL["C_minus_slope"], rel=1e-3)


def test_actuator_reproduces_seed001_trends():
    act = get_parameter_set("seed001_actuator")
    # 7 dB at ~3 Hz, 19 °C larger: straight from the model on seed 001's grid
    f = sc.seed001_frequencies_hz()
    M = np.abs(ActuatorModel(act).frequency_response(f, [19.0, 55.0])["M"][0])
    D = 20 * np.log10(M[0] / M[1])
    i = int(np.argmax(np.abs(D)))
    assert 6.5 < D[i] < 7.5 and 2.5 < f[i] < 3.6
    # resonance moves down, by the Euler-Bernoulli factor sqrt(E(55)/E(19)) of the modulus law
    tr = sc.actuator_trends(act)
    assert np.all(np.diff(tr.resonance_hz) < 0)
    ratio = math.sqrt(act.laws.E.factor(328.15, act.T_ref) / act.laws.E.factor(292.15, act.T_ref))
    assert tr.resonance_hz[-1] / tr.resonance_hz[0] == pytest.approx(ratio, rel=0.02)
    # the known problem of the development set: its gain near 2-3 Hz rises with T
    dev = np.abs(ActuatorModel(get_parameter_set("seed001_actuator_dev")).frequency_response([2.0], [19.0, 55.0])["M"][0, :, 0])
    assert dev[1] > dev[0]
