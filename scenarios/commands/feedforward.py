"""``ipmc feedforward``: a surrogate's feedforward voltage, with its error predicted on *your strip*.

    ipmc feedforward fit/model.json --temperature 35 --reference sine --amplitude 0.3 --frequency 1 \\
        --model diag/model.json --data sweep.csv --out ff-out

1. builds the reference (sine, multitone or smoothed steps from options, or ``--reference-file``)
   with C2 fade-in/fade-out windows and rest at both ends (:mod:`inversion.references`), in the
   surrogate's output unit (e.g. mm);
2. inverts the surrogate at ``--temperature`` (:func:`inversion.feedforward`; default preview
   ``auto``: truncation error below ``--preview-tol`` of the full inverse) and checks the voltage
   against ``--max-voltage`` (default 3 V; ``--no-voltage-limit`` drops it, said on stderr and in the
   report) and ``--max-rate``: a violation is refused (exit 3, nothing written) unless ``--on-limit warn``;
3. **predicts the tracking error on the strip** from the measured sweep (``--data``, or the data
   file named in the physics model's or the surrogate's provenance): the surrogate's misfit to
   the measured lines, carried to ``--temperature`` between the measured temperatures with a
   stated bound (:mod:`surrogate.strip_check`); without measured data the report says the
   prediction is unchecked against measurement;
4. runs V(t) through the physics model (``--model`` — the ``model.json`` of ``ipmc calibrate`` or
   ``ipmc diagnose``, effects included — or ``--set``/``--params-json``; by default the model the
   surrogate's sweep was made from, never an unrelated named set) with an exact frequency-domain
   simulation (:mod:`physmodel.data.fftsim`) and reports the error against that physics beside
   the prediction on the strip.

Verdicts travel: when the physics model or the model behind the surrogate's sweep does not fit the
data it was fitted to, the report and stderr say so and the exit code is 3 unless
``--accept-misfit``.

Writes into ``--out``: ``voltage.csv`` (``time_s, voltage_V, reference_<u>, predicted_tip_<u>``; the
``voltage_V`` column is what ``ipmc simulate --input`` reads), ``report.md``, ``report.json`` and
``feedforward.png``.  Exit codes: 0 ok, 2 bad input, 3 a limit was violated (refused), an
upstream model does not fit its data, or ``--max-error`` exceeded.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import warnings
from pathlib import Path

import numpy as np

from inversion.limits import DEFAULT_MAX_VOLTAGE

from ._columns import add_sweep_options, reference_column_unit, signal_scale, surrogate_role
from ._common import (
    EXIT_FAILED,
    EXIT_OK,
    CLIError,
    as_flags,
    check_celsius,
    check_result_file,
    floats,
    load_physics,
    provenance_data,
    verdict_lines,
)

__all__ = ["add_parser", "run", "build_reference", "drive_limits", "limit_flags"]


def add_parser(sub):
    p = sub.add_parser("feedforward", help="feedforward voltage of a surrogate, checked on the physics",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("surrogate", help="surrogate model JSON (what 'ipmc fit' writes)")
    p.add_argument("--temperature", type=float, required=True, help="operating temperature [°C]")
    g = p.add_argument_group("reference (in the surrogate's output unit, e.g. mm)")
    g.add_argument("--reference", choices=("sine", "multitone", "steps"), default="sine")
    g.add_argument("--reference-file", help="CSV/NPZ/MAT with a time column and a value column (instead of --reference)")
    g.add_argument("--reference-column", metavar="NAME|INDEX",
                   help="value column of --reference-file, by name or 0-based index (default: the first after time_s)")
    g.add_argument("--amplitude", default="0.3", help="amplitude(s), comma-separated for multitone")
    g.add_argument("--frequency", default="1", help="frequency(ies) [Hz], comma-separated for multitone")
    g.add_argument("--levels", default="0.2,-0.2", help="steps: plateau levels")
    g.add_argument("--hold", type=float, default=2.0, help="steps: plateau length [s]")
    g.add_argument("--transition", type=float, default=0.5, help="steps: ramp length [s]")
    g.add_argument("--duration", type=float, help="signal length incl. fades [s] (default 8 periods, >= 4 s)")
    g.add_argument("--fs", type=float, default=1000.0, help="sampling rate [Hz]")
    g.add_argument("--fade", type=float, help="fade-in and fade-out length [s] (default 2 periods; file: 0)")
    g.add_argument("--lead", type=float, default=1.0, help="rest before the reference [s]")
    g.add_argument("--tail", type=float, default=1.0, help="rest after the reference [s]")
    g.add_argument("--unit", help="reference unit (default: the surrogate's output unit; another length unit is "
                                  "converted to it, another kind refused)")
    c = p.add_argument_group("inversion and limits")
    c.add_argument("--preview", default="auto", help="'auto' (tolerance rule), '4/r0', 'inf' or seconds")
    c.add_argument("--preview-tol", type=float, default=1e-3, help="auto preview: relative truncation error")
    c.add_argument("--improper", choices=("error", "filter", "differentiate"), default="error",
                   help="a strictly proper surrogate (improper inverse): refuse, low-pass the inverse "
                        "(--filter-bandwidth) or apply its s^k terms as finite differences")
    c.add_argument("--filter-bandwidth", type=float, default=None, help="low-pass bandwidth [rad/s] for --improper filter")
    c.add_argument("--max-voltage", type=float, default=None,
                   help=f"largest |V| allowed [V], > 0 (default {DEFAULT_MAX_VOLTAGE:g} V: IPMCs take ~2-3 V)")
    c.add_argument("--no-voltage-limit", action="store_true",
                   help="drop the voltage limit (a virtual plant; never a real strip): said on stderr and in the report")
    c.add_argument("--max-rate", type=float, help="largest |dV/dt| allowed [V/s], > 0")
    c.add_argument("--on-limit", choices=("error", "warn"), default="error",
                   help="refuse (exit 3, nothing written) or warn and continue")
    c.add_argument("--max-error", type=float,
                   help="fail (exit 3) if the error against the physics (max between the fades) or the predicted RMS "
                        "error on the strip exceeds this [unit]")
    m = p.add_argument_group("checks: your measured data and the physics")
    m.add_argument("--data", help="the measured sweep of the strip (.csv/.npz/.mat); default: the data file named "
                                  "in the physics model's provenance, else in the surrogate's")
    m.add_argument("--model", help="physics model file (model.json of 'ipmc calibrate' or 'ipmc diagnose'); default: "
                                   "the model the surrogate's sweep was made from")
    m.add_argument("--set", default=None, help="a named parameter set or JSON file for the physics (instead of --model)")
    m.add_argument("--params-json", help="a JSON parameter or model file (same as --model)")
    m.add_argument("--param", action="append", metavar="NAME=VALUE", help="override a parameter (SI)")
    m.add_argument("--accept-misfit", action="store_true",
                   help="exit 0 even when the physics model (or the one behind the surrogate) does not fit its data")
    m.add_argument("--no-check", action="store_true", help="only write V(t); skip the physics simulation")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--quiet", action="store_true")
    add_sweep_options(p, "--data")
    p.set_defaults(func=run)
    return p


def build_reference(args, unit: str):
    """The :class:`inversion.references.Reference` the options describe."""
    from inversion import references as R

    lead, tail = args.lead, args.tail
    if args.reference_file:
        fade = 0.0 if args.fade is None else args.fade
        column = None if args.reference_column is None else \
            reference_column_unit(args.reference_file, args.reference_column)[0]     # an index → its name
        return R.from_file(args.reference_file, column=column, fade_in_s=fade,
                           fade_out_s=fade, lead_s=lead, tail_s=tail, unit=unit)
    if args.reference == "steps":
        return R.smoothed_steps(floats(args.levels, "--levels"), args.hold, args.fs,
                                transition_s=args.transition, lead_s=lead, tail_s=tail, unit=unit)
    amps = floats(args.amplitude, "--amplitude")
    freqs = floats(args.frequency, "--frequency")
    fmin = min(freqs)
    dur = args.duration if args.duration is not None else max(8.0 / fmin, 4.0)
    if args.reference == "sine":
        if len(amps) != 1 or len(freqs) != 1:
            raise CLIError("--reference sine takes one --amplitude and one --frequency (use multitone)")
        return R.sine(amps[0], freqs[0], dur, args.fs, fade_in_s=args.fade, fade_out_s=args.fade,
                      lead_s=lead, tail_s=tail, unit=unit)
    return R.multitone(amps, freqs, dur, args.fs, fade_in_s=args.fade, fade_out_s=args.fade,
                       lead_s=lead, tail_s=tail, unit=unit)


def _surrogate(path, temperature_c):
    import surrogate

    p = Path(path)
    if not p.exists():
        raise CLIError(f"{path}: no such surrogate file")
    try:
        model = surrogate.load(p)
    except (ValueError, KeyError, TypeError) as exc:
        raise CLIError(f"{path}: not a surrogate model JSON ({exc})") from None
    lo_hi = model.temperature_range_c
    if model.is_scheduled and lo_hi is not None and not (lo_hi[0] <= temperature_c <= lo_hi[1]):
        raise CLIError(f"--temperature {temperature_c:g} °C is outside the surrogate's range "
                       f"[{lo_hi[0]:g}, {lo_hi[1]:g}] °C")
    return model


def physics_for(args, model, command: str):
    """The physics model file of the check: the options' (--model/--set/--params-json), else the model
    the surrogate's sweep was made from (when its file still exists and its sha256 matches), else
    None.  Returns ``(ModelFile or None, overridden, note)``."""
    from physmodel.model_file import load_model

    mf, over = load_physics(args, command, default_set=None)
    if mf is not None:
        return mf, over, ""
    src = model.info.get("source_model") or {}
    path = src.get("file")
    if not path:
        return None, False, ("no physics model given and the surrogate names none (it was fitted to measured data): "
                             "the error against the physics is not computed")
    from physmodel import available_parameter_sets

    if not Path(path).is_file() and path not in available_parameter_sets():
        return None, False, f"the surrogate's physics model {path} is not found: pass --model"
    mf = load_model(path, kind=src.get("kind"))
    if src.get("sha256") and mf.fingerprint() != src["sha256"]:
        if src.get("overridden"):
            return None, False, (f"the surrogate's sweep was made from {path} with --param overrides: pass --model "
                                 "with the same --param to check against that physics")
        return None, False, (f"{path} has changed since the surrogate's sweep was made from it (sha256 differs): "
                             "pass --model explicitly")
    return mf, False, f"physics: the model the surrogate's sweep was made from ({path})"


def measured_data(args, mf, model):
    """The measured sweep to check against: ``--data``, else what the physics model or the
    surrogate names (:func:`~scenarios.commands._common.provenance_data`: only if still the same
    file and the same quantity).  Returns ``(path or None, how found, notes)``."""
    if args.data:
        if not Path(args.data).is_file():
            raise CLIError(f"--data {args.data}: no such file")
        return Path(args.data), "--data", []
    return provenance_data(mf, model.info)


def strip_prediction(data_path, model, temperature_c, t, signal, in_unit, out_unit, drive=None, args=None):
    """(DataMisfit, PredictedError) of the surrogate against the measured sweep at ``data_path``;
    with ``drive`` (the computed input, surrogate units) the inversion's own error is included."""
    from physmodel.errors import IPMCError
    from surrogate.strip_check import misfit_to_data, predicted_error

    from ._columns import read_sweep_mapped

    sweep = read_sweep_mapped(data_path, args, "--data")
    try:
        sweep = sweep.in_units(in_unit, out_unit)
    except IPMCError as exc:
        raise CLIError(f"{data_path}: its units {sweep.output_unit}/{sweep.input_unit} do not match the "
                       f"surrogate's {out_unit}/{in_unit} ({exc}); give the tip-displacement-per-volt sweep with "
                       "--data") from None
    mis = misfit_to_data(model, sweep, source=f"{data_path} (fingerprint {sweep.fingerprint()[:12]})")
    residual = None
    if drive is not None:
        from physmodel.data.fftsim import simulate_at_rest

        residual = simulate_at_rest(model, temperature_c, t, drive).y - signal     # the one model interface
    return mis, predicted_error(mis, temperature_c, t, signal, inversion_residual=residual)


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def drive_limits(args) -> tuple[float | None, float | None]:
    """(max |V| [V] or None, max |dV/dt| [V/s] or None) from ``--max-voltage``, ``--no-voltage-limit``
    and ``--max-rate``; a CLIError (exit 2) names the option for 0, negative, NaN or infinite values."""
    for opt, v in (("--max-voltage", args.max_voltage), ("--max-rate", args.max_rate)):
        if v is not None and not (math.isfinite(v) and v > 0):
            raise CLIError(f"{opt} {v:g}: expected a finite number > 0 [{'V' if opt == '--max-voltage' else 'V/s'}]"
                           + ("; to drop the voltage limit say --no-voltage-limit" if opt == "--max-voltage" else ""))
    if args.no_voltage_limit:
        if args.max_voltage is not None:
            raise CLIError(f"--max-voltage {args.max_voltage:g} and --no-voltage-limit: give one of them")
        return None, args.max_rate
    return (DEFAULT_MAX_VOLTAGE if args.max_voltage is None else args.max_voltage), args.max_rate


def limit_flags(message: str, max_v: float | None, max_rate: float | None) -> str:
    """A limit message of :func:`inversion.limits.check_limits` (Python names: ``max_voltage = ±…``,
    ``max_rate = …``, ``action='warn'``, ``preview='inf'``) with the options of this command that set
    them (``--max-voltage``, ``--max-rate``, ``--on-limit warn``, ``--preview inf``), so that the
    message names what the user can type.  ``max_v`` [V] and ``max_rate`` [V/s] are the options'
    values; the limit itself stays in the message's own unit."""
    if max_v is not None:
        message = re.sub(r"max_voltage = ±(\S+ \S+) \((\d+) samples violate it\)",
                         rf"±\1 (--max-voltage {max_v:g}; \2 samples violate it)", message)
    if max_rate is not None:
        message = re.sub(r"max_rate = (\S+ \S+) \((\d+) samples violate it\)",
                         rf"\1 (--max-rate {max_rate:g}; \2 samples violate it)", message)
    message = message.replace("preview='inf'", "--preview inf").replace("action='warn'", "--on-limit warn")
    return message.replace("relax the limits (--on-limit warn to proceed)",
                           "relax --max-voltage/--max-rate (--on-limit warn to proceed)")


def run(args) -> int:
    import json

    from inversion import InversionError, feedforward
    from inversion.limits import LimitError, Limits, LimitWarning
    from physmodel.data.files import atomic_write
    from physmodel.data.units import UNITS, unit_scale

    max_v, max_rate = drive_limits(args)
    check_celsius(args.temperature, "--temperature")
    check_result_file(args.surrogate, "SURROGATE")          # not from a fit interrupted in its write phase
    model = _surrogate(args.surrogate, args.temperature)
    G = model.at(args.temperature)
    in_unit = model.labels.get("input_unit") or "V"
    out_unit = model.labels.get("output_unit") or "mm"
    for u, what in ((in_unit, "input"), (out_unit, "output")):
        if u not in UNITS:
            raise CLIError(f"{args.surrogate}: {what} unit {u!r} is not one of {sorted(UNITS)}")
    if UNITS[in_unit][0] != "voltage" or UNITS[out_unit][0] != "length":
        raise CLIError(f"{args.surrogate}: {surrogate_role({'input_unit': in_unit, 'output_unit': out_unit, **model.labels})}: "
                       "a feedforward needs an actuator surrogate (tip displacement per volt, e.g. mm/V)")
    labels = {**model.labels, "output_unit": out_unit}
    ref_scale = signal_scale("reference", args.unit or out_unit, labels, "ipmc feedforward", "--unit")
    if args.reference_file:                             # a column with its own unit: its kind checked, a
        col, unit = reference_column_unit(args.reference_file, args.reference_column)   # conversion said
        if col is not None and unit is not None:
            signal_scale(col, unit, labels, "ipmc feedforward", "--reference-column/--unit")
    if args.no_check and (args.model or args.set or args.params_json or args.param):
        raise CLIError("--no-check: no physics check is run, so --model/--set/--params-json/--param have nothing to do")
    mf, overridden, phys_note = (None, False, "physics check skipped (--no-check)") if args.no_check else \
        physics_for(args, model, "ipmc feedforward")
    if mf is not None and mf.kind != "actuator":
        raise CLIError(f"{mf.path or mf.name}: a {mf.kind} model cannot check an actuator's feedforward")
    data_path, data_how, data_notes = measured_data(args, mf, model)
    if args.max_error is not None and data_path is None and mf is None:
        raise CLIError("--max-error: nothing to check it against (no measured data and no physics model)")
    ref = build_reference(args, args.unit or out_unit)
    if ref_scale != 1.0:                                # the reference in the surrogate's unit
        from dataclasses import replace

        ref = replace(ref, y=ref.y * ref_scale, unit=out_unit)
    from inversion.references import edge_jump

    jump = edge_jump(ref.y)
    if jump > 0.01:
        print(f"ipmc feedforward: warning: the reference is at {100 * jump:.0f} % of its peak at a record end; "
              "the noncausal inverse sees a jump to zero there (a voltage spike): use --fade and --lead/--tail",
              file=sys.stderr)
    v_scale = unit_scale(in_unit)                       # surrogate input unit -> V
    limits = Limits(max_voltage=None if max_v is None else max_v / v_scale,
                    max_rate=None if max_rate is None else max_rate / v_scale, action=args.on_limit)
    if max_v is None:
        print("ipmc feedforward: warning: --no-voltage-limit: the drive voltage is not limited; "
              "never play it on a real strip without checking its peak", file=sys.stderr)
    refused, error = None, None
    caught: list = []
    try:
        with warnings.catch_warnings(record=True) as caught:   # a limit warning is re-said below with the options
            warnings.simplefilter("always")
            try:
                ff = feedforward(G, ref.t, ref.y, preview=args.preview, preview_tol=args.preview_tol, limits=limits,
                                 improper=args.improper, filter_bandwidth=args.filter_bandwidth)
            except LimitError as exc:
                refused = limit_flags(str(exc), max_v, max_rate)
            except InversionError as exc:        # the library's keywords, spelled as this command's flags
                error = CLIError(f"{args.surrogate}: {as_flags(str(exc))}")
    finally:        # said even when something unexpected (or Ctrl-C) ends the inversion
        for w in caught:
            if isinstance(w.message, LimitWarning):
                warnings.warn(LimitWarning(limit_flags(str(w.message), max_v, max_rate)), stacklevel=1)
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if error is not None:
        raise error
    if refused is not None:
        print(f"ipmc feedforward: refused: {refused}", file=sys.stderr)
        return EXIT_FAILED
    volts = ff.output * v_scale
    from physmodel.data import results

    final = Path(args.out)          # written into a temporary sibling, moved into place when complete
    out = results.begin(final, "ipmc feedforward", force=True)
    r_rms = _rms(ref.y)
    cols = {"time_s": ref.t, "voltage_V": volts, f"reference_{out_unit}": ref.y}
    summary: dict = {"surrogate": str(args.surrogate), "temperature_c": args.temperature, "unit": out_unit,
                     "reference": ref.description, "reference_rms": r_rms,
                     "peak_voltage_V": float(ff.limit_report.peak * v_scale), "max_voltage_V": max_v}

    # ---- upstream verdicts
    upstream = []
    src = model.info.get("source_model") or {}
    if src.get("verdict") == "MISFIT":
        upstream.append(f"the physics the surrogate's sweep was made from ({src.get('file')}) does not fit its data: "
                        f"{src.get('verdict_reason', '')}")
    if mf is not None and mf.verdict is not None and not mf.verdict.adequate and \
            not (src.get("sha256") and src.get("sha256") == mf.fingerprint()):
        upstream.append(f"the physics model {mf.path or mf.name} does not fit its data: {mf.verdict.reason}")
    from ._common import surrogate_misfit

    own = surrogate_misfit(model.info)
    if own is not None:
        upstream.append(own)
    summary["upstream_misfit"] = upstream
    lo_hi = model.temperature_range_c
    range_notes = []
    fitted_t = src.get("fitted_temperatures_c") or (",".join(f"{t:g}" for t in mf.provenance.temperatures_c)
                                                    if mf is not None and mf.provenance is not None else "")
    if fitted_t:
        ts_ = [float(x) for x in str(fitted_t).split(",") if x.strip()]
        if ts_ and not (min(ts_) <= args.temperature <= max(ts_)):
            range_notes.append(f"{args.temperature:g} °C is outside the temperatures the physics was fitted at "
                               f"({min(ts_):g}–{max(ts_):g} °C): extrapolated physics")

    fit_band = (model.info.get("data") or {}).get("band_hz")
    if fit_band:
        from surrogate.strip_check import power_outside

        share = power_outside(ref.t, ref.y, fit_band)
        summary["power_outside_surrogate_band"] = share
        if share > 0.01:
            range_notes.append(f"{100 * share:.2g} % of the reference's power lies outside the band the surrogate was "
                               f"fitted on ({fit_band[0]:.4g}–{fit_band[1]:.4g} Hz): unchecked there")

    # ---- prediction on the strip
    lines = [f"# Feedforward at {args.temperature:g} °C", ""]
    strip = None
    if data_path is not None:
        mis, strip = strip_prediction(data_path, model, args.temperature, ref.t, ref.y, in_unit, out_unit,
                                      drive=ff.output, args=args)
        summary["predicted_error_on_strip_rms"] = strip.rms
        summary["predicted_error_on_strip_bound"] = strip.bound
        summary["strip_check"] = {**strip.to_dict(), "data": str(data_path), "found_by": data_how,
                                  "misfit_per_temperature": mis.table()}
        lines += ["## Predicted error on your strip", "",
                  f"- **{100 * strip.rms:.3g} % RMS of the reference** ({strip.rms * r_rms:.4g} {out_unit} RMS), "
                  f"stated bound {100 * strip.bound:.3g} % — the surrogate's misfit to the measured sweep "
                  f"`{data_path}` (found by {data_how}) carried to {args.temperature:g} °C",
                  f"- {strip.sentence()}",
                  "- measured misfit |H/G − 1| per temperature: " + ", ".join(
                      f"{r['temperature_c']:g} °C {100 * r['rms_misfit']:.3g} % (noise {100 * r['rms_sigma']:.2g} %)"
                      for r in mis.table())]
        if not strip.checked:
            print(f"ipmc feedforward: warning: the prediction on the strip is not covered by the data: {strip.sentence()}",
                  file=sys.stderr)
    else:
        summary["predicted_error_on_strip_rms"] = None
        lines += ["## Predicted error on your strip", "",
                  "- **UNCHECKED against measurement**: no measured sweep (give --data, or use a model whose provenance "
                  "names its data); the numbers below are against a model, not the strip"]
        print("ipmc feedforward: warning: the predicted error is unchecked against measurement (no --data)",
              file=sys.stderr)
    for u in upstream:
        lines.append(f"- **UPSTREAM MISFIT**: {u}")
        print(f"ipmc feedforward: {u}", file=sys.stderr)
    for n in data_notes:
        lines.append(f"- not used as data: {n}")
        print(f"ipmc feedforward: note: not used as data: {n}", file=sys.stderr)
    for n in range_notes:
        lines.append(f"- **{n}**")
        print(f"ipmc feedforward: warning: {n}", file=sys.stderr)
    lines += ["", "## Voltage", "",
              f"- surrogate: `{args.surrogate}` ({model!r})"
              + (f"; fitted over {lo_hi[0]:g}–{lo_hi[1]:g} °C" if lo_hi else ""),
              f"- reference: {ref.description}; fades {ref.fade_in_s:g}/{ref.fade_out_s:g} s, rest "
              f"{ref.lead_s:g}/{ref.tail_s:g} s, {ref.t.size} samples at {1 / ref.dt:g} Hz",
              f"- preview: {ff.preview_rule} -> {ff.preview_s:.4g} s"
              + (f" (truncation error {ff.preview_choice.relative_error:.2g} of the inverse, tolerance "
                 f"{ff.preview_choice.tolerance:g}; the 4/r0 rule would give {ff.auto_preview_s:.4g} s)"
                 if ff.preview_choice is not None else "")
              + f"; truncation error {ff.truncation_error * v_scale:.3g} V (bound {ff.truncation_bound * v_scale:.3g} V)",
              f"- peak voltage {ff.limit_report.peak * v_scale:.4g} V, peak rate {ff.limit_report.peak_rate * v_scale:.4g} V/s "
              f"(limits: --max-voltage {'**none (--no-voltage-limit)**' if max_v is None else f'{max_v:g} V'}, "
              f"--max-rate {'none' if max_rate is None else f'{max_rate:g} V/s'})"]
    trunc_rel = ff.truncation_error / max(ff.limit_report.peak, 1e-300)
    if trunc_rel > 0.01:
        lines.append(f"- **preview too short: it changes the voltage by {100 * trunc_rel:.0f} % of its peak "
                     "(use --preview auto or inf)**")
        print(f"ipmc feedforward: warning: the {ff.preview_s:.3g} s preview changes the voltage by "
              f"{100 * trunc_rel:.0f} % of its peak; use --preview auto or inf", file=sys.stderr)
    disc = ff.discretisation_error_estimate * v_scale
    lines.append(f"- sampling: discretisation error of the inverse <= {disc:.3g} V at {1 / ref.dt:g} Hz"
                 + (" — **more than 1 % of the peak voltage: sample faster (--fs)**"
                    if disc > 0.01 * ff.limit_report.peak * v_scale else ""))
    if jump > 0.01:
        lines.append(f"- **the reference ends away from rest ({100 * jump:.0f} % of its peak): expect spikes at the ends**")
    if not ff.limit_report.ok:
        lines.append(f"- **LIMIT VIOLATED**: {limit_flags(ff.limit_report.message, max_v, max_rate)}")
    for n in ff.notes:                  # what the inversion changed in the model (a zero treated as at infinity)
        lines.append(f"- inversion: {n}")
    summary["inversion_notes"] = list(ff.notes)
    status = EXIT_OK

    # ---- error against the physics model
    lines += ["", "## Error against the physics model", ""]
    if mf is None:
        lines.append(f"- not computed: {phys_note}")
        summary["physics_error_rms"] = None
    else:
        from physmodel.data.fftsim import simulate_at_rest

        from ..plots import feedforward_check

        if phys_note:
            lines.append(f"- {phys_note}")
        lines += verdict_lines(mf, overridden)
        sim = simulate_at_rest(mf.model(), args.temperature, ref.t, volts)
        y = sim.y / unit_scale(out_unit)
        err = y - ref.y
        e_max = float(np.max(np.abs(err)))
        e_body = float(np.max(np.abs(err[ref.body]))) if np.any(ref.body) else e_max
        cols[f"predicted_tip_{out_unit}"] = y
        summary.update(physics_error_rms=_rms(err) / r_rms, physics_error_max=e_max, physics_error_max_body=e_body,
                       physics_model=str(mf.path or mf.name), physics_model_sha256=mf.fingerprint())
        lines += [f"- {sim.describe()}",
                  f"- tracking error against this physics: {100 * _rms(err) / r_rms:.3g} % RMS of the reference; max "
                  f"{e_max:.4g} {out_unit} over the record, {e_body:.4g} {out_unit} between the fades (reference peak "
                  f"{float(np.max(np.abs(ref.y))):.4g} {out_unit})"]
        if not args.reference_file and args.reference == "sine":
            f = floats(args.frequency, "--frequency")[0]
            A = floats(args.amplitude, "--amplitude")[0]
            P = complex(mf.model().response(np.array([f]), [args.temperature])[0, 0]) / unit_scale(out_unit) * v_scale
            Gj = complex(G(2j * math.pi * f))
            lines.append(f"- steady-state prediction A |P/G - 1| = {A * abs(P / Gj - 1):.4g} {out_unit} "
                         f"(P: this physics, G: surrogate at {f:g} Hz)")
        fig = feedforward_check(ref.t, ref.y, y, volts, out / "feedforward.png", unit=out_unit,
                                max_voltage=max_v, body=ref.body,
                                title=f"{ref.description}, {args.temperature:g} °C, preview {ff.preview_s:.3g} s")
        lines += ["", f"![feedforward]({fig.name})"]
        if args.max_error is not None and e_body > args.max_error:
            lines.append(f"- **tracking error {e_body:.4g} {out_unit} exceeds --max-error {args.max_error:g}**")
            status = EXIT_FAILED
    if args.max_error is not None and strip is not None and strip.rms * r_rms > args.max_error:
        lines.append(f"- **predicted RMS error on the strip {strip.rms * r_rms:.4g} {out_unit} exceeds --max-error "
                     f"{args.max_error:g}**")
        status = EXIT_FAILED
    if upstream and not args.accept_misfit:
        status = EXIT_FAILED
    summary["exit_code"] = status
    arr = np.column_stack(list(cols.values()))

    def write_csv(fh):
        fh.write("# ipmc-timeseries 1\n")
        fh.write(f"# surrogate: {args.surrogate}\n# temperature_c: {args.temperature:g}\n")
        fh.write(f"# preview_s: {ff.preview_s:.6g}\n")
        fh.write("# predicted_error_on_strip: " + (f"{strip.rms:.6g} (bound {strip.bound:.6g})" if strip is not None
                                                   else "unchecked against measurement") + "\n")
        if upstream:
            fh.write(f"# upstream_misfit: {'; '.join(upstream)}\n")
        for n in ff.notes:
            fh.write(f"# inversion_note: {n}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt="%.12g")

    text = json.dumps(summary, indent=2, allow_nan=False, default=float)
    atomic_write(out / "voltage.csv", write_csv)
    atomic_write(out / "report.json", lambda fh: fh.write(text + "\n"))
    atomic_write(out / "report.md", lambda fh: fh.write("\n".join(lines) + "\n"))
    results.commit(out)
    if not args.quiet:
        print("\n".join(lines[2:]).replace("**", ""))
        print(f"ipmc feedforward: wrote {final / 'voltage.csv'}, report.md and report.json")
    if upstream and not args.accept_misfit:
        print("ipmc feedforward: an upstream model does not fit its data (exit 3; --accept-misfit to accept it)",
              file=sys.stderr)
    elif status != EXIT_OK:
        print(f"ipmc feedforward: tracking error above --max-error {args.max_error:g}", file=sys.stderr)
    return status
