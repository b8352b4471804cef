"""The automatic preview: the smallest ``T_p`` whose truncation error on the signal at hand is below
a stated tolerance of the full inverse.

Truncating the anticausal part to ``N`` samples changes the output by exactly (see
:mod:`inversion._discrete`)

    e_N[k] = y_N[k] - y_inf[k] = -(C_r Phi**N) x[k+N],

``x`` the anticausal first-order-hold state of the sampled signal (zero beyond the record).  In the
eigenbasis of ``Phi`` (``Phi = V diag(lam) V^-1``, ``z = V^-1 x``, ``w = C_r V``) this is
``e_N[k] = -Re sum_i w_i lam_i**N z_i[k+N]``: once the modal states ``z_i`` are computed (one
first-order recursion per mode), the exact error of any preview costs a few vector operations,
and ``sum_i |w_i| |lam_i|**N max|z_i|`` is a bound on it that decreases monotonically with ``N``.
:func:`choose_preview` takes the first ``N`` where that bound meets the tolerance, then bisects
(scanning down from it first in steps shorter than the modes' decay time and oscillation
half-period) with the exact error down to the ``N`` that meets it while ``N - 1`` does not; every
scanned longer preview meets it too.  When the
eigenbasis is ill-conditioned (repeated zeros), the exact errors come from one filter pass per
candidate instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.signal as sig

from ._discrete import FOHFilter, Plan, foh_matrices
from ._errors import InversionError, PreviewError
from .split import InverseSplit

__all__ = ["PreviewChoice", "TruncationModes", "choose_preview", "preview_rule", "resolve_preview", "RULE_4_OVER_R0"]

#: Largest condition number of the eigenvector matrix for the modal evaluation.
_MAX_COND = 1e8


#: Default tolerance of the automatic preview: truncation error relative to the full inverse.
DEFAULT_PREVIEW_TOL = 1e-3


def frequency_preview(split: InverseSplit, tol: float = DEFAULT_PREVIEW_TOL, *,
                      omega_max: float, omega_min: float | None = None,
                      n_omega: int = 256) -> tuple[float, float]:
    """Smallest preview whose truncation error is below ``tol`` for every sinusoid in a band.

    Signal-independent rule (used where the signal is not known in advance: streaming,
    bounded-memory and scheduled inversion): the smallest ``T`` on a grid of step
    ``0.05/r0`` such that, for it and every longer grid preview,

        max_w |E_T(j w)| / |H(j w)|  <=  tol      for w in {0} U [omega_min, omega_max],

    with ``E_T`` the discarded part of the anticausal kernel
    (:meth:`InverseSplit.truncation_response`) and ``H`` the full inverse.  By Parseval the
    same ratio bounds the L2 truncation error of any signal in the band relative to the L2
    norm of its full inverse (edge transients of the record aside).

    Parameters
    ----------
    split : InverseSplit
    tol : float
        Relative tolerance (> 0).
    omega_max : float
        Top of the band [rad/s] (e.g. the Nyquist frequency ``pi/dt``).
    omega_min : float, optional
        Bottom of the logarithmic part of the band [rad/s]; default ``1e-3 min(|zeros|)``.
    n_omega : int
        Frequencies on the logarithmic grid.

    Returns
    -------
    (preview_s, bound) : (float, float)
        The preview [s] and the relative error bound it achieves (0 for minimum phase).
    """
    if not (isinstance(tol, float | int) and math.isfinite(tol) and tol > 0):
        raise InversionError(f"preview tolerance must be a positive number; got {tol!r}")
    if split.n_unstable == 0:
        return 0.0, 0.0
    zmag = np.abs(split.zeros[np.abs(split.zeros) > 0])
    lo = float(omega_min) if omega_min is not None else 1e-3 * float(np.min(zmag))
    hi = float(omega_max)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise InversionError(f"frequency band must satisfy 0 < omega_min < omega_max; got {lo!r}, {hi!r}")
    w = np.concatenate(([0.0], np.logspace(math.log10(lo), math.log10(hi), n_omega)))
    H = np.abs(split.frequency_response(w))
    keep = H > 1e-12 * float(np.max(H))           # a zero of H (pole of G) carries no signal
    w, H = w[keep], H[keep]
    step = 0.05 / split.r0
    T = step * np.arange(2001)                    # up to 100/r0 (exp(-100) of the kernel)
    ratio = np.max(np.abs(split._truncation_terms(T, w)) / H, axis=1)
    bad = np.flatnonzero(ratio > tol)
    if bad.size == 0:
        return 0.0, float(ratio[0])
    i = int(bad[-1]) + 1
    if i >= T.size:
        raise InversionError(
            f"no finite preview up to 100/r0 = {T[-1]:.4g} s brings the truncation error below "
            f"{tol:g} of the inverse (best {ratio[-1]:.3g}); use preview='inf'")
    return float(T[i]), float(np.max(ratio[i:]))



#: Names of the 4/r0 rule (seed paper 000's Zou-Devasia choice), kept for its experiments.
RULE_4_OVER_R0 = ("4/r0", "4/r_0", "zou-devasia")
_INF_NAMES = ("inf", "infinite", "infinity", "none")


def preview_rule(preview: Any) -> str:
    """``"auto"``, ``"4/r0"``, ``"inf"`` or ``"fixed"`` for a ``preview`` argument."""
    if preview is None:
        return "inf"
    if isinstance(preview, str):
        key = preview.strip().lower()
        if key == "auto":
            return "auto"
        if key in RULE_4_OVER_R0:
            return "4/r0"
        if key in _INF_NAMES:
            return "inf"
    try:
        if math.isinf(float(preview)):
            return "inf"
    except (TypeError, ValueError):
        pass
    return "fixed"


def resolve_preview(preview: Any, split_or_auto: InverseSplit | float, dt: float,
                    n_samples: int | None = None, *,
                    tol: float = DEFAULT_PREVIEW_TOL) -> tuple[int | None, float]:
    """Turn a ``preview`` argument into ``(samples or None, seconds)`` without looking at a signal.

    Parameters
    ----------
    preview : "auto", "4/r0", "inf", None, float
        ``"auto"``: the signal-independent tolerance rule :func:`inversion.preview.frequency_preview`
        over ``[0, pi/dt]`` (the smallest preview whose truncation error is below ``tol`` of
        the inverse for every sinusoid up to the Nyquist frequency; :func:`invert` instead
        chooses it for the signal at hand); ``"4/r0"``: the Zou–Devasia rule of seed paper 000
        (too short for large anticausal residues, e.g. the seed 001 actuator surrogates);
        ``"inf"``, ``None`` or ``math.inf``: infinite preview; a number: preview [s] (>= 0).
    split_or_auto : InverseSplit or float
        Split, or an automatic preview already chosen by the caller [s] (used for both
        ``"auto"`` and ``"4/r0"``).
    dt : float
        Sampling interval [s].  The preview is rounded to ``round(preview/dt)`` samples.
    n_samples : int, optional
        Record length; a numeric or 4/r0 preview longer than the record (``N > n_samples - 1``)
        is an error; an automatic preview is capped at the record (where it equals ``inf``).
    tol : float
        Relative truncation tolerance of ``"auto"``.
    """
    rule = preview_rule(preview)
    if rule == "inf":
        return None, math.inf
    split = split_or_auto if isinstance(split_or_auto, InverseSplit) else None
    if rule == "auto":
        if split is None:
            seconds = float(split_or_auto)
        else:
            seconds, _ = frequency_preview(split, tol, omega_max=math.pi / dt)
    elif rule == "4/r0":
        seconds = split.auto_preview_s if split is not None else float(split_or_auto)
    else:
        try:
            seconds = float(preview.strip() if isinstance(preview, str) else preview)
        except (TypeError, ValueError):
            raise PreviewError(
                f"preview must be 'auto', '4/r0', 'inf' or a number of seconds; got {preview!r}") from None
    if math.isnan(seconds) or seconds < 0:
        raise PreviewError(f"preview must be >= 0 seconds (or 'auto'/'4/r0'/'inf'); got {preview!r}")
    n = int(round(seconds / dt))
    if n_samples is not None and n > n_samples - 1:
        if rule == "auto":   # the whole record ahead: identical to the infinite preview
            return n_samples - 1, (n_samples - 1) * dt
        raise PreviewError(
            f"preview {seconds:.6g} s ({n} samples at dt = {dt:.6g} s"
            f"{', the 4/r0 rule' if rule == '4/r0' else ''})"
            f" is longer than the record ({n_samples} samples = {(n_samples - 1) * dt:.6g} s); "
            "use a longer record, a shorter preview, or preview='auto' or 'inf'")
    return n, n * dt


class TruncationModes:
    """Exact truncation errors ``e_N = y_N - y_inf`` of one sampled signal, for any preview ``N``.

    Parameters
    ----------
    split : InverseSplit
    dt : float
        Sampling interval [s].
    u : ndarray
        The (validated, finite, 1-D) signal.
    """

    def __init__(self, split: InverseSplit, dt: float, u: np.ndarray):
        self.n = u.size
        self.u = u
        self.split_tail = lambda N: split.tail_l1_norm(N * dt)
        Phi, al, be = foh_matrices(-split.A_u, split.B_u, dt)
        self.Phi, self.al, self.be, self.Cr = Phi, al, be, -split.C_u
        lam, V = np.linalg.eig(Phi)
        self.modal = bool(np.isfinite(np.linalg.cond(V)) and np.linalg.cond(V) < _MAX_COND)
        if self.modal:
            Vi = np.linalg.inv(V)
            a, b = Vi @ al, Vi @ be
            ur = u[::-1]
            # z_i[k] = lam_i z_i[k+1] + a_i u[k] + b_i u[k+1], run over the reversed record and
            # kept reversed (zr[:, j] = z[:, n-1-j]) to avoid copies
            self.zr = np.empty((lam.size, self.n), complex)
            for i in range(lam.size):
                self.zr[i] = sig.lfilter([a[i], b[i]], [1.0, -lam[i]], ur)
            self.lam, self.w = lam, self.Cr @ V
            self._zmax = {"linf": np.max(np.abs(self.zr), axis=1),
                          "l2": np.sqrt(np.sum(np.abs(self.zr) ** 2, axis=1))}

    def error(self, N: int) -> np.ndarray:
        """``y_N - y_inf`` [output units] for a preview of ``N`` samples."""
        N = int(N)
        out = np.zeros(self.n)
        if N >= self.n:
            return out
        if self.modal:
            c = self.w * self.lam ** N
            out[:self.n - N] = -np.real(c @ self.zr[:, :self.n - N])[::-1]
            return out
        C2 = self.Cr @ np.linalg.matrix_power(self.Phi, N)
        if np.any(C2):
            f = FOHFilter.build(self.Phi, self.al, self.be, C2)
            out[:self.n - N] = -f.run(self.u[::-1], f.zi0())[0][::-1][N:]
        return out

    def bound(self, N: int, norm: str) -> float | None:
        """A bound on ``size(e_N)`` that does not increase with ``N`` (None without the modal form)."""
        if not self.modal:
            return None
        return float(np.sum(np.abs(self.w) * self._zmax[norm] * np.abs(self.lam) ** float(N)))

    def first_bounded(self, target: float, norm: str) -> int:
        """Smallest ``N`` whose bound is <= ``target`` (``n - 1`` if none); bisection on the
        monotone bound (the L1 tail of the kernel times max|u| without the modal form)."""
        def b(N: int) -> float:
            v = self.bound(N, norm)
            if v is None:
                v = float(self.split_tail(N)) * float(np.max(np.abs(self.u)))
                if norm == "l2":
                    v *= math.sqrt(self.n)
            return v

        if b(0) <= target:
            return 0
        lo, hi = 0, self.n - 1
        if b(hi) > target:
            return hi
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if b(mid) <= target:
                hi = mid
            else:
                lo = mid
        return hi


@dataclass(frozen=True)
class PreviewChoice:
    """How an automatic preview was chosen for one signal (see :func:`choose_preview`).

    Attributes
    ----------
    samples : int
        Preview [samples].
    seconds : float
        Preview [s].
    tolerance : float
        Requested bound on the truncation error relative to the full inverse.
    norm : str
        ``"linf"`` (max |e| / max |y_inf|) or ``"l2"`` (||e||_2 / ||y_inf||_2).
    relative_error : float
        Achieved truncation error in that norm (exact for the sampled signal).
    max_error : float
        Largest absolute truncation error [output units].
    tail_bound : float
        Signal-independent bound ``tail_l1_norm(T) * max|u|`` [output units].
    rule_4_over_r0_s : float
        What the 4/r0 rule would have chosen [s], for comparison.
    """

    samples: int
    seconds: float
    tolerance: float
    norm: str
    relative_error: float
    max_error: float
    tail_bound: float
    rule_4_over_r0_s: float


def choose_preview(split: InverseSplit, dt: float, u: Any, *, tol: float = DEFAULT_PREVIEW_TOL,
                   norm: str = "linf", checked: bool = False) -> PreviewChoice:
    """Smallest preview whose exact truncation error on the signal ``u`` is below ``tol``.

    The error of a preview of ``N`` samples (``e_N = y_N - y_inf``) is measured relative to the
    full (infinite-preview) inverse ``y_inf`` in the chosen norm.  The returned ``N`` meets the
    tolerance and ``N - 1`` does not (or ``N = 0``); a record too short for any shorter preview
    gets ``N = len(u) - 1``, which equals the infinite preview.

    Parameters
    ----------
    split : InverseSplit
    dt : float
        Sampling interval [s].
    u : array_like
        The signal to invert.
    tol : float
        Tolerance on the relative truncation error (> 0).
    norm : {"linf", "l2"}
    checked : bool
        ``u`` and ``dt`` were already validated (internal use).
    """
    if not (isinstance(tol, float | int) and math.isfinite(tol) and tol > 0):
        raise PreviewError(f"preview_tol must be a positive number; got {tol!r}")
    if norm not in ("linf", "l2"):
        raise PreviewError(f"preview_norm must be 'linf' or 'l2'; got {norm!r}")
    if not checked:
        from .batch import _signal, sampling_interval

        u = _signal(u)
        dt = sampling_interval(dt)
    ua = np.asarray(u, dtype=float)
    n = ua.size
    if split.n_unstable == 0:
        return PreviewChoice(0, 0.0, float(tol), norm, 0.0, 0.0, 0.0, 0.0)

    def size(e: np.ndarray) -> float:
        return float(np.max(np.abs(e))) if norm == "linf" else float(np.sqrt(np.dot(e, e)))

    plan = Plan(split, dt, None)
    y_inf = np.empty(n)
    plan.forward(ua, n, n, lambda c0, c1, y, _x: y_inf.__setitem__(slice(c0, c1), y), check=False)
    plan.backward(ua, n, n, lambda c0, c1, y, _x: y_inf.__setitem__(slice(c0, c1), y_inf[c0:c1] + y))
    ref = size(y_inf)
    umax = float(np.max(np.abs(ua)))
    if ref == 0.0:
        return PreviewChoice(0, 0.0, float(tol), norm, 0.0, 0.0, 0.0, split.auto_preview_s)
    modes = TruncationModes(split, dt, ua)
    target = tol * ref
    # upper end: the monotone modal bound (or the kernel's L1 tail) meets the tolerance
    hi = modes.first_bounded(target, norm)
    memo: dict[int, np.ndarray] = {}

    def err(N: int) -> np.ndarray:
        if N not in memo:
            memo[N] = modes.error(N)
        return memo[N]

    if size(err(hi)) > target:               # the bound is exact-or-larger; only rounding gets here
        hi = n - 1
    # scan down from the bound in steps shorter than the decay time and the oscillation
    # half-period of the anticausal modes (so no pocket where a longer preview fails again is
    # stepped over), then bisect to the sample
    rates = split.unstable_poles
    scale = min(0.25 / split.r0, 0.25 * math.pi / max(float(np.max(np.abs(rates.imag))), 1e-300))
    step = max(1, int(scale / dt))
    lo = None
    while lo is None:
        cand = hi - step
        if cand < 0:
            lo = -1 if size(err(0)) > target else None
            if lo is None:
                hi, lo = 0, -1
        elif size(err(cand)) <= target:
            hi = cand
        else:
            lo = cand
    while hi - lo > 1:                       # lo fails (or is -1), hi meets the tolerance
        mid = (lo + hi) // 2
        if size(err(mid)) <= target:
            hi = mid
        else:
            lo = mid
    N = hi
    e = err(N)
    return PreviewChoice(
        samples=N, seconds=N * dt, tolerance=float(tol), norm=norm, relative_error=size(e) / ref,
        max_error=float(np.max(np.abs(e))), tail_bound=float(split.tail_l1_norm(N * dt)) * umax,
        rule_4_over_r0_s=split.auto_preview_s)
