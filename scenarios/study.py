"""Parameter studies: Monte Carlo or grid over parameters × temperatures × frequencies, run on
local processes (default) or on a Dask distributed cluster, with identical results for the same
seed whatever runs them.  ``ipmc study SPEC.toml`` is the command line.

Study file (TOML; units SI except Hz and °C, as the key names say)::

    [study]
    name = "actuator_mc"
    kind = "actuator"                 # or "sensor"
    set = "seed001_actuator_dev"      # parameter set name or JSON path
    quantity = "M"                    # default M (actuator) / S (sensor)
    kernel = "boundary_charge"        # sensors only
    method = "monte_carlo"            # or "grid" (every parameter gives values = [...])
    samples = 64                      # Monte Carlo only
    seed = 1                          # master seed (required)
    temperatures_c = [20.0, 40.0]
    frequencies_hz = [...]            # or fmin_hz, fmax_hz, points (log-spaced)
    chunk_size = 16                   # samples per task
    [study.noise]                     # optional measurement noise per sample
    kind = "magphase"                 # or "complex"; sigma_db, sigma_deg / sigma
    [study.parameters.d]              # one table per parameter (an IPMCParameters field)
    distribution = "lognormal"        # median, sigma (of ln)  | "normal": mean, std
                                      # "uniform": low, high   | grid: values = [...]

Sample ``i`` draws its parameters (in file order), then its noise, from
``numpy.random.SeedSequence(seed).spawn(n)[i]`` — nothing depends on which worker evaluates it
or in which order, so local processes, a Dask cluster and a serial loop give bit-identical
tables.  A task evaluates its chunk of samples in one vectorised model call.

The result is a tidy table (:class:`StudyTable`): one row per sample × temperature × frequency
with columns ``sample``, one per parameter, ``temperature_c``, ``frequency_hz``,
``magnitude_db``, ``phase_deg`` (wrapped), ``real``, ``imag`` (response in the display units of
:data:`physmodel.data.sweep.QUANTITY_UNITS`), written as CSV or NPZ (atomically).
"""

from __future__ import annotations

import copy
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from physmodel.data.files import by_extension
from physmodel.errors import IPMCError

from .spec import ScenarioError, read_toml

_STUDY_KEYS = {"name", "kind", "set", "quantity", "kernel", "method", "samples", "seed", "temperatures_c",
               "frequencies_hz", "fmin_hz", "fmax_hz", "points", "chunk_size", "noise", "parameters"}
_DISTS = {"lognormal": ("median", "sigma"), "normal": ("mean", "std"), "uniform": ("low", "high")}
_NOISE_KEYS = {"kind", "sigma_db", "sigma_deg", "sigma"}


#: Most rows (samples × temperatures × frequencies) of one study table, checked before evaluation.
MAX_STUDY_ROWS = 50_000_000
#: Seconds a Dask scheduler has to accept the connection and send its handshake (--scheduler-timeout).
SCHEDULER_TIMEOUT_S = 20.0


class StudyError(ScenarioError):
    """A study file that does not follow the schema (exit code 2)."""


# ---------------------------------------------------------------------------- spec
def _num(v, where):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise StudyError(f"{where}: expected a finite number, got {v!r}")
    return float(v)


def _nums(v, where):
    if not isinstance(v, list) or not v:
        raise StudyError(f"{where}: expected a non-empty list of numbers, got {v!r}")
    return [_num(x, f"{where}[{i}]") for i, x in enumerate(v)]


def parse_study(raw: dict, where: str = "<study>") -> dict:
    """Validate a parsed study document; returns the normalised ``[study]`` table (plain data)."""
    from physmodel.params import IPMCParameters

    if set(raw) != {"study"}:
        raise StudyError(f"{where}: expected exactly one table [study], got {sorted(raw)}")
    s = copy.deepcopy(raw["study"])
    for k in s:
        if k not in _STUDY_KEYS:
            raise StudyError(f"{where}: [study] unknown key {k!r}; expected one of {sorted(_STUDY_KEYS)}")
    for k in ("kind", "set", "seed", "temperatures_c", "parameters"):
        if k not in s:
            raise StudyError(f"{where}: [study] missing required key {k!r}")
    for k in ("name", "set", "quantity", "kernel", "method"):
        if k in s and not isinstance(s[k], str):
            raise StudyError(f"{where}: [study] {k} must be a string, got {s[k]!r}")
    if s["kind"] not in ("actuator", "sensor"):
        raise StudyError(f"{where}: [study] kind must be 'actuator' or 'sensor', got {s['kind']!r}")
    if not isinstance(s["seed"], int) or isinstance(s["seed"], bool) or s["seed"] < 0:
        raise StudyError(f"{where}: [study] seed must be a non-negative integer, got {s['seed']!r}")
    s.setdefault("name", Path(where).stem)
    s.setdefault("quantity", "M" if s["kind"] == "actuator" else "S")
    s.setdefault("method", "monte_carlo")
    if s["method"] not in ("monte_carlo", "grid"):
        raise StudyError(f"{where}: [study] method must be 'monte_carlo' or 'grid', got {s['method']!r}")
    s["temperatures_c"] = _nums(s["temperatures_c"], f"{where}: [study] temperatures_c")
    if "frequencies_hz" in s:
        f = _nums(s["frequencies_hz"], f"{where}: [study] frequencies_hz")
    else:
        lo, hi = _num(s.get("fmin_hz", 0.1), "fmin_hz"), _num(s.get("fmax_hz", 100.0), "fmax_hz")
        n = s.get("points", 50)
        if not (0 < lo < hi) or not isinstance(n, int) or isinstance(n, bool) or not 2 <= n <= MAX_STUDY_ROWS:
            raise StudyError(f"{where}: [study] need 0 < fmin_hz < fmax_hz and integer points in [2, {MAX_STUDY_ROWS}]; "
                             f"got fmin_hz = {lo!r}, fmax_hz = {hi!r}, points = {n!r}")
        f = np.geomspace(lo, hi, n).tolist()
    if min(f) <= 0:
        raise StudyError(f"{where}: [study] frequencies must be > 0 Hz")
    from .commands._common import check_celsius

    try:
        check_celsius(s["temperatures_c"], f"{where}: [study] temperatures_c")
    except IPMCError as exc:
        raise StudyError(str(exc)) from None
    s["frequencies_hz"] = f
    for k in ("fmin_hz", "fmax_hz", "points"):
        s.pop(k, None)
    cs = s.setdefault("chunk_size", 16)
    if not isinstance(cs, int) or cs < 1:
        raise StudyError(f"{where}: [study] chunk_size must be a positive integer, got {cs!r}")
    params = s["parameters"]
    if not isinstance(params, dict) or not params:
        raise StudyError(f"{where}: [study.parameters] needs at least one parameter table")
    fields = set(IPMCParameters.__dataclass_fields__)
    for name, p in params.items():
        w = f"{where}: [study.parameters.{name}]"
        if name not in fields or name in ("name", "source", "laws"):
            raise StudyError(f"{w}: {name!r} is not a numeric IPMCParameters field")
        if not isinstance(p, dict):
            raise StudyError(f"{w}: expected a table")
        if s["method"] == "grid":
            if set(p) != {"values"}:
                raise StudyError(f"{w}: a grid study gives exactly values = [...], got keys {sorted(p)}")
            p["values"] = _nums(p["values"], f"{w} values")
        else:
            dist = p.get("distribution")
            if dist not in _DISTS:
                raise StudyError(f"{w}: distribution must be one of {sorted(_DISTS)}, got {dist!r}")
            need = set(_DISTS[dist]) | {"distribution"}
            if set(p) != need:
                raise StudyError(f"{w}: a {dist} parameter takes exactly {sorted(need)}, got {sorted(p)}")
            a, b = (_num(p[k], f"{w} {k}") for k in _DISTS[dist])
            if (dist == "uniform" and not a < b) or (dist != "uniform" and b < 0) or (dist == "lognormal" and a <= 0):
                raise StudyError(f"{w}: invalid {dist} parameters {_DISTS[dist]} = ({a}, {b})")
    if s["method"] == "grid":
        s["samples"] = int(np.prod([len(p["values"]) for p in params.values()]))
    else:
        n = s.get("samples")
        if not isinstance(n, int) or isinstance(n, bool) or n < 1:
            raise StudyError(f"{where}: [study] samples must be a positive integer, got {n!r}")
    rows = s["samples"] * len(s["temperatures_c"]) * len(s["frequencies_hz"])
    if rows > MAX_STUDY_ROWS:
        raise StudyError(f"{where}: [study] samples × temperatures_c × frequencies = {rows} rows; at most "
                         f"{MAX_STUDY_ROWS} (split the study)")
    if "noise" in s:
        nz = s["noise"]
        if not isinstance(nz, dict) or not set(nz) <= _NOISE_KEYS or nz.get("kind") not in ("magphase", "complex"):
            raise StudyError(f"{where}: [study.noise] takes kind = 'magphase' | 'complex' and "
                             f"{sorted(_NOISE_KEYS - {'kind'})}, got {nz!r}")
        for k in _NOISE_KEYS - {"kind"}:
            if k in nz and _num(nz[k], f"{where}: [study.noise] {k}") < 0:
                raise StudyError(f"{where}: [study.noise] {k} = {nz[k]!r}: expected >= 0")
    # fail now, not in a worker, on a bad set, parameter value or temperature
    from physmodel.plausible import check_physical

    try:
        check_physical(_base(s))
    except IPMCError as exc:
        raise StudyError(f"{where}: [study] set {s['set']!r}: {exc}") from None
    from physmodel.data.units import QUANTITY_UNITS

    if (s["kind"], s["quantity"]) not in QUANTITY_UNITS:
        raise StudyError(f"{where}: [study] quantity {s['quantity']!r} is not available for {s['kind']}s")
    return s


def load_study(path) -> dict:
    """Read and validate a study TOML file."""
    return parse_study(read_toml(path, "study", StudyError), str(path))


# ---------------------------------------------------------------------------- evaluation
def _base(spec):
    from physmodel import get_parameter_set

    return get_parameter_set(spec["set"])


def sample_values(spec: dict, i: int) -> tuple[dict, np.random.Generator]:
    """Parameter values of sample ``i`` and its generator (positioned after the draws)."""
    rng = np.random.default_rng(np.random.SeedSequence(spec["seed"], spawn_key=(i,)))
    params = spec["parameters"]
    if spec["method"] == "grid":
        idx = np.unravel_index(i, [len(p["values"]) for p in params.values()])
        return {k: p["values"][j] for (k, p), j in zip(params.items(), idx)}, rng
    out = {}
    for k, p in params.items():
        d = p["distribution"]
        if d == "lognormal":
            out[k] = float(p["median"] * np.exp(p["sigma"] * rng.standard_normal()))
        elif d == "normal":
            out[k] = float(p["mean"] + p["std"] * rng.standard_normal())
        else:
            out[k] = float(rng.uniform(p["low"], p["high"]))
    return out, rng


def evaluate_chunk(spec: dict, indices) -> dict:
    """Rows for samples ``indices`` (a task; runs in any worker).  Returns column arrays."""
    from physmodel import physics_model
    from physmodel.data.sweep import ComplexGaussianNoise, MagnitudePhaseNoise
    from physmodel.data.units import QUANTITY_UNITS, unit_scale

    base = _base(spec)
    draws = [sample_values(spec, int(i)) for i in indices]
    sets = []
    for vals, _ in draws:
        try:
            sets.append(base.replace(**vals))
        except IPMCError as exc:
            raise IPMCError(f"study sample with {vals}: {exc}") from None
    model = physics_model(spec["kind"], sets, kernel=spec.get("kernel", "boundary_charge"))
    q = spec["quantity"]
    f, T = np.asarray(spec["frequencies_hz"]), np.asarray(spec["temperatures_c"])
    _, in_u, _, out_u = QUANTITY_UNITS[(spec["kind"], q)]
    H = model.frequency_response(f, T, quantities=(q,))[q] * (unit_scale(in_u) / unit_scale(out_u))   # (n, nT, nf)
    nz = spec.get("noise")
    if nz:
        noise = (MagnitudePhaseNoise(nz.get("sigma_db", 0.1), nz.get("sigma_deg", 1.0)) if nz["kind"] == "magphase"
                 else ComplexGaussianNoise(nz.get("sigma", 0.01)))
        H = np.stack([noise.apply(H[k].ravel(), rng).reshape(H[k].shape) for k, (_, rng) in enumerate(draws)])
    n, nT, nf = H.shape
    cols = {"sample": np.repeat(np.asarray(indices, dtype=np.int64), nT * nf)}
    for name in spec["parameters"]:
        cols[name] = np.repeat([v[name] for v, _ in draws], nT * nf)
    cols["temperature_c"] = np.tile(np.repeat(T, nf), n)
    cols["frequency_hz"] = np.tile(f, n * nT)
    h = H.ravel()
    cols["magnitude_db"] = 20 * np.log10(np.abs(h))
    cols["phase_deg"] = np.degrees(np.angle(h))
    cols["real"], cols["imag"] = h.real, h.imag
    return cols


@dataclass(frozen=True)
class StudyTable:
    """A tidy study result: ``columns`` (name → 1-D array, one row per sample × T × f)."""

    columns: dict
    spec: dict
    backend: str
    elapsed_s: float
    metadata: dict = field(default_factory=dict)

    @property
    def n_rows(self) -> int:
        return int(next(iter(self.columns.values())).size)

    def equals(self, other: StudyTable) -> bool:
        """Bit-identical columns (the reproducibility contract)."""
        return list(self.columns) == list(other.columns) and all(
            np.array_equal(self.columns[k], other.columns[k]) for k in self.columns)

    def to_csv(self, path) -> Path:
        from physmodel.data.files import atomic_write
        from physmodel.data.units import QUANTITY_UNITS

        _, in_u, out_name, out_u = QUANTITY_UNITS[(self.spec["kind"], self.spec["quantity"])]

        def write(fh):
            fh.write("# ipmc-study 1\n")
            fh.write(f"# study: {self.spec['name']}\n# response: {out_name} [{out_u}/{in_u}] ({self.spec['quantity']})\n")
            fh.write(f"# spec: {json.dumps(self.spec, sort_keys=True)}\n")
            fh.write(",".join(self.columns) + "\n")
            cols = [c.tolist() for c in self.columns.values()]
            for row in zip(*cols):
                fh.write(",".join(repr(v) for v in row) + "\n")

        return atomic_write(path, write)

    def to_npz(self, path) -> Path:
        from physmodel.data.files import atomic_write

        def write(fh):
            np.savez(fh, header=np.array(json.dumps({"format": "ipmc-study", "version": 1, "spec": self.spec})),
                     **self.columns)

        return atomic_write(path, write, "wb")

    def save(self, path) -> Path:
        return by_extension(path, {".csv": self.to_csv, ".npz": self.to_npz}, "study table")(path)


def chunk_indices(spec) -> list[list[int]]:
    """The study's sample indices cut into chunks of ``spec["chunk_size"]`` (one task each)."""
    n, c = spec["samples"], spec["chunk_size"]
    return [list(range(a, min(a + c, n))) for a in range(0, n, c)]


def run_study(spec: dict, *, scheduler=None, workers: int | None = None, backend: str | None = None,
              progress=None, timeout_s: float = SCHEDULER_TIMEOUT_S) -> StudyTable:
    """Evaluate a validated study (:func:`parse_study`).

    ``backend``: "serial" (this process), "processes" (concurrent.futures, ``workers`` processes;
    the default) or "dask" (a ``distributed.Client`` on ``scheduler``: an address string or a
    Client/cluster object; the default when ``scheduler`` is given; an address is probed first,
    :func:`probe_scheduler`, with ``timeout_s``).  ``progress(n_chunks_done)``
    is called as chunks finish.  Results are assembled in sample order, identical across backends.
    """
    backend = backend or ("dask" if scheduler is not None else "processes")
    chunks = chunk_indices(spec)
    t0 = time.perf_counter()
    tick = progress or (lambda n: None)
    if backend == "serial":
        parts = []
        for c in chunks:
            parts.append(evaluate_chunk(spec, c))
            tick(1)
    elif backend == "processes":
        import concurrent.futures as cf
        import multiprocessing as mp

        parts = [None] * len(chunks)
        # workers ignore SIGINT/SIGTERM (a Ctrl-C reaches the whole process group): this process
        # reports the interrupt, sets `stop` (chunks already queued to a worker return at once) and
        # cancels what is left; no worker prints a traceback
        stop = mp.get_context().Event()
        ex = cf.ProcessPoolExecutor(max_workers=workers or min(len(chunks), os.cpu_count() or 1),
                                    initializer=_worker_init, initargs=(stop,))
        try:
            futs = {ex.submit(_chunk_task, spec, c): k for k, c in enumerate(chunks)}
            for fut in cf.as_completed(futs):
                parts[futs[fut]] = fut.result()
                tick(1)
        except BaseException:
            stop.set()
            _stop_workers(ex)
            raise
        ex.shutdown()
    elif backend == "dask":
        parts = _run_dask(spec, chunks, scheduler, tick, timeout_s)
    else:
        raise StudyError(f"backend must be 'serial', 'processes' or 'dask', got {backend!r}")
    cols = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return StudyTable(cols, spec, backend, time.perf_counter() - t0)


_STOP = None


def _worker_init(stop) -> None:
    """A study worker: SIGINT/SIGTERM ignored (:func:`physmodel.interrupts.worker_init`); ``stop``
    (a multiprocessing Event) set by the parent on an interrupt."""
    from physmodel.interrupts import worker_init

    global _STOP
    worker_init()
    _STOP = stop


def _chunk_task(spec, indices):
    """:func:`evaluate_chunk` in a worker, or None at once when the parent has stopped the study."""
    if _STOP is not None and _STOP.is_set():
        return None
    return evaluate_chunk(spec, indices)


def _stop_workers(ex) -> None:
    """Cancel the chunks not started; the workers finish the chunk they hold and exit (they ignore
    SIGINT/SIGTERM, :func:`physmodel.interrupts.worker_init`: a worker killed while it sends its
    result back would leave the executor — and this process's exit — waiting forever)."""
    ex.shutdown(wait=False, cancel_futures=True)


#: A Dask handshake is a few hundred bytes; a first frame announcing more is another protocol.
_MAX_HANDSHAKE_BYTES = 1 << 20


def probe_scheduler(address: str, timeout_s: float = SCHEDULER_TIMEOUT_S) -> None:
    """Check that ``address`` (``tcp://HOST:PORT``) is a Dask scheduler before a client connects: it
    must accept within ``timeout_s`` and send the start of a Dask handshake (a scheduler speaks
    first: an 8-byte frame length, then the frames) within ``timeout_s``.  A port that accepts and
    stays silent, or answers another protocol (an HTTP or SSH server, whose first bytes read as a
    length of exabytes), is a StudyError naming the address — the Dask client itself would wait
    forever or try to allocate that length."""
    import socket
    import struct

    scheme, sep, loc = address.partition("://")
    if not sep:
        scheme, loc = "tcp", address
    if scheme not in ("tcp", "tls"):
        return                                      # inproc://, ucx://: the client's own checks
    host, _, port = loc.rpartition(":")
    host = host.strip("[]")
    try:
        port_n = int(port.split("/")[0])
    except ValueError:
        raise StudyError(f"--scheduler {address!r}: expected an address such as tcp://HOST:8786") from None
    where = f"--scheduler {address}"
    try:
        sock = socket.create_connection((host or "localhost", port_n), timeout=timeout_s)
    except TimeoutError:
        raise StudyError(f"{where}: no connection within {timeout_s:g} s") from None
    except OSError as exc:
        raise StudyError(f"{where}: cannot connect ({exc.strerror or exc}); expected a Dask scheduler "
                         "such as tcp://HOST:8786") from None
    if scheme == "tls":                             # the TLS handshake comes first: cannot read Dask's
        sock.close()
        return
    try:
        sock.settimeout(timeout_s)
        head = b""
        deadline = time.monotonic() + timeout_s
        while len(head) < 8:
            sock.settimeout(max(0.01, deadline - time.monotonic()))
            chunk = sock.recv(8 - len(head))
            if not chunk:
                raise StudyError(f"{where}: the server closed the connection without a Dask handshake")
            head += chunk
    except TimeoutError:
        raise StudyError(f"{where}: accepted the connection but sent no Dask handshake within {timeout_s:g} s; is "
                         "it a Dask scheduler (dask scheduler --port ...)?") from None
    except OSError as exc:
        raise StudyError(f"{where}: connection failed during the handshake ({exc.strerror or exc})") from None
    finally:
        sock.close()
    (n,) = struct.unpack("Q", head)          # native order, as distributed.comm.tcp
    if not 0 < n <= _MAX_HANDSHAKE_BYTES:
        raise StudyError(f"{where}: answered {head!r}, not a Dask handshake (another protocol on that port?)")


def _run_dask(spec, chunks, scheduler, tick, timeout_s: float = SCHEDULER_TIMEOUT_S):
    try:
        from distributed import Client, as_completed
    except ModuleNotFoundError:
        raise StudyError("the Dask backend needs dask[distributed]: pip install 'ipmc[dask]'") from None
    own = isinstance(scheduler, str)
    if own:
        probe_scheduler(scheduler, timeout_s)
    try:
        client = Client(scheduler, timeout=f"{timeout_s}s") if own else (scheduler if isinstance(scheduler, Client)
                                                                         else Client(scheduler))
    except (ValueError, TypeError, OSError, TimeoutError) as exc:   # malformed or unreachable address
        raise StudyError(f"--scheduler {scheduler!r}: cannot connect to a Dask scheduler "
                         f"({type(exc).__name__}: {exc}); expected an address such as tcp://HOST:8786") from None
    try:
        futs = [client.submit(evaluate_chunk, spec, c, key=f"ipmc-study-{spec['name']}-{spec['seed']}-{k}-{os.getpid()}",
                              pure=False) for k, c in enumerate(chunks)]
        index = {f.key: k for k, f in enumerate(futs)}
        parts = [None] * len(chunks)
        for fut in as_completed(futs):
            parts[index[fut.key]] = fut.result()
            tick(1)
        return parts
    finally:
        if client is not scheduler:
            client.close()


__all__ = ["parse_study", "load_study", "run_study", "probe_scheduler", "SCHEDULER_TIMEOUT_S", "evaluate_chunk", "chunk_indices", "sample_values", "StudyTable", "StudyError"]
