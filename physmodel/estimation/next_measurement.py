"""The next measurement: which experiment would separate the models a diagnosis could not.

When :func:`~physmodel.estimation.discrepancy.diagnose` ends ``ambiguous`` (or ``at_bound`` with a
rival), the competing models each fit the record within its noise.  :func:`next_measurement`
searches the experiments the library can simulate — the measured quantity (actuator M, H, Z, I;
sensor S, Z), a frequency band on a log grid reaching below and above the measured band within
stated limits, a set of bath temperatures within the strip's range, and the excitation level — and
for each predicts both competing models' responses and the separation a record of it is expected to
give at the user's noise level.

Method (optimal design for model discrimination)
------------------------------------------------
Box & Hill (1967, Technometrics 9:57) proposed choosing the next experiment where rival models'
predictions differ most relative to the noise; Atkinson & Fedorov (1975, Biometrika 62:57, "the
design of experiments for discriminating between two rival models") made it precise as
*T-optimality*: when model A is true with parameters θ_A, the design should maximise

    λ_A(ξ) = min over θ_B of Σ_lines |η_A(x, θ_A) − η_B(x, θ_B)|² / σ²(x),

the noiseless χ² left when the rival B refits all its parameters to A's predictions — exactly
the non-centrality of the likelihood-ratio (and, for non-nested fits, of Vuong's z, mean ≈ √λ/2)
statistic that tells them apart.  Here the predictions are the standardised log-responses the
diagnosis fits (``ln|G|/σ_ln`` and ``∠G/σ_φ``, :mod:`~physmodel.estimation.residuals`), and the
minimisation is linearised at B's fit to the diagnosed record: with Δ = ln(G_A/G_B) per line and
J_B the Jacobian of ln G_B in B's free parameters (the user's base parameters and B's effect
parameters, central differences), λ_A = ‖(I − P_{J_B}) Δ‖²_W, W the diagonal weights 1/σ² of the
stacked lines.  A measurement of the diagnosed quantity is evaluated *together with* the diagnosed
record (the two are merged and diagnosed jointly; the rival refits to both); one of another
quantity alone.  A joint diagnosis (several quantities of one strip, :mod:`~physmodel.estimation.joint`)
is searched the same way with every experiment evaluated together with its whole record: a
measurement of one of its quantities is merged into that quantity's record, one of another
quantity is one more quantity diagnosed jointly; each keeps its own σ and the diagnosis's
``acts_on`` (:class:`~physmodel.estimation.next_measurement_design.RecordView`).  Since either model may be the true one the
criterion is min(λ_A, λ_B), and with several rivals the least over every pair of them (the
experiment must leave one standing, whichever is true).  A pair that no experiment separates even
linearised (λ < :data:`SAME_FORM_LAMBDA` everywhere: the same response in two forms) is said and
left out; so is one the nonlinear check below shows no experiment expected to separate it does
(nested forms: a single amplifier pole is an op-amp stage with a feedback capacitor), after which
the experiments are ranked again without it.  All candidate experiments are evaluated at once: the
responses and Jacobians are computed once on the union grid of each quantity, and each experiment
is a weight mask over it (batched normal equations).

Noise at the new lines: the diagnosed record's per-line σ_ln, σ_φ are regressed on |G| (log–log,
one slope b clipped to [−1, 0]: b = 0 is noise proportional to the signal, b = −1 a fixed
instrument floor, as the virtual lab's DAQ noise is); at a line where the model predicts |G| and at
excitation level a (a multiple of the record's drive) σ = σ_ref (|G|/|G_ref|)^b a^b.  Another
quantity is given the record's median relative σ (its instrument is not known): stated in the
result.  A joint record has one such noise model per quantity, and another quantity the median
over them.

Decision: the separation needed is λ* with Vuong power ``power`` at the diagnosis's α
(:func:`~physmodel.estimation.signatures.vuong_power`: z ~ N(√λ/2, 1), so λ* = 4(z_crit + Φ⁻¹(power))²).
Among the experiments reaching λ* and taking no longer than the diagnosed record did (duration ≈
number of temperatures × :data:`PERIODS` / lowest frequency, plus :data:`BATH_SETTLE_S` per new
bath temperature; or than the quickest that reaches λ*),
the recommendation is the one at the lowest drive level, then of the largest λ (the safest margin);
when none reaches λ*, the one of largest λ, with ``separates = False`` and the sentence saying so.  The linearised λ of the
recommendation (and of the next ones when it falls short) is then checked by a full nonlinear refit
of the rival to the true model's noiseless predictions (``separation_refit``), in rounds: a pair that
the refits show to be inseparable in every checked experiment expected to separate it leaves the
criterion and the experiments are ranked and checked again (at most one round per pair).

Two records: when no single experiment reaches λ* for every pair of several (two pairs that need different
quantities — contact resistance vs the diffusivity law in Z, a delay vs an amplifier pole in M above
the resonance), a second experiment is searched to add to the recommended one (greedy): the one
maximising the least over the pairs of the two records' λ, computed by stacking their
normal-equation sums (λ is not additive: the rival refits one set of parameters to both), none of
its lines the first's (:mod:`~physmodel.estimation.next_measurement_plan`); when that pair falls short
of λ* linearised, the plans started from each competing pair's own best record are searched too and
the one of largest λ taken (the first record then that pair's best, said).  When the two reach λ*
they are checked by full refits of the rivals to both records together, and recommended together
when the refits reach λ* too (``NextMeasurement.also``; ``separates`` then refers to both).  A
second record the refits refuse gives way to the next-best by linearised λ (at most
:data:`~physmodel.estimation.next_measurement_plan.MORE_SECOND_RECORDS` more, each checked, the
first confirmed taken); when none is confirmed, the checked pair of largest λ after the refits is
still recommended when it is above the best single record's own by more than
:data:`~physmodel.estimation.next_measurement_plan.SHORT_PLAN_GAIN` — ``separates`` False, the message and
``together["short"]`` saying what it reaches, the pairs short and by how much, and the remedies —
and otherwise not (said); when the two do not reach λ* linearised the single recommendation
stands, unchanged.

Temperatures: the search offers bath steps (a 5-point grid of the allowed range and its ends with
the middle) for every quantity the models predict at other temperatures through the parameter set's
laws — for a sensor the strip's Z moves with d(T), κe(T) and T, so an op-amp stage loaded by the
strip (``transimpedance``) moves with the bath while an amplifier pole does not.

Other forms of the fits: the linearisation is at the competing models' fits to the record, and a
fit may take a nested form of its rival (an op-amp stage fitted as ideal op-amps with a feedback
capacitor, i.e. one pole).  So when a pair comes out inseparable (linearised, or as fitted after the
refits) the search is run again with the other forms its models' fits take
(:mod:`~physmodel.estimation.next_measurement_forms`): each such model refitted to the record with
each effect parameter held at its off value in turn and from a multi-start (the diagnosis's candidate
fit, a log grid of the effect's parameters screened in one vectorised call); the optima whose
2Δcost to the best is within χ²_p(1 − α) (p the effect's parameters, α the diagnosis's: the record
cannot reject them) and that differ on the search grid are possible truths in every pair the model
is in.  Per direction the criterion is the least λ over the truth's forms, the rival linearised at
(and refitted from) each of its forms and its fit moved to the truth form's base values.  The two
fits of the pair found inseparable are the same response and are left to parsimony; so is any truth
form no experiment separates from the rival (linearised, or after the refits of every checked
experiment expected to separate it): a nested form is decided by parsimony, not by an experiment, and
the message and ``NextMeasurement.forms`` say which forms the separation assumes and which direction
parsimony decides.  Limits: the forms are those the starts reach (at most
:data:`~physmodel.estimation.next_measurement_forms.MAX_FORMS` more per model); the truth's own form
is near one of them, not equal to it, so a forecast near the target can still fall short (during
development, before the pair's two fits were left to parsimony, seed 7430 got λ 57 forecast at 35 °C,
2-210 Hz — the quickest experiment reaching the target — and stayed ambiguous where a bath step
forecast λ 1440); the refit check sees only the experiments it checks, so with Z searched too (the
three-way virtual-lab case) a form the S bath step would separate can be called nested on Z's
experiments and the pair stays inseparable as fitted (said so); and the search costs more where a
pair is inseparable (median CPU 6.4 s against 2.8 s on the opamp seeds of bench_next_measurement's
docstring, which measures the named-exactly rate: 12/12 and 10/10 on fresh seeds against main's
8/12 and 9/10).  Where no pair is inseparable the search is the one above, unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..data.sweep import FrequencySweep
from ..data.units import QUANTITY_UNITS
from ..errors import IPMCError
from .next_measurement_design import (
    FD_RELATIVE_STEP,
    REFIT_STARTS,
    RecordView,
    fit_competing_models,
    line_sigma,
    log_ratio,
    log_unit_factor,
    noise_model,
    refit_check,
    stack_real,
    t_criterion,
    t_solve,
    t_sums,
)
from .next_measurement_plan import PlanChoice, bath_premise, choose_plan, plan_message, record_base, refused_message
from .next_measurement_results import CandidateMeasurement, NextMeasurement, json_ready, merge_records
from .residuals import noise_std

#: Temperature range [°C] a hydrated strip is measured in by default (above freezing of the bath,
#: below where Nafion's water content falls off), intersected with the laws' own valid ranges.
DEFAULT_TEMPERATURE_LIMITS_C = (5.0, 65.0)
#: Bath limits above this are refused as kelvin typed for °C (the CLI's ``check_celsius`` bound). [°C]
MAX_BATH_C = 150.0
#: Frequency limits [Hz] of a candidate band by default (a 0.01 Hz line takes 100 s a period; the
#: single-mode beam and the DAQs of the scenarios end well below 1 kHz).
DEFAULT_BAND_LIMITS_HZ = (0.01, 1000.0)
#: Default excitation levels, as multiples of the diagnosed record's drive.
DEFAULT_LEVELS = (1.0, 2.0)
#: Measured periods per temperature assumed for a measurement's duration.
PERIODS = 10
#: Time a water bath takes to settle at a temperature the record was not measured at (a stated
#: choice: minutes for a stirred bath and a 0.2 mm strip), added to a measurement's duration. [s]
BATH_SETTLE_S = 600.0
#: A pair whose linearised separation stays below this in every experiment is the same response in
#: two forms (e.g. two amplifier poles and an op-amp stage's): said, and left out of the criterion.
SAME_FORM_LAMBDA = 1.0


# =============================================================================== competing models
def competing_models(d) -> list[tuple]:
    """The models an ``ambiguous`` / ``at_bound`` diagnosis ``d`` leaves competing: the best (its
    final effects) first, then each alternative — another named single effect, a pair with one member
    swapped for a named alternative declared confusable with it (or either member when no declaration
    says which), an ambiguous pair with both members swapped for such twins at once, or for
    ``at_bound`` a confusable candidate that stopped at its bound and, widened, competes (else the
    significant candidates that close the gap)."""
    final = tuple(d.final_effects) if d.final_effects else tuple(d.named[:1])
    if not final:
        return []
    alts: list[tuple] = []
    others = [c for c in d.named if c not in final]
    if d.verdict == "at_bound":
        others = [c for c, cr in d.candidates.items() if c not in final
                  and any(a.get("competes") for a in cr.at_bound)]
        if not others:
            others = [c for c, cr in d.candidates.items() if c not in final and cr.significant and cr.closes_gap]
    partner: dict = {}
    for x in d.confusability.get("pairs", []):
        partner.setdefault(x["other"], set()).add(x["top"])
    for a, b, _ in d.confusable:
        partner.setdefault(a, set()).add(b)
        partner.setdefault(b, set()).add(a)
    for c in others:
        if len(final) == 1:
            alts.append((c,))
            continue
        swap = [m for m in final if m in partner.get(c, ())] or list(final)
        for m in swap:
            alt = tuple(sorted([x for x in final if x != m] + [c]))
            if alt not in alts and set(alt) != set(final):
                alts.append(alt)
    # a pair whose members each have a named twin: both may stand for their twins at once (contact
    # resistance + delay vs the diffusivity law + an amplifier pole), not only one at a time
    if len(final) == 2 and d.verdict == "ambiguous":
        twins = [[c for c in others if m in partner.get(c, ()) and c not in final] for m in final]
        for a in twins[0]:
            for b in twins[1]:
                alt = tuple(sorted((a, b)))
                if a != b and alt not in alts:
                    alts.append(alt)
    return [final] + alts if alts else []



# =============================================================================== the search
def _skeleton(kind: str, q: str, f: np.ndarray, T: np.ndarray) -> FrequencySweep:
    """A sweep of ``q``'s units on the grid f × T (response placeholder 1) for the predictors."""
    in_name, unit_in, out_name, unit_out = QUANTITY_UNITS[(kind, q)]
    TT, FF = np.meshgrid(T, f, indexing="ij")
    return FrequencySweep(TT.ravel(), FF.ravel(), np.ones(FF.size, complex), None, None, in_name, unit_in,
                          out_name, unit_out)


def _band_windows(f_lo: float, f_hi: float, data_band: tuple) -> list[tuple]:
    """Candidate bands: the measured band, and windows of ½–2 decades with edges every ⅓ decade and at
    the limits ``f_lo``, ``f_hi`` (a limit off the ⅓-decade grid is an edge too, so a band can reach it)."""
    out = [tuple(data_band)]
    edges = 10 ** np.arange(math.floor(3 * math.log10(f_lo)) / 3, math.log10(f_hi) + 1e-9, 1 / 3)
    edges = np.unique(np.clip(np.append(edges, f_hi), f_lo, f_hi))
    for i, a in enumerate(edges):
        for b in edges[i + 1:]:
            w = math.log10(b / a)
            if 0.45 <= w <= 2.05:
                out.append((float(a), float(b)))
    return list(dict.fromkeys(out))


def _temperature_sets(data_T: np.ndarray, lo: float, hi: float) -> list[tuple]:
    """Candidate temperature sets: the record's, one each on a 5-point grid of the allowed range,
    and the range's ends with its middle."""
    sets = [tuple(float(t) for t in data_T)]
    if hi > lo:
        grid = np.linspace(lo, hi, 5)
        sets += [(float(t),) for t in grid]
        sets.append((float(lo), float(0.5 * (lo + hi)), float(hi)))
    elif not np.any(np.isclose(data_T, lo)):
        sets.append((float(lo),))
    return list(dict.fromkeys(sets))


def next_measurement(d, *, quantities: Sequence[str] | None = None,
                     band_limits_hz: tuple = DEFAULT_BAND_LIMITS_HZ, temperature_limits_c: tuple | None = None,
                     levels: Sequence[float] = DEFAULT_LEVELS, lines_per_decade: float | None = None,
                     power: float = 0.9, models: Sequence[tuple] | None = None, check_refit: int = 2,
                     max_nfev: int = 100, acts_on: Mapping[str, Sequence[str]] | None = None) -> NextMeasurement:
    """The experiment that best separates the models diagnosis ``d`` leaves competing (module doc).

    Parameters
    ----------
    d : Diagnosis
        An ``ambiguous`` or ``at_bound`` diagnosis (others have nothing to separate).
    quantities : sequence of str or None
        What may be measured (default: every quantity of ``d.kind`` the library simulates, M, H, Z,
        I or S, Z; a caller whose laboratory records one quantity passes just that).
    band_limits_hz : (float, float)
        The lowest and highest frequency any band may reach. [Hz]  Bands reach at most a decade
        below and above the record's.
    temperature_limits_c : (float, float) or None
        Bath temperatures allowed. [°C]  Default :data:`DEFAULT_TEMPERATURE_LIMITS_C` intersected
        with the laws' valid ranges; given limits are clipped to the laws' valid ranges (the message
        says so) and refused above :data:`MAX_BATH_C` (kelvin typed as °C).
    levels : sequence of float
        Excitation levels, multiples of the record's drive (cap them at what the strip takes). [-]
    lines_per_decade : float or None
        Line density of a new record (default: the record's).
    power : float
        Vuong-test power the separation must reach.
    models : sequence of tuple or None
        The competing models (effect names each, the best first; default :func:`competing_models`).
    check_refit : int
        How many of the preferred experiments to check by nonlinear refits of the rivals, in order,
        until one reaches the target; two records are checked together as well (0: none, and two
        records are then recommended on their linearised λ, ``together["linearised_only"]``).
    max_nfev : int
        Function evaluations of each refit.
    acts_on : mapping or None
        A one-quantity record only: ``{effect: [quantities]}``, where an effect acts among the
        quantities a new record may measure (each list including the record's own), as
        ``diagnose``'s ``acts_on`` for a joint record — e.g. ``{"time_delay": ["M"]}`` when the
        displacement channel carries the delay and Z is measured by another instrument; on a
        quantity not listed the effect is held at its off values in the predictions (default: every
        effect acts on every quantity it applies to).  A joint diagnosis carries its own.
    """
    from scipy.stats import norm

    from .signatures import vuong_critical

    if d.verdict not in ("ambiguous", "at_bound"):
        raise IPMCError(f"next_measurement: the diagnosis is {d.verdict!r}; only an ambiguous or at-bound "
                        "verdict leaves models to separate")
    if d.base_parameters is None:
        raise IPMCError("next_measurement: the diagnosis does not carry its base parameters; rerun diagnose")
    if isinstance(power, bool) or not isinstance(power, (int, float, np.integer, np.floating)) \
            or not 0.5 <= power < 1:
        raise IPMCError(f"power={power!r}: expected a number in [0.5, 1)")
    lv = np.asarray(sorted(set(float(x) for x in levels)), float)
    if lv.size == 0 or np.any(~np.isfinite(lv)) or np.any(lv <= 0):
        raise IPMCError(f"levels={list(levels)!r}: give positive multiples of the record's drive")
    kinds = [q for k, q in QUANTITY_UNITS if k == d.kind and q != "G"]
    qs = list(quantities) if quantities is not None else kinds
    bad = [q for q in qs if q not in kinds]
    if bad:
        raise IPMCError(f"quantities {bad}: a {d.kind} has {kinds}")
    z_crit = vuong_critical(d.alpha)
    target = 4.0 * (z_crit + float(norm.ppf(power))) ** 2
    mods = list(models) if models is not None else competing_models(d)
    nm = noise_model(d)
    view = RecordView(d, acts_on)
    assumed = {e: list(q) for e, q in {**view.acts_on, **view.new_acts_on}.items()}
    acts_note = (" It assumes " + "; ".join(f"{e} acts on {', '.join(q)} only" for e, q in sorted(assumed.items()))
                 + " (acts_on)." if assumed else "")
    if len(mods) < 2:
        return NextMeasurement([tuple(m) for m in mods], None, False, target, 0.0, 0, [], nm, {},
                               "No competing model to separate: the diagnosis names no rival "
                               + ("(widen the bound it stopped at instead)." if d.verdict == "at_bound" else ".")
                               + acts_note, acts_on=assumed)
    fitted = fit_competing_models(d, mods, max_nfev)
    opts: dict[str, Any] = dict(mods=mods, qs=qs, lv=lv, band_limits_hz=band_limits_hz, temperature_limits_c=temperature_limits_c,
                lines_per_decade=lines_per_decade, power=power, check_refit=check_refit, max_nfev=max_nfev,
                z_crit=z_crit, target=target, nm=nm, view=view)
    out = _search(d, fitted, None, **opts)
    assert out is not None          # None only when other forms are given
    def said(r: NextMeasurement) -> str:
        """``r``'s message with the acts_on premise and, for a forecast separation, its form premise."""
        return r.message + acts_note + (" " + FORMS_PREMISE if r.separates else "")

    out.acts_on, out.message = assumed, said(out)
    if not out.inseparable:
        return out
    # a pair inseparable as fitted: the search again, with the other forms its models' fits may take
    from .next_measurement_forms import alternative_forms

    alts = {}
    for m in fitted:
        if any(" + ".join(m.effects) in k.split(" vs ") for k in out.inseparable):
            found = alternative_forms(d, m, max_nfev)
            if len(found) > 1:
                alts[id(m)] = found
    again = _search(d, fitted, alts, first_inseparable=list(out.inseparable), **opts) if alts else None
    if again is None:       # no other form, or every other form the same response as the fit
        out.forms = {"tried": sorted(" + ".join(m.effects) for m in fitted
                                     if any(" + ".join(m.effects) in k.split(" vs ") for k in out.inseparable)),
                     "found": {}, "note": FORMS_NONE}
        out.message += " " + FORMS_NONE
        return out
    again.acts_on, again.message = assumed, said(again)
    return again


#: Said with every forecast separation: its premise, and how often it held where the truth's form was
#: not the library's (``tests/benchmarks/bench_next_measurement.py``, fresh blocks 52000-53800).
FORMS_PREMISE = ("The forecast takes one of the competing models as the strip's exact form; a form the library "
                 "does not have (a DAC's zero-order hold beside a delay, say) can leave the new records ambiguous "
                 "or misnamed, so read the verdict of the records diagnosed together, not this forecast (on an "
                 "independently written generator's two-effect strips, 23 of 34 forecast separations ended "
                 "named exactly).")

#: Said when a pair is inseparable as fitted and its models fit the record in no other form.
FORMS_NONE = ("Other forms tried: the models of the pairs not separated fit the record in no other form within its "
              "noise (each effect parameter held at its off value, and a multi-start over the effect's own "
              "parameters), so none is searched.")


def _search(d, fitted: list, alts: dict | None, *, mods, qs, lv, band_limits_hz, temperature_limits_c,
            lines_per_decade, power, check_refit, max_nfev, z_crit, target, nm, view,
            first_inseparable: Sequence[str] = ()) -> NextMeasurement | None:
    """The search of :func:`next_measurement` over its ``fitted`` competing models; ``alts``
    (``id(model) -> [(form, cost), ...]``, the fit first, :func:`~physmodel.estimation.next_measurement_forms.alternative_forms`)
    the other forms each model's fit may take, searched as possible truths in every pair it is in;
    ``first_inseparable`` the pairs the search without them found inseparable (their fits are the
    same response: left to parsimony, only their other forms searched).  None when ``alts`` is
    given but no model keeps a form distinct from its fit (nothing new to search)."""
    from .signatures import vuong_power

    label = lambda m: " + ".join(m.effects)  # noqa: E731
    # ---- the record itself (the part every joint experiment shares)
    s_ln0, s_ph0, _ = noise_std(d.data)
    w0 = np.concatenate([1 / s_ln0 ** 2, 1 / s_ph0 ** 2])
    rec = {}
    for m in fitted:
        rec[id(m)] = m.log_response_of(view.record_many(m.model))
    # ---- candidate grids
    f_data = d.data.frequency_hz
    T_data = d.data.temperatures()
    fmin, fmax = float(f_data.min()), float(f_data.max())
    n_per_T = f_data.size / max(T_data.size, 1) / len(view.sweeps)
    lpd = lines_per_decade or max(n_per_T / max(math.log10(fmax / fmin), 0.5), 5.0)
    f_lo = max(band_limits_hz[0], fmin / 10.0)
    f_hi = min(band_limits_hz[1], fmax * 10.0)
    if not f_lo < f_hi:
        raise IPMCError(f"band_limits_hz={band_limits_hz!r} leave no band near the record's {fmin:g}–{fmax:g} Hz")
    t_lo, t_hi, t_note = _temperature_limits(temperature_limits_c, d.base_parameters)
    f_grid = np.geomspace(f_lo, f_hi, max(int(round(lpd * math.log10(f_hi / f_lo))) + 1, 2))
    windows = _band_windows(f_lo, f_hi, (fmin, fmax))
    tsets = _temperature_sets(T_data, t_lo, t_hi)
    T_grid = np.unique(np.concatenate([np.asarray([t for s in tsets for t in s]), T_data]))
    rows: list[CandidateMeasurement] = []
    sums: dict = {}             # pair -> direction -> [t_sums per (quantity, level) block]: a second record
    pairs = [(a, b) for i, a in enumerate(fitted) for b in fitted[i + 1:]]     # every pair must separate
    key = lambda a, b: f"{label(a)} vs {label(b)}"  # noqa: E731
    contests, forms_resp, forms_said = ({}, {}, {}) if not alts else \
        _contests(d, fitted, alts, pairs, key, label, qs, f_grid, T_grid, nm, view, first_inseparable)
    if alts and not contests:
        return None
    for c in contests.values():          # the forms' and re-based rivals' responses on the record
        for m in c.models():
            if id(m) not in rec:
                rec[id(m)] = m.log_response_of(view.record_many(m.model))
    # the criterion on the record alone
    current = math.inf
    for a, b in pairs:
        La, Ja = rec[id(a)]
        Lb, Jb = rec[id(b)]
        D = stack_real(log_ratio(La, Lb))
        lam_a = t_criterion(D, stack_real(Jb), w0[None, :])[0]
        lam_b = t_criterion(-D, stack_real(Ja), w0[None, :])[0]
        current = min(current, lam_a, lam_b)
    for q in qs:
        sk = _skeleton(d.kind, q, f_grid, T_grid)
        resp = {id(m): m.log_response_of(view.many(m.model, sk, q)) for m in fitted}
        resp.update(forms_resp.get(q, {}))
        rs = view.sweeps.get(q)               # the record of this quantity, if any: the new lines merge with it
        same = rs is not None
        together = same or view.joint         # evaluated with the record (merged, or one more quantity of a joint one)
        logabs = resp[id(fitted[0])][0].real + (log_unit_factor(rs, sk) if same else 0.0)   # in the record's units
        sl, sp = line_sigma(nm["by_quantity"][q] if view.joint and same else nm, logabs, lv, same)   # (n_levels, N)
        if same:
            T_q, fmin_q, fmax_q = rs.temperatures(), float(rs.frequency_hz.min()), float(rs.frequency_hz.max())
        # masks: experiment e = (window, temperature set) × level
        masks, meta, seen = [], [], set()
        for (a, b) in windows:
            fm = (sk.frequency_hz >= a * (1 - 1e-9)) & (sk.frequency_hz <= b * (1 + 1e-9))
            for ts in tsets:
                m_ = fm & np.isin(sk.temperature_c, ts)
                if same:        # merged with the record: no line inside its band at its temperatures
                    m_ &= ~(np.isin(sk.temperature_c, T_q) & (sk.frequency_hz >= fmin_q * (1 - 1e-9))
                            & (sk.frequency_hz <= fmax_q * (1 + 1e-9)))
                mkey = m_.tobytes()
                if m_.sum() < 2 or mkey in seen:      # bands clipped to the same lines are one experiment
                    continue
                seen.add(mkey)
                masks.append(m_)
                meta.append(((a, b), ts))
        if not masks:
            continue
        M = np.asarray(masks, float)                           # (n_exp, N)
        by_pair: list = [dict() for _ in range(len(lv) * M.shape[0])]
        for a, b in pairs:
            if key(a, b) in contests:              # searched with its models' forms
                for i, _ in enumerate(lv):
                    W = np.hstack([M / sl[i] ** 2, M / sp[i] ** 2])
                    for e, v in enumerate(contests[key(a, b)].linearise(resp, rec if together else None, W, w0)):
                        by_pair[i * M.shape[0] + e][key(a, b)] = v
                continue
            La, Ja = resp[id(a)]
            Lb, Jb = resp[id(b)]
            D = stack_real(log_ratio(La, Lb))
            base_ab = base_ba = None
            if together:
                base_ab, base_ba = record_base(rec[id(a)], rec[id(b)], w0)
            for i, _ in enumerate(lv):
                W = np.hstack([M / sl[i] ** 2, M / sp[i] ** 2])
                sa, sb = t_sums(D, stack_real(Jb), W), t_sums(-D, stack_real(Ja), W)
                la, lb = t_solve(sa, base_ab), t_solve(sb, base_ba)
                for nme, s_ in ((f"{label(a)} true", sa), (f"{label(b)} true", sb)):   # kept for a second record
                    sums.setdefault(key(a, b), {}).setdefault(nme, []).append(s_)
                for e in range(M.shape[0]):
                    by_pair[i * M.shape[0] + e][f"{label(a)} vs {label(b)}"] = {
                        f"{label(a)} true": float(la[e]), f"{label(b)} true": float(lb[e])}
        for i, level in enumerate(lv):
            for e, (_, ts) in enumerate(meta):
                on = M[e] > 0
                fl = np.unique(sk.frequency_hz[on])
                rows.append(CandidateMeasurement(q, (float(fl.min()), float(fl.max())), tuple(ts), float(level),
                                                 int(M[e].sum()), fl, math.inf, by_pair[i * M.shape[0] + e],
                                                 together, len(ts) * PERIODS / float(fl.min())
                                                 + BATH_SETTLE_S * int(np.sum(~np.isin(ts, T_data))), 0.0,
                                                 line_temperatures_c=sk.temperature_c[on],
                                                 line_frequencies_hz=sk.frequency_hz[on],
                                                 added_quantity=together and not same))
    if not rows:
        raise IPMCError("next_measurement: no candidate experiment within the limits")
    sums = {k: {n: tuple(np.concatenate(x) for x in zip(*v)) for n, v in d_.items()} for k, d_ in sums.items()}
    # a pair that no experiment separates even linearised (the same response in another form) is
    # said, and left out of the criterion: the others can still be told apart
    for c in contests.values():
        c.settle_linearised(rows)
    best_pair = {k: max(min(r.separation_by_pair[k].values()) for r in rows) for k in rows[0].separation_by_pair}
    same_form = [k for k, v in best_pair.items() if v < SAME_FORM_LAMBDA]
    by_id = {id(r): r for r in rows}
    checked: list = []
    same_refit: list = []
    # the nonlinear check (the linearised λ overstates what a rival can reach after a full refit), in
    # rounds: a pair the refits show to be the same response in another form leaves the criterion,
    # the experiments are ranked again without it and the new preferred ones checked (otherwise one
    # such pair — two nested forms, or a linearisation error on a quantity that cannot see the
    # effects — ranks every experiment near 0 and the check lands on one that separates nothing)
    for _ in range(max(len(pairs), 1) + sum(len(t) for c in contests.values() for _, t, _ in c.directions)):
        gone = same_form + same_refit
        for c in contests.values():
            c.apply(rows)
        for r in rows:
            vals = [min(v.values()) for k, v in r.separation_by_pair.items() if k not in gone]
            r.separation = float(min(vals)) if vals else 0.0
            r.power = vuong_power(r.separation, z_crit)
        live = [(a, b) for a, b in pairs if key(a, b) not in gone]
        ranking = sorted(rows, key=lambda r: -r.separation)
        # among those reaching the target: within the time budget (the record's own duration, or the
        # quickest that reaches it), the lowest drive, then the largest separation (the safest margin)
        ok = [r for r in rows if r.separation >= target]
        budget = max(T_data.size * PERIODS / fmin, min((r.duration_s for r in ok), default=0.0))
        ok = sorted((r for r in ok if r.duration_s <= budget * (1 + 1e-9)), key=lambda r: (r.level, -r.separation))
        order = ok or ranking
        # the preferred experiment, then the one of largest linearised λ, then the next preferred ones
        to_check = [rid for rid in dict.fromkeys([id(r) for r in order[:1] + ranking[:1] + order[1:]])
                    if not any(id(c) == rid for c in checked)]
        for rid in to_check[:max(check_refit, 0) if live else 0]:
            r = by_id[rid]
            r.refit_by_pair = refit_check(d, [p for p in live if key(*p) not in contests], r, nm, max_nfev, label, view)
            r.refit_by_pair.update({key(*p): contests[key(*p)].check(d, r, nm, max_nfev, view) for p in live
                                    if key(*p) in contests})
            checked.append(r)
        # a pair is the same response in another form here when every checked experiment expected
        # (linearised) to separate it does not after the refits — one that was not expected to says nothing
        new_same, new_parsimony = [], False
        for a, b in live:
            k = key(a, b)
            if k in contests:      # a truth form the refits do not separate is left to parsimony
                c = contests[k]
                new_parsimony |= c.settle_refits(checked)
                if not c.live():
                    new_same.append(k)
                else:
                    for r in checked:
                        r.refit_by_pair[k] = c.refit_value(id(r))
                continue
            judged = [r for r in checked if k in r.refit_by_pair
                      and min(r.separation_by_pair[k].values()) >= SAME_FORM_LAMBDA]
            if judged and all(r.refit_by_pair[k] < SAME_FORM_LAMBDA for r in judged):
                new_same.append(k)
        same_refit += new_same
        if not new_same and not new_parsimony:
            break
    live = [(a, b) for a, b in pairs if key(a, b) not in same_form + same_refit]
    for r in checked:
        vals = [v for k, v in r.refit_by_pair.items() if k not in same_refit]
        # NaN (a refit that gave no λ: not separated) whatever the pairs' order — min() kept it only first
        r.separation_refit = float("nan") if any(v != v for v in vals) else float(min(vals)) if vals else 0.0
    done = {id(r) for r in checked}
    good = [r for r in order if id(r) in done and r.separation_refit >= target] \
        or [r for r in checked if r.separation_refit >= target]
    chosen = good[0] if good else (max(checked, key=lambda r: r.separation_refit) if checked else order[0])
    sep_ok = bool(live) and chosen.separation >= target and (not checked or chosen.separation_refit >= target)
    lam_said = chosen.separation_refit if math.isfinite(chosen.separation_refit) else chosen.separation
    pick = PlanChoice(target=target)     # no single experiment reaches the target: a second one with it (next_measurement_plan)
    # one pair: more data of one kind, said as 'lower the noise' (as before); a first record whose linearised λ
    # reaches the target but whose refits do not: the linearisation is not to be built on (no second record)
    if len(live) > 1 and not sep_ok and chosen.separation < target:
        bases = {key(a, b): dict(zip((f"{label(a)} true", f"{label(b)} true"), record_base(rec[id(a)], rec[id(b)], w0)))
                 for a, b in live}
        short = {k: max(0.0, min(chosen.separation_by_pair[k].values()) - v)
                 for k, v in chosen.refit_by_pair.items() if math.isfinite(v) and k in chosen.separation_by_pair}
        pick = choose_plan(d, chosen, rows, sums, bases, live, short, target, check_refit, nm, max_nfev, label, view)
    plan, plan_short = pick.plan, pick.refused
    who = " vs ".join(" + ".join(m) for m in mods)
    alike = _inseparable_note(same_form, same_refit, bool(contests))
    if not live:
        sep_ok = False
        msg = (f"No experiment within the limits can separate {who}.{alike}" if not same_refit else
               f"No experiment within the limits is expected to separate {who} as they were fitted.{alike}")
    elif sep_ok:
        msg = (f"Next measurement to separate {who}: {chosen.describe()} — expected separation λ = {lam_said:.3g} "
               f"(≥ {target:.3g} needed for {power:.0%} power at α = {d.alpha:g}; the record alone gives "
               f"{current:.3g}).{alike}")
    elif plan is not None:
        sep_ok = not pick.short
        chosen = pick.first or chosen       # the plan may start from a pair's own best record (issue 27)
        if plan.second.joint and not chosen.joint:    # the pair's λ counts the record: the first joins it too
            chosen = replace(chosen, joint=True, added_quantity=True)
        msg = plan_message(pick, chosen, who, power, d.alpha, shortfall(chosen)[1], current) + alike
    else:
        lam_low, lam_words = shortfall(chosen)
        msg = (f"No experiment within the limits is expected to separate {who} at the noise of this record: the "
               f"best, {chosen.describe()}, gives λ = {lam_words} < {target:.3g} needed (the record alone "
               f"{current:.3g}); lower the noise (more periods"
               + (f": λ grows in proportion to the periods averaged, so about {math.ceil(target / lam_low)}× "
                  "as many" if 0 < lam_low < target else "")
               + f"), widen the limits, or accept the ambiguity.{alike}")
        if plan_short is not None:       # two records reached the target linearised, not after the refits
            msg += refused_message(pick, shortfall(chosen)[1])
    forms: dict = {}
    if contests:
        msg += _forms_note(forms_said, contests, d.alpha)
        forms = {"found": forms_said, "contests": {k: c.describe(
            lambda f: {k2: v for k2, v in f.values.items() if "." in k2}) for k, c in contests.items()},
            "note": _forms_note(forms_said, contests, d.alpha).strip()}
    premise = bath_premise([chosen] + ([plan.second] if plan is not None else []), T_data, d.base_parameters)
    msg += t_note + (" " + premise if premise else "")
    return NextMeasurement([tuple(m) for m in mods], chosen, bool(sep_ok), target, float(current), len(rows),
                           ranking[:10], nm, {label(m): m.values for m in fitted}, msg, same_form + same_refit,
                           {q: max(r.separation for r in rows if r.quantity == q) for q in qs
                            if any(r.quantity == q for r in rows)}, list(same_refit), premise, forms,
                           also=[plan.second] if plan is not None else [], together=pick.together())


def _contests(d, fitted, alts, pairs, key, label, qs, f_grid, T_grid, nm, view, first_inseparable=()) -> tuple:
    """The pairs searched with their models' forms (every pair a model with other forms is in):
    ``({"A vs B": FormContest}, {q: {id(form): log-response on the search grid}}, {label: [form
    summaries]})``; a form whose response on the whole grid is within :data:`SAME_FORM_LAMBDA` of one
    kept is not kept (:func:`~physmodel.estimation.next_measurement_forms.distinct`)."""
    from .next_measurement_forms import FormContest, distinct, form_summary, form_threshold

    resp: dict = {q: {} for q in qs}
    by_q = nm.get("by_quantity", {})       # a joint record: each diagnosed quantity its own σ
    w = [(1.0 / by_q.get(q, nm)["median_ln"] ** 2, 1.0 / by_q.get(q, nm)["median_ph"] ** 2) for q in qs]
    kept, said = {}, {}
    for m in fitted:
        found = alts.get(id(m))
        if not found:
            continue
        by_form = []
        for f, _ in found:
            r_f = []
            for q in qs:
                L = f.log_response_of(view.many(f.model, _skeleton(d.kind, q, f_grid, T_grid), q))
                resp[q][id(f)] = L
                r_f.append(L[0])
            by_form.append(r_f)
        keep = distinct([f for f, _ in found], by_form, w, SAME_FORM_LAMBDA)
        if len(keep) < 2:        # every other form is the fit's own response: nothing new to search
            continue
        kept[id(m)] = [found[j][0] for j in keep]
        best = min(c for _, c in found)
        thr = form_threshold(d.alpha, len(m.free) - len(d.baseline.free))
        said[label(m)] = [form_summary(label(m), f, c, best, thr, "the fit to the record" if j == 0 else
                                       "another form that fits" if j in keep else "the same response as a kept form")
                          for j, (f, c) in enumerate(found)]
    contests = {}
    base_names = [fp.name for fp in d.baseline.free]
    for a, b in pairs:
        if id(a) in kept or id(b) in kept:
            fa, fb = kept.get(id(a), [a]), kept.get(id(b), [b])
            contests[key(a, b)] = FormContest(key(a, b), [(f"{label(a)} true", fa, fb), (f"{label(b)} true", fb, fa)],
                                              base_names, SAME_FORM_LAMBDA, key(a, b) in first_inseparable)
    for c in contests.values():      # the re-based rivals' responses on the search grid
        for m in c.models():
            for q in qs:
                if id(m) not in resp[q]:
                    resp[q][id(m)] = m.log_response_of(view.many(m.model, _skeleton(d.kind, q, f_grid, T_grid), q))
    for q in qs:                     # the fits' own responses are the search's
        for m in fitted:
            resp[q].pop(id(m), None)
    return contests, resp, said


def shortfall(r) -> tuple[float, str]:
    """The separation of experiment ``r`` that falls short and its words: an experiment separates only
    when its linearised λ and, where checked, the refits' both reach the target, so the lesser of the
    two is the one said (with the other where they differ by more than 10 %)."""
    lin, ref = float(r.separation), float(r.separation_refit)
    if not math.isfinite(ref):
        return lin, f"{lin:.3g}"
    if ref <= lin:
        return ref, f"{ref:.3g} after the refits" + (f" ({lin:.3g} linearised)" if lin > 1.1 * ref else "")
    return lin, f"{lin:.3g} linearised" + (f" ({ref:.3g} after the refits)" if ref > 1.1 * lin else "")


def _forms_note(said: dict, contests: dict, alpha: float) -> str:
    """The message's sentence on the forms searched and the directions left to parsimony."""
    other = []
    for lab, fs in said.items():
        for f in fs:
            if f["role"] == "another form that fits":
                vals = ", ".join(f"{k.split('.', 1)[1]}={v:.3g}" for k, v in f["effect_values"].items())
                other.append(f"{lab} as {vals} (2Δcost {f['delta_chi2']:.2g} ≤ {f['threshold']:.3g})")
    out = (" Searched with other forms of the fits (a pair was not separated as fitted) that the record cannot "
           f"reject (2Δcost to the best within the χ² quantile at α = {alpha:g} for the effect's parameters): "
           + "; ".join(other) + "; the separation assumes any form that fits may be the truth (the least λ over "
           "them, the rival refitting from each of its forms).")
    nested = []
    for k, c in contests.items():
        for name, truths, _ in c.directions:
            ex = c.excluded[name]
            if ex and len(ex) == len(truths):
                nested.append(f"{name} in {k} (every form of it a nested form of the rival)")
            elif ex:
                nested.append(f"{name} in {k} in {len(ex)} of its {len(truths)} forms (nested in the rival)")
    if nested:
        out += (" Decided by parsimony, not by the experiment (no experiment separates a nested form from the "
                "model that nests it; should the truth be that form, the simpler model is the name): "
                + "; ".join(nested) + ".")
    return out


def _inseparable_note(same_form: list, same_refit: list, forms_searched: bool = False) -> str:
    """The message's sentence on the pairs left out: ``same_form`` no experiment separates even
    linearised (the same response in another form), ``same_refit`` the refits of the checked
    experiments did not separate as the models were fitted (one fit a nested form of the other: the
    truth's own form may still separate — unless ``forms_searched``: the models' other forms that fit
    were searched too)."""
    out = ""
    if same_form:
        out += (" Not separable within the limits (the same response in another form; linearised λ below "
                f"{SAME_FORM_LAMBDA:g} in every experiment): " + "; ".join(same_form) + ".")
    if same_refit:
        out += (" Not separated as fitted (one model's fit is a nested form of the other: λ after refits below "
                f"{SAME_FORM_LAMBDA:g} in every checked experiment expected to separate it) — "
                + ("nor in the other forms of the fits that the record cannot reject (below): " if forms_searched else
                   "may separate in another form, which this search, linearised at the fits, does not try: ")
                + "; ".join(same_refit) + ".")
    return out


def temperature_premise(r, record_temperatures_c, base) -> str:
    """The premise of a recommended experiment ``r`` that steps the bath away from the record's
    temperatures: its separation is predicted through the diagnosed model's temperature laws (those
    of ``base``, named), so a misfit at the new temperature may mean the laws, not the effect, are
    wrong.  Empty when ``r`` (or its temperatures) stays at the record's.  Two records:
    :func:`~physmodel.estimation.next_measurement_plan.bath_premise`."""
    return bath_premise([r], record_temperatures_c, base)



def _laws_valid_range(base) -> tuple:
    """The intersection of every non-constant temperature law's valid range. [°C]"""
    from dataclasses import fields

    lo, hi = -273.15, math.inf
    laws = getattr(base, "laws", None)
    for f in fields(laws) if laws is not None else ():
        law = getattr(laws, f.name)
        if type(law).__name__ != "Constant" and hasattr(law, "valid_c"):
            lo, hi = max(lo, float(law.valid_c[0])), min(hi, float(law.valid_c[1]))
    return lo, hi


def _law_range(base) -> tuple:
    """:data:`DEFAULT_TEMPERATURE_LIMITS_C` intersected with every non-constant law's valid range."""
    lo, hi = _laws_valid_range(base)
    return max(DEFAULT_TEMPERATURE_LIMITS_C[0], lo), min(DEFAULT_TEMPERATURE_LIMITS_C[1], hi)


def _temperature_limits(limits, base) -> tuple[float, float, str]:
    """The bath limits searched (default :func:`_law_range`) and a note for the message: given limits
    above :data:`MAX_BATH_C` are refused (kelvin typed as °C); limits outside the laws' valid range are
    clipped to it (the models are not trusted beyond it) and the note says so."""
    if limits is None:
        lo, hi = _law_range(base)
        return lo, hi, ""
    try:
        t_lo, t_hi = (float(x) for x in limits)
    except (TypeError, ValueError):
        raise IPMCError(f"temperature_limits_c={limits!r}: expected two numbers (lower, upper) in °C") from None
    if not (math.isfinite(t_lo) and math.isfinite(t_hi)):
        raise IPMCError(f"temperature_limits_c={limits!r}: expected finite temperatures in °C")
    if t_lo > t_hi:
        raise IPMCError(f"temperature_limits_c={limits!r}: lower above upper")
    if t_hi > MAX_BATH_C or t_lo <= -273.15:
        raise IPMCError(f"temperature_limits_c={limits!r}: outside (-273.15, {MAX_BATH_C:g}] °C where a hydrated "
                        "IPMC works — kelvin? Temperatures are in °C (subtract 273.15)")
    v_lo, v_hi = _laws_valid_range(base)
    c_lo, c_hi = max(t_lo, v_lo), min(t_hi, v_hi)
    if c_lo > c_hi:
        raise IPMCError(f"temperature_limits_c={limits!r}: no temperature within the temperature laws' valid "
                        f"range {v_lo:g}–{v_hi:g} °C")
    if (c_lo, c_hi) == (t_lo, t_hi):
        return t_lo, t_hi, ""
    return c_lo, c_hi, (f" Bath limits {t_lo:g}–{t_hi:g} °C clipped to {c_lo:g}–{c_hi:g} °C, the temperature "
                        "laws' valid range.")



__all__ = ["CandidateMeasurement", "NextMeasurement", "competing_models", "json_ready", "merge_records",
           "next_measurement", "shortfall", "temperature_premise", "MAX_BATH_C",
           "PERIODS", "BATH_SETTLE_S", "SAME_FORM_LAMBDA", "REFIT_STARTS", "FD_RELATIVE_STEP",
           "DEFAULT_BAND_LIMITS_HZ", "DEFAULT_LEVELS", "DEFAULT_TEMPERATURE_LIMITS_C"]
