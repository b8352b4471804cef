"""Discretised two-rail electrode network (RC ladder) for the distributed-electrode IPMC model.

Independent of ``physmodel.electrode``/``physmodel.numerics``: the line is not solved in closed
form but as a linear circuit.  The strip z ∈ [0, L] is cut into N cells of length Δz = L/N; the
cell centres z_i = (i − ½) Δz carry one node on each electrode (top rail u_i, bottom rail l_i):

    rail resistors   r1 Δz between adjacent nodes of the same rail, r1 Δz/2 from the terminal
                     (z = 0) to node 1; the rails end open at z = L (no resistor after node N);
    shunt            admittance Y Δz between u_i and l_i, Y = (A/2) per unit length
                     (polymer + 2 r2 in series, parallel to the leakage Rp; midpoint rule);
    sources          optional current sources J(z_i) Δz injected into u_i and drawn from l_i
                     (Norton equivalents of the slices, sensing).

This cell-centred (midpoint) discretisation is second order in Δz.  The slice physics (θ, A,
frac, Φ, k) are evaluated here from their own closed forms (seed 002 eq. 11 structure re-derived
per slice), in plain numpy, independent of the code under test.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded


def slice_terms(s, *, h, d, K, W, kappa_e, alpha0, r2, Rp):
    """Per-unit-length slice quantities at complex s (plain numpy; γ = h sqrt((s+K)/d)).

    Returns dict: theta (half-slice admittance per length), Y (slice admittance per length between
    the electrodes), frac (polymer share of the slice voltage), Phi (moment per length per polymer
    volt), k (boundary-charge kernel).
    """
    s = np.asarray(s, dtype=complex)
    g = np.sqrt((s + K) / d) * h
    t = np.tanh(g)                       # safe for huge Re g (returns 1)
    theta = s * W * kappa_e * g * (s + K) / (h * (s * g + K * t))
    z_branch = 2.0 / theta + 2.0 * r2    # two polymer halves + the contact resistance of each electrode
    Y = 1.0 / z_branch + (0.0 if np.isinf(Rp) else 1.0 / Rp)
    frac = (2.0 / theta) / z_branch
    Phi = alpha0 * W * kappa_e * K * (g - t) / (s * g + K * t)
    k = (g - t) / (g * g * t)
    return {"theta": theta, "Y": Y, "frac": frac, "Phi": Phi, "k": k}


def solve_two_rail(n, L, r1, Y, *, v_top=0.5, v_bottom=-0.5, source=None):
    """Solve the two-rail ladder at one frequency.

    ``Y`` shunt admittance per unit length (complex scalar), ``source`` None or an array of n
    current densities J(z_i) [A/m] injected into the top rail.  Terminal potentials v_top/v_bottom.
    Returns ``(z, u, l, I_top)`` with I_top the current flowing from the top terminal into the
    strip (for a short-circuited sensor, −I_top is the output current).  I_top is summed by
    Kirchhoff's current law over the cells (shunt currents minus injected source currents), which
    avoids the cancellation in g·(v_top − u_1) when r1 is tiny.
    """
    dz = L / n
    z = (np.arange(n) + 0.5) * dz
    if r1 == 0:
        raise ValueError("ladder oracle needs r1 > 0 (r1 = 0 is the trivial uniform case)")
    g_seg = 1.0 / (r1 * dz)              # conductance between adjacent nodes
    g_end = 2.0 * g_seg                  # half segment to the terminal
    ys = Y * dz
    # unknown ordering: [u_1, l_1, u_2, l_2, ...]; banded storage with 2 sub/super-diagonals
    m = 2 * n
    ab = np.zeros((5, m), dtype=complex)
    rhs = np.zeros(m, dtype=complex)

    def put(r, c, v):
        ab[2 + r - c, c] += v

    for i in range(n):
        for rail, other in ((2 * i, 2 * i + 1), (2 * i + 1, 2 * i)):
            # shunt to the other rail
            put(rail, rail, ys)
            put(rail, other, -ys)
            # rail resistor towards the terminal
            if i == 0:
                put(rail, rail, g_end)
                rhs[rail] += g_end * (v_top if rail % 2 == 0 else v_bottom)
            else:
                put(rail, rail, g_seg)
                put(rail, rail - 2, -g_seg)
            # rail resistor towards the open end
            if i < n - 1:
                put(rail, rail, g_seg)
                put(rail, rail + 2, -g_seg)
        if source is not None:
            rhs[2 * i] += source[i] * dz
            rhs[2 * i + 1] -= source[i] * dz
    sol = solve_banded((2, 2), ab, rhs)
    u, lo = sol[0::2], sol[1::2]
    cell = ys * (u - lo)
    if source is not None:
        cell = cell - source * dz
    I_top = np.sum(cell)
    return z, u, lo, I_top


def actuator_ladder(n, s, *, L, r1, E, I2, **slice_kw):
    """Terminal impedance and quasi-static tip deflection per volt from the ladder, at points s."""
    Z = np.empty(len(s), dtype=complex)
    H = np.empty(len(s), dtype=complex)
    for j, sj in enumerate(s):
        sl = slice_terms(sj, **slice_kw)
        z, u, lo, I = solve_two_rail(n, L, r1, sl["Y"], v_top=0.5, v_bottom=-0.5)
        Z[j] = 1.0 / I
        vp = sl["frac"] * (u - lo)                   # polymer voltage of each slice
        m = -sl["Phi"] * vp                          # bending moment per length
        H[j] = np.sum((L - z) * m) * (L / n) / (E * I2)   # midpoint rule for ∫ (L − z) m dz / EI
    return Z, H


def sensor_ladder(n, s, *, L, r1, E, a0, kernel="boundary_charge", **slice_kw):
    """Short-circuit current per unit imposed tip displacement, distributed Norton sources.

    boundary_charge: slice current per length s W D(z), D = a0 σ(z) h k(γ), σ = 3 E h (L − z)/L³
    per unit tip displacement; reciprocal: s Φ κ(z) with curvature κ = 3 (L − z)/L³ per unit tip
    displacement, with the sign of the Onsager dual (−).  Each source reaches the rails through
    r2: J = frac · i_p.
    """
    W, h = slice_kw["W"], slice_kw["h"]
    S = np.empty(len(s), dtype=complex)
    for j, sj in enumerate(s):
        sl = slice_terms(sj, **slice_kw)
        dz = L / n
        z = (np.arange(n) + 0.5) * dz
        if kernel == "boundary_charge":
            sigma = 3.0 * E * h * (L - z) / L**3
            ip = sj * W * a0 * sigma * h * sl["k"]
        else:
            ip = -sj * sl["Phi"] * 3.0 * (L - z) / L**3
        _, _, _, I_top = solve_two_rail(n, L, r1, sl["Y"], v_top=0.0, v_bottom=0.0, source=sl["frac"] * ip)
        S[j] = -I_top
    return S
