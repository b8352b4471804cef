"""Sweep files: the tidy CSV (the project's exchange format), NPZ and MATLAB .mat, and the one
atomic writer every file of the library goes through (temporary file, then rename)."""

from __future__ import annotations

import csv
import io
import json
import math
import os
import secrets
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import interrupts
from ..errors import DataFormatError, IPMCError
from .sweep import FORMAT_VERSION, MAX_SWEEP_LINES, OPTIONAL_COLUMNS, REQUIRED_COLUMNS, FrequencySweep
from .units import UNITS


# ----------------------------------------------------------------------------------- I/O helpers
def atomic_write(path, write_fn, mode: str = "w") -> Path:
    """Write ``path`` via ``write_fn(fh)`` into a temporary file in the same folder, flushed to disk,
    then renamed over ``path``: never a half-written file, even on Ctrl-C.  ``mode``: "w" (UTF-8 text,
    no newline translation) or "wb".  The file gets the usual permissions (0666 less the umask)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # the name is fixed before the file exists, so an interrupt at any point after creation still
    # finds and removes it (mkstemp's name is only known once it returns)
    tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.part"
    try:
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError as exc:         # name the file asked for, not the temporary one
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        with os.fdopen(fd, mode, **({"newline": "", "encoding": "utf-8"} if "b" not in mode else {})) as fh:
            write_fn(fh)
            fh.flush()
            os.fsync(fh.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)   # created 0600
        interrupts.check()             # an interrupt a solver swallowed must not commit a file
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def read_text(path, what: str = "file") -> str:
    """The text of ``path`` decoded as UTF-8, a leading byte-order mark dropped (Excel writes one).

    Every text reader of the library (sweep CSV, scenario/study/experiment TOML, parameter JSON,
    signal CSV) goes through here, so a file that is not UTF-8 is a :class:`DataFormatError` naming
    the file, the line and the byte, never a ``UnicodeDecodeError``.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise DataFormatError(f"{what} {str(path)!r}: no such file") from None
    except IsADirectoryError:
        raise DataFormatError(f"{what} {str(path)!r} is a folder; expected a file") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise DataFormatError(f"{path}:{line}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
                              "save the file as UTF-8") from None


# result folders (all or nothing, completion marker): physmodel.data.results; the names stay importable here
from .results import OWNER_FILES, check_output_folder, folder_owner, output_folder  # noqa: E402, F401


def _columns(sw: FrequencySweep) -> dict[str, np.ndarray]:
    cols = {
        "temperature_c": sw.temperature_c,
        "frequency_hz": sw.frequency_hz,
        "magnitude_db": sw.magnitude_db,
        "phase_deg": sw.phase_deg,
    }
    if sw.magnitude_std_db is not None:
        cols["magnitude_std_db"] = sw.magnitude_std_db
        cols["phase_std_deg"] = sw.phase_std_deg
    return cols


def _from_columns(cols: Mapping[str, np.ndarray], header: Mapping[str, str], where: str) -> FrequencySweep:
    def unit_of(key):
        if key not in header:
            raise DataFormatError(f"{where}: missing header line '# {key}: <name> [<unit>]'")
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
    H = 10 ** (cols["magnitude_db"] / 20) * np.exp(1j * np.radians(cols["phase_deg"]))
    meta = {k: v for k, v in header.items() if k not in ("input", "output", "ipmc-sweep")}
    has_std = "magnitude_std_db" in cols
    return FrequencySweep(cols["temperature_c"], cols["frequency_hz"], H,
                          cols["magnitude_std_db"] if has_std else None,
                          cols["phase_std_deg"] if has_std else None,
                          in_name, in_unit, out_name, out_unit, meta)


def _header_lines(sw: FrequencySweep) -> list[str]:
    lines = [f"ipmc-sweep {FORMAT_VERSION}", f"input: {sw.input_name} [{sw.input_unit}]",
             f"output: {sw.output_name} [{sw.output_unit}]"]
    for k, v in sw.metadata.items():
        v = str(v).replace("\n", " ")
        lines.append(f"{k}: {v}")
    return lines


# ----------------------------------------------------------------------------------- CSV
def write_csv(sw: FrequencySweep, path) -> Path:
    """Write the tidy CSV (see module doc), atomically."""
    cols = _columns(sw)

    def write(fh):
        for line in _header_lines(sw):
            fh.write(f"# {line}\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(cols))
        for row in zip(*cols.values()):
            w.writerow([repr(float(v)) for v in row])

    return atomic_write(path, write)


def read_csv(path) -> FrequencySweep:
    """Read the tidy CSV; a malformed file raises :class:`DataFormatError` naming the line."""
    path = Path(path)
    text = read_text(path, "sweep file")
    header: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        body = lines[i].lstrip("#").strip()
        if body.startswith("ipmc-sweep"):
            header["ipmc-sweep"] = body.split(None, 1)[1] if len(body.split()) > 1 else ""
        elif ":" in body:
            k, v = body.split(":", 1)
            header[k.strip()] = v.strip()
        i += 1
    if i >= len(lines):
        raise DataFormatError(f"{path}: no column header line after the '#' header")
    colnames = [c.strip() for c in lines[i].split(",")]
    missing = [c for c in REQUIRED_COLUMNS if c not in colnames]
    if missing:
        raise DataFormatError(f"{path}:{i + 1}: missing column(s) {missing}; found {colnames}")
    unknown = [c for c in colnames if c not in REQUIRED_COLUMNS + OPTIONAL_COLUMNS]
    if unknown:
        raise DataFormatError(f"{path}:{i + 1}: unknown column(s) {unknown}; expected {list(REQUIRED_COLUMNS + OPTIONAL_COLUMNS)}")
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
def write_npz(sw: FrequencySweep, path) -> Path:
    cols = _columns(sw)
    header = json.dumps({"format": "ipmc-sweep", "version": FORMAT_VERSION,
                         "input": f"{sw.input_name} [{sw.input_unit}]",
                         "output": f"{sw.output_name} [{sw.output_unit}]", "metadata": sw.metadata})

    def write(fh):
        np.savez(fh, header=np.array(header), response_real=sw.response.real, response_imag=sw.response.imag, **cols)

    return atomic_write(path, write, "wb")


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
            raise DataFormatError(f"{where}: not an ipmc-sweep NPZ (no 'header' array)")
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


def write_mat(sw: FrequencySweep, path) -> Path:
    """MATLAB .mat (v5) with one column vector per field, the complex response and header strings."""
    from scipy.io import savemat

    cols = {k: v.reshape(-1, 1) for k, v in _columns(sw).items()}
    cols["response"] = sw.response.reshape(-1, 1)
    cols["input"] = f"{sw.input_name} [{sw.input_unit}]"
    cols["output"] = f"{sw.output_name} [{sw.output_unit}]"
    cols["format"] = f"ipmc-sweep {FORMAT_VERSION}"
    cols["metadata_json"] = json.dumps(sw.metadata)

    buf = io.BytesIO()
    savemat(buf, cols, do_compression=True)
    data = bytearray(buf.getvalue())
    # the 116-byte descriptive text of a v5 header carries the creation time; a fixed text makes
    # the file byte-reproducible like the CSV and NPZ (MATLAB ignores the text)
    data[:116] = MAT_HEADER_TEXT

    return atomic_write(path, lambda fh: fh.write(bytes(data)), "wb")


def _mat_text(data: dict, key: str, where: str) -> str:
    v = np.asarray(data[key])
    if v.dtype.kind != "U" or v.size != 1:
        raise DataFormatError(f"{where}: variable {key!r} must be a string, got {v.dtype} with shape {v.shape}")
    return str(v.reshape(-1)[0])


#: The descriptive text at the start of every .mat file written here (no timestamp).
MAT_HEADER_TEXT = f"MATLAB 5.0 MAT-file, written by ipmc (ipmc-sweep {FORMAT_VERSION})".encode("ascii").ljust(116)


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
        raise DataFormatError(f"{where}: missing variable(s) {missing}")
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


def by_extension(path, handlers: Mapping[str, Callable], what: str) -> Callable:
    """The handler for ``path``'s file extension, or a DataFormatError listing the accepted ones."""
    ext = Path(path).suffix.lower()
    if ext not in handlers:
        raise DataFormatError(f"{path}: unknown {what} file type {ext!r}; expected {', '.join(handlers)}")
    return handlers[ext]


def read_sweep(path) -> FrequencySweep:
    """Read a sweep by file extension (.csv, .npz, .mat)."""
    return by_extension(path, {".csv": read_csv, ".npz": read_npz, ".mat": read_mat}, "sweep")(path)


def write_sweep(sw: FrequencySweep, path) -> Path:
    """Write a sweep by file extension (.csv, .npz, .mat), atomically."""
    return by_extension(path, {".csv": write_csv, ".npz": write_npz, ".mat": write_mat}, "sweep")(sw, path)
