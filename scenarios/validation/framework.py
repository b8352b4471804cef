"""The validation framework: enumerate the printed claims, judge each check, and report.

Every key of every section of ``published.toml`` (the seed papers' printed numbers shipped in
:mod:`physmodel.parameter_sets`) is one claim; every element of a list of claims is one claim with
an index (``actuator_seed001.order_claims[1]``).  The keys ``citation``, ``cite_as`` and
``location`` describe the paper and where each claim is printed; they are not claims.

Each claim id is mapped in :data:`~scenarios.validation.claims.CHECKS` (filled by the per-seed modules) to a
:class:`~scenarios.validation.claims.Claim`:
the check, what the project expects (reproduce / a known finding / not checkable) and the
comparison's *kind*.  An id without a mapping becomes a failing row.

Status (what happened)
    ``reproduced``      our number meets the criterion.
    ``not-reproduced``  a known limit of the physics or of a model-exact experiment; the reason says
                        why.  A finding, not a failure.
    ``not-checkable``   the claim needs data that are not printed (measured records, hardware).
    ``fail``            a claim the project reproduces no longer meets its criterion, a check raised,
                        or a claim has no check: a regression (``ipmc validate`` exits 3).

Basis (how independent the comparison is)
    ``independent``  nothing in the model or its parameters was chosen using this claim, and the
                     comparison sets the physics against what the paper printed.
    ``calibrated``   the parameter set was fitted or solved to this claim or to data from it, or to a
                     claim that implies it on the grid the calibration searched (``Claim.implied_by``);
                     the row is a consistency check and never counts as a reproduction.
    ``round-trip``   a surrogate or an inverse fitted to the model is compared with the same model (or
                     with another fit to it): the row checks our fitting or inversion code, not the
                     physics against the paper; it passes whatever the model's temperature dependence
                     (an uncalibrated set, a trend of the wrong sign), so it never counts either.
    ``input``        the number is a model input (geometry, a printed parameter, a material law).
    ``paper``        the paper's own internal consistency (printed numbers against each other, or a
                     statement true by construction of the paper's model classes).
    ``metadata``     bookkeeping: units, bands, temperature lists, the paper's name.

A check declares its kind as one of ``model`` (a prediction of the physics), ``round-trip``,
``input``, ``paper``, ``metadata``.  ``model`` resolves to ``calibrated`` when the claim (or the claim
named by ``implied_by``) is listed in the ``CALIBRATION`` table of the parameter-set module that the
check uses, else to ``independent``: the calibrated basis comes from what the derivation actually
used, not from a label written beside the check.

The headline counts only ``reproduced`` × ``independent`` rows, out of the independent rows where
something was compared (``reproduced``, ``not-reproduced`` or ``fail``; a ``not-checkable`` row
compares nothing).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from functools import cached_property
from pathlib import Path

from physmodel.parameter_sets import published as _published_module

from .claims import CHECKS, EXTRA_ROWS, KINDS, Claim

STATUSES = ("reproduced", "not-reproduced", "not-checkable", "fail")
BASES = ("independent", "calibrated", "round-trip", "input", "paper", "metadata")
#: Statuses of a row where something was compared (``not-checkable`` compares nothing).
COMPARED = ("reproduced", "not-reproduced", "fail")
#: Keys of a section that describe the paper, not claims.
META_KEYS = ("citation", "cite_as", "location")
#: Default published numbers: the file shipped inside the package.
DEFAULT_PUBLISHED = Path(_published_module.__file__).with_name(_published_module.PUBLISHED_FILE)


# ============================================================================ records
@dataclass(frozen=True)
class ClaimRow:
    """One claim: where it is printed, what it says, our number, the criterion, status and basis.

    ``basis_note`` says why the row has its basis (e.g. which parameters were calibrated to it).
    """

    claim_id: str
    source: str
    location: str
    printed: str
    ours: str
    criterion: str
    status: str
    basis: str
    reason: str = ""
    basis_note: str = ""


@dataclass(frozen=True)
class ValidationReport:
    """All rows, in file order.  ``regressions``: the ``fail`` rows; ``calibration``: for each
    calibrated parameter set, the claims it was calibrated on and what was fitted to each."""

    rows: tuple
    quick: bool
    published: str
    elapsed_s: float
    metadata: dict = field(default_factory=dict)
    calibration: dict = field(default_factory=dict)
    papers: dict = field(default_factory=dict)

    @property
    def counts(self) -> dict:
        """Rows per status."""
        return {s: sum(r.status == s for r in self.rows) for s in STATUSES}

    @property
    def counts_by_basis(self) -> dict:
        """``{status: {basis: rows}}``."""
        return {s: {b: sum(r.status == s and r.basis == b for r in self.rows) for b in BASES} for s in STATUSES}

    @property
    def independent_reproductions(self) -> int:
        """The headline: claims reproduced by a comparison nothing was calibrated to."""
        return self.counts_by_basis["reproduced"]["independent"]

    @property
    def independent_comparisons(self) -> int:
        """The headline's denominator: independent rows where something was compared (not ``not-checkable``)."""
        return sum(r.basis == "independent" and r.status in COMPARED for r in self.rows)

    @property
    def regressions(self) -> list:
        return [r for r in self.rows if r.status == "fail"]

    @property
    def claim_ids(self) -> list:
        return [r.claim_id for r in self.rows]

    def headline(self) -> str:
        c = self.counts
        return (f"{self.independent_reproductions} claims independently reproduced "
                f"(of {self.independent_comparisons} independent comparisons made; {len(self.rows)} rows: "
                + ", ".join(f"{c[s]} {s}" for s in STATUSES) + ")")

    def to_dict(self) -> dict:
        return {"format": "ipmc-validation", "version": 3, "published": self.published, "quick": self.quick,
                "elapsed_s": round(self.elapsed_s, 3), "headline": self.headline(),
                "independent_reproductions": self.independent_reproductions,
                "independent_comparisons": self.independent_comparisons,
                "counts": self.counts, "counts_by_basis": self.counts_by_basis,
                "calibration": self.calibration, "papers": self.papers, "metadata": self.metadata,
                "rows": [asdict(r) for r in self.rows]}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, ensure_ascii=False, allow_nan=False)

    def to_markdown(self) -> str:
        esc = lambda s: str(s).replace("|", "\\|").replace("\n", " ")
        cb = self.counts_by_basis
        lines = ["# Validation against the seed papers", "",
                 f"**{self.headline()}**" + (" (quick mode: fewer temperatures)" if self.quick else "") + ".",
                 f"Claims from `{self.published}`, {self.elapsed_s:.1f} s.", "",
                 ("Only `reproduced` rows of basis `independent` are evidence that the physics reproduces a paper: "
                  "`calibrated` rows check that a fit hit its target (or a claim it implies), `round-trip` rows check "
                  "a surrogate or inverse of the model against the model, `input` rows re-read model inputs, `paper` "
                  "rows check the paper against itself, `metadata` rows are bookkeeping.  `not-checkable` rows compare "
                  "nothing and are not in the headline's count of comparisons.  `not-reproduced` is a finding "
                  "about the physics (the reason says why); `fail` is a regression."), "",
                 "| status \\ basis | " + " | ".join(BASES) + " | total |", "|---|" + "---|" * (len(BASES) + 1)]
        for s in STATUSES:
            lines.append(f"| {s} | " + " | ".join(str(cb[s][b]) for b in BASES) + f" | {sum(cb[s].values())} |")
        lines += ["", "## Papers", ""]
        lines += [f"- {esc(k)}: {esc(v)}" for k, v in self.papers.items()]
        lines += ["", "## Calibration and hold-out", ""]
        for name, table in self.calibration.items():
            lines.append(f"- `{name}` calibrated on: " + "; ".join(f"`{cid}` ({esc(what)})" for cid, what in table.items())
                         + ".  Every other row that uses it is a prediction.")
        lines += ["", "## Claims", "", "| claim | source, location | printed | ours | criterion | status | basis | reason |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in self.rows:
            basis = f"**{r.basis}**" + (f": {esc(r.basis_note)}" if r.basis_note else "")
            lines.append(f"| `{r.claim_id}` | {esc(r.source)}, {esc(r.location)} | {esc(r.printed)} | {esc(r.ours)} "
                         f"| {esc(r.criterion)} | **{r.status}** | {basis} | {esc(r.reason)} |")
        return "\n".join(lines) + "\n"


# ============================================================================ enumeration
def load_published(path=None) -> dict:
    """The printed claims: the bundled file, or ``path``."""
    return _published_module.load_published(path)


def published_claims(data: dict) -> list[tuple[str, str, str, object]]:
    """``(claim_id, section, key, printed value)`` for every claim in the TOML data, in file order."""
    out = []
    for section, table in data.items():
        if not isinstance(table, dict):
            out.append((section, section, section, table))
            continue
        for key, value in table.items():
            if key in META_KEYS:
                continue
            if isinstance(value, list) and value and all(isinstance(v, (str, dict)) for v in value):
                out.extend((f"{section}.{key}[{i}]", section, key, v) for i, v in enumerate(value))
            else:
                out.append((f"{section}.{key}", section, key, value))
    return out


def claim_location(data: dict, claim_id: str) -> str:
    """Where the paper prints the claim (the section's ``location`` table), or a note that it is not given."""
    section, _, rest = claim_id.partition(".")
    key, _, idx = rest.partition("[")
    loc = data.get(section, {}).get("location", {}).get(key) if isinstance(data.get(section), dict) else None
    if isinstance(loc, list):
        i = int(idx.rstrip("]")) if idx else 0
        loc = loc[i] if i < len(loc) else None
    return str(loc) if loc else "location not given in the data file"


def _printed(value) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} = {v}" for k, v in value.items())
    return str(value)


# ============================================================================ context
class Context:
    """The printed data, the parameter sets and a memo for evaluations shared by several checks."""

    def __init__(self, quick: bool, published: dict, path: Path = DEFAULT_PUBLISHED, sets: dict | None = None):
        self.quick = quick
        self.pub = published
        self.path = Path(path)
        self._memo: dict = {}
        #: what checks record for the report beside their rows (``ValidationReport.metadata``)
        self.metadata: dict = {}
        #: parameter sets used in place of the named ones (what-if runs: what does a check depend on?)
        self.sets = dict(sets or {})

    def memo(self, key: str, compute: Callable):
        """``compute(self)`` once per report."""
        if key not in self._memo:
            self._memo[key] = compute(self)
        return self._memo[key]

    def parameter_set(self, name: str):
        from physmodel import get_parameter_set

        return self.memo(f"set:{name}", lambda ctx: ctx.sets[name] if name in ctx.sets else get_parameter_set(name))

    @cached_property
    def calibration(self) -> dict:
        """``{set name: {claim id: what was fitted to it}}`` from the parameter-set modules."""
        from physmodel.parameter_sets import seed000, seed001

        return {**seed000.CALIBRATION, **seed001.CALIBRATION}


def _basis(ctx, claim_id: str, claim: Claim) -> tuple[str, str]:
    if claim.kind not in KINDS:
        raise ValueError(f"{claim_id}: kind {claim.kind!r} is not one of {KINDS}")
    if claim.kind != "model":
        return claim.kind, claim.note
    base = claim_id.split("+")[0]
    used = ctx.calibration.get(claim.uses or "", {})
    if base in used:
        return "calibrated", f"{claim.uses}: {used[base]}" + (f"; {claim.note}" if claim.note else "")
    if claim.implied_by in used:
        return "calibrated", (f"{claim.uses}: implied by the calibrated claim {claim.implied_by} "
                              f"({used[claim.implied_by]})" + (f"; {claim.note}" if claim.note else ""))
    return "independent", claim.note or (f"{claim.uses} was not calibrated on this claim" if claim.uses else "")


def _judge(ctx, claim_id, source, location, printed, value, claim: Claim) -> ClaimRow:
    basis, note = _basis(ctx, claim_id, claim)
    row = lambda ours, crit, status, reason: ClaimRow(claim_id, source, location, printed, ours, crit,
                                                      status, basis, reason, note)
    if claim.expect.startswith("not-checkable"):
        ours = claim.check(ctx, value).ours if claim.check is not None else "-"
        return row(ours, "-", "not-checkable", claim.expect.split(":", 1)[1].strip())
    if claim.check is None:
        return row("-", "-", "fail", "the claim has no check (a regression)")
    try:
        out = claim.check(ctx, value)
    except Exception as exc:  # noqa: BLE001 - a broken check is reported as a failing row, never skipped
        return row(f"error: {type(exc).__name__}: {exc}", "-", "fail", f"the check raised {type(exc).__name__}: {exc}")
    if out.ok:
        return row(out.ours, out.criterion, "reproduced", out.note)
    if claim.expect.startswith("finding"):
        return row(out.ours, out.criterion, "not-reproduced", claim.expect.split(":", 1)[1].strip())
    return row(out.ours, out.criterion, "fail", "regression: the project reproduces this claim, but the criterion is no "
               "longer met")


def _rows(ctx, claim_id, section, key, value) -> list[ClaimRow]:
    """The row of one claim, plus its EXTRA_ROWS."""
    table = ctx.pub.get(section, {}) if isinstance(ctx.pub.get(section), dict) else {}
    source = str(table.get("cite_as") or table.get("paper") or section)
    location = claim_location(ctx.pub, claim_id)
    if claim_id not in CHECKS:
        return [ClaimRow(claim_id, source, location, _printed(value), "-", "-", "fail", "metadata",
                         "no check is mapped to this claim (scenarios.validation CHECKS must cover every claim)")]
    rows = [_judge(ctx, claim_id, source, location, _printed(value), value, CHECKS[claim_id])]
    for tag, printed, extra in EXTRA_ROWS.get(claim_id, []):
        rows.append(_judge(ctx, f"{claim_id}+{tag}", source, location, printed, value, extra))
    return rows


def validate(*, quick: bool = False, progress=None, published=None, sets: dict | None = None) -> ValidationReport:
    """Check every claim of the published numbers; ``quick`` fits fewer temperatures.

    ``progress(n)`` is called with 1 after each claim.  ``published``: path of a TOML file of the
    same layout (default: the file shipped in :mod:`physmodel.parameter_sets`).  ``sets``: ``{set name:
    IPMCParameters}`` used in place of the named sets (a what-if run; the bases still come from the
    named sets' ``CALIBRATION``).
    """
    from . import seed000, seed001, seed002  # noqa: F401  (they register their checks)

    t0 = time.perf_counter()
    path = Path(published) if published is not None else DEFAULT_PUBLISHED
    data = load_published(path)
    ctx = Context(bool(quick), data, path, sets)
    rows = []
    for claim in published_claims(data):
        rows.extend(_rows(ctx, *claim))
        if progress:
            progress(1)
    papers = {str(t.get("cite_as", s)): str(t.get("citation", t.get("paper", s)))
              for s, t in data.items() if isinstance(t, dict)}
    return ValidationReport(tuple(rows), bool(quick), str(path), time.perf_counter() - t0,
                            dict(ctx.metadata), ctx.calibration, papers)
