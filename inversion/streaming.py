"""Streaming finite-preview inversion with a fixed delay and history-independent cost.

:class:`StreamingInverter` consumes chunks of any size and emits the finite-preview inverse
delayed by exactly ``N = round(T_p/dt)`` samples (plus the stencil half-width in the
``"differentiate"`` mode, see :attr:`StreamingInverter.delay_samples`).  Its output equals
:func:`inversion.invert` with the same preview up to floating-point rounding.

How the anticausal part is computed causally
--------------------------------------------
The truncated anticausal output at sample k depends only on the inputs ``u[k .. k+N]``
(see :mod:`inversion._discrete`):

    y_u[k] = C_r (x[k] - Phi^N x[k+N]) = sum_{q=0}^{N} taps[q] u[k+q],

where ``x`` is the backward FOH state of *any* record that contains ``u[k .. k+N]`` (the
difference of the two sums is the window sum, whatever lies beyond).  So once ``u[k+N]`` has
arrived, output k is computed from the retained inputs, in one of three ways, whichever is
cheapest for the L outputs a push makes final:

* the (N+1)-tap kernel ``taps`` applied directly (``L·(N+1)`` below :data:`KERNEL_WORK`; a
  one-sample push is one dot product);
* the batch finite-preview pass of :meth:`inversion._discrete.Plan.anticausal` over the
  segment ``u[k_lo .. k_hi+N)`` taken as a record of its own (large chunks: the same filters
  as :func:`~inversion.invert` on the chunk plus N samples);
* block sums (long previews, N > :data:`BLOCK_RATIO` · L): with the time axis cut into
  blocks of N samples, for k in block j (``jN <= k < a = (j+1)N``)

      F_k = S_k + Phi^(a-k) R_(k-jN),
      S_k = sum_{i=k}^{a-1} Phi^(i-k) g_i,   R_p = sum_{i=0}^{p-1} Phi^i g_(a+i),

  one backward pass per block and a running sum as samples arrive (the "two-stack" sliding
  window), O(n_u^2) per sample; only decaying powers of ``Phi``, so every step is stable.

The causal part (stable filter with its carried state, feedthrough, finite differences) runs
as in the batch inverse; a one-sample push steps the filter state in plain Python instead of
calling ``scipy.signal.lfilter``.  The cost per sample is independent of the history, and the
retained state is at most the current block, the delay and one chunk of inputs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ._discrete import Plan, left_powers
from ._errors import InversionError, NonFiniteSignalError, PreviewError
from .preview import resolve_preview
from .signals import as_split, sampling_interval

__all__ = ["StreamingInverter"]

#: The (N+1)-tap kernel is applied directly when outputs × (N+1) is below this many
#: multiply-adds.
KERNEL_WORK = 1 << 15
#: Above this ratio of preview to outputs per push (and from ``MIN_BLOCK`` samples of preview
#: on), the two-stack block sums are cheaper than the batch pass over chunk + N samples.
BLOCK_RATIO = 2
MIN_BLOCK = 32
#: Initial capacity of the sample buffers (they grow for larger chunks).
BUFFER = 1 << 12


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
        self.dt = sampling_interval(dt)
        self.split = as_split(model, improper, filter_bandwidth, self.dt)
        n_prev, prev_s = resolve_preview(preview, self.split, self.dt)
        if n_prev is None:
            raise PreviewError(
                f"a streaming inverter needs a finite preview (seconds or 'auto'); got {preview!r}")
        self.preview_samples: int = n_prev
        self.preview_s: float = prev_s
        self._plan = p = Plan(self.split, self.dt, n_prev)
        #: output delay [samples]: the preview, or the finite-difference half-width if larger
        self.delay_samples: int = max(n_prev, p.h)
        h, d = p.h, self.delay_samples
        # the anticausal kernel: y_u[k] = sum_q anti_taps[q] u[k+q], q = 0..N
        self._anti_taps = None
        self._blocks_ok = False
        if p.anti is not None:
            N = n_prev
            rows = left_powers(p.anti_C, p.anti_phi, N + 1)        # C_r Phi^q
            taps = np.zeros(N + 1)
            taps[:N] += rows[:N] @ p.anti_alpha
            taps[1:] += rows[:N] @ p.anti_beta
            self._anti_taps = taps
            if N >= MIN_BLOCK:
                self._blocks_ok = True
                self._Wr = rows                                      # C_r Phi^q
                self._Wa = rows @ p.anti_alpha                       # C_r Phi^q alpha
                self._Pa = left_powers(p.anti_alpha, p.anti_phi.T, N)   # Phi^i alpha
                self._Pb = left_powers(p.anti_beta, p.anti_phi.T, N)    # Phi^i beta
        # one kernel for a single output: anticausal taps and the difference stencil over
        # the window u[k-h .. k+delay]
        kern = np.zeros(h + d + 1)
        if self._anti_taps is not None:
            kern[h:h + n_prev + 1] += self._anti_taps
        if h:
            kern[:2 * h + 1] += p.kernel
        self._kernel = kern if np.any(kern) else None
        # the stable filter for one-sample steps (transposed direct form II, as lfilter)
        self._step_ba = self._step_sos = None
        if p.stable is not None:
            if p.stable.kind == "ba":
                b, a = p.stable.b / p.stable.a[0], p.stable.a / p.stable.a[0]
                n = max(a.size, b.size)
                self._step_ba = (np.pad(b, (0, n - b.size)).tolist(), np.pad(a, (0, n - a.size)).tolist())
            else:
                self._step_sos = [(r[:3] / r[3]).tolist() + (r[3:] / r[3]).tolist() for r in p.stable.sos]
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

    def _keep(self) -> int:
        """Index of the oldest input later outputs still need (the block start for the
        block sums)."""
        keep = self._n_out - self._plan.h
        if self._blocks_ok:
            N = self.preview_samples
            keep = min(keep, (self._n_out // N) * N)
        return max(keep, self._base)

    @property
    def _hist(self) -> np.ndarray:
        """Retained inputs (those later outputs still need), a view."""
        return self._u[self._keep() - self._base:self._n_in - self._base]

    @property
    def _ys(self) -> np.ndarray:
        """Causal part of the outputs not yet emitted, a view."""
        return self._y[self._n_out - self._base:self._n_in - self._base]

    def reset(self) -> None:
        """Forget all history (start a new signal)."""
        h = self._plan.h
        self._n_in = 0
        self._n_out = 0
        self._closed = False
        # inputs (and causal outputs) of sample k live at index k - base; the h samples
        # before the signal are zeros (for the difference stencil)
        self._base = -h
        self._u = np.zeros(max(BUFFER, 4 * (self.delay_samples + h + 1)))
        self._y = np.zeros_like(self._u)
        st = self._plan.stable
        self._zi = st.zi0() if st is not None else None    # lfilter/sosfilt state (array)
        self._zl = None                                      # the same state as a list
        self._reset_blocks()

    def _reset_blocks(self) -> None:
        """Forget the running sums of the block in progress (recomputed from its start)."""
        self._S: np.ndarray | None = None
        self._R = np.zeros(self._plan.anti_phi.shape[0])
        self._p_last = 0

    # ------------------------------------------------------------------------------------
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
        x = np.asarray(chunk, dtype=float)
        if x.size == 1:
            v = x.item()
            if not math.isfinite(v):
                raise NonFiniteSignalError(
                    f"the signal must be finite; sample {self._n_in} (chunk index 0) is {v!r}")
            return self._consume_one(v)
        x = x.ravel()
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
    def _room(self, count: int) -> int:
        """Make space for ``count`` more samples; return the buffer index of the next one."""
        pos = self._n_in - self._base
        if pos + count <= self._u.size:
            return pos
        keep = self._keep()                          # the oldest sample still needed
        live = self._n_in - keep
        size = max(BUFFER, 4 * (self.delay_samples + self._plan.h + 1), 2 * (live + count))
        if size > self._u.size or size < self._u.size // 4:
            u, y = np.zeros(size), np.zeros(size)
        else:
            u, y = self._u, self._y
        s = keep - self._base
        u[:live] = self._u[s:s + live]
        y[:live] = self._y[s:s + live]
        self._u, self._y, self._base = u, y, keep
        return live

    def _consume_one(self, v: float) -> np.ndarray:
        """One sample: the stable filter stepped in plain Python, one kernel dot product."""
        pos = self._room(1)
        self._u[pos] = v
        p = self._plan
        if self._step_ba is not None or self._step_sos is not None:
            z = self._zl
            if z is None:
                z = self._zl = [float(c) for c in np.ravel(self._zi)]
                self._zi = None
            if self._step_ba is not None:
                b, a = self._step_ba
                y = b[0] * v + z[0]
                n = len(z)
                for i in range(n - 1):
                    z[i] = z[i + 1] + b[i + 1] * v - a[i + 1] * y
                z[n - 1] = b[n] * v - a[n] * y
            else:
                y = v
                for k, (b0, b1, b2, _, a1, a2) in enumerate(self._step_sos):
                    xi = y
                    y = b0 * xi + z[2 * k]
                    z[2 * k] = b1 * xi - a1 * y + z[2 * k + 1]
                    z[2 * k + 1] = b2 * xi - a2 * y
        else:
            y = p.D * v
        self._y[pos] = y
        self._n_in += 1
        k = self._n_out
        if self._n_in - self.delay_samples <= k:
            return np.zeros(0)
        out = self._y[k - self._base]
        if self._S is not None or self._p_last:
            self._reset_blocks()
        if self._kernel is not None:
            w0 = k - p.h - self._base
            out += float(self._kernel @ self._u[w0:w0 + self._kernel.size])
        self._n_out = k + 1
        return np.array([out])

    def _consume(self, x: np.ndarray) -> np.ndarray:
        p = self._plan
        if x.size:
            pos = self._room(x.size)
            self._u[pos:pos + x.size] = x
            if p.stable is not None:
                if self._zl is not None:
                    zi = np.asarray(self._zl, float)
                    self._zi, self._zl = zi.reshape(p.stable.zi0().shape), None
                ys, self._zi = p.stable.run(x, self._zi)   # includes D * x
            else:
                ys = p.D * x
            self._y[pos:pos + x.size] = ys
            self._n_in += x.size
        k_lo, k_hi = self._n_out, self._n_in - self.delay_samples
        if k_hi <= k_lo:
            return np.zeros(0)
        b = self._base
        out = self._y[k_lo - b:k_hi - b].copy()
        n_out = k_hi - k_lo
        if p.h:
            out += np.correlate(self._u[k_lo - p.h - b:k_hi + p.h - b], p.kernel, mode="valid")
        taps = self._anti_taps
        if taps is not None:
            seg = self._u[k_lo - b:k_hi + taps.size - 1 - b]
            if n_out * taps.size <= KERNEL_WORK:
                out += np.correlate(seg, taps, mode="valid")
                self._reset_blocks()
            elif self._blocks_ok and taps.size - 1 > BLOCK_RATIO * n_out:
                out += self._blocks(k_lo, k_hi)
            else:
                self._add_anticausal(seg, out)
                self._reset_blocks()
        self._n_out = k_hi
        return out

    def _add_anticausal(self, seg: np.ndarray, out: np.ndarray) -> None:
        """``out += plan.anticausal(seg)[:out.size]`` (the same values), added block by block as the
        backward pass makes them, without the segment-sized array of the anticausal part."""
        n_out = out.size

        def add(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
            if c0 < n_out:
                hi = min(c1, n_out)
                out[c0:hi] += y[:hi - c0]

        self._plan.backward(seg, seg.size, max(seg.size, 1), add)

    # -- the two-stack block sums ---------------------------------------------------------
    def _ur(self, lo: int, hi: int) -> np.ndarray:
        """Retained inputs [lo, hi) (lo >= 0)."""
        return self._u[lo - self._base:hi - self._base]

    def _blocks(self, k_lo: int, k_hi: int) -> np.ndarray:
        """Anticausal outputs k_lo .. k_hi-1 from the block sums (module doc of the old
        block method: F_k = S_k + Phi^(a-k) R_(k-jN), both pieces with decaying powers)."""
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
        u = self._ur(k, k + (nb + 1) * N)            # blocks + the following block
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
        base = (k // N) * N
        a = base + N
        if self._S is None:
            seg = self._ur(base, a + 1)                # N + 1 samples, u_a last
            o, _ = p.anti.run(seg[::-1], p.anti.zi0())
            o = o[::-1]
            self._S = o[:N] - Wa[N:0:-1] * seg[N]      # C_r S_k = o'_k - C_r Phi^(a-k) alpha u_a
        P_lo, P_hi = k - base, k_end - base
        # R_p for p in [p_last, P_hi - 1]
        i0, i1 = self._p_last, P_hi - 1
        if i1 > i0:
            useg = self._ur(a + i0, a + i1 + 1)
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
            self._reset_blocks()
        return out
