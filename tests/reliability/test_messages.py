"""Issue 28: messages name flags the user can type, the real cause and the final output path;
warnings are one clean line; temperatures that look like kelvin are refused by every command that
reads temperatures; ``ipmc --help``/``--version`` import nothing heavy."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scenarios.cli import main

sys.path.insert(0, str(Path(__file__).parent))
import fuzzcases  # noqa: E402
from _faults import env, ipmc  # noqa: E402


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    d = tmp_path_factory.mktemp("msg")
    fuzzcases.valid_sweep(d, "sweep3.csv", temps=(20.0, 35.0, 50.0), points=14)
    for zeros in (1, 2):
        assert main(["fit", str(d / "sweep3.csv"), "--zeros", str(zeros), "--poles", "2", "--degree", "1",
                     "--out", str(d / f"fit{zeros}"), "--quiet", "--accept-misfit"]) in (0, 3)
    return d


def test_feedforward_names_its_own_flags_for_an_improper_inverse(work, tmp_path, capsys):
    argv = ["feedforward", str(work / "fit1" / "model.json"), "--temperature", "30", "--reference", "sine",
            "--amplitude", "0.1", "--frequency", "1", "--no-check", "--quiet", "--accept-misfit"]   # (the fit's misfit is not the subject)
    assert main([*argv, "--out", str(tmp_path / "ff")]) == 2
    err = capsys.readouterr().err
    assert "--improper filter" in err and "--filter-bandwidth" in err and "improper='filter'" not in err
    assert not (tmp_path / "ff").exists()
    # ... and the flags it names work
    assert main([*argv, "--improper", "filter", "--filter-bandwidth", "300", "--out", str(tmp_path / "ff")]) == 0
    assert (tmp_path / "ff" / "voltage.csv").exists()


def test_on_limit_warn_says_one_clean_line_per_warning(work, tmp_path):
    p = ipmc(["feedforward", work / "fit2" / "model.json", "--temperature", "30", "--reference", "sine",
              "--amplitude", "5", "--frequency", "1", "--no-check", "--max-voltage", "0.5", "--on-limit", "warn",
              "--accept-misfit", "--out", tmp_path / "ff", "--quiet"], tmp_path)
    assert p.returncode == 0, p.stderr[-1000:]
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert any("beyond" in ln and "0.5 V" in ln for ln in lines), lines
    assert all(ln.startswith("ipmc feedforward: ") for ln in lines), lines      # no echoed source line
    assert "warnings.warn" not in p.stderr and ".py:" not in p.stderr


def test_study_out_under_a_file_fails_before_the_study_naming_the_final_path(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    out = tmp_path / "file" / "table.csv"
    t0 = time.perf_counter()
    assert main(["study", "actuator_mc", "--out", str(out), "--quiet", "--serial"]) == 2
    err = capsys.readouterr().err
    assert str(out) in err and ".part" not in err
    assert time.perf_counter() - t0 < 5                     # the 200-sample study never ran


def test_a_write_that_fails_names_the_file_asked_for_not_the_temporary_one(tmp_path):
    import errno

    from physmodel.data.files import atomic_write

    (tmp_path / "ro").mkdir()
    (tmp_path / "ro").chmod(0o500)
    try:
        with pytest.raises(OSError) as info:
            import os

            if os.access(tmp_path / "ro", os.W_OK):
                pytest.skip("running as a user who can write anywhere")
            atomic_write(tmp_path / "ro" / "x.csv", lambda fh: fh.write("x"))
        assert info.value.filename == str(tmp_path / "ro" / "x.csv") and info.value.errno == errno.EACCES
    finally:
        (tmp_path / "ro").chmod(0o700)


# ------------------------------------------------------------------------------------- kelvin
def _kelvin_sweep(d: Path) -> Path:
    """A sweep whose temperature_c column holds 293.15/313.15 (kelvin written into the °C column)."""
    from faultcases import set_temperature_column

    return set_temperature_column(fuzzcases.valid_sweep(d, "k.csv", temps=(20.0, 40.0), points=8),
                                  lambda c: c + 273.15)


def _kelvin_cases(d: Path):
    k = _kelvin_sweep(d)
    study = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
    (d / "kstudy.toml").write_text(study.replace("temperatures_c = [20.0, 35.0, 50.0]", "temperatures_c = [293.15, 308.15]"))
    doc = fuzzcases._deep(fuzzcases.MINI_SCENARIO)
    doc["sweep"]["temperatures_c"] = [293.15, 313.15]
    doc.pop("surrogate")
    sc = fuzzcases.write_scenario(d, doc, "kscenario.toml")
    rec = d / "rec.csv"
    assert main(["simulate", "--duration", "2", "--fs", "200", "--out", str(rec), "--quiet"]) == 0
    hot = d / "hot.csv"                                  # the record's own header says 298 (kelvin)
    hot.write_text(rec.read_text().replace("# temperature_c: 25\n", "# temperature_c: 298.15\n"))
    return {
        "sweep --temperatures": (["sweep", "--temperatures", "293,313", "--points", "5", "--out", d / "o.csv"], "--temperatures"),
        "simulate --temperature": (["simulate", "--temperature", "300", "--out", d / "o.csv"], "--temperature"),
        "feedforward --temperature": (["feedforward", d / "missing.json", "--temperature", "303", "--reference", "sine",
                                       "--amplitude", "0.1", "--frequency", "1", "--out", d / "ff"], "--temperature"),
        "frf --temperature": (["frf", rec, "--input", "voltage", "--output", "tip_displacement", "--temperature", "298",
                               "--out", d / "o.csv"], "--temperature"),
        "frf record header": (["frf", hot, "--input", "voltage", "--output", "tip_displacement", "--out", d / "o.csv"],
                              str(hot)),
        "calibrate sweep file": (["calibrate", k, "--set", "seed002_table3", "--free", "d", "--out", d / "c"], str(k)),
        "diagnose sweep file": (["diagnose", "--data", k, "--set", "seed002_table3", "--out", d / "dg"], str(k)),
        "fit sweep file": (["fit", k, "--out", d / "f"], str(k)),
        "study TOML": (["study", d / "kstudy.toml", "--out", d / "o.csv"], "temperatures_c"),
        "run scenario TOML": (["run", sc, "--out", d / "r"], "temperatures_c"),
    }


def test_kelvin_in_a_celsius_column_or_option_is_refused_by_every_command(tmp_path, capsys):
    for what, (argv, token) in _kelvin_cases(tmp_path).items():
        capsys.readouterr()
        code = main([*map(str, argv), "--quiet"])
        err = capsys.readouterr().err
        assert code == 2, f"{what}: exit {code}: {err[-500:]}"
        assert token in err and ("kelvin" in err or "150 °C" in err), f"{what}: {err[-500:]}"


# ------------------------------------------------------------------------------ the command line
def test_help_and_version_import_nothing_heavy():
    code = ("import sys; from scenarios.cli import main\n"
            "for argv in (['--help'], ['--version']):\n"
            "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
            "heavy = sorted(m for m in ('numpy', 'scipy', 'casadi', 'matplotlib', 'physmodel') if m in sys.modules)\n"
            "print('HEAVY', heavy, file=sys.stderr)")
    p = subprocess.run([sys.executable, "-c", code], env=env(), capture_output=True, text=True, timeout=120)
    assert "HEAVY []" in p.stderr, p.stderr[-1500:]


def test_the_command_table_agrees_with_the_command_modules():
    import scenarios.cli as cli
    from scenarios.commands import _common

    assert (cli.EXIT_BAD_INPUT, cli.EXIT_FAILED, cli.EXIT_INTERRUPTED) == (
        _common.EXIT_BAD_INPUT, _common.EXIT_FAILED, _common.EXIT_INTERRUPTED)
    full = cli.build_parser()
    sub = next(a for a in full._actions if a.dest == "command")
    helps = {a.dest: a.help for a in sub._choices_actions}
    assert helps == dict(cli.COMMANDS)
    assert list(sub.choices) == list(cli.NAMES)


def test_each_command_still_parses_alone(tmp_path, capsys):
    assert main(["sets"]) == 0
    with pytest.raises(SystemExit) as e:
        main(["sweep", "--help"])
    assert e.value.code == 0 and "--points" in capsys.readouterr().out


def test_a_model_json_downstream_of_an_interrupted_fit_is_refused(work, tmp_path, capsys):
    legacy = tmp_path / "oldfit"
    legacy.mkdir()
    (legacy / "model.json").write_bytes((work / "fit2" / "model.json").read_bytes())
    assert json.loads((legacy / "model.json").read_text())["info"]["data"]["fingerprint"]
    assert main(["feedforward", str(legacy / "model.json"), "--temperature", "30", "--reference", "sine",
                 "--amplitude", "0.1", "--frequency", "1", "--no-check", "--out", str(tmp_path / "ff"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(legacy) in err and "interrupted" in err
