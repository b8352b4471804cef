"""An output never replaces an input (issue 28): ``ipmc invert``, ``ipmc frf`` and ``ipmc simulate``
refuse an output path that is one of their inputs (also through another spelling or a link), with
exit 2 and a message naming both, and the input is left byte for byte as it was."""

from __future__ import annotations

import os

import numpy as np
import pytest

from scenarios.cli import main


@pytest.fixture
def record(tmp_path):
    t = np.arange(2000) / 500.0
    p = tmp_path / "record.csv"
    p.write_text("time_s,voltage_V,tip_displacement_mm\n" + "\n".join(
        f"{a:.6g},{np.sin(2 * np.pi * a):.6g},{0.1 * np.sin(2 * np.pi * a - 0.3):.6g}" for a in t) + "\n")
    return p


@pytest.mark.parametrize("argv", [
    ["invert", "{rec}", "-o", "{rec}", "--num=1", "--den=1,1"],
    ["invert", "{rec}", "-o", "{alias}", "--num=1", "--den=1,1"],
    ["frf", "{rec}", "--input", "voltage", "--output", "tip_displacement", "--temperature", "25", "--out", "{rec}"],
    ["simulate", "--input", "{rec}", "--temperature", "25", "--out", "{link}"],
])
def test_an_output_that_is_an_input_is_refused(record, tmp_path, capsys, argv):
    (tmp_path / "sub").mkdir()
    alias = tmp_path / "sub" / ".." / "record.csv"
    link = tmp_path / "link.csv"
    os.symlink(record, link)
    before = record.read_bytes()
    args = [a.format(rec=record, alias=alias, link=link) for a in argv]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "never replaces an input" in err and "record.csv" in err
    assert record.read_bytes() == before


def test_fit_refuses_a_sweep_in_kelvin(tmp_path, capsys):
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.data.sweep import synthesize_sweep

    sw = synthesize_sweep(ActuatorModel(get_parameter_set("seed001_actuator")), "M", np.logspace(-1, 1, 12),
                          [20.0, 35.0, 50.0])
    text = sw.to_csv(tmp_path / "c.csv").read_text()
    lines = [ln if ln.startswith("#") or ln.startswith("temperature_c") or not ln.strip()
             else f"{float(ln.split(',')[0]) + 273.15:g}," + ln.split(",", 1)[1] for ln in text.splitlines()]
    (tmp_path / "k.csv").write_text("\n".join(lines) + "\n")
    assert main(["fit", str(tmp_path / "c.csv"), "--zeros", "2", "--poles", "3", "--degree", "1",
                 "--out", str(tmp_path / "ok"), "--quiet"]) in (0, 3)                 # the °C file is fitted
    assert main(["fit", str(tmp_path / "k.csv"), "--zeros", "2", "--poles", "3", "--degree", "1",
                 "--out", str(tmp_path / "no"), "--quiet"]) == 2
    assert "kelvin" in capsys.readouterr().err


def test_invert_blames_the_temperature_not_the_file(record, tmp_path, capsys):
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.data.sweep import synthesize_sweep

    sw = synthesize_sweep(ActuatorModel(get_parameter_set("seed001_actuator")), "M", np.logspace(-1, 1, 12),
                          [20.0, 35.0, 50.0])
    sw.to_csv(tmp_path / "c.csv")
    assert main(["fit", str(tmp_path / "c.csv"), "--zeros", "2", "--poles", "3", "--degree", "1",
                 "--out", str(tmp_path / "fit"), "--quiet"]) in (0, 3)
    capsys.readouterr()
    assert main(["invert", str(record), "--column", "tip_displacement_mm", "--surrogate",
                 str(tmp_path / "fit" / "model.json"), "--temperature", "300", "-o", str(tmp_path / "v.csv")]) == 2
    err = capsys.readouterr().err
    assert "--temperature 300" in err and "outside the surrogate's range [20, 50]" in err
    assert "not a usable surrogate" not in err
