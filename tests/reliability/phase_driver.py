"""Run ``ipmc`` (argv after the first two) and deliver SIGNAL (argv[1]) to itself at PHASE (argv[2]):

- ``write:NAME``   just after a file named NAME is committed (``os.replace`` onto it): the moment a
                   result file "appears";
- ``temp:STEM``    just after a temporary file ``.STEM.<pid>.<random>.part<suffix>`` is complete (a
                   file written together with others, e.g. a sweep and its plot);
- ``import:MOD``   when module MOD is about to be imported (an import hook), i.e. during start-up;
- ``begin``        just after a result folder's temporary sibling was created;
- ``twice:NAME``   as write:NAME, then the other of SIGINT/SIGTERM 1 ms later (a double Ctrl-C).

Used by test_signals.py and the fuzz benchmark's interrupt classes; not a test.  Prints
``DRIVER: fired`` on stderr when the signal was sent, so a test can tell that the phase was reached.
"""

import os
import signal
import sys
import time
from pathlib import Path

SIG = getattr(signal, sys.argv[1])
KIND, _, ARG = sys.argv[2].partition(":")
fired = False


def fire():
    global fired
    if fired:
        return
    fired = True
    print("DRIVER: fired", file=sys.stderr, flush=True)
    os.kill(os.getpid(), SIG)
    if KIND == "twice":
        time.sleep(0.001)
        os.kill(os.getpid(), signal.SIGTERM if SIG == signal.SIGINT else signal.SIGINT)


if KIND in ("write", "twice", "temp"):
    _replace = os.replace

    def replace(src, dst, *a, **k):
        _replace(src, dst, *a, **k)
        name = Path(dst).name
        if name == ARG if KIND != "temp" else (name.startswith(f".{ARG}.") and ".part" in name):
            fire()

    os.replace = replace
elif KIND == "import":
    import importlib.abc

    class Hook(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path, target=None):
            if name == ARG:
                fire()
            return None

    sys.meta_path.insert(0, Hook())
elif KIND == "begin":
    _mkdir = os.mkdir

    def mkdir(p, *a, **k):
        _mkdir(p, *a, **k)
        if str(p).endswith(".part"):
            fire()

    os.mkdir = mkdir

from scenarios.cli import main  # noqa: E402

sys.exit(main(sys.argv[3:]))
