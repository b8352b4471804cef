"""The verdict of the data a model was fitted to (:class:`FitVerdict`) and where the model came
from (:class:`Provenance`): the two records a :class:`~physmodel.ModelFile` carries beside the
physics, so that every command downstream can say whether the model fits and check that the data
it names are still the data it was fitted to."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

from .errors import ParameterError


def _num(v) -> float | None:
    if v is None:
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def file_sha256(path) -> str:
    """SHA-256 of a file's bytes (hex), read in blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class FitVerdict:
    """Whether a model fits the data it was fitted to.

    Parameters
    ----------
    adequate : bool
        The goodness-of-fit test passed (χ² consistent with the declared noise).
    chi2 : float or None
        Σ r² of the standardised residuals at the optimum. [-]
    dof : int or None
        Residual degrees of freedom.
    p_value : float or None
        P(χ²_dof ≥ chi2); None when the noise was estimated from the residuals. [-]
    reason : str
        The test's sentence.
    diagnosis : str or None
        The verdict of ``ipmc diagnose`` (none, named, ambiguous, at_bound, unexplained) when the
        model came from a diagnosis, with ``named`` the effects it named.
    named : tuple of str
        Effects the diagnosis named.
    """

    adequate: bool
    chi2: float | None
    dof: int | None
    p_value: float | None
    reason: str
    diagnosis: str | None = None
    named: tuple = ()

    @classmethod
    def from_goodness(cls, gof, diagnosis: str | None = None, named=()) -> FitVerdict:
        """From a :class:`physmodel.estimation.residuals.GoodnessOfFit` (or its ``to_dict()``).

        Parameters
        ----------
        gof : GoodnessOfFit or dict
            The test.
        diagnosis : str or None
            The diagnosis verdict, when there was one.
        named : sequence of str
            The effects it named.
        """
        d = gof.to_dict() if hasattr(gof, "to_dict") else dict(gof)
        dof = d.get("dof")
        return cls(bool(d.get("adequate")), _num(d.get("chi2")), None if dof is None else int(dof),
                   _num(d.get("p_value")), str(d.get("reason", "")), diagnosis, tuple(named))

    def to_dict(self) -> dict:
        """JSON-ready data (non-finite numbers as None)."""
        return {"adequate": bool(self.adequate), "chi2": _num(self.chi2), "dof": self.dof,
                "p_value": _num(self.p_value), "reason": self.reason, "diagnosis": self.diagnosis,
                "named": list(self.named)}

    @classmethod
    def from_dict(cls, d: dict, where: str = "model file") -> FitVerdict:
        """Read :meth:`to_dict`'s data.

        Parameters
        ----------
        d : dict
            The record.
        where : str
            The file, for messages.
        """
        if not isinstance(d, dict) or not isinstance(d.get("adequate"), bool):
            raise ParameterError(f"{where}: 'verdict' must be an object with 'adequate' true or false, got {d!r}")
        dof, named, diag = d.get("dof"), d.get("named") or [], d.get("diagnosis")
        if dof is not None and (isinstance(dof, bool) or not isinstance(dof, int)):
            raise ParameterError(f"{where}: verdict 'dof' = {dof!r}; expected an integer")
        if not isinstance(named, list) or not all(isinstance(n, str) for n in named) or \
                not (diag is None or isinstance(diag, str)):
            raise ParameterError(f"{where}: verdict 'named' must be a list of effect names and 'diagnosis' a string")
        return cls(d["adequate"], _num(d.get("chi2")), dof, _num(d.get("p_value")), str(d.get("reason", "")),
                   diag, tuple(named))

    def line(self) -> str:
        """One sentence: adequate or not, with χ²/dof and p."""
        stat = (f"chi2 {self.chi2:.4g} on {self.dof} dof" if self.chi2 is not None and self.dof else "chi2 n/a") + (
            f", p = {self.p_value:.2g}" if self.p_value is not None else "")
        diag = f"; diagnosis: {self.diagnosis}" + (f" ({', '.join(self.named)})" if self.named else "") \
            if self.diagnosis else ""
        return ("fits its data" if self.adequate else "DOES NOT FIT its data") + f" ({stat}{diag})"


@dataclass(frozen=True)
class Provenance:
    """Where a model came from.

    Parameters
    ----------
    creator : str
        The command or function that made it (``"ipmc calibrate"``, ``"ipmc diagnose"``, ...).
    data_file : str or None
        The data file it was fitted to, as given.
    data_sha256 : str or None
        SHA-256 of that file's bytes.
    data_fingerprint : str or None
        SHA-256 of the sweep's numerical content (:meth:`FrequencySweep.fingerprint`).
    temperatures_c : tuple of float
        Temperatures of the data. [°C]
    band_hz : tuple of float or None
        (lowest, highest) frequency of the data. [Hz]
    command : str
        The command line.
    library_version : str
        ``physmodel.__version__`` of the writer.
    """

    creator: str
    data_file: str | None = None
    data_sha256: str | None = None
    data_fingerprint: str | None = None
    temperatures_c: tuple = ()
    band_hz: tuple | None = None
    command: str = ""
    library_version: str = ""

    def to_dict(self) -> dict:
        """JSON-ready data."""
        return {"creator": self.creator, "data_file": self.data_file, "data_sha256": self.data_sha256,
                "data_fingerprint": self.data_fingerprint, "temperatures_c": [float(t) for t in self.temperatures_c],
                "band_hz": None if self.band_hz is None else [float(b) for b in self.band_hz],
                "command": self.command, "library_version": self.library_version}

    @classmethod
    def from_dict(cls, d: dict, where: str = "model file") -> Provenance:
        """Read :meth:`to_dict`'s data.

        Parameters
        ----------
        d : dict
            The record.
        where : str
            The file, for messages.
        """
        if not isinstance(d, dict):
            raise ParameterError(f"{where}: 'provenance' must be an object, got {d!r}")
        band, temps = d.get("band_hz"), d.get("temperatures_c") or []
        if not (band is None or (isinstance(band, list) and len(band) == 2 and all(_num(b) is not None for b in band))):
            raise ParameterError(f"{where}: provenance 'band_hz' = {band!r}; expected [lowest, highest] in Hz")
        if not (isinstance(temps, list) and all(_num(t) is not None for t in temps)):
            raise ParameterError(f"{where}: provenance 'temperatures_c' = {temps!r}; expected a list of numbers [°C]")
        for k in ("data_file", "data_sha256", "data_fingerprint"):
            if not (d.get(k) is None or isinstance(d.get(k), str)):
                raise ParameterError(f"{where}: provenance {k!r} = {d.get(k)!r}; expected a string")
        return cls(str(d.get("creator", "")), d.get("data_file"), d.get("data_sha256"), d.get("data_fingerprint"),
                   tuple(float(t) for t in temps),
                   None if band is None else (float(band[0]), float(band[1])),
                   str(d.get("command", "")), str(d.get("library_version", "")))

    def data_path(self, relative_to=None) -> Path | None:
        """The data file, resolved against the model file's folder when relative and not found
        from the working directory; None when unknown.

        Parameters
        ----------
        relative_to : str or Path or None
            The model file's path.
        """
        if not self.data_file:
            return None
        p = Path(self.data_file)
        if p.is_absolute() or relative_to is None:
            return p
        beside = Path(relative_to).parent / p          # older files: relative to where the command ran
        return beside if beside.exists() and not p.exists() else p

    def data_matches(self, path) -> bool | None:
        """Whether the file at ``path`` is the data the model was fitted to (its SHA-256 equals
        ``data_sha256``); None when no hash was recorded.

        Parameters
        ----------
        path : str or Path
            The data file found.
        """
        if not self.data_sha256:
            return None
        return file_sha256(path) == self.data_sha256


__all__ = ["FitVerdict", "Provenance", "file_sha256"]
