"""Identifiability of fitted parameters and the cost of holding the undetermined ones
(:mod:`physmodel.estimation.lsq`).

Flags (:func:`flag_parameters`)
    From the weighted, scaled Jacobian at the optimum a parameter is *undetermined* if its 95 %
    interval spans more than :data:`MAX_CI_DECADES` decade (log) or more than its bounds
    (linear), if it is pinned within :data:`BOUND_TOL` of a bound, or if the data do not depend on
    it; the reason names where its sensitivity peaks (:func:`sensitivity_peaks`) or the parameter
    it is confounded with.

Holds (:class:`HoldRecord`, :func:`hold_cost_tolerance`)
    The engine holds undetermined parameters at their start values and refits the rest; a hold
    step is taken only when it raises the cost over the all-free fit by no more than the
    likelihood-ratio tolerance, else it is undone and the un-held fit kept.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import IPMCError
from .batching import ModelBatch
from .residuals import ZERO_REASON, ZERO_SENSITIVITY, GoodnessOfFit


@dataclass(frozen=True)
class Identifiability:
    """Whether the data determine one parameter, and why not.

    ``sensitivity_peak_hz``: frequency where |∂ ln G/∂z| is largest (over the probe band when a
    :class:`SensitivityProbe` was given, else over the data); ``in_band_fraction``: the largest
    in-band sensitivity over that peak (1 = the peak is inside the measured band).
    """

    identifiable: bool
    reason: str
    sensitivity_peak_hz: float | None = None
    in_band_fraction: float | None = None


@dataclass(frozen=True)
class SensitivityProbe:
    """A wide-band evaluation used to locate where each parameter acts.

    ``predict_many(list_of_value_dicts) -> (n_sets, n_f) complex`` at ``frequency_hz`` [Hz]
    (one representative temperature); ``predict_array(X) -> (n_sets, n_f)``, when given, takes
    the rows of physical values (n_sets, n_free) in the order of the free parameters instead.
    """

    frequency_hz: np.ndarray
    predict_many: Callable[[Sequence[Mapping[str, float]]], np.ndarray]
    predict_array: Callable[[np.ndarray], np.ndarray] | None = None


#: Two-sided 95 % normal quantile.
Z95 = 1.959963984540054
#: A log parameter whose 95 % interval spans more decades than this is reported as undetermined.
MAX_CI_DECADES = 1.0
#: A parameter closer than this fraction of its scaled range to a bound is "pinned at the bound".
BOUND_TOL = 1e-3


def sensitivity_peaks(free, active, x_full: np.ndarray, J: np.ndarray, res,
                       probe: SensitivityProbe | None, batch: ModelBatch, fd_step: float):
    """Where each active free parameter acts: {name: (frequency of peak |∂lnG/∂z| [Hz] (NaN
    without frequencies), in-band max / overall max [-])}, over the probe's band when ``probe`` is
    given, else over the data.

    Parameters
    ----------
    free, active : sequence of FreeParameter, sequence of int
        All free parameters and the indices of the fitted ones.
    x_full : ndarray
        Physical values of every free parameter at the fit. [each parameter's SI unit]
    J : ndarray
        Standardised Jacobian of the residuals with respect to the active scaled coordinates. [-]
    res : SweepResiduals or ObservationResiduals
        The residual model of the data.
    probe : SensitivityProbe or None
        Wide-band evaluation.
    batch : ModelBatch
        The predictor.
    fd_step : float
        Finite-difference step in the scaled coordinates (100 times it is used here). [-]
    """
    out = {}
    in_band = res.ln_sensitivity(J)        # |∂ ln G/∂z| per line from the weighted Jacobian (N, n_free)
    band_max = in_band.max(axis=0)
    if probe is None or res.frequency_hz is None:
        for j, k in enumerate(active):
            out[free[k].name] = (float("nan") if res.frequency_hz is None else
                                 float(res.frequency_hz[np.argmax(in_band[:, j])]), 1.0)
        return out
    f = np.asarray(probe.frequency_hz, dtype=float)
    X = np.repeat(x_full[None, :], len(active) + 1, axis=0)
    steps = []
    for j, k in enumerate(active):
        fp = free[k]
        z = float(fp.to_z(x_full[k]))
        step = fd_step * 100 if z + fd_step * 100 <= fp.z_bounds[1] else -fd_step * 100
        X[j + 1, k] = float(fp.from_z(z + step))
        steps.append(step)
    G = batch.probe(X)
    base = np.log(G[0])
    fmin, fmax = res.band_hz
    inside = (f >= fmin) & (f <= fmax)
    for j, k in enumerate(active):
        fp = free[k]
        sens = np.abs((np.log(G[j + 1]) - base) / steps[j])
        k = int(np.argmax(sens))
        peak = float(sens[k])
        frac = float(sens[inside].max() / peak) if np.any(inside) and peak > 0 else float(band_max[j] > 0)
        out[fp.name] = (float(f[k]), frac)
    return out


def flag_parameters(free_all, active, z, J, cov, x_full, res, probe, batch, fd_step):
    """Flags and reasons for every active free parameter of one fit (no holding here): a
    parameter is undetermined when its 95 % interval spans more than :data:`MAX_CI_DECADES`
    decade (log) or its bounds (linear), when it is pinned within :data:`BOUND_TOL` of a bound, or
    when the data do not depend on it.

    Parameters
    ----------
    free_all, active : sequence of FreeParameter, sequence of int
        All free parameters and the indices of the fitted ones.
    z : ndarray
        The fitted scaled coordinates of the active parameters. [-]
    J, cov : ndarray
        Standardised Jacobian and covariance of the scaled coordinates. [-]
    x_full : ndarray
        Physical values of every free parameter. [each parameter's SI unit]
    res, probe, batch, fd_step
        As :func:`sensitivity_peaks`.

    Returns
    -------
    report : dict
        {name: Identifiability}.
    badness : dict
        {name: how undetermined} (inf when pinned or insensitive) for the undetermined ones.
    se, corr : ndarray
        Standard errors and correlation of the scaled coordinates. [-]
    dead : list of str
        The parameters the data do not depend on.
    """
    free = [free_all[k] for k in active]
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    corr = cov / np.outer(d, d)
    peaks = sensitivity_peaks(free_all, active, x_full, J, res, probe, batch, fd_step)
    fmin, fmax = res.band_hz
    report, badness, dead = {}, {}, []
    for j, fp in enumerate(free):
        lo, hi = fp.z_bounds
        width = 2 * Z95 * se[j]
        if fp.scale == "log":
            ratio = width / MAX_CI_DECADES
            spread = f"its 95 % interval would span {width:.3g} decades"
        else:
            ratio = width / (hi - lo)
            spread = f"its 95 % interval would be {ratio:.3g} times as wide as its bounds"
        pinned = None
        if z[j] - lo <= BOUND_TOL * (hi - lo):
            pinned = "lower" if fp.scale == "linear" or fp.sign > 0 else "upper"
        elif hi - z[j] <= BOUND_TOL * (hi - lo):
            pinned = "upper" if fp.scale == "linear" or fp.sign > 0 else "lower"
        peak_hz, frac = peaks[fp.name]
        if np.abs(J[:, j]).max() * 0.1 * (hi - lo) <= ZERO_SENSITIVITY:
            report[fp.name] = Identifiability(False, ZERO_REASON, peak_hz, frac)
            badness[fp.name] = np.inf
            dead.append(fp.name)
            continue
        where = ""
        if frac < 0.5:
            side = "above" if peak_hz > fmax else "below" if peak_hz < fmin else "inside"
            where = (f"sensitivity peaks at {_fmt_hz(peak_hz)}, {side} the measured band "
                     f"{_fmt_hz(fmin)}–{_fmt_hz(fmax)} (in-band sensitivity {100 * frac:.2g} % of the peak)")
        others = [(abs(corr[j, k]), free[k].name) for k in range(len(free)) if k != j and np.isfinite(corr[j, k])]
        conf = max(others) if others else (0.0, "")
        if pinned is not None:
            reason = f"ended at its {pinned} bound ({getattr(fp, pinned):.4g}), so the data do not determine it inside its bounds"
            if where:
                reason += "; " + where
            if np.isfinite(ratio) and ratio > 1.0:
                reason += "; " + spread
            report[fp.name] = Identifiability(False, reason, peak_hz, frac)
            badness[fp.name] = np.inf
        elif not np.isfinite(ratio) or ratio > 1.0:
            parts = [spread]
            if where:
                parts.insert(0, where)
            if conf[0] > 0.95:
                parts.append(f"confounded with {conf[1]} (correlation {conf[0]:.3f})")
            report[fp.name] = Identifiability(False, "; ".join(parts), peak_hz, frac)
            badness[fp.name] = ratio if np.isfinite(ratio) else 1e300
        else:
            report[fp.name] = Identifiability(True, "determined by the data" + (f" ({where})" if where else ""),
                                              peak_hz, frac)
    return report, badness, se, corr, dead


def _fmt_hz(f: float) -> str:
    if f >= 1e3:
        return f"{f / 1e3:.3g} kHz"
    return f"{f:.3g} Hz"


#: Confidence level of the hold test (:func:`hold_cost_tolerance`).
HOLD_LEVEL = 0.95


def hold_cost_tolerance(k: int, free_fit: GoodnessOfFit, level: float = HOLD_LEVEL) -> tuple[float, str]:
    """The largest cost increase an identifiability hold may cause: holding ``k`` parameters at
    their start values is accepted when cost_held − cost_free stays within it.

    Holding k parameters is a restriction of the free fit by k dimensions.  If the start values
    are consistent with the data, 2·(cost_held − cost_free) is a likelihood-ratio statistic
    distributed as χ²(k) (Wilks), so the hold is accepted when it stays below the ``level``
    quantile of χ²(k): the start values lie inside the joint ``level`` likelihood-ratio confidence
    region of the free fit, i.e. the data do not reject them.  This is the χ² machinery of
    :func:`~physmodel.estimation.residuals.goodness_of_fit` applied to the difference of two costs rather than to one cost; the
    alternative "a few cost_std" would scale with sqrt(number of residuals) and allow a hold that
    the data reject by dozens of standard errors on a long sweep.

    When the χ² scale is not the declared noise — estimated noise (fallback σ) or a free fit that
    fails its goodness-of-fit test (the declared σ are too small for this model) — the difference
    is measured in units of the free fit's residual variance s² = χ²/dof (the Birge ratio
    squared, as ``physmodel.estimation.calibration.apply_misfit_policy`` widens intervals):
    the F test, Δcost ≤ ½·s²·k·F_level(k, dof).

    Parameters
    ----------
    k : int
        Number of parameters held (cumulatively, relative to the free fit), >= 1.
    free_fit : GoodnessOfFit
        The goodness of fit of the fit with every parameter free.
    level : float
        Confidence level of the test. [-]

    Returns
    -------
    tolerance : float
        The largest allowed increase of the cost ½Σr². [-]
    rule : str
        How it was obtained, for messages.
    """
    from scipy.stats import chi2 as chi2_dist
    from scipy.stats import f as f_dist

    k = int(k)
    if k < 1:
        raise IPMCError(f"a hold test needs k >= 1 held parameters, got {k}")
    declared = free_fit.p_value is not None
    s2 = free_fit.reduced_chi2
    if (declared and free_fit.adequate) or free_fit.dof <= 0 or not (math.isfinite(s2) and s2 > 0):
        q = float(chi2_dist.ppf(level, k))
        return 0.5 * q, (f"half the {level:g} quantile of chi2({k}), {q:.3g}: the likelihood-ratio test of the "
                         "held values against the free fit")
    if declared:
        s2 = max(s2, 1.0)
    q = float(k * f_dist.ppf(level, k, free_fit.dof))
    why = "estimated noise" if not declared else "the free fit does not fit within the declared noise"
    return 0.5 * s2 * q, (f"half of s2·k·F_{level:g}({k}, {free_fit.dof}) = {s2:.3g}·{q:.3g} ({why}: the cost "
                          "difference is scaled by the free fit's residual variance s2)")


@dataclass(frozen=True)
class HoldRecord:
    """What holding undetermined parameters at their start values cost the fit.

    One record per hold step of :func:`~physmodel.estimation.lsq.fit_parameters` (one step holds
    every parameter pinned at a bound at once, else the worst other one), cumulative: ``names``
    are all the parameters held after the step, ``cost_before`` is the best fit with every
    parameter free, ``cost_after`` the refit with ``names`` held.  The step is ``accepted`` when
    cost_after − cost_before <= ``threshold``
    (:func:`hold_cost_tolerance`); a refused step is undone and
    the un-held fit kept.

    Parameters
    ----------
    names : tuple of str
        The parameters held (cumulatively) in this step.
    added : tuple of str
        The ones this step added.
    cost_before, cost_after : float
        ½Σr² with every parameter free and with ``names`` held. [-]
    threshold : float
        The largest cost increase accepted. [-]
    accepted : bool
        Whether the hold was taken.
    reason : str
        The test and its outcome, in words.
    """

    names: tuple
    added: tuple
    cost_before: float
    cost_after: float
    threshold: float
    accepted: bool
    reason: str

    @property
    def increase(self) -> float:
        """cost_after − cost_before. [-]"""
        return self.cost_after - self.cost_before

    def line(self) -> str:
        """One sentence: what the hold cost and whether it was taken."""
        if self.accepted:
            return (f"held {', '.join(self.names)} at the start value: cost {self.cost_before:.5g} -> "
                    f"{self.cost_after:.5g} "
                    + (f"(+{self.increase:.3g}, within the +{self.threshold:.3g} allowed)" if self.within_test else
                       f"(+{self.increase:.3g}, ABOVE the +{self.threshold:.3g} allowed: held anyway, "
                       "hold_undetermined='always')"))
        return (f"hold of {', '.join(self.added)} REFUSED: holding at the start value would raise the cost "
                f"{self.cost_before:.5g} -> {self.cost_after:.5g} (+{self.increase:.3g}, above the "
                f"+{self.threshold:.3g} allowed); the un-held fit is kept and {', '.join(self.added)} reported "
                "as not determined")

    @property
    def within_test(self) -> bool:
        """The cost increase passes the test (``accepted`` without it: ``hold_undetermined="always"``)."""
        return self.increase <= self.threshold

    def to_dict(self) -> dict:
        """The record as JSON-ready data (non-finite numbers as None)."""
        num = lambda v: float(v) if math.isfinite(v) else None  # noqa: E731
        return {"names": list(self.names), "added": list(self.added), "cost_before": num(self.cost_before),
                "cost_after": num(self.cost_after), "increase": num(self.increase),
                "threshold": num(self.threshold), "accepted": bool(self.accepted),
                "within_test": bool(self.within_test), "reason": self.reason}


def hold_record(names: tuple, added: tuple, cost_before: float, cost_after: float, free_fit: GoodnessOfFit,
                always: bool = False) -> HoldRecord:
    """Test one hold step (:func:`hold_cost_tolerance` for ``len(names)`` held parameters) and
    record it.

    Parameters
    ----------
    names, added : tuple of str
        All parameters held after the step, and those the step adds.
    cost_before, cost_after : float
        ½Σr² with every parameter free and with ``names`` held. [-]
    free_fit : GoodnessOfFit
        The goodness of fit of the all-free fit.
    always : bool
        Take the hold even when the test fails (``hold_undetermined="always"``; the record says so).
    """
    tol, rule = hold_cost_tolerance(len(names), free_fit)
    rise = cost_after - cost_before
    ok = bool(rise <= tol)
    accepted = ok or bool(always)
    return HoldRecord(tuple(names), tuple(added), float(cost_before), float(cost_after), tol, accepted,
                      f"holding {', '.join(names)} at the start value " + ("raises" if accepted else "would raise")
                      + f" the cost from {cost_before:.6g} (all free) to {cost_after:.6g} (+{rise:.3g}); "
                      + f"allowed +{tol:.3g} ({rule}): "
                      + ("taken" if ok else "taken although the data reject the start value (hold_undetermined="
                         "'always')" if accepted else "refused, the data reject the start value"))


def refused_identifiability(st: Identifiability, rec: HoldRecord, at_bound: bool) -> Identifiability:
    """``st`` with the reason a refused hold (``rec``) left the parameter free and undetermined.

    Parameters
    ----------
    st : Identifiability
        The parameter's flag before the hold was tried.
    rec : HoldRecord
        The refused hold step.
    at_bound : bool
        Whether the parameter's fitted value is at a bound.
    """
    return Identifiability(False, st.reason + f"; {'at its bound, ' if at_bound else ''}not determined and NOT held: "
                           f"holding it at its start value would raise the cost by {rec.increase:.3g} (allowed "
                           f"{rec.threshold:.3g}), so its fitted value is kept and its interval is not a valid 95 % "
                           "interval", st.sensitivity_peak_hz, st.in_band_fraction)


def refused_names(holds: Sequence[HoldRecord], held: Sequence[str]) -> list:
    """The parameters the last step of ``holds`` tried to hold and was refused (not in ``held``).

    Parameters
    ----------
    holds : sequence of HoldRecord
        The hold steps of a fit, in order.
    held : sequence of str
        The parameters the fit holds.
    """
    last = holds[-1] if holds else None
    return [] if last is None or last.accepted else [n for n in last.added if n not in held]
