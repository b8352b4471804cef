"""The choice among two-record plans (issue 27 item 3, next_measurement_plan.choose_plan): the
linearised-best second record is checked by refits; refused, the next-best by linearised λ are
tried (at most MORE_SECOND_RECORDS more, stopping at the first the refits confirm); none confirmed,
the plan of largest λ after the refits is still recommended, short, when above the first record's
own, else none.  The refits and the linearised ranking are replaced by stated numbers, so each
test's oracle is the decision rule applied by hand to them; the real refits are exercised on seed
47079 in test_next_measurement_plan."""

from __future__ import annotations

import math

import numpy as np
import pytest

from physmodel.estimation import next_measurement_plan as plan_mod
from physmodel.estimation.next_measurement_plan import (
    MORE_SECOND_RECORDS,
    RecordPair,
    choose_plan,
    covered,
    second_record,
)
from physmodel.estimation.next_measurement_results import CandidateMeasurement

TARGET = 42.0


def _row(q: str, f, level: float = 1.0) -> CandidateMeasurement:
    f = np.asarray(f, float)
    return CandidateMeasurement(q, (float(f.min()), float(f.max())), (35.0,), level, f.size, f, 0.0, {}, False, 1.0,
                                0.0, line_temperatures_c=np.full(f.size, 35.0), line_frequencies_hz=f)


def _setup(monkeypatch, linearised: dict, refit: dict, first_refit: float = 10.0):
    """Rows named by their first line; ``linearised[name]`` the plan's linearised λ (the ranking),
    ``refit[name]`` its λ after the refits (one pair "A vs B").  Returns (first, rows, names tried)."""
    first = _row("M", [1.0, 2.0])
    first.separation_refit = first_refit
    rows = [first] + [_row("Z", [float(i), float(i) + 0.5]) for i in range(10, 10 + len(linearised))]
    name = {id(r): n for r, n in zip(rows[1:], linearised)}
    tried: list = []
    asked: list = []
    _setup.asked = asked            # type: ignore[attr-defined]

    def fake_second(first_, rows_, sums, bases, live, deficit=None, exclude=()):
        cand = [r for r in rows_[1:] if not any(covered(r, x) for x in exclude)]
        if not cand:
            return None
        r = max(cand, key=lambda r: linearised[name[id(r)]])
        return RecordPair(r, linearised[name[id(r)]], {})

    def fake_refit(d, plan, first_, pairs, nm, max_nfev, label, view, target=math.inf, suspects=None, floor=math.nan):
        n = name[id(plan.second)]
        tried.append(n)
        asked.append((dict(suspects or {}), floor))
        return RecordPair(plan.second, plan.separation, {}, refit[n], {"A vs B": refit[n]}, {"fits": 4})

    monkeypatch.setattr(plan_mod, "second_record", fake_second)
    monkeypatch.setattr(plan_mod, "refit_plan", fake_refit)
    return first, rows, tried


def _choose(first, rows, check_refit: int = 2):
    return choose_plan(None, first, rows, {}, {}, [("A", "B")], {}, TARGET, check_refit, {}, 10, str, None)


def test_the_linearised_best_confirmed_is_the_plan(monkeypatch):
    first, rows, tried = _setup(monkeypatch, {"a": 100.0, "b": 90.0}, {"a": 50.0, "b": 80.0})
    pick = _choose(first, rows)
    assert tried == ["a"] and pick.plan is not None and pick.plan.separation_refit == 50.0 and not pick.short
    tg = pick.together()
    assert tg["recommended"] is True and tg["short"] == {} and tg["refits_total"] == {"fits": 4}


def test_a_refused_plan_gives_way_to_the_next_best_that_the_refits_confirm(monkeypatch):
    first, rows, tried = _setup(monkeypatch, {"a": 100.0, "b": 90.0, "c": 80.0}, {"a": 30.0, "b": 45.0, "c": 99.0})
    pick = _choose(first, rows)
    assert tried == ["a", "b"]                     # stops at the first confirmed (b), not the best (c)
    assert pick.plan is not None and pick.plan.separation_refit == 45.0 and not pick.short
    assert [c["separation"] for c in pick.together()["checked"]] == [30.0, 45.0]
    assert pick.together()["refits_total"] == {"fits": 8}


def test_at_most_two_more_are_tried_and_the_best_short_one_above_the_first_is_offered(monkeypatch):
    lin = {"a": 100.0, "b": 90.0, "c": 80.0, "d": 70.0}
    first, rows, tried = _setup(monkeypatch, lin, {"a": 20.0, "b": 35.0, "c": 25.0, "d": 99.0}, first_refit=10.0)
    pick = _choose(first, rows)
    assert tried == ["a", "b", "c"] and len(tried) == 1 + MORE_SECOND_RECORDS     # d (it would reach) is not tried
    # each later plan is told the pairs short before (their least λ) and the best λ had (the first
    # record's, then a plan's)
    assert _setup.asked == [({}, 10.0), ({"A vs B": 20.0}, 20.0), ({"A vs B": 20.0}, 35.0)]
    assert pick.short and pick.plan is not None and pick.plan.separation_refit == 35.0 and pick.refused is None
    tg = pick.together()
    assert tg["recommended"] is True and tg["separation"] == 35.0
    assert tg["short"] == {"A vs B": {"separation": 35.0, "short_by": TARGET - 35.0}}


def test_a_short_plan_not_above_the_first_record_is_not_offered(monkeypatch):
    for first_refit in (35.0, 36.0, float("nan")):       # equal, above, or the first not checked
        first, rows, tried = _setup(monkeypatch, {"a": 100.0, "b": 90.0, "c": 80.0}, {"a": 20.0, "b": 35.0, "c": 25.0},
                                    first_refit=first_refit)
        pick = _choose(first, rows)
        assert pick.plan is None and not pick.short and pick.refused is not None
        assert pick.refused.separation_refit == 35.0
        assert pick.together()["recommended"] is False and pick.together()["short"]["A vs B"]["separation"] == 35.0


def test_plans_below_the_target_linearised_are_not_refitted(monkeypatch):
    first, rows, tried = _setup(monkeypatch, {"a": 100.0, "b": 30.0}, {"a": 20.0, "b": 99.0}, first_refit=10.0)
    pick = _choose(first, rows)
    assert tried == ["a"] and pick.short and pick.plan.separation_refit == 20.0      # b not expected to reach
    first, rows, tried = _setup(monkeypatch, {"a": 30.0}, {"a": 99.0})
    pick = _choose(first, rows)
    assert tried == [] and pick.plan is None and pick.refused is None and pick.together() == {}


def test_without_the_refit_check_the_linearised_plan_stands(monkeypatch):
    first, rows, tried = _setup(monkeypatch, {"a": 100.0}, {"a": 1.0})
    pick = _choose(first, rows, check_refit=0)
    assert tried == [] and pick.plan is not None and not pick.short
    assert pick.together()["linearised_only"] is True and pick.together()["recommended"] is True


def test_a_record_of_the_same_lines_and_no_larger_weights_is_not_tried_again():
    """covered: merged into the record's quantity, the same lines at a lower (or the same) drive
    cannot do better after the refits (σ does not fall with a lower drive) and a higher drive may;
    in a quantity the record does not hold σ does not depend on the drive (line_sigma: the
    record's median), so any drive gives the same weights; other lines or another quantity may."""
    from dataclasses import replace

    from physmodel.estimation.next_measurement_design import line_sigma

    nm = {"slope": -0.5, "ref_ln": 0.01, "ref_ph": 0.01, "median_ln": 0.02, "median_ph": 0.02}
    lv = np.array([1.0, 3.0])
    other = line_sigma(nm, np.zeros(3), lv, False)
    assert np.array_equal(other[0][0], other[0][1])          # another quantity: σ the same at every drive
    merged = line_sigma(nm, np.zeros(3), lv, True)
    assert np.all(merged[0][1] < merged[0][0])               # the record's quantity: σ falls with the drive
    a = replace(_row("M", [10.0, 20.0], level=2.0), joint=True)
    assert covered(replace(a, level=1.0), a) and covered(replace(a, level=2.0), a)
    assert not covered(replace(a, level=3.0), a)
    z = _row("Z", [10.0, 20.0], level=1.0)                    # a record of its own
    zj = replace(z, joint=True, added_quantity=True)          # diagnosed jointly as one more quantity
    for x in (z, zj):
        assert covered(replace(x, level=2.0), x) and covered(replace(x, level=0.5), x)
    assert not covered(_row("Z", [10.0, 30.0]), z) and not covered(_row("M", [10.0, 20.0]), z)


def test_second_record_skips_the_records_already_refused():
    """The real second_record with ``exclude``: the pair's λ is Σ w Δ² (a rival parameter no line
    sees), so the ranking is known by hand — the record of Δ 3 first, then (that one refused) Δ 2,
    and the Δ 3 record's lines at a lower drive are skipped with it."""
    from physmodel.estimation.next_measurement_design import t_sums

    n = 2
    first = _row("M", [1.0, 2.0])
    rows = [first, _row("Z", [5.0, 6.0], 2.0), _row("Z", [5.0, 6.0], 1.0), _row("Z", [7.0, 8.0], 1.0)]
    deltas = [0.0, 3.0, 2.5, 2.0]
    J = np.zeros((2 * n, 1))
    s = [t_sums(np.r_[np.full(n, dl), np.zeros(n)], J, np.ones((1, 2 * n))) for dl in deltas]
    sums = {"A": {"x true": tuple(np.concatenate(x) for x in zip(*s))}}
    bases = {"A": {"x true": (0.0, np.zeros(1), np.zeros((1, 1)))}}
    p1 = second_record(first, rows, sums, bases, ["A"])
    assert p1 is not None and p1.second is rows[1] and p1.separation == pytest.approx(n * 9.0)
    p2 = second_record(first, rows, sums, bases, ["A"], exclude=[p1.second])
    assert p2 is not None and p2.second is rows[3] and p2.separation == pytest.approx(n * 4.0)
    assert second_record(first, rows, sums, bases, ["A"], exclude=[rows[1], rows[3]]) is None


def test_a_plan_whose_suspect_pairs_stay_below_the_best_had_is_not_refitted_further(monkeypatch):
    """refit_plan with ``suspects``: those pairs are refitted first (the lowest first), one direction at
    a time; a direction below the target and not above ``floor`` bounds the pair's λ (the least over
    its directions) and so the plan's (the least over the pairs): it can neither separate nor beat the
    best had, and nothing more is refitted (complete False).  Otherwise every pair gets what
    refit_check gives (both directions, their least), as without suspects."""
    from physmodel.estimation import next_measurement_design as design

    asked: list = []
    lam = {("A", "B"): 20.0, ("B", "A"): 25.0, ("C", "D"): 60.0, ("D", "C"): 65.0, ("E", "F"): 70.0, ("F", "E"): 75.0}

    def fake_lambda(d, records, nm, truth, rival, *a, **k):
        asked.append((truth, rival))
        return lam[(truth, rival)]

    def fake_check(d, pairs, records, *a, **k):
        return {f"{x} vs {y}": min(fake_lambda(d, records, None, x, y), fake_lambda(d, records, None, y, x))
                for x, y in pairs}

    monkeypatch.setattr(design, "refit_lambda", fake_lambda)
    monkeypatch.setattr(design, "refit_check", fake_check)
    first = _row("M", [1.0, 2.0])
    pairs = [("A", "B"), ("C", "D"), ("E", "F")]
    rp = RecordPair(_row("Z", [5.0, 6.0]), 100.0)
    run = lambda sus, floor: plan_mod.refit_plan(None, rp, first, pairs, {}, 10, str, None, TARGET,  # noqa: E731
                                                 suspects=sus, floor=floor)
    out = run({"C vs D": 50.0, "A vs B": 30.0}, 30.0)
    assert asked == [("A", "B")] and not out.complete and out.refit_by_pair == {"A vs B": 20.0}
    assert out.separation_refit == 20.0 and out.summary()["complete"] is False
    asked.clear()
    out = run({"A vs B": 30.0}, 15.0)                  # above the floor: every pair, as refit_check gives
    assert asked == [("A", "B"), ("B", "A"), ("C", "D"), ("D", "C"), ("E", "F"), ("F", "E")] and out.complete
    assert out.refit_by_pair == {"A vs B": 20.0, "C vs D": 60.0, "E vs F": 70.0} and out.separation_refit == 20.0
    lam[("A", "B")] = 50.0                              # the first direction reaches the target, the second not
    asked.clear()
    out = run({"A vs B": 30.0}, 30.0)
    assert asked == [("A", "B"), ("B", "A")] and not out.complete and out.refit_by_pair == {"A vs B": 25.0}
    asked.clear()
    out = run(None, 30.0)                               # no suspects: as before
    assert len(asked) == 6 and out.complete and out.refit_by_pair == {"A vs B": 25.0, "C vs D": 60.0, "E vs F": 70.0}
