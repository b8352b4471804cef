"""Penalised bounds (soft plausible ranges) for the least-squares engine, without changing it.

:func:`~physmodel.estimation.lsq.fit_parameters` minimises ½Σr² over the standardised residuals of
any predictor.  A :class:`PenalisedProblem` appends one pseudo-line per penalised parameter to the
data — response 1, σ_ln = 1 Np, phase σ 1° — and makes the predictor return ``exp(−ρ_k)`` on
that line, so its residual is exactly ρ_k (phase residual 0) and the engine minimises

    ½ Σ r_data² + ½ Σ_k ρ_k²,   ρ_k = max(0, log10(lower/|x|), log10(|x|/upper)) / w

— a flat prior inside the plausible range [lower, upper] and a Gaussian wall of width
``w`` = :data:`WALL_DECADES` decade outside it (leaving the range by 0.1 decade costs 12.5, i.e. a
χ² of 25: the ranges are broad, the wall is steep).  Inside the range the penalty and its
gradient are exactly zero, so fits and the
linearised null statistics of a baseline inside its range are unchanged.  ``data_cost`` and
``penalty`` are reported apart in the result's ``metadata``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..data.sweep import FrequencySweep
from ..effects import get_effect
from ..errors import ParameterError
from ..parameter_paths import is_effect_parameter, resolve_path
from ..params import IPMCParameters
from ..plausible import PlausibleRange
from .calibration import default_free_parameter
from .lsq import fit_parameters
from .records import CalibrationResult, FreeParameter
from .residuals import noise_std, standardised_residuals

#: Width of the soft wall outside a plausible range [decades].
WALL_DECADES = 0.02
_SIGMA_LN_DB = 20.0 / math.log(10.0)            # σ_ln = 1 Np in dB


@dataclass(frozen=True)
class RangePenalty:
    """Soft wall on parameter ``name`` outside ``prange`` (width ``wall`` decades)."""

    name: str
    prange: PlausibleRange
    wall: float = WALL_DECADES

    def residual(self, value: float) -> float:
        d = self.prange.decades_outside(value)
        return (d / self.wall) if math.isfinite(d) else 1e6


class PenalisedProblem:
    """``data`` and ``predict_many`` with the pseudo-lines of ``penalties`` appended.

    ``fit(free, **kw)`` runs :func:`fit_parameters` on the augmented problem and returns its
    :class:`CalibrationResult` with ``metadata["data_cost"]``, ``metadata["penalty"]`` and the
    per-parameter residuals ``metadata["penalties"]``; ``cost`` is the penalised total and
    ``expected_cost`` that of the data lines only."""

    def __init__(self, data: FrequencySweep, predict_many: Callable, penalties: Sequence[RangePenalty] = ()):
        self.data, self.predict_many = data, predict_many
        self.penalties = list(penalties)
        self.n_lines = data.frequency_hz.size
        self.s_ln, self.s_ph, self.estimated = noise_std(data)
        k = len(self.penalties)
        if k == 0:
            self.data_aug, self.pm_aug = data, predict_many
            return
        db = np.concatenate([self.s_ln * _SIGMA_LN_DB, np.full(k, _SIGMA_LN_DB)])
        deg = np.concatenate([np.degrees(self.s_ph), np.ones(k)])
        # pseudo-lines after the last line, above its frequency (a sweep's frequencies increase per
        # temperature); the predictor never sees them (it answers for the data lines only)
        t_last, f_last = data.temperature_c[-1], data.frequency_hz[data.temperature_c == data.temperature_c[-1]].max()
        self.data_aug = replace(        # keeps the record's type (a stacked sweep of several quantities)
            data, temperature_c=np.concatenate([data.temperature_c, np.full(k, t_last)]),
            frequency_hz=np.concatenate([data.frequency_hz, f_last * (2.0 + np.arange(k))]),
            response=np.concatenate([data.response, np.ones(k, dtype=complex)]), magnitude_std_db=db,
            phase_std_deg=deg, metadata=dict(data.metadata or {}))

        def pm_aug(values_list):
            G = np.asarray(predict_many(values_list), dtype=complex)
            pen = np.array([[self._rho(pe, v) for pe in self.penalties] for v in values_list])
            return np.hstack([G, np.exp(-pen)])

        self.pm_aug = pm_aug

    @staticmethod
    def _rho(pe: RangePenalty, values: Mapping[str, float]) -> float:
        return pe.residual(values[pe.name]) if pe.name in values else 0.0

    def penalties_at(self, values: Mapping[str, float]) -> dict:
        return {pe.name: self._rho(pe, values) for pe in self.penalties}

    def data_cost(self, values: Mapping[str, float]) -> float:
        r = standardised_residuals(np.asarray(self.predict_many([values]), dtype=complex)[0], self.data,
                                   self.s_ln, self.s_ph)
        return float(0.5 * r @ r)

    def fit(self, free: Sequence[FreeParameter], **kw) -> CalibrationResult:
        res = fit_parameters(self.data_aug, None, free, predict_many=self.pm_aug, **kw)
        pens = self.penalties_at(res.values)
        penalty = 0.5 * sum(v * v for v in pens.values())
        res.metadata.update({"data_cost": float(res.cost - penalty), "penalty": float(penalty), "penalties": pens})
        res.expected_cost = self.n_lines - len(res.names) / 2.0
        res.n_lines = self.n_lines
        res.cost_std = math.sqrt(max(res.expected_cost, 0.0))
        res.band_hz = (float(self.data.frequency_hz.min()), float(self.data.frequency_hz.max()))
        return res


def penalties_for(free: Sequence[FreeParameter], ranges: Mapping[str, PlausibleRange],
                  wall: float = WALL_DECADES) -> list[RangePenalty]:
    """One :class:`RangePenalty` per free parameter that has a plausible range."""
    return [RangePenalty(fp.name, ranges[fp.name], wall) for fp in free if fp.name in ranges]


# =============================================================================== free parameters
def free_parameters_for(base: IPMCParameters, free, effects: dict) -> list:
    """The free parameters of a diagnosis as :class:`FreeParameter` records, each with an initial value.

    ``free``: names or records; a parameter of the set (a field, ``omega_n``, ``laws.<q>.<a>``) gets
    :func:`~physmodel.estimation.calibration.default_free_parameter`'s bounds, an effect's
    (``"effect.parameter"``) its library bounds and, as its initial value, its value in ``effects``
    ({effect: {parameter: value}}, the baseline effects); an initial value left out is the value in
    ``base`` or ``effects``, clipped to the bounds.  Each name of the set is resolved once
    (:func:`~physmodel.parameter_paths.resolve_path`).
    """
    out = []
    for item in free:
        path = None
        if isinstance(item, FreeParameter):
            fp = item
        elif isinstance(item, str):
            if is_effect_parameter(item):
                e, p = item.split(".", 1)
                if e not in effects:
                    raise ParameterError(f"free parameter {item!r} belongs to effect {e!r}, which is not among "
                                         f"the baseline effects {sorted(effects)}")
                par = get_effect(e).parameter(p)
                fp = FreeParameter(item, par.lower, par.upper, "linear", effects[e][p])
            else:
                path = resolve_path(base, item)
                fp = default_free_parameter(base, path)
        else:
            raise ParameterError(f"free parameters must be names or FreeParameter, got {item!r}")
        if fp.initial is None:
            if is_effect_parameter(fp.name):
                e, p = fp.name.split(".", 1)
                v = effects[e][p]
            else:
                v = (path or resolve_path(base, fp.name)).value
            fp = fp.with_initial(min(max(v, fp.lower), fp.upper))
        out.append(fp)
    return out


# =============================================================================== audits
#: A parameter within this fraction of its scaled range from a bound is "at" it ...
AT_BOUND = 1e-3
#: ... and within this fraction "near" it.
NEAR_BOUND = 0.02


def bound_audit(res: CalibrationResult, free: Sequence[FreeParameter], hard: Mapping[str, tuple] | None = None) -> list:
    """Free parameters of ``res`` at or near a bound: ``[{name, value, bound, side, status, hard}]``.

    ``hard``: ``{name: sides}`` bounds that are physical limits (e.g. a CPE exponent at 1), reported
    but never a reason to widen."""
    out = []
    for fp in free:
        v = res.values[fp.name]
        lo, hi = fp.z_bounds
        z = float(fp.to_z(v)) if (fp.scale == "linear" or v != 0) else lo
        frac_lo, frac_hi = (z - lo) / (hi - lo), (hi - z) / (hi - lo)
        for side, frac in (("lower", frac_lo), ("upper", frac_hi)):
            if frac <= NEAR_BOUND:
                bound = fp.lower if (side == "lower") == (fp.scale == "linear" or fp.sign > 0) else fp.upper
                out.append({"name": fp.name, "value": float(v), "bound": float(bound), "side": side,
                            "status": "at" if frac <= AT_BOUND else "near",
                            "hard": side in (hard or {}).get(fp.name, ())})
    return out


def plausible_audit(values: Mapping[str, float], ranges: Mapping[str, PlausibleRange]) -> list:
    """Values outside their plausible range: ``[{name, value, lower, upper, decades, source}]``."""
    out = []
    for k, v in values.items():
        if k in ranges and not ranges[k].contains(v):
            r = ranges[k]
            out.append({"name": k, "value": float(v), "lower": r.lower, "upper": r.upper, "unit": r.unit,
                        "decades": r.decades_outside(v), "source": r.source})
    return out


def multistart_spread(res: CalibrationResult, tol: float = 1.0) -> dict:
    """Spread of the multi-start search: the costs of all starts, how many reach the best cost
    within ``tol`` (½Δχ²), and each parameter's range over those starts."""
    costs = [float(st.cost) for st in res.starts]
    if not costs:
        return {"n_starts": 0}
    best = min(costs)
    near = [st for st in res.starts if st.cost <= best + tol]
    rng = {n: [float(min(st.final[n] for st in near)), float(max(st.final[n] for st in near))] for n in res.names}
    return {"n_starts": len(costs), "costs": costs, "n_at_best": len(near), "tolerance": tol, "ranges": rng}


def cost_warning(cost: float, n_lines: int, n_free: int, level: float = 1e-3) -> str:
    """A warning when the weighted cost is inconsistent with the declared noise ('' if not).

    2·cost ~ χ²(2F − nθ) for a correct model and correct σ; below the ``level`` quantile the
    declared σ is too large, above the 1 − ``level`` quantile it is too small or a misfit remains."""
    from scipy.stats import chi2

    dof = max(2 * n_lines - n_free, 1)
    ratio = 2 * cost / dof
    if 2 * cost < chi2.ppf(level, dof):
        return (f"too low: the weighted cost is {ratio:.3g}× its expectation ({2 * cost:.4g} vs χ² with {dof} "
                f"degrees of freedom); the declared noise σ is likely about {1 / math.sqrt(max(ratio, 1e-12)):.3g}× "
                "too large, which makes every test here too lenient")
    if 2 * cost > chi2.ppf(1 - level, dof):
        return (f"too high: the weighted cost is {ratio:.3g}× its expectation ({2 * cost:.4g} vs χ² with {dof} "
                f"degrees of freedom); either a misfit remains or the declared σ is about "
                f"{math.sqrt(ratio):.3g}× too small")
    return ""


__all__ = ["RangePenalty", "PenalisedProblem", "penalties_for", "free_parameters_for", "WALL_DECADES", "bound_audit",
           "plausible_audit", "multistart_spread", "cost_warning", "AT_BOUND", "NEAR_BOUND"]
