"""physmodel — the Chen–Tan physics of IPMC actuators and sensors, with temperature laws, and the
estimation built on it (calibration, discrepancy workflow).

Layers (each imports only those above it in this list)
    sub-models     errors, params, temperature, transport, electrode, beam, numerics
    models         protocol (the one model interface), model, actuator, sensor, reduced, parameter_paths
    sets           parameter_sets (one module per source; the seeds' printed numbers)
    data           data.units, data.sweep (the one FrequencySweep record), data.files, data.timesim
    effects        effects (candidate physical and measurement-chain effects, composable with any model)
    model file     model_file (a model with its effects, the data's verdict and provenance: ModelFile)
    estimation     estimation.residuals, .records, .lsq, .calibration, .discrepancy

Public API
----------
Parameters
    IPMCParameters, get_parameter_set, available_parameter_sets, register_parameter_set,
    load_parameter_set, save_parameter_set, state_at, describe
Temperature laws (physmodel.temperature)
    TemperatureLaws, Arrhenius, LogLinear, Linear, WaterPermittivity, IonicResistance, Constant,
    ISOTHERMAL
Models (frequency domain, vectorised over sets × temperatures × frequencies)
    FrequencyModel — the model protocol: ``kind`` and ``response(frequency_hz, temperature_c)``
    ActuatorModel  — Z, H, G, M = H·G, I = 1/Z          (physmodel.actuator)
    SensorModel    — S = I/w, Z; kernels "boundary_charge" | "reciprocal"   (physmodel.sensor)
    TransimpedanceChain — seed 000 measurement circuit
    FrequencyResponse — result record
Data (physmodel.data)
    FrequencySweep, synthesize_sweep, MagnitudePhaseNoise, ComplexGaussianNoise, read_sweep,
    write_sweep; time-domain experiments in physmodel.data.timesim (simulate, sine, step,
    free_release, TimeSeries)
Calibration (physmodel.estimation)
    calibrate, fit_parameters, FreeParameter, CalibrationResult, ScalarObservations — weighted multi-start least squares
    with confidence intervals, correlations and an identifiability report; ``ipmc calibrate``
Discrepancy workflow (physmodel.effects, physmodel.estimation.discrepancy)
    EffectModel, LIBRARY — named candidate effects composable with any model;
    diagnose, Diagnosis — locate, name, add and refit; ``ipmc diagnose``
The model file (physmodel.model_file)
    ModelFile, load_model, FitVerdict, Provenance — what ``ipmc calibrate``/``ipmc diagnose`` write and
    every command that takes physics reads: parameters, laws, effects, the data's verdict, provenance
Errors (physmodel.errors) — the library's one error root
    IPMCError (a ValueError), ParameterError, TemperatureRangeError, DataFormatError

Units: SI inside (rad/s, K, m, V, A); Hz and °C at the edges, as the argument names say.
"""

__version__ = "0.1.0"

from .actuator import ActuatorModel
from .data import ComplexGaussianNoise, FrequencySweep, MagnitudePhaseNoise, read_sweep, synthesize_sweep, write_sweep
from .effects import LIBRARY, EffectModel
from .errors import DataFormatError, IPMCError, ParameterError, TemperatureRangeError
from .estimation.calibration import calibrate
from .estimation.discrepancy import Diagnosis, diagnose
from .estimation.lsq import fit_parameters
from .estimation.observations import ScalarObservations
from .estimation.records import CalibrationResult, FreeParameter
from .model import FrequencyResponse
from .model_file import FitVerdict, ModelFile, Provenance, load_model
from .parameter_sets import (
                             available_parameter_sets,
                             get_parameter_set,
                             load_parameter_set,
                             register_parameter_set,
                             save_parameter_set,
)
from .params import IPMCParameters, describe, state_at
from .protocol import FrequencyModel, physics_model
from .sensor import SensorModel, TransimpedanceChain
from .temperature import (
                             ISOTHERMAL,
                             Arrhenius,
                             Constant,
                             IonicResistance,
                             Linear,
                             LogLinear,
                             TemperatureLaws,
                             WaterPermittivity,
)

__all__ = [
    "__version__",
    "IPMCParameters", "describe", "state_at", "available_parameter_sets", "get_parameter_set",
    "register_parameter_set", "load_parameter_set", "save_parameter_set",
    "TemperatureLaws", "Arrhenius", "Constant", "IonicResistance", "Linear", "LogLinear", "WaterPermittivity",
    "ISOTHERMAL",
    "FrequencyModel", "physics_model", "FrequencyResponse", "ActuatorModel", "SensorModel", "TransimpedanceChain",
    "FrequencySweep", "synthesize_sweep", "MagnitudePhaseNoise", "ComplexGaussianNoise", "read_sweep",
    "write_sweep",
    "calibrate", "fit_parameters", "FreeParameter", "CalibrationResult", "ScalarObservations",
    "EffectModel", "LIBRARY", "diagnose", "Diagnosis",
    "ModelFile", "load_model", "FitVerdict", "Provenance",
    "IPMCError", "ParameterError", "TemperatureRangeError", "DataFormatError",
]
