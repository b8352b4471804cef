"""Records of the discrepancy workflow: one candidate's refit (:class:`CandidateResult`) and the
whole diagnosis (:class:`Diagnosis`: verdict, localisation before/after, gap, report files)."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..data.files import atomic_write
from ..data.sweep import FrequencySweep
from ..effects import LIBRARY, get_effect
from ..errors import ParameterError
from .joint import JointData
from .next_measurement import NextMeasurement, json_ready
from .records import CalibrationResult

VERDICTS = ("none", "named", "ambiguous", "at_bound", "unexplained")
#: Candidates whose signatures have a canonical correlation at least this high are confusable.
CONFUSABLE_COSINE = 0.9
#: The gap test runs at α / GAP_ALPHA_DIVISOR.
GAP_ALPHA_DIVISOR = 5.0
#: An effect also "closes the gap" when what it leaves above the gap threshold is at most this
#: fraction of the baseline's excess over it (another author's parametrisation of the same effect
#: leaves a residual that grows with the effect; the report gives the remaining share).
CLOSE_FRACTION = 0.005
#: A candidate whose largest possible (linearised) LR over its bounds is below this is skipped.
MIN_SIGNATURE_LR = 1.0


# =============================================================================== progress
class ProgressMessage(str):
    """A progress message (a ``str``, so a ``progress(message)`` callback that prints it still
    works) that also carries how far the whole diagnosis is, ``fraction`` ∈ [0, 1], and its stage."""

    fraction: float
    stage: str

    def __new__(cls, text: str, fraction: float, stage: str = ""):
        out = super().__new__(cls, text)
        out.fraction = float(min(max(fraction, 0.0), 1.0))
        out.stage = stage
        return out


#: Share of the whole diagnosis at the end of each stage (progress within a stage is interpolated).
STAGE_ENDS = {"baseline": 0.08, "signatures": 0.12, "candidates": 0.45, "null": 0.70, "verdict": 0.97,
              "audit": 1.0}


def stage_progress(progress):
    """``say(stage, message, done=1, total=1)``: calls ``progress`` with a :class:`ProgressMessage`
    at the share of the whole reached after ``done`` of ``total`` steps of ``stage``."""
    order = list(STAGE_ENDS)

    def say(stage: str, message: str, done: float = 1, total: float = 1) -> None:
        if progress is None:
            return
        i = order.index(stage)
        lo = STAGE_ENDS[order[i - 1]] if i else 0.0
        frac = lo + (STAGE_ENDS[stage] - lo) * (min(done, total) / total if total > 0 else 1.0)
        progress(ProgressMessage(message, frac, stage))
    return say


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
    bounds: dict = field(default_factory=dict)
    at_bound: list = field(default_factory=list)
    implausible: list = field(default_factory=list)
    penalty: float = 0.0
    multistart: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"name": self.name, "values": self.values, "ci95_lower": self.ci_lower,
                "ci95_upper": self.ci_upper, "cost": self.cost, "lr": self.lr, "aic": self.aic,
                "bic": self.bic, "n_parameters": self.n_parameters, "significant": self.significant,
                "closes_gap": self.closes_gap, "converged": self.converged,
                "signature_norm": self.signature_norm, "lr_linearised": self.lr_linearised, "note": self.note,
                "candidate_bounds": self.bounds, "at_or_near_bound": self.at_bound,
                "outside_plausible_range": self.implausible, "penalty": self.penalty,
                "multistart": self.multistart}


@dataclass
class Diagnosis:
    """Outcome of :func:`diagnose`.

    Parameters
    ----------
    verdict : str
        One of :data:`VERDICTS`.
    named : list of str
        The effects the verdict names (empty for ``none`` and ``unexplained``).
    message : str
        The verdict in words, as the report prints it.
    kind, quantity : str
        ``"actuator"``/``"sensor"`` and the measured quantity diagnosed.
    alpha : float
        Significance level of the tests. [-]
    threshold, gap_threshold : float
        Calibrated critical values of a candidate's likelihood-ratio statistic and of the gap test
        on the baseline's 2·cost; NaN for several quantities, whose gap test is per quantity (each
        one's threshold in ``per_quantity`` and ``null["gap_test"]``, :mod:`~physmodel.estimation.gap`). [-]
    baseline, final : CalibrationResult
        The baseline fit, and the fit with the named effects (None when nothing is named).
    final_effects : dict
        Named effect → its fitted parameter values.
    candidates, skipped : dict
        Candidate name → its refit and statistics; candidate name → why it was not tried.
    confusable : list
        Declared-confusable pairs ``(a, b, cosine)``.
    separation : dict
        ``"a~b"`` → how the pair could be separated, and why it was declared.
    localisation_before, localisation_after : list
        Where (temperature, band, magnitude/phase) the residual gap lies before and after.
    gap_before, gap_after : dict
        The gap statistics before and after.
    null : dict
        How the null distribution was obtained and its figures.
    noise_estimated : bool
        The noise level was estimated from the residuals (the data declared none).
    elapsed_s : float
        Wall time of the diagnosis. [s]
    data : FrequencySweep
        The data diagnosed.
    predicted_before, predicted_after : ndarray of complex
        The baseline's and the final model's responses at the data's lines. [the data's output/input unit]
    metadata : dict
        Provenance.
    laws : str
        The temperature laws used (a stated choice).
    baseline_audit : dict
        The baseline's parameters at/near a bound or outside their plausible range, the
        multi-start spread and the penalty.
    final_at_bound, final_implausible : list
        The same for the final fit.
    cost_warning : str
        '' or why the weighted cost is inconsistent with the declared noise.
    confusability : dict
        The cross-fit (Vuong) and in-band confusability records behind ``confusable``.
    base_parameters : IPMCParameters
        The base set with the laws used.
    reduced : list
        Named effects' parameters that ended at their off value (the simpler effect is meant).
    sign_flip : dict
        The costs of the baseline and of its sign reversal (the polarity check).
    per_quantity : list
        Diagnosed over several quantities (``quantity`` is then e.g. ``"M+Z"`` and ``data`` their
        stacked lines): per quantity its lines, unit, noise (declared or estimated, median σ), weighted
        cost before/after against its expectation and whether a misfit remains, and the gap test
        there (thresholds on 2·cost before/after, ``gap_before``, ``gap_left``); [] for one quantity.
        The pooled gap test over all of them (a model closes the gap only if it closes it there too)
        is ``null["gap_test"]["pooled"]``, a last row of the summary's table.
    joint : JointData or None
        The sweeps of those quantities and the σ used (:class:`~physmodel.estimation.joint.JointData`).
    next_measurement : NextMeasurement or None
        For an ``ambiguous`` or ``at_bound`` verdict, the experiment expected to separate the
        competing models and its expected separation at this record's noise
        (:func:`physmodel.estimation.next_measurement.next_measurement`; set by
        :meth:`recommend_next_measurement`, which ``ipmc diagnose`` calls); None otherwise.
    """

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
    laws: str = ""
    baseline_audit: dict = field(default_factory=dict)
    final_at_bound: list = field(default_factory=list)
    final_implausible: list = field(default_factory=list)
    cost_warning: str = ""
    confusability: dict = field(default_factory=dict)
    base_parameters: object = field(default=None, repr=False)    # the base set with the laws used (IPMCParameters)
    reduced: list = field(default_factory=list)      # named effects' parameters at their off value (simpler form)
    sign_flip: dict = field(default_factory=dict)    # costs of the baseline and of its sign reversal
    next_measurement: NextMeasurement | None = field(default=None, repr=False)   # ambiguous / at_bound
    per_quantity: list = field(default_factory=list)   # several quantities: each one's lines, noise, costs
    joint: JointData | None = field(default=None, repr=False)   # several quantities: their JointData

    # ---------------------------------------------------------------- the next measurement
    def recommend_next_measurement(self, **kw):
        """For an ``ambiguous`` or ``at_bound`` verdict, search the experiment that would separate the
        competing models (:func:`physmodel.estimation.next_measurement.next_measurement`, keywords
        passed on), keep it in :attr:`next_measurement` (the report and model file carry it) and
        return it; None for other verdicts.

        Parameters
        ----------
        **kw
            Keywords of :func:`~physmodel.estimation.next_measurement.next_measurement`
            (``quantities``, ``band_limits_hz``, ``temperature_limits_c``, ``levels``, ``power``, ...).
        """
        from .next_measurement import next_measurement

        if self.verdict not in ("ambiguous", "at_bound"):
            return None
        self.next_measurement = next_measurement(self, **kw)
        return self.next_measurement

    # ---------------------------------------------------------------- views
    def named_effect(self) -> dict | None:
        """The named effect(s) with fitted values and 95 % intervals (None unless verdict is named)."""
        if self.verdict not in ("named", "at_bound") or self.final is None:
            return None
        out = {}
        for n in self.named:
            out[n] = {k.split(".", 1)[1]: {"value": self.final.values[k], "ci95": [self.final.ci_lower[k], self.final.ci_upper[k]],
                                            "unit": get_effect(n).parameter(k.split(".", 1)[1]).unit}
                      for k in self.final.names if k.startswith(n + ".")}
        return out

    def to_model_file(self, provenance=None):
        """The model this diagnosis ends with, as a :class:`physmodel.ModelFile`: the base
        parameters (laws included) refitted, the baseline's effects plus the named ones with their
        fitted values — the final fit when the verdict is named, ambiguous or at_bound (the verdict
        and the names travel in the file's :class:`~physmodel.model_file.FitVerdict`), the baseline
        otherwise — and the goodness of fit of that model to the data (data cost against its χ²
        expectation, prior penalties excluded).

        Parameters
        ----------
        provenance : physmodel.model_file.Provenance or None
            Where the data came from (the caller knows the file and the command).
        """
        from ..model_file import FitVerdict, ModelFile, Provenance
        from ..parameter_paths import apply_values, is_effect_parameter
        from .residuals import goodness_of_fit

        if self.base_parameters is None:
            raise ParameterError("this diagnosis does not carry its base parameters; rerun diagnose")
        use_final = self.final is not None and self.verdict in ("named", "ambiguous", "at_bound")
        fit = self.final if use_final else self.baseline
        gap = self.gap_after if use_final else self.gap_before
        effects = {k: dict(v) for k, v in (self.metadata.get("baseline_effects") or {}).items()}
        base_vals = {}
        for n, v in fit.values.items():
            if is_effect_parameter(n):
                e, p = n.split(".", 1)
                effects.setdefault(e, {})[p] = float(v)
            else:
                base_vals[n] = float(v)
        params = apply_values(self.base_parameters, base_vals)
        name = f"{self.base_parameters.name}_diagnosed"
        src = (f"ipmc diagnose ({self.verdict}" + (f": {', '.join(self.named)}" if self.named else "")
               + f") on sweep {self.metadata.get('data_fingerprint', '')[:12]}; base {self.base_parameters.name}")
        from dataclasses import replace as _replace

        params = _replace(params, name=name, source=src)
        N = self.data.frequency_hz.size
        gof = goodness_of_fit(gap["cost"], 2 * N, int(gap["n_free"]), self.noise_estimated)
        verdict = FitVerdict.from_goodness(gof, self.verdict, self.named)
        # several quantities: the file is the model of one of them (model_quantity); an effect the
        # diagnosis held off on that quantity (acts_on) is not part of its model
        q_model = self.model_quantity
        held_off = sorted(e for e, on in (self.metadata.get("acts_on") or {}).items() if q_model not in on)
        effects = {e: v for e, v in effects.items() if e not in held_off}
        estimates = [r for r in fit.estimates() if r["name"].split(".", 1)[0] not in held_off]
        notes, lead = [], []
        if held_off:
            notes.append(f"this file is the model of {q_model}; {', '.join(held_off)} acted only on "
                         + "; ".join(f"{e}: {', '.join(self.metadata['acts_on'][e])}" for e in held_off)
                         + " in the diagnosis and is left out")
        if self.verdict == "unexplained" and verdict.adequate:
            # the gap test (α/GAP_ALPHA_DIVISOR) found a gap no candidate closes while the χ² test at
            # GOF_ALPHA passes: the file says what the diagnosis found, so every later command says it
            lead.append("unexplained: a significant gap remains that no candidate effect closes "
                        "(the diagnosis's gap test); the χ² test alone passes")
            verdict = _replace(verdict, adequate=False)
        bad = [r for r in self.per_quantity if r.get("misfit")]
        if bad:                             # a misfit in one quantity is a misfit of the model, said first
            lead.append("a misfit remains in " + "; ".join(
                f"{r['quantity']} (cost {r['cost_after']:.4g}, expected {r['expected_after']:.4g}, above its χ² band)"
                for r in bad) + "; pooled over every quantity")
            verdict = _replace(verdict, adequate=False)
        if notes or lead:
            verdict = _replace(verdict, reason="; ".join([": ".join(lead + [verdict.reason.rstrip(".")])] + notes))
        if self.next_measurement is not None:         # the later commands that read the file say it too
            verdict = _replace(verdict, reason=f"{verdict.reason.rstrip('.')}. {self.next_measurement.message}")
        if self.null.get("thin_tail"):               # a test level its null draws leave uncertain, said too
            verdict = _replace(verdict, reason=f"{verdict.reason.rstrip('.')}. {self.null['thin_tail']}")
        if provenance is None:
            provenance = Provenance("physmodel.diagnose", data_fingerprint=self.metadata.get("data_fingerprint"),
                                    temperatures_c=tuple(self.data.temperatures().tolist()),
                                    band_hz=(float(self.data.frequency_hz.min()), float(self.data.frequency_hz.max())))
        return ModelFile(self.kind, params, effects, q_model, self.metadata.get("kernel", "boundary_charge"),
                         verdict, tuple(estimates), provenance)

    @property
    def model_quantity(self) -> str:
        """The quantity :meth:`to_model_file` writes the model of: the diagnosed one, or of several
        the kind's default (M for an actuator, S for a sensor) when it was among them, else the first."""
        from ..effects import DEFAULT_QUANTITY

        qs = self.quantity.split("+")
        return DEFAULT_QUANTITY.get(self.kind, qs[0]) if DEFAULT_QUANTITY.get(self.kind) in qs else qs[0]

    def to_dict(self) -> dict:
        return json_ready({
            "format": "ipmc-diagnosis", "version": 1,
            "verdict": self.verdict, "named": list(self.named), "message": self.message,
            "named_effect": self.named_effect(),
            "kind": self.kind, "quantity": self.quantity, "alpha": self.alpha,
            "quantities": self.quantity.split("+"), "per_quantity": self.per_quantity,
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
            "temperature_laws": self.laws, "baseline_audit": self.baseline_audit,
            "baseline_parameters": self._baseline_rows(), "final_at_bound": self.final_at_bound,
            "final_outside_plausible_range": self.final_implausible, "cost_warning": self.cost_warning,
            "confusability": self.confusability, "reduced_to_simpler_form": self.reduced,
            "sign_flip": self.sign_flip,
            "next_measurement": self.next_measurement.to_dict() if self.next_measurement is not None else None,
        })

    def _baseline_rows(self) -> list:
        b = self.baseline
        rng = self.baseline_audit.get("plausible_ranges", {})
        flags = {a["name"]: f"{a['status']} {a['side']} bound" for a in self.baseline_audit.get("at_bound", [])}
        out_r = {a["name"] for a in self.baseline_audit.get("implausible", [])}
        spread = self.baseline_audit.get("multistart", {}).get("ranges", {})
        rows = []
        for fp in b.free:
            n = fp.name
            rows.append({"name": n, "value": b.values[n], "ci95": [b.ci_lower.get(n), b.ci_upper.get(n)],
                         "bounds": [fp.lower, fp.upper], "plausible": rng.get(n, "none"),
                         "flag": "; ".join(x for x in (flags.get(n, ""), "outside plausible range" if n in out_r else "")
                                           if x), "multistart_range": spread.get(n)})
        return rows

    def summary(self) -> str:
        """A readable Markdown summary."""
        L = [f"# Discrepancy diagnosis: {self.verdict.upper()}", "", self.message, ""]
        nm = self.next_measurement
        if nm is not None:
            L += ["## Next measurement", "", f"**{nm.message}**", ""]
            if nm.ranking:
                L += [f"Method: linearised T-optimal discrimination (Atkinson & Fedorov 1975) of "
                      f"{' vs '.join(' + '.join(m) for m in nm.models)}; {nm.evaluated} experiments evaluated, "
                      f"separation needed λ ≥ {nm.target:.3g}. Best by expected separation:", "",
                      "| quantity | band [Hz] | T [°C] | drive | lines | λ (linearised) | power |", "|---|---|---|---|---|---|---|"]
                L += [f"| {r.quantity} | {r.band_hz[0]:.3g}–{r.band_hz[1]:.3g} | "
                      f"{', '.join(f'{t:g}' for t in r.temperatures_c)} | ×{r.level:g} | {r.n_lines} | "
                      f"{r.separation:.3g} | {r.power:.2f} |" for r in nm.ranking[:5]]
                L += [""]
        if self.noise_estimated:
            L += ["*The data carry no per-line uncertainty: 1 % per line was assumed; absolute gap "
                  "tests are relative to that assumption.*", ""]
        if self.cost_warning:
            L += [f"**Cost vs declared noise — {self.cost_warning}.**", ""]
        L += [f"Temperature laws: {self.laws}", ""]
        if self.per_quantity:
            L += ["## Per quantity (diagnosed jointly)", "", "| quantity | lines | unit | noise | σ dB / deg (median) | "
                  "cost before | cost after | expected | misfit left | gap threshold on 2·cost before / after | "
                  "gap left |", "|---|---|---|---|---|---|---|---|---|---|---|"]
            L += [f"| {r['quantity']} | {r['lines']} | {r['unit']} | {r['noise']} | {r['sigma_db_median']:.3g} / "
                  f"{r['sigma_deg_median']:.3g} | {r['cost_before']:.4g} | {r['cost_after']:.4g} | "
                  f"{r['expected_after']:.4g} | {'not tested (estimated noise)' if r['misfit'] is None else 'yes' if r['misfit'] else 'no'} | "
                  f"{_g(r.get('gap_threshold_before_2cost'))} / {_g(r.get('gap_threshold_after_2cost'))} | "
                  f"{'yes' if r.get('gap_left') else 'no'} |" for r in self.per_quantity]
            pq = self.null.get("gap_test", {}).get("pooled") or {}
            if "gap_left" in pq:         # the pooled gap test: closing needs it too (estimation.gap)
                L += [f"| {pq['test']} | {sum(r['lines'] for r in self.per_quantity)} | – | – | – | "
                      f"{pq['two_cost_before'] / 2:.4g} | {pq['two_cost_after'] / 2:.4g} | – | – | "
                      f"{_g(pq['threshold_before_2cost'])} / {_g(pq['threshold_after_2cost'])} | "
                      f"{'yes' if pq['gap_left'] else 'no'} |"]
            L += [""]
        L += ["## Baseline parameters", "", "| parameter | value | 95 % CI | fit bounds | plausible range | flag | "
              "multi-start range |", "|---|---|---|---|---|---|---|"]
        for r in self._baseline_rows():
            ci = r["ci95"]
            ms = r["multistart_range"]
            L.append(f"| {r['name']} | {r['value']:.4g} | [{_g(ci[0])}, {_g(ci[1])}] | [{r['bounds'][0]:.3g}, "
                     f"{r['bounds'][1]:.3g}] | {r['plausible']} | {r['flag'] or '–'} | "
                     + (f"[{ms[0]:.4g}, {ms[1]:.4g}]" if ms else "–") + " |")
        ms = self.baseline_audit.get("multistart", {})
        if ms.get("n_starts"):
            L += ["", f"Multi-start: {ms['n_at_best']} of {ms['n_starts']} starts reach the best cost (within "
                      f"{ms['tolerance']:g}); start costs " + ", ".join(f"{c:.4g}" for c in ms["costs"]) + "."]
        if self.baseline_audit.get("penalty", 0) > 0:
            L += ["", f"Plausible-range penalty of the baseline: {self.baseline_audit['penalty']:.4g} (cost units)."]
        L += [""]
        gb, ga = self.gap_before, self.gap_after
        L += ["## Gap before / after", "",
              "| | weighted cost | expected | z | " + " | ".join(f"{t:g} °C dB / deg" for t in gb["temperatures_c"]) + " |",
              "|---|---|---|---|" + "---|" * len(gb["temperatures_c"])]
        for lab, g in (("before", gb), ("after", ga)):
            L.append(f"| {lab} | {g['cost']:.4g} | {g['expected_cost']:.4g} ± {g['cost_std']:.3g} | {g['z']:.3g} | "
                     + " | ".join(f"{a:.3g} / {b:.3g}" for a, b in zip(g["rms_db"], g["rms_deg"])) + " |")
        L += ["", f"Gap shrink (cost − expected, before / after): {gap_shrink_words(self)}", "",
              f"LR threshold (at {self.alpha * (1 - 1 / GAP_ALPHA_DIVISOR):g} of the verdict's family-wise "
              f"α = {self.alpha:g}, Monte Carlo under the null): {self.threshold:.3g}; "
              f"gap threshold on 2·cost (at α/{GAP_ALPHA_DIVISOR:g}): " + (f"{self.gap_threshold:.4g}" if not self.per_quantity
                                                                          else "per quantity, in the table above"), "",
              "## Candidates", "", "| effect | LR | significant | closes gap | AIC | BIC | fitted values "
              "[candidate bounds] | at/near a bound, outside plausible range |",
              "|---|---|---|---|---|---|---|---|"]
        for c in sorted(self.candidates.values(), key=lambda c: -c.lr):
            vals = ", ".join(f"{k} = {v:.4g} (CI [{c.ci_lower[k]:.3g}, {c.ci_upper[k]:.3g}]; bounds "
                             f"[{c.bounds.get(k, [float('nan')] * 2)[0]:.3g}, {c.bounds.get(k, [float('nan')] * 2)[1]:.3g}])"
                             for k, v in c.values.items())
            flags = "; ".join([f"{a['name']} {a['status']} {a['side']} bound {a['bound']:.3g}"
                               + (" (physical limit)" if a["hard"] else "") for a in c.at_bound]
                              + [f"{a['name']} = {a['value']:.3g} outside [{a['lower']:.3g}, {a['upper']:.3g}]"
                                 for a in c.implausible]) or "–"
            L.append(f"| {c.name} | {c.lr:.4g} | {'yes' if c.significant else 'no'} | "
                     f"{'yes' if c.closes_gap else 'no'} | {c.aic:.4g} | {c.bic:.4g} | {vals} | {flags} |")
        pt = self.metadata.get("pairs_tried", [])
        if pt:
            L += ["", "Pairs refitted jointly: " + "; ".join(
                f"{p['pair'][0]} + {p['pair'][1]}: cost {p['cost']:.4g}, LR on top {p['lr_first_on_top']:.3g} / "
                f"{p['lr_second_on_top']:.3g}{', closes the gap' if p['closes_gap'] else ''}" for p in pt)]
        if self.final_at_bound:
            L += ["", "Final fit, parameters at a bound: " + "; ".join(
                f"{a['name']} = {a['value']:.4g} ({a['side']} bound {a['bound']:.4g}"
                + (", physical limit)" if a["hard"] else ")") for a in self.final_at_bound)]
        if self.skipped:
            L += ["", "Not testable on these data: " + "; ".join(f"{k} ({v})" for k, v in self.skipped.items())]
        L += ["", "## Confusable pairs", "", f"Declared confusable: first-order signature cosine ≥ {CONFUSABLE_COSINE:.2g}, "
              "confusable in this band at the fitted sizes (noiseless cross-fit), or not separated by the data "
              "(Vuong's test).", ""]
        L += [f"- {a} ~ {b}: cosine {c:.3f}. {self.separation.get(f'{a}~{b}', '')}" for a, b, c in self.confusable] or ["- none"]
        cf = self.confusability
        if cf.get("in_band") or cf.get("data"):
            L += ["", f"Vuong's test at α = {self.alpha:g} (critical |z| {cf.get('z_critical', float('nan')):.3g}) "
                      f"against the best closer {cf.get('top', '–')}:", "",
                  "| candidate | z (data) | separated by the data | λ(it → best) | λ(best → it) | power | "
                  "confusable in this band |", "|---|---|---|---|---|---|---|"]
            ib = {x["other"]: x for x in cf.get("in_band", [])}
            for x in cf.get("data", []):
                y = ib.get(x["other"], {})
                L.append(f"| {x['other']} | {x['z']:.3g} | {'yes' if x['separated'] else 'no'} | "
                         f"{_g(y.get('lambda_other_to_top'))} | {_g(y.get('lambda_top_to_other'))} | "
                         f"{_g(y.get('power'))} | {'yes' if y.get('confusable') else ('no' if y else '–')} |")
        ms = [c for c in self.candidates.values() if c.multistart.get("n_starts")]
        if ms:
            L += ["", "Candidate refit multi-start (best origin; starts reaching the best cost within 1; "
                      "cost spread over starts): " + "; ".join(
                          f"{c.name}: {c.multistart['best_origin']}, {c.multistart['n_at_best']}/"
                          f"{c.multistart['n_starts']}, {c.multistart['cost_spread']:.3g}" for c in ms)]
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
    """(cost − expected) before / after, the excess cost removed by the named effect(s); the after
    excess floored at the cost's spread.  NaN when there was no gap to shrink: the cost before
    within one spread of its expectation (e.g. a verdict ``none`` on a record the baseline fits;
    the ratio of two noise-size numbers, negative below the expectation, meant nothing)."""
    before = d.gap_before["cost"] - d.gap_before["expected_cost"]
    if not before > d.gap_before["cost_std"]:
        return float("nan")
    after = max(d.gap_after["cost"] - d.gap_after["expected_cost"], d.gap_after["cost_std"])
    return float(before / after) if after > 0 else float("inf")


def gap_shrink_words(d: Diagnosis) -> str:
    """:func:`gap_shrink` as said in a message or report: ``"12.3×"``, or that there was no gap."""
    g = gap_shrink(d)
    return f"{g:.3g}×" if g == g else "none to shrink (the cost before was within its spread of the expectation)"


def _loc_lines(rows) -> list:
    flagged = [r for r in rows if r["flagged"]]
    if not flagged:
        return ["- no cell exceeds its band"]
    out = ["| band [Hz] | T [°C] | part | lines | RMS std. residual | RMS dB or deg | mean |", "|---|---|---|---|---|---|---|"]
    for r in flagged:
        if "quantity" in r:          # a joint record: the quantity with the part
            r = {**r, "part": f"{r['quantity']} {r['part']}"}
        if r["temperature_c"] is None:
            out.append(f"| {r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} | all | {r['part']} | {r['n']} | – | – | "
                       f"slope {r['slope_per_K']:.3g}/K (z = {r['z']:.3g}) |")
            continue
        out.append(f"| {r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} | {r['temperature_c']:g} | {r['part']} | {r['n']} | "
                   f"{r['rms_std']:.3g} | {r['rms_physical']:.3g} | {r['mean_std']:.3g} |")
    return out


# =============================================================================== internals


def _g(x) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:.3g}"


def resolve_laws(base, laws):
    """``(base with the chosen laws, a sentence stating the choice)``.

    ``laws``: None or ``"set"`` (the laws of ``base``), ``"isothermal"`` (every parameter
    constant), ``"default"`` (physics.md §7: Arrhenius d 15 kJ/mol, log-linear E −0.75 %/K, water
    permittivity, ionic leakage), a :class:`~physmodel.temperature.TemperatureLaws`, or a mapping
    ``{"base": one of those names, <quantity>: {"law": name, <parameter>: value} | name}``."""
    from dataclasses import replace

    from ..errors import ParameterError
    from ..temperature import ISOTHERMAL, TemperatureLaws

    named = {"isothermal": ISOTHERMAL, "default": TemperatureLaws(), "set": None}
    if laws is None:
        return base, f"those of the parameter set {base.name!r}: {base.laws.describe()}"
    if isinstance(laws, TemperatureLaws):
        return replace(base, laws=laws), f"given: {laws.describe()}"
    if isinstance(laws, str):
        if laws not in named:
            raise ParameterError(f"laws = {laws!r}; expected one of {sorted(named)}, a table of laws, or TemperatureLaws")
        chosen = named[laws] or base.laws
        return replace(base, laws=chosen), f"{laws!r}: {chosen.describe()}"
    if isinstance(laws, Mapping):
        spec = dict(laws)
        start = spec.pop("base", "set")
        if start not in named:
            raise ParameterError(f"laws.base = {start!r}; expected one of {sorted(named)}")
        cur = (named[start] or base.laws).to_dict()
        for k, v in spec.items():
            if k not in cur:
                raise ParameterError(f"laws: no temperature law for {k!r}; expected one of {sorted(cur)}")
            cur[k] = {"law": v} if isinstance(v, str) else dict(v)
            if "law" not in cur[k]:
                raise ParameterError(f"laws.{k} = {v!r}: give the law's name, e.g. {{law = \"Arrhenius\", "
                                     "activation_energy = 15e3}")
        try:
            chosen = TemperatureLaws.from_dict(cur)
        except TypeError as exc:
            raise ParameterError(f"laws: {exc}") from None
        return replace(base, laws=chosen), f"{start!r} with changes: {chosen.describe()}"
    raise ParameterError(f"laws must be None, a name, a mapping or TemperatureLaws; got {type(laws).__name__}")


def named_message(c: str, cr: CandidateResult) -> str:
    """The sentence that names effect ``c``: its title, LR and each fitted value with its 95 % interval."""
    e = LIBRARY[c]
    vals = "; ".join(f"{p.name} = {cr.values[p.name]:.4g} {p.unit} (95 % CI [{cr.ci_lower[p.name]:.3g}, "
                     f"{cr.ci_upper[p.name]:.3g}])" for p in e.parameters)
    return f"Named: {c} ({e.title}), LR {cr.lr:.4g}; {vals}."


def worst_cells(rows) -> str:
    """The (up to three) most significant flagged cells of a localisation table, as words."""
    flagged = sorted((r for r in rows if r["flagged"] and r["temperature_c"] is not None), key=lambda r: r["p_value"])
    if not flagged:
        return "no single cell (a diffuse misfit)"
    parts = [(f"{r['quantity']} " if "quantity" in r else "")        # a joint record's rows name their quantity
             + f"{r['band_hz'][0]:.3g}–{r['band_hz'][1]:.3g} Hz at {r['temperature_c']:g} °C ({r['part']})"
             for r in flagged[:3]]
    return ", ".join(parts)


def audit_notes(verdict: str, at_bound: list, widen: list, audit0: dict, final_implausible: list, res0, cres: dict) -> str:
    """The sentences a diagnosis message ends with: parameters at a bound (final fit, and the baseline's
    when nothing was named), plausible-range violations, and fits that did not converge."""
    out = ""
    other_bounds = [a for a in at_bound if a not in widen and not a["hard"]]
    if other_bounds:
        out += (" Parameters at a bound in the final fit: " + "; ".join(
            f"{a['name']} = {a['value']:.4g} ({a['side']} bound {a['bound']:.4g})" for a in other_bounds) + ".")
    b0 = [a for a in audit0["at_bound"] if a["status"] == "at"]
    if b0 and verdict in ("none", "unexplained"):
        out += " Baseline parameters at a fit bound: " + "; ".join(
            f"{a['name']} = {a['value']:.4g} ({a['side']} bound {a['bound']:.4g})" for a in b0) + "."
    if audit0["implausible"]:
        bad0 = ", ".join(f"{x['name']} = {x['value']:.3g} {x['unit']} (plausible [{x['lower']:.3g}, {x['upper']:.3g}])"
                         for x in audit0["implausible"])
        out += (f" The baseline fits only by leaving the plausible range of {bad0}: that is itself evidence of a "
                "missing effect" + ("." if verdict != "none" else "; consider the candidates above or "
                                    "revise the plausible range if it does not apply to this strip."))
    if final_implausible:
        out += " In the final fit outside the plausible range: " + ", ".join(
            f"{x['name']} = {x['value']:.3g} {x['unit']}" for x in final_implausible) + "."
    if not res0.converged:
        out += f" WARNING: the baseline calibration did not converge ({res0.message})."
    bad = [c for c, cr in cres.items() if not cr.converged]
    if bad:
        out += f" Candidate refits that did not converge: {', '.join(bad)}."
    return out
