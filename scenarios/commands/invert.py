"""``ipmc invert``: stable inversion of a recorded signal from the shell.

Input: a CSV (one header row of column names; ``,``, ``;`` or tab; ``#`` lines before it), an NPZ
archive or a MATLAB ``.mat`` file (each numeric vector a column), read as ``ipmc frf`` reads a
record (:func:`physmodel.data.columns.read_table`): a time column (``time_s`` unless
``--time-column`` names another, by name or 0-based index, in ``--time-unit`` or the unit of its
name's suffix; uniform steps) and one or more signal columns (the first numeric column other than
the time is inverted unless ``--column``/``--input-column`` names another).  Output CSV:
``time_s, <input column>, reconstruction`` plus ``<reference>, error`` when ``--reference``
names a column holding the true signal (error = reconstruction - reference).  Files are
written atomically (:func:`physmodel.data.files.atomic_write`), so an interrupted run never
leaves a half-written output.

Examples::

    ipmc invert current.csv --out displacement.csv \\
        --num=-17.3,2.2e4,-1.0e7,-9.4e8,4.5e10 --den=1,835,6.3e5,2.5e8,4.4e10 \\
        --preview auto --plot displacement.png

(Write coefficient lists with ``=`` and commas: argparse would read a separate token such as
``-1.0e7`` as an option.)

Exit codes: 0 success, 2 bad input (unreadable/invalid file, a column that is not there, invalid
model or options; the message names the file and the option).

A surrogate JSON (``--surrogate model.json --temperature T``, what ``ipmc fit`` writes) can
replace ``--num``/``--den``.  The signal must be the surrogate's output quantity (a displacement
for an actuator surrogate, a current for a sensor surrogate): its unit comes from the column name
(``tip_mm``) or ``--input-unit``; another kind is refused (exit 2), another unit of the same kind
(``tip_m`` for a mm surrogate) converted and said on stderr.  ``--column``/``--input-column``,
``--time-column`` and ``--reference`` take a name, the ``<name>`` of a ``<name>_<unit>`` column
or a 0-based index.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from inversion import InversionError, invert
from physmodel.data.files import atomic_write

from .. import plots
from ._columns import (
    add_record_options,
    add_sweep_options,
    column_values,
    pick_column,
    read_columns,
    record_time,
    signal_scale,
)
from ._common import EXIT_OK, check_plot_path

__all__ = ["add_parser", "run", "model_from_surrogate"]


def floats(tokens: list[str]) -> list[float]:
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
        help="stable (noncausal / finite-preview) inversion of a sampled signal in a .csv, .npz or .mat file",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("input", help="signal file (.csv, .npz, .mat) with a time column and signal columns")
    p.add_argument("-o", "--out", required=True, help="output CSV path")
    p.add_argument("--quiet", action="store_true", help="no summary line")
    p.add_argument("--column", default=None, metavar="NAME|INDEX",
                   help="signal column to invert (default: first column other than time_s); same as --input-column")
    p.add_argument("--reference", default=None, metavar="NAME|INDEX",
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
                   help="'auto' (smallest preview whose truncation error < --preview-tol of the inverse; default), "
                        "'4/r0' (the seed-000 rule), 'inf' (full noncausal inverse) or seconds")
    p.add_argument("--preview-tol", type=float, default=1e-3,
                   help="relative truncation error allowed by --preview auto (default 1e-3)")
    p.add_argument("--improper", choices=("error", "filter", "differentiate"), default="error",
                   help="handling of a strictly proper model (improper inverse)")
    p.add_argument("--filter-bandwidth", type=float, default=None,
                   help="low-pass bandwidth [rad/s] for --improper filter")
    p.add_argument("--plot", default=None, help="write a PNG with input, reconstruction and error")
    p.add_argument("--data", default=None,
                   help="with --surrogate: the measured sweep of the strip; the decoding error predicted from the "
                        "surrogate's misfit to it is reported (default: the data file in the surrogate's provenance)")
    p.add_argument("--accept-misfit", action="store_true",
                   help="exit 0 even when the physics behind the surrogate does not fit its data")
    add_record_options(p, ("input",), time_default="time_s")
    add_sweep_options(p, "--data")
    p.set_defaults(func=run)
    return p


def model_from_surrogate(path: str, temperature_c: float) -> Any:
    """The surrogate JSON at ``path`` (``surrogate.load``) evaluated at ``temperature_c`` [°C].

    A file that is not a complete surrogate document (not JSON, missing ``structure`` or
    ``params``, wrong types) is an InversionError naming the file, whatever the loader raised."""
    import json

    import surrogate
    from physmodel.data.files import read_text

    read_text(path, "--surrogate")           # missing file, folder, not UTF-8: a clear message
    try:
        model = surrogate.load(path)
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, json.JSONDecodeError) as exc:
        what = f"missing key {exc}" if isinstance(exc, KeyError) else f"{type(exc).__name__}: {exc}"
        raise InversionError(f"--surrogate {path}: not a usable surrogate model JSON ({what})") from None
    lo_hi = model.temperature_range_c
    if model.is_scheduled and lo_hi is not None and not (lo_hi[0] <= float(temperature_c) <= lo_hi[1]):
        raise InversionError(f"--temperature {float(temperature_c):g} °C is outside the surrogate's range "
                             f"[{lo_hi[0]:g}, {lo_hi[1]:g}] °C ({path})")
    return model.at(float(temperature_c))


def run(args: argparse.Namespace) -> int:
    """Execute ``ipmc invert``; 0 on success (bad input raises and ``ipmc`` exits 2)."""
    from ._common import refuse_overwriting_inputs

    refuse_overwriting_inputs({"--out": args.out, "--plot": args.plot},
                              {"INPUT": args.input, "--surrogate": args.surrogate, "--data": args.data})
    if args.surrogate is not None:
        if args.num is not None or args.den is not None:
            raise InversionError("give either --num/--den or --surrogate, not both")
        if args.temperature is None:
            raise InversionError("--surrogate needs --temperature (degC)")
        from ._common import check_result_file

        check_result_file(args.surrogate, "--surrogate")        # not from a fit interrupted in its write phase
        model: Any = model_from_surrogate(args.surrogate, args.temperature)
        import surrogate as _surrogate_pkg

        smodel = _surrogate_pkg.load(args.surrogate)
    else:
        if args.num is None or args.den is None:
            raise InversionError("the model is missing: give --num and --den (or --surrogate)")
        model = (floats(args.num), floats(args.den))
    preview: Any = args.preview
    if args.plot:
        check_plot_path(args.plot)
    table = read_columns(args.input, "INPUT")
    tcol, t = record_time(table, args)
    column_values(table, tcol, "--time-column", t.size)           # finite
    if args.column is not None and args.input_column is not None:
        raise InversionError("--column and --input-column name the same thing; give one of them")
    spec, opt = (args.column, "--column") if args.column is not None else (args.input_column, "--input-column")
    if spec is None:          # the first column beside the time, not a scalar of a .mat/.npz file
        others = [n for n in table.names if n != tcol and (n in table.text or table.data[n].size == t.size)]
        if not others:
            sizes = ", ".join(f"{n} has {table.data[n].size}" for n in table.names if n != tcol and n in table.data)
            raise InversionError(f"{args.input}: no signal column besides the time column {tcol!r} with its "
                                 f"{t.size} values" + (f" ({sizes})" if sizes else "") + f"; the file has "
                                 f"{table.describe()} (choose one with --input-column NAME|INDEX)")
        spec, opt = others[0], "--input-column"
    ucol = pick_column(table, spec, opt, "input")          # a text column: its first line that is not a number
    u = column_values(table, ucol, opt, t.size)
    ref, rcol = None, None
    if args.reference is not None:
        rcol = pick_column(table, args.reference, "--reference", "reference")
        ref = column_values(table, rcol, "--reference", t.size)
    u_file = u
    if args.surrogate is not None:     # the signal must be what the surrogate outputs, in its unit
        from physmodel.data.columns import suffix_unit

        named = (suffix_unit(ucol) or (None, None))[1]
        if args.input_unit and named and args.input_unit != named:
            raise InversionError(f"--input-unit {args.input_unit}: column {ucol!r} is in {named} by its name; drop one")
        unit = args.input_unit or named
        u = u * signal_scale(ucol, unit, smodel.labels, "ipmc invert", "--input-unit")
    if not (math.isfinite(args.preview_tol) and 0 < args.preview_tol < 1):
        raise InversionError(f"--preview-tol must be in (0, 1), got {args.preview_tol!r}")
    try:
        res = invert(model, t, u, preview=preview, preview_tol=args.preview_tol, improper=args.improper,
                     filter_bandwidth=args.filter_bandwidth)
    except InversionError as exc:
        from ._common import as_flags

        raise InversionError(f"{args.input}: {as_flags(str(exc))}") from None
    y = res.output
    if not np.all(np.isfinite(y)):
        # the CLI boundary guard: the library should refuse this itself (see the issue-13 report)
        k = int(np.flatnonzero(~np.isfinite(y))[0])
        raise InversionError(f"{args.input}: the inversion of column {ucol!r} overflows double precision "
                             f"({np.count_nonzero(~np.isfinite(y))} non-finite outputs from t = {t[k]:.6g} s; "
                             f"largest |input| {np.max(np.abs(u)):.3g}); scale the signal or check the model")
    cols = [tcol, ucol, "reconstruction"]
    out_cols = [table.data[tcol], u_file, y]      # the file's own columns
    if ref is not None:
        cols += [str(rcol), "error"]
        out_cols += [ref, y - ref]
    arr = np.column_stack(out_cols)

    status = EXIT_OK
    notes: list[str] = []
    if args.surrogate is not None:
        notes, status = _verdicts(args, smodel, t, y)
    elif args.data is not None:
        raise InversionError("--data needs --surrogate and --temperature (a coefficient model has no temperature)")
    notes += [f"inversion_note: {n}" for n in res.notes]     # e.g. a zero treated as at infinity

    def write_csv(fh: Any) -> None:
        for n in notes:
            fh.write(f"# {n}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt="%.12g")

    from physmodel.data.results import files_together

    prev = "infinite" if math.isinf(res.preview_s) else f"{res.preview_s:.4g} s"
    with files_together([args.out, *([args.plot] if args.plot else [])]) as tmp:     # both or neither
        atomic_write(tmp[0], write_csv)
        if args.plot:
            plots.inversion_traces(tmp[1], t, u, y, ucol, ref, rcol, f"stable inversion, preview {prev}")
    if not args.quiet:
        print(f"ipmc invert: wrote {args.out} ({t.size} samples, preview {prev})")
    return status


def _verdicts(args: argparse.Namespace, smodel: Any, t: np.ndarray, y: np.ndarray) -> tuple[list[str], int]:
    """The upstream verdict of the surrogate's physics and the decoding error predicted from its
    misfit to the measured sweep (said on stderr and as ``# key: value`` lines of the output);
    exit 3 on an upstream misfit unless ``--accept-misfit``."""
    import sys
    from pathlib import Path

    from surrogate.strip_check import misfit_to_data, predicted_error

    from ._columns import read_sweep_mapped

    notes, status = [], EXIT_OK
    src = smodel.info.get("source_model") or {}
    if src.get("verdict") == "MISFIT":
        msg = (f"upstream_misfit: the physics the surrogate's sweep was made from ({src.get('file')}) does not fit "
               f"its data: {src.get('verdict_reason', '')}")
        notes.append(msg)
        print(f"ipmc invert: {msg}" + ("" if args.accept_misfit else " (exit 3; --accept-misfit to accept)"),
              file=sys.stderr)
        status = EXIT_OK if args.accept_misfit else 3
    from ._common import provenance_data, surrogate_misfit

    own = surrogate_misfit(smodel.info)
    if own is not None:
        notes.append(f"surrogate_misfit: {own}")
        print(f"ipmc invert: surrogate_misfit: {own}" + ("" if args.accept_misfit else " (exit 3; --accept-misfit to accept)"),
              file=sys.stderr)
        status = EXIT_OK if args.accept_misfit else 3

    if args.data is not None:
        if not Path(args.data).is_file():
            raise InversionError(f"--data {args.data}: no such file")
        data = Path(args.data)
    else:
        data, _, skipped = provenance_data(None, smodel.info)
        for n in skipped:
            print(f"ipmc invert: note: not used as data: {n}", file=sys.stderr)
    if data is None:
        notes.append("predicted_error_on_strip: unchecked against measurement (no --data)")
        print("ipmc invert: warning: the decoding error is unchecked against measurement (give --data)", file=sys.stderr)
        return notes, status
    sweep = read_sweep_mapped(data, args, "--data")
    lab = smodel.labels
    try:
        sweep = sweep.in_units(lab.get("input_unit") or sweep.input_unit, lab.get("output_unit") or sweep.output_unit)
    except ValueError as exc:
        raise InversionError(f"--data {data}: its units do not match the surrogate's: {exc}") from None
    pe = predicted_error(misfit_to_data(smodel, sweep), float(args.temperature), t, y)
    # (the decoding's own error is not added: a measured signal is not at rest at its ends, so the
    # frequency-domain check of the inverse would see the record's edges, not the inversion)
    notes.append(f"predicted_error_on_strip: {pe.rms:.6g} (bound {pe.bound:.6g}; {pe.sentence()}; data {data})")
    if not args.quiet:
        print(f"ipmc invert: predicted decoding error on the strip: {pe.sentence()}")
    if not pe.checked:
        print(f"ipmc invert: warning: {pe.sentence()}", file=sys.stderr)
    return notes, status
