"""The column/unit options of the commands (scenarios/commands/_columns.py) and the signal
kind/unit checks of ``ipmc invert`` and ``ipmc feedforward``.

Input files are written here with the csv module / numpy.  Oracles: a mapped file gives exactly
what the same numbers give under the library's own column names (the mapping is transparent); a
column in metres gives the reconstruction of the same column in millimetres (the factor 1000 is
applied once, not zero or two times); an FIR plant written here is the truth of the frf estimate.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

import physmodel
import surrogate
from physmodel.data.files import read_sweep
from physmodel.data.sweep import synthesize_sweep
from scenarios.cli import main

FS = 200.0
FIR = np.array([0.5, 0.3, 0.1])            # y[n] = Σ h_k u[n-k]  → H(f) = Σ h_k e^{-2πi f k/fs}  [mm/V]


def _write(path, header, cols):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in zip(*cols):
            w.writerow([repr(float(v)) for v in row])
    return str(path)


@pytest.fixture(scope="module")
def daq(tmp_path_factory):
    d = tmp_path_factory.mktemp("daq")
    rng = np.random.default_rng(5)
    n = 8192
    t = np.arange(n) / FS
    u = rng.standard_normal(n)
    y = np.convolve(u, FIR)[:n] + 0.01 * rng.standard_normal(n)
    own = _write(d / "own.csv", ["t", "volts", "disp"], [t, u, y])
    lib = _write(d / "lib.csv", ["time_s", "volts_V", "disp_mm"], [t, u, y])
    return own, lib, t, u, y


def _frf(args, capsys):
    rc = main(["frf", *args, "--temperature", "25", "--quiet"])
    return rc, capsys.readouterr().err


def test_frf_reads_a_daqs_own_columns(daq, tmp_path, capsys):
    own, lib, *_ = daq
    rc, err = _frf([own, "--out", str(tmp_path / "a.csv"), "--input", "volts", "--output", "disp",
                    "--time-column", "t", "--input-unit", "V", "--output-unit", "mm"], capsys)
    assert rc == 0, err
    rc, err = _frf([lib, "--out", str(tmp_path / "b.csv"), "--input", "volts", "--output", "disp"], capsys)
    assert rc == 0, err
    rc, err = _frf([own, "--out", str(tmp_path / "c.csv"), "--input", "voltage", "--output", "tip",
                    "--time-column", "0", "--input-column", "1", "--output-column", "2",
                    "--input-unit", "V", "--output-unit", "mm"], capsys)
    assert rc == 0, err
    a, b, c = (read_sweep(tmp_path / f"{k}.csv") for k in "abc")
    np.testing.assert_array_equal(a.response, b.response)       # the mapping is transparent
    np.testing.assert_array_equal(c.response, b.response)
    assert (a.input_unit, a.output_unit, c.input_name, c.output_name) == ("V", "mm", "voltage", "tip")
    f = a.frequency_hz
    truth = sum(h * np.exp(-2j * np.pi * f * k / FS) for k, h in enumerate(FIR))
    band = f < 0.4 * FS
    assert np.median(np.abs(a.response[band] / truth[band] - 1)) < 0.05


@pytest.mark.parametrize("extra, option", [
    (["--input", "volts", "--output", "disp"], "--time-column"),
    (["--input", "volts", "--output", "disp", "--time-column", "t", "--input-unit", "V"], "--output-unit"),
    (["--input", "volts", "--output", "disp", "--time-column", "t", "--output-unit", "mm"], "--input-unit"),
    (["--input", "v", "--output", "disp", "--input-column", "9", "--time-column", "t", "--input-unit", "V",
      "--output-unit", "mm"], "--input-column"),
    (["--input", "volts", "--output", "disp", "--time-column", "time", "--input-unit", "V", "--output-unit", "mm"],
     "--time-column"),
    (["--input", "volts", "--output", "disp", "--time-column", "t", "--input-unit", "volt", "--output-unit", "mm"],
     "--input-unit"),
    (["--input", "volts", "--output", "disp", "--output-column", "1", "--output-column", "2", "--time-column", "t"],
     "--output-column"),
])
def test_frf_mapping_errors_exit_2_naming_the_option(daq, tmp_path, capsys, extra, option):
    own = daq[0]
    rc, err = _frf([own, "--out", str(tmp_path / "s.csv"), *extra], capsys)
    assert rc == 2
    assert option in err and "Traceback" not in err


# ----------------------------------------------------------------------------------- sweeps
@pytest.fixture(scope="module")
def analyser(tmp_path_factory):
    """An analyser's file of the actuator's M at three temperatures: T_degC,freq_Hz,gain_dB,phase_deg,coh."""
    d = tmp_path_factory.mktemp("an")
    plant = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    f = np.logspace(-1, np.log10(9.0), 25)
    temps = [30.0, 37.5, 45.0]
    R = plant.frequency_response(f, temps, quantities=("M",))["M"][0] * 1e3        # mm/V, (n_T, n_f)
    T = np.repeat(temps, f.size)
    H = R.ravel()
    path = _write(d / "an.csv", ["T_degC", "freq_Hz", "gain_dB", "phase_deg", "coh"],
                  [T, np.tile(f, len(temps)), 20 * np.log10(abs(H)), np.degrees(np.angle(H)), np.ones(H.size)])
    return path, H


MAP = ["--sweep-columns", "temperature=T_degC,frequency=freq_Hz,magnitude=gain_dB,phase=phase_deg"]


@pytest.mark.parametrize("cmd", ["fit", "calibrate"])
@pytest.mark.parametrize("extra, option", [
    ([], "--sweep-columns"),
    (MAP, "--sweep-units input=UNIT"),
    (["--sweep-columns", "temperature=9", "--sweep-units", "input=V,output=mm"], "--sweep-columns temperature"),
    ([*MAP, "--sweep-units", "input=V,output=mm", "--sweep-temperature", "30"], "--sweep-temperature"),
    (["--sweep-columns", "temperature"], "--sweep-columns"),
])
def test_sweep_commands_name_the_mapping_option(analyser, tmp_path, capsys, cmd, extra, option):
    path = analyser[0]
    argv = ["fit", path, "--out", str(tmp_path / "o"), "--quiet"] if cmd == "fit" else \
        ["calibrate", path, "--set", "seed001_actuator", "--free", "E", "--out", str(tmp_path / "o"), "--quiet"]
    assert main([*argv, *extra]) == 2
    err = capsys.readouterr().err
    assert option in err and "Traceback" not in err


def test_fit_reads_an_analysers_sweep(analyser, tmp_path, capsys):
    path, H = analyser
    rc = main(["fit", path, "--zeros", "4", "--poles", "4", "--out", str(tmp_path / "o"), "--quiet", *MAP,
               "--sweep-units", "input=V,output=mm"])
    assert rc == 0, capsys.readouterr().err
    model = surrogate.load(tmp_path / "o" / "model.json")
    assert model.labels["output_unit"] == "mm" and model.labels["input_unit"] == "V"


# ----------------------------------------------------------------------------------- invert/feedforward
@pytest.fixture(scope="module")
def surrogates(tmp_path_factory):
    d = tmp_path_factory.mktemp("sur")
    f = np.logspace(-1, np.log10(9.0), 30)
    act = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    fit = surrogate.ScheduledFit("coefficients", 4, 4, 2).fit(synthesize_sweep(act, "M", f, [30.0, 35.0, 40.0, 45.0]))
    sen = physmodel.SensorModel(physmodel.get_parameter_set("seed000_sensor_dev"))
    fit2 = surrogate.ScheduledFit("coefficients", 2, 2, 1).fit(synthesize_sweep(sen, "S", f, [30.0, 35.0, 40.0]))
    assert fit.converged and fit2.converged
    fit.model.to_json(d / "act.json")
    fit2.model.to_json(d / "sen.json")
    assert fit.model.labels["output_unit"] == "mm" and fit2.model.labels["output_unit"] == "uA"
    return d / "act.json", d / "sen.json"


def _signal(tmp_path, name, scale):
    t = np.arange(0.0, 2.0, 1e-3)
    x = 0.2 * np.sin(2 * np.pi * 2 * t) * np.sin(np.pi * t / 2) ** 2          # [mm], at rest at both ends
    return _write(tmp_path / f"{name}.csv", ["time_s", name], [t, x * scale])


def _table(path):
    """The numbers of a CSV written by a command: '#' lines and the header row skipped."""
    with open(path) as fh:
        rows = [ln for ln in fh if not ln.startswith("#")][1:]
    return np.loadtxt(rows, delimiter=",", ndmin=2)


def _invert(path, sur, out, capsys, *extra):
    rc = main(["invert", path, "-o", str(out), "--surrogate", str(sur), "--temperature", "37", "--quiet", *extra])
    return rc, capsys.readouterr().err


def test_invert_converts_metres_to_the_surrogates_millimetres(surrogates, tmp_path, capsys):
    act, _ = surrogates
    rc, err = _invert(_signal(tmp_path, "tip_mm", 1.0), act, tmp_path / "mm.csv", capsys)
    assert rc == 0, err
    rc, err = _invert(_signal(tmp_path, "tip_m", 1e-3), act, tmp_path / "m.csv", capsys)
    assert rc == 0 and "converted to the surrogate's mm" in err
    rc, err3 = _invert(_signal(tmp_path, "tip", 1e-3), act, tmp_path / "bare.csv", capsys, "--input-unit", "m")
    assert rc == 0 and "converted" in err3
    v = {k: _table(tmp_path / f"{k}.csv")[:, 2] for k in ("mm", "m", "bare")}
    assert np.max(np.abs(v["mm"])) > 0.01
    # equal to rounding (x·1e-3·1e3 is not x bit for bit; the output has 12 digits): 1e-8 of the peak,
    # where the error guarded against (a factor 1000 applied zero or two times) is 1e3 of it
    tol = 1e-8 * np.max(np.abs(v["mm"]))
    np.testing.assert_allclose(v["m"], v["mm"], rtol=0, atol=tol)
    np.testing.assert_allclose(v["bare"], v["mm"], rtol=0, atol=tol)
    rc, err = _invert(_signal(tmp_path, "tip", 1.0), act, tmp_path / "nounit.csv", capsys)
    assert rc == 0 and "states no unit" in err and "--input-unit" in err      # said, not silent


@pytest.mark.parametrize("which, column, extra, needles", [
    ("act", "current_uA", [], ["current", "actuator surrogate"]),
    ("sen", "tip_mm", [], ["length", "sensor surrogate"]),
    ("act", "sig", ["--input-unit", "uA"], ["current", "--input-unit"]),
    ("act", "sig", ["--input-unit", "furlong"], ["--input-unit furlong"]),
    ("act", "tip_mm", ["--input-column", "5"], ["--input-column"]),
    ("act", "tip_mm", ["--time-column", "t"], ["--time-column"]),
])
def test_invert_refuses_a_signal_of_another_kind(surrogates, tmp_path, capsys, which, column, extra, needles):
    sur = surrogates[0] if which == "act" else surrogates[1]
    rc, err = _invert(_signal(tmp_path, column, 1.0), sur, tmp_path / "o.csv", capsys, *extra)
    assert rc == 2 and not (tmp_path / "o.csv").exists()
    assert all(n in err for n in needles), err


def _ff(sur, out, capsys, *extra):
    rc = main(["feedforward", str(sur), "--temperature", "37", "--no-check", "--quiet", "--out", str(out), *extra])
    return rc, capsys.readouterr().err


def test_feedforward_reference_unit_is_converted_or_refused(surrogates, tmp_path, capsys):
    act, sen = surrogates
    rc, err = _ff(act, tmp_path / "mm", capsys, "--amplitude", "0.3")
    assert rc == 0, err
    rc, err = _ff(act, tmp_path / "m", capsys, "--amplitude", "0.0003", "--unit", "m")
    assert rc == 0 and "converted to the surrogate's mm" in err
    a, b = (_table(tmp_path / k / "voltage.csv") for k in ("mm", "m"))
    # same volts (0.3 mm is 0.0003 m) to rounding: 1e-8 of the peak (a factor 1000 error is 1e3 of it)
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-8 * np.max(np.abs(a)))
    rc, err = _ff(act, tmp_path / "uA", capsys, "--unit", "uA")
    assert rc == 2 and "current" in err and "--unit" in err
    rc, err = _ff(sen, tmp_path / "sen", capsys)
    assert rc == 2 and "sensor surrogate" in err and "actuator surrogate" in err


def test_feedforward_reference_file_column_unit(surrogates, tmp_path, capsys):
    act, _ = surrogates
    t = np.arange(0, 4, 1e-3)
    x = 0.2 * np.sin(2 * np.pi * t) * np.sin(np.pi * t / 4) ** 2            # [mm], at rest at both ends
    files = {"mm": _write(tmp_path / "r_mm.csv", ["time_s", "target_mm"], [t, x]),
             "m": _write(tmp_path / "r_m.csv", ["time_s", "target_m"], [t, x * 1e-3]),
             "uA": _write(tmp_path / "r_uA.csv", ["time_s", "target_uA"], [t, x])}
    rc, err = _ff(act, tmp_path / "fmm", capsys, "--reference-file", files["mm"])
    assert rc == 0, err
    rc, err = _ff(act, tmp_path / "fm", capsys, "--reference-file", files["m"])
    assert rc == 0 and "'target_m' is in m; converted to the surrogate's mm" in err
    a, b = (_table(tmp_path / k / "voltage.csv") for k in ("fmm", "fm"))
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-8 * np.max(np.abs(a)))   # rounding only (see above)
    rc, err = _ff(act, tmp_path / "fuA", capsys, "--reference-file", files["uA"])
    assert rc == 2 and "current" in err and "--reference-column" in err


def test_invert_input_unit_must_agree_with_the_column_name(surrogates, tmp_path, capsys):
    rc, err = _invert(_signal(tmp_path, "tip_mm", 1.0), surrogates[0], tmp_path / "o.csv", capsys, "--input-unit", "m")
    assert rc == 2 and "--input-unit m" in err and "in mm by its name" in err


def test_invert_mat_variable_with_a_stated_unit_is_converted(surrogates, tmp_path, capsys):
    from scipy.io import savemat

    act, _ = surrogates
    rc, err = _invert(_signal(tmp_path, "tip_mm", 1.0), act, tmp_path / "mm.csv", capsys)
    assert rc == 0, err
    t = np.arange(0.0, 2.0, 1e-3)
    x = 0.2 * np.sin(2 * np.pi * 2 * t) * np.sin(np.pi * t / 2) ** 2          # as _signal, in m below
    savemat(tmp_path / "rec.mat", {"tt": t, "defl": x * 1e-3})
    rc, err = _invert(str(tmp_path / "rec.mat"), act, tmp_path / "m.csv", capsys,
                      "--time-column", "tt", "--input-column", "defl", "--input-unit", "m")
    assert rc == 0 and "'defl' is in m; converted to the surrogate's mm" in err, err
    a, b = _table(tmp_path / "mm.csv")[:, 2], _table(tmp_path / "m.csv")[:, 2]
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-8 * np.max(np.abs(a)))      # rounding only (see above)
    rc, err = _invert(str(tmp_path / "rec.mat"), act, tmp_path / "uA.csv", capsys,
                      "--time-column", "tt", "--input-column", "defl", "--input-unit", "uA")
    assert rc == 2 and "current" in err and "--input-unit" in err


def test_feedforward_reference_column_by_index_as_the_other_column_options(surrogates, tmp_path, capsys):
    act, _ = surrogates
    t = np.arange(0, 4, 1e-3)
    x = 0.2 * np.sin(2 * np.pi * t) * np.sin(np.pi * t / 4) ** 2            # [mm], at rest at both ends
    ref = _write(tmp_path / "r.csv", ["time_s", "other_mm", "target_m"], [t, 5 * x, x * 1e-3])
    rc, err = _ff(act, tmp_path / "byname", capsys, "--reference-file", ref, "--reference-column", "target_m")
    assert rc == 0, err
    rc, err = _ff(act, tmp_path / "byindex", capsys, "--reference-file", ref, "--reference-column", "2")
    assert rc == 0 and "'target_m' is in m; converted to the surrogate's mm" in err, err
    a, b = (_table(tmp_path / k / "voltage.csv") for k in ("byname", "byindex"))
    np.testing.assert_array_equal(b, a)                                  # the same column, read the same way
    # the column really is column 2 (m → mm), not column 1 (5x in mm): the reference written is x
    np.testing.assert_allclose(b[:, 2][1000:5000], x, rtol=0, atol=1e-9)
    # a column that is not there: the wording of invert's --input-column, with this option's name
    rc, err = _ff(act, tmp_path / "bad", capsys, "--reference-file", ref, "--reference-column", "9")
    sig = _signal(tmp_path, "tip_mm", 1.0)
    rc2, err2 = _invert(sig, act, tmp_path / "o.csv", capsys, "--input-column", "9")
    assert rc == rc2 == 2 and not (tmp_path / "bad").exists()
    assert f"error: --reference-column: {ref}: columns['reference'] = 9: no column 9 (0-based); the file has 3 " \
           "column(s): 0:time_s, 1:other_mm, 2:target_m" in err, err
    assert f"error: --input-column: {sig}: columns['input'] = 9: no column 9 (0-based); the file has 2 " \
           "column(s): 0:time_s, 1:tip_mm" in err2, err2
    rc, err = _ff(act, tmp_path / "bad", capsys, "--reference-file", ref, "--reference-column", "tip")
    assert rc == 2 and "--reference-column: " in err and "'tip': no such column" in err, err
