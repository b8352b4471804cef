"""The ``[next_measurement]`` step: a virtual-lab record leaves two effects ambiguous, the
diagnosis recommends the measurement that separates them, the virtual lab takes it, and the two
records diagnosed together name the hidden effect (issue 27, item 3).

The hidden effect is an instrument element between the strip and the DAQ (a response-level
library effect written with the Laplace variable only: amplifier poles, a delay, a laser lag, AC
coupling; or with the strip's impedance as its source: ``transimpedance``, seed 000's op-amp
stages, which then move with the bath as Z does — give ``temperature_limits_c`` wider than the
record's to let the search step the bath), put into the transfer function the virtual lab
realises and simulates, so both records
are time-domain experiments measured like a DAQ (:mod:`scenarios.virtual_lab`): the first with the
table's design (``temperatures_c``, ``fmin_hz`` … ``rms``, ``output_noise_rms``, ``noise_seed``),
the second with the same design moved to the recommended band, temperatures and drive level, and
its own noise stream (:func:`record_noise_seed`).  The virtual lab records the model's main quantity only (actuator M, sensor S), so the
search is restricted to it; the two records are then of the same quantity and are merged
(:func:`physmodel.estimation.next_measurement.merge_records`, lines the first record already holds
left out of the second) and diagnosed jointly.  When no single record is expected to separate
every competing pair and the search recommends two (``NextMeasurement.also``: expected to
separate, or offered short as the best there is), the virtual lab takes both (each with its own
noise stream, none of the lines already held) and the three are diagnosed together; a
recommendation not expected to separate is taken all the same, its shortfall said (table, stderr,
``next_measurement.short_by``) at the lesser of its linearised and refit λ.
A diagnosis whose null draws leave fewer than 10 beyond a quantile its tests threshold at (the
400 draws of the demo's ``--quick``) says so (the "Thin null tail" note of
:func:`physmodel.estimation.nullstats.thin_tail_note`): under the report's table, in metrics.json
(``next_measurement.thin_null_tail``, ``next_measurement.null_tail_draws``) and on stderr.

Noise streams (since 2026-11-27): the first record's is ``noise_seed``'s; the recommended record ``k``
(1, and 2 for a second one) draws from the ``SeedSequence`` entropy ``[next_noise_seed, k, 0, 0, 0]``
(``next_noise_seed`` defaults to ``noise_seed``), which no other record, and no integer seed a user
may give anywhere (``ipmc simulate --seed``, a spec's ``[noise] seed``), produces — see
:func:`record_noise_seed` for why.  Before, the recommended records used the integers ``next_noise_seed``
(default ``noise_seed + 1``) and ``next_noise_seed + 1`` — another run's ``noise_seed``, or this
run's own first record's when ``next_noise_seed = noise_seed - 1``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .context import RunContext, md_table
from .spec import ScenarioError

#: Keys of the first record's design (virtual-lab [sweep] keys) and of its DAQ noise.
DESIGN = ("temperatures_c", "fmin_hz", "fmax_hz", "points", "fs_hz", "period_s", "periods", "transient_periods",
          "rms", "oversample")


class InstrumentModel:
    """A physics model with a hidden instrument element on its main quantity: ``evaluate`` (what the
    virtual lab realises) multiplies M or S by the library effect's factor at the Laplace points;
    everything else is the wrapped model's.  An element loaded by the strip (``transimpedance``:
    op-amp stages with the strip's impedance Z as source) gets the wrapped model's Z at the same
    points and temperatures, so it moves with the bath as the strip does."""

    def __init__(self, model, effects: dict):
        from types import SimpleNamespace

        from physmodel.effects import LIBRARY

        self._model, self._effects = model, {}
        for name, vals in effects.items():
            e = LIBRARY.get(name)
            if e is None or e.level != "response":
                raise ScenarioError(f"[next_measurement] effects.{name}: the virtual lab can hide an instrument "
                                    "element only (a response-level library effect, e.g. amplifier_bandwidth)")
            full = {**e.off, **vals}
            needs_z = False
            try:       # the factor must be a function of s alone (no state of the strip) ...
                e.apply("S", SimpleNamespace(s=np.array([1j])), full)
            except AttributeError:
                try:   # ... or of s and the strip's impedance Z (a stage the strip drives)
                    e.apply("S", SimpleNamespace(s=np.array([1j]), base={"Z": np.array([1.0 + 0j])}), full)
                    needs_z = True
                except (AttributeError, KeyError):
                    raise ScenarioError(f"[next_measurement] effects.{name}: its factor needs the strip's state "
                                        "beyond its impedance; hide an instrument element (amplifier_bandwidth, "
                                        "time_delay, transimpedance, ...)") from None
            self._effects[name] = (e, full, needs_z)

    def __getattr__(self, name):
        return getattr(self._model, name)

    def evaluate(self, s, temperature_c, quantities=None, **kw):
        """The wrapped model's quantities with the hidden factor on M (actuator) or S (sensor)."""
        from types import SimpleNamespace

        out = dict(self._model.evaluate(s, temperature_c, quantities=quantities, **kw))
        q = "M" if self._model.kind == "actuator" else "S"
        if q in out:
            ctx = SimpleNamespace(s=np.asarray(s, dtype=complex))
            if any(nz for _, _, nz in self._effects.values()):
                ctx.base = {"Z": self._model.evaluate(s, temperature_c, quantities=("Z",))["Z"]}
            for e, v, _ in self._effects.values():
                out[q] = out[q] * e.apply(q, ctx, v)
        return out


def _diagnose(ctx, data, cfg):
    from physmodel.estimation.discrepancy import diagnose

    m = ctx.spec.section("model")
    kw = {k: cfg[k] for k in ("null_draws", "null_refits", "alpha", "seed", "laws", "baseline_starts") if k in cfg}
    if "free" in cfg:
        kw["free"] = tuple(cfg["free"])
    if "candidates" in cfg:
        kw["candidates"] = list(cfg["candidates"])
    if m["kind"] == "sensor":
        kw["kernel"] = m.get("kernel", "boundary_charge")
    return diagnose(data, ctx.base_params, kind=m["kind"], quantity="M" if m["kind"] == "actuator" else "S", **kw)


def _new_lines(record, new):
    """``new`` without the lines ``record`` already holds (same temperature and frequency)."""
    from dataclasses import replace

    have = {(float(t), float(f)) for t, f in zip(record.temperature_c, record.frequency_hz)}
    keep = np.array([(float(t), float(f)) not in have for t, f in zip(new.temperature_c, new.frequency_hz)])
    if keep.all():
        return new
    if not keep.any():
        raise ScenarioError("the recommended measurement holds only lines the first record already has")
    pick = lambda a: None if a is None else np.asarray(a)[keep]  # noqa: E731
    return replace(new, temperature_c=new.temperature_c[keep], frequency_hz=new.frequency_hz[keep],
                   response=new.response[keep], magnitude_std_db=pick(new.magnitude_std_db),
                   phase_std_deg=pick(new.phase_std_deg))


def _design(sweep_cfg: dict, r) -> dict:
    """The first record's virtual-lab design moved to recommended experiment ``r``'s band,
    temperatures and drive level."""
    sw2 = dict(sweep_cfg, fmin_hz=float(r.band_hz[0]), fmax_hz=float(r.band_hz[1]),
               points=int(r.frequencies_hz.size), temperatures_c=[float(t) for t in r.temperatures_c])
    for k in ("rms", "amplitude"):
        sw2[k] = float(sweep_cfg.get(k, 1.0)) * r.level
    if "period_s" in sw2:            # the design's period: whole periods of the new lowest line
        sw2["period_s"] = max(float(sweep_cfg["period_s"]), 1.0 / r.band_hz[0])
    return sw2


#: Seeds are one 32-bit word each, so the words of a recommended record's key are always
#: ``[next_noise_seed, k, 0, 0, 0]`` (one layout, one ``(next_noise_seed, k)`` per key).
SEED_LIMIT = 2**32

#: Zero words after ``[next_noise_seed, k]`` in a recommended record's key: five words in all.
KEY_PADDING = 3


def record_noise_seed(cfg: dict, k: int, where: str = "") -> int | list[int]:
    """The noise seed of record ``k`` of the step (0 the first record, 1 the recommended record, 2 a
    second one): ``noise_seed`` for the first (a plain integer, its stream unchanged), the
    ``SeedSequence`` entropy ``[next_noise_seed, k, 0, 0, 0]`` for the others (``next_noise_seed``
    defaults to ``noise_seed``).

    Why five words ending in zeros: numpy turns an integer seed into its little-endian 32-bit words
    with no trailing zero word (0 → ``[0]``, 2**32 → ``[0, 1]``) and pads an entropy of fewer than
    four words with zeros, so the integer ``2**32·k + s`` *is* ``[s, k]`` (and ``[s, k, 0]``,
    ``[s, k, 0, 0]``); a spawn key is appended after the padding, so ``spawn_key=(k,)`` of ``s`` is the
    integer ``s + 2**128·k``.  Past four words every word is mixed in, a trailing zero too, and
    an integer of five or more words has a non-zero top word: no integer gives a list of five or more
    words ending in 0.  Checked by experiment (numpy 2.4.6, PCG64 states from ``default_rng``): the
    integers ``2**32·k + s``, ``2**64·k + s``, ``2**128 + 2**32·k + s``, 200 random ones in
    ``[2**128, 2**160)`` and 0-19999 against ``[s, k, 0, 0, 0]`` for s = 0, 4, 5, 6, 2**32 − 1 and
    k = 1, 2: none gives the same state, while ``2**32·k + s`` gives ``[s, k]``'s
    (tests/scenarios/test_next_measurement_noise_streams.py).  The keys of two records differ in ``k``, and
    of two runs in ``next_noise_seed``.  A seed outside ``[0, 2**32)`` raises :class:`ScenarioError`
    naming the key."""
    for key in ("noise_seed", "next_noise_seed"):
        v = cfg.get(key)
        if v is not None and not (isinstance(v, int) and not isinstance(v, bool) and 0 <= v < SEED_LIMIT):
            raise ScenarioError(f"{where}[next_measurement] {key} = {v!r}: expected an integer in [0, 2**32)")
    if k == 0:
        return int(cfg["noise_seed"])
    return [int(cfg.get("next_noise_seed", cfg["noise_seed"])), int(k), *[0] * KEY_PADDING]


def _thin_tails(ctx: RunContext, diagnoses: list) -> str:
    """The diagnoses' thin-null-tail notes (a quantile of the null draws with fewer than
    ``nullstats.MIN_TAIL_DRAWS`` draws beyond it, e.g. the 400 draws of ``--quick``): said on stderr
    (whether or not quiet, as ``ipmc diagnose`` does), as metrics ``next_measurement.thin_null_tail``
    (1 when any diagnosis has one) and ``next_measurement.null_tail_draws`` (the fewest draws beyond
    any quantile of any diagnosis) in metrics.json, and returned for report.md ("" when none)."""
    import sys

    ctx.metric("next_measurement.null_tail_draws", min(t["draws"] for d in diagnoses for t in d.null["tails"].values()))
    notes: dict = {}
    for i, d in enumerate(diagnoses, 1):
        if d.null.get("thin_tail"):
            notes.setdefault(d.null["thin_tail"], []).append(str(i))
    ctx.metric("next_measurement.thin_null_tail", bool(notes))
    text = " ".join(f"Diagnosis {' and '.join(ds)}: {note}" for note, ds in notes.items())
    if text:
        print(f"{ctx.spec.name}: {text}", file=sys.stderr)
    return text


def step_next_measurement(ctx: RunContext):
    """Ambiguous on one virtual-lab record → the recommended measurement → named on both.  A
    recommendation not expected to separate (one record, or two short of the target after the
    refits — ``also`` with ``separates`` False) is measured all the same, the best there is, and
    its shortfall said: in the table, on stderr and as the metric ``next_measurement.short_by``."""
    import sys

    from physmodel.estimation.next_measurement import merge_records, shortfall

    from . import plots
    from .virtual_lab import from_config

    cfg = ctx.spec.section("next_measurement")
    m = ctx.spec.section("model")
    where = f"{ctx.spec.path}: "
    effects = cfg.get("effects", {})
    if not effects:
        raise ScenarioError(f"{where}[next_measurement] effects: give the hidden instrument element")
    missing = [k for k in ("temperatures_c", "fs_hz", "output_noise_rms", "noise_seed") if k not in cfg]
    if missing:
        raise ScenarioError(f"{where}[next_measurement] {missing[0]}: required (the first record's design)")
    truth = InstrumentModel(ctx.model, effects)
    sweep_cfg = {"source": "virtual_lab", "excitation": "multisine",
                 **{k: cfg[k] for k in DESIGN if k in cfg}}
    noise_cfg = {"kind": "time", "output_noise_rms": cfg["output_noise_rms"], "seed": record_noise_seed(cfg, 0, where)}
    lab1 = from_config(truth, sweep_cfg, noise_cfg, where=where)
    rec1 = lab1.sweep
    ctx.file(rec1.to_csv(ctx.out / "next_measurement" / "record1.csv"))
    d1 = _diagnose(ctx, rec1, cfg)
    q = "M" if m["kind"] == "actuator" else "S"
    T = np.asarray(sweep_cfg["temperatures_c"], float)
    nm_kw = {"quantities": [q], "temperature_limits_c": tuple(cfg.get("temperature_limits_c", (T.min(), T.max())))}
    for k in ("band_limits_hz", "levels", "power"):
        if k in cfg:
            nm_kw[k] = tuple(cfg[k]) if isinstance(cfg[k], list) else cfg[k]
    nm = d1.recommend_next_measurement(**nm_kw) if d1.verdict in ("ambiguous", "at_bound") else None
    folder = d1.write_report(ctx.out / "next_measurement" / "diagnosis1")
    plots.diagnosis_figures(d1, folder)
    hidden = sorted(effects)
    ctx.metric("next_measurement.first_ambiguous", d1.verdict in ("ambiguous", "at_bound"))
    ctx.metric("next_measurement.first_n_named", len(d1.named))
    rows = [("1: " + f"{rec1.frequency_hz.min():.3g}–{rec1.frequency_hz.max():.3g} Hz", d1.verdict,
             ", ".join(d1.named) or "–", "–")]
    d2 = None
    if nm is not None and nm.recommended is not None:
        r = nm.recommended
        # a record not expected to separate is said at the lesser of its linearised and refit λ, as the
        # library's message says it (review: 8.8 linearised, 264 after the refits read "264, short of 42")
        ctx.metric("next_measurement.expected_separation", nm.together["separation"] if nm.also else
                   shortfall(r)[0] if not nm.separates else
                   r.separation_refit if np.isfinite(r.separation_refit) else r.separation)
        ctx.metric("next_measurement.target", nm.target)
        ctx.metric("next_measurement.expected_to_separate", nm.separates)
        fs = float(sweep_cfg["fs_hz"])
        both = rec1
        for rj in [r] + list(nm.also):      # every record checked before any is written (no half-written folder)
            if rj.band_hz[1] >= 0.4 * fs:
                raise ScenarioError(f"{where}the recommended band reaches {rj.band_hz[1]:g} Hz, beyond the virtual "
                                    f"lab's fs_hz = {fs:g} (set [next_measurement] band_limits_hz below 0.4·fs_hz)")
        for j, rj in enumerate([r] + list(nm.also)):    # a second record when no single one separates every pair
            nz2 = dict(noise_cfg, seed=record_noise_seed(cfg, j + 1, where))
            rec2 = _new_lines(both, from_config(truth, _design(sweep_cfg, rj), nz2, where=where).sweep)
            ctx.file(rec2.to_csv(ctx.out / "next_measurement" / f"record{j + 2}.csv"))
            both = merge_records(both, rec2)
        d2 = _diagnose(ctx, both, cfg)
        folder2 = d2.write_report(ctx.out / "next_measurement" / "diagnosis2")
        plots.diagnosis_figures(d2, folder2)
        what = f"adds {r.describe()}" + "".join(f" and {x.describe()}" for x in nm.also)
        lam = ctx.metrics["next_measurement.expected_separation"]
        ctx.metric("next_measurement.short_by", 0.0 if nm.separates else max(float(nm.target - lam), 0.0))
        short = "" if nm.separates else f" (short of {nm.target:.3g} needed: not expected to separate)"
        if short:        # the records were taken all the same (the best there is): said, not only in the report
            print(f"{ctx.spec.name}: the recommended record{'s' if nm.also else ''}, expected λ {lam:.3g}{short}",
                  file=sys.stderr)
        rows.append((f"1 + {' + '.join(str(j + 2) for j in range(1 + len(nm.also)))}: {what}", d2.verdict,
                     ", ".join(d2.named) or "–", f"{lam:.3g}{short}"))
    for p in sorted((ctx.out / "next_measurement").rglob("*")):
        if p.is_file() and not p.name.startswith(".") and p.suffix != ".csv":
            ctx.file(Path(p))
    ctx.metric("next_measurement.second_named_truth", d2 is not None and d2.verdict == "named" and sorted(d2.named)
               == hidden)
    ctx.metric("next_measurement.second_n_named", len(d2.named) if d2 is not None else 0)
    thin = _thin_tails(ctx, [d for d in (d1, d2) if d is not None])
    ctx.section("The next measurement",
                f"Hidden in the virtual lab's physics: {effects}. The first record (the table's design) is "
                f"diagnosed: **{d1.verdict}** ({', '.join(d1.named) or 'nothing named'}).", "",
                (nm.message if nm is not None else "No recommendation: the first verdict leaves no competing models."),
                "", md_table(["records diagnosed", "verdict", "named", "expected λ of the added record"], rows), "",
                *([thin, ""] if thin else []), "Diagnoses: `next_measurement/diagnosis1/summary.md` (with the recommendation) and "
                "`next_measurement/diagnosis2/summary.md` (both records).")


#: [next_measurement] (scenarios.spec checks the types): the hidden element, the first record's
#: design and noise, the diagnosis's settings and the search's limits.
SCHEMA_KEYS = ("effects", *DESIGN, "output_noise_rms", "noise_seed", "next_noise_seed", "free", "candidates",
               "null_draws", "null_refits", "alpha", "seed", "laws", "baseline_starts", "band_limits_hz",
               "temperature_limits_c", "levels", "power")

__all__ = ["DESIGN", "InstrumentModel", "KEY_PADDING", "SCHEMA_KEYS", "record_noise_seed", "step_next_measurement"]
