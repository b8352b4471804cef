"""The least-squares engine's array helpers (:mod:`physmodel.estimation.lsq`): rows of physical
parameter values built from scaled coordinates (:class:`ScaledRows`) and the predictor called on
many parameter sets at once, counted (:class:`ModelBatch`).  Physical units throughout.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import IPMCError


class ScaledRows:
    """Physical rows (n_sets, n_free) of parameter values: ``x_full`` [each parameter's SI unit]
    with the ``active`` columns of ``free`` at scaled coordinates ``Z`` (n_sets, n_active) [-];
    :meth:`FreeParameter.from_z` vectorised over sets and parameters."""

    def __init__(self, free, x_full: np.ndarray, active: Sequence[int]):
        act = [free[k] for k in active]
        self.x_full, self.active = np.asarray(x_full, dtype=float), np.asarray(active, dtype=int)
        self.log = np.array([fp.scale == "log" for fp in act])
        self.sign = np.array([fp.sign for fp in act])
        self.lower = np.array([fp.lower for fp in act])
        self.span = np.array([fp.upper - fp.lower for fp in act])

    def __call__(self, Z: np.ndarray) -> np.ndarray:
        X = np.repeat(self.x_full[None, :], len(Z), axis=0)
        # clipped as in FreeParameter.from_z (np.clip's values, without its Python layer), so that
        # the interval of an undetermined parameter stays finite
        E = np.power(10.0, np.minimum(np.maximum(Z, -300.0), 300.0))
        X[:, self.active] = np.where(self.log, np.multiply(self.sign, E, out=E), self.lower + Z * self.span)
        return X


class ModelBatch:
    """A predictor called on rows of physical values of ``free`` (n_sets, n_free) [SI] ->
    (n_sets, N) complex responses, through ``predict_array`` (one call, no per-set Python) or else
    ``predict_many``/``predict`` with one values dict per set (``fixed`` added); counts the
    parameter sets evaluated (``evaluations``) and the calls (``calls``)."""

    def __init__(self, free, fixed: dict, predict, predict_many, predict_array, probe, n_lines: int):
        self.names = [fp.name for fp in free]
        self.fixed, self.n_lines, self.probe_ = fixed, n_lines, probe
        self.predict, self.predict_many, self.predict_array = predict, predict_many, predict_array
        self.evaluations = 0
        self.calls = 0
        #: whether each row's prediction is the same whatever other rows share its call (two rows
        #: or more): ``predict_array.rows_independent`` (lets the engine group points freely)
        self.rows_independent = predict_array is not None and bool(getattr(predict_array, "rows_independent", False))
        #: per set of active columns, what the engine's Jacobians need that no point changes
        #: (:func:`physmodel.estimation.lsq._residuals_and_jacobians`); one residual model per batch
        self.layouts: dict = {}

    def jacobian_plan(self, active) -> dict:
        """The predictor's known Jacobian columns (``predict_array.jacobian_plan``: {k: ("scaled",
        j, c) | ("constant", dlnG)} over ``free``) re-indexed to the ``active`` columns."""
        plan = getattr(self.predict_array, "jacobian_plan", None) or {}
        pos = {int(k): i for i, k in enumerate(active)}
        return {pos[k]: (p if p[0] == "constant" else ("scaled", pos[p[1]], p[2])) for k, p in plan.items()
                if k in pos and (p[0] == "constant" or (p[1] in pos and p[1] not in plan))}

    def _dicts(self, X):
        # X.tolist() gives the same Python floats as float() of each element, in one call
        names, fixed = self.names, self.fixed
        if not fixed:
            return [dict(zip(names, row)) for row in np.asarray(X, dtype=float).tolist()]
        return [{**fixed, **dict(zip(names, row))} for row in np.asarray(X, dtype=float).tolist()]

    def __call__(self, X: np.ndarray) -> np.ndarray:
        n_sets = len(X)
        self.evaluations += n_sets
        self.calls += n_sets if self.predict_array is None and self.predict_many is None else 1
        if self.predict_array is not None:
            out = np.asarray(self.predict_array(X), dtype=complex)
        elif self.predict_many is not None:
            out = np.asarray(self.predict_many(self._dicts(X)), dtype=complex)
        else:
            out = np.stack([np.asarray(self.predict(v), dtype=complex).reshape(-1) for v in self._dicts(X)])
        if out.shape != (n_sets, self.n_lines):
            raise IPMCError(f"the predictor returned shape {out.shape}; expected {(n_sets, self.n_lines)} "
                            "(one complex value per data line and parameter set)")
        return out

    def probe(self, X: np.ndarray) -> np.ndarray:
        """The :class:`SensitivityProbe`'s responses (n_sets, n_f) at the rows of ``X``."""
        self.calls += 1
        self.evaluations += len(X)
        if self.probe_.predict_array is not None:
            return np.asarray(self.probe_.predict_array(X), dtype=complex)
        return np.asarray(self.probe_.predict_many(self._dicts(X)), dtype=complex)

