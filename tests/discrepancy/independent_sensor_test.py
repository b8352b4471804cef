"""The independent sensor generator (independent_sensor.py) against physmodel where both model the
same thing, and its own invariants.  Agreement is required: otherwise blind cases would test the
generator, not the workflow.  (Collected by pytest's default ``*_test.py`` pattern.)"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

try:
    from . import independent_sensor as isn
except ImportError:
    import independent_sensor as isn

from physmodel import SensorModel, get_parameter_set
from physmodel.effects import EffectModel

F = isn.FREQUENCIES_HZ
TAU = lambda f: 1.0 / (2 * math.pi * f)  # noqa: E731
LIBRARY_FORM = {
    "amplifier": lambda v: ("amplifier_bandwidth", {"time_constant": TAU(v["f_a"]),
                                                    "second_time_constant": TAU(v["f_a"] * v["ratio"])}),
    "delay": lambda v: ("time_delay", {"delay": v["tau"]}),
    "laser": lambda v: ("laser_lag", {"time_constant": TAU(v["f_l"])}),
    "ac_coupling": lambda v: ("ac_coupling", {"corner_hz": v["f_c"]}),
    "joint": lambda v: ("fixture_joint", {"time_constant": TAU(v["f_j"]), "damping": v["zeta"]}),
    "slit_beam": lambda v: ("tip_driven_beam", {"time_constant": TAU(v["f_cp"]), "damping": v["zeta"]}),
    "opamp": lambda v: ("transimpedance", {"unity_gain_time": TAU(v["gbw"]), "inverse_dc_gain": 1 / isn.A0}),
}


@pytest.fixture(scope="module")
def start():
    return get_parameter_set("seed000_sensor_dev", T_ref=isn.START["T"])


def test_strip_agrees_with_the_library_sensor(start):
    G, Z = isn.strip_sensor(isn.START, 2j * np.pi * F)
    r = SensorModel(start).frequency_response(F, [isn.TEMPERATURE_C], quantities=("S", "Z"))
    assert np.max(np.abs(G / r["S"][0, 0] - 1)) < 1e-9
    assert np.max(np.abs(Z / r["Z"][0, 0] - 1)) < 1e-9


@pytest.mark.parametrize("name", isn.IN_LIBRARY)
def test_each_chain_element_agrees_with_its_library_effect(name, start):
    v = isn.draw_effect(name, np.random.default_rng(3), 0.8)
    lib, lv = LIBRARY_FORM[name](v)
    assert isn.EFFECT_SPECS[name][0] == lib
    a = isn.response(isn.START, {name: v}, F)
    b = EffectModel(start, "sensor", {lib: lv}).frequency_response(F, [isn.TEMPERATURE_C])["S"][0, 0]
    assert np.max(np.abs(a / b - 1)) < 1e-9
    assert np.max(np.abs(a / isn.response(isn.START, {}, F) - 1)) > 1e-3       # the element shows


def test_clamped_pinned_root_and_beam_limits():
    assert isn.LAMBDA_CP == pytest.approx(brentq(lambda x: math.tan(x) - math.tanh(x), 3.5, 4.5, xtol=1e-15), abs=1e-14)
    s = 2j * np.pi * np.array([1e-3, 1.0])
    dev = isn.slit_beam(s, 1e4, 0.1) - 1.0        # far below resonance: static, plus the damping's lead ∝ s
    assert abs(dev[0]) < 1e-7 and dev[0] / dev[1] == pytest.approx(1e-3, rel=1e-3)
    # resonance at the first clamped-pinned mode: the tip slope per tip displacement peaks there
    f = np.linspace(30.0, 70.0, 401)
    peak = f[np.argmax(np.abs(isn.slit_beam(2j * np.pi * f, 50.0, 0.01)))]
    assert peak == pytest.approx(50.0, abs=0.2)


def test_cases_are_reproducible_and_labelled():
    a, ta = isn.make_case(4, "laser")
    b, tb = isn.make_case(4, "laser")
    assert np.array_equal(a.response, b.response) and ta["expected"] == ["laser_lag"]
    _, tn = isn.make_case(5, "notch")
    assert tn["expected"] == [] and tn["out_of_library"]
    _, t0 = isn.make_case(6, "none")
    assert t0["lam_baseline"] == 0.0 and t0["expected"] == []
    with pytest.raises(ValueError):
        isn.make_case(1, "nope")


# ------------------------------------------------------------------ the bath temperature (issue 27 item 3)
@pytest.mark.parametrize("t", [5.0, 20.0, 50.0, 65.0])
def test_strip_away_from_its_temperature_agrees_with_the_library_laws(t, start):
    """The generator's own code for the laws against the library's defaults at other bath temperatures: the same
    Arrhenius, log-linear and Nernst–Einstein laws, but water's permittivity from another published
    fit (Owen et al. 1961 here, Malmberg & Maryott 1956 there, ≤ 0.2 % apart over 5–65 °C)."""
    f = np.geomspace(1.0, 1000.0, 25)
    G, Z = isn.strip_sensor(isn.START, 2j * np.pi * f, t)
    r = SensorModel(start).frequency_response(f, [t], quantities=("S", "Z"))
    assert np.max(np.abs(G / r["S"][0, 0] - 1)) < 2e-3
    assert np.max(np.abs(Z / r["Z"][0, 0] - 1)) < 2e-3
    Z35 = isn.strip_sensor(isn.START, 2j * np.pi * f)[1]
    assert np.max(np.abs(Z / Z35 - 1)) > 0.05              # the bath moves the strip's impedance


def test_the_default_temperature_is_the_strip_as_it_was():
    """At the strip's own temperature every law's factor is exactly 1: the records of the sealed sets
    (made without a temperature) and the same lines asked for at 35 °C are bit-identical."""
    _, tr = isn.make_case(11, "opamp")
    f = np.geomspace(1.0, 1000.0, 17)
    assert np.array_equal(isn.response(tr["base"], tr["effects"], f),
                          isn.response(tr["base"], tr["effects"], f, temperature_c=isn.TEMPERATURE_C))
    assert isn.at_temperature(tr["base"], isn.TEMPERATURE_C) == tr["base"]
    with pytest.raises(ValueError, match="0-100"):
        isn.at_temperature(tr["base"], 308.15)               # kelvin typed for °C


@pytest.mark.parametrize("t", [5.0, 65.0])
def test_only_the_opamp_stage_follows_the_bath(t, start):
    """The op-amp stages see the strip's impedance, which the bath changes; an amplifier pole does
    not.  Each element's response at t against the library's effect at t; then the LIBRARY's
    element factor (its effect's S over its plain strip's S) at t against at 35 °C: the amplifier's
    must not move with the bath (it would if the library tied the pole to the strip's state), the
    op-amp stage's must, by as much as the generator's node equations say (its own code)."""
    f = np.geomspace(10.0, 1000.0, 21)
    lib_fac, gen_fac = {}, {}
    for name in ("amplifier", "opamp"):
        v = isn.draw_effect(name, np.random.default_rng(3), 0.8)
        lib, lv = LIBRARY_FORM[name](v)
        a = isn.response(isn.START, {name: v}, f, t)
        b = EffectModel(start, "sensor", {lib: lv}).frequency_response(f, [t])["S"][0, 0]
        assert np.max(np.abs(a / b - 1)) < 2e-3
        lib_fac[name], gen_fac[name] = [], []
        for tt in (t, isn.TEMPERATURE_C):
            with_el = EffectModel(start, "sensor", {lib: lv}).frequency_response(f, [tt])["S"][0, 0]
            lib_fac[name].append(with_el / SensorModel(start).frequency_response(f, [tt], quantities=("S",))["S"][0, 0])
            gen_fac[name].append(isn.response(isn.START, {name: v}, f, tt) / isn.response(isn.START, {}, f, tt))
    assert np.max(np.abs(lib_fac["amplifier"][0] / lib_fac["amplifier"][1] - 1)) < 1e-9
    moved_lib = lib_fac["opamp"][0] / lib_fac["opamp"][1]
    moved_gen = gen_fac["opamp"][0] / gen_fac["opamp"][1]
    assert np.max(np.abs(moved_lib - 1)) > 0.02
    assert np.max(np.abs(moved_lib / moved_gen - 1)) < 2e-3


def test_other_law_constants_move_the_strip_as_the_library_with_those_constants(start):
    """The ``laws`` option (bench_next_measurement ``--law-error``): left out, or given the module's
    constants, every record is bit-identical to before; given other constants the generator agrees
    with the LIBRARY configured with the same constants (its own Arrhenius and log-linear laws) and
    no longer with the library's defaults; at the strip's own temperature nothing moves."""
    from dataclasses import replace

    from physmodel.temperature import Arrhenius, LogLinear

    _, tr = isn.make_case(11, "opamp")
    f = np.geomspace(1.0, 1000.0, 17)
    moved = {"ea_d": 20e3, "e_logslope": -0.005}
    assert np.array_equal(isn.response(tr["base"], tr["effects"], f, 5.0),
                          isn.response(tr["base"], tr["effects"], f, 5.0,
                                       laws={"ea_d": isn.EA_D, "e_logslope": isn.E_LOGSLOPE}))
    assert np.array_equal(isn.response(tr["base"], tr["effects"], f, isn.TEMPERATURE_C, laws=moved),
                          isn.response(tr["base"], tr["effects"], f))
    lib = replace(start, laws=replace(start.laws, d=replace(start.laws.d, activation_energy=20e3),
                                      E=replace(start.laws.E, slope=-0.005)))
    assert isinstance(lib.laws.d, Arrhenius) and isinstance(lib.laws.E, LogLinear)
    for t in (5.0, 65.0):
        G, Z = isn.strip_sensor(isn.START, 2j * np.pi * f, t, laws=moved)
        r = SensorModel(lib).frequency_response(f, [t], quantities=("S", "Z"))
        assert np.max(np.abs(G / r["S"][0, 0] - 1)) < 2e-3
        assert np.max(np.abs(Z / r["Z"][0, 0] - 1)) < 2e-3
        r0 = SensorModel(start).frequency_response(f, [t], quantities=("S", "Z"))
        assert np.max(np.abs(Z / r0["Z"][0, 0] - 1)) > 0.02          # a strip the default laws misdescribe
    with pytest.raises(ValueError, match="unknown key"):
        isn.response(tr["base"], {}, f, 5.0, laws={"Ea": 20e3})
