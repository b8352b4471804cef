"""What the model path keeps between calls gives the numbers a fresh evaluation gives, bit for bit
(issue 27 item 6: the per-call overhead of the diagnosis's model calls).

* a parameter table keeps its groups' law factors per temperature array, shared by the tables
  made from it (``ParameterTable.with_columns``): a table evaluated after others, at temperatures
  seen before or not, gives the state a table built afresh gives;
* a predictor keeps its checked grid, the base columns per number of sets and its models: calls
  in any order give what a fresh predictor's first call gives;
* after parameter-level effects, K and ωn are recomputed only when an effect replaced one of their
  inputs: they are always the expressions of the state's final fields;
* the values' checks made from extremes refuse what the elementwise checks refused, with the
  same messages.
"""

from __future__ import annotations

import numpy as np
import pytest

from physmodel import get_parameter_set
from physmodel.data.sweep import synthesize_sweep
from physmodel.effects import LIBRARY, EffectModel
from physmodel.errors import ParameterError
from physmodel.params import STATE_FIELDS, ParameterTable, first_mode_omega
from physmodel.temperature import LogLinear
from physmodel.transport import debye_rate

P = get_parameter_set("seed002_table3").replace(r1_sheet=300.0)
FREQS = np.geomspace(0.05, 300.0, 11)
TEMPS = [18.0, 37.0, 55.0]


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _same_state(a, b) -> bool:
    return all(_same(getattr(a, k), getattr(b, k)) for k in STATE_FIELDS)


def _columns(table, rng):
    """Other values in every column of ``table`` (T_ref kept: it belongs to the groups)."""
    return {k: v * rng.uniform(0.7, 1.3, v.shape) if k != "T_ref" else v.copy() for k, v in table.columns.items()}


@pytest.mark.parametrize("groups", ["one", "two"])
def test_table_states_from_kept_law_factors_are_fresh_states(groups):
    sets = [P, P.replace(alpha0=P.alpha0 * 1.1)]
    if groups == "two":         # another laws object: two groups
        sets.append(P.replace(laws=P.laws.with_(E=LogLinear(slope=-0.01)), d=P.d * 0.9))
    base = ParameterTable.of(sets)
    rng = np.random.default_rng(6)
    tables = [base.with_columns(_columns(base, rng), base.n) for _ in range(3)]
    grids = [TEMPS, [25.0], TEMPS, [20.0, 30.0, 40.0], [19.0, 28.0, 37.0, 46.0, 55.0], [25.0], TEMPS, [20.0, 30.0, 40.0]]
    for k, T in enumerate(grids):                   # the same grids again: kept factors
        t = tables[k % len(tables)]
        fresh = ParameterTable(dict(t.columns), t.groups, t.n)          # nothing kept
        assert _same_state(t.state(T), fresh.state(T))
    assert len(base.seen) == 4 and all(t.seen is base.seen for t in tables)


def test_a_kept_temperature_array_is_not_written_through():
    table = ParameterTable.of(P)
    st = table.state(TEMPS)
    st.T[...] = 0.0                                 # the state's arrays are its own
    assert _same_state(table.state(TEMPS), ParameterTable.of(P).state(TEMPS))


def test_predictor_calls_in_any_order_give_a_fresh_predictors_numbers():
    sweep = synthesize_sweep(EffectModel(P, "actuator", {}), "M", FREQS, TEMPS)
    model = EffectModel(P, "actuator", {"time_delay": {"delay": 1e-3}})
    rng = np.random.default_rng(27)

    def sets(n):
        return [{"d": P.d * rng.uniform(0.6, 1.6), "xi": float(rng.uniform(0.05, 0.4)),
                 "omega_n": P.omega_n * rng.uniform(0.5, 2.0), "contact_resistance.r2_specific": float(rng.uniform(0, 1e-4)),
                 "diffusivity_temperature.activation_energy": float(rng.uniform(-2e4, 2e4)),
                 "diffusivity_temperature.curvature": 0.0} for _ in range(n)]

    batches = [sets(n) for n in (6, 1, 6, 9, 6)]
    warm = model.predictor(sweep, "M").many
    got = [warm(b) for b in batches + batches[::-1]]
    for b, g in zip(batches + batches[::-1], got, strict=True):
        assert _same(g, model.predictor(sweep, "M").many(b))


@pytest.mark.parametrize("name", sorted(n for n, e in LIBRARY.items() if e.level == "parameter" and "actuator" in e.kinds))
def test_mode_and_debye_rate_follow_the_fields_after_parameter_effects(name):
    e = LIBRARY[name]
    vals = {p.name: (p.typical if p.typical != p.off else 0.5 * (p.lower + p.upper)) for p in e.candidate_parameters(P)}
    st = EffectModel([P, P.replace(d=P.d * 1.3)], "actuator", {name: vals}).state(TEMPS)
    assert _same(st.K, debye_rate(st.d, st.C_minus, st.kappa_e, st.T))
    assert _same(st.omega_n, first_mode_omega(st.E, st.rho, st.L, st.h))
    base = EffectModel([P, P.replace(d=P.d * 1.3)], "actuator", {}).state(TEMPS)
    assert not all(_same(getattr(st, k), getattr(base, k)) for k in STATE_FIELDS)    # the effect acted


@pytest.mark.parametrize("change, words", [
    ({"contact_resistance.r2_specific": float("nan")}, "contact_resistance.r2_specific=nan"),
    ({"contact_resistance.r2_specific": float("inf")}, "contact_resistance.r2_specific=inf"),
    ({"contact_resistance.r2_specific": -1e-6}, "contact_resistance.r2_specific=-1e-06"),
    ({"d": float("nan")}, "d is NaN"),
    ({"d": -1e-10}, "d=-1e-10"),
    ({"d": float("inf")}, "d=inf"),
    ({"omega_n": float("nan")}, "omega_n=nan"),
    ({"omega_n": -3.0}, "omega_n=-3.0"),
    ({"omega_n": float("inf")}, "omega_n=inf"),
])
def test_bad_values_are_refused_in_a_batch_as_alone(change, words):
    sweep = synthesize_sweep(EffectModel(P, "actuator", {}), "M", FREQS, TEMPS)
    many = EffectModel(P, "actuator", {}).predictor(sweep, "M").many
    good = {"d": P.d, "omega_n": P.omega_n, "contact_resistance.r2_specific": 1e-5}
    many([good, dict(good)])
    for k in range(3):                              # the bad value in each place of the batch
        batch = [dict(good) for _ in range(3)]
        batch[k].update(change)
        with pytest.raises(ParameterError, match=words.replace("+", r"\+").replace(".", r"\.")):
            many(batch)


@pytest.mark.parametrize("name, first, second, words", [
    ("contact_resistance.r2_specific", -1e-6, -5.0, "contact_resistance.r2_specific=-1e-06"),
    ("d", -1e-10, -3e-9, "d=-1e-10"),
    ("omega_n", -3.0, -700.0, "omega_n=-3.0"),
])
def test_of_two_bad_values_the_first_is_named_not_the_extreme(name, first, second, words):
    sweep = synthesize_sweep(EffectModel(P, "actuator", {}), "M", FREQS, TEMPS)
    many = EffectModel(P, "actuator", {}).predictor(sweep, "M").many
    good = {"d": P.d, "omega_n": P.omega_n, "contact_resistance.r2_specific": 1e-5}
    batch = [dict(good), dict(good, **{name: first}), dict(good, **{name: second})]
    with pytest.raises(ParameterError, match=words.replace(".", r"\.")):
        many(batch)


def test_a_new_params_list_is_seen_by_the_kept_names_and_reference_temperatures():
    """Assigning another list (the documented way) changes the names and T_ref the model keeps."""
    m = EffectModel([P, P], "actuator", {"electrode_resistance": {"r1_sheet": 50.0}})
    m.frequency_response(FREQS, TEMPS, quantities=("M",))
    other = P.replace(name="other", T_ref=P.T_ref + 10.0)
    m.params = [other, P]
    got = m.frequency_response(FREQS, TEMPS, quantities=("M",))
    fresh = EffectModel([other, P], "actuator", {"electrode_resistance": {"r1_sheet": 50.0}}).frequency_response(
        FREQS, TEMPS, quantities=("M",))
    assert got.parameter_sets == fresh.parameter_sets == ("other", P.name)
    assert _same(got["M"], fresh["M"])


def test_replace_of_a_table_does_not_carry_its_kept_law_factors():
    from dataclasses import replace

    a = ParameterTable.of(P)
    a.state(TEMPS)                                  # keeps P's law factors at TEMPS
    q = P.replace(laws=P.laws.with_(E=LogLinear(slope=-0.02)))
    b = replace(a, groups=ParameterTable.of(q).groups)
    assert _same_state(b.state(TEMPS), ParameterTable(a.columns, ParameterTable.of(q).groups, a.n).state(TEMPS))
