"""
Your strip, from records to a voltage that works on it
======================================================

A strip of your own (its own width, a 3 ms acquisition delay the baseline physics lacks) is
measured at four temperatures.  Calibrating the physics alone leaves a misfit — and the verdict
says so; the discrepancy workflow names the delay, adds it and refits; that **model file** (effects
and verdict included) is what the dense sweep, the surrogate and the feedforward are built from;
and the feedforward's error is **predicted from the measured sweep**, then compared with what the
voltage does on the strip at a temperature between the measured ones.

The "strip" here is simulated with the library's own effect code, to keep the example short;
``tests/benchmarks/bench_journey.py`` runs the same journey from the command line on strips from an
independently written generator.
"""

# %%
# The strip and its measurement
# -----------------------------
import matplotlib.pyplot as plt
import numpy as np

from inversion import feedforward, references
from physmodel import EffectModel, MagnitudePhaseNoise, calibrate, diagnose, get_parameter_set, synthesize_sweep
from physmodel.data.fftsim import simulate_at_rest
from surrogate import ScheduledFit
from surrogate.strip_check import misfit_to_data, predicted_error

start = get_parameter_set("seed001_actuator", W=9e-3)          # our geometry, a generic start
strip = EffectModel(start.replace(d=1.2 * start.d, alpha0=0.9 * start.alpha0), "actuator",
                    {"time_delay": {"delay": 3e-3}})           # what the lab really has
measured = synthesize_sweep(strip, "M", np.logspace(-1, 1, 24), [20.0, 30.0, 40.0, 50.0],
                            noise=MagnitudePhaseNoise(0.05, 0.3), seed=11).in_units("V", "mm")

# %%
# Calibrate the physics: the verdict says it does not fit
# -------------------------------------------------------
cal = calibrate(measured, start, ["alpha0", "d"], starts=2, seed=0)
print(cal.goodness_of_fit.reason)
print("model file verdict:", cal.to_model_file().describe())

# %%
# Diagnose: the delay is named, added and refitted — and carried in the model file
# --------------------------------------------------------------------------------
d = diagnose(measured, start, free=["alpha0", "d"], laws="set", null_draws=400, null_refits=0, seed=0)
model_file = d.to_model_file()
print(d.verdict, d.named)
print(model_file.describe())

# %%
# Sweep that model densely, fit a scheduled surrogate, invert it at 35 °C
# -----------------------------------------------------------------------
physics = model_file.model()                                   # the physics *with* the named delay
dense = synthesize_sweep(physics, "M", np.logspace(-1, 1, 40), np.arange(20.0, 51.0, 5.0)).in_units("V", "mm")
sur = ScheduledFit("zpk", 4, 4, 2).fit_data(dense).model
ref = references.sine(0.3, 1.0, 8.0, 1000.0, lead_s=1.0, tail_s=1.0, unit="mm")
ff = feedforward(sur.at(35.0), ref.t, ref.y)
print(f"peak voltage {ff.limit_report.peak:.3g} V")

# %%
# Predicted on the strip (from the measured sweep) vs achieved on the strip
# -------------------------------------------------------------------------
residual = simulate_at_rest(sur, 35.0, ref.t, ff.output).y - ref.y           # the inversion's own error
pred = predicted_error(misfit_to_data(sur, measured), 35.0, ref.t, ref.y, inversion_residual=residual)
y_strip = simulate_at_rest(strip, 35.0, ref.t, ff.output).y * 1e3             # m -> mm
achieved = np.sqrt(np.mean((y_strip - ref.y) ** 2) / np.mean(ref.y ** 2))
print(f"predicted on the strip: {pred.sentence()}")
print(f"achieved on the strip: {100 * achieved:.3g} % RMS of the reference")

fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax[0].plot(ref.t, ref.y, label="reference")
ax[0].plot(ref.t, y_strip, "--", label="strip")
ax[0].set_ylabel("tip [mm]")
ax[0].legend()
ax[1].plot(ref.t, 1e3 * (y_strip - ref.y))
ax[1].set_ylabel("error [µm]")
ax[1].set_xlabel("time [s]")
ax[0].set_title(f"35 °C: predicted {100 * pred.rms:.2g} %, achieved {100 * achieved:.2g} % RMS")
fig.tight_layout()
