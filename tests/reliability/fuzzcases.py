"""Generators of bad (and some good) inputs for every file reader and ``ipmc`` entry point, and the
one judge of an outcome.  Shared by the hypothesis suite (``test_fuzz.py``, a ``random.Random``
drawn by hypothesis feeds each generator) and ``tests/benchmarks/fuzz_report.py`` (counts per
category).  Not a test module.

A case is judged **clear** when the command/reader (i) raised no traceback, (ii) ended with an
expected exit code (or, for a library call, raised :class:`physmodel.IPMCError` or returned), (iii)
when it refused the input, said which file/key/value (one of the case's ``tokens`` appears in the
message), and (iv) wrote or returned only finite numbers.  Anything else is **bad**.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import random
import warnings
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


# ----------------------------------------------------------------------------- the judge
@dataclass
class Case:
    category: str
    what: str
    argv: list | None = None                 # an ``ipmc`` command line ...
    func: Callable | None = None             # ... or a library call
    expect: tuple = (2,)                     # acceptable exit codes ("ok" results count as 0)
    tokens: tuple = ()                       # one must appear in a refusal's message
    post: Callable | None = None             # extra check after the call: returns "" or a complaint
    cwd: Path | None = None


@dataclass
class Outcome:
    verdict: str                             # "clear" | "bad"
    code: int | None
    detail: str = ""
    message: str = field(default="", repr=False)


def _named(msg: str, tokens) -> bool:
    return not tokens or any(str(t) in msg for t in tokens)


def judge(case: Case) -> Outcome:
    from physmodel.errors import IPMCError

    err, out = io.StringIO(), io.StringIO()
    old = os.getcwd()
    code, exc = None, None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            if case.cwd is not None:
                os.chdir(case.cwd)
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
                if case.argv is not None:
                    from scenarios.cli import main

                    try:
                        code = main([str(a) for a in case.argv])
                    except SystemExit as se:          # argparse: usage error, exit 2
                        code = se.code if isinstance(se.code, int) else 2
                else:
                    try:
                        res = case.func()
                        code = 0
                        if res is not None and not _finite(res):
                            return Outcome("bad", 0, "returned non-finite numbers")
                    except IPMCError as e:
                        code, exc = 2, e
        except MemoryError:
            return Outcome("bad", None, "MemoryError")
        except Exception as e:  # noqa: BLE001 - a traceback is exactly what is being counted
            return Outcome("bad", None, f"traceback {type(e).__name__}: {str(e)[:160]}")
        finally:
            os.chdir(old)
    msg = err.getvalue() + (str(exc) if exc is not None else "")
    runtime = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    if runtime:
        return Outcome("bad", code, f"RuntimeWarning: {str(runtime[0].message)[:120]}", msg)
    if "Traceback" in msg:
        return Outcome("bad", code, "traceback in stderr", msg)
    if code not in case.expect:
        return Outcome("bad", code, f"exit {code}, expected {case.expect}: {msg.strip()[-200:]}", msg)
    if code == 2 and not _named(msg, case.tokens):
        return Outcome("bad", code, f"message names none of {case.tokens}: {msg.strip()[-200:]}", msg)
    if case.post is not None:
        complaint = case.post()
        if complaint:
            return Outcome("bad", code, complaint, msg)
    return Outcome("clear", code, "", msg)


def _finite(res) -> bool:
    vals = []
    if hasattr(res, "response"):
        vals = [res.response, res.frequency_hz, res.temperature_c]
    elif hasattr(res, "values") and isinstance(getattr(res, "values"), dict):
        vals = list(res.values.values())
    elif isinstance(res, np.ndarray):
        vals = [res]
    return all(np.all(np.isfinite(np.asarray(v))) for v in vals)


def csv_all_finite(path) -> str:
    """'' when every numeric field of the CSV at ``path`` is finite (comment lines skipped)."""
    p = Path(path)
    if not p.exists():
        return ""
    for line in p.read_text(encoding="utf-8", errors="replace").splitlines():
        if line.startswith("#") or not line.strip():
            continue
        for f in line.split(","):
            try:
                v = float(f)
            except ValueError:
                continue
            if not math.isfinite(v):
                return f"{p.name} holds non-finite values ({line[:80]!r})"
    return ""


# ----------------------------------------------------------------------------- fixtures
def valid_sweep(d: Path, name="sweep.csv", temps=(20.0, 40.0), points=8, noise=True):
    from physmodel import ActuatorModel, get_parameter_set
    from physmodel.data.files import write_sweep
    from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep

    m = ActuatorModel(get_parameter_set("seed002_table3"))
    sw = synthesize_sweep(m, "M", np.geomspace(0.5, 20, points), list(temps),
                          MagnitudePhaseNoise(0.1, 1.0) if noise else None, 1 if noise else None)
    return write_sweep(sw, d / name)


def _params_record() -> dict:
    from physmodel import get_parameter_set
    from physmodel.formats import finite_json as _finite_json

    return _finite_json(get_parameter_set("seed002_table3").to_dict())


MINI_SCENARIO = {
    "scenario": {"name": "mini"},
    "model": {"kind": "actuator", "set": "seed002_table3"},
    "sweep": {"temperatures_c": [20.0, 40.0], "fmin_hz": 0.5, "fmax_hz": 20.0, "points": 12},
    "surrogate": {"form": "zpk", "n_zeros": 2, "n_poles": 2, "degree": 1},
    "checks": {"lines": {"metric": "sweep.lines", "min": 1}},
}


def toml_dumps(doc: dict, prefix: str = "") -> str:
    """A small TOML writer for the cases (tables, arrays of tables, scalars and lists)."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, float):
            return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{json.dumps(k)} = {val(x)}" for k, x in v.items()) + "}"
        return repr(v)

    lines, tables = [], []
    for k, v in doc.items():
        if isinstance(v, dict) and not (prefix and k == "params"):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v))
        else:
            lines.append(f"{json.dumps(k) if not k.replace('_', '').isalnum() else k} = {val(v)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, list):
            for x in v:
                out += f"\n[[{name}]]\n" + toml_dumps(x, name)
        else:
            out += f"\n[{name}]\n" + toml_dumps(v, name)
    return out


def write_scenario(d: Path, doc: dict, name="s.toml") -> Path:
    p = d / name
    p.write_text(toml_dumps(doc), encoding="utf-8")
    return p


def _deep(doc):
    return json.loads(json.dumps(doc))


# ----------------------------------------------------------------------------- generators
BAD_BYTES = [b"\xff", b"\xfe\xfe", b"\xc3(", b"\x80abc", b"\xed\xa0\x80"]


def gen_encoding(rnd: random.Random, d: Path) -> Case:
    """Non-UTF-8 bytes in a text input of one of the commands."""
    bad = rnd.choice(BAD_BYTES)
    target = rnd.choice(["fit", "calibrate", "invert", "run", "study", "diagnose", "params"])
    if target in ("fit", "calibrate", "invert"):
        src = valid_sweep(d).read_bytes() if target != "invert" else b"time_s,u\n0,1\n0.01,2\n0.02,3\n"
        lines = src.split(b"\n")
        k = rnd.randrange(len(lines))
        pos = rnd.randrange(len(lines[k]) + 1)
        lines[k] = lines[k][:pos] + bad + lines[k][pos:]
        f = d / "in.csv"
        f.write_bytes(b"\n".join(lines))
        argv = {"fit": ["fit", f, "--out", d / "o", "--quiet"],
                "calibrate": ["calibrate", f, "--set", "seed002_table3", "--free", "alpha0", "--out", d / "o", "--quiet"],
                "invert": ["invert", f, "--num=1", "--den=1,1", "--out", d / "o.csv", "--quiet"]}[target]
        return Case("encoding", f"{target}: {bad!r} in line {k}", argv, tokens=("in.csv",))
    if target in ("run", "study", "diagnose"):
        text = {"run": toml_dumps(MINI_SCENARIO),
                "study": 'name = "s"\n' if False else '[study]\nkind = "actuator"\nset = "dev"\nseed = 1\n'
                         'temperatures_c = [20.0]\nsamples = 2\n[study.parameters.d]\ndistribution = "uniform"\n'
                         'low = 1e-11\nhigh = 2e-11\n',
                "diagnose": 'data = "sweep.csv"\nkind = "actuator"\nset = "seed002_table3"\n'}[target].encode()
        if target == "diagnose":
            valid_sweep(d)
        pos = rnd.randrange(len(text) + 1)
        f = d / "in.toml"
        f.write_bytes(text[:pos] + b"# " + bad + b"\n" + text[pos:] if rnd.random() < 0.5 else text[:pos] + bad + text[pos:])
        argv = {"run": ["run", f, "--out", d / "o", "--quiet"], "study": ["study", f, "--out", d / "o.csv", "--quiet", "--serial"],
                "diagnose": ["diagnose", f, "--out", d / "o", "--quiet"]}[target]
        return Case("encoding", f"{target} TOML: {bad!r} at {pos}", argv, tokens=("in.toml",))
    text = json.dumps(_params_record()).encode()
    pos = rnd.randrange(1, len(text))
    f = d / "p.json"
    f.write_bytes(text[:pos] + bad + text[pos:])
    return Case("encoding", f"parameter JSON: {bad!r} at {pos}",
                ["sweep", "--params-json", f, "--points", 4, "--temperatures", "20", "--out", d / "o.csv", "--quiet"],
                tokens=("p.json",))


_CSV_EDITS = ("delete_char", "swap_lines", "garbage_token", "duplicate_line", "truncate", "nonfinite",
              "extra_column", "drop_column", "empty_field", "header_unit", "reverse_rows", "blank", "bom")


def gen_sweep_csv(rnd: random.Random, d: Path) -> Case:
    """A valid tidy sweep CSV with one random edit, read by ``read_sweep``."""
    from physmodel.data.files import read_sweep

    f = valid_sweep(d, "s.csv", points=rnd.randint(2, 6))
    lines = f.read_text(encoding="utf-8").split("\n")
    edit = rnd.choice(_CSV_EDITS)
    body = [i for i, l in enumerate(lines) if l and not l.startswith("#")]
    k = rnd.choice(body)
    if edit == "delete_char" and lines[k]:
        j = rnd.randrange(len(lines[k]))
        lines[k] = lines[k][:j] + lines[k][j + 1:]
    elif edit == "swap_lines":
        a, b = rnd.sample(range(len(lines)), 2)
        lines[a], lines[b] = lines[b], lines[a]
    elif edit == "garbage_token":
        parts = lines[k].split(",")
        parts[rnd.randrange(len(parts))] = rnd.choice(["abc", "1,2", "--", "0x10", "1e", "∞", "🙂", "1_0"])
        lines[k] = ",".join(parts)
    elif edit == "duplicate_line":
        lines.insert(k, lines[k])
    elif edit == "truncate":
        lines = lines[:k] + [lines[k][: rnd.randrange(len(lines[k]) + 1)]]
    elif edit == "nonfinite":
        parts = lines[k].split(",")
        parts[rnd.randrange(len(parts))] = rnd.choice(["nan", "inf", "-inf", "1e400", "-1e400"])
        lines[k] = ",".join(parts)
    elif edit == "extra_column":
        lines[k] += ",1.0"
    elif edit == "drop_column":
        lines = [",".join(l.split(",")[:-1]) if l and not l.startswith("#") else l for l in lines]
    elif edit == "empty_field":
        parts = lines[k].split(",")
        parts[rnd.randrange(len(parts))] = ""
        lines[k] = ",".join(parts)
    elif edit == "header_unit":
        lines = [rnd.choice(["# input: voltage [furlong]", "# input: voltage", "# output:", "#"]) if l.startswith("# input")
                 else l for l in lines]
    elif edit == "reverse_rows":
        head = [l for l in lines if l.startswith("#")] + [lines[body[0]]]
        lines = head + list(reversed([lines[i] for i in body[1:]]))
    elif edit == "blank":
        lines = [l for l in lines if l.startswith("#")]
    text = "\n".join(lines)
    if edit == "bom":
        f.write_bytes(b"\xef\xbb\xbf" + text.encode())
        return Case("sweep_csv", "BOM", func=lambda: read_sweep(f), expect=(0,))
    f.write_text(text, encoding="utf-8")
    return Case("sweep_csv", edit, func=lambda: read_sweep(f), expect=(0, 2), tokens=("s.csv",))


def _npz_parts(d: Path):
    from physmodel.data.files import read_sweep

    f = valid_sweep(d, "v.npz", points=5)
    with np.load(f, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}, read_sweep


def gen_sweep_binary(rnd: random.Random, d: Path) -> Case:
    """Malformed NPZ / MAT sweeps."""
    from physmodel.data.files import read_sweep

    kind = rnd.choice(["npz", "mat"])
    f = d / f"b.{kind}"
    if kind == "npz":
        arrays, _ = _npz_parts(d)
        edit = rnd.choice(["no_header", "header_not_json", "header_list", "header_no_input", "no_imag",
                           "length_mismatch", "empty_file", "garbage", "big_extra", "object", "strings", "2d",
                           "nonfinite", "header_bytes_json_number"])
        a = dict(arrays)
        if edit == "no_header":
            a.pop("header")
        elif edit == "header_not_json":
            a["header"] = np.array("{not json")
        elif edit == "header_list":
            a["header"] = np.array("[1, 2]")
        elif edit == "header_no_input":
            h = json.loads(str(a["header"]))
            h.pop("input")
            a["header"] = np.array(json.dumps(h))
        elif edit == "header_bytes_json_number":
            a["header"] = np.array("3")
        elif edit == "no_imag":
            a.pop("response_imag")
        elif edit == "length_mismatch":
            key = rnd.choice(["frequency_hz", "magnitude_db", "response_real", "temperature_c"])
            a[key] = a[key][:-1]
        elif edit == "strings":
            a["magnitude_db"] = np.array(["x"] * a["magnitude_db"].size)
        elif edit == "2d":
            a["phase_deg"] = np.stack([a["phase_deg"]] * 2)
        elif edit == "nonfinite":
            a[rnd.choice(["magnitude_db", "response_real", "frequency_hz"])][0] = rnd.choice([np.nan, np.inf])
        if edit == "empty_file":
            f.write_bytes(b"")
        elif edit == "garbage":
            f.write_bytes(bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 200))))
        elif edit == "object":
            buf = io.BytesIO()
            np.save(buf, np.array([{"a": 1}], dtype=object), allow_pickle=True)
            with zipfile.ZipFile(f, "w") as zf:
                for k, v in a.items():
                    if k != "magnitude_db":
                        b2 = io.BytesIO()
                        np.save(b2, v)
                        zf.writestr(k + ".npy", b2.getvalue())
                zf.writestr("magnitude_db.npy", buf.getvalue())
        elif edit == "big_extra":
            with zipfile.ZipFile(f, "w", compression=zipfile.ZIP_DEFLATED) as zf:
                for k, v in a.items():
                    b2 = io.BytesIO()
                    np.save(b2, v)
                    zf.writestr(k + ".npy", b2.getvalue())
                with zf.open("extra.npy", "w", force_zip64=True) as fh:     # 400 MB of zeros, ~0.4 MB on disk
                    np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": (50_000_000,)})
                    chunk = bytes(8_000_000)
                    for _ in range(50):
                        fh.write(chunk)
            return Case("sweep_binary", "npz with a 400 MB extra array", func=lambda: read_sweep(f), expect=(0, 2),
                        tokens=("b.npz",))
        else:
            with open(f, "wb") as fh:
                np.savez(fh, **a)
        return Case("sweep_binary", f"npz {edit}", func=lambda: read_sweep(f), expect=(2,), tokens=("b.npz",))
    from scipy.io import savemat

    sw = read_sweep(valid_sweep(d, "v.csv", points=5))
    cols = {"temperature_c": sw.temperature_c, "frequency_hz": sw.frequency_hz, "magnitude_db": sw.magnitude_db,
            "phase_deg": sw.phase_deg, "response": sw.response,
            "input": f"{sw.input_name} [{sw.input_unit}]", "output": f"{sw.output_name} [{sw.output_unit}]",
            "metadata_json": json.dumps(sw.metadata)}
    edit = rnd.choice(["no_frequency", "no_input", "metadata_not_json", "length_mismatch", "string_field", "empty_file",
                       "garbage", "complex_frequency", "nonfinite", "cell"])
    if edit == "no_frequency":
        cols.pop("frequency_hz")
    elif edit == "no_input":
        cols.pop("input")
    elif edit == "metadata_not_json":
        cols["metadata_json"] = "{oops"
    elif edit == "length_mismatch":
        cols["phase_deg"] = cols["phase_deg"][:-1]
    elif edit == "string_field":
        cols["magnitude_db"] = "abc"
    elif edit == "complex_frequency":
        cols["frequency_hz"] = cols["frequency_hz"] * (1 + 1j)
    elif edit == "nonfinite":
        cols["magnitude_db"] = cols["magnitude_db"].copy()
        cols["magnitude_db"][1] = np.nan
    elif edit == "cell":
        cols["input"] = np.array([1, 2, 3])
    if edit == "empty_file":
        f.write_bytes(b"")
    elif edit == "garbage":
        f.write_bytes(b"MATLAB 5.0 MAT-file" + bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 300))))
    else:
        savemat(f, cols)
    return Case("sweep_binary", f"mat {edit}", func=lambda: read_sweep(f), expect=(2,), tokens=("b.mat",))


def gen_params_json(rnd: random.Random, d: Path) -> Case:
    """Parameter JSON with one wrong value, read by ``ipmc sweep --params-json``."""
    rec = _params_record()
    key = rnd.choice(["L", "W", "h", "d", "E", "xi", "alpha0", "T_ref", "Rp_specific"])
    edit = rnd.choice(["string", "null", "true", "list", "object", "negative", "missing", "unknown", "law_no_law",
                       "law_unknown", "law_value_string", "top_list", "wrapped_bad_version", "laws_not_object"])
    tok = (key,)
    if edit == "string":
        rec[key] = rnd.choice(["abc", "", "1 m", "nan"])
    elif edit == "null":
        rec[key] = None
    elif edit == "true":
        rec[key] = True
    elif edit == "list":
        rec[key] = [1.0]
    elif edit == "object":
        rec[key] = {"value": 1}
    elif edit == "negative":
        rec[key] = -1.0 if key not in ("alpha0",) else "x"
    elif edit == "missing":
        rec.pop(key)
    elif edit == "unknown":
        rec["bogus"] = 1.0
        tok = ("bogus",)
    elif edit.startswith("law"):
        law = rnd.choice(sorted(rec["laws"]))
        tok = (law,)
        if edit == "law_no_law":
            rec["laws"][law] = {k: v for k, v in rec["laws"][law].items() if k != "law"}
        elif edit == "law_unknown":
            rec["laws"][law]["law"] = "quantum"
        else:
            extra = [k for k in rec["laws"][law] if k not in ("law", "law_name")]
            if extra:
                rec["laws"][law][extra[0]] = "abc"
                tok = (law, extra[0])
            else:
                rec["laws"][law] = 5
    elif edit == "top_list":
        rec = [rec]
        tok = ("p.json",)
    elif edit == "wrapped_bad_version":
        rec = {"format": "ipmc-parameter-set", "version": "one", "parameters": rec}
        tok = ("version",)
    elif edit == "laws_not_object":
        rec["laws"] = "arrhenius"
        tok = ("laws",)
    f = d / "p.json"
    f.write_text(json.dumps(rec), encoding="utf-8")
    return Case("params_json", f"{key} {edit}", expect=(0, 2) if (edit, key) == ("missing", "T_ref") else (2,),
                argv=["sweep", "--params-json", f, "--points", 4, "--temperatures", "20", "--out", d / "o.csv", "--quiet"],
                tokens=tok + ("p.json",) if edit != "unknown" else tok)


_SURROGATE_CACHE: dict = {}


def _surrogate_json(d: Path) -> dict:
    if "doc" not in _SURROGATE_CACHE:
        from surrogate import RationalFit

        f = np.geomspace(1, 100, 30)
        s = 2j * np.pi * f
        h = 50 / (s + 60)
        r = RationalFit(0, 1, raise_on_failure=False).fit(f, np.full(f.size, 25.0), h)
        r.model.to_json(d / "model.json")
        _SURROGATE_CACHE["doc"] = json.loads((d / "model.json").read_text())
    return _deep(_SURROGATE_CACHE["doc"])


def gen_surrogate_json(rnd: random.Random, d: Path) -> Case:
    doc = _surrogate_json(d)
    edit = rnd.choice(["no_structure", "no_params", "params_string", "params_short", "not_json", "list", "empty",
                       "schema", "structure_wrong", "nan_param"])
    if edit == "no_structure":
        doc.pop("structure", None)
    elif edit == "no_params":
        doc.pop("params", None)
    elif edit == "params_string":
        doc["params"] = "abc"
    elif edit == "params_short":
        doc["params"] = doc.get("params", [0])[:-1] if isinstance(doc.get("params"), list) else []
    elif edit == "list":
        doc = [doc]
    elif edit == "empty":
        doc = {}
    elif edit == "schema":
        doc["schema"] = "something.else"
    elif edit == "structure_wrong":
        doc["structure"] = "zpk"
    elif edit == "nan_param":
        doc["params"] = [float("nan")] * len(doc.get("params", [1]))
    f = d / "m.json"
    f.write_text("{oops" if edit == "not_json" else json.dumps(doc), encoding="utf-8")
    sig = d / "u.csv"
    sig.write_text("time_s,u\n" + "".join(f"{i * 0.01},{math.sin(i / 5)}\n" for i in range(50)))
    return Case("surrogate_json", edit, ["invert", sig, "--surrogate", f, "--temperature", 25, "--out", d / "o.csv",
                                         "--quiet"], tokens=("m.json",))


def gen_scenario(rnd: random.Random, d: Path) -> Case:
    """A small valid scenario with one out-of-domain value."""
    doc = _deep(MINI_SCENARIO)
    edit = rnd.choice(["orders_0_0", "orders_30_30", "degree_neg", "weighting", "points_huge", "points_1",
                       "fmin_neg", "fmax_lt_fmin", "held_out_missing", "temps_nan", "preview_long", "amplitude_0",
                       "amplitude_nan", "nyquist", "fixtures_count", "fixtures_count_neg", "check_div0", "sigma_neg",
                       "unknown_set", "param_negative", "temps_cold", "duration_huge", "window_empty"])
    key = {"orders_0_0": "n_zeros", "orders_30_30": "n_poles", "degree_neg": "degree", "weighting": "weighting",
           "points_huge": "points", "points_1": "points", "fmin_neg": "fmin_hz", "fmax_lt_fmin": "fmax_hz",
           "held_out_missing": "held_out_c", "temps_nan": "temperatures_c", "preview_long": "preview",
           "amplitude_0": "amplitude_mm", "amplitude_nan": "amplitude_mm", "nyquist": "frequencies_hz",
           "fixtures_count": "count", "fixtures_count_neg": "count", "check_div0": "ratio",
           "sigma_neg": "sigma_db", "unknown_set": "set", "param_negative": "W", "temps_cold": "temperatures_c",
           "duration_huge": "duration_s", "window_empty": "window_s"}[edit]
    sur, sweep = doc["surrogate"], doc["sweep"]
    exp = {"name": "e", "temperature_c": 30.0, "amplitude_mm": 0.1, "frequencies_hz": [1.0]}
    inv = {"fs_hz": 200.0, "duration_s": 4.0, "experiments": [exp]}
    expect = (2,)
    if edit == "orders_0_0":
        sur.update(n_zeros=0, n_poles=0)
    elif edit == "orders_30_30":
        sur.update(n_zeros=30, n_poles=30)
    elif edit == "degree_neg":
        sur["degree"] = -1
    elif edit == "weighting":
        sur["weighting"] = "bogus"
    elif edit == "points_huge":
        sweep["points"] = 100_000_000
    elif edit == "points_1":
        sweep["points"] = 1
    elif edit == "fmin_neg":
        sweep["fmin_hz"] = -1.0
    elif edit == "fmax_lt_fmin":
        sweep["fmax_hz"] = 0.1
    elif edit == "held_out_missing":
        sweep["held_out_c"] = [33.0]
    elif edit == "temps_nan":
        sweep["temperatures_c"] = [20.0, float("nan")]
    elif edit == "temps_cold":
        sweep["temperatures_c"] = [20.0, -300.0]
    elif edit == "sigma_neg":
        doc["noise"] = {"kind": "magphase", "sigma_db": -1.0, "sigma_deg": 1.0, "seed": 1}
    elif edit == "unknown_set":
        doc["model"]["set"] = "no_such_set"
    elif edit == "param_negative":
        doc["model"]["params"] = {"W": -1.0}
    elif edit == "fixtures_count" or edit == "fixtures_count_neg":
        doc["fixtures"] = {"count": 0 if edit == "fixtures_count" else -2, "formats": ["csv"]}
    elif edit == "check_div0":
        doc["sweep"]["temperatures_c"] = [20.0]          # one temperature: the difference is 0 dB
        doc.pop("surrogate")
        doc["checks"]["ratio"] = {"metric": "sweep.cold_minus_hot_db_at_max / sweep.max_db_difference", "max": 1.0}
        expect = (3,)
    else:
        doc["inversion"] = inv
        if edit == "preview_long":
            inv["preview"] = 100.0
        elif edit == "amplitude_0":
            exp["amplitude_mm"] = 0.0
        elif edit == "amplitude_nan":
            exp["amplitude_mm"] = float("nan")
        elif edit == "nyquist":
            inv["fs_hz"] = 500.0
            exp["frequencies_hz"] = [400.0]
        elif edit == "duration_huge":
            inv["duration_s"] = 1e9
        elif edit == "window_empty":
            exp["window_s"] = [10.0, 11.0]
    f = write_scenario(d, doc)
    out = d / "out"

    def post():
        if edit == "check_div0" and not (out / "report.md").exists():
            return "no report.md after a check that divides by zero"
        return ""

    tokens = ("n_zeros", "n_poles") if edit == "orders_0_0" else (key,)
    return Case("scenario", edit, ["run", f, "--out", out, "--quiet"], expect=expect, tokens=tokens, post=post)


def gen_scenario_name(rnd: random.Random, d: Path) -> Case:
    """A scenario name that is a path: the default folder must stay in the working directory."""
    name = rnd.choice(["/../../x", "../x", "a/../../b", "..", "/tmp/x", "x/y", "~/z", "\\..\\w", " ", "a\x00b"])
    doc = _deep(MINI_SCENARIO)
    doc["scenario"]["name"] = name
    doc.pop("surrogate")
    work = d / "w" / "cwd"
    work.mkdir(parents=True, exist_ok=True)
    f = write_scenario(d, doc)
    before = set(os.listdir(d))

    def post():
        escaped = set(os.listdir(d)) - before - {"w"}
        outside = [p for p in (d / "w").iterdir() if p.name != "cwd"]
        return f"wrote outside the working directory: {sorted(escaped) + [p.name for p in outside]}" \
            if escaped or outside else ""

    return Case("output_folder", f"name {name!r}", ["run", f, "--quiet"], expect=(0, 2), tokens=("name",),
                post=post, cwd=work)


def gen_output_folder(rnd: random.Random, d: Path) -> Case:
    """A second, different run into a folder that holds the first run's results must be refused."""
    doc = _deep(MINI_SCENARIO)
    doc.pop("surrogate")
    first = write_scenario(d, doc, "a.toml")
    doc["scenario"]["name"] = "other"
    second = write_scenario(d, doc, "b.toml")
    out = d / "shared"
    from scenarios.cli import main

    with contextlib.redirect_stderr(io.StringIO()):
        main(["run", str(first), "--out", str(out), "--quiet"])
    report = (out / "report.md").read_text() if (out / "report.md").exists() else ""
    which = rnd.choice(["run", "demo", "fit", "calibrate"])
    if which == "run":
        argv = ["run", second, "--out", out, "--quiet"]
    elif which == "demo":
        argv = ["demo", "--quick", "--out", out, "--quiet"]
    elif which == "fit":
        argv = ["fit", out / "data" / "sweep.csv", "--out", out, "--quiet", "--zeros", 0, "--poles", 1]
    else:
        argv = ["calibrate", out / "data" / "sweep.csv", "--set", "seed002_table3", "--free", "alpha0",
                "--out", out, "--quiet"]

    def post():
        now = (out / "report.md").read_text() if (out / "report.md").exists() else ""
        return "" if now == report else "the first run's report.md was overwritten"

    return Case("output_folder", f"{which} into another run's folder", argv, tokens=("shared",), post=post)


def gen_cli_options(rnd: random.Random, d: Path) -> Case:
    edit = rnd.choice(["seed_neg", "out_dir", "out_file_for_folder", "plot_txt", "scheduler_bad", "fmin_nan",
                       "points_0", "temps_cold", "temps_text", "sigma_neg", "fit_out_file", "calibrate_out_file",
                       "invert_plot_txt", "starts_0", "fit_exclude_all", "fit_zeros_neg", "sweep_points_huge",
                       "study_workers_0"])
    sweep = ["sweep", "--points", 4, "--temperatures", "20", "--quiet"]
    (d / "dir").mkdir(exist_ok=True)
    (d / "file.txt").write_text("x")
    if edit == "seed_neg":
        return Case("cli_options", edit, sweep + ["--noise", "magphase", "--seed", -1, "--out", d / "o.csv"], tokens=("--seed",))
    if edit == "out_dir":
        return Case("cli_options", edit, sweep + ["--out", d / "dir"], tokens=("dir",))
    if edit == "out_file_for_folder":
        return Case("cli_options", edit, ["run", write_scenario(d, MINI_SCENARIO), "--out", d / "file.txt", "--quiet"],
                    tokens=("file.txt",))
    if edit == "plot_txt":
        return Case("cli_options", edit, sweep + ["--out", d / "o.csv", "--plot", d / "p.txt"], tokens=("p.txt",))
    if edit == "invert_plot_txt":
        sig = d / "u.csv"
        sig.write_text("time_s,u\n0,0\n0.01,1\n0.02,0\n")
        return Case("cli_options", edit, ["invert", sig, "--num=1", "--den=1,1", "--out", d / "o.csv", "--plot",
                                          d / "p.txt", "--quiet"], tokens=("p.txt",))
    if edit == "scheduler_bad":
        sched = rnd.choice(["not a url", "tcp://", "http://[::1", "tcp://host:notaport"])
        spec = d / "st.toml"
        spec.write_text('[study]\nkind = "actuator"\nset = "dev"\nseed = 1\ntemperatures_c = [20.0]\nsamples = 2\n'
                        'points = 3\n[study.parameters.d]\ndistribution = "uniform"\nlow = 1e-11\nhigh = 2e-11\n')
        return Case("cli_options", f"{edit} {sched!r}", ["study", spec, "--out", d / "o.csv", "--scheduler", sched,
                                                         "--quiet"], tokens=("--scheduler", sched))
    if edit == "fmin_nan":
        return Case("cli_options", edit, ["sweep", "--fmin", "nan", "--out", d / "o.csv", "--quiet"], tokens=("--fmin", "nan"))
    if edit == "points_0":
        return Case("cli_options", edit, ["sweep", "--points", 0, "--out", d / "o.csv", "--quiet"], tokens=("--points",))
    if edit == "sweep_points_huge":
        return Case("cli_options", edit, ["sweep", "--points", 10 ** 9, "--out", d / "o.csv", "--quiet"],
                    tokens=("--points", "points"))
    if edit == "temps_cold":
        return Case("cli_options", edit, ["sweep", "--points", 4, "--temperatures=-300", "--out", d / "o.csv", "--quiet"],
                    tokens=("-300",))
    if edit == "temps_text":
        return Case("cli_options", edit, ["sweep", "--points", 4, "--temperatures", "20,abc", "--out", d / "o.csv",
                                          "--quiet"], tokens=("--temperatures",))
    if edit == "sigma_neg":
        return Case("cli_options", edit, sweep + ["--noise", "magphase", "--sigma-db", "-1", "--seed", 1, "--out",
                                                  d / "o.csv"], tokens=("sigma",))
    if edit in ("fit_out_file", "calibrate_out_file"):
        f = valid_sweep(d)
        cmd = ["fit", f, "--zeros", 0, "--poles", 1, "--degree", 1] if edit == "fit_out_file" else \
            ["calibrate", f, "--set", "seed002_table3", "--free", "alpha0"]
        return Case("cli_options", edit, cmd + ["--out", d / "file.txt", "--quiet"], tokens=("file.txt",))
    if edit == "starts_0":
        return Case("cli_options", edit, ["calibrate", valid_sweep(d), "--set", "seed002_table3", "--free", "alpha0",
                                          "--starts", 0, "--out", d / "o", "--quiet"], tokens=("--starts",))
    if edit == "fit_exclude_all":
        f = valid_sweep(d, temps=(20.0,))
        return Case("cli_options", edit, ["fit", f, "--exclude", 20, "--out", d / "o", "--quiet"], tokens=("--exclude",))
    if edit == "fit_zeros_neg":
        return Case("cli_options", edit, ["fit", valid_sweep(d), "--zeros", -1, "--out", d / "o", "--quiet"],
                    tokens=("--zeros", "zeros"))
    spec = d / "st.toml"
    spec.write_text('[study]\nkind = "actuator"\nset = "dev"\nseed = 1\ntemperatures_c = [20.0]\nsamples = 2\n'
                    'points = 3\n[study.parameters.d]\ndistribution = "uniform"\nlow = 1e-11\nhigh = 2e-11\n')
    return Case("cli_options", edit, ["study", spec, "--out", d / "o.csv", "--workers", 0, "--quiet"], tokens=("--workers",))


def gen_study_diagnose_toml(rnd: random.Random, d: Path) -> Case:
    """Study and diagnose TOML files with a field of the wrong type."""
    bad = rnd.choice(['"x"', "[1, 2]", "{ a = 1 }", "true", "-1", "1.5", "nan"])
    if rnd.random() < 0.5:
        key = rnd.choice(["samples", "seed", "temperatures_c", "points", "chunk_size", "fmin_hz", "fmax_hz", "name",
                          "set", "kind", "quantity", "median", "sigma", "sigma_db"])
        base = {"kind": '"actuator"', "set": '"dev"', "seed": "1", "temperatures_c": "[20.0]", "samples": "2",
                "points": "3", "name": '"s"'}
        if key in base or key in ("chunk_size", "fmin_hz", "fmax_hz", "quantity"):
            base[key] = bad
        noise = f'\n[study.noise]\nkind = "magphase"\nsigma_db = {bad if key == "sigma_db" else "0.1"}\nsigma_deg = 1.0\n'
        par = (f'\n[study.parameters.d]\ndistribution = "lognormal"\nmedian = {bad if key == "median" else "4e-11"}\n'
               f'sigma = {bad if key == "sigma" else "0.3"}\n')
        text = "[study]\n" + "".join(f"{k} = {v}\n" for k, v in base.items()) + noise + par
        f = d / "st.toml"
        f.write_text(text)
        return Case("study_diagnose_toml", f"study {key} = {bad}", ["study", f, "--out", d / "o.csv", "--serial",
                                                                    "--quiet"], expect=(0, 2), tokens=(key,),
                    post=lambda: csv_all_finite(d / "o.csv"))
    valid_sweep(d)
    key = rnd.choice(["alpha", "seed", "free", "candidates", "null_draws", "null_refits", "kind", "quantity", "data",
                      "set", "geometry", "L", "baseline_effects", "out", "kernel"])
    base = {"data": '"sweep.csv"', "kind": '"actuator"', "set": '"seed002_table3"', "null_draws": "200",
            "null_refits": "0", "free": '["alpha0"]', "candidates": '["time_delay"]'}
    if key not in ("L",):
        base[key] = bad
    text = "".join(f"{k} = {v}\n" for k, v in base.items() if k not in ("geometry", "baseline_effects"))
    if key == "geometry":
        text += f"geometry = {bad}\n"
    elif key == "baseline_effects":
        text += f"baseline_effects = {bad}\n"
    elif key == "L":
        text += f"[geometry]\nL = {bad}\n"
    f = d / "ex.toml"
    f.write_text(text)
    return Case("study_diagnose_toml", f"diagnose {key} = {bad}", ["diagnose", f, "--out", d / "o", "--quiet"],
                expect=(0, 2), tokens=(key,))


def gen_physics(rnd: random.Random, d: Path) -> Case:
    """Library calls at the edges of the physics' domain: finite results or an IPMCError."""
    from physmodel import ActuatorModel, SensorModel, get_parameter_set

    kind = rnd.choice(["actuator", "sensor"])
    p = get_parameter_set("seed002_table3" if kind == "actuator" else "seed000_sensor_dev")
    m = ActuatorModel(p) if kind == "actuator" else SensorModel(p)
    edit = rnd.choice(["huge", "tiny", "complex", "nan", "negative", "T_cold", "T_hot", "bool_param", "string_param",
                       "range", "object"])
    f = [10.0]
    T = [25.0]
    if edit == "huge":
        f = [rnd.choice([1e13, 1e20, 1e300, 1.7e308])]
    elif edit == "tiny":
        f = [rnd.choice([1e-10, 1e-30, 1e-300, 5e-324])]
    elif edit == "complex":
        f = [complex(10, rnd.choice([1.0, -3.0, 1e-9]))]
    elif edit == "nan":
        f = [float("nan")]
    elif edit == "negative":
        f = [-10.0]
    elif edit == "T_cold":
        T = [rnd.choice([-273.15, -300.0, -1e9])]
    elif edit == "T_hot":
        T = [rnd.choice([1e6, 1e300])]
    elif edit == "range":
        f = list(np.geomspace(1e-9, 1e12, 25))
    elif edit == "object":
        f = ["10"]
    if edit in ("bool_param", "string_param"):
        bad = True if edit == "bool_param" else "0.01"
        return Case("physics", f"L = {bad!r}", func=lambda: p.replace(L=bad), expect=(2,), tokens=("L",))
    return Case("physics", f"{kind} {edit} f={f[:1]} T={T}", func=lambda: m.frequency_response(f, T),
                expect=(0, 2), tokens=("freq", "temperature", str(f[0])[:5], str(T[0])[:5]))


def gen_invert_values(rnd: random.Random, d: Path) -> Case:
    """``ipmc invert`` on signals with extreme samples: a clear refusal or finite outputs."""
    n = rnd.randint(20, 200)
    u = [math.sin(i / 7) for i in range(n)]
    k = rnd.randrange(n)
    u[k] = rnd.choice([1e308, -1e308, 1e300, 1.7976931348623157e308, 1e200])
    t = [i * 0.01 for i in range(n)]
    sig = d / "u.csv"
    sig.write_text("time_s,u\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(t, u)))
    out = d / "o.csv"
    model = rnd.choice([["--num=1,2", "--den=1,1"], ["--num=0.05,0.3,1", "--den=1,3,2"], ["--num=0.01,1", "--den=1,1"],
                        ["--num=1,-1", "--den=1,2"]])
    return Case("invert_values", f"sample {u[k]:g} at {k}/{n}", ["invert", sig, *model, "--preview", "inf", "--out",
                                                               out, "--quiet"], expect=(0, 2),
                tokens=("u.csv",), post=lambda: csv_all_finite(out))


def gen_interop(rnd: random.Random, d: Path) -> Case:
    """What one command writes, another reads (exit 0 expected)."""
    which = rnd.choice(["simulate_invert", "params_roundtrip", "bom_fit", "bom_invert", "bom_toml", "bom_json"])
    if which == "simulate_invert":
        from scenarios.cli import main

        sim = d / "sim.csv"
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            main(["simulate", "--set", "seed002_table3", "--experiment", "sine", "--duration", "0.5", "--fs", "200",
                  "--out", str(sim), "--quiet"])
        return Case("interop", which, ["invert", sim, "--num=1,2", "--den=1,1", "--out", d / "o.csv", "--quiet"],
                    expect=(0,))
    if which == "params_roundtrip":
        from physmodel import get_parameter_set
        from physmodel.estimation.records import CalibrationResult  # noqa: F401 - the writer's module
        from physmodel.parameter_sets import save_parameter_set

        f = save_parameter_set(get_parameter_set("seed002_table3").replace(name="cal"), d / "parameters.json")
        return Case("interop", which, ["sweep", "--params-json", f, "--points", 4, "--temperatures", "20", "--out",
                                       d / "o.csv", "--quiet"], expect=(0,))
    bom = b"\xef\xbb\xbf"
    if which == "bom_fit":
        f = valid_sweep(d, temps=(25.0,))
        f.write_bytes(bom + f.read_bytes())
        return Case("interop", which, ["fit", f, "--zeros", 0, "--poles", 1, "--out", d / "o", "--quiet"], expect=(0, 3))
    if which == "bom_invert":
        f = d / "u.csv"
        f.write_bytes(bom + b"time_s,u\n0,0\n0.01,1\n0.02,0.5\n0.03,0\n")
        return Case("interop", which, ["invert", f, "--num=1,2", "--den=1,1", "--out", d / "o.csv", "--quiet"], expect=(0,))
    if which == "bom_json":
        f = d / "p.json"
        f.write_bytes(bom + json.dumps(_params_record()).encode())
        return Case("interop", which, ["sweep", "--params-json", f, "--points", 4, "--temperatures", "20", "--out",
                                       d / "o.csv", "--quiet"], expect=(0,))
    doc = _deep(MINI_SCENARIO)
    doc.pop("surrogate")
    f = write_scenario(d, doc)
    f.write_bytes(bom + f.read_bytes())
    return Case("interop", which, ["run", f, "--out", d / "o", "--quiet"], expect=(0,))


def gen_goodness_of_fit(rnd: random.Random, d: Path) -> Case:
    """Random magnitudes/phases that no model fits: calibrate and fit must not report success."""
    from physmodel.data.files import read_sweep, write_sweep

    sw = read_sweep(valid_sweep(d, temps=(25.0,), points=rnd.randint(15, 30), noise=False))
    r = np.random.default_rng(rnd.randrange(2 ** 32))
    resp = 10 ** r.uniform(-2, 1, sw.response.size) * np.exp(1j * r.uniform(-np.pi, np.pi, sw.response.size))
    declared = rnd.random() < 0.5
    from dataclasses import replace

    sw = replace(sw, response=resp, magnitude_std_db=np.full(resp.size, 0.1) if declared else None,
                 phase_std_deg=np.full(resp.size, 1.0) if declared else None)
    f = write_sweep(sw, d / "rand.csv")
    if rnd.random() < 0.5:
        return Case("goodness_of_fit", f"calibrate, noise {'declared' if declared else 'estimated'}",
                    ["calibrate", f, "--set", "seed002_table3", "--free", "alpha0", "--free", "xi", "--starts", 1,
                     "--out", d / "o", "--quiet"], expect=(3,))
    return Case("goodness_of_fit", f"fit, noise {'declared' if declared else 'estimated'}",
                ["fit", f, "--zeros", 1, "--poles", 2, "--out", d / "o", "--quiet"], expect=(3,))


#: category -> generator; the order of the report.
GENERATORS = {
    "encoding": gen_encoding,
    "sweep_csv": gen_sweep_csv,
    "sweep_binary": gen_sweep_binary,
    "params_json": gen_params_json,
    "surrogate_json": gen_surrogate_json,
    "scenario": gen_scenario,
    "output_folder": lambda rnd, d: (gen_scenario_name if rnd.random() < 0.5 else gen_output_folder)(rnd, d),
    "cli_options": gen_cli_options,
    "study_diagnose_toml": gen_study_diagnose_toml,
    "physics": gen_physics,
    "invert_values": gen_invert_values,
    "interop": gen_interop,
    "goodness_of_fit": gen_goodness_of_fit,
}

# the issue-28 fault classes (signals at chosen phases, huge counts, fake schedulers, kelvin,
# physical ranges, incomplete result folders)
from faultcases import FAULT_GENERATORS  # noqa: E402

GENERATORS.update(FAULT_GENERATORS)
