"""The papers' order-selection claims that the calibrated physics sweeps reproduce.

Protocols as printed: seed 001 — 30 log-spaced lines on 0.1–9 Hz at 19 and 55 °C on the
calibrated actuator (``seed001_actuator``); seed 002 — 60 log-spaced lines on 0.1–100 Hz at
300 K on the Table-3 sample (``seed002_table3``, 4 mm wide).  Noise 0.3 dB / 2° per line, given
to the fits as per-line standard deviations.  Every number is computed here by fitting; the
oracle is the published claim (data/published.toml) and the noise-free response.

Not reproduced on these sweeps (benchmark section 4, reported, deliberately not asserted):
seed 001 "fourth order adds little over third" (4/4 error ≈ 0.33 × 3/3: the noise-free 3/3
bias ≈ 0.13 is far above the noise, the 4/4 bias ≈ 0.004 below it; reproduced only in the
r1' = 2 Ω sensitivity case) and "often one very large negative pole"; seed 002 "4 poles /
1 zero misses the response" (the physics is fitted at 99.8 % noise-free by 4p/1z; the paper's
misfit is of measured data).
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
    # "clearly worse at every temperature": more than three times the third-order error at each T
    assert all(a > 3 * b for a, b in zip(e22, e33))


def test_seed001_strictly_proper_third_order_fits_no_better(seed001):
    _, rep = seed001
    e23, e33 = rep.row(2, 3).relative_rms_error, rep.row(3, 3).relative_rms_error
    assert all(a >= 0.95 * b for a, b in zip(e23, e33))


def test_seed001_third_order_has_a_complex_rhp_zero_pair_at_each_temperature(seed001):
    sweep, _ = seed001
    for temp in (19.0, 55.0):
        z = RationalFit(3, 3).fit(sweep.select(temp)).model.zeros()
        pair = z[(z.real > 0) & (np.abs(z.imag) > 1e-9)]
        assert pair.size == 2 and np.isclose(pair[0], np.conj(pair[1]))


def test_seed002_five_poles_two_zeros_reach_the_printed_fit():
    model = physmodel.ActuatorModel(physmodel.get_parameter_set("seed002_table3"))
    f_hz = np.geomspace(0.1, 100.0, 60)
    sweep = synthesize_sweep(model, "M", f_hz, [26.85], NOISE, seed=41)
    exact = synthesize_sweep(model, "M", f_hz, [26.85], None)
    res = RationalFit(2, 5).fit(sweep)
    assert res.converged and res.stability.stable
    assert fit_percent(res.model.frequency_response(f_hz), sweep.response) >= 92.5   # printed: 92.57 %, 92.96 %
    # the shortfall from 100 % is the noise, not the model: against the noise-free response the
    # fit is far better than against the data (≈ 98 % vs ≈ 94.6 %)
    fit_truth = fit_percent(res.model.frequency_response(f_hz), exact.response)
    assert fit_truth >= 97.0
    assert fit_truth > fit_percent(res.model.frequency_response(f_hz), sweep.response) + 2.0
