"""``diagnose`` reports progress within every stage (issue 27 item 6): each candidate refit, each
null refit and each pair fit says so, with the share of the whole done, so a progress bar never
sits still for a whole stage."""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "discrepancy"))
import independent_sensor as isn  # noqa: E402

from physmodel import get_parameter_set  # noqa: E402
from physmodel.data.sweep import FrequencySweep  # noqa: E402
from physmodel.estimation.diagnosis import STAGE_ENDS, ProgressMessage  # noqa: E402
from physmodel.estimation.discrepancy import diagnose  # noqa: E402
from physmodel.estimation.records import FreeParameter  # noqa: E402

F = isn.FREQUENCIES_HZ
SIG = 0.01 / math.sqrt(2)


def test_progress_moves_within_every_stage():
    b = dict(isn.START, d=isn.START["d"] * 1.2)
    H = isn.response(b, {"amplifier": {"f_a": 80.0, "ratio": 4.0}}, F)
    rng = np.random.default_rng(4)
    H = H * (1 + SIG * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)))
    data = FrequencySweep(np.full(F.size, isn.TEMPERATURE_C), F, H * 1e3, np.full(F.size, 20 / math.log(10) * SIG),
                          np.full(F.size, math.degrees(SIG)), "tip_displacement", "mm", "current", "uA")
    p0 = get_parameter_set("seed000_sensor_dev", T_ref=isn.START["T"])
    free = [FreeParameter("a0", 1e-4, 1e3, "log", p0.a0), FreeParameter("d", 1e-15, 1e-9, "log", p0.d),
            FreeParameter("kappa_e", 1e-8, 1e-3, "log", p0.kappa_e)]
    cands = ["amplifier_bandwidth", "time_delay", "laser_lag"]
    seen: list = []
    d = diagnose(data, p0, kind="sensor", free=free, candidates=cands, null_draws=500, null_refits=1,
                 baseline_starts=2, seed=1, progress=lambda m: seen.append((time.perf_counter(), m)))
    msgs = [m for _, m in seen]
    assert all(isinstance(m, ProgressMessage) and isinstance(m, str) for m in msgs)
    stages = [m.stage for m in msgs]
    # every stage reports, the candidate and null stages once per candidate refit at least
    assert set(stages) == set(STAGE_ENDS), stages
    assert stages.count("candidates") >= len(cands) + 1
    assert stages.count("null") >= len(cands) + 1
    fr = [m.fraction for m in msgs]
    assert all(b >= a for a, b in zip(fr, fr[1:])), fr          # never goes back (no basin restart here)
    assert fr[-1] == 1.0 and msgs[-1].startswith("verdict " + d.verdict)
    # within a stage the share grows step by step, not only at its end
    inner = [m.fraction for m in msgs if m.stage == "candidates"]
    assert len(set(inner)) >= len(cands)
