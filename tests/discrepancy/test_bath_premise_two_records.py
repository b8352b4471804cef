"""Two recommended records that both step the bath each get their premise (issue 27 review: only the
first record's was said).  The premise: a record at a temperature the diagnosed record does not hold
is predicted through the diagnosed model's temperature laws, so a misfit there may be the laws."""

from __future__ import annotations

from types import SimpleNamespace

import independent_generator as ig
import pytest

from physmodel import IPMCParameters, get_parameter_set
from physmodel.errors import IPMCError
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
    stepping: no premise; one record (or a second of None): main's single-record sentence, literally."""
    base = get_parameter_set("seed000_sensor_dev")
    laws = base.laws.describe()
    second = bath_premise([_rec("S", 35.0), _rec("S", 5.0, 35.0)], [35.0], base)
    assert second.startswith("Premise: the second experiment (S) steps the bath to 5 °C (the record: 35 °C; the first "
                             "stays at the record's temperatures)") and laws in second
    first = bath_premise([_rec("Z", 65.0), _rec("S", 35.0)], [35.0], base)
    assert first.startswith("Premise: the first experiment (Z) steps the bath to 65 °C") and "the second stays" in first
    assert bath_premise([_rec("S", 35.0), _rec("Z", 35.0)], [35.0], base) == ""
    for one, at, said in ((_rec("S", 5.0, 35.0), [35.0], MAIN_ONE_RECORD[0]),
                          (_rec("Z", 5.0, 65.0), [19.0, 35.0, 55.0], MAIN_ONE_RECORD[1])):
        assert temperature_premise(one, at, base) == said
        assert bath_premise([one], at, base) == said and bath_premise([one, None], at, base) == said
    assert temperature_premise(None, [35.0], base) == ""


#: The one-record premise as main printed it (e83b7c5's ``temperature_premise``, run once on
#: seed000_sensor_dev with the records of the test above) — the text the two-record change must keep.
_LAWS = ("d Arrhenius(activation_energy=15000); E LogLinear(slope=-0.0075); kappa_e WaterPermittivity(); "
         "Rp_specific IonicResistance()")
_REST = ("so its separation relies on the diagnosed model's temperature laws (" + _LAWS + "); a misfit at the new "
         "temperature (an 'unexplained' verdict on both records) means the laws, not the effect, may be wrong — "
         "check them (e.g. a record of the plain strip at that temperature) before reading it as an effect.")
MAIN_ONE_RECORD = ("Premise: this experiment steps the bath to 5 °C (the record: 35 °C), " + _REST,
                   "Premise: this experiment steps the bath to 5, 65 °C (the record: 19, 35, 55 °C), " + _REST)


def test_more_than_two_records_are_refused():
    """The roles are first and second: a third record is an error, not a sentence naming two."""
    base = get_parameter_set("seed000_sensor_dev")
    with pytest.raises(IPMCError, match="3 records given"):
        bath_premise([_rec("S", 5.0), _rec("S", 65.0), _rec("Z", 80.0)], [35.0], base)
