"""A surrogate checked against the user's own measured sweep, and the tracking (or decoding) error
that follows for a given signal: the prediction of what happens on *the strip*, not on the model
that produced the surrogate.

Inverting a model G on a plant P gives y = (P/G)·r, so the error is e = (P/G − 1)·r.  The measured
sweep H (with per-line σ) stands for P where it was measured:

1. :func:`misfit_to_data` — m = H/G − 1 at every measured line and temperature, with its standard
   deviation σ_m = |H/G|·σ_rel (σ_rel² = (σ_dB·ln10/20)² + σ_rad², the relative complex std of the
   measured line);
2. :func:`predicted_error` — for a signal r at a target temperature T: at each of the two measured
   temperatures around T (the nearest one beyond the range, *extrapolated*), m is carried onto the
   signal's spectrum by a weighted least-squares polynomial in log-frequency whose degree is the
   smallest that leaves residuals consistent with the declared noise (χ² test at
   ``SMOOTHING_ALPHA``: the misfit of a model is smooth where the model is, the line noise is
   not, so the noise averages out over the lines the polynomial spans; line-by-line interpolation
   when the lines declare no noise), flat beyond the measured band (the share of the signal's power
   outside the band is reported), and

   * the error spectrum is E = m·Y + E_inv, where Y = G·u is the surrogate's output for the drive
     and E_inv = Y − R the inversion's own error (preview truncation, sampling of the inverse;
     known exactly when ``inversion_residual`` is given, else 0 and Y = R), so misfit and
     inversion errors add with their phases;
   * the central prediction is RMS(e)/RMS(r) with m interpolated linearly in T between the two
     temperatures and the measurement noise removed on average (Σ|E|² − Σσ²|Y|², clipped at 0, σ²
     the variance of the interpolated m: interpolation averages the independent noise of the
     lines and temperatures it combines);
   * the stated upper bound takes, at each of the two temperatures, (|m| + 2σ_m)|Y| + |E_inv| per
     frequency, and the larger of the two (a misfit that changes monotonically between the
     measured temperatures stays below it; beyond the measured band or range nothing bounds it
     and the result says so).

Not in it: effects that the measured band did not excite.  Frequencies in Hz, temperatures in °C, signals in any one unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DataMisfit:
    """m = H/G − 1 per measured line (see the module doc).

    Parameters
    ----------
    temperatures_c : ndarray
        The measured temperatures, ascending. [°C]
    frequency_hz : tuple of ndarray
        Per temperature, the measured frequencies, ascending. [Hz]
    misfit : tuple of ndarray
        Per temperature, complex m at those frequencies. [-]
    sigma : tuple of ndarray
        Per temperature, the standard deviation of m from the measurement noise. [-]
    rms : ndarray
        Per temperature, sqrt(mean |m|²) over the measured lines. [-]
    source : str
        What was compared (file names, fingerprints).
    """

    temperatures_c: np.ndarray
    frequency_hz: tuple
    misfit: tuple
    sigma: tuple
    rms: np.ndarray
    source: str = ""

    @property
    def band_hz(self) -> tuple[float, float]:
        """(lowest, highest) measured frequency. [Hz]"""
        return (float(min(f[0] for f in self.frequency_hz)), float(max(f[-1] for f in self.frequency_hz)))

    def table(self) -> list[dict]:
        """Per temperature: T [°C], lines, RMS |m| and RMS σ_m [-]."""
        return [{"temperature_c": float(t), "lines": int(f.size), "rms_misfit": float(r),
                 "rms_sigma": float(np.sqrt(np.mean(s ** 2)))}
                for t, f, r, s in zip(self.temperatures_c, self.frequency_hz, self.rms, self.sigma)]


def misfit_to_data(model, sweep, *, source: str = "") -> DataMisfit:
    """Compare ``model`` (anything with ``frequency_response(f_hz, T_c, extrapolate=True)``, e.g. a
    :class:`~surrogate.RationalModel`, in the units of ``sweep``) with a measured sweep.

    Parameters
    ----------
    model : RationalModel
        The surrogate, in the sweep's units (convert the sweep first:
        ``FrequencySweep.in_units``).
    sweep : physmodel.FrequencySweep
        The measured sweep; lines without σ count as noise-free (σ_m = 0).
    source : str
        Recorded in the result.

    Returns
    -------
    DataMisfit
    """
    temps = np.unique(np.asarray(sweep.temperature_c, float))
    sdb = getattr(sweep, "magnitude_std_db", None)
    sdeg = getattr(sweep, "phase_std_deg", None)
    fs, ms, ss, rms = [], [], [], []
    for t in temps:
        sel = np.asarray(sweep.temperature_c) == t
        f = np.asarray(sweep.frequency_hz, float)[sel]
        order = np.argsort(f)
        f = f[order]
        H = np.asarray(sweep.response)[sel][order]
        G = np.asarray(model.frequency_response(f, float(t), extrapolate=True)).reshape(-1)
        ratio = H / G
        rel = np.zeros(f.size)
        if sdb is not None:
            rel = rel + (np.asarray(sdb, float)[sel][order] * math.log(10) / 20) ** 2
        if sdeg is not None:
            rel = rel + np.radians(np.asarray(sdeg, float)[sel][order]) ** 2
        m = ratio - 1.0
        fs.append(f)
        ms.append(m)
        ss.append(np.abs(ratio) * np.sqrt(rel))
        rms.append(float(np.sqrt(np.mean(np.abs(m) ** 2))))
    return DataMisfit(temps, tuple(fs), tuple(ms), tuple(ss), np.array(rms), source)


@dataclass(frozen=True)
class PredictedError:
    """The error a signal will see on the strip (see the module doc).

    Parameters
    ----------
    rms : float
        Central prediction, RMS(e)/RMS(r). [-]
    bound : float
        Stated upper bound of the same ratio. [-]
    temperature_c : float
        Target temperature. [°C]
    neighbours_c : tuple of float
        The measured temperatures used (one when extrapolated or exactly at one). [°C]
    extrapolated : bool
        The target lies outside the measured temperatures (the bound is then not a bound).
    out_of_band_power : float
        Share of the signal's power (rest excluded) outside the measured band. [-]
    per_temperature : dict
        {T: (central, bound)} at each neighbour. [-]
    inversion : float
        The inversion's own error, RMS over the signal's RMS (0 when not given). [-]
    """

    rms: float
    bound: float
    temperature_c: float
    neighbours_c: tuple
    extrapolated: bool
    out_of_band_power: float
    per_temperature: dict
    inversion: float = 0.0

    @property
    def checked(self) -> bool:
        """Whether the data cover the target (temperature inside the measured ones, ≥ 99 % of the
        signal's power inside the measured band)."""
        return not self.extrapolated and self.out_of_band_power <= 0.01

    def sentence(self) -> str:
        """One line for reports."""
        s = (f"{100 * self.rms:.3g} % RMS of the signal (bound {100 * self.bound:.3g} %), from the measured misfit at "
             + " and ".join(f"{t:g} °C" for t in self.neighbours_c)
             + (f" and the inversion's own error ({100 * self.inversion:.2g} %)" if self.inversion else ""))
        if self.extrapolated:
            s += f"; {self.temperature_c:g} °C is OUTSIDE the measured temperatures: extrapolated, not bounded"
        if self.out_of_band_power > 0.01:
            s += (f"; {100 * self.out_of_band_power:.2g} % of the signal's power lies outside the measured band: "
                  "unchecked there")
        return s

    def to_dict(self) -> dict:
        """JSON-ready data (temperatures as keys of ``per_temperature``)."""
        return {"rms": self.rms, "bound": self.bound, "temperature_c": self.temperature_c,
                "neighbours_c": list(self.neighbours_c), "extrapolated": self.extrapolated,
                "out_of_band_power": self.out_of_band_power, "checked": self.checked, "inversion": self.inversion,
                "per_temperature": {f"{k:g}": list(v) for k, v in self.per_temperature.items()}}


def _interp_log(f_new, f, values, sigma):
    """Linear interpolation over log10 f (flat beyond the ends) of complex ``values`` and of the
    variance of independent per-line noise ``sigma``: (1 − b)²σ_k² + b²σ_{k+1}² between lines k and
    k+1 (an interpolated value averages two noises)."""
    x, xn = np.log10(f), np.log10(f_new)
    m = np.interp(xn, x, values.real) + 1j * np.interp(xn, x, values.imag)
    if x.size == 1:
        return m, np.full(xn.shape, float(sigma[0]) ** 2)
    k = np.clip(np.searchsorted(x, xn) - 1, 0, x.size - 2)
    b = np.clip((xn - x[k]) / (x[k + 1] - x[k]), 0.0, 1.0)
    return m, (1 - b) ** 2 * sigma[k] ** 2 + b ** 2 * sigma[k + 1] ** 2


#: Significance of the χ² test that picks the smoothing degree (the smallest degree whose residuals
#: are consistent with the declared noise at this level).
SMOOTHING_ALPHA = 0.05
#: Highest polynomial degree (in log f) tried before falling back to line-by-line interpolation.
MAX_SMOOTHING_DEGREE = 8


def _smooth_log(f_new, f, values, sigma):
    """The misfit smoothed over log f by weighted least squares on Legendre polynomials, with the
    smallest degree whose residuals pass a χ² test against the declared noise (a misfit is smooth
    where the model is; line noise is not), and the variance of the smoothed value
    b(f)ᵀ(BᵀWB)⁻¹b(f).  Evaluated flat beyond the measured band.  Falls back to
    :func:`_interp_log` when the lines have no noise (σ = 0) or no degree passes."""
    from numpy.polynomial import legendre
    from scipy.stats import chi2

    n = f.size
    if n < 3 or not np.all(sigma > 0):
        return _interp_log(f_new, f, values, sigma)
    x = np.log10(f)
    lo, hi = x[0], x[-1]
    u = (2 * x - lo - hi) / (hi - lo)
    un = np.clip((2 * np.log10(f_new) - lo - hi) / (hi - lo), -1.0, 1.0)
    w = 1.0 / sigma
    for p in range(min(MAX_SMOOTHING_DEGREE, n - 2) + 1):
        B = legendre.legvander(u, p)
        A = B * w[:, None]
        beta, *_ = np.linalg.lstsq(A, values * w, rcond=None)
        stat = 2.0 * float(np.sum(np.abs((values - B @ beta) * w) ** 2))      # χ² on 2(n − p − 1) dof
        if chi2.sf(stat, 2 * (n - p - 1)) >= SMOOTHING_ALPHA:
            cov = np.linalg.inv(A.T @ A)
            Bn = legendre.legvander(un, p)
            return Bn @ beta, np.einsum("ij,jk,ik->i", Bn, cov, Bn).real
    return _interp_log(f_new, f, values, sigma)


def power_outside(t, signal, band_hz) -> float:
    """Share of a signal's power (its mean included) outside ``band_hz``.

    Parameters
    ----------
    t : array_like
        Uniform sample times. [s]
    signal : array_like
        The signal. [any unit]
    band_hz : (float, float)
        (lowest, highest) frequency. [Hz]

    Returns
    -------
    float
        The share, 0 to 1. [-]
    """
    t = np.asarray(t, float)
    r = np.asarray(signal, float)
    f = np.fft.rfftfreq(r.size, float(t[1] - t[0]))
    p = np.abs(np.fft.rfft(r)) ** 2 * np.where(np.arange(f.size) == 0, 1.0, 2.0)
    inside = (f >= band_hz[0] * (1 - 1e-9)) & (f <= band_hz[1] * (1 + 1e-9))
    total = float(np.sum(p))
    return 0.0 if total <= 0 else 1.0 - float(np.sum(p[inside])) / total


def predicted_error(misfit: DataMisfit, temperature_c: float, t, signal, inversion_residual=None) -> PredictedError:
    """The RMS error, relative to the signal's RMS, of inverting the surrogate on the measured strip
    for ``signal`` at ``temperature_c`` (see the module doc).

    Parameters
    ----------
    misfit : DataMisfit
        From :func:`misfit_to_data`.
    temperature_c : float
        Target temperature. [°C]
    t : array_like
        Uniform sample times of the signal. [s]
    signal : array_like
        The reference (feedforward) or the decoded input (sensor decoding). [any unit]
    inversion_residual : array_like or None
        G·u − signal: the surrogate's own response to the computed drive minus the signal (the
        inversion's error), same samples. [the signal's unit]

    Returns
    -------
    PredictedError
    """
    t = np.asarray(t, float)
    r = np.asarray(signal, float)
    if r.size < 4 or t.shape != r.shape:
        raise ValueError(f"signal and t must be equal-length arrays of >= 4 samples, got {r.shape} and {t.shape}")
    e_inv = np.zeros_like(r) if inversion_residual is None else np.asarray(inversion_residual, float)
    if e_inv.shape != r.shape:
        raise ValueError(f"inversion_residual has shape {e_inv.shape}, the signal {r.shape}")
    dt = float(t[1] - t[0])
    f = np.fft.rfftfreq(r.size, dt)
    W = np.where(np.arange(f.size) == 0, 1.0, 2.0)          # one-sided power weights
    R, Einv = np.fft.rfft(r), np.fft.rfft(e_inv)
    Y = R + Einv                                             # the surrogate's output for the drive, G·u
    total = float(np.sum(W * np.abs(R) ** 2))
    if total <= 0:
        raise ValueError("the signal is identically zero")
    lo, hi = misfit.band_hz
    inside = (f >= lo * (1 - 1e-9)) & (f <= hi * (1 + 1e-9))
    out_share = 1.0 - float(np.sum((W * np.abs(R) ** 2)[inside])) / total
    fpos = np.where(f > 0, f, f[1] if f.size > 1 else 1.0)
    T = np.asarray(misfit.temperatures_c, float)
    Tc = float(temperature_c)
    if Tc <= T[0]:
        idx, wts, extrap = [0], [1.0], Tc < T[0] - 1e-9
    elif Tc >= T[-1]:
        idx, wts, extrap = [T.size - 1], [1.0], Tc > T[-1] + 1e-9
    else:
        j = int(np.searchsorted(T, Tc))
        if abs(T[j] - Tc) <= 1e-9:
            idx, wts = [j], [1.0]
        else:
            a = (T[j] - Tc) / (T[j] - T[j - 1])
            idx, wts = [j - 1, j], [a, 1.0 - a]
        extrap = False

    def central2(m, s2):
        # E|m_meas·Y + E_inv|² = |m·Y + E_inv|² + σ²|Y|²: the measurement noise removed on average
        return max(float(np.sum(W * (np.abs(m * Y + Einv) ** 2 - s2 * np.abs(Y) ** 2))) / total, 0.0)

    per, bounds = {}, []
    m_T = np.zeros(f.size, complex)
    s2_T = np.zeros(f.size)
    for i, wt in zip(idx, wts):
        m, v = _smooth_log(fpos, misfit.frequency_hz[i], misfit.misfit[i], misfit.sigma[i])
        upper = math.sqrt(float(np.sum(W * ((np.abs(m) + 2.0 * np.sqrt(v)) * np.abs(Y) + np.abs(Einv)) ** 2)) / total)
        per[float(T[i])] = (math.sqrt(central2(m, v)), upper)
        bounds.append(upper)
        m_T += wt * m
        s2_T += wt ** 2 * v                      # independent noise at the two temperatures
    inv = float(np.sqrt(np.mean(e_inv ** 2) / np.mean(r ** 2)))
    return PredictedError(math.sqrt(central2(m_T, s2_T)), max(bounds), Tc, tuple(float(T[i]) for i in idx),
                          bool(extrap), out_share, per, inv)


__all__ = ["DataMisfit", "PredictedError", "misfit_to_data", "predicted_error", "power_outside"]
