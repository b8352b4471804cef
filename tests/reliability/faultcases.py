"""Generators of the issue-28 fault classes for the fuzz suite (``test_fuzz.py``) and the fuzz
benchmark (``tests/benchmarks/fuzz_report.py``), judged by ``fuzzcases.judge``.  Not a test module.

- ``interrupt_phase``: SIGINT/SIGTERM (or both) at a random phase of a random command — a module
  being imported, the temporary result folder appearing, any one of the result files appearing,
  the completion marker — into a fresh folder or over an earlier complete result;
- ``huge_counts``: a count or record length far beyond memory (null draws, study size, excitation
  length) on the command line or in a TOML file;
- ``scheduler``: a fake ``--scheduler`` that is silent, speaks HTTP, greets with a banner, closes,
  or announces an exabyte frame;
- ``kelvin``: a kelvin-looking temperature in any command that reads temperatures;
- ``physical_range``: a parameter decades outside any physical range (or a plausible one, which
  must work or be refused clearly);
- ``result_folder``: reading a parameter file out of a folder an interrupted run of an older
  version left (a prefix of calibrate's write order), a temporary folder, a folder with a broken
  marker, or a complete one — the expectation follows from how the folder was made, not from the
  rule's code.
"""

from __future__ import annotations

import atexit
import json
import shutil
import socket
import tempfile
import threading
from pathlib import Path

from fuzzcases import MINI_SCENARIO, Case, _deep, valid_sweep, write_scenario

_CACHE: dict[str, Path] = {}


def _cache_dir() -> Path:
    if "dir" not in _CACHE:
        d = Path(tempfile.mkdtemp(prefix="ipmc-faults-"))
        atexit.register(shutil.rmtree, d, True)
        _CACHE["dir"] = d
    return _CACHE["dir"]


def _calibration() -> Path:
    """One complete calibration folder per process (copied into cases)."""
    if "cal" not in _CACHE:
        import contextlib
        import io

        from scenarios.cli import main

        d = _cache_dir()
        sweep = valid_sweep(d, "sweep.csv", temps=(20.0, 40.0), points=10)
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            assert main(["calibrate", str(sweep), "--set", "seed002_table3", "--free", "d", "--starts", "1",
                         "--out", str(d / "cal"), "--quiet"]) == 0
        _CACHE["cal"] = d / "cal"
    return _CACHE["cal"]


# ------------------------------------------------------------------------- interrupts (subprocess)
#: What each command writes, in order (the phases a signal can land on), and its command line.
_WRITES = {
    "calibrate": ("model.json", "parameters.json", "calibration.json", "bode.png", "report.md"),
    "fit": ("bode_20C.png", "model.json", "report.md"),
    "diagnose": ("report.json", "summary.md", "model.json", "bode_before.png"),
}
_IMPORTS = ("numpy", "scipy.optimize", "scipy.linalg", "matplotlib", "casadi", "physmodel.actuator",
            "scenarios.commands._common")


def gen_interrupt_phase(rnd, d: Path) -> Case:
    from _faults import interrupted_contract, ipmc, snapshot

    cmd = rnd.choice(sorted(_WRITES))
    valid_sweep(d, "sweep.csv", temps=(20.0, 35.0, 50.0), points=10)
    out = d / "out"
    argv = {"calibrate": ["calibrate", "sweep.csv", "--set", "seed002_table3", "--free", "d", "--starts", "1"],
            "fit": ["fit", "sweep.csv", "--zeros", "2", "--poles", "2", "--degree", "1", "--accept-misfit"],
            "diagnose": ["diagnose", "--data", "sweep.csv", "--set", "seed002_table3", "--null-draws", "200",
                         "--null-refits", "0", "--baseline-starts", "1"]}[cmd] + ["--out", "out", "--quiet"]
    kind = rnd.choice(["write", "write", "import", "begin", "twice", "marker"])
    phase = {"write": lambda: f"write:{rnd.choice(_WRITES[cmd])}", "twice": lambda: f"twice:{rnd.choice(_WRITES[cmd])}",
             "import": lambda: f"import:{rnd.choice(_IMPORTS)}", "begin": lambda: "begin",
             "marker": lambda: "write:.ipmc-complete.json"}[kind]()
    sig = rnd.choice(["SIGINT", "SIGTERM"])
    rerun = rnd.random() < 0.4

    def run():
        if rerun and ipmc(argv, d).returncode not in (0, 3):
            raise AssertionError("the earlier complete run failed")
        before = snapshot(out)
        p = ipmc(argv + (["--force"] if rerun and cmd != "fit" else []), d, signal=sig, phase=phase)
        if "DRIVER: fired" not in p.stderr and p.returncode in (0, 3) and phase.startswith("import:"):
            return None                          # that module is not imported by this command
        problem = interrupted_contract(p, out, before)
        if problem:
            raise AssertionError(problem)
        return None

    return Case("interrupt_phase", f"{cmd} {sig} at {phase}" + (" over an earlier result" if rerun else ""),
                func=run, expect=(0,))


# ------------------------------------------------------------------------------------ huge counts
def gen_huge_counts(rnd, d: Path) -> Case:
    n = int(10 ** rnd.uniform(8.5, 30))
    which = rnd.choice(["null_draws_flag", "null_draws_toml", "multisine", "chirp", "study"])
    if which in ("null_draws_flag", "null_draws_toml"):
        sweep = valid_sweep(d, "sweep.csv", points=8)
        if which == "null_draws_flag":
            return Case("huge_counts", f"diagnose --null-draws {n}",
                        ["diagnose", "--data", sweep, "--set", "seed002_table3", "--null-draws", n, "--out", d / "o",
                         "--quiet"], tokens=("--null-draws",))
        (d / "e.toml").write_text(f'data = "{sweep}"\nset = "seed002_table3"\nnull_draws = {n}\nout = "{d / "o"}"\n')
        return Case("huge_counts", f"null_draws = {n} in TOML", ["diagnose", d / "e.toml", "--quiet"],
                    tokens=("null_draws",))
    if which == "multisine":
        period = max(1.0, n / 1000.0 / 9)
        return Case("huge_counts", f"excite multisine period {period:g} s",
                    ["excite", "multisine", "--fs", "1000", "--period", f"{period:.0f}", "--count", "5", "--fmin", "1",
                     "--fmax", "10", "--out", d / "x.npz", "--quiet"], tokens=("--period",))
    if which == "chirp":
        return Case("huge_counts", f"excite chirp {n / 1000:g} s",
                    ["excite", "chirp", "--f0", "1", "--f1", "10", "--sweep-s", f"{n / 1000:g}", "--fs", "1000",
                     "--out", d / "x.npz", "--quiet"], tokens=("--sweep-s",))
    text = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
    (d / "s.toml").write_text(text.replace("samples = 200", f"samples = {n}"))
    return Case("huge_counts", f"study samples = {n}", ["study", d / "s.toml", "--out", d / "t.csv", "--quiet",
                                                         "--serial"], tokens=("samples",))


# -------------------------------------------------------------------------------- fake schedulers
def _fake_server(mode: str):
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen(8)
    conns = []

    def loop():
        while True:
            try:
                c, _ = sock.accept()
            except OSError:
                return
            conns.append(c)
            try:
                if mode == "banner":
                    c.sendall(b"HTTP/1.1 200 OK\r\n\r\n")
                elif mode == "ssh":
                    c.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
                elif mode == "close":
                    c.close()
                elif mode == "huge":
                    c.sendall((1 << 62).to_bytes(8, "little"))
                elif mode == "zero":
                    c.sendall(bytes(8))
            except OSError:
                pass

    threading.Thread(target=loop, daemon=True).start()

    def close():
        sock.close()
        for c in conns:
            c.close()
        return ""

    return sock.getsockname()[1], close


def gen_scheduler(rnd, d: Path) -> Case:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return Case("scheduler", "distributed not installed: the refusal names the extra",
                    ["study", "actuator_mc", "--out", d / "t.csv", "--quiet", "--scheduler", "tcp://127.0.0.1:1"],
                    tokens=("dask",))
    mode = rnd.choice(["silent", "banner", "ssh", "close", "huge", "zero"])
    port, close = _fake_server(mode)
    addr = f"tcp://127.0.0.1:{port}"
    return Case("scheduler", f"a {mode} server at {addr}",
                ["study", "actuator_mc", "--out", d / "t.csv", "--quiet", "--scheduler", addr,
                 "--scheduler-timeout", "1"], tokens=(addr,), post=close)


# ------------------------------------------------------------------------------------------ kelvin
def set_temperature_column(path: Path, new) -> Path:
    """Rewrite the ``temperature_c`` column of the sweep CSV at ``path`` with ``new(old value)``."""
    lines = path.read_text().splitlines()
    head = next(i for i, ln in enumerate(lines) if ln and not ln.startswith("#"))
    col = lines[head].split(",").index("temperature_c")
    for i in range(head + 1, len(lines)):
        if lines[i] and not lines[i].startswith("#"):
            f = lines[i].split(",")
            f[col] = repr(float(new(float(f[col]))))
            lines[i] = ",".join(f)
    path.write_text("\n".join(lines) + "\n")
    return path


def gen_kelvin(rnd, d: Path) -> Case:
    t = round(rnd.uniform(150.5, 500.0), 2)
    which = rnd.choice(["sweep", "simulate", "feedforward", "study", "run", "calibrate", "fit"])
    if which == "sweep":
        return Case("kelvin", f"sweep --temperatures {t}", ["sweep", "--temperatures", f"20,{t}", "--points", "5",
                                                              "--out", d / "o.csv", "--quiet"], tokens=("--temperatures",))
    if which == "simulate":
        return Case("kelvin", f"simulate --temperature {t}", ["simulate", "--temperature", t, "--out", d / "o.csv",
                                                                "--quiet"], tokens=("--temperature",))
    if which == "feedforward":
        return Case("kelvin", f"feedforward --temperature {t}",
                    ["feedforward", d / "m.json", "--temperature", t, "--reference", "sine", "--amplitude", "0.1",
                     "--frequency", "1", "--out", d / "ff", "--quiet"], tokens=("--temperature",))
    if which == "study":
        text = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
        (d / "s.toml").write_text(text.replace("temperatures_c = [20.0, 35.0, 50.0]", f"temperatures_c = [20.0, {t}]"))
        return Case("kelvin", f"study temperatures_c {t}", ["study", d / "s.toml", "--out", d / "t.csv", "--quiet"],
                    tokens=("temperatures_c",))
    if which == "run":
        doc = _deep(MINI_SCENARIO)
        doc["sweep"]["temperatures_c"] = [20.0, t]
        doc.pop("surrogate")
        return Case("kelvin", f"scenario temperatures_c {t}", ["run", write_scenario(d, doc), "--out", d / "r",
                                                                "--quiet"], tokens=("temperatures_c",))
    p = set_temperature_column(valid_sweep(d, "k.csv", temps=(20.0, 40.0), points=8), lambda c: t if c > 30 else c)
    argv = (["calibrate", p, "--set", "seed002_table3", "--free", "d", "--out", d / "c", "--quiet"] if which == "calibrate"
            else ["fit", p, "--out", d / "f", "--quiet"])
    return Case("kelvin", f"{which}: temperature_c {t} in the sweep", argv, tokens=(str(p), "temperature_c"))


# -------------------------------------------------------------------------------- physical range
def gen_physical_range(rnd, d: Path) -> Case:
    from physmodel.plausible import PHYSICAL_LIMITS

    name = rnd.choice(sorted(PHYSICAL_LIMITS))
    lo, hi, _ = PHYSICAL_LIMITS[name]
    if rnd.random() < 0.75:
        v = (hi * 10 ** rnd.uniform(0.5, 300)) if rnd.random() < 0.5 else (lo / 10 ** rnd.uniform(0.5, 300))
        expect, what = (2,), "outside"
    else:
        v = lo * (hi / lo) ** rnd.uniform(0.05, 0.95)
        expect, what = (0, 2), "inside"
    cmd = rnd.choice(["sweep", "simulate"])
    argv = [cmd, "--param", f"{name}={v:.6g}", "--out", d / "o.csv", "--quiet"] + (["--points", "8"] if cmd == "sweep"
                                                                                    else ["--duration", "0.5"])
    return Case("physical_range", f"{cmd} {name} = {v:.3g} ({what} the physical limits)", argv, expect=expect,
                tokens=(name,))


# ---------------------------------------------------------------------------------- result folders
def gen_result_folder(rnd, d: Path) -> Case:
    cal = _calibration()
    order = _WRITES["calibrate"]
    state = rnd.choice(["prefix", "prefix", "complete", "marker", "part", "broken_marker", "by_hand"])
    folder = d / (".cal.4242.beef.part" if state == "part" else "cal")
    folder.mkdir()
    if state == "prefix":                    # an older version interrupted after k files
        k = rnd.randint(2, len(order) - 1)
        files, expect = order[:k], (2,)
    elif state == "by_hand":
        from physmodel import get_parameter_set, save_parameter_set

        save_parameter_set(get_parameter_set("seed002_table3"), folder / "parameters.json")
        files, expect = (), (0,)
    else:
        files = order
        expect = (0,) if state in ("complete", "marker") else (2,)
    for f in files:
        shutil.copyfile(cal / f, folder / f)
    if state == "marker":
        shutil.copyfile(cal / ".ipmc-complete.json", folder / ".ipmc-complete.json")
    elif state == "broken_marker":
        (folder / ".ipmc-complete.json").write_text(rnd.choice(["", "{", "[]", json.dumps({"format": "other"})]))
    option = rnd.choice(["--params-json", "--model", "--set"])
    target = folder / ("model.json" if option == "--model" and "model.json" in files else "parameters.json")
    return Case("result_folder", f"{option} from a {state} folder ({', '.join(files) or 'hand-written'})",
                ["sweep", option, target, "--points", "5", "--out", d / "s.csv", "--quiet"], expect=expect,
                tokens=(str(folder),))


FAULT_GENERATORS = {"interrupt_phase": gen_interrupt_phase, "huge_counts": gen_huge_counts, "scheduler": gen_scheduler,
                    "kelvin": gen_kelvin, "physical_range": gen_physical_range, "result_folder": gen_result_folder}
