"""Parameter records, named sets and temperature laws (values pinned to their sources)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import constants

from physmodel import (
    ISOTHERMAL,
    ActuatorModel,
    Arrhenius,
    Constant,
    IPMCParameters,
    Linear,
    LogLinear,
    TemperatureLaws,
    WaterPermittivity,
    available_parameter_sets,
    get_parameter_set,
    state_at,
)
from physmodel.errors import ParameterError, TemperatureRangeError
from physmodel.temperature import water_permittivity


def test_every_named_set_loads_and_has_a_source():
    names = available_parameter_sets()
    assert {"seed002_table2", "seed002_table3", "dev", "seed000_sensor_dev", "seed001_actuator_dev"} <= set(names)
    for n in names:
        p = get_parameter_set(n)
        assert p.name == n and len(p.source) > 10
        assert IPMCParameters.from_dict(p.to_dict()) == p


def test_seed002_sets_reproduce_printed_values():
    t2, t3 = get_parameter_set("seed002_table2"), get_parameter_set("seed002_table3")
    assert (t3.L, t3.W, 2 * t3.h, t3.T_ref) == (15e-3, 4e-3, 0.25e-3, 300.0)
    assert t3.omega_n == pytest.approx(75.4, rel=1e-12)
    assert (t3.E, t3.xi, t3.Rp_specific) == (154e6, 0.18, 0.37)
    assert (t2.d, t2.C_minus, t2.kappa_e, t2.r2_specific, t2.r1_sheet) == (3.48e-11, 1068.0, 5.07e-7, 9.99e-6, 64.0)
    assert (t3.d, t3.C_minus, t3.kappa_e, t3.r2_specific, t3.r1_sheet) == (3.07e-11, 941.94, 4.47e-7, 8.81e-6, 56.44)
    # alpha0 convention: printed value divided by omega_n (seed's mode has omega_n, not omega_n^2, on top)
    assert t2.alpha0 * 75.4 == pytest.approx(-40.0) and t3.alpha0 * 75.4 == pytest.approx(-155.0)


def test_seed002_dc_gain_is_a_few_mm_per_volt():
    """With the printed alpha0 and the seed's omega_n-numerator mode: M(0) = alpha0-form gain / omega_n.

    Independent hand computation: M(0) = -3 L^2 alpha0 kappa (gamma0 - 1) X(x0) / (2 E h^3) / omega_n with
    X(x0) for x0^2 = 2 r1' L^2 / Rp'.
    """
    p = get_parameter_set("seed002_table3")
    F, R = constants.physical_constants["Faraday constant"][0], constants.R
    K = F**2 * 3.07e-11 * 941.94 / (4.47e-7 * R * 300.0)
    g0 = 0.125e-3 * np.sqrt(K / 3.07e-11)
    x2 = 2 * 56.44 * 0.015**2 / 0.37
    x = np.sqrt(x2)
    X = (x * np.tanh(x) + 1 / np.cosh(x) - 1) / x2
    M0 = -3 * 0.015**2 * (-155.0) * 4.47e-7 * (g0 - np.tanh(g0)) * 2 * X / (4 * 154e6 * 0.125e-3**3) / 75.4
    got = ActuatorModel(p).dc_gain([300.0 - 273.15])["M0"][0, 0]
    assert got == pytest.approx(M0, rel=1e-12)
    assert 3e-3 < got < 8e-3   # 5.6 mm/V


def test_overrides_and_errors_name_the_field():
    p = get_parameter_set("seed002_table3", W=2e-3, omega_n=100.0)
    assert p.W == 2e-3 and p.omega_n == pytest.approx(100.0)
    with pytest.raises(ParameterError, match="unknown parameter"):
        get_parameter_set("seed002_table3", width=1.0)
    with pytest.raises(ParameterError, match="unknown parameter set 'nope'"):
        get_parameter_set("nope")
    with pytest.raises(ParameterError, match=r"d=-1.0 \[m\^2/s\]"):
        get_parameter_set("dev", d=-1.0)
    with pytest.raises(ParameterError, match="h is NaN"):
        get_parameter_set("dev", h=float("nan"))
    with pytest.raises(ParameterError, match="E=inf"):
        get_parameter_set("dev", E=float("inf"))
    assert get_parameter_set("dev", Rp_specific=np.inf, r1_sheet=0.0).Rp_specific == np.inf


def test_laws_at_reference_temperature_are_identity_and_follow_physics_md():
    p = get_parameter_set("dev")
    st = state_at(p, [p.T_ref - 273.15, 80.0])
    for k, ref in (("d", p.d), ("E", p.E), ("kappa_e", p.kappa_e), ("Rp", p.Rp_specific / p.W)):
        assert getattr(st, k)[0, 0, 0] == pytest.approx(ref, rel=1e-14)
    T1, T0 = 80.0 + 273.15, p.T_ref
    assert st.d[0, 1, 0] / p.d == pytest.approx(np.exp(-15e3 / constants.R * (1 / T1 - 1 / T0)))
    assert st.E[0, 1, 0] / p.E == pytest.approx(np.exp(-0.0075 * (T1 - T0)))
    assert st.kappa_e[0, 1, 0] / p.kappa_e == pytest.approx(water_permittivity(80.0) / water_permittivity(T0 - 273.15))
    assert st.Rp[0, 1, 0] / st.Rp[0, 0, 0] == pytest.approx((T1 / T0) / (st.d[0, 1, 0] / p.d))
    # omega_n follows sqrt(E)
    assert st.omega_n[0, 1, 0] / st.omega_n[0, 0, 0] == pytest.approx(np.sqrt(st.E[0, 1, 0] / st.E[0, 0, 0]))
    # K = F^2 d C / (kappa R T) at every temperature
    F = constants.physical_constants["Faraday constant"][0]
    assert st.K[0, 1, 0] == pytest.approx(F**2 * st.d[0, 1, 0] * p.C_minus / (st.kappa_e[0, 1, 0] * constants.R * T1))


def test_published_modulus_points_are_what_the_default_law_encodes():
    # DuPont water-soaked Nafion: 114 MPa at 23 °C, 64 MPa at 100 °C -> -0.75 %/K log-linear
    assert 114 * LogLinear().factor(373.15, 296.15) == pytest.approx(64, rel=0.01)
    # Malmberg & Maryott (1956) table: 78.30 at 25 °C, 55.72 at 100 °C
    assert water_permittivity(25.0) == pytest.approx(78.30, abs=0.01)
    assert water_permittivity(100.0) == pytest.approx(55.72, abs=0.05)


def test_law_validity_ranges_are_enforced():
    p = get_parameter_set("dev")
    with pytest.raises(TemperatureRangeError, match=r"valid on \[0, 100\] °C"):
        state_at(p, [120.0])
    with pytest.raises(TemperatureRangeError, match="absolute zero"):
        state_at(p, [-300.0])
    iso = p.replace(laws=ISOTHERMAL)
    st = state_at(iso, [120.0])
    assert st.d[0, 0, 0] == p.d
    narrow = p.replace(laws=TemperatureLaws(d=Arrhenius(20e3, valid_c=(10.0, 50.0))))
    with pytest.raises(TemperatureRangeError, match="for d"):
        state_at(narrow, [60.0])
    with pytest.raises(ParameterError, match="alpha"):
        Linear(alpha=0.05)
    laws = TemperatureLaws().with_(E=Constant(), r1_sheet=Linear(3.9e-3))
    assert TemperatureLaws.from_dict(laws.to_dict()) == laws
    with pytest.raises(ParameterError, match="no temperature law"):
        TemperatureLaws().with_(xi=Constant())


def test_batch_state_shapes():
    sets = [get_parameter_set("dev"), get_parameter_set("seed002_table3")]
    st = state_at(sets, [10.0, 20.0, 30.0])
    assert st.K.shape == (2, 3, 1)
    assert WaterPermittivity().factor(273.15 + 50, 273.15 + 25) == pytest.approx(69.91 / 78.30, rel=2e-3)


@pytest.mark.parametrize("name", ["dev", "seed002_table3", "seed001_actuator_dev"])
def test_parameter_file_round_trip_and_lookup_by_path(tmp_path, name):
    from physmodel import get_parameter_set, load_parameter_set, save_parameter_set

    p = get_parameter_set(name).replace(Rp_specific=float("inf"))
    path = save_parameter_set(p, tmp_path / "set.json")
    assert load_parameter_set(path) == p
    assert get_parameter_set(str(path), W=2e-3) == p.replace(W=2e-3)
    assert "Infinity" not in path.read_text()  # strict JSON


def test_parameter_file_errors_name_the_file(tmp_path):
    from physmodel import ParameterError, get_parameter_set

    with pytest.raises(ParameterError, match="does not exist"):
        get_parameter_set(str(tmp_path / "missing.json"))
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ParameterError, match="not valid JSON"):
        get_parameter_set(str(bad))
    other = tmp_path / "other.json"
    other.write_text('{"format": "something-else", "parameters": {}}')
    with pytest.raises(ParameterError, match="format"):
        get_parameter_set(str(other))


def _mixed_batch():
    """Sets that differ in values, in T_ref and in their temperature laws (shared and distinct
    law objects, equal laws built separately), in an interleaved order."""
    base = get_parameter_set("seed001_actuator")
    other = get_parameter_set("seed002_table3")
    iso = base.replace(laws=ISOTHERMAL, name="iso")
    rng = np.random.default_rng(3)
    out = []
    for i in range(60):
        src = (base, other, iso)[i % 3]
        changes = {"d": src.d * rng.lognormal(0, 0.3), "E": src.E * rng.lognormal(0, 0.1),
                   "W": src.W * rng.uniform(0.8, 1.2), "xi": src.xi * rng.uniform(0.5, 2.0)}
        if i % 7 == 0:
            changes["T_ref"] = src.T_ref + 5.0
        if i % 11 == 0:
            changes["laws"] = TemperatureLaws.from_dict(src.laws.to_dict())   # equal, not the same object
        out.append(src.replace(**changes))
    return out


def test_many_set_evaluation_equals_per_set_evaluation():
    """A batch is a vectorised loop over its sets: every state field and every quantity of
    ActuatorModel / SensorModel(batch) equals what each set gives alone (to rounding)."""
    from physmodel import SensorModel

    sets = _mixed_batch()
    temps = [20.0, 35.0, 50.0]
    f = np.logspace(-1, 1.5, 10)
    st = state_at(sets, temps)
    for i, p in enumerate(sets):
        one = state_at(p, temps)
        for k in ("L", "W", "h", "d", "C_minus", "kappa_e", "alpha0", "a0", "r1", "r2", "Rp", "E", "rho",
                  "xi", "T", "K", "omega_n"):
            np.testing.assert_allclose(getattr(st, k)[i], getattr(one, k)[0], rtol=1e-14, atol=0, err_msg=k)
    for cls in (ActuatorModel, SensorModel):
        many = cls(sets).frequency_response(f, temps)
        assert many.parameter_sets == tuple(p.name for p in sets)
        for i, p in enumerate(sets):
            alone = cls(p).frequency_response(f, temps)
            for q, v in alone.values.items():
                np.testing.assert_allclose(many[q][i], v[0], rtol=1e-13, atol=0, err_msg=f"{cls.__name__} {q} set {i}")


def test_batch_checks_every_sets_law_ranges():
    """A temperature outside one set's law validity range is an error for the batch too."""
    base = get_parameter_set("seed001_actuator")
    narrow = base.replace(laws=base.laws.with_(E=Linear(alpha=-1e-3, valid_c=(0.0, 40.0))))
    with pytest.raises(TemperatureRangeError):
        state_at([base, base.replace(d=2 * base.d), narrow], [60.0])
    with pytest.raises(TemperatureRangeError):
        ActuatorModel([base, narrow]).frequency_response([1.0], [60.0])


def test_law_factors_are_kept_per_laws_temperatures_and_reference():
    """TemperatureLaws.factors keeps its result for (laws, T, T_ref): the same numbers as each law's
    own factor(), shared read-only; another T, T_ref or law is evaluated afresh."""
    laws = TemperatureLaws().with_(r1_sheet=Linear(2e-3))
    T = np.array([290.0, 310.0, 330.0])
    first = laws.factors(T, 298.15)
    again = laws.factors(T.copy(), 298.15)
    for k in first:
        assert again[k] is first[k]
        assert not first[k].flags.writeable
    with pytest.raises(ValueError):
        first["d"][0] = 1.0
    np.testing.assert_array_equal(first["d"], Arrhenius().factor(T, 298.15))
    np.testing.assert_array_equal(first["r1_sheet"], Linear(2e-3).factor(T, 298.15))
    np.testing.assert_array_equal(first["Rp_specific"], (T / 298.15) / Arrhenius().factor(T, 298.15))
    other_ref = laws.factors(T, 310.0)
    np.testing.assert_array_equal(other_ref["d"], Arrhenius().factor(T, 310.0))
    assert other_ref["d"][1] == 1.0
    other_T = laws.factors(T[:2], 298.15)
    np.testing.assert_array_equal(other_T["d"], first["d"][:2])
    hot = laws.with_(d=Arrhenius(40e3)).factors(T, 298.15)
    np.testing.assert_array_equal(hot["d"], Arrhenius(40e3).factor(T, 298.15))
    narrow = laws.with_(d=Arrhenius(valid_c=(0.0, 40.0)))
    for _ in range(2):                       # a refused temperature is refused every time
        with pytest.raises(TemperatureRangeError, match="for d"):
            narrow.factors(T, 298.15)
