"""``ipmc compare`` — a model against measured data, per temperature (like the ``compare`` of
system-identification toolboxes).

    ipmc compare MODEL DATA [-o FOLDER] [--quantity Q] [--accept-misfit] [--force] [--quiet]

MODEL is a physics model file (``model.json`` of ``ipmc calibrate``/``ipmc diagnose``, an older
parameter file, or a named parameter set) or a surrogate (the ``model.json`` of ``ipmc fit``);
DATA a sweep file (.csv, .npz, .mat).  The model is evaluated on the data's lines in the data's
units (:func:`scenarios.comparison.compare`) and, per temperature, prints the fit % —
100·(1 − ‖H − Ĥ‖/‖H − mean H‖) on the complex response — and χ² of the standardised residuals
against the data's per-line σ with its p-value.

With ``-o FOLDER``: ``compare.json`` (the fit figures, the verdict, notes) and ``compare.png``
(data with ±2σ bars and the model with the ±2σ band its parameters' uncertainty gives, one
colour per temperature, the fit % in the legend).

Exit codes: 0 the model is consistent with the data at every temperature, 3 it is not (the
verdict on stderr; ``--accept-misfit``: exit 0, the verdict still said), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ._common import EXIT_FAILED, EXIT_OK, CLIError, refuse_overwriting_inputs

#: What ``-o FOLDER`` holds.
OUTPUTS = ("compare.json", "compare.png")


def add_parser(sub):
    """Add ``ipmc compare`` to the subcommands ``sub`` (an ``argparse`` subparsers object)."""
    p = sub.add_parser("compare", help="a model against measured data per temperature (fit %%, chi2, overlay)",
                       description="Overlay a model (physics model.json or a surrogate) on a measured sweep and give "
                                   "the fit %% and chi2 per temperature.")
    p.add_argument("model", metavar="MODEL", help="model file: model.json of 'ipmc calibrate'/'ipmc diagnose' "
                                                  "(physics), of 'ipmc fit' (surrogate), or a named parameter set")
    p.add_argument("data", metavar="DATA", help="sweep file (.csv, .npz, .mat)")
    p.add_argument("-o", "--out", help="folder for compare.json and compare.png")
    p.add_argument("--quantity", help="physics quantity the data hold: actuator M (default), H, Z, I; sensor S, Z")
    p.add_argument("--accept-misfit", action="store_true", help="exit 0 even when the model does not fit the data")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds other results")
    p.add_argument("--quiet", action="store_true", help="no table on stdout (the verdict still goes to stderr)")
    p.set_defaults(func=run)


def _check_inputs(args):
    model, data = Path(args.model), Path(args.data)
    if not data.is_file():
        raise CLIError(f"DATA {data}: no such file (expected a sweep: .csv, .npz or .mat)")
    if data.suffix.lower() not in (".csv", ".npz", ".mat"):
        raise CLIError(f"DATA {data}: unknown sweep type {data.suffix or '(none)'!r}; expected .csv, .npz or .mat")
    if (model.suffix.lower() == ".json" or model.parent != Path(".")) and not model.is_file():
        raise CLIError(f"MODEL {model}: no such file (expected a model.json or a named parameter set)")


def run(args) -> int:
    """Run ``ipmc compare`` on parsed ``args``; returns the exit code (see the module doc)."""
    from physmodel.data.files import atomic_write, check_output_folder, output_folder, read_sweep
    from physmodel.errors import IPMCError

    from ..comparison import compare
    from ..prediction import load_any_model

    _check_inputs(args)
    if args.out is not None:
        check_output_folder(args.out, "ipmc compare", force=args.force, option="-o")
        refuse_overwriting_inputs({f"-o {args.out}/{n}": Path(args.out) / n for n in OUTPUTS},
                                  {"MODEL": args.model, "DATA": args.data})
    try:
        model = load_any_model(args.model)
    except IPMCError as exc:
        raise CLIError(f"MODEL {args.model}: {exc}") from None
    try:
        data = read_sweep(args.data)
    except IPMCError as exc:
        raise CLIError(f"DATA {args.data}: {exc}") from None
    try:
        result = compare(model, data, quantity=args.quantity)
    except IPMCError as exc:
        raise CLIError(f"MODEL {args.model} against DATA {args.data}: {exc}") from None
    if not args.quiet:
        print(f"ipmc compare: {result.model_name} vs {args.data}")
        print(result.table())
        for note in result.notes:
            print(f"note: {note}")
    if args.out is not None:
        from .. import plots

        with output_folder(args.out, "ipmc compare", force=args.force, option="-o") as out:
            record = dict(result.to_dict(), model_file=str(args.model), data_file=str(args.data))
            text = json.dumps(record, indent=2, allow_nan=False)
            atomic_write(out / "compare.json", lambda fh: fh.write(text + "\n"))
            plots.compare_figure(result, out / "compare.png")
        if not args.quiet:
            print(f"wrote {args.out}/compare.json and {args.out}/compare.png")     # the final folder
    if not result.adequate:
        print(f"ipmc compare: {result.verdict()}", file=sys.stderr)
        return EXIT_OK if args.accept_misfit else EXIT_FAILED
    return EXIT_OK
