"""FRF estimation against independent oracles (see frf_oracle.py): scipy.signal.csd/welch on the
same record, python-control plants simulated exactly, the physics model through its own
time-domain simulation, and the statistics the per-line σ claims to have."""

from __future__ import annotations

import math

import frf_oracle as orc
import numpy as np
import pytest
from scipy import signal

from physmodel.data.timerecord import TimeRecord
from physmodel.errors import IPMCError
from physmodel.estimation.frf import FRFEstimate, effective_averages, estimate_record, frf_sweep, h1, h2
from physmodel.estimation.stepped import stepped_sine

FS = 1000.0
LN = math.log(10.0) / 20.0


def _t_stats(est: FRFEstimate, H_true, row: int = 0):
    """Errors of ln H over their stated σ: (magnitude terms, phase terms)."""
    d = np.log(est.response[row] / H_true)
    return d.real / (est.magnitude_std_db[row] * LN), d.imag / np.radians(est.phase_std_deg[row])


def _t2_mean_band(nu: float, n_terms: int, k: float = 4.0):
    """Mean of n_terms squared Student-t(ν) variables: expectation and a k-sd band."""
    mean = nu / (nu - 2)
    var = 3 * nu**2 / ((nu - 2) * (nu - 4)) - mean**2
    return mean, k * math.sqrt(var / n_terms)


# ------------------------------------------------------------------------------------- oracle
def test_oracle_simulation_is_python_controls_own():
    import control

    sysd = orc.resonant(FS)
    u = np.random.default_rng(0).standard_normal(3000)
    ref = control.forced_response(sysd, T=np.arange(u.size) / FS, U=u).outputs
    np.testing.assert_allclose(orc.simulate(sysd, u), ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())


# ------------------------------------------------------------------------------------- peer check
@pytest.mark.parametrize("kw", [dict(nperseg=1024), dict(nperseg=500, noverlap=100, window="boxcar"),
                                dict(nperseg=256, noverlap=192, window=("tukey", 0.3), detrend="linear")])
def test_welch_matches_scipy_csd_and_welch(kw):
    sysd = orc.resonant(FS)
    u, y, _, _ = orc.white_record(sysd, 60_000, seed=1, output_noise=0.2)
    y2 = 3.0 * y + 0.5 * np.random.default_rng(2).standard_normal(y.size)
    sp = {k: v for k, v in kw.items()}
    sp.setdefault("noverlap", kw["nperseg"] // 2)
    sp.setdefault("window", "hann")
    sp.setdefault("detrend", "constant")
    _, Puu = signal.welch(u, FS, **sp)
    _, Pyy = signal.welch(y, FS, **sp)
    f, Puy = signal.csd(u, y, FS, **sp)
    _, C = signal.coherence(u, y, FS, **sp)
    e1 = h1(FS, u, np.stack([y, y2]), **kw)
    e2 = h2(FS, u, y, **kw)
    np.testing.assert_allclose(e1.frequency_hz, f[1:], rtol=1e-15)
    np.testing.assert_allclose(e1.response[0], (Puy / Puu)[1:], rtol=1e-12)
    np.testing.assert_allclose(e2.response[0], (Pyy / Puy.conj())[1:], rtol=1e-12)
    np.testing.assert_allclose(e1.coherence[0], C[1:], rtol=1e-12)
    np.testing.assert_allclose(e1.response[1], (signal.csd(u, y2, FS, **sp)[1] / Puu)[1:], rtol=1e-12)
    # streamed in small blocks: the same numbers
    eb = h1(FS, u, np.stack([y, y2]), block_samples=3000, **kw)
    np.testing.assert_allclose(eb.response, e1.response, rtol=1e-12)
    np.testing.assert_allclose(eb.coherence, e1.coherence, rtol=1e-12)


def test_effective_averages_of_hann_half_overlap():
    # Welch (1967): Hann at 50 % overlap has ρ(1) = 1/6, so K segments count as K/(1 + 2(1-1/K)/36)
    w = signal.get_window("hann", 1024)
    assert effective_averages(w, 512, 100) == pytest.approx(100 / (1 + 2 * 0.99 / 36), rel=1e-3)
    assert effective_averages(w, 1024, 100) == 100.0


# ------------------------------------------------------------------------------------- H1 / H2
def test_h1_agrees_with_truth_within_its_sigma():
    """χ² over lines and repeats: every third line (Hann leakage correlates neighbours), where the
    true coherence is ≥ 0.2 (the first-order σ of ln|H| holds for small relative errors)."""
    sysd = orc.resonant(FS)
    noise = 0.3
    t2 = []
    for seed in range(5):
        u, y, _, _ = orc.white_record(sysd, 200_000, seed=seed, output_noise=noise)
        e = h1(FS, u, y, nperseg=1024)
        Ht = orc.truth(sysd, e.frequency_hz, FS)
        keep = (np.abs(Ht)**2 / (np.abs(Ht)**2 + noise**2) >= 0.2) & (np.arange(Ht.size) % 3 == 0)
        tm, tp = _t_stats(e, Ht)
        t2 += [tm[keep]**2, tp[keep]**2]
    t2 = np.concatenate(t2)
    nu = 2 * (e.settings["effective_averages"] - 1)
    mean, band = _t2_mean_band(nu, t2.size)
    assert t2.size > 400
    assert abs(t2.mean() - mean) < band, (t2.mean(), mean, band)


def test_h2_is_unbiased_for_input_noise_and_h1_is_biased_as_predicted():
    sysd = orc.resonant(FS)
    nu_in = 0.5                         # input measurement noise (std) on a unit-variance input
    u, y, _, _ = orc.white_record(sysd, 400_000, seed=7, input_noise=nu_in)
    e1, e2 = h1(FS, u, y, nperseg=1024), h2(FS, u, y, nperseg=1024)
    Ht = orc.truth(sysd, e1.frequency_hz, FS)
    band = e1.frequency_hz < 150
    # H1 → H·S_uu/(S_uu + S_nn) = H/(1 + 0.25) for white signals (Bendat & Piersol §9.2.2)
    ratio = np.mean((e1.response[0] / Ht)[band])
    assert ratio.real == pytest.approx(1 / (1 + nu_in**2), abs=0.01)
    tm, tp = _t_stats(e2, Ht)
    t2 = np.concatenate([tm[band][::3]**2, tp[band][::3]**2])
    mean, b = _t2_mean_band(2 * (e2.settings["effective_averages"] - 1), t2.size)
    assert abs(t2.mean() - mean) < b


@pytest.mark.parametrize("noise", [0.1, 0.4, 1.5])
def test_coherence_follows_added_output_noise(noise):
    """γ² = |H|²/(|H|² + σ_n²/σ_u²) for white input and noise; the estimator's bias is
    (1 − γ²)²/n (Carter, Knapp & Nuttall 1973), its variance 2γ²(1 − γ²)²/n.  Segments of 4096
    samples put 80 bins across the resonance's 20 Hz half-power band, so the resolution bias
    (see the next test) stays below the coherence's own scatter even at 1 − γ² = 0.01."""
    sysd = orc.resonant(FS)
    u, y, _, _ = orc.white_record(sysd, 200_000, seed=3, output_noise=noise)
    e = h1(FS, u, y, nperseg=4096, noverlap=0)
    n = e.settings["effective_averages"]
    g = np.abs(orc.truth(sysd, e.frequency_hz, FS))**2
    g = g / (g + noise**2)
    expected = g + (1 - g)**2 / n
    sd = np.sqrt(2 * g * (1 - g)**2 / n + (1 - g)**4 / n**2)
    z = (e.coherence[0] - expected) / sd
    assert abs(z.mean()) < 4 / math.sqrt(z.size)
    assert 0.8 < z.std() < 1.2


def test_coarse_segments_bias_coherence_low_at_a_resonance():
    """Known limitation, measured: leakage across the resonance (20 Hz half-power band) lowers γ²
    there by far more than its scatter when the noise is small.  The deficit falls as the bin width
    Δf for a rectangular window and as Δf² for Hann (smooth taper), so 4× longer segments cut it by
    about 4 and 16.  The per-line σ does not include this bias: choose nperseg accordingly."""
    sysd = orc.resonant(FS)
    u, y, _, _ = orc.white_record(sysd, 200_000, seed=3, output_noise=0.1)
    deficit, z = {}, {}
    for nper in (1000, 4000):
        for win in ("boxcar", "hann"):
            e = h1(FS, u, y, nperseg=nper, noverlap=0, window=win)
            n = e.settings["effective_averages"]
            g = np.abs(orc.truth(sysd, e.frequency_hz, FS))**2
            g = g / (g + 0.01)
            band = (e.frequency_hz > 40) & (e.frequency_hz < 60)
            d = (e.coherence[0] - g - (1 - g)**2 / n)[band]
            deficit[nper, win] = -d.mean()
            z[nper, win] = np.mean(d / np.sqrt(2 * g * (1 - g)**2 / n)[band])
    assert z[1000, "boxcar"] < -10 and z[1000, "hann"] < -10
    assert 2 < deficit[1000, "boxcar"] / deficit[4000, "boxcar"] < 8
    assert deficit[1000, "hann"] / deficit[4000, "hann"] > 8
    assert abs(z[4000, "hann"]) < 1


def test_lines_of_a_multisine_period_are_exact_without_noise():
    from physmodel.data.excitation import multisine

    sysd = orc.resonant(FS)
    ms = multisine(np.arange(1, 301) * 1.0, FS, 1.0)
    u = np.tile(ms.period(), 6)
    y = orc.simulate(sysd, u)
    e = h1(FS, u, y, nperseg=ms.n_samples, noverlap=0, window="boxcar", discard_s=ms.period_s,
           frequencies_hz=ms.frequency_hz)
    np.testing.assert_allclose(e.response[0], orc.truth(sysd, ms.frequency_hz, FS), rtol=1e-10)
    assert e.n_averages[0] == 5


# ------------------------------------------------------------------------------------- stepped sine
def _plan(f, settle, periods, fs=FS):
    dur = settle + periods / f
    n = np.ceil(dur * fs)
    edges = np.concatenate([[0.0], np.cumsum(n)]) / fs
    return edges[:-1], edges[1:]


def test_stepped_sine_exact_with_a_non_integer_number_of_samples_per_period():
    sysd, sysc = orc.slow_resonant(FS)
    f = np.array([0.7, 3.3, 13.7, 47.1, 123.4])            # fs/f = 1428.6, 303.0, 73.0, 21.2, 8.1 samples
    settle = math.log(1e12) * 0.2                            # transient of the slowest pole down to 1e-12
    starts, stops = _plan(f, settle, 7)
    t, u, y = orc.stepped_record(sysd, f, starts, stops, FS)
    e = stepped_sine(t, u, y, f, starts, stops, settle_s=settle, periods=7)
    np.testing.assert_allclose(e.response[0], orc.truth(sysd, f, FS), rtol=1e-9)


def test_stepped_sine_is_independent_of_settle_once_past_the_slowest_time_constant():
    tau = 0.2
    sysd, _ = orc.slow_resonant(FS, tau_s=tau)
    f = np.array([2.0, 9.0, 31.0])
    H = orc.truth(sysd, f, FS)
    err = {}
    for k in (0.0, 0.5, 3.0, 10.0, 20.0, 30.0):
        starts, stops = _plan(f, k * tau, 10)
        t, u, y = orc.stepped_record(sysd, f, starts, stops, FS)
        err[k] = np.max(np.abs(stepped_sine(t, u, y, f, starts, stops, settle_s=k * tau, periods=10).response[0] / H - 1))
    # the transient left after s seconds is ∝ exp(−s/τ): a few % when not waited for, then gone
    assert err[0.0] > 1e-2
    for k in (10.0, 20.0):
        assert err[k] < 2 * math.exp(-k) * max(err[0.0], 1.0)
    assert err[30.0] < 1e-10                                   # round-off from here on


def test_stepped_sine_uses_whole_periods_and_refuses_fractional_ones():
    sysd = orc.resonant(FS)
    f = np.array([5.0, 12.5])
    starts, stops = np.array([0.0, 3.0]), np.array([3.0, 5.0])
    t, u, y = orc.stepped_record(sysd, f, starts, stops, FS)
    y = y + 0.01 * np.random.default_rng(0).standard_normal(y.size)
    # 1 s settle leaves 10 and 12.5 periods: the trailing half period is not used
    auto = stepped_sine(t, u, y, f, starts, stops, settle_s=1.0)
    fixed = stepped_sine(t, u, y, f, starts, stops, settle_s=1.0, periods=[10, 12])
    np.testing.assert_array_equal(auto.n_averages, [10, 12])
    np.testing.assert_allclose(auto.response, fixed.response, rtol=1e-13)
    with pytest.raises(IPMCError, match="whole"):
        stepped_sine(t, u, y, f, starts, stops, settle_s=1.0, periods=2.5)
    with pytest.raises(IPMCError, match=r"step 1 \(12.5 Hz\): periods=13"):
        stepped_sine(t, u, y, f, starts, stops, settle_s=1.0, periods=[10, 13])
    with pytest.raises(IPMCError, match="at least 2"):
        stepped_sine(t, u, y, f, starts, stops, settle_s=2.95)


def test_stepped_sine_sigma_from_period_scatter_is_consistent():
    sysd = orc.resonant(FS)
    f = np.geomspace(1.0, 200.0, 20)
    P = 20
    starts, stops = _plan(f, 0.2, P)
    t, u, y0 = orc.stepped_record(sysd, f, starts, stops, FS)
    H = orc.truth(sysd, f, FS)
    t2 = []
    for seed in range(10):
        rng = np.random.default_rng(seed)
        e = stepped_sine(t, u + 0.002 * rng.standard_normal(u.size), [y0 + 0.05 * rng.standard_normal(u.size)],
                         f, starts, stops, settle_s=0.2, periods=P)
        tm, tp = _t_stats(e, H)
        t2 += [tm**2, tp**2]
    t2 = np.concatenate(t2)
    mean, band = _t2_mean_band(P - 1, t2.size)
    assert abs(t2.mean() - mean) < band, (t2.mean(), mean, band)


def test_stepped_sine_on_the_physics_model_matches_its_frequency_response():
    """The actuator's own time-domain simulation (timesim, first-order hold) against its frequency
    response.  A linearly interpolated input carries its sample-rate harmonic at sinc²(f/fs) of the
    sampled amplitude (the triangle kernel's transform), so the truth is M(jω)·sinc²(f/fs)."""
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.data.excitation import settle_time_s, stepped_sine_plan
    from physmodel.data.timesim import model_realization, simulate

    m = ActuatorModel(get_parameter_set("seed002_table3"))
    fs, T = 400.0, 25.0
    f = np.geomspace(0.1, 9.0, 12)                         # seed 001: 0.1-9 Hz
    real = model_realization(m, T, fs, 300.0)
    plan = stepped_sine_plan(f, fs, periods=8, min_measure_s=4.0, settle_s=settle_time_s(real.poles, 1e-6))
    t = np.arange(plan.n_samples) / fs
    ts = simulate(m, T, t, plan.signal(), realization=real, output_noise_rms=2e-6, seed=3)
    e = stepped_sine(t, ts.input, ts.output, plan=plan)
    H = m.frequency_response(f, [T])["M"][0, 0] * np.sinc(f / fs)**2
    tm, tp = _t_stats(e, H)
    # realisation error (≤ 4e-6 relative here) is far below σ; 24 terms, 4-sd band of t(7)²
    t2 = np.concatenate([tm**2, tp**2])
    mean, band = _t2_mean_band(7, t2.size)
    assert abs(t2.mean() - mean) < band
    exact = stepped_sine(t, ts.input, ts.clean_output, plan=plan)
    np.testing.assert_allclose(exact.response[0], H, rtol=2e-5)


# ------------------------------------------------------------------------------------- channels → sweeps
def test_several_channels_give_m_and_z_sweeps_usable_by_calibration(tmp_path):
    from physmodel.data.files import read_sweep
    from physmodel.data.sweep import sweep_layout

    rng = np.random.default_rng(5)
    adm = orc.resonant(FS, f_n=150.0, zeta=0.7, gain=0.02)           # current/voltage [A/V]
    mob = orc.resonant(FS, f_n=40.0, zeta=0.3, gain=2.0)             # displacement/voltage [mm/V]
    v = rng.standard_normal(120_000 + 4000)
    cur = orc.simulate(adm, v)[4000:] + 1e-3 * rng.standard_normal(120_000)
    disp = orc.simulate(mob, v)[4000:] + 0.05 * rng.standard_normal(120_000)
    v = v[4000:]
    rec = TimeRecord(np.arange(v.size) / FS, {"voltage": v, "current": cur, "tip_displacement": disp},
                     {"voltage": "V", "current": "A", "tip_displacement": "mm"}, {"temperature_c": "25"})
    e = estimate_record(rec, "voltage", method="h1", nperseg=1024)
    assert e.output_names == ("current", "tip_displacement")
    M = e.to_sweep(25.0, "tip_displacement", band_hz=(1.0, 200.0), quantity="M")
    Z = e.reciprocal("current").to_sweep(25.0, band_hz=(1.0, 200.0), quantity="Z")
    assert (M.input_unit, M.output_unit, Z.input_unit, Z.output_unit) == ("V", "mm", "A", "V")
    np.testing.assert_allclose(Z.response, 1 / e.response[0][(e.frequency_hz >= 1) & (e.frequency_hz <= 200)])
    sweep_layout(M, "actuator", "M")
    sweep_layout(Z, "actuator", "Z")
    back = read_sweep(M.to_csv(tmp_path / "m.csv"))
    np.testing.assert_allclose(back.magnitude_std_db, M.magnitude_std_db, rtol=1e-12)
    assert back.metadata["method"] == "h1"
    two = frf_sweep([(25.0, e), (40.0, e)], "tip_displacement", band_hz=(1.0, 200.0))
    np.testing.assert_array_equal(two.temperatures(), [25.0, 40.0])


def test_unexcited_lines_are_flagged_by_coherence_and_unexcitable_ones_refused():
    from physmodel.data.excitation import multisine

    ms = multisine([10.0, 20.0, 30.0], FS, 1.0)
    u = np.tile(ms.period(), 5)
    e = h1(FS, u, orc.simulate(orc.resonant(FS), u) + 1e-3 * np.random.default_rng(0).standard_normal(u.size),
           nperseg=ms.n_samples, noverlap=0, window="boxcar")
    lines = np.isin(e.frequency_hz, ms.frequency_hz)
    assert np.all(e.coherence[0][lines] > 0.999) and np.all(e.coherence[0][~lines] < 0.9)
    sw = e.to_sweep(25.0, min_coherence=0.9)
    np.testing.assert_array_equal(sw.frequency_hz, [10.0, 20.0, 30.0])
    sw = e.to_sweep(25.0, max_std_db=1.0)
    np.testing.assert_array_equal(sw.frequency_hz, e.frequency_hz[e.magnitude_std_db[0] <= 1.0])
    assert sw.magnitude_std_db.max() <= 1.0 and 10.0 in sw.frequency_hz
    flat = h1(FS, np.ones(4000), np.random.default_rng(1).standard_normal(4000), nperseg=1000)
    with pytest.raises(IPMCError, match="no finite response or σ"):
        flat.to_sweep(25.0)


# ------------------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("call,match", [
    (lambda u, y: h1(FS, u, y, nperseg=10**6), "nperseg"),
    (lambda u, y: h1(FS, u, y, nperseg=256, noverlap=256), "noverlap"),
    (lambda u, y: h1(FS, u, y, nperseg=3000, noverlap=0), "segment"),
    (lambda u, y: h1(FS, u, y[:-1]), "y\\[0\\] has 3999 samples"),
    (lambda u, y: h1(-1.0, u, y), "t_or_fs"),
    (lambda u, y: h1(np.r_[0.0, np.cumsum(np.full(3999, 1e-3))] ** 1.01, u, y), "uniform"),
    (lambda u, y: h1(FS, np.where(np.arange(u.size) == 17, np.nan, u), y), r"u contains NaN .* \[17\]"),
    (lambda u, y: h1(FS, u, y, nperseg=1000, frequencies_hz=[1.5]), "frequencies_hz"),
    (lambda u, y: h1(FS, u, y, window="nope"), "window"),
    (lambda u, y: h1(FS, u, y, detrend="quadratic"), "detrend"),
    (lambda u, y: h1(FS, u, y, discard_s=-1.0), "discard_s"),
    (lambda u, y: h1(FS, u, y).to_sweep(25.0, "displacement"), "output"),
    (lambda u, y: stepped_sine(FS, u, y, [300.0], [0.0]), "frequencies_hz"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0, 10.0], [0.0, 1.0]), "repeats"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0, 20.0], [0.0, 3.95]), r"step 1 \(20 Hz\): 1 whole"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0, 20.0], [0.0, 9.0]), r"step 0 .* must lie in the record"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0], None), "step_start_s"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0], [0.0]).to_sweep(25.0, min_coherence="high"), "min_coherence"),
    (lambda u, y: stepped_sine(FS, u, y, [10.0], [0.0], settle_s=-1), "settle"),
])
def test_bad_input_names_the_argument(call, match):
    rng = np.random.default_rng(0)
    u = rng.standard_normal(4000)
    with pytest.raises(IPMCError, match=match):
        call(u, orc.simulate(orc.resonant(FS), u))
