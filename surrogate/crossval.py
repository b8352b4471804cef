"""Can a temperature schedule be trusted *between* its fit temperatures?

A scheduled fit is judged at the temperatures it was fitted on, where a degree-``d`` polynomial
through ``d + 1`` temperatures matches by construction.  Between them nothing is checked: a 4/4
zpk schedule of degree 2 on 25/40/55 °C matches those to 1-3 % and was 100 % off at 49 °C with the
schema-1 zero sections (noisy seed 001 physics; 3 % with schema 2's — luck of the form, which the
data cannot tell).  This module measures what happens between:

* :func:`cross_validate` — leave-one-temperature-out: refit without each interior temperature
  (same settings) and measure the held-out error there; reported per temperature.  Impossible
  when the remaining temperatures cannot carry the degree (degree 2 on 3 temperatures): then it
  says so instead of inventing a number;
* :func:`select_degree` — the degree with the smallest cross-validated error;
* :func:`dense_check` — the schedule against a reference (the data's physics, see
  :func:`physics_reference`) on a dense temperature grid, split into "at fit temperatures" and
  "between";
* :func:`check_schedule` — both, and a :class:`ScheduleWarning` when the error between fit
  temperatures exceeds ``factor`` times the error at them (or cannot be verified), with the
  physics-calibrated route proposed when there are few temperatures;
* :func:`fit_checked` — fit (optionally choosing the degree by cross-validation) and check, in
  one call; ``.to_markdown()`` for a fit report.

Errors are relative RMS errors ``sqrt(mean |H_model/H_ref - 1|^2)`` over the sweep's frequencies [-].
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from physmodel.errors import IPMCError

from ._data import FrequencyData, to_data
from ._fit import per_temperature_errors
from ._nlp import ConvergenceError

__all__ = ["ScheduleWarning", "HeldOutError", "CrossValidation", "DegreeSelection", "DenseCheck",
           "ScheduleCheck", "cross_validate", "select_degree", "dense_check", "physics_reference",
           "check_schedule", "PHYSICS_ROUTE", "FEW_TEMPERATURES", "CheckedFit", "fit_checked"]

#: At most this many fit temperatures counts as "few": the physics-calibrated route is proposed.
FEW_TEMPERATURES = 5

PHYSICS_ROUTE = (
    "the physics-calibrated route: calibrate the physical model on this sweep "
    "(physmodel.estimation.calibration.calibrate, `ipmc calibrate`), sweep the calibrated physics densely "
    "(>= 7 temperatures over the range: `ipmc sweep --params-json calibrated.json`), fit the schedule "
    "to that sweep holding temperatures out (`ipmc fit --exclude ...`) and check it with "
    "surrogate.crossval.check_schedule(..., physics=...); the scenario control_route.toml shows it")


class ScheduleWarning(UserWarning):
    """A scheduled model's error between its fit temperatures exceeds its error at them (or
    cannot be verified)."""


@dataclass(frozen=True)
class HeldOutError:
    """Error of a schedule refitted without ``temperature_c``, evaluated there.

    Attributes
    ----------
    temperature_c : float  [°C]
    n_lines : int
    relative_rms_error : float  [-]
    converged : bool
        Whether the refit converged (an unconverged refit is still measured, and flagged).
    extrapolated : bool
        ``temperature_c`` lies outside the remaining temperatures (an end temperature).
    """

    temperature_c: float
    n_lines: int
    relative_rms_error: float
    converged: bool
    extrapolated: bool


@dataclass(frozen=True)
class CrossValidation:
    """Leave-one-temperature-out result for one structure and degree.

    Attributes
    ----------
    form : str
    n_zeros, n_poles, degree : int
    held_out : tuple of HeldOutError
        One per held-out temperature (interior ones; the ends too with ``ends=True``).
    fit_errors : tuple of (temperature_c, relative_rms_error)
        Errors of the fit on all temperatures at its fit temperatures [°C], [-].
    feasible : bool
        False when no temperature could be held out (too few temperatures for the degree).
    reason : str
        Why it is infeasible ("" otherwise).
    """

    form: str
    n_zeros: int
    n_poles: int
    degree: int
    held_out: tuple = ()
    fit_errors: tuple = ()
    feasible: bool = True
    reason: str = ""

    @property
    def between(self) -> list[HeldOutError]:
        """Held-out errors at interior temperatures (interpolation)."""
        return [h for h in self.held_out if not h.extrapolated]

    @property
    def cv_error(self) -> float:
        """Largest held-out error between fit temperatures [-] (``nan`` if infeasible)."""
        b = self.between
        return max(h.relative_rms_error for h in b) if b else float("nan")

    @property
    def mean_cv_error(self) -> float:
        b = self.between
        return float(np.mean([h.relative_rms_error for h in b])) if b else float("nan")

    @property
    def fit_error(self) -> float:
        """Largest error at the fit temperatures [-]."""
        return max(e for _, e in self.fit_errors) if self.fit_errors else float("nan")

    def to_markdown(self) -> str:
        head = (f"Leave-one-temperature-out, {self.form} {self.n_zeros}/{self.n_poles}, degree {self.degree}: "
                + ("" if self.feasible else f"not possible ({self.reason})"))
        rows = ["| T [°C] | role | relative RMS error | refit converged |", "|---:|:---|---:|:---|"]
        for t, e in self.fit_errors:
            rows.append(f"| {t:g} | in fit | {e:.4f} | |")
        for h in self.held_out:
            role = "held out (extrapolated)" if h.extrapolated else "held out"
            rows.append(f"| {h.temperature_c:g} | {role} | {h.relative_rms_error:.4f} | {'yes' if h.converged else 'NO'} |")
        return head + "\n\n" + "\n".join(rows) + "\n"


def _clone(template: Any, degree: int | None = None) -> Any:
    from .scheduled import ScheduledFit

    if not isinstance(template, ScheduledFit):
        raise IPMCError(f"expected a surrogate.ScheduledFit as the template, got {type(template).__name__}")
    s = template.settings()
    s.pop("estimator")
    form, nz, npl, deg = s.pop("form"), s.pop("n_zeros"), s.pop("n_poles"), s.pop("degree")
    return ScheduledFit(form, nz, npl, deg if degree is None else int(degree), raise_on_failure=False, **s)


def _fit(template: Any, data: FrequencyData, degree: int | None = None):
    try:
        return _clone(template, degree).fit_data(data)
    except ConvergenceError as exc:   # pragma: no cover - raise_on_failure=False returns flagged results
        return exc.result


def _errors_at(model: Any, data: FrequencyData, temps) -> list[tuple[float, float]]:
    errs = per_temperature_errors(model, data.select(np.isin(data.temperature_c, temps)), extrapolate=True)
    return [(float(e.temperature_c), float(e.relative_rms_error)) for e in errs]


def cross_validate(template: Any, data: Any, *, degree: int | None = None, ends: bool = False,
                   full_result: Any = None) -> CrossValidation:
    """Leave-one-temperature-out cross-validation of a scheduled fit.

    Parameters
    ----------
    template : ScheduledFit
        Settings (form, orders, degree, weighting, ...) of the fit to validate; it is cloned,
        never modified.
    data : FrequencySweep, FrequencyData, control.FrequencyResponseData list, ...
        The data the schedule is fitted to (several temperatures).
    degree : int, optional
        Override the template's degree.
    ends : bool
        Also hold out the lowest and highest temperature (extrapolation, flagged).
    full_result : FitResult, optional
        The fit on all temperatures (computed if not given), for the at-temperature errors.
    """
    data = to_data(data)
    if data.temperature_c is None:
        raise IPMCError("cross-validation over temperature needs data with temperatures")
    temps = data.temperatures()
    deg = template.degree if degree is None else int(degree)
    st = _clone(template, deg)
    base = dict(form=st.form, n_zeros=st.n_zeros, n_poles=st.n_poles, degree=deg)
    full = full_result if full_result is not None else _fit(template, data, deg)
    fit_errors = tuple(_errors_at(full.model, data, temps))
    need = max(deg + 1, 2)
    candidates = temps if ends else temps[1:-1]
    if temps.size - 1 < need or candidates.size == 0:
        reason = (f"{temps.size} temperatures: holding one out leaves {temps.size - 1}, a degree-{deg} "
                  f"schedule needs {need}" if temps.size - 1 < need else
                  f"no temperature lies between {temps[0]:g} and {temps[-1]:g} °C")
        return CrossValidation(**base, held_out=(), fit_errors=fit_errors, feasible=False, reason=reason)
    held = []
    for t in candidates:      # one refit per held-out temperature (each an NLP)
        train = data.select(data.temperature_c != t)
        res = _fit(template, train, deg)
        (_, err), = _errors_at(res.model, data, [t])
        tt = train.temperatures()
        held.append(HeldOutError(float(t), int(np.sum(data.temperature_c == t)), err, bool(res.converged),
                                 bool(t < tt.min() or t > tt.max())))
    return CrossValidation(**base, held_out=tuple(held), fit_errors=fit_errors)


@dataclass(frozen=True)
class DegreeSelection:
    """Cross-validated choice of the polynomial degree.

    Attributes
    ----------
    rows : tuple of CrossValidation
        One per candidate degree.
    best_degree : int
        Smallest mean held-out error among the feasible degrees (ties: the lower degree).
    result : FitResult
        The fit with ``best_degree`` on all temperatures.
    """

    rows: tuple
    best_degree: int
    result: Any

    def to_markdown(self) -> str:
        lines = ["| degree | error at fit T (max) | held-out error between (mean / max) |", "|---:|---:|:---|"]
        for r in self.rows:
            cv = f"{r.mean_cv_error:.4f} / {r.cv_error:.4f}" if r.feasible else f"n/a ({r.reason})"
            lines.append(f"| {r.degree}{' (chosen)' if r.degree == self.best_degree else ''} | {r.fit_error:.4f} | {cv} |")
        return "\n".join(lines) + "\n"


def select_degree(template: Any, data: Any, degrees=(0, 1, 2, 3)) -> DegreeSelection:
    """Choose the schedule's polynomial degree by leave-one-temperature-out cross-validation.

    Degrees the data cannot carry (``degree + 1`` > number of temperatures) are skipped; degrees
    that cannot be cross-validated are reported (``feasible=False``) and not chosen, unless none
    can be, in which case an ``IPMCError`` says so.
    """
    data = to_data(data)
    n_t = data.temperatures().size
    rows = []
    for d in sorted(set(int(x) for x in degrees)):
        if d < 0:
            raise IPMCError(f"degrees must be >= 0, got {d}")
        if d + 1 > n_t:
            continue
        rows.append(cross_validate(template, data, degree=d))
    ok = [r for r in rows if r.feasible]
    if not ok:
        raise IPMCError(f"no degree in {list(degrees)} can be cross-validated on {n_t} temperatures "
                        f"(need at least 3, one of them between the others); use " + PHYSICS_ROUTE)
    best = min(ok, key=lambda r: (round(r.mean_cv_error, 12), r.degree))
    return DegreeSelection(tuple(rows), best.degree, _fit(template, data, best.degree))


@dataclass(frozen=True)
class DenseCheck:
    """A schedule against a reference response on a dense temperature grid.

    Attributes
    ----------
    temperatures_c : ndarray  [°C]
    errors : ndarray
        Relative RMS error at each temperature [-].
    at_fit : ndarray of bool
        Which grid temperatures are fit temperatures.
    """

    temperatures_c: np.ndarray
    errors: np.ndarray
    at_fit: np.ndarray

    @property
    def at_fit_error(self) -> float:
        return float(np.max(self.errors[self.at_fit])) if np.any(self.at_fit) else float("nan")

    @property
    def between_error(self) -> float:
        return float(np.max(self.errors[~self.at_fit])) if np.any(~self.at_fit) else float("nan")

    @property
    def worst_temperature_c(self) -> float:
        return float(self.temperatures_c[int(np.argmax(self.errors))])


def physics_reference(model: Any, quantity: str = "M") -> Callable:
    """A reference ``f(frequency_hz, temperatures_c) -> (n_T, n_f) complex`` from a physmodel model,
    in the sweep units of :func:`physmodel.data.sweep.synthesize_sweep` (mm/V for actuation)."""
    from physmodel.data.sweep import synthesize_sweep

    def ref(frequency_hz, temperatures_c):
        sw = synthesize_sweep(model, quantity, np.asarray(frequency_hz, float), list(np.atleast_1d(temperatures_c)))
        _, _, H = sw.grid()
        return H

    return ref


def dense_check(model: Any, reference: Callable, frequency_hz: Any, fit_temperatures_c: Any, *,
                step_c: float = 1.0) -> DenseCheck:
    """Compare a scheduled ``model`` with ``reference`` on a grid of ``step_c`` [°C] spanning the fit
    temperatures (which are included).  ``reference(frequency_hz, temperatures) -> (n_T, n_f)``."""
    ft = np.unique(np.asarray(fit_temperatures_c, float))
    if ft.size < 2:
        raise IPMCError("a dense temperature check needs a schedule over at least 2 temperatures")
    if not (np.isfinite(step_c) and step_c > 0):
        raise IPMCError(f"step_c must be > 0, got {step_c!r}")
    grid = np.unique(np.concatenate((np.arange(ft[0], ft[-1] + 1e-9, step_c), ft)))
    f = np.asarray(frequency_hz, float)
    H_ref = np.asarray(reference(f, grid), complex)
    if H_ref.shape != (grid.size, f.size):
        raise IPMCError(f"reference returned shape {H_ref.shape}, expected {(grid.size, f.size)}")
    H_mod = np.stack([model.frequency_response(f, float(t)) for t in grid])
    errs = np.sqrt(np.mean(np.abs(H_mod / H_ref - 1.0) ** 2, axis=1))
    at_fit = np.any(np.isclose(grid[:, None], ft[None, :], rtol=0, atol=1e-9), axis=1)
    return DenseCheck(grid, errs, at_fit)


@dataclass(frozen=True)
class ScheduleCheck:
    """Verdict of :func:`check_schedule`.

    Attributes
    ----------
    ok : bool
        The error between fit temperatures is at most ``factor`` times the error at them, and
        it was measured (by cross-validation or against the physics).
    at_fit_error, between_error : float
        Largest relative RMS error at / between the fit temperatures [-] (``nan`` if unmeasured).
    cv : CrossValidation
    dense : DenseCheck or None
    message : str
    proposal : str
        The physics-calibrated route, when there are few temperatures ("" otherwise).
    """

    ok: bool
    at_fit_error: float
    between_error: float
    cv: CrossValidation
    dense: DenseCheck | None = None
    message: str = ""
    proposal: str = ""
    factor: float = 2.0
    notes: list = field(default_factory=list)


def check_schedule(template: Any, data: Any, model: Any = None, *, physics: Any = None,
                   frequency_hz: Any = None, factor: float = 2.0, step_c: float = 1.0,
                   warn: bool = True) -> ScheduleCheck:
    """Trust check of a scheduled fit between its temperatures.

    Parameters
    ----------
    template : ScheduledFit
        The fitter (its settings); cloned for the leave-one-out refits.
    data : sweep-like
        The data the schedule was fitted to.
    model : RationalModel, optional
        The fitted schedule (fitted here from ``template`` if not given).
    physics : callable or physmodel model, optional
        The data's physics: a reference ``f(frequency_hz, temperatures) -> (n_T, n_f)`` or a
        physmodel actuator/sensor model (wrapped by :func:`physics_reference`, quantity M/S).
    frequency_hz : array_like, optional
        Frequencies of the dense check [Hz] (default: those of the data).
    factor : float
        Warn when ``between_error > factor * at_fit_error``.
    step_c : float
        Dense grid spacing [°C].
    warn : bool
        Issue a :class:`ScheduleWarning` when the check fails.
    """
    data = to_data(data)
    temps = data.temperatures()
    full = _fit(template, data) if model is None else _Wrap(model)
    model = full.model
    cv = cross_validate(template, data, full_result=full)
    dense = None
    if physics is not None:
        ref = physics if callable(physics) and not hasattr(physics, "frequency_response") else \
            physics_reference(physics, "M" if type(physics).__name__ == "ActuatorModel" else "S")
        f = data.frequency_hz[data.temperature_c == temps[0]] if frequency_hz is None else frequency_hz
        dense = dense_check(model, ref, f, temps, step_c=step_c)
    at_fit = cv.fit_error
    measured = [x for x in (cv.cv_error, dense.between_error if dense else float("nan")) if np.isfinite(x)]
    between = max(measured) if measured else float("nan")
    notes = []
    if not cv.feasible:
        notes.append(f"leave-one-temperature-out not possible: {cv.reason}")
    else:
        notes.append("held-out errors: " + ", ".join(f"{h.temperature_c:g} °C {h.relative_rms_error:.3g}"
                                                   for h in cv.held_out))
    if dense is not None:
        notes.append(f"against the physics on {dense.temperatures_c.size} temperatures: at fit temperatures "
                     f"{dense.at_fit_error:.3g}, between {dense.between_error:.3g} (worst at "
                     f"{dense.worst_temperature_c:g} °C)")
    proposal = PHYSICS_ROUTE if temps.size <= FEW_TEMPERATURES else ""
    if not measured:
        ok = False
        msg = (f"the schedule ({cv.form} {cv.n_zeros}/{cv.n_poles}, degree {cv.degree}, {temps.size} "
               f"temperatures {temps.tolist()} °C) is unverified between its temperatures: "
               f"{'; '.join(notes)}; its error at them is {at_fit:.3g}")
    else:
        ok = bool(between <= factor * at_fit)
        msg = (f"schedule error between fit temperatures {between:.3g} "
               f"{'<=' if ok else 'exceeds'} {factor:g} x its error at them ({at_fit:.3g}); "
               + "; ".join(notes))
    if not ok and proposal:
        msg += f". With {temps.size} temperatures, use {proposal}"
    if not ok and warn:
        warnings.warn(ScheduleWarning(msg), stacklevel=2)
    return ScheduleCheck(ok, at_fit, between, cv, dense, msg, proposal if not ok else "", factor, notes)


class _Wrap:
    """A fitted model posing as a FitResult (for :func:`cross_validate`'s ``full_result``)."""

    def __init__(self, model: Any):
        self.model = model
        self.converged = True


@dataclass(frozen=True)
class CheckedFit:
    """A scheduled fit with its trust check (see :func:`fit_checked`).

    Attributes
    ----------
    result : FitResult
        The fit on all temperatures (with the chosen degree).
    selection : DegreeSelection or None
        The cross-validated degree choice (None when the template's degree was kept).
    check : ScheduleCheck
        Leave-one-temperature-out (and dense physics) check of ``result``.
    """

    result: Any
    selection: DegreeSelection | None
    check: ScheduleCheck

    def to_markdown(self) -> str:
        parts = []
        if self.selection is not None:
            parts += ["### Degree chosen by leave-one-temperature-out", "", self.selection.to_markdown()]
        parts += ["### Error between fit temperatures", "", self.check.cv.to_markdown(),
                  ("OK: " if self.check.ok else "**WARNING**: ") + self.check.message, ""]
        return "\n".join(parts)


def fit_checked(template: Any, data: Any, *, degrees=None, physics: Any = None, factor: float = 2.0,
                warn: bool = True) -> CheckedFit:
    """Fit a schedule and check it between its temperatures in one call.

    ``degrees``: candidate degrees to choose from by cross-validation (:func:`select_degree`);
    ``None`` keeps the template's degree.  ``physics``: the data's physics for the dense check
    (see :func:`check_schedule`).  A failed check warns (:class:`ScheduleWarning`) unless
    ``warn=False``; the verdict is in ``.check``.
    """
    data = to_data(data)
    selection = None
    if degrees is not None:
        selection = select_degree(template, data, degrees)
        result = selection.result
        template = _clone(template, selection.best_degree)
    else:
        result = _fit(template, data)
    check = check_schedule(template, data, result.model, physics=physics, factor=factor, warn=warn)
    return CheckedFit(result, selection, check)
