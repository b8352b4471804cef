"""Initial guesses for one temperature: Levy, Sanathanan–Koerner, log-spread poles.

All work in scaled variables (w̃ = ω/ω_ref, h = H/g_ref) and return degree-0 parameter
vectors of a ``sections`` (stable) or ``coefficients`` (free) structure.
"""

from __future__ import annotations

import numpy as np

from physmodel.numerics import weighted_complex_lstsq

from ._structure import (
    Structure,
    group_roots,
    pole_slots_from_groups,
    stabilise_roots,
)

__all__ = ["levy", "numerator_ls", "initial_candidates"]


def _solve_weighted(a: np.ndarray, rhs: np.ndarray, row_weight: np.ndarray) -> np.ndarray:
    return weighted_complex_lstsq(a, rhs, np.asarray(row_weight, dtype=float))


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


def numerator_ls(w, h, n_zeros: int, den, relative: bool = True):
    """Best numerator for a fixed denominator (linear least squares, relative error)."""
    jw = 1j * np.asarray(w, float)
    h = np.asarray(h, complex)
    d = np.polynomial.polynomial.polyval(jw, den)
    a = jw[:, None] ** np.arange(n_zeros + 1)
    wt = 1.0 / np.abs(d)
    if relative:
        wt = wt / np.abs(h)
    return _solve_weighted(a, h * d, wt)


def sanathanan_koerner(w, h, n_zeros, n_poles, n_iter: int = 8):
    """SK iterations (relative weighting); returns every iterate, Levy's first."""
    rel = 1.0 / np.abs(h)
    num, den = levy(w, h, n_zeros, n_poles, rel)
    out = [(num, den)]
    jw = 1j * np.asarray(w, float)
    for _ in range(n_iter):
        d = np.abs(np.polynomial.polynomial.polyval(jw, den))
        if not np.all(np.isfinite(d)) or np.any(d == 0):
            break
        num, den = levy(w, h, n_zeros, n_poles, rel / d)
        out.append((num, den))
    return out


def _stable_sections_theta(w, h, n_zeros, den_roots):
    quads, single = group_roots(stabilise_roots(den_roots))
    poles_part = pole_slots_from_groups(quads, single)
    den = np.real(np.poly(stabilise_roots(den_roots))[::-1])
    num = numerator_ls(w, h, n_zeros, den)
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


def initial_candidates(structure: Structure, w, h, problem_cost) -> list[tuple[str, np.ndarray]]:
    """Distinct starting points, best (lowest ``problem_cost``) first."""
    m, n = structure.n_zeros, structure.n_poles
    cands = []
    sk = sanathanan_koerner(w, h, m, n)
    with np.errstate(all="ignore"):
        if structure.form == "coefficients":
            for i, (num, den) in enumerate(sk):
                cands.append(("levy" if i == 0 else f"sk{i}", np.concatenate([num, den[:-1]])))
        else:
            for i, (num, den) in enumerate(sk):
                if np.all(np.isfinite(den)):
                    theta = _stable_sections_theta(w, h, m, np.roots(den[::-1]))
                    cands.append(("levy" if i == 0 else f"sk{i}", theta))
            cands.append(("spread", _stable_sections_theta(w, h, m, spread_poles(w, n))))
    scored = []
    for name, th in cands:
        if np.all(np.isfinite(th)):
            scored.append((problem_cost(th), name, th))
    scored.sort(key=lambda t: t[0])
    # keep Levy (the classic answer), the best SK iterate and the log-spread start
    keep, seen = [], set()
    for c, name, th in scored:
        tag = "sk" if name.startswith("sk") else name
        if tag not in seen and np.isfinite(c):
            seen.add(tag)
            keep.append((name, th))
    return keep
