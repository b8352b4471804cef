"""Calibration of physical parameters to measured frequency responses, with honest uncertainty.

A subset of physical parameters (:class:`FreeParameter`: bounds, log or linear scale) is fitted to
one or many :class:`~physmodel.data.sweep.FrequencySweep` by weighted nonlinear least squares
(``scipy.optimize.least_squares``, trust-region reflective, in a scaled space), multi-start, and
returned as a :class:`CalibrationResult` with 95 % confidence intervals, the correlation matrix
and an identifiability report.

Residuals (discrepancy.md §1; :class:`~physmodel.estimation.residuals.SweepResiduals`)
    For each line the relative error ln(G_data/G_model) is split into log-magnitude and phase:
    ``r = [ln|G_d/G_m| / σ_ln, wrap(∠G_d − ∠G_m) / σ_φ]`` with σ_ln = magnitude_std_db·ln10/20 and
    σ_φ = phase_std_deg·π/180 from the sweep.  The cost ½Σr² of a correct model averages
    F − nθ/2 (F lines, nθ fitted parameters) with spread ≈ sqrt(F − nθ/2).

    Fallback when the sweep carries no per-line standard deviations: every line gets
    σ_ln = σ_φ = :data:`FALLBACK_RELATIVE_STD` (1 % relative error), the result says
    ``noise_estimated=True``, and the covariance is rescaled by the residual variance
    2·cost/(2F − nθ) (the usual estimated-σ² least-squares covariance).  Scalar observations
    (:class:`ScalarObservations`, e.g. a0(T)) give one residual each, ln|y_model/y|/σ_ln.

Scaled space
    A ``"log"`` parameter is fitted as z = log10(|x|) (both bounds of one sign; its sign is kept),
    a ``"linear"`` one as z = (x − lower)/(upper − lower).  Jacobians are forward finite
    differences in z (step :data:`FD_STEP`), evaluated with the residuals in ONE batched model call
    (the point and all perturbed parameter sets at once; :func:`residual_jacobian` gives them).
    Parameter sets travel as arrays of physical values (``predict_array``) when the predictor
    takes them — :func:`~physmodel.estimation.calibration.calibrate` builds their states as arrays —
    else as one values dict per set.  Confidence intervals are z ± 1.96·se(z) mapped back:
    asymmetric in physical units for log parameters.  ``n_evaluations`` counts full-data model
    evaluations (one per parameter set predicted, also inside batched calls); ``n_model_calls``
    counts the batched calls.

Search and stopping (see ``_search``)
    Gauss–Newton steps while they lower the cost inside the bounds; a later start then takes up to
    :data:`~physmodel.estimation.lm_steps.LM_STEPS` Levenberg–Marquardt steps clipped to the bounds
    (:func:`~physmodel.estimation.lm_steps.damped_steps`: it
    usually reaches an earlier optimum or converges there, for a third of the overhead of scipy's
    trust region, which rebuilds its model from an SVD every iteration); then — start 0 directly —
    scipy's trust-region reflective search.  For a predictor whose rows do not depend on their
    call (``rows_independent``: the physics array path) the starts advance together, a round at a
    time: each round evaluates the next point of every running start (start 0 first) in shared
    model calls of at most :data:`CALL_VALUES` predictions (two points in one call cost about 0.8
    of two calls), and a later start can join an earlier start's optimum once that start has
    converged.  Each start takes the points it would take searched on its own, bit for bit, up
    to where it stops; a later start may stop later than one searched after the earlier ones had
    converged (a start's trust region, where scipy calls back, evaluates its points on their
    own).  Other predictors search the starts one after another, the later starts' first points
    in one call.
    When the trust region crawls (:func:`~physmodel.estimation.lm_steps.crawling`: over
    :data:`~physmodel.estimation.lm_steps.CRAWL_POINTS` points its best cost fell by less than a
    tenth of the Gauss–Newton decrement it had, that decrement above 1e-4·s²) — a valley the data
    barely determine, at a noise-size cost, where JᵀJ underrates the curvature along it and every
    step leaves it (the viscous-fluid load's ν: 100-200 points for 1e-3 in cost) — the valley is
    searched as a profile (:func:`~physmodel.estimation.lm_steps.profile_search`) and a fresh trust
    region resumes from the lowest point.
    A start ends (status 1) when the Gauss–Newton decrement ½gᵀ(JᵀJ)⁻¹g falls
    below :data:`GN_DECREMENT`·s² (within 1.4e-6 standard errors of the optimum), or on scipy's
    tests.  A later start stops early (status −2, never chosen as best) once its cost is within
    :data:`JOIN_COST`·s² above a converged earlier start's (below it only by what two converged
    points of one minimum can differ: GN_DECREMENT·s² and the cost's rounding,
    :data:`COST_ROUNDING`) and its Gauss–Newton step lands within :data:`JOIN_DISTANCE` standard
    errors of that optimum.  Advancing together, a later start can converge before an earlier one
    has: its optimum is then offered to the starts after it only once every earlier start has
    finished, and is first tested against theirs (it joins one whose basin it lies in), so it
    does not displace an earlier start's optimum whose basin it lies in (it would have joined
    that one on its way there, searched after it).

Identifiability (see :func:`fit_parameters`, :mod:`physmodel.estimation.identifiability`)
    From the SVD of the weighted, scaled Jacobian at the optimum a parameter is *undetermined* if
    its 95 % interval spans more than
    :data:`~physmodel.estimation.identifiability.MAX_CI_DECADES` decade (log) or more than its bounds
    (linear) — this includes near-null directions of the Jacobian, where se(z) is huge — or if it
    is pinned at a bound.  The reason names where its sensitivity peaks (from an optional
    :class:`SensitivityProbe` over a wide band) relative to the measured band, or the parameter it
    is confounded with.  Undetermined parameters are held at their start value (the base value in
    :func:`calibrate`) and the others refitted; they are reported without an interval.

Holding costs said (see :class:`~physmodel.estimation.identifiability.HoldRecord`)
    Each hold step is tested against the best fit with every parameter free: the hold is taken only
    when the cost rises by no more than :func:`~physmodel.estimation.identifiability.hold_cost_tolerance`
    (half the 0.95 quantile of χ²(k) for k held parameters: a likelihood-ratio test that the start
    values are consistent with the data).  A parameter pinned at a bound far from its start value
    fails it: the hold is undone, the un-held fit kept (the parameter at its bound, reported as not
    determined, its interval not a valid one) and the message says so.  ``result.holds`` records the
    cost before and after every step.

Temperature-law parameters are named ``"laws.<quantity>.<attribute>"``, e.g.
``"laws.d.activation_energy"`` [J/mol] or ``"laws.E.slope"`` [1/K] (see :mod:`physmodel.temperature`);
``"omega_n"`` [rad/s] sets the first bending mode through the density.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from ..data.sweep import FrequencySweep
from ..errors import IPMCError, ParameterError
from .batching import ModelBatch, ScaledRows
from .identifiability import (
    BOUND_TOL,
    Z95,
    HoldRecord,
    Identifiability,
    SensitivityProbe,
    flag_parameters,
    hold_record,
    refused_identifiability,
)
from .lm_steps import CRAWL_POINTS, CRAWL_SEARCHES, crawling, damped_steps, profile_search
from .observations import ScalarObservations
from .records import (
    CalibrationResult,
    FreeParameter,
    StartRecord,
    Values,
    lhs_starts,
)
from .residuals import (
    ZERO_REASON,
    gauss_newton_covariance,
    goodness_of_fit,
    insensitive,
    residual_model,
    tenth_moves,
)

#: Forward finite-difference step in the scaled space.
FD_STEP = 1e-6
#: A search ends when a Gauss–Newton step would gain less than this (times s², see ``_search``).
GN_DECREMENT = 1e-12
#: Predictions (parameter sets × lines) per batched model call at most when several points are
#: evaluated together: the kernel's temporaries then stay in cache.  Measured on the benchmark (500
#: lines, 7 sets per point; 2 shared cores): three points in one call of 21 sets took 1.37 ms,
#: in three calls 1.25 ms, two in one call 0.69 ms against 0.41 ms for one.
CALL_VALUES = 8192
#: A later start stops in a converged start's basin when its cost is within this (times s²) above
#: that start's optimum and ...
JOIN_COST = 25.0
#: ... its Gauss–Newton step lands within this many standard errors of that optimum: a distinct
#: optimum there would differ from it by less than the estimate's own uncertainty (0.1 until
#: 2026-11-27; it moves where a later start stops, not the estimate, on the benchmark's 20
#: calibrations compared).
JOIN_DISTANCE = 1.0
#: Relative rounding of a cost ½Σr² (about √N·ε for N residuals, with margin): below an
#: optimum's cost by less than this (plus GN_DECREMENT·s²) a point is not a lower minimum.
COST_ROUNDING = 1e-13



# =============================================================================== the engine
@dataclass
class _Fit:
    index: int
    z: np.ndarray
    cost: float
    J: np.ndarray
    r: np.ndarray
    nfev: int
    status: int
    message: str
    joined: int | None = None       # the earlier start whose optimum this one reached (status -2)
    parked: bool = False            # it finished while an earlier start still ran
    _gram: np.ndarray | None = None

    def gram(self) -> np.ndarray:
        """JᵀJ at the optimum, computed once (later starts test every point against it)."""
        if self._gram is None:
            self._gram = self.J.T @ self.J
        return self._gram


def _residuals_and_jacobian(batch: ModelBatch, rows: ScaledRows, z, hi, fd_step, res):
    """Standardised residuals (2N,) at scaled ``z`` and their Jacobian (2N, n) in one batched model
    call: forward differences (step ``fd_step``, backwards at the upper bound ``hi``) except for
    the columns the predictor knows by the chain rule (:meth:`ModelBatch.jacobian_plan`)."""
    return _residuals_and_jacobians(batch, rows, [z], hi, fd_step, res)[0]


def _residuals_and_jacobians(batch: ModelBatch, rows: ScaledRows, zs, hi, fd_step, res) -> list:
    """:func:`_residuals_and_jacobian` at several points ``zs`` in one batched model call (a model
    call costs about the same for one row or twenty: its per-call work dominates)."""
    fd, fd_rows, known, scaled = _layout(batch, rows, res)
    n, m = len(zs[0]), len(fd)
    per_call = max(1, CALL_VALUES // ((m + 1) * res.n_values)) if _regroups(batch, m) else len(zs)
    if len(zs) > per_call:      # in calls of at most CALL_VALUES predictions
        return [out for i in range(0, len(zs), per_call)
                for out in _residuals_and_jacobians(batch, rows, zs[i:i + per_call], hi, fd_step, res)]
    hi_fd = hi[fd]
    Z = np.repeat(np.asarray(zs, dtype=float), m + 1, axis=0)       # each point, then its m steps
    all_steps = []
    for b, z in enumerate(zs):
        steps = np.where(z[fd] + fd_step <= hi_fd, fd_step, -fd_step)   # backwards at the upper bound
        Z[b * (m + 1) + fd_rows, fd] += steps
        all_steps.append(steps)
    R = res(batch(rows(Z)))
    out = []
    for b, steps in enumerate(all_steps):
        Rb = R[b * (m + 1):(b + 1) * (m + 1)]
        JT = np.empty((n, Rb.shape[1]))         # built by rows, handed on as J = JTᵀ (C-ordered)
        D = Rb[1:] - Rb[0]
        D /= steps[:, None]
        JT[fd] = D
        for i, col in known:        # constant columns: the same at every point
            JT[i] = col
        for i, j, c in scaled:      # scaled columns: a fixed factor times a difference column
            np.multiply(JT[j], c, out=JT[i])
        out.append((Rb[0], np.ascontiguousarray(JT.T)))
    return out


def _regroups(batch: ModelBatch, m: int) -> bool:
    """Whether points may be grouped into model calls freely (:data:`CALL_VALUES`, every start's
    first point up front): only for a predictor whose rows do not depend on the other rows of
    their call (``batch.rows_independent``) and points of two sets or more (``m`` ≥ 1 difference
    columns: a single set goes through a matrix-vector product, rounded otherwise).  Else the
    points are grouped as before (an effect model's mode count, e.g., follows the lowest mode in
    its call)."""
    return batch.rows_independent and m >= 1


def _layout(batch: ModelBatch, rows: ScaledRows, res) -> tuple:
    """What :func:`_residuals_and_jacobians` needs for ``rows.active`` that no point changes, kept
    on ``batch`` (one residual model per batch): the difference columns ``fd`` and the rows of
    their steps, the known columns (:meth:`ModelBatch.jacobian_plan`) as (i, column) for the
    constant ones and (i, j, factor) for the scaled ones."""
    key = rows.active.tobytes()
    lay = batch.layouts.get(key)
    if lay is None:
        plan = batch.jacobian_plan(rows.active)
        fd = np.array([i for i in range(len(rows.active)) if i not in plan], dtype=int)
        known = [(i, res.constant_column(p[1])) for i, p in plan.items() if p[0] == "constant"]
        scaled = [(i, p[1], res.scaled_column(1.0, p[2])) for i, p in plan.items() if p[0] != "constant"]
        lay = batch.layouts[key] = (fd, np.arange(1, len(fd) + 1), known, scaled)
    return lay


def residual_jacobian(data: FrequencySweep | ScalarObservations, free: Sequence[FreeParameter], values: Values, *,
                      predict: Callable[[Values], np.ndarray] | None = None,
                      predict_many: Callable[[Sequence[Values]], np.ndarray] | None = None,
                      predict_array: Callable[[np.ndarray], np.ndarray] | None = None,
                      fixed: Values | None = None, fd_step: float = FD_STEP) -> tuple[np.ndarray, np.ndarray]:
    """The standardised residuals and their Jacobian with respect to the scaled coordinates z of
    ``free`` (see the module doc) at physical ``values``, exactly as :func:`fit_parameters`
    computes them (predictors as there).

    Returns
    -------
    r : ndarray
        (2N,) residuals ``[ln|G_d/G_m|/σ_ln, arg(G_d/G_m)/σ_φ]``. [-]
    J : ndarray
        (2N, len(free)) forward differences ∂r/∂z. [-]
    """
    free = list(free)
    res = residual_model(data)
    batch = ModelBatch(free, dict(fixed or {}), predict, predict_many, predict_array, None, res.n_values)
    x = np.array([float(values[fp.name]) for fp in free])
    z = np.array([float(fp.to_z(v)) for fp, v in zip(free, x)])
    hi = np.array([fp.z_bounds[1] for fp in free])
    return _residuals_and_jacobian(batch, ScaledRows(free, x, range(len(free))), z, hi, fd_step, res)


@lru_cache(maxsize=32)
def _lhs_cached(free: tuple, n: int, seed, seed_type: type) -> np.ndarray:
    out = lhs_starts(list(free), n, seed)
    out.flags.writeable = False
    return out


def _lhs_starts(free: Sequence[FreeParameter], n: int, seed) -> np.ndarray:
    """:func:`~physmodel.estimation.records.lhs_starts`, kept per (free, n, seed): the same points
    for every calibration of one problem (Monte Carlo draws, repeated fits) without rebuilding
    scipy's sampler."""
    try:
        # keyed by the seed's type too: True == 1, but lhs_starts refuses a bool
        return _lhs_cached(tuple(free), n, seed, type(seed))
    except TypeError:             # unhashable: not kept (lhs_starts says what is wrong with it)
        return lhs_starts(free, n, seed)


@lru_cache(maxsize=256)
def _z_bounds(fp: FreeParameter) -> tuple[float, float]:
    return fp.z_bounds


def _z_box(free: Sequence[FreeParameter]) -> tuple[np.ndarray, np.ndarray]:
    """The lower and upper bounds of ``free`` in the scaled coordinates (n,), (n,), each
    parameter's read once per process (FreeParameter is immutable)."""
    zb = [_z_bounds(fp) for fp in free]
    return np.array([b[0] for b in zb]), np.array([b[1] for b in zb])


def joined_start(record: StartRecord) -> int | None:
    """The index of the earlier start whose optimum ``record``'s start joined (status −2), else None."""
    return record.joined if record.status == -2 else None


#: A coordinate of an optimum within this fraction of its range from a bound sits at that bound.
AT_BOUND = 1e-6


def _landing(z, r, J, step, z_opt, lo, hi) -> np.ndarray:
    """Where the Gauss–Newton model from ``z`` lands, as seen from an earlier optimum ``z_opt``:
    ``z + step`` — unless ``z_opt`` sits at bounds (an effect at its off value): then the model's
    minimum on that face (those coordinates held at the optimum's bound, the others solved), if it
    is the minimum over the box too (each held coordinate's gradient there points out of the box,
    the Karush–Kuhn–Tucker sign); else ``z + step`` (no join on a face the model would leave)."""
    span = hi - lo
    low, high = z_opt - lo <= AT_BOUND * span, hi - z_opt <= AT_BOUND * span
    held = low | high
    if not held.any():
        return z + step
    d = np.zeros_like(z)
    d[held] = z_opt[held] - z[held]
    free = ~held
    rr = r + J[:, held] @ d[held]
    if free.any():
        d[free] = np.linalg.lstsq(J[:, free], -rr, rcond=None)[0]
    g = J.T @ (r + J @ d)                      # the model's gradient at the landing point
    if np.all(g[low] >= 0) and np.all(g[high] <= 0):
        return z + d
    return z + step


def _basin(z, r, J, step, c: float, s2: float, optima: Sequence[_Fit], lo, hi) -> _Fit | None:
    """The first of ``optima`` (converged earlier starts) in whose basin the point ``z`` (residuals
    ``r``, Jacobian ``J``, Gauss–Newton ``step``, cost ``c``) lies, else None: its cost within
    :data:`JOIN_COST`·s² above the optimum's, or below it by no more than two converged points of
    one minimum can differ (GN_DECREMENT·s² and the cost's rounding), and its Gauss–Newton step
    landing within :data:`JOIN_DISTANCE` standard errors of the optimum."""
    for opt in optima:
        below = GN_DECREMENT * s2 + COST_ROUNDING * opt.cost
        if opt.status > 0 and opt.cost - below <= c <= opt.cost + JOIN_COST * s2:
            d = _landing(z, r, J, step, opt.z, lo, hi) - opt.z
            if float(d @ opt.gram() @ d) <= JOIN_DISTANCE**2 * s2:
                return opt
    return None


def _lands(opt: _Fit) -> str:
    """Why a start is in ``opt``'s basin, for its message."""
    return (f"its Gauss-Newton step lands within {JOIN_DISTANCE:g} standard "
            f"error{'' if JOIN_DISTANCE == 1 else 's'} of start {opt.index}'s optimum")


def _gn_step(r, J) -> np.ndarray:
    """The Gauss–Newton step of residuals ``r`` with Jacobian ``J`` (minimum-norm if JᵀJ is singular)."""
    try:
        return np.linalg.solve(J.T @ J, -(J.T @ r))
    except np.linalg.LinAlgError:       # e.g. a zero column: the minimum-norm step
        return np.linalg.lstsq(J, -r, rcond=None)[0]


class _Stop(Exception):
    """Ends scipy's search from inside the residual function."""


class _Crawl(Exception):
    """Ends scipy's search from inside the residual function: it crawls (``lm_steps.crawling``)."""


def _solve(free, active: Sequence[int], x_full: np.ndarray, z0, batch: ModelBatch, res, max_nfev, ftol,
           fd_step) -> _Fit:
    """One start's search (:func:`_search`) from ``z0``, each point evaluated when asked for."""
    rows = ScaledRows(free, x_full, active)
    hi = _z_box([free[k] for k in active])[1]
    return _run(_search(free, active, z0, batch, res, max_nfev, ftol, fd_step, rows),
                lambda z: _residuals_and_jacobian(batch, rows, z, hi, fd_step, res))


def _run(search, evaluate) -> _Fit:
    """A search (:func:`_search`) run to its end, each point it asks for evaluated at once by
    ``evaluate(z) -> (r, J)``."""
    try:
        z = next(search)
        while True:
            z = search.send(evaluate(z))
    except StopIteration as stop:
        return stop.value


def _search(free, active: Sequence[int], z0, batch: ModelBatch, res, max_nfev, ftol, fd_step, rows: ScaledRows,
            optima: Sequence[_Fit] = (), first: tuple | None = None, damped: bool = True, later: bool = False):
    """Least squares over the ``active`` parameters of ``free`` in their scaled space (the others
    at ``rows.x_full``); search and stopping in the module doc.  A generator: it yields each point
    of its Gauss–Newton and damped steps, ``z`` (scaled, active), and takes back its residuals
    and Jacobian ``(r, J)`` (:func:`_residuals_and_jacobians`), so that :func:`fit_parameters`
    can advance several starts in shared model calls; the trust region's points (scipy calls
    back) it evaluates itself.  Returns its :class:`_Fit` (``StopIteration.value``).
    A point costs one batched model call, residuals and Jacobian together (a Broyden-updated
    Jacobian needed three times the points).
    Plain Gauss–Newton steps converge in 6–7 points on the benchmark where scipy's trust region,
    which starts small, needs 9–10.  s² = 2·cost/dof scales the tests to standard errors.
    ``optima``: the converged searches a later one may join (read at every point: it may grow
    while this one runs).  ``first``: the residuals and Jacobian at the (clipped) start, already
    computed.  ``later``: a later start, which takes damped steps (:func:`damped_steps`) before the
    trust region unless ``damped`` is False.
    """
    act = [free[k] for k in active]
    lo, hi = _z_box(act)
    dof = res.size - len(act)
    cache: dict = {}
    count, last, searches = [0], [None], [0]

    def assess(z, r, J):
        """(status or None, message, Gauss–Newton step, cost, the start joined or None) of a point."""
        c = 0.5 * float(r @ r)
        s2 = 2.0 * c / dof if dof > 0 else 1.0
        g = J.T @ r
        try:
            step = np.linalg.solve(J.T @ J, -g)
        except np.linalg.LinAlgError:       # e.g. a zero column: the minimum-norm step
            step = np.linalg.lstsq(J, -r, rcond=None)[0]
        decrement = -0.5 * float(g @ step)
        if 0 <= decrement < GN_DECREMENT * s2:
            return 1, f"Gauss-Newton decrement {decrement:.2g} below {GN_DECREMENT:g}·s² (s² = {s2:.3g})", step, c, None
        opt = _basin(z, r, J, step, c, s2, optima, lo, hi)
        if opt is not None:
            return -2, "stopped early: " + _lands(opt), step, c, opt.index
        return None, "", step, c, None

    def store(z, r, J):
        """The point ``(z, r, J, status, message, step, cost, joined)``, cached for the last two."""
        if len(cache) > 1:
            cache.pop(next(iter(cache)))
        pt = cache[z.tobytes()] = (z.copy(), r, J, *assess(z, r, J))
        return pt

    def evaluate(z):
        """The point at ``z``, evaluated here if not cached (the trust region's and profile search's)."""
        pt = cache.get(z.tobytes())
        if pt is None:
            pt = store(z, *_residuals_and_jacobian(batch, rows, z, hi, fd_step, res))
        last[0] = pt
        return pt

    def ask(z):
        """The point at ``z``, asked of the caller if not cached (a generator: ``yield from``)."""
        pt = cache.get(z.tobytes())
        if pt is None:
            pt = store(z, *(yield z))
        last[0] = pt
        return pt

    best: list = []           # the trust region's lowest point after each of its points

    def fun(z):
        count[0] += 1
        pt = evaluate(z)
        if pt[3] is not None:
            raise _Stop()
        best.append(pt if not best or pt[6] < best[-1][6] else best[-1])
        if searches[0] < CRAWL_SEARCHES and crawling(best, decrement, 2.0 * best[-1][6] / max(dof, 1)):
            raise _Crawl()
        return pt[1]

    span_b = hi - lo

    def decrement(pt):
        """The Gauss–Newton decrement with the coordinates at a bound that the gradient pushes
        outwards held there (as the profile's inner fit holds them): unbounded, such a
        coordinate's step promises a gain no point in the box can give, and the crawl test
        fired at an optimum on a bound."""
        z, r, J = pt[0], pt[1], pt[2]
        g = J.T @ r
        held = ((z - lo <= 1e-8 * span_b) & (g > 0)) | ((hi - z <= 1e-8 * span_b) & (g < 0))
        if not np.any(held):
            return -0.5 * float(g @ pt[5]) if pt[5] is not None else 0.0
        f = np.flatnonzero(~held)
        if not len(f):
            return 0.0
        try:
            sf = np.linalg.lstsq(J[:, f], -r, rcond=None)[0]
        except np.linalg.LinAlgError:
            return 0.0
        return -0.5 * float(g[f] @ sf)

    stopped_at_budget = lambda: max_nfev is not None and count[0] >= max_nfev  # noqa: E731
    count[0] = 1
    z_start = np.clip(np.asarray(z0, dtype=float), lo, hi)
    if first is not None:
        store(z_start, *first)
    pt = yield from ask(z_start)
    while pt[3] is None and pt[5] is not None and not stopped_at_budget():      # Gauss–Newton steps
        z_new = pt[0] + pt[5]
        if (z_new < lo).any() or (z_new > hi).any():
            break
        count[0] += 1
        new = yield from ask(z_new)
        if not new[6] < pt[6]:
            break
        pt = new
    if pt[3] is None and later and damped and not stopped_at_budget():
        # a later start: damped Gauss-Newton (Levenberg-Marquardt) steps kept in the box until it
        # converges or reaches an earlier optimum; scipy's trust region (below) only if it stalls
        pt = yield from damped_steps(pt, ask, lo, hi, count, stopped_at_budget)
    status, msg = pt[3], pt[4]
    if status is None and stopped_at_budget():
        status, msg = 0, f"stopped after {count[0]} function evaluations (max_nfev={max_nfev}) before converging"
    elif status is None:
        while True:
            count[0] -= 1              # scipy re-evaluates its start point (cached)
            best.clear()
            try:
                sol = least_squares(fun, pt[0], jac=lambda z: evaluate(z)[2], bounds=(lo, hi), method="trf",
                                    x_scale=1.0, ftol=ftol, xtol=1e-10, gtol=1e-10,
                                    max_nfev=None if max_nfev is None else max(max_nfev - count[0], 1))
                pt, status = evaluate(sol.x), int(sol.status)
                msg = sol.message.rstrip(".") if sol.status > 0 else (
                    f"stopped after {count[0]} function evaluations (max_nfev={max_nfev}) before converging"
                    if sol.status == 0 else sol.message)
            except _Stop:
                pt = last[0]
                status, msg = pt[3], pt[4]
            except _Crawl:
                # the trust region crawls along a valley whose curvature the Gauss-Newton model
                # underrates: a profile search along it (lm_steps.profile_search), then a fresh trust region
                searches[0] += 1
                pt = profile_search(best[-1], evaluate, lo, hi, count, stopped_at_budget,
                                    best[-1][0] - best[-CRAWL_POINTS - 1][0],
                                    2.0 * best[-1][6] / max(dof, 1))
                status, msg = pt[3], pt[4]
                if status is None and stopped_at_budget():
                    status, msg = 0, (f"stopped after {count[0]} function evaluations (max_nfev={max_nfev}) "
                                      "before converging")
                if status is None:
                    if pt is best[-1]:         # the search found nothing lower: no more searches
                        searches[0] = CRAWL_SEARCHES
                    cache[pt[0].tobytes()] = pt
                    continue                   # its point is counted; the restart re-evaluates it (cached)
            break
    z, r, J = pt[0], pt[1], pt[2]
    return _Fit(index=-1, z=z, cost=float(0.5 * r @ r), J=J, r=r, nfev=count[0], status=status, message=msg,
                joined=pt[7] if status == -2 else None)


def fit_parameters(data: FrequencySweep | ScalarObservations, predict: Callable[[Values], np.ndarray] | None,
                   free: Sequence[FreeParameter], *, starts: int = 1, seed: int = 0,
                   predict_many: Callable[[Sequence[Values]], np.ndarray] | None = None,
                   fixed: Values | None = None, max_nfev: int | None = None, ftol: float = 1e-10,
                   identify: bool = True, hold_undetermined: bool | str = True,
                   probe: SensitivityProbe | None = None, fd_step: float = FD_STEP,
                   progress: Callable[[int], None] | None = None,
                   predict_array: Callable[[np.ndarray], np.ndarray] | None = None,
                   initials: Sequence[Values] = (), damped: bool = True) -> CalibrationResult:
    """Fit ``free`` parameters of a generic predictor to ``data`` by weighted least squares.

    Parameters
    ----------
    data : FrequencySweep or ScalarObservations
        The measured lines; their per-line σ weight the residuals (without them: module doc).
        Or scalar observations y with σ of ln y: residuals ln|y_model/y|/σ_ln, predictions real
        (n_sets, N) (no probe; the sensitivity peaks are NaN).
    predict, predict_many, predict_array : callable or None
        The model at every line of ``data`` (same order and units), the first given of:
        ``predict_array(X) -> (n_sets, N)`` with ``X`` the physical values (n_sets, len(free)) in
        the order of ``free`` (``fixed`` built in; no values dict per set), ``predict_many(list of
        values) -> (n_sets, N)``, ``predict(values) -> (N,)`` complex.
    free : sequence of FreeParameter
        The parameters to fit.  Start 0 is each one's ``initial`` (else the mid-point); ``starts``
        − 1 more are Latin-hypercube points in the scaled boxes (``seed``); all are reported.
    starts, seed : int
    fixed : mapping or None
        Extra values passed to ``predict``/``predict_many`` unchanged. [SI]
    max_nfev, ftol, fd_step : int or None, float, float
        Residual evaluations per start and relative cost tolerance (scipy's meaning); the
        forward-difference step in the scaled coordinates. [-]
    identify : bool
        Flag undetermined parameters (module doc).
    hold_undetermined : bool or "insensitive"
        Hold undetermined parameters at their start-0 value and refit (one at a time, the worst
        first; those at a bound or with zero sensitivity at once); ``"insensitive"``: only those
        the data do not depend on (the others keep their fitted value and interval).  A step whose
        cost increase over the all-free fit exceeds
        :func:`~physmodel.estimation.identifiability.hold_cost_tolerance` is refused and undone (module
        doc); ``result.holds`` records every step.  ``"always"``: hold as ``True`` does even when
        the test fails (the record says so) — for a deliberate modelling choice, e.g. a stored
        set's derivation.
    probe : SensitivityProbe or None
        Wide-band evaluation locating where each parameter acts.
    progress : callable or None
        ``progress(1)`` after each start.
    initials : sequence of mappings
        Further start points, physical values of every free parameter (clipped to the bounds),
        taken after start 0 and before the Latin-hypercube ones: several warm starts searched
        as one multi-start, so a later one that reaches an earlier optimum stops there (status
        −2, :func:`joined_start`).
    damped : bool
        The later starts take Levenberg–Marquardt steps before scipy's trust region (module doc);
        False: they go to the trust region at once, as start 0 does (for starts whose optimum
        lies at a bound, where the damped steps crawl along it).

    Returns
    -------
    CalibrationResult
        ``parameters`` is None (see :func:`calibrate` for the physics wrapper).
    """
    t0 = time.perf_counter()
    res = residual_model(data)
    free = [fp if isinstance(fp, FreeParameter) else None for fp in free]
    if not free or any(fp is None for fp in free):
        raise ParameterError("free must be a non-empty sequence of FreeParameter")
    names = [fp.name for fp in free]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(f"free parameter(s) {dup} given more than once")
    if predict is None and predict_many is None and predict_array is None:
        raise IPMCError("give predict, predict_many or predict_array")
    if int(starts) < 1:
        raise IPMCError(f"starts must be >= 1, got {starts}")
    if hold_undetermined not in (True, False, "insensitive", "always"):
        raise IPMCError(f"hold_undetermined must be True, False, 'insensitive' or 'always', got {hold_undetermined!r}")
    if max_nfev is not None and int(max_nfev) < 1:
        raise IPMCError(f"max_nfev must be >= 1, got {max_nfev}")
    fixed = dict(fixed or {})
    estimated, n_lines = res.estimated, res.n_values
    if res.size <= len(free):
        raise IPMCError(f"{res.what} cannot determine {len(free)} parameters")
    batch = ModelBatch(free, fixed, predict, predict_many, predict_array, probe, n_lines)

    x_init = [fp.initial if fp.initial is not None else fp.midpoint() for fp in free]
    x_full = np.array(x_init, dtype=float)
    z_init = np.array([fp.to_z(x) for fp, x in zip(free, x_init)], float)
    held: dict[str, Identifiability] = {}
    if hold_undetermined == "insensitive":
        R = res(batch(ScaledRows(free, x_full, range(len(free)))(tenth_moves(free, z_init))))
        held = {free[k].name: Identifiability(False, ZERO_REASON + "; held at its start value") for k in insensitive(R)}
        if len(held) == len(free):
            raise IPMCError(f"the data depend on none of the free parameters {list(held)} (zero sensitivity)")
    active = [k for k, fp in enumerate(free) if fp.name not in held]
    z_given = [[fp.to_z(min(max(float(v[fp.name]), fp.lower), fp.upper)) for fp in free] for v in initials]
    z_starts = np.vstack([z_init[None, :], np.array(z_given, float).reshape(-1, len(free)),
                          _lhs_starts(free, int(starts) - 1, seed)])
    z_starts[:, [k for k in range(len(free)) if k not in active]] = z_init[[k for k in range(len(free)) if k not in active]]
    records, ends = [], []
    fits: list = [None] * len(z_starts)
    optima: list = []         # the finished starts, in the order they finished (a later one may join them)
    rows0 = ScaledRows(free, x_full, active)

    def search(i, first=None):
        return _search(free, active, z_starts[i][active], batch, res, max_nfev, ftol, fd_step, rows0,
                       optima if i else (), first, damped, later=i > 0)

    lo_a, hi_a = _z_box([free[k] for k in active])
    dof = res.size - len(active)
    admitted = [0]      # starts 0 .. admitted[0] − 1 finished, and their optima offered to the later ones

    def finish(i, fit):
        """Start i's fit; the optima are offered in start order, so a later start joins only an
        earlier one's, as when they run one after another: a start that converged while an earlier
        one still ran is tested against those earlier optima first (it joins one whose basin its
        optimum lies in)."""
        fit.index = i
        fits[i] = fit
        fit.parked = admitted[0] < i
        if progress:
            progress(1)
        while admitted[0] < len(fits) and fits[admitted[0]] is not None:
            f = fits[admitted[0]]
            if f.status > 0 and f.parked:
                opt = _basin(f.z, f.r, f.J, _gn_step(f.r, f.J), f.cost, 2.0 * f.cost / dof if dof > 0 else 1.0,
                             optima, lo_a, hi_a)
                if opt is not None:
                    f.status, f.joined = -2, opt.index
                    f.message = f"converged before start {opt.index} had, in its basin: " + _lands(opt)
            if f.status > 0:
                optima.append(f)
            admitted[0] += 1

    if len(z_starts) > 1 and _regroups(batch, len(_layout(batch, rows0, res)[0])):
        # with rows independent of their call (_regroups) the starts advance together, a round at
        # a time: each round's points (one per running start, start 0 first) share model calls
        # (CALL_VALUES: two points cost far less than two calls), and a later start joins an
        # optimum once that start has converged
        gens = {i: search(i) for i in range(len(z_starts))}
        asked = {i: next(g) for i, g in gens.items()}
        while asked:
            order = sorted(asked)
            for i, out in zip(order, _residuals_and_jacobians(batch, rows0, [asked[i] for i in order], hi_a,
                                                                fd_step, res)):
                try:
                    asked[i] = gens[i].send(out)
                except StopIteration as stop:
                    del asked[i]
                    finish(i, stop.value)
    else:
        firsts: dict = {}
        for i in range(len(z_starts)):
            if i == 1 and len(z_starts) > 2:    # the later starts' first points in one model call
                pts = [np.clip(z[active], lo_a, hi_a) for z in z_starts[1:]]
                firsts = dict(enumerate(_residuals_and_jacobians(batch, rows0, pts, hi_a, fd_step, res), start=1))
            finish(i, _run(search(i, firsts.get(i)), lambda z: _residuals_and_jacobian(batch, rows0, z, hi_a, fd_step,
                                                                                      res)))
    for i, (z0, fit) in enumerate(zip(z_starts, fits)):
        ends.append(z0.copy())
        ends[-1][active] = fit.z
        initial = dict(zip(names, x_init)) if i == 0 else {fp.name: float(fp.from_z(v)) for fp, v in zip(free, z0)}
        records.append(StartRecord(i, initial,
                                   {fp.name: float(fp.from_z(v)) for fp, v in zip(free, ends[-1])},
                                   fit.cost, fit.nfev, fit.status, fit.message, fit.joined))
    best = min((k for k in range(len(fits)) if fits[k].status != -2), key=lambda k: fits[k].cost)
    fit = fits[best]
    converged = fit.status > 0
    message = f"best of {len(fits)} start(s) is start {best}: {fit.message}"

    # identifiability: flag, hold the worst, refit the rest; repeat
    z_full = ends[best].copy()
    report: dict = {}
    holds: list[HoldRecord] = []
    held_in_loop: list[str] = []
    free_cost = fit.cost
    free_gof = goodness_of_fit(free_cost, res.size, len(active), estimated)
    while True:
        act = [free[k] for k in active]
        x_full = np.array([x_init[k] if fp.name in held else float(fp.from_z(z_full[k]))
                           for k, fp in enumerate(free)])
        cov, _ = gauss_newton_covariance(fit.J)
        noise_scale = 1.0
        dof = res.size - len(act)
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
        report, badness, se, corr, dead = flag_parameters(free, active, fit.z, fit.J, cov, x_full, res, probe,
                                                          batch, fd_step)
        if not badness or not hold_undetermined or (hold_undetermined == "insensitive" and not dead):
            break
        pinned = [n for n, b in badness.items() if b == np.inf]
        to_hold = dead if hold_undetermined == "insensitive" else pinned or [max(badness, key=badness.get)]
        # hold them, refit, and test what the hold cost against the free fit (hold_cost_tolerance)
        saved = (fit, z_full.copy(), list(active), dict(held), converged)
        for n in to_hold:
            held[n] = report[n]
        active = [k for k in active if free[k].name not in held]
        for k, fp in enumerate(free):
            if fp.name in held:
                z_full[k] = z_init[k]
        x_full = np.array([x_init[k] if fp.name in held else float(fp.from_z(z_full[k]))
                           for k, fp in enumerate(free)])
        if active:
            refit = _solve(free, active, x_full, z_full[active], batch, res, max_nfev, ftol, fd_step)
            z_full[active] = refit.z
            cost_held = refit.cost
        else:
            refit = None
            cost_held = float(0.5 * np.sum(res(batch(x_full[None, :]))[0] ** 2))
        what = ", ".join(to_hold)
        rec = hold_record(tuple(held_in_loop) + tuple(to_hold), tuple(to_hold), free_cost, cost_held, free_gof,
                          hold_undetermined == "always")
        holds.append(rec)
        if not rec.accepted:
            fit, z_full, active, held, converged = saved
            for n in to_hold:
                k = names.index(n)
                lo, hi = free[k].z_bounds
                report[n] = refused_identifiability(report[n], rec, min(z_full[k] - lo, hi - z_full[k])
                                                    <= BOUND_TOL * (hi - lo))
            message += (f"; hold of {what} refused: it would raise the cost from {free_cost:.6g} to {cost_held:.6g} "
                        f"(allowed +{rec.threshold:.3g}); un-held fit kept, {what} not determined")
            break
        held_in_loop = list(rec.names)
        if refit is None:
            break
        fit = refit
        converged = fit.status > 0
        message += (f"; refit without {what}: {fit.message} (cost {free_cost:.6g} -> {cost_held:.6g}, "
                    f"+{rec.increase:.3g} " + (f"within the {rec.threshold:.3g} allowed)" if rec.within_test else
                                               f"above the {rec.threshold:.3g} allowed, held anyway: "
                                               "hold_undetermined='always')"))

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
        G = batch(np.array([[values[n] for n in names]]))[0]
        cost = float(0.5 * np.sum(res(G) ** 2))
    else:
        cost = fit.cost
    expected = res.size / 2.0 - n_act / 2.0
    if held:
        message += f"; undetermined and held at their start value: {', '.join(held)}"
    gof = goodness_of_fit(cost, res.size, n_act, estimated)
    return CalibrationResult(
        names=names, values=values, parameters=None, stderr=stderr, ci_lower=lo_ci, ci_upper=hi_ci,
        correlation=C, cost=cost, expected_cost=expected, cost_std=math.sqrt(max(expected, 0.0)),
        n_lines=n_lines, n_evaluations=batch.evaluations, n_model_calls=batch.calls,
        converged=bool(converged), message=message, starts=records, identifiability=ident,
        noise_estimated=estimated, noise_scale=float(noise_scale), held=list(held), free=list(free),
        band_hz=res.band_hz, temperatures_c=res.temperatures_c, elapsed_s=time.perf_counter() - t0, goodness_of_fit=gof,
        holds=holds,
    )
