"""The one model file: a physics model (parameters, temperature laws, effects) with the verdict of
the data it was fitted to and where it came from.

``ipmc calibrate`` and ``ipmc diagnose`` write it (``FOLDER/model.json``); every command that takes
physics reads it (``--model FILE``, or ``--set FILE``), and :func:`load_model` reads it in Python:

>>> mf = load_model("diag/model.json")          # doctest: +SKIP
>>> mf.model().response([1.0], [35.0])           # the physics with its effects  # doctest: +SKIP
>>> mf.adequate, mf.verdict.reason               # did it fit its data?           # doctest: +SKIP

A model file holds

- ``kind`` (actuator | sensor), the fitted ``quantity`` and the sensing ``kernel``;
- ``parameters``: an :class:`~physmodel.IPMCParameters` with its temperature laws (SI);
- ``effects``: ``{effect name: {parameter: value}}`` switched on in the model (SI; see
  :mod:`physmodel.effects`) — for a diagnosis the baseline's effects plus the named ones, refitted;
- ``verdict``: a :class:`FitVerdict` — the goodness-of-fit test of the model against the data it
  was fitted to (χ², dof, p, adequate or not, and the diagnosis verdict when there was one); None
  when the model was never compared with data (a named set);
- ``estimates``: the fitted parameters with their 95 % intervals (as the fit reported them);
- ``provenance``: a :class:`Provenance` — the data file and its SHA-256, the temperatures and band
  fitted, the command line, the library version.

Files written by older versions load too: a ``parameters.json`` of ``ipmc calibrate`` (format
``ipmc-parameter-set`` with the calibration record inside: its goodness of fit becomes the
verdict, its fixed effects the effects) and a bare parameter record (no verdict).
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from .errors import ParameterError
from .fit_record import FitVerdict, Provenance, file_sha256
from .formats import (
    MODEL_FORMAT,
    MODEL_VERSION,
    PARAMETER_SET_FORMAT,
    PARAMETER_SET_VERSION,
    finite_json,
    read_json,
)
from .params import IPMCParameters


@dataclass(frozen=True)
class ModelFile:
    """A physics model with its data's verdict and provenance (see the module doc).

    Parameters
    ----------
    kind : str
        ``"actuator"`` or ``"sensor"``.
    parameters : IPMCParameters
        Parameters and temperature laws (SI).
    effects : dict
        ``{effect name: {parameter: value}}`` switched on (SI).
    quantity : str or None
        The quantity fitted (actuator M/H/Z/I, sensor S/Z); None for the kind's primary one.
    kernel : str
        Sensing kernel (sensors).
    verdict : FitVerdict or None
        The data's verdict; None when the model was never compared with data.
    estimates : tuple of dict
        Fitted parameters: name, value, ci95 [lower, upper], status. [SI]
    provenance : Provenance or None
        Where it came from.
    path : str or None
        The file it was read from (not written).
    """

    kind: str
    parameters: IPMCParameters
    effects: dict = field(default_factory=dict)
    quantity: str | None = None
    kernel: str = "boundary_charge"
    verdict: FitVerdict | None = None
    estimates: tuple = ()
    provenance: Provenance | None = None
    path: str | None = None

    def __post_init__(self):
        if self.kind not in ("actuator", "sensor"):
            raise ParameterError(f"model kind must be 'actuator' or 'sensor', got {self.kind!r}")
        if not isinstance(self.parameters, IPMCParameters):
            raise ParameterError(f"model parameters must be IPMCParameters, got {type(self.parameters).__name__}")
        from .effects import normalize_effects

        object.__setattr__(self, "effects", {k: dict(v) for k, v in normalize_effects(self.effects or {}).items()})

    # -------------------------------------------------------------- views
    @property
    def name(self) -> str:
        """The parameter set's name."""
        return self.parameters.name

    @property
    def checked(self) -> bool:
        """Whether the model was compared with data (it carries a verdict)."""
        return self.verdict is not None

    @property
    def adequate(self) -> bool | None:
        """True/False: the model fits / does not fit its data; None: never compared with data."""
        return None if self.verdict is None else bool(self.verdict.adequate)

    def model(self, params: IPMCParameters | None = None):
        """The model (the one interface, :mod:`physmodel.protocol`): the physics of ``kind`` with
        the effects switched on (:func:`physmodel.effects.EffectModel`), or the plain physics when
        there are none.

        Parameters
        ----------
        params : IPMCParameters or None
            Parameters replacing the file's (e.g. with overrides); default the file's.
        """
        p = self.parameters if params is None else params
        if self.effects:
            from .effects import EffectModel

            return EffectModel(p, self.kind, self.effects, kernel=self.kernel)
        from .protocol import physics_model

        return physics_model(self.kind, p, kernel=self.kernel)

    def describe(self) -> str:
        """One line: name, kind, effects, verdict."""
        eff = "; ".join(f"{k} ({', '.join(f'{p} = {v:.4g}' for p, v in e.items())})" for k, e in self.effects.items())
        ver = "not compared with data" if self.verdict is None else self.verdict.line()
        return f"`{self.name}` ({self.kind}" + (f", effects: {eff}" if eff else ", no effects") + f"): {ver}"

    def with_parameters(self, params: IPMCParameters) -> ModelFile:
        """A copy with other parameters (the verdict and provenance are kept: say so where it matters).

        Parameters
        ----------
        params : IPMCParameters
            The new parameters.
        """
        return replace(self, parameters=params)

    # -------------------------------------------------------------- files
    def to_dict(self) -> dict:
        """JSON-ready data (format ``ipmc-model`` 1; infinities as "inf")."""
        return finite_json({
            "format": MODEL_FORMAT, "version": MODEL_VERSION, "kind": self.kind, "quantity": self.quantity,
            "kernel": self.kernel, "parameters": self.parameters.to_dict(),
            "effects": {k: {p: float(v) for p, v in e.items()} for k, e in self.effects.items()},
            "verdict": None if self.verdict is None else self.verdict.to_dict(),
            "estimates": [dict(e) for e in self.estimates],
            "provenance": None if self.provenance is None else self.provenance.to_dict()})

    def fingerprint(self) -> str:
        """SHA-256 of the model's content (parameters, laws, effects, verdict, provenance), independent
        of formatting: what a sweep, a surrogate and a feedforward report cite."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()

    def save(self, path) -> Path:
        """Write the model file atomically and return its path.

        Parameters
        ----------
        path : str or Path
            The JSON file to write.
        """
        from .data.files import atomic_write

        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        return atomic_write(Path(path), lambda fh: fh.write(text + "\n"))

    @classmethod
    def from_dict(cls, d: dict, where: str = "model file", path: str | None = None) -> ModelFile:
        """Read the ``ipmc-model`` format (see :func:`load_model` for older formats).

        Parameters
        ----------
        d : dict
            The file's data.
        where : str
            The file, for messages.
        path : str or None
            Recorded as :attr:`path`.
        """
        if d.get("format") != MODEL_FORMAT:
            raise ParameterError(f"{where} has format {d.get('format')!r}, expected {MODEL_FORMAT!r}")
        version = d.get("version")
        if isinstance(version, bool) or not isinstance(version, int) or not 1 <= version <= MODEL_VERSION:
            raise ParameterError(f"{where}: version {version!r}; this library reads {MODEL_FORMAT} versions 1 to "
                                 f"{MODEL_VERSION}")
        missing = [k for k in ("kind", "parameters") if k not in d]
        if missing:
            raise ParameterError(f"{where}: missing key(s) {missing}")
        try:
            params = IPMCParameters.from_dict(dict(d["parameters"]))
        except (ParameterError, TypeError, ValueError) as exc:
            raise ParameterError(f"{where}: parameters: {exc}") from None
        effects = d.get("effects") or {}
        if not isinstance(effects, dict) or not all(isinstance(v, dict) for v in effects.values()):
            raise ParameterError(f"{where}: 'effects' must be an object of {{effect: {{parameter: value}}}}, got {effects!r}")
        verdict = None if d.get("verdict") is None else FitVerdict.from_dict(d["verdict"], where)
        prov = None if d.get("provenance") is None else Provenance.from_dict(d["provenance"], where)
        est = d.get("estimates") or []
        if not (isinstance(est, list) and all(isinstance(e, dict) for e in est)):
            raise ParameterError(f"{where}: 'estimates' must be a list of objects, got {est!r}")
        try:
            return cls(str(d["kind"]), params, {k: {p: float(v) for p, v in e.items()} for k, e in effects.items()},
                       d.get("quantity"), str(d.get("kernel") or "boundary_charge"), verdict,
                       tuple(est), prov, path)
        except (ParameterError, TypeError, ValueError) as exc:
            raise ParameterError(f"{where}: {exc}") from None


def _legacy(data: dict, where: str, kind: str | None, path: str) -> ModelFile:
    """A model from an ``ipmc-parameter-set`` file (what ``ipmc calibrate`` wrote before the model
    file) or a bare parameter record."""
    record = data
    cal = None
    if "parameters" in data:
        if data.get("format") != PARAMETER_SET_FORMAT:
            raise ParameterError(f"{where} has format {data.get('format')!r}, expected {MODEL_FORMAT!r} (or the older "
                                 f"{PARAMETER_SET_FORMAT!r})")
        version = data.get("version", 0)
        if isinstance(version, bool) or not isinstance(version, int) or version < 0:
            raise ParameterError(f"{where}: version must be a non-negative integer, got {version!r}")
        if version > PARAMETER_SET_VERSION:
            raise ParameterError(f"{where} has version {version}, this library reads up to {PARAMETER_SET_VERSION}")
        record = data["parameters"]
        cal = data.get("calibration")
    elif "calibration" in data and "parameters" not in data:
        raise ParameterError(f"{where} holds a calibration record without parameters (the calibration did not "
                             "produce a parameter set); use the folder's model.json")
    if not isinstance(record, dict):
        raise ParameterError(f"{where} holds {type(record).__name__}, expected an object")
    try:
        params = IPMCParameters.from_dict(dict(record))
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    verdict, effects, quantity, kernel, prov = None, {}, None, "boundary_charge", None
    if isinstance(cal, dict):
        meta = cal.get("metadata") or {}
        if cal.get("goodness_of_fit"):
            verdict = FitVerdict.from_goodness(cal["goodness_of_fit"])
        if kind is not None and meta.get("kind") not in (None, "", kind):
            raise ParameterError(f"{where} holds a model of kind {meta['kind']!r} (its calibration record says so); "
                                 f"this command needs kind {kind!r} (--kind)")
        kind = kind or meta.get("kind")
        quantity = meta.get("quantity") or None
        kernel = meta.get("kernel") or "boundary_charge"
        if meta.get("effects"):
            # the old writer stored metadata values with str(): a dict literal
            try:
                effects = ast.literal_eval(meta["effects"]) if isinstance(meta["effects"], str) else meta["effects"]
            except (ValueError, SyntaxError):
                raise ParameterError(f"{where}: calibration metadata 'effects' = {meta['effects']!r} cannot be read; "
                                     "recalibrate with this version to get a model.json") from None
        band = cal.get("band_hz")
        prov = Provenance("ipmc calibrate (older parameters.json)", meta.get("sweep_file"), None, None,
                          tuple(cal.get("temperatures_c") or ()), None if band is None else tuple(band))
    return ModelFile(kind or "actuator", params, effects, quantity, kernel, verdict, (), prov, path)


def load_model(source: str | os.PathLike, *, kind: str | None = None, **overrides: Any) -> ModelFile:
    """A model file, an older parameter file, or a named parameter set, as a :class:`ModelFile`.

    Parameters
    ----------
    source : str or path
        A model file (``ipmc-model``), a parameter file (``ipmc-parameter-set``, e.g. an older
        ``ipmc calibrate`` output, or a bare record), or a name from
        :func:`~physmodel.available_parameter_sets` (no verdict: never compared with data).
    kind : str or None
        ``"actuator"`` or ``"sensor"``: required for a named set or a bare record (default
        actuator); for a file that states its kind, a different one is an error.
    **overrides
        Parameter fields to override (SI). The verdict then describes the file's parameters, not
        the overridden ones: the caller must say so.

    Returns
    -------
    ModelFile
    """
    from .parameter_sets import available_parameter_sets, get_parameter_set

    text = os.fspath(source)
    if text in available_parameter_sets():
        mf = ModelFile(kind or "actuator", get_parameter_set(text))
    else:
        path = Path(text)
        if not (text.lower().endswith(".json") or path.is_file()):
            raise ParameterError(f"unknown parameter set {text!r} (and no such model file); expected one of "
                                 f"{available_parameter_sets()} or the path of a JSON model/parameter file")
        if not path.is_file():
            raise ParameterError(f"model file {text!r} does not exist")
        where = f"model file {text!r}"
        data = read_json(path, "model file")
        if not isinstance(data, dict):
            raise ParameterError(f"{where} holds {type(data).__name__}, expected an object")
        if data.get("format") == MODEL_FORMAT:
            mf = ModelFile.from_dict(data, where, path=text)
        else:
            mf = _legacy(data, where, kind, text)
        if kind is not None and mf.kind != kind:
            raise ParameterError(f"{where} holds a model of kind {mf.kind!r}; this command needs kind {kind!r} (--kind)")
    if overrides:
        mf = mf.with_parameters(mf.parameters.replace(**overrides))
    return mf


__all__ = ["ModelFile", "FitVerdict", "Provenance", "load_model", "file_sha256", "finite_json",
           "MODEL_FORMAT", "MODEL_VERSION", "PARAMETER_SET_FORMAT", "PARAMETER_SET_VERSION"]
