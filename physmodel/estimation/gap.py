"""The gap test of the discrepancy diagnosis (:func:`~physmodel.estimation.discrepancy.diagnose`, step 5), per quantity.

The *gap* is what the baseline leaves above the noise: 2·cost (½ Σ r² of the standardised data
residuals, penalties left out) against the (1 − α_gap) quantile of its null distribution, α_gap =
α / :data:`~physmodel.estimation.diagnosis.GAP_ALPHA_DIVISOR`.  The null draws are the diagnosis's
linearised Gaussian null at the fitted baseline: white standard-normal residuals ``Ep`` (2N × draws)
with the baseline's tangent space projected out; for a model with effects ``effs`` switched on
their signatures are projected out as well, so the threshold is that of the refit's own residual.

Several quantities of one strip (an actuator's M and Z, :mod:`~physmodel.estimation.joint`) are
tested *per quantity*: each quantity's block of rows (its lines' log-magnitude and phase residuals)
has its own statistic, 2·cost over the block, against its own null quantile at level α_gap/K
(K quantities).  A pooled test over all rows spreads its power over lines an effect does not touch
(an out-of-library effect in M alone was diluted by Z's lines and ended ``none``), and a model that
closes the pooled gap may still leave M's own.  So:

* the baseline's gap is significant when *any* block's 2·cost exceeds its threshold;
* a model (a candidate, a pair) closes the gap only when no test of the gap the library runs still
  sees it: it closes it in *every* block — within the block's threshold, or above it by at most
  :data:`~physmodel.estimation.diagnosis.CLOSE_FRACTION` of that block's own baseline excess (the
  tolerance for another author's parametrisation of an effect, applied where that effect's excess
  was) — *and* in the pooled statistic, 2·cost over every row against the (1 − α_gap) quantile of
  the pooled projected null (the single-quantity test; the same slack, a share of the baseline's
  pooled excess).  Per block alone, a model that moves misfit from M into Z could leave each block
  just inside its own quantile at α_gap/K while their sum stayed above the pooled one: a confident
  name with a gap the pooled test still sees (a creep named distributed_cpe + a temperature law,
  ``tests/benchmarks/bench_joint_diagnosis.py``).  The message says which test left the gap open
  (a quantity, or "pooled over M and Z").

The baseline's *significance* stays per block only: adding the pooled test there would be a third
test sharing the same false-positive budget α_gap (another split).  Closing is the other side: a
correct name fails to close when *some* test rejects the correct model's residual, which the
per-block family does with probability ≤ α_gap and the pooled test with probability α_gap, so
≤ ~2·α_gap by the union bound (instead of ~α_gap) — the price of the rule, paid in correct in-library
names left ``unexplained`` (or a correct pair not accepted).

The share of α: Bonferroni, α_gap/K per block, so that under the null the probability that some
block rejects is at most α_gap whatever the dependence between the blocks (the union bound), and
the verdict's family-wise rate stays α (the LR test's α − α_gap plus this α_gap).  Chosen over a
max-type statistic (the largest of the blocks' null p-values, calibrated on the same draws): the
blocks are different lines, coupled only through the few fitted parameters' projection, so they are
nearly independent and the calibrated level would be the Šidák one, 1 − (1 − α_gap)^(1/K) — for
α_gap = 0.01 and K = 2, 0.0050125 against Bonferroni's 0.005, a threshold difference far inside the
Monte-Carlo error of a 4000-draw quantile; Bonferroni needs no second calibration for every set of
effects projected out, holds for any dependence, and with K = 1 *is* the single-quantity test, bit
for bit (one block of all rows, the same statistic, the same quantile; the pooled test is that one
block, so it is not run twice).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .diagnosis import CLOSE_FRACTION
from .signatures import orth
from .verdicts import residual_sentence


def block_rows(sizes: Sequence[int]) -> tuple[np.ndarray, ...]:
    """Each block's rows in the 2N standardised residuals ``[ln-magnitude (N); phase (N)]`` of a
    record stacked from blocks of ``sizes`` lines (:class:`~physmodel.estimation.joint.StackedSweep`)."""
    n = int(sum(sizes))
    edges = np.cumsum([0, *[int(s) for s in sizes]])
    return tuple(np.concatenate([np.arange(a, b), n + np.arange(a, b)]) for a, b in zip(edges[:-1], edges[1:]))


@dataclass(frozen=True)
class GapTest:
    """The gap test of one diagnosis: per block (quantity) the baseline's data cost and its
    threshold on 2·cost (module docstring).

    ``quantities``: the blocks' names; ``rows``: each block's rows in the 2N residuals (None: one
    block of every row); ``alpha``: the gap test's family-wise share α_gap; ``cost0``: the
    baseline's data cost per block; ``thr0``: its thresholds on 2·cost, the (1 − α_gap/K) quantile
    of each block's null 2·cost.  ``null`` (2N × draws) and ``sigs`` ({candidate: signature
    columns}) give the thresholds of a model with effects on (:meth:`thresholds`)."""

    quantities: tuple
    rows: tuple | None
    alpha: float
    cost0: np.ndarray
    thr0: np.ndarray
    null: np.ndarray = field(repr=False)
    sigs: Mapping = field(repr=False)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def from_null(cls, Ep: np.ndarray, alpha: float, baseline_costs, sigs: Mapping | None = None,
                  quantities: Sequence[str] = ("",), sizes: Sequence[int] | None = None) -> GapTest:
        """The test from null draws ``Ep`` (2N × draws), the gap test's share ``alpha`` and the
        baseline's data cost per block (``sizes``: lines per block; None for one block)."""
        qs = tuple(quantities)
        rows = None if sizes is None or len(sizes) == 1 else block_rows(sizes)
        if len(qs) != (1 if rows is None else len(rows)):
            raise ValueError(f"{len(qs)} quantity names for {1 if rows is None else len(rows)} blocks")
        out = cls(qs, rows, float(alpha), np.atleast_1d(np.asarray(baseline_costs, dtype=float)),
                  np.zeros(len(qs)), Ep, dict(sigs or {}))
        object.__setattr__(out, "thr0", out.thresholds(()))
        return out

    @property
    def K(self) -> int:
        """Blocks (quantities)."""
        return len(self.quantities)

    @property
    def level(self) -> float:
        """Each block's quantile level, 1 − α_gap/K (Bonferroni)."""
        return 1 - self.alpha / self.K

    def null_costs(self, effs: Sequence[str] = ()) -> np.ndarray:
        """(K, draws): each block's 2·cost in the null draws with the baseline's and ``effs``'
        signatures projected out."""
        E = self.null
        if self.rows is None:          # one block: the statistic as the single-quantity test always had it
            c = np.sum(E * E, axis=0)
            if effs:
                Qs = orth(np.hstack([self.sigs[c] for c in effs]))
                c = c - np.sum((Qs.T @ E) ** 2, axis=0)
            return c[None, :]
        R = E
        if effs:
            Qs = orth(np.hstack([self.sigs[c] for c in effs]))
            R = E - Qs @ (Qs.T @ E)
        return np.vstack([np.sum(R[r] ** 2, axis=0) for r in self.rows])

    def _all_thresholds(self, effs: Sequence[str]) -> tuple[np.ndarray, float]:
        """(K,) the blocks' thresholds on 2·cost and the pooled one (that of the one block for K = 1)
        for a model with ``effs`` on (cached)."""
        key = tuple(effs)
        if key not in self._cache:
            c = self.null_costs(key)
            blocks = np.array([float(np.quantile(ck, self.level)) for ck in c])
            self._cache[key] = (blocks, float(blocks[0]) if self.K == 1
                                else float(np.quantile(c.sum(axis=0), 1 - self.alpha)))
        return self._cache[key]

    def thresholds(self, effs: Sequence[str] = ()) -> np.ndarray:
        """(K,) thresholds on 2·cost of each block for a model with ``effs`` on (cached)."""
        return self._all_thresholds(effs)[0]

    def pooled_threshold(self, effs: Sequence[str] = ()) -> float:
        """The pooled test's threshold on 2·cost over every row for a model with ``effs`` on: the
        (1 − α_gap) quantile of the pooled projected null (for K = 1, the one block's threshold)."""
        return self._all_thresholds(effs)[1]

    @property
    def _names(self) -> str:
        q = list(self.quantities)
        return q[0] if len(q) == 1 else ", ".join(q[:-1]) + " and " + q[-1]

    @property
    def pooled_name(self) -> str:
        """The pooled test in words: ``"pooled over M and Z"``."""
        return "pooled over " + self._names

    @property
    def pooled_excess0(self) -> float:
        """The baseline's pooled 2·cost above the pooled threshold (0 when within)."""
        return max(2 * float(np.sum(self.cost0)) - self.pooled_threshold(), 0.0)

    def closes_pooled(self, costs, effs: Sequence[str] = ()) -> bool:
        """The pooled 2·cost (Σ over the blocks) within the pooled threshold, or above it by at most
        CLOSE_FRACTION of the baseline's pooled excess; for K = 1 always True (the block test is the
        pooled test)."""
        if self.K == 1:
            return True
        two, thr = 2 * float(np.sum(costs)), self.pooled_threshold(effs)
        return bool(two <= thr or two - thr <= CLOSE_FRACTION * self.pooled_excess0)

    @property
    def excess0(self) -> np.ndarray:
        """(K,) the baseline's 2·cost above its threshold per block (0 where within)."""
        return np.maximum(2 * self.cost0 - self.thr0, 0.0)

    @property
    def significant0(self) -> bool:
        """The baseline leaves a significant gap: some block's 2·cost above its threshold."""
        return bool(self.significant(self.cost0))

    def significant(self, costs, effs: Sequence[str] = ()):
        """Some block's 2·cost above its threshold (``costs``: (K,) or (K, m) for m records at once:
        then an (m,) bool array)."""
        two = 2 * np.asarray(costs, dtype=float).reshape(self.K, -1)
        out = np.any(two > self.thresholds(effs)[:, None], axis=0)
        return bool(out[0]) if np.ndim(costs) <= 1 else out

    def block_costs(self, r: np.ndarray) -> np.ndarray:
        """(K,) data cost ½ Σ r² per block of a residual vector ``r`` (2N,)."""
        r = np.asarray(r, dtype=float)
        if self.rows is None:
            return np.array([float(0.5 * r @ r)])
        return np.array([float(0.5 * r[i] @ r[i]) for i in self.rows])

    def fit_costs(self, res, residuals: Callable[[Mapping], np.ndarray]) -> np.ndarray:
        """(K,) a fit's data cost per block: one block, its ``metadata["data_cost"]``; several, from
        its residuals (``residuals(values)``, 2N), kept in ``metadata["data_cost_by_quantity"]``."""
        if self.K == 1:
            return np.array([res.metadata["data_cost"]])
        if "data_cost_by_quantity" not in res.metadata:
            costs = self.block_costs(residuals(res.values))
            res.metadata["data_cost_by_quantity"] = dict(zip(self.quantities, costs.tolist()))
        return np.array([res.metadata["data_cost_by_quantity"][q] for q in self.quantities])

    def residual_sentence(self, res, costs, effs: Sequence[str] = ()) -> str:
        """What is said of the misfit the final model ``res`` (``effs`` on, data cost ``costs`` per
        block) leaves (:func:`~physmodel.estimation.verdicts.residual_sentence`): of the whole record
        for one block; per quantity, of each block above its threshold, against its share of the
        χ² expectation (the fitted parameters shared out by lines)."""
        thr, ex = self.thresholds(effs), self.excess0
        if self.K == 1:
            return residual_sentence(res.metadata["data_cost"], res.expected_cost, float(thr[0]), float(ex[0]))
        n = np.array([r.size // 2 for r in self.rows or ()])
        expected = n - 0.5 * len(res.names) * n / n.sum()
        out = "".join(residual_sentence(float(c), float(e), float(t), float(x), where=q)
                      for q, c, e, t, x in zip(self.quantities, costs, expected, thr, ex))
        # every block within its own threshold but their sum above the pooled one: said of the sum
        return out or residual_sentence(float(np.sum(costs)), float(np.sum(expected)), self.pooled_threshold(effs),
                                        self.pooled_excess0, where="the sum over " + self._names)

    def closes_blocks(self, costs, effs: Sequence[str] = ()) -> np.ndarray:
        """(K,) bool: each block's 2·cost within its threshold, or above it by at most
        CLOSE_FRACTION of that block's baseline excess."""
        two, thr = 2 * np.atleast_1d(np.asarray(costs, dtype=float)), self.thresholds(effs)
        return (two <= thr) | (two - thr <= CLOSE_FRACTION * self.excess0)

    def closes(self, costs, effs: Sequence[str] = ()) -> bool:
        """A model with ``effs`` on and data cost ``costs`` per block closes the gap in every block and
        pooled (module docstring)."""
        return bool(np.all(self.closes_blocks(costs, effs))) and self.closes_pooled(costs, effs)

    def strict(self, costs, effs: Sequence[str] = ()) -> bool:
        """Every block's 2·cost within its threshold and the pooled 2·cost within the pooled one (no
        tolerance)."""
        two = 2 * np.atleast_1d(np.asarray(costs, dtype=float))
        return bool(np.all(two <= self.thresholds(effs))) and (
            self.K == 1 or float(np.sum(two)) <= self.pooled_threshold(effs))

    def compare(self, costs, effs: Sequence[str] = ()) -> str:
        """2·cost against the threshold, in words: ``"2·cost 380 > 350"`` for one block; per
        quantity, the level and each block (``"M: 2·cost 380 > 350, Z: 2·cost 300 ≤ 320"``)."""
        two, thr = 2 * np.atleast_1d(np.asarray(costs, dtype=float)), self.thresholds(effs)
        if self.K == 1:
            return f"2·cost {two[0]:.4g} {'>' if two[0] > thr[0] else '≤'} {thr[0]:.4g}"
        tp, sp = float(np.sum(two)), self.pooled_threshold(effs)
        return (f"per quantity, each at {self.alpha / self.K:.3g}: " + ", ".join(
            f"{q}: 2·cost {a:.4g} {'>' if a > b else '≤'} {b:.4g}" for q, a, b in zip(self.quantities, two, thr))
            + f"; {self.pooled_name} at {self.alpha:.3g}: 2·cost {tp:.4g} {'>' if tp > sp else '≤'} {sp:.4g}")

    def threshold_text(self, effs: Sequence[str] = ()) -> str:
        """The thresholds on 2·cost in words: ``"350"`` for one block, ``"M 350, Z 320, pooled 690"``
        per quantity."""
        thr = self.thresholds(effs)
        return f"{thr[0]:.4g}" if self.K == 1 else ", ".join(
            f"{q} {t:.4g}" for q, t in zip(self.quantities, thr)) + f", pooled {self.pooled_threshold(effs):.4g}"

    def open_in(self, costs, effs: Sequence[str] = ()) -> list[str]:
        """The tests in which a model with ``effs`` on does not close the gap: the quantities, and
        :attr:`pooled_name` when the pooled test still sees it."""
        return [q for q, ok in zip(self.quantities, self.closes_blocks(costs, effs)) if not ok] + (
            [] if self.closes_pooled(costs, effs) else [self.pooled_name])

    def annotate(self, rows: Sequence[dict], effs: Sequence[str] = ()) -> list[dict]:
        """The per-quantity report rows (:meth:`~physmodel.estimation.joint.JointData.per_quantity`,
        with ``cost_before``/``cost_after``) with each quantity's gap test before and after: its
        thresholds on 2·cost, ``gap_before`` (the baseline's gap significant there) and
        ``gap_left`` (the final model, with ``effs`` on, does not close it there)."""
        cb = np.array([r["cost_before"] for r in rows])
        ca = np.array([r["cost_after"] for r in rows])
        thr_a, left = self.thresholds(effs), ~self.closes_blocks(ca, effs)
        for k, r in enumerate(rows):
            r.update({"gap_threshold_before_2cost": float(self.thr0[k]), "gap_before": bool(2 * cb[k] > self.thr0[k]),
                      "gap_threshold_after_2cost": float(thr_a[k]), "gap_left": bool(left[k])})
        return list(rows)

    def pooled_row(self, rows: Sequence[dict], effs: Sequence[str] = ()) -> dict | None:
        """The pooled test before and after for the report, from the per-quantity rows (their
        ``cost_before``/``cost_after`` summed): its name, 2·cost and thresholds, ``gap_before`` (the
        pooled 2·cost above its threshold; not part of the baseline's significance) and ``gap_left``
        (the final model, with ``effs`` on, does not close the pooled gap); None for one block."""
        if self.K == 1 or not rows:
            return None
        cb, ca = (float(sum(r[k] for r in rows)) for k in ("cost_before", "cost_after"))
        return {"test": self.pooled_name, "level": 1 - self.alpha, "two_cost_before": 2 * cb,
                "threshold_before_2cost": self.pooled_threshold(), "gap_before": bool(2 * cb > self.pooled_threshold()),
                "two_cost_after": 2 * ca, "threshold_after_2cost": self.pooled_threshold(effs),
                "gap_left": not self.closes_pooled([ca], effs)}

    def describe(self, pooled: dict | None = None) -> dict:
        """The test for the report (``Diagnosis.null``); ``pooled``: :meth:`pooled_row`."""
        out = {"rule": "one block" if self.K == 1 else f"per quantity, Bonferroni α_gap/{self.K} per block; "
               "the gap is significant if any block's is, and closed only if closed in every block and pooled "
               "(2·cost over every row against the pooled null's 1 − α_gap quantile)",
               "alpha_gap": self.alpha, "level_per_block": self.level,
               "thresholds_2cost": {q: float(t) for q, t in zip(self.quantities, self.thr0)},
               "baseline_2cost": {q: float(2 * c) for q, c in zip(self.quantities, self.cost0)}}
        if self.K > 1:
            out["pooled"] = pooled or {"test": self.pooled_name, "level": 1 - self.alpha,
                                       "threshold_before_2cost": self.pooled_threshold(),
                                       "two_cost_before": 2 * float(np.sum(self.cost0))}
        return out


__all__ = ["GapTest", "block_rows"]
