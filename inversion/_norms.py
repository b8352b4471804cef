"""Impulse-response norms of state-space parts of an inverse (L1 by quadrature of |C e^{At} B|)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["abs_impulse", "expm_small", "l1_norm", "propagate", "to_tf"]


def to_tf(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> Any:
    """``C (sI - A)^-1 B`` as a ``control.TransferFunction`` (None for an empty block)."""
    if A.shape[0] == 0:
        return None
    import control
    import scipy.signal as sig

    b, a = sig.ss2tf(A, B.reshape(-1, 1), C.reshape(1, -1), np.zeros((1, 1)))
    return control.tf(np.atleast_1d(b[0]), a)


def expm_small(A: np.ndarray) -> np.ndarray:
    """Matrix exponential of a small dense matrix: Taylor scaling and squaring, matmuls only.

    ``A`` is scaled by ``2**-s`` to 1-norm <= 1, the degree-20 Taylor polynomial is
    evaluated by Horner's rule (truncation error <= e/21! ~ 5e-20 relative) and squared ``s``
    times.  Against 40-digit ``mpmath.expm`` it is as accurate as ``scipy.linalg.expm`` on the
    FOH matrices of the inverses and on random 2x2..5x5 matrices (largest error 7e-14 of the
    largest entry, vs 2e-11 for scipy's Pade).  It is used instead of ``scipy.linalg.expm``
    because it calls no LAPACK routine: with a threaded OpenBLAS, the LU factorisation inside
    the Pade step wakes the BLAS worker threads, which then busy-wait and, on a machine whose
    other cores are busy, halve the speed of the filtering that follows (measured: the whole
    inversion ran 2x slower; ``scipy.linalg.expm`` of a 3x3 matrix took 4 ms that way, most of
    the automatic streaming preview).
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    eye = np.eye(n)
    if n == 0:
        return eye
    norm = float(np.max(np.sum(np.abs(A), axis=0)))
    s = int(np.ceil(np.log2(norm))) if norm > 1.0 else 0
    X = A / 2.0 ** s
    E = eye.copy()
    for k in range(20, 0, -1):
        E = eye + (X @ E) / k
    for _ in range(s):
        E = E @ E
    return E


def abs_impulse(M: np.ndarray, B: np.ndarray, C: np.ndarray) -> tuple[float, np.ndarray]:
    """``(step, |C exp(M t_i) B|)`` on a uniform grid ``t_i = i*step`` covering the response
    of a stable ``M`` down to ``exp(-40)`` of its slowest mode."""
    n = M.shape[0]
    lam = np.linalg.eigvals(M)
    slow = float(np.min(-lam.real))
    fast = float(np.max(np.abs(lam)))
    horizon = 40.0 / slow  # exp(-40) ~ 4e-18 of the slowest mode (times polynomial growth)
    step = min(0.02 / fast, horizon / 2000.0)
    n_steps = int(min(max(np.ceil(horizon / step), 2000), 400_000))
    step = horizon / n_steps
    Phi = expm_small(M * step)
    # propagate x(t) = exp(M t) B on the grid in blocks of powers (vectorised doubling)
    xs = np.empty((n_steps + 1, n))
    xs[0] = B
    filled = 1
    P = Phi
    while filled < n_steps + 1:
        m = min(filled, n_steps + 1 - filled)
        xs[filled:filled + m] = xs[:m] @ P.T
        filled += m
        P = P @ P
    return step, np.abs(xs @ C)


def propagate(M: np.ndarray, B: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Rows ``exp(M T_i) B`` (0 for infinite ``T_i``).  A uniform grid starting at 0 is filled by
    repeated multiplication with one ``exp(M step)`` (vectorised doubling); otherwise one matrix
    exponential per entry."""
    n = M.shape[0]
    out = np.zeros((T.size, n))
    fin = np.isfinite(T)
    Tf = T[fin]
    if Tf.size > 2 and Tf[0] == 0.0 and np.allclose(np.diff(Tf), Tf[1], rtol=1e-12, atol=0.0):
        xs = np.empty((Tf.size, n))
        xs[0] = B
        filled, P = 1, expm_small(M * Tf[1])
        while filled < Tf.size:
            m = min(filled, Tf.size - filled)
            xs[filled:filled + m] = xs[:m] @ P.T
            filled += m
            P = P @ P
        out[fin] = xs
    else:
        out[fin] = np.stack([expm_small(M * Ti) @ B for Ti in Tf]) if Tf.size else np.zeros((0, n))
    return out


def l1_norm(M: np.ndarray, B: np.ndarray, C: np.ndarray) -> float:
    """``int_0^inf |C exp(M t) B| dt`` for a stable ``M`` (trapezoid on a fine grid)."""
    if M.shape[0] == 0:
        return 0.0
    step, h = abs_impulse(M, B, C)
    return float(step * (h.sum() - 0.5 * (h[0] + h[-1])))
