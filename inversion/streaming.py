"""Streaming finite-preview inversion with a fixed delay and history-independent cost.

:class:`StreamingInverter` consumes chunks of any size and emits the finite-preview inverse
delayed by exactly ``N = round(T_p/dt)`` samples (plus the stencil half-width in the
``"differentiate"`` mode, see :attr:`StreamingInverter.delay_samples`).  Its output equals
:func:`inversion.invert` with the same preview up to floating-point rounding.

How the anticausal part is computed causally
--------------------------------------------
The truncated anticausal state at sample k is (see :mod:`inversion._discrete`)

    F_k = sum_{i=k}^{k+N-1} Phi^(i-k) g_i,     g_i = alpha u_i + beta u_{i+1},

an exponentially weighted window sum.  Updating it forward in time needs ``Phi^-1`` and is
numerically unstable.  Instead the time axis is cut into blocks of N samples; for k in block
j (``jN <= k < a = (j+1)N``)

    F_k = S_k + Phi^(a-k) R_(k-jN),
    S_k     = sum_{i=k}^{a-1} Phi^(i-k) g_i          (backward pass over block j, once per block)
    R_p     = sum_{i=0}^{p-1} Phi^i g_(a+i)          (running sum over block j+1, as samples arrive)

(the "two-stack" sliding-window trick).  Both pieces use only decaying powers of ``Phi``, so
every operation is stable, and each input sample enters one backward pass and one running
sum: the cost per sample is O(n_u^2), independent of the history and of N.  For short
previews (``N < 32``) the exact (N+1)-tap FIR form of the truncated kernel is used instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._discrete import Plan
from ._errors import InversionError, NonFiniteSignalError, PreviewError
from .batch import _as_split, resolve_preview, sampling_interval

__all__ = ["StreamingInverter"]

#: Below this preview (in samples) the truncated kernel is applied as an FIR filter.
FIR_MAX_TAPS = 32


def _left_powers(row: np.ndarray, Phi: np.ndarray, count: int) -> np.ndarray:
    """Rows ``row @ Phi**q`` for q = 0..count-1 (by doubling)."""
    out = np.empty((count, row.size))
    if count == 0:
        return out
    out[0] = row
    filled, P = 1, Phi
    while filled < count:
        m = min(filled, count - filled)
        out[filled:filled + m] = out[:m] @ P
        filled += m
        P = P @ P
    return out


def _right_powers(vec: np.ndarray, Phi: np.ndarray, count: int) -> np.ndarray:
    """Rows ``Phi**i @ vec`` for i = 0..count-1 (by doubling)."""
    return _left_powers(vec, Phi.T, count)


class StreamingInverter:
    """Finite-preview stable inverse that consumes chunks and emits delayed output.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, (num, den) or InverseSplit
        Proper continuous-time SISO model ``G(s)`` (s in rad/s).
    dt : float
        Sampling interval [s].
    preview : "auto" or float
        Preview time [s] (``"auto"`` = ``4/r0``); must be finite.
    improper : {"error", "filter", "differentiate"}
        See :func:`inversion.split_inverse`.
    filter_bandwidth : float, optional
        [rad/s], for ``improper="filter"``.

    Examples
    --------
    >>> inv = StreamingInverter(model, dt=1e-3)            # doctest: +SKIP
    >>> out = [inv.push(chunk) for chunk in chunks]         # doctest: +SKIP
    >>> out.append(inv.flush())                             # doctest: +SKIP
    >>> y = np.concatenate(out)   # == invert(model, dt, u, preview="auto").output

    Notes
    -----
    ``push`` returns the samples whose output is now final: after ``n`` input samples in
    total, outputs ``0 .. n - 1 - delay_samples`` have been emitted.  ``flush`` declares the
    end of the signal (zeros afterwards, as in the batch inverse) and returns the rest.
    """

    def __init__(self, model: Any, dt: float, preview: Any = "auto", *, improper: str = "error",
                 filter_bandwidth: float | None = None):
        self.split = _as_split(model, improper, filter_bandwidth)
        self.dt = sampling_interval(dt)
        n_prev, prev_s = resolve_preview(preview, self.split, self.dt)
        if n_prev is None:
            raise PreviewError(
                f"a streaming inverter needs a finite preview (seconds or 'auto'); got {preview!r}")
        self.preview_samples: int = n_prev
        self.preview_s: float = prev_s
        self._plan = Plan(self.split, self.dt, n_prev)
        #: output delay [samples]: the preview, or the finite-difference half-width if larger
        self.delay_samples: int = max(n_prev, self._plan.h)
        self._mode = "none"
        p = self._plan
        if p.anti is not None:
            N = n_prev
            Phi, al, be, Cr = p.anti_phi, p.anti_alpha, p.anti_beta, p.anti_C
            if N < FIR_MAX_TAPS:
                self._mode = "fir"
                rows = _left_powers(Cr, Phi, N + 1)  # C_r Phi^q, q = 0..N
                taps = np.zeros(N + 1)
                taps[:N] += rows[:N] @ al
                taps[1:] += rows[:N] @ be
                self._taps = taps
            else:
                self._mode = "blocks"
                self._Wr = _left_powers(Cr, Phi, N + 1)        # C_r Phi^q
                self._Wa = self._Wr @ al                       # C_r Phi^q alpha
                self._Pa = _right_powers(al, Phi, N)           # Phi^i alpha
                self._Pb = _right_powers(be, Phi, N)           # Phi^i beta
        self.reset()

    # ------------------------------------------------------------------------------------
    @property
    def r0(self) -> float:
        """Real part of the least unstable inverse pole [1/s]."""
        return self.split.r0

    @property
    def delay_s(self) -> float:
        """Output delay [s]."""
        return self.delay_samples * self.dt

    @property
    def samples_in(self) -> int:
        """Number of samples pushed so far."""
        return self._n_in

    @property
    def samples_out(self) -> int:
        """Number of output samples emitted so far."""
        return self._n_out

    def reset(self) -> None:
        """Forget all history (start a new signal)."""
        p = self._plan
        self._n_in = 0
        self._n_out = 0
        self._closed = False
        self._end: int | None = None
        self._hist = np.zeros(0)
        self._hist0 = 0
        self._zi = p.stable.zi0() if p.stable is not None else None
        self._ys = np.zeros(0)   # causal part for indices [n_out, n_in)
        n_u = p.anti_phi.shape[0]
        self._S: np.ndarray | None = None
        self._R = np.zeros(n_u)
        self._p_last = 0

    def push(self, chunk: Any) -> np.ndarray:
        """Consume samples; return the newly final output samples (possibly none).

        Parameters
        ----------
        chunk : array_like
            Next input samples (1-D, finite) [model output units].

        Returns
        -------
        ndarray
            Output for sample indices ``samples_out_before .. samples_out_after - 1``
            [model input units].
        """
        if self._closed:
            raise InversionError("the stream was flushed; call reset() before pushing again")
        x = np.asarray(chunk, dtype=float).ravel()
        if x.size and not np.all(np.isfinite(x)):
            i = int(np.flatnonzero(~np.isfinite(x))[0])
            raise NonFiniteSignalError(
                f"the signal must be finite; sample {self._n_in + i} (chunk index {i}) is {x[i]!r}")
        return self._consume(x)

    def flush(self) -> np.ndarray:
        """End the signal (zeros afterwards) and return the remaining output samples."""
        if self._closed:
            return np.zeros(0)
        end = self._n_in
        out = self._consume(np.zeros(self.delay_samples))
        self._closed = True
        return out[:max(0, end - (self._n_out - out.size))]

    # ------------------------------------------------------------------------------------
    def _consume(self, x: np.ndarray) -> np.ndarray:
        p = self._plan
        if x.size:
            if self._zi is not None:
                ys, self._zi = p.stable.run(x, self._zi)
            else:
                ys = p.D * x
            self._ys = np.concatenate((self._ys, ys))
            self._hist = np.concatenate((self._hist, x))
            self._n_in += x.size
        k_lo, k_hi = self._n_out, self._n_in - self.delay_samples
        if k_hi <= k_lo:
            return np.zeros(0)
        out = self._ys[:k_hi - k_lo].copy()
        if p.h:
            out += self._deriv(k_lo, k_hi)
        if self._mode == "fir":
            N = self.preview_samples
            seg = self._u(k_lo, k_hi + N)
            out += np.correlate(seg, self._taps, mode="valid")
        elif self._mode == "blocks":
            out += self._blocks(k_lo, k_hi)
        self._n_out = k_hi
        self._ys = self._ys[k_hi - k_lo:]
        # trim history to what later outputs still need
        keep = k_hi - p.h
        if self._mode == "blocks":
            N = self.preview_samples
            keep = min(keep, (k_hi // N) * N)
        keep = max(keep, 0)
        if keep > self._hist0:
            self._hist = self._hist[keep - self._hist0:]
            self._hist0 = keep
        return out

    def _u(self, lo: int, hi: int) -> np.ndarray:
        """Input samples [lo, hi) with zeros before index 0."""
        if lo >= self._hist0:
            return self._hist[lo - self._hist0:hi - self._hist0]
        pad = np.zeros(self._hist0 - lo)
        return np.concatenate((pad, self._hist[:hi - self._hist0]))

    def _deriv(self, k_lo: int, k_hi: int) -> np.ndarray:
        h = self._plan.h
        seg = self._u(k_lo - h, k_hi + h)
        return np.correlate(seg, self._plan.kernel, mode="valid")

    def _blocks(self, k_lo: int, k_hi: int) -> np.ndarray:
        N = self.preview_samples
        pieces = []
        k = k_lo
        # a block already started (partially emitted): continue it incrementally
        if k % N or self._S is not None or self._p_last:
            k_end = min(k_hi, (k // N + 1) * N)
            pieces.append(self._one_block(k, k_end))
            k = k_end
        # whole blocks, vectorised in groups of at most ~64k samples
        group = max(1, (1 << 16) // N)
        while k_hi - k >= N:
            nb = min((k_hi - k) // N, group)
            pieces.append(self._whole_blocks(k, nb))
            k += nb * N
        if k < k_hi:
            pieces.append(self._one_block(k, k_hi))
        return np.concatenate(pieces) if len(pieces) > 1 else pieces[0]

    def _whole_blocks(self, k: int, nb: int) -> np.ndarray:
        """Outputs of ``nb`` complete blocks starting at the block boundary ``k``."""
        p = self._plan
        N = self.preview_samples
        u = self._u(k, k + (nb + 1) * N)            # blocks + the following block
        win = np.lib.stride_tricks.sliding_window_view(u, N + 1)[: nb * N: N]  # (nb, N+1)
        o = p.anti.run_rows(np.ascontiguousarray(win[:, ::-1]))[:, ::-1]
        S = o[:, :N] - self._Wa[N:0:-1][None, :] * win[:, N:N + 1]
        nxt = u[N:].reshape(nb, N)                  # u_{a+i}, i = 0..N-1, per block
        terms = (self._Pa[None, :N - 1, :] * nxt[:, :N - 1, None]
                 + self._Pb[None, :N - 1, :] * nxt[:, 1:, None])
        R = np.zeros((nb, N, terms.shape[2]))
        np.cumsum(terms, axis=1, out=R[:, 1:, :])
        tail = np.einsum("pj,bpj->bp", self._Wr[N - np.arange(N)], R)
        return (S + tail).ravel()

    def _one_block(self, k: int, k_end: int) -> np.ndarray:
        """Outputs k .. k_end-1 inside one block, keeping the running state of that block."""
        p = self._plan
        N = self.preview_samples
        Wr, Wa, Pa, Pb = self._Wr, self._Wa, self._Pa, self._Pb
        j = k // N
        base = j * N
        a = base + N
        if self._S is None:
            seg = self._u(base, a + 1)                 # N + 1 samples, u_a last
            o, _ = p.anti.run(seg[::-1], p.anti.zi0())
            o = o[::-1]
            self._S = o[:N] - Wa[N:0:-1] * seg[N]      # C_r S_k = o'_k - C_r Phi^(a-k) alpha u_a
        P_lo, P_hi = k - base, k_end - base
        # R_p for p in [p_last, P_hi - 1]
        i0, i1 = self._p_last, P_hi - 1
        if i1 > i0:
            useg = self._u(a + i0, a + i1 + 1)
            terms = Pa[i0:i1] * useg[:-1, None] + Pb[i0:i1] * useg[1:, None]
            Rs = np.vstack((self._R, self._R + np.cumsum(terms, axis=0)))
        else:
            Rs = self._R[None, :]
        sel = Rs[P_lo - i0:]
        ps = np.arange(P_lo, P_hi)
        tail = np.einsum("ij,ij->i", Wr[N - ps], sel)
        out = self._S[P_lo:P_hi] + tail
        self._R = Rs[-1].copy()
        self._p_last = max(i1, i0)
        if k_end == a:
            self._S = None
            self._R = np.zeros_like(self._R)
            self._p_last = 0
        return out
