"""
Diagnose a discrepancy and read the report
==========================================

A calibrated model that does not fit everywhere is missing something.  ``physmodel.diagnose``
calibrates the base model, locates where the standardised residuals leave their band, refits
the model with each named effect of the library switched on, and accepts an effect only if its
likelihood-ratio statistic beats a Monte Carlo null threshold (family-wise false-positive rate
``alpha``).  The verdict is ``none``, ``named``, ``ambiguous`` or ``unexplained`` — it never
forces a name (discrepancy.md).

Here the data come from the seed 002 strip with a first-order measurement amplifier of 5 ms
time constant that the base model does not have.
"""

# %%
# Data with a hidden effect
# -------------------------
import matplotlib.pyplot as plt
import numpy as np

from physmodel import LIBRARY, EffectModel, diagnose, get_parameter_set
from physmodel.sweep import MagnitudePhaseNoise, synthesize_sweep

base = get_parameter_set("seed002_table3")
print("candidate effects:", ", ".join(LIBRARY))

hidden = EffectModel(base, "actuator", {"amplifier_bandwidth": {"time_constant": 5e-3}})
data = synthesize_sweep(hidden, "M", np.logspace(np.log10(0.5), np.log10(50.0), 40), [20.0, 40.0, 60.0],
                        noise=MagnitudePhaseNoise(0.1, 1.0), seed=3)

# %%
# Diagnose
# --------
# ``free`` are the parameters you would calibrate anyway; every candidate is refitted on top
# of them.  ``null_draws`` and ``null_refits`` set the Monte Carlo null (smaller here than the
# defaults to keep the example short).
diag = diagnose(data, base, kind="actuator", free=["alpha0"], null_draws=1000, null_refits=2, seed=0)
print(diag.summary())

# %%
# Reading the report
# ------------------
# * the localisation table: where (band × temperature × magnitude/phase) the baseline leaves
#   its ±band, before and after;
# * each candidate's likelihood-ratio statistic against the null threshold, with AIC/BIC;
# * confusable pairs: effects whose signatures the data cannot tell apart (a delay, an
#   amplifier pole and a lumped electrode resistance are close to first order);
# * the verdict, and the weighted cost and RMS dB/degrees before and after.
print("verdict:", diag.verdict, diag.named)
if diag.verdict == "named":
    print(diag.named_effect())
before, after = diag.gap_before, diag.gap_after
print(f"weighted cost before {before['cost']:.4g}, after {after['cost']:.4g} "
      f"(a correct model: {after['expected_cost']:.1f} ± {after['cost_std']:.1f})")

# %%
# Before/after on the data
# ------------------------
T0 = 60.0
rows = data.temperature_c == T0
fig, (ax_m, ax_p) = plt.subplots(2, 1, figsize=(6.5, 5), sharex=True)
f = data.frequency_hz[rows]
for label, G, style in (("data", data.response[rows], "k."),
                        ("base model, calibrated", diag.predicted_before[rows], "C0-"),
                        ("with the named effect", diag.predicted_after[rows], "C1--")):
    ax_m.semilogx(f, 20 * np.log10(np.abs(G)), style, label=label)
    ax_p.semilogx(f, np.degrees(np.unwrap(np.angle(G))), style)
ax_m.set_ylabel("|M| [dB mm/V]")
ax_p.set_ylabel("∠M [deg]")
ax_p.set_xlabel("frequency [Hz]")
ax_m.set_title(f"{T0:g} °C")
ax_m.legend(fontsize=8)
fig.tight_layout()
