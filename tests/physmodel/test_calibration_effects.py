"""calibrate(..., effects=...): physical parameters fitted with a measurement chain held fixed.

Oracle: sweeps synthesized from a known truth (parameter set and chain) with seeded noise of
known level; the chain's own effect (a pure delay) is checked against its closed form e^{−sτ}."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.effects import EffectModel
from physmodel.errors import IPMCError
from physmodel.estimation.calibration import calibrate, model_sweep

F = np.logspace(-1, 2, 40)
TEMPS = [25.0, 45.0]
CHAIN = {"time_delay": {"delay": 2e-3}}
FREE = ["d", "kappa_e", "E", "xi"]


@pytest.fixture(scope="module")
def problem():
    base = get_parameter_set("seed002_table3")
    truth = base.replace(d=base.d * 1.6, kappa_e=base.kappa_e * 0.8, E=base.E * 1.2, xi=base.xi * 1.3)
    sw = synthesize_sweep(EffectModel(truth, "actuator", CHAIN), "M", F, TEMPS,
                          noise=MagnitudePhaseNoise(0.1, 1.0), seed=11)
    return base, truth, sw


def test_the_chain_is_the_closed_form_delay(problem):
    _, truth, _ = problem
    plain = ActuatorModel(truth).frequency_response(F, TEMPS, quantities=("M",))["M"]
    chained = EffectModel(truth, "actuator", CHAIN).frequency_response(F, TEMPS, quantities=("M",))["M"]
    np.testing.assert_allclose(chained / plain, np.broadcast_to(np.exp(-2j * np.pi * F * 2e-3), plain.shape), rtol=1e-12)


def test_with_the_chain_the_truth_is_recovered_within_the_intervals(problem):
    base, truth, sw = problem
    res = calibrate(sw, base, FREE, starts=2, effects=CHAIN)
    assert res.converged and res.adequate and not res.held
    for n in FREE:
        assert res.ci_lower[n] <= getattr(truth, n) <= res.ci_upper[n], (n, res.values[n])
    assert res.metadata["effects"] == {"time_delay": {"delay": 2e-3}}
    # the overlay carries the chain: its residuals are the noise (2·cost ≈ 2N − nθ)
    G = model_sweep(res, sw).response
    assert np.abs(np.angle(sw.response / G)).max() < np.radians(5.0)


def test_without_the_chain_the_fit_says_it_does_not_fit(problem):
    base, _, sw = problem
    res = calibrate(sw, base, FREE, starts=2)
    assert not res.adequate and "MODEL INADEQUATE" in res.message


def test_bad_effects_are_refused(problem):
    base, _, sw = problem
    with pytest.raises(IPMCError, match="effects must map"):
        calibrate(sw, base, FREE, effects=[("time_delay", 1e-3)])
    with pytest.raises(IPMCError):
        calibrate(sw, base, FREE, effects={"no_such_effect": {}})
    with pytest.raises(IPMCError, match="delay"):
        calibrate(sw, base, FREE, effects={"time_delay": {"delay": -1.0}})


def test_effects_that_are_off_give_the_plain_calibration(problem):
    base, truth, _ = problem
    sw = synthesize_sweep(ActuatorModel(truth), "M", F, TEMPS, noise=MagnitudePhaseNoise(0.1, 1.0), seed=3)
    a = calibrate(sw, base, FREE, starts=1)
    b = calibrate(sw, base, FREE, starts=1, effects={"time_delay": {"delay": 0.0}})
    for n in FREE:
        assert b.values[n] == pytest.approx(a.values[n], rel=1e-6)
        assert b.ci_upper[n] == pytest.approx(a.ci_upper[n], rel=1e-4)
    assert "effects" in b.metadata and "effects" not in a.metadata
