"""Per-start step control of :class:`surrogate._lsq.LevenbergMarquardt`, on Python floats.

A fit races a few starts in lockstep; after the batched residual evaluation, deciding per
start whether its step is accepted and how its damping changes is a handful of scalar
operations, cheaper on Python floats than as ~25 array operations on arrays of a few
elements.  The arithmetic is the same IEEE arithmetic as the array form it replaced.
"""

from __future__ import annotations

import numpy as np

__all__ = ["step_control"]


def step_control(rr, rrt, pred, stationary, mu, nu, dx):
    """Gain ratio, acceptance and damping update of every start, on Python floats:

        actual = rr − rrt,  ρ = actual/pred (NaN unless pred > 0),
        accepted = ρ > 1e-4 and not stationary,
        μ ← μ·max(1/3, 1 − (2ρ − 1)³) if accepted else μ·ν,   ν ← 2 if accepted else 2ν,
        ended = stationary or (not accepted and (μ > 1e30 or the step is zero)).

    The same IEEE operations as the array expressions they replace (the cube by numpy's
    power, which can differ from libm's in the last bit).  Returns (accepted, μ array,
    ν array, ended, actual) (lists of bools / floats but μ, ν)."""
    rr_l, rrt_l, pred_l = rr.tolist(), rrt.tolist(), pred.tolist()
    st_l, mu_l, nu_l = stationary.tolist(), mu.tolist(), nu.tolist()
    moved = dx.any(axis=1).tolist()
    nan = float("nan")
    actual = [a - b for a, b in zip(rr_l, rrt_l, strict=True)]    # NaN where rt is not finite
    rho = [a / p if p > 0 else nan for a, p in zip(actual, pred_l, strict=True)]
    cube = ((2 * np.array(rho) - 1) ** 3).tolist()               # numpy's power, not libm's
    acc, end = [], []
    for j in range(len(rr_l)):
        ok = rho[j] > 1e-4 and not st_l[j]
        if ok:
            mu_l[j] = mu_l[j] * max(1 / 3, 1 - cube[j])
            nu_l[j] = 2.0
        else:
            mu_l[j] = mu_l[j] * nu_l[j]
            nu_l[j] = nu_l[j] * 2.0
        acc.append(ok)
        end.append(bool(st_l[j] or (not ok and (mu_l[j] > 1e30 or not moved[j]))))
    return acc, np.array(mu_l), np.array(nu_l), end, actual
