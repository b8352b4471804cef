"""Overflow- and cancellation-safe complex kernels shared by the physical sub-models.

The closed forms contain cosh/sinh of arguments with real parts of 1e3-1e4 (γ) and differences
such as γ − tanh γ or 1 − sech x − x tanh x that lose every digit for small arguments.  Nothing
here forms cosh or sinh: everything is written with ``em1 = expm1(-x)`` on the branch Re x ≥ 0
(principal square roots give that branch, and every final expression is even in its argument):

    e = 1 + em1 = exp(-x),  tanh x = -em1 (2 + em1) / (1 + e²),  sech x = 2e / (1 + e²).

These are exact rewritings, accurate to a few ulps for every x with Re x ≥ 0, including tiny
|x| (expm1 keeps the digits of 1 − e^{-x}).  The remaining cancellations are removed by series
below the thresholds given with each function; tests compare both sides of each switch with
mpmath at 50 digits.
"""

from __future__ import annotations

import functools
import threading

import numpy as np

#: |γ| below which γ − tanh γ is summed from its Taylor series.
GMT_SERIES_BELOW = 0.1
#: |x| below which the bending kernel X(x) and x coth x use their Taylor series.
X_SERIES_BELOW = 1e-4

# Taylor coefficients of (x - tanh x)/x^3 in powers of x^2 (from the Bernoulli-number series of
# tanh): 1/3, -2/15, 17/315, -62/2835, 1382/155925, -21844/6081075, 929569/638512875.
_GMT_COEF = np.array([1 / 3, -2 / 15, 17 / 315, -62 / 2835, 1382 / 155925, -21844 / 6081075, 929569 / 638512875])
# X(x) = (x tanh x + sech x - 1)/x^2 = 1/2 - x^2/8 + 7 x^4/144 - 113 x^6/5760 + ...
_X_COEF = np.array([1 / 2, -1 / 8, 7 / 144, -113 / 5760])
# x coth x = 1 + x^2/3 - x^4/45 + 2 x^6/945
_XCOTH_COEF = np.array([1.0, 1 / 3, -1 / 45, 2 / 945])


def _poly_x2(coef: np.ndarray, x2):
    """Horner evaluation of sum coef[k] (x2)^k."""
    acc = np.full_like(x2, coef[-1])
    for c in coef[-2::-1]:
        acc = acc * x2 + c
    return acc


#: |argument| above which exp() (not expm1) is accurate enough: 1 − e^{-z} loses < 1.3 digits.
EXP_FAST_ABOVE = 0.1


def _em1(z):
    """expm1(−z) for Re z ≥ 0: exp on the bulk (half the cost), expm1 where |z| is small."""
    em1 = np.exp(-z)
    em1 -= 1.0
    small = np.abs(z) < EXP_FAST_ABOVE
    if np.any(small):
        em1[small] = np.expm1(-z[small])
    return em1


#: Re γ above which tanh γ = 1 to double precision (2 e^{-2γ} < 1e-17).
TANH_IS_ONE_ABOVE = 20.0


def tanh_and_gmt(g, min_real=None):
    """``tanh γ`` and ``γ − tanh γ`` for complex γ with Re γ ≥ 0, without overflow or cancellation.

    Returns ``(tanh_g, g_minus_tanh_g)``.  Where Re γ > 20 (every physical case: γ ~ 1e3-1e4)
    tanh γ is exactly 1.0 in double precision and no transcendental is evaluated; when that holds
    everywhere ``tanh_g`` is returned as the scalar 1.0.  ``min_real``: a known lower bound of
    Re γ (skips the scan).
    """
    g = np.asarray(g, dtype=complex)
    if min_real is not None and min_real > TANH_IS_ONE_ABOVE:
        return 1.0, g - 1.0
    near = g.real <= TANH_IS_ONE_ABOVE
    if not np.any(near):
        return 1.0, g - 1.0
    t = np.ones_like(g)
    gn = g[near]
    em1 = _em1(2.0 * gn)
    tn = -em1 / (2.0 + em1)
    gmt_n = gn - tn
    small = np.abs(gn) < GMT_SERIES_BELOW
    if np.any(small):
        gs = gn[small]
        gmt_n[small] = gs**3 * _poly_x2(_GMT_COEF, gs * gs)
    t[near] = tn
    gmt = g - 1.0
    gmt[near] = gmt_n
    return t, gmt


def _negated(z, out=None):
    """−z for a complex array: the signs flipped on its doubles (exact, and several times faster
    than numpy's complex negation); plain negation for a 0-d or non-contiguous array."""
    if z.ndim and z.flags.c_contiguous and (out is None or out is z):
        v = z.view(np.float64)
        return np.negative(v, out=None if out is None else v).view(complex)
    return np.negative(z, out=out)


#: Re x above which sech x < 1e-17 relative to x tanh x: X = (x − 1)/x², x coth x = x.
LINE_ASYMPTOTIC_ABOVE = 40.0


def line_kernels(x, want_xcoth: bool = True):
    """Distributed-electrode kernels of ``x = L sqrt(B)`` (Re x ≥ 0).

    Returns ``(X, xcoth)`` with

    * ``X(x) = (x tanh x + sech x − 1)/x²`` — the bending kernel of seed 002 eq. (14) (there
      written −(1 − sech x − x tanh x)/x²); X → 1/2 for x → 0 (uniform moment);
    * ``xcoth = x coth x`` → 1 for x → 0 (terminal impedance factor); None if not wanted.

    With e = e^{-x}, em1 = e − 1: x tanh x + sech x − 1 = −em1 (x (2 + em1) + em1)/(1 + e²),
    which has no cancellation beyond a factor 2, so the series is needed only for |x| < 1e-4;
    expm1 replaces exp − 1 for |x| < 0.1.
    """
    x = np.asarray(x, dtype=complex)
    # |x| ≥ Re x: the real parts decide the usual case without |x| (the same test's outcome)
    if x.size and (x.real.min() >= EXP_FAST_ABOVE or np.abs(x).min() >= EXP_FAST_ABOVE):
        em1 = np.exp(_negated(x))
        em1 -= 1.0
        small = None
        xs = x
    else:
        small = np.abs(x) < X_SERIES_BELOW
        xs = np.where(small, 1.0, x)
        em1 = _em1(xs)
    two_p = em1 + 2.0
    one_p_e2 = two_p * em1          # e² + 1 = (em1 + 1)² + 1 = em1 (em1 + 2) + 2
    one_p_e2 += 2.0
    num = xs * two_p
    num += em1
    num *= em1
    den = one_p_e2 * xs
    den *= xs
    X = np.divide(num, den, out=num)
    _negated(X, out=X)
    xcoth = None
    if want_xcoth:
        xcoth = xs * one_p_e2
        two_p *= em1
        xcoth /= two_p
        _negated(xcoth, out=xcoth)
    if small is not None and np.any(small):
        x2 = x[small] ** 2
        X[small] = _poly_x2(_X_COEF, x2)
        if want_xcoth and xcoth is not None:
            xcoth[small] = _poly_x2(_XCOTH_COEF, x2)
    return X, xcoth


def weighted_complex_lstsq(M, rhs, row_weight):
    """Real least-squares solution of the complex system ``M x ≈ rhs`` (x real), rows weighted.

    Real and imaginary parts are stacked, columns scaled to unit norm for conditioning, solved
    by LAPACK ``gelsd`` (what ``numpy.linalg.lstsq`` runs, with its default cutoff
    ``eps·max(rows, columns)`` on the singular values; called directly, as these systems are
    small and solved many times) and unscaled.  Shared by vector fitting (timesim) and the Levy /
    Sanathanan-Koerner initialisers (surrogate).
    """
    M = np.asarray(M)
    rhs = np.asarray(rhs)
    m = M.shape[0]
    Mr = np.empty((2 * m, M.shape[1]))
    Mr[:m], Mr[m:] = M.real, M.imag
    rr = np.empty(2 * m)
    rr[:m], rr[m:] = rhs.real, rhs.imag
    w = np.asarray(row_weight, float)
    return stacked_weighted_lstsq(Mr, rr, np.concatenate([w, w]))


def stacked_weighted_lstsq(Mr, rr, row_weight):
    """``weighted_complex_lstsq`` with the real and imaginary parts already stacked:
    ``Mr`` (2m, n) = [Re M; Im M], ``rr`` (2m,) = [Re rhs; Im rhs], ``row_weight`` (2m,) =
    the line weights twice.  (The same numbers: a real weight scales the real and imaginary
    parts of a complex row exactly.)  For a system solved with many weightings (the
    Sanathanan–Koerner iterations) the stacking is done once."""
    Mw = Mr * row_weight[:, None]
    rw = rr * row_weight
    rows, n = Mw.shape
    scale = np.sqrt(_einsum("ij,ij->j", Mw, Mw))
    scale[scale == 0] = 1.0
    Mw /= scale
    cond = _EPS * max(rows, n)
    if rows < n:                        # underdetermined: numpy pads the right-hand side
        x, *_ = np.linalg.lstsq(Mw, rw, rcond=cond)
        return x / scale
    lwork, liwork = _gelsd_work(rows, n, cond)
    x, _, _, info = _GELSD[0](Mw, rw, lwork, liwork, cond, True, True)
    if info != 0:                       # not converged (or bad input): numpy's path raises clearly
        x, *_ = np.linalg.lstsq(Mw, rw, rcond=cond)
        return x / scale
    return x[:n] / scale


_EPS = float(np.finfo(float).eps)
_GELSD: list = []
try:        # what numpy.einsum calls (optimize=False), without its dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:  # pragma: no cover - other numpy layouts
    _einsum = np.einsum


@functools.lru_cache(maxsize=64)
def _gelsd_work(rows: int, cols: int, cond: float) -> tuple[int, int]:
    """Workspace sizes of ``gelsd`` for one right-hand side (LAPACK's query, once per shape)."""
    from scipy.linalg import lapack

    if not _GELSD:
        _GELSD.extend(lapack.get_lapack_funcs(("gelsd", "gelsd_lwork"), (np.zeros((1, 1)),)))
    work, iwork, info = _GELSD[1](rows, cols, 1, cond)
    if info != 0:
        raise ValueError(f"gelsd workspace query failed (info={info}) for a {rows}x{cols} system")
    return int(np.real(work)), int(iwork)


def principal_sqrt(z):
    """Principal complex square root (Re ≥ 0), the branch the closed forms assume."""
    return np.sqrt(np.asarray(z, dtype=complex))

def one_blas_thread(fn):
    """Run ``fn`` with BLAS held to one thread (a decorator): for small solves threads only stall, and
    the iterates must not depend on the machine's thread count (the reduction order of a threaded
    BLAS changes the last bits, and with them which start wins a race or where a solver stops —
    seen with numpy 1.24's OpenBLAS on two cores).

    The BLAS libraries are looked up once (a ``threadpoolctl.ThreadpoolController`` built on the
    first call, after numpy and scipy are loaded: a fresh lookup reads ``/proc/self/maps``, about
    2 ms, which was a third of a small rational fit), and a call made while the limit is already
    held (a decorated function calling another) does not set it again.

    Parameters
    ----------
    fn : callable
        The function to wrap.
    """
    import functools

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        if getattr(_BLAS_HELD, "held", False):
            return fn(*args, **kwargs)
        with _blas_controller().limit(limits=1, user_api="blas"):
            _BLAS_HELD.held = True
            try:
                return fn(*args, **kwargs)
            finally:
                _BLAS_HELD.held = False

    return wrapped


_BLAS_HELD = threading.local()


@functools.lru_cache(maxsize=1)
def _blas_controller():
    """The process's BLAS thread pools (looked up once)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()
