"""FRF of a periodic excitation over whole periods, at its excited lines only.

The record is cut into whole periods of N samples, aligned to its end (a leading partial period is
not used; any N consecutive samples of a steady periodic signal are a whole period).  Each period's
DFT at the excited lines gives input and output phasors ``U_p``, ``Y_p``.  Leading periods still in
the transient are discarded (:func:`leading_transient`), then

* H1 = ``Σ conj(U_p) Y_p / Σ |U_p|²`` (noise on the output), H2 = ``Σ |Y_p|² / Σ conj(Y_p) U_p``;
* σ of ln|H| and of the phase from the scatter of ``δ_p = (Y_p − H U_p)/Ȳ`` between periods,
  real and imaginary parts pooled (the noise of a DFT line is circular), so σ has ν = 2(P − 1)
  degrees of freedom (:func:`~physmodel.estimation.frf_estimate.phasor_scatter`; for an input
  repeating exactly it equals the Welch σ from the coherence, see :mod:`physmodel.estimation.frf`);
* the coherence over the periods, and the threshold an unrelated output exceeds 1 % of the time.

No window is needed: a whole period of a periodic signal has no leakage.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import fft as sp_fft
from scipy import stats

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

#: False-alarm probability per period of the transient test (:func:`leading_transient`).
TRANSIENT_ALPHA = 1e-3


def leading_transient(X, alpha: float = TRANSIENT_ALPHA) -> int:
    """Leading periods of ``X`` (P, m) (per-period features: phasors or samples) that differ from
    the steady state, judged against the scatter of the later half of the periods.

    With the later half's mean ``x̄`` and scatter ``s² = Σ|X_q − x̄|²/(P_l − 1)`` (summed over the
    features), period p of the first half is transient when ``|X_p − x̄|²`` exceeds
    ``s² (1 + 1/P_l)`` times the 1 − ``alpha`` quantile of F(d, d (P_l − 1)) (d = the real
    degrees of freedom of a period).  Everything up to the last such period is discarded (a
    decaying transient may dip under the threshold once by chance).  Fewer than 3 periods: 0.

    Parameters
    ----------
    X : (P, m) array_like
        Per-period features, real or complex.
    alpha : float
        False-alarm probability per steady period.
    """
    X = np.asarray(X)
    P = X.shape[0]
    if P < 3:
        return 0
    X = X.reshape(P, -1)
    late = X[P // 2:]
    Pl = late.shape[0]
    mean = late.mean(axis=0)
    s2 = float(np.sum(np.abs(late - mean)**2)) / (Pl - 1)
    d = np.sum(np.abs(X[:P // 2] - mean)**2, axis=1)
    dof = X.shape[1] * (2 if np.iscomplexobj(X) else 1)
    thr = s2 * (1 + 1 / Pl) * float(stats.f.isf(alpha, dof, dof * (Pl - 1)))
    over = np.flatnonzero(d > thr)
    return int(over[-1]) + 1 if over.size else 0


def period_phasors(x, N: int, first: int, P: int, lines: np.ndarray, name: str,
                   block_samples: int = BLOCK_SAMPLES) -> np.ndarray:
    """(P, K) DFT of P whole periods of ``x`` starting at sample ``first``, at bins ``lines``.

    Parameters
    ----------
    x : (n,) array_like
        Samples (read in blocks).
    N : int
        Samples per period.
    first : int
        First sample of the first period.
    P : int
        Periods.
    lines : (K,) int ndarray
        DFT bins of one period.
    name : str
        Channel name for errors.
    block_samples : int
        Samples read per block.
    """
    out = np.empty((P, lines.size), dtype=complex)
    B = max(1, block_samples // N)
    for p0 in range(0, P, B):
        p1 = min(P, p0 + B)
        a = first + p0 * N
        seg = finite_block(x[a:a + (p1 - p0) * N], name, a).reshape(p1 - p0, N)
        out[p0:p1] = sp_fft.rfft(seg, axis=1)[:, lines]
    return out


def periodic_frf(t_or_fs, u, y, period_samples: int, lines, *, estimator: str = "h1",
                 discard_periods: int | None = None, block_samples: int = BLOCK_SAMPLES, input_name: str = "input",
                 input_unit: str = "1", output_names: Sequence[str] | None = None,
                 output_units: Sequence[str] | None = None) -> FRFEstimate:
    """H1 or H2 of a periodic excitation at its excited lines, over whole periods (module doc).

    Parameters
    ----------
    t_or_fs : float or (n,) array_like
        Sample rate [Hz] or uniform sample times [s].
    u : (n,) array_like
        Input samples.
    y : (n,) or (n_out, n) array_like, or a list of (n,) arrays
        Output channels.
    period_samples : int
        Samples per period.
    lines : (K,) array_like of int
        Excited DFT bins of one period (frequency = k·fs/period_samples), each in 1..N/2 − 1.
    estimator : "h1" | "h2"
        Which ratio of the period spectra.
    discard_periods : int or None
        Leading whole periods not used; None finds the transient (:func:`leading_transient`).
    block_samples : int
        Samples read per block (bounds the memory).
    input_name, input_unit, output_names, output_units : str or sequences of str
        Channel names and units carried into the estimate.
    """
    if estimator not in ("h1", "h2"):
        raise IPMCError(f"estimator={estimator!r}; expected 'h1' or 'h2'")
    u = as_signal(u, "u")
    n = len(u)
    ys = as_outputs(y, n)
    fs = sample_rate(t_or_fs, n, block_samples)
    N = int(period_samples)
    if N != period_samples or N < 4:
        raise IPMCError(f"period_samples={period_samples!r} must be a whole number >= 4 [samples]")
    k = np.asarray(lines, dtype=int).ravel()
    if k.size == 0 or np.any(k < 1) or np.any(k >= N / 2) or np.any(np.diff(k) <= 0):
        raise IPMCError(f"lines must be increasing DFT bins in 1..{(N - 1) // 2} of a {N}-sample period")
    P_all = n // N
    first0 = n - P_all * N
    auto = discard_periods is None
    U = period_phasors(u, N, first0, P_all, k, "u", block_samples)
    Y = np.stack([period_phasors(yc, N, first0, P_all, k, f"y[{c}]", block_samples) for c, yc in enumerate(ys)],
                 axis=1)                                                     # (P, n_out, K)
    if auto:
        drop = max([leading_transient(U)] + [leading_transient(Y[:, c]) for c in range(len(ys))])
    else:
        drop = int(discard_periods or 0)
        if drop != discard_periods or drop < 0:
            raise IPMCError(f"discard_periods={discard_periods!r} must be a whole number >= 0")
    P = P_all - drop
    if P < 2:
        raise IPMCError(f"the record holds {P_all} whole period(s) of {N} samples ({N / fs:g} s) and {drop} are "
                        f"transient; σ from the scatter between periods needs at least 2 steady periods "
                        f"(record at least {(drop + 2) * N / fs:g} s)")
    U, Y = U[drop:], Y[drop:]
    with np.errstate(divide="ignore", invalid="ignore"):
        Suy = np.einsum("pf,pof->of", U.conj(), Y)
        if estimator == "h1":
            H = Suy / np.sum(np.abs(U)**2, axis=0)[None]
        else:
            H = np.sum(np.abs(Y)**2, axis=0) / Suy.conj()
    sl, sp, coh = phasor_scatter(U, Y, H, pooled=True)
    names, units = channel_names(output_names, output_units, len(ys), "output")
    settings = {"fs_hz": fs, "period_samples": N, "period_s": N / fs, "window": "none (whole periods)",
                "periods_in_record": P_all, "transient_periods": drop,
                "transient": "found from the period scatter" if auto else "given", "periods_used": P,
                "lines": k.size, "coherence_threshold": round(coherence_threshold(P), 4)}
    return FRFEstimate(k * fs / N, H, NEPER_TO_DB * sl, np.degrees(sp), coh, np.full(k.size, P),
                       f"periodic_{estimator}", input_name, input_unit, names, units, settings)
