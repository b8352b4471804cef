"""Two recommended records that both step the bath each get their premise (issue 27 review: only the
first record's was said).  The premise: a record at a temperature the diagnosed record does not hold
is predicted through the diagnosed model's temperature laws, so a misfit there may be the laws."""

from __future__ import annotations

from types import SimpleNamespace

import independent_generator as ig

from physmodel import IPMCParameters, get_parameter_set
from physmodel.estimation.next_measurement import next_measurement, temperature_premise
from physmodel.estimation.next_measurement_plan import bath_premise


def _temps(ts) -> str:
    return ", ".join(f"{t:g}" for t in ts)


def test_an_independent_pair_whose_two_records_both_step_the_bath_says_both():
    """Seed 50472 of bench_next_measurement ``--pairs`` (the independent generator's own physics:
    modulus and diffusivity temperature laws, the record at 19-55 °C): no single record separates
    the competing models, a Z and an M record together do, and both step the bath (to 5, 35, 65 °C,
    none of which the record holds).  The premise names each record in its role with the
    temperatures it adds — read off the recommended records, not the message."""
    from physmodel.estimation.discrepancy import diagnose

    seed = 50472
    sweep, truth = ig.make_case(seed, "modulus_temperature+diffusivity_temperature",
                                workflow_free=("alpha", "d", "eps", "zeta", "f1"))
    d = diagnose(sweep, IPMCParameters.from_dict(dict(truth["library_start"])), kind="actuator", quantity="M",
                 free=("alpha0", "d", "kappa_e", "xi", "omega_n"), seed=seed)
    assert d.verdict == "ambiguous", d.message
    nm = next_measurement(d, quantities=["M", "Z"], band_limits_hz=(0.01, 200.0),
                          acts_on={"time_delay": ("M",), "amplifier_bandwidth": ("M",)})
    assert len(nm.also) == 1, nm.message
    held = set(sweep.temperature_c.tolist())
    roles = (("first", nm.recommended), ("second", nm.also[0]))
    new = {role: [t for t in r.temperatures_c if t not in held] for role, r in roles}
    assert all(new.values()), new                                 # the case: both records step the bath
    for role, r in roles:
        assert f"the {role} ({r.quantity}) to {_temps(new[role])} °C" in nm.premise, nm.premise
    assert nm.premise.startswith("Premise: both experiments step the bath")
    assert nm.premise in nm.message and nm.to_dict()["premise"] == nm.premise


def _rec(q, *temps):
    return SimpleNamespace(quantity=q, temperatures_c=tuple(temps))


def test_the_premise_of_each_case_of_two_records():
    """One of two records stepping the bath is named in its role, the other said to stay; none
    stepping: no premise; one record: the single-record sentence (unchanged)."""
    base = get_parameter_set("seed000_sensor_dev")
    laws = base.laws.describe()
    second = bath_premise([_rec("S", 35.0), _rec("S", 5.0, 35.0)], [35.0], base)
    assert second.startswith("Premise: the second experiment (S) steps the bath to 5 °C (the record: 35 °C; the first "
                             "stays at the record's temperatures)") and laws in second
    first = bath_premise([_rec("Z", 65.0), _rec("S", 35.0)], [35.0], base)
    assert first.startswith("Premise: the first experiment (Z) steps the bath to 65 °C") and "the second stays" in first
    assert bath_premise([_rec("S", 35.0), _rec("Z", 35.0)], [35.0], base) == ""
    one = temperature_premise(_rec("S", 5.0, 35.0), [35.0], base)
    assert one == bath_premise([_rec("S", 5.0, 35.0)], [35.0], base)
    assert one.startswith("Premise: this experiment steps the bath to 5 °C (the record: 35 °C), so its separation")
