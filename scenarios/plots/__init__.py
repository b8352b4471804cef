"""Every figure of the library, behind one face: ``from scenarios.plots import plot_bode, ...``.

Two kinds of function:

- ``plot_*`` draw on the matplotlib ``Axes`` they are given (in a notebook, beside your own
  curves) and return them: :func:`plot_bode` (a sweep with its σ as error bars or bands, a
  physics model at temperatures, a model file or a surrogate with the band its parameters'
  uncertainty gives), :func:`plot_time` (a record's input and output), :func:`plot_compare`
  (a model against data with the fit % per temperature, from :func:`scenarios.comparison.compare`);
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
from .residuals import calibration_figure, diagnosis_figures, frf_estimate, residual_bode
from .roots import pole_zero_locus, pole_zero_maps, save_poles_zeros_vs_temperature
from .timeseries import curves, feedforward_check, inversion_traces, plot_time, traces, tracking

__all__ = [
    "plot_bode", "plot_compare", "plot_time",
    "a0_series", "bode", "bode_overlay", "calibration_figure", "compare_figure", "curves", "diagnosis_figures",
    "effect_intervals", "feedforward_check", "frf_estimate", "inversion_traces", "pole_zero_locus",
    "pole_zero_maps", "residual_bode", "save_bode", "save_poles_zeros_vs_temperature", "traces", "tracking",
]
