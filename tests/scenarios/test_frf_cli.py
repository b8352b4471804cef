"""``ipmc frf`` (scenarios.commands.frf): the round trip excite → physics (timesim, simulated here,
not by the virtual lab) → frf, judged against the physics' own frequency response within the σ
the sweep states; several channels, the reciprocal, the figure, and bad input named by option."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.files import read_sweep
from physmodel.data.timerecord import TimeRecord, read_record
from physmodel.data.timesim import model_realization, simulate
from physmodel.errors import IPMCError
from scenarios.commands import excite, frf

LN = math.log(10.0) / 20.0
FS = 250.0
MODEL = ActuatorModel(get_parameter_set("seed001_actuator"))


def _run(argv):
    parser = argparse.ArgumentParser(prog="ipmc")
    sub = parser.add_subparsers(dest="command", required=True)
    excite.add_parser(sub)
    frf.add_parser(sub)
    args = parser.parse_args(argv)
    return args.func(args)


def _t2_mean_band(nu: float, n_terms: int, k: float = 4.0):
    mean = nu / (nu - 2)
    var = 3 * nu**2 / ((nu - 2) * (nu - 4)) - mean**2
    return mean, k * math.sqrt(var / n_terms)


def _records(tmp_path, signal, temps, noise_m=20e-6, current=False, header=True):
    """Physics records of a signal file: tip displacement [mm] (and current [mA]) per voltage."""
    sig = read_record(signal)
    u = sig.channels["voltage"]
    paths = []
    for k, T in enumerate(temps):
        real = model_realization(MODEL, T, FS, float(sig.t[-1]))
        ts = simulate(MODEL, T, sig.t, u, realization=real, output_noise_rms=noise_m, seed=100 + k)
        chans, units = {"voltage": u, "tip_displacement": ts.output * 1e3}, {"voltage": "V", "tip_displacement": "mm"}
        if current:
            ci = simulate(MODEL, T, sig.t, u, output="current", output_noise_rms=1e-6, seed=200 + k)
            chans["current"], units["current"] = ci.output * 1e3, "mA"
        meta = {**(sig.metadata if header else {}), "temperature_c": f"{T:g}"}
        p = tmp_path / f"rec_{T:g}.csv"
        TimeRecord(sig.t, chans, units, meta).save(p)
        paths.append(str(p))
    return paths


def _truth(sweep):
    """M(jω) of the physics at the sweep's lines in mm/V, times sinc²(f/fs): timesim plays the
    samples through a first-order hold (see tests/estimation/test_frf.py)."""
    out = np.empty(sweep.response.shape, dtype=complex)
    for T in sweep.temperatures():
        m = sweep.temperature_c == T
        f = sweep.frequency_hz[m]
        out[m] = MODEL.frequency_response(f, [T])["M"][0, 0] * 1e3 * np.sinc(f / FS) ** 2
    return out


def _t2(sweep):
    d = np.log(sweep.response / _truth(sweep))
    return np.concatenate([d.real / (sweep.magnitude_std_db * LN), d.imag / np.radians(sweep.phase_std_deg)]) ** 2


@pytest.fixture(scope="module")
def multisine_signal(tmp_path_factory):
    p = tmp_path_factory.mktemp("sig") / "ms.csv"
    assert _run(["excite", "multisine", "--fs", str(FS), "--period", "5", "--fmin", "0.2", "--fmax", "9",
                 "--count", "20", "--rms", "1", "--periods", "8", "--transient-periods", "2", "--quiet",
                 "--out", str(p)]) == 0
    return p


# ------------------------------------------------------------------------------------- round trips
def test_multisine_round_trip_agrees_with_the_physics_within_sigma(tmp_path, multisine_signal, capsys):
    recs = _records(tmp_path, multisine_signal, [25.0, 45.0], header=False)
    out, png = tmp_path / "sweep.csv", tmp_path / "frf.png"
    assert _run(["frf", *recs, "--lines", str(multisine_signal), "--input", "voltage", "--output",
                 "tip_displacement", "--out", str(out), "--plot", str(png)]) == 0
    cap = capsys.readouterr()
    text = cap.out
    sw = read_sweep(out)
    assert (sw.input_unit, sw.output_unit) == ("V", "mm")
    np.testing.assert_array_equal(sw.temperatures(), [25.0, 45.0])
    n_lines = np.unique(np.maximum(np.round(np.geomspace(0.2, 9, 20) * 5), 1)).size
    assert sw.frequency_hz.size == 2 * n_lines
    # the input is periodic: the periodic estimator over whole 1250-sample periods, said on stderr
    assert f"{n_lines} of {n_lines} lines kept" in text and "period_samples=1250" in text
    assert cap.err.count("estimator: periodic H1") == 2 and sw.metadata["method"] == "periodic_h1"
    # errors over the stated σ: Student t with ν = 2(P − 1) for P = 8 whole periods
    t2 = _t2(sw)
    mean, band = _t2_mean_band(14, t2.size)
    assert abs(t2.mean() - mean) < band, (t2.mean(), mean, band)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_stepped_round_trip_takes_the_plan_from_the_record_header(tmp_path, capsys):
    sig = tmp_path / "st.npz"
    assert _run(["excite", "stepped", "--fs", str(FS), "--fmin", "0.3", "--fmax", "9", "--count", "6",
                 "--periods", "8", "--min-measure-s", "2", "--settle-s", "6", "--quiet", "--out", str(sig)]) == 0
    recs = _records(tmp_path, sig, [30.0])
    out = tmp_path / "st_sweep.npz"
    assert _run(["frf", *recs, "--method", "stepped", "--input", "voltage_V", "--output", "tip_displacement",
                 "--out", str(out)]) == 0
    sw = read_sweep(out)
    assert sw.frequency_hz.size == 6
    t2 = _t2(sw)
    # stepped-sine σ: real and imaginary parts of the period scatter, ν = P − 1 = 7 each
    mean, band = _t2_mean_band(7, t2.size)
    assert abs(t2.mean() - mean) < band, (t2.mean(), mean, band)
    # overriding the plan's periods uses fewer periods and widens σ
    out2 = tmp_path / "st2.csv"
    assert _run(["frf", *recs, "--method", "stepped", "--plan", str(sig), "--periods", "3", "--quiet",
                 "--input", "voltage", "--output", "tip_displacement", "--out", str(out2)]) == 0
    assert np.median(read_sweep(out2).magnitude_std_db) > np.median(sw.magnitude_std_db)


def test_two_outputs_give_two_files_and_the_reciprocal_is_the_impedance(tmp_path, multisine_signal, capsys):
    recs = _records(tmp_path, multisine_signal, [25.0], current=True)
    out = tmp_path / "s.csv"
    assert _run(["frf", *recs, "--input", "voltage", "--output", "tip_displacement", "--output", "current",
                 "--out", str(out), "--plot", str(tmp_path / "f.png")]) == 0        # lines from the header
    m, i = read_sweep(tmp_path / "s_tip_displacement.csv"), read_sweep(tmp_path / "s_current.csv")
    assert (i.output_unit, i.input_unit) == ("mA", "V")
    assert (tmp_path / "f_tip_displacement.png").exists() and (tmp_path / "f_current.png").exists()
    assert _run(["frf", *recs, "--input", "voltage", "--output", "current", "--reciprocal", "--quiet",
                 "--out", str(tmp_path / "z.csv")]) == 0
    z = read_sweep(tmp_path / "z.csv")
    assert (z.output_name, z.output_unit, z.input_name, z.input_unit) == ("voltage", "V", "current", "mA")
    np.testing.assert_allclose(z.response, 1 / i.response, rtol=1e-12)
    np.testing.assert_allclose(z.magnitude_std_db, i.magnitude_std_db, rtol=1e-12)
    np.testing.assert_allclose(m.frequency_hz, i.frequency_hz)


def test_welch_with_band_and_coherence_keeps_and_drops_lines(tmp_path, multisine_signal, capsys):
    recs = _records(tmp_path, multisine_signal, [25.0], header=False)
    out = tmp_path / "w.csv"
    # plain Welch on the multisine record: most bins are not excited (coherence ~ 0)
    assert _run(["frf", *recs, "--input", "voltage", "--output", "tip_displacement", "--nperseg", "1250",
                 "--noverlap", "0", "--window", "boxcar", "--discard-s", "10", "--min-coherence", "0.9",
                 "--band", "0.1", "5", "--out", str(out)]) == 0
    sw = read_sweep(out)
    lines = np.unique(np.maximum(np.round(np.geomspace(0.2, 9, 20) * 5), 1)) / 5
    np.testing.assert_allclose(sw.frequency_hz, lines[lines <= 5])      # exactly the excited lines in band
    assert "lines kept" in capsys.readouterr().out


# ------------------------------------------------------------------------------------- bad input
@pytest.fixture(scope="module")
def one_record(tmp_path_factory, multisine_signal):
    return _records(tmp_path_factory.mktemp("rec"), multisine_signal, [25.0])[0]


def _bad_cases(rec, sig, tmp):
    base = ["frf", rec, "--input", "voltage", "--output", "tip_displacement"]
    nometa = tmp / "nometa.csv"
    r = read_record(rec)
    TimeRecord(r.t, r.channels, r.units, {}).save(nometa)
    nofrf = ["frf", str(nometa), "--input", "voltage", "--output", "tip_displacement"]
    return [
        (base + ["--out", str(tmp / "x.txt")], "--out"),
        (["frf", str(tmp / "missing.csv"), "--input", "voltage", "--output", "x", "--out", str(tmp / "o.csv")],
         "missing.csv"),
        (base[:-1] + ["nothere", "--out", str(tmp / "o.csv")], "--output nothere"),
        (["frf", rec, "--input", "volts", "--output", "tip_displacement", "--out", str(tmp / "o.csv")], "--input volts"),
        (nofrf + ["--out", str(tmp / "o.csv")], "--temperature"),
        (base + ["--temperature", "20,30", "--out", str(tmp / "o.csv")], "--temperature"),
        (nofrf + ["--temperature", "20", "--method", "stepped", "--out", str(tmp / "o.csv")], "--plan"),
        (base + ["--method", "stepped", "--nperseg", "100", "--out", str(tmp / "o.csv")], "--nperseg"),
        (base + ["--settle-s", "1", "--out", str(tmp / "o.csv")], "--settle-s"),
        (base + ["--band", "5", "1", "--out", str(tmp / "o.csv")], "--band"),
        (base + ["--min-coherence", "2", "--out", str(tmp / "o.csv")], "--min-coherence"),
        (base + ["--lines", str(nometa), "--out", str(tmp / "o.csv")], "--lines"),
        (nofrf + ["--temperature", "20", "--frequencies", "0.33", "--nperseg", "1250", "--out", str(tmp / "o.csv")],
         "--frequencies: "),
        (base + ["--max-std-db", "1e-9", "--out", str(tmp / "o.csv")], "no lines left"),
    ]


def test_bad_input_names_the_option_or_file(tmp_path, one_record, multisine_signal):
    for argv, match in _bad_cases(one_record, str(multisine_signal), tmp_path):
        with pytest.raises(IPMCError, match=match):
            _run(argv)
        assert not (tmp_path / "o.csv").exists()


def test_reads_the_files_timesim_writes(tmp_path, multisine_signal):
    """``ipmc simulate`` / TimeSeries.save files (no per-channel header lines, clean columns, SI
    units) are time records too: the same estimate as from the record written by TimeRecord."""
    sig = read_record(multisine_signal)
    ts = simulate(MODEL, 25.0, sig.t, sig.channels["voltage"], output_noise_rms=20e-6, seed=7)
    p = ts.save(tmp_path / "ts.csv")
    out = tmp_path / "ts_sweep.csv"
    assert _run(["frf", str(p), "--lines", str(multisine_signal), "--input", "voltage", "--output",
                 "tip_displacement", "--quiet", "--out", str(out)]) == 0
    sw = read_sweep(out)
    assert (sw.input_unit, sw.output_unit) == ("V", "m") and sw.temperatures().tolist() == [25.0]
    clean = tmp_path / "clean.csv"
    assert _run(["frf", str(p), "--lines", str(multisine_signal), "--input", "voltage", "--output",
                 "tip_displacement_clean", "--quiet", "--out", str(clean), "--max-std-db", "1"]) == 0
    exact = read_sweep(clean)
    np.testing.assert_allclose(exact.response * 1e3, _truth(exact), rtol=1e-4)       # realisation tol
