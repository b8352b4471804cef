"""``ipmc run``: a scenario file, or a bundled scenario by name, into a report folder."""

from __future__ import annotations

import re
from pathlib import Path

from ..runner import run_scenario, summary_line
from ..spec import ScenarioError, bundled_scenarios, load_scenario, resolve_bundled


def add_parser(subparsers):
    p = subparsers.add_parser(
        "run", help="run a scenario file (scenarios/*.toml) into a report folder",
        description="Run a scenario TOML (model, parameter set, temperatures, grid or stimulus, noise, steps, "
                    "checks; schema in the README and scenarios/spec.py) and write data, surrogate JSON, PNG "
                    "figures, metrics.json and report.md (last) to --out.  Exit 3 when a check fails.")
    p.add_argument("scenario", nargs="?", help="scenario file, or the name of a bundled one (e.g. seed001_actuator)")
    p.add_argument("--list", action="store_true", help="list the bundled scenarios and exit")
    p.add_argument("--out", help="output folder (default ./ipmc-run-<name>)")
    p.add_argument("--quick", action="store_true", help="apply the scenario's [quick] table (smaller grids)")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds another run's results")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def resolve_scenario_path(text: str) -> Path:
    """A scenario file, or a bundled scenario by name."""
    return resolve_bundled(text, "scenario")


def default_folder(name: str) -> str:
    """``ipmc-run-<name>`` with every character outside [A-Za-z0-9._-] replaced, so a scenario name
    such as ``/../../tmp/x`` cannot place the default folder outside the working directory."""
    slug = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "scenario"
    return f"ipmc-run-{slug}"


def run(args) -> int:
    if args.list:
        for p in bundled_scenarios():
            sc = load_scenario(p)
            print(f"{p.stem:20s} {sc.section('scenario').get('title', '')}")
        return 0
    if not args.scenario:
        raise ScenarioError("name a scenario file or a bundled scenario (ipmc run --list shows them)")
    spec = load_scenario(resolve_scenario_path(args.scenario), quick=args.quick)
    res = run_scenario(spec, Path(args.out or default_folder(spec.name)), quiet=args.quiet, force=args.force)
    if not args.quiet:
        print(summary_line(res))
    return res.exit_code
