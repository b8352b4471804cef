"""Run a scenario (:mod:`scenarios.spec`) into an output folder: data, surrogate JSON, PNG figures,
``metrics.json`` and ``report.md`` with the tables and each check's pass/fail.

Every file is written atomically (temporary file, then rename); ``report.md`` is written last and
removed first, so a folder without it is visibly incomplete (an interrupted run, or one that
raised).  The steps themselves are in :mod:`scenarios.steps`; ``ipmc run`` is :mod:`scenarios.commands.run`.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .context import RunContext, md_table
from .spec import Scenario, ScenarioError
from .steps import STEPS, build_model


# ---------------------------------------------------------------------------- results
@dataclass(frozen=True)
class CheckResult:
    """One named expectation: ``value`` of ``metric`` against [``minimum``, ``maximum``]."""

    name: str
    metric: str
    value: float
    minimum: float | None
    maximum: float | None
    description: str
    passed: bool

    def bound_text(self) -> str:
        if self.minimum is not None and self.maximum is not None:
            return f"in [{self.minimum:g}, {self.maximum:g}]"
        return f">= {self.minimum:g}" if self.minimum is not None else f"<= {self.maximum:g}"


@dataclass(frozen=True)
class RunResult:
    """What :func:`run_scenario` produced: metrics (plain floats), checks, files, wall time [s]."""

    scenario: str
    out: Path
    metrics: dict
    checks: list
    files: list
    elapsed_s: float

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def exit_code(self) -> int:
        return 0 if self.passed else 3


# ---------------------------------------------------------------------------- checks and report
def _metric_value(expr: str, metrics: dict, where: str) -> float:
    terms = [t.strip() for t in expr.split("/")]
    if len(terms) > 2:
        raise ScenarioError(f"{where}: metric {expr!r}: only 'a' or 'a / b' is supported")
    for t in terms:
        if t not in metrics:
            raise ScenarioError(f"{where}: metric {t!r} was not produced; available: {sorted(metrics)}")
    if len(terms) == 1:
        return metrics[terms[0]]
    with np.errstate(divide="ignore", invalid="ignore"):   # a zero denominator is a failed check (inf/NaN)
        return float(np.float64(metrics[terms[0]]) / np.float64(metrics[terms[1]]))


def evaluate_checks(spec: Scenario, metrics: dict) -> list[CheckResult]:
    """Each ``[checks.NAME]`` against the measured metrics (NaN never passes), plus an implicit
    ``surrogate_converged`` check when the scenario fits a surrogate and does not check it."""
    out = []
    named = {c["metric"].strip() for c in spec.section("checks").values()}
    if "surrogate.converged" in metrics and "surrogate.converged" not in named:
        v = metrics["surrogate.converged"]
        out.append(CheckResult("surrogate_converged", "surrogate.converged", v, 1.0, None,
                               "(implicit) the surrogate fit converged", v >= 1))
    for name, c in spec.section("checks").items():
        v = float(_metric_value(c["metric"], metrics, f"{spec.path}: [checks.{name}]"))
        lo, hi = c.get("min"), c.get("max")
        ok = bool(np.isfinite(v) and (lo is None or v >= lo) and (hi is None or v <= hi))
        out.append(CheckResult(name, c["metric"], v, lo, hi, c.get("description", ""), ok))
    return out


def run_scenario(spec: Scenario, out, *, quiet: bool = False, force: bool = False) -> RunResult:
    """Run every step of ``spec`` into folder ``out`` and write its report (last).

    The folder is written all or nothing (:func:`physmodel.data.results.output_folder`: a temporary
    sibling moved into place when complete, with a completion marker): a second run into it is
    refused while this one writes, and a folder holding another run's results is refused unless
    ``force``.  An interrupt (even one a solver swallowed) ends the run before the next step and
    leaves ``out`` as it was."""
    from dataclasses import replace

    from physmodel.data.files import output_folder

    with output_folder(out, f"ipmc run {spec.name}", force=force) as folder:
        res = _run_scenario(spec, folder, quiet)
    return replace(res, out=Path(out))


def _run_scenario(spec: Scenario, out: Path, quiet: bool) -> RunResult:
    from physmodel import interrupts
    from physmodel.data.files import atomic_write

    t0 = time.perf_counter()
    (out / "report.md").unlink(missing_ok=True)         # a stale report must not vouch for new files
    say = (lambda *a: None) if quiet else (lambda *a: print(*a, file=sys.stderr))
    ctx = RunContext(spec, out, say)
    build_model(ctx)
    steps = spec.steps
    bar = None
    if not quiet:
        from tqdm import tqdm

        bar = tqdm(total=len(steps), desc=spec.name, unit="step", file=sys.stderr)
    try:
        for s in steps:
            if bar is not None:
                bar.set_postfix_str(s)
            STEPS[s](ctx)
            interrupts.check()
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    checks = evaluate_checks(spec, ctx.metrics)
    elapsed = time.perf_counter() - t0
    finite = lambda v: v if isinstance(v, float) and np.isfinite(v) else (None if isinstance(v, float) else v)  # noqa: E731
    payload = {"scenario": spec.name, "quick": spec.quick, "metrics": {k: finite(v) for k, v in ctx.metrics.items()},
               "checks": [{k: finite(v) for k, v in c.__dict__.items()} for c in checks]}
    ctx.file(atomic_write(out / "metrics.json", lambda fh: fh.write(json.dumps(payload, indent=2, allow_nan=False))))
    sc = spec.section("scenario")
    m = spec.section("model")
    lines = [f"# {sc.get('title', spec.name)}", "",
             sc.get("description", ""), "",
             f"Scenario `{spec.name}` ({spec.path}{', quick mode' if spec.quick else ''}); source: "
             f"{sc.get('source', '-')}.", "",
             f"Model: {m['kind']} `{ctx.base_params.name}` ({ctx.base_params.source})"
             + (f", overrides {m['params']}" if m.get("params") else "") + ".", "", *ctx.report,
             "## Checks", "",
             md_table(["check", "result", "measured", "expected", "what"],
                       [(c.name, "PASS" if c.passed else "FAIL", f"{c.value:.4g}", f"`{c.metric}` {c.bound_text()}",
                         c.description) for c in checks]), "",
             f"{sum(c.passed for c in checks)}/{len(checks)} checks passed; ran in {elapsed:.1f} s.", "",
             "## Files", "", *[f"- `{f}`" for f in ctx.files], "- `report.md` (this file, written last)", ""]
    interrupts.check()
    atomic_write(out / "report.md", lambda fh: fh.write("\n".join(lines)))
    return RunResult(spec.name, out, dict(ctx.metrics), checks, list(ctx.files), elapsed)


def summary_line(res: RunResult) -> str:
    n_ok = sum(c.passed for c in res.checks)
    failed = [c.name for c in res.checks if not c.passed]
    return (f"{res.scenario}: {n_ok}/{len(res.checks)} checks passed in {res.elapsed_s:.1f} s; report "
            f"{res.out / 'report.md'}" + (f"; FAILED: {', '.join(failed)}" if failed else ""))


__all__ = ["CheckResult", "RunResult", "run_scenario", "evaluate_checks", "summary_line", "STEPS"]
