"""Null statistics of the discrepancy workflow: each candidate's residual signature at the fitted
baseline (tangent, or secant where the tangent vanishes), which parameters only act once the others
are on, the constrained likelihood ratio of the linearised Gaussian null, and its look-elsewhere
scan over parameters that are not identified under the null (Davies 1987)."""

from __future__ import annotations

import math
from dataclasses import replace
from itertools import combinations

import numpy as np

from .diagnosis import CONFUSABLE_COSINE, MIN_SIGNATURE_LR
from .residuals import standardised_residuals
from .signatures import effect_signature, orth, project_out, separation_hint, with_noise, z_jacobian

#: A candidate parameter whose tangent signature at off is below this fraction of its secant to the
#: typical size (the first-order term carries < 10 % of the change, e.g. a resonance
#: 1/(1 + 2ζτs + τ²s²) in τ) is described by the secant instead (fixed a priori, not tuned).
SECANT_RATIO = 0.1


def signature_stage(pm, v0: dict, free0, cand, cpars: dict, r0, data, s_ln, s_ph):
    """Signatures of every candidate at the fitted baseline ``v0`` (columns d r/d δ, the baseline
    Jacobian projected out), which are one-sided, skipped (no signature on these data), described by
    the secant, *degenerate* (parameters with no first-order signature at off, scanned by
    :func:`scan_lr`), and the pairs whose signatures are confusable (canonical correlation
    ≥ ``CONFUSABLE_COSINE``) with what separates them.

    Returns ``(J0, Q0, sigs, sided, skipped, first_order, raw_sigs, degenerate, confusable, separation)``."""
    J0 = z_jacobian(pm, v0, free0, r0, data, s_ln, s_ph)
    Q0 = orth(J0)
    sigs, sided, skipped, first_order, raw_sigs, degenerate = {}, {}, {}, {}, {}, {}
    for c in cand:
        S, one = effect_signature(pm, v0, c, r0, data, s_ln, s_ph, cpars[c])
        reach = np.array([max(abs(p.upper - p.off), abs(p.lower - p.off)) / abs(p.typical - p.off) for p in cpars[c]])
        Ssec, _ = effect_signature(pm, v0, c, r0, data, s_ln, s_ph, cpars[c], h=1.0)    # secant to the typical size
        sec = np.linalg.norm(S, axis=0) < SECANT_RATIO * np.linalg.norm(Ssec, axis=0)
        if len(cpars[c]) > 1 and np.all(np.isfinite(S)):
            dead = _needs_others(pm, v0, c, cpars[c], np.where(sec[None, :], Ssec, S), r0, data, s_ln, s_ph,
                                 SECANT_RATIO)
            if (dead | sec).any():
                degenerate[c] = dead | sec
        elif sec.any():
            degenerate[c] = sec
        if np.all(np.isfinite(S)) and np.all(np.isfinite(Ssec)) and sec.any():
            S = np.where(sec[None, :], Ssec, S)
            first_order[c] = ("no first-order signature at off in " + ", ".join(
                p.name for p, x in zip(cpars[c], sec) if x) + " (secant to the typical size there; refitted)")
        Sp = project_out(Q0, S)
        max_lr = float(np.sum((np.linalg.norm(Sp, axis=0) * reach) ** 2))
        if not np.all(np.isfinite(S)) or np.sum((np.linalg.norm(S, axis=0) * reach) ** 2) < MIN_SIGNATURE_LR:
            skipped[c] = "no signature on these data (cannot change the cost by the noise level)"
            continue
        sigs[c], sided[c], raw_sigs[c] = Sp, one, S
        if max_lr < MIN_SIGNATURE_LR and c not in first_order:
            first_order[c] = "confounded with the free parameters to first order (refitted; only nonlinear terms can show it)"
    confusable = []
    bases = {c: orth(S) for c, S in sigs.items() if c not in first_order or first_order[c].startswith("no first")}
    for a, b in combinations(bases, 2):
        if bases[a].shape[1] == 0 or bases[b].shape[1] == 0:
            continue
        cos = float(np.linalg.svd(bases[a].T @ bases[b], compute_uv=False).max())
        if cos >= CONFUSABLE_COSINE:
            confusable.append((a, b, min(cos, 1.0)))
    separation = {f"{a}~{b}": separation_hint(a, b, raw_sigs, data) for a, b, _ in confusable}
    return J0, Q0, sigs, sided, skipped, first_order, raw_sigs, degenerate, confusable, separation


def constrained_lr(S, one_sided, E):
    """Max over δ (one-sided components ≥ 0) of 2δᵀSᵀe − δᵀSᵀSδ for every column e of E.

    Exact for ≤ 3 parameters by enumerating active sets (concave quadratic)."""
    return _constrained_lr_gram(S.T @ S, S.T @ E, one_sided)


def _constrained_lr_gram(G, B, one_sided):
    """:func:`constrained_lr` from the Gram matrix ``G`` = SᵀS (..., k, k) and ``B`` = SᵀE (..., k, n),
    batched over any leading axes (a zero column is a parameter left out); returns (..., n)."""
    k = G.shape[-1]
    best = np.zeros(B.shape[:-2] + B.shape[-1:])
    for m in range(1, k + 1):
        for sub in combinations(range(k), m):
            if m == 1:
                # one parameter: pinv of a 1 × 1 Gram is 1/g (0 for a left-out zero column) and the
                # product and the sum over its one row are single multiplications: the same numbers
                # as the general branch, without its batched SVD, matmul and reduction
                j = sub[0]
                g = G[..., j:j + 1, j]                          # (..., 1)
                with np.errstate(divide="ignore"):
                    ginv = np.where(g == 0.0, 0.0, 1.0 / np.where(g == 0.0, 1.0, g))
                b1 = B[..., j, :]                               # (..., n)
                d1 = ginv * b1
                lr = b1 * d1
                ok = lr > best
                if one_sided[j]:
                    ok &= d1 >= 0
            else:
                idx = np.array(sub)
                whole = m == k                      # every parameter: G and B as they are (no copy)
                Ginv = np.linalg.pinv(G if whole else G[..., idx[:, None], idx[None, :]])
                b = B if whole else B[..., idx, :]  # (..., m, n)
                d = Ginv @ b
                # Σ_j b_j d_j over the m rows: what np.sum(b * d, axis=-2) adds, in its order
                # (the first row, then each next one added), without the (..., m, n) product
                lr = b[..., 0, :] * d[..., 0, :]
                for j in range(1, m):
                    lr += b[..., j, :] * d[..., j, :]
                ok = lr > best
                for j, c in enumerate(sub):
                    if one_sided[c]:
                        ok &= d[..., j, :] >= 0
            np.copyto(best, lr, where=ok)
    return best


#: Largest number of grid points of :func:`scan_lr` per candidate (a few model evaluations each).
SCAN_POINTS = 256


def _scan_axis(p, n: int) -> np.ndarray:
    """Values of one parameter for the look-elsewhere scan: geometric steps away from an off value at
    a bound (10⁻³ … 1 of the span, where small values give small, differently shaped effects, e.g. a
    time constant), else the range (geometric when it spans a decade or more of positive values)."""
    if p.off in (p.lower, p.upper):
        other = p.upper if p.off == p.lower else p.lower
        return p.off + (other - p.off) * np.logspace(-3.0, 0.0, n)
    if p.lower > 0 and p.upper / p.lower >= 10.0:
        return np.geomspace(p.lower, p.upper, n)
    return np.linspace(p.lower, p.upper, n)


def scan_lr(predict_many, values: dict, effect: str, params, degenerate, r0, data, s_ln, s_ph, Q0, E,
             h: float = 1e-3, max_points: int = SCAN_POINTS, is_off=None) -> np.ndarray:
    """Linearised null LR of a candidate whose parameters include *degenerate* ones (no first-order
    signature at off: a shape that only exists once the effect is on, e.g. the frequency and damping
    of a resonance, the viscosity of a fluid load), with the look-elsewhere effect over them.

    Davies (1987, Biometrika 74:33): when a parameter is not identified under the null, the LR is
    the supremum over it of the LR with it fixed.  The degenerate parameters run over a grid
    (:func:`_scan_axis`, at most ``max_points`` points); at each point the other parameters enter by
    their tangent signatures at off (one-sided where off is a bound), plus the secant from the
    baseline to that point when it moves the prediction by itself (a one-sided ray: for a resonance
    whose time constant and damping are both degenerate, the sizes between grid points are covered
    by the ray, a slight over-cover, i.e. conservative).  Columns are projected off the baseline
    Jacobian (``Q0``); returns the max over the grid of the constrained LR for every column of ``E``
    (the null draws, already projected).  ``is_off(effect values)`` (the effect's
    :meth:`~physmodel.effects.base.Effect.is_off`): grid points where the effect is off (its
    amplitudes off) predict the baseline itself, so their residuals are ``r0``, not evaluated again."""
    from itertools import product

    deg = [i for i, x in enumerate(degenerate) if x]
    amp = [i for i in range(len(params)) if i not in deg]
    n_per = max(4, int(math.floor(max_points ** (1.0 / len(deg)) + 1e-9)))
    grid = list(product(*[_scan_axis(params[i], n_per) for i in deg]))
    pts = []
    for g in grid:
        v = dict(values)
        for j, i in enumerate(deg):
            v[f"{effect}.{params[i].name}"] = float(g[j])
        for i in amp:
            v[f"{effect}.{params[i].name}"] = params[i].off
        pts.append(v)
        for i in amp:
            w = dict(v)
            w[f"{effect}.{params[i].name}"] = params[i].off + h * (params[i].typical - params[i].off)
            pts.append(w)
    # a point where the effect is off (amplitudes off at a grid point of its shape) predicts the
    # baseline itself: its residuals are r0, not evaluated again
    on = np.array([is_off is None or not is_off({p.name: v[f"{effect}.{p.name}"] for p in params}) for v in pts])
    R = np.repeat(r0[None, :], len(pts), axis=0)                           # (points, 2N)
    if on.any():
        R[on] = standardised_residuals(predict_many([v for v, x in zip(pts, on) if x]), data, s_ln, s_ph)
    stride = 1 + len(amp)
    base = R[0::stride]                                                    # each grid point, amplitudes off
    tang = [(R[1 + j::stride] - base) / h for j in range(len(amp))]       # (G, 2N) each
    ray = base - r0[None, :]
    scale = np.sqrt(np.mean(r0 * r0)) + 1.0
    use_ray = np.linalg.norm(ray, axis=1) > 1e-6 * scale * math.sqrt(r0.size)
    cols = np.stack(tang + [ray], axis=1)                                  # (G, k + 1, 2N)
    cols = cols - (cols @ Q0) @ Q0.T if Q0.shape[1] else cols
    one = [params[i].off in (params[i].lower, params[i].upper) for i in amp] + [True]
    cols[~use_ray, len(amp)] = 0.0                                         # no ray where the point alone is off
    cols[~np.all(np.isfinite(cols), axis=(1, 2))] = 0.0                    # a grid point the model cannot evaluate
    B = (cols.reshape(-1, cols.shape[2]) @ E).reshape(cols.shape[0], cols.shape[1], -1)   # (G, k + 1, draws), BLAS
    return _constrained_lr_gram(cols @ cols.transpose(0, 2, 1), B, one).max(axis=0)


def _needs_others(predict_many, values: dict, effect: str, params, S, r0, data, s_ln, s_ph, ratio: float,
                  h: float = 1e-3) -> np.ndarray:
    """Which parameters act only once the effect's other parameters are on (a shape parameter: the
    damping of a resonance, the viscosity of a fluid load, the share of a second mode): their tangent
    at off (``S``, others off) is below ``ratio`` of their tangent with the others at their typical
    sizes."""
    pts = []
    for i, p in enumerate(params):
        v = dict(values)
        for j, q in enumerate(params):
            v[f"{effect}.{q.name}"] = q.typical if j != i else q.off
        w = dict(v)
        w[f"{effect}.{p.name}"] = p.off + h * (p.typical - p.off)
        pts += [v, w]
    R = standardised_residuals(predict_many(pts), data, s_ln, s_ph)
    T = (R[1::2] - R[0::2]) / h                                            # (k, 2N)
    with np.errstate(invalid="ignore"):
        return np.linalg.norm(S, axis=0) < ratio * np.linalg.norm(T, axis=1)


def bootstrap_ratio(E, lin_max, G0, data, s_ln, s_ph, n_refits: int, fit_null, refit_max):
    """Nonlinearity correction of the linearised threshold: on the first ``n_refits`` null draws
    (columns of ``E``, applied to the baseline prediction ``G0``), ``fit_null(sim)`` refits the
    baseline and ``refit_max(sim, baseline_fit)`` returns the largest full-refit LR over the
    candidates; the ratio of their sum to the linearised one (``lin_max``), clipped to [1, 3].
    Returns ``(ratio, full_max, lin_used)``."""
    full_max, lin_used = [], []
    for b in range(n_refits):
        sim = replace(data, response=with_noise(G0, E[:, b], s_ln, s_ph),     # keeps a stacked sweep's type
                      magnitude_std_db=np.asarray(s_ln) * 20 / math.log(10), phase_std_deg=np.degrees(s_ph))
        full_max.append(float(refit_max(sim, fit_null(sim))))
        lin_used.append(float(lin_max[b]))
    ratio = 1.0
    if full_max and sum(lin_used) > 0:
        ratio = float(np.clip(sum(full_max) / sum(lin_used), 1.0, 3.0))
    return ratio, full_max, lin_used


#: The fewest null draws beyond a quantile the diagnosis thresholds at before its result says the
#: quantile is thin (:func:`draws_beyond`: the draws actually beyond ``np.quantile``'s linear
#: interpolation, not the expected n·p).  The tail probability beyond the empirical (1 − p) quantile
#: of n draws (the test's realised level) is Beta-distributed (order statistics of uniforms), with
#: relative standard deviation ≈ sqrt((1 − p)/(n·p)) ≈ 1/sqrt(n_tail), n_tail ≈ n·p: at 10 draws ≈ 32 %,
#: so a nominal 0.5 % test realises about 0.34-0.66 % (± 1 SD); with 1-2 draws (200 draws at α_gap/2 =
#: 0.005) it is uncertain by 70-100 %, a level not known within a factor of two.  10 is also the tail
#: the former floor of 200 draws gave the α = 0.05 quantile it was written for (200 × 0.05), now
#: asked of every quantile used: the LR test's at α − α_gap, the gap test's at α_gap/K per quantity
#: (Bonferroni, :mod:`~physmodel.estimation.gap`) and the pooled one at α_gap.
MIN_TAIL_DRAWS = 10


def draws_beyond(null_draws: int, p: float) -> int:
    """How many of ``null_draws`` (distinct) draws lie above their ``np.quantile`` at ``1 − p`` (linear
    interpolation, numpy's default, as every threshold of the diagnosis uses): the quantile sits at
    sorted position (n − 1)(1 − p), so the draws beyond it are ceil((n − 1)·p) — e.g. 10 of 950 at
    p = 0.01, where n·p says 9.5.  Rounded to 9 digits first, so an integer (n − 1)·p is not pushed
    up by floating point."""
    return math.ceil(round((null_draws - 1) * p, 9))


def null_tails(null_draws: int, alpha: float, alpha_gap: float, K: int) -> dict:
    """``{quantile: {"tail_probability": p, "draws": draws beyond it}}`` (:func:`draws_beyond`) for
    every quantile of the null draws a diagnosis with ``K`` quantities thresholds at (the LR test at
    α − α_gap; the gap test at α_gap for one quantity, else at α_gap/K per quantity and α_gap pooled)."""
    tails = {"LR threshold": alpha - alpha_gap}
    if K == 1:
        tails["gap threshold"] = alpha_gap
    else:
        tails["per-quantity gap threshold"] = alpha_gap / K
        tails["pooled gap threshold"] = alpha_gap
    return {k: {"tail_probability": p, "draws": draws_beyond(null_draws, p)} for k, p in tails.items()}


def draws_for_tail(p: float, tail: int = MIN_TAIL_DRAWS) -> int:
    """The fewest null draws that put ``tail`` draws beyond the (1 − p) quantile (:func:`draws_beyond`)."""
    n = math.floor((tail - 1) / p) + 2                  # (n − 1)·p > tail − 1, then exact on the integers
    while draws_beyond(n - 1, p) >= tail:
        n -= 1
    while draws_beyond(n, p) < tail:
        n += 1
    return n


def thin_tail_note(tails: dict, null_draws: int) -> str:
    """A sentence for the diagnosis's message when any quantile of ``tails`` (:func:`null_tails`)
    has fewer than :data:`MIN_TAIL_DRAWS` draws beyond it, else ``""``."""
    thin = {k: t for k, t in tails.items() if t["draws"] < MIN_TAIL_DRAWS}
    if not thin:
        return ""
    need = draws_for_tail(min(t["tail_probability"] for t in tails.values()))
    which = ", ".join(f"{t['draws']} beyond the {k} (its {1 - t['tail_probability']:.4g} quantile)"
                      for k, t in thin.items())
    return (f" Thin null tail: of the {null_draws} null draws, {which} — fewer than {MIN_TAIL_DRAWS}, so the "
            f"actual level of each test named is uncertain by more than 1/sqrt({MIN_TAIL_DRAWS}) ≈ "
            f"{100 / math.sqrt(MIN_TAIL_DRAWS):.0f} % (relative, ≈ 1/sqrt(draws beyond)); null_draws ≥ {need} puts "
            f"{MIN_TAIL_DRAWS} beyond every quantile.")
