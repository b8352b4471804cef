"""Records of the discrepancy workflow: one candidate's refit (:class:`CandidateResult`) and the
whole diagnosis (:class:`Diagnosis`: verdict, localisation before/after, gap, report files)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..data.files import atomic_write
from ..data.sweep import FrequencySweep
from ..effects import LIBRARY, get_effect
from .records import CalibrationResult

VERDICTS = ("none", "named", "ambiguous", "unexplained")
#: Candidates whose signatures have a canonical correlation at least this high are confusable.
CONFUSABLE_COSINE = 0.9
#: Significant candidates within this AIC difference of the best are reported as ambiguous.
AMBIGUITY_AIC = 6.0
#: The gap test runs at α / GAP_ALPHA_DIVISOR.
GAP_ALPHA_DIVISOR = 5.0
#: A candidate whose largest possible (linearised) LR over its bounds is below this is skipped.
MIN_SIGNATURE_LR = 1.0


# =============================================================================== results


@dataclass
class CandidateResult:
    """One candidate's refit: fitted effect values and 95 % intervals, cost, LR, AIC, BIC."""

    name: str
    values: dict
    ci_lower: dict
    ci_upper: dict
    cost: float
    lr: float
    aic: float
    bic: float
    n_parameters: int
    significant: bool
    closes_gap: bool
    converged: bool
    signature_norm: float
    lr_linearised: float = float("nan")
    note: str = ""

    def to_dict(self) -> dict:
        return {"name": self.name, "values": self.values, "ci95_lower": self.ci_lower,
                "ci95_upper": self.ci_upper, "cost": self.cost, "lr": self.lr, "aic": self.aic,
                "bic": self.bic, "n_parameters": self.n_parameters, "significant": self.significant,
                "closes_gap": self.closes_gap, "converged": self.converged,
                "signature_norm": self.signature_norm, "lr_linearised": self.lr_linearised, "note": self.note}


@dataclass
class Diagnosis:
    """Outcome of :func:`diagnose`.  ``verdict`` ∈ :data:`VERDICTS`; ``named``: effect names."""

    verdict: str
    named: list
    message: str
    kind: str
    quantity: str
    alpha: float
    threshold: float
    gap_threshold: float
    baseline: CalibrationResult
    final: CalibrationResult | None
    final_effects: dict
    candidates: dict
    skipped: dict
    confusable: list
    separation: dict
    localisation_before: list
    localisation_after: list
    gap_before: dict
    gap_after: dict
    null: dict
    noise_estimated: bool
    elapsed_s: float
    data: FrequencySweep = field(repr=False)
    predicted_before: np.ndarray = field(repr=False)
    predicted_after: np.ndarray = field(repr=False)
    metadata: dict = field(default_factory=dict)

    # ---------------------------------------------------------------- views
    def named_effect(self) -> dict | None:
        """The named effect(s) with fitted values and 95 % intervals (None unless verdict is named)."""
        if self.verdict != "named" or self.final is None:
            return None
        out = {}
        for n in self.named:
            out[n] = {k.split(".", 1)[1]: {"value": self.final.values[k], "ci95": [self.final.ci_lower[k], self.final.ci_upper[k]],
                                            "unit": get_effect(n).parameter(k.split(".", 1)[1]).unit}
                      for k in self.final.names if k.startswith(n + ".")}
        return out

    def to_dict(self) -> dict:
        def clean(o):
            if isinstance(o, dict):
                return {str(k): clean(v) for k, v in o.items()}
            if isinstance(o, (list, tuple)):
                return [clean(v) for v in o]
            if isinstance(o, (np.floating, float)):
                return float(o) if math.isfinite(o) else None
            if isinstance(o, (np.integer,)):
                return int(o)
            if isinstance(o, np.bool_):
                return bool(o)
            return o

        return clean({
            "format": "ipmc-diagnosis", "version": 1,
            "verdict": self.verdict, "named": list(self.named), "message": self.message,
            "named_effect": self.named_effect(),
            "kind": self.kind, "quantity": self.quantity, "alpha": self.alpha,
            "lr_threshold": self.threshold, "gap_threshold_2cost": self.gap_threshold,
            "noise_estimated": self.noise_estimated,
            "baseline": self.baseline.to_dict(),
            "final": self.final.to_dict() if self.final is not None else None,
            "final_effects": self.final_effects,
            "candidates": {k: v.to_dict() for k, v in self.candidates.items()},
            "skipped_candidates": self.skipped,
            "confusable_pairs": [{"a": a, "b": b, "cosine": c, "what_separates": self.separation.get(f"{a}~{b}", "")}
                                 for a, b, c in self.confusable],
            "localisation_before": self.localisation_before,
            "localisation_after": self.localisation_after,
            "gap_before": self.gap_before, "gap_after": self.gap_after,
            "null": self.null, "elapsed_s": self.elapsed_s, "metadata": self.metadata,
        })

    def summary(self) -> str:
        """A readable Markdown summary."""
        L = [f"# Discrepancy diagnosis: {self.verdict.upper()}", "", self.message, ""]
        if self.noise_estimated:
            L += ["*The data carry no per-line uncertainty: 1 % per line was assumed; absolute gap "
                  "tests are relative to that assumption.*", ""]
        gb, ga = self.gap_before, self.gap_after
        L += ["## Gap before / after", "",
              "| | weighted cost | expected | z | " + " | ".join(f"{t:g} °C dB / deg" for t in gb["temperatures_c"]) + " |",
              "|---|---|---|---|" + "---|" * len(gb["temperatures_c"])]
        for lab, g in (("before", gb), ("after", ga)):
            L.append(f"| {lab} | {g['cost']:.4g} | {g['expected_cost']:.4g} ± {g['cost_std']:.3g} | {g['z']:.3g} | "
                     + " | ".join(f"{a:.3g} / {b:.3g}" for a, b in zip(g["rms_db"], g["rms_deg"])) + " |")
        L += ["", f"Gap shrink (cost − expected, before / after): {gap_shrink(self):.3g}×", "",
              f"LR threshold (family-wise α = {self.alpha:g}, Monte Carlo under the null): {self.threshold:.3g}; "
              f"gap threshold on 2·cost: {self.gap_threshold:.4g}", "",
              "## Candidates", "", "| effect | LR | significant | closes gap | AIC | BIC | fitted values |",
              "|---|---|---|---|---|---|---|"]
        for c in sorted(self.candidates.values(), key=lambda c: -c.lr):
            vals = ", ".join(f"{k} = {v:.4g} [{c.ci_lower[k]:.3g}, {c.ci_upper[k]:.3g}]"
                             for k, v in c.values.items())
            L.append(f"| {c.name} | {c.lr:.4g} | {'yes' if c.significant else 'no'} | "
                     f"{'yes' if c.closes_gap else 'no'} | {c.aic:.4g} | {c.bic:.4g} | {vals} |")
        if self.skipped:
            L += ["", "Not testable on these data: " + "; ".join(f"{k} ({v})" for k, v in self.skipped.items())]
        L += ["", "## Confusable pairs (signature cosine ≥ %.2g)" % CONFUSABLE_COSINE, ""]
        L += [f"- {a} ~ {b}: {c:.3f}. {self.separation.get(f'{a}~{b}', '')}" for a, b, c in self.confusable] or ["- none"]
        L += ["", "## Where the baseline misfits (flagged cells)", ""]
        L += _loc_lines(self.localisation_before)
        L += ["", "## After", ""]
        L += _loc_lines(self.localisation_after)
        return "\n".join(L) + "\n"

    def write_report(self, folder) -> Path:
        """report.json and summary.md in ``folder`` (atomic); the figures are drawn by the caller
        (``scenarios.plots.diagnosis_figures``)."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        atomic_write(folder / "report.json", lambda fh: fh.write(text + "\n"))
        summ = self.summary()
        atomic_write(folder / "summary.md", lambda fh: fh.write(summ))
        return folder


def gap_shrink(d: Diagnosis) -> float:
    """(cost − expected) before / after, the excess cost removed by the named effect(s)."""
    before = d.gap_before["cost"] - d.gap_before["expected_cost"]
    after = max(d.gap_after["cost"] - d.gap_after["expected_cost"], d.gap_after["cost_std"])
    return float(before / after) if after > 0 else float("inf")


def _loc_lines(rows) -> list:
    flagged = [r for r in rows if r["flagged"]]
    if not flagged:
        return ["- no cell exceeds its band"]
    out = ["| band [Hz] | T [°C] | part | lines | RMS std. residual | RMS dB or deg | mean |", "|---|---|---|---|---|---|---|"]
    for r in flagged:
        if r["temperature_c"] is None:
            out.append(f"| {r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} | all | {r['part']} | {r['n']} | – | – | "
                       f"slope {r['slope_per_K']:.3g}/K (z = {r['z']:.3g}) |")
            continue
        out.append(f"| {r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} | {r['temperature_c']:g} | {r['part']} | {r['n']} | "
                   f"{r['rms_std']:.3g} | {r['rms_physical']:.3g} | {r['mean_std']:.3g} |")
    return out


# =============================================================================== internals


def _named_msg(c: str, cr: CandidateResult) -> str:
    e = LIBRARY[c]
    vals = "; ".join(f"{p.name} = {cr.values[p.name]:.4g} {p.unit} (95 % CI [{cr.ci_lower[p.name]:.3g}, "
                     f"{cr.ci_upper[p.name]:.3g}])" for p in e.parameters)
    return f"Named: {c} ({e.title}), LR {cr.lr:.4g}; {vals}."


def _worst_cells(rows) -> str:
    flagged = sorted((r for r in rows if r["flagged"] and r["temperature_c"] is not None), key=lambda r: r["p_value"])
    if not flagged:
        return "no single cell (a diffuse misfit)"
    parts = [f"{r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} Hz at {r['temperature_c']:g} °C ({r['part']})"
             for r in flagged[:3]]
    return ", ".join(parts)
