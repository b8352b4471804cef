"""The frequency-domain simulation of a record at rest (:mod:`physmodel.data.fftsim`) against
independent oracles: a pure delay of a whole number of samples shifts the drive exactly, and a
first-order lag matches scipy's state-space simulation (``scipy.signal.lsim``)."""

from __future__ import annotations

import numpy as np
from scipy import signal

from physmodel.data.fftsim import simulate_at_rest


class _TF:
    def __init__(self, fn):
        self.fn = fn
        self.kind = "actuator"

    def response(self, f, T):
        return self.fn(2j * np.pi * np.asarray(f, float))[None, :]


def _drive(n=4000, fs=1000.0):
    t = np.arange(n) / fs
    w = np.sin(np.pi * t / t[-1]) ** 2                      # at rest at both ends
    return t, w * (np.sin(2 * np.pi * 3 * t) + 0.5 * np.sin(2 * np.pi * 11 * t))


def test_a_whole_sample_delay_shifts_the_drive():
    t, u = _drive()
    k = 37
    res = simulate_at_rest(_TF(lambda s: np.exp(-s * k / 1000.0)), 25.0, t, u)
    expected = np.concatenate([np.zeros(k), u[:-k]])
    assert np.max(np.abs(res.y - expected)) < 1e-10 * np.max(np.abs(u))


def test_a_first_order_lag_matches_lsim():
    t, u = _drive()
    a = 2 * np.pi * 5.0
    res = simulate_at_rest(_TF(lambda s: a / (s + a)), 25.0, t, u)
    # fine-grid lsim (linear interpolation of the input) as the oracle
    tf = np.linspace(0, t[-1], 16 * (t.size - 1) + 1)
    _, y, _ = signal.lsim(([a], [1, a]), np.interp(tf, t, u), tf)
    err = np.max(np.abs(res.y - y[::16])) / np.max(np.abs(y))
    assert err < 2e-3                    # the FFT treats u as band-limited, lsim as piecewise linear
    assert res.wraparound < 1e-4


def test_simulate_runs_a_model_with_a_delay_as_the_plain_model_shifted():
    """``timesim.simulate`` takes a model with effects (no finite realisation): a 12 ms delay
    gives the plain physics' output (through its vector-fitted realisation, another method)
    shifted by 12 samples."""
    from physmodel import ActuatorModel, EffectModel, get_parameter_set
    from physmodel.data.timesim import simulate

    p = get_parameter_set("seed001_actuator")
    fs, k = 1000.0, 12
    t = np.arange(8000) / fs
    u = np.sin(np.pi * t / t[-1]) ** 2 * np.sin(2 * np.pi * 1.5 * t)
    plain = simulate(ActuatorModel(p), 30.0, t, u).output
    delayed = simulate(EffectModel(p, "actuator", {"time_delay": {"delay": k / fs}}), 30.0, t, u)
    assert "frequency-domain" in delayed.metadata["realization"]
    np.testing.assert_allclose(delayed.output[k:], plain[:-k], atol=2e-3 * np.max(np.abs(plain)))
    assert np.max(np.abs(delayed.output[:k])) < 1e-3 * np.max(np.abs(plain))
