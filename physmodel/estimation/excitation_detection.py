"""What excitation a record's input channel carries: periodic (its period and excited lines), a
stepped sine (its steps), or random — read from the samples alone.

Periodic
    The normalised autocorrelation ``ρ(L) = Σ x_i x_{i+L} / √(Σ x_i² Σ x_{i+L}²)`` (over the overlap,
    mean removed) is computed by FFT over lags up to half the record.  After its main lobe (the
    first lag with ρ < 0.5), the first lag reaching 0.9 of the largest ρ (and at least 0.5) is
    taken up to its local maximum: the period N in samples (an integer: the generator and the
    converter share a clock).  It is accepted only if the periods agree: over the later half of the
    whole periods (at least 2), the period-to-period scatter ``s² = Σ_p |x_p − x̄|²/(P − 1)`` must be
    at most :data:`MAX_PERIOD_SCATTER` of the power per period (random excitation gives about 1,
    a periodic input with input noise at SNR ρ gives 1/(1 + SNR)).
Excited lines
    Bins k of the N-sample DFT whose period-mean power ``|Ū_k|²`` exceeds :data:`LINE_SNR` times
    the noise power of that mean (``s_k²/P``, a running median over 33 bins of the period scatter)
    and :data:`LINE_FLOOR` times the strongest line (numerical or quantisation residue of a
    noise-free input).  DC and the Nyquist bin are never lines.
Stepped sine
    Upward zero crossings (with hysteresis above the noise, see :func:`upward_crossings`; times
    interpolated between samples) give the periods of the signal.  Runs of at least :data:`MIN_STEP_PERIODS`
    consecutive intervals that agree within 0.2 samples plus 0.5 % (or six robust standard
    deviations of the relative change between consecutive intervals, when the noise is larger), covering at least 70 % of the
    record, each explained at least half by one sine (:func:`sine_fraction`), are the steps:
    frequency ``count/(t_last − t_first)``, start at the run's first crossing,
    stop at its last (whatever lies between steps is not used).
Random
    Anything else with a non-constant input.

Only the last :data:`DETECT_SAMPLES` samples are searched for a period (a longer period cannot be
checked anyway by a record of that length).  Not detected: a periodic input whose period is not a
whole number of samples (a generator on its own clock) — it is treated as random.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import fft as sp_fft
from scipy.ndimage import median_filter

from ..errors import IPMCError

#: Samples (the last ones) searched for a period.
DETECT_SAMPLES = 1 << 22
#: Largest period-to-period scatter, as a fraction of the power per period, of a periodic input.
MAX_PERIOD_SCATTER = 0.2
#: An excited line's period-mean power over the noise power of that mean.
LINE_SNR = 100.0
#: An excited line's power relative to the strongest line (−60 dB).
LINE_FLOOR = 1e-6
#: Whole periods a stepped-sine step needs to be recognised.
MIN_STEP_PERIODS = 3
_STEP_TOL = 0.005
_STEP_COVERAGE = 0.7


@dataclass(frozen=True)
class Excitation:
    """The excitation found on an input channel.

    Attributes
    ----------
    kind : str                 "periodic", "stepped_sine" or "random"
    fs_hz : float              sample rate. [Hz]
    period_samples : int or None     samples per period (periodic)
    lines : (K,) int ndarray   excited DFT bins of one period (periodic; frequency = k·fs/N)
    step_frequency_hz, step_start_s, step_stop_s : (S,) ndarrays   the steps (stepped sine), times
        from sample 0. [Hz], [s]
    evidence : dict            the numbers behind the decision (autocorrelation, period scatter, ...)
    """

    kind: str
    fs_hz: float
    period_samples: int | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    step_frequency_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_start_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    step_stop_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    evidence: dict = field(default_factory=dict)

    @property
    def frequency_hz(self) -> np.ndarray:
        """Excited lines (periodic) or step frequencies (stepped sine). [Hz]"""
        if self.kind == "periodic" and self.period_samples:
            return self.lines * self.fs_hz / self.period_samples
        return self.step_frequency_hz

    def describe(self) -> str:
        """One line: what was detected and on what evidence."""
        ev = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in self.evidence.items())
        if self.kind == "periodic" and self.period_samples:
            f = self.frequency_hz
            return (f"periodic input: period {self.period_samples} samples ({self.period_samples / self.fs_hz:.6g} s), "
                    f"{self.lines.size} excited lines {f.min():.4g}-{f.max():.4g} Hz ({ev})")
        if self.kind == "stepped_sine":
            f = self.step_frequency_hz
            return f"stepped sine: {f.size} steps {f.min():.4g}-{f.max():.4g} Hz ({ev})"
        return f"random (no period, no steps found: {ev})"


# ----------------------------------------------------------------------------------- periodic
def autocorrelation(x: np.ndarray, max_lag: int) -> np.ndarray:
    """Normalised autocorrelation ρ(L), L = 0..max_lag, over the overlap of ``x`` (mean removed).

    Parameters
    ----------
    x : (n,) ndarray
        Samples.
    max_lag : int
        Largest lag. [samples]
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    n = x.size
    m = sp_fft.next_fast_len(2 * n, real=True)
    X = sp_fft.rfft(x, m)
    r = sp_fft.irfft(X.real**2 + X.imag**2, m)[:max_lag + 1]
    c = np.concatenate([[0.0], np.cumsum(x**2)])
    lags = np.arange(max_lag + 1)
    e0 = c[n - lags]                         # Σ_{i < n−L} x_i²
    e1 = c[n] - c[lags]                      # Σ_{i ≥ L} x_i²
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = r / np.sqrt(e0 * e1)
    return np.where(np.isfinite(rho), rho, 0.0)


def period_scatter(periods: np.ndarray) -> float:
    """Period-to-period scatter over the power per period of ``periods`` (P, N): about 1 for
    random samples, the noise fraction for a periodic signal with noise.

    Parameters
    ----------
    periods : (P, N) ndarray
        P ≥ 2 consecutive periods of N samples.
    """
    P = periods.shape[0]
    dev = periods - periods.mean(axis=0)
    s2 = np.sum(dev**2) / (P - 1)
    power = np.sum((periods - periods.mean())**2) / P
    return float(s2 / power) if power > 0 else float("inf")


def find_period(x: np.ndarray) -> tuple[int | None, dict]:
    """(period in samples or None, evidence) of samples ``x`` (see the module doc).

    Parameters
    ----------
    x : (n,) ndarray
        Samples of the input channel.
    """
    n = x.size
    if n < 8:
        return None, {"samples": n}
    rho = autocorrelation(x, n // 2)
    below = np.flatnonzero(rho[1:] < 0.5)
    if below.size == 0:
        return None, {"autocorrelation": "no lag below 0.5"}
    L0 = int(below[0]) + 1
    tail = rho[L0:]
    if tail.size == 0:
        return None, {"autocorrelation": "no lag after the main lobe"}
    top = float(tail.max())
    if top < 0.5:
        return None, {"autocorrelation max": round(top, 3)}
    L = L0 + int(np.flatnonzero(tail >= 0.9 * top)[0])
    while L + 1 <= n // 2 and rho[L + 1] > rho[L]:
        L += 1
    P = n // L
    blocks = x[n - P * L:].reshape(P, L)
    late = blocks[P // 2:] if P >= 4 else blocks
    q = period_scatter(late)
    ev = {"autocorrelation": round(float(rho[L]), 4), "period scatter": round(q, 4), "periods": P}
    return (L if q <= MAX_PERIOD_SCATTER else None), ev


def excited_lines(periods: np.ndarray) -> np.ndarray:
    """Excited DFT bins of the (P, N) ``periods`` of an input (see the module doc).

    Parameters
    ----------
    periods : (P, N) ndarray
        P ≥ 2 whole periods of the input.
    """
    P, N = periods.shape
    U = sp_fft.rfft(periods, axis=1)
    Um = U.mean(axis=0)
    s2 = np.sum(np.abs(U - Um)**2, axis=0) / (P - 1)
    power = np.abs(Um)**2
    floor = median_filter(s2, size=33, mode="nearest") / P
    k = np.arange(power.size)
    inner = (k > 0) & (k < N / 2)
    strongest = power[inner].max() if inner.any() else 0.0
    return np.flatnonzero(inner & (power > LINE_SNR * floor) & (power > LINE_FLOOR * strongest))


# ----------------------------------------------------------------------------------- stepped sine
def upward_crossings(x: np.ndarray) -> np.ndarray:
    """Times [samples, interpolated] where ``x`` (mean removed) crosses zero upwards after having
    been below −h: hysteresis against noise, h = 10 % of the 99th-percentile amplitude or five
    times the white-noise level read from second differences, at most half the amplitude.

    Parameters
    ----------
    x : (n,) ndarray
        Samples.
    """
    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    a = float(np.percentile(np.abs(x), 99))
    # white-noise level from second differences (a smooth signal has almost none there)
    noise = 1.4826 * float(np.median(np.abs(np.diff(x, 2)))) / np.sqrt(6.0) if x.size > 2 else 0.0
    h = min(max(0.1 * a, 5.0 * noise), 0.5 * a)
    if h <= 0:
        return np.zeros(0)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0)) + 1
    if up.size == 0:
        return np.zeros(0)
    low = np.where(x < -h, np.arange(x.size), -1)
    last_low = np.maximum.accumulate(low)[up]
    prev = np.concatenate([[-1], up[:-1]])
    c = up[(last_low > prev) & (last_low >= 0)]
    return (c - 1) + (-x[c - 1]) / (x[c] - x[c - 1])


def sine_fraction(x: np.ndarray, f_per_sample: float) -> float:
    """Fraction of the variance of ``x`` explained by one sine of ``f_per_sample`` cycles per sample
    (least squares with cos, sin and an offset).

    Parameters
    ----------
    x : (n,) ndarray
        Samples.
    f_per_sample : float
        Frequency over the sample rate.
    """
    if x.size < 4 or np.var(x) == 0:
        return 0.0
    w = 2 * np.pi * f_per_sample * np.arange(x.size)
    A = np.stack([np.cos(w), np.sin(w), np.ones(x.size)], axis=1)
    coef, *_ = np.linalg.lstsq(A, x, rcond=None)
    return float(1.0 - np.var(x - A @ coef) / np.var(x))


def find_steps(x: np.ndarray, fs: float) -> tuple[tuple | None, dict]:
    """((frequency [Hz], start [s], stop [s]) arrays of the steps, or None; evidence) for samples
    ``x`` at ``fs`` [Hz] (see the module doc).

    Parameters
    ----------
    x : (n,) ndarray
        Samples of the input channel.
    fs : float
        Sample rate. [Hz]
    """
    tc = upward_crossings(x)
    if tc.size < MIN_STEP_PERIODS + 1:
        return None, {"upward crossings": int(tc.size)}
    T = np.diff(tc)
    # crossing-time jitter is relative (noise over the slope 2πfA): one robust scale for the record
    d = np.abs(np.diff(T)) / T[:-1]
    rel = max(_STEP_TOL, 6 * 1.4826 * float(np.median(d))) if d.size else _STEP_TOL
    tol = rel * T + 0.2
    brk = np.flatnonzero(np.abs(np.diff(T)) > np.minimum(tol[1:], tol[:-1])) + 1
    runs = np.split(np.arange(T.size), brk)
    steps = []
    for r in runs:
        if r.size < MIN_STEP_PERIODS:
            continue
        Tr = T[r]
        if Tr.max() - Tr.min() > 2 * (rel * Tr.mean() + 0.2):      # drifting: a chirp, not a step
            continue
        a, b = tc[r[0]], tc[r[-1] + 1]
        f = r.size * fs / (b - a)
        if sine_fraction(x[int(np.ceil(a)):int(b)], f / fs) >= 0.5:
            steps.append((f, a / fs, b / fs))
    covered = sum(s[2] - s[1] for s in steps) * fs / x.size
    ev = {"steps": len(steps), "coverage": round(covered, 3)}
    if not steps or covered < _STEP_COVERAGE:
        return None, ev
    f, a, b = (np.array(v) for v in zip(*steps))
    return (f, a, b), ev


# ----------------------------------------------------------------------------------- front door
def detect_excitation(t_or_fs, u, *, fs_hz: float | None = None) -> Excitation:
    """Periodic, stepped sine or random: what the input samples ``u`` carry (see the module doc).

    Parameters
    ----------
    t_or_fs : float or (n,) array_like
        Sample rate [Hz] or uniform sample times [s] (ignored when ``fs_hz`` is given).
    u : (n,) array_like
        Input samples.
    fs_hz : float or None
        Sample rate, when already known. [Hz]
    """
    from ..data.timerecord import sample_rate

    x = np.asarray(u, dtype=float)
    if x.ndim != 1:
        raise IPMCError(f"u must be 1-D samples, got shape {x.shape}")
    fs = float(fs_hz) if fs_hz is not None else sample_rate(t_or_fs, x.size)
    if x.size and np.ptp(x) == 0:
        raise IPMCError("the input channel is constant: it excites nothing")
    tail = x[-DETECT_SAMPLES:]
    N, ev = find_period(tail)
    if N is not None:
        P = tail.size // N
        blocks = tail[tail.size - P * N:].reshape(P, N)
        lines = excited_lines(blocks[P // 2:] if P >= 4 else blocks)
        if lines.size:
            return Excitation("periodic", fs, N, lines, evidence=ev)
        ev["lines"] = 0
    st, ev2 = find_steps(x, fs)
    ev.update(ev2)
    if st is not None:
        return Excitation("stepped_sine", fs, step_frequency_hz=st[0], step_start_s=st[1], step_stop_s=st[2],
                          evidence=ev2)
    return Excitation("random", fs, evidence=ev)
