"""``ipmc diagnose``: find, name and add the missing physical effect (physmodel.estimation.discrepancy).

    ipmc diagnose EXPERIMENT.toml [--out FOLDER] [--seed N] [--quiet]
    ipmc diagnose --data sweep.csv --kind actuator --set seed002_table3 \\
                  --free alpha0 --free d --free xi --free omega_n --out diagnosis
    ipmc diagnose --data M.csv --data Z.csv --quantity M,Z ...     # several quantities, jointly

EXPERIMENT.toml (paths relative to the TOML file; SI units for parameters)::

    data = "sweep.csv"                 # .csv / .npz / .mat in the physmodel sweep format
                                       # or several files of one strip, one per quantity:
                                       # data = ["M.csv", "Z.csv"]
    kind = "actuator"                  # or "sensor"
    quantity = "M"                     # optional (actuator M/H/Z/I, sensor S/Z); several files:
                                       # quantity = ["M", "Z"] (default: from each file's units)
    [acts_on]                          # several quantities from different instruments: where an
    amplifier_bandwidth = ["S"]        # effect acts (here the current amplifier and acquisition of
    time_delay = ["S"]                 # S, not an impedance analyser's Z; default: every quantity)
    set = "seed002_table3"             # named set or parameter JSON file
    free = ["alpha0", "d", "xi", "omega_n", "kappa_e:1e-7:1e-5"]   # NAME[:LOWER:UPPER[:SCALE[:INITIAL]]]
    candidates = ["time_delay", "amplifier_bandwidth"]             # optional (default: all that apply)
    alpha = 0.05
    seed = 0
    out = "diagnosis"
    [geometry]                         # optional overrides [m]
    L = 15e-3
    W = 2e-3
    [baseline_effects.time_delay]      # effects already in the model (values SI; {} = fitted)
    delay = 1e-3
    laws = "isothermal"                # temperature laws: "set" (the set's own), "isothermal",
                                       # "default" (physics.md §7), or a table (below); REQUIRED
                                       # when `set` is a JSON file without "laws"
    # [laws]                           # a table instead: start from `base`, change some laws
    # base = "isothermal"
    # d = { law = "Arrhenius", activation_energy = 15e3 }
    # E = "Constant"
    [candidate_bounds]                 # candidate bounds (SI), replacing the strip-scaled ones
    "contact_resistance.r2_specific" = [0.0, 0.05]
    "leakage.conductance" = { upper = 2000.0, typical = 100.0 }
    [candidate_starts]                 # extra start values of candidate parameters
    "series_cpe.n" = 0.7
    [plausible]                        # plausible ranges replacing the defaults (physmodel.plausible)
    kappa_e = [1e-7, 1e-5]
    prior = true                       # hold the free base parameters to their plausible ranges
    baseline_starts = 3                # multi-start count of the baseline fit
    [next_measurement]                 # an ambiguous / at-bound verdict's recommended next measurement
    quantities = ["S"]                 # what the lab can measure (default every quantity the kind has)
    band_limits_hz = [0.1, 1000.0]     # the band it may reach [Hz]; temperature_limits_c = [LO, HI] [°C]
    levels = [1.0, 2.0]                # drive levels, multiples of the record's (cap at what the strip takes)

When the verdict is ambiguous or at bound, it also searches the measurement that would separate
the competing models (physmodel.estimation.next_measurement: quantity, band, temperatures, drive
level, with the separation expected at this record's noise) and says it on stderr, in summary.md,
report.json ("next_measurement") and model.json's verdict reason. Its options are checked before the
diagnosis runs (exit 2, whatever the verdict); bath limits are in °C (above 150 refused as kelvin) and
clipped to the temperature laws' valid range. When no recommendation can be made (e.g. no candidate
experiment within the limits) the diagnosis is still written, with "no recommendation: <reason>" in
the same places.

A quantile of the null draws the tests threshold at with fewer than 10 draws beyond it (the LR test's
at α − α_gap, the gap test's at α_gap/K per quantity and α_gap pooled; e.g. two quantities on fewer
than 1802 --null-draws at α = 0.05) leaves that test's level uncertain: the "Thin null tail" note
says which and how many draws would do, on stderr (whether or not --quiet), in summary.md, report.json
(null.tails: each quantile's tail probability and draws beyond it; null.thin_tail: the note) and
model.json's verdict reason.

Several measured quantities of the same strip (actuator M and Z, sensor S and Z; one file per
quantity, ``--data`` repeated or a list): the baseline, the candidates and the null are fitted to
all their lines together, each quantity with its own noise (its per-line σ, or estimated per
quantity when the file has none); report.json ("per_quantity") and summary.md give each quantity's
cost before/after against its expectation, and the figures are drawn per quantity
(bode_before_M.png, bode_after_Z.png, ...). model.json is the model of one quantity — M for an
actuator, S for a sensor when diagnosed, else the first — with that quantity's file, lines and hash
in its provenance (the command line, kept there, lists every file); an effect held off on it
(--acts-on) is left out of it, and a misfit left in ANY quantity makes it say "does not fit" (exit 3
unless --accept-misfit), as every later command that reads it will. The next-measurement search
of a joint diagnosis evaluates every candidate experiment with the whole joint record: a new record
of a diagnosed quantity is merged into that quantity's record, another quantity is added as one more,
each with its own noise and the diagnosis's --acts-on. With one data file, --acts-on tells the
next-measurement search alone where an effect acts among the quantities a new record may measure (e.g.
time_delay=M when the displacement channel carries the delay and Z would come from an impedance analyser).

Writes model.json (the model it ends with — the baseline plus the named effect(s), refitted, with the
goodness-of-fit verdict and the data's provenance: what ``--model`` takes in every later command),
report.json (verdict none / named / ambiguous / unexplained, the named effect with its fitted
value and interval, every candidate's statistics, localisation tables, gap before/after, confusable
pairs, null calibration), summary.md, bode_before.png and bode_after.png.

Flags: --laws NAME, --law QUANTITY=LAW[:P=V,...] (repeatable), --candidate-bound EFFECT.PARAM=LO:HI,
--candidate-start EFFECT.PARAM=V, --plausible NAME=LO:HI, --no-prior, --baseline-starts N,
--next-quantities Q,Q --next-band-hz LO,HI --next-temperatures-c LO,HI --next-levels A,B.

Exit codes: 0 when the model it ends with fits the data (any verdict), 3 when it does not (the verdict
``unexplained``, or a named model still outside the noise; ``--accept-misfit`` to exit 0 — model.json
says so either way), 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from physmodel.errors import IPMCError, ParameterError

from .. import plots
from ._columns import add_sweep_options
from ._common import EXIT_FAILED, EXIT_OK, check_celsius, parse_assignments
from .calibrate import parse_effect, provenance_of, start_model

_GEOMETRY = ("L", "W", "h")


def add_parser(subparsers):
    """Add the ``diagnose`` subcommand."""
    p = subparsers.add_parser(
        "diagnose", help="locate a model/data discrepancy, name the missing effect, refit, show the gap shrink",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("experiment", nargs="?", help="experiment description (TOML); flags override its entries")
    p.add_argument("--data", action="append",
                   help="sweep file (.csv/.npz/.mat); repeat it for several quantities of the strip (one file each)")
    p.add_argument("--kind", choices=("actuator", "sensor"), help="model kind (default actuator)")
    p.add_argument("--quantity", help="actuator: M (default), H, Z, I; sensor: S (default), Z; several files: "
                                      "one per file, comma-separated (default: from each file's units)")
    p.add_argument("--acts-on", action="append", metavar="EFFECT=Q[,Q]",
                   help="the quantities an effect acts on (e.g. amplifier_bandwidth=S when Z is measured by another "
                        "instrument; repeatable; default every quantity it applies to): with several data files for "
                        "the diagnosis and the next-measurement search, with one for the search only")
    p.add_argument("--kernel", choices=("boundary_charge", "reciprocal"), help="sensing kernel")
    p.add_argument("--set", "--model", dest="base_set",
                   help="start: a named parameter set or a JSON model/parameter file (a model file's effects are "
                        "kept as baseline effects)")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="override a base parameter (SI), e.g. W=2e-3 (repeatable)")
    p.add_argument("--free", action="append", metavar="SPEC",
                   help="free parameter NAME[:LOWER:UPPER[:SCALE[:INITIAL]]] (repeatable; default alpha0)")
    p.add_argument("--baseline-effect", action="append", metavar="NAME[:P=V,...]",
                   help="effect already in the model; without values its parameters are fitted (repeatable)")
    p.add_argument("--candidates", help="comma-separated library effects to test (default: all that apply)")
    p.add_argument("--alpha", type=float, help="family-wise false-positive rate (default 0.05)")
    p.add_argument("--null-draws", type=int, help="linearised null Monte Carlo draws (default 4000)")
    p.add_argument("--null-refits", type=int, help="full-refit bootstrap draws under the null (default 4)")
    p.add_argument("--seed", type=int, help="seed of the null Monte Carlo (default 0)")
    p.add_argument("--laws", help="temperature laws: set (the set's own), isothermal, default (physics.md §7)")
    p.add_argument("--law", action="append", metavar="QUANTITY=LAW[:P=V,...]",
                   help="change one law, e.g. d=Arrhenius:activation_energy=20e3 or E=Constant (repeatable)")
    p.add_argument("--candidate-bound", action="append", metavar="EFFECT.PARAM=LO:HI",
                   help="candidate bounds (SI) replacing the strip-scaled ones (repeatable)")
    p.add_argument("--candidate-start", action="append", metavar="EFFECT.PARAM=V",
                   help="extra start value of a candidate parameter (repeatable)")
    p.add_argument("--plausible", action="append", metavar="NAME=LO:HI",
                   help="plausible range of a base parameter replacing the default (repeatable)")
    p.add_argument("--no-prior", action="store_true",
                   help="do not hold the free base parameters to their plausible ranges")
    p.add_argument("--baseline-starts", type=int, help="multi-start count of the baseline fit (default 3)")
    p.add_argument("--out", help="report folder (default diagnosis)")
    p.add_argument("--force", "--overwrite", action="store_true",
                   help="write into a folder that holds another run's results")
    p.add_argument("--accept-misfit", action="store_true",
                   help="exit 0 even when the model diagnose ends with does not fit the data (model.json says so)")
    p.add_argument("--next-quantities", metavar="Q[,Q]",
                   help="an ambiguous verdict's next measurement: quantities the lab can measure (default all)")
    p.add_argument("--next-band-hz", metavar="LO,HI", help="... lowest and highest frequency it may reach [Hz]")
    p.add_argument("--next-temperatures-c", metavar="LO,HI", help="... bath temperatures allowed [°C]")
    p.add_argument("--next-levels", metavar="A[,B...]", help="... drive levels, multiples of the record's")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    add_sweep_options(p, "--data")
    p.set_defaults(func=run)
    return p


def _load_toml(path: Path) -> dict:
    import tomllib

    from physmodel.data.files import read_text

    if not path.is_file():
        raise IPMCError(f"experiment file {str(path)!r} does not exist")
    try:
        spec = tomllib.loads(read_text(path, "experiment file"))
    except tomllib.TOMLDecodeError as exc:
        raise IPMCError(f"experiment file {str(path)!r} is not valid TOML: {exc}") from None
    known = {"data", "kind", "quantity", "kernel", "set", "free", "candidates", "alpha", "seed", "out",
             "geometry", "parameters", "baseline_effects", "null_draws", "null_refits", "laws",
             "candidate_bounds", "candidate_starts", "plausible", "prior", "baseline_starts", "next_measurement",
             "acts_on"}
    unknown = set(spec) - known
    if unknown:
        raise IPMCError(f"experiment file {str(path)!r}: unknown key(s) {sorted(unknown)}; expected {sorted(known)}")
    _check_types(spec, path)
    for key in ("data", "set"):
        if key in spec and isinstance(spec[key], str):
            cand = path.parent / spec[key]
            if key == "data" or cand.suffix.lower() == ".json":
                spec[key] = str(cand) if not Path(spec[key]).is_absolute() else spec[key]
    if isinstance(spec.get("data"), list):
        spec["data"] = [x if Path(x).is_absolute() else str(path.parent / x) for x in spec["data"]]
    return spec


def _is_num(v):
    import math

    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _is_int(v):
    return isinstance(v, int) and not isinstance(v, bool)


def _is_strs(v):
    return isinstance(v, list) and all(isinstance(x, str) for x in v)


#: Experiment-file keys: (check, what is expected).
_TYPES = {"data": (lambda v: isinstance(v, str) or _is_strs(v) and len(v) > 0,
                   "a file name or a non-empty list of file names (one per quantity)"), "kind": (lambda v: v in ("actuator", "sensor"), "'actuator' or 'sensor'"),
          "quantity": (lambda v: isinstance(v, str) or _is_strs(v) and len(v) > 0,
                       "a quantity name (M, H, Z, I, S) or a list of them (one per data file)"),
          "kernel": (lambda v: v in ("boundary_charge", "reciprocal"), "'boundary_charge' or 'reciprocal'"),
          "set": (lambda v: isinstance(v, str), "a parameter-set name or JSON file"),
          "free": (lambda v: _is_strs(v) and len(v) > 0, "a non-empty list of strings NAME[:LOWER:UPPER...]"),
          "candidates": (lambda v: _is_strs(v) or isinstance(v, str), "a list of effect names"),
          "alpha": (lambda v: _is_num(v) and 0 < v < 1, "a number in (0, 1)"),
          "seed": (lambda v: _is_int(v) and v >= 0, "a non-negative integer"),
          "out": (lambda v: isinstance(v, str), "a folder name"),
          "null_draws": (lambda v: _is_int(v) and v >= 1, "a positive integer"),
          "null_refits": (lambda v: _is_int(v) and v >= 0, "a non-negative integer"),
          "geometry": (lambda v: isinstance(v, dict) and all(_is_num(x) for x in v.values()), "a table of L, W, h [m] numbers"),
          "parameters": (lambda v: isinstance(v, dict) and all(_is_num(x) for x in v.values()), "a table of NAME = number (SI)"),
          "baseline_effects": (lambda v: isinstance(v, dict) and all(isinstance(e, dict) and all(_is_num(x) for x in e.values())
                                                                     for e in v.values()),
                               "a table of [baseline_effects.NAME] tables of numbers"),
          "laws": (lambda v: isinstance(v, (str, dict)), "a name (set, isothermal, default) or a [laws] table"),
          "candidate_bounds": (lambda v: isinstance(v, dict), "a table of NAME = [LOWER, UPPER]"),
          "candidate_starts": (lambda v: isinstance(v, dict) and all(_is_num(x) for x in v.values()),
                               "a table of NAME = number"),
          "plausible": (lambda v: isinstance(v, dict), "a table of NAME = [LOWER, UPPER]"),
          "prior": (lambda v: isinstance(v, bool), "true or false"),
          "baseline_starts": (lambda v: _is_int(v) and v >= 1, "a positive integer"),
          "acts_on": (lambda v: isinstance(v, dict) and all(_is_strs(x) and x for x in v.values()),
                      "a table of EFFECT = [quantities], e.g. amplifier_bandwidth = [\"S\"]"),
          "next_measurement": (lambda v: isinstance(v, dict) and set(v) <= {"quantities", "band_limits_hz",
                                                                            "temperature_limits_c", "levels", "power"},
                               "a table of quantities, band_limits_hz, temperature_limits_c, levels, power")}


def _check_types(spec: dict, path: Path) -> None:
    for key, value in spec.items():
        ok, what = _TYPES[key]
        if not ok(value):
            raise IPMCError(f"experiment file {str(path)!r}: {key} = {value!r}; expected {what}")
def _range(item: str, option: str) -> tuple[str, tuple[float, float]]:
    name, sep, rest = item.partition("=")
    parts = rest.split(":")
    try:
        if not sep or len(parts) != 2:
            raise ValueError
        return name.strip(), (float(parts[0]), float(parts[1]))
    except ValueError:
        raise IPMCError(f"{option} {item!r}: expected NAME=LOWER:UPPER (SI)") from None


def _laws(spec: dict, args, set_name) -> object:
    """The laws choice from TOML ``laws`` and ``--laws``/``--law``; a JSON set without laws needs one."""
    import json

    laws = args.laws if args.laws is not None else spec.get("laws")
    if args.law:
        table = dict(laws) if isinstance(laws, dict) else {"base": laws or "set"}
        for item in args.law:
            q, sep, rest = item.partition("=")
            law, _, params = rest.partition(":")
            if not sep or not law.strip():
                raise IPMCError(f"--law {item!r}: expected QUANTITY=LAW[:P=V,...], e.g. d=Arrhenius:activation_energy=2e4")
            table[q.strip()] = {"law": law.strip(),
                                **parse_assignments([x for x in params.split(",") if x.strip()], option=f"--law {item!r}:")}
        laws = table
    if laws is not None and not isinstance(laws, (str, dict)):
        raise IPMCError(f"laws = {laws!r}: expected a name (set, isothermal, default) or a table")
    if str(set_name).lower().endswith(".json") and Path(set_name).is_file():
        try:
            record = json.loads(Path(set_name).read_text(encoding="utf-8-sig"))
            # a bare record holds its laws at the top; a parameter or model file under "parameters"
            has_laws = isinstance(record, dict) and ("laws" in record or isinstance(record.get("parameters"), dict)
                                                     and "laws" in record["parameters"])
        except (OSError, ValueError) as exc:
            raise IPMCError(f"parameter file {set_name!r} cannot be read: {exc}") from None
        base_choice = laws.get("base", "set") if isinstance(laws, dict) else laws
        if not has_laws and base_choice in (None, "set"):
            raise IPMCError(f"parameter file {set_name!r} has no 'laws': choose the temperature laws explicitly "
                            "with laws = \"isothermal\" | \"default\" (physics.md §7) or a [laws] table "
                            "(--laws / --law); they are stated in the report")
    return laws


def _free(spec: str, base, effects: dict):
    from physmodel.effects import get_effect
    from physmodel.estimation.records import FreeParameter

    from .calibrate import parse_free

    name = spec.split(":")[0].strip()
    if "." in name and not name.startswith("laws."):
        e, p = name.split(".", 1)
        if e not in effects:
            raise ParameterError(f"--free {spec!r}: effect {e!r} is not a baseline effect ({sorted(effects)})")
        par = get_effect(e).parameter(p)
        parts = spec.split(":")
        lo, hi = (float(parts[1]), float(parts[2])) if len(parts) >= 3 else (par.lower, par.upper)
        return FreeParameter(name, lo, hi, "linear", min(max(effects[e][p], lo), hi))
    return parse_free(spec, base)


def build(args):
    """Resolve TOML + flags into ``(data, base, kwargs for diagnose, out folder, spec)``."""
    from physmodel.effects import normalize_effects

    from ._columns import read_sweep_mapped

    spec = _load_toml(Path(args.experiment)) if args.experiment else {}
    pick = lambda flag, key, default=None: flag if flag is not None else spec.get(key, default)  # noqa: E731
    data_path = pick(args.data, "data")
    if not data_path:
        raise IPMCError("no data: give --data FILE or 'data = ...' in the experiment file")
    paths = [data_path] if isinstance(data_path, str) else list(data_path)
    set_name = pick(args.base_set, "set")
    if not set_name:
        raise IPMCError("no starting parameter set: give --set NAME_OR_JSON or 'set = ...'")
    over = {}
    for sect in ("geometry", "parameters"):
        sec = spec.get(sect, {})
        if not isinstance(sec, dict):
            raise IPMCError(f"[{sect}] must be a table of NAME = VALUE (SI)")
        if sect == "geometry" and set(sec) - set(_GEOMETRY):
            raise IPMCError(f"[geometry] accepts {_GEOMETRY} [m]; got {sorted(sec)}")
        over.update({k: float(v) for k, v in sec.items()})
    over.update(parse_assignments(args.param))
    start = start_model(set_name, pick(args.kind, "kind"), over)
    base = start.parameters
    sweeps = [read_sweep_mapped(x, args, "--data") for x in paths]
    from physmodel.errors import DataFormatError
    from physmodel.estimation.residuals import noise_std

    for x, sw in zip(paths, sweeps):
        check_celsius(sw.temperatures(), f"{x}: temperature_c")
        try:                            # its per-line σ, checked here so that the message names the file
            noise_std(sw)
        except DataFormatError as exc:
            raise DataFormatError(f"data file {x}: {exc}") from None
    # the start model's effects are in the model (fixed at their values) unless the TOML/flags say otherwise
    effects_spec = {**start.effects, **dict(spec.get("baseline_effects", {}))}
    for item in args.baseline_effect or []:
        n, v = parse_effect(item, "--baseline-effect")
        effects_spec[n] = v
    fitted_effects = [n for n, v in effects_spec.items() if not v]
    effects = normalize_effects(effects_spec)
    free_specs = list(args.free) if args.free else list(spec.get("free", ["alpha0"]))
    free = [_free(s, base, effects) for s in free_specs]
    names = {f.name for f in free}
    from physmodel.effects import get_effect

    for n in fitted_effects:
        for p in get_effect(n).parameters:
            if f"{n}.{p.name}" not in names:
                free.append(_free(f"{n}.{p.name}", base, effects))
    cands = pick(args.candidates, "candidates")
    if isinstance(cands, str):
        cands = [c.strip() for c in cands.split(",") if c.strip()]
    if cands is not None:
        from physmodel.effects import ALL_EFFECTS

        unknown = [c for c in cands if c not in ALL_EFFECTS]
        if unknown:
            raise IPMCError(f"candidates: unknown effect(s) {unknown}; expected names from {sorted(ALL_EFFECTS)}")
    cb = dict(spec.get("candidate_bounds", {}))
    cb.update(dict(_range(x, "--candidate-bound") for x in args.candidate_bound or []))
    cs = dict(spec.get("candidate_starts", {}))
    cs.update(parse_assignments(args.candidate_start, option="--candidate-start"))
    pl = dict(spec.get("plausible", {}))
    pl.update(dict(_range(x, "--plausible") for x in args.plausible or []))
    for key, tab in (("candidate_bounds", cb), ("candidate_starts", cs), ("plausible", pl)):
        if not isinstance(tab, dict):
            raise IPMCError(f"[{key}] must be a table")
    prior = False if args.no_prior else spec.get("prior", True)
    if not isinstance(prior, bool):
        raise IPMCError(f"prior = {prior!r}: expected true or false")
    kind = pick(args.kind, "kind", start.kind)
    if kind not in ("actuator", "sensor"):
        raise IPMCError(f"kind = {kind!r}; expected 'actuator' or 'sensor'")
    data, quantity = _quantities(sweeps, paths, kind, pick(args.quantity, "quantity"),
                                 "--quantity" if args.quantity is not None else f"quantity (in {args.experiment})")
    acts_on = {k: list(v) for k, v in dict(spec.get("acts_on", {})).items()}
    for item in args.acts_on or []:
        e, sep, qs = item.partition("=")
        if not sep or not e.strip() or not [q for q in qs.split(",") if q.strip()]:
            raise IPMCError(f"--acts-on {item!r}: expected EFFECT=Q[,Q], e.g. amplifier_bandwidth=S")
        acts_on[e.strip()] = [q.strip() for q in qs.split(",") if q.strip()]
    # one quantity: acts_on is for the next measurement's search (where an effect acts among the
    # quantities a new record may measure), not for the diagnosis; checked now, before the diagnosis runs
    args.next_acts_on = None
    if acts_on and not isinstance(quantity, tuple):
        from physmodel.estimation.joint import quantity_of
        from physmodel.estimation.next_measurement_design import check_new_acts_on

        flag = "--acts-on" if args.acts_on else "acts_on"
        q1 = quantity_of(data, kind, quantity, f"data file {paths[0]}")
        try:
            args.next_acts_on = {e: list(q) for e, q in check_new_acts_on(kind, q1, acts_on).items()}
        except IPMCError as exc:
            raise IPMCError(f"{flag} (one data file: where an effect acts among the quantities the next measurement "
                            f"may record): {exc}") from None
    kw = dict(kind=kind, quantity=quantity, acts_on=(acts_on or None) if isinstance(quantity, tuple) else None,
              laws=_laws(spec, args, set_name), candidate_bounds=cb or None, candidate_starts=cs or None,
              plausible=pl or None, prior=prior, baseline_starts=int(pick(args.baseline_starts, "baseline_starts", 3)),
              free=free, baseline_effects=effects, candidates=cands, alpha=float(pick(args.alpha, "alpha", 0.05)),
              null_draws=int(pick(args.null_draws, "null_draws", 4000)),
              null_refits=int(pick(args.null_refits, "null_refits", 4)), seed=int(pick(args.seed, "seed", 0)),
              kernel=pick(args.kernel, "kernel", "boundary_charge"))
    from ._common import bound_count

    # the null Monte Carlo holds two (2·lines × draws) float64 arrays and a few rows per candidate
    bound_count(kw["null_draws"], "--null-draws" if args.null_draws is not None else f"null_draws (in {args.experiment})",
                8 * (4 * sum(sw.frequency_hz.size for sw in sweeps) + 16), what="draws")
    args.data_path, args.data_paths = paths[0], paths
    args.next_table = dict(spec.get("next_measurement", {}))
    return data, base, kw, Path(pick(args.out, "out", "diagnosis"))


def _quantities(sweeps: list, paths: list, kind: str, given, option: str):
    """``(data, quantity)`` for :func:`diagnose`: one sweep and its quantity as given, or the sweeps
    of several files with one quantity each (``given``: a list, ``"M,Z"``, or None to take each from
    its file's units); a quantity that does not fit its file, or two files of one quantity, is an
    IPMCError naming the file (exit 2)."""
    from physmodel.estimation.joint import quantity_of

    if isinstance(given, str):
        given = [q.strip() for q in given.split(",")] if "," in given or len(sweeps) > 1 else given
    if len(sweeps) == 1:
        if isinstance(given, list):
            if len(given) != 1:
                raise IPMCError(f"{option} = {given!r}: {len(given)} quantities for one data file ({paths[0]})")
            given = given[0]
        return sweeps[0], given
    if given is not None and len(given) != len(sweeps):
        raise IPMCError(f"{option} = {given!r}: {len(given)} quantities for {len(sweeps)} data files {paths}; "
                        "give one per file, in order (or none: each from its file's units)")
    qs = [quantity_of(sw, kind, None if given is None else given[i], f"data file {paths[i]}")
          for i, sw in enumerate(sweeps)]
    for i, q in enumerate(qs):
        if q in qs[:i]:
            raise IPMCError(f"data files {paths[qs.index(q)]} and {paths[i]} are both quantity {q}: give one file "
                            "per quantity (merge the records of one quantity into one sweep file first), or, "
                            "where one unit serves two quantities (mm/V: M or H), say which with --quantity, "
                            "e.g. --quantity M,H")
    return sweeps, tuple(qs)


def _next_kw(args, table: dict, kind: str) -> dict:
    """Keywords of :meth:`Diagnosis.recommend_next_measurement` from ``[next_measurement]`` (``table``,
    as :func:`build` read it) and the flags: ``quantities`` (what the lab measures), ``band_limits_hz``,
    ``temperature_limits_c``, ``levels`` (drive multiples; cap them at what the strip takes), ``power``,
    and for a one-quantity record the ``--acts-on`` that :func:`build` kept for the search
    (``args.next_acts_on``).  Checked before the diagnosis runs, whatever its verdict: bad input raises IPMCError (exit 2)
    naming the flag or key."""
    import math

    from physmodel.data.units import QUANTITY_UNITS

    from ._common import check_celsius

    where = f" (in {args.experiment})" if args.experiment else ""
    kw: dict = {}
    for key, flag, n in (("quantities", "next_quantities", None), ("band_limits_hz", "next_band_hz", 2),
                         ("temperature_limits_c", "next_temperatures_c", 2), ("levels", "next_levels", None)):
        v = getattr(args, flag, None)
        name = f"--{flag.replace('_', '-')}" if isinstance(v, str) else f"next_measurement.{key}{where}"
        v = [x.strip() for x in v.split(",")] if isinstance(v, str) else table.get(key)
        if v is None:
            continue
        if not isinstance(v, list) or not v or (n is not None and len(v) != n):
            raise IPMCError(f"{name} = {v!r}: expected a list" + (f" of {n} values" if n else "") + f" ({key})")
        if key == "quantities":
            kinds = [q for k, q in QUANTITY_UNITS if k == kind and q != "G"]
            bad = [q for q in v if q not in kinds]
            if bad:
                raise IPMCError(f"{name} = {v!r}: {bad} not measurable on a {kind}; expected some of {kinds}")
        else:
            try:
                if any(isinstance(x, bool) for x in v):
                    raise TypeError
                v = [float(x) for x in v]
            except (TypeError, ValueError):
                raise IPMCError(f"{name} = {v!r}: expected numbers ({key})") from None
            if not all(math.isfinite(x) for x in v):
                raise IPMCError(f"{name} = {v!r}: expected finite numbers ({key})")
            if key in ("band_limits_hz", "levels") and min(v) <= 0:
                raise IPMCError(f"{name} = {v!r}: expected positive numbers ({key})")
            if n == 2 and v[0] > v[1] or key == "band_limits_hz" and v[0] == v[1]:
                raise IPMCError(f"{name} = {v!r}: expected lower, upper with lower below upper ({key})")
            if key == "temperature_limits_c":
                check_celsius(v, name)
        kw[key] = tuple(v)
    if "power" in table:
        pw = table["power"]
        if isinstance(pw, bool) or not isinstance(pw, (int, float)) or not 0.5 <= pw < 1:
            raise IPMCError(f"next_measurement.power{where} = {pw!r}: expected a number in [0.5, 1)")
        kw["power"] = float(pw)
    if getattr(args, "next_acts_on", None):
        kw["acts_on"] = args.next_acts_on
    return kw


def recommend(d, kw: dict) -> None:
    """Search an ambiguous / at-bound diagnosis's next measurement into ``d.next_measurement``; when the
    search cannot give one (IPMCError: e.g. no candidate experiment within the limits) the reason is
    recorded there instead ("no recommendation: ..."), so the finished diagnosis is still written."""
    from physmodel.estimation.next_measurement import NextMeasurement

    try:
        d.recommend_next_measurement(**kw)
    except IPMCError as exc:
        d.next_measurement = NextMeasurement.unavailable(str(exc))


def run(args) -> int:
    """Execute ``ipmc diagnose``: 0 when the final model fits the data, 3 when not (unless
    ``--accept-misfit``); bad input raises IPMCError (exit 2)."""
    from physmodel.data.files import check_output_folder, output_folder
    from physmodel.estimation.diagnosis import gap_shrink_words
    from physmodel.estimation.discrepancy import diagnose

    data, base, kw, out = build(args)
    next_kw = _next_kw(args, args.next_table, kw["kind"])      # before the diagnosis, whatever its verdict
    check_output_folder(out, "ipmc diagnose", force=args.force)
    bar = None
    if not args.quiet:
        from tqdm import tqdm

        bar = tqdm(total=100, desc="diagnose", unit="%", file=sys.stderr,
                   bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining} {postfix}")

    def progress(msg):
        # every candidate refit, null refit and pair fit reports, with the share of the whole done
        if bar is not None:
            frac = getattr(msg, "fraction", None)
            bar.set_postfix_str(str(msg)[:60], refresh=False)
            if frac is not None:
                bar.n = int(round(100 * frac))
            bar.refresh()

    try:
        d = diagnose(data, base, progress=progress, **kw)
        if d.verdict in ("ambiguous", "at_bound"):       # which measurement would separate the rivals
            if bar is not None:
                bar.set_postfix_str("searching the next measurement", refresh=True)
            recommend(d, next_kw)
    finally:
        if bar is not None:
            bar.close()
    if d.joint is None:
        mf = d.to_model_file(provenance_of(args.data_path, d.data, "ipmc diagnose"))
    else:               # the file is the model of one quantity: its own data file, lines and hash
        i = d.joint.quantities.index(d.model_quantity)
        mf = d.to_model_file(provenance_of(args.data_paths[i], d.joint.sweeps[i], "ipmc diagnose"))
    with output_folder(out, "ipmc diagnose", force=args.force) as stage:     # all or nothing
        d.write_report(stage)
        mf.save(stage / "model.json")
        if d.joint is None:
            plots.diagnosis_figures(d, stage)
        else:                                   # one pair of figures per quantity, in its own units
            after = "after: + " + (", ".join(d.final_effects) or "nothing")
            for sw, q, gb, ga in zip(d.joint.sweeps, d.joint.quantities, d.joint.split(d.predicted_before),
                                     d.joint.split(d.predicted_after)):
                plots.residual_bode_pair((stage / f"bode_before_{q}.png", stage / f"bode_after_{q}.png"), sw,
                                         (gb, ga), (f"{q}: baseline (before)", f"{q}: {after}"))
    if not args.quiet:
        print(f"verdict: {d.verdict}" + (f" ({', '.join(d.named)})" if d.named else ""))
        print(d.message)
        print(f"weighted cost {d.gap_before['cost']:.4g} -> {d.gap_after['cost']:.4g} "
              f"(expected {d.gap_after['expected_cost']:.4g}); gap shrink {gap_shrink_words(d)}; "
              f"{d.elapsed_s:.1f} s")
        figs = ("bode_before.png, bode_after.png" if d.joint is None else
                ", ".join(f"bode_before_{q}.png, bode_after_{q}.png" for q in d.joint.quantities))
        print(f"report: {out}/report.json, summary.md, {figs}")
        print(f"model: {out}/model.json — {mf.describe()}; use it downstream with --model {out}/model.json")
    if d.next_measurement is not None:               # said whether or not --quiet: it is the verdict's advice
        print(f"ipmc diagnose: {d.verdict}; {d.next_measurement.message}", file=sys.stderr)
    if d.null.get("thin_tail"):                      # said whether or not --quiet: a level the draws leave uncertain
        print(f"ipmc diagnose: {d.null['thin_tail']}", file=sys.stderr)
    if not mf.adequate:
        print(f"ipmc diagnose: the diagnosed model does not fit the data ({mf.verdict.reason}); model.json says so "
              "and every command that reads it will too"
              + ("" if args.accept_misfit else " (exit 3; --accept-misfit to exit 0)"), file=sys.stderr)
        return EXIT_OK if args.accept_misfit else EXIT_FAILED
    return EXIT_OK


__all__ = ["add_parser", "run", "build"]
