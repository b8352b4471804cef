"""A process-wide record of SIGINT/SIGTERM, so that an interrupt swallowed inside a solver still
ends the run.

CasADi's IPOPT interface catches the ``KeyboardInterrupt`` raised by Python's signal handler
during a solve, prints ``KeyboardInterruptException`` and returns the status
``NonIpopt_Exception_Thrown``: the caller sees an ordinary failed solve and carries on.  With
:func:`handling` installed (``ipmc`` does this for every command), each SIGINT/SIGTERM is recorded
here *and* raises ``KeyboardInterrupt``; code that must not continue after an interrupt (between
steps of a run, before a file is committed by :func:`physmodel.data.files.atomic_write`) calls
:func:`check`, which raises ``KeyboardInterrupt`` again when one was recorded.

>>> from physmodel import interrupts
>>> interrupts.check()          # nothing recorded: returns
"""

from __future__ import annotations

import signal
import threading
import time
from contextlib import contextmanager

_requested: int | None = None
_raised_at = -1e9
_deferring = 0

#: A repeated signal raises ``KeyboardInterrupt`` again only this long [s] after the last one, so a
#: double Ctrl-C (or SIGINT then SIGTERM) cannot interrupt the clean-up and reporting the first
#: one started; a deliberate repeat later still breaks out of a loop that swallowed the first.
REPEAT_S = 2.0

#: The signals :func:`handling` turns into ``KeyboardInterrupt``.
SIGNALS = (signal.SIGINT, signal.SIGTERM)


def request(signum: int = signal.SIGINT) -> None:
    """Record an interrupt (what the signal handler does)."""
    global _requested
    _requested = int(signum)


def requested() -> int | None:
    """The signal number recorded since the last :func:`reset`, or None."""
    return _requested


def reset() -> None:
    """Forget a recorded interrupt."""
    global _requested, _raised_at
    _requested = None
    _raised_at = -1e9


def check() -> None:
    """Raise ``KeyboardInterrupt`` when an interrupt was recorded (even if a solver swallowed it)."""
    if _requested is not None:
        raise KeyboardInterrupt(f"interrupted by {signal.Signals(_requested).name}")


def _handler(signum, frame):
    global _raised_at
    request(signum)
    if _deferring:
        return                         # inside held(): raised when the block ends
    now = time.monotonic()
    if now - _raised_at >= REPEAT_S:
        _raised_at = now
        raise KeyboardInterrupt(f"interrupted by {signal.Signals(signum).name}")


@contextmanager
def held():
    """A block no SIGINT/SIGTERM interrupts (a few renames that must all happen): the signals are
    blocked for this thread and, under :func:`handling`, only recorded — a signal another thread
    received still runs the handler in the main thread — and ``KeyboardInterrupt`` is raised when
    the block ends if one arrived."""
    global _deferring
    blocked = hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS)) if blocked else None
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
        if blocked:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
    check()


def worker_init() -> None:
    """For worker processes (``ProcessPoolExecutor(initializer=...)``): SIGINT and SIGTERM are
    ignored.  A Ctrl-C or a SIGTERM sent to the whole process group reaches every worker; the parent
    reports it, cancels the work not started and lets each worker finish its current task and exit
    normally.  A worker killed while it sends a result back would leave a partial message in the
    result pipe, on which the executor's manager thread — and with it the parent's exit — waits
    forever; a worker that dies of a signal prints no traceback, but one that receives a
    ``KeyboardInterrupt`` does."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)


@contextmanager
def handling():
    """Within the block, SIGINT and SIGTERM are recorded and raise ``KeyboardInterrupt``; the
    record starts empty and the previous handlers are restored afterwards.  Outside the main
    thread (where Python cannot install handlers) it only resets the record.  The record is
    forgotten when the block ends: an interrupt is the block's to report (read :func:`requested`
    inside it), and must not stop later work in the same process (a notebook, a test session)."""
    reset()
    if threading.current_thread() is not threading.main_thread():
        try:
            yield
        finally:
            reset()
        return
    previous = {s: signal.signal(s, _handler) for s in SIGNALS}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
        reset()


__all__ = ["request", "requested", "reset", "check", "handling", "held", "worker_init", "SIGNALS", "REPEAT_S"]
