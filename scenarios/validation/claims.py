"""What a claim check is: the :class:`Claim` a per-seed module maps each printed claim to, the
:class:`Outcome` its check returns, and the registries the per-seed modules fill
(:data:`CHECKS`, :data:`EXTRA_ROWS`).

Below both :mod:`~scenarios.validation.framework` (which judges the claims) and the per-seed
modules (which register their checks): the framework imports those to fill the registries, and
they need nothing of the framework's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

#: What a check compares (see the framework's bases): ``model`` resolves to ``calibrated`` or ``independent``.
KINDS = ("model", "round-trip", "input", "paper", "metadata")


@dataclass
class Outcome:
    """What a check returns: our number, the criterion and whether it is met."""

    ours: str
    criterion: str
    ok: bool
    note: str = ""


@dataclass(frozen=True)
class Claim:
    """How one claim is checked.

    ``check(ctx, printed value) -> Outcome`` (None for a claim that is not checkable);
    ``expect``: ``"reproduce"``, ``"finding: <why the physics does not reproduce it>"`` or
    ``"not-checkable: <why>"``; ``kind``: one of :data:`KINDS`; ``uses``: the parameter set whose
    ``CALIBRATION`` decides between ``calibrated`` and ``independent`` (kind ``model``);
    ``note``: why the row has its basis (optional for ``model``); ``implied_by``: the id of a claim
    that implies this one on the grid the calibration of ``uses`` searched (a test shows it): when
    that claim is calibrated, so is this row.
    """

    check: Callable | None
    expect: str
    kind: str
    uses: str | None = None
    note: str = ""
    implied_by: str | None = None


#: claim id -> Claim; filled by the per-seed modules.
CHECKS: dict[str, Claim] = {}
#: claim id -> [(tag, printed statement, Claim)]: a second, separately judged statement of a claim;
#: its row has the id ``<claim id>+<tag>`` and follows the claim's row.
EXTRA_ROWS: dict[str, list] = {}


__all__ = ["KINDS", "Outcome", "Claim", "CHECKS", "EXTRA_ROWS"]
