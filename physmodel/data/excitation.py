"""Excitation design: multisines, stepped-sine plans and chirps, written as signal files a DAQ can play.

* :func:`multisine` — a periodic sum of cosines on chosen FFT lines of one period, with phases that
  keep the crest factor low: Schroeder's closed form (Schroeder 1970, IEEE Trans. Inf. Theory
  16:85, eq. 11: ``φ_k = −2π Σ_{l<k} (k − l) p_l`` with ``p_l`` the power share of line l) or
  iterative clipping started from it (van der Ouderaa, Schoukens & Renneboog 1988, IEEE Trans.
  Instrum. Meas. 37:207), or random phases (seeded) for comparison.  Estimate its FRF with
  :func:`~physmodel.estimation.frf.h1` using ``nperseg`` = one period, ``noverlap=0``,
  ``window='boxcar'``, ``discard_s`` = the transient periods and ``frequencies_hz`` = its lines.
* :func:`stepped_sine_plan` — frequencies, periods per step and settle time, each step starting on
  a sample at phase zero; the plan travels in the signal file's header so
  :func:`~physmodel.estimation.stepped.stepped_sine` can read the schedule back (``plan=``).
* :func:`chirp` — a (repeated) linear or logarithmic sweep.

The signal files are :class:`~physmodel.estimation.records.TimeRecord` files (``# ipmc-timeseries``
CSV/NPZ/MAT with ``time_s`` and ``<channel>_<unit>`` columns); the header carries the design and
``expected_duration_s``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from ..errors import IPMCError
from .timerecord import TimeRecord


def _fs(fs_hz) -> float:
    fs = float(fs_hz)
    if not (math.isfinite(fs) and fs > 0):
        raise IPMCError(f"fs_hz={fs_hz!r} must be a finite number > 0 [Hz]")
    return fs


def _whole(x, name: str, minimum: int = 0) -> int:
    if not (isinstance(x, (int, np.integer)) or (isinstance(x, float) and x.is_integer())) or x < minimum:
        raise IPMCError(f"{name}={x!r} must be a whole number >= {minimum}")
    return int(x)


def crest_factor(x) -> float:
    """Peak over RMS of samples ``x``."""
    x = np.asarray(x, dtype=float)
    return float(np.max(np.abs(x)) / np.sqrt(np.mean(x**2)))


# ----------------------------------------------------------------------------------- multisine
@dataclass(frozen=True)
class Multisine:
    """One period of ``u(t) = Σ_k A_k cos(2π f_k t + φ_k)`` on the FFT lines of ``n_samples`` samples.

    Attributes
    ----------
    fs_hz : float              sample rate. [Hz]
    n_samples : int            samples per period
    lines : (K,) int ndarray   FFT line of each component (frequency = line·fs/n_samples)
    amplitudes : (K,) ndarray  cosine amplitudes, in ``unit``
    phases_rad : (K,) ndarray  phases. [rad]
    phase_method : str         "schroeder", "clipped" or "random"
    channel, unit : str        name and unit of the signal (``voltage``, ``V``)
    """

    fs_hz: float
    n_samples: int
    lines: np.ndarray
    amplitudes: np.ndarray
    phases_rad: np.ndarray
    phase_method: str = "schroeder"
    channel: str = "voltage"
    unit: str = "V"

    @property
    def frequency_hz(self) -> np.ndarray:
        """Frequencies of the lines. [Hz]"""
        return self.lines * self.fs_hz / self.n_samples

    @property
    def period_s(self) -> float:
        return self.n_samples / self.fs_hz

    def period(self) -> np.ndarray:
        """Samples of one period (exact: an inverse real FFT of the line spectrum)."""
        X = np.zeros(self.n_samples // 2 + 1, dtype=complex)
        X[self.lines] = 0.5 * self.n_samples * self.amplitudes * np.exp(1j * self.phases_rad)
        return np.fft.irfft(X, self.n_samples)

    @property
    def crest_factor(self) -> float:
        """Peak/RMS of the sampled period (the waveform between samples may peak slightly higher)."""
        return crest_factor(self.period())

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.sum(self.amplitudes**2) / 2.0))

    def duration_s(self, periods: int, transient_periods: int = 1) -> float:
        """Expected measurement time for ``periods`` measured plus ``transient_periods`` discarded. [s]"""
        return (_whole(periods, "periods", 1) + _whole(transient_periods, "transient_periods")) * self.period_s

    def record(self, periods: int, transient_periods: int = 1) -> TimeRecord:
        """The signal to play: the period repeated ``transient_periods + periods`` times."""
        total = _whole(periods, "periods", 1) + _whole(transient_periods, "transient_periods")
        u = np.tile(self.period(), total)
        meta = {"excitation": "multisine", "multisine": json.dumps(self.to_dict()), "periods": periods,
                "transient_periods": transient_periods, "crest_factor": f"{self.crest_factor:.4f}",
                "expected_duration_s": f"{self.duration_s(periods, transient_periods):.6g}",
                "estimate_with": f"h1(nperseg={self.n_samples}, noverlap=0, window='boxcar', "
                                 f"discard_s={transient_periods * self.period_s:.6g}, frequencies_hz=lines)"}
        return TimeRecord(np.arange(u.size) / self.fs_hz, {self.channel: u}, {self.channel: self.unit}, meta)

    def to_dict(self) -> dict:
        return {"fs_hz": self.fs_hz, "n_samples": self.n_samples, "lines": self.lines.tolist(),
                "amplitudes": self.amplitudes.tolist(), "phases_rad": self.phases_rad.tolist(),
                "phase_method": self.phase_method, "channel": self.channel, "unit": self.unit}

    @classmethod
    def from_dict(cls, d: dict) -> Multisine:
        return cls(float(d["fs_hz"]), int(d["n_samples"]), np.asarray(d["lines"], dtype=int),
                   np.asarray(d["amplitudes"], dtype=float), np.asarray(d["phases_rad"], dtype=float),
                   d["phase_method"], d["channel"], d["unit"])


def schroeder_phases(amplitudes) -> np.ndarray:
    """Schroeder's low-crest-factor phases for components in order (Schroeder 1970, eq. 11). [rad]"""
    a = np.asarray(amplitudes, dtype=float)
    p = a**2 / np.sum(a**2)
    k = np.arange(1, a.size + 1)
    # φ_k = −2π Σ_{l<k} (k − l) p_l = −2π (k·P_{k−1} − Q_{k−1}) with cumulative sums P, Q of p, l·p
    P = np.concatenate([[0.0], np.cumsum(p)[:-1]])
    Q = np.concatenate([[0.0], np.cumsum(k * p)[:-1]])
    return np.mod(-2 * np.pi * (k * P - Q), 2 * np.pi)


def _clip_phases(ms: Multisine, iterations: int, clip: float) -> tuple[np.ndarray, float]:
    """Iterative clipping: clip the peaks, keep the phases of the lines, restore their amplitudes."""
    X = np.zeros(ms.n_samples // 2 + 1, dtype=complex)
    mag = 0.5 * ms.n_samples * ms.amplitudes
    phases, best_cf = ms.phases_rad, ms.crest_factor
    cur = phases
    for _ in range(iterations):
        X[:] = 0.0
        X[ms.lines] = mag * np.exp(1j * cur)
        x = np.fft.irfft(X, ms.n_samples)
        cf = crest_factor(x)
        if cf < best_cf:
            phases, best_cf = cur, cf
        lim = clip * np.max(np.abs(x))
        cur = np.angle(np.fft.rfft(np.clip(x, -lim, lim))[ms.lines])
    return np.mod(phases, 2 * np.pi), best_cf


def multisine(frequencies_hz, fs_hz: float, period_s: float, *, amplitude=1.0, rms: float | None = None,
              phases: str = "schroeder", iterations: int = 200, clip: float = 0.9, seed: int | None = None,
              channel: str = "voltage", unit: str = "V") -> Multisine:
    """Design a multisine.

    Parameters
    ----------
    frequencies_hz : (K,) array_like   lines, each a multiple of 1/period_s below fs/2. [Hz]
    fs_hz : float          sample rate of the DAQ. [Hz]
    period_s : float       period (frequency resolution 1/period_s); fs·period_s must be whole. [s]
    amplitude : float or (K,) array_like   cosine amplitude per line, in ``unit``
    rms : float or None    if given, scale the amplitudes to this RMS, in ``unit``
    phases : "schroeder" | "clipped" | "random"
    iterations, clip : iterative-clipping passes and the clip level (fraction of the peak)
    seed : int             required for random phases
    """
    fs = _fs(fs_hz)
    if not (math.isfinite(period_s) and period_s > 0):
        raise IPMCError(f"period_s={period_s!r} must be a finite number > 0 [s]")
    N = int(round(period_s * fs))
    if abs(N - period_s * fs) > 1e-6 * max(N, 1) or N < 4:
        raise IPMCError(f"period_s={period_s!r} s at fs_hz={fs:g} is {period_s * fs:g} samples; "
                        "a period must be a whole number (>= 4) of samples")
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)):
        raise IPMCError(f"frequencies_hz must be a non-empty 1-D array of finite values, got {frequencies_hz!r}")
    k = np.rint(f * period_s).astype(int)
    off = (np.abs(f * period_s - k) > 1e-6) | (k < 1) | (2 * k >= N)
    if off.any():
        raise IPMCError(f"frequencies_hz: {f[off][:5].tolist()} Hz are not lines of a {period_s:g} s period "
                        f"(multiples of {1 / period_s:g} Hz, above 0 and below fs/2 = {fs / 2:g} Hz)")
    if np.any(np.diff(k) <= 0):
        raise IPMCError("frequencies_hz must strictly increase (one component per line)")
    a = np.broadcast_to(np.asarray(amplitude, dtype=float), k.shape).copy() if np.ndim(amplitude) <= 1 else None
    if a is None or a.shape != k.shape or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise IPMCError(f"amplitude must be one finite value > 0 or one per line ({k.size}), got {amplitude!r}")
    if rms is not None:
        if not (math.isfinite(rms) and rms > 0):
            raise IPMCError(f"rms={rms!r} must be a finite number > 0")
        a *= rms / np.sqrt(np.sum(a**2) / 2.0)
    if phases not in ("schroeder", "clipped", "random"):
        raise IPMCError(f"phases={phases!r}; expected 'schroeder', 'clipped' or 'random'")
    if phases == "random":
        if seed is None:
            raise IPMCError("seed: random phases need an explicit integer seed (reproducibility)")
        ph = np.random.default_rng(seed).uniform(0, 2 * np.pi, k.size)
    else:
        ph = schroeder_phases(a)
    ms = Multisine(fs, N, k, a, ph, "schroeder" if phases != "random" else "random", channel, unit)
    if phases == "clipped":
        if not 0 < clip < 1:
            raise IPMCError(f"clip={clip!r} must lie in (0, 1)")
        ph, _ = _clip_phases(ms, _whole(iterations, "iterations", 1), clip)
        ms = Multisine(fs, N, k, a, ph, "clipped", channel, unit)
    return ms


# ----------------------------------------------------------------------------------- stepped sine
@dataclass(frozen=True)
class SteppedSinePlan:
    """A stepped-sine schedule: step i plays ``amplitude[i]·sin(2π f_i (t − start_i))`` from
    ``step_start_s[i]`` to ``step_stop_s[i]``, settles for ``settle_s[i]`` and is measured over
    ``periods[i]`` whole periods.  Times [s] from the first sample; frequencies [Hz]."""

    fs_hz: float
    frequency_hz: np.ndarray
    amplitude: np.ndarray
    settle_s: np.ndarray
    periods: np.ndarray
    step_start_s: np.ndarray
    step_stop_s: np.ndarray
    channel: str = "voltage"
    unit: str = "V"

    @property
    def duration_s(self) -> float:
        """Expected measurement time. [s]"""
        return float(self.step_stop_s[-1])

    @property
    def n_samples(self) -> int:
        return int(round(self.step_stop_s[-1] * self.fs_hz))

    def signal(self) -> np.ndarray:
        """The drive samples (vectorised over the whole schedule)."""
        t = np.arange(self.n_samples) / self.fs_hz
        i = np.clip(np.searchsorted(self.step_start_s, t + 0.5 / self.fs_hz, side="right") - 1, 0, None)
        return self.amplitude[i] * np.sin(2 * np.pi * self.frequency_hz[i] * (t - self.step_start_s[i]))

    def record(self) -> TimeRecord:
        u = self.signal()
        meta = {"excitation": "stepped_sine", "stepped_sine_plan": json.dumps(self.to_dict()),
                "steps": self.frequency_hz.size, "expected_duration_s": f"{self.duration_s:.6g}"}
        return TimeRecord(np.arange(u.size) / self.fs_hz, {self.channel: u}, {self.channel: self.unit}, meta)

    def to_dict(self) -> dict:
        return {"fs_hz": self.fs_hz, **{k: getattr(self, k).tolist() for k in
                ("frequency_hz", "amplitude", "settle_s", "periods", "step_start_s", "step_stop_s")},
                "channel": self.channel, "unit": self.unit}

    @classmethod
    def from_dict(cls, d: dict) -> SteppedSinePlan:
        arr = {k: np.asarray(d[k], dtype=float) for k in
               ("frequency_hz", "amplitude", "settle_s", "periods", "step_start_s", "step_stop_s")}
        arr["periods"] = arr["periods"].astype(int)
        return cls(float(d["fs_hz"]), channel=d["channel"], unit=d["unit"], **arr)

    @classmethod
    def from_record(cls, record: TimeRecord) -> SteppedSinePlan:
        """The plan stored in a signal file's header (written by :meth:`record`)."""
        if "stepped_sine_plan" not in record.metadata:
            raise IPMCError("record: no 'stepped_sine_plan' header line; it was not written by a SteppedSinePlan")
        try:
            return cls.from_dict(json.loads(record.metadata["stepped_sine_plan"]))
        except (ValueError, KeyError, TypeError) as exc:
            raise IPMCError(f"record: malformed 'stepped_sine_plan' header ({exc})") from None


def stepped_sine_plan(frequencies_hz, fs_hz: float, *, amplitude=1.0, periods=10, min_measure_s: float = 0.0,
                      settle_s: float = 0.0, settle_periods: float = 0.0, channel: str = "voltage",
                      unit: str = "V") -> SteppedSinePlan:
    """Plan a stepped sine.

    Parameters
    ----------
    frequencies_hz : (n,) array_like    step frequencies, distinct, in playing order, ≤ fs/4. [Hz]
    fs_hz : float                       sample rate. [Hz]
    amplitude : float or (n,)           sine amplitude per step, in ``unit``
    periods : int or (n,) int           whole periods measured per step (at least 2)
    min_measure_s : float               raise the periods of fast steps to measure at least this long. [s]
    settle_s, settle_periods : float    transient allowed per step: the longer of the two; choose
        several of the plant's slowest time constants (:func:`settle_time_s`). [s], [periods]
    """
    fs = _fs(fs_hz)
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(f > fs / 4):
        raise IPMCError(f"frequencies_hz must be finite values in (0, fs/4 = {fs / 4:g}] Hz, got {frequencies_hz!r}")
    if np.unique(f).size != f.size:
        raise IPMCError("frequencies_hz: give each frequency once")
    P = np.broadcast_to(np.asarray(periods), f.shape)
    if not np.all(P == np.round(P)) or np.any(P < 2):
        raise IPMCError(f"periods={periods!r} must be whole numbers >= 2 (σ comes from the scatter between periods)")
    for name, v in (("min_measure_s", min_measure_s), ("settle_s", settle_s), ("settle_periods", settle_periods)):
        if not (math.isfinite(v) and v >= 0):
            raise IPMCError(f"{name}={v!r} must be a finite number >= 0")
    P = np.maximum(P.astype(int), np.ceil(min_measure_s * f - 1e-9).astype(int))
    a = np.broadcast_to(np.asarray(amplitude, dtype=float), f.shape).copy()
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise IPMCError(f"amplitude must be finite and > 0, got {amplitude!r}")
    settle = np.maximum(settle_s, settle_periods / f)
    n_step = np.ceil((settle + P / f) * fs - 1e-9).astype(np.int64)      # whole samples, covering the periods
    edges = np.concatenate([[0], np.cumsum(n_step)]) / fs
    return SteppedSinePlan(fs, f, a, settle, P, edges[:-1], edges[1:], channel, unit)


def settle_time_s(poles, tolerance: float = 1e-3) -> float:
    """Time for the slowest mode (poles [1/s], or a python-control system) to decay to ``tolerance``
    of its start: ln(1/tolerance)/min|Re p|. [s]"""
    p = np.atleast_1d(poles.poles() if hasattr(poles, "poles") else np.asarray(poles, dtype=complex))
    if p.size == 0 or np.any(p.real >= 0):
        raise IPMCError(f"poles must be stable (Re < 0); got {p[p.real >= 0][:5].tolist() if p.size else 'none'}")
    if not 0 < tolerance < 1:
        raise IPMCError(f"tolerance={tolerance!r} must lie in (0, 1)")
    return float(math.log(1.0 / tolerance) / np.min(-p.real))


# ----------------------------------------------------------------------------------- chirp
def chirp(f0_hz: float, f1_hz: float, sweep_s: float, fs_hz: float, *, amplitude: float = 1.0,
          method: str = "logarithmic", repeats: int = 1, channel: str = "voltage", unit: str = "V") -> TimeRecord:
    """A swept sine from ``f0_hz`` to ``f1_hz`` over ``sweep_s`` [s], played ``repeats`` times.

    With repeats > 1 the sweep is periodic: estimate with ``h1(nperseg = sweep samples,
    noverlap=0, window='boxcar', discard_s = one sweep)``.
    """
    fs = _fs(fs_hz)
    if not (0 < f0_hz < f1_hz <= fs / 2):
        raise IPMCError(f"need 0 < f0_hz < f1_hz <= fs/2 = {fs / 2:g} Hz; got f0_hz={f0_hz!r}, f1_hz={f1_hz!r}")
    n = int(round(sweep_s * fs)) if math.isfinite(sweep_s) else 0
    if n < 4:
        raise IPMCError(f"sweep_s={sweep_s!r} s must hold at least 4 samples at {fs:g} Hz")
    if method not in ("linear", "logarithmic"):
        raise IPMCError(f"method={method!r}; expected 'linear' or 'logarithmic'")
    reps = _whole(repeats, "repeats", 1)
    tt = np.arange(n) / fs
    one = amplitude * signal.chirp(tt, f0_hz, n / fs, f1_hz, method=method, phi=-90)
    u = np.tile(one, reps)
    meta = {"excitation": f"{method} chirp", "f0_hz": f0_hz, "f1_hz": f1_hz, "sweep_s": n / fs, "repeats": reps,
            "expected_duration_s": f"{u.size / fs:.6g}"}
    return TimeRecord(np.arange(u.size) / fs, {channel: u}, {channel: unit}, meta)
