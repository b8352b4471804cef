"""Frequency-response data: validation, weighting, fingerprint, duck-typed sweep adapter.

Hz and °C at the edges; the fitters convert to ω = 2πf [rad/s] inside.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

__all__ = ["FrequencyData", "from_sweep"]

_LN10_OVER_20 = np.log(10.0) / 20.0


def _as_1d_float(name: str, values, n: int | None = None) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of real numbers ({exc})") from None
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(
            f"{name} has length {arr.shape[0]} but frequency_hz has length {n}"
        )
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{name} contains a non-finite value ({float(arr[i])!r}) at index {i}")
    return arr


@dataclass(frozen=True)
class FrequencyData:
    """Validated frequency-response data in tidy (long) form.

    Parameters
    ----------
    frequency_hz : array, shape (N,)
        Excitation frequencies, strictly positive. [Hz]
    temperature_c : array, shape (N,), float or None
        Temperature of each line; a scalar is broadcast; ``None`` means a single
        unspecified temperature. [°C]
    response : complex array, shape (N,)
        Complex frequency response, nonzero. [output_unit/input_unit]
    magnitude_std_db : array, shape (N,), optional
        Standard deviation of the measured magnitude of each line. [dB]
    phase_std_deg : array, shape (N,), optional
        Standard deviation of the measured phase of each line. [deg]
    input_name, input_unit, output_name, output_unit : str
        Labels carried into saved models and reports.
    """

    frequency_hz: np.ndarray
    temperature_c: np.ndarray | None
    response: np.ndarray
    magnitude_std_db: np.ndarray | None = None
    phase_std_deg: np.ndarray | None = None
    input_name: str = "input"
    input_unit: str = ""
    output_name: str = "output"
    output_unit: str = ""
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        f = _as_1d_float("frequency_hz", self.frequency_hz)
        n = f.shape[0]
        if n == 0:
            raise ValueError("frequency_hz is empty: at least one frequency line is needed")
        if (f <= 0).any():
            i = int(np.argmax(f <= 0))
            raise ValueError(f"frequency_hz must be > 0, got {float(f[i])!r} at index {i}")
        try:
            h = np.asarray(self.response, dtype=complex)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"response must be an array of complex numbers ({exc})") from None
        if h.ndim != 1:
            raise ValueError(f"response must be one-dimensional, got shape {h.shape}")
        if h.shape[0] != n:
            raise ValueError(
                f"response has length {h.shape[0]} but frequency_hz has length {n}"
            )
        bad = ~np.isfinite(h)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(
                f"response contains a non-finite value ({complex(h[i])!r}) at index {i} "
                f"(frequency_hz={float(f[i])!r})"
            )
        if (h == 0).any():
            i = int(np.argmax(h == 0))
            raise ValueError(
                f"response is exactly zero at index {i} (frequency_hz={float(f[i])!r}); "
                "log-magnitude and relative weighting need a nonzero response"
            )
        t = self.temperature_c
        if t is not None:
            t = _as_1d_float("temperature_c", [t] * n if np.ndim(t) == 0 else t, n)
        stds = {}
        for name in ("magnitude_std_db", "phase_std_deg"):
            v = getattr(self, name)
            if v is not None:
                v = _as_1d_float(name, v, n)
                if (v <= 0).any():
                    i = int(np.argmax(v <= 0))
                    raise ValueError(f"{name} must be > 0, got {float(v[i])!r} at index {i}")
            stds[name] = v
        f.setflags(write=False)
        h.setflags(write=False)
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "response", h)
        object.__setattr__(self, "temperature_c", t)
        for name, v in stds.items():
            if v is not None:
                v.setflags(write=False)
            object.__setattr__(self, name, v)
        if t is not None:
            t.setflags(write=False)

    # ------------------------------------------------------------------ views
    @property
    def n(self) -> int:
        return int(self.frequency_hz.shape[0])

    @property
    def omega(self) -> np.ndarray:
        """Angular frequency ω = 2πf. [rad/s]"""
        return 2.0 * np.pi * self.frequency_hz

    @property
    def has_uncertainty(self) -> bool:
        return self.magnitude_std_db is not None and self.phase_std_deg is not None

    def temperatures(self) -> np.ndarray:
        """Sorted unique temperatures (empty if none were given). [°C]"""
        if self.temperature_c is None:
            return np.array([])
        return np.unique(self.temperature_c)

    def select(self, mask) -> "FrequencyData":
        """Subset of the lines selected by a boolean mask or index array."""
        idx = np.arange(self.n)[mask]
        if idx.size == 0:
            raise ValueError("selection is empty")

        def take(a):
            return None if a is None else a[idx]

        return FrequencyData(
            self.frequency_hz[idx], take(self.temperature_c), self.response[idx],
            take(self.magnitude_std_db), take(self.phase_std_deg),
            self.input_name, self.input_unit, self.output_name, self.output_unit,
            dict(self.metadata),
        )

    def at_temperature(self, temperature_c: float) -> "FrequencyData":
        if self.temperature_c is None:
            raise ValueError("these data carry no temperature")
        mask = np.isclose(self.temperature_c, temperature_c, rtol=0, atol=1e-9)
        if not mask.any():
            raise ValueError(
                f"no data at temperature_c={temperature_c!r}; available: "
                f"{self.temperatures().tolist()}"
            )
        return self.select(mask)

    def fingerprint(self) -> str:
        """SHA-256 of the numerical content (float64, little-endian), as ``sha256:<hex>``."""
        hsh = hashlib.sha256()
        parts = [
            ("f", self.frequency_hz),
            ("t", self.temperature_c),
            ("re", self.response.real),
            ("im", self.response.imag),
            ("smag", self.magnitude_std_db),
            ("sph", self.phase_std_deg),
        ]
        for tag, arr in parts:
            hsh.update(tag.encode())
            if arr is None:
                hsh.update(b"none")
            else:
                hsh.update(np.ascontiguousarray(arr, dtype="<f8").tobytes())
        return "sha256:" + hsh.hexdigest()

    def log_std(self) -> tuple[np.ndarray, np.ndarray]:
        """Standard deviations of ln|H| [Np] and arg H [rad] per line."""
        if not self.has_uncertainty:
            raise ValueError(
                "weighting='uncertainty' needs both magnitude_std_db and phase_std_deg"
            )
        return self.magnitude_std_db * _LN10_OVER_20, np.deg2rad(self.phase_std_deg)

    def labels(self) -> dict:
        return {
            "input_name": self.input_name, "input_unit": self.input_unit,
            "output_name": self.output_name, "output_unit": self.output_unit,
        }


def from_sweep(sweep) -> FrequencyData:
    """Adapter for a ``physmodel.sweep.FrequencySweep`` (duck-typed, no import).

    Uses only the attributes ``temperature_c``, ``frequency_hz``, ``response``,
    ``magnitude_std_db``, ``phase_std_deg``, ``input_name``, ``input_unit``,
    ``output_name``, ``output_unit`` and ``metadata``.
    """
    missing = [a for a in ("frequency_hz", "temperature_c", "response") if not hasattr(sweep, a)]
    if missing:
        raise ValueError(f"sweep object lacks attribute(s) {missing}")
    return FrequencyData(
        frequency_hz=sweep.frequency_hz,
        temperature_c=sweep.temperature_c,
        response=sweep.response,
        magnitude_std_db=getattr(sweep, "magnitude_std_db", None),
        phase_std_deg=getattr(sweep, "phase_std_deg", None),
        input_name=str(getattr(sweep, "input_name", "input")),
        input_unit=str(getattr(sweep, "input_unit", "")),
        output_name=str(getattr(sweep, "output_name", "output")),
        output_unit=str(getattr(sweep, "output_unit", "")),
        metadata=dict(getattr(sweep, "metadata", {}) or {}),
    )
