"""
Simulate an actuator across temperature
=======================================

The Chen–Tan actuator model of seed 002 (Table 3 strip: 15 mm × 4 mm × 0.25 mm) evaluated at
five bath temperatures in one vectorised call.  ``M = H·G`` is the tip displacement per volt;
``Z`` the terminal impedance.  Frequencies are in Hz and temperatures in °C at the edges; every
array is SI inside (m/V, Ω).
"""

# %%
# Evaluate the physics
# --------------------
# ``frequency_response`` returns arrays of shape (n_parameter_sets, n_temperatures,
# n_frequencies).  The temperature laws of the parameter set (Arrhenius diffusivity, falling
# modulus, water permittivity, ...) move every parameter with temperature.
import matplotlib.pyplot as plt
import numpy as np

from physmodel import ActuatorModel, describe, get_parameter_set

params = get_parameter_set("seed002_table3")
print(describe(params))

model = ActuatorModel(params)
frequency_hz = np.logspace(-2, 2, 300)
temperatures_c = [5.0, 20.0, 35.0, 50.0, 65.0]
response = model.frequency_response(frequency_hz, temperatures_c)
M = response["M"][0]            # (n_T, n_f) tip displacement per volt [m/V]
Z = response["Z"][0]            # (n_T, n_f) terminal impedance [Ω]

# %%
# Closed-form DC gain and the first mode
# --------------------------------------
# ``dc_gain`` evaluates the s → 0 limits in closed form (the transfer functions themselves are
# singular at s = 0).  Seed 002 reports a DC gain of a few mm/V for this strip.
dc = model.dc_gain(temperatures_c)["M0"][0] * 1e3       # [mm/V]
state = model.state(temperatures_c)
fn_hz = state.omega_n[0, :, 0] / (2 * np.pi)            # first bending mode [Hz]
for T, g, f in zip(temperatures_c, dc, fn_hz):
    print(f"{T:5.1f} °C   M(0) = {g:6.3f} mm/V   first mode {f:5.2f} Hz")

# %%
# Bode plot of M and Z
# --------------------
fig, (ax_mag, ax_ph, ax_z) = plt.subplots(3, 1, figsize=(6.5, 7.5), sharex=True)
colors = plt.cm.coolwarm(np.linspace(0, 1, len(temperatures_c)))
for i, T in enumerate(temperatures_c):
    ax_mag.semilogx(frequency_hz, response.magnitude_db("M", 1e3)[0, i], color=colors[i], label=f"{T:g} °C")
    ax_ph.semilogx(frequency_hz, response.phase_deg("M")[0, i], color=colors[i])
    ax_z.loglog(frequency_hz, np.abs(Z[i]), color=colors[i])
ax_mag.set_ylabel("|M| [dB mm/V]")
ax_ph.set_ylabel("∠M [deg]")
ax_z.set_ylabel("|Z| [Ω]")
ax_z.set_xlabel("frequency [Hz]")
ax_mag.legend(fontsize=8, ncol=2)
fig.tight_layout()

# %%
# A finite-order model for control design
# ---------------------------------------
# Seed 002 §2.2.4 replaces X(s) by a Taylor series (eqs. 17–22); order 3 is what the paper
# needs to match the infinite-dimensional model around the first mode.  The result is a
# ``control.TransferFunction`` (s in rad/s, output in m/V).
reduced = model.reduced(25.0, taylor_order=3)
exact = model.frequency_response(frequency_hz, [25.0])["M"][0, 0]
approx = reduced(2j * np.pi * frequency_hz)
band = frequency_hz <= 20.0
err_db = np.max(np.abs(20 * np.log10(np.abs(approx[band] / exact[band]))))
print(f"order-3 Taylor model: {len(reduced.poles())} poles, max |error| {err_db:.2f} dB up to 20 Hz")
