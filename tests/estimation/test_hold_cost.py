"""Holding an undetermined parameter says what it costs, and is refused when the data reject it.

Data come from the library's own physics (seed002_table3 with d = 4e-11, seeded noise); the
base value of d, where a hold puts it, is 3.07e-11.  Oracles independent of the hold logic:
the cost with every parameter free is a separate ``hold_undetermined=False`` run; the cost after
the hold is a separate calibration in which the held parameters are simply not free (they stay
at their base value); the thresholds are printed χ² quantiles (χ²_0.95(1) = 3.841,
χ²_0.95(2) = 5.991, any statistics table) or, for a misfit, scipy's F quantile times the
residual variance of the independent all-free run.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import f as f_dist

from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.estimation.calibration import calibrate
from physmodel.estimation.records import FreeParameter

CHI2_95_1 = 3.841      # printed table values
CHI2_95_2 = 5.991


@pytest.fixture(scope="module")
def base():
    return get_parameter_set("seed002_table3")


@pytest.fixture(scope="module")
def wide_sweep(base):
    """d = 4e-11, 0.1-100 Hz at 25 and 45 °C."""
    return synthesize_sweep(ActuatorModel(base.replace(d=4e-11)), "M", np.logspace(-1, 2, 30), [25.0, 45.0],
                            noise=MagnitudePhaseNoise(0.1, 1.0), seed=3)


def test_a_hold_the_data_reject_is_refused_and_its_cost_said(base, wide_sweep):
    """The user's case: every start ends with d at its bound (3.98e-11, just below the truth),
    the all-free fit is adequate; holding d at its base value 3.07e-11 would multiply the cost
    by ~20.  The hold is refused: d stays at the bound, flagged, and the costs are recorded."""
    free = [FreeParameter("d", 1e-11, 3.98e-11), "alpha0"]
    res = calibrate(wide_sweep, base, free, starts=4)
    all_free = calibrate(wide_sweep, base, free, starts=4, hold_undetermined=False)
    d_fixed = calibrate(wide_sweep, base, ["alpha0"], starts=1)           # d not free: at its base value
    assert all(s.final["d"] == pytest.approx(3.98e-11, rel=1e-3) for s in res.starts)
    assert all_free.adequate
    (h,) = res.holds
    assert h.names == ("d",) and h.added == ("d",) and not h.accepted
    assert h.cost_before == pytest.approx(all_free.cost, rel=1e-9)
    assert h.cost_after == pytest.approx(d_fixed.cost, rel=1e-6)
    assert h.cost_after > 10 * h.cost_before
    assert h.threshold == pytest.approx(CHI2_95_1 / 2, rel=1e-3)
    # the un-held fit is kept
    assert res.held == [] and res.hold_refused == ["d"]
    assert res.cost == pytest.approx(all_free.cost, rel=1e-9)
    assert res.values["d"] == pytest.approx(3.98e-11, rel=1e-3)
    assert res.parameters.d == res.values["d"]
    st = res.identifiability["d"]
    assert not st.identifiable and "upper bound" in st.reason and "NOT held" in st.reason
    assert res.determined == ["alpha0"]
    assert "hold of d refused" in res.message
    text = res.summary()
    assert "REFUSED" in text and "NOT DETERMINED (hold refused)" in text and "(not valid)" in text
    assert f"{h.cost_before:.5g} -> {h.cost_after:.5g}" in text
    rec = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert rec["holds"][0]["accepted"] is False
    assert rec["holds"][0]["cost_after"] == pytest.approx(d_fixed.cost, rel=1e-6)
    entry = {e["name"]: e for e in rec["parameters"]}
    assert entry["d"]["hold_refused"] and not entry["d"]["held"]
    assert "undetermined, NOT held" in res.parameters.source


def test_the_hold_test_scales_by_the_residual_variance_under_a_misfit(base, wide_sweep):
    """Bound 3.3e-11, far below the truth: the all-free fit itself fails the χ² test, so the cost
    difference is measured in its residual variance s² = χ²/dof (the F test).  Still refused."""
    free = [FreeParameter("d", 1e-11, 3.3e-11), "alpha0"]
    res = calibrate(wide_sweep, base, free, starts=1)
    all_free = calibrate(wide_sweep, base, free, starts=1, hold_undetermined=False)
    assert not all_free.adequate
    dof = 2 * 60 - 2
    s2 = 2 * all_free.cost / dof
    (h,) = res.holds
    assert h.threshold == pytest.approx(0.5 * s2 * f_dist.ppf(0.95, 1, dof), rel=1e-9)
    assert h.threshold > CHI2_95_1 / 2
    assert not h.accepted and res.hold_refused == ["d"]
    # the misfit verdict does not erase why d is not determined
    assert "NOT held" in res.identifiability["d"].reason and "does not fit" in res.identifiability["d"].reason


def test_a_hold_that_costs_nothing_is_taken_and_its_cost_said(base):
    """Band 0.01-1 Hz: r2_specific and xi act above it; holding them at their base values (the
    truth) costs less than the χ² test allows, so they are held as before."""
    truth = base.replace(d=4e-11, alpha0=base.alpha0 * 1.2)
    sw = synthesize_sweep(ActuatorModel(truth), "M", np.logspace(-2, 0, 30), [25.0],
                          noise=MagnitudePhaseNoise(0.1, 1.0), seed=1)
    res = calibrate(sw, base, ["d", "alpha0", "r2_specific", "xi"], starts=2)
    all_free = calibrate(sw, base, ["d", "alpha0", "r2_specific", "xi"], starts=2, hold_undetermined=False)
    two = calibrate(sw, base, ["d", "alpha0"], starts=2)
    assert set(res.held) == {"r2_specific", "xi"} and res.hold_refused == []
    assert res.holds and all(h.accepted for h in res.holds)
    last = res.hold
    assert set(last.names) == {"r2_specific", "xi"}
    assert last.threshold == pytest.approx(CHI2_95_2 / 2, rel=1e-3)
    assert last.cost_before == pytest.approx(all_free.cost, rel=1e-6)
    assert last.cost_after == pytest.approx(two.cost, rel=1e-6)
    assert res.cost == pytest.approx(last.cost_after, rel=1e-12)
    assert 0 <= last.increase <= last.threshold
    assert "held r2_specific, xi" in res.hold_line() or "held xi, r2_specific" in res.hold_line()
    assert "hold: held" in res.summary()
    assert all(h["accepted"] for h in res.to_dict()["holds"])


def test_no_hold_records_nothing(base, wide_sweep):
    res = calibrate(wide_sweep, base, [FreeParameter("d", 1e-11, 3.98e-11), "alpha0"], starts=1,
                    hold_undetermined=False)
    assert res.holds == [] and res.hold is None and res.hold_refused == [] and res.hold_line() == ""
    assert res.to_dict()["holds"] == []


def test_always_holds_and_says_the_test_failed(base, wide_sweep):
    free = [FreeParameter("d", 1e-11, 3.98e-11), "alpha0"]
    res = calibrate(wide_sweep, base, free, starts=1, hold_undetermined="always")
    assert res.held == ["d"] and res.values["d"] == base.d and res.hold_refused == []
    h = res.hold
    assert h.accepted and not h.within_test and h.increase > 100 * h.threshold
    assert "ABOVE" in res.hold_line() and "hold_undetermined='always'" in res.message


def test_a_refused_hold_under_a_gross_misfit_widens_without_overflow():
    """The seed 000 sensor fit to the printed model (χ² ≈ 6000 on 57 dof): with the default hold
    test r2' (at its bound, an interval of thousands of decades) is not held; widening that
    interval by the Birge ratio overflowed a float power before."""
    from physmodel.parameter_sets import derivation as sc

    b = sc.sensor_base()
    free = [FreeParameter(n, lo, hi, "log", -abs(b.a0) if n == "a0" else None) for n, lo, hi in sc.SENSOR_FREE]
    res = calibrate(sc.printed_sensor_sweep(), b, free, kind="sensor", starts=4)
    assert not res.adequate and "r2_specific" in res.hold_refused
    lo, hi = res.ci_lower["r2_specific"], res.ci_upper["r2_specific"]
    assert 0 < lo <= res.values["r2_specific"] <= hi < 1e301
