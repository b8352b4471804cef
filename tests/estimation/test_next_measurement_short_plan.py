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

    def fake_second(first_, rows_, sums, bases, live, deficit=None, exclude=()):
        cand = [r for r in rows_[1:] if not any(covered(r, x) for x in exclude)]
        if not cand:
            return None
        r = max(cand, key=lambda r: linearised[name[id(r)]])
        return RecordPair(r, linearised[name[id(r)]], {})

    def fake_refit(d, plan, first_, pairs, nm, max_nfev, label, view, target=math.inf):
        n = name[id(plan.second)]
        tried.append(n)
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


def test_a_record_of_the_same_lines_at_no_higher_drive_is_not_tried_again():
    """covered: the same lines at a lower (or the same) drive cannot do better after the refits (σ
    does not fall with the drive); a higher drive, other lines or another quantity may."""
    a = _row("Z", [10.0, 20.0], level=2.0)
    assert covered(_row("Z", [10.0, 20.0], level=1.0), a) and covered(_row("Z", [10.0, 20.0], level=2.0), a)
    assert not covered(_row("Z", [10.0, 20.0], level=3.0), a)
    assert not covered(_row("Z", [10.0, 30.0], level=1.0), a) and not covered(_row("M", [10.0, 20.0], level=1.0), a)


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
