"""Records and sweeps a user wrote: columns chosen by name or index, units stated, and the
refusals that name the argument fixing them.

Every file here is written by the test itself with the csv module, numpy or scipy.io.savemat (not
the library's writers); the expected values are the numbers written (a response from its
magnitude and phase computed here with numpy), and a linear σ is checked against the dB change
of |H| + σ computed directly.
"""

import csv

import numpy as np
import pytest
from scipy.io import savemat

from physmodel.data.columns import ColumnMapError
from physmodel.data.files import read_sweep
from physmodel.data.interop import as_sweep
from physmodel.data.sweep import sweep_layout
from physmodel.data.timerecord import read_record
from physmodel.errors import DataFormatError, IPMCError

FS = 500.0
T = np.arange(200) / FS
U = np.sin(2 * np.pi * 7 * T)
Y = 0.25 * np.cos(2 * np.pi * 7 * T)


def _csv(path, header, rows, comments=()):
    with open(path, "w", newline="") as fh:
        for c in comments:
            fh.write(f"# {c}\n")
        w = csv.writer(fh)
        w.writerow(header)
        for r in zip(*rows):
            w.writerow([repr(float(v)) for v in r])
    return path


# ----------------------------------------------------------------------------------- records
def test_daq_columns_without_units_by_name(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["t", "volts", "disp"], [T, U, Y])
    rec = read_record(p, columns={"time": "t", "voltage": "volts", "tip": "disp"},
                      units={"voltage": "V", "tip": "mm"}, temperature_c=31)
    assert rec.units == {"voltage": "V", "tip": "mm"}
    np.testing.assert_array_equal(rec.t, T)
    np.testing.assert_array_equal(rec.channel("voltage"), U)
    np.testing.assert_array_equal(rec.channel("tip_mm"), Y)
    assert rec.temperature_c() == 31.0 and rec.fs == pytest.approx(FS)


def test_daq_columns_by_index_and_unit_suffix(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["time_s", "drive_V", "tip_mm", "trigger"], [T, U, Y, 0 * T])
    rec = read_record(p, columns={"voltage": 1, "tip": "2"})       # index as int or as digits
    assert rec.units == {"voltage": "V", "tip": "mm"}                # units from the names' suffixes
    np.testing.assert_array_equal(rec.channel("tip"), Y)
    rec = read_record(p, columns={"drive": "drive"}, units={})      # a name before its '_<unit>'
    assert rec.units == {"drive": "V"}


def test_time_in_milliseconds_and_only_time_mapped(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["t_ms", "volts", "disp"], [T * 1e3, U, Y])
    rec = read_record(p, columns={"time": "t_ms"}, units={"volts": "V", "disp": "um"})
    np.testing.assert_allclose(rec.t, T, rtol=1e-12, atol=0)
    assert rec.units == {"volts": "V", "disp": "um"}


def test_users_own_mat_and_npz_variables(tmp_path):
    savemat(tmp_path / "rec.mat", {"tt": T.reshape(-1, 1), "u": U.reshape(1, -1), "y": Y, "note": "bench 3"})
    rec = read_record(tmp_path / "rec.mat", columns={"time": "tt", "voltage": "u", "tip": "y"},
                      units={"voltage": "V", "tip": "mm"}, temperature_c=25)
    np.testing.assert_array_equal(rec.channel("tip"), Y)
    assert rec.metadata["note"] == "bench 3"
    np.savez(tmp_path / "rec.npz", time=T, drive=U, out=Y)
    rec = read_record(tmp_path / "rec.npz", columns={"time": 0, "voltage": 1, "current": 2},
                      units={"voltage": "mV", "current": "uA"})
    assert rec.units == {"voltage": "mV", "current": "uA"}
    np.testing.assert_array_equal(rec.channel("current"), Y)


@pytest.mark.parametrize("kw, argument, key, needle", [
    ({"units": {"volts": "V"}}, "columns", "time", "which column holds the time"),
    ({"columns": {"time": "t"}, "units": {"volts": "V"}}, "units", "disp", "no unit in its name"),
    ({"columns": {"time": "t", "voltage": 7}, "units": {"voltage": "V"}}, "columns", "voltage", "no column 7"),
    ({"columns": {"time": "t", "voltage": "volt"}}, "columns", "voltage", "no such column"),
    ({"columns": {"time": "t", "v": "volts"}, "units": {"v": "volt"}}, "units", "v", "not one of"),
    ({"columns": {"time": "t", "v": "volts"}, "units": {"v": "V", "x": "mm"}}, "units", "x", "no channel"),
    ({"columns": {"time": "t"}, "units": {"time": "h", "volts": "V", "disp": "mm"}}, "units", "time", "expected"),
])
def test_record_mapping_refusals_name_the_argument(tmp_path, kw, argument, key, needle):
    p = _csv(tmp_path / "daq.csv", ["t", "volts", "disp"], [T, U, Y])
    with pytest.raises(ColumnMapError, match=needle) as exc:
        read_record(p, **kw)
    assert (exc.value.argument, exc.value.key) == (argument, key)
    assert isinstance(exc.value, DataFormatError)


def test_stated_unit_contradicting_the_column_name_is_refused(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["time_s", "drive_V", "tip_mm"], [T, U, Y])
    with pytest.raises(ColumnMapError, match="in mm by its name") as exc:
        read_record(p, columns={"tip": "tip_mm"}, units={"tip": "m"})
    assert exc.value.key == "tip"


def test_unmapped_daq_file_says_how_to_map_it(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["t", "volts", "disp"], [T, U, Y])
    with pytest.raises(DataFormatError, match=r"--time-column.*--input-unit"):
        read_record(p)


# ----------------------------------------------------------------------------------- sweeps
F = np.array([1.0, 2.0, 5.0, 10.0, 20.0])


def _plant(f):
    s = 2j * np.pi * f
    return 3.0 / (1 + s / 40.0) / (1 + s / 300.0)        # [mm/V]


def test_analyser_sweep_in_db_and_degrees(tmp_path):
    H = _plant(F)
    rows = [np.repeat([30.0, 40.0], F.size), np.tile(F, 2), np.tile(20 * np.log10(abs(H)), 2),
            np.tile(np.degrees(np.angle(H)), 2), np.full(2 * F.size, 0.9)]
    p = _csv(tmp_path / "an.csv", ["T_degC", "freq_Hz", "gain_dB", "phase_deg", "coherence"], rows)
    sw = read_sweep(p, columns={"temperature": "T_degC", "frequency": "freq_Hz", "magnitude": "gain_dB"},
                    units={"input": "V", "output": "mm"})
    assert sw.temperatures().tolist() == [30.0, 40.0]
    np.testing.assert_allclose(sw.select(40).response, H, rtol=1e-12)
    assert (sw.input_unit, sw.output_unit) == ("V", "mm")
    assert sweep_layout(sw, "actuator").quantity == "M"      # the units are what calibration checks


def test_linear_magnitude_radians_rad_per_s_kelvin_and_sigma(tmp_path):
    H = _plant(F)
    sig_lin, sig_rad = 0.01 * abs(H), np.full(F.size, 0.02)
    order = np.arange(F.size)[::-1]                          # an analyser sweeping downwards
    rows = [np.full(F.size, 303.15), 2 * np.pi * F[order], abs(H)[order], np.angle(H)[order],
            sig_lin[order], sig_rad]
    p = _csv(tmp_path / "an.csv", ["temp", "w", "mag", "ph", "dmag", "dph"], rows)
    sw = read_sweep(p, columns={"temperature": 0, "frequency": 1, "magnitude": 2, "phase": 3,
                                "magnitude_std": 4, "phase_std": 5},
                    units={"input": "V", "output": "mm", "magnitude": "linear", "phase": "rad",
                           "frequency": "rad/s", "temperature": "K"})
    np.testing.assert_allclose(sw.frequency_hz, F, rtol=1e-14)
    np.testing.assert_allclose(sw.temperature_c, 30.0, rtol=1e-12)
    np.testing.assert_allclose(sw.response, H, rtol=1e-12)
    # σ of |H| in dB: to first order the dB change of |H| + σ
    direct = 20 * np.log10(abs(H) + sig_lin) - 20 * np.log10(abs(H))
    np.testing.assert_allclose(sw.magnitude_std_db, direct, rtol=0.01)
    np.testing.assert_allclose(sw.phase_std_deg, np.degrees(sig_rad[order]), rtol=1e-12)


def test_temperature_by_argument_and_header_and_mat_variables(tmp_path):
    H = _plant(F)
    savemat(tmp_path / "an.mat", {"f": F, "m": 20 * np.log10(abs(H)), "p": np.degrees(np.angle(H))})
    sw = read_sweep(tmp_path / "an.mat", columns={"frequency": "f", "magnitude": "m", "phase": "p"},
                    units={"input": "V", "output": "mm"}, temperature_c=31)
    assert sw.temperatures().tolist() == [31.0]
    np.testing.assert_allclose(sw.response, H, rtol=1e-12)
    p = _csv(tmp_path / "h.csv", ["f", "m", "p"], [F, 20 * np.log10(abs(H)), np.degrees(np.angle(H))],
             comments=["temperature_c: 28", "input: drive [V]", "output: tip [um]"])
    sw = read_sweep(p, columns={"frequency": "f", "magnitude": "m", "phase": "p"})
    assert sw.temperatures().tolist() == [28.0] and (sw.input_name, sw.output_unit) == ("drive", "um")


@pytest.mark.parametrize("kw, argument, key", [
    ({"columns": {"temperature": "T_degC"}}, "columns", "frequency"),
    ({"columns": {"temperature": "T_degC", "frequency": 1, "magnitude": 2}, "units": {"input": "V"}},
     "units", "output"),
    ({"columns": {"temperature": 9}}, "columns", "temperature"),
    ({"columns": {"frequency": 1, "magnitude": 2}, "units": {"input": "V", "output": "mm"}}, "columns", "temperature"),
    ({"columns": {"temperature": 0, "frequency": 1, "magnitude": 2}, "units": {"input": "V", "output": "mm"},
      "temperature_c": 30}, "temperature_c", "temperature"),
    ({"columns": {"temperature": 0, "frequency": 1, "magnitude": 2}, "units": {"input": "V", "output": "mm",
                                                                               "magnitude": "linear"}},
     "units", "magnitude"),                       # gain_dB says dB
    ({"columns": {"temperature": 0, "frequency": 1, "magnitude": 2, "magnitude_std": 4},
      "units": {"input": "V", "output": "mm"}}, "columns", "phase_std"),
    ({"columns": {"gain": 2}}, "columns", "gain"),
    ({"units": {"input": "volt"}, "columns": {"temperature": 0, "frequency": 1, "magnitude": 2}}, "units", "input"),
])
def test_sweep_mapping_refusals_name_the_argument(tmp_path, kw, argument, key):
    p = _csv(tmp_path / "an.csv", ["T_degC", "freq_Hz", "gain_dB", "phase_deg", "sd"],
             [[30, 30], [1, 2], [-10, -11], [-5, -8], [0.1, 0.1]])
    with pytest.raises(ColumnMapError) as exc:
        read_sweep(p, **kw)
    assert (exc.value.argument, exc.value.key) == (argument, key)


def test_analyser_file_without_mapping_names_the_mapping_no_traceback(tmp_path):
    p = _csv(tmp_path / "an.csv", ["T_degC", "freq_Hz", "gain_dB", "phase_deg"], [[30], [1], [-10], [-5]])
    with pytest.raises(ColumnMapError, match=r"columns=.*--sweep-columns"):
        read_sweep(p)
    np.savez(tmp_path / "an.npz", T_degC=[30.0], freq_Hz=[1.0])
    with pytest.raises(ColumnMapError, match="--sweep-columns"):
        read_sweep(tmp_path / "an.npz")
    savemat(tmp_path / "an.mat", {"T_degC": [30.0], "freq_Hz": [1.0]})
    with pytest.raises(ColumnMapError, match="--sweep-columns"):
        read_sweep(tmp_path / "an.mat")


@pytest.mark.parametrize("body, needle", [
    ("temperature_c,frequency_hz,magnitude_db,phase_deg\n30,1,1e300,0\n", "no finite nonzero response"),
    ("temperature_c,frequency_hz,magnitude_db,phase_deg,phase_deg\n30,1,1,0,0\n", "more than once"),
    ('"temperature_c","frequency_hz","magnitude_db","phase_deg"\n30,1,-3,0\n', None),
])
def test_odd_library_files_are_read_or_refused_without_warnings(tmp_path, body, needle):
    p = tmp_path / "s.csv"
    p.write_text("# input: voltage [V]\n# output: tip [mm]\n" + body)
    if needle is None:
        assert read_sweep(p).magnitude_db[0] == pytest.approx(-3.0)
    else:
        with pytest.raises(DataFormatError, match=needle):
            read_sweep(p)


# ----------------------------------------------------------------------------------- interop
def test_frd_with_temperature_and_units_and_a_dimensionless_sweep():
    control = pytest.importorskip("control")
    H = _plant(F)
    frd = control.frd(H, 2 * np.pi * F)
    sw = as_sweep(frd, 30, input_unit="V", output_unit="mm")
    assert sw.temperatures().tolist() == [30.0] and sw.output_unit == "mm"
    bare = as_sweep(frd, 30)                              # no units: dimensionless
    with pytest.raises(DataFormatError, match=r"input_unit='V', output_unit='mm'"):
        sweep_layout(bare, "actuator")
    labelled = as_sweep(bare, input_unit="V", output_unit="mm")
    np.testing.assert_array_equal(labelled.response, H)
    in_m = as_sweep(labelled, output_unit="m")            # another unit of the same kind: converted
    np.testing.assert_allclose(in_m.response, H * 1e-3, rtol=1e-15)
    with pytest.raises(IPMCError, match="output_unit='uA'"):
        as_sweep(labelled, output_unit="uA")
    with pytest.raises(IPMCError, match=r"got temperature_c=\[30, 31\]"):
        as_sweep(frd, [30, 31])


def test_calibrate_takes_the_frd_temperature_and_units():
    control = pytest.importorskip("control")
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.estimation.calibration import calibrate

    base = get_parameter_set("seed002_table3")
    f = np.logspace(-1, 1.3, 12)
    H_mm = ActuatorModel(base).response(f, 30.0)[0] * 1e3          # SI m/V → mm/V
    frd = control.frd(H_mm, 2 * np.pi * f)
    with pytest.raises(DataFormatError, match="input_unit="):
        calibrate(frd, base, ["E"], temperature_c=30, starts=1)
    res = calibrate(frd, base, ["E"], temperature_c=30, input_unit="V", output_unit="mm", starts=1)
    assert res.parameters.E == pytest.approx(base.E, rel=1e-6)     # exact data: the base value back


def test_a_text_column_is_refused_only_when_used(tmp_path):
    p = tmp_path / "an.csv"
    p.write_text("clock,T_degC,freq_Hz,gain_dB,phase_deg,status\n12:00,30,1,-10,-5,OK\n12:01,30,2,-11,-8,OK\n")
    m = {"temperature": "T_degC", "frequency": "freq_Hz", "magnitude": "gain_dB"}
    sw = read_sweep(p, columns=m, units={"input": "V", "output": "mm"})
    np.testing.assert_allclose(sw.magnitude_db, [-10, -11], rtol=1e-12)
    with pytest.raises(DataFormatError, match=r"an.csv:2: status = 'OK' is not a number"):
        read_sweep(p, columns={**m, "phase": "status"}, units={"input": "V", "output": "mm"})
    with pytest.raises(DataFormatError, match="clock = '12:00' is not a number"):
        read_record(p, columns={"time": "clock"})


def test_malformed_analyser_files_never_escape_as_another_exception(tmp_path):
    """Seeded mutations of an analyser file (cut, bytes replaced, cells emptied, separators
    changed), read with and without a mapping: a result or an IPMCError, never another
    exception or a warning (warnings are errors under pytest here)."""
    rng = np.random.default_rng(26)
    H = _plant(F)
    base = "T_degC,freq_Hz,gain_dB,phase_deg\n" + "".join(
        f"30,{float(f)!r},{float(20 * np.log10(abs(h)))!r},{float(np.degrees(np.angle(h)))!r}\n" for f, h in zip(F, H))
    alphabet = list(",;\t\n#.-e0123456789 ab\"") + ["1e400", "nan", "inf", "-0", "\ufeff"]
    m = {"temperature": 0, "frequency": 1, "magnitude": 2, "phase": 3}
    outcomes = {"read": 0, "refused": 0}
    for k in range(300):
        s = list(base)
        for _ in range(int(rng.integers(1, 6))):
            i = int(rng.integers(0, len(s)))
            op = rng.integers(0, 3)
            if op == 0:
                s[i] = str(rng.choice(alphabet))
            elif op == 1:
                del s[i:i + int(rng.integers(1, 8))]
            else:
                s.insert(i, str(rng.choice(alphabet)))
        p = tmp_path / f"m{k}.csv"
        p.write_text("".join(s), encoding="utf-8")
        for kw in ({}, {"columns": m, "units": {"input": "V", "output": "mm"}}):
            try:
                read_sweep(p, **kw)
                outcomes["read"] += 1
            except IPMCError:
                outcomes["refused"] += 1
    assert outcomes["read"] > 0 and outcomes["refused"] > 0       # both paths were exercised


def test_a_channel_named_by_its_column_keeps_the_name_before_the_unit(tmp_path):
    p = _csv(tmp_path / "daq.csv", ["t", "drive_V", "tip_mm"], [T, U, Y])
    rec = read_record(p, columns={"time": "t", "drive_V": "drive_V", "tip_mm": "tip_mm"})
    assert rec.units == {"drive": "V", "tip": "mm"} and rec.columns_names() == ["drive_V", "tip_mm"]
