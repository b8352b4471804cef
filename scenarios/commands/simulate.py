"""``ipmc simulate``: a time-domain virtual experiment (sine, step, free release, or any recorded input).

``--input FILE`` drives the model with a recorded input: a time record (CSV with ``#`` header
lines then a header row, NPZ or MAT, read by :func:`physmodel.data.timerecord.read_record`) as
``ipmc simulate`` / ``ipmc feedforward`` write them, with a ``time_s`` column (uniform) and
columns named ``<name>_<unit>`` (``voltage_V`` for an actuator, ``tip_displacement_m``/``_mm`` for
a sensor; the unit suffix converts it to SI).
``--input-column`` picks the column (default: ``voltage_*`` for an actuator,
``tip_displacement_*`` for a sensor, else the first non-time column).
"""

from __future__ import annotations

from pathlib import Path

from ._common import (
    EXIT_OK,
    CLIError,
    add_model_args,
    check_celsius,
    check_plot_path,
    floats,
    load_physics,
    model_metadata,
    refuse_overwriting_inputs,
    warn_verdict,
)


def add_parser(sub):
    p = sub.add_parser("simulate", help="time-domain virtual experiment",
                       description="Sine, step or free-release experiment with the exact model (via a verified "
                                   "rational realisation); SI units in the output file.")
    add_model_args(p)
    p.add_argument("--experiment", choices=("sine", "step", "release"), default=None,
                   help="built-in excitation (default sine); not with --input")
    p.add_argument("--input", dest="input_file", metavar="FILE",
                   help="drive the model with a recorded input (time-record CSV/NPZ/MAT with time_s and "
                        "e.g. voltage_V); see the module help")
    p.add_argument("--input-column", help="column of --input to use (default: voltage_* / tip_displacement_*)")
    p.add_argument("--temperature", type=float, default=25.0, help="bath temperature [°C]")
    p.add_argument("--amplitude", type=float, help="input amplitude: V (actuator, default 1) or m (sensor, default 1e-3)")
    p.add_argument("--frequency", type=float, default=2.0, help="sine frequency [Hz]")
    p.add_argument("--duration", type=float, default=2.0, help="record length [s]")
    p.add_argument("--fs", type=float, default=1000.0, help="sampling rate [Hz]")
    p.add_argument("--w0", type=float, default=1e-3, help="release: initial tip displacement [m]")
    p.add_argument("--t-release", type=float, default=0.2, help="release instant [s]")
    p.add_argument("--noise-rms", type=float, default=0.0, help="white noise on the recorded output (SI)")
    p.add_argument("--input-noise-rms", type=float, default=0.0, help="white noise on the recorded input (SI)")
    p.add_argument("--chain", help="sensor: transimpedance chain R1,R2,R3 [ohm] (seed 000: 470e3,10e3,R3)")
    p.add_argument("--seed", type=int, help="noise seed (required with noise)")
    p.add_argument("--out", required=True, help="output file (.csv, .npz or .mat)")
    p.add_argument("--plot", help="also write a plot of the traces (PNG)")
    p.set_defaults(func=run)

def run(args) -> int:
    from physmodel import TransimpedanceChain
    from physmodel.data.timesim import free_release, simulate, sine, step

    out = Path(args.out)
    if out.suffix.lower() not in (".csv", ".npz", ".mat"):
        raise CLIError(f"--out {out}: use a .csv, .npz or .mat file name")
    refuse_overwriting_inputs({"--out": out, "--plot": args.plot},
                              {"--input": args.input_file, "--model": getattr(args, "model", None),
                               "--set": getattr(args, "set", None), "--params-json": getattr(args, "params_json", None)})
    if args.plot:
        check_plot_path(args.plot)
    check_celsius(args.temperature, "--temperature")
    mf, overridden = load_physics(args, "ipmc simulate")
    warn_verdict(mf, "ipmc simulate")
    model = mf.model()
    args.model_metadata = model_metadata(mf, overridden)
    kw = dict(output_noise_rms=args.noise_rms, input_noise_rms=args.input_noise_rms, seed=args.seed)
    if args.chain:
        if args.kind != "sensor":
            raise CLIError("--chain applies to the sensor's current output (use --kind sensor)")
        r = floats(args.chain, "--chain")
        if len(r) != 3:
            raise CLIError(f"--chain expects R1,R2,R3 in ohm, got {args.chain!r}")
        kw["chain"] = TransimpedanceChain(*r)
    if args.input_file:
        if args.experiment is not None:
            raise CLIError("give either --input FILE or --experiment, not both")
        t, u, col = read_input(args.input_file, args.kind, args.input_column)
        ts = simulate(model, args.temperature, t, u, **kw)
        ts.metadata["input_file"] = f"{args.input_file}:{col}"
        return _finish(args, ts, model, f"recorded input {Path(args.input_file).name}", out)
    if args.experiment is None:
        args.experiment = "sine"
    amp = args.amplitude
    if amp is None:
        amp = 1.0 if args.kind == "actuator" else 1e-3
    if args.experiment == "sine":
        ts = sine(model, args.temperature, amp, args.frequency, args.duration, args.fs, **kw)
    elif args.experiment == "step":
        ts = step(model, args.temperature, amp, args.duration, args.fs, **kw)
    else:
        if args.kind == "actuator":
            kw = {}
        ts = free_release(model, args.temperature, args.w0, args.t_release, args.duration, args.fs, **kw)
    return _finish(args, ts, model, args.experiment, out)


def _finish(args, ts, model, what: str, out: Path) -> int:
    ts.metadata.update(getattr(args, "model_metadata", {}))
    from physmodel.data.results import files_together

    with files_together([out, *([args.plot] if args.plot else [])]) as tmp:     # both or neither
        ts.save(tmp[0])
        if args.plot:
            from ..plots import traces

            traces(ts, tmp[1], title=f"{what}, {model.params[0].name}, {args.temperature:g} °C")
    if not args.quiet:
        print(f"wrote {out} ({ts.t.size} samples; {ts.metadata.get('realization', 'free response of the first mode')})")
    return EXIT_OK


def read_input(path, kind: str, column: str | None = None):
    """``(t [s], u [SI], column)`` from a recorded-input file (see the module help).

    The column's unit suffix (``voltage_V``, ``voltage_mV``, ``tip_displacement_mm`` ...) converts
    it to SI; an actuator needs a voltage, a sensor a displacement.
    """
    from physmodel.data.timerecord import read_record
    from physmodel.data.timesim import check_uniform_time
    from physmodel.data.units import UNITS

    cols = read_record(path).columns()
    want = ("voltage", "V", "voltage") if kind == "actuator" else ("tip_displacement", "m", "length")
    names = [c for c in cols if c != "time_s"]
    if column is None:
        pick = [c for c in names if c.rsplit("_", 1)[0] == want[0]]
        if not pick:
            raise CLIError(f"--input {path}: no {want[0]}_<unit> column for a {kind} (found {names}); "
                           "name it with --input-column")
        column = pick[0]
    if column not in cols:
        raise CLIError(f"--input-column {column!r}: not in {path} (found {names})")
    unit = column.rsplit("_", 1)[1] if "_" in column else ""
    if unit not in UNITS:
        raise CLIError(f"--input {path}: column {column!r} has no unit suffix from {sorted(UNITS)} "
                       f"(expected e.g. {want[0]}_{want[1]})")
    if UNITS[unit][0] != want[2]:
        raise CLIError(f"--input {path}: column {column!r} is a {UNITS[unit][0]}, but a {kind} is driven "
                       f"by a {want[2]} ({want[0]}_{want[1]})")
    t = cols["time_s"]
    try:
        check_uniform_time(t)
    except ValueError as exc:
        raise CLIError(f"--input {path}: {exc}") from None
    return t, cols[column] * UNITS[unit][1], column
