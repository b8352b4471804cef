"""
Model vs your data: Bode plots on your own Axes, bands, and a fit figure per temperature
========================================================================================

``scenarios.plots.plot_bode`` draws a sweep or a model on matplotlib Axes you give it (in a
notebook, beside your own curves) and returns them: a measured sweep with its per-line σ as
error bars, a physics model at any temperatures, and a calibrated model with the band its
parameters' 95 % intervals give.  ``scenarios.comparison.compare`` puts a model against data
and gives, per temperature, the fit % of system-identification toolboxes,
100·(1 − ‖H − Ĥ‖/‖H − mean H‖) on the complex response, and χ² against the data's σ with its
verdict.  ``ipmc compare MODEL DATA -o FOLDER`` does the same from the command line.  The
Bode, time, calibration, residual and pole-zero figures have such a ``plot_*`` form
(``plot_calibration`` below; the list is in :mod:`scenarios.plots`).

The "measurement" here is a synthetic sweep of the seed 002 strip whose diffusion coefficient is
30 % larger than the named set's, so the named set should misfit and a calibration should not.
"""

# %%
# Data, and the named set against it
# ----------------------------------
import matplotlib.pyplot as plt
import numpy as np

from physmodel import ActuatorModel, MagnitudePhaseNoise, calibrate, get_parameter_set, load_model, synthesize_sweep
from scenarios.comparison import compare
from scenarios.plots import plot_bode, plot_calibration, plot_compare
from scenarios.prediction import predict_sweep

base = get_parameter_set("seed002_table3")
truth = base.replace(d=1.3 * base.d)
f = np.geomspace(0.1, 30.0, 30)
data = synthesize_sweep(ActuatorModel(truth), "M", f, [20.0, 40.0], noise=MagnitudePhaseNoise(0.2, 2.0), seed=4)

named = load_model("seed002_table3")             # a named set: never compared with data
before = compare(named, data)
print(before.table())
print(before.verdict())

# %%
# Calibrate, then compare again
# -----------------------------
# ``to_model_file`` is what ``ipmc calibrate`` writes as ``model.json``: the parameters with their
# 95 % intervals.  The intervals give the model's band; their correlation comes with the
# calibration result here (``ipmc calibrate`` writes it to ``calibration.json`` beside
# ``model.json``, where ``predict_sweep`` finds it).
result = calibrate(data, base, ["d", "alpha0", "xi"], starts=2, seed=0)
calibrated = result.to_model_file()
after = compare(calibrated, data)
print(after.table())
print(after.verdict())

# %%
# Drawing on your own Axes
# ------------------------
# Left: the data with ±2σ bars and the named set as lines (``align`` puts its phase on the data's
# branch).  Right: ``plot_compare`` of the calibrated model, the fit % in the legend.  Every
# ``plot_*`` returns the Axes it was given, so you keep styling them.
fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
plot_bode(data, axes[:, 0], style="o")
plot_bode(named, axes[:, 0], like=data, label="_named set", align=data, style="--")
axes[0, 0].set_title("data (±2σ) and the named set (dashed)", fontsize=9)
axes[0, 0].legend(fontsize=7)
plot_compare(after, axes[:, 1])
axes[0, 1].set_title("calibrated model vs data", fontsize=9)
axes[0, 1].legend(fontsize=7)
fig.tight_layout()

# %%
# The calibration's residuals
# ---------------------------
# ``plot_calibration`` draws what ``ipmc calibrate`` writes as ``bode.png``, on your Axes: the data
# (markers) and the calibrated model (lines) beside their standardised residuals, which scatter
# within the grey ±2 band when the model fits.
fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharex=True)
plot_calibration(data, result, axes)
axes[0, 0].legend(fontsize=7)
axes[0, 1].set_title(f"cost {result.cost:.3g}, expected {result.expected_cost:.3g}", fontsize=9)
fig.tight_layout()

# %%
# The model's band
# ----------------
# ``predict_sweep`` gives the model as a sweep whose σ are the model's own (the delta method over
# the parameters' intervals and correlation); ``plot_bode`` draws it like a measurement.  Thirty
# lines at two temperatures pin the three parameters well, so the band is narrow: its width, not
# the curve, is what is drawn below.
band = predict_sweep(calibrated, np.geomspace(0.1, 30.0, 200), [20.0, 40.0], like=data,
                     correlation=(result.names, result.correlation))
print(band.metadata["notes"])
fig, ax = plt.subplots(figsize=(7, 3.5))
for t in band.temperatures():
    m = band.temperature_c == t
    ax.semilogx(band.frequency_hz[m], 2 * band.magnitude_std_db[m], label=f"{t:g} °C")
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel("2σ of the model's magnitude [dB]")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
