"""The library's file plumbing: the one atomic writer (temporary file, then rename), the one UTF-8
text reader, the extension dispatcher and the output-folder claim of the commands.

Below every file format (sweeps, time records, model files, studies): nothing here knows a format.
"""

from __future__ import annotations

import json
import os
import secrets
from collections.abc import Callable, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from .. import interrupts
from ..errors import DataFormatError, IPMCError


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
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
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


#: What each ipmc command leaves in its output folder, to recognise whose results a folder holds:
#: (file, identity, or a function of the file's JSON giving the identity).
OWNER_FILES = (("metrics.json", lambda d: f"ipmc run {d['scenario']}"), ("calibration.json", lambda d: "ipmc calibrate"),
               ("model.json", lambda d: "ipmc fit"), ("report.json", lambda d: "ipmc diagnose"))


def folder_owner(folder) -> str | None:
    """Whose results ``folder`` holds: ``"ipmc run <scenario>"``, ``"ipmc calibrate"``, ``"ipmc fit"``,
    ``"ipmc diagnose"``, a description of other files, or None when it is empty."""
    folder = Path(folder)
    entries = sorted(p.name for p in folder.iterdir())
    if not entries:
        return None
    for name, identity in OWNER_FILES:
        if name in entries:
            try:
                return identity(json.loads((folder / name).read_text(encoding="utf-8")))
            except (OSError, ValueError, KeyError, TypeError):
                continue
    return f"files not written by a finished ipmc run ({', '.join(entries[:3])}{', ...' if len(entries) > 3 else ''})"


def check_output_folder(path, identity: str, *, force: bool = False, option: str = "--out") -> Path:
    """The refusals of :func:`output_folder` without creating or locking anything: for commands
    that compute first and write at the end (they claim the folder then)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise IPMCError(f"{option} {path}: exists and is not a folder")
    owner = folder_owner(path) if path.is_dir() else None
    if owner is not None and owner != identity and not force:
        held = owner if owner.startswith("files") else f"the results of {owner!r}"
        raise IPMCError(f"{option} {path}: the folder holds {held}, not of {identity!r}; choose another "
                        "folder or pass --force to write into it")
    return path


@contextmanager
def output_folder(path, identity: str, *, force: bool = False, option: str = "--out"):
    """Claim the folder ``path`` for one run (a context manager yielding it as a Path).

    The folder is created if needed and locked (``fcntl.flock`` on the folder itself) for the
    duration of the block, so a second run into the same folder is refused while the first one
    writes.  A folder that holds another run's results (:func:`folder_owner` differs from
    ``identity``, e.g. another scenario, or files ipmc did not finish writing) is refused unless
    ``force``; the same command or scenario may replace its own results.  Errors are
    :class:`~physmodel.errors.IPMCError` naming ``option`` and the folder.
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise IPMCError(f"{option} {path}: exists and is not a folder")
    path.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDONLY)
    try:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock, the ownership check still applies
            fcntl = None  # type: ignore[assignment]
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                raise IPMCError(f"{option} {path}: another ipmc run is writing into this folder; wait for it "
                                "or choose another folder") from None
        check_output_folder(path, identity, force=force, option=option)
        yield path
    finally:
        os.close(fd)                   # closing the descriptor releases the lock


def by_extension(path, handlers: Mapping[str, Callable], what: str) -> Callable:
    """The handler for ``path``'s file extension, or a DataFormatError listing the accepted ones."""
    ext = Path(path).suffix.lower()
    if ext not in handlers:
        raise DataFormatError(f"{path}: unknown {what} file type {ext!r}; expected {', '.join(handlers)}")
    return handlers[ext]
