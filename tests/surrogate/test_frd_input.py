"""The fitters (and ``physmodel.data.interop.as_sweep``, the calibration's door) take python-control
FRD objects and plain arrays as well as FrequencySweep files.

Oracle: the same numbers given as a FrequencySweep; the FRD is built by python-control itself
(``control.frd``) from the sweep's arrays.
"""

import control
import numpy as np
import pytest

import physmodel
import surrogate
from physmodel.data.interop import as_sweep
from physmodel.data.sweep import synthesize_sweep
from physmodel.errors import IPMCError
from surrogate._data import to_data

F_HZ = np.logspace(-1, np.log10(9.0), 25)
TEMPS = [25.0, 40.0, 55.0]


@pytest.fixture(scope="module")
def sweep():
    plant = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    return synthesize_sweep(plant, "M", F_HZ, TEMPS)


def _frd(sweep, T):
    sub = sweep.select(T)
    return control.frd(sub.response, 2 * np.pi * sub.frequency_hz)


def test_as_sweep_reads_frds_mappings_and_arrays(sweep):
    frds = {T: _frd(sweep, T) for T in TEMPS}
    a = as_sweep(frds, input_unit="V", output_unit="mm")
    np.testing.assert_allclose(a.response, sweep.response, rtol=1e-15)
    np.testing.assert_array_equal(a.temperature_c, sweep.temperature_c)
    b = as_sweep(list(frds.values()), TEMPS)
    np.testing.assert_allclose(b.frequency_hz, sweep.frequency_hz, rtol=1e-15)
    one = as_sweep(frds[40.0], 40.0)
    assert one.temperatures().tolist() == [40.0]
    c = as_sweep((sweep.frequency_hz[::-1], sweep.response[::-1]), sweep.temperature_c[::-1])
    np.testing.assert_allclose(c.response, sweep.response)          # sorted back per temperature
    assert as_sweep(sweep) is sweep
    assert as_sweep([sweep.select(25.0), sweep.select(40.0)]).temperatures().tolist() == [25.0, 40.0]


@pytest.mark.parametrize("obj, kw, match", [
    (lambda s: _frd(s, 25.0), {}, "carries no temperature"),
    (lambda s: [_frd(s, 25.0), _frd(s, 40.0)], {"temperature_c": [25.0]}, "need 2 temperatures"),
    (lambda s: {"hot": _frd(s, 25.0)}, {}, "keys must be temperatures"),
    (lambda s: (s.frequency_hz, s.response), {}, "need temperature_c"),
    (lambda s: "sweep.csv", {}, "cannot read"),
    (lambda s: control.frd(np.ones((2, 1, 3)), [1.0, 2.0, 3.0]), {"temperature_c": 25.0}, "SISO"),
])
def test_as_sweep_bad_input(sweep, obj, kw, match):
    with pytest.raises(IPMCError, match=match):
        as_sweep(obj(sweep), **kw)


def test_fitters_take_frds_and_arrays(sweep):
    ref = surrogate.RationalFit(3, 3).fit_data(sweep.select(40.0))
    via_frd = surrogate.RationalFit(3, 3).fit_data(_frd(sweep, 40.0))
    via_arrays = surrogate.RationalFit(3, 3).fit_data((F_HZ, sweep.select(40.0).response))
    for r in (via_frd, via_arrays):
        assert r.converged
        np.testing.assert_allclose(r.model.frequency_response(F_HZ), ref.model.frequency_response(F_HZ),
                                   rtol=1e-6)
    sched_ref = surrogate.ScheduledFit("coefficients", 3, 3, 2).fit(sweep)
    sched = surrogate.ScheduledFit("coefficients", 3, 3, 2).fit_data({T: _frd(sweep, T) for T in TEMPS})
    np.testing.assert_allclose(sched.model.frequency_response(F_HZ, 33.0),
                               sched_ref.model.frequency_response(F_HZ, 33.0), rtol=1e-6)
    assert to_data(_frd(sweep, 25.0)).temperature_c is None


def test_calibration_takes_frds_through_as_sweep(sweep):
    from physmodel.estimation.calibration import calibrate

    truth = physmodel.get_parameter_set("seed001_actuator")
    prior = truth.replace(E=3.6e8)
    frds = {T: _frd(sweep, T) for T in TEMPS}
    a = calibrate(as_sweep(frds, input_name="voltage", input_unit="V", output_name="tip_displacement",
                           output_unit="mm"), prior, ["E"], starts=1)
    b = calibrate(sweep, prior, ["E"], starts=1)
    assert a.converged and a.values["E"] == pytest.approx(b.values["E"], rel=1e-9)
    assert a.values["E"] == pytest.approx(truth.E, rel=1e-4)          # noise-free: the truth
