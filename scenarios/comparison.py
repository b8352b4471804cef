"""Model vs data per temperature (:func:`compare`, ``ipmc compare``): the model's response on the
data's lines (:func:`scenarios.prediction.predict_sweep`, in the data's units) and, per temperature,
on the complex response H of those lines:

- fit % = 100·(1 − ‖H − Ĥ‖ / ‖H − mean H‖) (MATLAB's ``compare``; 100 % exact, 0 % no better
  than the mean, negative worse);
- χ² = Σ r² of the standardised residuals ln|H/Ĥ|/σ_ln and ∠(H/Ĥ)/σ_φ
  (:func:`physmodel.estimation.residuals.residuals`) on 2n degrees of freedom, tested with
  :func:`~physmodel.estimation.residuals.goodness_of_fit` (no parameter counted: the model is
  taken as given).  Without per-line σ in the data the test is the library's fallback
  (the implied relative noise) and χ² is not reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from physmodel.data.sweep import FrequencySweep
from physmodel.errors import IPMCError

from .prediction import load_any_model, model_name, predict_sweep

__all__ = ["Comparison", "TemperatureFit", "compare"]


@dataclass(frozen=True)
class TemperatureFit:
    """How well a model matches the data at one temperature (see the module doc).

    Parameters
    ----------
    temperature_c : float
        The temperature. [°C]
    n_lines : int
        Data lines.
    fit_percent : float
        100·(1 − ‖H − Ĥ‖/‖H − mean H‖) on the complex response. [%]
    chi2 : float or None
        Σ r² against the data's σ (None without per-line σ). [-]
    dof : int
        Degrees of freedom of the test (2·n_lines).
    p_value : float or None
        P(χ²_dof ≥ chi2); None without per-line σ. [-]
    adequate : bool
        The model is consistent with the data at this temperature.
    rms_db : float
        RMS of 20·log10|H/Ĥ|. [dB]
    rms_deg : float
        RMS of ∠(H/Ĥ). [deg]
    reason : str
        The test's sentence.
    """

    temperature_c: float
    n_lines: int
    fit_percent: float
    chi2: float | None
    dof: int
    p_value: float | None
    adequate: bool
    rms_db: float
    rms_deg: float
    reason: str

    def to_dict(self) -> dict:
        """JSON-ready data (non-finite numbers as None)."""
        def num(v):
            return None if v is None or not math.isfinite(v) else float(v)

        return {"temperature_c": float(self.temperature_c), "n_lines": int(self.n_lines),
                "fit_percent": num(self.fit_percent), "chi2": num(self.chi2), "dof": int(self.dof),
                "p_value": num(self.p_value), "adequate": bool(self.adequate), "rms_db": num(self.rms_db),
                "rms_deg": num(self.rms_deg), "reason": self.reason}


@dataclass(frozen=True)
class Comparison:
    """A model against data, per temperature (:func:`compare`).

    Parameters
    ----------
    model_name : str
        What was compared.
    data : FrequencySweep
        The data.
    predicted : FrequencySweep
        The model on the data's lines, in the data's units.
    fits : tuple of TemperatureFit
        One per data temperature, coldest first.
    notes : tuple of str
        What the reader should know (e.g. the data are those the model was fitted to).
    model : object
        The model compared (for drawing it on a finer grid, :func:`scenarios.plots.plot_compare`).
    """

    model_name: str
    data: FrequencySweep
    predicted: FrequencySweep
    fits: tuple
    notes: tuple = field(default=())
    model: object = field(default=None, repr=False, compare=False)

    @property
    def adequate(self) -> bool:
        """The model is consistent with the data at every temperature."""
        return all(f.adequate for f in self.fits)

    @property
    def misfits(self) -> list:
        """The temperatures where it is not (:class:`TemperatureFit` records)."""
        return [f for f in self.fits if not f.adequate]

    def verdict(self) -> str:
        """One sentence: fits everywhere, or where it does not."""
        if self.adequate:
            return f"{self.model_name} is consistent with the data at every temperature"
        bad = self.misfits
        return (f"{self.model_name} DOES NOT FIT the data at {', '.join(f'{f.temperature_c:g}' for f in bad)} °C: "
                + "; ".join(f"{f.temperature_c:g} °C: {f.reason}" for f in bad))

    def table(self) -> str:
        """A plain-text table of the fit figures."""
        lines = [f"{'T [°C]':>8} {'lines':>6} {'fit %':>8} {'chi2':>10} {'dof':>5} {'p':>9} {'rms dB':>8} "
                 f"{'rms deg':>8}  verdict"]
        for f in self.fits:
            chi2 = "n/a" if f.chi2 is None else f"{f.chi2:.4g}"
            p = "n/a" if f.p_value is None else f"{f.p_value:.2g}"
            lines.append(f"{f.temperature_c:8g} {f.n_lines:6d} {f.fit_percent:8.2f} {chi2:>10} {f.dof:5d} {p:>9} "
                         f"{f.rms_db:8.3g} {f.rms_deg:8.3g}  {'fits' if f.adequate else 'MISFIT'}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready data."""
        return {"format": "ipmc-comparison", "version": 1, "model": self.model_name, "adequate": self.adequate,
                "verdict": self.verdict(), "temperatures": [f.to_dict() for f in self.fits],
                "notes": list(self.notes), "data_fingerprint": self.data.fingerprint()}


def compare(model, data, *, quantity: str | None = None) -> Comparison:
    """Model vs data per temperature: fit % and χ² (see the module doc).

    Parameters
    ----------
    model : ModelFile, RationalModel, FrequencyModel, str or Path
        The model, or a file :func:`load_any_model` reads.
    data : FrequencySweep, str or Path
        The data, or a sweep file (.csv, .npz, .mat).
    quantity : str or None
        Physics quantity the data hold (default the model file's, else the kind's primary one).

    Returns
    -------
    Comparison
    """
    from physmodel.estimation.residuals import goodness_of_fit, noise_std, residuals

    if isinstance(model, (str, Path)):
        model = load_any_model(model)
    if isinstance(data, (str, Path)):
        from physmodel.data.files import read_sweep

        data = read_sweep(data)
    if not isinstance(data, FrequencySweep):
        raise IPMCError(f"data must be a FrequencySweep or a sweep file, got {type(data).__name__}")
    pred = predict_sweep(model, like=data, quantity=quantity, uncertainty=False)
    _, _, estimated = noise_std(data)
    fits = []
    for t in data.temperatures():
        m = data.temperature_c == t
        d, g = data.select(t), pred.response[m]
        r = residuals(g, d)
        chi2 = float(r @ r)
        gof = goodness_of_fit(0.5 * chi2, r.size, 0, estimated)
        q = d.response / g
        fits.append(TemperatureFit(float(t), int(m.sum()), _fit_percent(g, d.response),
                                   None if estimated else chi2, int(r.size), gof.p_value, bool(gof.adequate),
                                   float(np.sqrt(np.mean((20 * np.log10(np.abs(q))) ** 2))),
                                   float(np.sqrt(np.mean(np.degrees(np.angle(q)) ** 2))), gof.reason))
    notes = []
    prov = getattr(model, "provenance", None)
    if prov is not None and prov.data_fingerprint and prov.data_fingerprint == data.fingerprint():
        notes.append("these are the data the model was fitted to: χ² here counts no fitted parameter, so it is "
                     "slightly larger than the fit's own")
    if estimated:
        notes.append("the data carry no per-line σ: the verdict is the implied-noise test, χ² not reported")
    return Comparison(model_name(model), data, pred, tuple(fits), tuple(notes), model)



def _fit_percent(predicted, response) -> float:
    from surrogate.metrics import fit_percent

    try:
        return fit_percent(predicted, response)
    except ValueError:                  # a constant response: the figure is undefined
        return float("nan")
