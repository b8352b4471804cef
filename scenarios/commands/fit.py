"""``ipmc fit``: fit a (temperature-scheduled) rational model to a measured/simulated CSV.

The CSV is the physmodel sweep format: header lines starting with ``#`` (``# input:
tip_displacement [mm]``, ``# output: current [uA]``, other ``# key: value`` lines kept as
metadata), then a header row and columns ``temperature_c,frequency_hz,magnitude_db,
phase_deg`` with optional ``magnitude_std_db,phase_std_deg``.

Outputs (written atomically into ``--out``): ``model.json``, ``report.md``, one Bode overlay
per temperature (``bode_<T>C.png``) and, for scheduled fits, ``poles_zeros_vs_temperature.png``.

Exit codes: 0 ok, 2 bad input, 3 the fit did not converge.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from physmodel.data.files import atomic_write
from surrogate import FORMS
from surrogate._data import FrequencyData
from surrogate._fit import WEIGHTINGS
from surrogate._nlp import ConvergenceError

from .. import plots
from ._columns import add_sweep_options
from ._common import EXIT_BAD_INPUT, EXIT_OK
from ._common import EXIT_FAILED as EXIT_NOT_CONVERGED

__all__ = ["add_parser", "run", "read_csv"]

#: Highest temperature a sweep may hold [°C]: a hydrated ionomer works in liquid water (the
#: physics' laws are valid to 100 °C); 150 °C leaves a margin, and lab temperatures in kelvin
#: (273–373) are all above it.
MAX_PLAUSIBLE_C = 150.0


def read_csv(path, args=None) -> FrequencyData:
    """Read a sweep file (.csv, .npz or .mat in the physmodel format) into ``FrequencyData``.

    Parsing and validation are physmodel's (:func:`physmodel.data.sweep.read_sweep`): a malformed file
    raises ``DataFormatError`` (a ``ValueError``) naming the line and the problem.  With ``args``, a
    file of another layout is read through its ``--sweep-columns``/``--sweep-units`` options.
    """
    from surrogate._data import from_sweep

    from ._columns import read_sweep_mapped

    return from_sweep(read_sweep_mapped(path, args, "CSV"))


def add_parser(subparsers):
    """Add the ``fit`` subcommand to an argparse subparsers object."""
    p = subparsers.add_parser(
        "fit", help="fit a temperature-scheduled rational transfer function to a sweep CSV",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("csv", help="sweep CSV (physmodel format)")
    p.add_argument("--zeros", type=int, default=3, help="number of zeros (default 3)")
    p.add_argument("--poles", type=int, default=3, help="number of poles (default 3)")
    p.add_argument("--degree", type=int, default=2, help="polynomial degree in T (default 2)")
    p.add_argument("--form", choices=FORMS, default="zpk",
                   help="schedule form (default zpk)")
    p.add_argument("--method", choices=("joint", "two-stage"), default="joint")
    p.add_argument("--weighting", choices=WEIGHTINGS, default="auto")
    p.add_argument("--exclude", type=float, nargs="*", default=[], metavar="T",
                   help="temperatures [°C] held out of the fit and reported as validation")
    p.add_argument("--max-iter", type=int, default=500)
    p.add_argument("--accept-misfit", action="store_true",
                   help="exit 0 even when the model does not fit the data (goodness-of-fit test failed)")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds another run's results")
    p.add_argument("--out", default="fit-out", help="output directory (default fit-out)")
    p.add_argument("--quiet", action="store_true", help="no summary line")
    add_sweep_options(p)
    p.set_defaults(func=run)
    return p


def _fmt(v, spec=".4g"):
    return "n/a" if v is None else format(v, spec)


def _report(args, data, fit_data, res, held_out, figures, verdict=None) -> str:
    m = res.model
    st = m.structure
    lines = [
        f"# Surrogate fit: {data.output_name} / {data.input_name}",
        "",
        f"- data: `{args.csv}` ({data.n} lines, fingerprint `{data.fingerprint()}`)",
        f"- model: form `{st.form}`, {st.n_zeros} zeros, {st.n_poles} poles, degree {st.degree} in T, "
        f"method `{res.method}`, weighting `{res.weighting}`",
        f"- status: {'converged' if res.converged else 'NOT CONVERGED'} (`{res.status}`, "
        f"{res.iterations} iterations, {res.time_s:.2f} s)",
        f"- weighted RMS residual: {res.weighted_rms:.4g}",
        f"- goodness of fit: {'adequate' if verdict is None or verdict.adequate else '**INADEQUATE**'}"
        + (f" — {verdict.reason}" if verdict is not None else ""),
        f"- stability: {'stable' if res.stability.stable else 'UNSTABLE'} on {res.stability.n_temperatures} "
        f"temperatures (max pole real part {res.stability.max_pole_real_part_rad_s:.4g} rad/s)",
        f"- units: response in {data.output_unit or '?'}/{data.input_unit or '?'}, s in rad/s",
        "",
        "## Error per temperature",
        "",
        "| T [°C] | role | lines | relative RMS error | fit % |",
        "|---:|:---|---:|---:|---:|",
    ]
    for e in res.per_temperature:
        lines.append(f"| {_fmt(e.temperature_c, 'g')} | fit | {e.n_lines} | {e.relative_rms_error:.4f} | {e.fit_percent:.2f} |")
    lo, hi = m.temperature_range_c or (None, None)
    for e in held_out:
        role = "held out" if lo is None or lo <= e.temperature_c <= hi else "held out, extrapolated"
        lines.append(f"| {_fmt(e.temperature_c, 'g')} | {role} | {e.n_lines} | {e.relative_rms_error:.4f} | {e.fit_percent:.2f} |")
    lines += ["", "## Parameters (scaled; see model.json for the scales)", "",
              "| name | value | std. error | 95 % CI |", "|:---|---:|---:|:---|"]
    for row in m.parameter_table():
        ci = f"[{row['ci95_low']:.4g}, {row['ci95_high']:.4g}]" if "ci95_low" in row else "n/a"
        lines.append(f"| {row['name']} | {row['value']:.6g} | {_fmt(row.get('stderr'))} | {ci} |")
    if res.at_bounds:
        lines += ["", f"Parameters on a bound (intervals unreliable): {', '.join(res.at_bounds)}"]
    lines += ["", "## Figures", ""] + [f"![{p}]({p})" for p in figures]
    return "\n".join(lines) + "\n"


def provenance(args, data, fit_data) -> dict:
    """What the surrogate records of its data: the sweep file, its fingerprint, the temperatures and
    band fitted and, when the sweep was made from a physics model (``ipmc sweep --model``), that
    model (file, sha256, effects, its data's verdict) — read by ``ipmc feedforward``/``ipmc invert``."""
    from pathlib import Path

    info = {"data": {"file": str(Path(args.csv).resolve()), "fingerprint": data.fingerprint(),
                     "temperatures_c": [float(t) for t in fit_data.temperatures()],
                     "band_hz": [float(np.min(fit_data.frequency_hz)), float(np.max(fit_data.frequency_hz))]}}
    src = {k[len("model_"):]: v for k, v in (data.metadata or {}).items() if k.startswith("model_")}
    if src:
        info["source_model"] = src
    return info


def upstream_lines(info: dict) -> str:
    """The report section on the physics this surrogate was fitted to (empty when it was measured data)."""
    src = info.get("source_model")
    if not src:
        return ""
    v = src.get("verdict", "unchecked")
    text = ["", "## Upstream physics", "",
            f"- the sweep was made from `{src.get('file')}` (sha256 `{str(src.get('sha256', ''))[:16]}`; effects: "
            f"{src.get('effects', 'none')})",
            "- its verdict on its own data: " + {"adequate": "fits its data", "MISFIT": "**DOES NOT FIT its data**",
                                                 "unchecked": "never compared with measured data"}.get(v, v)
            + (f" — {src['verdict_reason']}" if src.get("verdict_reason") else "")]
    if src.get("overridden"):
        text.append(f"- **{src['overridden']}**")
    if src.get("fitted_temperatures_c"):
        text.append(f"- that model was fitted at {src['fitted_temperatures_c']} °C"
                    + (f", {src['fitted_band_hz'].replace(',', '–')} Hz" if src.get("fitted_band_hz") else ""))
    return "\n".join(text) + "\n"


def run(args) -> int:
    """Execute ``fit``; returns the exit code (0 ok, 2 bad input, 3 not converged)."""
    from physmodel.data.files import check_output_folder
    from surrogate import RationalFit, ScheduledFit

    check_output_folder(args.out, "ipmc fit", force=args.force)     # refuse before the fit, not after
    try:
        data = read_csv(args.csv, args)
        temps = data.temperatures()
        if temps.size and float(np.max(temps)) > MAX_PLAUSIBLE_C:
            raise ValueError(f"{args.csv}: temperature_c holds {float(np.min(temps)):g}–{float(np.max(temps)):g}, above "
                             f"{MAX_PLAUSIBLE_C:g} °C where no hydrated IPMC works — kelvin? The sweep format's "
                             "temperature_c is in °C (subtract 273.15)")
        excl = np.array(sorted(set(args.exclude)), float)
        for t in excl:
            if not np.any(np.isclose(temps, t)):
                raise ValueError(f"--exclude {t:g}: no data at that temperature (have {temps.tolist()})")
        keep = ~np.any(np.isclose(data.temperature_c[:, None], excl[None, :]), axis=1) if excl.size else np.ones(data.n, bool)
        if not keep.any():
            raise ValueError(f"--exclude {sorted(set(args.exclude))} leaves no temperature to fit (have {temps.tolist()})")
        fit_data = data.select(keep)
        fit_temps = fit_data.temperatures()
        if fit_temps.size == 1:
            fitter = RationalFit(args.zeros, args.poles, weighting=args.weighting, max_iter=args.max_iter)
        else:
            fitter = ScheduledFit(args.form, args.zeros, args.poles, args.degree, method=args.method,
                                  weighting=args.weighting, max_iter=args.max_iter)
        res = fitter.fit_data(fit_data)
    except ConvergenceError as exc:
        print(f"ipmc fit: {exc}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    except (ValueError, OSError) as exc:
        print(f"ipmc fit: bad input: {args.csv}: {exc}" if str(args.csv) not in str(exc) else f"ipmc fit: bad input: {exc}",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    from physmodel.data.files import output_folder
    from surrogate.adequacy import assess

    if (data.metadata or {}).get("model_verdict") == "MISFIT":
        print(f"ipmc fit: warning: {args.csv} was made from {data.metadata.get('model_file')}, which does not fit "
              f"its own data ({data.metadata.get('model_verdict_reason', '')}); the surrogate inherits that misfit "
              "and ipmc feedforward/invert will refuse it without --accept-misfit", file=sys.stderr)

    verdict = assess(res)
    schedule = None
    if res.model.is_scheduled:
        from surrogate import check_schedule

        schedule = check_schedule(fitter, fit_data, res.model, warn=False)     # leave-one-temperature-out
        if not schedule.ok:
            print(f"ipmc fit: WARNING: {schedule.message}", file=sys.stderr)
    with output_folder(args.out, "ipmc fit", force=args.force) as out:          # all or nothing
        _write(args, data, fit_data, res, excl, temps, fit_temps, out, verdict, schedule)
    if not args.quiet:
        print(f"ipmc fit: wrote {Path(args.out) / 'model.json'} and {Path(args.out) / 'report.md'}")
    if not res.converged:
        print(f"ipmc fit: the fit did not converge (IPOPT status {res.status!r})", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    if not verdict.adequate:
        print(f"ipmc fit: the model does not fit the data: {verdict.reason}"
              + ("" if args.accept_misfit else " (--accept-misfit to exit 0)"), file=sys.stderr)
        print("ipmc fit: model.json records this verdict; ipmc feedforward/invert will say it and refuse the "
              "surrogate without --accept-misfit", file=sys.stderr)
        return EXIT_OK if args.accept_misfit else EXIT_NOT_CONVERGED
    return EXIT_OK


def _write(args, data, fit_data, res, excl, temps, fit_temps, out, verdict, schedule=None):
    from surrogate import TemperatureError, fit_percent, relative_rms_error

    model = res.model
    held = []
    for t in excl:
        d = data.at_temperature(t)
        h = model.frequency_response(d.frequency_hz, t if model.is_scheduled else None, extrapolate=True)
        held.append(TemperatureError(float(t), d.n, relative_rms_error(h, d.response), fit_percent(h, d.response)))
    figures = []
    for t in temps:
        name = f"bode_{t:g}C.png"
        extrap = model.is_scheduled and not (fit_temps.min() <= t <= fit_temps.max())
        if extrap:
            continue
        plots.save_bode(model, data, t, out / name, title=f"T = {t:g} °C" + (" (held out)" if t in excl else ""))
        figures.append(name)
    if model.is_scheduled:
        plots.save_poles_zeros_vs_temperature(model, out / "poles_zeros_vs_temperature.png",
                                        res.per_temperature_models)
        figures.append("poles_zeros_vs_temperature.png")
    model.info.update(provenance(args, data, fit_data))
    model.info["adequacy"] = {"adequate": bool(verdict.adequate), "test": verdict.test, "reason": verdict.reason,
                              "p_value": verdict.p_value, "accepted": bool(args.accept_misfit)}   # read by feedforward/invert
    model.to_json(out / "model.json")
    report = _report(args, data, fit_data, res, held, figures, verdict)
    report += upstream_lines(model.info)
    if schedule is not None:
        report += ("\n## Between the fit temperatures (leave-one-temperature-out)\n\n" + schedule.cv.to_markdown()
                   + "\n" + ("OK: " if schedule.ok else "**WARNING**: ") + schedule.message
                   + "\n")
    atomic_write(out / "report.md", lambda fh: fh.write(report))
