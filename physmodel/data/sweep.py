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
import io
import json
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DataFormatError, IPMCError
from .fileio import atomic_write, by_extension
from .units import QUANTITY_UNITS, UNITS, unit_scale

FORMAT_VERSION = 1
REQUIRED_COLUMNS = ("temperature_c", "frequency_hz", "magnitude_db", "phase_deg")
OPTIONAL_COLUMNS = ("magnitude_std_db", "phase_std_deg")
#: Most lines (frequencies × temperatures) in one sweep: checked before anything is allocated, so
#: a typo such as ``points = 100000000`` is a clear error, not a process killed for memory.
MAX_SWEEP_LINES = 5_000_000

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
        if np.any(T <= -273.15):
            raise IPMCError(f"temperature_c must be above absolute zero (-273.15 °C); got {T[T <= -273.15][:5].tolist()}")
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

    def select(self, temperature_c: float) -> FrequencySweep:
        """The lines at one temperature (exact match)."""
        mask = self.temperature_c == float(temperature_c)
        if not np.any(mask):
            raise IPMCError(f"no lines at {temperature_c!r} °C; the sweep has {self.temperatures().tolist()}")
        return self._subset(mask)

    def _subset(self, mask) -> FrequencySweep:
        return replace(
            self, temperature_c=self.temperature_c[mask], frequency_hz=self.frequency_hz[mask],
            response=self.response[mask],
            magnitude_std_db=None if self.magnitude_std_db is None else self.magnitude_std_db[mask],
            phase_std_deg=None if self.phase_std_deg is None else self.phase_std_deg[mask],
        )

    def exclude(self, temperatures_c: Sequence[float]) -> FrequencySweep:
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

    def in_units(self, input_unit: str, output_unit: str) -> FrequencySweep:
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
def synthesize_sweep(model, quantity: str, frequency_hz, temperature_c, noise=None, seed: int | None = None,
                     set_index: int = 0, progress=None) -> FrequencySweep:
    """A synthetic sweep of ``model`` (ActuatorModel / SensorModel) with seeded noise.

    ``noise``: None (exact), :class:`MagnitudePhaseNoise` or :class:`ComplexGaussianNoise`.
    The sweep carries the noise's per-line standard deviations.  Units: mm/V for actuation,
    µA/mm for sensing, Ω for impedance.
    """
    kind = getattr(model, "kind", None)
    if kind not in ("actuator", "sensor"):
        raise IPMCError(f"model kind {kind!r}: synthesize_sweep needs a physics model (kind 'actuator' or 'sensor')")
    key = (kind, quantity)
    if key not in QUANTITY_UNITS:
        raise IPMCError(f"{kind} quantity {quantity!r} cannot be swept; expected one of "
                        f"{[q for k, q in QUANTITY_UNITS if k == kind]}")
    if noise is not None and seed is None:
        raise IPMCError("a noisy sweep needs an explicit integer seed (reproducibility)")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise IPMCError(f"seed must be a non-negative integer, got {seed!r}")
    n_lines = int(np.size(frequency_hz)) * int(np.size(temperature_c))
    if n_lines > MAX_SWEEP_LINES:
        raise IPMCError(f"{np.size(frequency_hz)} frequencies × {np.size(temperature_c)} temperatures = {n_lines} "
                        f"lines; a sweep holds at most {MAX_SWEEP_LINES} (split it)")
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


# ----------------------------------------------------------------------------------- layout
@dataclass(frozen=True)
class SweepLayout:
    """How a model response maps onto the rows of a sweep: evaluate at ``temperatures_c`` ×
    ``frequencies_hz`` (unique, sorted), take ``[..., t_index, f_index]`` and multiply by ``factor``
    (SI response → the sweep's display units)."""

    quantity: str
    factor: float
    frequencies_hz: np.ndarray
    f_index: np.ndarray
    temperatures_c: np.ndarray
    t_index: np.ndarray


def sweep_layout(data: FrequencySweep, kind: str, quantity: str | None = None) -> SweepLayout:
    """Check that ``data`` can hold the ``kind`` model's ``quantity`` (default M / S) and lay it out."""
    if kind not in ("actuator", "sensor"):
        raise IPMCError(f"kind={kind!r}; expected 'actuator' or 'sensor'")
    q = quantity or ("M" if kind == "actuator" else "S")
    if (kind, q) not in QUANTITY_UNITS:
        raise IPMCError(f"{kind} quantity {q!r} cannot be compared with data; expected one of "
                        f"{[k[1] for k in QUANTITY_UNITS if k[0] == kind]}")
    _, unit_in, _, unit_out = QUANTITY_UNITS[(kind, q)]
    want_in, want_out = UNITS[unit_in][0], UNITS[unit_out][0]
    got_in, got_out = UNITS[data.input_unit][0], UNITS[data.output_unit][0]
    if (got_in, got_out) != (want_in, want_out):
        hint = ""
        if "dimensionless" in (got_in, got_out) and "dimensionless" not in (want_in, want_out):
            hint = (f"; the data carry no units (an FRD or an estimate from bare arrays): state them with "
                    f"input_unit={unit_in!r}, output_unit={unit_out!r} (calibrate(..., input_unit=, output_unit=) or "
                    f"as_sweep(..., input_unit=, output_unit=)), or units={{'input': ..., 'output': ...}} of read_sweep")
        raise DataFormatError(f"the sweep is {data.output_name} [{data.output_unit}] per {data.input_name} "
                              f"[{data.input_unit}] ({got_out}/{got_in}); {kind} quantity {q} needs "
                              f"{want_out}/{want_in} (see physmodel.sweep.QUANTITY_UNITS {QUANTITY_UNITS[(kind, q)]})"
                              + hint)
    factor = unit_scale(data.input_unit) / unit_scale(data.output_unit)   # SI response -> sweep units
    fu, inv_f = np.unique(data.frequency_hz, return_inverse=True)
    Tu, inv_T = np.unique(data.temperature_c, return_inverse=True)
    return SweepLayout(q, factor, fu, inv_f, Tu, inv_T)


def merge_sweeps(data: FrequencySweep | Sequence[FrequencySweep]) -> FrequencySweep:
    """One sweep from several (distinct temperatures), in the units of the first."""
    if isinstance(data, FrequencySweep):
        return data
    sweeps = list(data)
    if not sweeps or not all(isinstance(s, FrequencySweep) for s in sweeps):
        raise IPMCError("data must be a FrequencySweep or a non-empty sequence of them")
    first = sweeps[0]
    conv = [s.in_units(first.input_unit, first.output_unit) for s in sweeps]
    seen: set = set()
    for s in conv:
        common = seen & set(s.temperatures().tolist())
        if common:
            raise IPMCError(f"several sweeps hold lines at {sorted(common)} °C; merge them into one sweep first")
        seen |= set(s.temperatures().tolist())
    std = all(s.magnitude_std_db is not None for s in conv)
    if not std and any(s.magnitude_std_db is not None for s in conv):
        raise IPMCError("some sweeps carry per-line standard deviations and others do not; give all or none")
    cat = lambda k: np.concatenate([getattr(s, k) for s in conv])  # noqa: E731
    return FrequencySweep(cat("temperature_c"), cat("frequency_hz"), cat("response"),
                          cat("magnitude_std_db") if std else None, cat("phase_std_deg") if std else None,
                          first.input_name, first.input_unit, first.output_name, first.output_unit,
                          dict(first.metadata))


# ----------------------------------------------------------------------------------- writing
def _file_columns(sw: FrequencySweep) -> dict[str, Any]:
    cols: dict[str, Any] = {
        "temperature_c": sw.temperature_c,
        "frequency_hz": sw.frequency_hz,
        "magnitude_db": sw.magnitude_db,
        "phase_deg": sw.phase_deg,
    }
    if sw.magnitude_std_db is not None:
        cols["magnitude_std_db"] = sw.magnitude_std_db
        cols["phase_std_deg"] = sw.phase_std_deg
    return cols


def _header_lines(sw: FrequencySweep) -> list[str]:
    lines = [f"ipmc-sweep {FORMAT_VERSION}", f"input: {sw.input_name} [{sw.input_unit}]",
             f"output: {sw.output_name} [{sw.output_unit}]"]
    for k, v in sw.metadata.items():
        v = str(v).replace("\n", " ")
        lines.append(f"{k}: {v}")
    return lines


def write_csv(sw: FrequencySweep, path) -> Path:
    """Write the tidy CSV (see module doc), atomically."""
    cols = _file_columns(sw)

    def write(fh):
        for line in _header_lines(sw):
            fh.write(f"# {line}\n")
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(cols))
        for row in zip(*cols.values()):
            w.writerow([repr(float(v)) for v in row])

    return atomic_write(path, write)


def write_npz(sw: FrequencySweep, path) -> Path:
    cols = _file_columns(sw)
    header = json.dumps({"format": "ipmc-sweep", "version": FORMAT_VERSION,
                         "input": f"{sw.input_name} [{sw.input_unit}]",
                         "output": f"{sw.output_name} [{sw.output_unit}]", "metadata": sw.metadata})

    def write(fh):
        np.savez(fh, header=np.array(header), response_real=sw.response.real, response_imag=sw.response.imag, **cols)

    return atomic_write(path, write, "wb")


#: The descriptive text at the start of every .mat file written here (no timestamp).
MAT_HEADER_TEXT = f"MATLAB 5.0 MAT-file, written by ipmc (ipmc-sweep {FORMAT_VERSION})".encode("ascii").ljust(116)


def write_mat(sw: FrequencySweep, path) -> Path:
    """MATLAB .mat (v5) with one column vector per field, the complex response and header strings."""
    from scipy.io import savemat

    cols: dict[str, Any] = {k: v.reshape(-1, 1) for k, v in _file_columns(sw).items()}
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


def write_sweep(sw: FrequencySweep, path) -> Path:
    """Write a sweep by file extension (.csv, .npz, .mat), atomically."""
    return by_extension(path, {".csv": write_csv, ".npz": write_npz, ".mat": write_mat}, "sweep")(sw, path)
