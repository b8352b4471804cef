"""Initial guesses for one temperature: Levy, Sanathanan–Koerner, log-spread poles.

All work in scaled variables (w̃ = ω/ω_ref, h = H/g_ref) and return degree-0 parameter
vectors of a ``sections`` (stable) or ``coefficients`` (free) structure.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from physmodel.numerics import stacked_weighted_lstsq, weighted_complex_lstsq

from ._convert import group_roots, pole_slots_from_groups, stabilise_roots
from ._structure import Structure

__all__ = ["levy", "numerator_ls", "initial_candidates"]


def _solve_weighted(a: np.ndarray, rhs: np.ndarray, row_weight: np.ndarray) -> np.ndarray:
    return weighted_complex_lstsq(a, rhs, np.asarray(row_weight, dtype=float))


def _horner(x: np.ndarray, c) -> np.ndarray:
    """Σ c_i x^i by Horner's rule, the operations of ``numpy.polynomial.polynomial.polyval``
    (the same numbers) without its argument handling."""
    c0 = c[-1] + x * 0
    for i in range(2, len(c) + 1):
        c0 = c[-i] + c0 * x
    return c0


def levy(w, h, n_zeros: int, n_poles: int, row_weight=None):
    """Levy's linearised least squares: min Σ |wt·(N(jw̃) − h·D(jw̃))|², D monic.

    With ``row_weight=None`` this is what Octave's ``invfreqs`` solves (no iterations).
    Returns ``(num, den)``, ascending coefficients in s̃, ``den[-1] = 1``.
    """
    w = np.asarray(w, float)
    h = np.asarray(h, complex)
    jw = 1j * w
    vz = jw[:, None] ** np.arange(n_zeros + 1)
    vp = jw[:, None] ** np.arange(n_poles)
    a = np.hstack([vz, -h[:, None] * vp])
    rhs = h * jw ** n_poles
    wt = np.ones_like(w) if row_weight is None else np.asarray(row_weight, float)
    sol = _solve_weighted(a, rhs, wt)
    return sol[: n_zeros + 1], np.append(sol[n_zeros + 1:], 1.0)


def numerator_ls(w, h, n_zeros: int, den, relative: bool = True, powers=None):
    """Best numerator for a fixed denominator (linear least squares, relative error).
    ``powers``: (jw̃)^k for k = 0..≥n_zeros (columns), if already at hand."""
    jw = 1j * np.asarray(w, float)
    h = np.asarray(h, complex)
    d = _horner(jw, den)
    a = jw[:, None] ** np.arange(n_zeros + 1) if powers is None else powers[:, :n_zeros + 1]
    wt = 1.0 / np.abs(d)
    if relative:
        wt = wt / np.abs(h)
    return _solve_weighted(a, h * d, wt)


#: SK stops once its weights 1/|D(jw̃)| change by less than this (largest relative change over
#: the lines): the next iterate would move the start by about as much, which the
#: Levenberg–Marquardt solve that follows removes in its first step
SK_WEIGHT_CHANGE = 1e-2


def sanathanan_koerner(w, h, n_zeros, n_poles, n_iter: int = 8, powers=None,
                       weight_change: float = SK_WEIGHT_CHANGE):
    """SK iterations (relative weighting); returns every iterate, Levy's first.
    ``powers``: (jw̃)^k for k = 0..n_poles (columns), if already at hand.  Stops after
    ``n_iter`` reweightings, or earlier once the weights have converged: the largest relative
    change of |D(jw̃)| between two iterates is at most ``weight_change`` (0: never early)."""
    w = np.asarray(w, float)
    h = np.asarray(h, complex)
    jw = 1j * w
    vd = jw[:, None] ** np.arange(n_poles + 1) if powers is None else powers[:, :n_poles + 1]
    a = np.hstack([vd[:, :n_zeros + 1] if n_zeros <= n_poles else jw[:, None] ** np.arange(n_zeros + 1),
                   -h[:, None] * vd[:, :n_poles]])
    rhs = h * vd[:, n_poles]
    rel = 1.0 / np.abs(h)
    n_w = w.size
    ar = np.concatenate([a.real, a.imag])               # the system stacked once, reweighted below
    br = np.concatenate([rhs.real, rhs.imag])
    wt2 = np.empty(2 * n_w)
    wt2[:n_w] = wt2[n_w:] = rel
    out = []
    d_old = None
    for i in range(n_iter + 1):
        sol = stacked_weighted_lstsq(ar, br, wt2)
        den = np.empty(n_poles + 1)
        den[:n_poles], den[n_poles] = sol[n_zeros + 1:], 1.0
        out.append((sol[:n_zeros + 1], den))
        if i == n_iter:
            break
        d = np.abs(vd @ den)
        if not (np.isfinite(d).all() and d.all()):
            break
        if d_old is not None and np.abs(d / d_old - 1.0).max() <= weight_change:
            break
        d_old = d
        np.divide(rel, d, out=wt2[:n_w])
        wt2[n_w:] = wt2[:n_w]
    return out


def _stable_sections_theta(w, h, n_zeros, den_roots, num=None, powers=None):
    """Sections parameters for the given poles (unstable ones reflected).  ``num`` (the
    numerator that came with these poles) is kept when no pole had to be moved; otherwise
    the numerator is refitted by linear least squares."""
    rts = np.asarray(den_roots, complex)
    stable = stabilise_roots(rts)
    quads, single = group_roots(stable)
    poles_part = pole_slots_from_groups(quads, single)
    if num is None or np.any(stable != rts):
        den = np.real(np.poly(stable)[::-1])
        num = numerator_ls(w, h, n_zeros, den, powers=powers)
    return np.concatenate([num, poles_part])


def spread_poles(w, n_poles: int, damping: float = 0.5) -> np.ndarray:
    """Poles log-spaced over the band: damped pairs and (odd order) one real pole."""
    lo, hi = np.log(np.min(w)), np.log(np.max(w))
    n_pairs = n_poles // 2
    mags = np.exp(np.linspace(lo, hi, n_pairs + 2)[1:-1]) if n_pairs else np.array([])
    rts = []
    for m in mags:
        rts += [m * (-damping + 1j * np.sqrt(1 - damping ** 2)),
                m * (-damping - 1j * np.sqrt(1 - damping ** 2))]
    if n_poles % 2:
        rts.append(-np.exp(0.5 * (lo + hi)))
    return np.array(rts, complex)


@lru_cache(maxsize=64)
def _spread_sections(w_min: float, w_max: float, n_poles: int) -> tuple[np.ndarray, np.ndarray]:
    """Pole slots and monic denominator (ascending) of ``spread_poles`` over [w_min, w_max]:
    they depend on the band only, so the fits of a sweep's temperatures (one band) share
    them.  The same operations as ``_stable_sections_theta`` applies to any poles."""
    stable = stabilise_roots(spread_poles(np.array([w_min, w_max]), n_poles))
    slots = np.array(pole_slots_from_groups(*group_roots(stable)), float)
    den = np.real(np.poly(stable)[::-1])
    slots.flags.writeable = den.flags.writeable = False
    return slots, den


def _sk_costs(sk, structure, costs):
    """Cost of each SK iterate as it stands (coefficient form, one batched evaluation),
    +inf where a pole is unstable (those would be reflected before use), and the poles of
    every iterate (one batched eigenvalue call; NaN where the denominator is not finite)."""
    n = structure.n_poles
    dens = np.array([den for _, den in sk])                   # (k, n+1), monic
    comp = np.zeros((len(sk), n, n))
    comp[:, 0, :] = -dens[:, -2::-1]
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    ok = np.all(np.isfinite(comp), axis=(1, 2))
    poles = np.full((len(sk), n), np.nan, complex)
    if ok.any():
        poles[ok] = np.linalg.eigvals(comp[ok])
    stable = np.all(poles.real < 0, axis=1)
    coef = structure.with_form("coefficients")
    thetas = np.concatenate([np.array([num for num, _ in sk]), dens[:, :-1]], axis=1)
    c = np.asarray(costs(coef, thetas), float)
    return np.where(stable & np.isfinite(c), c, np.inf), poles


def initial_candidates(structure: Structure, w, h, costs, powers=None) -> list[tuple[str, np.ndarray]]:
    """Distinct starting points, best first: Levy's answer, the best Sanathanan–Koerner
    iterate and (stable forms) poles log-spread over the band.

    ``costs(structure, thetas)`` scores a stack of parameter vectors (k, p) of a structure
    with these orders (the fit's own, or the coefficient form for ranking the raw SK
    iterates, so that only the best stable one is converted to sections).  ``powers``:
    (jw̃)^k for k = 0..max(orders) (columns), if already at hand (``Evaluator.spow``).
    """
    m, n = structure.n_zeros, structure.n_poles
    cands = []
    w = np.asarray(w, float)
    if powers is None:                                          # shared by SK and the numerators
        powers = (1j * w)[:, None] ** np.arange(max(m, n) + 1)
    sk = sanathanan_koerner(w, h, m, n, powers=powers)
    with np.errstate(all="ignore"):
        if structure.form == "coefficients":
            for i, (num, den) in enumerate(sk):
                cands.append(("levy" if i == 0 else f"sk{i}", np.concatenate([num, den[:-1]])))
        else:
            raw, poles = _sk_costs(sk, structure, costs)
            picks = list(range(len(sk)))
            if len(sk) > 1:
                j = 1 + int(np.argmin(raw[1:]))
                if np.isfinite(raw[j]):   # else: no stable SK iterate, convert them all
                    picks = [0, j]
            for i in picks:
                num, den = sk[i]
                if np.all(np.isfinite(poles[i])):
                    theta = _stable_sections_theta(w, h, m, poles[i], num, powers)
                    cands.append(("levy" if i == 0 else f"sk{i}", theta))
            slots, den = _spread_sections(float(w.min()), float(w.max()), n)
            cands.append(("spread", np.concatenate([numerator_ls(w, h, m, den, powers=powers), slots])))
    cands = [(name, th) for name, th in cands if np.isfinite(th).all()]
    if not cands:
        return []
    c = np.asarray(costs(structure, np.array([th for _, th in cands])), float)
    order = np.argsort(np.where(np.isfinite(c), c, np.inf), kind="stable")
    # keep Levy (the classic answer), the best SK iterate and the log-spread start
    keep, seen = [], set()
    for i in order:
        name, th = cands[i]
        tag = "sk" if name.startswith("sk") else name
        if tag not in seen and np.isfinite(c[i]):
            seen.add(tag)
            keep.append((name, th))
    return keep
