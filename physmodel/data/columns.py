"""A user's own tables: columns chosen by name or index, units stated by the user.

The time-record and sweep readers (:func:`physmodel.data.timerecord.read_record`,
:func:`physmodel.data.files.read_sweep`) read the library's own formats without help; a file a
DAQ, an analyser or a MATLAB session wrote (``t, volts, disp``; ``T_degC,freq_Hz,gain_dB,...``;
variables ``t``, ``u``, ``y``) is read through a *mapping*: ``columns={role: name or index}`` and
``units={role: unit}``.  This module holds what both readers share: :func:`read_table` (any CSV
with one header row, NPZ archive or MATLAB file as named numeric columns), :func:`pick` (a column
by name, by ``<name>_<unit>`` prefix or by 0-based index) and :class:`ColumnMapError`, which
names the argument and the key that fix the problem so that a command can name its option.
"""

from __future__ import annotations

import csv
import io
import json
import math
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import DataFormatError
from .fileio import by_extension, comment_header, read_text
from .units import UNITS

__all__ = ["ColumnMapError", "Table", "read_table", "pick", "suffix_unit", "time_column", "map_record", "TIME_UNITS"]


class ColumnMapError(DataFormatError):
    """A column or unit the mapping must give: ``argument`` (``'columns'``, ``'units'`` or
    ``'temperature_c'``) and ``key`` (the role or channel) say which entry fixes it."""

    def __init__(self, message: str, argument: str, key: str):
        super().__init__(message)
        self.argument = argument
        self.key = key


@dataclass(frozen=True)
class Table:
    """Named numeric columns of one file, in file order, and its ``# key: value`` header lines
    (CSV) or string entries (NPZ ``header`` JSON metadata, MATLAB strings)."""

    names: list
    data: dict
    header: dict
    where: str
    text: dict = field(default_factory=dict)     # column → why it is not numeric (its first bad line)

    def describe(self) -> str:
        """``'0:t, 1:volts, 2:disp'``: the columns with their 0-based indices (said by the errors)."""
        return ", ".join(f"{k}:{n}" for k, n in enumerate(self.names))


def suffix_unit(column: str, known=UNITS) -> tuple[str, str] | None:
    """``('tip', 'mm')`` for ``'tip_mm'`` when the part after the last ``_`` is a unit in ``known``."""
    if "_" not in column:
        return None
    name, unit = column.rsplit("_", 1)
    return (name, unit) if name and unit in known else None


def pick(table: Table, spec, key: str, argument: str = "columns") -> str:
    """The column of ``table`` that ``spec`` names: its name, the one column ``<spec>_<unit>``, or a
    0-based index (an int or a string of digits that is not a column name); a column that is not
    numeric is a DataFormatError naming its first line that is not a number."""
    name = _pick(table, spec, key, argument)
    if name in table.text:
        raise DataFormatError(table.text[name])
    return name


def _pick(table: Table, spec, key: str, argument: str) -> str:
    names = table.names
    if isinstance(spec, str):
        if spec in names:
            return spec
        pre = [n for n in names if suffix_unit(n) and suffix_unit(n)[0] == spec]   # type: ignore[index]
        if len(pre) == 1:
            return pre[0]
        if spec.strip().lstrip("-").isdigit():
            spec = int(spec)
    if isinstance(spec, int | np.integer) and not isinstance(spec, bool):
        k = int(spec)
        if not 0 <= k < len(names):
            raise ColumnMapError(f"{table.where}: {argument}[{key!r}] = {k}: no column {k} (0-based); the file has "
                                 f"{len(names)} column(s): {table.describe()}", argument, key)
        return names[k]
    raise ColumnMapError(f"{table.where}: {argument}[{key!r}] = {spec!r}: no such column; the file has "
                         f"{table.describe()} (give a name or a 0-based index)", argument, key)


# ----------------------------------------------------------------------------------- reading
def _delimiter(line: str) -> str:
    if "," in line:
        return ","
    return ";" if ";" in line else ("\t" if "\t" in line else ",")


def _csv_table(path) -> Table:
    where = str(path)
    lines = read_text(path, "data file").splitlines()
    head = comment_header(lines)
    header, i = head.entries, head.end
    if i >= len(lines):
        raise DataFormatError(f"{where}: no column header line (expected one row of column names)")
    delim = _delimiter(lines[i])
    names = [n.strip() for n in next(csv.reader([lines[i]], delimiter=delim))]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise DataFormatError(f"{where}:{i + 1}: column name(s) {dup} appear more than once")
    rows = [ln for ln in lines[i + 1:] if ln.strip() and not ln.lstrip().startswith("#")]
    if not rows:
        raise DataFormatError(f"{where}: no data rows after the column header (line {i + 1})")
    try:
        data = np.loadtxt(io.StringIO("\n".join(rows)), delimiter=delim, ndmin=2, dtype=float)
    except ValueError:
        data = None
    if data is not None and data.shape[1] == len(names):
        return Table(names, {n: data[:, k] for k, n in enumerate(names)}, header, where)
    # a text column (a status, a time stamp) or a ragged row: column by column, a text column is
    # refused only when it is used (pick), naming its first line that is not a number
    values: list[list[float]] = [[] for _ in names]
    bad: dict[str, str] = {}
    for j in range(i + 1, len(lines)):
        raw = lines[j]
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        parts = next(csv.reader([raw], delimiter=delim))
        if len(parts) != len(names):
            raise DataFormatError(f"{where}:{j + 1}: {len(parts)} values; the header has {len(names)} columns")
        for c, (n, p) in enumerate(zip(names, parts)):
            try:
                values[c].append(float(p))
            except ValueError:
                bad.setdefault(n, f"{where}:{j + 1}: {n} = {p.strip()!r} is not a number")
    return Table(names, {n: np.array(v) for n, v in zip(names, values) if n not in bad}, header, where, bad)


def _numeric(v) -> np.ndarray | None:
    a = np.asarray(v)
    if a.dtype.kind not in "iuf" or a.size == 0 or (a.ndim > 1 and max(a.shape) != a.size):
        return None
    return a.reshape(-1).astype(float)


def _npz_table(path) -> Table:
    where = str(path)
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            raw = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise DataFormatError(f"{where}: no such file") from None
    except (OSError, ValueError, EOFError, AttributeError, TypeError, zipfile.BadZipFile) as exc:
        raise DataFormatError(f"{where}: not a readable NPZ archive ({type(exc).__name__}: {exc})") from None
    return _arrays_table(raw, where)


def _mat_table(path) -> Table:
    from scipy.io import loadmat

    where = str(path)
    if not Path(path).is_file():
        raise DataFormatError(f"{where}: no such file")
    try:   # scipy's parser raises many exception types on a malformed file; all mean "not readable"
        raw = {k: v for k, v in loadmat(path).items() if not k.startswith("__")}
    except Exception as exc:  # noqa: BLE001
        raise DataFormatError(f"{where}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})") from None
    return _arrays_table(raw, where)


def _arrays_table(raw: dict, where: str) -> Table:
    names, data, header = [], {}, {}
    for k, v in raw.items():
        a = np.asarray(v)
        if a.dtype.kind == "U" and a.size == 1:
            text = str(a.reshape(-1)[0])
            if k in ("header", "metadata_json"):
                try:
                    d = json.loads(text)
                except ValueError:
                    d = None
                if isinstance(d, dict):
                    header.update({str(kk): str(vv) for kk, vv in (d.get("metadata", d) or {}).items()})
                    for kk in ("input", "output"):
                        if isinstance(d.get(kk), str):
                            header[kk] = d[kk]
                    continue
            header[k] = text
            continue
        col = _numeric(a)
        if col is not None:
            names.append(k)
            data[k] = col
    if not names:
        raise DataFormatError(f"{where}: no numeric vector in the file (variables: {sorted(raw)})")
    return Table(names, data, header, where)


def read_table(path, what: str = "data") -> Table:
    """Named numeric columns of a CSV (one header row of names; ``,``, ``;`` or tab; ``#`` lines
    before it are ``key: value`` header lines), an NPZ archive or a MATLAB .mat file (each numeric
    vector a column, in file order; string entries become header entries)."""
    return by_extension(path, {".csv": _csv_table, ".npz": _npz_table, ".mat": _mat_table}, what)(path)


# ----------------------------------------------------------------------------------- records
#: Units of a time column, as multiples of a second.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0}


def time_column(table: Table, columns: dict, units: dict) -> tuple[str, np.ndarray]:
    """``(column name, times [s])`` of ``table``: the column ``columns['time']`` (a name or 0-based
    index; default ``time_s``) in ``units['time']`` (s, ms, us or min; default the column name's
    ``_<unit>`` suffix, else s).  A ColumnMapError names ``columns['time']`` or ``units['time']``."""
    if "time" in columns:
        tcol = pick(table, columns["time"], "time")
    elif "time_s" in table.names:
        tcol = pick(table, "time_s", "time")
    else:
        raise ColumnMapError(f"{table.where}: which column holds the time? give columns={{'time': NAME or INDEX}} "
                             f"(ipmc: --time-column NAME); the file has {table.describe()}", "columns", "time")
    unit = units.get("time")
    if unit is None:
        suffix = tcol.rsplit("_", 1)[-1] if "_" in tcol else ""
        unit = suffix if suffix in TIME_UNITS else "s"
    if unit not in TIME_UNITS:
        raise ColumnMapError(f"{table.where}: units['time'] = {unit!r}; expected one of {list(TIME_UNITS)}",
                             "units", "time")
    return tcol, table.data[tcol] * TIME_UNITS[unit]


def map_record(path, columns: dict | None = None, units: dict | None = None, temperature_c: float | None = None,
               unitless: str | None = None) -> tuple:
    """``(t [s], channels, units, metadata, where)`` of a time record in a user's own CSV/NPZ/MAT
    file, read through a column and unit mapping
    (:func:`physmodel.data.timerecord.read_mapped_record` makes the record).

    ``columns``: channel name → column name (or its ``<name>`` before a ``_<unit>`` suffix) or
    0-based index; the key ``'time'`` names the time column (default ``time_s``).  Only the
    channels named are read (all columns when only ``'time'`` is mapped).  ``units``: channel (or
    column) name → unit (one of :data:`physmodel.data.units.UNITS`; ``'time'``: s, ms, us or
    min); a column named ``<name>_<unit>`` carries its unit, which a stated unit must not
    contradict.  ``temperature_c``: the record's temperature [°C] (replaces a header's).

    Raises
    ------
    ColumnMapError (a DataFormatError)
        naming the argument and key that fix the problem.
    """
    columns, units = dict(columns or {}), dict(units or {})
    table = read_table(path, "time-record")
    where = table.where
    tcol, t = time_column(table, columns, units)
    chosen = {k: v for k, v in columns.items() if k != "time"}
    mapped = bool(chosen)
    if not mapped:
        chosen = {c: c for c in table.names if c != tcol}
    chans, cunits, used = {}, {}, {"time"}
    for key, spec in chosen.items():
        src = pick(table, spec, key)
        su = suffix_unit(src)
        name = su[0] if su is not None and (not mapped or key == src) else key
        ukey = next((k for k in (key, src, name) if k in units), None)
        unit = units[ukey] if ukey is not None else (su[1] if su else unitless)
        used.add(ukey or key)
        if unit is None:
            raise ColumnMapError(f"{where}: column {src!r} has no unit in its name; state it: units={{{name!r}: UNIT}} "
                                 "(ipmc: --input-unit/--output-unit)", "units", key)
        if unit not in UNITS:
            raise ColumnMapError(f"{where}: unit {unit!r} of column {src!r} is not one of {sorted(UNITS)}", "units", key)
        if su is not None and su[1] != unit:
            raise ColumnMapError(f"{where}: column {src!r} is in {su[1]} by its name but its unit is given as {unit!r}; "
                                 "drop one of them (a unit that is not the file's would scale the data wrongly)",
                                 "units", key)
        if name in chans:
            raise ColumnMapError(f"{where}: channel {name!r} is read twice (column {src!r})", "columns", key)
        chans[name], cunits[name] = table.data[src], unit
    extra = sorted(set(units) - used)
    if extra:
        raise ColumnMapError(f"{where}: units[{extra[0]!r}]: no channel or column of that name is read; channels "
                             f"{sorted(chans)}", "units", extra[0])
    meta = {k: v for k, v in table.header.items() if k not in table.data and not k.startswith("ipmc-")}
    if temperature_c is not None:
        try:
            T = float(temperature_c)
        except (TypeError, ValueError):
            T = math.nan
        if not math.isfinite(T) or T <= -273.15:
            raise ColumnMapError(f"{where}: temperature_c = {temperature_c!r}; expected a number of °C",
                                 "temperature_c", "temperature")
        if "temperature_c" in meta and meta["temperature_c"] != str(T):
            meta["temperature_c_header"] = meta["temperature_c"]
        meta["temperature_c"] = str(T)
    return t, chans, cunits, meta, where
