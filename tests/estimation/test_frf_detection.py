"""Reading the excitation from the input (physmodel.estimation.excitation_detection), clipping
(physmodel.estimation.clipping) and the estimate that follows (physmodel.estimation.frf.estimate_frf).

The signals are written here (Schroeder multisines by an inverse FFT of a line spectrum chosen
here, steps of sines, white noise) and the plant is a resonance discretised and filtered with
scipy.signal, so neither the records nor the truth pass through the library's excitation or
simulation code."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from physmodel.errors import IPMCError
from physmodel.estimation.clipping import detect_clipping
from physmodel.estimation.excitation_detection import detect_excitation
from physmodel.estimation.frf import estimate_frf
from physmodel.estimation.frf_estimate import FRFWarning
from physmodel.estimation.stepped import stepped_sine

FS = 1000.0
LN = math.log(10.0) / 20.0
WN = 2 * np.pi * 60.0
B, A = signal.cont2discrete(([WN**2], [1.0, 2 * 0.1 * WN, WN**2]), 1 / FS, "zoh")[:2]
B = np.ravel(B)


def plant(u):
    return signal.lfilter(B, A, u)


def truth(f):
    z = np.exp(2j * np.pi * np.asarray(f) / FS)
    return np.polyval(B, z) / np.polyval(A, z)


def schroeder(N, lines):
    X = np.zeros(N // 2 + 1, dtype=complex)
    k = np.asarray(lines)
    X[k] = N / 2 * np.exp(-1j * np.pi * np.arange(k.size) * (np.arange(k.size) + 1) / k.size)
    x = np.fft.irfft(X, N)
    return x / np.sqrt(np.mean(x**2))


def t2_band(nu, n_terms, k=4.0):
    mean = nu / (nu - 2)
    var = 3 * nu**2 / ((nu - 2) * (nu - 4)) - mean**2
    return mean, k * math.sqrt(var / n_terms)


LINES = np.unique(np.round(np.geomspace(2, 300, 40)).astype(int))      # of a 1000-sample period


# ------------------------------------------------------------------------------------- detection
@pytest.mark.parametrize("input_noise", [0.0, 0.05])
def test_period_and_exactly_the_excited_lines_are_found(input_noise):
    rng = np.random.default_rng(3)
    u = np.tile(schroeder(1000, LINES), 7)[300:]                # the record starts mid-period
    exc = detect_excitation(FS, u + input_noise * rng.standard_normal(u.size))
    assert exc.kind == "periodic" and exc.period_samples == 1000
    np.testing.assert_array_equal(exc.lines, LINES)


def test_odd_lines_of_a_longer_period_are_found_not_a_shorter_period():
    u = np.tile(schroeder(2048, np.arange(1, 400, 2)), 4)
    exc = detect_excitation(FS, u)
    assert exc.period_samples == 2048
    np.testing.assert_array_equal(exc.lines, np.arange(1, 400, 2))


def test_stepped_sine_and_random_are_told_apart():
    rng = np.random.default_rng(4)
    f = np.array([3.0, 7.3, 19.1, 55.7, 140.2])
    n_step = np.ceil((0.4 + 12 / f) * FS).astype(int)
    starts = np.concatenate([[0], np.cumsum(n_step)[:-1]])
    u = np.concatenate([np.sin(2 * np.pi * fi * np.arange(m) / FS) for fi, m in zip(f, n_step)])
    exc = detect_excitation(FS, u + 0.01 * rng.standard_normal(u.size))
    assert exc.kind == "stepped_sine"
    np.testing.assert_allclose(exc.step_frequency_hz, f, rtol=2e-3)
    assert np.all(exc.step_start_s >= starts / FS - 2 / FS) and np.all(exc.step_start_s < starts / FS + 2 / f)
    assert detect_excitation(FS, rng.standard_normal(50_000)).kind == "random"
    with pytest.raises(IPMCError, match="constant"):
        detect_excitation(FS, np.ones(1000))


# ------------------------------------------------------------------------------------- estimates
def test_periodic_estimate_holds_every_excited_line_and_its_sigma_is_calibrated():
    """Plant started from rest: the transient periods are found and dropped; errors over σ are
    Student t with ν = 2(P − 1) over 12 records."""
    t2 = []
    for seed in range(12):
        rng = np.random.default_rng(100 + seed)
        u = np.tile(schroeder(1000, LINES), 10)
        y = plant(u) + 0.05 * rng.standard_normal(u.size)
        e = estimate_frf(FS, u + 1e-4 * rng.standard_normal(u.size), y)
        np.testing.assert_array_equal(e.frequency_hz, LINES * FS / 1000)
        assert e.method == "periodic_h1" and e.settings["transient_periods"] >= 1 and e.warnings == ()
        d = np.log(e.response[0] / truth(e.frequency_hz))
        t2 += [(d.real / (e.magnitude_std_db[0] * LN))**2, (d.imag / np.radians(e.phase_std_deg[0]))**2]
    P = e.settings["periods_used"]
    mean, band = t2_band(2 * (P - 1), np.concatenate(t2).size)
    assert abs(np.concatenate(t2).mean() - mean) < band, (np.concatenate(t2).mean(), mean, band)


def test_detected_steps_give_the_stepped_sine_estimate():
    rng = np.random.default_rng(5)
    f = np.array([4.0, 11.5, 31.0, 63.0, 97.0, 180.0])
    n_step = np.ceil((0.5 + 16 / f) * FS).astype(int)
    u = np.concatenate([np.sin(2 * np.pi * fi * np.arange(m) / FS) for fi, m in zip(f, n_step)])
    y = plant(u) + 0.01 * rng.standard_normal(u.size)
    e = estimate_frf(FS, u, y)
    assert e.method == "stepped_sine" and e.settings["excitation"].startswith("stepped sine: 6 steps")
    np.testing.assert_allclose(e.frequency_hz, f, rtol=1e-3)
    d = np.log(e.response[0] / truth(e.frequency_hz))
    assert np.all(np.abs(d.real) < 5 * e.magnitude_std_db[0] * LN)
    # the truth at the exact frequency: the detected frequency's error is far below σ
    exact = stepped_sine(FS, u, y, f, np.cumsum(np.r_[0, n_step[:-1]]) / FS, settle_s=0.5)
    np.testing.assert_allclose(np.abs(e.response[0] / exact.response[0]), 1, atol=5 * e.magnitude_std_db[0].max() * LN)


def test_random_input_uses_welch_with_a_segment_resolving_the_band():
    rng = np.random.default_rng(6)
    u = rng.standard_normal(60_000)
    y = plant(u) + 0.1 * rng.standard_normal(u.size)
    e = estimate_frf(FS, u, y)
    assert e.method == "h1" and e.settings["excitation"].startswith("random")
    assert e.settings["segments"] >= 16 and e.frequency_hz.max() < FS / 2
    narrow = estimate_frf(FS, u, y, band_hz=(0.5, 20.0))
    assert narrow.settings["resolution_hz"] <= 0.25 and narrow.frequency_hz.min() >= 0.5
    assert narrow.frequency_hz.max() <= 20.0
    with pytest.raises(IPMCError, match="too short.*band_hz"):
        estimate_frf(FS, u[:3000], y[:3000], band_hz=(0.1, 20.0))


# ------------------------------------------------------------------------------------- what is refused or warned
def test_clipping_fraction_is_counted_and_a_quantised_peak_is_not_clipping():
    t = np.arange(20_000) / FS
    x = np.sin(2 * np.pi * 3.7 * t)
    c = detect_clipping(np.clip(x, -0.7, 0.7), "tip")
    assert c.clipped and c.high == 0.7 and c.low == -0.7
    assert c.samples == np.count_nonzero(np.abs(x) >= 0.7) and "tip" in c.describe()
    assert not detect_clipping(np.round(x * 2000) / 2000).clipped             # 12-bit-like codes, full peak
    assert not detect_clipping(x).clipped
    one = detect_clipping(np.minimum(x, 0.95))
    assert one.high == 0.95 and one.low is None


def test_clipped_output_is_refused_and_below_the_limit_warned():
    u = np.tile(schroeder(1000, LINES), 8)
    y = plant(u)
    y = np.clip(y, -0.3 * np.abs(y).max(), 0.3 * np.abs(y).max())
    with pytest.raises(IPMCError, match=r"clipped: output: .*% of samples"):
        estimate_frf(FS, u, y)
    with pytest.warns(FRFWarning, match="clipped"):
        e = estimate_frf(FS, u, y, max_clipped_fraction=1.0)
    assert any("clipped" in w for w in e.warnings)
    assert "clipped" in e.to_sweep(25.0).metadata["warnings"]


def test_pure_noise_output_warns_low_coherence_and_drops_its_lines():
    rng = np.random.default_rng(7)
    u = np.tile(schroeder(1000, LINES), 8)
    with pytest.warns(FRFWarning, match="low coherence"):
        e = estimate_frf(FS, u, rng.standard_normal(u.size))
    assert e.significant().mean() < 0.2
    sig = estimate_frf(FS, u, plant(u) + 0.05 * rng.standard_normal(u.size))
    assert sig.significant().all() and sig.warnings == ()


def test_too_short_records_are_refused():
    rng = np.random.default_rng(8)
    with pytest.raises(IPMCError, match="10 samples.*too short"):
        estimate_frf(FS, rng.standard_normal(10), rng.standard_normal(10))
    with pytest.raises(IPMCError, match="too short"):
        estimate_frf(FS, rng.standard_normal(20), rng.standard_normal(20))
    with pytest.raises(IPMCError, match="excitation='periodic'"):
        estimate_frf(FS, rng.standard_normal(3000), rng.standard_normal(3000), excitation="periodic")
