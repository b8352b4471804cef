"""scenarios — the papers' experiments as runnable virtual experiments, and the ``ipmc`` CLI.

Public API
----------
cli.main            the ``ipmc`` console script
demo.run_demo       the flagship scenario (``ipmc demo``)
plots               Bode plots and time traces (matplotlib, Agg)
"""
