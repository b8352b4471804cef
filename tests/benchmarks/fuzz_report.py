"""Counts of inputs tried / refused clearly or handled / bad, per category, over every file reader
and ``ipmc`` entry point (issue 13) and the fault classes of issue 28 (``faultcases.py``: a signal
at a random phase of a command, huge counts, fake Dask schedulers, kelvin, physical ranges,
incomplete result folders).  The generators and the judge are those of the hypothesis suite
(``tests/reliability/fuzzcases.py``); here each category draws ``--n`` seeded cases.

    python tests/benchmarks/fuzz_report.py --n 40                 # this checkout
    python tests/benchmarks/fuzz_report.py --n 40 --root OTHER    # another checkout (e.g. before)
    python tests/benchmarks/fuzz_report.py --n 20 --only interrupt_phase,huge_counts,scheduler,kelvin,physical_range,result_folder

"clear": no traceback, an expected exit code, a refusal that names the file/key/value, finite
outputs.  "bad": anything else (the first few are listed).  The address space is capped
(``--memory-gb``) so an input that would exhaust memory counts as bad instead of stalling the host.
"""

from __future__ import annotations

import argparse
import os
import random
import resource
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=30, help="cases per category (default 30)")
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("--root", default=str(HERE), help="checkout whose packages are tested")
    ap.add_argument("--only", help="comma-separated categories")
    ap.add_argument("--memory-gb", type=float, default=4.0)
    ap.add_argument("--show", type=int, default=4, help="bad cases listed per category")
    a = ap.parse_args()
    lim = int(a.memory_gb * 2 ** 30)
    resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    sys.path.insert(0, str(Path(a.root).resolve()))
    os.environ["IPMC_FAULT_ROOT"] = str(Path(a.root).resolve())        # subprocess cases run that checkout
    sys.path.insert(1, str(HERE / "tests" / "reliability"))
    import fuzzcases

    import physmodel

    print(f"packages from {Path(physmodel.__file__).parent.parent}; {a.n} cases per category, seed {a.seed}")
    cats = a.only.split(",") if a.only else list(fuzzcases.GENERATORS)
    rows = []
    for cat in cats:
        gen = fuzzcases.GENERATORS[cat]
        counts, bad, t0 = Counter(), [], time.perf_counter()
        for i in range(a.n):
            rnd = random.Random(f"{a.seed}-{cat}-{i}")
            with tempfile.TemporaryDirectory() as tmp:
                try:
                    case = gen(rnd, Path(tmp))
                except Exception as exc:  # noqa: BLE001 - a generator that needs the new API
                    counts["setup"] += 1
                    bad.append(f"(setup) {type(exc).__name__}: {exc}"[:200])
                    continue
                out = fuzzcases.judge(case)
                counts[out.verdict] += 1
                if out.verdict == "bad":
                    bad.append(f"{case.what}: {out.detail}"[:240])
        rows.append((cat, a.n, counts["clear"], counts["bad"] + counts["setup"], time.perf_counter() - t0))
        print(f"{cat:20s} tried {a.n:4d}  clear {counts['clear']:4d}  bad {counts['bad'] + counts['setup']:4d}"
              f"  ({rows[-1][4]:.0f} s)", flush=True)
        for b in bad[: a.show]:
            print(f"    bad: {b}", flush=True)
    tot = [sum(r[k] for r in rows) for k in (1, 2, 3)]
    print(f"{'TOTAL':20s} tried {tot[0]:4d}  clear {tot[1]:4d}  bad {tot[2]:4d}")


if __name__ == "__main__":
    main()
