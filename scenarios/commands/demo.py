"""``ipmc demo``: the flagship chain (physics → scheduled surrogate → inversion → checks)."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("demo", help="run the flagship chain (physics → scheduled surrogate → inversion → checks)",
                       description="The flagship chain on embedded defaults (scenarios/demo.toml): physics sweeps of "
                                   "the seed 001 actuator at eight temperatures, a joint temperature-scheduled "
                                   "surrogate fitted without the held-out 35/45 °C, the held-out check, stable-"
                                   "inversion feedforward at 45 °C applied to the physics plant, and validation "
                                   "checks; writes data, surrogate.json, PNG figures and report.md (last).  "
                                   "Exit 3 when a check fails.")
    p.add_argument("--out", default="ipmc-demo", help="report folder (default ./ipmc-demo)")
    p.add_argument("--quick", action="store_true", help="shorter time records (what the test suite runs)")
    p.add_argument("--update-figures", action="store_true",
                   help="also refresh the README figures in scenarios/figures/ (developers)")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds another run's results")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)

def run(args) -> int:
    from ..demo import run_demo

    return run_demo(Path(args.out), quiet=args.quiet, quick=args.quick,
                    update_figures=args.update_figures, force=args.force).exit_code
