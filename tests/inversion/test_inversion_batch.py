"""Batch inversion: exactness against independent oracles, discretisation error, input errors.

Oracles
-------
* steady-state sinusoid: y = |H(jw)| sin(wt + arg H(jw)) with H = den/num evaluated by
  numpy.polyval;
* forward simulation of G with scipy.signal.lsim on a 10-20x finer grid;
* the truncated anticausal integral evaluated by scipy.integrate.quad with residues from
  scipy.signal.residue.

Tolerances follow the discretisation analysis of inversion._discrete: the inverse is exact
for the piecewise-linear interpolant of the samples, so for a sinusoid of angular frequency
w the error is about (w dt)^2/12 times the strictly proper parts |H_s(jw)| + |H_u(jw)| (the
triangle-hold gain sinc^2(w dt/2)), plus small aliasing terms; we allow a factor 2 on that.
"""

import math

import control
import numpy as np
import pytest
import scipy.integrate as si
import scipy.signal as ss

from inversion import (
    InversionError,
    NonFiniteSignalError,
    NonUniformSamplingError,
    PreviewError,
    decode_sensor,
    feedforward,
    invert,
    invert_to,
    split_inverse,
)
from inversion.examples import SEED000_DEN_35C, SEED000_NUM_35C, seed000_sensor_35c, toy_actuator

NMP = (list(SEED000_NUM_35C), list(SEED000_DEN_35C))
MP = (np.poly([-50.0, -500.0]).tolist(), np.poly([-10.0, -100.0]).tolist())   # minimum phase, biproper


def _H(model, w):
    num, den = model
    return np.polyval(den, 1j * w) / np.polyval(num, 1j * w)


def _sine_error(model, f, dt, preview="inf"):
    w = 2 * np.pi * f
    t = np.arange(0.0, 3.0, dt)
    res = invert(model, t, np.sin(w * t), preview=preview)
    H = _H(model, w)
    exact = abs(H) * np.sin(w * t + np.angle(H))
    m = (t > 1.0) & (t < 1.8)     # edge transients: e^{-50*1} and e^{-35.2*1.2} < 1e-18
    return np.max(np.abs(res.output[m] - exact[m])), res, H


@pytest.mark.parametrize("model", [NMP, MP], ids=["non-minimum-phase", "minimum-phase"])
@pytest.mark.parametrize("f", [20.0, 54.0])
def test_sinusoid_steady_state_matches_analytic_inverse(model, f):
    dt = 2e-4
    err, res, H = _sine_error(model, f, dt)
    w = 2 * np.pi * f
    sp = res.split
    hsp = abs(sp.frequency_response(w, "stable")[0]) + abs(sp.frequency_response(w, "unstable")[0])
    tol = 2.0 * hsp * (w * dt) ** 2 / 12
    assert err <= tol
    # not vacuous: the error is genuinely the second-order discretisation error
    assert err >= 0.2 * hsp * (w * dt) ** 2 / 12


def test_discretisation_error_is_second_order():
    e1, _, _ = _sine_error(NMP, 20.0, 1e-3)
    e2, _, _ = _sine_error(NMP, 20.0, 5e-4)
    assert 3.6 < e1 / e2 < 4.4


def test_minimum_phase_inverse_is_causal():
    _, res, _ = _sine_error(MP, 20.0, 1e-3, preview="auto")
    assert res.preview_samples == 0 and res.preview_s == 0.0 and res.r0 == math.inf
    assert not np.any(res.unstable_part)
    np.testing.assert_array_equal(res.output, res.stable_part)


def _lsim_fine(model, t, x, fine):
    """Forward-simulate G on a grid `fine` times finer, input linearly interpolated."""
    num, den = model
    tf = np.linspace(t[0], t[-1], (t.size - 1) * fine + 1)
    xf = np.interp(tf, t, x)
    _, y, _ = ss.lsim((num, den), xf, tf)
    return y[::fine]


def _g_l1(model, horizon=1.0):
    """L1 norm of the impulse response of G's strictly proper part (fine grid)."""
    num, den = model
    q, r = np.polydiv(num, den)
    tt = np.linspace(0, horizon, 200001)
    _, h = ss.impulse((r, den), T=tt)
    return float(np.sum(np.abs(h)) * (tt[1] - tt[0]))


@pytest.mark.parametrize("model", [NMP, MP], ids=["non-minimum-phase", "minimum-phase"])
def test_G_applied_to_inverse_returns_signal(model):
    """G[H[u]] = u: lsim (independent FOH-exact simulator) applied to the inverse."""
    dt = 5e-4
    t = np.arange(0.0, 2.0, dt)
    win = np.where((t > 0.3) & (t < 1.5), np.sin(np.pi * (t - 0.3) / 1.2) ** 2, 0.0)
    u = win * (np.sin(2 * np.pi * 20 * t) + 0.5 * np.sin(2 * np.pi * 7 * t))
    res = invert(model, t, u, preview="inf")
    y = res.output
    back = _lsim_fine(model, t, y, 1)
    # both steps are exact for piecewise-linear signals; the only error is replacing the
    # continuous inverse y(t) by its interpolant.  The feedthrough part D u is piecewise
    # linear already, so |err| <= ||g_sp||_1 max|y_sp''| dt^2 / 8 with y_sp = y - D u.
    d2 = np.max(np.abs(np.diff(y - res.split.feedthrough * u, 2)))
    bound = 1.5 * _g_l1(model) * d2 / 8
    err = np.max(np.abs(back - u))
    assert err <= bound
    assert err < 2e-3 * np.max(np.abs(u))


def test_sensor_decoding_recovers_displacement_from_fine_grid_simulation():
    """Sensor use: displacement -> current by lsim on a 20x finer grid, then decode."""
    G = NMP
    errs = []
    for dt in (1e-3, 5e-4):
        t = np.arange(0.0, 2.0, dt)
        tf = np.arange(0.0, 2.0 - dt / 2, dt / 20)
        d = lambda x: np.where((x > 0.3) & (x < 1.5), np.sin(np.pi * (x - 0.3) / 1.2) ** 2, 0.0) * np.sin(2 * np.pi * 20 * x)
        _, i_f, _ = ss.lsim(G, d(tf), tf)
        i = i_f[::20][: t.size]
        res = decode_sensor(G, t, i, preview="inf")
        err = np.max(np.abs(res.output - d(t)))
        # rigorous-in-spirit a-posteriori estimate (||h||_1 dt^2/8 max|i''|) must cover it
        assert err <= res.discretisation_error_estimate
        errs.append(err)
    assert 3.0 < errs[0] / errs[1] < 5.0          # O(dt^2)
    assert errs[1] < 0.002                          # mm, for a 1 mm stimulus


def test_actuator_feedforward_tracks_desired_trajectory():
    """Actuator use (seed 001 style NMP 3rd-order model): voltage that makes lsim(G) track."""
    G = toy_actuator()
    model = (G.num[0][0], G.den[0][0])
    dt = 2e-3
    t = np.arange(0.0, 24.0, dt)
    env = np.where((t > 4) & (t < 18), np.sin(np.pi * (t - 4) / 14) ** 2, 0.0)
    desired = 0.325 * (np.sin(np.pi * t) + np.sin(4 * np.pi * t)) * env   # seed 001 two-tone shape
    ff = feedforward(G, t, desired, preview="inf")
    same = invert(G, t, desired, preview="inf")
    np.testing.assert_array_equal(ff.output, same.output)   # one code path
    achieved = _lsim_fine(model, t, ff.output, 1)
    # as in test_G_applied_to_inverse_returns_signal: only the interpolation of the voltage
    ysp = ff.output - ff.split.feedthrough * desired
    bound = 1.5 * _g_l1(model, horizon=25.0) * np.max(np.abs(np.diff(ysp, 2))) / 8
    err = np.max(np.abs(achieved - desired))
    assert err <= bound
    assert err < 2e-3 * 0.65                               # 0.2 % of the 0.65 mm amplitude
    assert ff.r0 == pytest.approx(4.0, rel=1e-9)
    # the voltage starts before the motion (pre-actuation of a NMP inverse)
    assert np.max(np.abs(ff.output[(t > 3.0) & (t < 4.0)])) > 1e-4


def test_finite_preview_equals_truncated_integral_by_quadrature():
    """eq. (6) of seed 000 evaluated independently with residues + adaptive quadrature."""
    dt = 1e-3
    t = np.arange(0.0, 1.0, dt)
    u = np.sin(2 * np.pi * 13 * t) * np.exp(-((t - 0.5) / 0.2) ** 2)
    Tp = 0.05
    res = invert(NMP, t, u, preview=Tp)
    assert res.preview_samples == 50 and res.preview_s == pytest.approx(0.05)
    r, p, _ = ss.residue(NMP[1], NMP[0])
    unstable = p.real > 0
    uf = lambda x: np.interp(x, t, u, right=0.0)
    for k in (100, 400, 480, 700):
        tk = t[k]
        total = 0.0
        for ri, pi in zip(r[unstable], p[unstable]):
            re = si.quad(lambda x: np.real(-ri * np.exp(pi * (tk - x))) * uf(x), tk, tk + Tp,
                         limit=200, points=t[k:k + 51], epsabs=1e-13)[0]
            total += re
        assert res.unstable_part[k] == pytest.approx(total, rel=1e-6, abs=1e-10)


def test_chunked_processing_equals_single_pass():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(5000)
    for preview in ("inf", "4/r0", 0.02, 0.5):
        a = invert(NMP, 1e-3, u, preview=preview)
        b = invert(NMP, 1e-3, u, preview=preview, chunk_size=777)
        np.testing.assert_allclose(b.output, a.output, rtol=0, atol=1e-12 * np.max(np.abs(a.output)))
        np.testing.assert_allclose(b.unstable_part, a.unstable_part, rtol=0,
                                   atol=1e-12 * np.max(np.abs(a.output)))


def test_invert_to_memmap_bounded_memory_equals_invert(tmp_path):
    rng = np.random.default_rng(2)
    n = 20000
    src = np.lib.format.open_memmap(tmp_path / "u.npy", mode="w+", dtype=float, shape=(n,))
    src[:] = rng.standard_normal(n)
    dst = np.lib.format.open_memmap(tmp_path / "y.npy", mode="w+", dtype=float, shape=(n,))
    for preview in ("4/r0", "inf"):
        summary = invert_to(NMP, 1e-3, src, dst, preview=preview, chunk_size=1500)
        ref = invert(NMP, 1e-3, np.asarray(src), preview=preview).output
        np.testing.assert_allclose(np.asarray(dst), ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
        assert summary.n_samples == n and summary.chunk_size == 1500
    src[123] = np.nan
    with pytest.raises(NonFiniteSignalError, match="sample 123"):
        invert_to(NMP, 1e-3, src, dst)


def test_time_stamps_and_result_fields():
    t = 2.0 + 1e-3 * np.arange(500)
    u = np.sin(2 * np.pi * 20 * t)
    r = invert(NMP, t, u, preview="4/r0")
    np.testing.assert_array_equal(r.t, t)
    assert r.dt == pytest.approx(1e-3)
    assert r.preview_samples == round(r.auto_preview_s / 1e-3) == 113
    np.testing.assert_allclose(r.output, r.stable_part + r.unstable_part, rtol=0, atol=1e-15)
    r2 = invert(NMP, 1e-3, u, t0=2.0, preview="4/r0")
    np.testing.assert_allclose(r2.t, t, rtol=0, atol=1e-12)
    # same signal, dt from the stamps differs from 1e-3 by rounding only
    np.testing.assert_allclose(r2.output, r.output, rtol=0, atol=1e-11)


@pytest.mark.parametrize(
    "kwargs, exc, match",
    [
        (dict(t=np.r_[0.0, 0.001, 0.002, 0.0035, 0.0045]), NonUniformSamplingError, r"t\[3\] - t\[2\]"),
        (dict(t=np.r_[0.0, -0.001, -0.002, -0.003, -0.004]), NonUniformSamplingError, "increase"),
        (dict(t=-1e-3), NonUniformSamplingError, "positive"),
        (dict(u=np.r_[0.0, 1.0, np.nan, 0.0, 0.0]), NonFiniteSignalError, "sample 2"),
        (dict(preview=-0.1), PreviewError, ">= 0"),
        (dict(preview="soon"), PreviewError, "auto"),
        (dict(preview=0.01), PreviewError, "longer than the record"),
        (dict(preview="4/r0"), PreviewError, "4/r0"),
        (dict(u=np.zeros((2, 3))), InversionError, "1-D"),
        (dict(t=np.arange(4) * 1e-3), InversionError, "same length"),
    ],
)
def test_clear_input_errors(kwargs, exc, match):
    args = dict(t=np.arange(5) * 1e-3, u=np.zeros(5), preview="inf")
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        invert(NMP, args["t"], args["u"], preview=args["preview"])


def test_preview_spellings():
    u = np.zeros(1000)
    for p in ("inf", "INF", None, math.inf, "infinite"):
        r = invert(NMP, 1e-3, u, preview=p)
        assert r.preview_samples is None and r.preview_s == math.inf
    r = invert(NMP, 1e-3, u, preview="0.0504")
    assert r.preview_samples == 50


def test_improper_models_differentiate_and_filter_against_analytic():
    model = ([100.0], [1.0, 14.0, 100.0])      # H = s^2/100 + 0.14 s + 1
    f, dt = 5.0, 1e-3
    w = 2 * np.pi * f
    t = np.arange(0.0, 2.0, dt)
    u = np.sin(w * t)
    with pytest.raises(InversionError, match="improper"):
        invert(model, t, u)
    r = invert(model, t, u, improper="differentiate")
    H = _H(model, w)
    exact = abs(H) * np.sin(w * t + np.angle(H))
    m = (t > 0.1) & (t < 1.9)
    # central differences: relative errors (w dt)^2/6 (first) and (w dt)^2/12 (second derivative)
    tol = 1.1 * (0.14 * w * (w * dt) ** 2 / 6 + 0.01 * w**2 * (w * dt) ** 2 / 12)
    assert np.max(np.abs(r.output[m] - exact[m])) <= tol
    wf = 300.0
    rf = invert(model, t, u, improper="filter", filter_bandwidth=wf, preview="inf")
    Hf = H * (wf / (1j * w + wf)) ** 2
    exact_f = abs(Hf) * np.sin(w * t + np.angle(Hf))
    sp = rf.split
    hsp = abs(sp.frequency_response(w, "stable")[0])
    m2 = (t > 0.5) & (t < 1.9)
    assert np.max(np.abs(rf.output[m2] - exact_f[m2])) <= 2 * hsp * (w * dt) ** 2 / 12 + 1e-12


def test_control_transfer_function_and_split_inputs_agree():
    u = np.sin(np.linspace(0, 30, 3000))
    a = invert(seed000_sensor_35c(), 1e-3, u)
    b = invert(split_inverse(seed000_sensor_35c()), 1e-3, u)
    c = invert(control.ss(seed000_sensor_35c()), 1e-3, u)
    np.testing.assert_array_equal(a.output, b.output)
    np.testing.assert_allclose(c.output, a.output, rtol=0, atol=1e-7 * np.max(np.abs(a.output)))


@pytest.mark.parametrize("model, kwargs", [
    (NMP, dict(preview="4/r0")),                                     # fused finite-preview pass
    (NMP, dict(preview="inf")),                                      # whole-record passes
    (NMP, dict(preview=0.05, chunk_size=700)),                       # block by block
    (NMP, dict(preview="auto")),                                     # the extremes pass's check
    ((np.poly([-50.0, -500.0]), np.poly([-10.0, -100.0])), dict(preview="inf")),   # causal only
    (([100.0], [1.0, 14.0, 100.0]), dict(improper="differentiate")),               # stencil, D = 0
    ((np.array([1.0, -30.0]), np.array([1.0, 40.0])), dict(preview=0.05)),          # no stable part
])
@pytest.mark.parametrize("where", [0, 777, 2999])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_input_sample_is_named_whatever_the_path(model, kwargs, where, bad):
    # the input is proved finite by the output's sum (or the auto preview's extremes pass), not by a
    # pass of its own: every path must still refuse a bad sample and name it (oracle: its index)
    u = np.sin(2 * np.pi * 5e-3 * np.arange(3000))
    u[where] = bad
    if where < 2500:
        u[2500] = np.nan                    # a later bad sample: the first is the one named
    with pytest.raises(NonFiniteSignalError, match=f"the signal must be finite; sample {where} is"):
        invert(model, 1e-3, u, **kwargs)
