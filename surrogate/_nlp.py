"""Residuals, the constrained CasADi/IPOPT solver, outcomes and the covariance.

Residuals compare the model with the data through the ratio R = H_model/H_data:

* ``log``:      (ln|R|, arg R), optionally divided by the per-line standard deviations of
                ln|H| [Np] and arg H [rad] (weighting ``uncertainty``); arg R is the
                principal value, so no phase unwrapping of the data is needed;
* ``relative``: (Re R − 1, Im R), i.e. (H_model − H_data)/H_data.

The objective is ½·mean(r²); the Jacobian of r at the optimum (:mod:`surrogate._lsq`) gives
the Gauss–Newton covariance used for confidence intervals.  Unconstrained fits are solved by
Levenberg–Marquardt in :mod:`surrogate._lsq`; :class:`Solver` (IPOPT) handles the fits that
need constraints.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from physmodel import interrupts
from physmodel.errors import NotConvergedError

from ._structure import CasadiBackend, NumpyBackend, Structure, evaluate, hurwitz_matrix

__all__ = ["ConvergenceError", "Problem", "Solver", "SolveOutcome", "get_solver"]

_OK_STATUSES = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


class ConvergenceError(NotConvergedError):
    """A fit did not converge; ``.result`` holds the flagged result."""

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result


def residual(structure: Structure, theta, w, tau, hr, hi, ia, ib, kind: str, be=NumpyBackend):
    """Weighted residual vector (length 2N) in the backend's type."""
    nr, ni, dr, di = evaluate(structure, theta, w, tau, be)
    pr = dr * hr - di * hi
    pi = dr * hi + di * hr
    qr = nr * pr + ni * pi
    qi = ni * pr - nr * pi
    if kind == "log":
        r1 = 0.5 * (be.log(nr * nr + ni * ni) - be.log(pr * pr + pi * pi))
        r2 = be.atan2(qi, qr)
    else:
        p2 = pr * pr + pi * pi
        r1 = qr / p2 - 1.0
        r2 = qi / p2
    if be is NumpyBackend:
        return np.concatenate([r1 * ia, r2 * ib])
    import casadi as ca

    return ca.vertcat(r1 * ia, r2 * ib)


@dataclass(frozen=True)
class Problem:
    """Everything numeric a fit needs, already scaled.

    ``w`` = ω/ω_ref, ``tau`` scaled temperature, ``h`` = H/g_ref, ``inv_sig_*`` per-line
    residual weights.
    """

    structure: Structure
    w: np.ndarray
    tau: np.ndarray
    h: np.ndarray
    kind: str  # "log" | "relative"
    inv_sig_a: np.ndarray
    inv_sig_b: np.ndarray

    @property
    def n_points(self) -> int:
        return self.w.shape[0]

    @property
    def n_residuals(self) -> int:
        return 2 * self.n_points

    def line_data(self, n_lines: int | None = None) -> np.ndarray:
        """(w̃, τ, Re h, Im h, 1/σ_a, 1/σ_b) of every line, line after line (6N,); padded to
        ``n_lines`` with copies of the first line at zero weight (zero residuals)."""
        d = np.column_stack([self.w, self.tau, self.h.real, self.h.imag,
                             self.inv_sig_a, self.inv_sig_b])
        if n_lines is not None and n_lines > d.shape[0]:
            pad = np.repeat(d[:1], n_lines - d.shape[0], axis=0)
            pad[:, 4:] = 0.0
            d = np.vstack([d, pad])
        return d.ravel()

    def residual(self, theta) -> np.ndarray:
        return residual(self.structure, np.asarray(theta, float), self.w, self.tau, self.h.real,
                        self.h.imag, self.inv_sig_a, self.inv_sig_b, self.kind)

    def cost(self, theta) -> float:
        """½·mean(r²); +inf where the model cannot be evaluated."""
        with np.errstate(all="ignore"):
            r = self.residual(theta)
        if not np.all(np.isfinite(r)):
            return np.inf
        return 0.5 * float(r @ r) / r.shape[0]


@dataclass
class SolveOutcome:
    theta: np.ndarray
    cost: float
    status: str
    converged: bool
    iterations: int
    time_s: float
    objective_trace: list = field(default_factory=list)
    #: ``resume(n)`` continues this solve for up to n more iterations and returns the new
    #: outcome (None when the solver cannot be continued in place)
    resume: object = field(default=None, repr=False, compare=False)


_CACHE: dict = {}
_CACHE_MAX = 64


#: lines per block of the IPOPT problem: the data are padded to whole blocks, so the CasADi
#: graph maps a block function (built once per structure) over ceil(N/BLOCK_LINES) blocks
BLOCK_LINES = 128


@lru_cache(maxsize=64)
def _block_functions(structure: Structure, kind: str):
    """Residuals of one block of ``BLOCK_LINES`` frequency lines, r(θ; data) ∈ R^(2×B) with
    data (w̃, τ, Re h, Im h, 1/σ_a, 1/σ_b) as a 6×B matrix, and the Hessian of ½‖r‖² in θ
    summed over the block, as CasADi functions: one per-line residual and its exact Hessian,
    mapped over the block.  Built once per structure and residual kind; mapping them over
    the blocks of any data set costs little (mapping a p×p output over thousands of single
    lines does not: CasADi's map then costs time proportional to the lines)."""
    import casadi as ca

    x = ca.SX.sym("x", structure.n_params)
    d = ca.SX.sym("d", 6)
    r = residual(structure, x, d[0], d[1], d[2], d[3], d[4], d[5], kind, CasadiBackend())
    line_r = ca.Function("line_residual", [x, d], [r])
    line_h = ca.Function("line_hessian", [x, d], [ca.hessian(0.5 * ca.sumsqr(r), x)[0]])
    xm = ca.MX.sym("x", structure.n_params)
    dm = ca.MX.sym("d", 6, BLOCK_LINES)
    block_r = ca.Function("block_residual", [xm, dm],
                          [line_r.map("lines", "serial", BLOCK_LINES, [0], [])(xm, dm)])
    block_h = ca.Function("block_hessian", [xm, dm],
                          [line_h.map("lines_h", "serial", BLOCK_LINES, [0], [0])(xm, dm)])
    return block_r, block_h


class Solver:
    """IPOPT on ½·mean(r(θ; data)²) with the data as NLP parameters.

    The objective is one per-line residual function mapped over blocks of lines (CasADi
    ``map``, see :func:`_block_functions`), and the Hessian of the Lagrangian is assembled from
    the per-line Hessians the same way, so building a solver costs about the same whatever
    the number of lines; solvers are cached per
    structure, number of lines, residual kind and constraint set (:func:`get_solver`).  The
    fitters use it only where constraints are needed (Levenberg–Marquardt in
    :mod:`surrogate._lsq` does the unconstrained solves).

    ``grid_taus`` (scheduled models): the log pole-section slots (and the 'zpk' zero-section
    slots) are kept inside ``Structure.slot_bounds`` at these scaled temperatures (linear
    constraints), and for the
    ``coefficients`` form with ``hurwitz=True`` the Liénard–Chipart conditions (all
    denominator coefficients > 0 and Hurwitz minors Δ_{n-1}, Δ_{n-3}, … > 0) are imposed there
    on the shifted denominator D(s̃ − ``pole_margin``), i.e. every pole has Re s̃ < −pole_margin
    at the grid temperatures (a margin, so that poles cannot cross the axis between them).
    """

    def __init__(self, structure: Structure, n_points: int, kind: str, *, max_iter: int = 300,
                 tol: float = 1e-10, grid_taus=None, hurwitz: bool = False,
                 hurwitz_margin: float = 1e-4, pole_margin: float = 0.0):
        import casadi as ca

        st = self.structure = structure
        self.n_points = int(n_points)
        n = self.n_points
        self.n_blocks = nb = -(-n // BLOCK_LINES)
        x = ca.MX.sym("x", st.n_params)
        p = ca.MX.sym("p", 6 * nb * BLOCK_LINES)      # line after line, see line_data
        data = ca.reshape(p, 6, nb * BLOCK_LINES)
        block_r, block_h = _block_functions(st, kind)
        r = block_r.map("blocks", "serial", nb, [0], [])(x, data)
        f = 0.5 * ca.sumsqr(r) / (2 * n)
        xs = ca.SX.sym("x", st.n_params)
        g, self._g_kinds = [], []
        taus = np.asarray([] if grid_taus is None else grid_taus, float)
        if taus.size and st.degree > 0:
            nc = st.n_coef
            for s_name in [s for s in st.slots if s.startswith("log_")] + st.zero_slots:
                j = st.slots.index(s_name) * nc
                for tau in taus:
                    g.append(ca.dot(xs[j:j + nc], ca.DM(tau ** np.arange(nc))))
                    self._g_kinds.append(s_name)
        if hurwitz and taus.size:
            if st.form != "coefficients":
                raise ValueError("Hurwitz constraints apply to the 'coefficients' form only")
            h = self._hurwitz_constraints(st, xs, taus, pole_margin)
            g += h
            self._g_kinds += ["hurwitz"] * len(h)
        self.hurwitz_margin = hurwitz_margin
        gs = ca.vertcat(*g) if g else ca.SX(0, 1)
        lam_gs = ca.SX.sym("lam_g", gs.shape[0])
        g_hess = ca.Function("g_hess", [xs, lam_gs], [ca.hessian(ca.dot(lam_gs, gs), xs)[0]
                                                     if g else ca.SX(st.n_params, st.n_params)])
        gx = ca.Function("constraints", [xs], [gs])(x)
        # exact Hessian of the Lagrangian, assembled from per-line Hessians (mapped and summed:
        # differentiating the mapped objective instead costs time proportional to the lines)
        lam_f = ca.MX.sym("lam_f")
        lam_g = ca.MX.sym("lam_g", gs.shape[0])
        h_f = block_h.map("blocks_h", "serial", nb, [0], [0])(x, data) / (2 * n)
        hess = ca.Function("lagrangian_hessian", [x, p, lam_f, lam_g],
                           [ca.triu(lam_f * h_f + g_hess(x, lam_g))],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
        nlp = {"x": x, "p": p, "f": f, "g": gx}
        opts = {
            "print_time": False,
            "error_on_fail": False,
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "ipopt.max_iter": int(max_iter),
            "ipopt.tol": float(tol),
            "ipopt.constr_viol_tol": 1e-9,
            "hess_lag": hess,
        }
        self._solver = ca.nlpsol("surrogate_fit", "ipopt", nlp, opts)

    @staticmethod
    def _hurwitz_constraints(st: Structure, x, taus, shift: float = 0.0):
        from math import comb

        import casadi as ca

        n, nc = st.n_poles, st.n_coef
        # Taylor shift D(s) → D(s − shift): q_i = Σ_{k≥i} a_k C(k, i) (−shift)^(k−i), a_n = 1
        tmat = np.array([[comb(k, i) * (-shift) ** (k - i) if k >= i else 0.0 for k in range(n + 1)]
                         for i in range(n)])
        g = []
        for tau in taus:
            tp = ca.DM(tau ** np.arange(nc))
            a = []
            for j in range(n):
                k = st.slots.index(f"a{j}")
                a.append(ca.dot(x[k * nc:(k + 1) * nc], tp))
            a_all = a + [1.0]
            a = [sum(float(tmat[i, k]) * a_all[k] for k in range(n + 1) if tmat[i, k] != 0.0)
                 for i in range(n)]
            g += a  # Liénard–Chipart: all coefficients positive …
            hm = hurwitz_matrix([1.0] + a[::-1])
            for order in range(n - 1, 1, -2):  # … and Δ_{n-1}, Δ_{n-3}, … positive
                sub = ca.SX(order, order)
                for i in range(order):
                    for j in range(order):
                        sub[i, j] = hm[i][j]
                g.append(ca.det(sub))
        return g

    def solve(self, problem: Problem, theta0) -> SolveOutcome:
        st = self.structure
        w_min, w_max = float(problem.w.min()), float(problem.w.max())
        lbx, ubx = st.bounds(w_min, w_max)
        theta0 = np.clip(np.asarray(theta0, float), lbx + 1e-9, ubx - 1e-9)
        args = {"x0": theta0, "lbx": lbx, "ubx": ubx, "p": problem.line_data(self.n_blocks * BLOCK_LINES)}
        if self._g_kinds:
            sb = st.slot_bounds(w_min, w_max)
            lbg = [sb[k][0] if k in sb else self.hurwitz_margin for k in self._g_kinds]
            ubg = [sb[k][1] if k in sb else np.inf for k in self._g_kinds]
            args["lbg"], args["ubg"] = lbg, ubg
        t0 = time.perf_counter()
        sol = self._solver(**args)
        elapsed = time.perf_counter() - t0
        stats = self._solver.stats()
        interrupts.check()     # CasADi catches Ctrl-C inside IPOPT and reports it as a failed solve
        theta = np.asarray(sol["x"], float).ravel()
        status = str(stats.get("return_status", "unknown"))
        cost = float(sol["f"])
        ok = status in _OK_STATUSES and np.isfinite(cost) and np.all(np.isfinite(theta))
        trace = [float(v) for v in stats.get("iterations", {}).get("obj", [])]
        return SolveOutcome(theta, cost, status, bool(ok), int(stats.get("iter_count", -1)),
                            elapsed, trace)


def get_solver(structure: Structure, n_points: int, kind: str, *, max_iter: int, tol: float,
               grid_taus=None, hurwitz: bool = False, pole_margin: float = 0.0) -> Solver:
    """Cached :class:`Solver` (building one costs far more than solving a small fit)."""
    taus = None if grid_taus is None else tuple(np.round(np.asarray(grid_taus, float), 12))
    key = (structure, int(n_points), kind, int(max_iter), float(tol), taus, bool(hurwitz),
           float(pole_margin))
    solver = _CACHE.get(key)
    if solver is None:
        if len(_CACHE) >= _CACHE_MAX:
            _CACHE.pop(next(iter(_CACHE)))
        solver = Solver(structure, n_points, kind, max_iter=max_iter, tol=tol,
                        grid_taus=taus, hurwitz=hurwitz, pole_margin=pole_margin)
        _CACHE[key] = solver
    return solver


def _r_factor(a: np.ndarray) -> np.ndarray:
    """Triangular factor of a = QR by modified Gram–Schmidt (backward stable for R), with
    element-wise numpy operations only (no BLAS/LAPACK call on the tall matrix)."""
    q = np.array(a.T, dtype=float, order="C")          # columns of a as rows
    p = q.shape[0]
    r = np.zeros((p, p))
    for j in range(p):
        nrm = float(np.sqrt(np.einsum("i,i->", q[j], q[j])))
        r[j, j] = nrm
        if nrm == 0.0:
            continue
        q[j] /= nrm
        if j + 1 < p:
            proj = np.einsum("ij,j->i", q[j + 1:], q[j])
            r[j, j + 1:] = proj
            q[j + 1:] -= proj[:, None] * q[j]
    return r


def covariance(jac: np.ndarray, resid: np.ndarray, scale: bool):
    """Gauss–Newton covariance (JᵀJ)⁻¹·s², s² = reduced χ² when ``scale`` (else 1).

    Returns ``(cov, rank_deficient)``; a rank-deficient Jacobian gives the pseudo-inverse.
    """
    n_res, n_par = jac.shape
    # SVD of the triangular factor R (jac = QR): the same singular values and right vectors,
    # but the only LAPACK call is on the small R.  LAPACK on the tall jac runs matrix-vector
    # products on several OpenBLAS threads, which on a busy machine wait for each other (up to
    # 0.7 s for 4800 x 21, against 2 ms here).
    small = jac.size <= 20_000                  # below OpenBLAS's threading thresholds
    s, vt = np.linalg.svd(jac if small else _r_factor(jac), full_matrices=False)[1:]
    keep = s > s[0] * 1e-12 if s.size else s.astype(bool)
    inv_s2 = np.where(keep, 1.0 / np.where(keep, s, 1.0) ** 2, 0.0)
    cov = (vt.T * inv_s2) @ vt
    dof = n_res - n_par
    s2 = float(resid @ resid) / dof if (scale and dof > 0) else 1.0
    return cov * s2, bool(not keep.all())
