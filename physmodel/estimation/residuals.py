"""Standardised residuals of a model against a :class:`~physmodel.data.sweep.FrequencySweep`.

For each line the relative error ln(G_data/G_model) is split into log-magnitude and phase:
``r = [ln|G_d/G_m| / σ_ln, wrap(∠G_d − ∠G_m) / σ_φ]`` with σ_ln = magnitude_std_db·ln10/20 [Np] and
σ_φ = phase_std_deg·π/180 [rad] from the sweep (discrepancy.md §1).  The cost ½Σr² of a correct
model averages F − nθ/2 (F lines, nθ fitted parameters) with spread ≈ sqrt(F − nθ/2).
"""

from __future__ import annotations

import math

import numpy as np

from ..data.sweep import FrequencySweep
from ..errors import DataFormatError, IPMCError

#: Relative standard deviation assumed per line (log-magnitude [Np] and phase [rad]) when a sweep
#: carries no per-line uncertainty; the covariance is then rescaled by the fitted residual variance.
FALLBACK_RELATIVE_STD = 0.01

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
