"""``ipmc validate``: every claim printed by the seed papers next to the project's own number.

:mod:`~scenarios.validation.claims` says what a claim check is (``Claim``, ``Outcome``) and holds the
registries; :mod:`~scenarios.validation.framework` enumerates the claims of the shipped
``published.toml``, judges each check and writes the report (status × basis, see there); one module
per seed paper holds its claim checks (:mod:`~scenarios.validation.seed000`,
:mod:`~scenarios.validation.seed001`, :mod:`~scenarios.validation.seed002`), with the check builders
they share in :mod:`~scenarios.validation.shared`.
"""

from . import seed000, seed001, seed002  # noqa: F401  (register their checks)
from .claims import CHECKS, EXTRA_ROWS, KINDS, Claim, Outcome
from .framework import (
    BASES,
    DEFAULT_PUBLISHED,
    META_KEYS,
    STATUSES,
    ClaimRow,
    Context,
    ValidationReport,
    claim_location,
    load_published,
    published_claims,
    validate,
)

__all__ = ["BASES", "CHECKS", "DEFAULT_PUBLISHED", "EXTRA_ROWS", "KINDS", "META_KEYS", "STATUSES", "Claim", "ClaimRow",
           "Context", "Outcome", "ValidationReport", "claim_location", "load_published", "published_claims", "validate"]
