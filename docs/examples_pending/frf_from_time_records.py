"""OUTLINE — not run, not in the gallery (see README.md here): estimate an FRF from time records.

Needs the FRF estimators being built in parallel (``physmodel.estimation.frf``).  Intended steps:

1. ``physmodel.timesim.simulate`` the seed 002 strip at 25 °C with a multisine voltage
   (0.1-50 Hz, 64 periods) and laser noise on the displacement;
2. estimate H1 with per-line log-magnitude/phase σ (Welch) and a stepped-sine estimate;
3. overlay both on ``ActuatorModel(...).frequency_response`` and report the fraction of lines
   within ±2σ of the exact response (expected a little under 95 %, Student-t);
4. pass the estimate (a ``FrequencySweep`` with per-line σ) to ``physmodel.calibrate``.
"""

raise NotImplementedError("pending: FRF estimation from time records (issue 18 to-do)")
