"""Other forms of a competing model's fit, for the next-measurement search (issue 27 item 3).

A model may fit the diagnosed record in more than one form: the library's ``transimpedance`` as a
stage led by its feedback capacitor with ideal op-amps (one pole — a nested form of
``amplifier_bandwidth``) or as one led by the op-amps' gain–bandwidth, whose corner GBW·|Z|/R1
moves with the strip's impedance and so with the bath.  The search of
:mod:`~physmodel.estimation.next_measurement` linearises at each model's fit to the record; when a
pair comes out inseparable as fitted it asks this module for the model's other forms:

* :func:`alternative_forms` refits the model to the record from starts in its other forms — each
  effect parameter held at its lower bound (its off value) in turn, the effect's other parameters
  that sit near their lower bound started at their typical size; and, as one multi-start, from the
  diagnosis's own candidate fit and a log grid of the effect's parameters within the candidate
  bounds (the grid screened by one vectorised ``predict_many`` call on the record with the base
  parameters at the fit, its best :data:`GRID_REFITS` points refitted);
* every optimum found is kept as a form that *fits* when 2·(cost − best cost) ≤ χ²_p(1 − α) with p
  the effect's parameters and α the diagnosis's: the likelihood-ratio confidence region of the
  effect at the diagnosis's level, so the record cannot reject it (:func:`form_threshold`);
  forms whose responses on the search grid are within :data:`~physmodel.estimation.next_measurement.SAME_FORM_LAMBDA`
  (χ², summed over every candidate line) of one already kept are one form (:func:`distinct`).

The search then takes each form that fits as a possible truth (:class:`FormContest`: the criterion,
per direction, is the least λ over them, the rival linearised at and refitted from each of its own
forms and from its fit moved to the truth form's base parameters), and leaves out a truth form no
experiment separates from the rival (λ below ``SAME_FORM_LAMBDA`` everywhere linearised, or after
the refits of every checked experiment expected to separate it) and the two fits of a pair the first
search found inseparable: the truth is then a nested form of the rival and the diagnosis decides it
by parsimony, which the result says.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .next_measurement_design import CompetingModel, RecordView
from .residuals import noise_std, standardised_residuals

#: Alternative forms kept per model (the best by cost), besides its fit.
MAX_FORMS = 3
#: Log-grid points per effect parameter of the multi-start screen (plus the lower bound when it is 0).
GRID_POINTS = 4
#: Grid points refitted after the screen (the best by screened cost).
GRID_REFITS = 3
#: Screened points at most (a model with many effect parameters: a seeded random subset of the
#: product grid, so one predict_many call stays bounded; an evenly strided subset would hold the
#: fastest axes fixed).
MAX_GRID = 625


def form_threshold(alpha: float, n_params: int) -> float:
    """2·Δcost below which a form fits as well as the best: χ²_p quantile at 1 − α (p = ``n_params``,
    the effect's parameters; the likelihood-ratio confidence region at the diagnosis's level). [-]"""
    from scipy.stats import chi2

    return float(chi2.ppf(1.0 - alpha, max(int(n_params), 1)))


def _record_costs(d, m: CompetingModel, sets: list) -> np.ndarray:
    """½ Σ r² of each parameter set of ``sets`` on the diagnosed record (one predict_many call, the
    residuals of every set in one array); a set the model refuses or where it is not finite costs
    inf (it is not a form), found set by set only when the batch fails."""
    s_ln, s_ph, _ = noise_std(d.data)
    pm = RecordView(d).record_many(m.model)
    try:
        r = standardised_residuals(np.asarray(pm(sets)), d.data, s_ln, s_ph)
        return 0.5 * np.einsum("ij,ij->i", r, r)
    except (ValueError, FloatingPointError):
        pass
    out = np.full(len(sets), math.inf)
    for i, one in enumerate(sets):
        try:
            r = standardised_residuals(np.asarray(pm([one]))[0], d.data, s_ln, s_ph)
        except (ValueError, FloatingPointError):    # not a form
            continue
        out[i] = 0.5 * float(r @ r)
    return out


def _grid_axis(lo: float, hi: float, typ: float) -> list[float]:
    """Screening values of one effect parameter within [lo, hi]: a log grid where the range is
    positive (from typical/30 when the lower bound is 0, which is kept), a linear one for a
    parameter that changes sign (e.g. a temperature coefficient), else the two bounds."""
    if lo > 0 and hi > lo:
        return [float(v) for v in np.geomspace(lo, hi, GRID_POINTS)]
    if lo == 0 and typ > 0 and hi > typ / 30.0:
        return [0.0] + [float(v) for v in np.geomspace(typ / 30.0, hi, GRID_POINTS)]
    if lo < 0 < hi:
        return [float(v) for v in np.linspace(lo, hi, GRID_POINTS)]
    return [float(lo), float(hi)]


def alternative_forms(d, m: CompetingModel, max_nfev: int) -> list[tuple[CompetingModel, float]]:
    """``m``'s fits to the diagnosed record in other forms (module doc), each ``(model, cost)`` with
    ``cost`` = ½χ² on the record, the fit itself first, the others by cost; only those within
    :func:`form_threshold` of the best."""
    from .lsq import fit_parameters

    cb = d.metadata.get("candidate_bounds", {})
    eff = [(f"{c}.{p}", lo, hi, typ) for c in m.effects for p, (lo, hi, typ) in cb.get(c, {}).items()]
    if not eff:
        return [(m, float(_record_costs(d, m, [m.values])[0]))]
    pm = RecordView(d).record_many(m.model)
    names = [fp.name for fp in m.free]
    found: list[dict] = [dict(m.values)]

    def near_lo(v, lo, hi):
        return v - lo <= 1e-3 * (hi - lo)

    # each effect parameter held at its lower bound (its off value), the others near theirs started at typical
    for name, lo, _hi, _ in eff:
        start = {**m.values, **{n: t for n, lo_, hi_, t in eff if n != name and near_lo(m.values[n], lo_, hi_)}}
        free = [fp.with_initial(min(max(start[fp.name], fp.lower), fp.upper)) for fp in m.free if fp.name != name]
        held = {name: float(lo)}

        def pm_held(sets, held=held):
            return pm([{**s, **held} for s in sets])

        res = fit_parameters(d.data, None, free, predict_many=pm_held, starts=1, seed=0, max_nfev=max_nfev,
                             identify=False, hold_undetermined=False)
        found.append({**m.values, **dict(res.values), **held})
    # one multi-start: the diagnosis's own candidate fit(s) and the best points of a log grid of the effect
    initials = []
    for c in m.effects:
        cr = getattr(d, "candidates", {}).get(c)
        if cr is not None:
            rng = (cr.multistart or {}).get("ranges", {})
            initials.append({**m.values, **{k: 0.5 * (v[0] + v[1]) for k, v in rng.items() if k in names},
                             **{f"{c}.{p}": v for p, v in cr.values.items() if f"{c}.{p}" in names}})
    axes = [_grid_axis(lo, hi, typ) for _, lo, hi, typ in eff]
    points = list(itertools.product(*axes))
    if len(points) > MAX_GRID:
        keep = np.sort(np.random.default_rng(0).choice(len(points), MAX_GRID, replace=False))
        points = [points[i] for i in keep]
    grid = [{**m.values, **{n: float(v) for (n, *_), v in zip(eff, pt)}} for pt in points]
    screened = _record_costs(d, m, grid)
    initials += [grid[i] for i in np.argsort(screened)[:GRID_REFITS] if np.isfinite(screened[i])]
    free = [fp.with_initial(min(max(m.values[fp.name], fp.lower), fp.upper)) for fp in m.free]
    res = fit_parameters(d.data, None, free, predict_many=pm, starts=1, seed=0, max_nfev=max_nfev, identify=False,
                         hold_undetermined=False, initials=initials)
    found += [{**m.values, **s.final} for s in res.starts if s.status != -2]
    costs = _record_costs(d, m, found)
    thr = form_threshold(d.alpha, len(eff))
    ok = [i for i in np.argsort(costs, kind="stable") if i > 0 and 2.0 * (costs[i] - costs.min()) <= thr]
    out = [(m, float(costs[0]))]
    for i in ok:
        out.append((CompetingModel(d, m.effects, found[i], m.free), float(costs[i])))
    return out


def distinct(forms: list, responses: list, weights: list, limit: float) -> list[int]:
    """Indices of ``forms`` kept as distinct: the first (the fit) always, then farthest first — the
    form whose log-response is farthest (χ² summed over the search grid) from every kept one — while
    that distance is at least ``limit`` (the search's
    :data:`~physmodel.estimation.next_measurement.SAME_FORM_LAMBDA`), at most :data:`MAX_FORMS` more.
    ``responses``: per form, a list over quantities of complex log-responses; ``weights``: per
    quantity, (1/σ_ln², 1/σ_φ²) of its lines."""
    from .next_measurement_design import log_ratio

    def chi(i: int, j: int) -> float:
        out = 0.0
        for q, (wl, wp) in enumerate(weights):
            D = log_ratio(responses[j][q], responses[i][q])
            out += float(np.sum(wl * D.real ** 2 + wp * D.imag ** 2))
        return out if math.isfinite(out) else 0.0

    keep = [0]
    near = np.array([chi(0, j) for j in range(len(forms))])
    while len(keep) <= MAX_FORMS:
        j = int(np.argmax(near))
        if not near[j] >= limit:
            break
        keep.append(j)
        near = np.minimum(near, [chi(j, k) for k in range(len(forms))])
    return keep


def form_summary(label: str, form: CompetingModel, cost: float, best: float, thr: float, role: str) -> dict:
    """JSON-ready description of one form of model ``label``: its effect values, ½χ² on the record,
    2Δcost to the best form and the threshold, and its ``role`` in the search."""
    eff = {k: v for k, v in form.values.items() if "." in k}
    return {"model": label, "effect_values": eff, "cost": cost, "delta_chi2": 2.0 * (cost - best),
            "threshold": thr, "role": role}



class FormContest:
    """One pair searched with its models' forms: per direction (``"A true"``) the truth forms that fit
    and the rival's forms it refits from; which truth forms are left to parsimony (no experiment
    separates them from the rival: nested in it); per candidate experiment the linearised λ and,
    when checked, the refit λ of each truth form."""

    def __init__(self, key: str, directions: list, base_names: list, limit: float, same_as_fitted: bool = False):
        self.key, self.directions, self.limit = key, directions, float(limit)
        # per direction and truth form, the rival's fit moved to the truth form's base parameters: one
        # more point the rival's refit may start from (its base values need not be the ones its own fit
        # to the record took; a quantity the effects do not reach sees only those)
        self.rebased = {(name, j): CompetingModel(rivals[0].d, rivals[0].effects,
                                                  {**rivals[0].values, **{n: t.values[n] for n in base_names}},
                                                  rivals[0].free)
                        for name, truths, rivals in directions for j, t in enumerate(truths)}
        # name -> {form index: why}; a pair the search without forms found inseparable: its two fits
        # (form 0 of each direction) are the same response, each a nested form of the other
        self.excluded: dict = {name: ({0: "as fitted"} if same_as_fitted else {}) for name, _, _ in directions}
        self.lin: dict = {}            # id(row) -> {name: [λ per truth form]}
        self.refit: dict = {}          # id(row) -> {name: {form index: λ}}

    def linearise(self, resp: dict, rec: dict | None, W: np.ndarray, w0: np.ndarray) -> list[dict]:
        """Per experiment (rows of the weight masks ``W``), ``{name: [λ per truth form]}``: the least
        over the rival's forms of the T-criterion linearised at each (``rec``: the record's
        log-responses when the experiment is evaluated together with it)."""
        from .next_measurement_design import log_ratio, stack_real, t_criterion

        out: dict = {}
        for name, truths, rivals in self.directions:
            per = []
            for j, t in enumerate(truths):
                lam = np.full(W.shape[0], np.inf)
                for rv in rivals + [self.rebased[(name, j)]]:
                    D = stack_real(log_ratio(resp[id(t)][0], resp[id(rv)][0]))
                    base = None
                    if rec is not None:
                        D0, J0 = stack_real(log_ratio(rec[id(t)][0], rec[id(rv)][0])), stack_real(rec[id(rv)][1])
                        base = (w0 @ (D0 * D0), (w0[:, None] * J0).T @ D0, (w0[:, None] * J0).T @ J0)
                    lam = np.minimum(lam, t_criterion(D, stack_real(resp[id(rv)][1]), W, base))
                per.append(lam)
            out[name] = per
        return [{name: [float(x[e]) for x in per] for name, per in out.items()} for e in range(W.shape[0])]

    def models(self) -> list:
        """Every model whose responses the contest uses (forms and re-based rivals)."""
        out = {id(m): m for _, truths, rivals in self.directions for m in truths + rivals}
        out.update({id(m): m for m in self.rebased.values()})
        return list(out.values())

    def settle_linearised(self, rows: list) -> None:
        """Store each row's per-form λ and leave to parsimony the truth forms no experiment separates
        from the rival even linearised."""
        for r in rows:
            self.lin[id(r)] = r.separation_by_pair[self.key]
        for name, truths, _ in self.directions:
            for j in range(len(truths)):
                if max(self.lin[id(r)][name][j] for r in rows) < self.limit:
                    self.excluded[name][j] = "linearised"
        self.apply(rows)

    def live(self) -> bool:
        """Some direction keeps a truth form."""
        return any(len(self.excluded[n]) < len(t) for n, t, _ in self.directions)

    def value(self, rid: int) -> dict:
        """``{name: least λ over the direction's kept truth forms}`` of row ``rid`` (directions with
        none kept left out; every direction's least over all forms when none is kept at all)."""
        lin = self.lin[rid]
        if not self.live():
            return {n: min(v) for n, v in lin.items()}
        return {n: min(v[j] for j in range(len(v)) if j not in self.excluded[n]) for n, v in lin.items()
                if len(self.excluded[n]) < len(v)}

    def apply(self, rows: list) -> None:
        """Write this pair's linearised separation (the least over its kept truth forms) into each
        row's ``separation_by_pair``."""
        for r in rows:
            r.separation_by_pair[self.key] = self.value(id(r))

    def check(self, d, r, nm: dict, max_nfev: int, view=None) -> float:
        """Refit λ of row ``r``: the least over directions and kept truth forms, the rival refitted
        from each of its forms (computed once per truth form and row)."""
        from .next_measurement_design import refit_lambda

        got = self.refit.setdefault(id(r), {n: {} for n, _, _ in self.directions})
        for name, truths, rivals in self.directions:
            for j, t in enumerate(truths):
                if j in self.excluded[name] or j in got[name]:
                    continue
                got[name][j] = refit_lambda(d, r, nm, t, rivals[0], max_nfev,
                                            [rv.values for rv in rivals[1:] + [self.rebased[(name, j)]]], view=view)
        return self.refit_value(id(r))

    def refit_value(self, rid: int) -> float:
        """The refit λ of the row with ``id`` ``rid``: the least over the directions' truth forms not
        left to parsimony (0 when none was refitted). [-]"""
        got = self.refit.get(rid, {})
        vals = [v for n in got for j, v in got[n].items() if j not in self.excluded[n]]
        return float(min(vals)) if vals else 0.0

    def settle_refits(self, checked: list) -> bool:
        """Leave to parsimony a truth form that every checked experiment expected (linearised) to
        separate it does not separate after the refits; True when one was."""
        new = False
        for name, truths, _ in self.directions:
            for j in range(len(truths)):
                if j in self.excluded[name]:
                    continue
                judged = [r for r in checked if j in self.refit.get(id(r), {}).get(name, {})
                          and self.lin[id(r)][name][j] >= self.limit]
                if judged and all(self.refit[id(r)][name][j] < self.limit for r in judged):
                    self.excluded[name][j] = "refits"
                    new = True
        return new

    def describe(self, forms_of) -> dict:
        """JSON-ready: per direction, each truth form's role (searched, or left to parsimony and why)."""
        out = {}
        for name, truths, _ in self.directions:
            out[name] = [{"form": forms_of(t), "role": ("searched as a possible truth" if j not in self.excluded[name]
                                                        else "nested in the rival (" + self.excluded[name][j]
                                                        + "): decided by parsimony")}
                         for j, t in enumerate(truths)]
        return out


__all__ = ["FormContest", "GRID_POINTS", "GRID_REFITS", "MAX_FORMS", "alternative_forms", "distinct",
           "form_summary", "form_threshold"]
