"""A model as a sweep: its response on data's lines or on a grid, with the uncertainty its parameters
carry (:func:`predict_sweep`); what :func:`scenarios.comparison.compare` and
:func:`scenarios.plots.plot_bode` draw models with.

A model is any of

- a :class:`physmodel.ModelFile` (``model.json`` of ``ipmc calibrate``/``ipmc diagnose``, or a named
  parameter set): the physics with its effects; its ``estimates`` (95 % intervals) give the band;
- a :class:`surrogate.RationalModel` (what ``ipmc fit`` writes): its parameter covariance gives the band;
- anything with the model interface (:mod:`physmodel.protocol`: ``kind`` and ``response``), no band.

The band is the delta method in the fit's own coordinates: each parameter with an interval is
moved by ±1σ (log10 of the value for a parameter whose interval is symmetric in the logarithm,
the value otherwise; σ = the 95 % half-width / 1.96), the complex logarithm of the response
differenced (one vectorised call for all moved parameter sets of the physics), and
var ln|H| = Jᵣ C Jᵣᵀ, var ∠H = Jᵢ C Jᵢᵀ with C the parameters' covariance — their correlation
from ``calibration.json`` beside the model file when it is there, else none (then said in the
notes).  It returns a :class:`~physmodel.data.sweep.FrequencySweep` whose per-line σ are the
model's, so a model's band draws like a measurement's (:func:`scenarios.plots.plot_bode`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from statistics import NormalDist

import numpy as np

from physmodel.data.sweep import FrequencySweep
from physmodel.errors import IPMCError

__all__ = ["Z95", "load_any_model", "model_name", "predict_sweep"]

#: Half-width of a 95 % normal interval in standard deviations.
Z95 = NormalDist().inv_cdf(0.975)
#: Estimate statuses whose interval is not a valid one (held at the start value, or at a bound).
_NO_INTERVAL = ("held", "hold refused")


# ----------------------------------------------------------------------------- models
def load_any_model(path):
    """The model in a file: a surrogate (``ipmc fit``'s JSON, schema ``ipmc.surrogate.rational_model``)
    as a :class:`surrogate.RationalModel`, anything else through :func:`physmodel.load_model`
    (a model file, a parameter file or a named parameter set) as a :class:`physmodel.ModelFile`.

    Parameters
    ----------
    path : str or Path
        The file (or a parameter set's name).
    """
    from physmodel.model_file import load_model
    from surrogate.models import SCHEMA, load

    text = str(path)
    p = Path(text)
    if p.is_file() and p.suffix.lower() == ".json":
        try:
            head = json.loads(p.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise IPMCError(f"model file {text!r} is not valid JSON ({exc})") from None
        if isinstance(head, dict) and head.get("schema") == SCHEMA:
            return load(p)
    return load_model(text)


def model_name(model) -> str:
    """A short name of a model for reports: its parameter set and kind, or the surrogate's structure.

    Parameters
    ----------
    model : ModelFile, RationalModel or FrequencyModel
        The model.
    """
    if hasattr(model, "parameters") and hasattr(model, "estimates"):
        return f"{model.name} ({model.kind})"
    if getattr(model, "kind", None) == "rational":
        return repr(model)
    params = getattr(model, "params", None)
    first = params[0] if isinstance(params, (list, tuple)) and params else params
    return f"{getattr(first, 'name', type(model).__name__)} ({getattr(model, 'kind', '?')})"


def _rows(frequency_hz, temperatures_c, units) -> FrequencySweep:
    f = np.unique(np.asarray(frequency_hz, float).ravel())
    T = np.unique(np.asarray(temperatures_c, float).ravel())
    if f.size == 0 or T.size == 0:
        raise IPMCError("predict_sweep: give at least one frequency and one temperature")
    return FrequencySweep(np.repeat(T, f.size), np.tile(f, T.size), np.ones(T.size * f.size, complex), None, None,
                          *units)


def _default_units(model, quantity):
    from physmodel.data.units import QUANTITY_UNITS

    kind = model.kind
    if kind == "rational":
        lab = model.labels
        return (lab.get("input_name") or "input", lab.get("input_unit") or "1",
                lab.get("output_name") or "output", lab.get("output_unit") or "1")
    q = quantity or getattr(model, "quantity", None) or ("M" if kind == "actuator" else "S")
    if (kind, q) not in QUANTITY_UNITS:
        raise IPMCError(f"{kind} quantity {q!r} has no display units; expected one of "
                        f"{[k[1] for k in QUANTITY_UNITS if k[0] == kind]}")
    return QUANTITY_UNITS[(kind, q)]


def _default_temperatures(model):
    prov = getattr(model, "provenance", None)
    if prov is not None and prov.temperatures_c:
        return list(prov.temperatures_c)
    rng = getattr(model, "temperature_range_c", None)
    if rng is not None:
        return [float(np.mean(rng))]
    raise IPMCError("predict_sweep: the model states no temperatures; pass temperatures_c (or like=a sweep)")


def _rational_units_factor(model, rows: FrequencySweep) -> float:
    """Factor from the surrogate's units to the rows' units (1 when the surrogate has no unit labels)."""
    from physmodel.data.units import UNITS, unit_scale

    lab = model.labels
    u_in, u_out = lab.get("input_unit") or "", lab.get("output_unit") or ""
    if not u_in or not u_out or (u_in, u_out) == (rows.input_unit, rows.output_unit):
        return 1.0
    if u_in not in UNITS or u_out not in UNITS or UNITS[u_in][0] != UNITS[rows.input_unit][0] or \
            UNITS[u_out][0] != UNITS[rows.output_unit][0]:
        raise IPMCError(f"the surrogate is in {u_out}/{u_in}, the data in {rows.output_unit}/{rows.input_unit}: "
                        "not the same quantity")
    return (unit_scale(u_out) / unit_scale(rows.output_unit)) / (unit_scale(u_in) / unit_scale(rows.input_unit))


def _rational_response(model, rows: FrequencySweep, params=None) -> np.ndarray:
    """The surrogate on the rows (in their units); ``params`` replaces its parameter vector."""
    from surrogate.models import RationalModel

    m = model if params is None else RationalModel(model.structure, params, model.scaling, model.temperature_range_c,
                                                   labels=model.labels)
    fu, fi = np.unique(rows.frequency_hz, return_inverse=True)
    Tu, ti = np.unique(rows.temperature_c, return_inverse=True)
    try:
        R = m.response(fu, Tu if model.is_scheduled else None)
    except ValueError as exc:
        raise IPMCError(f"surrogate: {exc}") from None
    return R[ti if model.is_scheduled else 0, fi] * _rational_units_factor(model, rows)


def _physics_predictor(model, rows: FrequencySweep, quantity):
    """``many(list of {name: value}) -> (n_sets, N)`` on the rows for a model file; the plain
    model's response for a model object."""
    from physmodel.effects import EffectModel

    if hasattr(model, "estimates"):     # a ModelFile: the physics with its effects, moved by name
        q = quantity or model.quantity
        m = EffectModel(model.parameters, model.kind, model.effects, kernel=model.kernel)
        return m.predictor(rows, q).many
    from physmodel.data.sweep import sweep_layout

    lay = sweep_layout(rows, model.kind)

    def many(values_list):
        if any(values_list):
            raise IPMCError("this model object cannot be moved by parameter name; use its model file")
        R = np.asarray(model.response(lay.frequencies_hz, lay.temperatures_c))
        return np.repeat((R[lay.t_index, lay.f_index] * lay.factor)[None, :], len(values_list), axis=0)

    return many


def _estimate_coordinates(est) -> tuple[bool, float, float, float] | None:
    """(log, sign, z, σ_z) of a model file's estimate, or None without a valid interval."""
    v, ci = est.get("value"), est.get("ci95") or [None, None]
    status = str(est.get("status", ""))
    if v is None or None in ci or any(status.startswith(s) for s in _NO_INTERVAL):
        return None
    lo, hi = float(min(ci)), float(max(ci))
    v = float(v)
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return None
    sign = 1.0 if v > 0 else -1.0
    lin_asym = abs((hi - v) - (v - lo)) / (hi - lo)
    log_ok = v != 0 and lo * sign > 0 and hi * sign > 0
    if log_ok:
        a, b, c = (math.log10(x * sign) for x in (lo, v, hi))
        lo_z, hi_z = min(a, c), max(a, c)
        if abs((hi_z - b) - (b - lo_z)) / (hi_z - lo_z) <= lin_asym:
            return True, sign, b, (hi_z - lo_z) / (2 * Z95)
    return False, 1.0, v, (hi - lo) / (2 * Z95)


def _correlation_beside(model, names) -> np.ndarray | None:
    """The correlation of ``names`` from ``calibration.json`` beside the model file, when that file
    records the same fitted values (the same calibration); else None."""
    if not getattr(model, "path", None):
        return None
    cal = Path(model.path).parent / "calibration.json"
    if not cal.is_file():
        return None
    try:
        d = json.loads(cal.read_text(encoding="utf-8"))
        fitted = {p["name"]: p["value"] for p in d["parameters"]}
        cn, M = d["correlation"]["names"], np.array(d["correlation"]["matrix"], dtype=float)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    values = {e["name"]: e.get("value") for e in model.estimates}
    if any(n not in cn or fitted.get(n) is None or values.get(n) is None or
           not math.isclose(float(fitted[n]), float(values[n]), rel_tol=1e-9) for n in names):
        return None
    return _select(cn, M, names)


def _select(all_names, matrix, names) -> np.ndarray:
    """The rows and columns of ``names`` in a correlation over ``all_names`` (NaN of held
    parameters as 0, unit diagonal)."""
    missing = [n for n in names if n not in list(all_names)]
    if missing:
        raise IPMCError(f"correlation: no row for {missing}; it has {list(all_names)}")
    idx = [list(all_names).index(n) for n in names]
    R = np.nan_to_num(np.asarray(matrix, float)[np.ix_(idx, idx)], nan=0.0)
    np.fill_diagonal(R, 1.0)
    return R


def _band_model_file(model, rows, quantity, correlation, notes) -> tuple[np.ndarray, np.ndarray] | None:
    many = _physics_predictor(model, rows, quantity)
    coords = [(e["name"], c) for e in model.estimates if (c := _estimate_coordinates(e)) is not None]
    coords = [(n, c) for n, c in coords if c[3] > 0]
    skipped = [e.get("name") for e in model.estimates if e.get("name") not in {n for n, _ in coords}]
    if not coords:
        notes.append("no parameter with a 95 % interval in the model file: no band")
        return None
    names = [n for n, _ in coords]

    def value(c, z):
        log, sign, _, _ = c
        return sign * 10.0 ** z if log else z

    def steps(n, c):
        """z ± σ_z, an effect parameter's kept within the values its model accepts (a one-sided
        difference at a bound: the interval of an estimate at 0 reaches below it)."""
        zs = [c[2] + c[3], c[2] - c[3]]
        if is_effect_parameter(n):
            e, p = n.split(".", 1)
            par = get_effect(e).parameter(p)
            for i, z in enumerate(zs):
                v = min(max(value(c, z), par.lower), par.upper)
                if not c[0]:
                    zs[i] = v
                elif v * c[1] > 0:          # log coordinates: a clipped value of the same sign
                    zs[i] = math.log10(v * c[1])
        return zs

    from physmodel.effects import get_effect
    from physmodel.parameter_paths import is_effect_parameter

    zsteps = [steps(n, c) for n, c in coords]
    rows_v: list[dict] = [{}]
    for (n, c), (zp, zm) in zip(coords, zsteps):
        rows_v += [{n: value(c, zp)}, {n: value(c, zm)}]
    R = many(rows_v)
    dz = np.array([(zp - zm) / c[3] for (_, c), (zp, zm) in zip(coords, zsteps)])   # in units of σ_z
    with np.errstate(all="ignore"):
        J = np.log(R[1::2] / R[2::2]) / np.where(dz > 0, dz, np.inf)[:, None]   # per 1σ: (p, N)
    if correlation is None:
        correlation = _correlation_beside(model, names)
        src = "their correlation from calibration.json" if correlation is not None else \
            "no correlation recorded (treated as independent: the band may be too wide or too narrow)"
    else:
        if isinstance(correlation, tuple) and len(correlation) == 2 and not np.isscalar(correlation[0]) and \
                all(isinstance(n, str) for n in correlation[0]):
            correlation = _select(correlation[0], correlation[1], names)
        correlation = np.asarray(correlation, float)
        src = "the correlation given"
    C = np.eye(len(names)) if correlation is None else correlation
    if C.shape != (len(names), len(names)):
        raise IPMCError(f"correlation must be {len(names)}x{len(names)} for {names}")
    notes.append(f"band: ±1σ of {len(names)} parameter(s) with 95 % intervals ({', '.join(names)}), {src}"
                 + (f"; without an interval (no contribution): {', '.join(map(str, skipped))}" if skipped else ""))
    if model.verdict is not None and not model.verdict.adequate:
        notes.append("the model does not fit the data it was fitted to: its intervals (and this band) are not "
                     "confidence statements")
    return _variances(J, C)


def _band_rational(model, rows, notes) -> tuple[np.ndarray, np.ndarray] | None:
    C = model.covariance
    if C is None:
        notes.append("the surrogate carries no parameter covariance: no band")
        return None
    th = np.asarray(model.params, float)
    J = np.empty((th.size, rows.response.size), complex)
    for i in range(th.size):
        step = 1e-6 * max(1.0, abs(th[i]))
        e = np.zeros_like(th)
        e[i] = step
        with np.errstate(all="ignore"):
            J[i] = np.log(_rational_response(model, rows, th + e) / _rational_response(model, rows, th - e)) / (2 * step)
    notes.append(f"band: the surrogate's parameter covariance ({th.size} parameters), delta method")
    return _variances(J, np.asarray(C, float))


def _variances(J, C) -> tuple[np.ndarray, np.ndarray]:
    """var of ln|H| and of ∠H [Np², rad²] per line from J = ∂ln H/∂θ (p, N) and cov(θ) (p, p)."""
    vr = np.einsum("in,ij,jn->n", J.real, C, J.real)
    vi = np.einsum("in,ij,jn->n", J.imag, C, J.imag)
    return np.clip(vr, 0.0, None), np.clip(vi, 0.0, None)


def predict_sweep(model, frequency_hz=None, temperatures_c=None, *, like: FrequencySweep | None = None,
                  quantity: str | None = None, uncertainty: bool = True, correlation=None) -> FrequencySweep:
    """A model's response as a sweep, with the model's own σ per line when its parameters carry
    uncertainty (see the module doc).

    Parameters
    ----------
    model : ModelFile, RationalModel or FrequencyModel
        The model (see the module doc).
    frequency_hz : array_like or None
        Frequencies [Hz]; None: ``like``'s lines (or 200 points over its band with ``temperatures_c``).
    temperatures_c : array_like or None
        Temperatures [°C]; None: ``like``'s, else the model's own (its data's, or the middle of a
        surrogate's range).
    like : FrequencySweep or None
        Data whose units the result takes (and whose lines, when no grid is given).
    quantity : str or None
        Physics quantity (M, H, I, Z, S); default the model file's, else the kind's primary one.
    uncertainty : bool
        Compute the band (σ per line); False: the nominal response only.
    correlation : array_like, (names, array_like) or None
        Correlation of a model file's parameters: (p, p) over those with an interval, in the order
        of its estimates, or ``(names, matrix)`` over any superset (e.g. ``(result.names,
        result.correlation)`` of a calibration; NaN rows of held parameters ignored); None: from
        ``calibration.json`` beside the file, else none (said in the notes).

    Returns
    -------
    FrequencySweep
        The nominal response; ``magnitude_std_db``/``phase_std_deg`` the model's 1σ [dB, deg] (None
        without a band); ``metadata["notes"]`` says where the band came from.
    """
    if like is not None and frequency_hz is None and temperatures_c is None:
        rows = like
    else:
        if frequency_hz is None:
            if like is None:
                raise IPMCError("predict_sweep: give frequency_hz (or like=a sweep)")
            frequency_hz = np.geomspace(like.frequency_hz.min(), like.frequency_hz.max(), 200)
        if temperatures_c is None:
            temperatures_c = like.temperatures() if like is not None else _default_temperatures(model)
        units = (like.input_name, like.input_unit, like.output_name, like.output_unit) if like is not None \
            else _default_units(model, quantity)
        rows = _rows(frequency_hz, temperatures_c, units)
    notes: list[str] = []
    kind = getattr(model, "kind", None)
    if kind == "rational":
        H = _rational_response(model, rows)
        band = _band_rational(model, rows, notes) if uncertainty else None
    elif kind in ("actuator", "sensor"):
        H = _physics_predictor(model, rows, quantity)([{}])[0]
        band = None
        if uncertainty and hasattr(model, "estimates"):
            band = _band_model_file(model, rows, quantity, correlation, notes)
        elif uncertainty:
            notes.append("a model object without estimates: no band (load its model file for one)")
    else:
        raise IPMCError(f"not a model: {type(model).__name__} (expected a ModelFile, a RationalModel or an object "
                        "with kind and response)")
    if not np.all(np.isfinite(H)) or np.any(H == 0):
        raise IPMCError(f"the model's response is zero or not finite at {int(np.sum(~np.isfinite(H) | (H == 0)))} line(s)")
    sm = sp = None
    if band is not None:
        sm, sp = np.sqrt(band[0]) * 20 / math.log(10), np.degrees(np.sqrt(band[1]))
    return FrequencySweep(rows.temperature_c, rows.frequency_hz, H, sm, sp, rows.input_name, rows.input_unit,
                          rows.output_name, rows.output_unit,
                          {"source": "model", "model": model_name(model), "notes": "; ".join(notes)})
