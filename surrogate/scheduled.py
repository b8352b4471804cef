"""Temperature-scheduled fits: the papers' two-stage method and the joint fit.

Two-stage (seed 000, seed 001): fit each temperature, then fit each coefficient / gain,
zero and pole entry with a polynomial in T.  Joint: one least-squares problem over all
temperatures whose unknowns are the polynomial coefficients themselves, started from the
two-stage answer (forms 'zpk' and 'sections': from the coefficient form's joint answer converted
to the form) and from a constant schedule and solved by Levenberg–Marquardt (the lower
converged cost wins, unless an unconverged solve is cheaper: then that one is returned,
flagged); CasADi/IPOPT re-solves with constraints where a bound or stability needs them (form
'coefficients': only a solve stable on the dense temperature grid can be the answer).
"""

from __future__ import annotations

import time

import numpy as np

from physmodel.numerics import one_blas_thread

from . import _fit as F
from ._convert import convert
from ._data import FrequencyData, to_data
from ._init import levy
from ._lsq import STATUS_STOPPED, Evaluator
from ._nlp import SolveOutcome, get_solver
from ._structure import FORMS, Structure
from .models import RationalModel, Scaling
from .rational import RationalFit

__all__ = ["ScheduledFit"]

_METHODS = ("joint", "two-stage")
_DENSE_CHECK = 501   # temperatures of the final stability check (FitResult.stability)
_MAX_REFINE = 4      # rounds of adding unstable temperatures to the Hurwitz constraint grid
#: forms 'zpk' and 'sections': a joint start whose cost stays above this multiple of the other
#: start's, without closing the gap, is stopped before either converges (see
#: ``LevenbergMarquardt.trailing_ratio``): on the seed 002 sample a coefficient-schedule start
#: caught in a poor basin (cost 10-240 after 10 iterations; the optimum: 0.5) otherwise ran the
#: whole 150-230 iteration race in lockstep, at about twice the cost per iteration of the winner
#: alone.  (The coefficient form's races end within ~10 iterations, and its stability handling
#: re-solves from every start: not used there.)
_TRAILING_RATIO = 2.0


class ScheduledFit:
    """Fit H(s, T) whose parameters are polynomials of degree ``degree`` in temperature.

    Parameters
    ----------
    form : {'coefficients', 'zpk', 'sections'}
        'coefficients': every numerator and monic-denominator coefficient is a polynomial
        in T (seed 000); if the unconstrained joint optimum has an unstable pole anywhere on
        a dense temperature grid, the fit is repeated with Liénard–Chipart constraints on
        ``stability_grid`` temperatures (``enforce_stability``), and re-checked on the dense
        grid (``result.stability``): the answer is stable there, whatever the solvers' exit
        status, or flagged not converged with status ``Unstable_Solution``.  'zpk': gain, zero
        sections (1 + β1 s̃ + β2 s̃², and 1 + β s̃) and log pole-section coefficients are
        polynomials in T (seed 001's gain/zeros/poles, in a form that survives real↔complex
        transitions and takes a zero through infinity as β2 or β through 0); stable at every
        temperature by construction.
        'sections': free numerator coefficients with the 'zpk' denominator.
    n_zeros, n_poles : int
        Orders (``n_zeros <= n_poles``).
    degree : int
        Polynomial degree in temperature (the papers: 3 for seed 000, 2 for seed 001).
    method : {'joint', 'two-stage'}
        'two-stage' returns the papers' baseline; 'joint' refines it with one NLP over all
        temperatures (the result also carries the two-stage model).
    weighting, max_iter, tol, raise_on_failure, scale_covariance
        As in ``RationalFit``.
    per_temperature : {'nlp', 'levy'}
        First stage of the two-stage method: our stable least-squares fit at each temperature
        ('nlp', default) or Levy's linear least squares ('levy', the papers' ``invfreqs``;
        unstable Levy poles are reflected when converting to the 'zpk' form).
    enforce_stability : bool
        Only for form='coefficients' (the other forms are stable by construction).
    stability_grid : int
        Number of temperatures on which the constraints are imposed at first; temperatures
        where the 501-point check still finds an unstable pole are added (up to 4 rounds).
    stability_margin : float
        Form 'coefficients' with constraints: every pole has Re s < −stability_margin·ω_ref
        at the constrained temperatures (so none crosses the axis between them). [-]
    omega_ref_rad_s, gain_ref, temperature_center_c, temperature_scale_c : float, optional
        Scales (defaults from the data: geometric means; mid-range and half-range). [rad/s],
        [output/input], [°C], [°C]

    Attributes
    ----------
    model_, result_, history_, two_stage_model_, per_temperature_models_
    """

    def __init__(self, form: str = "zpk", n_zeros: int = 3, n_poles: int = 3, degree: int = 2, *,
                 method: str = "joint", weighting: str = "auto", enforce_stability: bool = True,
                 stability_grid: int = 41, stability_margin: float = 1e-3, max_iter: int = 500, tol: float = 1e-10,
                 omega_ref_rad_s: float | None = None, gain_ref: float | None = None,
                 temperature_center_c: float | None = None, temperature_scale_c: float | None = None,
                 per_temperature: str = "nlp", raise_on_failure: bool = True,
                 scale_covariance: bool = True):
        if form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {form!r}")
        if method not in _METHODS:
            raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
        self.structure = Structure(form, n_zeros, n_poles, degree)
        self.form, self.method = form, method
        self.n_zeros, self.n_poles, self.degree = n_zeros, n_poles, self.structure.degree
        self.weighting = F.check_weighting(weighting)
        self.enforce_stability = bool(enforce_stability)
        self.stability_grid = F.check_positive_int("stability_grid", stability_grid, 2)
        self.stability_margin = F.check_positive_float("stability_margin", stability_margin,
                                                       allow_none=False)
        self.max_iter = F.check_positive_int("max_iter", max_iter)
        self.tol = F.check_positive_float("tol", tol, allow_none=False)
        self.omega_ref_rad_s = F.check_positive_float("omega_ref_rad_s", omega_ref_rad_s)
        self.gain_ref = F.check_positive_float("gain_ref", gain_ref)
        if temperature_center_c is not None and not np.isfinite(temperature_center_c):
            raise ValueError(f"temperature_center_c must be finite, got {temperature_center_c!r}")
        self.temperature_center_c = temperature_center_c
        self.temperature_scale_c = F.check_positive_float("temperature_scale_c", temperature_scale_c)
        if per_temperature not in ("nlp", "levy"):
            raise ValueError(f"per_temperature must be 'nlp' or 'levy', got {per_temperature!r}")
        self.per_temperature = per_temperature
        self.raise_on_failure = bool(raise_on_failure)
        self.scale_covariance = bool(scale_covariance)

    def settings(self) -> dict:
        return {"estimator": "ScheduledFit", "form": self.form, "n_zeros": self.n_zeros,
                "n_poles": self.n_poles, "degree": self.degree, "method": self.method,
                "weighting": self.weighting, "enforce_stability": self.enforce_stability,
                "stability_grid": self.stability_grid,
                "stability_margin": self.stability_margin, "max_iter": self.max_iter, "tol": self.tol,
                "omega_ref_rad_s": self.omega_ref_rad_s, "gain_ref": self.gain_ref,
                "temperature_center_c": self.temperature_center_c,
                "temperature_scale_c": self.temperature_scale_c,
                "per_temperature": self.per_temperature,
                "scale_covariance": self.scale_covariance}

    def fit(self, frequency_hz, temperature_c=None, response=None, magnitude_std_db=None,
            phase_std_deg=None):
        """Fit tidy data (one line per frequency and temperature), or a ``FrequencySweep`` /
        ``FrequencyData`` passed alone.

        Units: ``frequency_hz`` [Hz], ``temperature_c`` [°C] (N,), ``response`` complex
        [output/input], ``magnitude_std_db`` [dB], ``phase_std_deg`` [deg].
        Returns a ``FitResult``; also sets ``model_``, ``result_``, ``history_``,
        ``two_stage_model_`` and ``per_temperature_models_``.
        """
        data = F.as_data(frequency_hz, temperature_c, response, magnitude_std_db, phase_std_deg)
        return self.fit_data(data)

    # ------------------------------------------------------------------ stages
    def _per_temperature(self, data: FrequencyData, scaling, history):
        """Per-temperature fits in ascending T.

        'nlp': stable ``RationalFit`` fits, each warm-started from its neighbour (kept unless a fresh
        start is >2 % better, so sections are tracked continuously).  'levy': Levy's linear
        least squares (Octave ``invfreqs`` without iterations), the papers' first stage.
        Returns {T: (structure, params, converged)}.
        """
        out = {}
        if self.per_temperature == "levy":
            st0 = Structure("coefficients", self.n_zeros, self.n_poles, 0)
            for t in data.temperatures():
                d = data.at_temperature(t)
                num, den = levy(d.omega / scaling.omega_ref_rad_s, d.response / scaling.gain_ref,
                                self.n_zeros, self.n_poles)
                theta = np.concatenate([num, den[:-1]])
                ok = bool(np.all(np.isfinite(theta)))
                history.append({"stage": f"per-T {t:g} °C", "start": "levy", "status": "linear least squares",
                                "converged": ok, "iterations": 0, "cost": float("nan"), "time_s": 0.0,
                                "objective_trace": []})
                out[float(t)] = (st0, theta, ok)
            return out
        fitter = RationalFit(self.n_zeros, self.n_poles, stable=True, weighting=self.weighting,
                             max_iter=self.max_iter, tol=self.tol,
                             omega_ref_rad_s=scaling.omega_ref_rad_s, gain_ref=scaling.gain_ref,
                             raise_on_failure=False, scale_covariance=self.scale_covariance)
        prev = None
        for t in data.temperatures():
            res = fitter.fit_data(data.at_temperature(t), theta0=prev, stage=f"per-T {t:g} °C")
            history.extend(res.history)
            out[float(t)] = (res.model.structure, res.params, res.converged)
            prev = res.params
        return out

    def _two_stage_params(self, per_t: dict, scaling, structure: Structure | None = None) -> np.ndarray:
        """Polynomial least squares in τ of each slot of the per-temperature fits (in the form of
        ``structure``, default the fit's own)."""
        st = self.structure if structure is None else structure
        temps = np.array(sorted(per_t))
        tau = (temps - scaling.temperature_center_c) / scaling.temperature_scale_c
        rows, ref = [], None
        for t in temps:
            st0, theta, _ = per_t[t]
            row = theta if st0.form == st.form else convert(st0, theta, st.form, reference_theta=ref)
            rows.append(row)
            ref = row
        y = np.array(rows)  # (n_T, n_slots)
        coef = np.polynomial.polynomial.polyfit(tau, y, st.degree)  # (degree+1, n_slots)
        return np.asarray(coef, float).T.ravel()

    def _coefficient_schedule_start(self, data: FrequencyData, scaling, per_t: dict, history) -> np.ndarray | None:
        """A start for the 'zpk' and 'sections' joint fits: the joint fit of the coefficient form
        (unconstrained Levenberg–Marquardt from its two-stage answer, a few iterations), read at
        the data's temperatures, converted to this form and fitted with a polynomial in τ.

        The coefficient form's problem is nearly linear in its unknowns and converges in a few
        iterations; its schedule carries the far-out, weakly determined zeros smoothly across
        temperatures (seed 002 sample, 4/4 cubic on 0.1–9 Hz, with the former monic zero
        sections s̃² + c1 s̃ + c0: 1,200 joint iterations from the two-stage and constant starts,
        68 from this one).  A far zero passing through infinity (the coefficient form's leading
        numerator coefficient changes sign) is β2 or β passing through 0 in the 'zpk' form's
        zero sections, so the converted per-temperature values lie on a smooth curve; where
        this start still lands in a poorer basin the race stops it early (``_TRAILING_RATIO``)
        and the constant start wins.  None when that solve gives no finite start."""
        st_c = Structure("coefficients", self.n_zeros, self.n_poles, self.degree)
        problem_c, _ = F.make_problem(st_c, data, scaling, self.weighting)
        theta_c = self._two_stage_params(per_t, scaling, st_c)
        lb, ub = st_c.bounds()
        (_, out), = F.race_starts(Evaluator(problem_c), [("two-stage", theta_c)], self.max_iter, self.tol,
                                  lb, ub, prefer=None)
        history.append(F.history_entry("joint (coefficient form, for a start)", "two-stage", out))
        if not np.all(np.isfinite(out.theta)):
            return None
        st0 = Structure("coefficients", self.n_zeros, self.n_poles, 0)
        c, sc = scaling.temperature_center_c, scaling.temperature_scale_c
        per_c = {}
        for t in per_t:
            vals = st_c.slot_matrix(out.theta) @ (((t - c) / sc) ** np.arange(st_c.n_coef))
            per_c[t] = (st0, vals, True)
        with np.errstate(all="ignore"):
            try:
                start = self._two_stage_params(per_c, scaling)
            except (np.linalg.LinAlgError, ValueError):
                return None
        return start if np.all(np.isfinite(start)) else None

    def _joint(self, problem, scaling, t_range, per_t, theta2, history, data=None):
        """One least-squares problem over all temperatures from two starts (the two-stage
        answer — for the 'zpk' and 'sections' forms the coefficient form's joint answer in
        this form instead, :meth:`_coefficient_schedule_start` —; a constant schedule of the
        mid-range per-T fit).  Returns ``(evaluator, outcome)``.

        * Levenberg–Marquardt runs both starts in lockstep (``_fit.race_starts``); a start
          is stopped when the other has converged to a lower cost (a converged two-stage
          start can be a poor local minimum: sensor zpk 2/2, cost 112 vs 0.49); forms 'zpk'
          and 'sections': also before either has converged, when it trails the other by more
          than ``_TRAILING_RATIO`` and is not closing the gap;
        * if the lowest cost belongs to a solve that ran out of iterations (slow, not
          failed: far-out zeros are weakly determined), it is resumed once with
          ``RESUME_FACTOR × max_iter`` iterations (``_fit.resume_slowest``); if it still
          does not converge, the result is that solve, flagged (``_fit.best_outcome``);
        * a solution whose pole or zero sections leave ``Structure.slot_bounds`` at one of
          the ``stability_grid`` temperatures is re-solved by IPOPT with those bounds as
          constraints (``_nlp.Solver``);
        * form 'coefficients': a solution with a pole at or right of the axis anywhere on the
          501-point grid is re-solved by IPOPT with Liénard–Chipart constraints (margin
          ``stability_margin``) on ``stability_grid`` temperatures, refined where the dense
          check still fails, whatever the unconstrained solve's exit status (a start stopped
          on reaching another's unstable optimum, or out of iterations, is a candidate too);
          only a solution stable on the dense grid can be the answer, and if no solve ended
          stable the lowest-cost one is returned flagged (status ``Unstable_Solution: …``,
          not converged).
        """
        st = self.structure
        c, sc = scaling.temperature_center_c, scaling.temperature_scale_c
        taus = np.linspace((t_range[0] - c) / sc, (t_range[1] - c) / sc, self.stability_grid)
        dense_t = np.linspace(t_range[0], t_range[1], _DENSE_CHECK)
        hurwitz = st.form == "coefficients" and self.enforce_stability
        w_min, w_max = float(problem.w.min()), float(problem.w.max())

        def solver_for(grid, constrained, budget=1):
            return get_solver(st, problem.n_points, problem.kind, max_iter=budget * self.max_iter,
                              tol=self.tol, grid_taus=grid, hurwitz=constrained,
                              pole_margin=self.stability_margin if constrained else 0.0)

        def unstable(theta):
            """Per dense-grid temperature: a pole at or right of the axis (or no finite poles)."""
            with np.errstate(all="ignore"):
                try:
                    re = RationalModel(st, theta, scaling, t_range).max_pole_real_part(dense_t)
                except np.linalg.LinAlgError:          # non-finite coefficients
                    return np.ones(dense_t.size, bool)
            return ~(re < 0)

        def outside_slot_bounds(theta) -> bool:
            bounds = st.slot_bounds(w_min, w_max)
            if not bounds:
                return False
            vals = st.slot_matrix(theta) @ (taus[None, :] ** np.arange(st.n_coef)[:, None])
            for j, name in enumerate(st.slots):
                if name in bounds and (np.any(vals[j] < bounds[name][0]) or np.any(vals[j] > bounds[name][1])):
                    return True
            return False

        mid = min(per_t, key=lambda t: abs(t - c))
        st0, th0 = per_t[mid][:2]
        const = np.zeros((len(st.slots), st.n_coef))
        const[:, 0] = th0 if st0.form == st.form else convert(st0, th0, st.form)
        evaluator = Evaluator(problem)
        lb, ub = st.bounds()
        starts = {"two-stage": theta2, "constant": const.ravel()}
        if st.form != "coefficients" and data is not None:
            # the coefficient form's joint answer, in this form, replaces the two-stage start:
            # the per-temperature fits' far-out zeros change pairing from one temperature to the
            # next, so the polynomial through their sections starts far off (cost 10^3-10^4 of
            # the optimum's 0.5 on the seed 002 sample) and was never the winner there
            theta_c = self._coefficient_schedule_start(data, scaling, per_t, history)
            if theta_c is not None:
                del starts["two-stage"]
                starts["coefficient schedule"] = np.clip(theta_c, *st.bounds())
        outcomes = F.race_starts(evaluator, list(starts.items()), self.max_iter, self.tol, lb, ub,
                                 prefer=None,
                                 trailing_ratio=None if st.form == "coefficients" else _TRAILING_RATIO)
        history += [F.history_entry("joint", name, out) for name, out in outcomes]
        F.resume_slowest(outcomes, None, history, "joint", self.max_iter)
        final, setups = [], {}
        # constrained re-solves, cheapest outcome first; an outcome whose (unconstrained) cost
        # is already above a settled one cannot win and keeps its unconstrained answer; a
        # start stopped in favour of one whose constrained answer turned out costlier is
        # finished now and treated the same way
        settled = np.inf
        for name, out in sorted(outcomes, key=lambda o: o[1].cost if np.isfinite(o[1].cost) else np.inf):
            if not out.cost < settled:
                final.append((name, out))
                continue
            if out.status == STATUS_STOPPED:
                out = out.resume(self.max_iter)
                history.append(F.history_entry("joint (continued)", name, out))
                if not out.cost < settled:
                    final.append((name, out))
                    continue
            if outside_slot_bounds(out.theta):
                setups[name] = (taus, False)
                out = solver_for(taus, False).solve(problem, out.theta)
                history.append(F.history_entry(
                    f"joint (section bounds at {taus.size} temperatures)", name, out))
            # whatever the solver's exit status: an unconverged answer (out of iterations, or
            # stopped on reaching the unstable optimum of another start) is a candidate too
            if hurwitz and unstable(out.theta).any():
                start = starts[name]          # a stable start is the better way in
                grid, th = taus, (start if not unstable(start).any() else out.theta)
                for _ in range(_MAX_REFINE + 1):
                    setups[name] = (grid, True)
                    out = solver_for(grid, True).solve(problem, th)
                    history.append(F.history_entry(
                        f"joint (Hurwitz constraints at {grid.size} temperatures)", name, out))
                    bad = unstable(out.theta)
                    if not out.converged or not bad.any():
                        break
                    grid, th = np.union1d(grid, (dense_t[bad] - c) / sc), out.theta
            final.append((name, out))
            if out.converged and not (hurwitz and unstable(out.theta).any()):
                settled = min(settled, out.cost)
        if hurwitz:
            # only a model stable on the dense grid can be the answer, whatever its cost or exit
            # status (an unstable answer is not returned flagged: the form promises stability)
            stable = [o for o in final if not unstable(o[1].theta).any()]
            if not stable:
                return evaluator, self._no_stable_answer(final, dense_t, unstable)
            final = stable
        # a constrained (IPOPT) solve that ran out of iterations is resumed like the others
        low = min(final, key=lambda o: o[1].cost if np.isfinite(o[1].cost) else np.inf)[0]
        if low in setups:
            n_before = len(final)
            F.resume_slowest(final, lambda th: solver_for(*setups[low], F.RESUME_FACTOR).solve(problem, th),
                             history, "joint", self.max_iter)
            if hurwitz and len(final) > n_before and unstable(final[-1][1].theta).any():
                final.pop()                            # the resumed solve left the stable set
        return evaluator, F.best_outcome(final)[1]

    @staticmethod
    def _no_stable_answer(final, dense_t, unstable) -> SolveOutcome:
        """The lowest-cost outcome, flagged as not converged: no solve (constrained or not)
        ended with every pole left of the axis on the dense temperature grid."""
        _, out = min(final, key=lambda o: o[1].cost if np.isfinite(o[1].cost) else np.inf)
        bad = dense_t[unstable(out.theta)]
        return SolveOutcome(out.theta, out.cost,
                            f"Unstable_Solution: no stable solve; the best ({out.status}) has a pole at or "
                            f"right of the axis at {bad.size} of {dense_t.size} temperatures "
                            f"({bad.min():g}-{bad.max():g} °C)",
                            False, out.iterations, out.time_s, out.objective_trace)

    @one_blas_thread
    def fit_data(self, data: FrequencyData):
        """Fit a ``FrequencyData`` or a ``physmodel.data.sweep.FrequencySweep``."""
        t_start = time.perf_counter()
        data = to_data(data)
        st = self.structure
        if data.temperature_c is None:
            raise ValueError("ScheduledFit needs temperature_c for every line")
        temps = data.temperatures()
        if temps.size < st.degree + 1 or temps.size < 2:
            raise ValueError(
                f"degree={st.degree} needs at least {max(st.degree + 1, 2)} distinct temperatures, "
                f"got {temps.size}: {temps.tolist()}"
            )
        F.check_order_per_temperature(st, data)
        scaling = F.make_scaling(data, self.omega_ref_rad_s, self.gain_ref,
                                 self.temperature_center_c, self.temperature_scale_c)
        t_range = (float(temps.min()), float(temps.max()))
        history = []
        per_t = self._per_temperature(data, scaling, history)
        per_t_models = {t: RationalModel(s0, th, Scaling(scaling.omega_ref_rad_s, scaling.gain_ref, t, 1.0),
                                         (t, t), labels=data.labels())
                        for t, (s0, th, _) in per_t.items()}
        theta2 = self._two_stage_params(per_t, scaling)
        problem, wname = F.make_problem(st, data, scaling, self.weighting)
        settings = self.settings()
        ok2 = all(c for _, _, c in per_t.values())
        two_out = SolveOutcome(theta2, problem.cost(theta2),
                               "two-stage" if ok2 else "two-stage: a per-temperature fit did not converge",
                               ok2, 0, 0.0)
        two_res = F.finish(st, problem, None, two_out, scaling, data, weighting_name=wname,
                           method="two-stage", settings={**settings, "method": "two-stage"},
                           scale_covariance=self.scale_covariance, history=list(history),
                           time_s=time.perf_counter() - t_start, temperature_range=t_range,
                           compute_covariance=False, per_temperature_models=per_t_models,
                           raise_on_failure=self.raise_on_failure and self.method == "two-stage")
        if self.method == "two-stage":
            res = two_res
        else:
            evaluator, best = self._joint(problem, scaling, t_range, per_t, theta2, history, data)
            res = F.finish(st, problem, evaluator, best, scaling, data, weighting_name=wname,
                           method="joint", settings=settings,
                           scale_covariance=self.scale_covariance, history=history,
                           time_s=time.perf_counter() - t_start, temperature_range=t_range,
                           two_stage=two_res.model, per_temperature_models=per_t_models,
                           raise_on_failure=self.raise_on_failure)
        self.model_, self.result_, self.history_ = res.model, res, res.history
        self.two_stage_model_ = two_res.model
        self.per_temperature_models_ = per_t_models
        return res
