"""Validation of the independent blind-case generator (issue 11), each part against an oracle it
did not produce:

(a) its actuator against the library's ``physmodel.ActuatorModel`` — two implementations of the
    Chen–Tan model written separately must agree to rounding for the same physical parameters;
(b) its second bending mode (modal participation, Rayleigh damping, moment profile from the
    electrode line) against a finite-element Euler–Bernoulli cantilever solved directly;
(c) its series constant-phase element against nodal analysis of the two-rail electrode ladder
    driven through the CPE;
(d) every hidden effect is exactly off at its off value and clearly on at its largest size;
plus the case machinery (seeds, noise, λ, imports).
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import beam_circuit_oracles as oracles
import independent_generator as gen
import independent_physics as ip
import numpy as np
import pytest
from scipy import constants

from physmodel import ActuatorModel, IPMCParameters

HERE = Path(__file__).resolve().parent
F_HZ = np.logspace(-2, 2.5, 37)


def _library(base):
    return ActuatorModel(IPMCParameters.from_dict(gen.library_fields(base)))


def _bases():
    """Seed 002 at 25 °C, drawn bases, and the legal edge values (no leakage, ideal electrodes)."""
    b0 = gen._at_reference(gen.START_SEED002, 25.0, False)
    rng = np.random.default_rng(11)
    out = [b0] + [gen.draw_base(gen.START_SEED002, rng, ("alpha", "d", "zeta", "f1", "eps", "C"), False)
                  for _ in range(3)]
    out += [dict(b0, Gp=0.0), dict(b0, r1s=0.0, r2s=0.0), dict(b0, r1s=2000.0, r2s=5e-3, Gp=100.0)]
    return out


# --------------------------------------------------------------------------- (a) cross-check
@pytest.mark.parametrize("k", range(7))
def test_base_agrees_with_library_isothermal(k):
    base = _bases()[k]
    T = [19.0, 37.0, 55.0]                     # K = F²dC/(κe R T) carries 1/T even without laws
    lib = _library(base).frequency_response(F_HZ, T, quantities=("M", "Z"))
    mine = ip.actuator_response(base, F_HZ, T)
    np.testing.assert_allclose(mine["M"], lib["M"][0], rtol=1e-9, atol=0)
    np.testing.assert_allclose(mine["Z"], lib["Z"][0], rtol=1e-9, atol=0)


def test_base_agrees_with_library_with_temperature_laws():
    """Arrhenius-by-Q10 diffusivity, log-linear modulus, Nernst–Einstein leakage and the mode's
    √E shift agree to rounding when κe is held constant on both sides."""
    base = dict(gen._at_reference(gen.START_SEED002, 25.0, True), eps_water=False)
    T = [19.0, 28.0, 37.0, 46.0, 55.0]
    lib = _library(base).frequency_response(F_HZ, T, quantities=("M", "Z"))
    mine = ip.actuator_response(base, F_HZ, T)
    np.testing.assert_allclose(mine["M"], lib["M"][0], rtol=1e-9, atol=0)
    np.testing.assert_allclose(mine["Z"], lib["Z"][0], rtol=1e-9, atol=0)


def test_water_permittivity_fits_differ_only_slightly():
    """The two sides use different published fits of ε_water(T) (Owen et al. 1961 here, Malmberg &
    Maryott 1956 in the library).  The response difference is measured and bounded by the
    difference of the two fits' ratios ε(T)/ε(25 °C) (sensitivity of M to κe is at most 1)."""
    base = gen._at_reference(gen.START_SEED002, 25.0, True)
    T = np.array([19.0, 28.0, 37.0, 46.0, 55.0])
    mine = ip.actuator_response(base, F_HZ, T)["M"]
    lib = _library(base).frequency_response(F_HZ, T, quantities=("M",))["M"][0]
    mm = lambda t: 87.740 - 0.40008 * t + 9.398e-4 * t**2 - 1.410e-6 * t**3  # noqa: E731
    fit_gap = np.max(np.abs(ip.water_permittivity(T) / ip.water_permittivity(25.0) - mm(T) / mm(25.0)))
    diff = np.max(np.abs(mine / lib - 1))
    assert 1e-5 < diff <= fit_gap < 2e-3


# --------------------------------------------------------------------------- beam
def test_cantilever_roots_and_mode_shapes():
    """Roots against the printed table (Blevins, Formulas for natural frequency, Table 8-1,
    9 digits); unit-norm modes with tip value ±2; uniform-moment participations sum to 1."""
    lam = ip.cantilever_roots(5)
    np.testing.assert_allclose(lam, [1.87510407, 4.69409113, 7.85475744, 10.99554073, 14.13716839], atol=6e-9)
    xi = np.linspace(0, 1, 4001)
    phi = ip.mode_shape(lam, xi)
    norms = np.sum((phi[:, 1:] ** 2 + phi[:, :-1] ** 2) / 2 * np.diff(xi), axis=1)
    np.testing.assert_allclose(norms, 1.0, rtol=1e-6)
    np.testing.assert_allclose(np.abs(phi[:, -1]), 2.0, rtol=1e-10)
    p = ip.uniform_moment_participation(200)
    np.testing.assert_allclose(p[:4], [0.890772, 0.078774, 0.016495, 0.006018], atol=1e-6)
    assert abs(p.sum() - 1) < 2e-5                  # tail Σ_{n>200} 8/λ_n³ ≈ 1.6e-6


@pytest.mark.parametrize("x", [0.0, 1 + 1j, 5 + 3j, 20 + 10j])
@pytest.mark.parametrize("nu", [0.0, 0.7, 1.0])
def test_second_mode_against_finite_elements(x, nu):
    """Modal sum (12 modes + quasi-static residual) vs 160 Hermite elements, Rayleigh damping,
    moment profile cosh(x(1 − ξ))/cosh x, 0.05-25 ω1 (modes 1-3 and the antiresonance near 3 ω1).
    A-priori error: truncation Σ_{n>12} π_n (ω/ω_n)² < 1e-6, mesh < 1e-5 of the static deflection."""
    lam1 = 1.8751040687119611                      # Blevins Table 8-1
    w1, z1 = lam1**2, 0.05                          # L = EI = ρA = 1
    s = 1j * w1 * np.array([0.05, 0.5, 0.98, 1.0, 1.5, 3.0, 5.0, 6.27, 8.0, 17.5, 25.0])
    tip, static = oracles.fe_cantilever_tip(
        s, lambda z: np.cosh(x * (1 - z)) / np.cosh(x) + 0 * z, n_el=160,
        rayleigh=(2 * z1 * w1 * nu, 2 * z1 * (1 - nu) / w1))
    assert abs(static / ip.bending_kernel(x) - 1) < 1e-8      # FE statics = closed-form X(x)
    fe = tip / static
    xs = np.full(s.shape, x, dtype=complex)
    assert np.max(np.abs(ip.modal_mechanics(xs, s, w1, z1, 12, nu) - fe)) < 2e-5
    # the base's folded single mode misses it by far more (the test can fail)
    assert np.max(np.abs(ip.modal_mechanics(xs, s, w1, z1, 1) - fe)) > 0.1


# --------------------------------------------------------------------------- (c) series CPE
def _slice(base, s, T_c):
    """Slice physics from seed 002 eq. (11)-(13), written out again here for the ladder."""
    F, R = constants.physical_constants["Faraday constant"][0], constants.R
    K = F**2 * base["d"] * base["C"] / (base["eps"] * R * (T_c + constants.zero_Celsius))
    g = base["h"] * np.sqrt((s + K) / base["d"])
    yp = base["W"] * base["eps"] * s * g * (s + K) / (2 * base["h"] * (s * g + K * np.tanh(g)))
    zb = 1 / yp + 2 * base["r2s"] / base["W"]
    phi = base["alpha"] * base["W"] * base["eps"] * K * (g - np.tanh(g)) / (s * g + K * np.tanh(g))
    return 1 / zb + base["Gp"] * base["W"], (1 / yp) / zb, phi


def _ladder_case(base, cpe, f, T_c, n):
    EI = base["E"] * 2 / 3 * base["W"] * base["h"] ** 3
    w1 = 2 * np.pi * base["f1"]
    M, Z = [], []
    for fi in f:
        s = 2j * np.pi * fi
        y, fpol, phi = _slice(base, s, T_c)
        Q = cpe["q_area"] * base["W"] * base["L"]
        zc = np.exp(-0.5j * np.pi * cpe["n"]) / (Q * (2 * np.pi * fi) ** cpe["n"])   # polar form
        Zin, z, v = oracles.ladder_with_series(y, base["r1s"] / base["W"], base["L"], n, zc)
        wts = np.full(n + 1, base["L"] / n)
        wts[[0, -1]] /= 2
        tip = -np.sum(wts * (base["L"] - z) * phi * fpol * v) / EI
        M.append(tip * w1**2 / (s * s + 2 * base["zeta"] * w1 * s + w1**2))
        Z.append(Zin)
    return np.array(M), np.array(Z)


@pytest.mark.parametrize("cpe", [{"n": 0.75, "q_area": 20.0}, {"n": 0.6, "q_area": 2.0}, {"n": 0.95, "q_area": 500.0}])
def test_series_cpe_against_ladder(cpe):
    """Nodal analysis of the ladder driven through the CPE converges at second order to the closed
    form (error ratio ≈ 4 per halving; Richardson-extrapolated agreement < 1e-6)."""
    base = gen._at_reference(gen.START_SEED002, 25.0, False)
    f = np.array([0.05, 0.5, 3.0, 20.0, 50.0])
    cf = ip.actuator_response(base, f, [25.0], {"series_cpe": cpe})
    errs = []
    for n in (100, 200):
        M, Z = _ladder_case(base, cpe, f, 25.0, n)
        errs.append((M, Z))
    for q, i in (("M", 0), ("Z", 1)):
        ref = cf[q][0]
        e1, e2 = np.abs(errs[0][i] / ref - 1), np.abs(errs[1][i] / ref - 1)
        assert np.all(e2 < 1e-3)
        big = e1 > 1e-7
        assert np.all((e1[big] / e2[big] > 3.5) & (e1[big] / e2[big] < 4.5))
        rich = (4 * errs[1][i] - errs[0][i]) / 3
        assert np.max(np.abs(rich / ref - 1)) < 1e-6
    base_only = ip.actuator_response(base, f, [25.0])
    assert np.max(np.abs(cf["M"] / base_only["M"] - 1)) > 0.02          # the CPE is visible
    assert np.all(np.real(cf["Z"] - base_only["Z"]) > 0)                 # a passive series element


# --------------------------------------------------------------------------- (d) off values
@pytest.mark.parametrize("name", list(gen.EFFECT_SPECS))
def test_effect_off_and_on(name):
    base = gen._at_reference(gen.START_SEED002, 25.0, True)
    T = list(gen.TEMPERATURES_C)
    ref = ip.actuator_response(base, gen.FREQUENCIES_HZ, T)
    off = ip.actuator_response(base, gen.FREQUENCIES_HZ, T, {name: gen.off_values(name)})
    np.testing.assert_allclose(off["M"], ref["M"], rtol=1e-13, atol=0)
    np.testing.assert_allclose(off["Z"], ref["Z"], rtol=1e-13, atol=0)
    on = ip.actuator_response(base, gen.FREQUENCIES_HZ, T,
                              {name: gen.draw_effect(name, np.random.default_rng(0), size=1.0)})
    assert np.max(np.abs(on["M"] / ref["M"] - 1)) > 0.02


def test_effect_directions():
    """Physical invariants of the effects: contact resistance lowers the gain (seed 002 Fig. 11),
    the extra fluid load lowers and damps the resonance (passive: Im of the modal denominator > 0),
    the series resistance and CPE add a positive real part to Z, leakage lowers |Z| at 0.05 Hz."""
    base = gen._at_reference(gen.START_SEED002, 25.0, False)
    f = np.linspace(3, 20, 400)
    r0 = ip.actuator_response(base, f, [25.0])
    r2 = ip.actuator_response(base, f, [25.0], {"contact_resistance": {"extra_area_resistance": 1e-3}})
    assert np.all(np.abs(r2["M"]) < np.abs(r0["M"]))
    w1, w = 2 * np.pi * base["f1"], 2 * np.pi * f
    mu = 0.5 * np.conj(ip.hydrodynamic_gamma(10.0 * w / w1))   # as actuator_response builds it
    g0 = np.abs(ip.modal_mechanics(0.0, 1j * w, w1, base["zeta"]))
    g1 = np.abs(ip.modal_mechanics(0.0, 1j * w, w1, base["zeta"], mu=mu))
    assert f[np.argmax(g1)] < f[np.argmax(g0)] and g1.max() < g0.max()
    assert np.all(-mu.imag > 0)                    # −ω²(1 + μ) adds +j·(damping)
    lk = ip.actuator_response(base, [0.05], [25.0], {"leakage": {"conductance": 30.0}})
    assert abs(lk["Z"][0, 0]) < abs(ip.actuator_response(base, [0.05], [25.0])["Z"][0, 0])


# --------------------------------------------------------------------------- cases
def test_make_case_is_reproducible_and_blind():
    a, ta = gen.make_case(5, "time_delay+leakage")
    b, tb = gen.make_case(5, "time_delay+leakage")
    c, _ = gen.make_case(6, "time_delay+leakage")
    np.testing.assert_array_equal(a.response, b.response)
    assert ta["effects"] == tb["effects"] and not np.array_equal(a.response, c.response)
    assert ta["expected"] == ["leakage", "time_delay"]
    assert "time_delay" not in str(a.metadata) and "leakage" not in str(a.metadata)
    assert a.output_unit == "mm" and a.input_unit == "V" and a.response.size == 5 * 31
    assert a.temperatures().tolist() == [19.0, 28.0, 37.0, 46.0, 55.0]
    assert a.frequency_hz.min() == pytest.approx(0.05) and a.frequency_hz.max() == pytest.approx(50.0)


def test_base_drawn_away_from_start_and_library_round_trip():
    _, t = gen.make_case(3, "none", thermal=True)
    start = gen._at_reference(gen.START_SEED002, 25.0, True)
    for k in gen.PERTURBED:
        assert 0.30 <= abs(t["base"][k] / start[k] - 1) <= 0.40
    p = IPMCParameters.from_dict(t["library_base"])
    assert p.omega_n == pytest.approx(2 * np.pi * t["base"]["f1"], rel=1e-12)
    assert p.laws.d.activation_energy == pytest.approx(15e3, rel=1e-12)
    q = IPMCParameters.from_dict(t["library_start"])
    assert q.T_ref == pytest.approx(300.0) and q.alpha0 == pytest.approx(-155 / 75.4)


def test_noise_matches_the_stated_sigma():
    """Standardised residuals of the noisy data have unit variance (620 values: ±5 sd = ±0.28)."""
    for seed in (1, 2):
        sw, t = gen.make_case(seed, "none")
        exact = ip.actuator_response(t["base"], gen.FREQUENCIES_HZ, gen.TEMPERATURES_C)["M"].reshape(-1) * 1e3
        r = np.log(sw.response / exact)
        z = np.concatenate([r.real / (sw.magnitude_std_db * math.log(10) / 20), r.imag / np.radians(sw.phase_std_deg)])
        assert abs(np.var(z) - 1) < 0.28 and abs(np.mean(z)) < 0.2
        rel = np.sqrt(2) * np.radians(sw.phase_std_deg)
        assert 0.005 <= rel.min() and rel.min() <= 0.02 and rel.max() <= 2 * 0.02 + 1e-12


def test_lambda_properties():
    _, t0 = gen.make_case(0, "none")
    assert t0["lam"] == 0 and t0["lam_baseline"] == 0
    _, t = gen.make_case(0, "contact_resistance+leakage")
    assert 0 <= t["lam_baseline"] <= t["lam"] * (1 + 1e-9)
    assert set(t["lam_each"]) == {"contact_resistance", "leakage"}
    for n in t["lam_each"]:
        assert 0 <= t["lam_each_baseline"][n] <= t["lam_each"][n] * (1 + 1e-9)
    small = gen.make_case(0, "series_resistance", size=0.0)[1]["lam_baseline"]
    large = gen.make_case(0, "series_resistance", size=1.0)[1]["lam_baseline"]
    assert small < 25 < large
    # λ after refitting a larger free set (the workflow's, κe too) can only be smaller (nested fits);
    # the same free set gives the same λ
    _, tw = gen.make_case(0, "contact_resistance+leakage", workflow_free=gen.PERTURBED + ("eps",))
    assert 0 <= tw["lam_workflow"] <= tw["lam_baseline"] * (1 + 1e-6)
    for n in tw["lam_each"]:
        assert 0 <= tw["lam_each_workflow"][n] <= tw["lam_each_baseline"][n] * (1 + 1e-6)
    _, ts = gen.make_case(0, "leakage", workflow_free=gen.PERTURBED)
    assert ts["lam_workflow"] == pytest.approx(ts["lam_baseline"], rel=1e-9)


def test_bad_labels_and_sizes():
    with pytest.raises(ValueError, match="label"):
        gen.make_case(0, "gremlins")
    with pytest.raises(ValueError, match="label"):
        gen.make_case(0, "time_delay+time_delay")
    with pytest.raises(ValueError, match="size"):
        gen.make_case(0, "time_delay", size=1.5)
    with pytest.raises(ValueError, match="unknown effect"):
        ip.actuator_response(gen.START_SEED002, [1.0], [25.0], {"gremlins": {}})


def test_generator_does_not_import_the_library_physics():
    """Only the output record may come from physmodel (``physmodel.data.sweep.FrequencySweep``)."""
    for fname in ("independent_physics.py", "independent_generator.py", "beam_circuit_oracles.py"):
        tree = ast.parse((HERE / fname).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                assert not any(a.name.split(".")[0] == "physmodel" for a in node.names), fname
            elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("physmodel"):
                assert fname == "independent_generator.py" and node.module == "physmodel.data.sweep", fname
                assert [a.name for a in node.names] == ["FrequencySweep"]
