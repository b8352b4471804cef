"""Calibration of physical parameters to measured frequency responses, with honest uncertainty.

A subset of physical parameters (:class:`FreeParameter`: bounds, log or linear scale) is fitted to
one or many :class:`~physmodel.sweep.FrequencySweep` by weighted nonlinear least squares
(``scipy.optimize.least_squares``, trust-region reflective, in a scaled space), multi-start, and
returned as a :class:`CalibrationResult` with 95 % confidence intervals, the correlation matrix
and an identifiability report.

Residuals (discrepancy.md §1)
    For each line the relative error ln(G_data/G_model) is split into log-magnitude and phase:
    ``r = [ln|G_d/G_m| / σ_ln, wrap(∠G_d − ∠G_m) / σ_φ]`` with σ_ln = magnitude_std_db·ln10/20 and
    σ_φ = phase_std_deg·π/180 from the sweep.  The cost ½Σr² of a correct model averages
    F − nθ/2 (F lines, nθ fitted parameters) with spread ≈ sqrt(F − nθ/2).

    Fallback when the sweep carries no per-line standard deviations: every line gets
    σ_ln = σ_φ = :data:`FALLBACK_RELATIVE_STD` (1 % relative error), the result says
    ``noise_estimated=True``, and the covariance is rescaled by the residual variance
    2·cost/(2F − nθ) (the usual estimated-σ² least-squares covariance).

Scaled space
    A ``"log"`` parameter is fitted as z = log10(|x|) (both bounds of one sign; its sign is kept),
    a ``"linear"`` one as z = (x − lower)/(upper − lower).  Jacobians are forward finite
    differences in z, evaluated in ONE batched model call (all perturbed parameter sets at once).
    Confidence intervals are z ± 1.96·se(z) mapped back: asymmetric in physical units for log
    parameters.  ``n_evaluations`` counts full-data model evaluations (one per parameter set
    predicted, also inside batched calls); ``n_model_calls`` counts the batched calls.

Identifiability (see :func:`fit_parameters`)
    From the SVD of the weighted, scaled Jacobian at the optimum a parameter is *undetermined* if
    its 95 % interval spans more than :data:`MAX_CI_DECADES` decade (log) or more than its bounds
    (linear) — this includes near-null directions of the Jacobian, where se(z) is huge — or if it
    is pinned at a bound.  The reason names where its sensitivity peaks (from an optional
    :class:`SensitivityProbe` over a wide band) relative to the measured band, or the parameter it
    is confounded with.  Undetermined parameters are held at their start value (the base value in
    :func:`calibrate`) and the others refitted; they are reported without an interval.

Temperature-law parameters are named ``"laws.<quantity>.<attribute>"``, e.g.
``"laws.d.activation_energy"`` [J/mol] or ``"laws.E.slope"`` [1/K] (see :mod:`physmodel.temperature`);
``"omega_n"`` [rad/s] sets the first bending mode through the density.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares

from .errors import DataFormatError, IPMCError, ParameterError
from .params import IPMCParameters
from .sweep import QUANTITY_UNITS, UNITS, FrequencySweep, atomic_write, unit_scale

#: Relative standard deviation assumed per line (log-magnitude [Np] and phase [rad]) when a sweep
#: carries no per-line uncertainty; the covariance is then rescaled by the fitted residual variance.
FALLBACK_RELATIVE_STD = 0.01
#: Two-sided 95 % normal quantile.
Z95 = 1.959963984540054
#: A log parameter whose 95 % interval spans more decades than this is reported as undetermined.
MAX_CI_DECADES = 1.0
#: A parameter closer than this fraction of its scaled range to a bound is "pinned at the bound".
BOUND_TOL = 1e-3
#: Forward finite-difference step in the scaled space.
FD_STEP = 1e-6

Values = Mapping[str, float]


# =============================================================================== free parameters
@dataclass(frozen=True)
class FreeParameter:
    """A parameter to calibrate, with bounds in its physical unit.

    ``scale``: ``"log"`` (fitted as log10 |x|; both bounds must have one sign, not zero) or
    ``"linear"``; default ``"log"`` when ``lower > 0`` else ``"linear"``.  ``initial``: the start
    value (default: the base value in :func:`calibrate`, else the geometric/arithmetic mid-point).
    """

    name: str
    lower: float
    upper: float
    scale: str | None = None
    initial: float | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"a free parameter needs a non-empty name, got {self.name!r}")
        for k in ("lower", "upper"):
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise ParameterError(f"free parameter {self.name}: {k}={v!r} must be a finite number")
            object.__setattr__(self, k, float(v))
        if not self.lower < self.upper:
            raise ParameterError(f"free parameter {self.name}: bounds reversed or empty, lower={self.lower!r} "
                                 f"must be < upper={self.upper!r}")
        scale = self.scale or ("log" if self.lower > 0 else "linear")
        if scale not in ("log", "linear"):
            raise ParameterError(f"free parameter {self.name}: scale={self.scale!r}; expected 'log' or 'linear'")
        if scale == "log" and not (self.lower > 0 or self.upper < 0):
            raise ParameterError(f"free parameter {self.name}: a log scale needs bounds of one sign, not "
                                 f"crossing zero; got [{self.lower!r}, {self.upper!r}]")
        object.__setattr__(self, "scale", scale)
        if self.initial is not None:
            v = self.initial
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise ParameterError(f"free parameter {self.name}: initial={v!r} must be a finite number")
            if not self.lower <= v <= self.upper:
                raise ParameterError(f"free parameter {self.name}: initial={v!r} lies outside its bounds "
                                     f"[{self.lower!r}, {self.upper!r}]")
            object.__setattr__(self, "initial", float(v))

    # scaled coordinate ---------------------------------------------------------------------
    @property
    def sign(self) -> float:
        return -1.0 if self.upper < 0 else 1.0

    def to_z(self, x):
        x = np.asarray(x, dtype=float)
        if self.scale == "log":
            return np.log10(np.abs(x))
        return (x - self.lower) / (self.upper - self.lower)

    def from_z(self, z):
        z = np.asarray(z, dtype=float)
        if self.scale == "log":
            # clipped so that the interval of an undetermined parameter (huge se(z)) stays finite
            return self.sign * 10.0 ** np.clip(z, -300.0, 300.0)
        return self.lower + z * (self.upper - self.lower)

    @property
    def z_bounds(self) -> tuple[float, float]:
        a, b = float(self.to_z(self.lower)), float(self.to_z(self.upper))
        return (min(a, b), max(a, b))

    def midpoint(self) -> float:
        """Geometric (log) or arithmetic (linear) mid-point of the bounds."""
        lo, hi = self.z_bounds
        return float(self.from_z(0.5 * (lo + hi)))

    def with_initial(self, value: float) -> "FreeParameter":
        return replace(self, initial=float(value))


# =============================================================================== residuals
def noise_std(data: FrequencySweep) -> tuple[np.ndarray, np.ndarray, bool]:
    """Per-line σ_ln [Np] and σ_φ [rad] of a sweep, and whether they are the fallback (estimated)."""
    n = data.frequency_hz.size
    if data.magnitude_std_db is None:
        return np.full(n, FALLBACK_RELATIVE_STD), np.full(n, FALLBACK_RELATIVE_STD), True
    s_ln = data.magnitude_std_db * (math.log(10.0) / 20.0)
    s_ph = np.radians(data.phase_std_deg)
    bad = np.flatnonzero((s_ln <= 0) | (s_ph <= 0))
    if bad.size:
        raise DataFormatError(f"per-line standard deviations must be > 0 to weight a fit; line(s) "
                              f"{bad[:5].tolist()} have magnitude_std_db={data.magnitude_std_db[bad[:5]].tolist()}, "
                              f"phase_std_deg={data.phase_std_deg[bad[:5]].tolist()}")
    return s_ln, s_ph, False


def standardised_residuals(model_response, data: FrequencySweep, s_ln, s_ph) -> np.ndarray:
    """:func:`residuals` with given per-line σ_ln [Np] and σ_φ [rad] (see :func:`noise_std`);
    an error, never NaN, where the model response is zero or not finite."""
    G = np.asarray(model_response, dtype=complex)
    n = data.response.size
    if G.shape[-1] != n:
        raise IPMCError(f"model response has {G.shape[-1]} values per set for {n} data lines")
    bad = ~np.isfinite(G) | (G == 0)
    if np.any(bad):
        raise IPMCError(f"model response is zero or not finite at {int(bad.sum())} line(s) "
                        f"(first at frequency {data.frequency_hz[np.flatnonzero(bad.reshape(-1, n).any(0))[0]]:g} Hz)")
    lr = np.log(data.response / G)
    return np.concatenate([lr.real / s_ln, lr.imag / s_ph], axis=-1)


def residuals(model_response: np.ndarray, data: FrequencySweep) -> np.ndarray:
    """Standardised real residuals ``[ln|G_d/G_m|/σ_ln (N), wrap(∠G_d − ∠G_m)/σ_φ (N)]``.

    ``model_response``: complex (N,) in the sweep's units (or (n_sets, N) → (n_sets, 2N)).
    Without per-line standard deviations the fallback σ = :data:`FALLBACK_RELATIVE_STD` is used.
    """
    s_ln, s_ph, _ = noise_std(data)
    return standardised_residuals(model_response, data, s_ln, s_ph)


def weighted_cost(model_response, data: FrequencySweep) -> float:
    """½·Σ r² of :func:`residuals`; for a correct model its mean is ≈ F − nθ/2 (F lines)."""
    r = residuals(model_response, data)
    return float(0.5 * np.sum(r * r))


# =============================================================================== results
@dataclass(frozen=True)
class StartRecord:
    """One start of the multi-start search: where it began and where it ended."""

    index: int
    initial: dict
    final: dict
    cost: float
    nfev: int
    status: int
    message: str


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
    (one representative temperature).
    """

    frequency_hz: np.ndarray
    predict_many: Callable[[Sequence[Values]], np.ndarray]


@dataclass
class CalibrationResult:
    """Outcome of a calibration.  Physical units throughout; intervals are 95 %.

    ``values``: fitted (or held) value of every free parameter; ``stderr``: standard error
    (delta method for log parameters; NaN when held); ``ci_lower``/``ci_upper``: 95 % interval
    (NaN when held); ``correlation``: (n, n) in the order of ``names`` (NaN rows for held ones);
    ``cost`` = ½Σr², ``expected_cost`` = F − nθ/2, ``cost_std`` = sqrt(F − nθ/2);
    ``held``: undetermined parameters kept at their start value.
    """

    names: list
    values: dict
    parameters: IPMCParameters | None
    stderr: dict
    ci_lower: dict
    ci_upper: dict
    correlation: np.ndarray
    cost: float
    expected_cost: float
    cost_std: float
    n_lines: int
    n_evaluations: int
    n_model_calls: int
    converged: bool
    message: str
    starts: list
    identifiability: dict
    noise_estimated: bool
    noise_scale: float
    held: list
    free: list
    band_hz: tuple
    temperatures_c: list
    elapsed_s: float
    metadata: dict = field(default_factory=dict)

    @property
    def determined(self) -> list:
        return [n for n in self.names if n not in self.held]

    def summary(self) -> str:
        lines = [
            f"calibration: {'converged' if self.converged else 'NOT CONVERGED'} ({self.message})",
            f"  data: {self.n_lines} lines, {len(self.temperatures_c)} temperature(s), band "
            f"{self.band_hz[0]:.4g}-{self.band_hz[1]:.4g} Hz; noise "
            + ("estimated from the residuals (no per-line std in the data), scale "
               f"{self.noise_scale:.3g}" if self.noise_estimated else "from the sweep's per-line std"),
            f"  cost {self.cost:.4g} (expected {self.expected_cost:.4g} ± {self.cost_std:.3g}); "
            f"{len(self.starts)} start(s); {self.n_evaluations} model evaluations in {self.n_model_calls} calls; "
            f"{self.elapsed_s:.2f} s",
            f"  {'parameter':34s} {'value':>12s} {'95 % interval':>27s}  status",
        ]
        for n in self.names:
            ident = self.identifiability.get(n)
            if n in self.held:
                lines.append(f"  {n:34s} {self.values[n]:12.5g} {'(held)':>27s}  UNDETERMINED: {ident.reason}")
            else:
                ci = f"[{self.ci_lower[n]:.5g}, {self.ci_upper[n]:.5g}]"
                lines.append(f"  {n:34s} {self.values[n]:12.5g} {ci:>27s}  ok")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        def num(v):
            v = float(v)
            return v if math.isfinite(v) else None

        corr = [[num(c) for c in row] for row in np.asarray(self.correlation, dtype=float)]
        return {
            "format": "ipmc-calibration", "version": 1,
            "converged": bool(self.converged), "message": self.message,
            "parameters": [
                {"name": n, "value": num(self.values[n]), "stderr": num(self.stderr[n]),
                 "ci95_lower": num(self.ci_lower[n]), "ci95_upper": num(self.ci_upper[n]),
                 "held": n in self.held,
                 "identifiable": bool(self.identifiability[n].identifiable) if n in self.identifiability else None,
                 "reason": self.identifiability[n].reason if n in self.identifiability else "",
                 "sensitivity_peak_hz": (num(self.identifiability[n].sensitivity_peak_hz)
                                         if n in self.identifiability and self.identifiability[n].sensitivity_peak_hz is not None else None),
                 "bounds": [fp.lower, fp.upper], "scale": fp.scale}
                for n, fp in zip(self.names, self.free)
            ],
            "correlation": {"names": list(self.names), "matrix": corr},
            "cost": num(self.cost), "expected_cost": num(self.expected_cost), "cost_std": num(self.cost_std),
            "n_lines": int(self.n_lines), "n_evaluations": int(self.n_evaluations),
            "n_model_calls": int(self.n_model_calls),
            "noise_estimated": bool(self.noise_estimated), "noise_scale": num(self.noise_scale),
            "band_hz": [float(self.band_hz[0]), float(self.band_hz[1])],
            "temperatures_c": [float(t) for t in self.temperatures_c],
            "starts": [{"index": s.index, "initial": s.initial, "final": s.final, "cost": num(s.cost),
                        "nfev": s.nfev, "status": s.status, "message": s.message} for s in self.starts],
            "elapsed_s": float(self.elapsed_s),
            "metadata": {k: str(v) for k, v in self.metadata.items()},
        }

    def save(self, path) -> Path:
        """Atomic JSON: a parameter-set payload (readable by :func:`physmodel.load_parameter_set`)
        when ``parameters`` is known, plus the calibration record under ``"calibration"``."""
        from .parameter_sets import _FORMAT, _VERSION, _finite_json

        payload: dict = {}
        if self.parameters is not None:
            payload = {"format": _FORMAT, "version": _VERSION, "parameters": _finite_json(self.parameters.to_dict())}
        payload["calibration"] = self.to_dict()
        text = json.dumps(payload, indent=2, allow_nan=False)
        return atomic_write(Path(path), lambda fh: fh.write(text + "\n"))


# =============================================================================== the engine
class _Counter:
    def __init__(self):
        self.evaluations = 0
        self.calls = 0


def _as_batch(predict, predict_many, counter: _Counter, n_lines: int):
    """A function list-of-values -> (n_sets, N) complex, counting evaluations."""

    def many(values_list):
        counter.calls += 1 if predict_many is not None else len(values_list)
        counter.evaluations += len(values_list)
        if predict_many is not None:
            out = np.asarray(predict_many(values_list), dtype=complex)
        else:
            out = np.stack([np.asarray(predict(v), dtype=complex).reshape(-1) for v in values_list])
        if out.shape != (len(values_list), n_lines):
            raise IPMCError(f"the predictor returned shape {out.shape}; expected {(len(values_list), n_lines)} "
                            "(one complex value per data line and parameter set)")
        return out

    return many


def _lhs_starts(free: Sequence[FreeParameter], n: int, seed: int) -> np.ndarray:
    """``n`` Latin-hypercube points in the scaled boxes (n, n_free), seeded."""
    from scipy.stats import qmc

    if n <= 0:
        return np.empty((0, len(free)))
    u = qmc.LatinHypercube(d=len(free), seed=seed).random(n)
    lo = np.array([fp.z_bounds[0] for fp in free])
    hi = np.array([fp.z_bounds[1] for fp in free])
    return lo + u * (hi - lo)


@dataclass
class _Fit:
    z: np.ndarray
    cost: float
    J: np.ndarray
    r: np.ndarray
    nfev: int
    status: int
    message: str


def _solve(free, fixed: dict, z0, many, data, s_ln, s_ph, max_nfev, ftol, fd_step) -> _Fit:
    """least_squares in the scaled space of ``free`` (others fixed); one batched call per Jacobian."""
    lo = np.array([fp.z_bounds[0] for fp in free])
    hi = np.array([fp.z_bounds[1] for fp in free])

    def values_of(z):
        v = dict(fixed)
        for fp, zi in zip(free, z):
            v[fp.name] = float(fp.from_z(zi))
        return v

    cache: dict = {}

    def fun(z):
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            G = many([values_of(z)])[0]
            cache[key] = standardised_residuals(G, data, s_ln, s_ph)
        return cache[key]

    def jac(z):
        f0 = fun(z)
        steps = np.where(z + fd_step <= hi, fd_step, -fd_step)
        pts = []
        for i in range(z.size):
            zz = z.copy()
            zz[i] += steps[i]
            pts.append(values_of(zz))
        G = many(pts)
        R = standardised_residuals(G, data, s_ln, s_ph)
        return ((R - f0[None, :]) / steps[:, None]).T

    z0 = np.clip(np.asarray(z0, dtype=float), lo, hi)
    sol = least_squares(fun, z0, jac=jac, bounds=(lo, hi), method="trf", x_scale=1.0,
                        ftol=ftol, xtol=1e-10, gtol=1e-10, max_nfev=max_nfev)
    z = sol.x
    r = fun(z)
    J = jac(z)
    msg = sol.message.rstrip(".") if sol.status > 0 else (
        f"stopped after {sol.nfev} function evaluations (max_nfev={max_nfev}) before converging"
        if sol.status == 0 else sol.message)
    return _Fit(z=z, cost=float(0.5 * r @ r), J=J, r=r, nfev=int(sol.nfev), status=int(sol.status), message=msg)


def _covariance(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Newton covariance (JᵀJ)⁻¹ via the SVD; returns (cov, singular values)."""
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    tiny = s.max() * 1e-14 if s.size and s.max() > 0 else 1e-300
    inv = 1.0 / np.maximum(s, tiny) ** 2
    return (Vt.T * inv) @ Vt, s


def _sensitivity_peaks(free, values: dict, J: np.ndarray, data: FrequencySweep, probe: SensitivityProbe | None,
                       many_counter: _Counter, fd_step: float):
    """Per free parameter: (frequency of peak |∂lnG/∂z| [Hz], in-band max / overall max)."""
    n = data.frequency_hz.size
    out = {}
    # in-band sensitivity from the weighted Jacobian converted back to |∂ ln G/∂z| per line
    s_ln, s_ph, _ = noise_std(data)
    in_band = np.sqrt((J[:n] * s_ln[:, None]) ** 2 + (J[n:] * s_ph[:, None]) ** 2)   # (N, n_free)
    band_max = in_band.max(axis=0)
    if probe is None:
        for j, fp in enumerate(free):
            out[fp.name] = (float(data.frequency_hz[np.argmax(in_band[:, j])]), 1.0)
        return out
    f = np.asarray(probe.frequency_hz, dtype=float)
    pts = [dict(values)]
    for fp in free:
        v = dict(values)
        z = float(fp.to_z(values[fp.name]))
        step = fd_step * 100 if z + fd_step * 100 <= fp.z_bounds[1] else -fd_step * 100
        v[fp.name] = float(fp.from_z(z + step))
        pts.append((v, step))
    G = np.asarray(probe.predict_many([pts[0]] + [p[0] for p in pts[1:]]), dtype=complex)
    many_counter.calls += 1
    many_counter.evaluations += len(pts)
    base = np.log(G[0])
    fmin, fmax = data.frequency_hz.min(), data.frequency_hz.max()
    inside = (f >= fmin) & (f <= fmax)
    for j, fp in enumerate(free):
        sens = np.abs((np.log(G[j + 1]) - base) / pts[j + 1][1])
        k = int(np.argmax(sens))
        peak = float(sens[k])
        frac = float(sens[inside].max() / peak) if np.any(inside) and peak > 0 else float(band_max[j] > 0)
        out[fp.name] = (float(f[k]), frac)
    return out


def _identifiability(free, z, J, cov, values, data, probe, counter, fd_step):
    """Flags and reasons for every free parameter of one fit (no holding here)."""
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    corr = cov / np.outer(d, d)
    peaks = _sensitivity_peaks(free, values, J, data, probe, counter, fd_step)
    fmin, fmax = float(data.frequency_hz.min()), float(data.frequency_hz.max())
    report, badness = {}, {}
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
    return report, badness, se, corr


def _fmt_hz(f: float) -> str:
    if f >= 1e3:
        return f"{f / 1e3:.3g} kHz"
    return f"{f:.3g} Hz"


def fit_parameters(data: FrequencySweep, predict: Callable[[Values], np.ndarray] | None,
                   free: Sequence[FreeParameter], *, starts: int = 1, seed: int = 0,
                   predict_many: Callable[[Sequence[Values]], np.ndarray] | None = None,
                   fixed: Values | None = None, max_nfev: int | None = None, ftol: float = 1e-10,
                   identify: bool = True, hold_undetermined: bool = True,
                   probe: SensitivityProbe | None = None, fd_step: float = FD_STEP,
                   progress: Callable[[int], None] | None = None) -> CalibrationResult:
    """Fit ``free`` parameters of a generic predictor to ``data`` by weighted least squares.

    ``predict(values) -> (N,) complex`` at every line of ``data`` (same order and units);
    ``predict_many(list of values) -> (n_sets, N)`` is used when given (one call per Jacobian).
    ``fixed``: extra values passed to the predictor unchanged.  ``starts``: start 0 is each
    parameter's ``initial`` (else the mid-point); the others are seeded Latin-hypercube points in
    the scaled boxes; all are reported, the best is kept.  With ``identify`` undetermined parameters
    are flagged (module doc) and, with ``hold_undetermined``, held at their start-0 value while the
    others are refitted.  ``max_nfev``: residual evaluations per start (scipy's meaning).
    ``progress(1)`` is called after each start.  ``parameters`` of the result is None (see
    :func:`calibrate` for the physics wrapper).
    """
    t0 = time.perf_counter()
    if not isinstance(data, FrequencySweep):
        raise IPMCError(f"data must be a FrequencySweep, got {type(data).__name__}")
    free = [fp if isinstance(fp, FreeParameter) else None for fp in free]
    if not free or any(fp is None for fp in free):
        raise ParameterError("free must be a non-empty sequence of FreeParameter")
    names = [fp.name for fp in free]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(f"free parameter(s) {dup} given more than once")
    if predict is None and predict_many is None:
        raise IPMCError("give predict or predict_many")
    if int(starts) < 1:
        raise IPMCError(f"starts must be >= 1, got {starts}")
    if max_nfev is not None and int(max_nfev) < 1:
        raise IPMCError(f"max_nfev must be >= 1, got {max_nfev}")
    fixed = dict(fixed or {})
    s_ln, s_ph, estimated = noise_std(data)
    n_lines = data.frequency_hz.size
    if 2 * n_lines <= len(free):
        raise IPMCError(f"{n_lines} lines (2 residuals each) cannot determine {len(free)} parameters")
    counter = _Counter()
    many = _as_batch(predict, predict_many, counter, n_lines)

    x_init = [fp.initial if fp.initial is not None else fp.midpoint() for fp in free]
    z_init = np.array([fp.to_z(x) for fp, x in zip(free, x_init)], float)
    z_starts = np.vstack([z_init[None, :], _lhs_starts(free, int(starts) - 1, seed)])
    records, fits = [], []
    for i, z0 in enumerate(z_starts):
        fit = _solve(free, fixed, z0, many, data, s_ln, s_ph, max_nfev, ftol, fd_step)
        fits.append(fit)
        initial = dict(zip(names, x_init)) if i == 0 else {fp.name: float(fp.from_z(v)) for fp, v in zip(free, z0)}
        records.append(StartRecord(i, initial,
                                   {fp.name: float(fp.from_z(v)) for fp, v in zip(free, fit.z)},
                                   fit.cost, fit.nfev, fit.status, fit.message))
        if progress:
            progress(1)
    best = min(range(len(fits)), key=lambda k: fits[k].cost)
    fit = fits[best]
    converged = fit.status > 0
    message = f"best of {len(fits)} start(s) is start {best}: {fit.message}"

    # identifiability: flag, hold the worst, refit the rest; repeat
    active = list(range(len(free)))
    z_full = fit.z.copy()
    held: dict[str, Identifiability] = {}
    report: dict = {}
    while True:
        act = [free[k] for k in active]
        values = dict(fixed)
        values.update({fp.name: (x_init[k] if fp.name in held else float(fp.from_z(z_full[k])))
                       for k, fp in enumerate(free)})
        cov, _ = _covariance(fit.J)
        noise_scale = 1.0
        dof = 2 * n_lines - len(act)
        if estimated:
            noise_scale = math.sqrt(2.0 * fit.cost / dof) if dof > 0 else float("nan")
            cov = cov * noise_scale**2
        if not (identify and converged and act):
            report = {fp.name: Identifiability(True, "not assessed" if not identify else
                                               "not assessed (the fit did not converge)") for fp in act}
            se = np.sqrt(np.maximum(np.diag(cov), 0.0))
            d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
            corr = cov / np.outer(d, d)
            break
        report, badness, se, corr = _identifiability(act, fit.z, fit.J, cov, values, data, probe, counter, fd_step)
        if not badness or not hold_undetermined:
            break
        pinned = [n for n, b in badness.items() if b == np.inf]
        to_hold = pinned or [max(badness, key=badness.get)]
        for n in to_hold:
            held[n] = report[n]
        active = [k for k in active if free[k].name not in held]
        for k, fp in enumerate(free):
            if fp.name in held:
                z_full[k] = z_init[k]
        if not active:
            break
        fixed_now = dict(fixed)
        fixed_now.update({free[k].name: x_init[k] for k in range(len(free)) if free[k].name in held})
        fit = _solve([free[k] for k in active], fixed_now, z_full[active], many, data, s_ln, s_ph,
                     max_nfev, ftol, fd_step)
        z_full[active] = fit.z
        converged = fit.status > 0
        message += f"; refit without {', '.join(to_hold)}: {fit.message}"

    # assemble in the order of `free`
    n_act = len(active)
    values = {fp.name: (x_init[k] if fp.name in held else float(fp.from_z(z_full[k]))) for k, fp in enumerate(free)}
    stderr, lo_ci, hi_ci, ident = {}, {}, {}, {}
    C = np.full((len(free), len(free)), np.nan)
    pos = {k: i for i, k in enumerate(active)}
    for k, fp in enumerate(free):
        if fp.name in held:
            stderr[fp.name] = lo_ci[fp.name] = hi_ci[fp.name] = float("nan")
            ident[fp.name] = held[fp.name]
            continue
        i = pos[k]
        zk, sk = z_full[k], se[i]
        a, b = fp.from_z(zk - Z95 * sk), fp.from_z(zk + Z95 * sk)
        lo_ci[fp.name], hi_ci[fp.name] = float(min(a, b)), float(max(a, b))
        stderr[fp.name] = float(abs(values[fp.name]) * math.log(10) * sk if fp.scale == "log"
                                else sk * (fp.upper - fp.lower))
        ident[fp.name] = report[fp.name]
        for k2 in active:
            C[k, k2] = corr[i, pos[k2]]
    if not active:
        cost = float(0.5 * np.sum(standardised_residuals(many([dict(fixed, **values)])[0], data, s_ln, s_ph) ** 2))
    else:
        cost = fit.cost
    expected = n_lines - n_act / 2.0
    if held:
        message += f"; undetermined and held at their start value: {', '.join(held)}"
    return CalibrationResult(
        names=names, values=values, parameters=None, stderr=stderr, ci_lower=lo_ci, ci_upper=hi_ci,
        correlation=C, cost=cost, expected_cost=expected, cost_std=math.sqrt(max(expected, 0.0)),
        n_lines=n_lines, n_evaluations=counter.evaluations, n_model_calls=counter.calls,
        converged=bool(converged), message=message, starts=records, identifiability=ident,
        noise_estimated=estimated, noise_scale=float(noise_scale), held=list(held), free=list(free),
        band_hz=(float(data.frequency_hz.min()), float(data.frequency_hz.max())),
        temperatures_c=data.temperatures().tolist(), elapsed_s=time.perf_counter() - t0,
    )


# =============================================================================== physics wrapper
_NUMERIC_FIELDS = tuple(f.name for f in fields(IPMCParameters) if f.name not in ("laws", "name", "source"))


def _law_target(base: IPMCParameters, name: str):
    """(quantity, attribute, law) for a ``laws.<quantity>.<attribute>`` name, or a clear error."""
    parts = name.split(".")
    laws = base.laws
    qnames = [f.name for f in fields(laws)]
    if len(parts) != 3 or parts[1] not in qnames:
        raise ParameterError(f"unknown temperature-law parameter {name!r}; expected 'laws.<quantity>.<attribute>' "
                             f"with quantity in {qnames}")
    law = getattr(laws, parts[1])
    attrs = [f.name for f in fields(law) if f.name != "valid_c"]
    if parts[2] not in attrs:
        raise ParameterError(f"{name!r}: the law for {parts[1]} is {type(law).__name__}, whose parameters are "
                             f"{attrs or 'none'}")
    return parts[1], parts[2], law


def check_parameter_name(base: IPMCParameters, name: str) -> None:
    """Raise :class:`ParameterError` unless ``name`` is calibratable on ``base``."""
    if name.startswith("laws."):
        _law_target(base, name)
    elif name != "omega_n" and name not in _NUMERIC_FIELDS:
        raise ParameterError(f"unknown parameter {name!r}; expected one of {list(_NUMERIC_FIELDS) + ['omega_n']} "
                             "or 'laws.<quantity>.<attribute>'")


def base_value(base: IPMCParameters, name: str) -> float:
    """The value of a calibratable parameter in ``base`` (physical units)."""
    check_parameter_name(base, name)
    if name.startswith("laws."):
        q, attr, law = _law_target(base, name)
        return float(getattr(law, attr))
    if name == "omega_n":
        return float(base.omega_n)
    return float(getattr(base, name))


def apply_values(base: IPMCParameters, values: Values) -> IPMCParameters:
    """``base`` with parameters (fields, ``omega_n``, ``laws.<q>.<attr>``) replaced by ``values``."""
    plain, law_changes, wn = {}, {}, None
    for name, v in values.items():
        if name.startswith("laws."):
            q, attr, _ = _law_target(base, name)
            law_changes.setdefault(q, {})[attr] = float(v)
        elif name == "omega_n":
            wn = float(v)
        else:
            check_parameter_name(base, name)
            plain[name] = float(v)
    if law_changes:
        laws = base.laws.with_(**{q: replace(getattr(base.laws, q), **ch) for q, ch in law_changes.items()})
        plain["laws"] = laws
    p = replace(base, **plain) if plain else base
    return p.replace(omega_n=wn) if wn is not None else p


def default_free_parameter(base: IPMCParameters, name: str) -> FreeParameter:
    """Default bounds for a bare name (initial = base value):

    * positive fields and ``omega_n``: [base/10, 10·base], log (``xi`` capped at 2; ``omega_n`` ×/÷ 3);
    * signed couplings ``alpha0``/``a0``: the same decade either side, log of the magnitude, sign kept;
    * ``laws.*.activation_energy``: [0, 60] kJ/mol, linear; ``laws.*.slope``: [−0.05, 0.05] /K, linear;
      ``laws.*.alpha``: [−5e-3, 5e-3] /K, linear.
    A zero or infinite base value (e.g. ``Rp_specific = inf``) needs explicit bounds.
    """
    v = base_value(base, name)
    if name.startswith("laws."):
        attr = name.split(".")[2]
        defaults = {"activation_energy": (0.0, 60e3), "slope": (-0.05, 0.05), "alpha": (-5e-3, 5e-3)}
        if attr not in defaults:
            raise ParameterError(f"no default bounds for {name!r}; give them as FreeParameter(name, lower, upper)")
        lo, hi = defaults[attr]
        return FreeParameter(name, lo, hi, "linear", min(max(v, lo), hi))
    if not math.isfinite(v) or v == 0:
        raise ParameterError(f"{name} = {v!r} in the base set: no default bounds; give them explicitly "
                             f"(e.g. '{name}:LOWER:UPPER')")
    span = 3.0 if name == "omega_n" else 10.0
    lo, hi = sorted((v / span, v * span))
    if name == "xi":
        hi = min(hi, 2.0)
        lo = min(lo, hi / 10)
    return FreeParameter(name, lo, hi, "log", v)


@dataclass(frozen=True)
class SweepLayout:
    """How a model response maps onto the rows of a sweep: evaluate at ``temperatures_c`` ×
    ``frequencies_hz`` (unique, sorted), take ``[..., t_index, f_index]`` and multiply by ``factor``
    (SI response → the sweep's display units)."""

    quantity: str
    factor: float
    frequencies_hz: np.ndarray
    f_index: np.ndarray
    temperatures_c: np.ndarray
    t_index: np.ndarray


def sweep_layout(data: FrequencySweep, kind: str, quantity: str | None = None) -> SweepLayout:
    """Check that ``data`` can hold the ``kind`` model's ``quantity`` (default M / S) and lay it out."""
    if kind not in ("actuator", "sensor"):
        raise IPMCError(f"kind={kind!r}; expected 'actuator' or 'sensor'")
    q = quantity or ("M" if kind == "actuator" else "S")
    if (kind, q) not in QUANTITY_UNITS:
        raise IPMCError(f"{kind} quantity {q!r} cannot be compared with data; expected one of "
                        f"{[k[1] for k in QUANTITY_UNITS if k[0] == kind]}")
    _, unit_in, _, unit_out = QUANTITY_UNITS[(kind, q)]
    want_in, want_out = UNITS[unit_in][0], UNITS[unit_out][0]
    got_in, got_out = UNITS[data.input_unit][0], UNITS[data.output_unit][0]
    if (got_in, got_out) != (want_in, want_out):
        raise DataFormatError(f"the sweep is {data.output_name} [{data.output_unit}] per {data.input_name} "
                              f"[{data.input_unit}] ({got_out}/{got_in}); {kind} quantity {q} needs "
                              f"{want_out}/{want_in} (see physmodel.sweep.QUANTITY_UNITS {QUANTITY_UNITS[(kind, q)]})")
    factor = unit_scale(data.input_unit) / unit_scale(data.output_unit)   # SI response -> sweep units
    fu, inv_f = np.unique(data.frequency_hz, return_inverse=True)
    Tu, inv_T = np.unique(data.temperature_c, return_inverse=True)
    return SweepLayout(q, factor, fu, inv_f, Tu, inv_T)


def merge_sweeps(data: FrequencySweep | Sequence[FrequencySweep]) -> FrequencySweep:
    """One sweep from several (distinct temperatures), in the units of the first."""
    if isinstance(data, FrequencySweep):
        return data
    sweeps = list(data)
    if not sweeps or not all(isinstance(s, FrequencySweep) for s in sweeps):
        raise IPMCError("data must be a FrequencySweep or a non-empty sequence of them")
    first = sweeps[0]
    conv = [s.in_units(first.input_unit, first.output_unit) for s in sweeps]
    seen: set = set()
    for s in conv:
        common = seen & set(s.temperatures().tolist())
        if common:
            raise IPMCError(f"several sweeps hold lines at {sorted(common)} °C; merge them into one sweep first")
        seen |= set(s.temperatures().tolist())
    std = all(s.magnitude_std_db is not None for s in conv)
    if not std and any(s.magnitude_std_db is not None for s in conv):
        raise IPMCError("some sweeps carry per-line standard deviations and others do not; give all or none")
    cat = lambda k: np.concatenate([getattr(s, k) for s in conv])  # noqa: E731
    return FrequencySweep(cat("temperature_c"), cat("frequency_hz"), cat("response"),
                          cat("magnitude_std_db") if std else None, cat("phase_std_deg") if std else None,
                          first.input_name, first.input_unit, first.output_name, first.output_unit,
                          dict(first.metadata))


def physics_predictor(data: FrequencySweep, base: IPMCParameters, kind: str = "actuator",
                      quantity: str | None = None, kernel: str = "boundary_charge"):
    """``predict_many(list of values) -> (n_sets, N)`` in the sweep's units, plus a wide-band
    :class:`SensitivityProbe` at the median data temperature.  One model call per batch
    (sets × temperatures × union of frequencies)."""
    from .actuator import ActuatorModel
    from .sensor import SensorModel

    lay = sweep_layout(data, kind, quantity)
    q, factor, fu, inv_f, Tu, inv_T = (lay.quantity, lay.factor, lay.frequencies_hz, lay.f_index,
                                       lay.temperatures_c, lay.t_index)

    def model_of(values_list):
        plist = [apply_values(base, v) for v in values_list]
        return ActuatorModel(plist) if kind == "actuator" else SensorModel(plist, kernel=kernel)

    def predict_many(values_list):
        R = model_of(values_list).frequency_response(fu, Tu, quantities=(q,))[q]
        return R[:, inv_T, inv_f] * factor

    t_probe = float(Tu[np.argmin(np.abs(Tu - np.median(data.temperature_c)))])
    f_probe = np.logspace(math.log10(fu[0]) - 3, math.log10(fu[-1]) + 3, 121)

    def probe_many(values_list):
        return model_of(values_list).frequency_response(f_probe, [t_probe], quantities=(q,))[q][:, 0, :] * factor

    return predict_many, SensitivityProbe(f_probe, probe_many), q


def calibrate(data: FrequencySweep | Sequence[FrequencySweep], base: IPMCParameters,
              free: Sequence[FreeParameter | str], *, kind: str = "actuator", quantity: str | None = None,
              starts: int = 4, seed: int = 0, kernel: str = "boundary_charge", max_nfev: int | None = None,
              identify: bool = True, hold_undetermined: bool = True, name: str | None = None,
              progress: Callable[[int], None] | None = None, **kwargs) -> CalibrationResult:
    """Calibrate physical parameters of ``base`` to frequency-response data at one or many temperatures.

    ``free``: :class:`FreeParameter` records or bare names (default bounds: see
    :func:`default_free_parameter`); names are IPMCParameters fields, ``"omega_n"`` or
    ``"laws.<quantity>.<attribute>"`` (temperature-law parameters, fitted jointly across
    temperatures).  Start 0 is the base value (or ``initial``); ``starts − 1`` more are seeded
    Latin-hypercube points.  ``kind``/``quantity``: ``"actuator"`` (``"M"`` tip displacement per
    volt by default, also ``H``, ``Z``, ``I``) or ``"sensor"`` (``"S"``, ``"Z"``); the data's units must
    be of the matching kinds (mm/V, µA/mm, Ω, ...).  Returns a :class:`CalibrationResult` whose
    ``parameters`` is ``base`` with the determined values (held ones at their base value), named
    ``name`` (default ``"<base.name>_calibrated"``).
    """
    if not isinstance(base, IPMCParameters):
        raise ParameterError(f"base must be IPMCParameters, got {type(base).__name__}")
    data = merge_sweeps(data)
    fps = []
    for item in free:
        if isinstance(item, str):
            fps.append(default_free_parameter(base, item))
        elif isinstance(item, FreeParameter):
            check_parameter_name(base, item.name)
            if item.initial is None:
                v = base_value(base, item.name)
                if not item.lower <= v <= item.upper:
                    raise ParameterError(f"free parameter {item.name}: the base value {v!r} lies outside the "
                                         f"bounds [{item.lower!r}, {item.upper!r}]; give an initial value")
                item = item.with_initial(v)
            fps.append(item)
        else:
            raise ParameterError(f"free parameters must be names or FreeParameter, got {item!r}")
    predict_many, probe, q = physics_predictor(data, base, kind, quantity, kernel)
    res = fit_parameters(data, None, fps, starts=starts, seed=seed, predict_many=predict_many,
                         max_nfev=max_nfev, identify=identify, hold_undetermined=hold_undetermined,
                         probe=probe, progress=progress, **kwargs)
    label = name or f"{base.name}_calibrated"
    src = (f"calibrated by physmodel.calibration to {data.output_name}/{data.input_name} sweep "
           f"{data.fingerprint()[:12]} ({kind} {q}); free: {', '.join(res.names)}"
           + (f"; undetermined (held at base): {', '.join(res.held)}" if res.held else "")
           + f"; base: {base.name}")
    res.parameters = replace(apply_values(base, res.values), name=label, source=src)
    res.metadata.update({"kind": kind, "quantity": q, "kernel": kernel, "base": base.name,
                         "data_fingerprint": data.fingerprint(), "seed": seed})
    return res


def model_sweep(result: CalibrationResult, data: FrequencySweep, kind: str | None = None,
                quantity: str | None = None, kernel: str | None = None) -> FrequencySweep:
    """The calibrated model's response on the data's lines, as a sweep (for overlays)."""
    if result.parameters is None:
        raise IPMCError("the result has no physical parameter set (use calibrate(), not fit_parameters())")
    kind = kind or result.metadata.get("kind", "actuator")
    predict_many, _, _ = physics_predictor(data, result.parameters, kind,
                                           quantity or result.metadata.get("quantity"),
                                           kernel or result.metadata.get("kernel", "boundary_charge"))
    G = predict_many([{}])[0]
    return replace(data, response=G, magnitude_std_db=None, phase_std_deg=None,
                   metadata={"source": "calibrated model", "parameter_set": result.parameters.name})


__all__ = ["FreeParameter", "CalibrationResult", "StartRecord", "Identifiability", "SensitivityProbe",
           "residuals", "weighted_cost", "noise_std", "fit_parameters", "calibrate", "apply_values",
           "base_value", "check_parameter_name", "default_free_parameter", "merge_sweeps",
           "physics_predictor", "model_sweep", "FALLBACK_RELATIVE_STD", "MAX_CI_DECADES"]
