"""Oracle 2 of physics.md §6: the linearised PNP problem solved by finite volumes, vs the closed forms.

The oracle (tests/physmodel/oracles/pnp_fd.py) discretises the coupled equations

    s ρ = d (ρ'' + Q φ''),  Q = F² C⁻/(R T),      κe φ'' = −ρ,      x ∈ [−h, h]

directly (ρ and φ both unknowns, no closed form used) on a wall-clustered grid, second order.
It is compared with ``physmodel.transport``:

(a) blocking electrodes, J(±h) = 0, φ(±h) = ±V/2:
      current into the +h electrode per area, s·σ₊ (σ₊ = κe φ'(h))   vs  θ(s)/(2W)·V
      bending moment per length W ∫ α0 ρ x dx                          vs  −Φ(s)·V
(b) sensing, φ(±h) = 0, ρ(±h) = ±a0σ0:
      D(h) = −κe φ'(h)                                                 vs  a0 σ0 h k(γ)
with K from ``physmodel.transport.debye_rate`` (so the constant K = F² d C⁻/(κe R T) is checked too).

Scaled slices: the real transport constants (d = 3e-11 m²/s, C⁻ = 1000 mol/m³, κe = 1e-6 F/m,
T = 300 K) with h chosen so that γ0 = h sqrt(K/d) ∈ {0.05, 1.5, 12, 30}, i.e. the series branch of
γ − tanh γ (|γ| < 0.1), the tanh branch (Re γ ≤ 20) and the tanh γ = 1 branch (Re γ > 20) of
``physmodel.numerics`` are all exercised; γ0 = 30 puts a resolvable Debye layer (λ = h/30) at each wall.
Laplace points from s = 1e-3 K/γ0 (double-layer regime) through the corner K/γ0 to s = 3jK, plus a
real s and a complex s off the imaginary axis.

Tolerances (measured on this grid family, see the final report):
* observed order between N = 100, 200, 400 must lie in [1.9, 2.1] (the scheme is second order and
  the measured orders are 1.9987–2.0001 for every quantity and point);
* the Richardson extrapolation (4 Q_400 − Q_200)/3 must match the closed form to 1e-7 relative
  (measured ≤ 1.1e-8: 7-8 digits, far beyond any plausible constant/sign/factor-2 error);
* the raw N = 400 error must be below 2e-3 (measured ≤ 8.6e-5; N = 100: ≤ 1.4e-3).
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np
import pytest

_HERE = pathlib.Path(__file__).resolve().parent
if str(_HERE) not in sys.path:
    sys.path.insert(0, str(_HERE))

from oracles.pnp_fd import blocking_response, material_for_gamma0, sensing_response, solve_slice  # noqa: E402

from physmodel import transport  # noqa: E402

GRIDS = (100, 200, 400)
ORDER_RANGE = (1.9, 2.1)
RICHARDSON_RTOL = 1e-7
RAW_RTOL = 2e-3
ALPHA0 = -0.7           # J/C, any non-zero value (tests the α0 factor and the sign)
RHO0 = 3.0e4            # C/m³, Dirichlet boundary charge a0·σ0 for the sensing problem

# (γ0, grid stretching a): a = 0 is a uniform grid (nothing to resolve at γ0 = 0.05)
CASES = [(0.05, 0.0), (1.5, 1.0), (12.0, 2.5), (30.0, 3.0)]


def _s_points(g0, K):
    """Laplace points [1/s] as multiples of K: ≪ K/γ0, around K/γ0, up to 3K, and off-axis."""
    mult = [1e-3j / g0, 0.1j / g0, 1j / g0, 10j / g0, 1j, 3j, (1 + 1j) / g0, 1.0 / g0]
    return [m * K for m in mult]


def _closed_forms(mat, K, s):
    c = transport.charge_terms(np.array([s]), mat.h, mat.d, K)
    theta = transport.polymer_admittance(mat.W, mat.h, mat.kappa_e, c)[0]
    phi = transport.moment_coupling(mat.W, mat.kappa_e, ALPHA0, K, c)[0]
    k = transport.boundary_charge_kernel(c)[0]
    return {"current": theta / (2.0 * mat.W), "moment": -phi, "D": RHO0 * mat.h * k}


def _fd_values(mat, s, n, stretch):
    current, moment, _ = blocking_response(mat, s, n, stretch, V=1.0, alpha0=ALPHA0)
    D, _ = sensing_response(mat, s, n, stretch, rho0=RHO0)
    return {"current": current, "moment": moment, "D": D}


@pytest.fixture(scope="module", params=CASES, ids=lambda c: f"gamma0={c[0]:g}")
def sweep(request):
    """FD values on three grids and the closed forms, for every Laplace point of one γ0."""
    g0, stretch = request.param
    mat, _ = material_for_gamma0(g0)
    K = float(transport.debye_rate(mat.d, mat.C_minus, mat.kappa_e, mat.T))
    rows = []
    for s in _s_points(g0, K):
        fd = {n: _fd_values(mat, s, n, stretch) for n in GRIDS}
        rows.append((s, fd, _closed_forms(mat, K, s)))
    return g0, mat, K, rows


def test_scaled_slice_has_requested_gamma0(sweep):
    g0, mat, K, _ = sweep
    assert mat.h * np.sqrt(K / mat.d) == pytest.approx(g0, rel=1e-12)


@pytest.mark.parametrize("quantity", ["current", "moment", "D"])
def test_fd_converges_to_closed_form_at_second_order(sweep, quantity):
    g0, mat, K, rows = sweep
    for s, fd, exact in rows:
        ref = exact[quantity]
        errs = np.array([abs(fd[n][quantity] / ref - 1.0) for n in GRIDS])
        orders = np.log2(errs[:-1] / errs[1:])
        where = f"{quantity} at gamma0={g0}, s/K={s / K:.3g}: errors {errs}, orders {orders}"
        assert np.all(errs[1:] < errs[:-1]), where
        assert np.all((orders > ORDER_RANGE[0]) & (orders < ORDER_RANGE[1])), where
        assert errs[-1] < RAW_RTOL, where
        rich = (4.0 * fd[GRIDS[-1]][quantity] - fd[GRIDS[-2]][quantity]) / 3.0
        assert abs(rich / ref - 1.0) < RICHARDSON_RTOL, where + f", Richardson {abs(rich / ref - 1.0):.3e}"


def test_fd_detects_a_wrong_closed_form(sweep):
    """The comparison has teeth: a factor-of-2 slip in θ, a sign slip in Φ, or k(γ) with tanh γ := 1
    (wrong for small γ) are all rejected by the tolerance used above."""
    g0, mat, K, rows = sweep
    for s, fd, exact in rows:
        rich = {q: (4.0 * fd[400][q] - fd[200][q]) / 3.0 for q in exact}
        assert abs(rich["current"] / (2.0 * exact["current"]) - 1.0) > 0.4
        assert abs(rich["moment"] / (-exact["moment"]) - 1.0) > 1.9
        if g0 < 2:
            g = mat.h * np.sqrt((s + K) / mat.d)
            k_bad = (g - 1.0) / g**2
            assert abs(rich["D"] / (RHO0 * mat.h * k_bad) - 1.0) > 1e-3


@pytest.mark.parametrize("g0, stretch", [CASES[1], CASES[3]])
def test_oracle_self_consistency(g0, stretch):
    """The FD solution itself: ρ odd and φ odd (symmetric drive), total charge zero (blocking walls
    conserve it exactly in the finite-volume form), equal and opposite electrode charges, and the
    identity κe φ'(h)·2h = κe V − ∫ x ρ dx (Green's identity for the symmetric solution) to
    discretisation error."""
    mat, K = material_for_gamma0(g0)
    s_hat = mat.s_hat(0.5j * K / g0)
    sol = solve_slice(s_hat, mat.q, 400, stretch)
    scale = np.max(np.abs(sol.rho))
    np.testing.assert_allclose(sol.rho, -sol.rho[::-1], atol=1e-10 * scale)
    np.testing.assert_allclose(sol.phi, -sol.phi[::-1], atol=1e-10)  # |φ| ≤ 1/2; solver roundoff ~1e-11
    vol = np.empty_like(sol.x)
    vol[1:-1] = 0.5 * (sol.x[2:] - sol.x[:-2])
    vol[0], vol[-1] = 0.5 * (sol.x[1] - sol.x[0]), 0.5 * (sol.x[-1] - sol.x[-2])
    assert abs(np.sum(vol * sol.rho)) < 1e-11 * scale
    assert sol.dphi_wall == pytest.approx(sol.dphi_wall_minus, rel=1e-10)
    xr = sol.rho * sol.x
    first_moment = np.sum(0.5 * (xr[1:] + xr[:-1]) * np.diff(sol.x))
    assert 2.0 * sol.dphi_wall == pytest.approx(1.0 - first_moment, rel=1e-3)
