"""Every figure of the library, behind one face: ``from scenarios.plots import plot_bode, ...``.

Two kinds of function:

- ``plot_*`` draw on the matplotlib ``Axes`` they are given (in a notebook, beside your own
  curves) and return them: :func:`plot_bode` (a sweep with its σ as error bars or bands, a
  physics model at temperatures, a model file or a surrogate with the band its parameters'
  uncertainty gives), :func:`plot_time` (a record's input and output), :func:`plot_compare`
  (a model against data with the fit % per temperature, from :func:`scenarios.comparison.compare`),
  :func:`plot_calibration` (a calibration's overlay and standardised residuals, from
  :func:`physmodel.calibrate`), :func:`plot_residual_bode` (data with ±2σ bands against a model's
  response, and the residuals), :func:`plot_pole_zero_locus`, :func:`plot_poles_zeros_vs_temperature`
  (a scheduled surrogate's roots across temperature) and :func:`plot_pole_zero_maps`.  Figures of
  several panels take ``axes=`` (a grid or a flat sequence in the documented order); every one
  creates a figure when given None, and none saves, shows or closes one;
- the writers (every other name) make a figure — with the ``plot_*`` functions where one fits —
  and write it atomically (temporary file, then rename, :func:`physmodel.data.files.atomic_write`)
  in the format of the file name.

Figures are matplotlib ``Figure`` objects on an Agg canvas (no pyplot state: safe in threads and
workers).  The package is the only place that imports matplotlib, and only when a figure is drawn.
Modules: :mod:`~scenarios.plots.frequency` (Bode plots and comparisons), :mod:`~scenarios.plots.residuals`
(fits against their data), :mod:`~scenarios.plots.timeseries` (signals against time),
:mod:`~scenarios.plots.roots` (poles and zeros), :mod:`~scenarios.plots.chain` (parameter
estimates), :mod:`~scenarios.plots.canvas` (new figures and the writer they share).
"""

from __future__ import annotations

from .chain import a0_series, effect_intervals
from .frequency import bode, bode_overlay, compare_figure, plot_bode, plot_compare, save_bode
from .residuals import (
    calibration_figure,
    diagnosis_figures,
    frf_estimate,
    plot_calibration,
    plot_residual_bode,
    residual_bode,
    residual_bode_pair,
)
from .roots import (
    plot_pole_zero_locus,
    plot_pole_zero_maps,
    plot_poles_zeros_vs_temperature,
    pole_zero_locus,
    pole_zero_maps,
    save_poles_zeros_vs_temperature,
)
from .timeseries import curves, feedforward_check, inversion_traces, plot_time, traces, tracking

__all__ = [
    "plot_bode", "plot_calibration", "plot_compare", "plot_pole_zero_locus", "plot_pole_zero_maps",
    "plot_poles_zeros_vs_temperature", "plot_residual_bode", "plot_time",
    "a0_series", "bode", "bode_overlay", "calibration_figure", "compare_figure", "curves", "diagnosis_figures",
    "effect_intervals", "feedforward_check", "frf_estimate", "inversion_traces", "pole_zero_locus",
    "pole_zero_maps", "residual_bode", "residual_bode_pair", "save_bode", "save_poles_zeros_vs_temperature", "traces", "tracking",
]
