"""``ipmc frf`` with no estimator option on CSV records written here (a Schroeder multisine through
a resonance filtered with scipy.signal, no header but the channels): every excited line and no
other, the detection said; clipped, pure-noise and too-short records refused or warned."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from scipy import signal

from physmodel.data.files import read_sweep
from physmodel.data.timerecord import TimeRecord
from physmodel.errors import IPMCError
from scenarios.commands import frf

FS = 500.0
N = 1000
LINES = np.unique(np.round(np.geomspace(1, 200, 25)).astype(int))
WN = 2 * np.pi * 40.0
B, A = signal.cont2discrete(([WN**2], [1.0, 2 * 0.15 * WN, WN**2]), 1 / FS, "zoh")[:2]


def _run(argv):
    parser = argparse.ArgumentParser(prog="ipmc")
    frf.add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


def _csv(path, u, y, unit="mm"):
    TimeRecord(np.arange(u.size) / FS, {"drive": u, "tip": y}, {"drive": "V", "tip": unit}).save(path)
    return str(path)


def _multisine(periods=8):
    X = np.zeros(N // 2 + 1, dtype=complex)
    X[LINES] = N / 2 * np.exp(-1j * np.pi * np.arange(LINES.size)**2 / LINES.size)
    return np.tile(np.fft.irfft(X, N), periods)


def test_default_estimate_of_a_periodic_record_is_the_excited_lines(tmp_path, capsys):
    u = _multisine()
    y = signal.lfilter(np.ravel(B), A, u) + 0.02 * np.random.default_rng(0).standard_normal(u.size)
    rec = _csv(tmp_path / "daq.csv", u, y)
    out = tmp_path / "sweep.csv"
    assert _run(["frf", rec, "--input", "drive", "--output", "tip", "--temperature", "25", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    sw = read_sweep(out)
    np.testing.assert_allclose(sw.frequency_hz, LINES * FS / N, rtol=1e-12)
    assert "periodic input: period 1000 samples" in cap.out and "periodic_h1" in cap.out
    assert sw.metadata["method"] == "periodic_h1" and "periodic input" in sw.metadata["excitation"]
    assert cap.err == "" and "warnings" not in sw.metadata


def test_pure_noise_output_is_never_a_quiet_success(tmp_path, capsys):
    u = _multisine()
    rec = _csv(tmp_path / "noise.csv", u, np.random.default_rng(1).standard_normal(u.size))
    out = tmp_path / "n.csv"
    try:
        code = _run(["frf", rec, "--input", "drive", "--output", "tip", "--temperature", "25", "--out", str(out)])
    except IPMCError as exc:                     # every line dropped: refused, naming the coherence
        assert "low coherence" in str(exc)
    else:
        assert code == 0 and "low coherence" in capsys.readouterr().err
        assert "low coherence" in read_sweep(out).metadata["warnings"]


def test_clipped_and_too_short_records_are_refused(tmp_path, capsys):
    u = _multisine()
    y = signal.lfilter(np.ravel(B), A, u)
    y = np.clip(y, -0.3 * np.abs(y).max(), 0.3 * np.abs(y).max())
    rec = _csv(tmp_path / "clip.csv", u, y)
    base = ["frf", rec, "--input", "drive", "--output", "tip", "--temperature", "25"]
    with pytest.raises(IPMCError, match=r"clip.csv: clipped: tip: .*% of samples"):
        _run(base + ["--out", str(tmp_path / "c.csv")])
    assert not (tmp_path / "c.csv").exists()
    assert _run(base + ["--max-clipped-fraction", "1", "--out", str(tmp_path / "c.csv")]) == 0
    assert "clipped" in capsys.readouterr().err
    assert "clipped" in read_sweep(tmp_path / "c.csv").metadata["warnings"]
    # the explicit Welch options still work, and still see the clipping
    with pytest.raises(IPMCError, match="clipped"):
        _run(base + ["--nperseg", "1000", "--out", str(tmp_path / "w.csv")])
    short = _csv(tmp_path / "short.csv", u[:10], y[:10])
    with pytest.raises(IPMCError, match="short.csv: .*10 samples.*too short"):
        _run(["frf", short, "--input", "drive", "--output", "tip", "--temperature", "25",
              "--out", str(tmp_path / "s.csv")])
