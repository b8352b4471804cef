"""Reference and toy models used by the tests, the benchmark and the documentation.

Only :func:`seed000_sensor_35c` is a published model; everything else is a clearly labelled
toy built to exercise the inversion (not a fit to data).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from physmodel.parameter_sets.published import seed000_printed_model_35c

__all__ = [
    "SEED000_NUM_35C",
    "SEED000_DEN_35C",
    "SEED000_ZEROS_35C",
    "seed000_sensor_35c",
    "toy_scheduled_sensor",
    "toy_actuator",
    "released_cantilever",
]

#: Seed 000, Sec. IV-A: 35 degC sensor model, tip displacement [mm] -> current [uA], s [rad/s], and its
#: zeros as printed (computed by the authors from the unrounded coefficients) [rad/s]; the printed
#: numbers live in :mod:`physmodel.parameter_sets.published`.
SEED000_NUM_35C, SEED000_DEN_35C, SEED000_ZEROS_35C = seed000_printed_model_35c()


def seed000_sensor_35c(form: str = "coefficients") -> Any:
    """The published 35 degC IPMC sensor model of seed paper 000 as a ``control.TransferFunction``.

    Parameters
    ----------
    form : {"coefficients", "zeros"}
        ``"coefficients"``: the printed (2-3 significant figure) coefficients.  Their zeros
        are -107.9, 35.49, 672.0 +/- 477.0j, i.e. the rounding moves the least unstable zero
        from the printed 35.2 to 35.49 (T_p* 0.1136 -> 0.1127 s).
        ``"zeros"``: numerator rebuilt from the printed zeros with the printed leading
        coefficient -17.3 (same denominator), so that r0 = 35.2 exactly.

    Returns
    -------
    control.TransferFunction
        ``G(s)`` in uA/mm.
    """
    import control

    if form == "coefficients":
        return control.tf(list(SEED000_NUM_35C), list(SEED000_DEN_35C))
    if form == "zeros":
        num = np.real(np.poly(np.array(SEED000_ZEROS_35C))) * SEED000_NUM_35C[0]
        return control.tf(num, list(SEED000_DEN_35C))
    raise ValueError(f"form must be 'coefficients' or 'zeros'; got {form!r}")


def toy_scheduled_sensor(temperature_c: float, *, kappa_per_c: float = 0.01,
                         gain_per_c: float = 0.004) -> Any:
    """TOY temperature-scheduled sensor: the printed 35 degC model time-scaled and rescaled.

    ``G_T(s) = g(T) G_35(s / kappa(T))`` with ``kappa(T) = 1 - kappa_per_c (T - 35)`` and
    ``g(T) = 1 - gain_per_c (T - 35)``: every pole and zero moves in proportion to ``kappa``,
    so the cut-off frequency and the high-frequency gain fall as T rises (the trends seed
    000 reports) and the model stays hyperbolic.  Not a fit: a smooth, plausible stand-in
    for the surrogate while that package is written.  Valid for 0 < kappa, g.

    Parameters
    ----------
    temperature_c : float
        [degC]
    kappa_per_c, gain_per_c : float
        Relative change per degC of the time scale and of the gain [1/degC].
    """
    import control

    kappa = 1.0 - kappa_per_c * (temperature_c - 35.0)
    g = 1.0 - gain_per_c * (temperature_c - 35.0)
    if kappa <= 0 or g <= 0:
        raise ValueError(f"toy model undefined at {temperature_c} degC (kappa={kappa}, g={g})")
    n = np.asarray(SEED000_NUM_35C, float)
    d = np.asarray(SEED000_DEN_35C, float)
    powers = np.arange(n.size - 1, -1, -1)
    # p(s/kappa) = sum c_k s^k kappa^-k ; multiply both by kappa^4 to keep den monic
    num = g * n * kappa ** (4 - powers)
    den = d * kappa ** (4 - powers)
    return control.tf(num, den)


def toy_actuator() -> Any:
    """TOY proper third-order non-minimum-phase actuator, voltage [V] -> tip displacement [mm].

    Shaped like the seed 001 models (proper, 3 zeros / 3 poles, a complex pair of
    right-half-plane zeros, resonance of a few Hz):
    ``G(s) = 0.0125 (s^2 - 8 s + 1600)(s + 60) / ((s + 3)(s^2 + 4 s + 400))`` — DC gain 1 mm/V,
    resonance near 3.2 Hz, RHP zeros at 4 +/- 39.8j rad/s (r0 = 4, T_p* = 1 s).
    """
    import control

    num = 0.0125 * np.polymul([1.0, -8.0, 1600.0], [1.0, 60.0])
    den = np.polymul([1.0, 3.0], [1.0, 4.0, 400.0])
    return control.tf(num, den)


def released_cantilever(t: Any, *, w0: float = 1.0, t_release: float = 0.5,
                        f_n: float = 30.0, zeta: float = 0.1) -> np.ndarray:
    """Tip displacement of a cantilever held at ``w0`` until ``t_release``, then released.

    After release it oscillates freely as a damped second-order system,
    ``w(tau) = w0 e^{-zeta wn tau} (cos wd tau + zeta/sqrt(1-zeta^2) sin wd tau)``,
    ``tau = t - t_release`` (continuous with zero velocity at release).

    Parameters
    ----------
    t : array_like
        Times [s].
    w0 : float
        Held displacement [mm].
    t_release : float
        Release instant [s].
    f_n : float
        Natural frequency [Hz].
    zeta : float
        Damping ratio (0 < zeta < 1).

    Returns
    -------
    ndarray
        Displacement [mm].
    """
    t = np.asarray(t, dtype=float)
    wn = 2 * np.pi * f_n
    wd = wn * np.sqrt(1 - zeta**2)
    tau = np.maximum(t - t_release, 0.0)
    free = w0 * np.exp(-zeta * wn * tau) * (np.cos(wd * tau) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * tau))
    return np.where(t < t_release, w0, free)
