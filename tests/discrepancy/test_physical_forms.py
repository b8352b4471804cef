"""The effects in their physical form (issue 27 item 4) against oracles the library did not produce:

* ``higher_modes``: the cantilever roots against mpmath (1 + cos λ cosh λ = 0 at 30 digits) and the
  independent generator's brentq roots; participations against the generator's quadrature; the
  library effect against a finite-element cantilever with a modal damping matrix built from the FE's
  own modes, solved directly; and against the generator's own modal sum;
* ``distributed_cpe``: a finite two-rail ladder whose every shunt is (polymer branch + 2 r2 + CPE),
  written from the generator's own polymer admittance, converging as 1/n² to the library with the
  number of sections; ideal electrodes → ``series_cpe``; the generator's own implementation; off is
  bit-identical to the base;
* ``mount_resonance`` (sensor) and ``clamp_mount`` (actuator): directly solved two-mass/spring circuits;
* calibration: the library effect fitted to independent-generator data closes the gap to the noise
  (χ² at its 99.9 % quantile), the base alone does not.
"""

from __future__ import annotations

import math

import beam_circuit_oracles as oracles
import independent_generator as gen
import independent_physics as ip
import independent_sensor as isn
import mpmath
import numpy as np
import pytest
from scipy.stats import chi2

from physmodel import ActuatorModel, IPMCParameters, SensorModel, beam, electrode, get_parameter_set
from physmodel.effects import LIBRARY, EffectModel, declared_confusable
from physmodel.effects.sensing import base_excited_resonance, mount_resonance
from physmodel.params import STATE_FIELDS

P = get_parameter_set("seed002_table3").replace(r1_sheet=500.0)      # a clearly decaying moment


# =========================================================================== higher modes
def test_cantilever_roots_against_mpmath_and_the_generator():
    lam = beam.cantilever_roots(8)
    mpmath.mp.dps = 30
    ref = [mpmath.findroot(lambda x: 1 + mpmath.cos(x) * mpmath.cosh(x), (k - 0.5) * mpmath.pi) for k in range(1, 9)]
    np.testing.assert_allclose(lam, [float(r) for r in ref], rtol=1e-14)
    np.testing.assert_allclose(lam, ip.cantilever_roots(8), rtol=1e-14)
    assert (lam[1] / lam[0]) ** 2 == pytest.approx(6.2669, abs=1e-4)          # Blevins Table 8-1


def test_participations_for_actuation_and_sensing_loading():
    x = np.array([0.0, 0.8 + 0.6j, 2.5 + 2.0j, 6.0 + 5.0j])
    np.testing.assert_allclose(beam.moment_participation(x, 8), ip.modal_participation(x, 8), rtol=1e-7, atol=1e-12)
    # tip force: 3 φ_n(1)²/λ_n⁴ from the generator's own mode shapes, and the static check Σ → 1
    lam = ip.cantilever_roots(8)
    phi1 = ip.mode_shape(lam, [1.0])[:, 0]
    np.testing.assert_allclose(beam.tip_force_participation(8), 3 * phi1**2 / lam**4, rtol=1e-12)
    # modes above 8 carry ≈ Σ 12/λ_n⁴ (φ_n(1)² → 4)
    tail = sum(12.0 / ((k - 0.5) * math.pi) ** 4 for k in range(9, 200000))
    assert 1 - beam.tip_force_participation(8).sum() == pytest.approx(tail, rel=0.01)


def test_modal_damping_sum_matches_the_generator():
    s = 2j * np.pi * np.logspace(-1, 2.5, 40)
    for x in (0.0, 1.2 + 0.8j):
        np.testing.assert_allclose(beam.modal_damping_response(s, 70.0, 0.18, 0.03, x, 8),
                                   ip.modes_with_modal_damping(x, s, 70.0, 0.18, 0.03, 8), rtol=1e-12)


@pytest.mark.parametrize("zeta_h", [0.02, 0.2])
def test_higher_modes_against_finite_element_cantilever_with_modal_damping(zeta_h):
    """M_effect/H (weight 1) equals the FE tip over its static value, the FE damped mode by mode
    (ξ on its first mode, ζ_h on all others), under the library's own line moment profile."""
    T_c = 26.85
    f = np.array([0.3, 5.0, 11.0, 40.0, 75.0, 120.0, 200.0])
    st = ActuatorModel(P).state([T_c])
    p = {k: getattr(st, k) for k in STATE_FIELDS}
    A = electrode.strip_terms(p, 2j * np.pi * f[None, None, :], want_xcoth=False).A
    x = electrode.line_argument(A, p["r1"], p["L"])[0, 0]
    assert np.max(np.abs(x)) > 1.0
    r = EffectModel(P, "actuator", {"higher_modes": {"weight": 1.0, "damping": zeta_h}}).frequency_response(
        f, [T_c], quantities=("M", "H"))
    lib = r["M"][0, 0] / r["H"][0, 0]
    w1, xi = float(st.omega_n.ravel()[0]), float(st.xi.ravel()[0])
    lam1 = beam.cantilever_roots(1)[0]
    scale = lam1**2 / w1                       # FE beam with EI = ρA = L = 1: ω1 = λ1²
    fe = []
    for fk, xk in zip(f, x):
        tip, tip0 = oracles.fe_cantilever_tip_modal([2j * np.pi * fk * scale],
                                                    lambda z, xk=xk: np.cosh(xk * (1 - z)) / np.cosh(xk),
                                                    lambda k: xi if k == 0 else zeta_h, n_el=60)
        fe.append(tip[0] / tip0)
    # the library keeps modes above N (modes_for_band) quasi-static: π_N+1 (ω/ω_N+1)² ≲ 1e-5 here
    np.testing.assert_allclose(lib, np.array(fe), rtol=2e-4)
    assert np.max(np.abs(lib / beam.first_mode(2j * np.pi * f, w1, xi) - 1)) > 0.05     # not the base


def test_higher_modes_matches_the_independent_generator():
    b = gen._at_reference(gen.START_SEED002, 25.0, False)
    lib = IPMCParameters.from_dict(gen.library_fields(b))
    f, T = np.logspace(np.log10(0.02), np.log10(200.0), 41), [25.0]
    mine = ip.actuator_response(b, f, T, {"bending_modes": {"n_modes": 12, "zeta_higher": 0.04}})["M"]
    got = EffectModel(lib, "actuator", {"higher_modes": {"weight": 1.0, "damping": 0.04}}).frequency_response(
        f, T, quantities=("M",))["M"][0]
    # the library's modes_for_band keeps every mode below 10·f_max dynamic; the generator 12 modes:
    # they differ by the modes in between taken quasi-statically, ≤ 1e-2 π_N+1 (module doc of beam)
    np.testing.assert_allclose(got, mine, rtol=1e-4)
    assert np.max(np.abs(mine / ip.actuator_response(b, f, T)["M"] - 1)) > 0.1     # visible near ω2


def test_higher_modes_off_and_declared_confusable_with_second_mode():
    f = np.logspace(-1, 2, 9)
    a = ActuatorModel(P).frequency_response(f, [25.0], quantities=("M",))["M"]
    b = EffectModel(P, "actuator", {"higher_modes": {"weight": 0.0, "damping": 0.3}}).frequency_response(
        f, [25.0], quantities=("M",))["M"]
    assert np.array_equal(a, b)
    assert declared_confusable("second_mode", "higher_modes")


# =========================================================================== distributed CPE
def _ladder_case(q_area, n_cpe, f, r1s=500.0, Gp=None):
    b = gen._at_reference(gen.START_SEED002, 25.0, False)
    b["r1s"] = r1s
    if Gp is not None:
        b["Gp"] = Gp
    st = ip.base_state(b, [25.0])
    s = 2j * np.pi * np.asarray(f)
    K = ip.FARADAY**2 * b["d"] * b["C"] / (b["eps"] * ip.R_GAS * st["T"][0, 0])
    W, h, L = b["W"], b["h"], b["L"]
    gam = h * np.sqrt((s + K) / b["d"])
    y_p = W * b["eps"] * s * gam * (s + K) / (2 * h * (s * gam + K * np.tanh(gam)))
    z_if = 1.0 / (q_area * W * s**n_cpe)
    return b, s, y_p, z_if, W, L


@pytest.mark.parametrize("cpe", [(20.0, 0.8), (2.0, 0.65)])
def test_distributed_cpe_against_a_finite_ladder(cpe):
    """Every ladder shunt is the polymer branch in series with 2 r2 and the interface CPE (per
    section), plus the leakage; nodal analysis of n = 50 … 400 sections converges as 1/n² to the
    library's Z and to its actuation ∫(L − z) v_polymer dz relative to no CPE."""
    q_area, n_cpe = cpe
    f = np.array([0.05, 0.5, 3.0, 20.0, 50.0])
    b, s, y_p, z_if, W, L = _ladder_case(q_area, n_cpe, f)
    r1, r2, g = b["r1s"] / W, b["r2s"] / W, b["Gp"] * W
    lib = IPMCParameters.from_dict(gen.library_fields(b))
    got = EffectModel(lib, "actuator", {"distributed_cpe": {"S_area": 1.0 / q_area, "n": n_cpe}}).frequency_response(
        f, [25.0], quantities=("M", "Z"))
    base = ActuatorModel(lib).frequency_response(f, [25.0], quantities=("M", "Z"))
    lib_Z, lib_R = got["Z"][0, 0], got["M"][0, 0] / base["M"][0, 0]
    errs = []
    for n in (50, 100, 200, 400):
        Zs, ratio = [], []
        for k in range(f.size):
            zb = 1 / y_p[k] + 2 * r2 + z_if[k]
            zb0 = 1 / y_p[k] + 2 * r2
            Zin, z, v = oracles.ladder_with_series(1 / zb + g, r1, L, n)
            _, _, v0 = oracles.ladder_with_series(1 / zb0 + g, r1, L, n)
            wts = np.full(n + 1, L / n)
            wts[[0, -1]] /= 2
            vp, vp0 = v * (1 / y_p[k]) / zb, v0 * (1 / y_p[k]) / zb0        # the polymer's share
            ratio.append(np.sum(wts * (L - z) * vp) / np.sum(wts * (L - z) * vp0))
            Zs.append(Zin)
        errs.append((np.max(np.abs(np.array(Zs) / lib_Z - 1)), np.max(np.abs(np.array(ratio) / lib_R - 1))))
        if n >= 200:
            last = (np.array(Zs), np.array(ratio))
        if n == 200:
            prev = (np.array(Zs), np.array(ratio))
    errs = np.array(errs)
    assert np.all(errs[-1] < 1e-3)
    assert np.all((errs[:-1] / errs[1:] > 3.5) & (errs[:-1] / errs[1:] < 4.5))          # O(1/n²)
    Z_ex, R_ex = (4 * last[0] - prev[0]) / 3, (4 * last[1] - prev[1]) / 3
    np.testing.assert_allclose(lib_Z, Z_ex, rtol=2e-6)
    np.testing.assert_allclose(lib_R, R_ex, rtol=2e-6)
    assert np.max(np.abs(lib_R - 1)) > 0.05                                               # visible


def test_distributed_cpe_is_series_cpe_with_ideal_electrodes():
    p = get_parameter_set("seed002_table3").replace(r1_sheet=1e-9, Rp_specific=math.inf)
    f = np.logspace(-1.5, 2, 12)
    cpe = {"S_area": 0.3, "n": 0.75}
    a = EffectModel(p, "actuator", {"distributed_cpe": cpe}).frequency_response(f, [25.0, 45.0], quantities=("M", "Z"))
    b = EffectModel(p, "actuator", {"series_cpe": cpe}).frequency_response(f, [25.0, 45.0], quantities=("M", "Z"))
    for q in ("M", "Z"):
        np.testing.assert_allclose(a[q], b[q], rtol=1e-9)
    assert declared_confusable("series_cpe", "distributed_cpe")
    # with resistive electrodes they differ (the CPE acts along the line)
    c = EffectModel(P, "actuator", {"distributed_cpe": cpe}).frequency_response(f, [25.0], quantities=("M",))["M"]
    d = EffectModel(P, "actuator", {"series_cpe": cpe}).frequency_response(f, [25.0], quantities=("M",))["M"]
    assert np.max(np.abs(c / d - 1)) > 0.02


def test_distributed_cpe_matches_the_independent_generator_and_is_off_exactly():
    b = gen._at_reference(gen.START_SEED002, 25.0, False)
    b["r1s"] = 300.0
    lib = IPMCParameters.from_dict(gen.library_fields(b))
    f, T = gen.FREQUENCIES_HZ, [25.0, 40.0]
    mine = ip.actuator_response(b, f, T, {"distributed_cpe": {"q_area": 20.0, "n": 0.8}})
    got = EffectModel(lib, "actuator", {"distributed_cpe": {"S_area": 1 / 20.0, "n": 0.8}}).frequency_response(
        f, T, quantities=("M", "Z"))
    np.testing.assert_allclose(got["M"][0], mine["M"], rtol=1e-9)
    np.testing.assert_allclose(got["Z"][0], mine["Z"], rtol=1e-9)
    off = EffectModel(lib, "actuator", {"distributed_cpe": {"S_area": 0.0, "n": 0.6}}).frequency_response(f, T)
    ref = ActuatorModel(lib).frequency_response(f, T)
    for q in ref.values:
        assert np.array_equal(off[q], ref[q])
    # sensor: the source current reaches the electrodes through the interface too
    s_on = EffectModel(lib.replace(a0=0.3), "sensor", {"distributed_cpe": {"S_area": 0.05, "n": 0.8}})
    s_off = SensorModel(lib.replace(a0=0.3))
    ratio = s_on.frequency_response(f, [25.0])["S"] / s_off.frequency_response(f, [25.0])["S"]
    assert np.all(np.abs(ratio) < 1.0 + 1e-12) and np.max(np.abs(ratio - 1)) > 0.02


def test_distributed_cpe_composes_with_a_series_element():
    """The series divider sees the strip's impedance with the distributed CPE (Z_tot = Z_dcpe + R)."""
    f = np.logspace(-1, 1.5, 7)
    R = 30.0
    both = EffectModel(P, "actuator", {"distributed_cpe": {"S_area": 0.1, "n": 0.8},
                                       "series_resistance": {"resistance": R}}).frequency_response(f, [25.0])
    one = EffectModel(P, "actuator", {"distributed_cpe": {"S_area": 0.1, "n": 0.8}}).frequency_response(f, [25.0])
    np.testing.assert_allclose(both["Z"], one["Z"] + R, rtol=1e-12)
    np.testing.assert_allclose(both["M"], one["M"] * one["Z"] / (one["Z"] + R), rtol=1e-12)


# =========================================================================== mounts
def test_mount_resonance_against_a_two_mass_circuit():
    """Cup (m1 on the membrane spring k1, driven by a force) carrying the piece m2 through a joint
    (k, c_r), the piece damped by the water (c_a): x2/x1 from the 2×2 solve is the element, whatever
    the cup's own dynamics."""
    f = np.logspace(1, 3, 50)
    s = 2j * np.pi * f
    m1, k1, c1 = 5e-3, 4e3, 0.3
    m2, k, cr, ca = 2e-3, 2e3, 0.05, 0.25
    x = np.array([np.linalg.solve([[m1 * si**2 + (c1 + cr) * si + k1 + k, -(cr * si + k)],
                                   [-(cr * si + k), m2 * si**2 + (cr + ca) * si + k]], [1.0, 0.0]) for si in s])
    tau, zeta = math.sqrt(m2 / k), (cr + ca) / (2 * math.sqrt(k * m2))
    np.testing.assert_allclose(mount_resonance(s, tau, zeta, cr / (cr + ca)), x[:, 1] / x[:, 0], rtol=1e-12)
    np.testing.assert_allclose(mount_resonance(s, tau, zeta, 1.0), base_excited_resonance(s, tau, zeta), rtol=1e-14)
    # the library effect (ν = 0: the water's damping only) on S
    start = get_parameter_set("seed000_sensor_dev", T_ref=35.0 + 273.15)
    v = {"time_constant": tau, "damping": ca / (2 * math.sqrt(k * m2))}
    r = EffectModel(start, "sensor", {"mount_resonance": v}).frequency_response(f, [35.0])["S"][0, 0]
    r0 = SensorModel(start).frequency_response(f, [35.0])["S"][0, 0]
    xa = np.array([np.linalg.solve([[m1 * si**2 + c1 * si + k1 + k, -k], [-k, m2 * si**2 + ca * si + k]], [1.0, 0.0])
                   for si in s])
    np.testing.assert_allclose(r / r0, xa[:, 1] / xa[:, 0], rtol=1e-12)
    assert declared_confusable("fixture_joint", "mount_resonance")


def test_mount_resonance_matches_the_independent_sensor():
    p = get_parameter_set("seed000_sensor_dev", T_ref=isn.START["T"])      # = isn.START (independent_sensor_test)
    f = isn.FREQUENCIES_HZ
    v = isn.draw_effect("mount", np.random.default_rng(3), 0.8)
    a = isn.response(isn.START, {"mount": v}, f)
    a0 = isn.response(isn.START, {}, f)
    lv = {"time_constant": 1 / (2 * math.pi * v["f_m"]), "damping": v["zeta"]}
    b = EffectModel(p, "sensor", {"mount_resonance": lv}).frequency_response(f, [isn.TEMPERATURE_C])["S"][0, 0]
    b0 = SensorModel(p).frequency_response(f, [isn.TEMPERATURE_C])["S"][0, 0]
    np.testing.assert_allclose(a / a0, b / b0, rtol=1e-12)
    assert np.max(np.abs(a / a0 - 1)) > 0.05


def test_clamp_mount_against_a_two_mass_circuit():
    """Strip (first mode: tip mass m_t, spring k_t, damping c_t to the fluid) on a clamp (m_c, k_c,
    c_c to the lab), the active force pair F between tip and clamp: x_t from the 2×2 solve over the
    rigid clamp's."""
    p = get_parameter_set("seed002_table3")
    f = np.logspace(-1, 2, 60)
    s = 2j * np.pi * f
    st = ActuatorModel(p).state([26.85])
    w1, xi = float(st.omega_n.ravel()[0]), float(st.xi.ravel()[0])
    kt = 1.0
    mt, ct = kt / w1**2, 2 * xi * w1 * (kt / w1**2)
    mc, kc, cc = 4 * mt, 4 * mt * (2 * math.pi * 20.0) ** 2, 0.2 * 2 * math.sqrt(4 * mt * 4 * mt * (2 * math.pi * 20.0) ** 2) / 2
    xt = np.array([np.linalg.solve([[mt * si**2 + ct * si + kt, -kt],
                                    [-kt, mc * si**2 + cc * si + kc + kt]], [1.0, -1.0])[0] for si in s])
    x0 = 1.0 / (mt * s**2 + ct * s + kt)
    v = {"time_constant": math.sqrt(mc / kc), "damping": cc / (2 * math.sqrt(kc * mc)), "mass_ratio": mt / mc}
    r = EffectModel(p, "actuator", {"clamp_mount": v}).frequency_response(f, [26.85], quantities=("M",))["M"][0, 0]
    r0 = ActuatorModel(p).frequency_response(f, [26.85], quantities=("M",))["M"][0, 0]
    np.testing.assert_allclose(r / r0, xt / x0, rtol=1e-10)
    assert np.max(np.abs(xt / x0 - 1)) > 0.05


# =========================================================================== registration
@pytest.mark.parametrize("name", ["higher_modes", "distributed_cpe", "clamp_mount", "mount_resonance"])
def test_registered_with_source_off_and_bounds(name):
    e = LIBRARY[name]
    assert e.reference and e.description and e.switch is not None
    for prm in e.parameters:
        assert prm.lower <= prm.off <= prm.upper and prm.unit


# =========================================================================== calibration closes the gap
def _fit(data, base_free, predictor, effect=None, starts=()):
    from physmodel.estimation.lsq import fit_parameters
    from physmodel.estimation.records import FreeParameter

    best = None
    for st in (starts or [None]):
        fr = list(base_free)
        if effect is not None:
            cp = LIBRARY[effect].candidate_parameters()
            fr += [FreeParameter(f"{effect}.{q.name}", q.lower, q.upper, "linear",
                                 float(np.clip((st or {}).get(q.name, q.typical), q.lower, q.upper))) for q in cp]
        r = fit_parameters(data, None, fr, predict_many=predictor.many, starts=1, seed=0, max_nfev=400, identify=False)
        best = r if best is None or r.cost < best.cost else best
    return best


def _closes(sweep, p0, kind, free, effect, starts):
    from physmodel.estimation.discrepancy import free_parameters_for

    q = "M" if kind == "actuator" else "S"
    fr = free_parameters_for(p0, free, {})
    base = _fit(sweep, fr, EffectModel(p0, kind, {}).predictor(sweep, q))
    eff = _fit(sweep, fr, EffectModel(p0, kind, {effect: {}}).predictor(sweep, q), effect, starts)
    dof = 2 * sweep.response.size - len(fr) - len(LIBRARY[effect].parameters)
    limit = chi2.ppf(0.999, dof)
    return 2 * base.cost, 2 * eff.cost, limit


def test_higher_modes_calibrated_closes_the_independent_gap():
    f = np.logspace(np.log10(0.02), np.log10(200.0), 41)
    sweep, truth = gen.make_case(123, "bending_modes", size=0.8, frequencies_hz=f, baseline_lambda=False)
    p0 = IPMCParameters.from_dict(dict(truth["library_base"]))
    lam_b, lam_e, limit = _closes(sweep, p0, "actuator", ("alpha0", "d", "kappa_e", "xi", "omega_n"), "higher_modes",
                                  [{"weight": 1.0, "damping": 0.05}, {"weight": 1.0, "damping": 0.02}])
    assert lam_b > 3 * limit and lam_e < limit


def test_distributed_cpe_calibrated_closes_the_independent_gap():
    sweep, truth = gen.make_case(321, "distributed_cpe", size=0.7, thermal=False, baseline_lambda=False)
    p0 = IPMCParameters.from_dict(dict(truth["library_base"]))
    lam_b, lam_e, limit = _closes(sweep, p0, "actuator", ("alpha0", "d", "kappa_e", "xi", "omega_n"), "distributed_cpe",
                                  [{"S_area": 0.05, "n": 0.8}, {"S_area": 0.5, "n": 0.7}])
    assert lam_b > 3 * limit and lam_e < limit


def test_mount_resonance_calibrated_closes_the_independent_gap():
    sweep, truth = isn.make_case(77, "mount", size=0.9)
    p0 = get_parameter_set("seed000_sensor_dev", T_ref=isn.START["T"])
    lf = isn.library_fields(truth["base"])
    p0 = p0.replace(**{k: lf[k] for k in ("a0", "d", "kappa_e")})
    lam_b, lam_e, limit = _closes(sweep, p0, "sensor", ("a0", "d", "kappa_e"), "mount_resonance",
                                  [{"time_constant": 1 / (2 * math.pi * 100), "damping": 0.1},
                                   {"time_constant": 1 / (2 * math.pi * 300), "damping": 0.3}])
    assert lam_b > 3 * limit and lam_e < limit


def test_a_pair_the_data_do_not_separate_carries_the_librarys_reason_when_it_declares_them(monkeypatch):
    """``declare_confusable`` says why the library holds two forms as one physics (effects.CONFUSABLE)."""
    from physmodel.estimation import signatures

    sig = np.arange(1.0, 9.0).reshape(4, 2)          # a signature: (residuals, parameters)
    confusable, separation = [], {}
    conf = {"data": [{"top": "distributed_cpe", "other": "series_cpe", "z": 0.3, "separated": False},
                     {"top": "distributed_cpe", "other": "leakage", "z": 0.2, "separated": False}],
            "in_band": []}
    sigs = {"distributed_cpe": sig, "series_cpe": sig, "leakage": sig}
    monkeypatch.setattr(signatures, "separation_hint", lambda a, b, raw, data: "")
    signatures.declare_confusable(confusable, separation, conf, sigs, sigs, None)
    twin = separation["distributed_cpe~series_cpe"]
    assert declared_confusable("series_cpe", "distributed_cpe") in twin and "two forms" in twin
    assert "two forms" not in separation["distributed_cpe~leakage"]
