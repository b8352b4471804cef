"""Seed 002 §2.2.4: the finite-order Taylor model and its claim that third order is needed."""

from __future__ import annotations

import control
import numpy as np
import pytest

from physmodel import ISOTHERMAL, ActuatorModel, get_parameter_set
from physmodel.errors import IPMCError
from physmodel.reduced import reduced_frequency_response, taylor_coefficients


def test_taylor_coefficients_match_the_series_of_x_sinh_and_cosh():
    # P_3(u) = 1/2 + (1/6 - 1/24) u + (1/120 - 1/720) u^2 + u^3/5040
    P, Q = taylor_coefficients(3)
    np.testing.assert_allclose(P, [1 / 2, 1 / 6 - 1 / 24, 1 / 120 - 1 / 720, 1 / 5040])
    np.testing.assert_allclose(Q, [1, 1 / 2, 1 / 24, 1 / 720])
    with pytest.raises(IPMCError, match="taylor_order"):
        taylor_coefficients(0)


def _errors_db(order):
    m = ActuatorModel(get_parameter_set("seed002_table3", laws=ISOTHERMAL))
    f = np.logspace(np.log10(2.0), np.log10(30.0), 120)     # around the first mode (12 Hz)
    exact = m.frequency_response(f, [26.85])["M"][0, 0]
    red = reduced_frequency_response(m.state([26.85]), f, order)
    return np.max(np.abs(20 * np.log10(np.abs(red / exact)))), np.max(np.abs(np.degrees(np.angle(red / exact))))


def test_third_order_matches_around_the_first_mode_lower_orders_do_not():
    e1, e2, e3 = (_errors_db(k) for k in (1, 2, 3))
    assert e3[0] < 0.5 and e3[1] < 3.0              # third order: within 0.5 dB / 3 deg
    assert e2[0] > 1.0 and e1[0] > 3.0              # lower orders miss by > 1 dB
    assert e1[0] > e2[0] > e3[0]


def test_reduced_tf_is_a_control_object_with_the_model_dc_gain_limit():
    m = ActuatorModel(get_parameter_set("seed002_table3", laws=ISOTHERMAL))
    tf = m.reduced(26.85, taylor_order=3)
    assert isinstance(tf, control.TransferFunction)
    assert np.all(np.real(tf.poles()) < 0)
    # DC of the reduced model: tanh(gamma0) ~ 1 is the only approximation at s = 0 and X_3(u0)
    dc_exact = m.dc_gain([26.85])["M0"][0, 0]
    assert float(np.real(tf(0))) == pytest.approx(dc_exact, rel=1e-3)
    f = np.array([3.0, 12.0])
    np.testing.assert_allclose(tf(2j * np.pi * f), reduced_frequency_response(m.state([26.85]), f, 3), rtol=1e-9)
