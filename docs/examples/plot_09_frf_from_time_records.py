"""
Frequency responses from time records, with per-line uncertainty
================================================================

A measured frequency response usually starts as time records: the drive voltage and the laser's
tip displacement, sampled together.  ``physmodel.estimation.frf`` turns such records into a
frequency response with a standard deviation per line (Welch H1/H2 with coherence, or a stepped
sine fitted period by period), and the result is a ``FrequencySweep`` that ``calibrate`` and the
surrogate fitters read like any other.

Here the "experiment" is a virtual one: the seed 002 strip at 25 °C, simulated in the time
domain (``physmodel.data.timesim``) with white laser noise, so the estimate can be checked
against the physics that made the data.
"""

# %%
# A multisine designed for the band, played to the strip
# ------------------------------------------------------
# A multisine is periodic: with the analysis segment equal to one period (rectangular window,
# no overlap) every excited line falls on an FFT bin and there is no leakage.  Schroeder phases
# keep the crest factor low.  One period is played first and discarded (the transient).
import tempfile
from dataclasses import replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy import stats

from physmodel import ActuatorModel, calibrate, get_parameter_set
from physmodel.data.excitation import multisine, settle_time_s, stepped_sine_plan
from physmodel.data.timerecord import TimeRecord, read_record
from physmodel.data.timesim import simulate
from physmodel.estimation.frf import estimate_record
from physmodel.estimation.stepped import stepped_sine

truth = get_parameter_set("seed002_table3")
strip = ActuatorModel(truth)
T_C = 25.0
FS_HZ, PERIOD_S = 1000.0, 2.0                # DAQ rate; 0.5 Hz line spacing
LASER_NOISE_M = 2e-6                         # white noise on the displacement, RMS [m]

lines_hz = np.unique(np.round(np.logspace(np.log10(0.5), 2.0, 40) * PERIOD_S) / PERIOD_S)
design = multisine(lines_hz, FS_HZ, PERIOD_S, rms=1.0)        # 1 V RMS
drive = design.record(periods=16, transient_periods=1)
print(f"{lines_hz.size} lines from {lines_hz[0]:g} to {lines_hz[-1]:g} Hz, crest factor "
      f"{design.crest_factor:.2f}, {drive.t.size} samples ({drive.t[-1]:.0f} s)")

run = simulate(strip, T_C, drive.t, drive.channels["voltage"], output_noise_rms=LASER_NOISE_M, seed=3)

# the record as a DAQ would save it: one file, channels with units, the temperature in the header
record = TimeRecord(run.t, {"voltage": run.input, "tip_displacement": run.output * 1e3},
                    {"voltage": "V", "tip_displacement": "mm"}, {"temperature_c": T_C})
with tempfile.TemporaryDirectory() as tmp:
    path = record.save(Path(tmp) / "run_25C.csv")
    print(path.read_text().splitlines()[:3])
    record = read_record(path)

# %%
# H1 with per-line σ
# ------------------
# The noise is on the output, so H1 = S_uy/S_uu is the unbiased estimator.  σ of each line comes
# from the coherence and the number of averages (Bendat & Piersol): 16 periods give 15 degrees of
# freedom, so ±2σ covers the truth with the Student-t probability for 15 degrees of freedom
# (93.6 %), not 95 %.
est = estimate_record(record, "voltage", method="h1", nperseg=design.n_samples, noverlap=0,
                      window="boxcar", discard_s=PERIOD_S, frequencies_hz=design.frequency_hz)
f = est.frequency_hz
H = est.response[0]                                                    # mm/V
M_exact = strip.frequency_response(f, T_C)["M"][0, 0] * 1e3           # m/V -> mm/V

# %%
# What is the truth of a sampled experiment?
# ------------------------------------------
# The simulator, like a real DAQ, only knows the drive at the samples; between them it
# interpolates linearly (first-order hold).  The strip is therefore driven by the interpolated
# signal, whose spectrum at a line f below the Nyquist frequency is the sampled one times
# sinc²(f/fs) (the Fourier transform of the triangular interpolation kernel; a zero-order hold
# would give sinc(f/fs) and half a sample of delay).  The sampled experiment's transfer function
# is M(j2πf)·sinc²(f/fs): 0.3 dB below M at 100 Hz, a real factor, so the phase is unchanged.
hold = np.sinc(f / FS_HZ) ** 2
M_sampled = M_exact * hold

nu = float(est.n_averages[0]) - 1.0
p_cover = 1.0 - 2.0 * stats.t.sf(2.0, nu)            # P(|t_nu| <= 2)


def coverage(reference):
    d_db = 20 * np.log10(np.abs(H / reference))
    d_deg = np.degrees(np.angle(H / reference))
    return (np.abs(d_db) <= 2 * est.magnitude_std_db[0]), (np.abs(d_deg) <= 2 * est.phase_std_deg[0])


# fewest lines inside ±2σ that is still plausible (0.1 % binomial quantile) if σ is right
n_min = int(stats.binom.ppf(0.001, f.size, p_cover))
for label, ref in (("M(j2πf)", M_exact), ("M(j2πf)·sinc²(f/fs)", M_sampled)):
    in_mag, in_ph = coverage(ref)
    print(f"within ±2σ of {label:20s}: magnitude {in_mag.sum():2d}/{f.size}, phase {in_ph.sum():2d}/{f.size} "
          f"(expected {p_cover * f.size:.1f}, plausible >= {n_min})")
in_mag, in_ph = coverage(M_sampled)
assert in_mag.sum() >= n_min and in_ph.sum() >= n_min, "the per-line σ does not describe the scatter"

# %%
# A stepped sine of the same strip
# --------------------------------
# One frequency at a time, a settling time, then whole periods, each fitted by a three-parameter
# sine fit; σ comes from the scatter between periods (6 periods: 5 degrees of freedom, so σ
# itself is rough).  The settling time comes from the plant: ``settle_time_s`` of the strip's
# poles (its slowest mode decayed to 10⁻³).  A shorter guess, 0.5 s, leaves the start of each
# low-frequency step in the fit, a bias of about one σ that repeats from seed to seed.  The plan
# travels in the signal file's header, so the estimator reads the schedule back from the record.
settle_s = settle_time_s(strip.reduced(T_C))
plan = stepped_sine_plan(np.logspace(0.0, np.log10(80.0), 8), FS_HZ, amplitude=1.0, periods=6, settle_s=settle_s)
played = plan.record()
run2 = simulate(strip, T_C, played.t, played.channels["voltage"], output_noise_rms=LASER_NOISE_M, seed=4)
steps = stepped_sine(run2.t, run2.input, run2.output * 1e3, plan=plan, input_name="voltage", input_unit="V",
                     output_names=["tip_displacement"], output_units=["mm"])
M_steps = strip.frequency_response(steps.frequency_hz, T_C)["M"][0, 0] * 1e3 * np.sinc(steps.frequency_hz / FS_HZ) ** 2
z_steps = 20 * np.log10(np.abs(steps.response[0] / M_steps)) / steps.magnitude_std_db[0]
print(f"stepped sine: settle {settle_s:.2f} s per step, {plan.duration_s:.1f} s for {steps.frequency_hz.size} lines; "
      f"error/σ of the magnitude: {np.array2string(z_steps, precision=2)}")

# %%
# Bode plot: estimates with ±2σ over the physics
# ----------------------------------------------
fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
fd = np.logspace(np.log10(0.4), np.log10(120.0), 300)
Md = strip.frequency_response(fd, T_C)["M"][0, 0] * 1e3 * np.sinc(fd / FS_HZ) ** 2
ax_m.semilogx(fd, 20 * np.log10(np.abs(Md)), "k-", lw=1, label="physics × sinc²(f/fs)")
ax_m.errorbar(f, 20 * np.log10(np.abs(H)), yerr=2 * est.magnitude_std_db[0], fmt="o", ms=3, capsize=2,
              label="H1 from the multisine, ±2σ")
ax_m.errorbar(steps.frequency_hz, 20 * np.log10(np.abs(steps.response[0])), yerr=2 * steps.magnitude_std_db[0],
              fmt="s", ms=4, mfc="none", capsize=2, label="stepped sine, ±2σ")
ax_m.set_ylabel("|M| [dB re 1 mm/V]")
ax_m.legend(fontsize=8)
ax_p.semilogx(fd, np.degrees(np.unwrap(np.angle(Md))), "k-", lw=1)
ax_p.errorbar(f, np.degrees(np.unwrap(np.angle(H))), yerr=2 * est.phase_std_deg[0], fmt="o", ms=3, capsize=2)
ax_p.errorbar(steps.frequency_hz, np.degrees(np.unwrap(np.angle(steps.response[0]))),
              yerr=2 * steps.phase_std_deg[0], fmt="s", ms=4, mfc="none", capsize=2)
ax_p.set_ylabel("phase [deg]")
ax_p.set_xlabel("frequency [Hz]")
fig.tight_layout()

# %%
# The magnitude error in units of its σ.  Against M alone it reaches about −13σ near the first
# mode, where the response is large and σ a few ten-thousandths of a dB: there the hold's sinc²,
# a bias of a few thousandths of a dB, is far larger than the noise.  Against the sampled
# experiment's transfer function the errors scatter within ±2σ.
fig, ax = plt.subplots(figsize=(7, 3))
for label, ref, marker in (("vs M(j2πf)", M_exact, "x"), ("vs M(j2πf)·sinc²(f/fs)", M_sampled, "o")):
    ax.semilogx(f, 20 * np.log10(np.abs(H / ref)) / est.magnitude_std_db[0], marker, ms=4, label=label)
ax.axhspan(-2, 2, color="0.9")
ax.set_ylim(-15, 5)
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel("magnitude error / σ")
ax.legend(fontsize=8)
fig.tight_layout()

# %%
# From the estimate to a calibration
# ----------------------------------
# ``to_sweep`` makes a ``FrequencySweep`` (per-line σ included) that ``calibrate`` weighs line
# by line.  Calibrated as it is, the fit's cost exceeds what the noise explains: the data contain
# the hold's sinc², which the physics does not.  Dividing the known sinc² out first (a property
# of the acquisition, not of the strip) leaves a cost within the noise's expectation.
start = truth.replace(d=1.3 * truth.d)                 # a 30 % wrong starting value of d
as_estimated = est.to_sweep(T_C)
hold_removed = replace(as_estimated, response=as_estimated.response / hold)
for label, data in (("as estimated", as_estimated), ("hold divided out", hold_removed)):
    result = calibrate(data, start, ["d"], starts=2, seed=0)
    print(f"--- {label}: d = {result.parameters.d:.5g} (truth {truth.d:.5g}); cost {result.cost:.1f}, "
          f"expected {result.expected_cost:.1f} ± {result.cost_std:.1f}")
