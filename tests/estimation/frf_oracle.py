"""Independent generators for the FRF tests and benchmark: python-control plants discretised
exactly (zero-order hold), simulated sample by sample with ``scipy.signal.lfilter`` and evaluated
with python-control, so neither the data nor the truth passes through physmodel.estimation.

For a ZOH discretisation the sampled map u[k] → y[k] *is* the discrete system, so its frequency
response H_d(e^{jωT}) is the exact truth for any sampled input (white noise, multisine, steps of
sines); it is not the continuous H(jω)."""

from __future__ import annotations

import control
import numpy as np
from scipy import signal


def resonant(fs: float, f_n: float = 50.0, zeta: float = 0.2, gain: float = 1.0):
    """ZOH discretisation of gain·ω_n²/(s² + 2ζω_n s + ω_n²)."""
    wn = 2 * np.pi * f_n
    return control.c2d(control.tf([gain * wn**2], [1.0, 2 * zeta * wn, wn**2]), 1.0 / fs, "zoh")


def slow_resonant(fs: float, tau_s: float = 0.2, f_n: float = 20.0, zeta: float = 0.3):
    """A resonance in series with a slow pole (time constant ``tau_s``) and a zero: transients
    that outlive many periods of a fast step."""
    wn = 2 * np.pi * f_n
    sysc = control.tf([wn**2, wn**2 * 3.0], [1.0, 2 * zeta * wn, wn**2]) * control.tf([1.0], [tau_s, 1.0])
    return control.c2d(sysc, 1.0 / fs, "zoh"), sysc


def coefficients(sysd):
    """(b, a) for lfilter, the numerator padded to the denominator's length (the delay of a
    strictly proper system)."""
    b = np.ravel(sysd.num[0][0]).astype(float)
    a = np.ravel(sysd.den[0][0]).astype(float)
    return np.concatenate([np.zeros(a.size - b.size), b]), a


def simulate(sysd, u):
    b, a = coefficients(sysd)
    return signal.lfilter(b, a, u)


def truth(sysd, frequency_hz, fs: float):
    """H_d(e^{j2πf/fs}) evaluated by python-control."""
    return np.asarray(sysd(np.exp(2j * np.pi * np.asarray(frequency_hz) / fs)), dtype=complex).reshape(-1)


def white_record(sysd, n: int, seed: int, output_noise: float = 0.0, input_noise: float = 0.0,
                 warmup: int = 4000):
    """Unit-variance white input through the plant (after a warm-up, so no start transient), with
    white measurement noise of the given standard deviations on output and input."""
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n + warmup)
    y = simulate(sysd, u)[warmup:]
    u = u[warmup:]
    return u + input_noise * rng.standard_normal(n), y + output_noise * rng.standard_normal(n), u, y


def stepped_record(sysd, frequency_hz, starts_s, stops_s, fs: float, amplitude: float = 1.0):
    """Steps of sines from phase zero at each start (written here, not by the excitation module)."""
    n = int(round(stops_s[-1] * fs))
    t = np.arange(n) / fs
    i = np.clip(np.searchsorted(starts_s, t + 0.5 / fs, side="right") - 1, 0, None)
    u = amplitude * np.sin(2 * np.pi * np.asarray(frequency_hz)[i] * (t - np.asarray(starts_s)[i]))
    return t, u, simulate(sysd, u)
