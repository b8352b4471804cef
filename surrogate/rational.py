"""Rational fit at one temperature: Levenberg–Marquardt on a stable-by-construction
parametrisation, several starts raced in lockstep."""

from __future__ import annotations

import time

import numpy as np

from physmodel.numerics import one_blas_thread

from . import _fit as F
from ._data import FrequencyData, to_data
from ._init import initial_candidates
from ._lsq import Evaluator
from ._structure import Structure

__all__ = ["RationalFit"]

_INITS = ("auto", "sk", "levy", "spread")


class RationalFit:
    """Fit H(s) = N(s)/D(s) with ``n_zeros`` zeros and ``n_poles`` poles to one frequency response.

    Parameters
    ----------
    n_zeros, n_poles : int
        Orders; ``n_zeros <= n_poles`` (proper models).
    stable : bool
        True: the denominator is a product of sections s̃² + e^u s̃ + e^v (and s̃ + e^w), so
        every pole is in the open left half plane for every parameter value.  False: free
        monic denominator coefficients (what ``invfreqs`` fits).
    weighting : {'auto', 'uncertainty', 'log', 'relative'}
        'uncertainty': log-magnitude and phase residuals divided by the per-line standard
        deviations; 'log': the same with unit weights (1 Np ~ 1 rad); 'relative':
        (H_model − H_data)/H_data.  'auto' = 'uncertainty' when both standard deviations are
        given, else 'log'.
    init : {'auto', 'sk', 'levy', 'spread'}
        Starting point(s): Levy's linear least squares, the best Sanathanan–Koerner iterate,
        poles log-spread over the band; 'auto' runs Levenberg–Marquardt from each in
        lockstep, stops the starts another has beaten and keeps the best.
    max_iter : int
        Iteration limit per start (a best start that runs out is resumed once with 6×
        more, see ``_fit.resume_slowest``).
    tol : float
        Convergence tolerance (relative cost decrease; see ``_lsq.LevenbergMarquardt``).
    omega_ref_rad_s, gain_ref : float, optional
        Frequency [rad/s] and gain scales (default: geometric means over the data).
    raise_on_failure : bool
        Raise ``ConvergenceError`` (carrying the flagged result) if the fit does not converge;
        with False the result has ``converged=False``.
    scale_covariance : bool
        Scale the Gauss–Newton covariance by the reduced χ².

    Attributes
    ----------
    model_ : RationalModel
    result_ : FitResult
    history_ : list of dict, one per start (and resumed solve).
    """

    def __init__(self, n_zeros: int, n_poles: int, *, stable: bool = True, weighting: str = "auto",
                 init: str = "auto", max_iter: int = 300, tol: float = 1e-10,
                 omega_ref_rad_s: float | None = None, gain_ref: float | None = None,
                 raise_on_failure: bool = True, scale_covariance: bool = True):
        self.structure = Structure("sections" if stable else "coefficients", n_zeros, n_poles, 0)
        self.n_zeros, self.n_poles = self.structure.n_zeros, self.structure.n_poles
        self.stable = bool(stable)
        self.weighting = F.check_weighting(weighting)
        if init not in _INITS:
            raise ValueError(f"init must be one of {_INITS}, got {init!r}")
        self.init = init
        self.max_iter = F.check_positive_int("max_iter", max_iter)
        self.tol = F.check_positive_float("tol", tol, allow_none=False)
        self.omega_ref_rad_s = F.check_positive_float("omega_ref_rad_s", omega_ref_rad_s)
        self.gain_ref = F.check_positive_float("gain_ref", gain_ref)
        self.raise_on_failure = bool(raise_on_failure)
        self.scale_covariance = bool(scale_covariance)

    def settings(self) -> dict:
        return {"estimator": "RationalFit", "n_zeros": self.n_zeros, "n_poles": self.n_poles,
                "stable": self.stable, "weighting": self.weighting, "init": self.init,
                "max_iter": self.max_iter, "tol": self.tol,
                "omega_ref_rad_s": self.omega_ref_rad_s, "gain_ref": self.gain_ref,
                "scale_covariance": self.scale_covariance}

    def fit(self, frequency_hz, temperature_c=None, response=None, magnitude_std_db=None,
            phase_std_deg=None):
        """Fit one temperature's data (``temperature_c`` scalar, constant array or None), or a
        ``FrequencySweep`` / ``FrequencyData`` passed alone.

        Units: ``frequency_hz`` [Hz], ``temperature_c`` [°C], ``response`` complex
        [output/input], ``magnitude_std_db`` [dB], ``phase_std_deg`` [deg].
        Returns a ``FitResult``; also sets ``model_``, ``result_`` and ``history_``.
        """
        data = F.as_data(frequency_hz, temperature_c, response, magnitude_std_db, phase_std_deg)
        return self.fit_data(data)

    @one_blas_thread
    def fit_data(self, data: FrequencyData, theta0=None, *, stage: str = "per-temperature"):
        """Fit a ``FrequencyData`` or a ``physmodel.data.sweep.FrequencySweep``.

        ``theta0`` (same layout, e.g. a neighbouring temperature's solution) is an extra
        start that is kept unless another start is more than 2 % better.
        """
        t_start = time.perf_counter()
        data = to_data(data)
        temps = data.temperatures()
        if temps.size > 1:
            raise ValueError(
                f"RationalFit fits one temperature but the data hold {temps.size}: "
                f"{temps.tolist()} °C; use ScheduledFit or select one temperature"
            )
        st = self.structure
        F.check_order_per_temperature(st, data, temps)
        scaling = F.make_scaling(data, self.omega_ref_rad_s, self.gain_ref,
                                 float(temps[0]) if temps.size else 0.0, 1.0)
        problem, wname = F.make_problem(st, data, scaling, self.weighting)
        starts = []
        if theta0 is not None:
            theta0 = np.asarray(theta0, float)
            if theta0.shape != (st.n_params,):
                raise ValueError(f"theta0 must have {st.n_params} entries, got shape {theta0.shape}")
            starts.append(("warm", theta0))
        evaluator = Evaluator(problem)

        def costs(structure, thetas):
            ev = evaluator if structure == st else evaluator.with_structure(structure)
            return ev.costs(thetas)

        cands = initial_candidates(st, problem.w, problem.h, costs, powers=evaluator.spow)
        if self.init == "auto":
            starts += cands
        else:
            chosen = [c for c in cands if (c[0].startswith("sk") if self.init == "sk" else c[0] == self.init)]
            starts += chosen[:1] or cands[:1]
        if not starts:
            raise ValueError("no finite initial guess could be formed from these data")
        lb, ub = st.bounds(float(problem.w.min()), float(problem.w.max()))
        outcomes = F.race_starts(evaluator, starts, self.max_iter, self.tol, lb, ub)
        history = [F.history_entry(stage, name, out) for name, out in outcomes]
        F.resume_slowest(outcomes, None, history, stage, self.max_iter)
        _, best = F.best_outcome(outcomes, prefer="warm")
        temp_range = None if not temps.size else (float(temps[0]), float(temps[0]))
        res = F.finish(st, problem, evaluator, best, scaling, data, weighting_name=wname,
                       method="rational", settings=self.settings(),
                       scale_covariance=self.scale_covariance, history=history,
                       time_s=time.perf_counter() - t_start, temperature_range=temp_range,
                       raise_on_failure=self.raise_on_failure, temperatures=temps,
                       cost_is_mean_square=True)
        self.model_, self.result_, self.history_ = res.model, res, history
        return res

