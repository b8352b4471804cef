"""Stepped-sine FRF estimation: per-period three-parameter sine fits after each step's transient.

Each step drives one frequency.  The first ``settle_s`` (or ``settle_periods``) of the step are
discarded; every whole period of the rest is fitted by least squares with cos, sin and an offset
(IEEE Std 1057 three-parameter fit), which stays exact when a period is not a whole number of
samples.  The estimate is the ratio of the period-mean phasors ``H = Ȳ/Ū``; a partial period at
the end of a step is not used, and a request for a fractional number of periods is refused.

σ comes from the scatter between periods: ``δ ln H_k = (Y_k − H U_k)/Ȳ``, whose real and
imaginary parts give the σ of ln|H| and of the phase (sample variance with P − 1 degrees of
freedom, divided by P), reported in dB (×20/ln 10) and degrees.  It assumes the noise of different
periods is independent (white or short-memory noise).  The coherence of each step over its periods,
``|Σ conj(U_k) Y_k|²/(Σ|U_k|² Σ|Y_k|²)``, shows whether the output follows the input at all
(``settings['coherence_threshold']``: the value an unrelated output exceeds with probability 1 %
at the fewest periods of any step).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..data.timerecord import sample_rate
from ..errors import IPMCError
from .frf_estimate import (
    BLOCK_SAMPLES,
    NEPER_TO_DB,
    FRFEstimate,
    as_outputs,
    as_signal,
    channel_names,
    coherence_threshold,
    finite_block,
    phasor_scatter,
)


def _per_step(x, name: str, shape, what: str) -> np.ndarray:
    try:
        v = np.broadcast_to(np.asarray(x, dtype=float), shape).copy()
    except ValueError:
        raise IPMCError(f"{name} has shape {np.shape(x)}; expected one value or one per step {shape}") from None
    if not np.all(np.isfinite(v)):
        raise IPMCError(f"{name} must be finite {what}")
    return v


def period_phasors(chans: list, fs: float, t0: float, m0: float, f: float, P: int,
                   block: int = BLOCK_SAMPLES) -> np.ndarray:
    """(P, n_channels) phasors (a − jb of a·cos + b·sin + c, phase from ``m0``) of P whole periods.

    Parameters
    ----------
    chans : list of (n,) arrays
        Channels sampled together (the first is called ``u`` in errors, the others ``y[i]``).
    fs : float
        Sample rate. [Hz]
    t0 : float
        Time of sample 0. [s]
    m0 : float
        Start of the first period. [s]
    f : float
        Frequency of the sine. [Hz]
    P : int
        Whole periods fitted, one phasor each.
    block : int
        Samples read per block (bounds the memory).
    """
    n = len(chans[0])
    a = max(int(math.ceil((m0 - t0) * fs - 1e-9)), 0)
    b = min(int(math.ceil((m0 + P / f - t0) * fs - 1e-9)), n)
    sums = np.zeros((6 + 3 * len(chans), P))
    for a0 in range(a, b, block):
        b0 = min(b, a0 + block)
        tau = np.arange(a0, b0) / fs - (m0 - t0)
        g = np.clip(np.floor(tau * f).astype(np.int64), 0, P - 1)
        c, s = np.cos(2 * np.pi * f * tau), np.sin(2 * np.pi * f * tau)
        # one product at a time: the memory stays a few block-sized arrays
        for k, (p, q) in enumerate(((c, c), (c, s), (c, None), (s, s), (s, None), (None, None))):
            sums[k] += np.bincount(g, weights=None if p is None else p if q is None else p * q, minlength=P)
        for x_i, x in enumerate(chans):
            xb = finite_block(x[a0:b0], "u" if x_i == 0 else f"y[{x_i - 1}]", a0)
            for k, q in enumerate((c, s, None)):
                sums[6 + 3 * x_i + k] += np.bincount(g, weights=xb if q is None else xb * q, minlength=P)
    cc, cs, c1, ss, s1, n1 = sums[:6]
    A = np.stack([np.stack([cc, cs, c1], -1), np.stack([cs, ss, s1], -1), np.stack([c1, s1, n1], -1)], -2)
    R = sums[6:].reshape(len(chans), 3, P).transpose(2, 1, 0)           # (P, 3, n_channels)
    coef = np.linalg.solve(A, R)
    return coef[:, 0, :] - 1j * coef[:, 1, :]


def stepped_sine(t_or_fs, u, y, frequencies_hz=None, step_start_s=None, step_stop_s=None, *, plan=None,
                 settle_s=0.0, settle_periods=0.0, periods=None, block_samples: int = BLOCK_SAMPLES,
                 input_name: str = "input", input_unit: str = "1", output_names: Sequence[str] | None = None,
                 output_units: Sequence[str] | None = None) -> FRFEstimate:
    """Stepped-sine estimate: per-period sine fits after each step's transient (see module doc).

    Parameters
    ----------
    t_or_fs : float or (n,) array_like   sample rate [Hz] or uniform sample times [s]
    u, y : as :func:`welch_frf`
    frequencies_hz : (n_steps,) array_like   frequency of each step, distinct, at most fs/4. [Hz]
    step_start_s : (n_steps,) array_like   start of each step on the record's time axis (the time of
        sample 0 is ``t[0]``, or 0 when ``fs`` is given). [s]
    step_stop_s : (n_steps,) array_like or None   end of each step; default the next step's start
        and, for the last, the end of the record. [s]
    plan : SteppedSinePlan or None   take frequencies, starts, stops, settle and periods from a plan
        (:func:`physmodel.estimation.excitation.stepped_sine_plan`) instead.
    settle_s, settle_periods : float or per step   transient discarded at each step's start: the
        longer of ``settle_s`` [s] and ``settle_periods`` periods.
    periods : int or per step or None   whole periods to use after settling; None uses every whole
        period left in the step (a trailing partial period is not used).  Non-integer values are
        refused: a fractional period would leak.
    """
    u = as_signal(u, "u")
    n = len(u)
    ys = as_outputs(y, n)
    fs = sample_rate(t_or_fs, n, block_samples)
    t0 = float(t_or_fs[0]) if np.ndim(t_or_fs) else 0.0
    if plan is not None:
        if frequencies_hz is not None or step_start_s is not None or step_stop_s is not None:
            raise IPMCError("plan: give either a plan or frequencies_hz/step_start_s/step_stop_s, not both")
        frequencies_hz, step_start_s, step_stop_s = plan.frequency_hz, plan.step_start_s + t0, plan.step_stop_s + t0
        settle_s, settle_periods, periods = plan.settle_s, 0.0, plan.periods
    if frequencies_hz is None or step_start_s is None:
        raise IPMCError("frequencies_hz and step_start_s (or plan=) are required")
    f = np.asarray(frequencies_hz, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)):
        raise IPMCError(f"frequencies_hz must be a non-empty 1-D array of finite values, got {frequencies_hz!r}")
    if np.any(f <= 0) or np.any(f > fs / 4):
        raise IPMCError(f"frequencies_hz: {f[(f <= 0) | (f > fs / 4)][:5].tolist()} Hz are outside (0, fs/4 = "
                        f"{fs / 4:g}] Hz; a sine fit needs at least 4 samples per period")
    vals, counts = np.unique(f, return_counts=True)
    if np.any(counts > 1):
        raise IPMCError(f"frequencies_hz repeats {vals[counts > 1][:5].tolist()} Hz; give each frequency once")
    starts = _per_step(step_start_s, "step_start_s", f.shape, "[s]")
    t_end = t0 + n / fs
    stops = (np.append(starts[1:], t_end) if step_stop_s is None
             else _per_step(step_stop_s, "step_stop_s", f.shape, "[s]"))
    bad = np.flatnonzero((stops <= starts) | (starts < t0 - 0.5 / fs) | (stops > t_end + 1e-9 * max(1.0, abs(t_end))))
    if bad.size:
        i = bad[0]
        raise IPMCError(f"step {i} ({f[i]:g} Hz) runs from {starts[i]:g} to {stops[i]:g} s; steps must lie in the "
                        f"record ({t0:g} to {t_end:g} s) and end after they start")
    s_s = _per_step(settle_s, "settle_s", f.shape, ">= 0 [s]")
    s_p = _per_step(settle_periods, "settle_periods", f.shape, ">= 0")
    if np.any(s_s < 0) or np.any(s_p < 0):
        raise IPMCError("settle_s and settle_periods must be >= 0")
    settle = np.maximum(s_s, s_p / f)
    m0 = starts + settle
    avail = np.floor((stops - m0) * f + 1e-9)
    if periods is None:
        P = avail
    else:
        P = _per_step(periods, "periods", f.shape, "whole numbers")
        if np.any(P != np.round(P)):
            raise IPMCError(f"periods={periods!r}: a stepped sine is measured over whole periods; a fractional "
                            f"period leaks the sine into the estimate.  Give whole numbers (or None for all "
                            f"whole periods in each step)")
        short = np.flatnonzero(P > avail)
        if short.size:
            i = short[0]
            raise IPMCError(f"step {i} ({f[i]:g} Hz): periods={int(P[i])} need {P[i] / f[i]:g} s after the "
                            f"{settle[i]:g} s settle, but the step leaves {max(stops[i] - m0[i], 0):g} s")
    few = np.flatnonzero(P < 2)
    if few.size:
        i = few[0]
        raise IPMCError(f"step {i} ({f[i]:g} Hz): {int(max(P[i], 0))} whole period(s) after the {settle[i]:g} s "
                        f"settle; σ from the scatter between periods needs at least 2")
    chans = [u, *ys]
    H = np.empty((len(ys), f.size), dtype=complex)
    sl = np.empty((len(ys), f.size))
    sp = np.empty((len(ys), f.size))
    coh = np.empty((len(ys), f.size))
    for i in range(f.size):
        Pi = int(P[i])
        ph = period_phasors(chans, fs, t0, m0[i], f[i], Pi, block_samples)
        U, Y = ph[:, 0], ph[:, 1:]
        if np.mean(U) == 0:
            raise IPMCError(f"step {i} ({f[i]:g} Hz): the input has no component at this frequency")
        Hi = Y.mean(axis=0) / U.mean()
        H[:, i] = Hi
        s_l, s_p, c = phasor_scatter(U[:, None], Y[:, :, None], Hi[:, None])
        sl[:, i], sp[:, i], coh[:, i] = s_l[:, 0], s_p[:, 0], c[:, 0]
    order = np.argsort(f)
    names, units = channel_names(output_names, output_units, len(ys), "output")
    settings = {"fs_hz": fs, "steps": f.size, "settle_s_min": float(settle.min()), "settle_s_max": float(settle.max()),
                "periods_min": int(P.min()), "periods_max": int(P.max()),
                "unused_tail_s_max": float(np.max(stops - m0 - P / f)),
                "coherence_threshold": round(coherence_threshold(float(P.min())), 4)}
    return FRFEstimate(f[order], H[:, order], NEPER_TO_DB * sl[:, order], np.degrees(sp[:, order]), coh[:, order],
                       P[order].astype(int), "stepped_sine", input_name, input_unit, names, units, settings)
