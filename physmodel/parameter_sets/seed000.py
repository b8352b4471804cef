"""Seed 000 sensor set.

seed000_sensor
    The seed 000 sensor (Ganley et al., IEEE/ASME Trans. Mechatronics 16(1), 2011; 18 × 6.5 mm,
    210 µm Nafion-117) calibrated on part of the paper's printed evidence (:data:`CALIBRATION`):

    * a0 and d fitted to the printed 35 °C model (Sec. IV-A), evaluated as data over 10–100 Hz with
      0.5 dB / 5° per line, by ``physmodel.estimation.calibration.calibrate`` (kernel
      "boundary_charge", T_ref = 35 °C): a0 = −0.2174 C/J (95 %: −0.2225…−0.2124), d = 1.971e-13 m²/s
      (1.70…2.29e-13).  κe, r1', r2' ran to their upper bounds (more electrode lag always helps the
      phase) and are held at the development values.  The misfit stays 4.2 dB / 62° RMS: the
      printed phase falls by ~250° over the band (three right-half-plane zeros), which this
      physics cannot produce.
    * C⁻ log-linear −2.5 %/K and E log-linear −1.25 %/K: the smallest departure from the physics.md
      defaults on a grid that makes the cut-off and the 100 Hz gain fall with T (Sec. II-B, Fig. 5;
      default laws make K = F²dC⁻/(κe R T) rise with T and the cut-off rise).  The third printed
      direction, the phase lag rising with T, was not used, but it is no prediction: on every slope
      pair of the grid it holds exactly when the cut-off falls (both follow the C⁻ slope through
      K(T)), so ``ipmc validate`` counts its row as calibrated.  The effects are small:
      cut-off 65.0 → 63.1 Hz, 100 Hz gain 31.0 → 30.2 dB µA/mm, band-mean lag 100.3 → 102.4° over
      23–65 °C; the paper's Fig. 5 shows a larger change but prints no number.

    What the fitted values mean, and whether they are plausible:

    * a0 (sensing coupling, charge per stress-energy, C/J): its size is set by the printed gain and
      is of the order of the development value 0.3 C/J; its sign is the current's polarity
      convention (which electrode the op-amp of Fig. 4 grounds, not printed) — plausible, not
      independently known.
    * d (cation diffusivity): 2e-13 m²/s is 150–200× below the 3.07e-11 m²/s fitted in seed 002
      (Table 3) and the 4e-11 m²/s of the development set — not plausible for hydrated Nafion-117.
      Its role is to move the Debye rate K = F²dC⁻/(κe R T) from ~1.6e5 1/s to ~600 1/s (K/2π ≈
      96 Hz, inside the band) so that the charge relaxation bends the response where the printed
      model does.  Consequences: ionic conductivity F²dC⁻/(RT) ≈ 8e-4 S/m (0.12 S/m with seed 002's
      d) and a terminal impedance of 1.25–1.51 kΩ over 10–100 Hz, against ≈ 23 Ω for the same
      geometry with development values; the paper prints no impedance, but tens of ohms is what a
      strip this size with platinum electrodes is expected to show.
    * κe, r1', r2', C⁻, E at T_ref: not determined by the data (held at development values).

    So the set is a curve fit of one printed model in this geometry, not a characterisation of the
    sample: use it for seed 000's virtual experiments, not to predict the sample's impedance or
    ion transport.  Derivation: ``python3 -m physmodel.parameter_sets.derivation``.
"""

from __future__ import annotations

from ..params import IPMCParameters
from ..temperature import LogLinear
from .dev import dev_set

#: Calibrated seed values (derived by physmodel/parameter_sets/derivation.py; see the module doc).
SEED000_SENSOR_CAL = {"a0": -0.217398, "d": 1.97062e-13, "T_ref": 308.15,
                      "C_minus_slope": -0.025, "E_slope": -0.0125}


def _seed000_sensor() -> IPMCParameters:
    c = SEED000_SENSOR_CAL
    p = dev_set("seed000_sensor", 18e-3, 6.5e-3, 105e-6,
             "seed 000 sensor geometry; a0, d calibrated to the printed 35 C model over 10-100 Hz "
             "(kappa_e, r1', r2' undetermined, held at development values); C- and E log-linear laws "
             "(-2.5 %/K, -1.25 %/K) chosen on the published cut-off and high-frequency-gain directions "
             "(physmodel/parameter_sets/derivation.py)")
    return p.replace(a0=c["a0"], d=c["d"], T_ref=c["T_ref"],
                     laws=p.laws.with_(C_minus=LogLinear(slope=c["C_minus_slope"]), E=LogLinear(slope=c["E_slope"])))


SETS = {"seed000_sensor": _seed000_sensor}

#: The published claims (``published.toml`` ids) each calibrated set was fitted or solved to, and what
#: was fitted to each.  Every other claim checked with the set is not a calibration target (whether it is a
#: prediction is for ``ipmc validate`` to say: a claim the calibration implies is not).
CALIBRATION = {"seed000_sensor": {
    "sensor_seed000.model_35c_num": "a0, d fitted to the printed 35 C model (its response over 10-100 Hz as data)",
    "sensor_seed000.model_35c_den": "a0, d fitted to the printed 35 C model (its response over 10-100 Hz as data)",
    "sensor_seed000.model_order": "the only response the set was fitted to is a printed 4/4 model",
    "sensor_seed000.trends_with_rising_temperature[0]": "C- and E law slopes chosen on a grid to make it hold",
    "sensor_seed000.trends_with_rising_temperature[1]": "C- and E law slopes chosen on a grid to make it hold",
}}
