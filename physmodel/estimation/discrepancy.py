"""The discrepancy workflow: locate a misfit, name the missing effect, add it, show the gap shrink.

:func:`diagnose` (discrepancy.md) takes frequency-response data, a base parameter set and the
user's free parameters, and:

1. calibrates the baseline model (the project's one engine,
   :func:`physmodel.estimation.lsq.fit_parameters`, multi-start) with the free base parameters
   held to their plausible ranges (:mod:`physmodel.plausible`) by soft walls
   (:mod:`physmodel.estimation.priors`: zero penalty inside, a Gaussian wall of 0.02 decade
   outside), and audits it: parameters at or near a bound, outside their plausible range, and the
   multi-start spread; it tabulates where the standardised residuals exceed their band;
2. refits the full model with each candidate effect of :data:`physmodel.effects.LIBRARY` switched
   on (nested, full nonlinear refits, starting from off, from a linearised estimate, from a
   typical size and from any user start — each from the baseline optimum and from the user's start
   values (a baseline that absorbed the effect can hold a refit in its basin); the best is kept and
   the spread reported), within *candidate bounds* scaled to the strip
   (:meth:`physmodel.effects.Effect.candidate_parameters`; user-adjustable) and scores it by
   LR = 2 (cost_baseline − cost_candidate) of the penalised costs, with AIC/BIC alongside;
3. sets the acceptance threshold by Monte Carlo under the null (no effect), so that the
   *family-wise* false-positive rate of "max over candidates of LR" is α − α/5 — the other α/5 is
   the gap test's (step 5), so that a null record's verdict is wrong with probability at most α
   (the union bound; until 2026-11-26 the LR test took all of α, 1.2 α in all): a linearised Gaussian
   null at the fitted baseline (constrained LR per candidate: χ̄² mixtures for effects whose off
   value is a bound; for a candidate with parameters that act only once it is on — the damping
   of a resonance, a fluid's viscosity — the supremum over a grid of them, Davies' look-elsewhere
   correction, :func:`~physmodel.estimation.nullstats.scan_lr`), ``null_draws`` draws, scaled by
   the ratio of full-refit to linearised LR on ``null_refits`` parametric-bootstrap draws
   (clipped to [1, 3]; each candidate refitted warm from the draw's baseline refit with the effect
   starts of the data, :meth:`~physmodel.estimation.refits.Refitter.null_max_lr`);
4. reports as *confusable* the candidate pairs whose signatures (Jacobian columns with the
   baseline Jacobian projected out; the secant to the typical size where the tangent at off carries
   < :data:`~physmodel.estimation.nullstats.SECANT_RATIO` of it) have a largest canonical correlation ≥ :data:`CONFUSABLE_COSINE`,
   and, after the refits, the pairs the data cannot separate (below) or that are *confusable in this
   band at the fitted sizes*: each fitted noiselessly to the other's fitted prediction leaves
   λ = 2·cost < 4·z_crit², where Vuong's test has less than even odds;
5. decides: ``none``, ``named`` (one significant candidate that closes the gap, plus a second one
   significant on top of it if any — a forward step; else the best pair among the
   :data:`PAIR_POOL` most significant candidates whose members are each significant on top of the
   other and that closes the gap; pairs are drawn from the most significant candidates and from
   those that best explain what the best one leaves, never a declared-confusable pair; each
   member must carry more than :data:`CLOSE_FRACTION` of the baseline's excess, unless the pair
   closes the gap strictly — within the noise band — where neither member alone does), ``ambiguous``
   (``named`` lists the candidates: the closer of lowest AIC and every significant candidate that
   Vuong's test of non-nested models (1989; :func:`~physmodel.estimation.signatures.vuong_z`,
   per-residual log-likelihood ratios of the two refits) does not reject against it, two-sided at
   the user's α: z < Φ⁻¹(1 − α/2).  For exactly specified candidates whose noiseless fits differ by
   λ, z has mean ≈ √λ/2, so a wrong confident name has chance ≤ α/2 and a pair with λ ≥ 25 is
   told apart in about 70 % of draws; the best pair likewise against every other closing pair,
   the members in which two unseparated pairs differ being declared confusable), ``at_bound`` (the named
   effect closes the gap only with one of its *own* parameters at a candidate bound that matters —
   relaxing it would gain more than χ²₁ at α, :mod:`~physmodel.estimation.verdicts`: "widen the
   bound, or the effect is larger than allowed" — never a confident name; another candidate at its
   bound is only noted, and a parameter ending at its off value reports the effect in its simpler
   form), ``unexplained`` (a significant gap nothing closes).  The gap test
   (:class:`~physmodel.estimation.gap.GapTest`) compares 2·cost (data lines only) with the
   (1 − α/5) quantile of its null distribution; an effect that leaves at most
   :data:`CLOSE_FRACTION` of the baseline's excess above it also closes the gap (the message then
   states the remaining share).  Several quantities: per quantity, each one's 2·cost against its own
   quantile at α/5/K (Bonferroni over K quantities), the gap significant if any quantity's is and
   closed only if closed in every one (the slack of each quantity's own excess) and in the pooled
   statistic at α/5; the message says which test leaves it open.

The report also states the temperature laws used, warns when the weighted cost is inconsistent
with the declared noise (too low or too high, with the factor), and says when the baseline fits
only by leaving its plausible range (evidence of a missing effect).  Residuals are those of
:func:`physmodel.estimation.residuals.standardised_residuals`; data without per-line standard
deviations use the 1 % fallback and the report says so.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from functools import partial
from itertools import combinations

import numpy as np

from ..data.sweep import FrequencySweep
from ..effects import DEFAULT_QUANTITY, LIBRARY, EffectModel, candidates_for, get_effect, normalize_effects
from ..errors import IPMCError, ParameterError
from ..parameter_paths import is_effect_parameter
from ..params import IPMCParameters
from ..plausible import plausible_ranges
from .diagnosis import (
    CLOSE_FRACTION,
    CONFUSABLE_COSINE,
    GAP_ALPHA_DIVISOR,
    VERDICTS,
    CandidateResult,
    Diagnosis,
    audit_notes,
    gap_shrink,
    named_message,
    resolve_laws,
    stage_progress,
    worst_cells,
)
from .gap import GapTest, block_rows
from .joint import check_acts_on, joint_data, per_quantity_sentence
from .nullstats import bootstrap_ratio, constrained_lr, null_tails, scan_lr, signature_stage, thin_tail_note
from .priors import (
    WALL_DECADES,
    PenalisedProblem,
    bound_audit,
    cost_warning,
    free_parameters_for,
    multistart_spread,
    penalties_for,
    plausible_audit,
)
from .records import CalibrationResult, FreeParameter
from .refits import Refitter, StageCounter
from .residuals import GOF_ALPHA, standardised_residuals
from .signatures import (
    declare_confusable,
    gap_statistics,
    localise,
    orth,
    pair_members,
    project_out,
    vuong_confusability,
    vuong_critical,
    vuong_z,
)
from .verdicts import reduced_parameters, reduced_sentence, relax_gain, relax_threshold, sign_flip

#: Pairs of two effects: every pair among this many most significant candidates, and each of them
#: with the PAIR_EXPLAINERS candidates that best explain what its refit leaves; the PAIR_FITS best
#: of those (by LR of the first + linearised LR of the second on its residual) are refitted jointly.
PAIR_POOL = 4
PAIR_EXPLAINERS = 2
PAIR_FITS = 6


# =============================================================================== main entry
def diagnose(data: FrequencySweep | Sequence[FrequencySweep], base: IPMCParameters, *, kind: str = "actuator",
             quantity: str | Sequence[str] | None = None,
             free: Sequence[str | FreeParameter] = ("alpha0",),
             baseline_effects: Mapping[str, Mapping[str, float]] | Sequence[str] = (),
             candidates: Sequence[str] | None = None, alpha: float = 0.05, null_draws: int = 4000,
             null_refits: int = 4, seed: int = 0, kernel: str = "boundary_charge", max_nfev: int = 200,
             laws=None, candidate_bounds: Mapping | None = None, candidate_starts: Mapping | None = None,
             plausible: Mapping | None = None, prior: bool = True, baseline_starts: int = 3,
             progress: Callable[[str], None] | None = None, acts_on: Mapping[str, Sequence[str]] | None = None,
             _restart: Mapping | None = None) -> Diagnosis:
    """Diagnose the discrepancy between ``data`` and the ``base`` model (see module docstring).

    A candidate refit that beats the baseline may have found a better basin of the baseline itself:
    for the three best candidates above the linearised threshold, the baseline is refitted from
    their base values and, if lower by more than ½ in cost, the diagnosis restarts once with it
    (``metadata["baseline_restart"]``; ``_restart`` is that internal start).

    Parameters
    ----------
    data : FrequencySweep or sequence of FrequencySweep
        One sweep (one measured quantity), or sweeps of the same strip, one per quantity (e.g. an
        actuator's M and Z), diagnosed jointly: baseline, candidates and null over all their lines,
        each quantity with its own noise (:mod:`~physmodel.estimation.joint`).
    base : IPMCParameters
        The user's starting parameter set.
    kind : {"actuator", "sensor"}
        The physics.
    quantity : str, sequence of str or None
        The measured quantity (default M for an actuator, S for a sensor), or one name per sweep
        (None: each taken from its sweep's metadata and units).
    free : sequence of str or FreeParameter
        The user's calibration parameters: names with default bounds, ``"effect.param"`` of a
        baseline effect, or :class:`~physmodel.estimation.records.FreeParameter` records.
    baseline_effects : mapping or sequence of str
        Effects already in the model, ``{name: {param: value}}`` (SI); a bare name means all its
        parameters free from their off value.
    candidates : sequence of str or None
        Library effect names to test (default: all that apply to ``kind`` and the quantities and
        are not in the baseline).
    alpha : float
        Family-wise false-positive rate of the verdict [-]: the candidates' LR test runs at
        α − α/5 and the gap test at α/5 (:data:`~physmodel.estimation.diagnosis.GAP_ALPHA_DIVISOR`).
    null_draws, null_refits : int
        Linearised null Monte-Carlo draws, and full bootstrap refits that correct its threshold.  A quantile
        the tests use with < 10 draws beyond it is said in the message and ``null["thin_tail"]`` (each
        quantile's draws beyond it: ``null["tails"]``; :func:`~physmodel.estimation.nullstats.thin_tail_note`).
    seed : int
        Seed of the null draws and multi-starts.
    kernel : str
        The sensor's collection kernel (see :func:`~physmodel.estimation.calibration.calibrate`).
    max_nfev : int
        Residual evaluations per fit start.
    laws : None, str, TemperatureLaws or mapping
        Temperature laws: None/``"set"`` (those of ``base``), ``"isothermal"``, ``"default"``
        (physics.md §7), a :class:`~physmodel.temperature.TemperatureLaws` or a mapping (see
        :func:`~physmodel.estimation.diagnosis.resolve_laws`); the report states the choice.
    candidate_bounds : mapping or None
        ``{"effect.param": (lower, upper) or {"lower", "upper", "typical"}}`` replacing the
        strip-scaled candidate bounds (SI).
    candidate_starts : mapping or None
        ``{"effect.param": value}``: extra start values (SI).
    plausible : mapping or None
        ``{field: (lower, upper)}`` replacing the default plausible ranges (SI).
    prior : bool
        Hold the free base parameters to their plausible ranges (soft walls).
    baseline_starts : int
        Multi-start count of the baseline fit.
    progress : callable or None
        ``progress(message)``, called within every stage.
    acts_on : mapping or None
        Several quantities only: ``{effect: [quantities]}`` narrowing where an effect acts (e.g.
        a current amplifier on S, not on Z measured by another instrument); elsewhere it is held
        at its off values.

    Returns
    -------
    Diagnosis
        The verdict, the named effect(s), every candidate's statistics and the refitted models.
    """
    args = dict(kind=kind, quantity=quantity, free=free, baseline_effects=baseline_effects, candidates=candidates,
                alpha=alpha, null_draws=null_draws, null_refits=null_refits, seed=seed, kernel=kernel,
                max_nfev=max_nfev, laws=laws, candidate_bounds=candidate_bounds, candidate_starts=candidate_starts,
                plausible=plausible, prior=prior, baseline_starts=baseline_starts, progress=progress, acts_on=acts_on)
    base_in, data_in = base, data
    t0 = time.perf_counter()
    jd = None                                   # several quantities: their stacked lines (joint.py)
    if not isinstance(data, FrequencySweep):
        if isinstance(data, (str, bytes)) or not isinstance(data, Sequence):
            raise IPMCError(f"data must be a FrequencySweep or a sequence of them (one per quantity), "
                            f"got {type(data).__name__}")
        jd = joint_data(data, kind, quantity)
        if len(jd.quantities) == 1:             # one quantity: today's path
            data, quantity, jd = jd.sweeps[0], jd.quantities[0], None
    if not isinstance(base, IPMCParameters):
        raise ParameterError(f"base must be IPMCParameters, got {type(base).__name__}")
    if not (0 < alpha < 0.5):
        raise IPMCError(f"alpha={alpha!r} must lie in (0, 0.5)")
    # >= 200 runs; any quantile used with < 10 draws beyond it is said (nullstats.thin_tail_note): 1000 draws
    # can be too few (K = 2: 5 beyond the 0.995 per-quantity quantile), so can 4000 (α = 0.01, K = 2: 4)
    if int(null_draws) < 200:
        raise IPMCError(f"null_draws={null_draws!r} is too small for a {1 - alpha:g} quantile; use >= 200")
    if int(null_refits) < 0:
        raise IPMCError(f"null_refits={null_refits!r} must be >= 0")
    if int(baseline_starts) < 1:
        raise IPMCError(f"baseline_starts={baseline_starts!r} must be >= 1")
    base, laws_note = resolve_laws(base, laws)
    q = jd.label if jd is not None else (quantity or DEFAULT_QUANTITY.get(kind, ""))
    qs = jd.quantities if jd is not None else (q,)
    say = stage_progress(progress)
    if isinstance(baseline_effects, Mapping):
        beff = normalize_effects(baseline_effects)
        extra_free = []
    else:
        beff = normalize_effects({n: {} for n in baseline_effects})
        extra_free = [f"{n}.{p.name}" for n in beff for p in get_effect(n).parameters]
    cbounds, cstarts = _candidate_overrides(candidate_bounds, candidate_starts)
    model0 = EffectModel(base, kind, beff, kernel=kernel)
    if acts_on and jd is None:
        raise IPMCError("acts_on narrows where effects act among several measured quantities; this diagnosis has one")
    scope = check_acts_on(acts_on, kind, qs)
    counter = StageCounter(jd.predictor(model0, scope) if jd is not None else model0.predictor(data, q).many)
    pm = counter.predict_many
    free0 = free_parameters_for(base, list(free) + [f for f in extra_free if f not in free], beff)
    names0 = [fp.name for fp in free0]
    ranges = plausible_ranges(base, plausible)
    pens = penalties_for(free0, ranges) if prior else []
    if jd is not None:                          # each quantity's own σ where its sweep declares none
        counter.enter("baseline")
        jd = jd.resolve_noise(lambda d: pm([PenalisedProblem(d, pm, pens).fit(
            free0, seed=seed, max_nfev=max_nfev, identify=False, hold_undetermined=False).values])[0])
        data = jd.stacked
    prob = PenalisedProblem(data, pm, pens)
    s_ln, s_ph, estimated = prob.s_ln, prob.s_ph, prob.estimated or (jd is not None and jd.any_estimated)
    N = data.frequency_hz.size
    n_temps = data.temperatures().size

    cpars: dict = {}       # {candidate: its parameters with candidate bounds}, filled below
    rf = Refitter(prob, free0, cpars, cstarts, seed=seed, max_nfev=max_nfev, baseline_starts=baseline_starts,
                  counter=counter)
    from_, fit = rf.from_, rf.fit

    # ---- 1. baseline
    counter.enter("baseline")
    res0 = fit(free0, starts=int(baseline_starts))
    if _restart is not None:
        res0 = min(res0, fit(from_(_restart)), key=lambda x: x.cost)
    v0 = dict(res0.values)
    G0 = pm([v0])[0]
    r0 = standardised_residuals(G0, data, s_ln, s_ph)
    cost0 = res0.metadata["data_cost"]
    audit0 = {"at_bound": bound_audit(res0, free0), "implausible": plausible_audit(v0, ranges),
              "multistart": multistart_spread(res0), "penalty": res0.metadata["penalty"],
              "plausible_ranges": {k: ranges[k].describe() for k in names0 if k in ranges}}
    say("baseline", f"baseline fitted: cost {cost0:.4g} (expected {res0.expected_cost:.4g})")

    # ---- 2. signatures, confusability
    applies = {c for qq in qs for c in candidates_for(kind, qq, n_temps)}      # to any of the quantities
    cand = [get_effect(c).name for c in candidates] if candidates is not None else [
        c for c in LIBRARY if c in applies and c not in beff]
    for c in cand:
        if c not in LIBRARY:
            raise ParameterError(f"unknown candidate effect {c!r}; expected library names {sorted(LIBRARY)}")
        if not any(LIBRARY[c].applies_to(kind, qq) and qq in scope.get(c, qs) for qq in qs):
            raise ParameterError(f"candidate {c!r} does not apply to {kind} quantity {q}")
    bad = sorted(set(cbounds) - set(cand)) + sorted(set(cstarts) - set(cand))
    if bad:
        raise ParameterError(f"candidate bounds/starts given for {bad}, which are not candidates here ({cand})")
    counter.enter("signatures")
    cpars.update({c: LIBRARY[c].candidate_parameters(base, cbounds.get(c)) for c in cand})
    hard = _hard_sides(cpars)
    J0, Q0, sigs, sided, skipped, first_order, raw_sigs, degenerate, confusable, separation = signature_stage(
        pm, v0, free0, cand, cpars, r0, data, s_ln, s_ph)
    conf_set = {frozenset((a, b)) for a, b, _ in confusable}

    # ---- 3. linearised null Monte Carlo
    rng = np.random.default_rng(seed + 7919)
    E = rng.standard_normal((2 * N, int(null_draws)))
    Ep = project_out(Q0, E)
    lin = {c: constrained_lr(S, sided[c], Ep) for c, S in sigs.items()}
    for c in [c for c in sigs if c in degenerate]:      # look-elsewhere over parameters without a first-order signature
        lin[c] = np.maximum(lin[c], scan_lr(pm, v0, c, cpars[c], degenerate[c], r0, data, s_ln, s_ph, Q0, Ep,
                                            is_off=LIBRARY[c].is_off))
    lin_max = np.max(np.vstack(list(lin.values())), axis=0) if lin else np.zeros(E.shape[1])
    alpha_gap = alpha / GAP_ALPHA_DIVISOR
    T_lin = float(np.quantile(lin_max, 1 - (alpha - alpha_gap)))     # the LR test's share of α (module doc, 3)
    # the gap test, per quantity of a joint record (gap.py); its costs per block of a fit
    gap = GapTest.from_null(Ep, alpha_gap, [cost0] if jd is None else 0.5 * np.array(
        [r0[i] @ r0[i] for i in block_rows(jd.sizes)]), sigs, qs, None if jd is None else jd.sizes)
    bc = partial(gap.fit_costs, residuals=lambda v, p=pm: standardised_residuals(p([v])[0], data, s_ln, s_ph))
    say("signatures", f"linearised null: LR threshold {T_lin:.3g} from {E.shape[1]} draws")
    tails = null_tails(int(null_draws), alpha, alpha_gap, gap.K)

    # ---- 4. candidate refits
    counter.enter("singles")
    rf.sigs = sigs
    eff_free, refit, lin_start, starts_for = rf.eff_free, rf.refit, rf.lin_start, rf.starts_for

    def audit(res, extra_free):
        fl = free0 + extra_free
        return bound_audit(res, fl, hard), plausible_audit({k: res.values[k] for k in names0}, ranges)

    cres: dict[str, CandidateResult] = {}
    fits: dict[str, CalibrationResult] = {}
    k0 = len(free0)
    n_res = 2 * N
    for i_c, c in enumerate(sigs):
        say("candidates", f"refitting candidate {i_c + 1}/{len(sigs)}: {c}", i_c, len(sigs))
        res = refit([c], v0, starts_for(c, r0, Q0), from_user=True)
        fits[c] = res
        k = len(cpars[c])
        lr = max(0.0, 2 * (res0.cost - res.cost))
        ev = {p.name: res.values[f"{c}.{p.name}"] for p in cpars[c]}
        dc = res.metadata["data_cost"]
        ab, imp = audit(res, eff_free(c))
        cres[c] = CandidateResult(
            c, ev, {p: res.ci_lower[f"{c}.{p}"] for p in ev}, {p: res.ci_upper[f"{c}.{p}"] for p in ev},
            dc, lr, 2 * res.cost + 2 * (k0 + k), 2 * res.cost + (k0 + k) * math.log(n_res), k,
            False, False, res.converged, float(np.linalg.norm(sigs[c])),
            float(constrained_lr(sigs[c], sided[c], -project_out(Q0, r0[:, None]))[0]), first_order.get(c, ""),
            bounds={p.name: [p.lower, p.upper] for p in cpars[c]}, at_bound=ab, implausible=imp,
            penalty=res.metadata["penalty"], multistart=res.metadata["refit_multistart"])
    say("candidates", f"{len(cres)} candidates refitted")
    for c in sorted(cres, key=lambda c: -cres[c].lr)[:3] if _restart is None else []:
        if cres[c].lr <= T_lin:
            break
        rb = fit(from_(fits[c].values))
        if rb.cost < res0.cost - 0.5:       # ½Δχ² > ½: a better baseline basin, not the effect
            say("candidates", f"baseline basin from the {c} refit: cost {rb.cost:.4g} < {res0.cost:.4g}; restarting")
            out = diagnose(data_in, base_in, **args, _restart=rb.values)
            out.metadata["baseline_restart"] = {"from_candidate": c, "cost_before": res0.cost, "cost_after": rb.cost}
            return out
    # ---- 5. bootstrap refits under the null (nonlinearity correction of the threshold)
    counter.enter("null")
    n_boot = int(null_refits) * (len(sigs) + 1)
    boot_done = [0]

    def refit_max(sim, rb):
        def say_c(c):
            say("null", f"null refit {boot_done[0] // (len(sigs) + 1) + 1}/{int(null_refits)}: {c}", boot_done[0], n_boot)
            boot_done[0] += 1
        boot_done[0] += 1
        return rf.null_max_lr(sim, rb, Q0, say_c)

    fit_null = partial(rf.fit_null, v0)
    ratio, full_max, lin_used = bootstrap_ratio(E, lin_max, G0, data, s_ln, s_ph, int(null_refits), fit_null, refit_max)
    T = T_lin * ratio
    say("null", f"null threshold {T:.3g} (linearised {T_lin:.3g} × nonlinearity ratio {ratio:.3g})")

    # ---- 6. verdict (its steps are not known in advance: each one moves the share done on)
    v_steps = [0]

    def say_v(msg: str) -> None:
        v_steps[0] += 1
        say("verdict", msg, v_steps[0], v_steps[0] + 4)

    counter.enter("verdicts")
    say_v("testing significance and the gap")
    for c, cr in cres.items():
        cr.significant = cr.lr > T
        cr.closes_gap = gap.closes(bc(fits[c]), [c])
    gap0_sig = gap.significant0
    z_crit = vuong_critical(alpha)
    confusability: dict = {"z_critical": z_crit, "data": [], "in_band": []}
    sig = sorted((c for c in cres if cres[c].significant), key=lambda c: -cres[c].lr)
    final_effects: list[str] = []
    final_fit: CalibrationResult | None = None
    pair_tried: list = []
    named2: list = []
    where = worst_cells(localise(data, r0, alpha))
    if not sig:
        if gap0_sig:
            verdict = "unexplained"
            message = (f"The baseline leaves a significant gap ({gap.compare(gap.cost0)}) "
                       f"that no library candidate reduces significantly; the gap remains in {where}.")
        else:
            verdict = "none"
            message = (f"No significant discrepancy: best candidate LR "
                       f"{max([c.lr for c in cres.values()], default=0.0):.3g} ≤ threshold {T:.3g}, and the "
                       + (f"baseline cost {cost0:.4g} is within its null band." if gap.K == 1 else
                          f"baseline is within its null band ({gap.compare(gap.cost0)})."))
    else:
        expl_cache: dict = {}

        def explain_scores(a):
            """Linearised LR of every other candidate on what a's refit leaves (its residual, with the
            baseline Jacobian and a's signature projected out), with that residual and projector."""
            if a not in expl_cache:
                r_a = standardised_residuals(pm([fits[a].values])[0], data, s_ln, s_ph)
                Qa = orth(np.hstack([J0, sigs[a]]))
                rr = -project_out(Qa, r_a[:, None])
                expl_cache[a] = ({b: float(constrained_lr(project_out(Qa, sigs[b]), sided[b], rr)[0])
                                  for b in sigs if b != a}, r_a, Qa)
            return expl_cache[a]

        def strict(res, effs) -> bool:
            """2·cost within its null band in every block (no tolerance for a parametrisation mismatch)."""
            return gap.strict(bc(res), effs)

        def screen_pairs(exclude=frozenset()):
            """Pairs among the PAIR_POOL most significant candidates and each of them with the
            PAIR_EXPLAINERS candidates that best explain what its refit leaves (significant alone or
            not), ranked by LR(first) + linearised LR(second on the first's residual), best order;
            never a declared-confusable pair nor two of ``exclude``; the PAIR_FITS best."""
            top = sig[:PAIR_POOL]
            pool = {frozenset(x) for x in combinations(top, 2)}
            for a in top:
                sc = explain_scores(a)[0]
                pool |= {frozenset((a, b)) for b in sorted(sc, key=lambda k: -sc[k])[:PAIR_EXPLAINERS]}
            pool = {x for x in pool if x not in conf_set and not x <= exclude}

            def score(x):
                a, b = sorted(x)
                return max(cres[a].lr + explain_scores(a)[0][b], cres[b].lr + explain_scores(b)[0][a])
            ranked = sorted(pool, key=lambda x: (-score(x), sorted(x)))[:PAIR_FITS]
            return [tuple(sorted(x, key=lambda c: -cres[c].lr)) for x in ranked]

        def joint_start(a, b):
            """Both effects' values from the linearised joint fit of their signatures to the baseline residual."""
            S = project_out(Q0, np.hstack([sigs[a], sigs[b]]))
            d, *_ = np.linalg.lstsq(S, -r0, rcond=None)
            out, j = {}, 0
            for c in (a, b):
                out[c] = {p.name: float(np.clip(p.off + d[j + k] * (p.typical - p.off), p.lower, p.upper))
                          for k, p in enumerate(cpars[c])}
                j += len(cpars[c])
            return out

        best_single = min(fits[c].cost for c in fits)
        fitted_pairs: dict = {}

        def fit_pair(a, b):
            """Joint refit of a + b, the best of starts from a's own fit (b from its own fit and from
            its linearised estimate on a's residual), from b's own fit (a likewise) and from the
            joint linearised estimate at the baseline."""
            key = frozenset((a, b))
            if key not in fitted_pairs:
                was = counter.stage
                counter.enter("pairs")
                own = {**fits[a].values, **{k: v for k, v in fits[b].values.items() if k.startswith(b + ".")}}
                own_b = {**fits[b].values, **{k: v for k, v in fits[a].values.items() if k.startswith(a + ".")}}
                _, r_a, Qa = explain_scores(a)
                _, r_b, Qb = explain_scores(b)
                # one multi-start: a later start that reaches an earlier one's optimum stops there
                # (three separate fits each ran to the same optimum)
                fitted_pairs[key] = refit([a, b], own, [None, {b: lin_start(b, r_a, Qa)}],
                                          more=[(f"{b} refit", own_b, [{a: lin_start(a, r_b, Qb)}]),
                                                ("baseline optimum, joint linearised", v0, [joint_start(a, b)])],
                                          origin=f"{a} refit")
                counter.enter(was)
            return fitted_pairs[key]

        def pair_fits(pairs):
            out = []
            for i_p, (a, b) in enumerate(pairs):
                say_v(f"pair {i_p + 1}/{len(pairs)}: {a} + {b}")
                res2 = fit_pair(a, b)
                lr_a, lr_b = 2 * (fits[b].cost - res2.cost), 2 * (fits[a].cost - res2.cost)   # each on top
                gain = 2 * (best_single - res2.cost)                                           # over the best single
                closes = gap.closes(bc(res2), [a, b])
                # the pair's gain over the best single passes the calibrated threshold, and either
                # carries more than the share of the excess a closing effect may leave, or the pair
                # closes the gap strictly (within the noise band) where neither member alone does and
                # each explains the majority of what the other leaves above its χ² expectation
                left = {c: 2 * fits[c].metadata["data_cost"] - (n_res - len(fits[c].names)) for c in (a, b)}
                rescue = (strict(res2, [a, b]) and not strict(fits[a], [a]) and not strict(fits[b], [b])
                          and lr_b >= 0.5 * left[a] and lr_a >= 0.5 * left[b])
                accepted = gain > T and (gain > T2 or rescue)
                pair_tried.append({"pair": [a, b], "cost": res2.metadata["data_cost"], "lr_first_on_top": lr_a,
                                   "lr_second_on_top": lr_b, "gain_over_best_single": gain, "closes_gap": closes,
                                   "closes_strictly": rescue, "accepted": accepted})
                if accepted:
                    out.append(((a, b), res2, lr_a, lr_b, closes))
            return sorted(out, key=lambda x: x[1].cost)

        def with_alternatives(ok, alias):
            """``ok`` plus the pairs that swap a member of the best pair for a candidate declared
            confusable with it (first-order signatures, or ``alias``: not separated by the data), so
            name_pair's test reports them."""
            if not ok:
                return ok
            best2 = ok[0][0]
            seen = {frozenset(x[0]) for x in ok}
            for m in best2:
                other = [x for x in best2 if x != m][0]
                for c in sigs:
                    if c in best2 or not (frozenset((m, c)) in conf_set or (m in alias and c in alias)):
                        continue
                    key = frozenset((other, c))
                    if key in seen or key in conf_set or cres[c].lr <= T:
                        continue
                    seen.add(key)
                    res2 = fit_pair(other, c)
                    ok = ok + [((other, c), res2, 2 * (fits[c].cost - res2.cost), 2 * (fits[other].cost - res2.cost),
                                gap.closes(bc(res2), [other, c]))]
            return ok

        def name_pair(ok):
            """The best pair, ambiguous with every closing pair Vuong's test does not separate from it
            (two-sided at α, as for single effects); their differing members are declared confusable."""
            best2 = ok[0]
            a, b = best2[0]
            r_best = standardised_residuals(pm([best2[1].values])[0], data, s_ln, s_ph)
            alt = []
            for x in ok[1:]:
                if not x[4]:
                    continue
                z = vuong_z(r_best, standardised_residuals(pm([x[1].values])[0], data, s_ln, s_ph),
                            best2[1].cost, x[1].cost)
                if z < z_crit:
                    alt.append((x[0], z))
                    for m, o in pair_members(best2[0], x[0], sigs):
                        confusability.setdefault("pairs", []).append({"top": m, "other": o, "z": z, "separated": False})
            msg = (f"Named two effects: {a} and {b} (joint refit; gain over the best single effect LR "
                   f"{2 * (best_single - best2[1].cost):.4g} > {T:.3g}; LR of each on top of the other "
                   f"{best2[2]:.4g}, {best2[3]:.4g})" + ("; the gap closes." if best2[4] else "."))
            if alt:
                return ("ambiguous", sorted({a, b} | {c for x, _ in alt for c in x}), list(best2[0]), best2[1],
                        msg.replace("Named two effects", "Ambiguous: best pair")
                        + f" Other pairs the data do not separate from it (Vuong z < {z_crit:.3g}): "
                        + "; ".join(f"{x[0]} + {x[1]} (z = {z:.3g})" for x, z in alt) + ".")
            return "named", [a, b], list(best2[0]), best2[1], msg

        # a second effect must be significant and carry more than the share of the excess that a
        # closing effect may leave (the tolerance for another author's parametrisation; several
        # quantities: the sum of what each quantity's slack allows)
        T2 = max(T, CLOSE_FRACTION * float(np.sum(gap.excess0)))
        closers = [c for c in sig if cres[c].closes_gap]
        if closers:
            top = min(closers, key=lambda c: cres[c].aic)
            confusability = vuong_confusability(top, sig, fits, cres, pm, data, s_ln, s_ph, z_crit,
                                                lambda *a, **k: (say_v(f"cross-fit of {a[0][0]} (Vuong's test)"),
                                                                 refit(*a, **k))[1])
            amb = [top] + [x["other"] for x in confusability["data"] if not x["separated"]]
            final_effects, final_fit = [top], fits[top]
            if len(amb) > 1:
                verdict = "ambiguous"
                zs = "; ".join(f"{x['other']} z = {x['z']:.3g}" for x in confusability["data"] if not x["separated"])
                message = (f"Ambiguous between {', '.join(amb)}: the data do not separate them from the best "
                           f"closer {top} (Vuong's test of non-nested fits, z < {z_crit:.3g} at "
                           f"α = {alpha:g}: {zs}). "
                           "Separate them with a wider band, more temperatures, or magnitude vs phase.")
            else:
                verdict, message = "named", named_message(top, cres[top])
            # a second effect: pairs searched (not only grown from the first), accepted when their
            # gain over the best single passes the calibrated threshold
            ok = with_alternatives(pair_fits(screen_pairs(frozenset(amb))), amb)
            if ok:
                v2, n2, final_effects, final_fit, m2 = name_pair(ok)
                if verdict == "ambiguous" and top in final_effects:       # the first effect stays ambiguous
                    v2, n2 = "ambiguous", sorted(set(n2) | set(amb))
                    m2 += f" The first effect is ambiguous between {', '.join(amb)}."
                verdict, named2, message = v2, n2, m2
        else:
            # two effects: pairs among the most significant candidates and each of them with the
            # candidates that best explain what it leaves, refitted jointly from several starts
            ok = with_alternatives(pair_fits(screen_pairs()), [])
            if ok and ok[0][4]:
                verdict, named2, final_effects, final_fit, message = name_pair(ok)
            else:
                best = sig[0]
                verdict = "unexplained"
                final_effects = list(ok[0][0]) if ok else [best]
                final_fit = ok[0][1] if ok else fits[best]
                message = (f"Unexplained: the best candidate {best} (LR {cres[best].lr:.4g}) reduces the cost but a "
                           f"significant gap remains ({gap.compare(bc(final_fit), final_effects)}) in {where}; no "
                           "candidate or pair of candidates in the library explains it.")
    if verdict in ("named", "ambiguous") and final_fit is not None:
        message += gap.residual_sentence(final_fit, bc(final_fit), final_effects)
    # ---- 7. audits of the final model: a named effect's own parameter at a bound that matters
    # (relaxing it would gain more than χ²₁ at α) makes the name 'at bound'; one at its off value
    # reduces the effect to its simpler form; another candidate's bound is only noted
    final_bounds, final_implausible = ([], [])
    if final_fit is not None:
        final_bounds, final_implausible = audit(final_fit, [fp for c in final_effects for fp in eff_free(c)])
    reduced = reduced_parameters(final_effects, final_bounds, final_fit.values, cpars) if final_fit is not None else []
    red_names = {x["name"] for x in reduced}
    at_bound = [a for a in final_bounds if a["status"] == "at" and a["name"] not in red_names]
    own = [a for a in at_bound if not a["hard"] and is_effect_parameter(a["name"])
           and a["name"].split(".", 1)[0] in final_effects]
    if own and final_fit is not None:
        gains = relax_gain(pm, final_fit.values, final_fit.free, [a["name"] for a in own], data, s_ln, s_ph)
        for a in own:
            a["relax_lr"] = gains.get(a["name"], float("nan"))
    relax_thr = relax_threshold(alpha)
    widen = [a for a in own if not (a.get("relax_lr", math.inf) <= relax_thr)]
    others_stuck = [a for c in sig if c not in final_effects and any(frozenset((c, n)) in conf_set for n in final_effects)
                    for a in cres[c].at_bound if a["status"] == "at" and not a["hard"] and a["name"].startswith(c + ".")
                    and a["bound"] != getattr(LIBRARY[c].parameter(a["name"].split(".", 1)[1]), a["side"])]
    if verdict in ("named", "ambiguous") and widen:
        verdict = "at_bound"
        message = ("At bound — widen or the effect is larger than allowed: " + "; ".join(
            f"{a['name']} = {a['value']:.4g} at its {a['side']} bound {a['bound']:.4g} (relaxing it would gain "
            f"LR {a.get('relax_lr', float('nan')):.3g} > {relax_thr:.3g})" for a in widen)
            + ". The gap closes only there, so this is not a confident name (raise the bound with "
            "candidate_bounds / --candidate-bound, or the effect is outside the physical range assumed). "
            + message)
    loose = [a for a in own if a not in widen]
    if loose and verdict in ("named", "ambiguous"):
        message += " " + "; ".join(f"{a['name']} = {a['value']:.4g} stopped at its {a['side']} bound {a['bound']:.4g}, "
                                   f"but relaxing it gains only LR {a['relax_lr']:.3g} ≤ {relax_thr:.3g}: the bound "
                                   "does not limit the fit" for a in loose) + "."
    # another candidate's bound matters only when, widened to its absolute bound, it competes with
    # the name: it closes the gap, or its LR comes within χ²₁(α) of the named model's
    lr_named = 2 * (res0.cost - final_fit.cost) if final_fit is not None else 0.0
    for c in {a["name"].split(".", 1)[0] for a in others_stuck}:
        mine = [a for a in others_stuck if a["name"].startswith(c + ".")]
        wide = {a["name"]: a["side"] for a in mine}
        fw = [replace(fp, **{wide[fp.name]: getattr(LIBRARY[c].parameter(fp.name.split(".", 1)[1]), wide[fp.name])})
              .with_initial(fits[c].values[fp.name]) if fp.name in wide else fp.with_initial(fits[c].values[fp.name])
              for fp in fits[c].free]
        say_v(f"widening the bound of {c} (a confusable candidate stopped there)")
        rw = fit(fw, identify=False)
        lr_w = 2 * (res0.cost - rw.cost)
        for a in mine:
            a["lr_widened"] = float(lr_w)
            a["competes"] = bool(gap.closes(bc(rw), [c]) or lr_w >= lr_named - relax_threshold(alpha))
    if verdict in ("named", "ambiguous") and any(a["competes"] for a in others_stuck):
        verdict = "at_bound"
        rival = [a for a in others_stuck if a["competes"]]
        message = ("At bound — a confusable candidate stopped at its bound and, widened, could compete with the "
                   "name: " + "; ".join(f"{a['name']} = {a['value']:.4g} at its {a['side']} bound {a['bound']:.4g} "
                                        f"(widened: LR {a['lr_widened']:.4g} vs the name's {lr_named:.4g})" for a in rival)
                   + " — widen it (candidate_bounds / --candidate-bound) before trusting the name. " + message)
        widen = widen + rival
    others_stuck = [a for a in others_stuck if not a["competes"]]
    if others_stuck and verdict in ("named", "ambiguous", "at_bound"):
        message += (" Noted, not a reason to doubt the name: the confusable candidate(s) " + "; ".join(
            f"{a['name']} = {a['value']:.4g} at its {a['side']} bound {a['bound']:.4g}" for a in others_stuck)
            + " stopped at a candidate bound without closing the gap; relaxing it could not let it compete "
            "with the name.")
    if verdict in ("named", "ambiguous", "at_bound"):
        message += reduced_sentence(reduced)
    if verdict == "unexplained" and final_effects:
        stuck = [a for c in final_effects for a in cres[c].at_bound if c in cres and a["status"] == "at"
                 and not a["hard"] and a["name"].startswith(c + ".")] if len(final_effects) == 1 else [
            a for a in at_bound if not a["hard"] and a["name"].split(".", 1)[0] in final_effects]
        if stuck:
            message += (" The best candidate ended at its bound (" + "; ".join(
                f"{a['name']} = {a['value']:.4g}, {a['side']} bound {a['bound']:.4g}" for a in stuck)
                + "): widen it — the effect may be larger than allowed.")
    # a sign flip: the baseline with its sign reversed, refitted, explains what the candidates leave
    flip: dict = {}
    resid_sig = final_fit is not None and not gap.strict(bc(final_fit), final_effects)
    if gap0_sig and (verdict in ("unexplained", "at_bound") or resid_sig):
        say_v("checking for a sign flip (the baseline with its sign reversed)")
        pneg = PenalisedProblem(data, lambda vals: -np.asarray(pm(vals)), prob.penalties)
        rflip = min((pneg.fit(from_(v0), seed=seed, max_nfev=max_nfev, identify=False, hold_undetermined=False),
                     pneg.fit(free0, seed=seed, max_nfev=max_nfev, identify=False, hold_undetermined=False)),
                    key=lambda x: x.cost)
        flip = sign_flip(pm([rflip.values])[0], data, s_ln, s_ph)
        cost_now = final_fit.metadata["data_cost"] if final_fit is not None else cost0
        flip["refit_cost"] = float(rflip.metadata["data_cost"])
        neg = partial(bc, residuals=lambda v: standardised_residuals(pneg.predict_many([v])[0], data, s_ln, s_ph))
        flip["recognised"] = bool(flip["refit_cost"] < cost_now and (
            gap.closes(neg(rflip), []) or flip["refit_cost"] < 0.1 * cost0))
        if flip["recognised"]:
            verdict, final_effects, final_fit, at_bound, widen = "unexplained", [], None, [], []
            message = (f"Sign flip: the data are the model with its sign reversed — a constant "
                       f"{flip['phase_offset_deg']:.0f}° phase offset over the band with the magnitude matching "
                       f"(RMS {flip['magnitude_rms_db']:.2g} dB): with the sign reversed the baseline refits to "
                       + (f"2·cost {2 * flip['refit_cost']:.4g} (gap threshold {gap.threshold_text()}; as given "
                          if gap.K == 1 else f"{gap.compare(neg(rflip))} (as given 2·cost ")
                       + f"{2 * cost0:.4g}). No physical effect is needed: check the polarity of the excitation or "
                       "the sensor wiring and the sign convention of the measured quantity, then rerun.")
    message += audit_notes(verdict, at_bound, widen, audit0, final_implausible, res0, cres)
    named = list(final_effects) if verdict in ("named", "ambiguous", "at_bound") else []
    if verdict == "ambiguous":
        named = named2 if named2 else amb
    if final_fit is not None:
        Gf = pm([final_fit.values])[0]
        n_free_after = len(final_fit.names)
    else:
        Gf, n_free_after = G0, k0
    rf = standardised_residuals(Gf, data, s_ln, s_ph)
    cost_f = float(0.5 * rf @ rf)
    warn = cost_warning(cost_f, N, n_free_after) if not estimated else ""
    if warn:
        message += f" Cost vs declared noise: {warn}."
    # each quantity's "does it fit" at the model file's goodness-of-fit level shared out over the
    # quantities (the pooled verdict's test, residuals.GOF_ALPHA), not at the detection α
    per_q = gap.annotate(jd.per_quantity(G0, Gf, k0, n_free_after, GOF_ALPHA), final_effects) if jd is not None else []
    pooled = gap.pooled_row(per_q, final_effects)      # the pooled gap test (gap.py), None for one quantity
    message += per_quantity_sentence(per_q, pooled) + (thin := thin_tail_note(tails, int(null_draws)))
    declare_confusable(confusable, separation, confusability, sigs, raw_sigs, data)
    say("audit", f"verdict {verdict}" + (f": {', '.join(named)}" if named else ""))
    fe = {c: {k.split(".", 1)[1]: final_fit.values[k] for k in final_fit.names if k.startswith(c + ".")}
          for c in final_effects} if final_fit is not None else {}
    return Diagnosis(
        verdict=verdict, named=named, message=message, kind=kind, quantity=q, alpha=alpha, threshold=T,
        gap_threshold=float(gap.thr0[0]) if gap.K == 1 else math.nan, baseline=res0, final=final_fit,
        final_effects=fe, candidates=cres,
        skipped=skipped, confusable=confusable, separation=separation, localisation_before=localise(data, r0, alpha),
        localisation_after=localise(data, rf, alpha), gap_before=gap_statistics(data, r0, k0),
        gap_after=gap_statistics(data, rf, n_free_after),
        null={"method": "linearised Gaussian null at the fitted baseline (constrained LR per candidate, "
                        "max over candidates) scaled by full-refit parametric bootstrap",
              "draws": int(null_draws), "refits": int(null_refits), "lr_threshold_linearised": T_lin,
              "nonlinearity_ratio": ratio, "bootstrap_full_max_lr": full_max, "bootstrap_lin_max_lr": lin_used,
              "alpha_gap": alpha_gap, "gap_test": gap.describe(pooled), "seed": seed, "tails": tails,
              "thin_tail": thin.strip()},
        noise_estimated=estimated, elapsed_s=time.perf_counter() - t0, data=data,
        predicted_before=G0, predicted_after=Gf,
        metadata={"base": base.name, "kernel": kernel, "free": names0, "baseline_effects": beff, "candidates": cand,
                  "quantities": list(qs), "acts_on": {k: list(v) for k, v in scope.items()},
                  "data_fingerprint": data.fingerprint(), "pairs_tried": pair_tried, "profile": counter.as_dict(),
                  "candidate_bounds": {c: {p.name: [p.lower, p.upper, p.typical] for p in cpars[c]} for c in cpars},
                  "prior": f"soft walls of {WALL_DECADES:g} decade outside the plausible ranges" if prior else "none"},
        laws=laws_note, baseline_audit=audit0, final_at_bound=at_bound, final_implausible=final_implausible,
        cost_warning=warn, confusability=confusability, base_parameters=base,
        reduced=reduced, sign_flip=flip, per_quantity=per_q, joint=jd,
    )


# =============================================================================== inputs
def _candidate_overrides(candidate_bounds, candidate_starts) -> tuple[dict, dict]:
    """``{"effect.param": (lo, hi) | {"lower"|"upper"|"typical": v}}`` → {effect: {param: {...}}};
    ``{"effect.param": value}`` → {effect: {param: value}}."""
    bounds: dict = {}
    for key, v in (candidate_bounds or {}).items():
        if "." not in key:
            raise ParameterError(f"candidate bound {key!r}: expected 'effect.parameter'")
        e, p = key.split(".", 1)
        get_effect(e).parameter(p)
        if isinstance(v, Mapping):
            spec = dict(v)
        else:
            try:
                lo, hi = (float(x) for x in v)
            except (TypeError, ValueError):
                raise ParameterError(f"candidate bound {key!r}: expected (lower, upper) or a table of "
                                     f"lower/upper/typical, got {v!r}") from None
            spec = {"lower": lo, "upper": hi}
        bounds.setdefault(get_effect(e).name, {})[p] = spec
    starts: dict = {}
    for key, v in (candidate_starts or {}).items():
        if "." not in key:
            raise ParameterError(f"candidate start {key!r}: expected 'effect.parameter'")
        e, p = key.split(".", 1)
        get_effect(e).parameter(p)
        try:
            starts.setdefault(get_effect(e).name, {})[p] = float(v)
        except (TypeError, ValueError):
            raise ParameterError(f"candidate start {key!r} = {v!r}: expected a number") from None
    return bounds, starts


def _hard_sides(cpars: dict) -> dict:
    """Bounds that are physical limits or the effect's off value (no reason to widen)."""
    out = {}
    for c, pars in cpars.items():
        for p in pars:
            sides = set(p.limits)
            if p.off == p.lower:
                sides.add("lower")
            if p.off == p.upper:
                sides.add("upper")
            out[f"{c}.{p.name}"] = tuple(sides)
    return out


__all__ = ["diagnose", "Diagnosis", "CandidateResult", "VERDICTS", "gap_shrink", "CONFUSABLE_COSINE",
           "PAIR_POOL"]
