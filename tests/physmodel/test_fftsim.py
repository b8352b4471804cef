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
