"""The documentation's gallery examples run in the suite, not only in the docs build (and the
citation file names the package's version).

Each ``docs/examples/plot_*.py`` runs in a fresh interpreter with this checkout first on the
path, the Agg backend and warnings as errors (the suite's rule), and must exit 0.  A new example
is picked up by the glob; a pending one stays in ``docs/examples_pending/`` until its feature
exists.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "docs" / "examples").glob("plot_*.py"))
#: Per-example limit: the gallery's budget is about 30 s on two cores; this is a hang guard.
TIMEOUT_S = 300


def test_the_gallery_is_not_empty():
    assert len(EXAMPLES) >= 9, [p.name for p in EXAMPLES]


#: The fast tier runs one quick example (the gallery's mechanics: fresh interpreter, warnings as errors);
#: the others take 2-15 s each and run in the slow tier and in the docs build.
FAST_EXAMPLES = {"plot_04_calibration_identifiability"}


@pytest.mark.parametrize("script", [pytest.param(p, id=p.stem) if p.stem in FAST_EXAMPLES
                                    else pytest.param(p, id=p.stem, marks=pytest.mark.slow) for p in EXAMPLES])
def test_example_runs(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else [])))
    proc = subprocess.run([sys.executable, "-W", "error", str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert proc.returncode == 0, f"{script.name} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"


def test_citation_names_the_package_version():
    """CITATION.cff is kept by hand; its version must be the one the package reports."""
    import re

    import physmodel

    text = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    found = re.findall(r"^version:\s*\"?([^\s\"]+)\"?\s*$", text, flags=re.M)
    assert found == [physmodel.__version__], (found, physmodel.__version__)

