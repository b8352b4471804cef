"""Verdict semantics of ``diagnose`` (issue 27 item 5), on data the library did not make.

* another, non-closing candidate stopped at its candidate bound does not downgrade a correct,
  closing name to 'at bound';
* a two-parameter effect with one parameter collapsed to its off value is reported in its simpler
  form, not at a bound;
* a sign flip (the model with its sign reversed) is recognised and said, without advice to widen
  a bound;
* "a small residual misfit" only when the cost is near its expectation;
* the gain of relaxing a bound (what decides whether a bound matters) against a closed form.

Data: tests/discrepancy/independent_sensor.py (its own strip and chain elements, no physmodel
effect code) or analytic constructions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

try:
    from . import independent_sensor as isn
except ImportError:
    import independent_sensor as isn

from physmodel import get_parameter_set
from physmodel.data.sweep import FrequencySweep
from physmodel.estimation.discrepancy import diagnose
from physmodel.estimation.records import FreeParameter
from physmodel.estimation.verdicts import relax_gain, residual_sentence

F = isn.FREQUENCIES_HZ
SIG = 0.01 / math.sqrt(2)


def _base():
    return get_parameter_set("seed000_sensor_dev", T_ref=isn.START["T"])


def _free(p0):
    s = math.copysign(1.0, p0.a0)
    lo, hi = sorted((s * 1e-4, s * 1e3))
    return [FreeParameter("a0", lo, hi, "log", p0.a0), FreeParameter("d", 1e-15, 1e-9, "log", p0.d),
            FreeParameter("kappa_e", 1e-8, 1e-3, "log", p0.kappa_e)]


def _sweep(H, seed):
    rng = np.random.default_rng(seed)
    noisy = H * (1 + SIG * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)))
    return FrequencySweep(np.full(F.size, isn.TEMPERATURE_C), F, noisy * 1e3, np.full(F.size, 20 / math.log(10) * SIG),
                          np.full(F.size, math.degrees(SIG)), "tip_displacement", "mm", "current", "uA")


def _strip():
    b = dict(isn.START)
    b["d"] *= 1.2
    b["a0"] *= 0.8
    return b


def _run(H, cands, **kw):
    return diagnose(_sweep(H, 3), _base(), kind="sensor", free=_free(_base()), candidates=cands, null_draws=1000,
                    null_refits=0, baseline_starts=2, seed=1, **kw)


@pytest.fixture(scope="module")
def single_pole():
    """A single amplifier pole at 60 Hz (the generator's two-pole amplifier with its second pole
    10⁷ times higher), seen in 10-100 Hz."""
    return isn.response(_strip(), {"amplifier": {"f_a": 60.0, "ratio": 1e7}}, F)


def test_a_non_closing_candidate_at_its_bound_does_not_downgrade_the_closing_name(single_pole):
    # time_delay (first-order confusable with a pole) held below what it would need: significant,
    # stopped at its candidate bound, not closing the gap
    d = _run(single_pole, ["amplifier_bandwidth", "time_delay"], candidate_bounds={"time_delay.delay": (0.0, 2e-4)})
    td = d.candidates["time_delay"]
    assert td.significant and not td.closes_gap and any(a["status"] == "at" for a in td.at_bound)
    assert d.candidates["amplifier_bandwidth"].closes_gap
    assert d.verdict == "named" and d.named == ["amplifier_bandwidth"], d.message
    assert "time_delay.delay" in d.message and "not a reason to doubt" in d.message


def test_a_collapsed_second_time_constant_is_the_simpler_effect_not_at_bound(single_pole):
    d = _run(single_pole, ["amplifier_bandwidth", "time_delay"])
    assert d.verdict == "named" and d.named == ["amplifier_bandwidth"], d.message
    # one of the two time constants carries the 60 Hz pole, the other sits at its off value 0
    tau = sorted(d.final_effects["amplifier_bandwidth"].values())
    assert tau[1] == pytest.approx(1 / (2 * math.pi * 60.0), rel=0.05)
    assert len(d.reduced) == 1 and d.reduced[0]["effect"] == "amplifier_bandwidth" and d.reduced[0]["off"] == 0.0
    assert "simpler form" in d.message
    assert not any(a["name"] == d.reduced[0]["name"] for a in d.final_at_bound)
    assert d.to_dict()["reduced_to_simpler_form"][0]["name"] == d.reduced[0]["name"]


def test_a_sign_flip_is_recognised_and_said():
    H = -isn.response(_strip(), {}, F)          # the strip's response with its sign reversed
    d = _run(H, ["time_delay", "amplifier_bandwidth", "ac_coupling"])
    assert d.verdict == "unexplained" and d.named == []
    assert d.message.startswith("Sign flip") and "polarity" in d.message
    assert "widen" not in d.message and "Hz at" not in d.message.split(".")[0]
    assert abs(abs(d.sign_flip["phase_offset_deg"]) - 180.0) < 2.0 and d.sign_flip["magnitude_rms_db"] < 0.3
    assert d.sign_flip["recognised"] and 2 * d.sign_flip["refit_cost"] <= d.gap_threshold


def test_no_sign_flip_claimed_for_an_ordinary_gap(single_pole):
    d = _run(single_pole, ["time_delay"])               # a pole that a delay cannot close
    assert "Sign flip" not in d.message
    assert not d.sign_flip.get("recognised", False)


def test_small_residual_only_near_the_expectation():
    # 310 residuals, 5 free: E[cost] = 152.5, 2·cost threshold 357 (≈ the 0.99 quantile of χ²₃₀₅)
    expected, thr, excess = 152.5, 357.0, 1e5
    assert residual_sentence(170.0, expected, thr, excess) == ""                # within the gap threshold
    small = residual_sentence(200.0, expected, thr, excess)                      # 2·cost 400 ≤ 2·357 − 305
    assert "small residual misfit" in small
    big = residual_sentence(18 * expected, expected, thr, excess)
    assert "small" not in big and "significant" in big and "18× its expectation" in big


def _exp_model(x):
    """G = exp(c + θ x) over lines x (magnitude only): ln|data/G| is linear in (c, θ)."""
    def pm(vals):
        return np.array([np.exp(v["c"] + v["theta"] * x) + 0j for v in vals])
    return pm


def test_relax_gain_matches_the_projected_linear_oracle():
    x = np.linspace(-1.0, 2.0, 25)
    s = 0.01
    theta_true, upper = 0.5, 0.4
    data = FrequencySweep(np.full(x.size, 25.0), np.logspace(0, 1, x.size), np.exp(0.1 + theta_true * x) + 0j,
                          np.full(x.size, 20 / math.log(10) * s), np.full(x.size, math.degrees(s)))
    pm = _exp_model(x)
    free = [FreeParameter("c", -5.0, 5.0, "linear", 0.0), FreeParameter("theta", -1.0, upper, "linear", 0.0)]
    xc = x - x.mean()
    c_fit = 0.1 + (theta_true - upper) * x.mean()               # c refitted with θ at its bound
    vals = {"c": c_fit, "theta": upper}
    oracle = (theta_true - upper) ** 2 * float(xc @ xc) / s ** 2
    g = relax_gain(pm, vals, free, ["theta"], data, np.full(x.size, s), np.full(x.size, s))
    assert g["theta"] == pytest.approx(oracle, rel=1e-4)
    # the data lie inside the bound: relaxing it gains nothing
    free_lo = [free[0], FreeParameter("theta", 0.6, 2.0, "linear", 1.0)]
    g2 = relax_gain(pm, {"c": 0.1 + (theta_true - 0.6) * x.mean(), "theta": 0.6}, free_lo, ["theta"], data,
                    np.full(x.size, s), np.full(x.size, s))
    assert g2["theta"] > 0            # θ at its *lower* bound 0.6 > 0.5: the data want it lower (outward)
    free_hi = [free[0], FreeParameter("theta", 0.6, 2.0, "linear", 1.0)]
    g3 = relax_gain(pm, {"c": 0.1 + (theta_true - 2.0) * x.mean(), "theta": 2.0}, free_hi, ["theta"], data,
                    np.full(x.size, s), np.full(x.size, s))
    assert g3["theta"] == 0.0         # at the upper bound 2.0 the data want it lower (inward): no gain
