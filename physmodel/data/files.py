"""Sweep files: the tidy CSV (the project's exchange format), NPZ and MATLAB .mat, and a user's own
sweep files (an analyser's ``T_degC,freq_Hz,gain_dB,phase_deg,...``) read through a column and unit
mapping (:func:`read_sweep` ``columns=``/``units=``/``temperature_c=``).

The writers live with the record (:mod:`physmodel.data.sweep`) and the file plumbing below both
(:mod:`physmodel.data.fileio`); both are re-exported here, where callers have always found them.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import DataFormatError, IPMCError
from .columns import ColumnMapError, Table, pick, read_table
from .fileio import atomic_write, by_extension, comment_header, read_text
from .results import check_output_folder, folder_owner, output_folder
from .sweep import (
    MAX_SWEEP_LINES,
    OPTIONAL_COLUMNS,
    REQUIRED_COLUMNS,
    FrequencySweep,
    write_csv,
    write_mat,
    write_npz,
    write_sweep,
)
from .units import UNITS

# the file plumbing (data.fileio) and the sweep writers (data.sweep) are re-exported: callers have
# always found them here
__all__ = ["read_sweep", "read_csv", "read_npz", "read_mat", "read_mapped_sweep", "write_sweep", "write_csv",
           "write_npz", "write_mat", "atomic_write", "by_extension", "check_output_folder", "folder_owner",
           "output_folder", "read_text", "MAPPING_HINT", "ROLES"]

#: How to map a sweep file that is not in the library's format (said by every "missing column" error).
MAPPING_HINT = ("map the file's own columns: read_sweep(path, columns={'temperature': ..., 'frequency': ..., "
                "'magnitude': ..., 'phase': ...}, units={'input': 'V', 'output': 'mm', 'magnitude': 'dB', "
                "'phase': 'deg'}) (ipmc: --sweep-columns temperature=T_degC,frequency=freq_Hz,magnitude=gain_dB,"
                "phase=phase_deg --sweep-units input=V,output=mm)")
#: Roles of a sweep's columns (keys of ``columns=``) and the library's own column for each.
ROLES = ("temperature", "frequency", "magnitude", "phase", "magnitude_std", "phase_std")
ROLE_OF = dict(zip(REQUIRED_COLUMNS + OPTIONAL_COLUMNS, ROLES))
UNITS_HINT = ("state the units of the response: units={'input': 'V', 'output': 'mm'} "
              "(ipmc: --sweep-units input=V,output=mm)")


def _from_columns(cols: Mapping[str, np.ndarray], header: Mapping[str, str], where: str) -> FrequencySweep:
    def unit_of(key):
        if key not in header:
            raise ColumnMapError(f"{where}: missing header line '# {key}: <name> [<unit>]'; {UNITS_HINT}", "units", key)
        text = header[key].strip()
        if not (text.endswith("]") and "[" in text):
            raise DataFormatError(f"{where}: header '{key}: {text}' must look like 'name [unit]'")
        name, unit = text[:-1].split("[", 1)
        unit = unit.strip()
        if unit not in UNITS:
            raise DataFormatError(f"{where}: unknown {key} unit {unit!r}; expected one of {sorted(UNITS)}")
        return name.strip(), unit

    in_name, in_unit = unit_of("input")
    out_name, out_unit = unit_of("output")
    H = _response(cols["magnitude_db"], cols["phase_deg"], "dB", "deg", where)
    meta = {k: v for k, v in header.items() if k not in ("input", "output") and not k.startswith("ipmc-")}
    has_std = "magnitude_std_db" in cols
    return FrequencySweep(cols["temperature_c"], cols["frequency_hz"], H,
                          cols["magnitude_std_db"] if has_std else None,
                          cols["phase_std_deg"] if has_std else None,
                          in_name, in_unit, out_name, out_unit, meta)


# ----------------------------------------------------------------------------------- CSV
def read_csv(path) -> FrequencySweep:
    """Read the tidy CSV; a malformed file raises :class:`DataFormatError` naming the line."""
    path = Path(path)
    lines = read_text(path, "sweep file").splitlines()
    head = comment_header(lines)
    header, i = head.entries, head.end
    if i >= len(lines):
        raise DataFormatError(f"{path}: no column header line after the '#' header")
    colnames = [c.strip() for c in next(csv.reader([lines[i]]))]
    if len(set(colnames)) != len(colnames):
        raise DataFormatError(f"{path}:{i + 1}: column name(s) {sorted({c for c in colnames if colnames.count(c) > 1})} "
                              "appear more than once")
    missing = [c for c in REQUIRED_COLUMNS if c not in colnames]
    if missing:
        raise ColumnMapError(f"{path}:{i + 1}: missing column(s) {missing}; found {colnames}; {MAPPING_HINT}",
                             "columns", ROLE_OF[missing[0]])
    unknown = [c for c in colnames if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:
        raise DataFormatError(f"{path}:{i + 1}: unknown column(s) {unknown}; expected "
                              f"{list(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)}, or {MAPPING_HINT}")
    has_std = [c in colnames for c in OPTIONAL_COLUMNS]
    if any(has_std) and not all(has_std):
        raise DataFormatError(f"{path}:{i + 1}: give both {OPTIONAL_COLUMNS} or neither")
    rows = []
    line_no = []
    for j in range(i + 1, len(lines)):
        raw = lines[j]
        if not raw.strip() or raw.lstrip().startswith("#"):
            continue
        parts = [p.strip() for p in raw.split(",")]
        if len(parts) != len(colnames):
            raise DataFormatError(f"{path}:{j + 1}: expected {len(colnames)} values, got {len(parts)}")
        vals = []
        for name, p in zip(colnames, parts):
            try:
                v = float(p)
            except ValueError:
                raise DataFormatError(f"{path}:{j + 1}: {name} = {p!r} is not a number") from None
            if not math.isfinite(v):
                raise DataFormatError(f"{path}:{j + 1}: {name} is {p!r}; expected a finite number")
            vals.append(v)
        rows.append(vals)
        line_no.append(j + 1)
    if not rows:
        raise DataFormatError(f"{path}: no data rows")
    arr = np.array(rows)
    cols = {name: arr[:, k] for k, name in enumerate(colnames)}
    T, f = cols["temperature_c"], cols["frequency_hz"]
    for k in range(len(rows)):
        if f[k] <= 0:
            raise DataFormatError(f"{path}:{line_no[k]}: frequency_hz = {float(f[k])!r} must be > 0")
        if "magnitude_std_db" in cols and (cols["magnitude_std_db"][k] < 0 or cols["phase_std_deg"][k] < 0):
            raise DataFormatError(f"{path}:{line_no[k]}: standard deviations must be >= 0")
    seen_T: set[float] = set()
    for k in range(len(rows)):
        if k > 0 and T[k] == T[k - 1]:
            if f[k] == f[k - 1]:
                raise DataFormatError(f"{path}:{line_no[k]}: duplicate frequency {f[k]:g} Hz at {T[k]:g} °C")
            if f[k] < f[k - 1]:
                raise DataFormatError(f"{path}:{line_no[k]}: frequencies at {T[k]:g} °C are not sorted "
                                      f"({f[k]:g} Hz after {f[k - 1]:g} Hz)")
        else:
            if T[k] in seen_T:
                raise DataFormatError(f"{path}:{line_no[k]}: rows at {T[k]:g} °C are not contiguous")
            seen_T.add(T[k])
    try:
        return _from_columns(cols, header, str(path))
    except DataFormatError:
        raise
    except IPMCError as exc:
        raise DataFormatError(f"{path}: {exc}") from None


# ----------------------------------------------------------------------------------- NPZ / MAT
#: The arrays a sweep NPZ may hold (others are ignored without being decompressed).
NPZ_ARRAYS = ("header",) + REQUIRED_COLUMNS + OPTIONAL_COLUMNS + ("response_real", "response_imag")
#: Largest array accepted from a sweep file [bytes], checked before it is decompressed: 16 bytes
#: (complex128) for each of MAX_SWEEP_LINES lines.
MAX_ARRAY_BYTES = 16 * MAX_SWEEP_LINES + 4096


def _column(v, key: str, where: str, *, allow_complex: bool = False) -> np.ndarray:
    """``v`` as a 1-D float (or complex) array, or a DataFormatError naming ``key``."""
    a = np.asarray(v)
    kinds = "biufc" if allow_complex else "iuf"
    if a.dtype.kind not in kinds:
        what = "complex numbers" if a.dtype.kind == "c" else f"dtype {a.dtype}"
        raise DataFormatError(f"{where}: {key} holds {what}; expected real numbers")
    if a.ndim > 1 and max(a.shape) != a.size:
        raise DataFormatError(f"{where}: {key} has shape {a.shape}; expected one value per line")
    return a.reshape(-1).astype(complex if allow_complex and a.dtype.kind == "c" else float)


def _sweep_from_arrays(cols: dict, header: dict, response, where: str) -> FrequencySweep:
    """Check lengths, build the sweep, and name the file in any error of the record itself."""
    n = {k: v.size for k, v in cols.items()}
    if response is not None:
        n["response"] = response.size
    if len(set(n.values())) > 1:
        raise DataFormatError(f"{where}: arrays differ in length {n}; expected one value per line in each")
    try:
        sw = _from_columns(cols, header, where)
        return replace(sw, response=response) if response is not None else sw
    except DataFormatError:
        raise
    except IPMCError as exc:
        raise DataFormatError(f"{where}: {exc}") from None


def read_npz(path) -> FrequencySweep:
    """Read a sweep NPZ.  Only the arrays of the format are read, each after its uncompressed size
    is checked (an extra or oversized array cannot exhaust memory); never unpickles."""
    import zipfile

    where = str(path)
    try:
        zf = zipfile.ZipFile(path)
    except FileNotFoundError:
        raise DataFormatError(f"{where}: no such file") from None
    except (zipfile.BadZipFile, OSError, ValueError) as exc:
        raise DataFormatError(f"{where}: not an NPZ archive ({exc})") from None
    data = {}
    with zf:
        members = {n[:-4]: n for n in zf.namelist() if n.endswith(".npy")}
        if "header" not in members:
            raise ColumnMapError(f"{where}: not an ipmc-sweep NPZ (no 'header' array); {MAPPING_HINT}", "columns",
                             "temperature")
        for key in NPZ_ARRAYS:
            if key not in members:
                continue
            size = zf.getinfo(members[key]).file_size
            if size > MAX_ARRAY_BYTES:
                raise DataFormatError(f"{where}: array {key!r} holds {size} bytes; a sweep array holds at most "
                                      f"{MAX_ARRAY_BYTES} ({MAX_SWEEP_LINES} lines)")
            try:
                with zf.open(members[key]) as fh:
                    data[key] = np.lib.format.read_array(fh, allow_pickle=False)
            except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
                raise DataFormatError(f"{where}: array {key!r} cannot be read: {exc}") from None
    h = data["header"]
    if h.dtype.kind != "U" or h.ndim != 0:
        raise DataFormatError(f"{where}: 'header' must be one JSON string, got {h.dtype} with shape {h.shape}")
    try:
        hdr = json.loads(str(h))
    except json.JSONDecodeError as exc:
        raise DataFormatError(f"{where}: 'header' is not JSON: {exc}") from None
    if not isinstance(hdr, dict):
        raise DataFormatError(f"{where}: 'header' must be a JSON object, got {type(hdr).__name__}")
    for key in ("input", "output"):
        if not isinstance(hdr.get(key), str):
            raise DataFormatError(f"{where}: header key {key!r} must be a string 'name [unit]', got {hdr.get(key)!r}")
    meta = hdr.get("metadata", {})
    if not isinstance(meta, dict):
        raise DataFormatError(f"{where}: header key 'metadata' must be an object, got {meta!r}")
    missing = [c for c in REQUIRED_COLUMNS if c not in data]
    if missing:
        raise DataFormatError(f"{where}: missing array(s) {missing}")
    cols = {k: _column(data[k], k, where) for k in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if k in data}
    parts = [k for k in ("response_real", "response_imag") if k in data]
    if len(parts) == 1:
        raise DataFormatError(f"{where}: has {parts[0]!r} but not its partner; give response_real and "
                              "response_imag together, or neither")
    response = None
    if parts:
        re_, im_ = (_column(data[k], k, where) for k in ("response_real", "response_imag"))
        if re_.size != im_.size:
            raise DataFormatError(f"{where}: response_real has {re_.size} values, response_imag {im_.size}")
        response = re_ + 1j * im_      # exact complex values, not rounded through dB/deg
    header = {"input": hdr["input"], "output": hdr["output"], **{str(k): str(v) for k, v in meta.items()}}
    return _sweep_from_arrays(cols, header, response, where)


def _mat_text(data: dict, key: str, where: str) -> str:
    v = np.asarray(data[key])
    if v.dtype.kind != "U" or v.size != 1:
        raise DataFormatError(f"{where}: variable {key!r} must be a string, got {v.dtype} with shape {v.shape}")
    return str(v.reshape(-1)[0])


def read_mat(path) -> FrequencySweep:
    """Read a sweep .mat; variable sizes are checked (``whosmat``) before anything is loaded."""
    from scipy.io import loadmat, whosmat

    where = str(path)
    if not Path(path).is_file():
        raise DataFormatError(f"{where}: no such file")
    wanted = REQUIRED_COLUMNS + OPTIONAL_COLUMNS + ("response", "input", "output", "metadata_json")
    try:   # scipy's parser raises many exception types on a malformed file; all mean "not readable"
        shapes = {name: shape for name, shape, _ in whosmat(path)}
        for key in wanted:
            if key in shapes and 16 * int(np.prod(shapes[key], dtype=np.int64)) > MAX_ARRAY_BYTES:
                raise DataFormatError(f"{where}: variable {key!r} has shape {shapes[key]}; a sweep holds at most "
                                      f"{MAX_SWEEP_LINES} lines")
        data = loadmat(path, variable_names=[k for k in wanted if k in shapes])
    except DataFormatError:
        raise
    except Exception as exc:  # noqa: BLE001
        raise DataFormatError(f"{where}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})") from None
    missing = [c for c in REQUIRED_COLUMNS + ("input", "output") if c not in data]
    if missing:
        raise ColumnMapError(f"{where}: missing variable(s) {missing}; {MAPPING_HINT}",
                             "columns" if missing[0] in REQUIRED_COLUMNS else "units", ROLE_OF.get(missing[0], missing[0]))
    cols = {k: _column(data[k], k, where) for k in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if k in data}
    meta = {}
    if "metadata_json" in data:
        try:
            meta = json.loads(_mat_text(data, "metadata_json", where))
        except json.JSONDecodeError as exc:
            raise DataFormatError(f"{where}: variable 'metadata_json' is not JSON: {exc}") from None
        if not isinstance(meta, dict):
            raise DataFormatError(f"{where}: variable 'metadata_json' must hold a JSON object")
    header = {"input": _mat_text(data, "input", where), "output": _mat_text(data, "output", where),
              **{str(k): str(v) for k, v in meta.items()}}
    response = _column(data["response"], "response", where, allow_complex=True).astype(complex) \
        if "response" in data else None
    return _sweep_from_arrays(cols, header, response, where)


#: Units of the number columns (keys of ``units=`` besides input/output): accepted spellings.
NUMBER_UNITS = {
    "magnitude": {"dB": ("db",), "linear": ("linear", "lin", "abs", "1")},
    "phase": {"deg": ("deg", "degree", "degrees", "°"), "rad": ("rad", "radian", "radians")},
    "frequency": {"Hz": ("hz",), "rad/s": ("rad/s", "rad_s", "rads")},
    "temperature": {"degC": ("degc", "c", "°c", "celsius"), "K": ("k", "kelvin")},
}


def _number_unit(role: str, given, column: str, where: str) -> str:
    """The unit of the ``role`` column: ``given`` (units=) checked against the column name's suffix."""
    table = NUMBER_UNITS[role]
    canon = {a: k for k, al in table.items() for a in (k.lower(), *al)}
    suffix = column.rsplit("_", 1)[-1].lower() if "_" in column else ""
    from_name = canon.get(suffix)
    if given is None:
        return from_name or next(iter(table))
    unit = canon.get(str(given).strip().lower())
    if unit is None:
        raise ColumnMapError(f"{where}: units[{role!r}] = {given!r}; expected one of {list(table)}", "units", role)
    if from_name is not None and from_name != unit:
        raise ColumnMapError(f"{where}: column {column!r} is in {from_name} by its name but units[{role!r}] = "
                             f"{given!r}; drop one of them", "units", role)
    return unit


def _response(mag, phase, mag_unit: str, phase_unit: str, where: str) -> np.ndarray:
    with np.errstate(over="ignore", invalid="ignore"):
        m = 10 ** (np.asarray(mag, float) / 20) if mag_unit == "dB" else np.asarray(mag, float)
        H = m * np.exp(1j * (np.radians(phase) if phase_unit == "deg" else np.asarray(phase, float)))
    bad = np.flatnonzero(~np.isfinite(H) | (m <= 0) | ~np.isfinite(m))
    if bad.size:
        k = int(bad[0])
        raise DataFormatError(f"{where}: line {k + 1}: magnitude {float(np.asarray(mag)[k])!r} {mag_unit} gives no "
                              f"finite nonzero response (a magnitude in dB between -600 and 600, or > 0 linear)")
    return H


def _response_units(units: Mapping, header: Mapping, where: str) -> dict:
    labels = {}
    for key in ("input", "output"):
        u = units.get(key)
        if u is None:
            text = str(header.get(key, "")).strip()
            if text.endswith("]") and "[" in text:
                name, u = (x.strip() for x in text[:-1].split("[", 1))
                labels[f"{key}_name"] = name or key
            else:
                raise ColumnMapError(f"{where}: the {key} unit of the response is not known; {UNITS_HINT}", "units", key)
        if u not in UNITS:
            raise ColumnMapError(f"{where}: units[{key!r}] = {u!r} is not a unit of the library; expected one of "
                                 f"{sorted(UNITS)}", "units", key)
        labels[f"{key}_unit"] = u
        labels.setdefault(f"{key}_name", {"length": "displacement"}.get(UNITS[u][0], UNITS[u][0]))
    return labels


def read_mapped_sweep(path, columns: Mapping | None = None, units: Mapping | None = None,
                      temperature_c: float | None = None) -> FrequencySweep:
    """A sweep from a user's own CSV/NPZ/MAT file through a column and unit mapping.

    ``columns``: role → column name or 0-based index, roles :data:`ROLES` (unmapped roles use
    the library's column if present: ``temperature_c``, ``frequency_hz``, ...).  ``units``:
    ``input``/``output`` (the response is output/input, e.g. ``'mm'``/``'V'``; default: the
    file's ``# input: name [unit]`` header), ``magnitude`` (``'dB'`` or ``'linear'``), ``phase``
    (``'deg'`` or ``'rad'``), ``frequency`` (``'Hz'`` or ``'rad/s'``), ``temperature``
    (``'degC'`` or ``'K'``); a column-name suffix (``gain_dB``, ``phase_rad``) sets them too and
    must agree.  The σ columns are in the magnitude's and phase's units (a linear σ is converted
    to dB at each line's magnitude).  ``temperature_c``: one temperature [°C] for a file without
    a temperature column.  Lines are sorted by temperature, then frequency.

    Raises
    ------
    ColumnMapError (a DataFormatError)
        naming the argument and key that fix the problem (``columns['frequency']``, ``units['input']``).
    """
    columns, units = dict(columns or {}), dict(units or {})
    bad = sorted(set(columns) - set(ROLES)) or sorted(set(units) - {"input", "output", *NUMBER_UNITS})
    if bad:
        arg = "columns" if set(columns) - set(ROLES) else "units"
        allowed = list(ROLES) if arg == "columns" else ["input", "output", *NUMBER_UNITS]
        raise ColumnMapError(f"{path}: {arg}[{bad[0]!r}]: not a role of a sweep; expected {allowed}", arg, bad[0])
    table = read_table(path, "sweep")
    where = table.where
    picked: dict[str, str] = {}
    for role, default in zip(ROLES, REQUIRED_COLUMNS + OPTIONAL_COLUMNS):
        if role in columns:
            picked[role] = pick(table, columns[role], role)
        elif default in table.names and not (role == "temperature" and temperature_c is not None):
            picked[role] = pick(table, default, role)
    T = _temperatures(table, picked, columns, units, temperature_c)
    for role in ("frequency", "magnitude", "phase"):
        if role not in picked:
            raise ColumnMapError(f"{where}: which column holds the {role}? give columns={{{role!r}: NAME or INDEX}} "
                                 f"(ipmc: --sweep-columns {role}=NAME); the file has {table.describe()}", "columns", role)
    if ("magnitude_std" in picked) != ("phase_std" in picked):
        miss = "phase_std" if "magnitude_std" in picked else "magnitude_std"
        raise ColumnMapError(f"{where}: give both σ columns or neither; columns[{miss!r}] is missing", "columns", miss)
    u = {r: _number_unit(r, units.get(r), picked.get(r, ""), where) for r in ("magnitude", "phase", "frequency")}
    col = {r: table.data[c] for r, c in picked.items()}
    for r, c in picked.items():
        nonfinite = np.flatnonzero(~np.isfinite(col[r]))
        if nonfinite.size:
            raise DataFormatError(f"{where}: column {c!r} ({r}) is not finite at line(s) {(nonfinite[:5] + 1).tolist()}")
    f = col["frequency"] / (2 * np.pi) if u["frequency"] == "rad/s" else col["frequency"]
    H = _response(col["magnitude"], col["phase"], u["magnitude"], u["phase"], where)
    std = None
    if "magnitude_std" in col:
        ms = col["magnitude_std"] if u["magnitude"] == "dB" else 20 / np.log(10) * col["magnitude_std"] / np.abs(H)
        std = (ms, col["phase_std"] if u["phase"] == "deg" else np.degrees(col["phase_std"]))
    labels = _response_units(units, table.header, where)
    order = np.lexsort((f, T))
    dup = np.flatnonzero((np.diff(T[order]) == 0) & (np.diff(f[order]) == 0))
    if dup.size:
        k = order[dup[0]]
        raise DataFormatError(f"{where}: two lines at {f[k]:g} Hz and {T[k]:g} °C")
    meta = {k: v for k, v in table.header.items()
            if k not in ("input", "output", "temperature_c") and not k.startswith("ipmc-")}     # not format lines
    meta["columns"] = ", ".join(f"{r}={c}" for r, c in picked.items())
    try:
        return FrequencySweep(T[order], f[order], H[order], None if std is None else std[0][order],
                              None if std is None else std[1][order], metadata=meta, **labels)
    except IPMCError as exc:
        raise DataFormatError(f"{where}: {exc}") from None


def _temperatures(table: Table, picked: dict, columns: Mapping, units: Mapping, temperature_c) -> np.ndarray:
    n = max((v.size for v in table.data.values()), default=0)
    if temperature_c is not None:
        if "temperature" in columns:
            raise ColumnMapError(f"{table.where}: give temperature_c or columns['temperature'], not both",
                                 "temperature_c", "temperature")
        try:
            t = float(temperature_c)
        except (TypeError, ValueError):
            t = math.nan
        if not math.isfinite(t):
            raise ColumnMapError(f"{table.where}: temperature_c = {temperature_c!r}; expected a number [°C]",
                                 "temperature_c", "temperature")
        return np.full(n, t)
    if "temperature" not in picked:
        if "temperature_c" in table.header:        # a '# temperature_c: 30' header line
            return _temperatures(table, picked, columns, units, table.header["temperature_c"])
        raise ColumnMapError(f"{table.where}: no temperature: give columns={{'temperature': NAME or INDEX}} or "
                             "temperature_c=<°C> (ipmc: --sweep-columns temperature=NAME or --sweep-temperature T)",
                             "columns", "temperature")
    T = table.data[picked["temperature"]]
    unit = _number_unit("temperature", units.get("temperature"), picked["temperature"], table.where)
    return T - 273.15 if unit == "K" else T


def read_sweep(path, *, columns: Mapping | None = None, units: Mapping | None = None,
               temperature_c: float | None = None) -> FrequencySweep:
    """Read a sweep by file extension (.csv, .npz, .mat).

    Parameters
    ----------
    path : str or Path
        The file.  With no mapping it must be in the library's format (see
        :mod:`physmodel.data.sweep`).
    columns : mapping or None
        A user's own file: role (temperature, frequency, magnitude, phase, magnitude_std,
        phase_std) → column name or 0-based index (:func:`read_mapped_sweep`).
    units : mapping or None
        ``input``/``output`` units of the response (e.g. ``'V'``, ``'mm'``) and the units of the
        number columns (magnitude dB/linear, phase deg/rad, frequency Hz/rad/s, temperature degC/K).
    temperature_c : float or None
        Temperature [°C] of every line of a file without a temperature column.

    Raises
    ------
    DataFormatError
        naming the file and the problem; a :class:`~physmodel.data.columns.ColumnMapError` when a
        mapping entry fixes it, naming the argument and the ``ipmc`` option to give.
    """
    if columns or units or temperature_c is not None:
        return read_mapped_sweep(path, columns, units, temperature_c)
    return by_extension(path, {".csv": read_csv, ".npz": read_npz, ".mat": read_mat}, "sweep")(path)
