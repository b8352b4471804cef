"""The one model file (:mod:`physmodel.model_file`): effects, laws and the verdict survive a round
trip; older files still load; a calibration and a diagnosis both write it."""

from __future__ import annotations

import json

import numpy as np
import pytest

from physmodel import EffectModel, ModelFile, ParameterError, get_parameter_set, load_model
from physmodel.model_file import FitVerdict, Provenance


def _model_file():
    p = get_parameter_set("seed001_actuator", W=9e-3)
    return ModelFile("actuator", p, {"time_delay": {"delay": 2e-3}}, "M", "boundary_charge",
                     FitVerdict(False, 500.0, 100, 1e-20, "chi2 = 500 on 100 dof"),
                     ({"name": "d", "value": 4e-11, "ci95": [None, None], "status": "determined"},),
                     Provenance("test", "sweep.csv", "ab" * 32, "cd" * 32, (20.0, 40.0), (0.1, 9.0), "ipmc x", "0.1.0"))


def test_round_trip_keeps_effects_laws_verdict_and_provenance(tmp_path):
    mf = _model_file()
    mf.save(tmp_path / "m.json")
    back = load_model(tmp_path / "m.json")
    assert back.fingerprint() == mf.fingerprint()
    assert back.effects == {"time_delay": {"delay": 2e-3}}
    assert back.adequate is False and back.verdict.dof == 100
    assert back.provenance.temperatures_c == (20.0, 40.0)
    assert back.parameters.laws.to_dict() == mf.parameters.laws.to_dict()
    f = np.array([0.5, 5.0, 50.0])
    direct = EffectModel(get_parameter_set("seed001_actuator", W=9e-3), "actuator", {"time_delay": {"delay": 2e-3}})
    np.testing.assert_allclose(back.model().response(f, [30.0]), direct.response(f, [30.0]), rtol=1e-14)
    # the delay is really in the model: the phase differs from the plain physics by 2π f τ
    plain = get_parameter_set("seed001_actuator", W=9e-3)
    from physmodel import ActuatorModel

    dphi = np.angle(back.model().response(f, [30.0]) / ActuatorModel(plain).response(f, [30.0]))[0]
    np.testing.assert_allclose(dphi, -2 * np.pi * f * 2e-3, atol=1e-9)


def test_a_named_set_has_no_verdict_and_kind_conflicts_are_refused(tmp_path):
    mf = load_model("seed002_table3")
    assert mf.verdict is None and mf.adequate is None and mf.effects == {}
    _model_file().save(tmp_path / "m.json")
    with pytest.raises(ParameterError, match="kind 'actuator'"):
        load_model(tmp_path / "m.json", kind="sensor")


def test_an_older_calibrate_parameters_file_loads_with_its_verdict_and_effects(tmp_path):
    # written by hand as ipmc calibrate wrote parameters.json before the model file (metadata values as str())
    params = get_parameter_set("seed001_actuator").to_dict()
    params["laws"] = params["laws"]
    old = {"format": "ipmc-parameter-set", "version": 1, "parameters": json.loads(json.dumps(params, default=str)),
           "calibration": {"format": "ipmc-calibration", "version": 1, "temperatures_c": [20.0, 50.0],
                           "band_hz": [0.1, 9.0],
                           "goodness_of_fit": {"adequate": False, "chi2": 9000.0, "dof": 200, "reduced_chi2": 45.0,
                                               "p_value": 0.0, "relative_noise": None, "reason": "misfit"},
                           "metadata": {"kind": "actuator", "quantity": "M", "kernel": "boundary_charge",
                                        "effects": "{'time_delay': {'delay': 0.002}}", "sweep_file": "s.csv"}}}
    path = tmp_path / "parameters.json"
    path.write_text(json.dumps(old).replace("Infinity", '"inf"'))
    mf = load_model(path)
    assert mf.adequate is False
    assert mf.effects == {"time_delay": {"delay": 0.002}}
    assert mf.provenance.data_file == "s.csv"
    assert get_parameter_set(path).name == params["name"]        # the parameters alone, as before


def test_a_file_of_another_format_is_refused_with_its_name(tmp_path):
    p = tmp_path / "x.json"
    p.write_text(json.dumps({"format": "something-else", "parameters": {}}))
    with pytest.raises(ParameterError, match="x.json.*format"):
        load_model(p)


@pytest.mark.parametrize("patch, needle", [
    ({"verdict": {"adequate": "false"}}, "adequate"),                 # a string is not a verdict
    ({"verdict": {"adequate": True, "dof": "abc"}}, "dof"),
    ({"provenance": {"creator": "x", "band_hz": 5}}, "band_hz"),
    ({"provenance": {"creator": "x", "temperatures_c": "25"}}, "temperatures_c"),
    ({"estimates": "abc"}, "estimates"),
    ({"effects": {"time_delay": 3}}, "effects"),
])
def test_a_badly_typed_model_file_is_refused_naming_the_key(tmp_path, patch, needle):
    d = _model_file().to_dict()
    d.update(patch)
    p = tmp_path / "m.json"
    p.write_text(json.dumps(d))
    with pytest.raises(ParameterError, match=needle):
        load_model(p)


def test_an_older_file_of_another_kind_is_refused(tmp_path):
    params = json.loads(json.dumps(get_parameter_set("seed000_sensor").to_dict(), default=str))
    old = {"format": "ipmc-parameter-set", "version": 1, "parameters": params,
           "calibration": {"metadata": {"kind": "sensor", "quantity": "S"}}}
    p = tmp_path / "parameters.json"
    p.write_text(json.dumps(old).replace("Infinity", '"inf"'))
    assert load_model(p).kind == "sensor"
    with pytest.raises(ParameterError, match="kind 'sensor'"):
        load_model(p, kind="actuator")


def test_a_calibration_that_did_not_converge_writes_a_model_that_does_not_fit():
    from physmodel import MagnitudePhaseNoise, calibrate, synthesize_sweep
    from physmodel.estimation.calibration import default_free_parameter

    p = get_parameter_set("seed001_actuator")
    sw = synthesize_sweep(EffectModel(p, "actuator", {}), "M", np.logspace(-1, 1, 20), [25.0],
                          noise=MagnitudePhaseNoise(0.05, 0.3), seed=2)
    res = calibrate(sw, p.replace(d=3 * p.d), [default_free_parameter(p, "d")], starts=1, max_nfev=1)
    assert not res.converged
    mf = res.to_model_file()
    assert mf.adequate is False and "did not converge" in mf.verdict.reason
