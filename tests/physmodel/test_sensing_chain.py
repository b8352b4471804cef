"""Sensing-chain elements (physmodel.effects.sensing) against independent evaluations.

Oracles: the circuit's node equations solved numerically per frequency (numpy.linalg.solve, with
the op-amp written as A0/(1 + s A0/ω_t)); steady states of the elements' ODEs integrated in time
from rest (scipy solve_ivp) and lock-in demodulated; a time-shifted sampled sine; a modal sum of
clamped-pinned beam modes (extrapolated in the number of modes); a shooting solution (solve_ivp) of
the beam equation with a spring at the tip; the closed form at 50 digits (mpmath); roots of the clamped-pinned frequency equation by brentq.
"""

import json
import math

import mpmath as mp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from physmodel import IPMCError
from physmodel.effects.sensing import (
    CLAMPED_PINNED_LAMBDA1,
    ELEMENTS,
    base_excited_resonance,
    chain_elements,
    chain_response,
    clamped_pinned_frequency_hz,
    first_order_lag,
    get_element,
    highpass,
    laser_lag,
    polarity,
    pure_delay,
    second_order_lowpass,
    tip_driven_beam,
    transimpedance,
    transimpedance_factor,
)
from physmodel.sensor import TransimpedanceChain

W = 2 * np.pi * np.array([3.0, 10.0, 31.6, 100.0, 316.0])      # rad/s
S = 1j * W
Z_RC = 12.0 + 1.0 / (S * 4e-4)                                    # a series R-C source [Ω]


# ------------------------------------------------------------------ helpers (independent numerics)
def ode_phasor(rhs, n, out, omega, settle, periods=4):
    """Steady-state phasor Y/U of y = out(t, x) for x' = rhs(t, x, cos ωt), integrated from rest."""
    T = 2 * np.pi / omega
    t_end = settle + periods * T
    sol = solve_ivp(lambda t, x: rhs(t, x, math.cos(omega * t)), (0, t_end), np.zeros(n), method="DOP853",
                    rtol=1e-11, atol=1e-13, dense_output=True)
    t = np.linspace(t_end - periods * T, t_end, 4000 * periods, endpoint=False)
    y = np.array([out(tt, sol.sol(tt)) for tt in t])
    return 2 * np.mean(y * np.exp(-1j * omega * t))


def test_off_values_give_identity_exactly():
    for name, e in ELEMENTS.items():
        f = e.factor(S, e.off, Z_RC)
        assert np.array_equal(f, np.ones_like(S)), name
    assert np.array_equal(highpass(np.array([0.0, 1j]), 0.0, 2), np.ones(2))   # also at s = 0


def test_declarations_are_plain_data_with_sources():
    decl = chain_elements()
    assert {d["name"] for d in decl} == set(ELEMENTS)
    for d in decl:
        assert callable(d["response"]) and d["description"] and d["source"]
        json.dumps({k: v for k, v in d.items() if k != "response"})          # everything else is plain data
        for p in d["parameters"]:
            assert p["lower"] <= p["off"] <= p["upper"] and p["lower"] <= p["start"] <= p["upper"]
            assert p["source"] and p["unit"]
            if p["plausible"] is not None:
                assert p["lower"] <= p["plausible"][0] <= p["plausible"][1] <= p["upper"], (d["name"], p["name"])
        assert not np.allclose(ELEMENTS[d["name"]].factor(S, ELEMENTS[d["name"]].start, Z_RC), 1.0), d["name"]


def test_delay_equals_a_time_shifted_sampled_sine():
    fs, f0 = 20000.0, 37.0
    t = np.arange(int(fs)) / fs                                            # 1 s = 37 whole periods
    for tau in (2.5e-3, -0.7e-3):
        y = np.cos(2 * np.pi * f0 * (t - tau))
        ph = 2 * np.mean(y * np.exp(-2j * np.pi * f0 * t))
        assert abs(ph - pure_delay(2j * np.pi * f0, tau)) < 1e-10


def test_first_order_current_lag_and_laser_lag_from_their_odes():
    tau = 1.3e-3
    for w in (2 * np.pi * 20, 2 * np.pi * 150):
        got = ode_phasor(lambda t, x, u: [(u - x[0]) / tau], 1, lambda t, x: x[0], w, 30 * tau)
        assert abs(got - first_order_lag(1j * w, tau)) < 1e-7
        # laser: the displacement channel reads d through the lag; I/D_read for I ∝ d is D/D_read
        assert abs(1.0 / got - laser_lag(1j * w, tau)) < 1e-6 * abs(laser_lag(1j * w, tau))


def test_second_order_lowpass_and_highpasses_from_their_odes():
    tau, z = 1.7e-3, 0.4
    lp = lambda t, x, u: [x[1], (u - x[0] - 2 * z * tau * x[1]) / tau**2]
    fc = 18.0
    wc = 2 * np.pi * fc
    rc = lambda t, x, u: [wc * (u - x[0])]                  # capacitor voltage; output u − v_C
    hp2 = lambda t, x, u: [x[1], u - 2 * z * wc * x[1] - wc**2 * x[0]]        # output x''
    for w in (2 * np.pi * 25, 2 * np.pi * 90):
        got = ode_phasor(lp, 2, lambda t, x: x[0], w, 40 * tau / z)
        assert abs(got - second_order_lowpass(1j * w, tau, z)) < 1e-7
        got = ode_phasor(rc, 1, lambda t, x, w=w: math.cos(w * t) - x[0], w, 30 / wc)
        assert abs(got - highpass(1j * w, fc, 1)) < 1e-7
        got = ode_phasor(hp2, 2, lambda t, x, w=w: math.cos(w * t) - 2 * z * wc * x[1] - wc**2 * x[0], w,
                         40 / (z * wc))
        assert abs(got - highpass(1j * w, fc, 2, z)) < 1e-7


def test_base_excited_fixture_from_its_equation_of_motion():
    wf, z = 2 * np.pi * 95.0, 0.2                               # m x'' + c(x' − y') + k(x − y) = 0, y = cos ωt

    for w in (2 * np.pi * 40, 2 * np.pi * 95, 2 * np.pi * 160):
        rhs = lambda t, x, u, w=w: [x[1], -2 * z * wf * (x[1] + w * math.sin(w * t)) - wf**2 * (x[0] - u)]
        got = ode_phasor(rhs, 2, lambda t, x: x[0], w, 40 / (z * wf))
        assert abs(got - base_excited_resonance(1j * w, 1 / wf, z)) < 1e-7


# ------------------------------------------------------------------ tip-driven strip
def test_clamped_pinned_root_and_frequency():
    lam = brentq(lambda x: math.tan(x) - math.tanh(x), 3.5, 4.5)
    assert abs(lam - CLAMPED_PINNED_LAMBDA1) < 1e-12
    E, h, W_, L = 3e8, 105e-6, 6.5e-3, 18e-3                   # seed 000 strip, polymer 2000 kg/m3, in water
    m = 2000 * 2 * h * W_ + 1000 * math.pi * W_**2 / 4
    f_cf = 1.8751040687**2 / L**2 * math.sqrt(E * W_ * (2 * h) ** 3 / 12 / m) / (2 * math.pi)
    assert clamped_pinned_frequency_hz(E, h, W_, L) == pytest.approx(f_cf * (lam / 1.8751040687) ** 2, rel=1e-9)


def _modal_data(n_modes=120, n_quad=2000):
    """Clamped-pinned modes on [0, 1]: λ_k (brentq on sin λ − tanh λ cos λ), ∫φ², ∫φ w_qs (Gauss-Legendre)
    and φ'(1), with φ = cosh λξ − cos λξ − σ(sinh λξ − sin λξ) written without overflow;
    w_qs = (3ξ² − ξ³)/2 is the static shape with the tip displaced by 1."""
    xg, wg = np.polynomial.legendre.leggauss(n_quad)
    xi, wq = 0.5 * (xg + 1), 0.5 * wg
    out = []
    for k in range(1, n_modes + 1):
        lam = brentq(lambda x: math.sin(x) - math.tanh(x) * math.cos(x), k * math.pi + 0.1,
                     k * math.pi + math.pi / 2 - 1e-9, xtol=1e-15)
        em, sech = math.exp(-lam), 2 * math.exp(-lam) / (1 + math.exp(-2 * lam))
        sig = (1 - math.cos(lam) * sech) / (math.tanh(lam) - math.sin(lam) * sech)
        a = 2 * (math.cos(lam) - math.sin(lam) - em) / (1 - em * em - 2 * math.sin(lam) * em)   # (1 − σ)e^λ
        phi = (0.5 * (a * np.exp(lam * (xi - 1)) + (1 + sig) * np.exp(-lam * xi)) - np.cos(lam * xi)
               + sig * np.sin(lam * xi))
        d1 = lam * (0.5 * (a - (1 + sig) * em) + math.sin(lam) + sig * math.cos(lam))
        out.append((lam, np.sum(wq * phi**2), np.sum(wq * phi * (3 * xi**2 - xi**3) / 2), d1))
    return np.array(out)


@pytest.fixture(scope="module")
def modes():
    return _modal_data()


def test_pinned_tip_factor_equals_modal_sum(modes):
    lam, N, P, d1 = modes.T
    w1, z = 2 * np.pi * 50.0, 0.05
    wk = w1 * (lam / lam[0]) ** 2
    s = 1j * 2 * np.pi * np.array([5.0, 20.0, 32.0, 45.0, 50.0, 60.0, 100.0, 200.0])
    sd = s * s + 2 * z * w1 * s                                   # mass-proportional damping

    def modal(K):                                                 # u = Σ q_k φ_k, w = w_qs + u
        q = -sd[:, None] * P[:K] / (N[:K] * (wk[:K] ** 2 + sd[:, None]))
        return (1.5 + q @ d1[:K]) / 1.5

    got = tip_driven_beam(s, 1 / w1, z)
    assert np.max(np.abs(got / modal(120) - 1)) < 3e-6           # the tail falls as K⁻³ ...
    richardson = (8 * modal(120) - modal(60)) / 7                 # ... so extrapolate it away
    assert np.max(np.abs(got / richardson - 1)) < 2e-7
    # resonance at ω1 and antiresonance at x = π, i.e. (π/λ1)² ω1
    w = np.linspace(0.3, 1.3, 2001) * w1
    mag = np.abs(tip_driven_beam(1j * w, 1 / w1, 1e-3))
    assert w[np.argmax(mag)] / w1 == pytest.approx(1.0, abs=1e-3)
    assert w[np.argmin(mag)] / w1 == pytest.approx((math.pi / CLAMPED_PINNED_LAMBDA1) ** 2, abs=1e-3)


def shooting_tip_slope(b, eps):
    """w'(1) of w'''' = b w on [0, 1], w(0) = w'(0) = 0, w''(1) = 0 and w(1) = 1 (ε = 0) or
    w'''(1) = (3/ε)(w(1) − 1): two solutions from z = 0 (solve_ivp) combined to meet the tip conditions."""
    ends = []
    for y0 in ([0, 0, 1, 0], [0, 0, 0, 1]):
        sol = solve_ivp(lambda x, y: [y[1], y[2], y[3], b * y[0]], (0, 1), np.array(y0, complex), method="DOP853",
                        rtol=1e-12, atol=1e-14)
        ends.append(sol.y[:, -1])
    A, B = ends
    if eps == 0:
        M, r = [[A[2], B[2]], [A[0], B[0]]], [0, 1]
    else:
        M, r = [[A[2], B[2]], [A[3] - 3 / eps * A[0], B[3] - 3 / eps * B[0]]], [0, -3 / eps]
    al, be = np.linalg.solve(np.array(M), np.array(r, complex))
    return al * A[1] + be * B[1]


@pytest.mark.parametrize("eps", [0.0, 0.05, 0.8])
def test_spring_coupled_tip_factor_equals_shooting_solution(eps):
    w1, z = 2 * np.pi * 50.0, 0.08
    for f in (15.0, 40.0, 70.0, 150.0):
        s = 2j * np.pi * f
        b = -(CLAMPED_PINNED_LAMBDA1**4) * ((s / w1) ** 2 + 2 * z * s / w1)
        ref = shooting_tip_slope(b, eps) / (1.5 / (1 + eps))
        assert abs(tip_driven_beam(s, 1 / w1, z, eps) / ref - 1) < 1e-8, f


def test_beam_series_and_closed_form_agree_with_50_digit_evaluation():
    mp.mp.dps = 50
    w = np.logspace(-5, 0.3, 50)                                  # ω/ω1: |βL| 0.11 to 5.5, across the switch at 0.25
    for eps in (0.0, 0.4):
        got = tip_driven_beam(1j * w, 1.0, 0.03, eps)
        for wk, g in zip(w, got):
            x = mp.root(-mp.mpf(CLAMPED_PINNED_LAMBDA1) ** 4 * ((1j * wk) ** 2 + 2 * 0.03 * 1j * wk), 4)
            ref = complex((2 * x / 3) * (1 + eps) * mp.tanh(x) * mp.sin(x) / (
                eps / 3 * x**3 * (mp.sech(x) + mp.cos(x)) + mp.sin(x) - mp.tanh(x) * mp.cos(x)))
            assert abs(g - ref) < 1e-13 * abs(ref), (eps, wk)


# ------------------------------------------------------------------ the transimpedance circuit
def node_solution(s, Z, R1, R2, R3, C1, C3, gbw1, A01, gbw2, A02):
    """v2 per unit source current from the four node/op-amp equations, solved per frequency."""
    out = []
    for sk, zk in zip(np.atleast_1d(s), np.broadcast_to(Z, np.shape(np.atleast_1d(s)))):
        A1 = A01 / (1 + sk * A01 / (2 * np.pi * gbw1))
        A2 = A02 / (1 + sk * A02 / (2 * np.pi * gbw2))
        Y1, Y3 = 1 / R1 + sk * C1, 1 / R3 + sk * C3
        M = np.array([[1 / zk + Y1, -Y1, 0, 0],                    # KCL at n1: source in, Z, feedback
                      [A1, 1, 0, 0],                              # v1 = A1 (0 − v_n1)
                      [0, -1 / R2, 1 / R2 + Y3, -Y3],             # KCL at n2
                      [0, 0, A2, 1]], dtype=complex)              # v2 = A2 (0 − v_n2)
        out.append(np.linalg.solve(M, np.array([1, 0, 0, 0], dtype=complex))[3])
    return np.array(out)


@pytest.mark.parametrize("Z", [Z_RC, 26.0 + 0j, 1500.0 - 700.0j])
def test_transimpedance_equals_node_equations(Z):
    kw = {"R1": 470e3, "R2": 10e3, "R3": 33e3, "C1": 2e-10, "C3": 1e-11}
    for g1, a1, g2, a2 in ((1e6, 2e5, 1e6, 2e5), (3e6, 1e5, 0.7e6, 5e4)):
        ref = node_solution(S, Z, kw["R1"], kw["R2"], kw["R3"], kw["C1"], kw["C3"], g1, a1, g2, a2)
        got = transimpedance(S, Z, kw["R1"], kw["R2"], kw["R3"], C1=kw["C1"], C3=kw["C3"],
                             unity_gain_time=1 / (2 * np.pi * g1), inverse_dc_gain=1 / a1,
                             unity_gain_time_2=1 / (2 * np.pi * g2), inverse_dc_gain_2=1 / a2)
        assert np.max(np.abs(got / ref - 1)) < 1e-10


def test_ideal_circuit_is_the_printed_law_and_finite_gbw_closes_near_wt_Z_over_R1():
    assert np.allclose(transimpedance(S, Z_RC), TransimpedanceChain(R3=10e3).gain, rtol=1e-15)
    # resistive source: first-stage pole at ω_t Z/R1 (the second stage's is 6 decades higher)
    gbw, Z = 1e6, 26.0
    wp = 2 * np.pi * gbw * Z / (470e3 + Z)
    f = transimpedance_factor(1j * wp, Z, unity_gain_time=1 / (2 * np.pi * gbw))
    assert abs(f) == pytest.approx(1 / math.sqrt(2), rel=1e-3)
    assert np.degrees(np.angle(f)) == pytest.approx(-45.0, abs=0.1)


# ------------------------------------------------------------------ composition, vectorisation, errors
def test_chain_composes_and_broadcasts_parameter_batches():
    settings = {"acquisition_delay": {"delay": 2e-3}, "fixture_joint": {"time_constant": 1.6e-3, "damping": 0.2},
                "transimpedance": {"unity_gain_time": 1.6e-7}, "polarity": {"sign": -1.0}}
    prod = np.ones_like(S)
    for n, v in settings.items():
        prod = prod * get_element(n).factor(S, v, Z_RC)
    assert np.allclose(chain_response(S, settings, Z_RC), prod, rtol=1e-14)
    taus = np.array([[1e-3], [2e-3], [4e-3]])
    batch = tip_driven_beam(S[None, :], taus, 0.1, 0.2)
    for i, t in enumerate(taus[:, 0]):
        assert np.array_equal(batch[i], tip_driven_beam(S, t, 0.1, 0.2))
    assert np.array_equal(polarity(S, -1.0), -np.ones_like(S))


@pytest.mark.parametrize("call", [
    lambda: first_order_lag(S, -1e-3), lambda: polarity(S, 0.5), lambda: second_order_lowpass(S, 1e-3, 0.0),
    lambda: highpass(S, 5.0, 3), lambda: transimpedance(S, 0.0), lambda: pure_delay(S, np.nan),
    lambda: get_element("nope"), lambda: get_element("laser_lag").factor(S, {"tau": 1.0}),
    lambda: get_element("transimpedance").factor(S, {}), lambda: tip_driven_beam(S, 1e-3, 0.1, -1.0),
])
def test_bad_input_raises_ipmc_error(call):
    with pytest.raises(IPMCError):
        call()


# ------------------------------------------------------------------ the chain as library effects
def test_registered_effects_compose_with_the_sensor_model_and_match_the_node_equations():
    """EffectModel(S) with the transimpedance effect = SensorModel S × the circuit solved from its
    node equations with the model's own Z as source; every registered effect is sensor-only on S."""
    from physmodel import SensorModel, get_parameter_set
    from physmodel.effects import LIBRARY, EffectModel
    from physmodel.effects.sensing import EFFECTS, PLAUSIBLE

    p = get_parameter_set("seed000_sensor_dev", T_ref=308.15)
    f = np.array([10.0, 31.6, 100.0])
    r = SensorModel(p).frequency_response(f, [35.0], quantities=("S", "Z"))
    S0, Z = r["S"][0, 0], r["Z"][0, 0]
    gbw, a0 = 1e6, 2e5
    got = EffectModel(p, "sensor", {"transimpedance": {"unity_gain_time": 1 / (2 * np.pi * gbw),
                                                       "inverse_dc_gain": 1 / a0}}).frequency_response(f, [35.0])["S"][0, 0]
    ref = S0 * node_solution(2j * np.pi * f, Z, 470e3, 10e3, 10e3, 0.0, 0.0, gbw, a0, gbw, a0) / 470e3
    assert np.max(np.abs(got / ref - 1)) < 1e-9
    assert abs(got[-1] / S0[-1]) < 0.9                       # the effect is not negligible in the band
    for e in EFFECTS:
        assert LIBRARY[e.name] is e and e.kinds == ("sensor",) and e.quantities == ("S",)
        m = EffectModel(p, "sensor", {e.name: e.typical}).frequency_response(f, [35.0])["S"][0, 0]
        assert not np.allclose(m, S0, rtol=1e-3), e.name
        for k in PLAUSIBLE:
            lo, hi, src = PLAUSIBLE[k]
            assert lo < hi and src
    s = 2j * np.pi * f
    beam = EffectModel(p, "sensor", {"tip_driven_beam": {"time_constant": 3e-3, "damping": 0.1}}).frequency_response(
        f, [35.0])["S"][0, 0]
    assert np.allclose(beam / S0, tip_driven_beam(s, 3e-3, 0.1, 0.0), rtol=1e-12)
    with pytest.raises(IPMCError):
        EffectModel(p, "actuator", {"laser_lag": {"time_constant": 1e-3}})


def test_transimpedance_chain_with_finite_opamps_matches_the_node_equations_and_keeps_its_defaults():
    Z = 26.0 + 1.0 / (S * 3e-4)
    ch = TransimpedanceChain(R3=33e3, gbw_hz=3e6, dc_gain=1e5)
    ref = node_solution(S, Z, 470e3, 10e3, 33e3, 0.0, 0.0, 3e6, 1e5, 3e6, 1e5)
    assert np.max(np.abs(ch.response(S, Z) / ref - 1)) < 1e-10
    assert np.array_equal(TransimpedanceChain().response(S), np.full_like(S, 470e3))
    with pytest.raises(IPMCError):
        ch.response(S)
    with pytest.raises(IPMCError):
        ch.transfer_function()
    with pytest.raises(IPMCError):
        TransimpedanceChain(gbw_hz=-1.0)
