"""Scalar observations: what :func:`~physmodel.estimation.lsq.fit_parameters` takes besides a
frequency sweep (e.g. a printed a0(T), one value per temperature), fitted on a log scale."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError


@dataclass(frozen=True)
class ScalarObservations:
    """Scalar observations fitted on a log scale: what :func:`~physmodel.estimation.lsq.fit_parameters`
    takes besides a frequency sweep (e.g. a printed a0(T), one value per temperature).

    The residual of observation i is ln|y_model,i / y_i| / σ_ln,i (a sign flip of the model is a
    misfit of the magnitude only); for a correct model the cost ½Σr² averages (N − nθ)/2.

    Parameters
    ----------
    values : array_like
        The observed values y, finite and nonzero. [their own unit, the predictor's]
    sigma_ln : array_like
        Standard deviation of ln y per observation, > 0. [-]
    labels : sequence of str
        One name per observation (e.g. ``"a0(23 °C)"``), for messages.
    temperatures_c : array_like or None
        The temperature of each observation, when it has one. [°C]
    source : str
        Where the numbers come from.
    """

    values: np.ndarray
    sigma_ln: np.ndarray
    labels: tuple = ()
    temperatures_c: np.ndarray | None = None
    source: str = ""

    def __post_init__(self):
        y = np.atleast_1d(np.asarray(self.values, dtype=float))
        s = np.atleast_1d(np.asarray(self.sigma_ln, dtype=float))
        labels = tuple(str(x) for x in self.labels) or tuple(f"y[{i}]" for i in range(y.size))
        if y.ndim != 1 or y.size == 0:
            raise ParameterError(f"ScalarObservations.values must be a non-empty 1-D array, got shape {y.shape}")
        if s.shape != y.shape or len(labels) != y.size:
            raise ParameterError(f"ScalarObservations: {y.size} values need as many sigma_ln and labels, got "
                                 f"{s.size} sigma_ln and {len(labels)} labels")
        bad = [labels[i] for i in np.flatnonzero(~np.isfinite(y) | (y == 0))]
        if bad:
            raise ParameterError(f"ScalarObservations.values must be finite and nonzero; not so at {bad[:5]}")
        bad = [labels[i] for i in np.flatnonzero(~(np.isfinite(s) & (s > 0)))]
        if bad:
            raise ParameterError(f"ScalarObservations.sigma_ln must be finite and > 0; not so at {bad[:5]}")
        T = None if self.temperatures_c is None else np.atleast_1d(np.asarray(self.temperatures_c, dtype=float))
        if T is not None and T.shape != y.shape:
            raise ParameterError(f"ScalarObservations.temperatures_c: {T.size} values for {y.size} observations")
        object.__setattr__(self, "values", y)
        object.__setattr__(self, "sigma_ln", s)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "temperatures_c", T)


