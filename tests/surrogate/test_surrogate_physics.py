"""Surrogate fits on real physmodel sweeps (Chen–Tan, infinite-dimensional: no exact answer).

Seed 001's protocol on its calibrated actuator (``seed001_actuator``): 30 log-spaced lines on
0.1–9 Hz at the ten bath temperatures, 35 and 45 °C held out, noise 0.2 dB / 1°.  On this
physics the response needs a fourth-order model (benchmark section 4), and per-temperature zpk
entries of a 4/4 fit do not interpolate (the papers' two-stage method fails), while the joint
scheduled fit predicts the held-out temperatures close to the noise-free response.

Robustness (benchmark, robustness table): the zpk 4/4 joint fit converged and was stable for
all noise seeds 1–10 of this protocol once far-out zeros were bounded and a slow best solve is
resumed (before: 7/10).  The fits are fitted to FrequencySweep objects directly.
"""

import numpy as np
import pytest

import physmodel
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from surrogate import ScheduledFit, from_sweep, order_selection, relative_rms_error

TEMPS = [19.0, 21.5, 23.3, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0]
HELD_OUT = [35.0, 45.0]
F_HZ = np.geomspace(0.1, 9.0, 30)


def _model():
    return physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))


@pytest.fixture(scope="module")
def sweeps():
    noisy = synthesize_sweep(_model(), "M", F_HZ, TEMPS, MagnitudePhaseNoise(0.2, 1.0), seed=2)
    exact = synthesize_sweep(_model(), "M", F_HZ, TEMPS, None)
    return noisy, exact


@pytest.fixture(scope="module")
def joint(sweeps):
    data, _ = sweeps
    return ScheduledFit("zpk", 4, 4, 2).fit(data.exclude(HELD_OUT))


def test_from_sweep_carries_units_and_uncertainty(sweeps):
    data, exact = sweeps
    data = from_sweep(data)
    assert (data.input_unit, data.output_unit) == ("V", "mm")
    assert data.has_uncertainty and np.allclose(data.magnitude_std_db, 0.2) and np.allclose(data.phase_std_deg, 1.0)
    assert np.array_equal(data.frequency_hz, exact.frequency_hz)
    assert np.array_equal(data.temperature_c, exact.temperature_c)


def test_joint_fit_predicts_held_out_temperatures(sweeps, joint):
    data, exact = sweeps
    papers = ScheduledFit("zpk", 4, 4, 2, method="two-stage", per_temperature="levy",
                          raise_on_failure=False).fit(data.exclude(HELD_OUT))
    assert joint.converged
    for temp in HELD_OUT:
        k = data.temperature_c == temp
        truth = exact.response[k]
        e_joint = relative_rms_error(joint.model.frequency_response(data.frequency_hz[k], temp), truth)
        e_papers = relative_rms_error(papers.model.frequency_response(data.frequency_hz[k], temp), truth)
        assert e_joint < 0.02                      # noise floor of one line is ~0.029
        assert e_joint <= 0.5 * e_papers           # issue goal, against the papers' two-stage method


def test_joint_fit_is_stable_on_a_dense_temperature_grid(joint):
    check = joint.model.stability_check(501)
    assert check.stable and check.max_pole_real_part_rad_s < -0.1
    for temp in np.linspace(19.0, 55.0, 37):
        assert np.all(joint.model.poles(temp).real < 0)


def test_order_selection_on_physics_second_order_is_clearly_worse(sweeps):
    data, _ = sweeps
    sub = from_sweep(data)
    sub = sub.select(np.isin(sub.temperature_c, [19.0, 55.0]))
    rep = order_selection(sub.frequency_hz, sub.temperature_c, sub.response, [(2, 2), (3, 3), (4, 4)],
                          sub.magnitude_std_db, sub.phase_std_deg)
    e2, e3, e4 = (rep.row(k, k).worst_relative_rms_error for k in (2, 3, 4))
    assert all(all(r.stable) for r in rep.rows)
    assert e2 > 3 * e3 and e3 > e4            # the error falls with order up to 4/4
    assert e4 < 0.05                          # 4/4 reaches the noise floor (≈ 0.029)


def test_joint_fit_keeps_the_best_start_on_the_sensor_sweep():
    """Seed 000's sensor protocol (10–100 Hz, 35/45 °C held out), zpk 2/2 cubic: the joint NLP
    from the two-stage start converges to a poor local minimum (cost ≈ 112, 35 °C error ≈ 3900);
    the constant start reaches cost ≈ 0.49.  The fit must keep the better one."""
    temps = [23.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 60.0, 65.0]
    sensor = physmodel.SensorModel(physmodel.get_parameter_set("seed000_sensor_dev"))  # where the poor basin was found
    f_hz = np.geomspace(10.0, 100.0, 60)
    data = from_sweep(synthesize_sweep(sensor, "S", f_hz, temps, MagnitudePhaseNoise(0.2, 1.0), seed=2))
    exact = synthesize_sweep(sensor, "S", f_hz, temps, None)
    res = ScheduledFit("zpk", 2, 2, 3).fit_data(data.select(~np.isin(data.temperature_c, HELD_OUT)))
    joint_costs = [e["cost"] for e in res.history if e["stage"].startswith("joint") and e["converged"]]
    assert res.cost == pytest.approx(min(joint_costs)) and res.cost < 1.0
    assert max(e.relative_rms_error for e in res.per_temperature) < 0.05
    for temp in HELD_OUT:
        k = data.temperature_c == temp
        assert relative_rms_error(res.model.frequency_response(f_hz, temp), exact.response[k]) < 0.02


def test_sensor_coefficients_fit_is_stable_when_the_losing_start_reaches_an_unstable_optimum():
    """Seed 000's sensor protocol (seed000_sensor physics, 1-100 Hz, seven temperatures, 0.1 dB /
    1°, noise seed 3), the scenario's 4/4 coefficient schedule, degree 1.  On this realisation
    the unconstrained optimum reached from both starts has a pole at about +100 rad/s at the
    cold end; the start that lost the race ends 'Stopped_Early' on it, and was returned as the
    answer (unstable, unconverged) instead of being re-solved with the Hurwitz constraints.
    Checked with numpy's roots of the returned denominators on a dense grid."""
    model = physmodel.SensorModel(physmodel.get_parameter_set("seed000_sensor"))
    temps = [23.0, 25.0, 30.0, 40.0, 50.0, 60.0, 65.0]
    data = synthesize_sweep(model, "S", np.geomspace(1.0, 100.0, 40), temps, MagnitudePhaseNoise(0.1, 1.0), seed=3)
    res = ScheduledFit("coefficients", 4, 4, 1).fit(data)
    assert res.converged
    worst = max(np.max(np.roots(res.model.coefficients(T)[1]).real) for T in np.linspace(23.0, 65.0, 1001))
    assert worst < 0
