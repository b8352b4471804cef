"""The verdict and the named effect travel through every command (issue 24): calibrate and
diagnose write one model file; sweep, fit, feedforward and invert read it and say when the model
does not fit its data (feedforward and invert exit 3 unless --accept-misfit); the feedforward's
predicted error is checked against the measured sweep, never against an unrelated named set."""

from __future__ import annotations

import json

import numpy as np
import pytest

from physmodel import EffectModel, get_parameter_set
from physmodel.data.fftsim import simulate_at_rest
from physmodel.data.files import read_sweep, write_sweep
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from scenarios.cli import main

DELAY = 4e-3
TRUTH = EffectModel(get_parameter_set("seed001_actuator"), "actuator", {"time_delay": {"delay": DELAY}})
FF = ["--temperature", "35", "--reference", "sine", "--amplitude", "0.2", "--frequency", "1", "--fs", "1000"]


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    """A measured sweep with a 4 ms acquisition delay the start model lacks; calibrate (misfit),
    a dense sweep of the misfit model and a surrogate of it."""
    root = tmp_path_factory.mktemp("chain")
    sw = synthesize_sweep(TRUTH, "M", np.logspace(-1, np.log10(9), 24), [20.0, 30.0, 40.0, 50.0],
                          noise=MagnitudePhaseNoise(0.05, 0.3), seed=5)
    write_sweep(sw, root / "sweep.csv")
    rc = main(["calibrate", str(root / "sweep.csv"), "--set", "seed001_actuator", "--free", "alpha0",
               "--starts", "1", "--out", str(root / "cal"), "--quiet"])
    assert rc == 3                                        # the delay is missing: the model does not fit
    return root


def _achieved_on_truth(folder) -> float:
    """RMS(y − r)/RMS(r) of the voltage in ``folder/voltage.csv`` applied to the strip itself (the
    truth with its delay; simulated exactly in the frequency domain, a simulation checked against
    lsim and an exact shift in tests/physmodel/test_fftsim.py)."""
    lines = [ln for ln in (folder / "voltage.csv").read_text().splitlines() if not ln.startswith("#")]
    arr = np.loadtxt(lines[1:], delimiter=",")
    v = {n: arr[:, i] for i, n in enumerate(lines[0].split(","))}
    y = simulate_at_rest(TRUTH, 35.0, v["time_s"], v["voltage_V"]).y * 1e3
    return float(np.sqrt(np.mean((y - v["reference_mm"]) ** 2)) / np.sqrt(np.mean(v["reference_mm"] ** 2)))


def test_calibrate_writes_a_model_file_that_carries_the_misfit(chain):
    mf = json.loads((chain / "cal" / "model.json").read_text())
    assert mf["format"] == "ipmc-model" and mf["verdict"]["adequate"] is False
    assert mf["provenance"]["data_file"].endswith("sweep.csv") and len(mf["provenance"]["data_sha256"]) == 64


def test_the_misfit_travels_through_sweep_fit_and_feedforward(chain, capsys):
    capsys.readouterr()
    rc = main(["sweep", "--model", str(chain / "cal" / "model.json"), "--temperatures", "20,30,40,50",
               "--fmin", "0.1", "--fmax", "9", "--points", "30", "--out", str(chain / "dense.csv"), "--quiet"])
    assert rc == 0
    assert "does not fit the data it was fitted to" in capsys.readouterr().err
    meta = read_sweep(chain / "dense.csv").metadata
    assert meta["model_verdict"] == "MISFIT" and meta["model_file"].endswith("model.json")
    rc = main(["fit", str(chain / "dense.csv"), "--zeros", "4", "--poles", "4", "--degree", "2",
               "--out", str(chain / "fit"), "--quiet"])
    assert rc == 0
    assert "does not fit its own data" in capsys.readouterr().err
    surrogate = json.loads((chain / "fit" / "model.json").read_text())
    assert surrogate["info"]["source_model"]["verdict"] == "MISFIT"
    # no --model and no --set: the check uses the surrogate's own physics and its data, exit 3 on the misfit
    rc = main(["feedforward", str(chain / "fit" / "model.json"), *FF, "--out", str(chain / "ff"), "--quiet"])
    assert rc == 3
    assert "does not fit its data" in capsys.readouterr().err
    rep = json.loads((chain / "ff" / "report.json").read_text())
    assert rep["upstream_misfit"] and rep["physics_model"] == str((chain / "cal" / "model.json").resolve())
    # the voltage on the strip itself (the truth with its delay; simulated exactly in the frequency domain,
    # a simulation checked against lsim and an exact shift in tests/physmodel/test_fftsim.py)
    achieved = _achieved_on_truth(chain / "ff")
    assert achieved > 2 * np.pi * 1.0 * DELAY * 0.8            # the delay the model lacks: |e^{-jωτ} − 1| ≈ ωτ
    assert 0.5 < rep["predicted_error_on_strip_rms"] / achieved < 2.0
    assert rep["predicted_error_on_strip_rms"] > rep["physics_error_rms"]       # the physics check alone is blind to it
    text = (chain / "ff" / "report.md").read_text()
    assert text.index("Predicted error on your strip") < text.index("Error against the physics model")
    assert "UPSTREAM MISFIT" in text
    rc = main(["feedforward", str(chain / "fit" / "model.json"), *FF, "--accept-misfit",
               "--out", str(chain / "ff2"), "--quiet"])
    assert rc == 0
    assert json.loads((chain / "ff2" / "report.json").read_text())["upstream_misfit"]


def test_feedforward_without_data_says_its_prediction_is_unchecked(chain, tmp_path, capsys):
    # a surrogate fitted straight to the measured sweep: no physics behind it, no data unless given
    assert main(["fit", str(chain / "sweep.csv"), "--zeros", "3", "--poles", "3", "--degree", "1",
                 "--out", str(tmp_path / "fit"), "--quiet", "--accept-misfit"]) in (0, 3)
    info = json.loads((tmp_path / "fit" / "model.json").read_text())["info"]
    assert "source_model" not in info
    capsys.readouterr()
    # the surrogate's provenance names its data file: the prediction is checked against it; the
    # surrogate's own misfit to that sweep (accepted at fit) is said again and needs --accept-misfit
    fit_ok = json.loads((tmp_path / "fit" / "model.json").read_text())["info"]["adequacy"]["adequate"]
    acc = [] if fit_ok else ["--accept-misfit"]
    assert main(["feedforward", str(tmp_path / "fit" / "model.json"), *FF, "--out", str(tmp_path / "ff"),
                 "--quiet", *acc]) == 0
    rep = json.loads((tmp_path / "ff" / "report.json").read_text())
    assert rep["physics_error_rms"] is None and rep["predicted_error_on_strip_rms"] is not None
    info["data"]["file"] = str(tmp_path / "gone.csv")
    doc = json.loads((tmp_path / "fit" / "model.json").read_text())
    doc["info"] = info
    (tmp_path / "fit" / "model.json").write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["feedforward", str(tmp_path / "fit" / "model.json"), *FF, "--out", str(tmp_path / "ff3"),
                 "--quiet", *acc]) == 0
    assert "unchecked against measurement" in capsys.readouterr().err
    assert json.loads((tmp_path / "ff3" / "report.json").read_text())["predicted_error_on_strip_rms"] is None


@pytest.mark.slow
def test_diagnose_takes_calibrates_output_and_its_model_carries_the_named_effect(chain):
    # the older parameters.json of calibrate (laws nested under "parameters") is accepted
    rc = main(["diagnose", "--data", str(chain / "sweep.csv"), "--set", str(chain / "cal" / "parameters.json"),
               "--free", "alpha0", "--null-draws", "400", "--null-refits", "0", "--out", str(chain / "diag"), "--quiet"])
    assert rc == 0
    mf = json.loads((chain / "diag" / "model.json").read_text())
    assert "time_delay" in mf["effects"] and mf["verdict"]["adequate"] is True
    assert mf["effects"]["time_delay"]["delay"] == pytest.approx(DELAY, rel=0.1)
    rc = main(["sweep", "--model", str(chain / "diag" / "model.json"), "--temperatures", "20,30,40,50",
               "--fmin", "0.1", "--fmax", "9", "--points", "30", "--out", str(chain / "dense2.csv"), "--quiet"])
    assert rc == 0 and read_sweep(chain / "dense2.csv").metadata["model_verdict"] == "adequate"
    assert main(["fit", str(chain / "dense2.csv"), "--zeros", "4", "--poles", "4", "--degree", "2",
                 "--out", str(chain / "fit2"), "--quiet"]) == 0
    assert main(["feedforward", str(chain / "fit2" / "model.json"), *FF, "--out", str(chain / "ff4"), "--quiet"]) == 0
    rep = json.loads((chain / "ff4" / "report.json").read_text())
    assert not rep["upstream_misfit"]
    achieved = _achieved_on_truth(chain / "ff4")
    assert 0.5 < rep["predicted_error_on_strip_rms"] / achieved < 2.0
    # the named delay is in the model now: the strip tracks better than the steady-state error of the missing delay
    assert achieved < 2 * np.pi * 1.0 * DELAY * 0.8


def test_invert_refuses_a_surrogate_of_a_misfit_model_unless_accepted(chain, tmp_path, capsys):
    if not (chain / "fit" / "model.json").exists():          # run alone: make the misfit surrogate here
        assert main(["sweep", "--model", str(chain / "cal" / "model.json"), "--temperatures", "20,30,40,50",
                     "--fmin", "0.1", "--fmax", "9", "--points", "30", "--out", str(chain / "dense.csv"), "--quiet"]) == 0
        assert main(["fit", str(chain / "dense.csv"), "--zeros", "4", "--poles", "4", "--degree", "2",
                     "--out", str(chain / "fit"), "--quiet"]) == 0
    t = np.arange(2000) / 500.0
    w = np.sin(np.pi * t / t[-1]) ** 2 * 0.1 * np.sin(2 * np.pi * 1.0 * t)
    np.savetxt(tmp_path / "tip.csv", np.column_stack([t, w]), delimiter=",", header="time_s,tip_mm", comments="")
    args = ["invert", str(tmp_path / "tip.csv"), "--surrogate", str(chain / "fit" / "model.json"),
            "--temperature", "35", "--quiet"]
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "v.csv")]) == 3
    assert "does not fit its data" in capsys.readouterr().err
    head = [ln for ln in (tmp_path / "v.csv").read_text().splitlines() if ln.startswith("#")]
    assert any("upstream_misfit" in h for h in head) and any("predicted_error_on_strip" in h for h in head)
    assert main([*args, "--accept-misfit", "--out", str(tmp_path / "v2.csv")]) == 0


def test_diagnose_exits_3_when_the_model_it_ends_with_does_not_fit(chain, tmp_path, capsys):
    # only a candidate that cannot make a 4 ms delay: the gap stays open, the verdict is not a fit
    argv = ["diagnose", "--data", str(chain / "sweep.csv"), "--set", "seed001_actuator", "--laws", "set",
            "--free", "alpha0", "--candidates", "leakage", "--null-draws", "400", "--null-refits", "0", "--quiet"]
    capsys.readouterr()
    assert main([*argv, "--out", str(tmp_path / "d1")]) == 3
    assert "does not fit the data" in capsys.readouterr().err
    mf = json.loads((tmp_path / "d1" / "model.json").read_text())
    assert mf["verdict"]["adequate"] is False
    assert main([*argv, "--accept-misfit", "--out", str(tmp_path / "d2")]) == 0


def test_provenance_data_is_used_only_while_it_is_the_same_file(chain, tmp_path, monkeypatch, capsys):
    """A relative data path is stored absolute (a command run elsewhere finds it); a data file changed
    since the fit is not used as the strip's data, and the report says why."""
    work = tmp_path / "lab"
    work.mkdir()
    (work / "sweep.csv").write_bytes((chain / "sweep.csv").read_bytes())
    monkeypatch.chdir(work)
    assert main(["calibrate", "sweep.csv", "--set", "seed001_actuator", "--free", "alpha0", "--starts", "1",
                 "--accept-misfit", "--out", "cal", "--quiet"]) == 0
    prov = json.loads((work / "cal" / "model.json").read_text())["provenance"]
    assert prov["data_file"] == str((work / "sweep.csv").resolve())
    assert main(["sweep", "--model", "cal/model.json", "--temperatures", "20,30,40,50", "--fmin", "0.1", "--fmax", "9",
                 "--points", "30", "--out", "dense.csv", "--quiet"]) == 0
    assert main(["fit", "dense.csv", "--zeros", "4", "--poles", "4", "--degree", "2", "--out", "fit", "--quiet"]) == 0
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["feedforward", str(work / "fit" / "model.json"), *FF, "--accept-misfit", "--out", "ff1",
                 "--quiet"]) == 0
    assert json.loads((elsewhere / "ff1" / "report.json").read_text())["predicted_error_on_strip_rms"] is not None
    # the lab re-measures into the same file name: the model's data are gone, the hash says so
    sw = read_sweep(work / "sweep.csv")
    write_sweep(type(sw)(**{**sw.__dict__, "response": sw.response * 1.01}), work / "sweep.csv")
    capsys.readouterr()
    assert main(["feedforward", str(work / "fit" / "model.json"), *FF, "--accept-misfit", "--out", "ff2",
                 "--quiet"]) == 0
    assert "has changed since the model was fitted" in capsys.readouterr().err
    assert json.loads((elsewhere / "ff2" / "report.json").read_text())["predicted_error_on_strip_rms"] is None


def test_param_without_the_physics_it_overrides_is_bad_input(chain, capsys):
    if not (chain / "fit" / "model.json").exists():          # run alone: make the misfit surrogate here
        assert main(["sweep", "--model", str(chain / "cal" / "model.json"), "--temperatures", "20,30,40,50",
                     "--fmin", "0.1", "--fmax", "9", "--points", "30", "--out", str(chain / "dense.csv"), "--quiet"]) == 0
        assert main(["fit", str(chain / "dense.csv"), "--zeros", "4", "--poles", "4", "--degree", "2",
                     "--out", str(chain / "fit"), "--quiet"]) == 0
    # the surrogate's own physics is used by default; --param has no --model/--set to apply to
    assert main(["feedforward", str(chain / "fit" / "model.json"), *FF, "--param", "d=1e-11",
                 "--out", str(chain / "ffp"), "--quiet"]) == 2
    assert "--param needs the physics it overrides" in capsys.readouterr().err
    assert main(["feedforward", str(chain / "fit" / "model.json"), *FF, "--no-check", "--model",
                 str(chain / "cal" / "model.json"), "--param", "d=1e-11", "--out", str(chain / "ffq"), "--quiet"]) == 2
    assert "--no-check" in capsys.readouterr().err
