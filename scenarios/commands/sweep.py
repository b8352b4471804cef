"""``ipmc sweep``: a synthetic frequency sweep of the physics at several temperatures."""

from __future__ import annotations

import numpy as np

from ._common import (
    EXIT_OK,
    CLIError,
    Progress,
    add_model_args,
    check_celsius,
    check_out_file,
    check_plot_path,
    floats,
    load_physics,
    model_metadata,
    warn_verdict,
)


def add_parser(sub):
    p = sub.add_parser("sweep", help="synthetic frequency sweep at several temperatures",
                       description="Evaluate the physics model on a log frequency grid at several temperatures, "
                                   "optionally add seeded noise, and write CSV/NPZ/MAT (+ a Bode plot).")
    add_model_args(p)
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
    p.set_defaults(func=run)

def run(args) -> int:
    from physmodel.data.files import write_sweep
    from physmodel.data.sweep import ComplexGaussianNoise, MagnitudePhaseNoise, synthesize_sweep

    temps = floats(args.temperatures, "--temperatures")
    if not (np.isfinite(args.fmin) and np.isfinite(args.fmax) and 0 < args.fmin < args.fmax):
        raise CLIError(f"need 0 < --fmin < --fmax, got {args.fmin} and {args.fmax}")
    from physmodel.data.sweep import MAX_SWEEP_LINES

    if not 2 <= args.points <= MAX_SWEEP_LINES // len(temps):
        raise CLIError(f"--points must be 2 to {MAX_SWEEP_LINES // len(temps)} (at most {MAX_SWEEP_LINES} lines over "
                       f"{len(temps)} temperature(s)), got {args.points}")
    check_celsius(temps, "--temperatures")
    if args.seed is not None and args.seed < 0:
        raise CLIError(f"--seed must be a non-negative integer, got {args.seed}")
    for opt, v in (("--sigma-db", args.sigma_db), ("--sigma-deg", args.sigma_deg), ("--sigma", args.sigma)):
        if not (np.isfinite(v) and v >= 0):
            raise CLIError(f"{opt} must be a finite number >= 0, got {v}")
    out = check_out_file(args.out, (".csv", ".npz", ".mat"))
    if args.plot:
        check_plot_path(args.plot)
    mf, overridden = load_physics(args, "ipmc sweep")
    warn_verdict(mf, "ipmc sweep")
    model = mf.model()
    quantity = args.quantity or ("M" if args.kind == "actuator" else "S")
    noise = None
    if args.noise == "magphase":
        noise = MagnitudePhaseNoise(args.sigma_db, args.sigma_deg)
    elif args.noise == "complex":
        noise = ComplexGaussianNoise(args.sigma)
    f = np.logspace(np.log10(args.fmin), np.log10(args.fmax), args.points)
    bar = Progress(len(f) * len(temps), args.quiet, "sweep")
    try:
        sw = synthesize_sweep(model, quantity, f, temps, noise=noise, seed=args.seed, progress=bar)
    finally:
        bar.close()
    meta = model_metadata(mf, overridden)
    from dataclasses import replace

    sw = replace(sw, metadata={**sw.metadata, **meta})
    from physmodel.data.results import files_together

    with files_together([out, *([args.plot] if args.plot else [])]) as tmp:     # both or neither
        write_sweep(sw, tmp[0])
        if args.plot:
            from ..plots import bode

            bode(sw, tmp[1], title=f"{model.params[0].name}: {sw.metadata['description']}")
    if not args.quiet:
        print(f"wrote {out} ({sw.frequency_hz.size} lines, {len(temps)} temperatures, "
              f"{sw.output_unit}/{sw.input_unit}) from {mf.describe()}" + (f" and {args.plot}" if args.plot else ""))
    return EXIT_OK
