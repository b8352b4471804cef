"""The effects library: each effect's "off" value is the base model exactly, each has its documented
physical signature (checked against an independent oracle: an equivalent base-model parameter set,
a closed form, an Euler-Bernoulli root, a constant-phase limit), and effects compose.  The higher
modes and the series interface CPE are checked against a finite-element cantilever and a nodal
ladder in tests/discrepancy/test_library_effects.py."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from physmodel import ActuatorModel, IPMCError, ParameterError, SensorModel, get_parameter_set
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.effects.library import (
    CPE_REFERENCE_HZ,
    LIBRARY,
    OUT_OF_LIBRARY,
    SECOND_MODE_RATIO,
    EffectModel,
    candidates_for,
    get_effect,
)
from physmodel.temperature import Arrhenius, LogLinear

F = np.logspace(-2, 3, 60)
T = [10.0, 26.85, 60.0]
P = get_parameter_set("seed002_table3")
PS = get_parameter_set("seed000_sensor_dev")


def act(effects, params=P, q=("M", "Z", "I", "H")):
    return EffectModel(params, "actuator", effects).frequency_response(F, T, quantities=q)


def sen(effects, params=PS, q=("S", "Z")):
    return EffectModel(params, "sensor", effects).frequency_response(F, T, quantities=q)


def test_library_has_at_least_ten_documented_candidates():
    assert len(LIBRARY) >= 10
    assert not set(OUT_OF_LIBRARY) & set(LIBRARY)
    for e in LIBRARY.values():
        assert e.description and e.reference and e.parameters and e.level in ("parameter", "strip", "response", "series", "kernel")
        for p in e.parameters:
            assert p.lower <= p.off <= p.upper and p.typical != p.off
    for kind, q in (("actuator", "M"), ("sensor", "S"), ("actuator", "Z")):
        assert not set(candidates_for(kind, q)) & set(OUT_OF_LIBRARY)


@pytest.mark.parametrize("name", sorted(LIBRARY) + sorted(OUT_OF_LIBRARY))
def test_off_value_reproduces_base_exactly(name):
    e = get_effect(name)
    if "actuator" in e.kinds:
        base = ActuatorModel(P).frequency_response(F, T, quantities=("M", "Z", "I", "H"))
        got = act({name: e.off})
        for q in ("M", "Z", "I", "H"):
            assert np.array_equal(got[q], base[q]), q
    if "sensor" in e.kinds:
        base = SensorModel(PS).frequency_response(F, T, quantities=("S", "Z"))
        got = sen({name: e.off})
        for q in ("S", "Z"):
            assert np.array_equal(got[q], base[q]), q


def test_every_effect_changes_what_it_claims():
    for name, e in {**LIBRARY, **OUT_OF_LIBRARY}.items():
        for kind, fn, q in (("actuator", act, "M"), ("sensor", sen, "S")):
            if kind in e.kinds and q in e.quantities:
                on, off = fn({name: e.typical})[q], fn({})[q]
                assert np.max(np.abs(np.log(on / off))) > 1e-3, (name, kind)


def test_time_delay_is_phase_only_minus_omega_tau():
    tau = 2.5e-3
    r = act({"time_delay": {"delay": tau}})["M"] / act({})["M"]
    np.testing.assert_allclose(np.abs(r), 1.0, atol=1e-13)
    np.testing.assert_allclose(np.angle(r * np.exp(2j * np.pi * F * tau)), 0.0, atol=1e-12)


def test_amplifier_pole_is_first_order_low_pass():
    ta = 1e-3
    r = sen({"amplifier_bandwidth": {"time_constant": ta}})["S"] / sen({})["S"]
    np.testing.assert_allclose(r, np.broadcast_to(1 / (1 + 2j * np.pi * F * ta), r.shape), rtol=1e-13)


@pytest.mark.parametrize("name,param,field,combine", [
    ("electrode_resistance", "r1_sheet", "r1_sheet", lambda b, v: b + v),
    ("contact_resistance", "r2_specific", "r2_specific", lambda b, v: b + v),
    ("leakage", "conductance", "Rp_specific", lambda b, v: 1.0 / (1.0 / b + v)),
])
def test_electrode_effects_equal_the_base_model_with_changed_parameters(name, param, field, combine):
    v = get_effect(name).typical[param]
    t_ref = [P.T_ref - 273.15]        # leakage is added temperature-independently: compare at T_ref
    oracle = ActuatorModel(P.replace(**{field: combine(getattr(P, field), v)})).frequency_response(F, t_ref)
    got = EffectModel(P, "actuator", {name: {param: v}}).frequency_response(F, t_ref)
    for q in ("M", "Z"):
        np.testing.assert_allclose(got[q], oracle[q], rtol=1e-12)


def test_contact_resistance_lowers_the_gain_seed002():
    lo = act({"contact_resistance": {"r2_specific": 1e-5}})["M"]
    hi = act({"contact_resistance": {"r2_specific": 1e-4}})["M"]
    assert np.all(np.abs(hi) < np.abs(lo)) and np.all(np.abs(lo) < np.abs(act({})["M"]))


def test_series_resistance_is_a_voltage_divider():
    Rs = 50.0
    got, base = act({"series_resistance": {"resistance": Rs}}), act({})
    np.testing.assert_allclose(got["Z"], base["Z"] + Rs, rtol=1e-13)
    np.testing.assert_allclose(got["I"], 1 / (base["Z"] + Rs), rtol=1e-13)
    np.testing.assert_allclose(got["M"], base["M"] * got["I"] * base["Z"], rtol=1e-12)
    assert np.all(np.abs(got["M"]) < np.abs(base["M"]))      # Re Z > 0: a passive divider


def test_temperature_effects_equal_modified_laws_and_vanish_at_T_ref():
    c, dEa = -0.01, 12e3
    got = act({"modulus_temperature": {"slope": c}, "diffusivity_temperature": {"activation_energy": dEa}})
    laws = P.laws.with_(E=LogLinear(slope=P.laws.E.slope + c),
                        d=Arrhenius(activation_energy=P.laws.d.activation_energy + dEa))
    oracle = ActuatorModel(P.replace(laws=laws)).frequency_response(F, T)
    for q in ("M", "Z"):
        np.testing.assert_allclose(got[q], oracle[q], rtol=1e-12)
    t_ref = [P.T_ref - 273.15]
    for name, e in LIBRARY.items():
        if e.needs_temperatures:
            m = EffectModel(P, "actuator", {name: e.typical}).frequency_response(F, t_ref)["M"]
            np.testing.assert_allclose(m, ActuatorModel(P).frequency_response(F, t_ref)["M"], rtol=1e-13)


def test_temperature_effects_curvature_is_a_quadratic_in_ln_factor():
    c, c2 = 0.004, -8e-5
    st0 = ActuatorModel(P).state(T)
    dT = np.asarray(T) + 273.15 - P.T_ref
    for name, field in (("modulus_temperature", "E"), ("permittivity_temperature", "kappa_e")):
        st = EffectModel(P, "actuator", {name: {"slope": c, "curvature": c2}}).state(T)
        np.testing.assert_allclose((getattr(st, field) / getattr(st0, field)).ravel(), np.exp(c * dT + c2 * dT**2),
                                   rtol=1e-13)
    st = EffectModel(P, "actuator", {"diffusivity_temperature": {"curvature": c2}}).state(T)
    np.testing.assert_allclose((st.d / st0.d).ravel(), np.exp(c2 * dT**2), rtol=1e-13)
    np.testing.assert_allclose((st.Rp * st.d / (st0.Rp * st0.d)).ravel(), 1.0, rtol=1e-13)   # Nernst-Einstein


def test_amplifier_second_pole_multiplies():
    t1, t2 = 2e-3, 4e-4
    got, base = act({"amplifier_bandwidth": {"time_constant": t1, "second_time_constant": t2}}), act({})
    s = 2j * np.pi * F
    np.testing.assert_allclose(got["M"], base["M"] / ((1 + s * t1) * (1 + s * t2)), rtol=1e-12)


def test_water_uptake_equals_swollen_strip_at_one_temperature():
    u, t = 0.004, 60.0
    sw = 1 + u * (t + 273.15 - P.T_ref)
    oracle = ActuatorModel(P.replace(h=P.h * sw, C_minus=P.C_minus / sw)).frequency_response(F, [t])["M"]
    got = EffectModel(P, "actuator", {"water_uptake": {"swelling": u}}).frequency_response(F, [t])["M"]
    np.testing.assert_allclose(got, oracle, rtol=1e-12)
    # isotropic swelling: the strip scaled in all three directions, anions diluted by the volume
    iso = ActuatorModel(P.replace(h=P.h * sw, L=P.L * sw, W=P.W * sw, C_minus=P.C_minus / sw**3)).frequency_response(
        F, [t], quantities=("M", "Z"))
    got = EffectModel(P, "actuator", {"water_uptake": {"swelling": u, "in_plane_share": 1.0}}).frequency_response(
        F, [t], quantities=("M", "Z"))
    for q in ("M", "Z"):
        np.testing.assert_allclose(got[q], iso[q], rtol=1e-12)


def test_viscous_fluid_lowers_and_damps_the_resonance():
    # water (Sader 1998 load; its formulas are checked in tests/discrepancy/test_fluid_effect.py):
    # extra mass lowers the peak frequency, the viscous part lowers the peak
    p = P.replace(xi=0.05)
    f = np.linspace(2.0, 30.0, 600)
    base = np.abs(ActuatorModel(p).frequency_response(f, [26.85])["M"][0, 0])
    wet = np.abs(EffectModel(p, "actuator", {"viscous_fluid": {"viscous_load": 1.0}}).frequency_response(f, [26.85])["M"][0, 0])
    assert f[np.argmax(wet)] < f[np.argmax(base)] and wet.max() < base.max()


def test_second_mode_ratio_is_the_euler_bernoulli_root_and_dc_gain_is_kept():
    b = [brentq(lambda x: 1 + math.cos(x) * math.cosh(x), a, a + 1.5) for a in (1.0, 4.0)]
    assert SECOND_MODE_RATIO == pytest.approx((b[1] / b[0]) ** 2, rel=1e-12)
    p = P.replace(xi=0.02)
    f = np.concatenate([[1e-4], np.linspace(30, 150, 800)])
    m = EffectModel(p, "actuator", {"second_mode": {"weight": 1.0}}).frequency_response(f, [26.85])
    base = ActuatorModel(p).frequency_response(f, [26.85])
    assert abs(m["M"][0, 0, 0] / base["M"][0, 0, 0] - 1) < 1e-6
    st = ActuatorModel(p).state([26.85])
    f2 = SECOND_MODE_RATIO * float(st.omega_n.ravel()[0]) / (2 * np.pi)
    mag = np.abs(m["M"][0, 0, 1:])
    assert abs(f[1:][np.argmax(mag)] - f2) < 0.01 * f2      # the second mode's resonance
    # above the first mode the base falls as ω⁻² while the modal sum keeps the higher modes'
    # quasi-static residual: with ideal electrodes (a uniform moment) an antiresonance between the
    # first two modes
    p = p.replace(r1_sheet=0.0)
    f_mid = np.logspace(np.log10(2 * f2 / SECOND_MODE_RATIO), np.log10(0.9 * f2), 300)
    mm = np.abs(EffectModel(p, "actuator", {"second_mode": {"weight": 1.0}}).frequency_response(f_mid, [26.85])["M"][0, 0])
    i = int(np.argmin(mm))
    assert 0 < i < f_mid.size - 1 and mm[i] < 0.2 * np.abs(ActuatorModel(p).frequency_response(f_mid, [26.85])["M"][0, 0, i])


def test_second_mode_weight_interpolates_between_base_and_modal_sum():
    f = np.logspace(-1, 2, 40)
    base, full = act({})["M"], act({"second_mode": {"weight": 1.0, "viscous_share": 0.6}})["M"]
    half = act({"second_mode": {"weight": 0.5, "viscous_share": 0.6}})["M"]
    np.testing.assert_allclose(half, 0.5 * (base + full), rtol=1e-12)
    assert f.size


def test_fractional_transport_gives_a_constant_phase_double_layer():
    beta = 0.8
    p = P.replace(r1_sheet=0.0, r2_specific=0.0, Rp_specific=float("inf"))
    f = np.array([1e-5, 1e-4])
    z = EffectModel(p, "actuator", {"fractional_transport": {"beta": beta}}).frequency_response(f, [26.85], quantities=("Z",))["Z"][0, 0]
    z0 = ActuatorModel(p).frequency_response(f, [26.85], quantities=("Z",))["Z"][0, 0]
    # low frequency: a constant-phase double layer, phase −β·90° (the capacitive model gives −90°)
    np.testing.assert_allclose(np.degrees(np.angle(z)), -90 * beta, atol=0.05)
    np.testing.assert_allclose(np.degrees(np.angle(z0)), -90, atol=0.05)
    # and |Z| falls as ω^-β: 20β dB per decade
    assert 20 * np.log10(abs(z[0] / z[1])) == pytest.approx(20 * beta, abs=0.02)


def test_fractional_transport_is_the_transport_at_s_hat_with_the_mode_at_s():
    beta, f = 0.9, np.array([0.3, 3.0, 30.0])
    s = 2j * np.pi * f
    wc = 2 * np.pi * CPE_REFERENCE_HZ
    s_hat = wc * np.abs(s / wc) ** beta * np.exp(1j * beta * np.pi / 2)    # polar form of ω_c (s/ω_c)^β
    got = EffectModel(P, "actuator", {"fractional_transport": {"beta": beta}}).frequency_response(f, [26.85])
    old = EffectModel(P, "actuator", {"constant_phase_element": {"beta": beta}}).frequency_response(f, [26.85])
    np.testing.assert_array_equal(old["M"], got["M"])                   # the old name is an alias
    at_hat = ActuatorModel(P).evaluate(s_hat, [26.85], quantities=("Z", "H"))
    G = ActuatorModel(P).frequency_response(f, [26.85], quantities=("G",))["G"]
    np.testing.assert_allclose(got["Z"], at_hat["Z"], rtol=1e-12)
    np.testing.assert_allclose(got["M"], at_hat["H"] * G, rtol=1e-12)


def test_coupling_compliance_divides_the_sensor_gain_quasi_statically():
    eps = 0.3
    f = np.array([1e-6])
    r = (EffectModel(PS, "sensor", {"coupling_compliance": {"compliance_ratio": eps}}).frequency_response(f, [25])["S"]
         / SensorModel(PS).frequency_response(f, [25])["S"])
    assert r[0, 0, 0] == pytest.approx(1 / (1 + eps), rel=1e-8)


def test_composition_commutes_and_multiplies():
    a = {"time_delay": {"delay": 1e-3}, "amplifier_bandwidth": {"time_constant": 2e-3},
         "second_mode": {"weight": 0.7}, "series_resistance": {"resistance": 30.0},
         "electrode_resistance": {"r1_sheet": 100.0}, "modulus_temperature": {"slope": -0.005}}
    b = dict(reversed(list(a.items())))
    for q in ("M", "Z", "I"):
        np.testing.assert_allclose(act(a)[q], act(b)[q], rtol=1e-13)
    c = {k: v for k, v in a.items() if k not in ("electrode_resistance", "modulus_temperature")}
    prod = act({})["M"]
    for k, v in c.items():
        prod = prod * (act({k: v})["M"] / act({})["M"])
    np.testing.assert_allclose(act(c)["M"], prod, rtol=1e-9)   # response-level effects compose as products


def test_leakage_resistance_follows_its_temperature_coefficient():
    g0, tcr, t = 40.0, 3.9e-3, 60.0
    dT = t + 273.15 - P.T_ref
    got = EffectModel(P, "actuator", {"leakage": {"conductance": g0, "tcr": tcr}}).frequency_response(F, [t])
    same = EffectModel(P, "actuator", {"leakage": {"conductance": g0 / (1 + tcr * dT)}}).frequency_response(F, [t])
    for q in ("M", "Z"):
        np.testing.assert_allclose(got[q], same[q], rtol=1e-12)
    with pytest.raises(ParameterError, match="tcr"):
        from physmodel.temperature import ISOTHERMAL

        EffectModel(P.replace(laws=ISOTHERMAL), "actuator",
                    {"leakage": {"conductance": g0, "tcr": -0.01}}).frequency_response(F, [150.0])


def test_series_elements_add_as_one_impedance():
    """Series resistance and interface CPE: Z = Z0 + Rs + S'/(W L) (jω)^−n; every driven quantity
    is divided by (Z0 + Rs + Z_cpe)/Z0 (a direct evaluation of the circuit)."""
    Rs, Sa, n = 40.0, 0.05, 0.8
    got = act({"series_resistance": {"resistance": Rs}, "series_cpe": {"S_area": Sa, "n": n}})
    base = act({})
    w = 2 * np.pi * F
    zc = Sa / (P.W * P.L) / (w**n * np.exp(1j * n * np.pi / 2))        # polar form of (jω)^−n
    Z = base["Z"] + Rs + zc
    np.testing.assert_allclose(got["Z"], Z, rtol=1e-12)
    np.testing.assert_allclose(got["I"], 1 / Z, rtol=1e-12)
    for q in ("M", "H"):
        np.testing.assert_allclose(got[q], base[q] * base["Z"] / Z, rtol=1e-11)
    sb = sen({})
    sg = sen({"series_cpe": {"S_area": Sa, "n": n}})
    zs = Sa / (PS.W * PS.L) / (w**n * np.exp(1j * n * np.pi / 2))
    np.testing.assert_allclose(sg["S"], sb["S"] * sb["Z"] / (sb["Z"] + zs), rtol=1e-11)


def test_candidate_bounds_scale_with_the_strip():
    """Contact resistance up to 5× and leakage up to 3× the polymer's own through-thickness ionic
    area resistance/conductance 2h/(κe K), K = F² d C⁻/(κe R T) (computed here from CODATA)."""
    from scipy import constants

    K = constants.physical_constants["Faraday constant"][0] ** 2 * P.d * P.C_minus / (P.kappa_e * constants.R * P.T_ref)
    ra = 2 * P.h / (P.kappa_e * K)
    assert ra == pytest.approx(2.3e-3, rel=0.05)                 # the 1.2e-2 / 5 for seed 002
    (r2,) = LIBRARY["contact_resistance"].candidate_parameters(P)
    g = LIBRARY["leakage"].candidate_parameters(P)[0]
    assert r2.upper == pytest.approx(5 * ra, rel=1e-12) and g.upper == pytest.approx(3 / ra, rel=1e-12)
    thin = P.replace(h=P.h / 2)
    assert LIBRARY["contact_resistance"].candidate_parameters(thin)[0].upper == pytest.approx(r2.upper / 2, rel=1e-12)
    over = LIBRARY["contact_resistance"].candidate_parameters(P, {"r2_specific": {"upper": 0.05}})
    assert over[0].upper == 0.05
    with pytest.raises(ParameterError, match="absolute bounds"):
        LIBRARY["contact_resistance"].candidate_parameters(P, {"r2_specific": {"upper": 5.0}})
    with pytest.raises(ParameterError, match="off value"):
        LIBRARY["contact_resistance"].candidate_parameters(P, {"r2_specific": {"lower": 1e-4}})
    with pytest.raises(ParameterError, match="unknown bound"):
        LIBRARY["contact_resistance"].candidate_parameters(P, {"r2_specific": {"max": 1.0}})


def test_simulates_sweeps_and_predicts_them():
    m = EffectModel(PS, "sensor", {"time_delay": {"delay": 1e-3}})
    sw = synthesize_sweep(m, "S", [10, 20, 50], [25, 45])
    assert sw.output_unit == "uA" and sw.metadata["model"].startswith("EffectSensorModel")
    pred = m.predictor(sw)
    np.testing.assert_allclose(pred({}), sw.response, rtol=1e-13)
    vals = [{"time_delay.delay": 2e-3}, {"a0": 0.5, "time_delay.delay": 1e-3}, {}]
    many = pred.many(vals)
    for k, v in enumerate(vals):
        np.testing.assert_allclose(many[k], pred(v), rtol=1e-13)
    noisy = synthesize_sweep(EffectModel(P, "actuator", {"leakage": {"conductance": 10.0}}), "M", [1, 2], [25],
                             MagnitudePhaseNoise(0.1, 1.0), seed=1)
    assert noisy.magnitude_std_db is not None


def test_bad_input_is_named():
    with pytest.raises(ParameterError, match="unknown effect"):
        EffectModel(P, "actuator", {"warp_drive": {}})
    with pytest.raises(ParameterError, match="time_delay.delay"):
        EffectModel(P, "actuator", {"time_delay": {"delay": -1.0}})
    with pytest.raises(ParameterError, match="no parameter"):
        EffectModel(P, "actuator", {"time_delay": {"tau": 1e-3}})
    with pytest.raises(IPMCError, match="does not apply"):
        EffectModel(P, "actuator", {"coupling_compliance": {"compliance_ratio": 0.1}})
    with pytest.raises(IPMCError, match="kind"):
        EffectModel(P, "beam", {})
