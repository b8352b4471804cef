"""A second record when no single one separates every competing pair (issue 27).

:func:`~physmodel.estimation.next_measurement.next_measurement` searches ONE experiment maximising
the least separation λ over the competing pairs.  When two pairs need different quantities (contact
resistance vs the diffusivity law separate in Z; a time delay vs an amplifier pole in M above the
resonance) no single experiment reaches the target for every pair, and the least over the pairs
picks a record that separates none.  Then a SECOND experiment is searched to add to the best single
one (greedy): the one maximising the least over the pairs of the two records' combined λ.
The best single record may be a compromise that separates no pair, and then no second record lifts
every pair with it; so when the greedy plan falls short of the target linearised, the plans whose
first record is each pair's own best (:func:`first_records`) are searched too, each with its best
second record, and the one of largest λ is taken (:func:`choose_plan`; issue 27 item 3: seeds 50676,
50679, 51277, 51282 of bench_next_measurement, a greedy λ of 13.7, 13.5, 1.9, 0.38, from a pair's
best record 1420, 3120, 198, 114, the target 42).

Combined λ.  The linearised T-criterion of an experiment is λ = min_δ Σ w |Δ − Jδ|² over the rival's
parameters δ (:func:`~physmodel.estimation.next_measurement_design.t_criterion`).  For independent
records the weighted sums of squares add, but the rival refits ONE δ to both: λ(e₁ ∪ e₂) = min_δ
[Q₁(δ) + Q₂(δ)] ≥ min Q₁ + min Q₂ = λ(e₁) + λ(e₂), with equality only when the two records ask the
same δ of the rival.  So λ is not additive (it is super-additive; and a record evaluated together
with the diagnosed one counts that record in each λ, which a sum would count twice): the combined λ
is computed by stacking — the two experiments' normal-equation sums
(:func:`~physmodel.estimation.next_measurement_design.t_sums`) added, with the diagnosed record's once
when either is evaluated together with it (then all three are diagnosed together: a record of the
same quantity merged, another quantity jointly), and solved
(:func:`~physmodel.estimation.next_measurement_design.t_solve`).

Not overlapping: a second record of the first's quantity holds none of its lines (temperature and
frequency, whatever the drive level).  The pair is recommended only when it reaches the target
where the best single experiment does not, linearised and then after full nonlinear refits
(:func:`refit_plan`, 2026-11-27): for each competing pair each model in turn is the truth and the
rival is refitted to its noiseless predictions on BOTH records together (with the diagnosed
record's lines when they are evaluated with it), from the starts the single-record check uses (the
rival's own fit, its effect at its typical size, :data:`~physmodel.estimation.next_measurement_design.REFIT_STARTS`),
the least over the two directions (:func:`~physmodel.estimation.next_measurement_design.refit_lambda`
of the two records).  The linearisation overstates what a rival reaches after a refit (a rival in
another form may match both records), so a pair the refits leave below the target is said, with
its shortfall.  Then (:func:`choose_plan`, the project lead's decisions of issue 27 item 3) the
next-best second records by linearised λ that reach the target linearised are checked in turn, at
most :data:`MORE_SECOND_RECORDS` more, and the first the refits confirm is recommended; when none
is, the checked plan of largest λ after the refits is still recommended, SHORT (``separates``
False; its shortfall, the pairs short and the remedies said, and ``together["short"]``), when that
λ is above the first record's own after the refits — the best single record — by more than
:data:`SHORT_PLAN_GAIN` (a material gain, not an optimiser's: the second experiment costs the user
a measurement), and otherwise the two records are not recommended (said).  Note that a rival
refitted to more lines cannot fit them better, so a plan from the best single record has, per
pair, at least that record's λ (up to the optimiser); a plan from another first record need not.  Pairs searched with their models' other
forms (:mod:`~physmodel.estimation.next_measurement_forms`) are not combined: when one is still
competing no second record is searched.  Nor is one for a single pair: there a second record only
adds lines of the same kind, which the shortfall message already covers (more periods).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import IPMCError
from .next_measurement_design import log_ratio, stack_real, t_solve
from .next_measurement_results import CandidateMeasurement


@dataclass
class RecordPair:
    """Two experiments recommended together.

    Attributes
    ----------
    second : CandidateMeasurement
        The experiment added to the first, described in its role: diagnosed jointly with the record
        where the pair's λ counts the record (its ``separation``, ``power`` and ``separation_by_pair``
        are still those of the experiment alone).
    separation : float
        Linearised λ of both records (with the diagnosed record where either is evaluated with it),
        the least over the live pairs and the two directions. [-]
    separation_by_pair : dict
        ``"A vs B"`` → {"A true": λ_A, "B true": λ_B} of both records (linearised). [-]
    separation_refit : float
        λ of both records after the refits (:func:`refit_plan`), the least over the live pairs; NaN
        unless checked. [-]
    refit_by_pair : dict
        ``"A vs B"`` → λ of both records after the refits, the least over the two directions. [-]
    refits : dict
        What the check cost: ``fits`` (least-squares calls), ``starts``, ``evaluations``.
    complete : bool
        False when the refits stopped early (:func:`refit_plan`'s ``suspects``): ``refit_by_pair``
        holds only the pairs refitted, and ``separation_refit`` is their least, an upper bound of
        the plan's.
    """

    second: CandidateMeasurement
    separation: float
    separation_by_pair: dict = field(default_factory=dict)
    separation_refit: float = float("nan")
    refit_by_pair: dict = field(default_factory=dict)
    refits: dict = field(default_factory=dict)
    complete: bool = True

    def short(self, target: float) -> dict:
        """``{"A vs B": λ after the refits}`` of the pairs the refits leave below ``target``."""
        return {k: v for k, v in self.refit_by_pair.items() if not v >= target}

    def together(self, target: float | None = None) -> dict:
        """:attr:`~physmodel.estimation.next_measurement_results.NextMeasurement.together` of the
        plan: ``separation`` the refits' λ when checked (else the linearised one),
        ``separation_linearised``, ``separation_by_pair`` (linearised, per direction),
        ``refit_by_pair``, ``linearised_only``, ``refits`` and ``recommended`` (True here; the search
        sets it False for a plan it does not recommend); with ``target``, ``short``: ``{"A vs B":
        {"separation": λ after the refits, "short_by": target − λ}}`` of the pairs the refits leave
        below it (empty when none)."""
        checked = bool(self.refit_by_pair)
        out = {"separation": self.separation_refit if checked else self.separation,
               "separation_linearised": self.separation, "separation_by_pair": dict(self.separation_by_pair),
               "refit_by_pair": dict(self.refit_by_pair), "linearised_only": not checked,
               "refits": dict(self.refits), "recommended": True}
        if target is not None:
            out["short"] = {k: {"separation": v, "short_by": target - v} for k, v in self.short(target).items()}
        return out

    def summary(self) -> dict:
        """The checked plan in brief (``NextMeasurement.together["checked"]``): the second record
        (``second``, its ``quantity``), ``separation_linearised``, ``separation`` (after the refits)
        and ``refit_by_pair``."""
        return {"second": self.second.describe(), "quantity": self.second.quantity,
                "separation_linearised": self.separation, "separation": self.separation_refit,
                "refit_by_pair": dict(self.refit_by_pair), "complete": self.complete, "fits": self.refits.get("fits", 0)}


#: Second records tried after the linearised best is refused by the refits, the next-best by
#: linearised λ (each refit-checked; the search stops at the first reaching the target): a bound on
#: the check's cost, which ``ipmc diagnose`` pays (the project lead's decision, issue 27 item 3).
MORE_SECOND_RECORDS = 2
#: A short two-record plan is offered only when its least λ after the refits is above the best
#: single record's by more than this fraction: a material gain (the 10 % at which a message also
#: states the other of two λ, ``next_measurement.shortfall``), not an optimiser's.
SHORT_PLAN_GAIN = 0.1


@dataclass
class PlanChoice:
    """What :func:`choose_plan` decided.

    Attributes
    ----------
    plan : RecordPair or None
        The two records recommended: reaching the target (after the refits when checked), or — when
        ``short`` — short of it but better than the first record alone.
    short : bool
        ``plan`` is short of the target after the refits (offered as the best there is).
    refused : RecordPair or None
        Without ``plan``: the best checked plan, short of the target and not better than the first
        record alone (not recommended; said).
    checked : list of RecordPair
        Every plan checked by refits, in the order tried (by linearised λ).
    target : float
        The separation needed. [-]
    first : CandidateMeasurement or None
        The plans' first record when it is not the best single record (the one given to
        :func:`choose_plan`) but a pair's own best (:func:`first_records`): the greedy plan from the
        best single record falls short of ``target`` linearised and this one's plan is larger.
        None when the plans start from the best single record.
    first_for : str
        The pair (``"A vs B"``) ``first`` is the best record of; empty when ``first`` is None.
    greedy, greedy_linearised : float
        The λ of the greedy plan from the best single record with that record's refit shortfall
        taken off (what ``first``'s plan was compared with), and linearised (NaN when no second record
        can be added to it); set when ``first`` is. [-]
    single : CandidateMeasurement or None
        The best single record (the one given to :func:`choose_plan`): its refit λ is the bar a
        short plan must clear.
    """

    plan: RecordPair | None = None
    short: bool = False
    refused: RecordPair | None = None
    checked: list = field(default_factory=list)
    target: float = math.inf
    first: CandidateMeasurement | None = None
    first_for: str = ""
    greedy: float = float("nan")
    greedy_linearised: float = float("nan")
    single: CandidateMeasurement | None = None

    def together(self) -> dict:
        """:attr:`~physmodel.estimation.next_measurement_results.NextMeasurement.together`: the
        recommended plan's (or the refused one's, ``recommended`` False) with ``short``,
        ``checked`` (each plan checked, :meth:`RecordPair.summary`), ``refits_total`` (the
        refits' cost over them) and ``first_for`` (the pair whose own best record is the plans'
        first, :attr:`first_for`, with ``first`` its description and ``greedy`` / ``greedy_linearised``
        the greedy plan's λ with and without the refit shortfall; None when the plans start from the best single record); empty when no plan
        was searched to the target."""
        shown = self.plan or self.refused
        if shown is None:
            return {}
        total: dict = {}
        for p in self.checked:
            for k, v in p.refits.items():
                total[k] = total.get(k, 0) + v
        out = {**shown.together(self.target), "recommended": self.plan is not None,
               "checked": [p.summary() for p in self.checked], "refits_total": total,
               "first_for": self.first_for or None}
        if self.first is not None:
            out.update(first=self.first.describe(), greedy=self.greedy, greedy_linearised=self.greedy_linearised)
        return out


def first_records(first: CandidateMeasurement, rows: list, live: list) -> list:
    """The other first records a plan may start from: for each ``live`` pair (``"A vs B"``) the
    experiment of ``rows`` maximising that pair's λ (the least over its two directions, linearised),
    ``[(pair, record)]``, each record once (the first pair it is best for) and ``first`` — the best
    single record, the greedy start — left out.  At most one per pair: a handful."""
    out: list = []
    for k in live:
        best = max(rows, key=lambda r: min(r.separation_by_pair[k].values()) if k in r.separation_by_pair
                   else -math.inf)
        if best is not first and all(best is not r for _, r in out):
            out.append((k, best))
    return out


def choose_plan(d, first: CandidateMeasurement, rows: list, sums: dict, bases: dict, pairs: list, deficit: dict,
                target: float, check_refit: int, nm: dict, max_nfev: int, label, view) -> PlanChoice:
    """The second record to run with ``first`` (module doc): the linearised best
    (:func:`second_record`, over ``pairs``' keys ``"A vs B"``) when it reaches ``target``, checked by
    the refits (:func:`refit_plan`, when ``check_refit`` > 0); when the refits refuse it, the
    next-best by linearised λ that also reach the target linearised, up to
    :data:`MORE_SECOND_RECORDS` more, each checked, stopping at the first the refits confirm.  When
    none is confirmed, the checked plan of largest λ after the refits is still recommended, short,
    when that λ is above ``first``'s own after the refits (its ``separation_refit``: the best single
    record); else none is (``refused``).

    When the greedy plan from ``first`` (the best single record) falls short of ``target``
    linearised, the plans started from each pair's own best record (:func:`first_records`) are
    searched too, each with its best second record (:func:`second_record`, linearised: cheap), and
    the one of largest λ is taken when it is larger than the greedy one (``PlanChoice.first``); it,
    and its next-best second records, go through the same check, and "better than the first
    record" stays the best single record's refit λ (the recommendation without a second record).
    The greedy plan is compared with its first record's refit shortfall taken off (``deficit``: the
    refits showed that record's linearisation overstating, so its raw λ is not to be built on), the
    others on their linearised λ (their first records' refits are not known, so no ``deficit`` is
    taken off their plans); the refit check then decides on every plan alike.  (Compared raw
    against raw, strip 51883's greedy plan — 27.1 with its shortfall, more raw — was kept, short,
    over a plan its refits confirm at 44.6.)  Both greedy values are kept and said."""
    keys = [f"{label(a)} vs {label(b)}" for a, b in pairs]
    out = PlanChoice(target=target, single=first)
    single = first
    plan = second_record(first, rows, sums, bases, keys, deficit)
    if plan is None or plan.separation < target:      # the greedy first record may be a compromise (issue 27)
        raw = second_record(first, rows, sums, bases, keys) if deficit else plan    # the greedy plan linearised
        greedy = plan.separation if plan is not None else math.nan
        bar = greedy
        for k, f in first_records(first, rows, keys):
            p = second_record(f, rows, sums, bases, keys)
            if p is not None and not p.separation <= bar:     # NaN bar (no greedy plan): any plan
                plan, first, deficit, bar = p, f, {}, p.separation
                out.first, out.first_for, out.greedy = f, k, greedy
                out.greedy_linearised = raw.separation if raw is not None else math.nan
    while plan is not None and plan.separation >= target:
        if check_refit <= 0:          # linearised only (said so)
            out.plan = plan
            return out
        had = [v for v in [single.separation_refit] + [p.separation_refit for p in out.checked] if v == v]
        short = [(k, v) for p in out.checked for k, v in p.short(target).items()]
        plan = refit_plan(d, plan, first, pairs, nm, max_nfev, label, view, target,
                          suspects={k: min((v for x, v in short if x == k), default=math.nan) for k, _ in short},
                          floor=max(had, default=math.nan))
        out.checked.append(plan)
        if not plan.short(target):
            out.plan = plan
            return out
        if len(out.checked) > MORE_SECOND_RECORDS:
            break
        plan = second_record(first, rows, sums, bases, keys, deficit, exclude=[p.second for p in out.checked])
    if not out.checked:
        return out
    best = max((p for p in out.checked if p.complete),       # a plan stopped early is below one checked before
               key=lambda p: p.separation_refit if p.separation_refit == p.separation_refit else -math.inf)
    if best.separation_refit > (1.0 + SHORT_PLAN_GAIN) * single.separation_refit:      # NaN either side: not better
        out.plan, out.short = best, True
    else:
        out.refused = best
    return out


def record_base(rec_a: tuple, rec_b: tuple, w0: np.ndarray) -> tuple:
    """The diagnosed record's fixed normal-equation sums of a pair, ``(A true, B true)``: for each
    direction (rᵀWr, JᵀWr, JᵀWJ) of the rival on the record's lines (``rec_*`` the models'
    ``(ln G, ∂ln G/∂θ)`` there, ``w0`` the record's weights)."""
    D0 = stack_real(log_ratio(rec_a[0], rec_b[0]))
    JB0, JA0 = stack_real(rec_b[1]), stack_real(rec_a[1])
    base_ab = (w0 @ (D0 * D0), (w0[:, None] * JB0).T @ D0, (w0[:, None] * JB0).T @ JB0)
    base_ba = (w0 @ (D0 * D0), -(w0[:, None] * JA0).T @ D0, (w0[:, None] * JA0).T @ JA0)
    return base_ab, base_ba


def overlaps(r1: CandidateMeasurement, r2: CandidateMeasurement) -> bool:
    """Whether ``r2`` is ``r1`` or holds one of its lines (same quantity, temperature and frequency)."""
    if r1 is r2:
        return True
    if r1.quantity != r2.quantity:
        return False
    have = set(zip(r1.line_temperatures_c.tolist(), r1.line_frequencies_hz.tolist()))
    return any(x in have for x in zip(r2.line_temperatures_c.tolist(), r2.line_frequencies_hz.tolist()))


def covered(r: CandidateMeasurement, tried: CandidateMeasurement) -> bool:
    """Whether experiment ``r`` holds exactly the lines of ``tried`` (quantity, temperature and
    frequency) with no larger weights: at no higher a drive, or at any drive for a quantity the
    diagnosed record does not hold (its σ is the record's median, whatever the drive:
    :func:`~physmodel.estimation.next_measurement_design.line_sigma`).  Its refits cannot reach more
    than ``tried``'s (in the record's quantity σ does not fall with a lower drive, the noise model's
    slope b ≤ 0, and λ = min_δ Σ w r² does not grow when no weight does), so after ``tried`` was
    refused it is not worth a refit (41038: the Z record at drive ×2 after ×1, the same λ, 24 fits)."""
    level_sets_sigma = r.joint and not r.added_quantity          # merged into a quantity the record holds
    return (r.quantity == tried.quantity and (r.level <= tried.level or not level_sets_sigma)
            and np.array_equal(r.line_temperatures_c, tried.line_temperatures_c)
            and np.array_equal(r.line_frequencies_hz, tried.line_frequencies_hz))


def second_record(first: CandidateMeasurement, rows: list, sums: dict, bases: dict, live: list,
                  deficit: dict | None = None, exclude: Sequence[CandidateMeasurement] = ()) -> RecordPair | None:
    """The experiment of ``rows`` that, added to ``first``, maximises the least over the ``live``
    pairs (``"A vs B"``) of the combined linearised λ (module doc); none :func:`covered` by one of
    ``exclude`` (second records already refused by the refits: the next-best by linearised λ).

    ``deficit[pair]``: how far the refits of ``first`` fell below its linearised λ of that pair
    (≥ 0; 0 where not checked).  It is taken off the pair's combined λ: the combination adds only
    non-negative terms to ``first``'s linearised sums, so without it a pair the refits say ``first``
    cannot separate would count as separated whatever record is added (review).

    ``sums[pair][direction]`` the :func:`~physmodel.estimation.next_measurement_design.t_sums` of
    every row (arrays over ``rows`` in order) and ``bases[pair][direction]`` the diagnosed record's
    sums (:func:`record_base`).  None when a live pair has no sums (searched with other forms) or
    no row can be added."""
    if not live or any(k not in sums for k in live):
        return None
    i1 = next(i for i, r in enumerate(rows) if r is first)
    cand = np.array([j for j, r in enumerate(rows) if not overlaps(first, r)
                     and not any(covered(r, x) for x in exclude)], int)
    if cand.size == 0:
        return None
    with_rec = np.array([first.joint or rows[j].joint for j in cand], float)
    least = np.full(cand.size, np.inf)
    by: dict = {}
    for k in live:
        by[k] = {}
        for name, (rr, Jr, JJ) in sums[k].items():
            b = bases[k][name]
            comb = (rr[i1] + rr[cand] + with_rec * b[0],
                    Jr[i1][None, :] + Jr[cand] + with_rec[:, None] * b[1][None, :],
                    JJ[i1][None, :, :] + JJ[cand] + with_rec[:, None, None] * b[2][None, :, :])
            lam = t_solve(comb) - (deficit or {}).get(k, 0.0)
            by[k][name] = lam
            least = np.minimum(least, lam)
    j = int(np.argmax(least))
    second = rows[int(cand[j])]
    if with_rec[j] and not second.joint:      # counted with the record: diagnosed jointly with it (review)
        second = replace(second, joint=True, added_quantity=True)
    return RecordPair(second, float(least[j]),
                      {k: {name: float(v[j]) for name, v in d.items()} for k, d in by.items()})


def refit_plan(d, plan: RecordPair, first: CandidateMeasurement, pairs: list, nm: dict, max_nfev: int, label,
               view, target: float = math.inf, suspects: Mapping[str, float] | None = None,
               floor: float = math.nan) -> RecordPair:
    """``plan`` checked by full nonlinear refits (module doc): for each of ``pairs`` (model pairs)
    the least over the two directions of the rival refitted to the truth's noiseless predictions on
    ``first`` and ``plan.second`` together
    (:func:`~physmodel.estimation.next_measurement_design.refit_check`), and what the refits cost.
    A pair whose refits on ``first`` alone already reach ``target`` (``first.refit_by_pair``) is not
    refitted again: a rival fitted to more lines cannot fit them better, so its λ on both records is
    at least that one, which it keeps (a lower bound).

    ``suspects`` (``{"A vs B": λ}``: the pairs a plan checked before fell short in, with the least λ
    they had) are refitted first, the lowest first, one direction at a time; as soon as one
    direction's λ is below ``target`` and not above ``floor`` (the best λ already had: the first
    record's or a checked plan's), the plan can neither separate nor beat it — a pair's λ is the
    least over its directions and the plan's the least over the pairs, so no larger — and nothing
    more is refitted: the plan is returned ``complete`` False with the pairs refitted so far (the
    last one's λ that direction's, an upper bound) (:func:`choose_plan`'s bound on the cost;
    41038: 24 fits a plan → 4).  Otherwise every pair's λ is the one :func:`refit_check` gives."""
    from .next_measurement_design import refit_check, refit_lambda

    count: dict = {"fits": 0, "starts": 0, "evaluations": 0}
    done = {f"{label(a)} vs {label(b)}": first.refit_by_pair.get(f"{label(a)} vs {label(b)}", math.nan)
            for a, b in pairs}
    done = {k: v for k, v in done.items() if v >= target}
    rest = [(a, b) for a, b in pairs if f"{label(a)} vs {label(b)}" not in done]
    sus = suspects or {}
    early = sorted((p for p in rest if f"{label(p[0])} vs {label(p[1])}" in sus),
                   key=lambda p: sus[f"{label(p[0])} vs {label(p[1])}"])
    part: dict = {}
    for a, b in early:
        k, vals = f"{label(a)} vs {label(b)}", []
        for truth, rival in ((a, b), (b, a)):
            vals.append(refit_lambda(d, [first, plan.second], nm, truth, rival, max_nfev, view=view, count=count))
            if not vals[-1] >= target and not vals[-1] > floor:       # NaN too: not separated
                part[k] = min(vals)
                low = float("nan") if any(v != v for v in part.values()) else float(min(part.values()))
                return replace(plan, separation_refit=low, refit_by_pair=part, refits=count, complete=False)
        part[k] = min(vals)
    done.update(part)
    rest = [p for p in rest if p not in early]
    by = {**done, **(refit_check(d, rest, [first, plan.second], nm, max_nfev, label, view, count=count)
                     if rest else {})}
    by = {f"{label(a)} vs {label(b)}": by[f"{label(a)} vs {label(b)}"] for a, b in pairs}     # the pairs' order
    # a pair whose refits gave no finite λ is not separated: NaN, whatever the order of the pairs
    least = float("nan") if not by or any(v != v for v in by.values()) else float(min(by.values()))
    return replace(plan, separation_refit=least, refit_by_pair=by, refits=count)


def _short_words(plan: RecordPair, target: float) -> str:
    """The pairs ``plan``'s refits leave below ``target``, each with its λ and shortfall."""
    return "; ".join(f"{k} reaches only {v:.3g} (short of {target:.3g} by {target - v:.3g})"
                     for k, v in plan.short(target).items())


def plan_message(pick: PlanChoice, first: CandidateMeasurement, who: str, power: float, alpha: float,
                 first_words: str, current: float) -> str:
    """The message of a recommended plan (``pick.plan``): the two records and their λ together;
    when short (``pick.short``), that no single experiment nor any pair of records checked by refits
    is expected to separate, the pairs that fall short and by how much, and the remedies (more periods — λ grows in proportion
    to the periods averaged, so about ⌈target/λ⌉× as many —, wider limits, or the ambiguity
    accepted).  ``first_words``: the first record's own λ in words; ``current``: the record's."""
    plan, target = pick.plan, pick.target
    assert plan is not None
    both = f"{first.describe()} and, with it, {plan.second.describe()}"
    need = f"{target:.3g} needed for {power:.0%} power at α = {alpha:g}"
    if (pick.first is not None and first.separation_refit != first.separation_refit
            and not first_words.endswith("linearised")):
        first_words += " linearised (not refitted alone)"
    alone = f"the first alone gives {first_words}, the record alone {current:.3g}"
    tried = len(pick.checked)
    if pick.first is not None:       # a pair's own best record, not the best single one (issue 27)
        single = pick.single
        with_single = ("to which no second record can be added" if pick.greedy != pick.greedy else
                       f"with which the best second record gives only λ = {pick.greedy:.3g} with that record's "
                       f"refit shortfall taken off ({pick.greedy_linearised:.3g} linearised)"
                       if pick.greedy_linearised != pick.greedy else
                       f"with which the best second record gives only λ = {pick.greedy:.3g} linearised")
        alone += (f"; the first is the best experiment for {pick.first_for}, not the best single one"
                  + (f" ({single.describe()}: {_refit_words(single)})" if single is not None else "")
                  + f", {with_single}")
    if not pick.short:
        refused = pick.checked[:-1]
        return (f"Next measurements to separate {who} (no single experiment within the limits is expected to): "
                f"{both}: together expected λ = "
                + (f"{plan.separation_refit:.3g}, checked by refits of the rivals to both records together "
                   f"({plan.separation:.3g} linearised)" if plan.refit_by_pair else f"{plan.separation:.3g}, "
                   "linearised only (no refit check asked)")
                + f", the records diagnosed together (≥ {need}; {alone})."
                + (f" {len(refused)} second record(s) of larger linearised λ fell short after the refits ("
                   + "; ".join(f"{p.second.describe()}: {_plan_refit_words(p)}" for p in refused) + ")."
                   if refused else ""))
    lam = plan.separation_refit
    return (f"No single experiment within the limits is expected to separate {who} at the noise of this record, nor "
            + ("the pair of records checked by refits" if tried == 1 else
               f"any of the {tried} pairs of records checked by refits (chosen by linearised λ)")
            + f"; the best checked is two records, {both}: together expected λ = {lam:.3g} after refits of the "
            f"rivals to both records together ({plan.separation:.3g} linearised) < {need}, the records diagnosed "
            f"together ({alone}); short after the refits: {_short_words(plan, target)}"
            + ". Lower the noise (more periods in both records"
            + (f": λ grows in proportion to the periods averaged, so about {math.ceil(target / lam)}× as many"
               if 0 < lam < target else "")
            + "), widen the limits, or accept the ambiguity.")


def _refit_words(r: CandidateMeasurement) -> str:
    """A single record's λ as said beside a plan: after its refits, else linearised."""
    return (f"λ {r.separation_refit:.3g} after the refits" if r.separation_refit == r.separation_refit else
            f"λ {r.separation:.3g} linearised")


def _plan_refit_words(p: RecordPair) -> str:
    """A checked plan's λ after the refits; an upper bound when they stopped early (``complete``
    False: a pair fell below what an earlier plan reached, so its least is no larger)."""
    return f"λ {p.separation_refit:.3g}" if p.complete else f"λ ≤ {p.separation_refit:.3g} (refits stopped early)"


def refused_message(pick: PlanChoice, first_words: str) -> str:
    """The sentence added to a short single record's message when two records reached the target
    linearised but every checked pair falls short after the refits and none is better than the
    first record alone (``first_words``: its λ in words): not recommended."""
    best, target, n = pick.refused, pick.target, len(pick.checked)
    assert best is not None
    start = ("with it" if pick.first is None else
             f"started instead from {pick.first.describe()} (the best experiment for {pick.first_for})")
    return (" Two records were checked too" + (f" ({n} second records, by linearised λ; the best after the refits "
                                                "said)" if n > 1 else "")
            + f": {start}, {best.second.describe()} gives λ = {best.separation:.3g} linearised, but after refits of "
            f"the rivals to both records together {_short_words(best, target)}: not expected to separate, "
            + (f"nor better than the {'first' if pick.first is None else 'best single record'} alone "
               f"({first_words}) by more than {SHORT_PLAN_GAIN:.0%}"
               if pick.single is None or pick.single.separation_refit == pick.single.separation_refit else
               "and the best single record's refits gave no λ to compare it with")
            + ", so not recommended.")


def bath_premise(records: list, record_temperatures_c, base) -> str:
    """The premise of the recommended experiments (``records``: the recommended one, then a second
    of :func:`second_record`) that step the bath away from the diagnosed record's temperatures:
    their separation is predicted through the diagnosed model's temperature laws (those of
    ``base``, named), so a misfit at a new temperature may mean the laws, not the effect, are
    wrong.  With two records each that steps the bath is named in its role with its temperatures
    (before, only the first's was said when both did).  Empty when none steps it.  A ``None`` entry
    (no record in that role) is left out, so ``[r, None]`` says what ``[r]`` does; more than two
    records raise :class:`~physmodel.errors.IPMCError` (the roles are first and second)."""
    if len(records) > 2:
        raise IPMCError(f"bath_premise: {len(records)} records given; expected the recommended one and at most a "
                        "second (second_record)")
    records = [r for r in records if r is not None]
    T0 = np.asarray(record_temperatures_c, float)
    new = [[t for t in r.temperatures_c if not np.any(np.isclose(t, T0))] for r in records]
    if not any(new):
        return ""
    laws = getattr(base, "laws", None)
    said = laws.describe() if laws is not None else "the parameter set's"
    at = ", ".join(f"{t:g}" for t in np.unique(T0))
    check = ("means the laws, not the effect, may be wrong — check them (e.g. a record of the plain strip at that "
             "temperature) before reading it as an effect.")
    temps = [", ".join(f"{t:g}" for t in n) for n in new]
    if len(records) == 1:
        return (f"Premise: this experiment steps the bath to {temps[0]} °C (the record: {at} °C), so its separation "
                f"relies on the diagnosed model's temperature laws ({said}); a misfit at the new temperature (an "
                f"'unexplained' verdict on both records) {check}")
    role = ("first", "second")
    stepping = [i for i in range(len(records)) if new[i]]
    if len(stepping) == len(records):
        which = ("both experiments step the bath: " + "; ".join(
            f"the {role[i]} ({records[i].quantity}) to {temps[i]} °C" for i in stepping)
            + f" (the record: {at} °C), so the separation of each, and of the records together,")
    else:
        i = stepping[0]
        which = (f"the {role[i]} experiment ({records[i].quantity}) steps the bath to {temps[i]} °C (the record: "
                 f"{at} °C; the {role[1 - i]} stays at the record's temperatures), so its separation, and that of "
                 "the records together,")
    return (f"Premise: {which} relies on the diagnosed model's temperature laws ({said}); a misfit at a new "
            f"temperature (an 'unexplained' verdict on the records together) {check}")


__all__ = ["MORE_SECOND_RECORDS", "SHORT_PLAN_GAIN", "PlanChoice", "RecordPair", "bath_premise", "choose_plan", "covered", "first_records",
           "overlaps",
           "plan_message", "record_base", "refit_plan", "refused_message", "second_record"]
