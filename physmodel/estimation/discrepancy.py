"""The discrepancy workflow: locate a misfit, name the missing effect, add it, show the gap shrink.

:func:`diagnose` (discrepancy.md) takes frequency-response data, a base parameter set and the
user's free parameters, and:

1. calibrates the baseline model (:func:`physmodel.estimation.calibration.fit_parameters`, the project's one
   calibration engine) and tabulates where the standardised residuals exceed their band
   (frequency band × temperature × magnitude/phase, and the trend with temperature);
2. refits the full model with each candidate effect of :data:`physmodel.effects.LIBRARY` switched
   on (nested, full nonlinear refits) and scores it by the likelihood-ratio statistic
   LR = 2 (cost_baseline − cost_candidate), with AIC/BIC alongside;
3. sets the acceptance threshold by Monte Carlo under the null (no effect), so that the
   *family-wise* false-positive rate of "max over candidates of LR" is α:

   * a linearised Gaussian null at the fitted baseline: standardised noise e ~ N(0, I) with the
     baseline Jacobian projected out, and for each candidate the exact constrained LR of the
     linearised problem (parameters whose "off" value is a bound enter one-sided, which gives the
     χ̄² mixture), ``null_draws`` draws (default 4000, milliseconds);
   * a parametric bootstrap with full nonlinear refits (simulate from the fitted baseline with the
     data's noise, refit baseline and every candidate) on the first ``null_refits`` of the same
     noise draws (default 4): the ratio Σ LR_full / Σ LR_lin over these draws (clipped to
     [1, 3]) scales the linearised threshold, correcting it for nonlinearity at the cost of a
     few refits;

4. reports as *confusable* the candidate pairs whose signatures (Jacobian columns with the
   baseline Jacobian projected out) have a largest canonical correlation ≥ :data:`CONFUSABLE_COSINE`;
5. decides: ``none`` (no significant LR and no significant gap), ``named`` (one significant
   candidate that closes the gap, or a greedy second effect when the first leaves a significant
   gap), ``ambiguous`` (several significant candidates that close the gap and whose AIC differ by
   less than :data:`AMBIGUITY_AIC`), ``unexplained`` (a significant gap that no candidate, or
   pair, closes).  The gap test compares 2·cost with the (1 − α/5) quantile of its null
   distribution from the same Monte Carlo (stricter than α: a false "unexplained" costs a name).

Residuals are those of :func:`physmodel.estimation.calibration.residuals`: ln-magnitude/σ_ln and wrapped
phase/σ_φ per line.  Data without per-line standard deviations use the calibration module's
fallback (1 % per line); the report says so, and absolute gap tests are then relative to that.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from ..data.files import atomic_write
from ..data.sweep import FrequencySweep
from ..effects import DEFAULT_QUANTITY, LIBRARY, EffectModel, candidates_for, get_effect, normalize_effects
from ..errors import IPMCError, ParameterError
from ..params import IPMCParameters
from ..parameter_paths import base_value
from .calibration import default_free_parameter
from .lsq import fit_parameters
from .records import CalibrationResult, FreeParameter
from .residuals import noise_std, standardised_residuals

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
def _z_jacobian(predict_many, values: dict, params: Sequence[FreeParameter], r0, data, s_ln, s_ph, step=1e-4):
    """Forward-difference Jacobian of the standardised residuals in the scaled z space."""
    pts, steps = [], []
    for fp in params:
        z = float(fp.to_z(values[fp.name]))
        lo, hi = fp.z_bounds
        h = step if z + step <= hi else -step
        v = dict(values)
        v[fp.name] = float(fp.from_z(z + h))
        pts.append(v)
        steps.append(h)
    G = predict_many(pts)
    R = standardised_residuals(G, data, s_ln, s_ph)
    return ((R - r0[None, :]) / np.array(steps)[:, None]).T


def _signature(predict_many, values: dict, effect: str, r0, data, s_ln, s_ph):
    """Columns d r/d δ at "off" for each effect parameter, δ in units of (typical − off);
    and which are one-sided (off at a bound)."""
    e = LIBRARY[effect]
    pts, steps, one_sided = [], [], []
    for p in e.parameters:
        span = p.typical - p.off
        h = 1e-3
        v = dict(values)
        v[f"{effect}.{p.name}"] = p.off + h * span
        pts.append(v)
        steps.append(h)
        one_sided.append(p.off in (p.lower, p.upper))
    G = predict_many(pts)
    R = standardised_residuals(G, data, s_ln, s_ph)
    return ((R - r0[None, :]) / np.array(steps)[:, None]).T, np.array(one_sided)


def _orth(A):
    if A.shape[1] == 0:
        return A
    Q, R = np.linalg.qr(A)
    keep = np.abs(np.diag(R)) > 1e-10 * max(1.0, np.abs(np.diag(R)).max())
    return Q[:, keep]


def _project_out(Q, A):
    return A - Q @ (Q.T @ A) if Q.shape[1] else A


def _constrained_lr(S, one_sided, E):
    """Max over δ (one-sided components ≥ 0) of 2δᵀSᵀe − δᵀSᵀSδ for every column e of E.

    Exact for ≤ 3 parameters by enumerating active sets (concave quadratic)."""
    k = S.shape[1]
    best = np.zeros(E.shape[1])
    for m in range(1, k + 1):
        for sub in combinations(range(k), m):
            Ss = S[:, sub]
            G = Ss.T @ Ss
            try:
                Ginv = np.linalg.pinv(G)
            except np.linalg.LinAlgError:  # pragma: no cover
                continue
            b = Ss.T @ E                        # (m, n)
            d = Ginv @ b
            lr = np.sum(b * d, axis=0)
            ok = np.ones(E.shape[1], bool)
            for j, c in enumerate(sub):
                if one_sided[c]:
                    ok &= d[j] >= 0
            best = np.where(ok & (lr > best), lr, best)
    return best


def _localise(data: FrequencySweep, r: np.ndarray, alpha: float, n_bands: int = 4) -> list:
    """Standardised residuals by band × temperature × part, flagged at Bonferroni level α."""
    from scipy.stats import chi2

    N = data.frequency_hz.size
    lf = np.log10(data.frequency_hz)
    edges = np.linspace(lf.min(), lf.max() + 1e-12, n_bands + 1)
    band = np.clip(np.searchsorted(edges, lf, side="right") - 1, 0, n_bands - 1)
    temps = data.temperatures()
    s_ln, s_ph, _ = noise_std(data)
    parts = (("magnitude", r[:N], s_ln * 20 / math.log(10)), ("phase", r[N:], np.degrees(s_ph)))
    rows = []
    cells = n_bands * temps.size * 2
    for bi in range(n_bands):
        for pname, rr, scale in parts:
            means = []
            for t in temps:
                m = (band == bi) & (data.temperature_c == t)
                n = int(m.sum())
                if n == 0:
                    continue
                x = rr[m]
                ss = float(np.sum(x * x))
                p = float(chi2.sf(ss, n))
                rows.append({"band_hz": [float(10 ** edges[bi]), float(10 ** edges[bi + 1])],
                             "temperature_c": float(t), "part": pname, "n": n,
                             "rms_std": float(math.sqrt(ss / n)), "mean_std": float(x.mean()),
                             "rms_physical": float(np.sqrt(np.mean((x * scale[m]) ** 2))),
                             "p_value": p, "flagged": bool(p < alpha / cells)})
                means.append((float(t), float(x.mean()), n))
            if len(means) >= 3:
                T = np.array([m[0] for m in means])
                y = np.array([m[1] for m in means])
                w = np.array([m[2] for m in means], float)    # var(mean) = 1/n
                Tm = np.sum(w * T) / w.sum()
                sxx = np.sum(w * (T - Tm) ** 2)
                slope = float(np.sum(w * (T - Tm) * y) / sxx)
                z = slope * math.sqrt(sxx)
                rows.append({"band_hz": [float(10 ** edges[bi]), float(10 ** edges[bi + 1])], "temperature_c": None,
                             "part": pname + " trend with T", "n": int(w.sum()), "rms_std": float("nan"),
                             "mean_std": slope, "rms_physical": float("nan"),
                             "p_value": float(2 * _norm_sf(abs(z))), "flagged": bool(2 * _norm_sf(abs(z)) < alpha / cells),
                             "slope_per_K": slope, "z": float(z)})
    return rows


def _norm_sf(z):
    return 0.5 * math.erfc(z / math.sqrt(2))


def _gap(data: FrequencySweep, r: np.ndarray, n_free: int) -> dict:
    N = data.frequency_hz.size
    s_ln, s_ph, _ = noise_std(data)
    cost = float(0.5 * r @ r)
    exp = N - n_free / 2.0
    temps = data.temperatures()
    db = r[:N] * s_ln * 20 / math.log(10)
    deg = np.degrees(r[N:] * s_ph)
    return {"cost": cost, "expected_cost": exp, "cost_std": math.sqrt(max(exp, 1e-12)),
            "z": (cost - exp) / math.sqrt(max(exp, 1e-12)), "n_free": n_free,
            "temperatures_c": temps.tolist(),
            "rms_db": [float(np.sqrt(np.mean(db[data.temperature_c == t] ** 2))) for t in temps],
            "rms_deg": [float(np.sqrt(np.mean(deg[data.temperature_c == t] ** 2))) for t in temps]}


def _free_list(base: IPMCParameters, free, effects: dict) -> list:
    out = []
    for item in free:
        if isinstance(item, FreeParameter):
            fp = item
        elif isinstance(item, str):
            if "." in item and not item.startswith("laws."):
                e, p = item.split(".", 1)
                if e not in effects:
                    raise ParameterError(f"free parameter {item!r} belongs to effect {e!r}, which is not among "
                                         f"the baseline effects {sorted(effects)}")
                par = get_effect(e).parameter(p)
                fp = FreeParameter(item, par.lower, par.upper, "linear", effects[e][p])
            else:
                fp = default_free_parameter(base, item)
        else:
            raise ParameterError(f"free parameters must be names or FreeParameter, got {item!r}")
        if fp.initial is None:
            if "." in fp.name and not fp.name.startswith("laws."):
                e, p = fp.name.split(".", 1)
                v = effects[e][p]
            else:
                v = base_value(base, fp.name)
            fp = fp.with_initial(min(max(v, fp.lower), fp.upper))
        out.append(fp)
    return out


def _effect_free(effect: str, start: Mapping[str, float] | None = None) -> list:
    e = LIBRARY[effect]
    out = []
    for p in e.parameters:
        v = p.off if start is None else float(np.clip(start[p.name], p.lower, p.upper))
        out.append(FreeParameter(f"{effect}.{p.name}", p.lower, p.upper, "linear", v))
    return out


def _simulated(G, e, s_ln, s_ph):
    N = G.size
    return G * np.exp(e[:N] * s_ln + 1j * e[N:] * s_ph)


# =============================================================================== main entry
def diagnose(data: FrequencySweep, base: IPMCParameters, *, kind: str = "actuator", quantity: str | None = None,
             free: Sequence[str | FreeParameter] = ("alpha0",),
             baseline_effects: Mapping[str, Mapping[str, float]] | Sequence[str] = (),
             candidates: Sequence[str] | None = None, alpha: float = 0.05, null_draws: int = 4000,
             null_refits: int = 4, seed: int = 0, kernel: str = "boundary_charge", max_nfev: int = 200,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """Diagnose the discrepancy between ``data`` and the ``base`` model (see module docstring).

    ``free``: the user's calibration parameters (names with default bounds, ``"effect.param"`` of a
    baseline effect, or :class:`FreeParameter`).  ``baseline_effects``: effects already in the model
    (``{name: {param: value}}``; a bare name means all its parameters free from their off value).
    ``candidates``: library names to test (default: all that apply to ``kind``/``quantity`` and are
    not in the baseline).  ``alpha``: family-wise false-positive rate.  ``null_draws``: linearised
    null Monte Carlo draws; ``null_refits``: full nonlinear bootstrap refits (see module doc).
    ``progress(message)`` is called after each stage.
    """
    t0 = time.perf_counter()
    if not isinstance(data, FrequencySweep):
        raise IPMCError(f"data must be a FrequencySweep, got {type(data).__name__}")
    if not isinstance(base, IPMCParameters):
        raise ParameterError(f"base must be IPMCParameters, got {type(base).__name__}")
    if not (0 < alpha < 0.5):
        raise IPMCError(f"alpha={alpha!r} must lie in (0, 0.5)")
    if int(null_draws) < 200:
        raise IPMCError(f"null_draws={null_draws!r} is too small for a {1 - alpha:g} quantile; use >= 200")
    if int(null_refits) < 0:
        raise IPMCError(f"null_refits={null_refits!r} must be >= 0")
    q = quantity or DEFAULT_QUANTITY.get(kind, "")
    say = progress or (lambda msg: None)
    if isinstance(baseline_effects, Mapping):
        beff = normalize_effects(baseline_effects)
        extra_free = []
    else:
        beff = normalize_effects({n: {} for n in baseline_effects})
        extra_free = [f"{n}.{p.name}" for n in beff for p in get_effect(n).parameters]
    model0 = EffectModel(base, kind, beff, kernel=kernel)
    predict = model0.predictor(data, q)
    pm = predict.many
    free0 = _free_list(base, list(free) + [f for f in extra_free if f not in free], beff)
    names0 = [fp.name for fp in free0]
    s_ln, s_ph, estimated = noise_std(data)
    N = data.frequency_hz.size
    n_temps = data.temperatures().size

    # ---- 1. baseline
    res0 = fit_parameters(data, None, free0, predict_many=pm, max_nfev=max_nfev, identify=True,
                          hold_undetermined=False, seed=seed)
    v0 = dict(res0.values)
    G0 = pm([v0])[0]
    r0 = standardised_residuals(G0, data, s_ln, s_ph)
    say(f"baseline fitted: cost {res0.cost:.4g} (expected {res0.expected_cost:.4g})")

    # ---- 2. signatures, confusability
    cand = list(candidates) if candidates is not None else [
        c for c in candidates_for(kind, q, n_temps) if c not in beff]
    for c in cand:
        if c not in LIBRARY:
            raise ParameterError(f"unknown candidate effect {c!r}; expected library names {sorted(LIBRARY)}")
        if not LIBRARY[c].applies_to(kind, q):
            raise ParameterError(f"candidate {c!r} does not apply to {kind} quantity {q}")
    J0 = _z_jacobian(pm, v0, free0, r0, data, s_ln, s_ph)
    Q0 = _orth(J0)
    sigs, sided, skipped, first_order, raw_sigs = {}, {}, {}, {}, {}
    for c in cand:
        S, one = _signature(pm, v0, c, r0, data, s_ln, s_ph)
        Sp = _project_out(Q0, S)
        e = LIBRARY[c]
        reach = np.array([max(abs(p.upper - p.off), abs(p.lower - p.off)) / abs(p.typical - p.off) for p in e.parameters])
        max_lr = float(np.sum((np.linalg.norm(Sp, axis=0) * reach) ** 2))
        if not np.all(np.isfinite(S)) or np.sum((np.linalg.norm(S, axis=0) * reach) ** 2) < MIN_SIGNATURE_LR:
            skipped[c] = "no signature on these data (cannot change the cost by the noise level)"
            continue
        sigs[c], sided[c], raw_sigs[c] = Sp, one, S
        if max_lr < MIN_SIGNATURE_LR:
            first_order[c] = "confounded with the free parameters to first order (refitted; only nonlinear terms can show it)"
    confusable = []
    orth = {c: _orth(S) for c, S in sigs.items() if c not in first_order}
    for a, b in combinations(orth, 2):
        if orth[a].shape[1] == 0 or orth[b].shape[1] == 0:
            continue
        cos = float(np.linalg.svd(orth[a].T @ orth[b], compute_uv=False).max())
        if cos >= CONFUSABLE_COSINE:
            confusable.append((a, b, min(cos, 1.0)))
    separation = {f"{a}~{b}": _separation(a, b, raw_sigs, data) for a, b, _ in confusable}
    conf_set = {frozenset((a, b)) for a, b, _ in confusable}

    # ---- 3. linearised null Monte Carlo
    rng = np.random.default_rng(seed + 7919)
    E = rng.standard_normal((2 * N, int(null_draws)))
    Ep = _project_out(Q0, E)
    lin = {c: _constrained_lr(S, sided[c], Ep) for c, S in sigs.items()}
    lin_max = np.max(np.vstack(list(lin.values())), axis=0) if lin else np.zeros(E.shape[1])
    cost2_null = np.sum(Ep * Ep, axis=0)
    T_lin = float(np.quantile(lin_max, 1 - alpha))
    alpha_gap = alpha / GAP_ALPHA_DIVISOR
    gap_thr0 = float(np.quantile(cost2_null, 1 - alpha_gap))
    say(f"linearised null: LR threshold {T_lin:.3g} from {E.shape[1]} draws")

    # ---- 4. candidate refits
    def refit(effects_on: Sequence[str], start_vals: dict, eff_starts: list[dict | None]):
        best = None
        for starts in eff_starts:
            fr = [fp.with_initial(min(max(start_vals[fp.name], fp.lower), fp.upper)) for fp in free0]
            for c in effects_on:
                st = None if starts is None else starts.get(c)
                if st is None and any(k.startswith(c + ".") for k in start_vals):
                    st = {k.split(".", 1)[1]: v for k, v in start_vals.items() if k.startswith(c + ".")}
                fr += _effect_free(c, st)
            res = fit_parameters(data, None, fr, predict_many=pm, max_nfev=max_nfev, identify=True,
                                 hold_undetermined=False, seed=seed)
            if best is None or res.cost < best.cost:
                best = res
        return best

    def lin_start(c, r_now, Qb):
        """Linearised estimate of the effect's values from the current residual."""
        S = _project_out(Qb, sigs[c])
        d, *_ = np.linalg.lstsq(S, -r_now, rcond=None)
        e = LIBRARY[c]
        return {p.name: p.off + d[j] * (p.typical - p.off) for j, p in enumerate(e.parameters)}

    cres: dict[str, CandidateResult] = {}
    fits: dict[str, CalibrationResult] = {}
    k0 = len(free0)
    n_res = 2 * N
    for c in sigs:
        res = refit([c], v0, [None, {c: lin_start(c, r0, Q0)}, {c: LIBRARY[c].typical}])
        fits[c] = res
        k = len(LIBRARY[c].parameters)
        lr = max(0.0, 2 * (res0.cost - res.cost))
        ev = {p.name: res.values[f"{c}.{p.name}"] for p in LIBRARY[c].parameters}
        cres[c] = CandidateResult(
            c, ev, {p: res.ci_lower[f"{c}.{p}"] for p in ev}, {p: res.ci_upper[f"{c}.{p}"] for p in ev},
            res.cost, lr, 2 * res.cost + 2 * (k0 + k), 2 * res.cost + (k0 + k) * math.log(n_res), k,
            False, False, res.converged, float(np.linalg.norm(sigs[c])),
            float(_constrained_lr(sigs[c], sided[c], -_project_out(Q0, r0[:, None]))[0]), first_order.get(c, ""))
    say(f"{len(cres)} candidates refitted")

    # ---- 5. bootstrap refits under the null (nonlinearity correction of the threshold)
    full_max, lin_used = [], []
    for b in range(int(null_refits)):
        e = E[:, b]
        sim = FrequencySweep(data.temperature_c, data.frequency_hz, _simulated(G0, e, s_ln, s_ph),
                             data.magnitude_std_db, data.phase_std_deg, data.input_name, data.input_unit,
                             data.output_name, data.output_unit)
        fr0 = [fp.with_initial(min(max(v0[fp.name], fp.lower), fp.upper)) for fp in free0]
        rb = fit_parameters(sim, None, fr0, predict_many=pm, max_nfev=max_nfev, identify=False)
        m = 0.0
        for c in sigs:
            fr = [fp.with_initial(min(max(rb.values[fp.name], fp.lower), fp.upper)) for fp in free0] + _effect_free(c)
            rc = fit_parameters(sim, None, fr, predict_many=pm, max_nfev=max_nfev, identify=False)
            m = max(m, 2 * (rb.cost - rc.cost))
        full_max.append(m)
        lin_used.append(float(lin_max[b]))
    ratio = 1.0
    if full_max and sum(lin_used) > 0:
        ratio = float(np.clip(sum(full_max) / sum(lin_used), 1.0, 3.0))
    T = T_lin * ratio
    say(f"null threshold {T:.3g} (linearised {T_lin:.3g} × nonlinearity ratio {ratio:.3g})")

    # ---- 6. verdict
    def gap_thr(effs: Sequence[str]) -> float:
        if not effs:
            return gap_thr0
        S = np.hstack([sigs[c] for c in effs])
        Qs = _orth(S)
        after = cost2_null - np.sum((Qs.T @ Ep) ** 2, axis=0)
        return float(np.quantile(after, 1 - alpha_gap))

    for c, cr in cres.items():
        cr.significant = cr.lr > T
        cr.closes_gap = 2 * cr.cost <= gap_thr([c])
    gap0_sig = 2 * res0.cost > gap_thr0
    sig = sorted((c for c in cres if cres[c].significant), key=lambda c: -cres[c].lr)
    final_effects: list[str] = []
    final_fit: CalibrationResult | None = None
    where = _worst_cells(_localise(data, r0, alpha))
    if not sig:
        if gap0_sig:
            verdict = "unexplained"
            message = (f"The baseline leaves a significant gap (2·cost {2 * res0.cost:.4g} > {gap_thr0:.4g}) "
                       f"that no library candidate reduces significantly; the gap remains in {where}.")
        else:
            verdict = "none"
            message = (f"No significant discrepancy: best candidate LR "
                       f"{max([c.lr for c in cres.values()], default=0.0):.3g} ≤ threshold {T:.3g}, and the "
                       f"baseline cost {res0.cost:.4g} is within its null band.")
    else:
        best = sig[0]
        closers = [c for c in sig if cres[c].closes_gap]
        if closers:
            top = min(closers, key=lambda c: cres[c].aic)
            amb = [c for c in closers if cres[c].aic - cres[top].aic < AMBIGUITY_AIC]
            final_effects, final_fit = [top], fits[top]
            if len(amb) > 1:
                verdict = "ambiguous"
                pairs = [f"{a}~{b}" + ("" if frozenset((a, b)) in conf_set else " (not declared confusable)")
                         for a, b in combinations(amb, 2)]
                message = (f"Ambiguous between {', '.join(amb)} (AIC within {AMBIGUITY_AIC:g}; {'; '.join(pairs)}). "
                           "Separate them with a wider band, more temperatures, or magnitude vs phase.")
                final_effects = amb[:1]
            else:
                verdict = "named"
                message = _named_msg(top, cres[top])
        else:
            # greedy second effect on top of the best
            r1 = standardised_residuals(pm([fits[best].values])[0], data, s_ln, s_ph)
            Q1 = _orth(np.hstack([J0, sigs[best]]))
            best2 = None
            for c2 in sigs:
                if c2 == best:
                    continue
                res2 = refit([best, c2], fits[best].values,
                             [None, {c2: lin_start(c2, r1, Q1)}, {c2: LIBRARY[c2].typical}])
                lr2 = max(0.0, 2 * (fits[best].cost - res2.cost))
                if lr2 > T and (best2 is None or res2.cost < best2[1].cost):
                    best2 = (c2, res2, lr2)
            if best2 is not None and 2 * best2[1].cost <= gap_thr([best, best2[0]]):
                verdict = "named"
                final_effects, final_fit = [best, best2[0]], best2[1]
                message = (f"Named two effects (greedy): {best} (LR {cres[best].lr:.4g}) then {best2[0]} "
                           f"(LR {best2[2]:.4g} on top); the gap closes.")
            else:
                verdict = "unexplained"
                final_effects = [best] + ([best2[0]] if best2 else [])
                final_fit = best2[1] if best2 else fits[best]
                message = (f"Unexplained: the best candidate {best} (LR {cres[best].lr:.4g}) reduces the cost but a "
                           f"significant gap remains (2·cost {2 * final_fit.cost:.4g} > "
                           f"{gap_thr(final_effects):.4g}) in {where}; nothing in the library explains it.")
    if not res0.converged:
        message += f" WARNING: the baseline calibration did not converge ({res0.message})."
    bad = [c for c, cr in cres.items() if not cr.converged]
    if bad:
        message += f" Candidate refits that did not converge: {', '.join(bad)}."
    named = final_effects if verdict in ("named", "ambiguous") else []
    if verdict == "ambiguous":
        named = [c for c in sig if cres[c].closes_gap and cres[c].aic - min(cres[x].aic for x in sig if cres[x].closes_gap) < AMBIGUITY_AIC]
    if final_fit is not None:
        Gf = pm([final_fit.values])[0]
        n_free_after = len(final_fit.names)
    else:
        Gf, n_free_after = G0, k0
    rf = standardised_residuals(Gf, data, s_ln, s_ph)
    fe = {c: {k.split(".", 1)[1]: final_fit.values[k] for k in final_fit.names if k.startswith(c + ".")}
          for c in final_effects} if final_fit is not None else {}
    return Diagnosis(
        verdict=verdict, named=named, message=message, kind=kind, quantity=q, alpha=alpha, threshold=T,
        gap_threshold=gap_thr0, baseline=res0, final=final_fit, final_effects=fe, candidates=cres,
        skipped=skipped, confusable=confusable, separation=separation, localisation_before=_localise(data, r0, alpha),
        localisation_after=_localise(data, rf, alpha), gap_before=_gap(data, r0, k0),
        gap_after=_gap(data, rf, n_free_after),
        null={"method": "linearised Gaussian null at the fitted baseline (constrained LR per candidate, "
                        "max over candidates) scaled by full-refit parametric bootstrap",
              "draws": int(null_draws), "refits": int(null_refits), "lr_threshold_linearised": T_lin,
              "nonlinearity_ratio": ratio, "bootstrap_full_max_lr": full_max, "bootstrap_lin_max_lr": lin_used,
              "alpha_gap": alpha_gap, "seed": seed},
        noise_estimated=estimated, elapsed_s=time.perf_counter() - t0, data=data,
        predicted_before=G0, predicted_after=Gf,
        metadata={"base": base.name, "free": names0, "baseline_effects": beff, "candidates": cand,
                  "data_fingerprint": data.fingerprint()},
    )


def _separation(a: str, b: str, raw: dict, data: FrequencySweep) -> str:
    """What tells two confusable candidates apart: their magnitude/phase split, their dependence on
    temperature and where in frequency their (unprojected) signatures act."""
    N = data.frequency_hz.size
    temps = data.temperatures()

    def traits(c):
        S = raw[c]
        e2 = np.sum(S * S, axis=1)
        phase = float(e2[N:].sum() / e2.sum())
        per_T = np.array([e2[:N][data.temperature_c == t].sum() + e2[N:][data.temperature_c == t].sum() for t in temps])
        cv = float(per_T.std() / per_T.mean()) if temps.size > 1 else 0.0
        w = e2[:N] + e2[N:]
        fc = float(10 ** (np.sum(w * np.log10(data.frequency_hz)) / w.sum()))
        return phase, cv, fc

    pa, ca, fa = traits(a)
    pb, cb, fb = traits(b)
    hints = []
    if abs(pa - pb) > 0.2:
        hints.append(f"magnitude vs phase ({a} {100 * pa:.0f} % phase, {b} {100 * pb:.0f} %)")
    if abs(ca - cb) > 0.2:
        hints.append(f"temperature dependence (spread over T: {a} {ca:.2f}, {b} {cb:.2f}); add temperatures")
    if abs(math.log10(fa / fb)) > 0.15:
        hints.append(f"frequency (centroids {fa:.3g} Hz vs {fb:.3g} Hz); widen the band")
    if not hints:
        return ("Their first-order signatures coincide on these data; only higher-order terms separate "
                "them: extend the band to where the effects are large.")
    return "Separate by " + "; ".join(hints) + "."


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

__all__ = ["diagnose", "Diagnosis", "CandidateResult", "VERDICTS", "gap_shrink", "CONFUSABLE_COSINE",
           "AMBIGUITY_AIC"]
