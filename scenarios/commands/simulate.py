"""``ipmc simulate``: a time-domain virtual experiment (sine, step, free release)."""

from __future__ import annotations

from pathlib import Path


from ._common import EXIT_OK, CLIError, _add_model_args, _floats, _load_params, _model


def add_parser(sub):
    p = sub.add_parser("simulate", help="time-domain virtual experiment",
                       description="Sine, step or free-release experiment with the exact model (via a verified "
                                   "rational realisation); SI units in the output file.")
    _add_model_args(p)
    p.add_argument("--experiment", choices=("sine", "step", "release"), default="sine")
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
    p.add_argument("--out", required=True, help="output file (.csv or .npz)")
    p.add_argument("--plot", help="also write a plot of the traces (PNG)")
    p.set_defaults(func=run)

def run(args) -> int:
    from physmodel import TransimpedanceChain
    from physmodel.data.timesim import free_release, sine, step

    out = Path(args.out)
    if out.suffix.lower() not in (".csv", ".npz"):
        raise CLIError(f"--out {out}: use a .csv or .npz file name")
    model = _model(args, _load_params(args))
    kw = dict(output_noise_rms=args.noise_rms, input_noise_rms=args.input_noise_rms, seed=args.seed)
    if args.chain:
        if args.kind != "sensor":
            raise CLIError("--chain applies to the sensor's current output (use --kind sensor)")
        r = _floats(args.chain, "--chain")
        if len(r) != 3:
            raise CLIError(f"--chain expects R1,R2,R3 in ohm, got {args.chain!r}")
        kw["chain"] = TransimpedanceChain(*r)
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
    ts.save(out)
    if args.plot:
        from ..plots import traces

        traces(ts, args.plot, title=f"{args.experiment}, {model.params[0].name}, {args.temperature:g} °C")
    if not args.quiet:
        print(f"wrote {out} ({ts.t.size} samples; {ts.metadata.get('realization', 'free response of the first mode')})")
    return EXIT_OK
