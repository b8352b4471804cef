"""Goodness of fit of a surrogate :class:`~surrogate._fit.FitResult`: does the rational model fit
its data, or did the optimiser merely stop?

Two tests, chosen by what the data declare:

* the data carry per-line standard deviations and the fit used ``weighting="uncertainty"``: the
  residuals are standardised (ln-magnitude/σ_ln, phase/σ_φ), so Σr² = 2·n_res·cost is χ² on
  n_res − n_params degrees of freedom; the model is adequate when P(χ² ≥ observed) ≥ ``alpha``;
* otherwise there is no noise scale to test against, and the relative RMS error
  sqrt(mean |H_m/H_d − 1|²) at each temperature is compared with ``max_relative_rms`` (20 %:
  a fit worse than that explains too little of the data to be called a model of it; random
  magnitudes/phases give > 60 %).

``ipmc fit`` exits 3 when the verdict is inadequate unless ``--accept-misfit`` is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: χ² tail probability below which the fit is inconsistent with the declared noise.
ALPHA = 1e-3
#: Largest relative RMS error at any temperature accepted when the data declare no noise.
MAX_RELATIVE_RMS = 0.2


@dataclass(frozen=True)
class Adequacy:
    """The verdict: ``adequate``; the ``test`` used ("chi2" or "relative_rms"); its ``statistic``
    (χ², or the worst relative RMS error [-]); ``dof`` and ``p_value`` (χ² only); ``threshold``;
    and a sentence ``reason``."""

    adequate: bool
    test: str
    statistic: float
    dof: int | None
    p_value: float | None
    threshold: float
    reason: str


def assess(result, *, alpha: float = ALPHA, max_relative_rms: float = MAX_RELATIVE_RMS) -> Adequacy:
    """The goodness-of-fit verdict of a surrogate FitResult (see the module docstring)."""
    n_lines = sum(e.n_lines for e in result.per_temperature)
    n_res, n_par = 2 * n_lines, int(np.size(result.params))
    if result.weighting == "uncertainty" and n_res > n_par and math.isfinite(result.cost):
        from scipy.stats import chi2

        x = 2.0 * n_res * float(result.cost)          # cost = ½·mean r²
        dof = n_res - n_par
        p = float(chi2.sf(x, dof))
        ok = p >= alpha
        return Adequacy(ok, "chi2", x, dof, p, alpha,
                        f"chi2 = {x:.4g} on {dof} degrees of freedom (expected {dof} ± {math.sqrt(2 * dof):.3g}), "
                        f"p = {p:.2g}: " + ("consistent with the declared noise" if ok else
                                            f"the model does not fit the data within the declared noise (p < {alpha:g})"))
    worst = max((e for e in result.per_temperature), key=lambda e: e.relative_rms_error)
    ok = bool(np.isfinite(worst.relative_rms_error) and worst.relative_rms_error <= max_relative_rms)
    at = "" if worst.temperature_c is None else f" at {worst.temperature_c:g} °C"
    return Adequacy(ok, "relative_rms", float(worst.relative_rms_error), None, None, max_relative_rms,
                    f"no declared noise: worst relative RMS error {worst.relative_rms_error:.3g}{at} (fit "
                    f"{worst.fit_percent:.1f} %); " + ("within" if ok else "above") +
                    f" {max_relative_rms:g}" + ("" if ok else ": the model does not fit the data"))


__all__ = ["Adequacy", "assess", "ALPHA", "MAX_RELATIVE_RMS"]
