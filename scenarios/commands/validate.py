"""``ipmc validate``: every printed claim of the seed papers next to the project's own number."""

from __future__ import annotations

import sys
from pathlib import Path

from physmodel.errors import IPMCError

from ..validation import load_published, published_claims, validate
from ._common import EXIT_FAILED, EXIT_OK


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "validate", help="check every published claim of the seed papers against the project's numbers",
        description="Evaluate every claim printed by the seed papers (the published.toml shipped in "
                    "physmodel.parameter_sets: sensor study, actuator study, seed 002) with the seed parameter sets "
                    "and write validation.md and validation.json.  Each row has a status (reproduced, "
                    "not-reproduced, not-checkable, fail) and a basis (independent, calibrated, round-trip, input, "
                    "paper, metadata); the headline counts only independent reproductions, out of the independent "
                    "rows where something was compared.  Exit 0 when every claim is "
                    "reproduced or explained (not-reproduced / not-checkable rows are findings), 3 when a claim "
                    "the project reproduces fails (regression).")
    p.add_argument("--out", default="ipmc-validation", help="output folder (default ./ipmc-validation)")
    p.add_argument("--quick", action="store_true", help="fewer temperatures in the surrogate fits (faster)")
    p.add_argument("--published", help="path of a TOML file of printed claims (default: the one shipped in the package)")
    p.add_argument("--quiet", action="store_true", help="no progress bar or summary")


def run(args) -> int:
    from physmodel.data.files import atomic_write

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise IPMCError(f"--out {out} exists and is not a folder")
    n = len(published_claims(load_published(args.published)))
    if n == 0:
        raise IPMCError(f"--published {args.published}: no claims found (expected tables like [sensor_seed000] "
                        "with printed numbers)")
    bar = None
    if not args.quiet:
        from tqdm import tqdm

        bar = tqdm(total=n, desc="validate", unit="claim", file=sys.stderr)
    try:
        rep = validate(quick=args.quick, progress=bar.update if bar else None, published=args.published)
    finally:
        if bar is not None:
            bar.close()
    from physmodel.data.results import output_folder

    with output_folder(out, "ipmc validate", force=True) as stage:        # all or nothing
        atomic_write(stage / "validation.json", lambda fh: fh.write(rep.to_json() + "\n"))
        atomic_write(stage / "validation.md", lambda fh: fh.write(rep.to_markdown()))
    if not args.quiet:
        print(f"wrote {out / 'validation.md'} and {out / 'validation.json'}: {rep.headline()}")
        for r in rep.regressions:
            print(f"REGRESSION {r.claim_id}: {r.ours} (criterion: {r.criterion})", file=sys.stderr)
    return EXIT_FAILED if rep.regressions else EXIT_OK
