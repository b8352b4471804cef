"""``ipmc frf`` — frequency responses with per-line σ from time records → a sweep file.

    ipmc frf RECORD [RECORD ...] --out sweep.csv --input voltage --output tip_displacement
             [--output current] [--method auto|h1|h2|stepped] [--temperature T ...]
             [--nperseg N] [--noverlap N] [--window hann] [--discard-s S]
             [--lines SIGNAL | --frequencies F1,F2,...] [--plan SIGNAL]
             [--settle-s S] [--settle-periods P] [--periods P] [--max-clipped-fraction F]
             [--min-coherence G|auto] [--max-std-db D] [--band LO HI] [--reciprocal] [--plot fig.png] [--quiet]

One record per temperature (``--temperature``, one value per record; default each record's
``temperature_c`` header).  Channels are named as in the record (``voltage`` or the column
``voltage_V``); the sweep is in the record's units.  Several ``--output`` channels give one sweep
file per channel, ``<out stem>_<channel><suffix>``.

Methods (physmodel.estimation.frf / .periodic / .stepped):

* ``auto`` (default): the excitation is read from the input channel
  (physmodel.estimation.excitation_detection).  A *periodic* input (its period found from the
  record and checked period by period) is estimated by H1 at its excited lines only, over whole
  periods, the leading transient periods found and discarded, σ from the scatter between periods;
  a *stepped sine* by per-period sine fits on each detected step (its transient found the same
  way); anything else (*random*) by Welch H1 (Hann, 50 % overlap) with a segment long enough to
  resolve ``--band``.  The summary, and the sweep's metadata (``excitation``, ``method``), say
  what was detected and used.  ``--discard-s`` discards a leading time instead of finding it.
* ``h1`` / ``h2``: the same with that ratio; with ``--nperseg``, ``--noverlap``, ``--window`` or
  ``--frequencies`` (with any method but stepped) the estimate is plain Welch-averaged spectra,
  σ from the coherence.
* ``--lines SIGNAL`` takes a multisine's lines and period from its signal file (``ipmc excite
  multisine``); a record whose own header holds the multisine uses it without ``--lines``.  A
  record whose input is detected periodic with that period is estimated by the periodic
  estimator at exactly those lines (H1/H2 over whole periods, σ from the period-to-period
  scatter; discarded: ``--discard-s`` if given, else the design's transient periods or the
  transient found from the period scatter, whichever is longer); any other record (a random
  input) by Welch with one-period boxcar segments at the lines, as do ``--nperseg``,
  ``--noverlap`` or ``--window`` given with it.  stderr says per record which estimator was used.
* ``stepped``: per-period sine fits after each step's transient, σ from the scatter between
  periods; the schedule comes from ``--plan SIGNAL`` (``ipmc excite stepped``), the record's own
  header, or else is detected from the input; ``--settle-s``/``--settle-periods``/``--periods``
  override the plan's.

Checks on every record: a channel with samples held at a rail (clipping) is refused when more than
``--max-clipped-fraction`` (default 0.01) of its samples are clipped, and warned about below that.
``--min-coherence`` (default ``auto``: the coherence an output unrelated to the input exceeds
with probability 1 %, from the number of averages; for a Welch estimate 1 % for any of its lines), ``--max-std-db`` and ``--band`` drop lines;
more than half of a channel's lines below the coherence threshold is a low-coherence warning
(noise only? wrong channel?).  Warnings go to stderr and into the sweep's ``warnings`` metadata.
``--reciprocal`` writes input/output (e.g. impedance V/A from a current channel).  ``--plot``
draws magnitude and phase with their ±2σ bands and the coherence.  Exit codes: 0 written (with
any warnings on stderr), 2 bad input (too short, clipped, no line left).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError

from ._columns import add_record_options, read_record_mapped
from ._common import EXIT_OK, CLIError, check_celsius, floats, refuse_overwriting_inputs
from .excite import as_options

SUFFIXES = (".csv", ".npz", ".mat")
#: Estimator argument names → the options that set them (error messages name the option).
OPTIONS = {"frequencies_hz": "--frequencies", "nperseg": "--nperseg", "noverlap": "--noverlap", "window": "--window",
           "discard_s": "--discard-s", "settle_s": "--settle-s", "settle_periods": "--settle-periods",
           "periods": "--periods", "max_std_db": "--max-std-db", "band_hz": "--band", "min_coherence": "--min-coherence",
           "max_clipped_fraction": "--max-clipped-fraction"}
#: Options that ask for a plain Welch estimate.
WELCH_OPTIONS = ("nperseg", "noverlap", "window", "frequencies")


def add_parser(sub):
    p = sub.add_parser("frf", help="estimate frequency responses with per-line σ from time records -> sweep",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("records", nargs="+", metavar="RECORD", help="time records (.csv, .npz, .mat; ipmc-timeseries)")
    p.add_argument("--out", required=True, help="sweep file (.csv, .npz or .mat)")
    p.add_argument("--input", required=True, help="input (reference) channel, e.g. voltage")
    p.add_argument("--output", action="append", required=True, help="output channel (repeatable)")
    p.add_argument("--method", choices=("auto", "h1", "h2", "stepped"), default="auto",
                   help="estimator (default auto: read the excitation from the input channel)")
    p.add_argument("--temperature", action="append",
                   help="bath temperature [°C], one per record (repeatable or comma-separated); "
                        "default each record's temperature_c header")
    g = p.add_argument_group("Welch (h1, h2)")
    g.add_argument("--nperseg", type=int, help="segment length [samples]")
    g.add_argument("--noverlap", type=int, help="segment overlap [samples] (default nperseg/2)")
    g.add_argument("--window", help="window name (scipy.signal.get_window; default hann)")
    g.add_argument("--discard-s", type=float, help="leading transient not used [s] (default 0)")
    g.add_argument("--lines", metavar="SIGNAL", help="multisine signal file: use its lines and period")
    g.add_argument("--frequencies", help="comma-separated lines to keep [Hz] (bins of the segment)")
    s = p.add_argument_group("stepped sine")
    s.add_argument("--plan", metavar="SIGNAL", help="stepped-sine signal file: its schedule")
    s.add_argument("--settle-s", type=float, help="transient discarded per step [s] (overrides the plan)")
    s.add_argument("--settle-periods", type=float, help="transient discarded per step [periods]")
    s.add_argument("--periods", type=int, help="whole periods used per step (default: all whole periods)")
    k = p.add_argument_group("lines kept")
    k.add_argument("--min-coherence", default="auto",
                   help="drop lines with coherence below this (default auto: the 1 %% level of an unrelated output; Welch: for any of its lines)")
    k.add_argument("--max-clipped-fraction", type=float,
                   help="refuse a channel with more clipped samples than this fraction (default 0.01; 1 only warns)")
    k.add_argument("--max-std-db", type=float, help="drop lines whose magnitude σ exceeds this [dB]")
    k.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), help="keep lines in [LO, HI] Hz")
    p.add_argument("--reciprocal", action="store_true", help="write input/output instead of output/input")
    p.add_argument("--plot", help="figure of the estimate with ±2σ bands and coherence (PNG)")
    p.add_argument("--quiet", action="store_true", help="no summary")
    add_record_options(p)
    p.set_defaults(func=run)
    return p


# ---------------------------------------------------------------------------- inputs
def _read(path: str, option: str):
    from physmodel.data.timerecord import read_record

    if not Path(path).exists():
        raise CLIError(f"{option} {path}: no such file")
    return read_record(path)


def _temperatures(args, records) -> list[float]:
    if args.temperature:
        temps = [v for item in args.temperature for v in floats(item, "--temperature")]
        if len(temps) != len(records):
            raise CLIError(f"--temperature: {len(temps)} value(s) for {len(records)} record(s); give one per record")
        check_celsius(temps, "--temperature")
        return temps
    temps = []
    for path, rec in zip(args.records, records):
        T = rec.temperature_c()
        if T is None:
            raise CLIError(f"{path}: no 'temperature_c' header; give --temperature (one per record)")
        check_celsius(T, f"{path}: header temperature_c")
        temps.append(T)
    return temps


def _multisine(args, records):
    """The multisine design from --lines, or from the records' own header (None if neither)."""
    from physmodel.data.excitation import Multisine

    if args.lines:
        src, where = _read(args.lines, "--lines").metadata, f"--lines {args.lines}"
    elif "multisine" in records[0].metadata and args.frequencies is None:
        src, where = records[0].metadata, f"{args.records[0]}"
    else:
        return None
    if "multisine" not in src:
        raise CLIError(f"{where}: no 'multisine' header (write the signal with 'ipmc excite multisine')")
    try:
        ms = Multisine.from_dict(json.loads(src["multisine"]))
        tp = int(src.get("transient_periods", 1))
    except (ValueError, KeyError, TypeError) as exc:
        raise CLIError(f"{where}: malformed 'multisine' header ({exc})") from None
    return ms, tp


def _plan(args, records):
    from physmodel.data.excitation import SteppedSinePlan

    if args.plan:
        rec, where = _read(args.plan, "--plan"), f"--plan {args.plan}"
    elif "stepped_sine_plan" in records[0].metadata:
        rec, where = records[0], args.records[0]
    else:
        raise CLIError("--plan: a stepped-sine estimate needs the schedule; give the signal file written by "
                       "'ipmc excite stepped' (or records whose header holds 'stepped_sine_plan')")
    try:
        return SteppedSinePlan.from_record(rec)
    except IPMCError as exc:
        raise CLIError(f"{where}: {exc}") from None


def _estimator_kwargs(args, records) -> tuple[dict, str]:
    """Keyword arguments of estimate_record and a description of where they came from."""
    if args.method == "stepped":
        bad = [o for o in ("nperseg", "noverlap", "window", "discard_s", "lines", "frequencies")
               if getattr(args, o) is not None]
        if bad:
            raise CLIError(f"--{bad[0].replace('_', '-')} applies to h1/h2, not to --method stepped")
        if not args.plan and "stepped_sine_plan" not in records[0].metadata:
            if any(getattr(args, k) is not None for k in ("settle_s", "settle_periods", "periods")):
                raise CLIError("--settle-s/--settle-periods/--periods override a plan; give it with --plan SIGNAL")
            return {"method": "auto", "excitation": "stepped_sine", "band_hz": _band(args),
                    "max_clipped_fraction": args.max_clipped_fraction}, "stepped-sine schedule detected from the input"
        plan = _plan(args, records)
        over = {k: getattr(args, k) for k in ("settle_s", "settle_periods", "periods") if getattr(args, k) is not None}
        if not over:
            return {"method": "stepped_sine", "plan": plan}, f"plan of {plan.frequency_hz.size} steps"
        return ({"method": "stepped_sine", "plan": None, "_plan": plan, **over},
                f"plan of {plan.frequency_hz.size} steps, overrides {over}")
    bad = [o for o in ("plan", "settle_s", "settle_periods", "periods") if getattr(args, o) is not None]
    if bad:
        raise CLIError(f"--{bad[0].replace('_', '-')} applies to --method stepped, not to {args.method}")
    ratio = "h1" if args.method == "auto" else args.method
    found = _multisine(args, records)
    if found is None and all(getattr(args, o) is None for o in WELCH_OPTIONS):
        kw = {"method": "auto", "estimator": ratio, "band_hz": _band(args), "discard_s": args.discard_s,
              "max_clipped_fraction": args.max_clipped_fraction}
        return kw, "excitation read from the input"
    kw = {"method": ratio}
    how = "Welch"
    if found is not None:
        ms, tp = found
        for rec, path in zip(records, args.records):
            if abs(rec.fs - ms.fs_hz) > 1e-9 * ms.fs_hz:
                raise CLIError(f"{path}: sampled at {rec.fs:g} Hz but the multisine was designed at {ms.fs_hz:g} Hz")
        how = f"multisine lines ({ms.lines.size} lines, period {ms.period_s:g} s, {tp} transient period(s))"
        if all(getattr(args, o) is None for o in ("nperseg", "noverlap", "window")):
            # periodic or not is read per record (_lines_estimate); Welch only for a record that is not
            return {"method": "lines", "estimator": ratio, "multisine": ms, "transient_periods": tp,
                    "where": f"--lines {args.lines}" if args.lines else "the record's multisine header"}, how
        kw.update(nperseg=ms.n_samples, noverlap=0, window="boxcar", discard_s=tp * ms.period_s,
                  frequencies_hz=ms.frequency_hz)
    elif args.frequencies is not None:
        kw["frequencies_hz"] = floats(args.frequencies, "--frequencies")
    for opt in ("nperseg", "noverlap", "window", "discard_s"):
        v = getattr(args, opt)
        if v is not None:
            kw[opt] = v
    return kw, how


def _band(args):
    return tuple(args.band) if args.band else None


def _checked(est, rec, args):
    """``est`` with the clipping and low-coherence warnings the auto path gives (clipping above
    ``--max-clipped-fraction`` refused)."""
    from dataclasses import replace

    from physmodel.estimation.clipping import check_clipping
    from physmodel.estimation.frf_estimate import low_coherence_warning

    inp = rec.resolve(args.input)
    notes = check_clipping({inp: rec.channels[inp], **{rec.resolve(o): rec.channel(o) for o in args.output}},
                           args.max_clipped_fraction)
    low = low_coherence_warning(est)
    return replace(est, warnings=tuple(notes + ([low] if low else [])))


def _lines_estimate(rec, path: str, args, kw: dict):
    """The estimate at a multisine's lines (``--lines`` or the record's header).

    A record whose input the detector finds periodic with the multisine's period (or a divisor of
    it) is estimated by :func:`~physmodel.estimation.periodic.periodic_frf` at those lines over
    whole periods, σ from the scatter between periods; the leading periods discarded are
    ``--discard-s`` when given, else the design's transient periods or the transient found from the
    period scatter, whichever is longer.  Any other record (an input that is not periodic: noise on
    the drive, another clock) is estimated by Welch with one-period boxcar segments at the lines.
    Which one was used is said on stderr."""
    import math

    from physmodel.estimation.excitation_detection import detect_excitation
    from physmodel.estimation.frf import estimate_record
    from physmodel.estimation.periodic import periodic_frf

    ms, tp, ratio = kw["multisine"], kw["transient_periods"], kw["estimator"]
    N = ms.n_samples
    inp, outs = rec.resolve(args.input), [rec.resolve(o) for o in args.output]
    u = rec.channels[inp]
    exc = detect_excitation(None, u, fs_hz=rec.fs)
    what = f"{ms.lines.size} lines of {kw['where']}"
    if exc.kind == "periodic" and exc.period_samples and N % exc.period_samples == 0:
        common = dict(estimator=ratio, input_name=inp, input_unit=rec.units[inp], output_names=outs,
                      output_units=[rec.units[o] for o in outs])
        ys = [rec.channels[o] for o in outs]

        def whole(seconds):                      # leading periods of the end-aligned grid in `seconds`
            return max(0, int(math.ceil((seconds * rec.fs - u.size % N) / N - 1e-9)))

        if args.discard_s is not None:
            est = periodic_frf(rec.t, u, ys, N, ms.lines, discard_periods=whole(args.discard_s), **common)
            why = f"--discard-s {args.discard_s:g}"
        else:
            est = periodic_frf(rec.t, u, ys, N, ms.lines, discard_periods=None, **common)
            design = whole(tp * ms.period_s)
            why = "found from the period scatter"
            if est.settings["transient_periods"] < design:
                est = periodic_frf(rec.t, u, ys, N, ms.lines, discard_periods=design, **common)
                why = f"the design's {tp} transient period(s)"
        st = est.settings
        note = (f"periodic {ratio.upper()} at the {what} over {st['periods_used']} whole periods of {N} samples "
                f"({st['transient_periods']} leading period(s) discarded: {why}), σ from the period-to-period "
                f"scatter; input: {exc.describe()}")
    else:
        est = estimate_record(rec, args.input, args.output, method=ratio, nperseg=N, noverlap=0, window="boxcar",
                              discard_s=args.discard_s if args.discard_s is not None else tp * ms.period_s,
                              frequencies_hz=ms.frequency_hz)
        note = (f"Welch {ratio.upper()} (boxcar segments of one period, {N} samples) at the {what}, σ from the "
                f"coherence: the input is not periodic with the multisine's period ({exc.describe()})")
    print(f"ipmc frf: {path}: estimator: {note}", file=sys.stderr)
    from dataclasses import replace

    return replace(est, settings={**est.settings, "excitation": exc.describe(), "estimator_note": note})


def _estimate(rec, path: str, args, kw: dict):
    """The estimate of one record, with the warnings of every method (clipping, low coherence)."""
    from physmodel.estimation.frf import estimate_record
    from physmodel.estimation.frf_estimate import FRFWarning

    kw = dict(kw)
    plan = kw.pop("_plan", None)
    if plan is not None:                    # a plan with overridden settle/periods: explicit schedule
        t0 = float(rec.t[0])
        kw.pop("plan")
        kw.update(frequencies_hz=plan.frequency_hz, step_start_s=plan.step_start_s + t0,
                  step_stop_s=plan.step_stop_s + t0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FRFWarning)        # printed below from est.warnings
            est = _lines_estimate(rec, path, args, kw) if kw["method"] == "lines" else \
                estimate_record(rec, args.input, args.output, **kw)
        if kw["method"] != "auto":           # the auto path checks these itself
            est = _checked(est, rec, args)
    except IPMCError as exc:
        text = str(exc)
        if kw.get("excitation") == "stepped_sine":
            text += "; give the schedule with --plan SIGNAL (written by 'ipmc excite stepped')"
        raise as_options(IPMCError(text), OPTIONS, f"{path}: ") from None
    return est


def _out_paths(out: Path, outputs: list[str]) -> list[Path]:
    if len(outputs) == 1:
        return [out]
    return [out.with_name(f"{out.stem}_{o}{out.suffix}") for o in outputs]


def _min_coherence(text):
    if text is None or str(text).strip().lower() == "auto":
        return "auto"
    try:
        v = float(text)
    except ValueError:
        raise CLIError(f"--min-coherence {text!r}: expected a number in [0, 1] or 'auto'") from None
    if not 0 <= v <= 1:
        raise CLIError(f"--min-coherence {text}: must lie in [0, 1]")
    return v


# ---------------------------------------------------------------------------- run
def run(args) -> int:
    from physmodel.data.files import write_sweep
    from physmodel.data.sweep import merge_sweeps

    out = Path(args.out)
    if out.suffix.lower() not in SUFFIXES:
        raise CLIError(f"--out {out}: use a .csv, .npz or .mat file name")
    refuse_overwriting_inputs({"--out": out, "--plot": args.plot},
                              {**{f"RECORD {k + 1}": r for k, r in enumerate(args.records)}, "--lines": args.lines})
    if args.plot and Path(args.plot).suffix.lower() not in (".png", ".pdf", ".svg"):
        raise CLIError(f"--plot {args.plot}: use a .png, .pdf or .svg file name")
    if len(set(args.output)) != len(args.output):
        raise CLIError(f"--output repeats a channel: {args.output}")
    if args.band is not None and not (0 <= args.band[0] <= args.band[1]):
        raise CLIError(f"--band {args.band[0]:g} {args.band[1]:g}: need 0 <= LO <= HI [Hz]")
    args.min_coherence = _min_coherence(args.min_coherence)
    if args.max_clipped_fraction is not None and not 0 <= args.max_clipped_fraction <= 1:
        raise CLIError(f"--max-clipped-fraction {args.max_clipped_fraction}: must lie in [0, 1]")
    if args.max_std_db is not None and not args.max_std_db > 0:
        raise CLIError(f"--max-std-db {args.max_std_db}: must be > 0 [dB]")
    records = [read_record_mapped(p, args, {"input": args.input, "output": args.output}) for p in args.records]
    temps = _temperatures(args, records)
    if len(set(temps)) != len(temps):
        raise CLIError(f"--temperature: records at the same temperature {temps}; one record per temperature")
    for rec, path in zip(records, args.records):
        for opt, names in (("--input", [args.input]), ("--output", args.output)):
            for nm in names:
                try:
                    rec.resolve(nm)
                except IPMCError as exc:
                    raise CLIError(f"{path}: {opt} {nm}: {exc}") from None
    kw, how = _estimator_kwargs(args, records)
    ests = [_estimate(rec, p, args, kw) for rec, p in zip(records, args.records)]
    keep = {"min_coherence": args.min_coherence, "band_hz": tuple(args.band) if args.band else None,
                "max_std_db": args.max_std_db}
    written, lines = [], []
    jobs: list[tuple[Callable[[Path], object], Path]] = []      # (write to a path, final path)
    for o, path in zip(args.output, _out_paths(out, args.output)):
        sweeps, kept = [], []
        for T, e, src in zip(temps, ests, args.records):
            c = e.channel(o if o in e.output_names else e.output_names[args.output.index(o)])
            c = c.reciprocal() if args.reciprocal else c
            try:
                sw = c.to_sweep(T, **keep, metadata={"record": Path(src).name})
            except IPMCError as exc:
                why = "; ".join(c.warnings)
                raise as_options(IPMCError(f"{exc}{' (' + why + ')' if why else ''}"), OPTIONS,
                                 f"{src} ({o}): ") from None
            sweeps.append(sw)
            kept.append((c, T, np.isin(c.frequency_hz, sw.frequency_hz)))
            lines.append(f"  {Path(src).name} at {T:g} °C, {sw.output_name}/{sw.input_name}: {sw.frequency_hz.size} "
                         f"of {c.frequency_hz.size} lines kept, median σ {np.median(sw.magnitude_std_db):.3g} dB / "
                         f"{np.median(sw.phase_std_deg):.3g}°")
        sweep = merge_sweeps(sweeps)
        jobs.append((partial(write_sweep, sweep), path))
        written.append(path)
        if args.plot:
            from .. import plots

            ppath = Path(args.plot)
            if len(args.output) > 1:
                ppath = ppath.with_name(f"{ppath.stem}_{o}{ppath.suffix}")
            title = f"{sweep.output_name} [{sweep.output_unit}] / {sweep.input_name} [{sweep.input_unit}], {args.method}"
            jobs.append((partial(plots.frf_estimate, kept, title=title), ppath))
            written.append(ppath)
    from physmodel.data.results import files_together

    with files_together([p for _, p in jobs]) as tmps:         # every sweep and figure, or none
        for (write, _), tmp in zip(jobs, tmps):
            write(tmp)
    for e, src in zip(ests, args.records):
        for w in e.warnings:
            print(f"warning: {src}: {w}", file=sys.stderr)
    if not args.quiet:
        st = ests[0].settings
        print(f"{ests[0].method} from {len(records)} record(s), {how}; settings: "
              + ", ".join(f"{k}={v}" for k, v in st.items() if k != "excitation"))
        for e, src in zip(ests, args.records):
            if "excitation" in e.settings:
                print(f"  {Path(src).name}: {e.settings['excitation']}")
        print("\n".join(lines))
        print("wrote " + ", ".join(str(p) for p in written))
    return EXIT_OK
