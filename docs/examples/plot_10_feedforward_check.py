"""
Compute a feedforward and check it on the plant
================================================

A feedforward voltage is only as good as the plant it drives.  This example computes the voltage
for a faded 1 Hz reference from a temperature-scheduled surrogate of the seed 001 actuator, refuses
anything above 3 V, drives the *physics* (the plant, not the surrogate) with it, and compares the
tracking error with the steady-state prediction :math:`A\\,|P(j\\omega)/G(j\\omega) - 1|`, where
:math:`P` is the physics and :math:`G` the surrogate — an oracle that does not use the time
simulation.  It also compares the automatic preview with the infinite one and with the seed 000
rule 4/r0.
"""

# %%
# A schedule fitted to dense physics sweeps (the physics-calibrated route)
# ------------------------------------------------------------------------
import warnings

import matplotlib.pyplot as plt
import numpy as np

from inversion import Limits, feedforward
from inversion.references import sine
from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.timesim import simulate
from surrogate import ScheduledFit

plant = ActuatorModel(get_parameter_set("seed001_actuator"))
f = np.logspace(-1, np.log10(9.0), 40)
temps = np.arange(19.0, 56.0, 6.0)
M_mm = plant.response(f, temps) * 1e3                       # (n_T, n_f) mm/V
fit = ScheduledFit("zpk", 4, 4, 2).fit(np.tile(f, temps.size), np.repeat(temps, f.size), M_mm.ravel())
G = fit.model.at(40.0)                                     # V -> mm at 40 °C, s in rad/s

# %%
# The voltage, with a limit
# -------------------------
# The reference fades in and out (the noncausal inverse needs room at both ends).
fs = 4000.0
ref = sine(0.3, 1.0, duration_s=6.0, fs_hz=fs, fade_in_s=1.0, fade_out_s=1.0, unit="mm")
# A violation warns here (``action="warn"``) so that all three can be compared; the default refuses.
runs = {}
for p in ("auto", "inf", "4/r0"):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs[p] = feedforward(G, ref.t, ref.y, preview=p, limits=Limits(max_voltage=3.0, action="warn"))
    flag = f"  <- {caught[0].message}" if caught else ""
    print(f"preview {p:>4}: {runs[p].preview_s:.3f} s, peak {np.max(np.abs(runs[p].output)):.3f} V{flag}")

# %%
# On the plant
# ------------
u = runs["auto"].output
tip_mm = simulate(plant, 40.0, ref.t, u).output * 1e3            # the physics driven by the voltage [mm]
body = (ref.t > ref.t[0] + 2.5) & (ref.t < ref.t[-1] - 2.5)    # between the fades
err = np.max(np.abs(tip_mm - ref.y)[body])
P = plant.response([1.0], [40.0])[0, 0] * 1e3
Gj = fit.model.response([1.0], 40.0)[0, 0]
predicted = 0.3 * abs(P / Gj - 1)
print(f"tracking error between the fades {err * 1e3:.2f} um; steady-state prediction {predicted * 1e3:.2f} um")
assert 0.5 < err / predicted < 2.0, (err, predicted)

fig, (ax_u, ax_y) = plt.subplots(2, 1, figsize=(6.5, 5), sharex=True)
for p, r in runs.items():
    ax_u.plot(ref.t, r.output, label=f"preview {p}")
ax_u.set_ylabel("voltage [V]")
ax_u.legend(fontsize=8)
ax_y.plot(ref.t, ref.y, "k", lw=2, label="reference")
ax_y.plot(ref.t, tip_mm, "--", label="physics driven by the auto-preview voltage")
ax_y.set_ylabel("tip displacement [mm]")
ax_y.set_xlabel("time [s]")
ax_y.legend(fontsize=8)
fig.tight_layout()
