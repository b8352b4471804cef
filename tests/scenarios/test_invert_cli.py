"""``ipmc invert`` subcommand: CSV in/out, plot, exit codes, atomic writes."""

import argparse

import numpy as np
import pytest

from inversion import invert
from inversion.examples import SEED000_DEN_35C, SEED000_NUM_35C
from scenarios.cli import main
from scenarios.commands.invert import add_parser

NUM = "--num=" + ",".join(str(c) for c in SEED000_NUM_35C)
DEN = "--den=" + ",".join(str(c) for c in SEED000_DEN_35C)


def _args(argv):
    parser = argparse.ArgumentParser(prog="ipmc")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    return parser.parse_args(argv)


@pytest.fixture
def signal_csv(tmp_path):
    t = np.arange(0.0, 1.0, 1e-3)
    cur = np.sin(2 * np.pi * 20 * t) * np.sin(np.pi * t) ** 2
    ref = 0.2 * cur
    p = tmp_path / "in.csv"
    with open(p, "w") as fh:
        fh.write("time_s,current_uA,disp_mm\n")
        np.savetxt(fh, np.column_stack([t, cur, ref]), delimiter=",", fmt="%.12g")
    return p, t, cur, ref


def _read(path):
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1)


def test_invert_writes_csv_and_plot(signal_csv, tmp_path):
    p, t, cur, ref = signal_csv
    out, png = tmp_path / "out.csv", tmp_path / "out.png"
    rc = main(["invert", str(p), "-o", str(out), NUM, DEN, "--preview", "auto",
                    "--reference", "disp_mm", "--plot", str(png)])
    assert rc == 0
    header, data = _read(out)
    assert header == ["time_s", "current_uA", "reconstruction", "disp_mm", "error"]
    expect = invert((list(SEED000_NUM_35C), list(SEED000_DEN_35C)), t, cur, preview="auto").output
    np.testing.assert_allclose(data[:, 2], expect, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(data[:, 4], data[:, 2] - data[:, 3], rtol=1e-9, atol=1e-12)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*.part"))


def test_main_entry_point_and_preview_options(signal_csv, tmp_path):
    p, t, cur, _ = signal_csv
    out = tmp_path / "o.csv"
    assert main(["invert", str(p), "-o", str(out), NUM, DEN, "--preview", "inf",
                 "--column", "current_uA"]) == 0
    _, data = _read(out)
    expect = invert((list(SEED000_NUM_35C), list(SEED000_DEN_35C)), t, cur, preview="inf").output
    np.testing.assert_allclose(data[:, 2], expect, rtol=1e-10, atol=1e-12)
    assert data.shape[1] == 3


@pytest.mark.parametrize(
    "content, extra, match",
    [
        ("time_s,x\n0,1\n0.001,nan\n0.002,1\n", [], "finite"),
        ("time_s,x\n0,1\n0.001,2\n0.003,1\n0.004,0\n", [], "uniformly"),
        ("t,x\n0,1\n0.001,2\n", [], "time column"),
        ("time_s,x\n0,1\n0.001,abc\n", [], "non-numeric"),
        ("time_s,x\n0,1\n0.001,2\n", ["--column", "y"], "signal column"),
        ("time_s,x\n" + "".join(f"{k * 1e-3},0\n" for k in range(50)), ["--preview", "1.0"], "longer than the record"),
    ],
)
def test_bad_input_exit_code_2(tmp_path, capsys, content, extra, match):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    out = tmp_path / "o.csv"
    rc = main(["invert", str(p), "-o", str(out), NUM, DEN, "--preview", "inf", *extra])
    assert rc == 2
    assert match in capsys.readouterr().err
    assert not out.exists()


def test_bad_model_options_exit_code_2(signal_csv, tmp_path, capsys):
    p, *_ = signal_csv
    out = str(tmp_path / "o.csv")
    assert main(["invert", str(p), "-o", out, NUM]) == 2
    assert "--num and --den" in capsys.readouterr().err
    assert main(["invert", str(p), "-o", out, "--num=100", "--den=1,14,100"]) == 2
    assert "improper" in capsys.readouterr().err
    assert main(["invert", str(p), "-o", out, "--num=100", "--den=1,14,100",
                      "--improper", "filter", "--filter-bandwidth", "500", "--preview", "inf"]) == 0
    assert main(["invert", str(p), "-o", out, "--surrogate", "m.json"]) == 2
    assert "--temperature" in capsys.readouterr().err
    assert main(["invert", str(p), "-o", out, NUM, DEN, "--surrogate", "m.json",
                      "--temperature", "35"]) == 2
    assert main(["invert", str(p), "-o", out, "--num=1,x", DEN]) == 2
    assert "'x'" in capsys.readouterr().err
    assert main(["invert", str(tmp_path / "missing.csv"), "-o", out, NUM, DEN]) == 2


def test_interrupted_write_leaves_previous_file_intact(signal_csv, tmp_path, monkeypatch):
    p, *_ = signal_csv
    out = tmp_path / "o.csv"
    out.write_text("previous result\n")

    def boom(fh, *a, **k):
        fh.write("0,1,2\n0.001,1,")       # half a table, then the "crash"
        raise OSError("disk full")

    monkeypatch.setattr(np, "savetxt", boom)
    assert main(["invert", str(p), "-o", str(out), NUM, DEN]) == 2
    assert out.read_text() == "previous result\n"
    assert not list(tmp_path.glob(".*.part"))
