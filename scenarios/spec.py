"""Scenario files: experiments as data (TOML), validated strictly.

A scenario names the model, the parameter set, the temperatures, the frequency grid or the
stimulus, the noise, the steps to run and the checks it expects.  Every table is optional
except ``[scenario]``, ``[model]`` and ``[checks]``; the steps run in this order when their
table is present:

``[sweep]`` → ``[surrogate]`` → ``[inversion]`` → ``[widths]`` → ``[taylor]`` → ``[blackbox]``
→ ``[discrepancy]`` → ``[fixtures]``.

Schema (units in the key names; SI otherwise)::

    [scenario]   name (str, required), title, description, source
    [model]      kind = "actuator" | "sensor" (required), set (parameter-set name or JSON path,
                 required), quantity ("M", "H", "Z", "I" for actuators; "S", "Z" for sensors;
                 default M / S), kernel ("boundary_charge" | "reciprocal", sensors),
                 params = { NAME = value, ... }  (SI overrides of the set)
    [sweep]      temperatures_c (list, required), fmin_hz, fmax_hz, points, held_out_c (list),
                 plot_temperatures_c (list)
    [noise]      kind = "none" | "magphase" | "complex", sigma_db, sigma_deg, sigma, seed (int)
    [surrogate]  form = "zpk" | "coefficients" | "sections", n_zeros, n_poles, degree,
                 method = "joint" | "two-stage", weighting
    [inversion]  preview = "inf" | "auto" | seconds, fs_hz, duration_s, settle_s, end_margin_s,
                 lead_s, ramp_s (sine references are zero for lead_s, then faded in over ramp_s),
                 [[inversion.experiments]] name, temperature_c, stimulus = "sine" | "release",
                 amplitude_mm, frequencies_hz (list; a multisine splits the amplitude equally),
                 model_temperature_c (surrogate evaluated there instead: a fixed-model scheme),
                 t_release_s, noise_rms (sensor current noise [uA]), seed, window_s = [t0, t1]
                 (error window; default [settle_s, duration_s - end_margin_s]), highpass_hz
                 (compare zero-phase high-passed signals: a current sensor cannot see a static
                 displacement)
    [widths]     widths_m (list), temperature_c, fmin_hz, fmax_hz, points
    [taylor]     orders (list), temperature_c, fmin_hz, fmax_hz, points, band_hz = [lo, hi]
    [blackbox]   orders = [[n_zeros, n_poles], ...], temperature_c (one of the sweep's)
    [discrepancy] effects = { name = { param = value } } (physmodel.effects), free (list),
                 null_draws, null_refits, alpha, seed  (physmodel.estimation.discrepancy.diagnose)
    [fixtures]   count, seed, formats (subset of ["csv", "npz", "mat"]), temperatures_c,
                 fmin_hz, fmax_hz, points, step_duration_s, fs_hz, noise_rms_mm
    [checks.NAME] metric = "section.metric" or "a / b", min, max, description
    [quick]      any of the tables above (not scenario/checks): deep-merged over them by --quick

Unknown tables or keys, wrong types and checks naming a section the scenario does not run are
errors (:class:`ScenarioError`, a :class:`physmodel.IPMCError`) naming the key and the file.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass
from pathlib import Path

from physmodel.errors import IPMCError

#: The order in which the runner executes the step tables.
STEP_ORDER = ("sweep", "surrogate", "inversion", "widths", "taylor", "blackbox", "discrepancy", "fixtures")


class ScenarioError(IPMCError):
    """A scenario file that does not follow the schema (exit code 2)."""


# ---------------------------------------------------------------------------- schema types
class _T:
    """A value type: ``check(value, where)`` returns the (normalised) value or raises."""

    def __init__(self, name, ok, conv=lambda v: v):
        self.name, self.ok, self.conv = name, ok, conv

    def check(self, v, where):
        if not self.ok(v):
            raise ScenarioError(f"{where}: expected {self.name}, got {v!r}")
        return self.conv(v)


def _is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


NUM = _T("a number", _is_num, float)
INT = _T("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool))
STR = _T("a string", lambda v: isinstance(v, str))
NUMS = _T("a non-empty list of numbers", lambda v: isinstance(v, list) and v and all(map(_is_num, v)),
          lambda v: [float(x) for x in v])
INTS = _T("a non-empty list of integers", lambda v: isinstance(v, list) and v and all(
    isinstance(x, int) and not isinstance(x, bool) for x in v))
STRS = _T("a list of strings", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v))
NUM_OR_STR = _T("a number or a string", lambda v: _is_num(v) or isinstance(v, str))
PAIRS = _T("a list of [n_zeros, n_poles] pairs", lambda v: isinstance(v, list) and v and all(
    isinstance(p, list) and len(p) == 2 and all(isinstance(x, int) for x in p) for p in v))


def _choice(*opts):
    return _T(f"one of {list(opts)}", lambda v: v in opts)


class _Map:
    """A table with free keys, every value of one type."""

    def __init__(self, value):
        self.value = value


class _List:
    """An array of tables with a fixed schema."""

    def __init__(self, schema):
        self.schema = schema


_SWEEP_GRID = {"fmin_hz": NUM, "fmax_hz": NUM, "points": INT}
SECTIONS = {
    "scenario": {"name": STR, "title": STR, "description": STR, "source": STR},
    "model": {"kind": _choice("actuator", "sensor"), "set": STR, "quantity": STR,
              "kernel": _choice("boundary_charge", "reciprocal"), "params": _Map(NUM)},
    "sweep": {"temperatures_c": NUMS, **_SWEEP_GRID, "held_out_c": NUMS, "plot_temperatures_c": NUMS},
    "noise": {"kind": _choice("none", "magphase", "complex"), "sigma_db": NUM, "sigma_deg": NUM,
              "sigma": NUM, "seed": INT},
    "surrogate": {"form": _choice("zpk", "coefficients", "sections"), "n_zeros": INT, "n_poles": INT,
                  "degree": INT, "method": _choice("joint", "two-stage"), "weighting": STR},
    "inversion": {"preview": NUM_OR_STR, "fs_hz": NUM, "duration_s": NUM, "settle_s": NUM, "end_margin_s": NUM,
                  "lead_s": NUM, "ramp_s": NUM,
                  "experiments": _List({"name": STR, "temperature_c": NUM, "stimulus": _choice("sine", "release"),
                                        "amplitude_mm": NUM, "frequencies_hz": NUMS, "model_temperature_c": NUM,
                                        "t_release_s": NUM, "noise_rms": NUM, "seed": INT,
                                        "highpass_hz": NUM, "window_s": NUMS})},
    "widths": {"widths_m": NUMS, "temperature_c": NUM, **_SWEEP_GRID},
    "taylor": {"orders": INTS, "temperature_c": NUM, **_SWEEP_GRID, "band_hz": NUMS},
    "blackbox": {"orders": PAIRS, "temperature_c": NUM},
    "discrepancy": {"effects": _Map(_Map(NUM)), "free": STRS, "null_draws": INT, "null_refits": INT, "alpha": NUM,
                    "seed": INT},
    "fixtures": {"count": INT, "seed": INT, "formats": STRS, "temperatures_c": NUMS, **_SWEEP_GRID,
                 "step_duration_s": NUM, "fs_hz": NUM, "noise_rms_mm": NUM},
    "checks": _Map({"metric": STR, "min": NUM, "max": NUM, "description": STR}),
}
REQUIRED = {"scenario": ("name",), "model": ("kind", "set"), "sweep": ("temperatures_c",),
            "checks.*": ("metric",), "inversion.experiments": ("name", "temperature_c", "amplitude_mm")}


def _validate(value, schema, where: str, req_key: str):
    if isinstance(schema, _T):
        return schema.check(value, where)
    if not isinstance(value, dict):
        raise ScenarioError(f"{where}: expected a table, got {value!r}")
    if isinstance(schema, _Map):
        out = {}
        for k, v in value.items():
            out[k] = _validate(v, schema.value, f"{where}.{k}", req_key + ".*")
            if isinstance(schema.value, dict) and req_key + ".*" in REQUIRED:
                _require(out[k], REQUIRED[req_key + ".*"], f"{where}.{k}")
        return out
    out = {}
    for k, v in value.items():
        if k not in schema:
            raise ScenarioError(f"{where}: unknown key {k!r}; expected one of {sorted(schema)}")
        sub = schema[k]
        if isinstance(sub, _List):
            if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
                raise ScenarioError(f"{where}.{k}: expected an array of tables ([[{where.split(': ')[-1]}.{k}]])")
            out[k] = [_validate(x, sub.schema, f"{where}.{k}[{i}]", f"{req_key}.{k}") for i, x in enumerate(v)]
            for i, x in enumerate(out[k]):
                _require(x, REQUIRED.get(f"{req_key}.{k}", ()), f"{where}.{k}[{i}]")
        else:
            out[k] = _validate(v, sub, f"{where}.{k}", f"{req_key}.{k}")
    return out


def _require(table: dict, keys, where: str):
    for k in keys:
        if k not in table:
            raise ScenarioError(f"{where}: missing required key {k!r}")


def _merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else copy.deepcopy(v)
    return out


@dataclass(frozen=True)
class Scenario:
    """A validated scenario: ``data`` holds the tables (``quick`` already merged when asked)."""

    name: str
    path: str
    data: dict
    quick: bool = False

    def section(self, name: str) -> dict:
        return self.data.get(name, {})

    def has(self, name: str) -> bool:
        return name in self.data

    @property
    def steps(self) -> list[str]:
        return [s for s in STEP_ORDER if s in self.data]


def parse_scenario(raw: dict, where: str = "<scenario>", *, quick: bool = False) -> Scenario:
    """Validate a parsed TOML document (see the module docstring) and return a :class:`Scenario`."""
    if not isinstance(raw, dict):
        raise ScenarioError(f"{where}: expected a TOML document")
    known = set(SECTIONS) | {"quick"}
    for k in raw:
        if k not in known:
            raise ScenarioError(f"{where}: unknown table [{k}]; expected one of {sorted(known)}")
    data = {}
    for k, v in raw.items():
        if k != "quick":
            data[k] = _validate(v, SECTIONS[k], f"{where}: [{k}]", k)
    quick_tab = raw.get("quick", {})
    if not isinstance(quick_tab, dict):
        raise ScenarioError(f"{where}: [quick] must be a table")
    for k, v in quick_tab.items():
        if k in ("scenario", "checks", "quick") or k not in SECTIONS:
            raise ScenarioError(f"{where}: [quick.{k}] is not allowed; quick may shrink "
                                f"{sorted(set(SECTIONS) - {'scenario', 'checks'})}")
        if k not in data:
            raise ScenarioError(f"{where}: [quick.{k}] shrinks a table the scenario does not have")
        checked = _validate(v, SECTIONS[k], f"{where}: [quick.{k}]", k)
        if quick:
            data[k] = _merge(data[k], checked)
    for sec in ("scenario", "model", "checks"):
        if sec not in data:
            raise ScenarioError(f"{where}: missing table [{sec}]")
    _require(data["scenario"], REQUIRED["scenario"], f"{where}: [scenario]")
    _require(data["model"], REQUIRED["model"], f"{where}: [model]")
    for sec in ("sweep",):
        if sec in data:
            _require(data[sec], REQUIRED[sec], f"{where}: [{sec}]")
    for dep, need in (("surrogate", "sweep"), ("inversion", "surrogate"), ("blackbox", "sweep"),
                      ("discrepancy", "sweep")):
        if dep in data and need not in data:
            raise ScenarioError(f"{where}: [{dep}] needs a [{need}] table")
    if "inversion" in data and not data["inversion"].get("experiments"):
        raise ScenarioError(f"{where}: [inversion] needs at least one [[inversion.experiments]]")
    for name, chk in data["checks"].items():
        if "min" not in chk and "max" not in chk:
            raise ScenarioError(f"{where}: [checks.{name}] needs min and/or max")
        for term in chk["metric"].split("/"):
            sec = term.strip().split(".")[0]
            if sec not in data or sec not in STEP_ORDER:
                raise ScenarioError(f"{where}: [checks.{name}] metric {term.strip()!r} refers to [{sec}], "
                                    f"which this scenario does not run (steps: {[s for s in STEP_ORDER if s in data]})")
    return Scenario(data["scenario"]["name"], where, data, quick)


def read_toml(path, what: str, error: type[Exception]) -> dict:
    """The parsed TOML file at ``path``, or ``error`` naming the file (missing or not valid TOML)."""
    path = Path(path)
    if not path.is_file():
        raise error(f"{what} file {str(path)!r} does not exist")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None


def load_scenario(path, *, quick: bool = False) -> Scenario:
    """Read and validate a scenario TOML file; ``quick`` merges its ``[quick]`` table."""
    return parse_scenario(read_toml(path, "scenario", ScenarioError), str(path), quick=quick)


def bundled_scenarios() -> list[Path]:
    """The scenario files shipped with the package (``scenarios/*.toml``)."""
    return sorted(Path(__file__).parent.glob("*.toml"))
