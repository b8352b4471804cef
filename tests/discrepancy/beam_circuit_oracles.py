"""Direct-solution oracles for two hidden effects (issue 11): no modes, no closed forms.

* :func:`fe_cantilever_tip` — a finite-element Euler–Bernoulli cantilever (Hermite cubic elements,
  consistent mass, Rayleigh damping C = a M + b K) under a distributed active bending moment m(z),
  solved directly in the frequency domain: the reference for the second bending mode (modal
  participation of a uniform or decaying moment).
* :func:`ladder_with_series` — the electrode line as a two-rail resistor ladder with a shunt slice
  admittance at every node, driven through an arbitrary series element (a constant-phase element),
  solved by nodal analysis: the reference for the series CPE divider and the terminal impedance.

Neither imports ``physmodel`` nor ``independent_physics``; both are plain numpy/scipy linear algebra,
so the closed forms they check (and the library's future effects) can be compared with them.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded


def _solve_band(A, b, w):
    """Solve A x = b for a matrix with half-bandwidth ``w`` (all other entries zero)."""
    n = A.shape[0]
    ab = np.zeros((2 * w + 1, n), dtype=A.dtype)
    for k in range(-w, w + 1):
        d = np.diagonal(A, k)
        if k >= 0:
            ab[w - k, k:] = d
        else:
            ab[w - k, :n + k] = d
    return solve_banded((w, w), ab, b)


# --------------------------------------------------------------------------- beam
def _hermite_d2(zeta, le):
    """Second z-derivatives of the Hermite shape functions (w1, θ1, w2, θ2) at ζ ∈ [0, 1]."""
    return np.stack([(-6 + 12 * zeta) / le**2, (-4 + 6 * zeta) / le, (6 - 12 * zeta) / le**2, (-2 + 6 * zeta) / le])


def fe_cantilever_tip_modal(s_values, moment, zetas, *, n_el=80, L=1.0, EI=1.0, rhoA=1.0, gauss=6):
    """As :func:`fe_cantilever_tip` with a modal damping matrix instead of Rayleigh's:
    C = M Φ diag(2 ζ_k ω_k) Φᵀ M over the FE modes Φ (Mᵀ-orthonormal, scipy.linalg.eigh), mode k
    damped by ``zetas(k)`` (k = 0 the first mode) — Clough & Penzien, Dynamics of Structures, eq. 12-38.
    Solved directly (dense) at each s; returns ``(tip, tip_static)``."""
    from scipy.linalg import eigh

    K, M, f = _fe_system(moment, n_el, L, EI, rhoA, gauss)
    w2, Phi = eigh(K, M)
    w = np.sqrt(w2)
    z = np.array([zetas(k) for k in range(w.size)])
    MP = M @ Phi
    C = MP @ np.diag(2 * z * w) @ MP.T
    tip_static = np.linalg.solve(K.astype(complex), f)[-2]
    tip = np.array([np.linalg.solve(K + s * C + s * s * M, f)[-2] for s in np.atleast_1d(s_values)])
    return tip, tip_static


def _fe_system(moment, n_el, L, EI, rhoA, gauss):
    """Clamped (K, M, f) of the Hermite-element cantilever under the active moment ``moment(z)``."""
    le = L / n_el
    ke = EI / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    me = rhoA * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                     [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    n = 2 * (n_el + 1)
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    f = np.zeros(n, dtype=complex)
    t, w = np.polynomial.legendre.leggauss(gauss)
    zq, wq = (t + 1) / 2, w / 2
    for e in range(n_el):
        idx = slice(2 * e, 2 * e + 4)
        K[idx, idx] += ke
        M[idx, idx] += me
        m = np.asarray(moment(e * le + le * zq), dtype=complex)
        f[idx] += _hermite_d2(zq, le) @ (m * wq) * le
    return K[2:, 2:], M[2:, 2:], f[2:]


def fe_cantilever_tip(s_values, moment, *, n_el=80, L=1.0, EI=1.0, rhoA=1.0, rayleigh=(0.0, 0.0), gauss=6):
    """Tip deflection of a clamped-free Euler–Bernoulli beam driven by the active moment ``moment(z)``.

    Parameters
    ----------
    s_values : array_like  Laplace points (s = jω). [1/s]
    moment : callable  m(z) for z in [0, L], the active bending moment per unit width (curvature
        EI w'' = m at a free section; constant m gives w(L) = m L²/(2 EI)). [N·m]
    n_el : int  number of elements.
    rayleigh : (a, b)  damping C = a M + b K; mode n then has ζ_n = a/(2ω_n) + b ω_n/2.

    Returns
    -------
    (tip, tip_static) : complex ndarray per s, and the static (s = 0) tip deflection. [m]
    """
    le = L / n_el
    ke = EI / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    me = rhoA * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                     [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    n = 2 * (n_el + 1)
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    f = np.zeros(n, dtype=complex)
    t, w = np.polynomial.legendre.leggauss(gauss)
    zq, wq = (t + 1) / 2, w / 2
    for e in range(n_el):
        idx = slice(2 * e, 2 * e + 4)
        K[idx, idx] += ke
        M[idx, idx] += me
        m = np.asarray(moment(e * le + le * zq), dtype=complex)
        f[idx] += _hermite_d2(zq, le) @ (m * wq) * le       # f_i = ∫ m N_i'' dz
    K, M, f = K[2:, 2:], M[2:, 2:], f[2:]                     # clamp: w = θ = 0 at z = 0
    C = rayleigh[0] * M + rayleigh[1] * K
    tip_static = _solve_band(K.astype(complex), f, 3)[-2]
    tip = np.array([_solve_band(K + s * C + s * s * M, f, 3)[-2] for s in np.atleast_1d(s_values)])
    return tip, tip_static


# --------------------------------------------------------------------------- electrode ladder
def ladder_with_series(y, r1, L, n, z_series=None, V=1.0):
    """Two-rail ladder at one frequency: nodes z_k = k L/n (k = 0…n) on each electrode.

    Rails: resistors r1·L/n between neighbouring nodes.  Shunts: y·L/n between the two nodes of a
    station (half at the two ends; trapezoid rule).  The bottom terminal (z = 0) is ground; the top
    terminal is driven by V through ``z_series`` (None: directly).  Returns ``(Z_in, z, v)``: the
    input impedance V/I [Ω], node positions [m] and slice voltages u_k − l_k [V].
    """
    dz = L / n
    g = 1.0 / (r1 * dz)
    wts = np.full(n + 1, dz)
    wts[[0, -1]] = dz / 2
    ysh = y * wts
    # unknowns interleaved u_0, u_1, l_1, u_2, l_2, … (l_0 = 0 is ground): half-bandwidth 2
    A = np.zeros((2 * n + 1, 2 * n + 1), dtype=complex)
    b = np.zeros(2 * n + 1, dtype=complex)

    def ui(k):
        return 0 if k == 0 else 2 * k - 1

    def li(k):                                   # k >= 1
        return 2 * k

    for k in range(n + 1):
        for kk in (k - 1, k + 1):                # rail neighbours
            if 0 <= kk <= n:
                A[ui(k), ui(k)] += g
                A[ui(k), ui(kk)] -= g
                if k >= 1:
                    A[li(k), li(k)] += g
                    if kk >= 1:
                        A[li(k), li(kk)] -= g
        A[ui(k), ui(k)] += ysh[k]                # shunt u_k — l_k
        if k >= 1:
            A[ui(k), li(k)] -= ysh[k]
            A[li(k), li(k)] += ysh[k]
            A[li(k), ui(k)] -= ysh[k]
    if z_series is None:
        A[0, :] = 0
        A[0, 0] = 1
        b[0] = V
    else:
        A[0, 0] += 1.0 / z_series
        b[0] = V / z_series
    x = _solve_band(A, b, 2)
    u = x[[ui(k) for k in range(n + 1)]]
    lo = np.concatenate([[0.0], x[[li(k) for k in range(1, n + 1)]]])
    I_in = g * (u[0] - u[1]) + ysh[0] * (u[0] - lo[0])       # current leaving the top terminal node
    return V / I_in, np.arange(n + 1) * dz, u - lo
