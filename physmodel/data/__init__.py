"""Data: units, the one frequency-response record, its files, and time-domain experiments.

Modules
-------
units     UNITS, unit_scale, QUANTITY_UNITS — file units as multiples of SI; each model
          quantity's input/output names and display units
sweep     FrequencySweep (tidy frequency-response record with per-line σ), MagnitudePhaseNoise,
          ComplexGaussianNoise, synthesize_sweep, sweep_layout, merge_sweeps
interop   as_sweep — a FrequencySweep from a sweep, python-control FRD objects or arrays
files     read_sweep / write_sweep (.csv, .npz, .mat by extension), the per-format readers and
          writers, a user's own sweep files through columns=/units= (read_mapped_sweep)
columns   a user's own CSV/NPZ/MAT as named columns (read_table, pick, ColumnMapError)
fileio    atomic_write (the library's one atomic writer), read_text, by_extension, output folders
timesim   realize, simulate, sine, step, free_release, TimeSeries — time-domain virtual experiments
"""

from .files import (
                    atomic_write,
                    by_extension,
                    read_csv,
                    read_mat,
                    read_npz,
                    read_sweep,
                    write_csv,
                    write_mat,
                    write_npz,
                    write_sweep,
)
from .interop import as_sweep
from .sweep import (
                    ComplexGaussianNoise,
                    FrequencySweep,
                    MagnitudePhaseNoise,
                    SweepLayout,
                    merge_sweeps,
                    sweep_layout,
                    synthesize_sweep,
)
from .units import QUANTITY_UNITS, UNITS, unit_scale

__all__ = ["as_sweep", "FrequencySweep", "MagnitudePhaseNoise", "ComplexGaussianNoise", "synthesize_sweep", "SweepLayout",
           "sweep_layout", "merge_sweeps", "read_sweep", "write_sweep", "read_csv", "write_csv", "read_npz",
           "write_npz", "read_mat", "write_mat", "atomic_write", "by_extension", "UNITS", "unit_scale",
           "QUANTITY_UNITS"]
