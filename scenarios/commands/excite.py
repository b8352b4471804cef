"""``ipmc excite`` — design an excitation and write the signal file a DAQ plays.

    ipmc excite multisine --fs 1000 --period 10 --fmin 0.1 --fmax 9 --count 30 --rms 1 --periods 8
                          --transient-periods 2 --out ms.csv
    ipmc excite stepped   --fs 1000 --fmin 0.1 --fmax 9 --count 12 --amplitude 1 --periods 8
                          --min-measure-s 4 --settle-s 3 --out steps.csv
    ipmc excite chirp     --fs 1000 --f0 0.1 --f1 9 --sweep-s 20 --repeats 3 --out chirp.csv

The file is an ``ipmc-timeseries`` record (CSV/NPZ/MAT by extension: ``time_s`` and one
``<channel>_<unit>`` column); its header carries the design (the multisine's lines and phases, the
stepped-sine schedule), so ``ipmc frf --lines FILE`` / ``--plan FILE`` can estimate from a record
of it.  Prints the expected measurement time and the crest factor (peak/RMS of the samples), and
warns (stderr and the file's header) when a voltage drive's peak exceeds the 3 V an IPMC strip takes.
Frequencies [Hz], times [s], amplitudes in ``--unit``.  Exit codes: 0 written, 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ._common import EXIT_OK, CLIError, floats

SUFFIXES = (".csv", ".npz", ".mat")


def _common(p):
    p.add_argument("--fs", type=float, required=True, help="sample rate of the DAQ [Hz]")
    p.add_argument("--channel", help="signal name (default voltage; 'tip_displacement' to drive a sensor)")
    p.add_argument("--unit", help="signal unit (default V, or mm for tip_displacement)")
    p.add_argument("--out", required=True, help="signal file (.csv, .npz or .mat)")
    p.add_argument("--quiet", action="store_true", help="no summary")


def _frequency_options(p, count_help: str):
    p.add_argument("--frequencies", help="comma-separated frequencies [Hz] (instead of --fmin/--fmax/--count)")
    p.add_argument("--fmin", type=float, help="lowest frequency [Hz]")
    p.add_argument("--fmax", type=float, help="highest frequency [Hz]")
    p.add_argument("--count", type=int, help=count_help)


def add_parser(sub):
    p = sub.add_parser("excite", help="design an excitation (multisine, stepped sine, chirp) -> signal file",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    kinds = p.add_subparsers(dest="design", metavar="DESIGN", required=True)
    m = kinds.add_parser("multisine", help="periodic multisine with low-crest-factor phases")
    _common(m)
    m.add_argument("--period", type=float, required=True, help="period [s]; lines are multiples of 1/period")
    _frequency_options(m, "number of log-spaced lines between --fmin and --fmax (rounded to lines of the period)")
    m.add_argument("--amplitude", type=float, default=None, help="cosine amplitude of every line (default 1)")
    m.add_argument("--rms", type=float, help="scale the amplitudes to this RMS instead")
    m.add_argument("--phases", choices=("schroeder", "clipped", "random"), default="schroeder")
    m.add_argument("--seed", type=int, help="seed of random phases")
    m.add_argument("--periods", type=int, default=8, help="measured periods (default 8; σ needs >= 2)")
    m.add_argument("--transient-periods", type=int, default=1, help="leading periods to discard (default 1)")
    s = kinds.add_parser("stepped", help="stepped sine: one frequency per step, settle, whole periods")
    _common(s)
    _frequency_options(s, "number of log-spaced steps between --fmin and --fmax")
    s.add_argument("--amplitude", type=float, default=1.0, help="sine amplitude (default 1)")
    s.add_argument("--periods", type=int, default=8, help="whole periods measured per step (default 8, >= 2)")
    s.add_argument("--min-measure-s", type=float, default=0.0, help="measure each step at least this long [s]")
    s.add_argument("--settle-s", type=float, default=0.0, help="transient allowed per step [s]")
    s.add_argument("--settle-periods", type=float, default=0.0, help="transient allowed per step [periods]")
    c = kinds.add_parser("chirp", help="linear or logarithmic swept sine (repeat it for a periodic sweep)")
    _common(c)
    c.add_argument("--f0", type=float, required=True, help="start frequency [Hz]")
    c.add_argument("--f1", type=float, required=True, help="end frequency [Hz]")
    c.add_argument("--sweep-s", type=float, required=True, help="duration of one sweep [s]")
    c.add_argument("--amplitude", type=float, default=1.0, help="amplitude (default 1)")
    c.add_argument("--method", choices=("linear", "logarithmic"), default="logarithmic")
    c.add_argument("--repeats", type=int, default=1, help="sweeps played back to back (default 1)")
    p.set_defaults(func=run)
    return p


def _frequencies(args, grid: float | None) -> np.ndarray:
    """--frequencies, or --count log-spaced values in [--fmin, --fmax] (rounded to ``grid`` [Hz])."""
    if args.frequencies is not None:
        if any(v is not None for v in (args.fmin, args.fmax, args.count)):
            raise CLIError("--frequencies: give either --frequencies or --fmin/--fmax/--count, not both")
        return np.asarray(floats(args.frequencies, "--frequencies"))
    if args.fmin is None or args.fmax is None or args.count is None:
        raise CLIError("give --frequencies, or all of --fmin, --fmax and --count")
    if not (0 < args.fmin <= args.fmax) or not np.isfinite(args.fmax):
        raise CLIError(f"need 0 < --fmin <= --fmax, got --fmin {args.fmin} and --fmax {args.fmax}")
    if args.count < 1:
        raise CLIError(f"--count must be >= 1, got {args.count}")
    f = np.geomspace(args.fmin, args.fmax, args.count)
    if grid is not None:
        f = np.unique(np.maximum(np.round(f / grid), 1)) * grid
    return f


#: Library argument names → the options that set them (error messages name the option).
OPTIONS = {"frequencies_hz": "--frequencies", "fs_hz": "--fs", "period_s": "--period", "f0_hz": "--f0",
           "f1_hz": "--f1", "sweep_s": "--sweep-s", "transient_periods": "--transient-periods",
           "min_measure_s": "--min-measure-s", "settle_s": "--settle-s", "settle_periods": "--settle-periods",
           "repeats": "--repeats", "amplitude": "--amplitude", "rms": "--rms", "seed": "--seed",
           "iterations": "--iterations", "periods": "--periods"}


def as_options(exc: Exception, options: dict, prefix: str = "") -> CLIError:
    """``exc`` re-worded with the command-line options in place of the library's argument names."""
    import re

    text = prefix + str(exc)
    for name in sorted(options, key=len, reverse=True):
        text = re.sub(rf"(?<![\w-]){name}(?![\w])", options[name], text)
    return CLIError(text)


def _channel(args) -> tuple[str, str]:
    ch = args.channel or "voltage"
    unit = args.unit or ("mm" if ch == "tip_displacement" else "V")
    return ch, unit


def run(args) -> int:
    from physmodel.data.excitation import crest_factor
    from physmodel.data.timerecord import split_column
    from physmodel.errors import IPMCError

    out = Path(args.out)
    if out.suffix.lower() not in SUFFIXES:
        raise CLIError(f"--out {out}: use a .csv, .npz or .mat file name")
    ch, unit = _channel(args)
    try:
        split_column(f"{ch}_{unit}")
    except IPMCError as exc:                  # DataFormatError: name the options
        raise CLIError(f"--channel {ch!r} / --unit {unit!r}: {exc}") from None

    try:
        rec, what = _design(args, ch, unit)
    except CLIError:
        raise
    except IPMCError as exc:
        raise as_options(exc, OPTIONS) from None
    u = rec.channels[ch]
    cf = crest_factor(u)
    rec.metadata["crest_factor"] = f"{cf:.4f}"
    warning = drive_warning(args, u, unit, cf)
    if warning:
        rec.metadata["drive_warning"] = warning
    rec.save(out)
    if warning:
        print(f"ipmc excite: warning: {warning}", file=sys.stderr)
    if not args.quiet:
        print(f"wrote {out}: {what}")
        print(f"  {u.size} samples at {args.fs:g} Hz; expected duration {float(rec.metadata['expected_duration_s']):g} s; "
              f"crest factor {cf:.3f} (peak {np.max(np.abs(u)):.4g} {unit}, RMS {np.sqrt(np.mean(u**2)):.4g} {unit})")
    return EXIT_OK


def drive_warning(args, u: np.ndarray, unit: str, cf: float) -> str:
    """A sentence when a voltage drive's peak exceeds :data:`inversion.limits.DEFAULT_MAX_VOLTAGE`
    (what an IPMC strip takes), naming the option that lowers it; "" otherwise (or for a
    displacement channel)."""
    import math

    from inversion.limits import DEFAULT_MAX_VOLTAGE
    from physmodel.data.units import UNITS

    if UNITS.get(unit, ("",))[0] != "voltage":
        return ""
    scale = UNITS[unit][1]
    peak_v = float(np.max(np.abs(u))) * scale
    if not peak_v > DEFAULT_MAX_VOLTAGE:
        return ""
    shrink = DEFAULT_MAX_VOLTAGE / peak_v

    def below(x: float) -> str:        # x rounded DOWN to 3 significant figures
        k = 10.0 ** (math.floor(math.log10(abs(x))) - 2)
        return f"{math.floor(x / k) * k:.6g}"

    if args.design == "multisine":
        opt = f"--rms {below(args.rms * shrink)}" if args.rms is not None else \
            f"--amplitude {below((1.0 if args.amplitude is None else args.amplitude) * shrink)}"
        how = f"lower it with {opt} (same crest factor {cf:.3g})"
        if args.phases != "clipped":
            how += (f", or lower the crest factor with --phases clipped (iterative clipping of the "
                    f"{args.phases} phases; keep the RMS, check the new peak)")
    else:
        how = f"lower it with --amplitude {below(args.amplitude * shrink)} (a sine's crest factor is fixed at 1.41)"
    return (f"the drive's peak {peak_v:.4g} V exceeds the {DEFAULT_MAX_VOLTAGE:g} V an IPMC strip takes "
            f"(the default limit of ipmc feedforward and inversion.feedforward); {how}")


#: Bytes per record sample while a design is generated and saved (time, drive, file buffer, FFT work).
BYTES_PER_SAMPLE = 48


def _bound_samples(n, option: str) -> None:
    """Refuse (exit 2) a record longer than this machine can hold, before it is generated."""
    from ._common import bound_count

    if np.isfinite(n) and n > 0:
        bound_count(min(float(n), 2.0**62), option, BYTES_PER_SAMPLE, what="samples")


def _design(args, ch: str, unit: str):
    from physmodel.data.excitation import chirp, multisine, stepped_sine_plan

    note = ""
    if args.design == "multisine":
        if args.period is None or not (np.isfinite(args.period) and args.period > 0):
            raise CLIError(f"--period must be a finite number > 0 [s], got {args.period}")
        f = _frequencies(args, 1.0 / args.period)
        if args.count is not None and f.size < args.count:
            note = f" ({args.count - f.size} requested lines coincided on the 1/period = {1 / args.period:g} Hz grid)"
        if args.amplitude is not None and args.rms is not None:
            raise CLIError("--amplitude and --rms: give one of them")
        _bound_samples(args.period * args.fs * (max(args.periods, 0) + max(args.transient_periods, 0)),
                       "--period × --fs × (--periods + --transient-periods)")
        ms = multisine(f, args.fs, args.period, amplitude=1.0 if args.amplitude is None else args.amplitude,
                       rms=args.rms, phases=args.phases, seed=args.seed, channel=ch, unit=unit)
        rec = ms.record(args.periods, args.transient_periods)
        what = (f"multisine: {f.size} lines {f[0]:g}-{f[-1]:g} Hz{note}, period {ms.period_s:g} s, "
                f"{args.transient_periods} transient + {args.periods} measured periods, {args.phases} phases")
    elif args.design == "stepped":
        f = _frequencies(args, None)
        plan = stepped_sine_plan(f, args.fs, amplitude=args.amplitude, periods=args.periods,
                                 min_measure_s=args.min_measure_s, settle_s=args.settle_s,
                                 settle_periods=args.settle_periods, channel=ch, unit=unit)
        _bound_samples(plan.n_samples, "the stepped-sine record (--fs × the steps' --periods and --settle-s)")
        rec = plan.record()
        what = (f"stepped sine: {f.size} steps {f.min():g}-{f.max():g} Hz, {int(plan.periods.min())}-"
                f"{int(plan.periods.max())} periods per step, settle {plan.settle_s.min():g}-{plan.settle_s.max():g} s")
    else:
        if np.isfinite(args.sweep_s) and np.isfinite(args.fs):
            _bound_samples(args.sweep_s * args.fs * max(args.repeats, 1), "--sweep-s × --fs × --repeats")
        rec = chirp(args.f0, args.f1, args.sweep_s, args.fs, amplitude=args.amplitude, method=args.method,
                    repeats=args.repeats, channel=ch, unit=unit)
        what = f"{args.method} chirp {args.f0:g}-{args.f1:g} Hz, {args.sweep_s:g} s x {args.repeats}"
    return rec, what
