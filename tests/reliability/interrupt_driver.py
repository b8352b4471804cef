"""Run ``ipmc`` (argv after the first two) and deliver SIGNAL (argv[1]) while the main thread is
inside an IPOPT solve: a watcher thread waits until the main thread's stack holds
inside the ``self._solver(...)`` call of ``surrogate._nlp.Solver.solve`` (so the process is executing
CasADi's C++ code), and only then signals the process.  Used by test_interrupt.py; not a test."""

import os
import signal
import sys
import threading
import time

import surrogate._nlp as nlp
from scenarios.cli import main

SIG = getattr(signal, sys.argv[1])
MAIN = threading.main_thread().ident
NLP_FILE = os.path.abspath(nlp.__file__)


def _in_solver_call() -> bool:
    """True when a frame of the main thread's stack is the solver call in Solver.solve (the frames
    above it are CasADi's Python wrappers around the C++ call)."""
    import linecache

    frame = sys._current_frames().get(MAIN)
    while frame is not None:
        if (frame.f_code.co_name == "solve" and os.path.abspath(frame.f_code.co_filename) == NLP_FILE
                and "self._solver(" in linecache.getline(NLP_FILE, frame.f_lineno)):
            return True
        frame = frame.f_back
    return False


def _watch():
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if _in_solver_call():
            time.sleep(0.002)
            if _in_solver_call():
                print("DRIVER: signalling inside an IPOPT solve", file=sys.stderr, flush=True)
                os.kill(os.getpid(), SIG)
                return
        time.sleep(0.0005)


threading.Thread(target=_watch, daemon=True).start()
sys.exit(main(sys.argv[2:]))
