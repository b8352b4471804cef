"""The column and unit options of the commands that read a user's own files.

One place adds them and turns them into the mapping arguments of the readers
(:func:`physmodel.data.timerecord.read_record`, :func:`physmodel.data.files.read_sweep`):

* time records (``ipmc frf``, ``ipmc invert``): ``--time-column NAME|INDEX [--time-unit s|ms|us]``,
  ``--input-column NAME|INDEX --input-unit UNIT``, ``--output-column ... --output-unit ...``
  (repeatable where the command takes several outputs);
* sweeps (``ipmc calibrate``, ``fit``, ``diagnose``, and the ``--data`` of ``invert`` and
  ``feedforward``): ``--sweep-columns temperature=T_degC,frequency=freq_Hz,magnitude=gain_dB,
  phase=phase_deg[,magnitude_std=...,phase_std=...]``, ``--sweep-units input=V,output=mm[,magnitude=dB|linear,
  phase=deg|rad,frequency=Hz|rad/s,temperature=degC|K]`` and ``--sweep-temperature T``.

A mapping problem is a :class:`~physmodel.data.columns.ColumnMapError` naming the reader's
argument; :func:`read_record_mapped` and :func:`read_sweep_mapped` re-raise it as a
:class:`CLIError` (exit 2) naming the option that fixes it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._common import CLIError

__all__ = ["add_record_options", "add_sweep_options", "record_mapping", "read_record_mapped", "sweep_mapping",
           "read_sweep_mapped", "read_columns", "pick_column", "record_time", "column_values"]

TIME_UNITS = ("s", "ms", "us", "min")


# ---------------------------------------------------------------------------- time records
def add_record_options(p, roles=("input", "output"), *, repeat=("output",), time_default: str | None = None):
    """Add ``--time-column``, ``--time-unit`` and ``--<role>-column``/``--<role>-unit`` per role."""
    g = p.add_argument_group("columns of a record not written by ipmc (e.g. a DAQ's 't, volts, disp')")
    g.add_argument("--time-column", metavar="NAME|INDEX", default=time_default,
                   help=f"time column, by name or 0-based index (default {time_default or 'time_s'})")
    g.add_argument("--time-unit", choices=TIME_UNITS, help="unit of the time column (default s)")
    for role in roles:
        many = role in repeat
        g.add_argument(f"--{role}-column", metavar="NAME|INDEX", action="append" if many else "store",
                       help=f"{role} column by name or 0-based index" + (" (one per --output)" if many else ""))
        g.add_argument(f"--{role}-unit", metavar="UNIT", action="append" if many else "store",
                       help=f"unit of the {role} column (V, mm, m, uA, ...) when its name has no '_<unit>' suffix"
                            + (" (one per --output, or one for all)" if many else ""))
    return g


def _spec(text):
    return int(text) if isinstance(text, str) and text.strip().isdigit() else text


def _per_channel(args, role: str, names: list) -> list[tuple]:
    """[(channel name, column spec, unit)] of ``role``; one option value per channel (a unit may
    be given once for all)."""
    cols = getattr(args, f"{role}_column", None)
    units = getattr(args, f"{role}_unit", None)
    cols = cols if isinstance(cols, list) else ([cols] if cols is not None else None)
    units = units if isinstance(units, list) else ([units] if units is not None else None)
    if cols is not None and len(cols) != len(names):
        raise CLIError(f"--{role}-column: {len(cols)} value(s) for {len(names)} {role} channel(s) {names}; give one each")
    if units is not None and len(units) not in (1, len(names)):
        raise CLIError(f"--{role}-unit: {len(units)} value(s) for {len(names)} {role} channel(s) {names}; give one "
                       "each or one for all")
    return [(n, _spec(cols[k]) if cols else n, (units[k] if len(units) > 1 else units[0]) if units else None)
            for k, n in enumerate(names)]


def record_mapping(args, channels: dict) -> dict:
    """``{'columns': ..., 'units': ...}`` for :func:`read_record` from the options, or ``{}`` when
    none is given (the file is then read as an ``ipmc-timeseries`` record).  ``channels``: role →
    channel name(s) the command uses (e.g. ``{'input': 'voltage', 'output': ['tip']}``)."""
    roles = {r: (n if isinstance(n, list) else [n]) for r, n in channels.items()}
    given = [args.time_column, args.time_unit] + [getattr(args, f"{r}_{w}", None) for r in roles for w in ("column", "unit")]
    if all(v is None for v in given):
        return {}
    columns: dict = {"time": _spec(args.time_column or "time_s")}
    units: dict = {"time": args.time_unit} if args.time_unit else {}
    for role, names in roles.items():
        for name, spec, unit in _per_channel(args, role, names):
            if name is None:
                continue
            if name in columns and columns[name] != spec:
                raise CLIError(f"channel {name!r} is named twice with different columns")
            columns[name] = spec
            if unit is not None:
                units[name] = unit
    return {"columns": columns, "units": units}


def _record_option(exc: Any, channels: dict) -> str:
    if exc.key == "time":
        return "--time-unit" if exc.argument == "units" else "--time-column"
    for role, names in channels.items():
        if exc.key in (names if isinstance(names, list) else [names]):
            return f"--{role}-{'unit' if exc.argument == 'units' else 'column'}"
    return "--temperature" if exc.argument == "temperature_c" else "--time-column/--input-column/--output-column"


def read_record_mapped(path, args, channels: dict, option: str = "RECORD"):
    """The time record at ``path`` read with the options' mapping (:func:`record_mapping`); a
    mapping problem is a CLIError naming the option that fixes it."""
    from physmodel.data.columns import ColumnMapError
    from physmodel.data.timerecord import read_record

    if not Path(path).exists():
        raise CLIError(f"{option} {path}: no such file")
    try:
        return read_record(path, **record_mapping(args, channels))
    except ColumnMapError as exc:
        raise CLIError(f"{_record_option(exc, channels)}: {exc}") from None


def read_columns(path, option: str):
    """The named columns of ``path`` (CSV, NPZ or MAT: :func:`physmodel.data.columns.read_table`),
    for a command that picks its columns itself (``--column``-style options, no channel units
    needed); a missing file is a CLIError naming ``option``."""
    from physmodel.data.columns import read_table

    if not Path(path).exists():
        raise CLIError(f"{option} {path}: no such file")
    return read_table(path, "data")


def pick_column(table, spec, option: str, key: str) -> str:
    """The column of ``table`` that ``spec`` names (a name, the ``<name>`` of a ``<name>_<unit>``
    column, or a 0-based index: :func:`physmodel.data.columns.pick`); a column that is not there is
    a CLIError ``'<option>: <file>: columns[<key>] = <spec>: no such column; the file has 0:t, 1:...'``,
    the wording of the record options of ``ipmc frf``."""
    from physmodel.data.columns import ColumnMapError, pick

    try:
        return pick(table, spec, key)
    except ColumnMapError as exc:
        raise CLIError(f"{option}: {exc}") from None


def record_time(table, args):
    """``(time column, times [s])`` of ``table`` from ``--time-column``/``--time-unit`` (default
    ``time_s``; the unit from the column name's suffix, else s); a problem names the option."""
    from physmodel.data.columns import ColumnMapError, time_column

    columns = {} if args.time_column is None else {"time": _spec(args.time_column)}
    units = {} if args.time_unit is None else {"time": args.time_unit}
    try:
        return time_column(table, columns, units)
    except ColumnMapError as exc:
        raise CLIError(f"{'--time-unit' if exc.argument == 'units' else '--time-column'}: {exc}") from None


def column_values(table, name: str, option: str, n: int):
    """The samples of column ``name`` (chosen by ``option``), refused unless there are ``n`` of them
    (the time column's) and every one is finite."""
    import numpy as np

    v = table.data[name]
    if v.size != n:
        raise CLIError(f"{option}: {table.where}: column {name!r} has {v.size} value(s); the time column has {n}")
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        raise CLIError(f"{option}: {table.where}: column {name!r} is not finite at sample(s) {bad[:5].tolist()} "
                       "(0-based); expected finite numbers")
    return v


# ---------------------------------------------------------------------------- sweeps
def add_sweep_options(p, what: str = "the sweep"):
    """Add ``--sweep-columns``, ``--sweep-units`` and ``--sweep-temperature``."""
    g = p.add_argument_group(f"columns of {what} when it is not an ipmc sweep file (e.g. an analyser's)")
    g.add_argument("--sweep-columns", action="append", metavar="ROLE=NAME|INDEX,...",
                   help="roles temperature, frequency, magnitude, phase, magnitude_std, phase_std, e.g. "
                        "temperature=T_degC,frequency=freq_Hz,magnitude=gain_dB,phase=phase_deg")
    g.add_argument("--sweep-units", action="append", metavar="KEY=UNIT,...",
                   help="input=V,output=mm (the response is output/input); magnitude=dB|linear, phase=deg|rad, "
                        "frequency=Hz|rad/s, temperature=degC|K (default: from the column names, else dB, deg, Hz, degC)")
    g.add_argument("--sweep-temperature", type=float, metavar="T",
                   help="temperature of every line [°C] for a file without a temperature column")
    return g


def _pairs(items, option: str) -> dict:
    out: dict = {}
    for item in items or []:
        for part in item.split(","):
            if not part.strip():
                continue
            if "=" not in part:
                raise CLIError(f"{option} {item!r}: expected KEY=VALUE pairs separated by commas")
            k, v = (x.strip() for x in part.split("=", 1))
            if not k or not v:
                raise CLIError(f"{option} {part!r}: expected KEY=VALUE")
            out[k] = v
    return out


def sweep_mapping(args) -> dict:
    """``{'columns', 'units', 'temperature_c'}`` for :func:`read_sweep` (empty when no option is given)."""
    columns = {k: _spec(v) for k, v in _pairs(getattr(args, "sweep_columns", None), "--sweep-columns").items()}
    units = _pairs(getattr(args, "sweep_units", None), "--sweep-units")
    T = getattr(args, "sweep_temperature", None)
    if not columns and not units and T is None:
        return {}
    return {"columns": columns, "units": units, "temperature_c": T}


def read_sweep_mapped(path, args, option: str = "SWEEP_FILE"):
    """The sweep at ``path`` read with the options' mapping; a problem a mapping entry fixes is a
    CLIError naming ``--sweep-columns ROLE=...``, ``--sweep-units KEY=...`` or ``--sweep-temperature``."""
    from physmodel.data.columns import ColumnMapError
    from physmodel.data.files import read_sweep

    if not Path(path).exists():
        raise CLIError(f"{option} {path}: no such file")
    try:
        return read_sweep(path, **sweep_mapping(args))
    except ColumnMapError as exc:
        opt = {"columns": f"--sweep-columns {exc.key}=NAME|INDEX", "units": f"--sweep-units {exc.key}=UNIT",
               "temperature_c": "--sweep-temperature"}[exc.argument]
        raise CLIError(f"{opt}: {option} {exc}") from None


# ---------------------------------------------------------------------------- signal kind and unit
def surrogate_role(labels: dict) -> str:
    """'an actuator surrogate (mm/V)', 'a sensor surrogate (uA/mm)' or 'a surrogate (out/in)'."""
    from physmodel.data.units import UNITS

    iu, ou = labels.get("input_unit") or "?", labels.get("output_unit") or "?"
    kinds = (UNITS.get(iu, ("?",))[0], UNITS.get(ou, ("?",))[0])
    what = {("voltage", "length"): "an actuator surrogate", ("length", "current"): "a sensor surrogate"}.get(kinds, "a surrogate")
    return f"{what} ({labels.get('output_name') or 'output'} [{ou}] per {labels.get('input_name') or 'input'} [{iu}])"


def signal_scale(column: str, unit: str | None, labels: dict, command: str, fix: str) -> float:
    """Factor taking the samples of ``column`` (in ``unit``; None: not stated) into the unit of the
    surrogate's output (``labels['output_unit']``), whose signal the command inverts.

    Another kind of quantity (a current column for an actuator surrogate, a displacement column
    for a sensor surrogate) is a CLIError; another unit of the same kind (m for mm) is converted
    and said on stderr; a column without a stated unit is taken in the surrogate's unit and said
    on stderr (``fix``: the option that states it)."""
    import sys

    from physmodel.data.units import UNITS

    want = labels.get("output_unit") or ""
    if want not in UNITS:
        if unit is not None:
            print(f"{command}: warning: the surrogate states no known output unit ({want!r}); column {column!r} "
                  f"[{unit}] is used unchecked", file=sys.stderr)
        return 1.0
    if unit is None:
        print(f"{command}: note: column {column!r} states no unit; taken to be in {want} like the output of "
              f"{surrogate_role(labels)} (state it with {fix} UNIT)", file=sys.stderr)
        return 1.0
    if unit not in UNITS:
        raise CLIError(f"{fix} {unit}: not a unit of the library; expected one of {sorted(UNITS)}")
    have_kind, want_kind = UNITS[unit][0], UNITS[want][0]
    if have_kind != want_kind:
        raise CLIError(f"column {column!r} holds a {have_kind} [{unit}], but {surrogate_role(labels)} needs its output, a "
                       f"{want_kind} [{want}]: give the surrogate whose output is this signal, or the {want_kind} "
                       f"column (its unit with {fix})")
    k = UNITS[unit][1] / UNITS[want][1]
    if k != 1.0:
        print(f"{command}: note: column {column!r} is in {unit}; converted to the surrogate's {want} (×{k:g})",
              file=sys.stderr)
    return k


def reference_column_unit(path, column) -> tuple[str | None, str | None]:
    """(column, unit in its name or None) of the value column of a reference file: ``column`` (a
    name, the ``<name>`` of a ``<name>_<unit>`` column, or a 0-based index) or, when None, the
    first column that is not ``time_s`` (None when there is none: the reader then says what is
    missing).  A column that is not there is a CLIError naming ``--reference-column`` in the
    wording of :func:`pick_column`; a missing file names ``--reference-file``."""
    from physmodel.data.columns import suffix_unit

    table = read_columns(path, "--reference-file")
    name: str | None = pick_column(table, column, "--reference-column", "reference") if column is not None else \
        next((n for n in table.names if n != "time_s"), None)
    return name, (suffix_unit(name) or (None, None))[1] if name is not None else None
