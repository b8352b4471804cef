"""
Export to python-control and MATLAB
===================================

Everything the library fits or reduces is available as a python-control object (s in rad/s),
and sweeps and surrogates are plain arrays that MATLAB reads from a ``.mat`` file.

* ``RationalModel.at(T)`` → ``control.TransferFunction`` at a temperature;
* ``ActuatorModel.reduced(T, taylor_order)`` → seed 002's finite-order model as a
  ``control.TransferFunction``;
* ``FrequencySweep.to_frd(T)`` → ``control.FrequencyResponseData``;
* ``FrequencySweep.to_mat(path)`` → MATLAB v5 ``.mat`` with one column per field;
* a surrogate's schedule as ``num``/``den`` arrays over a temperature grid, for ``tf`` in
  MATLAB.
"""

# %%
# A sweep and a surrogate
# -----------------------
import tempfile
from pathlib import Path

import control
import matplotlib.pyplot as plt
import numpy as np
from scipy.io import loadmat, savemat

from physmodel import ActuatorModel, get_parameter_set, synthesize_sweep
from surrogate import fit_sweep

model = ActuatorModel(get_parameter_set("seed002_table3"))
sweep = synthesize_sweep(model, "M", np.logspace(-1, 2, 60), [20.0, 30.0, 40.0, 50.0])   # mm/V
result = fit_sweep(sweep, n_zeros=3, n_poles=4, degree=2, form="zpk")
surr = result.model
print(result.summary().splitlines()[0])

# %%
# python-control
# --------------
G30 = surr.at(30.0)                         # control.TransferFunction, V -> mm
print(G30)
frd = sweep.to_frd(30.0)                    # control.FrequencyResponseData (omega in rad/s)
reduced = model.reduced(30.0, taylor_order=3)   # m/V, seed 002 eqs. (17)-(22)
print(f"reduced model: {len(reduced.poles())} poles; DC gain {float(np.real(reduced(0))) * 1e3:.3f} mm/V; "
      f"surrogate DC gain {float(np.real(G30(0))):.3f} mm/V")
ss30 = control.ss(G30)                      # state space, for controller design
print(f"state space: {ss30.nstates} states; poles {np.round(np.sort_complex(ss30.poles()), 2)} rad/s")

omega = frd.omega
fig, ax = plt.subplots(figsize=(6.5, 4))
ax.semilogx(omega, 20 * np.log10(np.abs(frd.eval(omega))), "k.", label="sweep (FRD)")
ax.semilogx(omega, 20 * np.log10(np.abs(G30(1j * omega))), label="surrogate.at(30)")
ax.semilogx(omega, 20 * np.log10(np.abs(reduced(1j * omega) * 1e3)), "--", label="reduced(30), order 3")
ax.set_xlabel("ω [rad/s]")
ax.set_ylabel("|M| [dB mm/V]")
ax.legend()
fig.tight_layout()

# %%
# MATLAB
# ------
# ``to_mat`` writes the sweep's columns (``temperature_c``, ``frequency_hz``, ``magnitude_db``,
# ``phase_deg``, the complex ``response``) and header strings; the schedule goes out as
# coefficient arrays.  In MATLAB::
#
#     S = load('sweep.mat');  G = load('surrogate.mat');
#     k = find(G.temperature_c == 30);
#     G30 = tf(G.num(k, :), G.den(k, :));     % s in rad/s, V -> mm
#     bode(G30)
out = Path(tempfile.mkdtemp())
sweep.to_mat(out / "sweep.mat")
grid_c = np.arange(20.0, 51.0, 5.0)
coeffs = [surr.coefficients(T) for T in grid_c]
num = np.array([np.pad(n, (d.size - n.size, 0)) for n, d in coeffs])   # same width as den
den = np.array([d for _, d in coeffs])
savemat(out / "surrogate.mat", {"temperature_c": grid_c.reshape(-1, 1), "num": num, "den": den,
                                "units": "input V, output mm, s in rad/s"})

back = loadmat(out / "surrogate.mat")
k = int(np.flatnonzero(back["temperature_c"].ravel() == 30.0)[0])
G30_back = control.tf(back["num"][k], back["den"][k])
print("read back from surrogate.mat:", np.allclose(G30_back(1j * omega), G30(1j * omega), rtol=1e-12))
print("sweep.mat variables:", sorted(k for k in loadmat(out / "sweep.mat") if not k.startswith("__")))
