"""The gap shrink said after a diagnosis: (cost − expected) before / after, floored after at the
cost's spread — and no number when there was no gap (a `none` verdict on a record the baseline
fits printed "gap shrink -9.38x": two noise-size excesses, one negative)."""

import math
from types import SimpleNamespace

from physmodel.estimation.diagnosis import gap_shrink, gap_shrink_words


def _d(before, after, expected=100.0, std=10.0):
    g = lambda c: {"cost": c, "expected_cost": expected, "cost_std": std}  # noqa: E731
    return SimpleNamespace(gap_before=g(before), gap_after=g(after))


def test_a_gap_closed_to_its_spread():
    d = _d(600.0, 103.0)                 # excess 500 before, 3 after: floored at the spread 10
    assert gap_shrink(d) == 50.0
    assert gap_shrink_words(d) == "50×"


def test_no_gap_to_shrink_is_said_not_numbered():
    for before in (100.0 - 30.0, 100.0, 100.0 + 10.0):      # below, at, and one spread above the expectation
        d = _d(before, before)
        assert math.isnan(gap_shrink(d))
        assert gap_shrink_words(d).startswith("none to shrink")
    assert gap_shrink(_d(110.5, 100.0)) == 1.05         # just beyond one spread: a (small) number
