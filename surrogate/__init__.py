"""Low-order, temperature-scheduled rational surrogates of IPMC frequency responses.

Fits are solved in scaled variables (s̃ = s/ω_ref, response/g_ref, τ = (T − T_c)/T_s) by a
Levenberg–Marquardt solver with a closed-form Jacobian (all starts in lockstep, losing starts
stopped early), and by CasADi/IPOPT only where a constraint is needed (section bounds, the
Hurwitz stability constraints of the coefficient form); frequencies are in Hz at the edges and the fitted transfer functions
use s in rad/s, like the seed papers' models.

Public API
----------
Data
    Every fitter takes a ``physmodel.data.sweep.FrequencySweep`` directly (``fit(sweep)`` or
    ``fit_data(sweep)``), or arrays.
    FrequencyData(frequency_hz, temperature_c, response, magnitude_std_db=None,
                  phase_std_deg=None, ...)        for data a sweep does not cover (no
                                               temperature, free unit labels); validated by
                                               FrequencySweep's own checks; ``fingerprint()``
    from_sweep(sweep) -> FrequencyData         FrequencySweep (or look-alike) → FrequencyData
Fitters (estimator style: settings in the constructor, ``fit`` returns a FitResult and sets
``model_``, ``result_``, ``history_``)
    RationalFit(n_zeros, n_poles, stable=True, weighting='auto', init='auto', ...)
        .fit(frequency_hz | sweep, temperature_c=None, response=None, magnitude_std_db=None,
             phase_std_deg=None)
    ScheduledFit(form='zpk'|'coefficients'|'sections', n_zeros, n_poles, degree,
                 method='joint'|'two-stage', per_temperature='nlp'|'levy',
                 stability_margin=1e-3, ...)
        .fit(frequency_hz | sweep, temperature_c=None, response=None, magnitude_std_db=None,
             phase_std_deg=None)
    fit_sweep(sweep, n_zeros, n_poles, degree=2, form='zpk', **settings) -> FitResult
    levy(omega_scaled, response_scaled, n_zeros, n_poles)   Levy / Octave-invfreqs baseline
Results and models
    FitResult        converged, status, params, stderr, ci95_low/high, per_temperature,
                     stability, history, two_stage, per_temperature_models, summary()
    RationalModel    kind = "rational", response(frequency_hz, temperature_c) (the model protocol),
                     frequency_response(frequency_hz, temperature_c), at(T) -> control.TransferFunction,
                     coefficients(T), poles(T), zeros(T), stability_check(), parameter_table(),
                     confidence_intervals(), to_json(path)
    load(path) -> RationalModel                versioned JSON (schema ``ipmc.surrogate.rational_model``)
    Structure, Scaling, StabilityCheck, TemperatureError
Trusting a schedule between its temperatures (:mod:`surrogate.crossval`)
    cross_validate (leave one temperature out), select_degree, dense_check / physics_reference
    (against the physics on a dense temperature grid), check_schedule -> ScheduleCheck (warns with
    ScheduleWarning and proposes the physics-calibrated route), fit_checked (fit + check)
Order selection
    order_selection(frequency_hz, temperature_c, response, orders, ...) -> OrderSelectionReport
Metrics
    relative_rms_error, fit_percent (100·(1 − NRMSE)), log_rms_error
Errors
    ConvergenceError (a ``physmodel.errors.NotConvergedError``: raised when a fit does not converge;
    ``.result`` holds the flagged result)
Command line: ``ipmc fit`` (:mod:`scenarios.commands.fit`); figures: :mod:`scenarios.plots`.
"""

from ._data import FrequencyData, from_sweep
from ._fit import FitResult, TemperatureError
from ._init import levy
from ._nlp import ConvergenceError
from ._structure import FORMS, Structure
from .crossval import (
    CrossValidation,
    ScheduleCheck,
    ScheduleWarning,
    check_schedule,
    cross_validate,
    dense_check,
    fit_checked,
    physics_reference,
    select_degree,
)
from .metrics import fit_percent, log_rms_error, relative_rms_error
from .models import RationalModel, Scaling, StabilityCheck, load
from .rational import RationalFit
from .scheduled import ScheduledFit
from .selection import OrderRow, OrderSelectionReport, order_selection

__all__ = [
    "FrequencyData", "from_sweep", "RationalFit", "ScheduledFit", "fit_sweep", "levy",
    "FitResult", "TemperatureError", "RationalModel", "Scaling", "StabilityCheck", "Structure", "FORMS",
    "load", "order_selection", "OrderRow", "OrderSelectionReport", "relative_rms_error",
    "fit_percent", "log_rms_error", "ConvergenceError",
    "cross_validate", "select_degree", "check_schedule", "fit_checked", "dense_check", "physics_reference",
    "CrossValidation", "ScheduleCheck", "ScheduleWarning",
]


def fit_sweep(sweep, n_zeros: int, n_poles: int, degree: int = 2, form: str = "zpk", **settings):
    """Fit a physmodel ``FrequencySweep``: one temperature → ``RationalFit``,
    several → ``ScheduledFit``.  ``settings`` go to the fitter's constructor."""
    data = from_sweep(sweep)
    if data.temperatures().size <= 1:
        settings.pop("method", None)
        return RationalFit(n_zeros, n_poles, **settings).fit_data(data)
    return ScheduledFit(form, n_zeros, n_poles, degree, **settings).fit_data(data)
