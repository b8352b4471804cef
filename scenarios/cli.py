"""``ipmc`` — the command line of the IPMC library.

    ipmc sets                       list the named parameter sets (``ipmc sets NAME`` shows one)
    ipmc sweep ...                  synthetic frequency sweep → CSV/NPZ/MAT (+ Bode plot)
    ipmc simulate ...               time-domain virtual experiment → CSV/NPZ (+ plot)
    ipmc demo                       the flagship chain on embedded defaults → a report folder
    ipmc run SCENARIO.toml          a scenario file (scenarios/*.toml) → data, figures, report.md
    ipmc study STUDY.toml           Monte Carlo / grid parameter study (local processes or Dask)
    ipmc fit / ipmc invert ...      surrogate fitting and stable inversion (when installed)

Exit codes: 0 success, 2 bad input (the message names it), 3 a check or a fit failed,
130 interrupted.  ``--quiet`` silences progress bars.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

import numpy as np

from physmodel._cli import parse_assignments

EXIT_OK, EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED = 0, 2, 3, 130

#: Optional subcommand providers: modules exposing add_parser(subparsers) and run(args) -> int.
PLUGINS = ("scenarios.runner", "scenarios.study", "surrogate.cli", "inversion.cli", "physmodel.calibration_cli",
           "physmodel.discrepancy_cli", "scenarios.validate")


class CLIError(Exception):
    """Bad command-line input (exit code 2)."""


# ------------------------------------------------------------------------ argument helpers
def _floats(text: str, what: str) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise CLIError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not vals:
        raise CLIError(f"{what} is empty")
    if not all(np.isfinite(vals)):
        raise CLIError(f"{what} must be finite, got {text!r}")
    return vals


def _load_params(args):
    from physmodel import get_parameter_set
    from physmodel.params import IPMCParameters

    if getattr(args, "params_json", None):
        import json

        path = Path(args.params_json)
        if not path.exists():
            raise CLIError(f"--params-json {path}: no such file")
        p = IPMCParameters.from_dict(json.loads(path.read_text()))
        over = parse_assignments(args.param)
        return p.replace(**over) if over else p
    return get_parameter_set(args.set, **parse_assignments(args.param))


def _model(args, params):
    from physmodel import ActuatorModel, SensorModel

    if args.kind == "actuator":
        return ActuatorModel(params)
    return SensorModel(params, kernel=args.kernel)


def _add_model_args(p):
    p.add_argument("--kind", choices=("actuator", "sensor"), default="actuator",
                   help="actuator (voltage in) or sensor (tip displacement in, short-circuit current out)")
    p.add_argument("--set", default="seed002_table3", help="named parameter set (see 'ipmc sets'); default seed002_table3")
    p.add_argument("--params-json", help="a parameter-set JSON file (IPMCParameters.to_dict) instead of --set")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="override a parameter in SI units, e.g. --param W=2e-3 (repeatable)")
    p.add_argument("--kernel", choices=("boundary_charge", "reciprocal"), default="boundary_charge",
                   help="sensing kernel (sensor only)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")


class _Progress:
    def __init__(self, total: int, quiet: bool, desc: str):
        self.bar = None
        if not quiet and total >= 200_000:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=desc, unit="pt", unit_scale=True, file=sys.stderr)

    def __call__(self, n):
        if self.bar is not None:
            self.bar.update(n)

    def close(self):
        if self.bar is not None:
            self.bar.close()


# ------------------------------------------------------------------------ sets
def cmd_sets(args) -> int:
    from physmodel import available_parameter_sets, describe, get_parameter_set

    if args.name:
        print(describe(get_parameter_set(args.name)))
        if args.json:
            import json

            from physmodel.data.files import atomic_write

            atomic_write(args.json, lambda fh: fh.write(json.dumps(get_parameter_set(args.name).to_dict(), indent=2, default=str)))
        return EXIT_OK
    for n in available_parameter_sets():
        print(f"{n:24s} {get_parameter_set(n).source}")
    return EXIT_OK


# ------------------------------------------------------------------------ sweep
def cmd_sweep(args) -> int:
    from physmodel.data.sweep import ComplexGaussianNoise, MagnitudePhaseNoise, synthesize_sweep
    from physmodel.data.files import write_sweep

    temps = _floats(args.temperatures, "--temperatures")
    if not (0 < args.fmin < args.fmax):
        raise CLIError(f"need 0 < --fmin < --fmax, got {args.fmin} and {args.fmax}")
    if args.points < 2:
        raise CLIError(f"--points must be >= 2, got {args.points}")
    out = Path(args.out)
    if out.suffix.lower() not in (".csv", ".npz", ".mat"):
        raise CLIError(f"--out {out}: use a .csv, .npz or .mat file name")
    model = _model(args, _load_params(args))
    quantity = args.quantity or ("M" if args.kind == "actuator" else "S")
    noise = None
    if args.noise == "magphase":
        noise = MagnitudePhaseNoise(args.sigma_db, args.sigma_deg)
    elif args.noise == "complex":
        noise = ComplexGaussianNoise(args.sigma)
    f = np.logspace(np.log10(args.fmin), np.log10(args.fmax), args.points)
    bar = _Progress(len(f) * len(temps), args.quiet, "sweep")
    try:
        sw = synthesize_sweep(model, quantity, f, temps, noise=noise, seed=args.seed, progress=bar)
    finally:
        bar.close()
    write_sweep(sw, out)
    if args.plot:
        from .plots import bode

        bode(sw, args.plot, title=f"{model.params[0].name}: {sw.metadata['description']}")
    if not args.quiet:
        print(f"wrote {out} ({sw.frequency_hz.size} lines, {len(temps)} temperatures, "
              f"{sw.output_unit}/{sw.input_unit})" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_OK


# ------------------------------------------------------------------------ simulate
def cmd_simulate(args) -> int:
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
        from .plots import traces

        traces(ts, args.plot, title=f"{args.experiment}, {model.params[0].name}, {args.temperature:g} °C")
    if not args.quiet:
        print(f"wrote {out} ({ts.t.size} samples; {ts.metadata.get('realization', 'free response of the first mode')})")
    return EXIT_OK


# ------------------------------------------------------------------------ parser
def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="ipmc", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("sets", help="list named parameter sets or show one")
    p.add_argument("name", nargs="?", help="a set to describe")
    p.add_argument("--json", help="also write the set as JSON to this file")
    p.set_defaults(func=cmd_sets)

    p = sub.add_parser("sweep", help="synthetic frequency sweep at several temperatures",
                       description="Evaluate the physics model on a log frequency grid at several temperatures, "
                                   "optionally add seeded noise, and write CSV/NPZ/MAT (+ a Bode plot).")
    _add_model_args(p)
    p.add_argument("--quantity", help="actuator: M (default), H, Z, I; sensor: S (default), Z")
    p.add_argument("--temperatures", default="20,40,60", help="comma-separated temperatures [°C] (default 20,40,60)")
    p.add_argument("--fmin", type=float, default=0.1, help="lowest frequency [Hz] (default 0.1)")
    p.add_argument("--fmax", type=float, default=100.0, help="highest frequency [Hz] (default 100)")
    p.add_argument("--points", type=int, default=60, help="frequencies per temperature (default 60)")
    p.add_argument("--noise", choices=("none", "magphase", "complex"), default="none", help="noise model")
    p.add_argument("--sigma-db", type=float, default=0.1, help="magphase: log-magnitude std [dB]")
    p.add_argument("--sigma-deg", type=float, default=1.0, help="magphase: phase std [deg]")
    p.add_argument("--sigma", type=float, default=0.01, help="complex: relative std per line")
    p.add_argument("--seed", type=int, help="noise seed (required with noise)")
    p.add_argument("--out", required=True, help="output file (.csv, .npz or .mat)")
    p.add_argument("--plot", help="also write a Bode plot (PNG)")
    p.set_defaults(func=cmd_sweep)

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
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("demo", help="run the flagship chain (physics → scheduled surrogate → inversion → checks)",
                       description="The flagship chain on embedded defaults (scenarios/demo.toml): physics sweeps of "
                                   "the seed 001 actuator at eight temperatures, a joint temperature-scheduled "
                                   "surrogate fitted without the held-out 35/45 °C, the held-out check, stable-"
                                   "inversion feedforward at 45 °C applied to the physics plant, and validation "
                                   "checks; writes data, surrogate.json, PNG figures and report.md (last).  "
                                   "Exit 3 when a check fails.")
    p.add_argument("--out", default="ipmc-demo", help="report folder (default ./ipmc-demo)")
    p.add_argument("--quick", action="store_true", help="shorter time records (what the test suite runs)")
    p.add_argument("--update-figures", action="store_true",
                   help="also refresh the README figures in scenarios/figures/ (developers)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=_run_demo)

    for name in PLUGINS:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name in (name, name.split(".")[0]):
                continue
            raise
        before = set(sub.choices)
        mod.add_parser(sub)
        for cmd in set(sub.choices) - before:
            _PLUGIN_COMMANDS[cmd] = mod
    return ap


_PLUGIN_COMMANDS: dict = {}


def _run_demo(args) -> int:
    from .demo import run_demo

    return run_demo(Path(args.out), quiet=args.quiet, quick=args.quick,
                    update_figures=args.update_figures).exit_code


def main(argv=None) -> int:
    from physmodel.errors import IPMCError

    ap = build_parser()
    args = ap.parse_args(argv)
    if not getattr(args, "command", None):
        ap.print_help()
        return EXIT_BAD_INPUT
    try:
        if args.command in _PLUGIN_COMMANDS:
            return int(_PLUGIN_COMMANDS[args.command].run(args))
        return int(args.func(args))
    except (CLIError, IPMCError) as exc:
        print(f"ipmc {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"ipmc {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
