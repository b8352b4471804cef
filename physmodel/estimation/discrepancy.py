"""The discrepancy workflow: locate a misfit, name the missing effect, add it, show the gap shrink.

:func:`diagnose` (discrepancy.md) takes frequency-response data, a base parameter set and the
user's free parameters, and:

1. calibrates the baseline model (:func:`physmodel.estimation.calibration.fit_parameters`, the project's one
   calibration engine) and tabulates where the standardised residuals exceed their band
   (frequency band × temperature × magnitude/phase, and the trend with temperature);
2. refits the full model with each candidate effect of :data:`physmodel.effects.LIBRARY` switched
   on (nested, full nonlinear refits) and scores it by the likelihood-ratio statistic
   LR = 2 (cost_baseline − cost_candidate), with AIC/BIC alongside;
3. sets the acceptance threshold by Monte Carlo under the null (no effect), so that the
   *family-wise* false-positive rate of "max over candidates of LR" is α:

   * a linearised Gaussian null at the fitted baseline: standardised noise e ~ N(0, I) with the
     baseline Jacobian projected out, and for each candidate the exact constrained LR of the
     linearised problem (parameters whose "off" value is a bound enter one-sided, which gives the
     χ̄² mixture), ``null_draws`` draws (default 4000, milliseconds);
   * a parametric bootstrap with full nonlinear refits (simulate from the fitted baseline with the
     data's noise, refit baseline and every candidate) on the first ``null_refits`` of the same
     noise draws (default 4): the ratio Σ LR_full / Σ LR_lin over these draws (clipped to
     [1, 3]) scales the linearised threshold, correcting it for nonlinearity at the cost of a
     few refits;

4. reports as *confusable* the candidate pairs whose signatures (Jacobian columns with the
   baseline Jacobian projected out) have a largest canonical correlation ≥ :data:`CONFUSABLE_COSINE`;
5. decides: ``none`` (no significant LR and no significant gap), ``named`` (one significant
   candidate that closes the gap, or a greedy second effect when the first leaves a significant
   gap), ``ambiguous`` (several significant candidates that close the gap and whose AIC differ by
   less than :data:`AMBIGUITY_AIC`), ``unexplained`` (a significant gap that no candidate, or
   pair, closes).  The gap test compares 2·cost with the (1 − α/5) quantile of its null
   distribution from the same Monte Carlo (stricter than α: a false "unexplained" costs a name).

Residuals are those of :func:`physmodel.estimation.calibration.residuals`: ln-magnitude/σ_ln and wrapped
phase/σ_φ per line.  Data without per-line standard deviations use the calibration module's
fallback (1 % per line); the report says so, and absolute gap tests are then relative to that.
"""
from __future__ import annotations

import math
import time
from itertools import combinations
from typing import Callable, Mapping, Sequence

import numpy as np

from ..data.sweep import FrequencySweep
from ..effects import DEFAULT_QUANTITY, LIBRARY, EffectModel, candidates_for, get_effect, normalize_effects
from ..errors import IPMCError, ParameterError
from ..params import IPMCParameters
from ..parameter_paths import base_value
from .calibration import default_free_parameter
from .lsq import fit_parameters
from .records import CalibrationResult, FreeParameter
from .residuals import noise_std, standardised_residuals

from .diagnosis import (AMBIGUITY_AIC, CONFUSABLE_COSINE, GAP_ALPHA_DIVISOR, MIN_SIGNATURE_LR, VERDICTS,
                        CandidateResult, Diagnosis, _named_msg, _worst_cells, gap_shrink)
from .signatures import (_constrained_lr, _gap, _localise, _orth, _project_out, _separation, _signature,
                         _z_jacobian)


def _free_list(base: IPMCParameters, free, effects: dict) -> list:
    out = []
    for item in free:
        if isinstance(item, FreeParameter):
            fp = item
        elif isinstance(item, str):
            if "." in item and not item.startswith("laws."):
                e, p = item.split(".", 1)
                if e not in effects:
                    raise ParameterError(f"free parameter {item!r} belongs to effect {e!r}, which is not among "
                                         f"the baseline effects {sorted(effects)}")
                par = get_effect(e).parameter(p)
                fp = FreeParameter(item, par.lower, par.upper, "linear", effects[e][p])
            else:
                fp = default_free_parameter(base, item)
        else:
            raise ParameterError(f"free parameters must be names or FreeParameter, got {item!r}")
        if fp.initial is None:
            if "." in fp.name and not fp.name.startswith("laws."):
                e, p = fp.name.split(".", 1)
                v = effects[e][p]
            else:
                v = base_value(base, fp.name)
            fp = fp.with_initial(min(max(v, fp.lower), fp.upper))
        out.append(fp)
    return out


def _effect_free(effect: str, start: Mapping[str, float] | None = None) -> list:
    e = LIBRARY[effect]
    out = []
    for p in e.parameters:
        v = p.off if start is None else float(np.clip(start[p.name], p.lower, p.upper))
        out.append(FreeParameter(f"{effect}.{p.name}", p.lower, p.upper, "linear", v))
    return out


def _simulated(G, e, s_ln, s_ph):
    N = G.size
    return G * np.exp(e[:N] * s_ln + 1j * e[N:] * s_ph)


# =============================================================================== main entry
def diagnose(data: FrequencySweep, base: IPMCParameters, *, kind: str = "actuator", quantity: str | None = None,
             free: Sequence[str | FreeParameter] = ("alpha0",),
             baseline_effects: Mapping[str, Mapping[str, float]] | Sequence[str] = (),
             candidates: Sequence[str] | None = None, alpha: float = 0.05, null_draws: int = 4000,
             null_refits: int = 4, seed: int = 0, kernel: str = "boundary_charge", max_nfev: int = 200,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """Diagnose the discrepancy between ``data`` and the ``base`` model (see module docstring).

    ``free``: the user's calibration parameters (names with default bounds, ``"effect.param"`` of a
    baseline effect, or :class:`FreeParameter`).  ``baseline_effects``: effects already in the model
    (``{name: {param: value}}``; a bare name means all its parameters free from their off value).
    ``candidates``: library names to test (default: all that apply to ``kind``/``quantity`` and are
    not in the baseline).  ``alpha``: family-wise false-positive rate.  ``null_draws``: linearised
    null Monte Carlo draws; ``null_refits``: full nonlinear bootstrap refits (see module doc).
    ``progress(message)`` is called after each stage.
    """
    t0 = time.perf_counter()
    if not isinstance(data, FrequencySweep):
        raise IPMCError(f"data must be a FrequencySweep, got {type(data).__name__}")
    if not isinstance(base, IPMCParameters):
        raise ParameterError(f"base must be IPMCParameters, got {type(base).__name__}")
    if not (0 < alpha < 0.5):
        raise IPMCError(f"alpha={alpha!r} must lie in (0, 0.5)")
    if int(null_draws) < 200:
        raise IPMCError(f"null_draws={null_draws!r} is too small for a {1 - alpha:g} quantile; use >= 200")
    if int(null_refits) < 0:
        raise IPMCError(f"null_refits={null_refits!r} must be >= 0")
    q = quantity or DEFAULT_QUANTITY.get(kind, "")
    say = progress or (lambda msg: None)
    if isinstance(baseline_effects, Mapping):
        beff = normalize_effects(baseline_effects)
        extra_free = []
    else:
        beff = normalize_effects({n: {} for n in baseline_effects})
        extra_free = [f"{n}.{p.name}" for n in beff for p in get_effect(n).parameters]
    model0 = EffectModel(base, kind, beff, kernel=kernel)
    predict = model0.predictor(data, q)
    pm = predict.many
    free0 = _free_list(base, list(free) + [f for f in extra_free if f not in free], beff)
    names0 = [fp.name for fp in free0]
    s_ln, s_ph, estimated = noise_std(data)
    N = data.frequency_hz.size
    n_temps = data.temperatures().size

    # ---- 1. baseline
    res0 = fit_parameters(data, None, free0, predict_many=pm, max_nfev=max_nfev, identify=True,
                          hold_undetermined=False, seed=seed)
    v0 = dict(res0.values)
    G0 = pm([v0])[0]
    r0 = standardised_residuals(G0, data, s_ln, s_ph)
    say(f"baseline fitted: cost {res0.cost:.4g} (expected {res0.expected_cost:.4g})")

    # ---- 2. signatures, confusability
    cand = list(candidates) if candidates is not None else [
        c for c in candidates_for(kind, q, n_temps) if c not in beff]
    for c in cand:
        if c not in LIBRARY:
            raise ParameterError(f"unknown candidate effect {c!r}; expected library names {sorted(LIBRARY)}")
        if not LIBRARY[c].applies_to(kind, q):
            raise ParameterError(f"candidate {c!r} does not apply to {kind} quantity {q}")
    J0 = _z_jacobian(pm, v0, free0, r0, data, s_ln, s_ph)
    Q0 = _orth(J0)
    sigs, sided, skipped, first_order, raw_sigs = {}, {}, {}, {}, {}
    for c in cand:
        S, one = _signature(pm, v0, c, r0, data, s_ln, s_ph)
        Sp = _project_out(Q0, S)
        e = LIBRARY[c]
        reach = np.array([max(abs(p.upper - p.off), abs(p.lower - p.off)) / abs(p.typical - p.off) for p in e.parameters])
        max_lr = float(np.sum((np.linalg.norm(Sp, axis=0) * reach) ** 2))
        if not np.all(np.isfinite(S)) or np.sum((np.linalg.norm(S, axis=0) * reach) ** 2) < MIN_SIGNATURE_LR:
            skipped[c] = "no signature on these data (cannot change the cost by the noise level)"
            continue
        sigs[c], sided[c], raw_sigs[c] = Sp, one, S
        if max_lr < MIN_SIGNATURE_LR:
            first_order[c] = "confounded with the free parameters to first order (refitted; only nonlinear terms can show it)"
    confusable = []
    orth = {c: _orth(S) for c, S in sigs.items() if c not in first_order}
    for a, b in combinations(orth, 2):
        if orth[a].shape[1] == 0 or orth[b].shape[1] == 0:
            continue
        cos = float(np.linalg.svd(orth[a].T @ orth[b], compute_uv=False).max())
        if cos >= CONFUSABLE_COSINE:
            confusable.append((a, b, min(cos, 1.0)))
    separation = {f"{a}~{b}": _separation(a, b, raw_sigs, data) for a, b, _ in confusable}
    conf_set = {frozenset((a, b)) for a, b, _ in confusable}

    # ---- 3. linearised null Monte Carlo
    rng = np.random.default_rng(seed + 7919)
    E = rng.standard_normal((2 * N, int(null_draws)))
    Ep = _project_out(Q0, E)
    lin = {c: _constrained_lr(S, sided[c], Ep) for c, S in sigs.items()}
    lin_max = np.max(np.vstack(list(lin.values())), axis=0) if lin else np.zeros(E.shape[1])
    cost2_null = np.sum(Ep * Ep, axis=0)
    T_lin = float(np.quantile(lin_max, 1 - alpha))
    alpha_gap = alpha / GAP_ALPHA_DIVISOR
    gap_thr0 = float(np.quantile(cost2_null, 1 - alpha_gap))
    say(f"linearised null: LR threshold {T_lin:.3g} from {E.shape[1]} draws")

    # ---- 4. candidate refits
    def refit(effects_on: Sequence[str], start_vals: dict, eff_starts: list[dict | None]):
        best = None
        for starts in eff_starts:
            fr = [fp.with_initial(min(max(start_vals[fp.name], fp.lower), fp.upper)) for fp in free0]
            for c in effects_on:
                st = None if starts is None else starts.get(c)
                if st is None and any(k.startswith(c + ".") for k in start_vals):
                    st = {k.split(".", 1)[1]: v for k, v in start_vals.items() if k.startswith(c + ".")}
                fr += _effect_free(c, st)
            res = fit_parameters(data, None, fr, predict_many=pm, max_nfev=max_nfev, identify=True,
                                 hold_undetermined=False, seed=seed)
            if best is None or res.cost < best.cost:
                best = res
        return best

    def lin_start(c, r_now, Qb):
        """Linearised estimate of the effect's values from the current residual."""
        S = _project_out(Qb, sigs[c])
        d, *_ = np.linalg.lstsq(S, -r_now, rcond=None)
        e = LIBRARY[c]
        return {p.name: p.off + d[j] * (p.typical - p.off) for j, p in enumerate(e.parameters)}

    cres: dict[str, CandidateResult] = {}
    fits: dict[str, CalibrationResult] = {}
    k0 = len(free0)
    n_res = 2 * N
    for c in sigs:
        res = refit([c], v0, [None, {c: lin_start(c, r0, Q0)}, {c: LIBRARY[c].typical}])
        fits[c] = res
        k = len(LIBRARY[c].parameters)
        lr = max(0.0, 2 * (res0.cost - res.cost))
        ev = {p.name: res.values[f"{c}.{p.name}"] for p in LIBRARY[c].parameters}
        cres[c] = CandidateResult(
            c, ev, {p: res.ci_lower[f"{c}.{p}"] for p in ev}, {p: res.ci_upper[f"{c}.{p}"] for p in ev},
            res.cost, lr, 2 * res.cost + 2 * (k0 + k), 2 * res.cost + (k0 + k) * math.log(n_res), k,
            False, False, res.converged, float(np.linalg.norm(sigs[c])),
            float(_constrained_lr(sigs[c], sided[c], -_project_out(Q0, r0[:, None]))[0]), first_order.get(c, ""))
    say(f"{len(cres)} candidates refitted")

    # ---- 5. bootstrap refits under the null (nonlinearity correction of the threshold)
    full_max, lin_used = [], []
    for b in range(int(null_refits)):
        e = E[:, b]
        sim = FrequencySweep(data.temperature_c, data.frequency_hz, _simulated(G0, e, s_ln, s_ph),
                             data.magnitude_std_db, data.phase_std_deg, data.input_name, data.input_unit,
                             data.output_name, data.output_unit)
        fr0 = [fp.with_initial(min(max(v0[fp.name], fp.lower), fp.upper)) for fp in free0]
        rb = fit_parameters(sim, None, fr0, predict_many=pm, max_nfev=max_nfev, identify=False)
        m = 0.0
        for c in sigs:
            fr = [fp.with_initial(min(max(rb.values[fp.name], fp.lower), fp.upper)) for fp in free0] + _effect_free(c)
            rc = fit_parameters(sim, None, fr, predict_many=pm, max_nfev=max_nfev, identify=False)
            m = max(m, 2 * (rb.cost - rc.cost))
        full_max.append(m)
        lin_used.append(float(lin_max[b]))
    ratio = 1.0
    if full_max and sum(lin_used) > 0:
        ratio = float(np.clip(sum(full_max) / sum(lin_used), 1.0, 3.0))
    T = T_lin * ratio
    say(f"null threshold {T:.3g} (linearised {T_lin:.3g} × nonlinearity ratio {ratio:.3g})")

    # ---- 6. verdict
    def gap_thr(effs: Sequence[str]) -> float:
        if not effs:
            return gap_thr0
        S = np.hstack([sigs[c] for c in effs])
        Qs = _orth(S)
        after = cost2_null - np.sum((Qs.T @ Ep) ** 2, axis=0)
        return float(np.quantile(after, 1 - alpha_gap))

    for c, cr in cres.items():
        cr.significant = cr.lr > T
        cr.closes_gap = 2 * cr.cost <= gap_thr([c])
    gap0_sig = 2 * res0.cost > gap_thr0
    sig = sorted((c for c in cres if cres[c].significant), key=lambda c: -cres[c].lr)
    final_effects: list[str] = []
    final_fit: CalibrationResult | None = None
    where = _worst_cells(_localise(data, r0, alpha))
    if not sig:
        if gap0_sig:
            verdict = "unexplained"
            message = (f"The baseline leaves a significant gap (2·cost {2 * res0.cost:.4g} > {gap_thr0:.4g}) "
                       f"that no library candidate reduces significantly; the gap remains in {where}.")
        else:
            verdict = "none"
            message = (f"No significant discrepancy: best candidate LR "
                       f"{max([c.lr for c in cres.values()], default=0.0):.3g} ≤ threshold {T:.3g}, and the "
                       f"baseline cost {res0.cost:.4g} is within its null band.")
    else:
        best = sig[0]
        closers = [c for c in sig if cres[c].closes_gap]
        if closers:
            top = min(closers, key=lambda c: cres[c].aic)
            amb = [c for c in closers if cres[c].aic - cres[top].aic < AMBIGUITY_AIC]
            final_effects, final_fit = [top], fits[top]
            if len(amb) > 1:
                verdict = "ambiguous"
                pairs = [f"{a}~{b}" + ("" if frozenset((a, b)) in conf_set else " (not declared confusable)")
                         for a, b in combinations(amb, 2)]
                message = (f"Ambiguous between {', '.join(amb)} (AIC within {AMBIGUITY_AIC:g}; {'; '.join(pairs)}). "
                           "Separate them with a wider band, more temperatures, or magnitude vs phase.")
                final_effects = amb[:1]
            else:
                verdict = "named"
                message = _named_msg(top, cres[top])
        else:
            # greedy second effect on top of the best
            r1 = standardised_residuals(pm([fits[best].values])[0], data, s_ln, s_ph)
            Q1 = _orth(np.hstack([J0, sigs[best]]))
            best2 = None
            for c2 in sigs:
                if c2 == best:
                    continue
                res2 = refit([best, c2], fits[best].values,
                             [None, {c2: lin_start(c2, r1, Q1)}, {c2: LIBRARY[c2].typical}])
                lr2 = max(0.0, 2 * (fits[best].cost - res2.cost))
                if lr2 > T and (best2 is None or res2.cost < best2[1].cost):
                    best2 = (c2, res2, lr2)
            if best2 is not None and 2 * best2[1].cost <= gap_thr([best, best2[0]]):
                verdict = "named"
                final_effects, final_fit = [best, best2[0]], best2[1]
                message = (f"Named two effects (greedy): {best} (LR {cres[best].lr:.4g}) then {best2[0]} "
                           f"(LR {best2[2]:.4g} on top); the gap closes.")
            else:
                verdict = "unexplained"
                final_effects = [best] + ([best2[0]] if best2 else [])
                final_fit = best2[1] if best2 else fits[best]
                message = (f"Unexplained: the best candidate {best} (LR {cres[best].lr:.4g}) reduces the cost but a "
                           f"significant gap remains (2·cost {2 * final_fit.cost:.4g} > "
                           f"{gap_thr(final_effects):.4g}) in {where}; nothing in the library explains it.")
    if not res0.converged:
        message += f" WARNING: the baseline calibration did not converge ({res0.message})."
    bad = [c for c, cr in cres.items() if not cr.converged]
    if bad:
        message += f" Candidate refits that did not converge: {', '.join(bad)}."
    named = final_effects if verdict in ("named", "ambiguous") else []
    if verdict == "ambiguous":
        named = [c for c in sig if cres[c].closes_gap and cres[c].aic - min(cres[x].aic for x in sig if cres[x].closes_gap) < AMBIGUITY_AIC]
    if final_fit is not None:
        Gf = pm([final_fit.values])[0]
        n_free_after = len(final_fit.names)
    else:
        Gf, n_free_after = G0, k0
    rf = standardised_residuals(Gf, data, s_ln, s_ph)
    fe = {c: {k.split(".", 1)[1]: final_fit.values[k] for k in final_fit.names if k.startswith(c + ".")}
          for c in final_effects} if final_fit is not None else {}
    return Diagnosis(
        verdict=verdict, named=named, message=message, kind=kind, quantity=q, alpha=alpha, threshold=T,
        gap_threshold=gap_thr0, baseline=res0, final=final_fit, final_effects=fe, candidates=cres,
        skipped=skipped, confusable=confusable, separation=separation, localisation_before=_localise(data, r0, alpha),
        localisation_after=_localise(data, rf, alpha), gap_before=_gap(data, r0, k0),
        gap_after=_gap(data, rf, n_free_after),
        null={"method": "linearised Gaussian null at the fitted baseline (constrained LR per candidate, "
                        "max over candidates) scaled by full-refit parametric bootstrap",
              "draws": int(null_draws), "refits": int(null_refits), "lr_threshold_linearised": T_lin,
              "nonlinearity_ratio": ratio, "bootstrap_full_max_lr": full_max, "bootstrap_lin_max_lr": lin_used,
              "alpha_gap": alpha_gap, "seed": seed},
        noise_estimated=estimated, elapsed_s=time.perf_counter() - t0, data=data,
        predicted_before=G0, predicted_after=Gf,
        metadata={"base": base.name, "free": names0, "baseline_effects": beff, "candidates": cand,
                  "data_fingerprint": data.fingerprint()},
    )


__all__ = ["diagnose", "Diagnosis", "CandidateResult", "VERDICTS", "gap_shrink", "CONFUSABLE_COSINE",
           "AMBIGUITY_AIC"]
