"""Synthetic sweeps, their noise model and the CSV / NPZ / MAT files."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel import ActuatorModel, SensorModel, get_parameter_set
from physmodel.data.files import read_csv, read_sweep, write_sweep
from physmodel.data.sweep import ComplexGaussianNoise, FrequencySweep, MagnitudePhaseNoise, synthesize_sweep
from physmodel.errors import DataFormatError, IPMCError

F = np.logspace(-1, 2, 30)
T = [20.0, 40.0, 60.0]


@pytest.fixture(scope="module")
def noisy():
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    return synthesize_sweep(m, "M", F, T, MagnitudePhaseNoise(0.2, 2.0), seed=11)


def test_exact_sweep_is_the_model_in_display_units():
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    sw = synthesize_sweep(m, "M", F, T)
    ref = m.frequency_response(F, T)["M"][0] * 1e3      # m/V -> mm/V
    f, temps, H = sw.grid()
    np.testing.assert_array_equal(temps, T)
    np.testing.assert_allclose(H, ref, rtol=1e-15)
    assert (sw.input_unit, sw.output_unit) == ("V", "mm")
    s = synthesize_sweep(SensorModel(get_parameter_set("seed000_sensor_dev")), "S", F, T)
    assert (s.input_unit, s.output_unit) == ("mm", "uA")


def test_noise_is_seeded_and_matches_its_stated_std(noisy):
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    again = synthesize_sweep(m, "M", F, T, MagnitudePhaseNoise(0.2, 2.0), seed=11)
    np.testing.assert_array_equal(noisy.response, again.response)
    other = synthesize_sweep(m, "M", F, T, MagnitudePhaseNoise(0.2, 2.0), seed=12)
    assert not np.array_equal(noisy.response, other.response)
    exact = synthesize_sweep(m, "M", F, T)
    dm = noisy.magnitude_db - exact.magnitude_db
    dp = np.degrees(np.angle(noisy.response / exact.response))
    # 90 lines: sample std within ±25 % of the stated value (chi distribution, >3 sigma margin)
    assert np.std(dm) == pytest.approx(0.2, rel=0.25)
    assert np.std(dp) == pytest.approx(2.0, rel=0.25)
    np.testing.assert_array_equal(noisy.magnitude_std_db, 0.2)


def test_complex_gaussian_per_line_std_is_what_the_noise_does():
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    f = np.logspace(0, 1, 2000)
    exact = synthesize_sweep(m, "M", f, [25.0])
    sw = synthesize_sweep(m, "M", f, [25.0], ComplexGaussianNoise(0.02), seed=1)
    rel = np.log(sw.response / exact.response)
    assert np.std(rel.real) * 20 / np.log(10) == pytest.approx(sw.magnitude_std_db[0], rel=0.06)
    assert np.degrees(np.std(rel.imag)) == pytest.approx(sw.phase_std_deg[0], rel=0.06)


def test_noisy_sweep_needs_a_seed():
    m = ActuatorModel(get_parameter_set("dev"))
    with pytest.raises(IPMCError, match="seed"):
        synthesize_sweep(m, "M", F, T, MagnitudePhaseNoise())


@pytest.mark.parametrize("ext", ["csv", "npz", "mat"])
def test_roundtrip(noisy, tmp_path, ext):
    back = read_sweep(write_sweep(noisy, tmp_path / f"s.{ext}"))
    np.testing.assert_allclose(back.response, noisy.response, rtol=1e-13)
    np.testing.assert_array_equal(back.temperature_c, noisy.temperature_c)
    np.testing.assert_array_equal(back.magnitude_std_db, noisy.magnitude_std_db)
    assert (back.input_name, back.input_unit, back.output_name, back.output_unit) == ("voltage", "V", "tip_displacement", "mm")
    assert back.metadata["seed"] == "11"
    assert back.fingerprint() == FrequencySweep(back.temperature_c, back.frequency_hz, back.response).fingerprint()


GOOD = """# ipmc-sweep 1
# input: tip_displacement [mm]
# output: current [uA]
temperature_c,frequency_hz,magnitude_db,phase_deg
25,10,1.0,80
25,20,2.0,70
35,10,0.5,85
35,20,1.5,75
"""


def _write(tmp_path, text):
    p = tmp_path / "d.csv"
    p.write_text(text)
    return p


def test_good_csv_reads(tmp_path):
    sw = read_csv(_write(tmp_path, GOOD))
    assert sw.temperatures().tolist() == [25.0, 35.0]
    assert sw.magnitude_db[1] == pytest.approx(2.0)
    assert sw.phase_deg[2] == pytest.approx(85.0)
    assert sw.magnitude_std_db is None


@pytest.mark.parametrize("mutate,message", [
    (lambda s: s.replace("temperature_c,frequency_hz,magnitude_db,phase_deg", "temperature_c,frequency_hz,magnitude_db"), r"missing column.*phase_deg"),
    (lambda s: s.replace("25,20,2.0,70", "25,20,nan,70"), r":6: magnitude_db is 'nan'"),
    (lambda s: s.replace("25,20,2.0,70", "25,20,abc,70"), r":6: magnitude_db = 'abc' is not a number"),
    (lambda s: s.replace("25,20,2.0,70", "25,5,2.0,70"), r":6: frequencies at 25 °C are not sorted"),
    (lambda s: s.replace("25,20,2.0,70", "25,10,2.0,70"), r":6: duplicate frequency 10 Hz"),
    (lambda s: s.replace("[uA]", "[furlong]"), r"unknown output unit 'furlong'"),
    (lambda s: s.replace("# input: tip_displacement [mm]\n", ""), r"missing header line '# input"),
    (lambda s: s.replace("25,20,2.0,70", "25,20,2.0"), r":6: expected 4 values, got 3"),
    (lambda s: s.replace("35,20,1.5,75", "35,20,1.5,75\n25,30,1,1"), r":9: rows at 25 °C are not contiguous"),
    (lambda s: s.replace("25,10,1.0,80", "25,-10,1.0,80"), r":5: frequency_hz = -10.0 must be > 0"),
])
def test_malformed_csv_names_line_and_problem(tmp_path, mutate, message):
    with pytest.raises(DataFormatError, match=message):
        read_csv(_write(tmp_path, mutate(GOOD)))


def test_write_is_atomic(tmp_path, noisy, monkeypatch):
    target = tmp_path / "out.csv"
    target.write_text("old complete file\n")
    import csv as _csv

    class Boom(Exception):
        pass

    real_writer = _csv.writer

    def bad_writer(*a, **k):
        w = real_writer(*a, **k)

        class W:
            n = 0

            def writerow(self, row):
                W.n += 1
                if W.n > 5:
                    raise Boom()
                w.writerow(row)
        return W()

    monkeypatch.setattr(_csv, "writer", bad_writer)
    with pytest.raises(Boom):
        write_sweep(noisy, target)
    assert target.read_text() == "old complete file\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_grid_refuses_ragged_and_to_frd_uses_rad_per_s(noisy):
    sub = noisy.exclude([40.0])
    assert sub.temperatures().tolist() == [20.0, 60.0]
    frd = noisy.to_frd(20.0)
    np.testing.assert_allclose(frd.omega, 2 * np.pi * F)
    ragged = FrequencySweep(np.array([1.0, 1.0, 2.0]), np.array([1.0, 2.0, 1.0]), np.ones(3))
    with pytest.raises(IPMCError, match="differs"):
        ragged.grid()


# ------------------------------------------------------------------ the one '# key: value' header scan
HEADER_LINES = ["# ipmc-sweep 1", "", "   # input: tip_displacement [mm]", "\t## output: current [uA]",
                "# a free comment without a colon", "#   note:  a: b  ", "# ipmc-timeseries", "# note: again",
                "temperature_c,frequency_hz,magnitude_db,phase_deg", "# after the header: not read"]


def test_comment_header_reads_entries_format_lines_and_indented_hashes():
    from physmodel.data.fileio import comment_header

    h = comment_header(HEADER_LINES)
    # written out by hand: a later key wins, the value keeps its own colons, free text is no entry
    assert h.entries == {"ipmc-sweep": "1", "input": "tip_displacement [mm]", "output": "current [uA]",
                         "note": "again", "ipmc-timeseries": ""}
    assert h.end == 8
    assert comment_header([]).end == 0 and comment_header(["# only: header"]).end == 1
    assert comment_header(["t,x", "# k: v"]).entries == {}


def test_both_csv_readers_take_the_same_header(tmp_path):
    """The sweep CSV and a user's own table read one header the same way: indented '#' lines are
    header lines in both (the sweep reader took one for the column-name row and refused the file),
    and the format line is no metadata."""
    from physmodel.data.columns import read_table

    text = "\n".join(HEADER_LINES[:-2] + HEADER_LINES[-2:-1]) + "\n25,10,1.0,80\n25,20,2.0,70\n"
    p = _write(tmp_path, text)
    sw = read_csv(p)
    assert (sw.input_name, sw.input_unit, sw.output_name, sw.output_unit) == ("tip_displacement", "mm", "current", "uA")
    assert sw.metadata == {"note": "again"}
    np.testing.assert_allclose(sw.magnitude_db, [1.0, 2.0], rtol=1e-12)
    table = read_table(p)
    assert table.header == {"ipmc-sweep": "1", "input": "tip_displacement [mm]", "output": "current [uA]",
                            "note": "again", "ipmc-timeseries": ""}
    assert table.names == ["temperature_c", "frequency_hz", "magnitude_db", "phase_deg"]
    mapped = read_sweep(p, columns={"temperature": 0, "frequency": 1, "magnitude": 2, "phase": 3})
    assert mapped.metadata.get("note") == "again" and not any(k.startswith("ipmc-") for k in mapped.metadata)
    # the library's own sweep file still reads as before (its format line is not metadata)
    assert read_csv(_write(tmp_path, GOOD)).metadata == {}
