"""Frequency-domain simulation of a record that starts and ends at rest: the exact response of any
model in the one interface (physics, physics with effects — a time delay included, which no
finite realisation holds — or a surrogate) to a drive that is zero before and after it.

The drive is zero-padded to a length N ≥ ``pad`` × its own, transformed, multiplied by the
model's response on the FFT grid (the DC bin evaluated at 10⁻³ of the first bin) and transformed
back; the result is exact up to the wrap-around of the impulse-response tail beyond N − n
samples.  That residue is measured, not assumed: the same simulation with twice the padding gives
``wraparound`` = max|y_N − y_2N| / max|y_2N| and, when it exceeds ``tol``, the padding is doubled
again (up to 64×).  Times in s, frequencies in Hz, temperatures in °C, SI signals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import fft as sfft

from ..errors import IPMCError

#: Largest padding factor tried before giving up on the wrap-around tolerance.
MAX_PAD = 64


@dataclass(frozen=True)
class RestSimulation:
    """Output of :func:`simulate_at_rest`: ``y`` at the drive's samples [output SI unit], the
    padding used (``n_fft`` points) and the measured ``wraparound`` residue [-]."""

    y: np.ndarray
    n_fft: int
    wraparound: float

    def describe(self) -> str:
        """One line for reports: the padding and the measured wrap-around residue."""
        return (f"frequency-domain simulation ({self.n_fft} points, wrap-around residue "
                f"{self.wraparound:.1e} of the peak)")


def _run(model, temperature_c: float, u: np.ndarray, dt: float, n_fft: int) -> np.ndarray:
    f = sfft.rfftfreq(n_fft, dt)
    f_eval = f.copy()
    f_eval[0] = 1e-3 * f[1]
    H = np.asarray(model.response(f_eval, [float(temperature_c)]))[0]
    H[0] = H[0].real
    return sfft.irfft(sfft.rfft(u, n_fft) * H, n_fft)[: u.size]


def simulate_at_rest(model, temperature_c: float, t, u, *, pad: int = 4, tol: float = 1e-4) -> RestSimulation:
    """The model's primary output (``response``: M for an actuator, S for a sensor) for the drive
    ``u`` at uniform times ``t``, assuming rest before and after the record.

    Parameters
    ----------
    model : FrequencyModel
        Any model with ``response(frequency_hz, temperature_c)`` (n_T, n_f).
    temperature_c : float
        Temperature. [°C]
    t : array_like
        Uniform sample times. [s]
    u : array_like
        Drive samples (V for an actuator, m for a sensor); should be ~0 at both ends.
    pad : int
        Initial padding factor (N ≥ pad × n).
    tol : float
        Largest accepted wrap-around residue (relative to the output's peak).

    Returns
    -------
    RestSimulation
    """
    t = np.asarray(t, float)
    u = np.asarray(u, float)
    if t.ndim != 1 or t.shape != u.shape or t.size < 4:
        raise IPMCError(f"t and u must be equal-length 1-D arrays of >= 4 samples, got {t.shape} and {u.shape}")
    dt = float(t[1] - t[0])
    if not (np.isfinite(dt) and dt > 0) or not np.allclose(np.diff(t), dt, rtol=1e-6, atol=0):
        raise IPMCError("t must be uniformly spaced and increasing")
    if not np.all(np.isfinite(u)):
        raise IPMCError("the drive contains NaN or inf")
    p = max(int(pad), 2)
    n = sfft.next_fast_len(p * u.size, real=True)
    y = _run(model, temperature_c, u, dt, n)
    while True:
        n2 = sfft.next_fast_len(2 * n, real=True)
        y2 = _run(model, temperature_c, u, dt, n2)
        peak = float(np.max(np.abs(y2))) or 1.0
        wrap = float(np.max(np.abs(y - y2))) / peak
        if wrap <= tol or n2 >= MAX_PAD * u.size:
            return RestSimulation(y2, n2, wrap)
        n, y = n2, y2


class RestRealization:
    """What :func:`physmodel.data.timesim.simulate` uses for a model with no finite realisation (a
    model with effects, e.g. a delay): :func:`simulate_at_rest` behind the realisation's
    ``simulate(t, u, hold, initial)`` call.  Exact for any drive that starts at rest (the model is
    causal, so what follows the record does not matter beyond the measured wrap-around).

    Parameters
    ----------
    model : FrequencyModel
        The model (its primary ``response``).
    temperature_c : float
        Temperature. [°C]
    """

    def __init__(self, model, temperature_c: float):
        self.model, self.temperature_c = model, float(temperature_c)
        self.summary = "frequency-domain simulation (a model with effects has no finite realisation)"

    def simulate(self, t, u, hold: str = "foh", initial: str = "rest") -> np.ndarray:
        """Output for input samples ``u`` at uniform times ``t`` [s]; ``initial`` must be "rest".

        Parameters
        ----------
        t : array_like
            Uniform sample times. [s]
        u : array_like
            Drive samples. [SI input unit]
        hold : str
            Ignored: the drive is treated as band-limited.
        initial : str
            Only ``"rest"``.
        """
        if initial != "rest":
            raise IPMCError(f"initial={initial!r}: a model with effects is simulated from rest only")
        sim = simulate_at_rest(self.model, self.temperature_c, t, u)
        self.summary = sim.describe()
        return sim.y


__all__ = ["simulate_at_rest", "RestSimulation", "RestRealization", "MAX_PAD"]
