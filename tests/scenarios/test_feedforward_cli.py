"""``ipmc feedforward`` and ``ipmc simulate --input``: the control path closed from the shell.

Called through a local argparse parser (scenarios.cli lists the command at merge).  Oracles: the
voltage file is re-simulated by ``ipmc simulate --input`` (a different command, reading the file
back) and must give the tip the feedforward command predicted; the predicted tracking error is
compared with A |P/G - 1| from physmodel's frequency response; the refusal names the first sample
over the limit, located here with numpy on the unrestricted voltage.
"""

import argparse

import numpy as np
import pytest

import physmodel
import surrogate
from physmodel.data.sweep import synthesize_sweep
from physmodel.errors import IPMCError
from scenarios.commands import feedforward, simulate
from scenarios.commands._common import EXIT_FAILED, EXIT_OK

F_HZ = np.logspace(-1, np.log10(9.0), 30)


def _run(argv):
    ap = argparse.ArgumentParser(prog="ipmc")
    sub = ap.add_subparsers(dest="command", required=True)
    feedforward.add_parser(sub)
    simulate.add_parser(sub)
    args = ap.parse_args(argv)
    return args.func(args)


def _cols(path):
    with open(path) as fh:
        lines = [ln for ln in fh if not ln.startswith("#")]
    header = lines[0].strip().split(",")
    data = np.loadtxt(lines[1:], delimiter=",")
    return {h: data[:, i] for i, h in enumerate(header)}


@pytest.fixture(scope="module")
def model_json(tmp_path_factory):
    plant = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    sw = synthesize_sweep(plant, "M", F_HZ, [30.0, 35.0, 40.0, 45.0])
    fit = surrogate.ScheduledFit("coefficients", 4, 4, 2).fit(sw)
    assert fit.converged
    p = tmp_path_factory.mktemp("model") / "model.json"
    fit.model.to_json(p)
    return p, plant, fit.model


def test_feedforward_writes_voltage_checks_it_and_simulate_reproduces_it(model_json, tmp_path, capsys):
    path, plant, model = model_json
    out = tmp_path / "ff"
    rc = _run(["feedforward", str(path), "--temperature", "37", "--amplitude", "0.3", "--frequency", "1",
               "--fs", "10000", "--set", "seed001_actuator", "--out", str(out)])
    assert rc == EXIT_OK
    assert (out / "feedforward.png").stat().st_size > 0 and (out / "report.md").exists()
    c = _cols(out / "voltage.csv")
    assert set(c) == {"time_s", "voltage_V", "reference_mm", "predicted_tip_mm"}
    assert 0.2 < np.max(np.abs(c["voltage_V"])) < 1.0               # ~0.4 V, not tens of volts
    report = (out / "report.md").read_text()
    assert "preview: auto" in report and "steady-state prediction" in report
    # closing the loop with the other command: the file drives the physics to the same tip
    sim = tmp_path / "sim.csv"
    assert _run(["simulate", "--set", "seed001_actuator", "--temperature", "37", "--input",
                 str(out / "voltage.csv"), "--out", str(sim), "--quiet"]) == EXIT_OK
    s = _cols(sim)
    # two methods: feedforward's exact frequency-domain simulation and simulate's vector-fitted realisation
    # (max relative error 1e-4 by construction): they agree to that tolerance
    np.testing.assert_allclose(s["tip_displacement_m"] * 1e3, c["predicted_tip_mm"], rtol=0,
                               atol=1e-4 * np.max(np.abs(c["predicted_tip_mm"])))
    np.testing.assert_allclose(s["voltage_V"], c["voltage_V"], rtol=0, atol=1e-12)
    # the tracking error between the fades equals the steady-state prediction
    body = (c["time_s"] >= 3.0) & (c["time_s"] <= 7.0)
    err = np.max(np.abs(c["predicted_tip_mm"] - c["reference_mm"])[body])
    P = plant.frequency_response(np.array([1.0]), [37.0])["M"][0, 0, 0] * 1e3
    G = complex(model.at(37.0)(2j * np.pi))
    assert err == pytest.approx(0.3 * abs(P / G - 1), rel=0.15, abs=2e-4)


def _sine():
    from inversion.references import sine

    ref = sine(0.3, 1.0, 8.0, 1000.0, fade_in_s=2.0, fade_out_s=2.0, lead_s=1.0, tail_s=1.0, unit="mm")
    return ref.t, ref.y


def test_voltage_over_the_limit_is_refused_with_the_first_sample(model_json, tmp_path, capsys):
    path, _, model = model_json
    out = tmp_path / "refused"
    rc = _run(["feedforward", str(path), "--temperature", "37", "--amplitude", "0.3", "--frequency", "1",
               "--max-voltage", "0.2", "--no-check", "--out", str(out)])
    assert rc == EXIT_FAILED and not out.exists()
    err = capsys.readouterr().err
    # the option that sets the limit is named, not the library's keyword (issue 26)
    assert "refused" in err and "beyond ±0.2 V (--max-voltage 0.2; " in err and "max_voltage" not in err
    assert "--on-limit warn to proceed" in err and "action=" not in err
    # the Python API keeps its own names
    import inversion
    from inversion.limits import LimitError, Limits

    with pytest.raises(LimitError, match="beyond max_voltage = ±0.2 V .*action='warn'"):
        inversion.feedforward(model.at(37.0), *_sine(), limits=Limits(max_voltage=0.2))
    rc = _run(["feedforward", str(path), "--temperature", "37", "--amplitude", "0.3", "--frequency", "1",
               "--max-rate", "0.5", "--no-check", "--out", str(tmp_path / "rate")])
    err_rate = capsys.readouterr().err
    assert rc == EXIT_FAILED and "V/s (--max-rate 0.5; " in err_rate and "max_rate" not in err_rate, err_rate
    # the same sample, located independently on the unrestricted voltage
    ok = tmp_path / "ok"
    assert _run(["feedforward", str(path), "--temperature", "37", "--amplitude", "0.3", "--frequency", "1",
                 "--no-check", "--quiet", "--out", str(ok)]) == EXIT_OK
    v = _cols(ok / "voltage.csv")["voltage_V"]
    first = int(np.flatnonzero(np.abs(v) > 0.2)[0])
    assert f"at sample {first} " in err
    warn = tmp_path / "warn"
    with pytest.warns(UserWarning, match=r"beyond ±0.2 V \(--max-voltage 0.2; "):
        assert _run(["feedforward", str(path), "--temperature", "37", "--amplitude", "0.3", "--frequency",
                     "1", "--max-voltage", "0.2", "--on-limit", "warn", "--no-check", "--quiet",
                     "--out", str(warn)]) == EXIT_OK
    report = (warn / "report.md").read_text()
    assert "LIMIT VIOLATED" in report and "(--max-voltage 0.2; " in report and "max_voltage =" not in report


def test_reference_kinds_and_file(model_json, tmp_path, capsys):
    path, _, _ = model_json
    for extra in (["--reference", "multitone", "--amplitude", "0.1,0.05", "--frequency", "0.5,2"],
                  ["--reference", "steps", "--levels", "0.1,-0.1", "--hold", "1"]):
        out = tmp_path / extra[1]
        assert _run(["feedforward", str(path), "--temperature", "40", *extra, "--no-check", "--quiet",
                     "--out", str(out)]) == EXIT_OK
        c = _cols(out / "voltage.csv")
        assert c["reference_mm"][0] == 0 and c["reference_mm"][-1] == 0
    ref = tmp_path / "ref.csv"
    t = np.arange(0, 6, 1e-3)
    np.savetxt(ref, np.c_[t, 0.2 * np.sin(2 * np.pi * t)], delimiter=",", header="time_s,target_mm", comments="")
    out = tmp_path / "file"
    assert _run(["feedforward", str(path), "--temperature", "40", "--reference-file", str(ref), "--fade", "1",
                 "--no-check", "--quiet", "--out", str(out)]) == EXIT_OK
    assert _cols(out / "voltage.csv")["reference_mm"].size == t.size + 2000     # 1 s rest each side
    # a record that starts and ends mid-swing, not faded: warned about, and its end spike is refused
    np.savetxt(ref, np.c_[t, 0.2 * np.cos(2 * np.pi * t)], delimiter=",", header="time_s,target_mm", comments="")
    argv = ["feedforward", str(path), "--temperature", "40", "--reference-file", str(ref), "--no-check",
            "--quiet", "--out", str(tmp_path / "abrupt")]
    assert _run(argv) == EXIT_FAILED
    err = capsys.readouterr().err
    assert "100 % of its peak at a record end" in err and "refused" in err
    with pytest.warns(UserWarning, match="--max-voltage"):
        assert _run([*argv, "--on-limit", "warn"]) == EXIT_OK
    assert "ends away from rest" in (tmp_path / "abrupt" / "report.md").read_text()


@pytest.mark.parametrize("argv, match", [
    (["--temperature", "80"], "outside the surrogate's range"),
    (["--temperature", "35", "--reference", "sine", "--amplitude", "0.1,0.2"], "one --amplitude"),
    (["--temperature", "35", "--frequency", "600"], "below fs_hz/2"),
])
def test_bad_input(model_json, tmp_path, argv, match):
    path, _, _ = model_json
    with pytest.raises(IPMCError, match=match):
        _run(["feedforward", str(path), *argv, "--no-check", "--out", str(tmp_path / "x")])


def test_simulate_input_errors(tmp_path):
    bad = tmp_path / "v.csv"
    np.savetxt(bad, np.c_[np.arange(5) * 1e-3, np.ones(5)], delimiter=",", header="time_s,current_A", comments="")
    with pytest.raises(IPMCError, match="is a current, but a actuator is driven by a voltage|no voltage_"):
        _run(["simulate", "--input", str(bad), "--input-column", "current_A", "--out", str(tmp_path / "o.csv")])
    with pytest.raises(IPMCError, match="no voltage_<unit> column"):
        _run(["simulate", "--input", str(bad), "--out", str(tmp_path / "o.csv")])
    with pytest.raises(IPMCError, match="not both"):
        _run(["simulate", "--input", str(bad), "--experiment", "step", "--out", str(tmp_path / "o.csv")])


def test_a_too_short_preview_is_flagged(model_json, tmp_path, capsys):
    path, _, _ = model_json
    out = tmp_path / "short"
    # the 4/r0 rule asks this 4/4 surrogate for more than 3 V (refused by default); lift the limit
    # to see the preview itself flagged
    assert _run(["feedforward", str(path), "--temperature", "37", "--preview", "4/r0", "--no-check", "--quiet",
                 "--out", str(out)]) == EXIT_FAILED
    assert _run(["feedforward", str(path), "--temperature", "37", "--preview", "4/r0", "--max-voltage", "100",
                 "--no-check", "--quiet", "--out", str(out)]) == EXIT_OK
    assert "preview too short" in (out / "report.md").read_text()
    assert "changes the voltage by" in capsys.readouterr().err


@pytest.mark.parametrize("opts, needle", [
    (["--max-voltage", "0"], "--max-voltage 0: expected a finite number > 0 [V]"),
    (["--max-voltage", "-1"], "--max-voltage -1: expected a finite number > 0"),
    (["--max-voltage", "nan"], "--max-voltage nan: expected a finite number > 0"),
    (["--max-voltage", "inf"], "--max-voltage inf: expected a finite number > 0"),
    (["--max-rate", "0"], "--max-rate 0: expected a finite number > 0 [V/s]"),
    (["--max-rate", "-5"], "--max-rate -5: expected a finite number > 0"),
    (["--max-voltage", "5", "--no-voltage-limit"], "give one of them"),
])
def test_limit_options_must_be_positive_exit_2(model_json, tmp_path, capsys, opts, needle):
    """Today --max-voltage 0 switched the limit off and wrote a 99 V drive with exit 0."""
    from scenarios.cli import main

    path, _, _ = model_json
    out = tmp_path / "x"
    assert main(["feedforward", str(path), "--temperature", "37", "--preview", "4/r0", *opts, "--no-check",
                 "--quiet", "--out", str(out)]) == 2
    assert needle in capsys.readouterr().err
    assert not out.exists()


def test_no_voltage_limit_is_explicit_and_said(model_json, tmp_path, capsys):
    """The 4/r0 preview asks this surrogate for tens of volts: refused by default (3 V); with
    --no-voltage-limit it is written, and stderr and the report say the drive is not limited."""
    path, _, _ = model_json
    argv = ["feedforward", str(path), "--temperature", "37", "--preview", "4/r0", "--no-check", "--quiet"]
    assert _run([*argv, "--out", str(tmp_path / "default")]) == EXIT_FAILED
    assert "beyond ±3 V (--max-voltage 3; " in capsys.readouterr().err
    out = tmp_path / "unlimited"
    assert _run([*argv, "--no-voltage-limit", "--out", str(out)]) == EXIT_OK
    assert "--no-voltage-limit: the drive voltage is not limited" in capsys.readouterr().err
    v = _cols(out / "voltage.csv")["voltage_V"]
    assert np.max(np.abs(v)) > 10.0
    assert "--max-voltage **none (--no-voltage-limit)**" in (out / "report.md").read_text()
    # the CLI default is the library's one constant
    from inversion.limits import DEFAULT_MAX_VOLTAGE
    from scenarios.commands.feedforward import drive_limits

    ap = argparse.ArgumentParser()
    feedforward.add_parser(ap.add_subparsers())
    args = ap.parse_args(["feedforward", "m.json", "--temperature", "30", "--out", "o"])
    assert drive_limits(args) == (DEFAULT_MAX_VOLTAGE, None)


def test_limit_flags_follow_the_library_wording():
    """``limit_flags`` rewrites the library's limit messages into this command's options; it is
    applied to messages the library itself produced, so a change of their wording fails here
    instead of silently leaving Python keywords in what the user reads."""
    from inversion.limits import LimitError, Limits, check_limits
    from scenarios.commands.feedforward import limit_flags

    t = np.arange(200) * 1e-3
    y = 3.0 * np.sin(2 * np.pi * 20 * t)           # peak 3 V, peak rate 2π·20·3 ≈ 377 V/s
    for limits, option, keyword in ((Limits(max_voltage=2.0), "--max-voltage 2", "max_voltage"),
                                    (Limits(max_rate=100.0), "--max-rate 100", "max_rate")):
        with pytest.raises(LimitError) as exc:
            check_limits(y, 1e-3, limits, what="feedforward voltage", unit="V")
        said = limit_flags(str(exc.value), 2.0, 100.0)
        assert option in said, said
        assert keyword + " =" not in said, said
        assert "samples violate it" in said
