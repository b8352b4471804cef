"""Levenberg–Marquardt steps for the least-squares engine's later starts
(:func:`physmodel.estimation.lsq.fit_parameters`) and the profile search it runs when scipy's
trust region crawls along a curved valley, kept apart from :mod:`~physmodel.estimation.lsq` for
its size."""

from __future__ import annotations

import numpy as np

__all__ = ["LM_STEPS", "damped_steps", "crawling", "profile_search", "CRAWL_POINTS", "CRAWL_GAIN", "CRAWL_DECREMENT",
           "CRAWL_SEARCHES", "PROFILE_STEPS", "PROFILE_STALE", "INNER_POINTS",
           "INNER_DECREMENT"]

#: Damped steps a later start takes before handing over to scipy's trust region.
LM_STEPS = 30


def damped_steps(pt, evaluate, lo, hi, count, stopped_at_budget):
    """Levenberg-Marquardt from the point ``pt``, a tuple ``(z, r, J, status, message, step,
    cost, joined)`` as the engine's ``evaluate(z)`` returns it (cached and counted in ``count``).
    A generator, as ``evaluate`` is (``new = yield from evaluate(z)``: the engine's searches yield
    their points to the caller, :func:`physmodel.estimation.lsq._search`); its return value
    (``pt = yield from damped_steps(...)``) is the point it ends at.

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
        new = yield from evaluate(z_new)
        if new[6] < pt[6]:
            pt, lam = new, lam / 3.0
        else:
            lam *= 4.0
    return pt


#: The trust region is crawling when over this many of its points ...
CRAWL_POINTS = 10
#: ... its best cost fell by less than this fraction of the Gauss–Newton decrement predicted at
#: the best point it had before them (a valley where the Gauss–Newton model's curvature is far
#: below the cost's: the neglected Σ rᵢ∇²rᵢ, large along a direction the data barely determine).
CRAWL_GAIN = 0.1
#: Profile searches (each followed by a fresh trust region) per search at most.
CRAWL_SEARCHES = 8
#: Secant steps of the profile search per crawl at most.
PROFILE_STEPS = 12
#: Secant steps in a row without a lower point that end the search (an inner fit whose
#: Jacobian jumps between points — a kink of the model — moves k back and forth for nothing).
PROFILE_STALE = 3
#: Gauss–Newton points of one inner fit (the other coordinates at a fixed flat one) at most ...
INNER_POINTS = 6
#: ... ending when its decrement falls below this times s² (the trust region converges after).
INNER_DECREMENT = 1e-9


def profile_search(pt, evaluate, lo, hi, count, stopped_at_budget, moved, s2):
    """Where the trust region crawls, the cost is flat along one direction the data barely
    determine and curved across it (the Gauss–Newton model's smallest eigenvalue against the
    neglected Σ rᵢ∇²rᵢ), so every step that model proposes leaves the curved valley.  Search the
    valley as a profile instead: the coordinate k most aligned with JᵀJ's flattest eigenvector
    fixed, the others fitted by Gauss–Newton (well determined: a few points, :data:`INNER_POINTS`),
    and k moved by secant steps on the profile's derivative, which at an inner optimum is the
    gradient's k-th component (Jᵀr)_k (the envelope theorem), regula falsi (Illinois) once
    bracketed — also by a step that overshoots the minimum, where the cost rises but that
    derivative changes sign, provided the inner fit converged there or the cost rose by at most
    4 s² (else the point is on the valley's wall, its gradient the wall's, and the search ends);
    the first step ``moved`` (what the trust region moved k by while crawling) times four.  Each step starts the others where the last point's Gauss–Newton model
    puts them at the new k (along the valley).  At most :data:`PROFILE_STEPS` secant steps,
    ending when a step moves k by less than 1e-9 of its range, after :data:`PROFILE_STALE` steps
    without a point lower by more than :data:`INNER_DECREMENT`·s² (near the optimum g is
    finite-difference noise and "lower" by 1e-12 kept the search going), at a point with a status (converged, joined) or at the budget; the
    inner fits end at a decrement below :data:`INNER_DECREMENT`·s² (``s2`` the engine's s²).
    Returns the lowest point reached; the trust region resumes from it (and its tests end the
    search)."""
    n = len(pt[0])
    if n < 2:
        return pt
    A = pt[2].T @ pt[2]
    # k: the coordinate most aligned with JᵀJ's flattest direction in the engine's coordinates,
    # among those the residuals depend on (a column of zeros — a parameter without effect — has an
    # exact zero eigenvalue and would be chosen, with a zero gradient: no search).  Not on the
    # correlation matrix D^-½ A D^-½: for two strongly correlated coordinates its flattest
    # eigenvector is (1, 1)/√2 exactly, so the choice fell to the order of the parameters.
    d = np.diag(A)
    act = np.flatnonzero(d > 1e-12 * float(np.max(d))) if np.max(d) > 0 else np.zeros(0, dtype=int)
    if len(act) < 2:
        return pt
    w, V = np.linalg.eigh(A[np.ix_(act, act)])
    k = int(act[int(np.argmax(np.abs(V[:, 0])))])
    o = np.array([i for i in range(n) if i != k])
    span = hi - lo
    lo_in = lo + 1e-10 * np.maximum(1.0, np.abs(lo))
    hi_in = hi - 1e-10 * np.maximum(1.0, np.abs(hi))

    def gn_step(p, rr):
        """The Gauss–Newton step of the coordinates other than k for residuals ``rr`` with p's
        Jacobian, as (those that move, their step): a coordinate at a bound that the gradient or
        the step pushes outwards stays there (the step is solved again without it: clipped at the
        bound, it would leave the others' step aimed at a point they no longer reach and the
        inner fit gave up, the cost risen); None for a singular system."""
        J, zo = p[2], p[0][o]
        at_lo, at_hi = zo - lo[o] <= 1e-8 * span[o], hi[o] - zo <= 1e-8 * span[o]
        go = J[:, o].T @ rr
        held = (at_lo & (go > 0)) | (at_hi & (go < 0))
        while True:
            f = o[~held]
            if not len(f):
                return f, np.zeros(0)
            Jf = J[:, f]
            try:
                sf = np.linalg.solve(Jf.T @ Jf, -(Jf.T @ rr))
            except np.linalg.LinAlgError:
                return None
            out = (at_lo[~held] & (sf < 0)) | (at_hi[~held] & (sf > 0))
            if not out.any():
                return f, sf
            held[np.flatnonzero(~held)[out]] = True

    def along(p, zk):
        """p's point with k moved to zk and the others where p's Gauss–Newton model has its
        minimum at that k: from an inner optimum, along the valley's tangent (moving k alone
        leaves the valley: the cost rose a hundredfold and the inner fit took 4-5 points back)."""
        z = p[0].copy()
        st = gn_step(p, p[1] + p[2][:, k] * (zk - z[k]))
        if st is not None and len(st[0]):
            z[st[0]] = np.clip(z[st[0]] + st[1], lo_in[st[0]], hi_in[st[0]])
        z[k] = zk
        return z

    def inner(p):
        """The other coordinates fitted by Gauss–Newton steps at p's k (halved when the cost
        rises), as (point, converged): converged when the decrement fell below
        :data:`INNER_DECREMENT`·s² (or nothing is left to move)."""
        for _ in range(INNER_POINTS):
            if p[3] is not None or stopped_at_budget():
                return p, p[3] is not None
            st = gn_step(p, p[1])
            if st is None:
                return p, False
            if not len(st[0]):
                return p, True
            f, sf = st
            if -0.5 * float((p[2][:, f].T @ p[1]) @ sf) < INNER_DECREMENT * s2:
                return p, True
            for _ in range(2):
                z = p[0].copy()
                z[f] = np.clip(z[f] + sf, lo_in[f], hi_in[f])
                if stopped_at_budget():
                    return p, False
                count[0] += 1
                new = evaluate(z)
                if new[6] < p[6] or new[3] is not None:
                    p = new
                    break
                sf = 0.5 * sf
            else:
                return p, False
        return p, False

    def grad_k(p):
        return float(p[2][:, k] @ p[1])

    cur, _ = inner(pt)
    best = cur if cur[6] < pt[6] else pt
    if cur[3] is not None:
        return cur
    g = grad_k(cur)
    step = 4.0 * moved[k] if moved[k] * -g > 0 else -np.sign(g) * 1e-3 * (hi[k] - lo[k])
    below = above = None             # (z_k, g) with g < 0 and with g > 0: the bracket
    last = 0                         # the end the previous point replaced (-1 below, +1 above)
    stale = 0                        # secant steps since the lowest point last moved
    for _ in range(PROFILE_STEPS):
        if g == 0 or stopped_at_budget() or stale >= PROFILE_STALE:
            break
        side = -1 if g < 0 else 1
        if side < 0:
            below = (cur[0][k], g)
        else:
            above = (cur[0][k], g)
        if below is not None and above is not None:
            if side == last:         # the same end replaced twice: halve the other's g (Illinois),
                if side < 0:         # else regula falsi creeps up to the minimum from one side
                    above = (above[0], 0.5 * above[1])
                else:
                    below = (below[0], 0.5 * below[1])
            zk = below[0] - below[1] * (above[0] - below[0]) / (above[1] - below[1])
        else:
            zk = cur[0][k] + step
        last = side
        zk = float(np.clip(zk, lo_in[k], hi_in[k]))
        if abs(zk - cur[0][k]) <= 1e-9 * (hi[k] - lo[k]):
            break
        count[0] += 1
        new, converged = inner(evaluate(along(cur, zk)))
        if new[3] is not None:
            return new if new[6] < best[6] else best
        g_new = grad_k(new)
        if not np.isfinite(g_new):
            break
        # a point whose inner fit did not get back into the valley (its cost far above the last)
        # is no profile point: its g is the steep wall's, not the profile's derivative
        if not converged and new[6] > cur[6] + 4.0 * s2:
            break
        if not new[6] < cur[6] and (below is None or above is None) and not g_new * g < 0:
            break                        # the profile does not fall that way: leave it to the trust region
        if below is None or above is None:      # secant on g, at most four times further
            dz = new[0][k] - cur[0][k]
            slope = (g_new - g) / dz if dz != 0 else 0.0
            step = -g_new / slope if slope > 0 else 4.0 * dz
            step = float(np.clip(step, -4.0 * abs(dz), 4.0 * abs(dz)))
        cur, g = new, g_new
        stale += 1
        if cur[6] < best[6] - INNER_DECREMENT * s2:
            best, stale = cur, 0
        elif cur[6] < best[6]:
            best = cur
    return best


#: ... and that decrement is above this times s² (the point ≥ 0.014 standard errors from the
#: optimum by the Gauss–Newton model: closer, the trust region's path left is short).
CRAWL_DECREMENT = 1e-4


def crawling(best: list, decrement, s2: float) -> bool:
    """Whether the trust region crawls: ``best`` the lowest point reached after each of its
    points (engine tuples, cost at index 6), ``decrement(pt)`` a point's Gauss–Newton decrement,
    ``s2`` the engine's s²."""
    if len(best) <= CRAWL_POINTS:
        return False
    old, now = best[-CRAWL_POINTS - 1], best[-1]
    dec = decrement(old)
    return dec > CRAWL_DECREMENT * s2 and old[6] - now[6] < CRAWL_GAIN * dec
