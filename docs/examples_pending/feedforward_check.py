"""OUTLINE — not run, not in the gallery (see README.md here): compute and check a feedforward.

Needs the feedforward check on the plant being built in parallel.  Intended steps, continuing
``docs/examples/plot_05_measured_to_feedforward.py``:

1. the scheduled surrogate's 40 °C feedforward for a 0.5 mm, 1 Hz reference
   (``inversion.feedforward(surr.at(40.0), t, desired)``);
2. apply it to the calibrated physics and to the truth at 40 °C;
3. compare the tracking error bound with the steady-state prediction A·|P(jω)/G(jω) − 1| from the
   physics frequency response, and with a fixed 19 °C model's feedforward.
"""

raise NotImplementedError("pending: feedforward check on the plant (issue 18 to-do)")
