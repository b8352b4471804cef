"""``ipmc`` — the command line of the IPMC library.

    ipmc sets                       list the named parameter sets (``ipmc sets NAME`` shows one)
    ipmc sweep ...                  synthetic frequency sweep → CSV/NPZ/MAT (+ Bode plot)
    ipmc simulate ...               time-domain virtual experiment → CSV/NPZ (+ plot)
    ipmc demo                       the flagship chain on embedded defaults → a report folder
    ipmc run SCENARIO               a scenario file or bundled scenario → data, figures, report.md
    ipmc study STUDY                Monte Carlo / grid parameter study (local processes or Dask)
    ipmc excite KIND                excitation signal (multisine, stepped sine, chirp) for a DAQ
    ipmc frf RECORD...              frequency response with per-line σ from time records
    ipmc fit SWEEP                  temperature-scheduled rational surrogate
    ipmc invert SIGNAL              stable (noncausal) inversion of a surrogate
    ipmc feedforward ...            actuator voltage for a reference, checked on the physics
    ipmc calibrate SWEEP            calibrate physical parameters to a measured sweep
    ipmc diagnose                   discrepancy workflow: locate, name, add, refit
    ipmc validate                   every printed claim of the seed papers vs our number

One module per subcommand in :mod:`scenarios.commands` (``add_parser(subparsers)`` and
``run(args) -> exit code``).  Exit codes (:mod:`scenarios.commands._common`): 0 success, 2 bad
input (the message names it), 3 a check failed or a fit did not converge, 130 interrupted.
Every command has ``--help`` and ``--quiet``.
"""

from __future__ import annotations

import argparse
import sys

from .commands import (
    calibrate,
    compare,
    demo,
    diagnose,
    excite,
    feedforward,
    fit,
    frf,
    invert,
    run,
    sets,
    simulate,
    study,
    sweep,
    validate,
)
from .commands._common import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED

#: The subcommands, in the order ``ipmc --help`` lists them.
COMMANDS = (sets, sweep, simulate, excite, frf, demo, run, study, fit, invert, feedforward, calibrate, diagnose,
            compare, validate)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ipmc")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        from physmodel import __version__

        return __version__


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="ipmc", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"ipmc {_version()}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    for mod in COMMANDS:
        before = set(sub.choices)
        mod.add_parser(sub)
        for name in set(sub.choices) - before:
            sub.choices[name].set_defaults(func=mod.run)
    return ap


def main(argv=None) -> int:
    """Run one ``ipmc`` command; returns its exit code.

    SIGINT and SIGTERM are recorded and raise ``KeyboardInterrupt`` (:mod:`physmodel.interrupts`)
    for the whole command, so an interrupt that a solver swallows (CasADi/IPOPT catches it and
    reports a failed solve) still ends the command with 130: the runner checks between steps and
    :func:`~physmodel.data.files.atomic_write` refuses to commit a file once one was recorded.
    """
    from physmodel import interrupts

    with interrupts.handling():
        code = _main(argv)
        if interrupts.requested() is not None and code != EXIT_INTERRUPTED:
            print("ipmc: interrupted", file=sys.stderr)
            return EXIT_INTERRUPTED
        return code


def _main(argv) -> int:
    from physmodel import interrupts
    from physmodel.errors import IPMCError, NotConvergedError

    ap = build_parser()
    args = ap.parse_args(argv)
    if not getattr(args, "command", None):
        ap.print_help()
        return EXIT_BAD_INPUT
    try:
        return int(args.func(args))
    except NotConvergedError as exc:
        print(f"ipmc {args.command}: not converged: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except IPMCError as exc:
        print(f"ipmc {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        print(f"ipmc {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"ipmc {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except SystemError:
        # CasADi 3.7 leaves the KeyboardInterrupt it caught inside an IPOPT solve pending, so the solve
        # returns into "SystemError: ... returned a result with an exception set" (3.8 returns a failed
        # solve); with an interrupt recorded, that error is the interrupt
        if interrupts.requested() is None:
            raise
        print(f"ipmc {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
