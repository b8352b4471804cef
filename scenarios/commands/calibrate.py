"""``ipmc calibrate`` — calibrate physical parameters to a measured sweep (CSV/NPZ/MAT).

    ipmc calibrate SWEEP_FILE --set NAME_OR_JSON --kind actuator|sensor [--quantity M]
                   --free d --free "kappa_e:1e-7:1e-5" --free laws.d.activation_energy ...
                   [--effect "time_delay:delay=1e-3" ...] [--starts N] [--seed S] --out FOLDER [--name NAME] [--quiet]

``--free`` (repeatable): ``NAME`` (default bounds, see physmodel.estimation.calibration.default_free_parameter),
``NAME:LOWER:UPPER``, ``NAME:LOWER:UPPER:log|linear`` or ``NAME:LOWER:UPPER:SCALE:INITIAL``, in SI
units; NAME is an IPMCParameters field, ``omega_n`` or ``laws.<quantity>.<attribute>``.
``--effect`` (repeatable): ``NAME:PARAM=VALUE,...`` — a measurement-chain element or other library effect
(a name of ``physmodel.effects.LIBRARY``; values SI) held fixed while the physical parameters are fitted, e.g. the
chain a previous ``ipmc diagnose`` named; parameters not given stay at their "off" values.

Writes into FOLDER: ``model.json`` (the model file every later command takes with ``--model``:
parameters, laws, the fixed effects, the goodness-of-fit verdict and the data's provenance;
``physmodel.load_model`` reads it), ``parameters.json`` (the parameters alone, as before), ``calibration.json`` (estimates, 95 % intervals, correlation,
identifiability, starts), ``report.md`` and ``bode.png`` (data/model overlay and standardised residuals).
Exit codes: 0 converged, 2 bad input, 3 the fit did not converge or the model does not fit the data
(``--accept-misfit``: exit 0; the verdict still travels in model.json), 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from physmodel.errors import ParameterError

from .. import plots
from ._columns import add_sweep_options
from ._common import EXIT_FAILED, EXIT_OK, check_celsius, parse_assignments


def parse_free(spec: str, base):
    """A ``--free`` specification → FreeParameter (bare names get default bounds)."""
    from physmodel.estimation.calibration import default_free_parameter
    from physmodel.estimation.records import FreeParameter
    from physmodel.parameter_paths import base_value, check_parameter_name

    parts = [p.strip() for p in spec.split(":")]
    name = parts[0]
    if not name:
        raise ParameterError(f"--free {spec!r}: missing parameter name")
    check_parameter_name(base, name)
    if len(parts) == 1:
        return default_free_parameter(base, name)
    if len(parts) not in (3, 4, 5):
        raise ParameterError(f"--free {spec!r}: expected NAME, NAME:LOWER:UPPER, NAME:LOWER:UPPER:SCALE "
                             "or NAME:LOWER:UPPER:SCALE:INITIAL")
    try:
        lo, hi = float(parts[1]), float(parts[2])
        initial = float(parts[4]) if len(parts) == 5 else None
    except ValueError:
        raise ParameterError(f"--free {spec!r}: bounds and initial value must be numbers (SI units)") from None
    scale = (parts[3] or None) if len(parts) >= 4 else None
    if initial is None:
        v = base_value(base, name)
        initial = v if lo <= v <= hi else None
    return FreeParameter(name, lo, hi, scale, initial)


def start_model(source: str, kind: str | None, overrides: dict):
    """The start of a calibration or diagnosis: a named set or a model/parameter file (its effects
    come along), with ``overrides`` (SI) applied."""
    from pathlib import Path

    from physmodel.model_file import load_model

    from ._common import check_plausible, check_result_file

    if Path(source).is_file():
        check_result_file(source, "--set")          # not from a folder an interrupted run left behind
    mf = load_model(source, kind=kind, **overrides)
    check_plausible(mf.parameters, f"--set {source}" + (" with the overrides" if overrides else ""))
    return mf


def parse_effect(item: str, option: str = "--effect") -> tuple[str, dict]:
    """``NAME:P=V,...`` → ``(NAME, {P: V})`` (SI values; none = the effect's parameters left to the caller)."""
    name, _, rest = item.partition(":")
    items = [s.strip() for s in rest.split(",") if s.strip()]
    return name.strip(), parse_assignments(items, option=f"{option} {item!r}:")


def provenance_of(data_file, data, creator: str):
    """The :class:`physmodel.model_file.Provenance` of a model fitted to ``data`` read from ``data_file``."""
    import shlex
    from pathlib import Path

    import physmodel
    from physmodel.model_file import Provenance, file_sha256

    # absolute, so that a later command run from another folder finds it (and its hash guards it)
    return Provenance(creator, str(Path(data_file).resolve()), file_sha256(data_file), data.fingerprint(),
                      tuple(float(t) for t in data.temperatures()),
                      (float(np.min(data.frequency_hz)), float(np.max(data.frequency_hz))),
                      " ".join(shlex.quote(a) for a in ["ipmc", *sys.argv[1:]]), physmodel.__version__)


def add_parser(subparsers):
    """Add the ``calibrate`` subcommand."""
    p = subparsers.add_parser(
        "calibrate", help="calibrate physical parameters to a measured sweep (estimates, intervals, identifiability)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("sweep", metavar="SWEEP_FILE", help="frequency sweep (.csv, .npz or .mat; physmodel format)")
    p.add_argument("--set", "--model", required=True, dest="base_set",
                   help="start: a named parameter set (see 'ipmc sets') or a model file (model.json of an earlier "
                        "calibrate/diagnose: its effects are kept, fixed)")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="override a base parameter in SI units before fitting (repeatable)")
    p.add_argument("--kind", choices=("actuator", "sensor"), default=None,
                   help="model kind (default: the model file's, else actuator)")
    p.add_argument("--quantity", help="actuator: M (default), H, Z, I; sensor: S (default), Z")
    p.add_argument("--kernel", choices=("boundary_charge", "reciprocal"), default="boundary_charge",
                   help="sensing kernel (sensor only)")
    p.add_argument("--free", action="append", required=True, metavar="SPEC",
                   help="a parameter to fit: NAME[:LOWER:UPPER[:log|linear[:INITIAL]]] (repeatable)")
    p.add_argument("--effect", action="append", metavar="NAME:P=V,...",
                   help="a library effect held fixed at these SI values while fitting (repeatable)")
    p.add_argument("--starts", type=int, default=4, help="number of starts (base value + seeded Latin hypercube; default 4)")
    p.add_argument("--seed", type=int, default=0, help="seed of the extra starts (default 0)")
    p.add_argument("--max-nfev", type=int, help="residual evaluations allowed per start (default: scipy's)")
    p.add_argument("--no-hold", action="store_true",
                   help="report undetermined parameters but do not hold them at their base value (a hold "
                        "that would worsen the fit beyond its likelihood-ratio test is refused anyway)")
    p.add_argument("--accept-misfit", action="store_true",
                   help="exit 0 even when the model does not fit the data (goodness-of-fit test failed); "
                        "intervals are then widened by the Birge ratio instead of withheld")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds another run's results")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--name", help="name of the calibrated parameter set (default <base>_calibrated)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    add_sweep_options(p)
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    """Execute ``ipmc calibrate``; returns 0, or 3 when the fit did not converge (bad input raises)."""
    from ._columns import read_sweep_mapped

    if args.starts < 1:
        raise ParameterError(f"--starts must be >= 1, got {args.starts}")
    data = read_sweep_mapped(args.sweep, args)
    check_celsius(data.temperatures(), f"{args.sweep}: temperature_c")
    over = parse_assignments(args.param)
    start = start_model(args.base_set, args.kind, over)
    args.kind = start.kind
    base = start.parameters
    free = [parse_free(s, base) for s in args.free]
    effects = dict(start.effects) or None
    if args.effect:
        from physmodel.effects import normalize_effects

        effects = normalize_effects({**(effects or {}), **dict(parse_effect(e, "--effect") for e in args.effect)})
    from physmodel.data.files import check_output_folder, output_folder
    from physmodel.estimation.calibration import calibrate

    out = check_output_folder(args.out, "ipmc calibrate", force=args.force)
    bar = None
    if not args.quiet:
        from tqdm import tqdm

        bar = tqdm(total=args.starts, desc="calibrate (starts)", unit="start", file=sys.stderr)
    try:
        res = calibrate(data, base, free, kind=args.kind, quantity=args.quantity, kernel=args.kernel,
                        starts=args.starts, seed=args.seed, max_nfev=args.max_nfev,
                        hold_undetermined=not args.no_hold, name=args.name,
                        misfit="widen" if args.accept_misfit else "withhold", effects=effects,
                        progress=bar.update if bar is not None else None)
    finally:
        if bar is not None:
            bar.close()
    res.metadata["sweep_file"] = str(args.sweep)
    if start.verdict is not None and not start.verdict.adequate and not args.quiet:
        print(f"ipmc calibrate: note: the start model {args.base_set} did not fit its own data "
              f"({start.verdict.reason}); this calibration is judged afresh on {args.sweep}", file=sys.stderr)
    with output_folder(out, "ipmc calibrate", force=args.force) as stage:
        _write(res, data, args, stage)
    if not args.quiet:                      # said once the folder is in place, not before
        print(res.summary())
        print(f"wrote {out}/model.json (the model for every later command: --model {out}/model.json), "
              "parameters.json, calibration.json, report.md, bode.png")
    if res.hold_refused or (res.holds and not args.quiet):
        print(f"ipmc calibrate: {res.hold_line()}", file=sys.stderr)
    if not res.converged:
        print(f"ipmc calibrate: the fit did not converge: {res.message}", file=sys.stderr)
        return EXIT_FAILED
    if not res.adequate:
        print(f"ipmc calibrate: the model does not fit the data: {res.goodness_of_fit.reason}"
              + ("" if args.accept_misfit else " (intervals withheld; --accept-misfit to exit 0 with widened intervals)"),
              file=sys.stderr)
        return EXIT_OK if args.accept_misfit else EXIT_FAILED
    return EXIT_OK


def _write(res, data, args, out):
    """Write the results into ``out`` (the temporary folder that becomes the --out folder)."""
    from physmodel.data.files import atomic_write
    from physmodel.estimation.calibration import model_sweep

    if res.parameters is not None:
        res.to_model_file(provenance_of(args.sweep, data, "ipmc calibrate")).save(out / "model.json")
    res.save(out / "parameters.json")
    record = res.to_dict()
    record["sweep_file"] = str(args.sweep)
    record["base_set"] = str(args.base_set)
    text = json.dumps(record, indent=2, allow_nan=False)
    atomic_write(out / "calibration.json", lambda fh: fh.write(text + "\n"))
    model = model_sweep(res, data)
    plots.calibration_figure(data, model, res, out / "bode.png")
    report = render_report(res, data, args)
    atomic_write(out / "report.md", lambda fh: fh.write(report))


def _g(v) -> str:
    return "–" if v is None or not np.isfinite(v) else f"{v:.5g}"


def render_report(res, data, args) -> str:
    """The Markdown report of a calibration."""
    lines = [
        f"# Calibration of `{res.parameters.name}`",
        "",
        f"- data: `{args.sweep}` — {res.n_lines} lines, temperatures {', '.join(f'{t:g}' for t in res.temperatures_c)} °C, "
        f"band {res.band_hz[0]:.4g}–{res.band_hz[1]:.4g} Hz, {data.output_name} [{data.output_unit}] per "
        f"{data.input_name} [{data.input_unit}]",
        f"- model: {res.metadata.get('kind')} quantity {res.metadata.get('quantity')}, base set `{args.base_set}`"
        + ("" if not res.metadata.get("effects") else "; fixed effects: " + "; ".join(
            f"{k} ({', '.join(f'{p} = {v:.4g}' for p, v in e.items())})" for k, e in res.metadata["effects"].items())),
        f"- status: {'converged' if res.converged else '**NOT CONVERGED**'} — {res.message}",
        f"- weighted cost {res.cost:.5g}; expected for a correct model {res.expected_cost:.5g} ± {res.cost_std:.3g}",
        "- goodness of fit: " + ("n/a" if res.goodness_of_fit is None else
                                 ("adequate" if res.adequate else "**INADEQUATE**") + f" — {res.goodness_of_fit.reason}"),
        *([f"- hold: {res.hold_line()}", *(f"  - step {i + 1}: {h.reason}" for i, h in enumerate(res.holds))]
          if res.holds else []),
        "- noise: " + ("**estimated** from the residuals (the sweep has no per-line standard deviations); "
                        f"intervals scaled by {res.noise_scale:.3g}" if res.noise_estimated
                        else "per-line standard deviations from the sweep"),
        f"- effort: {len(res.starts)} start(s), {res.n_evaluations} model evaluations in {res.n_model_calls} "
        f"batched calls, {res.elapsed_s:.2f} s",
        "",
        "## Estimates (95 % intervals)",
        "",
        "| parameter | value | std. error | 95 % interval | bounds | scale | status |",
        "|:---|---:|---:|:---|:---|:---|:---|",
    ]
    for n, fp in zip(res.names, res.free):
        st = res.identifiability[n]
        status = ("determined" if st.identifiable else f"**not assessed**: {st.reason}") if n not in res.held \
            else f"**undetermined** (held at base): {st.reason}"
        ci = "–" if n in res.held else f"[{_g(res.ci_lower[n])}, {_g(res.ci_upper[n])}]"
        if n in res.hold_refused:
            status, ci = f"**not determined, hold refused**: {st.reason}", ci + " (not valid)"
        lines.append(f"| `{n}` | {_g(res.values[n])} | {_g(res.stderr[n])} | {ci} | "
                     f"[{fp.lower:.4g}, {fp.upper:.4g}] | {fp.scale} | {status} |")
    det = res.determined
    if len(det) > 1:
        idx = [res.names.index(n) for n in det]
        lines += ["", "## Correlation of the determined parameters", "",
                  "| | " + " | ".join(f"`{n}`" for n in det) + " |",
                  "|:---|" + "---:|" * len(det)]
        for i, n in zip(idx, det):
            lines.append(f"| `{n}` | " + " | ".join(f"{res.correlation[i, j]:.3f}" for j in idx) + " |")
    lines += ["", "## Identifiability", ""]
    for n in res.names:
        st = res.identifiability[n]
        peak = ("" if st.sensitivity_peak_hz is None or st.identifiable
                else f" (sensitivity peak {st.sensitivity_peak_hz:.4g} Hz)")
        lines.append(f"- `{n}`: {'identifiable' if st.identifiable else 'NOT identifiable'} — {st.reason}{peak}")
    lines += ["", "## Starts", "", "| start | initial | final | cost | evaluations | status |",
              "|---:|:---|:---|---:|---:|:---|"]
    for s in res.starts:
        ini = ", ".join(f"{k}={v:.4g}" for k, v in s.initial.items())
        fin = ", ".join(f"{k}={v:.4g}" for k, v in s.final.items())
        lines.append(f"| {s.index} | {ini} | {fin} | {s.cost:.5g} | {s.nfev} | {s.message} |")
    lines += ["", "## Figure", "", "![Bode overlay and residuals](bode.png)", "",
              "Use the model downstream with `--model <folder>/model.json` (effects and this verdict travel with it), "
              "or in Python with `physmodel.load_model(\"<folder>/model.json\")`.", ""]
    return "\n".join(lines)
