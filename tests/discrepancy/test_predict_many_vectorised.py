"""``EffectModel.predictor(...).many`` evaluates every parameter set in one model call, effect values
as arrays over the sets (physmodel/effects/library.py).  The oracle is the grouped form
``predict.many_grouped`` — one model call per distinct set of effect values, each effect switched on
only where it is on, scalar values — which the effect tests check against independent physics.

For every library effect (and out-of-library effect) alone and every pair of library effects, for
actuators (M and Z) and sensors (S): random in-range base parameters and effect values over several
sets, some sets at the effect's off value, some with its switch off and the other parameters
anywhere, some without it; the two forms agree to rtol 1e-10 (1e-12 here; the margin is for other BLAS builds).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from physmodel import get_parameter_set
from physmodel.data.sweep import synthesize_sweep
from physmodel.effects import LIBRARY, OUT_OF_LIBRARY, EffectModel, get_effect
from physmodel.effects.library import EffectActuatorModel, EffectSensorModel
from physmodel.errors import IPMCError, ParameterError

P_ACT = get_parameter_set("seed002_table3").replace(r1_sheet=300.0)
P_SEN = get_parameter_set("seed000_sensor_dev")
FREQS = np.geomspace(0.05, 300.0, 13)
TEMPS = [18.0, 37.0, 55.0]
CASES = [("actuator", "M", P_ACT, "alpha0"), ("actuator", "Z", P_ACT, "alpha0"), ("sensor", "S", P_SEN, "a0")]


#: Effects already on in the model the predictor comes from (sets that do not name them keep these values).
BASELINE = {"time_delay": {"delay": 2e-3}, "leakage": {"conductance": 20.0, "tcr": 2e-3}}


def _predictor(kind, q, p, baseline=None):
    sweep = synthesize_sweep(EffectModel(p, kind, {}), q, FREQS, TEMPS)
    return EffectModel(p, kind, baseline or {}).predictor(sweep, q)


def _effects_for(kind, q, library=LIBRARY):
    return [n for n, e in library.items() if kind in e.kinds and q in e.quantities]


def _draw_effect(rng, name, p, mode):
    """Values of effect ``name``: ``mode`` "on" (random in its candidate bounds), "off" (all at off),
    "switch_off" (the switch at off, the others random), "absent" (not given)."""
    e = get_effect(name)
    if mode == "absent":
        return {}
    pars = e.candidate_parameters(p)
    v = {q.name: float(rng.uniform(q.lower, q.upper)) for q in pars}
    if mode == "off":
        v = {q.name: q.off for q in pars}
    elif mode == "switch_off":
        v[e.switch or pars[0].name] = e.parameter(e.switch or pars[0].name).off
        if e.switch is None:
            v = {q.name: q.off for q in pars}
    return {f"{name}.{k}": x for k, x in v.items()}


def _draw_sets(rng, names, p, gain):
    modes = ("on", "on", "off", "switch_off", "absent", "on", "on")
    sets = []
    for k, mode in enumerate(modes):
        v = {"d": p.d * rng.uniform(0.6, 1.6), "kappa_e": p.kappa_e * rng.uniform(0.7, 1.4),
             "xi": float(rng.uniform(0.05, 0.4)), "omega_n": p.omega_n * rng.uniform(0.4, 3.0),
             gain: getattr(p, gain) * rng.uniform(0.8, 1.2)}
        for j, n in enumerate(names):
            # the second effect of a pair takes its modes in another order
            v.update(_draw_effect(rng, n, p, mode if j == 0 else modes[(k + 3) % len(modes)]))
        sets.append(v)
    return sets


def _check(pred, sets):
    grouped = pred.many_grouped(sets)
    batched = pred.many(sets)
    assert np.all(np.isfinite(grouped))
    np.testing.assert_allclose(batched, grouped, rtol=1e-10, atol=0)


@pytest.mark.parametrize("baseline", [None, BASELINE], ids=["plain", "with-baseline-effects"])
@pytest.mark.parametrize("kind, q, p, gain", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_every_effect_alone(kind, q, p, gain, baseline):
    pred = _predictor(kind, q, p, baseline)
    rng = np.random.default_rng(27)
    names = _effects_for(kind, q)
    assert len(names) >= 8
    for n in names + _effects_for(kind, q, OUT_OF_LIBRARY):     # the blind generators' effects too
        _check(pred, _draw_sets(rng, [n], p, gain))


@pytest.mark.parametrize("kind, q, p, gain", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_every_pair_of_effects(kind, q, p, gain):
    pred = _predictor(kind, q, p)
    rng = np.random.default_rng(2706)
    for a, b in itertools.combinations(_effects_for(kind, q), 2):
        _check(pred, _draw_sets(rng, [a, b], p, gain))


def _count_calls(monkeypatch):
    calls = []
    for cls in (EffectActuatorModel, EffectSensorModel):
        orig = cls.frequency_response

        def counted(self, *a, _orig=orig, **k):
            calls.append(len(self.params))
            return _orig(self, *a, **k)

        monkeypatch.setattr(cls, "frequency_response", counted)
    return calls


def test_batchable_effects_take_one_model_call(monkeypatch):
    pred = _predictor("actuator", "M", P_ACT)
    rng = np.random.default_rng(5)
    sets = _draw_sets(rng, ["contact_resistance", "time_delay"], P_ACT, "alpha0")
    calls = _count_calls(monkeypatch)
    pred.many(sets)
    assert calls == [len(sets)]
    calls.clear()
    pred.many_grouped(sets)
    assert len(calls) > 1


@pytest.mark.parametrize("kind, q, p, gain", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_a_kernel_effect_is_grouped_by_whether_it_is_on(monkeypatch, kind, q, p, gain):
    """fractional_transport changes the charge dynamics' ŝ: the sets where it is on go in one call,
    each on its own ŝ (issue 27 item 6: a Jacobian's finite-difference set of β joins the point's),
    those where it is off in another; each set's response is the same, bit for bit, as in a call
    of the sets sharing its β alone (one ŝ grid per call, as before), and agrees with the
    one-call-per-distinct-values reference."""
    assert not LIBRARY["fractional_transport"].batchable
    pred = _predictor(kind, q, p)
    g0 = getattr(p, gain)
    sets = [{"fractional_transport.beta": b, gain: g0 * f}
            for b, f in ((0.8, 1.0), (0.9, 1.1), (0.8, 0.9), (1.0, 1.0), (0.9, 1.0))]
    calls = _count_calls(monkeypatch)
    out = pred.many(sets)
    assert sorted(calls) == [1, 4]             # beta on (0.8, 0.9: four sets) and off (1.0)
    calls.clear()
    on = [s for s in sets if s["fractional_transport.beta"] < 1.0]
    pred.many(on)
    assert calls == [4]                        # on in every set: one call
    calls.clear()
    for beta in (0.8, 0.9, 1.0):
        rows = [i for i, s in enumerate(sets) if s["fractional_transport.beta"] == beta]
        alone = pred.many([sets[i] for i in rows])
        assert calls == [len(rows)]
        calls.clear()
        np.testing.assert_array_equal(out[rows], alone)
    np.testing.assert_allclose(out, pred.many_grouped(sets), rtol=1e-10, atol=0)
    with pytest.raises(ParameterError, match="beta"):
        pred.many([{"fractional_transport.beta": 0.8}, {"fractional_transport.beta": 0.2}])


def test_a_set_does_not_depend_on_its_batch_mates():
    """The modal effects' mode count is each set's own, not that of the softest strip in the call."""
    pred = _predictor("actuator", "M", P_ACT)
    stiff = {"omega_n": P_ACT.omega_n * 3.0, "second_mode.weight": 1.0, "higher_modes.weight": 0.8}
    soft = {"omega_n": P_ACT.omega_n * 0.2, "second_mode.weight": 0.5, "higher_modes.weight": 1.0}
    both = pred.many([soft, stiff])
    np.testing.assert_array_equal(both[1], pred.many([stiff])[0])
    np.testing.assert_array_equal(both[0], pred.many([soft])[0])


def test_bad_effect_values_are_named():
    pred = _predictor("actuator", "M", P_ACT)
    with pytest.raises(ParameterError, match=r"time_delay\.delay=-1\.0"):
        pred.many([{"time_delay.delay": 1e-3}, {"time_delay.delay": -1.0}])
    with pytest.raises(ParameterError, match=r"time_delay\.delay=nan"):
        pred.many([{"time_delay.delay": float("nan")}])
    with pytest.raises(ParameterError, match="no parameter"):
        pred.many([{"time_delay.delay": 1e-3}, {"time_delay.tau": 1e-3}])
    with pytest.raises(IPMCError, match="does not apply"):
        pred.many([{}, {"coupling_compliance.compliance_ratio": 0.1}])
    with pytest.raises(ParameterError, match="unknown effect"):
        pred.many([{"warp_drive.speed": 1.0}])


def test_base_values_built_as_arrays_match_records_and_laws_fall_back(monkeypatch):
    """Base values go into one table of arrays (no record per set); a temperature-law name or T_ref
    makes one record per set (apply_values), and both agree with the grouped form."""
    import physmodel.effects.library as lib

    pred = _predictor("actuator", "M", P_ACT)
    built = []
    orig = lib._table_of
    monkeypatch.setattr(lib, "_table_of", lambda *a: built.append(orig(*a)) or built[-1])
    sets = [{"d": P_ACT.d * 1.3, "omega_n": P_ACT.omega_n * 2, "E": P_ACT.E * 0.7, "time_delay.delay": 1e-3},
            {"E": P_ACT.E * 1.5, "h": P_ACT.h * 1.1}, {"omega_n": P_ACT.omega_n * 0.5, "r1_sheet": 0.0}, {}]
    np.testing.assert_allclose(pred.many(sets), pred.many_grouped(sets), rtol=1e-10, atol=0)
    assert built[-1] is not None and built[-1].n == len(sets)
    for extra in ({"laws.d.activation_energy": 25e3}, {"T_ref": 310.0}):
        law_sets = [dict(v, **extra) if k % 2 else v for k, v in enumerate(sets)]
        np.testing.assert_allclose(pred.many(law_sets), pred.many_grouped(law_sets), rtol=1e-10, atol=0)
        assert built[-1] is None


def test_bad_base_values_are_named_as_the_record_names_them():
    pred = _predictor("actuator", "M", P_ACT)
    for bad, pattern in (({"d": -1.0}, r"d=-1\.0 \[m\^2/s\]"), ({"kappa_e": float("nan")}, "kappa_e is NaN"),
                         ({"omega_n": 0.0}, r"omega_n=0\.0 rad/s must be a positive finite number"),
                         ({"E": float("inf")}, r"E=inf .* must be finite")):
        for form in (pred.many, pred.many_grouped):
            with pytest.raises(ParameterError, match=pattern):
                form([{}, bad])


def _same_names(rng, names, p, gain, n_sets=6):
    """Sets that all name the same parameters, as a fit's points and Jacobian columns do: each effect
    on, at its off values or with its switch off in turn."""
    sets = []
    for k in range(n_sets):
        v = {gain: getattr(p, gain) * rng.uniform(0.8, 1.2), "d": p.d * rng.uniform(0.6, 1.6),
             "kappa_e": p.kappa_e * rng.uniform(0.7, 1.4), "xi": float(rng.uniform(0.05, 0.4)),
             "omega_n": p.omega_n * rng.uniform(0.4, 3.0)}
        for j, n in enumerate(names):
            v.update(_draw_effect(rng, n, p, ("on", "on", "off", "switch_off")[(k + j) % 4]))
        sets.append(v)
    return sets


def _array_path(monkeypatch):
    """Count the general path's tables: the array path of sets naming the same parameters builds none."""
    import physmodel.effects.library as lib

    built = []
    orig = lib._table_of
    monkeypatch.setattr(lib, "_table_of", lambda *a: built.append(1) or orig(*a))
    return built


@pytest.mark.parametrize("kind, q, p, gain", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_sets_naming_the_same_parameters_take_the_array_path(kind, q, p, gain, monkeypatch):
    """Sets with one tuple of names go through one array of values (no per-set dicts or table) and
    agree with the grouped form, every batchable effect alone and with a neighbour, with baseline
    effects in the model; a non-batchable effect or a law name takes the general path."""
    rng = np.random.default_rng(2727)
    built = _array_path(monkeypatch)
    names = [n for n in _effects_for(kind, q) if get_effect(n).batchable]
    for baseline in (None, BASELINE if kind == "actuator" else None):
        pred = _predictor(kind, q, p, baseline)
        for i, n in enumerate(names):
            _check(pred, _same_names(rng, [n], p, gain))
            _check(pred, _same_names(rng, [n, names[(i + 1) % len(names)]], p, gain))
        _check(pred, _same_names(rng, [], p, gain))
        # C order as the general path's (an F-ordered result rounds differently in the fits' products)
        assert pred.many(_same_names(rng, names[:1], p, gain)).flags.c_contiguous
    assert built == []
    if kind == "actuator":
        pred = _predictor(kind, q, p)
        _check(pred, [dict(v, **{"fractional_transport.beta": 0.85}) for v in _same_names(rng, ["time_delay"], p, gain)])
        _check(pred, [dict(v, **{"laws.d.activation_energy": 20e3 + 1e3 * k})
                      for k, v in enumerate(_same_names(rng, ["time_delay"], p, gain))])
        assert built


def test_the_array_path_words_bad_values_as_the_general_path(monkeypatch):
    pred = _predictor("actuator", "M", P_ACT)
    built = _array_path(monkeypatch)
    for bad, pattern in (([{"time_delay.delay": 1e-3}, {"time_delay.delay": -1.0}], r"time_delay\.delay=-1\.0"),
                         ([{"time_delay.delay": float("nan")}] * 2, r"time_delay\.delay=nan"),
                         ([{"d": P_ACT.d}, {"d": -1.0}], r"d=-1\.0 \[m\^2/s\]"),
                         ([{"kappa_e": float("nan")}], "kappa_e is NaN"),
                         ([{"omega_n": 1.0}, {"omega_n": 0.0}], r"omega_n=0\.0 rad/s must be a positive finite number"),
                         ([{"E": float("inf")}], r"E=inf .* must be finite")):
        with pytest.raises(ParameterError, match=pattern):
            pred.many(bad)
    assert built == []
    with pytest.raises(ParameterError, match="no parameter"):           # refused names: the general path says so
        pred.many([{"time_delay.tau": 1e-3}] * 2)
    with pytest.raises(IPMCError, match="does not apply"):
        pred.many([{"coupling_compliance.compliance_ratio": 0.1}] * 2)
    with pytest.raises(ParameterError, match="unknown effect"):
        pred.many([{"warp_drive.speed": 1.0}])
    with pytest.raises(ParameterError, match="unknown parameter 'dd'"):
        pred.many([{"dd": 1.0}])


def test_sets_sharing_an_electrode_line_give_what_each_gives_alone():
    """The finite-difference sets of the gain, the mode and response/series effects repeat the
    point's electrode line and slice, evaluated once for them: each set's response is bit for bit
    what it gives alone."""
    pred = _predictor("actuator", "M", P_ACT)
    point = {"alpha0": P_ACT.alpha0, "d": P_ACT.d, "xi": 0.2, "omega_n": P_ACT.omega_n,
             "time_delay.delay": 1e-3, "series_resistance.resistance": 2.0}
    sets = [point] + [dict(point, **{k: v * 1.01}) for k, v in point.items()]
    both = pred.many(sets)
    for i, v in enumerate(sets):
        np.testing.assert_array_equal(both[i], pred.many([v])[0])
