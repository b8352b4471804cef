"""Frequency responses with per-line uncertainty, estimated from time records.

Estimators
----------
:func:`h1`, :func:`h2`
    Welch-averaged spectra for random, multisine or swept excitation: segments of ``nperseg``
    samples (window, overlap, per-segment mean removal as :func:`scipy.signal.csd`), read in blocks
    so a memory-mapped record of any length is processed in bounded memory.  With
    ``S_uu = Σ|U|²``, ``S_yy = Σ|Y|²`` and ``S_uy = Σ conj(U)·Y`` over the segments,
    ``H1 = S_uy/S_uu`` (unbiased for noise on the output), ``H2 = S_yy/conj(S_uy)`` (unbiased for
    noise on the input) and the coherence ``γ² = |S_uy|²/(S_uu S_yy)``.
:func:`physmodel.estimation.stepped.stepped_sine`
    One sinusoid per step: the transient of each step (``settle_s`` or ``settle_periods``) is
    discarded, then every whole period of the rest is fitted by a three-parameter sine fit
    (IEEE 1057: cos, sin and offset by least squares), which stays exact when a period is not an
    integer number of samples.  The estimate is the ratio of the period-mean phasors; a partial
    period at the end of a step is not used.

Per-line uncertainty (σ of ln|H| in nepers and of the phase in radians, reported in dB and degrees
via ×20/ln 10 and ×180/π):

* Welch (Bendat & Piersol, *Random Data*, 4th ed., §9.2.3, eqs 9.73 and 9.90):
  ``σ_ln² = σ_φ² = (1 − γ²)/(2 ν γ²)`` with the sample coherence γ² and ``ν = n_eff − 1`` degrees
  of freedom; ``n_eff`` is the number of segments corrected for overlap (Welch 1967:
  ``K / (1 + 2 Σ_j (1 − j/K) ρ_j²)``, ρ_j the window's overlap correlation at a shift of j segments).
  For H1 with output noise this is the conditional variance given the input spectra, estimated from
  the residual ``S_yy(1 − γ²)``; for H2 it is the mirror case (input noise).  A line with γ² = 0 has
  infinite σ.
* Stepped sine: the scatter of the per-period phasors, ``δ ln H_k = (Y_k − H U_k)/Ȳ``; its real
  and imaginary parts give σ_ln and σ_φ (sample variance with P − 1 degrees of freedom, divided by P).

Both σ are estimates with few degrees of freedom when averages are few, so ±2σ covers the truth a
little less than 95 % of the time (Student t with ν degrees of freedom).  When the input repeats
exactly in every segment (a multisine estimated over whole periods, P segments), the line's complex
noise gives σ̂ two real degrees of freedom per period, ν = 2(P − 1)
(``tests/scenarios/test_virtual_lab.py`` measures mean t² = 1.19 for P = 8, t₁₄: 1.17).  Both are first-order
(small-error) results: as a standard deviation the Welch σ holds down to γ² ≈ 0.02, but once σ of
the magnitude exceeds about 1 dB the error of ln|H| = ln|1 + ε| is visibly skewed (a long tail
where |1 + ε| → 0), so its ±2σ interval covers less; :meth:`FRFEstimate.to_sweep` can drop such
lines (``max_std_db``).  Leakage (resolution) bias is not in σ: choose ``nperseg`` so the bin width
is well below the half-power bandwidth of the sharpest resonance (the bias falls as Δf for a
rectangular window, Δf² for Hann).  ``tests/benchmarks/bench_frf.py`` measures the coverage.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import fft as sp_fft
from scipy import signal

from ..data.sweep import FrequencySweep
from ..data.timerecord import sample_rate
from ..errors import IPMCError

NEPER_TO_DB = 20.0 / math.log(10.0)
BLOCK_SAMPLES = 1 << 20


# ----------------------------------------------------------------------------------- inputs
def _as_signal(x, name: str, n: int | None = None):
    if np.ndim(x) != 1:
        raise IPMCError(f"{name} must be 1-D samples, got shape {np.shape(x)}")
    if n is not None and len(x) != n:
        raise IPMCError(f"{name} has {len(x)} samples; the input has {n}")
    return x


def _as_outputs(y, n: int) -> list:
    """Output channels as a list of 1-D sample arrays (views, not copies)."""
    if isinstance(y, (list, tuple)):
        outs = list(y)
    elif np.ndim(y) == 1:
        outs = [y]
    elif np.ndim(y) == 2:
        outs = [y[i] for i in range(np.shape(y)[0])]
    else:
        raise IPMCError(f"y must be (n,) or (channels, n) samples, got shape {np.shape(y)}")
    if not outs:
        raise IPMCError("y: no output channels")
    return [_as_signal(v, f"y[{i}]", n) for i, v in enumerate(outs)]


def _names(names, units, k: int, default: str):
    names = tuple(names) if names is not None else ((default,) if k == 1 else tuple(f"{default}{i}" for i in range(k)))
    units = tuple(units) if units is not None else ("1",) * k
    if len(names) != k or len(units) != k:
        raise IPMCError(f"output_names/output_units: {len(names)} names and {len(units)} units for {k} output channels")
    return names, units


def _finite_block(x, name: str, offset: int) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(x)):
        bad = np.flatnonzero(~np.isfinite(x))[:5] + offset
        raise IPMCError(f"{name} contains NaN or inf at samples {bad.tolist()}")
    return x


# ----------------------------------------------------------------------------------- result
@dataclass(frozen=True)
class FRFEstimate:
    """Estimated frequency response of one input to one or more output channels.

    Attributes
    ----------
    frequency_hz : (n_f,) ndarray          lines, increasing. [Hz]
    response : (n_out, n_f) complex ndarray   output/input in ``output_units[i]/input_unit``
    magnitude_std_db : (n_out, n_f) ndarray   σ of 20·log10|H|. [dB]
    phase_std_deg : (n_out, n_f) ndarray      σ of the phase. [deg]
    coherence : (n_out, n_f) ndarray or None  ordinary coherence γ² (Welch estimators only)
    n_averages : (n_f,) ndarray            segments (Welch) or whole periods (stepped sine) per line
    method : str                           "h1", "h2" or "stepped_sine"
    input_name, input_unit : str
    output_names, output_units : tuple of str
    settings : dict                        estimator settings (fs, nperseg, window, settle, ...)
    """

    frequency_hz: np.ndarray
    response: np.ndarray
    magnitude_std_db: np.ndarray
    phase_std_deg: np.ndarray
    coherence: np.ndarray | None
    n_averages: np.ndarray
    method: str
    input_name: str = "input"
    input_unit: str = "1"
    output_names: tuple = ("output",)
    output_units: tuple = ("1",)
    settings: dict = field(default_factory=dict)

    def index(self, output: str | int | None) -> int:
        """Row of an output channel (by name or index; None = the only one)."""
        if output is None:
            if len(self.output_names) != 1:
                raise IPMCError(f"output: the estimate has channels {list(self.output_names)}; name one")
            return 0
        if isinstance(output, (int, np.integer)) and 0 <= output < len(self.output_names):
            return int(output)
        if output in self.output_names:
            return self.output_names.index(output)
        raise IPMCError(f"output {output!r} is not a channel of the estimate; expected one of {list(self.output_names)}")

    def channel(self, output: str | int | None) -> FRFEstimate:
        """The estimate for one output channel."""
        i = self.index(output)
        return replace(self, response=self.response[i:i + 1], magnitude_std_db=self.magnitude_std_db[i:i + 1],
                       phase_std_deg=self.phase_std_deg[i:i + 1],
                       coherence=None if self.coherence is None else self.coherence[i:i + 1],
                       output_names=(self.output_names[i],), output_units=(self.output_units[i],))

    def reciprocal(self, output: str | int | None = None) -> FRFEstimate:
        """input/output of one channel (e.g. impedance V/I from the admittance I/V estimated with the
        voltage as reference).  σ of ln|H| and of the phase are unchanged by inversion."""
        c = self.channel(output)
        return replace(c, response=1.0 / c.response, input_name=c.output_names[0], input_unit=c.output_units[0],
                       output_names=(c.input_name,), output_units=(c.input_unit,),
                       settings={**c.settings, "reciprocal": True})

    def to_sweep(self, temperature_c: float, output: str | int | None = None, *, min_coherence: float | None = None,
                 band_hz: tuple | None = None, max_std_db: float | None = None, quantity: str | None = None,
                 metadata: dict | None = None) -> FrequencySweep:
        """A :class:`~physmodel.sweep.FrequencySweep` of one channel at ``temperature_c`` [°C].

        ``min_coherence``, ``band_hz`` [Hz] and ``max_std_db`` [dB] drop lines (e.g. the unexcited
        bins of a multisine, or lines whose log-magnitude error is too large to be Gaussian: beyond
        about 1 dB the ±2σ interval of 20·log10|H| covers less than 95 %, see the module doc); a kept
        line without a finite response and σ is an error naming its frequency.
        """
        if not math.isfinite(float(temperature_c)):
            raise IPMCError(f"temperature_c={temperature_c!r} must be a finite number [°C]")
        i = self.index(output)
        f = self.frequency_hz
        keep = np.ones(f.size, dtype=bool)
        if band_hz is not None:
            lo, hi = (float(v) for v in band_hz)
            if not lo <= hi:
                raise IPMCError(f"band_hz={band_hz!r} must be (low, high) with low <= high [Hz]")
            keep &= (f >= lo) & (f <= hi)
        if min_coherence is not None:
            if self.coherence is None:
                raise IPMCError(f"min_coherence: a {self.method} estimate has no coherence; use band_hz")
            with np.errstate(invalid="ignore"):
                keep &= self.coherence[i] >= float(min_coherence)
        if max_std_db is not None:
            if not float(max_std_db) > 0:
                raise IPMCError(f"max_std_db={max_std_db!r} must be > 0 [dB]")
            with np.errstate(invalid="ignore"):
                keep &= self.magnitude_std_db[i] <= float(max_std_db)
        if not keep.any():
            raise IPMCError(f"no lines left after band_hz={band_hz!r}, min_coherence={min_coherence!r} "
                            f"and max_std_db={max_std_db!r}")
        H, sm, sp = self.response[i, keep], self.magnitude_std_db[i, keep], self.phase_std_deg[i, keep]
        bad = ~(np.isfinite(H) & (H != 0) & np.isfinite(sm) & np.isfinite(sp))
        if bad.any():
            raise IPMCError(f"lines at {f[keep][bad][:5].tolist()} Hz have no finite response or σ "
                            f"(no excitation there?); drop them with min_coherence=, band_hz= or the "
                            f"estimator's frequencies_hz=")
        meta = {"source": f"physmodel.estimation.frf.{self.method}", "method": self.method,
                **{k: str(v) for k, v in self.settings.items()}}
        if quantity is not None:
            meta["quantity"] = quantity
        meta.update({k: str(v) for k, v in (metadata or {}).items()})
        return FrequencySweep(np.full(H.size, float(temperature_c)), f[keep], H, sm, sp, self.input_name,
                              self.input_unit, self.output_names[i], self.output_units[i], meta)


def _sigma_from_coherence(coh: np.ndarray, dof: float) -> tuple[np.ndarray, np.ndarray]:
    """σ [dB], σ [deg] of an FRF line from coherence and degrees of freedom (Bendat & Piersol 9.90)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(np.clip(1.0 - coh, 0.0, None) / (2.0 * dof * coh))
    s = np.where(coh > 0, s, np.inf)
    return NEPER_TO_DB * s, np.degrees(s)


# ----------------------------------------------------------------------------------- Welch
def effective_averages(window: np.ndarray, step: int, n_segments: int) -> float:
    """Number of independent averages equivalent to ``n_segments`` overlapping windowed segments
    (Welch 1967, eq. for the variance of an averaged periodogram)."""
    w = np.asarray(window, dtype=float)
    n = w.size
    js = np.arange(1, min(n_segments, -(-n // step)))
    if js.size == 0:
        return float(n_segments)
    rho = np.array([np.dot(w[:n - j * step], w[j * step:]) for j in js]) / np.dot(w, w)
    return float(n_segments / (1.0 + 2.0 * np.sum((1.0 - js / n_segments) * rho**2)))


def _spectra(x: np.ndarray, nperseg: int, step: int, win: np.ndarray, detrend) -> np.ndarray:
    segs = np.lib.stride_tricks.sliding_window_view(x, nperseg)[::step]
    if detrend == "constant":
        segs = segs - segs.mean(axis=1, keepdims=True)
    elif detrend == "linear":
        segs = signal.detrend(segs, axis=1, type="linear")
    else:
        segs = segs.copy()
    segs *= win
    return sp_fft.rfft(segs, axis=1, overwrite_x=True)


def _power(X: np.ndarray) -> np.ndarray:
    """Σ over segments of |X|² (no temporary of X's size)."""
    return np.einsum("ij,ij->j", X.real, X.real) + np.einsum("ij,ij->j", X.imag, X.imag)


def welch_frf(t_or_fs, u, y, *, estimator: str = "h1", nperseg: int | None = None, noverlap: int | None = None,
              window="hann", detrend: str | bool = "constant", discard_s: float = 0.0, frequencies_hz=None,
              block_samples: int = BLOCK_SAMPLES, input_name: str = "input", input_unit: str = "1",
              output_names: Sequence[str] | None = None, output_units: Sequence[str] | None = None) -> FRFEstimate:
    """H1 or H2 estimate with coherence and per-line σ (see module doc).

    Parameters
    ----------
    t_or_fs : float or (n,) array_like   sample rate [Hz] or uniform sample times [s]
    u : (n,) array_like                  input samples (memory-mapped arrays are read in blocks)
    y : (n,) or (n_out, n) array_like, or a list of (n,) arrays   output channels
    estimator : "h1" | "h2"
    nperseg : int    segment length [samples]; default the largest power of two giving ≥ 16
        segments at the default overlap
    noverlap : int   overlap [samples]; default ``nperseg // 2``
    window : str, tuple or (nperseg,) array    as :func:`scipy.signal.get_window` (periodic)
    detrend : "constant" | "linear" | False     per segment, as :func:`scipy.signal.csd`
    discard_s : float    leading transient not used. [s]
    frequencies_hz : array_like or None   keep only these lines (each must be a bin, e.g. the lines
        of a multisine whose period is ``nperseg``). [Hz]
    block_samples : int  samples read per block (bounds the memory)
    """
    if estimator not in ("h1", "h2"):
        raise IPMCError(f"estimator={estimator!r}; expected 'h1' or 'h2'")
    if detrend not in ("constant", "linear", False, None):
        raise IPMCError(f"detrend={detrend!r}; expected 'constant', 'linear' or False")
    u = _as_signal(u, "u")
    n_all = len(u)
    ys = _as_outputs(y, n_all)
    fs = sample_rate(t_or_fs, n_all, block_samples)
    if not (math.isfinite(discard_s) and discard_s >= 0):
        raise IPMCError(f"discard_s={discard_s!r} must be a finite number >= 0 [s]")
    start = int(math.ceil(discard_s * fs - 1e-9))
    n = n_all - start
    if nperseg is None:
        nperseg = 1 << max(int(math.floor(math.log2(max(2 * n / 17, 2)))), 1)
    if not (isinstance(nperseg, (int, np.integer)) and 2 <= nperseg <= n):
        raise IPMCError(f"nperseg={nperseg!r} must be an integer between 2 and the {n} samples after discard_s")
    nperseg = int(nperseg)
    noverlap = nperseg // 2 if noverlap is None else noverlap
    if not (isinstance(noverlap, (int, np.integer)) and 0 <= noverlap < nperseg):
        raise IPMCError(f"noverlap={noverlap!r} must be an integer with 0 <= noverlap < nperseg={nperseg}")
    step = nperseg - int(noverlap)
    K = (n - nperseg) // step + 1
    if K < 2:
        raise IPMCError(f"nperseg={nperseg}, noverlap={noverlap} give {K} segment from {n} samples; "
                        f"σ needs at least 2 averages (shorten nperseg or record longer)")
    try:
        win = (signal.get_window(window, nperseg) if isinstance(window, (str, tuple))
               else np.asarray(window, dtype=float))
    except ValueError as exc:
        raise IPMCError(f"window={window!r}: {exc}") from None
    if win.shape != (nperseg,):
        raise IPMCError(f"window has {win.size} samples; expected nperseg={nperseg}")
    if not (isinstance(block_samples, (int, np.integer)) and block_samples >= 1):
        raise IPMCError(f"block_samples={block_samples!r} must be a positive integer")

    nf = nperseg // 2 + 1
    Suu = np.zeros(nf)
    Syy = np.zeros((len(ys), nf))
    Suy = np.zeros((len(ys), nf), dtype=complex)
    B = max(1, block_samples // step)
    for k0 in range(0, K, B):
        k1 = min(K, k0 + B)
        a, b = start + k0 * step, start + (k1 - 1) * step + nperseg
        U = _spectra(_finite_block(u[a:b], "u", a), nperseg, step, win, detrend)
        Suu += _power(U)
        np.conjugate(U, out=U)
        for c, yc in enumerate(ys):
            Y = _spectra(_finite_block(yc[a:b], f"y[{c}]", a), nperseg, step, win, detrend)
            Suy[c] += np.einsum("ij,ij->j", U, Y)
            Syy[c] += _power(Y)
            del Y
    f = sp_fft.rfftfreq(nperseg, 1.0 / fs)[1:]            # DC carries no response after detrending
    Suu, Syy, Suy = Suu[1:], Syy[:, 1:], Suy[:, 1:]
    if frequencies_hz is not None:
        want = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
        k = np.rint(want * nperseg / fs).astype(int)
        off = (k < 1) | (k > nf - 1) | (np.abs(want * nperseg / fs - k) > 1e-6)
        if off.any() or want.size == 0:
            raise IPMCError(f"frequencies_hz: {want[off][:5].tolist()} Hz are not bins of a {nperseg}-sample "
                            f"segment at fs={fs:g} Hz (multiples of {fs / nperseg:g} Hz up to {fs / 2:g} Hz)")
        if np.any(np.diff(k) <= 0):
            raise IPMCError("frequencies_hz must strictly increase")
        f, Suu, Syy, Suy = f[k - 1], Suu[k - 1], Syy[:, k - 1], Suy[:, k - 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        H = Suy / Suu if estimator == "h1" else Syy / Suy.conj()
        coh = np.abs(Suy)**2 / (Suu * Syy)
    coh = np.where(np.isfinite(coh), coh, 0.0)
    n_eff = effective_averages(win, step, K)
    sm, sp = _sigma_from_coherence(coh, n_eff - 1.0)
    names, units = _names(output_names, output_units, len(ys), "output")
    settings = {"fs_hz": fs, "nperseg": nperseg, "noverlap": int(noverlap),
                "window": window if isinstance(window, (str, tuple)) else "custom", "detrend": detrend,
                "discard_s": discard_s, "segments": K, "effective_averages": round(n_eff, 3),
                "resolution_hz": fs / nperseg}
    return FRFEstimate(f, H, sm, sp, coh, np.full(f.size, K), estimator, input_name, input_unit, names, units, settings)


def h1(t_or_fs, u, y, **kw) -> FRFEstimate:
    """H1 = S_uy/S_uu (noise on the output); see :func:`welch_frf` for the arguments."""
    return welch_frf(t_or_fs, u, y, estimator="h1", **kw)


def h2(t_or_fs, u, y, **kw) -> FRFEstimate:
    """H2 = S_yy/S_yu (noise on the input); see :func:`welch_frf` for the arguments."""
    return welch_frf(t_or_fs, u, y, estimator="h2", **kw)


# ----------------------------------------------------------------------------------- records
def estimate_record(record, input: str, outputs: Sequence[str] | None = None, method: str = "h1",
                    **kw) -> FRFEstimate:
    """FRF from channel ``input`` to ``outputs`` (default: every other channel) of a
    :class:`~physmodel.estimation.records.TimeRecord`, in the record's units.

    ``method``: "h1", "h2" (keywords of :func:`welch_frf`) or "stepped_sine" (keywords of
    :func:`~physmodel.estimation.stepped.stepped_sine`).
    """
    from .stepped import stepped_sine

    fns: dict[str, Callable[..., FRFEstimate]] = {"h1": h1, "h2": h2, "stepped_sine": stepped_sine}
    if method not in fns:
        raise IPMCError(f"method={method!r}; expected one of {list(fns)}")
    inp = record.resolve(input)
    outs = [c for c in record.channels if c != inp] if outputs is None else [record.resolve(o) for o in outputs]
    if not outs:
        raise IPMCError(f"outputs: the record has no channel besides the input {inp!r}")
    if inp in outs:
        raise IPMCError(f"outputs: {inp!r} is the input channel")
    return fns[method](record.t, record.channels[inp], [record.channels[o] for o in outs], input_name=inp,
                       input_unit=record.units[inp], output_names=outs, output_units=[record.units[o] for o in outs],
                       **kw)


def frf_sweep(estimates: Sequence[tuple[float, FRFEstimate]], output: str | int | None = None,
              **to_sweep_kw) -> FrequencySweep:
    """One :class:`FrequencySweep` from ``[(temperature_c, estimate), ...]`` (one estimate per
    temperature [°C]), each converted by :meth:`FRFEstimate.to_sweep`."""
    from ..data.sweep import merge_sweeps

    items = list(estimates)
    if not items:
        raise IPMCError("estimates: give at least one (temperature_c, FRFEstimate) pair")
    return merge_sweeps([est.to_sweep(T, output, **to_sweep_kw) for T, est in items])
