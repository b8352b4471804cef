"""The records of a next-measurement search and the merging of a new record with the diagnosed one.

:class:`CandidateMeasurement` (one experiment and the separation it is expected to give) and
:class:`NextMeasurement` (what :func:`~physmodel.estimation.next_measurement.next_measurement`
found), :func:`json_ready` (the reports' one JSON sanitiser) and :func:`merge_records` (the
diagnosed record and the new measurement as one sweep, to be diagnosed jointly).  The search itself
is :mod:`~physmodel.estimation.next_measurement`; the design algebra it uses (competing models,
noise at new lines, the T-criterion, the nonlinear check) is
:mod:`~physmodel.estimation.next_measurement_design`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..data.sweep import FrequencySweep
from ..errors import IPMCError


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
        Evaluated together with the diagnosed record: either merged with it (the same quantity:
        merge and diagnose both) or, when ``added_quantity``, one more quantity diagnosed jointly
        with the record's quantities.  False: a record of its own.
    duration_s : float
        Measurement time estimate: temperatures × :data:`~physmodel.estimation.next_measurement.PERIODS` / lowest frequency, plus
        :data:`~physmodel.estimation.next_measurement.BATH_SETTLE_S` per temperature the record was not measured at. [s]
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
    added_quantity : bool
        A quantity the diagnosed record did not hold, diagnosed jointly with the record's quantities
        (``joint`` is then True too).
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
    #: A quantity the diagnosed record did not hold, diagnosed jointly with its quantities (then
    #: ``joint`` is True too; ``joint and not added_quantity``: merged with the record).
    added_quantity: bool = field(default=False, repr=False)

    def describe(self) -> str:
        """The experiment in words."""
        T = ", ".join(f"{t:g}" for t in self.temperatures_c)
        merged = self.joint and not self.added_quantity
        return (f"{self.quantity} at {T} °C, {self.band_hz[0]:.3g}–{self.band_hz[1]:.3g} Hz "
                f"({self.n_lines} lines"
                + (", none inside the record's band at its temperatures" if merged else "")
                + f"), drive ×{self.level:g}"
                + (" (merged with the diagnosed record)" if merged else " (diagnosed jointly with the record's "
                   "quantities)" if self.joint else " (a record of its own)"))

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"quantity": self.quantity, "band_hz": list(self.band_hz), "temperatures_c": list(self.temperatures_c),
                "level": self.level, "n_lines": self.n_lines, "frequencies_hz": self.frequencies_hz.tolist(),
                "lines": {"temperature_c": self.line_temperatures_c.tolist(),
                          "frequency_hz": self.line_frequencies_hz.tolist()},
                "separation": self.separation, "separation_by_pair": self.separation_by_pair, "joint": self.joint,
                "added_quantity": self.added_quantity, "duration_s": self.duration_s, "power": self.power,
                "separation_refit": self.separation_refit,
                "refit_by_pair": self.refit_by_pair,
                "description": self.describe()}


@dataclass
class NextMeasurement:
    """What :func:`~physmodel.estimation.next_measurement.next_measurement` found.

    Attributes
    ----------
    models : list of tuple
        The competing models (effect names each); the first is the diagnosis's best.
    recommended : CandidateMeasurement or None
        The experiment to run (None when there is nothing to separate).
    separates : bool
        The recommendation (with ``also``, both records) is expected to reach ``target`` (and its
        refit check agrees).
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
        ``"A vs B"`` pairs left out of the criterion: no experiment within the limits separates them
        linearised (the same response in another form), or — listed also in
        ``inseparable_as_fitted`` — the refits of every checked experiment expected to separate them
        did not.
    best_by_quantity : dict
        Quantity → the largest linearised separation any experiment of it reaches. [-]
    inseparable_as_fitted : list of str
        The pairs of ``inseparable`` dropped by the refits: not separated as the models were fitted
        (one fit a nested form of the other); the truth's own form may still separate.
    premise : str
        When the recommended experiment steps the bath away from the record's temperatures: that
        its separation relies on the diagnosed model's temperature laws (named), and that a misfit
        at the new temperature may mean the laws, not the effect, are wrong ("" otherwise; also
        said in ``message``).
    forms : dict
        Empty unless a pair came out inseparable as fitted: then the search was run again with the
        other forms its models' fits may take
        (:mod:`~physmodel.estimation.next_measurement_forms`) — ``found``: per model, each form
        (effect values, ½χ² on the record, 2Δcost to the best and the χ² threshold, its role);
        ``contests``: per pair and direction (``"A true"``), each truth form searched or left to
        parsimony (nested in the rival); ``note``: the sentence of ``message`` that says which forms
        the separation assumes.  When no other form fits: ``tried``, ``found`` {} and ``note``.
    acts_on : dict
        Where the search assumed an effect acts among the quantities (effect → quantities; on
        the others it was held at its off values in the predictions of a new record): the
        caller's ``acts_on`` for a one-quantity record, a joint diagnosis's own otherwise; empty
        when every effect acts on every quantity it applies to.  ``message`` ends by saying it.
    also : list of CandidateMeasurement
        A second experiment to run with ``recommended`` when no single one is expected to separate
        every pair and the two together are, linearised and after refits of the rivals to both
        records together (:mod:`~physmodel.estimation.next_measurement_plan`) — or, short of the
        target after the refits, when the two reach more than the first alone (``separates``
        False; ``together["short"]`` and the message say the shortfall); empty otherwise.
        ``separates`` then refers to the two records together.
    together : dict
        With ``also``: ``separation`` (λ of the records together after the refits, the least over the
        pairs; the linearised one when ``check_refit`` is 0), ``separation_linearised``,
        ``separation_by_pair`` (linearised, per direction), ``refit_by_pair`` (after the refits, the
        least over the directions; a pair the first record's refits already separate keeps that
        value, a lower bound, and is not refitted again), ``linearised_only`` (True: not checked by refits) and ``refits``
        (their ``fits``, ``starts`` and ``evaluations``), ``recommended`` True, ``short`` (``"A vs
        B"`` → ``{"separation": λ after the refits, "short_by": target − λ}`` of the pairs below the
        target; empty when none), ``checked`` (each pair of records checked by refits, in the order
        tried: ``second``, ``quantity``, ``separation_linearised``, ``separation``,
        ``refit_by_pair``), ``refits_total`` (the refits' cost over them) and ``first_for`` (None
        when the plans start from the best single record; else the pair whose own best record the
        plans start from — ``recommended`` when a plan is, the best single record stays so when
        none is — searched because the greedy plan from the best single record fell short of the
        target: ``greedy`` its λ with the best single record's refit shortfall taken off,
        ``greedy_linearised`` without, ``first`` the record's description).  The plans' linearised values have the first record's refit
        shortfall taken off each pair (none for a pair's own best first record: its refits, if it was
        among the records checked alone, are not used).  A plan short after the refits but above the
        best single record's own λ by more than ``SHORT_PLAN_GAIN``: these keys, ``recommended``
        True, ``separates`` False.
        When two records reached the target linearised but every one checked falls short after the
        refits and none is above the first alone: the best checked's keys with ``recommended``
        False, ``also`` empty and the message saying which pair falls short and by how much.  Empty
        otherwise.
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
    inseparable_as_fitted: list = field(default_factory=list)
    premise: str = ""
    forms: dict = field(default_factory=dict)
    acts_on: dict = field(default_factory=dict)
    also: list = field(default_factory=list)
    together: dict = field(default_factory=dict)

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
                      "inseparable": list(self.inseparable), "best_by_quantity": self.best_by_quantity,
                      "inseparable_as_fitted": list(self.inseparable_as_fitted), "premise": self.premise,
                      "forms": self.forms, "acts_on": self.acts_on,
                      "also": [r.to_dict() for r in self.also], "together": self.together})



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



__all__ = ["CandidateMeasurement", "NextMeasurement", "json_ready", "merge_records"]
