"""The error predicted on the strip from a surrogate's misfit to measured data
(:mod:`surrogate.strip_check`), against closed-form values: a constant relative misfit m gives
exactly |m| for any in-band signal; a sine sees |m(f0)|; between two temperatures the misfit
interpolates linearly; measurement noise is removed on average (debiased |m|² − σ²)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from physmodel.data.sweep import FrequencySweep
from surrogate.strip_check import misfit_to_data, predicted_error


class _Model:
    """G(f, T) = 1/(1 + j f/3) · (1 + T/100): a stand-in surrogate with the RationalModel call."""

    def frequency_response(self, f, T, extrapolate=False):
        f = np.asarray(f, float)
        return (1.0 / (1.0 + 1j * f / 3.0)) * (1.0 + float(T) / 100.0)


def _sweep(temps, f, ratio, sdb=None, sdeg=None):
    """H = G·ratio(f, T) at every (T, f)."""
    G = _Model()
    T = np.repeat(temps, f.size)
    F = np.tile(f, len(temps))
    H = np.concatenate([G.frequency_response(f, t) * ratio(f, t) for t in temps])
    kw = {}
    if sdb is not None:
        kw = dict(magnitude_std_db=np.full(F.size, sdb), phase_std_deg=np.full(F.size, sdeg))
    return FrequencySweep(frequency_hz=F, temperature_c=T.astype(float), response=H, input_name="voltage",
                          input_unit="V", output_name="tip_displacement", output_unit="mm", **kw)


def _signal(kind="multitone", fs=200.0, dur=40.0):
    t = np.arange(int(fs * dur)) / fs
    if kind == "sine":
        return t, np.sin(2 * np.pi * 1.25 * t)
    rng = np.random.default_rng(3)
    y = sum(rng.uniform(0.5, 1) * np.sin(2 * np.pi * fk * t + rng.uniform(0, 6)) for fk in (0.3, 0.7, 1.5, 2.2))
    return t, y


F = np.logspace(-1, 1, 25)


def test_constant_misfit_is_predicted_exactly():
    m0 = 0.02 * np.exp(0.7j)
    mis = misfit_to_data(_Model(), _sweep([20.0, 40.0], F, lambda f, t: 1 + m0))
    t, r = _signal()
    pe = predicted_error(mis, 31.0, t, r)
    assert pe.rms == pytest.approx(abs(m0), rel=1e-9)
    assert pe.bound == pytest.approx(abs(m0), rel=1e-9)       # no noise declared: the bound is the value
    assert pe.checked and pe.neighbours_c == (20.0, 40.0)


def test_a_sine_sees_the_misfit_at_its_frequency():
    # m(f) = 0.01·log10(f)+0.03 (linear in log f, so the log-f interpolation is exact)
    mis = misfit_to_data(_Model(), _sweep([25.0], F, lambda f, t: 1 + 0.01 * np.log10(f) + 0.03))
    t, r = _signal("sine")
    pe = predicted_error(mis, 25.0, t, r)
    assert pe.rms == pytest.approx(0.01 * math.log10(1.25) + 0.03, rel=1e-3)


def test_the_misfit_interpolates_linearly_between_temperatures():
    mis = misfit_to_data(_Model(), _sweep([20.0, 40.0], F, lambda f, t: 1 + (0.01 if t == 20.0 else 0.03)))
    t, r = _signal()
    pe = predicted_error(mis, 25.0, t, r)            # weights 0.75 / 0.25
    assert pe.rms == pytest.approx(0.75 * 0.01 + 0.25 * 0.03, rel=1e-9)
    assert pe.bound == pytest.approx(0.03, rel=1e-9)
    out = predicted_error(mis, 50.0, t, r)
    assert out.extrapolated and not out.checked and out.rms == pytest.approx(0.03)


def test_noise_is_removed_on_average_and_the_bound_covers_the_truth():
    rng = np.random.default_rng(11)
    f = np.logspace(-1, 1, 400)
    sdb, sdeg = 0.08, 0.5
    s_rel = math.hypot(sdb * math.log(10) / 20, math.radians(sdeg))
    true = 0.01

    def ratio(ff, T):
        noise = (rng.standard_normal(ff.size) * sdb * math.log(10) / 20
                 + 1j * rng.standard_normal(ff.size) * math.radians(sdeg))
        return (1 + true) * np.exp(noise)

    mis = misfit_to_data(_Model(), _sweep([20.0, 30.0], f, ratio, sdb, sdeg))
    assert mis.rms[0] > 1.2 * true                        # raw misfit is inflated by the noise (s_rel ~ 1 %)
    t, r = _signal()
    pe = predicted_error(mis, 25.0, t, r)
    assert abs(pe.rms - true) < 0.35 * true               # smoothed over the lines and debiased
    assert true < pe.bound < true + 2 * s_rel             # (|m| + 2σ) with σ of the smoothed misfit: covers the truth


def test_signal_power_outside_the_measured_band_is_reported():
    mis = misfit_to_data(_Model(), _sweep([20.0], np.logspace(0, 1, 10), lambda f, t: 1.01))
    t = np.arange(8000) / 200.0
    r = np.sin(2 * np.pi * 0.2 * t) + 0.1 * np.sin(2 * np.pi * 2.0 * t)      # most power at 0.2 Hz, below 1 Hz
    pe = predicted_error(mis, 20.0, t, r)
    assert pe.out_of_band_power > 0.9 and not pe.checked
    assert "outside the measured band" in pe.sentence()


def test_an_inversion_residual_adds_with_its_phase():
    # G·u = (1 + ε) r (an inverse that is 1 % off in gain): e = m·(1 + ε) r + ε r exactly
    m0, eps = 0.02, 0.01
    mis = misfit_to_data(_Model(), _sweep([20.0], F, lambda f, t: 1 + m0))
    t, r = _signal()
    pe = predicted_error(mis, 20.0, t, r, inversion_residual=eps * r)
    assert pe.rms == pytest.approx(m0 * (1 + eps) + eps, rel=1e-9)
    assert pe.inversion == pytest.approx(eps, rel=1e-9)
    pe = predicted_error(mis, 20.0, t, r, inversion_residual=-eps * r)        # opposite sign: they cancel
    assert pe.rms == pytest.approx(abs(m0 * (1 - eps) - eps), rel=1e-9)


def test_a_sharp_misfit_is_not_smoothed_away():
    # a 2 % bump 0.1 decade wide at 2 Hz (a mis-placed resonance), 0.2 % line noise: the χ² test
    # rejects the low degrees, so the value at the bump is kept
    rng = np.random.default_rng(5)
    f = np.logspace(-1, 1, 60)
    sig = 0.002

    def ratio(ff, T):
        bump = 0.02 * np.exp(-((np.log10(ff) - np.log10(2.0)) / 0.05) ** 2)
        return 1 + bump + sig / math.sqrt(2) * (rng.standard_normal(ff.size) + 1j * rng.standard_normal(ff.size))

    mis = misfit_to_data(_Model(), _sweep([20.0], f, ratio, sdb=sig / math.sqrt(2) * 20 / math.log(10),
                                          sdeg=math.degrees(sig / math.sqrt(2))))
    t = np.arange(20000) / 500.0
    pe = predicted_error(mis, 20.0, t, np.sin(2 * np.pi * 2.0 * t))
    assert pe.rms == pytest.approx(0.02, rel=0.15)


def test_power_outside_a_band():
    from surrogate.strip_check import power_outside

    t = np.arange(10000) / 1000.0
    r = np.sin(2 * np.pi * 2.0 * t) + 0.5 * np.sin(2 * np.pi * 50.0 * t)      # powers 0.5 and 0.125
    assert power_outside(t, r, (0.1, 10.0)) == pytest.approx(0.125 / 0.625, rel=1e-6)
    assert power_outside(t, r, (0.1, 100.0)) == pytest.approx(0.0, abs=1e-9)
