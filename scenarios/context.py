"""What a scenario run carries from step to step (:class:`RunContext`) and the markdown table its
report is written with (:func:`md_table`).

Below both :mod:`scenarios.runner` (which makes the context and writes the report) and
:mod:`scenarios.steps` (whose steps fill it): neither needs the other's insides.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .spec import Scenario


@dataclass
class RunContext:
    """The run in progress: the scenario, its output folder, what the steps measured (metrics),
    wrote (files, relative to ``out``) and said (report sections), and what later steps reuse (the
    model and its base parameters, the noisy and the exact sweep, the surrogate fit)."""

    spec: Scenario
    out: Path
    say: Callable
    metrics: dict = field(default_factory=dict)
    files: list = field(default_factory=list)
    report: list = field(default_factory=list)
    model: object = None
    base_params: object = None
    data: object = None      # noisy sweep (what a lab would measure)
    exact: object = None     # noise-free physics on the same grid
    fit: object = None       # surrogate FitResult

    def file(self, path: Path) -> Path:
        """Record ``path`` (inside ``out``) as a file of the run; returns it."""
        self.files.append(Path(path).relative_to(self.out).as_posix())
        return path

    def section(self, title: str, *lines: str):
        """Add a report section ``## title`` with ``lines``."""
        self.report += [f"## {title}", "", *lines, ""]

    def metric(self, name: str, value) -> float:
        """Record metric ``name`` as a float (what ``[checks]`` compare); returns it."""
        v = float(value)
        self.metrics[name] = v
        return v


def md_table(header, rows) -> str:
    """A markdown table: ``header`` (column titles) over ``rows`` (each cell printed with ``str``)."""
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


__all__ = ["RunContext", "md_table"]
