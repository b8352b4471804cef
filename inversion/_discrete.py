"""Exact first-order-hold (FOH) discretisation of the split inverse and the filter engine.

Signal model
------------
The sampled signal ``u[k] = u(k dt)`` is taken to be the piecewise-linear interpolant of its
samples, with ``u[k] = 0`` outside the record (so the record is joined to zero by one-sample
ramps at both ends).  For a stable continuous block ``x' = M x + B u, y = C x`` driven by such
a signal the state at the sample instants obeys exactly

    x[k] = Phi x[k-1] + alpha u[k] + beta u[k-1],
    Phi   = exp(M dt),
    alpha = int_0^dt exp(M tau) (1 - tau/dt) d tau  B,
    beta  = int_0^dt exp(M tau) tau/dt d tau  B,

(computed together from one matrix exponential of an (n+2)x(n+2) matrix, see
:func:`expm_small`).  Written with the shifted state ``xi = x - alpha u`` it is the ordinary
discrete system ``(Phi, Phi alpha + beta, C, C alpha)``, run with ``scipy.signal.lfilter``.
The causal stable part runs this forward; the anticausal part
``x_u(t) = int_t^inf exp(-A_u (t'-t)) B_u u(t') dt'`` is the same recursion with
``M = -A_u`` run over the time-reversed samples — piecewise-linear interpolation commutes
with time reversal, so both parts are exact for the same continuous signal.  The only
discretisation error is therefore the interpolation error of the input,
``|u - u_interp| <= dt**2/8 max|u''|``, which reaches the output through the strictly proper
parts only (feedthrough and polynomial terms are applied at the samples):

    |error| <= (||h_s||_1 + ||h_u||_1) * dt**2/8 * max|u''|

(for a sinusoid of angular frequency w that is a relative error of about (w dt)**2/12 on
the strictly proper parts).

Finite preview
--------------
Truncating eq. (6) of seed paper 000 to ``[t, t + N dt]`` gives exactly

    x_bar[k] = x[k] - Phi**N x[k+N]

so the truncated anticausal output is ``C_r x[k] - (C_r Phi**N) x[k+N]``: two passes of the
same reversed recursion with output rows ``C_r`` and ``C_r Phi**N``, the second advanced by N
samples.  ``x[j] = 0`` for ``j >= len(u)`` (the signal is zero beyond the record).

Both passes share the denominator ``a(z)`` (the poles of ``Phi``); only their numerators
``b1`` (row ``C_r``) and ``b2`` (row ``C_r Phi**N``) differ.  When both are run as
transfer-function pairs the batch pass is therefore fused into one recursion,

    y_u = (1/a) [b1 * u_rev  -  z**-N b2 * u_rev],

i.e. in forward time ``q[k] = sum_i b1[i] u[k+i] - sum_i b2[i] u[k+N+i]`` (two short
correlations) followed by a single backward all-pole pass, block by block so that the
intermediate ``q`` stays in cache (:data:`FUSED_BLOCK`).  Same polynomials as the two
separate passes; the results agree to rounding.  When the poles cluster near z = 1 (fast
sampling) and the denominator polynomial of ``ss2tf`` is not accurate enough, the poles are
factored into second-order sections (:class:`FusedPass`, :mod:`inversion._sections`); the
all-pole pass then runs as one polynomial re-expanded from those sections in extended precision
and rounded to the best doubles, if that and its running rounding stay within 1e-10 and the
cascade amplifies nothing more than a constant, so that a step probes the worst case of that
rounding (one ``lfilter``: the seed 000 sensor at 20 kHz), else as the
sections (``sosfilt``, ~1.3 ns/sample slower: at 50 kHz and above, or a resonant anticausal
part), with the same correlations in front; only if that, too, fails the accuracy check are the
two passes run separately as sections.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal as sig

from ._norms import expm_small
from ._sections import FusedPass, sos_sections
from .split import InverseSplit

__all__ = ["foh_matrices", "expm_small", "FOHFilter", "FusedPass", "Plan", "plan_for", "pass_errstate",
           "central_difference_kernel", "left_powers", "FUSED_BLOCK", "PLAN_CACHE_SIZE"]

#: Samples per block of the fused finite-preview backward pass (intermediates stay in cache).
FUSED_BLOCK = 1 << 16

#: Plans kept per split (the most recently built ones, by sampling interval and preview).
PLAN_CACHE_SIZE = 8


def foh_matrices(M: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``(Phi, alpha, beta)`` of the exact FOH recursion ``x[k] = Phi x[k-1] + alpha u[k] + beta u[k-1]``.

    Parameters
    ----------
    M : (n, n) ndarray
        Continuous state matrix [1/s].
    B : (n,) ndarray
        Input vector.
    dt : float
        Sampling interval [s].
    """
    n = M.shape[0]
    big = np.zeros((n + 2, n + 2))
    big[:n, :n] = M * dt
    big[:n, n] = B * dt
    big[n, n + 1] = 1.0
    E = expm_small(big)
    Phi = E[:n, :n]
    J0 = E[:n, n]          # int_0^dt exp(M tau) d tau B
    alpha = E[:n, n + 1]   # int_0^dt exp(M tau) (1 - tau/dt) d tau B
    beta = J0 - alpha      # int_0^dt exp(M tau) tau/dt d tau B
    return Phi, alpha, beta


@dataclass
class FOHFilter:
    """Scalar output ``y[k] = C x[k] + D_extra u[k]`` of the FOH recursion, as a linear filter.

    The discrete system is ``(Phi, Phi alpha + beta, C, C alpha + D_extra)``.  Two
    realizations are built and checked against the exact state-space frequency response on
    a logarithmic grid of the unit circle (down to 1e-7 of the Nyquist frequency):

    * a transfer-function pair run with ``scipy.signal.lfilter`` (fastest), used when its
      largest relative deviation is below ``1e-10``;
    * otherwise second-order sections run with ``scipy.signal.sosfilt``: poles are the
      eigenvalues of ``Phi``, zeros the finite generalised eigenvalues of the Rosenbrock
      pencil.  A single high-order polynomial loses accuracy when the poles cluster near
      z = 1 (``|lambda| dt`` small): at 500 kHz sampling the 35 degC sensor inverse lost
      three orders of magnitude that way.
    """

    Phi: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    C: np.ndarray
    D: float
    b: np.ndarray | None
    a: np.ndarray | None
    sos: np.ndarray | None

    @classmethod
    def build(cls, Phi: np.ndarray, alpha: np.ndarray, beta: np.ndarray, C: np.ndarray,
              D_extra: float = 0.0) -> FOHFilter:
        n = Phi.shape[0]
        Bd = Phi @ alpha + beta
        Dd = float(C @ alpha) + float(D_extra)
        zs = _TEST_POINTS
        exact = _exact_response(Phi, Bd, C, Dd, zs)
        bb, aa = sig.ss2tf(Phi, Bd.reshape(n, 1), C.reshape(1, n), np.array([[Dd]]))
        b = np.atleast_1d(np.asarray(bb, float)[0])
        a = np.asarray(aa, float)
        if _tf_accurate(b, a, zs, exact):
            return cls(Phi=Phi, alpha=alpha, beta=beta, C=C, D=Dd, b=b, a=a, sos=None)
        sos = sos_sections(Phi, Bd, C, Dd, zs, exact)
        return cls(Phi=Phi, alpha=alpha, beta=beta, C=C, D=Dd, b=None, a=None, sos=sos)

    def with_row(self, C2: np.ndarray) -> FOHFilter:
        """The filter of the same recursion with the output row ``C2`` (no extra feedthrough).

        The transfer-function numerator is linear in the output row, so it is formed as
        ``sum_i C2[i] b_i`` from the numerators ``b_i`` of the unit rows (one ``ss2tf`` with
        ``C = I``), over this filter's denominator: its error scales with ``C2``.  ``ss2tf`` of
        ``C2`` itself subtracts polynomials of order one to get a numerator of the size of
        ``C2``; for the truncated kernel's row ``C_r Phi**N`` of a long preview (``|C2|`` 1.6e-3
        of ``|C_r|``) that lost the 1e-10 accuracy checked here, and the filter fell back to
        second-order sections: the fused finite-preview pass then ran ``sosfilt`` instead of
        ``lfilter`` (the automatic previews at 1 and 5 kHz of the seed 000 sensor).  The result is
        checked as in :meth:`build` and built by :meth:`build` if it fails.
        """
        n = self.order
        C2 = np.asarray(C2, dtype=float)
        if self.sos is None and n:
            Bd = self.Phi @ self.alpha + self.beta
            D2 = float(C2 @ self.alpha)
            zs = _TEST_POINTS
            exact = _exact_response(self.Phi, Bd, C2, D2, zs)
            basis = np.asarray(sig.ss2tf(self.Phi, Bd.reshape(n, 1), np.eye(n), self.alpha.reshape(n, 1))[0],
                               float)
            b = C2 @ basis
            if _tf_accurate(b, self.a, zs, exact):
                return FOHFilter(Phi=self.Phi, alpha=self.alpha, beta=self.beta, C=C2, D=D2, b=b, a=self.a,
                                 sos=None)
        return FOHFilter.build(self.Phi, self.alpha, self.beta, C2)

    @property
    def order(self) -> int:
        return int(self.Phi.shape[0])

    def response(self, zs: np.ndarray) -> np.ndarray:
        """Exact frequency response ``C (zI - Phi)^-1 Bd + Dd`` at the points ``zs``."""
        return _exact_response(self.Phi, self.Phi @ self.alpha + self.beta, self.C, self.D, zs)

    @property
    def kind(self) -> str:
        """``"ba"`` (lfilter) or ``"sos"`` (sosfilt)."""
        return "ba" if self.sos is None else "sos"

    def zi0(self) -> np.ndarray:
        if self.sos is None:
            return np.zeros(max(self.a.size, self.b.size) - 1)
        return np.zeros((self.sos.shape[0], 2))

    def run(self, x: np.ndarray, zi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.sos is None:
            return sig.lfilter(self.b, self.a, x, zi=zi)
        return sig.sosfilt(self.sos, x, zi=zi)

    def run_rows(self, X: np.ndarray) -> np.ndarray:
        """Filter every row of ``X`` from zero initial state."""
        if self.sos is None:
            return sig.lfilter(self.b, self.a, X, axis=1)
        return sig.sosfilt(self.sos, X, axis=1)


#: Points of the unit circle where a realization is checked against the exact response: a
#: logarithmic grid down to 1e-7 of the Nyquist frequency, and z = 1.
_TEST_POINTS = np.exp(1j * np.pi * np.concatenate((np.logspace(-7, 0, 36), [0.0])))


def _exact_response(Phi: np.ndarray, Bd: np.ndarray, C: np.ndarray, Dd: float, zs: np.ndarray) -> np.ndarray:
    """``C (zI - Phi)^-1 Bd + Dd`` at the points ``zs`` (one batched solve)."""
    n = Phi.shape[0]
    rhs = np.broadcast_to(Bd.astype(complex)[:, None], (zs.size, n, 1))
    return np.linalg.solve(zs[:, None, None] * np.eye(n) - Phi, rhs)[..., 0] @ C + Dd


def _tf_accurate(b: np.ndarray, a: np.ndarray, zs: np.ndarray, exact: np.ndarray) -> bool:
    """The transfer function ``b/a`` (ascending powers of 1/z) is within 1e-10 of ``exact`` at ``zs``,
    relative to each value or, where it is far below the largest, to 1e-3 of the largest."""
    zinv = 1.0 / zs
    tf_val = np.polyval(b[::-1], zinv) / np.polyval(a[::-1], zinv)
    ref = np.maximum(np.abs(exact), 1e-300)
    scale = float(np.max(np.abs(exact)))
    return bool(np.all(np.abs(tf_val - exact) <= 1e-10 * np.maximum(ref, 1e-3 * scale)))


def left_powers(row: np.ndarray, Phi: np.ndarray, count: int) -> np.ndarray:
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


def central_difference_kernel(coeffs: np.ndarray, dt: float) -> tuple[np.ndarray, int]:
    """Correlation kernel applying ``sum_k coeffs[k-1] d^k/dt^k`` with O(dt**2) central differences.

    The k-th derivative uses the minimal symmetric stencil of half-width ``ceil(k/2)``
    (3 points for k = 1, 2; 5 points for k = 3, 4; ...), whose truncation error is
    ``O(dt**2 max|u^(k+2)|)``.

    Returns
    -------
    kernel : ndarray, length 2h+1
        ``out[k] = sum_j kernel[j] u[k - h + j]``.
    h : int
        Half-width (number of future samples needed).
    """
    r = coeffs.size
    if r == 0:
        return np.zeros(1), 0
    h = (r + 1) // 2
    kernel = np.zeros(2 * h + 1)
    for k in range(1, r + 1):
        c = coeffs[k - 1]
        if c == 0:
            continue
        hk = (k + 1) // 2
        offs = np.arange(-hk, hk + 1, dtype=float)
        # solve sum_j w_j offs_j^q / q! = delta_{qk}, q = 0..2hk
        V = np.vander(offs, 2 * hk + 1, increasing=True).T
        rhs = np.zeros(2 * hk + 1)
        rhs[k] = float(np.prod(np.arange(1, k + 1)))
        w = np.linalg.solve(V, rhs)
        kernel[h - hk:h + hk + 1] += c * w / dt**k
    return kernel, h


class Plan:
    """Discretised inverse for one sampling interval and one preview.

    Parameters
    ----------
    split : InverseSplit
    dt : float
        Sampling interval [s].
    n_preview : int or None
        Preview in samples; ``None`` for infinite preview.
    """

    def __init__(self, split: InverseSplit, dt: float, n_preview: int | None):
        self.split = split
        self.dt = float(dt)
        self.n_preview = n_preview
        self.D = float(split.feedthrough)
        self.kernel, self.h = central_difference_kernel(split.derivative_coefficients, self.dt)
        self.stable: FOHFilter | None = None
        if split.n_stable:
            Phi, al, be = foh_matrices(split.A_s, split.B_s, self.dt)
            # the feedthrough D is exact at the samples: fold it into the stable filter
            self.stable = FOHFilter.build(Phi, al, be, split.C_s, D_extra=self.D)
        self.anti: FOHFilter | None = None
        self.anti_tail: FOHFilter | None = None
        self.anti_phi = np.zeros((0, 0))
        self.anti_alpha = self.anti_beta = self.anti_C = np.zeros(0)
        if split.n_unstable and (n_preview is None or n_preview > 0):
            Phi, al, be = foh_matrices(-split.A_u, split.B_u, self.dt)
            Cr = -split.C_u
            self.anti_phi, self.anti_alpha, self.anti_beta, self.anti_C = Phi, al, be, Cr
            self.anti = FOHFilter.build(Phi, al, be, Cr)
            if n_preview is not None:
                C2 = Cr @ np.linalg.matrix_power(Phi, n_preview)
                if np.any(C2 != 0):
                    self.anti_tail = self.anti.with_row(C2)
        #: the fused finite-preview backward pass (:class:`FusedPass`), or None (module doc)
        self.fused: FusedPass | None = None
        t1, t2 = self.anti, self.anti_tail
        if t1 is not None and t2 is not None:
            if (t1.sos is None and t2.sos is None and t1.a.size == t2.a.size
                    and np.array_equal(t1.a, t2.a)):
                p = max(t1.b.size, t2.b.size)
                b1 = np.zeros(p)
                b1[:t1.b.size] = t1.b
                b2 = np.zeros(p)
                b2[:t2.b.size] = t2.b
                self.fused = FusedPass([b1], [b2], np.array(t1.a, dtype=float), None)
            else:
                self.fused = FusedPass.factored(t1, t2)

    # -- chunked passes -------------------------------------------------------------------
    def forward(self, src: Any, n: int, chunk: int, sink: Any, check: bool = True) -> None:
        """Causal pass: call ``sink(c0, c1, causal_part, u_chunk)`` chunk by chunk.

        ``check`` verifies that every chunk is finite (skip it when the caller already did).
        """
        zi = self.stable.zi0() if self.stable is not None else None
        h = self.h
        for c0 in range(0, n, chunk):
            c1 = min(n, c0 + chunk)
            x = _read(src, c0, c1, check)
            if zi is not None:
                y, zi = self.stable.run(x, zi)   # includes D * x
            else:
                y = self.D * x
            if h:
                lo, hi = max(0, c0 - h), min(n, c1 + h)
                ext = np.zeros(c1 - c0 + 2 * h)
                ext[lo - (c0 - h):hi - (c0 - h)] = _read(src, lo, hi, False)
                y += np.correlate(ext, self.kernel, mode="valid")
            sink(c0, c1, y, x)

    def backward(self, src: Any, n: int, chunk: int, sink: Any) -> None:
        """Anticausal pass: call ``sink(c0, c1, anticausal_part, u_chunk)`` from the end backwards.

        Does nothing (never calls ``sink``) when there is no anticausal part.
        """
        if self.anti is None:
            return
        if self.fused is not None:
            self._backward_fused(src, n, max(1, min(int(chunk), FUSED_BLOCK)), sink)
            return
        N = self.n_preview
        zi1 = self.anti.zi0()
        tail_f = self.anti_tail
        zi2 = tail_f.zi0() if tail_f is not None else None
        tail = np.zeros(N) if (tail_f is not None and N) else None  # o2 at [c1, c1+N)
        for c1 in range(n, 0, -chunk):
            c0 = max(0, c1 - chunk)
            L = c1 - c0
            x = _read(src, c0, c1, False)
            xr = x[::-1]
            o1r, zi1 = self.anti.run(xr, zi1)
            yu = o1r[::-1]
            if tail_f is not None:
                # yu[k] -= o2[k + N]; o2 of this chunk is o2r reversed, later ones are in `tail`
                o2r, zi2 = tail_f.run(xr, zi2)
                o2 = o2r[::-1]
                if N < L:
                    yu[:L - N] -= o2[N:]
                    yu[L - N:] -= tail
                    tail = o2[:N].copy()
                else:
                    yu -= tail[N - L:]
                    tail = np.concatenate((o2, tail[:N - L]))
            sink(c0, c1, yu, x)

    def causal(self, ua: np.ndarray, chunk: int) -> np.ndarray:
        """The causal part (feedthrough, polynomial part, ``H_s``) of the in-memory record ``ua``
        (the same for every preview), ``chunk`` samples at a time."""
        n = ua.size
        parts: dict[str, Any] = {}
        if chunk >= n:
            # single chunk: keep the filter output itself, no copy
            def put_s(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
                parts["s"] = y
        else:
            parts["s"] = np.empty(n)

            def put_s(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
                parts["s"][c0:c1] = y

        self.forward(ua, n, chunk, put_s, check=False)
        return parts["s"]

    def run(self, ua: np.ndarray, chunk: int, stable: np.ndarray | None = None,
            keep_unstable: bool = True, output_sum: list[float] | None = None,
            keep_stable: bool = True) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray]:
        """``(stable, unstable, output)`` of this plan's inverse of the in-memory record ``ua``,
        ``chunk`` samples at a time.  ``stable``: the causal part if it was already computed
        (it does not depend on the preview), else computed here.

        ``keep_unstable=False``: when the backward pass runs block by block (chunked, or the
        fused finite-preview pass) the anticausal part is not kept (``unstable`` is None):
        only ``output`` is written, which saves one record-sized array (writing it into fresh
        memory was a sixth to a fifth of a finite-preview inversion of 2**21 samples, measured).
        :meth:`anticausal` with the same ``chunk`` recomputes it bit for bit.

        ``output_sum``: a list to which the sum of ``output`` is appended (a finite sum proves
        every sample finite); on the block-wise path it is summed block by block while each
        block is in cache, instead of reading the whole output once more.

        ``keep_stable=False`` (with ``keep_unstable=False``): on the block-wise path the output is
        written over the causal part's array (``stable``, the caller's if given), which is then
        not returned (None): one record-sized array fewer, and no fresh memory to fault in for
        it.  :meth:`run` with ``keep_unstable=True`` and the same ``chunk`` recomputes both parts
        bit for bit (``stable + unstable`` is what was written), and on the block-wise path its
        ``output_sum`` is summed in the same blocks and order, so it equals the first pass's sum
        bit for bit when the input is the same (a fingerprint of the input that does not read
        ``output`` again, see :attr:`inversion.InversionResult.stable_part`).
        """
        n = ua.size
        if stable is None:
            stable = self.causal(ua, chunk)
        if self.anti is None:
            return stable, np.zeros(n), _summed(stable.copy(), output_sum)
        if chunk >= n and self.fused is None:
            # one whole-record backward pass: keep its output itself
            whole: list[np.ndarray] = []
            self.backward(ua, n, chunk, lambda c0, c1, y, _x: whole.append(y))
            return stable, whole[0], _summed(stable + whole[0], output_sum)
        # block by block (chunked, or the fused finite-preview pass): write the results while
        # the block is in cache
        in_place = not (keep_unstable or keep_stable)
        output = stable if in_place else np.empty(n)
        unstable = None if not keep_unstable else np.empty(n)
        total = [0.0]

        def put(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
            # the same additions and block sums whether the anticausal part is kept or not: the
            # recomputation (keep_unstable=True) reproduces the first pass's output_sum bit for bit
            if unstable is not None:
                unstable[c0:c1] = y
            o = output[c0:c1]
            np.add(stable[c0:c1], y, out=o)
            if output_sum is not None:
                with np.errstate(over="ignore", invalid="ignore"):
                    total[0] += float(np.add.reduce(o))

        self.backward(ua, n, chunk, put)
        if output_sum is not None:
            output_sum.append(total[0])
        return (None if in_place else stable), unstable, output

    def anticausal(self, u: np.ndarray, chunk: int | None = None) -> np.ndarray:
        """Anticausal part for the in-memory record ``u`` (zero beyond its end), as an array,
        ``chunk`` samples at a time (default: the whole record) — with the ``chunk`` given to
        :meth:`run`, the same values bit for bit as the ``unstable`` it returns.

        With a finite preview, output k depends only on ``u[k .. k+N]``, so the first
        ``len(u) - N`` values are exact whatever follows the record (the streaming inverter
        relies on this)."""
        n = u.size
        out = np.zeros(n)

        def sink(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
            out[c0:c1] = y

        self.backward(u, n, max(n, 1) if chunk is None else int(chunk), sink)
        return out

    def _backward_fused(self, src: Any, n: int, block: int, sink: Any) -> None:
        """Finite-preview anticausal pass as one all-pole recursion (see module doc)."""
        fp = self.fused
        N = self.n_preview
        h1, h2 = fp.reach(fp.fir1), fp.reach(fp.fir2)   # correlation reach beyond the block
        zi = fp.zi0()
        for c1 in range(n, 0, -block):
            c0 = max(0, c1 - block)
            # q[k] = sum_i b1[i] u[k+i] - sum_i b2[i] u[k+N+i], k in [c0, c1), u = 0 past n
            seg = _read_padded(src, n, c0, c1 + h1)
            q = fp.correlate(seg, fp.fir1)
            if c0 + N < n:
                q -= fp.correlate(_read_padded(src, n, c0 + N, c1 + N + h2), fp.fir2)
            w, zi = fp.all_pole(q[::-1], zi)
            sink(c0, c1, w[::-1], seg[:c1 - c0])


def plan_for(split: InverseSplit, dt: float, n_preview: int | None) -> Plan:
    """The :class:`Plan` of ``split`` at ``dt`` and ``n_preview``, built once and kept on the split.

    Building a plan (matrix exponentials, transfer-function and section realizations, their
    accuracy checks) costs about a quarter of one ``lfilter`` pass over 2**21 samples; repeated
    inversions with the same model, sampling interval and preview reuse it.  A plan holds no
    state between passes (the filter states are local to :meth:`Plan.forward` and
    :meth:`Plan.backward`), so sharing it is safe.  The split is immutable; the cache keeps the
    :data:`PLAN_CACHE_SIZE` most recently built plans.
    """
    key = (float(dt), None if n_preview is None else int(n_preview))
    cache = split.__dict__.get("_plan_cache")
    if cache is None:
        cache = {}
        object.__setattr__(split, "_plan_cache", cache)
    plan = cache.get(key)
    if plan is None:
        plan = Plan(split, key[0], key[1])
        if len(cache) >= PLAN_CACHE_SIZE:
            cache.pop(next(iter(cache)), None)
        cache[key] = plan
    return plan


def pass_errstate(quiet: bool) -> contextlib.AbstractContextManager[Any]:
    """numpy's overflow/invalid warnings silenced (``quiet``) or not, for a caller of the passes
    that refuses a non-finite output itself, naming the sample (:func:`inversion.invert`): a
    non-finite input sample, or an overflow, makes ``inf - inf`` and ``D * x`` warn on the way."""
    return np.errstate(over="ignore", invalid="ignore") if quiet else contextlib.nullcontext()


def _summed(output: np.ndarray, output_sum: list[float] | None) -> np.ndarray:
    """``output``, its sum appended to ``output_sum`` if that is a list (see :meth:`Plan.run`)."""
    if output_sum is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            output_sum.append(float(np.add.reduce(output)))
    return output


def _read_padded(src: Any, n: int, lo: int, hi: int) -> np.ndarray:
    """Samples ``[lo, hi)`` of a record of length ``n``, zero beyond its end (``lo >= 0``)."""
    if hi <= n:
        return _read(src, lo, hi, False)
    out = np.zeros(hi - lo)
    if lo < n:
        out[:n - lo] = _read(src, lo, n, False)
    return out


def _read(src: Any, c0: int, c1: int, check: bool) -> np.ndarray:
    x = np.asarray(src[c0:c1], dtype=float)
    if check and not np.all(np.isfinite(x)):
        from ._errors import NonFiniteSignalError

        bad = int(np.flatnonzero(~np.isfinite(x))[0]) + c0
        raise NonFiniteSignalError(
            f"the signal must be finite; sample {bad} is {x[bad - c0]!r} (NaN/inf are not "
            "allowed: fill or interpolate gaps before inverting)")
    return x
