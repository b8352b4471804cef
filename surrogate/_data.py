"""Frequency-response data for the fitters: a thin layer over ``physmodel.data.sweep.FrequencySweep``.

The fitters accept a :class:`physmodel.data.sweep.FrequencySweep` directly.  :class:`FrequencyData`
exists for what a sweep does not cover: data without a temperature (a single unspecified one),
free-form unit labels, and the per-line log-domain standard deviations used by the weighting.
Its validation *is* the sweep's (lengths, finiteness, f > 0, H ≠ 0, strictly increasing
frequencies per temperature, both-or-neither standard deviations): ``__post_init__`` builds a
``FrequencySweep`` and keeps its arrays; the only check added here is that standard deviations
are > 0 (they become weights 1/σ).

Hz and °C at the edges; the fitters convert to ω = 2πf [rad/s] inside.  ``to_data`` also takes
python-control ``FrequencyResponseData`` objects and arrays (through
:func:`physmodel.data.interop.as_sweep`).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from physmodel.data.sweep import FrequencySweep
from physmodel.errors import IPMCError

__all__ = ["FrequencyData", "from_sweep", "to_data"]

_LN10_OVER_20 = np.log(10.0) / 20.0
_SWEEP_ATTRS = ("frequency_hz", "temperature_c", "response")


def _temperature_column(temperature_c, n: int) -> np.ndarray | None:
    """``None`` → ``None``; scalar → broadcast to ``n`` lines; array → float array. [°C]"""
    if temperature_c is None:
        return None
    try:
        t = np.asarray(temperature_c, dtype=float)
    except (TypeError, ValueError) as exc:
        raise IPMCError(f"temperature_c must be an array of real numbers or a scalar ({exc})") from None
    if t.ndim == 0:
        return np.full(n, float(t))
    if t.shape != (n,):
        raise IPMCError(f"temperature_c has shape {t.shape} but frequency_hz has {n} lines")
    return t


@dataclass(frozen=True)
class FrequencyData:
    """Validated frequency-response data in tidy (long) form.

    Parameters
    ----------
    frequency_hz : array, shape (N,)
        Excitation frequencies, > 0 and strictly increasing within each temperature. [Hz]
    temperature_c : array, shape (N,), float or None
        Temperature of each line; a scalar is broadcast; ``None`` means a single
        unspecified temperature. [°C]
    response : complex array, shape (N,)
        Complex frequency response, nonzero. [output_unit/input_unit]
    magnitude_std_db, phase_std_deg : array, shape (N,), optional (both or neither)
        Standard deviation of the measured magnitude [dB] and phase [deg] of each line, > 0.
    input_name, input_unit, output_name, output_unit : str
        Labels carried into saved models and reports (free-form).
    metadata : dict
        Provenance.
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
        n = int(np.size(self.frequency_hz))
        t = _temperature_column(self.temperature_c, n)
        # the sweep's checks, once; a missing temperature is one (arbitrary) temperature
        sweep = FrequencySweep(np.zeros(n) if t is None else t, self.frequency_hz, self.response,
                               self.magnitude_std_db, self.phase_std_deg)
        for name in ("magnitude_std_db", "phase_std_deg"):
            v = getattr(sweep, name)
            if v is not None and np.any(v <= 0):
                i = int(np.argmax(v <= 0))
                raise IPMCError(f"{name} must be > 0 (it becomes a weight 1/σ), got {float(v[i])!r} at index {i}")
        values = {"frequency_hz": sweep.frequency_hz, "response": sweep.response,
                  "temperature_c": None if t is None else sweep.temperature_c,
                  "magnitude_std_db": sweep.magnitude_std_db, "phase_std_deg": sweep.phase_std_deg}
        for name, v in values.items():
            if v is not None:
                v = v.copy()
                v.setflags(write=False)
            object.__setattr__(self, name, v)

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
        return self.magnitude_std_db is not None

    def temperatures(self) -> np.ndarray:
        """Sorted unique temperatures (empty if none were given). [°C]"""
        if self.temperature_c is None:
            return np.array([])
        return np.unique(self.temperature_c)

    def select(self, mask) -> FrequencyData:
        """Subset of the lines selected by a boolean mask or index array."""
        idx = np.arange(self.n)[mask]
        if idx.size == 0:
            raise IPMCError("selection is empty")

        def take(a):
            return None if a is None else a[idx]

        return FrequencyData(
            self.frequency_hz[idx], take(self.temperature_c), self.response[idx],
            take(self.magnitude_std_db), take(self.phase_std_deg),
            self.input_name, self.input_unit, self.output_name, self.output_unit,
            dict(self.metadata),
        )

    def at_temperature(self, temperature_c: float) -> FrequencyData:
        """The lines at one temperature (within 1e-9 °C)."""
        if self.temperature_c is None:
            raise IPMCError("these data carry no temperature")
        mask = np.isclose(self.temperature_c, temperature_c, rtol=0, atol=1e-9)
        if not mask.any():
            raise IPMCError(
                f"no data at temperature_c={temperature_c!r}; available: "
                f"{self.temperatures().tolist()}"
            )
        return self.select(mask)

    def fingerprint(self) -> str:
        """SHA-256 of the numerical content including the standard deviations (float64,
        little-endian; a missing column hashes as ``none``), as ``sha256:<hex>``."""
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
            raise IPMCError(
                "weighting='uncertainty' needs both magnitude_std_db and phase_std_deg"
            )
        return self.magnitude_std_db * _LN10_OVER_20, np.deg2rad(self.phase_std_deg)

    def labels(self) -> dict:
        return {
            "input_name": self.input_name, "input_unit": self.input_unit,
            "output_name": self.output_name, "output_unit": self.output_unit,
        }


def from_sweep(sweep) -> FrequencyData:
    """``FrequencyData`` of a ``physmodel.data.sweep.FrequencySweep`` (or any object with its
    attributes ``frequency_hz``, ``temperature_c``, ``response`` and, optionally,
    ``magnitude_std_db``, ``phase_std_deg``, ``input_name``, ``input_unit``, ``output_name``,
    ``output_unit``, ``metadata``)."""
    missing = [a for a in _SWEEP_ATTRS if not hasattr(sweep, a)]
    if missing:
        raise IPMCError(f"sweep object lacks attribute(s) {missing}; expected a physmodel FrequencySweep")
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


def to_data(data, temperature_c=None) -> FrequencyData:
    """What every fitter's ``fit_data`` accepts: a ``FrequencyData`` (returned as is), a
    ``FrequencySweep`` / sweep-like object (converted by :func:`from_sweep`), or anything
    :func:`physmodel.data.interop.as_sweep` reads — a ``control.FrequencyResponseData``, a mapping
    ``{temperature_c: FRD or (frequency_hz, response)}``, a list of FRDs with ``temperature_c``, or
    ``(frequency_hz, response)`` arrays.  An FRD or arrays without ``temperature_c`` are one
    unspecified temperature (enough for ``RationalFit``)."""
    if isinstance(data, FrequencyData):
        return data
    if isinstance(data, FrequencySweep) or all(hasattr(data, a) for a in _SWEEP_ATTRS):
        return from_sweep(data)
    from physmodel.data.interop import as_sweep, is_frd

    if temperature_c is None and (is_frd(data) or (isinstance(data, tuple | list) and len(data) == 2
                                                   and not is_frd(data[0]))):
        sw = as_sweep(data, 0.0)        # one unspecified temperature
        return FrequencyData(sw.frequency_hz, None, sw.response)
    if isinstance(data, dict | list | tuple) or is_frd(data):
        return from_sweep(as_sweep(data, temperature_c))
    raise IPMCError(f"expected FrequencyData or a physmodel FrequencySweep, got {type(data).__name__} "
                    "(also accepted: a control.FrequencyResponseData, a mapping {temperature_c: FRD} or "
                    "(frequency_hz, response) arrays)")
