"""``ipmc invert``: stable inversion of a CSV signal from the shell.

Input CSV: a header row, a ``time_s`` column (uniform steps) and one or more signal columns
(the first non-time column is inverted unless ``--column`` names another).  Output CSV:
``time_s, <input column>, reconstruction`` plus ``<reference>, error`` when ``--reference``
names a column holding the true signal (error = reconstruction - reference).  Files are
written atomically (temporary file in the same directory, then ``os.replace``), so an
interrupted run never leaves a half-written output.

Examples::

    ipmc invert current.csv -o displacement.csv \\
        --num=-17.3,2.2e4,-1.0e7,-9.4e8,4.5e10 --den=1,835,6.3e5,2.5e8,4.4e10 \\
        --preview auto --plot displacement.png

(Write coefficient lists with ``=`` and commas: argparse would read a separate token such as
``-1.0e7`` as an option.)

Exit codes: 0 success, 2 bad input (unreadable/invalid CSV, invalid model or options).

``add_parser(subparsers)`` registers the subcommand; ``run(args)`` executes it.  The
surrogate hook (``--surrogate model.json --temperature T``) calls
:func:`model_from_surrogate`, which uses the ``surrogate`` package once it provides a JSON
loader.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ._errors import InversionError
from .batch import invert

__all__ = ["add_parser", "run", "main", "model_from_surrogate", "read_csv", "atomic_write"]


def _floats(tokens: list[str]) -> list[float]:
    out: list[float] = []
    for tok in tokens:
        for part in tok.replace(";", ",").split(","):
            part = part.strip()
            if part:
                try:
                    out.append(float(part))
                except ValueError:
                    raise InversionError(f"cannot read coefficient {part!r} as a number") from None
    return out


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``invert`` subcommand to an ``argparse`` subparsers object and return it."""
    p = subparsers.add_parser(
        "invert",
        help="stable (noncausal / finite-preview) inversion of a sampled signal in a CSV file",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("input", help="input CSV with a header, a time_s column and signal columns")
    p.add_argument("-o", "--output", required=True, help="output CSV path")
    p.add_argument("--column", default=None,
                   help="signal column to invert (default: first column other than time_s)")
    p.add_argument("--time-column", default="time_s", help="time column name [s] (default time_s)")
    p.add_argument("--reference", default=None,
                   help="column with the true signal; adds reference and error columns/plot")
    p.add_argument("--num", nargs="+", default=None, metavar="C",
                   help="model numerator coefficients, descending powers of s (s in rad/s); "
                        "write --num=-17.3,2.2e4,... when a coefficient is negative")
    p.add_argument("--den", nargs="+", default=None, metavar="C",
                   help="model denominator coefficients, descending powers of s")
    p.add_argument("--surrogate", default=None,
                   help="surrogate model JSON (needs --temperature); hook for the surrogate package")
    p.add_argument("--temperature", type=float, default=None, help="temperature [degC] for --surrogate")
    p.add_argument("--preview", default="auto",
                   help="preview: 'auto' (4/r0), 'inf' (full noncausal inverse) or seconds")
    p.add_argument("--improper", choices=("error", "filter", "differentiate"), default="error",
                   help="handling of a strictly proper model (improper inverse)")
    p.add_argument("--filter-bandwidth", type=float, default=None,
                   help="low-pass bandwidth [rad/s] for --improper filter")
    p.add_argument("--plot", default=None, help="write a PNG with input, reconstruction and error")
    p.set_defaults(func=run)
    return p


def model_from_surrogate(path: str, temperature_c: float) -> Any:
    """Load a surrogate JSON and evaluate it at ``temperature_c`` [degC] (hook).

    Uses ``surrogate.load(path)`` (or ``surrogate.load_json``) returning an object with
    ``.at(T)``; raises :class:`InversionError` with a clear message until that exists.
    """
    try:
        import surrogate  # type: ignore[import-not-found]
    except ImportError:
        raise InversionError(
            "--surrogate needs the 'surrogate' package, which is not available; pass the model "
            "as --num/--den coefficients instead") from None
    loader: Callable[[str], Any] | None = getattr(surrogate, "load", None) or getattr(
        surrogate, "load_json", None)
    if loader is None:
        raise InversionError(
            "the installed 'surrogate' package has no load()/load_json() yet; pass the model "
            "as --num/--den coefficients instead")
    model = loader(path)
    if not hasattr(model, "at"):
        raise InversionError(f"surrogate loaded from {path!r} has no .at(temperature) method")
    return model.at(float(temperature_c))


def read_csv(path: str | os.PathLike[str]) -> tuple[list[str], np.ndarray]:
    """Read a numeric CSV with a header row; return (column names, 2-D float array)."""
    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise InversionError(f"{path}: empty file (expected a header row)") from None
        rows = []
        for lineno, row in enumerate(reader, start=2):
            if not row or all(not c.strip() for c in row):
                continue
            if len(row) != len(header):
                raise InversionError(
                    f"{path}:{lineno}: expected {len(header)} fields like the header, got {len(row)}")
            try:
                rows.append([float(c) for c in row])
            except ValueError:
                raise InversionError(f"{path}:{lineno}: non-numeric field in {row!r}") from None
    if len(set(header)) != len(header):
        raise InversionError(f"{path}: duplicate column names in header {header}")
    data = np.array(rows, dtype=float).reshape(len(rows), len(header))
    return header, data


def atomic_write(path: str | os.PathLike[str], write: Callable[[Any], None], binary: bool = False) -> None:
    """Write a file atomically: ``write(fh)`` into a temporary file beside it, then ``os.replace``."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb" if binary else "w", newline=None if binary else "") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)   # mkstemp creates 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _plot(path: str, t: np.ndarray, u: np.ndarray, y: np.ndarray, ucol: str,
          ref: np.ndarray | None, refcol: str | None, title: str) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rows = 3 if ref is not None else 2
    fig = Figure(figsize=(8, 2.4 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(rows, 1, sharex=True)
    axes[0].plot(t, u, lw=0.8)
    axes[0].set_ylabel(ucol)
    axes[0].set_title(title)
    axes[1].plot(t, y, lw=0.8, label="reconstruction")
    if ref is not None:
        axes[1].plot(t, ref, lw=0.8, ls="--", label=refcol)
        axes[2].plot(t, y - ref, lw=0.8, color="C3")
        axes[2].set_ylabel("error")
    axes[1].set_ylabel("reconstruction")
    axes[1].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("time [s]")
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110), binary=True)


def run(args: argparse.Namespace) -> int:
    """Execute ``ipmc invert``; return 0 on success, 2 on bad input."""
    try:
        return _run(args)
    except (InversionError, ValueError, OSError) as exc:
        print(f"ipmc invert: error: {exc}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace) -> int:
    if args.surrogate is not None:
        if args.num is not None or args.den is not None:
            raise InversionError("give either --num/--den or --surrogate, not both")
        if args.temperature is None:
            raise InversionError("--surrogate needs --temperature (degC)")
        model: Any = model_from_surrogate(args.surrogate, args.temperature)
    else:
        if args.num is None or args.den is None:
            raise InversionError("the model is missing: give --num and --den (or --surrogate)")
        model = (_floats(args.num), _floats(args.den))
    preview: Any = args.preview
    header, data = read_csv(args.input)
    if args.time_column not in header:
        raise InversionError(f"{args.input}: no time column {args.time_column!r} in header {header}")
    it = header.index(args.time_column)
    others = [h for h in header if h != args.time_column]
    ucol = args.column if args.column is not None else (others[0] if others else None)
    if ucol is None or ucol not in header:
        raise InversionError(f"{args.input}: no signal column {ucol!r} in header {header}")
    if args.reference is not None and args.reference not in header:
        raise InversionError(f"{args.input}: no reference column {args.reference!r} in header {header}")
    t = data[:, it]
    u = data[:, header.index(ucol)]
    res = invert(model, t, u, preview=preview, improper=args.improper,
                 filter_bandwidth=args.filter_bandwidth)
    y = res.output
    ref = data[:, header.index(args.reference)] if args.reference is not None else None
    cols = [args.time_column, ucol, "reconstruction"]
    table = [t, u, y]
    if ref is not None:
        cols += [args.reference, "error"]
        table += [ref, y - ref]
    arr = np.column_stack(table)

    def write_csv(fh: Any) -> None:
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt="%.12g")

    atomic_write(args.output, write_csv)
    if args.plot:
        prev = "infinite" if math.isinf(res.preview_s) else f"{res.preview_s:.4g} s"
        _plot(args.plot, t, u, y, ucol, ref, args.reference, f"stable inversion, preview {prev}")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Standalone entry point: ``python -m inversion.cli invert ...``."""
    parser = argparse.ArgumentParser(prog="ipmc")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser(sub)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
