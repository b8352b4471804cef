"""Frequency sweeps: synthetic (seeded, with a documented noise model) or measured, and their files.

A :class:`FrequencySweep` is tidy (long) data: one row per (temperature, frequency) line, with a
complex response in ``output_unit / input_unit`` and, optionally, a per-line standard deviation of
the log-magnitude [dB] and of the phase [deg].  Temperatures need not share a frequency grid.

Noise models (both seeded through ``numpy.random.default_rng(seed)``):

* :class:`MagnitudePhaseNoise` — independent Gaussian errors on each line's log-magnitude
  (σ in dB) and phase (σ in degrees), the way swept-sine analysers report their uncertainty.
* :class:`ComplexGaussianNoise` — circular complex Gaussian error of standard deviation σ per line,
  relative to |H| (``relative=True``) or absolute in the sweep's units.  For small σ the
  log-magnitude and phase errors each have variance σ²/(2|H|²) (discrepancy.md §1), which is the
  per-line uncertainty the sweep carries.

Files
-----
CSV (the project's exchange format)::

    # ipmc-sweep 1
    # input: voltage [V]
    # output: tip_displacement [mm]
    # any other '# key: value' lines are kept as metadata
    temperature_c,frequency_hz,magnitude_db,phase_deg[,magnitude_std_db,phase_std_deg]

Rows are grouped by temperature; inside a group frequencies strictly increase.  NPZ and MATLAB
.mat files hold the same columns as arrays plus the header fields.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from .errors import DataFormatError, IPMCError

FORMAT_VERSION = 1
REQUIRED_COLUMNS = ("temperature_c", "frequency_hz", "magnitude_db", "phase_deg")
OPTIONAL_COLUMNS = ("magnitude_std_db", "phase_std_deg")

#: Units the files may use, as multiples of the SI unit of their kind.
UNITS: dict[str, tuple[str, float]] = {
    "V": ("voltage", 1.0), "mV": ("voltage", 1e-3), "uV": ("voltage", 1e-6), "µV": ("voltage", 1e-6),
    "m": ("length", 1.0), "mm": ("length", 1e-3), "um": ("length", 1e-6), "µm": ("length", 1e-6),
    "A": ("current", 1.0), "mA": ("current", 1e-3), "uA": ("current", 1e-6), "µA": ("current", 1e-6),
    "nA": ("current", 1e-9),
    "Ohm": ("impedance", 1.0), "ohm": ("impedance", 1.0), "Ω": ("impedance", 1.0), "kOhm": ("impedance", 1e3),
    "N": ("force", 1.0), "mN": ("force", 1e-3),
    "1": ("dimensionless", 1.0),
}


def unit_scale(unit: str) -> float:
    """Size of ``unit`` in SI (``'mm'`` → 1e-3)."""
    if unit not in UNITS:
        raise DataFormatError(f"unknown unit {unit!r}; expected one of {sorted(UNITS)}")
    return UNITS[unit][1]


# ----------------------------------------------------------------------------------- noise
@dataclass(frozen=True)
class MagnitudePhaseNoise:
    """Gaussian noise on log-magnitude (``sigma_db`` [dB]) and phase (``sigma_deg`` [deg]) per line."""

    sigma_db: float = 0.1
    sigma_deg: float = 1.0

    def __post_init__(self):
        for k in ("sigma_db", "sigma_deg"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v >= 0):
                raise IPMCError(f"{k}={v!r} must be a finite number >= 0")

    def std(self, H):
        shape = np.shape(H)
        return np.full(shape, float(self.sigma_db)), np.full(shape, float(self.sigma_deg))

    def apply(self, H, rng):
        H = np.asarray(H, dtype=complex)
        dm = rng.standard_normal(H.shape) * self.sigma_db
        dp = rng.standard_normal(H.shape) * self.sigma_deg
        return H * 10 ** (dm / 20) * np.exp(1j * np.radians(dp))

    def describe(self) -> str:
        return f"magnitude/phase Gaussian: sigma_db={self.sigma_db:g}, sigma_deg={self.sigma_deg:g}"


@dataclass(frozen=True)
class ComplexGaussianNoise:
    """Circular complex Gaussian noise, std ``sigma`` per line (relative to |H| when ``relative``)."""

    sigma: float = 0.01
    relative: bool = True

    def __post_init__(self):
        if not (np.isfinite(self.sigma) and self.sigma >= 0):
            raise IPMCError(f"sigma={self.sigma!r} must be a finite number >= 0")

    def _abs_sigma(self, H):
        H = np.asarray(H, dtype=complex)
        return self.sigma * np.abs(H) if self.relative else np.full(H.shape, float(self.sigma))

    def std(self, H):
        rel = self._abs_sigma(H) / (np.sqrt(2.0) * np.abs(H))
        return 20 / np.log(10) * rel, np.degrees(rel)

    def apply(self, H, rng):
        H = np.asarray(H, dtype=complex)
        sig = self._abs_sigma(H) / np.sqrt(2.0)
        return H + sig * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))

    def describe(self) -> str:
        return f"complex Gaussian: sigma={self.sigma:g} ({'relative' if self.relative else 'absolute'})"


# ----------------------------------------------------------------------------------- sweep
@dataclass(frozen=True)
class FrequencySweep:
    """Frequency-response data in tidy form (one row per line).

    Attributes
    ----------
    temperature_c : (N,) ndarray     bath temperature of each line [°C]
    frequency_hz : (N,) ndarray      frequency of each line [Hz]
    response : (N,) complex ndarray  output/input in ``output_unit``/``input_unit``
    magnitude_std_db, phase_std_deg : (N,) ndarray or None   per-line standard deviations
    input_name, input_unit, output_name, output_unit : str
    metadata : dict                  provenance (model, parameter set, noise, seed, ...)
    """

    temperature_c: np.ndarray
    frequency_hz: np.ndarray
    response: np.ndarray
    magnitude_std_db: np.ndarray | None = None
    phase_std_deg: np.ndarray | None = None
    input_name: str = "input"
    input_unit: str = "1"
    output_name: str = "output"
    output_unit: str = "1"
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        T = np.asarray(self.temperature_c, dtype=float).reshape(-1)
        f = np.asarray(self.frequency_hz, dtype=float).reshape(-1)
        H = np.asarray(self.response, dtype=complex).reshape(-1)
        if not (T.size == f.size == H.size):
            raise IPMCError(f"temperature_c, frequency_hz and response must have one value per line; "
                            f"got {T.size}, {f.size}, {H.size}")
        if T.size == 0:
            raise IPMCError("a sweep needs at least one line")
        for name, arr in (("temperature_c", T), ("frequency_hz", f)):
            if not np.all(np.isfinite(arr)):
                raise IPMCError(f"{name} contains NaN or inf at rows {np.flatnonzero(~np.isfinite(arr))[:5].tolist()}")
        if not np.all(np.isfinite(H)):
            raise IPMCError(f"response contains NaN or inf at rows {np.flatnonzero(~np.isfinite(H))[:5].tolist()}")
        if np.any(f <= 0):
            raise IPMCError(f"frequencies must be > 0 Hz; got {f[f <= 0][:5].tolist()}")
        if np.any(H == 0):
            raise IPMCError(f"response is exactly 0 at rows {np.flatnonzero(H == 0)[:5].tolist()}; magnitude in dB undefined")
        object.__setattr__(self, "temperature_c", T)
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "response", H)
        for name in OPTIONAL_COLUMNS:
            v = getattr(self, name)
            if v is not None:
                v = np.asarray(v, dtype=float).reshape(-1)
                if v.size != T.size:
                    raise IPMCError(f"{name} has {v.size} values for {T.size} lines")
                if not np.all(np.isfinite(v)) or np.any(v < 0):
                    raise IPMCError(f"{name} must be finite and >= 0")
                object.__setattr__(self, name, v)
        if (self.magnitude_std_db is None) != (self.phase_std_deg is None):
            raise IPMCError("give both magnitude_std_db and phase_std_deg, or neither")
        unit_scale(self.input_unit)
        unit_scale(self.output_unit)
        for t in self.temperatures():
            ff = f[T == t]
            bad = np.flatnonzero(np.diff(ff) <= 0)
            if bad.size:
                raise IPMCError(f"frequencies at {t:g} °C must strictly increase; "
                                f"{ff[bad[0]]:g} Hz is followed by {ff[bad[0] + 1]:g} Hz")

    # -------------------------------------------------------------- views
    def temperatures(self) -> np.ndarray:
        """Sorted unique temperatures [°C]."""
        return np.unique(self.temperature_c)

    def select(self, temperature_c: float) -> "FrequencySweep":
        """The lines at one temperature (exact match)."""
        mask = self.temperature_c == float(temperature_c)
        if not np.any(mask):
            raise IPMCError(f"no lines at {temperature_c!r} °C; the sweep has {self.temperatures().tolist()}")
        return self._subset(mask)

    def _subset(self, mask) -> "FrequencySweep":
        return replace(
            self, temperature_c=self.temperature_c[mask], frequency_hz=self.frequency_hz[mask],
            response=self.response[mask],
            magnitude_std_db=None if self.magnitude_std_db is None else self.magnitude_std_db[mask],
            phase_std_deg=None if self.phase_std_deg is None else self.phase_std_deg[mask],
        )

    def exclude(self, temperatures_c: Sequence[float]) -> "FrequencySweep":
        """All lines except those at the given temperatures (e.g. held-out validation temperatures)."""
        return self._subset(~np.isin(self.temperature_c, np.asarray(temperatures_c, dtype=float)))

    @property
    def omega(self) -> np.ndarray:
        return 2 * np.pi * self.frequency_hz

    @property
    def magnitude_db(self) -> np.ndarray:
        return 20 * np.log10(np.abs(self.response))

    @property
    def phase_deg(self) -> np.ndarray:
        """Phase [deg], unwrapped along frequency within each temperature."""
        out = np.empty(self.response.size)
        for t in self.temperatures():
            idx = np.flatnonzero(self.temperature_c == t)
            out[idx] = np.degrees(np.unwrap(np.angle(self.response[idx])))
        return out

    def grid(self):
        """``(frequency_hz (n_f,), temperature_c (n_T,), response (n_T, n_f))`` if every
        temperature has the same frequencies; otherwise an error naming the first that differs."""
        temps = self.temperatures()
        f0 = self.frequency_hz[self.temperature_c == temps[0]]
        H = np.empty((temps.size, f0.size), dtype=complex)
        for i, t in enumerate(temps):
            m = self.temperature_c == t
            if m.sum() != f0.size or not np.array_equal(self.frequency_hz[m], f0):
                raise IPMCError(f"the frequency grid at {t:g} °C differs from the one at {temps[0]:g} °C")
            H[i] = self.response[m]
        return f0, temps, H

    def to_frd(self, temperature_c: float):
        """A ``control.FrequencyResponseData`` at one temperature (ω in rad/s)."""
        import control

        sub = self.select(temperature_c)
        return control.frd(sub.response, sub.omega)

    def fingerprint(self) -> str:
        """SHA-256 of the numerical content (for provenance of fitted models)."""
        h = hashlib.sha256()
        for arr in (self.temperature_c, self.frequency_hz, self.response.real, self.response.imag):
            h.update(np.ascontiguousarray(arr, dtype=float).tobytes())
        return h.hexdigest()

    def in_units(self, input_unit: str, output_unit: str) -> "FrequencySweep":
        """The same sweep with the response expressed in other units."""
        k = (unit_scale(self.output_unit) / unit_scale(output_unit)) / (unit_scale(self.input_unit) / unit_scale(input_unit))
        if UNITS[input_unit][0] != UNITS[self.input_unit][0] or UNITS[output_unit][0] != UNITS[self.output_unit][0]:
            raise IPMCError(f"cannot convert {self.output_unit}/{self.input_unit} to {output_unit}/{input_unit}")
        return replace(self, response=self.response * k, input_unit=input_unit, output_unit=output_unit)

    # -------------------------------------------------------------- files
    def to_csv(self, path) -> Path:
        return write_csv(self, path)

    def to_npz(self, path) -> Path:
        return write_npz(self, path)

    def to_mat(self, path) -> Path:
        return write_mat(self, path)


# ----------------------------------------------------------------------------------- synthesis
#: Display units per physical quantity of the models: (input name, unit, output name, unit, SI scale).
QUANTITY_UNITS = {
    ("actuator", "M"): ("voltage", "V", "tip_displacement", "mm"),
    ("actuator", "H"): ("voltage", "V", "tip_displacement", "mm"),
    ("actuator", "G"): ("quasi_static_displacement", "1", "tip_displacement", "1"),
    ("actuator", "Z"): ("current", "A", "voltage", "V"),
    ("actuator", "I"): ("voltage", "V", "current", "A"),
    ("sensor", "S"): ("tip_displacement", "mm", "current", "uA"),
    ("sensor", "Z"): ("current", "A", "voltage", "V"),
}


def synthesize_sweep(model, quantity: str, frequency_hz, temperature_c, noise=None, seed: int | None = None,
                     set_index: int = 0, progress=None) -> FrequencySweep:
    """A synthetic sweep of ``model`` (ActuatorModel / SensorModel) with seeded noise.

    ``noise``: None (exact), :class:`MagnitudePhaseNoise` or :class:`ComplexGaussianNoise`.
    The sweep carries the noise's per-line standard deviations.  Units: mm/V for actuation,
    µA/mm for sensing, Ω for impedance.
    """
    from .actuator import ActuatorModel

    kind = "actuator" if isinstance(model, ActuatorModel) else "sensor"
    key = (kind, quantity)
    if key not in QUANTITY_UNITS:
        raise IPMCError(f"{kind} quantity {quantity!r} cannot be swept; expected one of "
                        f"{[q for k, q in QUANTITY_UNITS if k == kind]}")
    if noise is not None and seed is None:
        raise IPMCError("a noisy sweep needs an explicit integer seed (reproducibility)")
    in_name, in_unit, out_name, out_unit = QUANTITY_UNITS[key]
    resp = model.frequency_response(frequency_hz, temperature_c, quantities=(quantity,), progress=progress)
    H = resp[quantity][set_index] * (unit_scale(in_unit) / unit_scale(out_unit))     # (n_T, n_f)
    f = np.broadcast_to(resp.frequency_hz, H.shape).ravel()
    T = np.broadcast_to(resp.temperature_c[:, None], H.shape).ravel()
    H = H.ravel()
    meta = {
        "source": "physmodel synthetic sweep",
        "model": type(model).__name__ + (f" (kernel={model.kernel})" if hasattr(model, "kernel") else ""),
        "quantity": quantity,
        "description": resp.descriptions[quantity],
        "parameter_set": model.params[set_index].name,
        "parameter_source": model.params[set_index].source,
    }
    mstd = pstd = None
    if noise is not None:
        rng = np.random.default_rng(seed)
        mstd, pstd = noise.std(H)
        H = noise.apply(H, rng)
        meta["noise"] = noise.describe()
        meta["seed"] = str(seed)
    return FrequencySweep(T, f, H, mstd, pstd, in_name, in_unit, out_name, out_unit, meta)


# ----------------------------------------------------------------------------------- I/O helpers
def atomic_write(path, write_fn, mode: str = "w") -> Path:
    """Write via a temporary file in the same folder, then rename: never a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, mode, **({"newline": "", "encoding": "utf-8"} if "b" not in mode else {})) as fh:
            write_fn(fh)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


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
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DataFormatError(f"{path}: no such file") from None
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


def read_npz(path) -> FrequencySweep:
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise DataFormatError(f"{path}: no such file") from None
    if "header" not in data:
        raise DataFormatError(f"{path}: not an ipmc-sweep NPZ (no 'header')")
    hdr = json.loads(str(data["header"]))
    missing = [c for c in REQUIRED_COLUMNS if c not in data]
    if missing:
        raise DataFormatError(f"{path}: missing array(s) {missing}")
    cols = {k: np.asarray(data[k], dtype=float) for k in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if k in data}
    header = {"input": hdr["input"], "output": hdr["output"], **{k: str(v) for k, v in hdr.get("metadata", {}).items()}}
    sw = _from_columns(cols, header, str(path))
    if "response_real" in data:   # exact complex values, not rounded through dB/deg
        sw = replace(sw, response=data["response_real"] + 1j * data["response_imag"])
    return sw


def write_mat(sw: FrequencySweep, path) -> Path:
    """MATLAB .mat (v5) with one column vector per field, the complex response and header strings."""
    from scipy.io import savemat

    cols = {k: v.reshape(-1, 1) for k, v in _columns(sw).items()}
    cols["response"] = sw.response.reshape(-1, 1)
    cols["input"] = f"{sw.input_name} [{sw.input_unit}]"
    cols["output"] = f"{sw.output_name} [{sw.output_unit}]"
    cols["format"] = f"ipmc-sweep {FORMAT_VERSION}"
    cols["metadata_json"] = json.dumps(sw.metadata)

    def write(fh):
        savemat(fh, cols, do_compression=True)

    return atomic_write(path, write, "wb")


def read_mat(path) -> FrequencySweep:
    from scipy.io import loadmat

    try:
        data = loadmat(path)
    except FileNotFoundError:
        raise DataFormatError(f"{path}: no such file") from None
    missing = [c for c in REQUIRED_COLUMNS if c not in data]
    if missing:
        raise DataFormatError(f"{path}: missing variable(s) {missing}")
    cols = {k: np.asarray(data[k], dtype=float).reshape(-1) for k in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if k in data}
    meta = json.loads(str(data["metadata_json"][0])) if "metadata_json" in data else {}
    header = {"input": str(data["input"][0]), "output": str(data["output"][0]), **{k: str(v) for k, v in meta.items()}}
    sw = _from_columns(cols, header, str(path))
    if "response" in data:
        sw = replace(sw, response=np.asarray(data["response"], dtype=complex).reshape(-1))
    return sw


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
