"""Scenario step ``[control_route]``: the physics-calibrated route from a few measured temperatures
to a feedforward that can be trusted between them (issue 14).

Given the scenario's (noisy) sweep at a few temperatures (``[sweep]``), the step

1. fits the schedule directly to those temperatures and measures it against the true physics on a
   dense grid (and records whether :func:`surrogate.crossval.check_schedule` warned);
2. calibrates the physics to the same sweep (``free`` parameters, starting from the scenario's set
   with ``prior`` values), sweeps the calibrated physics on ``dense_temperatures_c``, fits the
   schedule there, checks it (leave-one-temperature-out and a dense check against the calibrated
   physics) and measures it against the true physics;
3. computes the feedforward of both schedules for a faded sine at ``temperature_c`` (between the
   measured temperatures) and runs it through the true physics: tracking error, peak voltage and
   the steady-state prediction ``A |P/G - 1|``.

Schema (to add to :data:`scenarios.spec.SECTIONS` as ``"control_route"``, step after ``surrogate``)::

    [control_route] free (list of parameter names), prior = { NAME = value } (start values),
                    starts, seed, dense_temperatures_c (list), form, n_zeros, n_poles, degree,
                    temperature_c, frequency_hz, amplitude_mm, fs_hz, duration_s
"""

from __future__ import annotations

import warnings

import numpy as np

from .context import md_table
from .spec import ScenarioError

__all__ = ["step_control_route"]

def _dense_vs(model, physics_model, f, temps):
    from surrogate.crossval import dense_check, physics_reference

    return dense_check(model, physics_reference(physics_model), f, temps, step_c=1.0)


def step_control_route(ctx) -> None:
    import physmodel
    import surrogate
    from inversion import feedforward
    from inversion.limits import DEFAULT_MAX_VOLTAGE, Limits
    from inversion.references import sine
    from physmodel.data.sweep import synthesize_sweep
    from physmodel.data.timesim import model_realization, simulate
    from physmodel.estimation.calibration import calibrate
    from physmodel.parameter_paths import apply_values
    from surrogate.crossval import ScheduleWarning, check_schedule

    from . import plots
    from .plots import feedforward_check

    cfg = ctx.spec.section("control_route")
    if ctx.spec.section("model")["kind"] != "actuator":
        raise ScenarioError(f"{ctx.spec.path}: [control_route] needs an actuator model")
    data, truth = ctx.data, ctx.model
    measured = data.temperatures()
    f = data.frequency_hz[data.temperature_c == measured[0]]
    nz, npo, deg = cfg.get("n_zeros", 4), cfg.get("n_poles", 4), cfg.get("degree", 2)
    form = cfg.get("form", "zpk")
    T_ff = cfg.get("temperature_c", float(np.mean(measured)))
    if not measured[0] < T_ff < measured[-1]:
        raise ScenarioError(f"{ctx.spec.path}: [control_route] temperature_c must lie between the measured "
                            f"temperatures {measured.tolist()}")
    # 1. the direct fit on the measured temperatures
    direct_fitter = surrogate.ScheduledFit(form, nz, npo, deg, raise_on_failure=False)
    direct = direct_fitter.fit(data)
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always", ScheduleWarning)
        chk_direct = check_schedule(direct_fitter, data, direct.model)        # no physics: what a user sees
    warned = any(issubclass(w.category, ScheduleWarning) for w in rec)
    dense_direct = _dense_vs(direct.model, truth, f, measured)
    # 2. the physics-calibrated route
    free = cfg.get("free", ["E"])
    prior = apply_values(ctx.base_params, cfg.get("prior", {}))
    cal = calibrate(data, prior, free, starts=cfg.get("starts", 2), seed=cfg.get("seed", 0))
    physics = physmodel.ActuatorModel(cal.parameters)
    dense_t = cfg.get("dense_temperatures_c", list(np.linspace(measured[0], measured[-1], 7)))
    dense_sw = synthesize_sweep(physics, "M", f, dense_t)
    route_fitter = surrogate.ScheduledFit(form, nz, npo, deg, raise_on_failure=False)
    route = route_fitter.fit(dense_sw)
    with warnings.catch_warnings(record=True) as rec2:
        warnings.simplefilter("always", ScheduleWarning)
        chk_route = check_schedule(route_fitter, dense_sw, route.model, physics=physics)
    route_warned = any(issubclass(w.category, ScheduleWarning) for w in rec2)
    dense_route = _dense_vs(route.model, truth, f, dense_t)
    # 3. feedforward through the true physics at T_ff
    A, fr, fs = cfg.get("amplitude_mm", 0.3), cfg.get("frequency_hz", 1.0), cfg.get("fs_hz", 10_000.0)
    ref = sine(A, fr, cfg.get("duration_s", max(8.0 / fr, 4.0)), fs, unit="mm")
    real = model_realization(truth, T_ff, fs, ref.t[-1])
    P = truth.frequency_response(np.array([fr]), [T_ff])["M"][0, 0, 0] * 1e3      # mm/V
    lim = Limits(max_voltage=cfg.get("max_voltage_v", DEFAULT_MAX_VOLTAGE), action="warn")
    rows = []
    for name, res in (("direct", direct), ("route", route)):
        G = res.model.at(T_ff)
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always")
            ff = feedforward(G, ref.t, ref.y, limits=lim)
        y = simulate(truth, T_ff, ref.t, ff.output, realization=real).output * 1e3
        err = float(np.max(np.abs(y - ref.y)[ref.body]))
        pred = A * abs(P / complex(G(2j * np.pi * fr)) - 1)
        ctx.metric(f"control_route.{name}_tracking_error_mm", err)
        ctx.metric(f"control_route.{name}_predicted_error_mm", pred)
        ctx.metric(f"control_route.{name}_peak_voltage_v", ff.limit_report.peak)
        # the prediction holds up to what the inversion itself reports it adds: the preview's
        # truncation error and the sampling (discretisation) bound, both through |P|, plus 5 %
        allow = abs(P) * (ff.truncation_error + ff.discretisation_error_estimate) + 0.05 * pred
        ctx.metric(f"control_route.{name}_prediction_gap_over_allowance", abs(err - pred) / allow)
        rows.append((name, f"{ff.preview_s:.3g}", f"{ff.limit_report.peak:.3g}", f"{err * 1e3:.3g}",
                     f"{pred * 1e3:.3g}"))
        if name == "route":
            ctx.file(feedforward_check(ref.t, ref.y, y, ff.output, ctx.out / "control_route_feedforward.png",
                                       unit="mm", max_voltage=lim.max_voltage, body=ref.body,
                                       title=f"physics-calibrated route, {T_ff:g} °C, {fr:g} Hz"))
    ctx.metric("control_route.direct_between_error", dense_direct.between_error)
    ctx.metric("control_route.direct_at_fit_error", dense_direct.at_fit_error)
    ctx.metric("control_route.direct_warned", warned)
    ctx.metric("control_route.route_between_error", dense_route.between_error)
    ctx.metric("control_route.route_max_error", float(np.max(dense_route.errors)))
    ctx.metric("control_route.route_cv_error", chk_route.cv.cv_error)
    ctx.metric("control_route.route_check_ok", chk_route.ok and not route_warned)
    for k, v in cal.values.items():
        ctx.metric(f"control_route.calibrated.{k}", v)
    ctx.file(plots.curves(dense_direct.temperatures_c,
                          {f"direct fit on {measured.tolist()} °C": dense_direct.errors,
                           f"calibrated physics, fit on {len(dense_t)} temperatures": np.interp(
                               dense_direct.temperatures_c, dense_route.temperatures_c, dense_route.errors)},
                          ctx.out / "control_route_schedule_error.png", "temperature [°C]",
                          "relative RMS error vs the true physics", logx=False,
                          title=f"{form} {nz}/{npo} schedule, degree {deg}"))
    ctx.section(
        "Physics-calibrated route",
        f"Direct {form} {nz}/{npo} degree-{deg} fit on the measured {measured.tolist()} °C: error at them "
        f"{dense_direct.at_fit_error:.3g}, between them up to {dense_direct.between_error:.3g} (worst at "
        f"{dense_direct.worst_temperature_c:g} °C) against the true physics; "
        f"`check_schedule` {'warned' if warned else 'did not warn'}: {chk_direct.message[:300]}.", "",
        f"Route: calibrated {', '.join(f'{k} = {v:.4g}' for k, v in cal.values.items())} "
        f"({'converged' if cal.converged else 'NOT converged'}); calibrated physics swept at {dense_t} °C; "
        f"schedule error against the true physics at most {float(np.max(dense_route.errors)):.3g} "
        f"(leave-one-out {chk_route.cv.cv_error:.3g}; check {'ok' if chk_route.ok else 'FAILED'}).", "",
        "![schedule error](control_route_schedule_error.png)", "",
        f"Feedforward of a faded {A:g} mm, {fr:g} Hz sine at {T_ff:g} °C through the true physics "
        f"({fs:g} Hz; error between the fades):", "",
        md_table(["schedule", "preview [s]", "peak [V]", "tracking error [um]", "A|P/G-1| [um]"], rows), "",
        "![feedforward](control_route_feedforward.png)")

