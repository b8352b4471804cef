"""The library's file plumbing: the one atomic writer (temporary file, then rename), the one UTF-8
text reader and the extension dispatcher (the output-folder claim: physmodel.data.results).

Below every file format (sweeps, time records, model files, studies): nothing here knows a format.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import interrupts
from ..errors import DataFormatError


# ----------------------------------------------------------------------------------- I/O helpers
def atomic_write(path, write_fn, mode: str = "w") -> Path:
    """Write ``path`` via ``write_fn(fh)`` into a temporary file in the same folder, flushed to disk,
    then renamed over ``path``: never a half-written file, even on Ctrl-C.  ``mode``: "w" (UTF-8 text,
    no newline translation) or "wb".  The file gets the usual permissions (0666 less the umask)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # the name is fixed before the file exists, so an interrupt at any point after creation still
    # finds and removes it (mkstemp's name is only known once it returns)
    tmp = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.part"
    try:
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError as exc:         # name the file asked for, not the temporary one
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        text: dict[str, Any] = {"newline": "", "encoding": "utf-8"} if "b" not in mode else {}
        with os.fdopen(fd, mode, **text) as fh:
            write_fn(fh)
            fh.flush()
            os.fsync(fh.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)   # created 0600
        interrupts.check()             # an interrupt a solver swallowed must not commit a file
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def read_text(path, what: str = "file") -> str:
    """The text of ``path`` decoded as UTF-8, a leading byte-order mark dropped (Excel writes one).

    Every text reader of the library (sweep CSV, scenario/study/experiment TOML, parameter JSON,
    signal CSV) goes through here, so a file that is not UTF-8 is a :class:`DataFormatError` naming
    the file, the line and the byte, never a ``UnicodeDecodeError``.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise DataFormatError(f"{what} {str(path)!r}: no such file") from None
    except IsADirectoryError:
        raise DataFormatError(f"{what} {str(path)!r} is a folder; expected a file") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise DataFormatError(f"{path}:{line}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
                              "save the file as UTF-8") from None


@dataclass(frozen=True)
class CommentHeader:
    """The ``# key: value`` lines at the top of a text table (:func:`comment_header`).

    Attributes
    ----------
    entries : dict[str, str]
        Key → value of each ``# key: value`` line, in file order (a later line with the same key
        wins); a format line ``# ipmc-<format> <version>`` is the entry ``{'ipmc-<format>': '<version>'}``.
    end : int
        Index (0-based) of the first line after the header: the column-name row, or ``len(lines)``
        when the text holds nothing else.
    """

    entries: dict = field(default_factory=dict)
    end: int = 0


def comment_header(lines: Sequence[str]) -> CommentHeader:
    """The comment header of a text table: the leading lines that are blank or start with ``#``
    (after any indentation).

    Each such line's text after the ``#`` signs is an entry when it holds a ``:`` (``# input:
    voltage [V]`` → ``{'input': 'voltage [V]'}``, key and value stripped) or when its first word
    names a library format (``# ipmc-sweep 1`` → ``{'ipmc-sweep': '1'}``); other comment lines
    (free text) are skipped.  The one header scan of the library's CSV readers (the sweep CSV and
    a user's own tables, :mod:`physmodel.data.columns`).

    Parameters
    ----------
    lines : sequence of str
        The text's lines, without line ends (``text.splitlines()``).
    """
    entries: dict[str, str] = {}
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        body = lines[i].strip().lstrip("#").strip()
        words = body.split(None, 1)
        if words and words[0].startswith("ipmc-") and ":" not in words[0]:
            entries[words[0]] = words[1] if len(words) > 1 else ""
        elif ":" in body:
            k, v = body.split(":", 1)
            entries[k.strip()] = v.strip()
        i += 1
    return CommentHeader(entries, i)


# the output-folder claim of the commands lives in physmodel.data.results (all or nothing, with a
# completion marker), above this module; physmodel.data.files re-exports its names


def by_extension(path, handlers: Mapping[str, Callable], what: str) -> Callable:
    """The handler for ``path``'s file extension, or a DataFormatError listing the accepted ones."""
    ext = Path(path).suffix.lower()
    if ext not in handlers:
        raise DataFormatError(f"{path}: unknown {what} file type {ext!r}; expected {', '.join(handlers)}")
    return handlers[ext]
