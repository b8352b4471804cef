"""Estimation above the physics: standardised residuals, the weighted multi-start least-squares
engine with intervals and identifiability, calibration of physical parameters, and the
discrepancy workflow (locate, name, add, refit).  No plotting here (``scenarios.plots`` draws).

Modules: residuals, records, lsq, calibration, discrepancy.
"""
