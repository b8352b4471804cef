"""The seed papers' printed numbers and claims, shipped with the package (``published.toml``).

Each table cites its paper (``citation``, short form ``cite_as``; ``paper``: the text the numbers
were transcribed from), holds the numbers as printed (units as printed, e.g. s in rad/s, current in
µA, displacement in mm) and, in its ``location`` sub-table, where each claim is printed (section /
table / figure / equation, a list for a list of claims).  :func:`load_published` returns
the parsed file; :func:`seed000_printed_model_35c` the one printed sensor model as coefficient
tuples.  Nothing here reads anything outside the package.
"""

from __future__ import annotations

import tomllib
from functools import lru_cache
from importlib import resources
from pathlib import Path

from ..errors import DataFormatError

#: The bundled file (a copy of the facts printed in the three seed papers).
PUBLISHED_FILE = "published.toml"


@lru_cache(maxsize=4)
def _load_cached(path: str | None) -> dict:
    if path is None:
        text = resources.files(__package__).joinpath(PUBLISHED_FILE).read_text(encoding="utf-8")
        where = f"{__package__}/{PUBLISHED_FILE}"
    else:
        p = Path(path)
        if not p.is_file():
            raise DataFormatError(f"published claims file {path!r} does not exist")
        try:
            text = p.read_text(encoding="utf-8-sig")
        except UnicodeDecodeError as exc:
            raise DataFormatError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
        where = path
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DataFormatError(f"{where}: not valid TOML: {exc}") from None


def load_published(path: str | Path | None = None) -> dict:
    """The printed numbers: the bundled file, or another TOML file of the same layout."""
    return _load_cached(None if path is None else str(path))


def seed000_printed_model_35c() -> tuple[tuple[float, ...], tuple[float, ...], tuple[complex, ...]]:
    """Seed 000, Sec. IV-A, the 35 °C sensor model: (numerator, denominator) in descending powers of
    s [rad/s], tip displacement [mm] → current [µA], and its zeros as printed [rad/s]."""
    t = load_published()["sensor_seed000"]
    return (tuple(float(v) for v in t["model_35c_num"]), tuple(float(v) for v in t["model_35c_den"]),
            tuple(complex(z.replace(" ", "")) for z in t["model_35c_zeros_printed"]))
