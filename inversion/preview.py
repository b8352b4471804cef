"""The automatic preview: the shortest ``T_p`` whose bound on the truncation error of the signal
at hand is below a stated tolerance of the full inverse.

Truncating the anticausal part to ``N`` samples changes the output by exactly (see
:mod:`inversion._discrete`)

    e_N[k] = y_N[k] - y_inf[k] = -(C_r Phi**N) x[k+N] = -sum_l G_l u[k+N+l],

``x`` the anticausal first-order-hold state of the sampled signal (zero beyond the record) and
``G`` the part of the sampled anticausal kernel beyond the preview.  Hence
``max|e_N| <= ||G||_1 max|u|`` and ``||e_N||_2 <= ||G||_1 ||u||_2``, with ``||G||_1`` (the tail
of the kernel, :func:`discrete_tail_l1`) computed for every ``N`` at once from the powers
``C_r Phi**j`` — no pass over the signal per candidate.  :func:`choose_preview` takes the first
``N`` whose bound is at most the tolerance times a certified size of the full inverse ``y_inf``:
for the max norm a lower bound of ``max|y_inf|`` from the exact values of ``y_inf`` at a few
samples (:func:`reference_lower_bound`, multiply-adds over the kernel, no pass), so
``invert(preview="auto")`` costs the causal pass and the finite-preview anticausal pass of the
chosen preview — what inverting with that preview given costs — plus one pass that reads the signal
(:func:`~inversion.signals.signal_extremes`: its peak, and the proof that it is finite), and the
exact error of ``N`` (one more anticausal pass, plus the full inverse for the relative error) is
computed only when it is read, from the caller's array, checked unchanged (no copy is kept; see
:func:`auto_preview_passes`).  For the l2 norm ``||y_inf||_2`` itself is computed (the full inverse, then one more
anticausal pass for the exact error; the three passes sum to the finite-preview inverse).
The bound is tight for a signal that follows the sign pattern of the kernel's tail; for a
sinusoid it gives away the ratio of the tail's l1 norm to its gain at that frequency, i.e. a
preview one or two slowest-mode time constants longer than the shortest that meets the
tolerance (a shorter error, never a larger one).  A lower bound ``R`` of ``max|y_inf|`` in place
of the peak itself lengthens the preview by ``ln(max|y_inf| / R)`` slowest time constants
(``R`` is within a few per cent of the peak for the smooth and the noisy sines measured).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ._discrete import Plan, left_powers, pass_errstate, plan_for
from ._errors import InversionError, NonFiniteSignalError, PreviewError
from .signals import (
    SignalFingerprint,
    as_signal,
    check_finite,
    check_unchanged,
    sampling_interval,
    signal_extremes,
    signal_fingerprint,
)
from .split import InverseSplit, check_split_for

__all__ = ["PreviewChoice", "AutoPreviewPasses", "auto_preview_passes", "choose_preview", "discrete_tail_l1",
           "reference_lower_bound", "REFERENCE_PROBES",
           "frequency_preview", "preview_rule", "resolve_preview", "truncation_error", "RULE_4_OVER_R0",
           "DEFAULT_PREVIEW_TOL"]

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
    ratio = _preview_ratios(split, T, w, H, tol)
    bad = np.flatnonzero(ratio > tol)
    if bad.size == 0:
        return 0.0, float(ratio[0])
    i = int(bad[-1]) + 1
    if i >= T.size:
        raise InversionError(
            f"no finite preview up to 100/r0 = {T[-1]:.4g} s brings the truncation error below "
            f"{tol:g} of the inverse (best {ratio[-1]:.3g}); use preview='inf'")
    return float(T[i]), float(np.max(ratio[i:]))


def _preview_ratios(split: InverseSplit, T: np.ndarray, w: np.ndarray, H: np.ndarray, tol: float) -> np.ndarray:
    """``max_w |E_T(j w)| / |H(j w)|`` for each ``T``, exactly wherever it can exceed ``tol`` and
    wherever it can be the largest of the previews at and after the first that meets ``tol``;
    elsewhere an upper bound that is at most ``tol`` and at most that largest value, so that
    :func:`frequency_preview` answers as from the exact ratios everywhere.

    ``E_T(j w) = R(w) . V_T`` (:meth:`InverseSplit.truncation_factors`), so by Cauchy-Schwarz
    ``ratio(T) <= c ||V_T||`` with ``c = max_w ||R(w)|| / |H(w)|``: the exact ratio (a row of the
    (previews x frequencies) product) is needed only where that bound exceeds ``tol`` and, after the
    last preview that fails, where it exceeds the largest exact ratio found there (a few hundred of
    the 2001 previews instead of all of them: the product was most of the cost of the automatic
    streaming preview).
    """
    V, R = split.truncation_factors(T, w)

    def exact(rows: np.ndarray) -> np.ndarray:
        return np.max(np.abs(V[rows] @ R.T) / H, axis=1)

    upper = float(np.max(np.linalg.norm(R, axis=1) / H)) * np.linalg.norm(V, axis=1)
    ratio = upper.copy()
    done = upper > tol
    done[0] = True                  # the no-preview ratio is reported when no preview is needed
    rows = np.flatnonzero(done)
    ratio[rows] = exact(rows)
    fail = rows[ratio[rows] > tol]
    first_ok = int(fail[-1]) + 1 if fail.size else 0
    if first_ok < T.size:
        top = float(np.max(ratio[first_ok:], where=done[first_ok:], initial=0.0))
        more = first_ok + np.flatnonzero(~done[first_ok:] & (upper[first_ok:] > top))
        if more.size:
            ratio[more] = exact(more)
    return ratio



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


def truncation_error(split: InverseSplit, dt: float, u: np.ndarray, N: int) -> np.ndarray:
    """``e_N = y_N - y_inf`` [output units] of one sampled signal for a preview of ``N`` samples.

    Exact (module doc): ``e_N[k] = -(C_r Phi**N) x[k+N]``, one pass of the anticausal recursion
    with the output row ``C_r Phi**N`` over ``u[N:]``, negated (zero for ``N >= len(u)``).
    """
    n = u.size
    out = np.zeros(n)
    head = _truncation_head(split, dt, u, int(N))
    np.negative(head, out=out[:head.size])
    return out


def _truncation_head(split: InverseSplit, dt: float, u: np.ndarray, N: int) -> np.ndarray:
    """``-e_N[:n - N]`` (the rest is zero), as a reversed view of the filter output.

    The output row is ``C_r Phi**N`` itself, as in :class:`~inversion._discrete.Plan`, so that
    the filter realization (transfer function or sections) is the one the plan would pick."""
    n = u.size
    if split.n_unstable == 0 or N >= n:
        return np.zeros(0)
    anti = plan_for(split, dt, None).anti
    C2 = anti.C @ np.linalg.matrix_power(anti.Phi, N)
    if not np.any(C2):
        return np.zeros(n - N)
    f = anti.with_row(C2)
    return f.run(u[N:][::-1], f.zi0())[0][::-1]


def discrete_tail_l1(split: InverseSplit, dt: float, n: int) -> np.ndarray:
    """``tail[N]`` for ``0 <= N <= K``: the l1 norm of the sampled anticausal kernel a preview of ``N``
    samples discards, so that ``|e_N[k]| <= tail[N] max|u|`` and ``||e_N||_2 <= tail[N] ||u||_2``.

    With ``r_j = C_r Phi**j`` the truncation error is ``e_N[k] = -sum_l G_l u[k+N+l]``,
    ``G_0 = r_N alpha``, ``G_l = r_{N+l} alpha + r_{N+l-1} beta`` (module doc of
    :mod:`inversion._discrete`), and only ``N + l <= n - 1`` reaches a sample of the record, so
    ``tail[N] = |r_N alpha| + sum_{N < j < n} |r_j alpha + r_{j-1} beta|`` — the induced
    infinity-norm of the truncation (attained by ``u = sign(G)``) and, by Young's inequality, a
    bound of its 2-norm gain.  The kernel is summed up to ``K = min(n, 50 / -ln rho(Phi) + 10 m)``
    samples (beyond, it is below ``exp(-50)`` of its slowest mode); ``tail[K] = 0``.
    """
    return _anti_kernel(split, dt, n)[1].copy()


#: Sampled anticausal kernels kept per split (by sampling interval and length).
_KERNEL_CACHE_SIZE = 8


def _anti_kernel(split: InverseSplit, dt: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(h, tail)``: the sampled anticausal kernel ``h_j`` (``j < K``: ``h_0 = r_0 alpha``,
    ``h_j = r_j alpha + r_{j-1} beta``) and :func:`discrete_tail_l1`, built once per ``(dt, K)``
    and kept on the split (read-only)."""
    return _kernel_entry(split, dt, n)[:2]


def _kernel_entry(split: InverseSplit, dt: float, n: int) -> tuple[Any, ...]:
    """``(h, tail, hk, rest, l1)`` for ``(dt, K)``: :func:`_anti_kernel`'s pair and the cut kernel of
    :func:`reference_lower_bound` (the first ``M`` samples of ``h``, the l1 norm of the rest, and
    of the whole), so that a call with a cached entry costs no pass over the kernel."""
    cache = split.__dict__.get("_kernel_cache")
    lengths = split.__dict__.get("_kernel_lengths")
    if cache is None or lengths is None:
        cache, lengths = {}, {}
        object.__setattr__(split, "_kernel_cache", cache)
        object.__setattr__(split, "_kernel_lengths", lengths)
    plan = plan_for(split, dt, None)
    Phi, al, be = plan.anti_phi, plan.anti_alpha, plan.anti_beta
    m = Phi.shape[0]
    kmax = lengths.get(float(dt))
    if kmax is None:            # the kernel's length at dt, whatever the record's (-1: unbounded)
        rho = float(np.max(np.abs(np.linalg.eigvals(Phi)))) if m else 0.0
        kmax = int(math.ceil(50.0 / -math.log(rho))) + 10 * m if 0.0 < rho < 1.0 else -1
        lengths[float(dt)] = kmax
    K = max(min(n, kmax) if kmax >= 0 else n, 1)
    key = (float(dt), K)
    entry = cache.get(key)
    if entry is not None:
        return entry
    rows = left_powers(plan.anti_C, Phi, K) if m else np.zeros((K, 0))
    ra, rb = rows @ al, rows @ be
    h = ra.copy()
    h[1:] += rb[:-1]                                   # h_j = r_j alpha + r_{j-1} beta
    g = np.abs(h[1:])                                  # |G| at j = 1 .. K-1
    suffix = np.concatenate((np.cumsum(g[::-1])[::-1], [0.0]))   # sum over j >= N + 1
    tail = np.empty(K + 1)
    tail[:K] = np.abs(ra) + suffix
    tail[K] = 0.0
    # the kernel of the reference, cut where the rest of its l1 norm is below 1e-6 of the whole
    full = np.cumsum(np.abs(h)[::-1])[::-1]
    l1 = float(full[0])
    cut = np.flatnonzero(full <= 1e-6 * l1)
    M = int(cut[0]) if cut.size else h.size
    rest = float(full[M]) if M < h.size else 0.0
    hk = h[:M].copy()
    for a in (h, tail, hk):
        a.flags.writeable = False
    entry = (h, tail, hk, rest, l1)
    if len(cache) >= _KERNEL_CACHE_SIZE:
        cache.pop(next(iter(cache), None), None)
    cache[key] = entry
    return entry


@dataclass(frozen=True, eq=False)
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
    tail_bound : float
        Signal-independent bound ``tail_l1_norm(T) * max|u|`` [output units].
    rule_4_over_r0_s : float
        What the 4/r0 rule would have chosen [s], for comparison.
    reference_bound : float
        The size of the full inverse the preview was certified against [output units]: for
        ``"linf"`` a lower bound of ``max|y_inf|`` from the exact values of ``y_inf`` at a few
        samples (:func:`reference_lower_bound`), for ``"l2"`` ``||y_inf||_2`` itself.
    relative_error : float
        Achieved truncation error in that norm (exact for the sampled signal).
    max_error : float
        Largest absolute truncation error [output units].
    error_bound : float
        ``discrete_tail_l1[N]`` times ``max|u|`` (linf) or ``||u||_2`` (l2), relative to the full
        inverse in that norm (<= ``tolerance``).

    ``relative_error``, ``max_error`` and ``error_bound`` need the full inverse and the exact
    truncation error of the signal (two more passes over it); for ``"linf"`` (and a chunked
    ``"l2"``) they are computed when first read, not when the preview is chosen, from the
    caller's array (no copy is kept), which must not have been modified in place since: its
    fingerprint taken when the preview was chosen (:class:`~inversion.signals.SignalFingerprint`:
    the sum of its samples' bit patterns modulo 2**64 and its extremes) must be the same when
    they are first read, else :class:`InversionError` (read them before reusing the array, or
    pass a copy).  Any change of one sample is seen, and a shift, a reversal or a scaling of the
    record; not, e.g., two samples exchanged when neither is an extreme.
    """

    samples: int
    seconds: float
    tolerance: float
    norm: str
    tail_bound: float
    rule_4_over_r0_s: float
    reference_bound: float = 0.0
    _errors_of: Callable[[], tuple[float, float, float]] | None = field(default=None, repr=False)

    @cached_property
    def _errors(self) -> tuple[float, float, float]:
        if self._errors_of is None:
            return 0.0, 0.0, 0.0
        rel, emax, bound = self._errors_of()
        return float(rel), float(emax), float(bound)

    @property
    def relative_error(self) -> float:
        """Achieved truncation error relative to the full inverse, in ``norm``."""
        return self._errors[0]

    @property
    def max_error(self) -> float:
        """Largest absolute truncation error [output units]."""
        return self._errors[1]

    @property
    def error_bound(self) -> float:
        """The kernel-tail bound of the chosen preview relative to the full inverse, in ``norm``."""
        return self._errors[2]


@dataclass(frozen=True, eq=False)
class AutoPreviewPasses:
    """What :func:`auto_preview_passes` computed: the choice and the pieces of the inverse.

    Attributes
    ----------
    choice : PreviewChoice
    stable : ndarray or None
        Causal part (feedthrough, polynomial part and ``H_s[u]``); None when the output was
        written over it (``keep_stable=False``): ``plan.run(signal, chunk)`` recomputes it exactly.
    unstable : ndarray or None
        Anticausal part truncated to the chosen preview; None when it was not kept
        (``keep_unstable=False``): ``plan.anticausal(ua, chunk)`` recomputes it exactly.
    output : ndarray
        The inverse with that preview, ``stable + unstable``.
    finite : bool
        Every output sample is finite (proved from the peaks, or from a finite sum of the
        output; False: not proved).
    plan : Plan or None
        The plan of the chosen preview that produced ``unstable``/``output`` (None on the
        ``"l2"`` path, whose ``unstable`` is always kept).
    output_sum : float or None
        The sum of ``output`` as the pass wrote it (see :meth:`~inversion._discrete.Plan.run`;
        None on the whole-record ``"l2"`` path).
    fingerprint : SignalFingerprint or None
        :func:`~inversion.signals.signal_extremes` of the signal, taken in the extremes pass
        (None on the whole-record ``"l2"`` path, which keeps both parts).
    """

    choice: PreviewChoice
    stable: np.ndarray | None
    unstable: np.ndarray | None
    output: np.ndarray
    finite: bool = False
    plan: Plan | None = None
    output_sum: float | None = None
    fingerprint: SignalFingerprint | None = None


#: Probes of the full inverse for the linf reference: equally spaced samples, plus the extremes
#: of the signal and the last samples of the record (where the anticausal edge transient is).
REFERENCE_PROBES = 64


def reference_lower_bound(split: InverseSplit, dt: float, ua: np.ndarray, stable: np.ndarray,
                          umax: float, extremes: tuple[int, int] | None = None) -> float:
    """A lower bound of ``max|y_inf|``, the peak of the full (infinite-preview) inverse of ``ua``.

    ``y_inf[k] = stable[k] + sum_j h_j u[k+j]`` with ``h`` the sampled anticausal kernel
    (:func:`discrete_tail_l1`'s ``G`` at ``N = 0``), evaluated exactly at the probe samples
    (:data:`REFERENCE_PROBES` equally spaced, the extremes of ``u`` and the last 8 samples) with
    the kernel cut where the rest of its l1 norm is below ``1e-6`` of the whole; that rest times
    ``max|u|`` and a rounding margin of ``1e-12`` are subtracted.  ``stable`` is the causal part
    (already computed, it does not depend on the preview).  Costs about
    ``(REFERENCE_PROBES + 10) * 14`` slowest time constants of multiply-adds, not a pass.
    ``extremes``: ``(argmax u, argmin u)`` if already known.
    """
    n = ua.size
    if split.n_unstable == 0 or umax == 0.0:
        return _peak(stable)
    _, _, hk, rest, l1 = _kernel_entry(split, dt, n)
    M = hk.size
    probes = np.unique(np.concatenate((
        np.linspace(0, n - 1, REFERENCE_PROBES).astype(np.intp),
        extremes or (int(np.argmax(ua)), int(np.argmin(ua))), np.arange(max(0, n - 8), n))))
    best = 0.0
    with np.errstate(over="ignore", invalid="ignore"):      # an overflow is refused below, by name
        for k in probes:
            seg = ua[k:k + M]
            y = float(stable[k]) + float(np.dot(seg, hk[:seg.size]))
            if not math.isfinite(y):
                # the tolerance is relative to this inverse: it cannot be certified, say why
                raise NonFiniteSignalError(
                    f"the inverse overflowed: output sample {int(k)} of the full (infinite-preview) inverse "
                    f"is {y!r} (input peak {umax:.3g}); scale the signal to the model's units")
            slack = rest * umax + 1e-12 * (abs(float(stable[k])) + l1 * umax)
            best = max(best, abs(y) - slack)
    return best


def auto_preview_passes(split: InverseSplit, dt: float, ua: np.ndarray, *, tol: float = DEFAULT_PREVIEW_TOL,
                        norm: str = "linf", chunk: int | None = None,
                        keep_unstable: bool = True, finite_checked: bool = True,
                        keep_stable: bool = True, quiet_passes: bool = False) -> AutoPreviewPasses:
    """Choose the automatic preview for the validated signal ``ua`` and invert it (see
    :func:`choose_preview`).

    ``"linf"``: the causal pass, the preview from :func:`reference_lower_bound` (no pass), then
    the finite-preview anticausal pass of :class:`~inversion._discrete.Plan` — the cost of
    inverting with that preview given; the exact truncation error is computed when the choice's
    ``relative_error``/``max_error``/``error_bound`` is first read.  ``"l2"``: the causal pass,
    the full anticausal pass (for ``||y_inf||_2``) and the truncation error of the chosen
    preview, whose sums are the inverse.  ``chunk``: samples per pass block (default: whole).
    ``keep_unstable``: as in :meth:`~inversion._discrete.Plan.run` (the ``"linf"`` path).
    ``keep_stable``: as in :meth:`~inversion._discrete.Plan.run` (the ``"linf"`` path).
    ``finite_checked=False``: ``ua`` was not yet checked finite (it is checked here, on the
    ``"linf"`` path in the pass that finds its extremes, see below).  ``quiet_passes``: the caller refuses
    a non-finite output itself (from ``output_sum``, as :func:`~inversion.invert` does), so
    numpy's overflow/invalid warnings inside the inverse's passes are silenced (only there: the
    choice's own arithmetic, e.g. the ``"l2"`` norms, is not).

    No copy of ``ua`` is kept (a copy was 1.45 of ~14.5 ns/sample at 20 kHz): one pass,
    :func:`~inversion.signals.signal_extremes`, reads it block by block for the peak (the bound),
    the extremes (probes of the reference), the proof that it is finite and a fingerprint
    (:class:`~inversion.signals.SignalFingerprint`: the sum of the samples' 64-bit patterns modulo
    2**64, which any change of one sample changes, and the extremes' places and values).  The errors are computed when first
    read from ``ua`` itself, so ``ua`` (the caller's array) must not change in the meantime: they
    first take the fingerprint again and refuse (:class:`InversionError`,
    :func:`~inversion.signals.check_unchanged`) one that differs.  A change that leaves it the
    same (see there) is not seen.  The fingerprint's sum costs ~0.14 ns/sample here (2**21
    samples) and the whole extremes pass ~0.6 when the errors are read.  The sum alone missed
    an in-place circular shift (a periodic record's buffer reused) and the whole record scaled
    by 2, ½, 4 … when its length times the power is a multiple of 4096 (review); the extremes
    see both.  A position-weighted sum would see any exchange too, but cost ~0.4 ns/sample more
    here (3 % of the automatic preview at 20 kHz).  Measured and not kept: the sum of the output this pass takes anyway as the
    fingerprint (nothing here, but the errors would run this pass again: reading them went from
    21 to 27-29 ns/sample, seed 000 sensor at 1-20 kHz, and ``ipmc feedforward`` and the
    scenarios always read them); the float sum of the signal (~0.2 ns/sample here, and a change
    of one sample smaller than its rounding goes unseen).  The result's arrays (``output``,
    ``stable``) are not read: the caller may edit them.
    """
    _check_tolerance(tol, norm)
    n = ua.size
    chunk = n if chunk is None else int(chunk)
    plan0 = plan_for(split, dt, None)
    if norm == "l2" and chunk >= n:
        return _auto_l2(split, dt, ua if finite_checked else check_finite(ua), plan0, tol, quiet_passes)
    fingerprint = signal_extremes(ua)
    extremes = (fingerprint.imax, fingerprint.imin)
    with pass_errstate(quiet_passes):
        stable = plan0.causal(ua, chunk)
    umax = max(float(ua[extremes[0]]), -float(ua[extremes[1]]))
    size_u = umax if norm == "linf" else l2_norm(ua)
    if norm == "linf":
        ref = reference_lower_bound(split, dt, ua, stable, umax, extremes)
    else:     # chunked l2: the full inverse once for its norm
        with pass_errstate(quiet_passes):
            y_inf = plan0.run(ua, chunk, stable)[2]
        ref = _l2_reference(y_inf)
    if split.n_unstable == 0:
        N = 0
        tail_n = 0.0
    else:
        tail = _anti_kernel(split, dt, n)[1] * size_u
        ok = np.flatnonzero(tail <= tol * ref)          # tail is non-increasing: the first index
        N = min(int(ok[0]) if ok.size else n - 1, n - 1)
        tail_n = float(tail[min(N, tail.size - 1)])
    plan = plan_for(split, dt, N)
    sums: list[float] = []
    with pass_errstate(quiet_passes):
        stable_kept, unstable, output = plan.run(ua, chunk, stable, keep_unstable=keep_unstable,
                                                 output_sum=sums, keep_stable=keep_stable)
    written = sums[0]

    def errors() -> tuple[float, float, float]:
        # from the caller's array, checked unchanged by its fingerprint (the result's arrays are not
        # read: the caller may have edited them)
        check_unchanged(signal_fingerprint(ua), fingerprint, "the truncation errors of the automatic preview",
                        "preview_choice.relative_error (or max_error, error_bound)",
                        "its fingerprint (SignalFingerprint)")
        minus_e = _truncation_head(split, dt, ua, N)     # -e_N[:n - N]; e_N is zero beyond
        y_inf = plan0.run(ua, n)[2]
        size = _peak if norm == "linf" else l2_norm
        r = size(y_inf)
        emax = _peak(minus_e) if minus_e.size else 0.0
        e = emax if norm == "linf" else (size(minus_e) if minus_e.size else 0.0)
        return (e / r, emax, tail_n / r) if r > 0 else (0.0, emax, 0.0)

    choice = PreviewChoice(
        samples=N, seconds=N * dt, tolerance=float(tol), norm=norm,
        tail_bound=float(split.tail_l1_norm(N * dt)) * umax, rule_4_over_r0_s=split.auto_preview_s,
        reference_bound=ref, _errors_of=errors)
    return AutoPreviewPasses(choice, stable_kept, unstable, output, finite=math.isfinite(written), plan=plan,
                             output_sum=written, fingerprint=fingerprint)


def _auto_l2(split: InverseSplit, dt: float, ua: np.ndarray, plan0: Plan, tol: float,
             quiet_passes: bool = False) -> AutoPreviewPasses:
    """The l2 choice: ``||y_inf||_2`` needs the full inverse, so three passes whose sums are the
    inverse with the chosen preview (the causal part, the full anticausal part, the truncation error)."""
    n = ua.size
    with pass_errstate(quiet_passes):
        stable, y_u, output = plan0.run(ua, n)
    y_u = y_u.copy() if y_u is stable else y_u
    size = l2_norm
    ref = _l2_reference(output)
    umax = _peak(ua)
    if split.n_unstable == 0 or ref == 0.0:
        # tail_bound as its doc says (it is 0 but for a signal whose inverse underflows to 0)
        zero = PreviewChoice(0, 0.0, float(tol), "l2", float(split.tail_l1_norm(0.0)) * umax,
                             split.auto_preview_s if split.n_unstable else 0.0, ref)
        return AutoPreviewPasses(zero, stable, np.zeros(n), stable.copy())
    tail = _anti_kernel(split, dt, n)[1] * size(ua)
    ok = np.flatnonzero(tail <= tol * ref)
    N = min(int(ok[0]) if ok.size else n - 1, n - 1)
    minus_e = _truncation_head(split, dt, ua, N)
    y_u[:minus_e.size] -= minus_e
    output[:minus_e.size] -= minus_e
    emax = _peak(minus_e) if minus_e.size else 0.0
    errs = ((size(minus_e) if minus_e.size else 0.0) / ref, emax, float(tail[min(N, tail.size - 1)]) / ref)
    choice = PreviewChoice(
        samples=N, seconds=N * dt, tolerance=float(tol), norm="l2",
        tail_bound=float(split.tail_l1_norm(N * dt)) * umax, rule_4_over_r0_s=split.auto_preview_s,
        reference_bound=ref, _errors_of=lambda: errs)
    return AutoPreviewPasses(choice, stable, y_u, output, finite=math.isfinite(ref + emax))


def l2_norm(x: np.ndarray) -> float:
    """``||x||_2``, without overflow or underflow of the sum of squares.

    ``sqrt(dot(x, x))`` when the sum of squares is a normal number; otherwise (a signal beyond
    ~1e154, where it overflows to inf, or below ~1e-140, where it loses digits) the same of
    ``x / max|x|`` times ``max|x|``.  Non-finite for a non-finite ``x`` only.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        s = float(np.dot(x, x))
    if math.isfinite(s) and (s == 0.0 or s >= 1e-280):
        if s > 0.0 or not np.any(x):
            return math.sqrt(s)
    p = _peak(x) if x.size else 0.0
    if p == 0.0 or not math.isfinite(p):
        return p
    y = x / p
    return p * math.sqrt(float(np.dot(y, y)))


def _l2_reference(y_inf: np.ndarray) -> float:
    """``||y_inf||_2`` for the ``"l2"`` choice, or :class:`NonFiniteSignalError` naming the overflow
    (an infinite reference made every preview pass, and the relative error NaN)."""
    ref = l2_norm(y_inf)
    if math.isfinite(ref):
        return ref
    bad = np.flatnonzero(~np.isfinite(y_inf))
    what = (f"output sample {int(bad[0])} is {float(y_inf[bad[0]])!r}" if bad.size
            else f"its l2 norm exceeds the double range (peak {_peak(y_inf):.3g})")
    raise NonFiniteSignalError(
        f"the inverse overflowed: {what}; preview_norm='l2' needs ||y_inf||_2 of the full inverse: "
        "scale the signal to the model's units (or use preview_norm='linf')")


def _peak(x: np.ndarray) -> float:
    """``max|x|`` without an ``|x|`` temporary."""
    return max(float(np.max(x)), -float(np.min(x)))


def _check_tolerance(tol: Any, norm: Any) -> None:
    if not (isinstance(tol, float | int) and math.isfinite(tol) and tol > 0):
        raise PreviewError(f"preview_tol must be a positive number; got {tol!r}")
    if norm not in ("linf", "l2"):
        raise PreviewError(f"preview_norm must be 'linf' or 'l2'; got {norm!r}")


def choose_preview(split: InverseSplit, dt: float, u: Any, *, tol: float = DEFAULT_PREVIEW_TOL,
                   norm: str = "linf", checked: bool = False) -> PreviewChoice:
    """Smallest preview whose bound on the truncation error of the signal ``u`` is below ``tol``.

    The truncation error of a preview of ``N`` samples (``e_N = y_N - y_inf``) is measured
    relative to the full (infinite-preview) inverse ``y_inf`` in the chosen norm.  ``N`` is the
    first preview at which the l1 norm of the discarded sampled kernel
    (:func:`discrete_tail_l1`) times ``max|u|`` (linf) or ``||u||_2`` (l2) is at most ``tol``
    times that of ``y_inf`` — for ``"linf"`` times a certified lower bound of ``max|y_inf|``
    (:func:`reference_lower_bound`, reported as ``reference_bound``), for ``"l2"`` times
    ``||y_inf||_2``: a bound, so the exact error of ``N`` (reported) meets the tolerance.
    It costs no search over previews and, for ``"linf"``, no pass beyond the inverse with the
    chosen preview (the exact error is computed when first read); ``N`` is longer than the
    smallest preview meeting the tolerance by what the bound gives away, typically one to two
    time constants ``1/r0`` of the slowest anticausal mode (10–25 % on the seed 000 sensor and
    the toy actuator with sines, measured), plus ``ln(max|y_inf|/reference_bound)`` of them.  A
    record too short for any shorter preview gets ``N = len(u) - 1``, which equals the infinite
    preview.

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
    _check_tolerance(tol, norm)
    if not checked:
        u = as_signal(u)
        dt = sampling_interval(dt)
        check_split_for(split, dt)      # its zeros judged for this dt (inversion.split)
    return auto_preview_passes(split, dt, np.asarray(u, dtype=float), tol=tol, norm=norm).choice
