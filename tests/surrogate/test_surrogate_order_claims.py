"""The papers' order-selection claims on the seed parameter sets' physics sweeps.

Protocols as printed: seed 001 (Dong and Tan 2012, Sec. 2.3) — 30 log-spaced lines on 0.1–9 Hz at
19 and 55 °C on ``seed001_actuator`` (calibrated on the 19-vs-55 °C 7 dB trend only, so the order
claims are predictions); seed 002 (Sec. 5) — 60 log-spaced lines on 0.1–100 Hz at 300 K on the
Table-3 sample (``seed002_table3``, 4 mm wide).  Seed 001 sweeps carry 0.3 dB / 2° noise per line,
given to the fits as standard deviations (a measurement-like setting; the noise-free verdicts are
the same, see ``ipmc validate``).

Reproduced: second order clearly worse (read as at least twice the 3/3 error at each temperature);
a complex right-half-plane zero pair at each temperature; a strictly proper 2/3 model no better than
3/3 (true for any data, since 2/3 is 3/3 with b3 = 0: this checks the fitter, not the physics).
Not reproduced, asserted as measured: seed 001 "fourth order adds little over third" (4/4 error
≈ 0.3 × 3/3) and seed 002's 92.57 / 92.96 % fits of 5 poles / 2 zeros, which are against measured
responses: the noise-free physics is fitted at > 99.9 %, so the printed shortfall is dynamics or
noise the physics does not have.
"""

import numpy as np
import pytest

import physmodel
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from surrogate import RationalFit, fit_percent, order_selection

NOISE = MagnitudePhaseNoise(0.3, 2.0)


@pytest.fixture(scope="module")
def seed001():
    model = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    sweep = synthesize_sweep(model, "M", np.geomspace(0.1, 9.0, 30), [19.0, 55.0], NOISE, seed=31)
    return sweep, order_selection(sweep, orders=[(2, 2), (2, 3), (3, 3), (4, 4)])


def test_seed001_second_order_is_clearly_worse_at_every_temperature(seed001):
    _, rep = seed001
    assert all(all(r.converged) and all(r.stable) for r in rep.rows)
    e22, e33 = rep.row(2, 2).relative_rms_error, rep.row(3, 3).relative_rms_error
    assert all(a > 2 * b for a, b in zip(e22, e33))


def test_seed001_strictly_proper_third_order_fits_no_better(seed001):
    _, rep = seed001
    e23, e33 = rep.row(2, 3).relative_rms_error, rep.row(3, 3).relative_rms_error
    assert all(a >= b * (1 - 1e-3) for a, b in zip(e23, e33))        # nested classes; 1e-3: fitter tolerance


def test_seed001_fourth_order_adds_little_is_not_reproduced(seed001):
    _, rep = seed001
    e44, e33 = rep.row(4, 4).relative_rms_error, rep.row(3, 3).relative_rms_error
    assert all(a < 0.5 * b for a, b in zip(e44, e33)), "4/4 now adds little: update the docstring and ipmc validate"


def test_seed001_third_order_has_a_complex_rhp_zero_pair_at_each_temperature(seed001):
    sweep, _ = seed001
    for temp in (19.0, 55.0):
        z = RationalFit(3, 3).fit(sweep.select(temp)).model.zeros()
        pair = z[(z.real > 0) & (np.abs(z.imag) > 1e-9)]
        assert pair.size == 2 and np.isclose(pair[0], np.conj(pair[1]))


def test_seed002_five_poles_two_zeros_fit_the_physics_far_better_than_the_printed_fit():
    model = physmodel.ActuatorModel(physmodel.get_parameter_set("seed002_table3"))
    f_hz = np.geomspace(0.1, 100.0, 60)
    exact = synthesize_sweep(model, "M", f_hz, [26.85], None)
    res = RationalFit(2, 5).fit(exact)
    assert res.converged and res.stability.stable
    fit = fit_percent(res.model.frequency_response(f_hz), exact.response)
    assert fit > 99.0                  # printed: 92.57 % (sample 4), 92.96 % (sample 1), against measured data
