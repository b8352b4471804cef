"""
From a measured sweep to a feedforward: the working route
=========================================================

A measurement gives a few noisy lines at a few temperatures.  Fitting a temperature-scheduled
surrogate to those lines directly leaves its schedule poorly constrained between and beyond
them.  The route that works:

1. **calibrate** the physics to the measurement (few, physically meaningful parameters);
2. **sweep the calibrated physics densely** (many temperatures and frequencies, no noise);
3. **fit the scheduled surrogate** to that sweep, holding temperatures out to check it;
4. **invert** the surrogate at the operating temperature for a feedforward.

The "measurement" here is synthetic: the seed 001 strip with changed diffusivity, coupling and
modulus law, at five temperatures with 0.2 dB / 1° noise, so each step can be checked.
"""

# %%
# 0. The measurement
# ------------------
import control
import matplotlib.pyplot as plt
import numpy as np

from inversion import feedforward
from physmodel import ActuatorModel, LogLinear, MagnitudePhaseNoise, calibrate, get_parameter_set, synthesize_sweep
from surrogate import ScheduledFit, relative_rms_error

start = get_parameter_set("seed001_actuator")          # what we believe before measuring
truth = start.replace(d=1.3 * start.d, alpha0=0.85 * start.alpha0,
                      laws=start.laws.with_(E=LogLinear(slope=-0.011)))
measured = synthesize_sweep(ActuatorModel(truth), "M", np.logspace(-1, np.log10(9.0), 15),
                            [19.0, 28.0, 37.0, 46.0, 55.0],
                            noise=MagnitudePhaseNoise(0.2, 1.0), seed=7)
print(f"measurement: {measured.frequency_hz.size} lines at {measured.temperatures().tolist()} °C "
      f"[{measured.output_unit}/{measured.input_unit}]")

# %%
# 1. Calibrate
# ------------
# Free what the 0.1–9 Hz band can see: the coupling ``alpha0`` (gain), the diffusivity ``d``
# (electrical corner), the mode (``omega_n``, ``xi``) and the modulus temperature slope
# ``laws.E.slope`` [1/K] (the mode moves with T).
cal = calibrate(measured, start, ["alpha0", "d", "omega_n", "xi", "laws.E.slope"], starts=3, seed=0)
print(cal.summary())
calibrated = cal.parameters
print(f"truth: alpha0 {truth.alpha0:.4g} J/C, d {truth.d:.4g} m²/s, laws.E.slope {truth.laws.E.slope:.4g} 1/K")

# %%
# 2. Sweep the calibrated physics densely
# ---------------------------------------
frequency_hz = np.logspace(-1, np.log10(9.0), 40)
temperatures_c = np.arange(19.0, 56.0, 4.0)              # 19, 23, ..., 55 °C
held_out_c = [31.0, 47.0]
M_mm = ActuatorModel(calibrated).frequency_response(frequency_hz, temperatures_c)["M"][0] * 1e3
T_rows = np.repeat(temperatures_c, frequency_hz.size)
f_rows = np.tile(frequency_hz, temperatures_c.size)
fit_rows = ~np.isin(T_rows, held_out_c)

# %%
# 3. Scheduled surrogate with held-out temperatures
# -------------------------------------------------
result = ScheduledFit(form="zpk", n_zeros=4, n_poles=4, degree=2).fit(
    f_rows[fit_rows], T_rows[fit_rows], M_mm.ravel()[fit_rows])
surr = result.model
print(result.summary().splitlines()[0])
for T in held_out_c:
    i = int(np.flatnonzero(temperatures_c == T)[0])
    err = relative_rms_error(surr.frequency_response(frequency_hz, T), M_mm[i])
    print(f"held-out {T:g} °C: surrogate vs calibrated physics, relative RMS {err:.4f}")

# The surrogate against the measurement itself (which also contains the noise, ~2-3 % per line):
for T in measured.temperatures():
    line = measured.select(T)
    err = relative_rms_error(surr.frequency_response(line.frequency_hz, T), line.response)
    print(f"measured {T:g} °C: surrogate vs data, relative RMS {err:.3f}")

# %%
# 4. Feedforward at 40 °C
# -----------------------
# ``surr.at(T)`` is a ``control.TransferFunction`` (V → mm, s in rad/s); ``feedforward`` runs the
# stable noncausal inverse (infinite preview here: the whole reference is known in advance).
# The inverse is discretised exactly for the piecewise-linear interpolant of the samples; the
# mismatch with the continuous model falls as 1/fs² (1.8e-2 mm at 400 Hz, 1.8e-4 mm at 4 kHz).
fs = 4000.0
t = np.arange(0.0, 12.0, 1.0 / fs)
envelope = np.clip((t - 1.0) / 2.0, 0, 1) * np.clip((t[-1] - 1.0 - t) / 2.0, 0, 1)
desired_mm = 0.5 * envelope * np.sin(2 * np.pi * 1.0 * t)
G40 = surr.at(40.0)
ff = feedforward(G40, t, desired_mm, preview="inf")
voltage = ff.output
print(f"feedforward: peak {np.max(np.abs(voltage)):.3f} V for a 0.5 mm, 1 Hz reference")

# consistency with the model it inverts (not yet a check on the plant: see the note below)
y_model = control.forced_response(G40, t, voltage).outputs
print(f"surrogate driven by the feedforward: max |y - desired| = {np.max(np.abs(y_model - desired_mm)):.2e} mm")

fig, (ax_v, ax_y) = plt.subplots(2, 1, figsize=(6.5, 5), sharex=True)
ax_v.plot(t, voltage)
ax_v.set_ylabel("feedforward [V]")
ax_y.plot(t, desired_mm, "k", lw=2, label="desired")
ax_y.plot(t, y_model, "--", label="surrogate output")
ax_y.set_ylabel("tip displacement [mm]")
ax_y.set_xlabel("time [s]")
ax_y.legend()
fig.tight_layout()

# %%
# The check that matters is the feedforward applied to the *plant* (the physics at 40 °C, or the
# strip itself).  ``ipmc demo`` and the ``seed001_actuator`` scenario do it on the physics and
# compare the error with the steady-state prediction :math:`A\,|P(j\omega)/G(j\omega) - 1|`.
