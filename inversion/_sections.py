"""Second-order-section forms of the FOH filters: the sections fallback of a single filter
and the factored fused finite-preview pass (see :mod:`inversion._discrete`)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.signal as sig

__all__ = ["FusedPass", "sos_sections", "polynomial_denominator", "best_rounded_polynomial", "running_error_ok",
           "all_pole_sections", "probe_length", "POLY_MAX_ORDER", "PROBE_MAX", "DC_PEAK_TOL"]


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


def all_pole_sections(poles: np.ndarray) -> np.ndarray:
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


#: The unit-circle test points of ``FOHFilter``: a logarithmic grid down to 1e-7 of the Nyquist
#: frequency, and z = 1.  The factored responses are checked there (:meth:`FusedPass.factored`) and
#: the rounded denominator polynomial is chosen there (:func:`best_rounded_polynomial`).
_TEST_Z = np.exp(1j * np.pi * np.concatenate((np.logspace(-7, 0, 36), [0.0])))


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
      passes before, 0.26× lfilter instead of 0.31–0.35×).  Where the product of the sections
      has a double-precision polynomial accurate to the same 1e-10 (chosen and checked in
      extended precision, :func:`polynomial_denominator`; the seed 000 sensor at 20 kHz), the
      factored form is that transfer function: ``lfilter`` is ~1.3 ns/sample cheaper than
      ``sosfilt``.
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
        factored responses do not reproduce the exact ones (checked as in ``FOHFilter``).  When
        each numerator is one kernel and the cascade of poles has a double-precision polynomial
        accurate enough (:func:`polynomial_denominator`), the transfer-function form with that
        denominator (``lfilter``) instead of the sections (``sosfilt``)."""
        sos = all_pole_sections(_conjugate_clean(np.linalg.eigvals(f1.Phi)))
        firs = []
        zs = _TEST_Z
        zinv = 1.0 / zs
        den = np.prod([np.polyval(r[3:][::-1], zinv) for r in sos], axis=0)
        exacts = []
        for f in (f1, f2):
            exact = f.response(zs)
            exacts.append(exact)
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
        # the cascade as one polynomial if that is accurate enough (one lfilter, not sosfilt)
        den_poly = polynomial_denominator(sos, firs, zinv, exacts)
        if den_poly is not None:
            return cls(firs[0], firs[1], den_poly, None)
        return cls(firs[0], firs[1], None, np.ascontiguousarray(sos))


#: Largest number of denominator coefficients (the order) :func:`polynomial_denominator` searches.
POLY_MAX_ORDER = 8

#: Largest probe of :func:`running_error_ok` [samples]; slower poles keep the sections.
PROBE_MAX = 1 << 15

#: How far the all-pole cascade may amplify anything more than it amplifies a constant (its gain
#: at any frequency, the l1 norm of its impulse response, both relative to its DC gain) for the
#: step probe of :func:`running_error_ok` to stand for the worst case (:func:`probe_length`).
DC_PEAK_TOL = 1e-9


def polynomial_denominator(sos: np.ndarray, firs: list, zinv: np.ndarray, exact: list) -> np.ndarray | None:
    """The all-pole cascade ``sos`` as one denominator polynomial ``a`` (ascending powers of 1/z)
    whose filters ``fir / a`` are within 1e-10 of ``exact`` at ``1/zinv`` (checked as in
    ``FOHFilter``), or None.  ``firs``: each numerator as a list of kernels (only single kernels
    qualify); ``exact``: their exact responses.

    One ``lfilter`` pass costs ~1.3 ns/sample less than one ``sosfilt`` pass whatever the order.
    With the poles near z = 1 the polynomial's value there is a difference of coefficients of
    order one (at 20 kHz, ``a(1)`` is 2.9e-6 of coefficients up to 2.9): rounding each
    coefficient to the nearest double leaves ~1e-10 of ``a(1)``, and evaluating the check in
    double adds as much again (so the single transfer function of ``FOHFilter.build`` fails it).
    Here the exact coefficients are the product of the sections in extended precision
    (``np.longdouble``), the doubles within 2 ulp of them (1 ulp beyond order 4) that best match
    the exact denominator at the test points are chosen (:func:`best_rounded_polynomial`: the
    rounding errors of the coefficients then partly cancel where the polynomial is small: 1.6e-11
    instead of 9.2e-11 at 20 kHz), and the check is evaluated in extended precision too.  The
    check bounds the coefficients, not the rounding while the recursion runs: that is probed
    against the sections (:func:`running_error_ok`), and only where a step is the worst case for
    it (:func:`probe_length`: the cascade amplifies nothing more than a constant).  Where
    ``np.longdouble`` is no wider than double (the check could not see the error it is meant to
    bound), the order is above :data:`POLY_MAX_ORDER`, the cascade peaks away from DC (a resonant
    anticausal part), the probe would be longer than :data:`PROBE_MAX` or fails (the seed 000
    sensor at 50 and 100 kHz), None: the sections are kept.
    """
    if any(len(f) != 1 for f in firs) or np.finfo(np.longdouble).eps > 1e-18:
        return None
    sos = np.ascontiguousarray(sos, dtype=float)
    found = _rounded_denominator(sos.tobytes(), sos.shape[0], PROBE_MAX, POLY_MAX_ORDER)
    if found is None:
        return None
    a = np.array(found)
    ld = np.longdouble
    zl = np.asarray(zinv, dtype=np.clongdouble)
    den = _horner(a.astype(ld), zl)
    for fir, ex in zip(firs, exact):
        val = (_horner(np.asarray(fir[0], dtype=ld), zl) / den).astype(complex)
        scale = float(np.max(np.abs(ex)))
        if not np.all(np.abs(val - ex) <= 1e-10 * np.maximum(np.abs(ex), 1e-3 * scale)):
            return None
    return a


@functools.lru_cache(maxsize=32)
def _rounded_denominator(sos_bytes: bytes, n_sections: int, probe_max: int,
                         max_order: int) -> tuple[float, ...] | None:
    """The best-rounded double polynomial of the all-pole sections (see
    :func:`polynomial_denominator`) if its recursion passes :func:`running_error_ok`, else None.
    It depends on the poles only (not on the preview's numerator), so it is kept per cascade: a
    plan for another preview at the same sampling interval does not search and probe again.  The
    limits it is decided under (:data:`PROBE_MAX`, :data:`POLY_MAX_ORDER`) are part of the key.
    The cheap rejections (:func:`probe_length`: an unstable or too slow cascade, one that peaks
    away from DC) come before the search for the coefficients."""
    sos = np.frombuffer(sos_bytes, dtype=float).reshape(n_sections, 6).copy()
    length = probe_length(sos, probe_max)
    if length is None:
        return None
    a = best_rounded_polynomial(sos, max_order)
    if a is None or not _probes_pass(a, sos, length):
        return None
    return tuple(float(v) for v in a)


def best_rounded_polynomial(sos: np.ndarray, max_order: int | None = None) -> np.ndarray | None:
    """The double-precision denominator polynomial of the all-pole sections ``sos`` (ascending
    powers of 1/z) closest to their exact product at the test points (see
    :func:`polynomial_denominator`; no check of the running error), or None above ``max_order``
    (default :data:`POLY_MAX_ORDER`) or where the exact product, though formed in extended
    precision, is not resolved at a test point (poles too clustered: 8 poles within 5e-3 of z = 1,
    whose product at z = 1 is 2.5e-21 of coefficients up to 69, comes out as 0 or as 3e-18 of
    rounding, depending on the numpy version).

    The exact coefficients ``c_i`` are formed once in ``np.longdouble``, with their nearest doubles
    ``n_i`` and the residuals ``r_i = c_i - n_i`` (exact there, then rounded to double).  A
    candidate is ``n_i + d_i``, ``d_i`` one of the steps of -2..2 ulp (-1..1 beyond order 4) to the
    neighbouring doubles (exact in double); its error relative to the exact polynomial at a test
    point ``z`` is ``sum_i (d_i - r_i) z**-i / c(z)``, a sum of terms of the size of an ulp that is
    evaluated in double, for all 5**m (3**m) candidates as one small matrix product.  Evaluating
    the candidates themselves in ``np.clongdouble`` (as before) takes differences of values of the
    size of ``c(z)``, which leave ~2 digits of the errors at 20 kHz, and runs in software where
    ``np.longdouble`` is quad precision (aarch64 Linux); both choose the same coefficients for the
    seed 000 sensor at 20 kHz (equal bits); on x86-64 the search takes 0.2 ms instead of 0.8 there
    (order 3), 2.2 ms instead of 40 at order 8."""
    max_order = POLY_MAX_ORDER if max_order is None else max_order
    ld = np.longdouble
    exact_den = np.ones(1, dtype=ld)
    for r in sos:
        exact_den = np.convolve(exact_den, np.asarray(r[3:], dtype=ld))
    exact_den = np.trim_zeros(exact_den, "b")
    m = exact_den.size - 1
    if m < 1 or m > max_order:
        return None
    zinv = 1.0 / _TEST_Z
    ref_ld = _horner(exact_den, zinv.astype(np.clongdouble))
    # resolved: the rounding of the product and of its evaluation (~(m+1) eps of the coefficients'
    # sum) below 1e-3 of its value, so that the candidates' errors relative to it are meaningful
    floor = 1024 * (m + 1) * np.finfo(ld).eps * np.sum(np.abs(exact_den))
    if not np.all(np.isfinite(ref_ld) & (np.abs(ref_ld) > floor)):
        return None
    ref = ref_ld.astype(complex)
    nearest = exact_den.astype(float)
    resid = (exact_den - nearest.astype(ld)).astype(float)
    span = 2 if m <= 4 else 1
    # the neighbouring doubles of each coefficient 1..m (the leading 1 is exact), -span .. +span ulp
    values = np.empty((m, 2 * span + 1))
    for i in range(m):
        c = nearest[i + 1]
        ups, downs = [c], [c]
        for _ in range(span):
            ups.append(np.nextafter(ups[-1], np.inf))
            downs.append(np.nextafter(downs[-1], -np.inf))
        values[i] = downs[:0:-1] + ups
    # every combination of them, as indices: (candidates, m)
    grid = np.stack(np.meshgrid(*([np.arange(2 * span + 1)] * m), indexing="ij"), axis=-1).reshape(-1, m)
    dev = (values - nearest[1:, None] - resid[1:, None])[np.arange(m), grid]
    powers = zinv[None, :] ** np.arange(1, m + 1)[:, None]
    err = np.max(np.abs(dev @ powers) / np.abs(ref), axis=1)
    best = grid[int(np.argmin(err))]
    return np.concatenate(([1.0], values[np.arange(m), best]))


def probe_length(sos: np.ndarray, probe_max: int | None = None) -> int | None:
    """Samples of the running-error probe of the all-pole sections ``sos`` (:func:`running_error_ok`):
    20 time constants of the slowest pole, at least 2,000; None where that is longer than
    ``probe_max`` (default :data:`PROBE_MAX`), the cascade is not stable, or its probe on a step
    would not be the worst case.

    The rounding while ``lfilter(1, a)`` runs is a sequence of small local errors ``e[k]`` that
    the recursion itself propagates: the output is off by ``h * e``, ``h`` the impulse response
    of ``1/a``.  A step (a constant input repeats the same rounding: the errors add up
    coherently) and a slowly varying walk see its DC gain; a sine sees ``|1/a(e^jw)|`` at its
    frequency, and an error sequence matched to the signs of ``h`` sees ``||h||_1``.  Where
    ``|1/a|`` peaks away from DC this is beyond what the probes measure (a resonant anticausal
    part at 20 kHz, sensor ``poly([600, 15±200j]) / poly([-1000]*3)``: the probes accepted the
    polynomial, a sine at the resonance ran 1.15e-10 off the extended-precision recursion, the
    sections 1.0e-11).  So the polynomial is only considered where a constant is amplified the
    most: ``|1/a|`` is at most ``1 + DC_PEAK_TOL`` times its DC value on a dense grid of
    frequencies (computed from the poles, each factor ``|1 - p/z|**2 = (1-|p|)**2 + 4|p|
    sin**2((w - arg p)/2)`` without cancellation near z = 1), and ``||h||_1`` (over the probe's
    length) at most ``1 + DC_PEAK_TOL`` times ``|sum h|``, i.e. ``h`` is nonnegative up to that.
    The second bound is the one that makes the step the worst case: no error sequence of a given
    size is amplified more than by ``||h||_1 = sum h``, and a constant one gets that much (a sine
    at the frequency of the largest ``|1/a|`` would be the step itself).  It also implies the
    first at every frequency (``|1/a(e^jw)| <= ||h||_1``); the grid states the peak condition on
    its own and does not depend on the truncation of ``h``.  Seed 000 at 20 kHz: ``h`` > 0 (its
    complex pair alone has a negative lobe, ``||h||_1`` 2.4% above ``sum h``, which the slow real
    pole smooths out), kept."""
    probe_max = PROBE_MAX if probe_max is None else probe_max
    poles = np.concatenate([np.roots(r[3:]) for r in sos])
    rho = float(np.max(np.abs(poles)))
    if not rho < 1.0 or 20.0 / (1.0 - rho) > probe_max:
        return None
    length = max(2000, int(math.ceil(20.0 / (1.0 - rho))))
    r, theta = np.abs(poles)[:, None], np.angle(poles)[:, None]
    d = 1.0 - r
    w = np.concatenate((np.linspace(0.0, np.pi, 2049), np.geomspace(1e-3 * float(np.min(d)), np.pi, 2049),
                        (np.abs(theta) + d * np.linspace(-8.0, 8.0, 161)).ravel(), [0.0]))
    w = w[(w >= 0.0) & (w <= np.pi)]
    log_a2 = np.sum(np.log(d**2 + 4.0 * r * np.sin((w - theta) / 2.0) ** 2), axis=0)   # log |a(e^jw)|**2
    if not np.min(log_a2) >= log_a2[-1] - 2.0 * math.log1p(DC_PEAK_TOL):
        return None
    impulse = np.zeros(length)
    impulse[0] = 1.0
    h = sig.sosfilt(sos, impulse)
    if not np.sum(np.abs(h)) <= (1.0 + DC_PEAK_TOL) * abs(float(np.sum(h))):
        return None
    return length


def running_error_ok(a: np.ndarray, sos: np.ndarray, probe_max: int | None = None) -> bool:
    """The recursion ``lfilter(1, a)`` stays within half the 1e-10 guarantee of the sections
    ``sos`` (accurate to ~1e-13, measured) on a step and on a random walk, relative to the
    largest output, and the step is the worst case for its rounding (:func:`probe_length`,
    which also sets the length, at most ``probe_max``, default :data:`PROBE_MAX`: slower poles
    fail).  The check at the test points bounds the coefficients, not the rounding while the
    recursion runs, which near z = 1 is amplified by up to ``1/|a(1)|`` (at 100 kHz the seed 000
    polynomial passes the check at 1.0e-11 but runs 3-4e-10 off the explicit recursion).  A step
    is where the rounding errors add up coherently (a constant input repeats the same rounding),
    a random walk a slowly varying input; each runs 20 time constants of the slowest pole; half
    of 1e-10 is the margin for other signals.  Measured for the seed 000 sensor at 20 kHz:
    2.1e-11 (step) and 1.5e-11 (walk) here, and 2.5e-11 at most against an explicit
    extended-precision recursion on 2**21-sample records."""
    length = probe_length(sos, probe_max)
    return length is not None and _probes_pass(a, sos, length)


def _probes_pass(a: np.ndarray, sos: np.ndarray, length: int) -> bool:
    """``lfilter(1, a)`` within 0.5e-10 of ``sosfilt(sos)`` on a step and a random walk of ``length``
    samples, relative to the largest output (see :func:`running_error_ok`)."""
    walk = np.cumsum(np.random.default_rng(0).standard_normal(length))
    for x in (np.ones(length), walk):
        ref = sig.sosfilt(sos, x)
        got = sig.lfilter(np.ones(1), a, x)
        if not np.max(np.abs(got - ref)) <= 0.5e-10 * float(np.max(np.abs(ref))):
            return False
    return True


def _horner(coeffs: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``sum_i coeffs[i] x**i`` (ascending powers; ``coeffs`` may carry trailing axes)."""
    out = np.zeros(np.broadcast_shapes(x.shape, coeffs.shape[1:]), dtype=np.result_type(coeffs, x))
    for c in coeffs[::-1]:
        out = out * x + c
    return out
