"""Multi-channel time records: the ipmc-timeseries files (also those timesim writes)."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel.data.timerecord import TimeRecord, read_record
from physmodel.errors import DataFormatError, IPMCError
from physmodel.estimation.frf import estimate_record


def _record(n=2000):
    rng = np.random.default_rng(0)
    t = np.arange(n) / 1000.0
    return TimeRecord(t, {"voltage": rng.standard_normal(n), "current": 1e-3 * rng.standard_normal(n),
                          "tip_displacement": rng.standard_normal(n)},
                      {"voltage": "V", "current": "uA", "tip_displacement": "mm"}, {"temperature_c": "35.5"})


@pytest.mark.parametrize("ext", ["csv", "npz", "mat"])
def test_roundtrip(tmp_path, ext):
    rec = _record()
    back = read_record(rec.save(tmp_path / f"r.{ext}"))
    assert back.units == rec.units
    for k in rec.channels:
        np.testing.assert_array_equal(back.channels[k], rec.channels[k])
    np.testing.assert_array_equal(back.t, rec.t)
    assert back.temperature_c() == 35.5
    assert back.fs == pytest.approx(1000.0, rel=1e-12)


def test_reads_what_timesim_writes(tmp_path):
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.data.timesim import sine

    ts = sine(ActuatorModel(get_parameter_set("dev")), 30.0, 1.0, 2.0, 3.0, 200.0, output_noise_rms=1e-6, seed=1)
    for ext in ("csv", "npz"):
        rec = read_record(ts.save(tmp_path / f"ts.{ext}"))
        assert set(rec.channels) == {"voltage", "tip_displacement", "tip_displacement_clean", "voltage_clean"}
        assert rec.units["tip_displacement"] == "m"
        np.testing.assert_array_equal(rec.channel("tip_displacement_m"), ts.output)
        assert rec.temperature_c() == 30.0


def test_estimate_from_a_file_equals_the_arrays(tmp_path):
    rec = _record(8000)
    rec.channels["tip_displacement"][:] = np.convolve(rec.channels["voltage"], [0.5, 0.3, 0.1], "same")
    back = read_record(rec.save(tmp_path / "r.npz"))
    a = estimate_record(rec, "voltage", ["tip_displacement_mm"], nperseg=512)
    b = estimate_record(back, "voltage_V", nperseg=512)
    assert b.output_names == ("current", "tip_displacement") and b.output_units == ("uA", "mm")
    np.testing.assert_array_equal(a.response[0], b.response[1])
    with pytest.raises(IPMCError, match="no channel 'force'"):
        estimate_record(rec, "force")
    with pytest.raises(IPMCError, match="is the input"):
        estimate_record(rec, "voltage", ["voltage"])
    with pytest.raises(IPMCError, match="method"):
        estimate_record(rec, "voltage", method="h3")


@pytest.mark.parametrize("text,match", [
    ("# ipmc-timeseries 1\nt,voltage_V\n0,1\n0.001,2\n", "no 'time_s' column"),
    ("# ipmc-timeseries 2\ntime_s,voltage_V\n0,1\n0.001,2\n", "version '2'"),
    ("time_s,voltage\n0,1\n0.001,2\n", "column 'voltage' must be named"),
    ("# voltage_V: current [A]\ntime_s,voltage_V\n0,1\n0.001,2\n", "disagrees"),
    ("time_s,voltage_V\n0,1\n0.001,abc\n", "abc"),
    ("time_s,voltage_V\n0,1\n0.001,nan\n", "not finite at samples \\[1\\]"),
    ("time_s,voltage_V,current_A\n0,1,2\n0.001,2,3\n", None),
    ("# only a header\n", "no column header"),
])
def test_malformed_csv_is_named(tmp_path, text, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    if match is None:
        assert read_record(p).units == {"voltage": "V", "current": "A"}
        return
    with pytest.raises(DataFormatError, match=match):
        read_record(p)


def test_bad_records():
    with pytest.raises(DataFormatError, match="unknown time-record file type"):
        read_record("x.txt")
    with pytest.raises(DataFormatError, match="no such file"):
        read_record("/nonexistent/r.csv")
    with pytest.raises(IPMCError, match="shape"):
        TimeRecord(np.arange(3.0), {"v": np.zeros(4)}, {"v": "V"})
    with pytest.raises(IPMCError, match="same channels"):
        TimeRecord(np.arange(3.0), {"v": np.zeros(3)}, {"w": "V"})
