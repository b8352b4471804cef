"""Time-record files read through the one reader (physmodel.data.timerecord.read_record), which
``ipmc simulate --input`` and ``inversion.references.from_file`` now share: whatever is wrong with
a file, the refusal is an IPMCError naming the file (exit code 2 from the command line), never a
traceback from numpy, zipfile or the codec.  Good files are compared with arrays written here
with plain numpy/csv, not with the library's writer.
"""

import zipfile

import numpy as np
import pytest

from physmodel.data.timerecord import read_record
from physmodel.errors import IPMCError
from scenarios.cli import main


def _good_csv(path, bom=False):
    t = np.arange(5) * 0.01
    v = np.r_[0.0, 0.5, -0.25, 1.0, 0.0]
    text = "# ipmc-timeseries 1\ntime_s,voltage_mV\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t.tolist(), v.tolist()))
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + text.encode())
    return t, v


def test_good_files_read_back(tmp_path):
    t, v = _good_csv(tmp_path / "a.csv")
    rec = read_record(tmp_path / "a.csv")
    np.testing.assert_array_equal(rec.t, t)
    np.testing.assert_array_equal(rec.channel("voltage_mV"), v)
    assert rec.units == {"voltage": "mV"}
    _good_csv(tmp_path / "bom.csv", bom=True)                  # Excel's byte-order mark
    np.testing.assert_array_equal(read_record(tmp_path / "bom.csv").channel("voltage"), v)
    np.savez(tmp_path / "a.npz", time_s=t, voltage_mV=v)        # no header: plain columns
    np.testing.assert_array_equal(read_record(tmp_path / "a.npz").channel("voltage"), v)


def _bad_files(d):
    (d / "latin1.csv").write_bytes(b"time_s,voltage_V\n0,1\n0.01,\xe9\n")
    (d / "text.csv").write_text("time_s,voltage_V\n0,1\n0.01,one\n")
    (d / "ragged.csv").write_text("time_s,voltage_V\n0,1\n0.01,2,3\n")
    (d / "nan.csv").write_text("time_s,voltage_V\n0,1\n0.01,nan\n0.02,0\n")
    (d / "nounit.csv").write_text("time_s,voltage\n0,1\n0.01,2\n")
    (d / "onerow.csv").write_text("time_s,voltage_V\n0,1\n")
    (d / "empty.csv").write_text("# ipmc-timeseries 1\n")
    (d / "v9.csv").write_text("# ipmc-timeseries 9\ntime_s,voltage_V\n0,1\n0.01,2\n")
    (d / "notzip.npz").write_bytes(b"PK\x03\x04 this is not a zip archive")
    (d / "garbage.npz").write_bytes(b"\x00\x01\x02 not numpy at all")
    np.save(d / "array.npy", np.arange(3.0))
    (d / "array.npy").rename(d / "array.npz")
    with zipfile.ZipFile(d / "badheader.npz", "w") as z:
        z.writestr("header.npy", b"\x93NUMPY garbage")
    (d / "garbage.mat").write_bytes(b"MATLAB 5.0 MAT-file, but nothing else")
    (d / "folder.csv").mkdir()
    return sorted(p for p in d.iterdir())


def test_every_bad_file_is_refused_with_its_name(tmp_path):
    for path in _bad_files(tmp_path):
        with pytest.raises(IPMCError) as exc:
            read_record(path)
        assert str(path) in str(exc.value), f"{path.name}: {exc.value}"
    with pytest.raises(IPMCError, match="no such file"):
        read_record(tmp_path / "missing.csv")


def test_simulate_input_exits_2_naming_the_file(tmp_path, capsys):
    for path in _bad_files(tmp_path):
        code = main(["simulate", "--set", "dev", "--input", str(path), "--out", str(tmp_path / "o.csv"), "--quiet"])
        err = capsys.readouterr().err
        assert code == 2 and str(path) in err and "Traceback" not in err, f"{path.name}: {code} {err}"
        assert not (tmp_path / "o.csv").exists()
