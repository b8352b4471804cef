"""What the ``ipmc`` subcommands share: the exit codes, the command-line error, option parsers,
the model options (--kind/--set/--params-json/--param/--kernel) and a progress bar."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError, ParameterError

#: Exit codes of every command: success, bad input (the message names it), a check failed or a fit
#: did not converge, interrupted (SIGINT/SIGTERM).
EXIT_OK, EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED = 0, 2, 3, 130


def parse_assignments(items, option: str = "--param") -> dict[str, float]:
    """``["W=2e-3", "xi=0.2"]`` → ``{"W": 0.002, "xi": 0.2}``; a clear error naming ``option`` otherwise."""
    out: dict[str, float] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"{option} expects NAME=VALUE (SI units), got {item!r}")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise ParameterError(f"{option} {k.strip()}: {v!r} is not a number") from None
    return out


class CLIError(IPMCError):
    """Bad command-line input (exit code 2)."""


# ------------------------------------------------------------------------ argument helpers
def _floats(text: str, what: str) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise CLIError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not vals:
        raise CLIError(f"{what} is empty")
    if not all(np.isfinite(vals)):
        raise CLIError(f"{what} must be finite, got {text!r}")
    return vals


#: Figure formats the plots can write (matplotlib's savefig).
PLOT_FORMATS = (".png", ".pdf", ".svg", ".svgz", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")


def check_plot_path(path, option: str = "--plot") -> Path:
    """``path`` when its extension is a figure format, a CLIError naming it otherwise (checked
    before any computation, so a typo does not cost a whole run)."""
    p = Path(path)
    if p.suffix.lower() not in PLOT_FORMATS:
        raise CLIError(f"{option} {p}: unknown figure type {p.suffix or '(none)'!r}; use one of {', '.join(PLOT_FORMATS)}")
    if p.is_dir():
        raise CLIError(f"{option} {p} is a folder; expected a file name")
    return p


def check_out_file(path, suffixes, option: str = "--out") -> Path:
    """An output file name with one of ``suffixes`` that is not an existing folder."""
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise CLIError(f"{option} {p}: use a {', '.join(suffixes)} file name")
    if p.is_dir():
        raise CLIError(f"{option} {p} is a folder; expected a file name")
    return p


def _load_params(args):
    from physmodel import get_parameter_set
    if getattr(args, "params_json", None):
        from physmodel.parameter_sets import load_parameter_set

        path = Path(args.params_json)
        if not path.is_file():
            raise CLIError(f"--params-json {path}: no such file")
        # the same reader as --set FILE.json: the versioned file ipmc calibrate writes, or a bare record
        p = load_parameter_set(path)
        over = parse_assignments(args.param)
        return p.replace(**over) if over else p
    return get_parameter_set(args.set, **parse_assignments(args.param))


def _model(args, params):
    from physmodel import physics_model

    return physics_model(args.kind, params, kernel=args.kernel)


def _add_model_args(p):
    p.add_argument("--kind", choices=("actuator", "sensor"), default="actuator",
                   help="actuator (voltage in) or sensor (tip displacement in, short-circuit current out)")
    p.add_argument("--set", default="seed002_table3", help="named parameter set (see 'ipmc sets'); default seed002_table3")
    p.add_argument("--params-json", help="a parameter-set JSON file (IPMCParameters.to_dict) instead of --set")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="override a parameter in SI units, e.g. --param W=2e-3 (repeatable)")
    p.add_argument("--kernel", choices=("boundary_charge", "reciprocal"), default="boundary_charge",
                   help="sensing kernel (sensor only)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")


class _Progress:
    def __init__(self, total: int, quiet: bool, desc: str):
        self.bar = None
        if not quiet and total >= 200_000:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=desc, unit="pt", unit_scale=True, file=sys.stderr)

    def __call__(self, n):
        if self.bar is not None:
            self.bar.update(n)

    def close(self):
        if self.bar is not None:
            self.bar.close()
