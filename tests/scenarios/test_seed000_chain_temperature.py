"""Temperature series of ``seed000_chain`` (issue 16): the a0(T) calibration of the polymer's laws.

Oracles: the printed numbers themselves (the 35 °C model's coefficients, its a0 = 4.4e10 at its two
printed digits), 4/4 transfer functions built from chosen roots (numpy.poly), first-order high-passes
whose cutoff, gain and lag are known in closed form, and a0(T) made by the independently written
sensor generator (tests/discrepancy/independent_sensor.py: its own strip, its own clamped-pinned
beam BVP) with its own temperature laws and its own equation-error fit (numpy.linalg.lstsq per
temperature, unscaled Vandermonde columns), recovered by the step's calibration within its
intervals.  The scenario's own temperature metrics are checked in test_seed000_chain.py (it runs the
scenario once)."""

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy import constants

from physmodel.params import IPMCParameters
from physmodel.temperature import LogLinear
from scenarios.steps_chain import printed_sweep
from scenarios.steps_chain_temperature import (
    A0Series,
    a0_series,
    calibrate_laws,
    law_free_parameters,
    levy_4_4,
    printed_a0,
    series_model,
    trend_signs,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "discrepancy"))
import independent_sensor as gen  # noqa: E402

F_HZ = np.geomspace(10.0, 100.0, 31)


def test_equation_error_fit_recovers_exact_4_4_models_in_batch():
    from physmodel.parameter_sets.published import seed000_printed_model_35c

    num, den, _ = seed000_printed_model_35c()
    s = 2j * np.pi * F_HZ
    other_den = np.poly([-50.0, -300.0, -80 + 400j, -80 - 400j]).real
    other_num = 3.0 * np.poly([-20.0, 10.0, 500 + 300j, 500 - 300j]).real
    G = np.stack([np.polyval(num, s) / np.polyval(den, s), np.polyval(other_num, s) / np.polyval(other_den, s)])
    n, d = levy_4_4(F_HZ, G)
    np.testing.assert_allclose(n[0], num, rtol=1e-8, atol=1e-6)
    np.testing.assert_allclose(d[0], den, rtol=1e-8)
    np.testing.assert_allclose(d[1], other_den, rtol=1e-8)
    np.testing.assert_allclose(n[1], other_num, rtol=1e-8, atol=1e-6)


def test_printed_a0_polynomial_agrees_with_the_printed_35c_model():
    from physmodel.parameter_sets.published import seed000_printed_model_35c

    a0_35 = seed000_printed_model_35c()[1][-1]                     # 4.4e10, two digits printed
    assert abs(printed_a0(35.0)[0] - a0_35) <= 0.05e10
    assert printed_a0(23.07)[0] == pytest.approx(4.81e10, rel=1e-12)


def test_a0_data_noise_model():
    data = a0_series(printed_sweep(), draws=1000)
    assert data.a0.shape == data.sigma_ln.shape == (7,)
    # rounding of the printed polynomial is tiny; the identification spread dominates and is common
    assert np.all(data.rounding_ln < 0.01) and 0.02 < data.identification_ln < 1.0
    np.testing.assert_allclose(data.sigma_ln, np.hypot(data.rounding_ln, data.identification_ln))


def test_trend_signs_on_known_high_passes():
    s = 2j * np.pi * F_HZ
    fc = np.array([[60.0], [40.0], [20.0]])                        # falling cutoff
    gain = np.array([[3.0], [2.0], [1.0]])                         # falling gain
    tau = np.array([[1e-3], [2e-3], [3e-3]])                       # growing lag
    G = gain * s / (s + 2 * np.pi * fc) * np.exp(-s * tau)
    t = trend_signs(F_HZ, G)
    assert t["as_printed"] == {"cutoff falls": True, "gain falls": True, "lag grows": True}
    # |g s/(s+ωc)|² = g² f²/(f² + fc²) reaches |G(f_max)|²/2 at f = fc f_max sqrt(0.5/(0.5 f_max² + fc²))
    fm = F_HZ[-1]
    exact = fc[:, 0] * fm * np.sqrt(0.5 / (0.5 * fm ** 2 + fc[:, 0] ** 2))
    k = np.searchsorted(F_HZ, t["cutoff_hz"])
    assert np.all(t["cutoff_hz"] >= exact * (1 - 1e-12)) and np.all(F_HZ[k - 1] < exact)
    np.testing.assert_allclose(t["hf_gain"], gain[:, 0] * np.abs(s[-1] / (s[-1] + 2 * np.pi * fc[:, 0])), rtol=1e-12)
    lag = -np.degrees(np.angle(s[None, :] / (s[None, :] + 2 * np.pi * fc)) - (s[None, :] * tau).imag).mean(1)
    np.testing.assert_allclose(t["mean_lag_deg"], lag, rtol=1e-10)
    reversed_t = trend_signs(F_HZ, G[::-1])
    assert reversed_t["as_printed"] == {"cutoff falls": False, "gain falls": False, "lag grows": False}


# --------------------------------------------------------------------------- independent recovery
TEMPS_C = np.array([23.0, 25.0, 30.0, 40.0, 50.0, 60.0, 65.0])
T35 = 35.0
TRUTH = {"laws.d.activation_energy": 15e3, "laws.E.slope": -0.0075}
KAPPA_SLOPE = -0.0045                  # κe(T) = κe(35 °C)·exp(slope (T − 35)), given to both sides
CHAIN = {"f_cp": 60.0, "zeta": 0.2, "f_c": 20.0, "tau": 1e-3}


def _generator_a0(temps_c, ea, e_slope):
    """a0(T) of the independent generator: its strip with d, κe, E, leakage moved by its own laws, its
    slit beam whose mode follows E (f ∝ sqrt(E)), its AC coupling and delay; its own 4/4 fit."""
    R, T0 = constants.R, constants.zero_Celsius
    out = []
    for t in temps_c:
        b = dict(gen.START)
        arr = math.exp(-ea / R * (1 / (t + T0) - 1 / (T35 + T0)))
        b.update(d=b["d"] * arr, eps=b["eps"] * math.exp(KAPPA_SLOPE * (t - T35)), E=b["E"] * math.exp(e_slope * (t - T35)),
                 Gp=b["Gp"] * arr * (T35 + T0) / (t + T0), T=t + T0)
        eff = {"slit_beam": {"f_cp": CHAIN["f_cp"] * math.exp(0.5 * e_slope * (t - T35)), "zeta": CHAIN["zeta"]},
               "ac_coupling": {"f_c": CHAIN["f_c"]}, "delay": {"tau": CHAIN["tau"]}}
        G = gen.response(b, eff, F_HZ)
        s = 2j * np.pi * F_HZ
        # G·(s⁴ + a3 s³ + … + a0) = b4 s⁴ + … + b0, unknowns (b4..b0, a3..a0), real and imaginary rows
        M = np.hstack([s[:, None] ** np.arange(4, -1, -1), -G[:, None] * s[:, None] ** np.arange(3, -1, -1)])
        sc = np.abs(M).max(0)
        x = np.linalg.lstsq(np.vstack([M.real, M.imag]) / sc, np.concatenate([(G * s ** 4).real, (G * s ** 4).imag]),
                            rcond=None)[0] / sc
        out.append(x[-1])
    return np.array(out)


def _library_side():
    # alpha0, rho, xi do not enter the sensor's S (quasi-static strip; the beam is the chain's)
    b = IPMCParameters.from_dict({**gen.library_fields(gen.START), "alpha0": 0.13, "rho": 2000.0, "xi": 0.1})
    b = replace(b, laws=b.laws.with_(kappa_e=LogLinear(slope=KAPPA_SLOPE)))
    effects = {"tip_driven_beam": {"time_constant": 1 / (2 * np.pi * CHAIN["f_cp"]), "damping": CHAIN["zeta"],
                                   "coupling_ratio": 0.0},
               "ac_coupling": {"corner_hz": CHAIN["f_c"]}, "time_delay": {"delay": CHAIN["tau"]}}
    return b, effects


@pytest.mark.parametrize("sigma_ln", [0.02, 0.155])
def test_known_laws_through_the_same_chain_are_recovered_within_their_intervals(sigma_ln):
    a0 = _generator_a0(TEMPS_C, TRUTH["laws.d.activation_energy"], TRUTH["laws.E.slope"])
    data = A0Series(TEMPS_C, a0, np.full(TEMPS_C.size, sigma_ln), np.zeros(TEMPS_C.size), sigma_ln, "independent")
    base, effects = _library_side()
    respond = series_model(base, {}, effects, F_HZ, TEMPS_C, beam_follows_E=True)
    free = [fp.with_initial(v) for fp, v in zip(law_free_parameters(base, list(TRUTH)), (30e3, 0.0))]
    cal = calibrate_laws(data, respond, F_HZ, free, starts=2, seed=1)
    r = cal.result
    assert r.converged
    assert r.goodness_of_fit.chi2 < 1e-3                           # noise-free data, the same physics
    for n, v in TRUTH.items():
        assert np.isfinite(r.ci_lower[n]) and np.isfinite(r.ci_upper[n])
        assert r.ci_lower[n] <= v <= r.ci_upper[n], (n, r.values[n], r.ci_lower[n], r.ci_upper[n])
        if r.identifiability[n].identifiable:
            assert abs(r.values[n] - v) < 0.05 * (r.ci_upper[n] - r.ci_lower[n])


def test_a0_is_blind_to_the_modulus_when_the_chain_is_fixed():
    """E multiplies the strip's current only (a gain), so with the beam fixed it cannot move a0 (the poles)."""
    a0 = _generator_a0(TEMPS_C, 15e3, -0.0075)
    data = A0Series(TEMPS_C, a0, np.full(TEMPS_C.size, 0.02), np.zeros(TEMPS_C.size), 0.02, "independent")
    base, effects = _library_side()
    respond = series_model(base, {}, effects, F_HZ, TEMPS_C, beam_follows_E=False)
    cal = calibrate_laws(data, respond, F_HZ, law_free_parameters(base, ["laws.d.activation_energy", "laws.E.slope"]))
    idf = cal.result.identifiability["laws.E.slope"]
    assert not idf.identifiable and "zero sensitivity" in idf.reason
    assert cal.result.held == ["laws.E.slope"] and math.isnan(cal.result.ci_lower["laws.E.slope"])


def test_library_series_model_matches_the_independent_generator():
    a0 = _generator_a0(TEMPS_C, TRUTH["laws.d.activation_energy"], TRUTH["laws.E.slope"])
    base, effects = _library_side()
    respond = series_model(base, {}, effects, F_HZ, TEMPS_C, beam_follows_E=True)
    mine = levy_4_4(F_HZ, respond([dict(TRUTH)]))[1][0, :, -1]
    np.testing.assert_allclose(mine, a0, rtol=1e-6)


def test_interval_coverage_under_noise():
    """Noisy a0 (σ of ln a0 = 0.02, 20 seeded draws): the 95 % intervals cover the truth in ≥ 80 % of
    the draws (binomial: P(≤ 15 of 20 | 0.95) ≈ 0.003)."""
    sig = 0.02
    a0 = _generator_a0(TEMPS_C, TRUTH["laws.d.activation_energy"], TRUTH["laws.E.slope"])
    base, effects = _library_side()
    respond = series_model(base, {}, effects, F_HZ, TEMPS_C, beam_follows_E=True)
    rng = np.random.default_rng(16)
    hits = {n: 0 for n in TRUTH}
    for _ in range(20):
        noisy = a0 * np.exp(sig * rng.standard_normal(a0.size))
        data = A0Series(TEMPS_C, noisy, np.full(TEMPS_C.size, sig), np.zeros(TEMPS_C.size), sig, "independent")
        r = calibrate_laws(data, respond, F_HZ, law_free_parameters(base, list(TRUTH)), starts=1).result
        for n, v in TRUTH.items():
            hits[n] += bool(r.identifiability[n].identifiable and r.ci_lower[n] <= v <= r.ci_upper[n])
    assert min(hits.values()) >= 16, hits


def test_laws_do_nothing_at_the_reference_temperature():
    """At T_ref = 35 °C every law factor is 1, so the series model is the step's 35 °C response
    (physmodel's EffectModel called directly) whatever the law parameters."""
    from scenarios.steps_chain import _response

    base, effects = _library_side()
    vals = {f"{e}.{p}": v for e, pv in effects.items() for p, v in pv.items()}
    want = _response(base, vals, list(effects), F_HZ, T35) / 1e3                       # µA/mm -> A/m
    respond = series_model(base, {}, effects, F_HZ, [T35], beam_follows_E=True)
    got = respond([{}, {"laws.d.activation_energy": 90e3, "laws.E.slope": 0.03, "laws.kappa_e.slope": -0.04}])
    np.testing.assert_allclose(got[:, 0, :], np.broadcast_to(want, (2, F_HZ.size)), rtol=1e-12)
