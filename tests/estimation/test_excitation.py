"""Excitation design: multisine spectra and crest factors, stepped-sine plans, chirps and the
signal files, checked against spectra and closed forms computed here."""

from __future__ import annotations

import math

import frf_oracle as orc
import numpy as np
import pytest

from physmodel.data.excitation import (
    SteppedSinePlan,
    chirp,
    crest_factor,
    multisine,
    schroeder_phases,
    settle_time_s,
    stepped_sine_plan,
)
from physmodel.data.timerecord import read_record
from physmodel.errors import IPMCError
from physmodel.estimation.frf import h1
from physmodel.estimation.stepped import stepped_sine

FS = 1000.0


def test_multisine_has_exactly_the_designed_line_spectrum():
    f = np.array([2.0, 5.0, 11.0, 40.0, 250.0])
    amp = np.array([1.0, 0.5, 2.0, 0.25, 1.0])
    for phases in ("schroeder", "clipped", "random"):
        ms = multisine(f, FS, 2.0, amplitude=amp, phases=phases, seed=4)
        x = ms.period()
        X = np.fft.rfft(x) * 2 / x.size
        k = np.rint(f * 2.0).astype(int)
        np.testing.assert_allclose(np.abs(X[k]), amp, rtol=1e-12)
        np.testing.assert_allclose(np.angle(X[k] * np.exp(-1j * ms.phases_rad)), 0, atol=1e-12)
        others = np.delete(np.abs(X), k)
        assert others.max() < 1e-13 * amp.max()
        assert np.sqrt(np.mean(x**2)) == pytest.approx(math.sqrt(np.sum(amp**2) / 2), rel=1e-12)


def test_schroeder_phases_are_the_flat_spectrum_closed_form():
    K = 37
    k = np.arange(1, K + 1)
    expected = -np.pi * k * (k - 1) / K                # Schroeder 1970 for equal powers
    got = schroeder_phases(np.ones(K))
    np.testing.assert_allclose(np.exp(1j * got), np.exp(1j * expected), atol=1e-12)


def test_crest_factor_schroeder_below_random_and_clipping_below_schroeder():
    lines = np.arange(1, 201) * 1.0
    schroeder = multisine(lines, FS, 1.0).period()
    clipped = multisine(lines, FS, 1.0, phases="clipped").period()
    random = [crest_factor(multisine(lines, FS, 1.0, phases="random", seed=s).period()) for s in range(20)]
    cf_s, cf_c = crest_factor(schroeder), crest_factor(clipped)
    assert cf_s < min(random)
    assert cf_s < 2.0                                   # ≈ 1.7 for flat spectra (Schroeder 1970)
    assert cf_c < cf_s
    assert np.median(random) > 2.5


def test_rms_and_bad_designs():
    ms = multisine([1.0, 2.0, 3.0], FS, 1.0, rms=0.3)
    assert np.sqrt(np.mean(ms.period()**2)) == pytest.approx(0.3, rel=1e-12)
    assert ms.duration_s(10, 2) == pytest.approx(12.0)
    with pytest.raises(IPMCError, match=r"frequencies_hz: \[1.5\]"):
        multisine([1.0, 1.5], FS, 1.0)
    with pytest.raises(IPMCError, match="period_s"):
        multisine([1.0], FS, 1.00005)
    with pytest.raises(IPMCError, match="seed"):
        multisine([1.0], FS, 1.0, phases="random")
    with pytest.raises(IPMCError, match="amplitude"):
        multisine([1.0, 2.0], FS, 1.0, amplitude=[1.0, -1.0])
    with pytest.raises(IPMCError, match="phases"):
        multisine([1.0], FS, 1.0, phases="newman")


def test_multisine_signal_file_and_its_frf():
    sysd = orc.resonant(FS)
    ms = multisine(np.arange(1, 101) * 2.0, FS, 0.5, phases="clipped")
    rec = ms.record(periods=8, transient_periods=2)
    assert rec.metadata["expected_duration_s"] == "5"
    assert rec.t.size == 10 * ms.n_samples
    u = rec.channel("voltage_V")
    y = orc.simulate(sysd, u)
    e = h1(rec.t, u, y, nperseg=ms.n_samples, noverlap=0, window="boxcar", discard_s=2 * ms.period_s,
           frequencies_hz=ms.frequency_hz)
    np.testing.assert_allclose(e.response[0], orc.truth(sysd, ms.frequency_hz, FS), rtol=1e-10)


def test_stepped_plan_covers_settle_and_whole_periods_and_plays_the_sines(tmp_path):
    f = np.array([0.5, 3.0, 17.0, 120.0])
    plan = stepped_sine_plan(f, FS, amplitude=[1.0, 1.0, 0.5, 0.5], periods=4, min_measure_s=1.0, settle_s=0.3)
    np.testing.assert_array_equal(plan.periods, [4, 4, 17, 120])
    length = plan.step_stop_s - plan.step_start_s
    needed = plan.settle_s + plan.periods / f
    assert np.all(length >= needed - 1e-12) and np.all(length < needed + 1 / FS)
    assert plan.duration_s == pytest.approx(np.sum(np.ceil(needed * FS)) / FS)
    u = plan.signal()
    for i in range(f.size):
        idx = np.arange(int(round(plan.step_start_s[i] * FS)), int(round(plan.step_stop_s[i] * FS)))
        ref = plan.amplitude[i] * np.sin(2 * np.pi * f[i] * (idx / FS - plan.step_start_s[i]))
        np.testing.assert_allclose(u[idx], ref, atol=1e-12)
    path = plan.record().save(tmp_path / "steps.csv")
    text = path.read_text().splitlines()
    assert text[0] == "# ipmc-timeseries 1" and "# voltage_V: voltage [V]" in text
    assert any(line.startswith("# expected_duration_s: ") for line in text)
    back = SteppedSinePlan.from_record(read_record(path))
    np.testing.assert_array_equal(back.frequency_hz, plan.frequency_hz)
    np.testing.assert_array_equal(back.step_start_s, plan.step_start_s)


def test_stepped_plan_feeds_the_estimator():
    sysd, sysc = orc.slow_resonant(FS)
    f = np.geomspace(0.3, 200, 9)
    plan = stepped_sine_plan(f, FS, periods=3, min_measure_s=0.5, settle_s=settle_time_s(sysc, 1e-11))
    rec = plan.record()
    y = orc.simulate(sysd, rec.channel("voltage"))
    e = stepped_sine(rec.t, rec.channel("voltage"), y, plan=plan)
    np.testing.assert_allclose(e.response[0], orc.truth(sysd, f, FS), rtol=1e-9)
    late = stepped_sine(rec.t + 100.0, rec.channel("voltage"), y, plan=plan)   # a clock not starting at 0
    np.testing.assert_allclose(late.response, e.response, rtol=1e-10)


def test_settle_time_of_the_slowest_pole():
    import control

    sys = control.tf([1.0], [0.2, 1.0]) * control.tf([100.0], [1.0, 20.0, 100.0])   # poles -5, -10 ± 0j
    assert settle_time_s(sys, 1e-3) == pytest.approx(0.2 * math.log(1e3), rel=1e-9)
    with pytest.raises(IPMCError, match="stable"):
        settle_time_s([-1.0, 0.5])


def test_chirp_sweeps_its_band():
    rec = chirp(5.0, 200.0, 4.0, FS, amplitude=0.5)
    assert rec.metadata["expected_duration_s"] == "4"
    u = rec.channel("voltage")
    k, T = 200.0 / 5.0, 4.0                  # exponential sweep: phase 2π f0 T (k^(t/T) − 1)/ln k
    np.testing.assert_allclose(u, 0.5 * np.sin(2 * np.pi * 5.0 * T * (k**(rec.t / T) - 1) / np.log(k)), atol=1e-9)
    assert np.max(np.abs(u)) == pytest.approx(0.5, rel=1e-3)
    with pytest.raises(IPMCError, match="f1_hz"):
        chirp(5.0, 600.0, 1.0, FS)


def test_periodic_chirp_frf_is_exact_where_it_has_energy():
    sysd = orc.resonant(FS)
    rec = chirp(2.0, 300.0, 2.0, FS, repeats=4, method="linear")
    u = rec.channel("voltage")
    e = h1(rec.t, u, orc.simulate(sysd, u), nperseg=2000, noverlap=0, window="boxcar", discard_s=2.0)
    band = (e.frequency_hz > 5) & (e.frequency_hz < 290)
    np.testing.assert_allclose(e.response[0][band], orc.truth(sysd, e.frequency_hz[band], FS), rtol=1e-9)


def test_plan_bad_input():
    with pytest.raises(IPMCError, match="whole"):
        stepped_sine_plan([1.0], FS, periods=2.5)
    with pytest.raises(IPMCError, match="frequencies_hz"):
        stepped_sine_plan([1.0, 400.0], FS)
    with pytest.raises(IPMCError, match="settle_s"):
        stepped_sine_plan([1.0], FS, settle_s=-1.0)
    with pytest.raises(IPMCError, match="fs_hz"):
        stepped_sine_plan([1.0], 0.0)
