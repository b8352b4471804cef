"""``ipmc study``: a Monte Carlo or grid parameter study on local processes or a Dask cluster."""

from __future__ import annotations

import sys
from pathlib import Path

from ..spec import resolve_bundled
from ..study import SCHEDULER_TIMEOUT_S, StudyError, chunk_indices, load_study, run_study


def add_parser(subparsers):
    p = subparsers.add_parser(
        "study", help="Monte Carlo / grid parameter study on local processes or a Dask cluster",
        description="Evaluate a parameter study (parameters × temperatures × frequencies; schema in "
                    "scenarios/study.py and the README) and write a tidy table, one row per sample × "
                    "temperature × frequency.  Same seed → identical table on any backend.")
    p.add_argument("spec", help="study TOML file, or the name of a bundled study (e.g. actuator_mc)")
    p.add_argument("--out", required=True, help="output table (.csv or .npz)")
    p.add_argument("--scheduler", help="Dask scheduler address (e.g. tcp://10.0.0.5:8786); default: local processes")
    p.add_argument("--scheduler-timeout", type=float, default=SCHEDULER_TIMEOUT_S, metavar="SECONDS",
                   help="seconds the Dask scheduler has to connect and answer (default %(default)g)")
    p.add_argument("--workers", type=int, help="local worker processes (default: number of CPUs)")
    p.add_argument("--serial", action="store_true", help="evaluate in this process (no workers)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def run(args) -> int:
    spec = load_study(resolve_bundled(args.spec, "study"))
    out = Path(args.out)
    if out.suffix.lower() not in (".csv", ".npz"):
        raise StudyError(f"--out {out}: use a .csv or .npz file name")
    if args.workers is not None and args.workers < 1:
        raise StudyError(f"--workers must be >= 1, got {args.workers}")
    if not 0 < args.scheduler_timeout <= 3600:
        raise StudyError(f"--scheduler-timeout {args.scheduler_timeout:g}: expected seconds in (0, 3600]")
    from physmodel.data.results import check_writable_parent

    from ._common import bound_count, check_out_file

    check_out_file(out, (".csv", ".npz"))
    check_writable_parent(out)                  # before the study runs, not after
    rows = spec["samples"] * len(spec["temperatures_c"]) * len(spec["frequencies_hz"])
    # the columns (parameters + 7) as float64, held about three times (chunks, table, file buffer)
    bound_count(rows, f"{args.spec}: [study] samples × temperatures_c × frequencies", 24 * (len(spec["parameters"]) + 7),
                what="rows")
    bar = None
    if not args.quiet:
        from tqdm import tqdm

        bar = tqdm(total=len(chunk_indices(spec)), desc=spec["name"], unit="chunk", file=sys.stderr)
    try:
        table = run_study(spec, scheduler=args.scheduler, workers=args.workers,
                          backend="serial" if args.serial else None, progress=bar.update if bar else None,
                          timeout_s=args.scheduler_timeout)
    finally:
        if bar is not None:
            bar.close()
    table.save(out)
    if not args.quiet:
        print(f"wrote {out}: {table.n_rows} rows ({spec['samples']} samples × {len(spec['temperatures_c'])} "
              f"temperatures × {len(spec['frequencies_hz'])} frequencies) on {table.backend} in {table.elapsed_s:.1f} s")
    return 0
