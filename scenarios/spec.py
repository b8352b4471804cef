"""Scenario files: experiments as data (TOML), validated strictly.

A scenario names the model, the parameter set, the temperatures, the frequency grid or the
stimulus, the noise, the steps to run and the checks it expects.  Every table is optional
except ``[scenario]``, ``[model]`` and ``[checks]``; the steps run in this order when their
table is present:

``[sweep]`` → ``[surrogate]`` → ``[inversion]`` → ``[widths]`` → ``[taylor]`` → ``[blackbox]``
→ ``[discrepancy]`` → ``[next_measurement]`` → ``[fixtures]``.

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
    [inversion]  preview = "inf" | "auto" | "4/r0" | seconds, fs_hz, duration_s, settle_s, end_margin_s,
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
    [next_measurement] effects = { name = { param = value } } (a hidden instrument element), the first
                 virtual-lab record's design (temperatures_c, fmin_hz, fmax_hz, points, fs_hz, period_s,
                 periods, transient_periods, rms, oversample), output_noise_rms, noise_seed,
                 next_noise_seed, the diagnosis's free, candidates, null_draws, null_refits, alpha, seed,
                 laws, baseline_starts and the search's band_limits_hz, temperature_limits_c, levels, power
                 (scenarios/steps_next_measurement.py)
    [fixtures]   count, seed, formats (subset of ["csv", "npz", "mat"]), temperatures_c,
                 fmin_hz, fmax_hz, points, step_duration_s, fs_hz, noise_rms_mm
    [checks.NAME] metric = "section.metric" or "a / b", min, max, description
    [quick]      any of the tables above (not scenario/checks): deep-merged over them by --quick

Unknown tables or keys, wrong types and checks naming a section the scenario does not run are
errors (:class:`ScenarioError`, a :class:`physmodel.IPMCError`) naming the key and the file.
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from physmodel.errors import IPMCError
from surrogate import FORMS

#: The order in which the runner executes the step tables.
STEP_ORDER = ("sweep", "surrogate", "control_route", "inversion", "widths", "taylor", "blackbox", "discrepancy",
              "next_measurement", "chain", "fixtures")


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
    """A finite TOML number (TOML also spells nan and inf, which no scenario value may be)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


NUM = _T("a finite number", _is_num, float)
INT = _T("an integer", lambda v: isinstance(v, int) and not isinstance(v, bool))
STR = _T("a string", lambda v: isinstance(v, str))
BOOL = _T("true or false", lambda v: isinstance(v, bool))
NUMS = _T("a non-empty list of finite numbers", lambda v: isinstance(v, list) and v and all(map(_is_num, v)),
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
#: [control_route]: the physics-calibrated route vs a direct schedule (scenarios/steps_control.py).
CONTROL_ROUTE_SCHEMA = {"free": STRS, "prior": _Map(NUM), "starts": INT, "seed": INT, "dense_temperatures_c": NUMS,
                        "form": _choice(*FORMS), "n_zeros": INT, "n_poles": INT,
                        "degree": INT, "temperature_c": NUM, "frequency_hz": NUM, "amplitude_mm": NUM,
                        "fs_hz": NUM, "duration_s": NUM, "max_voltage_v": NUM, "note": STR}
#: [chain]: seed 000's printed model vs physics × sensing chain (scenarios/steps_chain.py).
CHAIN_SCHEMA = {"temperature_c": NUM, "fmin_hz": NUM, "fmax_hz": NUM, "points": INT, "floor_db": NUM,
                "floor_deg": NUM, "free": STRS, "candidates": STRS, "documented": STRS, "max_steps": INT,
                "null_draws": INT, "null_refits": INT, "baseline_starts": INT, "alpha": NUM, "seed": INT,
                "preview": NUM_OR_STR, "decode_frequencies_hz": NUMS, "amplitude_mm": NUM, "fs_hz": NUM,
                "duration_s": NUM, "settle_s": NUM, "end_margin_s": NUM, "d_profile": NUMS}

#: [next_measurement]: ambiguous → the recommended measurement → named (scenarios/steps_next_measurement.py).
NEXT_MEASUREMENT_SCHEMA = {"effects": _Map(_Map(NUM)), "temperatures_c": NUMS, **_SWEEP_GRID, "fs_hz": NUM, "period_s": NUM,
                           "periods": INT, "transient_periods": INT, "rms": NUM, "oversample": INT, "output_noise_rms": NUM,
                           "noise_seed": INT, "next_noise_seed": INT, "free": STRS, "candidates": STRS, "null_draws": INT,
                           "null_refits": INT, "alpha": NUM, "seed": INT, "laws": STR, "baseline_starts": INT,
                           "band_limits_hz": NUMS, "temperature_limits_c": NUMS, "levels": NUMS, "power": NUM}

SECTIONS = {
    "chain": CHAIN_SCHEMA,
    "next_measurement": NEXT_MEASUREMENT_SCHEMA,
    "control_route": CONTROL_ROUTE_SCHEMA,
    "scenario": {"name": STR, "title": STR, "description": STR, "source": STR},
    "model": {"kind": _choice("actuator", "sensor"), "set": STR, "quantity": STR,
              "kernel": _choice("boundary_charge", "reciprocal"), "params": _Map(NUM)},
    "sweep": {"temperatures_c": NUMS, **_SWEEP_GRID, "held_out_c": NUMS, "plot_temperatures_c": NUMS,
              # source = "virtual_lab": the sweep is estimated from simulated time records
              # (scenarios/virtual_lab.py, which validates the values of these keys)
              "source": _choice("synthetic", "virtual_lab"), "excitation": _choice("multisine", "stepped"),
              "fs_hz": NUM, "period_s": NUM, "periods": INT, "transient_periods": INT, "rms": NUM, "amplitude": NUM,
              "phases": STR, "settle_s": NUM, "settle_periods": NUM, "min_measure_s": NUM, "oversample": INT,
              "estimator": _choice("h1", "h2"), "max_std_db": NUM},
    "noise": {"kind": _choice("none", "magphase", "complex", "time"), "sigma_db": NUM, "sigma_deg": NUM,
              "sigma": NUM, "seed": INT,
              # kind = "time" (virtual lab): noise and quantisation of the recorded signals [SI]
              "output_noise_rms": NUM, "input_noise_rms": NUM, "output_adc_step": NUM, "input_adc_step": NUM,
              "chain": NUMS, "chain_bandwidth_hz": NUM},
    "surrogate": {"form": _choice(*FORMS), "n_zeros": INT, "n_poles": INT,
                  "degree": INT, "method": _choice("joint", "two-stage"), "weighting": STR},
    "inversion": {"preview": NUM_OR_STR, "fs_hz": NUM, "duration_s": NUM, "settle_s": NUM, "end_margin_s": NUM,
                  "lead_s": NUM, "ramp_s": NUM, "max_voltage_v": NUM_OR_STR,
                  "experiments": _List({"name": STR, "temperature_c": NUM, "stimulus": _choice("sine", "release"),
                                        "amplitude_mm": NUM, "frequencies_hz": NUMS, "model_temperature_c": NUM,
                                        "t_release_s": NUM, "noise_rms": NUM, "seed": INT,
                                        "highpass_hz": NUM, "window_s": NUMS})},
    "widths": {"widths_m": NUMS, "temperature_c": NUM, **_SWEEP_GRID},
    "taylor": {"orders": INTS, "temperature_c": NUM, **_SWEEP_GRID, "band_hz": NUMS},
    "blackbox": {"orders": PAIRS, "temperature_c": NUM},
    "discrepancy": {"effects": _Map(_Map(NUM)), "free": STRS, "null_draws": INT, "null_refits": INT, "alpha": NUM,
                    "seed": INT, "laws": STR, "candidate_bounds": _Map(NUMS), "candidate_starts": _Map(NUM),
                    "plausible": _Map(NUMS), "prior": BOOL, "baseline_starts": INT},
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
    for dep, need in (("surrogate", "sweep"), ("control_route", "sweep"), ("inversion", "surrogate"), ("blackbox", "sweep"),
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
    _check_values(data, where)
    return Scenario(data["scenario"]["name"], where, data, quick)


#: Most samples of one time record (duration_s × fs_hz): checked before anything is allocated.
MAX_TIME_SAMPLES = 20_000_000
#: Most datasets a [fixtures] table may ask for.
MAX_FIXTURES = 1000


def _check_values(data: dict, where: str) -> None:
    """The domain of each value (the schema only checks types): every refusal names the table and
    key, the value and what is allowed, before the run allocates or computes anything."""
    from physmodel.data.sweep import MAX_SWEEP_LINES

    def need(ok, sec, key, value, expected):
        if not ok:
            raise ScenarioError(f"{where}: [{sec}] {key} = {value!r}: expected {expected}")

    def grid(sec, cfg, n_temps=1):
        lo, hi, n = cfg.get("fmin_hz", 1.0), cfg.get("fmax_hz", math.inf), cfg.get("points", 2)
        need(lo > 0, sec, "fmin_hz", lo, "> 0 Hz")
        need(hi > lo, sec, "fmax_hz", cfg.get("fmax_hz"), f"> fmin_hz ({lo:g} Hz)")
        need(2 <= n <= MAX_SWEEP_LINES // max(n_temps, 1), sec, "points", n,
             f"2 to {MAX_SWEEP_LINES // max(n_temps, 1)} (at most {MAX_SWEEP_LINES} lines over {n_temps} temperature(s))")

    def temps(sec, key, values):
        for t in values if isinstance(values, list) else [values]:
            need(t > -273.15, sec, key, values, "temperatures above absolute zero (-273.15 °C)")
            need(t <= 150.0, sec, key, values, "°C, at most 150 °C (no hydrated IPMC works above; kelvin? subtract 273.15)")

    from physmodel.plausible import PHYSICAL_LIMITS

    for key, v in (data["model"].get("params") or {}).items():      # L = 1e300: refused, not an SVD failure
        if key in PHYSICAL_LIMITS and v != 0 and not (key == "Rp_specific" and math.isinf(v)):
            lo, hi, unit = PHYSICAL_LIMITS[key]
            need(lo <= abs(v) <= hi, "model", f"params.{key}", v, f"a value in [{lo:g}, {hi:g}] {unit} (any physical IPMC)")
    if "sweep" in data:
        sw = data["sweep"]
        for key in ("temperatures_c", "held_out_c", "plot_temperatures_c"):
            if key in sw:
                temps("sweep", key, sw[key])
        grid("sweep", sw, len(sw["temperatures_c"]))
        missing = [t for t in sw.get("held_out_c", []) if t not in sw["temperatures_c"]]
        need(not missing, "sweep", "held_out_c", sw.get("held_out_c"), f"temperatures from temperatures_c {sw['temperatures_c']}")
        need(len(set(sw["temperatures_c"]) - set(sw.get("held_out_c", []))) >= 1, "sweep", "held_out_c",
             sw.get("held_out_c"), "at least one temperature left to fit")
    nz = data.get("noise", {})
    for key in ("sigma_db", "sigma_deg", "sigma"):
        if key in nz:
            need(nz[key] >= 0, "noise", key, nz[key], ">= 0")
    if "seed" in nz:
        need(nz["seed"] >= 0, "noise", "seed", nz["seed"], "a non-negative integer")
    if "surrogate" in data:
        from surrogate._fit import WEIGHTINGS

        sg = data["surrogate"]
        need(sg.get("n_zeros", 3) >= 0, "surrogate", "n_zeros", sg.get("n_zeros"), ">= 0")
        need(sg.get("n_poles", 3) >= 1, "surrogate", "n_poles", sg.get("n_poles"), ">= 1")
        need(sg.get("degree", 2) >= 0, "surrogate", "degree", sg.get("degree"), ">= 0 (polynomial degree in T)")
        need(sg.get("weighting", "auto") in WEIGHTINGS, "surrogate", "weighting", sg.get("weighting"), f"one of {list(WEIGHTINGS)}")
    if "inversion" in data:
        inv = data["inversion"]
        fs, dur = inv.get("fs_hz", 1000.0), inv.get("duration_s", 8.0)
        need(fs > 0, "inversion", "fs_hz", fs, "> 0 Hz")
        need(dur > 0, "inversion", "duration_s", dur, "> 0 s")
        need(dur * fs <= MAX_TIME_SAMPLES, "inversion", "duration_s", dur,
             f"at most {MAX_TIME_SAMPLES} samples at fs_hz = {fs:g} (duration_s × fs_hz = {dur * fs:.3g})")
        for key in ("settle_s", "end_margin_s", "lead_s", "ramp_s"):
            if key in inv:
                need(0 <= inv[key] < dur, "inversion", key, inv[key], f"in [0, duration_s = {dur:g}) s")
        mv = inv.get("max_voltage_v")             # default inversion.limits.DEFAULT_MAX_VOLTAGE
        if isinstance(mv, str):
            need(mv == "off", "inversion", "max_voltage_v", mv, "a voltage > 0 [V] or 'off'")
        elif mv is not None:
            need(math.isfinite(mv) and mv > 0, "inversion", "max_voltage_v", mv, "a voltage > 0 [V] or 'off'")
        pv = inv.get("preview", "inf")
        if isinstance(pv, str):
            need(pv in ("inf", "auto", "4/r0"), "inversion", "preview", pv, "'inf', 'auto', '4/r0' or seconds")
        else:
            need(0 < pv <= dur, "inversion", "preview", pv, f"seconds in (0, duration_s = {dur:g}]")
        for i, exp in enumerate(inv.get("experiments", [])):
            sec = f"inversion.experiments[{i}] ({exp['name']!r})"
            need(exp["amplitude_mm"] > 0, sec, "amplitude_mm", exp["amplitude_mm"], "> 0 mm")
            temps(sec, "temperature_c", exp["temperature_c"])
            if "model_temperature_c" in exp:
                temps(sec, "model_temperature_c", exp["model_temperature_c"])
            for fr in exp.get("frequencies_hz", []):
                need(0 < fr < fs / 2, sec, "frequencies_hz", exp["frequencies_hz"],
                     f"in (0, {fs / 2:g}) Hz, below the Nyquist frequency of fs_hz = {fs:g}")
            if "t_release_s" in exp:
                need(0 < exp["t_release_s"] < dur, sec, "t_release_s", exp["t_release_s"], f"in (0, duration_s = {dur:g}) s")
            if "noise_rms" in exp:
                need(exp["noise_rms"] >= 0, sec, "noise_rms", exp["noise_rms"], ">= 0")
            if "highpass_hz" in exp:
                need(0 < exp["highpass_hz"] < fs / 2, sec, "highpass_hz", exp["highpass_hz"], f"in (0, {fs / 2:g}) Hz")
            if "window_s" in exp:
                w = exp["window_s"]
                need(len(w) == 2 and 0 <= w[0] < w[1] <= dur, sec, "window_s", w, f"[t0, t1] with 0 <= t0 < t1 <= {dur:g} s")
            if "seed" in exp:
                need(exp["seed"] >= 0, sec, "seed", exp["seed"], "a non-negative integer")
    if "widths" in data:
        w = data["widths"]
        need(all(x > 0 for x in w.get("widths_m", [1])), "widths", "widths_m", w.get("widths_m"), "widths > 0 m")
        grid("widths", w)
    if "taylor" in data:
        t = data["taylor"]
        need(all(1 <= k <= 12 for k in t.get("orders", [1])), "taylor", "orders", t.get("orders"), "orders 1 to 12")
        grid("taylor", t)
    if "blackbox" in data:
        for nzb, npb in data["blackbox"]["orders"]:
            need(nzb >= 0 and npb >= 1, "blackbox", "orders", data["blackbox"]["orders"], "[n_zeros >= 0, n_poles >= 1] pairs")
    if "fixtures" in data:
        fx = data["fixtures"]
        need(1 <= fx.get("count", 3) <= MAX_FIXTURES, "fixtures", "count", fx.get("count"), f"1 to {MAX_FIXTURES}")
        temps("fixtures", "temperatures_c", fx.get("temperatures_c", [25.0]))
        grid("fixtures", fx, len(fx.get("temperatures_c", [25.0])))
        fs, dur = fx.get("fs_hz", 500.0), fx.get("step_duration_s", 1.0)
        need(fs > 0, "fixtures", "fs_hz", fs, "> 0 Hz")
        need(0 < dur and dur * fs <= MAX_TIME_SAMPLES, "fixtures", "step_duration_s", dur,
             f"> 0 s and at most {MAX_TIME_SAMPLES} samples at fs_hz = {fs:g}")
        if "seed" in fx:
            need(fx["seed"] >= 0, "fixtures", "seed", fx["seed"], "a non-negative integer")
        if "noise_rms_mm" in fx:
            need(fx["noise_rms_mm"] >= 0, "fixtures", "noise_rms_mm", fx["noise_rms_mm"], ">= 0")
    for name, chk in data.get("checks", {}).items():
        if "min" in chk and "max" in chk:
            need(chk["min"] <= chk["max"], f"checks.{name}", "min", chk["min"], f"<= max ({chk['max']:g})")


def read_toml(path, what: str, error: type[Exception]) -> dict:
    """The parsed TOML file at ``path``, or ``error`` naming the file (missing or not valid TOML)."""
    from physmodel.data.files import read_text
    from physmodel.errors import DataFormatError

    path = Path(path)
    if not path.is_file():
        raise error(f"{what} file {str(path)!r} does not exist")
    try:
        return tomllib.loads(read_text(path, f"{what} file"))
    except DataFormatError as exc:
        raise error(str(exc)) from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not valid TOML: {exc}") from None


def load_scenario(path, *, quick: bool = False) -> Scenario:
    """Read and validate a scenario TOML file; ``quick`` merges its ``[quick]`` table."""
    return parse_scenario(read_toml(path, "scenario", ScenarioError), str(path), quick=quick)


def bundled_scenarios() -> list[Path]:
    """The scenario files shipped with the package (``scenarios/*.toml``)."""
    return sorted(Path(__file__).parent.glob("*.toml"))


def bundled_studies() -> list[Path]:
    """The study files shipped with the package (``scenarios/studies/*.toml``)."""
    return sorted((Path(__file__).parent / "studies").glob("*.toml"))


def resolve_bundled(text: str, what: str = "scenario") -> Path:
    """A file path, or the name of a bundled scenario (``what="scenario"``) or study (``"study"``)."""
    p = Path(text)
    if p.is_file():
        return p
    found = bundled_scenarios() if what == "scenario" else bundled_studies()
    for b in found:
        if b.stem == text:
            return b
    raise ScenarioError(f"{what} {text!r} is neither a file nor a bundled {what} ({[b.stem for b in found]})")
