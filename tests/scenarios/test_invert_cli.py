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
        ("t,x\n0,1\n0.001,2\n", [], "--time-column"),          # the option that fixes it is named
        ("time_s,x\n0,1\n0.001,abc\n", [], "bad.csv:3: x = 'abc' is not a number"),
        ("time_s,x\n0,1\n0.001,2\n", ["--column", "y"], "--column: "),
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


# ------------------------------------------------------------------ NPZ / MAT records (issue 26)
# Files written here with numpy / scipy.io.savemat under a DAQ's or a MATLAB session's own names;
# the oracle is inversion.invert on the same arrays, which never sees a file.
def _expect(t, u, preview="inf"):
    return invert((list(SEED000_NUM_35C), list(SEED000_DEN_35C)), t, u, preview=preview).output


@pytest.fixture
def own_names():
    t = np.arange(0.0, 1.0, 1e-3)
    cur = np.sin(2 * np.pi * 20 * t) * np.sin(np.pi * t) ** 2
    return t, cur, 0.2 * cur


def test_invert_reads_an_npz_by_name_and_by_index(own_names, tmp_path, capsys):
    t, cur, disp = own_names
    p = tmp_path / "daq.npz"
    np.savez(p, t=t, cur=cur, disp=disp)
    for spec in ("cur", "1"):
        out = tmp_path / f"o{spec}.csv"
        rc = main(["invert", str(p), "-o", str(out), NUM, DEN, "--preview", "inf", "--quiet",
                   "--time-column", "t", "--input-column", spec, "--reference", "2"])
        assert rc == 0, capsys.readouterr().err
        header, data = _read(out)
        assert header == ["t", "cur", "reconstruction", "disp", "error"]
        np.testing.assert_array_equal(data[:, 1], np.array([float(f"{v:.12g}") for v in cur]))
        np.testing.assert_allclose(data[:, 2], _expect(t, cur), rtol=1e-10, atol=1e-12)


def test_invert_reads_mat_variables_in_their_time_unit(own_names, tmp_path, capsys):
    from scipy.io import savemat

    t, cur, _ = own_names
    p = tmp_path / "session.mat"
    # row vectors and a scalar and a string beside them, as a MATLAB session saves its workspace
    savemat(p, {"t_ms": (t * 1e3)[None, :], "fs": 1000.0, "note": "bench 3", "i_meas": cur[None, :]})
    out = tmp_path / "o.csv"
    rc = main(["invert", str(p), "-o", str(out), NUM, DEN, "--preview", "inf", "--quiet", "--time-column", "t_ms"])
    assert rc == 0, capsys.readouterr().err
    header, data = _read(out)
    assert header == ["t_ms", "i_meas", "reconstruction"]          # the scalar fs is not a signal
    np.testing.assert_allclose(data[:, 2], _expect(t, cur), rtol=1e-10, atol=1e-12)
    out2 = tmp_path / "o2.csv"                                       # the unit stated instead of named
    savemat(tmp_path / "s2.mat", {"time": (t * 1e3)[:, None], "i_meas": cur[:, None]})
    rc = main(["invert", str(tmp_path / "s2.mat"), "-o", str(out2), NUM, DEN, "--preview", "inf", "--quiet",
               "--time-column", "0", "--time-unit", "ms", "--input-column", "i_meas"])
    assert rc == 0, capsys.readouterr().err
    np.testing.assert_allclose(_read(out2)[1][:, 2], _expect(t, cur), rtol=1e-10, atol=1e-12)


def _bad_files(d, t, cur):
    from scipy.io import savemat

    np.savez(d / "ok.npz", t=t, cur=cur)
    savemat(d / "ok.mat", {"t": t, "cur": cur, "fs": 1000.0})
    (d / "junk.npz").write_bytes(b"not a zip archive")
    (d / "junk.mat").write_bytes(b"MATLAB 5.0 MAT-file, truncated")
    (d / "sig.txt").write_text("t,cur\n0,1\n")
    np.savez(d / "nan.npz", t=t, cur=np.where(t > 0.5, np.nan, cur))


@pytest.mark.parametrize("name, extra, needles", [
    ("ok.npz", ["--time-column", "t", "--input-column", "volts"], ["--input-column: ", "ok.npz", "'volts'", "0:t, 1:cur"]),
    ("ok.npz", ["--time-column", "t", "--input-column", "7"], ["--input-column: ", "ok.npz", "no column 7"]),
    ("ok.npz", ["--time-column", "time_s"], ["--time-column: ", "ok.npz", "0:t, 1:cur"]),
    ("ok.npz", ["--time-column", "t", "--reference", "truth"], ["--reference: ", "'truth'"]),
    ("ok.mat", ["--time-column", "t", "--input-column", "fs"], ["--input-column: ", "'fs'", "1 value(s)"]),
    ("junk.npz", ["--time-column", "t"], ["junk.npz", "not a readable NPZ"]),
    ("junk.mat", ["--time-column", "t"], ["junk.mat", "not a readable MATLAB"]),
    ("sig.txt", [], ["sig.txt", "'.txt'", ".csv, .npz, .mat"]),
    ("missing.npz", [], ["INPUT", "missing.npz", "no such file"]),
    ("nan.npz", ["--time-column", "t"], ["--input-column: ", "nan.npz", "'cur'", "not finite at sample(s) [501"]),
])
def test_invert_bad_record_files_exit_2_naming_file_or_option(own_names, tmp_path, capsys, name, extra, needles):
    t, cur, _ = own_names
    _bad_files(tmp_path, t, cur)
    out = tmp_path / "o.csv"
    rc = main(["invert", str(tmp_path / name), "-o", str(out), NUM, DEN, "--preview", "inf", *extra])
    err = capsys.readouterr().err
    assert rc == 2 and not out.exists()
    assert "Traceback" not in err and all(n in err for n in needles), err
