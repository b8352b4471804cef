"""``ipmc feedforward``: a surrogate's feedforward voltage, checked on the calibrated physics.

    ipmc feedforward model.json --temperature 35 --reference sine --amplitude 0.3 --frequency 1 \\
        --set seed001_actuator --out ff-out

1. builds the reference (sine, multitone or smoothed steps from options, or ``--reference-file``)
   with C2 fade-in/fade-out windows and rest at both ends (:mod:`inversion.references`), in the
   surrogate's output unit (e.g. mm);
2. inverts the surrogate at ``--temperature`` (:func:`inversion.feedforward`; default preview
   ``auto``: truncation error below ``--preview-tol`` of the full inverse) and checks the voltage
   against ``--max-voltage`` (default 3 V; ``--no-voltage-limit`` drops it, said on stderr and in the
   report) and ``--max-rate``: a violation is refused (exit 3, nothing written) unless ``--on-limit warn``;
3. runs V(t) through the physics (``--set``/``--params-json``, ``physmodel.data.timesim.simulate``)
   and reports the tracking error and peak voltage (and, for a sine, the steady-state prediction
   ``A |P/G - 1|`` from the physics frequency response P and the surrogate G).

Writes into ``--out``: ``voltage.csv`` (``time_s, voltage_V, reference_<u>, predicted_tip_<u>``; the
``voltage_V`` column is what ``ipmc simulate --input`` reads), ``report.md`` and ``feedforward.png``.
Exit codes: 0 ok, 2 bad input, 3 a limit was violated (refused) or ``--max-error`` exceeded.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from inversion.limits import DEFAULT_MAX_VOLTAGE

from ._common import EXIT_FAILED, EXIT_OK, CLIError, _floats, _load_params

__all__ = ["add_parser", "run", "build_reference", "drive_limits"]


def add_parser(sub):
    p = sub.add_parser("feedforward", help="feedforward voltage of a surrogate, checked on the physics",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("surrogate", help="surrogate model JSON (what 'ipmc fit' writes)")
    p.add_argument("--temperature", type=float, required=True, help="operating temperature [°C]")
    g = p.add_argument_group("reference (in the surrogate's output unit, e.g. mm)")
    g.add_argument("--reference", choices=("sine", "multitone", "steps"), default="sine")
    g.add_argument("--reference-file", help="CSV/NPZ with time_s and a value column (instead of --reference)")
    g.add_argument("--reference-column", help="value column of --reference-file")
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
    g.add_argument("--unit", help="reference unit (default: the surrogate's output unit)")
    c = p.add_argument_group("inversion and limits")
    c.add_argument("--preview", default="auto", help="'auto' (tolerance rule), '4/r0', 'inf' or seconds")
    c.add_argument("--preview-tol", type=float, default=1e-3, help="auto preview: relative truncation error")
    c.add_argument("--max-voltage", type=float, default=None,
                   help=f"largest |V| allowed [V], > 0 (default {DEFAULT_MAX_VOLTAGE:g} V: IPMCs take ~2-3 V)")
    c.add_argument("--no-voltage-limit", action="store_true",
                   help="drop the voltage limit (a virtual plant; never a real strip): said on stderr and in the report")
    c.add_argument("--max-rate", type=float, help="largest |dV/dt| allowed [V/s], > 0")
    c.add_argument("--on-limit", choices=("error", "warn"), default="error",
                   help="refuse (exit 3, nothing written) or warn and continue")
    c.add_argument("--max-error", type=float, help="fail (exit 3) if the predicted tracking error exceeds this [unit]")
    m = p.add_argument_group("physics check")
    m.add_argument("--set", default="seed001_actuator", help="parameter set of the physics (default seed001_actuator)")
    m.add_argument("--params-json", help="calibrated parameter-set JSON (what 'ipmc calibrate' writes)")
    m.add_argument("--param", action="append", metavar="NAME=VALUE", help="override a parameter (SI)")
    m.add_argument("--no-check", action="store_true", help="only write V(t); skip the physics simulation")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=run)
    return p


def build_reference(args, unit: str):
    """The :class:`inversion.references.Reference` the options describe."""
    from inversion import references as R

    lead, tail = args.lead, args.tail
    if args.reference_file:
        fade = 0.0 if args.fade is None else args.fade
        return R.from_file(args.reference_file, column=args.reference_column, fade_in_s=fade,
                           fade_out_s=fade, lead_s=lead, tail_s=tail, unit=unit)
    if args.reference == "steps":
        return R.smoothed_steps(_floats(args.levels, "--levels"), args.hold, args.fs,
                                transition_s=args.transition, lead_s=lead, tail_s=tail, unit=unit)
    amps = _floats(args.amplitude, "--amplitude")
    freqs = _floats(args.frequency, "--frequency")
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


def run(args) -> int:
    from inversion import feedforward
    from inversion.limits import LimitError, Limits
    from physmodel.data.files import atomic_write
    from physmodel.data.units import UNITS, unit_scale

    max_v, max_rate = drive_limits(args)
    model = _surrogate(args.surrogate, args.temperature)
    G = model.at(args.temperature)
    in_unit = model.labels.get("input_unit") or "V"
    out_unit = args.unit or model.labels.get("output_unit") or "mm"
    for u, what in ((in_unit, "input"), (out_unit, "output")):
        if u not in UNITS:
            raise CLIError(f"{args.surrogate}: {what} unit {u!r} is not one of {sorted(UNITS)}")
    if UNITS[in_unit][0] != "voltage" or UNITS[out_unit][0] != "length":
        raise CLIError(f"{args.surrogate}: expected an actuator surrogate (length per voltage), got "
                       f"{out_unit}/{in_unit}")
    ref = build_reference(args, out_unit)
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
    try:
        ff = feedforward(G, ref.t, ref.y, preview=args.preview, preview_tol=args.preview_tol, limits=limits)
    except LimitError as exc:
        print(f"ipmc feedforward: refused: {exc}", file=sys.stderr)
        return EXIT_FAILED
    volts = ff.output * v_scale
    out = Path(args.out)
    cols = {"time_s": ref.t, "voltage_V": volts, f"reference_{out_unit}": ref.y}
    lines = [f"# Feedforward at {args.temperature:g} °C", "",
             f"- surrogate: `{args.surrogate}` ({model!r})",
             f"- reference: {ref.description}; fades {ref.fade_in_s:g}/{ref.fade_out_s:g} s, rest "
             f"{ref.lead_s:g}/{ref.tail_s:g} s, {ref.t.size} samples at {1 / ref.dt:g} Hz",
             f"- preview: {ff.preview_rule} -> {ff.preview_s:.4g} s"
             + (f" (truncation error {ff.preview_choice.relative_error:.2g} of the inverse, tolerance "
                f"{ff.preview_choice.tolerance:g}; the 4/r0 rule would give {ff.auto_preview_s:.4g} s)"
                if ff.preview_choice is not None else "")
             + f"; truncation error {ff.truncation_error * v_scale:.3g} V (bound {ff.truncation_bound * v_scale:.3g} V)",
             f"- peak voltage {ff.limit_report.peak * v_scale:.4g} V, peak rate {ff.limit_report.peak_rate * v_scale:.4g} V/s "
             f"(limits: max_voltage {'**none (--no-voltage-limit)**' if max_v is None else f'{max_v:g} V'}, "
             f"max_rate {'none' if max_rate is None else f'{max_rate:g} V/s'})"]
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
        lines.append(f"- **LIMIT VIOLATED**: {ff.limit_report.message}")
    status = EXIT_OK
    if not args.no_check:
        from physmodel import ActuatorModel
        from physmodel.data.timesim import simulate

        from ..plots_control import feedforward_check

        params = _load_params(args)
        plant = ActuatorModel(params)
        ts = simulate(plant, args.temperature, ref.t, volts)
        y = ts.output / unit_scale(out_unit)
        err = y - ref.y
        e_max = float(np.max(np.abs(err)))
        e_body = float(np.max(np.abs(err[ref.body]))) if np.any(ref.body) else e_max
        cols[f"predicted_tip_{out_unit}"] = y
        lines += [f"- physics: `{params.name}`, {ts.metadata['realization']}",
                  f"- tracking error: max {e_max:.4g} {out_unit} over the record, {e_body:.4g} {out_unit} "
                  f"between the fades (reference peak {float(np.max(np.abs(ref.y))):.4g} {out_unit})"]
        if not args.reference_file and args.reference == "sine":
            f = _floats(args.frequency, "--frequency")[0]
            A = _floats(args.amplitude, "--amplitude")[0]
            P = plant.frequency_response(np.array([f]), [args.temperature])["M"][0, 0, 0] / unit_scale(out_unit) * v_scale
            Gj = complex(G(2j * math.pi * f))
            lines.append(f"- steady-state prediction A |P/G - 1| = {A * abs(P / Gj - 1):.4g} {out_unit} "
                         f"(P: physics, G: surrogate at {f:g} Hz)")
        fig = feedforward_check(ref.t, ref.y, y, volts, out / "feedforward.png", unit=out_unit,
                                max_voltage=max_v, body=ref.body,
                                title=f"{ref.description}, {args.temperature:g} °C, preview {ff.preview_s:.3g} s")
        lines += ["", f"![feedforward]({fig.name})"]
        if args.max_error is not None and e_body > args.max_error:
            lines.append(f"- **tracking error {e_body:.4g} {out_unit} exceeds --max-error {args.max_error:g}**")
            status = EXIT_FAILED
    arr = np.column_stack(list(cols.values()))

    def write_csv(fh):
        fh.write("# ipmc-timeseries 1\n")
        fh.write(f"# surrogate: {args.surrogate}\n# temperature_c: {args.temperature:g}\n")
        fh.write(f"# preview_s: {ff.preview_s:.6g}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt="%.12g")

    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / "voltage.csv", write_csv)
    atomic_write(out / "report.md", lambda fh: fh.write("\n".join(lines) + "\n"))
    if not args.quiet:
        print("\n".join(lines[2:]).replace("**", ""))
        print(f"ipmc feedforward: wrote {out / 'voltage.csv'} and {out / 'report.md'}")
    if status != EXIT_OK:
        print(f"ipmc feedforward: tracking error above --max-error {args.max_error:g}", file=sys.stderr)
    return status
