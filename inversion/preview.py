"""The automatic preview: the shortest ``T_p`` whose bound on the truncation error of the signal
at hand is below a stated tolerance of the full inverse.

Truncating the anticausal part to ``N`` samples changes the output by exactly (see
:mod:`inversion._discrete`)

    e_N[k] = y_N[k] - y_inf[k] = -(C_r Phi**N) x[k+N] = -sum_l G_l u[k+N+l],

``x`` the anticausal first-order-hold state of the sampled signal (zero beyond the record) and
``G`` the part of the sampled anticausal kernel beyond the preview.  Hence
``max|e_N| <= ||G||_1 max|u|`` and ``||e_N||_2 <= ||G||_1 ||u||_2``, with ``||G||_1`` (the tail
of the kernel, :func:`discrete_tail_l1`) computed for every ``N`` at once from the powers
``C_r Phi**j`` — no pass over the signal per candidate.  :func:`choose_preview` runs the full
inverse once (for the reference ``y_inf``), takes the first ``N`` whose bound meets the
tolerance, and computes the exact error of that ``N`` with one more pass of the anticausal
recursion (:func:`truncation_error`); the three passes sum to the finite-preview inverse, so
``invert(preview="auto")`` costs about one extra pass over inverting with the chosen preview.
The bound is tight for a signal that follows the sign pattern of the kernel's tail; for a
sinusoid it gives away the ratio of the tail's l1 norm to its gain at that frequency, i.e. a
preview one or two slowest-mode time constants longer than the shortest that meets the
tolerance (a shorter error, never a larger one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._discrete import FOHFilter, Plan, foh_matrices, left_powers
from ._errors import InversionError, PreviewError
from .signals import as_signal, sampling_interval
from .split import InverseSplit

__all__ = ["PreviewChoice", "AutoPreviewPasses", "auto_preview_passes", "choose_preview", "discrete_tail_l1",
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
    ratio = np.max(np.abs(split.truncation_terms(T, w)) / H, axis=1)
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
    Phi, al, be = foh_matrices(-split.A_u, split.B_u, dt)
    C2 = -split.C_u @ np.linalg.matrix_power(Phi, N)
    if not np.any(C2):
        return np.zeros(n - N)
    f = FOHFilter.build(Phi, al, be, C2)
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
    Phi, al, be = foh_matrices(-split.A_u, split.B_u, dt)
    m = Phi.shape[0]
    rho = float(np.max(np.abs(np.linalg.eigvals(Phi)))) if m else 0.0
    K = n
    if 0.0 < rho < 1.0:
        K = min(n, int(math.ceil(50.0 / -math.log(rho))) + 10 * m)
    K = max(K, 1)
    rows = left_powers(-split.C_u, Phi, K)
    ra, rb = rows @ al, rows @ be
    g = np.abs(ra[1:] + rb[:-1])                       # |G| at j = 1 .. K-1
    suffix = np.concatenate((np.cumsum(g[::-1])[::-1], [0.0]))   # sum over j >= N + 1
    tail = np.empty(K + 1)
    tail[:K] = np.abs(ra) + suffix
    tail[K] = 0.0
    return tail


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
    error_bound : float
        The bound the preview was chosen by: ``discrete_tail_l1[N]`` times ``max|u|`` (linf)
        or ``||u||_2`` (l2), relative to the full inverse in that norm (<= ``tolerance``).
    """

    samples: int
    seconds: float
    tolerance: float
    norm: str
    relative_error: float
    max_error: float
    tail_bound: float
    rule_4_over_r0_s: float
    error_bound: float = 0.0


@dataclass(frozen=True, eq=False)
class AutoPreviewPasses:
    """What :func:`auto_preview_passes` computed: the choice and the pieces of the inverse.

    Attributes
    ----------
    choice : PreviewChoice
    stable : ndarray
        Causal part (feedthrough, polynomial part and ``H_s[u]``).
    unstable : ndarray
        Anticausal part truncated to the chosen preview.
    output : ndarray
        The inverse with that preview, ``stable + unstable``.
    finite : bool
        Every output sample is finite (proved from the peaks; False: not proved).
    """

    choice: PreviewChoice
    stable: np.ndarray
    unstable: np.ndarray
    output: np.ndarray
    finite: bool = False


def auto_preview_passes(split: InverseSplit, dt: float, ua: np.ndarray, *, tol: float = DEFAULT_PREVIEW_TOL,
                        norm: str = "linf") -> AutoPreviewPasses:
    """Choose the automatic preview for the validated signal ``ua`` and invert it (see
    :func:`choose_preview`): three passes over the record — the causal part, the full anticausal
    part, and the truncation error of the chosen preview — whose sums are the inverse."""
    _check_tolerance(tol, norm)
    n = ua.size
    plan = Plan(split, dt, None)
    parts: dict[str, np.ndarray] = {}
    plan.forward(ua, n, n, lambda c0, c1, y, _x: parts.__setitem__("s", y), check=False)
    stable = parts["s"]
    if split.n_unstable == 0:
        return AutoPreviewPasses(PreviewChoice(0, 0.0, float(tol), norm, 0.0, 0.0, 0.0, 0.0),
                                 stable, np.zeros(n), stable.copy())
    plan.backward(ua, n, n, lambda c0, c1, y, _x: parts.__setitem__("u", y))
    y_u = parts["u"]                                   # the full anticausal part
    output = stable + y_u                              # y_inf, made the output below

    def size(e: np.ndarray) -> float:
        return _peak(e) if norm == "linf" else float(np.sqrt(np.dot(e, e)))

    ref = size(output)
    if ref == 0.0:
        zero = PreviewChoice(0, 0.0, float(tol), norm, 0.0, 0.0, 0.0, split.auto_preview_s)
        return AutoPreviewPasses(zero, stable, np.zeros(n), stable.copy())
    umax = _peak(ua)
    tail = discrete_tail_l1(split, dt, n) * (umax if norm == "linf" else size(ua))
    ok = np.flatnonzero(tail <= tol * ref)          # tail is non-increasing: the first index
    N = min(int(ok[0]) if ok.size else n - 1, n - 1)
    minus_e = _truncation_head(split, dt, ua, N)      # -e_N[:n - N]; e_N is zero beyond
    y_u[:minus_e.size] -= minus_e
    output[:minus_e.size] -= minus_e
    emax = _peak(minus_e) if minus_e.size else 0.0
    choice = PreviewChoice(
        samples=N, seconds=N * dt, tolerance=float(tol), norm=norm,
        relative_error=(emax if norm == "linf" else size(minus_e)) / ref, max_error=emax,
        tail_bound=float(split.tail_l1_norm(N * dt)) * umax, rule_4_over_r0_s=split.auto_preview_s,
        error_bound=float(tail[min(N, tail.size - 1)]) / ref)
    # |output| <= max|y_inf| + max|e_N| <= ref + max|e_N| (in both norms, max|.| <= ||.||_2)
    return AutoPreviewPasses(choice, stable, y_u, output, finite=math.isfinite(ref + emax))


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
    times that of ``y_inf``: a bound, so the exact error of ``N`` (reported) meets the tolerance.
    It costs no search over previews (one full inverse, then one pass for the exact error of
    ``N``); ``N`` is longer than the smallest preview meeting the tolerance by what the bound
    gives away, typically one to two time constants ``1/r0`` of the slowest anticausal mode
    (10–25 % on the seed 000 sensor and the toy actuator with sines, measured).  A record too
    short for any shorter preview gets ``N = len(u) - 1``, which equals the infinite preview.

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
    return auto_preview_passes(split, dt, np.asarray(u, dtype=float), tol=tol, norm=norm).choice
