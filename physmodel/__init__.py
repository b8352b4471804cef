"""physmodel — the Chen-Tan physics of IPMC actuators and sensors, with temperature laws.

Public API
----------
Parameters
    IPMCParameters, get_parameter_set, available_parameter_sets, register_parameter_set,
    state_at, describe
Temperature laws (physmodel.temperature)
    TemperatureLaws, Arrhenius, LogLinear, Linear, WaterPermittivity, IonicResistance, Constant,
    ISOTHERMAL
Models (frequency domain, vectorised over sets × temperatures × frequencies)
    ActuatorModel  — Z, H, G, M = H·G, I = 1/Z          (physmodel.actuator)
    SensorModel    — S = I/w, Z; kernels "boundary_charge" | "reciprocal"   (physmodel.sensor)
    TransimpedanceChain — seed 000 measurement circuit
    FrequencyResponse — result record
Reduced models
    reduced_actuator (physmodel.reduced) — seed 002 §2.2.4 Taylor model as control.TransferFunction
Sweeps and data files (physmodel.sweep)
    FrequencySweep, synthesize_sweep, MagnitudePhaseNoise, ComplexGaussianNoise,
    read_csv / write_csv, read_npz / write_npz, read_mat / write_mat
Time-domain virtual experiments (physmodel.data.timesim)
    realize, simulate, sine, step, free_release, TimeSeries
Calibration (physmodel.estimation.calibration)
    calibrate, fit_parameters, FreeParameter, CalibrationResult — weighted multi-start least squares
    with confidence intervals, correlations and an identifiability report; ``ipmc calibrate``
Discrepancy workflow (physmodel.effects, physmodel.estimation.discrepancy)
    EffectModel, LIBRARY — named candidate effects (electrode/contact resistance, leakage, second mode,
    fluid mass, temperature laws, water uptake, amplifier, delay, CPE, ...) composable with any model;
    diagnose, Diagnosis — locate, name, add and refit; ``ipmc diagnose``
Errors (physmodel.errors)
    IPMCError, ParameterError, TemperatureRangeError, DataFormatError

Units: SI inside (rad/s, K, m, V, A); Hz and °C at the edges, as the argument names say.
"""

from .errors import DataFormatError, IPMCError, ParameterError, TemperatureRangeError
from .params import IPMCParameters, describe, state_at
from .parameter_sets import available_parameter_sets, get_parameter_set, load_parameter_set, register_parameter_set, save_parameter_set
from .temperature import (ISOTHERMAL, Arrhenius, Constant, IonicResistance, Linear, LogLinear,
                          TemperatureLaws, WaterPermittivity)
from .model import FrequencyResponse
from .actuator import ActuatorModel
from .sensor import SensorModel, TransimpedanceChain
from .estimation.records import CalibrationResult, FreeParameter
from .estimation.calibration import calibrate
from .estimation.lsq import fit_parameters
from .effects import LIBRARY, EffectModel
from .estimation.discrepancy import Diagnosis, diagnose

__all__ = [
    "IPMCParameters", "describe", "state_at", "available_parameter_sets", "get_parameter_set",
    "register_parameter_set", "load_parameter_set", "save_parameter_set", "TemperatureLaws", "Arrhenius", "Constant", "IonicResistance", "Linear",
    "LogLinear", "WaterPermittivity", "ISOTHERMAL", "FrequencyResponse", "ActuatorModel", "SensorModel",
    "TransimpedanceChain", "calibrate", "fit_parameters", "FreeParameter", "CalibrationResult", "EffectModel", "LIBRARY", "diagnose", "Diagnosis", "IPMCError", "ParameterError", "TemperatureRangeError", "DataFormatError",
]
