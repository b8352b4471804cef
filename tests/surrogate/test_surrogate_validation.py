"""Bad input reaches a ValueError that names it; non-convergence is never silent."""

import numpy as np
import pytest
from surrogate_standin import physics_sweep

from physmodel.data.sweep import FrequencySweep
from physmodel.errors import IPMCError
from surrogate import ConvergenceError, FrequencyData, RationalFit, from_sweep

F = np.geomspace(1.0, 100.0, 12)
H = 1.0 / (1 + 1j * F / 10.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [   # FrequencyData is validated by physmodel.data.sweep.FrequencySweep's checks (one code path)
        (dict(frequency_hz=np.append(F[:-1], np.nan)), r"frequency_hz contains NaN or inf at rows \[11\]"),
        (dict(response=np.append(H[:-1], np.nan)), r"response contains NaN or inf at rows \[11\]"),
        (dict(response=H[:-1]), r"one value per line; got 12, 12, 11"),
        (dict(temperature_c=np.full(11, 25.0)), r"temperature_c has shape \(11,\) but frequency_hz has 12 lines"),
        (dict(frequency_hz=-F), r"frequencies must be > 0 Hz; got \[-1.0"),
        (dict(frequency_hz=F[::-1]), r"frequencies at 25 °C must strictly increase"),
        (dict(magnitude_std_db=np.zeros(12), phase_std_deg=np.ones(12)),
         r"magnitude_std_db must be > 0 \(it becomes a weight 1/σ\), got 0.0 at index 0"),
        (dict(phase_std_deg=np.full(12, np.inf), magnitude_std_db=np.ones(12)), r"phase_std_deg must be finite"),
        (dict(magnitude_std_db=np.ones(12)), r"give both magnitude_std_db and phase_std_deg, or neither"),
        (dict(response=np.where(np.arange(12) == 3, 0, H)), r"response is exactly 0 at rows \[3\]"),
        (dict(temperature_c="warm"), r"temperature_c must be an array of real numbers"),
    ],
)
def test_bad_data_is_named(kwargs, message):
    args = dict(frequency_hz=F, temperature_c=25.0, response=H)
    args.update(kwargs)
    with pytest.raises(IPMCError, match=message):
        FrequencyData(**args)


def test_fitters_take_a_frequency_sweep_directly():
    sweep = FrequencySweep(np.full(12, 30.0), F, H, input_unit="V", output_unit="mm")
    res = RationalFit(0, 1).fit(sweep)
    np.testing.assert_allclose(res.model.poles(), [-2 * np.pi * 10.0], rtol=1e-6)
    assert res.model.labels["output_unit"] == "mm"
    assert RationalFit(0, 1).fit_data(sweep).data_fingerprint == res.data_fingerprint
    with pytest.raises(IPMCError, match="expected FrequencyData or a physmodel FrequencySweep, got str"):
        RationalFit(0, 1).fit("sweep.csv")


def test_order_too_high_for_the_number_of_points():
    with pytest.raises(ValueError, match=r"order too high .* 11 real unknowns .* only 5 frequency lines"):
        RationalFit(5, 5).fit(F[:5], 25.0, H[:5])


def test_bad_settings_are_named():
    with pytest.raises(ValueError, match="n_zeros=4 > n_poles=3"):
        RationalFit(4, 3)
    with pytest.raises(ValueError, match="weighting must be one of"):
        RationalFit(1, 2, weighting="magic")
    with pytest.raises(ValueError, match="max_iter must be an integer >= 1"):
        RationalFit(1, 2, max_iter=0)


def test_uncertainty_weighting_needs_both_standard_deviations():
    with pytest.raises(ValueError, match="needs both magnitude_std_db and phase_std_deg"):
        RationalFit(0, 1, weighting="uncertainty").fit(F, 25.0, H)


def test_rational_fit_rejects_several_temperatures():
    with pytest.raises(ValueError, match=r"RationalFit fits one temperature .* \[20.0, 30.0\]"):
        RationalFit(0, 1).fit(np.tile(F, 2), np.repeat([20.0, 30.0], 12), np.tile(H, 2))


def test_evaluation_outside_the_validity_range_is_an_error():
    f, t, h, *_ = physics_sweep([20.0, 40.0, 60.0], np.geomspace(0.1, 20, 25))
    from surrogate import ScheduledFit

    res = ScheduledFit("coefficients", 2, 3, 1).fit(f, t, h)
    with pytest.raises(ValueError, match=r"temperature_c=70.0 is outside the model's validity range \[20.0, 60.0\]"):
        res.model.frequency_response([1.0], 70.0)
    assert np.isfinite(res.model.frequency_response([1.0], 70.0, extrapolate=True)).all()
    with pytest.raises(ValueError, match="temperature_c is required"):
        res.model.at(None)


def test_rational_non_convergence_raises_or_is_flagged():
    f, t, h, _, smag, sph = physics_sweep([25.0], np.geomspace(0.1, 20, 40), magnitude_std_db=0.2,
                                          phase_std_deg=1.0)
    with pytest.raises(ConvergenceError, match="Maximum_Iterations_Exceeded") as info:
        RationalFit(4, 4, max_iter=1).fit(f, t, h, smag, sph)
    assert info.value.result is not None and not info.value.result.converged
    res = RationalFit(4, 4, max_iter=1, raise_on_failure=False).fit(f, t, h, smag, sph)
    assert res.converged is False and res.status == "Maximum_Iterations_Exceeded"
    assert all(not e["converged"] for e in res.history)


def test_from_sweep_uses_only_the_documented_attributes():
    class Sweep:  # duck-typed stand-in for physmodel.data.sweep.FrequencySweep
        __slots__ = ("temperature_c", "frequency_hz", "response", "magnitude_std_db", "phase_std_deg",
                     "input_name", "input_unit", "output_name", "output_unit", "metadata")

        def temperatures(self):
            return np.unique(self.temperature_c)

    s = Sweep()
    s.frequency_hz, s.temperature_c, s.response = F, np.full(12, 30.0), H
    s.magnitude_std_db = s.phase_std_deg = None
    s.input_name, s.input_unit, s.output_name, s.output_unit = "voltage", "V", "tip_displacement", "mm"
    s.metadata = {"source": "test"}
    d = from_sweep(s)
    assert d.labels() == {"input_name": "voltage", "input_unit": "V",
                          "output_name": "tip_displacement", "output_unit": "mm"}
    from surrogate import fit_sweep

    res = fit_sweep(s, 0, 1)
    np.testing.assert_allclose(res.model.poles(), [-2 * np.pi * 10.0], rtol=1e-6)
