"""A second record when no single one separates every competing pair (issue 27).

:func:`~physmodel.estimation.next_measurement.next_measurement` searches ONE experiment maximising
the least separation λ over the competing pairs.  When two pairs need different quantities (contact
resistance vs the diffusivity law separate in Z; a time delay vs an amplifier pole in M above the
resonance) no single experiment reaches the target for every pair, and the least over the pairs
picks a record that separates none.  Then a SECOND experiment is searched to add to the best single
one (greedy): the one maximising the least over the pairs of the two records' combined λ.

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
its shortfall, and the two records are not recommended.  Pairs searched with their models' other
forms (:mod:`~physmodel.estimation.next_measurement_forms`) are not combined: when one is still
competing no second record is searched.  Nor is one for a single pair: there a second record only
adds lines of the same kind, which the shortfall message already covers (more periods).
"""

from __future__ import annotations

import math
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
    """

    second: CandidateMeasurement
    separation: float
    separation_by_pair: dict = field(default_factory=dict)
    separation_refit: float = float("nan")
    refit_by_pair: dict = field(default_factory=dict)
    refits: dict = field(default_factory=dict)

    def short(self, target: float) -> dict:
        """``{"A vs B": λ after the refits}`` of the pairs the refits leave below ``target``."""
        return {k: v for k, v in self.refit_by_pair.items() if not v >= target}

    def together(self) -> dict:
        """:attr:`~physmodel.estimation.next_measurement_results.NextMeasurement.together` of the
        plan: ``separation`` the refits' λ when checked (else the linearised one),
        ``separation_linearised``, ``separation_by_pair`` (linearised, per direction),
        ``refit_by_pair``, ``linearised_only``, ``refits`` and ``recommended`` (True here; the search
        sets it False for a plan the refits refuse)."""
        checked = bool(self.refit_by_pair)
        return {"separation": self.separation_refit if checked else self.separation,
                "separation_linearised": self.separation, "separation_by_pair": dict(self.separation_by_pair),
                "refit_by_pair": dict(self.refit_by_pair), "linearised_only": not checked,
                "refits": dict(self.refits), "recommended": True}


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


def second_record(first: CandidateMeasurement, rows: list, sums: dict, bases: dict, live: list,
                  deficit: dict | None = None) -> RecordPair | None:
    """The experiment of ``rows`` that, added to ``first``, maximises the least over the ``live``
    pairs (``"A vs B"``) of the combined linearised λ (module doc).

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
    cand = np.array([j for j, r in enumerate(rows) if not overlaps(first, r)], int)
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
               view, target: float = math.inf) -> RecordPair:
    """``plan`` checked by full nonlinear refits (module doc): for each of ``pairs`` (model pairs)
    the least over the two directions of the rival refitted to the truth's noiseless predictions on
    ``first`` and ``plan.second`` together
    (:func:`~physmodel.estimation.next_measurement_design.refit_check`), and what the refits cost.
    A pair whose refits on ``first`` alone already reach ``target`` (``first.refit_by_pair``) is not
    refitted again: a rival fitted to more lines cannot fit them better, so its λ on both records is
    at least that one, which it keeps (a lower bound)."""
    from .next_measurement_design import refit_check

    count: dict = {"fits": 0, "starts": 0, "evaluations": 0}
    done = {f"{label(a)} vs {label(b)}": first.refit_by_pair.get(f"{label(a)} vs {label(b)}", math.nan)
            for a, b in pairs}
    done = {k: v for k, v in done.items() if v >= target}
    rest = [(a, b) for a, b in pairs if f"{label(a)} vs {label(b)}" not in done]
    by = {**done, **(refit_check(d, rest, [first, plan.second], nm, max_nfev, label, view, count=count)
                     if rest else {})}
    by = {f"{label(a)} vs {label(b)}": by[f"{label(a)} vs {label(b)}"] for a, b in pairs}     # the pairs' order
    # a pair whose refits gave no finite λ is not separated: NaN, whatever the order of the pairs
    least = float("nan") if not by or any(v != v for v in by.values()) else float(min(by.values()))
    return replace(plan, separation_refit=least, refit_by_pair=by, refits=count)


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


__all__ = ["RecordPair", "bath_premise", "overlaps", "record_base", "refit_plan", "second_record"]
