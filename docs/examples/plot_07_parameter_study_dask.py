"""
Run a parameter study on a Dask cluster
=======================================

A Monte Carlo study draws uncertain parameters, evaluates the physics for every sample ×
temperature × frequency and returns a tidy table.  Sample *i* draws from
``SeedSequence(seed).spawn(n)[i]``, and each task evaluates a chunk of samples in one
vectorised model call, so a serial run, local processes and a Dask cluster give bit-identical
tables.

The study is plain data (the same table as a ``[study]`` TOML file for ``ipmc study``).  The
cluster here is a small in-process ``distributed.LocalCluster`` so that the example runs
anywhere; on real machines start ``dask scheduler`` and ``dask worker tcp://HOST:8786`` and pass
``scheduler="tcp://HOST:8786"`` (or ``ipmc study STUDY.toml --scheduler tcp://HOST:8786``).
"""

# %%
# The study
# ---------
import matplotlib.pyplot as plt
import numpy as np
from distributed import LocalCluster

from scenarios.study import parse_study, run_study

spec = parse_study({"study": {
    "name": "actuator_mc_small",
    "kind": "actuator",
    "set": "seed001_actuator",
    "method": "monte_carlo",
    "samples": 48,
    "seed": 7,
    "temperatures_c": [20.0, 50.0],
    "fmin_hz": 0.1, "fmax_hz": 10.0, "points": 30,
    "chunk_size": 12,
    "parameters": {
        "d": {"distribution": "lognormal", "median": 4e-11, "sigma": 0.3},      # [m²/s]
        "E": {"distribution": "normal", "mean": 421e6, "std": 30e6},            # [Pa]
        "r1_sheet": {"distribution": "uniform", "low": 5.0, "high": 20.0},     # [Ω]
    },
}})

# %%
# Serial reference and the same study on a Dask cluster
# -----------------------------------------------------
serial = run_study(spec, backend="serial")
with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
    on_dask = run_study(spec, scheduler=cluster.scheduler_address)
print(f"{on_dask.n_rows} rows on {on_dask.backend} in {on_dask.elapsed_s:.2f} s; "
      f"serial {serial.elapsed_s:.2f} s; bit-identical: {on_dask.equals(serial)}")

# %%
# The spread of the response
# --------------------------
# Columns: ``sample``, one per varied parameter (SI), ``temperature_c``, ``frequency_hz``,
# ``magnitude_db`` (mm/V), ``phase_deg`` (wrapped), ``real``, ``imag``.
c = on_dask.columns
fig, ax = plt.subplots(figsize=(6.5, 4))
for T, color in ((20.0, "C0"), (50.0, "C3")):
    rows = c["temperature_c"] == T
    f = np.unique(c["frequency_hz"][rows])
    mag = c["magnitude_db"][rows].reshape(-1, f.size)          # (samples, frequencies)
    lo, med, hi = np.percentile(mag, [5, 50, 95], axis=0)
    ax.fill_between(f, lo, hi, color=color, alpha=0.3, label=f"{T:g} °C, 5-95 %")
    ax.semilogx(f, med, color=color)
ax.set_xlabel("frequency [Hz]")
ax.set_ylabel("|M| [dB mm/V]")
ax.legend()
fig.tight_layout()
