"""Second-order-section forms of the FOH filters: the sections fallback of a single filter
and the factored fused finite-preview pass (see :mod:`inversion._discrete`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.signal as sig

__all__ = ["FusedPass", "sos_sections"]


def sos_sections(Phi: np.ndarray, Bd: np.ndarray, C: np.ndarray, Dd: float, zs: np.ndarray,
         exact: np.ndarray) -> np.ndarray:
    """Second-order sections of the discrete system ``(Phi, Bd, C, Dd)``: poles the eigenvalues of
    ``Phi``, zeros the finite generalised eigenvalues of the Rosenbrock pencil, gain matched to
    ``exact`` (the response at the points ``zs``) where the product form is largest."""
    n = Phi.shape[0]
    poles = np.linalg.eigvals(Phi)
    pencil_a = np.block([[Phi, Bd.reshape(n, 1)], [C.reshape(1, n), np.array([[Dd]])]])
    pencil_b = np.zeros((n + 1, n + 1))
    pencil_b[:n, :n] = np.eye(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        zz = sla.eigvals(pencil_a, pencil_b)
    zeros = zz[np.isfinite(zz) & (np.abs(zz) < 1e8)]
    zeros = _conjugate_clean(zeros)
    poles = _conjugate_clean(poles)
    prod = np.prod(zs[:, None] - zeros, axis=1) / np.prod(zs[:, None] - poles, axis=1)
    i = int(np.argmax(np.abs(prod)))
    k = float(np.real(exact[i] / prod[i]))
    if k == 0.0:
        return np.array([[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]])
    return np.ascontiguousarray(sig.zpk2sos(zeros, poles, k))


def _all_pole_sections(poles: np.ndarray) -> np.ndarray:
    """Second-order sections ``1/((1 - p z^-1)(1 - p' z^-1))`` of the given poles: conjugate
    pairs together, real poles in pairs (one first-order section if their number is odd)."""
    upper = [p for p in poles if p.imag > 0]
    real = sorted(p.real for p in poles if p.imag == 0)
    rows = [[1.0, 0.0, 0.0, 1.0, -2.0 * p.real, abs(p) ** 2] for p in upper]
    for i in range(0, len(real) - 1, 2):
        rows.append([1.0, 0.0, 0.0, 1.0, -(real[i] + real[i + 1]), real[i] * real[i + 1]])
    if len(real) % 2:
        rows.append([1.0, 0.0, 0.0, 1.0, -real[-1], 0.0])
    return np.array(rows, dtype=float)


def _conjugate_clean(r: np.ndarray) -> np.ndarray:
    """Make nearly-real roots exactly real so that zpk2sos pairs conjugates cleanly."""
    r = np.asarray(r, complex).copy()
    small = np.abs(r.imag) <= 1e-12 * np.maximum(1.0, np.abs(r))
    r[small] = r[small].real
    return r


@dataclass
class FusedPass:
    """The finite-preview backward pass as FIR correlations and one all-pole recursion.

    ``q[k] = (b1 * u)[k] - (b2 * u)[k + N]`` (correlations, forward time), then the all-pole
    filter ``1/a`` runs over ``q`` reversed.  Two forms:

    * transfer function: ``fir1 = [b1]``, ``fir2 = [b2]``, ``a`` the common denominator;
    * factored (:meth:`factored`, when either FOH filter needed second-order sections): the
      common poles as an all-pole cascade of sections (``sos``), and each numerator as one
      polynomial or, if that is not accurate enough, as its second-order factors applied one
      after the other (``fir1``, ``fir2``: lists of kernels).  It is the denominator whose
      coefficients lose accuracy when the poles cluster near z = 1 (fast sampling): as
      sections each pole stays exact.  One ``sosfilt`` pass costs about one ``lfilter``
      pass, so the fused pass is kept at 20 kHz (it was replaced by two second-order-section
      passes before, 0.26× lfilter instead of 0.31–0.35×).
    """

    fir1: list
    fir2: list
    a: np.ndarray | None
    sos: np.ndarray | None

    @staticmethod
    def reach(fir: list) -> int:
        return int(sum(f.size - 1 for f in fir))

    @staticmethod
    def correlate(x: np.ndarray, fir: list) -> np.ndarray:
        for f in fir:
            x = np.correlate(x, f, "valid")
        return x

    def zi0(self) -> np.ndarray:
        if self.sos is None:
            return np.zeros(self.a.size - 1)
        return np.zeros((self.sos.shape[0], 2))

    def all_pole(self, x: np.ndarray, zi: np.ndarray):
        if self.sos is None:
            return sig.lfilter(np.ones(1), self.a, x, zi=zi)
        return sig.sosfilt(self.sos, x, zi=zi)

    @classmethod
    def factored(cls, f1, f2) -> FusedPass | None:
        """Factored form for two FOH filters with the same state matrix, or None when their
        factored responses do not reproduce the exact ones (checked as in ``FOHFilter``)."""
        sos = _all_pole_sections(_conjugate_clean(np.linalg.eigvals(f1.Phi)))
        firs = []
        theta = np.pi * np.concatenate((np.logspace(-7, 0, 36), [0.0]))
        zs = np.exp(1j * theta)
        zinv = 1.0 / zs
        den = np.prod([np.polyval(r[3:][::-1], zinv) for r in sos], axis=0)
        for f in (f1, f2):
            exact = f.response(zs)
            num_sos = f.sos if f.sos is not None else sos_sections(f.Phi, f.Phi @ f.alpha + f.beta, f.C, f.D, zs, exact)
            fir = [np.trim_zeros(np.asarray(r[:3], float), "b") for r in num_sos]
            fir = [k if k.size else np.zeros(1) for k in fir]
            # the zeros' sections carry their own denominators (the same poles): divide out
            # the poles of those rows and keep only the numerators, overall gain in the first
            gain = np.prod([r[3] for r in num_sos])
            fir[0] = fir[0] / gain
            merged = fir[0]
            for k in fir[1:]:
                merged = np.convolve(merged, k)
            scale = float(np.max(np.abs(exact)))
            tol = 1e-10 * np.maximum(np.abs(exact), 1e-3 * scale)
            # one correlation with the whole numerator is cheapest; its factors, if needed
            for cand in ([merged], fir):
                num = np.prod([np.polyval(k[::-1], zinv) for k in cand], axis=0)
                if np.all(np.abs(num / den - exact) <= tol):
                    firs.append(cand)
                    break
            else:
                return None
        return cls(firs[0], firs[1], None, np.ascontiguousarray(sos))
