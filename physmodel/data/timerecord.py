"""Multi-channel time records (measured or designed) and their files.

A :class:`TimeRecord` is a uniform time base and any number of named channels, each with a unit,
kept in the units of the file (V, A, mm, s, ...) — the frequency responses estimated from it are in
those units.  The files are the ``ipmc-timeseries`` format that
:class:`physmodel.timesim.TimeSeries` writes, so virtual experiments and laboratory records read the
same way::

    # ipmc-timeseries 1
    # voltage_V: voltage [V]              one line per channel: column, name and unit
    # tip_displacement_mm: tip_displacement [mm]
    # temperature_c: 25                   any other '# key: value' line is metadata
    time_s,voltage_V,tip_displacement_mm
    0.0,0.0,0.0
    ...

Column names are ``time_s`` and ``<name>_<unit>`` (the unit after the last underscore); the
per-channel header lines are optional when reading (files of older versions of TimeSeries and
hand-made files have none) and, when present, must agree with their column.  TimeSeries,
:meth:`inversion.references.Reference.save` and the excitation plans all write through
:class:`TimeRecord`.  NPZ files hold one array per column plus a JSON ``header``
(format, version, metadata); MATLAB ``.mat`` files one column vector per column plus
``metadata_json``.
"""

from __future__ import annotations

import io
import json
import math
import re
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import DataFormatError, IPMCError
from .columns import ColumnMapError, map_record
from .fileio import atomic_write, by_extension, comment_header, read_text

#: Samples read per block when checking long (memory-mapped) time bases.
TIME_BLOCK_SAMPLES = 1 << 20

FORMAT = "ipmc-timeseries"
FORMAT_VERSION = 1
#: The format name :meth:`inversion.references.Reference.save` wrote before it wrote through
#: :class:`TimeRecord` (still read; its CSV marker line is skipped like any comment).
LEGACY_REFERENCE_FORMAT = "ipmc-reference"
TIME_COLUMN = "time_s"
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_UNIT = re.compile(r"^[A-Za-zµΩ0-9]+$")


def split_column(column: str, where: str = "") -> tuple[str, str]:
    """``'tip_displacement_mm'`` → ``('tip_displacement', 'mm')``; the unit follows the last ``_``."""
    if "_" not in column:
        raise DataFormatError(f"{where}column {column!r} must be named '<name>_<unit>', e.g. 'voltage_V'")
    name, unit = column.rsplit("_", 1)
    if not (_NAME.match(name) and _UNIT.match(unit)):
        raise DataFormatError(f"{where}column {column!r} must be named '<name>_<unit>' with a name of "
                              f"letters, digits and '_' and a unit of letters/digits, e.g. 'current_uA'")
    return name, unit



#: Largest deviation of one time step from the mean step, relative to the mean step (default).
UNIFORM_RTOL = 1e-6
#: Largest deviation of a sample from the uniform grid through the end points [samples]
#: (a slow clock drift passes the step test but not this one).
GRID_TOL = 1e-3


def uniform_interval(t, n: int | None = None, *, rtol: float = UNIFORM_RTOL, what: str = "time stamps",
                     block_samples: int = TIME_BLOCK_SAMPLES) -> float:
    """The sampling interval [s] of uniform sample times ``t`` [s], or of a scalar interval ``t``.

    The one uniform-time check of the library (simulation, inversion, frequency-response
    estimation).  ``t`` is checked in blocks of ``block_samples`` (long memory-mapped records):
    finite, increasing end to end, every step within ``rtol`` of the mean step
    ``(t[-1] - t[0])/(n - 1)`` (plus float rounding, 8 eps max|t|), and every sample within
    :data:`GRID_TOL` of a step of the uniform grid through the end points.  ``n``: the length
    ``t`` must have (e.g. the signal's).

    Raises
    ------
    IPMCError
        naming ``what``, the offending sample, its time, the step before it and the mean step.
    """
    if np.ndim(t) == 0:
        try:
            h = float(t)
        except (TypeError, ValueError):
            raise IPMCError(f"{what}: the sampling interval must be a number of seconds; got {t!r}") from None
        if not (math.isfinite(h) and h > 0):
            raise IPMCError(f"{what}: the sampling interval must be a positive finite number of seconds; got {t!r}")
        return h
    if np.ndim(t) != 1 or len(t) < 2 or (n is not None and len(t) != n):
        want = "at least 2 samples" if n is None else f"shape ({n},) like the signal"
        raise IPMCError(f"{what}: time vector has shape {np.shape(t)}; expected a 1-D array with {want}")
    n = len(t)
    t0, t1 = float(t[0]), float(t[-1])
    if not (math.isfinite(t0) and math.isfinite(t1)):
        k = 0 if not math.isfinite(t0) else n - 1
        raise IPMCError(f"{what}: sample {k} is at {float(t[k])!r} s; time stamps must be finite")
    h = (t1 - t0) / (n - 1)
    if not h > 0:
        raise IPMCError(f"{what}: time stamps must increase; got t[0] = {t0!r} s and t[-1] = {t1!r} s")
    rounding = 8 * np.finfo(float).eps * max(abs(t0), abs(t1))
    step_tol = rtol * h + rounding
    grid_tol = GRID_TOL * h + rounding
    worst_step, k_step, worst_grid, k_grid = 0.0, 0, 0.0, 0
    for a in range(0, n, block_samples):
        b = min(n, a + block_samples + 1)            # one sample of overlap: the step into the next block
        tb = np.asarray(t[a:b], dtype=float)
        bad = ~np.isfinite(tb)
        if bad.any():
            k = a + int(np.flatnonzero(bad)[0])
            raise IPMCError(f"{what}: sample {k} is at {float(t[k])!r} s; time stamps must be finite")
        if tb.size > 1:
            step_dev = np.abs(np.diff(tb) - h)
            i = int(np.argmax(step_dev))
            if step_dev[i] > worst_step:
                worst_step, k_step = float(step_dev[i]), a + 1 + i
        grid_dev = np.abs(tb - (t0 + np.arange(a, b) * h))
        i = int(np.argmax(grid_dev))
        if grid_dev[i] > worst_grid:
            worst_grid, k_grid = float(grid_dev[i]), a + i
    if worst_step > step_tol or worst_grid > grid_tol:
        k = k_step if worst_step > step_tol else max(k_grid, 1)     # the worst step first: it is the cause
        step = float(t[k]) - float(t[k - 1])
        raise IPMCError(
            f"{what} are not uniformly spaced: sample {k} is at t = {float(t[k])!r} s, step t[{k}] - t[{k - 1}] "
            f"= {step!r} s, mean step {h!r} s (uniform grid: t[{k}] = {t0 + k * h!r} s; tolerance {rtol:g} of a "
            f"step per step, {GRID_TOL:g} of a step from the grid); resample the record onto a uniform time base")
    return float(h)


def sample_rate(t_or_fs, n: int, block_samples: int = TIME_BLOCK_SAMPLES) -> float:
    """Sample rate [Hz] from a scalar ``fs`` [Hz] or from uniform sample times ``t`` [s] of length ``n``.

    The times are checked by :func:`uniform_interval` with the tolerance of measured records
    (steps within 2e-3 of the mean step, samples within 1e-3 of a step from the uniform grid).
    """
    if np.ndim(t_or_fs) == 0:
        try:
            fs = float(t_or_fs)
        except (TypeError, ValueError):
            fs = math.nan
        if not (math.isfinite(fs) and fs > 0):
            raise IPMCError(f"t_or_fs: sample rate {t_or_fs!r} Hz must be a finite number > 0")
        return fs
    return 1.0 / uniform_interval(t_or_fs, n, rtol=2 * GRID_TOL, what="t_or_fs: time stamps",
                                  block_samples=block_samples)


@dataclass(frozen=True)
class TimeRecord:
    """Uniformly sampled channels in the units of their file.

    Attributes
    ----------
    t : (n,) ndarray            sample times [s]
    channels : dict[str, ndarray]   channel name → (n,) samples, in ``units[name]``
    units : dict[str, str]      channel name → unit (e.g. ``'V'``, ``'mm'``, ``'uA'``)
    metadata : dict             provenance, e.g. ``temperature_c``
    """

    t: np.ndarray
    channels: dict
    units: dict
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise IPMCError(f"t must be 1-D with at least 2 samples, got shape {t.shape}")
        if not self.channels:
            raise IPMCError("a time record needs at least one channel")
        if set(self.channels) != set(self.units):
            raise IPMCError(f"channels {sorted(self.channels)} and units {sorted(self.units)} must name the same channels")
        chans = {}
        for name, v in self.channels.items():
            split_column(f"{name}_{self.units[name]}", "")
            v = np.asarray(v, dtype=float)
            if v.shape != t.shape:
                raise IPMCError(f"channel {name!r} has shape {v.shape}; t has shape {t.shape}")
            chans[name] = v
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "channels", chans)
        object.__setattr__(self, "units", dict(self.units))

    # ------------------------------------------------------------------ views
    @property
    def fs(self) -> float:
        """Sample rate [Hz] (the time base is checked to be uniform)."""
        return sample_rate(self.t, self.t.size)

    def resolve(self, name: str) -> str:
        """The channel called ``name`` or stored in column ``name`` (``'<name>_<unit>'``)."""
        if name in self.channels:
            return name
        for k, u in self.units.items():
            if name == f"{k}_{u}":
                return k
        raise IPMCError(f"no channel {name!r}; the record has {self.columns_names()}")

    def channel(self, name: str) -> np.ndarray:
        """Samples of channel ``name`` (or of its column ``<name>_<unit>``)."""
        return self.channels[self.resolve(name)]

    def columns_names(self) -> list[str]:
        return [f"{k}_{u}" for k, u in self.units.items()]

    def temperature_c(self) -> float | None:
        """The ``temperature_c`` metadata entry [°C], if the record has one."""
        v = self.metadata.get("temperature_c")
        if v is None:
            return None
        try:
            return float(v)
        except (TypeError, ValueError):
            raise DataFormatError(f"metadata temperature_c = {v!r} is not a number") from None

    def columns(self) -> dict:
        return {TIME_COLUMN: self.t, **{f"{k}_{self.units[k]}": v for k, v in self.channels.items()}}

    @classmethod
    def from_columns(cls, columns: dict, metadata: dict | None = None, where: str = "") -> TimeRecord:
        """From ``{'time_s': t, '<name>_<unit>': samples, ...}`` (e.g. ``TimeSeries.columns()``)."""
        if TIME_COLUMN not in columns:
            raise DataFormatError(f"{where}no '{TIME_COLUMN}' column; found {list(columns)}")
        chans: dict[str, np.ndarray] = {}
        units: dict[str, str] = {}
        for col, v in columns.items():
            if col == TIME_COLUMN:
                continue
            name, unit = split_column(col, where)
            if name in chans:
                raise DataFormatError(f"{where}channel {name!r} appears twice (columns {name}_{units[name]}, {col})")
            chans[name], units[name] = v, unit
        return cls(columns[TIME_COLUMN], chans, units, dict(metadata or {}))

    # ------------------------------------------------------------------ files
    def header_lines(self) -> list[str]:
        lines = [f"{FORMAT} {FORMAT_VERSION}"]
        lines += [f"{k}_{u}: {k} [{u}]" for k, u in self.units.items()]
        lines += [f"{k}: {str(v).replace(chr(10), ' ')}" for k, v in self.metadata.items()]
        return lines

    def to_csv(self, path) -> Path:
        cols = self.columns()
        data = np.column_stack(list(cols.values()))

        def write(fh):
            for line in self.header_lines():
                fh.write(f"# {line}\n")
            fh.write(",".join(cols) + "\n")
            np.savetxt(fh, data, delimiter=",", fmt="%.17g")

        return atomic_write(path, write)

    def to_npz(self, path) -> Path:
        header = json.dumps({"format": FORMAT, "version": FORMAT_VERSION, "metadata": self.metadata})

        def write(fh):
            np.savez(fh, header=np.array(header), **self.columns())

        return atomic_write(path, write, "wb")

    def to_mat(self, path) -> Path:
        from scipy.io import savemat

        cols = {k: v.reshape(-1, 1) for k, v in self.columns().items()}
        cols["format"] = f"{FORMAT} {FORMAT_VERSION}"
        cols["metadata_json"] = json.dumps(self.metadata)

        def write(fh):
            savemat(fh, cols, do_compression=True)

        return atomic_write(path, write, "wb")

    def save(self, path) -> Path:
        """Write by extension (.csv, .npz, .mat), atomically."""
        return by_extension(path, {".csv": self.to_csv, ".npz": self.to_npz, ".mat": self.to_mat}, "time-record")(path)


# ----------------------------------------------------------------------------------- reading
def _check_finite(cols: dict, where: str) -> None:
    for k, v in cols.items():
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise DataFormatError(f"{where}column {k} is not finite at samples {bad[:5].tolist()}")


def _check_version(text: str, where: str) -> None:
    parts = text.split()
    if len(parts) > 1 and parts[1] != str(FORMAT_VERSION):
        raise DataFormatError(f"{where}{FORMAT} version {parts[1]!r} is not supported; expected {FORMAT_VERSION}")


def _apply_channel_headers(rec_cols: dict, header: dict, where: str) -> dict:
    """Metadata without the per-channel lines, after checking them against their columns."""
    meta = {}
    for k, v in header.items():
        if k in rec_cols and k != TIME_COLUMN:
            name, unit = split_column(k, where)
            if v.replace(" ", "") != f"{name}[{unit}]":
                raise DataFormatError(f"{where}header '{k}: {v}' disagrees with its column; expected '{name} [{unit}]'")
        else:
            meta[k] = v
    return meta


def read_csv(path, unitless: str | None = None) -> TimeRecord:
    """Read an ``ipmc-timeseries`` CSV (see module doc); ``unitless``: see :func:`read_record`."""
    path = Path(path)
    where = f"{path}: "
    text = read_text(path, "time-record")
    lines = text.splitlines()
    head = comment_header(lines)
    n_head = head.end
    if FORMAT in head.entries:
        _check_version(f"{FORMAT} {head.entries[FORMAT]}", where)
    header = {k: v for k, v in head.entries.items() if not k.startswith("ipmc-")}   # format lines are not metadata
    if n_head >= len(lines):
        raise DataFormatError(f"{where}no column header line after the '#' header")
    names = [c.strip() for c in lines[n_head].strip().split(",")]
    if len(set(names)) != len(names):
        raise DataFormatError(f"{path}:{n_head + 1}: repeated column names in {names}")
    try:
        data = np.loadtxt(io.StringIO("\n".join(lines[n_head + 1:])), delimiter=",", comments="#", ndmin=2)
    except ValueError as exc:
        raise DataFormatError(f"{where}{exc} (data rows start at line {n_head + 2})") from None
    if data.shape[0] == 0:
        raise DataFormatError(f"{where}no data rows")
    if data.shape[1] != len(names):
        raise DataFormatError(f"{where}{data.shape[1]} values per row but {len(names)} columns {names}")
    cols = {n: data[:, i] for i, n in enumerate(names)}
    _check_finite(cols, where)
    meta = _apply_channel_headers(cols, header, where)
    return _build(cols, meta, where, unitless)


#: How to read a file whose columns are not ``time_s`` and ``<name>_<unit>`` (said by the errors).
MAPPING_HINT = ("or map the file's own columns: read_record(path, columns={'time': 't', 'voltage': 'volts'}, "
                "units={'voltage': 'V'}) (ipmc: --time-column, --input-column/--input-unit, "
                "--output-column/--output-unit)")


def _build(cols: dict, meta: dict, where: str, unitless: str | None = None) -> TimeRecord:
    if unitless is not None:
        cols = {(k if k == TIME_COLUMN or "_" in k else f"{k}_{unitless}"): v for k, v in cols.items()}
    try:
        return TimeRecord.from_columns(cols, meta, where)
    except DataFormatError as exc:
        raise DataFormatError(f"{exc}; {MAPPING_HINT}") from None
    except IPMCError as exc:
        raise DataFormatError(f"{where}{exc}") from None


def _load_failed(path, exc: BaseException, what: str):
    if isinstance(exc, FileNotFoundError):
        return DataFormatError(f"{path}: no such file")
    if isinstance(exc, IsADirectoryError):
        return DataFormatError(f"{path} is a folder; expected a {what} file")
    return DataFormatError(f"{path}: not a readable {what} time record ({type(exc).__name__}: {exc})")


def read_npz(path, unitless: str | None = None) -> TimeRecord:
    """Read an ``ipmc-timeseries`` NPZ (also the ``ipmc-reference`` NPZ of older versions)."""
    where = f"{path}: "
    try:   # the file is opened here so that it is closed whatever np.load makes of it
        with open(path, "rb") as fh:
            archive = np.load(fh, allow_pickle=False)
            if isinstance(archive, np.ndarray):        # an .npy array under an .npz name
                raise DataFormatError(f"{where}one .npy array, not an NPZ archive of columns")
            with archive as z:
                data = {k: z[k] for k in z.files}
    except DataFormatError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise _load_failed(path, exc, "NPZ") from None
    meta = {}
    if "header" in data:
        try:
            hdr = json.loads(str(data.pop("header")))
        except ValueError:
            raise DataFormatError(f"{where}the 'header' entry is not JSON") from None
        if not isinstance(hdr, dict) or hdr.get("format") not in (FORMAT, LEGACY_REFERENCE_FORMAT):
            fmt = hdr.get("format") if isinstance(hdr, dict) else hdr
            raise DataFormatError(f"{where}header format {fmt!r} is not {FORMAT!r}")
        if hdr["format"] == FORMAT:
            _check_version(f"{FORMAT} {hdr.get('version')}", where)
        meta = {k: str(v) for k, v in (hdr.get("metadata") or {}).items()}
    try:
        cols = {k: np.asarray(v, dtype=float).reshape(-1) for k, v in data.items()}
    except (TypeError, ValueError):
        raise DataFormatError(f"{where}every entry but 'header' must be a numeric column") from None
    _check_finite(cols, where)
    return _build(cols, meta, where, unitless)


def read_mat(path, unitless: str | None = None) -> TimeRecord:
    """Read an ``ipmc-timeseries`` MATLAB file (one column vector per column, ``metadata_json``)."""
    from scipy.io import loadmat

    where = f"{path}: "
    try:   # scipy's parser raises many exception types on a malformed file; all mean "not readable"
        data = loadmat(path)
    except Exception as exc:  # noqa: BLE001
        raise _load_failed(path, exc, "MAT") from None
    try:
        meta = json.loads(str(data["metadata_json"][0])) if "metadata_json" in data else {}
    except (ValueError, IndexError):
        raise DataFormatError(f"{where}metadata_json is not JSON") from None
    skip = {"format", "metadata_json"}
    try:
        cols = {k: np.asarray(v, dtype=float).reshape(-1) for k, v in data.items()
                if not k.startswith("__") and k not in skip}
    except (TypeError, ValueError):
        raise DataFormatError(f"{where}every variable but format/metadata_json must be a numeric column") from None
    _check_finite(cols, where)
    return _build(cols, {k: str(v) for k, v in dict(meta).items()}, where, unitless)


def read_mapped_record(path, columns: dict | None = None, units: dict | None = None,
                       temperature_c: float | None = None, unitless: str | None = None) -> TimeRecord:
    """A time record from a user's own CSV/NPZ/MAT file through a column and unit mapping
    (:func:`physmodel.data.columns.map_record` says how ``columns``, ``units`` and
    ``temperature_c`` are read).

    Raises
    ------
    ColumnMapError (a DataFormatError)
        naming the argument and key that fix the problem.
    """
    t, chans, cunits, meta, where = map_record(path, columns, units, temperature_c, unitless)
    bad = [n for n in chans if not _NAME.match(n)]
    if bad:
        raise ColumnMapError(f"{where}: channel name {bad[0]!r} must start with a letter and hold letters, digits "
                             "and '_'", "columns", bad[0])
    _check_finite({TIME_COLUMN: t, **chans}, f"{where}: ")
    try:
        return TimeRecord(t, chans, cunits, meta)
    except IPMCError as exc:
        raise DataFormatError(f"{where}: {exc}") from None


def read_record(path, unitless: str | None = None, *, columns: dict | None = None, units: dict | None = None,
                temperature_c: float | None = None) -> TimeRecord:
    """Read a time record by extension (.csv, .npz, .mat).

    ``unitless``: unit given to a column named without a ``_<unit>`` suffix (files of the older
    ``inversion.references.Reference.save``, which wrote a bare ``reference`` column when the
    reference had no unit; hand-made files with e.g. ``time_s,target``); None refuses such a column.
    ``columns``, ``units``, ``temperature_c``: a user's own file (a DAQ's ``t, volts, disp``, a
    MATLAB session's variables) through a mapping, see :func:`read_mapped_record`.
    """
    if columns or units or temperature_c is not None:
        return read_mapped_record(path, columns, units, temperature_c, unitless)
    reader = by_extension(path, {".csv": read_csv, ".npz": read_npz, ".mat": read_mat}, "time-record")
    return reader(path, unitless)
