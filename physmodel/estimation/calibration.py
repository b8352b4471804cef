"""Calibration of an IPMC physics model's parameters (fields, ``omega_n``, temperature-law
parameters) to measured sweeps: the physics binding of the least-squares engine in
:mod:`physmodel.estimation.lsq` (weighted, multi-start, with intervals and identifiability).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np

from ..data.interop import as_sweep
from ..data.sweep import FrequencySweep, sweep_layout
from ..errors import IPMCError, ParameterError
from ..parameter_paths import ParameterPath, StateMap, apply_values, resolve_path, resolve_paths
from ..params import IPMCParameters
from .identifiability import Identifiability
from .lsq import CalibrationResult, FreeParameter, SensitivityProbe, fit_parameters


def default_free_parameter(base: IPMCParameters, name: str | ParameterPath) -> FreeParameter:
    """Default bounds for a bare name, or its path already resolved against ``base`` (initial = base value):

    * positive fields and ``omega_n``: [base/10, 10·base], log (``xi`` capped at 2; ``omega_n`` ×/÷ 3);
    * signed couplings ``alpha0``/``a0``: the same decade either side, log of the magnitude, sign kept;
    * ``laws.*.activation_energy``: [0, 60] kJ/mol, linear; ``laws.*.slope``: [−0.05, 0.05] /K, linear;
      ``laws.*.alpha``: [−5e-3, 5e-3] /K, linear.
    A zero or infinite base value (e.g. ``Rp_specific = inf``) needs explicit bounds.
    """
    path = name if isinstance(name, ParameterPath) else resolve_path(base, name)
    name, v = path.name, path.value
    if path.is_law:
        attr = path.attribute
        defaults = {"activation_energy": (0.0, 60e3), "slope": (-0.05, 0.05), "alpha": (-5e-3, 5e-3)}
        if attr not in defaults:
            raise ParameterError(f"no default bounds for {name!r}; give them as FreeParameter(name, lower, upper)")
        lo, hi = defaults[attr]
        return FreeParameter(name, lo, hi, "linear", min(max(v, lo), hi))
    if not math.isfinite(v) or v == 0:
        raise ParameterError(f"{name} = {v!r} in the base set: no default bounds; give them explicitly "
                             f"(e.g. '{name}:LOWER:UPPER')")
    span = 3.0 if name == "omega_n" else 10.0
    lo, hi = sorted((v / span, v * span))
    if name == "xi":
        hi = min(hi, 2.0)
        lo = min(lo, hi / 10)
    return FreeParameter(name, lo, hi, "log", v)


def physics_predictor(data: FrequencySweep, base: IPMCParameters, kind: str = "actuator",
                      quantity: str | None = None, kernel: str = "boundary_charge",
                      free: Sequence[FreeParameter] | None = None,
                      effects: Mapping[str, Mapping[str, float]] | None = None,
                      paths: Mapping[str, ParameterPath] | None = None):
    """``predict_many(list of values) -> (n_sets, N)`` in the sweep's units, plus a wide-band
    :class:`SensitivityProbe` at the median data temperature.  One model call per batch
    (sets × temperatures × union of frequencies).

    With ``free`` (bounds and initial values known), ``predict_many`` also carries
    ``predict_many.array(X) -> (n_sets, N)`` for rows of physical values of ``free`` (and the probe
    a ``predict_array``): states built as arrays by a :class:`~physmodel.parameter_paths.StateMap`,
    no parameter set per row; None when the state is not log-affine in those parameters.

    With ``effects`` ({effect: {parameter: value}}, see :mod:`physmodel.effects`) the predictions
    are those of ``EffectModel(sets, kind, effects)`` (the measurement chain fixed at those values;
    no array path).

    ``paths``: names already resolved against ``base`` (:func:`~physmodel.parameter_paths.resolve_paths`,
    e.g. by :func:`calibrate`); the free names it lacks are resolved here, once.
    """
    from ..params import STATE_FIELDS, State
    from ..protocol import physics_model

    lay = sweep_layout(data, kind, quantity)
    q, factor, fu, inv_f, Tu, inv_T = (lay.quantity, lay.factor, lay.frequencies_hz, lay.f_index,
                                       lay.temperatures_c, lay.t_index)

    paths = dict(paths or {})         # each name read once, for every set below
    paths.update(resolve_paths(base, [fp.name for fp in free or () if fp.name not in paths]))

    def model_of(values_list):
        plist = [apply_values(base, v, paths) for v in values_list]
        if effects:
            from ..effects import EffectModel

            return EffectModel(plist, kind, effects, kernel=kernel)
        return physics_model(kind, plist, kernel=kernel)

    def predict_many(values_list):
        R = model_of(values_list).frequency_response(fu, Tu, quantities=(q,))[q]
        return R[:, inv_T, inv_f] * factor

    i_probe = int(np.argmin(np.abs(Tu - np.median(data.temperature_c))))
    t_probe = float(Tu[i_probe])
    f_probe = np.logspace(math.log10(fu[0]) - 3, math.log10(fu[-1]) + 3, 121)

    def probe_many(values_list):
        return model_of(values_list).frequency_response(f_probe, [t_probe], quantities=(q,))[q][:, 0, :] * factor

    predict_many.array = probe_array = None
    smap = None if not free or effects else StateMap.build(base, [paths[fp.name] for fp in free],
                                                           [fp.lower for fp in free], [fp.upper for fp in free],
                                                           [paths[fp.name].value if fp.initial is None else fp.initial
                                                            for fp in free], Tu)
    if smap is not None:
        # the same model class, evaluated on states built as arrays
        model = physics_model(kind, base, kernel=kernel)
        s_data, s_probe = 2j * np.pi * fu, 2j * np.pi * f_probe

        # lines laid out as the (temperature × frequency) grid, row-major: a reshape, not a gather
        on_grid = inv_T.size == Tu.size * fu.size and np.array_equal(inv_T * fu.size + inv_f, np.arange(inv_T.size))

        columns = getattr(model, "evaluate_columns", None)     # states as flat columns, no State per call

        def predict_array(X):
            with np.errstate(all="ignore"):     # a non-finite response is refused by the residuals
                if columns is not None:
                    p, n_rows, differ = smap.columns(X)
                    R = columns(p, n_rows, Tu.size, s_data, (q,), differ)[q]
                else:
                    R = model.evaluate_state(smap(X), s_data, (q,))[q]
            if on_grid:
                R = R.reshape(R.shape[0], -1)
                R *= factor
                return R
            return R[:, inv_T, inv_f] * factor

        def probe_array(X):
            st = smap(X)
            st = State(**{k: getattr(st, k)[:, i_probe:i_probe + 1] for k in STATE_FIELDS})
            with np.errstate(all="ignore"):
                return model.evaluate_state(st, s_probe, (q,))[q][:, 0, :] * factor

        key = (smap, tuple(free), kind, q, kernel, fu.tobytes(), Tu.tobytes(), inv_T.tobytes(), inv_f.tobytes())
        if key not in _PLANS:
            if len(_PLANS) >= 32:
                _PLANS.pop(next(iter(_PLANS)))
            _PLANS[key] = _jacobian_plan(smap, list(free), predict_array, inv_T)
        predict_array.jacobian_plan = _PLANS[key]
        # each row evaluated on its own: the kernel is elementwise and its batch-wide tests (the
        # smallest Re γ, the smallest line argument) only choose between forms giving the same
        # numbers; the state map's matrix product rounds every row alike in calls of two rows or
        # more (a single row takes a matrix-vector product)
        predict_array.rows_independent = True
        predict_many.array = predict_array
    return predict_many, SensitivityProbe(f_probe, probe_many, probe_array), q


#: Largest spread of ∂ln G/∂u over lines and rows for a response taken as exponential in u.
AFFINE_TOL = 1e-10
#: Jacobian plans per (state map, model, data grid): repeated calibrations of one problem reuse theirs.
_PLANS: dict = {}


def _jacobian_plan(smap: StateMap, free: list, predict_array, inv_T) -> dict:
    """Columns of the Jacobian in z known without a finite difference of their own (the chain
    rule through the state map), {k: ("scaled", j, c) | ("constant", dlnG)}:

    * ("scaled", j, c): parameter k moves the state at every temperature T along c(T) times
      parameter j's direction (e.g. ``laws.E.slope`` and ``E``), so ∂r/∂z_k = c(T_line)·∂r/∂z_j;
    * ("constant", dlnG): ln G is affine in k's coordinate, with the same slope at every line,
      measured at two rows and two steps (e.g. M ∝ α0): ∂ln G/∂z_k = dlnG.

    Only parameters whose natural coordinate u is affine in z (log-scale fields, linear-scale
    law parameters) qualify.
    """
    _, slope = smap.log_slopes()
    dudz = [math.log(10.0) if fp.scale == "log" and not fp.name.startswith("laws.") else
            (fp.upper - fp.lower) if fp.scale == "linear" and fp.name.startswith("laws.") else None for fp in free]
    A = slope * np.array([0.0 if d is None else d for d in dudz])               # ∂ln|state|/∂z
    plan: dict = {}
    x0 = np.array([fp.initial if fp.initial is not None else fp.midpoint() for fp in free])
    X1 = np.vstack([x0, [float(fp.from_z(0.3 * fp.z_bounds[0] + 0.7 * fp.z_bounds[1])) for fp in free]])
    single = []
    # every pair (k, j) at once: c_kj(T) = <A_k, A_j>/<A_j, A_j> per temperature, and whether
    # A_k = c_kj A_j to 1e-12 of max|A_k| (the loop below only picks the first match)
    gram = np.einsum("vtk,vtj->tkj", A, A)                                            # (n_T, n, n)
    nj = np.diagonal(gram, axis1=1, axis2=2)                                          # (n_T, n)
    cs = np.divide(gram, nj[:, None, :], out=np.zeros_like(gram), where=nj[:, None, :] > 0)
    atol = 1e-12 * np.abs(A).max(axis=(0, 1))                                         # (n,)
    match = np.all(np.abs(A[:, :, :, None] - cs[None] * A[:, :, None, :]) <= atol[None, None, :, None], axis=(0, 1))
    moves = np.count_nonzero(np.abs(A).max(axis=1), axis=0)                          # fields moved per parameter
    for k in range(len(free)):
        if dudz[k] is None:
            continue
        for j in range(k):
            if dudz[j] is not None and j not in plan and match[k, j]:
                plan[k] = ("scaled", j, cs[:, k, j][inv_T])
                break
        if k not in plan and moves[k] == 1:
            single.append(k)        # the affine test below only for a parameter moving one field
    if not single:
        return plan
    rows, du = list(X1), []
    for k in single:                # two rows, two steps in u each, all in one model call
        step = 1.0 if free[k].scale == "log" else 0.1 * dudz[k]
        for x in X1:
            for h in (0.5, 1.0):
                xx = x.copy()
                xx[k] = np.sign(x[k]) * np.exp(np.log(abs(x[k])) + h) if free[k].scale == "log" else x[k] + h * step
                rows.append(xx)
                du.append(h * step)
    G = predict_array(np.array(rows))
    base_rows = np.tile([0, 0, 1, 1], len(single))
    q = G[2:] / G[base_rows]            # ln q = ln|q| + i arg q, without the slower complex logarithm
    rates = ((np.log(np.abs(q)) + 1j * np.angle(q)) / np.array(du)[:, None]).reshape(len(single), 4, -1)  # ∂lnG/∂u
    for k, rk in zip(single, rates):
        if np.all(np.isfinite(rk)) and np.ptp(rk.real) <= AFFINE_TOL and np.ptp(rk.imag) <= AFFINE_TOL:
            plan[k] = ("constant", complex(rk.mean()) * dudz[k])
    return plan


def calibrate(data: FrequencySweep | Sequence[FrequencySweep], base: IPMCParameters,
              free: Sequence[FreeParameter | str], *, kind: str = "actuator", quantity: str | None = None,
              starts: int = 4, seed: int = 0, kernel: str = "boundary_charge", max_nfev: int | None = None,
              identify: bool = True, hold_undetermined: bool | str = True, name: str | None = None,
              progress: Callable[[int], None] | None = None, misfit: str = "widen",
              effects: Mapping[str, Mapping[str, float]] | None = None, temperature_c: float | None = None,
              input_unit: str | None = None, output_unit: str | None = None, **kwargs) -> CalibrationResult:
    """Calibrate physical parameters of ``base`` to frequency-response data at one or many temperatures.

    Start 0 is the base value (or ``initial``); ``starts − 1`` more are seeded Latin-hypercube
    points.  Goodness of fit (``result.goodness_of_fit``,
    :func:`~physmodel.estimation.residuals.goodness_of_fit`): when the cost is inconsistent with
    its χ² expectation (declared noise) or implies implausible noise (estimated noise), the result
    says so (``adequate`` False, message), no parameter is reported as identifiable, and its
    intervals are widened by the Birge ratio sqrt(χ²/dof) or withheld (``misfit``).

    Parameters
    ----------
    data : FrequencySweep or sequence of FrequencySweep
        The measured lines, in units of the matching kind (mm/V, µA/mm, Ω, ...).
    base : IPMCParameters
        The parameter set whose other parameters are kept.
    free : sequence of FreeParameter or str
        Records or bare names (default bounds: :func:`default_free_parameter`): IPMCParameters
        fields, ``"omega_n"`` or ``"laws.<quantity>.<attribute>"`` (temperature-law parameters,
        fitted jointly across temperatures).
    kind, quantity, kernel : str, str or None, str
        ``"actuator"`` (``"M"`` tip displacement per volt by default, also ``H``, ``Z``, ``I``) or
        ``"sensor"`` (``"S"``, ``"Z"``); the sensor's collection kernel.
    starts, seed, max_nfev : int, int, int or None
        Starts of the multi-start search, their seed, residual evaluations per start.
    identify, hold_undetermined : bool, bool or str
        Flag undetermined parameters; hold them at their base value (see
        :func:`~physmodel.estimation.lsq.fit_parameters`).
    name : str or None
        Name of the calibrated set (default ``"<base.name>_calibrated"``).
    progress : callable or None
        ``progress(1)`` after each start.
    misfit : {"widen", "withhold"}
        On a misfit widen the intervals by the Birge ratio (default) or withhold them as NaN
        (what ``ipmc calibrate`` does unless ``--accept-misfit``).
    effects : mapping or None
        A measurement chain or other effects ({effect: {parameter: value}}, SI,
        :mod:`physmodel.effects`) held fixed while the physical parameters are fitted: the model
        is ``EffectModel(base, kind, effects)``.
    temperature_c : float or None
        Temperature [°C] of data that carry none (a ``control.FrequencyResponseData``); passed to
        :func:`~physmodel.data.interop.as_sweep`.
    input_unit, output_unit : str or None
        Units of data that carry none (an FRD, an estimate from bare arrays), e.g. ``"V"`` and
        ``"mm"``; a sweep in other units of the same kind is converted.
    **kwargs
        Passed to :func:`~physmodel.estimation.lsq.fit_parameters` (``fixed``, ``ftol``, ``fd_step``).

    Returns
    -------
    CalibrationResult
        ``parameters`` is ``base`` with the determined values (held ones at their base value).
    """
    if misfit not in ("widen", "withhold"):
        raise ParameterError(f"misfit must be 'widen' or 'withhold', got {misfit!r}")
    if not isinstance(base, IPMCParameters):
        raise ParameterError(f"base must be IPMCParameters, got {type(base).__name__}")
    data = as_sweep(data, temperature_c, input_unit=input_unit, output_unit=output_unit)
    if effects is not None:
        if not isinstance(effects, Mapping):
            raise ParameterError(f"effects must map effect names to {{parameter: value}}, got {effects!r}")
        from ..effects import normalize_effects

        effects = normalize_effects(effects)
    fps, paths = [], {}           # each name resolved once against base (ParameterPath)
    for item in free:
        if isinstance(item, str):
            path = paths[item] = resolve_path(base, item)
            fps.append(default_free_parameter(base, path))
        elif isinstance(item, FreeParameter):
            path = paths[item.name] = resolve_path(base, item.name)
            if item.initial is None:
                v = path.value
                if not item.lower <= v <= item.upper:
                    raise ParameterError(f"free parameter {item.name}: the base value {v!r} lies outside the "
                                         f"bounds [{item.lower!r}, {item.upper!r}]; give an initial value")
                item = item.with_initial(v)
            fps.append(item)
        else:
            raise ParameterError(f"free parameters must be names or FreeParameter, got {item!r}")
    fixed = kwargs.get("fixed") or {}
    predict_many, probe, q = physics_predictor(data, apply_values(base, fixed) if fixed else base, kind, quantity,
                                               kernel, free=fps, effects=effects, paths=None if fixed else paths)
    res = fit_parameters(data, None, fps, starts=starts, seed=seed, predict_many=predict_many,
                         predict_array=predict_many.array, max_nfev=max_nfev, identify=identify,
                         hold_undetermined=hold_undetermined, probe=probe, progress=progress, **kwargs)
    label = name or f"{base.name}_calibrated"
    fingerprint = data.fingerprint()          # a SHA-256 of the data: once
    src = (f"calibrated by physmodel.estimation.calibration to {data.output_name}/{data.input_name} sweep "
           f"{fingerprint[:12]} ({kind} {q}); free: {', '.join(res.names)}"
           + (f"; undetermined (held at base): {', '.join(res.held)}" if res.held else "")
           + (f"; undetermined, NOT held (holding would worsen the fit beyond its test): {', '.join(res.hold_refused)}"
              if res.hold_refused else "")
           + f"; base: {base.name}")
    res.parameters = replace(apply_values(base, res.values, paths), name=label, source=src)
    res.metadata.update({"kind": kind, "quantity": q, "kernel": kernel, "base": base.name,
                         "data_fingerprint": fingerprint, "seed": seed})
    if effects:
        res.metadata["effects"] = {k: dict(v) for k, v in effects.items()}
    if not res.adequate:
        apply_misfit_policy(res, widen=misfit == "widen")
    return res


def apply_misfit_policy(res: CalibrationResult, widen: bool) -> CalibrationResult:
    """For a result whose model does not fit its data: no identifiability verdict, and the
    intervals withheld (NaN) or, with ``widen``, widened by the Birge ratio
    R = sqrt(χ²/dof) (in the fitted scale: log parameters multiplicatively).  In place; returned."""
    gof = res.goodness_of_fit
    R = math.sqrt(gof.reduced_chi2) if gof.reduced_chi2 > 0 and math.isfinite(gof.reduced_chi2) else float("nan")
    for n, fp in zip(res.names, res.free):
        if n in res.held:
            continue
        v, lo, hi = res.values[n], res.ci_lower[n], res.ci_upper[n]
        if widen and math.isfinite(R):
            if fp.scale == "log" and v != 0 and lo * v > 0 and hi * v > 0:
                # in log10 and clipped as FreeParameter.from_z does: the interval of an undetermined
                # parameter (a refused hold) can span hundreds of decades
                lo, hi = (math.copysign(10.0 ** min(max(math.log10(abs(v)) + R * math.log10(b / v), -300.0), 300.0), v)
                          for b in (lo, hi))
            else:
                lo, hi = v - R * (v - lo), v + R * (hi - v)
            res.ci_lower[n], res.ci_upper[n] = min(lo, hi), max(lo, hi)
            res.stderr[n] = res.stderr[n] * R
        else:
            res.ci_lower[n] = res.ci_upper[n] = res.stderr[n] = float("nan")
        was = res.identifiability.get(n)
        keep = f"{was.reason}; " if n in res.hold_refused and was is not None else ""
        res.identifiability[n] = Identifiability(False, keep + "not assessed: the model does not fit the data ("
                                                 + gof.reason + ")")
    res.message += ("; MODEL INADEQUATE: " + gof.reason
                    + ("; intervals widened by the Birge ratio %.3g" % R if widen else "; intervals withheld"))
    return res


def model_sweep(result: CalibrationResult, data: FrequencySweep, kind: str | None = None,
                quantity: str | None = None, kernel: str | None = None) -> FrequencySweep:
    """The calibrated model's response on the data's lines, as a sweep (for overlays)."""
    if result.parameters is None:
        raise IPMCError("the result has no physical parameter set (use calibrate(), not fit_parameters())")
    kind = kind or result.metadata.get("kind", "actuator")
    predict_many, _, _ = physics_predictor(data, result.parameters, kind,
                                           quantity or result.metadata.get("quantity"),
                                           kernel or result.metadata.get("kernel", "boundary_charge"),
                                           effects=result.metadata.get("effects"))
    G = predict_many([{}])[0]
    return replace(data, response=G, magnitude_std_db=None, phase_std_deg=None,
                   metadata={"source": "calibrated model", "parameter_set": result.parameters.name})


__all__ = ["default_free_parameter", "physics_predictor", "calibrate", "apply_misfit_policy", "model_sweep"]
