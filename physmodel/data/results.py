"""Result folders written all or nothing, and the check that a folder read later is complete.

Every ``ipmc`` command that writes a folder (``calibrate``, ``diagnose``, ``fit``, ``run``,
``demo``, ``feedforward``, ``validate``) goes through :func:`output_folder`: the files are written
into a temporary sibling ``.NAME.<pid>.<random>.part/``; when the block ends without an exception
the completion marker :data:`MARKER` (``.ipmc-complete.json``: which command, which files, when) is
written last and the temporary folder takes the place of ``NAME`` in one rename (Linux: an atomic
exchange with a previous ``NAME``; elsewhere two renames with SIGINT/SIGTERM held back).  An
interrupt or an error removes the temporary folder: ``NAME`` holds the previous complete result or
nothing.  Files of a previous ``NAME`` that the new result does not write (and that were not part of
the previous result's marker) are carried over, so a user's own files in the folder survive.

Readers (``--model``, ``--params-json``, ``--set FILE``, ``--surrogate``) call
:func:`check_complete` on the file they read.  The rule:

- a folder holding :data:`MARKER` is complete;
- a folder whose name ends in ``.part`` is the temporary folder of a run that has not finished
  (or was killed): refused;
- a folder without the marker (written by ipmc before 0.13, or by hand) is refused only when it is
  recognisably an ipmc result — the file read records that ``ipmc calibrate``/``diagnose``/``fit``
  wrote it, or the folder holds ``calibration.json``/``metrics.json``/``report.json`` — and lacks
  the report those versions wrote last (``report.md``, or ``summary.md`` for ``diagnose``): that
  is a run interrupted in its write phase.  A parameter or model file written by hand is accepted.

Errors are :class:`~physmodel.errors.IPMCError` (exit 2) naming the option and the folder.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import time
from contextlib import contextmanager
from pathlib import Path

from .. import interrupts
from ..errors import IPMCError
from .fileio import atomic_write

#: The completion marker, written last into every result folder.
MARKER = ".ipmc-complete.json"
MARKER_FORMAT = "ipmc-result"

#: What each ipmc command leaves in its output folder, to recognise whose results a folder holds:
#: (file, identity, or a function of the file's JSON giving the identity).
#: (report.json before model.json: a diagnosis folder holds both; a fit folder only model.json)
OWNER_FILES = (("metrics.json", lambda d: f"ipmc run {d['scenario']}"), ("calibration.json", lambda d: "ipmc calibrate"),
               ("validation.json", lambda d: "ipmc validate"), ("compare.json", lambda d: "ipmc compare"),
               ("report.json", lambda d: "ipmc feedforward" if "peak_voltage_V" in d else "ipmc diagnose"),
               ("model.json", lambda d: "ipmc fit"))

#: Files only ipmc result folders hold, and the reports older versions wrote last.
_RESULT_SIGNS = ("calibration.json", "metrics.json", "report.json")
_LAST_WRITTEN = ("report.md", "summary.md")


def _marker(folder: Path) -> dict | None:
    p = folder / MARKER
    if not p.is_file():
        return None
    try:
        d = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return d if isinstance(d, dict) and d.get("format") == MARKER_FORMAT else {}


def folder_owner(folder) -> str | None:
    """Whose results ``folder`` holds: ``"ipmc run <scenario>"``, ``"ipmc calibrate"``, ``"ipmc fit"``,
    ``"ipmc diagnose"``, a description of other files, or None when it is empty."""
    folder = Path(folder)
    mark = _marker(folder)
    if mark and isinstance(mark.get("command"), str):
        return mark["command"]
    entries = sorted(p.name for p in folder.iterdir() if p.name != MARKER)
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
    """The refusals of :func:`output_folder` without creating or locking anything, for commands that
    compute first and write at the end (checked before the computation): not a file, writable, and
    not another command's results unless ``force``."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise IPMCError(f"{option} {path}: exists and is not a folder")
    check_writable_parent(path, option)
    owner = folder_owner(path) if path.is_dir() else None
    if owner is not None and owner != identity and not force:
        held = owner if owner.startswith("files") else f"the results of {owner!r}"
        raise IPMCError(f"{option} {path}: the folder holds {held}, not of {identity!r}; choose another "
                        "folder or pass --force to write into it")
    return path


def check_writable_parent(path, option: str = "--out") -> Path:
    """``path`` when the folder it would be written into exists (or can be created) and is writable;
    an IPMCError naming ``option`` and ``path`` otherwise — checked before a long computation."""
    path = Path(path)
    anc = path.absolute().parent
    while not anc.exists() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise IPMCError(f"{option} {path}: {anc} is not a folder")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise IPMCError(f"{option} {path}: cannot write into {anc} (permission denied)")
    return path


def _staging_folders(path: Path) -> list[Path]:
    return sorted(path.parent.glob(f".{path.name}.*.part")) if path.parent.is_dir() else []


def _try_lock(fd: int) -> bool:
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except OSError:
        return False


def _busy(path: Path, own: Path | None = None) -> bool:
    """Whether another live run is writing ``path`` (holds a lock on its staging folder); stale
    staging folders of killed runs are removed on the way."""
    busy = False
    for st in _staging_folders(path):
        if own is not None and st == own:
            continue
        try:
            fd = os.open(st, os.O_RDONLY)
        except OSError:
            continue
        try:
            if _try_lock(fd):
                if own is not None:          # only the run that has claimed its own folder cleans up
                    shutil.rmtree(st, ignore_errors=True)
            else:
                busy = True
        finally:
            os.close(fd)
    return busy


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swap two paths (Linux renameat2 RENAME_EXCHANGE); False when not available."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    rc = fn(at_fdcwd, os.fsencode(str(a)), at_fdcwd, os.fsencode(str(b)), rename_exchange)
    return rc == 0


def _carry_over(old: Path, new: Path) -> None:
    """Link into ``new`` the top-level entries of ``old`` the new result did not write and that
    were not part of the old result (its marker's list): the user's own files survive."""
    mark = _marker(old) or {}
    owned = {Path(f).parts[0] for f in mark.get("files", []) if isinstance(f, str) and f}
    for entry in old.iterdir():
        if entry.name == MARKER or entry.name in owned or (new / entry.name).exists():
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.copytree(entry, new / entry.name, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(entry, new / entry.name)


def _link_or_copy(src, dst):
    try:
        if Path(src).is_symlink():
            os.symlink(os.readlink(src), dst)
        else:
            os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)
    return dst


def _files(folder: Path) -> list[str]:
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file() and p.name != MARKER)


def _write_marker(stage: Path, identity: str) -> None:
    from .. import __version__
    doc = {"format": MARKER_FORMAT, "version": 1, "command": identity, "files": _files(stage),
           "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "library_version": __version__}
    atomic_write(stage / MARKER, lambda fh: fh.write(json.dumps(doc, indent=2) + "\n"))


def _in_place_only(path: Path) -> bool:
    """A folder that cannot be swapped: the working directory or one of its ancestors, or a mount point."""
    try:
        here, target = Path.cwd().resolve(), path.resolve()
    except OSError:
        return True
    return target == here or target in here.parents or os.path.ismount(target)


def _commit(stage: Path, path: Path) -> None:
    """Move the complete ``stage`` to ``path`` with SIGINT/SIGTERM held back, so no interrupt lands
    between the renames; the previous folder (now at a temporary name) is then removed."""
    trash = None
    try:
        with interrupts.held():            # an interrupt meanwhile is raised after the renames
            trash = _swap(stage, path)
    finally:
        if trash is not None:
            shutil.rmtree(trash, ignore_errors=True)


def _swap(stage: Path, path: Path) -> Path | None:
    """The renames of :func:`_commit`; returns the previous folder's temporary name, if any."""
    if not path.exists():
        os.rename(stage, path)
        return None
    if _in_place_only(path):                     # move the files one by one; the marker last
        (path / MARKER).unlink(missing_ok=True)
        for entry in sorted(stage.iterdir(), key=lambda p: p.name == MARKER):
            dst = path / entry.name
            if dst.is_dir() and not dst.is_symlink():
                shutil.rmtree(dst)
            os.replace(entry, dst)
        stage.rmdir()
        return None
    _carry_over(path, stage)
    if _exchange(stage, path):
        return stage
    trash = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.old"
    os.rename(path, trash)
    os.rename(stage, path)
    return trash


#: Temporary folders claimed and not yet committed: stage → (final path, identity, locked descriptor).
_OPEN: dict[Path, tuple[Path, str, int]] = {}


def begin(path, identity: str, *, force: bool = False, option: str = "--out") -> Path:
    """Claim the result folder ``path`` and return the temporary sibling folder to write into; finish
    with :func:`commit` (or :func:`abort`).  :func:`output_folder` is the context-manager form;
    ``ipmc`` aborts every folder left open when a command ends."""
    path = Path(path)
    check_output_folder(path, identity, force=force, option=option)
    path = Path(os.path.abspath(path))          # "." or "x/..": a real name for the sibling
    if _busy(path):
        raise IPMCError(f"{option} {path}: another ipmc run is writing into this folder; wait for it "
                        "or choose another folder")
    path.parent.mkdir(parents=True, exist_ok=True)
    stage = path.parent / f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.part"
    # registered before it exists, so an interrupt at any point after creation still removes it
    _OPEN[stage] = (path, identity, -1)
    try:
        os.mkdir(stage, 0o777)
    except OSError as exc:
        _OPEN.pop(stage, None)
        raise IPMCError(f"{option} {path}: cannot create a folder next to it ({exc.strerror})") from None
    fd = os.open(stage, os.O_RDONLY)
    _OPEN[stage] = (path, identity, fd)
    _try_lock(fd)
    if _busy(path, own=stage):                  # a run that started at the same moment
        abort(stage)
        raise IPMCError(f"{option} {path}: another ipmc run is writing into this folder; wait for it "
                        "or choose another folder")
    return stage


def commit(stage) -> Path:
    """Write the completion marker into ``stage`` and move it to its final place; returns that path.
    An interrupt recorded meanwhile (even one a solver swallowed) aborts instead."""
    stage = Path(stage)
    path, identity, _ = _OPEN[stage]
    try:
        interrupts.check()
        _write_marker(stage, identity)
        interrupts.check()
        _commit(stage, path)
    finally:
        abort(stage)
    return path


def abort(stage=None) -> None:
    """Remove the temporary folder ``stage`` (every open one when None) and release its lock."""
    for st in ([Path(stage)] if stage is not None else list(_OPEN)):
        entry = _OPEN.pop(st, None)
        if entry is not None and entry[2] >= 0:
            os.close(entry[2])
        if st.exists():
            shutil.rmtree(st, ignore_errors=True)


@contextmanager
def output_folder(path, identity: str, *, force: bool = False, option: str = "--out"):
    """Write one run's result folder ``path`` all or nothing (a context manager yielding the
    temporary folder to write into, a sibling of ``path``).

    On a normal exit the completion marker is written and the folder moved into place (see the
    module docstring); on an exception or interrupt the temporary folder is removed and ``path`` is
    left as it was.  A second run into ``path`` is refused while one writes (a lock on the
    temporary folder); a folder holding another command's results is refused unless ``force``.
    Errors are :class:`~physmodel.errors.IPMCError` naming ``option`` and ``path``."""
    stage = begin(path, identity, force=force, option=option)
    try:
        yield stage
        commit(stage)
    finally:
        abort(stage)


@contextmanager
def files_together(paths):
    """Write several files as one result (a data file and its plot): yields temporary names next to
    ``paths`` (same folder, same extension, so writers that pick the format by extension work);
    when the block ends normally they are renamed onto ``paths`` with SIGINT/SIGTERM held back, so
    an interrupt leaves all of them or none; otherwise the temporary files are removed."""
    paths = [Path(p) for p in paths]
    tmps = [p.parent / f".{p.stem}.{os.getpid()}.{secrets.token_hex(4)}.part{p.suffix}" for p in paths]
    try:
        yield tmps
        interrupts.check()
        with interrupts.held():
            for t, p in zip(tmps, paths):
                if t.exists():
                    os.replace(t, p)
    finally:
        for t in tmps:
            t.unlink(missing_ok=True)


def _written_by_ipmc(file: Path) -> bool:
    """Whether the JSON ``file`` records that an ipmc folder command wrote it."""
    if file.suffix.lower() != ".json" or not file.is_file():
        return False
    try:
        d = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if not isinstance(d, dict):
        return False
    prov = d.get("provenance")
    data = (d.get("info") or {}).get("data") if isinstance(d.get("info"), dict) else None
    return ("calibration" in d or (isinstance(prov, dict) and str(prov.get("creator", "")).startswith("ipmc "))
            or (isinstance(data, dict) and "fingerprint" in data))


def check_complete(file, option: str) -> None:
    """Refuse (IPMCError naming ``option``, the file and its folder) a file read from a result folder
    that an interrupted run left incomplete; the rule is in the module docstring."""
    file = Path(file)
    folder = file.parent
    if folder.name.endswith(".part") and folder.name.startswith("."):
        raise IPMCError(f"{option} {file}: {folder} is the temporary folder of an ipmc run that has not finished "
                        "(or was killed); use the folder it is moved to when complete, or rerun the command")
    mark = _marker(folder)
    if mark is not None:
        if not mark:
            raise IPMCError(f"{option} {file}: the completion marker {folder / MARKER} is unreadable; rerun the "
                            "command that wrote the folder")
        return
    try:
        names = {p.name for p in folder.iterdir()}
    except OSError:
        return
    if (names & set(_RESULT_SIGNS) or _written_by_ipmc(file)) and not names & set(_LAST_WRITTEN):
        raise IPMCError(f"{option} {file}: the folder {folder} is an incomplete ipmc result (no {MARKER} and no "
                        "report.md: the run that wrote it was interrupted); rerun the command that wrote it")


__all__ = ["MARKER", "OWNER_FILES", "folder_owner", "check_output_folder", "check_writable_parent", "output_folder",
           "begin", "commit", "abort", "files_together", "check_complete"]
