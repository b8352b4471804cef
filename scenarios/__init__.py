"""scenarios — the papers' experiments as runnable virtual experiments, and the ``ipmc`` CLI.

Public API
----------
spec.load_scenario(path, quick=False) -> Scenario      validated scenario file (schema in spec.py)
spec.parse_scenario(dict, where, quick=False), spec.bundled_scenarios(), spec.ScenarioError
runner.run_scenario(scenario, out, quiet=False) -> RunResult   data, figures, metrics.json, report.md
runner.RunResult (.metrics, .checks, .files, .passed, .exit_code), runner.CheckResult
study.load_study(path) / parse_study(dict) -> spec dict;  study.run_study(spec, scheduler=None,
    workers=None, backend=None, progress=None) -> StudyTable (.columns, .save, .equals)
demo.run_demo(out, quiet=False, quick=False, update_figures=False) -> RunResult   (``ipmc demo``)
cli.main            the ``ipmc`` console script (sets, sweep, simulate, demo, run, study + plugins)
plots               Bode plots, pole/zero loci, tracking traces (matplotlib, Agg, atomic writes)

Bundled scenarios: ``scenarios/*.toml``; bundled studies: ``scenarios/studies/*.toml``.
"""
