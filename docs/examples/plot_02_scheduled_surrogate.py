"""
Fit a temperature-scheduled surrogate and inspect its pole–zero locus
=====================================================================

Seed 001 fits, at each bath temperature, a low-order zero-pole-gain model of the actuator and
makes the gain, zeros and poles polynomials in temperature.  Here the same is done jointly
(one CasADi/IPOPT problem over all temperatures) on the noise-free physics of the seed 001
strip (``seed001_actuator``: 45 × 11 × 0.3 mm), with two temperatures held out to check the
schedule where it was not fitted.

Fitting the *physics* densely, rather than the few noisy lines of a measurement, is the working
route from measured data to a feedforward: calibrate the physics to the measurement first
(see :ref:`sphx_glr_auto_examples_plot_04_calibration_identifiability.py`), then sweep the
calibrated physics as densely as the surrogate needs.
"""

# %%
# A dense sweep of the physics
# ----------------------------
import matplotlib.pyplot as plt
import numpy as np

from physmodel import ActuatorModel, get_parameter_set
from surrogate import ScheduledFit, relative_rms_error

model = ActuatorModel(get_parameter_set("seed001_actuator"))
frequency_hz = np.logspace(-1, np.log10(9.0), 40)          # seed 001's band, 0.1-9 Hz
temperatures_c = np.array([19.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0])
held_out_c = [35.0, 45.0]
M_mm = model.frequency_response(frequency_hz, temperatures_c)["M"][0] * 1e3   # (n_T, n_f) [mm/V]

# tidy (one row per line) arrays, as a FrequencySweep holds them
T_rows = np.repeat(temperatures_c, frequency_hz.size)
f_rows = np.tile(frequency_hz, temperatures_c.size)
H_rows = M_mm.ravel()
fit_rows = ~np.isin(T_rows, held_out_c)

# %%
# Joint fit: gain, zeros and poles quadratic in temperature
# ---------------------------------------------------------
# ``form="zpk"`` keeps every pole stable at every temperature by construction.
fitter = ScheduledFit(form="zpk", n_zeros=4, n_poles=4, degree=2)
result = fitter.fit(f_rows[fit_rows], T_rows[fit_rows], H_rows[fit_rows])
print(result.summary())
surrogate_model = result.model

# %%
# Check at the held-out temperatures
# ----------------------------------
# The relative RMS error against the physics the fit never saw.
for T in held_out_c:
    i = int(np.flatnonzero(temperatures_c == T)[0])
    pred = surrogate_model.frequency_response(frequency_hz, T)
    print(f"held-out {T:g} °C: relative RMS error {relative_rms_error(pred, M_mm[i]):.4f}")

# %%
# Pole–zero locus against temperature
# -----------------------------------
# ``zeros(T)`` and ``poles(T)`` are in rad/s.  Zeros in the right half-plane make the model
# non-minimum phase: its inverse is unstable unless it runs backwards in time (stable
# noncausal inversion, package ``inversion``).
T_dense = np.linspace(temperatures_c.min(), temperatures_c.max(), 37)
fig, ax = plt.subplots(figsize=(6.5, 4.5))
for T in T_dense:
    c = plt.cm.coolwarm((T - T_dense[0]) / (T_dense[-1] - T_dense[0]))
    z, p = surrogate_model.zeros(T), surrogate_model.poles(T)
    ax.plot(z.real, z.imag, "o", mfc="none", color=c, ms=5)
    ax.plot(p.real, p.imag, "x", color=c, ms=5)
ax.axvline(0, color="k", lw=0.6)
ax.set_xlabel("Re s [rad/s]")
ax.set_ylabel("Im s [rad/s]")
ax.set_title("zeros (o) and poles (x), 19 °C (blue) to 55 °C (red)")
sm = plt.cm.ScalarMappable(cmap="coolwarm", norm=plt.Normalize(T_dense[0], T_dense[-1]))
fig.colorbar(sm, ax=ax, label="temperature [°C]")
fig.tight_layout()

rhp = [int(np.sum(surrogate_model.zeros(T).real > 0)) for T in T_dense]
print(f"right-half-plane zeros between {T_dense[0]:g} and {T_dense[-1]:g} °C: {min(rhp)}..{max(rhp)}")
print("stable on a dense temperature grid:", surrogate_model.stability_check().stable)

# %%
# Bode plot: data, fit and held-out check
# ---------------------------------------
fig, (ax_m, ax_p) = plt.subplots(2, 1, figsize=(6.5, 5.5), sharex=True)
for i, T in enumerate(temperatures_c):
    c = plt.cm.coolwarm(i / (temperatures_c.size - 1))
    pred = surrogate_model.frequency_response(frequency_hz, T)
    style = "s" if T in held_out_c else "."
    ax_m.semilogx(frequency_hz, 20 * np.log10(np.abs(M_mm[i])), style, color=c, ms=4)
    ax_m.semilogx(frequency_hz, 20 * np.log10(np.abs(pred)), "-", color=c, lw=1)
    ax_p.semilogx(frequency_hz, np.degrees(np.unwrap(np.angle(M_mm[i]))), style, color=c, ms=4)
    ax_p.semilogx(frequency_hz, np.degrees(np.unwrap(np.angle(pred))), "-", color=c, lw=1)
ax_m.set_ylabel("|M| [dB mm/V]")
ax_p.set_ylabel("∠M [deg]")
ax_p.set_xlabel("frequency [Hz]")
ax_m.set_title("physics (dots; squares held out) and scheduled surrogate (lines)")
fig.tight_layout()
