"""A second record when no single one separates every pair (issue 27, next_measurement_plan): the
combined λ of two records against a direct least-squares oracle on the concatenated records, two
pairs that need different quantities get one record of each, and a one-pair search is unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from physmodel.estimation.next_measurement_design import t_criterion, t_sums
from physmodel.estimation.next_measurement_plan import overlaps, record_base, second_record
from physmodel.estimation.next_measurement_results import CandidateMeasurement


def _row(q: str, f, joint: bool = False) -> CandidateMeasurement:
    f = np.asarray(f, float)
    return CandidateMeasurement(q, (float(f.min()), float(f.max())), (35.0,), 1.0, f.size, f, 0.0, {}, joint, 1.0,
                                0.0, line_temperatures_c=np.full(f.size, 35.0), line_frequencies_hz=f)


def _lstsq_lambda(blocks) -> float:
    """min_δ Σ w (Δ − Jδ)² over the concatenated records ``[(D, J, w), ...]`` by numpy.linalg.lstsq on
    the explicitly weighted, stacked rows (not the normal equations the search adds)."""
    A = np.vstack([J * np.sqrt(w)[:, None] for D, J, w in blocks])
    b = np.concatenate([D * np.sqrt(w) for D, J, w in blocks])
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    return float(np.sum((b - A @ x) ** 2))


def test_combined_lambda_is_the_stacked_records_not_the_sum_of_their_lambdas():
    """Two records (one merged with the diagnosed record, one of another quantity): the combined λ
    of second_record equals lstsq on the record + both new records concatenated, and it is not the
    sum of the two single λ (the rival refits one δ to both; the record counted once)."""
    rng = np.random.default_rng(11)
    k = 3
    D0, J0, w0 = rng.standard_normal(12), rng.standard_normal((12, k)), rng.uniform(0.5, 2, 12)
    # the diagnosed record as log-responses (real: the phase rows carry nothing and weigh 0):
    # ln G_a − ln G_b = D0 and the rival b's Jacobian −J0, so its rows are (D0, −J0, w0)
    rec_a = (D0 + 0j, np.zeros((12, k), complex))
    rec_b = (np.zeros(12, complex), -J0 + 0j)
    w0s = np.r_[w0, np.zeros(12)]
    base_ab, _ = record_base(rec_a, rec_b, w0s)
    blocks, rows, sums_ab = [], [], []
    for q, n, joint in (("M", 9, True), ("Z", 7, False), ("Z", 5, False)):
        D, J, w = rng.standard_normal(n), rng.standard_normal((n, k)), rng.uniform(0.5, 3, n)
        blocks.append((D, J, w))
        rows.append(_row(q, np.arange(1, n + 1) * (10.0 if q == "M" else 1.0), joint))
        sums_ab.append(t_sums(D, J, w[None, :]))
    sums = {"A vs B": {"A true": tuple(np.concatenate(x) for x in zip(*sums_ab))}}
    bases = {"A vs B": {"A true": base_ab}}
    plan = second_record(rows[0], rows, sums, bases, ["A vs B"])
    assert plan is not None
    # the oracle for each candidate second record: the diagnosed record + the first + it, stacked
    lam = {j: _lstsq_lambda([(D0, -J0, w0), blocks[0], blocks[j]]) for j in (1, 2)}
    j_best = max(lam, key=lam.get)
    # the best row, described in its role: counted with the record, so diagnosed jointly with it (review)
    best = rows[j_best]
    assert (plan.second.quantity, plan.second.band_hz, plan.second.temperatures_c) == (
        best.quantity, best.band_hz, best.temperatures_c)
    assert plan.second.joint and plan.second.added_quantity and not best.joint
    assert plan.separation == pytest.approx(lam[j_best], rel=1e-7)
    assert plan.separation_by_pair["A vs B"]["A true"] == pytest.approx(lam[j_best], rel=1e-7)
    single = [float(t_criterion(D, J, w[None, :], base_ab if rows[i].joint else None)[0])
              for i, (D, J, w) in enumerate(blocks)]
    assert single[0] == pytest.approx(_lstsq_lambda([(D0, -J0, w0), blocks[0]]), rel=1e-7)
    assert abs(plan.separation - (single[0] + single[j_best])) > 1e-3 * plan.separation    # not additive


def test_two_pairs_that_need_different_quantities_get_one_record_of_each():
    """Pair A separates only in M, pair B only in Z (each quantity's Δ of the other pair is 0): the
    best single record separates one pair at most, so the second is of the other quantity; and a
    second M record never repeats the first's lines."""
    k, n = 1, 6
    J = np.zeros((2 * n, k))          # the rival has one parameter that no line sees: λ = Σ w Δ²
    rows, s = [], {"A": [], "B": []}
    for q, fs, big in (("M", [1, 2, 3, 4, 5, 6], 3.0), ("M", [7, 8, 9, 10, 11, 12], 2.0),
                       ("Z", [1, 2, 3, 4, 5, 6], 1.0), ("Z", [20, 30, 40, 50, 60, 70], 0.5)):
        rows.append(_row(q, np.asarray(fs, float)))
        w = np.ones((1, 2 * n))
        DA = np.r_[np.full(n, big), np.zeros(n)] if q == "M" else np.zeros(2 * n)
        DB = np.r_[np.full(n, big), np.zeros(n)] if q == "Z" else np.zeros(2 * n)
        s["A"].append(t_sums(DA, J, w))
        s["B"].append(t_sums(DB, J, w))
    sums = {p: {"x true": tuple(np.concatenate(x) for x in zip(*v))} for p, v in s.items()}
    zero = (0.0, np.zeros(k), np.zeros((k, k)))
    bases = {p: {"x true": zero} for p in sums}
    plan = second_record(rows[0], rows, sums, bases, ["A", "B"])
    assert plan is not None and plan.second is rows[2]              # Z, the larger of the Z records
    assert plan.separation == pytest.approx(min(6 * 9.0, 6 * 1.0))
    plan_z = second_record(rows[2], rows, sums, bases, ["A", "B"])
    assert plan_z.second is rows[0]                                   # and the other way round
    assert overlaps(rows[0], _row("M", [6.0, 13.0])) and not overlaps(rows[0], _row("Z", [6.0]))
    only_m = second_record(rows[0], rows[:2], sums_subset(sums, 2), bases, ["A", "B"])
    assert only_m.second is rows[1] and only_m.separation == 0.0      # M cannot see B: honest 0
    assert second_record(rows[0], rows, sums, bases, ["A", "C"]) is None    # a pair without sums: no plan


def sums_subset(sums: dict, n: int) -> dict:
    """``sums`` of the first ``n`` rows."""
    return {p: {d: tuple(a[:n] for a in v) for d, v in dd.items()} for p, dd in sums.items()}


@pytest.fixture(scope="module")
def seed47079():
    """Development seed 47079 of bench_next_measurement ``--pairs`` (the independent generator's own
    physics: contact resistance + delay) diagnosed on M as the bench does."""
    from next_measurement_cases import independent

    from physmodel import IPMCParameters
    from physmodel.estimation.discrepancy import diagnose

    ig = independent("independent_generator")
    sweep, truth = ig.make_case(47079, "contact_resistance+time_delay",
                                workflow_free=("alpha", "d", "eps", "zeta", "f1"))
    base = IPMCParameters.from_dict(dict(truth["library_start"]))
    d = diagnose(sweep, base, kind="actuator", quantity="M", free=("alpha0", "d", "kappa_e", "xi", "omega_n"),
                 seed=47079)
    assert d.verdict == "ambiguous"
    return d


def _search_47079(d):
    from physmodel.estimation.next_measurement import next_measurement

    return next_measurement(d, quantities=["M", "Z"], band_limits_hz=(0.01, 200.0),
                            acts_on={"time_delay": ("M",), "amplifier_bandwidth": ("M",)})


def test_the_independent_actuator_pair_gets_an_m_and_a_z_record(seed47079, monkeypatch):
    """Seed 47079: the first record leaves the pair and its twins (diffusivity law, amplifier pole)
    ambiguous; the delay against the pole parts only in M (the chain is on M, declared), the
    contact resistance against the diffusivity law best in Z, so no single record reaches the
    target and two are recommended, one M and one Z, with the message saying both; the refits of
    the rivals to both records together confirm it, within the linearised value's order."""
    d = seed47079
    nm = _search_47079(d)
    r, also = nm.recommended, nm.also
    assert len(also) == 1 and {r.quantity, also[0].quantity} == {"M", "Z"}
    assert r.separation < nm.target <= nm.together["separation"] and nm.separates
    assert set(nm.together["separation_by_pair"]) == set(r.separation_by_pair)
    lin = nm.together["separation_linearised"]
    assert min(min(v.values()) for v in nm.together["separation_by_pair"].values()) == lin
    # checked by refits of the rivals to both records together (the least over the pairs and directions)
    assert not nm.together["linearised_only"] and set(nm.together["refit_by_pair"]) == set(r.separation_by_pair)
    assert nm.together["separation"] == min(nm.together["refit_by_pair"].values()) >= nm.target
    # 2 calls × 2 directions a pair, for the pairs the first record's refits leave short of the target
    # (the others keep the first record's value: a lower bound)
    short = [k for k in r.separation_by_pair if not r.refit_by_pair.get(k, float("nan")) >= nm.target]
    assert 0 < len(short) < len(r.separation_by_pair)
    assert nm.together["refits"]["fits"] == 2 * 2 * len(short)
    assert all(nm.together["refit_by_pair"][k] == r.refit_by_pair[k] for k in r.separation_by_pair if k not in short)
    assert 0.5 < nm.together["separation"] / lin < 2.0
    assert nm.together["recommended"] is True and nm.to_dict()["together"]["recommended"] is True   # review
    assert "and, with it," in nm.message and "together expected λ" in nm.message
    assert "checked by refits of the rivals to both records together" in nm.message
    assert nm.to_dict()["also"][0]["quantity"] == also[0].quantity
    # the pair's λ counts the first record's linearised sums: where its refits fall short of them for a
    # pair the first record carries alone, the shortfall is taken off, so a second record that sees
    # nothing of that pair cannot make it "separated" (review: it had, with separates=True)
    import physmodel.estimation.next_measurement as nmod

    carried = min(also[0].separation_by_pair, key=lambda k: min(also[0].separation_by_pair[k].values()))
    assert min(also[0].separation_by_pair[carried].values()) < 1.0       # the second record does not see it
    assert min(r.separation_by_pair[carried].values()) >= nm.target      # the first carries it alone
    real = nmod.refit_check

    def capped(*a, **k):
        out = real(*a, **k)
        if carried in out:
            out[carried] = min(out[carried], 5.0)
        return out

    monkeypatch.setattr(nmod, "refit_check", capped)
    nm2 = _search_47079(d)
    # the greedy plan from the first record is short once the shortfall is taken off (it was recommended
    # before the review); a plan started from another pair's own best record (issue 27, first_records)
    # is not built on the capped refits: it is recommended only when its own refits of every pair, on
    # both records together, reach the target (here they do: the cap is on the single-record check only)
    tg2 = nm2.together
    assert tg2["greedy"] < nm2.target and tg2["first_for"] is not None
    assert tg2["greedy_linearised"] >= tg2["greedy"]        # both said (review: the reduced one was called linearised)
    assert nm2.recommended.describe() != r.describe() and "and, with it," in nm2.message
    assert "not the best single one" in nm2.message
    assert tg2["refits"]["fits"] == 2 * 2 * len(r.separation_by_pair)      # every pair refitted, none carried
    assert nm2.separates == (tg2["refit_by_pair"][carried] >= nm2.target and tg2["separation"] >= nm2.target)


def _claimed_m(real, every: bool):
    """A ``second_record`` that claims the best M record not overlapping the first (none of the
    records already refused, ``exclude``) at λ 1e6 linearised: on the first call only (``every``
    False: later calls are the real search's next-best), or on every call."""
    from physmodel.estimation.next_measurement_plan import RecordPair

    def claimed(first, rows, *a, exclude=(), **k):
        if exclude and not every:
            return real(first, rows, *a, exclude=exclude, **k)
        if exclude:
            from physmodel.estimation.next_measurement_plan import covered
        m = max((r for r in rows if r.quantity == first.quantity and not overlaps(first, r)
                 and not any(covered(r, x) for x in exclude)), key=lambda r: r.separation)
        return RecordPair(m, 1e6, {})

    return claimed


def _patch_second_record(monkeypatch, fake):
    """``fake`` for the search's second record, wherever the search looks it up (main called it
    from next_measurement, the branch from next_measurement_plan.choose_plan)."""
    import physmodel.estimation.next_measurement as nmod
    import physmodel.estimation.next_measurement_plan as plan_mod

    monkeypatch.setattr(nmod, "second_record", fake, raising=False)
    monkeypatch.setattr(plan_mod, "second_record", fake)


def _cr_dt(k: str) -> bool:
    return k.count(" vs ") == 1 and "contact_resistance" in k and "diffusivity_temperature" in k


def test_a_refused_second_record_gives_way_to_the_next_best(seed47079, monkeypatch):
    """Seed 47079 with the linearised-best second record swapped for a second M record claimed at
    λ 1e6: M cannot tell the contact resistance from the diffusivity law (they part in Z: physics,
    not this code), so the refits refuse it; the search must then try the next-best second record by
    linearised λ — the real search's, a Z record — which the refits confirm: recommended, separates.
    (On main, 0e3466e, the refused plan ended the search: no second record, separates False.)"""
    from physmodel.estimation import next_measurement_plan as plan_mod

    unpatched = _search_47079(seed47079)
    _patch_second_record(monkeypatch, _claimed_m(plan_mod.second_record, every=False))
    nm = _search_47079(seed47079)
    assert nm.separates and len(nm.also) == 1 and nm.also[0].quantity == "Z" != nm.recommended.quantity
    assert nm.also[0].describe() == unpatched.also[0].describe()
    tg = nm.together
    assert tg["recommended"] is True and tg["short"] == {} and tg["separation"] >= nm.target
    first, second = tg["checked"]
    assert first["quantity"] == "M" and first["separation_linearised"] == 1e6 and first["separation"] < nm.target
    assert all(_cr_dt(k) for k, v in first["refit_by_pair"].items() if v < nm.target)
    assert second["quantity"] == "Z" and second["separation"] == tg["separation"]
    assert tg["refits_total"]["fits"] >= tg["refits"]["fits"] > 0
    assert "1 second record(s) of larger linearised λ fell short after the refits" in nm.message
    assert nm.to_dict()["together"]["checked"][0]["quantity"] == "M"


def test_a_short_pair_of_records_better_than_the_first_alone_is_offered(seed47079, monkeypatch, tmp_path):
    """Seed 47079 with every second record tried an M record claimed at λ 1e6: the refits leave the
    contact resistance against the diffusivity law short in each (three tried: the linearised best
    and two more), so none reaches the target; the one of largest λ after the refits is still above
    the first record's own (a rival refitted to more lines cannot fit them better: per pair at least
    the first record's refit λ, the invariant checked here), so it is recommended with
    ``separates`` False and its shortfall in the message and in to_dict.  Its gain here is small
    (1.74 against 1.63 after the refits): below the default margin ``SHORT_PLAN_GAIN`` (10 %), which
    this test sets to 0 to check how an offered plan travels; the next test checks the default."""
    import math

    from physmodel.estimation import next_measurement_plan as plan_mod

    monkeypatch.setattr(plan_mod, "SHORT_PLAN_GAIN", 0.0)
    _patch_second_record(monkeypatch, _claimed_m(plan_mod.second_record, every=True))
    nm = _search_47079(seed47079)
    r, tg = nm.recommended, nm.together
    assert not nm.separates and len(nm.also) == 1 and nm.also[0].quantity == "M"
    assert len(tg["checked"]) == 1 + plan_mod.MORE_SECOND_RECORDS
    assert all(c["separation"] < nm.target for c in tg["checked"])
    assert tg["recommended"] is True and tg["separation"] == max(c["separation"] for c in tg["checked"])
    for k, v in tg["refit_by_pair"].items():        # least squares over a superset of the lines
        assert v >= r.refit_by_pair[k] * (1 - 1e-3)
    lam = tg["separation"]
    assert r.separation_refit < lam < nm.target
    assert tg["short"] and all(_cr_dt(k) for k in tg["short"])
    for k, v in tg["short"].items():
        assert v == {"separation": tg["refit_by_pair"][k], "short_by": nm.target - tg["refit_by_pair"][k]}
        assert f"{k} reaches only {v['separation']:.3g} (short of {nm.target:.3g} by {v['short_by']:.3g})" in nm.message
    assert nm.to_dict()["together"]["short"] == tg["short"] and nm.to_dict()["separates"] is False
    assert "No single experiment within the limits is expected to separate" in nm.message
    assert f"nor any of the {len(tg['checked'])} pairs of records checked by refits" in nm.message   # review: not all pairs
    assert "and, with it," in nm.message
    assert f"about {math.ceil(nm.target / lam)}× as many" in nm.message and "accept the ambiguity" in nm.message
    # what `ipmc diagnose` writes carries it: report.json, summary.md and model.json's verdict reason
    # (its stderr line is the message, as test_next_measurement's CLI test checks)
    import json
    from dataclasses import replace

    d = replace(seed47079)
    d.next_measurement = nm
    d.write_report(tmp_path)
    rep = json.loads((tmp_path / "report.json").read_text())["next_measurement"]
    assert rep["separates"] is False and rep["also"] and rep["together"]["short"] == json.loads(json.dumps(tg["short"]))
    k = next(iter(tg["short"]))
    assert f"{k} reaches only" in (tmp_path / "summary.md").read_text()
    assert f"{k} reaches only" in d.to_model_file().verdict.reason


def test_a_short_pair_of_records_with_an_optimiser_size_gain_is_not_recommended(seed47079, monkeypatch):
    """The same records with the default margin: the best plan's 1.74 after the refits is above the
    first record's 1.63 by 7 %, under ``SHORT_PLAN_GAIN`` — not a gain worth a second experiment
    (review of the short plans: a strict ">" sent the user to measure for an optimiser's
    difference); not recommended, and the message says by what margin it would have had to win."""
    from physmodel.estimation import next_measurement_plan as plan_mod

    _patch_second_record(monkeypatch, _claimed_m(plan_mod.second_record, every=True))
    nm = _search_47079(seed47079)
    best = max(c["separation"] for c in nm.together["checked"])
    assert nm.recommended.separation_refit < best <= (1 + plan_mod.SHORT_PLAN_GAIN) * nm.recommended.separation_refit
    assert not nm.also and not nm.separates and nm.together["recommended"] is False
    assert f"by more than {plan_mod.SHORT_PLAN_GAIN:.0%}, so not recommended" in nm.message


def test_a_short_pair_of_records_not_better_than_the_first_alone_is_not_recommended(seed47079, monkeypatch):
    """As above, but the refits of the two records together are made to give no more than the first
    record's own λ (the second record adds nothing): not better than the best single record, so not
    recommended — the single record stands, short, and the message says the pairs of records checked
    fall short and are not recommended."""
    from physmodel.estimation import next_measurement_design as design
    from physmodel.estimation import next_measurement_plan as plan_mod

    _patch_second_record(monkeypatch, _claimed_m(plan_mod.second_record, every=True))
    real = design.refit_lambda
    monkeypatch.setattr(design, "refit_lambda",        # two records (a list): nothing; one record: the real refit
                        lambda d, r, *a, **k: 0.0 if isinstance(r, list) else real(d, r, *a, **k))
    nm = _search_47079(seed47079)
    tg = nm.together
    assert not nm.separates and nm.also == [] and "and, with it," not in nm.message
    assert tg["recommended"] is False and tg["separation_linearised"] == 1e6 and not tg["linearised_only"]
    assert tg["separation"] <= nm.recommended.separation_refit and len(tg["checked"]) == 3
    assert "Two records were checked too (3 second records" in nm.message and "not recommended" in nm.message
    assert "nor better than the first alone" in nm.message
    for k, v in tg["short"].items():
        assert f"{k} reaches only {v['separation']:.3g} (short of {nm.target:.3g} by {v['short_by']:.3g})" in nm.message
    assert nm.to_dict()["together"]["recommended"] is False
