"""What the ``ipmc`` subcommands share: the exit codes, the command-line error, option parsers,
the model options (--kind/--set/--params-json/--param/--kernel) and a progress bar."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError, ParameterError

#: Exit codes of every command: success, bad input (the message names it), a check failed or a fit
#: did not converge, interrupted (SIGINT/SIGTERM).
EXIT_OK, EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED = 0, 2, 3, 130


def parse_assignments(items, option: str = "--param") -> dict[str, float]:
    """``["W=2e-3", "xi=0.2"]`` → ``{"W": 0.002, "xi": 0.2}``; a clear error naming ``option`` otherwise."""
    out: dict[str, float] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"{option} expects NAME=VALUE (SI units), got {item!r}")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise ParameterError(f"{option} {k.strip()}: {v!r} is not a number") from None
    return out


class CLIError(IPMCError):
    """Bad command-line input (exit code 2)."""


# ------------------------------------------------------------------------ argument helpers
def floats(text: str, what: str) -> list[float]:
    """Comma- (or semicolon-) separated numbers in ``text``; IPMCError naming ``what`` otherwise."""
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise CLIError(f"{what} must be comma-separated numbers, got {text!r}") from None
    if not vals:
        raise CLIError(f"{what} is empty")
    if not all(np.isfinite(vals)):
        raise CLIError(f"{what} must be finite, got {text!r}")
    return vals


#: Figure formats the plots can write (matplotlib's savefig).
PLOT_FORMATS = (".png", ".pdf", ".svg", ".svgz", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")


def check_plot_path(path, option: str = "--plot") -> Path:
    """``path`` when its extension is a figure format, a CLIError naming it otherwise (checked
    before any computation, so a typo does not cost a whole run)."""
    p = Path(path)
    if p.suffix.lower() not in PLOT_FORMATS:
        raise CLIError(f"{option} {p}: unknown figure type {p.suffix or '(none)'!r}; use one of {', '.join(PLOT_FORMATS)}")
    if p.is_dir():
        raise CLIError(f"{option} {p} is a folder; expected a file name")
    return p


def refuse_overwriting_inputs(outputs: dict, inputs: dict) -> None:
    """A CLIError (exit 2) when an output file would replace an input: ``outputs`` and ``inputs``
    map an option or role (e.g. ``"--out"``, ``"RECORD"``) to a path or None; two paths are the same
    file when they resolve to the same place (links included), whether or not the output exists yet."""
    def same(a: Path, b: Path) -> bool:
        try:
            return a.resolve() == b.resolve() or (a.exists() and b.exists() and a.samefile(b))
        except OSError:
            return False

    for o_opt, o in outputs.items():
        for i_opt, i in inputs.items():
            if o is not None and i is not None and same(Path(o), Path(i)):
                raise CLIError(f"{o_opt} {o} is the input {i_opt} {i}: an output never replaces an input; "
                               "choose another file name")


def available_memory() -> int:
    """Bytes this process can still allocate: the kernel's MemAvailable (else free RAM), capped by
    the address-space limit (ulimit -v) when one is set."""
    avail = None
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
            avail = 8 << 30
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            avail = min(avail, soft)
    except (ImportError, OSError, ValueError):  # pragma: no cover - not POSIX
        pass
    return int(avail)


#: Share of the available memory one count-driven allocation may claim.
MEMORY_SHARE = 0.5


def bound_count(value, option: str, bytes_each: float, *, what: str = "items") -> int:
    """``value`` (a count that drives an allocation of ``bytes_each`` per unit) when this machine can
    hold it; a CLIError (exit 2) naming ``option`` and the largest value it can hold otherwise —
    checked before anything is allocated."""
    value = int(value)
    limit = max(1, int(available_memory() * MEMORY_SHARE // max(float(bytes_each), 1.0)))
    if value > limit:
        raise CLIError(f"{option} {value}: at most {limit} on this machine ({what} of about {bytes_each:.0f} bytes "
                       f"each, {available_memory() / 2**30:.3g} GiB available)")
    return value


def check_result_file(path, option: str) -> Path:
    """``path`` when the result folder holding it is complete (:func:`physmodel.data.results.check_complete`):
    a file of a run interrupted in its write phase is refused, naming ``option`` and the folder."""
    from physmodel.data.results import check_complete

    try:
        check_complete(path, option)
    except IPMCError as exc:
        raise CLIError(str(exc)) from None
    return Path(path)


def check_plausible(params, option: str) -> None:
    """Refuse (CLIError) parameters outside any physical range before numerical work: a length of
    1e300 m would end in an SVD failure, not a message (:func:`physmodel.plausible.check_physical`)."""
    from physmodel.plausible import check_physical

    try:
        check_physical(params)
    except IPMCError as exc:
        raise CLIError(f"{option}: {exc}") from None


#: Highest plausible operating temperature of a hydrated IPMC [°C] (the physics' laws hold to 100 °C);
#: a °C column or option above it almost always holds kelvin (293–373 K).
MAX_PLAUSIBLE_C = 150.0


def check_celsius(values, where: str) -> None:
    """Refuse (CLIError naming ``where``) temperatures in °C that are below absolute zero or above
    :data:`MAX_PLAUSIBLE_C` — the latter almost always kelvin in a °C column or option."""
    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.size == 0:
        return
    if np.any(v <= -273.15):
        raise CLIError(f"{where} {v[v <= -273.15][:5].tolist()}: below absolute zero (-273.15 °C)")
    if np.any(v > MAX_PLAUSIBLE_C):
        hot = v[v > MAX_PLAUSIBLE_C]
        raise CLIError(f"{where} holds {float(hot.min()):g}{'' if hot.size == 1 else f'–{float(hot.max()):g}'}, above "
                       f"{MAX_PLAUSIBLE_C:g} °C where no hydrated IPMC works — kelvin? Temperatures are in °C "
                       "(subtract 273.15)")


def as_flags(message: str) -> str:
    """A library message's keyword arguments (``improper='filter'``, ``filter_bandwidth=<rad/s>``)
    spelled as the command-line flags of ``ipmc invert``/``feedforward`` (``--improper filter``,
    ``--filter-bandwidth RAD_PER_S``), so that a message names what the user can type."""
    import re

    message = re.sub(r"improper='(\w+)'", r"--improper \1", message)
    message = re.sub(r"filter_bandwidth=<rad/s>", "--filter-bandwidth RAD_PER_S", message)
    return re.sub(r"filter_bandwidth=", "--filter-bandwidth ", message)


def check_out_file(path, suffixes, option: str = "--out") -> Path:
    """An output file name with one of ``suffixes`` that is not an existing folder."""
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise CLIError(f"{option} {p}: use a {', '.join(suffixes)} file name")
    if p.is_dir():
        raise CLIError(f"{option} {p} is a folder; expected a file name")
    return p


#: The named set the model options fall back to when no model is given (sweep, simulate).
DEFAULT_SET = "seed002_table3"


def load_physics(args, command: str, *, default_set: str | None = DEFAULT_SET):
    """The physics the model options name, as a :class:`physmodel.ModelFile`: ``--model FILE``,
    ``--params-json FILE`` or ``--set NAME_OR_FILE`` (one of them), with ``--param`` overrides; the
    file's own kind wins over a ``--kind`` left at its default.  Returns ``(model file, whether
    --param overrode parameters)``; ``(None, False)`` when nothing is given and ``default_set`` is
    None."""
    from physmodel.model_file import load_model

    given = [(o, v) for o, v in (("--model", getattr(args, "model", None)), ("--params-json", getattr(args, "params_json", None)),
                                 ("--set", getattr(args, "set", None))) if v]
    if len(given) > 1:
        raise CLIError(f"{command}: give one of --model, --params-json, --set (got {', '.join(o for o, _ in given)})")
    over = parse_assignments(getattr(args, "param", None))
    if not given:
        if default_set is None:
            if over:
                raise CLIError(f"{command}: --param needs the physics it overrides: give --model or --set")
            return None, False
        given = [("--set", default_set)]
    option, source = given[0]
    if option != "--set" and not Path(source).is_file():
        raise CLIError(f"{option} {source}: no such file")
    if Path(source).is_file():
        check_result_file(source, option)          # not from a folder an interrupted run left behind
    kind = getattr(args, "kind", None)
    try:
        mf = load_model(source, kind=kind)
    except IPMCError as exc:
        raise CLIError(f"{option} {source}: {exc}") from None
    if over:
        mf = mf.with_parameters(mf.parameters.replace(**over))
    check_plausible(mf.parameters, f"{option} {source}" + (" with --param" if over else ""))
    if mf.path is None and getattr(args, "kernel", None):       # a named set: the kernel is the command's
        from dataclasses import replace

        mf = replace(mf, kernel=args.kernel)
    if hasattr(args, "kind") and args.kind is None:
        args.kind = mf.kind
    return mf, bool(over)


def verdict_lines(mf, overridden: bool = False) -> list[str]:
    """Report lines (Markdown) saying what the physics is and whether it fits its data."""
    lines = [f"- physics: {mf.describe()}" + (f" — file `{mf.path}`, sha256 `{mf.fingerprint()[:16]}`" if mf.path else "")]
    if mf.verdict is not None and not mf.verdict.adequate:
        lines.append(f"- **the physics DOES NOT FIT the data it was fitted to**: {mf.verdict.reason}; every number "
                     "computed from it inherits that misfit")
    elif mf.verdict is None:
        lines.append("- the physics was never compared with measured data (a named set or a bare parameter file)")
    if mf.provenance is not None and mf.provenance.temperatures_c:
        band = mf.provenance.band_hz
        lines.append(f"- fitted on {', '.join(f'{t:g}' for t in mf.provenance.temperatures_c)} °C"
                     + (f", {band[0]:.4g}–{band[1]:.4g} Hz" if band else "")
                     + (f" (`{mf.provenance.data_file}`)" if mf.provenance.data_file else ""))
    if overridden:
        lines.append("- **parameters overridden with --param**: the verdict above describes the file's parameters, "
                     "not these")
    return lines


def warn_verdict(mf, command: str) -> None:
    """Say on stderr when the physics does not fit its data (the verdict travels)."""
    if mf.verdict is not None and not mf.verdict.adequate:
        print(f"{command}: warning: the model {mf.path or mf.name} does not fit the data it was fitted to "
              f"({mf.verdict.reason}); results computed from it inherit the misfit", file=sys.stderr)


def model_metadata(mf, overridden: bool = False) -> dict[str, str]:
    """What a sweep or record written from ``mf`` records of it (``model_*`` keys, read back by
    ``ipmc fit``); ``overridden``: its parameters were changed with --param."""
    path = str(Path(mf.path).resolve()) if mf.path and Path(mf.path).is_file() else str(mf.path or mf.name)
    meta = {"model_file": path, "model_sha256": mf.fingerprint(), "model_kind": mf.kind,
            "model_quantity": mf.quantity or ("M" if mf.kind == "actuator" else "S"),
            "model_effects": ", ".join(mf.effects) or "none",
            "model_verdict": ("unchecked" if mf.verdict is None else ("adequate" if mf.verdict.adequate else "MISFIT")),
            "model_verdict_reason": "" if mf.verdict is None else mf.verdict.reason}
    prov = mf.provenance
    if prov is not None:
        if prov.temperatures_c:
            meta["model_fitted_temperatures_c"] = ",".join(f"{t:g}" for t in prov.temperatures_c)
        if prov.band_hz:
            meta["model_fitted_band_hz"] = f"{prov.band_hz[0]:.6g},{prov.band_hz[1]:.6g}"
        if prov.data_file:
            data = prov.data_path(mf.path)
            meta["model_data_file"] = str(Path(data).resolve()) if data is not None and Path(data).exists() else prov.data_file
            if prov.data_sha256:
                meta["model_data_sha256"] = prov.data_sha256
    if overridden:
        meta["model_overridden"] = "parameters overridden with --param: the verdict describes the file's parameters"
    return meta


def surrogate_misfit(info: dict) -> str | None:
    """The surrogate's own verdict on the sweep it was fitted to, as ``ipmc fit`` recorded it in
    ``model.json`` (``info["adequacy"]``): a sentence when it does not fit that sweep, else None
    (also for surrogates written before the verdict was recorded)."""
    a = info.get("adequacy") or {}
    if a.get("adequate") is False:
        data = (info.get("data") or {}).get("file", "its sweep")
        return (f"the surrogate does not fit the sweep it was fitted to ({data}): {a.get('reason', '')}"
                + (" (accepted with ipmc fit --accept-misfit)" if a.get("accepted") else ""))
    return None


def provenance_data(mf, info: dict) -> tuple:
    """The measured sweep a model or a surrogate names as its data, when it is still that file:
    the physics model's provenance first, then the surrogate's source model, then — for a surrogate
    fitted straight to a measured sweep — that sweep.  A candidate is skipped (and a note says why)
    when the file is gone, its SHA-256 differs from the one recorded, or it holds another quantity
    than the tip displacement per volt.  Returns ``(path or None, how found, notes)``."""
    from physmodel.model_file import file_sha256

    notes: list[str] = []
    cands = []
    if mf is not None and mf.provenance is not None and mf.provenance.data_file:
        cands.append((mf.provenance.data_path(mf.path), f"the physics model's provenance ({mf.path or mf.name})",
                      mf.provenance.data_sha256, mf.quantity))
    src = info.get("source_model") or {}
    if src.get("data_file"):
        cands.append((Path(src["data_file"]), "the surrogate's source model", src.get("data_sha256"), src.get("quantity")))
    own = (info.get("data") or {}).get("file")
    if not src and own:
        cands.append((Path(own), "the surrogate's own data (it was fitted to a measured sweep)", None, None))
    for path, how, sha, quantity in cands:
        if path is None or not path.is_file():
            notes.append(f"{how} names {path}, which is not found")
        elif quantity not in (None, "", "M"):
            notes.append(f"{how} names {path}, fitted to quantity {quantity}, not the tip displacement per volt")
        elif sha and file_sha256(path) != sha:
            notes.append(f"{how} names {path}, which has changed since the model was fitted (SHA-256 differs)")
        else:
            return path, how, notes
    return None, "", notes


def add_model_args(p, default_set: str | None = DEFAULT_SET):
    """Add the model options every model-evaluating command shares (kind, set, model file, --param)."""
    p.add_argument("--kind", choices=("actuator", "sensor"), default=None,
                   help="actuator (voltage in) or sensor (tip displacement in, short-circuit current out); "
                        "default: the model file's kind, else actuator")
    p.add_argument("--model", help="a model file (model.json of 'ipmc calibrate' or 'ipmc diagnose': parameters, "
                                   "laws, effects and the data's verdict)")
    p.add_argument("--set", default=None, help="named parameter set (see 'ipmc sets') or a JSON model/parameter file"
                   + (f"; default {default_set}" if default_set else ""))
    p.add_argument("--params-json", help="a JSON parameter or model file (same as --model)")
    p.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="override a parameter in SI units, e.g. --param W=2e-3 (repeatable)")
    p.add_argument("--kernel", choices=("boundary_charge", "reciprocal"), default="boundary_charge",
                   help="sensing kernel (sensor only)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")


class Progress:
    """A tqdm bar on stderr for long evaluations (none when ``quiet`` or under 200,000 points)."""

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
