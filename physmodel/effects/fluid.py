"""A cantilever strip in a viscous fluid: Sader's hydrodynamic function (discrepancy.md §3).

Sader (1998, J. Appl. Phys. 84:64) writes the load of the fluid on a beam of width b vibrating at
ω as a frequency-dependent added mass and damping per unit length,

    F_hydro = (π/4) ρ_f ω² b² Γ(ω) W(x, ω)        (his eq. 10, time factor e^{−iωt}),

with the Reynolds number Re = ρ_f ω b²/(4 η) = ω b²/(4 ν) (ν = η/ρ_f the kinematic viscosity) and

    Γ_circ(Re) = 1 + 4i K1(−i√(iRe)) / (√(iRe) K0(−i√(iRe)))          (eq. 19, exact, a cylinder)
    Γ_rect(Re) = Ω(Re) Γ_circ(Re)                                     (eq. 20, a thin rectangle)

where Ω = Ω_r + iΩ_i is his rational fit in τ = log10 Re (eq. 21, fitted over 1e-6 ≤ Re ≤ 1e4;
outside it τ is held at the end of that range: Ω(1e4) = 1.014 + 0.006i where the exact thin-plate
limit is 1, so the added mass above Re = 1e4 carries up to 1.5 % of error — below the fluid's
effect on ωn that a free ωn absorbs anyway).
Re Γ is the added mass over the inviscid mass of the fluid cylinder of diameter b (→ 1 as Re → ∞:
the potential-flow added mass π ρ_f b²/4 of a flat plate), Im Γ the viscous damping.  With this
package's e^{+st} convention Γ is conjugated.

The load is uniform along the beam, so every mode keeps its shape and its modal mass is multiplied
by 1 + μ Γ*(Re(ω)), μ = π ρ_f W/(8 ρ h) the inviscid added mass over the strip's own mass per
length ρ·2h·W (Sader's assumption: L ≫ W, small amplitude, incompressible fluid).  For the unit-DC-
gain mode of :mod:`physmodel.beam` that is

    g = 1/(1 + 2ξ s/ωn + m (s/ωn)²) = beam.first_mode(s √m, ωn, ξ/√m),   m = 1 + μ Γ*(Re(ω)),

the beam sub-model evaluated at a scaled frequency (exact, either branch of √m).  The kinematic
viscosity follows an Andrade (Arrhenius) law ν(T) = ν_ref / Arrhenius(E_η).factor(T, T_ref): the
fluidity of a liquid rises with temperature like a diffusivity (water E_η ≈ 16 kJ/mol, glycerol
≈ 60 kJ/mol, from their tabulated viscosities at 20 and 50 °C).  The fluid density is held
constant (water changes by 1.2 % from 20 to 55 °C).

Parametrisation.  With a free ωn the inviscid added mass is invisible and, at Re ≫ 1, the load
that remains is the Stokes boundary layer's, μ (Γ − 1) ∝ ρ_f √ν/√ω: the data determine
√(ρ_f η) = ρ_f √ν (the fluid's "viscous load", kg m⁻² s^-½; water 1.0, glycerol at 20 °C 42) far
better than ρ_f and ν apart, which slide along that ridge.  The effect is therefore parametrised by
``viscous_load`` √(ρ_f η) (the switch, linear: the load is proportional to it at fixed ν),
``log10_viscosity`` log10 ν and ``viscosity_energy`` E_η, all at T_ref; ρ_f = √(ρ_f η)/√ν.  As
ν → 0 at fixed √(ρ_f η) the load tends to the boundary-layer asymptote plus an inviscid added mass
that a free ωn absorbs, so a fit that stops at the smallest ν of the range is in that regime (ν not
determined) rather than beyond a physical limit.

``ρ`` is the model's modal density: the strip's own density when this effect is on.  A parameter
set calibrated in the fluid already holds a constant added mass in ``ρ`` (seed 002: ≈ 6× the
strip's mass); freeing ``omega_n`` lets the refit move that mass into the fluid term.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import special

from .. import beam
from ..temperature import Arrhenius
from .base import law_factor

# Sader (1998) eq. (21): Ω_r and Ω_i as rational functions of τ = log10 Re (coefficients of
# τ⁰, τ¹, …).
_OMEGA_R_NUM = (0.91324, -0.48274, 0.46842, -0.12886, 0.044055, -0.0035117, 0.00069085)
_OMEGA_R_DEN = (1.0, -0.56964, 0.48690, -0.13444, 0.045155, -0.0035862, 0.00069085)
_OMEGA_I_NUM = (-0.024134, -0.029256, 0.016294, -0.00010961, 0.000064577, -0.000044510)
_OMEGA_I_DEN = (1.0, -0.59702, 0.55182, -0.18357, 0.079156, -0.014369, 0.0028361)
#: Range of log10 Re over which Sader fitted Ω.
OMEGA_LOG10_RE_RANGE = (-6.0, 4.0)


def reynolds_number(omega, width, kinematic_viscosity):
    """Re = ω b²/(4 ν) [-] for angular frequency ``omega`` [rad/s], width ``width`` [m] and
    kinematic viscosity ``kinematic_viscosity`` [m²/s] (Sader 1998 eq. 5)."""
    return np.asarray(omega, dtype=float) * np.asarray(width, dtype=float) ** 2 / (4.0 * np.asarray(kinematic_viscosity))


def gamma_circular(reynolds):
    """Sader's Γ_circ(Re) of a circular cylinder [-], his e^{−iωt} convention (Im Γ > 0 dissipates).

    K1/K0 is formed from the exponentially scaled Bessel functions (no underflow at large Re)."""
    re = np.asarray(reynolds, dtype=float)
    a = np.sqrt(1j * re)                       # √(iRe)
    z = -1j * a                                # Re z = √(Re/2) > 0
    return 1.0 + 4j * special.kve(1, z) / (a * special.kve(0, z))


def rectangular_correction(reynolds):
    """Sader's Ω(Re) = Γ_rect/Γ_circ [-] (eq. 21), τ = log10 Re held to :data:`OMEGA_LOG10_RE_RANGE`."""
    tau = np.clip(np.log10(np.asarray(reynolds, dtype=float)), *OMEGA_LOG10_RE_RANGE)
    pv = _polyval
    return (pv(tau, _OMEGA_R_NUM) / pv(tau, _OMEGA_R_DEN)) + 1j * (pv(tau, _OMEGA_I_NUM) / pv(tau, _OMEGA_I_DEN))


def _polyval(x, c):
    """``numpy.polynomial.polynomial.polyval(x, c)`` for a float array ``x`` and a tuple ``c``: the
    same Horner steps in the same order, without its argument handling (four per evaluation)."""
    acc = c[-1] + x * 0
    for k in range(2, len(c) + 1):
        acc = c[-k] + acc * x
    return acc


def gamma_rectangular(reynolds):
    """Sader's Γ_rect(Re) = Ω(Re) Γ_circ(Re) of a thin rectangular beam [-] (e^{−iωt} convention).

    Evaluated once per distinct Reynolds number: a batch of parameter sets repeats the same Re
    wherever the sets share the width and the viscosity at a temperature (the finite-difference sets
    of every parameter but the viscosity's own), and the Bessel functions are the costly part."""
    re = np.asarray(reynolds, dtype=float)
    if re.size > 1:
        u, inv = np.unique(re, return_inverse=True)
        if u.size < re.size:
            return (rectangular_correction(u) * gamma_circular(u))[inv.reshape(re.shape)]
    return rectangular_correction(re) * gamma_circular(re)


def kinematic_viscosity(v, T, T_ref):
    """ν(T) [m²/s] from the effect values ``v`` (``log10_viscosity`` at ``T_ref``, Andrade energy
    ``viscosity_energy`` [J/mol]); ``T``, ``T_ref`` [K]."""
    return 10.0 ** v["log10_viscosity"] / law_factor(Arrhenius, "activation_energy", v["viscosity_energy"], T, T_ref)


def fluid_density(v):
    """ρ_f = √(ρ_f η)/√ν [kg/m³] at T_ref from the effect values ``v`` (``viscous_load`` √(ρ_f η)
    [kg m⁻² s^-½], ``log10_viscosity``)."""
    return v["viscous_load"] / np.sqrt(10.0 ** np.asarray(v["log10_viscosity"], dtype=float))


def mass_factor(s, st, T_ref, v):
    """m(ω) = 1 + μ Γ_rect*(Re(ω)) [-]: the modal mass in the fluid over the strip's own, e^{+st}.

    ``s`` = jω [1/s] on the imaginary axis; ``st`` a :class:`~physmodel.params.State` (W, h, rho,
    T); ``T_ref`` [K] broadcastable to it; ``v`` the effect values (:func:`fluid_density`,
    :func:`kinematic_viscosity`; the density is held constant with temperature)."""
    omega = np.abs(np.imag(s))
    mu = math.pi * fluid_density(v) * st.W / (8.0 * st.rho * st.h)
    nu = kinematic_viscosity(v, st.T, T_ref)
    return 1.0 + mu * np.conj(_gamma_by_row(omega, st.W, nu))


def _gamma_by_row(omega, W, nu):
    """Γ_rect(Re) with Re = :func:`reynolds_number` (ω, W, ν) for ``W``, ``ν`` (n_sets, n_T, 1) and
    the frequencies ``omega`` (1, 1, n_f): evaluated on the distinct (W, ν) rows only — a batch's
    finite-difference sets of every parameter but the viscosity's (and the width's) repeat the
    point's rows, and the Bessel functions are the costly part — then spread back; the same numbers
    as :func:`gamma_rectangular` of the whole grid (each Re the same product and quotient, each Γ
    the same function of it), without sorting every Reynolds number of the batch."""
    W = np.asarray(W, dtype=float)
    nu = np.asarray(nu, dtype=float)
    shape = np.broadcast_shapes(W.shape, nu.shape)
    if len(shape) != 3 or shape[2] != 1 or np.ndim(omega) != 3 or shape[0] * shape[1] < 2:
        return gamma_rectangular(reynolds_number(omega, W, nu))
    rows = np.stack(np.broadcast_arrays(W, nu), axis=-1).reshape(-1, 2)      # (n_sets·n_T, 2)
    first: dict = {}
    inv = np.array([first.setdefault(key, len(first)) for key in map(tuple, rows.tolist())])
    if len(first) == rows.shape[0]:
        return gamma_rectangular(reynolds_number(omega, W, nu))
    kept = np.array(list(first), dtype=float)                                   # (k, 2)
    re = reynolds_number(omega, kept[:, 0, None, None], kept[:, 1, None, None])   # (k, 1, n_f)
    g = rectangular_correction(re) * gamma_circular(re)
    return g[inv, 0, :].reshape(shape[0], shape[1], -1)


def loaded_first_mode(s, omega_n, xi, m):
    """The unit-DC-gain first mode with modal mass factor ``m``: beam.first_mode(s √m, ωn, ξ/√m) [-]."""
    r = np.sqrt(m)
    return beam.first_mode(s * r, omega_n, xi / r)


def response_factor(q, ctx, v):
    """M(fluid)/M: the loaded first mode over the base's (a response-level factor)."""
    st = ctx.st
    m = mass_factor(ctx.s, st, ctx.T_ref, v)
    return loaded_first_mode(ctx.s, st.omega_n, st.xi, m) / beam.first_mode(ctx.s, st.omega_n, st.xi)


__all__ = ["reynolds_number", "gamma_circular", "rectangular_correction", "gamma_rectangular", "kinematic_viscosity",
           "fluid_density",
           "mass_factor", "loaded_first_mode", "response_factor", "OMEGA_LOG10_RE_RANGE"]
