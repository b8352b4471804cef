"""The flagship scenario behind ``ipmc demo``: physics sweeps across temperature, the reduced-model
check of seed 002, seed 002's width and r2 claims, and virtual time-domain experiments, written to a
report folder (CSV data, PNG figures, report.md with each check's pass/fail).

Every file is written atomically; report.md is written last, so a folder without it is incomplete.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np


def _md_table(header, rows) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def run_demo(out: Path, quiet: bool = False) -> int:
    from physmodel import ISOTHERMAL, ActuatorModel, SensorModel, TransimpedanceChain, get_parameter_set
    from physmodel.reduced import reduced_frequency_response
    from physmodel.sweep import MagnitudePhaseNoise, atomic_write, synthesize_sweep
    from physmodel.timesim import free_release, step

    from . import plots

    t_start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    checks: list[tuple[str, bool, str]] = []
    say = (lambda *a: None) if quiet else (lambda *a: print(*a))

    # 1. actuator sweeps across temperature (seed 002 Table 3 strip, default temperature laws)
    act = ActuatorModel(get_parameter_set("seed002_table3"))
    temps = [20.0, 40.0, 60.0]
    f = np.logspace(-1, 2, 80)
    sw = synthesize_sweep(act, "M", f, temps, MagnitudePhaseNoise(0.1, 1.0), seed=2026)
    sw.to_csv(out / "actuator_sweep.csv")
    exact = synthesize_sweep(act, "M", f, temps)
    plots.bode([sw, exact], out / "actuator_bode.png", labels=["data", "model"], styles=["o", "-"],
               title="seed002_table3 actuator: tip displacement / voltage")
    say(f"actuator sweep: {out / 'actuator_sweep.csv'}")
    dc = act.dc_gain(temps)["M0"][0] * 1e3
    fpk = []
    for t in temps:
        m = exact.temperature_c == t
        fpk.append(f[np.argmax(np.abs(exact.response[m]) * (f > 3))])

    # 2. sensor sweeps (seed 000 geometry, development material values)
    sen = SensorModel(get_parameter_set("seed000_sensor_dev"))
    temps_s = [25.0, 45.0, 65.0]
    fs_ = np.logspace(0, np.log10(200), 60)
    sws = synthesize_sweep(sen, "S", fs_, temps_s, MagnitudePhaseNoise(0.1, 1.0), seed=2027)
    sws.to_csv(out / "sensor_sweep.csv")
    plots.bode(sws, out / "sensor_bode.png", title="seed000 sensor geometry: current / tip displacement")

    # 3. reduced (Taylor) models vs the infinite-dimensional model around the first mode
    iso = ActuatorModel(get_parameter_set("seed002_table3", laws=ISOTHERMAL))
    st = iso.state([26.85])
    fr = np.logspace(np.log10(0.5), np.log10(50), 150)
    ex = iso.frequency_response(fr, [26.85])["M"][0, 0]
    curves = {"infinite": 20 * np.log10(np.abs(ex) * 1e3)}
    rows = []
    band = (fr >= 2) & (fr <= 30)
    for k in (1, 2, 3, 4):
        red = reduced_frequency_response(st, fr, k)
        curves[f"Taylor order {k}"] = 20 * np.log10(np.abs(red) * 1e3)
        err = np.abs(20 * np.log10(np.abs(red / ex)))[band].max()
        rows.append((k, f"{err:.3f}"))
    plots.curves(fr, curves, out / "taylor_orders.png", "frequency [Hz]", "magnitude [dB mm/V]",
                 "seed 002 Fig. 4: reduced models around the first mode")
    e = {k: float(v) for k, v in rows}
    checks.append(("third-order Taylor within 0.5 dB of the infinite model (2-30 Hz); order 2 and 1 miss by > 1 dB",
                   e[3] < 0.5 and e[2] > 1.0 and e[1] > 1.0, f"orders 1-4: {', '.join(f'{e[k]:.2f}' for k in (1, 2, 3, 4))} dB"))

    # 4. seed 002 claims: width independence and r2 lowering the gain
    widths = [4e-3, 2e-3, 1e-3, 0.5e-3]
    Ms = [ActuatorModel(get_parameter_set("seed002_table3", W=w)).frequency_response(fr, [26.85])["M"][0, 0] for w in widths]
    wdev = max(np.max(np.abs(M / Ms[0] - 1)) for M in Ms)
    checks.append(("physics model independent of width (4, 2, 1, 0.5 mm)", wdev < 1e-12, f"max relative change {wdev:.1e}"))
    base = get_parameter_set("seed002_table3")
    g = [np.abs(ActuatorModel(base.replace(r2_specific=base.r2_specific * k)).frequency_response(fr, [26.85])["M"][0, 0])
         for k in (1, 10, 100)]
    checks.append(("increasing r2 lowers the gain at every frequency", bool(np.all(g[1] < g[0]) and np.all(g[2] < g[1])),
                   f"at 10 Hz: {', '.join(f'{20*np.log10(x[np.argmin(abs(fr-10))]*1e3):.2f}' for x in g)} dB mm/V for r2 x1, x10, x100"))
    checks.append(("first vibration mode near 10 Hz", 8 <= act.params[0].omega_n / (2 * np.pi) <= 15,
                   f"omega_n/2pi = {act.params[0].omega_n / (2 * np.pi):.2f} Hz at 300 K"))

    # 5. time-domain virtual experiments
    ts = step(act, 40.0, 1.0, 1.0, 1000.0, output_noise_rms=5e-6, seed=1)
    ts.to_csv(out / "actuator_step.csv")
    plots.traces(ts, out / "actuator_step.png", title="1 V step, seed002_table3, 40 °C", output_scale=1e3,
                 output_label="tip displacement [mm]")
    final = float(np.mean(ts.clean_output[-50:]))
    dc40 = float(act.dc_gain([40.0])["M0"][0, 0])
    checks.append(("step response settles to the closed-form DC gain", abs(final / dc40 - 1) < 1e-2,
                   f"{final*1e3:.4f} mm vs {dc40*1e3:.4f} mm/V"))
    tr = free_release(sen, 35.0, 1e-3, 0.1, 0.5, 4000.0, chain=TransimpedanceChain(470e3, 10e3, 10e3),
                      output_noise_rms=1e-3, seed=3)
    tr.to_csv(out / "sensor_release.csv")
    plots.traces(tr, out / "sensor_release.png", title="sensor: tip released from 1 mm at 0.1 s, 35 °C (seed 000 circuit)")

    # report
    elapsed = time.perf_counter() - t_start
    lines = [
        "# ipmc demo report", "",
        "Physics: Chen-Tan actuator and sensor models (seed 002 eqs. 10-16), default temperature laws "
        "(Arrhenius diffusivity 15 kJ/mol, modulus -0.75 %/K, water permittivity, Nernst-Einstein leakage).", "",
        "## Actuator across temperature (seed002_table3)", "",
        "![actuator Bode](actuator_bode.png)", "",
        _md_table(["T [°C]", "DC gain [mm/V]", "peak above 3 Hz [Hz]"],
                  [(f"{t:g}", f"{d:.3f}", f"{p:.2f}") for t, d, p in zip(temps, dc, fpk)]), "",
        "## Sensor across temperature (seed 000 geometry, development values)", "",
        "![sensor Bode](sensor_bode.png)", "",
        "## Reduced models (seed 002 §2.2.4)", "",
        "![Taylor orders](taylor_orders.png)", "",
        _md_table(["Taylor order", "max |error| 2-30 Hz [dB]"], rows), "",
        "## Time domain", "",
        "![step](actuator_step.png)", "", "![release](sensor_release.png)", "",
        "## Checks", "",
        _md_table(["check", "result", "measured"], [(c, "PASS" if ok else "FAIL", m) for c, ok, m in checks]), "",
        f"Ran in {elapsed:.1f} s.", "",
    ]
    atomic_write(out / "report.md", lambda fh: fh.write("\n".join(lines)))
    n_fail = sum(not ok for _, ok, _ in checks)
    say(f"report: {out / 'report.md'} ({len(checks) - n_fail}/{len(checks)} checks passed, {elapsed:.1f} s)")
    return 0 if n_fail == 0 else 3
