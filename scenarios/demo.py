"""The flagship chain behind ``ipmc demo``: the bundled scenario ``scenarios/demo.toml``.

physics sweeps at eight temperatures (seed 001 actuator) → joint temperature-scheduled zpk
surrogate fitted without the held-out temperatures → held-out check → stable-inversion
feedforward at a held-out temperature, applied to the physics plant → validation checks (each
against an independent reference: the noise-free physics, the steady-state error predicted from
the physics frequency response, seed 001's printed trends) → ``report.md`` and PNG figures.

It is an ordinary scenario (``ipmc run demo`` runs the same thing); this module only finds it,
runs it and, with ``update_figures``, refreshes the README figures in ``scenarios/figures/``.
"""

from __future__ import annotations

from pathlib import Path

from .runner import RunResult, run_scenario, summary_line
from .spec import load_scenario

DEMO_SCENARIO = Path(__file__).with_name("demo.toml")
#: Demo outputs copied into scenarios/figures/ for the README: {report file: figure file}.
README_FIGURES = {"surrogate_bode.png": "demo_surrogate_bode.png",
                  "inversion_2_hz_sine_at_45_c.png": "demo_tracking_45c.png"}


def run_demo(out: Path, quiet: bool = False, quick: bool = False, update_figures: bool = False,
             force: bool = False) -> RunResult:
    """Run the flagship scenario into ``out`` (``force``: even when it holds another run's results);
    returns the :class:`~scenarios.runner.RunResult`."""
    res = run_scenario(load_scenario(DEMO_SCENARIO, quick=quick), Path(out), quiet=quiet, force=force)
    if update_figures:
        figs = Path(__file__).with_name("figures")
        for src, dst in README_FIGURES.items():
            from physmodel.data.files import atomic_write

            data = (res.out / src).read_bytes()
            atomic_write(figs / dst, lambda fh, data=data: fh.write(data), "wb")
    if not quiet:
        print(summary_line(res))
    return res


__all__ = ["run_demo", "DEMO_SCENARIO", "README_FIGURES"]
