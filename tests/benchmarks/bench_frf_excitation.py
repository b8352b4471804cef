"""Benchmark of FRF estimation that reads the excitation (issue 26, item 2; not collected by pytest).

Records come from a generator written here, without the library's excitation or simulation code:
a rational plant (a resonance at 8 Hz, ζ = 0.15, in series with a pole at 30 Hz) simulated with
``scipy.signal.lsim`` (zero-order hold of the samples) from rest, driven by

* a Schroeder multisine (30 log-spaced lines, 0.2-40 Hz, period 5 s) of 8 periods plus a record
  start at a random point of the period (the acquisition not synchronised with the generator);
* white Gaussian noise (120 s);
* a stepped sine (10 steps, 0.5-40 Hz, 1.5 s plus 10 periods each, each step from phase 0);

at fs = 250 Hz, with white noise on the output (5 % of its RMS) and on the input (0.1 % of its
RMS).  The truth is the plant's ZOH discretisation (``scipy.signal.cont2discrete``) evaluated on
the unit circle (``scipy.signal.freqz``) — the exact map from samples to samples.  Each case runs
``estimate_frf`` with defaults only, over seeds 5000.. (not used while writing the code), and
reports lines held vs lines excited, and the RMS of error/σ of ln|H| and of the phase over the lines
above the estimate's coherence threshold (the lines ``ipmc frf`` keeps by default; the goal is
0.7-1.4; for small errors and ν degrees of freedom the expected value is √(ν/(ν − 2))), also over
the lines with a stated σ ≤ 1 dB.  ``--first-seed`` runs seeds not looked at while developing.  The
multisine case is also run once through ``ipmc frf`` on a CSV with columns ``drive_V``, ``tip_mm``
and no header, giving only --input, --output and --temperature.  Then: what a clipped record
(output clipped at 30 % of its peak), a pure-noise output and a 10-sample record give.

    python tests/benchmarks/bench_frf_excitation.py [--seeds 20] [--first-seed 5000]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
from scipy import signal

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from physmodel.errors import IPMCError  # noqa: E402
from physmodel.estimation.frf import estimate_frf  # noqa: E402

FS = 250.0
LN = math.log(10.0) / 20.0
W1, Z1, W2 = 2 * np.pi * 8.0, 0.15, 2 * np.pi * 30.0
NUM = [W1**2 * W2]
DEN = np.polymul([1.0, 2 * Z1 * W1, W1**2], [1.0, W2])
BD, AD = signal.cont2discrete((NUM, DEN), 1 / FS, "zoh")[:2]


def simulate(u, rng, out_noise=0.05, in_noise=1e-3):
    t = np.arange(u.size) / FS
    _, y, _ = signal.lsim((NUM, DEN), u, t, interp=False)
    y = y + out_noise * np.std(y) * rng.standard_normal(u.size)
    return u + in_noise * np.std(u) * rng.standard_normal(u.size), y


def truth(f):
    _, h = signal.freqz(np.ravel(BD), AD, worN=2 * np.pi * np.asarray(f) / FS)
    return h


def multisine(rng):
    N = int(5 * FS)
    k = np.unique(np.round(np.geomspace(0.2, 40, 30) * 5).astype(int))
    X = np.zeros(N // 2 + 1, dtype=complex)
    X[k] = N / 2 * np.exp(-1j * np.pi * np.arange(k.size)**2 / k.size)
    per = np.fft.irfft(X, N)
    start = int(rng.integers(N))
    return np.tile(per / np.std(per), 9)[start:start + 8 * N], k * FS / N


def stepped(rng):
    f = np.geomspace(0.5, 40, 10)
    parts = [np.sin(2 * np.pi * fi * np.arange(int(np.ceil((1.5 + 10 / fi) * FS))) / FS) for fi in f]
    return np.concatenate(parts), f


def standardised(e):
    d = np.log(e.response[0] / truth(e.frequency_hz))
    return d.real / (e.magnitude_std_db[0] * LN), d.imag / np.radians(e.phase_std_deg[0])


def run_case(name, make, seeds):
    tm, tp, sd, held, excited, extra, notes, warned = [], [], [], 0, 0, 0, set(), 0
    for s in seeds:
        rng = np.random.default_rng(s)
        u, f_true = make(rng)
        u, y = simulate(u, rng)
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            e = estimate_frf(FS, u, y)
        warned += bool(w)
        a, b = standardised(e)
        keep = e.significant()[0]
        tm.append(a[keep])
        tp.append(b[keep])
        sd.append(e.magnitude_std_db[0][keep])
        if f_true is not None:
            hit = np.isclose(e.frequency_hz[:, None], f_true[None], rtol=2e-3).any(axis=0)
            held += int(hit.sum())
            excited += f_true.size
            extra += int(e.frequency_hz.size - hit.sum())
        notes.add(f"{e.method}: {e.settings['excitation'].split('(')[0].strip()}")
    tm, tp, sd = np.concatenate(tm), np.concatenate(tp), np.concatenate(sd)
    small = sd <= 1.0
    print(f"== {name}: {len(seeds)} records; {'; '.join(sorted(notes))[:160]}")
    if excited:
        print(f"   lines held {held} of {excited} excited, {extra} other lines")
    print(f"   lines above the coherence threshold: {tm.size};  error/σ RMS  magnitude {np.sqrt(np.mean(tm**2)):.3f}  "
          f"phase {np.sqrt(np.mean(tp**2)):.3f};  |error| ≤ 2σ: {np.mean(np.abs(tm) <= 2):.3f} / "
          f"{np.mean(np.abs(tp) <= 2):.3f};  records with warnings: {warned}")
    print(f"   of which stated σ ≤ 1 dB (small errors): {small.sum()}, error/σ RMS magnitude "
          f"{np.sqrt(np.mean(tm[small]**2)):.3f}  phase {np.sqrt(np.mean(tp[small]**2)):.3f}")
    return e


def cli_case(seed):
    from physmodel.data.files import read_sweep
    from physmodel.data.timerecord import TimeRecord
    from scenarios.cli import main

    rng = np.random.default_rng(seed)
    u, f_true = multisine(rng)
    u, y = simulate(u, rng)
    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "daq.csv"
        TimeRecord(np.arange(u.size) / FS, {"drive": u, "tip": y}, {"drive": "V", "tip": "mm"}).save(rec)
        text = rec.read_text().splitlines()
        body = [line for line in text if not line.startswith("#")]
        rec.write_text("\n".join(body) + "\n")                 # a DAQ's file: no header, its own column names
        out = Path(tmp) / "sweep.csv"
        code = main(["frf", str(rec), "--input", "drive", "--output", "tip", "--temperature", "25", "--quiet",
                     "--out", str(out)])
        sw = read_sweep(out)
    d = np.log(sw.response / truth(sw.frequency_hz))
    hit = np.isclose(sw.frequency_hz[:, None], f_true[None], rtol=1e-9).any(axis=0)
    print(f"== ipmc frf on a headerless CSV ({body[0]}), only --input/--output/--temperature: exit {code}, "
          f"{hit.sum()} of {f_true.size} excited lines, {sw.frequency_hz.size - hit.sum()} others; error/σ RMS "
          f"magnitude {np.sqrt(np.mean((d.real / (sw.magnitude_std_db * LN))**2)):.3f} "
          f"phase {np.sqrt(np.mean((d.imag / np.radians(sw.phase_std_deg))**2)):.3f}; method {sw.metadata['method']}")


def outcome(label, fn):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            e = fn()
        except IPMCError as exc:
            print(f"   {label}: refused (IPMCError → exit 2): {exc}")
            return
    print(f"   {label}: estimate of {e.frequency_hz.size} lines, {int(e.significant().sum())} above the coherence "
          f"threshold; warnings: {[str(x.message)[:150] for x in w] or 'NONE'}")


def bad_records(seed):
    print("== records that must not pass quietly")
    rng = np.random.default_rng(seed)
    u, _ = multisine(rng)
    u, y = simulate(u, rng)
    c = 0.3 * np.abs(y).max()
    outcome("output clipped at 30 % of its peak", lambda: estimate_frf(FS, u, np.clip(y, -c, c)))
    outcome("same, max_clipped_fraction=1 (warn only)",
            lambda: estimate_frf(FS, u, np.clip(y, -c, c), max_clipped_fraction=1.0))
    outcome("pure-noise output", lambda: estimate_frf(FS, u, rng.standard_normal(u.size)))
    outcome("random drive, pure-noise output", lambda: estimate_frf(FS, rng.standard_normal(30_000),
                                                                   rng.standard_normal(30_000)))
    outcome("10-sample record", lambda: estimate_frf(FS, u[:10], y[:10]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=5000,
                    help="first seed (5000: the seeds the figures in the issue were measured on)")
    args = ap.parse_args(argv)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    run_case("periodic Schroeder multisine, 8 periods, unsynchronised start, plant from rest", multisine, seeds)
    run_case("random (white) drive, 120 s", lambda rng: (rng.standard_normal(int(120 * FS)), None), seeds)
    run_case("stepped sine, 10 steps", stepped, seeds)
    cli_case(seeds[0])
    bad_records(seeds[-1] + 1)


if __name__ == "__main__":
    main()
