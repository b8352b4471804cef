"""Output-error least squares in numpy: residual, analytic Jacobian, Levenberg–Marquardt.

The residuals are those of :mod:`surrogate._nlp` (``log``: ln|R|, arg R; ``relative``:
R − 1, with R = H_model/H_data, weighted per line).  Their Jacobian follows from

    ∂ ln H/∂ slot = ∂ ln N/∂ slot − ∂ ln D/∂ slot,

a short closed form for every slot of every form (a coefficient b_i: s̃^i/N; a section
coefficient c: its derivative over the section; a log-section coefficient u: e^u times that),
times τ^q for the q-th polynomial coefficient of a scheduled slot.  One evaluation is a few
vectorised complex operations on (starts × lines × slots) arrays, whatever the number of
lines: nothing is built per data set, and several parameter vectors (the starting points of
a fit) are evaluated in one call.

:class:`LevenbergMarquardt` minimises ½·mean(r²) from several starts *in lockstep*: one
batched evaluation serves all starts, each start keeps its own damping, and the linear
systems are solved together.  Variables are scaled by the Jacobian's column norms (Moré's
scaling), bounds are kept by projection.  When a start converges, the still-running starts it
has beaten are stopped (see ``margins``): losing starts end early.
"""

from __future__ import annotations

import time
from functools import lru_cache

import numpy as np

from physmodel.numerics import one_blas_thread

from ._lm_control import step_control
from ._structure import Structure

try:        # what numpy.einsum calls (optimize=False), without its dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:  # pragma: no cover - other numpy layouts
    _einsum = np.einsum
try:        # the gufunc numpy.linalg.solve calls, without its checks and error-state switching
    from numpy.linalg._umath_linalg import solve as _gesv
except ImportError:  # pragma: no cover - other numpy layouts
    def _gesv(a, b, signature=None):
        return np.linalg.solve(a, b)

__all__ = ["Evaluator", "LevenbergMarquardt", "STATUS_OK", "STATUS_ACCEPTABLE", "STATUS_MAXITER",
           "STATUS_STOPPED", "STATUS_FAILED"]

# statuses follow IPOPT's names, so results read the same whichever solver produced them
STATUS_OK = "Solve_Succeeded"
STATUS_ACCEPTABLE = "Solved_To_Acceptable_Level"
STATUS_MAXITER = "Maximum_Iterations_Exceeded"
STATUS_STOPPED = "Stopped_Early"   # a start that lost the race (see LevenbergMarquardt)
STATUS_FAILED = "Evaluation_Failed"


@lru_cache(maxsize=128)
def _layout(structure: Structure) -> dict:
    """Slot positions by role (slices: each role's slots are contiguous or evenly spaced in
    ``Structure.slots``), computed once per structure."""
    ix = {s: i for i, s in enumerate(structure.slots)}
    m, n = structure.n_zeros, structure.n_poles

    def span(names, step=1):
        if not names:
            return slice(0, 0)
        i0 = ix[names[0]]
        idx = [ix[nm] for nm in names]
        assert idx == list(range(i0, i0 + step * len(names), step)), names
        return slice(i0, i0 + step * len(names), step)

    lay = {"form": structure.form, "m": m, "n": n, "n_slots": len(ix)}
    if structure.form == "zpk":
        p1, p2, single = structure.zero_section_slots
        lay["k"] = ix["k"]
        lay["unit"] = structure.zero_sections == "unit"
        lay["z1"] = span([f"{p1}_{k}" for k in range(m // 2)], 2)
        lay["z0"] = span([f"{p2}_{k}" for k in range(m // 2)], 2)     # c0 ('monic') or β2 ('unit')
        lay["ze"] = ix[single] if m % 2 else None
    else:
        lay["b"] = span([f"b{i}" for i in range(m + 1)])
    if structure.form == "coefficients":
        lay["a"] = span([f"a{j}" for j in range(n)])
    else:
        lay["p1"] = span([f"log_a1_{k}" for k in range(n // 2)], 2)
        lay["p0"] = span([f"log_a0_{k}" for k in range(n // 2)], 2)
        lay["p10"] = slice(lay["p1"].start, lay["p1"].start + 2 * (n // 2)) if n > 1 else slice(0, 0)
        lay["pc"] = ix["log_c"] if n % 2 else None
    return lay



class Evaluator:
    """Residual and Jacobian of one fit problem (a :class:`surrogate._nlp.Problem`) for one
    parameter vector (p,) or a stack of them (S, p)."""

    def __init__(self, problem):
        st = problem.structure
        self.structure = st
        self.kind = problem.kind
        self.lay = _layout(st)
        w = np.asarray(problem.w, float)
        self.n_lines = w.size
        self.s = (1j * w)[:, None]                   # (N, 1)
        self.s2 = self.s * self.s
        m, n = st.n_zeros, st.n_poles
        self.spow = (1j * w)[:, None] ** np.arange(max(m, n) + 1)
        self._sp_num_t = np.ascontiguousarray(self.spow[:, :m + 1].T)
        self._sp_den_t = np.ascontiguousarray(self.spow[:, :n].T)
        self.tpow = np.asarray(problem.tau, float)[:, None] ** np.arange(st.n_coef)
        self.inv_h = 1.0 / np.asarray(problem.h, complex)
        self.weights = np.concatenate([np.asarray(problem.inv_sig_a, float),
                                       np.asarray(problem.inv_sig_b, float)])
        self.n_params = st.n_params

    def with_structure(self, structure: Structure) -> Evaluator:
        """The same problem in another form with the same orders and degree (e.g. the
        coefficient form, to score Sanathanan–Koerner iterates), sharing the data arrays."""
        st = self.structure
        if (structure.n_zeros, structure.n_poles, structure.degree) != (st.n_zeros, st.n_poles, st.degree):
            raise ValueError(f"{structure} does not have the orders and degree of {st}")
        ev = object.__new__(Evaluator)
        ev.__dict__.update(self.__dict__)
        ev.structure, ev.lay, ev.n_params = structure, _layout(structure), structure.n_params
        return ev

    def _slots(self, theta: np.ndarray) -> np.ndarray:
        """Slot values (S, N or 1, slots)."""
        st = self.structure
        if st.n_coef == 1:
            return theta[:, None, :]
        th = theta.reshape(theta.shape[0], self.lay["n_slots"], st.n_coef)
        return np.einsum("nq,sjq->snj", self.tpow, th)

    def _model(self, theta: np.ndarray, grad: bool):
        """q = N/(D·h) (S, N) and, with ``grad``, G = ∂ ln(N/D)/∂ slot (S, N, slots)."""
        lay = self.lay
        v = self._slots(theta)
        s, s2, sp = self.s, self.s2, self.spow
        m, n = lay["m"], lay["n"]
        g = np.empty(v.shape[:1] + (self.n_lines, lay["n_slots"]), complex) if grad else None
        if lay["form"] == "zpk":
            k = v[..., lay["k"]]
            num = k
            unit = lay["unit"]
            if m > 1:
                z1s = v[..., lay["z1"]] * s
                sec = (1.0 + z1s + v[..., lay["z0"]] * s2) if unit else (s2 + z1s + v[..., lay["z0"]])
                num = num * (sec[..., 0] if m < 4 else np.prod(sec, axis=-1))
                if grad:
                    inv = 1.0 / sec
                    g[..., lay["z1"]] = s * inv
                    g[..., lay["z0"]] = s2 * inv if unit else inv
            if grad:
                g[..., lay["k"]] = 1.0 / k
            if lay["ze"] is not None:
                e = (1.0 + v[..., lay["ze"]] * s[:, 0]) if unit else (s[:, 0] + v[..., lay["ze"]])
                num = num * e
                if grad:
                    g[..., lay["ze"]] = (s[:, 0] if unit else 1.0) / e
        elif v.shape[1] == 1:                     # one temperature: a matrix product
            num = v[:, 0, lay["b"]] @ self._sp_num_t
            if grad:
                np.divide(sp[:, :m + 1], num[..., None], out=g[..., lay["b"]])
        else:
            num = (v[..., lay["b"]] * sp[:, :m + 1]).sum(axis=-1)
            if grad:
                g[..., lay["b"]] = sp[:, :m + 1] / num[..., None]
        if lay["form"] == "coefficients":
            if v.shape[1] == 1:
                den = sp[:, n] + v[:, 0, lay["a"]] @ self._sp_den_t
            else:
                den = sp[:, n] + (v[..., lay["a"]] * sp[:, :n]).sum(axis=-1)
            if grad:
                g[..., lay["a"]] = -sp[:, :n] / den[..., None]
        else:
            den = None
            if n > 1:
                e = np.exp(v[..., lay["p10"]])          # (a1_0, a0_0, a1_1, a0_1, ...)
                e1, e0 = e[..., 0::2], e[..., 1::2]
                e1s = e1 * s
                sec = s2 + e1s + e0
                den = sec[..., 0] if n < 4 else np.prod(sec, axis=-1)
                if grad:
                    inv = 1.0 / sec
                    np.multiply(np.negative(e1s, out=e1s), inv, out=g[..., lay["p1"]])
                    np.multiply(-e0, inv, out=g[..., lay["p0"]])
            if lay["pc"] is not None:
                c = np.exp(v[..., lay["pc"]])
                d1 = s[:, 0] + c
                den = d1 if den is None else den * d1
                if grad:
                    g[..., lay["pc"]] = -c / d1
        return num / den * self.inv_h, g

    def residual(self, theta, jacobian: bool = False):
        """Weighted residuals ((S,) 2N) and, with ``jacobian``, their Jacobian ((S,) 2N × p).

        Non-finite values are returned as such (no warnings)."""
        with np.errstate(all="ignore"):
            return self._residual(theta, jacobian)

    def _residual(self, theta, jacobian: bool):
        """``residual`` for callers that already ignore floating-point warnings."""
        theta = np.asarray(theta, float)
        single = theta.ndim == 1
        th = theta[None, :] if single else theta
        n = self.n_lines
        q, g = self._model(th, jacobian)
        r = np.empty((th.shape[0], 2 * n))
        if self.kind == "log":
            np.log(np.abs(q), out=r[:, :n])
            np.arctan2(q.imag, q.real, out=r[:, n:])
        else:
            np.subtract(q.real, 1.0, out=r[:, :n])
            r[:, n:] = q.imag
        r *= self.weights
        if not jacobian:
            return r[0] if single else r
        if self.kind != "log":
            g = g * q[..., None]
        nc = self.structure.n_coef
        if nc > 1:
            g = (g[..., None] * self.tpow[:, None, :]).reshape(g.shape[0], self.n_lines, -1)
        jac = np.empty((g.shape[0], 2 * n, g.shape[2]))
        np.multiply(g.real, self.weights[:n, None], out=jac[:, :n])
        np.multiply(g.imag, self.weights[n:, None], out=jac[:, n:])
        return (r[0], jac[0]) if single else (r, jac)

    def ratio(self, theta) -> np.ndarray:
        """R = H_model/H_data on every line, at one parameter vector."""
        with np.errstate(all="ignore"):
            return self._model(np.asarray(theta, float)[None, :], False)[0][0]

    def cost(self, theta) -> float:
        """½·mean(r²) at one parameter vector; +inf where the model cannot be evaluated."""
        return float(self.costs(np.asarray(theta, float)[None, :])[0])

    def costs(self, thetas) -> np.ndarray:
        """½·mean(r²) for a stack of parameter vectors (S, p); +inf where not finite."""
        r = self.residual(np.asarray(thetas, float).reshape(-1, self.n_params))
        c = 0.5 * _einsum("si,si->s", r, r) / r.shape[1]
        c[~np.isfinite(c)] = np.inf
        return c


@lru_cache(maxsize=64)
def block_rows(p: int) -> int:
    """Rows per block of the products with a Jacobian of ``p`` columns.  OpenBLAS runs a
    matrix product on several threads above about 2.6e5 multiply-adds (a matrix-vector
    product above 9216 entries), and on a machine whose other cores are busy those threads
    wait for each other (a joint fit ran 5–15x slower); blocks below both limits stay on
    one thread."""
    return int(max(16, min(512, 9216 // max(p, 1), 250_000 // max(p * p, 1))))


def _normal_equations(J: np.ndarray, r: np.ndarray):
    """JᵀJ (S, p, p) and Jᵀr (S, p), summed over blocks of rows (see ``block_rows``)."""
    rows = block_rows(J.shape[2])
    if J.shape[1] <= rows:                       # one block
        jt = J.transpose(0, 2, 1)
        return jt @ J, (jt @ r[..., None])[..., 0]
    a = g = None
    for i in range(0, J.shape[1], rows):
        jb = J[:, i:i + rows]
        jt = jb.transpose(0, 2, 1)
        ab, gb = jt @ jb, (jt @ r[:, i:i + rows, None])[..., 0]
        a, g = (ab, gb) if a is None else (a + ab, g + gb)
    return a, g


def _matvec(J: np.ndarray, x: np.ndarray) -> np.ndarray:
    """J x (S, m), block by block (see ``block_rows``)."""
    rows = block_rows(J.shape[2])
    if J.shape[1] <= rows:
        return (J @ x[..., None])[..., 0]
    return np.concatenate([(J[:, i:i + rows] @ x[..., None])[..., 0]
                           for i in range(0, J.shape[1], rows)], axis=1)


class LevenbergMarquardt:
    """Levenberg–Marquardt on ½·mean(r²) from several starts in lockstep, with box bounds.

    Parameters
    ----------
    evaluator : Evaluator
    starts : array (S, p)
        Initial parameter vectors (clipped into the bounds).
    lb, ub : arrays (p,)
        Bounds (±inf allowed).
    tol : float
        A start has converged when an accepted step lowers the cost by less than ``tol``
        (relative) and the Gauss–Newton model predicts no more, or when every cosine
        between the residual and a free Jacobian column is below ``sqrt(tol)`` (first-order
        optimality, scale-free).  It is *solved to an acceptable level* when the cost fell
        by less than ``ACCEPTABLE_RATE`` (relative) per iteration over the last
        ``ACCEPTABLE_WINDOW`` iterations: a crawl along a nearly flat valley, e.g. a pole and
        a zero drifting together far outside the band. [-]
    margins : array (S,), optional
        Once a start has converged with cost c, a running start whose cost exceeds
        c·(1 + margin) is stopped (status ``Stopped_Early``) if it is more than
        ``BEATEN_RATIO`` above c or would need more than ``CATCH_UP_ITERATIONS`` iterations to
        reach c at its recent rate: a losing start ends early, one still falling fast towards
        c is let through.  A start within ``SAME_ANSWER`` above c has reached the same answer
        and is stopped whatever its margin.  Default 0 for every start.
    trailing_ratio : float, optional
        Also stop a running start while no start has converged yet, when its cost is more
        than ``trailing_ratio`` times the lowest cost of the other running starts and, at the rates both
        fell over their last ``CATCH_UP_WINDOW`` accepted steps, it would need more than
        ``CATCH_UP_ITERATIONS`` iterations to close the gap (status ``Stopped_Early``).  A
        start caught in a poor basin then no longer doubles the cost of every iteration of a
        long race it cannot win.  None (default): starts are compared with converged ones only.

    ``run(k)`` takes at most ``k`` more iterations (every running start advances by one
    trial step per iteration); ``theta``, ``cost``, ``status``, ``converged``,
    ``iterations``, ``time_s`` and ``traces`` describe every start.
    """

    ACCEPTABLE_RATE = 1e-7
    ACCEPTABLE_WINDOW = 10
    CATCH_UP_WINDOW = 5
    CATCH_UP_ITERATIONS = 10
    BEATEN_RATIO = 0.2
    SAME_ANSWER = 1e-6

    def __init__(self, evaluator: Evaluator, starts, lb, ub, tol: float = 1e-10, margins=None,
                 trailing_ratio: float | None = None):
        t0 = time.perf_counter()
        self.trailing_ratio = trailing_ratio
        self.ev, self.tol = evaluator, float(tol)
        x = np.atleast_2d(np.asarray(starts, float))
        S, p = x.shape
        lb, ub = np.asarray(lb, float), np.asarray(ub, float)
        if lb.shape != (p,) or ub.shape != (p,):
            lb, ub = np.broadcast_to(lb, (p,)), np.broadcast_to(ub, (p,))
        width = np.where(np.isfinite(ub - lb), ub - lb, 1.0)
        self.lb, self.ub = lb, ub
        self.theta = np.minimum(np.maximum(x, lb + 1e-9 * width), ub - 1e-9 * width)   # np.clip
        self.margins = np.zeros(S) if margins is None else np.array(margins, float)
        self._r, self._J = evaluator.residual(self.theta, jacobian=True)
        self._m = self._r.shape[1]
        self._rr = (self._r * self._r).sum(axis=1)
        ok = np.isfinite(self._rr) & np.all(np.isfinite(self._J), axis=(1, 2))
        self.cost = np.where(ok, 0.5 * self._rr / self._m, np.inf)
        self.status = [""] * S
        self.converged = np.zeros(S, bool)
        self.running = ok.copy()
        for i in np.flatnonzero(~ok):
            self.status[i] = STATUS_FAILED
        self.iterations = np.zeros(S, int)
        self.traces = [[float(c)] for c in self.cost]
        self._scale = np.zeros((S, p))
        self._bounded = bool(np.isfinite(lb).any() or np.isfinite(ub).any())
        self._mu = np.full(S, np.nan)
        self._nu = np.full(S, 2.0)
        self.time_s = time.perf_counter() - t0

    @property
    def n_starts(self) -> int:
        return self.theta.shape[0]

    def revive(self, i: int) -> None:
        """Let a start that was stopped (or ran out of iterations) run again; it is no longer
        stopped in favour of the others."""
        if self.status[i] in (STATUS_STOPPED, STATUS_MAXITER):
            self.running[i], self.status[i], self.converged[i] = True, "", False
            self.margins[i] = np.inf

    def _end(self, i: int, status: str, converged: bool) -> None:
        self.running[i] = False
        self.status[i] = status
        self.converged[i] = converged

    @one_blas_thread
    def run(self, max_iterations: int, only=None) -> LevenbergMarquardt:
        """Advance the running starts (or those in ``only``) by up to ``max_iterations``."""
        t0 = time.perf_counter()
        allowed = np.ones(self.n_starts, bool) if only is None else np.isin(np.arange(self.n_starts), only)
        left = int(max_iterations)
        # one floating-point context for the whole run: non-finite trial values are rejected
        # by the step control (the evaluator ignores them the same way)
        with np.errstate(all="ignore"):
            while left > 0:
                act = np.flatnonzero(self.running & allowed)
                if act.size == 0:
                    break
                left -= self._iterate(act, left)
        for i in np.flatnonzero(self.running & allowed):
            self.status[i] = STATUS_MAXITER
        self.time_s += time.perf_counter() - t0
        return self

    def _iterate(self, act: np.ndarray, budget: int) -> int:
        """Iterate the starts ``act`` (compacted copies of their state) until one of them
        ends or ``budget`` iterations are used; write the state back; return the count."""
        ev, tol = self.ev, self.tol
        lb, ub = self.lb, self.ub
        bounded = self._bounded
        x, r, J, rr = self.theta[act], self._r[act], self._J[act], self._rr[act]
        scale, mu, nu = self._scale[act], self._mu[act], self._nu[act]
        sqrt_tol = np.sqrt(tol)
        w = self.ACCEPTABLE_WINDOW
        done = 0
        ended = False
        mu_unset = bool(np.isnan(mu).any())         # only before a start's first iteration
        while done < budget and not ended:
            done += 1
            a, g = _normal_equations(J, r)
            diag = _einsum("sii->si", a)                    # a view
            cn = np.sqrt(diag)
            np.maximum(scale, cn, out=scale)
            d = np.where(scale > 0, scale, 1.0)
            cos = np.abs(g) / np.where(cn > 0, cn, 1.0)
            free = None
            if bounded:
                at_bound = (x <= lb) | (x >= ub)
                if at_bound.any():
                    free = ~(at_bound & (((x <= lb) & (g > 0)) | ((x >= ub) & (g < 0))))
                    cos = np.where(free, cos, 0.0)
            stationary = np.maximum.reduce(cos, axis=1) <= sqrt_tol * np.sqrt(rr)
            a /= d[:, :, None] * d[:, None, :]
            b = g / d
            if mu_unset:
                mu = np.where(np.isnan(mu), 1e-3 * np.maximum(diag.max(axis=1), 1e-300), mu)
                mu_unset = False
            if free is None:
                diag += mu[:, None]
            else:
                a = np.where(free[:, :, None] & free[:, None, :], a, 0.0)
                b = np.where(free, b, 0.0)
                np.einsum("sii->si", a)[...] = np.where(free, np.einsum("sii->si", a) + mu[:, None], 1.0)
            # LAPACK gesv as numpy.linalg.solve runs it; a singular system (not expected: μ > 0
            # on a unit diagonal) gives a non-finite step, which the step control rejects
            step = _gesv(a, b[..., None], signature="dd->d")[..., 0]
            step /= -d
            xt = x + step
            if bounded:
                np.maximum(xt, lb, out=xt)
                np.minimum(xt, ub, out=xt)
            dx = xt - x
            lin = r + _matvec(J, dx)
            pred = rr - _einsum("si,si->s", lin, lin)
            rt, jt_new = ev._residual(xt, True)            # the Jacobian serves if accepted
            rrt = _einsum("si,si->s", rt, rt)
            # per-start bookkeeping on Python floats (a few starts: cheaper than array
            # operations, the same numbers)
            acc, mu, nu, end_now, actual = step_control(rr, rrt, pred, stationary, mu, nu, dx)
            if any(end_now):
                for j in [j for j, e in enumerate(end_now) if e]:
                    # first-order optimal, or no decrease along any damped direction
                    self._end(act[j], STATUS_OK, True)
                ended = True
            if any(acc):
                if all(acc):
                    ja = slice(None)
                    x, r, J, rr = xt, rt, jt_new, rrt
                    idx = range(act.size)
                else:
                    ja = np.array([j for j, a in enumerate(acc) if a])
                    x[ja], r[ja], J[ja], rr[ja] = xt[ja], rt[ja], jt_new[ja], rrt[ja]
                    idx = ja
                bad = (~np.isfinite(_einsum("sij->s", jt_new[ja]))).tolist()
                rrt_l, pred_l = rrt.tolist(), pred.tolist()
                for k, j in enumerate(idx):
                    i = act[j]
                    tr = self.traces[i]
                    tr.append(0.5 * rrt_l[j] / self._m)
                    lim = tol * rrt_l[j]
                    if bad[k]:
                        self._end(i, STATUS_FAILED, False)
                    elif actual[j] <= lim and pred_l[j] <= lim:
                        self._end(i, STATUS_OK, True)
                    elif len(tr) > w and tr[-1 - w] - tr[-1] <= w * self.ACCEPTABLE_RATE * tr[-1]:
                        self._end(i, STATUS_ACCEPTABLE, True)
                    else:
                        continue
                    ended = True
            if ended or self.converged.any():
                self.cost[act] = 0.5 * rr / self._m
                ended = self._stop_losers() or ended
            elif self.trailing_ratio is not None and act.size > 1:
                self.cost[act] = 0.5 * rr / self._m
                ended = self._stop_trailing()
        self.theta[act], self._r[act], self._J[act], self._rr[act] = x, r, J, rr
        self._scale[act], self._mu[act], self._nu[act] = scale, mu, nu
        self.cost[act] = 0.5 * rr / self._m
        self.iterations[act] += done
        return done

    def _stop_trailing(self) -> bool:
        """Stop every running start whose cost exceeds ``trailing_ratio`` times the lowest
        cost of the running starts and which, at the rates both fell over their last
        ``CATCH_UP_WINDOW`` accepted steps, would need more than ``CATCH_UP_ITERATIONS``
        iterations to reach it (see ``trailing_ratio``)."""
        run = np.flatnonzero(self.running)
        if run.size < 2:
            return False
        lead = run[np.argmin(self.cost[run])]
        c, w = self.cost[lead], self.CATCH_UP_WINDOW
        tl = self.traces[lead]
        rate_lead = (tl[-1 - w] - tl[-1]) / w if len(tl) > w else 0.0
        stopped = False
        for i in run:
            tr = self.traces[i]
            if i == lead or not self.cost[i] > self.trailing_ratio * c or len(tr) <= w:
                continue
            closing = (tr[-1 - w] - tr[-1]) / w - rate_lead
            if closing <= 0 or self.cost[i] - c > self.CATCH_UP_ITERATIONS * closing:
                self._end(i, STATUS_STOPPED, False)
                stopped = True
        return stopped

    def _stop_losers(self) -> bool:
        """Stop every running start that another start has beaten: one has converged with a
        cost c, the running start's cost exceeds c·(1 + margin), and either exceeds it by more
        than ``BEATEN_RATIO`` or, at the rate it fell over its last ``CATCH_UP_WINDOW``
        steps, would need more than ``CATCH_UP_ITERATIONS`` more iterations to reach c.
        A start within ``SAME_ANSWER`` (relative) above c has reached the same answer and is
        stopped too, whatever its margin."""
        if not self.converged.any() or not self.running.any():
            return False
        c = self.cost[self.converged].min()
        stopped = False
        w = self.CATCH_UP_WINDOW
        for i in np.flatnonzero(self.running):
            if 0.0 < self.cost[i] - c <= self.SAME_ANSWER * c:
                self._end(i, STATUS_STOPPED, False)
                stopped = True
                continue
            gap = self.cost[i] - c * (1.0 + self.margins[i])
            if gap <= 0:
                continue
            tr = self.traces[i]
            rate = (tr[-1 - w] - tr[-1]) / w if len(tr) > w else np.inf
            if gap > self.BEATEN_RATIO * c or gap > self.CATCH_UP_ITERATIONS * rate:
                self._end(i, STATUS_STOPPED, False)
                stopped = True
        return stopped
