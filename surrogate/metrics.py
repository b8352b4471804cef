"""Error measures between a model response and data (complex arrays of equal shape)."""

from __future__ import annotations

import numpy as np

__all__ = ["relative_rms_error", "fit_percent", "log_rms_error"]


def _pair(model, data):
    m = np.asarray(model, complex).ravel()
    d = np.asarray(data, complex).ravel()
    if m.shape != d.shape:
        raise ValueError(f"model has {m.size} values, data has {d.size}")
    if m.size == 0:
        raise ValueError("empty response")
    return m, d


def relative_rms_error(model, data) -> float:
    """sqrt(mean(|H_model − H_data|² / |H_data|²)). [-]

    Parameters
    ----------
    model : array_like
        Model response, complex, any shape. [output/input]
    data : array_like
        Measured response, complex, the same number of values. [output/input]
    """
    m, d = _pair(model, data)
    return float(np.sqrt(np.mean(np.abs(m - d) ** 2 / np.abs(d) ** 2)))


def fit_percent(model, data) -> float:
    """MATLAB-style fit 100·(1 − NRMSE), NRMSE = ‖H_model − H_data‖ / ‖H_data − mean H_data‖. [%]

    Parameters
    ----------
    model : array_like
        Model response, complex, any shape. [output/input]
    data : array_like
        Measured response, complex, the same number of values. [output/input]
    """
    m, d = _pair(model, data)
    den = np.linalg.norm(d - d.mean())
    if den == 0:
        raise ValueError("fit_percent is undefined for a constant response")
    return float(100.0 * (1.0 - np.linalg.norm(m - d) / den))


def log_rms_error(model, data) -> float:
    """RMS of ln(H_model/H_data) (ln-magnitude [Np] and phase [rad] residuals together). [-]

    Parameters
    ----------
    model : array_like
        Model response, complex, any shape. [output/input]
    data : array_like
        Measured response, complex, the same number of values. [output/input]
    """
    m, d = _pair(model, data)
    r = np.log(m / d)
    return float(np.sqrt(np.mean(r.real ** 2 + r.imag ** 2)))
