"""Frequency responses with per-line uncertainty, estimated from time records.

Front door
----------
:func:`estimate_frf` (and :func:`estimate_record` with its default ``method="auto"``) reads the
excitation from the input channel and picks the estimator: clipping is checked on every channel
(:mod:`physmodel.estimation.clipping`: refused above 1 % of samples held at a rail, warned below),
the excitation is detected (:mod:`physmodel.estimation.excitation_detection`), then a periodic
input is estimated at its excited lines over whole steady periods
(:mod:`physmodel.estimation.periodic`), a stepped sine on its detected steps
(:mod:`physmodel.estimation.stepped`), and only a random input by Welch (below) with a segment
that resolves the requested band.  A record too short for one line in the band is refused; every
estimate carries a per-line coherence and ``settings['coherence_threshold']``; low coherence,
clipping below the limit and unused steps are ``FRFEstimate.warnings`` (and ``FRFWarning``).
``tests/benchmarks/bench_frf_excitation.py`` measures it on records from its own generator.

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

* Welch (Bendat & Piersol, *Random Data*, 4th ed., §9.2.3, eqs 9.73 and 9.90): to first order
  ``σ_ln² = σ_φ² = (1 − γ²)/(2 ν γ²)`` with the sample coherence γ² and ``ν = n_eff − 1`` degrees
  of freedom; ``n_eff`` is the number of segments corrected for overlap (Welch 1967:
  ``K / (1 + 2 Σ_j (1 − j/K) ρ_j²)``, ρ_j the window's overlap correlation at a shift of j segments).
  For H1 with output noise the error ``Ĥ − H`` is, given the input spectra, circular complex
  Gaussian with a variance estimated from the residual ``S_yy(1 − γ²)`` (Goodman 1957); σ is the
  root-mean-square of ln|H/Ĥ| and of arg(H/Ĥ) over that exact distribution
  (:func:`~physmodel.estimation.frf_estimate.sigma_exact`): the first-order value for small
  errors, and not linearised where σ exceeds about 1 dB.  For H2 it is the mirror case (input
  noise).  A line with γ² = 0 has infinite σ.
* Which Welch lines stand out of noise: ``settings['coherence_threshold']`` is the coherence that
  any of the estimate's ``coherence_lines`` noise-only lines exceeds with probability 1 %
  (:func:`~physmodel.estimation.frf_estimate.coherence_threshold` with ``lines``).  A per-line
  1 % (``settings['coherence_threshold_per_line']``, used for the low-coherence warning) would
  keep about ten noise lines in an estimate of a thousand; the exact confidence disc of such a
  line reaches H = 0, so its error of ln|H| is unbounded and no σ describes it
  (``tests/benchmarks/bench_frf_excitation.py``: those lines made the error/σ RMS of a random
  record 1.44 instead of 1.05).
* Stepped sine: the scatter of the per-period phasors, ``δ ln H_k = (Y_k − H U_k)/Ȳ``; its real
  and imaginary parts give σ_ln and σ_φ (sample variance with P − 1 degrees of freedom, divided by P).

Both σ are estimates with few degrees of freedom when averages are few, so ±2σ covers the truth a
little less than 95 % of the time (Student t with ν degrees of freedom).  When the input repeats
exactly in every segment (a multisine estimated over whole periods, P segments), the line's complex
noise gives σ̂ two real degrees of freedom per period, ν = 2(P − 1)
(``tests/scenarios/test_virtual_lab.py`` measures mean t² = 1.19 for P = 8, t₁₄: 1.17).  Once σ of
the magnitude exceeds about 1 dB the error of ln|H| = ln|1 + ε| is skewed (a long tail where
|1 + ε| → 0): the Welch σ is its exact RMS, but its ±2σ interval is not the Gaussian one, and a
line kept because its sample coherence came out high has its |Ĥ| pushed up and its σ down (with
fewer than about 16 segments this shows; ``tests/estimation/test_frf_sigma.py``);
:meth:`FRFEstimate.to_sweep` can drop such lines (``max_std_db``).  Leakage (resolution) bias is not in σ: choose ``nperseg`` so the bin width
is well below the half-power bandwidth of the sharpest resonance (the bias falls as Δf for a
rectangular window, Δf² for Hann).  ``tests/benchmarks/bench_frf.py`` measures the coverage.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from scipy import fft as sp_fft
from scipy import signal

from ..data.sweep import FrequencySweep
from ..data.timerecord import sample_rate
from ..errors import IPMCError
from .frf_estimate import (
    BLOCK_SAMPLES,
    FRFEstimate,
    as_outputs,
    as_signal,
    channel_names,
    coherence_threshold,
    finite_block,
    sigma_exact,
)

__all__ = ["FRFEstimate", "effective_averages", "welch_frf", "h1", "h2", "estimate_frf", "estimate_record",
           "frf_sweep"]


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
    u = as_signal(u, "u")
    n_all = len(u)
    ys = as_outputs(y, n_all)
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
        U = _spectra(finite_block(u[a:b], "u", a), nperseg, step, win, detrend)
        Suu += _power(U)
        np.conjugate(U, out=U)
        for c, yc in enumerate(ys):
            Y = _spectra(finite_block(yc[a:b], f"y[{c}]", a), nperseg, step, win, detrend)
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
    sm, sp = sigma_exact(coh, n_eff - 1.0)
    names, units = channel_names(output_names, output_units, len(ys), "output")
    settings = {"fs_hz": fs, "nperseg": nperseg, "noverlap": int(noverlap),
                "window": window if isinstance(window, (str, tuple)) else "custom", "detrend": detrend,
                "discard_s": discard_s, "segments": K, "effective_averages": round(n_eff, 3),
                "resolution_hz": fs / nperseg, "coherence_lines": f.size,
                "coherence_threshold": round(coherence_threshold(max(n_eff, 2.0), lines=f.size), 4),
                "coherence_threshold_per_line": round(coherence_threshold(max(n_eff, 2.0)), 4)}
    return FRFEstimate(f, H, sm, sp, coh, np.full(f.size, K), estimator, input_name, input_unit, names, units, settings)


def h1(t_or_fs, u, y, **kw) -> FRFEstimate:
    """H1 = S_uy/S_uu (noise on the output); see :func:`welch_frf` for the arguments."""
    return welch_frf(t_or_fs, u, y, estimator="h1", **kw)


def h2(t_or_fs, u, y, **kw) -> FRFEstimate:
    """H2 = S_yy/S_yu (noise on the input); see :func:`welch_frf` for the arguments."""
    return welch_frf(t_or_fs, u, y, estimator="h2", **kw)


# ----------------------------------------------------------------------------------- reading the excitation
#: Welch segments of a random excitation: at least this many samples.
MIN_NPERSEG = 16
#: Keywords that ask for a Welch estimate explicitly (:func:`estimate_record` with ``method="auto"``).
WELCH_KEYWORDS = ("nperseg", "noverlap", "window", "detrend", "frequencies_hz")


def _in_band(f: np.ndarray, band_hz) -> np.ndarray:
    if band_hz is None:
        return np.ones(f.size, dtype=bool)
    lo, hi = (float(v) for v in band_hz)
    if not 0 <= lo <= hi:
        raise IPMCError(f"band_hz={band_hz!r} must be (low, high) with 0 <= low <= high [Hz]")
    return (f >= lo) & (f <= hi)


def _random_nperseg(n: int, fs: float, band_hz) -> int:
    """Longest power of two giving ≥ 16 Hann segments at 50 % overlap, lengthened so the bin width
    is at most half the band's lower edge; refused when not 2 segments of MIN_NPERSEG remain."""
    nper = 1 << max(int(math.floor(math.log2(max(2 * n / 17, 1)))), 0)
    lo = float(band_hz[0]) if band_hz is not None else 0.0
    if lo > 0:
        nper = max(nper, 1 << int(math.ceil(math.log2(2 * fs / lo))))
    nper = max(nper, MIN_NPERSEG)
    if (n - nper) // (nper // 2) + 1 < 2:
        need = "" if lo <= 0 else f" to resolve band_hz={tuple(band_hz)!r} (bin width {lo / 2:g} Hz)"
        raise IPMCError(f"the record has {n} samples: too short for a random-excitation estimate{need}; it needs "
                        f"2 half-overlapping segments of {nper} samples ({nper * 3 // 2} samples, "
                        f"{nper * 1.5 / fs:g} s)")
    return nper


def _stepped_schedule(exc, u, ys, fs: float, block: int, notes: list):
    """Per step: frequency, start, stop, settle periods (transient found from the period phasors;
    a trailing period that mixes two steps cut)."""
    from .periodic import leading_transient
    from .stepped import period_phasors

    f, a, b = exc.step_frequency_hz, exc.step_start_s, exc.step_stop_s
    keep = np.ones(f.size, dtype=bool)
    _, first = np.unique(f, return_index=True)
    rep = np.setdiff1d(np.arange(f.size), first)
    if rep.size:
        keep[rep] = False
        notes.append(f"stepped sine: repeated steps at {f[rep][:5].round(6).tolist()} Hz not used (first kept)")
    fast = f > fs / 4
    if fast.any():
        keep &= ~fast
        notes.append(f"stepped sine: steps above fs/4 ({f[fast][:5].round(3).tolist()} Hz) not used")
    rows = []
    for i in np.flatnonzero(keep):
        P = int(round((b[i] - a[i]) * f[i]))
        ph = period_phasors([u, *ys], fs, 0.0, a[i], f[i], P, block)
        U, Y = ph[:, 0], ph[:, 1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            lead = max(leading_transient(U), leading_transient(Y / U[:, None]))
        trail = leading_transient(U[::-1])
        if P - lead - trail < 2:
            notes.append(f"stepped sine: the step at {f[i]:.6g} Hz has {P} periods, {lead + trail} unsettled; not used")
            continue
        rows.append((f[i], a[i], a[i] + (P - trail) / f[i], lead))
    if not rows:
        raise IPMCError("stepped sine: no step keeps 2 settled whole periods; record longer steps")
    return (np.array(v) for v in zip(*rows))


def estimate_frf(t_or_fs, u, y, *, estimator: str = "h1", excitation: str = "auto", band_hz=None,
                 discard_s: float | None = None, max_clipped_fraction: float | None = None,
                 block_samples: int = BLOCK_SAMPLES, input_name: str = "input", input_unit: str = "1",
                 output_names: Sequence[str] | None = None, output_units: Sequence[str] | None = None) -> FRFEstimate:
    """The FRF estimate the input's excitation calls for, found from the samples.

    1. Clipping: each channel is checked for samples held at a rail
       (:func:`~physmodel.estimation.clipping.detect_clipping`); more than
       ``max_clipped_fraction`` on any channel is refused, less is a warning.
    2. The excitation (:func:`~physmodel.estimation.excitation_detection.detect_excitation`):
       *periodic* → :func:`~physmodel.estimation.periodic.periodic_frf` at the excited lines over
       whole periods, the transient found from the period scatter; *stepped sine* →
       :func:`~physmodel.estimation.stepped.stepped_sine` on the detected steps, each step's
       transient found the same way; *random* → Welch (:func:`welch_frf`, Hann, 50 % overlap) with
       the longest power-of-two segment giving ≥ 16 segments, lengthened to resolve ``band_hz``.
    3. Lines outside ``band_hz`` (and the Nyquist line) are not estimated; a record too short for
       one line in the band is refused.  ``settings['excitation']`` says what was detected and
       ``settings['coherence_threshold']`` what an unrelated output exceeds 1 % of the time (at
       any of the estimate's lines, for Welch; at a line, for the others); more than half of a
       channel's lines below the per-line value is a low-coherence warning.  Warnings are in
       ``FRFEstimate.warnings`` and issued as :class:`~physmodel.estimation.frf_estimate.FRFWarning`.

    Parameters
    ----------
    t_or_fs : float or (n,) array_like
        Sample rate [Hz] or uniform sample times [s].
    u : (n,) array_like
        Input samples.
    y : (n,) or (n_out, n) array_like, or a list of (n,) arrays
        Output channels.
    estimator : "h1" | "h2"
        Ratio for periodic and random excitation (a stepped sine is always the ratio of mean phasors).
    excitation : "auto" | "periodic" | "stepped_sine" | "random"
        Expected excitation: "auto" takes what is detected, another value refuses a record where
        something else is detected ("random" always runs Welch).
    band_hz : (float, float) or None
        Lines kept, (low, high). [Hz]
    discard_s : float or None
        Leading time not used (periodic and random); None: periodic finds its transient, random uses all. [s]
    max_clipped_fraction : float or None
        Largest fraction of clipped samples accepted on a channel (default
        :data:`~physmodel.estimation.clipping.MAX_CLIPPED_FRACTION`; 1 only warns).
    block_samples : int
        Samples read per block (bounds the memory).
    input_name, input_unit, output_names, output_units : str or sequences of str
        Channel names and units carried into the estimate.
    """
    import warnings as _warnings
    from dataclasses import replace

    from .clipping import check_clipping
    from .excitation_detection import Excitation, detect_excitation
    from .frf_estimate import FRFWarning, low_coherence_warning
    from .periodic import periodic_frf
    from .stepped import stepped_sine

    if estimator not in ("h1", "h2"):
        raise IPMCError(f"estimator={estimator!r}; expected 'h1' or 'h2'")
    if excitation not in ("auto", "periodic", "stepped_sine", "random"):
        raise IPMCError(f"excitation={excitation!r}; expected 'auto', 'periodic', 'stepped_sine' or 'random'")
    if discard_s is not None and not (math.isfinite(discard_s) and discard_s >= 0):
        raise IPMCError(f"discard_s={discard_s!r} must be a finite number >= 0 [s]")
    u = as_signal(u, "u")
    n = len(u)
    ys = as_outputs(y, n)
    fs = sample_rate(t_or_fs, n, block_samples)
    names, units = channel_names(output_names, output_units, len(ys), "output")
    if n < MIN_NPERSEG + MIN_NPERSEG // 2:
        raise IPMCError(f"the record has {n} samples ({n / fs:g} s): too short for one line of a frequency "
                        f"response with σ (at least {MIN_NPERSEG * 3 // 2} samples)")
    notes = check_clipping({input_name: u, **dict(zip(names, ys))}, max_clipped_fraction)
    exc = Excitation("random", fs, evidence={"forced": "random"}) if excitation == "random" \
        else detect_excitation(None, u, fs_hz=fs)
    if excitation not in ("auto", "random") and exc.kind != excitation:
        raise IPMCError(f"excitation={excitation!r}, but the input looks {exc.describe()}")
    common = dict(block_samples=block_samples, input_name=input_name, input_unit=input_unit, output_names=names,
                  output_units=units)
    if exc.kind == "periodic":
        N = int(exc.period_samples or 0)
        lines = exc.lines[_in_band(exc.frequency_hz, band_hz)]
        if lines.size == 0:
            raise IPMCError(f"no excited line in band_hz={band_hz!r}; the input's lines are "
                            f"{exc.frequency_hz.min():g}-{exc.frequency_hz.max():g} Hz")
        drop = None
        if discard_s is not None:
            drop = max(0, int(math.ceil((discard_s * fs - n % N) / N - 1e-9)))
        est = periodic_frf(fs, u, ys, N, lines, estimator=estimator, discard_periods=drop, **common)
    elif exc.kind == "stepped_sine":
        if discard_s is not None:
            raise IPMCError("discard_s applies to periodic and random excitation; a stepped sine's transient is "
                            "found step by step (or estimate with stepped_sine(..., settle_s=))")
        f, a, b, settle = _stepped_schedule(exc, u, ys, fs, block_samples, notes)
        inb = _in_band(f, band_hz)
        if not inb.any():
            raise IPMCError(f"no step in band_hz={band_hz!r}; the steps are {f.min():g}-{f.max():g} Hz")
        est = stepped_sine(fs, u, ys, f[inb], a[inb], b[inb], settle_periods=settle[inb], **common)
    else:
        start = int(math.ceil((discard_s or 0.0) * fs - 1e-9))
        nper = _random_nperseg(n - start, fs, band_hz)
        est = welch_frf(fs, u, ys, estimator=estimator, nperseg=nper, discard_s=discard_s or 0.0, **common)
        keep = _in_band(est.frequency_hz, band_hz) & (est.frequency_hz < fs / 2)
        if not keep.any():
            raise IPMCError(f"no line of a {nper}-sample segment (bin width {fs / nper:g} Hz) lies in "
                            f"band_hz={band_hz!r}; record longer or widen the band")
        est = replace(est, frequency_hz=est.frequency_hz[keep], response=est.response[:, keep],
                      magnitude_std_db=est.magnitude_std_db[:, keep], phase_std_deg=est.phase_std_deg[:, keep],
                      coherence=None if est.coherence is None else est.coherence[:, keep],
                      n_averages=est.n_averages[keep],
                      settings={**est.settings, "coherence_lines": int(keep.sum()), "coherence_threshold": round(
                          coherence_threshold(max(est.settings["effective_averages"], 2.0), lines=int(keep.sum())), 4)})
    low = low_coherence_warning(est)
    if low:
        notes.append(low)
    est = replace(est, settings={**est.settings, "excitation": exc.describe()}, warnings=tuple(notes))
    for note in notes:
        _warnings.warn(FRFWarning(note), stacklevel=2)
    return est


def estimate_record(record, input: str, outputs: Sequence[str] | None = None, method: str = "auto",
                    **kw) -> FRFEstimate:
    """FRF from channel ``input`` to ``outputs`` (default: every other channel) of a
    :class:`~physmodel.data.timerecord.TimeRecord`, in the record's units.

    ``method``: "auto" (default: :func:`estimate_frf`, which reads the excitation from the input;
    with any of ``nperseg``, ``noverlap``, ``window``, ``detrend``, ``frequencies_hz`` it is an
    explicit Welch H1), "h1", "h2" (keywords of :func:`welch_frf`) or "stepped_sine" (keywords of
    :func:`~physmodel.estimation.stepped.stepped_sine`).

    Parameters
    ----------
    record : TimeRecord
        The record.
    input : str
        Input (reference) channel.
    outputs : sequence of str or None
        Output channels; None: every other channel.
    method : str
        Estimator, see above.
    **kw
        Keywords of the estimator.
    """
    from .stepped import stepped_sine

    fns: dict[str, Callable[..., FRFEstimate]] = {"auto": estimate_frf, "h1": h1, "h2": h2,
                                                  "stepped_sine": stepped_sine}
    if method not in fns:
        raise IPMCError(f"method={method!r}; expected one of {list(fns)}")
    if method == "auto" and any(k in kw for k in WELCH_KEYWORDS):
        method = "h1"
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
