"""The design algebra of the next-measurement search (:mod:`~physmodel.estimation.next_measurement`).

The competing models with their fitted values and log-response Jacobians
(:class:`CompetingModel`, :func:`fit_competing_models`), the noise a new line is expected to carry
(:func:`noise_model`, :func:`line_sigma`), the linearised T-criterion over many experiments at once
(:func:`t_criterion`, on real-stacked log-ratios :func:`log_ratio`, :func:`stack_real`) and its
nonlinear check by full refits of the rivals (:func:`refit_check`).  The method is described in
:mod:`~physmodel.estimation.next_measurement`'s module documentation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..data.sweep import FrequencySweep
from ..data.units import QUANTITY_UNITS
from ..errors import IPMCError
from .next_measurement_results import CandidateMeasurement, merge_records
from .residuals import noise_std

#: Relative step of the central differences of the Jacobians.
FD_RELATIVE_STEP = 1e-5
#: Starts of each rival refit in the nonlinear check (its own fit, the typical size, and LHS).
REFIT_STARTS = 3


class CompetingModel:
    """A competing model: its predictor factory, free parameters and fitted values."""

    def __init__(self, d, effects: tuple, values: dict, free: list):
        from ..effects import EffectModel

        self.effects, self.values, self.free, self.d = effects, dict(values), list(free), d
        beff = {k: dict(v) for k, v in (d.metadata.get("baseline_effects") or {}).items()}
        on = {c: {k.split(".", 1)[1]: v for k, v in values.items() if k.startswith(c + ".")} for c in effects}
        self.model = EffectModel(d.base_parameters, d.kind, {**beff, **on}, kernel=d.metadata.get("kernel",
                                                                                                   "boundary_charge"))

    def log_response(self, sweep: FrequencySweep, q: str) -> tuple[np.ndarray, np.ndarray]:
        """(ln G at θ (N,), ∂ ln G/∂θ (N, k)) on ``sweep``'s lines (central differences in θ)."""
        return self.log_response_of(self.model.predictor(sweep, q).many)

    def log_response_of(self, pm) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`log_response` of a predictor ``pm(values_list) -> (n_sets, N)`` of this model's lines."""
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


class RecordView:
    """The diagnosed record as the search sees it: one quantity's sweep, or the sweeps of a joint
    diagnosis (:mod:`~physmodel.estimation.joint`, one per quantity, effects narrowed by its
    ``acts_on``), each a quantity a new measurement of it is merged with."""

    def __init__(self, d, acts_on: Mapping[str, Sequence[str]] | None = None):
        jd = getattr(d, "joint", None)
        self.kind, self.joint, self._d, self._jd = d.kind, jd is not None, d, jd
        self.acts_on = {k: tuple(v) for k, v in ((d.metadata or {}).get("acts_on") or {}).items()} if self.joint else {}
        self.sweeps = dict(zip(jd.quantities, jd.sweeps)) if jd is not None else {d.quantity: d.data}
        #: where effects act on a quantity the one-quantity record does not hold (the caller's
        #: declaration, :func:`~physmodel.estimation.next_measurement.next_measurement`'s ``acts_on``)
        self.new_acts_on = new_quantity_acts_on(d, acts_on) if acts_on else {}
        #: λ of the refits made in this search (:func:`refit_lambda`), by what determines them: the
        #: rival (its effects, values and free parameters), the refitted lines (the truth's
        #: predictions and their σ, quantities and stacking) and the starts.  Two experiments that differ only where a refit cannot see it
        #: (e.g. drive ×1 and ×2 of a linear model under relative noise: the same lines, the same σ)
        #: are refitted once.
        self.refits: dict = {}

    def record_many(self, model):
        """The predictor of ``model`` on the whole diagnosed record (stacked when joint)."""
        if self._jd is not None:
            return self._jd.predictor(model, self.acts_on)
        return model.predictor(self._d.data, self._d.quantity).many

    def many(self, model, sweep: FrequencySweep, q: str):
        """The predictor of ``model`` on ``sweep``'s lines of quantity ``q`` (``acts_on`` applied when
        joint, ``new_acts_on`` on a quantity the record does not hold)."""
        acts = self.acts_on if q in self.sweeps else {**self.acts_on, **self.new_acts_on}
        if not self.joint and not acts:
            return model.predictor(sweep, q).many
        from .joint import joint_data

        if sweep.magnitude_std_db is None:        # σ does not enter a prediction; the stacking wants one
            n = sweep.frequency_hz.size
            sweep = FrequencySweep(sweep.temperature_c, sweep.frequency_hz, sweep.response, np.ones(n), np.ones(n),
                                   sweep.input_name, sweep.input_unit, sweep.output_name, sweep.output_unit)
        return joint_data([sweep], self.kind, (q,)).predictor(model, acts)

    def restacked(self, sweeps: dict) -> tuple:
        """(record, predictor factory ``model -> many``) of ``{quantity: sweep}`` diagnosed as the
        record is (jointly when it is joint)."""
        if not self.joint:
            (q, sw), = sweeps.items()
            return sw, lambda model: model.predictor(sw, q).many
        from .joint import joint_data

        jd = joint_data(list(sweeps.values()), self.kind, tuple(sweeps))
        return jd.stacked, lambda model: jd.predictor(model, self.acts_on)


def check_new_acts_on(kind: str, quantity: str, acts_on: Mapping[str, Sequence[str]]) -> dict:
    """``acts_on`` of a one-quantity record of ``quantity`` (a ``kind`` model), validated before any
    search (the command checks it before the diagnosis runs): a mapping of library effects to
    lists of ``kind``'s quantities, each including ``quantity`` (where the effect was diagnosed).
    Returns it as ``{effect: [quantities]}``; an IPMCError names the entry and what was expected."""
    from .joint import check_acts_on

    if not isinstance(acts_on, Mapping):
        raise IPMCError(f"acts_on = {acts_on!r}: expected a mapping of effect names to lists of quantities")
    kinds = [q for k, q in QUANTITY_UNITS if k == kind and q != "G"]
    out = check_acts_on(acts_on, kind, kinds)
    bad = {e: list(qs) for e, qs in out.items() if quantity not in qs}
    if bad:
        raise IPMCError(f"acts_on {bad}: each effect's quantities must include the diagnosed record's "
                        f"{quantity!r} (where the effect was diagnosed)")
    return out


def new_quantity_acts_on(d, acts_on: Mapping[str, Sequence[str]]) -> dict:
    """``acts_on`` for the quantities a one-quantity record ``d`` does not hold, validated
    (:func:`check_new_acts_on`); an IPMCError for a joint diagnosis (its ``acts_on`` is the
    diagnosis's own: pass it to ``diagnose``)."""
    if getattr(d, "joint", None) is not None:
        raise IPMCError("acts_on: a joint diagnosis carries its own (diagnose(..., acts_on=...)); "
                        "next_measurement takes one only for a one-quantity record")
    return check_new_acts_on(d.kind, d.quantity, acts_on)


def refit_model(d, effects: tuple, start: dict, max_nfev: int):
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
    m = CompetingModel(d, effects, {fp.name: fp.initial for fp in free}, free)
    pm = RecordView(d).record_many(m.model)
    # the effects' values ride in the predictor's base model; the fit varies them through the names
    res = fit_parameters(d.data, None, free, predict_many=pm, starts=1, seed=0, max_nfev=max_nfev, identify=False,
                         hold_undetermined=False)
    return CompetingModel(d, effects, dict(res.values), free), float(res.cost)


def fit_competing_models(d, models: Sequence[tuple], max_nfev: int) -> list[CompetingModel]:
    """Each competing model with its fitted values: the diagnosis's final fit for the first, a refit
    to the record (from the baseline optimum and the candidates' own fitted values) for the others."""
    out = []
    for i, effs in enumerate(models):
        if i == 0 and d.final is not None and set(effs) == set(d.final_effects):
            cb = d.metadata.get("candidate_bounds", {})
            from .records import FreeParameter

            free = list(d.baseline.free) + [FreeParameter(f"{c}.{p}", lo, hi, "linear", d.final.values[f"{c}.{p}"])
                                            for c in effs for p, (lo, hi, _) in cb.get(c, {}).items()]
            out.append(CompetingModel(d, effs, dict(d.final.values), free))
            continue
        start = dict(d.final.values if d.final is not None else d.baseline.values)
        start = {k: v for k, v in start.items() if "." not in k or k.split(".", 1)[0] in effs}
        for c in effs:
            if c in d.candidates:
                start.update({f"{c}.{p}": v for p, v in d.candidates[c].values.items()})
        out.append(refit_model(d, effs, start, max_nfev)[0])
    return out



def noise_model(d) -> dict:
    """σ_ln [Np], σ_φ [rad] of the record against |G| (:mod:`~physmodel.estimation.next_measurement`,
    "Noise at the new lines"): slope b ∈ [−1, 0] [-] and the references ``ref_ln`` [Np], ``ref_ph``
    [rad] (σ at |G| = 1 in the record's response units, level 1), the medians ``median_ln`` [Np],
    ``median_ph`` [rad]; a joint record's per quantity (``by_quantity``), with the median relative σ
    over its quantities for another one."""
    view = RecordView(d)
    if not view.joint:
        return sweep_noise_model(d.data)
    by_q = {q: sweep_noise_model(s) for q, s in view.sweeps.items()}
    return {"by_quantity": by_q, "median_ln": float(np.median([v["median_ln"] for v in by_q.values()])),
            "median_ph": float(np.median([v["median_ph"] for v in by_q.values()])),
            "estimated": any(v["estimated"] for v in by_q.values()),
            "rule": next(iter(by_q.values()))["rule"].replace("the diagnosed quantity", "each diagnosed quantity")
            .replace("the record's median relative σ", "the median over the diagnosed quantities of their median "
                     "relative σ")}


def sweep_noise_model(sweep: FrequencySweep) -> dict:
    """:func:`noise_model` of one quantity's sweep."""
    s_ln, s_ph, estimated = noise_std(sweep)
    a = np.log(np.abs(sweep.response))
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


def line_sigma(nm: dict, logabs: np.ndarray, level: np.ndarray, same_quantity: bool) -> tuple[np.ndarray, np.ndarray]:
    """(σ_ln [Np], σ_φ [rad]) per (experiment level, line): shapes (n_levels, N).

    ``nm`` a :func:`noise_model`; ``logabs`` ln|G| of the lines in the record's response units [Np];
    ``level`` the drive levels, multiples of the record's [-]; ``same_quantity`` the diagnosed
    quantity (σ regressed on |G|) or another (the record's median σ_ln, σ_φ, independent of level)."""
    if same_quantity:
        f = np.exp(nm["slope"] * logabs)[None, :] * (level[:, None] ** nm["slope"])
        return nm["ref_ln"] * f, nm["ref_ph"] * f
    one = np.ones((level.size, logabs.size))
    return nm["median_ln"] * one, nm["median_ph"] * one


def t_criterion(delta: np.ndarray, J: np.ndarray, w: np.ndarray, base: tuple | None = None) -> np.ndarray:
    """min_δ Σ w |Δ − J δ|² per weight row of ``w`` (n_exp, 2N); ``delta`` (2N,), ``J`` (2N, k)
    real-stacked; ``base`` adds fixed (rᵀr, Jᵀr, JᵀJ) sums of the diagnosed record."""
    return t_solve(t_sums(delta, J, w), base)


def t_sums(delta: np.ndarray, J: np.ndarray, w: np.ndarray) -> tuple:
    """The normal-equation sums (rᵀWr (n_exp,), JᵀWr (n_exp, k), JᵀWJ (n_exp, k, k)) of
    :func:`t_criterion` per weight row of ``w``: independent records' sums add, so the criterion of
    records stacked is :func:`t_solve` of their summed sums (not the sum of their λ)."""
    rr = w @ (delta * delta)
    Jr = w @ (J * delta[:, None])
    JJ = np.einsum("ei,ij,ik->ejk", w, J, J, optimize=True)
    return rr, Jr, JJ


def t_solve(sums: tuple, base: tuple | None = None) -> np.ndarray:
    """min_δ (rᵀWr − 2δᵀJᵀWr + δᵀJᵀWJδ) per experiment from :func:`t_sums` ``sums`` (plus ``base``,
    fixed sums of the diagnosed record)."""
    rr, Jr, JJ = sums
    if base is not None:
        rr, Jr, JJ = rr + base[0], Jr + base[1], JJ + base[2]
    k = JJ.shape[-1]
    if k == 0:
        return rr
    scale = np.sqrt(np.maximum(np.einsum("ejj->ej", JJ), 1e-300))
    A = JJ / (scale[:, :, None] * scale[:, None, :]) + 1e-10 * np.eye(k)
    x = np.linalg.solve(A, (Jr / scale)[..., None])[..., 0]
    return np.maximum(rr - np.einsum("ej,ej->e", Jr / scale, x), 0.0)


def log_ratio(La: np.ndarray, Lb: np.ndarray) -> np.ndarray:
    """ln(G_A/G_B) from the two log-responses, its phase wrapped to (−π, π]."""
    D = La - Lb
    return D.real + 1j * np.angle(np.exp(1j * D.imag))


def stack_real(z: np.ndarray) -> np.ndarray:
    """Complex (N, ...) → real (2N, ...): log-magnitude rows, then phase rows."""
    return np.concatenate([z.real, z.imag], axis=0)



def log_unit_factor(record: FrequencySweep, sk: FrequencySweep) -> float:
    """ln of the factor from ``sk``'s response units to ``record``'s (same dimensions)."""
    from ..data.units import unit_scale

    if (record.input_unit, record.output_unit) == (sk.input_unit, sk.output_unit):
        return 0.0
    try:
        f = (unit_scale(sk.output_unit) / unit_scale(sk.input_unit)) / (unit_scale(record.output_unit)
                                                                        / unit_scale(record.input_unit))
    except (KeyError, IPMCError):
        return 0.0
    return float(np.log(abs(f)))



def refit_check(d, pairs: list, r, nm: dict, max_nfev: int, label, view: RecordView | None = None,
                count: dict | None = None) -> dict:
    """λ of experiment ``r`` (or of the experiments of a sequence ``r`` together: a two-record plan,
    :mod:`~physmodel.estimation.next_measurement_plan`) by full refits: each rival refitted to the
    other's noiseless predictions on the new lines (with the record's lines when joint) from its own
    fit, from its effect at its typical size and from :data:`REFIT_STARTS` − 2 more Latin-hypercube
    starts; ``{"A vs B": the least over the two directions}`` for each of ``pairs``.  ``count``
    (:func:`refit_lambda`) tallies the refits."""
    out = {}
    for a, b in pairs:
        out[f"{label(a)} vs {label(b)}"] = min(refit_lambda(d, r, nm, truth, rival, max_nfev, view=view, count=count)
                                               for truth, rival in ((a, b), (b, a)))
    return out


def refit_data(d, records: Sequence[CandidateMeasurement], nm: dict, truth: CompetingModel,
               view: RecordView) -> tuple:
    """(sweep, predictor factory ``model -> many``) of the new ``records`` as ``truth`` predicts them,
    noiseless, each line with the σ it is expected to carry (:func:`line_sigma`): when any record is
    evaluated with the diagnosed record (``joint``) the record's lines too (as ``truth`` predicts
    them, with their σ), a record of a quantity the record holds merged into it and another quantity
    diagnosed jointly; otherwise the records alone (two of one quantity merged, of two quantities
    diagnosed jointly).  One record: the sweep :func:`refit_lambda` always refitted to."""
    joint = any(r.joint for r in records)
    new: dict = {}
    for r in records:
        in_name, unit_in, out_name, unit_out = QUANTITY_UNITS[(d.kind, r.quantity)]
        sk = FrequencySweep(r.line_temperatures_c, r.line_frequencies_hz, np.ones(r.n_lines, complex), None, None,
                            in_name, unit_in, out_name, unit_out)
        G = np.asarray(view.many(truth.model, sk, r.quantity)([truth.values])[0])
        same = joint and r.quantity in view.sweeps       # σ regressed on |G| of the record's quantity
        rs = view.sweeps.get(r.quantity) if same else None
        logabs = np.log(np.abs(G)) + (log_unit_factor(rs, sk) if rs is not None else 0.0)
        s_ln, s_ph = line_sigma(nm["by_quantity"][r.quantity] if view.joint and same else nm, logabs,
                                np.array([r.level]), same)
        sw = FrequencySweep(sk.temperature_c, sk.frequency_hz, G, s_ln[0] * 20 / math.log(10), np.degrees(s_ph[0]),
                            sk.input_name, sk.input_unit, sk.output_name, sk.output_unit)
        new[r.quantity] = merge_records(new[r.quantity], sw) if r.quantity in new else sw
    if joint:
        sweeps = {}
        for q0, s0 in view.sweeps.items():      # the record, as the truth predicts it, with its σ
            G0 = np.asarray(view.many(truth.model, s0, q0)([truth.values])[0])
            if s0.magnitude_std_db is None:
                s0l, s0p, _ = noise_std(s0)
                std0 = (s0l * 20 / math.log(10), np.degrees(s0p))
            else:
                std0 = (s0.magnitude_std_db, s0.phase_std_deg)
            sweeps[q0] = FrequencySweep(s0.temperature_c, s0.frequency_hz, G0, *std0, s0.input_name,
                                        s0.input_unit, s0.output_name, s0.output_unit)
        for q, sw in new.items():
            sweeps[q] = merge_records(sweeps[q], sw) if q in sweeps else sw
        if view.joint or len(sweeps) == 1:
            return view.restacked(sweeps)
    elif len(new) == 1:
        (q, sw), = new.items()
        return sw, lambda model: view.many(model, sw, q)
    else:
        sweeps = new
    from .joint import joint_data  # several quantities the one-quantity view does not stack itself

    jd = joint_data(list(sweeps.values()), d.kind, tuple(sweeps))
    acts = {**view.acts_on, **view.new_acts_on}
    return jd.stacked, lambda model: jd.predictor(model, acts)


def refit_lambda(d, r, nm: dict, truth: CompetingModel, rival: CompetingModel, max_nfev: int,
                 rival_starts: Sequence[dict] = (), view: RecordView | None = None, count: dict | None = None) -> float:
    """λ of experiment ``r`` (a :class:`CandidateMeasurement`, or a sequence of them measured
    together, :func:`refit_data`) when ``truth`` is true: ``rival`` refitted to its noiseless
    predictions (:func:`refit_check`), from its own fit, its effect at its typical size, each of
    ``rival_starts`` (values of every free parameter: the rival's other forms) and
    :data:`REFIT_STARTS` − 2 Latin-hypercube starts; the least λ over them (each start group its own
    fit: in a refit the cost is misfit, not noise, and a start must not join another's optimum by a
    test scaled with it).  A refit made before in the same search
    (``view.refits``, :func:`refit_fingerprint`) is not made again.  ``count``, when given, is added to: ``fits`` (least-squares calls),
    ``starts`` and ``evaluations`` (their function evaluations), and ``cached`` (refits answered from ``view.refits``)."""
    from .lsq import fit_parameters

    view = view or RecordView(d)
    records = [r] if isinstance(r, CandidateMeasurement) else list(r)
    if not records:
        raise IPMCError("refit_lambda: no experiment given")
    sw, factory = refit_data(d, records, nm, truth, view)
    # by content, not identity (a model made for one check and freed may share a later one's id): the
    # truth is in the refitted lines (its predictions), the rival in its effects, values and free box
    key = (tuple(rival.effects), repr(sorted(rival.values.items())), repr(rival.free), max_nfev, repr(list(rival_starts)),
           tuple((r.quantity, r.joint) for r in records), refit_fingerprint(sw))
    if key in view.refits:          # the same refit made before in this search: its λ, no new fit
        if count is not None:
            count["cached"] = count.get("cached", 0) + 1
        return view.refits[key]
    pm = factory(rival.model)
    cb = d.metadata.get("candidate_bounds", {})
    typical = {f"{c}.{p}": v[2] for c in rival.effects for p, v in cb.get(c, {}).items()}
    best = math.inf
    starts = [(rival.values, 1), ({**rival.values, **typical}, REFIT_STARTS - 1)] + [(s, 1) for s in rival_starts]
    for start, n in starts:
        free = [fp.with_initial(min(max(start[fp.name], fp.lower), fp.upper)) for fp in rival.free]
        res = fit_parameters(sw, None, free, predict_many=pm, starts=n, seed=0, max_nfev=max_nfev, identify=False,
                             hold_undetermined=False)
        lam = 2.0 * float(res.cost)
        best = min(best, lam) if lam == lam else float("nan")   # NaN stays NaN: not separated (review)
        if count is not None:
            count["fits"] = count.get("fits", 0) + 1
            count["starts"] = count.get("starts", 0) + len(res.starts)
            count["evaluations"] = count.get("evaluations", 0) + int(sum(s.nfev for s in res.starts))
        if best != best:
            break
    view.refits[key] = best
    return best


def refit_fingerprint(sw: FrequencySweep) -> tuple:
    """What of the refitted lines ``sw`` a refit depends on: their temperatures, frequencies,
    responses and σ (the bytes), units and, stacked, the blocks (``metadata``'s quantities, sizes
    and units) — two equal fingerprints are the same least-squares problem (:func:`refit_lambda`)."""
    arrays = tuple(None if a is None else np.asarray(a).tobytes()
                   for a in (sw.temperature_c, sw.frequency_hz, sw.response, sw.magnitude_std_db, sw.phase_std_deg))
    meta = sw.metadata or {}
    return (type(sw).__name__, sw.input_unit, sw.output_unit, arrays, repr(meta.get("quantities")),
            repr(meta.get("block_sizes")), repr(meta.get("units")))


__all__ = ["CompetingModel", "FD_RELATIVE_STEP", "REFIT_STARTS", "RecordView", "fit_competing_models", "line_sigma",
           "log_ratio", "log_unit_factor", "check_new_acts_on", "new_quantity_acts_on", "noise_model", "refit_check", "refit_data", "refit_fingerprint", "refit_lambda", "refit_model", "stack_real",
           "sweep_noise_model", "t_criterion", "t_solve", "t_sums"]
