"""``ipmc calibrate`` end to end in a temporary folder: files written atomically, the parameter set
loadable by path and holding the truth within its intervals, exit codes 0 / 2 / 3."""

from __future__ import annotations

import json

import numpy as np
import pytest

from physmodel import ActuatorModel, SensorModel, get_parameter_set
from physmodel.data.files import write_sweep
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from scenarios.cli import main

TRUTH = dict(d=4.0e-11, kappa_e=3.8e-7)


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    truth = get_parameter_set("seed002_table3", **TRUTH)
    sw = synthesize_sweep(ActuatorModel(truth), "M", np.logspace(-1, 2, 30), [20.0, 45.0],
                          noise=MagnitudePhaseNoise(0.1, 1.0), seed=9)
    path = tmp_path_factory.mktemp("data") / "sweep.csv"
    write_sweep(sw, path)
    return path


def test_calibrate_end_to_end(sweep_file, tmp_path, capsys):
    out = tmp_path / "cal"
    rc = main(["calibrate", str(sweep_file), "--set", "seed002_table3", "--free", "d",
               "--free", "kappa_e:1e-7:1e-5", "--free", "alpha0", "--free", "laws.d.activation_energy",
               "--starts", "2", "--seed", "1", "--out", str(out), "--name", "strip7", "--quiet"])
    assert rc == 0
    assert capsys.readouterr().out == ""                       # --quiet
    assert sorted(p.name for p in out.iterdir()) == [".ipmc-complete.json", "bode.png", "calibration.json", "model.json",
                                                     "parameters.json", "report.md"]
    p = get_parameter_set(str(out / "parameters.json"))        # loadable as a named set by path
    assert p.name == "strip7"
    cal = json.loads((out / "calibration.json").read_text())
    assert cal["converged"] and len(cal["starts"]) == 2
    entries = {e["name"]: e for e in cal["parameters"]}
    for name, true in TRUTH.items():
        assert entries[name]["ci95_lower"] <= true <= entries[name]["ci95_upper"]
        assert getattr(p, name) == entries[name]["value"]
    assert entries["kappa_e"]["bounds"] == [1e-7, 1e-5]
    assert (out / "bode.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (out / "report.md").read_text()
    assert "## Estimates (95 % intervals)" in report and "laws.d.activation_energy" in report
    # the written set can be the base of another calibration
    rc = main(["calibrate", str(sweep_file), "--set", str(out / "parameters.json"), "--free", "xi",
               "--starts", "1", "--out", str(tmp_path / "again"), "--quiet"])
    assert rc == 0


def test_calibrate_bad_input_exits_2(sweep_file, tmp_path, capsys):
    base = ["calibrate", str(sweep_file), "--set", "seed002_table3", "--out", str(tmp_path / "x"), "--quiet"]
    assert main(base + ["--free", "nonsense"]) == 2
    assert "unknown parameter 'nonsense'" in capsys.readouterr().err
    assert main(base + ["--free", "d:1e-10:1e-12"]) == 2
    assert "bounds reversed" in capsys.readouterr().err
    assert main(base + ["--free", "d:1e-12"]) == 2
    assert main(base + ["--free", "d", "--kind", "sensor"]) == 2          # mm/V data for a sensor model
    assert "needs current/length" in capsys.readouterr().err
    assert main(base + ["--free", "d", "--set", "no_such_set"]) == 2
    assert not (tmp_path / "x").exists()                                  # nothing half-written
    with pytest.raises(SystemExit) as exc:
        main(["calibrate", "--help"])
    assert exc.value.code == 0
    assert "--free" in capsys.readouterr().out


def test_calibrate_not_converged_exits_3(sweep_file, tmp_path, capsys):
    out = tmp_path / "nc"
    rc = main(["calibrate", str(sweep_file), "--set", "seed002_table3", "--free", "d", "--free", "alpha0",
               "--starts", "1", "--max-nfev", "1", "--out", str(out), "--quiet"])
    assert rc == 3
    assert "did not converge" in capsys.readouterr().err
    cal = json.loads((out / "calibration.json").read_text())
    assert cal["converged"] is False
    assert "NOT CONVERGED" in (out / "report.md").read_text()


def test_calibrate_sensor_sweep(tmp_path):
    truth = get_parameter_set("seed000_sensor_dev", a0=0.5)
    sw = synthesize_sweep(SensorModel(truth), "S", np.logspace(0, 2, 20), [25.0],
                          noise=MagnitudePhaseNoise(0.1, 1.0), seed=2)
    write_sweep(sw, tmp_path / "s.npz")
    rc = main(["calibrate", str(tmp_path / "s.npz"), "--set", "seed000_sensor_dev", "--kind", "sensor",
               "--free", "a0", "--starts", "1", "--out", str(tmp_path / "o"), "--quiet"])
    assert rc == 0
    cal = json.loads((tmp_path / "o" / "calibration.json").read_text())
    e = cal["parameters"][0]
    assert e["ci95_lower"] <= 0.5 <= e["ci95_upper"]


def test_calibrate_with_a_fixed_chain_effect(tmp_path, capsys):
    """Data with a 2 ms acquisition delay (EffectModel, the library's own chain element): with the
    delay given by --effect the truth lies in the intervals and the fit is adequate; without it the
    phase misfit (up to 36° at 50 Hz, against 1° noise) makes the goodness-of-fit test fail (exit 3)."""
    from physmodel.effects import EffectModel

    truth = get_parameter_set("seed002_table3", **TRUTH)
    sw = synthesize_sweep(EffectModel(truth, "actuator", {"time_delay": {"delay": 2e-3}}), "M",
                          np.logspace(-1, np.log10(50), 30), [20.0, 45.0], noise=MagnitudePhaseNoise(0.1, 1.0), seed=4)
    path = tmp_path / "delayed.csv"
    write_sweep(sw, path)
    base = ["calibrate", str(path), "--set", "seed002_table3", "--free", "d", "--free", "kappa_e:1e-7:1e-5",
            "--free", "alpha0", "--starts", "2", "--quiet"]
    assert main(base + ["--effect", "time_delay:delay=2e-3", "--out", str(tmp_path / "with")]) == 0
    cal = json.loads((tmp_path / "with" / "calibration.json").read_text())
    entries = {e["name"]: e for e in cal["parameters"]}
    for name, true in TRUTH.items():
        assert entries[name]["ci95_lower"] <= true <= entries[name]["ci95_upper"]
    assert "fixed effects: time_delay (delay = 0.002)" in (tmp_path / "with" / "report.md").read_text()
    assert main(base + ["--out", str(tmp_path / "without")]) == 3
    assert "does not fit the data" in capsys.readouterr().err
    assert main(base + ["--effect", "time_dilation:delay=2e-3", "--out", str(tmp_path / "bad")]) == 2
    assert "time_dilation" in capsys.readouterr().err


def test_calibrate_says_what_a_hold_costs_and_refuses_a_costly_one(sweep_file, tmp_path, capsys):
    """d's bound 3.8e-11 sits below the truth 4e-11 (and below the all-free optimum 3.90e-11): every
    start ends there; holding d at the base value 3.07e-11 would double the cost, so the un-held fit
    is kept and the report, calibration.json and stderr say what the hold would have cost;
    --no-hold gives the same cost."""
    base = ["calibrate", str(sweep_file), "--set", "seed002_table3", "--free", "d:1e-11:3.8e-11",
            "--free", "kappa_e:1e-7:1e-5", "--free", "alpha0", "--starts", "4", "--quiet"]
    assert main(base + ["--out", str(tmp_path / "held")]) == 0
    err = capsys.readouterr().err
    assert "ipmc calibrate: hold of d REFUSED" in err
    cal = json.loads((tmp_path / "held" / "calibration.json").read_text())
    (h,) = cal["holds"]
    assert h["accepted"] is False and h["names"] == ["d"] and h["cost_after"] > 2 * h["cost_before"]
    entry = {e["name"]: e for e in cal["parameters"]}
    assert entry["d"]["hold_refused"] and not entry["d"]["held"]
    assert entry["d"]["value"] == pytest.approx(3.8e-11, rel=1e-3)
    assert all(s["final"]["d"] == pytest.approx(3.8e-11, rel=1e-3) for s in cal["starts"] if s["status"] != -2)
    report = (tmp_path / "held" / "report.md").read_text()
    assert "- hold: hold of d REFUSED" in report and "not determined, hold refused" in report
    assert f"{h['cost_before']:.5g} -> {h['cost_after']:.5g}" in report
    assert main(base + ["--no-hold", "--out", str(tmp_path / "free")]) == 0
    free = json.loads((tmp_path / "free" / "calibration.json").read_text())
    assert free["cost"] == pytest.approx(cal["cost"], rel=1e-9) == pytest.approx(h["cost_before"], rel=1e-9)
    assert free["holds"] == [] and "hold" not in capsys.readouterr().err
