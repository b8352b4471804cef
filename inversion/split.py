"""Split the inverse of a SISO model into causal-stable and anticausal-stable parts.

For a proper model ``G(s) = num(s)/den(s)`` the inverse ``H = 1/G = den/num`` is written as

    H(s) = sum_{k=1}^{r} c_k s^k  +  D  +  H_s(s)  +  H_u(s)

where ``r = deg den - deg num`` is the relative degree of ``G`` (the polynomial part is
present only when ``G`` is strictly proper), ``D`` is the direct feedthrough, ``H_s`` is
strictly proper with every pole in the open left half-plane (the minimum-phase zeros of
``G``) and ``H_u`` is strictly proper with every pole in the open right half-plane (the
non-minimum-phase zeros of ``G``).  ``H_s`` is run forward in time, ``H_u`` backward in time
(Devasia, Chen & Paden 1996; seed paper 000, Sec. IV-A).

Numerics
--------
The partial-fraction split is not done with residues (ill-conditioned for close or repeated
zeros).  Instead:

1. frequency scaling ``s = w0*sigma`` with ``w0`` the geometric mean of the zero magnitudes,
   so that polynomial coefficients such as ``4.5e10`` become O(1);
2. polynomial division ``den/num`` (``numpy.polydiv``) for ``D`` and the polynomial part;
3. a controllable-canonical realization of the strictly proper remainder, balanced with
   ``scipy.linalg.matrix_balance``;
4. a real Schur form ordered with ``sort='lhp'`` (``scipy.linalg.schur``) followed by the
   Sylvester equation ``T11 X - X T22 = -T12`` (``scipy.linalg.solve_sylvester``) that
   block-diagonalises the Schur form into the stable and the anti-stable blocks.

Improper inverses (strictly proper ``G``) are handled according to ``improper``:

``"error"`` (default)
    raise :class:`~inversion.ImproperInverseError`;
``"filter"``
    invert ``G`` augmented with ``r`` real poles at ``-filter_bandwidth`` [rad/s]:
    ``H_f(s) = H(s) * (w_f/(s + w_f))**r``, which is biproper.  The result is the inverse
    followed by an r-th order low-pass of bandwidth ``w_f``, i.e. ``G H_f = (w_f/(s+w_f))**r``
    (magnitude error about ``r (w/w_f)**2/2`` and phase lag about ``r w/w_f`` at frequency
    ``w``);
``"differentiate"``
    keep the polynomial part ``sum c_k s^k``; it is applied to the sampled signal with
    second-order-accurate central finite differences (see :mod:`inversion.batch`).

Zeros at infinity
-----------------
Given the sampling interval ``dt``, a zero ``z`` of ``G`` with ``omega_N/|z| <=``
:data:`ZERO_AT_INFINITY_RTOL` (``omega_N = pi/dt`` the Nyquist frequency) is treated as at
infinity: its factor ``(1 - s/z)`` is divided out of ``num`` and the model handled as the
model without it (one relative degree more, so ``improper=`` decides: refuse, filter or
differentiate).  Below the Nyquist frequency — all a sampled signal carries — that factor
differs from 1 by at most ``omega_N/|z|`` in magnitude and phase, so dropping it changes the
inverse by at most that, relative, at every representable frequency.  Keeping it instead puts a
feedthrough and a pole part that each scale like ``|z|`` into the inverse and cancel in band
(in separate passes when the zero is in the right half-plane: 4e7 times the true peak for a
zero at s = +1e13 rad/s at dt = 1 ms); and a schedule whose zero coefficient passes through 0
sends the zero through infinity from one half-plane to the other, so that without this rule the
answer jumps from "refused" (coefficient exactly 0) to "wrong".  The tolerance is the default
accuracy the inversion promises anyway (:data:`inversion.preview.DEFAULT_PREVIEW_TOL`, the part
of the inverse the automatic preview may discard): the dropped factor is below it at every
representable frequency, and in band (``omega << omega_N``) far below it.  It also keeps the
zeros that are kept inside the range where keeping them is measured to be accurate: with a right
half-plane pair at 0.75 +- 2.1j rad/s and a third zero at +-|z|, a 1 Hz sine inverted at dt = 1 ms
matched the mpmath steady state as well for |z| dt = 1e5 as for 1e2 in either half-plane, and
degraded from |z| dt = 1e6 in the right half-plane (relative error 3.9e-2, then 61 at 1e7); the
rule drops every zero from |z| dt = pi/1e-3 = 3142 on.  The dropped zeros are recorded
(:attr:`InverseSplit.zeros_at_infinity`, :attr:`InverseSplit.notes`) and warned about
(:class:`~inversion.ZeroAtInfinityWarning`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
import scipy.linalg as sla

from ._coefficients import model_coefficients
from ._errors import ImproperInverseError, InversionError, NonHyperbolicModelError, ZeroAtInfinityWarning
from ._norms import abs_impulse, l1_norm, propagate, to_tf

__all__ = ["InverseSplit", "split_inverse", "model_coefficients", "IMPROPER_MODES",
           "ZERO_AT_INFINITY_RTOL", "zeros_beyond_sampling", "check_split_for"]

IMPROPER_MODES = ("error", "filter", "differentiate")

#: A zero ``z`` counts as lying on the imaginary axis when ``|Re z| <= _AXIS_RTOL * max(|z|, w0)``.
_AXIS_RTOL = 1e-9
#: Largest acceptable norm of the Sylvester coupling ``X`` (in scaled units) before the
#: stable/anti-stable separation is declared numerically meaningless.
_MAX_SYLVESTER_NORM = 1e8
#: A zero ``z`` is treated as at infinity at sampling interval ``dt`` when its factor
#: ``(1 - s/z)`` differs from 1 by at most this much (relative) up to the Nyquist frequency,
#: ``(pi/dt)/|z| <= ZERO_AT_INFINITY_RTOL`` (module doc: the inversion's default accuracy,
#: equal to ``inversion.preview.DEFAULT_PREVIEW_TOL``, which cannot be imported here).
ZERO_AT_INFINITY_RTOL = 1e-3


@dataclass(frozen=True, eq=False)
class InverseSplit:
    """The inverse ``H = 1/G`` of a model split into polynomial, stable and anti-stable parts.

    ``H(s) = sum_k derivative_coefficients[k-1] s^k + feedthrough
    + C_s (sI - A_s)^{-1} B_s + C_u (sI - A_u)^{-1} B_u``.

    Attributes
    ----------
    num, den : ndarray
        Coefficients of the model ``G`` that was inverted (descending powers of s), after
        the zeros at infinity were divided out and after the ``"filter"`` augmentation if it
        was used.
    zeros : ndarray
        Zeros of ``num`` = poles of ``H`` [rad/s].
    relative_degree : int
        ``deg den - deg num`` of the model *as given* (before filter augmentation), after
        the zeros at infinity were divided out (each adds one).
    improper : str
        How an improper inverse was handled (``"error"``, ``"filter"``, ``"differentiate"``).
    filter_bandwidth : float or None
        Bandwidth of the added low-pass poles [rad/s] (``"filter"`` mode).
    feedthrough : float
        ``D = lim_{s->inf} (H(s) - polynomial part)``.
    derivative_coefficients : ndarray
        ``c_1 .. c_r`` multiplying ``s^1 .. s^r`` (empty unless ``"differentiate"``).
    A_s, B_s, C_s : ndarray
        Realization of the stable part: shapes (n_s, n_s), (n_s,), (n_s,) [A in 1/s].
    A_u, B_u, C_u : ndarray
        Realization of the anti-stable part: shapes (n_u, n_u), (n_u,), (n_u,).
    r0 : float
        Real part of the least unstable pole of ``H_u`` (the non-minimum-phase zero of ``G``
        closest to the imaginary axis) [1/s]; ``inf`` for a minimum-phase model.
    auto_preview_s : float
        Zou–Devasia preview rule ``T_p* = 4/r0`` [s]; 0 for a minimum-phase model.
    frequency_scale : float
        ``w0`` used to scale s during the computation [rad/s].
    zeros_at_infinity : ndarray
        Zeros of the model as given that were treated as at infinity because the sampling
        cannot represent them (``(pi/dt)/|z| <=`` :data:`ZERO_AT_INFINITY_RTOL`; module doc)
        [rad/s]; empty when none were, or when the split was built without ``dt``.
    model_zeros : ndarray
        Zeros of the model that was inverted, before the ``"filter"`` augmentation [rad/s].
    sampling_interval : float or None
        The ``dt`` the zeros were judged for [s] (None: built without ``dt``).
    """

    num: np.ndarray
    den: np.ndarray
    zeros: np.ndarray
    relative_degree: int
    improper: str
    filter_bandwidth: float | None
    feedthrough: float
    derivative_coefficients: np.ndarray
    A_s: np.ndarray
    B_s: np.ndarray
    C_s: np.ndarray
    A_u: np.ndarray
    B_u: np.ndarray
    C_u: np.ndarray
    r0: float
    auto_preview_s: float
    frequency_scale: float = field(default=1.0)
    zeros_at_infinity: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    model_zeros: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    sampling_interval: float | None = None

    def __post_init__(self):
        # plans built from the split are cached on it (inversion._discrete.plan_for), so its arrays
        # are read-only copies: changing one in place would leave stale plans behind
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                v = v.copy()
                v.setflags(write=False)
                object.__setattr__(self, f.name, v)

    @property
    def notes(self) -> tuple[str, ...]:
        """What the split changed in the model, in words (one line per zero treated as at infinity)."""
        return tuple(_infinity_note(z, self.sampling_interval or math.nan)
                     for z in self.zeros_at_infinity)

    @property
    def n_stable(self) -> int:
        """Order of the stable (causal) part."""
        return int(self.A_s.shape[0])

    @property
    def n_unstable(self) -> int:
        """Order of the anti-stable (anticausal) part."""
        return int(self.A_u.shape[0])

    @property
    def is_minimum_phase(self) -> bool:
        """True when the inverse has no anticausal part."""
        return self.n_unstable == 0

    @property
    def unstable_poles(self) -> np.ndarray:
        """Poles of ``H_u`` (right half-plane zeros of G) [rad/s]."""
        return np.linalg.eigvals(self.A_u) if self.n_unstable else np.zeros(0, complex)

    @property
    def stable_poles(self) -> np.ndarray:
        """Poles of ``H_s`` (left half-plane zeros of G) [rad/s]."""
        return np.linalg.eigvals(self.A_s) if self.n_stable else np.zeros(0, complex)

    def frequency_response(self, omega: Any, part: str = "total") -> np.ndarray:
        """Evaluate the inverse (or one of its parts) at ``s = j*omega``.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].
        part : {"total", "stable", "unstable", "polynomial"}
            ``"stable"`` includes neither the feedthrough nor the polynomial part;
            ``"polynomial"`` is ``D + sum c_k s^k``.

        Returns
        -------
        ndarray of complex
            ``H(j omega)`` in output units per input unit.
        """
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        s = 1j * w

        def block(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
            n = A.shape[0]
            if n == 0:
                return np.zeros_like(s)
            # one batched solve for every frequency (a loop of solves was 3.6 ms for 257 of them,
            # half of the automatic streaming preview's cost)
            rhs = np.broadcast_to(B.astype(complex)[:, None], (s.size, n, 1))
            return np.linalg.solve(s[:, None, None] * np.eye(n) - A, rhs)[..., 0] @ C

        poly = np.full(s.shape, self.feedthrough, dtype=complex)
        for k, c in enumerate(self.derivative_coefficients, start=1):
            poly = poly + c * s**k
        if part == "polynomial":
            return poly
        hs = block(self.A_s, self.B_s, self.C_s)
        if part == "stable":
            return hs
        hu = block(self.A_u, self.B_u, self.C_u)
        if part == "unstable":
            return hu
        if part != "total":
            raise InversionError(
                f"part must be 'total', 'stable', 'unstable' or 'polynomial'; got {part!r}")
        return poly + hs + hu

    def stable_tf(self) -> Any:
        """``H_s`` as a ``control.TransferFunction`` (None if empty)."""
        return to_tf(self.A_s, self.B_s, self.C_s)

    def unstable_tf(self) -> Any:
        """``H_u`` as a ``control.TransferFunction`` (None if empty)."""
        return to_tf(self.A_u, self.B_u, self.C_u)

    def l1_norms(self) -> tuple[float, float]:
        """L1 norms of the impulse responses of ``H_s`` and ``H_u`` (integral of |h|).

        Used for the discretisation error estimate: a bounded input perturbation ``e``
        changes each part's output by at most ``||h||_1 * max|e|``.
        """
        return l1_norm(self.A_s, self.B_s, self.C_s), l1_norm(-self.A_u, self.B_u, self.C_u)

    def tail_l1_norm(self, preview_s: Any) -> np.ndarray:
        """L1 norm of the anticausal kernel beyond the preview, ``int_T^inf |h_u(-sigma)| d sigma``.

        A preview ``T`` neglects exactly this part of the kernel, so for any input the
        truncation error is at most ``tail_l1_norm(T) * max|u|`` [output units].

        Parameters
        ----------
        preview_s : float or array_like
            Preview(s) ``T`` >= 0 [s]; ``inf`` gives 0.

        Returns
        -------
        ndarray
            Same shape as ``preview_s`` [output units per input unit * s / s].
        """
        T = np.asarray(preview_s, dtype=float)
        if self.n_unstable == 0:
            return np.zeros(T.shape)
        curve_t, curve = self._tail_curve
        return np.interp(T, curve_t, curve, right=0.0)

    @property
    def _tail_curve(self) -> tuple[np.ndarray, np.ndarray]:
        cached = self.__dict__.get("_tail_cache")
        if cached is None:
            step, h = abs_impulse(-self.A_u, self.B_u, self.C_u)
            # cumulative trapezoid from the far end: tail[i] = int_{t_i}^{horizon} |h|
            seg = 0.5 * step * (h[1:] + h[:-1])
            tail = np.concatenate((np.cumsum(seg[::-1])[::-1], [0.0]))
            cached = (step * np.arange(h.size), tail)
            object.__setattr__(self, "_tail_cache", cached)
        return cached

    def truncation_response(self, preview_s: Any, omega: Any) -> np.ndarray:
        """Frequency response of the error caused by truncating the anticausal part at ``T``.

        ``E_T(j w) = C_u (j w I - A_u)^{-1} exp(-A_u T) B_u exp(j w T)``: the part of
        ``H_u(j w)`` the preview ``T`` discards (``E_0 = H_u``, ``E_inf = 0``).  For a sinusoid
        of angular frequency ``w`` and amplitude ``A`` the steady-state truncation error is
        ``A |E_T(j w)|``.

        Parameters
        ----------
        preview_s : float or array_like, shape (m,)
            Previews [s].
        omega : array_like, shape (k,)
            Angular frequencies [rad/s].

        Returns
        -------
        ndarray of complex, shape (m, k)  (squeezed for scalar ``preview_s``)
        """
        T = np.atleast_1d(np.asarray(preview_s, dtype=float))
        w = np.atleast_1d(np.asarray(omega, dtype=float))
        out = self.truncation_terms(T, w)
        if self.n_unstable:
            out = out * np.exp(1j * np.outer(np.where(np.isfinite(T), T, 0.0), w))
        return out[0] if np.ndim(preview_s) == 0 else out

    def truncation_terms(self, T: np.ndarray, w: np.ndarray) -> np.ndarray:
        """``C_u (j w I - A_u)^{-1} exp(-A_u T) B_u``: :meth:`truncation_response` without its
        unit-modulus factor ``exp(j w T)`` (its magnitude, as the preview rules use it).

        Parameters
        ----------
        T : ndarray, shape (m,)
            Previews [s] (``inf`` gives 0).
        w : ndarray, shape (k,)
            Angular frequencies [rad/s].

        Returns
        -------
        ndarray of complex, shape (m, k)
        """
        if self.n_unstable == 0:
            return np.zeros((T.size, w.size), complex)
        V, R = self.truncation_factors(T, w)
        return V @ R.T

    def truncation_factors(self, T: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(V, R)`` with :meth:`truncation_terms` ``= V @ R.T`` (for an anticausal part).

        Parameters
        ----------
        T : ndarray, shape (m,)
            Previews [s] (``inf`` gives 0).
        w : ndarray, shape (k,)
            Angular frequencies [rad/s].

        Returns
        -------
        V : ndarray, shape (m, n_u)
            Rows ``exp(-A_u T_i) B_u`` (real).
        R : ndarray of complex, shape (k, n_u)
            Rows ``C_u (j w_k I - A_u)^{-1}``.
        """
        n = self.n_unstable
        # rows R(w) = C_u (j w I - A_u)^{-1}, one batched solve (transpose system)
        lhs = (1j * w)[:, None, None] * np.eye(n) - self.A_u
        R = np.linalg.solve(np.transpose(lhs, (0, 2, 1)),
                            np.broadcast_to(self.C_u.astype(complex), (w.size, n))[..., None])[..., 0]
        V = propagate(-self.A_u, self.B_u, T)                           # (m, n)
        return V, R


def _scale_poly(c: np.ndarray, w0: float) -> np.ndarray:
    """Coefficients of p(w0*sigma) given those of p(s) (descending powers)."""
    deg = c.size - 1
    return c * w0 ** np.arange(deg, -1, -1, dtype=float)


def split_inverse(model: Any, *, improper: str = "error",
                  filter_bandwidth: float | None = None, dt: float | None = None) -> InverseSplit:
    """Split ``1/G`` into polynomial + feedthrough + stable + anti-stable parts.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, or (num, den)
        Proper continuous-time SISO model ``G(s)`` (s in rad/s).
    improper : {"error", "filter", "differentiate"}
        Handling of a strictly proper ``G`` (improper inverse); see the module docstring.
    filter_bandwidth : float, optional
        Bandwidth of the low-pass poles for ``improper="filter"`` [rad/s].
    dt : float, optional
        Sampling interval the inverse will be run at [s].  Zeros beyond what it can represent
        (``(pi/dt)/|z| <=`` :data:`ZERO_AT_INFINITY_RTOL`) are treated as at infinity (module
        doc); the inversion entry points always pass it.

    Returns
    -------
    InverseSplit

    Raises
    ------
    NonHyperbolicModelError
        if ``G`` has a zero on the imaginary axis (|Re z| <= 1e-9 max(|z|, w0)).
    ImproperInverseError
        if ``G`` is strictly proper and ``improper="error"``.
    InversionError
        for invalid models or options.
    """
    if improper not in IMPROPER_MODES:
        raise InversionError(
            f"improper must be one of {IMPROPER_MODES}; got {improper!r}")
    if dt is not None and not (isinstance(dt, int | float | np.floating) and math.isfinite(dt) and dt > 0):
        raise InversionError(f"dt must be a positive finite sampling interval in s; got {dt!r}")
    num, den = model_coefficients(model)
    num, dropped = zeros_beyond_sampling(num, dt)
    model_num = num
    rel_deg = den.size - num.size
    wf: float | None = None
    if improper == "filter":
        if filter_bandwidth is None or not (np.isfinite(filter_bandwidth) and filter_bandwidth > 0):
            raise InversionError(
                "improper='filter' needs filter_bandwidth, a positive finite bandwidth in "
                f"rad/s; got {filter_bandwidth!r}")
        wf = float(filter_bandwidth)
        if rel_deg > 0:
            # G_f = G * ((s + wf)/wf)^r  (so that H_f = H * (wf/(s+wf))^r)
            lp = np.poly(np.full(rel_deg, -wf)) / wf**rel_deg
            num = np.polymul(num, lp)
    elif filter_bandwidth is not None:
        raise InversionError(
            f"filter_bandwidth={filter_bandwidth!r} is only used with improper='filter'; got "
            f"improper={improper!r}")
    r_eff = den.size - num.size
    if r_eff > 0 and improper == "error":
        why = "".join(_infinity_note(z, float(dt or math.nan)) + "; " for z in dropped)
        why = why + "without it " if why else ""
        raise ImproperInverseError(
            why + f"the model is strictly proper (relative degree {r_eff}), so its inverse is "
            "improper (it contains s^k terms); choose improper='filter' with "
            "filter_bandwidth=<rad/s> to low-pass the inverse, or improper='differentiate' "
            "to apply the s^k terms as central finite differences")

    for z in dropped:       # the inverse is that of another model: say so (also in .notes)
        warnings.warn(_infinity_note(z, float(dt or math.nan)) + f"; improper={improper!r} applies",
                      ZeroAtInfinityWarning, stacklevel=2)
    m = num.size - 1  # number of zeros of G = order of the dynamic part of H
    zeros = np.roots(num) if m > 0 else np.zeros(0, complex)
    if model_num.size == num.size:
        model_zeros = zeros
    else:
        model_zeros = np.roots(model_num) if model_num.size > 1 else np.zeros(0, complex)
    extra: dict[str, Any] = dict(zeros_at_infinity=dropped, model_zeros=model_zeros,
                                 sampling_interval=None if dt is None else float(dt))
    nonzero = np.abs(zeros)[np.abs(zeros) > 0]
    w0 = float(np.exp(np.mean(np.log(nonzero)))) if nonzero.size else 1.0
    if not np.isfinite(w0) or w0 <= 0:  # pragma: no cover - defensive
        w0 = 1.0
    for z in zeros:
        if abs(z.real) <= _AXIS_RTOL * max(abs(z), w0):
            raise NonHyperbolicModelError(
                f"the model has a zero at s = {complex(z):.6g} on the imaginary axis "
                f"(|Re| = {abs(z.real):.3g} rad/s <= {_AXIS_RTOL:g} * max(|z|, {w0:.3g})); "
                "the inverse would have a pole there and has no bounded stable realization. "
                "Stable inversion needs a hyperbolic model (no zeros with Re s = 0): remove or "
                "shift that zero (e.g. a zero at s = 0 of a high-pass sensor)")

    num_sc = _scale_poly(num, w0)
    den_sc = _scale_poly(den, w0)
    lead = num_sc[0]
    num_sc = num_sc / lead
    den_sc = den_sc / lead
    q, rem = np.polydiv(den_sc, num_sc)
    q = np.atleast_1d(q)
    # q: descending powers sigma^r_eff .. sigma^0
    feedthrough = float(q[-1])
    deriv = np.zeros(max(r_eff, 0))
    for k in range(1, r_eff + 1):
        deriv[k - 1] = q[-1 - k] / w0**k

    empty2, empty1 = np.zeros((0, 0)), np.zeros(0)
    if m == 0:
        return InverseSplit(num=num, den=den, zeros=zeros, relative_degree=rel_deg,
                            improper=improper, filter_bandwidth=wf, feedthrough=feedthrough,
                            derivative_coefficients=deriv, A_s=empty2, B_s=empty1, C_s=empty1,
                            A_u=empty2, B_u=empty1, C_u=empty1, r0=math.inf,
                            auto_preview_s=0.0, frequency_scale=w0, **extra)

    rem = np.atleast_1d(rem)
    rem_full = np.zeros(m)
    rem_full[m - rem.size:] = rem[-m:] if rem.size > m else rem
    # controllable canonical form of rem(sigma)/num(sigma), num monic of degree m
    A = np.zeros((m, m))
    A[0, :] = -num_sc[1:]
    if m > 1:
        A[1:, :-1] = np.eye(m - 1)
    B = np.zeros(m)
    B[0] = 1.0
    C = rem_full.copy()
    Ab, (sca, _) = sla.matrix_balance(A, permute=False, separate=True)
    B = B / sca
    C = C * sca
    T, Z, sdim = sla.schur(Ab, output="real", sort="lhp")
    n_lhp = int(np.sum(zeros.real < 0))
    if sdim != n_lhp:  # pragma: no cover - only for pathological near-axis cases
        raise NonHyperbolicModelError(
            f"cannot separate stable and unstable zeros reliably: the Schur form has {sdim} "
            f"left half-plane eigenvalues but the zeros {zeros} have {n_lhp}")
    k = sdim
    T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
    if 0 < k < m:
        X = sla.solve_sylvester(T11, -T22, -T12)
        xn = float(np.linalg.norm(X))
        if not np.isfinite(xn) or xn > _MAX_SYLVESTER_NORM:
            raise NonHyperbolicModelError(
                f"the stable and unstable zeros {zeros} are too close to separate the "
                f"inverse numerically (Sylvester coupling norm {xn:.3g} > "
                f"{_MAX_SYLVESTER_NORM:g})")
    else:
        X = np.zeros((k, m - k))
    W = np.eye(m)
    W[:k, k:] = X
    Winv = np.eye(m)
    Winv[:k, k:] = -X
    V = Z @ W
    Bt = Winv @ (Z.T @ B)
    Ct = C @ V
    A_s = w0 * T11
    B_s = w0 * Bt[:k]
    C_s = Ct[:k].copy()
    A_u = w0 * T22
    B_u = w0 * Bt[k:]
    C_u = Ct[k:].copy()
    # equalise |B| and |C| per part (cosmetic, improves the conditioning of ss2tf later)
    A_s, B_s, C_s = _equalise(A_s, B_s, C_s)
    A_u, B_u, C_u = _equalise(A_u, B_u, C_u)
    if A_u.shape[0]:
        r0 = float(np.min(np.linalg.eigvals(A_u).real))
        auto = 4.0 / r0
    else:
        r0, auto = math.inf, 0.0
    return InverseSplit(num=num, den=den, zeros=zeros, relative_degree=rel_deg,
                        improper=improper, filter_bandwidth=wf, feedthrough=feedthrough,
                        derivative_coefficients=deriv, A_s=A_s, B_s=B_s, C_s=C_s,
                        A_u=A_u, B_u=B_u, C_u=C_u, r0=r0, auto_preview_s=auto,
                        frequency_scale=w0, **extra)


def _equalise(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, ...]:
    if A.shape[0] == 0:
        return A, B, C
    nb, nc = float(np.linalg.norm(B)), float(np.linalg.norm(C))
    if nb > 0 and nc > 0:
        f = math.sqrt(nc / nb)
        return A, B * f, C / f
    return A, B, C


def _nyquist_ratio(z: complex, dt: float) -> float:
    """``(pi/dt)/|z|``: the largest deviation of ``(1 - s/z)`` from 1 below the Nyquist frequency."""
    return math.pi / (dt * abs(z))


def _infinity_note(z: complex, dt: float) -> str:
    return (f"the model's zero at s = {complex(z):.6g} (|z| = {abs(z):.3g} rad/s, |z|*dt = "
            f"{abs(z) * dt:.3g}) is beyond what sampling at dt = {dt:.6g} s represents: its factor "
            f"(1 - s/z) differs from 1 by at most {_nyquist_ratio(z, dt):.3g} <= "
            f"{ZERO_AT_INFINITY_RTOL:g} up to the Nyquist frequency, so it was treated as at "
            "infinity (as if its coefficient were exactly 0)")


def zeros_beyond_sampling(num: np.ndarray, dt: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Divide the zeros the sampling cannot represent out of ``num`` (module doc, "Zeros at infinity").

    Parameters
    ----------
    num : ndarray
        Numerator coefficients, descending powers of s.
    dt : float or None
        Sampling interval [s]; None drops nothing.

    Returns
    -------
    num : ndarray
        ``num(s) / prod (1 - s/z)`` over the dropped zeros (the same low-frequency gain), or
        ``num`` itself when none is dropped.
    dropped : ndarray of complex
        The dropped zeros [rad/s] (conjugate pairs together).
    """
    none = np.zeros(0, complex)
    if dt is None or num.size < 2:
        return num, none
    zeros = np.roots(num)
    far = np.array([z != 0 and _nyquist_ratio(z, float(dt)) <= ZERO_AT_INFINITY_RTOL for z in zeros],
                   dtype=bool)
    if not far.any():
        return num, none
    dropped = zeros[far]
    # f(s) = prod (1 - s/z), real (the dropped set is closed under conjugation), ascending powers
    f = np.real(np.poly(dropped)[::-1] / np.prod(-dropped))
    a = num[::-1].astype(float)                        # ascending powers
    d = dropped.size
    b = np.zeros(a.size - d)
    # a = f b solved from the low powers up: f_j ~ |z|^-j is tiny, so no rounding error is
    # amplified (dividing from the leading coefficient, as numpy.polydiv does, multiplies by |z|)
    for k in range(b.size):
        acc = a[k]
        for j in range(1, min(k, d) + 1):
            acc -= f[j] * b[k - j]
        b[k] = acc
    return b[::-1].copy(), dropped


def check_split_for(split: InverseSplit, dt: float) -> InverseSplit:
    """Return ``split`` if its zeros were judged right for sampling interval ``dt`` [s] (module doc,
    "Zeros at infinity"), else raise :class:`InversionError` saying to rebuild it with ``dt``.

    A split built elsewhere (without ``dt``, or for another ``dt``) is only used as it is when
    it keeps no zero the sampling cannot represent and drops none that it can.
    """
    bad_kept = [z for z in split.model_zeros if z != 0 and _nyquist_ratio(z, dt) <= ZERO_AT_INFINITY_RTOL]
    bad_dropped = [z for z in split.zeros_at_infinity if _nyquist_ratio(z, dt) > ZERO_AT_INFINITY_RTOL]
    if bad_kept:
        z = bad_kept[0]
        raise InversionError(
            f"this InverseSplit keeps the model's zero at s = {complex(z):.6g} (|z|*dt = {abs(z) * dt:.3g}), "
            f"which sampling at dt = {dt:.6g} s cannot represent (its factor differs from 1 by at most "
            f"{_nyquist_ratio(z, dt):.3g} <= {ZERO_AT_INFINITY_RTOL:g} up to the Nyquist frequency) and "
            "whose inverse is numerically meaningless there; build it with "
            f"split_inverse(model, dt={dt!r}) (or pass the model itself) so that it is treated as at infinity")
    if bad_dropped:
        z = bad_dropped[0]
        raise InversionError(
            f"this InverseSplit was built for dt = {split.sampling_interval!r} s and treated the zero at "
            f"s = {complex(z):.6g} as at infinity, but at dt = {dt:.6g} s it is representable; build it "
            f"with split_inverse(model, dt={dt!r}) (or pass the model itself)")
    return split
