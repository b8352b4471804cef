"""Finite-volume solver of the linearised Poisson-Nernst-Planck problem through the thickness.

Written from the PDEs, not from the closed forms of ``physmodel.transport``.

Physics (one slice, x ∈ [−h, h], small perturbation around the neutral state C⁺ = C⁻):

    cation flux          J = −d (∂C⁺/∂x + (C⁺ F/(R T)) ∂φ/∂x)      (seed 002 eq. 3, no pressure term)
    continuity           ∂C⁺/∂t = −∂J/∂x                            (eq. 2)
    Gauss                κe ∂²φ/∂x² = −ρ,   ρ = F (C⁺ − C⁻)          (eq. 1)

Linearising C⁺ ≈ C⁻ in the migration term and multiplying the continuity equation by F gives, in
the Laplace domain (charge flux J_q = F J = −d (ρ' + Q φ'), Q = F² C⁻/(R T)):

    s ρ = d (ρ'' + Q φ''),      κe φ'' = −ρ.

The two equations are kept coupled (φ is an unknown, not eliminated).  Non-dimensionalising
with x = h x̂, s = (d/h²) ŝ, φ = Φs φ̂, ρ = (κe Φs/h²) ρ̂ gives

    ŝ ρ̂ = ρ̂'' + q φ̂'',   φ̂'' = −ρ̂,   q = Q h²/κe  (= γ0², but computed here from F, R, T, C⁻).

Discretisation: vertex-centred finite volumes on a wall-clustered grid x̂_i = tanh(a ξ_i)/tanh a,
ξ uniform on [−1, 1] (N intervals).  Face fluxes (u_{i+1} − u_i)/(x̂_{i+1} − x̂_i), control volumes
V_i = (x̂_{i+1} − x̂_{i−1})/2 (half cells at the walls).  On a smoothly mapped grid this is second
order in 1/N.  The electrode charge is taken from the half-cell Gauss balance at the wall (so it is
second order too), integrals by the trapezoidal rule (second order on the mapped grid).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy import constants

FARADAY = constants.physical_constants["Faraday constant"][0]
R_GAS = constants.R


def clustered_grid(n: int, stretch: float) -> np.ndarray:
    """n + 1 nodes on [−1, 1], clustered at both walls (x̂ = tanh(a ξ)/tanh a)."""
    xi = np.linspace(-1.0, 1.0, n + 1)
    if stretch == 0:
        return xi
    return np.tanh(stretch * xi) / np.tanh(stretch)


def _trapezoid(y, x):
    return np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x))


@dataclass(frozen=True)
class SliceSolution:
    x: np.ndarray          # dimensionless nodes x̂
    rho: np.ndarray        # dimensionless charge density ρ̂
    phi: np.ndarray        # dimensionless potential φ̂
    dphi_wall: complex     # dφ̂/dx̂ at x̂ = +1 from the half-cell Gauss balance
    dphi_wall_minus: complex  # dφ̂/dx̂ at x̂ = −1
    flux_wall: complex     # discrete charge flux −(ρ̂' + q φ̂') through the last interior face


def solve_slice(s_hat: complex, q: float, n: int, stretch: float, *, rho_wall=None,
                phi_wall=(-0.5, 0.5)) -> SliceSolution:
    """Solve ŝ ρ = ρ'' + q φ'', φ'' = −ρ on [−1, 1].

    ``phi_wall`` = (φ̂(−1), φ̂(+1)).  ``rho_wall`` None: blocking walls (zero charge flux);
    else (ρ̂(−1), ρ̂(+1)) Dirichlet values (sensing problem).
    Unknown vector: [ρ_0..ρ_n, φ_0..φ_n].
    """
    x = clustered_grid(n, stretch)
    m = n + 1
    dx = np.diff(x)                         # face spacings, length n
    vol = np.empty(m)
    vol[1:-1] = 0.5 * (x[2:] - x[:-2])
    vol[0] = 0.5 * dx[0]
    vol[-1] = 0.5 * dx[-1]
    gface = 1.0 / dx                        # face "conductances"

    rows, cols, vals = [], [], []
    rhs = np.zeros(2 * m, dtype=complex)

    def add(r, c, v):
        rows.append(r)
        cols.append(c)
        vals.append(v)

    R = lambda i: i          # noqa: E731  index of ρ_i
    P = lambda i: m + i      # noqa: E731  index of φ_i

    # --- Nernst-Planck (charge conservation) in every control volume:
    #     ŝ ρ_i V_i − Σ_faces g (ρ_nb − ρ_i + q (φ_nb − φ_i)) = 0   (wall faces: zero flux)
    for i in range(m):
        eq = R(i)
        if rho_wall is not None and i in (0, m - 1):
            add(eq, R(i), 1.0)
            rhs[eq] = rho_wall[0] if i == 0 else rho_wall[1]
            continue
        add(eq, R(i), s_hat * vol[i])
        for nb, g in ((i - 1, gface[i - 1] if i > 0 else None), (i + 1, gface[i] if i < m - 1 else None)):
            if g is None:
                continue
            add(eq, R(i), g)
            add(eq, R(nb), -g)
            add(eq, P(i), q * g)
            add(eq, P(nb), -q * g)
    # --- Gauss: Σ_faces g (φ_nb − φ_i) + ρ_i V_i = 0 inside; Dirichlet φ at the walls
    for i in range(m):
        eq = P(i)
        if i == 0 or i == m - 1:
            add(eq, P(i), 1.0)
            rhs[eq] = phi_wall[0] if i == 0 else phi_wall[1]
            continue
        for nb, g in ((i - 1, gface[i - 1]), (i + 1, gface[i])):
            add(eq, P(nb), g)
            add(eq, P(i), -g)
        add(eq, R(i), vol[i])

    A = sp.csc_matrix((np.asarray(vals, dtype=complex), (rows, cols)), shape=(2 * m, 2 * m))
    sol = spla.spsolve(A, rhs)
    rho, phi = sol[:m], sol[m:]
    # half-cell Gauss balance at x̂ = +1:  φ'(1) − (φ_n − φ_{n−1})/Δ = −ρ_n V_n
    dphi_p = (phi[-1] - phi[-2]) / dx[-1] - rho[-1] * vol[-1]
    # at x̂ = −1:  (φ_1 − φ_0)/Δ − φ'(−1) = −ρ_0 V_0
    dphi_m = (phi[1] - phi[0]) / dx[0] + rho[0] * vol[0]
    flux = -((rho[-1] - rho[-2]) + q * (phi[-1] - phi[-2])) / dx[-1]
    return SliceSolution(x, rho, phi, dphi_p, dphi_m, flux)


@dataclass(frozen=True)
class Material:
    """Physical slice parameters (SI)."""

    h: float        # half-thickness [m]
    d: float        # diffusivity [m²/s]
    C_minus: float  # [mol/m³]
    kappa_e: float  # [F/m]
    T: float        # [K]
    W: float = 1.0  # width [m]

    @property
    def Q(self) -> float:
        """F² C⁻/(R T) [C²/(J m³)] — coefficient of the migration term in the charge flux."""
        return FARADAY**2 * self.C_minus / (R_GAS * self.T)

    @property
    def q(self) -> float:
        """Dimensionless migration coefficient Q h²/κe."""
        return self.Q * self.h**2 / self.kappa_e

    def s_hat(self, s):
        return s * self.h**2 / self.d


def blocking_response(mat: Material, s: complex, n: int, stretch: float, V: float = 1.0,
                      alpha0: float = 1.0):
    """Blocking electrodes, φ(±h) = ±V/2.

    Returns ``(current_per_area, moment_per_length, sol)``:
    current into the +h electrode per unit area, s·σ₊ with σ₊ = κe φ'(h) (the electrode charge,
    i.e. minus the normal displacement D·n̂ on the polymer side), and W ∫ α0 ρ x dx.
    """
    sol = solve_slice(mat.s_hat(s), mat.q, n, stretch, phi_wall=(-0.5 * V, 0.5 * V))
    # back to SI: φ = φ̂ (V already carried in phi_wall), ρ = κe ρ̂ / h², x = h x̂
    sigma_plus = mat.kappa_e * sol.dphi_wall / mat.h
    current = s * sigma_plus
    moment = mat.W * alpha0 * mat.kappa_e * _trapezoid(sol.rho * sol.x, sol.x)
    return current, moment, sol


def sensing_response(mat: Material, s: complex, n: int, stretch: float, rho0: float = 1.0):
    """Short-circuited faces φ(±h) = 0 with Dirichlet charge ρ(±h) = ±ρ0.

    Returns ``(D_wall, sol)``: the electric displacement at the +h face, D(h) = −κe φ'(h) [C/m²]
    (equal to the charge collected on the −h electrode; the +h electrode carries −D(h)).
    """
    sol = solve_slice(mat.s_hat(s), mat.q, n, stretch, rho_wall=(-rho0, rho0), phi_wall=(0.0, 0.0))
    # scales: ρ = ρ0 ρ̂ (ρ0 in rho_wall), φ = (h²/κe) φ̂, so φ'(h) = (h/κe) φ̂'(1)
    D = -mat.kappa_e * (mat.h / mat.kappa_e) * sol.dphi_wall
    return D, sol


def material_for_gamma0(gamma0: float, *, d=3e-11, C_minus=1000.0, kappa_e=1e-6, T=300.0, W=4e-3):
    """Scaled slice: the physical transport constants, with h chosen so that h sqrt(K/d) = γ0."""
    K = FARADAY**2 * d * C_minus / (kappa_e * R_GAS * T)
    h = gamma0 * np.sqrt(d / K)
    return Material(h=h, d=d, C_minus=C_minus, kappa_e=kappa_e, T=T, W=W), K
