"""Helpers of the issue-28 fault-injection tests (not a test module): run ``ipmc`` in a subprocess
with a signal at a chosen phase (``phase_driver.py``), snapshot a folder, and the contract an
interrupted command must keep."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

#: The checkout whose packages the subprocesses run (``fuzz_report.py --root`` sets IPMC_FAULT_ROOT).
ROOT = Path(os.environ.get("IPMC_FAULT_ROOT") or Path(__file__).resolve().parents[2])
DRIVER = Path(__file__).with_name("phase_driver.py")


def env() -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
            "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}


def ipmc(argv, cwd, *, signal: str | None = None, phase: str | None = None, timeout: float = 600):
    """``ipmc argv`` in a subprocess (with ``signal`` delivered at ``phase`` when given)."""
    head = [sys.executable, str(DRIVER), signal, phase] if signal else [sys.executable, "-m", "scenarios.cli"]
    return subprocess.run([*head, *map(str, argv)], cwd=cwd, env=env(), capture_output=True, text=True,
                          timeout=timeout)


def snapshot(folder: Path) -> dict | None:
    """Every file under ``folder`` → its bytes (None when the folder does not exist)."""
    if not folder.exists():
        return None
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def leftovers(parent: Path) -> list[str]:
    """Temporary files or folders of an unfinished write anywhere under ``parent``."""
    return sorted(p.name for p in parent.rglob("*") if p.name.endswith((".part", ".old")) or ".part." in p.name)


def interrupted_contract(p, out: Path, before) -> str:
    """'' when an interrupted command kept the contract, else what it broke: exit 130, one line
    saying what was interrupted, no traceback, ``out`` as it was (absent, or the earlier complete
    result byte for byte) and no temporary file or folder left next to it."""
    err = p.stderr
    if "DRIVER: fired" not in err:
        return "the phase was never reached"
    if p.returncode != 130:
        return f"exit {p.returncode}, expected 130: {err[-600:]}"
    if "Traceback" in err:
        return f"a traceback: {err[-1200:]}"
    said = [ln for ln in err.splitlines() if "interrupted" in ln]
    if len(said) != 1 or not said[0].startswith("ipmc"):
        return f"expected one line saying what was interrupted, got {said}"
    if snapshot(out) != before:
        return f"{out} changed: {sorted(snapshot(out) or {})} (before: {sorted(before or {})})"
    left = leftovers(out.parent)
    if left:
        return f"temporary files left: {left}"
    return ""
