"""Levenberg–Marquardt steps for the least-squares engine's later starts
(:func:`physmodel.estimation.lsq.fit_parameters`), kept apart from :mod:`~physmodel.estimation.lsq`
for its size."""

from __future__ import annotations

import numpy as np

__all__ = ["LM_STEPS", "damped_steps"]

#: Damped steps a later start takes before handing over to scipy's trust region.
LM_STEPS = 30


def damped_steps(pt, evaluate, lo, hi, count, stopped_at_budget):
    """Levenberg-Marquardt from the point ``pt``, a tuple ``(z, r, J, status, message, step,
    cost, joined)`` as the engine's ``evaluate(z)`` returns it (cached and counted in ``count``).

    Steps ``(JᵀJ + λ diag JᵀJ) d = -Jᵀr`` clipped to just inside the box [lo, hi]; λ is divided by 3 after a
    decrease and multiplied by 4 after an increase.  Ends at a point with a status (converged, or
    joined an earlier optimum), after ``LM_STEPS`` points, at the budget, when λ exceeds 1e10 or
    when a clipped step no longer moves.  Returns the lowest point reached (a later start's
    search is cheaper this way than in scipy's trust region, which rebuilds its model from an
    SVD every iteration).
    """
    # strictly inside the box, as scipy's trust region keeps its points: a bound itself can map
    # back to a physical value a rounding outside it (10**log10(0.005) < 0.005)
    lo_in = lo + 1e-10 * np.maximum(1.0, np.abs(lo))
    hi_in = hi - 1e-10 * np.maximum(1.0, np.abs(hi))
    tight = lo_in > hi_in
    lo_in[tight] = hi_in[tight] = 0.5 * (lo[tight] + hi[tight])
    lam = 1e-3
    for _ in range(LM_STEPS):
        if pt[3] is not None or stopped_at_budget() or lam > 1e10:
            break
        z, r, J = pt[0], pt[1], pt[2]
        A = J.T @ J
        g = J.T @ r
        d = np.maximum(np.diag(A), 1e-12 * max(float(np.max(np.diag(A))), 1e-300))
        try:
            step = np.linalg.solve(A + lam * np.diag(d), -g)
        except np.linalg.LinAlgError:
            lam *= 4.0
            continue
        z_new = np.clip(z + step, lo_in, hi_in)
        if np.array_equal(z_new, z):
            break
        count[0] += 1
        new = evaluate(z_new)
        if new[6] < pt[6]:
            pt, lam = new, lam / 3.0
        else:
            lam *= 4.0
    return pt
