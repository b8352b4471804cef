"""Named parameter sets, one module per source, each with its source; look them up with
:func:`get_parameter_set`.

Modules: :mod:`~physmodel.parameter_sets.dev` (development values; ``dev``, ``seed000_sensor_dev``,
``seed001_actuator_dev``), :mod:`~physmodel.parameter_sets.seed000` (``seed000_sensor``),
:mod:`~physmodel.parameter_sets.seed001` (``seed001_actuator``),
:mod:`~physmodel.parameter_sets.seed002` (``seed002_table2``, ``seed002_table3``);
:mod:`~physmodel.parameter_sets.derivation` re-derives the calibrated sets
(``python3 -m physmodel.parameter_sets.derivation``); :mod:`~physmodel.parameter_sets.published`
holds the seed papers' printed numbers (``published.toml``, shipped with the package).

A new source is one new module here that defines ``SETS = {name: factory}``; it is found
automatically.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..params import IPMCParameters

#: Modules of this package that are not parameter-set sources.
_NOT_SOURCES = ("derivation", "published")


def _discover() -> dict[str, Callable[[], IPMCParameters]]:
    """Every ``SETS`` mapping of the modules in this package (one module per source)."""
    import importlib
    import pkgutil

    found: dict[str, Callable[[], IPMCParameters]] = {}
    for info in pkgutil.iter_modules(__path__):
        if info.name in _NOT_SOURCES:
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        for name, factory in getattr(mod, "SETS", {}).items():
            if name in found:
                raise ParameterError(f"parameter set {name!r} is defined twice (module {info.name})")
            found[name] = factory
    return found


_REGISTRY: dict[str, Callable[[], IPMCParameters]] = _discover()
def available_parameter_sets() -> list[str]:
    """Names accepted by :func:`get_parameter_set`."""
    return sorted(_REGISTRY)


def get_parameter_set(name: str | os.PathLike, **overrides: Any) -> IPMCParameters:
    """The named parameter set, with any field overridden (``omega_n=`` adjusts ``rho``).

    ``name`` may also be the path of a JSON parameter file (what ``ipmc calibrate`` writes, or
    :func:`save_parameter_set`): any string ending in ``.json``, or an existing path.

    >>> p = get_parameter_set("seed002_table3", W=2e-3)
    """
    text = os.fspath(name)
    if text in _REGISTRY:
        p = _REGISTRY[text]()
    elif text.lower().endswith(".json") or Path(text).is_file():
        p = load_parameter_set(text)
    else:
        raise ParameterError(f"unknown parameter set {text!r}; expected one of {available_parameter_sets()} "
                             "or the path of a JSON parameter file")
    return p.replace(**overrides) if overrides else p


def save_parameter_set(params: IPMCParameters, path: str | os.PathLike) -> Path:
    """Write ``params`` as a versioned JSON parameter file (atomically) and return its path (no
    verdict, no effects: :class:`physmodel.ModelFile` writes a whole model)."""
    from ..data.files import atomic_write
    from ..formats import PARAMETER_SET_FORMAT, PARAMETER_SET_VERSION, finite_json

    path = Path(path)
    payload = {"format": PARAMETER_SET_FORMAT, "version": PARAMETER_SET_VERSION,
               "parameters": finite_json(params.to_dict())}
    text = json.dumps(payload, indent=2, allow_nan=False)
    atomic_write(path, lambda fh: fh.write(text + "\n"))
    return path


def load_parameter_set(path: str | os.PathLike) -> IPMCParameters:
    """The parameters of a JSON model file (``ipmc calibrate``/``ipmc diagnose``'s ``model.json``), of
    a parameter file written by :func:`save_parameter_set` or an older ``ipmc calibrate``, or of a
    bare parameter record.  Effects and the data's verdict are not parameters: read the whole model
    with :func:`physmodel.load_model`."""
    from ..formats import MODEL_FORMAT, MODEL_VERSION, PARAMETER_SET_FORMAT, PARAMETER_SET_VERSION, read_json

    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"parameter file {str(path)!r} does not exist")
    data = read_json(path, "parameter file")
    if isinstance(data, dict) and "parameters" in data:
        known = {PARAMETER_SET_FORMAT: PARAMETER_SET_VERSION, MODEL_FORMAT: MODEL_VERSION}
        fmt = data.get("format")
        if fmt not in known:
            raise ParameterError(f"parameter file {str(path)!r} has format {fmt!r}, expected one of {sorted(known)}")
        version = data.get("version", 0)
        if isinstance(version, bool) or not isinstance(version, int) or version < 0:
            raise ParameterError(f"parameter file {str(path)!r}: version must be a non-negative integer, "
                                 f"got {version!r}")
        if version > known[fmt]:
            raise ParameterError(f"parameter file {str(path)!r} has {fmt} version {version}, "
                                 f"this library reads up to {known[fmt]}")
        data = data["parameters"]
    if not isinstance(data, dict):
        raise ParameterError(f"parameter file {str(path)!r} holds {type(data).__name__}, expected an object")
    try:
        return IPMCParameters.from_dict(data)
    except ParameterError as exc:
        raise ParameterError(f"parameter file {str(path)!r}: {exc}") from None


def register_parameter_set(name: str, factory: Callable[[], IPMCParameters], *, overwrite: bool = False) -> None:
    """Register a parameter set (e.g. a calibrated one) under ``name``."""
    if name in _REGISTRY and not overwrite:
        raise ParameterError(f"parameter set {name!r} exists; pass overwrite=True to replace it")
    _REGISTRY[name] = factory
