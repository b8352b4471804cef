"""``ipmc excite`` (scenarios.commands.excite): the signal files it writes, checked by an FFT of the
samples (the designed lines and nothing else), the stated durations and crest factors recomputed
from the samples, and bad input named by its option."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from physmodel.data.timerecord import read_record
from physmodel.errors import IPMCError
from scenarios.commands import excite


def _run(argv):
    parser = argparse.ArgumentParser(prog="ipmc")
    sub = parser.add_subparsers(dest="command", required=True)
    excite.add_parser(sub)
    args = parser.parse_args(["excite", *argv])
    return args.func(args)


@pytest.mark.parametrize("ext", ["csv", "npz", "mat"])
def test_multisine_file_holds_exactly_the_designed_lines(tmp_path, capsys, ext):
    out = tmp_path / f"ms.{ext}"
    assert _run(["multisine", "--fs", "200", "--period", "5", "--fmin", "0.2", "--fmax", "20", "--count", "25",
                 "--rms", "0.5", "--periods", "3", "--transient-periods", "2", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    rec = read_record(out)
    u = rec.channels["voltage"]
    assert rec.units == {"voltage": "V"} and u.size == 5 * 5 * 200
    one = u[:1000]
    np.testing.assert_allclose(u, np.tile(one, 5), atol=1e-12)                  # periodic
    X = np.fft.rfft(one)
    excited = np.flatnonzero(np.abs(X) > 1e-9 * np.abs(X).max())
    design = json.loads(rec.metadata["multisine"])
    np.testing.assert_array_equal(excited, design["lines"])
    want = np.unique(np.maximum(np.round(np.geomspace(0.2, 20, 25) * 5), 1)).astype(int)
    np.testing.assert_array_equal(design["lines"], want)
    assert np.sqrt(np.mean(u**2)) == pytest.approx(0.5, rel=1e-12)
    cf = np.max(np.abs(u)) / np.sqrt(np.mean(u**2))
    assert f"crest factor {cf:.3f}" in text
    assert "expected duration 25 s" in text and float(rec.metadata["expected_duration_s"]) == 25.0


def test_stepped_plan_round_trips_and_the_duration_is_the_samples(tmp_path, capsys):
    from physmodel.data.excitation import SteppedSinePlan

    out = tmp_path / "st.csv"
    assert _run(["stepped", "--fs", "500", "--frequencies", "1,2.5,7", "--amplitude", "0.3", "--periods", "4",
                 "--settle-s", "0.5", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    rec = read_record(out)
    plan = SteppedSinePlan.from_record(rec)
    np.testing.assert_array_equal(plan.frequency_hz, [1.0, 2.5, 7.0])
    n = rec.t.size
    # each step: 0.5 s settle + 4 periods, rounded up to whole samples
    assert n == sum(int(np.ceil((0.5 + 4 / f) * 500 - 1e-9)) for f in (1.0, 2.5, 7.0))
    assert f"expected duration {n / 500:g} s" in text
    assert np.max(np.abs(rec.channels["voltage"])) <= 0.3 + 1e-12


def test_chirp_repeats_and_sensor_channel(tmp_path):
    out = tmp_path / "ch.npz"
    assert _run(["chirp", "--fs", "1000", "--f0", "1", "--f1", "50", "--sweep-s", "2", "--repeats", "3",
                 "--channel", "tip_displacement", "--quiet", "--out", str(out)]) == 0
    rec = read_record(out)
    assert rec.units == {"tip_displacement": "mm"}
    x = rec.channels["tip_displacement"]
    assert x.size == 6000
    np.testing.assert_array_equal(x[:2000], x[4000:])


@pytest.mark.parametrize("argv, match", [
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1,2", "--out", "x.txt"], "--out"),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1,2", "--fmin", "1", "--out", "x.csv"],
     "--frequencies"),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1.5", "--out", "x.csv"], "--frequencies: "),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1,abc", "--out", "x.csv"], "--frequencies"),
    (["multisine", "--fs", "100", "--period", "1", "--fmin", "1", "--out", "x.csv"], "--fmax"),
    (["multisine", "--fs", "100", "--period", "0", "--frequencies", "1", "--out", "x.csv"], "--period"),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1", "--phases", "random", "--out", "x.csv"],
     "--seed"),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1", "--rms", "1", "--amplitude", "2",
      "--out", "x.csv"], "--rms"),
    (["multisine", "--fs", "100", "--period", "1", "--frequencies", "1", "--channel", "1bad", "--out", "x.csv"],
     "--channel"),
    (["stepped", "--fs", "100", "--frequencies", "30", "--out", "x.csv"], "--frequencies must .*fs/4"),
    (["stepped", "--fs", "100", "--fmin", "2", "--fmax", "1", "--count", "3", "--out", "x.csv"], "--fmin"),
    (["stepped", "--fs", "100", "--frequencies", "1", "--periods", "1", "--out", "x.csv"], "--periods="),
    (["chirp", "--fs", "100", "--f0", "5", "--f1", "1", "--sweep-s", "1", "--out", "x.csv"], "--f0="),
])
def test_bad_input_names_the_option(tmp_path, monkeypatch, argv, match):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(IPMCError, match=match):
        _run(argv)
    assert not list(tmp_path.iterdir())                      # nothing (half-)written


def test_a_drive_above_3_V_is_warned_about_naming_the_options(tmp_path, capsys):
    """The README's multisine (1 V RMS, Schroeder phases over log-spaced lines) peaks at 3.9 V:
    written (exit 0) with a warning naming --rms (the value that brings the peak to 3 V, checked
    here by regenerating with it) and --phases clipped (whose peak, regenerated, is below 3 V)."""
    import re

    argv = ["multisine", "--fs", "500", "--period", "10", "--fmin", "0.1", "--fmax", "9", "--count", "30",
            "--periods", "2"]
    out = tmp_path / "ms.csv"
    assert _run([*argv, "--rms", "1", "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    u = read_record(out).channels["voltage"]
    peak = float(np.max(np.abs(u)))
    assert peak > 3.0
    assert f"the drive's peak {peak:.4g} V exceeds the 3 V" in err and "--phases clipped" in err
    assert "drive_warning" in read_record(out).metadata
    rms = float(re.search(r"--rms ([0-9.]+)", err).group(1))
    assert rms == pytest.approx(3.0 / peak, rel=2e-3) and rms <= 3.0 / peak
    for fix in (["--rms", str(rms)], ["--rms", "1", "--phases", "clipped"]):
        fixed = tmp_path / "fixed.csv"
        assert _run([*argv, *fix, "--out", str(fixed), "--quiet"]) == 0
        assert np.max(np.abs(read_record(fixed).channels["voltage"])) <= 3.0
        assert "warning" not in capsys.readouterr().err
    # a sine: the amplitude is the only knob; a displacement channel is no drive voltage
    assert _run(["chirp", "--fs", "200", "--f0", "1", "--f1", "5", "--sweep-s", "2", "--amplitude", "4",
                 "--out", str(tmp_path / "c.csv"), "--quiet"]) == 0
    assert "--amplitude 3 " in capsys.readouterr().err
    assert _run(["chirp", "--fs", "200", "--f0", "1", "--f1", "5", "--sweep-s", "2", "--amplitude", "4",
                 "--channel", "tip_displacement", "--out", str(tmp_path / "d.csv"), "--quiet"]) == 0
    assert "warning" not in capsys.readouterr().err
    # mV: 2000 mV is 2 V, no warning; 4000 mV is
    for amp, warned in (("2000", False), ("4000", True)):
        assert _run(["stepped", "--fs", "200", "--frequencies", "1", "--amplitude", amp, "--unit", "mV",
                     "--out", str(tmp_path / "s.csv"), "--quiet"]) == 0
        assert ("exceeds the 3 V" in capsys.readouterr().err) is warned
