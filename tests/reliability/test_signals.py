"""Issue 28: a signal at any moment — start-up imports, the computation, the write phase, the final
rename, inside study workers — ends the command with exit 130, one line saying what was
interrupted, no traceback, and the output as it was (nothing, or the earlier complete result).
The signal is injected at a chosen phase by ``phase_driver.py`` (os.kill on itself when a named
file appears, a module is imported, or the temporary result folder is created)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
import fuzzcases  # noqa: E402
from _faults import env, interrupted_contract, ipmc, leftovers, snapshot  # noqa: E402


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    d = tmp_path_factory.mktemp("signals")
    fuzzcases.valid_sweep(d, "sweep.csv", temps=(20.0, 40.0), points=12)
    fuzzcases.valid_sweep(d, "sweep3.csv", temps=(20.0, 35.0, 50.0), points=12)
    return d


CAL = ["calibrate", "sweep.csv", "--set", "seed002_table3", "--free", "d", "--starts", "1", "--quiet"]


@pytest.mark.parametrize("sig,phase", [("SIGINT", "write:parameters.json"), ("SIGTERM", "write:parameters.json"),
                                       ("SIGTERM", "write:report.md"), ("SIGINT", "begin"),
                                       ("SIGINT", "twice:calibration.json"),
                                       ("SIGTERM", "write:.ipmc-complete.json")])
def test_calibrate_interrupted_in_its_write_phase_leaves_nothing(work, sig, phase):
    out = work / f"cal-{sig}-{phase.replace(':', '-')}"
    p = ipmc([*CAL, "--out", out.name], work, signal=sig, phase=phase)
    assert not interrupted_contract(p, out, None), interrupted_contract(p, out, None)
    assert f"by {sig}" in p.stderr or phase.startswith("twice")


def test_an_interrupted_rerun_keeps_the_previous_complete_result(work):
    out = work / "cal-rerun"
    assert ipmc([*CAL, "--out", out.name], work).returncode == 0
    before = snapshot(out)
    assert ".ipmc-complete.json" in before
    p = ipmc([*CAL, "--out", out.name, "--seed", "3"], work, signal="SIGTERM", phase="write:bode.png")
    assert not interrupted_contract(p, out, before), interrupted_contract(p, out, before)
    # the complete result is still usable downstream
    q = ipmc(["sweep", "--params-json", out / "parameters.json", "--points", "5", "--out", "s.csv", "--quiet"], work)
    assert q.returncode == 0, q.stderr


def test_diagnose_interrupted_as_report_json_appears_leaves_nothing(work):
    out = work / "diag"
    p = ipmc(["diagnose", "--data", "sweep.csv", "--set", "seed002_table3", "--null-draws", "200", "--null-refits",
              "0", "--baseline-starts", "1", "--out", out.name, "--quiet"], work, signal="SIGINT",
             phase="write:report.json")
    assert not interrupted_contract(p, out, None), interrupted_contract(p, out, None)


def test_fit_interrupted_as_model_json_appears_leaves_nothing(work):
    out = work / "fit"
    p = ipmc(["fit", "sweep3.csv", "--zeros", "2", "--poles", "2", "--degree", "1", "--out", out.name, "--quiet",
              "--accept-misfit"], work, signal="SIGTERM", phase="write:model.json")
    assert not interrupted_contract(p, out, None), interrupted_contract(p, out, None)


@pytest.mark.parametrize("sig,module", [("SIGINT", "scipy.optimize"), ("SIGTERM", "scipy.optimize"),
                                        ("SIGINT", "scenarios.commands.calibrate"), ("SIGTERM", "matplotlib")])
def test_a_signal_during_start_up_imports_gives_no_traceback(work, sig, module):
    out = work / f"cal-import-{sig}-{module}"
    p = ipmc([*CAL, "--out", out.name], work, signal=sig, phase=f"import:{module}")
    assert not interrupted_contract(p, out, None), interrupted_contract(p, out, None)


def _study(work: Path) -> Path:
    text = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
    text = text.replace("samples = 200", "samples = 20000").replace("chunk_size = 25", "chunk_size = 100")
    (work / "long.toml").write_text(text.replace("points = 40", "points = 400"))
    return work / "long.toml"


@pytest.mark.parametrize("sig,group", [("SIGINT", True), ("SIGTERM", True), ("SIGTERM", False)])
def test_a_study_interrupted_while_its_workers_run(work, sig, group):
    """Ctrl-C reaches the whole process group (every worker too); a SIGTERM may reach only the
    parent.  Either way: no worker traceback, the parent reports in one line, cancels the chunks not
    started, the workers finish the one they hold (a worker killed while sending its result back
    would leave the parent waiting forever at exit), and no table (or temporary file) is left."""
    spec = _study(work)
    out = work / f"study-{sig}-{group}.csv"
    p = subprocess.Popen([sys.executable, "-m", "scenarios.cli", "study", str(spec), "--out", str(out), "--workers",
                          "2", "--quiet"], cwd=work, env=env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    deadline = time.monotonic() + 120
    kids: list[str] = []
    while time.monotonic() < deadline and len(kids) < 2:
        kids = subprocess.run(["pgrep", "-P", str(p.pid)], capture_output=True, text=True).stdout.split()
        time.sleep(0.05)
    assert len(kids) >= 2, "the workers never started"
    time.sleep(0.5)                                       # inside their chunks
    t0 = time.monotonic()
    (os.killpg if group else os.kill)(p.pid, getattr(signal, sig))
    _, err = p.communicate(timeout=120)
    stopped = time.monotonic() - t0
    assert p.returncode == 130, err[-1500:]
    assert "Traceback" not in err, err[-2000:]
    assert [ln for ln in err.splitlines() if ln.strip()] == [ln for ln in err.splitlines() if "ipmc study: interrupted" in ln]
    assert stopped < 30, f"took {stopped:.1f} s to stop"      # a chunk of 100 samples: about a second
    assert not out.exists() and not leftovers(work)
    for k in kids:                                        # no orphaned worker
        assert not Path(f"/proc/{k}").exists() or "zombie" in Path(f"/proc/{k}/status").read_text().lower()


@pytest.mark.parametrize("cmd", ["sweep", "simulate"])
@pytest.mark.parametrize("sig,phase", [("SIGINT", "temp:o"), ("SIGTERM", "temp:o"), ("SIGTERM", "write:o.csv")])
def test_a_data_file_and_its_plot_appear_together_or_not_at_all(work, cmd, sig, phase):
    d = work / f"pair-{cmd}-{sig}-{phase.replace(':', '-')}"
    d.mkdir()
    argv = [cmd, "--out", "o.csv", "--plot", "o.png", "--quiet"] + (["--points", "10"] if cmd == "sweep"
                                                                      else ["--duration", "0.5"])
    p = ipmc(argv, d, signal=sig, phase=phase)
    assert p.returncode == 130 and "Traceback" not in p.stderr, p.stderr[-1500:]
    files = sorted(f.name for f in d.iterdir())
    # interrupted while the files were being written: neither; at the final renames: both (complete)
    assert files in ([], ["o.csv", "o.png"]), files
    assert files == ([] if phase.startswith("temp") else ["o.csv", "o.png"])


def test_held_defers_an_interrupt_to_the_end_of_the_block():
    from physmodel import interrupts

    done = []
    with interrupts.handling():
        with pytest.raises(KeyboardInterrupt):
            with interrupts.held():
                signal.raise_signal(signal.SIGTERM)     # to this (main) thread, before it returns
                for _ in range(1000):             # the handler runs between these bytecodes ...
                    done.append(1)
        assert len(done) == 1000                  # ... and did not break the block
        assert interrupts.requested() == signal.SIGTERM


def test_an_interrupt_handled_in_one_block_does_not_stop_later_work():
    """After an interrupted ``handling()`` block, the same process (a notebook) works on."""
    from physmodel import interrupts

    with interrupts.handling():
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGTERM)
            for _ in range(1000):
                pass
        assert interrupts.requested() == signal.SIGTERM
    assert interrupts.requested() is None
    interrupts.check()                            # raises if the old interrupt were still recorded


@pytest.mark.parametrize("sig,phase", [("SIGTERM", "temp:o"), ("SIGTERM", "write:o.csv")])
def test_frf_writes_its_sweep_and_figure_together_or_not_at_all(work, sig, phase):
    d = work / f"pair-frf-{phase.replace(':', '-')}"
    d.mkdir()
    made = ipmc(["simulate", "--out", "rec.csv", "--duration", "4", "--quiet"], d)
    assert made.returncode == 0, made.stderr[-1500:]
    p = ipmc(["frf", "rec.csv", "--input", "voltage", "--output", "tip_displacement", "--temperature", "25",
              "--out", "o.csv", "--plot", "o.png", "--quiet"], d, signal=sig, phase=phase)
    assert p.returncode == 130 and "Traceback" not in p.stderr, p.stderr[-1500:]
    files = sorted(f.name for f in d.iterdir() if f.name != "rec.csv")
    assert files == ([] if phase.startswith("temp") else ["o.csv", "o.png"]), files
