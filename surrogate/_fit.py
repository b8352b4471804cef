"""Shared pieces of the fitters: scaling, weighting, order checks, results."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ._data import FrequencyData, to_data
from ._lsq import LevenbergMarquardt
from ._nlp import ConvergenceError, Problem, SolveOutcome, covariance
from ._structure import Structure
from .metrics import fit_percent, relative_rms_error
from .models import RationalModel, Scaling, StabilityCheck

WEIGHTINGS = ("auto", "uncertainty", "log", "relative")


def as_data(frequency_hz, temperature_c, response, magnitude_std_db, phase_std_deg) -> FrequencyData:
    """Arrays → ``FrequencyData``; a ``FrequencyData`` or ``FrequencySweep`` passed as the first
    argument (the others ``None``) is taken as the data."""
    if response is None:          # data (a sweep, FrequencyData, FRD or {T: FRD}) and an optional temperature
        return to_data(frequency_hz, temperature_c)
    return FrequencyData(frequency_hz, temperature_c, response, magnitude_std_db, phase_std_deg)


def check_weighting(weighting: str) -> str:
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {WEIGHTINGS}, got {weighting!r}")
    return weighting


def check_positive_int(name, v, minimum=1):
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {v!r}")
    return int(v)


def check_positive_float(name, v, allow_none=True):
    if v is None and allow_none:
        return None
    try:
        f = float(v)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {v!r}") from None
    if not np.isfinite(f) or f <= 0:
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")
    return f


def resolve_weighting(weighting: str, data: FrequencyData):
    """(residual kind, 1/σ_a, 1/σ_b, resolved name)."""
    if weighting == "auto":
        weighting = "uncertainty" if data.has_uncertainty else "log"
    ones = np.ones(data.n)
    if weighting == "uncertainty":
        sa, sb = data.log_std()
        return "log", 1.0 / sa, 1.0 / sb, weighting
    if weighting == "log":
        return "log", ones, ones, weighting
    return "relative", ones, ones, weighting


def make_scaling(data: FrequencyData, omega_ref=None, gain_ref=None, t_center=None, t_scale=None) -> Scaling:
    w = data.omega
    if omega_ref is None:
        omega_ref = float(np.sqrt(w.min() * w.max()))
    if gain_ref is None:
        gain_ref = float(np.exp(np.mean(np.log(np.abs(data.response)))))
    if t_center is None or t_scale is None:
        temps = data.temperatures()
        if t_center is None:
            t_center = float(0.5 * (temps.min() + temps.max())) if temps.size else 0.0
        if t_scale is None:
            t_scale = float(0.5 * (temps.max() - temps.min())) if temps.size > 1 else 1.0
    return Scaling(float(omega_ref), float(gain_ref), float(t_center), float(t_scale))


def make_problem(structure: Structure, data: FrequencyData, scaling: Scaling, weighting: str):
    kind, ia, ib, name = resolve_weighting(weighting, data)
    w = data.omega / scaling.omega_ref_rad_s
    if data.temperature_c is None or structure.degree == 0:
        tau = np.zeros(data.n)
    else:
        tau = (data.temperature_c - scaling.temperature_center_c) / scaling.temperature_scale_c
    return Problem(structure, w, tau, data.response / scaling.gain_ref, kind, ia, ib), name


def check_order_per_temperature(structure: Structure, data: FrequencyData, temps=None):
    """Each temperature must carry at least as many real equations as a per-T fit has unknowns.
    ``temps``: ``data.temperatures()`` if already at hand."""
    n_unknown = structure.n_zeros + 1 + structure.n_poles
    if data.temperature_c is None:
        groups = [(None, data.n)]
    else:
        temps = data.temperatures() if temps is None else temps
        groups = [(temps[0], data.n)] if temps.size == 1 else [
            (t, int(np.sum(data.temperature_c == t))) for t in temps]
    for t, count in groups:
        if 2 * count < n_unknown:
            where = "" if t is None else f" at temperature_c={t:g}"
            raise ValueError(
                f"order too high for the number of points: n_zeros={structure.n_zeros}, "
                f"n_poles={structure.n_poles} has {n_unknown} real unknowns but{where} there are "
                f"only {count} frequency lines ({2 * count} real equations); "
                f"need at least {int(np.ceil(n_unknown / 2))} lines"
            )


@dataclass(frozen=True)
class TemperatureError:
    """Fit quality at one temperature.

    relative_rms_error : sqrt(mean |H_m − H_d|²/|H_d|²). [-]
    fit_percent : 100·(1 − NRMSE). [%]
    """

    temperature_c: float | None
    n_lines: int
    relative_rms_error: float
    fit_percent: float


def per_temperature_errors(model: RationalModel, data: FrequencyData, extrapolate=False,
                           response=None):
    """Fit quality at each temperature of ``data`` (one evaluation of the model over all
    lines, split by temperature).  ``response``: the model's response on the lines of
    ``data`` if already at hand."""
    if response is None:
        tt = data.temperature_c if (model.is_scheduled and data.temperature_c is not None) else None
        response = model.frequency_response(data.frequency_hz, tt, extrapolate=extrapolate)
    h = response
    temps = [None] if data.temperature_c is None else list(data.temperatures())
    out = []
    for t in temps:
        k = slice(None) if (t is None or len(temps) == 1) else np.isclose(data.temperature_c, t, rtol=0, atol=1e-9)
        hm, hd = h[k], data.response[k]
        try:
            fp = fit_percent(hm, hd)
        except ValueError:  # a single line per temperature: NRMSE undefined
            fp = float("nan")
        out.append(TemperatureError(None if t is None else float(t), int(hd.size),
                                    relative_rms_error(hm, hd), fp))
    return out


class _Deferred:
    """A value computed on first use (then kept): the parts of a fit result that cost more
    than the fit's last iterations but are often not read (covariance, pole check,
    per-temperature errors)."""

    __slots__ = ("_fn", "_value")

    def __init__(self, fn):
        self._fn, self._value = fn, None

    def __call__(self):
        if self._fn is not None:
            self._value, self._fn = self._fn(), None
        return self._value

    def __getstate__(self):            # pickled / deep-copied as the computed value
        return self()

    def __setstate__(self, value):
        self._fn, self._value = None, value


@dataclass
class FitResult:
    """What a fit returns.  Every array is in the model's parameter layout.

    converged : the solver reported success (``status`` holds its return status, in IPOPT's
        names whichever solver ran: Levenberg–Marquardt, or IPOPT for constrained solves).
    cost : ½·mean of squared weighted residuals at the solution. [-]
    weighted_rms : sqrt(2·cost), RMS weighted residual (≈1 for a correct model and
        correct uncertainties with weighting 'uncertainty'). [-]
    stderr, ci95_low, ci95_high : from the Gauss–Newton covariance at the optimum
        (None when not available, e.g. for the two-stage baseline).
    covariance_rank_deficient : the Jacobian at the optimum is rank deficient (the
        covariance is then a pseudo-inverse).
    at_bounds : parameters that ended on a bound (their intervals are unreliable).
    per_temperature : list of ``TemperatureError``, one per temperature of the data.
    stability : independent pole check (dense temperature grid for scheduled models).
    history : one dict per solver run (stage, start, status, iterations, cost, time_s,
        objective trace).

    The covariance (hence ``stderr``, ``ci95_low``, ``ci95_high``,
    ``covariance_rank_deficient`` and ``model.covariance``), ``per_temperature`` and
    ``stability`` are computed when first read, not by the fit: a fit whose caller reads
    only the model does not pay for them.
    """

    model: RationalModel
    converged: bool
    status: str
    iterations: int
    cost: float
    weighted_rms: float
    weighting: str
    method: str
    param_names: list
    params: np.ndarray
    at_bounds: list
    time_s: float
    data_fingerprint: str
    history: list = field(default_factory=list)
    two_stage: RationalModel | None = None
    per_temperature_models: dict | None = None
    _covariance: _Deferred | None = field(default=None, repr=False, compare=False)
    _per_temperature: _Deferred | None = field(default=None, repr=False, compare=False)
    _stability: _Deferred | None = field(default=None, repr=False, compare=False)

    @property
    def stderr(self) -> np.ndarray | None:
        """Standard errors of ``params`` (Gauss–Newton covariance), or None. [-]"""
        return self.model.stderr

    @property
    def ci95_low(self) -> np.ndarray | None:
        """Lower ends of the normal-approximation 95 % intervals of ``params``, or None. [-]"""
        ci = self.model.confidence_intervals()
        return None if ci is None else ci[0]

    @property
    def ci95_high(self) -> np.ndarray | None:
        """Upper ends of the normal-approximation 95 % intervals of ``params``, or None. [-]"""
        ci = self.model.confidence_intervals()
        return None if ci is None else ci[1]

    @property
    def covariance_rank_deficient(self) -> bool:
        """True when the Jacobian at the optimum is rank deficient."""
        return False if self._covariance is None else bool(self._covariance()[1])

    @property
    def per_temperature(self) -> list:
        """``TemperatureError`` per temperature of the data."""
        return [] if self._per_temperature is None else self._per_temperature()

    @property
    def stability(self) -> StabilityCheck:
        """Pole check of the fitted model (see ``RationalModel.stability_check``)."""
        return self._stability()

    def summary(self) -> str:
        st = self.model.structure
        lines = [
            f"{self.method} fit, form={st.form}, zeros={st.n_zeros}, poles={st.n_poles}, "
            f"degree={st.degree}: {'converged' if self.converged else 'NOT CONVERGED'} "
            f"({self.status}, {self.iterations} iterations, {self.time_s:.3f} s)",
            f"weighting={self.weighting}, weighted RMS residual={self.weighted_rms:.4g}",
            f"stability: {'stable' if self.stability.stable else 'UNSTABLE'} "
            f"(max pole real part {self.stability.max_pole_real_part_rad_s:.4g} rad/s over "
            f"{self.stability.n_temperatures} temperature(s))",
        ]
        for e in self.per_temperature:
            t = "" if e.temperature_c is None else f"T={e.temperature_c:g} °C: "
            lines.append(f"  {t}relative RMS error {e.relative_rms_error:.4g}, fit {e.fit_percent:.2f} %")
        return "\n".join(lines)


def history_entry(stage: str, start: str, out: SolveOutcome) -> dict:
    return {"stage": stage, "start": start, "status": out.status, "converged": out.converged,
            "iterations": out.iterations, "cost": out.cost, "time_s": out.time_s,
            "objective_trace": out.objective_trace}


def best_outcome(outcomes, prefer: str | None = None, rel_tol: float = 0.02):
    """Lowest-cost converged outcome, unless an unconverged one is more than ``rel_tol``
    cheaper (then that one, flagged: a converged poor local minimum is not reported as the
    answer); with no converged outcome, the lowest-cost one (flagged).

    If ``prefer`` names a converged start whose cost is within ``rel_tol`` of the best, it
    wins (continuation across temperatures keeps section identities that way)."""
    def cost(o):
        return o[1].cost if np.isfinite(o[1].cost) else np.inf

    ok = [o for o in outcomes if o[1].converged]
    lowest = min(outcomes, key=cost)
    if not ok:
        return lowest
    best = min(ok, key=cost)
    if cost(lowest) < cost(best) * (1 - rel_tol):
        return lowest
    for o in ok:
        if o[0] == prefer and o[1].cost <= best[1].cost * (1 + rel_tol) + 1e-300:
            return o
    return best


#: iteration budget (× max_iter) of the one resumed solve, see :func:`resume_slowest`
RESUME_FACTOR = 6
#: smallest ``max_iter`` for which a solve that ran out of iterations is resumed; a smaller
#: limit is taken as a deliberate hard cap
RESUME_MIN_ITER = 50
#: a warm start (continuation across temperatures) keeps running while its cost is within
#: this fraction of a converged start's, so it is kept unless another start is clearly better
WARM_MARGIN = 0.02


def _outcome(lm: LevenbergMarquardt, i: int, time_s: float) -> SolveOutcome:
    def resume(n):
        t0 = time.perf_counter()
        lm.revive(i)
        lm.run(n, only=[i])
        return _outcome(lm, i, time.perf_counter() - t0)

    return SolveOutcome(lm.theta[i].copy(), float(lm.cost[i]), lm.status[i], bool(lm.converged[i]),
                        int(lm.iterations[i]), time_s, list(lm.traces[i]), resume)


def race_starts(evaluator, starts, max_iter: int, tol: float, lb, ub, prefer: str | None = "warm",
                trailing_ratio: float | None = None) -> list:
    """Levenberg–Marquardt from every start in lockstep (one batched evaluation per
    iteration serves them all); when one converges, the starts whose cost is higher are
    stopped (status ``Stopped_Early``), except the start named ``prefer`` (a warm start),
    which keeps running while within ``WARM_MARGIN`` of it; with ``trailing_ratio``, a start
    that trails another running one by more than that factor and is not catching up is
    stopped before any has converged (``LevenbergMarquardt``).  Returns ``[(name, SolveOutcome)]``
    (the time of the lockstep run is shared equally among the starts)."""
    names = [name for name, _ in starts]
    margins = [WARM_MARGIN if name == prefer else 0.0 for name in names]
    lm = LevenbergMarquardt(evaluator, np.array([th for _, th in starts]), lb, ub, tol, margins,
                            trailing_ratio)
    lm.run(max_iter)
    share = lm.time_s / len(names)
    return [(name, _outcome(lm, i, share)) for i, name in enumerate(names)]


def resume_slowest(outcomes: list, solve_long, history: list, stage: str, max_iter: int = 0) -> None:
    """If the lowest-cost outcome ran out of iterations, resume it once from where it stopped
    and append the new outcome: in place with ``RESUME_FACTOR × max_iter`` more iterations
    when the outcome can be continued (Levenberg–Marquardt), else with ``solve_long(theta)``
    (a solver with ``RESUME_FACTOR × max_iter`` iterations), unless ``max_iter`` is below
    ``RESUME_MIN_ITER`` (a hard cap).  Slow is not failed: poles and
    zeros far outside the data band are weakly determined and can need over a thousand
    iterations to settle; only one long resume is tried."""
    name, low = min(outcomes, key=lambda o: o[1].cost if np.isfinite(o[1].cost) else np.inf)
    if low.converged or low.status != "Maximum_Iterations_Exceeded" or max_iter < RESUME_MIN_ITER:
        return
    if low.resume is not None:
        out = low.resume(RESUME_FACTOR * max_iter)
    else:
        out = solve_long(low.theta)
    history.append(history_entry(f"{stage} (resumed, {RESUME_FACTOR}× max_iter)", name, out))
    outcomes.append((name, out))


def finish(structure, problem: Problem, evaluator, outcome: SolveOutcome, scaling: Scaling,
           data: FrequencyData, *, weighting_name: str, method: str, settings: dict,
           scale_covariance: bool, history: list, time_s: float, temperature_range,
           compute_covariance: bool = True, two_stage=None, per_temperature_models=None,
           raise_on_failure: bool = True, stability_grid: int = 501, temperatures=None,
           cost_is_mean_square: bool = False) -> FitResult:
    """The ``FitResult`` of ``outcome``.  The covariance (from the Jacobian at the optimum),
    the per-temperature errors and the stability check are deferred: computed, the same
    way, when first read.  ``temperatures``: ``data.temperatures()`` if already at hand.
    ``cost_is_mean_square``: ``outcome.cost`` is ½·mean(r²) of ``evaluator``'s residuals at
    ``outcome.theta`` (a Levenberg–Marquardt outcome), so the weighted RMS is √(2·cost)
    without evaluating the residuals again."""
    theta = outcome.theta
    cov = None
    at_bounds = []
    param_names = structure.param_names()
    if compute_covariance and evaluator is not None:
        def _cov(ev=evaluator, th=theta, scale=scale_covariance):
            r, jac = ev.residual(th, jacobian=True)
            return covariance(jac, r, scale)

        cov = _Deferred(_cov)
        lo, hi = structure.bounds(float(problem.w.min()), float(problem.w.max()))
        names = param_names
        at_bounds = [names[i] for i in np.flatnonzero((theta <= lo + 1e-6) | (theta >= hi - 1e-6))]
    if cost_is_mean_square and np.isfinite(outcome.cost):
        weighted_rms = float(np.sqrt(2.0 * outcome.cost))
    else:
        r = (evaluator or problem).residual(theta)
        weighted_rms = float(np.sqrt(np.mean(r ** 2)))
    temps = data.temperatures() if temperatures is None else temperatures
    fingerprint = data.fingerprint()
    info = {
        "method": method,
        "settings": settings,
        "weighting": weighting_name,
        "converged": outcome.converged,
        "status": outcome.status,
        "cost": outcome.cost if np.isfinite(outcome.cost) else None,
        "data_fingerprint": fingerprint,
        "n_lines": data.n,
        "temperatures_c": temps.tolist(),
    }
    model = RationalModel(structure, theta, scaling, temperature_range,
                          None if cov is None else (lambda c=cov: c()[0]), data.labels(), info)

    def _errors(model=model, ev=evaluator, th=theta, data=data):
        # the model's response on the data lines: H_model = R · H_data, R from the residual model
        return per_temperature_errors(model, data, response=None if ev is None else ev.ratio(th) * data.response)

    res = FitResult(
        model=model, converged=outcome.converged, status=outcome.status,
        iterations=outcome.iterations, cost=outcome.cost,
        weighted_rms=weighted_rms, weighting=weighting_name, method=method,
        param_names=param_names, params=theta.copy(), at_bounds=at_bounds,
        time_s=time_s, data_fingerprint=fingerprint,
        history=history, two_stage=two_stage, per_temperature_models=per_temperature_models,
        _covariance=cov, _per_temperature=_Deferred(_errors),
        _stability=_Deferred(lambda m=model, k=stability_grid: m.stability_check(k)),
    )
    if not outcome.converged and raise_on_failure:
        raise ConvergenceError(
            f"{method} fit did not converge: status {outcome.status!r} after "
            f"{outcome.iterations} iterations (raise_on_failure=False returns the flagged result)",
            res,
        )
    return res
