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


# ------------------------------------------------------------------ --lines (issue 26, what remained 5)
def _lines_file(path, transient_periods):
    """The --lines signal file of the test's multisine (its lines and period, in the library's format)."""
    from physmodel.data.excitation import Multisine

    ms = Multisine(FS, N, LINES, np.ones(LINES.size), -np.pi * np.arange(LINES.size)**2 / LINES.size,
                   channel="drive", unit="V")
    assert np.max(np.abs(ms.period() - _multisine(1))) < 1e-12        # the same signal as the records'
    ms.record(6, transient_periods).save(path)
    return str(path)


def _err_over_sigma_rms(sw):
    """RMS of error/σ (log-magnitude and phase) against the filter's own response (scipy freqz)."""
    ln = np.log(10.0) / 20.0
    _, truth = signal.freqz(np.ravel(B), A, worN=sw.frequency_hz, fs=FS)
    e = np.log(sw.response / truth)
    z = np.concatenate([e.real / (sw.magnitude_std_db * ln), e.imag / np.radians(sw.phase_std_deg)])
    return float(np.sqrt(np.mean(z**2)))


def test_lines_on_a_periodic_record_is_the_periodic_estimate_of_the_default_path(tmp_path, capsys):
    u = _multisine()
    y = signal.lfilter(np.ravel(B), A, u) + 0.02 * np.random.default_rng(3).standard_normal(u.size)
    rec = _csv(tmp_path / "daq.csv", u, y)
    base = ["frf", rec, "--input", "drive", "--output", "tip", "--temperature", "25", "--quiet"]
    assert _run(base + ["--out", str(tmp_path / "a.csv")]) == 0
    assert _run(base + ["--lines", _lines_file(tmp_path / "ms1.csv", 1), "--out", str(tmp_path / "b.csv")]) == 0
    err = capsys.readouterr().err
    a, b = read_sweep(tmp_path / "a.csv"), read_sweep(tmp_path / "b.csv")
    assert a.metadata["method"] == b.metadata["method"] == "periodic_h1"
    assert "estimator: periodic H1 at the 22 lines of --lines" in err and "σ from the period-to-period scatter" in err
    # the same excited lines, the same whole periods (the plant's transient, found in the first period, is the
    # design's one transient period): the same estimate and σ to rounding
    np.testing.assert_allclose(b.frequency_hz, LINES * FS / N, rtol=1e-12)
    np.testing.assert_allclose(b.frequency_hz, a.frequency_hz, rtol=1e-12)
    np.testing.assert_allclose(b.response, a.response, rtol=1e-12)
    np.testing.assert_allclose(b.magnitude_std_db, a.magnitude_std_db, rtol=1e-9)
    np.testing.assert_allclose(b.phase_std_deg, a.phase_std_deg, rtol=1e-9)
    assert a.metadata["transient_periods"] == b.metadata["transient_periods"] == "1"
    assert 0.7 <= _err_over_sigma_rms(b) <= 1.4                       # σ calibrated against the true filter
    # a design with more transient periods than the record shows: the design's count is discarded, and said
    assert _run(base + ["--lines", _lines_file(tmp_path / "ms2.csv", 2), "--out", str(tmp_path / "c.csv")]) == 0
    c = read_sweep(tmp_path / "c.csv")
    assert (c.metadata["transient_periods"], c.metadata["periods_used"]) == ("2", "6")
    assert "2 leading period(s) discarded: the design's 2 transient period(s)" in capsys.readouterr().err


def test_lines_on_a_random_record_is_welch_and_said(tmp_path, capsys):
    rng = np.random.default_rng(4)
    u = rng.standard_normal(8 * N)
    y = signal.lfilter(np.ravel(B), A, u) + 0.02 * rng.standard_normal(u.size)
    rec = _csv(tmp_path / "rnd.csv", u, y)
    assert _run(["frf", rec, "--input", "drive", "--output", "tip", "--temperature", "25", "--quiet",
                 "--lines", _lines_file(tmp_path / "ms.csv", 1), "--out", str(tmp_path / "r.csv")]) == 0
    err = capsys.readouterr().err
    r = read_sweep(tmp_path / "r.csv")
    assert r.metadata["method"] == "h1" and "random" in r.metadata["excitation"]
    assert "estimator: Welch H1 (boxcar segments of one period, 1000 samples)" in err and "not periodic" in err
    assert "not periodic" in r.metadata["estimator_note"]          # and in the sweep a later command reads
    np.testing.assert_allclose(r.frequency_hz, LINES * FS / N, rtol=1e-12)
