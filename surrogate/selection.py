"""Order selection: fit error against (n_zeros, n_poles) at every temperature."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _fit as F
from ._data import FrequencyData
from .metrics import fit_percent, relative_rms_error
from .rational import RationalFit

__all__ = ["OrderRow", "OrderSelectionReport", "order_selection"]


@dataclass(frozen=True)
class OrderRow:
    """One order, all temperatures.

    Parameters
    ----------
    n_zeros, n_poles : int
        The order fitted.
    n_params : int
        Fitted coefficients, ``n_zeros + n_poles + 1``.
    temperatures_c : tuple of float or None
        The temperatures fitted (None for data without temperatures). [°C]
    relative_rms_error : tuple of float
        Per temperature, in the order of ``temperatures_c``. [-]
    fit_percent : tuple of float
        MATLAB-style fit per temperature. [%]
    weighted_rms : tuple of float
        RMS of the weighted residuals per temperature (≈ 1 when the model fits within the data's
        σ). [-]
    converged, stable : tuple of bool
        Per temperature: did the fit converge, is the fitted model stable.
    """

    n_zeros: int
    n_poles: int
    n_params: int
    temperatures_c: tuple
    relative_rms_error: tuple
    fit_percent: tuple
    weighted_rms: tuple
    converged: tuple
    stable: tuple

    @property
    def mean_relative_rms_error(self) -> float:
        """Mean over temperatures of the relative RMS error. [-]"""
        return float(np.mean(self.relative_rms_error))

    @property
    def worst_relative_rms_error(self) -> float:
        """Largest relative RMS error over temperatures. [-]"""
        return float(np.max(self.relative_rms_error))

    @property
    def min_fit_percent(self) -> float:
        """Smallest fit over temperatures. [%]"""
        return float(np.min(self.fit_percent))

    @property
    def mean_fit_percent(self) -> float:
        """Mean fit over temperatures. [%]"""
        return float(np.mean(self.fit_percent))


@dataclass(frozen=True)
class OrderSelectionReport:
    """The errors of every order tried (:func:`order_selection`).

    Parameters
    ----------
    rows : tuple of OrderRow
        One row per order, in the order given.
    """

    rows: tuple

    def row(self, n_zeros: int, n_poles: int) -> OrderRow:
        """The row of one order.

        Parameters
        ----------
        n_zeros, n_poles : int
            The order; a ``KeyError`` names it when it was not tried.
        """
        for r in self.rows:
            if (r.n_zeros, r.n_poles) == (n_zeros, n_poles):
                return r
        raise KeyError(f"order ({n_zeros}, {n_poles}) not in the report")

    def to_markdown(self) -> str:
        """The table in Markdown: errors averaged and worst over temperatures, convergence and
        stability."""
        lines = [
            "| zeros | poles | params | mean rel. RMS error | worst rel. RMS error | mean fit % | min fit % | all converged | all stable |",
            "|---:|---:|---:|---:|---:|---:|---:|:---:|:---:|",
        ]
        for r in self.rows:
            lines.append(
                f"| {r.n_zeros} | {r.n_poles} | {r.n_params} | {r.mean_relative_rms_error:.4f} | "
                f"{r.worst_relative_rms_error:.4f} | {r.mean_fit_percent:.2f} | {r.min_fit_percent:.2f} | "
                f"{'yes' if all(r.converged) else 'NO'} | {'yes' if all(r.stable) else 'NO'} |"
            )
        return "\n".join(lines)


def order_selection(frequency_hz, temperature_c=None, response=None, orders=None,
                    magnitude_std_db=None, phase_std_deg=None, *, weighting: str = "auto", stable: bool = True,
                    max_iter: int = 300) -> OrderSelectionReport:
    """Fit every (n_zeros, n_poles) in ``orders`` at every temperature and tabulate the errors.

    Units as in ``RationalFit.fit``; a ``FrequencySweep`` / ``FrequencyData`` may be passed as
    the first argument instead of the arrays (``orders`` then by keyword).  Fits that do not
    converge are kept and flagged in the ``converged`` column (never dropped silently).

    Parameters
    ----------
    frequency_hz : array_like or FrequencySweep or FrequencyData
        Frequency of each line. [Hz]
    temperature_c : array_like or None
        Temperature of each line (None: one temperature). [°C]
    response : array_like
        Complex response of each line. [output/input]
    orders : sequence of (int, int)
        The (n_zeros, n_poles) to try.
    magnitude_std_db : array_like or None
        Per-line σ of the magnitude. [dB]
    phase_std_deg : array_like or None
        Per-line σ of the phase. [deg]
    weighting : {'auto', 'uncertainty', 'log', 'relative'}
        Residual weighting, as :class:`~surrogate.RationalFit`.
    stable : bool
        Constrain the poles to the left half-plane.
    max_iter : int
        Iterations per fit.

    Returns
    -------
    OrderSelectionReport
    """
    data = F.as_data(frequency_hz, temperature_c, response, magnitude_std_db, phase_std_deg)
    orders = [tuple(int(v) for v in o) for o in (orders or [])]
    if not orders:
        raise ValueError("orders is empty")
    temps = [None] if data.temperature_c is None else list(data.temperatures())
    rows = []
    for m, n in orders:
        fitter = RationalFit(m, n, stable=stable, weighting=weighting, max_iter=max_iter,
                             raise_on_failure=False)
        rel, fp, wr, conv, stab = [], [], [], [], []
        for t in temps:
            d: FrequencyData = data if t is None else data.at_temperature(t)
            res = fitter.fit_data(d)
            h = res.model.frequency_response(d.frequency_hz)
            rel.append(relative_rms_error(h, d.response))
            fp.append(fit_percent(h, d.response))
            wr.append(res.weighted_rms)
            conv.append(res.converged)
            stab.append(res.stability.stable)
        rows.append(OrderRow(m, n, m + n + 1, tuple(None if t is None else float(t) for t in temps),
                             tuple(rel), tuple(fp), tuple(wr), tuple(conv), tuple(stab)))
    return OrderSelectionReport(tuple(rows))
