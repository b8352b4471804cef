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
    ipmc compare MODEL DATA         a model against measured data: overlay and fit % per temperature
    ipmc validate                   every printed claim of the seed papers vs our number

One module per subcommand in :mod:`scenarios.commands` (``add_parser(subparsers)`` and
``run(args) -> exit code``).  Exit codes (:mod:`scenarios.commands._common`): 0 success, 2 bad
input (the message names it), 3 a check failed or a fit did not converge, 130 interrupted.
Every command has ``--help`` and ``--quiet``.
"""

from __future__ import annotations

# Only the standard library at module level: ``ipmc --help`` and ``--version`` must not pay for
# numpy/scipy/CasADi, and the signal handlers are installed before anything heavy is imported.
import argparse
import importlib
import sys

#: Exit codes (the same as :mod:`scenarios.commands._common`, repeated here so that this module
#: imports nothing heavy; tests/reliability checks they agree).
EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED = 2, 3, 130

#: The subcommands, in the order ``ipmc --help`` lists them, with their one-line help (each module's
#: ``add_parser`` gives the same line; a test checks they agree).  A command's module — and with it
#: its dependencies — is imported only when that command runs (or shows its own --help).
COMMANDS = (
    ("sets", "list named parameter sets or show one"),
    ("sweep", "synthetic frequency sweep at several temperatures"),
    ("simulate", "time-domain virtual experiment"),
    ("excite", "design an excitation (multisine, stepped sine, chirp) -> signal file"),
    ("frf", "estimate frequency responses with per-line σ from time records -> sweep"),
    ("demo", "run the flagship chain (physics → scheduled surrogate → inversion → checks)"),
    ("run", "run a scenario file (scenarios/*.toml) into a report folder"),
    ("study", "Monte Carlo / grid parameter study on local processes or a Dask cluster"),
    ("fit", "fit a temperature-scheduled rational transfer function to a sweep CSV"),
    ("invert", "stable (noncausal / finite-preview) inversion of a sampled signal in a .csv, .npz or .mat file"),
    ("feedforward", "feedforward voltage of a surrogate, checked on the physics"),
    ("calibrate", "calibrate physical parameters to a measured sweep (estimates, intervals, identifiability)"),
    ("diagnose", "locate a model/data discrepancy, name the missing effect, refit, show the gap shrink"),
    ("compare", "a model against measured data per temperature (fit %%, chi2, overlay)"),
    ("validate", "check every published claim of the seed papers against the project's numbers"),
)
NAMES = tuple(n for n, _ in COMMANDS)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ipmc")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        from physmodel import __version__

        return __version__


class _Version(argparse.Action):
    """``--version``, looked up only when asked for."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        parser.exit(message=f"ipmc {_version()}\n")


def command_module(name: str):
    """The module of subcommand ``name`` (imported now)."""
    return importlib.import_module(f"scenarios.commands.{name}")


def build_parser(commands=None) -> argparse.ArgumentParser:
    """The ``ipmc`` parser with the full parsers of ``commands`` (names; default all, which imports
    every command module) and a help-only entry for the others."""
    wanted = NAMES if commands is None else tuple(commands)
    ap = argparse.ArgumentParser(prog="ipmc", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action=_Version, help="show the version and exit")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    for name, text in COMMANDS:
        if name in wanted:
            mod = command_module(name)
            before = set(sub.choices)
            mod.add_parser(sub)
            for new in set(sub.choices) - before:
                sub.choices[new].set_defaults(func=mod.run)
        else:
            sub.add_parser(name, help=text, add_help=False)
    return ap


def _command_in(argv) -> str | None:
    """The subcommand ``argv`` names (its first word that is not an option), if any."""
    for a in argv:
        if a == "--":
            return None
        if not a.startswith("-"):
            return a if a in NAMES else None
    return None


def _early_handlers() -> tuple[list[int], dict]:
    """Before :mod:`physmodel.interrupts` is imported (it pulls numpy): SIGINT/SIGTERM raise
    ``KeyboardInterrupt``, recorded so that the full handler can take the record over."""
    import signal
    import threading

    seen: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        return seen, {}

    def early(signum, frame):
        seen.append(signum)
        raise KeyboardInterrupt

    return seen, {s: signal.signal(s, early) for s in (signal.SIGINT, signal.SIGTERM)}


def _noted(signum, frame) -> None:
    """While a finished or interrupted command cleans up: a further signal changes nothing."""


def _say_interrupted(what: str, signum) -> None:
    import signal

    name = signal.Signals(signum).name if signum else "SIGINT"
    try:
        print(f"{what}: interrupted by {name}; nothing half-written was left (results are moved into place only "
              "when complete)", file=sys.stderr)
    except (KeyboardInterrupt, OSError):  # pragma: no cover - a second signal or a closed stderr while reporting
        pass


def main(argv=None) -> int:
    """Run one ``ipmc`` command; returns its exit code.

    SIGINT and SIGTERM are recorded and raise ``KeyboardInterrupt`` (:mod:`physmodel.interrupts`)
    from the first line — import time included — so an interrupt at any moment ends the command with
    130 and one line on stderr, never a traceback; an interrupt that a solver swallows
    (CasADi/IPOPT catches it and reports a failed solve) still ends the command with 130: the
    runner checks between steps, and :func:`~physmodel.data.files.atomic_write` and
    :func:`~physmodel.data.results.commit` refuse to commit once one was recorded.  Result folders
    left open by the command are removed (:func:`physmodel.data.results.abort`).
    """
    import signal

    argv = sys.argv[1:] if argv is None else list(argv)
    seen, previous = _early_handlers()
    what = f"ipmc {_command_in(argv)}" if _command_in(argv) else "ipmc"
    try:
        if _command_in(argv) is None:         # --help, --version, a usage error: nothing heavy to import
            return _main(argv)
        try:
            from physmodel import interrupts
        except KeyboardInterrupt:
            _say_interrupted(f"{what} (while starting)", seen[-1] if seen else None)
            return EXIT_INTERRUPTED
        with interrupts.handling():
            if seen:
                interrupts.request(seen[-1])
            try:
                interrupts.check()
                code = _main(argv)
            except KeyboardInterrupt:
                code = EXIT_INTERRUPTED
            if interrupts.requested() is not None or code == EXIT_INTERRUPTED:
                _say_interrupted(what, interrupts.requested())
                return EXIT_INTERRUPTED
            return code
    except KeyboardInterrupt:                 # a signal in the instant the handlers change hands
        _say_interrupted(what, seen[-1] if seen else None)
        return EXIT_INTERRUPTED
    finally:
        for s in previous:                    # clean-up is not interrupted: later signals are only noted
            signal.signal(s, _noted)
        results = sys.modules.get("physmodel.data.results")
        if results is not None:
            results.abort()                   # result folders the command left open: removed
        for s, h in previous.items():
            signal.signal(s, h)


def _main(argv) -> int:
    command = _command_in(argv)
    ap = build_parser([command] if command else [])
    args = ap.parse_args(argv)
    if not getattr(args, "command", None) or not hasattr(args, "func"):
        ap.print_help()
        return EXIT_BAD_INPUT
    import warnings

    from physmodel import interrupts
    from physmodel.errors import IPMCError, NotConvergedError

    def one_line(message, category, filename, lineno, line=None):
        """A warning as one clean line (not the library source line Python shows by default)."""
        return f"ipmc {args.command}: warning: {message}\n"

    shown = warnings.formatwarning
    warnings.formatwarning = one_line
    try:
        return int(args.func(args))
    except NotConvergedError as exc:
        print(f"ipmc {args.command}: not converged: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except IPMCError as exc:
        print(f"ipmc {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MemoryError:
        print(f"ipmc {args.command}: error: not enough memory for this input; reduce the sizes it asks for "
              "(points, samples, draws, record length)", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        print(f"ipmc {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except SystemError:
        # CasADi 3.7 leaves the KeyboardInterrupt it caught inside an IPOPT solve pending, so the solve
        # returns into "SystemError: ... returned a result with an exception set" (3.8 returns a failed
        # solve); with an interrupt recorded, that error is the interrupt
        if interrupts.requested() is None:
            raise
        return EXIT_INTERRUPTED
    finally:
        warnings.formatwarning = shown


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
