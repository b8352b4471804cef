"""The next measurement: which experiment would separate the models a diagnosis could not.

When :func:`~physmodel.estimation.discrepancy.diagnose` ends ``ambiguous`` (or ``at_bound`` with a
rival), the competing models each fit the record within its noise.  :func:`next_measurement`
searches the experiments the library can simulate — the measured quantity (actuator M, H, Z, I;
sensor S, Z), a frequency band on a log grid reaching below and above the measured band within
stated limits, a set of bath temperatures within the strip's range, and the excitation level — and
for each predicts both competing models' responses and the separation a record of it is expected to
give at the user's noise level.

Method (optimal design for model discrimination)
------------------------------------------------
Box & Hill (1967, Technometrics 9:57) proposed choosing the next experiment where rival models'
predictions differ most relative to the noise; Atkinson & Fedorov (1975, Biometrika 62:57, "the
design of experiments for discriminating between two rival models") made it precise as
*T-optimality*: when model A is true with parameters θ_A, the design should maximise

    λ_A(ξ) = min over θ_B of Σ_lines |η_A(x, θ_A) − η_B(x, θ_B)|² / σ²(x),

the noiseless χ² left when the rival B refits all its parameters to A's predictions — exactly
the non-centrality of the likelihood-ratio (and, for non-nested fits, of Vuong's z, mean ≈ √λ/2)
statistic that tells them apart.  Here the predictions are the standardised log-responses the
diagnosis fits (``ln|G|/σ_ln`` and ``∠G/σ_φ``, :mod:`~physmodel.estimation.residuals`), and the
minimisation is linearised at B's fit to the diagnosed record: with Δ = ln(G_A/G_B) per line and
J_B the Jacobian of ln G_B in B's free parameters (the user's base parameters and B's effect
parameters, central differences), λ_A = ‖(I − P_{J_B}) Δ‖²_W, W the diagonal weights 1/σ² of the
stacked lines.  A measurement of the diagnosed quantity is evaluated *together with* the diagnosed
record (the two are merged and diagnosed jointly; the rival refits to both); one of another
quantity alone (the diagnosis takes one quantity).  Since either model may be the true one the
criterion is min(λ_A, λ_B), and with several rivals the least over every pair of them (the
experiment must leave one standing, whichever is true).  A pair that no experiment separates even
linearised (λ < :data:`SAME_FORM_LAMBDA` everywhere: the same response in two forms) is said and
left out.  All candidate experiments are evaluated at once: the
responses and Jacobians are computed once on the union grid of each quantity, and each experiment
is a weight mask over it (batched normal equations).

Noise at the new lines: the diagnosed record's per-line σ_ln, σ_φ are regressed on |G| (log–log,
one slope b clipped to [−1, 0]: b = 0 is noise proportional to the signal, b = −1 a fixed
instrument floor, as the virtual lab's DAQ noise is); at a line where the model predicts |G| and at
excitation level a (a multiple of the record's drive) σ = σ_ref (|G|/|G_ref|)^b a^b.  Another
quantity is given the record's median relative σ (its instrument is not known): stated in the
result.

Decision: the separation needed is λ* with Vuong power ``power`` at the diagnosis's α
(:func:`~physmodel.estimation.signatures.vuong_power`: z ~ N(√λ/2, 1), so λ* = 4(z_crit + Φ⁻¹(power))²).
Among the experiments reaching λ* and taking no longer than the diagnosed record did (duration ≈
number of temperatures × :data:`PERIODS` / lowest frequency, plus :data:`BATH_SETTLE_S` per new
bath temperature; or than the quickest that reaches λ*),
the recommendation is the one at the lowest drive level, then of the largest λ (the safest margin);
when none reaches λ*, the one of largest λ, with ``separates = False`` and the sentence saying so.  The linearised λ of the
recommendation (and of the next ones when it falls short) is then checked by a full nonlinear refit
of the rival to the true model's noiseless predictions (``separation_refit``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..data.sweep import FrequencySweep
from ..data.units import QUANTITY_UNITS
from ..errors import IPMCError
from .residuals import noise_std

#: Temperature range [°C] a hydrated strip is measured in by default (above freezing of the bath,
#: below where Nafion's water content falls off), intersected with the laws' own valid ranges.
DEFAULT_TEMPERATURE_LIMITS_C = (5.0, 65.0)
#: Bath limits above this are refused as kelvin typed for °C (the CLI's ``check_celsius`` bound). [°C]
MAX_BATH_C = 150.0
#: Frequency limits [Hz] of a candidate band by default (a 0.01 Hz line takes 100 s a period; the
#: single-mode beam and the DAQs of the scenarios end well below 1 kHz).
DEFAULT_BAND_LIMITS_HZ = (0.01, 1000.0)
#: Default excitation levels, as multiples of the diagnosed record's drive.
DEFAULT_LEVELS = (1.0, 2.0)
#: Measured periods per temperature assumed for a measurement's duration.
PERIODS = 10
#: Time a water bath takes to settle at a temperature the record was not measured at (a stated
#: choice: minutes for a stirred bath and a 0.2 mm strip), added to a measurement's duration. [s]
BATH_SETTLE_S = 600.0
#: Relative step of the central differences of the Jacobians.
FD_RELATIVE_STEP = 1e-5
#: A pair whose linearised separation stays below this in every experiment is the same response in
#: two forms (e.g. two amplifier poles and an op-amp stage's): said, and left out of the criterion.
SAME_FORM_LAMBDA = 1.0
#: Starts of each rival refit in the nonlinear check (its own fit, the typical size, and LHS).
REFIT_STARTS = 3


@dataclass
class CandidateMeasurement:
    """One experiment and the separation it is expected to give.

    Attributes
    ----------
    quantity : str
        What is measured (actuator M, H, Z, I; sensor S, Z).
    band_hz : tuple of float
        Lowest and highest line. [Hz]
    temperatures_c : tuple of float
        Bath temperatures. [°C]
    level : float
        Excitation amplitude as a multiple of the diagnosed record's drive. [-]
    n_lines : int
        Lines of the new record (all temperatures).
    frequencies_hz : ndarray
        The lines (per temperature). [Hz]
    separation : float
        Expected noiseless χ² between the competing models (linearised T-criterion, the least over
        which model is true and over the rival pairs). [-]
    separation_by_pair : dict
        ``"A vs B"`` → {"A true": λ_A, "B true": λ_B}. [-]
    joint : bool
        Evaluated together with the diagnosed record (same quantity: merge and diagnose both).
    duration_s : float
        Measurement time estimate: temperatures × :data:`PERIODS` / lowest frequency, plus
        :data:`BATH_SETTLE_S` per temperature the record was not measured at. [s]
    power : float
        Probability that Vuong's test separates them at the diagnosis's α (normal approximation).
    separation_refit : float
        λ after full nonlinear refits of the rivals (NaN unless checked), pairs that are the same
        response in another form left out. [-]
    refit_by_pair : dict
        ``"A vs B"`` → λ after the refits, the least over the two directions (checked experiments). [-]
    line_temperatures_c, line_frequencies_hz : ndarray
        Every line of the new record (a joint record leaves out the diagnosed record's band at its
        temperatures). [°C], [Hz]
    """

    quantity: str
    band_hz: tuple
    temperatures_c: tuple
    level: float
    n_lines: int
    frequencies_hz: np.ndarray = field(repr=False)
    separation: float
    separation_by_pair: dict
    joint: bool
    duration_s: float
    power: float
    separation_refit: float = float("nan")
    refit_by_pair: dict = field(default_factory=dict)
    line_temperatures_c: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    line_frequencies_hz: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    def describe(self) -> str:
        """The experiment in words."""
        T = ", ".join(f"{t:g}" for t in self.temperatures_c)
        return (f"{self.quantity} at {T} °C, {self.band_hz[0]:.3g}–{self.band_hz[1]:.3g} Hz "
                f"({self.n_lines} lines"
                + (", none inside the record's band at its temperatures" if self.joint else "")
                + f"), drive ×{self.level:g}"
                + (" (merged with the diagnosed record)" if self.joint else " (a record of its own)"))

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"quantity": self.quantity, "band_hz": list(self.band_hz), "temperatures_c": list(self.temperatures_c),
                "level": self.level, "n_lines": self.n_lines, "frequencies_hz": self.frequencies_hz.tolist(),
                "lines": {"temperature_c": self.line_temperatures_c.tolist(),
                          "frequency_hz": self.line_frequencies_hz.tolist()},
                "separation": self.separation, "separation_by_pair": self.separation_by_pair, "joint": self.joint,
                "duration_s": self.duration_s, "power": self.power, "separation_refit": self.separation_refit,
                "refit_by_pair": self.refit_by_pair,
                "description": self.describe()}


@dataclass
class NextMeasurement:
    """What :func:`next_measurement` found.

    Attributes
    ----------
    models : list of tuple
        The competing models (effect names each); the first is the diagnosis's best.
    recommended : CandidateMeasurement or None
        The experiment to run (None when there is nothing to separate).
    separates : bool
        The recommendation is expected to reach ``target`` (and its refit check agrees).
    target : float
        The separation needed, 4 (z_crit + Φ⁻¹(power))². [-]
    current : float
        The same criterion on the diagnosed record alone. [-]
    evaluated : int
        Candidate experiments evaluated.
    ranking : list of CandidateMeasurement
        The best experiments by separation (up to 10).
    noise_model : dict
        How σ at new lines was predicted (slope b, reference, quantity rule).
    fitted : dict
        Model label → the fitted values each prediction used.
    message : str
        The recommendation in words (what the report and stderr say).
    inseparable : list of str
        ``"A vs B"`` pairs no experiment within the limits separates (the same response in another
        form: linearised, or after the refits of every checked experiment).
    best_by_quantity : dict
        Quantity → the largest linearised separation any experiment of it reaches. [-]
    """

    models: list
    recommended: CandidateMeasurement | None
    separates: bool
    target: float
    current: float
    evaluated: int
    ranking: list
    noise_model: dict
    fitted: dict
    message: str
    inseparable: list = field(default_factory=list)
    best_by_quantity: dict = field(default_factory=dict)

    @classmethod
    def unavailable(cls, reason: str, models=()) -> NextMeasurement:
        """The record of a search that gave no recommendation (``reason``: why), so that a finished
        diagnosis still carries, reports and says it instead of losing it."""
        return cls([tuple(m) for m in models], None, False, math.nan, math.nan, 0, [], {}, {},
                   f"no recommendation: {reason}")

    def to_dict(self) -> dict:
        """JSON-ready form (finite floats; NaN as None)."""
        return json_ready({"models": [list(m) for m in self.models],
                      "recommended": self.recommended.to_dict() if self.recommended else None,
                      "separates": self.separates, "target": self.target, "current": self.current,
                      "evaluated": self.evaluated, "ranking": [r.to_dict() for r in self.ranking],
                      "noise_model": self.noise_model, "fitted": self.fitted, "message": self.message,
                      "inseparable": list(self.inseparable), "best_by_quantity": self.best_by_quantity})


# =============================================================================== competing models
def json_ready(o):
    """``o`` with dict keys as str, tuples as lists, numpy scalars as Python ones and non-finite floats
    as None: what ``json.dumps(..., allow_nan=False)`` accepts (the reports' one sanitiser)."""
    if isinstance(o, dict):
        return {str(k): json_ready(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [json_ready(v) for v in o]
    if isinstance(o, (float, np.floating)):
        return float(o) if math.isfinite(o) else None
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.integer):
        return int(o)
    return o


def competing_models(d) -> list[tuple]:
    """The models an ``ambiguous`` / ``at_bound`` diagnosis ``d`` leaves competing: the best (its
    final effects) first, then each alternative — another named single effect, a pair with one member
    swapped for a named alternative declared confusable with it (or either member when no declaration
    says which), or for ``at_bound`` a confusable candidate that stopped at its bound and, widened,
    competes (else the significant candidates that close the gap)."""
    final = tuple(d.final_effects) if d.final_effects else tuple(d.named[:1])
    if not final:
        return []
    alts: list[tuple] = []
    others = [c for c in d.named if c not in final]
    if d.verdict == "at_bound":
        others = [c for c, cr in d.candidates.items() if c not in final
                  and any(a.get("competes") for a in cr.at_bound)]
        if not others:
            others = [c for c, cr in d.candidates.items() if c not in final and cr.significant and cr.closes_gap]
    partner: dict = {}
    for x in d.confusability.get("pairs", []):
        partner.setdefault(x["other"], set()).add(x["top"])
    for a, b, _ in d.confusable:
        partner.setdefault(a, set()).add(b)
        partner.setdefault(b, set()).add(a)
    for c in others:
        if len(final) == 1:
            alts.append((c,))
            continue
        swap = [m for m in final if m in partner.get(c, ())] or list(final)
        for m in swap:
            alt = tuple(sorted([x for x in final if x != m] + [c]))
            if alt not in alts and set(alt) != set(final):
                alts.append(alt)
    return [final] + alts if alts else []


# =============================================================================== the search
def _skeleton(kind: str, q: str, f: np.ndarray, T: np.ndarray) -> FrequencySweep:
    """A sweep of ``q``'s units on the grid f × T (response placeholder 1) for the predictors."""
    in_name, unit_in, out_name, unit_out = QUANTITY_UNITS[(kind, q)]
    TT, FF = np.meshgrid(T, f, indexing="ij")
    return FrequencySweep(TT.ravel(), FF.ravel(), np.ones(FF.size, complex), None, None, in_name, unit_in,
                          out_name, unit_out)


def _band_windows(f_lo: float, f_hi: float, data_band: tuple) -> list[tuple]:
    """Candidate bands: the measured band, and windows of ½–2 decades with edges every ⅓ decade."""
    out = [tuple(data_band)]
    edges = 10 ** np.arange(math.floor(3 * math.log10(f_lo)) / 3, math.log10(f_hi) + 1e-9, 1 / 3)
    edges = np.unique(np.clip(edges, f_lo, f_hi))
    for i, a in enumerate(edges):
        for b in edges[i + 1:]:
            w = math.log10(b / a)
            if 0.45 <= w <= 2.05:
                out.append((float(a), float(b)))
    return list(dict.fromkeys(out))


def _temperature_sets(data_T: np.ndarray, lo: float, hi: float) -> list[tuple]:
    """Candidate temperature sets: the record's, one each on a 5-point grid of the allowed range,
    and the range's ends with its middle."""
    sets = [tuple(float(t) for t in data_T)]
    if hi > lo:
        grid = np.linspace(lo, hi, 5)
        sets += [(float(t),) for t in grid]
        sets.append((float(lo), float(0.5 * (lo + hi)), float(hi)))
    elif not np.any(np.isclose(data_T, lo)):
        sets.append((float(lo),))
    return list(dict.fromkeys(sets))


class _Model:
    """A competing model: its predictor factory, free parameters and fitted values."""

    def __init__(self, d, effects: tuple, values: dict, free: list):
        from ..effects import EffectModel

        self.effects, self.values, self.free = effects, dict(values), list(free)
        beff = {k: dict(v) for k, v in (d.metadata.get("baseline_effects") or {}).items()}
        on = {c: {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith(c + ".")} for c in effects}
        self.model = EffectModel(d.base_parameters, d.kind, {**beff, **on}, kernel=d.metadata.get("kernel",
                                                                                                   "boundary_charge"))

    def log_response(self, sweep: FrequencySweep, q: str) -> tuple[np.ndarray, np.ndarray]:
        """(ln G at θ (N,), ∂ ln G/∂θ (N, k)) on ``sweep``'s lines (central differences in θ)."""
        pm = self.model.predictor(sweep, q).many
        sets, steps = [self.values], []
        for fp in self.free:
            v = self.values[fp.name]
            h = FD_RELATIVE_STEP * (abs(v) if v != 0 else (fp.upper - fp.lower))
            up, dn = min(v + h, fp.upper), max(v - h, fp.lower)
            sets += [{**self.values, fp.name: up}, {**self.values, fp.name: dn}]
            steps.append(up - dn)
        with np.errstate(all="ignore"):
            G = np.asarray(pm(sets), dtype=complex)
            L0 = np.log(G[0])
            J = np.stack([np.log(G[1 + 2 * j] / G[2 + 2 * j]) / steps[j] for j in range(len(self.free))], axis=-1) \
                if self.free else np.zeros((G.shape[1], 0), complex)
        return L0, J


def _refit(d, effects: tuple, start: dict, max_nfev: int):
    """The model ``effects`` refitted to the diagnosed record from ``start`` (free: the diagnosis's
    base parameters and the effects' parameters within their candidate bounds)."""
    from .lsq import fit_parameters
    from .records import FreeParameter

    free = [fp.with_initial(min(max(start.get(fp.name, fp.initial if fp.initial is not None else fp.lower),
                                    fp.lower), fp.upper)) for fp in d.baseline.free]
    cb = d.metadata.get("candidate_bounds", {})
    for c in effects:
        for p, (lo, hi, typ) in cb.get(c, {}).items():
            name = f"{c}.{p}"
            v = start.get(name, typ)
            free.append(FreeParameter(name, lo, hi, "linear", float(min(max(v, lo), hi))))
    m = _Model(d, effects, {fp.name: fp.initial for fp in free}, free)
    pm = m.model.predictor(d.data, d.quantity).many
    # the effects' values ride in the predictor's base model; the fit varies them through the names
    res = fit_parameters(d.data, None, free, predict_many=pm, starts=1, seed=0, max_nfev=max_nfev, identify=False,
                         hold_undetermined=False)
    return _Model(d, effects, dict(res.values), free), float(res.cost)


def _models_for(d, models: Sequence[tuple], max_nfev: int) -> list[_Model]:
    """Each competing model with its fitted values: the diagnosis's final fit for the first, a refit
    to the record (from the baseline optimum and the candidates' own fitted values) for the others."""
    out = []
    for i, effs in enumerate(models):
        if i == 0 and d.final is not None and set(effs) == set(d.final_effects):
            cb = d.metadata.get("candidate_bounds", {})
            from .records import FreeParameter

            free = list(d.baseline.free) + [FreeParameter(f"{c}.{p}", lo, hi, "linear", d.final.values[f"{c}.{p}"])
                                            for c in effs for p, (lo, hi, _) in cb.get(c, {}).items()]
            out.append(_Model(d, effs, dict(d.final.values), free))
            continue
        start = dict(d.final.values if d.final is not None else d.baseline.values)
        start = {k: v for k, v in start.items() if "." not in k or k.split(".", 1)[0] in effs}
        for c in effs:
            if c in d.candidates:
                start.update({f"{c}.{p}": v for p, v in d.candidates[c].values.items()})
        out.append(_refit(d, effs, start, max_nfev)[0])
    return out


def _noise_model(d) -> dict:
    """σ_ln, σ_φ of the record against |G| (module doc): slope b ∈ [−1, 0] and the references."""
    s_ln, s_ph, estimated = noise_std(d.data)
    a = np.log(np.abs(d.data.response))
    b = 0.0
    if not estimated and a.size > 2 and np.ptp(a) > 0.1:
        y = np.log(np.concatenate([s_ln, s_ph]))
        x = np.concatenate([a, a])
        X = np.column_stack([np.ones_like(x), x, np.r_[np.zeros(a.size), np.ones(a.size)]])
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        b = float(np.clip(coef[1], -1.0, 0.0))
    ref_ln = float(np.exp(np.median(np.log(s_ln) - b * a)))
    ref_ph = float(np.exp(np.median(np.log(s_ph) - b * a)))
    return {"slope": b, "ref_ln": ref_ln, "ref_ph": ref_ph, "median_ln": float(np.median(s_ln)),
            "median_ph": float(np.median(s_ph)), "estimated": bool(estimated),
            "rule": ("σ = σ_ref·(|G|)^b·level^b on the diagnosed quantity, b from the record "
                     "(0: proportional to the signal, −1: a fixed floor); another quantity: the record's "
                     "median relative σ, independent of the level (its instrument is unknown)")}


def _sigma(nm: dict, logabs: np.ndarray, level: np.ndarray, same_quantity: bool) -> tuple[np.ndarray, np.ndarray]:
    """(σ_ln, σ_φ) per (experiment level, line): shapes (n_levels, N)."""
    if same_quantity:
        f = np.exp(nm["slope"] * logabs)[None, :] * (level[:, None] ** nm["slope"])
        return nm["ref_ln"] * f, nm["ref_ph"] * f
    one = np.ones((level.size, logabs.size))
    return nm["median_ln"] * one, nm["median_ph"] * one


def _lambda(delta: np.ndarray, J: np.ndarray, w: np.ndarray, base: tuple | None = None) -> np.ndarray:
    """min_δ Σ w |Δ − J δ|² per weight row of ``w`` (n_exp, 2N); ``delta`` (2N,), ``J`` (2N, k)
    real-stacked; ``base`` adds fixed (rᵀr, Jᵀr, JᵀJ) sums of the diagnosed record."""
    rr = w @ (delta * delta)
    Jr = w @ (J * delta[:, None])
    JJ = np.einsum("ei,ij,ik->ejk", w, J, J, optimize=True)
    if base is not None:
        rr, Jr, JJ = rr + base[0], Jr + base[1], JJ + base[2]
    k = J.shape[1]
    if k == 0:
        return rr
    scale = np.sqrt(np.maximum(np.einsum("ejj->ej", JJ), 1e-300))
    A = JJ / (scale[:, :, None] * scale[:, None, :]) + 1e-10 * np.eye(k)
    x = np.linalg.solve(A, (Jr / scale)[..., None])[..., 0]
    return np.maximum(rr - np.einsum("ej,ej->e", Jr / scale, x), 0.0)


def _diff(La: np.ndarray, Lb: np.ndarray) -> np.ndarray:
    """ln(G_A/G_B) from the two log-responses, its phase wrapped to (−π, π]."""
    D = La - Lb
    return D.real + 1j * np.angle(np.exp(1j * D.imag))


def _stack(z: np.ndarray) -> np.ndarray:
    """Complex (N, ...) → real (2N, ...): log-magnitude rows, then phase rows."""
    return np.concatenate([z.real, z.imag], axis=0)


def next_measurement(d, *, quantities: Sequence[str] | None = None,
                     band_limits_hz: tuple = DEFAULT_BAND_LIMITS_HZ, temperature_limits_c: tuple | None = None,
                     levels: Sequence[float] = DEFAULT_LEVELS, lines_per_decade: float | None = None,
                     power: float = 0.9, models: Sequence[tuple] | None = None, check_refit: int = 2,
                     max_nfev: int = 100) -> NextMeasurement:
    """The experiment that best separates the models diagnosis ``d`` leaves competing (module doc).

    Parameters
    ----------
    d : Diagnosis
        An ``ambiguous`` or ``at_bound`` diagnosis (others have nothing to separate).
    quantities : sequence of str or None
        What may be measured (default: every quantity of ``d.kind`` the library simulates, M, H, Z,
        I or S, Z; a caller whose laboratory records one quantity passes just that).
    band_limits_hz : (float, float)
        The lowest and highest frequency any band may reach. [Hz]  Bands reach at most a decade
        below and above the record's.
    temperature_limits_c : (float, float) or None
        Bath temperatures allowed. [°C]  Default :data:`DEFAULT_TEMPERATURE_LIMITS_C` intersected
        with the laws' valid ranges; given limits are clipped to the laws' valid ranges (the message
        says so) and refused above :data:`MAX_BATH_C` (kelvin typed as °C).
    levels : sequence of float
        Excitation levels, multiples of the record's drive (cap them at what the strip takes). [-]
    lines_per_decade : float or None
        Line density of a new record (default: the record's).
    power : float
        Vuong-test power the separation must reach.
    models : sequence of tuple or None
        The competing models (effect names each, the best first; default :func:`competing_models`).
    check_refit : int
        How many of the preferred experiments to check by nonlinear refits of the rivals, in order,
        until one reaches the target (0: none).
    max_nfev : int
        Function evaluations of each refit.
    """
    from scipy.stats import norm

    from .signatures import vuong_critical, vuong_power

    if d.verdict not in ("ambiguous", "at_bound"):
        raise IPMCError(f"next_measurement: the diagnosis is {d.verdict!r}; only an ambiguous or at-bound "
                        "verdict leaves models to separate")
    if d.base_parameters is None:
        raise IPMCError("next_measurement: the diagnosis does not carry its base parameters; rerun diagnose")
    if isinstance(power, bool) or not isinstance(power, (int, float, np.integer, np.floating)) \
            or not 0.5 <= power < 1:
        raise IPMCError(f"power={power!r}: expected a number in [0.5, 1)")
    lv = np.asarray(sorted(set(float(x) for x in levels)), float)
    if lv.size == 0 or np.any(~np.isfinite(lv)) or np.any(lv <= 0):
        raise IPMCError(f"levels={list(levels)!r}: give positive multiples of the record's drive")
    kinds = [q for k, q in QUANTITY_UNITS if k == d.kind and q != "G"]
    qs = list(quantities) if quantities is not None else kinds
    bad = [q for q in qs if q not in kinds]
    if bad:
        raise IPMCError(f"quantities {bad}: a {d.kind} has {kinds}")
    z_crit = vuong_critical(d.alpha)
    target = 4.0 * (z_crit + float(norm.ppf(power))) ** 2
    mods = list(models) if models is not None else competing_models(d)
    nm = _noise_model(d)
    if len(mods) < 2:
        return NextMeasurement([tuple(m) for m in mods], None, False, target, 0.0, 0, [], nm, {},
                               "No competing model to separate: the diagnosis names no rival "
                               + ("(widen the bound it stopped at instead)." if d.verdict == "at_bound" else "."))
    fitted = _models_for(d, mods, max_nfev)
    label = lambda m: " + ".join(m.effects)  # noqa: E731
    # ---- the record itself (the part every joint experiment shares)
    s_ln0, s_ph0, _ = noise_std(d.data)
    w0 = np.concatenate([1 / s_ln0 ** 2, 1 / s_ph0 ** 2])
    rec = {}
    for m in fitted:
        rec[id(m)] = m.log_response(d.data, d.quantity)
    # ---- candidate grids
    f_data = d.data.frequency_hz
    T_data = d.data.temperatures()
    fmin, fmax = float(f_data.min()), float(f_data.max())
    n_per_T = f_data.size / max(T_data.size, 1)
    lpd = lines_per_decade or max(n_per_T / max(math.log10(fmax / fmin), 0.5), 5.0)
    f_lo = max(band_limits_hz[0], fmin / 10.0)
    f_hi = min(band_limits_hz[1], fmax * 10.0)
    if not f_lo < f_hi:
        raise IPMCError(f"band_limits_hz={band_limits_hz!r} leave no band near the record's {fmin:g}–{fmax:g} Hz")
    t_lo, t_hi, t_note = _temperature_limits(temperature_limits_c, d.base_parameters)
    f_grid = np.geomspace(f_lo, f_hi, max(int(round(lpd * math.log10(f_hi / f_lo))) + 1, 2))
    windows = _band_windows(f_lo, f_hi, (fmin, fmax))
    tsets = _temperature_sets(T_data, t_lo, t_hi)
    T_grid = np.unique(np.concatenate([np.asarray([t for s in tsets for t in s]), T_data]))
    rows: list[CandidateMeasurement] = []
    pairs = [(a, b) for i, a in enumerate(fitted) for b in fitted[i + 1:]]     # every pair must separate
    # the criterion on the record alone
    current = math.inf
    for a, b in pairs:
        La, Ja = rec[id(a)]
        Lb, Jb = rec[id(b)]
        D = _stack(_diff(La, Lb))
        lam_a = _lambda(D, _stack(Jb), w0[None, :])[0]
        lam_b = _lambda(-D, _stack(Ja), w0[None, :])[0]
        current = min(current, lam_a, lam_b)
    for q in qs:
        sk = _skeleton(d.kind, q, f_grid, T_grid)
        resp = {id(m): m.log_response(sk, q) for m in fitted}
        same = q == d.quantity
        logabs = resp[id(fitted[0])][0].real + _log_unit_factor(d, sk)      # in the record's units
        sl, sp = _sigma(nm, logabs, lv, same)                   # (n_levels, N)
        # masks: experiment e = (window, temperature set) × level
        masks, meta, seen = [], [], set()
        for (a, b) in windows:
            fm = (sk.frequency_hz >= a * (1 - 1e-9)) & (sk.frequency_hz <= b * (1 + 1e-9))
            for ts in tsets:
                m_ = fm & np.isin(sk.temperature_c, ts)
                if same:        # merged with the record: no line inside its band at its temperatures
                    m_ &= ~(np.isin(sk.temperature_c, T_data) & (sk.frequency_hz >= fmin * (1 - 1e-9))
                            & (sk.frequency_hz <= fmax * (1 + 1e-9)))
                key = m_.tobytes()
                if m_.sum() < 2 or key in seen:      # bands clipped to the same lines are one experiment
                    continue
                seen.add(key)
                masks.append(m_)
                meta.append(((a, b), ts))
        if not masks:
            continue
        M = np.asarray(masks, float)                           # (n_exp, N)
        by_pair: list = [dict() for _ in range(len(lv) * M.shape[0])]
        for a, b in pairs:
            La, Ja = resp[id(a)]
            Lb, Jb = resp[id(b)]
            D = _stack(_diff(La, Lb))
            base_ab = base_ba = None
            if same:
                Ra, RJa = rec[id(a)]
                Rb, RJb = rec[id(b)]
                D0, JB0, JA0 = _stack(_diff(Ra, Rb)), _stack(RJb), _stack(RJa)
                base_ab = (w0 @ (D0 * D0), (w0[:, None] * JB0).T @ D0, (w0[:, None] * JB0).T @ JB0)
                base_ba = (w0 @ (D0 * D0), -(w0[:, None] * JA0).T @ D0, (w0[:, None] * JA0).T @ JA0)
            for i, _ in enumerate(lv):
                W = np.hstack([M / sl[i] ** 2, M / sp[i] ** 2])
                la = _lambda(D, _stack(Jb), W, base_ab)
                lb = _lambda(-D, _stack(Ja), W, base_ba)
                for e in range(M.shape[0]):
                    by_pair[i * M.shape[0] + e][f"{label(a)} vs {label(b)}"] = {
                        f"{label(a)} true": float(la[e]), f"{label(b)} true": float(lb[e])}
        for i, level in enumerate(lv):
            for e, (_, ts) in enumerate(meta):
                on = M[e] > 0
                fl = np.unique(sk.frequency_hz[on])
                rows.append(CandidateMeasurement(q, (float(fl.min()), float(fl.max())), tuple(ts), float(level),
                                                 int(M[e].sum()), fl, math.inf, by_pair[i * M.shape[0] + e],
                                                 same, len(ts) * PERIODS / float(fl.min())
                                                 + BATH_SETTLE_S * int(np.sum(~np.isin(ts, T_data))), 0.0,
                                                 line_temperatures_c=sk.temperature_c[on],
                                                 line_frequencies_hz=sk.frequency_hz[on]))
    if not rows:
        raise IPMCError("next_measurement: no candidate experiment within the limits")
    # a pair that no experiment separates even linearised (the same response in another form) is
    # said, and left out of the criterion: the others can still be told apart
    best_pair = {k: max(min(r.separation_by_pair[k].values()) for r in rows) for k in rows[0].separation_by_pair}
    same_form = [k for k, v in best_pair.items() if v < SAME_FORM_LAMBDA]
    for r in rows:
        vals = [min(v.values()) for k, v in r.separation_by_pair.items() if k not in same_form]
        r.separation = float(min(vals)) if vals else 0.0
        r.power = vuong_power(r.separation, z_crit)
    live = [(a, b) for a, b in pairs if f"{label(a)} vs {label(b)}" not in same_form]
    ranking = sorted(rows, key=lambda r: -r.separation)
    # among those reaching the target: within the time budget (the record's own duration, or the
    # quickest that reaches it), the lowest drive, then the largest separation (the safest margin)
    ok = [r for r in rows if r.separation >= target]
    budget = max(T_data.size * PERIODS / fmin, min((r.duration_s for r in ok), default=0.0))
    ok = sorted((r for r in ok if r.duration_s <= budget * (1 + 1e-9)), key=lambda r: (r.level, -r.separation))
    order = ok or ranking
    # the nonlinear check (the linearised λ overstates what a rival can reach after a full refit):
    # the preferred experiment, then the one of largest linearised λ, then the next preferred ones
    to_check = list(dict.fromkeys([id(r) for r in order[:1] + ranking[:1] + order[1:]]))
    by_id = {id(r): r for r in rows}
    checked: list = []
    for rid in to_check[:max(check_refit, 0) if live else 0]:
        r = by_id[rid]
        r.refit_by_pair = _refit_check(d, live, r, nm, max_nfev, label)
        checked.append(r)
    # a pair no checked experiment separates after refits is the same response in another form here
    same_refit = [k for k in (checked[0].refit_by_pair if checked else {})
                  if all(r.refit_by_pair[k] < SAME_FORM_LAMBDA for r in checked)]
    for r in checked:
        vals = [v for k, v in r.refit_by_pair.items() if k not in same_refit]
        r.separation_refit = float(min(vals)) if vals else 0.0
    good = [r for r in checked if r.separation_refit >= target]
    chosen = good[0] if good else (max(checked, key=lambda r: r.separation_refit) if checked else order[0])
    same_form = same_form + same_refit
    sep_ok = bool(live) and len(same_refit) < len(live) and chosen.separation >= target \
        and (not checked or chosen.separation_refit >= target)
    lam_said = chosen.separation_refit if math.isfinite(chosen.separation_refit) else chosen.separation
    who = " vs ".join(" + ".join(m) for m in mods)
    alike = (" Not separable within the limits (the same response in another form; best λ after refits "
             "below " f"{SAME_FORM_LAMBDA:g}): " + "; ".join(same_form) + "." if same_form else "")
    if not live or len(same_refit) == len(live):
        sep_ok = False
        msg = f"No experiment within the limits can separate {who}.{alike}"
    elif sep_ok:
        msg = (f"Next measurement to separate {who}: {chosen.describe()} — expected separation λ = {lam_said:.3g} "
               f"(≥ {target:.3g} needed for {power:.0%} power at α = {d.alpha:g}; the record alone gives "
               f"{current:.3g}).{alike}")
    else:
        msg = (f"No experiment within the limits is expected to separate {who} at the noise of this record: the "
               f"best, {chosen.describe()}, gives λ = {lam_said:.3g} < {target:.3g} needed (the record alone "
               f"{current:.3g}); lower the noise (more periods"
               + (f": λ grows in proportion to the periods averaged, so about {math.ceil(target / lam_said)}× "
                  "as many" if 0 < lam_said < target else "")
               + f"), widen the limits, or accept the ambiguity.{alike}")
    msg += t_note
    return NextMeasurement([tuple(m) for m in mods], chosen, bool(sep_ok), target, float(current), len(rows),
                           ranking[:10], nm, {label(m): m.values for m in fitted}, msg, same_form,
                           {q: max(r.separation for r in rows if r.quantity == q) for q in qs
                            if any(r.quantity == q for r in rows)})


def merge_records(record: FrequencySweep, new: FrequencySweep) -> FrequencySweep:
    """One sweep of the same quantity from the diagnosed ``record`` and the ``new`` measurement (lines
    sorted by temperature, then frequency; in ``record``'s units), to be diagnosed jointly; a line
    both hold at the same temperature and frequency is refused (measure it once, or average first)."""
    if not isinstance(record, FrequencySweep) or not isinstance(new, FrequencySweep):
        raise IPMCError("merge_records: both records must be FrequencySweep")
    b = new.in_units(record.input_unit, record.output_unit)
    if (record.magnitude_std_db is None) != (b.magnitude_std_db is None):
        raise IPMCError("merge_records: one record carries per-line standard deviations and the other does not")
    T = np.r_[record.temperature_c, b.temperature_c]
    f = np.r_[record.frequency_hz, b.frequency_hz]
    order = np.lexsort((f, T))
    dup = (np.diff(T[order]) == 0) & (np.diff(f[order]) == 0)
    if np.any(dup):
        k = order[1:][dup][0]
        raise IPMCError(f"merge_records: both records hold a line at {T[k]:g} °C, {f[k]:g} Hz")
    std = record.magnitude_std_db is not None
    return FrequencySweep(T[order], f[order], np.r_[record.response, b.response][order],
                          np.r_[record.magnitude_std_db, b.magnitude_std_db][order] if std else None,
                          np.r_[record.phase_std_deg, b.phase_std_deg][order] if std else None,
                          record.input_name, record.input_unit, record.output_name, record.output_unit,
                          {**dict(record.metadata or {}), "merged_with": dict(b.metadata or {})})


def _laws_valid_range(base) -> tuple:
    """The intersection of every non-constant temperature law's valid range. [°C]"""
    from dataclasses import fields

    lo, hi = -273.15, math.inf
    laws = getattr(base, "laws", None)
    for f in fields(laws) if laws is not None else ():
        law = getattr(laws, f.name)
        if type(law).__name__ != "Constant" and hasattr(law, "valid_c"):
            lo, hi = max(lo, float(law.valid_c[0])), min(hi, float(law.valid_c[1]))
    return lo, hi


def _law_range(base) -> tuple:
    """:data:`DEFAULT_TEMPERATURE_LIMITS_C` intersected with every non-constant law's valid range."""
    lo, hi = _laws_valid_range(base)
    return max(DEFAULT_TEMPERATURE_LIMITS_C[0], lo), min(DEFAULT_TEMPERATURE_LIMITS_C[1], hi)


def _temperature_limits(limits, base) -> tuple[float, float, str]:
    """The bath limits searched (default :func:`_law_range`) and a note for the message: given limits
    above :data:`MAX_BATH_C` are refused (kelvin typed as °C); limits outside the laws' valid range are
    clipped to it (the models are not trusted beyond it) and the note says so."""
    if limits is None:
        lo, hi = _law_range(base)
        return lo, hi, ""
    try:
        t_lo, t_hi = (float(x) for x in limits)
    except (TypeError, ValueError):
        raise IPMCError(f"temperature_limits_c={limits!r}: expected two numbers (lower, upper) in °C") from None
    if not (math.isfinite(t_lo) and math.isfinite(t_hi)):
        raise IPMCError(f"temperature_limits_c={limits!r}: expected finite temperatures in °C")
    if t_lo > t_hi:
        raise IPMCError(f"temperature_limits_c={limits!r}: lower above upper")
    if t_hi > MAX_BATH_C or t_lo <= -273.15:
        raise IPMCError(f"temperature_limits_c={limits!r}: outside (-273.15, {MAX_BATH_C:g}] °C where a hydrated "
                        "IPMC works — kelvin? Temperatures are in °C (subtract 273.15)")
    v_lo, v_hi = _laws_valid_range(base)
    c_lo, c_hi = max(t_lo, v_lo), min(t_hi, v_hi)
    if c_lo > c_hi:
        raise IPMCError(f"temperature_limits_c={limits!r}: no temperature within the temperature laws' valid "
                        f"range {v_lo:g}–{v_hi:g} °C")
    if (c_lo, c_hi) == (t_lo, t_hi):
        return t_lo, t_hi, ""
    return c_lo, c_hi, (f" Bath limits {t_lo:g}–{t_hi:g} °C clipped to {c_lo:g}–{c_hi:g} °C, the temperature "
                        "laws' valid range.")


def _log_unit_factor(d, sk: FrequencySweep) -> float:
    """ln of the factor from ``sk``'s response units to the diagnosed record's (same dimensions)."""
    from ..data.units import unit_scale

    if (d.data.input_unit, d.data.output_unit) == (sk.input_unit, sk.output_unit):
        return 0.0
    try:
        f = (unit_scale(sk.output_unit) / unit_scale(sk.input_unit)) / (unit_scale(d.data.output_unit)
                                                                        / unit_scale(d.data.input_unit))
    except (KeyError, IPMCError):
        return 0.0
    return float(np.log(abs(f)))


def _refit_check(d, pairs: list, r: CandidateMeasurement, nm: dict, max_nfev: int, label) -> dict:
    """λ of experiment ``r`` by full refits: each rival refitted to the other's noiseless predictions
    on the new lines (with the record's lines when joint) from its own fit, from its effect at its
    typical size and from :data:`REFIT_STARTS` − 2 more Latin-hypercube starts; ``{"A vs B": the
    least over the two directions}`` for each of ``pairs``."""
    from .lsq import fit_parameters

    in_name, unit_in, out_name, unit_out = QUANTITY_UNITS[(d.kind, r.quantity)]
    sk = FrequencySweep(r.line_temperatures_c, r.line_frequencies_hz, np.ones(r.n_lines, complex), None, None,
                        in_name, unit_in, out_name, unit_out)
    cb = d.metadata.get("candidate_bounds", {})
    out = {}
    for a, b in pairs:
        best = math.inf
        for truth, rival in ((a, b), (b, a)):
            G = np.asarray(truth.model.predictor(sk, r.quantity).many([truth.values])[0])
            if r.joint:
                s_ln, s_ph = _sigma(nm, np.log(np.abs(G)) + _log_unit_factor(d, sk), np.array([r.level]), True)
                G0 = np.asarray(truth.model.predictor(d.data, d.quantity).many([truth.values])[0])
                rec = FrequencySweep(d.data.temperature_c, d.data.frequency_hz, G0, d.data.magnitude_std_db,
                                     d.data.phase_std_deg, d.data.input_name, d.data.input_unit, d.data.output_name,
                                     d.data.output_unit)
                if rec.magnitude_std_db is None:
                    s0l, s0p, _ = noise_std(d.data)
                    rec = FrequencySweep(rec.temperature_c, rec.frequency_hz, G0, s0l * 20 / math.log(10),
                                         np.degrees(s0p), rec.input_name, rec.input_unit, rec.output_name,
                                         rec.output_unit)
                new = FrequencySweep(sk.temperature_c, sk.frequency_hz, G, s_ln[0] * 20 / math.log(10),
                                     np.degrees(s_ph[0]), sk.input_name, sk.input_unit, sk.output_name, sk.output_unit)
                sw = merge_records(rec, new)
                q = d.quantity
            else:
                s_ln, s_ph = _sigma(nm, np.log(np.abs(G)), np.array([r.level]), False)
                sw = FrequencySweep(sk.temperature_c, sk.frequency_hz, G, s_ln[0] * 20 / math.log(10),
                                    np.degrees(s_ph[0]), sk.input_name, sk.input_unit, sk.output_name, sk.output_unit)
                q = r.quantity
            pm = rival.model.predictor(sw, q).many
            typical = {f"{c}.{p}": v[2] for c in rival.effects for p, v in cb.get(c, {}).items()}
            for k, start in enumerate((rival.values, {**rival.values, **typical})):
                free = [fp.with_initial(min(max(start[fp.name], fp.lower), fp.upper)) for fp in rival.free]
                res = fit_parameters(sw, None, free, predict_many=pm, starts=1 if k == 0 else REFIT_STARTS - 1,
                                     seed=0, max_nfev=max_nfev, identify=False, hold_undetermined=False)
                best = min(best, 2.0 * float(res.cost))
        out[f"{label(a)} vs {label(b)}"] = best
    return out


__all__ = ["CandidateMeasurement", "NextMeasurement", "competing_models", "json_ready", "merge_records",
           "next_measurement", "MAX_BATH_C",
           "PERIODS", "BATH_SETTLE_S", "SAME_FORM_LAMBDA", "REFIT_STARTS", "FD_RELATIVE_STEP",
           "DEFAULT_BAND_LIMITS_HZ", "DEFAULT_LEVELS", "DEFAULT_TEMPERATURE_LIMITS_C"]
