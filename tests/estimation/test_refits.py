"""The shared speed-ups of the discrepancy workflow (issue 27 item 6): warm starts searched as one
multi-start (``fit_parameters(initials=...)``: a later start stops in an earlier start's basin),
the multi-start record of a candidate refit, and the look-elsewhere scan that does not re-evaluate
grid points where the effect is off.

Oracles: the same fit run start by start (the search the multi-start replaces), an exact first-order
lag written here, and the scan without the shortcut (exactly equal, not close)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from physmodel.data.sweep import FrequencySweep
from physmodel.effects.base import EffectParameter
from physmodel.estimation.lsq import fit_parameters, joined_start
from physmodel.estimation.nullstats import scan_lr
from physmodel.estimation.records import FreeParameter
from physmodel.estimation.signatures import refit_spread

N = 40
F = np.logspace(-1, 2, N)
SIG = 0.01


def _lag(g, fc):
    return g / (1.0 + 1j * F / fc)


def _sweep(seed=3):
    rng = np.random.default_rng(seed)
    G = _lag(2.0, 5.0) * np.exp(SIG * (rng.standard_normal(N) + 1j * rng.standard_normal(N)))
    return FrequencySweep(np.full(N, 25.0), F, G, np.full(N, SIG * 20 / math.log(10)), np.full(N, math.degrees(SIG)),
                          "voltage", "V", "tip_displacement", "mm")


def _predict_many(values_list):
    return np.array([_lag(v["g"], v["fc"]) for v in values_list])


def _free(g, fc):
    return [FreeParameter("g", 0.1, 20.0, "log", g), FreeParameter("fc", 0.5, 50.0, "log", fc)]


def test_warm_starts_as_one_multistart_reach_the_same_optimum_and_join_it():
    data = _sweep()
    starts = [(1.5, 4.0), (2.05, 5.1), (0.3, 40.0)]
    alone = [fit_parameters(data, None, _free(*s), predict_many=_predict_many, identify=False) for s in starts]
    best_alone = min(alone, key=lambda r: r.cost)
    multi = fit_parameters(data, None, _free(*starts[0]), predict_many=_predict_many, identify=False,
                           initials=[{"g": g, "fc": fc} for g, fc in starts[1:]])
    assert len(multi.starts) == 3
    assert multi.cost == pytest.approx(best_alone.cost, rel=1e-9)
    for k in ("g", "fc"):
        assert multi.values[k] == pytest.approx(best_alone.values[k], rel=1e-6)
        assert multi.values[k] == pytest.approx({"g": 2.0, "fc": 5.0}[k], rel=0.02)    # the lag written here
    # the start next to the optimum stops in start 0's basin instead of converging again
    near = multi.starts[1]
    assert near.status == -2 and joined_start(near) == 0
    assert joined_start(multi.starts[0]) is None
    assert sum(s.nfev for s in multi.starts) < sum(s.nfev for r in alone for s in r.starts)
    spread = refit_spread(multi, ["baseline optimum", "baseline optimum", "user start"])
    assert spread["n_starts"] == 3 and spread["n_joined"] >= 1
    assert spread["n_at_best"] >= 2 and spread["best_origin"] == "baseline optimum"


AMP = EffectParameter("amp", "1", 0.0, 0.0, 5.0, 1.0)
CENTRE = EffectParameter("centre", "1", 0.5, -1.0, 2.0, 1.0)


def test_the_scan_skips_points_where_the_effect_is_off_and_gives_the_same_statistic():
    data = FrequencySweep(np.full(N, 25.0), F, np.ones(N, complex), np.full(N, 20 / math.log(10)),
                          np.full(N, math.degrees(1.0)), "voltage", "V", "tip_displacement", "mm")
    seen = []

    def predict_many(points):
        seen.append(len(points))
        return np.array([np.exp(p["bump.amp"] * np.exp(-((np.log10(F) - p["bump.centre"]) ** 2) / 0.18))
                         for p in points], dtype=complex)

    r0 = np.zeros(2 * N)
    Q0 = np.zeros((2 * N, 1))
    Q0[:N, 0] = 1.0 / math.sqrt(N)
    E = np.random.default_rng(5).standard_normal((2 * N, 500))
    Ep = E - Q0 @ (Q0.T @ E)
    args = (predict_many, {}, "bump", (AMP, CENTRE), np.array([False, True]), r0, data, np.ones(N), np.ones(N), Q0, Ep)
    full = scan_lr(*args)
    n_full = sum(seen)
    seen.clear()
    short = scan_lr(*args, is_off=lambda v: v["amp"] == AMP.off)
    np.testing.assert_array_equal(short, full)
    assert sum(seen) == n_full // 2           # the amplitude-off half of the grid is the baseline


def test_a_refit_from_several_origins_is_one_multistart_with_the_separate_refits_best():
    # the pair refits of a diagnosis: starts from several origins searched as one multi-start
    # (Refitter.refit(more=...)) instead of one fit per origin, each of which ran to the same optimum
    from physmodel.estimation.priors import PenalisedProblem
    from physmodel.estimation.refits import Refitter, StageCounter

    data = _sweep()

    def pm(values_list):                 # the baseline gain g; the candidate "lag" adds the pole fc
        return np.array([_lag(v["g"], v["lag.fc"]) if "lag.fc" in v else np.full(N, v["g"] + 0j)
                         for v in values_list])

    counter = StageCounter(pm)
    rf = Refitter(PenalisedProblem(data, counter.predict_many), [FreeParameter("g", 0.1, 20.0, "log", 1.0)],
                  {"lag": [EffectParameter("fc", "Hz", 50.0, 0.5, 50.0, 10.0)]}, {}, seed=0, max_nfev=200,
                  baseline_starts=1, counter=counter)
    origins = [("baseline optimum", {"g": 1.5}, [None, {"lag": {"fc": 4.0}}]),
               ("second", {"g": 2.05}, [{"lag": {"fc": 5.1}}]), ("third", {"g": 0.5}, [{"lag": {"fc": 20.0}}])]
    alone = [rf.refit(["lag"], sv, es) for _, sv, es in origins]
    best_alone = min(alone, key=lambda r: r.cost)
    one = rf.refit(["lag"], origins[0][1], origins[0][2], more=origins[1:])
    ms = one.metadata["refit_multistart"]
    assert ms["origins"] == ["baseline optimum", "baseline optimum", "second", "third"]
    assert len(one.starts) == 4 and ms["n_joined"] >= 1          # a later start stopped in an earlier basin
    # each start began at its own origin's values, the off value 50 Hz where no effect start is given
    # (review: a start of `more` taken from start_vals or from the first origin's effect starts
    # went unnoticed)
    expected = [v for _, sv, e_s in origins for es in e_s for v in (sv["g"], (es or {}).get("lag", {}).get("fc", 50.0))]
    assert [v for s in one.starts for v in (s.initial["g"], s.initial["lag.fc"])] == pytest.approx(expected, rel=1e-12)
    assert one.cost == pytest.approx(best_alone.cost, rel=1e-9)
    for k in ("g", "lag.fc"):
        assert one.values[k] == pytest.approx(best_alone.values[k], rel=1e-5)
    assert one.values["lag.fc"] == pytest.approx(5.0, rel=0.05)    # the lag written here
    assert sum(s.nfev for s in one.starts) < sum(s.nfev for r in alone for s in r.starts)
