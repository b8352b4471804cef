"""The ``ipmc`` command line: each subcommand end to end, exit codes, and clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel.data.files import read_csv
from scenarios.cli import main


def test_sweep_writes_csv_and_plot(tmp_path, capsys):
    out = tmp_path / "s.csv"
    png = tmp_path / "s.png"
    rc = main(["sweep", "--temperatures", "20,50", "--fmin", "1", "--fmax", "50", "--points", "12",
               "--noise", "magphase", "--seed", "4", "--out", str(out), "--plot", str(png), "--param", "W=2e-3"])
    assert rc == 0
    sw = read_csv(out)
    assert sw.temperatures().tolist() == [20.0, 50.0] and sw.frequency_hz.size == 24
    assert sw.metadata["seed"] == "4"
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    assert "wrote" in capsys.readouterr().out


def test_sensor_sweep_mat(tmp_path):
    from physmodel.data.files import read_mat

    out = tmp_path / "s.mat"
    assert main(["sweep", "--kind", "sensor", "--set", "seed000_sensor_dev", "--points", "5", "--out", str(out), "--quiet"]) == 0
    assert read_mat(out).output_unit == "uA"


@pytest.mark.parametrize("argv,needle", [
    (["sweep", "--out", "x.txt"], "use a .csv"),
    (["sweep", "--fmin", "10", "--fmax", "1", "--out", "x.csv"], "0 < --fmin < --fmax"),
    (["sweep", "--temperatures", "20,abc", "--out", "x.csv"], "--temperatures must be"),
    (["sweep", "--param", "W2e-3", "--out", "x.csv"], "NAME=VALUE"),
    (["sweep", "--param", "width=1", "--out", "x.csv"], "unknown parameter"),
    (["sweep", "--set", "nope", "--out", "x.csv"], "unknown parameter set 'nope'"),
    (["sweep", "--noise", "magphase", "--out", "x.csv"], "seed"),
    (["sweep", "--temperatures", "150", "--out", "x.csv"], "valid on"),
    (["simulate", "--frequency", "900", "--out", "x.csv"], "fs/2"),
    (["simulate", "--chain", "1,2,3", "--out", "x.csv"], "--kind sensor"),
])
def test_bad_input_exit_code_2_with_a_named_problem(tmp_path, monkeypatch, capsys, argv, needle):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert needle in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []        # nothing half-written


def test_simulate_release_with_chain(tmp_path):
    out = tmp_path / "r.npz"
    rc = main(["simulate", "--kind", "sensor", "--set", "seed000_sensor_dev", "--experiment", "release",
               "--chain", "470e3,10e3,10e3", "--duration", "0.3", "--fs", "2000", "--out", str(out),
               "--plot", str(tmp_path / "r.png"), "--quiet"])
    assert rc == 0
    z = np.load(out)
    assert "amplifier_output_V" in z.files and z["time_s"].size == 601


def test_sets_lists_and_describes(capsys, tmp_path):
    assert main(["sets"]) == 0
    assert "seed002_table3" in capsys.readouterr().out
    assert main(["sets", "seed002_table3", "--json", str(tmp_path / "p.json")]) == 0
    assert "omega_n" in capsys.readouterr().out
    import json

    from physmodel import IPMCParameters, get_parameter_set

    assert IPMCParameters.from_dict(json.loads((tmp_path / "p.json").read_text())) == get_parameter_set("seed002_table3")


def test_demo_writes_a_complete_report(tmp_path):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--quick", "--quiet"]) == 0
    report = (out / "report.md").read_text()
    assert "FAIL" not in report and report.count("| PASS |") >= 8
    for name in ("data/sweep.csv", "surrogate.json", "bode.png", "surrogate_bode.png", "pole_zero_locus.png",
                 "inversion_2_hz_sine_at_45_c.png", "metrics.json"):
        assert (out / name).stat().st_size > 0
    import surrogate

    assert surrogate.load(out / "surrogate.json").is_scheduled
